"""The follower as a chain of bodies: natural frequencies against closed forms and the
continuous spring, the exact periodic steady state against an independent frequency-domain
solution written here (Fourier series of the lift times the chain's exact response)."""

import dataclasses
import math

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg
import scipy.optimize
from helpers import FOLLOWER, compiled_programs, two_cycloids

from camjax.program import (
    Body,
    Chain,
    ContactForceBound,
    Follower,
    Oscillator,
    Spring,
    SteadyState,
    analyse,
    chain_from_dict,
    jump_speed_rpm,
)

LB = 0.45359237  # kg
LBF_PER_IN_AS_N_PER_MM = 4.4482216152605 / 25.4


def rothbart(units_g=None):
    """Rothbart's valve gear (Cam Design Handbook ch. 11) in SI: lbm exactly, or through
    ``1 lbm = 1 / units_g lbf s^2/in`` where ``units_g`` is given."""
    to_kg = LB if units_g is None else 4.4482216152605 / 0.0254 / units_g
    return Chain(
        (
            Body("lifter", 0.0327 * to_kg),
            Body("valve", 0.110 * to_kg, 3.0e5 * LBF_PER_IN_AS_N_PER_MM),
        ),
        Spring(660 * LBF_PER_IN_AS_N_PER_MM, 100.0),
    )


def two_mass_frequencies(m1, m2, k, ks):
    """The free chain's two frequencies (Hz): roots of m1 m2 w^4 - ((k + ks) m1 + k m2) w^2 + k ks."""
    b = (k + ks) * m1 + k * m2
    w2 = (b + np.array([-1.0, 1.0]) * math.sqrt(b * b - 4 * m1 * m2 * k * ks)) / (2 * m1 * m2)
    return np.sqrt(w2) / (2 * math.pi)


def test_rothbart_free_of_the_cam():
    hz, shapes = rothbart(386.09).natural_frequencies(contact=False)
    m1, m2 = 0.0327 / 386.09, 0.110 / 386.09  # lbf s^2/in
    np.testing.assert_allclose(hz, two_mass_frequencies(m1, m2, 3.0e5, 660.0), rtol=1e-9)
    assert abs(hz[0] / 212.666 - 1) < 1e-5 and abs(hz[1] / 10789.2 - 1) < 1e-5
    # exact lbm: the book's figures as printed, to their digits (67 and 3400 Hz are 3.17 times low)
    hz = rothbart().natural_frequencies(contact=False)[0]
    assert abs(hz[0] - 212.666) < 5e-4 and abs(hz[1] - 10789.2) < 0.05
    assert shapes.shape == (2, 2) and np.allclose(np.max(np.abs(shapes), axis=0), 1.0)
    # held: the valve alone on the pushrod and the spring
    held = rothbart(386.09).natural_frequencies(contact=True)[0]
    np.testing.assert_allclose(held, math.sqrt((3.0e5 + 660.0) / m2) / (2 * math.pi), rtol=1e-12)


SURGING = dict(tappet=0.03, valve=0.05, element=200.0, rate=52.0, spring_mass=0.049)


def surging_chain(**spring):
    s = SURGING
    return Chain(
        (Body("tappet", s["tappet"]), Body("valve", s["valve"], s["element"], 5.0)),
        Spring(s["rate"], 250.0, s["spring_mass"], **spring),
    )


def continuous_held_frequencies(count=3):
    """The valve on its element (tappet held) and on the continuous spring: roots of
    k_e + k_s b cot b - m_v w^2 = 0, b = w sqrt(m_s / k_s), one between each pair of poles."""
    s = SURGING
    ke, ks, ms, mv = 1e3 * s["element"], 1e3 * s["rate"], s["spring_mass"], s["valve"]
    to_b = math.sqrt(ms / ks)

    def det(w):
        b = w * to_b
        return ke + ks * b / math.tan(b) - mv * w * w

    roots = []
    for n in range(count):
        lo, hi = (n * math.pi + 1e-9) / to_b, ((n + 1) * math.pi - 1e-9) / to_b
        roots.append(scipy.optimize.brentq(det, lo, hi, xtol=1e-12, rtol=1e-15) / (2 * math.pi))
    return np.array(roots)


