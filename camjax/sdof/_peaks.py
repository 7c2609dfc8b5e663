"""What a designer reads off the complex mode: accelerations, forces, their refined peaks
and the residual vibration.

Any linear output of the SDOF's state is ``Re(G q)`` for a complex gain ``G`` (the payload
acceleration ``x''``, a spring-train force ``k e + c e'``, the deflection ``e``); its time
derivatives follow from ``q' = lambda q + a`` with one-sided forcing, which is what the
Hermite peak refinement (``camjax.metrics.refined_peak``) needs at every interval's ends.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from ..metrics import interval_peaks, interval_septics, refined_peak
from ._grid import INTERPOLATION_DEGREE, MotionGrid
from ._step import eigenvalue


def mode_gain(omega, zeta):
    """``K`` with ``x'' = Re(K q)`` (payload acceleration from the complex mode)."""
    damped = omega * jnp.sqrt(1.0 - zeta**2)
    return 2 * zeta * omega - 1j * omega**2 * (1 - 2 * zeta**2) / damped


def deflection_gains(omega, zeta):
    """``(G_e, G_e')`` with ``e = Re(G_e q)`` and ``e' = Re(G_e' q)``."""
    lam = eigenvalue(omega, zeta)
    return -1j / jnp.imag(lam), 1.0 - 1j * jnp.real(lam) / jnp.imag(lam)


def gain_derivatives(gain, lam, q, one_sided):
    """First three time derivatives of ``Re(gain q)`` at nodes with mode ``q`` (``(K,)``),
    from one-sided forcing ``(a, a', a'')`` (``(K, 3)``, ``MotionGrid.one_sided``)."""
    d1 = lam * q + one_sided[:, 0]
    d2 = lam * d1 + one_sided[:, 1]
    d3 = lam * d2 + one_sided[:, 2]
    return jnp.real(gain * jnp.stack([d1, d2, d3], axis=1))


def output_jets(gain, q, grid: MotionGrid, omega, zeta):
    """``Re(gain q)`` at the nodes and its derivatives at both ends of every interval
    (``(values, left, right)``, the arguments of ``refined_peak`` after the widths)."""
    lam = eigenvalue(omega, zeta)
    left, right = grid.one_sided()
    return (jnp.real(gain * q), gain_derivatives(gain, lam, q[:-1], left),
            gain_derivatives(gain, lam, q[1:], right))


PEAK_CANDIDATES = 16
"""Intervals that ``bounded_peak_in_motion`` refines; when more than these can hold the
peak, the dense search runs instead (``peak_in_motion``)."""

_FALLING = np.array([[math.perm(m, j) for j in range(4)]
                     for m in range(INTERPOLATION_DEGREE + 1)], dtype=float)


def _cubic_extent(c0, c1, c2, c3):
    """``max |c0 + c1 u + c2 u^2 + c3 u^3|`` over ``u`` in ``[0, 1/2]``, exactly: at the
    ends and the critical points inside (any other point tried is harmless)."""
    a, b = 3 * c3, 2 * c2
    root = jnp.sqrt(jnp.maximum(b * b - 4 * a * c1, 0.0))
    stable = -0.5 * (b + jnp.where(b >= 0, root, -root))
    points = [jnp.zeros_like(c0), jnp.full_like(c0, 0.5)]
    for num, den in ((stable, a), (c1, stable)):
        u = jnp.where(den != 0, num / jnp.where(den != 0, den, 1.0), 0.0)
        points.append(jnp.clip(jnp.where(jnp.isfinite(u), u, 0.0), 0.0, 0.5))
    return jnp.max(jnp.stack([jnp.abs(c0 + u * (c1 + u * (c2 + u * c3))) for u in points]), axis=0)


def peak_bounds(gain, q, grid: MotionGrid, omega, zeta):
    """``(lower, upper)`` bounds of ``max |Re(gain q)|`` over every interval (``(K,)`` each).

    Each half of an interval is its cubic Taylor polynomial from the nearer end (extremes
    found exactly) within ``M4 (h/2)^4 / 24``, ``M4`` bounding the fourth derivative from
    the ODE: ``q4 = lambda^4 q + lambda^3 a + lambda^2 a1 + lambda a2 + a3`` (``aj`` the
    forcing's derivatives) with ``|lambda| = w``, ``|q(t)| <= |q_k| + h max|a|``
    (``zeta >= 0``) and ``h^j max|aj|`` bounded by the interpolant's coefficients.
    Rigorous up to rounding (a relative 1e-12 is added to the slack).  Every array is one
    value per interval (no ``(K, 3)`` stacks: this runs on every interval of every ratio).
    """
    lam = eigenvalue(omega, zeta)
    h = grid.widths
    wh = omega * h
    forcing_bounds = jnp.abs(grid.forcing) @ _FALLING  # (K, 4): h^j max|a^(j)|
    one_left, one_right = grid.one_sided()
    # Scaled derivatives h^j f^(j) / j! at both ends, the right end's read backwards.
    lam_h = lam * h
    ends = []
    for nodes, forcing, sign in ((q[:-1], one_left, 1.0), (q[1:], one_right, -1.0)):
        d1 = lam_h * nodes + h * forcing[:, 0]
        d2 = lam_h * d1 + h**2 * forcing[:, 1]
        d3 = lam_h * d2 + h**3 * forcing[:, 2]
        coefficients = [jnp.real(gain * nodes), sign * jnp.real(gain * d1),
                        jnp.real(gain * d2) / 2, sign * jnp.real(gain * d3) / 6]
        ends.append(_cubic_extent(*coefficients))
    extent = jnp.maximum(*ends)
    left_q = q[:-1]
    amplitude = jnp.sqrt(jnp.real(left_q) ** 2 + jnp.imag(left_q) ** 2) + h * forcing_bounds[:, 0]
    fourth = wh**4 * amplitude + h * (wh**3 * forcing_bounds[:, 0] + wh**2 * forcing_bounds[:, 1]
                                      + wh * forcing_bounds[:, 2] + forcing_bounds[:, 3])
    slack = jnp.abs(gain) * fourth / (24 * 16) + 1e-12 * extent
    return extent - slack, extent + slack


def bounded_peak_in_motion(q, grid: MotionGrid, omega, zeta, count: int = PEAK_CANDIDATES):
    """Max ``|x''|`` over the grid's span refining only the intervals that can hold it, and
    whether more than ``count`` can: ``(peak, overflow)`` (on overflow, use
    ``dense_peak_in_motion``).

    ``peak_bounds`` gives every interval an upper and a lower bound; an interval whose upper
    bound is below the best lower bound cannot hold the peak.  Up to ``count`` of those
    that can are refined as ``refined_peak`` refines every one, so without overflow the
    peak is the dense search's.
    """
    gain = mode_gain(omega, zeta)
    lower, upper = jax.lax.stop_gradient(peak_bounds(gain, q, grid, omega, zeta))
    count = min(count, upper.shape[0])
    qualify = upper >= jnp.max(lower)
    overflow = jnp.sum(qualify) > count
    chosen = jnp.nonzero(qualify, size=count, fill_value=jnp.argmax(upper))[0]
    lam = eigenvalue(omega, zeta)
    q_start, q_end = q[chosen], q[chosen + 1]
    one_left, one_right = grid.one_sided()
    peaks = interval_peaks(interval_septics(
        jnp.real(gain * q_start), jnp.real(gain * q_end), grid.widths[chosen],
        gain_derivatives(gain, lam, q_start, one_left[chosen]),
        gain_derivatives(gain, lam, q_end, one_right[chosen])))
    return jnp.max(peaks), overflow


def dense_peak_in_motion(q, grid: MotionGrid, omega, zeta):
    """Max ``|x''|`` over the grid's span, every interval refined (``refined_peak``)."""
    values, left, right = output_jets(mode_gain(omega, zeta), q, grid, omega, zeta)
    return refined_peak(values, grid.widths, left, right)


def peak_in_motion(q, grid: MotionGrid, omega, zeta):
    """Max ``|x''|`` over the grid's span: ``x'' = Re(K q)`` at the nodes, refined between
    (the candidates of ``bounded_peak_in_motion``, every interval when they overflow)."""
    peak, overflow = bounded_peak_in_motion(q, grid, omega, zeta)
    return jax.lax.cond(overflow, lambda: dense_peak_in_motion(q, grid, omega, zeta),
                        lambda: peak)


def refined_max(values, widths, left, right):
    """``max f`` (signed) of a sampled continuous signal, refined between samples: the
    signed counterpart of ``refined_peak`` (shifted so that ``|f - shift| = f - shift``)."""
    low = jnp.min(values)
    shift = low - (jnp.max(values) - low) - 1.0
    return refined_peak(values - shift, widths, left, right) + shift


def refined_extremes(values, widths, left, right):
    """``(min f, max f)`` of a sampled continuous signal, refined between samples."""
    high = refined_max(values, widths, left, right)
    low = -refined_max(-values, widths, -left, -right)
    return low, high


def dwell_peak(q_end, omega, zeta, dwell: float):
    """Max |x''| over the free vibration of the dwell, in closed form.

    ``x''(t) = Re(K q_end exp(lambda t))``; its extrema shrink by ``exp(-zeta w pi/w_d)``
    each half period, so the maximum is at ``t = 0`` or at the first extremum (or the
    dwell's end if that comes first).
    """
    lam = eigenvalue(omega, zeta)
    amplitude = mode_gain(omega, zeta) * q_end
    first = jnp.mod(jnp.pi / 2 - jnp.angle(amplitude * lam), jnp.pi) / jnp.imag(lam)
    t = jnp.minimum(first, dwell)
    return jnp.maximum(jnp.abs(jnp.real(amplitude)), jnp.abs(jnp.real(amplitude * jnp.exp(lam * t))))


def residual_amplitude(e, de, omega, zeta):
    """``w^2`` times the amplitude of the free vibration started by ``(e, e')``: the
    residual vibration (units of h/T^2) of a dwell that starts in that state."""
    q = de - jnp.conj(eigenvalue(omega, zeta)) * e
    return residual_of_mode(q, omega, zeta)


def residual_of_mode(q, omega, zeta):
    """``w^2`` times the amplitude of the free vibration of mode ``q``:
    ``w |q| / sqrt(1 - zeta^2)``."""
    return omega * jnp.abs(q) / jnp.sqrt(1.0 - zeta**2)
