"""Whole cam programs against independent references (closed forms, ct_curve, scipy)."""

import json
import math

import numpy as np
import pytest
from helpers import (
    FOLLOWER,
    follower_constants,
    program_lift,
    scipy_deflection,
    scipy_periodic_deflection,
    two_cycloids,
)
from scipy.integrate import solve_ivp

import camjax
from camjax import laws
from camjax.cli import main
from camjax.program import (
    Follower,
    MaxPreload,
    Program,
    Segment,
    SteadyState,
    analyse,
    example_path,
    flight,
    flights,
    jump_speed_rpm,
    profile,
    startup,
    with_law,
    write_dxf,
)


def cycloid_lift(theta_deg):
    """Lift (mm) and its first two derivatives in degrees of ``two_cycloids``, in numpy."""
    theta = np.mod(theta_deg, 360.0)
    y, dy, ddy = np.zeros_like(theta), np.zeros_like(theta), np.zeros_like(theta)
    for start, lift in ((0.0, 20.0), (180.0, -20.0)):
        tau = (theta - start) / 100.0
        inside = (tau >= 0) & (tau < 1)
        t = tau[inside]
        y[inside] = (0.0 if lift > 0 else 20.0) + lift * (t - np.sin(2 * np.pi * t) / (2 * np.pi))
        dy[inside] = lift * (1 - np.cos(2 * np.pi * t)) / 100.0
        ddy[inside] = lift * 2 * np.pi * np.sin(2 * np.pi * t) / 100.0**2
    y[(theta >= 100) & (theta < 180)] = 20.0
    return y, dy, ddy


@pytest.fixture(scope="module")
def cam():
    return two_cycloids()


@pytest.fixture(scope="module")
def solver(cam):
    return SteadyState(cam, 300.0)


def test_example_loads_and_matches_the_constructor():
    program = Program.load(example_path())
    assert [s.angle_deg for s in program.segments] == [100, 80, 100, 80]
    assert program.segments[2].law.name == laws.get("modified-sine").name
    assert Program.from_dict(__import__("tomllib").loads(program.to_toml())) == program
    assert camjax.Program is Program


