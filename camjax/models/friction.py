"""The SDOF of MISSION.md with Coulomb (constant) friction on the payload, with stick-slip.

Normalised equation of motion of the payload ``x(tau)`` (units of stroke):

    x'' = w^2 (s - x) + 2 zeta w (s' - x') - mu sign(x')          while slipping,
    x'  = 0                                                     while stuck,

with ``w = 2 pi n`` and the friction level ``mu = F_friction T^2 / (W h)``: the friction
force in units of the force that gives the payload the acceleration ``h/T^2`` (compare
the law's peak, ``Ca``).  The payload sticks when its velocity reaches zero while the
transmission force ``F = w^2 (s - x) + 2 zeta w s'`` is within the stick band
``|F| <= mu``; it slips again, in the direction of ``F``, when ``|F|`` reaches ``mu``.
In a dwell (``s = 1``) a stuck payload rests out of position by ``|x - 1| <= mu / w^2``.

Three solution paths:
- :func:`solve_friction` with ``method="events"``: diffrax with events located by a
  root finder, one integration segment per slip or stick phase (true stick-slip);
- :func:`solve_friction` with ``method="regularised"``: ``sign(x')`` replaced by
  ``tanh(x'/eps)``, smooth and differentiable, but it creeps instead of sticking;
- :func:`free_vibration`: the exact piecewise closed form of the unforced vibration
  (a dwell): between velocity reversals the motion is a linear oscillator about a
  centre shifted by ``mu / w^2``.
"""

from __future__ import annotations

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..laws import AbstractMotionLaw
from ..laws._base import is_concrete, require
from ._events import EventBisection
from ._spring_mass import check_damping, check_period_ratios

METHODS = ("events", "regularised")


class CoulombFriction(eqx.Module):
    """Payload on an elastic transmission with viscous and Coulomb friction.

    Attributes:
        period_ratio: ``n = T f`` (> 0).
        friction: normalised friction force ``mu = F_friction T^2 / (W h)`` (>= 0).
        damping: viscous damping ratio ``zeta`` in ``[0, 1)``.
    """

    period_ratio: float | jax.Array
    friction: float | jax.Array
    damping: float | jax.Array = 0.0

    def __check_init__(self):
        if is_concrete(self.period_ratio, self.friction, self.damping):
            if jnp.ndim(self.period_ratio) == 0:
                check_period_ratios(self.period_ratio)
            if jnp.ndim(self.damping) == 0:
                check_damping(self.damping)
            if jnp.ndim(self.friction) == 0:
                mu = float(self.friction)
                require(np.isfinite(mu) and mu >= 0, f"friction must be >= 0 and finite, got {mu}")

    @property
    def omega(self):
        """Normalised natural angular frequency ``w = 2 pi n``."""
        return 2 * jnp.pi * self.period_ratio

    @property
    def stick_band(self):
        """Half-width ``mu / w^2`` of the positions where a payload at rest in a dwell stays stuck."""
        return self.friction / self.omega**2


class FrictionResponse(eqx.Module):
    """Response of :class:`CoulombFriction` over the rise and the following dwell.

    Attributes:
        tau: sample times (rise and dwell).
        position: payload position ``x`` (units of stroke).
        velocity: payload velocity ``x'``.
        acceleration: payload acceleration ``x''``.
        stuck: whether the payload is stuck at each sample (events path; regularised:
            never).
        peak_in_motion: max ``|x''|`` over the rise samples, over Ca.
        ct: max ``|x''|`` over all samples, over Ca.
        rest_offset: ``x - 1`` at the end of the dwell (units of stroke): the rest offset
            when the payload is stuck there.
        settled: whether the payload is stuck at the end of the dwell.
        segments: slip and stick phases integrated (events path).
        reached: time the solution reached: ``1 + dwell``, or where a segment failed.
        result: diffrax result of the last segment that failed, else successful.
    """

    tau: jax.Array
    position: jax.Array
    velocity: jax.Array
    acceleration: jax.Array
    stuck: jax.Array
    peak_in_motion: jax.Array
    ct: jax.Array
    rest_offset: jax.Array
    settled: jax.Array
    segments: jax.Array
    reached: jax.Array
    result: diffrax.RESULTS


def _command(law, t):
    s, v, _, _ = law.evaluate(t)
    return s, v


