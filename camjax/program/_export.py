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

import numpy as np

from .. import geometry
from ._spec import Program


class Profile(NamedTuple):
    """Cam geometry over ``theta_deg`` (mm, degrees) with its undercut check."""

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


def follower_geometry(program: Program) -> geometry.AbstractRollerFollower:
    """The ``camjax.geometry`` follower of the program, in mm."""
    f = program.follower
    if f.kind == "swinging-roller":
        return geometry.SwingingRollerFollower(pivot_distance=f.pivot_mm, arm_length=f.arm_mm,
                                               roller_radius=f.roller_radius_mm, base_radius=f.base_radius_mm)
    return geometry.TranslatingRollerFollower(offset=f.offset_mm, roller_radius=f.roller_radius_mm,
                                              base_radius=f.base_radius_mm)


def profile(program: Program, points: int = 3600) -> Profile:
    """Pitch curve and profile at ``points`` cam angles evenly over the turn."""
    if int(points) < 8:
        raise ValueError(f"points must be at least 8, got {points}")
    theta_deg = np.arange(int(points)) * 360.0 / int(points)
    follower = follower_geometry(program)
    cam = geometry.cam_profile(follower, program.lift_curve(), np.radians(theta_deg))
    cut = geometry.undercut(cam, follower.roller_radius)
    outer = np.asarray(cam.outer)
    clearance = program.follower.groove_clearance_mm
    if clearance:  # the groove's other wall stands the clearance further off the pitch curve
        pitch = np.asarray(cam.pitch)
        outer = pitch + (outer - pitch) * (1.0 + clearance / program.follower.roller_radius_mm)
    return Profile(
        theta_deg=theta_deg,
        lift_mm=program.lift(theta_deg)[0],
        pitch=np.asarray(cam.pitch),
        profile=np.asarray(cam.inner),
        outer=outer,
        pressure_angle_deg=np.degrees(np.asarray(cam.pressure_angle)),
        pitch_radius_of_curvature_mm=np.asarray(cam.pitch_radius_of_curvature),
        profile_radius_of_curvature_mm=np.asarray(cam.inner_radius_of_curvature),
        undercut=np.asarray(cut.inner | (cut.outer if program.follower.form_closed else False)),
    )


def write_csv(prof: Profile, path, *, outer: bool = False) -> Path:
    """One row per cam angle: lift, pitch and profile points, pressure angle, curvature."""
    path = Path(path)
    header = ["theta_deg", "lift_mm", "pitch_x_mm", "pitch_y_mm", "profile_x_mm", "profile_y_mm",
              "pressure_angle_deg", "pitch_radius_of_curvature_mm", "profile_radius_of_curvature_mm", "undercut"]
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


def write_dxf(prof: Profile, path, *, outer: bool = False) -> Path:
    """DXF in mm: the profile as one closed polyline on layer PROFILE, the pitch curve on PITCH.

    A grooved cam's other wall goes on layer PROFILE_OUTER.
    """
    import ezdxf

    path = Path(path)
    doc = ezdxf.new(units=ezdxf.units.MM)
    msp = doc.modelspace()
    layers = {"PROFILE": prof.profile, "PITCH": prof.pitch}
    if outer:
        layers["PROFILE_OUTER"] = prof.outer
    for name, points in layers.items():
        doc.layers.add(name)
        msp.add_lwpolyline([tuple(map(float, p)) for p in points], close=True, dxfattribs={"layer": name})
    doc.saveas(path)
    return path


def check_profile(prof: Profile, roller_radius_mm: float) -> float:
    """Largest deviation (mm) of a profile point's distance from its pitch point from the roller radius."""
    distance = np.linalg.norm(prof.profile - prof.pitch, axis=1)
    return float(np.max(np.abs(distance - roller_radius_mm))) if distance.size else math.nan
