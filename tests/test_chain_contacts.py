"""A chain with lash and a seat: its simulated periodic steady state against independent
references (the ramp's velocity, an event-driven scipy integration written here, the closed
chain's exact steady state) and its refusals."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
import scipy.integrate
import scipy.optimize
from helpers import two_cycloids

import camjax.geometry
from camjax.program import (
    Body,
    Chain,
    ChainContacts,
    ContactOptions,
    Program,
    Seat,
    Spring,
    SteadyState,
    analyse,
    contacts_note,
    flights_at,
)

EXAMPLE = "camjax/program/examples/trains/valve_lash.toml"
RAMP_MM_PER_DEG = 0.01  # the example's ramps


@pytest.fixture(scope="module")
def example():
    return Program.load(EXAMPLE)


@pytest.fixture(scope="module")
def example_turns(example):
    return ChainContacts(example, example.chain, 1000.0).turns([1000.0, 3000.0])


def test_lash_closing_on_a_ramp_seats_at_the_ramp_velocity(example, example_turns):
    """At low speed the valve lands at the closing ramp's velocity through the rocker."""
    slow = example_turns[0]
    ratio = example.chain.bodies[1].ratio
    ramp = 1e-3 * RAMP_MM_PER_DEG * 360.0 * slow.rpm / 60.0 * ratio  # m/s at the valve
    assert slow.seating_velocity_m_s == pytest.approx(ramp, rel=0.03)
    # the valve seats on the closing ramp, the lash opens after it, and once a turn
    closing_ramp = (9 + 20 + 75 + 75, 9 + 20 + 75 + 75 + 20)
    assert list(slow.lash_openings_deg) == ["valve"]
    (opening,) = slow.lash_openings_deg["valve"]
    assert closing_ramp[0] < opening < closing_ramp[1] + 9
    assert not slow.separates["cam"] and not slow.separates["valve"]


def _event_driven(program, chain: Chain, rpm: float, turns: int = 3):
    """The valve of a tappet held on the cam, with lash and a seat, integrated with scipy
    from event to event (each contact open or closed, switched where its approach or force
    crosses zero), from rest for ``turns`` turns: the seat's landings of the last turn as
    ``(angle_deg, velocity_m_s)``."""
    _, valve = chain.bodies
    k, c, r, lash = (
        1e3 * valve.stiffness_n_per_mm,
        valve.damping_n_s_per_m,
        valve.ratio,
        1e-3 * valve.lash_mm,
    )
    ks, preload = 1e3 * chain.spring.rate_n_per_mm, chain.spring.preload_n
    kseat, cseat = 1e3 * chain.seat.stiffness_n_per_mm, chain.seat.damping_n_s_per_m
    m = valve.mass_kg
    period = 60.0 / rpm
    w = 360.0 / period  # deg/s

    def cam(t):
        y, dy, ddy, _ = program.turn.jet(np.atleast_1d(w * t % 360.0))
        return 1e-3 * y[0], 1e-3 * dy[0] * w

    def parts(t, z):
        y, yd = cam(t)
        a, ad = -lash + r * y - z[0], r * yd - z[1]
        s, sd = preload / kseat - z[0], -z[1]
        return a, ad, s, sd

    def rhs(t, z, mode):
        a, ad, s, sd = parts(t, z)
        f = k * a + c * ad if mode[0] else 0.0
        fs = kseat * s + cseat * sd if mode[1] else 0.0
        return [z[1], (f + fs - preload - ks * z[0]) / m]

    def events(mode):
        """Each contact's event: ``min(k a, k a + c a')`` (positive while it is closed)
        crossing zero downwards where it is closed, upwards where it is open."""

        def lash_event(t, z, *_):
            a, ad, _, _ = parts(t, z)
            return min(k * a, k * a + c * ad)

        def seat_event(t, z, *_):
            _, _, s, sd = parts(t, z)
            return min(kseat * s, kseat * s + cseat * sd)

        for event, closed in ((lash_event, mode[0]), (seat_event, mode[1])):
            event.terminal, event.direction = True, -1.0 if closed else 1.0
        return lash_event, seat_event

    t, z, mode = 0.0, np.zeros(2), [False, True]  # at rest: the lash open, the valve seated
    landings = []
    end = turns * period
    while t < end:
        sol = scipy.integrate.solve_ivp(
            rhs,
            (t, end),
            z,
            method="DOP853",
            rtol=1e-11,
            atol=1e-14,
            events=events(mode),
            args=(mode,),
            max_step=period / 200,
        )
        t, z = sol.t[-1], sol.y[:, -1]
        if sol.status != 1:
            break
        which = 0 if sol.t_events[0].size else 1
        if which == 1 and not mode[1] and t > (turns - 1) * period:
            landings.append((w * t % 360.0, -z[1]))
        mode = list(mode)
        mode[which] = not mode[which]
        t = t + 1e-12 * period  # step off the switching point
    return landings


def test_seating_and_bounce_against_an_event_driven_integration(example, example_turns):
    """The seating velocity, the number of bounces and the first bounce's velocity within 1%
    of scipy's event-driven integration of the same valve (the tappet held on the cam)."""
    for turn in example_turns:
        assert not turn.separates["cam"]
        landings = _event_driven(example, example.chain, turn.rpm)
        angles = np.array([a for a, _ in landings])
        lift = example.turn.jet(angles)[0]
        assert len(landings) == 1 + len(turn.bounces)
        seating_angle, seating = landings[0]
        assert turn.seating_velocity_m_s == pytest.approx(seating, rel=0.01)
        assert turn.bounces[0].velocity_m_s == pytest.approx(landings[1][1], rel=0.01)
        assert turn.bounces[0].angle_deg == pytest.approx(landings[1][0], abs=0.05)
        assert np.all(lift >= 0)


