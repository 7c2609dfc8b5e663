"""Servo drives: motor sizing against an independent steady state, and dynamic compensation
against its closed form and an independent simulation (scipy ``solve_ivp``)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import betainc

from camjax import laws
from camjax.program import (
    Drive,
    Follower,
    Motor,
    Program,
    Segment,
    choose_motor,
    compensate,
    compensated_lift,
    duty_cycle,
    read_motors,
    response,
    size_motor,
)

RPM = 120.0
STROKE_MM = 40.0
FOLLOWER = Follower(
    mass_kg=4.0, stiffness_n_per_mm=200, damping_ratio=0.05, spring_rate_n_per_mm=2, preload_n=50
)
DRIVE = Drive(
    travel_mm_per_rev=20,
    gear_ratio=2.0,
    transmission_efficiency=0.9,
    gearbox_efficiency=0.95,
    motor_side_inertia_kg_m2=2e-5,
    gearbox_inertia_kg_m2=1e-5,
    load_side_inertia_kg_m2=5e-5,
)
CATALOGUE = """name,maximum_speed_rpm,maximum_torque_n_m,continuous_stall_torque_n_m,rotor_inertia_kg_m2,envelope
big,4500,7.2,2.4,2.6e-4,0:7.2 3000:7.2 4500:4
tiny,6000,0.5,0.1,1.7e-5,
small,6000,1.9,0.64,4.2e-5,0:1.9 3500:1.9 6000:0.9
medium,6000,3.8,1.3,1.2e-4,0:3.8 3500:3.8 6000:1.8
"""
SEGMENTS = [(30.0, 0.0), (120.0, STROKE_MM), (60.0, 0.0), (120.0, -STROKE_MM), (30.0, 0.0)]


def _cycloidal_program() -> Program:
    cycloidal = laws.get("cycloidal")
    return Program(
        "servo-test", tuple(Segment(a, h, cycloidal if h else None) for a, h in SEGMENTS), FOLLOWER
    )


def _cycloidal_lift(theta_deg: float) -> tuple[float, float, float]:
    """The test cam's lift (mm) and its derivatives per degree, written out independently."""
    theta = theta_deg % 360.0
    start, base = 0.0, 0.0
    for angle, h in SEGMENTS:
        if theta < start + angle or start + angle >= 360.0:
            if h == 0:
                return base, 0.0, 0.0
            tau = (theta - start) / angle
            s = tau - math.sin(2 * math.pi * tau) / (2 * math.pi)
            v = 1 - math.cos(2 * math.pi * tau)
            a = 2 * math.pi * math.sin(2 * math.pi * tau)
            return base + h * s, h * v / angle, h * a / angle**2
        start, base = start + angle, base + h
    raise AssertionError("unreachable")


