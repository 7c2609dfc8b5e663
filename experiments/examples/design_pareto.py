"""Pareto fronts of residual vibration against peak acceleration: max R over a band
against Ca, for designed splines, their LP lower bound, the standard laws and the
polynomial family s = I_tau(k, k), k = 3..7.

Each Ca cap gets one design (24 knots, Cj <= 100) and one LP bound (the global optimum
of the convex problem, experiments/examples/design_convex.py).  R is in units of the law's own Ca.

Usage: python experiments/examples/design_pareto.py  (writes results/design_pareto/)
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import camjax.law_design as D  # noqa: E402
from camjax.laws import PolynomialLaw, standard_laws  # noqa: E402

BANDS = ((4.0, 8.0), (6.0, 12.0), (8.0, 16.0))
CA_CAPS = (5.5, 6.0, 6.5, 7.0, 7.5, 8.0, 8.5, 9.0)
MAX_JERK = 100.0
KNOTS = 24


def front(n1, n2, caps=CA_CAPS, knots=KNOTS, max_jerk=MAX_JERK):
    """Designed max R and the LP bound at each Ca cap, plus the reference laws."""
    problem = D.ConvexBound(n1, n2, knots)
    rows = []
    for ca in caps:
        bound, _ = problem.lower_bound(ca, max_jerk)
        result = D.design(D.MaxResidual(n1, n2), caps=D.Caps(ca, max_jerk), knots=knots,
                          progress=False)
        r = result.values[f"max R over [{n1:g}, {n2:g}]"]
        rows.append(dict(max_ca=ca, lp_bound=bound, design_max_r=r, ratio=r / bound,
                         design_ca=result.coefficients["Ca"], design_cj=result.coefficients["Cj"],
                         seconds=result.seconds))
        print(n1, n2, rows[-1], flush=True)
    objective = D.MaxResidual(n1, n2)
    references = {law.name: dict(ca=float(law.Ca), max_r=objective.report(law))
                  for law in standard_laws()}
    family = {f"I(k,k), k={k}": dict(ca=float(law.Ca), max_r=objective.report(law))
              for k in range(3, 8) for law in [PolynomialLaw(k)]}
    return dict(band=[n1, n2], knots=knots, max_jerk=max_jerk, designs=rows,
                standard=references, polynomial_family=family)


def plot(fronts, path):
    fig, axes = plt.subplots(1, len(fronts), figsize=(5 * len(fronts), 4.2), sharey=True)
    for ax, f in zip(np.atleast_1d(axes), fronts):
        d = f["designs"]
        ca = [r["design_ca"] for r in d]
        ax.semilogy(ca, [r["design_max_r"] for r in d], "o-", label=f"designed ({f['knots']} knots, Cj<=100)")
        ax.semilogy([r["max_ca"] for r in d], [r["lp_bound"] for r in d], "k--", lw=1,
                    label="global optimum (LP bound)")
        fam = f["polynomial_family"]
        ax.semilogy([v["ca"] for v in fam.values()], [v["max_r"] for v in fam.values()], "s:",
                    color="tab:red", label="I(k,k), k=3..7")
        for name, v in f["standard"].items():
            if 5.0 <= v["ca"] <= 10.0:
                ax.semilogy(v["ca"], v["max_r"], "^", color="tab:green")
                ax.annotate(name, (v["ca"], v["max_r"]), fontsize=7, xytext=(3, 3),
                            textcoords="offset points")
        ax.set_title(f"band [{f['band'][0]:g}, {f['band'][1]:g}]")
        ax.set_xlabel("Ca")
        ax.grid(True, which="both", alpha=0.3)
    np.atleast_1d(axes)[0].set_ylabel("max R over the band (units of Ca)")
    np.atleast_1d(axes)[0].legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(out=Path("results/design_pareto")):
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    fronts = [front(*band) for band in BANDS]
    (out / "pareto.json").write_text(json.dumps(fronts, indent=1))
    lines = []
    for f in fronts:
        lines += [f"Band [{f['band'][0]:g}, {f['band'][1]:g}], {f['knots']} knots, Cj <= {f['max_jerk']:g}", "",
                  "| Ca cap | designed max R | LP bound | design / bound | Ca | Cj | s |",
                  "|---|---|---|---|---|---|---|"]
        lines += [f"| {r['max_ca']:g} | {r['design_max_r']:.3g} | {r['lp_bound']:.3g} | {r['ratio']:.3f} | "
                  f"{r['design_ca']:.3f} | {r['design_cj']:.1f} | {r['seconds']:.1f} |" for r in f["designs"]]
        refs = {**f["polynomial_family"], **f["standard"]}
        lines += ["", "| law | Ca | max R |", "|---|---|---|"]
        lines += [f"| {k} | {v['ca']:.3f} | {v['max_r']:.3g} |" for k, v in refs.items()]
        lines.append("")
    lines.append(f"total {time.perf_counter() - t0:.0f} s")
    (out / "pareto.md").write_text("\n".join(lines) + "\n")
    plot(fronts, out / "pareto.png")
    print("\n".join(lines))


if __name__ == "__main__":
    main(*(Path(a) for a in sys.argv[1:]))
