"""Every named law: Cv, Ca, Cj, and the worst Ct and residual vibration over n in [5, 20].

Writes results/laws/: ``laws_table.md`` (the table of docs/laws.md), ``laws.json`` and
``residual.png`` (the residual vibration of the classic laws and of the named laws over
the period ratio, undamped SDOF, as in the dynamics chapter of Rothbart's Cam Design
Handbook).  One ``ct_curves`` call per grid; the whole run takes seconds.

    python experiments/examples/laws_table.py [--out results/laws]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import camjax  # noqa: E402
from camjax import laws  # noqa: E402

BAND = (5.0, 20.0)
FAMILY_EXAMPLES = [
    "modified-trapezoid-cv:0.2", "modified-sine-cv:0.2", "cycloidal-cv:0.2",
    "modified-trapezoid-asym:0.4", "modified-sine-asym:0.4", "cycloidal-asym:0.4",
    "modified-sine-asym:0.3",
]
IN_MOTION = ["double-harmonic", "constant-velocity"]
CLASSIC = ["cycloidal", "modified-sine", "modified-trapezoid", "harmonic", "poly345", "poly4567"]
NAMED = ["freudenstein-1-3", "freudenstein-1-3-5", "triple-harmonic-modified-sine",
         "triple-harmonic-zero-jerk", "modified-sine-asym:0.4", "modified-sine-cv:0.2"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results/laws")
    parser.add_argument("--quick", action="store_true", help="a tenth of the period ratios (a smoke run)")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    rest = laws.names() + FAMILY_EXAMPLES
    band = np.linspace(*BAND, 151 if args.quick else 1501)
    wide = np.linspace(1.0, 20.0, 381 if args.quick else 3801)
    start = time.perf_counter()
    worst = camjax.ct_curves({name: name for name in rest}, band)  # keyed by the names given
    curves = camjax.ct_curves({name: name for name in sorted(set(CLASSIC + NAMED))}, wide)
    seconds = time.perf_counter() - start

    rows = []
    for name in rest + IN_MOTION:
        law = laws.get(name)
        row = {"law": name, **law.peak_coefficients(), "ct": None, "ca_ct": None, "residual": None}
        if name in worst:
            c = worst[name]
            row.update(ct=float(np.max(c.ct)), ca_ct=float(np.max(c.ca_ct)), residual=float(np.max(c.residual)))
        rows.append(row)

    def cell(x, digits=4):
        return "refused" if x is None else "inf" if not np.isfinite(x) else f"{x:.{digits}f}"

    lines = ["| law | Cv | Ca | Cj | worst Ct | worst Ca*Ct | worst R |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    lines += [f"| {r['law']} | {cell(r['Cv'])} | {cell(r['Ca'])} | {cell(r['Cj'], 2)} | {cell(r['ct'])} | "
              f"{cell(r['ca_ct'], 3)} | {cell(r['residual'])} |" for r in rows]
    note = (f"Worst over {band.size} period ratios n in [{BAND[0]:g}, {BAND[1]:g}], undamped SDOF, exact "
            "path; Ct and R in units of Ca, Ca*Ct in h/T^2; Cj = inf: an acceleration step. "
            "'refused': the law does not rise from rest to rest.")
    (out / "laws_table.md").write_text("\n".join(lines) + "\n\n" + note + "\n")
    (out / "laws.json").write_text(json.dumps(
        {"band": list(BAND), "ratios": band.size, "seconds": seconds,
         "laws": [{k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in r.items()}
                  for r in rows]}, indent=1) + "\n")

    fig, axes = plt.subplots(2, 1, figsize=(9, 8), sharex=True)
    for ax, group, title in ((axes[0], CLASSIC, "classic laws"), (axes[1], NAMED, "named laws of the trade")):
        for name in group:
            ax.plot(wide, curves[name].residual, lw=1.0, label=name)
        ax.set_ylabel("residual vibration R (units of Ca)")
        ax.set_title(f"Residual vibration after the rise, {title} (undamped)")
        ax.set_yscale("log")
        ax.set_ylim(1e-4, 5)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, ncol=2)
    axes[1].set_xlabel("period ratio n = rise time / natural period")
    fig.tight_layout()
    fig.savefig(out / "residual.png", dpi=110)
    print("\n".join(lines))
    print(note)
    print(f"wrote {out}/laws_table.md, laws.json, residual.png ({seconds:.1f} s for the curves)")


if __name__ == "__main__":
    main()
