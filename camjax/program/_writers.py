"""The files of a program's report: ``summary.json``, the profile, ``response.csv``, figures.

What ``camjax program --out DIR`` writes, from the typed ``Report`` (``MachineReport`` for
a machine file); the figures import matplotlib on first use.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

from .._plain import json_ready
from ._chain_contacts import ChainContacts
from ._dynamics import SteadyState
from ._export import profile, write_csv, write_dxf
from ._groove import groove_turns
from ._program import Program
from ._report import Report, response, steady_state

RESPONSE_SPEEDS = 10
"""Most speeds whose histories over the turn ``response.csv`` holds (the first ones), with
the figures' speed where it is not among them."""


def write_report(out, program: Program, report: Report, *, steady: SteadyState | ChainContacts | None = None,
                 points: int = 3600, plot_rpm: float | None = None, summary: dict | None = None) -> None:
    """Write ``report`` of ``program`` to the directory ``out``: ``summary.json``
    (``Report.to_json``, or the JSON of ``summary`` where given), ``profile.csv`` and ``profile.dxf`` (``points`` points),
    ``response.csv`` (``response`` at the first ``RESPONSE_SPEEDS`` speeds and the figures'
    speed; a chain's with every body's histories) and the figures (``save_figures``; the
    turn at ``plot_rpm``, default ``Report.plot_rpm``).  ``steady``: the steady state the
    report was computed from (``SteadyState``, or ``ChainContacts`` for a chain with lash
    or a seat, whose turns it keeps), else one is built."""
    from ._figures import save_figures

    out = Path(out)
    plot_rpm = report.plot_rpm(plot_rpm)
    lowest = min(s.rpm for s in report.speeds)
    if steady is None:
        steady = steady_state(program, lowest)
    text = report.to_json() if summary is None else json.dumps(json_ready(summary), indent=1)
    (out / "summary.json").write_text(text + "\n")
    prof = profile(program, points)
    write_csv(prof, out / "profile.csv", outer=program.follower.form_closed)
    write_dxf(prof, out / "profile.dxf", outer=program.follower.form_closed)
    written = [s.rpm for s in report.speeds[:RESPONSE_SPEEDS]]
    written += [] if plot_rpm in written else [plot_rpm]
    histories = [(r, response(program, r, steady=steady)) for r in written]
    with (out / "response.csv").open("w", newline="") as handle:
        writer = csv.writer(handle)
        keys = list(histories[0][1])
        writer.writerow(["rpm", *keys])
        for r, h in histories:
            for i in range(h["theta_deg"].size):
                writer.writerow([r] + [f"{h[k][i]:.10g}" for k in keys])
    shown = next(h for r, h in histories if r == plot_rpm)
    groove = None
    if program.follower.form_closed and program.follower.groove_clearance_mm:
        groove = groove_turns(program, [plot_rpm])[0]
    save_figures(out, program, report, (plot_rpm, shown), prof, histories=histories[:RESPONSE_SPEEDS],
                 groove=groove)


def write_machine_report(out, machine, report, *, points: int = 3600) -> None:
    """Write a ``MachineReport`` of ``machine`` to ``out``: its ``summary.json``, each cam's
    files (``write_report``, its summary with its ``phase_deg``) in ``cam<i>-<name>/`` and
    the shaft's figures."""
    from ._figures import shaft_figures

    out = Path(out)
    (out / "summary.json").write_text(report.to_json() + "\n")
    summaries = report.as_dict()["cams"]
    for i, ((program, _), cam, summary) in enumerate(zip(machine.cams, report.cams, summaries), 1):
        folder = out / f"cam{i}-{program.name}"
        folder.mkdir(exist_ok=True)
        write_report(folder, program, cam, points=points, summary=summary)
    shaft_figures(out, machine, report, [s.rpm for s in report.shaft])
