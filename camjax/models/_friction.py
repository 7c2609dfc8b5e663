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

Three solution paths (the first two through ``camjax.solve`` and the sweeps):
- ``method="events"`` (default): one phase per slip or stick phase (true stick-slip,
  ``camjax.models._hybrid``): slip phases by diffrax, ended by an event where the
  velocity reverses (however briefly); stick phases in closed form (the payload is at rest), ended by an
  exact search for ``|F| = mu`` that cannot step over a short excursion;
- ``method="regularised"``: ``sign(x')`` replaced by ``tanh(x'/eps)``, smooth and
  differentiable, but it creeps instead of sticking;
- ``free_vibration``: the exact piecewise closed form of the unforced vibration
  (a dwell): between velocity reversals the motion is a linear oscillator about a
  centre shifted by ``mu / w^2``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp

from .. import checks
from ..checks import require
from ..errors import RESULTS, promote
from ..sdof import residual_amplitude
from ._base import Metrics, Options, Response
from ._hybrid import AbstractHybridModel, sample_times


@dataclasses.dataclass(frozen=True)
class FrictionOptions(Options):
    """Static settings of a friction solution.

    Attributes:
        method: ``"events"`` (true stick-slip: slip phases by diffrax Dopri8, stick phases
            in closed form) or ``"regularised"`` (``sign(x')`` replaced by
            ``tanh(x'/eps)``: smooth, for gradients, but it creeps instead of sticking).
        dwell: dwell after the rise, in motion periods.
        samples: equal sample steps over the rise (the dwell is sampled as finely).
        eps: velocity scale of the regularised path.
        rtol, atol: tolerances of the slip phases.
        max_segments: most slip and stick phases in one solve.
        max_steps: step limit of one phase.
        max_step: largest step of a slip phase, in natural periods ``1/n`` (default 1/64).
            A slip phase ends where the velocity reverses; a step inside which it reverses
            and returns is rejected and retried shorter (``_hybrid.ExcursionGuard``), so
            such a reversal is found too.  Should one still escape (shallower than
            ``atol``), the invariant check after the solve reports it, never a number.
    """

    method: str = "events"
    samples: int = 1024
    eps: float = 1e-3
    rtol: float = 1e-10
    atol: float = 1e-12
    max_segments: int = 256
    max_steps: int = 100_000
    max_step: float = 1 / 64

    def checked(self, max_period_ratio: float) -> FrictionOptions:
        base = super().checked(max_period_ratio)
        require(int(self.samples) >= 8, f"samples must be at least 8, got {self.samples}")
        require(math.isfinite(self.eps) and self.eps > 0, f"eps must be positive, got {self.eps}")
        require(int(self.max_segments) >= 1, f"max_segments must be positive, got {self.max_segments}")
        require(int(self.max_steps) >= 1, f"max_steps must be positive, got {self.max_steps}")
        return base


