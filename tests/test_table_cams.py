"""Lift tables (``law = "table"`` segments and whole cams from one periodic table) against
the closed-form laws and the analytic program they were sampled from."""

import dataclasses
import math
import re
import tomllib

import jax
import numpy as np
import pytest

from camjax import laws
from camjax.cli import main
from camjax.laws import TableLaw
from camjax.program import Program, analyse, design_warnings, example_path, segment_kinematics

RPM = [300.0, 1200.0]  # the indexer loses contact near 723 rpm: the jump speed lies between


def cycloid(tau):
    """The cycloidal rise in closed form: s, v, a, j."""
    w = 2 * math.pi
    return (tau - np.sin(w * tau) / w, 1 - np.cos(w * tau), w * np.sin(w * tau), w * w * np.cos(w * tau))


def test_table_law_is_the_exact_spline_of_a_sampled_cycloid():
    angle = np.arange(0.0, 100.0 + 1e-9, 0.5)
    law = TableLaw.fit(angle, 20.0 * cycloid(angle / 100.0)[0])
    tau = np.linspace(0.0, 1.0, 1001)
    s, v, a, j = (np.asarray(x) for x in law.evaluate(tau))
    exact = cycloid(tau)
    assert np.max(np.abs(s - exact[0])) < 1e-12
    assert np.max(np.abs(v - exact[1])) < 1e-9
    assert np.max(np.abs(a - exact[2])) < 1e-6 * exact[2].max()
    assert law.breakpoints() == tuple(angle[1:-1] / 100.0)
    peaks = law.peak_coefficients()
    assert peaks["Ca"] == pytest.approx(2 * math.pi, rel=1e-8)
    assert peaks["Cv"] == pytest.approx(2.0, rel=1e-10)
    assert law.end_state() == pytest.approx((0.0, 0.0, 0.0, 0.0), abs=1e-8)
    # The jerk and acceleration are the spline's own derivatives (finite differences of v).
    h = 1e-6
    t = np.array([0.1234, 0.5, 0.777])
    dv = (np.asarray(law.v(t + h)) - np.asarray(law.v(t - h))) / (2 * h)
    da = (np.asarray(law.a(t + h)) - np.asarray(law.a(t - h))) / (2 * h)
    assert np.asarray(law.a(t)) == pytest.approx(dv, abs=1e-6)
    assert np.asarray(law.j(t)) == pytest.approx(da, abs=1e-4)
    # Under jit, with the coefficients traced.
    scaled = jax.jit(lambda lw, x: lw.evaluate(x)[2])(law, tau)
    assert np.asarray(scaled) == pytest.approx(a, abs=1e-12)
    with pytest.raises(ValueError, match="lift table"):
        laws.get("table")


def test_table_law_saves_and_loads(tmp_path):
    angle = np.linspace(0.0, 90.0, 31)
    law = TableLaw.fit(angle, -15.0 * cycloid(angle / 90.0)[0])  # a return
    back = laws.load(laws.save(law, tmp_path / "law.json"))
    tau = np.linspace(0.0, 1.0, 77)
    assert isinstance(back, TableLaw)
    assert np.asarray(back.a(tau)) == pytest.approx(np.asarray(law.a(tau)), abs=1e-13)
    assert np.asarray(law.s(tau)) == pytest.approx(cycloid(tau)[0], abs=1e-6)


def test_segment_table_file_in_a_program(tmp_path):
    indexer = Program.load(example_path("indexer"))
    angle = np.arange(0.0, 100.0 + 1e-9, 0.5)
    lift = indexer.lift(angle)[0]
    rows = "\n".join(f"{float(a)!r};{float(y)!r}" for a, y in zip(angle, lift))
    (tmp_path / "rise.csv").write_text("angle_deg;lift_mm\n" + rows + "\n")
    text = example_path("indexer").read_text().replace('law = "cycloidal"', 'law = "table"\nfile = "rise.csv"', 1)
    (tmp_path / "cam.toml").write_text(text)
    program = Program.load(tmp_path / "cam.toml")
    theta = np.linspace(0.0, 360.0, 3601)
    for got, want in zip(program.lift(theta), indexer.lift(theta)):
        assert np.max(np.abs(got - want)) < 1e-7 * np.max(np.abs(want))
    row = segment_kinematics(program)[0]
    # Through every point of the table (the distance measured here, not the fit's report).
    assert np.max(np.abs(program.lift(angle)[0] - lift)) < 1e-12
    assert row["fit_deviation_mm"] < 1e-12
    assert row["peak_acceleration_mm_per_deg2"] == pytest.approx(20 * 2 * math.pi / 100**2, rel=1e-7)
    # Written back, the program reads the same (its table inline).
    again = Program.from_dict(tomllib.loads(program.to_toml()))
    assert np.max(np.abs(again.lift(theta)[2] - program.lift(theta)[2])) < 1e-12


