"""The simulated chain's report (lash and a seat) checked against finer runs.

``refine``: the example valve (``valve_lash.toml``, with a 10 mm line contact) at 3000 rpm
simulated at 1024, 4096 and 32768 samples a turn: each run's extremes over its samples and
refined between them (``ChainContacts.summary``), so the refined coarse figures can be read
against the finest run.  ``jump``: the same valve with a 60 N preload, the jump speed
searched between 3500 and 4500 rpm (``analyse``) against a scan of 32 speeds 0.1 rpm
apart around it, with the time of each.

    PYTHONPATH=. python experiments/benchmarks/chain_contacts_report.py refine
    PYTHONPATH=. python experiments/benchmarks/chain_contacts_report.py jump
"""

from __future__ import annotations

import dataclasses
import sys
import time

import numpy as np

from camjax.program import ChainContacts, ContactOptions, Program, Spring, analyse

EXAMPLE = "camjax/program/examples/trains/valve_lash.toml"


def refine(program):
    wide = dataclasses.replace(
        program, follower=dataclasses.replace(program.follower, contact_width_mm=10.0)
    )
    for samples in (1024, 4096, 32768):
        start = time.perf_counter()
        contacts = ChainContacts(wide, wide.chain, 3000.0, ContactOptions(samples=samples))
        summary, (turn,) = contacts.summary([3000.0])
        took = time.perf_counter() - start
        print(f"{samples} samples ({took:.1f} s, {turn.refined.switched.sum()} switched intervals)")
        rows = [
            ("max contact force N", turn.cam_force_n.max(), summary.max_contact_force_n[0]),
            (
                "valve max |x''| m/s2",
                np.abs(turn.acceleration_m_s2[-1]).max(),
                summary.max_acceleration_m_s2[0, -1],
            ),
            (
                "tappet max |x''| m/s2",
                np.abs(turn.acceleration_m_s2[0]).max(),
                summary.max_acceleration_m_s2[0, 0],
            ),
            ("max seat force N", turn.spring_seat_force_n.max(), summary.max_seat_force_n[0]),
            ("max |T| N m", np.abs(turn.drive_torque_n_m).max(), summary.max_drive_torque_n_m[0]),
            ("max Hertz MPa", None, summary.stress.stress_mpa[0]),
        ]
        for name, sampled, refined in rows:
            text = "-" if sampled is None else f"{sampled:.10g}"
            print(f"  {name:24s} sampled {text:>16s}  refined {refined:.10g}")


def jump(program):
    chain = dataclasses.replace(program.chain, spring=Spring(40.0, 60.0))
    start = time.perf_counter()
    report = analyse(dataclasses.replace(program, chain=chain), [3500.0, 4500.0])
    found, below = report.jump_speed_rpm, report.jump_below_range
    print(
        f"jump speed searched: {found!r} rpm (below {below}), {time.perf_counter() - start:.1f} s"
    )
    scan = found + 0.1 * (np.arange(32) - 15.5)
    start = time.perf_counter()
    turns = ChainContacts(program, chain, 3500.0).turns(scan, refine=False)
    cam = np.array([t.separates["cam"] for t in turns])
    first = scan[np.argmax(cam)] if cam.any() else None
    print(f"scan {scan[0]:.2f} to {scan[-1]:.2f} rpm by 0.1: separates {cam.astype(int).tolist()}")
    print(f"first separating speed of the scan: {first!r}, {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    part = sys.argv[1] if len(sys.argv) > 1 else "refine"
    {"refine": refine, "jump": jump}[part](Program.load(EXAMPLE))
