"""What the machine designer sizes (drive torque, flywheel, Hertz stress, flat faces, the
cam's geometry) against independent references: scipy quadrature of the exact response,
hand-computed Hertz cases and the closed forms of the cam's curvature."""

import dataclasses
import json
import math
import tomllib

import numpy as np
import pytest
from helpers import FOLLOWER, follower_constants
from scipy.integrate import quad

from camjax import laws
from camjax.cli import main
from camjax.program import (
    Follower,
    Machine,
    Materials,
    Program,
    Segment,
    SteadyState,
    analyse,
    analyse_machine,
    cam_geometry,
    example_path,
    profile,
    response,
    shaft_torque,
    shape,
)
from camjax.sdof import deflection_gains


@pytest.fixture(scope="module")
def indexer():
    return Program.load(example_path())


def exact_torque(steady: SteadyState, rpm: float):
    """``T(theta_deg) = F_c dy/dtheta`` (N m) from the exact mode anywhere (``mode_at``)
    and the program's own lift derivative: no grid, no interpolant."""
    cycle, train, program = steady.cycle(rpm), follower_constants(steady.program), steady.program
    period = 60.0 / rpm
    ge, gr = (complex(g) for g in deflection_gains(train.omega_per_turn(rpm), train.zeta))
    gain = 1e-3 * train.k * ge + 1e-3 * train.c / period * gr

    def torque(theta_deg):
        theta_deg = np.atleast_1d(np.asarray(theta_deg, dtype=float))
        force = train.preload + np.real(gain * steady.mode_at(cycle.q, rpm, theta_deg / 360.0)[0])
        return force * program.lift(theta_deg)[1] * (180.0 / math.pi) * 1e-3

    return torque


def quad_over_turn(f, program: Program) -> float:
    """``int_0^360 f dtheta_deg`` by scipy quadrature, segment by segment (f is smooth in each)."""
    edges = [*program.start_deg, 360.0]
    return sum(quad(lambda t: float(f(t)[0]), a, b, limit=400, epsabs=1e-14, epsrel=1e-12)[0]
               for a, b in zip(edges[:-1], edges[1:]))


@pytest.mark.parametrize("rpm", [600.0, 900.0])
def test_drive_torque_is_the_work_of_the_contact_force(indexer, rpm):
    """Mean and RMS torque against scipy quadrature of ``F_c dy/dtheta`` (so the cycle's
    ``oint T dtheta`` is ``oint F_c dy``), peak and energy fluctuation against a dense sample."""
    steady = SteadyState(indexer, rpm)
    out = analyse(indexer, [rpm], steady=steady, with_flight=False, speed_fluctuation=0.02).speeds[0]
    torque = exact_torque(steady, rpm)
    work = quad_over_turn(lambda t: torque(t) * math.pi / 180.0, indexer)  # J per turn, = oint F_c dy
    assert out.mean_drive_torque_n_m * 2 * math.pi == pytest.approx(work, rel=1e-7, abs=1e-12)
    # The work per turn is what the train's damper dissipates: positive and small here.
    assert work > 0
    rms = math.sqrt(quad_over_turn(lambda t: torque(t) ** 2, indexer) / 360.0)
    assert out.rms_drive_torque_n_m == pytest.approx(rms, rel=1e-9)
    theta = np.linspace(0.0, 360.0, 360001)
    t = torque(theta)
    assert out.max_drive_torque_n_m == pytest.approx(np.abs(t).max(), rel=1e-8)
    w = np.concatenate([[0.0], np.cumsum(0.5 * (t[1:] + t[:-1]) * np.diff(np.radians(theta)))])
    w -= out.mean_drive_torque_n_m * np.radians(theta)
    assert out.energy_fluctuation_j == pytest.approx(w.max() - w.min(), rel=1e-8)
    omega = 2 * math.pi * rpm / 60.0
    assert out.flywheel_inertia_kg_m2 == pytest.approx(out.energy_fluctuation_j / (0.02 * omega**2), rel=1e-14)
    h = response(indexer, rpm, steady=steady)
    assert np.abs(h["drive_torque_n_m"] - torque(h["theta_deg"])).max() < 1e-9 * np.abs(t).max()


