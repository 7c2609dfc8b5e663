"""The exact path's kernel: the candidate peak search against the dense one, in one process.

For a 1000-ratio Ct curve over n in [1, 30] (cycloidal, modified sine, 4-5-6-7): the warm
kernel (``batch_metrics`` on a sampled law) with the default peak search (only the intervals
a rigorous bound leaves in play are refined, ``camjax.sdof.bounded_peak_in_motion``) and with
every interval refined (``dense_peak_in_motion``, the search before), the warm
``camjax.ct_curve`` (kernel plus host), and the share of ratios whose candidates overflowed.
Then SCCA laws of the face x 1000 ratios through ``camjax.ct_curves``, and the accuracy of
both searches against the exact path at 4x its grid (Ct relative, R absolute) over
n in [0.5, 100] at damping 0, 0.05, 0.2.  Medians of CPU time (``time.process_time``: the
machine is shared), milliseconds.

    python experiments/bench_kernel.py [--repeats 7] [--scca-laws 64]
"""

from __future__ import annotations

import argparse
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import camjax
from camjax import distributed, sweep
from camjax.laws import standard_laws
from camjax.models import SpringMass, SpringMassOptions, batch_metrics
from camjax.sdof import (
    bounded_peak_in_motion,
    chunked_map,
    dense_peak_in_motion,
    dwell_peak,
    propagate,
    residual_of_mode,
)
from camjax.studies import timed


def median_ms(fn, repeats: int) -> float:
    """Median warm CPU time of ``fn()`` (ms)."""
    return 1e3 * timed(fn, repeats, clock=time.process_time).median_s


@eqx.filter_jit
def dense_metrics(law, n, damping, options):
    """``batch_metrics`` with every interval refined (the search before the bound)."""
    grid = law.grid

    def one(x):
        omega = 2 * jnp.pi * x
        q = propagate(grid, omega, damping)
        peak = dense_peak_in_motion(q, grid, omega, damping)
        ct = jnp.maximum(peak, dwell_peak(q[-1], omega, damping, options.dwell)) / law.Ca
        return ct, residual_of_mode(q[-1], omega, damping) / law.Ca

    return chunked_map(one, n, grid.nodes.shape[0])


@jax.jit
def overflow_share(law, n):
    grid = law.grid

    def one(x):
        omega = 2 * jnp.pi * x
        return bounded_peak_in_motion(propagate(grid, omega, 0.0), grid, omega, 0.0)[1]

    return jnp.mean(chunked_map(one, n, grid.nodes.shape[0]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--scca-laws", type=int, default=64)
    args = parser.parse_args()
    n = np.linspace(1, 30, 1000)
    ratios, template, options = sweep.prepare_sweep(n)
    chosen = {law.name: law for law in standard_laws()}
    print(f"{'law':<14} {'dense ms':>9} {'bounded ms':>11} {'ratio':>6} {'ct_curve ms':>12} "
          f"{'host ms':>8} {'overflow':>9}")
    for name in ("cycloidal", "modified-sine", "poly4567"):
        law = chosen[name]
        sampled = template.sweep_law(law, options)
        dense = median_ms(lambda s=sampled: dense_metrics(s, ratios, 0.0, options), args.repeats)
        bounded = median_ms(lambda s=sampled: batch_metrics(s, ratios, 0.0, options), args.repeats)
        curve = median_ms(lambda law=law: camjax.ct_curve(law, n).ct, args.repeats)
        share = float(overflow_share(sampled, ratios))
        print(f"{name:<14} {dense:9.1f} {bounded:11.1f} {dense / bounded:6.2f} {curve:12.1f} "
              f"{curve - bounded:8.1f} {share:9.1%}")

    face = distributed.scca_grid(0.01, face=True)
    pick = np.linspace(0, len(face) - 1, args.scca_laws).astype(int)
    scca = {f"scca{i}": face[i] for i in pick}
    camjax.ct_curves(scca, n)  # compile
    start = time.process_time()
    camjax.ct_curves(scca, n)
    spent = time.process_time() - start
    print(f"ct_curves: {len(scca)} SCCA laws x 1000 ratios {spent:.2f} s CPU "
          f"({1e3 * spent / len(scca):.1f} ms per law; 256 laws: {256 * spent / len(scca):.1f} s)")

    ns = jnp.asarray(np.linspace(0.5, 100, 200))
    grid_options = SpringMassOptions().checked(100.0)
    fine = SpringMassOptions(resolution=4 * grid_options.resolution).checked(100.0)
    worst = {"bounded": [0.0, 0.0], "dense": [0.0, 0.0]}
    for law in [*standard_laws(), *list(scca.values())[:: max(1, len(scca) // 3)]]:
        for damping in (0.0, 0.05, 0.2):
            ref = batch_metrics(law, ns, damping, fine)[0]
            sampled = SpringMass(1.0, damping).sweep_law(law, grid_options)
            runs = {"bounded": batch_metrics(sampled, ns, damping, grid_options)[0],
                    "dense": dense_metrics(sampled, ns, damping, grid_options)}
            for key, got in runs.items():
                ct, r = (got.ct, got.residual) if key == "bounded" else got
                worst[key][0] = max(worst[key][0], float(jnp.max(jnp.abs(ct - ref.ct) / ref.ct)))
                worst[key][1] = max(worst[key][1], float(jnp.max(jnp.abs(r - ref.residual))))
    for key, (ct_err, r_err) in worst.items():
        print(f"accuracy {key:<8} vs 4x grid, n in [0.5, 100], damping 0/0.05/0.2: "
              f"Ct rel {ct_err:.1e}, R abs {r_err:.1e}")


if __name__ == "__main__":
    main()
