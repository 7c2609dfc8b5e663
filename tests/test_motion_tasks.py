"""Motion tasks beyond rest-to-rest (VDI 2143): boundary polynomials, constant velocity,
"match" and the join checks, against closed forms, dense sampling, finite differences and
a scipy solve of the physical equation of motion."""

import json
import math
import tomllib

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import FOLLOWER, follower_constants, scipy_periodic_deflection

from camjax import laws
from camjax.cli import main
from camjax.program import (
    EndState,
    Follower,
    Program,
    Segment,
    SteadyState,
    example_path,
    node_contact_force,
    profile,
)


def hermite_coefficients(degree, start, end):
    """Ascending coefficients of the polynomial with s(0) = 0, s(1) = 1 and the given
    derivatives at both ends: the full (degree + 1)-square system, solved directly."""
    n = degree + 1
    rows, rhs = [], []
    for at, values in ((0.0, [0.0, *start]), (1.0, [1.0, *end])):
        for order, value in enumerate(values):
            row = [math.perm(k, order) * at ** (k - order) if k >= order else 0.0 for k in range(n)]
            rows.append(row)
            rhs.append(value)
    return np.linalg.solve(np.array(rows), np.array(rhs))


# -- laws ----------------------------------------------------------------------------------


def test_rest_to_rest_boundary_polynomials_are_345_and_4567():
    quintic, septic = laws.BoundaryPolynomial(degree=5), laws.BoundaryPolynomial(degree=7)
    assert np.asarray(quintic.coefficients()) == pytest.approx([0, 0, 0, 10, -15, 6], abs=1e-12)
    assert np.asarray(septic.coefficients()) == pytest.approx([0, 0, 0, 0, 35, -84, 70, -20], abs=1e-11)
    c = quintic.peak_coefficients()
    assert (c["Cv"], c["Ca"], c["Cj"]) == pytest.approx((1.875, 10 / math.sqrt(3), 60.0), rel=1e-12)
    c = septic.peak_coefficients()
    assert (c["Cv"], c["Ca"], c["Cj"]) == pytest.approx((35 / 16, 7.5132, 52.5), abs=1e-4)
    assert c["Cj"] == pytest.approx(52.5, rel=1e-12)


def test_peaks_of_a_quintic_whose_leading_coefficient_cancels():
    """A quintic between constant velocities whose lift is the natural ``(v0 + v1) beta / 2``
    (``v0 + v1 = 2`` normalised) is a cubic whose ``tau^5`` term cancels to round-off: its
    peaks and displacement range against dense sampling of the polynomial solved directly
    (the derivative's roots were spoilt by the round-off term: Ca 1.8e-15 for 1.364)."""
    law = laws.get("polynomial5:0.5454545454545454,0.0,1.4545454545454546,0.0")
    assert law.Ca == pytest.approx(15 / 11, rel=1e-12)  # a = 6 (v1 - v0) tau (1 - tau): 15/11 at 1/2
    tau = np.linspace(0.0, 1.0, 200_001)
    for v0 in (0.5454545454545454, 0.1, 0.3, 0.7, 1.0 / 3.0, 0.9, 1.25, 1.9, -0.4):
        c = hermite_coefficients(5, [v0, 0.0], [2.0 - v0, 0.0])
        law = laws.BoundaryPolynomial(v0=v0, v1=2.0 - v0)
        peaks = law.peak_coefficients()
        poly = np.polynomial.Polynomial(c)
        for order, key in ((1, "Cv"), (2, "Ca"), (3, "Cj")):
            assert peaks[key] == pytest.approx(np.abs(poly.deriv(order)(tau)).max(), rel=1e-9, abs=1e-12)
        s = poly(tau)
        assert law.displacement_range() == pytest.approx((s.min(), s.max()), abs=1e-9)


