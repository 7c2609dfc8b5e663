"""A cam read back from its DXF profile: the lift it implies against closed forms (an
eccentric circle under each follower kind), against the program it was exported from
(within the polygon's chord sag), the re-imported cam's dynamics, and bad drawings."""

import dataclasses
import math
import re

import ezdxf
import numpy as np
import pytest
from ezdxf.math import rational_bspline_from_arc

from camjax.cli import main
from camjax.program import (
    Program,
    analyse,
    design_warnings,
    example_path,
    lift_from_dxf,
    profile,
    read_dxf_profile,
    segment_kinematics,
    write_dxf,
)

FEED = Program.load(example_path("feed"))
INDEXER = Program.load(example_path("indexer"))


def _drawing(path, shapes):
    """A DXF with ``shapes``: ``(layer, points, closed)`` polylines or ``(layer, centre, radius)`` circles."""
    doc = ezdxf.new(units=ezdxf.units.MM)
    msp = doc.modelspace()
    for layer, a, b in shapes:
        if isinstance(b, bool):
            msp.add_lwpolyline([tuple(map(float, p)) for p in a], close=b, dxfattribs={"layer": layer})
        else:
            msp.add_circle(a, b, dxfattribs={"layer": layer})
    doc.saveas(path)
    return path


# -- an eccentric circle: radius R about (c, 0), so the base radius is R - c -----------------
R, C = 45.0, 5.0


def _eccentric_lift(f, theta):
    """The closed-form lift of the eccentric circle (its centre at c (cos t, sin t) in the
    fixed frame) under follower ``f``, from the base circle ``R - c``."""
    centre = C * np.stack([np.cos(theta), np.sin(theta)])
    if f.kind == "translating-flat":
        return centre[1] + R - f.base_radius_mm
    if f.kind == "translating-roller":
        e, r = f.offset_mm, f.roller_radius_mm
        height = centre[1] + np.sqrt((R + r) ** 2 - (e - centre[0]) ** 2)
        return height - math.sqrt((f.base_radius_mm + r) ** 2 - e**2)
    d, l = f.pivot_mm, f.arm_mm
    to_centre = centre - np.array([[d], [0.0]])
    D, phi = np.hypot(*to_centre), np.mod(np.arctan2(to_centre[1], to_centre[0]), 2 * np.pi)  # near pi
    if f.kind == "swinging-flat":  # the upper tangent from the pivot, its normal 90 deg below
        beta = phi - np.arcsin(R / D) - math.pi / 2
        return l * (math.acos(f.base_radius_mm / d) - beta)
    rp, rc = f.base_radius_mm + f.roller_radius_mm, R + f.roller_radius_mm
    psi = phi - np.arccos((l**2 + D**2 - rc**2) / (2 * l * D))  # arm circle meets the roller-centre circle
    psi0 = math.pi - math.acos((d**2 + l**2 - rp**2) / (2 * d * l))
    return l * (psi0 - psi)


def _eccentric_drawing(path, entity):
    """The eccentric circle as a CIRCLE, a closed LWPOLYLINE of two half-circle bulges, or
    an exact rational SPLINE."""
    doc = ezdxf.new(units=ezdxf.units.MM)
    msp = doc.modelspace()
    if entity == "CIRCLE":
        msp.add_circle((C, 0.0), R)
    elif entity == "LWPOLYLINE":
        msp.add_lwpolyline([(C + R, 0.0, 0, 0, 1.0), (C - R, 0.0, 0, 0, 1.0)], format="xyseb", close=True)
    else:
        arc = rational_bspline_from_arc(center=(C, 0.0), radius=R, start_angle=0.0, end_angle=360.0)
        msp.add_rational_spline([tuple(p) for p in arc.control_points], arc.weights(), degree=arc.degree,
                                knots=arc.knots())
    doc.saveas(path)
    return path