def test_surging_spring_held_frequencies_within_half_a_percent():
    chain = surging_chain()
    hz = chain.natural_frequencies(contact=True)[0][:3]
    reference = continuous_held_frequencies()
    assert np.all(np.abs(hz / reference - 1) < 0.005), (hz, reference)
    fewer = surging_chain(elements=4).natural_frequencies(contact=True)[0][:3]
    assert np.max(np.abs(fewer / reference - 1)) > 0.005  # the setting trades accuracy for states


def test_harmonic_check_orders():
    chain = surging_chain()
    f1 = chain.natural_frequencies()[0][0]
    (hz, orders), *_ = chain.harmonic_check(1000.0, 3000.0)
    assert hz == f1 and orders == [k for k in range(1, 100) if 1000 <= 60 * f1 / k <= 3000]


@pytest.mark.parametrize("rpm", [(3000.0, 1000.0), (-5.0, 1000.0), (0.0, 1000.0), (1000.0, math.inf)])
def test_harmonic_check_refuses_a_bad_speed_range(rpm):
    with pytest.raises(ValueError, match=r"harmonic_check") as error:
        surging_chain().harmonic_check(*rpm)
    assert "\n" not in str(error.value)


def test_a_chain_without_a_spring_moves_freely_off_the_cam():
    """Form-closed (no [spring]): let go of the cam, the chain is one free rigid body, its
    lowest free frequency exactly 0; the other is the two masses on their element,
    sqrt(k (m1 + m2) / (m1 m2)) / 2 pi."""
    chain = Chain((Body("tappet", 0.1), Body("valve", 0.1, 1000.0, 20.0)))
    hz = chain.natural_frequencies(contact=False)[0]
    assert hz[0] == 0.0
    assert hz[1] == pytest.approx(math.sqrt(1e6 * 0.2 / 0.01) / (2 * math.pi), rel=1e-12)


def test_a_rider_on_a_surging_spring_is_rayleighs_effective_mass():
    """One rigid body riding on the cam (no element) on a spring with mass: the coils are
    what vibrates.  Far below the surge, the force at the cam is the rigid body's and the
    spring's with a third of its mass (Rayleigh) and its strain-rate damping (``tau k_s``,
    ``tau = 2 zeta / w_1`` at the continuous spring's first surge):
    (m + m_s / 3) y'' + tau k_s y' + k_s y + F_0, within 1e-3 of the inertial part (the
    surge the rise's jerk leaves; measured 1.05e-4, 2026-11-29)."""
    from camjax.program import response

    m, k_s, m_s, preload = 0.1, 50.0, 0.005, 300.0
    chain = Chain((Body("valve", m),), Spring(k_s, preload, m_s, damping_ratio=0.05))
    program = dataclasses.replace(two_cycloids(), chain=chain)
    out = response(program, 300.0, steady=SteadyState(program, 300.0))
    ddy = out["kinematic_acceleration_m_s2"]
    tau = 2 * 0.05 / (2 * math.pi * 0.5 * math.sqrt(1e3 * k_s / m_s))
    dy = out["valve_velocity_m_s"]
    rigid = (m + m_s / 3) * ddy + tau * 1e3 * k_s * dy + k_s * out["lift_mm"] + preload
    assert np.max(np.abs(out["contact_force_n"] - rigid)) < 1e-3 * (m + m_s / 3) * np.max(np.abs(ddy))
    assert np.max(np.abs(out["payload_acceleration_m_s2"] - ddy)) < 1e-9 * np.max(np.abs(ddy))


def toml_tables(**spring):
    return {
        "follower": {"kind": "translating-roller", "base_radius_mm": 30, "roller_radius_mm": 10},
        "train": [
            {"name": "tappet", "mass_kg": 0.03},
            {
                "name": "valve",
                "mass_kg": 0.05,
                "stiffness_n_per_mm": 200.0,
                "damping_n_s_per_m": 5.0,
            },
        ],
        "spring": {"rate_n_per_mm": 52.0, "preload_n": 250.0, "mass_kg": 0.049, **spring},
    }


