"""The least seating velocity over a speed range as a design objective of a chain with lash
and a seat: its value against the simulation's own reading, its derivatives against central
differences of that reading, a short design that lowers it, and its refusals."""

from __future__ import annotations

import dataclasses
import warnings

import jax.numpy as jnp
import numpy as np
import pytest

from camjax.cli import main
from camjax.laws import CorrectedPolynomial
from camjax.program import ChainContacts, Program, design_segment

EXAMPLE = "camjax/program/examples/trains/valve_lash.toml"
CLOSING = (
    4  # the example's closing onto its closing ramp: a degree-7 polynomial in motion at its end
)


@pytest.fixture(scope="module")
def example():
    return Program.load(EXAMPLE)


def _goal(program, rpm_lo, rpm_hi, count):
    from camjax.program import MaxSeatingVelocity  # imports optax: only when designing

    return MaxSeatingVelocity(program, CLOSING, rpm_lo, rpm_hi, count=count)


def _corrected(program, coefficients):
    """The closing as the design holds it: its polynomial plus a B-spline correction."""
    return CorrectedPolynomial(program.segments[CLOSING - 1].law, jnp.asarray(coefficients), 5)


def _largest_seating(program, speeds) -> float:
    """The largest seating velocity (m/s) of the program's chain over ``speeds``, simulated
    apart from the design (unrefined turns, as the design reads them)."""
    turns = ChainContacts(program, program.chain, min(speeds)).turns(speeds, refine=False)
    return max(t.seating_velocity_m_s for t in turns)


@pytest.mark.slow
def test_seating_objective_reads_the_simulation_and_its_derivative_is_the_differences(example):
    """The objective's value (the landing read in JAX from the settled start state, on the
    law's own grid) is the simulation's reading of the original program at every speed, to
    1e-6: both read the same sampled path (the integrator's error control, rtol 1e-8, is what
    may part them).  Its derivative along a direction is the central difference of the
    simulation's reading (settled from rest each time) to 1e-4 of the gradient's size: the
    step (1e-4 of the lift) keeps the landing in one sample interval at both ends (asserted;
    across one the reading jumps by its extrapolation's error, about 6e-5 of its value),
    and the difference's truncation and the integrator's tolerance are below that."""
    goal = _goal(example, 2000.0, 2500.0, 2)
    speeds = goal.speeds()
    assert speeds == pytest.approx([2000.0, 2500.0])
    own = ChainContacts(example, example.chain, 2000.0).turns(speeds, refine=False)
    start = _corrected(example, np.zeros(8))
    model = goal.linearised(start)
    assert model.values == pytest.approx([t.seating_velocity_m_s for t in own], rel=1e-6)
    # the same law as a corrected polynomial samples to rounding apart: the error control too
    assert model.reported == pytest.approx([t.seating_velocity_m_s for t in own], rel=1e-6)
    assert model.values == pytest.approx(model.reported, rel=1e-6)
    assert goal.report(start) == pytest.approx(max(model.reported), rel=1e-12)
    direction = np.random.default_rng(3).normal(size=8)
    direction /= np.linalg.norm(direction)
    h = 1e-4
    ends = [goal._turns(_corrected(example, sign * h * direction))[1] for sign in (1.0, -1.0)]
    plus, minus = ([t.seating_velocity_m_s for t in end] for end in ends)
    assert [t.seating_sample for t in ends[0]] == [t.seating_sample for t in ends[1]]
    difference = (np.array(plus) - np.array(minus)) / (2 * h)
    derivative = model.jacobian @ direction
    scale = np.linalg.norm(model.jacobian, axis=1)
    assert np.all(scale > 1.0)  # the law moves the landing: a derivative to check
    assert np.abs(derivative - difference) == pytest.approx(
        np.zeros(2), abs=1e-4 * float(scale.min())
    )