@pytest.mark.parametrize("entity", ["CIRCLE", "LWPOLYLINE", "SPLINE"])
@pytest.mark.parametrize("follower", [
    dict(kind="translating-roller", offset_mm=8.0),
    dict(kind="swinging-roller", arm_mm=90.0, pivot_mm=110.0),
    dict(kind="translating-flat"),
    dict(kind="swinging-flat", arm_mm=100.0, pivot_mm=120.0),
], ids=lambda f: f["kind"])
def test_eccentric_circle_lift_is_the_closed_form(tmp_path, follower, entity):
    path = _eccentric_drawing(tmp_path / "ecc.dxf", entity)
    assert read_dxf_profile(path).entity == entity
    f = dataclasses.replace(FEED.follower, base_radius_mm=R - C, **follower)
    angle, lift = lift_from_dxf(path, f, points=720)
    assert angle[0] == 0.0 and angle[-1] == pytest.approx(359.5)
    exact = _eccentric_lift(f, np.radians(angle))
    assert np.ptp(exact) > 9.0 * (f.arm_mm / 110.0 if f.swinging else 1.0)  # a real stroke
    # ezdxf flattens the circle within 1e-4 mm (its vertices on it); the lift follows within
    # that (over the pressure angle's cosine, below 1.2 here)
    np.testing.assert_allclose(lift, exact, atol=1.2e-4)


def _chord_sag(program, points):
    """The largest distance of the true profile from the chords of a ``points``-vertex
    export: the midpoints of a twice as dense export measured against each chord."""
    dense = profile(program, 2 * points).profile
    a, mid, b = dense[0::2], dense[1::2], np.roll(dense[0::2], -1, axis=0)
    t = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    off = mid - a
    return float(np.max(np.abs(t[:, 0] * off[:, 1] - t[:, 1] * off[:, 0])))


ROUND_TRIPS = {
    "feed, offset roller": (FEED, dict(offset_mm=10.0)),
    "indexer, swinging roller": (INDEXER, dict(kind="swinging-roller", arm_mm=98.0, pivot_mm=110.0)),
    "feed, translating flat": (FEED, dict(kind="translating-flat", base_radius_mm=60.0)),
    "indexer, swinging flat": (INDEXER, dict(kind="swinging-flat", base_radius_mm=80.0, arm_mm=100.0, pivot_mm=200.0)),
}


@pytest.mark.parametrize("case", ROUND_TRIPS)
def test_exported_profile_reads_back_within_its_chord_sag(tmp_path, case):
    base, change = ROUND_TRIPS[case]
    program = dataclasses.replace(base, follower=dataclasses.replace(base.follower, **change))
    points = 997  # its vertices fall between the table's 0.5 degree angles, not on them
    path = write_dxf(profile(program, points), tmp_path / "cam.dxf")
    angle, lift = lift_from_dxf(path, program.follower)
    error = np.max(np.abs(lift - program.lift(angle)[0]))
    sag = _chord_sag(program, points)
    # The polygon lies within its sag of the profile, so the follower stands within the sag
    # (over the pressure angle's cosine) of where the true cam puts it; 4e-4 mm at 997 points.
    assert error <= 1.2 * sag
    assert 1e-5 < sag < 1e-3


@pytest.fixture(scope="module")
def feed_dxf(tmp_path_factory):
    return write_dxf(profile(FEED), tmp_path_factory.mktemp("dxf") / "feed.dxf")


def test_round_trip_dynamics_and_program_file(feed_dxf):
    # The default export (3600 points) has a vertex at every 0.5 degree of the table: the
    # lift is the cam's to the table spline's interpolation error.
    cam = Program.from_dxf("feed", feed_dxf, FEED.follower)
    angle = np.linspace(0.0, 360.0, 2001)[:-1]
    np.testing.assert_allclose(cam.lift(angle)[0], FEED.lift(angle)[0], atol=1e-6)
    rpm = [600.0]
    mine, theirs = (analyse(p, rpm, with_flight=False).speeds[0] for p in (cam, FEED))
    for key in ("max_contact_force_n", "min_contact_force_n"):
        assert getattr(mine, key) == pytest.approx(getattr(theirs, key), rel=1e-4)
    # The program file: the path relative to it, the base radius taken from the profile.
    text = example_path("feed").read_text().partition("[follower]")[2].replace("base_radius_mm = 40\n", "")
    assert "base_radius_mm" not in text
    (feed_dxf.parent / "cam.toml").write_text('[program]\nname = "f"\ndxf = "feed.dxf"\n[follower]' + text)
    loaded = Program.load(feed_dxf.parent / "cam.toml")
    assert loaded.follower.base_radius_mm == pytest.approx(40.0, abs=1e-9)
    np.testing.assert_allclose(loaded.lift(angle)[0], FEED.lift(angle)[0], atol=1e-6)


