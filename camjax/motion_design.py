"""Gradient-based design of B-spline motion laws with optax.

A design minimises a weighted sum of objectives (residual vibration R at one period
ratio, the maximum of R over a band, its expectation under a normal distribution of n,
Ca*Ct at one n or its worst case over a band) over the free coefficients of a
``BSplineLaw``, subject to caps ``Ca <= C``, ``Cj <= J`` and a monotone rise ``v >= 0``.

How the pieces fit:

- R comes from its closed form ``R = w |int_0^1 a(u) exp(lambda (1 - u)) du| / (sqrt(1 -
  zeta^2) Ca)`` (``lambda`` the oscillator's eigenvalue; for ``zeta = 0`` this is MISSION.md's
  ``w |int a exp(-i w u) du| / Ca``), integrated by Gauss-Legendre on every smooth piece of
  the law: one matrix-vector product per batch of period ratios, so thousands of n cost
  little.  Ca*Ct needs the whole response: the payload acceleration by exact propagation
  (``camjax.propagation.propagate``) on a fine grid, and the dwell's peak in closed form.
- Every quantity an objective or a cap needs (the residual's Fourier integral, the payload
  acceleration on a fine grid, the law's a, j, v on a dense grid) is linear in the spline
  coefficients, because the law is and the SDOF model is linear.  A design computes these
  maps once (one jitted Jacobian) and trains on small dense matrices: thousands of
  optimiser steps cost a second or two.
- A maximum (over a band, or over time) trains as a power mean ``(mean x^p)^(1/p)``.  L-BFGS
  runs in stages whose exponent grows fourfold (8 to 8192 by default), each stage starting
  from the last: smooth early, within 0.1% of the true max at the end.  Reports are true
  maxima over 2000 period ratios that are not the training samples.
- Caps train as quadratic penalties on a dense grid, aimed a little inside the caps.
  The constraint set is convex in the coefficients, so a result that still breaks a cap is
  blended towards a strictly feasible spline (a fit of a standard law) by bisection; then
  the caps are verified on a fine grid with refined peaks.  If no feasible point is known,
  ``CapError`` is raised: a result that breaks a requested cap is never returned.
"""

from __future__ import annotations

import abc
import dataclasses
import math
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax
from tqdm.auto import tqdm

from .laws import AbstractMotionLaw, BSplineLaw
from .laws import get as get_law
from .propagation import SolveOptions, batch_metrics, default_resolution, motion_grid, propagate
from .propagation._response import _dwell_peak, _mode_gain

EVALUATION_SAMPLES = 2000
"""Period ratios across a band on which reported (true) maxima are taken."""

DEFAULT_STEPS = 6000
"""Optimiser steps of a design (L-BFGS: 1000 per sharpness stage; a stage that has
converged hands over early)."""

_GAUSS_ORDER = 12
_MAX_PHASE_PER_PANEL = 2.0  # radians of exp(lambda u) across one quadrature panel
_DENSE_PER_PIECE = 24  # samples per smooth piece where caps and Ca are checked in training
_TRAINING_OVERSAMPLING = 4  # Ca*Ct trains on a grid this much finer than the default


class CapError(ValueError):
    """The design breaks a requested cap (Ca, Cj or a monotone rise) on the fine grid."""


# --------------------------------------------------------------------------------------
# Residual vibration by quadrature over the law's smooth pieces


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


def _kernel(period_ratios: np.ndarray, damping: float, nodes, weights):
    """``K[k, q]`` with ``R_k Ca = |K[k] @ a(nodes)|`` (complex, NumPy)."""
    omega = 2 * np.pi * np.asarray(period_ratios, dtype=float)[:, None]
    lam = -damping * omega + 1j * omega * np.sqrt(1.0 - damping**2)
    return omega / np.sqrt(1.0 - damping**2) * weights * np.exp(lam * (1.0 - nodes))


def _residual_components(law, period_ratios, damping: float) -> jax.Array:
    """``(2, N)`` real and imaginary parts of the residual's complex amplitude (linear in
    the law; its modulus is ``R * Ca``).  ``period_ratios`` must be concrete."""
    n = np.atleast_1d(np.asarray(period_ratios, dtype=float))
    nodes, weights = quadrature(law, n.max())
    k = _kernel(n, float(damping), nodes, weights)
    acc = law.a(jnp.asarray(nodes))
    return jnp.stack([jnp.asarray(k.real) @ acc, jnp.asarray(k.imag) @ acc])