def _transmission_force(law, model, t, x):
    """Force of the transmission on a stuck payload (``x' = 0``), per unit mass."""
    s, v = _command(law, t)
    w = model.omega
    return w**2 * (s - x) + 2 * model.damping * w * v


def _slip_field(t, y, args):
    law, model, direction = args
    x, dx = y
    s, v = _command(law, t)
    w = model.omega
    return dx, w**2 * (s - x) + 2 * model.damping * w * (v - dx) - model.friction * direction


def _stick_field(t, y, args):
    return jnp.zeros_like(y[0]), jnp.zeros_like(y[1])


def _phase_field(t, y, args):
    law, model, mode = args
    slip = _slip_field(t, y, (law, model, mode.astype(float)))
    return jax.tree.map(lambda a: jnp.where(mode == 0, 0.0, a), slip)


def _phase_end(t, y, args, **kwargs):
    """Up-crossing of zero ends the phase: ``|F| - mu`` when stuck, ``-sign x'`` slipping."""
    law, model, mode = args
    x, dx = y
    force = _transmission_force(law, model, t, x)
    return jnp.where(mode == 0, jnp.abs(force) - model.friction, -mode.astype(float) * dx)


def _next_mode(law, model, t, x, mode):
    """The phase after an event: slip along the transmission force, unless a slip phase
    ended (zero velocity) with the force inside the stick band."""
    force = _transmission_force(law, model, t, x)
    sticks = (mode != 0) & (jnp.abs(force) <= model.friction)
    return jnp.where(sticks, 0, jnp.where(force > 0, 1, -1))


def _phase_solver(rtol, atol):
    return (
        diffrax.Dopri8(),
        diffrax.Event(_phase_end, EventBisection(rtol=1e-14, atol=1e-14), direction=True),
    )


def _events_path(law, model, ts, t_end, rtol, atol, max_segments, max_steps):
    """Position, velocity, stuck flag at ``ts``, one diffrax solve per slip or stick phase."""
    solver, event = _phase_solver(rtol, atol)
    # Stick phases have a zero vector field: cap the step so the force history is
    # sampled finely enough for the event (a few steps per vibration period).
    dtmax = 0.125 / jnp.maximum(model.period_ratio, 1.0)
    controller = diffrax.PIDController(rtol=rtol, atol=atol, dtmax=dtmax)

    def segment(state):
        t0, x0, dx0, mode, xs, dxs, modes, count, result = state
        save = jnp.clip(ts, t0, t_end)
        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(_phase_field),
            solver,
            t0=t0,
            t1=t_end,
            dt0=None,
            y0=(x0, dx0),
            args=(law, model, mode),
            saveat=diffrax.SaveAt(subs=[diffrax.SubSaveAt(ts=save), diffrax.SubSaveAt(t1=True)]),
            stepsize_controller=controller,
            event=event,
            max_steps=max_steps,
            throw=False,
        )
        (x_saved, dx_saved), (x_end, dx_end) = sol.ys
        t1 = sol.ts[1][0]
        inside = (ts >= t0) & (ts <= t1)
        xs = jnp.where(inside, x_saved, xs)
        dxs = jnp.where(inside, dx_saved, dxs)
        modes = jnp.where(inside, mode, modes)
        x1, dx1 = x_end[0], dx_end[0]
        ended = sol.result == diffrax.RESULTS.event_occurred
        new_mode = jnp.where(ended, _next_mode(law, model, t1, x1, mode), mode)
        dx1 = jnp.where(ended, 0.0, dx1)  # the phase ends exactly at zero velocity
        ok = (sol.result == diffrax.RESULTS.successful) | ended
        result = diffrax.RESULTS.where(ok, result, sol.result)
        return t1, x1, dx1, new_mode, xs, dxs, modes, count + 1, result

    def running(state):
        t0, *_, count, result = state
        return (t0 < t_end) & (count < max_segments) & (result == diffrax.RESULTS.successful)

    zeros = jnp.zeros_like(ts)
    start = (
        jnp.asarray(0.0),
        jnp.asarray(0.0),
        jnp.asarray(0.0),
        jnp.asarray(0),
        zeros,
        zeros,
        jnp.zeros(ts.shape, int),
        jnp.asarray(0),
        diffrax.RESULTS.successful,
    )
    t_last, x_last, _, mode_last, xs, dxs, modes, count, result = jax.lax.while_loop(
        running, segment, start
    )
    # Running out of segments is reported as running out of steps.
    out_of_segments = (t_last < t_end) & (result == diffrax.RESULTS.successful)
    result = diffrax.RESULTS.where(out_of_segments, diffrax.RESULTS.max_steps_reached, result)
    return xs, dxs, modes, mode_last == 0, count, t_last, result


