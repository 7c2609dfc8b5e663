"""The studio's curves and exports against the program API: ``GET /api/curves`` is
``camjax.program.response`` at the same speed, and each export reads back as the program
(the CSV as ``profile``'s points, the DXF as the lift within its chord sag, the TOML as
the ``Program``).  No browser: the JSON interface as the page calls it."""

import csv
import io
import tomllib
import urllib.parse
import urllib.request

import numpy as np
import pytest
from helpers import call

from camjax import program as cp
from camjax.studio import studio

RPM = "400:1000:4"  # as tests/test_studio.py: the same analysis, compiled once
CURVE_RPM = 700.0  # above the feed cam's jump speed (about 660 rpm): the contact force dips
DXF_POINTS = 997  # vertices between the lift table's 0.5 degree angles, not on them


def fetch(url: str) -> bytes:
    with urllib.request.urlopen(url, timeout=600) as response:
        assert response.status == 200
        return response.read()


@pytest.fixture(scope="module")
def server():
    running = studio("feed", rpm=RPM)
    yield running
    running.stop()


@pytest.fixture(scope="module")
def feed():
    return cp.Program.load(cp.example_path("feed"))


def test_curves_are_the_response_at_the_same_speed(server, feed):
    status, curves = call(server.url + f"api/curves?rpm={CURVE_RPM:g}")
    assert status == 200 and curves["rpm"] == CURVE_RPM
    reference = cp.response(feed, CURVE_RPM)
    got = curves["response"]
    np.testing.assert_allclose(got["theta_deg"], reference["theta_deg"], rtol=0, atol=1e-9)
    for key in ("payload_acceleration_m_s2", "contact_force_n", "lift_mm"):
        exact = reference[key]
        peak = np.max(np.abs(exact))
        assert peak > 0, key
        np.testing.assert_allclose(got[key], exact, rtol=0, atol=1e-9 * peak, err_msg=key)
    # above the jump speed the contact force reaches zero somewhere: a real dynamic curve
    assert min(got["contact_force_n"]) < 0.05 * max(got["contact_force_n"])


def test_csv_export_is_the_profile(server, feed):
    text = fetch(server.url + "api/profile.csv?points=720").decode()
    rows = list(csv.DictReader(io.StringIO(text)))
    prof = cp.profile(feed, 720)
    assert len(rows) == 720
    column = {name: np.array([float(r[name]) for r in rows]) for name in rows[0]}
    # written to 10 significant digits
    np.testing.assert_allclose(column["theta_deg"], prof.theta_deg, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(column["lift_mm"], prof.lift_mm, rtol=1e-9, atol=1e-9)
    scale = np.max(np.abs(prof.profile))
    for name, points in (("pitch", prof.pitch), ("profile", prof.profile)):
        drawn = np.stack([column[f"{name}_x_mm"], column[f"{name}_y_mm"]], axis=1)
        np.testing.assert_allclose(drawn, points, rtol=0, atol=1e-9 * scale, err_msg=name)


def test_dxf_export_reads_back_as_the_lift(server, feed, tmp_path):
    path = tmp_path / "feed.dxf"
    path.write_bytes(fetch(server.url + f"api/profile.dxf?points={DXF_POINTS}"))
    drawn = cp.read_dxf_profile(path)
    assert drawn.layer == "PROFILE" and len(drawn.points) == DXF_POINTS
    angle, lift = cp.lift_from_dxf(path, feed.follower)
    # the drawing is a polygon of DXF_POINTS vertices on the profile: the true profile lies
    # within its chord sag of it (a twice as dense profile's midpoints against the chords)
    dense = cp.profile(feed, 2 * DXF_POINTS).profile
    a, mid, b = dense[0::2], dense[1::2], np.roll(dense[0::2], -1, axis=0)
    t = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    sag = float(np.max(np.abs(t[:, 0] * (mid - a)[:, 1] - t[:, 1] * (mid - a)[:, 0])))
    assert 1e-5 < sag < 1e-3
    error = np.max(np.abs(lift - feed.lift(angle)[0]))
    assert error <= 1.2 * sag, (error, sag)  # over the pressure angle's cosine


def test_toml_export_is_the_program(server, feed):
    text = fetch(server.url + "api/program.toml").decode()
    assert cp.Program.from_dict(tomllib.loads(text), base=cp.example_path("feed").parent) == feed
    # an edit is what the export then holds
    assert text == feed.to_toml()  # the one writer of a program file
    edited = text.replace("lift_mm = 8.0\n", "lift_mm = 7.0\n").replace(
        "lift_mm = -23.0\n", "lift_mm = -22.0\n"
    )
    assert edited != text
    assert call(server.url + "api/program?session=edit", edited)[0] == 200
    again = fetch(server.url + "api/program.toml?session=edit").decode()
    program = cp.Program.from_dict(tomllib.loads(again), base=cp.example_path("feed").parent)
    assert program != feed and program.segments[1].lift_mm == 7.0
