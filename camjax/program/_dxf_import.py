"""A cam's profile read from a DXF drawing, and the lift table it implies for a follower.

The inverse of ``write_dxf``: the profile is a closed curve in mm in the cam-fixed frame of
``camjax.geometry`` (cam centre at the origin, the cam turning counter-clockwise, the
follower at angle 0 where the program's angle 0 puts it).  The curve is flattened by ezdxf
(``ezdxf.path``) into a polygon whose vertices lie on it; at each cam angle the polygon is
turned by the angle into the fixed frame and the follower is placed where it touches it,
by its ``camjax.geometry`` class's ``lift_from_polygon``:

- translating roller: the highest roller centre on the line ``x = offset`` whose roller
  touches the polygon (the upper end of the polygon's roller-radius neighbourhood on the
  line: an endpoint circle or an edge's offset line, exactly);
- swinging roller: likewise on the circle of the arm about the pivot, the arm swung as far
  out as the polygon pushes it;
- translating flat face: the polygon's support function in the follower's direction;
- swinging flat face: the tangent from the pivot to the polygon.

The base circle is the largest circle about the centre inside the profile (its least
distance from the centre); the follower's ``base_radius_mm`` must agree with it, since the
lift is measured from it and the cam's geometry (pressure angle, curvature) depends on it.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..geometry import polygon_edges
from ._follower import _in_keys

FLATTEN_MM = 1e-4
"""Largest distance of ezdxf's flattened polygon from a curved entity (arc, spline), mm."""
MAX_VERTICES = 200_000
"""Most polygon vertices of a profile: more is refused before the lift is computed."""
REACH_TOLERANCE_MM = 1e-3
"""How far a profile point may stay off the follower (a roller bridging a hollow, a flat
face bridging a dent) before the profile is not a cam for that follower."""
BASE_RADIUS_TOLERANCE_MM = 0.01
"""How closely the follower's ``base_radius_mm`` must match the profile's base circle."""
DEFAULT_POINTS = 720
"""Cam angles of the lift table by default (0.5 degree apart): the whole-cam table's
quintic spline through them follows the lift within 1e-7 mm on the example cams; a denser
table gains little there and costs the engine a piece per point."""
_CURVES = ("LWPOLYLINE", "POLYLINE", "SPLINE", "CIRCLE", "ELLIPSE")
_CHUNK = 128  # profile vertices checked at once against the roller centres' path
_ARC_BEZIERS = 128


ROTATIONS = ("ccw", "cw")
"""How the drawn cam turns: counter-clockwise (camjax's convention) or clockwise (read as
its mirror image in the follower's axis, ``x -> -x``, which turns counter-clockwise)."""
UNITS = {"mm": 4, "cm": 5, "m": 6, "in": 1, "ft": 2}
"""Units a drawing's lengths may be read in (``units=``, ``dxf_units``), by ``$INSUNITS`` code."""
SIZE_RANGE_MM = (1.0, 2000.0)
"""Base radii outside this range (mm) are warned of: a drawing read in the wrong unit."""


class DxfProfile(NamedTuple):
    """The closed profile read from a DXF file: polygon vertices (counter-clockwise, mm),
    the entity's layer and type, and its base radius (least distance from the centre).
    ``units``: how its lengths were read (``$INSUNITS`` and the scale to mm);
    ``rotation``: ``"ccw"`` or ``"cw"`` (mirrored to turn counter-clockwise)."""

    points: np.ndarray
    layer: str
    entity: str
    base_radius_mm: float
    units: str = "mm"
    rotation: str = "ccw"
    scale: float = 1.0

    def note(self, path) -> str:
        """One line saying what was read from the drawing and how."""
        turning = ("counter-clockwise (dxf_rotation = \"ccw\")" if self.rotation == "ccw" else
                   "clockwise (dxf_rotation = \"cw\": read as its mirror image, x -> -x)")
        return (f"the cam's profile is the {self.entity} on layer {self.layer!r} of {Path(path).name}, "
                f"lengths {self.units}, the cam turning {turning}; base radius {self.base_radius_mm:.6g} mm")

    def size_warning(self, path) -> str | None:
        """A warning where the base radius is implausible for a cam in mm: the wrong unit."""
        lo, hi = SIZE_RANGE_MM
        if lo <= self.base_radius_mm <= hi:
            return None
        other = [n for n, code in UNITS.items() if n != "mm" or self.scale != 1.0]
        return (f"{Path(path).name}: the profile's base radius is {self.base_radius_mm:.6g} mm "
                f"(lengths {self.units}), outside {lo:g} to {hi:g} mm: if the drawing is in another "
                f"unit, say which with dxf_units (one of {', '.join(other)})")


