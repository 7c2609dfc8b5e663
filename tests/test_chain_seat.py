"""A stiff seat with zero lash against the closed chain (docs/valve-trains.md, "The rest
state"): what a seat changes and what it leaves as it was.

With a seat the valve rests on it and the seat carries the spring's preload ``P``; the chain
carries nothing, so the cam must first lift by ``delta`` (the chain compressed by ``P`` and
the seat relieved of its own compression ``s_0 = P / k_seat``) before the valve leaves it.
Off its seat the seated chain's equations are the closed chain's driven by the lift less
``delta`` (its valve ``s_0`` higher).  These tests check that against the closed chain's
exact periodic steady state (``SteadyState``, exact propagation: a path apart from the
simulation) on a cam that takes up ``delta`` and dwells there before its lift, and against
scipy's integration of the closed chain's equations written here on a cam without that
dwell, where the lift-off from rest rings the valve (what cannot equal the closed chain).

And the seat's landings read from a turn's samples, and the seats and chains that never let
the valve leave it (refused before simulating, or warned of in the report), with the
``[seat]`` table's own messages."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import scipy.integrate

from camjax import laws
from camjax.program import (
    Body,
    Chain,
    ChainContacts,
    ContactOptions,
    Program,
    Seat,
    Segment,
    Spring,
    SteadyState,
    seat_landings,
)

VALVE = "camjax/program/examples/trains/valve.toml"
RPM = 1000.0
RATIO, STIFFNESS, DAMPING = 1.5, 2000.0, 200.0  # the rocker: N/mm, N s/m (zeta about 0.3)
PRELOAD, RATE = 250.0, 40.0  # the return spring: N, N/mm
SEAT = Seat(50000.0, 500.0)
LIFT_MM = 8.0


def _chains(stiffness: float = STIFFNESS) -> tuple[Chain, Chain]:
    """A tappet riding the cam and a valve behind a rocker without lash, on a massless
    spring: the closed chain and the same on a seat.  The rocker's damping lets the free
    vibration of a dwell's start die out within 30 degrees at ``RPM`` (by ``e^-10``), so that
    both chains start the lift at rest."""
    closed = Chain(
        (Body("tappet", 0.03), Body("valve", 0.05, stiffness, DAMPING, RATIO)),
        Spring(RATE, PRELOAD),
    )
    return closed, dataclasses.replace(closed, seat=SEAT)


def _lift_off_mm(stiffness: float = STIFFNESS) -> float:
    """``delta``: the cam's lift (mm) at which the seated valve, quasi-static, leaves its
    seat: the rocker compressed by the spring's force there, ``P + k_s s_0``, and the valve
    risen by the seat's compression ``s_0``: ``k (r delta - s_0) = P + k_s s_0``."""
    k, ks = 1e3 * stiffness, 1e3 * RATE
    s0 = PRELOAD / (1e3 * SEAT.stiffness_n_per_mm)
    return 1e3 * (PRELOAD + (k + ks) * s0) / (k * RATIO)


def _taken_up(delta_mm: float) -> Program:
    """A cam that takes up ``delta_mm`` (cycloidal, 20 deg), dwells there 30 deg, lifts 8 mm
    (cycloidal, 90 deg), dwells 10, returns to ``delta_mm``, dwells 30 and returns to the
    base circle (70 deg): the valve leaves its seat and lands on it at rest, on the dwells."""
    cycloidal = laws.get("cycloidal")
    segments = (
        Segment(20, delta_mm, cycloidal),
        Segment(30),
        Segment(90, LIFT_MM, cycloidal),
        Segment(10),
        Segment(90, -LIFT_MM, cycloidal),
        Segment(30),
        Segment(20, -delta_mm, cycloidal),
        Segment(70),
    )
    return dataclasses.replace(Program.load(VALVE), segments=segments)


@pytest.fixture(scope="module")
def taken_up():
    closed, seated = _chains()
    program = _taken_up(_lift_off_mm())
    exact = SteadyState(dataclasses.replace(program, chain=closed), [RPM]).summary([RPM]).cycles
    summary, (turn,) = ChainContacts(program, seated, RPM).summary([RPM])
    return exact, summary, turn


