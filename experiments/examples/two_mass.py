"""Elastic input drive (two-mass model): Ct and the Ca*Ct ranking against stiffness ratio.

ModSine, ModTrap and Cycloidal on the two-mass model (camshaft on an elastic input
shaft, driven at constant speed; payload on the output transmission), inertia ratio
``m`` (default 1):

1. Ct and Ca*Ct against the input-to-output stiffness ratio ``k`` at a few output
   period ratios, with the rigid-input SDOF (``camjax.ct_curve``) as the ``k -> inf`` limit;
2. Ca*Ct curves over the output period ratio for several ``k``, and where the fitted
   envelopes of ModSine and Cycloidal cross (``camjax.ca_ct_crossings``), against the
   note's 6.4 (a rigid-input claim).

    python experiments/examples/two_mass.py [--inertia-ratio 1.0] [--quick] [--out DIR]

writes results/two_mass/ (ct_vs_stiffness.csv, ca_ct_curves.csv, summary.json, *.png).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import matplotlib

import camjax

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from camjax.models import TwoMass  # noqa: E402

OUT = Path(__file__).resolve().parents[2] / "results" / "two_mass"
LAWS = ("modified-sine", "modified-trapezoid", "cycloidal")
OPTIONS = dict(samples=1024, rtol=1e-8, atol=1e-10)  # chart accuracy, ~1e-6 in Ct


def curve(law, n, k, m):
    """A ``CtCurve`` of the two-mass model (``k = inf``: the rigid-input SDOF)."""
    if np.isinf(k):
        return camjax.ct_curve(law, n)
    curve = camjax.ct_curve(law, n, model=TwoMass(1.0, k, m), **OPTIONS)
    ct, residual = curve.ct, curve.residual
    return camjax.CtCurve(
        period_ratio=np.asarray(n), ct=ct, residual=residual, peak_in_motion=ct,
        ca=float(law.Ca), name=law.name,
    )


def envelope_crossings(a, b):
    """Crossings of the fitted Ca*Ct envelopes, or ``None`` when a curve has too few crests."""
    try:
        return camjax.ca_ct_crossings(a, b)
    except ValueError:
        return None


def main():
    global OUT
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--inertia-ratio", type=float, default=1.0)
    parser.add_argument("--quick", action="store_true", help="coarse grids")
    parser.add_argument("--out", type=Path, default=OUT, help="output folder (default: results/two_mass)")
    args = parser.parse_args()
    OUT = args.out
    m = args.inertia_ratio
    OUT.mkdir(parents=True, exist_ok=True)
    laws = {name: camjax.laws.get(name) for name in LAWS}
    spot_n = np.array([4.0, 6.4, 10.0])
    stiffness = np.logspace(-0.5, 3, 8 if args.quick else 15)
    summary = {"inertia_ratio": m, "spot_period_ratios": spot_n.tolist(), "stiffness_ratio": stiffness.tolist(),
               "laws": {}}

    # 1. Ct against k at fixed output period ratios.
    start = time.perf_counter()
    rows = []
    for name, law in laws.items():
        ct = np.array([curve(law, spot_n, k, m).ct for k in stiffness])  # (k, n)
        rigid = camjax.ct_curve(law, spot_n).ct
        summary["laws"][name] = {"ca": float(law.Ca), "ct_vs_k": ct.tolist(), "ct_rigid": rigid.tolist()}
        for i, k in enumerate(stiffness):
            for j, n in enumerate(spot_n):
                rows.append(f"{name},{m},{n},{k},{ct[i, j]},{law.Ca * ct[i, j]}")
    print(f"Ct vs k: {time.perf_counter() - start:.1f} s")
    (OUT / "ct_vs_stiffness.csv").write_text(
        "law,inertia_ratio,period_ratio,stiffness_ratio,ct,ca_ct\n" + "\n".join(rows) + "\n"
    )

    fig, axes = plt.subplots(2, len(spot_n), figsize=(5 * len(spot_n), 8), sharex=True)
    for j, n in enumerate(spot_n):
        for name in LAWS:
            d = summary["laws"][name]
            ct = np.asarray(d["ct_vs_k"])[:, j]
            line, = axes[0, j].semilogx(stiffness, ct, label=name)
            axes[0, j].axhline(d["ct_rigid"][j], color=line.get_color(), ls=":", lw=0.8)
            axes[1, j].semilogx(stiffness, d["ca"] * ct, label=name, color=line.get_color())
            axes[1, j].axhline(d["ca"] * d["ct_rigid"][j], color=line.get_color(), ls=":", lw=0.8)
        axes[0, j].set(title=f"output period ratio n = {n:g}, m = {m:g}", ylabel="Ct")
        axes[1, j].set(xlabel="input/output stiffness ratio k", ylabel="Ca*Ct (h/T^2)")
        for ax in axes[:, j]:
            ax.grid(alpha=0.3, which="both")
    axes[0, 0].legend(fontsize=8, title="dotted: rigid input (SDOF)")
    fig.tight_layout()
    fig.savefig(OUT / "ct_vs_stiffness.png", dpi=120)

    # 2. Ca*Ct over n for several k, and the ModSine/Cycloidal envelope crossing.
    n_grid = np.arange(2.0, 16.0001, 0.5 if args.quick else 0.25)
    ks = [1.0, 3.0, 10.0, 30.0, 100.0, np.inf] if not args.quick else [1.0, 10.0, np.inf]
    start = time.perf_counter()
    curves = {k: {name: curve(law, n_grid, k, m) for name, law in laws.items()} for k in ks}
    print(f"Ca*Ct curves: {time.perf_counter() - start:.1f} s")
    crossings, lines = {}, ["k,law,period_ratio,ct,ca_ct"]
    for k in ks:
        c = curves[k]
        key = "rigid" if np.isinf(k) else f"{k:g}"
        crossings[key] = {
            "modsine_cycloidal_envelope": envelope_crossings(c["modified-sine"], c["cycloidal"]),
            "modsine_modtrap_envelope": envelope_crossings(c["modified-sine"], c["modified-trapezoid"]),
            "modsine_cycloidal_raw": camjax.ca_ct_crossings(c["modified-sine"], c["cycloidal"], envelope=False),
            "max_ca_ct": {name: float(np.max(c[name].ca_ct)) for name in LAWS},
        }
        for name in LAWS:
            for n, ct in zip(n_grid, c[name].ct):
                lines.append(f"{key},{name},{n},{ct},{c[name].ca * ct}")
    summary["crossings"] = crossings
    (OUT / "ca_ct_curves.csv").write_text("\n".join(lines) + "\n")
    (OUT / "summary.json").write_text(json.dumps(summary, indent=1))
    print(json.dumps(crossings, indent=1))

    fig, axes = plt.subplots(2, 3, figsize=(16, 8.5), sharex=True, sharey=True, squeeze=False)
    for ax, k in zip(axes.flat, ks):
        for name in LAWS:
            cv = curves[k][name]
            line, = ax.plot(n_grid, cv.ca_ct, lw=0.8, alpha=0.6)
            try:
                fit = camjax.fit_torsion_factor(cv)
                ax.plot(n_grid, cv.ca * fit(n_grid), color=line.get_color(), lw=2, label=name)
            except ValueError:
                line.set_label(name)
        key = "rigid" if np.isinf(k) else f"{k:g}"
        for x in crossings[key]["modsine_cycloidal_envelope"] or []:
            ax.axvline(x, color="k", ls="--", lw=0.8)
        ax.axvline(6.4, color="r", ls=":", lw=1)
        ax.set(title=f"k = {key} (dashed: ModSine = Cycloidal; red: note's 6.4)", ylim=(0, 25))
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("output period ratio n")
    for ax in axes[:, 0]:
        ax.set_ylabel("Ca*Ct (h/T^2): thin raw, thick envelope fit")
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "ca_ct_vs_period_ratio.png", dpi=120)


if __name__ == "__main__":
    main()