def read_dxf_profile(path, layer: str | None = None, *, rotation: str = "ccw",
                     units: str | None = None) -> DxfProfile:
    """The cam profile in a DXF file: the one closed curve (on ``layer`` if given; else the
    one on layer ``PROFILE``, ``write_dxf``'s, if there is one; else the only closed curve,
    unless it lies on a layer named for a pitch curve).

    Lengths are scaled to mm from the unit the file's ``$INSUNITS`` names (unitless: mm),
    or from ``units`` (a key of ``UNITS``) where given.  ``rotation="cw"``: the drawn cam
    turns clockwise, and its mirror image in the follower's axis (``x -> -x``) is read.
    Several closed curves with no way to choose between them, none, a file that is not a
    DXF, or a profile that does not enclose the cam centre are each a one-line
    ``ValueError`` naming the file.
    """
    import ezdxf

    if rotation not in ROTATIONS:
        raise ValueError(f"rotation must be one of {', '.join(map(repr, ROTATIONS))}, got {rotation!r}")
    if units is not None and units not in UNITS:
        raise ValueError(f"units must be one of {', '.join(map(repr, UNITS))}, got {units!r}")
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: DXF file not found")
    try:
        doc = ezdxf.readfile(path)
    except (OSError, ezdxf.DXFError, UnicodeDecodeError, ValueError) as error:
        detail = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise ValueError(f"{path}: not a readable DXF file ({detail})") from None
    scale, unit_text = _to_mm(doc, units)
    entities = [e for e in doc.modelspace() if e.dxftype() in _CURVES]
    if layer is not None:
        entities = [e for e in entities if e.dxf.layer == layer]
    closed, open_ = [], 0
    for entity in entities:
        points = _flattened(entity, path)
        if points is None:
            open_ += 1
        else:
            closed.append((entity, points))
    where = f" on layer {layer!r}" if layer is not None else ""
    if not closed:
        found = f"{open_} open curve(s)" if open_ else f"no {', '.join(_CURVES)}"
        raise ValueError(f"{path}: no closed profile{where} ({found}); the cam's profile is one closed "
                         "polyline, spline, circle or ellipse")
    if len(closed) > 1 and layer is None:
        on_profile = [c for c in closed if c[0].dxf.layer == "PROFILE"]
        closed = on_profile or closed
    if len(closed) == 1 and layer is None and "PITCH" in str(closed[0][0].dxf.layer).upper():
        raise ValueError(f"{path}: the only closed curve, a {closed[0][0].dxftype()} on layer "
                         f"{closed[0][0].dxf.layer!r}, looks like a pitch curve (the roller centre's "
                         "path), not the profile; give its layer (dxf_layer, layer=) to read it as the profile")
    if len(closed) > 1:
        names = ", ".join(f"{e.dxftype()} on layer {e.dxf.layer!r}" for e, _ in closed)
        hint = ("draw the profile alone on its own layer" if layer is not None else
                "choose one by its layer (dxf_layer in a program file, layer= in Python)")
        raise ValueError(f"{path}: {len(closed)} closed curves{where} ({names}); {hint}")
    entity, points = closed[0]
    points = points * scale
    if rotation == "cw":
        points = points * np.array([-1.0, 1.0])
    if _signed_area(points) < 0:
        points = points[::-1]
    name = f"{path}: {entity.dxftype()} on layer {entity.dxf.layer!r}"
    if not _encloses_origin(points):
        raise ValueError(f"{name} does not enclose the cam centre (the origin): the profile must be "
                         "drawn about the cam's centre")
    radius = float(np.min(np.hypot(points[:, 0], points[:, 1])))
    return DxfProfile(points, str(entity.dxf.layer), entity.dxftype(), radius, unit_text, rotation, scale)


def _to_mm(doc, units: str | None) -> tuple[float, str]:
    """The scale from the drawing's lengths to mm, and how it was found (for the note)."""
    import ezdxf.units

    code = doc.header.get("$INSUNITS", 0)
    try:
        name = ezdxf.units.unit_name(code)
    except (KeyError, IndexError, TypeError):
        name = "unknown"
    said = f"$INSUNITS = {code} ({name})"
    if units is not None:
        scale = float(ezdxf.units.conversion_factor(UNITS[units], ezdxf.units.MM))
        return scale, f"in {units} (dxf_units; the file's {said})" + (f", times {scale:g} to mm" if scale != 1 else "")
    if code in (0, ezdxf.units.MM):
        return 1.0, f"in mm ({said})"
    try:
        scale = float(ezdxf.units.conversion_factor(code, ezdxf.units.MM))
    except (KeyError, IndexError, TypeError, ZeroDivisionError):
        return 1.0, f"in mm ({said}, a unit camjax does not know)"
    return scale, f"scaled from {said} by {scale:g} to mm"