def _steady_contact_force(theta_nodes: np.ndarray) -> np.ndarray:
    """The contact force of the periodic steady state at ``RPM``, by integrating the follower
    (``m x'' = k (y - x) + c (y' - x') - k_s x``) from rest over six turns with scipy."""
    f = FOLLOWER
    m, k, c, ks = f.mass_kg, f.stiffness, f.damping, f.spring_rate
    omega = 360.0 * RPM / 60.0  # degrees per second
    turn = 60.0 / RPM

    def rhs(t, state):
        x, v = state
        y, dy, _ = _cycloidal_lift(omega * t)
        y, dy = 1e-3 * y, 1e-3 * dy * omega
        return [v, (k * (y - x) + c * (dy - v) - ks * x) / m]

    turns = 6
    t_eval = (turns - 1) * turn + theta_nodes / omega
    sol = solve_ivp(
        rhs, (0.0, turns * turn), [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-15, t_eval=t_eval
    )
    assert sol.success
    lift = np.array([_cycloidal_lift(th) for th in theta_nodes])
    y, dy = 1e-3 * lift[:, 0], 1e-3 * lift[:, 1] * omega
    return f.preload_n + k * (y - sol.y[0]) + c * (dy - sol.y[1])


def _motor_figures(theta: np.ndarray, force: np.ndarray, motor: Motor) -> dict:
    """Peak and RMS torque, inertia ratio written out from the equations (docs/servo.md)."""
    omega = 360.0 * RPM / 60.0
    lift = np.array([_cycloidal_lift(th) for th in theta])
    velocity, acceleration = 1e-3 * lift[:, 1] * omega, 1e-3 * lift[:, 2] * omega**2
    r = 20e-3 / 2.0 / (2 * math.pi)  # m per motor radian
    eta = 0.9 * 0.95
    load = np.where(force * velocity >= 0, force * r / eta, force * r * eta)
    inertia = motor.rotor_inertia_kg_m2 + 2e-5 + 1e-5 + 5e-5 / 4.0
    torque = inertia * acceleration / r + load
    rms = math.sqrt(np.trapezoid(torque**2, theta) / 360.0)
    ratio = (2e-5 + 1e-5 + 5e-5 / 4.0 + FOLLOWER.mass_kg * r**2) / motor.rotor_inertia_kg_m2
    return {
        "peak": np.abs(torque).max(),
        "rms": rms,
        "ratio": ratio,
        "speed": np.abs(velocity / r * 60 / (2 * math.pi)).max(),
    }


@pytest.fixture(scope="module")
def sized(tmp_path_factory):
    program = _cycloidal_program()
    history = response(program, RPM)
    path = tmp_path_factory.mktemp("motors") / "catalogue.csv"
    path.write_text(CATALOGUE)
    motors = read_motors(path)
    duty = duty_cycle(program, DRIVE, RPM, history)
    return program, history, motors, duty, choose_motor(motors, [duty])


def test_motor_torque_equals_an_independent_steady_state(sized):
    """Peak and RMS torque (dynamic and rigid), the inertia ratio and the largest speed of
    every motor equal the equations evaluated on scipy's steady state to 1e-6."""
    program, history, motors, duty, choice = sized
    theta = history["theta_deg"]
    dynamic = _steady_contact_force(theta)
    lift = np.array([_cycloidal_lift(th) for th in theta])
    omega = 360.0 * RPM / 60.0
    rigid = (
        FOLLOWER.mass_kg * 1e-3 * lift[:, 2] * omega**2
        + FOLLOWER.spring_rate * 1e-3 * lift[:, 0]
        + FOLLOWER.preload_n
    )
    for motor, (sizing,) in zip(motors, choice.sizings):
        for load, force in ((sizing.dynamic, dynamic), (sizing.rigid, rigid)):
            expected = _motor_figures(theta, force, motor)
            assert load.peak_torque_n_m == pytest.approx(expected["peak"], rel=1e-6)
            assert load.rms_torque_n_m == pytest.approx(expected["rms"], rel=1e-6)
            assert load.max_speed_rpm == pytest.approx(expected["speed"], rel=1e-9)
        assert sizing.inertia_ratio == pytest.approx(expected["ratio"], rel=1e-12)
    # the dynamic load differs from the rigid one here: the test would see a swapped force
    assert (
        abs(
            choice.sizings[0][0].dynamic.peak_torque_n_m
            / choice.sizings[0][0].rigid.peak_torque_n_m
            - 1
        )
        > 1e-4
    )


def test_catalogue_picks_the_smallest_passing_motor(sized):
    """The pick is the passing motor of least continuous stall torque, found here from the
    independent figures and the stated limits (RMS <= 80% continuous, peak within the
    envelope and maximum torque, speed, inertia ratio <= 10)."""
    program, history, motors, duty, choice = sized
    dynamic = _steady_contact_force(history["theta_deg"])
    passing = []
    for motor in motors:
        fig = _motor_figures(history["theta_deg"], dynamic, motor)
        ok = (
            fig["rms"] <= 0.8 * motor.continuous_stall_torque_n_m
            and fig["peak"] <= motor.maximum_torque_n_m
            and fig["speed"] <= motor.maximum_speed_rpm
            and fig["ratio"] <= 10
        )
        passing += [motor] if ok else []
    expected = min(passing, key=lambda m: m.continuous_stall_torque_n_m)
    assert choice.picked.name == expected.name == "small"


def test_a_failing_motor_names_its_check_and_margin(sized):
    program, history, motors, duty, choice = sized
    tiny = next(m for m in motors if m.name == "tiny")
    sizing = size_motor(tiny, duty)
    failed = [c for c in sizing.dynamic.checks if not c.passed]
    rms = next(c for c in failed if c.name.startswith("rms"))
    assert rms.value == pytest.approx(sizing.dynamic.rms_torque_n_m / 0.1, rel=1e-12)
    assert rms.margin == pytest.approx(1 - rms.value / 0.8, rel=1e-12)
    lone = choose_motor([tiny], [duty])
    assert lone.picked is None and lone.closest.name == "tiny"
    worst = min(sizing.dynamic.checks, key=lambda c: c.margin)
    assert lone.closest_check == worst
    assert lone.summary() == (
        f"no motor passes; the closest, tiny, fails {worst.name}: {worst.value:.4g} against "
        f"{worst.limit:.4g} (by {-100 * worst.margin:.1f}%)"
    )


def test_a_torque_past_the_envelope_is_said_in_words_not_inf():
    """A torque asked where the envelope gives none divides by zero: the check's shortfall
    says so instead of "inf against 1 (by inf%)"."""
    from camjax.program import Check

    past = Check.of("peak torque / envelope (worst point)", math.inf, 1.0)
    assert not past.passed and past.shortfall() == (
        "no bound against 1 (a torque asked at a speed past the envelope, where the motor "
        "gives none)"
    )
    slow = Check.of("max speed / maximum speed", 3.6, 1.0)
    assert slow.shortfall() == "3.6 against 1 (by 260.0%)"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "name,maximum_speed_rpm,maximum_torque_n_m,rotor_inertia_kg_m2\nm,6000,2,1e-4\n",
            "row 2 (motor 'm'): missing continuous_stall_torque_n_m, which the checks need",
        ),
        (
            "name,maximum_speed_rpm,maximum_torque_n_m,continuous_stall_torque_n_m,rotor_inertia_kg_m2,envelope\n"
            "m,6000,2,1,1e-4,0:2 3000:2 2000:1\n",
            "row 2: motor 'm': envelope is not a function of speed: its speeds must start at 0 and rise strictly",
        ),
    ],
)
def test_bad_motor_records(tmp_path, text, message):
    path = tmp_path / "m.csv"
    path.write_text(text)
    with pytest.raises(
        ValueError,
        match="^"
        + str(path).replace("\\", "\\\\")
        + ": "
        + message.replace("(", r"\(").replace(")", r"\)"),
    ):
        read_motors(path)


