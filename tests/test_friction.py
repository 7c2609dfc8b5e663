"""Coulomb friction with stick-slip: closed forms, the exact SDOF, and three solution paths."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import camjax
from camjax.models import CoulombFriction, free_vibration

solve = camjax.solve

SAMPLES = 512  # samples per rise; one static setting, so the events path compiles once


@pytest.fixture(scope="module")
def cycloidal():
    return camjax.laws.Cycloidal()


def test_free_vibration_decays_linearly_by_four_mu_over_w2_per_cycle():
    model = CoulombFriction(2.0, 1.0)
    w = 2 * np.pi * 2.0
    band = 1.0 / w**2
    fv = free_vibration(model, 0.1, 0.0)
    times = np.asarray(fv.reversal_time)
    finite = np.isfinite(times)
    x = np.concatenate([[0.1], np.asarray(fv.reversal_position)[finite]])
    # Half a period between reversals; each half cycle swings about the centre
    # sign(x) mu / w^2, so x_(k+1) = -x_k + 2 mu / w^2 sign(x_k): 4 mu / w^2 lost a cycle.
    np.testing.assert_allclose(np.diff(times[finite]), np.pi / w, rtol=1e-12)
    np.testing.assert_allclose(x[1:], -x[:-1] + 2 * band * np.sign(x[:-1]), rtol=1e-10, atol=1e-15)
    swinging = np.abs(x[:-1])  # every reversal but the one where it sticks
    np.testing.assert_allclose(swinging[2:] - swinging[:-2], -4 * band, rtol=1e-10)
    # It sticks at the first reversal inside the band, after ceil((0.1 - band) / (2 band)) of them.
    k = int(np.ceil((0.1 - band) / (2 * band)))
    assert finite.sum() == k
    assert np.all(np.abs(x[:-1]) > band) and abs(float(fv.rest_position)) <= band
    np.testing.assert_allclose(float(fv.rest_position), (-1) ** k * (0.1 - 2 * k * band), rtol=1e-10)
    np.testing.assert_allclose(float(fv.stick_time), k * np.pi / w, rtol=1e-12)


def test_free_vibration_with_viscous_damping_matches_scipy_events():
    model = CoulombFriction(1.5, 2.0, 0.05)
    w, zeta, mu = 2 * np.pi * 1.5, 0.05, 2.0
    fv = free_vibration(model, -0.08, 0.3)

    def field(t, y, direction):
        return [y[1], -(w**2) * y[0] - 2 * zeta * w * y[1] - mu * direction]

    t, y, times, positions = 0.0, np.array([-0.08, 0.3]), [], []
    direction = np.sign(y[1])
    while True:
        reversal = lambda t, y, d=direction: y[1]  # noqa: E731
        reversal.terminal, reversal.direction = True, -direction
        sol = solve_ivp(field, (t, t + 50), y, args=(direction,), events=reversal,
                        method="DOP853", rtol=1e-12, atol=1e-14)
        t, y = sol.t_events[0][0], sol.y_events[0][0]
        times.append(t)
        positions.append(y[0])
        if abs(w**2 * y[0]) <= mu:
            break
        direction = -np.sign(y[0])
        y = np.array([y[0], 0.0])
    k = len(times)
    np.testing.assert_allclose(np.asarray(fv.reversal_time)[:k], times, rtol=1e-9)
    np.testing.assert_allclose(np.asarray(fv.reversal_position)[:k], positions, rtol=1e-8, atol=1e-12)
    assert np.isinf(np.asarray(fv.reversal_time)[k])
    np.testing.assert_allclose(float(fv.rest_position), positions[-1], rtol=1e-8)


def test_zero_friction_reproduces_exact_sdof(cycloidal):
    response = solve(cycloidal, CoulombFriction(5.25, 0.0), samples=SAMPLES)
    exact = camjax.solve(cycloidal, camjax.SpringMass(5.25))
    # Deflection e = s - x at the end of the rise and the end of the dwell.
    tau = np.asarray(response.tau)
    for t in (1.0, 2.0):
        i = int(np.argmin(np.abs(tau - t)))
        j = int(np.argmin(np.abs(np.asarray(exact.tau) - t)))
        assert tau[i] == t and float(exact.tau[j]) == pytest.approx(t, abs=1e-14)
        e = float(cycloidal.s(t) - response.position[i])
        assert e == pytest.approx(float(exact.deflection[j]), abs=1e-10)
    # Ct refined between samples (512 per period) agrees with the exact path's.
    assert float(response.metrics.ct) == pytest.approx(float(exact.metrics.ct), rel=1e-7)
    assert float(response.metrics.residual) == pytest.approx(float(exact.metrics.residual), rel=1e-8)
    assert float(response.metrics.peak_in_motion) == pytest.approx(
        float(exact.metrics.peak_in_motion), rel=1e-7
    )
    assert not bool(response.settled)


@pytest.mark.parametrize(
    "law_name, n, mu, zeta",
    [
        ("cycloidal", 5.25, 0.5, 0.0),
        ("cycloidal", 3.3, 1.0, 0.02),
        ("modified-sine", 4.5, 2.0, 0.0),
        ("modified-trapezoid", 3.3, 1.0, 0.02),
    ],
)
def test_events_agree_with_piecewise_exact_dwell_and_rest_in_band(law_name, n, mu, zeta):
    law = camjax.laws.get(law_name)
    model = CoulombFriction(n, mu, zeta)
    response = solve(law, model, samples=SAMPLES)
    i_end = int(np.argmin(np.abs(np.asarray(response.tau) - 1.0)))
    # The dwell from the events path's state at tau = 1, propagated in closed form.
    fv = free_vibration(model, response.position[i_end] - 1.0, response.velocity[i_end])
    band = mu / (2 * np.pi * n) ** 2
    assert bool(response.settled)
    assert float(fv.stick_time) < 1.0
    assert float(response.rest_offset) == pytest.approx(float(fv.rest_position), abs=1e-9)
    assert abs(float(response.rest_offset)) <= band * (1 + 1e-9)
    assert abs(float(response.rest_offset)) > 0  # out of position, as the note warns
    # Stuck from the closed-form stick time on (samples after it, with a little margin).
    after = np.asarray(response.tau) > 1.0 + float(fv.stick_time) + 1e-6
    assert np.all(np.asarray(response.stuck)[after])


def _poly4567(t):
    """Position and velocity of the 4-5-6-7 polynomial rise, then the dwell (numpy)."""
    t = np.minimum(t, 1.0)
    return 35 * t**4 - 84 * t**5 + 70 * t**6 - 20 * t**7, 140 * t**3 * (1 - t) ** 3


def _stick_slip_reference(command, n, mu, t_end, max_step=np.inf):
    """Stick-slip of the undamped SDOF by scipy: DOP853 slip phases ending at x' = 0
    (events), stick phases ending where ``|w^2 (s - x)| = mu`` (grid scan and brentq).
    Returns the phases as ``(start, mode, x0, dense solution or None)``."""
    w2 = (2 * np.pi * n) ** 2
    t, x, mode, phases = 0.0, 0.0, 0, []
    while t < t_end:
        if mode == 0:
            phases.append((t, 0, x, None))
            grid = np.linspace(t, t_end, int((t_end - t) * 4000) + 2)
            above = np.nonzero(np.abs(w2 * (command(grid)[0] - x)) - mu > 0)[0]
            if above.size == 0:
                break
            k = above[0]
            t = brentq(lambda u, x=x: abs(w2 * (command(u)[0] - x)) - mu, grid[k - 1], grid[k], xtol=1e-15)
            mode = 1 if command(t)[0] > x else -1
        else:
            def field(u, y, d=mode):
                return [y[1], w2 * (command(u)[0] - y[0]) - mu * d]

            reversal = lambda u, y: y[1]  # noqa: E731
            reversal.terminal, reversal.direction = True, -mode
            sol = solve_ivp(field, (t, t_end), [x, 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                            events=reversal, dense_output=True, first_step=1e-5, max_step=max_step)
            phases.append((t, mode, x, sol.sol))
            if sol.t_events[0].size == 0:
                break
            t, x = sol.t_events[0][0], sol.y_events[0][0][0]
            force = w2 * (command(t)[0] - x)
            mode = 0 if abs(force) <= mu else int(np.sign(force))
    return phases


def _reference_positions(phases, tau):
    """The scipy reference's position at each ``tau``, from the phase that contains it."""
    starts = np.array([p[0] for p in phases])
    out = []
    for t in tau:
        _, mode, x0, dense = phases[np.searchsorted(starts, t, side="right") - 1]
        out.append(x0 if mode == 0 else dense(t)[0])
    return np.asarray(out)


