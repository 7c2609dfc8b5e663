"""The per-speed report of a program: what ``camjax program`` prints and writes."""

from __future__ import annotations

import numpy as np

from ._dynamics import Solver, check_rpm
from ._groove import groove_turns
from ._jump import flights, jump_speed_rpm, min_preload_n
from ._spec import Program


def kinematic_acceleration_m_s2(program: Program, rpm) -> np.ndarray:
    """``max |y''|`` over the turn at each speed, exactly: ``|lift| Ca / t_segment^2``."""
    rpm = check_rpm(rpm)
    peak = max((abs(s.lift_mm) * float(s.law.Ca) / (s.angle_deg / 360.0) ** 2 for s in program.segments if s.moving),
               default=0.0)
    return 1e-3 * peak * (rpm / 60.0) ** 2


def period_ratios(program: Program, rpm) -> np.ndarray:
    """``(speeds, moving segments)``: each segment's duration times the natural frequency."""
    rpm = check_rpm(rpm)
    f_n = program.follower.natural_frequency_hz
    fractions = np.array([program.segments[i].angle_deg / 360.0 for i in program.moving_segments()])
    return f_n * 60.0 / rpm[:, None] * fractions[None, :]


def analyse(program: Program, rpm, *, with_flight: bool = True, solver: Solver | None = None,
            devices=None) -> dict:
    """The steady-state report at every speed in ``rpm`` (see docs/program.md).

    Every field but ``flight``, ``flights`` and ``impacts`` is the periodic steady state
    with contact held (linear); where that says contact is lost, ``flights`` lists every
    flight of the turn from the event simulation and ``flight`` is its first (null, both,
    where contact holds).  For a form-closed cam ``min_contact_force_n`` is the signed
    flank force (negative: the outer wall pushes), ``jump`` is false and ``min_preload_n``
    is null; with a groove clearance ``impacts`` lists the roller's strikes on the flanks
    in one settled turn (the ``Backlash`` hand-over, ``camjax.program.groove_turns``), else
    it is null.  The speeds are split over ``devices`` (``Solver``) when no ``solver`` is
    given.
    """
    rpm = check_rpm(rpm)
    solver = solver or Solver(program, rpm.min(), devices=devices)
    out = solver.summary(rpm)
    closed = program.follower.form_closed
    preload = min_preload_n(out["min_contact_force_n"], program.follower.preload_n)
    kinematic = kinematic_acceleration_m_s2(program, rpm)
    ratios = period_ratios(program, rpm)
    grooved = closed and bool(program.follower.groove_clearance_mm) and with_flight
    turns = groove_turns(program, rpm) if grooved else [None] * rpm.size
    speeds = []
    for i, r in enumerate(rpm):
        jump = bool(out["min_contact_force_n"][i] < 0) and not closed
        found = [x.as_dict() for x in flights(solver, float(r))] if jump and with_flight else None
        speeds.append({
            "rpm": float(r),
            "max_payload_acceleration_m_s2": float(out["max_payload_acceleration_m_s2"][i]),
            "max_kinematic_acceleration_m_s2": float(kinematic[i]),
            "min_contact_force_n": float(out["min_contact_force_n"][i]),
            "max_contact_force_n": float(out["max_contact_force_n"][i]),
            "jump": jump,
            "min_preload_n": None if closed else float(preload[i]),
            "residual_vibration_mm": [float(v) for v in out["residual_vibration_mm"][i]],
            "period_ratios": [float(v) for v in ratios[i]],
            "flight": found[0] if found else None,
            "flights": found,
            "impacts": None if turns[i] is None else [x.as_dict() for x in turns[i].impacts],
        })
    jump_speed = None
    if not closed and rpm.size > 1 and rpm.max() > rpm.min():
        jump_speed = jump_speed_rpm(solver, float(rpm.min()), float(rpm.max()))
    return {"program": program.name, "speeds": speeds, "jump_speed_rpm": jump_speed}


def response(program: Program, rpm: float, *, solver: Solver | None = None) -> dict[str, np.ndarray]:
    """Steady state over one turn at ``rpm``, at the grid nodes (law breakpoints included).

    Keys: ``theta_deg``, ``lift_mm``, ``payload_displacement_mm``, ``kinematic_acceleration_m_s2``
    (``y''``), ``payload_acceleration_m_s2`` (``x''``), ``contact_force_n``.
    """
    rpm = float(check_rpm(rpm)[0])
    solver = solver or Solver(program, rpm)
    cycle = solver.cycle(rpm)
    g = solver.grid
    theta = 360.0 * g.nodes
    y, _, ddy = program.lift(theta)
    deflection = np.imag(cycle.q) / float(np.imag(solver.lam(rpm)))
    return {
        "theta_deg": theta,
        "lift_mm": y,
        "payload_displacement_mm": y - deflection,
        "kinematic_acceleration_m_s2": 1e-3 * ddy * (360.0 * rpm / 60.0) ** 2,
        "payload_acceleration_m_s2": cycle.payload_acceleration_m_s2,
        "contact_force_n": cycle.contact_force_n,
    }
