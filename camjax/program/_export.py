"""The cam's shape for the machine shop: pitch curve and profile by envelope, as CSV and DXF.

Lengths in mm, the cam centre at the origin, points in the cam-fixed frame of
``camjax.geometry`` (the cam turns counter-clockwise).  The profile is the flank the roller
rides (``inner``); a form-closed (grooved) cam also gets the other wall (``outer``).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import NamedTuple

import jax
import numpy as np

from .. import geometry
from ._program import Program


class Profile(NamedTuple):
    """Cam geometry over ``theta_deg`` (mm, degrees) with its undercut check.

    ``pressure_angle_deg`` has camjax's sign (``camjax.geometry``): negative on a rise of a
    translating roller follower without offset, the opposite of most textbooks.  Under a
    flat face ``pitch`` repeats the profile (there is no roller centre), the radii are the
    cam's and ``face_position_mm`` says where the contact lies along the face.
    """

    theta_deg: np.ndarray
    lift_mm: np.ndarray
    pitch: np.ndarray
    profile: np.ndarray
    outer: np.ndarray
    pressure_angle_deg: np.ndarray
    pitch_radius_of_curvature_mm: np.ndarray
    profile_radius_of_curvature_mm: np.ndarray
    undercut: np.ndarray
    """True where the roller cannot follow the pitch curve (the profile loops)."""
    face_position_mm: np.ndarray | None = None

    @property
    def flat_face(self) -> bool:
        return self.face_position_mm is not None


def _angle_ranges(theta_deg: np.ndarray, bad: np.ndarray) -> str:
    """``"a-b, c-d deg"`` of the runs of ``bad`` (sorted angles)."""
    runs, i = [], 0
    while i < bad.size:
        if bad[i]:
            j = i
            while j + 1 < bad.size and bad[j + 1]:
                j += 1
            runs.append(f"{theta_deg[i]:.2f}-{theta_deg[j]:.2f}" if j > i else f"{theta_deg[i]:.2f}")
            i = j + 1
        else:
            i += 1
    return ", ".join(runs) + " deg"


def shape(program: Program, theta_deg, side: str = "after"):
    """The cam's shape at ``theta_deg`` from the lift's one-sided jet (``Program.lift``):
    ``geometry.CamProfile`` for a roller, ``geometry.FlatProfile`` for a flat face.

    A flat face over a cusp (radius of curvature not positive) is a ``ValueError`` naming
    the angles: no face can cut that cam.
    """
    theta_deg = np.asarray(theta_deg, dtype=float)
    y, dy, ddy = program.lift(theta_deg, side)
    f = program.follower
    follower = f.geometry
    per_rad = 180.0 / math.pi
    scale = 1.0 / follower.lift_per_displacement
    jet = (np.radians(theta_deg), scale * y, scale * dy * per_rad, scale * ddy * per_rad**2)
    if not f.flat_face:
        return follower.profile_from_jet(*jet)
    flat = jax.tree.map(np.asarray, follower.profile_from_jet(*jet))
    cusp = ~(flat.radius_of_curvature > 0)
    if cusp.any():
        order = np.argsort(np.mod(theta_deg, 360.0))
        raise ValueError(f"follower.kind = {f.kind!r}: the cam's radius of curvature under the flat face "
                         f"(r_b + y + y'' for a translating one) is not positive at "
                         f"{_angle_ranges(np.mod(theta_deg, 360.0)[order], cusp[order])}: a cusp; "
                         "raise base_radius_mm or soften the motion")
    if not follower.on_face(flat.face_position).all():  # a swinging face's contact past its pivot
        raise ValueError("follower.pivot_mm: the contact point passes the pivot along the face; "
                         "move the pivot further out")
    return flat


MAX_PROFILE_POINTS = 100_000
"""Most profile points over a turn (0.0036 degrees apart, far below any machining step):
more is refused before any work (a million took minutes and 0.75 GB)."""


def profile(program: Program, points: int = 3600) -> Profile:
    """Pitch curve and profile at ``points`` cam angles evenly over the turn.

    The geometry comes from the lift's derivatives after each angle (``shape``), so a join
    where the acceleration steps gets the next segment's curvature, not an average.
    """
    if not 8 <= int(points) <= MAX_PROFILE_POINTS:
        raise ValueError(f"points must be from 8 to {MAX_PROFILE_POINTS:,}, got {points}")
    theta_deg = np.arange(int(points)) * 360.0 / int(points)
    lift_mm = program.lift(theta_deg)[0]
    cam = shape(program, theta_deg)
    if program.follower.flat_face:
        points_ = cam.profile
        return Profile(theta_deg=theta_deg, lift_mm=lift_mm, pitch=points_, profile=points_, outer=points_,
                       pressure_angle_deg=np.zeros_like(theta_deg),
                       pitch_radius_of_curvature_mm=cam.radius_of_curvature,
                       profile_radius_of_curvature_mm=cam.radius_of_curvature,
                       undercut=np.zeros(theta_deg.shape, bool), face_position_mm=cam.face_position)
    cut = geometry.undercut(cam, program.follower.roller_radius_mm)
    outer = np.asarray(cam.outer)
    clearance = program.follower.groove_clearance_mm
    if clearance:  # the groove's other wall stands the clearance further off the pitch curve
        pitch = np.asarray(cam.pitch)
        outer = pitch + (outer - pitch) * (1.0 + clearance / program.follower.roller_radius_mm)
    return Profile(
        theta_deg=theta_deg,
        lift_mm=lift_mm,
        pitch=np.asarray(cam.pitch),
        profile=np.asarray(cam.inner),
        outer=outer,
        pressure_angle_deg=np.degrees(np.asarray(cam.pressure_angle)),
        pitch_radius_of_curvature_mm=np.asarray(cam.pitch_radius_of_curvature),
        profile_radius_of_curvature_mm=np.asarray(cam.inner_radius_of_curvature),
        undercut=np.asarray(cut.inner | (cut.outer if program.follower.form_closed else False)),
    )


PRESSURE_ANGLE_COLUMN = "pressure_angle_deg_negative_on_rise"
"""The CSV's pressure-angle column, named for camjax's sign convention."""


def write_csv(prof: Profile, path, *, outer: bool = False) -> Path:
    """One row per cam angle: lift, pitch and profile points, pressure angle, curvature.

    The pressure-angle column is named for its sign, ``pressure_angle_deg_negative_on_rise``
    (camjax's: negative on a rise, the opposite of most textbooks; see ``Profile``).  Under a
    flat face: lift, profile point, the cam's radius of curvature and the face position.
    """
    path = Path(path)
    if prof.flat_face:
        return _write_flat_csv(prof, path)
    header = ["theta_deg", "lift_mm", "pitch_x_mm", "pitch_y_mm", "profile_x_mm", "profile_y_mm",
              PRESSURE_ANGLE_COLUMN, "pitch_radius_of_curvature_mm", "profile_radius_of_curvature_mm", "undercut"]
    if outer:
        header += ["outer_x_mm", "outer_y_mm"]
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for i in range(prof.theta_deg.size):
            row = [prof.theta_deg[i], prof.lift_mm[i], *prof.pitch[i], *prof.profile[i], prof.pressure_angle_deg[i],
                   prof.pitch_radius_of_curvature_mm[i], prof.profile_radius_of_curvature_mm[i], int(prof.undercut[i])]
            if outer:
                row += list(prof.outer[i])
            writer.writerow([f"{v:.10g}" if isinstance(v, float | np.floating) else v for v in row])
    return path


def _write_flat_csv(prof: Profile, path: Path) -> Path:
    header = ["theta_deg", "lift_mm", "profile_x_mm", "profile_y_mm", PRESSURE_ANGLE_COLUMN,
              "profile_radius_of_curvature_mm", "face_position_mm"]
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for i in range(prof.theta_deg.size):
            row = [prof.theta_deg[i], prof.lift_mm[i], *prof.profile[i], prof.pressure_angle_deg[i],
                   prof.profile_radius_of_curvature_mm[i], prof.face_position_mm[i]]
            writer.writerow([f"{float(v):.10g}" for v in row])
    return path


def write_dxf(prof: Profile, path, *, outer: bool = False) -> Path:
    """DXF in mm: the profile as one closed polyline on layer PROFILE, the pitch curve on PITCH.

    A grooved cam's other wall goes on layer PROFILE_OUTER; a flat face's cam has no PITCH.
    """
    import ezdxf

    path = Path(path)
    doc = ezdxf.new(units=ezdxf.units.MM)
    msp = doc.modelspace()
    layers = {"PROFILE": prof.profile} if prof.flat_face else {"PROFILE": prof.profile, "PITCH": prof.pitch}
    if outer:
        layers["PROFILE_OUTER"] = prof.outer
    for name, points in layers.items():
        doc.layers.add(name)
        msp.add_lwpolyline([tuple(map(float, p)) for p in points], close=True, dxfattribs={"layer": name})
    doc.saveas(path)
    return path