@pytest.fixture(scope="module")
def indexer_and_table():
    indexer = Program.load(example_path("indexer"))
    angle = np.arange(0.0, 360.0, 0.5)
    return indexer, angle, indexer.lift(angle)[0], analyse(indexer, RPM, with_flight=False)


def _speeds(report, key):
    return np.array([getattr(s, key) for s in report.speeds])


def test_whole_cam_table_gives_the_cams_accelerations_forces_and_jump(indexer_and_table):
    indexer, angle, lift, want = indexer_and_table
    table = Program.from_table("indexer table", angle, lift, indexer.follower)
    got = analyse(table, RPM, with_flight=False)
    for key in ("max_payload_acceleration_m_s2", "max_kinematic_acceleration_m_s2",
                "min_contact_force_n", "max_contact_force_n"):
        assert _speeds(got, key) == pytest.approx(_speeds(want, key), rel=0.01), key
    assert got.jump_speed_rpm == pytest.approx(want.jump_speed_rpm, rel=0.005)
    assert np.max(np.abs(table.lift(angle)[0] - (lift - lift[0]))) < 1e-12  # through every point
    assert got.warnings == ()
    # Written back, it is one periodic table again (inline), and reads the same.
    text = table.to_toml()
    assert "[[segment]]" not in text
    again = Program.from_dict(tomllib.loads(text))
    theta = np.linspace(0.0, 360.0, 721)
    assert np.max(np.abs(again.lift(theta)[2] - table.lift(theta)[2])) < 1e-12


def _peak_acceleration(program):
    """The cam's largest |y''| over the turn (mm/deg^2), from its segments' exact peaks."""
    return max(row["peak_acceleration_mm_per_deg2"] for row in segment_kinematics(program))


def _band_distance(program, angle, lift):
    """The largest distance of a whole-cam table's fit from its points.  The program's lift
    is the fit less its value at 0 (unknown here): the least largest distance over that
    constant, half the spread of the points' residuals, which the fit's own cannot be below."""
    residual = lift - program.lift(angle)[0]
    return 0.5 * float(np.ptp(residual))


def test_noisy_table_needs_smoothing(indexer_and_table):
    indexer, angle, lift, want = indexer_and_table
    noisy = lift + np.random.default_rng(7).normal(0.0, 0.001, lift.size)  # a micrometre of noise
    exact = _peak_acceleration(indexer)

    # Interpolated, the noise's second derivative swamps the cam's acceleration.
    raw = Program.from_table("raw", angle, noisy, indexer.follower)
    assert _peak_acceleration(raw) > 3 * exact
    assert any("scatter" in w and "smoothing_mm" in w for w in design_warnings(raw))

    # Within three sigma of the points: the cam's acceleration within 10%, and no warning.
    smooth = Program.from_table("3 sigma", angle, noisy, indexer.follower, smoothing_mm=0.003)
    assert _peak_acceleration(smooth) == pytest.approx(exact, rel=0.10)
    assert design_warnings(smooth) == []

    # Within the noise's sigma: the follower's own accelerations, forces and jump speed hold
    # (the train filters the noise), the cam's acceleration is still the noise's (the
    # largest points lie three sigma out, and the fit must reach within one of them).
    sigma = Program.from_table("sigma", angle, noisy, indexer.follower, smoothing_mm=0.001)
    assert _peak_acceleration(sigma) > 2 * exact
    got = analyse(sigma, RPM, with_flight=False)
    for key in ("max_payload_acceleration_m_s2", "min_contact_force_n", "max_contact_force_n"):
        assert _speeds(got, key) == pytest.approx(_speeds(want, key), rel=0.10), key
    assert got.jump_speed_rpm == pytest.approx(want.jump_speed_rpm, rel=0.03)
    distance = _band_distance(sigma, angle, noisy)
    assert 0.001 * (1 - 1e-6) <= distance <= 0.001 * (1 + 1e-9)  # the band is used, not exceeded
    assert any("scatter" in w for w in got.warnings)


