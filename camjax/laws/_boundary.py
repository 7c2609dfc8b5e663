"""Laws that start or end in motion: the boundary-condition polynomial and constant velocity.

VDI 2143 joins a segment to its neighbours at rest (R), at constant velocity (G), at a
reversal (U) or in general motion (B).  The classic laws join R to R; these meet any
given end state.  Both are normalised like every law (``s(0) = 0``, ``s(1) = 1``), so
their boundary values are in normalised units: ``v = (beta / h) dy/dtheta``,
``a = (beta^2 / h) d2y/dtheta2``, ``j = (beta^3 / h) d3y/dtheta3`` for a segment of lift
``h`` over ``beta``.
"""

from __future__ import annotations

import functools
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import Breakpoints, LawValues
from ..checks import is_concrete, require
from ._base import (
    AbstractMotionLaw,
    AbstractSearchedPeaksLaw,
    float_leaf,
    number_text,
    polynomial_critical_points,
    polynomial_peaks,
)
from ._spline import BSplineLaw, max_abs_piecewise

DEGREES = (5, 7)


@functools.lru_cache(maxsize=2)
def _end_inverse(degree: int) -> np.ndarray:
    """Inverse of the map from the top ``m`` coefficients (``tau^(n-m+1) .. tau^n``) to
    ``(s, s', ..., s^(m-1))`` at ``tau = 1``, with ``m = (degree + 1) / 2``."""
    m = (degree + 1) // 2
    powers = np.arange(degree + 1 - m, degree + 1)
    rows = [np.ones(m)]
    for r in range(1, m):
        rows.append(rows[-1] * (powers - (r - 1)))
    return np.linalg.inv(np.array(rows))


@functools.lru_cache(maxsize=2)
def _end_low(degree: int) -> np.ndarray:
    """Map from the low coefficients (``tau^0 .. tau^(m-1)``) to the same end values."""
    m = (degree + 1) // 2
    powers = np.arange(m)
    rows = [np.ones(m)]
    for r in range(1, m):
        rows.append(rows[-1] * np.maximum(powers - (r - 1), 0))
    return np.array(rows)


class BoundaryPolynomial(AbstractSearchedPeaksLaw):
    """The polynomial of degree 5 or 7 from 0 to 1 that meets given end states.

    Degree 5 meets velocity ``v`` and acceleration ``a`` at both ends; degree 7 also the
    jerk ``j``.  With every end value zero it is the 3-4-5 (degree 5) or 4-5-6-7 (degree
    7) rise.  The coefficients are linear in the boundary values (the law's leaves), so
    everything is differentiable in them.  ``Cv``, ``Ca``, ``Cj`` are exact (roots of the
    next derivative) for concrete values; under a trace, sampled and polished.
    """

    v0: jax.Array = eqx.field(converter=float_leaf, default=0.0)
    a0: jax.Array = eqx.field(converter=float_leaf, default=0.0)
    v1: jax.Array = eqx.field(converter=float_leaf, default=0.0)
    a1: jax.Array = eqx.field(converter=float_leaf, default=0.0)
    j0: jax.Array = eqx.field(converter=float_leaf, default=0.0)
    j1: jax.Array = eqx.field(converter=float_leaf, default=0.0)
    degree: int = eqx.field(static=True, default=5)

    def __check_init__(self):
        require(type(self.degree) is int and self.degree in DEGREES,
                f"polynomial degree must be 5 or 7, got {self.degree!r}")
        if is_concrete(self):
            values = [float(getattr(self, k)) for k in ("v0", "a0", "v1", "a1", "j0", "j1")]
            require(all(math.isfinite(x) for x in values),
                    f"polynomial boundary values must be finite, got {values}")
            require(self.degree == 7 or (values[4] == 0 and values[5] == 0),
                    "a degree-5 polynomial cannot meet a jerk condition (use degree 7)")

    @property
    def name(self) -> str:
        ends = (self.v0, self.a0, self.v1, self.a1) if self.degree == 5 else (
            self.v0, self.a0, self.j0, self.v1, self.a1, self.j1)
        if not is_concrete(self):
            return f"polynomial{self.degree}"
        # A value at rounding noise beside the others (a "match" that read -5e-16) reads 0.
        values = [float(x) for x in ends]
        floor = 1e-12 * max(1.0, *map(abs, values))
        return f"polynomial{self.degree}:" + ",".join(number_text(0.0 if abs(x) <= floor else x)
                                                     for x in values)

    def coefficients(self) -> jax.Array:
        """Ascending coefficients of ``s(tau)`` (degree + 1 of them)."""
        xp = np if is_concrete(self) else jnp  # NumPy when concrete: no eager JAX op by op
        m = (self.degree + 1) // 2
        low = xp.stack([xp.zeros(()), self.v0, self.a0 / 2] + ([self.j0 / 6] if m == 4 else []))
        target = xp.stack([xp.ones(()), self.v1, self.a1] + ([self.j1] if m == 4 else []))
        high = xp.asarray(_end_inverse(self.degree)) @ (target - xp.asarray(_end_low(self.degree)) @ low)
        return xp.concatenate([low, high]).astype(float)

    def _numpy_derivative(self, order: int) -> np.ndarray:
        poly = np.polynomial.Polynomial(np.asarray(self.coefficients(), dtype=float))
        return poly.deriv(order).coef if order else poly.coef

    def rise(self, tau) -> LawValues:
        c = self.coefficients()
        out = []
        for _ in range(4):
            out.append(jnp.polyval(c[::-1], tau))
            c = c[1:] * jnp.arange(1, c.size)
        return tuple(out)

    def breakpoints(self) -> Breakpoints:
        return ()

    def peak(self, order: int):
        if is_concrete(self):
            return polynomial_peaks(self._numpy_derivative(order))
        return max_abs_piecewise(lambda t: self.rise(t)[order], np.array([0.0, 1.0]), 64)

    def peak_coefficients(self) -> dict[str, float]:
        if is_concrete(self):
            return {"Cv": self.Cv, "Ca": self.Ca, "Cj": self.Cj}
        return super().peak_coefficients()

    def end_state(self):
        if not is_concrete(self):
            return None
        return tuple(float(x) for x in (self.v0, self.a0, self.v1, self.a1))

    def displacement_range(self) -> tuple[float, float]:
        """``(min s, max s)`` over ``[0, 1]``, exactly: outside ``[0, 1]`` the lift overshoots."""
        poly = np.polynomial.Polynomial(self._numpy_derivative(0))
        values = poly(polynomial_critical_points(poly.coef))
        return float(values.min()), float(values.max())