def _slotted(depth=3.0, width=4.0):
    """A 40 mm base circle with a convex lobe ``40 + 5 (1 - cos 2 phi)`` over its upper half
    and a radial slot ``width`` wide, ``depth`` deep cut into the lobe's top at 90 degrees."""
    phi = np.radians(np.arange(0.0, 360.0, 0.5))
    radius = 40.0 + np.where(phi < np.pi, 5.0 * (1.0 - np.cos(2.0 * phi)), 0.0)
    ring = radius[:, None] * np.stack([np.cos(phi), np.sin(phi)], axis=1)
    left = ring[:, 0] > width / 2
    right = (ring[:, 0] < -width / 2) | (ring[:, 1] < 0)
    first = int(np.argmin(left))  # the first point inside the slot's width
    slot = [(width / 2, 50.0 - depth), (-width / 2, 50.0 - depth)]
    return np.concatenate([ring[:first], slot, ring[first:][right[first:]]])


def test_bad_drawings_are_one_line_errors_naming_the_file(tmp_path):
    f = FEED.follower
    cases = [
        (tmp_path / "empty.dxf", [], f, r"empty\.dxf: no closed profile \(no LWPOLYLINE"),
        (tmp_path / "open.dxf", [("0", [(40, 0), (0, 40), (-40, 0)], False)], f,
         r"open\.dxf: no closed profile \(1 open curve\(s\)\)"),
        (tmp_path / "two.dxf", [("A", (0, 0), 40.0), ("B", (0, 0), 50.0)], f,
         r"two\.dxf: 2 closed curves \(CIRCLE on layer 'A', CIRCLE on layer 'B'\); choose one by its layer"),
        (tmp_path / "off.dxf", [("0", (100, 0), 10.0)], f, r"off\.dxf: CIRCLE on layer '0' does not enclose the cam centre"),
        (tmp_path / "base.dxf", [("0", (0, 0), 35.0)], f,
         r"base\.dxf: CIRCLE on layer '0': its base circle .* is 35 mm, not the follower's base_radius_mm = 40; "
         r"set base_radius_mm = 35"),
        (tmp_path / "slot.dxf", [("0", _slotted(), True)], f,
         r"slot\.dxf: .* the roller \(roller_radius_mm = 12\) cannot reach the profile near (87|92)\.\d+ deg on the cam "
         r"\(it stays [23]\.\d+ mm off\)"),
        (tmp_path / "flat.dxf", [("0", _slotted(), True)], dataclasses.replace(f, kind="translating-flat"),
         r"flat\.dxf: .* the profile is not convex near (87|92)\.\d+ deg on the cam \(2\.9\d+ mm inside its convex hull\)"),
    ]
    for path, shapes, follower, message in cases:
        _drawing(path, shapes)
        with pytest.raises(ValueError, match=message) as caught:
            lift_from_dxf(path, follower, points=360)
        assert "\n" not in str(caught.value), path
    ecc = _eccentric_drawing(tmp_path / "ecc.dxf", "CIRCLE")
    inside = dataclasses.replace(f, kind="swinging-flat", base_radius_mm=R - C, arm_mm=100.0, pivot_mm=45.0)
    with pytest.raises(ValueError, match=r"ecc\.dxf: CIRCLE on layer '0': follower\.pivot_mm: the pivot \(45\) lies "
                                         r"within the profile's largest radius \(50\); move the pivot out"):
        lift_from_dxf(ecc, inside, points=72)
    # its base circle faces the follower (on +y) at 270 degrees, not at 0
    with pytest.raises(ValueError, match=r"ecc\.dxf: .*angle 0 must be on the base circle.*; in the drawing, the "
                                         r"follower stands at angle 0 .*turn the profile"):
        Program.from_dxf("ecc", ecc, dataclasses.replace(f, base_radius_mm=R - C), points=72)
    (tmp_path / "text.dxf").write_text("angle_deg,lift_mm\n0,0\n")
    with pytest.raises(ValueError, match=r"text\.dxf: not a readable DXF file"):
        lift_from_dxf(tmp_path / "text.dxf", f)
    # several curves: a layer picks one; camjax's own export is read from its PROFILE layer
    assert read_dxf_profile(tmp_path / "two.dxf", layer="B").base_radius_mm == pytest.approx(50.0, abs=1e-6)
    with pytest.raises(ValueError, match=r"two\.dxf: no closed profile on layer 'C'"):
        read_dxf_profile(tmp_path / "two.dxf", layer="C")
    with pytest.raises(ValueError, match=r"points must be a whole number of cam angles from 6 to 4,000, got 3"):
        lift_from_dxf(tmp_path / "two.dxf", f, points=3, layer="A")


