"""Large sweeps from a spec file: chunks written atomically, resumable, over many processes.

A sweep is every law of a list (named laws and/or a grid over the SCCA family) against
one set of period ratios, at one or more damping ratios.  The work is cut into chunks of
``laws_per_chunk`` laws at one damping ratio; each chunk is written to its own file
(a temporary file, then ``os.replace``), so an interrupted run loses at most the chunks
in flight and a rerun computes only the missing ones.  Within a process a chunk is split
over the local devices (:mod:`camjax.sharding`).

Several processes (hosts) share the chunks: process ``p`` of ``P`` takes chunks
``p, p + P, ...``.  On a cluster, start the same command on every host::

    camjax sweep spec.toml --coordinator HOST0:PORT --num-processes P --process-id p

(on SLURM and other launchers ``jax.distributed.initialize`` can also find these itself:
pass ``--distributed``).  The output directory must be on a file system every process
sees.  After its chunks each process waits at a barrier; process 0 then merges the chunks
into ``sweep.npz``.

Spec file (TOML; every key, its default and the files written: docs/sweep.md)::

    output = "scca-sweep"          # output directory, relative to the spec file
    method = "exact"               # or a diffrax solver name
    damping = [0.0, 0.05]
    laws_per_chunk = 64
    dwell = 1.0                    # optional
    phase_step = 1.5               # optional: largest w h of the exact path's grid (below)
    [period_ratio]
    start = 1.0
    stop = 30.0
    count = 1000                   # or: values = [1.0, 2.5, ...]
    [laws]
    names = ["cycloidal", "modified-sine"]   # registered law names, and/or
    scca_step = 0.05                          # every SCCA (a, b, c) on this grid,
    scca_face = false                         # true: only a + b + c = 1

The exact path runs each band of period ratios on a grid of its own
(``camjax.sweep.resolution_bands``), sized so that the vibration turns by at most
``phase_step`` radians per interval: the default 1.5 is ``ct_curve``'s and the largest the
exact path accepts (``camjax.sdof.MAX_PHASE_STEP``); a smaller step gives a finer grid, to
check a sweep against.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

from .checks import period_ratio_count, read_toml
from .laws import SCCA, AbstractMotionLaw, rest_to_rest
from .sdof import (
    MAX_GRID_INTERVALS,
    MAX_PHASE_STEP,
    check_grid_size,
    default_resolution,
    period_ratio_reach,
)

METRICS = ("ct", "residual", "peak_in_motion")
SPEC_KEYS = {"output", "method", "damping", "laws_per_chunk", "dwell", "period_ratio", "laws",
             "phase_step"}
"""The top-level keys a sweep spec may hold (docs/sweep.md); any other is refused."""


MAX_SCCA_LAWS = 1_000_000
"""Most laws an SCCA grid may hold (the face at a step of 0.001 holds 501,501): a finer
grid is refused before the laws are built."""


def scca_grid(step: float, *, face: bool = False) -> list[SCCA]:
    """Every SCCA law with fractions on a grid of ``step``.

    ``face=True`` keeps ``a + b + c = 1`` (no constant-velocity part; the named laws lie
    there); otherwise ``0 < a + b + c <= 1`` (the all-zero point is no law).  A step of
    0.01 on the face gives 5151 laws; 0.05 over the family gives 1770.
    """
    if not step > 0 or 1.0 / step > 10**6:
        raise ValueError(f"scca_step must divide 1 into a whole number of steps, got {step}")
    m = round(1.0 / step)
    if not abs(m * step - 1.0) < 1e-9:
        raise ValueError(f"scca_step must divide 1 into a whole number of steps, got {step}")
    count = (m + 1) * (m + 2) // 2 if face else (m + 1) * (m + 2) * (m + 3) // 6 - 1
    if count > MAX_SCCA_LAWS:
        raise ValueError(f"scca_step {step:g} gives {count:,} SCCA laws; the limit is "
                         f"{MAX_SCCA_LAWS:,} (a coarser step"
                         + (")" if face else ", or scca_face = true)"))
    out = []
    for i in range(m + 1):
        for j in range(m + 1 - i):
            for k in ([m - i - j] if face else range(m + 1 - i - j)):
                if i + j + k:
                    out.append(SCCA(i / m, j / m, k / m))
    return out


@dataclasses.dataclass(frozen=True)
class SweepSpec:
    """A checked sweep spec (see the module docstring for the file format)."""

    output: Path
    laws: tuple[AbstractMotionLaw, ...]
    period_ratio: np.ndarray
    damping: tuple[float, ...]
    method: str = "exact"
    dwell: float = 1.0
    laws_per_chunk: int = 64
    phase_step: float = MAX_PHASE_STEP
    fingerprint: str = ""

    @property
    def names(self) -> list[str]:
        return [law.name for law in self.laws]

    def chunks(self) -> list[tuple[int, int]]:
        """``(damping index, first law)`` of every chunk, in a fixed order."""
        return [(d, start) for d in range(len(self.damping))
                for start in range(0, len(self.laws), self.laws_per_chunk)]

    def chunk_path(self, chunk: tuple[int, int]) -> Path:
        d, start = chunk
        return self.output / "chunks" / f"d{d:02d}_l{start:07d}.npz"


def load_spec(path) -> SweepSpec:
    """Read and check a TOML sweep spec; ``ValueError`` names the file and any problem."""
    path = Path(path)
    raw = read_toml(path, "sweep spec")
    try:
        return spec_from_dict(raw, base=path.parent)
    except ValueError as error:
        raise ValueError(f"{path}: {error}") from None


def _number(value, key: str, kind=float):
    """``value`` as a ``kind`` (float or int), or a ``ValueError`` naming ``key``: a spec
    takes numbers as TOML numbers, as program files do (``"0.1"`` is refused)."""
    if isinstance(value, bool) or not isinstance(value, int | float) or (
            kind is int and not float(value).is_integer()):
        expected = "an integer" if kind is int else "a number"
        raise ValueError(f"{key} must be {expected}, got {value!r}")
    return kind(value)


def _numbers(value, key: str) -> list[float]:
    """A number or a list of numbers as floats, or a ``ValueError`` naming ``key``."""
    items = value if isinstance(value, list) else [value]
    return [_number(x, key) for x in items]


def spec_from_dict(raw: dict, base=".") -> SweepSpec:
    """:func:`load_spec` for an already parsed dict; ``base`` anchors a relative output."""
    unknown = set(raw) - SPEC_KEYS
    if unknown:
        raise ValueError(f"unknown spec keys {sorted(unknown)}; expected some of {sorted(SPEC_KEYS)}")
    if "output" not in raw:
        raise ValueError("spec needs an output directory: output = \"DIR\"")
    if not isinstance(raw["output"], str):
        raise ValueError(f"output must be a directory name (a string), got {raw['output']!r}")
    ratios = raw.get("period_ratio")
    if not isinstance(ratios, dict):
        raise ValueError("spec needs [period_ratio] with start/stop/count or values")
    if "values" in ratios and ratios.keys() & {"start", "stop", "count"}:
        raise ValueError("[period_ratio] takes either values or start/stop/count, not both")
    if "values" in ratios:
        n = np.asarray(_numbers(ratios["values"], "period_ratio.values"), dtype=float)
    else:
        try:
            n = np.linspace(_number(ratios["start"], "period_ratio.start"),
                            _number(ratios["stop"], "period_ratio.stop"),
                            period_ratio_count(_number(ratios["count"], "period_ratio.count", int),
                                               "period_ratio.count"))
        except KeyError as error:
            raise ValueError(f"[period_ratio] is missing {error.args[0]!r}") from None
    if n.ndim != 1 or n.size == 0 or not np.all(np.isfinite(n)) or np.any(n <= 0):
        raise ValueError("period ratios must be a non-empty list of positive finite numbers")
    if "values" not in ratios and n[-1] < n[0]:
        raise ValueError(f"period_ratio.stop must not be below period_ratio.start, got start "
                         f"{n[0]:g}, stop {n[-1]:g}")
    table = raw.get("laws", {})
    names = table.get("names", [])
    if not isinstance(names, list) or not all(isinstance(x, str) for x in names):
        raise ValueError(f"laws.names must be a list of law names, got {names!r}")
    laws = [rest_to_rest(name, "a sweep spec", "laws.names entry") for name in names]
    if "scca_step" in table:
        laws += scca_grid(_number(table["scca_step"], "laws.scca_step"),
                          face=bool(table.get("scca_face", False)))
    if not laws:
        raise ValueError("spec needs [laws] with names = [...] and/or scca_step = STEP")
    names = [law.name for law in laws]
    twice = sorted({x for x in names if names.count(x) > 1})
    if twice:
        raise ValueError(f"spec lists the law {twice[0]} twice (laws.names and the SCCA grid "
                         "together must name each law once)")
    damping = tuple(_numbers(raw.get("damping", [0.0]), "damping"))
    if not damping:
        raise ValueError("damping must name at least one damping ratio, got []")
    if not all(0.0 <= z < 1.0 for z in damping):
        raise ValueError(f"damping ratios must be in [0, 1), got {list(damping)}")
    per_chunk = _number(raw.get("laws_per_chunk", 64), "laws_per_chunk", int)
    if per_chunk < 1:
        raise ValueError(f"laws_per_chunk must be at least 1, got {per_chunk}")
    method = raw.get("method", "exact")
    if not isinstance(method, str):
        raise ValueError(f"method must be a method name (a string), got {method!r}")
    dwell = _number(raw.get("dwell", 1.0), "dwell")
    phase_step = _number(raw.get("phase_step", MAX_PHASE_STEP), "phase_step")
    if not 0.0 < phase_step <= MAX_PHASE_STEP:
        raise ValueError(f"phase_step must be in (0, {MAX_PHASE_STEP:g}] (radians per grid "
                         f"interval), got {phase_step}")
    if method == "exact":
        # The grid's size depends on the largest ratio and phase_step alone (not on the
        # chunks): a coarser step helps up to MAX_PHASE_STEP, past that only a smaller stop.
        def advice() -> str:
            needed = 2 * np.pi * n.max() / MAX_GRID_INTERVALS
            if needed <= MAX_PHASE_STEP:
                return f"phase_step at least {_up(needed):g}, at most {MAX_PHASE_STEP:g}"
            return (f"period ratios up to {math.floor(period_ratio_reach(MAX_PHASE_STEP)):,} at phase_step "
                    f"{MAX_PHASE_STEP:g}: lower period_ratio.stop (or the largest of values)")

        check_grid_size(default_resolution(n.max(), phase_step),
                        f"a rise at period ratio {n.max():g} and phase_step {phase_step:g}", advice)
    what = json.dumps([names, n.tolist(), damping, method, dwell, per_chunk]
                      + ([phase_step] if phase_step != MAX_PHASE_STEP else []))
    return SweepSpec(
        output=Path(base) / raw["output"], laws=tuple(laws), period_ratio=n, damping=damping,
        method=method, dwell=dwell, laws_per_chunk=per_chunk, phase_step=phase_step,
        fingerprint=hashlib.sha256(what.encode()).hexdigest()[:16],
    )


def _up(value: float, digits: int = 3) -> float:
    """``value`` rounded up to ``digits`` significant digits: a printed bound that admits it."""
    scale = 10.0 ** (math.floor(math.log10(value)) - digits + 1)
    return math.ceil(value / scale) * scale


def _write_atomic(path: Path, **arrays) -> None:
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp")
    with open(tmp, "wb") as f:
        np.savez(f, **arrays)
    os.replace(tmp, path)


def _compute_chunk(spec: SweepSpec, chunk, devices) -> dict[str, np.ndarray]:
    """Metrics of one chunk's laws, ``(laws, ratios)`` each.

    Laws of one pytree structure (an SCCA grid) are stacked, padded to ``laws_per_chunk``
    with copies of the last (one compiled program per band of ratios for every chunk),
    split over the devices and run band by band (``camjax.sweep.resolution_bands``);
    other mixes go through ``ct_curves``.
    """
    import jax

    from .errors import raise_if_failed
    from .sweep import ct_curves, prepare_sweep, stack_of, stacked_ca, sweep_banded, sweep_law_stack

    d, start = chunk
    laws = list(spec.laws[start:start + spec.laws_per_chunk])
    structures = {jax.tree.structure(law) for law in laws}
    if len(structures) == 1 and jax.tree.leaves(laws[0]):
        padded = laws + laws[-1:] * (spec.laws_per_chunk - len(laws))
        stacked = stack_of(padded)
        n, template, options = prepare_sweep(
            spec.period_ratio, damping=spec.damping[d], method=spec.method, dwell=spec.dwell
        )
        # Each band of ratios on its own grid (the default phase step at every ratio).
        metrics, result = sweep_banded(sweep_law_stack, stacked, n, template, options,
                                       devices=devices, phase_step=spec.phase_step)
        count = len(laws)
        out = {k: np.asarray(getattr(metrics, k))[:count] for k in METRICS}
        ratios = np.tile(spec.period_ratio, count)
        raise_if_failed(jax.tree.map(lambda x: x[:count].reshape(-1), result),
                        lambda i: f"{options.method} sweep at period ratio {ratios[i]:g} "
                        f"(law {laws[i // spec.period_ratio.size].name})",
                        out["ct"].reshape(-1), out["residual"].reshape(-1))
        out["ca"] = np.asarray(stacked_ca(stacked))[:count]
        return out
    # One grid at the spec's phase step for every ratio (the default grid meets the default).
    finer = ({"resolution": default_resolution(spec.period_ratio.max(), spec.phase_step)}
             if spec.method == "exact" and spec.phase_step != MAX_PHASE_STEP else {})
    curves = ct_curves(laws, spec.period_ratio, damping=spec.damping[d], method=spec.method,
                       dwell=spec.dwell, devices=devices, **finer)
    out = {k: np.stack([getattr(curves[law.name], k) for law in laws]) for k in METRICS}
    out["ca"] = np.asarray([curves[law.name].ca for law in laws])
    return out


def _claim_output(spec: SweepSpec) -> None:
    """Create the output directory, or check that it holds this same sweep."""
    (spec.output / "chunks").mkdir(parents=True, exist_ok=True)
    stamp = spec.output / "spec.json"
    record = {"fingerprint": spec.fingerprint, "laws": len(spec.laws),
              "period_ratios": int(spec.period_ratio.size), "damping": list(spec.damping),
              "method": spec.method, "laws_per_chunk": spec.laws_per_chunk,
              "phase_step": spec.phase_step}
    if stamp.exists():
        found = json.loads(stamp.read_text()).get("fingerprint")
        if found != spec.fingerprint:
            raise ValueError(f"{spec.output} holds a different sweep (spec changed); "
                             "choose another output directory or delete it")
        return
    tmp = stamp.with_name(f".spec.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(record, indent=1) + "\n")
    os.replace(tmp, stamp)


def missing_chunks(spec: SweepSpec) -> list[tuple[int, int]]:
    """Chunks with no file yet."""
    return [c for c in spec.chunks() if not spec.chunk_path(c).exists()]


def run_sweep(spec: SweepSpec, *, process_id: int = 0, num_processes: int = 1,
              devices=None, progress: bool | None = None) -> list[tuple[int, int]]:
    """Compute this process's missing chunks; returns the chunks it computed.

    Process ``process_id`` of ``num_processes`` takes every ``num_processes``-th chunk.
    ``progress=None`` shows a tqdm bar (with the time left) when stderr is a terminal.
    """
    from tqdm import tqdm

    _claim_output(spec)
    mine = [c for i, c in enumerate(spec.chunks()) if i % num_processes == process_id]
    todo = [c for c in mine if not spec.chunk_path(c).exists()]
    done = []
    disable = (not sys.stderr.isatty()) if progress is None else not progress
    bar = tqdm(todo, desc=f"camjax sweep {process_id + 1}/{num_processes}", unit="chunk",
               file=sys.stderr, disable=disable, initial=len(mine) - len(todo),
               total=len(mine))
    for chunk in bar:
        _write_atomic(spec.chunk_path(chunk), **_compute_chunk(spec, chunk, devices))
        done.append(chunk)
    bar.close()
    return done


def merge(spec: SweepSpec) -> Path:
    """Gather every chunk into ``sweep.npz`` (arrays ``(damping, law, ratio)``)."""
    missing = missing_chunks(spec)
    if missing:
        raise ValueError(f"{len(missing)} of {len(spec.chunks())} chunks are missing "
                         f"(first: {spec.chunk_path(missing[0]).name}); run the sweep again")
    shape = (len(spec.damping), len(spec.laws), spec.period_ratio.size)
    merged = {k: np.empty(shape) for k in METRICS}
    ca = np.empty(len(spec.laws))
    for d, start in spec.chunks():
        with np.load(spec.chunk_path((d, start))) as part:
            stop = start + part["ca"].size
            for k in METRICS:
                merged[k][d, start:stop] = part[k]
            ca[start:stop] = part["ca"]
    path = spec.output / "sweep.npz"
    _write_atomic(path, law=np.asarray(spec.names), period_ratio=spec.period_ratio,
                  damping=np.asarray(spec.damping), ca=ca, **merged)
    return path


def initialize(coordinator: str | None = None, num_processes: int | None = None,
               process_id: int | None = None) -> tuple[int, int]:
    """Join a multi-process JAX run; returns ``(process_id, num_processes)``.

    Wraps ``jax.distributed.initialize`` (all arguments ``None``: let it detect the
    cluster, e.g. SLURM) and turns on CPU collectives (gloo) so the barrier works on
    CPU-only hosts.  Call before any other JAX computation.
    """
    import jax

    jax.config.update("jax_cpu_collectives_implementation", "gloo")
    jax.distributed.initialize(coordinator, num_processes, process_id)
    return jax.process_index(), jax.process_count()


def barrier(name: str) -> None:
    """Wait until every process of the run reaches this point."""
    import jax
    from jax.experimental import multihost_utils

    if jax.process_count() > 1:
        multihost_utils.sync_global_devices(name)


def run_distributed(spec: SweepSpec, *, devices=None, progress: bool | None = None):
    """:func:`run_sweep` on this process's share, a barrier, then process 0 merges.

    Returns the merged file's path on process 0 and ``None`` on the others.
    """
    import jax

    run_sweep(spec, process_id=jax.process_index(), num_processes=jax.process_count(),
              devices=devices, progress=progress)
    barrier("camjax-sweep-chunks")
    path = merge(spec) if jax.process_index() == 0 else None
    barrier("camjax-sweep-merged")
    return path
