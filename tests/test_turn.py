"""The program's turn (``Program.turn``): the one reader of the lift over the turn, against
the cycloidal law's closed form, at joins that are not whole degrees, concrete and traced."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import FOLLOWER

from camjax import laws
from camjax.program import Follower, Program, Segment, TurnLaw

# dwell, rise, dwell, return, with joins at awkward angles (not whole degrees)
ANGLES = (37.3, 112.77, 60.0 + 1 / 3, 360.0 - 37.3 - 112.77 - (60.0 + 1 / 3))
LIFT = 12.5


def _program():
    law = laws.get("cycloidal")
    return Program("awkward", (Segment(ANGLES[0]), Segment(ANGLES[1], LIFT, law), Segment(ANGLES[2]),
                               Segment(ANGLES[3], -LIFT, law)), Follower(**FOLLOWER))


def _closed_form(theta_deg):
    """``(y, y', y'', y''')`` of the program from the cycloid ``s = t - sin(2 pi t) / 2 pi``."""
    theta = np.mod(np.asarray(theta_deg, dtype=float), 360.0)
    starts = np.cumsum((0.0,) + ANGLES)
    y, dy, ddy, dddy = (np.zeros_like(theta) for _ in range(4))
    for k, sign, base in ((1, 1.0, 0.0), (3, -1.0, LIFT)):
        beta = ANGLES[k]
        inside = (theta >= starts[k]) & (theta <= starts[k + 1])
        t = (theta[inside] - starts[k]) / beta
        w = 2 * math.pi
        h = sign * LIFT
        y[inside] = base + h * (t - np.sin(w * t) / w)
        dy[inside] = h * (1 - np.cos(w * t)) / beta
        ddy[inside] = h * w * np.sin(w * t) / beta**2
        dddy[inside] = h * w * w * np.cos(w * t) / beta**3
    y[(theta > starts[2]) & (theta < starts[3])] = LIFT
    return y, dy, ddy, dddy


def test_the_turns_jet_is_the_cycloids_closed_form_everywhere():
    theta = np.linspace(0.0, 360.0, 7201)
    y, dy, ddy, dddy = _program().turn.jet(theta)
    ry, rdy, rddy, rdddy = _closed_form(theta)
    for got, want, scale in ((y, ry, LIFT), (dy, rdy, LIFT / 60), (ddy, rddy, LIFT / 60**2)):
        np.testing.assert_allclose(got, want, atol=1e-12 * scale)
    inside = np.abs(rdddy) > 0  # the jerk steps at a cycloid's ends: compare inside them
    np.testing.assert_allclose(dddy[inside], rdddy[inside], atol=1e-12 * LIFT / 60**3)


@pytest.mark.parametrize("hair", [0.0, 1e-12, -1e-12])
def test_a_join_within_rounding_reads_the_segment_on_the_side_asked(hair):
    """At the rise's end (awkward angle) the jerk steps from ``4 pi^2 h / beta^3`` to 0."""
    program = _program()
    end = ANGLES[0] + ANGLES[1] + hair
    before = program.turn.jet(np.array([end]), side="before")
    after = program.turn.jet(np.array([end]), side="after")
    assert before[0][0] == pytest.approx(LIFT, abs=1e-12) and after[0][0] == pytest.approx(LIFT, abs=1e-12)
    assert before[3][0] == pytest.approx(4 * math.pi**2 * LIFT / ANGLES[1] ** 3, rel=1e-12)
    assert after[3][0] == 0.0
    start = ANGLES[0] + hair  # the rise's start: its velocity is 0, its jerk not
    assert program.turn.jet(np.array([start]), side="after")[3][0] == pytest.approx(
        4 * math.pi**2 * LIFT / ANGLES[1] ** 3, rel=1e-12)
    assert program.turn.jet(np.array([start]), side="before")[3][0] == 0.0


def test_traced_and_concrete_turns_agree_and_differentiate():
    program = _program()
    turn = program.turn
    joins = np.cumsum(ANGLES)
    theta = np.concatenate([np.linspace(0.0, 359.9, 997), joins, joins + 1e-12, joins - 1e-12])
    concrete = turn.jet(theta)
    traced = jax.jit(lambda t, turn: turn.jet(t))(jnp.asarray(theta), turn)
    for a, b in zip(concrete, traced):
        np.testing.assert_allclose(np.asarray(b), a, rtol=1e-13, atol=1e-13)
    # the JAX displacement (radians in, mm out) differentiates to the jet's slope, joins included
    slope = jax.vmap(jax.grad(program.displacement))(jnp.radians(jnp.asarray(theta)))
    np.testing.assert_allclose(np.asarray(slope), concrete[1] * 180 / math.pi, rtol=1e-11, atol=1e-12)


def test_the_groove_law_is_the_turn_normalised():
    program = _program()
    tau = np.linspace(0.0, 3.0, 601)  # three turns: periodic
    s, v, a, _ = (np.asarray(x) for x in TurnLaw.of(program, LIFT, 3).evaluate(tau))
    y, dy, ddy, _ = _closed_form(360.0 * tau)
    np.testing.assert_allclose(s, y / LIFT, atol=1e-12)
    np.testing.assert_allclose(v, 360 * dy / LIFT, atol=1e-10)
    np.testing.assert_allclose(a, 360**2 * ddy / LIFT, atol=1e-8)


def test_a_side_other_than_before_or_after_is_refused():
    with pytest.raises(ValueError, match="side must be 'before' or 'after', got 'left'"):
        _program().turn.jet(np.array([10.0]), side="left")


def test_an_angle_that_is_not_a_number_is_refused():
    for bad in (math.nan, math.inf):
        with pytest.raises(ValueError, match="cam angles must be finite"):
            _program().lift(np.array([10.0, bad]))
