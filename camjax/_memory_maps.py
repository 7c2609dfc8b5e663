"""A long-lived process's memory maps, and JAX's compiled programs let go before they run out.

Every program XLA compiles for the CPU maps its code and data into the process as regions
of their own, tens to hundreds per program, and keeps them while JAX's caches hold the
program.  A process that compiles many programs and lives long (a test worker, a studio
open all day) reaches the system's limit on memory maps (``vm.max_map_count``, 65,530 on
most Linux systems); XLA's compiler then fails to map memory ("LLVM compilation error:
Cannot allocate memory") and the process dies of a segmentation fault.  Measured on
2026-11-29 (jaxlib 0.10.2): three built-in cams analysed add about 2,000 maps, and
``jax.clear_caches()`` gives back all but about 80 of them.

``relieve(fraction)`` clears JAX's caches when the process holds more than ``fraction`` of
the limit; a program still in use stays alive (its caller holds it) and one used again is
compiled again (or read from the persistent compilation cache).  Off Linux, where there is
no such count to read, it does nothing.
"""

from __future__ import annotations

import gc
from pathlib import Path

CROWDED_FRACTION = 0.4
"""The share of the system's limit past which compiled programs are let go: a test
module or a studio's analysis adds well under the remaining 60% before the next check."""

_MAPS = Path("/proc/self/maps")
_LIMIT = Path("/proc/sys/vm/max_map_count")


def memory_maps() -> tuple[int, int] | None:
    """``(maps the process holds, the system's limit)``, or None where the system does not say."""
    try:
        limit = int(_LIMIT.read_text())
        with _MAPS.open("rb") as maps:
            return maps.read().count(b"\n"), limit
    except (OSError, ValueError):
        return None


def relieve(fraction: float = CROWDED_FRACTION) -> bool:
    """Clear JAX's compiled programs if the process holds more than ``fraction`` of the
    system's memory maps; True when it did."""
    counted = memory_maps()
    if counted is None or counted[0] <= fraction * counted[1]:
        return False
    import jax

    jax.clear_caches()
    gc.collect()  # the executables go when the last reference does
    return True