def test_a_closed_chain_simulated_equals_its_exact_steady_state():
    """Without lash and seat the simulation is the closed chain: its contact force and the
    bodies' peak accelerations equal the exact periodic steady state's within 1e-4 of their
    peaks (samples against refined extremes; the integration's tolerance is 1e-8)."""
    program = Program.load("camjax/program/examples/trains/valve.toml")
    chain = Chain((Body("tappet", 0.03), Body("valve", 0.05, 200.0, 20.0)), Spring(52.0, 250.0))
    rpm = [1200.0]
    exact = SteadyState(dataclasses.replace(program, chain=chain), rpm).summary(rpm).cycles
    summary, (turn,) = ChainContacts(program, chain, rpm[0]).summary(rpm)
    peak = float(exact.max_contact_force_n[0])
    assert abs(summary.min_contact_force_n[0] - float(exact.min_contact_force_n[0])) < 1e-4 * peak
    assert abs(summary.max_contact_force_n[0] - peak) < 1e-4 * peak
    a = np.asarray(exact.train.max_acceleration_m_s2[0])
    assert np.all(np.abs(summary.max_acceleration_m_s2[0] - a) < 1e-4 * a.max())
    assert turn.seating_velocity_m_s is None and turn.separates == {"cam": False}


def test_bad_input_is_one_line(example):
    with pytest.raises(ValueError, match=r"\[seat\]: a seat needs a \[spring\] with preload_n > 0"):
        Chain((Body("tappet", 0.03), Body("valve", 0.05, 200.0, 5.0)), Spring(52.0, 0.0), Seat(5e4))
    with pytest.raises(ValueError, match=r"body 2 \(valve\) lash_mm must be non-negative"):
        Body("valve", 0.05, 200.0, 5.0, lash_mm=-0.1) and Chain(
            (Body("tappet", 0.03), Body("valve", 0.05, 200.0, 5.0, lash_mm=-0.1)),
            Spring(52.0, 250.0),
        )
    with pytest.raises(ValueError, match=r"\[seat\] damping_n_s_per_m must be non-negative"):
        Chain(
            (Body("tappet", 0.03), Body("valve", 0.05, 200.0, 5.0)),
            Spring(52.0, 250.0),
            Seat(5e4, -1.0),
        )
    with pytest.raises(
        ValueError, match=r"body 1 \(rocker\) lever_mass_kg: .* first \[\[train\]\] body"
    ):
        ChainContacts(
            example,
            Chain(
                (Body("rocker", 0.03, 500.0, 5.0, lever_mass_kg=0.01),),
                Spring(52.0, 250.0),
                Seat(5e4, 100.0),
            ),
            1000.0,
        )
    undamped = Chain(
        (Body("tappet", 0.04), Body("valve", 0.05, 2000.0, 0.0, ratio=1.5, lash_mm=0.15)),
        Spring(40.0, 250.0),
        Seat(5e4),
    )
    with pytest.raises(ValueError) as error:
        ChainContacts(example, undamped, 3000.0, ContactOptions(max_turns=3)).turns([3000.0])
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(
        "[seat] damping_n_s_per_m: the chain at 3000 rpm does not settle within 3 turns"
    )


def test_the_report_carries_the_contacts(example, example_turns):
    """``analyse`` routes a chain with lash and a seat to the simulation: the train section's
    contacts equal the simulation's turns, and the JSON carries them."""
    report = analyse(example, [1000.0, 3000.0])
    contacts = report.train["contacts"]
    for turn, row in zip(example_turns, contacts["speeds"]):
        assert row["seating_velocity_m_s"] == pytest.approx(turn.seating_velocity_m_s, rel=1e-9)
        assert row["bounce_count"] == len(turn.bounces)
        assert row["lash_openings"]["valve"]["count"] == len(turn.lash_openings_deg["valve"])
    assert contacts["note"] == contacts_note(example.chain)
    # the example's spring has no mass: no surge, exactly, as the exact path's zero row gives
    assert not example.chain.spring.surges
    assert [s["max_surge_n"] for s in report.train["speeds"]] == [0.0, 0.0]
    for turn in example_turns:
        assert not np.any(turn.surge_n) and not np.any(turn.refined.jets[:, 3])
    assert contacts["lowest_separation_rpm"] == {"cam": None, "valve": None, "seat": 1000.0}
    assert contacts["separation_below_range"] == {"cam": False, "valve": False, "seat": True}
    assert report.jump_speed_rpm is None and not report.jump_below_range
    assert json.loads(report.to_json())["train"]["contacts"]["speeds"][0]["bounce_count"] == len(
        example_turns[0].bounces
    )
    assert all(s.values["min_preload_n"] is None for s in report.speeds)
    assert math.isfinite(report.train["speeds"][0]["max_contact_force_n"])


def _wide(program, width_mm: float = 10.0):
    """``program`` with a line contact of ``width_mm`` (for the Hertz stress)."""
    return dataclasses.replace(
        program, follower=dataclasses.replace(program.follower, contact_width_mm=width_mm)
    )


