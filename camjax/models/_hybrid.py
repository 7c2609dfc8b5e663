"""Hybrid (event) models: one smooth phase after another, each ended at an exact event.

Friction (slip and stick) and backlash (contact with either flank, free flight) share this
integrator.  A phase is solved one of two ways:

- **in closed form** where the model knows the motion exactly (a stuck payload, a free
  flight under a constant force).  Its end is the first time an *exit function*
  ``g_i(t)`` reaches zero from below, located by ``first_exit``, which cannot step
  over an event: a sample interval is searched whenever its end values plus the bound
  ``G h^2 / 8`` on the excursion of a function with ``|g''| <= G`` reach zero, so a
  grazing excursion between two samples is found (the apex by bisection on ``g'``, then
  the crossing), however short.  This is what a Runge-Kutta step cannot do for a free
  flight: its error estimate is zero there, its step grows without a cap, and a step
  that spans an excursion past a flank sees no sign change.
- **with diffrax** otherwise (the phases in which the transmission acts), the step capped
  (``max_step``) and the event root-found by ``EventBisection``.  diffrax sees an event as
  a sign change between step ends, so ``ExcursionGuard`` screens each step's dense output
  and rejects a step inside which the exit function rises through zero and falls back
  (a velocity reversal shorter than a step): the shorter retry ends inside the excursion
  and the event is seen.

After the solve, each model checks its invariants on every sample (contact state
consistent with the deflection, a stuck payload inside its stick band); a violation is
reported as ``RESULTS.invariant_violated``, never returned as a number.
"""

from __future__ import annotations

import abc
from collections.abc import Callable

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx

from ..errors import RESULTS, promote
from ..metrics import refined_peak
from ._base import AbstractModel

_BISECTIONS = 64  # halves a bracket of width <= 1 below float64 resolution
SEARCH_POINTS = 4096
"""Sample points over the whole solve at which closed-form exit functions are screened."""


class _BracketState(eqx.Module):
    lower: jax.Array
    upper: jax.Array
    flip: jax.Array
    width: jax.Array
    stalled: jax.Array


class EventBisection(optx.AbstractRootFinder):
    """Bisection of the step in which diffrax detected the event, ended on time alone.

    ``optx.Newton`` and ``optx.Bisection`` end only once ``|g| < atol`` for the event
    function ``g`` as well; a friction stick event ``|F| - mu`` near the end of a rise has
    a floating-point resolution of ``w^2`` times the rounding of ``s(tau)`` (1.2e-11 for
    4-5-6-7 at ``n = 5.25``), above such an ``atol``.  The step ends bracket the root, so
    bisecting until the bracket is ``atol + rtol |tau|`` wide locates the event to that
    time tolerance whatever the scale or noise of ``g``.  Unlike ``optx.Bisection`` it
    accepts a bracket with an end exactly at ``g = 0`` (a step that starts at a root).
    """

    rtol: float
    atol: float
    norm: Callable = optx.max_norm

    def init(self, fn, y, args, options, f_struct, aux_struct, tags):
        lower = jnp.asarray(options["lower"], f_struct.dtype)
        upper = jnp.asarray(options["upper"], f_struct.dtype)
        flip = fn(lower, args)[0] > fn(upper, args)[0]
        return _BracketState(lower, upper, flip, upper - lower, jnp.asarray(False))

    def step(self, fn, y, args, options, state, tags):
        value, aux = fn(y, args)
        below = state.flip ^ (value < 0)
        lower = jnp.where(below, y, state.lower)
        upper = jnp.where(below, state.upper, y)
        middle = lower + 0.5 * (upper - lower)
        stalled = (middle <= lower) | (middle >= upper)
        return middle, _BracketState(lower, upper, state.flip, upper - lower, stalled), aux

    def terminate(self, fn, y, args, options, state, tags):
        narrow = state.width <= self.atol + self.rtol * jnp.abs(y)
        return narrow | state.stalled, optx.RESULTS.successful

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        return y, aux, {}


def bisect(fn, lo, hi):
    """Point where ``fn`` turns from ``< 0`` (at ``lo``) to ``>= 0`` (at ``hi``), to 1 ulp."""

    def halve(_, bracket):
        lo, hi = bracket
        mid = 0.5 * (lo + hi)
        above = fn(mid) >= 0
        return jnp.where(above, lo, mid), jnp.where(above, mid, hi)

    return jax.lax.fori_loop(0, _BISECTIONS, halve, (lo, hi))[1]


