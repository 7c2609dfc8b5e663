"""SCCA atlas: every SCCA law against 1000 period ratios, and the best one at each ratio.

Two grids (``camjax.distributed.scca_grid``): the face ``a + b + c = 1`` (no constant-
velocity part, where every named law lies) at step 0.01, 5151 laws, and the whole family
``0 < a + b + c <= 1`` at step 0.05, 1770 laws (C(23, 3) = 1771 points less the all-zero
one, which is no law); each undamped and at zeta = 0.05, against 1000 period ratios in
[1, 30].  At every ratio n the script picks the law with the lowest worst case over the
band [0.9 n, 1.1 n] of Ct, of Ca*Ct (the peak load in h/T^2) and of Ca*R (the residual
vibration in h/T^2), and draws maps of the band-worst Ca*Ct and Ca*R over the face at
chosen n with the named laws marked.

The sweeps run through ``camjax.distributed`` (chunks written atomically under --work,
split over the local devices), so an interrupted run resumes where it stopped and a
re-run after a code change only needs --work emptied.  Each sweep records its wall
time and CPU time, throughput in (law, ratio) evaluations per second per core and per CPU
second (the figure that survives a shared machine), peak memory
(``resource.getrusage``) and the machine load (``uptime``).

    python experiments/examples/scca_atlas.py                   # the full atlas (long: see the docs)
    python experiments/examples/scca_atlas.py --quick           # a small grid for development
    python experiments/examples/scca_atlas.py --analyse-only    # redo the figures from --work
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
BAND = 0.10
MAP_RATIOS = (2.0, 5.0, 10.0, 20.0)
METRICS = {  # label -> function of (merged arrays, damping index), (laws, ratios)
    "Ct": lambda m, d: m["ct"][d],
    "Ca*Ct": lambda m, d: m["ca"][:, None] * m["ct"][d],
    "Ca*R": lambda m, d: m["ca"][:, None] * m["residual"][d],
}


def band_worst(values: np.ndarray, n: np.ndarray, band: float = BAND) -> np.ndarray:
    """``max`` of ``values[:, j]`` over ``|n_j - n_i| <= band n_i``, for every i."""
    lo = np.searchsorted(n, (1 - band) * n, side="left")
    hi = np.searchsorted(n, (1 + band) * n, side="right")
    return np.stack([values[:, a:b].max(axis=1) for a, b in zip(lo, hi)], axis=1)


def run_sweeps(args, work: Path, runs_path: Path) -> None:
    """Compute (or resume) the four sweeps, adding each one's timing to ``runs_path``."""
    import jax

    from camjax import distributed

    grids = {"face": {"scca_step": args.face_step, "scca_face": True},
             "family": {"scca_step": args.family_step, "scca_face": False}}
    records = json.loads(runs_path.read_text()) if runs_path.exists() else {}
    for damping in args.damping:
        for grid in args.grids:
            laws = grids[grid]
            key = f"{grid}-z{damping:g}"
            spec = distributed.spec_from_dict({
                "output": str(work / key), "damping": [damping],
                "laws_per_chunk": args.laws_per_chunk, "laws": laws,
                **({} if args.phase_step is None else {"phase_step": args.phase_step}),
                "period_ratio": {"start": 1.0, "stop": 30.0, "count": args.count},
            })
            load_before = os.getloadavg()
            start, cpu = time.perf_counter(), time.process_time()
            done = distributed.run_sweep(spec, progress=True)
            wall, cpu = time.perf_counter() - start, time.process_time() - cpu
            distributed.merge(spec)
            evaluations = sum(min(spec.laws_per_chunk, len(spec.laws) - c[1]) for c in done)
            evaluations *= spec.period_ratio.size
            cores = os.cpu_count()
            record = {
                "laws": len(spec.laws), "period_ratios": int(spec.period_ratio.size),
                "damping": damping, "devices": jax.local_device_count(), "cores": cores,
                "phase_step": spec.phase_step,
                "compilation_cache": bool(jax.config.jax_compilation_cache_dir),
                "load_before": [round(x, 2) for x in load_before],
                "chunks_computed": len(done), "evaluations": evaluations,
                "wall_s": round(wall, 2), "cpu_s": round(cpu, 2),
                "peak_memory_gib": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
                                         / 2**20, 3),
                "uptime_after": subprocess.run(["uptime"], capture_output=True,
                                               text=True).stdout.strip(),
            }
            if evaluations:
                record["evaluations_per_s_per_core"] = round(evaluations / wall / cores, 1)
                # per CPU second: what a core gives when the machine is shared (load > cores)
                record["evaluations_per_cpu_s"] = round(evaluations / cpu, 1)
            print(key, json.dumps(record), file=sys.stderr, flush=True)
            if done:  # a run that found everything written keeps the earlier record
                records[key] = record
                runs_path.write_text(json.dumps(records, indent=1) + "\n")


def _fractions(names) -> np.ndarray:
    """``(laws, 3)`` fractions from names ``scca:a,b,c`` or a named member's (``cycloidal``)."""
    from camjax import laws as lawlib

    def fractions(name):
        if ":" in name:
            return [float(x) for x in name.split(":")[1].split(",")]
        return [float(x) for x in lawlib.get(name).fractions]

    return np.asarray([fractions(name) for name in names])