def test_program_file_tables_give_the_python_chain():
    assert chain_from_dict(toml_tables()) == surging_chain()
    assert chain_from_dict({"follower": {}}) is None


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda d: d["train"][1].update(mass_kg=-1.0),
            r"body 2 \(valve\) mass_kg must be positive",
        ),
        (lambda d: d["train"][0].pop("mass_kg"), r"body 1 \(tappet\): needs mass_kg"),
        (
            lambda d: d["train"][1].pop("stiffness_n_per_mm"),
            r"body 2 \(valve\): stiffness_n_per_mm is needed",
        ),
        (lambda d: d["train"][1].update(ratio=0.0), r"body 2 \(valve\) ratio must be positive"),
        (
            lambda d: d["train"][1].update(lash_mm=-0.1),
            r"body 2 \(valve\) lash_mm must be non-negative",
        ),
        (
            lambda d: d.update(seat={"stiffness_n_per_mm": 5e4}, spring={"rate_n_per_mm": 52.0}),
            r"\[seat\]: a seat needs a \[spring\] with preload_n > 0",
        ),
        (lambda d: d["spring"].update(elements=2), r"\[spring\] elements = 2 cannot resolve"),
        (
            lambda d: d["follower"].update(mass_kg=1.0),
            r"\[follower\] mass_kg: a file with a \[\[train\]\]",
        ),
        (lambda d: d["train"][1].update(rato=1.6), r"body 2 \(valve\): unknown field\(s\) rato"),
        (
            lambda d: (d["train"].pop(1), d["spring"].pop("mass_kg")),
            r"body 1 \(tappet\): a single body riding on the cam is rigid .* give it "
            r"stiffness_n_per_mm",
        ),
        (
            lambda d: (d["train"].pop(1), d.pop("spring")),
            r"body 1 \(tappet\): a single body riding on the cam is rigid",
        ),
        (lambda d: d["train"][1].update(name=""), r"body 2: name must be a non-empty text"),
        (lambda d: d["train"][1].update(name="  "), r"body 2: name must be a non-empty text"),
        (lambda d: d["train"][1].update(name="tappet"), r"body 2 \(tappet\): name given twice"),
        (
            lambda d: (d.pop("spring"), d["train"][1].update(lash_mm=0.1)),
            r"body 2 \(valve\) lash_mm: a chain without a \[spring\] is form-closed",
        ),
    ],
)
def test_bad_train_input_is_one_line(edit, message):
    data = toml_tables()
    edit(data)
    with pytest.raises(ValueError, match=message) as error:
        chain_from_dict(data)
    assert "\n" not in str(error.value)


# -- the steady state -------------------------------------------------------------------


def chain_steady(program, chain, rpm_min):
    """The steady state of ``program`` driving ``chain``."""
    return SteadyState(dataclasses.replace(program, chain=chain), rpm_min)


class Summary:
    """A chain's figures per speed (``SteadyState.summary`` and its ``TrainPeaks``)."""

    def __init__(self, steady, rpm):
        out = steady.summary(np.asarray(rpm, dtype=float))
        peaks = out.cycles.train
        self.min_contact_force_n, self.max_contact_force_n = (
            out.min_contact_force_n,
            out.max_contact_force_n,
        )
        self.max_acceleration_m_s2 = np.asarray(peaks.max_acceleration_m_s2)
        self.min_seat_force_n, self.max_seat_force_n = (
            peaks.min_seat_force_n,
            peaks.max_seat_force_n,
        )
        self.max_surge_n = peaks.max_surge_n
        self.cycles = out.cycles