@pytest.mark.parametrize("n, mu", [(5.25, 0.1), (5.25, 0.5), (2.5, 1.0), (2.5, 100.0), (2.5, 1e9)])
def test_residual_is_the_dwells_first_swing_and_zero_for_a_payload_held(cycloidal, n, mu):
    """Undamped, R is w^2 times the first slip's amplitude about its shifted centre: the
    largest |x''| over the dwell's first half period (sampled: 1e-3); a payload held by
    friction has none (it was the frictionless spring's w^2 |1 - x|: R = 39 at n = 2.5 with
    the payload never moving)."""
    response = camjax.solve(cycloidal, CoulombFriction(n, mu), dwell=1.0)
    tau, acc = np.asarray(response.tau), np.abs(np.asarray(response.payload_acceleration))
    first_swing = acc[(tau >= 1.0) & (tau <= 1.0 + 0.5 / n)].max() / cycloidal.Ca
    residual = float(response.metrics.residual)
    assert residual == pytest.approx(first_swing, rel=1e-3, abs=1e-15)
    if mu >= 100:  # stuck before the dwell; at 1e9 it never moves
        assert residual == 0.0 and (mu < 1e9 or float(response.metrics.ct) == 0.0)


def test_stick_starting_near_the_end_of_the_rise_matches_scipy_reference():
    """4-5-6-7 polynomial, n = 5.25, mu = 0.3: a stick phase from tau = 0.928 to 0.944,
    where the transmission force w^2 (s - x) ~ 1088 (s - x) is resolved only to ~1e-11,
    used to fail the event root finder (Newton, |g| < 1e-13)."""
    law = camjax.laws.get("poly4567")
    response = solve(law, CoulombFriction(5.25, 0.3), samples=SAMPLES)
    phases = _stick_slip_reference(_poly4567, 5.25, 0.3, 2.0)
    assert [p[1] for p in phases] == [0, 1, -1, 0, 1, 0]
    assert 0.92 < phases[3][0] < 0.93 < 0.94 < phases[4][0] < 0.95
    tau = np.asarray(response.tau)
    starts = np.array([p[0] for p in phases])
    np.testing.assert_allclose(np.asarray(response.position), _reference_positions(phases, tau),
                               rtol=0, atol=2e-9)
    assert int(response.stats["segments"]) == len(phases)
    assert bool(response.settled)
    assert float(response.rest_offset) == pytest.approx(phases[-1][2] - 1.0, abs=1e-10)
    # Stuck over the last two stick phases, slipping between them (2e-4 inside each phase).
    for (start, mode, *_), end in zip(phases[3:], [*starts[4:], 2.0]):
        inside = (tau > start + 2e-4) & (tau < end - 2e-4)
        assert inside.any() and np.all(np.asarray(response.stuck)[inside] == (mode == 0))


