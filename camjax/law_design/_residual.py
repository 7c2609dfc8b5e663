"""Residual vibration by Gauss-Legendre quadrature over the law's smooth pieces.

The mode at the end of the rise, ``q = int_0^1 a(u) exp(lambda (1 - u)) du``, is linear in
the law's acceleration, so one matrix-vector product per batch of period ratios; its
envelope ``w |q| / sqrt(1 - zeta^2)`` is R undamped (the design objectives' smooth
measure), and ``residual`` is the largest acceleration in the dwell it starts.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from ..laws import AbstractMotionLaw
from ..sdof import eigenvalue

_GAUSS_ORDER = 12
_MAX_PHASE_PER_PANEL = 2.0  # radians of exp(lambda u) across one quadrature panel
_DENSE_PER_PIECE = 24  # samples per smooth piece where caps and Ca are checked in training


def _piece_edges(law: AbstractMotionLaw) -> np.ndarray:
    points = law.breakpoints()
    if not isinstance(points, tuple):
        raise ValueError(
            f"law {law.name!r} has traced breakpoints; the quadrature residual needs fixed "
            "ones (use camjax.residual_vibration instead)"
        )
    return np.array([0.0, *points, 1.0])


def quadrature(law: AbstractMotionLaw, max_period_ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights over ``[0, 1]``, exact to rounding for R up to
    ``max_period_ratio``: panels never straddle a breakpoint and span at most 2 radians of
    the vibration (the integrand is a low-degree polynomial times an exponential)."""
    x, w = np.polynomial.legendre.leggauss(_GAUSS_ORDER)
    omega = 2 * math.pi * max(float(max_period_ratio), 1e-3)
    nodes, weights = [], []
    for lo, hi in zip(*(lambda e: (e[:-1], e[1:]))(_piece_edges(law))):
        panels = max(1, math.ceil((hi - lo) * omega / _MAX_PHASE_PER_PANEL))
        cuts = np.linspace(lo, hi, panels + 1)
        for a, b in zip(cuts[:-1], cuts[1:]):
            nodes.append(a + (b - a) * (x + 1) / 2)
            weights.append((b - a) / 2 * w)
    return np.concatenate(nodes), np.concatenate(weights)


def residual_kernel(period_ratios: np.ndarray, damping: float, nodes, weights):
    """``K[k, q]`` with ``R_k Ca = |K[k] @ a(nodes)|`` (complex, NumPy): the residual is
    linear in the acceleration at the quadrature ``nodes`` (``quadrature``)."""
    omega = 2 * np.pi * np.asarray(period_ratios, dtype=float)[:, None]
    lam = eigenvalue(omega, damping)  # the engine's (NumPy for concrete values)
    return omega / np.sqrt(1.0 - damping**2) * weights * np.exp(lam * (1.0 - nodes))


def _residual_components(law, period_ratios, damping: float) -> jax.Array:
    """``(2, N)`` real and imaginary parts of the residual's complex amplitude (linear in
    the law; its modulus is ``R * Ca``).  ``period_ratios`` must be concrete."""
    n = np.atleast_1d(np.asarray(period_ratios, dtype=float))
    nodes, weights = quadrature(law, n.max())
    k = residual_kernel(n, float(damping), nodes, weights)
    acc = law.a(jnp.asarray(nodes))
    return jnp.stack([jnp.asarray(k.real) @ acc, jnp.asarray(k.imag) @ acc])


def residual_amplitude(law, period_ratios, damping: float = 0.0) -> jax.Array:
    """``R * Ca`` (the largest residual acceleration in the dwell, units of h/T^2) at
    ``period_ratios``: ``camjax.sdof.residual_of_mode`` of the mode at ``tau = 1``, whose
    modulus times ``w / sqrt(1 - zeta^2)`` is the quadrature's (undamped, the two agree).

    ``period_ratios`` must be concrete (NumPy); the law may be traced.
    """
    from ..sdof import residual_of_mode

    omega = 2 * np.pi * np.atleast_1d(np.asarray(period_ratios, dtype=float))
    c = _residual_components(law, period_ratios, damping)
    q = (c[0] + 1j * c[1]) * jnp.asarray(np.sqrt(1.0 - damping**2) / omega)
    return residual_of_mode(q, jnp.asarray(omega), damping, 1.0)