def analyse(work: Path, out: Path) -> dict:
    """Best laws per ratio and the named laws' standing, per sweep; figures."""
    from camjax import laws as lawlib

    named = {law.name: tuple(float(x) for x in law.fractions)
             for law in lawlib.standard_laws() if isinstance(law, lawlib.AbstractSCCA)}
    summary = {}
    maps = {}
    for key in sorted(p.name for p in work.iterdir() if (p / "sweep.npz").exists()):
        with np.load(work / key / "sweep.npz") as z:
            merged = {k: z[k] for k in z.files}
        n = merged["period_ratio"]
        frac = _fractions(merged["law"])
        rows, best_curves = [], {}
        for label, metric in METRICS.items():
            worst = band_worst(metric(merged, 0), n)
            best = worst.argmin(axis=0)
            best_curves[label] = (worst[best, np.arange(n.size)], frac[best])
            named_worst = {}
            for name, f in named.items():
                hit = np.flatnonzero(np.all(np.abs(frac - f) < 1e-9, axis=1))
                if hit.size:
                    named_worst[name] = worst[hit[0]]
            rows.append((label, worst, best, named_worst))
            if key.startswith("face"):
                maps[(key, label)] = (frac, worst, n, named)
        summary[key] = _summarise(n, frac, rows)
        _write_best_csv(out / f"best_{key}.csv", n, merged["law"], rows)
        _plot_best(out / f"best_{key}.png", key, n, rows, best_curves)
    for (key, label), (frac, worst, n, named_fracs) in maps.items():
        if label != "Ct":
            _plot_maps(out / f"map_{key}_{label.replace('*', '')}.png", key, label, frac,
                       worst, n, named_fracs)
    return summary


def _summarise(n, frac, rows) -> dict:
    out = {}
    for label, worst, best, named_worst in rows:
        picks = {}
        for target in MAP_RATIOS + (1.5, 3.0, 15.0, 30.0):
            i = int(np.argmin(np.abs(n - target)))
            picks[f"{n[i]:.3g}"] = {
                "best": [round(float(x), 4) for x in frac[best[i]]],
                "value": round(float(worst[best[i], i]), 5),
                **{name: round(float(v[i]), 5) for name, v in named_worst.items()},
            }
        # how much better the best law is than the best named law, over the whole range
        named_min = np.min(np.stack(list(named_worst.values())), axis=0) if named_worst else None
        entry = {"at": picks, "distinct_best_laws": int(np.unique(best).size)}
        if named_min is not None:
            gain = 1 - worst[best, np.arange(n.size)] / named_min
            entry["gain_over_best_named_median"] = round(float(np.median(gain)), 4)
            entry["gain_over_best_named_max"] = round(float(gain.max()), 4)
        out[label] = entry
    return out


def _write_best_csv(path, n, names, rows) -> None:
    header = ["period_ratio"]
    for label, *_ in rows:
        header += [f"best_{label}", f"band_worst_{label}"]
    lines = [",".join(header)]
    for i, ni in enumerate(n):
        cells = [f"{ni:.6g}"]
        for _, worst, best, _ in rows:
            cells += [names[best[i]], f"{worst[best[i], i]:.8g}"]
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n")