def test_off_its_seat_the_valve_moves_as_the_closed_chain_on_the_lift_less_delta(taken_up):
    """Where the cam takes up ``delta`` and dwells before the lift, the seated chain's valve
    leaves its seat at rest as the closed chain's starts the lift at rest: over the lift the
    two differ by the closed chain's static response to ``delta`` alone.  Its valve stands
    ``P / (k + k_s)`` higher than the seated one's above ``s_0``, so its spring pushes by
    ``k_s P / (k + k_s)`` more and the cam by ``r`` times that; the accelerations are the
    same.  Against the exact steady state within 1e-7 of the peaks (measured 2026-11-29:
    see docs/valve-trains.md)."""
    exact, summary, turn = taken_up
    ks = 1e3 * RATE
    static = ks * PRELOAD / (1e3 * STIFFNESS + ks)  # N at the spring: 4.9
    # off its seat over the lift, to 2.5 deg before the return ends: there the closed chain's
    # valve dips a few nm below its rest and the seated one touches its seat
    lift = (turn.theta_deg[:-1] > 50.0) & (turn.theta_deg[:-1] < 237.0)
    assert np.all(turn.seat_contact_force_n[:-1][lift] == 0.0)
    assert not turn.separates["cam"]
    peak = float(exact.max_contact_force_n[0])
    assert summary.max_contact_force_n[0] == pytest.approx(peak - RATIO * static, abs=1e-7 * peak)
    spring = float(exact.train.max_seat_force_n[0])
    assert summary.max_seat_force_n[0] == pytest.approx(spring - static, abs=1e-7 * spring)
    # the peak acceleration falls on a cycloid's quarter, a breakpoint the step control is told
    # of, where the simulation's interpolant is the chord between samples (12,288 a turn, 3.3e-4
    # of the rise apart): a sine's peak read on a chord is low by up to (pi 3.3e-4)^2 / 2 = 5e-7
    # (measured 4.7e-7)
    a = np.asarray(exact.train.max_acceleration_m_s2[0])
    assert summary.max_acceleration_m_s2[0] == pytest.approx(a, abs=2e-6 * a.max())


def test_on_its_seat_the_seat_carries_the_preload(taken_up):
    """On the base circle the seat carries the preload and the spring pushes with it, as the
    closed chain's spring at rest, within 1e-8 of it; the chain carries nothing (the cam's
    force is zero).  The spring's least force is the preload within 1e-6 of it: where the
    cam falls back to its base circle the unloading chain lets the valve sink into its seat
    (by ``s_0``, 5 microns) and a few nm past its rest (measured 2026-11-29: 1.6e-4 N)."""
    _, summary, turn = taken_up
    base = turn.theta_deg[:-1] > 300.0
    assert np.abs(turn.seat_contact_force_n[:-1][base] - PRELOAD).max() < 1e-7 * PRELOAD
    assert np.abs(turn.spring_seat_force_n[:-1][base] - PRELOAD).max() < 1e-8 * PRELOAD
    assert np.abs(turn.cam_force_n[:-1][base]).max() < 1e-7 * PRELOAD
    assert summary.min_seat_force_n[0] == pytest.approx(PRELOAD, abs=1e-6 * PRELOAD)


def _cycloidal_rise(theta_deg: float) -> tuple[float, float]:
    """``valve.toml``'s rise from its base circle (m and m/deg): cycloidal, ``LIFT_MM`` over
    100 deg, ``h (x - sin(2 pi x) / (2 pi))``; zero before it (``theta_deg`` below 0)."""
    x = min(max(theta_deg / 100.0, 0.0), 1.0)
    h = 1e-3 * LIFT_MM
    return h * (x - math.sin(2 * math.pi * x) / (2 * math.pi)), h * (
        1 - math.cos(2 * math.pi * x)
    ) / 100.0


