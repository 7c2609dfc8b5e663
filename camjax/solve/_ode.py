"""The SDOF motion integrated with diffrax: the general path and the exact path's check."""

from __future__ import annotations

import diffrax
import jax.numpy as jnp

from ..laws import AbstractMotionLaw
from ._grid import MotionGrid

FIXED_STEP_SOLVERS = {
    "euler": diffrax.Euler,
    "heun": diffrax.Heun,
    "midpoint": diffrax.Midpoint,
    "ralston": diffrax.Ralston,
}
ADAPTIVE_SOLVERS = {
    "bosh3": diffrax.Bosh3,
    "tsit5": diffrax.Tsit5,
    "dopri5": diffrax.Dopri5,
    "dopri8": diffrax.Dopri8,
    "kvaerno3": diffrax.Kvaerno3,
    "kvaerno4": diffrax.Kvaerno4,
    "kvaerno5": diffrax.Kvaerno5,
}
SOLVERS = {**FIXED_STEP_SOLVERS, **ADAPTIVE_SOLVERS}


def check_method(method: str) -> str:
    """Canonical method name (``"exact"`` or a diffrax solver), or a ``ValueError``."""
    key = str(method).strip().lower()
    if key != "exact" and key not in SOLVERS:
        valid = ", ".join(["exact", *SOLVERS])
        raise ValueError(f"unknown method {method!r}; valid methods: {valid}")
    return key


def _vector_field(t, y, args):
    law, omega, zeta = args
    e, de = y
    return de, law.a(t) - omega**2 * e - 2 * zeta * omega * de


def integrate(
    law: AbstractMotionLaw,
    grid: MotionGrid,
    omega,
    zeta,
    *,
    method: str,
    rtol: float,
    atol: float,
    steps: int | None,
    max_steps: int,
    use_jump_ts: bool = True,
):
    """Deflection ``(e, e')`` at the grid nodes, the diffrax result code and step count.

    Adaptive solvers stop at the law's breakpoints (``jump_ts``) unless
    ``use_jump_ts=False``; fixed-step solvers take ``steps`` equal steps over the rise.
    """
    solver = SOLVERS[method]()
    if method in FIXED_STEP_SOLVERS:
        controller = diffrax.ConstantStepSize()
        dt0 = 1.0 / steps
    else:
        jumps = jnp.asarray(law.breakpoints(), dtype=float) if use_jump_ts else None
        controller = diffrax.PIDController(rtol=rtol, atol=atol)
        if jumps is not None and jumps.size:
            controller = diffrax.ClipStepSizeController(controller, jump_ts=jumps)
        dt0 = None
    solution = diffrax.diffeqsolve(
        diffrax.ODETerm(_vector_field),
        solver,
        t0=0.0,
        t1=1.0,
        dt0=dt0,
        y0=(jnp.zeros(()), jnp.zeros(())),
        args=(law, omega, zeta),
        saveat=diffrax.SaveAt(ts=grid.nodes),
        stepsize_controller=controller,
        max_steps=max_steps,
        throw=False,
    )
    e, de = solution.ys
    return e, de, solution.result, solution.stats["num_steps"]
