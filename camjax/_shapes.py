"""Bucketed array sizes: the shapes compiled programs are built for.

A compiled program serves one shape; sizes that vary with the user's values (a program's
grid, a batch of speeds, the points a law is evaluated at) are rounded up to a few sizes
per octave, so that nearby sizes share a program and the padding stays below a quarter.
"""

from __future__ import annotations


def bucket(size: int, minimum: int = 16) -> int:
    """``size`` rounded up to ``2^k``, ``1.25 2^k``, ``1.5 2^k`` or ``1.75 2^k`` (at least
    ``minimum``)."""
    size = max(int(size), minimum)
    step = max(1, 2 ** (size.bit_length() - 1) // 4)
    return step * -(-size // step)


def power_of_two(size: int, minimum: int = 256) -> int:
    """``size`` rounded up to a power of two (at least ``minimum``): coarser buckets, for
    small programs that are traced anew in every process (a law evaluated on the host),
    where fewer shapes save more tracing than the padding costs."""
    return max(int(minimum), 1 << max(0, int(size) - 1).bit_length())
