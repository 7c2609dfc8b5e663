"""Every public entry point of a cam program checks its speeds once, at entry: a bad speed
(negative, NaN, infinite, none, not a number) is a one-line ``ValueError`` that names the
option, before any work; the functions inside take the checked speeds as they are."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import COMPILED_RTOL

from camjax import program as cp
from camjax.program import Program, example_path

BAD = [
    (-300.0, "must be positive and finite, got -300"),
    (math.nan, "must be positive and finite, got nan"),
    (math.inf, "must be positive and finite, got inf"),
    ([], "must be one speed or a 1-D list of speeds"),
    ("300", "must be a speed in rpm or a 1-D list of speeds, got '300'"),
    (True, "must be a speed in rpm or a 1-D list of speeds, got True"),
]


@pytest.fixture(scope="module")
def feed():
    return Program.load(example_path("feed"))


@pytest.fixture(scope="module")
def steady(feed):
    return cp.SteadyState(feed, 300.0)


def _entry_points(feed, steady, tmp):
    """``(option, call)``: each public entry point with the bad speed in that option."""
    machine = cp.Machine("two", ((feed, 0.0), (feed, 90.0)))
    grooved = Program.load(example_path("indexer"))
    return [
        ("rpm", lambda bad: cp.analyse(feed, bad)),
        ("rpm", lambda bad: cp.response(feed, bad)),
        ("rpm", lambda bad: cp.startup(feed, bad, 1)),
        ("rpm", lambda bad: cp.node_contact_force(feed, bad)),
        ("rpm_min", lambda bad: cp.node_contact_force(feed, [300.0], rpm_min=bad)),
        ("rpm", lambda bad: cp.kinematic_acceleration_m_s2(feed, bad)),
        ("rpm", lambda bad: cp.period_ratios(feed, bad)),
        ("rpm", lambda bad: cp.groove_turns(grooved, bad)),
        ("rpm", lambda bad: cp.analyse_machine(machine, bad)),
        ("rpm", lambda bad: cp.shaft_figures(tmp, machine, {}, bad)),
        ("rpm_lo", lambda bad: cp.design_segment(feed, 2, bad, 600.0)),
        ("rpm_hi", lambda bad: cp.design_segment(feed, 2, 300.0, bad)),
        ("rpm_lo", lambda bad: cp.MaxPreload(feed, 2, bad, 600.0)),
        ("rpm_lo", lambda bad: cp.segment_band(feed, 2, bad, 600.0)),
        ("rpm_min", lambda bad: cp.SteadyState(feed, bad)),
        ("rpm", lambda bad: steady.summary(bad)),
        ("rpm", lambda bad: steady.cycles_at(bad)),
        ("rpm", lambda bad: steady.cycle(bad)),
        ("rpm", lambda bad: steady.min_contact_force_n(bad)),
        ("rpm_lo", lambda bad: cp.jump_speed_rpm(steady, bad, 600.0)),
        ("rpm_hi", lambda bad: cp.jump_speed_rpm(steady, 300.0, bad)),
        ("rpm", lambda bad: cp.flights(steady, bad)),
        ("rpm", lambda bad: cp.flights_at(steady, bad)),
        ("rpm", lambda bad: cp.flight(steady, bad)),
    ]


@pytest.mark.parametrize("bad, message", BAD, ids=["negative", "nan", "inf", "empty", "string", "bool"])
def test_every_entry_point_refuses_a_bad_speed_in_one_line(feed, steady, tmp_path, bad, message):
    for option, call in _entry_points(feed, steady, tmp_path):
        with pytest.raises(ValueError) as caught:
            call(bad)
        text = str(caught.value)
        assert text.startswith(f"{option} {message}"), text
        assert "\n" not in text


def test_a_design_range_must_run_upwards(feed, steady):
    with pytest.raises(ValueError, match=r"^need 0 < rpm_lo < rpm_hi, got 600, 300$"):
        cp.design_segment(feed, 2, 600.0, 300.0)
    with pytest.raises(ValueError, match=r"^need rpm_lo <= rpm_hi, got 600, 300$"):
        cp.jump_speed_rpm(steady, 600.0, 300.0)


def test_a_traced_speed_is_checked_when_the_computation_runs(feed):
    """``node_contact_force`` is jittable in ``rpm`` (with ``rpm_min`` concrete): a bad
    traced speed raises the same message when the program runs; good ones give the
    force of the concrete speeds."""
    force = jax.jit(lambda r: cp.node_contact_force(feed, r, rpm_min=1000.0))  # a coarse grid
    # good speeds pass the check unchanged: the force of the same speeds given concretely
    # (inside a jit too: eagerly the vmap runs op by op, 12 s)
    concrete = jax.jit(lambda: cp.node_contact_force(feed, [1000.0, 1200.0]))()
    np.testing.assert_allclose(force(jnp.array([1000.0, 1200.0])), concrete, rtol=COMPILED_RTOL)  # constants folded
    for bad in (-300.0, np.nan, np.inf):
        with pytest.raises(Exception, match="rpm must be positive and finite"):
            jax.block_until_ready(force(jnp.array([1200.0, bad])))
    with pytest.raises(ValueError, match="rpm_min is needed where rpm is traced"):
        jax.jit(lambda r: cp.node_contact_force(feed, r))(jnp.array([300.0]))