def test_exported_dxf_is_read_from_its_profile_layer(feed_dxf):
    cam = read_dxf_profile(feed_dxf)  # PROFILE and PITCH are both closed
    assert cam.layer == "PROFILE" and cam.base_radius_mm == pytest.approx(40.0, abs=1e-9)
    # the export runs clockwise (the cam turns counter-clockwise); the reader turns it round
    np.testing.assert_allclose(cam.points, profile(FEED).profile[::-1], atol=1e-12)


@pytest.mark.parametrize(("extra", "dxf", "message"), [
    ("", "missing.dxf", r"\[program\] dxf: .*missing\.dxf: DXF file not found"),
    ("dxf_points = 2", "cam.dxf", r"\[program\] dxf: dxf_points must be a whole number"),
    ('file = "lift.csv"', "cam.dxf", r"\[program\] dxf: the cam's profile replaces a lift table"),
    ("", "cam.dxf", r"\[program\] dxf: .*cam\.dxf: CIRCLE on layer '0': its base circle .* set base_radius_mm = 35"),
])
def test_program_file_dxf_errors_exit_2_with_one_line(tmp_path, capsys, extra, dxf, message):
    _drawing(tmp_path / "cam.dxf", [("0", (0, 0), 35.0)])
    follower = example_path("feed").read_text().partition("[follower]")[2]
    path = tmp_path / "prog.toml"
    path.write_text(f'[program]\nname = "p"\ndxf = "{dxf}"\n{extra}\n[follower]{follower}')
    with pytest.raises(ValueError, match=message) as caught:
        Program.load(path)
    assert str(caught.value).startswith(str(path)) and "\n" not in str(caught.value)
    assert main(["program", str(path), "--no-flight"]) == 2
    err = capsys.readouterr().err.strip()
    assert re.search(message, err) and "\n" not in err and "Traceback" not in err


def _polyline_drawing(path, points, layer="PROFILE", **new):
    doc = ezdxf.new(**new)
    doc.modelspace().add_lwpolyline([tuple(map(float, p)) for p in points], close=True, dxfattribs={"layer": layer})
    doc.saveas(path)
    return path


