"""Speed and accuracy of one law's 1000-point Ct curve: exact path, diffrax, scipy.

For 1000 period ratios in [1, 30] and every standard law: warm time and compile time of
the exact path and of the diffrax path (Tsit5), and the time of a scipy ``solve_ivp``
(DOP853, rtol 1e-10) loop over the same n (timed on a subset and scaled, since it runs
at Python speed), all in this process; each compared with the exact path at 4x the
default resolution.  Writes results/bench_ct/results.md and .json.

    python experiments/benchmarks/bench_ct.py [--scipy-subset 40]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import jax.numpy as jnp
import numpy as np

from camjax import laws
from camjax.models import SpringMassOptions, batch_metrics
from camjax.studies import scipy_reference, timed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scipy-subset", type=int, default=40,
                        help="period ratios timed for the scipy loop (scaled to 1000)")
    parser.add_argument("--out", default="results/bench_ct")
    args = parser.parse_args()
    n = np.linspace(1.0, 30.0, 1000)
    nj = jnp.asarray(n)
    rows = []
    for law in laws.standard_laws():
        exact_opts = SpringMassOptions().checked(30.0)
        ref_opts = SpringMassOptions(resolution=4 * exact_opts.resolution).checked(30.0)
        ode_opts = SpringMassOptions(method="tsit5", rtol=1e-10, atol=1e-12).checked(30.0)
        ref = batch_metrics(law, nj, 0.0, ref_opts)[0]
        exact = timed(lambda law=law, o=exact_opts: batch_metrics(law, nj, 0.0, o))
        exact_first, exact_warm = exact.first_s, exact.best_s
        ode = timed(lambda law=law, o=ode_opts: batch_metrics(law, nj, 0.0, o), repeats=2)
        ode_first, ode_warm = ode.first_s, ode.best_s
        exact = batch_metrics(law, nj, 0.0, exact_opts)[0]
        ode = batch_metrics(law, nj, 0.0, ode_opts)[0]
        subset = np.linspace(0, n.size - 1, args.scipy_subset).astype(int)
        start = time.perf_counter()
        sp = np.array([scipy_reference(law, n[i], "DOP853", 1e-10)[:2] for i in subset])
        scipy_time = (time.perf_counter() - start) * n.size / subset.size

        def err(m, idx=slice(None), ref=ref):
            ct_ref, r_ref = np.asarray(ref.ct)[idx], np.asarray(ref.residual)[idx]
            return (float(np.max(np.abs(np.asarray(m[0]) - ct_ref) / ct_ref)),
                    float(np.max(np.abs(np.asarray(m[1]) - r_ref))))

        rows.append({
            "law": law.name,
            "exact_warm_s": exact_warm, "exact_compile_s": exact_first - exact_warm,
            "exact_ct_rel_err": err((exact.ct, exact.residual))[0],
            "exact_r_abs_err": err((exact.ct, exact.residual))[1],
            "tsit5_warm_s": ode_warm, "tsit5_compile_s": ode_first - ode_warm,
            "tsit5_ct_rel_err": err((ode.ct, ode.residual))[0],
            "tsit5_r_abs_err": err((ode.ct, ode.residual))[1],
            "scipy_s_scaled": scipy_time,
            "scipy_ct_rel_err": err((sp[:, 0], sp[:, 1]), subset)[0],
            "scipy_r_abs_err": err((sp[:, 0], sp[:, 1]), subset)[1],
            "speedup_vs_scipy": scipy_time / exact_warm,
        })
        r = rows[-1]
        print(f"{law.name:<20} exact {1e3 * exact_warm:6.1f} ms (compile {r['exact_compile_s']:.1f} s, "
              f"Ct err {r['exact_ct_rel_err']:.1e})  tsit5 {1e3 * ode_warm:7.1f} ms "
              f"(Ct err {r['tsit5_ct_rel_err']:.1e})  scipy {scipy_time:6.1f} s "
              f"(Ct err {r['scipy_ct_rel_err']:.1e})  exact/scipy speed-up {r['speedup_vs_scipy']:.0f}x",
              flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(json.dumps(rows, indent=1))
    lines = [
        "| law | exact warm (ms) | exact compile (s) | exact max Ct rel. err | exact max R abs. err "
        "| tsit5 warm (ms) | tsit5 max Ct rel. err | scipy DOP853 loop (s) | scipy max Ct rel. err "
        "| scipy max R abs. err | speed-up vs scipy |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['law']} | {1e3 * r['exact_warm_s']:.1f} | {r['exact_compile_s']:.2f} "
            f"| {r['exact_ct_rel_err']:.1e} | {r['exact_r_abs_err']:.1e} "
            f"| {1e3 * r['tsit5_warm_s']:.0f} | {r['tsit5_ct_rel_err']:.1e} | {r['scipy_s_scaled']:.1f} "
            f"| {r['scipy_ct_rel_err']:.1e} | {r['scipy_r_abs_err']:.1e} | {r['speedup_vs_scipy']:.0f}x |"
        )
    (out / "results.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