def test_hertz_stress_against_a_hand_computed_case(indexer):
    """On the base circle (a dwell, pressure angle 0): cam radius 40 mm, roller 12 mm, width
    10 mm, aluminium cam (70 GPa, 0.33) on a steel roller (210 GPa, 0.3)."""
    materials = Materials(cam_youngs_modulus_gpa=70.0, cam_poisson_ratio=0.33)
    program = dataclasses.replace(indexer, materials=materials,
                                  follower=dataclasses.replace(indexer.follower, contact_width_mm=10.0))
    e_star = 1.0 / ((1 - 0.33**2) / 70e3 + (1 - 0.3**2) / 210e3)  # MPa
    assert materials.contact_modulus_mpa == pytest.approx(e_star, rel=1e-14)
    radius = 1.0 / (1 / 12.0 + 1 / 40.0)
    h = response(program, 600.0)
    dwell = (h["theta_deg"] > 290.0) & (h["theta_deg"] < 350.0)
    hand = np.sqrt(h["contact_force_n"][dwell] * e_star / (math.pi * 10.0 * radius))
    assert np.abs(h["contact_stress_mpa"][dwell] - hand).max() < 1e-9 * hand.max()
    steady = SteadyState(program, 600.0)
    report = analyse(program, [600.0], with_flight=False, steady=steady).speeds[0]
    i = int(np.argmax(h["contact_stress_mpa"]))
    # refined between the nodes (tests/test_hertz_refined.py): at least the nodes' largest,
    # within a grid interval of it
    assert report.max_contact_stress_mpa >= h["contact_stress_mpa"][i]
    assert abs(report.max_contact_stress_deg - h["theta_deg"][i]) < 2 * np.diff(h["theta_deg"]).max()
    # At the reported angle, from the lift alone: the pitch curve r = r_b + r_r + y(theta)
    # (no offset), its radius of curvature (r^2 + r'^2)^1.5 / (r^2 + 2 r'^2 - r r''), the
    # cam's rho = that - r_r, the pressure angle atan(r' / r); F_n = F_c / cos(phi),
    # 1/R' = 1/r_r + 1/rho, p = sqrt(F_n E* / (pi L R')) and the half-width b = 2 R' p / E*,
    # with the exact contact force there (the steady state's mode between the nodes).
    theta = float(report.max_contact_stress_deg)
    train = follower_constants(steady.program)
    ge, gr = (complex(g) for g in deflection_gains(train.omega_per_turn(600.0), train.zeta))
    gain = 1e-3 * train.k * ge + 1e-3 * train.c / 0.1 * gr
    force = float(train.preload + np.real(gain * steady.mode_at(steady.cycle(600.0).q, 600.0, theta / 360.0)[0])[0])
    assert min(abs(theta - j) for j in (0.0, 100.0, 180.0, 280.0, 360.0)) > 1e-6  # not at a join
    y, dy, ddy = (float(v[0]) for v in indexer.lift(np.array([theta])))
    r, dr, ddr = 40.0 + 12.0 + y, dy * 180 / math.pi, ddy * (180 / math.pi) ** 2
    rho = (r**2 + dr**2) ** 1.5 / (r**2 + 2 * dr**2 - r * ddr) - 12.0
    phi = math.atan2(dr, r)
    r_eff = 1.0 / (1 / 12.0 + 1 / rho)
    p = math.sqrt(force / math.cos(phi) * e_star / (math.pi * 10.0 * r_eff))
    assert report.max_contact_stress_mpa == pytest.approx(p, rel=1e-9)
    assert report.contact_half_width_mm == pytest.approx(2 * r_eff * p / e_star, rel=1e-9)


def test_grooved_cam_bears_on_the_other_wall_where_the_force_is_negative(indexer):
    """Form-closed, on the base-circle dwell: the inner flank is the base circle (40 mm,
    convex); the other wall, 0.05 mm of clearance further out, is concave to the roller:
    ``1/R' = 1/12 - 1/(52 + 12 + 0.05)``."""
    follower = dataclasses.replace(indexer.follower, spring_rate_n_per_mm=None, preload_n=0.0,
                                   groove_clearance_mm=0.05, contact_width_mm=12.0)
    program = dataclasses.replace(indexer, follower=follower)
    h = response(program, 600.0)
    e_star = Materials().contact_modulus_mpa
    dwell = (h["theta_deg"] > 290.0) & (h["theta_deg"] < 355.0)
    force = h["contact_force_n"][dwell]
    assert (force > 0).any() and (force < 0).any()  # the free vibration about zero in the dwell
    radius = np.where(force > 0, 1 / (1 / 12.0 + 1 / 40.0), 1 / (1 / 12.0 - 1 / 64.05))
    hand = np.sqrt(np.abs(force) * e_star / (math.pi * 12.0 * radius))
    assert np.abs(h["contact_stress_mpa"][dwell] - hand).max() < 1e-9 * hand.max()


