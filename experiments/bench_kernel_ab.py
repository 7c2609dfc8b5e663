"""A/B the exact kernel (propagation, batching, peak search) against another git revision's,
in one process.

The warm time of a whole-curve kernel moves by up to 1.5x between processes on a shared
machine, which hides changes of a few percent.  This loads ``camjax/sdof/_step.py``,
``_batch.py`` and ``_peaks.py`` of ``--baseline`` (a git revision), with the
``camjax/metrics.py`` they refine peaks with, beside the working tree's, builds the same
1000-ratio kernel (propagation, refined peak, dwell, residual) on each, checks that they
agree, and times them in turn.

    python experiments/bench_kernel_ab.py --baseline 6dcd6bb [--n-max 30] [--repeats 15]
        [--laws cycloidal modified-sine poly4567] [--damping 0.0]

``--laws`` takes any law spec (``parabolic``, ``scca:0.2,0.6,0.2``); ``--damping`` is the
damping ratio of the timed runs.
"""

from __future__ import annotations

import argparse
import importlib.util
import inspect
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from camjax import laws
from camjax.models import SpringMassOptions
from camjax.sdof import SampledLaw, chunked_map, dwell_peak, peak_in_motion, residual_of_mode
from camjax.sdof import _step as current


def baseline_module(revision: str, name: str):
    """``camjax/sdof/<name>.py`` (or ``camjax/<name>.py`` for ``metrics``) at ``revision``,
    imported as a stand-alone module; the sdof modules import the baseline's metrics."""
    root = Path(__file__).resolve().parents[1]
    path = "camjax/metrics.py" if name == "metrics" else f"camjax/sdof/{name}.py"
    source = subprocess.run(["git", "show", f"{revision}:{path}"], cwd=root,
                            check=True, capture_output=True, text=True).stdout
    source = source.replace("from ..metrics import", "from baselinemetrics import")
    source = source.replace("from ._", "from camjax.sdof._").replace("from ..", "from camjax.")
    path = Path(tempfile.mkdtemp(prefix="camjax-ab-")) / f"baseline{name}.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(f"baseline{name}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[f"baseline{name}"] = module
    spec.loader.exec_module(module)
    return module


def kernel(propagate, chunked_map, peak_in_motion, sampled: SampledLaw, zeta: float = 0.0,
           gather=None):
    grid = sampled.grid

    # The SDOF path's own setting where the revision has it (its grids resolve w h <= 1).
    resolved = {"resolved": True} if "resolved" in inspect.signature(propagate).parameters else {}

    def one(n):
        w = 2 * jnp.pi * n
        q = propagate(grid, w, zeta, gather=gather, **resolved)
        peak = jnp.maximum(peak_in_motion(q, grid, w, zeta), dwell_peak(q[-1], w, zeta, 1.0))
        return peak, residual_of_mode(q[-1], w, zeta)

    return jax.jit(lambda n: chunked_map(one, n, grid.nodes.shape[0]))


def difference(outputs) -> tuple[float, float]:
    """Largest relative difference of the peaks and absolute of the residuals."""
    (peak, residual), (base_peak, base_residual) = outputs["current"], outputs["baseline"]
    return (float(jnp.max(jnp.abs(peak - base_peak) / base_peak)),
            float(jnp.max(jnp.abs(residual - base_residual))))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", required=True, help="git revision to compare against")
    parser.add_argument("--n-max", type=float, default=30.0, help="ratios in [1, N_MAX]")
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--laws", nargs="+", default=["cycloidal", "modified-sine", "poly4567"])
    parser.add_argument("--damping", type=float, default=0.0, help="of the timed runs")
    args = parser.parse_args()
    baseline_module(args.baseline, "metrics")  # registered for the baseline's _peaks
    base_grid, base_peaks = (baseline_module(args.baseline, name) for name in ("_grid", "_peaks"))
    variants = {
        "baseline": (baseline_module(args.baseline, "_step").propagate,
                     baseline_module(args.baseline, "_batch").chunked_map,
                     base_peaks.peak_in_motion),
        "current": (current.propagate, chunked_map, peak_in_motion),
    }
    # Each kernel on its own revision's default grid for the SDOF path: the working tree's
    # from its options; a baseline's at ``MAX_PHASE_STEP`` if its peaks are refined by
    # degree 11 (``REFINED_DERIVATIVES``, from 12aff92), else at its default step (0.5).
    step = (base_grid.MAX_PHASE_STEP if hasattr(base_peaks, "REFINED_DERIVATIVES")
            else base_grid.TARGET_PHASE_STEP)
    resolutions = {"baseline": base_grid.default_resolution(args.n_max, step),
                   "current": SpringMassOptions().checked(args.n_max).resolution}
    print(f"grids: {resolutions}")
    n = jnp.linspace(1.0, args.n_max, 1000)
    times = {key: [] for key in variants}
    for name in args.laws:
        samplers = {"baseline": base_grid.SampledLaw, "current": SampledLaw}  # each its layout
        sampled = {key: samplers[key].of(laws.as_law(name), resolutions[key], 8) for key in variants}
        # Agreement: undamped, damped, and with each interval's weights gathered (the path
        # of a program's turn).
        for zeta, gather in ((0.0, None), (0.05, None), (0.2, None), (0.05, True)):
            out = {key: kernel(*parts, sampled[key], zeta, gather)(n)
                   for key, parts in variants.items()}
            peak, residual = difference(out)
            print(f"{name}, damping {zeta}{', gathered' if gather else ''}: peak differs by "
                  f"{peak:.1e} (relative), residual by {residual:.1e}")
        fns = {key: kernel(*parts, sampled[key], args.damping) for key, parts in variants.items()}
        for f in fns.values():
            jax.block_until_ready(f(n))
        for repeat in range(args.repeats):  # in turn, each first as often as the other
            for key in (list(fns) if repeat % 2 == 0 else list(fns)[::-1]):
                start = time.perf_counter()
                jax.block_until_ready(fns[key](n))
                times[key].append(time.perf_counter() - start)
    for key, values in times.items():
        print(f"{key:9s} median {1e3 * np.median(values):.2f} ms over {len(values)} runs "
              f"(damping {args.damping})")
    print(f"baseline / current: {np.median(times['baseline']) / np.median(times['current']):.3f}")


if __name__ == "__main__":
    main()