def _modulus(components):
    return jnp.hypot(components[0], components[1])


def dense_tau(law: AbstractMotionLaw) -> jax.Array:
    """``_DENSE_PER_PIECE + 1`` samples of every smooth piece (both ends included): where
    the caps on a design's acceleration and jerk are checked."""
    edges = _piece_edges(law)
    return jnp.asarray(np.concatenate(
        [np.linspace(lo, hi, _DENSE_PER_PIECE + 1) for lo, hi in zip(edges[:-1], edges[1:])]))


def residual(law, period_ratios, damping: float = 0.0, *, ca=None) -> jax.Array:
    """Residual vibration R (units of Ca) at ``period_ratios``, by quadrature."""
    ca = law.Ca if ca is None else ca
    return residual_amplitude(law, period_ratios, damping) / ca


def percentage_vibration(law, period_ratios, damping: float = 0.0) -> jax.Array:
    """``V``: the residual vibration a move leaves, relative to an unshaped step's.

    The amplitude of the payload's deviation from the law when the rise ends,
    ``|q| / w_d`` with ``q = int_0^1 a(u) exp(lambda (1 - u)) du``, over that of a unit step
    of position applied as the rise ends, ``1 / sqrt(1 - zeta^2)``: so ``V = |q| / w``, the
    Singer-Seering percentage vibration of an impulse train carried over to a smooth move (a
    shaped law's ``V`` is its base's times its shaper's, ``camjax.laws.Shaper.vibration``).
    ``period_ratios`` must be concrete; the law may be traced.
    """
    n = np.atleast_1d(np.asarray(period_ratios, dtype=float))
    return _modulus(_residual_components(law, n, damping)) * jnp.asarray(
        np.sqrt(1.0 - damping**2) / (2 * np.pi * n) ** 2)


def vibration_band(vibration, limit: float = 0.05, search: tuple[float, float] = (0.25, 1.75),
                   samples: int = 6001) -> tuple[float, float]:
    """``(lo, hi)``: the frequency ratios (actual / design) about 1 between which
    ``vibration(r) <= limit`` throughout, the edges solved by ``brentq``; an edge that
    reaches ``search`` is returned as that end.  ``vibration`` maps a NumPy array of ratios
    to ``V`` (``Shaper.vibration``, or ``percentage_vibration`` of a law at ``n0 r``)."""
    from scipy.optimize import brentq

    if not 0.0 < limit < 1.0:
        raise ValueError(f"vibration_band: limit must be in (0, 1), got {limit}")
    r = np.unique(np.concatenate([np.linspace(*search, samples), [1.0]]))
    inside = np.asarray(vibration(r), dtype=float) <= limit * (1 + 1e-9)  # EI touches it at 1
    k = int(np.searchsorted(r, 1.0))
    if not inside[k]:
        raise ValueError(f"vibration_band: V = {float(vibration(np.array([1.0]))[0]):.4g} at the "
                         f"design frequency is above the limit {limit:g}")
    lo, hi = k, k
    while lo > 0 and inside[lo - 1]:
        lo -= 1
    while hi < r.size - 1 and inside[hi + 1]:
        hi += 1

    def edge(a, b):
        return brentq(lambda x: float(vibration(np.array([x]))[0]) - limit, a, b, xtol=1e-14)

    return (float(r[0]) if lo == 0 else edge(r[lo - 1], r[lo]),
            float(r[-1]) if hi == r.size - 1 else edge(r[hi], r[hi + 1]))
