"""Laws built from a few harmonics: Freudenstein's 1-3 and 1-3-5, the triple harmonic, and
the double harmonic (rest to reversal).

The rest-to-rest ones are one family, ``HarmonicSeries``: the acceleration is a sine series
``a = sum_k A_k sin(2 pi k tau)``, k = 1..K, whose every term vanishes at both ends with its
velocity ``(A_k / 2 pi k)(1 - cos 2 pi k tau)``, so ``v = a = 0`` at both ends for any
amplitudes; the rise closes (``s(1) = 1``) when ``sum_k A_k / (2 pi k) = 1``.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import Breakpoints, LawValues
from ..checks import is_concrete, require
from ._base import AbstractSearchedPeaksLaw, float_leaf, number_text
from ._spline import max_abs_piecewise

_PI = math.pi


def dense_peak(derivative, order: int, samples: int = 4096) -> float:
    """``max |derivative(order)|`` over ``[0, 1]`` of a smooth function, in NumPy: the
    largest sampled crests polished by Newton steps on ``derivative(order + 1) = 0``
    (``derivative(m)`` maps a NumPy array to the m-th derivative)."""
    grid = np.linspace(0.0, 1.0, samples + 1)
    values = np.abs(derivative(order)(grid))
    around = np.pad(values, 1, constant_values=-np.inf)
    crests = np.flatnonzero((values >= around[:-2]) & (values >= around[2:]))
    best = float(values.max())
    for k in crests[np.argsort(values[crests])[-8:]]:
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, samples)]
        x = grid[k]
        for _ in range(30):
            slope = derivative(order + 2)(np.array([x]))[0]
            if slope == 0:
                break
            x = float(np.clip(x - derivative(order + 1)(np.array([x]))[0] / slope, lo, hi))
        best = max(best, float(abs(derivative(order)(np.array([x]))[0])))
    return best


FREUDENSTEIN_1_3_5_M = 1.0 / (1.0 + 3.0 / 54.0 + 5.0 / 1250.0)
"""Freudenstein 1-3-5's factor ``m``: ``s'(0) = 1 - m (1 + 3/54 + 5/1250) = 0``."""

PRESETS: dict[str, tuple[float, ...]] = {
    # s = tau - (1/2pi)[(27/28) sin 2pi tau + (1/84) sin 6pi tau]: a = 2 pi k^2 c_k sin(2 pi k tau).
    "freudenstein-1-3": (2 * _PI * 27 / 28, 0.0, 2 * _PI * 9 / 84),
    "freudenstein-1-3-5": tuple(2 * _PI * k**2 * FREUDENSTEIN_1_3_5_M * c for k, c in
                                ((1, 1.0), (2, 0.0), (3, 1 / 54), (4, 0.0), (5, 1 / 1250))),
}
"""Amplitudes ``A_k`` of the named sine-series laws (the triple harmonics' are added below)."""


def closing_amplitude(a1, a2):
    """``A3`` of a triple harmonic: ``A1/2pi + A2/4pi + A3/6pi = 1``."""
    return 6 * _PI * (1.0 - a1 / (2 * _PI) - a2 / (4 * _PI))


TRIPLE_HARMONIC_PRESETS = {
    # Both close by A3; their end jerk is 2 pi (A1 + 2 A2 + 3 A3).
    "triple-harmonic-modified-sine": (5.1968, 1.769),  # A3 = 0.6057, end jerk 66.3 (a step, as ModSine's)
    "triple-harmonic-zero-jerk": (9 * _PI / 4, 0.0),  # A3 = -3 pi/4, end jerk 0, Ca = 3 pi
}
"""``(A1, A2)`` of the named triple harmonics (``A3`` follows from ``s(1) = 1``)."""

PRESETS.update({name: (a1, a2, closing_amplitude(a1, a2)) for name, (a1, a2) in TRIPLE_HARMONIC_PRESETS.items()})


class _SeriesLaw(AbstractSearchedPeaksLaw):
    """A law written as its derivatives in closed form (``derivative(order, xp)``), smooth
    over the whole rise: no breakpoints, the peaks searched on ``derivative``."""

    def rise(self, tau) -> LawValues:
        return tuple(self.derivative(k)(tau) for k in range(4))

    def breakpoints(self) -> Breakpoints:
        return ()


class HarmonicSeries(_SeriesLaw):
    """Rise whose acceleration is ``sum_k A_k sin(2 pi k tau)`` (k = 1..K, ``amplitudes``).

    ``v = a = 0`` at both ends for any amplitudes; valid amplitudes close the rise,
    ``sum_k A_k / (2 pi k) = 1`` (built from a preset or by ``TripleHarmonic`` they do).
    The jerk at the ends is ``2 pi sum_k k A_k``.  Amplitudes are differentiable leaves.
    """

    amplitudes: jax.Array | np.ndarray

    def __init__(self, amplitudes):
        self.amplitudes = float_leaf(amplitudes, "harmonic amplitudes")

    def __check_init__(self):
        require(jnp.ndim(self.amplitudes) == 1 and jnp.size(self.amplitudes) >= 1,
                f"harmonic amplitudes must be a non-empty 1-D list, got shape {jnp.shape(self.amplitudes)}")
        if is_concrete(self.amplitudes):
            amps = np.asarray(self.amplitudes, dtype=float)
            require(bool(np.all(np.isfinite(amps))), f"harmonic amplitudes must be finite, got {amps.tolist()}")
            end = float(np.sum(amps / (2 * _PI * np.arange(1, amps.size + 1))))
            require(abs(end - 1.0) <= 1e-9, "harmonic amplitudes must close the rise, sum A_k/(2 pi k) = 1, "
                    f"got {end:.12g}")

    @property
    def name(self) -> str:
        """A preset's name, ``triple-harmonic:A1,A2`` for three harmonics, else
        ``harmonic-series`` (which ``get`` does not rebuild)."""
        if not is_concrete(self.amplitudes):
            return "harmonic-series"
        amps = np.asarray(self.amplitudes, dtype=float)
        for name, known in PRESETS.items():
            if len(known) == amps.size and np.max(np.abs(amps - known)) <= 1e-12:
                return name
        if amps.size == 3:
            return f"triple-harmonic:{number_text(amps[0])},{number_text(amps[1])}"
        return "harmonic-series"

    def derivative(self, order: int, xp=jnp):
        """The ``order``-th derivative of ``s`` (0..5) as a function of ``tau`` (``xp``:
        ``jax.numpy`` or ``numpy``)."""
        amps = self.amplitudes if xp is jnp else np.asarray(self.amplitudes, dtype=float)
        w = 2 * _PI * np.arange(1, np.size(self.amplitudes) + 1)  # the harmonics' 2 pi k

        def f(tau):
            t = xp.asarray(tau)[..., None]
            if order == 0:
                return xp.sum(amps / w * (t - xp.sin(w * t) / w), axis=-1)
            if order == 1:
                return xp.sum(amps / w * (1 - xp.cos(w * t)), axis=-1)
            return xp.sum(amps * w ** (order - 2) * xp.sin(w * t + (order - 2) * _PI / 2), axis=-1)

        return f

    def end_state(self):
        return (0.0, 0.0, 0.0, 0.0) if is_concrete(self) else None

    def peak(self, order: int):
        if is_concrete(self.amplitudes):
            return dense_peak(lambda m: self.derivative(m, np), order)
        return max_abs_piecewise(self.derivative(order), np.array([0.0, 1.0]), 256)


def FreudensteinOneThree() -> HarmonicSeries:
    """Freudenstein's 1-3 harmonic law (Rothbart, Cam Design Handbook, eq. 4.12):
    ``s = tau - (1/2pi)[(27/28) sin 2pi tau + (1/84) sin 6pi tau]``."""
    return HarmonicSeries(PRESETS["freudenstein-1-3"])


def FreudensteinOneThreeFive() -> HarmonicSeries:
    """Freudenstein's 1-3-5 harmonic law (eq. 4.13): ``s = tau - (m/2pi)[sin 2pi tau +
    (1/54) sin 6pi tau + (1/1250) sin 10pi tau]``, ``m = 1/(1 + 1/18 + 1/250)`` from ``s'(0) = 0``."""
    return HarmonicSeries(PRESETS["freudenstein-1-3-5"])


def TripleHarmonic(a1, a2) -> HarmonicSeries:
    """``a = A1 sin 2pi tau + A2 sin 4pi tau + A3 sin 6pi tau`` with ``A3`` closing the rise
    (``sum A_k/(2 pi k) = 1``), as MechDesigner and Pilz parameterise it; differentiable in
    ``A1``, ``A2``.  End jerk ``2 pi (A1 + 2 A2 + 3 A3)``: zero for ``(9 pi/4, 0)``."""
    if is_concrete(a1, a2):
        a1, a2 = float(a1), float(a2)
        require(math.isfinite(a1) and math.isfinite(a2),
                f"triple-harmonic amplitudes must be finite, got A1={a1}, A2={a2}")
        return HarmonicSeries(np.array([a1, a2, closing_amplitude(a1, a2)]))
    a1, a2 = jnp.asarray(a1, float), jnp.asarray(a2, float)
    return HarmonicSeries(jnp.stack([a1, a2, closing_amplitude(a1, a2)]))


class DoubleHarmonic(_SeriesLaw):
    """Rest to reversal: ``s = [(1 - cos pi tau) - (1 - cos 2 pi tau)/4] / 2``.

    ``v(0) = a(0) = 0``, and it ends at ``s = 1`` with ``v = 0``, ``a = -pi^2``: a reversal,
    for a program segment that turns back without a dwell.  The rest-to-rest tools refuse
    it (``ends_in_reversal``).  Cv = 3 sqrt(3) pi/8 (at tau = 2/3), Ca = pi^2 (at the end).
    """

    ends_in_reversal = True

    @property
    def name(self) -> str:
        return "double-harmonic"

    @staticmethod
    def derivative(order: int, xp=jnp):
        """The ``order``-th derivative of ``s`` as a function of ``tau``."""
        def f(tau):
            tau = xp.asarray(tau)
            if order == 0:
                return ((1 - xp.cos(_PI * tau)) - (1 - xp.cos(2 * _PI * tau)) / 4) / 2
            shift = order * _PI / 2
            return (-(_PI**order) * xp.cos(_PI * tau + shift)
                    + (2 * _PI) ** order * xp.cos(2 * _PI * tau + shift) / 4) / 2

        return f

    def end_state(self):
        return 0.0, 0.0, 0.0, -(_PI**2)

    def peak(self, order: int) -> float:
        return dense_peak(lambda m: self.derivative(m, np), order)