def first_exit(g, dg, t0, t_end, curvature, points):
    """First time in ``(t0, t_end]`` at which any exit function reaches zero.

    Args:
        g, dg: ``t -> (C,)`` exit functions (negative inside the phase) and their time
            derivatives, exact (closed form), vectorised over leading axes of ``t``.
        t0, t_end: the phase starts at ``t0``; the solve ends at ``t_end``.
        curvature: bound ``G >= |g_i''|`` on every sample interval.
        points: sorted sample times covering ``[0, t_end]`` (the law's breakpoints among
            them, so that ``g`` is smooth inside each interval).

    Returns:
        ``(t_exit, found)``; ``t_exit = t_end`` when no function reaches zero.

    Every interval whose ends plus ``G h^2 / 8`` could reach zero is examined: the
    interior maximum (where ``g'`` turns from positive to negative, by bisection) decides
    whether the function reaches zero, and the crossing is bisected before it.
    """
    ts = jnp.clip(points, t0, t_end)
    values = jax.vmap(g)(ts)  # (M, C)
    ta, tb = ts[:-1], ts[1:]
    ga, gb = values[:-1], values[1:]
    h = (tb - ta)[:, None]
    flagged = jnp.any((h > 0) & (jnp.maximum(ga, gb) + curvature * h**2 / 8 >= 0), axis=1)
    index = jnp.arange(flagged.shape[0])

    def component(i, lo, hi):
        gi = lambda t: g(t)[i]  # noqa: E731
        dgi = lambda t: dg(t)[i]  # noqa: E731
        has_max = (dgi(lo) > 0) & (dgi(hi) < 0)
        apex = bisect(lambda t: -dgi(t), lo, hi)  # g' turns negative
        top = jnp.where(has_max, apex, hi)
        top = jnp.where(has_max & (gi(apex) < 0) & (gi(hi) >= 0), hi, top)
        reaches = gi(top) >= 0
        root = bisect(gi, lo, top)
        return jnp.where(reaches, root, jnp.inf)

    def examine(state):
        k, _, _ = state
        k = jnp.argmax(flagged & (index >= k))
        k = jnp.where(flagged[k] & (index[k] >= state[0]), k, flagged.shape[0])
        lo, hi = ta[jnp.minimum(k, flagged.shape[0] - 1)], tb[jnp.minimum(k, flagged.shape[0] - 1)]
        crossing = jnp.min(jnp.stack([component(i, lo, hi) for i in range(values.shape[1])]))
        found = (k < flagged.shape[0]) & jnp.isfinite(crossing)
        return k + 1, found, jnp.where(found, crossing, t_end)

    def more(state):
        k, found, _ = state
        return (~found) & (k < flagged.shape[0])

    _, found, t_exit = jax.lax.while_loop(more, examine, (jnp.asarray(0), jnp.asarray(False), t_end))
    return t_exit, found


GUARD_POINTS = 8
"""Sub-intervals of each accepted diffrax step screened for an excursion of the exit function."""


def cubic_peak(p0, p1, m0, m1):
    """Largest value on ``[0, 1]`` of the cubic with ends ``p0, p1`` and end slopes ``m0, m1``
    (Hermite form; the slopes per unit of ``u``): the ends and the critical points inside."""
    a = 6.0 * (p0 - p1) + 3.0 * (m0 + m1)  # p'(u) = a u^2 + b u + c
    b = 6.0 * (p1 - p0) - 4.0 * m0 - 2.0 * m1
    c = m0
    root = jnp.sqrt(jnp.maximum(b * b - 4.0 * a * c, 0.0))
    q = -0.5 * (b + jnp.where(b >= 0, root, -root))
    safe = lambda num, den: jnp.where(den != 0, num / jnp.where(den != 0, den, 1.0), 0.0)  # noqa: E731
    candidates = jnp.clip(jnp.stack([safe(q, a), safe(c, q)]), 0.0, 1.0)

    def value(u):
        h00, h10 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u
        h01, h11 = -2 * u**3 + 3 * u**2, u**3 - u**2
        return h00 * p0 + h10 * m0 + h01 * p1 + h11 * m1

    return jnp.maximum(jnp.maximum(p0, p1), jnp.max(value(candidates), axis=0))