def _seated_opening(
    rpm: float, theta_deg: np.ndarray, stiffness: float
) -> tuple[np.ndarray, float]:
    """The seated valve's acceleration (m/s^2) at ``theta_deg`` over the opening of
    ``valve.toml``'s cam (``_cycloidal_rise``), integrated with scipy (DOP853 at ``rtol``
    1e-11) from rest on its seat on the base circle: on its seat the valve's equation has the
    seat's push ``k_seat (s_0 - w) - c_seat w'``, until that force reaches zero (an event),
    then the closed chain's ``m w'' = k (r y - w) + c (r y' - w') - P - k_s w`` (the tappet
    held on the cam; ``y`` its lift); and the lift-off's angle (deg)."""
    k, c, ks = 1e3 * stiffness, DAMPING, 1e3 * RATE
    kseat, cseat = 1e3 * SEAT.stiffness_n_per_mm, SEAT.damping_n_s_per_m
    s0, m = PRELOAD / kseat, 0.05
    w_deg = 6.0 * rpm  # deg/s

    def accel(t, z, seated):
        y, dy = _cycloidal_rise(w_deg * t)
        yd = dy * w_deg
        seat = kseat * (s0 - z[0]) - cseat * z[1] if seated else 0.0
        return (k * (RATIO * y - z[0]) + c * (RATIO * yd - z[1]) - PRELOAD - ks * z[0] + seat) / m

    def seat_force(t, z, seated):
        return kseat * (s0 - z[0]) - cseat * z[1]

    seat_force.terminal, seat_force.direction = True, -1.0
    start = -40.0 / w_deg  # on the base circle, at rest
    kw = dict(method="DOP853", rtol=1e-11, atol=1e-15, max_step=0.2 / w_deg, dense_output=True)
    on = scipy.integrate.solve_ivp(
        lambda t, z, s: [z[1], accel(t, z, s)],
        (start, 180.0 / w_deg),
        [0.0, 0.0],
        events=seat_force,
        args=(True,),
        **kw,
    )
    assert on.status == 1  # the valve left its seat
    lift_off = on.t[-1]
    off = scipy.integrate.solve_ivp(
        lambda t, z, s: [z[1], accel(t, z, s)],
        (lift_off, theta_deg.max() / w_deg),
        on.y[:, -1],
        args=(False,),
        **kw,
    )
    t = theta_deg / w_deg
    return np.array(
        [accel(ti, (on if ti < lift_off else off).sol(ti), ti < lift_off) for ti in t]
    ), w_deg * lift_off


@pytest.mark.slow
def test_a_lift_off_from_rest_rings_the_valve_as_scipy_integrates_it():
    """On a cam without the dwell at ``delta`` (the example's cycloidal 8 mm over 100 deg)
    the valve leaves its seat at rest where the closed chain's already moves with the cam
    (``r y'`` at the lift-off): the seated valve rings at the closed chain's frequency from
    there, so its peak acceleration over the opening is not the closed chain's, however stiff
    the rocker (2000 and 20,000 N/mm).  Its acceleration over the opening equals scipy's
    integration of its equation (written here) within ``omega^2`` times the simulation's
    tolerance on the state, 1e-8 mm (measured 2026-11-29: 8.8e-5 and 4.2e-4 m/s^2 against
    4.1e-4 and 4.0e-3, peaks of 893 and 732), it leaves its seat before the cam has lifted by ``delta`` (the rocker's damping
    adds ``c r y'`` to its force), and its peak is more than twice the closed chain's (893
    against 267 m/s^2 at 2000 N/mm, 732 against 271 at 20,000).  Once the ring has died (by
    ``e^-13`` at the nose) the spring's largest force is the closed chain's less ``k_s P / (k
    + k_s)``, the static difference that falls as ``1/k``, within 1e-7 of it (measured
    2e-14)."""
    program = Program.load(VALVE)
    options = ContactOptions(samples=12288)  # both stiffnesses in one compiled turn
    for stiffness in (STIFFNESS, 10.0 * STIFFNESS):
        closed, seated = _chains(stiffness)
        summary, (turn,) = ChainContacts(program, seated, RPM, options).summary([RPM])
        exact = SteadyState(dataclasses.replace(program, chain=closed), [RPM]).summary([RPM])
        opening = turn.theta_deg < 100.0
        simulated = turn.acceleration_m_s2[-1][opening]
        reference, lift_off_deg = _seated_opening(RPM, turn.theta_deg[opening], stiffness)
        peak = np.abs(reference).max()
        omega_squared = (1e3 * stiffness + 1e3 * RATE) / 0.05
        assert np.abs(simulated - reference).max() < omega_squared * 1e-11, stiffness
        lift = 1e3 * _cycloidal_rise(lift_off_deg)[0]
        assert 0.5 * _lift_off_mm(stiffness) < lift < _lift_off_mm(stiffness), stiffness
        train = exact.cycles.train
        assert peak > 2.0 * float(train.max_acceleration_m_s2[0][-1]), stiffness
        ks = 1e3 * RATE
        static = ks * PRELOAD / (1e3 * stiffness + ks)
        spring = float(train.max_seat_force_n[0])
        assert summary.max_seat_force_n[0] == pytest.approx(spring - static, abs=1e-7 * spring)


EXAMPLE = "camjax/program/examples/trains/valve_lash.toml"
VALVE_LIFT_MM = 1.5 * (0.05 + 0.2 + 5.5)  # the example's cam lift through its rocker