def test_torque_and_hertz_against_the_simulated_force_samples(example, example_turns):
    """The drive torque's figures and the largest Hertz stress of a chain with lash and a
    seat, against the simulation's own contact-force samples through the cam's geometry
    (``camjax.geometry``): the torque as the normal force ``F_c / cos(phi)`` times its lever
    about the cam's centre, ``(R_p + y) |sin(phi)|`` (a centred translating roller), its mean,
    RMS and energy fluctuation by the trapezoidal rule over the samples; the Hertz stress in
    closed form, ``p^2 = F_n E* / (pi L R')`` with ``1/R' = 1/rho_cam + 1/r_roller``, at the
    samples (the reported peak is refined between them)."""
    wide = _wide(example)
    contacts = ChainContacts(wide, wide.chain, 1000.0)
    stress = contacts.contact_stress(example_turns)
    f = example.follower
    theta = example_turns[0].theta_deg
    y, dy, ddy, _ = example.turn.jet(theta)
    per_rad = 180.0 / math.pi
    profile = camjax.geometry.cam_profile_from_jet(
        f.geometry, np.radians(theta), y, dy * per_rad, ddy * per_rad**2
    )
    phi = np.asarray(profile.pressure_angle)
    # the lever of the normal force about the cam's centre (phi is signed against the turn)
    lever_mm = -(f.base_radius_mm + f.roller_radius_mm + y) * np.sin(phi)
    rho = np.asarray(profile.pitch_radius_of_curvature) - f.roller_radius_mm
    radius = 1.0 / (1.0 / rho + 1.0 / f.roller_radius_mm)
    modulus = wide.materials.contact_modulus_mpa
    for i, turn in enumerate(example_turns):
        normal = turn.cam_force_n / np.cos(phi)
        torque = 1e-3 * normal * lever_mm
        assert np.max(np.abs(turn.drive_torque_n_m - torque)) < 1e-9 * np.max(np.abs(torque))
        t = torque[:-1]  # periodic samples: the last is the first a turn later
        mean = t.mean()
        work = (
            2 * math.pi * np.concatenate([[0.0], np.cumsum(0.5 * (t + torque[1:]) - mean)]) / t.size
        )
        peak = np.max(np.abs(t))
        assert turn.torque.max_abs == pytest.approx(peak, rel=1e-5)
        assert turn.torque.max_abs >= peak * (1 - 1e-12)
        assert turn.torque.rms == pytest.approx(np.sqrt(np.mean(t**2)), rel=1e-5)
        assert turn.torque.mean == pytest.approx(mean, abs=1e-5 * peak)
        assert turn.torque.energy_fluctuation == pytest.approx(np.ptp(work), rel=1e-5)
        p = np.sqrt(np.maximum(normal, 0.0) * modulus / (math.pi * 10.0 * radius))[:-1]
        # refined between the samples: at least their largest, a sample step from it at most
        k = np.argmax(p)
        assert p[k] * (1 - 1e-12) <= stress.stress_mpa[i] <= p[k] * (1 + 1e-5)
        assert abs(stress.angle_deg[i] - theta[k]) <= theta[1]
        assert stress.radius_mm[i] == pytest.approx(radius[k], rel=1e-4)


def _linear_and_lashed() -> tuple[Chain, Chain]:
    """A tappet and a valve on a surging spring, and the same chain with 0.1 mm of lash at
    the valve: a lash the spring's preload keeps closed at the speeds these tests run."""
    valve = Body("valve", 0.05, 200.0, 20.0)
    linear = Chain((Body("tappet", 0.03), valve), Spring(52.0, 250.0))
    return linear, dataclasses.replace(linear, bodies=(linear.bodies[0], dataclasses.replace(valve, lash_mm=0.1)))


def test_a_lash_that_never_opens_reports_the_linear_chain():
    """A lash without a seat is closed at rest and opens only where the force would pull: where
    it never does, the report (``analyse``, routed to the simulation) gives the linear chain's
    numbers (the exact path's ``analyse``) within the simulation's tolerance: every peak
    (contact force, payload acceleration, drive torque, Hertz stress), refined between samples
    against refined between nodes, and every integral (RMS and mean torque, energy
    fluctuation, flywheel) within 1e-7 (measured 2026-11-29: 8e-9 at most)."""
    program = _wide(Program.load("camjax/program/examples/trains/valve.toml"))
    linear, lash = _linear_and_lashed()
    rpm = [1200.0]
    (exact,) = analyse(dataclasses.replace(program, chain=linear), rpm).speeds
    report = analyse(dataclasses.replace(program, chain=lash), rpm)
    (row,) = report.speeds
    assert report.train["contacts"]["speeds"][0]["separates"] == {"valve": False, "cam": False}
    for name in (
        "max_payload_acceleration_m_s2",
        "min_contact_force_n",
        "max_contact_force_n",
        "max_drive_torque_n_m",
        "rms_drive_torque_n_m",
        "energy_fluctuation_j",
        "flywheel_inertia_kg_m2",
        "max_contact_stress_mpa",
        "contact_half_width_mm",
    ):
        assert row.values[name] == pytest.approx(exact.values[name], rel=1e-7), name
    torque = exact.max_drive_torque_n_m
    assert row.mean_drive_torque_n_m == pytest.approx(
        exact.mean_drive_torque_n_m, abs=1e-7 * torque
    )
    assert row.max_contact_stress_deg == pytest.approx(exact.max_contact_stress_deg, abs=1e-4)
    assert row.min_preload_n is None and not row.jump