def residual_amplitude(law, period_ratios, damping: float = 0.0) -> jax.Array:
    """``R * Ca`` (residual acceleration amplitude in units of h/T^2) at ``period_ratios``.

    ``period_ratios`` must be concrete (NumPy); the law may be traced.
    """
    return _modulus(_residual_components(law, period_ratios, damping))


def _modulus(components):
    return jnp.hypot(components[0], components[1])


def _dense_tau(law: AbstractMotionLaw) -> jax.Array:
    """``_DENSE_PER_PIECE + 1`` samples of every smooth piece (both ends included)."""
    edges = _piece_edges(law)
    return jnp.asarray(np.concatenate(
        [np.linspace(lo, hi, _DENSE_PER_PIECE + 1) for lo, hi in zip(edges[:-1], edges[1:])]))


def residual(law, period_ratios, damping: float = 0.0, *, ca=None) -> jax.Array:
    """Residual vibration R (units of Ca) at ``period_ratios``, by quadrature."""
    ca = law.Ca if ca is None else ca
    return residual_amplitude(law, period_ratios, damping) / ca


# --------------------------------------------------------------------------------------
# Objectives


def _power_mean(values, p):
    """``(mean values^p)^(1/p)``, computed stably; tends to ``max`` as ``p`` grows."""
    top = jax.lax.stop_gradient(jnp.max(values))
    return top * jnp.mean((values / top) ** p) ** (1.0 / p)


def _band(n1: float, n2: float, what: str) -> None:
    if not (math.isfinite(n1) and math.isfinite(n2) and 0 < n1 < n2):
        raise ValueError(f"{what}: band must satisfy 0 < n1 < n2, got [{n1}, {n2}]")


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
    def report(self, law) -> float:
        """Reported value."""

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

    def features(self, law):
        return _residual_components(law, [self.period_ratio], self.damping)

    def value(self, features, ca, sharpness):
        return _modulus(features)[0] / ca

    def report(self, law) -> float:
        return float(residual(law, [self.period_ratio], self.damping)[0])

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
        if self.samples < 2:
            raise ValueError(f"MaxResidual: samples must be at least 2, got {self.samples}")

    def features(self, law):
        return _residual_components(law, np.linspace(self.n1, self.n2, self.samples), self.damping)

    def value(self, features, ca, sharpness):
        return _power_mean(_modulus(features), sharpness) / ca

    def evaluation_ratios(self):
        return np.linspace(self.n1, self.n2, EVALUATION_SAMPLES)

    def report(self, law) -> float:
        return float(jnp.max(residual(law, self.evaluation_ratios(), self.damping)))

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

    def _rule(self):
        x, w = np.polynomial.hermite_e.hermegauss(self.nodes)
        return self.mean + self.std * x, w / w.sum()

    def features(self, law):
        return _residual_components(law, self._rule()[0], self.damping)

    def value(self, features, ca, sharpness):
        return jnp.dot(self._rule()[1], _modulus(features)) / ca

    def report(self, law) -> float:
        n, w = self._rule()
        return float(jnp.dot(w, residual(law, n, self.damping)))

    def evaluation_ratios(self):
        return np.linspace(self.mean - 3 * self.std, self.mean + 3 * self.std, EVALUATION_SAMPLES)

    @property
    def label(self):
        return f"E[R], n ~ N({self.mean:g}, {self.std:g}^2)"


def _payload_acceleration(law, period_ratios, damping):
    """Ca*Ct's ingredients at each period ratio, linear in the law: the payload's x'' (in
    h/T^2) on a grid ``_TRAINING_OVERSAMPLING`` times finer than the default (so sampled
    peaks fall within 0.2% of the true ones), and the dwell peak's complex amplitude."""
    n = np.atleast_1d(np.asarray(period_ratios, dtype=float))
    grid = motion_grid(law, _TRAINING_OVERSAMPLING * default_resolution(float(n.max())))
    omega = 2 * np.pi * n

    def one(w):
        q = propagate(grid, w, damping)
        return jnp.real(_mode_gain(w, damping) * q), jnp.stack([q[-1].real, q[-1].imag])

    return jax.vmap(one)(jnp.asarray(omega))