def eccentric(kind: str, **follower) -> Program:
    """Harmonic rise over 180 degrees and return over 180: ``y = e (1 - cos theta)``, ``e = 5``."""
    law = laws.get("harmonic")
    base = {**FOLLOWER, "kind": kind, **follower}
    base.pop("roller_radius_mm")
    return Program("eccentric", (Segment(180, 10.0, law), Segment(180, -10.0, law)), Follower(**base))


def test_flat_face_on_a_harmonic_eccentric_is_a_circle():
    """A translating flat face on ``y = e (1 - cos theta)``: the cam is a circle of radius
    ``r_b + e`` about a point ``e`` from the centre, the contact at ``y' = e sin theta``."""
    program = eccentric("translating-flat")
    prof = profile(program, 720)
    e, rb = 5.0, 40.0
    assert np.abs(prof.profile_radius_of_curvature_mm - (rb + e)).max() < 1e-9
    centre = prof.profile.mean(axis=0)
    assert np.abs(np.linalg.norm(prof.profile - centre, axis=1) - (rb + e)).max() < 1e-9
    assert np.linalg.norm(centre) == pytest.approx(e, rel=1e-9)
    theta = np.radians(prof.theta_deg)
    assert np.abs(prof.face_position_mm - e * np.sin(theta)).max() < 1e-9
    geometry = cam_geometry(program, np.arange(360.0))
    assert geometry.face_width_mm == pytest.approx(2 * e, rel=1e-12)
    assert geometry.min_radius_of_curvature_mm == pytest.approx(rb + e, rel=1e-12)
    assert geometry.max_pressure_angle_deg == 0.0 and geometry.min_concave_radius_of_curvature_mm is None
    again = Program.from_dict(tomllib.loads(dataclasses.replace(program, materials=Materials(70.0, 0.33)).to_toml()))
    assert again == dataclasses.replace(program, materials=Materials(70.0, 0.33))


def test_swinging_flat_face_envelope():
    """The contact point lies on the face (a line through the pivot at the swing), the face
    touches the cam there, and the radius of curvature matches the points' own."""
    program = eccentric("swinging-flat", arm_mm=80.0, pivot_mm=100.0)
    prof = profile(program, 3600)
    theta = np.radians(prof.theta_deg)
    c, s = np.cos(theta), np.sin(theta)
    fixed = np.stack([c * prof.profile[:, 0] - s * prof.profile[:, 1], s * prof.profile[:, 0] + c * prof.profile[:, 1]], 1)
    beta = np.arccos(40.0 / 100.0) - prof.lift_mm / 80.0
    normal = np.stack([np.cos(beta), np.sin(beta)], 1)
    # On the face line n . X = d cos(beta) ...
    assert np.abs(np.sum(fixed * normal, 1) - 100.0 * np.cos(beta)).max() < 1e-9
    # ... at the face position's distance from the pivot ...
    assert np.abs(np.linalg.norm(fixed - [100.0, 0.0], axis=1) - prof.face_position_mm).max() < 1e-9
    # ... and the radius of curvature of the traced points (circle through neighbours).
    a, b, d = prof.profile, np.roll(prof.profile, -1, 0), np.roll(prof.profile, 1, 0)
    area2 = (b - a)[:, 0] * (d - a)[:, 1] - (b - a)[:, 1] * (d - a)[:, 0]
    circum = np.linalg.norm(b - a, axis=1) * np.linalg.norm(d - a, axis=1) * np.linalg.norm(b - d, axis=1) / (2 * np.abs(area2))
    assert np.abs(circum / prof.profile_radius_of_curvature_mm - 1).max() < 1e-4
    report = analyse(program, [300.0], with_flight=False)
    assert report.geometry.face_width_mm == pytest.approx(np.ptp(prof.face_position_mm), rel=1e-4)


