"""The SDOF motion integrated with diffrax: the general path and the exact path's check.

A diffrax solution is checked before it is returned, so that an unstable or failed run
gives a failure status and NaN values instead of plausible wrong numbers:

- fixed-step explicit solvers: the growth of their numerical free vibration over the
  rise, ``|R(lambda h)|^steps`` with ``R`` the method's stability polynomial, must stay
  below ``MAX_FREE_VIBRATION_GROWTH`` (the true free vibration never grows).  Euler and
  the two-stage methods have no stable interval on the imaginary axis, so this bounds
  ``w h`` for a given step count (see docs/work-precision.md);
- every diffrax solver: the complex mode ``q = e' - conj(lambda) e`` must stay finite
  and within its physical bound ``|q(t)| <= integral |a| <= Ca`` (``zeta >= 0``).
A failed check reports ``diffrax.RESULTS.nonfinite`` (the values are replaced by NaN).
"""

from __future__ import annotations

import diffrax
import jax.numpy as jnp

from ..laws import AbstractMotionLaw
from ._exact import eigenvalue
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

# Stability polynomials R(z) (coefficients of z^0, z^1, ...): one step maps y to R(h J) y.
STABILITY_POLYNOMIALS = {
    "euler": (1.0, 1.0),
    "heun": (1.0, 1.0, 0.5),
    "midpoint": (1.0, 1.0, 0.5),
    "ralston": (1.0, 1.0, 0.5),
}
MAX_FREE_VIBRATION_GROWTH = 1.1
"""Largest growth of a fixed-step solver's free vibration over the rise that is accepted."""
_BOUND_MARGIN = 1.01


def check_method(method: str) -> str:
    """Canonical method name (``"exact"`` or a diffrax solver), or a ``ValueError``."""
    key = str(method).strip().lower()
    if key != "exact" and key not in SOLVERS:
        valid = ", ".join(["exact", *SOLVERS])
        raise ValueError(f"unknown method {method!r}; valid methods: {valid}")
    return key


def free_vibration_growth(method: str, omega, zeta, steps: int):
    """Factor by which ``method``'s numerical free vibration grows over ``steps`` steps.

    ``|R(lambda / steps)|^steps`` for the fixed-step explicit solvers (the exact factor,
    ``exp(-zeta w)``, is at most 1); 1 for adaptive solvers, whose error control bounds it.
    """
    if method not in STABILITY_POLYNOMIALS:
        return jnp.ones_like(jnp.asarray(omega, dtype=float))
    z = eigenvalue(omega, zeta) / steps
    amplification = sum(c * z**k for k, c in enumerate(STABILITY_POLYNOMIALS[method]))
    return jnp.exp(steps * jnp.log(jnp.abs(amplification)))


def vector_field(t, y, args):
    """Right-hand side of the SDOF deflection equation, in diffrax's ``(t, y, args)`` form.

    ``y = (e, e')`` is the transmission deflection ``e = s - x`` and its rate;
    ``args = (law, omega, zeta)`` with ``omega = 2 pi n``.  Returns ``(e', e'')`` with
    ``e'' = a(t) - omega^2 e - 2 zeta omega e'``.  Parameters travel in ``args`` (not a
    closure), so vmap and grad see them.
    """
    law, omega, zeta = args
    e, de = y
    return de, law.a(t) - omega**2 * e - 2 * zeta * omega * de


def sdof_term() -> diffrax.ODETerm:
    """The diffrax term of the SDOF deflection equation (:func:`vector_field`).

    For custom ``diffrax.diffeqsolve`` calls (other controllers, adjoints, saved
    statistics) that the :func:`camjax.solve.solve` options do not cover::

        diffrax.diffeqsolve(sdof_term(), diffrax.Tsit5(), 0.0, 1.0, None,
                            (jnp.zeros(()), jnp.zeros(())), args=(law, 2 * jnp.pi * n, zeta))
    """
    return diffrax.ODETerm(vector_field)


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
    An unstable or out-of-bound solution comes back as NaN with result ``nonfinite``
    (see the module docstring).
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
        sdof_term(),
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
    mode = jnp.abs(de - jnp.conj(eigenvalue(omega, zeta)) * e)
    within_bound = jnp.all(mode <= _BOUND_MARGIN * law.Ca)  # False for NaN too
    stable = free_vibration_growth(method, omega, zeta, steps) <= MAX_FREE_VIBRATION_GROWTH
    accepted = within_bound & stable
    result = diffrax.RESULTS.where(
        accepted | (solution.result != diffrax.RESULTS.successful),
        solution.result,
        diffrax.RESULTS.nonfinite,
    )
    e, de = (jnp.where(accepted, x, jnp.nan) for x in (e, de))
    return e, de, result, solution.stats["num_steps"]
