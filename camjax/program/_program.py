"""A whole cam: a program of segments over 360 degrees and its follower, in physical units.

A program is read from TOML (``Program.load``, through the reader ``_reader.py``) or built
directly.  Every check names the segment or the field that fails, with a ``ValueError``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..checks import is_concrete, read_toml, speeds
from ..laws import AbstractMotionLaw, ConstantVelocity
from ._follower import (
    Follower,
    Materials,
    _check_follower,
    _finite,
    _positive,
)
from ._motion import (
    check_excursions,
    joins,
    resolve_segments,
)
from ._motor import Drive, Motor
from ._reader import (
    drawn_segments,
    program_toml,
    read_program,
    table_segments,
    unnamed_laws,
)
from ._segment import Segment, check_segment_count
from ._train import Chain
from ._turn import JOIN_TOLERANCE_DEG, Turn

_LIFT_TOLERANCE_MM = 1e-9


@dataclasses.dataclass(frozen=True)
class Program:
    """A cam program: segments covering one turn and the follower they drive.

    Checks (each a ``ValueError`` naming the segment or field): angles positive and
    summing to 360 degrees; a law on every segment with a lift and a lift on every
    segment with a law; the cumulative lift never below zero and back to zero at 360
    degrees (the program starts and ends on the base circle); the velocity continuous at
    every join, the wrap from the last segment to the first included (an acceleration
    step is allowed: ``joins``); the follower's numbers positive and finite.  Any number
    of segments up to ``MAX_SEGMENTS``, in any order.  Polynomial segments get their laws solved from their end
    states (``"match"`` reads the neighbour's).  ``chain``: the follower as a chain of
    bodies (a program file's ``[[train]]``; docs/valve-trains.md): the follower's one-body
    fields are then set from it (``Chain.follower_fields``, whatever was given); ``None``:
    the classic one-body follower.
    """

    name: str
    segments: tuple[Segment, ...]
    follower: Follower
    materials: Materials = Materials()
    drive: Drive | None = None  # a servo's transmission ([drive]), for motor sizing
    motors: tuple[Motor, ...] = ()  # [motor] records (or a catalogue file) to size
    chain: Chain | None = None  # the follower as a chain of bodies ([[train]]); None: the classic one

    def __post_init__(self):
        object.__setattr__(self, "segments", tuple(self.segments))
        if not self.segments:
            raise ValueError("a program needs at least one segment")
        check_segment_count(len(self.segments))
        lift = 0.0
        for i, seg in enumerate(self.segments, 1):
            _positive(seg.angle_deg, f"segment {i}: angle_deg")
            _finite(seg.lift_mm, f"segment {i}: lift_mm")
            if seg.law is None and seg.lift_mm != 0:
                raise ValueError(f"segment {i}: lift_mm = {seg.lift_mm:g} needs a law")
            if seg.law is not None and not isinstance(seg.law, AbstractMotionLaw):
                raise ValueError(f"segment {i}: law must be a camjax motion law")
            if seg.law is not None and not isinstance(seg.law.breakpoints(), tuple):
                raise ValueError(f"segment {i}: the law's breakpoints must be fixed numbers")
            lift += seg.lift_mm
            if lift < -_LIFT_TOLERANCE_MM:
                raise ValueError(f"segment {i}: the cumulative lift goes below zero ({lift:g} mm)")
        total = sum(seg.angle_deg for seg in self.segments)
        if abs(total - 360.0) > JOIN_TOLERANCE_DEG:
            raise ValueError(f"segment angles sum to {total:g} degrees, not 360")
        if abs(lift) > _LIFT_TOLERANCE_MM:
            raise ValueError(f"the cumulative lift ends at {lift:g} mm, not back at zero (the base circle)")
        object.__setattr__(self, "segments", resolve_segments(self.segments))
        if is_concrete([s.law for s in self.segments]):
            check_excursions(self.segments, self.start_lift_mm)
            self.joins()
        if self.chain is not None:
            if not isinstance(self.chain, Chain):
                raise ValueError(f"chain must be a camjax.program.Chain or None, got {self.chain!r}")
            object.__setattr__(self, "follower", dataclasses.replace(self.follower, **self.chain.follower_fields()))
        _check_follower(self.follower)
        if self.chain is not None:
            self.chain.check_follower(self.follower)

    @property
    def one_body(self) -> bool:
        """Whether the follower's one-body dynamics are this program's: no chain, or a chain
        that only spells the classic follower (``Chain.spells_follower``)."""
        return self.chain is None or self.chain.spells_follower

    def joins(self):
        """Every join of the turn (``camjax.program.Join``: velocity, acceleration either
        side, C1/C2, VDI 2143 state); a velocity jump is a ``ValueError``."""
        return joins(self.segments, self.start_deg)

    # -- reading and writing (the reader: _reader.py) ----------------------------------------

    @classmethod
    def load(cls, path) -> Program:
        """Read a program TOML file (law files named in it are relative to it)."""
        path = Path(path)
        data = read_toml(path, "program file")
        try:
            return cls.from_dict(data, base=path.parent)
        except ValueError as error:
            raise ValueError(f"{path}: {error}") from None

    @classmethod
    def from_dict(cls, data: dict, *, base: Path | None = None) -> Program:
        """A program from the TOML structure (``program``, ``segment`` list, ``follower``)."""
        return cls(**read_program(data, base))

    @classmethod
    def from_table(cls, name: str, angle_deg, lift_mm, follower: Follower, *,
                   smoothing_mm: float | None = None, materials: Materials = Materials()) -> Program:
        """A whole cam from one periodic lift table: ``angle_deg`` from 0 to below 360, the
        lift there (mm; the program's lift is measured from the lift at 0 degrees), fitted
        by a periodic quintic spline through the points, or within ``smoothing_mm`` of them."""
        return cls(name, table_segments(angle_deg, lift_mm, smoothing_mm), follower, materials)

    @classmethod
    def from_dxf(cls, name: str, path, follower: Follower, *, points: int | None = None, layer: str | None = None,
                 smoothing_mm: float | None = None, rotation: str = "ccw", units: str | None = None,
                 materials: Materials = Materials()) -> Program:
        """A whole cam from its profile drawn in a DXF file (``write_dxf``'s inverse): the
        lift ``lift_from_dxf`` finds for ``follower`` at ``points`` angles (``layer``,
        ``rotation``, ``units`` as there), fitted as ``from_table`` fits a table
        (``smoothing_mm`` as there).  Errors are one-line ``ValueError``s naming the file."""
        segments = drawn_segments(path, follower, points=points, layer=layer, smoothing_mm=smoothing_mm,
                                  rotation=rotation, units=units)
        return cls(name, segments, follower, materials)

    def unnamed_laws(self) -> dict[int, AbstractMotionLaw]:
        """The laws ``to_toml`` can only name by a file (``law_files``), by 1-based segment:
        none of a lift table (written as its points), a polynomial (its end states) or a law
        the registry names (``camjax.laws.get``)."""
        return unnamed_laws(self)

    def to_toml(self, law_files: dict[int, str] | None = None) -> str:
        """The program as TOML text: laws by registry name, or by ``law_files[i]`` (1-based)."""
        return program_toml(self, law_files)

    # -- the lift over the turn ----------------------------------------------------------

    @functools.cached_property
    def turn(self) -> Turn:
        """The lift over the turn (``Turn``): the one object every reader of the motion asks
        (built once per program; the fields are frozen)."""
        return Turn.of(self.segments)

    @property
    def start_deg(self) -> np.ndarray:
        """Cam angle at the start of each segment (degrees)."""
        return self.turn.start_deg

    @property
    def start_lift_mm(self) -> np.ndarray:
        """Lift at the start of each segment (mm)."""
        return self.turn.start_lift_mm

    def lift(self, theta_deg, side: str = "after") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Lift (mm) and its first two derivatives in cam angle (mm/deg, mm/deg^2), periodic.

        At a join of two segments the derivatives are the next segment's (``side="after"``)
        or the one ending there (``side="before"``): where the acceleration steps they differ
        (``Turn.locate`` decides).
        """
        return self.turn.jet(theta_deg, side)[:3]

    def largest_lift_mm(self) -> float:
        """The cam's largest lift (mm), read every 0.1 degree: times a chain's ratios
        (``Chain.lever_ratio``), the scale of the checks at the valve (the seat's squeeze,
        the lash, the lift error)."""
        return float(np.max(np.abs(self.lift(np.arange(3600) * 0.1)[0])))

    def lift_curve(self) -> LiftCurve:
        """The lift as a pytree (laws as leaves) for ``camjax.geometry`` and other JAX code."""
        return LiftCurve(self.turn, 1.0 / self.follower.geometry.lift_per_displacement)

    def displacement(self, theta):
        """Follower displacement at cam angle ``theta`` (radians), jittable: see ``LiftCurve``."""
        return self.lift_curve().displacement(theta)

    def moving_segments(self) -> list[int]:
        return [i for i, s in enumerate(self.segments) if s.moving]

    def residual_segments(self) -> list[int]:
        """The dwells and constant-velocity segments: where the residual vibration is reported."""
        return [i for i, s in enumerate(self.segments) if not s.moving or isinstance(s.law, ConstantVelocity)]


class LiftCurve(eqx.Module):
    """The follower's displacement over the turn as a JAX pytree, ``camjax.geometry``'s
    program interface: the turn's lift in mm for a translating follower, radians of swing
    for a swinging one (``scale = 1/arm``)."""

    turn: Turn
    scale: float = eqx.field(static=True)

    def displacement(self, theta):
        theta_deg = jnp.asarray(theta, dtype=float) * (180 / math.pi)
        return self.scale * self.turn.jet(theta_deg)[0]


def with_law(program: Program, segment: int, law) -> Program:
    """``program`` with segment ``segment``'s (1-based) law replaced."""
    segments = list(program.segments)
    # The new law is the segment's own: a polynomial's end states no longer solve for it.
    segments[segment - 1] = dataclasses.replace(segments[segment - 1], law=law, start=None, end=None)
    return dataclasses.replace(program, segments=tuple(segments))


def segment_band(program: Program, segment: int, rpm_lo: float, rpm_hi: float) -> tuple[float, float]:
    """Period-ratio band ``(n1, n2)`` of segment ``segment`` (1-based) over the speed range
    (the design's check of its speeds, ``camjax.checks.speeds``)."""
    bounds = []
    for value, name in ((rpm_lo, "rpm_lo"), (rpm_hi, "rpm_hi")):
        checked = speeds(value, name)
        if checked.size != 1:
            raise ValueError(f"{name} must be one speed in rpm, got {checked.size}")
        bounds.append(float(checked[0]))
    rpm_lo, rpm_hi = bounds
    if not rpm_lo < rpm_hi:
        raise ValueError(f"need 0 < rpm_lo < rpm_hi, got {rpm_lo:g}, {rpm_hi:g}")
    if not 1 <= segment <= len(program.segments):
        raise ValueError(f"segment must be 1..{len(program.segments)}, got {segment}")
    seg = program.segments[segment - 1]
    if not seg.moving:
        raise ValueError(f"segment {segment} is a dwell: nothing to design")
    per_turn = program.follower.vibrations_per_turn(np.array([rpm_hi, rpm_lo]))
    return tuple(float(n) for n in per_turn * seg.angle_deg / 360.0)