@pytest.mark.parametrize("degree", [5, 7])
def test_boundary_polynomial_meets_its_end_states(degree):
    rng = np.random.default_rng(degree)
    v0, a0, j0, v1, a1, j1 = rng.normal(scale=3.0, size=6)
    if degree == 5:
        j0 = j1 = 0.0
    law = laws.BoundaryPolynomial(v0=v0, a0=a0, v1=v1, a1=a1, j0=j0, j1=j1, degree=degree)
    m = (degree + 1) // 2
    expected = hermite_coefficients(degree, [v0, a0, j0][: m - 1], [v1, a1, j1][: m - 1])
    assert np.asarray(law.coefficients()) == pytest.approx(expected, abs=1e-10)
    s, v, a, j = (np.asarray(x) for x in law.evaluate(np.array([0.0, 1.0])))
    assert s == pytest.approx([0, 1], abs=1e-12) and v == pytest.approx([v0, v1], abs=1e-11)
    assert a == pytest.approx([a0, a1], abs=1e-10)
    if degree == 7:
        assert j == pytest.approx([j0, j1], abs=1e-9)
    # Peaks: exact for concrete values, and the traced path (sampled and polished) agrees.
    tau = np.linspace(0.0, 1.0, 400001)
    dense = [np.abs(np.polynomial.Polynomial(expected).deriv(k)(tau)).max() for k in (1, 2, 3)]
    exact = law.peak_coefficients()
    assert [exact["Cv"], exact["Ca"], exact["Cj"]] == pytest.approx(dense, rel=1e-9)
    traced = jax.jit(lambda law: jnp.stack([law.Cv, law.Ca, law.Cj]))(law)
    assert np.asarray(traced) == pytest.approx(dense, rel=1e-9)
    low, high = law.displacement_range()
    s_dense = np.polynomial.Polynomial(expected)(tau)
    assert (low, high) == pytest.approx((s_dense.min(), s_dense.max()), abs=1e-9)


def test_boundary_polynomial_is_differentiable_in_its_end_states():
    def peak(values, tau=0.37):
        law = laws.BoundaryPolynomial(*values, degree=7)
        s, v, a, _ = law.evaluate(tau)
        return s + 0.1 * v + 0.01 * a + law.Ca

    values = jnp.array([0.4, -1.0, 1.3, 0.2, 0.5, -0.3])  # v0, a0, v1, a1, j0, j1
    grad = np.asarray(jax.grad(peak)(values))
    h = 1e-6
    for k in range(6):
        step = np.zeros(6)
        step[k] = h
        fd = (peak(values + step) - peak(values - step)) / (2 * h)
        assert grad[k] == pytest.approx(float(fd), rel=1e-6, abs=1e-8)


def test_constant_velocity_and_names():
    law = laws.get("constant-velocity")
    s, v, a, j = (np.asarray(x) for x in law.evaluate(np.array([0.0, 0.25, 1.0])))
    assert s.tolist() == [0.0, 0.25, 1.0] and v.tolist() == [1.0] * 3 and not a.any() and not j.any()
    assert law.peak_coefficients() == {"Cv": 1.0, "Ca": 0.0, "Cj": 0.0}
    # The named lists hold rest-to-rest laws only; the laws in motion are found by name.
    assert "constant-velocity" not in laws.names() and "double-harmonic" not in laws.names()
    assert [law.name for law in laws.standard_laws()] == laws.names()[:len(laws.standard_laws())]
    poly = laws.BoundaryPolynomial(v0=0.5, a0=-1.25, v1=2.0, a1=0.0, j0=3.0, j1=0.0, degree=7)
    assert laws.get(poly.name) == poly
    assert laws.from_dict(laws.to_dict(poly)) == poly
    with pytest.raises(ValueError, match="polynomial degree must be 5 or 7, got 6"):
        laws.BoundaryPolynomial(degree=6)
    with pytest.raises(ValueError, match="degree-5 polynomial cannot meet a jerk"):
        laws.BoundaryPolynomial(j0=1.0, degree=5)
    with pytest.raises(ValueError, match=r"polynomial5:V0,A0,V1,A1 takes 4 numbers after the colon \(boundary values"):
        laws.get("polynomial5:1,2")


