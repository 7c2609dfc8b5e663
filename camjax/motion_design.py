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
  little.  Ca*Ct needs the whole response and comes from ``camjax.solve.response_metrics``
  (exact propagation, differentiable).
- A maximum over a band trains as a power mean ``(mean R^p)^(1/p)`` whose exponent grows
  during the run (smooth early, close to the max late) and is reported as the true max
  over 2000 period ratios that are not the training samples.
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
from .models import SpringMass
from .solve import SolveOptions, batch_metrics, default_resolution, response_metrics

EVALUATION_SAMPLES = 2000
"""Period ratios across a band on which reported (true) maxima are taken."""

_GAUSS_ORDER = 12
_MAX_PHASE_PER_PANEL = 2.0  # radians of exp(lambda u) across one quadrature panel


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


def residual_amplitude(law, period_ratios, damping: float = 0.0) -> jax.Array:
    """``R * Ca`` (residual acceleration amplitude in units of h/T^2) at ``period_ratios``.

    ``period_ratios`` must be concrete (NumPy); the law may be traced.
    """
    n = np.atleast_1d(np.asarray(period_ratios, dtype=float))
    nodes, weights = quadrature(law, n.max())
    k = _kernel(n, float(damping), nodes, weights)
    acc = law.a(jnp.asarray(nodes))
    return jnp.abs(jnp.asarray(k.real) @ acc + 1j * (jnp.asarray(k.imag) @ acc))