def test_extremes_refined_between_samples_against_a_finer_simulation(example):
    """The extremes of a coarse simulation (1024 samples a turn, 20 on the seat's half period
    at 3000 rpm) refined between its samples equal those of a simulation sampled 16 times
    finer within 1e-6 of their scale, where the coarse samples alone miss the valve's peak
    acceleration (its seat landing) by more than 1%; no finer sample exceeds them."""
    wide = _wide(example)
    rpm = [3000.0]
    runs = {}
    for samples in (1024, 16384):
        contacts = ChainContacts(wide, wide.chain, rpm[0], ContactOptions(samples=samples))
        runs[samples] = contacts.summary(rpm)
    (coarse, (coarse_turn,)), (fine, (fine_turn,)) = runs[1024], runs[16384]
    pairs = {
        "max_contact_force_n": fine_turn.cam_force_n.max(),
        "max_seat_force_n": fine_turn.spring_seat_force_n.max(),
        "max_drive_torque_n_m": np.abs(fine_turn.drive_torque_n_m).max(),
    }
    for name, sampled in pairs.items():
        a, b = getattr(coarse, name)[0], getattr(fine, name)[0]
        assert a == pytest.approx(b, rel=1e-6), name
        assert sampled <= a * (1 + 1e-6), name
    low = coarse.min_seat_force_n[0]
    assert low == pytest.approx(fine.min_seat_force_n[0], rel=1e-6)
    assert fine_turn.spring_seat_force_n.min() >= low * (1 - 1e-6)
    peaks, finest = coarse.max_acceleration_m_s2[0], np.abs(fine_turn.acceleration_m_s2).max(axis=1)
    np.testing.assert_allclose(peaks, fine.max_acceleration_m_s2[0], rtol=1e-6)
    assert np.all(finest <= peaks * (1 + 1e-6))
    missed = 1 - np.abs(coarse_turn.acceleration_m_s2[-1]).max() / peaks[-1]
    assert missed > 0.01
    assert coarse.stress.stress_mpa[0] == pytest.approx(fine.stress.stress_mpa[0], rel=1e-6)
    assert coarse.stress.angle_deg[0] == pytest.approx(fine.stress.angle_deg[0], abs=1e-3)


def test_bad_options_of_the_report_are_one_line(example):
    for options, text in (
        (dict(samples=8), r"ContactOptions.samples must be a whole number of at least 16, got 8"),
        (dict(samples=2048.0), r"ContactOptions.samples must be a whole number"),
        (
            dict(jump_tolerance_rpm=0.0),
            r"ContactOptions.jump_tolerance_rpm must be a positive number",
        ),
        (
            dict(jump_tolerance_rpm=math.nan),
            r"jump_tolerance_rpm must be a positive number, got nan",
        ),
    ):
        with pytest.raises(ValueError, match=text) as error:
            ContactOptions(**options)
        assert "\n" not in str(error.value)
    with pytest.raises(
        ValueError, match=r"the cam separates at the lowest speed given \(3500 rpm\)"
    ):
        ChainContacts(example, example.chain, 3500.0).jump_speed([3500.0, 4500.0], [True, True])


def test_jump_speed_searched_between_the_speeds_against_a_fine_scan(example):
    """With a 60 N preload the tappet leaves the cam between 3500 and 4500 rpm: the jump
    speed searched there (to 0.1 rpm) against a scan 0.1 rpm apart around it, in the same
    block as the two speeds given (the cam holds at 3500 and separates at 4500): every
    speed of the scan below the answer holds, every one above separates."""
    chain = dataclasses.replace(example.chain, spring=Spring(40.0, 60.0))
    contacts = ChainContacts(example, chain, 3500.0)
    found = contacts.jump_speed([3500.0, 4500.0], [False, True])
    scan = found + 0.1 * (np.arange(30) - 14.5)
    speeds = np.concatenate([[3500.0, 4500.0], scan])
    cam = np.array([t.separates["cam"] for t in contacts.turns(speeds, refine=False)])
    assert list(cam[:2]) == [False, True]
    assert not cam[2:][scan < found].any() and cam[2:][scan > found].all()


FLIGHT_RPM = (3390.0, 3600.0)
"""The valve example's chain about its jump (3428 rpm, 2026-11-29): held, then separating."""


@pytest.fixture(scope="module")
def valve_steady():
    program = Program.load("camjax/program/examples/trains/valve.toml")
    return SteadyState(program, FLIGHT_RPM[0])


def _first_zero_deg(steady: SteadyState, rpm: float) -> float:
    """The exact steady state's first zero of the contact force after its largest one
    (degrees): its sign change on the grid's nodes, then scipy's brentq on the force
    anywhere (the exact modes, ``SteadyState.mode_at``, and the laws' own lift)."""
    osc, turn = steady.oscillator, steady.program.turn
    cycle = steady.cycle(rpm)
    period = 60.0 / rpm

    def force(theta):
        y, d1, d2, _ = (np.asarray(v) for v in turn.jet(np.atleast_1d(theta)))
        w = 360.0 / period  # degrees per second
        modes = steady.mode_at(cycle.q, rpm, np.atleast_1d(theta) / 360.0)
        e0, e1, e2 = np.asarray(osc.direct)[0]
        value = osc.static[0] + np.real(np.asarray(osc.gain)[0] @ modes) / period  # turn-time modes
        return value + e0 * y + e1 * d1 * w + e2 * d2 * w**2

    theta = np.linspace(0.0, 360.0, 36001)
    values = force(theta)
    start = int(np.argmax(values))
    order = (start + np.arange(theta.size - 1)) % (theta.size - 1)
    k = order[int(np.argmax(values[order] < 0))]
    return scipy.optimize.brentq(lambda t: float(force(t)[0]), theta[k - 1], theta[k], xtol=1e-10)


def test_a_chains_flights_start_at_the_exact_steady_states_first_zero(valve_steady):
    """The valve example's chain (a tappet riding on the cam, a surging spring): below its
    jump the steady state holds contact and there is no flight; above it the simulation,
    started on the exact steady state where the cam holds, separates at the exact steady
    state's first zero of the contact force (it is exact until then) within 1e-4 degrees
    (measured 2026-11-29: 3e-6), and every flight lands again later in the turn, closing."""
    held, lost = flights_at(valve_steady, FLIGHT_RPM)
    assert held == []
    assert len(lost) >= 2
    assert lost[0].separation_deg == pytest.approx(
        _first_zero_deg(valve_steady, FLIGHT_RPM[1]), abs=1e-4
    )
    for f in lost:
        assert f.impact_velocity_m_s > 0 and f.peak_impact_force_n > 0
        assert 0 < (f.reimpact_deg - f.separation_deg) % 360 < 360