def test_one_rise_and_dwell_reproduces_ct_curve():
    """A 10-degree rise, then 170 degrees of damped dwell (the vibration decays to 2e-8
    before the mirrored return): max |x''| / (h Ca / t_r^2) is Ct at n = f_n t_r."""
    law = laws.get("cycloidal")
    follower = Follower(mass_kg=1.0, stiffness_n_per_mm=1000.0, damping_ratio=0.05, base_radius_mm=40.0,
                        roller_radius_mm=10.0)  # form-closed: no spring, the forcing is y'' alone
    program = Program("rise", (Segment(10, 10.0, law), Segment(170), Segment(10, -10.0, law), Segment(170)),
                      follower)
    n = 3.3
    rpm = 60.0 * follower.natural_frequency_hz * (10 / 360) / n
    reference = camjax.ct_curve(law, np.array([n]), damping=0.05)
    scale = 1e-3 * 10.0 * float(law.Ca) / (60.0 / rpm * 10 / 360) ** 2  # h Ca / t_r^2 in m/s^2
    report = analyse(program, [rpm], with_flight=False).speeds[0]
    assert report.max_payload_acceleration_m_s2 / scale == pytest.approx(float(reference.ct[0]), rel=1e-6)
    assert report.max_kinematic_acceleration_m_s2 == pytest.approx(scale, rel=1e-12)
    assert report.period_ratios == pytest.approx([n, n], rel=1e-12)
    # Residual vibration after the rise: the displacement amplitude A of the free vibration at
    # the dwell's start; w^2 A is its acceleration envelope there, w |q| / sqrt(1 - zeta^2)
    # (Ca h / t_r^2 units) with q = e' - conj(lambda) e from the end state of the rise (scipy);
    # R, the largest acceleration in the dwell, lies below it (each crest is sqrt(1 - zeta^2)
    # of the envelope, decayed to its time).
    omega = 2 * np.pi * follower.natural_frequency_hz
    residual = omega**2 * 1e-3 * report.residual_vibration_mm[0] / scale
    w, zeta = 2 * np.pi * n, 0.05
    end = solve_ivp(lambda t, z: [z[1], float(law.a(t)) - w * w * z[0] - 2 * zeta * w * z[1]], (0.0, 1.0),
                    [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
    lam = complex(-zeta * w, w * math.sqrt(1 - zeta**2))
    envelope = w * abs(end[1] - lam.conjugate() * end[0]) / math.sqrt(1 - zeta**2) / float(law.Ca)
    assert residual == pytest.approx(envelope, rel=1e-6)
    assert float(reference.residual[0]) < math.sqrt(1 - zeta**2) * envelope
    assert report.jump is False and report.min_preload_n is None


def test_start_up_converges_to_the_periodic_steady_state(cam, solver):
    rpm = 600.0
    steady = solver.cycle(rpm)
    s, accel, force = startup(cam, rpm, 12, steady=solver)
    nodes = solver.grid.nodes.size - 1
    first = np.abs(force[:nodes] - steady.contact_force_n[:-1]).max()
    last = np.abs(force[-nodes:] - steady.contact_force_n[:-1]).max()
    assert first > 1.0  # the start from rest is visibly off the steady state
    assert last < 1e-8 * np.abs(steady.contact_force_n).max()
    assert np.abs(accel[-nodes:] - steady.payload_acceleration_m_s2[:-1]).max() < 1e-8 * np.abs(accel).max()


def test_start_up_against_a_scipy_solve_from_rest(cam):
    """``startup``'s contact force over the first two turns from rest (``e = e' = 0`` on the
    base circle) against scipy's integration of ``m x'' = k (y - x) + c (y' - x') - k_s x``:
    ``F_c = F_0 + k e + c e'`` at every tenth node."""
    rpm = 700.0
    s, accel, force = startup(cam, rpm, 2)
    pick = np.arange(0, s.size, 10)
    e, de = scipy_deflection(cam.follower, rpm, program_lift(cam), [0, 100, 180, 280, 360],
                             s[pick] * 60.0 / rpm)
    f = cam.follower
    expected = f.preload_n + f.stiffness * e + f.damping * de
    assert np.abs(force[pick] - expected).max() < 1e-7 * np.abs(expected).max()
    # x'' = (k e + c e' - k_s x) / m with x = y - e.
    y = cam.lift(np.mod(360.0 * s[pick], 360.0))[0] * 1e-3
    payload = (f.stiffness * e + f.damping * de - f.spring_rate * (y - e)) / f.mass_kg
    assert np.abs(accel[pick] - payload).max() < 1e-7 * np.abs(payload).max()


def test_jump_speed_against_a_scipy_steady_state():
    """The built-in indexer's jump speed: the least contact force of the periodic steady
    state from scipy (``m x'' = k (y - x) + c (y' - x') - k_s x`` integrated over a turn from
    three starts, then the fixed point, rtol 1e-9; ``F_c = F_0 + k e + c e'`` on 20,000
    instants) is positive 1 rpm below the reported speed and negative 1 rpm above it (the
    least force moves by about 1.4 N per rpm there)."""
    program = Program.load(example_path())
    speed = jump_speed_rpm(SteadyState(program, 300.0), 300.0, 900.0)  # what analyse reports
    assert 300.0 < speed < 900.0
    f = program.follower
    least = []
    for rpm in (speed - 1.0, speed + 1.0):
        times = np.linspace(0.0, 60.0 / rpm, 20000, endpoint=False)
        e, de = scipy_periodic_deflection(f, rpm, program_lift(program), [0, 100, 180, 280, 360], times,
                                          rtol=1e-9)
        least.append(np.min(f.preload_n + f.stiffness * e + f.damping * de))
    assert least[0] > 0 > least[1], least


def _shooting(program, rpm, times):
    """Periodic deflection of ``two_cycloids`` by scipy shooting."""
    def lift(theta):
        return tuple(x[0] for x in cycloid_lift(np.array([theta])))

    return scipy_periodic_deflection(program.follower, rpm, lift, [0, 100, 180, 280, 360], times)


def test_periodic_steady_state_matches_a_scipy_shooting_solve(cam, solver):
    rpm = 900.0
    steady = solver.cycle(rpm)
    period = 60.0 / rpm
    pick = np.arange(0, solver.grid.nodes.size - 1, 7)
    e_scipy, de_scipy = _shooting(cam, rpm, solver.grid.nodes[pick] * period)
    tr = follower_constants(solver.program)
    force = tr.preload + tr.k * e_scipy + tr.c * de_scipy
    assert np.abs(steady.contact_force_n[pick] - force).max() < 1e-7 * np.abs(force).max()


def test_min_preload_tends_to_the_rigid_closed_form():
    rpm = 600.0
    rate = 360.0 * rpm / 60.0
    y, _, ddy = cycloid_lift(np.linspace(0, 360, 360001))
    m, ks = 1.5, 10e3
    rigid = max(0.0, np.max(-(m * 1e-3 * ddy * rate**2 + ks * 1e-3 * y)))
    gaps = []
    for k in (1e5, 4e5):
        program = two_cycloids(stiffness_n_per_mm=k, damping_ratio=0.2)
        preload = analyse(program, [rpm], with_flight=False).speeds[0].min_preload_n
        gaps.append(abs(preload - rigid) / rigid)
    assert rigid > 50
    # The quasi-static deflection m y'' / k makes the gap fall as 1/k (measured: 2.4e-2,
    # 2.4e-3, 6.0e-4 at k = 1e4, 1e5, 4e5 N/mm).
    assert gaps[0] / gaps[1] == pytest.approx(4.0, rel=0.05)
    assert gaps[1] < 1e-3


def test_every_flight_of_the_turn_matches_a_scipy_event_solve(cam, solver):
    """At 900 rpm the roller leaves the cam seven times in the turn after the steady
    state's first separation; every separation, re-impact, impact velocity and peak force
    against scipy's event solve of the hybrid system (contact, flight, contact, ...)."""
    rpm = 900.0
    result = flights(solver, rpm)
    assert flight(solver, rpm) == result[0]
    tr = follower_constants(solver.program)
    period = 60.0 / rpm
    rate = 360.0 / period

    def lift(t):
        y, dy, _ = cycloid_lift(np.array([rate * t]))
        return 1e-3 * y[0], 1e-3 * dy[0] * rate

    def contact(t, s):
        y, dy = lift(t)
        return [s[1], (tr.k * (y - s[0]) + tr.c * (dy - s[1]) - tr.ks * s[0]) / tr.m]

    def force(t, s):
        y, dy = lift(t)
        return tr.preload + tr.k * (y - s[0]) + tr.c * (dy - s[1])

    force.terminal, force.direction = True, -1

    def flying(t, s):
        return [s[1], -(tr.preload + tr.ks * s[0]) / tr.m, -(tr.preload + tr.k * s[2]) / tr.c]

    def gap(t, s):
        return s[0] + s[2] - lift(t)[0]

    gap.terminal, gap.direction = True, -1
    # Start on the steady state where contact surely holds (the base-circle dwell).
    t0 = 330.0 / rate
    e_s, de_s = _shooting(cam, rpm, np.array([t0]))
    y0, dy0 = lift(t0)
    opts = dict(method="DOP853", rtol=1e-12, atol=1e-15, max_step=period / 2000)
    a = solve_ivp(contact, (t0, t0 + period), [y0 - e_s[0], dy0 - de_s[0]], events=force, **opts)
    t_sep = a.t_events[0][0]
    xs, vs = a.y_events[0][0]
    t_end = t_sep + period
    reference = []
    while t_sep < t_end:
        b = solve_ivp(flying, (t_sep, t_sep + period), [xs, vs, lift(t_sep)[0] - xs], events=gap, **opts)
        t_i = b.t_events[0][0]
        xi, vi, efi = b.y_events[0][0]
        impact_velocity = lift(t_i)[1] - (vi - (tr.preload + tr.k * efi) / tr.c)
        c = solve_ivp(contact, (t_i, t_i + period), [xi, vi], events=force, dense_output=True, **opts)
        t_next = c.t_events[0][0] if len(c.t_events[0]) else t_i + period
        tt = np.linspace(t_i, t_next, 100001)
        states = c.sol(tt)
        y, dy, _ = cycloid_lift(rate * tt)
        peak = np.max(tr.preload + tr.k * (1e-3 * y - states[0]) + tr.c * (1e-3 * dy * rate - states[1]))
        reference.append((np.mod(rate * t_sep, 360), np.mod(rate * t_i, 360), impact_velocity, peak))
        if not len(c.t_events[0]):
            break
        t_sep, (xs, vs) = t_next, c.y_events[0][0]
    assert len(result) == len(reference) == 7
    for got, (separation, reimpact, velocity, peak) in zip(result, reference):
        assert got.separation_deg == pytest.approx(separation, abs=1e-5)
        assert got.reimpact_deg == pytest.approx(reimpact, abs=1e-5)
        assert got.impact_velocity_m_s == pytest.approx(velocity, rel=1e-6)
        assert got.peak_impact_force_n == pytest.approx(peak, rel=1e-6)


def test_jump_speed_is_the_first_loss_of_contact(cam, solver):
    speed = jump_speed_rpm(solver, 300.0, 1200.0)
    below, above = solver.summary([speed - 0.1, speed + 0.1]).min_contact_force_n
    assert below >= 0 > above
    # Contact holds everywhere below it: a dense check of the scan.
    assert np.all(solver.summary(np.linspace(300.0, speed - 0.1, 500)).min_contact_force_n >= 0)
    # And a one-speed call agrees with the sweep (one compiled, vmapped call).
    sweep = solver.summary([400.0, 700.0, 1000.0])
    one = solver.cycle(700.0)
    assert sweep.min_contact_force_n[1] == pytest.approx(float(one.min_contact_force_n), rel=1e-12)


def test_dxf_reads_back_with_the_profile_at_roller_radius(cam, tmp_path):
    import ezdxf

    prof = profile(cam, 720)
    path = write_dxf(prof, tmp_path / "cam.dxf")
    doc = ezdxf.readfile(path)
    shapes = {e.dxf.layer: e for e in doc.modelspace().query("LWPOLYLINE")}
    assert set(shapes) == {"PROFILE", "PITCH"} and all(e.closed for e in shapes.values())
    outline = np.array([p[:2] for p in shapes["PROFILE"].get_points()])
    pitch = np.array([p[:2] for p in shapes["PITCH"].get_points()])
    # Pitch curve of a radial follower: the roller centre at base + roller + lift from the centre.
    y, _, _ = cycloid_lift(prof.theta_deg)
    assert np.abs(np.linalg.norm(pitch, axis=1) - (52.0 + y)).max() < 1e-9
    # Every profile point lies at the roller radius from its pitch point, along the normal.
    offset = outline - pitch
    assert np.abs(np.linalg.norm(offset, axis=1) - 12.0).max() < 1e-9
    tangent = np.roll(pitch, -1, axis=0) - np.roll(pitch, 1, axis=0)
    cosine = np.sum(offset * tangent, axis=1) / (12.0 * np.linalg.norm(tangent, axis=1))
    assert np.abs(cosine).max() < 1e-3
    # ... and no closer than the roller radius to any pitch point (a true envelope, no undercut).
    gaps = np.linalg.norm(outline[:, None, :] - pitch[None, :, :], axis=2).min(axis=1)
    assert gaps.min() > 12.0 - 1e-6 and not prof.undercut.any()


GOOD = """
[program]
name = "t"
[[segment]]
law = "cycloidal"
lift_mm = 10
angle_deg = 180
[[segment]]
law = "cycloidal"
lift_mm = -10
angle_deg = 180
[follower]
mass_kg = 1.0
stiffness_n_per_mm = 1000
damping_ratio = 0.05
spring_rate_n_per_mm = 5
preload_n = 100
"""

BAD = [
    (GOOD.replace("angle_deg = 180\n[[segment]]", "angle_deg = 170\n[[segment]]"), "sum to 350 degrees, not 360"),
    (GOOD.replace("angle_deg = 180\n[[segment]]", "angle_deg = -180\n[[segment]]"), "segment 1: angle_deg must be positive"),
    (GOOD.replace("lift_mm = 10", "lift_mm = -10"), "segment 1: the cumulative lift goes below zero"),
    (GOOD.replace("lift_mm = -10", "lift_mm = -5"), "not back at zero"),
    (GOOD.replace('law = "cycloidal"\nlift_mm = 10', 'law = "cycloidl"\nlift_mm = 10'), "segment 1: unknown law 'cycloidl'"),
    (GOOD.replace('law = "cycloidal"\nlift_mm = 10', 'lift_mm = 10'), "segment 1: lift_mm = 10 needs a law"),
    (GOOD.replace('lift_mm = 10\n', ''), "segment 1: law given without lift_mm"),
    (GOOD.replace('law = "cycloidal"\nlift_mm = 10', 'law = "missing.json"\nlift_mm = 10'), "segment 1: law file"),
    (GOOD.replace("mass_kg = 1.0", "mass_kg = -1.0"), "follower.mass_kg must be positive"),
    (GOOD.replace("stiffness_n_per_mm = 1000", "stiffness_n_per_mm = nan"), "follower.stiffness_n_per_mm must be finite"),
    (GOOD.replace("damping_ratio = 0.05", "damping_ratio = 1.5"), "follower.damping_ratio must be in"),
    (GOOD.replace("preload_n = 100", "preload_n = -1"), "follower.preload_n must be non-negative"),
    (GOOD.replace("mass_kg = 1.0", "mass_kg = 1.0\nkind = \"flat\""), "follower.kind must be one of"),
    (GOOD.replace("mass_kg = 1.0", "mass_kg = 1.0\nmas_kg = 1"), r"\[follower\]: unknown field\(s\) mas_kg"),
    (GOOD.replace("mass_kg = 1.0\n", ""), r"\[follower\] needs mass_kg"),
    (GOOD.replace("[follower]", "[follower"), "not valid TOML"),
    (GOOD.replace("preload_n = 100", "preload_n = 100\ngroove_clearance_mm = 0.1"),
     "follower.groove_clearance_mm: only a form-closed cam"),
    (GOOD.replace("spring_rate_n_per_mm = 5\npreload_n = 100", "groove_clearance_mm = -0.1"),
     "follower.groove_clearance_mm must be positive"),
]


@pytest.mark.parametrize("text, message", BAD, ids=[m[:30] for _, m in BAD])
def test_bad_program_files_give_clear_errors(tmp_path, capsys, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        Program.load(path)
    assert main(["program", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("camjax program: error: ") and "\n" not in err


def test_good_file_loads_and_missing_file_is_an_error(tmp_path, capsys):
    path = tmp_path / "good.toml"
    path.write_text(GOOD)
    assert [s.lift_mm for s in Program.load(path).segments] == [10, -10]
    with pytest.raises(ValueError, match="none.toml: no such program file"):
        Program.load(tmp_path / "none.toml")
    assert main(["program", str(tmp_path / "none.toml")]) == 2
    assert main(["program", "--rpm", "0,600"]) == 2
    assert "--rpm: speeds must be positive" in capsys.readouterr().err


def test_cli_json_and_out_dir(tmp_path, capsys):
    assert main(["program", "--rpm", "300,900", "--format", "json", "--out", str(tmp_path)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["program"] == "indexer" and len(report["speeds"]) == 2
    slow, fast = report["speeds"]
    assert slow["jump"] is False and slow["flight"] is None and slow["min_preload_n"] < 300
    assert fast["jump"] is True and fast["flight"]["reimpact_deg"] > fast["flight"]["separation_deg"]
    assert fast["flights"][0] == fast["flight"] and slow["flights"] is None
    assert fast["min_preload_n"] == pytest.approx(300 - fast["min_contact_force_n"], rel=1e-12)
    assert 300 < report["jump_speed_rpm"] < 900
    assert len(slow["residual_vibration_mm"]) == 2 and len(slow["period_ratios"]) == 2
    for name in ("profile.csv", "profile.dxf", "response.csv", "summary.json", "svaj.png",
                 "contact_force.png", "sweep.png", "profile.png"):
        assert (tmp_path / name).stat().st_size > 0
    assert math.isclose(json.loads((tmp_path / "summary.json").read_text())["jump_speed_rpm"],
                        report["jump_speed_rpm"])
    # profile.csv read back: a roller without offset, its pitch curve at r_b + r_r + y(theta)
    # from the lift alone, the profile one roller radius inside it, and the pitch curve's
    # radius of curvature (r^2 + r'^2)^1.5 / (r^2 + 2 r'^2 - r r'') in r(theta) (radians).
    program = Program.load(example_path())
    rows = np.genfromtxt(tmp_path / "profile.csv", delimiter=",", names=True)
    y, dy, ddy = program.lift(rows["theta_deg"])
    r = 52.0 + y
    np.testing.assert_allclose(np.hypot(rows["pitch_x_mm"], rows["pitch_y_mm"]), r, rtol=1e-9)
    np.testing.assert_allclose(rows["lift_mm"], y, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(np.hypot(rows["pitch_x_mm"] - rows["profile_x_mm"],
                                        rows["pitch_y_mm"] - rows["profile_y_mm"]), 12.0, rtol=1e-8)
    dr, ddr = dy * 180 / math.pi, ddy * (180 / math.pi) ** 2
    curvature = (r**2 + dr**2) ** 1.5 / (r**2 + 2 * dr**2 - r * ddr)
    joins = np.isin(np.round(rows["theta_deg"], 9), [0.0, 100.0, 180.0, 280.0])  # y'' steps there
    np.testing.assert_allclose(rows["pitch_radius_of_curvature_mm"][~joins], curvature[~joins], rtol=1e-7)
    # response.csv read back: Newton on the payload at every node, m x'' = F_c - F_0 - k_s x,
    # and the least node force at 900 rpm just above the refined least force of the report.
    h = np.genfromtxt(tmp_path / "response.csv", delimiter=",", names=True)
    f = program.follower
    newton = (h["contact_force_n"] - f.preload_n - f.spring_rate_n_per_mm * h["payload_displacement_mm"]) / f.mass_kg
    np.testing.assert_allclose(h["payload_acceleration_m_s2"], newton, rtol=0, atol=1e-7 * np.abs(newton).max())
    fast_rows = h["rpm"] == 900.0
    assert fast["min_contact_force_n"] <= h["contact_force_n"][fast_rows].min() < fast["min_contact_force_n"] + 1.0


def test_swinging_roller_program_geometry():
    law = laws.get("cycloidal")
    follower = Follower(**{**FOLLOWER, "kind": "swinging-roller", "arm_mm": 98.0, "pivot_mm": 110.0})
    program = Program("swing", (Segment(120, 15.0, law), Segment(60), Segment(120, -15.0, law), Segment(60)), follower)
    prof = profile(program, 360)
    theta = np.radians(prof.theta_deg)
    # Roller centre back in the fixed frame: on the arm's circle about the pivot, swung by lift / arm.
    c, s = np.cos(theta), np.sin(theta)
    fixed = np.stack([c * prof.pitch[:, 0] - s * prof.pitch[:, 1], s * prof.pitch[:, 0] + c * prof.pitch[:, 1]], 1)
    assert np.abs(np.linalg.norm(fixed - [110.0, 0.0], axis=1) - 98.0).max() < 1e-9
    swing = np.arctan2(fixed[:, 1], fixed[:, 0] - 110.0)
    assert np.abs(np.unwrap(swing[0] - swing) - prof.lift_mm / 98.0).max() < 1e-9
    assert np.abs(np.linalg.norm(prof.profile - prof.pitch, axis=1) - 12.0).max() < 1e-9
    with pytest.raises(ValueError, match="follower.arm_mm is missing: a swinging-roller follower needs"):
        Program("swing", program.segments, Follower(**{**FOLLOWER, "kind": "swinging-roller"}))


KIND_SAMPLES = {  # a follower of each kind whose cam is smooth and convex enough for a face
    "translating-roller": dict(offset_mm=4.0),
    "swinging-roller": dict(arm_mm=98.0, pivot_mm=110.0),
    "translating-flat": dict(base_radius_mm=60.0),
    "swinging-flat": dict(base_radius_mm=100.0, arm_mm=150.0, pivot_mm=250.0),
}


@pytest.mark.parametrize("kind", list(KIND_SAMPLES))
def test_a_kinds_keys_are_the_fields_that_shape_its_cam(kind):
    """``follower_kinds`` (what the studio offers for a kind) lists exactly the follower
    fields that move its cam's profile: each geometric field nudged by 2%, the profile
    moves where it is listed and stays to the last bit where it is not."""
    from camjax.program import FOLLOWER_KINDS, follower_kinds

    assert [k["name"] for k in follower_kinds()] == list(FOLLOWER_KINDS)
    listed = next(k for k in follower_kinds() if k["name"] == kind)
    follower = {**FOLLOWER, "kind": kind, "roller_radius_mm": 12.0, "offset_mm": 0.0, "arm_mm": 98.0,
                "pivot_mm": 110.0, **KIND_SAMPLES[kind]}
    base = profile(two_cycloids(**follower), 72).profile
    moved = set()
    for key in ("base_radius_mm", "roller_radius_mm", "offset_mm", "arm_mm", "pivot_mm"):
        nudged = {**follower, key: 1.02 * follower[key] + (0.5 if key == "offset_mm" else 0.0)}
        if key == "base_radius_mm" and not listed["roller"]:
            nudged["base_radius_mm"] = follower[key] + 0.5
        try:
            shape = profile(two_cycloids(**nudged), 72).profile
        except ValueError:  # a field the kind does not take, refused (a translating face's offset)
            continue
        if np.abs(shape - base).max() > 1e-3:
            moved.add(key)
        else:
            assert np.array_equal(shape, base), key
    assert moved == set(listed["keys"])
    assert listed["roller"] == ("roller_radius_mm" in moved)
    assert listed["swinging"] == ("pivot_mm" in moved)


def test_preload_objective_is_the_program_steady_state_and_its_gradient(cam, solver):
    """The objective's training value is the steady state's required preload (the program's
    own SteadyState path, refined between nodes), and its gradient matches finite differences."""
    import jax

    objective = MaxPreload(cam, 1, 500.0, 700.0)
    law = laws.BSplineLaw.fit(laws.get("cycloidal"), 8, 5)
    value = jax.jit(lambda c, p: objective.train(laws.BSplineLaw(c, 5), 1.0, p))
    speeds = objective.speeds()
    force = SteadyState(with_law(cam, 1, law), 500.0).summary(speeds).min_contact_force_n
    required = np.max(cam.follower.preload_n - force)
    # p = 1e6 is the max over nodes to 1e-5; refinement between nodes adds 7e-4 (measured).
    assert float(value(law.coefficients, 1e6)) == pytest.approx(required, rel=2e-3)
    assert float(value(law.coefficients, 1e6)) <= required + 1e-9
    direction = np.random.default_rng(0).normal(size=8)
    gradient = jax.jit(jax.grad(value))(law.coefficients, 64.0)
    h = 1e-5
    difference = (value(law.coefficients + h * direction, 64.0) - value(law.coefficients - h * direction, 64.0)) / (2 * h)
    assert float(gradient @ direction) == pytest.approx(float(difference), rel=1e-6)
    with pytest.raises(ValueError, match="segment 2 is a dwell"):
        MaxPreload(cam, 2, 500.0, 700.0)
    with pytest.raises(ValueError, match="needs a return spring"):
        MaxPreload(two_cycloids(spring_rate_n_per_mm=None), 1, 500.0, 700.0)


def test_design_one_segment_for_a_speed_range(tmp_path, capsys):
    """``--objective preload`` lowers the largest preload the whole program needs over the
    range (checked on a finer grid than the design's: the SteadyState for 250 rpm)."""
    program = Program.load(example_path())
    n1, n2 = camjax.program.segment_band(program, 1, 300.0, 600.0)
    f_n = program.follower.natural_frequency_hz
    assert (n1, n2) == pytest.approx((f_n * 100 / 360 * 60 / 600, f_n * 100 / 360 * 60 / 300), rel=1e-12)
    with pytest.raises(ValueError, match="segment 2 is a dwell"):
        camjax.program.segment_band(program, 2, 300.0, 600.0)
    code = main(["design", "--program", str(example_path()), "--segment", "1", "--rpm", "300:600",
                 "--objective", "preload", "--steps", "200", "--knots", "8", "--quiet", "--out", str(tmp_path)])
    assert code == 0
    reported = float(capsys.readouterr().out.split("rpm = ")[1].split(";")[0])
    designed = Program.load(tmp_path / "program.toml")
    speeds = np.linspace(300.0, 600.0, 2000)
    before, after = (np.max(camjax.program.min_preload_n(SteadyState(p, 250.0).summary(speeds).min_contact_force_n,
                                                         300.0)) for p in (program, designed))
    assert after < 0.9 * before  # measured: 138.4 N -> 114.5 N (105.8 N with 24 knots, 6000 steps)
    assert reported == pytest.approx(after, rel=1e-4)
    assert designed.segments[0].law.name.startswith("bspline")
    assert designed.segments[1:] == program.segments[1:] and designed.follower == program.follower
    # A designed law has array leaves: the profile still builds (the lift is a pytree).
    prof = profile(designed, 90)
    assert np.abs(np.linalg.norm(prof.pitch, axis=1) - 52.0 - designed.lift(prof.theta_deg)[0]).max() < 1e-9
    assert main(["design", "--program", str(example_path()), "--out", str(tmp_path)]) == 2
    assert "--program needs --segment and --rpm" in capsys.readouterr().err


def groove_cam(clearance_mm):
    """``two_cycloids`` in a groove (no spring), soft enough for a cheap scipy reference."""
    return two_cycloids(stiffness_n_per_mm=200.0, damping_ratio=0.1, spring_rate_n_per_mm=None, preload_n=0.0,
                        groove_clearance_mm=clearance_mm)


def _scipy_groove(program, rpm, turns):
    """Strikes ``(time, |relative velocity|, flank)`` of the grooved cam by scipy, in SI:
    ``m x'' = k s + c (y' - x')`` with the dead-zone stretch ``s = e`` on the inner flank,
    ``e + g`` on the outer, no force in between (``e = y - x``); DOP853 phase by phase,
    each ended by a terminal event on its own contact boundary, from rest on the base circle."""
    f = program.follower
    m, k, c, g = f.mass_kg, f.stiffness, f.damping, 1e-3 * f.groove_clearance_mm
    period = 60.0 / rpm
    rate = 360.0 / period

    def lift(t):
        y, dy, _ = cycloid_lift(np.array([rate * t]))
        return 1e-3 * y[0], 1e-3 * dy[0] * rate

    def field(t, z, mode):
        y, dy = lift(t)
        force = 0.0 if mode == 1 else k * (y - z[0] + (g if mode == 2 else 0.0)) + c * (dy - z[1])
        return [z[1], force / m]

    def boundary(offset, direction):
        event = lambda t, z, mode: lift(t)[0] - z[0] + offset  # noqa: E731
        event.terminal, event.direction = True, direction
        return event

    events = {0: [boundary(0.0, -1)], 2: [boundary(g, 1)], 1: [boundary(0.0, 1), boundary(g, -1)]}
    stops = sorted({(turn + a / 360.0) * period for turn in range(turns) for a in (0, 100, 180, 280)} | {turns * period})
    t, z, mode, strikes = 0.0, np.zeros(2), 0, []
    while t < stops[-1] - 1e-14:
        t_stop = min(x for x in stops if x > t + 1e-14)
        sol = solve_ivp(field, (t, t_stop), z, args=(mode,), events=events[mode], method="DOP853",
                        rtol=1e-12, atol=1e-15, max_step=period / 2000)
        hit = [i for i, te in enumerate(sol.t_events) if te.size]
        if not hit:
            t, z = t_stop, sol.y[:, -1]
            continue
        t, z = sol.t_events[hit[0]][0], sol.y_events[hit[0]][0]
        if mode == 1:
            mode = 0 if hit[0] == 0 else 2
            strikes.append((t, abs(lift(t)[1] - z[1]), mode))
        else:
            mode = 1
    return strikes


def test_first_groove_turn_from_rest_against_scipy():
    """``groove_turns`` for a fixed count from rest (the least it runs, two turns): every
    strike (angle, speed, flank) of the last turn against scipy's phase-by-phase
    integration of the dead-zone follower from rest."""
    rpm = 600.0
    program = groove_cam(0.1)
    turn = camjax.program.groove_turns(program, [rpm], turns=1)[0]
    last = turn.turns - 1  # the turns run (at least two), whose last one is reported
    period = 60.0 / rpm
    reference = [r for r in _scipy_groove(program, rpm, turn.turns) if r[0] >= last * period]
    assert len(turn.impacts) == len(reference) >= 2
    for got, (t, speed, flank) in zip(turn.impacts, reference):
        assert got.angle_deg == pytest.approx(360.0 * (t / period - last), abs=1e-6)
        assert got.velocity_m_s == pytest.approx(speed, rel=1e-6)
        assert got.flank == {0: "inner", 2: "outer"}[flank]


@pytest.mark.slow
def test_groove_clearance_hands_over_to_backlash(tmp_path, capsys):
    """The grooved cam's strikes against scipy; clearance -> 0 gives the contact-held flank
    force; the report and the CLI list the strikes.

    Slow (35 s on the loaded 2-core machine, 2026-11-27): the scipy reference integrates the dead-zone follower from rest over every turn the groove run takes to settle, impact by impact, in Python.
    """
    rpm = 600.0
    program = groove_cam(0.1)
    turns = camjax.program.groove_turns(program, [rpm])[0]
    settle = turns.turns  # the turns from rest the settled run took
    period = 60.0 / rpm
    reference = [r for r in _scipy_groove(program, rpm, settle) if r[0] >= (settle - 1) * period]
    assert len(turns.impacts) == len(reference) >= 4
    for got, (t, speed, flank) in zip(turns.impacts, reference):
        assert got.angle_deg == pytest.approx(360.0 * (t / period - (settle - 1)), abs=1e-6)
        assert got.velocity_m_s == pytest.approx(speed, rel=1e-6)
        assert got.flank == {0: "inner", 2: "outer"}[flank]
    # A vanishing clearance: the train force is the contact-held one, k e + c e'.
    solver = SteadyState(groove_cam(None), rpm)
    tight = camjax.program.groove_turns(groove_cam(1e-6), [rpm])[0]
    lam = solver.lam(rpm)[0]
    q = solver.mode_at(solver.cycle(rpm).q, rpm, tight.theta_deg / 360.0)[0]
    e = q.imag / lam.imag
    held = 1e-3 * (follower_constants(solver.program).k * e + follower_constants(solver.program).c * (q.real + lam.real * e) / period)
    assert np.abs(tight.force_n - held).max() < 1e-5 * np.abs(held).max()  # measured 1e-6
    report = analyse(program, [rpm]).speeds[0]
    assert [i.angle_deg for i in report.impacts] == pytest.approx([i.angle_deg for i in turns.impacts])
    assert report.jump is False and report.flight is None
    path = tmp_path / "groove.toml"
    path.write_text(program.to_toml())
    assert main(["program", str(path), "--rpm", "600"]) == 0
    lines = [x for x in capsys.readouterr().out.splitlines() if "strikes the" in x]
    assert len(lines) == len(turns.impacts) and "outer flank at 56.166 deg" in lines[1]


def test_strikes_closer_than_a_sample_get_the_next_samples_force():
    """A chattering roller strikes twice between two samples: its first strike's peak force
    is the force at the next sample (was NaN: no sample lay between the strikes)."""
    from types import SimpleNamespace

    from camjax.program import GrooveTurn

    ts = np.linspace(0.0, 2.0, 201)  # samples 0.01 apart
    acceleration = np.sin(7.0 * ts)
    strikes = np.array([1.1003, 1.1007, 1.5003])
    response = SimpleNamespace(n_impacts=3, impact_tau=strikes, impact_velocity=np.ones(3),
                               impact_flank=np.zeros(3, int), tau=ts,
                               payload_acceleration=acceleration)
    turn = GrooveTurn.from_response(600.0, response, 2, mass=1.0, stroke_m=1.0, period=1.0)
    peaks = [impact.peak_force_n for impact in turn.impacts]
    assert peaks[0] == acceleration[111]  # the first sample after 1.1003
    inside = acceleration[111:151]  # from 1.1007 to 1.5003
    assert peaks[1] == inside[np.argmax(np.abs(inside))]
    rest = acceleration[151:]
    assert peaks[2] == rest[np.argmax(np.abs(rest))]


def test_a_groove_turns_motion_law_reads_each_join_once():
    """The hand-over's law over the turn (``TurnLaw``) against the program's lift at every
    join and between: at a join of two moving segments in motion (the feed cam's constant
    velocity stroke) the velocity was counted from both segments (twice the stroke's)."""
    from camjax.program import TurnLaw

    program = Program.load(example_path("feed"))
    h = float(np.max(program.lift(np.linspace(0.0, 360.0, 721))[0]))  # the law's length unit
    theta = np.concatenate([program.start_deg, np.linspace(0.0, 360.0, 97)[:-1] + 0.37])
    s, v, a, _ = (np.asarray(x) for x in TurnLaw.of(program, h, 1).evaluate(theta / 360.0))
    y, dy, ddy = program.lift(theta)  # after each join: the solver steps forward from it
    assert np.abs(s - y / h).max() < 1e-12
    assert np.abs(v - 360.0 * dy / h).max() < 1e-12 * 360.0 * np.abs(dy / h).max()
    assert np.abs(a - 360.0**2 * ddy / h).max() < 1e-12 * 360.0**2 * np.abs(ddy / h).max()


def test_the_last_strike_of_a_turn_runs_its_peak_force_to_the_next_turns_first():
    """The turn's last strike is followed by the next turn's first: its peak force runs on
    across 360 degrees (the settled turn is periodic, so from the turn's start to its first
    strike); it was cut off at 360 degrees."""
    from types import SimpleNamespace

    from camjax.program import GrooveTurn

    ts = np.linspace(0.0, 2.0, 401)
    u = np.mod(ts, 1.0)
    acceleration = 5.0 * np.exp(-((u - 0.05) / 0.02) ** 2) - 0.5 * np.sin(2 * np.pi * u)  # periodic
    strikes = np.array([0.3, 0.8, 1.3, 1.8])
    response = SimpleNamespace(n_impacts=4, impact_tau=strikes, impact_velocity=np.ones(4),
                               impact_flank=np.zeros(4, int), tau=ts, payload_acceleration=acceleration)
    last, first = (GrooveTurn.from_response(600.0, response, 2, mass=1.0, stroke_m=1.0, period=1.0, turn=k)
                   for k in (1, 0))
    assert [i.peak_force_n for i in last.impacts] == [i.peak_force_n for i in first.impacts]
    assert last.impacts[1].peak_force_n == pytest.approx(5.0 - 0.5 * np.sin(0.1 * np.pi), rel=1e-3)  # at 0.05 turns
    window = (ts >= 1.8) | ((ts >= 1.0) & (ts <= 1.3))
    assert last.impacts[1].peak_force_n == np.abs(acceleration[window]).max()


def test_a_groove_turn_is_settled_when_its_strikes_repeat():
    """The settling criterion compares strikes turn by turn: flanks must match, angles
    within SETTLED_DEG and velocities within SETTLED_REL, else the change is infinite."""
    from camjax.program import SETTLED_DEG, GrooveTurn, Impact

    def turn(*strikes):
        return GrooveTurn(600.0, np.zeros(2), np.zeros(2), [Impact(a, f, v, 1.0) for a, f, v in strikes])

    before = turn((10.0, "outer", 0.5), (200.0, "inner", 0.25))
    assert turn((10.0 + 3e-7, "outer", 0.5), (200.0 - 5e-7, "inner", 0.25)).change_from(before) == \
        pytest.approx(5e-7, rel=1e-6)
    assert turn((10.0 + 2e-6, "outer", 0.5), (200.0, "inner", 0.25)).change_from(before) > SETTLED_DEG
    assert turn((10.0, "outer", 0.5)).change_from(before) == math.inf  # a strike fewer
    assert turn((10.0, "inner", 0.5), (200.0, "inner", 0.25)).change_from(before) == math.inf
    assert turn((10.0, "outer", 0.5 * (1 + 1e-5)), (200.0, "inner", 0.25)).change_from(before) == math.inf


@pytest.mark.slow
def test_a_settled_groove_turn_does_not_move_with_more_turns():
    """Run from rest until the strikes repeat: twice the turns moves them by less than
    SETTLED_DEG (a fixed count from the contact decay left them moving by 5e-4 deg).

    Slow (19 s on the loaded 2-core machine, 2026-11-27): two runs from rest, the second over twice the turns the first needed to settle.
    """
    settled = camjax.program.groove_turns(groove_cam(0.1), [600.0])[0]
    assert settled.settled and settled.turns >= 2
    longer = camjax.program.groove_turns(groove_cam(0.1), [600.0], turns=2 * settled.turns)[0]
    assert [i.flank for i in longer.impacts] == [i.flank for i in settled.impacts]
    assert max(abs(a.angle_deg - b.angle_deg) for a, b in zip(longer.impacts, settled.impacts)) < 1e-6


def test_results_outside_the_design_rules_are_warned_about(tmp_path, capsys):
    """A 100 mm lift over 60 degrees on a 40 mm base circle: the pressure angle (64 deg)
    passes the translating roller's 30 and the lift is large against the base circle;
    both are said on stderr, once each, and the run still reports."""
    law = laws.get("cycloidal")
    program = Program("absurd", (Segment(60, 100.0, law), Segment(120), Segment(60, -100.0, law), Segment(120)),
                      Follower(**FOLLOWER))
    path = tmp_path / "absurd.toml"
    path.write_text(program.to_toml())
    assert main(["program", str(path), "--rpm", "100"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2
    assert err[0].startswith("warning: the pressure angle reaches 64.4 deg, above the 30 deg")
    assert "the lift (100 mm) is more than twice the base circle's radius (40 mm)" in err[1]
    assert main(["program", "--rpm", "300"]) == 0  # the indexer: within the rules
    assert "warning" not in capsys.readouterr().err
