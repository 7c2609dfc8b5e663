"""Design objectives: residual vibration and peak inertia load, at one n or over a band, and
the RMS acceleration (a servo's heating)."""

from __future__ import annotations

import abc
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..laws import RMS_ACCELERATION_FLOOR
from ..models import SpringMassOptions
from ..sdof import (
    TARGET_PHASE_STEP,
    check_grid_size,
    default_resolution,
    dwell_peak,
    mode_gain,
    motion_grid,
    period_ratio_reach,
    propagate,
)
from ._residual import _modulus, _residual_components, quadrature, residual

EVALUATION_SAMPLES = 2000
"""Period ratios across a band on which reported (true) maxima are taken."""

_TRAINING_OVERSAMPLING = 4  # Ca*Ct trains on a grid this much finer than the default


def _power_mean(values, p):
    """``(mean values^p)^(1/p)``, computed stably; tends to ``max`` as ``p`` grows."""
    top = jax.lax.stop_gradient(jnp.max(values))
    return top * jnp.mean((values / top) ** p) ** (1.0 / p)


def _band(n1: float, n2: float, what: str) -> None:
    if not (math.isfinite(n1) and math.isfinite(n2) and 0 < n1 < n2):
        raise ValueError(f"{what}: band must satisfy 0 < n1 < n2, got [{n1}, {n2}]")


def _training_resolution(max_period_ratio: float, name: str) -> int:
    """The Ca*Ct training grid for period ratios up to ``max_period_ratio``, or a
    ``ValueError`` (before any work) where it would pass ``MAX_GRID_INTERVALS``."""
    resolution = _TRAINING_OVERSAMPLING * default_resolution(max_period_ratio)
    largest = period_ratio_reach(TARGET_PHASE_STEP / _TRAINING_OVERSAMPLING)
    check_grid_size(resolution, f"{name}: the training grid at period ratio {max_period_ratio:g}",
                    f"period ratios up to about {largest:,.0f}")
    return resolution


def _reported(max_period_ratio: float, name: str) -> None:
    """The exact path's own refusal (``SpringMassOptions.checked``), named, where it cannot
    reach ``max_period_ratio``: it reports the design, so this is checked before any work."""
    try:
        SpringMassOptions().checked(max_period_ratio)
    except ValueError as error:
        raise ValueError(f"{name}: {error}") from None


def _check_common(weight: float, damping: float, name: str) -> None:
    if not (math.isfinite(weight) and weight > 0):
        raise ValueError(f"{name}: weight must be positive, got {weight}")
    if not (0.0 <= damping < 1.0):
        raise ValueError(f"{name}: damping ratio must be in [0, 1), got {damping}")


class AbstractObjective(eqx.Module):
    """A design objective: a smooth training value and a reported value.

    Training splits in two: ``features(law)``, the quantities the objective needs, linear
    in the law's coefficients (so a design evaluates them as one matrix product), and
    ``value(features, ca, sharpness)``, the smooth training value from them (``ca`` is the
    law's Ca as used in training, ``sharpness`` the power-mean exponent of maxima).
    ``report(law)`` is the figure a user is shown (true maxima on ``EVALUATION_SAMPLES``
    period ratios, refined Ca).

    Every objective has static fields ``weight`` (its share of the loss) and ``damping``.
    """

    @abc.abstractmethod
    def features(self, law):
        """Quantities of the law the objective needs; linear in its coefficients."""

    @abc.abstractmethod
    def value(self, features, ca, sharpness):
        """Training value from ``features`` (jittable, differentiable)."""

    def train(self, law, ca, sharpness):
        """Training value of ``law`` (jittable, differentiable in the law)."""
        return self.value(self.features(law), ca, sharpness)

    @abc.abstractmethod
    def report(self, law, **sweep_options) -> float:
        """Reported value; ``sweep_options``: static options of the exact-path sweep that
        computes it, where one does (``camjax.ct_curve``'s, such as ``peak_search`` or
        ``sweep``), which change how it compiles, not the value."""

    @property
    @abc.abstractmethod
    def label(self) -> str:
        """What the objective is, for tables."""

    @abc.abstractmethod
    def evaluation_ratios(self) -> np.ndarray:
        """Period ratios on which reports and comparisons evaluate it."""


class Residual(AbstractObjective):
    """Residual vibration R at one period ratio."""

    period_ratio: float = eqx.field(static=True)
    weight: float = eqx.field(static=True, default=1.0)
    damping: float = eqx.field(static=True, default=0.0)

    def __check_init__(self):
        _check_common(self.weight, self.damping, "Residual")
        if not (math.isfinite(self.period_ratio) and self.period_ratio > 0):
            raise ValueError(f"Residual: period ratio must be positive, got {self.period_ratio}")
        _reported(self.period_ratio, "Residual")

    def features(self, law):
        return _residual_components(law, [self.period_ratio], self.damping)

    def value(self, features, ca, sharpness):
        return _modulus(features)[0] / ca

    def report(self, law, **sweep_options) -> float:
        return float(_exact_curve(law, [self.period_ratio], self.damping, **sweep_options).residual[0])

    def evaluation_ratios(self):
        return np.array([self.period_ratio])

    @property
    def label(self):
        return f"R(n={self.period_ratio:g})"


