"""A valve's seat: its landings read from a turn's samples, and the seats and chains that
never let the valve leave it (refused before simulating, or warned of in the report)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from camjax.program import ChainContacts, Program, seat_landings

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
