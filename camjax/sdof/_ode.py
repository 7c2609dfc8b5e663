"""The same SDOF equation integrated by diffrax: the reference path for the exact one, and
the template of the nonlinear models.  diffrax is imported on first use, so the exact path
never pays for its import."""

from __future__ import annotations

import jax.numpy as jnp

from ..errors import RESULTS, promote
from ..solvers import FIXED_STEP_SOLVERS, MAX_FREE_VIBRATION_GROWTH, free_vibration_growth, solver
from ._grid import SUBSTEPS_PER_INTERVAL, MotionGrid
from ._step import eigenvalue

BOUND_MARGIN = 1.01
"""Tolerance on the physical bound ``|q| <= Ca`` that an integrated response must keep."""


def vector_field(t, y, args):
    """Right-hand side of the SDOF deflection equation, in diffrax's ``(t, y, args)`` form.

    ``y = (e, e')``; ``args = (law, omega, zeta)`` with ``omega = 2 pi n``.  Returns
    ``(e', e'')`` with ``e'' = a(t) - omega^2 e - 2 zeta omega e'``.  Parameters travel in
    ``args`` (not a closure), so vmap and grad see them.
    """
    law, omega, zeta = args
    e, de = y
    return de, law.a(t) - omega**2 * e - 2 * zeta * omega * de


def sdof_term():
    """The diffrax term (``diffrax.ODETerm``) of the SDOF deflection equation
    (``vector_field``), for custom ``diffrax.diffeqsolve`` calls (other controllers,
    adjoints, saved statistics)::

        diffrax.diffeqsolve(sdof_term(), diffrax.Tsit5(), 0.0, 1.0, None,
                            (jnp.zeros(()), jnp.zeros(())), args=(law, 2 * jnp.pi * n, zeta))
    """
    import diffrax

    return diffrax.ODETerm(vector_field)


def integrate(law, grid: MotionGrid, omega, zeta, *, method: str, steps: int | None = None,
              rtol: float = 1e-10, atol: float = 1e-12, max_steps: int = 100_000,
              use_jump_ts: bool = True):
    """Complex mode at the grid's nodes by the diffrax solver ``method``, its result code
    and the steps taken.

    A fixed-step solver (``steps`` steps over the rise, default ``SUBSTEPS_PER_INTERVAL``
    per grid interval: ``w h <= 0.5`` on the SDOF grid, as its peaks are refined)
    whose numerical free vibration grows past ``MAX_FREE_VIBRATION_GROWTH`` is refused
    (``unstable_fixed_step``); every solution must keep ``|q| <= Ca`` at the nodes (its
    physical bound for ``zeta >= 0``) or is refused (``invariant_violated``).  A refused
    solution's mode is NaN.
    """
    import diffrax

    steps = steps or SUBSTEPS_PER_INTERVAL * grid.piece.size
    if method in FIXED_STEP_SOLVERS:
        controller, dt0 = diffrax.ConstantStepSize(), 1.0 / steps
    else:
        controller, dt0 = diffrax.PIDController(rtol=rtol, atol=atol), None
        jumps = jnp.asarray(law.breakpoints(), dtype=float) if use_jump_ts else None
        if jumps is not None and jumps.size:
            controller = diffrax.ClipStepSizeController(controller, jump_ts=jumps)
    solution = diffrax.diffeqsolve(
        sdof_term(), solver(method), t0=0.0, t1=1.0, dt0=dt0, y0=(jnp.zeros(()), jnp.zeros(())),
        args=(law, omega, zeta), saveat=diffrax.SaveAt(ts=grid.nodes),
        stepsize_controller=controller, max_steps=max_steps, throw=False,
    )
    e, de = solution.ys
    q = de - jnp.conj(eigenvalue(omega, zeta)) * e
    within_bound = jnp.all(jnp.abs(q) <= BOUND_MARGIN * law.Ca)  # False for NaN too
    stable = free_vibration_growth(method, omega, zeta, steps) <= MAX_FREE_VIBRATION_GROWTH
    result = promote(solution.result)
    ok = result == RESULTS.successful
    result = RESULTS.where(ok & ~stable, RESULTS.unstable_fixed_step, result)
    result = RESULTS.where(ok & stable & ~within_bound, RESULTS.invariant_violated, result)
    q = jnp.where(ok & stable & within_bound, q, jnp.nan)
    return q, result, solution.stats["num_steps"]
