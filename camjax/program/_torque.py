"""The drive torque a cam asks of its shaft, and the energy its flywheel must store.

Frictionless power balance: the cam's power ``T Omega`` is the contact force's power on the
follower, ``F_c`` along the follower's path times the path's speed, so ``T = F_c dy/dtheta``
for a translating follower and, with the lift the arc length at ``arm_mm`` (the force
referred to that radius), for a swinging one too (the arm's moment ``F_c arm`` times the
swing rate ``dy/dtheta / arm``).  In turn time ``s`` (``theta = 2 pi s``)
``T = 1e-3 F_c y_s / (2 pi)`` N m with ``y_s`` in mm per turn; its derivatives at both ends
of every interval follow from the force's and the lift's one-sided ones, so the torque has
the same septic Hermite interpolant per interval as the refined peaks
(``camjax.metrics.septic_coefficients``), which is integrated exactly.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from .._plain import DEFAULT_SPEED_FLUCTUATION as DEFAULT_SPEED_FLUCTUATION
from ..metrics import bounded_extremes, bounded_peak, septic_coefficients

TORQUE_PER_FORCE_VELOCITY = 1e-3 / (2 * math.pi)
"""N m of drive torque per N of contact force and mm per turn of lift velocity."""
_HILBERT = 1.0 / (np.arange(8)[:, None] + np.arange(8)[None, :] + 1.0)


def torque_jets(force, force_left, force_right, velocity, lift_left, lift_right):
    """Drive torque (N m) at the nodes and its first three derivatives in turn time at both
    ends of every interval, from the contact force's (``gain_derivatives``) and the lift's
    (``y_s`` at the nodes, ``(y_ss, y_sss, y_ssss)`` one-sided, ``MotionGrid.one_sided``)."""

    def ends(f, df, ys, dy):
        d1 = df[:, 0] * ys + f * dy[:, 0]
        d2 = df[:, 1] * ys + 2 * df[:, 0] * dy[:, 0] + f * dy[:, 1]
        d3 = df[:, 2] * ys + 3 * df[:, 1] * dy[:, 0] + 3 * df[:, 0] * dy[:, 1] + f * dy[:, 2]
        return TORQUE_PER_FORCE_VELOCITY * jnp.stack([d1, d2, d3], axis=1)

    values = TORQUE_PER_FORCE_VELOCITY * force * velocity
    return (values, ends(force[:-1], force_left, velocity[:-1], lift_left),
            ends(force[1:], force_right, velocity[1:], lift_right))


class TorqueFigures(NamedTuple):
    """Peak ``|T|``, RMS and mean torque (N m) over a turn and the energy fluctuation (J)."""

    max_abs: float
    rms: float
    mean: float
    energy_fluctuation: float


def torque_figures(values, widths, left, right) -> TorqueFigures:
    """The figures of a torque sampled over one turn (``sum(widths) == 1``), jittable.

    Mean and RMS integrate the septic interpolant exactly; ``W(s) = 2 pi int (T - mean) ds``
    is its running integral at the nodes, with ``W' = T - mean``, ``W'' = T'``, ``W''' = T''``
    at both ends of every interval.  ``max |T|``, ``max W`` and ``min W`` are refined between
    nodes by the bounded search (``camjax.metrics.bounded_peak``): only the intervals that can
    hold them (refining every interval of the three signals was most of a cam turn's cost).
    """
    c = septic_coefficients(values, widths, left, right)
    integrals = widths * (c @ jnp.asarray(1.0 / np.arange(1, 9)))
    mean = jnp.sum(integrals)
    rms = jnp.sqrt(jnp.maximum(jnp.sum(widths * jnp.einsum("ki,ij,kj->k", c, jnp.asarray(_HILBERT), c)), 0.0))
    work = jnp.concatenate([jnp.zeros(1), jnp.cumsum(integrals - mean * widths)])

    def work_ends(t, d):
        return jnp.stack([t - mean, d[:, 0], d[:, 1]], axis=1)

    low, high = bounded_extremes(work, widths, work_ends(values[:-1], left), work_ends(values[1:], right))
    return TorqueFigures(bounded_peak(values, widths, left, right), rms, mean, 2 * math.pi * (high - low))


def flywheel_inertia_kg_m2(energy_fluctuation_j, rpm, speed_fluctuation: float):
    """``J = dE / (Cs Omega^2)``: the inertia that keeps the speed within ``Cs`` of its mean."""
    omega = 2 * math.pi * np.asarray(rpm) / 60.0
    return np.asarray(energy_fluctuation_j) / (speed_fluctuation * omega**2)


def check_speed_fluctuation(value, what: str = "speed_fluctuation") -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < value < 2 or not math.isfinite(value):
        raise ValueError(f"{what} must be a number in (0, 2), got {value!r}")
    return float(value)


# -- the cam's geometry for the contact ---------------------------------------------------------