def test_one_body_spellings_and_the_classic_follower():
    """The classic fields and a one-body ``[[train]]`` are one chain (same numbers); the
    chain's own realisation (forced by the lift) through the same steady state is the
    classic follower's (forced by its acceleration: the two interpolate different
    derivatives of the lift): 1e-12 of the peaks (measured 5e-13), 1e-10 at the nodes."""
    program = two_cycloids()
    f = program.follower
    tables = {
        "follower": {},
        "train": [
            {
                "name": "follower",
                "mass_kg": f.mass_kg,
                "stiffness_n_per_mm": f.stiffness_n_per_mm,
                "damping_n_s_per_m": f.damping,
            }
        ],
        "spring": {"rate_n_per_mm": f.spring_rate_n_per_mm, "preload_n": f.preload_n},
    }
    assert chain_from_dict(tables) == Chain.of_follower(f)
    rpm = np.array([400.0, 700.0, 1000.0])
    classic = SteadyState(program, 300.0)
    # the chain's own realisation (forced by the lift alone) through the same steady state
    chain = SteadyState(program, 300.0, oscillator=Oscillator.of_chain(Chain.of_follower(f)))
    a, b = classic.cycles(rpm), chain.cycles(rpm)
    for i in range(rpm.size):
        peak_force, peak = a.max_contact_force_n[i], a.max_payload_acceleration_m_s2[i]
        assert np.max(np.abs(b.contact_force_n[i] - a.contact_force_n[i])) < 1e-10 * peak_force
        assert (
            np.max(np.abs(b.payload_acceleration_m_s2[i] - a.payload_acceleration_m_s2[i]))
            < 1e-10 * peak
        )
        assert abs(b.min_contact_force_n[i] - a.min_contact_force_n[i]) < 1e-12 * peak_force
        assert abs(b.max_payload_acceleration_m_s2[i] - peak) < 1e-12 * peak
        assert (
            abs(b.max_drive_torque_n_m[i] - a.max_drive_torque_n_m[i])
            < 1e-12 * a.max_drive_torque_n_m[i]
        )
        np.testing.assert_allclose(
            b.residual_vibration_mm[i], a.residual_vibration_mm[i], rtol=1e-10
        )


def cycloid_lift(s):
    """The two-cycloids program's lift (mm) at turn times ``s`` (written apart from camjax)."""
    deg = 360.0 * np.mod(s, 1.0)

    def cyc(t):
        return t - np.sin(2 * np.pi * t) / (2 * np.pi)

    return np.select(
        [deg < 100, deg < 180, deg < 280],
        [20.0 * cyc(deg / 100), 20.0, 20.0 - 20.0 * cyc((deg - 180) / 100)],
        0.0,
    )


THREE = dict(
    m=(0.4, 0.3, 0.5),
    k=(2.0e6, 1.5e6, 1.0e6),
    c=(60.0, 40.0, 50.0),
    ratio=1.5,
    ks=2.0e4,
    preload=900.0,
)


def three_body_chain(stiffen=1.0, t=THREE):
    bodies = (
        Body("a", t["m"][0], 1e-3 * t["k"][0], t["c"][0]),
        Body("b", t["m"][1], stiffen * 1e-3 * t["k"][1], t["c"][1], ratio=t["ratio"]),
        Body("c", t["m"][2], stiffen * 1e-3 * t["k"][2], t["c"][2]),
    )
    return Chain(bodies, Spring(1e-3 * t["ks"], t["preload"]))


def frequency_domain(rpm, samples=2**17, t=THREE):
    """Contact force (N) and the last body's acceleration (m/s^2) at ``samples`` times of
    the turn: each harmonic of the lift through the chain's exact response, by hand."""
    s = np.arange(samples) / samples
    Y = np.fft.rfft(1e-3 * cycloid_lift(s)) / samples
    w = 2 * np.pi * np.arange(Y.size) * rpm / 60.0
    (m1, m2, m3), (k1, k2, k3), (c1, c2, c3), r = t["m"], t["k"], t["c"], t["ratio"]
    e1, e2, e3 = k1 + 1j * w * c1, k2 + 1j * w * c2, k3 + 1j * w * c3
    Z = np.zeros((Y.size, 3, 3), complex)
    Z[:, 0, 0] = e1 + r * r * e2 - m1 * w**2
    Z[:, 0, 1] = Z[:, 1, 0] = -r * e2
    Z[:, 1, 1] = e2 + e3 - m2 * w**2
    Z[:, 1, 2] = Z[:, 2, 1] = -e3
    Z[:, 2, 2] = e3 + t["ks"] - m3 * w**2
    rhs = np.zeros((Y.size, 3), complex)
    rhs[:, 0] = e1 * Y
    X = np.linalg.solve(Z, rhs[..., None])[..., 0]

    def to_time(spectrum):
        return np.fft.irfft(spectrum, n=samples) * samples

    return t["preload"] * r + to_time(e1 * (Y - X[:, 0])), to_time(-(w**2) * X[:, 2])