def _plot_best(path, key, n, rows, best_curves) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(15, 7.5), sharex=True)
    for col, (label, _, _, named_worst) in enumerate(rows):
        value, frac = best_curves[label]
        ax = axes[0, col]
        ax.plot(n, value, "k", lw=2, label="best SCCA")
        for name, v in named_worst.items():
            ax.plot(n, v, lw=0.9, label=name)
        ax.set_yscale("log")
        ax.set_title(f"{key}: worst {label} over n +-{BAND:.0%}")
        ax.legend(fontsize=7)
        ax = axes[1, col]
        for j, part in enumerate(("a (sine)", "b (constant)", "c (cosine)")):
            ax.plot(n, frac[:, j], ".", ms=2, label=part)
        ax.plot(n, 1 - frac.sum(axis=1), ".", ms=2, label="d (constant velocity)")
        ax.set_xlabel("period ratio n")
        ax.set_ylabel("fractions of the best law")
        ax.legend(fontsize=7, markerscale=4)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _plot_maps(path, key, label, frac, worst, n, named) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def xy(f):
        f = np.atleast_2d(f)
        return f[:, 1] + 0.5 * f[:, 2], np.sqrt(3) / 2 * f[:, 2]

    x, y = xy(frac)
    fig, axes = plt.subplots(1, len(MAP_RATIOS), figsize=(4.6 * len(MAP_RATIOS), 4.4))
    for ax, target in zip(axes, MAP_RATIOS):
        i = int(np.argmin(np.abs(n - target)))
        values = np.log10(worst[:, i])
        art = ax.tricontourf(x, y, values, levels=30, cmap="viridis")
        fig.colorbar(art, ax=ax, shrink=0.8, label=f"log10 worst {label}")
        b = int(np.argmin(worst[:, i]))
        ax.plot(*xy(frac[b]), "r*", ms=14, label="best")
        for name, f in named.items():
            px, py = xy(np.asarray(f))
            ax.plot(px, py, "wo", mec="k", ms=6)
            ax.annotate(name, (px[0], py[0]), fontsize=7, xytext=(4, 4),
                        textcoords="offset points", color="w")
        ax.set_title(f"n = {n[i]:.2f} (+-{BAND:.0%})", pad=22)
        ax.set_aspect("equal")
        ax.axis("off")
        ax.text(0, -0.08, "a = 1 (sine)", ha="center", fontsize=8)
        ax.text(1, -0.08, "b = 1 (constant)", ha="center", fontsize=8)
        ax.text(0.5, np.sqrt(3) / 2 + 0.05, "c = 1 (cosine)", ha="center", fontsize=8)
    axes[0].legend(loc="upper left", fontsize=7)
    fig.suptitle(f"SCCA face a + b + c = 1, {key}: worst {label} over the band")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def markdown(summary: dict, runs: dict) -> str:
    """The results as markdown tables (copied into docs/scca-atlas.md)."""
    lines = ["## Runs", "",
             "| sweep | laws | ratios | devices | wall (s) | CPU (s) | evaluations/s/core "
             "| evaluations/CPU-s | peak GiB | load |", "|---" * 10 + "|"]
    for key, r in runs.items():
        load = r["uptime_after"].split("load average:")[-1].strip()
        lines.append(f"| {key} | {r['laws']} | {r['period_ratios']} | {r['devices']} | "
                     f"{r['wall_s']} | {r.get('cpu_s', '-')} | "
                     f"{r.get('evaluations_per_s_per_core', '-')} | "
                     f"{r.get('evaluations_per_cpu_s', '-')} | "
                     f"{r['peak_memory_gib']} | {load} |")
    for key, metrics in summary.items():
        for label, entry in metrics.items():
            named = [k for k in next(iter(entry["at"].values())) if k not in ("best", "value")]
            lines += ["", f"## {key}: worst {label} over n +-{BAND:.0%}", "",
                      f"{entry['distinct_best_laws']} distinct best laws over the range; the "
                      "best law's band-worst value is below the best named law's by "
                      f"{entry.get('gain_over_best_named_median', float('nan')):.1%} (median "
                      f"over n), up to {entry.get('gain_over_best_named_max', float('nan')):.1%}.",
                      "", "| n | best (a, b, c) | best | " + " | ".join(named) + " |",
                      "|---" * (3 + len(named)) + "|"]
            for n, row in sorted(entry["at"].items(), key=lambda kv: float(kv[0])):
                cells = [f"{row[k]:.4g}" for k in named]
                best = ", ".join(f"{x:g}" for x in row["best"])
                lines.append(f"| {n} | ({best}) | {row['value']:.4g} | "
                             + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small grids for development")
    parser.add_argument("--face-step", type=float, default=0.01)
    parser.add_argument("--family-step", type=float, default=0.05)
    parser.add_argument("--count", type=int, default=1000, help="period ratios in [1, 30]")
    parser.add_argument("--damping", type=float, nargs="+", default=[0.0, 0.05])
    parser.add_argument("--grids", nargs="+", choices=("face", "family"),
                        default=["face", "family"], help="which grids to sweep, in order")
    parser.add_argument("--laws-per-chunk", type=int, default=64)
    parser.add_argument("--phase-step", type=float, default=None,
                        help="largest w h of the exact path's grid (default: ct_curve's, "
                        "camjax.sdof.MAX_PHASE_STEP; smaller is finer)")
    parser.add_argument("--no-cache", action="store_true",
                        help="do not use camjax's persistent compilation cache (a cold run)")
    parser.add_argument("--work", type=Path, help="chunk directory (default: under --out)")
    parser.add_argument("--out", type=Path, default=HERE.parents[1] / "results" / "scca_atlas")
    parser.add_argument("--analyse-only", action="store_true",
                        help="skip the sweeps; analyse what --work holds")
    parser.add_argument("--devices", type=int, default=os.cpu_count(),
                        help="host devices to force (one per core; default: every core)")
    args = parser.parse_args()
    flag = f"--xla_force_host_platform_device_count={args.devices}"
    os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {flag}".strip()
    if not args.no_cache:
        from camjax.cli import enable_compilation_cache

        enable_compilation_cache()
    if args.quick:
        args.face_step, args.family_step, args.count = 0.1, 0.25, 100
        args.out = args.out.with_name("scca_atlas_quick")
    work = args.work or args.out / "sweeps"  # large: kept out of git (see .gitignore)
    args.out.mkdir(parents=True, exist_ok=True)
    if not args.analyse_only:
        run_sweeps(args, work, args.out / "runs.json")
    summary = analyse(work, args.out)
    (args.out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    runs_path = args.out / "runs.json"
    runs = json.loads(runs_path.read_text()) if runs_path.exists() else {}
    text = markdown(summary, runs)
    (args.out / "summary.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