def test_a_transmission_of_zero_is_refused():
    with pytest.raises(
        ValueError, match=r"^\[drive\] travel_mm_per_rev is zero: a transmission of zero moves"
    ):
        Drive(travel_mm_per_rev=0.0)
    with pytest.raises(ValueError, match=r"^\[drive\] gear_ratio is zero"):
        Drive(travel_mm_per_rev=10.0, gear_ratio=0)


def test_program_file_reads_drive_and_motor(tmp_path):
    from camjax.program import example_path

    program = Program.load(example_path("servo"))
    assert program.drive.travel_mm_per_rev == 20 and [m.name for m in program.motors][:2] == [
        "S1-040",
        "S2-060",
    ]
    again = Program.from_dict(__import__("tomllib").loads(program.to_toml()))
    assert again.drive == program.drive and again.motors == program.motors


# -- compensation ------------------------------------------------------------------------

C4_LAW = laws.PolynomialLaw(5)  # degree 9: derivatives up to the fourth vanish at both ends


def _c4_program(follower: Follower) -> Program:
    return Program("c4", tuple(Segment(a, h, C4_LAW if h else None) for a, h in SEGMENTS), follower)


def test_one_body_compensation_equals_the_closed_form():
    """``y = x + (m x'' + k_s x + F_0) / k`` to 1e-9 of the stroke (undamped train)."""
    follower = Follower(mass_kg=4.0, stiffness_n_per_mm=200, spring_rate_n_per_mm=2, preload_n=50)
    program = _c4_program(follower)
    theta = np.arange(5760) * (360.0 / 5760)
    x, _, ddx = program.lift(theta)
    omega = 360.0 * RPM / 60.0
    y = 1e3 * compensated_lift(1e-3 * x, 60.0 / RPM, [4.0], [2e5], [0.0], [1.0], 2e3, 50.0)
    closed = x + 1e3 * (4.0 * 1e-3 * ddx * omega**2 + 2e3 * 1e-3 * x + 50.0) / 2e5
    assert np.abs(y - closed).max() < 1e-9 * STROKE_MM
    assert np.abs(y - x).max() > 1e-3 * STROKE_MM  # the correction is not negligible here