def test_three_body_chain_against_the_frequency_domain():
    steady = chain_steady(two_cycloids(), three_body_chain(), 400.0)
    rpm = np.array([600.0, 1100.0])
    summary = Summary(steady, rpm)
    for i, r in enumerate(rpm):
        force, accel = frequency_domain(r)
        scale = np.max(np.abs(force))
        assert abs(summary.min_contact_force_n[i] - force.min()) < 1e-6 * scale
        assert abs(summary.max_contact_force_n[i] - force.max()) < 1e-6 * scale
        peak = np.max(np.abs(accel))
        assert abs(summary.max_acceleration_m_s2[i, 2] - peak) < 1e-6 * peak


def test_an_overdamped_fast_mode_sets_the_grid_and_the_steady_state_holds():
    """A 2000 N s/m damper on the middle element makes an overdamped mode about four times
    faster than the highest natural frequency (|lam| / 2 pi 2710 Hz against 675 Hz): the
    grid resolves it (the propagation's series is exact only within ``MAX_PHASE_STEP`` per
    interval), and the steady state still equals the frequency-domain solution; an
    oscillator faster than a program's grid is refused in one line."""
    damped = dict(THREE, c=(60.0, 2000.0, 50.0))
    chain = three_body_chain(t=damped)
    lam = Oscillator.of_chain(chain).lam
    assert np.max(np.abs(lam)) > 3.5 * 2 * np.pi * chain.highest_frequency_hz()
    steady = chain_steady(two_cycloids(), chain, 400.0)
    widest = np.max(steady.grid.piece_width) * 60.0 / 400.0  # seconds
    assert np.max(np.abs(lam)) * widest <= 0.5 + 1e-12  # every mode at the grid's target step
    rpm = np.array([600.0, 1100.0])
    summary = Summary(steady, rpm)
    for i, r in enumerate(rpm):
        force, accel = frequency_domain(r, t=damped)
        scale = np.max(np.abs(force))
        assert abs(summary.min_contact_force_n[i] - force.min()) < 1e-6 * scale
        assert abs(summary.max_contact_force_n[i] - force.max()) < 1e-6 * scale
        peak = np.max(np.abs(accel))
        assert abs(summary.max_acceleration_m_s2[i, 2] - peak) < 1e-6 * peak
    with pytest.raises(ValueError, match="^oscillator: its fastest mode turns too far per interval"):
        SteadyState(two_cycloids(), 400.0, oscillator=Oscillator.of_chain(chain))  # the classic's grid


def test_three_body_jump_speed_against_the_frequency_domain():
    steady = chain_steady(two_cycloids(), three_body_chain(), 400.0)
    jump = jump_speed_rpm(steady, 400.0, 3000.0, tolerance_rpm=1e-3)
    assert jump is not None

    def low(r):
        return frequency_domain(r, 2**15)[0].min()

    reference = scipy.optimize.brentq(low, jump - 0.5, jump + 0.5, xtol=1e-4)
    assert abs(jump - reference) < 0.01, (jump, reference)
    assert all(
        low(r) > 0 for r in np.linspace(400.0, reference - 0.5, 300)
    )  # the lowest such speed