def _flattened(entity, path: Path) -> np.ndarray | None:
    """The closed entity's polygon (last vertex not repeated), or ``None`` if it is open.

    A SPLINE is flattened by its own NURBS evaluation (``Spline.flattening``: a rational one
    as well); the rest through ``ezdxf.path``, whose arcs (circles, ellipses, bulges) become
    cubic Bezier curves first: 128 of them keep a circle within 1e-11 of its radius
    (ezdxf's default, one per quarter, strays 2.7e-4 of it)."""
    import ezdxf.path

    where = f"{path}: {entity.dxftype()} on layer {entity.dxf.layer!r}"
    try:
        if entity.dxftype() == "SPLINE":
            vertices, flagged = entity.flattening(FLATTEN_MM), bool(entity.closed)
        else:
            curve = ezdxf.path.make_path(entity, segments=_ARC_BEZIERS)
            if len(curve) == 0:
                return None
            vertices, flagged = curve.flattening(FLATTEN_MM), False
        points = []
        for v in vertices:
            points.append((v.x, v.y))
            if len(points) > MAX_VERTICES:
                raise ValueError(f"{where} flattens to more than {MAX_VERTICES:,} points")
    except (TypeError, AttributeError, ZeroDivisionError, ezdxf.DXFError) as error:
        raise ValueError(f"{where} cannot be read as a curve ({error})") from None
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(points) < 2:
        return None
    size = float(np.max(np.ptp(points, axis=0)))
    if np.hypot(*(points[-1] - points[0])) <= 1e-9 * max(size, 1.0):
        points = points[:-1]
    elif not flagged:
        return None
    keep = np.r_[True, np.any(np.diff(points, axis=0) != 0, axis=1)]
    points = points[keep]
    return points if len(points) >= 3 else None


def _signed_area(p: np.ndarray) -> float:
    q = np.roll(p, -1, axis=0)
    return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


def _encloses_origin(p: np.ndarray) -> bool:
    """Winding number of the polygon about the origin is not zero (and the origin is off it)."""
    angle = np.arctan2(p[:, 1], p[:, 0])
    if np.min(np.hypot(p[:, 0], p[:, 1])) == 0:
        return False
    turn = np.sum(np.mod(np.diff(np.r_[angle, angle[0]]) + np.pi, 2 * np.pi) - np.pi)
    return abs(turn) > np.pi


def lift_from_dxf(path, follower, *, points: int = DEFAULT_POINTS, layer: str | None = None,
                  rotation: str = "ccw", units: str | None = None):
    """``(angle_deg, lift_mm)`` of the cam drawn in a DXF file under ``follower`` (a
    ``camjax.program.Follower``): ``points`` angles evenly over the turn from 0, the lift
    measured from the follower's base circle (for a swinging follower the arc of the roller
    centre or the face's swing times ``arm_mm``, as ``Program.lift``).

    The profile is ``read_dxf_profile``'s (``layer``, ``rotation``, ``units`` as there).  A ``ValueError`` naming the file says why a
    profile is not a cam for this follower: its base circle is not ``base_radius_mm``, the
    roller cannot reach a hollow narrower than itself, a flat face meets a non-convex
    profile, the follower does not reach the profile or its pivot lies inside it.
    """
    from ..laws import MAX_TABLE_POINTS, MIN_TABLE_POINTS
    from ._follower import _check_follower

    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or not MIN_TABLE_POINTS <= points <= MAX_TABLE_POINTS:
        raise ValueError(f"points must be a whole number of cam angles from {MIN_TABLE_POINTS} to {MAX_TABLE_POINTS:,}, "
                         f"got {points!r}")
    _check_follower(follower)
    cam = read_dxf_profile(path, layer, rotation=rotation, units=units)
    return _lift(cam, path, follower, int(points))


