"""Batched sweeps: Ct and residual curves over many period ratios in one compiled call."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .laws import AbstractMotionLaw
from .models._spring_mass import check_damping, check_period_ratios
from .propagation._response import SolveOptions, batch_metrics, raise_on_failure
from .sharding import law_batch_metrics, shard_batch


class CtCurve(eqx.Module):
    """Ct, residual and peak-in-motion of one law over a set of period ratios.

    All values are in units of the law's Ca (multiply by ``ca`` for units of h/T^2).
    """

    period_ratio: np.ndarray
    ct: np.ndarray
    residual: np.ndarray
    peak_in_motion: np.ndarray
    ca: float
    name: str = eqx.field(static=True)
    damping: float = eqx.field(static=True, default=0.0)
    method: str = eqx.field(static=True, default="exact")

    @property
    def ca_ct(self) -> np.ndarray:
        """Peak inertia load ``Ca * Ct`` in units of h/T^2 (the figure to compare laws by)."""
        return self.ca * self.ct


def _options(period_ratios, damping, method, dwell, resolution, solver_options):
    n = check_period_ratios(period_ratios)
    zeta = check_damping(damping)
    options = SolveOptions(method, dwell, resolution, **solver_options).checked(float(n.max()))
    return n, zeta, options


def _curve(law, n, zeta, options, metrics) -> CtCurve:
    return CtCurve(
        period_ratio=n,
        ct=np.asarray(metrics.ct),
        residual=np.asarray(metrics.residual),
        peak_in_motion=np.asarray(metrics.peak_in_motion),
        ca=float(law.Ca),
        name=law.name,
        damping=zeta,
        method=options.method,
    )


def ct_curve(
    law: AbstractMotionLaw,
    period_ratios,
    *,
    damping: float = 0.0,
    method: str = "exact",
    dwell: float = 1.0,
    resolution: int | None = None,
    devices=None,
    **solver_options,
) -> CtCurve:
    """Ct, residual vibration and peak in motion of ``law`` at every period ratio.

    One compiled, vmapped call covers the whole batch.  ``method`` is ``"exact"`` (closed-
    form propagation, the default) or a diffrax solver name; ``solver_options`` go to
    :class:`camjax.propagation.SolveOptions` (``rtol``, ``atol``, ``steps``, ``max_steps``,
    ``use_jump_ts``).  Raises ``ValueError`` for bad input and ``SolverError`` if the
    solver fails at any period ratio.  The ratios are split over ``devices`` (default:
    every local device; see :func:`camjax.sharding.shard_batch`).
    """
    n, zeta, options = _options(period_ratios, damping, method, dwell, resolution, solver_options)
    metrics, result, _ = shard_batch(batch_metrics, law, jnp.asarray(n), zeta, options,
                                     batched_argnums=1, devices=devices)
    raise_on_failure(result, (metrics.ct, metrics.residual), n, options.method)
    return _curve(law, n, zeta, options, metrics)


def ct_curves(
    laws: Iterable[AbstractMotionLaw] | Mapping[str, AbstractMotionLaw],
    period_ratios,
    *,
    damping: float = 0.0,
    method: str = "exact",
    dwell: float = 1.0,
    resolution: int | None = None,
    devices=None,
    **solver_options,
) -> dict[str, CtCurve]:
    """:func:`ct_curve` for several laws, keyed by name (or by the mapping's keys).

    Laws of the same type (for example several ``SCCA`` or ``BSplineLaw`` of one size)
    are stacked and mapped together, so a family of laws costs one compiled call; the
    stack is split over ``devices`` (default: every local device).
    """
    named = dict(laws) if isinstance(laws, Mapping) else {law.name: law for law in laws}
    n, zeta, options = _options(period_ratios, damping, method, dwell, resolution, solver_options)
    groups: dict = {}
    for key, law in named.items():
        groups.setdefault(jax.tree.structure(law), []).append(key)
    curves = {}
    for keys in groups.values():
        members = [named[k] for k in keys]
        if len(members) == 1 or not jax.tree.leaves(members[0]):
            batch = [shard_batch(batch_metrics, m, jnp.asarray(n), zeta, options,
                                 batched_argnums=1, devices=devices) for m in members]
        else:
            stacked = jax.tree.map(lambda *x: jnp.stack(x), *members)
            out = law_batch_metrics(stacked, jnp.asarray(n), zeta, options, devices=devices)
            batch = [jax.tree.map(lambda x, i=i: x[i], out) for i in range(len(members))]
        for key, law, (metrics, result, _) in zip(keys, members, batch):
            raise_on_failure(result, (metrics.ct, metrics.residual), n, options.method)
            curves[key] = _curve(law, n, zeta, options, metrics)
    return {key: curves[key] for key in named}