def _peak_load_value(features, period_ratios, damping, dwell, sharpness):
    """Smooth max of |x''| over the rise and the dwell, across all period ratios."""
    samples, ends = features
    omega = 2 * np.pi * np.atleast_1d(np.asarray(period_ratios, dtype=float))
    q_end = ends[:, 0] + 1j * ends[:, 1]
    dwell_peaks = jax.vmap(lambda q, w: _dwell_peak(q, w, damping, dwell))(q_end, jnp.asarray(omega))
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

    def features(self, law):
        return _payload_acceleration(law, [self.period_ratio], self.damping)

    def value(self, features, ca, sharpness):
        return _peak_load_value(features, [self.period_ratio], self.damping, self.dwell, sharpness)

    def report(self, law) -> float:
        return float(peak_loads(law, [self.period_ratio], self.damping, self.dwell)[0])

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

    def report(self, law) -> float:
        return float(np.max(peak_loads(law, self.evaluation_ratios(), self.damping, self.dwell)))

    @property
    def label(self):
        return f"max Ca*Ct over [{self.n1:g}, {self.n2:g}]"


def peak_loads(law, period_ratios, damping=0.0, dwell=1.0) -> np.ndarray:
    """Ca*Ct at every period ratio from one vmapped exact-path call (NumPy)."""
    n = np.atleast_1d(np.asarray(period_ratios, dtype=float))
    options = SolveOptions(dwell=dwell).checked(float(n.max()))
    metrics, _, _ = batch_metrics(law, jnp.asarray(n), float(damping), options)
    return np.asarray(metrics.ct) * float(law.Ca)


# --------------------------------------------------------------------------------------
# Caps


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
        return law.evaluate(_dense_tau(law))[1:]

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


@eqx.filter_jit
def _fine_checks(law: AbstractMotionLaw):
    """Refined Cv, Ca and Cj, and the least velocity on 20001 points (one compiled call)."""
    return law.Cv, law.Ca, law.Cj, jnp.min(law.v(jnp.linspace(0.0, 1.0, 20001)))


_ANCHORS = ("cycloidal", "modified-sine", "modified-trapezoid", "poly345", "poly4567")


def _restore(law: BSplineLaw, caps: Caps) -> BSplineLaw:
    """The nearest point, along a segment towards a strictly feasible spline, meeting the caps."""
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


def _describe(violations: dict[str, float]) -> str:
    return ", ".join(f"{k} over by {100 * v:.3g}%" for k, v in violations.items() if v > 0)


# --------------------------------------------------------------------------------------
# The optimisation loop


class DesignResult(eqx.Module):
    """A designed law with its reported objective values and training history."""

    law: BSplineLaw
    objectives: tuple[AbstractObjective, ...] = eqx.field(static=True)
    values: dict = eqx.field(static=True)
    coefficients: dict = eqx.field(static=True)
    loss_history: np.ndarray
    restored: bool = eqx.field(static=True)
    seconds: float = eqx.field(static=True)


def _acceleration_coordinates(knots: int, degree: int) -> jax.Array:
    """Matrix ``M`` such that a step ``theta`` in the coefficients ``M theta`` moves the
    acceleration's control points by ``U theta`` with ``U`` orthonormal.

    The map from free coefficients to acceleration control points is a second difference
    scaled by the squared knot count: badly conditioned (its singular values span two or
    more decades).  Optimising in these coordinates makes every direction equally stiff,
    which first-order methods need.
    """
    from .laws._spline import _derivative_matrix, _knots

    n_basis = knots + 6
    second = _derivative_matrix(_knots(n_basis, degree), degree, 2)[:, 3:-3]
    _, singular, vt = np.linalg.svd(second, full_matrices=False)
    return jnp.asarray(vt.T / singular)


def _as_objectives(objective) -> tuple[AbstractObjective, ...]:
    objectives = (objective,) if isinstance(objective, AbstractObjective) else tuple(objective)
    if not objectives or not all(isinstance(o, AbstractObjective) for o in objectives):
        raise ValueError("objective must be an objective or a non-empty sequence of them")
    return objectives


