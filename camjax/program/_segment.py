"""One stretch of a cam's turn: a rise, return or dwell by its law, and how many a program may have."""

from __future__ import annotations

import dataclasses

from ..laws import AbstractMotionLaw, BoundaryPolynomial, ConstantVelocity
from ._follower import (
    _as_floats,
)
from ._motion import (
    MATCH,
    EndState,
)

MAX_SEGMENTS = 360
"""Most segments of a program (a degree each on average): each is sampled, checked and
reported apart, so 100,000 slivers took minutes and megabytes of output; more is refused
before any work."""


@dataclasses.dataclass(frozen=True)
class Segment:
    """One stretch of the cam turn: a rise or return by ``law`` over ``angle_deg``, or a dwell.

    ``lift_mm`` is the change of lift over the segment (negative for a return); a dwell has
    ``law=None`` and ``lift_mm=0``.  A polynomial segment (``Segment.polynomial``) has
    ``start`` and ``end``: each ``"match"`` (the neighbour's state there) or an
    ``EndState``; the program solves its ``BoundaryPolynomial`` law from them.
    """

    angle_deg: float
    lift_mm: float = 0.0
    law: AbstractMotionLaw | None = None
    start: str | EndState | None = None
    end: str | EndState | None = None

    def __post_init__(self):
        _as_floats(self)  # a TOML integer lift or angle, however large, as a float

    @property
    def moving(self) -> bool:
        return self.law is not None and self.lift_mm != 0.0

    @classmethod
    def polynomial(cls, angle_deg: float, lift_mm: float, degree: int = 5, start=MATCH, end=MATCH) -> Segment:
        """A polynomial of ``degree`` 5 or 7 from ``start`` to ``end`` (``"match"`` or ``EndState``)."""
        return cls(angle_deg, lift_mm, BoundaryPolynomial(degree=degree), start, end)

    @classmethod
    def constant_velocity(cls, angle_deg: float, lift_mm: float) -> Segment:
        """The follower moving at ``lift_mm / angle_deg`` mm/deg over the whole segment."""
        return cls(angle_deg, lift_mm, ConstantVelocity())


def check_segment_count(count: int) -> None:
    if count > MAX_SEGMENTS:
        raise ValueError(f"the program has {count:,} segments; the limit is {MAX_SEGMENTS} "
                         "(merge neighbouring dwells, and short segments into their neighbours)")