def test_the_report_gives_a_chains_flights(valve_steady):
    """The report's rows (and their JSON) carry the chain's flights where its steady state
    loses contact, ``flights_at``'s, and none where it holds."""
    report = analyse(valve_steady.program, FLIGHT_RPM, steady=valve_steady)
    held, lost = report.speeds
    assert held.flights is None and not held.jump
    assert lost.jump and list(lost.flights) == flights_at(valve_steady, [FLIGHT_RPM[1]])[0]
    row = json.loads(json.dumps(report.as_dict()))["speeds"][1]
    assert row["flight"] == row["flights"][0] == lost.flights[0].as_dict()


def test_a_one_body_chain_flies_as_the_classic_follower():
    """The classic follower spelled as a train (one body on its element) simulated with the
    cam's contact one-sided (``ChainContacts``) against the classic's closed-form flights
    (``flights_at``), every flight of the turn at two speeds above the jump (771 rpm).

    Until the first separation both are the exact steady state: the separations agree
    within 1e-3 degrees.  In flight the classic's massless roller leaves the cam and its
    train relaxes to its free length, ``F_0 + k e + c e' = 0`` (time constant ``c/k``:
    0.44 degrees at 850 rpm), and it lands where the relaxing roller meets the cam; the
    simulation's element is a Kelvin-Voigt contact clipped at zero, which closes where its
    approach ``y - x + F_0/k`` reaches zero: the same point once the relaxation has died
    (``exp(-k t/c)``), and from the landing both hold the same ``k e + c e'``.  So a flight
    of ten relaxation times or more lands within 1e-3 degrees, with its impact velocity and
    peak force within 1e-4 (measured 2026-11-29: 5e-4 degrees, 2e-5, 2e-5).  A shorter one
    lands where the roller is still relaxing (850 rpm: a flight of 2.3 degrees, ``exp(-k t/c)
    = 6e-3``): its impact velocity differs by 1.4%, and the flights after it inherit the
    difference (within 1e-2 degrees, 2% and 1e-3 here)."""
    classic = two_cycloids()
    chain = Chain.of_follower(classic.follower)
    train = dataclasses.replace(classic, chain=chain)
    rpm = [850.0, 1000.0]
    expected = flights_at(SteadyState(classic, rpm[0]), rpm)
    simulated = flights_at(
        SteadyState(train, rpm[0]), rpm, simulation=ChainContacts(train, chain, rpm[0])
    )
    f = classic.follower
    relaxation_s = 2 * f.damping_ratio * math.sqrt(f.mass_kg / (1e3 * f.stiffness_n_per_mm))
    inherited = 0
    for r, want, got in zip(rpm, expected, simulated):
        assert len(got) == len(want) >= 5
        relaxed = True
        for a, b in zip(want, got):
            assert b.separation_deg == pytest.approx(a.separation_deg, abs=1e-3)
            flight_s = (a.reimpact_deg - a.separation_deg) % 360 / 360 * 60 / r
            relaxed = relaxed and flight_s > 10 * relaxation_s
            inherited += not relaxed
            tight = (1e-3, 1e-4, 1e-4) if relaxed else (1e-2, 2e-2, 1e-3)
            assert b.reimpact_deg == pytest.approx(a.reimpact_deg, abs=tight[0])
            assert b.impact_velocity_m_s == pytest.approx(a.impact_velocity_m_s, rel=tight[1])
            assert b.peak_impact_force_n == pytest.approx(a.peak_impact_force_n, rel=tight[2])
    assert inherited == 5  # the short flight at 850 rpm and the four after it
    assert flights_at(SteadyState(train, rpm[0]), rpm) == expected  # unsimulated: the classic's


def test_bad_flights_input_is_one_line(valve_steady):
    """A simulation slower than asked: one line (an arm's flights: tests/test_arm_flights.py)."""
    program = valve_steady.program
    slow = ChainContacts(program, program.chain, 4000.0)
    with pytest.raises(ValueError, match="below the simulation's slowest speed 4000") as err:
        flights_at(valve_steady, [FLIGHT_RPM[1]], simulation=slow)
    assert "\n" not in str(err.value)


def test_a_lash_that_never_opens_has_the_linear_chains_residual_vibration():
    """The residual vibration at each dwell's start of a lash that never opens (no seat)
    equals the linear chain's exact one within the simulation's tolerance (measured
    2026-11-29: 5e-7 of it at most, at 3000 rpm)."""
    program = Program.load("camjax/program/examples/trains/valve.toml")
    linear, lash = _linear_and_lashed()
    rpm = [1200.0, 3000.0]
    exact = analyse(dataclasses.replace(program, chain=linear), rpm, with_flight=False)
    report = analyse(dataclasses.replace(program, chain=lash), rpm)
    for row, reference in zip(report.speeds, exact.speeds):
        assert len(row.residual_vibration_mm) == 2
        np.testing.assert_allclose(
            row.residual_vibration_mm, reference.residual_vibration_mm, rtol=1e-5, atol=1e-7
        )
    assert not any(s["separates"]["valve"] for s in report.train["contacts"]["speeds"])
    assert report.as_dict()["speeds"][1]["residual_vibration_mm"] == list(
        report.speeds[1].residual_vibration_mm
    )