# -- program file --------------------------------------------------------------------------


def feed_from_python() -> Program:
    return Program("feed", (
        Segment(30),
        Segment.polynomial(50, 8, 5),
        Segment.constant_velocity(60, 18),
        Segment.polynomial(55, -3, 7, "match", EndState(-0.4, 0.0, 0.0)),
        Segment.polynomial(105, -23, 5),
        Segment(60),
    ), Follower(**{**FOLLOWER, "offset_mm": 0}))


@pytest.fixture(scope="module")
def feed():
    return Program.load(example_path("feed"))


def test_feed_example_joins_and_segments(feed):
    assert feed == feed_from_python()
    assert Program.from_dict(tomllib.loads(feed.to_toml())) == feed
    joins = feed.joins()
    assert [(j.before, j.after) for j in joins] == [(1, 2), (2, 3), (3, 4), (4, 5), (5, 6), (6, 1)]
    assert [j.state for j in joins] == ["R", "G", "G", "G", "R", "R"]
    assert all(j.continuity == "C2" for j in joins)
    assert [j.velocity_mm_per_deg for j in joins] == pytest.approx([0, 0.3, 0.3, -0.4, 0, 0], abs=1e-12)
    # Segment 2 starts at rest and meets the working stroke's 18/60 mm/deg: in normalised
    # units v1 = 0.3 * 50 / 8.
    poly = feed.segments[1].law
    assert np.asarray(poly.coefficients()) == pytest.approx(
        hermite_coefficients(5, [0, 0], [0.3 * 50 / 8, 0]), abs=1e-12)
    # Segment 5 starts at segment 4's given end.
    assert float(feed.segments[4].law.v0) == pytest.approx(-0.4 * 105 / -23, rel=1e-14)
    from camjax.program import segment_kinematics

    rows = segment_kinematics(feed)
    assert [r["kind"] for r in rows] == ["dwell", "polynomial", "constant-velocity", "polynomial",
                                         "polynomial", "dwell"]
    assert rows[2]["peak_velocity_mm_per_deg"] == pytest.approx(0.3, rel=1e-15)
    assert rows[2]["peak_acceleration_mm_per_deg2"] == 0.0
    # Segment 4 leaves the working stroke still rising, so it overshoots its start.
    assert [r["overshoot"] for r in rows] == [False, False, False, True, False, False]
    tau = np.linspace(0, 1, 200001)
    for row, seg in zip(rows, feed.segments):
        if seg.moving:
            _, v, a, j = (np.asarray(x) for x in seg.law.evaluate(tau))
            h, beta = abs(seg.lift_mm), seg.angle_deg
            assert row["peak_velocity_mm_per_deg"] == pytest.approx(h * np.abs(v).max() / beta, rel=1e-9)
            assert row["peak_acceleration_mm_per_deg2"] == pytest.approx(h * np.abs(a).max() / beta**2, rel=1e-8)
            assert row["peak_jerk_mm_per_deg3"] == pytest.approx(h * np.abs(j).max() / beta**3, rel=1e-8)


def test_acceleration_step_is_reported_and_a_velocity_jump_refused(tmp_path, capsys):
    follower = Follower(**FOLLOWER)
    program = Program("harmonic", (Segment(90), Segment(90, 10.0, laws.get("harmonic")),
                                   Segment(90, -10.0, laws.get("harmonic")), Segment(90)), follower)
    j = program.joins()
    # The harmonic rise ends decelerating as the harmonic return starts: a reversal (U), C2.
    assert [x.continuity for x in j] == ["C1", "C2", "C1", "C2"]
    assert [x.state for x in j] == ["R/U", "U", "U/R", "R"]
    a = math.pi**2 / 2 * 10 / 90**2  # harmonic: a(0) = pi^2 / 2 in normalised units
    assert j[0].acceleration_after_mm_per_deg2 == pytest.approx(a, rel=1e-12)
    with pytest.raises(ValueError, match=r"segments 1 and 2 meet at 180 deg with velocity 0 mm/deg "
                                         r"\(end of segment 1\) and 0.1 mm/deg \(start of segment 2\)"):
        Program("jump", (Segment(180), Segment.constant_velocity(18, 1.8),
                         Segment(162, -1.8, laws.get("cycloidal"))), follower)