def _regularised_field(t, y, args):
    law, model, eps = args
    x, dx = y
    s, v = _command(law, t)
    w = model.omega
    friction = model.friction * jnp.tanh(dx / eps)
    return dx, w**2 * (s - x) + 2 * model.damping * w * (v - dx) - friction


def _regularised_path(law, model, ts, t_end, eps, rtol, atol, max_steps):
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(_regularised_field),
        diffrax.Kvaerno5(),
        t0=0.0,
        t1=t_end,
        dt0=None,
        y0=(jnp.zeros(()), jnp.zeros(())),
        args=(law, model, eps),
        saveat=diffrax.SaveAt(ts=ts),
        stepsize_controller=diffrax.PIDController(
            rtol=rtol, atol=atol, dtmax=0.125 / jnp.maximum(model.period_ratio, 1.0)
        ),
        max_steps=max_steps,
        throw=False,
    )
    xs, dxs = sol.ys
    reached = jnp.where(sol.result == diffrax.RESULTS.successful, t_end, jnp.nan)
    return xs, dxs, jnp.zeros(ts.shape, int) + 1, jnp.asarray(False), jnp.asarray(1), reached, sol.result


@eqx.filter_jit
def friction_response(
    law: AbstractMotionLaw,
    model: CoulombFriction,
    *,
    method: str = "events",
    dwell: float = 1.0,
    samples: int = 2048,
    eps: float = 1e-3,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    max_segments: int = 256,
    max_steps: int = 100_000,
) -> FrictionResponse:
    """:class:`FrictionResponse` on ``samples`` equal steps over ``[0, 1 + dwell]``.

    Jittable and vmappable over the model's leaves (no failure checks: see
    :func:`solve_friction`).  ``eps`` is the velocity scale of the regularised path.
    """
    t_end = 1.0 + dwell
    ts = jnp.linspace(0.0, t_end, samples + 1)
    if method == "events":
        xs, dxs, modes, settled, count, reached, result = _events_path(
            law, model, ts, t_end, rtol, atol, max_segments, max_steps
        )
    else:
        xs, dxs, modes, settled, count, reached, result = _regularised_path(
            law, model, ts, t_end, eps, rtol, atol, max_steps
        )
        modes = jnp.sign(dxs).astype(int)
    s, v = _command(law, ts)
    w = model.omega
    if method == "events":
        friction = model.friction * modes
    else:
        friction = model.friction * jnp.tanh(dxs / eps)
    acc = w**2 * (s - xs) + 2 * model.damping * w * (v - dxs) - friction
    acc = jnp.where((modes == 0) & (method == "events"), 0.0, acc)
    in_motion = ts <= 1.0
    return FrictionResponse(
        tau=ts,
        position=xs,
        velocity=dxs,
        acceleration=acc,
        stuck=modes == 0,
        peak_in_motion=jnp.max(jnp.where(in_motion, jnp.abs(acc), 0.0)) / law.Ca,
        ct=jnp.max(jnp.abs(acc)) / law.Ca,
        rest_offset=xs[-1] - 1.0,
        settled=settled,
        segments=count,
        reached=reached,
        result=result,
    )


