"""B-spline motion laws whose boundary conditions hold for any coefficients."""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import checks
from .._custom_types import Breakpoints, LawValues
from ..checks import is_concrete, require
from ._base import AbstractMotionLaw, AbstractSearchedPeaksLaw

COEFFICIENTS_RULE = "BSplineLaw coefficients must be finite (got NaN or inf)"


@functools.lru_cache(maxsize=64)
def _knots(n_basis: int, degree: int) -> tuple[float, ...]:
    """Clamped knot vector with uniform interior knots on [0, 1]."""
    spans = n_basis - degree
    interior = np.linspace(0.0, 1.0, spans + 1)[1:-1]
    return tuple(np.concatenate([np.zeros(degree + 1), interior, np.ones(degree + 1)]))


@functools.lru_cache(maxsize=64)
def _derivative_matrix(knots: tuple[float, ...], degree: int, order: int) -> np.ndarray:
    """Matrix taking control points to those of the ``order``-th derivative spline."""
    t = np.asarray(knots)
    matrix = np.eye(len(t) - degree - 1)
    for r in range(order):
        p = degree - r
        tt = t[r : len(t) - r]
        n = len(tt) - p - 1
        diff = np.zeros((n - 1, n))
        for i in range(n - 1):
            span = tt[i + p + 1] - tt[i + 1]
            if span > 0:
                diff[i, i + 1] = p / span
                diff[i, i] = -p / span
        matrix = diff @ matrix
    return matrix


def _basis(knots: np.ndarray, degree: int, x: jax.Array) -> jax.Array:
    """Cox-de Boor basis functions, shape ``x.shape + (len(knots) - degree - 1,)``."""
    t = np.asarray(knots)
    x = x[..., None]
    last = np.max(np.nonzero(t[1:] > t[:-1])[0])  # last non-empty span, closed at x = 1
    left, right = t[:-1], t[1:]
    inside = (x >= left) & (x < right)
    inside = inside | ((np.arange(len(t) - 1) == last) & (x == right))
    basis = inside.astype(x.dtype)
    for p in range(1, degree + 1):
        n = len(t) - p - 1
        d1 = t[p : p + n] - t[:n]
        d2 = t[p + 1 : p + 1 + n] - t[1 : 1 + n]
        w1 = np.where(d1 > 0, 1.0 / np.where(d1 > 0, d1, 1.0), 0.0)
        w2 = np.where(d2 > 0, 1.0 / np.where(d2 > 0, d2, 1.0), 0.0)
        basis = (x - t[:n]) * w1 * basis[..., :n] + (t[p + 1 : p + 1 + n] - x) * w2 * basis[
            ..., 1 : n + 1
        ]
    return basis


REFINED_CRESTS = 4
"""Sampled crests of ``|f|`` that ``max_abs_piecewise`` refines: two crests within the
sampling's loss of each other may swap places once refined."""


def max_abs_piecewise(f, edges: np.ndarray, samples_per_piece: int = 32) -> jax.Array:
    """``max |f|`` over ``[edges[0], edges[-1]]`` for a function smooth between ``edges``.

    Samples each piece, then refines the ``REFINED_CRESTS`` largest sampled crests (local
    maxima of ``|f|`` over the samples, ends included) by golden-section search between
    each one's neighbours, all at once.  Refining the best sample alone missed the peak
    where two crests nearly tie (a 7th-degree boundary polynomial's Ca off by 1e-3).  The
    search locations carry no gradient, so derivatives follow the envelope theorem (the
    value's partial derivative at the maximiser).
    """
    pieces = [np.linspace(lo, hi, samples_per_piece + 1) for lo, hi in zip(edges[:-1], edges[1:])]
    grid = jnp.asarray(np.concatenate(pieces))
    values = jnp.abs(f(grid))
    around = jnp.pad(values, 1, constant_values=-jnp.inf)
    crest = (values >= around[:-2]) & (values >= around[2:])
    _, k = jax.lax.top_k(jax.lax.stop_gradient(jnp.where(crest, values, -jnp.inf)),
                         min(REFINED_CRESTS, grid.size))
    lo = grid[jnp.maximum(k - 1, 0)]
    hi = grid[jnp.minimum(k + 1, grid.size - 1)]
    ratio = (np.sqrt(5.0) - 1) / 2

    def step(_, bracket):
        lo, hi = bracket
        x1 = hi - ratio * (hi - lo)
        x2 = lo + ratio * (hi - lo)
        better_left = jnp.abs(f(x1)) >= jnp.abs(f(x2))
        return jnp.where(better_left, lo, x1), jnp.where(better_left, x2, hi)

    lo, hi = jax.lax.fori_loop(0, 60, step, (lo, hi))
    x_best = jax.lax.stop_gradient(0.5 * (lo + hi))
    best_sample = jax.lax.stop_gradient(grid[jnp.argmax(values)])
    return jnp.maximum(jnp.max(jnp.abs(f(x_best))), jnp.abs(f(best_sample)))


