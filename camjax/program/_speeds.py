"""A cam program's speeds, checked once at every public entry point."""

from __future__ import annotations

import warnings

import numpy as np

from .. import checks
from ._spec import Program

IMPLAUSIBLE_RPM, IMPLAUSIBLE_PERIOD_RATIO = 100_000.0, 0.05
"""Speeds no cam runs at, warned of (not refused): above 100,000 rpm, or a moving segment's
period ratio below 0.05 (the follower cannot follow its motion at all): often a unit slip."""


class CheckedSpeed(float):
    """A speed (rpm) that ``check_rpm`` has passed, for an entry point to hand to
    ``SteadyState`` (which then does not check it again).  Arithmetic on it gives a
    plain ``float``, so no computed value passes for a checked one."""


def check_rpm(rpm, program: Program | None = None, *, name: str = "rpm") -> np.ndarray:
    """Speeds as a 1-D float array, checked: numbers, positive and finite (a one-line
    ``ValueError`` naming ``name``, the caller's option, if not: ``camjax.checks.speeds``);
    with ``program``, a ``UserWarning`` for a speed past ``IMPLAUSIBLE_RPM`` or one that
    gives a segment a period ratio below ``IMPLAUSIBLE_PERIOD_RATIO``.

    The public entry points call it once, on their own arguments; the functions they call
    take the checked array (``SteadyState.summary_checked`` and its kin)."""
    rpm = checks.speeds(rpm, name)
    if program is not None:
        warn_implausible(program, rpm, stacklevel=4)
    return rpm


def warn_implausible(program: Program, rpm: np.ndarray, *, stacklevel: int = 3) -> None:
    """The ``UserWarning`` of ``check_rpm(rpm, program)`` for checked speeds
    (``speed_warnings``' line; ``analyse`` puts it in its report instead)."""
    for line in speed_warnings(program, rpm):
        warnings.warn(line, stacklevel=stacklevel)


def speed_warnings(program: Program, rpm) -> list[str]:
    """The line (none, or one) saying that speeds ``rpm`` are past ``IMPLAUSIBLE_RPM`` or give
    a moving segment a period ratio below ``IMPLAUSIBLE_PERIOD_RATIO``: often a unit slip."""
    rpm = np.asarray(rpm, dtype=float)
    shortest = min((s.angle_deg / 360.0 for s in program.segments if s.moving), default=1.0)
    ratio = program.follower.vibrations_per_turn(rpm.max()) * shortest
    why = [text for bad, text in (
        (rpm.max() > IMPLAUSIBLE_RPM, f"faster than any cam runs (above {IMPLAUSIBLE_RPM:,.0f} rpm)"),
        (ratio < IMPLAUSIBLE_PERIOD_RATIO, f"the shortest moving segment's period ratio is {ratio:.2g}, "
         f"below {IMPLAUSIBLE_PERIOD_RATIO:g}: the follower cannot follow the motion at all")) if bad]
    if not why:
        return []
    return [f"{program.name} at {rpm.max():g} rpm: {'; '.join(why)} (check the speed's units)"]