def _beta_rise(order: int) -> np.polynomial.Polynomial:
    """``s(tau)`` of the symmetric rise whose first ``order - 1`` derivatives vanish at both
    ends (``integral of tau^(k-1) (1 - tau)^(k-1)``, normalised), written out here."""
    P = np.polynomial.Polynomial
    s = (P([0, 1]) ** (order - 1) * P([1, -1]) ** (order - 1)).integ()
    return s / s(1.0)


CHAIN = {
    "masses": [0.4, 1.0, 2.0],
    "stiffnesses": [4e6, 1e6, 4e5],
    "ratios": [1.0, 1.5, 0.8],
    "spring_rate": 5e3,
    "preload": 0.0,
}
CHAIN_ORDER = 10  # derivatives up to the ninth continuous: the three-body inverse takes six
CHAIN_STROKE = 0.01  # m
CHAIN_PERIOD = 0.25  # s: the payload's rise lasts a quarter of it


def _chain_payload(t: np.ndarray, order: int = 0) -> np.ndarray:
    """The payload's motion over one period, a quarter each: rise, dwell, return, dwell;
    the rise itself as scipy's regularised incomplete beta function (no round-off step at
    its ends), its derivatives from the written-out polynomial."""
    s = _beta_rise(CHAIN_ORDER)

    def rise(tau):  # s^(order)(tau)
        tau = np.clip(tau, 0.0, 1.0)
        return betainc(CHAIN_ORDER, CHAIN_ORDER, tau) if order == 0 else s.deriv(order)(tau)

    quarter = CHAIN_PERIOD / 4
    u = np.mod(t, CHAIN_PERIOD)
    up = np.where(u < quarter, rise(u / quarter), 0.0)
    back = np.where((u >= 2 * quarter) & (u < 3 * quarter), -rise(u / quarter - 2), 0.0)
    plateau = np.where((u >= quarter) & (u < 3 * quarter), 1.0, 0.0) if order == 0 else 0.0
    return CHAIN_STROKE * (up + back + plateau) / quarter**order


