"""The feed cam (motion tasks beyond rest-to-rest): acceleration and contact force over a turn.

The built-in example ``feed`` (``camjax/program/examples/feed.toml``: dwell, quintic from
rest onto a constant-velocity working stroke, septic reversal, quintic return, dwell) in
its periodic steady state at two speeds: the cam's ``y''`` and the payload's ``x''``, and
the contact force, over the turn; the joins and each segment's peaks.

Then the choices for the reversal (segment 4, G -> G: 0.3 mm/deg in, -0.4 mm/deg out) a
designer would try, with the same end states and the rest of the cam unchanged: the
degree-5 and degree-7 boundary polynomials and the ``CorrectedPolynomial`` designed for
the least preload over the band (``design_segment``, 8 knots, 200 steps; about 40 s).  The
preload each needs (``SteadyState.summary(...).min_contact_force_n`` through
``min_preload_n``) against rpm.  A modified-sine (or any rest-to-rest) transition does not
apply: both ends of the segment are in motion.

    python experiments/examples/motion_tasks.py [--rpm 400,650] [--band 500:650] [--quick] [--out DIR]

writes results/motion_tasks/ (feed_turn.png, feed_turn.csv, summary.json,
reversal_preload.png, reversal_preload.csv, reversal_preload.json, designed/ with the
designed program).
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from camjax.program import (  # noqa: E402
    EndState,
    Program,
    Segment,
    SteadyState,
    analyse,
    design_segment,
    example_path,
    min_preload_n,
    response,
    write_program,
)

OUT = Path(__file__).resolve().parents[2] / "results" / "motion_tasks"
REVERSAL = 4  # the feed cam's G -> G segment (1-based)
PLOT_RPM = (400.0, 700.0)  # the preload chart's speeds, wider than the design band
PLOT_POINTS = 301


def reversal_choices(program: Program, rpm_lo: float, rpm_hi: float) -> dict[str, Program]:
    """The feed cam with its reversal as a quintic, a septic (the example) and the designed law."""
    seg = program.segments[REVERSAL - 1]
    quintic = Segment.polynomial(seg.angle_deg, seg.lift_mm, 5, seg.start,
                                 EndState(seg.end.velocity_mm_per_deg, seg.end.acceleration_mm_per_deg2))
    segments = list(program.segments)
    segments[REVERSAL - 1] = quintic
    designed, _ = design_segment(program, REVERSAL, rpm_lo, rpm_hi, objective="preload", knots=8,
                                 steps=200, progress=False)
    return {"degree-5 polynomial": Program(program.name, tuple(segments), program.follower,
                                           program.materials),
            "degree-7 polynomial (the example)": program,
            "designed CorrectedPolynomial": designed}


def compare_reversals(program: Program, rpm_lo: float, rpm_hi: float) -> dict:
    """Preload needed against rpm for each reversal choice; figure, CSV and JSON into OUT."""
    choices = reversal_choices(program, rpm_lo, rpm_hi)
    write_program(choices["designed CorrectedPolynomial"], OUT / "designed")
    lo, hi = min(PLOT_RPM[0], rpm_lo), max(PLOT_RPM[1], rpm_hi)
    rpm = np.unique(np.concatenate([np.linspace(lo, hi, PLOT_POINTS), np.linspace(rpm_lo, rpm_hi, 151)]))
    band = (rpm >= rpm_lo) & (rpm <= rpm_hi)
    preload, rows = {}, []
    for label, choice in choices.items():
        summary = SteadyState(choice, lo).summary(rpm)
        preload[label] = min_preload_n(summary.min_contact_force_n, choice.follower.preload_n)
        law = choice.segments[REVERSAL - 1].law
        rows.append({"choice": label, "law": law.name, "max_preload_n_in_band": float(preload[label][band].max()),
                     "rpm_of_max": float(rpm[band][np.argmax(preload[label][band])]),
                     "Ca": float(law.Ca), "Cj": float(law.Cj),
                     "joins": [j.as_dict() for j in choice.joins()]})

    fig, ax = plt.subplots(figsize=(8, 4.5))
    for label, values in preload.items():
        ax.plot(rpm, values, label=label)
    ax.axvspan(rpm_lo, rpm_hi, color="0.92", zorder=0, label=f"design band {rpm_lo:g}-{rpm_hi:g} rpm")
    ax.axhline(program.follower.preload_n, color="k", ls="--", lw=0.8, label="the example's preload")
    ax.set(xlabel="rpm", ylabel="preload needed (N)",
           title="feed cam: preload needed, three laws for the reversal (segment 4, G to G)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "reversal_preload.png", dpi=120)
    with (OUT / "reversal_preload.csv").open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["rpm", *preload])
        for i, r in enumerate(rpm):
            writer.writerow([f"{r:.10g}"] + [f"{v[i]:.10g}" for v in preload.values()])
    result = {"segment": REVERSAL, "rpm_lo": rpm_lo, "rpm_hi": rpm_hi, "choices": rows}
    (OUT / "reversal_preload.json").write_text(json.dumps(result, indent=1) + "\n")
    for row in rows:
        print(f"{row['choice']}: largest preload over {rpm_lo:g}-{rpm_hi:g} rpm {row['max_preload_n_in_band']:.1f} N "
              f"at {row['rpm_of_max']:.1f} rpm (Ca {row['Ca']:.3f}, Cj {row['Cj']:.1f})")
    return result


def main() -> None:
    global OUT
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rpm", default="400,650", help="two speeds (rpm)")
    parser.add_argument("--band", default="500:650", help="the reversal's design band LO:HI (rpm)")
    parser.add_argument("--quick", action="store_true",
                        help="the steady state only: no reversal design (a smoke run)")
    parser.add_argument("--out", type=Path, default=OUT, help="output folder (default: results/motion_tasks)")
    args = parser.parse_args()
    OUT = args.out
    band = [float(x) for x in args.band.split(":")]
    speeds = [float(x) for x in args.rpm.split(",")]
    OUT.mkdir(parents=True, exist_ok=True)
    program = Program.load(example_path("feed"))
    steady = SteadyState(program, min(speeds))
    report = analyse(program, speeds, steady=steady, with_flight=False).as_dict()
    histories = {rpm: response(program, rpm, steady=steady) for rpm in speeds}

    fig, axes = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    for rpm, h in histories.items():
        line, = axes[0].plot(h["theta_deg"], h["payload_acceleration_m_s2"], lw=1.0,
                             label=f"payload x'' at {rpm:g} rpm")
        axes[0].plot(h["theta_deg"], h["kinematic_acceleration_m_s2"], "--", lw=0.8, color=line.get_color(),
                     label=f"cam y'' at {rpm:g} rpm")
        axes[1].plot(h["theta_deg"], h["contact_force_n"], lw=1.0, color=line.get_color(), label=f"{rpm:g} rpm")
    axes[1].axhline(0.0, color="k", lw=0.6)
    for ax in axes:
        for start in program.start_deg[1:]:
            ax.axvline(start, color="0.8", lw=0.6, zorder=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_ylabel("acceleration (m/s^2)")
    axes[1].set_ylabel("contact force (N)")
    axes[1].set_xlabel("cam angle (deg); grey lines: segment joins")
    axes[0].set_title("feed cam: periodic steady state (R-G quintic, G stroke, G-B septic, B-R quintic)")
    fig.tight_layout()
    fig.savefig(OUT / "feed_turn.png", dpi=120)

    with (OUT / "feed_turn.csv").open("w", newline="") as handle:
        writer = csv.writer(handle)
        keys = list(next(iter(histories.values())))
        writer.writerow(["rpm", *keys])
        for rpm, h in histories.items():
            for i in range(h["theta_deg"].size):
                writer.writerow([rpm] + [f"{h[k][i]:.10g}" for k in keys])
    (OUT / "summary.json").write_text(json.dumps(report, indent=1) + "\n")
    for s in report["speeds"]:
        print(f"{s['rpm']:g} rpm: max|x''| {s['max_payload_acceleration_m_s2']:.4g} m/s2, min Fc "
              f"{s['min_contact_force_n']:.4g} N, min preload {s['min_preload_n']:.4g} N, residual "
              + ", ".join(f"{r:.3g}" for r in s["residual_vibration_mm"]) + " mm")
    if not args.quick:
        compare_reversals(program, *band)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