FEED_TEXT = example_path("feed").read_text()

BAD = [
    (FEED_TEXT.replace('law = "constant-velocity"', 'law = "constant-speed"'),
     "segment 3: unknown law 'constant-speed'.*or \"polynomial\""),
    (FEED_TEXT.replace("degree = 7", "degree = 6"), "segment 4: degree must be 5 or 7, got 6"),
    (FEED_TEXT.replace("degree = 7", "degree = 7.0"), "segment 4: degree must be 5 or 7, got 7.0"),
    (FEED_TEXT.replace("velocity_mm_per_deg = -0.4", 'velocity_mm_per_deg = "fast"'),
     "segment 4: end.velocity_mm_per_deg must be a number, got 'fast'"),
    (FEED_TEXT.replace("jerk_mm_per_deg3 = 0.0", "jerk = 0.0"),
     r"segment 4: end: unknown field\(s\) jerk"),
    (FEED_TEXT.replace('end = { velocity_mm_per_deg = -0.4, acceleration_mm_per_deg2 = 0.0, '
                       'jerk_mm_per_deg3 = 0.0 }', 'end = "match"'),
     'segment 5: start = "match" meets segment 4\'s end = "match"'),
    (FEED_TEXT.replace("degree = 7", "degree = 5"),
     "segment 4: end.jerk_mm_per_deg3: a degree-5 polynomial meets velocity and acceleration only"),
    (FEED_TEXT.replace('end = "match"          # the working', 'end = "free"          # the working'),
     'segment 2: end must be "match" or a table'),
    (FEED_TEXT.replace('law = "constant-velocity"', 'law = "constant-velocity"\nstart = "match"'),
     'segment 3: start belong\\(s\\) to law = "polynomial"'),
    (FEED_TEXT.replace("lift_mm = -3\n", "lift_mm = 0\n").replace("lift_mm = -23", "lift_mm = -26"),
     "segment 4: a polynomial cannot meet its end states with lift_mm = 0"),
    (FEED_TEXT.replace("lift_mm = 18\nangle_deg = 60", "lift_mm = 24\nangle_deg = 60")
     .replace("lift_mm = -23", "lift_mm = -29")
     .replace('start = "match"\nend = { velocity', 'start = { velocity_mm_per_deg = 0.3 }\nend = { velocity'),
     r"segments 3 and 4 meet at 140 deg with velocity 0.4 mm/deg \(end of segment 3\) and 0.3 mm/deg"),
]


