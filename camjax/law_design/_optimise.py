"""The optimisation loop: linear feature maps, L-BFGS or Adam in stages, repair."""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Mapping

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax
from tqdm.auto import tqdm

from .. import checks
from ..laws import AbstractMotionLaw, BoundaryPolynomial, BSplineLaw, CorrectedPolynomial, as_law
from ._caps import CapError, Caps, _describe, _fine_checks
from ._objectives import AbstractObjective
from ._residual import dense_tau

DEFAULT_STEPS = 6000
"""Optimiser steps of a design (L-BFGS: 1000 per sharpness stage; a stage that has
converged hands over early)."""
MAX_STEPS = 1_000_000
"""Most optimiser steps a design takes: its history is kept in memory (more is refused
before any work)."""
MAX_KNOTS = 200
"""Most free B-spline coefficients of a design: its linearised features hold one column
per coefficient and its grid a piece per knot, so memory grows with the square (1000
knots took 6 GB); more is refused before any work."""


class DesignNotImproved(UserWarning):
    """A design that ended no better than the law it started from, which it returns instead."""


class DesignResult(eqx.Module):
    """A designed law with its reported objective values and training history.

    ``initial_values`` are the same reports of the law the design started from;
    ``kept_initial`` is true where the design did not improve on it and that law is
    returned instead (with a ``DesignNotImproved`` warning).
    """

    law: BSplineLaw
    objectives: tuple[AbstractObjective, ...] = eqx.field(static=True)
    values: dict = eqx.field(static=True)
    coefficients: dict = eqx.field(static=True)
    loss_history: np.ndarray
    restored: bool = eqx.field(static=True)
    seconds: float = eqx.field(static=True)
    initial_values: dict = eqx.field(static=True, default=None)
    kept_initial: bool = eqx.field(static=True, default=False)


def _acceleration_coordinates(knots: int, degree: int, fixed: int = 3) -> jax.Array:
    """Matrix ``M`` such that a step ``theta`` in the coefficients ``M theta`` moves the
    acceleration's control points by ``U theta`` with ``U`` orthonormal.

    The map from free coefficients to acceleration control points is a second difference
    scaled by the squared knot count: badly conditioned (its singular values span two or
    more decades).  Optimising in these coordinates makes every direction equally stiff,
    which first-order methods need.
    """
    from ..laws import BSplineLaw

    n_basis = knots + 2 * fixed
    second = BSplineLaw.derivative_map(n_basis, degree, 2)[:, fixed:-fixed]
    _, singular, vt = np.linalg.svd(second, full_matrices=False)
    return jnp.asarray(vt.T / singular)


def _restore_corrected(law: CorrectedPolynomial, caps: Caps) -> CorrectedPolynomial:
    """The nearest point towards the base polynomial (no correction) that meets the caps."""
    if caps.met(law):
        return law

    def blend(t):
        return CorrectedPolynomial(law.base, (1 - t) * law.coefficients, law.spline_degree)

    if not caps.met(blend(1.0)):
        raise CapError(f"the design breaks its caps ({_describe(caps.violations(law))}) and so does "
                       f"its boundary polynomial ({_describe(caps.violations(blend(1.0)))}); relax the caps")
    lo, hi = 0.0, 1.0
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if caps.met(blend(mid)) else (mid, hi)
    return blend(hi)


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


class _Constant:
    """A pytree compiled in as constants (a static argument of the compiled steps), equal to
    another of the same structure and values: a boundary polynomial's end states stay
    concrete inside the trace (a program objective checks its joins with them)."""

    def __init__(self, value):
        self.value = value
        leaves, tree = jax.tree.flatten(value)
        self._key = (tree, tuple((np.shape(x), np.asarray(x).tobytes()) for x in leaves))

    def __hash__(self):
        return hash(self._key)

    def __eq__(self, other):
        return isinstance(other, _Constant) and self._key == other._key


class _LawMap(eqx.Module):
    """The designed law of a step ``theta`` in acceleration coordinates: a B-spline
    (``base`` None) or a boundary polynomial with a B-spline correction."""

    start: jax.Array
    to_coefficients: jax.Array
    degree: int = eqx.field(static=True)
    base: _Constant | None = eqx.field(static=True, default=None)

    def __call__(self, theta):
        coefficients = self.start + self.to_coefficients @ theta
        if self.base is None:
            return BSplineLaw(coefficients, self.degree)
        return CorrectedPolynomial(self.base.value, coefficients, self.degree)


