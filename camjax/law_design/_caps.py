"""Caps on the designed law (Ca, Cj, a monotone rise): penalties, checks and repair."""

from __future__ import annotations

import dataclasses
import math

import equinox as eqx
import jax
import jax.numpy as jnp

from ..laws import AbstractMotionLaw, BSplineLaw
from ..laws import get as get_law
from ._residual import dense_tau


class CapError(ValueError):
    """The design breaks a requested cap (Ca, Cj or a monotone rise) on the fine grid."""


MIN_CJ = 32.0
"""Least peak jerk of any rise from rest to rest in unit time (see :func:`least_jerk`)."""


def least_jerk(max_ca: float | None = None) -> float:
    """Least Cj of any rise whose acceleration stays within ``max_ca`` (None: no cap).

    The rise of least peak jerk is the time-optimal rest-to-rest motion under a jerk
    bound (Pontryagin: the jerk is bang-bang).  Without an acceleration cap the jerk is
    +J, -J, +J with switches at tau = 1/4 and 3/4, which travels J/32: so Cj >= 32.  With
    ``|a| <= A < J/4`` the acceleration is a trapezoid (ramps of A/J, flat at A), which
    travels ``A (1/2 - A/J) / 2``; reaching 1 needs ``J >= 2 A^2 / (A - 4)``.
    """
    if max_ca is None or max_ca >= 8.0:
        return MIN_CJ
    if max_ca <= 4.0:
        return math.inf
    return max(MIN_CJ, 2 * max_ca**2 / (max_ca - 4.0))


@dataclasses.dataclass(frozen=True)
class Caps:
    """Limits the designed law must meet: ``Ca <= max_ca``, ``Cj <= max_jerk``, ``v >= 0``."""

    max_ca: float | None = None
    max_jerk: float | None = None
    monotone: bool = True

    def __post_init__(self):
        for label, value in (("max_ca", self.max_ca), ("max_jerk", self.max_jerk)):
            if value is not None and not (math.isfinite(value) and value > 0):
                raise ValueError(f"Caps: {label} must be positive and finite, got {value}")
        if self.max_ca is not None and self.max_ca < 4.0:
            raise ValueError(
                f"Caps: max_ca = {self.max_ca} is infeasible: every rise has Ca >= 4 "
                "(the parabolic law's bound)"
            )
        if self.max_jerk is not None and self.max_jerk < MIN_CJ:
            raise ValueError(
                f"Caps: max_jerk = {self.max_jerk} is infeasible: every rise has Cj >= {MIN_CJ:g} "
                "(the least is a jerk of +-32 switching at tau = 1/4 and 3/4)"
            )
        if self.max_ca is not None and self.max_jerk is not None:
            least = least_jerk(self.max_ca)
            if self.max_jerk < least:
                raise ValueError(
                    f"Caps: max_jerk = {self.max_jerk} is infeasible with max_ca = {self.max_ca}: "
                    f"every rise with Ca <= {self.max_ca} has Cj >= {least:.6g}"
                )

    def features(self, law):
        """``(v, a, j)`` on a dense grid of every smooth piece (linear in the law)."""
        return law.evaluate(dense_tau(law))[1:]

    def penalty(self, law, margin: float) -> jax.Array:
        """Sum of squared relative violations on a dense grid (zero when inside)."""
        return self.penalty_of(self.features(law), margin)

    def penalty_of(self, features, margin: float) -> jax.Array:
        """``penalty`` from ``features``, aimed ``margin`` (a fraction) inside the caps."""
        v, a, j = features
        total = jnp.zeros(())
        if self.max_ca is not None:
            total += jnp.sum(jax.nn.relu(jnp.abs(a) / (self.max_ca * (1 - margin)) - 1) ** 2)
        if self.max_jerk is not None:
            total += jnp.sum(jax.nn.relu(jnp.abs(j) / (self.max_jerk * (1 - margin)) - 1) ** 2)
        if self.monotone:
            total += jnp.sum(jax.nn.relu(-v) ** 2)
        return total

    def violations(self, law: AbstractMotionLaw) -> dict[str, float]:
        """Relative excess over each cap (<= 0 when met), from refined peaks and a fine grid."""
        _, ca, cj, v_min = (float(x) for x in _fine_checks(law))
        out = {}
        if self.max_ca is not None:
            out["Ca"] = ca / self.max_ca - 1
        if self.max_jerk is not None:
            out["Cj"] = cj / self.max_jerk - 1
        if self.monotone:
            out["v>=0"] = -v_min - 1e-12
        return out

    def met(self, law) -> bool:
        return all(x <= 0 for x in self.violations(law).values())

    def repair(self, law: BSplineLaw) -> BSplineLaw:
        """``law`` itself if it meets the caps, else the nearest spline meeting them along
        the segment towards the standard law (fitted with ``law``'s knots) that breaks them
        least; a ``CapError`` where no standard law meets them.  A design's last step."""
        caps = self
        if caps.met(law):
            return law
        anchors = [BSplineLaw.fit(get_law(name), len(law.coefficients), law.degree, law.zero_jerk)
                   for name in _ANCHORS]
        feasible = [x for x in anchors if caps.met(x)]
        if not feasible:
            raise CapError(
                f"the design breaks its caps ({_describe(caps.violations(law))}) and no feasible "
                "starting spline is known to repair it; relax the caps or add knots"
            )
        anchor = min(feasible, key=lambda x: max(caps.violations(x).values()))

        def blend(t):
            return BSplineLaw((1 - t) * law.coefficients + t * anchor.coefficients, law.degree,
                              law.zero_jerk)

        lo, hi = 0.0, 1.0
        for _ in range(30):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if caps.met(blend(mid)) else (mid, hi)
        return blend(hi)


def _fine_checks(law: AbstractMotionLaw) -> tuple[float, float, float, float]:
    """Refined Cv, Ca and Cj, and the least velocity on 20001 points.

    The peaks are the law's own ``peak_coefficients``, the compiled program its Ct curves
    read too (``camjax.ct_curve`` divides by Ca): one compilation of the spline's peak
    search in a design, not two (about 2 s of a cold ``camjax design``)."""
    peaks = law.peak_coefficients()
    return peaks["Cv"], peaks["Ca"], peaks["Cj"], float(_least_velocity(law))


@eqx.filter_jit
def _least_velocity(law: AbstractMotionLaw):
    return jnp.min(law.v(jnp.linspace(0.0, 1.0, 20001)))


_ANCHORS = ("cycloidal", "modified-sine", "modified-trapezoid", "poly345", "poly4567")


def _describe(violations: dict[str, float]) -> str:
    return ", ".join(f"{k} over by {100 * v:.3g}%" for k, v in violations.items() if v > 0)