def dense_peak(law: AbstractMotionLaw, order: int, per_piece: int = 48) -> jax.Array:
    """``max |d^order s|`` over samples of every smooth piece (differentiable, envelope)."""
    edges = _piece_edges(law)
    tau = np.concatenate([np.linspace(lo, hi, per_piece + 1) for lo, hi in zip(edges[:-1], edges[1:])])
    return jnp.max(jnp.abs(law.evaluate(jnp.asarray(tau))[order]))


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

    ``train(law, ca, sharpness)`` is jittable and differentiable (``ca`` is the law's Ca
    as used in training); ``report(law)`` is the figure a user is shown (true maxima on
    ``EVALUATION_SAMPLES`` period ratios, refined Ca).

    Every objective has static fields ``weight`` (its share of the loss) and ``damping``.
    """

    @abc.abstractmethod
    def train(self, law, ca, sharpness):
        """Training value (jittable, differentiable in the law)."""

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

    def train(self, law, ca, sharpness):
        return residual_amplitude(law, [self.period_ratio], self.damping)[0] / ca

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

    def train(self, law, ca, sharpness):
        n = np.linspace(self.n1, self.n2, self.samples)
        return _power_mean(residual_amplitude(law, n, self.damping), sharpness) / ca

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

    def train(self, law, ca, sharpness):
        n, w = self._rule()
        return jnp.dot(w, residual_amplitude(law, n, self.damping)) / ca

    def report(self, law) -> float:
        n, w = self._rule()
        return float(jnp.dot(w, residual(law, n, self.damping)))

    def evaluation_ratios(self):
        return np.linspace(self.mean - 3 * self.std, self.mean + 3 * self.std, EVALUATION_SAMPLES)

    @property
    def label(self):
        return f"E[R], n ~ N({self.mean:g}, {self.std:g}^2)"


def _peak_load(law, n, damping, dwell):
    """Ca*Ct (peak |x''| in units of h/T^2) of the exact path at one period ratio."""
    options = SolveOptions(dwell=dwell, resolution=default_resolution(float(np.max(n))))
    metrics = response_metrics(law, SpringMass(n, damping), options)
    return metrics.ct * law.Ca


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

    def train(self, law, ca, sharpness):
        options = SolveOptions(dwell=self.dwell, resolution=default_resolution(self.period_ratio))
        return response_metrics(law, SpringMass(self.period_ratio, self.damping), options).ct * law.Ca

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

    def train(self, law, ca, sharpness):
        options = SolveOptions(dwell=self.dwell, resolution=default_resolution(self.n2))

        def one(n):
            return response_metrics(law, SpringMass(n, self.damping), options).ct

        ct = jax.vmap(one)(jnp.linspace(self.n1, self.n2, self.samples))
        return _power_mean(ct, sharpness) * law.Ca

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

    def penalty(self, law, margin: float) -> jax.Array:
        """Sum of squared relative violations on a dense grid (zero when inside)."""
        edges = _piece_edges(law)
        tau = jnp.asarray(
            np.concatenate([np.linspace(lo, hi, 17) for lo, hi in zip(edges[:-1], edges[1:])])
        )
        _, v, a, j = law.evaluate(tau)
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
        ca, cj, v_min = (float(x) for x in _fine_checks(law))
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
    """Refined Ca and Cj, and the least velocity on 20001 points (one compiled call)."""
    return law.Ca, law.Cj, jnp.min(law.v(jnp.linspace(0.0, 1.0, 20001)))


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


def design(
    objective,
    *,
    caps: Caps = Caps(),
    knots: int = 24,
    degree: int = 5,
    initial: AbstractMotionLaw | str = "cycloidal",
    optimizer: str = "lbfgs",
    steps: int = 300,
    learning_rate: float = 1e-2,
    sharpness: tuple[float, float] = (8.0, 64.0),
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
        optimizer: ``"lbfgs"`` (optax L-BFGS with zoom line search, at the final
            sharpness) or ``"adam"`` (rate decaying 100-fold).
        steps: optimiser steps.
        sharpness: power-mean exponent of the band maxima at the first and the last step
            (geometric ramp under Adam; L-BFGS uses the last).
        penalty, margin: weight of the cap penalty and the fraction by which training aims
            inside the caps.
        seed, noise: a run is deterministic; with ``noise > 0`` the seed draws a Gaussian
            perturbation of that size (in acceleration coordinates) of the starting point,
            so multi-start is a loop over seeds.  L-BFGS is sensitive to the start on this
            minimax problem: ``noise=0`` (the fitted law) works best in our runs.
    Raises:
        CapError: the result breaks a cap and cannot be repaired.
    """
    started = time.perf_counter()
    objectives = _as_objectives(objective)
    if optimizer not in ("adam", "lbfgs"):
        raise ValueError(f"optimizer must be 'adam' or 'lbfgs', got {optimizer!r}")
    if int(steps) < 1 or int(knots) < 1:
        raise ValueError(f"steps and knots must be positive, got steps={steps}, knots={knots}")
    if not (len(sharpness) == 2 and all(1.0 <= p for p in sharpness)):
        raise ValueError(f"sharpness must be two exponents >= 1, got {sharpness}")
    start_law = get_law(initial) if isinstance(initial, str) else initial
    start = BSplineLaw.fit(start_law, int(knots), degree)
    to_coefficients = _acceleration_coordinates(int(knots), degree)
    key = jax.random.PRNGKey(seed)
    theta0 = jnp.zeros(int(knots)) + noise * jax.random.normal(key, (int(knots),))

    def law_of(theta):
        return BSplineLaw(start.coefficients + to_coefficients @ theta, degree)

    def raw_values(theta, p):
        law = law_of(theta)
        # With a Ca cap, R trains normalised by the cap: the problem stays convex, and the
        # cap bounds the true Ca, so the reported R (divided by the true Ca) is what it is.
        ca = caps.max_ca if caps.max_ca is not None else dense_peak(law, 2)
        return jnp.stack([o.train(law, ca, p) for o in objectives])

    scale = np.asarray(jax.jit(raw_values)(theta0, sharpness[0]))
    weights = np.array([o.weight for o in objectives]) / np.maximum(scale, 1e-300)

    def loss(theta, p):
        return jnp.dot(weights, raw_values(theta, p)) + penalty * caps.penalty(law_of(theta), margin)

    total = int(steps)
    chunk = max(1, min(100, total))
    ramp = np.geomspace(sharpness[0], sharpness[1], total)
    if optimizer == "adam":
        schedule = optax.exponential_decay(learning_rate, total, 0.01)
        opt = optax.adam(schedule)
    else:
        # L-BFGS needs one fixed objective (its line search caches values and its
        # memory holds curvature): it runs at the final sharpness throughout.
        opt = optax.lbfgs()
        ramp = np.full(total, sharpness[1])

    @jax.jit
    def run_chunk(theta, state, ps):
        def step(carry, p):
            theta, state = carry
            if optimizer == "adam":
                value, grad = jax.value_and_grad(loss)(theta, p)
                updates, state = opt.update(grad, state, theta)
            else:
                fn = lambda x: loss(x, p)  # noqa: E731
                value, grad = optax.value_and_grad_from_state(fn)(theta, state=state)
                updates, state = opt.update(grad, state, theta, value=value, grad=grad,
                                            value_fn=fn)
            return (optax.apply_updates(theta, updates), state), value

        (theta, state), values = jax.lax.scan(step, (theta, state), ps)
        return theta, state, values

    theta, state = theta0, opt.init(theta0)
    history = []
    pad = (-total) % chunk
    ps_all = np.concatenate([ramp, np.full(pad, ramp[-1])]).reshape(-1, chunk)
    with tqdm(total=total, disable=not progress, desc="design", unit="step") as bar:
        for i, ps in enumerate(ps_all):
            theta, state, values = run_chunk(theta, state, jnp.asarray(ps))
            keep = chunk - pad if i == len(ps_all) - 1 else chunk
            history.append(np.asarray(values)[:keep])
            bar.update(keep)
            bar.set_postfix(loss=f"{float(values[keep - 1]):.4g}")
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
        coefficients=final.peak_coefficients(),
        loss_history=np.concatenate(history),
        restored=final is not law,
        seconds=time.perf_counter() - started,
    )