def test_noise_inside_the_band_gives_the_cams_acceleration(indexer_and_table):
    # Uniform noise of +/-1 um and smoothing_mm its bound: the cam itself lies within the
    # band, so the smoothest spline within it is no rougher than the cam.
    indexer, angle, lift, want = indexer_and_table
    noisy = lift + np.random.default_rng(11).uniform(-0.001, 0.001, lift.size)
    smooth = Program.from_table("band", angle, noisy, indexer.follower, smoothing_mm=0.001)
    assert _band_distance(smooth, angle, noisy) <= 0.001 * (1 + 1e-9)
    assert _peak_acceleration(smooth) == pytest.approx(_peak_acceleration(indexer), rel=0.10)
    got = analyse(smooth, RPM, with_flight=False)
    key = "max_kinematic_acceleration_m_s2"
    assert _speeds(got, key) == pytest.approx(_speeds(want, key), rel=0.10)


def _gauss(edges):
    """3-point Gauss nodes and weights on each interval of ``edges`` (exact for ``j^2`` of a quintic)."""
    nodes, weights = np.polynomial.legendre.leggauss(3)
    a, b = np.asarray(edges)[:-1], np.asarray(edges)[1:]
    x = (0.5 * (a + b)[:, None] + 0.5 * (b - a)[:, None] * nodes).ravel()
    return x, (0.5 * (b - a)[:, None] * weights).ravel()


def _jerk_energy(spline, knots):
    """``int j^2`` of a scipy ``BSpline`` over ``knots``."""
    x, w = _gauss(knots)
    return float(np.sum(w * spline.derivative(3)(x) ** 2))


def test_table_fit_is_scipys_spline_and_the_smoothest_within_the_band():
    from scipy.interpolate import BSpline, make_interp_spline
    from scipy.optimize import lsq_linear

    # Interpolating: scipy's quintic through the same points with v = a = 0 at both ends
    # (its knots are the points, as the table law's).
    angle = np.linspace(0.0, 100.0, 41)
    tau = angle / 100.0
    lift = 20.0 * cycloid(tau)[0] + 0.3 * np.sin(7 * tau)
    rest = [(1, 0.0), (2, 0.0)]
    reference = make_interp_spline(tau, lift, k=5, bc_type=(rest, rest))
    law = TableLaw.fit(angle, lift)
    t = np.linspace(0.0, 1.0, 2001)
    rise = lift[-1] - lift[0]
    for order in range(4):
        got = rise * np.asarray(law.evaluate(t)[order]) + (lift[0] if order == 0 else 0.0)
        want = reference.derivative(order)(t) if order else reference(t)
        assert np.max(np.abs(got - want)) < 1e-9 * np.max(np.abs(want)), order
    # A whole turn: scipy's periodic quintic.
    indexer = Program.load(example_path("indexer"))
    turn = np.arange(0.0, 360.0, 2.0)
    table = Program.from_table("t", turn, indexer.lift(turn)[0], indexer.follower)
    x = np.append(turn, 360.0)
    periodic = make_interp_spline(x, np.append(indexer.lift(turn)[0], indexer.lift(0.0)[0]), k=5, bc_type="periodic")
    theta = np.linspace(0.0, 360.0, 3601)
    for order in range(3):
        want = periodic.derivative(order)(theta) if order else periodic(theta)
        assert np.max(np.abs(table.lift(theta)[order] - want)) < 1e-9 * np.max(np.abs(want)), order

    # Smoothing: the least int j^2 within the band, against scipy's bounded-variable least
    # squares on the same quintic B-spline space.  Its variables are the spline's values at
    # the inner points (with the ends at rest at the first and last lift they fix the
    # spline), bounded by the band; the residual is sqrt(w) j at Gauss nodes.
    noisy = lift + np.random.default_rng(3).uniform(-0.05, 0.05, lift.size)
    band = 0.05
    smooth = TableLaw.fit(angle, noisy, smoothing_mm=band)
    rise = noisy[-1] - noisy[0]
    mine = noisy[0] + rise * np.asarray(smooth.s(tau))
    assert np.max(np.abs(mine - noisy)) <= band * (1 + 1e-9)
    knots = np.r_[[0.0] * 5, tau, [1.0] * 5]
    size = len(knots) - 6
    basis = [BSpline(knots, np.eye(size)[i], 5) for i in range(size)]

    def rows(x, order):
        return np.array([b.derivative(order)(x) if order else b(x) for b in basis]).T

    inner = slice(1, -1)
    to_coefficients = np.linalg.inv(np.concatenate([rows(tau[inner], 0)] + [rows(np.array([0.0, 1.0]), k) for k in range(3)]))
    ends = np.array([noisy[0], noisy[-1], 0, 0, 0, 0])
    nodes, weights = _gauss(tau)
    jerk = np.sqrt(weights)[:, None] * rows(nodes, 3)
    free, fixed = jerk @ to_coefficients[:, : size - 6], jerk @ to_coefficients[:, size - 6 :] @ ends
    result = lsq_linear(free, -fixed, bounds=(noisy[inner] - band, noisy[inner] + band), method="bvls", tol=1e-14)
    assert result.success, result.message
    spline = BSpline(knots, to_coefficients @ np.concatenate([result.x, ends]), 5)
    scipy_energy = _jerk_energy(spline, tau)
    mine_energy = rise**2 * _jerk_energy_of_law(smooth)
    assert mine_energy <= scipy_energy * (1 + 1e-6)
    assert mine_energy == pytest.approx(scipy_energy, rel=1e-6)
    assert np.max(np.abs(noisy[0] + rise * np.asarray(smooth.s(t)) - spline(t))) < 1e-4 * band
    # The band binds: a spline through the points has several times the energy.
    assert _jerk_energy(make_interp_spline(tau, noisy, k=5, bc_type=(rest, rest)), tau) > 3 * mine_energy


