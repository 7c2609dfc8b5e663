"""Symmetric polynomial rises: 3-4-5, 4-5-6-7 and the rest of their family."""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._custom_types import Breakpoints, LawValues
from ..checks import require
from ._base import AbstractMotionLaw, polynomial_peaks


def _rise_polynomial(order: int) -> np.ndarray:
    """Ascending coefficients of ``s = I_tau(k, k)``, the regularised incomplete beta.

    Its velocity is ``tau^(k-1) (1-tau)^(k-1) / B(k, k)``: the first ``k - 1`` derivatives
    vanish at both ends.  ``k = 3`` gives 10t^3 - 15t^4 + 6t^5 (3-4-5) and ``k = 4`` gives
    35t^4 - 84t^5 + 70t^6 - 20t^7 (4-5-6-7).
    """
    k = order
    velocity = np.polynomial.Polynomial([0] * (k - 1) + [1]) * np.polynomial.Polynomial([1, -1]) ** (
        k - 1
    )
    s = velocity.integ()
    return (s / s(1.0)).coef


class PolynomialLaw(AbstractMotionLaw):
    """The symmetric polynomial rise of order ``k`` (``s = I_tau(k, k)``, degree ``2k - 1``).

    ``PolynomialLaw(3)`` is the 3-4-5 polynomial, ``PolynomialLaw(4)`` the 4-5-6-7.
    ``k = 2`` (the cubic) has acceleration steps at both ends.
    """

    order: int = eqx.field(static=True)

    def __check_init__(self):
        require(
            isinstance(self.order, int) and 2 <= self.order <= 12,
            f"PolynomialLaw order must be an integer in [2, 12], got {self.order!r}",
        )

    @property
    def name(self) -> str:
        powers = range(self.order, 2 * self.order)
        if 2 * self.order - 1 <= 9:
            return "poly" + "".join(str(p) for p in powers)
        return f"poly:{self.order}"

    def _coefficients(self, derivative: int) -> np.ndarray:
        poly = np.polynomial.Polynomial(_rise_polynomial(self.order))
        return poly.deriv(derivative).coef if derivative else poly.coef

    def rise(self, tau) -> LawValues:
        return tuple(
            jnp.polyval(jnp.asarray(self._coefficients(d)[::-1]), tau) for d in range(4)
        )

    def breakpoints(self) -> Breakpoints:
        return ()

    def end_state(self):
        a = np.polynomial.Polynomial(self._coefficients(2))
        return 0.0, float(a(0.0)), 0.0, float(a(1.0))

    @property
    def Cv(self) -> float:
        return polynomial_peaks(self._coefficients(1))

    @property
    def Ca(self) -> float:
        return polynomial_peaks(self._coefficients(2))

    @property
    def Cj(self) -> float:
        # k = 2 starts and ends with an acceleration step (a(0) = 6 != 0).
        if abs(self._coefficients(2)[0]) > 0:
            return math.inf
        return polynomial_peaks(self._coefficients(3))
