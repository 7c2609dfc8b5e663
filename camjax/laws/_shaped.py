"""Input shapers as motion laws: a rise convolved with a shaper's impulses.

A shaper is a few impulses ``A_i`` at times ``t_i`` (``sum A_i = 1``) that cancel a mode's
residual vibration at its design frequency.  Convolving a rest-to-rest law with them gives a
rest-to-rest law again, longer by the last impulse time ``t_N``; its residual vibration is the
base law's times the shaper's percentage vibration (Singer and Seering, 1990)

    V(w) = exp(-zeta w t_N) |sum_i A_i exp(zeta w t_i) exp(i w_d t_i)|,   w_d = w sqrt(1 - zeta^2),

the vibration the impulses leave relative to one unit impulse at ``t_N`` (an unshaped step):
1 unshaped, 0 at the design frequency for ZV and ZVD.  The shapers (``T_d`` the damped period
at the design frequency, ``K = exp(-zeta pi / sqrt(1 - zeta^2))``):

- ZV:  A = [1, K] / (1 + K) at [0, T_d/2];
- ZVD: A = [1, 2K, K^2] / (1 + K)^2 at [0, T_d/2, T_d];
- EI (undamped, for a vibration tolerance Vtol): A = [(1 + Vtol)/4, (1 - Vtol)/2, (1 + Vtol)/4]
  at [0, T_d/2, T_d]: V = Vtol at the design frequency, and V <= Vtol over a wider band.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._custom_types import Breakpoints, LawValues
from ._base import (
    AbstractMotionLaw,
    AbstractSearchedPeaksLaw,
    number_text,
    refined_max,
    static_breakpoints,
)

SHAPERS = ("zv", "zvd", "ei")
"""The input shapers ``Shaper`` builds."""


class Shaper(eqx.Module):
    """The impulses of a ZV, ZVD or EI shaper for a mode of damping ratio ``damping``.

    ``times`` are in damped periods of the design frequency; ``vtol`` is the EI shaper's
    vibration tolerance (the others ignore it).  The EI shaper is the undamped closed form.
    """

    kind: str = eqx.field(static=True)
    damping: float = eqx.field(static=True, default=0.0)
    vtol: float = eqx.field(static=True, default=0.05)

    def __check_init__(self):
        if self.kind not in SHAPERS:
            raise ValueError(f"shaper must be one of {', '.join(SHAPERS)}, got {self.kind!r}")
        if not (math.isfinite(self.damping) and 0.0 <= self.damping < 1.0):
            raise ValueError(
                f"shaper {self.kind}: damping ratio must be in [0, 1), got {self.damping}"
            )
        if self.kind == "ei" and self.damping != 0.0:
            raise ValueError(
                "shaper ei: only the undamped closed form is built (damping 0); "
                "use zv or zvd for a damped mode"
            )
        if self.kind == "ei" and not 0.0 < self.vtol < 1.0:
            raise ValueError(
                f"shaper ei: vibration tolerance vtol must be in (0, 1), got {self.vtol}"
            )

    @property
    def amplitudes(self) -> np.ndarray:
        K = math.exp(-self.damping * math.pi / math.sqrt(1.0 - self.damping**2))
        if self.kind == "zv":
            return np.array([1.0, K]) / (1.0 + K)
        if self.kind == "zvd":
            return np.array([1.0, 2.0 * K, K * K]) / (1.0 + K) ** 2
        v = self.vtol
        return np.array([(1.0 + v) / 4, (1.0 - v) / 2, (1.0 + v) / 4])

    @property
    def times(self) -> np.ndarray:
        """Impulse times in damped periods of the design frequency."""
        return np.array([0.0, 0.5]) if self.kind == "zv" else np.array([0.0, 0.5, 1.0])

    def vibration(self, frequency_ratio) -> np.ndarray:
        """Percentage vibration ``V`` (Singer-Seering, module docstring) of the impulses at
        ``frequency_ratio`` = actual / design natural frequency, the damping unchanged."""
        r = np.asarray(frequency_ratio, dtype=float)[..., None]
        root = math.sqrt(1.0 - self.damping**2)
        w = 2 * math.pi * r / root  # the design's damped period is 1: w_n = 2 pi / sqrt(1 - zeta^2)
        t = self.times
        terms = self.amplitudes * np.exp(self.damping * w * (t - t[-1])) * np.exp(1j * w * root * t)
        return np.abs(terms.sum(axis=-1))


class ShapedLaw(AbstractSearchedPeaksLaw):
    """``base`` convolved with ``shaper`` designed for period ratio ``period_ratio`` of the
    *base* rise (its duration over the mode's natural period), renormalised to ``[0, 1]``.

    With ``t_i`` the impulse times in units of the base rise and ``D = 1 + t_N`` the
    shaped move's length in the same units, ``s(tau) = sum_i A_i s_b(D tau - t_i)`` and each
    derivative of order ``m`` is ``D^m`` times the same sum: exact.  At the design frequency
    the shaped move's own period ratio is ``D * period_ratio``.
    """

    base: AbstractMotionLaw
    shaper: Shaper
    period_ratio: float = eqx.field(static=True)

    def __check_init__(self):
        if not isinstance(self.base, AbstractMotionLaw):
            raise TypeError(
                f"ShapedLaw needs a motion law as its base, got {type(self.base).__name__}"
            )
        if not (math.isfinite(self.period_ratio) and self.period_ratio > 0):
            raise ValueError(f"shaped law: period ratio must be positive, got {self.period_ratio}")

    @property
    def shifts(self) -> np.ndarray:
        """Impulse times in units of the base rise's duration."""
        damped_period = 1.0 / (self.period_ratio * math.sqrt(1.0 - self.shaper.damping**2))
        return self.shaper.times * damped_period

    @property
    def stretch(self) -> float:
        """``D``: the shaped move's duration in units of the base rise's."""
        return 1.0 + float(self.shifts[-1])

    @property
    def name(self) -> str:
        extra = f",{number_text(self.shaper.vtol)}" if self.shaper.kind == "ei" else ""
        return (
            f"{self.shaper.kind}-{self.base.name}:{number_text(self.period_ratio)},"
            f"{number_text(self.shaper.damping)}{extra}"
        )

    def rise(self, tau) -> LawValues:
        D = self.stretch
        out = [0.0, 0.0, 0.0, 0.0]
        for amplitude, shift in zip(self.shaper.amplitudes, self.shifts):
            for k, x in enumerate(self.base._evaluate(D * tau - shift)):
                out[k] = out[k] + amplitude * x
        return tuple(out[k] * D**k for k in range(4))

    def breakpoints(self) -> Breakpoints:
        points = self.base.breakpoints()
        D = self.stretch
        if isinstance(points, tuple):
            return static_breakpoints(
                [(t + b) / D for t in self.shifts for b in (0.0, *points, 1.0)]
            )
        inner = jnp.concatenate([jnp.zeros(1), jnp.asarray(points, float).ravel(), jnp.ones(1)])
        return jnp.sort(jnp.concatenate([(t + inner) / D for t in self.shifts]))

    def end_state(self):
        ends = self.base.end_state()
        if ends is None:
            return None
        D, A = self.stretch, self.shaper.amplitudes
        v0, a0, v1, a1 = ends
        return A[0] * D * v0, A[0] * D**2 * a0, A[-1] * D * v1, A[-1] * D**2 * a1

    def peak(self, order: int):
        return refined_max(lambda t: jnp.abs(self.rise(t)[order]), _sample_points(self))


def _sample_points(law: AbstractMotionLaw):
    edges = (
        np.array([0.0, *law.breakpoints(), 1.0]) if isinstance(law.breakpoints(), tuple) else None
    )
    if edges is None:
        return jnp.linspace(0.0, 1.0, 4097)
    return jnp.asarray(
        np.unique(
            np.concatenate([np.linspace(lo, hi, 257) for lo, hi in zip(edges[:-1], edges[1:])])
        )
    )