def solve_friction(law: AbstractMotionLaw, model: CoulombFriction, **options) -> FrictionResponse:
    """Response of one friction model, validated; raises ``SolverError`` if a solve fails.

    Options as :func:`friction_response`; ``method`` is ``"events"`` (true stick-slip)
    or ``"regularised"`` (``tanh(x'/eps)``, for gradients).
    """
    from ..errors import SolverError

    method = options.get("method", "events")
    require(method in METHODS, f"unknown friction method {method!r}; valid: {', '.join(METHODS)}")
    dwell = float(options.get("dwell", 1.0))
    require(np.isfinite(dwell) and dwell >= 0, f"dwell must be >= 0, got {dwell}")
    samples = int(options.get("samples", 2048))
    require(samples >= 8, f"samples must be at least 8, got {samples}")
    eps = float(options.get("eps", 1e-3))
    require(np.isfinite(eps) and eps > 0, f"eps must be positive, got {eps}")
    model = CoulombFriction(
        jnp.asarray(check_period_ratios(model.period_ratio)[0]),
        jnp.asarray(float(model.friction)),
        jnp.asarray(check_damping(model.damping)),
    )
    # Traced leaves, not static settings: no recompilation per value.
    options["eps"] = jnp.asarray(eps)
    max_segments = int(options.get("max_segments", 256))
    options["max_segments"] = jnp.asarray(max_segments)
    response = friction_response(law, model, **options)
    if response.result != diffrax.RESULTS.successful:
        where = f"friction solve ({method}) at period ratio {float(model.period_ratio):g}, " + (
            f"friction {float(model.friction):g}"
        )
        if method == "events" and int(response.segments) >= max_segments:
            raise SolverError(
                f"{where} used all {max_segments} slip and stick phases by tau = "
                f"{float(response.reached):.6g} of {1 + dwell:g} (raise max_segments)"
            )
        at = f" at tau = {float(response.reached):.6g}" if method == "events" else ""
        raise SolverError(f"{where} failed{at}: {diffrax.RESULTS[response.result]}")
    if not bool(jnp.all(jnp.isfinite(response.position))):
        raise SolverError(f"friction solve ({method}) produced non-finite values")
    return response


class FreeVibration(eqx.Module):
    """Exact piecewise free vibration with Coulomb friction (a dwell at ``x = 0``).

    Attributes:
        reversal_time: times where the velocity reaches zero (``inf`` after sticking).
        reversal_position: position at each of them (the last value repeats once stuck).
        stick_time: when the payload sticks (``inf`` if it does not within the reversals).
        rest_position: position where it sticks (``nan`` if it does not).
    """

    reversal_time: jax.Array
    reversal_position: jax.Array
    stick_time: jax.Array
    rest_position: jax.Array


def free_vibration(model: CoulombFriction, x0, dx0, *, reversals: int = 64) -> FreeVibration:
    """Unforced motion ``x'' = -w^2 x - 2 zeta w x' - mu sign(x')`` from ``(x0, dx0)``, exactly.

    Each slip phase is a damped oscillator about the centre ``-sign(x') mu / w^2``; its
    velocity vanishes after a known time, at which the payload sticks if
    ``|x| <= mu / w^2``.  A scan over ``reversals`` phases (static) gives the sequence.
    """
    w, zeta, mu = model.omega, model.damping, model.friction
    wd = w * jnp.sqrt(1.0 - zeta**2)
    band = mu / w**2

    def phase(carry, _):
        t, x, dx, stuck = carry
        direction = jnp.where(dx != 0, jnp.sign(dx), -jnp.sign(x))
        centre = -direction * band
        a = x - centre  # y = x - centre = exp(-zeta w t) (a cos wd t + b sin wd t)
        b = (dx + zeta * w * a) / wd
        p, q = b * wd - zeta * w * a, a * wd + zeta * w * b  # y' ~ p cos - q sin
        angle = jnp.mod(jnp.arctan2(p, q), jnp.pi)
        angle = jnp.where((angle <= 1e-15) | (p == 0), jnp.pi, angle)
        dt = angle / wd
        decay = jnp.exp(-zeta * w * dt)
        x_new = centre + decay * (a * jnp.cos(angle) + b * jnp.sin(angle))
        sticks_now = (dx == 0) & (jnp.abs(x) <= band)
        stuck_next = stuck | sticks_now
        t_new = jnp.where(stuck_next, t, t + dt)
        x_new = jnp.where(stuck_next, x, x_new)
        return (t_new, x_new, jnp.zeros_like(dx), stuck_next), (
            jnp.where(stuck_next, jnp.inf, t_new),
            x_new,
            stuck_next,
            t_new,
        )

    x0 = jnp.asarray(x0, dtype=float)
    start = (jnp.zeros_like(x0), x0, jnp.asarray(dx0, dtype=float), jnp.asarray(False))
    (t, x, _, stuck), (times, positions, stuck_flags, _) = jax.lax.scan(
        phase, start, None, length=reversals
    )
    # A reversal where the payload sticks is one step late in the flags: the stick is
    # decided when the phase after it starts.
    last_stuck = stuck | (jnp.abs(x) <= band)
    return FreeVibration(
        reversal_time=times,
        reversal_position=positions,
        stick_time=jnp.where(last_stuck, t, jnp.inf),
        rest_position=jnp.where(last_stuck, x, jnp.nan),
    )