def _jerk_energy_of_law(law):
    """``int j^2`` of a table law over its knots."""
    x, w = _gauss(law.edges)
    return float(np.sum(w * np.asarray(law.j(x)) ** 2))


def test_sparse_table_warns():
    # A modified trapezoid (its jerk steps four times) at 7.7 degrees: too few points for its
    # acceleration; the same spacing resolves a cycloid.
    angle = np.linspace(0.0, 100.0, 14)
    law = TableLaw.fit(angle, 20.0 * np.asarray(laws.ModifiedTrapezoid().s(angle / 100.0)))
    assert law.peak_coefficients()["Ca"] > 1.01 * laws.ModifiedTrapezoid().Ca
    assert TableLaw.fit(angle, 20.0 * cycloid(angle / 100.0)[0]).fit_info.spacing_ratio == pytest.approx(1.0, abs=0.01)
    indexer = Program.load(example_path("indexer"))
    program = dataclasses.replace(indexer, segments=(dataclasses.replace(indexer.segments[0], law=law),
                                                     *indexer.segments[1:]))
    warnings = design_warnings(program)
    assert any("too sparse" in w for w in warnings), warnings
    assert law.fit_info.noise_mm == 0.0  # coarse, not noisy


def _program_with(tmp_path, csv: str, extra: str = "", whole: bool = False):
    (tmp_path / "lift.csv").write_text(csv)
    text = example_path("indexer").read_text()
    if whole:
        head, _, tail = text.partition("[follower]")
        text = f'[program]\nname = "t"\nfile = "lift.csv"\n{extra}\n[follower]' + tail
    else:
        text = text.replace('law = "cycloidal"\nlift_mm = 20',
                            f'law = "table"\nfile = "lift.csv"\n{extra}', 1)
    (tmp_path / "cam.toml").write_text(text)
    return tmp_path / "cam.toml"


def _rows(angle, lift, sep=","):
    return "".join(f"{float(a)!r}{sep}{float(y)!r}\n" for a, y in zip(angle, lift))


ANGLES = np.linspace(0.0, 100.0, 21)
LIFTS = 20.0 * cycloid(ANGLES / 100.0)[0]
GOOD = "angle_deg,lift_mm\n" + _rows(ANGLES, LIFTS)