def _design_features(law_map: _LawMap, objectives, caps: Caps, theta):
    """The objectives' features, the caps' features and (without a Ca cap) the dense
    acceleration of the law at ``theta``: all affine in ``theta``."""
    # The optimiser's own coefficients: no runtime checks (host callbacks) in its
    # programs; a step gone NaN is the optimiser's failure, caught where it reports.
    with checks.checked_outside():
        law = law_map(theta)
        acceleration = law.a(dense_tau(law)) if caps.max_ca is None else jnp.zeros(())
        return [o.features(law) for o in objectives], caps.features(law), acceleration


@eqx.filter_jit
def _design_maps(law_map: _LawMap, objectives, caps: Caps, zero):
    """``linear_maps`` of ``_design_features``, compiled once per shape of the design (the
    law map, objectives and caps are arguments, not closures)."""
    offset, tangent = jax.linearize(lambda theta: _design_features(law_map, objectives, caps, theta), zero)
    return offset, jax.vmap(tangent, out_axes=-1)(jnp.eye(zero.size))


class _Problem(eqx.Module):
    """A design's training loss: its linear features (``offset + jacobian @ theta``), the
    objectives' weights and the caps' penalty.  An argument of the compiled steps, so a
    design of the same shape compiles nothing."""

    offset: list
    jacobian: list
    weights: jax.Array
    penalty: jax.Array
    margin: jax.Array
    objectives: tuple
    caps: Caps

    def raw_values(self, theta, p):
        objective_features, _, acceleration = self.features(theta)
        # With a Ca cap, R trains normalised by the cap: the problem stays convex, and the
        # cap bounds the true Ca, so the reported R (divided by the true Ca) is what it is.
        ca = self.caps.max_ca if self.caps.max_ca is not None else jnp.max(jnp.abs(acceleration))
        return jnp.stack([o.value(f, ca, p) for o, f in zip(self.objectives, objective_features)])

    def features(self, theta):
        return jax.tree.map(lambda b, m: b + m @ theta, self.offset, self.jacobian)

    def loss(self, theta, p):
        cap_penalty = self.caps.penalty_of(self.features(theta)[1], self.margin)
        return jnp.dot(self.weights, self.raw_values(theta, p)) + self.penalty * cap_penalty


@eqx.filter_jit
def _raw_values(problem: _Problem, theta, p):
    return problem.raw_values(theta, p)


@eqx.filter_jit
def _run_chunk(problem: _Problem, optimizer, line_search: bool, theta, state, ps, rates):
    """``len(ps)`` optimiser steps at sharpness ``ps``, each update scaled by ``rates``
    (ones for a transformation with its own rate): one program per shape of the design and
    optimiser, compiled once in a process."""

    def step(carry, xs):
        theta, state = carry
        p, rate = xs
        fn = lambda x: problem.loss(x, p)  # noqa: E731
        if line_search:
            value, grad = optax.value_and_grad_from_state(fn)(theta, state=state)
            updates, state = optimizer.update(grad, state, theta, value=value, grad=grad, value_fn=fn)
        else:
            value, grad = jax.value_and_grad(fn)(theta)
            updates, state = optimizer.update(grad, state, theta)
            updates = jax.tree.map(lambda u: rate * u, updates)
        return (optax.apply_updates(theta, updates), state), value

    (theta, state), values = jax.lax.scan(step, (theta, state), (ps, rates))
    return theta, state, values


_LBFGS = optax.lbfgs(memory_size=40)
"""``optimizer="lbfgs"``: one transformation for every design (a new one would compile again)."""
_ADAM_DIRECTION = optax.scale_by_adam()
"""``optimizer="adam"``: Adam's direction; its decaying rate is passed per step (``rates``)."""


