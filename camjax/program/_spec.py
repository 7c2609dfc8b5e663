"""A whole cam: a program of segments over 360 degrees and its follower, in physical units.

A program is read from TOML (``Program.load``) or built directly.  Every check names the
segment or the field that fails, with a ``ValueError``.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .. import laws
from ..checks import finite_number, is_concrete, read_toml, speeds
from ..laws import AbstractMotionLaw, BoundaryPolynomial, ConstantVelocity, TableLaw
from ._motion import (
    END_STATE_KEYS,
    MATCH,
    EndState,
    check_excursions,
    is_polynomial,
    joins,
    resolve_segments,
)
from ._table import points_toml, read_points, table_points, turn_segments
from ._table import segment_law as table_segment_law

FOLLOWER_KINDS = ("translating-roller", "swinging-roller", "translating-flat", "swinging-flat")
MAX_SEGMENTS = 360
"""Most segments of a program (a degree each on average): each is sampled, checked and
reported apart, so 100,000 slivers took minutes and megabytes of output; more is refused
before any work."""
TABLE_KEYS = ("file", "points", "smoothing_mm")
"""A ``law = "table"`` segment's keys (and a whole cam's, in ``[program]``)."""
_ANGLE_TOLERANCE_DEG = 1e-9
_LIFT_TOLERANCE_MM = 1e-9


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


@dataclasses.dataclass(frozen=True)
class Follower:
    """The follower train, referred to the roller (lengths in mm, forces in N).

    ``spring_rate_n_per_mm=None`` is a form-closed (grooved) cam: no return spring, no
    preload, no jump; ``groove_clearance_mm`` (form-closed only) is how much wider than
    the roller its groove is: the roller then crosses it when the train force changes sign.  For ``kind="swinging-roller"`` the lift is the arc length of the
    roller centre (swing angle times ``arm_mm``) and ``pivot_mm`` is the cam-centre to pivot
    distance.  A flat-faced follower (``"translating-flat"``, ``"swinging-flat"``) has no
    roller: the swinging face is a plane through the pivot and its lift is the swing angle
    times ``arm_mm``.  ``contact_width_mm`` is the width of the line contact (the roller's, or
    the cam's under a flat face) for the Hertz stress; without it no stress is reported.
    """

    mass_kg: float
    stiffness_n_per_mm: float
    damping_ratio: float = 0.0
    spring_rate_n_per_mm: float | None = None
    preload_n: float = 0.0
    base_radius_mm: float = 40.0
    roller_radius_mm: float = 10.0
    offset_mm: float = 0.0
    kind: str = "translating-roller"
    arm_mm: float | None = None
    pivot_mm: float | None = None
    groove_clearance_mm: float | None = None
    contact_width_mm: float | None = None

    @property
    def flat_face(self) -> bool:
        return self.kind.endswith("-flat")

    @property
    def swinging(self) -> bool:
        return self.kind.startswith("swinging")

    @property
    def form_closed(self) -> bool:
        return self.spring_rate_n_per_mm is None

    @property
    def spring_rate(self) -> float:
        """Return-spring rate in N/m (0 for a form-closed cam)."""
        return 0.0 if self.form_closed else 1e3 * self.spring_rate_n_per_mm

    @property
    def stiffness(self) -> float:
        """Train stiffness in N/m."""
        return 1e3 * self.stiffness_n_per_mm

    @property
    def damping(self) -> float:
        """Train damping ``c = 2 zeta sqrt(k m)`` in N s/m."""
        return 2 * self.damping_ratio * math.sqrt(self.stiffness * self.mass_kg)

    @property
    def natural_frequency_hz(self) -> float:
        """``sqrt((k + k_s) / m) / (2 pi)``."""
        return math.sqrt((self.stiffness + self.spring_rate) / self.mass_kg) / (2 * math.pi)

    def vibrations_per_turn(self, rpm):
        """Natural vibrations of the follower per cam turn at ``rpm``, ``f_n 60 / rpm``: the
        period ratio of the whole turn (a segment's is this times its angle over 360).  The
        one place where a speed becomes a period ratio."""
        return self.natural_frequency_hz * 60.0 / rpm


_finite = finite_number  # a program file's numbers are checked as every other input


def _positive(value, what: str) -> float:
    value = _finite(value, what)
    if value <= 0:
        raise ValueError(f"{what} must be positive, got {value:g}")
    return value


def _check_follower(f: Follower) -> None:
    if f.kind not in FOLLOWER_KINDS:
        raise ValueError(f"follower.kind must be one of {', '.join(FOLLOWER_KINDS)}, got {f.kind!r}")
    for name in ("mass_kg", "stiffness_n_per_mm", "base_radius_mm", "roller_radius_mm"):
        _positive(getattr(f, name), f"follower.{name}")
    zeta = _finite(f.damping_ratio, "follower.damping_ratio")
    if not 0 <= zeta < 1:
        raise ValueError(f"follower.damping_ratio must be in [0, 1), got {zeta:g}")
    if not f.form_closed:
        _positive(f.spring_rate_n_per_mm, "follower.spring_rate_n_per_mm")
    if f.groove_clearance_mm is not None:
        if not f.form_closed:
            raise ValueError("follower.groove_clearance_mm: only a form-closed cam (no "
                             "spring_rate_n_per_mm) has a groove")
        _positive(f.groove_clearance_mm, "follower.groove_clearance_mm")
    if _finite(f.preload_n, "follower.preload_n") < 0:
        raise ValueError(f"follower.preload_n must be non-negative, got {f.preload_n:g}")
    if f.contact_width_mm is not None:
        _positive(f.contact_width_mm, "follower.contact_width_mm")
    offset = _finite(f.offset_mm, "follower.offset_mm")
    if f.kind == "translating-roller" and abs(offset) >= f.base_radius_mm + f.roller_radius_mm:
        raise ValueError("follower.offset_mm: |offset| must be below base_radius_mm + roller_radius_mm")
    if f.flat_face and f.groove_clearance_mm is not None:
        raise ValueError("follower.groove_clearance_mm: a flat-faced follower runs on no groove")
    if f.kind == "translating-flat" and offset != 0:
        raise ValueError("follower.offset_mm: a flat face's profile does not depend on an offset; "
                         "leave it 0")
    if f.swinging:
        for name in ("arm_mm", "pivot_mm"):
            if getattr(f, name) is None:
                raise ValueError(f"follower.{name} is missing: a {f.kind} follower needs "
                                 "arm_mm and pivot_mm")
    if f.kind == "swinging-flat":
        _positive(f.arm_mm, "follower.arm_mm")
        if _positive(f.pivot_mm, "follower.pivot_mm") <= f.base_radius_mm:
            raise ValueError("follower.pivot_mm: the pivot must lie outside the base circle "
                             "(pivot_mm > base_radius_mm) for its face to touch it")
    if f.kind == "swinging-roller":
        arm = _positive(f.arm_mm, "follower.arm_mm")
        pivot = _positive(f.pivot_mm, "follower.pivot_mm")
        rp = f.base_radius_mm + f.roller_radius_mm
        if not abs(pivot - arm) < rp < pivot + arm:
            raise ValueError("follower.arm_mm, pivot_mm: the arm cannot reach the base circle "
                             "(|pivot - arm| < base + roller < pivot + arm fails)")


@dataclasses.dataclass(frozen=True)
class Materials:
    """Elastic constants of the cam and the follower (roller or face) for the Hertz stress."""

    cam_youngs_modulus_gpa: float = 210.0
    cam_poisson_ratio: float = 0.3
    follower_youngs_modulus_gpa: float = 210.0
    follower_poisson_ratio: float = 0.3

    def __post_init__(self):
        for part in ("cam", "follower"):
            _positive(getattr(self, f"{part}_youngs_modulus_gpa"), f"materials.{part}_youngs_modulus_gpa")
            nu = _finite(getattr(self, f"{part}_poisson_ratio"), f"materials.{part}_poisson_ratio")
            if not -1.0 < nu < 0.5:
                raise ValueError(f"materials.{part}_poisson_ratio must be in (-1, 0.5), got {nu:g}")

    @property
    def contact_modulus_mpa(self) -> float:
        """``E*`` with ``1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2``, in MPa (N/mm^2)."""
        compliance = sum((1 - getattr(self, f"{p}_poisson_ratio") ** 2) / getattr(self, f"{p}_youngs_modulus_gpa")
                         for p in ("cam", "follower"))
        return 1e3 / compliance


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
    states (``"match"`` reads the neighbour's).
    """

    name: str
    segments: tuple[Segment, ...]
    follower: Follower
    materials: Materials = Materials()

    def __post_init__(self):
        object.__setattr__(self, "segments", tuple(self.segments))
        if not self.segments:
            raise ValueError("a program needs at least one segment")
        _segment_count(len(self.segments))
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
        if abs(total - 360.0) > _ANGLE_TOLERANCE_DEG:
            raise ValueError(f"segment angles sum to {total:g} degrees, not 360")
        if abs(lift) > _LIFT_TOLERANCE_MM:
            raise ValueError(f"the cumulative lift ends at {lift:g} mm, not back at zero (the base circle)")
        object.__setattr__(self, "segments", resolve_segments(self.segments))
        if is_concrete([s.law for s in self.segments]):
            check_excursions(self.segments, self.start_lift_mm)
            self.joins()
        _check_follower(self.follower)

    def joins(self):
        """Every join of the turn (``camjax.program.Join``: velocity, acceleration either
        side, C1/C2, VDI 2143 state); a velocity jump is a ``ValueError``."""
        return joins(self.segments, self.start_deg)

    # -- reading and writing -------------------------------------------------------------

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
        _no_unknown(data, {"program", "segment", "follower", "materials"}, "top level")
        header = data.get("program", {})
        _no_unknown(header, {"name", *TABLE_KEYS}, "[program]")
        segments_data = data.get("segment")
        if any(k in header for k in ("file", "points")):
            # A whole cam from one periodic table, in place of segments.
            if segments_data is not None:
                raise ValueError("[program] table: a whole cam's table replaces the [[segment]] tables; "
                                 "give one or the other")
            segments = _turn_segments(header, base)
        elif "smoothing_mm" in header:
            raise ValueError("[program] smoothing_mm belongs to a whole cam's table (file or points)")
        else:
            if not isinstance(segments_data, list) or not segments_data:
                raise ValueError("no [[segment]] tables: a program needs at least one segment "
                                 "(or [program] file = a whole cam's lift table)")
            _segment_count(len(segments_data))
            segments = [_segment(i, s, base) for i, s in enumerate(segments_data, 1)]
        follower_data = data.get("follower")
        if not isinstance(follower_data, dict):
            raise ValueError("no [follower] table")
        fields = {f.name for f in dataclasses.fields(Follower)}
        _no_unknown(follower_data, fields, "[follower]")
        for required in ("mass_kg", "stiffness_n_per_mm"):
            if required not in follower_data:
                raise ValueError(f"[follower] needs {required}")
        if str(follower_data.get("kind", "")).endswith("-flat") and "roller_radius_mm" in follower_data:
            raise ValueError("[follower] roller_radius_mm: a flat-faced follower has no roller")
        materials = data.get("materials", {})
        _no_unknown(materials, {f.name for f in dataclasses.fields(Materials)}, "[materials]")
        return cls(str(header.get("name", "program")), tuple(segments), Follower(**follower_data),
                   Materials(**materials))

    @classmethod
    def from_table(cls, name: str, angle_deg, lift_mm, follower: Follower, *,
                   smoothing_mm: float | None = None, materials: Materials = Materials()) -> Program:
        """A whole cam from one periodic lift table: ``angle_deg`` from 0 to below 360, the
        lift there (mm; the program's lift is measured from the lift at 0 degrees), fitted
        by a periodic quintic spline through the points, or within ``smoothing_mm`` of them."""
        angle, lift = _table_arrays(angle_deg, lift_mm)
        if smoothing_mm is not None and _finite(smoothing_mm, "smoothing_mm") <= 0:
            raise ValueError(f"smoothing_mm must be a positive tolerance in mm, got {smoothing_mm:g}")
        segments = [Segment(a, h, law) for a, h, law in turn_segments(angle, lift, smoothing_mm, "points", "from_table")]
        return cls(name, tuple(segments), follower, materials)

    def to_toml(self, law_files: dict[int, str] | None = None) -> str:
        """The program as TOML text: laws by registry name, or by ``law_files[i]`` (1-based)."""
        law_files = law_files or {}
        lines = ["[program]", f'name = "{self.name}"', ""]
        turn = _turn_table(self)
        if turn is not None:
            lines[-1:-1] = [f"points = {points_toml(turn.turn)}"] + (
                [] if turn.smoothing_mm is None else [f"smoothing_mm = {turn.smoothing_mm!r}"])
        for i, seg in enumerate(() if turn is not None else self.segments, 1):
            lines.append("[[segment]]")
            if isinstance(seg.law, TableLaw) and seg.law.fit_info is not None:
                fit = seg.law.fit_info
                lines += ['law = "table"', f"lift_mm = {seg.lift_mm!r}", f"points = {points_toml(fit.points)}"]
                lines += [] if fit.smoothing_mm is None else [f"smoothing_mm = {fit.smoothing_mm!r}"]
            elif is_polynomial(seg):
                lines += ['law = "polynomial"', f"degree = {seg.law.degree}", f"lift_mm = {seg.lift_mm!r}"]
                lines += [f"{key} = " + ('"match"' if spec == MATCH else spec.toml())
                          for key, spec in (("start", seg.start), ("end", seg.end))]
            elif seg.law is not None:
                lines += [f'law = "{law_files.get(i, seg.law.name)}"', f"lift_mm = {seg.lift_mm!r}"]
            lines += [f"angle_deg = {seg.angle_deg!r}", ""]
        lines.append("[follower]")
        for field in dataclasses.fields(Follower):
            value = getattr(self.follower, field.name)
            if field.name == "roller_radius_mm" and self.follower.flat_face:
                continue
            if value is not None:
                lines.append(f'{field.name} = "{value}"' if isinstance(value, str) else f"{field.name} = {value!r}")
        if self.materials != Materials():
            lines += ["", "[materials]"]
            lines += [f"{f.name} = {getattr(self.materials, f.name)!r}" for f in dataclasses.fields(Materials)]
        return "\n".join(lines) + "\n"

    # -- the lift over the turn ----------------------------------------------------------

    @property
    def start_deg(self) -> np.ndarray:
        """Cam angle at the start of each segment (degrees)."""
        return np.concatenate([[0.0], np.cumsum([s.angle_deg for s in self.segments])[:-1]])

    @property
    def start_lift_mm(self) -> np.ndarray:
        """Lift at the start of each segment (mm)."""
        return np.concatenate([[0.0], np.cumsum([s.lift_mm for s in self.segments])[:-1]])

    def lift(self, theta_deg, side: str = "after") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Lift (mm) and its first two derivatives in cam angle (mm/deg, mm/deg^2), periodic.

        At a join of two segments the derivatives are the next segment's (``side="after"``)
        or the one ending there (``side="before"``): where the acceleration steps they differ.
        """
        if side not in ("before", "after"):
            raise ValueError(f"side must be 'before' or 'after', got {side!r}")
        theta = np.mod(np.asarray(theta_deg, dtype=float), 360.0)
        # Each angle's segment by index: an angle within the angle tolerance of a join is
        # that join, read at the end of the segment before it (tau = 1) or the start of the
        # one after (tau = 0); comparing rounded angles put a quarter of the joins past
        # their segment (tau a hair above 1 reads the dwell beyond).
        n = len(self.segments)
        starts = self.start_deg
        widths = np.array([seg.angle_deg for seg in self.segments], dtype=float)
        bounds = np.append(starts, 360.0)
        above = np.clip(np.searchsorted(bounds, theta), 1, n)  # the nearest join: above or below
        nearest = np.where(bounds[above] - theta < theta - bounds[above - 1], above, above - 1)
        at_join = np.abs(theta - bounds[nearest]) <= _ANGLE_TOLERANCE_DEG
        index = np.clip(np.searchsorted(bounds, theta, side="right") - 1, 0, n - 1)
        index = np.where(at_join, (nearest - 1) % n if side == "before" else nearest % n, index)
        tau = np.clip((theta - starts[index]) / widths[index], 0.0, 1.0)
        tau = np.where(at_join, 1.0 if side == "before" else 0.0, tau)
        y, dy, ddy = (np.zeros_like(theta) for _ in range(3))
        for k, (seg, y0) in enumerate(zip(self.segments, self.start_lift_mm)):
            inside = index == k
            if not inside.any():
                continue
            y[inside] = y0
            if seg.moving:
                s, v, a, _ = (np.asarray(x) for x in seg.law.evaluate(tau[inside]))
                y[inside] += seg.lift_mm * s
                dy[inside] = seg.lift_mm * v / seg.angle_deg
                ddy[inside] = seg.lift_mm * a / seg.angle_deg**2
        return y, dy, ddy

    def lift_curve(self) -> LiftCurve:
        """The lift as a pytree (laws as leaves) for ``camjax.geometry`` and other JAX code."""
        moving = [i for i, seg in enumerate(self.segments) if seg.moving]
        scale = 1.0 / self.follower.arm_mm if self.follower.swinging else 1.0
        return LiftCurve(
            laws=tuple(self.segments[i].law for i in moving),
            start_deg=tuple(float(self.start_deg[i]) for i in moving),
            angle_deg=tuple(float(self.segments[i].angle_deg) for i in moving),
            lift_mm=tuple(float(self.segments[i].lift_mm) for i in moving),
            scale=scale,
        )

    def displacement(self, theta):
        """Follower displacement at cam angle ``theta`` (radians), jittable: see ``LiftCurve``."""
        return self.lift_curve().displacement(theta)

    def moving_segments(self) -> list[int]:
        return [i for i, s in enumerate(self.segments) if s.moving]

    def dwell_segments(self) -> list[int]:
        return [i for i, s in enumerate(self.segments) if not s.moving]

    def residual_segments(self) -> list[int]:
        """The dwells and constant-velocity segments: where the residual vibration is reported."""
        return [i for i, s in enumerate(self.segments) if not s.moving or isinstance(s.law, ConstantVelocity)]


class LiftCurve(eqx.Module):
    """The program's lift over the turn as a JAX pytree, ``camjax.geometry``'s program interface.

    The lift is the sum of each moving segment's contribution ``lift * s(tau)`` (0 before
    the segment, ``lift`` after it), so dwells need no term.  ``displacement`` is in mm
    for a translating follower and radians of swing for a swinging one (``scale = 1/arm``).
    """

    laws: tuple
    start_deg: tuple = eqx.field(static=True)
    angle_deg: tuple = eqx.field(static=True)
    lift_mm: tuple = eqx.field(static=True)
    scale: float = eqx.field(static=True)

    def displacement(self, theta):
        theta_deg = jnp.mod(jnp.asarray(theta, dtype=float) * (180 / math.pi), 360.0)
        y = jnp.zeros_like(theta_deg)
        for law, start, angle, lift in zip(self.laws, self.start_deg, self.angle_deg, self.lift_mm):
            y = y + lift * law.s((theta_deg - start) / angle)
        return self.scale * y


def _segment_count(count: int) -> None:
    if count > MAX_SEGMENTS:
        raise ValueError(f"the program has {count:,} segments; the limit is {MAX_SEGMENTS} "
                         "(merge neighbouring dwells, and short segments into their neighbours)")


def _no_unknown(table, allowed: set[str], where: str) -> None:
    if not isinstance(table, dict):
        raise ValueError(f"{where} must be a table")
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ValueError(f"{where}: unknown field(s) {', '.join(unknown)}; expected {', '.join(sorted(allowed))}")


def _segment(i: int, data, base: Path | None) -> Segment:
    _no_unknown(data, {"law", "lift_mm", "angle_deg", "degree", "start", "end", *TABLE_KEYS}, f"segment {i}")
    if "angle_deg" not in data:
        raise ValueError(f"segment {i}: needs angle_deg")
    lift = data.get("lift_mm", 0.0)
    law = None
    if data.get("law") == "table":
        extra = sorted({"degree", "start", "end"} & set(data))
        if extra:
            raise ValueError(f'segment {i}: {", ".join(extra)} belong(s) to law = "polynomial"')
        angle = _positive(data["angle_deg"], f"segment {i}: angle_deg")
        given = _finite(data["lift_mm"], f"segment {i}: lift_mm") if "lift_mm" in data else None
        lift, law = table_segment_law(f"segment {i}", angle, given, data, base)
        return Segment(angle_deg=angle, lift_mm=lift, law=law)
    table_keys = sorted(set(TABLE_KEYS) & set(data))
    if table_keys:
        raise ValueError(f'segment {i}: {", ".join(table_keys)} belong(s) to law = "table"')
    if "law" in data:
        if "lift_mm" not in data:
            raise ValueError(f"segment {i}: law given without lift_mm")
        if data["law"] == "polynomial":
            degree = data.get("degree", 5)
            if isinstance(degree, bool) or not isinstance(degree, int) or degree not in (5, 7):
                raise ValueError(f"segment {i}: degree must be 5 or 7, got {degree!r}")
            return Segment(data["angle_deg"], lift, BoundaryPolynomial(degree=degree),
                           _end_state(i, "start", data.get("start", MATCH)),
                           _end_state(i, "end", data.get("end", MATCH)))
        law = _law(i, data["law"], base)
    extra = sorted({"degree", "start", "end"} & set(data))
    if extra:
        raise ValueError(f'segment {i}: {", ".join(extra)} belong(s) to law = "polynomial"')
    return Segment(angle_deg=data["angle_deg"], lift_mm=lift, law=law)


def _turn_segments(header: dict, base: Path | None) -> list[Segment]:
    """The rise and return of a whole cam's periodic table (``[program] file`` or ``points``)."""
    angle, lift, source = table_points(header, "[program]", base)
    smoothing = header.get("smoothing_mm")
    if smoothing is not None and _finite(smoothing, "[program] smoothing_mm") <= 0:
        raise ValueError(f"[program] smoothing_mm must be a positive tolerance in mm, got {smoothing:g}")
    return [Segment(a, h, law) for a, h, law in turn_segments(angle, lift, smoothing, source)]


def _table_arrays(angle_deg, lift_mm):
    """Checked ``(angle, lift)`` arrays of a table given in Python (as a program file's points)."""
    angle, lift = (np.asarray(x, dtype=float).ravel() for x in (angle_deg, lift_mm))
    if angle.shape != lift.shape:
        raise ValueError(f"angle_deg and lift_mm must have the same length, got {angle.size} and {lift.size}")
    return read_points(np.stack([angle, lift], axis=1).tolist(), "table")


def _turn_table(program: Program):
    """The whole-cam table a program was cut from (its laws' ``fit_info``), or ``None``."""
    fits = [getattr(s.law, "fit_info", None) for s in program.segments]
    if fits and all(f is not None and f.turn is not None for f in fits) and len({f.turn for f in fits}) == 1:
        return fits[0]
    return None


def _end_state(i: int, key: str, value) -> str | EndState:
    """``"match"`` or an ``EndState`` from a program file's ``start`` or ``end``."""
    if value == MATCH:
        return MATCH
    if not isinstance(value, dict):
        raise ValueError(f'segment {i}: {key} must be "match" or a table {{ {", ".join(END_STATE_KEYS)} }}, '
                         f"got {value!r}")
    _no_unknown(value, set(END_STATE_KEYS), f"segment {i}: {key}")
    if "velocity_mm_per_deg" not in value:
        raise ValueError(f"segment {i}: {key} needs velocity_mm_per_deg")
    numbers = {k: _finite(v, f"segment {i}: {key}.{k}") for k, v in value.items()}
    return EndState(**numbers)


def _law(i: int, name, base: Path | None) -> AbstractMotionLaw:
    if not isinstance(name, str):
        raise ValueError(f"segment {i}: law must be a name or a file, got {name!r}")
    if name.endswith(".json"):
        path = Path(name) if base is None else base / name
        if not path.exists():
            raise ValueError(f"segment {i}: law file {str(path)!r} not found")
        try:
            return laws.load(path)  # its errors name the file
        except ValueError as error:
            raise ValueError(f"segment {i}: law file {error}") from None
    try:
        return laws.get(name)
    except ValueError as error:
        raise ValueError(f'segment {i}: {error}, or "polynomial" (with degree, start, end), '
                         'or "table" (with file or points)') from None


def with_law(program: Program, segment: int, law) -> Program:
    """``program`` with segment ``segment``'s (1-based) law replaced."""
    segments = list(program.segments)
    # The new law is the segment's own: a polynomial's end states no longer solve for it.
    segments[segment - 1] = dataclasses.replace(segments[segment - 1], law=law, start=None, end=None)
    return dataclasses.replace(program, segments=tuple(segments))


def segment_band(program: Program, segment: int, rpm_lo: float, rpm_hi: float) -> tuple[float, float]:
    """Period-ratio band ``(n1, n2)`` of segment ``segment`` (1-based) over the speed range
    (the design's check of its speeds, ``camjax.checks.speeds``)."""
    rpm_lo, rpm_hi = float(speeds(rpm_lo, "rpm_lo")[0]), float(speeds(rpm_hi, "rpm_hi")[0])
    if not rpm_lo < rpm_hi:
        raise ValueError(f"need 0 < rpm_lo < rpm_hi, got {rpm_lo:g}, {rpm_hi:g}")
    if not 1 <= segment <= len(program.segments):
        raise ValueError(f"segment must be 1..{len(program.segments)}, got {segment}")
    seg = program.segments[segment - 1]
    if not seg.moving:
        raise ValueError(f"segment {segment} is a dwell: nothing to design")
    per_turn = program.follower.vibrations_per_turn(np.array([rpm_hi, rpm_lo]))
    return tuple(float(n) for n in per_turn * seg.angle_deg / 360.0)


def example_path(name: str = "indexer") -> Path:
    """Path of a program file shipped with camjax (``camjax/program/examples``)."""
    return Path(__file__).parent / "examples" / f"{name}.toml"
