"""What a designer reads off the complex mode: accelerations, forces, their refined peaks
and the residual vibration.

Any linear output of the SDOF's state is ``Re(G q)`` for a complex gain ``G`` (the payload
acceleration ``x''``, a spring-train force ``k e + c e'``, the deflection ``e``); its time
derivatives follow from ``q' = lambda q + a`` with one-sided forcing, which is what the
Hermite peak refinement (``camjax.metrics.refined_peak``) needs at every interval's ends.
"""

from __future__ import annotations

import jax.numpy as jnp

from ..metrics import refined_peak
from ._grid import MotionGrid
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
    return _mode_terms(gain, lam, q) + _forcing_terms(gain, lam, one_sided)


def _mode_terms(gain, lam, q):
    """``Re(gain lam^j q)`` for ``j = 1, 2, 3`` (``(K, 3)``): the part of the derivatives
    that the mode carries.  With ``q' = lam q + a``, the j-th derivative of ``gain q`` is
    ``gain (lam^j q + lam^(j-1) a + ... + a^(j-1))``."""
    return jnp.real(q[:, None] * (gain * jnp.stack([lam, lam**2, lam**3])))


def _forcing_terms(gain, lam, one_sided):
    """The forcing's part of the derivatives (``(K, 3)``): real, since the one-sided
    ``(a, a', a'')`` are, and only ``Re(gain lam^k)`` multiplies them (complex
    arithmetic on every node costs the kernel a fifth of its time on CPU)."""
    g0, g1, g2 = jnp.real(gain), jnp.real(gain * lam), jnp.real(gain * lam**2)
    a, da, dda = one_sided[:, 0], one_sided[:, 1], one_sided[:, 2]
    return jnp.stack([g0 * a, g1 * a + g0 * da, g2 * a + g1 * da + g0 * dda], axis=1)


def output_jets(gain, q, grid: MotionGrid, omega, zeta):
    """``Re(gain q)`` at the nodes and its derivatives at both ends of every interval
    (``(values, left, right)``, the arguments of ``refined_peak`` after the widths); the
    mode's part is computed once per node and shared by the intervals on either side."""
    lam = eigenvalue(omega, zeta)
    left, right = grid.one_sided()
    carried = _mode_terms(gain, lam, q)
    return (jnp.real(gain * q), carried[:-1] + _forcing_terms(gain, lam, left),
            carried[1:] + _forcing_terms(gain, lam, right))


def peak_in_motion(q, grid: MotionGrid, omega, zeta):
    """Max ``|x''|`` over the grid's span: ``x'' = Re(K q)`` at the nodes, refined between."""
    values, left, right = output_jets(mode_gain(omega, zeta), q, grid, omega, zeta)
    return refined_peak(values, grid.widths, left, right)


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
