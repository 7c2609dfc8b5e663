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
from camjax.checks import MAX_SPEEDS
from camjax.program import Program, example_path

BAD = [
    (-300.0, "must be positive and finite, got -300"),
    (math.nan, "must be positive and finite, got nan"),
    (math.inf, "must be positive and finite, got inf"),
    ([], "must be one speed or a 1-D list of speeds"),
    ("300", "must be a speed in rpm or a 1-D list of speeds, got '300'"),
    (True, "must be a speed in rpm or a 1-D list of speeds, got True"),
    (np.linspace(200.0, 1400.0, MAX_SPEEDS + 1), f"has {MAX_SPEEDS + 1:,} speeds, more than the "
     f"{MAX_SPEEDS:,} one analysis takes (about 0.45 MB of memory a speed); give fewer speeds"),
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


@pytest.mark.parametrize("bad, message", BAD, ids=["negative", "nan", "inf", "empty", "string", "bool", "too-many"])
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


def test_speeds_are_a_value_checked_once_when_built(feed):
    """``Speeds``: built from a range string, a list, an array or a number, checked then;
    read-only; passed through unchecked by ``Speeds.of``; a subset is a ``Speeds``."""
    speeds = cp.Speeds.parse("300:900:101")
    np.testing.assert_array_equal(speeds.rpm, np.linspace(300.0, 900.0, 101))
    assert cp.Speeds.parse("300,450").tolist() == [300.0, 450.0] == cp.Speeds([300, 450]).tolist()
    assert cp.Speeds(np.array([600.0])) == cp.Speeds(600.0) and len(cp.Speeds(600.0)) == 1
    assert cp.Speeds.of(speeds) is speeds
    assert (speeds.min(), speeds.max(), speeds[0]) == (300.0, 900.0, 300.0)
    assert isinstance(speeds[speeds.rpm > 600.0], cp.Speeds) and speeds[speeds.rpm > 600.0].min() > 600.0
    with pytest.raises(ValueError):
        speeds.rpm[0] = -1.0  # read-only: no bad speed after the check
    source = np.array([300.0, 600.0])
    kept = cp.Speeds(source)
    source[0] = -1.0  # the value is its own copy
    assert kept.min() == 300.0
    for text, message in (("300,-1", "rpm: speeds must be positive and finite, got '300,-1'"),
                          ("900:300:3", "rpm: START must be below STOP"),
                          ("300:900:x", "rpm: COUNT must be an integer")):
        with pytest.raises(ValueError, match=f"^{message}"):
            cp.Speeds.parse(text)
    # an entry point takes the value as it is: |lift| Ca / t^2, the feed's closed form
    expected = cp.kinematic_acceleration_m_s2(feed, [300.0, 900.0])
    np.testing.assert_array_equal(cp.kinematic_acceleration_m_s2(feed, cp.Speeds.parse("300:900:2")), expected)
    np.testing.assert_allclose(expected[1] / expected[0], 9.0, rtol=1e-14)


def test_the_command_refuses_too_many_speeds_before_building_them(capsys):
    """A COUNT of 1e12 would need 8 TB for the range alone: refused from the count."""
    from camjax.cli import main

    for rpm in (f"200:1400:{10**12}", ",".join(["300"] * (MAX_SPEEDS + 1))):
        assert main(["program", "--rpm", rpm]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and err.startswith("camjax program: error: --rpm has ")
        assert f"more than the {MAX_SPEEDS:,} one analysis takes" in err and "split the range" in err


@pytest.mark.parametrize("option", ["rpm_lo", "rpm_hi"])
def test_a_design_bound_is_one_speed_not_the_first_of_several(feed, option):
    """A design's speed bound given as several speeds is refused in one line naming it (it
    used to take the first silently), as NumPy or JAX array or list alike, and an array
    given as one speed raises no warning of a static array."""
    import warnings

    bounds = {"rpm_lo": 300.0, "rpm_hi": 600.0}
    for several in ([300.0, 500.0], np.array([300.0, 500.0]), jnp.array([300.0, 500.0])):
        for call in (cp.design_segment, cp.MaxPreload, cp.segment_band):
            with pytest.raises(ValueError, match=f"^{option} must be one speed in rpm, got 2$"):
                call(feed, 2, **{**bounds, option: several})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        objective = cp.MaxPreload(feed, 2, rpm_lo=np.float64(300.0), rpm_hi=jnp.asarray(600.0))
    assert (objective.rpm_lo, objective.rpm_hi) == (300.0, 600.0)
    assert type(objective.rpm_hi) is float