@pytest.mark.parametrize(("csv", "extra", "whole", "message"), [
    ("angle_deg,lift_mm\n" + _rows(ANGLES[[0, 1, 3, 2, *range(4, 21)]], LIFTS), "", False,
     r"lift\.csv: line 5: angle_deg 10 does not increase \(the row before has 15\)"),
    ("angle_deg,lift_mm\n" + _rows(ANGLES[:4], LIFTS[:4]), "", False, r"lift\.csv: 4 point\(s\); a lift table needs at least 6"),
    (GOOD.replace("\n5.0,", "\nfive,"), "", False, r"lift\.csv: line 3: angle_deg \(column 1\) is not a number"),
    ("angle_deg;lift_mm\n" + _rows(ANGLES, LIFTS, ";").replace(".", ","), "", False,
     r"lift\.csv: line 2: angle_deg \(column 1\) is not a number \(decimals take '\.', not ','\)"),
    (GOOD, "smoothing_mm = 1e-18", False, r"lift\.csv: smoothing_mm = 1e-18 cannot be met: even the interpolating spline is .* mm from point \d+ \(angle_deg [\d.]+\)"),
    (GOOD, "lift_mm = 21", False, r"lift_mm = 21 but lift\.csv rises 20 mm"),
    ("angle,lift\n" + _rows(ANGLES, LIFTS), "", False, r"lift\.csv: line 1: the header must name the columns"),
    ("angle_deg,lift_mm\n" + _rows(np.linspace(0, 180, 19), np.sin(np.linspace(0, np.pi, 19))), "", True,
     r"lift\.csv: the table ends at 180 deg and does not close over the turn"),
    ("angle_deg,lift_mm\n" + _rows(np.arange(0, 360, 10), 1 + np.cos(np.radians(np.arange(0, 360, 10)))), "", True,
     r"lift\.csv: angle 0 must be on the base circle .* at 180 deg 0 mm"),
    ("angle_deg,lift_mm\n" + _rows(np.linspace(0, 360, 37), np.sin(np.linspace(0, np.pi, 37))), "", True,
     r"lift\.csv: the last angle_deg \(360\) must be below 360"),
])
def test_bad_tables_name_the_file_and_row(tmp_path, capsys, csv, extra, whole, message):
    path = _program_with(tmp_path, csv, extra, whole)
    with pytest.raises(ValueError, match=message) as caught:
        Program.load(path)
    assert "\n" not in str(caught.value)
    assert str(caught.value).startswith(str(path))
    assert main(["program", str(path), "--no-flight"]) == 2
    err = capsys.readouterr().err.strip()
    assert re.search(message, err) and "\n" not in err and "Traceback" not in err


def test_inline_points_and_their_errors():
    data = {"program": {"name": "p"},
            "segment": [{"law": "table", "angle_deg": 100.0, "points": [[float(a), float(y)] for a, y in zip(ANGLES, LIFTS)]},
                        {"angle_deg": 80.0},
                        {"law": "cycloidal", "lift_mm": -20.0, "angle_deg": 100.0},
                        {"angle_deg": 80.0}],
            "follower": {"mass_kg": 1.0, "stiffness_n_per_mm": 1000.0, "spring_rate_n_per_mm": 10.0}}
    program = Program.from_dict(data)
    assert program.segments[0].lift_mm == pytest.approx(20.0, abs=1e-12)
    data["segment"][0]["points"][4][1] = "x"
    with pytest.raises(ValueError, match=r"segment 1: points row 5: lift_mm 'x' is not a number"):
        Program.from_dict(data)
    data["segment"][0]["points"] = [[0, 0]] * 3
    with pytest.raises(ValueError, match=r"segment 1: 3 point\(s\)"):
        Program.from_dict(data)


def test_tab_separated_table_reads_as_the_comma_one(tmp_path):
    theta = np.linspace(0.0, 360.0, 721)
    comma = Program.load(_program_with(tmp_path, GOOD))
    tab = Program.load(_program_with(tmp_path, "angle_deg\tlift_mm\n" + _rows(ANGLES, LIFTS, "\t")))
    np.testing.assert_array_equal(tab.lift(theta)[0], comma.lift(theta)[0])
    space = _program_with(tmp_path, "angle_deg lift_mm\n" + _rows(ANGLES, LIFTS, " "))
    with pytest.raises(ValueError, match=r"lift\.csv: line 1: the header must name the columns angle_deg and "
                                         r"lift_mm \(found 1 name\(s\), no tab, ';' or ',' separates its names\)"):
        Program.load(space)
    semicolon = _program_with(tmp_path, "angle;lift\n" + _rows(ANGLES, LIFTS, ";"))
    with pytest.raises(ValueError, match=r"\(found 2 name\(s\), read as semicolon-separated\); missing angle_deg"):
        Program.load(semicolon)