class CoulombFriction(AbstractHybridModel):
    """Payload on an elastic transmission with viscous and Coulomb friction.

    Attributes:
        period_ratio: ``n = T f`` (> 0).
        friction: normalised friction force ``mu = F_friction T^2 / (W h)`` (>= 0).
        damping: viscous damping ratio ``zeta`` in ``[0, 1)``.
    """

    period_ratio: float | jax.Array
    friction: float | jax.Array
    damping: float | jax.Array = 0.0
    methods: ClassVar[tuple[str, ...]] = ("events", "regularised")
    options_type: ClassVar[type[Options]] = FrictionOptions

    def checked_parameters(self) -> dict:
        return {
            "period_ratio": checks.positive(self.period_ratio, "period ratio"),
            "friction": checks.non_negative(self.friction, "friction"),
            "damping": checks.damping_ratio(self.damping),
        }

    @property
    def stick_band(self):
        """Half-width ``mu / w^2`` of the positions where a payload at rest in a dwell stays stuck."""
        return self.friction / self.omega**2

    # --- phases: mode 0 stuck, +1 / -1 slipping forward / backward ---

    def _force(self, t, x, law):
        """Force of the transmission on a stuck payload (``x' = 0``), per unit mass."""
        s, v = _command(law, t)
        w = self.omega
        return w**2 * (s - x) + 2 * self.damping * w * v

    def phase_field(self, t, y, law, mode):
        x, dx = y
        s, v = _command(law, t)
        w = self.omega
        slip = w**2 * (s - x) + 2 * self.damping * w * (v - dx) - self.friction * mode
        return jnp.where(mode == 0, 0.0, dx), jnp.where(mode == 0, 0.0, slip)

    def phase_exit(self, t, y, law, mode):
        return -mode * y[1]  # a slip phase ends where the velocity reverses

    def next_phase(self, t, y, law, mode):
        force = self._force(t, y[0], law)
        sticks = (mode != 0) & (jnp.abs(force) <= self.friction)
        new = jnp.where(sticks, 0, jnp.where(force > 0, 1, -1))
        return new, (y[0], jnp.zeros_like(y[1]))  # the phase ends exactly at zero velocity

    def closed_form(self, mode):
        return mode == 0

    def closed_state(self, t, t0, y0, law, mode):
        return y0[0] + 0.0 * t, jnp.zeros_like(t)

    def closed_exits(self, t0, y0, law, mode):
        """A stuck payload slips once ``|F(t)| = mu``, ``F = w^2 (s - x0) + 2 zeta w s'``."""
        w, zeta = self.omega, self.damping

        def g(t):
            force = self._force(t, y0[0], law)
            return jnp.stack([force - self.friction, -force - self.friction])

        def dg(t):
            _, v, a, _ = law.evaluate(t)
            rate = w**2 * v + 2 * zeta * w * a
            return jnp.stack([rate, -rate])

        # |F''| = |w^2 a + 2 zeta w j| inside the law's pieces; the jerk bound is the
        # law's Cj where finite, else its largest value sampled inside the pieces.
        jerk = jnp.where(jnp.isfinite(law.Cj), law.Cj, _piecewise_jerk_bound(law))
        return g, dg, w**2 * law.Ca + 2 * zeta * w * jerk

    def phase_acceleration(self, t, y, law, mode):
        return self.phase_field(t, y, law, mode)[1]

    # --- solution ---

    def sweeps_in_turn(self, options) -> bool:
        """The event path in turn (see ``AbstractHybridModel``); the regularised one is one
        stiff solve per ratio, faster vmapped (16 ratios: 0.56 s against 1.47 s warm)."""
        return options.method == "events"

    def response(self, law, options) -> FrictionResponse:
        model = self.validated()
        ts = sample_times(options.samples, options.dwell)
        i_end = options.samples  # tau = 1
        if options.method == "regularised":
            (x, dx), result, steps = _regularised(law, model, ts, options)
            s, v = _command(law, ts)
            w = model.omega
            acc = w**2 * (s - x) + 2 * model.damping * w * (v - dx) - model.friction * jnp.tanh(dx / options.eps)
            peak_all = jnp.max(jnp.abs(acc))
            peak_rise = jnp.max(jnp.where(ts <= 1.0, jnp.abs(acc), 0.0))
            stuck = jnp.zeros(ts.shape, bool)
            stats = {"steps": steps}
        else:
            sol = model._integrate(
                law, ts, (jnp.zeros(()), jnp.zeros(())),
                jnp.where(model.friction > 0, 0, 1),  # frictionless: no zero-length stick at rest
                solver=diffrax.Dopri8(),
                rtol=options.rtol, atol=options.atol, max_steps=options.max_steps,
                max_segments=options.max_segments, max_step=options.max_step,
            )
            x, dx = sol.y
            stuck = sol.mode == 0
            acc = jax.vmap(lambda t, y, m: model.phase_acceleration(t, y, law, m))(ts, sol.y, sol.mode)
            peak_rise, peak_all = model._peaks(law, ts, sol)
            # Invariants: a stuck payload is at rest inside the stick band; a slipping one
            # moves the way it slips.
            force = jax.vmap(lambda t, x: model._force(t, x, law))(ts, x)
            scale = 1e-9 * (1.0 + model.omega**2)
            held = jnp.where(stuck, (jnp.abs(force) <= model.friction + scale) & (dx == 0), sol.mode * dx >= -1e-9)
            result = RESULTS.where(
                (sol.result == RESULTS.successful) & ~jnp.all(held), RESULTS.invariant_violated, sol.result
            )
            stats = {"steps": sol.steps, "segments": sol.segments, "reached": sol.reached}
        residual = _dwell_residual(model, x[i_end], dx[i_end], model._force(1.0, x[i_end], law), options.dwell)
        return FrictionResponse(
            tau=ts,
            payload_acceleration=acc,
            metrics=Metrics(peak_all / law.Ca, residual / law.Ca, peak_rise / law.Ca),
            result=result,
            stats=stats,
            position=x,
            velocity=dx,
            stuck=stuck,
            rest_offset=x[-1] - 1.0,
            settled=stuck[-1],
        )


