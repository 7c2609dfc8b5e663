"""Laws for servo cams: the least RMS acceleration under a jerk cap, and laws robust to the
frequency (input shapers as laws, and a law designed over a frequency band).

Writes results/robust_laws/:

- ``bands.md``, ``bands.csv``: the table drive vendors publish, for each shaper (ZV, ZVD, EI;
  undamped and at zeta = 0.1) and each law: the band of frequency error (actual / design
  natural frequency - 1) over which the percentage vibration V (the residual relative to an
  unshaped step's, ``camjax.law_design.percentage_vibration``) stays at most 5%, and the
  duration the shaping adds;
- ``vibration.png``: V against the frequency error for all of them;
- ``rms.md``, ``rms.csv``, ``rms.png``: the least-RMS-acceleration designs at several jerk
  caps against the floor 2 sqrt(3), and the acceleration of the one at ``JERK_CAP``;
- ``summary.json``: every number above.

    python experiments/examples/robust_laws.py [--out results/robust_laws] [--quick]
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

from camjax import law_design as D  # noqa: E402
from camjax import laws  # noqa: E402

DESIGN_RATIO = (
    1.75  # the unshaped move's period ratio at the design frequency (the cycloidal's V is 6% there)
)
DAMPING = 0.1
BAND = 0.2  # the designed law holds V <= LIMIT over +/- BAND of frequency error
LIMIT = 0.05
DESIGN_CAPS = (8.0, 150.0)  # Ca, Cj of the band design
JERK_CAP = 200.0  # the least-RMS design's jerk cap stated on the laws page
JERK_CAPS = (60.0, 100.0, 200.0, 400.0)
PUBLISHED = {"zv": 3.2, "zvd": 14.4, "ei": 20.0}  # undamped, +/- percent (Singhose)


SEARCH = (0.25, 1.75)  # frequency ratios searched for a band's edges


def _band_row(label, vibration, added):
    try:
        lo, hi = D.vibration_band(vibration, LIMIT, SEARCH)
    except ValueError:  # V above the limit at the design frequency: no band
        return {
            "what": label,
            "band_low_percent": None,
            "band_high_percent": None,
            "added_duration": added,
        }
    return {
        "what": label,
        "band_low_percent": 100 * (lo - 1),
        "band_high_percent": 100 * (hi - 1),
        "added_duration": added,
    }


def robust(out: Path, quick: bool) -> dict:
    base = laws.Cycloidal()
    steps = 1200 if quick else D.DEFAULT_STEPS
    started = time.perf_counter()
    result = D.design(
        D.MaxResidual((1 - BAND) * DESIGN_RATIO, (1 + BAND) * DESIGN_RATIO, damping=DAMPING),
        caps=D.Caps(*DESIGN_CAPS),
        steps=steps,
        progress=False,
    )
    design_seconds = time.perf_counter() - started
    designed = result.law
    laws.save(designed, out / "designed_law.json")

    def law_vibration(
        law, ratio
    ):  # V of a law whose period ratio is `ratio` at the design frequency
        return lambda r: np.asarray(D.percentage_vibration(law, ratio * np.asarray(r), DAMPING))

    rows = []
    for kind in laws.SHAPERS:  # the impulse trains, undamped: the published bands
        row = _band_row(
            f"{kind} shaper, zeta = 0",
            laws.Shaper(kind).vibration,
            "0.5 T_d" if kind == "zv" else "T_d",
        )
        row["published_percent"] = PUBLISHED[kind]
        rows.append(row)
    for kind in ("zv", "zvd"):
        rows.append(
            _band_row(
                f"{kind} shaper, zeta = {DAMPING:g}",
                laws.Shaper(kind, DAMPING).vibration,
                "0.5 T_d" if kind == "zv" else "T_d",
            )
        )
    shaped = {
        kind: laws.ShapedLaw(
            base, laws.Shaper(kind, DAMPING if kind != "ei" else 0.0), DESIGN_RATIO
        )
        for kind in laws.SHAPERS
    }
    for kind, law in shaped.items():
        if kind == "ei":
            continue  # undamped only
        rows.append(
            _band_row(
                f"{law.name} (the whole move), zeta = {DAMPING:g}",
                law_vibration(law, law.stretch * DESIGN_RATIO),
                f"{law.stretch - 1:.3f} of the move",
            )
        )
    rows.append(
        _band_row(
            f"designed over +/-{100 * BAND:g}%, zeta = {DAMPING:g} (Ca <= {DESIGN_CAPS[0]:g}, "
            f"Cj <= {DESIGN_CAPS[1]:g})",
            law_vibration(designed, DESIGN_RATIO),
            "0",
        )
    )
    rows.append(
        _band_row(f"cycloidal unshaped, zeta = {DAMPING:g}", law_vibration(base, DESIGN_RATIO), "0")
    )

    r = np.linspace(0.5, 1.5, 1001)
    error = 100 * (r - 1)
    fig, ax = plt.subplots(figsize=(8, 5))
    for kind, style in zip(laws.SHAPERS, ("C0", "C1", "C2")):
        ax.plot(
            error,
            100 * laws.Shaper(kind).vibration(r),
            color=style,
            label=f"{kind.upper()} shaper, zeta = 0",
        )
    for kind, style in zip(("zv", "zvd"), ("C0", "C1")):
        ax.plot(
            error,
            100 * laws.Shaper(kind, DAMPING).vibration(r),
            color=style,
            ls="--",
            label=f"{kind.upper()} shaper, zeta = {DAMPING:g}",
        )
    v_designed = law_vibration(designed, DESIGN_RATIO)(r)
    v_cycloidal = law_vibration(base, DESIGN_RATIO)(r)
    ax.plot(
        error,
        100 * v_designed,
        color="k",
        lw=2,
        label=f"designed law, no added duration, zeta = {DAMPING:g}",
    )
    ax.plot(error, 100 * v_cycloidal, color="C7", label=f"cycloidal, unshaped, zeta = {DAMPING:g}")
    ax.axhline(100 * LIMIT, color="C3", lw=0.8, ls=":")
    ax.axvspan(-100 * BAND, 100 * BAND, color="C3", alpha=0.06)
    ax.set(
        xlabel="frequency error, actual / design - 1 (%)",
        ylabel="V: residual / unshaped step's (%)",
        ylim=(0, 40),
        title=f"Residual vibration against frequency error (design period ratio "
        f"{DESIGN_RATIO:g} for the laws)",
    )
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "vibration.png", dpi=120)
    plt.close(fig)

    def cell(x):
        if x is None:
            return "none (V > 5% at 0)"
        return f"beyond {x:+.0f}" if abs(abs(x) - 100 * (SEARCH[1] - 1)) < 1e-9 else f"{x:+.2f}"

    md = [
        "| shaper or law | band low (%) | band high (%) | published (+/- %) | added duration |",
        "|---|---:|---:|---:|---|",
    ]
    md += [
        f"| {row['what']} | {cell(row['band_low_percent'])} | {cell(row['band_high_percent'])} | "
        f"{row.get('published_percent', '')} | {row['added_duration']} |"
        for row in rows
    ]
    (out / "bands.md").write_text("\n".join(md) + "\n")
    keys = ("what", "band_low_percent", "band_high_percent", "published_percent", "added_duration")
    (out / "bands.csv").write_text(
        "\n".join(
            [",".join(keys)]
            + [
                ",".join(
                    f'"{row.get(k, "")}"'
                    if k in ("what", "added_duration")
                    else str(row.get(k, ""))
                    for k in keys
                )
                for row in rows
            ]
        )
        + "\n"
    )
    inside = np.abs(r - 1) <= BAND
    return {
        "bands": rows,
        "design_ratio": DESIGN_RATIO,
        "damping": DAMPING,
        "limit": LIMIT,
        "designed_max_V_over_band": float(v_designed[inside].max()),
        "cycloidal_max_V_over_band": float(v_cycloidal[inside].max()),
        "designed_coefficients": result.coefficients,
        "design_seconds": design_seconds,
    }


def least_rms(out: Path, quick: bool) -> dict:
    floor = laws.RMS_ACCELERATION_FLOOR
    caps = (JERK_CAP,) if quick else JERK_CAPS
    steps = 1200 if quick else D.DEFAULT_STEPS
    rows, chosen = [], None
    for cap in caps:
        result = D.design(
            D.RmsAcceleration(), caps=D.Caps(max_jerk=cap), steps=steps, progress=False
        )
        c = result.law.rms_coefficients()
        rows.append(
            {
                "max_jerk": cap,
                "Ca_rms": c["Ca_rms"],
                "over_floor": c["Ca_rms"] / floor,
                "Ca": result.coefficients["Ca"],
                "Cv_rms": c["Cv_rms"],
                "Cva": c["Cva"],
            }
        )
        if cap == JERK_CAP:
            chosen = result.law
    laws.save(chosen, out / "least_rms_law.json")
    lines = [
        "| jerk cap | Ca_rms | Ca_rms / floor | Ca | Cv_rms | Cva |",
        "|---:|---:|---:|---:|---:|---:|",
    ]
    lines += [
        f"| {r['max_jerk']:g} | {r['Ca_rms']:.4f} | {r['over_floor']:.4f} | {r['Ca']:.3f} | "
        f"{r['Cv_rms']:.4f} | {r['Cva']:.3f} |"
        for r in rows
    ]
    (out / "rms.md").write_text("\n".join(lines) + "\n")
    keys = list(rows[0])
    (out / "rms.csv").write_text(
        "\n".join([",".join(keys)] + [",".join(str(r[k]) for k in keys) for r in rows]) + "\n"
    )
    tau = np.linspace(0, 1, 2001)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(
        tau,
        np.asarray(chosen.a(tau)),
        "k",
        lw=2,
        label=f"least Ca_rms, Cj <= {JERK_CAP:g}: {chosen.rms_coefficients()['Ca_rms']:.4f}",
    )
    ax.plot(
        tau,
        6 - 12 * tau,
        "C3",
        ls="--",
        label=f"cubic 3t^2 - 2t^3 (the floor 2 sqrt 3 = {floor:.4f})",
    )
    for name in ("modified-sine", "cycloidal"):
        law = laws.get(name)
        ax.plot(
            tau,
            np.asarray(law.a(tau)),
            lw=1,
            label=f"{name}: {law.rms_coefficients()['Ca_rms']:.4f}",
        )
    ax.set(
        xlabel="tau",
        ylabel="a (h/T^2)",
        title="Acceleration of the least-RMS design (Ca_rms in the legend)",
    )
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "rms.png", dpi=120)
    plt.close(fig)
    return {"floor": floor, "designs": rows, "jerk_cap": JERK_CAP}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results/robust_laws")
    parser.add_argument(
        "--quick", action="store_true", help="fewer optimiser steps and one jerk cap"
    )
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    summary = {"robust": robust(out, args.quick), "least_rms": least_rms(out, args.quick)}
    summary["seconds"] = time.perf_counter() - start
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=str) + "\n")
    print((out / "bands.md").read_text())
    print((out / "rms.md").read_text())
    print(
        f"designed law: max V over +/-{100 * BAND:g}% = {summary['robust']['designed_max_V_over_band']:.4f} "
        f"(cycloidal {summary['robust']['cycloidal_max_V_over_band']:.4f}); {summary['seconds']:.0f} s; wrote {out}"
    )


if __name__ == "__main__":
    main()
