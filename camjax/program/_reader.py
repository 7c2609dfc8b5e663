"""A program file read and written: the TOML structure to a program's parts (segments by law,
lift table or drawing; the follower, its chain, materials, drive and motors) and back.

Every error is one ``ValueError`` naming the table, the segment or the key; the program
type itself (``_program.Program``) checks the parts it is built from.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from .. import laws
from .._plain import example_file, example_names
from ..laws import AbstractMotionLaw, BoundaryPolynomial, TableLaw
from ._follower import (
    FOLLOWER_KINDS,
    Follower,
    Materials,
    _finite,
    _positive,
    follower_keys,
)
from ._motion import (
    END_STATE_KEYS,
    MATCH,
    EndState,
    is_polynomial,
)
from ._motor import Drive, motors_from_program_file
from ._segment import Segment, check_segment_count
from ._table import points_toml, read_points, table_points, turn_segments
from ._table import segment_law as table_segment_law
from ._train import CLASSIC_FIELDS, chain_from_dict

TABLE_KEYS = ("file", "points", "smoothing_mm")
"""A ``law = "table"`` segment's keys (and a whole cam's, in ``[program]``)."""
DXF_KEYS = ("dxf", "dxf_layer", "dxf_points", "dxf_rotation", "dxf_units")
"""``[program]`` keys of a whole cam drawn in a DXF file (with ``smoothing_mm``)."""


def read_program(data: dict, base: Path | None) -> dict:
    """The arguments of ``Program`` from a program file's TOML structure (``program``,
    ``segment`` list, ``follower``, ...); law files and tables named relative to ``base``."""
    no_unknown(data, {"program", "segment", "follower", "materials", "drive", "motor", "train", "spring",
                       "seat", "arm"}, "top level")
    chain = chain_from_dict(data)  # refuses a [[train]] beside the classic follower fields
    header = data.get("program", {})
    no_unknown(header, {"name", *TABLE_KEYS, *DXF_KEYS}, "[program]")
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
        check_segment_count(len(segments_data))
        segments = [_segment(i, s, base) for i, s in enumerate(segments_data, 1)]
    follower_data = data.get("follower")
    if not isinstance(follower_data, dict):
        raise ValueError("no [follower] table")
    fields = {f.name for f in dataclasses.fields(Follower)}
    no_unknown(follower_data, fields, "[follower]")
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
    no_unknown(materials, {f.name for f in dataclasses.fields(Materials)}, "[materials]")
    if dxf is not None:
        segments, follower_data = _dxf_segments(dxf, header, follower_data, base)
    drive = Drive.from_dict(data["drive"]) if "drive" in data else None
    motors = motors_from_program_file(data["motor"], base) if "motor" in data else ()
    return dict(name=str(header.get("name", "program")), segments=tuple(segments), follower=Follower(**follower_data),
                materials=Materials(**materials), drive=drive, motors=motors, chain=chain)



def table_segments(angle_deg, lift_mm, smoothing_mm: float | None) -> tuple[Segment, ...]:
    """A whole cam from one periodic lift table: ``angle_deg`` from 0 to below 360, the
    lift there (mm; the program's lift is measured from the lift at 0 degrees), fitted
    by a periodic quintic spline through the points, or within ``smoothing_mm`` of them."""
    angle, lift = _table_arrays(angle_deg, lift_mm)
    if smoothing_mm is not None and _finite(smoothing_mm, "smoothing_mm") <= 0:
        raise ValueError(f"smoothing_mm must be a positive tolerance in mm, got {smoothing_mm:g}")
    return tuple(Segment(a, h, law) for a, h, law in turn_segments(angle, lift, smoothing_mm, "points", "from_table"))



def drawn_segments(path, follower: Follower, *, points: int | None, layer: str | None, smoothing_mm: float | None,
                   rotation: str, units: str | None) -> tuple[Segment, ...]:
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
    return tuple(Segment(a, h, law) for a, h, law in parts)



def unnamed_laws(program) -> dict[int, AbstractMotionLaw]:
    """The laws ``to_toml`` can only name by a file (``law_files``), by 1-based segment:
    none of a lift table (written as its points), a polynomial (its end states) or a law
    the registry names (``camjax.laws.get``)."""
    if _turn_table(program) is not None:
        return {}
    out = {}
    for i, seg in enumerate(program.segments, 1):
        if seg.law is None or is_polynomial(seg) or (isinstance(seg.law, TableLaw) and seg.law.fit_info):
            continue
        try:
            named = laws.get(seg.law.name) == seg.law
        except ValueError:
            named = False
        if not named:
            out[i] = seg.law
    return out



def program_toml(program, law_files: dict[int, str] | None = None) -> str:
    """The program as TOML text: laws by registry name, or by ``law_files[i]`` (1-based)."""
    law_files = law_files or {}
    lines = ["[program]", f'name = "{program.name}"', ""]
    turn = _turn_table(program)
    if turn is not None:
        lines[-1:-1] = [f"points = {points_toml(turn.turn)}"] + (
            [] if turn.smoothing_mm is None else [f"smoothing_mm = {turn.smoothing_mm!r}"])
    for i, seg in enumerate(() if turn is not None else program.segments, 1):
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
        value = getattr(program.follower, field.name)
        if field.name == "roller_radius_mm" and program.follower.flat_face:
            continue
        if program.chain is not None and field.name in CLASSIC_FIELDS:
            continue  # the chain's tables below give them
        if value is not None:
            lines.append(f'{field.name} = "{value}"' if isinstance(value, str) else f"{field.name} = {value!r}")
    if program.materials != Materials():
        lines += ["", "[materials]"]
        lines += [f"{f.name} = {getattr(program.materials, f.name)!r}" for f in dataclasses.fields(Materials)]
    if program.drive is not None:
        lines += ["", program.drive.toml()]
    for motor in program.motors:
        lines += ["", motor.toml().replace("[motor]", "[[motor]]")]
    if program.chain is not None:
        lines += ["", *program.chain.toml_lines()]
    return "\n".join(lines).rstrip("\n") + "\n"



def no_unknown(table, allowed: set[str], where: str) -> None:
    if not isinstance(table, dict):
        raise ValueError(f"{where} must be a table")
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ValueError(f"{where}: unknown field(s) {', '.join(unknown)}; expected {', '.join(sorted(allowed))}")


def _segment(i: int, data, base: Path | None) -> Segment:
    no_unknown(data, {"law", "lift_mm", "angle_deg", "degree", "start", "end", *TABLE_KEYS}, f"segment {i}")
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


def _turn_table(program):
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
    no_unknown(value, set(END_STATE_KEYS), f"segment {i}: {key}")
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


def example_path(name: str = "indexer") -> Path:
    """Path of a program file shipped with camjax (``camjax/program/examples``, or its
    ``trains`` folder; ``camjax._plain.example_names`` lists them)."""
    return example_file(name)


def program_path(text: str | None, default: str = "indexer") -> Path:
    """The program file ``text`` names: a path, or a built-in example's name
    (``example_names``) where no such file exists; without ``text``, the example ``default``.
    A ``ValueError`` names the built-in examples where neither exists."""
    if not text:
        return example_path(default)
    path = Path(text)
    if text.isidentifier() and not path.exists() and example_path(text).exists():
        return example_path(text)  # a built-in example by name
    if not path.exists():
        raise ValueError(f"{text}: no such program file, nor a built-in example ({', '.join(example_names())})")
    return path