def _sharpness_stages(sharpness: tuple[float, float]) -> np.ndarray:
    """Power-mean exponents from ``sharpness[0]`` to ``sharpness[1]``, growing about 4x."""
    first, last = (float(p) for p in sharpness)
    count = 1 + max(0, math.ceil(math.log(last / first, 4.0) - 1e-9))
    return np.geomspace(first, last, count)


def linear_maps(features, knots: int):
    """``(offset, jacobian)`` of ``features(theta)``, a pytree of arrays affine in ``theta``
    (``knots`` entries): ``features(theta) = offset + jacobian @ theta`` leaf by leaf.

    One jitted ``jax.linearize`` at zero, and its tangent map applied to the unit vectors.
    """
    @jax.jit
    def maps(zero):
        offset, tangent = jax.linearize(features, zero)
        return offset, jax.vmap(tangent, out_axes=-1)(jnp.eye(knots))

    return maps(jnp.zeros(knots))


def _linearised(features, knots: int):
    """``features`` as matrix products (``linear_maps``), which is all the optimiser needs."""
    offset, jacobian = linear_maps(features, knots)
    return lambda theta: jax.tree.map(lambda b, m: b + m @ theta, offset, jacobian)


def design(
    objective,
    *,
    caps: Caps = Caps(),
    knots: int = 24,
    degree: int = 5,
    initial: AbstractMotionLaw | str = "cycloidal",
    optimizer: str = "lbfgs",
    steps: int = DEFAULT_STEPS,
    learning_rate: float = 1e-2,
    sharpness: tuple[float, float] = (8.0, 8192.0),
    penalty: float = 1e4,
    margin: float = 1e-3,
    seed: int = 0,
    noise: float = 0.0,
    progress: bool = True,
) -> DesignResult:
    """Design a B-spline rise minimising ``sum(weight * objective)`` under ``caps``.

    Args:
        objective: one objective or a sequence (weights are their ``weight`` fields; each
            is divided by its value at the starting law so weights are relative).
        caps: ``Caps(max_ca, max_jerk, monotone=True)``, met by the result on a fine grid.
        knots: free B-spline coefficients (the boundary conditions fix three more at
            each end).
        initial: the law (or its name) fitted as the starting point.
        optimizer: ``"lbfgs"`` (optax L-BFGS with zoom line search, restarted at each
            sharpness stage) or ``"adam"`` (rate decaying 100-fold, sharpness ramped
            geometrically over the run).
        steps: optimiser steps in all; L-BFGS splits them evenly over the stages (rounded
            up to whole chunks of at most 200) and moves to the next stage early once a
            stage has converged.
        sharpness: power-mean exponent of maxima at the first and the last stage; L-BFGS
            stages grow it about fourfold each.
        penalty, margin: weight of the cap penalty and the fraction by which training aims
            inside the caps.
        seed, noise: a run is deterministic; with ``noise > 0`` the seed draws a Gaussian
            perturbation of that size (in acceleration coordinates) of the starting point,
            so multi-start is a loop over seeds.
    Raises:
        CapError: the result breaks a cap and cannot be repaired.
    """
    started = time.perf_counter()
    objectives = _as_objectives(objective)
    if optimizer not in ("adam", "lbfgs"):
        raise ValueError(f"optimizer must be 'adam' or 'lbfgs', got {optimizer!r}")
    if int(steps) < 1 or int(knots) < 1:
        raise ValueError(f"steps and knots must be positive, got steps={steps}, knots={knots}")
    if not (len(sharpness) == 2 and 1.0 <= sharpness[0] <= sharpness[1]):
        raise ValueError(f"sharpness must be two increasing exponents >= 1, got {sharpness}")
    knots = int(knots)
    start_law = get_law(initial) if isinstance(initial, str) else initial
    start = BSplineLaw.fit(start_law, knots, degree)
    to_coefficients = _acceleration_coordinates(knots, degree)

    def law_of(theta):
        return BSplineLaw(start.coefficients + to_coefficients @ theta, degree)

    def features(theta):
        law = law_of(theta)
        acceleration = law.a(_dense_tau(law)) if caps.max_ca is None else jnp.zeros(())
        return [o.features(law) for o in objectives], caps.features(law), acceleration

    linear = _linearised(features, knots)

    def raw_values(theta, p):
        objective_features, _, acceleration = linear(theta)
        # With a Ca cap, R trains normalised by the cap: the problem stays convex, and the
        # cap bounds the true Ca, so the reported R (divided by the true Ca) is what it is.
        ca = caps.max_ca if caps.max_ca is not None else jnp.max(jnp.abs(acceleration))
        return jnp.stack([o.value(f, ca, p) for o, f in zip(objectives, objective_features)])

    theta0 = jnp.zeros(knots)
    if noise:
        theta0 = noise * jax.random.normal(jax.random.PRNGKey(seed), (knots,))
    scale = np.asarray(jax.jit(raw_values)(theta0, sharpness[0]))
    weights = np.array([o.weight for o in objectives]) / np.maximum(scale, 1e-300)

    def loss(theta, p):
        cap_penalty = caps.penalty_of(linear(theta)[1], margin)
        return jnp.dot(weights, raw_values(theta, p)) + penalty * cap_penalty

    if optimizer == "adam":
        opt = optax.adam(optax.exponential_decay(learning_rate, int(steps), 0.01))
        stages = [np.geomspace(sharpness[0], sharpness[1], int(steps))]
    else:
        # L-BFGS needs one fixed objective per run (its line search caches values and
        # its memory holds curvature): each sharpness stage is a fresh run.
        opt = optax.lbfgs(memory_size=40)
        exponents = _sharpness_stages(sharpness)
        per_stage = math.ceil(int(steps) / len(exponents))
        stages = [np.full(per_stage, p) for p in exponents]
    chunk = min(200, max(len(ps) for ps in stages))

    @jax.jit
    def run_chunk(theta, state, ps):
        def step(carry, p):
            theta, state = carry
            fn = lambda x: loss(x, p)  # noqa: E731
            if optimizer == "adam":
                value, grad = jax.value_and_grad(fn)(theta)
                updates, state = opt.update(grad, state, theta)
            else:
                value, grad = optax.value_and_grad_from_state(fn)(theta, state=state)
                updates, state = opt.update(grad, state, theta, value=value, grad=grad,
                                            value_fn=fn)
            return (optax.apply_updates(theta, updates), state), value

        (theta, state), values = jax.lax.scan(step, (theta, state), ps)
        return theta, state, values

    theta, history = theta0, []
    total = sum(chunk * math.ceil(len(ps) / chunk) for ps in stages)
    with tqdm(total=total, disable=not progress, desc="design", unit="step") as bar:
        for ps in stages:
            # Strongly typed, as run_chunk returns it, so that one compilation serves all.
            state = jax.tree.map(lambda x: jnp.asarray(x, dtype=x.dtype), opt.init(theta))
            ps = np.concatenate([ps, np.full((-len(ps)) % chunk, ps[-1])]).reshape(-1, chunk)
            for i, chunk_ps in enumerate(ps):
                theta, state, values = run_chunk(theta, state, jnp.asarray(chunk_ps))
                values = np.asarray(values)
                history.append(values)
                bar.set_postfix(loss=f"{values[-1]:.4g}", p=f"{chunk_ps[0]:.4g}")
                converged = optimizer == "lbfgs" and values[0] - values[-1] <= 1e-13 * abs(values[-1])
                bar.update(chunk * (len(ps) - i if converged else 1))
                if converged:
                    break
    if not np.all(np.isfinite(np.asarray(theta))):
        raise FloatingPointError("the optimiser produced non-finite coefficients; lower the rate")
    law = law_of(theta)
    final = _restore(law, caps)
    violations = caps.violations(final)
    if any(v > 0 for v in violations.values()):  # pragma: no cover - _restore guarantees it
        raise CapError(f"the design breaks its caps: {_describe(violations)}")
    values = {o.label: o.report(final) for o in objectives}
    return DesignResult(
        law=final,
        objectives=objectives,
        values=values,
        coefficients=dict(zip(("Cv", "Ca", "Cj"), (float(x) for x in _fine_checks(final)[:3]))),
        loss_history=np.concatenate(history),
        restored=final is not law,
        seconds=time.perf_counter() - started,
    )
