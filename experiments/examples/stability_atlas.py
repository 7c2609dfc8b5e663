"""Stability atlas: where each solution method fails, and whether camjax says so.

Panels (results/stability_atlas/atlas.png):
1. fixed-step explicit solvers (Euler; Heun, whose stability polynomial Midpoint and
   Ralston share) over period ratio and step count: the Ct error, or the failure camjax
   reports; the line is the detection limit (free-vibration growth 1.1 over the rise);
2. adaptive solvers with and without ``jump_ts`` on laws with jumps: accepted and
   rejected steps against period ratio (the wasted work);
3. float32 against float64: the Ct error of the exact path and of Tsit5 against n;
4. very high period ratios: error and steps of the exact path and of Tsit5 up to n = 300
   (one grid for the batch, set by n = 300);
5. the exact path on the default grid of a range [1, top] (top 30, 100, 200, 300): the
   ratios near the top, sampled at w h near 0.5, where a peak search that refines only the
   largest samples misses the crest (camjax's refines every interval, so none is skipped).

    python experiments/examples/stability_atlas.py            # about six minutes on 2 cores (under load)
    python experiments/examples/stability_atlas.py --quick    # a smoke run
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def fixed_step_map(n, step_counts, methods=("euler", "heun")):
    """``{method: (len(steps), len(n))}`` Ct error (NaN where camjax reported a failure)."""
    import jax.numpy as jnp

    import camjax
    from camjax.models import SpringMassOptions, batch_metrics
    from camjax.studies import reference_metrics

    law = camjax.laws.get("cycloidal")
    ref_ct, _ = reference_metrics(law, n)
    errors, failed = {}, {}
    for method in methods:
        err = np.full((len(step_counts), n.size), np.nan)
        bad = np.zeros_like(err, dtype=bool)
        for i, steps in enumerate(step_counts):
            options = SpringMassOptions(method=method, steps=int(steps)).checked(float(n.max()))
            metrics, result, _ = batch_metrics(law, jnp.asarray(n), 0.0, options)
            bad[i] = ~np.asarray(result == camjax.RESULTS.successful)
            err[i] = np.where(bad[i], np.nan, np.abs(np.asarray(metrics.ct) - ref_ct))
        errors[method], failed[method] = err, bad
    return errors, failed


def jump_ts_work(n, law_names=("parabolic", "modified-trapezoid"), rtol=1e-8):
    """Accepted and rejected steps of Tsit5 with and without ``jump_ts``, per n."""
    import diffrax
    import jax
    import jax.numpy as jnp

    import camjax
    from camjax.sdof import sdof_term

    out = {}
    for name in law_names:
        law = camjax.laws.get(name)
        for use_jumps in (True, False):
            controller = diffrax.PIDController(rtol=rtol, atol=rtol * 1e-2)
            if use_jumps:
                controller = diffrax.ClipStepSizeController(
                    controller, jump_ts=jnp.asarray(law.breakpoints(), dtype=float))

            @jax.jit
            @jax.vmap
            def stats(period_ratio, controller=controller, law=law):
                solution = diffrax.diffeqsolve(
                    sdof_term(), diffrax.Tsit5(), 0.0, 1.0, None,
                    (jnp.zeros(()), jnp.zeros(())), args=(law, 2 * jnp.pi * period_ratio, 0.0),
                    stepsize_controller=controller, max_steps=100_000)
                return solution.stats["num_accepted_steps"], solution.stats["num_rejected_steps"]

            accepted, rejected = stats(jnp.asarray(n))
            out[f"{name} {'jump_ts' if use_jumps else 'no jump_ts'}"] = (np.asarray(accepted), np.asarray(rejected))
    return out


def float32_errors(n, law_name="modified-trapezoid"):
    """Ct error against n of the float32 runs (from the work-precision float32 worker)."""
    import camjax
    from camjax.studies import reference_metrics

    spec = Path(f"/tmp/camjax_atlas_float32_{os.getpid()}.json")
    spec.write_text(json.dumps({"law": law_name, "n": n.tolist()}))
    subprocess.run([sys.executable, str(HERE.parent / "benchmarks" / "work_precision.py"), "--float32-worker", str(spec)],
                   env={**os.environ, "JAX_ENABLE_X64": "0"}, check=True)
    data = json.loads(spec.read_text())
    spec.unlink()
    ref_ct, _ = reference_metrics(camjax.laws.get(law_name), n)
    return {label: np.abs(np.asarray(d["ct"]) - ref_ct) for label, d in data.items()}


def high_period_ratio(n, law_name="modified-trapezoid"):
    """Ct error and steps against n of the exact path (default grid) and Tsit5 (rtol 1e-8)."""
    import jax.numpy as jnp

    import camjax
    from camjax.models import SpringMassOptions, batch_metrics
    from camjax.studies import reference_metrics

    law = camjax.laws.get(law_name)
    ref_ct, _ = reference_metrics(law, n)
    out = {}
    for label, options in (("exact default", SpringMassOptions()),
                           ("tsit5 rtol=1e-8", SpringMassOptions(method="tsit5", rtol=1e-8, atol=1e-10))):
        metrics, _, steps = batch_metrics(law, jnp.asarray(n), 0.0, options.checked(float(n.max())))
        out[label] = (np.abs(np.asarray(metrics.ct) - ref_ct), np.asarray(steps))
    return out


def default_grid_ranges(range_tops, count, law_names=("harmonic", "modified-trapezoid")):
    """Ct error of the exact path on the default grid of each range ``[1, top]``.

    ``ct_curve(law, n)`` picks its grid from the largest ``n`` (``w h <= 0.5``), so the
    ratios near the top of a range are sampled at about 0.5 rad per interval.  Each
    segment ``(previous top, top]`` is computed on the grid of ``[1, top]``, as a user
    sweeping ``[1, top]`` gets it; the reference is the exact path at four times that grid.
    Returns ``{law: (n, error)}``.
    """
    import jax.numpy as jnp

    import camjax
    from camjax.models import SpringMassOptions, batch_metrics
    from camjax.studies import reference_metrics

    out = {}
    for name in law_names:
        law = camjax.laws.get(name)
        n_all, err_all = [], []
        for low, top in zip((1.0, *range_tops[:-1]), range_tops):
            n = np.linspace(low, top, count + 1)[1:] if low > 1.0 else np.linspace(low, top, count)
            ref_ct, _ = reference_metrics(law, n, max_period_ratio=top)
            metrics, _, _ = batch_metrics(law, jnp.asarray(n), 0.0, SpringMassOptions().checked(float(top)))
            n_all.append(n)
            err_all.append(np.abs(np.asarray(metrics.ct) - ref_ct))
        out[name] = (np.concatenate(n_all), np.concatenate(err_all))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="8 ratios per panel, 3 step counts (a smoke run)")
    parser.add_argument("--out", default="results/stability_atlas")
    args = parser.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    from camjax.solvers import MAX_FREE_VIBRATION_GROWTH

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    count = 8 if args.quick else 80
    n_fixed = np.geomspace(1.0, 100.0, count)
    steps = np.array([250, 1000, 4000] if args.quick else [125, 250, 500, 1000, 2000, 4000, 8000, 16000, 32000, 64000])
    errors, failed = fixed_step_map(n_fixed, steps)
    n_jump = np.linspace(1.0, 30.0, count)
    work = jump_ts_work(n_jump)
    n_f32 = np.linspace(1.0, 30.0, count)
    f32 = float32_errors(n_f32)
    n_high = np.geomspace(1.0, 300.0, count)
    high = high_period_ratio(n_high)
    range_tops = (30.0, 100.0, 200.0, 300.0)
    grid_errors = default_grid_ranges(range_tops, 5 * count)

    fig, axes = plt.subplots(2, 4, figsize=(20, 8.5))
    for ax, method in zip(axes[0][:2], errors):
        err = np.where(failed[method], np.nan, np.maximum(errors[method], 1e-16))
        mesh = ax.pcolormesh(n_fixed, steps, err, norm=LogNorm(1e-10, 1.0), shading="nearest", cmap="viridis")
        ax.contourf(n_fixed, steps, failed[method].astype(float), levels=[0.5, 1.5], colors="none",
                    hatches=["xx"])
        # Detection limit: growth**(1/steps) of the stability polynomial at w h.
        w = 2 * np.pi * n_fixed
        fine_steps = np.geomspace(steps.min(), steps.max(), 200)
        ratio = np.log(MAX_FREE_VIBRATION_GROWTH)
        theta = w[None, :] / fine_steps[:, None]
        growth = np.log1p(theta**2) / 2 if method == "euler" else np.log1p(theta**4 / 4) / 2
        ax.contour(n_fixed, fine_steps, fine_steps[:, None] * growth, levels=[ratio], colors="r")
        ax.set(xscale="log", yscale="log", xlabel="period ratio n", ylabel="steps over the rise",
               title=f"{method}: Ct error (hatched: SolverError)")
        fig.colorbar(mesh, ax=ax, label="|Ct - Ct_ref|")
    ax = axes[0][2]
    for label, (accepted, rejected) in work.items():
        line, = ax.plot(n_jump, accepted, label=f"{label}: accepted")
        ax.plot(n_jump, rejected, ls="--", color=line.get_color(), label=f"{label}: rejected")
    ax.set(yscale="log", xlabel="period ratio n", ylabel="steps", title="Tsit5 rtol 1e-8: jump_ts or not")
    ax.legend(fontsize=6)
    ax = axes[1][0]
    for label, err in f32.items():
        ax.semilogy(n_f32, np.maximum(err, 1e-16), label=f"{label} (float32)")
    ax.set(xlabel="period ratio n", ylabel="|Ct - Ct_ref (float64)|", title="float32 error floor (ModTrap)")
    ax.legend(fontsize=7)
    ax = axes[1][1]
    for label, (err, _) in high.items():
        ax.loglog(n_high, np.maximum(err, 1e-17), label=label)
    ax.set(xlabel="period ratio n", ylabel="|Ct - Ct_ref|", title="high period ratios (ModTrap), float64")
    ax.legend(fontsize=7)
    ax = axes[1][2]
    for label, (_, st) in high.items():
        ax.loglog(n_high, st, label=label)
    ax.set(xlabel="period ratio n", ylabel="steps (grid intervals for exact)", title="work at high period ratios")
    ax.legend(fontsize=7)
    ax = axes[0][3]
    for label, (n_grid, err) in grid_errors.items():
        ax.semilogy(n_grid, np.maximum(err, 1e-16), ".", ms=3, label=label)
    for top in range_tops:
        ax.axvline(top, color="grey", lw=0.6, ls=":")
    ax.axhline(1e-6, color="k", lw=0.8, ls="--", label="1e-6")
    ax.set(xlabel="period ratio n (grid of the range [1, next dotted line])", ylabel="|Ct - Ct_ref|",
           title="exact path, default grid of each range (w h -> 0.5)")
    ax.legend(fontsize=7)
    axes[1][3].axis("off")
    fig.tight_layout()
    fig.savefig(out / "atlas.png", dpi=120)

    summary = {
        "command": "python " + " ".join(sys.argv),
        "fixed_step_failed_fraction": {m: float(failed[m].mean()) for m in failed},
        "fixed_step_max_error_accepted": {m: float(np.nanmax(errors[m])) for m in errors},
        "jump_ts_steps_total": {k: [int(a.sum()), int(r.sum())] for k, (a, r) in work.items()},
        "float32_max_ct_error": {k: float(np.max(v)) for k, v in f32.items()},
        "high_n_max_ct_error": {k: float(np.max(e)) for k, (e, _) in high.items()},
        "high_n_max_steps": {k: int(np.max(s)) for k, (_, s) in high.items()},
        "default_grid_ranges": list(range_tops),
        "default_grid_max_ct_error": {k: float(np.max(e)) for k, (_, e) in grid_errors.items()},
        "default_grid_ratios_above_1e-6": {
            k: [round(float(x), 3) for x in n_grid[e > 1e-6]] for k, (n_grid, e) in grid_errors.items()},
    }
    (out / "atlas.json").write_text(json.dumps(summary, indent=1))
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
