"""The SCCA atlas's kernel: cost of one (law, n) evaluation, banded grids, accuracy.

Three parts, all in one process (so the ratios between them survive a shared machine):

1. **Profile** at each grid size the atlas uses: the grid and the sampled forcing of one
   law, then per period ratio the propagation alone and the whole evaluation
   (propagation, peak refinement over every interval, dwell and residual), one law
   against 1000 ratios, warm, in CPU seconds.
2. **Throughput** of one atlas chunk (64 laws of the face x 1000 ratios in [1, 30]) through
   the stacked path: on one grid sized by the largest ratio (the atlas before banding),
   banded at the default phase step 0.5, at 0.8, and at 1.0 (the atlas's setting), each
   as (law, n) evaluations per CPU second and as a ratio to the first.
3. **Accuracy** of the banded sweeps against ``ct_curve`` at its default grid on a sample
   of laws (20 random face laws and 10 extreme ones), undamped and at zeta = 0.05: the
   largest relative error in Ct and absolute error in R (units of Ca).

    python experiments/benchmarks/bench_atlas.py        # writes results/scca_atlas/bench.json
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", type=Path, default=HERE.parents[1] / "results" / "scca_atlas")
    args = parser.parse_args()
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "")
                               + " --xla_force_host_platform_device_count=1").strip()

    import jax
    import jax.numpy as jnp

    from camjax import ct_curve, distributed
    from camjax.laws import SCCA
    from camjax.models import SpringMassOptions, batch_metrics
    from camjax.sdof import chunk_nodes, motion_grid, propagate
    from camjax.studies import timed
    from camjax.sweep import prepare_sweep, resolution_bands, sweep_banded, sweep_law_stack

    report = {"cores": os.cpu_count(), "load_before": [round(x, 2) for x in os.getloadavg()]}
    ratios = np.linspace(1.0, 30.0, 1000)
    face = distributed.scca_grid(0.01, face=True)
    law = SCCA(0.25, 0.5, 0.25)

    # 1. profile
    profile = {}
    grid_of = jax.jit(lambda law, r: motion_grid(law, r).forcing, static_argnums=1)
    n = jnp.asarray(ratios)
    for resolution in (128, 192, 256, 384):
        options = SpringMassOptions(resolution=resolution)

        @jax.jit
        def propagation_only(law, n, resolution=resolution):
            # in chunks of ratios as batch_metrics runs them (the same working set)
            grid = motion_grid(law, resolution)
            rows = -(-n.size // max(1, chunk_nodes() // grid.nodes.shape[0]))
            n = jnp.pad(n, (0, (-n.size) % rows), mode="edge").reshape(rows, -1)
            return jax.lax.map(jax.vmap(lambda m: propagate(grid, 2 * jnp.pi * m, 0.0)[-1]), n)

        grid_s = timed(lambda r=resolution: grid_of(law, r), args.repeats, clock=time.process_time).best_s
        prop_s = timed(lambda f=propagation_only: f(law, n), args.repeats, clock=time.process_time).best_s
        full_s = timed(lambda o=options: batch_metrics(law, n, 0.0, o), args.repeats, clock=time.process_time).best_s
        row = {"intervals": resolution + 8, "grid_per_law_us": round(1e6 * grid_s, 1),
               "propagation_per_eval_us": round(1e6 * prop_s / n.size, 3),
               "evaluation_per_eval_us": round(1e6 * full_s / n.size, 3)}
        row["metrics_share"] = round(1 - prop_s / full_s, 2)
        profile[resolution] = row
        print(f"grid {resolution}+8: {row}", flush=True)
    report["profile_one_law_1000_ratios"] = profile

    # 2. throughput of one chunk
    chunk = face[1000:1064]
    stack = jax.tree.map(lambda *x: jnp.stack(x), *chunk)
    n, template, options = prepare_sweep(ratios)
    runs = {
        "one grid (before)": lambda: sweep_law_stack(stack, jnp.asarray(n), template, options,
                                                     devices=1),
        "banded 0.5": lambda: sweep_banded(sweep_law_stack, stack, n, template, options,
                                           devices=1, phase_step=0.5),
        "banded 0.8": lambda: sweep_banded(sweep_law_stack, stack, n, template, options,
                                           devices=1, phase_step=0.8),
        "banded 1.0": lambda: sweep_banded(sweep_law_stack, stack, n, template, options,
                                           devices=1, phase_step=1.0),
    }
    throughput = {}
    for name, run in runs.items():
        start = time.perf_counter()
        jax.block_until_ready(run())
        first = time.perf_counter() - start
        seconds = timed(run, max(2, args.repeats // 2), clock=time.process_time).best_s
        throughput[name] = {"first_call_s": round(first, 2), "cpu_s": round(seconds, 3),
                            "evaluations_per_cpu_s": round(len(chunk) * n.size / seconds)}
    base = throughput["one grid (before)"]["evaluations_per_cpu_s"]
    for name, row in throughput.items():
        row["over_before"] = round(row["evaluations_per_cpu_s"] / base, 2)
        step = float(name.split()[-1]) if "banded" in name else None
        row["bands"] = len(resolution_bands(n, options, phase_step=step)) if step else 1
        print(f"{name}: {row}", flush=True)
    report["chunk_64_laws_x_1000"] = throughput

    # 3. accuracy against ct_curve at its default grid
    rng = np.random.default_rng(0)
    sample = [face[i] for i in rng.choice(len(face), 20, replace=False)]
    sample += [SCCA(*f) for f in ((0.01, 0.98, 0.01), (0.01, 0, 0.99), (0.99, 0, 0.01),
                                  (0, 0, 1), (0, 1, 0), (0.5, 0, 0.5), (0.25, 0.5, 0.25),
                                  (0.01, 0.01, 0.98), (0.98, 0.01, 0.01), (0, 0.01, 0.99))]
    stack = jax.tree.map(lambda *x: jnp.stack(x), *sample)
    accuracy = {}
    for damping in (0.0, 0.05):
        reference = [ct_curve(law, ratios, damping=damping, devices=1) for law in sample]
        ref_ct = np.stack([c.ct for c in reference])
        ref_r = np.stack([c.residual for c in reference])
        n, template, options = prepare_sweep(ratios, damping=damping)
        for step in (0.5, 0.8, 1.0):
            metrics, _ = sweep_banded(sweep_law_stack, stack, n, template, options, devices=1,
                                      phase_step=step)
            ct_err = np.abs(np.asarray(metrics.ct) - ref_ct) / ref_ct
            accuracy[f"zeta {damping:g}, phase step {step:g}"] = {
                "max_ct_rel_error": float(f"{ct_err.max():.3g}"),
                "worst_law": sample[int(np.argmax(ct_err.max(axis=1)))].name,
                "max_r_abs_error": float(f"{np.abs(np.asarray(metrics.residual) - ref_r).max():.3g}"),
            }
            print(f"zeta {damping:g}, phase step {step:g}: "
                  f"{accuracy[f'zeta {damping:g}, phase step {step:g}']}", flush=True)
    report["accuracy_vs_ct_curve"] = accuracy
    report["peak_memory_gib"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20, 3)
    report["load_after"] = [round(x, 2) for x in os.getloadavg()]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench.json").write_text(json.dumps(report, indent=1) + "\n")
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