class MaxResidual(AbstractObjective):
    """max R over the band ``[n1, n2]`` (a power mean of ``samples`` values in training)."""

    n1: float = eqx.field(static=True)
    n2: float = eqx.field(static=True)
    samples: int = eqx.field(static=True, default=256)
    weight: float = eqx.field(static=True, default=1.0)
    damping: float = eqx.field(static=True, default=0.0)

    def __check_init__(self):
        _check_common(self.weight, self.damping, "MaxResidual")
        _band(self.n1, self.n2, "MaxResidual")
        _reported(self.n2, "MaxResidual")
        if self.samples < 2:
            raise ValueError(f"MaxResidual: samples must be at least 2, got {self.samples}")

    def features(self, law):
        return _residual_components(law, np.linspace(self.n1, self.n2, self.samples), self.damping)

    def value(self, features, ca, sharpness):
        return _power_mean(_modulus(features), sharpness) / ca

    def evaluation_ratios(self):
        return np.linspace(self.n1, self.n2, EVALUATION_SAMPLES)

    def report(self, law, **sweep_options) -> float:
        return float(np.max(_exact_curve(law, self.evaluation_ratios(), self.damping,
                                         **sweep_options).residual))

    @property
    def label(self):
        return f"max R over [{self.n1:g}, {self.n2:g}]"


class ExpectedResidual(AbstractObjective):
    """Expected R when n is normal with ``mean`` and ``std`` (Gauss-Hermite, ``nodes``)."""

    mean: float = eqx.field(static=True)
    std: float = eqx.field(static=True)
    nodes: int = eqx.field(static=True, default=32)
    weight: float = eqx.field(static=True, default=1.0)
    damping: float = eqx.field(static=True, default=0.0)

    def __check_init__(self):
        _check_common(self.weight, self.damping, "ExpectedResidual")
        if not (self.std > 0 and self.mean - 4 * self.std > 0):
            raise ValueError(
                "ExpectedResidual: need std > 0 and mean - 4 std > 0 (n must stay positive), "
                f"got mean {self.mean}, std {self.std}"
            )
        _reported(self.mean + 4 * self.std, "ExpectedResidual")

    def _rule(self):
        x, w = np.polynomial.hermite_e.hermegauss(self.nodes)
        return self.mean + self.std * x, w / w.sum()

    def features(self, law):
        return _residual_components(law, self._rule()[0], self.damping)

    def value(self, features, ca, sharpness):
        return jnp.dot(self._rule()[1], _modulus(features)) / ca

    def report(self, law, **sweep_options) -> float:
        n, w = self._rule()  # the closed-form residual: no sweep
        return float(jnp.dot(w, residual(law, n, self.damping)))

    def evaluation_ratios(self):
        return np.linspace(self.mean - 3 * self.std, self.mean + 3 * self.std, EVALUATION_SAMPLES)

    @property
    def label(self):
        return f"E[R], n ~ N({self.mean:g}, {self.std:g}^2)"


class RmsAcceleration(AbstractObjective):
    """The law's RMS acceleration ``Ca_rms = sqrt(int_0^1 a^2 dtau)``: a servo's RMS torque
    (its heating) per ``h/T^2`` where inertia dominates the load.  No rest-to-rest law goes
    below ``RMS_ACCELERATION_FLOOR`` (2 sqrt 3, the cubic); a jerk cap keeps a design above it.

    Its features are ``sqrt(w) a`` at Gauss-Legendre nodes on every smooth piece (linear in
    the law; exact for a spline's polynomial pieces), their norm the training value: the
    problem stays convex.
    """

    weight: float = eqx.field(static=True, default=1.0)
    damping: float = eqx.field(static=True, default=0.0)  # not used: the law alone sets it

    def __check_init__(self):
        _check_common(self.weight, self.damping, "RmsAcceleration")

    def features(self, law):
        nodes, weights = quadrature(law, 0.0)
        return jnp.asarray(np.sqrt(weights)) * law.a(jnp.asarray(nodes))

    def value(self, features, ca, sharpness):
        return jnp.sqrt(jnp.sum(features**2))

    def report(self, law) -> float:
        return float(law.rms_coefficients()["Ca_rms"])

    def evaluation_ratios(self):
        return np.zeros(0)

    @property
    def label(self):
        return f"Ca_rms (floor {RMS_ACCELERATION_FLOOR:.4f})"