def test_drawing_says_its_unit_layer_and_rotation(tmp_path):
    angle = np.arange(0.0, 360.0, 0.5)
    # ezdxf.new()'s default $INSUNITS is metres: a cam drawn in mm reads a thousand times too large
    metres = _polyline_drawing(tmp_path / "m.dxf", profile(FEED).profile)
    with pytest.raises(ValueError, match=r"m\.dxf: LWPOLYLINE on layer 'PROFILE': its base circle .* is 40000 mm, .*"
                                         r"lengths that large suggest a drawing read in the wrong unit .*dxf_units"):
        Program.from_dxf("m", metres, FEED.follower)
    big = Program.from_dxf("m", metres, dataclasses.replace(FEED.follower, base_radius_mm=40000.0), points=72)
    said = design_warnings(big)
    assert said[0] == ("the cam's profile is the LWPOLYLINE on layer 'PROFILE' of m.dxf, lengths scaled from "
                       "$INSUNITS = 6 (Meters) by 1000 to mm, the cam turning counter-clockwise "
                       '(dxf_rotation = "ccw"); base radius 40000 mm')
    assert any("base radius is 40000 mm" in w and "outside 1 to 2000 mm" in w for w in said)
    cam = Program.from_dxf("m", metres, FEED.follower, units="mm")
    np.testing.assert_allclose(cam.lift(angle)[0], FEED.lift(angle)[0], atol=1e-6)
    assert "lengths in mm (dxf_units; the file's $INSUNITS = 6 (Meters))" in design_warnings(cam)[0]

    # A cam turning clockwise, drawn so (the mirror image of camjax's export): read as drawn
    # it is the reversed cam; with rotation="cw" it is the cam.
    offset = dataclasses.replace(FEED, follower=dataclasses.replace(FEED.follower, offset_mm=10.0))
    mirrored = _polyline_drawing(tmp_path / "cw.dxf", profile(offset).profile * [-1.0, 1.0], units=ezdxf.units.MM)
    _, as_drawn = lift_from_dxf(mirrored, offset.follower)
    assert np.max(np.abs(as_drawn - offset.lift(angle)[0])) > 1.0
    _, clockwise = lift_from_dxf(mirrored, offset.follower, rotation="cw")
    np.testing.assert_allclose(clockwise, offset.lift(angle)[0], atol=1e-6)
    cam = Program.from_dxf("cw", mirrored, offset.follower, rotation="cw", points=72)
    assert "the cam turning clockwise (dxf_rotation = \"cw\": read as its mirror image, x -> -x)" in design_warnings(cam)[0]
    with pytest.raises(ValueError, match=r"rotation must be one of 'ccw', 'cw', got 'left'"):
        lift_from_dxf(mirrored, offset.follower, rotation="left")

    # Only the pitch curve left (write_dxf's PITCH layer): not read as the profile unless chosen
    pitch = _polyline_drawing(tmp_path / "pitch.dxf", profile(FEED).pitch, layer="PITCH", units=ezdxf.units.MM)
    with pytest.raises(ValueError, match=r"pitch\.dxf: the only closed curve, a LWPOLYLINE on layer 'PITCH', looks "
                                         r"like a pitch curve .*give its layer"):
        read_dxf_profile(pitch)
    assert read_dxf_profile(pitch, layer="PITCH").base_radius_mm == pytest.approx(52.0, abs=1e-6)


def test_drawing_read_at_too_few_angles_warns(feed_dxf):
    exact = max(r["peak_acceleration_mm_per_deg2"] for r in segment_kinematics(FEED))
    coarse = Program.from_dxf("coarse", feed_dxf, FEED.follower, points=10)
    peak = max(r["peak_acceleration_mm_per_deg2"] for r in segment_kinematics(coarse))
    assert peak < 0.8 * exact  # the 36 degree spacing misses the peak
    said = design_warnings(coarse)
    assert any("too sparse for its acceleration: against the drawing read at 20 angles" in w for w in said), said
    fine = Program.from_dxf("fine", feed_dxf, FEED.follower)
    assert max(r["peak_acceleration_mm_per_deg2"] for r in segment_kinematics(fine)) == pytest.approx(exact, rel=1e-4)
    assert design_warnings(fine)[1:] == []  # the note on what was read, and nothing else


@pytest.mark.parametrize(("key", "message"), [
    ('dxf_rotation = "left"', r"\[program\] dxf_rotation must be one of 'ccw', 'cw' \(how the drawn cam turns\), got 'left'"),
    ('dxf_units = "furlong"', r"\[program\] dxf_units must be one of 'mm', 'cm', 'm', 'in', 'ft' .*got 'furlong'"),
])
def test_program_file_dxf_options_are_checked(tmp_path, key, message):
    _drawing(tmp_path / "cam.dxf", [("0", (0, 0), 40.0)])
    follower = example_path("feed").read_text().partition("[follower]")[2]
    path = tmp_path / "prog.toml"
    path.write_text(f'[program]\nname = "p"\ndxf = "cam.dxf"\n{key}\n[follower]{follower}')
    with pytest.raises(ValueError, match=message):
        Program.load(path)