class ConstantVelocity(AbstractMotionLaw):
    """``s = tau``: the follower moves at the constant speed ``h / beta`` (a VDI 2143 G-G law)."""

    @property
    def name(self) -> str:
        return "constant-velocity"

    def rise(self, tau) -> LawValues:
        return tau, jnp.ones_like(tau), jnp.zeros_like(tau), jnp.zeros_like(tau)

    def breakpoints(self) -> Breakpoints:
        return ()

    def end_state(self):
        return 1.0, 0.0, 1.0, 0.0

    @property
    def Cv(self) -> float:
        return 1.0

    @property
    def Ca(self) -> float:
        return 0.0

    @property
    def Cj(self) -> float:
        return 0.0

    def displacement_range(self) -> tuple[float, float]:
        return 0.0, 1.0


class CorrectedPolynomial(AbstractSearchedPeaksLaw):
    """A ``BoundaryPolynomial`` plus a B-spline correction that keeps its end states.

    ``s = base(tau) + sum_i c_i B_i(tau)`` on the clamped uniform basis of a
    ``BSplineLaw`` of ``spline_degree`` whose first three (degree-7 base: four) control
    points at each end are zero, so the correction vanishes with its first two (three)
    derivatives at both ends: the base's velocity, acceleration (and jerk) hold there for
    any coefficients.  Only the coefficients are leaves a design moves (the base's are
    leaves too, so the law differentiates in both).  A family for designing a segment
    that starts or ends in motion.
    """

    base: BoundaryPolynomial
    coefficients: jax.Array
    spline_degree: int = eqx.field(static=True, default=5)

    def _spline(self, coefficients) -> BSplineLaw:
        return BSplineLaw(coefficients, self.spline_degree, zero_jerk=self.base.degree == 7)

    @property
    def name(self) -> str:
        return f"corrected-polynomial{self.base.degree}:{len(self.coefficients)}"

    def rise(self, tau) -> LawValues:
        base = self.base.rise(tau)
        full = self._spline(self.coefficients).rise(tau)
        zero = self._spline(jnp.zeros_like(self.coefficients)).rise(tau)
        return tuple(b + f - z for b, f, z in zip(base, full, zero))

    def breakpoints(self) -> Breakpoints:
        return self._spline(self.coefficients).breakpoints()

    def end_state(self):
        # The correction keeps the base's end states for any coefficients.
        return self.base.end_state() if is_concrete(self) else None

    def peak(self, order: int):
        edges = np.array([0.0, *self.breakpoints(), 1.0])
        return max_abs_piecewise(lambda t: self.rise(t)[order], edges)