def test_three_body_compensation_equals_the_closed_form():
    """The backward recursion through each element written out with the law's derivatives
    (undamped): ``x_{j-1} = (x_j + f_j / k_j) / r_j``, ``f_{j-1} = m_{j-1} x_{j-1}'' + r_j f_j``."""
    n = 2**15
    t = np.arange(n) * (CHAIN_PERIOD / n)
    m, k, r = CHAIN["masses"], CHAIN["stiffnesses"], CHAIN["ratios"]
    d = [_chain_payload(t, i) for i in range(7)]  # x_3 and its derivatives
    f3 = [m[2] * d[i + 2] + CHAIN["spring_rate"] * d[i] for i in range(5)]  # f_3 and derivatives
    x2 = [(d[i] + f3[i] / k[2]) / r[2] for i in range(5)]
    f2 = [m[1] * x2[i + 2] + r[2] * f3[i] for i in range(3)]
    x1 = [(x2[i] + f2[i] / k[1]) / r[1] for i in range(3)]
    f1 = m[0] * x1[2] + r[1] * f2[0]
    closed = (x1[0] + f1 / k[0]) / r[0]
    y = compensated_lift(d[0], CHAIN_PERIOD, dampings=[0.0, 0.0, 0.0], **CHAIN)
    assert np.abs(y - closed).max() < 1e-9 * CHAIN_STROKE
    assert np.abs(y - d[0]).max() > 1e-3 * CHAIN_STROKE


def test_three_body_payload_follows_the_law_in_an_independent_simulation():
    """A damped chain driven by its compensated input (the input's Fourier series, exact
    between samples) from rest in the dwell: the payload follows the law to 1e-6 of the
    stroke over two periods (scipy DOP853)."""
    m, k, r = (np.array(CHAIN[key]) for key in ("masses", "stiffnesses", "ratios"))
    c = 2 * 0.05 * np.sqrt(k * m)
    n = 2**14
    t = np.arange(n) * (CHAIN_PERIOD / n)
    y = compensated_lift(_chain_payload(t), CHAIN_PERIOD, m, k, c, r, CHAIN["spring_rate"])
    spectrum = np.fft.rfft(y) / n
    keep = np.flatnonzero(np.abs(spectrum) > 1e-16 * CHAIN_STROKE)
    w = 2 * np.pi * keep / CHAIN_PERIOD
    weight = np.where(keep == 0, 1.0, 2.0) * spectrum[keep]

    def cam(time):
        phase = np.exp(1j * w * time)
        return float(np.real(np.sum(weight * phase))), float(
            np.real(np.sum(1j * w * weight * phase))
        )

    def rhs(time, state):
        x, v = state[:3], state[3:]
        y0, dy0 = cam(time)
        below, dbelow = np.array([y0, x[0], x[1]]), np.array([dy0, v[0], v[1]])
        force = k * (r * below - x) + c * (r * dbelow - v)
        spring = np.array([0.0, 0.0, CHAIN["spring_rate"] * x[2]])
        pushed_back = np.append(r[1:] * force[1:], 0.0)
        return np.concatenate([v, (force - pushed_back - spring) / m])

    # at rest in the dwell before the rise: each body at its (zero) static position
    start = 0.9 * CHAIN_PERIOD
    sol = solve_ivp(
        rhs,
        (start, start + 2 * CHAIN_PERIOD),
        np.zeros(6),
        method="DOP853",
        rtol=1e-12,
        atol=1e-16,
        dense_output=True,
    )
    assert sol.success
    times = np.linspace(start, start + 2 * CHAIN_PERIOD, 4001)
    error = np.abs(sol.sol(times)[2] - _chain_payload(times))
    assert error.max() < 1e-6 * CHAIN_STROKE


def test_program_compensation_drives_the_payload_along_the_law():
    """The compensated whole-cam table, read back as a program, makes camjax's own steady
    state follow the law at the design speed to 1e-6 of the stroke (and the table equals
    the inverse at its points)."""
    program = _c4_program(FOLLOWER)
    compensation = compensate(program, RPM)
    history = response(compensation.program, RPM)
    law, _, _ = program.lift(history["theta_deg"])
    assert np.abs(history["payload_displacement_mm"] - law).max() < 1e-6 * STROKE_MM
    uncompensated = response(program, RPM)
    law0, _, _ = program.lift(uncompensated["theta_deg"])
    assert np.abs(uncompensated["payload_displacement_mm"] - law0).max() > 1e-3 * STROKE_MM