def _two_contacts_at(program, chain: Chain, rpm: float, angles_deg, turns: int = 24):
    """A pushrod on the cam (its element one-sided) and a valve behind a lash (no seat: closed
    at rest, carrying the preload), integrated with scipy from event to event (each contact
    open or closed, switched where ``min(k a, k a + c a')`` crosses zero) from rest for
    ``turns`` turns: the state ``(x1, x2, v1, v2)`` (m, m/s from rest) at ``angles_deg`` of
    the last turn, and the contacts' openings counted over it."""
    rod, valve = chain.bodies
    k = np.array([1e3 * rod.stiffness_n_per_mm, 1e3 * valve.stiffness_n_per_mm])
    c = np.array([rod.damping_n_s_per_m, valve.damping_n_s_per_m])
    m = np.array([rod.mass_kg, valve.mass_kg])
    ks, preload = 1e3 * chain.spring.rate_n_per_mm, chain.spring.preload_n
    d0 = preload / k
    period = 60.0 / rpm
    w = 360.0 / period

    def approach(t, z):
        y, dy, _, _ = program.turn.jet(np.atleast_1d(w * t % 360.0))
        y, dy = 1e-3 * y[0], 1e-3 * dy[0] * w
        return d0 + np.array([y - z[0], z[0] - z[1]]), np.array([dy - z[2], z[2] - z[3]])

    def rhs(t, z, mode):
        a, ad = approach(t, z)
        f = np.where(mode, k * a + c * ad, 0.0)
        return [z[2], z[3], (f[0] - f[1]) / m[0], (f[1] - preload - ks * z[1]) / m[1]]

    def events(mode):
        out = []
        for j in range(2):

            def event(t, z, *_, j=j):
                a, ad = approach(t, z)
                return min(k[j] * a[j], k[j] * a[j] + c[j] * ad[j])

            event.terminal, event.direction = True, -1.0 if mode[j] else 1.0
            out.append(event)
        return out

    t, z, mode = 0.0, np.zeros(4), np.array([True, True])
    end, last = turns * period, (turns - 1) * period
    wanted = last + np.asarray(angles_deg) / 360.0 * period
    states, openings = {}, [0, 0]
    while t < end:
        sol = scipy.integrate.solve_ivp(
            rhs, (t, end), z, method="DOP853", rtol=1e-10, atol=1e-13,
            events=events(mode), args=(mode,), dense_output=True, max_step=period / 400,
        )  # fmt: skip
        for i, tw in enumerate(wanted):
            if t <= tw <= sol.t[-1]:
                states[i] = sol.sol(tw)
        t, z = sol.t[-1], sol.y[:, -1]
        if sol.status != 1:
            break
        which = 0 if sol.t_events[0].size else 1
        if mode[which] and t > last:
            openings[which] += 1
        mode = mode.copy()
        mode[which] = not mode[which]
    return [states[i] for i in range(len(wanted))], openings


@pytest.mark.slow
def test_residual_vibration_where_the_lash_opens_against_an_event_driven_integration():
    """Slow: scipy's integration of 24 turns with its Python right-hand side (200 s on two
    shared cores, 2026-11-29).  A pushrod leaving the cam and a valve leaving it through its lash at 3000 rpm: the
    residual vibration at each dwell's start against scipy's event-driven integration
    (rtol 1e-10) of the same chain, its state there split over the closed chain's modes
    (both contacts close in the dwells' static states) as written here: within 1e-4."""
    program = Program.load("camjax/program/examples/trains/valve.toml")
    rod = Body("pushrod", 0.03, 500.0, 60.0)
    valve = Body("valve", 0.05, 200.0, 40.0, lash_mm=0.1)
    chain = Chain((rod, valve), Spring(20.0, 60.0))
    rpm = 3000.0
    (turn,) = ChainContacts(program, chain, rpm).turns([rpm])
    assert turn.separates == {"cam": True, "valve": True}
    assert len(turn.lash_openings_deg["valve"]) == 1
    starts = [100.0, 220.0]  # the top dwell's and the base circle's
    states, openings = _two_contacts_at(program, chain, rpm, starts)
    assert openings[1] == 1
    m = np.diag([rod.mass_kg, valve.mass_kg])
    k1, k2, ks = 5e5, 2e5, 2e4
    K = np.array([[k1 + k2, -k2], [-k2, k2 + ks]])
    C = np.array([[100.0, -40.0], [-40.0, 40.0]])
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(m, K), -np.linalg.solve(m, C)]])
    _, V = np.linalg.eig(A)
    for start, state, residual in zip(starts, states, turn.residual_vibration_mm):
        y = 1e-3 * float(program.turn.jet(np.array([start]))[0][0])
        x2 = y / (1 + ks / k2 + ks / k1)  # the static state in the dwell: both contacts carry
        static = np.array([y - ks * x2 / k1, x2, 0.0, 0.0])  # the spring's force
        xi = np.linalg.solve(V, state - static)
        expected = 1e3 * np.sum(np.abs(V[1] * xi))
        assert residual == pytest.approx(expected, rel=1e-4)


@pytest.mark.slow
def test_a_lashs_lowest_separation_searched_against_a_fine_scan():
    """Slow: the report, the search and the scan (36 s on two shared cores, 2026-11-29).  The pushrod and valve above: the lash holds at 2900 rpm and opens at 3000 (the pushrod
    leaves the cam at both): the report's lowest speed of the lash's separation is searched
    between them (to 0.1 rpm) and checked by a scan 0.1 rpm apart around it: every speed of
    the scan below the answer holds, every one above separates; the cam's is the lowest speed
    given, below the range."""
    program = Program.load("camjax/program/examples/trains/valve.toml")
    rod = Body("pushrod", 0.03, 500.0, 60.0)
    valve = Body("valve", 0.05, 200.0, 40.0, lash_mm=0.1)
    chain = Chain((rod, valve), Spring(20.0, 60.0))
    simulation = ChainContacts(program, chain, 2900.0)
    report = analyse(dataclasses.replace(program, chain=chain), [2900.0, 3000.0], steady=simulation)
    contacts = report.train["contacts"]
    found = contacts["lowest_separation_rpm"]["valve"]
    assert 2900.0 < found < 3000.0 and not contacts["separation_below_range"]["valve"]
    assert contacts["lowest_separation_rpm"]["cam"] == 2900.0
    assert contacts["separation_below_range"]["cam"] and report.jump_below_range
    scan = found + 0.1 * (np.arange(30) - 14.5)
    opens = np.array([t.separates["valve"] for t in simulation.turns(scan, refine=False)])
    assert not opens[scan < found].any() and opens[scan > found].all()
    assert (
        json.loads(report.to_json())["train"]["contacts"]["lowest_separation_rpm"]["valve"] == found
    )


