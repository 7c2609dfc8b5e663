"""``camjax program --out`` for a chain of bodies: the written ``response.csv`` against
independent computations (the riding body against the cam's own lift, the chain's equations
of motion and its static equilibrium in a dwell, the steady state's contact force; a chain
with lash and a seat against a fresh simulation of it), the train's figures, and bad input."""

from __future__ import annotations

import csv
import dataclasses
import math
import tomllib

import numpy as np
import pytest
from test_train_program import TWO, two_body

from camjax.cli import main
from camjax.program import (
    ChainContacts,
    Oscillator,
    Program,
    SteadyState,
    analyse,
    response,
    write_report,
)

LASH_EXAMPLE = "camjax/program/examples/trains/valve_lash.toml"
SPEEDS = (100.0, 600.0)
TRAIN_FIGURES = ("train.png", "modes.png", "seat_force.png", "train_sweep.png")


def read_response(path) -> dict[float, dict[str, np.ndarray]]:
    """``response.csv`` as ``{rpm: {column: values}}``."""
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    out = {}
    for rpm in dict.fromkeys(float(r["rpm"]) for r in rows):
        mine = [r for r in rows if float(r["rpm"]) == rpm]
        out[rpm] = {k: np.array([float(r[k]) for r in mine]) for k in mine[0] if k != "rpm"}
    return out


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """The two-body program (a tappet riding the cam, a valve on an element) written by the
    command at two speeds."""
    folder = tmp_path_factory.mktemp("two")
    path = folder / "two.toml"
    path.write_text(two_body().to_toml())
    rpm = ",".join(f"{r:g}" for r in SPEEDS)
    assert main(["program", str(path), "--rpm", rpm, "--out", str(folder / "out")]) == 0
    return folder / "out"


def test_chain_response_columns(written):
    """Every body's histories by name and unit, the seat force, surge and lift error, beside
    the one-body follower's columns (no contact stress without ``contact_width_mm``: none is
    computed, the JSON's null, not a column of zeros); the train's figures beside the others."""
    histories = read_response(written / "response.csv")
    assert list(histories) == list(SPEEDS)
    keys = list(histories[SPEEDS[0]])
    bodies = [
        f"{name}_{what}"
        for name in ("tappet", "valve")
        for what in ("displacement_mm", "velocity_m_s", "acceleration_m_s2")
    ]
    assert keys[:7] == [
        "theta_deg",
        "lift_mm",
        "payload_displacement_mm",
        "kinematic_acceleration_m_s2",
        "payload_acceleration_m_s2",
        "contact_force_n",
        "drive_torque_n_m",
    ]
    assert keys[7:] == [*bodies, "seat_force_n", "surge_n", "lift_error_mm"]
    for name in ("svaj.png", "contact_force.png", "sweep.png", "profile.png", *TRAIN_FIGURES):
        assert (written / name).stat().st_size > 10_000, name