def test_flat_face_runs_the_same_dynamics_as_the_roller():
    roller = eccentric("translating-roller", roller_radius_mm=12.0)
    flat = eccentric("translating-flat")
    a, b = (analyse(p, [400.0, 800.0], with_flight=False) for p in (roller, flat))
    for x, y in zip(a.speeds, b.speeds):
        assert x.min_contact_force_n == y.min_contact_force_n
        assert x.max_drive_torque_n_m == y.max_drive_torque_n_m


def test_one_sided_curvature_where_the_acceleration_steps():
    """Harmonic rise (90 deg) straight into a harmonic return (120 deg): at the nose
    ``y' = 0`` and ``rho_pitch = R^2 / (R - y'')`` with ``R = r_b + r_r + y`` and ``y''`` the
    one-sided second derivative (mm/rad^2) of the segment on each side."""
    law = laws.get("harmonic")
    program = Program("step", (Segment(90, 20.0, law), Segment(120, -20.0, law), Segment(150)),
                      Follower(**{**FOLLOWER, "contact_width_mm": 10.0}))
    big_r = 40.0 + 12.0 + 20.0
    before = -10.0 * (180.0 / 90.0) ** 2  # -h/2 (pi/beta)^2, beta in radians
    after = -10.0 * (180.0 / 120.0) ** 2
    expected = [big_r**2 / (big_r - ydd) - 12.0 for ydd in (before, after)]
    geometry = cam_geometry(program, np.arange(0.0, 360.0, 0.5))
    nose = next(j for j in geometry.joins if j.angle_deg == 90.0)
    assert nose.radius_before_mm == pytest.approx(expected[0], rel=1e-12)
    assert nose.radius_after_mm == pytest.approx(expected[1], rel=1e-12)
    assert geometry.min_radius_of_curvature_mm == pytest.approx(min(expected), rel=1e-12)
    assert profile(program, 720).profile_radius_of_curvature_mm[180] == pytest.approx(expected[1], rel=1e-12)
    # The stress at the nose uses the smaller radius (the larger stress).
    h = response(program, 300.0)
    at = int(np.argmin(np.abs(h["theta_deg"] - 90.0)))
    r_eff = 1.0 / (1 / 12.0 + 1 / min(expected))
    p = math.sqrt(h["contact_force_n"][at] * Materials().contact_modulus_mpa / (math.pi * 10.0 * r_eff))
    assert h["contact_stress_mpa"][at] == pytest.approx(p, rel=1e-12)


def test_shaft_torque_is_the_sum_of_the_phased_cams(indexer):
    other = dataclasses.replace(indexer, name="heavy", follower=dataclasses.replace(indexer.follower, mass_kg=2.5))
    rpm, phases = 500.0, (0.0, 123.4)
    report = analyse_machine([(indexer, phases[0]), (other, phases[1])], [rpm], with_flight=False)
    steadies = [SteadyState(p, rpm) for p in (indexer, other)]
    nodes, values, _, _ = shaft_torque([s.cycle(rpm) for s in steadies], [s.grid.nodes for s in steadies], phases)
    theta = 360.0 * nodes
    exact = sum(exact_torque(s, rpm)(theta - phase) for s, phase in zip(steadies, phases))
    assert np.abs(values - exact).max() < 1e-8 * np.abs(exact).max()
    shaft = report.shaft[0]
    assert shaft.mean_drive_torque_n_m == pytest.approx(sum(c.speeds[0].mean_drive_torque_n_m for c in report.cams),
                                                        rel=1e-9)
    dense = np.linspace(0.0, 360.0, 200001)
    t = sum(exact_torque(s, rpm)(dense - phase) for s, phase in zip(steadies, phases))
    assert shaft.max_drive_torque_n_m == pytest.approx(np.abs(t).max(), rel=1e-8)
    assert shaft.rms_drive_torque_n_m == pytest.approx(np.sqrt(np.mean(t[:-1] ** 2)), rel=1e-7)
    w = np.concatenate([[0.0], np.cumsum(0.5 * (t[1:] + t[:-1]) * np.diff(np.radians(dense)))])
    w -= shaft.mean_drive_torque_n_m * np.radians(dense)
    assert shaft.energy_fluctuation_j == pytest.approx(np.ptp(w), rel=1e-7)
    # One cam alone: the shaft is that cam.
    alone = analyse_machine([(indexer, 0.0)], [rpm], with_flight=False)
    assert alone.shaft[0].energy_fluctuation_j == pytest.approx(alone.cams[0].speeds[0].energy_fluctuation_j,
                                                                rel=1e-12)


