"""The feed cam (motion tasks beyond rest-to-rest): acceleration and contact force over a turn.

The built-in example ``feed`` (``camjax/program/examples/feed.toml``: dwell, quintic from
rest onto a constant-velocity working stroke, septic reversal, quintic return, dwell) in
its periodic steady state at two speeds: the cam's ``y''`` and the payload's ``x''``, and
the contact force, over the turn; the joins and each segment's peaks.

    python experiments/motion_tasks.py [--rpm 400,650]

writes results/motion_tasks/ (feed_turn.png, feed_turn.csv, summary.json).
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from camjax.program import Program, SteadyState, analyse, example_path, response  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "results" / "motion_tasks"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rpm", default="400,650", help="two speeds (rpm)")
    args = parser.parse_args()
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
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