class ExcursionGuard(diffrax.AbstractAdaptiveSolver, diffrax.AbstractWrappedSolver):
    """Rejects a step inside which the event function crosses zero unseen.

    diffrax sees an event as a sign change of ``exit(t, y)`` between step ends: an
    excursion through zero and back within one step (a velocity reversal shorter than a
    slip step) is stepped over.  Each step's dense output is screened on ``GUARD_POINTS``
    sub-intervals: the value and slope of ``exit`` along it at their ends, and the peak of
    the cubic through them.  A peak above ``tol`` followed by a value at or below zero
    later in the step (a crossing up and back, or up, back and up again) rejects the step
    (an infinite error estimate: the controller shrinks it), until the step ends inside
    the excursion and the event is seen, or before it.  ``tol`` is the solve's absolute
    tolerance: a shallower excursion is within the solution's error.
    """

    solver: diffrax.AbstractSolver
    exit: Callable
    tol: float

    @property
    def term_structure(self):
        return self.solver.term_structure

    @property
    def interpolation_cls(self):
        return self.solver.interpolation_cls

    @property
    def term_compatible_contr_kwargs(self):
        return self.solver.term_compatible_contr_kwargs

    @property
    def root_finder(self):
        """The wrapped implicit solver's (diffrax forwards ``isinstance`` to it, then asks)."""
        return self.solver.root_finder

    def order(self, terms):
        return self.solver.order(terms)

    def error_order(self, terms):
        return self.solver.error_order(terms)

    def init(self, terms, t0, t1, y0, args):
        return self.solver.init(terms, t0, t1, y0, args)

    def func(self, terms, t0, y0, args):
        return self.solver.func(terms, t0, y0, args)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        y1, y_error, dense_info, solver_state, result = self.solver.step(
            terms, t0, t1, y0, args, solver_state, made_jump
        )
        if y_error is None:
            return y1, y_error, dense_info, solver_state, result
        path = self.solver.interpolation_cls(t0=t0, t1=t1, **dense_info)

        def along(t):
            return self.exit(t, path.evaluate(t), args)

        nodes = t0 + (t1 - t0) * jnp.linspace(0.0, 1.0, GUARD_POINTS + 1)
        values, slopes = jax.vmap(lambda t: jax.jvp(along, (t,), (jnp.ones_like(t),)))(nodes)
        width = (t1 - t0) / GUARD_POINTS
        peaks = cubic_peak(values[:-1], values[1:], slopes[:-1] * width, slopes[1:] * width)
        later_low = jax.lax.cummin(values[1:], reverse=True)  # lowest value from each node on
        hidden = jnp.any((peaks > self.tol) & (later_low <= 0.0))
        y_error = jax.tree.map(lambda e: jnp.where(hidden, jnp.inf, e), y_error)
        return y1, y_error, dense_info, solver_state, result


def search_points(law, t_end):
    """Screening times for ``first_exit``: a fine grid plus the law's breakpoints."""
    grid = jnp.linspace(0.0, t_end, SEARCH_POINTS + 1)
    breaks = jnp.asarray(law.breakpoints(), dtype=float).reshape(-1)
    return jnp.sort(jnp.concatenate([grid, breaks, jnp.ones(1)]))


MAX_SAMPLES = 1_000_000
"""Most samples of one solve over the rise and the dwell (each is a state kept per period
ratio): more is refused before any work (a dwell of 10,000 rises at 1024 samples per rise
took 5 GB)."""


def sample_times(samples: int, dwell: float):
    """``samples`` equal steps over the rise and as fine over the dwell; ``tau = 1`` is
    sample ``samples`` exactly (where the residual is read).  More than ``MAX_SAMPLES`` in
    all is a ``ValueError`` naming the dwell and the samples."""
    count = max(1, int(round(samples * dwell)))
    if samples + count > MAX_SAMPLES:
        raise ValueError(f"dwell {dwell:g} at {samples} samples per rise needs {samples + count:,} "
                         f"samples; the limit is {MAX_SAMPLES:,} (a shorter dwell, or fewer samples)")
    rise = jnp.linspace(0.0, 1.0, samples + 1)
    return jnp.concatenate([rise, 1.0 + jnp.linspace(0.0, dwell, count + 1)[1:]])


class PhaseSolution(eqx.Module):
    """The states at the sample times and the record of every event."""

    y: tuple  # states at ``ts``
    mode: jax.Array  # phase mode at ``ts``
    event_t: jax.Array  # (max_segments,) event times, inf where unused
    event_y: tuple  # states at each event (before the reset)
    event_mode: jax.Array  # (mode before, mode after) per event, shape (max_segments, 2)
    segments: jax.Array
    steps: jax.Array
    reached: jax.Array
    result: RESULTS