MOTORS = """name,maximum_speed_rpm,maximum_torque_n_m,continuous_stall_torque_n_m,rotor_inertia_kg_m2,envelope
medium,6000,3.8,1.3,1.2e-4,0:3.8 3500:3.8 6000:1.8
large,6000,24,8,6e-4,0:24 3500:24 6000:12
"""


@pytest.mark.slow
def test_a_lash_that_never_opens_sizes_the_linear_chains_motor(tmp_path):
    """Slow: both chains' steady states at two speeds (50 s on two shared cores, 2026-11-29).
    Motor sizing of a chain with lash reads the simulated contact force over the settled
    turn (``response`` of its ``ChainContacts``): where the lash never opens it gives the
    linear chain's motor figures, the same motor picked.  The two sum over different points:
    the exact path over its 260 nodes at 1200 rpm, the simulation over its 4096 samples (with
    the motion's breakpoints), whose figures 16384 samples change by 1e-6 at most: the
    difference is the nodes' trapezoid and sampling error, within 2e-3 (measured 2026-11-29:
    7e-4 at most, the RMS torque of the motor with the largest rotor)."""
    from camjax.program import Drive, program_motor_choice, read_motors

    catalogue = tmp_path / "motors.csv"
    catalogue.write_text(MOTORS)
    motors = read_motors(catalogue)
    drive = Drive(travel_mm_per_rev=40, transmission_efficiency=0.9)
    program = dataclasses.replace(
        Program.load("camjax/program/examples/trains/valve.toml"), drive=drive
    )
    linear, lash = _linear_and_lashed()
    rpm = [1200.0, 3000.0]
    exact = program_motor_choice(dataclasses.replace(program, chain=linear), rpm, motors=motors)
    simulated = dataclasses.replace(program, chain=lash)
    steady = ChainContacts(simulated, lash, min(rpm))
    report = analyse(simulated, rpm, steady=steady)
    assert not any(s["separates"]["valve"] for s in report.train["contacts"]["speeds"])
    choice = program_motor_choice(simulated, rpm, steady=steady, motors=motors)
    assert choice.shown.name == exact.shown.name and choice.picked == exact.picked
    tolerance = {"max_speed_rpm": 1e-6}
    for per_speed, reference in zip(choice.sizings, exact.sizings):
        for sizing, expected in zip(per_speed, reference):
            assert sizing.inertia_ratio == pytest.approx(expected.inertia_ratio, rel=1e-12)
            for name in (
                "peak_torque_n_m",
                "rms_torque_n_m",
                "max_speed_rpm",
                "regenerated_energy_j",
                "thermal_use",
                "envelope_use",
            ):
                a, b = getattr(sizing.dynamic, name), getattr(expected.dynamic, name)
                assert a == pytest.approx(b, rel=tolerance.get(name, 2e-3)), name


def test_compensating_a_chain_with_lash_is_refused_in_one_line(tmp_path, capsys):
    """A chain with lash or a seat has no compensated lift: refused before the analysis,
    in one line saying why."""
    from camjax.cli import main

    code = main(["program", EXAMPLE, "--compensate", "1000", "--out", str(tmp_path / "out")])
    out, err = capsys.readouterr()
    assert code != 0 and out == "" and len(err.strip().splitlines()) == 1
    assert "--compensate: a chain with lash or a seat has no compensated lift" in err


def _with_chain(program, **changes):
    """``program`` with its chain's valve (body 2), spring or seat changed: ``valve``,
    ``spring`` and ``seat`` take the fields to replace."""
    chain = program.chain
    valve = dataclasses.replace(chain.bodies[1], **changes.get("valve", {}))
    spring = dataclasses.replace(chain.spring, **changes.get("spring", {}))
    seat = dataclasses.replace(chain.seat, **changes.get("seat", {}))
    return dataclasses.replace(
        program,
        chain=dataclasses.replace(chain, bodies=(chain.bodies[0], valve), spring=spring, seat=seat),
    )


def test_a_turn_past_the_step_limit_is_refused_before_simulating(example):
    """A slow speed whose turn needs more integration steps than ``ContactOptions.max_steps``
    is refused when the simulation is built, naming the slowest speed that fits.  The
    stiffest contact of the example is the tappet's landing, 8 times the chain's first mode
    with the cam held (above the seat's sqrt(k_seat / m_valve)); the estimate is 10 steps a
    period of it and 2,500 a turn (measured: 8.2 a period and 2,200 a turn)."""
    landing_hz = 8 * example.chain.natural_frequencies(contact=True)[0][0]
    assert landing_hz > math.sqrt(5e7 / 0.05) / (2 * math.pi)

    def slowest(max_steps):
        rpm = 10 * landing_hz * 60 / (max_steps - 2_500)
        scale = 10.0 ** (math.floor(math.log10(rpm)) - 2)
        return math.ceil(rpm / scale) * scale

    with pytest.raises(ValueError) as error:
        ChainContacts(example, example.chain, 10.0)
    message = str(error.value)
    assert "\n" not in message and "ContactOptions.max_steps (200,000)" in message
    assert f"run at {slowest(200_000):g} rpm or faster" in message
    assert message.endswith("or lower [[train]] body 2 (valve) stiffness_n_per_mm")
    assert 24 < slowest(200_000) < 26  # the measured rate runs out at about 20 rpm
    ChainContacts(example, example.chain, slowest(200_000))  # builds: no refusal at that speed
    with pytest.raises(ValueError, match=f"run at {slowest(50_000):g} rpm or faster"):
        ChainContacts(example, example.chain, 90.0, ContactOptions(max_steps=50_000))