def _dwell_residual(model: CoulombFriction, x, dx, force, dwell: float):
    """The largest ``|x''|`` of the dwell's first slip, from the state at its start.

    Slipping the way ``s`` (the velocity's sign, or the force's from rest), the payload is
    a linear oscillator about ``1 - s mu / w^2``, so ``x''`` swings to ``w^2`` times its
    amplitude about that centre (damped, its largest value over the dwell:
    ``camjax.sdof.residual_of_mode``); a payload at rest inside the stick band stays there
    (zero).  Without friction it is the SDOF's residual."""
    w, mu = model.omega, model.friction
    slip = jnp.where(dx != 0, jnp.sign(dx), jnp.sign(force))
    held = (dx == 0) & (jnp.abs(force) <= mu)
    amplitude = residual_amplitude(1.0 - x - slip * mu / w**2, -dx, w, model.damping, dwell)
    return jnp.where(held, 0.0, amplitude)


def _piecewise_jerk_bound(law):
    """Largest ``|j|`` sampled inside the law's pieces (away from jumps), with a margin."""
    t = jnp.linspace(0.0, 1.0, 4097)
    mid = 0.5 * (t[1:] + t[:-1])
    return 1.25 * jnp.max(jnp.abs(law.j(mid))) + 1e-12


class FrictionResponse(Response):
    """Response of ``CoulombFriction`` over the rise and the following dwell.

    Attributes:
        position: payload position ``x`` (units of stroke).
        velocity: payload velocity ``x'``.
        stuck: whether the payload is stuck at each sample (regularised path: never).
        rest_offset: ``x - 1`` at the end of the dwell (units of stroke): the rest offset
            when the payload is stuck there.
        settled: whether the payload is stuck at the end of the dwell.
    """

    position: jax.Array
    velocity: jax.Array
    stuck: jax.Array
    rest_offset: jax.Array
    settled: jax.Array


def _command(law, t):
    s, v, _, _ = law.evaluate(t)
    return s, v


def _regularised_field(t, y, args):
    law, model, eps = args
    x, dx = y
    s, v = _command(law, t)
    w = model.omega
    friction = model.friction * jnp.tanh(dx / eps)
    return dx, w**2 * (s - x) + 2 * model.damping * w * (v - dx) - friction


def _regularised(law, model, ts, options):
    """Position and velocity of the regularised model, and the result code."""
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(_regularised_field),
        diffrax.Kvaerno5(),
        t0=0.0,
        t1=ts[-1],
        dt0=None,
        y0=(jnp.zeros(()), jnp.zeros(())),
        args=(law, model, options.eps),
        saveat=diffrax.SaveAt(ts=ts),
        stepsize_controller=diffrax.PIDController(
            rtol=options.rtol, atol=options.atol, dtmax=0.125 / jnp.maximum(model.period_ratio, 1.0)
        ),
        max_steps=options.max_steps,
        throw=False,
    )
    return sol.ys, promote(sol.result), jnp.asarray(sol.stats["num_steps"], dtype=int)


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