def test_machine_file_and_cli(tmp_path, capsys):
    (tmp_path / "m.toml").write_text(
        f'[machine]\nname = "press"\n\n[[cam]]\nprogram = "{example_path()}"\nphase_deg = 0\n\n'
        f'[[cam]]\nprogram = "{example_path()}"\nphase_deg = 180\n')
    machine = Machine.load(tmp_path / "m.toml")
    assert [phase for _, phase in machine.cams] == [0.0, 180.0]
    assert main(["program", str(tmp_path / "m.toml"), "--rpm", "300,600", "--format", "json", "--no-flight",
                 "--speed-fluctuation", "0.1"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["machine"] == "press" and report["speed_fluctuation"] == 0.1
    assert [c["phase_deg"] for c in report["cams"]] == [0.0, 180.0]
    shaft = report["shaft"]["speeds"]
    assert shaft[0]["mean_drive_torque_n_m"] == pytest.approx(
        sum(c["speeds"][0]["mean_drive_torque_n_m"] for c in report["cams"]), rel=1e-9)
    (tmp_path / "bad.toml").write_text('[[cam]]\nprogram = "none.toml"\n')
    assert main(["program", str(tmp_path / "bad.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert "cam 1: " in err and "no such program file" in err and "\n" not in err


def test_cli_reports_torque_stress_and_geometry_and_keeps_the_example_numbers(tmp_path, capsys):
    assert main(["program", "--rpm", "300,600,900", "--format", "json"]) == 0
    report = json.loads(capsys.readouterr().out)
    # The example's numbers as docs/program.md records them.
    for s, (accel, fmin, preload) in zip(report["speeds"], [(42.53, 291.2, 8.8), (222.5, 161.6, 138.4),
                                                             (504.0, -265.4, 565.4)]):
        assert s["max_payload_acceleration_m_s2"] == pytest.approx(accel, abs=0.05)
        assert s["min_contact_force_n"] == pytest.approx(fmin, abs=0.05)
        assert s["min_preload_n"] == pytest.approx(preload, abs=0.05)
        assert s["max_drive_torque_n_m"] > s["rms_drive_torque_n_m"] > abs(s["mean_drive_torque_n_m"])
        assert s["max_contact_stress_mpa"] is None
    assert report["jump_speed_rpm"] == pytest.approx(723.1, abs=0.05)
    g = report["geometry"]
    assert 0 < g["max_pressure_angle_deg"] < 30 and g["min_radius_of_curvature_mm"] > 0
    assert [j["angle_deg"] for j in g["joins"]] == [0.0, 100.0, 180.0, 280.0]
    text = (tmp_path / "p.toml")
    text.write_text(example_path().read_text().replace("offset_mm = 0", "offset_mm = 0\ncontact_width_mm = 15"))
    assert main(["program", str(text), "--rpm", "300,600", "--out", str(tmp_path / "out")]) == 0
    table = capsys.readouterr().out
    assert "max|T| N m" in table and "max p MPa" in table and "max pressure angle" in table
    header = (tmp_path / "out" / "response.csv").read_text().splitlines()[0]
    assert header.endswith("drive_torque_n_m,contact_stress_mpa")
    # Read back: T = F_c dy/dtheta (dy/dtheta in m/rad) at every node, and on the base-circle
    # dwell the Hertz stress of steel on steel (E* = 210 GPa / (2 (1 - 0.3^2))), 15 mm wide,
    # 1/R' = 1/12 + 1/40.
    h = np.genfromtxt(tmp_path / "out" / "response.csv", delimiter=",", names=True)
    slope = 1e-3 * Program.load(text).lift(h["theta_deg"])[1] * 180 / math.pi
    np.testing.assert_allclose(h["drive_torque_n_m"], h["contact_force_n"] * slope, rtol=2e-8,
                               atol=1e-9 * np.abs(h["drive_torque_n_m"]).max())  # 10 digits each
    dwell = (h["theta_deg"] > 290.0) & (h["theta_deg"] < 350.0)
    e_star = 210e3 / (2 * (1 - 0.3**2))
    hertz = np.sqrt(h["contact_force_n"][dwell] * e_star / (math.pi * 15.0 / (1 / 12.0 + 1 / 40.0)))
    np.testing.assert_allclose(h["contact_stress_mpa"][dwell], hertz, rtol=2e-8)
    for name in ("drive_torque.png", "contact_stress.png", "torque_sweep.png"):
        assert (tmp_path / "out" / name).stat().st_size > 0


BASE = example_path().read_text()


@pytest.mark.parametrize("text, message", [
    (BASE.replace("offset_mm = 0", "offset_mm = 0\ncontact_width_mm = 0"),
     "follower.contact_width_mm must be positive, got 0"),
    (BASE.replace("offset_mm = 0", "offset_mm = 0\ncontact_width_mm = -3"),
     "follower.contact_width_mm must be positive, got -3"),
    (BASE + "\n[materials]\ncam_youngs_modulus_gpa = 0\n", "materials.cam_youngs_modulus_gpa must be positive, got 0"),
    (BASE + "\n[materials]\nfollower_youngs_modulus_gpa = -70\n",
     "materials.follower_youngs_modulus_gpa must be positive, got -70"),
    (BASE + "\n[materials]\ncam_poisson_ratio = 0.5\n", r"materials.cam_poisson_ratio must be in \(-1, 0.5\), got 0.5"),
    (BASE + "\n[materials]\nfollower_poisson_ratio = -1\n",
     r"materials.follower_poisson_ratio must be in \(-1, 0.5\), got -1"),
    (BASE + "\n[materials]\ncam_modulus = 1\n", r"\[materials\]: unknown field\(s\) cam_modulus"),
    (BASE.replace('kind = "translating-roller"', 'kind = "translating-flat"'),
     "roller_radius_mm: a flat-faced follower has no roller"),
])
def test_bad_machine_inputs_give_one_line_errors(tmp_path, capsys, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        Program.load(path)
    assert main(["program", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("camjax program: error: ") and "\n" not in err


def test_flat_face_over_a_cusp_names_the_angles(capsys, tmp_path):
    """A harmonic 20 mm rise over 60 degrees and back on r_b = 20 mm under a flat face:
    ``r_b + y + y'' = 30 + 80 cos(3 theta)`` is negative from 37.3 to 82.7 degrees."""
    law = laws.get("harmonic")
    follower = Follower(**{**FOLLOWER, "kind": "translating-flat", "base_radius_mm": 20.0})
    program = Program("cusp", (Segment(60, 20.0, law), Segment(60, -20.0, law), Segment(240)), follower)
    theta = np.arange(0.0, 360.0, 0.01)
    y, _, ydd = program.lift(theta)
    rho = 20.0 + y + ydd * (180 / math.pi) ** 2
    bad = theta[rho <= 0]
    with pytest.raises(ValueError, match=r"not positive at .*\d deg: a cusp") as error:
        profile(program, 36000)
    first = float(str(error.value).split("not positive at ")[1].split("-")[0])
    assert first == pytest.approx(bad.min(), abs=0.011)
    with pytest.raises(ValueError, match="a cusp"):
        analyse(program, [300.0], with_flight=False)
    with pytest.raises(ValueError, match="speed_fluctuation must be a number in"):
        analyse(program, [300.0], speed_fluctuation=0.0)
    assert main(["program", "--speed-fluctuation", "0"]) == 2
    assert "--speed-fluctuation: must be in (0, 2)" in capsys.readouterr().err


@pytest.mark.parametrize("kind, extra", [("translating-roller", dict(offset_mm=6.0)),
                                         ("swinging-roller", dict(arm_mm=98.0, pivot_mm=110.0)),
                                         ("swinging-flat", dict(arm_mm=80.0, pivot_mm=100.0))])
def test_drive_torque_is_the_moment_of_the_normal_force(kind, extra):
    """``T = F_c dy/dtheta`` (power balance) equals the moment about the cam centre of the
    normal contact force ``F_n`` acting along the contact normal: for a roller
    ``F_n = F_c / cos(phi)`` through the roller centre, under a swinging face
    ``F_n = F_c arm / l`` at the contact point (``l`` its distance from the pivot)."""
    law = laws.get("cycloidal")
    follower = {**FOLLOWER, "kind": kind, **extra}
    if kind.endswith("flat"):
        follower.pop("roller_radius_mm")
    program = Program("p", (Segment(120, 15.0, law), Segment(60), Segment(120, -15.0, law), Segment(60)),
                      Follower(**follower))
    h = response(program, 400.0)
    cam = shape(program, h["theta_deg"])
    if kind.endswith("roller"):
        point = np.asarray(cam.pitch)
        normal = (point - np.asarray(cam.inner)) / 12.0
        normal_force = h["contact_force_n"] / np.cos(np.asarray(cam.pressure_angle))
    else:
        point = np.asarray(cam.profile)
        alpha = np.arccos(40.0 / 100.0) - h["lift_mm"] / 80.0 - np.radians(h["theta_deg"])
        normal = np.stack([np.cos(alpha), np.sin(alpha)], 1)
        normal_force = h["contact_force_n"] * 80.0 / np.asarray(cam.face_position)
    moment = 1e-3 * normal_force * (point[:, 0] * normal[:, 1] - point[:, 1] * normal[:, 0])
    assert np.abs(moment - h["drive_torque_n_m"]).max() < 1e-12 * np.abs(moment).max()
    assert np.abs(moment).max() > 1.0


def test_one_sided_curvature_at_joins_of_any_angles():
    """Harmonic rise straight into a harmonic return over angles that are not whole degrees
    (a quarter of such joins read past their segment when the side was decided by
    comparing rounded angles): every join's radius on both sides against the closed form
    at ``y' = 0``, translating roller ``R^2 / (R - y'') - r_r`` and flat face
    ``r_b + y + y''``; the Hertz factor at a join node a rounding off the join's angle
    (as the dynamics grid places it) takes the side of the larger stress."""
    from camjax.program import node_contact

    law = laws.get("harmonic")
    rng = np.random.default_rng(7)
    for _ in range(12):
        up, down = np.round(rng.uniform(70.0, 140.0, 2), 1) + rng.uniform(0.0, 1e-3, 2)
        rest = 360.0 - up - down
        segments = (Segment(float(up), 10.0, law), Segment(float(down), -10.0, law), Segment(float(rest)))
        # y'' at the ends (mm/rad^2): -h/2 (pi/beta)^2 at the nose, +h/2 (pi/beta)^2 at the return's end
        nose = (-5.0 * (180.0 / up) ** 2, -5.0 * (180.0 / down) ** 2)
        foot = (5.0 * (180.0 / down) ** 2, 0.0)
        roller = Program("p", segments, Follower(**{**FOLLOWER, "base_radius_mm": 20.0, "roller_radius_mm": 3.0,
                                                      "contact_width_mm": 10.0}))
        flat = dict(FOLLOWER, kind="translating-flat", base_radius_mm=40.0)
        flat.pop("roller_radius_mm")
        flat = Program("p", segments, Follower(**flat))
        for join, (lift, sides) in zip(cam_geometry(roller, [0.0]).joins[1:], [(10.0, nose), (0.0, foot)]):
            big_r = 20.0 + 3.0 + lift
            expected = [big_r**2 / (big_r - ydd) - 3.0 for ydd in sides]
            assert [join.radius_before_mm, join.radius_after_mm] == pytest.approx(expected, rel=1e-12)
            for theta in np.nextafter(join.angle_deg, [0.0, 360.0]):  # a rounding off the join
                curvature = max(1 / 3.0 + 1 / rho for rho in expected)  # 1/R', the larger stress
                factor = Materials().contact_modulus_mpa * curvature / (math.pi * 10.0)
                assert node_contact(roller, [theta]).inner[0] == pytest.approx(factor, rel=1e-12)
        for join, (lift, sides) in zip(cam_geometry(flat, [0.0]).joins[1:], [(10.0, nose), (0.0, foot)]):
            assert [join.radius_before_mm, join.radius_after_mm] == pytest.approx(
                [40.0 + lift + ydd for ydd in sides], rel=1e-12)
