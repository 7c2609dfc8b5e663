"""Root finder for ``diffrax.Event``: bisect the step bracket to a time tolerance.

Shared by the event-driven models (:mod:`camjax.models.friction`,
:mod:`camjax.models.backlash`).
"""

from __future__ import annotations

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx


class _BracketState(eqx.Module):
    lower: jax.Array
    upper: jax.Array
    flip: jax.Array
    width: jax.Array
    stalled: jax.Array


class EventBisection(optx.AbstractRootFinder):
    """Bisection of the step in which diffrax detected the event, ended on time alone.

    ``optx.Newton`` and ``optx.Bisection`` end only once ``|g| < atol`` for the event
    function ``g`` as well.  The friction stick-phase event ``|F| - mu`` is a force per
    unit mass of size ``w^2 (s - x)``: near the end of a rise, with ``s`` and ``x`` both
    close to 1, its floating-point resolution is ``w^2`` times the rounding error of
    ``s(tau)`` (``1.2e-11`` for the degree-7 polynomial law at ``n = 5.25``,
    ``w^2 = 1088``), above the ``atol = 1e-13`` Newton had there, so the root finder ran
    out of steps and the solve failed (poly4567 at 3 of 31 friction levels).  The step
    ends bracket the root (the event was detected by a sign change there), so bisecting
    until the bracket is ``atol + rtol |tau|`` wide locates the event to that time
    tolerance whatever the scale or noise of ``g``: noise only moves the result inside
    the band where ``g`` is zero to within its resolution.  A bracket that cannot shrink
    further (adjacent floats) also ends it.  Batch members without an event have the
    root at ``upper``.

    Unlike ``optx.Bisection`` (``flip="detect"``) it does not reject a bracket with an
    end exactly at ``g = 0`` (diffrax triggers a ``direction=True`` event on a step from
    ``g <= 0`` to ``g > 0``, so the step's start can be a root): it bisects as usual,
    converging on that end if ``g > 0`` inside the step.
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