@pytest.fixture(scope="module")
def example():
    return Program.load(EXAMPLE)


def _with_seat(program, stiffness_n_per_mm: float):
    chain = program.chain
    seat = dataclasses.replace(chain.seat, stiffness_n_per_mm=stiffness_n_per_mm)
    return dataclasses.replace(program, chain=dataclasses.replace(chain, seat=seat))


def test_seat_landings_read_the_last_sample_in_flight():
    """One long flight over the turn's end (samples 90 to 9, landing at 10) and a bounce
    (samples 40 to 44): the seating is read from sample 9, the bounce from 44; where the
    valve touches already at the closing's sample, from the one before."""
    m = 100
    closed = np.ones(m, bool)
    closed[90:] = closed[:10] = False
    closed[40:45] = False
    approach = np.where(closed, 1e-6, -1e-6)
    assert seat_landings(closed, approach) == [9, 44]
    touching = approach.copy()
    touching[9] = 1e-9  # the seat's approach positive, its force not yet past closed
    assert seat_landings(closed, touching) == [8, 44]
    wrapped = np.ones(m, bool)
    wrapped[50:] = False  # open from sample 50 to the turn's last one, closing at 0
    approach = np.where(wrapped, 1e-6, -1e-6)
    assert seat_landings(wrapped, approach) == [m - 1]


def test_a_turn_that_never_leaves_or_never_lands_on_its_seat_has_no_landing():
    """The seat's force dipping under its threshold (its dashpot unloading it) while the valve
    stays on it is no landing; nor is a turn the valve spends wholly off its seat, or wholly
    on it."""
    m = 6145
    closed = np.ones(m, bool)
    closed[1000:3000] = False  # the seat's force below closed, the valve still pressed into it
    approach = np.full(m, 0.25)  # 250 N on 1 N/mm: 250 mm of squeeze, never released
    assert seat_landings(closed, approach) == []
    assert seat_landings(np.zeros(m, bool), np.full(m, -1e-3)) == []
    assert seat_landings(np.ones(m, bool), np.full(m, 1e-3)) == []
    # a dip on the seat beside a true flight: only the flight lands
    approach = np.full(m, 1e-6)
    closed[4000:4100] = False
    approach[4000:4100] = -1e-6
    assert seat_landings(closed, approach) == [4099]


def test_a_seat_the_lift_cannot_lift_the_valve_off_is_refused_before_simulating(example):
    """The example's 250 N preload squeezes a 1 N/mm seat by 250 mm, a 10 N/mm one by 25 mm,
    against the valve's 8.625 mm lift less the 0.15 mm lash: refused when the simulation is
    built, naming the seat's stiffness and the numbers.  A 100 N/mm seat (2.5 mm) builds
    (its warning is the report's)."""
    for stiffness, squeeze in ((1.0, "250"), (10.0, "25")):
        soft = _with_seat(example, stiffness)
        with pytest.raises(ValueError) as error:
            ChainContacts(soft, soft.chain, 2000.0)
        assert str(error.value) == (
            f"[seat] stiffness_n_per_mm = {stiffness:g}: the spring's preload (250 N) squeezes the "
            f"seat by {squeeze} mm at rest, which with the lash (0.15 mm at the valve) is not less "
            f"than the valve's lift through the chain ({VALVE_LIFT_MM:.4g} mm: the cam's 5.75 mm "
            "times the ratios): the valve never leaves its seat (a valve's seat takes tens of "
            "thousands of N/mm)"
        )
    # the squeeze and the lash just under the lift: 250 / k + 0.15 = 0.99 * 8.625
    near = _with_seat(example, 250.0 / (0.99 * VALVE_LIFT_MM - 0.15))
    ChainContacts(near, near.chain, 2000.0)
    ChainContacts(_with_seat(example, 100.0), _with_seat(example, 100.0).chain, 2000.0)


