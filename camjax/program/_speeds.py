"""A cam program's speeds as a value: ``Speeds``, checked once when built."""

from __future__ import annotations

import warnings

import numpy as np

from .. import checks
from .._plain import parse_range
from ._program import Program

IMPLAUSIBLE_RPM = 100_000.0
"""A speed above it is warned of (not refused): no cam runs so fast, often a unit slip."""
IMPLAUSIBLE_PERIOD_RATIO = 0.05
"""A moving segment's period ratio below it is warned of (not refused): the follower cannot
follow the motion at all, often a unit slip."""


class Speeds:
    """Machine speeds (rpm): a non-empty, read-only 1-D float array, each speed positive and
    finite, checked once when built (``checks.speeds``: a one-line ``ValueError`` naming
    ``name``, the caller's option, if not).

    Every entry point takes a ``Speeds`` or anything it is built from (a number, a list, an
    array; ``Speeds.parse`` reads ``START:STOP:COUNT`` or ``V1,V2,...``) and builds it with
    ``Speeds.of``, which passes a ``Speeds`` through unchecked; so the functions an entry
    point calls take its ``Speeds`` as they are.  A subset (``speeds[mask]``) is a
    ``Speeds``; one speed (``speeds[i]``) a ``float``."""

    __slots__ = ("rpm",)

    def __init__(self, values, name: str = "rpm"):
        rpm = values.rpm if isinstance(values, Speeds) else checks.speeds(values, name).copy()
        rpm.flags.writeable = False
        self.rpm: np.ndarray = rpm

    @classmethod
    def of(cls, values, name: str = "rpm") -> Speeds:
        """``values`` as they are if a ``Speeds``, else checked into one."""
        return values if isinstance(values, Speeds) else cls(values, name)

    @classmethod
    def parse(cls, text: str, name: str = "rpm") -> Speeds:
        """The speeds written as ``START:STOP:COUNT`` (inclusive) or ``V1,V2,...``, or a
        one-line ``ValueError`` that starts with ``name``."""
        values = parse_range(str(text), name, check_count=checks.speed_count)  # before it is built
        checks.speed_count(values.size, name)  # a list V1,V2,... as long
        if not np.all(np.isfinite(values) & (values > 0)):
            raise ValueError(f"{name}: speeds must be positive and finite, got {text!r}")
        return cls(values, name)

    def __len__(self) -> int:
        return self.rpm.size

    @property
    def size(self) -> int:
        return self.rpm.size

    def __iter__(self):
        return iter(self.rpm.tolist())

    def __getitem__(self, index):
        picked = self.rpm[index]
        return float(picked) if np.ndim(picked) == 0 else Speeds._subset(picked)

    @classmethod
    def _subset(cls, rpm: np.ndarray) -> Speeds:
        if rpm.size == 0:
            raise ValueError("rpm must be one speed or a 1-D list of speeds")
        out = cls.__new__(cls)
        out.rpm = rpm
        return out

    def __array__(self, dtype=None, copy=None):
        return self.rpm if dtype is None else self.rpm.astype(dtype)

    def __repr__(self) -> str:
        return f"Speeds({self.rpm.tolist()!r})"

    def __eq__(self, other) -> bool:
        return isinstance(other, Speeds) and np.array_equal(self.rpm, other.rpm)

    def __hash__(self) -> int:
        return hash(tuple(self.rpm.tolist()))

    def min(self) -> float:
        return float(self.rpm.min())

    def max(self) -> float:
        return float(self.rpm.max())

    def tolist(self) -> list[float]:
        return self.rpm.tolist()


def warn_implausible(program: Program, rpm, *, stacklevel: int = 3) -> None:
    """A ``UserWarning`` with ``speed_warnings``' line, for an entry point that returns no
    report (``analyse`` puts the line in its report instead)."""
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