def design(
    objective,
    *,
    caps: Caps | None = None,
    knots: int = 24,
    degree: int = 5,
    initial: AbstractMotionLaw | str = "cycloidal",
    optimizer: str | optax.GradientTransformation = "lbfgs",
    steps: int = DEFAULT_STEPS,
    learning_rate: float = 1e-2,
    sharpness: tuple[float, float] = (8.0, 8192.0),
    penalty: float = 1e4,
    margin: float = 1e-3,
    seed: int = 0,
    noise: float = 0.0,
    progress: bool | Callable[[int, int, float], None] = True,
    sweep_options: Mapping | None = None,
) -> DesignResult:
    """Design a B-spline rise minimising ``sum(weight * objective)`` under ``caps``.

    Args:
        objective: one objective or a sequence (weights are their ``weight`` fields; each
            is divided by its value at the starting law so weights are relative).
        caps: ``Caps(max_ca, max_jerk, monotone=True)``, met by the result on a fine grid
            (default ``Caps()``: a monotone rise, no caps on Ca and Cj).
        knots: free B-spline coefficients (the boundary conditions fix three more at
            each end).
        initial: the law (or its name) fitted as the starting point.  A
            ``BoundaryPolynomial`` (or ``CorrectedPolynomial``) starts the design in the
            ``CorrectedPolynomial`` family instead: the polynomial plus a B-spline
            correction of ``knots`` coefficients, so the design keeps its end states.
        optimizer: ``"lbfgs"`` (optax L-BFGS with zoom line search, restarted at each
            sharpness stage), ``"adam"`` (rate decaying 100-fold, sharpness ramped
            geometrically over the run) or an optax ``GradientTransformation`` (its own
            rate; run in sharpness stages like L-BFGS where its state keeps a line
            search's ``value``, else ramped like Adam).  The compiled steps are shared by
            every design of one shape in a process: pass the same transformation object
            again to reuse them.
        steps: optimiser steps in all; L-BFGS splits them evenly over the stages (rounded
            up to whole chunks of at most 200) and moves to the next stage early once a
            stage has converged.
        sharpness: power-mean exponent of maxima at the first and the last stage; L-BFGS
            stages grow it about fourfold each.
        penalty: weight of the cap penalty.
        margin: the fraction by which training aims inside the caps.
        seed: a run is deterministic; with ``noise > 0`` the seed draws the perturbation
            of the starting point, so multi-start is a loop over seeds.
        noise: size of a Gaussian perturbation of the starting point (in acceleration
            coordinates); 0 starts from ``initial`` itself.
        progress: a progress bar on the terminal, none (``False``), or a function called
            after each compiled chunk of steps as ``progress(step, total, loss)`` (steps
            done and in all, counting a converged stage's rest as done; the training loss)
            in place of the bar, for a caller that shows progress its own way.
        sweep_options: static options of the exact-path sweeps that report the objectives
            (``camjax.ct_curve``'s, such as ``peak_search`` or ``sweep``): how they
            compile, not what they report.
    Raises:
        CapError: the result breaks a cap and cannot be repaired.
    """
    started = time.perf_counter()
    caps = Caps() if caps is None else caps
    objectives = _as_objectives(objective)
    if not (optimizer in ("adam", "lbfgs") or isinstance(optimizer, optax.GradientTransformation)):
        raise ValueError(f"optimizer must be 'adam', 'lbfgs' or an optax GradientTransformation, "
                         f"got {optimizer!r}")
    if not 1 <= int(steps) <= MAX_STEPS:
        raise ValueError(f"steps must be from 1 to {MAX_STEPS:,}, got {steps}")
    if not 1 <= int(knots) <= MAX_KNOTS:
        raise ValueError(f"knots must be from 1 to {MAX_KNOTS} (free coefficients of the "
                         f"designed spline), got {knots}")
    if not (len(sharpness) == 2 and 1.0 <= sharpness[0] <= sharpness[1]):
        raise ValueError(f"sharpness must be two increasing exponents >= 1, got {sharpness}")
    knots = int(knots)
    start_law = as_law(initial, "initial")
    if isinstance(start_law, BoundaryPolynomial | CorrectedPolynomial):
        base = start_law if isinstance(start_law, BoundaryPolynomial) else start_law.base
        same_size = (isinstance(start_law, CorrectedPolynomial) and start_law.spline_degree == degree
                     and len(start_law.coefficients) == knots)
        start_coefficients = start_law.coefficients if same_size else jnp.zeros(knots)
        law_of = _LawMap(jnp.asarray(start_coefficients),
                         _acceleration_coordinates(knots, degree, 4 if base.degree == 7 else 3), degree,
                         _Constant(base))
    else:
        start = BSplineLaw.fit(start_law, knots, degree)
        law_of = _LawMap(jnp.asarray(start.coefficients), _acceleration_coordinates(knots, degree), degree)

    offset, jacobian = _design_maps(law_of, objectives, caps, jnp.zeros(knots))
    problem = _Problem(offset, jacobian, jnp.ones(len(objectives)), jnp.asarray(float(penalty)),
                       jnp.asarray(float(margin)), objectives, caps)

    theta0 = jnp.zeros(knots)
    if noise:
        theta0 = noise * jax.random.normal(jax.random.PRNGKey(seed), (knots,))
    scale = np.asarray(_raw_values(problem, theta0, jnp.asarray(float(sharpness[0]))))
    # |value|: an objective may be signed (a required preload can be negative, a margin).
    weights = np.array([o.weight for o in objectives]) / np.maximum(np.abs(scale), 1e-300)
    problem = eqx.tree_at(lambda pr: pr.weights, problem, jnp.asarray(weights))

    if optimizer == "adam":
        opt, line_search = _ADAM_DIRECTION, False
    elif optimizer == "lbfgs":
        opt, line_search = _LBFGS, True
    else:
        opt = optimizer
        line_search = optax.tree_utils.tree_get(opt.init(theta0), "value", None) is not None
    if line_search:
        # L-BFGS needs one fixed objective per run (its line search caches values and
        # its memory holds curvature): each sharpness stage is a fresh run.
        exponents = _sharpness_stages(sharpness)
        per_stage = math.ceil(int(steps) / len(exponents))
        stages = [np.full(per_stage, p) for p in exponents]
    else:
        stages = [np.geomspace(sharpness[0], sharpness[1], int(steps))]
    chunk = min(200, max(len(ps) for ps in stages))

    theta, history, done = theta0, [], 0
    total = sum(chunk * math.ceil(len(ps) / chunk) for ps in stages)
    report = progress if callable(progress) else None
    with tqdm(total=total, disable=report is not None or not progress, desc="design", unit="step") as bar:
        for ps in stages:
            # Strongly typed, as _run_chunk returns it, so that one compilation serves all.
            state = jax.tree.map(lambda x: jnp.asarray(x, dtype=x.dtype), opt.init(theta))
            ps = np.concatenate([ps, np.full((-len(ps)) % chunk, ps[-1])]).reshape(-1, chunk)
            if optimizer == "adam":  # optax.adam's exponential decay, step by step
                rates = -learning_rate * 0.01 ** (np.arange(ps.size) / int(steps))
            else:
                rates = np.ones(ps.size)
            rates = rates.reshape(ps.shape)
            for i, chunk_ps in enumerate(ps):
                theta, state, values = _run_chunk(problem, opt, line_search, theta, state, jnp.asarray(chunk_ps),
                                                  jnp.asarray(rates[i]))
                values = np.asarray(values)
                history.append(values)
                bar.set_postfix(loss=f"{values[-1]:.4g}", p=f"{chunk_ps[0]:.4g}")
                converged = line_search and values[0] - values[-1] <= 1e-13 * abs(values[-1])
                advance = chunk * (len(ps) - i if converged else 1)
                bar.update(advance)
                done += advance
                if report is not None:
                    report(done, total, float(values[-1]))
                if converged:
                    break
        if not np.all(np.isfinite(np.asarray(theta))):
            raise FloatingPointError("the optimiser produced non-finite coefficients; lower the rate")
        # What follows the optimiser still takes seconds (fine-grid checks, a possible
        # repair, the reported values): the bar stays up and says which.
        bar.set_postfix_str("checking the caps on a fine grid")
        law = law_of(theta)
        final = _restore_corrected(law, caps) if isinstance(law, CorrectedPolynomial) else caps.repair(law)
        violations = caps.violations(final)
        if any(v > 0 for v in violations.values()):  # pragma: no cover - Caps.repair guarantees it
            raise CapError(f"the design breaks its caps: {_describe(violations)}")
        bar.set_postfix_str("reporting the objectives")
        sweep_options = dict(sweep_options or {})
        values = {o.label: o.report(final, **sweep_options) for o in objectives}
        start = law_of(jnp.zeros(knots))
        initial_values = {o.label: o.report(start, **sweep_options) for o in objectives}
        kept = not _improved(objectives, values, initial_values) and caps.met(start)
        if kept:
            warnings.warn("the design did not improve on the law it started from ("
                          + "; ".join(f"{k}: {values[k]:.6g} designed against {initial_values[k]:.6g}"
                                      for k in values) + "); that law is returned",
                          DesignNotImproved, stacklevel=2)
            final, values = start, dict(initial_values)
        coefficients = dict(zip(("Cv", "Ca", "Cj"), (float(x) for x in _fine_checks(final)[:3])))
        bar.set_postfix_str("done")
    return DesignResult(
        law=final,
        objectives=objectives,
        values=values,
        coefficients=coefficients,
        loss_history=np.concatenate(history),
        restored=not kept and final is not law,
        seconds=time.perf_counter() - started,
        initial_values=initial_values,
        kept_initial=kept,
    )


def _improved(objectives, values: dict, initial: dict) -> bool:
    """Whether the weighted sum of the reports, each relative to its start, went down."""
    def score(v):
        return sum(o.weight * v[o.label] / max(abs(initial[o.label]), 1e-300) for o in objectives)
    return score(values) < score(initial)
