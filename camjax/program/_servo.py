"""A program's servo motor sized from its dynamic steady state (``program_motor_choice``):
the duty cycle at each master speed (``_motor.duty_cycle``) from the steady state's histories
(``response``), then ``choose_motor``.  Above the analysis, which it reads; the drive and
motor types it sizes with stay under the program's reader (``_motor.py``)."""

from __future__ import annotations

from ._motor import MotorChoice, choose_motor, duty_cycle
from ._report import response


def program_motor_choice(program, speeds, *, steady=None, motors=None) -> MotorChoice:
    """``choose_motor`` for ``program`` (its ``[drive]``) at master ``speeds`` from the
    dynamic steady state (``steady``: a ``SteadyState`` already solved at those speeds, or
    for a chain with lash or a seat its ``ChainContacts``, whose settled turns give the
    simulated contact force at the cam over the turn: ``response``); ``motors``: a catalogue
    in place of the program's own ``[motor]``."""
    motors = program.motors if motors is None else tuple(motors)
    if program.drive is None:
        raise ValueError(
            "motor sizing needs the program's [drive] (travel_mm_per_rev or degrees_per_rev, "
            "gear_ratio, efficiencies, inertias: docs/servo.md)"
        )
    duties = [
        duty_cycle(program, program.drive, rpm, response(program, rpm, steady=steady))
        for rpm in speeds
    ]
    return choose_motor(motors, duties)