@pytest.mark.parametrize(
    ("law", "message"),
    [
        ("poly4567", "fourth derivative steps at 30 deg"),
        ("cycloidal", "jerk steps at 30 deg"),
    ],
)
def test_compensation_refuses_a_rough_law(law, message):
    program = Program(
        "rough", tuple(Segment(a, h, laws.get(law) if h else None) for a, h in SEGMENTS), FOLLOWER
    )
    with pytest.raises(ValueError, match=message) as error:
        compensate(program, RPM)
    assert "degree 9" in str(error.value) and "\n" not in str(error.value)


def test_compensation_refuses_lash_and_separation():
    grooved = Follower(
        mass_kg=4.0, stiffness_n_per_mm=200, damping_ratio=0.05, groove_clearance_mm=0.05
    )
    with pytest.raises(ValueError, match="has lash"):
        compensate(_c4_program(grooved), RPM)
    light = Follower(
        mass_kg=4.0,
        stiffness_n_per_mm=200,
        damping_ratio=0.05,
        spring_rate_n_per_mm=0.1,
        preload_n=1,
    )
    with pytest.raises(ValueError, match="compensation needs contact held at 120 rpm"):
        compensate(_c4_program(light), RPM)


def test_motor_toml_reads_as_the_catalogue_row():
    from camjax.program import example_path

    (toml,) = read_motors(example_path("motor"))
    catalogue = read_motors(example_path("servo").parent / "motors.csv")
    assert toml == next(m for m in catalogue if m.name == "S2-060")


def _cli(capsys, *argv):
    from camjax.cli import main

    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_refuses_a_bad_motor_file_and_a_rough_law_in_one_line(tmp_path, capsys, monkeypatch):
    """Both fail before the analysis: a catalogue missing a field the checks need, and
    ``--compensate`` of a program whose laws are too rough (the built-in indexer's)."""
    monkeypatch.setenv("CAMJAX_CACHE_DIR", "off")
    catalogue = tmp_path / "bad.csv"
    catalogue.write_text(
        "name,maximum_speed_rpm,maximum_torque_n_m,rotor_inertia_kg_m2\nm,6000,2,1e-4\n"
    )
    code, out, err = _cli(capsys, "program", "servo", "--motor", str(catalogue))
    assert code != 0 and out == "" and len(err.strip().splitlines()) == 1
    assert "missing continuous_stall_torque_n_m, which the checks need" in err
    code, out, err = _cli(
        capsys, "program", "indexer", "--compensate", "300", "--out", str(tmp_path / "o")
    )
    assert (
        code != 0
        and len(err.strip().splitlines()) == 1
        and "jerk steps" in err
        and "degree 9" in err
    )


def test_a_rotary_axis_drive_is_the_linear_drive_of_its_arc(sized):
    """``degrees_per_rev`` with an arm moves the follower ``radians(degrees) * arm`` mm per
    drive revolution: the duty equals that of a screw with that lead; without an arm (a
    translating follower) the drive is refused in one line."""
    import dataclasses

    program, history, _, duty, _ = sized
    degrees, arm = 30.0, 20.0 / math.radians(30.0)  # the arc of DRIVE's 20 mm lead
    rotary = dataclasses.replace(DRIVE, travel_mm_per_rev=None, degrees_per_rev=degrees, arm_mm=arm)
    turned = duty_cycle(program, rotary, RPM, history)
    for name in ("motor_speed_rpm", "motor_acceleration_rad_s2", "dynamic_torque_n_m", "rigid_torque_n_m"):
        np.testing.assert_allclose(getattr(turned, name), getattr(duty, name), rtol=1e-12, atol=1e-12)
    assert turned.load_inertia_kg_m2 == pytest.approx(duty.load_inertia_kg_m2, rel=1e-12)
    armless = dataclasses.replace(rotary, arm_mm=None)
    with pytest.raises(ValueError, match=r"^\[drive\] degrees_per_rev needs arm_mm") as error:
        duty_cycle(program, armless, RPM, history)
    assert "\n" not in str(error.value)
