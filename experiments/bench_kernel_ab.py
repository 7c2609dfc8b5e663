"""A/B the exact kernel's propagation and batching against another git revision's, in one
process.

The warm time of a whole-curve kernel moves by up to 1.5x between processes on a shared
machine, which hides changes of a few percent.  This loads ``camjax/sdof/_step.py`` and
``_batch.py`` of ``--baseline`` (a git revision) beside the working tree's, builds the same
1000-ratio kernel (propagation, refined peak, dwell, residual) on each, checks that they
agree, and times them in turn.

    python experiments/bench_kernel_ab.py --baseline 6dcd6bb [--n-max 30] [--repeats 15]
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
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
    """``camjax/sdof/<name>.py`` at ``revision``, imported as a stand-alone module."""
    root = Path(__file__).resolve().parents[1]
    source = subprocess.run(["git", "show", f"{revision}:camjax/sdof/{name}.py"], cwd=root,
                            check=True, capture_output=True, text=True).stdout
    source = source.replace("from ._grid import", "from camjax.sdof._grid import")
    path = Path(tempfile.mkdtemp()) / f"baseline{name}.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(f"baseline{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def kernel(propagate, chunked_map, sampled: SampledLaw):
    grid = sampled.grid

    def one(n):
        w = 2 * jnp.pi * n
        q = propagate(grid, w, 0.0)
        peak = jnp.maximum(peak_in_motion(q, grid, w, 0.0), dwell_peak(q[-1], w, 0.0, 1.0))
        return peak, residual_of_mode(q[-1], w, 0.0)

    return jax.jit(lambda n: chunked_map(one, n, grid.nodes.shape[0]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", required=True, help="git revision to compare against")
    parser.add_argument("--n-max", type=float, default=30.0, help="ratios in [1, N_MAX]")
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    variants = {
        "baseline": (baseline_module(args.baseline, "_step").propagate,
                     baseline_module(args.baseline, "_batch").chunked_map),
        "current": (current.propagate, chunked_map),
    }
    n = jnp.linspace(1.0, args.n_max, 1000)
    options = SpringMassOptions().checked(args.n_max)
    times = {key: [] for key in variants}
    for name in ("cycloidal", "modified-sine", "poly4567"):
        sampled = SampledLaw.of(laws.as_law(name), options.resolution, 8)
        fns = {key: kernel(*parts, sampled) for key, parts in variants.items()}
        out = {key: jax.block_until_ready(f(n)) for key, f in fns.items()}
        peak = float(jnp.max(jnp.abs(out["current"][0] - out["baseline"][0]) / out["baseline"][0]))
        residual = float(jnp.max(jnp.abs(out["current"][1] - out["baseline"][1])))
        print(f"{name}: peak differs by {peak:.1e} (relative), residual by {residual:.1e}")
        for _ in range(args.repeats):
            for key, f in fns.items():
                start = time.perf_counter()
                jax.block_until_ready(f(n))
                times[key].append(time.perf_counter() - start)
    for key, values in times.items():
        print(f"{key:9s} median {1e3 * np.median(values):.2f} ms over {len(values)} runs")
    print(f"baseline / current: {np.median(times['baseline']) / np.median(times['current']):.3f}")


if __name__ == "__main__":
    main()