def test_a_short_stick_phase_inside_the_rise_is_not_stepped_over():
    """4-5-6-7, n = 5.25, mu = 1.15: the velocity dips to zero near tau = 0.9208 and the
    payload sticks for 1.5e-3 (a 1/100 of a period) before it slips on.  A slip step of 1/8
    of a period stepped over the reversal (a sign change and back within one step); the
    invariant check reported it; with slip steps of 1/64 of a period the phase is found.
    Reference: scipy, DOP853 with max_step 1e-4 and a grid scan of the stick force."""
    law = camjax.laws.get("poly4567")
    response = solve(law, CoulombFriction(5.25, 1.15), samples=SAMPLES)
    phases = _stick_slip_reference(_poly4567, 5.25, 1.15, 2.0, max_step=1e-4)
    assert [p[1] for p in phases] == [0, 1, 0, 1, 0]
    assert phases[3][0] - phases[2][0] < 2e-3
    tau = np.asarray(response.tau)
    np.testing.assert_allclose(np.asarray(response.position), _reference_positions(phases, tau),
                               rtol=0, atol=2e-9)
    assert int(response.stats["segments"]) == len(phases)


def _modified_sine_command():
    """Position of the modified-sine rise, then the dwell, as a NumPy function of tau (the
    law's own closed form, compiled once: the reference's input, not under test)."""
    law = camjax.laws.get("modified-sine")
    position = jax.jit(lambda t: law.s(jnp.minimum(t, 1.0)))
    return lambda t: (np.asarray(position(np.asarray(t, dtype=float))),)


@pytest.mark.parametrize(
    "n, sequence",
    [
        (7.01508, [0, 1, 0, 1, 0]),  # a stick of 9e-4 near tau = 0.9753
        (7.0, [0, 1, -1, 0, 1, 0]),  # a reversal there
        (7.0152, [0, 1, 0]),  # past the grazing ratio
    ],
)
def test_a_reversal_shorter_than_a_slip_step_is_found(n, sequence):
    """Modified sine, mu = 0.3, n = 7.01508: near tau = 0.975 the velocity dips below zero
    for 9e-4, less than one slip step (2.2e-3).  Sign changes at step ends missed it and
    the invariant check failed the solve (a whole ``camjax ct`` sweep with it); each step's
    dense output is now screened for such an excursion.  Reference: scipy, DOP853 with
    max_step 1e-4 (events at sign changes between its steps) and a grid scan of the stick
    force."""
    law = camjax.laws.get("modified-sine")
    response = solve(law, CoulombFriction(n, 0.3), samples=SAMPLES)
    phases = _stick_slip_reference(_modified_sine_command(), n, 0.3, 2.0, max_step=1e-4)
    assert [p[1] for p in phases] == sequence
    tau = np.asarray(response.tau)
    np.testing.assert_allclose(np.asarray(response.position), _reference_positions(phases, tau),
                               rtol=0, atol=1e-12)
    assert int(response.stats["segments"]) == len(phases)