def _lift(cam: DxfProfile, path, follower, points: int):
    """The lift table of ``lift_from_dxf`` for a profile already read."""
    name = f"{Path(path)}: {cam.entity} on layer {cam.layer!r}"
    f = follower
    if abs(cam.base_radius_mm - f.base_radius_mm) > BASE_RADIUS_TOLERANCE_MM:
        raise ValueError(f"{name}: its base circle (least distance from the centre) is "
                         f"{cam.base_radius_mm:.6g} mm, not the follower's base_radius_mm = {f.base_radius_mm:g}; "
                         f"set base_radius_mm = {cam.base_radius_mm:.6g}")
    theta = np.radians(np.arange(int(points)) * 360.0 / int(points))
    q = cam.points
    follower_geometry = f.geometry
    try:  # its kind's own refusals (a swinging follower's pivot inside the profile)
        displacement, centres = follower_geometry.lift_from_polygon(q, theta)
    except ValueError as error:
        raise ValueError(f"{name}: follower.{_in_keys(str(error))}") from None
    lift = follower_geometry.lift_per_displacement * displacement
    missed = ~np.isfinite(lift)
    if missed.any():
        raise ValueError(f"{name}: the follower does not reach the profile at cam angle "
                         f"{np.degrees(theta[np.argmax(missed)]):.6g} deg; check offset_mm, arm_mm and pivot_mm")
    if f.flat_face:
        _check_convex(q, name, f.kind)
    else:
        _check_reach(q, centres, f.roller_radius_mm, name)
    # The polygon's chords dip inside the base circle by their sag (its vertices lie on it);
    # no follower goes inside the base circle of a true profile.
    return np.degrees(theta), np.maximum(lift, 0.0)


def _polar_deg(p: np.ndarray) -> float:
    return float(np.mod(np.degrees(np.arctan2(p[1], p[0])), 360.0))


def _check_reach(q: np.ndarray, centres: np.ndarray, r: float, name: str) -> None:
    """Every profile vertex lies a roller radius from the roller centres' path (the pitch
    polygon), within the tolerance plus the sag of its chords over a hollow (``h^2 / 8 r``)."""
    a, t, length = polygon_edges(centres)
    gap = np.empty(len(q))
    for i in range(0, len(q), _CHUNK):
        p = q[i:i + _CHUNK, None, :] - a[None]
        u = np.clip(np.sum(p * t[None], axis=-1), 0.0, length[None])
        foot = p - u[..., None] * t[None]
        gap[i:i + _CHUNK] = np.min(np.hypot(foot[..., 0], foot[..., 1]), axis=1) - r
    tolerance = REACH_TOLERANCE_MM + float(np.max(length)) ** 2 / (8 * r)
    worst = int(np.argmax(gap))
    if gap[worst] > tolerance:
        raise ValueError(f"{name}: the roller (roller_radius_mm = {r:g}) cannot reach the profile near "
                         f"{_polar_deg(q[worst]):.4g} deg on the cam (it stays {gap[worst]:.4g} mm off): a hollow "
                         "whose radius is smaller than the roller; use a smaller roller")


def _check_convex(q: np.ndarray, name: str, kind: str) -> None:
    """A flat face touches only the profile's convex hull: every vertex must lie on it."""
    from scipy.spatial import ConvexHull

    hull = q[ConvexHull(q).vertices]  # counter-clockwise
    a, t, _ = polygon_edges(hull)
    normal = np.stack([t[:, 1], -t[:, 0]], axis=-1)
    offset = np.sum(normal * a, axis=-1)
    depth = np.min(offset[None] - q @ normal.T, axis=1)
    worst = int(np.argmax(depth))
    if depth[worst] > REACH_TOLERANCE_MM:
        raise ValueError(f"{name}: the profile is not convex near {_polar_deg(q[worst]):.4g} deg on the cam "
                         f"({depth[worst]:.4g} mm inside its convex hull): a {kind} follower's face cannot "
                         "touch it")


def dxf_segments(path, follower, *, points: int = DEFAULT_POINTS, layer: str | None = None,
                 rotation: str = "ccw", units: str | None = None, smoothing_mm: float | None = None,
                 source: str | None = None):
    """A whole cam's segments from its drawing: ``turn_segments`` of ``lift_from_dxf``'s
    table, their record (``TableFit``) carrying what was read (``DxfProfile.note``), a
    warning where its size suggests the wrong unit, and the spacing check (for fewer than
    12 angles, against the drawing itself read at twice the angles)."""
    from ..laws import MIN_TABLE_POINTS as MIN_POINTS
    from ._table import turn_segments

    angle, lift = lift_from_dxf(path, follower, points=points, layer=layer, rotation=rotation, units=units)
    cam = read_dxf_profile(path, layer, rotation=rotation, units=units)
    # Too few angles for a fit through every other one (the tables' spacing check): the
    # drawing read at twice the angles instead.  Not always: between a polyline's vertices
    # the denser read follows its chords' kinks, and reads them as acceleration.
    denser = _lift(cam, path, follower, 2 * int(points)) if (int(points) + 1) // 2 < MIN_POINTS else None
    notes = (cam.note(path),) + tuple(w for w in (cam.size_warning(path),) if w)
    return turn_segments(angle, lift, smoothing_mm, str(path) if source is None else source, "",
                         denser=denser, notes=notes)