def test_the_command_refuses_a_soft_seat_in_one_line(tmp_path, capsys):
    """The trial's ``[seat] stiffness_n_per_mm = 1`` file: one line, exit 2, no traceback."""
    from camjax.cli import main

    text = open(EXAMPLE).read().replace("stiffness_n_per_mm = 50000", "stiffness_n_per_mm = 1")
    assert "stiffness_n_per_mm = 1\n" in text
    path = tmp_path / "seat1.toml"
    path.write_text(text)
    code = main(["program", str(path), "--rpm", "2000"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    (line,) = err.strip().splitlines()
    assert (
        "[seat] stiffness_n_per_mm = 1: the spring's preload (250 N) squeezes the seat by 250"
        in line
    )


def test_a_valve_that_never_leaves_its_seat_is_warned_of(example):
    """The example with its rocker at 20 N/mm instead of 2000: the 250 N preload compresses it
    by 12.5 mm, more than the valve's 8.625 mm lift, so the valve stays on its seat (within the
    seat's 250 / 50000 mm squeeze) all turn: no seating, a lift error of the whole lift, and a
    warning in the report (stderr, JSON) naming the rocker's stiffness."""
    from camjax.program import analyse

    chain = example.chain
    soft = dataclasses.replace(
        example,
        chain=dataclasses.replace(
            chain,
            bodies=(
                chain.bodies[0],
                dataclasses.replace(chain.bodies[1], stiffness_n_per_mm=20.0),
            ),
        ),
    )
    report = analyse(soft, [2000.0])
    (speed,) = report.train["contacts"]["speeds"]
    assert speed["seating_velocity_m_s"] is None and speed["bounce_count"] == 0
    error = report.train["speeds"][0]["max_lift_error_mm"]
    assert VALVE_LIFT_MM - 250 / 50000 - 1e-6 <= error <= VALVE_LIFT_MM
    (line,) = [w for w in report.warnings if "kinematic lift" in w]
    assert line == (
        f"at 2000 rpm the last body (valve) misses its kinematic lift ({VALVE_LIFT_MM:.4g} mm: "
        f"the cam's lift times the ratios) by up to {error:.4g} mm (100%, at 2000 rpm): it "
        "barely follows the cam and may never leave its seat; the chain gives most at "
        "[[train]] body 2 (valve) stiffness_n_per_mm = 20 (the spring's preload, 250 N, "
        "compresses it by 12.5 mm at the last body): stiffen it"
    )
    assert line in report.as_dict()["warnings"]


def test_the_contacts_note_says_what_the_chain_has(example):
    """The note's rest state is the chain's own (``ContactSystem.of``): the valve on its seat
    with the lash open; a seat without lash, the elements just touching; lash without a
    seat, the closed chain carrying the preload, the lash closed, and no seat's separation."""
    from camjax.program import contacts_note

    chain = example.chain
    seated = contacts_note(chain)
    assert (
        "; the rest state has the valve on its seat carrying the spring's preload, the lash open;"
        in seated
    )
    assert "while the valve is off its seat, the seat where the valve bounces;" in seated
    no_lash = dataclasses.replace(
        chain, bodies=(chain.bodies[0], dataclasses.replace(chain.bodies[1], lash_mm=0.0))
    )
    assert "on its seat carrying the spring's preload, the elements just touching;" in (
        contacts_note(no_lash)
    )
    unseated = contacts_note(dataclasses.replace(chain, seat=None))
    assert (
        "; no seat: the rest state is the closed chain carrying the spring's preload through the "
        "levers, the lash closed by it; extremes" in unseated
    )
    assert "seat where" not in unseated and "on its seat" not in unseated
    assert "; a contact separates where it opens; jump speed:" in unseated


def test_a_bad_seat_table_is_named(example):
    """A misspelt [seat] key is named; a [seat] beside the classic follower gets the seat's
    own message, not the spring's."""
    import tomllib

    data = tomllib.loads(example.to_toml())
    data["seat"] = {"stiffness_n_per_mm": 50000, "dampin_n_s_per_m": 5}
    with pytest.raises(ValueError) as error:
        Program.from_dict(data)
    assert str(error.value) == (
        "[seat]: unknown field(s) dampin_n_s_per_m; it takes stiffness_n_per_mm and optionally "
        "damping_n_s_per_m"
    )
    data["seat"] = {"damping_n_s_per_m": 5}
    with pytest.raises(ValueError, match=r"^\[seat\]: it takes stiffness_n_per_mm and"):
        Program.from_dict(data)
    classic = {key: value for key, value in data.items() if key not in ("train", "spring")}
    classic["follower"] = {**data["follower"], "mass_kg": 0.2, "stiffness_n_per_mm": 500.0}
    classic["seat"] = {"stiffness_n_per_mm": 50000}
    with pytest.raises(ValueError) as error:
        Program.from_dict(classic)
    assert str(error.value).startswith(
        "[seat] belongs to a [[train]]: a seat sits under a chain's last body, and the classic "
        "[follower] has none"
    )
