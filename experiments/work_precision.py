"""Work-precision study: time against the error of Ct and R for every solution method.

For each law and method: warm wall time of the whole batch of period ratios, compile
time, steps, and the max error of Ct and R (units of Ca) against the exact path at a
high resolution.  Peers: scipy ``solve_ivp`` (timed on a subset of the period ratios and
scaled to the whole batch) and float32 (a subprocess with ``JAX_ENABLE_X64=0``).

    python experiments/work_precision.py                       # n in [1, 30], 1000 ratios
    python experiments/work_precision.py --n-max 100 --tag hard --laws poly4567,parabolic
    python experiments/work_precision.py --level quick --n-count 50   # a smoke run

Writes results/work_precision/<tag>.csv, .md, .json and .png.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

FLOAT32_CASES = (("exact default", {}), ("tsit5 rtol=1e-06", {"method": "tsit5", "rtol": 1e-6, "atol": 1e-8}),
                 ("tsit5 rtol=1e-08", {"method": "tsit5", "rtol": 1e-8, "atol": 1e-10}))
SCIPY_METHODS = (("RK45", 1e-6), ("RK45", 1e-9), ("DOP853", 1e-6), ("DOP853", 1e-10),
                 ("Radau", 1e-6), ("Radau", 1e-9), ("LSODA", 1e-6), ("LSODA", 1e-9))


def float32_worker(path: Path) -> None:
    """Run in a child with JAX_ENABLE_X64=0: Ct and R of each float32 case, to ``path``."""
    import diffrax
    import jax
    import jax.numpy as jnp

    import camjax
    from camjax.solve import SolveOptions, batch_metrics

    spec = json.loads(path.read_text())
    n = jnp.asarray(spec["n"], dtype=jnp.float32)
    out = {}
    for label, kwargs in FLOAT32_CASES:
        law = camjax.laws.get(spec["law"])
        options = SolveOptions(**kwargs).checked(float(n.max()))
        start = time.perf_counter()
        jax.block_until_ready(batch_metrics(law, n, 0.0, options))
        first = time.perf_counter() - start
        start = time.perf_counter()
        metrics, result, steps = jax.block_until_ready(batch_metrics(law, n, 0.0, options))
        warm = time.perf_counter() - start
        out[label] = {
            "dtype": str(metrics.ct.dtype), "warm_s": warm, "compile_s": max(first - warm, 0.0),
            "ct": np.asarray(metrics.ct, dtype=float).tolist(),
            "residual": np.asarray(metrics.residual, dtype=float).tolist(),
            "ok": np.asarray(result == diffrax.RESULTS.successful).tolist(),
            "steps_mean": float(np.mean(np.asarray(steps))),
        }
    path.write_text(json.dumps(out))


def float32_rows(law_name: str, n: np.ndarray, reference) -> list[dict]:
    """Rows of the float32 cases, from a child process (float32 needs a fresh JAX)."""
    spec = Path(f"/tmp/camjax_float32_{os.getpid()}_{law_name}.json")
    spec.write_text(json.dumps({"law": law_name, "n": n.tolist()}))
    env = {**os.environ, "JAX_ENABLE_X64": "0"}
    subprocess.run([sys.executable, __file__, "--float32-worker", str(spec)], env=env, check=True)
    out = json.loads(spec.read_text())
    spec.unlink()
    rows = []
    for label, data in out.items():
        ct, residual, ok = (np.asarray(data[k]) for k in ("ct", "residual", "ok"))
        ok = ok & np.isfinite(ct) & np.isfinite(residual)
        rows.append({
            "law": law_name, "method": f"{label} float32", "family": "float32", "solver": label.split()[0],
            "n_count": int(n.size), "warm_s": data["warm_s"], "compile_s": data["compile_s"],
            "steps_mean": data["steps_mean"], "steps_max": -1, "failed": int((~ok).sum()),
            "ct_error": float(np.max(np.abs(ct - reference[0])[ok])) if ok.any() else np.nan,
            "residual_error": float(np.max(np.abs(residual - reference[1])[ok])) if ok.any() else np.nan,
            "dtype": data["dtype"],
        })
    return rows


def scipy_metrics(law, n: float, method: str, rtol: float):
    """Ct, R and function evaluations of scipy's ``solve_ivp`` (undamped SDOF).

    Integrates the deflection ``e'' = a - w^2 e``; the payload acceleration is ``w^2 e``
    in the rise, and the dwell's free vibration has amplitude ``w |e' + i w e|`` at
    ``tau = 1``.  The in-motion peak is the max of the dense output sampled at 64 points
    per vibration period, polished by a bounded scalar search around the largest sample.
    """
    import jax
    from scipy.integrate import solve_ivp
    from scipy.optimize import minimize_scalar

    accel = jax.jit(law.a)
    omega = 2 * np.pi * n
    jumps = [float(t) for t in np.asarray(law.breakpoints())]
    edges = [0.0, *jumps, 1.0]

    def field(t, y):
        return [y[1], float(accel(t)) - omega**2 * y[0]]

    y, nfev, pieces = [0.0, 0.0], 0, []
    for t0, t1 in zip(edges[:-1], edges[1:]):  # restart at jumps, as jump_ts does
        sol = solve_ivp(field, (t0, t1), y, method=method, rtol=rtol, atol=rtol * 1e-2, dense_output=True)
        if sol.status != 0:
            raise RuntimeError(f"scipy {method} failed at n={n}: {sol.message}")
        y, nfev = sol.y[:, -1], nfev + sol.nfev
        pieces.append((t0, t1, sol.sol))
    peak = 0.0
    for t0, t1, dense in pieces:
        t = np.linspace(t0, t1, max(16, int(64 * n * (t1 - t0))))
        values = np.abs(omega**2 * dense(t)[0])
        k = int(np.argmax(values))
        lo, hi = t[max(k - 1, 0)], t[min(k + 1, t.size - 1)]
        polished = minimize_scalar(lambda s, dense=dense: -abs(omega**2 * dense(s)[0]), bounds=(lo, hi), method="bounded",
                                   options={"xatol": 1e-12})
        peak = max(peak, values[k], -polished.fun)
    residual = omega * abs(complex(y[1], omega * y[0]))
    return max(peak, residual) / law.Ca, residual / law.Ca, nfev


def scipy_rows(law, n: np.ndarray, reference, subset: int) -> list[dict]:
    """Rows of the scipy peers, timed on ``subset`` evenly spread period ratios, scaled up."""
    pick = np.unique(np.linspace(0, n.size - 1, subset).round().astype(int))
    rows = []
    for method, rtol in SCIPY_METHODS:
        start = time.perf_counter()
        results = [scipy_metrics(law, float(n[i]), method, rtol) for i in pick]
        elapsed = time.perf_counter() - start
        ct, residual, nfev = (np.asarray(x) for x in zip(*results))
        rows.append({
            "law": law.name, "method": f"scipy {method} rtol={rtol:.0e}", "family": "scipy", "solver": method,
            "n_count": int(pick.size), "warm_s": elapsed * n.size / pick.size, "compile_s": 0.0,
            "steps_mean": float(nfev.mean()), "steps_max": int(nfev.max()), "failed": 0,
            "ct_error": float(np.max(np.abs(ct - reference[0][pick]))),
            "residual_error": float(np.max(np.abs(residual - reference[1][pick]))),
        })
    return rows


FAMILY_MARKERS = {"exact": ("o", "C0"), "fixed-step": ("s", "C1"), "adaptive": ("^", "C2"),
                  "adaptive-no-jumps": ("v", "C3"), "implicit": ("D", "C4"), "scipy": ("P", "C5"),
                  "float32": ("x", "C6")}


def plot(rows: list[dict], path: Path, title: str) -> None:
    """Error (worse of Ct and R) against warm time, one panel per law, Pareto front drawn."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from camjax.cli.bench import ACCURACY_GOAL, pareto_front

    laws = list(dict.fromkeys(r["law"] for r in rows))
    fig, axes = plt.subplots(1, len(laws), figsize=(4.2 * len(laws), 4.4), squeeze=False, sharey=True)
    for ax, law in zip(axes[0], laws):
        group = [r for r in rows if r["law"] == law and r["failed"] == 0]
        times = np.array([r["warm_s"] for r in group])
        errors = np.array([max(r["ct_error"], r["residual_error"], 1e-16) for r in group])
        for family, (marker, color) in FAMILY_MARKERS.items():
            pick = [i for i, r in enumerate(group) if r["family"] == family]
            if pick:
                ax.scatter(times[pick], errors[pick], marker=marker, color=color, label=family, s=28)
        front = pareto_front(times, errors)
        ax.step(times[front], errors[front], where="post", color="k", lw=1, alpha=0.6, label="Pareto front")
        for i in front:
            ax.annotate(group[i]["method"], (times[i], errors[i]), fontsize=6, xytext=(3, 3),
                        textcoords="offset points")
        failed = [r["method"] for r in rows if r["law"] == law and r["failed"]]
        if failed:
            ax.text(0.02, 0.02, "failed: " + ", ".join(failed), transform=ax.transAxes, fontsize=5, wrap=True)
        ax.axhline(ACCURACY_GOAL, color="grey", ls=":", lw=1)
        ax.set(xscale="log", yscale="log", title=law, xlabel="warm time of the batch [s]")
    axes[0][0].set_ylabel("max error of Ct and R [units of Ca]")
    axes[0][-1].legend(fontsize=7, loc="upper right")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--laws", default="poly4567,modified-trapezoid,harmonic,parabolic")
    parser.add_argument("--n-max", type=float, default=30.0)
    parser.add_argument("--n-count", type=int, default=1000)
    parser.add_argument("--level", default="medium", choices=("quick", "medium", "full"))
    parser.add_argument("--scipy-subset", type=int, default=3, help="period ratios scipy runs (0: none)")
    parser.add_argument("--no-float32", action="store_true")
    parser.add_argument("--tag", default="range30")
    parser.add_argument("--out", default="results/work_precision")
    parser.add_argument("--float32-worker", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.float32_worker:
        float32_worker(Path(args.float32_worker))
        return

    import camjax
    from camjax.cli.bench import (
        ACCURACY_GOAL,
        default_method,
        format_table,
        measure,
        reference_metrics,
        reference_resolution,
        study_cases,
    )

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    n = np.linspace(1.0, args.n_max, args.n_count)
    rows, checks = [], {}
    for name in args.laws.split(","):
        law = camjax.laws.get(name)
        reference = reference_metrics(law, n)
        # The reference's own error: the same path on a grid twice as fine.
        finer = camjax.ct_curve(law, n, resolution=2 * reference_resolution(args.n_max))
        checks[name] = max(np.max(np.abs(finer.ct - reference[0])), np.max(np.abs(finer.residual - reference[1])))
        for case in study_cases(args.level):
            rows.append(measure(law, n, case, reference))
            print(format_table(rows[-1:]).splitlines()[-1], flush=True)
        if args.scipy_subset:
            rows += scipy_rows(law, n, reference, args.scipy_subset)
        if not args.no_float32:
            rows += float32_rows(name, n, reference)
        for row in rows[-12:]:
            print(format_table([row]).splitlines()[-1], flush=True)

    columns = list(dict.fromkeys(k for r in rows for k in r))
    with open(out / f"{args.tag}.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    best = default_method([r for r in rows if r["family"] not in ("scipy", "float32")])
    summary = {
        "command": "python " + " ".join(sys.argv), "period_ratios": [1.0, args.n_max, args.n_count],
        "reference_resolution": reference_resolution(args.n_max), "reference_self_error": checks,
        "accuracy_goal": ACCURACY_GOAL, "default_method": best,
        "note": "scipy rows: timed on a subset of period ratios and scaled to the batch; "
                "warm times are of one shared 2-core CPU and provisional",
    }
    (out / f"{args.tag}.json").write_text(json.dumps({"summary": summary, "rows": rows}, indent=1, default=float))
    text = [f"# Work-precision, n in [1, {args.n_max:g}], {args.n_count} period ratios", "",
            f"Command: `{summary['command']}`", "",
            f"Reference: exact path at resolution {summary['reference_resolution']}; its change on a grid "
            f"twice as fine: {max(checks.values()):.2g}.", "",
            f"Fastest method meeting {ACCURACY_GOAL:g} on every law: {best}", "", summary["note"], "",
            format_table(rows, columns=("law", "method", "warm_s", "compile_s", "steps_mean", "failed",
                                        "ct_error", "residual_error"))]
    (out / f"{args.tag}.md").write_text("\n".join(text) + "\n")
    plot(rows, out / f"{args.tag}.png", f"Work-precision, {args.n_count} period ratios in [1, {args.n_max:g}]")
    print(f"default method: {best}")


if __name__ == "__main__":
    main()