class BSplineLaw(AbstractSearchedPeaksLaw):
    """A rise ``s(tau) = sum_i c_i B_i(tau)`` on a clamped, uniform B-spline basis.

    The first three control points are 0 and the last three are 1, so ``s(0) = 0``,
    ``s(1) = 1`` and ``v = a = 0`` at both ends for *any* free coefficients; with
    ``zero_jerk=True`` a fourth point at each end also pins the jerk to zero there.
    Only the free (interior) coefficients are pytree leaves, so they can be optimised
    without constraints.  ``degree`` is at least 3 (continuous acceleration).
    """

    coefficients: jax.Array
    degree: int = eqx.field(static=True, default=5)
    zero_jerk: bool = eqx.field(static=True, default=False)

    def __init__(self, coefficients, degree: int = 5, zero_jerk: bool = False):
        if not is_concrete(coefficients):
            # Built from traced coefficients (inside jit, vmap or grad): the computation
            # that uses the law raises when it runs with one that is not finite.
            coefficients = checks.guard(
                coefficients, ~jnp.all(jnp.isfinite(coefficients)), COEFFICIENTS_RULE)
        self.coefficients = coefficients
        self.degree = degree
        self.zero_jerk = zero_jerk

    def __check_init__(self):
        require(
            isinstance(self.degree, int) and 3 <= self.degree <= 9,
            f"BSplineLaw degree must be an integer in [3, 9], got {self.degree!r}",
        )
        require(
            jnp.ndim(self.coefficients) == 1,
            f"BSplineLaw coefficients must be 1-D, got shape {jnp.shape(self.coefficients)}",
        )
        require(
            self.n_basis >= self.degree + 1,
            f"BSplineLaw of degree {self.degree} needs at least "
            f"{self.degree + 1 - 2 * self._n_fixed} free coefficients, got {len(self.coefficients)}",
        )
        if is_concrete(self.coefficients):
            require(
                bool(np.all(np.isfinite(np.asarray(self.coefficients)))),
                COEFFICIENTS_RULE,
            )

    @property
    def _n_fixed(self) -> int:
        return 4 if self.zero_jerk else 3

    @property
    def n_basis(self) -> int:
        return len(self.coefficients) + 2 * self._n_fixed

    @property
    def knots(self) -> np.ndarray:
        return np.asarray(_knots(self.n_basis, self.degree))

    @property
    def control_points(self) -> jax.Array:
        """All control points: the fixed 0s and 1s around the free coefficients."""
        c = jnp.asarray(self.coefficients)
        return jnp.concatenate(
            [jnp.zeros(self._n_fixed, c.dtype), c, jnp.ones(self._n_fixed, c.dtype)]
        )

    @property
    def name(self) -> str:
        return f"bspline:{len(self.coefficients)}"

    @staticmethod
    def derivative_map(n_basis: int, degree: int, order: int) -> np.ndarray:
        """Matrix from all ``n_basis`` control points of a degree-``degree`` law (clamped
        uniform knots) to the control points of its ``order``-th derivative (the linear map
        a design optimises through)."""
        return _derivative_matrix(_knots(n_basis, degree), degree, order)

    def _derivative(self, tau, order: int) -> jax.Array:
        knots = _knots(self.n_basis, self.degree)
        points = jnp.asarray(_derivative_matrix(knots, self.degree, order)) @ self.control_points
        trimmed = np.asarray(knots)[order : len(knots) - order]
        return _basis(trimmed, self.degree - order, jnp.asarray(tau)) @ points

    def rise(self, tau) -> LawValues:
        return _spline_rise(self, tau)

    def end_state(self):
        # v = a = 0 at both ends for any coefficients (the fixed control points).
        return (0.0, 0.0, 0.0, 0.0) if is_concrete(self) else None

    def breakpoints(self) -> Breakpoints:
        return tuple(float(x) for x in np.unique(self.knots)[1:-1])

    def peak(self, order: int) -> jax.Array:
        return _peak(self, order)

    @classmethod
    def fit(
        cls, law: AbstractMotionLaw, n_free: int, degree: int = 5, zero_jerk: bool = False
    ) -> BSplineLaw:
        """Least-squares fit of another law's displacement (a starting point for design)."""
        n_fixed = 4 if zero_jerk else 3
        tau = np.linspace(0.0, 1.0, 40 * (n_free + 2 * n_fixed))
        basis, s = _fit_samples(law, n_free + 2 * n_fixed, degree, jnp.asarray(tau))
        basis = np.asarray(basis)
        target = np.asarray(s) - basis[:, -n_fixed:].sum(axis=1)
        free = np.linalg.lstsq(basis[:, n_fixed:-n_fixed], target, rcond=None)[0]
        return cls(jnp.asarray(free), degree=degree, zero_jerk=zero_jerk)


@eqx.filter_jit
def _fit_samples(law: AbstractMotionLaw, n_basis: int, degree: int, tau):
    """The B-spline basis and ``law``'s displacement at ``tau``, for ``BSplineLaw.fit``: one
    compiled call per law and size (evaluated eagerly they dispatch many small ops)."""
    return _basis(np.asarray(_knots(n_basis, degree)), degree, tau), law.s(tau)


# Compiled once per spline size: eager evaluation dispatches hundreds of small ops.
@eqx.filter_jit
def _spline_rise(law: BSplineLaw, tau) -> LawValues:
    return tuple(law._derivative(tau, order) for order in range(4))


@eqx.filter_jit
def _peak(law: BSplineLaw, order: int) -> jax.Array:
    edges = np.unique(law.knots)
    return max_abs_piecewise(lambda t: law._derivative(t, order), edges)
