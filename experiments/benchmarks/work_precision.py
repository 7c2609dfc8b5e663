"""Work-precision study: time against the error of Ct and R for every solution method.

For each law and method: warm wall time of the whole batch of period ratios, compile
time, steps, and the max error of Ct and R (units of Ca) against the exact path at a
high resolution.  Peers: scipy ``solve_ivp`` (timed on a subset of the period ratios and
scaled to the whole batch) and float32 (a subprocess with ``JAX_ENABLE_X64=0``).

    python experiments/benchmarks/work_precision.py                       # n in [1, 30], 1000 ratios
    python experiments/benchmarks/work_precision.py --n-max 100 --resolutions 2560 --tag range100
    python experiments/benchmarks/work_precision.py --level full --n-count 200 --laws parabolic --tag full200-parabolic
    python experiments/benchmarks/work_precision.py --level none --laws harmonic --tag peers   # scipy, float32 only
    python experiments/benchmarks/work_precision.py --level quick --n-count 50   # a smoke run
    python experiments/benchmarks/work_precision.py --combine full200-poly4567,full200-parabolic --tag full200

Writes results/work_precision/<tag>.csv, .md, .json and .png; ``--combine`` merges the
``.json`` of runs over the same period ratios (one law per process, say) into one table,
chart and default method.  docs/work-precision.md lists the commands behind each figure.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np

FLOAT32_CASES = (("exact default", {}), ("tsit5 rtol=1e-06", {"method": "tsit5", "rtol": 1e-6, "atol": 1e-8}),
                 ("tsit5 rtol=1e-08", {"method": "tsit5", "rtol": 1e-8, "atol": 1e-10}))
SCIPY_METHODS = (("RK45", 1e-6), ("RK45", 1e-9), ("DOP853", 1e-6), ("DOP853", 1e-10),
                 ("Radau", 1e-6), ("Radau", 1e-9), ("LSODA", 1e-6), ("LSODA", 1e-9))


def float32_worker(path: Path) -> None:
    """Run in a child with JAX_ENABLE_X64=0: Ct and R of each float32 case, to ``path``."""
    import jax
    import jax.numpy as jnp

    import camjax
    from camjax.models import SpringMassOptions, batch_metrics

    spec = json.loads(path.read_text())
    n = jnp.asarray(spec["n"], dtype=jnp.float32)
    out = {}
    for label, kwargs in FLOAT32_CASES:
        law = camjax.laws.get(spec["law"])
        options = SpringMassOptions(**kwargs).checked(float(n.max()))
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
            "ok": np.asarray(result == camjax.RESULTS.successful).tolist(),
            "steps_mean": float(np.mean(np.asarray(steps))),
        }
    path.write_text(json.dumps(out))


def float32_rows(law_name: str, n: np.ndarray, reference) -> list[dict]:
    """Rows of the float32 cases, from a child process (float32 needs a fresh JAX)."""
    from camjax.studies import locate_errors

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
            **locate_errors(n, ok, ct - reference[0], residual - reference[1]),
            "dtype": data["dtype"],
        })
    return rows


def scipy_rows(law, n: np.ndarray, reference, subset: int) -> list[dict]:
    """Rows of the scipy peers, timed on ``subset`` evenly spread period ratios, scaled up."""
    from camjax.studies import locate_errors, scipy_reference

    pick = np.unique(np.linspace(0, n.size - 1, subset).round().astype(int))
    rows = []
    for method, rtol in SCIPY_METHODS:
        start = time.perf_counter()
        results = [scipy_reference(law, float(n[i]), method, rtol) for i in pick]
        elapsed = time.perf_counter() - start
        ct, residual, nfev = (np.asarray(x) for x in zip(*results))
        rows.append({
            "law": law.name, "method": f"scipy {method} rtol={rtol:.0e}", "family": "scipy", "solver": method,
            "n_count": int(pick.size), "warm_s": elapsed * n.size / pick.size, "compile_s": 0.0,
            "steps_mean": float(nfev.mean()), "steps_max": int(nfev.max()), "failed": 0,
            "ct_error": float(np.max(np.abs(ct - reference[0][pick]))),
            "residual_error": float(np.max(np.abs(residual - reference[1][pick]))),
            **locate_errors(n[pick], np.ones(pick.size, bool), ct - reference[0][pick],
                            residual - reference[1][pick]),
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

    from camjax.studies import ACCURACY_GOAL, pareto_front

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
        failed = [f"{r['method']} ({r['failed']})" for r in rows if r["law"] == law and r["failed"]]
        if failed:  # not drawn as points: their errors are over the ratios that succeeded only
            note = textwrap.fill("not shown, some ratios failed (count): " + ", ".join(failed), width=70)
            ax.text(0.02, 0.02, note, transform=ax.transAxes, fontsize=4.5, va="bottom").set_in_layout(False)
        ax.axhline(ACCURACY_GOAL, color="grey", ls=":", lw=1)
        ax.set(xscale="log", yscale="log", title=law, xlabel="warm time of the batch [s]")
        ax.set_ylim(1e-15, 3.0)  # errors reach 1 (units of Ca); room for the note on failed cases below
    axes[0][0].set_ylabel("max error of Ct and R [units of Ca]")
    legend = {}  # one legend for the figure: every family any panel shows
    for ax in axes[0]:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            legend.setdefault(label, handle)
    fig.legend(legend.values(), legend.keys(), loc="lower center", ncol=len(legend), fontsize=8, frameon=False)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    fig.savefig(path, dpi=130)
    plt.close(fig)


def write_outputs(rows: list[dict], summary: dict, out: Path, tag: str, title: str) -> None:
    """``<tag>.csv``, ``.json``, ``.md`` and ``.png`` of the rows under ``out``."""
    from camjax.studies import format_table

    columns = list(dict.fromkeys(k for r in rows for k in r))
    with open(out / f"{tag}.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    (out / f"{tag}.json").write_text(json.dumps({"summary": summary, "rows": rows}, indent=1, default=float))
    commands = summary["command"] if isinstance(summary["command"], list) else [summary["command"]]
    checks = summary["reference_self_error"]
    text = [f"# {title}", "", "Command: " + "; ".join(f"`{c}`" for c in commands), "",
            f"Reference: exact path at resolution {summary['reference_resolution']}; its change on a grid "
            f"twice as fine: {max(checks.values()):.2g}.", "",
            f"Fastest method meeting {summary['accuracy_goal']:g} on every law: {summary['default_method']}", "",
            summary["note"], "",
            "worst_n: the period ratio of the largest error; failed_n_min: the smallest that failed.", "",
            format_table(rows, columns=("law", "method", "warm_s", "compile_s", "steps_mean", "failed",
                                        "ct_error", "residual_error", "worst_n", "failed_n_min"))]
    (out / f"{tag}.md").write_text("\n".join(text) + "\n")
    plot(rows, out / f"{tag}.png", title)


NOTE = ("scipy rows: timed on a subset of period ratios and scaled to the batch; "
        "warm times: best of two runs on a shared 2-core CPU (docs/work-precision.md gives each run's load)")


def combine(tags: list[str], out: Path, tag: str) -> None:
    """Merge the rows of earlier runs (``<tag>.json``) into one table, chart and default method."""
    from camjax.studies import ACCURACY_GOAL, default_method

    runs = [json.loads((out / f"{t}.json").read_text()) for t in tags]
    rows = [r for run in runs for r in run["rows"]]
    ranges = {tuple(run["summary"]["period_ratios"]) for run in runs}
    if len(ranges) != 1:
        raise SystemExit(f"--combine: the runs cover different period ratios: {sorted(ranges)}")
    (lo, hi, count), = ranges
    summary = {
        "command": [c for run in runs for c in ([run["summary"]["command"]] if isinstance(run["summary"]["command"], str)
                                                else run["summary"]["command"])]
                   + ["python " + " ".join(sys.argv)],
        "period_ratios": [lo, hi, count],
        "reference_resolution": max(run["summary"]["reference_resolution"] for run in runs),
        "reference_self_error": {k: v for run in runs for k, v in run["summary"]["reference_self_error"].items()},
        "accuracy_goal": ACCURACY_GOAL,
        "default_method": default_method([r for r in rows if r["family"] not in ("scipy", "float32")],
                                         laws={r["law"] for r in rows}),
        "note": NOTE, "combined_from": tags,
    }
    write_outputs(rows, summary, out, tag, f"Work-precision, {int(count)} period ratios in [{lo:g}, {hi:g}]")
    print(f"default method: {summary['default_method']}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--laws", default="poly4567,modified-trapezoid,harmonic,parabolic")
    parser.add_argument("--n-max", type=float, default=30.0)
    parser.add_argument("--n-count", type=int, default=1000)
    parser.add_argument("--level", default="medium", choices=("none", "quick", "medium", "full"),
                        help="the camjax methods run (none: only the scipy and float32 peers)")
    parser.add_argument("--resolutions", default="",
                        help="extra exact-path grids, comma-separated intervals per unit tau (e.g. 2560,4096)")
    parser.add_argument("--scipy-subset", type=int, default=3, help="period ratios scipy runs (0: none)")
    parser.add_argument("--no-float32", action="store_true")
    parser.add_argument("--tag", default="range30")
    parser.add_argument("--out", default="results/work_precision")
    parser.add_argument("--combine", help="comma-separated tags of earlier runs to merge into --tag (runs nothing)")
    parser.add_argument("--float32-worker", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.float32_worker:
        float32_worker(Path(args.float32_worker))
        return
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.combine:
        combine([t.strip() for t in args.combine.split(",") if t.strip()], out, args.tag)
        return

    import camjax
    from camjax.models import SpringMassOptions
    from camjax.studies import (
        ACCURACY_GOAL,
        Case,
        default_method,
        format_table,
        measure,
        reference_metrics,
        reference_resolution,
        study_cases,
    )

    n = np.linspace(1.0, args.n_max, args.n_count)
    cases = [] if args.level == "none" else study_cases(args.level, args.n_max)
    cases += [Case(f"exact res={int(r)}", "exact", SpringMassOptions(resolution=int(r)))
              for r in args.resolutions.split(",") if r.strip()]
    rows, checks = [], {}
    for name in args.laws.split(","):
        law = camjax.laws.get(name)
        reference = reference_metrics(law, n)
        # The reference's own error: the same path on a grid twice as fine.
        finer = camjax.ct_curve(law, n, resolution=2 * reference_resolution(args.n_max))
        checks[name] = max(np.max(np.abs(finer.ct - reference[0])), np.max(np.abs(finer.residual - reference[1])))
        first = len(rows)
        for case in cases:
            rows.append(measure(law, n, case, reference))
            print(format_table(rows[-1:]).splitlines()[-1], flush=True)
        if args.scipy_subset:
            rows += scipy_rows(law, n, reference, args.scipy_subset)
        if not args.no_float32:
            rows += float32_rows(law.name, n, reference)
        for row in rows[first + len(cases):]:
            print(format_table([row]).splitlines()[-1], flush=True)

    best = default_method([r for r in rows if r["family"] not in ("scipy", "float32")], laws={camjax.laws.get(x).name for x in args.laws.split(",")})
    summary = {
        "command": "python " + " ".join(sys.argv), "period_ratios": [1.0, args.n_max, args.n_count],
        "reference_resolution": reference_resolution(args.n_max), "reference_self_error": checks,
        "accuracy_goal": ACCURACY_GOAL, "default_method": best, "note": NOTE,
    }
    write_outputs(rows, summary, out, args.tag, f"Work-precision, {args.n_count} period ratios in [1, {args.n_max:g}]")
    print(f"default method: {best}")


if __name__ == "__main__":
    main()