class AbstractHybridModel(AbstractModel):
    """A model whose motion is a sequence of smooth phases (``mode`` an integer): friction,
    backlash.  A new one writes the phase methods below (public: they are its interface);
    the base integrates phase after phase (diffrax within a phase, events at its ends) and
    supplies the sweep."""

    def sweeps_in_turn(self, options) -> bool:
        """Phase by phase, ratios differ in their count of phases and steps.  Warm sweeps of
        16 ratios (``experiments/benchmarks/sweep_in_turn.py``): friction's events 13.9 s in lockstep,
        0.21 s in turn; backlash 1.78 s and 0.11 s."""
        return True

    @abc.abstractmethod
    def phase_field(self, t, y, law, mode):
        """``dy/dt`` in ``mode`` (a pair of scalars)."""

    @abc.abstractmethod
    def phase_exit(self, t, y, law, mode):
        """Event function of a diffrax phase: negative inside, crossing zero upward at its end."""

    @abc.abstractmethod
    def next_phase(self, t, y, law, mode):
        """``(new mode, state after the event)`` at an event that ends ``mode``."""

    @abc.abstractmethod
    def closed_form(self, mode) -> jax.Array:
        """Whether ``mode`` is solved in closed form."""

    @abc.abstractmethod
    def closed_state(self, t, t0, y0, law, mode):
        """State at ``t`` of a closed-form phase that started at ``(t0, y0)``."""

    @abc.abstractmethod
    def closed_exits(self, t0, y0, law, mode):
        """``(g, dg, curvature)`` of the closed-form phase (see ``first_exit``)."""

    @abc.abstractmethod
    def phase_acceleration(self, t, y, law, mode):
        """Payload acceleration ``x''`` (units of h/T^2) in ``mode``."""

    def _integrate(self, law, ts, y0, mode0, *, solver, rtol, atol, max_steps, max_segments,
                   max_step=0.125):
        """Phases from ``(0, y0, mode0)`` to ``ts[-1]``; one loop iteration per phase.

        ``max_step`` caps the diffrax step in natural periods (``1/n``); ``None`` leaves it
        to error control.
        """
        t_end = ts[-1]
        points = search_points(law, t_end)
        jumps = jnp.concatenate([jnp.asarray(law.breakpoints(), dtype=float).reshape(-1), jnp.ones(1)])
        dtmax = None if max_step is None else max_step / jnp.maximum(self.period_ratio, 1.0)
        controller = diffrax.ClipStepSizeController(
            diffrax.PIDController(rtol=rtol, atol=atol, dtmax=dtmax), jump_ts=jumps
        )
        event = diffrax.Event(
            lambda t, y, args, **kw: self.phase_exit(t, y, args[0], args[1]),
            EventBisection(rtol=1e-14, atol=1e-14),
            direction=True,
        )
        term = diffrax.ODETerm(lambda t, y, args: self.phase_field(t, y, args[0], args[1]))
        guarded = ExcursionGuard(solver, lambda t, y, args: self.phase_exit(t, y, args[0], args[1]), atol)

        def smooth(t0, y0, mode):
            sol = diffrax.diffeqsolve(
                term, guarded, t0=t0, t1=t_end, dt0=None, y0=y0, args=(law, mode),
                saveat=diffrax.SaveAt(
                    subs=[diffrax.SubSaveAt(ts=jnp.clip(ts, t0, t_end)), diffrax.SubSaveAt(t1=True)]
                ),
                stepsize_controller=controller, event=event, max_steps=max_steps, throw=False,
            )
            saved, end = sol.ys
            ended = sol.result == diffrax.RESULTS.event_occurred
            ok = (sol.result == diffrax.RESULTS.successful) | ended
            result = RESULTS.where(ok, RESULTS.successful, promote(sol.result))
            t1 = sol.ts[1][0]
            steps = jnp.asarray(sol.stats["num_steps"], dtype=int)
            return t1, jax.tree.map(lambda x: x[0], end), saved, ended, result, steps

        def closed(t0, y0, mode):
            g, dg, curvature = self.closed_exits(t0, y0, law, mode)
            t1, ended = first_exit(g, dg, t0, t_end, curvature, points)
            at = lambda t: self.closed_state(t, t0, y0, law, mode)  # noqa: E731
            return t1, at(t1), jax.vmap(at)(jnp.clip(ts, t0, t1)), ended, RESULTS.successful, jnp.asarray(0, dtype=int)

        def segment(state):
            t0, y0, mode, ys, modes, events, count, steps, result = state
            t1, y1, saved, ended, seg_result, seg_steps = jax.lax.cond(
                self.closed_form(mode), closed, smooth, t0, y0, mode
            )
            inside = (ts >= t0) & (ts <= t1)
            ys = jax.tree.map(lambda old, new: jnp.where(inside, new, old), ys, saved)
            modes = jnp.where(inside, mode, modes)
            new_mode, y_next = self.next_phase(t1, y1, law, mode)
            new_mode = jnp.where(ended, new_mode, mode)
            y_next = jax.tree.map(lambda a, b: jnp.where(ended, a, b), y_next, y1)
            times, states, mode_pairs = events
            slot = jnp.where(ended, count, times.shape[0])  # out of range: dropped
            events = (
                times.at[slot].set(t1, mode="drop"),
                jax.tree.map(lambda s, v: s.at[slot].set(v, mode="drop"), states, y1),
                mode_pairs.at[slot].set(jnp.stack([mode, new_mode]), mode="drop"),
            )
            result = RESULTS.where(result == RESULTS.successful, seg_result, result)
            return t1, y_next, new_mode, ys, modes, events, count + 1, steps + seg_steps, result

        def running(state):
            t0, *_, count, _, result = state
            return (t0 < t_end) & (count < max_segments) & (result == RESULTS.successful)

        zeros = jnp.zeros_like(ts)
        empty = jnp.full((max_segments,), jnp.inf)
        start = (
            jnp.asarray(0.0, dtype=float), jax.tree.map(lambda x: jnp.asarray(x, dtype=float), y0),
            jnp.asarray(mode0), (zeros, zeros), jnp.zeros(ts.shape, int),
            (empty, (empty, empty), jnp.zeros((max_segments, 2), int)),
            jnp.asarray(0), jnp.asarray(0, dtype=int), RESULTS.successful,
        )
        t_last, _, _, ys, modes, events, count, steps, result = jax.lax.while_loop(running, segment, start)
        out_of_segments = (t_last < t_end) & (result == RESULTS.successful)
        result = RESULTS.where(out_of_segments, RESULTS.too_many_segments, result)
        return PhaseSolution(ys, modes, events[0], events[1], events[2], count, steps, t_last, result)

    def _acceleration_jet(self, t, y, law, mode):
        """``x''`` and its first three time derivatives along the motion in ``mode``."""

        def along(fn):
            def derivative(t, y):
                field = self.phase_field(t, y, law, mode)
                return jax.jvp(fn, (t, y), (jnp.ones_like(t), field))[1]

            return derivative

        d0 = lambda t, y: self.phase_acceleration(t, y, law, mode)  # noqa: E731
        d1 = along(d0)
        d2 = along(d1)
        d3 = along(d2)
        return d0(t, y), jnp.stack([d1(t, y), d2(t, y), d3(t, y)])

    def _peaks(self, law, ts, solution: PhaseSolution):
        """``(max |x''| over the rise, over everything)``, refined between samples.

        Intervals inside one phase get the septic Hermite refinement of
        ``camjax.metrics.refined_peak``; an interval with an event inside is bounded by
        its end samples and the one-sided values at the event, which are added as samples.
        """
        acc, jets = jax.vmap(lambda t, y, m: self._acceleration_jet(t, y, law, m))(
            ts, solution.y, solution.mode
        )
        valid = jnp.isfinite(solution.event_t)
        k = jnp.clip(jnp.searchsorted(ts, solution.event_t, side="right") - 1, 0, ts.shape[0] - 2)
        split = jnp.zeros(ts.shape[0] - 1, bool).at[k].max(valid)
        widths = jnp.where(split, 0.0, jnp.diff(ts))  # 0 width: bounded by the end samples
        rise = ts <= 1.0

        def peak(mask_nodes):
            values = jnp.where(mask_nodes, acc, 0.0)
            inner = mask_nodes[:-1] & mask_nodes[1:]
            return refined_peak(values, jnp.where(inner, widths, 0.0), jets[:-1], jets[1:])

        before = jax.vmap(lambda t, y, m: self.phase_acceleration(t, y, law, m))(
            solution.event_t, solution.event_y, solution.event_mode[:, 0]
        )
        after_y = jax.vmap(lambda t, y, m: self.next_phase(t, y, law, m)[1])(
            solution.event_t, solution.event_y, solution.event_mode[:, 0]
        )
        after = jax.vmap(lambda t, y, m: self.phase_acceleration(t, y, law, m))(
            solution.event_t, after_y, solution.event_mode[:, 1]
        )
        at_events = jnp.where(valid, jnp.maximum(jnp.abs(before), jnp.abs(after)), 0.0)
        in_rise = valid & (solution.event_t <= 1.0)
        motion = jnp.maximum(peak(rise), jnp.max(jnp.where(in_rise, at_events, 0.0)))
        whole = jnp.maximum(peak(jnp.ones_like(rise)), jnp.max(at_events))
        return motion, whole