def _payload_acceleration(law, period_ratios, damping):
    """Ca*Ct's ingredients at each period ratio, linear in the law: the payload's x'' (in
    h/T^2) on a grid ``_TRAINING_OVERSAMPLING`` times finer than the default (so sampled
    peaks fall within 0.2% of the true ones), and the dwell peak's complex amplitude."""
    n = np.atleast_1d(np.asarray(period_ratios, dtype=float))
    grid = motion_grid(law, _training_resolution(float(n.max()), "Ca*Ct"))
    omega = 2 * np.pi * n

    def one(w):
        q = propagate(grid, w, damping, resolved=True)  # w h <= 0.5 / oversampling
        return jnp.real(mode_gain(w, damping) * q), jnp.stack([q[-1].real, q[-1].imag])

    return jax.vmap(one)(jnp.asarray(omega))


def _peak_load_value(features, period_ratios, damping, dwell, sharpness):
    """Smooth max of |x''| over the rise and the dwell, across all period ratios."""
    samples, ends = features
    omega = 2 * np.pi * np.atleast_1d(np.asarray(period_ratios, dtype=float))
    q_end = ends[:, 0] + 1j * ends[:, 1]
    dwell_peaks = jax.vmap(lambda q, w: dwell_peak(q, w, damping, dwell))(q_end, jnp.asarray(omega))
    return _power_mean(jnp.concatenate([jnp.abs(samples).ravel(), dwell_peaks]), sharpness)


class CaCt(AbstractObjective):
    """Peak inertia load Ca*Ct at one period ratio."""

    period_ratio: float = eqx.field(static=True)
    weight: float = eqx.field(static=True, default=1.0)
    damping: float = eqx.field(static=True, default=0.0)
    dwell: float = eqx.field(static=True, default=1.0)

    def __check_init__(self):
        _check_common(self.weight, self.damping, "CaCt")
        if not (math.isfinite(self.period_ratio) and self.period_ratio > 0):
            raise ValueError(f"CaCt: period ratio must be positive, got {self.period_ratio}")
        _training_resolution(self.period_ratio, "CaCt")

    def features(self, law):
        return _payload_acceleration(law, [self.period_ratio], self.damping)

    def value(self, features, ca, sharpness):
        return _peak_load_value(features, [self.period_ratio], self.damping, self.dwell, sharpness)

    def report(self, law, **sweep_options) -> float:
        return float(peak_loads(law, [self.period_ratio], self.damping, self.dwell, **sweep_options)[0])

    def evaluation_ratios(self):
        return np.array([self.period_ratio])

    @property
    def label(self):
        return f"Ca*Ct(n={self.period_ratio:g})"


class MaxCaCt(AbstractObjective):
    """Worst-case Ca*Ct over ``[n1, n2]`` (robust to uncertain mass and stiffness)."""

    n1: float = eqx.field(static=True)
    n2: float = eqx.field(static=True)
    samples: int = eqx.field(static=True, default=16)
    weight: float = eqx.field(static=True, default=1.0)
    damping: float = eqx.field(static=True, default=0.0)
    dwell: float = eqx.field(static=True, default=1.0)

    def __check_init__(self):
        _check_common(self.weight, self.damping, "MaxCaCt")
        _band(self.n1, self.n2, "MaxCaCt")
        _training_resolution(self.n2, "MaxCaCt")
        if self.samples < 2:
            raise ValueError(f"MaxCaCt: samples must be at least 2, got {self.samples}")

    def _ratios(self):
        return np.linspace(self.n1, self.n2, self.samples)

    def features(self, law):
        return _payload_acceleration(law, self._ratios(), self.damping)

    def value(self, features, ca, sharpness):
        return _peak_load_value(features, self._ratios(), self.damping, self.dwell, sharpness)

    def evaluation_ratios(self):
        return np.linspace(self.n1, self.n2, EVALUATION_SAMPLES)

    def report(self, law, **sweep_options) -> float:
        return float(np.max(peak_loads(law, self.evaluation_ratios(), self.damping, self.dwell,
                                       **sweep_options)))

    @property
    def label(self):
        return f"max Ca*Ct over [{self.n1:g}, {self.n2:g}]"


def peak_loads(law, period_ratios, damping=0.0, dwell=1.0, *, devices=None, **sweep_options
               ) -> np.ndarray:
    """Ca*Ct at every period ratio from one vmapped exact-path call (NumPy).

    The ratios (a band's evaluation grid) are split over ``devices`` (default: every
    local device; ``camjax.sharding.shard_batch``), with results equal to one device's;
    ``sweep_options`` are the sweep's static options (``camjax.ct_curve``'s).
    """
    return _exact_curve(law, period_ratios, damping, dwell, devices=devices, **sweep_options).ca_ct


def _exact_curve(law, period_ratios, damping, dwell=1.0, *, devices=None, **sweep_options):
    """The exact-path sweep of ``law`` (one compiled program for every law of up to
    eight pieces, and one for longer splines): what reports and comparisons show."""
    from ..sweep import ct_curve

    return ct_curve(law, np.atleast_1d(np.asarray(period_ratios, dtype=float)),
                    damping=damping, dwell=dwell, devices=devices, **sweep_options)