def test_stiff_elements_tend_to_one_body_of_the_summed_mass():
    program = two_cycloids()
    t = THREE
    total = t["m"][0] + t["ratio"] ** 2 * (
        t["m"][1] + t["m"][2]
    )  # the far bodies seen through the lever
    ks = t["ratio"] ** 2 * t["ks"]
    one = Chain(
        (Body("one", total, 1e-3 * t["k"][0], t["c"][0]),),
        Spring(1e-3 * ks, t["ratio"] * t["preload"]),
    )
    reference = Summary(chain_steady(program, one, 500.0), [800.0]).max_contact_force_n[0]
    gaps = [
        abs(
            Summary(chain_steady(program, three_body_chain(s), 500.0), [800.0]).max_contact_force_n[
                0
            ]
            - reference
        )
        for s in (10.0, 1000.0)
    ]
    assert gaps[1] < 0.02 * gaps[0] and gaps[1] < 1e-3 * reference


def test_seat_force_of_a_surging_spring_against_the_continuous_spring():
    """The valve on its surging spring, driven at its first held mode's third order: the
    seat force's swing against the continuous spring's exact dynamic stiffness."""
    program = two_cycloids()
    chain = surging_chain(damping_ratio=0.05)
    s = SURGING
    rpm = 60 * chain.natural_frequencies()[0][0] / 7.5
    steady = chain_steady(program, chain, rpm)
    summary = Summary(steady, [rpm])
    samples = 2**14
    Y = np.fft.rfft(1e-3 * cycloid_lift(np.arange(samples) / samples)) / samples
    w = 2 * np.pi * np.arange(Y.size) * rpm / 60.0
    ks, ms = 1e3 * s["rate"], s["spring_mass"]
    tau = 2 * 0.05 / (np.pi * math.sqrt(ks / ms))
    k_star = ks * (1 + 1j * w * tau)
    b = w * np.sqrt(ms / k_star)
    b = np.where(w == 0, 1e-30, b)
    body_side = np.where(w == 0, ks, k_star * b / np.tan(b))
    seat_side = np.where(w == 0, ks, k_star * b / np.sin(b))
    ke = 1e3 * s["element"] + 1j * w * 5.0
    X = ke * Y / (ke + body_side - s["valve"] * w**2)  # the tappet rides on the cam: x_1 = y
    seat = 250.0 + np.fft.irfft(seat_side * X, n=samples) * samples
    swing = seat.max() - seat.min()
    assert abs(summary.max_seat_force_n[0] - seat.max()) < 0.01 * swing
    assert abs(summary.min_seat_force_n[0] - seat.min()) < 0.01 * swing
    assert summary.max_surge_n[0] > 0.02 * swing  # the surge is there to measure


def test_an_edit_of_values_compiles_nothing():
    program = two_cycloids()
    chain_steady(program, three_body_chain(), 500.0).summary(np.array([600.0, 900.0]))
    edited = Chain(
        tuple(
            b.__class__(**{**b.__dict__, "mass_kg": 1.1 * b.mass_kg})
            for b in three_body_chain().bodies
        ),
        Spring(25.0, 800.0),
    )
    steady = chain_steady(program, edited, 500.0)
    assert (
        steady.turn.grid.motion.nodes.shape
        == chain_steady(program, three_body_chain(), 500.0).turn.grid.motion.nodes.shape
    )
    with compiled_programs() as names:
        steady.summary(np.array([600.0, 700.0, 900.0]))
    assert "_cycles" not in names, names


def test_the_classic_fields_build_the_one_body_chain():
    follower = Follower(**FOLLOWER)
    chain = Chain.of_follower(follower)
    hz = chain.natural_frequencies()[0]
    np.testing.assert_allclose(hz, follower.natural_frequency_hz, rtol=1e-12)
    modes = Oscillator.of_chain(chain)
    np.testing.assert_allclose(
        np.sort(np.abs(modes.lam)), 2 * math.pi * follower.natural_frequency_hz, rtol=1e-12
    )
    # contact, payload acceleration and displacement, the body's acceleration, seat force,
    # surge and lift error: the preload at the cam and at the seat
    preload = follower.preload_n
    assert scipy.linalg.norm(modes.static - [preload, 0, 0, 0, preload, 0, 0]) == 0


