"""The valve of camjax/program/examples/trains/valve_lash.toml near its closing: its lift
against the cam's kinematic lift through the rocker, the seating and the bounce, at two
speeds (docs/valve-trains.md, "Lash and the seat").

    python experiments/examples/valve_seating.py [--out docs/valve-seating.png]
"""

from __future__ import annotations

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from camjax.program import ChainContacts, Program  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", default="docs/valve-seating.png")
    parser.add_argument("--rpm", default="1000,3000")
    args = parser.parse_args()
    program = Program.load("camjax/program/examples/trains/valve_lash.toml")
    chain = program.chain
    rpm = [float(r) for r in args.rpm.split(",")]
    turns = ChainContacts(program, chain, min(rpm)).turns(rpm)
    ratio = float(np.prod([b.ratio for b in chain.bodies if not b.rides]))
    valve = chain.bodies[-1]
    # the valve's quasi-static lift: the cam's through the rocker, less the lash and the
    # rocker's compression under the spring's preload
    offset = valve.lash_mm + chain.spring.preload_n / valve.stiffness_n_per_mm  # mm
    fig, axes = plt.subplots(
        len(turns), 1, figsize=(8, 3.2 * len(turns)), layout="constrained", sharex=True
    )
    for ax, turn in zip(np.atleast_1d(axes), turns):
        window = (turn.theta_deg > 160) & (turn.theta_deg < 215)
        theta = turn.theta_deg[window]
        ax.plot(
            theta,
            ratio * turn.lift_mm[window],
            "--",
            color="0.5",
            label="cam's kinematic lift x ratio",
        )
        ax.plot(
            theta,
            ratio * turn.lift_mm[window] - offset,
            ":",
            color="0.5",
            label="... less the lash and the rocker's compression by the preload",
        )
        ax.plot(theta, turn.last_mm[window], color="C0", label="valve")
        landing = [(b.angle_deg, b.velocity_m_s) for b in turn.bounces]
        seat_contacts = np.flatnonzero(np.diff((turn.seat_contact_force_n > 0).astype(int)) == 1)
        for i in seat_contacts:
            if 160 < turn.theta_deg[i] < 215:
                ax.axvline(turn.theta_deg[i], color="C3", lw=0.6)
        ax.set_ylim(-0.05, 0.6)
        ax.set_ylabel("lift (mm)")
        text = f"{turn.rpm:g} rpm: seats at {turn.seating_velocity_m_s:.3f} m/s"
        if landing:
            text += "; bounces " + ", ".join(f"{v:.3f} m/s" for _, v in landing[:3])
        ax.set_title(text, fontsize=10)
        ax.legend(fontsize=8, loc="upper right")
    np.atleast_1d(axes)[-1].set_xlabel("cam angle (deg); red: the valve lands on its seat")
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
