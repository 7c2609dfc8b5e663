"""A whole cam: a program of segments over 360 degrees and its follower, in physical units.

A program is read from TOML (``Program.load``) or built directly.  Every check names the
segment or the field that fails, with a ``ValueError``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .. import laws
from ..checks import is_concrete, read_toml, speeds
from ..laws import AbstractMotionLaw, BoundaryPolynomial, ConstantVelocity, TableLaw
from ._follower import (
    FOLLOWER_KINDS,
    Follower,
    Materials,
    _as_floats,
    _check_follower,
    _finite,
    _positive,
    follower_keys,
)
from ._motion import (
    END_STATE_KEYS,
    MATCH,
    EndState,
    check_excursions,
    is_polynomial,
    joins,
    resolve_segments,
)
from ._motor import Drive, Motor, motors_from_program_file
from ._table import points_toml, read_points, table_points, turn_segments
from ._table import segment_law as table_segment_law
from ._train import CLASSIC_FIELDS, Chain, chain_from_dict
from ._turn import JOIN_TOLERANCE_DEG, Turn

MAX_SEGMENTS = 360
"""Most segments of a program (a degree each on average): each is sampled, checked and
reported apart, so 100,000 slivers took minutes and megabytes of output; more is refused
before any work."""
TABLE_KEYS = ("file", "points", "smoothing_mm")
"""A ``law = "table"`` segment's keys (and a whole cam's, in ``[program]``)."""
DXF_KEYS = ("dxf", "dxf_layer", "dxf_points", "dxf_rotation", "dxf_units")
"""``[program]`` keys of a whole cam drawn in a DXF file (with ``smoothing_mm``)."""
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
        _no_unknown(data, {"program", "segment", "follower", "materials", "drive", "motor", "train", "spring",
                           "seat", "arm"}, "top level")
        chain = chain_from_dict(data)  # refuses a [[train]] beside the classic follower fields
        header = data.get("program", {})
        _no_unknown(header, {"name", *TABLE_KEYS, *DXF_KEYS}, "[program]")
        segments_data = data.get("segment")
        dxf = _dxf_header(header, segments_data)
        if dxf is not None:
            segments = []  # from the follower, below
        elif any(k in header for k in ("file", "points")):
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
        if chain is not None:
            follower_data = {**follower_data, **chain.follower_fields()}
        for required in ("mass_kg", "stiffness_n_per_mm"):
            if required not in follower_data:
                raise ValueError(f"[follower] needs {required}")
        kind = follower_data.get("kind", Follower.kind)
        if ("roller_radius_mm" in follower_data and isinstance(kind, str) and kind in FOLLOWER_KINDS
                and "roller_radius_mm" not in follower_keys(FOLLOWER_KINDS[kind])):
            raise ValueError("[follower] roller_radius_mm: a flat-faced follower has no roller")
        materials = data.get("materials", {})
        _no_unknown(materials, {f.name for f in dataclasses.fields(Materials)}, "[materials]")
        if dxf is not None:
            segments, follower_data = _dxf_segments(dxf, header, follower_data, base)
        drive = Drive.from_dict(data["drive"]) if "drive" in data else None
        motors = motors_from_program_file(data["motor"], base) if "motor" in data else ()
        return cls(str(header.get("name", "program")), tuple(segments), Follower(**follower_data),
                   Materials(**materials), drive, motors, chain)

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

    @classmethod
    def from_dxf(cls, name: str, path, follower: Follower, *, points: int | None = None, layer: str | None = None,
                 smoothing_mm: float | None = None, rotation: str = "ccw", units: str | None = None,
                 materials: Materials = Materials()) -> Program:
        """A whole cam from its profile drawn in a DXF file (``write_dxf``'s inverse): the
        lift ``lift_from_dxf`` finds for ``follower`` at ``points`` angles (``layer``,
        ``rotation``, ``units`` as there), fitted as ``from_table`` fits a table
        (``smoothing_mm`` as there).  Errors are one-line ``ValueError``s naming the file."""
        from ._dxf_import import DEFAULT_POINTS, dxf_segments

        if smoothing_mm is not None and _finite(smoothing_mm, "smoothing_mm") <= 0:
            raise ValueError(f"smoothing_mm must be a positive tolerance in mm, got {smoothing_mm:g}")
        points = DEFAULT_POINTS if points is None else points
        try:
            parts = dxf_segments(path, follower, points=points, layer=layer, rotation=rotation, units=units,
                                 smoothing_mm=smoothing_mm)
        except ValueError as error:
            message = _dxf_table_error(error)
            raise ValueError(message if message.startswith(str(path)) else f"{path}: {message}") from None
        return cls(name, tuple(Segment(a, h, law) for a, h, law in parts), follower, materials)

    def unnamed_laws(self) -> dict[int, AbstractMotionLaw]:
        """The laws ``to_toml`` can only name by a file (``law_files``), by 1-based segment:
        none of a lift table (written as its points), a polynomial (its end states) or a law
        the registry names (``camjax.laws.get``)."""
        if _turn_table(self) is not None:
            return {}
        out = {}
        for i, seg in enumerate(self.segments, 1):
            if seg.law is None or is_polynomial(seg) or (isinstance(seg.law, TableLaw) and seg.law.fit_info):
                continue
            try:
                named = laws.get(seg.law.name) == seg.law
            except ValueError:
                named = False
            if not named:
                out[i] = seg.law
        return out

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
            if self.chain is not None and field.name in CLASSIC_FIELDS:
                continue  # the chain's tables below give them
            if value is not None:
                lines.append(f'{field.name} = "{value}"' if isinstance(value, str) else f"{field.name} = {value!r}")
        if self.materials != Materials():
            lines += ["", "[materials]"]
            lines += [f"{f.name} = {getattr(self.materials, f.name)!r}" for f in dataclasses.fields(Materials)]
        if self.drive is not None:
            lines += ["", self.drive.toml()]
        for motor in self.motors:
            lines += ["", motor.toml().replace("[motor]", "[[motor]]")]
        if self.chain is not None:
            lines += ["", *self.chain.toml_lines()]
        return "\n".join(lines).rstrip("\n") + "\n"

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


def _dxf_header(header: dict, segments_data) -> str | None:
    """``[program] dxf``'s path, checked against the keys it excludes, or ``None``."""
    if "dxf" not in header:
        extra = sorted(k for k in DXF_KEYS if k in header)
        if extra:
            raise ValueError(f"[program] {', '.join(extra)} belong(s) to dxf = \"....dxf\"")
        return None
    if any(k in header for k in ("file", "points")):
        raise ValueError("[program] dxf: the cam's profile replaces a lift table (file or points); give one")
    if segments_data is not None:
        raise ValueError("[program] dxf: the cam's profile replaces the [[segment]] tables; give one or the other")
    if not isinstance(header["dxf"], str):
        raise ValueError(f"[program] dxf must be a path, got {header['dxf']!r}")
    return header["dxf"]


def _dxf_segments(name: str, header: dict, follower_data: dict, base: Path | None):
    """A whole cam's segments from ``[program] dxf`` (path relative to the program file) and
    the follower's fields, ``base_radius_mm`` taken from the profile when not given."""
    from ._dxf_import import DEFAULT_POINTS, ROTATIONS, UNITS, dxf_segments, read_dxf_profile

    path = Path(name) if base is None else base / name
    layer = header.get("dxf_layer")
    if layer is not None and not isinstance(layer, str):
        raise ValueError(f"[program] dxf_layer must be a layer name, got {layer!r}")
    rotation = header.get("dxf_rotation", "ccw")
    if rotation not in ROTATIONS:
        raise ValueError(f"[program] dxf_rotation must be one of {', '.join(map(repr, ROTATIONS))} (how the drawn "
                         f"cam turns), got {rotation!r}")
    units = header.get("dxf_units")
    if units is not None and units not in UNITS:
        raise ValueError(f"[program] dxf_units must be one of {', '.join(map(repr, UNITS))} (the drawing's "
                         f"length unit, in place of its $INSUNITS), got {units!r}")
    points = header.get("dxf_points", DEFAULT_POINTS)
    smoothing = header.get("smoothing_mm")
    if smoothing is not None and _finite(smoothing, "[program] smoothing_mm") <= 0:
        raise ValueError(f"[program] smoothing_mm must be a positive tolerance in mm, got {smoothing:g}")
    try:
        if "base_radius_mm" not in follower_data:
            cam = read_dxf_profile(path, layer, rotation=rotation, units=units)
            follower_data = {**follower_data, "base_radius_mm": cam.base_radius_mm}
        parts = dxf_segments(path, Follower(**follower_data), points=points, layer=layer, rotation=rotation,
                             units=units, smoothing_mm=smoothing, source=name)
    except ValueError as error:
        message = _dxf_table_error(error).replace("points must", "dxf_points must", 1)
        raise ValueError(f"[program] dxf: {message}") from None
    return [Segment(a, h, law) for a, h, law in parts], follower_data


def _dxf_table_error(error: ValueError) -> str:
    """A whole-cam table's error said of a DXF profile: its angle 0 is where the follower is
    drawn (on the +y axis for a translating follower), not a table's first row."""
    message = str(error)
    if "angle 0 must be on the base circle" in message or "highest lift must lie after angle 0" in message:
        message += ("; in the drawing, the follower stands at angle 0 (a translating one on the +y axis): "
                    "turn the profile so that the base circle is there")
    return message + _units_hint(message)


def _units_hint(message: str) -> str:
    """A note on the drawing's unit where a DXF error's lengths are implausibly large."""
    import re

    lengths = [float(x) for x in re.findall(r"(-?\d+(?:\.\d+)?(?:e[+-]?\d+)?) mm", message)]
    if lengths and max(map(abs, lengths)) > 2000.0 and "dxf_units" not in message:
        return ("; lengths that large suggest a drawing read in the wrong unit (its $INSUNITS): "
                "say which with dxf_units")
    return ""


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
        if not str(error).startswith("unknown law"):  # a known law's parameters: what is wrong with them
            raise ValueError(f"segment {i}: {error}") from None
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
    """Path of a program file shipped with camjax (``camjax/program/examples``, or its
    ``trains`` folder: 'valve', 'swinging_arm')."""
    examples = Path(__file__).parent / "examples"
    train = examples / "trains" / f"{name}.toml"
    return train if train.exists() and not (examples / f"{name}.toml").exists() else examples / f"{name}.toml"


def program_path(text: str | None, default: str = "indexer") -> Path:
    """The program file ``text`` names: a path, or a built-in example's name ('indexer',
    'feed', 'valve', 'swinging_arm') where no such file exists; without ``text``, the example ``default``."""
    if not text:
        return example_path(default)
    path = Path(text)
    if text.isidentifier() and not path.exists() and example_path(text).exists():
        return example_path(text)  # a built-in example by name
    return path