def test_the_steady_state_refuses_what_it_does_not_model():
    lash = Chain(
        (Body("tappet", 0.03), Body("valve", 0.05, 200.0, 5.0, lash_mm=0.2)), Spring(52.0, 250.0)
    )
    with pytest.raises(ValueError, match=r"body 2 \(valve\) lash_mm: .* simulated \(ChainContacts\)"):
        Oscillator.of_chain(lash)
    with pytest.raises(ValueError, match="nothing to vibrate"):
        Chain((Body("tappet", 0.03),), Spring(52.0, 250.0))


# -- every output of the one-body follower, for a chain ---------------------------------


def cycloid_slope(deg):
    """The two-cycloids program's ``dy/dtheta`` (mm/deg), by hand."""
    deg = np.mod(deg, 360.0)
    rise = 0.2 * (1 - np.cos(2 * np.pi * deg / 100))
    fall = -0.2 * (1 - np.cos(2 * np.pi * (deg - 180) / 100))
    return np.select([deg < 100, deg < 180, deg < 280], [rise, 0.0, fall], 0.0)


def test_a_chains_drive_torque_is_its_contact_force_times_the_velocity_ratio():
    """``T = F_c dy/dtheta``: the three-body chain's peak drive torque against the
    frequency-domain contact force times the cam's own slope, written here."""
    program = dataclasses.replace(two_cycloids(), chain=three_body_chain())
    rpm = np.array([600.0, 1100.0])
    rows = SteadyState(program, 400.0).summary(rpm)
    samples = 2**17
    slope = cycloid_slope(360.0 * np.arange(samples) / samples) * 180 / math.pi * 1e-3  # m per rad
    for i, r in enumerate(rpm):
        torque = frequency_domain(r, samples)[0] * slope
        peak = np.max(np.abs(torque))
        assert abs(rows.max_drive_torque_n_m[i] - peak) < 1e-6 * peak
        assert abs(rows.mean_drive_torque_n_m[i] - torque.mean()) < 1e-6 * peak


TWO_FREE = dict(m=(0.4, 0.5), k=(2.0e6, 1.0e6), c=(60.0, 50.0), ks=2.0e4, preload=900.0)


def two_free_bodies():
    t = TWO_FREE
    return Chain(
        (
            Body("a", t["m"][0], 1e-3 * t["k"][0], t["c"][0]),
            Body("b", t["m"][1], 1e-3 * t["k"][1], t["c"][1]),
        ),
        Spring(1e-3 * t["ks"], t["preload"]),
    )