def test_causes_other_than_damping_are_named_before_simulating(example):
    """A lash the cam's lift cannot take up (the valve's lift through the rocker is the cam's
    0.05 + 0.2 + 5.5 mm times 1.5), and a speed no cam runs (the exact path's warning), are
    refused before any turn is simulated."""
    lift = 1.5 * (0.05 + 0.2 + 5.5)
    huge = _with_chain(example, valve={"lash_mm": 50.0})
    with pytest.raises(ValueError) as error:
        ChainContacts(huge, huge.chain, 1000.0)
    message = str(error.value)
    assert message.startswith("[[train]] body 2 (valve) lash_mm = 50: ")
    assert f"the valve's lift through the chain ({lift:.4g} mm" in message
    just = _with_chain(example, valve={"lash_mm": 0.99 * lift})
    ChainContacts(just, just.chain, 1000.0)  # the lash closes near the top: not refused
    fast = ChainContacts(example, example.chain, 1e6)
    for run in (lambda: fast.turns([1e6]), lambda: analyse(example, [1e6])):
        with pytest.raises(
            ValueError, match=r"at 1e\+06 rpm: faster than any cam runs \(above 100,000"
        ):
            run()


def test_a_spring_too_weak_is_named_where_the_chain_does_not_settle(example):
    """A return spring that cannot hold the chain on the cam: the unsettled chain names the
    spring and the speed up to which it holds the chain taken rigid,
    ``sqrt(R P / (m max(-y'')))`` with the spring's rate negligible (``m`` the tappet's mass
    and the valve's times the square of the rocker's ratio ``R``)."""
    weak = _with_chain(example, spring={"rate_n_per_mm": 1e-9, "preload_n": 0.5})
    theta = np.linspace(0.0, 360.0, 36_001)
    deceleration = -np.min(weak.lift(theta)[2])  # mm/deg^2
    mass = 0.04 + 0.05 * 1.5**2
    hold = math.sqrt(1.5 * 0.5 / (mass * 1e-3 * deceleration)) / 6.0  # deg/s -> rpm
    with pytest.raises(ValueError) as error:
        ChainContacts(weak, weak.chain, 3000.0, ContactOptions(max_turns=3)).turns([3000.0])
    message = str(error.value)
    assert message.startswith(
        "[spring] preload_n: the chain at 3000 rpm does not settle within 3 turns"
    )
    assert f"only up to about {hold:.3g} rpm" in message


def test_absurd_chain_inputs_are_warned_of(example):
    """A seat that the preload squeezes by more than a millimetre (250 N on 1 N/mm: 250 mm),
    a lash of a kilometre, a lever's ratio of a million: each a warning naming its field."""
    from camjax.program import MAX_SEAT_COMPRESSION_MM, design_warnings

    assert not [w for w in design_warnings(example) if "[seat]" in w or "[[train]]" in w]
    soft = _with_chain(example, seat={"stiffness_n_per_mm": 1.0})
    (line,) = [w for w in design_warnings(soft) if w.startswith("[seat] stiffness_n_per_mm = 1:")]
    assert (
        f"compresses the seat by 250 mm at rest, more than {MAX_SEAT_COMPRESSION_MM:g} mm" in line
    )
    # 300 N/mm: 0.83 mm, under both 1 mm and the valve's lift: no warning
    assert not [
        w
        for w in design_warnings(_with_chain(example, seat={"stiffness_n_per_mm": 300.0}))
        if w.startswith("[seat]")
    ]
    odd = _with_chain(
        example, valve={"lash_mm": 1e6, "ratio": 1e6}, seat={"stiffness_n_per_mm": 1e10}
    )
    lines = design_warnings(odd)
    for start in (
        "[[train]] body 2 (valve) lash_mm = 1e+06 is more than 10,000 mm",
        "[[train]] body 2 (valve) ratio = 1e+06 is more than 100,",
        "[seat] stiffness_n_per_mm = 1e+10 is more than 1,000,000,000 N/mm",
    ):
        assert any(w.startswith(start) for w in lines), start


def test_an_unsettled_chain_names_what_rattles_and_the_speeds_that_settled(example):
    """The example's tappet, between the cam and the valve's open lash, is held by no spring:
    where the chain does not settle and every element and the seat is damped, the message
    names it, the lash and the damping it has, and the speeds that did settle.  The state's
    change over the second turn is 2.7e-9 of the lift at 1000 rpm and 6.6e-10 at 3000 rpm
    (measured 2026-11-29): a tolerance of 1.3e-9 settles 3000 rpm only."""
    options = ContactOptions(max_turns=2, settle_tolerance=1.3e-9)
    with pytest.raises(ValueError) as error:
        ChainContacts(example, example.chain, 1000.0, options).turns([1000.0, 3000.0])
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(
        "[[train]] body 1 (tappet): the chain at 1000 rpm does not settle within 2 turns (its "
        "state still moves by 2.7e-09 of the lift a turn, against 1.3e-09; 3000 rpm settled: "
        "run it alone): "
    )
    assert message.endswith(
        ": between the cam and the open lash of body 2 (valve, lash_mm = 0.15) nothing holds it "
        "(no spring): it rattles there with only the damping of body 2 (valve) "
        "damping_n_s_per_m = 20: give more damping_n_s_per_m, or less lash; or check the return "
        "spring ([spring] preload_n, rate_n_per_mm: too weak to return the chain onto the cam)"
    )