@pytest.mark.parametrize("text, message", BAD, ids=[m[:30] for _, m in BAD])
def test_bad_motion_tasks_give_clear_errors(tmp_path, capsys, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        Program.load(path)
    assert main(["program", str(path), "--no-flight"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("camjax program: error: ") and "\n" not in err


# -- dynamics ------------------------------------------------------------------------------


def numpy_lift(program):
    """Lift (mm) and its first two derivatives in degrees, from each segment's polynomial
    coefficients (numpy), for a program of dwells, boundary polynomials and constant velocity."""
    pieces = []
    for seg, start, y0 in zip(program.segments, program.start_deg, program.start_lift_mm):
        if not seg.moving:
            coef = np.array([0.0])
        elif isinstance(seg.law, laws.ConstantVelocity):
            coef = np.array([0.0, 1.0])
        else:
            coef = np.asarray(seg.law.coefficients())
        poly = np.polynomial.Polynomial(coef)
        pieces.append((start, seg.angle_deg, y0, seg.lift_mm, poly, poly.deriv(), poly.deriv(2)))

    def lift(theta):
        theta = theta % 360.0
        for start, beta, y0, h, s, v, a in pieces:
            if start <= theta < start + beta or start + beta >= 360.0:
                tau = (theta - start) / beta
                return y0 + h * s(tau), h * v(tau) / beta, h * a(tau) / beta**2
        raise AssertionError(theta)

    return lift, np.array([*program.start_deg, 360.0])


def scipy_periodic(program, rpm, times):
    """Periodic deflection e, e' (m, m/s) of the physical ODE by scipy shooting."""
    lift, edges_deg = numpy_lift(program)
    return scipy_periodic_deflection(program.follower, rpm, lift, edges_deg, times)


def test_feed_steady_state_and_constant_velocity_residual_match_scipy(feed):
    rpm = 600.0
    steady = SteadyState(feed, rpm)
    cycle = steady.cycle(rpm)
    period = 60.0 / rpm
    pick = np.arange(0, steady.grid.nodes.size - 1, 11)
    e, de = scipy_periodic(feed, rpm, steady.grid.nodes[pick] * period)
    tr = follower_constants(steady.program)
    force = tr.preload + tr.k * e + tr.c * de
    assert np.abs(cycle.contact_force_n[pick] - force).max() < 1e-7 * np.abs(force).max()
    # Residual vibration where the working stroke starts (80 deg): the free vibration
    # about the steady motion e_p = A + B t that the linear lift y0 + V t forces.
    assert feed.residual_segments() == [0, 2, 5]
    f = feed.follower
    omega = 2 * math.pi * f.natural_frequency_hz
    zeta = f.damping / (2 * f.mass_kg * omega)
    rate = 360.0 / period
    y0, velocity = 1e-3 * 8.0, 1e-3 * 0.3 * rate  # m, m/s
    forcing = f.spring_rate / f.mass_kg
    slope = forcing * velocity / omega**2
    offset = (forcing * y0 - 2 * zeta * omega * slope) / omega**2
    (e0,), (de0,) = scipy_periodic(feed, rpm, np.array([80.0 / rate]))
    omega_d = omega * math.sqrt(1 - zeta**2)
    free, free_rate = e0 - offset, de0 - slope
    amplitude = math.hypot(free, (free_rate + zeta * omega * free) / omega_d)
    residual = steady.summary([rpm]).residual_vibration_mm[0]
    assert residual[1] == pytest.approx(1e3 * amplitude, rel=1e-6)
    # Measured about the static point of the start's lift alone (a dwell's definition), the
    # amplitude would be far off: the steady motion's rate B matters.
    static = e0 - forcing * y0 / omega**2
    naive = math.hypot(static, (de0 + zeta * omega * static) / omega_d)
    assert abs(naive - amplitude) > 0.1 * amplitude  # 18% at 600 rpm
    # The dwells' residuals keep their definition (static point of the lift).
    assert residual[0] > 0 and residual[2] > 0


def test_feed_cli_every_output(tmp_path, capsys):
    assert main(["program", "feed", "--rpm", "600,900", "--format", "json", "--out", str(tmp_path)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["program"] == "feed"
    slow, fast = report["speeds"]
    assert len(slow["residual_vibration_mm"]) == 3 and len(slow["period_ratios"]) == 4
    assert fast["jump"] and fast["flights"] and fast["min_preload_n"] > slow["min_preload_n"] > 0
    assert [j["state"] for j in report["joins"]] == ["R", "G", "G", "G", "R", "R"]
    assert [s["overshoot"] for s in report["segments"]] == [False, False, False, True, False, False]
    for name in ("profile.csv", "profile.dxf", "response.csv", "summary.json", "svaj.png",
                 "contact_force.png", "sweep.png", "profile.png"):
        assert (tmp_path / name).stat().st_size > 0
    # Read back: the pitch curve at r_b + r_r + y(theta) from the lift alone (no offset), and
    # the summary's least contact force at or below every node force of response.csv.
    rows = np.genfromtxt(tmp_path / "profile.csv", delimiter=",", names=True)
    lift = Program.load(example_path("feed")).lift(rows["theta_deg"])[0]
    np.testing.assert_allclose(np.hypot(rows["pitch_x_mm"], rows["pitch_y_mm"]), 52.0 + lift, rtol=1e-9)
    h = np.genfromtxt(tmp_path / "response.csv", delimiter=",", names=True)
    for speed in (slow, fast):
        nodes = h["contact_force_n"][h["rpm"] == speed["rpm"]]
        assert speed["min_contact_force_n"] <= nodes.min() < speed["min_contact_force_n"] + 1.0
    assert main(["program", "feed", "--rpm", "600", "--no-flight"]) == 0
    table = capsys.readouterr().out
    assert "segment 4 polynomial" in table and "overshoots its ends" in table
    assert "join 3|4 at 140 deg: G C2, y' 0.3 mm/deg" in table
    assert main(["program", "feed", "--rpm", "600", "--format", "csv"]) == 0
    assert capsys.readouterr().out.splitlines()[1].startswith("600")


def test_feed_profile_follows_the_lift(feed):
    prof = profile(feed, 720)
    lift, _ = numpy_lift(feed)
    y = np.array([lift(t)[0] for t in prof.theta_deg])
    assert np.abs(np.linalg.norm(prof.pitch, axis=1) - (52.0 + y)).max() < 1e-9
    assert np.abs(np.linalg.norm(prof.profile - prof.pitch, axis=1) - 12.0).max() < 1e-9


def test_required_preload_gradient_in_a_join_velocity(feed):
    """d(required preload)/d(velocity at the join of segments 4 and 5), through the exact
    steady state (``node_contact_force``), against central finite differences."""
    rpm = jnp.array([500.0, 600.0, 700.0])
    seg4, seg5 = feed.segments[3], feed.segments[4]

    def required(velocity):
        law4 = laws.BoundaryPolynomial(seg4.law.v0, 0.0, velocity * seg4.angle_deg / seg4.lift_mm, 0.0,
                                       degree=7)
        law5 = laws.BoundaryPolynomial(velocity * seg5.angle_deg / seg5.lift_mm, 0.0, 0.0, 0.0, degree=5)
        force = node_contact_force(feed, rpm, {4: law4, 5: law5}, rpm_min=500.0)
        return jnp.max(feed.follower.preload_n - force)

    value = jax.jit(required)
    velocity = -0.4
    grad = float(jax.jit(jax.grad(required))(velocity))
    h = 1e-5
    fd = (float(value(velocity + h)) - float(value(velocity - h))) / (2 * h)
    assert grad == pytest.approx(fd, rel=1e-6)
    assert abs(grad) > 1.0  # N per mm/deg: the join's speed matters
    # At the program's own velocity the value is the SteadyState's required preload (nodes).
    force = SteadyState(feed, 500.0).summary(np.asarray(rpm)).min_contact_force_n
    assert float(value(velocity)) == pytest.approx(np.max(feed.follower.preload_n - force), rel=2e-3)


# -- design of a segment in motion ------------------------------------------------------------


@pytest.mark.parametrize("degree", [5, 7])
def test_corrected_polynomial_keeps_the_end_states_of_its_base(degree):
    base = laws.BoundaryPolynomial(v0=-1.5, a0=2.0, v1=0.7, a1=-3.0, j0=4.0 if degree == 7 else 0.0,
                                   j1=-1.0 if degree == 7 else 0.0, degree=degree)
    law = laws.CorrectedPolynomial(base, jnp.asarray(np.random.default_rng(1).normal(size=9)))
    ends = [np.asarray(x) for x in law.evaluate(np.array([0.0, 1.0]))]
    expected = [np.asarray(x) for x in base.evaluate(np.array([0.0, 1.0]))]
    for order in range(2 if degree == 5 else 3):
        assert ends[order] == pytest.approx(expected[order], abs=1e-9)
    assert float(law.Ca) > 0 and laws.from_dict(json.loads(json.dumps(laws.to_dict(law)))) == law


def test_design_a_segment_in_motion_keeps_its_joins(feed, tmp_path, capsys):
    """``--objective preload`` on the feed cam's reversal (a septic in motion at both ends):
    the designed law keeps every join's state and lowers the preload the program needs."""
    argv = ["design", "--program", str(example_path("feed")), "--segment", "4", "--rpm", "500:650",
            "--objective", "preload", "--knots", "8", "--steps", "200", "--quiet", "--out", str(tmp_path)]
    assert main(argv) == 0
    capsys.readouterr()
    new = Program.load(tmp_path / "program.toml")
    law = new.segments[3].law
    assert isinstance(law, laws.CorrectedPolynomial)
    for before, after in zip(feed.joins(), new.joins()):
        assert after.state == before.state and after.continuity == before.continuity
        assert after.velocity_mm_per_deg == pytest.approx(before.velocity_mm_per_deg, abs=1e-9)
    from camjax.program import MaxPreload

    objective = MaxPreload(feed, 4, 500.0, 650.0)
    assert objective.report(law) < 0.5 * objective.report(feed.segments[3].law)  # 94 N from 280 N
    argv[argv.index("preload")] = "ca-ct"
    assert main(argv) == 2
    assert "segment 4 starts or ends in motion: the ca-ct objective measures a rise from rest to rest" \
        in capsys.readouterr().err


def test_the_program_residual_objective_is_the_residual_vibration(feed):
    """``MaxProgramResidual`` trains on the residual modes of the whole program: their
    moduli at a training speed are the free vibration's amplitude at every dwell and
    constant-velocity start (0, 80 and 300 deg) from a scipy shooting solve of the physical
    equation (about the static point of a dwell's lift, 0 here; about the steady motion
    ``e_p = A + B t`` of the working stroke); its training value is a smooth maximum of them
    that tends to the largest as the sharpness grows."""
    from camjax.program import MaxProgramResidual

    objective = MaxProgramResidual(feed, 4, 500.0, 650.0)
    law = feed.segments[3].law
    features = np.asarray(objective.features(law))
    moduli = np.hypot(features[0], features[1]).sum(axis=-2)  # over the modes: one here
    rpm = float(objective.speeds()[0])
    f = feed.follower
    omega = 2 * math.pi * f.natural_frequency_hz
    zeta = f.damping / (2 * f.mass_kg * omega)
    omega_d = omega * math.sqrt(1 - zeta**2)
    rate = 360.0 * rpm / 60.0
    forcing = f.spring_rate / f.mass_kg
    slope = forcing * 1e-3 * 0.3 * rate / omega**2  # B: the stroke's 0.3 mm/deg
    offset = (forcing * 1e-3 * 8.0 - 2 * zeta * omega * slope) / omega**2  # A: from its 8 mm
    e, de = scipy_periodic(feed, rpm, np.array([0.0, 80.0, 300.0]) / rate)
    free = e - [0.0, offset, 0.0]
    free_rate = de - [0.0, slope, 0.0]
    amplitude = 1e3 * np.hypot(free, (free_rate + zeta * omega * free) / omega_d)
    np.testing.assert_allclose(moduli[0], amplitude, rtol=1e-6)
    top = float(np.max(moduli))
    assert float(objective.value(objective.features(law), 1.0, 2000.0)) == pytest.approx(top, rel=5e-3)
    assert float(objective.value(objective.features(law), 1.0, 8.0)) < top


def test_design_a_segment_in_motion_for_the_least_residual(feed, tmp_path):
    """``--objective residual`` on the feed cam's reversal lowers the largest residual
    vibration of the program over the speed range and keeps every join."""
    from camjax.program import MaxProgramResidual

    argv = ["design", "--program", str(example_path("feed")), "--segment", "4", "--rpm", "500:650",
            "--objective", "residual", "--knots", "8", "--steps", "100", "--quiet", "--out", str(tmp_path)]
    assert main(argv) == 0
    new = Program.load(tmp_path / "program.toml")
    for before, after in zip(feed.joins(), new.joins()):
        assert after.state == before.state
    objective = MaxProgramResidual(feed, 4, 500.0, 650.0)
    assert objective.report(new.segments[3].law) < objective.report(feed.segments[3].law)