def test_a_chains_residual_vibration_against_scipy_over_the_dwell():
    """Two bodies on elements (two modes): the periodic state at the dwell's start by a
    scipy shooting solve, the last body's free vibration over the dwell by solve_ivp, and
    its envelope ``sum_j |c_j|`` from scipy's own eigenvectors: the report's residual is
    that envelope, and the vibration over the dwell stays under it."""
    t = TWO_FREE
    (m1, m2), (k1, k2), (c1, c2), ks = t["m"], t["k"], t["c"], t["ks"]
    rpm = 900.0
    period = 60.0 / rpm
    rate = 360.0 / period
    program = dataclasses.replace(two_cycloids(), chain=two_free_bodies())
    residual = SteadyState(program, rpm).summary(np.array([rpm])).residual_vibration_mm[0]

    def field(time, z, hold=None):
        y = 1e-3 * (cycloid_lift(time / period) if hold is None else hold)
        dy = 0.0 if hold is not None else 1e-3 * cycloid_slope(rate * time) * rate
        x1, x2, v1, v2 = z
        f1 = k1 * (y - x1) + c1 * (dy - v1) - k2 * (x1 - x2) - c2 * (v1 - v2)
        f2 = k2 * (x1 - x2) + c2 * (v1 - v2) - ks * x2
        return [v1, v2, f1 / m1, f2 / m2]

    options = dict(method="DOP853", rtol=1e-12, atol=1e-15)
    edges = np.array([0.0, 100.0, 180.0, 280.0, 360.0]) / rate

    def turn(z0, stop=360.0):
        z = np.asarray(z0, dtype=float)
        for a, b in zip(edges[:-1], edges[1:]):
            b = min(b, stop / rate)
            if b > a:
                z = scipy.integrate.solve_ivp(field, (a, b), z, **options).y[:, -1]
        return z

    c = turn(np.zeros(4))
    phi = np.stack([turn(e) - c for e in np.eye(4)], axis=1)
    start = np.linalg.solve(np.eye(4) - phi, c)  # the periodic state at 0 deg
    at_dwell = turn(start, stop=100.0)
    h = cycloid_lift(100.0 / 360.0)
    static = np.linalg.solve([[k1 + k2, -k2], [-k2, k2 + ks]], [k1 * 1e-3 * h, 0.0])
    free = at_dwell - np.concatenate([static, [0.0, 0.0]])
    A = np.array(
        [
            [0, 0, 1, 0],
            [0, 0, 0, 1],
            [-(k1 + k2) / m1, k2 / m1, -(c1 + c2) / m1, c2 / m1],
            [k2 / m2, -(k2 + ks) / m2, c2 / m2, -(c2) / m2],
        ]
    )
    lam, V = scipy.linalg.eig(A)
    amplitudes = V[1] * np.linalg.solve(V, free)  # x2's free vibration: sum_j a_j exp(lam_j t)
    envelope = 1e3 * np.sum(np.abs(amplitudes))
    assert abs(residual[0] - envelope) < 1e-6 * envelope
    dwell = scipy.integrate.solve_ivp(
        lambda s, z: field(s, z, hold=h), (0.0, 80.0 / rate), at_dwell, dense_output=True, **options
    )
    tau = np.linspace(0.0, 80.0 / rate, 20001)
    vibration = 1e3 * (dwell.sol(tau)[1] - static[1])
    modal = 1e3 * np.real(np.exp(np.outer(tau, lam)) @ amplitudes)
    assert np.max(np.abs(vibration - modal)) < 1e-7 * envelope  # the modes are the dwell's motion
    assert np.max(np.abs(vibration)) <= envelope * (1 + 1e-9)
    assert np.max(np.abs(vibration)) > 0.3 * envelope


def test_a_stiffening_chain_tends_to_the_one_body_follower_in_every_output():
    """The three-body chain's drive torque, Hertz stress and residual vibration (the last
    body's, through the lever) tend to the one body's of the lever-reduced mass."""
    program = two_cycloids(contact_width_mm=12.0)
    t = THREE
    total = t["m"][0] + t["ratio"] ** 2 * (t["m"][1] + t["m"][2])
    one = Chain(
        (Body("one", total, 1e-3 * t["k"][0], t["c"][0]),),
        Spring(1e-3 * t["ratio"] ** 2 * t["ks"], t["ratio"] * t["preload"]),
    )
    rpm = [800.0]

    def outputs(chain, scale=1.0):
        report = analyse(dataclasses.replace(program, chain=chain), rpm, with_flight=False)
        row = report.speeds[0]
        return np.array(
            [row.max_drive_torque_n_m, row.max_contact_stress_mpa, *row.residual_vibration_mm]
        ) / np.array([1.0, 1.0, scale, scale])

    reference = outputs(one)
    gaps = [np.abs(outputs(three_body_chain(s), t["ratio"]) - reference) for s in (10.0, 1000.0)]
    assert np.all(gaps[1] < 0.05 * gaps[0]), gaps
    assert np.all(gaps[1] < 2e-3 * reference), (gaps, reference)


@pytest.mark.parametrize("chain, slowest", [("three", 200.0), ("surging", 1000.0)])
def test_the_contact_force_bound_holds_for_a_chain(chain, slowest):
    """``ContactForceBound`` summed over a chain's modes stays below its least contact
    force, and still rules out the low speeds (where the jump's scan is densest)."""
    built = three_body_chain() if chain == "three" else surging_chain(damping_ratio=0.05)
    steady = chain_steady(two_cycloids(), built, slowest)
    rpm = np.geomspace(slowest, 3000.0, 32)
    force = steady.min_contact_force_n(rpm)
    bound = ContactForceBound(steady)(rpm)
    assert np.all(bound <= force), (rpm[bound > force], bound[bound > force], force[bound > force])
    assert ContactForceBound(steady).first_unheld(rpm) > 0  # the lowest speeds need no steady state