@pytest.mark.slow
def test_a_short_seating_design_lowers_it_and_reports_what_it_is(example):
    """Two rounds over two speeds: the designed program's seating velocity, simulated
    apart, is the one reported, below the start's (the example's own law, simulated apart
    too); where a design does not improve it says so and keeps the program."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        designed, result = design_segment(
            example,
            CLOSING,
            2500.0,
            3000.0,
            objective="seating",
            knots=8,
            steps=300,
            rounds=2,
            seating_speeds=2,
            progress=False,
        )
    (label,) = result.values
    speeds = [2500.0, 3000.0]

    def largest(program):
        return _largest_seating(program, speeds)

    start = largest(example)
    assert result.initial_values[label] == pytest.approx(
        start, rel=1e-6
    )  # its law as the design holds it
    if result.kept_initial:
        assert any("did not improve" in str(w.message) for w in caught)
        assert designed == example
    else:
        assert result.values[label] == pytest.approx(largest(designed), rel=1e-9)
        assert result.values[label] < 0.9 * start


def test_seating_needs_a_seat(example, tmp_path, capsys):
    """A program without a seat (a chain without one, the classic follower) is refused in
    one line naming the seat, at the library and at the command line."""
    valve = Program.load("camjax/program/examples/trains/valve.toml")
    assert valve.chain is not None and valve.chain.seat is None
    for program in (valve, Program.load("camjax/program/examples/indexer.toml")):
        with pytest.raises(ValueError, match=r"needs a valve seat") as error:
            design_segment(program, 1, 600.0, 900.0, objective="seating", progress=False)
        assert "\n" not in str(error.value)
    with pytest.raises(ValueError, match="count of speeds"):
        _goal(example, 2500.0, 3000.0, 0)
    with pytest.raises(ValueError, match="seating_speeds: only with objective 'seating'"):
        design_segment(example, CLOSING, 2500.0, 3000.0, objective="preload", seating_speeds=2)
    argv = [
        "design",
        "--program",
        "camjax/program/examples/trains/valve.toml",
        "--segment",
        "1",
        "--rpm",
        "600:900",
        "--objective",
        "seating",
        "--out",
        str(tmp_path / "out"),
        "--quiet",
    ]
    assert main(argv) != 0
    err = capsys.readouterr().err.strip()
    assert "needs a valve seat" in err and "\n" not in err
    assert (
        main(["design", "--objective", "seating", "--band", "1:2", "--out", str(tmp_path / "o2")])
        != 0
    )
    assert "--objective seating needs --program" in capsys.readouterr().err
    for option in ("--rounds", "--seating-speeds"):
        assert main([*argv, option, "0"]) != 0
        assert f"{option}: must be a whole number of at least 1" in capsys.readouterr().err
        residual = [*("residual" if a == "seating" else a for a in argv), option, "2"]
        assert main(residual) != 0
        assert f"{option}: only with --objective seating" in capsys.readouterr().err


@pytest.mark.parametrize("option", ["rpm_lo", "rpm_hi"])
def test_a_traced_seating_bound_is_refused_in_one_line(example, option):
    """The seating objective's speed bounds choose its speeds and simulations on the host:
    one traced under ``jax.jit``, ``jax.grad`` or ``jax.vmap`` (and through
    ``design_segment``) is refused in one line naming it, as the program's other objectives
    refuse one, with no other warning or error first; a concrete array given as one speed is
    held as a Python float (no static-array warning), several speeds are refused."""
    import jax

    from camjax.program import MaxSeatingVelocity

    bounds = {"rpm_lo": 2500.0, "rpm_hi": 3000.0}
    inside = {"rpm_lo": 2600.0, "rpm_hi": 2900.0}[option]

    def largest(value):
        goal = MaxSeatingVelocity(example, CLOSING, **{**bounds, option: value}, count=2)
        return goal.value(jnp.ones(2) * value, None, 8.0)

    message = f"{option} must be concrete speeds here (not traced inside jit, vmap or grad)"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for transform, value in (
            (jax.jit, inside),
            (jax.grad, inside),
            (jax.vmap, jnp.array([inside, inside + 10.0])),
        ):
            with pytest.raises(ValueError) as error:
                transform(largest)(value)
            assert str(error.value) == message
        with pytest.raises(ValueError) as error:
            jax.jit(
                lambda v: design_segment(
                    example, CLOSING, **{**bounds, option: v}, objective="seating"
                )
            )(inside)
        assert str(error.value) == message
        goal = MaxSeatingVelocity(
            example, CLOSING, **{**bounds, option: jnp.asarray(bounds[option])}, count=2
        )
    assert type(getattr(goal, option)) is float and list(goal.speeds()) == [2500.0, 3000.0]
    for several in ([2500.0, 2600.0], np.array([2500.0, 2600.0]), jnp.array([2500.0, 2600.0])):
        with pytest.raises(ValueError, match=f"^{option} must be one speed in rpm, got 2$"):
            MaxSeatingVelocity(example, CLOSING, **{**bounds, option: several}, count=2)


@pytest.mark.slow
def test_a_rest_to_rest_closing_is_designed_as_a_spline(tmp_path):
    """The valve example's cycloidal cam (no ramps) on the lash example's chain and seat: its
    return, from rest to rest, is designed as a B-spline; the start reported is the cycloid's
    own seating velocity and the designed one is the designed program's, each simulated
    apart."""
    cam = Program.load("camjax/program/examples/trains/valve.toml")
    lash = Program.load(EXAMPLE)
    program = dataclasses.replace(lash, segments=cam.segments, name="cycloidal valve")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        designed, result = design_segment(
            program,
            3,
            1500.0,
            2000.0,
            objective="seating",
            knots=8,
            steps=200,
            rounds=2,
            seating_speeds=2,
            progress=False,
        )
    (label,) = result.values

    def largest(p):
        return _largest_seating(p, [1500.0, 2000.0])

    assert result.initial_values[label] == pytest.approx(largest(program), rel=1e-12)
    if result.kept_initial:
        assert any("did not improve" in str(w.message) for w in caught)
        assert designed == program
    else:
        assert designed.segments[2].law.name.startswith("bspline")
        assert result.values[label] == pytest.approx(largest(designed), rel=1e-12)
        assert result.values[label] < result.initial_values[label]