def test_a_friction_sweep_solves_every_ratio():
    """Both laws over n in [1, 20] with the ratio that used to fail among them; each
    ratio as its own solve gives the same Ct."""
    n = np.sort(np.append(np.linspace(1.0, 20.0, 24), 7.01508))
    for name in ("modified-sine", "cycloidal"):
        law = camjax.laws.get(name)
        curve = camjax.ct_curve(law, n, model=CoulombFriction(1.0, 0.3), samples=SAMPLES)
        assert not curve.failed.any() and np.all(np.isfinite(curve.ct))
        k = int(np.flatnonzero(n == 7.01508)[0])
        one = solve(law, CoulombFriction(7.01508, 0.3), samples=SAMPLES)
        assert curve.ct[k] == pytest.approx(float(one.metrics.ct), rel=1e-9)


@pytest.mark.slow
def test_a_dense_friction_sweep_solves_every_ratio():
    """Slow (22 s on the loaded 2-core machine, 2026-11-27): 800 event-driven stick-slip solves, to catch a rare ratio that fails; the vmap and the events path run by default on few ratios."""
    n = np.linspace(1.0, 20.0, 400)
    for name in ("modified-sine", "cycloidal"):
        curve = camjax.ct_curve(camjax.laws.get(name), n, model=CoulombFriction(1.0, 0.3),
                                throw=False)
        assert curve.result_names == ["successful"] * n.size
        assert np.all(np.isfinite(curve.ct))


def test_regularised_converges_to_stick_slip_as_eps_shrinks(cycloidal):
    model = CoulombFriction(5.25, 0.5)
    events = solve(cycloidal, model, samples=SAMPLES)
    errors = []
    for eps in (1e-2, 1e-3, 1e-4):
        smooth = solve(cycloidal, model, samples=SAMPLES, method="regularised", eps=eps)
        in_motion = events.tau <= 1.0
        errors.append(float(jnp.max(jnp.where(in_motion, jnp.abs(smooth.position - events.position), 0))))
    assert errors[0] > 3 * errors[1] > 9 * errors[2]
    assert errors[2] < 1e-4


def test_bad_input_is_a_clear_error(cycloidal):
    with pytest.raises(ValueError, match="friction"):
        CoulombFriction(5.0, -1.0)
    with pytest.raises(ValueError, match="period ratio"):
        CoulombFriction(-5.0, 1.0)
    with pytest.raises(ValueError, match="unknown method"):
        solve(cycloidal, CoulombFriction(5.0, 1.0), method="bogus")
    with pytest.raises(ValueError, match="eps"):
        solve(cycloidal, CoulombFriction(5.0, 1.0), method="regularised", eps=0.0)


def test_too_few_segments_raises_solver_error(cycloidal):
    with pytest.raises(camjax.SolverError, match="max_segments"):
        solve(cycloidal, CoulombFriction(5.25, 0.5), samples=SAMPLES, max_segments=2)


def test_vmap_over_period_ratios_equals_loop(cycloidal):
    ns = [3.3, 5.25]
    curve = camjax.ct_curve(cycloidal, ns, model=CoulombFriction(1.0, 0.5), samples=SAMPLES)
    for k, n in enumerate(ns):
        one = solve(cycloidal, CoulombFriction(n, 0.5), samples=SAMPLES)
        assert curve.ct[k] == pytest.approx(float(one.metrics.ct), rel=1e-8)
        assert curve.residual[k] == pytest.approx(float(one.metrics.residual), rel=1e-8)


@pytest.mark.slow
def test_regularised_gradient_matches_finite_differences(cycloidal):
    """Slow (25 s on the loaded 2-core machine, 2026-11-27): reverse mode through the regularised diffrax solve compiles a program of its own."""
    def offset(mu):
        model = CoulombFriction(5.25, mu)
        response = solve(cycloidal, model, samples=128, method="regularised", eps=1e-2, throw=False)
        return response.position[-1]

    g = float(jax.grad(offset)(jnp.asarray(0.5)))
    h = 1e-5
    fd = (float(offset(jnp.asarray(0.5 + h))) - float(offset(jnp.asarray(0.5 - h)))) / (2 * h)
    assert g == pytest.approx(fd, rel=1e-4, abs=1e-9)


@pytest.mark.slow
def test_a_failing_segment_names_where_it_failed(cycloidal):
    """Slow (14 s on the loaded 2-core machine, 2026-11-27): a step limit of 8 is a new static option, so the events path compiles again for one message."""
    with pytest.raises(camjax.SolverError, match=r"\(reached tau = 0\.\d+\) failed: the maximum number of solver steps"):
        solve(cycloidal, CoulombFriction(5.25, 0.5), samples=SAMPLES, max_steps=8)