def test_chain_response_against_the_chain_equations(written):
    """The tappet rides the cam: its displacement, velocity and acceleration are the cam's
    lift and its derivatives (``Program.lift``); the valve's columns satisfy its equation of
    motion ``m_v x_v'' = k (x_t - x_v) + c (x_t' - x_v') - k_s x_v`` (from the preloaded
    rest), the cam's contact force the tappet's ``F_0 + m_t x_t'' + k (x_t - x_v) + c (...)``,
    the massless spring's seat force ``F_0 + k_s x_v`` without surge, and the contact force
    is the steady state's at the same angles."""
    program = two_body()
    steady = SteadyState(program, min(SPEEDS))
    m_t, m_v, k, c = TWO["tappet"], TWO["valve"], 1e3 * TWO["element"], TWO["damping"]
    k_s, preload = 1e3 * TWO["rate"], TWO["preload"]
    theta = 360.0 * steady.grid.nodes  # the written angles, at ten digits
    y, dy, ddy = program.lift(theta)
    for rpm, h in read_response(written / "response.csv").items():
        np.testing.assert_allclose(h["theta_deg"], theta, rtol=1e-9, atol=0)
        omega = 360.0 * rpm / 60.0  # deg/s
        np.testing.assert_allclose(h["tappet_displacement_mm"], y, rtol=0, atol=1e-9 * np.ptp(y))
        np.testing.assert_allclose(
            h["tappet_velocity_m_s"],
            1e-3 * dy * omega,
            rtol=0,
            atol=1e-9 * np.max(np.abs(1e-3 * dy * omega)),
        )
        np.testing.assert_allclose(
            h["tappet_acceleration_m_s2"],
            1e-3 * ddy * omega**2,
            rtol=0,
            atol=1e-9 * np.max(np.abs(1e-3 * ddy * omega**2)),
        )
        x_t, x_v = 1e-3 * h["tappet_displacement_mm"], 1e-3 * h["valve_displacement_mm"]
        v_t, v_v = h["tappet_velocity_m_s"], h["valve_velocity_m_s"]
        element = k * (x_t - x_v) + c * (v_t - v_v)
        scale = np.max(np.abs(element)) + k_s * np.max(np.abs(x_v))
        np.testing.assert_allclose(
            m_v * h["valve_acceleration_m_s2"], element - k_s * x_v, rtol=0, atol=1e-7 * scale
        )
        np.testing.assert_allclose(
            h["contact_force_n"],
            preload + m_t * h["tappet_acceleration_m_s2"] + element,
            rtol=0,
            atol=1e-7 * scale,
        )
        np.testing.assert_allclose(
            h["seat_force_n"], preload + k_s * x_v, rtol=0, atol=1e-9 * scale
        )
        np.testing.assert_allclose(h["surge_n"], 0.0, rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(
            h["lift_error_mm"], h["valve_displacement_mm"] - y, rtol=0, atol=1e-9 * np.ptp(y)
        )
        np.testing.assert_array_equal(h["payload_displacement_mm"], h["valve_displacement_mm"])
        np.testing.assert_array_equal(h["payload_acceleration_m_s2"], h["valve_acceleration_m_s2"])
        cycle = steady.cycle(rpm)
        force = np.asarray(cycle.contact_force_n)
        np.testing.assert_allclose(
            h["contact_force_n"], force, rtol=0, atol=1e-9 * np.max(np.abs(force))
        )


def test_last_body_at_the_dwell_is_static(written):
    """At the end of the top dwell the valve sits where the element and the spring balance,
    ``x_v = k h / (k + k_s)``: within what is left of its free vibration at the dwell's
    start (its amplitude there from the written state, ``sqrt(e^2 + (e'/w_d)^2)``, decayed
    over the dwell at ``zeta w``)."""
    h = read_response(written / "response.csv")[SPEEDS[0]]
    k, k_s, c, m_v = 1e3 * TWO["element"], 1e3 * TWO["rate"], TWO["damping"], TWO["valve"]
    lift = 20.0  # two_cycloids: rise 20 mm over 100 deg, dwell 100 to 180 deg
    static = k * lift / (k + k_s)
    omega = math.sqrt((k + k_s) / m_v)
    zeta = c / (2 * m_v * omega)
    damped = omega * math.sqrt(1 - zeta**2)
    theta = h["theta_deg"]
    start, end = (
        np.flatnonzero(np.isclose(theta, 100.0))[0],
        np.flatnonzero(np.isclose(theta, 180.0))[0],
    )
    e0 = h["valve_displacement_mm"][start] - static
    rate0 = 1e3 * h["valve_velocity_m_s"][start]  # mm/s
    amplitude = math.hypot(e0, (rate0 + zeta * omega * e0) / damped)
    dwell_s = 80.0 / 360.0 * 60.0 / SPEEDS[0]
    bound = amplitude * math.exp(-zeta * omega * dwell_s)
    print(
        f"dwell: amplitude at its start {amplitude:.3g} mm, bound at its end {bound:.3g} mm, "
        f"off static {h['valve_displacement_mm'][end] - static:.3g} mm"
    )
    assert 0 < bound < 1e-6 * lift  # a test with teeth: settled far below the lift
    assert abs(h["valve_displacement_mm"][end] - static) <= bound
    assert abs(h["valve_velocity_m_s"][end]) <= 1e-3 * omega * (1 + zeta) * bound


def test_coordinate_modes_are_the_chain_modes():
    """``Chain.coordinate_modes`` (the modes figure's shapes along the chain): each shape
    solves ``(K - w^2 M) phi = 0`` over the moving coordinates, the bodies' rows are
    ``natural_frequencies``' shapes up to their scale, and the held cam and the seat are still."""
    chain = Program.load("camjax/program/examples/trains/valve.toml").chain
    for contact in (True, False):
        hz, shapes, a = chain.coordinate_modes(contact=contact)
        moving = np.arange(0 if not contact else 1, a.seat)
        w2 = (2 * math.pi * hz) ** 2
        K, M = a.K[np.ix_(moving, moving)], a.M[np.ix_(moving, moving)]
        phi = shapes[moving]
        residual = K @ phi - M @ phi * w2
        assert np.max(np.abs(residual)) <= 1e-9 * np.max(np.abs(K @ phi))
        assert np.all(shapes[a.seat] == 0) and (not contact or np.all(shapes[0] == 0))
        body_hz, body_shapes = chain.natural_frequencies(contact=contact)
        np.testing.assert_array_equal(body_hz, hz)
        rows = shapes[a.body_index]
        scale = rows[np.argmax(np.abs(rows), axis=0), np.arange(hz.size)]
        np.testing.assert_allclose(rows / scale, body_shapes, rtol=0, atol=1e-12)


def test_contact_chain_files_are_its_simulation(tmp_path):
    """A chain with lash and a seat: its response.csv is the settled turn of a fresh
    simulation (``ChainContacts``) at the same speed, sample for sample; the tappet rides
    the cam's lift wherever the cam pushes it; the valve's seat contact force is written."""
    program = Program.load(LASH_EXAMPLE)
    rpm = 1000.0
    simulation = ChainContacts(program, program.chain, rpm)
    report = analyse(program, [rpm], steady=simulation)
    write_report(tmp_path, program, report, steady=simulation, points=720)
    h = read_response(tmp_path / "response.csv")[rpm]
    assert "drive_torque_n_m" not in h and "contact_stress_mpa" not in h
    # a one-sided contact force is never below zero: no -0, no undershoot between samples
    least = [report.speeds[0].min_contact_force_n, report.train["speeds"][0]["min_contact_force_n"]]
    assert least == [0.0, 0.0] and all(math.copysign(1.0, f) == 1.0 for f in least)
    turn = ChainContacts(program, program.chain, rpm).turns([rpm])[0]
    pairs = {
        "theta_deg": turn.theta_deg,
        "lift_mm": turn.lift_mm,
        "contact_force_n": turn.cam_force_n,
        "seat_force_n": turn.spring_seat_force_n,
        "surge_n": turn.surge_n,
        "seat_contact_force_n": turn.seat_contact_force_n,
        "payload_displacement_mm": turn.last_mm,
    }
    for j, name in enumerate(program.chain.names):
        pairs[f"{name}_displacement_mm"] = turn.displacement_mm[j]
        pairs[f"{name}_velocity_m_s"] = turn.velocity_m_s[j]
        pairs[f"{name}_acceleration_m_s2"] = turn.acceleration_m_s2[j]
    for key, expected in pairs.items():
        np.testing.assert_allclose(
            h[key], expected, rtol=1e-9, atol=1e-9 * np.max(np.abs(expected)), err_msg=key
        )
    np.testing.assert_array_equal(h["valve_displacement_mm"], h["payload_displacement_mm"])
    pushed = h["contact_force_n"] > 1.0
    assert pushed.sum() > 100
    np.testing.assert_allclose(
        h["tappet_displacement_mm"][pushed],
        program.lift(h["theta_deg"][pushed])[0],
        rtol=0,
        atol=1e-6,
    )
    # on the base circle the valve sits on its seat, which carries the preload
    base = h["theta_deg"] > 250.0
    np.testing.assert_allclose(
        h["seat_contact_force_n"][base], program.chain.spring.preload_n, rtol=1e-3
    )
    for name in ("contact_force.png", "svaj.png", "train.png", "modes.png", "seat_force.png"):
        assert (tmp_path / name).exists(), name


def test_body_named_like_a_column_is_one_line(tmp_path, capsys):
    """A body whose histories would repeat a column of the response: one line naming it."""
    data = tomllib.loads(two_body().to_toml())
    data["train"][1]["name"] = "payload"
    path = tmp_path / "bad.toml"
    path.write_text(Program.from_dict(data).to_toml())
    assert main(["program", str(path), "--rpm", "600", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "body 2 (payload)" in err and "payload_displacement_mm" in err


def test_response_of_a_chain_needs_its_train_rows():
    """A steady state built on an oscillator without the chain's rows: one line."""
    program = two_body()
    stand_in = Oscillator.of_follower(dataclasses.replace(program.follower, damping_ratio=0.05))
    steady = SteadyState(program, 600.0, oscillator=stand_in)
    with pytest.raises(ValueError, match="train rows") as error:
        response(program, 600.0, steady=steady)
    assert "\n" not in str(error.value)


def test_one_body_train_response_is_the_classic_one():
    """A one-body train spelled as the classic follower: its response is the classic
    follower's, and its body's columns are the payload's (its velocity the derivative of
    the displacement ``y - e`` written by hand from the deflection's state), its seat force
    the massless spring's ``F_0 + k_s x``."""
    from helpers import two_cycloids
    from test_train_program import one_body_train

    classic = two_cycloids()
    train = Program.from_dict(one_body_train(classic))
    rpm = 120.0
    a, b = response(classic, rpm), response(train, rpm)
    for key, values in a.items():
        np.testing.assert_allclose(
            b[key], values, rtol=0, atol=1e-12 * np.max(np.abs(values)) + 1e-300
        )
    np.testing.assert_array_equal(b["follower_displacement_mm"], b["payload_displacement_mm"])
    accel = b["payload_acceleration_m_s2"]  # the compiled turn's; the body's read on the host
    np.testing.assert_allclose(
        b["follower_acceleration_m_s2"], accel, rtol=0, atol=1e-12 * np.max(np.abs(accel))
    )
    steady = SteadyState(classic, rpm)
    e, e_rate = steady.oscillator.state(np.asarray(steady.cycle(rpm).q) / (60.0 / rpm))
    dy = classic.lift(a["theta_deg"])[1] * 360.0 * rpm / 60.0  # mm/s
    velocity = 1e-3 * (dy - e_rate)
    np.testing.assert_allclose(
        b["follower_velocity_m_s"], velocity, rtol=0, atol=1e-10 * np.max(np.abs(velocity))
    )
    f = classic.follower
    np.testing.assert_allclose(
        b["seat_force_n"],
        f.preload_n + f.spring_rate_n_per_mm * b["payload_displacement_mm"],
        rtol=1e-12,
    )


def test_a_simulated_chains_table_says_what_its_force_is(capsys):
    """The text table of a chain with lash and a seat: its contact force is the simulated one,
    which pushes only (no "contact held (linear)"), and its least value prints 0, never -0."""
    assert main(["program", LASH_EXAMPLE, "--rpm", "1000"]) == 0
    out = capsys.readouterr().out
    assert "contact held (linear)" not in out
    assert "Fc: contact force at the cam of the simulated periodic steady state" in out
    row = next(line.split() for line in out.splitlines() if line.split()[:1] == ["1000"])
    assert row[3] == "0"  # rpm, max|x''|, max|y''|, min Fc


def test_csv_says_where_the_train_section_is(tmp_path, capsys):
    """``--format csv`` has the speeds' rows only: with a chain, one line on stderr says the
    train section is in --format json and --out's summary.json; the classic follower none."""
    path = tmp_path / "two.toml"
    path.write_text(two_body().to_toml())
    assert main(["program", str(path), "--rpm", "600", "--format", "csv"]) == 0
    captured = capsys.readouterr()
    notes = [line for line in captured.err.splitlines() if line.startswith("note:")]
    assert len(notes) == 1 and "--format json" in notes[0] and "train section" in notes[0]
    assert captured.out.startswith("rpm,")
    assert main(["program", "indexer", "--rpm", "600", "--format", "csv"]) == 0
    assert "note:" not in capsys.readouterr().err
