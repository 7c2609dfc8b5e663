"""What a designer reads off the complex mode: accelerations, forces, their refined peaks
and the residual vibration.

Any linear output of the SDOF's state is ``Re(G q)`` for a complex gain ``G`` (the payload
acceleration ``x''``, a spring-train force ``k e + c e'``, the deflection ``e``); its time
derivatives follow from ``q' = lambda q + a`` with one-sided forcing, which is what the
Hermite peak refinement (``camjax.metrics.refined_peak``) needs at every interval's ends.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..metrics import PEAK_TOLERANCE, bernstein_bound, hermite_data, peak_search, refined_peak
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
    return jnp.stack(_jet_columns(gain, lam, q, one_sided), axis=1)


def _jet_columns(gain, lam, q, one_sided):
    """The derivatives of ``gain_derivatives`` as separate arrays, as many as ``one_sided``
    has columns: the mode's part ``Re(gain lam^j q)`` plus the forcing's, real since
    ``(a, a', a'', ...)`` are (complex arithmetic on every node costs the kernel a fifth of
    its time on CPU).  With ``q' = lam q + a``, the j-th derivative of ``gain q`` is
    ``gain (lam^j q + lam^(j-1) a + ... + a^(j-1))``."""
    order = one_sided.shape[1]
    g = _jet_gains(gain, lam, order)
    re, im = jnp.real(q), jnp.imag(q)
    return tuple(g[2 * j] * re - g[2 * j + 1] * im
                 + sum(g[2 * (j - 1 - i)] * one_sided[:, i] for i in range(j))
                 for j in range(1, order + 1))


def _jet_gains(gain, lam, order: int = 3):
    """Real and imaginary parts of ``gain lam^j``, ``j = 0..order``, as real scalars.

    Kept apart from the per-node arithmetic (an optimisation barrier): fused into it, XLA
    recomputed these complex products for every node."""
    parts = []
    for j in range(order + 1):
        parts += [jnp.real(gain * lam**j), jnp.imag(gain * lam**j)]
    return jax.lax.optimization_barrier(parts)


def output_jets(gain, q, grid: MotionGrid, omega, zeta):
    """``Re(gain q)`` at the nodes and its derivatives at both ends of every interval
    (``(values, left, right)``, the arguments of ``refined_peak`` after the widths)."""
    values, left, right = _output_columns(gain, eigenvalue(omega, zeta), q, *grid.one_sided())
    return values, jnp.stack(left, axis=1), jnp.stack(right, axis=1)


def _output_columns(gain, lam, q, one_left, one_right):
    """``output_jets`` with each derivative a separate array (from the grid's one-sided
    forcing): the bound of every interval reads them in one pass without storing them."""
    g = _jet_gains(gain, lam)
    values = g[0] * jnp.real(q) - g[1] * jnp.imag(q)
    return (values, _jet_columns(gain, lam, q[:-1], one_left),
            _jet_columns(gain, lam, q[1:], one_right))


PEAK_SEARCHES = ("bounded", "dense")
"""How ``peak_in_motion`` refines between nodes (its ``search``; a sweep's
``SpringMassOptions.peak_search``): ``"bounded"`` (default: ``camjax.metrics.peak_search``,
only the intervals that can hold the peak; a sweep's kernel 1.7-1.9x faster warm, its
program larger to compile) or ``"dense"`` (``camjax.metrics.refined_peak``, every
interval).  Both give the same answer; the ``camjax`` command picks ``"dense"`` for its
short commands, whose time is mostly compilation."""


def checked_peak_search(search: str) -> str:
    """``search`` if it names one of ``PEAK_SEARCHES``, else a one-line ``ValueError``."""
    if not isinstance(search, str) or search not in PEAK_SEARCHES:
        raise ValueError(f"peak_search must be one of {', '.join(PEAK_SEARCHES)}, got {search!r}")
    return search


REFINED_DERIVATIVES = 5
"""Derivatives at each end of the interpolant ``peak_in_motion`` refines: degree 11, within
``(w h)^12 / 2e12`` of the vibration's amplitude (6.5e-11 at the SDOF grid's ``w h <=
MAX_PHASE_STEP`` = 1.5; Ct within 1e-11 measured over n <= 30).  In single precision the fifth
derivative's rounding costs more than the septic's ``(w h)^8 / 1e7`` (2.6e-6 there):
float32 refines septics (three)."""
BOUND_SLACK = 1e-5
"""What every interval's bound is raised by, as a fraction of the largest: the bounds come
from the septic over each interval (three derivatives, cheaper than five), within
``(w h)^8 / 1e7`` (2.6e-6 at ``w h = MAX_PHASE_STEP``) of the vibration's amplitude, which
no interval's bound falls far short of."""


def constant_intervals(forcing):
    """``(K,)`` whether each interval's forcing (``(K, 6)`` monomial coefficients) is a
    constant: exactly, since ``to_monomial`` gives equal samples as ``(a, 0, ..., 0)``."""
    return jnp.all(forcing[:, 1:] == 0, axis=1)


def plateau_bound(values, slope_left, slope_right, forcing, omega, zeta):
    """``(K,)`` bounds of ``|Re(K q)|`` on the intervals where the forcing is constant
    (``inf`` elsewhere), exact on those that hold a crest.

    With constant forcing ``a`` the output is ``p + v``: the constant ``p = -Re(K / lambda)
    a`` and a free vibration ``v = Re(C exp(lambda t))``, whose largest ``|v|`` on the
    interval is at an end or, if ``v'`` changes sign inside (an interval spans less than
    half a period), at most its envelope at the start.  Undamped, every crest of a
    constant-acceleration piece has the same height: the Bernstein bounds of the septics
    exceed it by a margin, so each crest's interval would be refined; this bound is the
    crest itself, and the first refined crest closes the others (``PEAK_TOLERANCE``)."""
    lam = eigenvalue(omega, zeta)
    # Per-ratio scalars behind a barrier, or XLA recomputes them at every node.
    static, decay, inverse_frequency = jax.lax.optimization_barrier(
        (-jnp.real(mode_gain(omega, zeta) / lam), -jnp.real(lam), 1 / jnp.imag(lam)))
    constant = constant_intervals(forcing)
    p = static * forcing[:, 0]
    v0, v1 = values[:-1] - p, values[1:] - p
    # hypot and the slopes' signs: no underflow at any scale of the signal.
    envelope = jnp.hypot(v0, (slope_left + decay * v0) * inverse_frequency)
    vibration = jnp.where(jnp.sign(slope_left) * jnp.sign(slope_right) < 0, envelope,
                          jnp.maximum(jnp.abs(v0), jnp.abs(v1)))
    return jnp.where(constant, jnp.abs(p) + vibration, jnp.inf)


def peak_in_motion(q, grid: MotionGrid, omega, zeta, search: str = "bounded"):
    """Max ``|x''|`` over the grid's span: ``x'' = Re(K q)`` at the nodes, refined between
    by an interpolant of degree 11 on each interval (``search``, one of
    ``PEAK_SEARCHES``).

    The bounded search takes every interval's bound from the septic (three derivatives per
    end) in one pass over the jets; only the intervals it refines get their five
    derivatives, from the mode at their ends, so no interval's jets are stored.  On
    intervals of constant forcing the bound is the smaller of that and ``plateau_bound``
    (exact at crests), so a constant-acceleration piece's equal crests take one round of
    refinement instead of up to ten: undamped, such laws' kernels run 1.5x faster.  The dense
    search refines every interval.
    """
    checked_peak_search(search)
    gain, lam = mode_gain(omega, zeta), eigenvalue(omega, zeta)
    widths = grid.widths
    double = jnp.finfo(jnp.result_type(q)).bits >= 64
    one_left, one_right = grid.one_sided(REFINED_DERIVATIVES if double else 3)
    if search == "dense":
        values, left, right = _output_columns(gain, lam, q, one_left, one_right)
        return refined_peak(values, widths, jnp.stack(left, axis=1), jnp.stack(right, axis=1))
    values, left, right = _output_columns(gain, lam, q, one_left[:, :3], one_right[:, :3])
    bound = bernstein_bound(values, widths, left, right)
    bound = bound + BOUND_SLACK * jnp.max(bound)
    # Laws without a constant piece skip the plateaus' pass (unbatched over period ratios,
    # the condition stays a branch under vmap).
    bound = jax.lax.cond(
        jnp.any(constant_intervals(grid.forcing)),
        lambda: jnp.minimum(bound, plateau_bound(values, left[0], right[0], grid.forcing,
                                                 omega, zeta)),
        lambda: bound)
    law = jnp.concatenate([widths[:, None], one_left, one_right], axis=1)
    ends = one_left.shape[1] + 1

    def hermite_of(index):
        rows = law[index]
        start, end = q[jnp.concatenate([index, index + 1])].reshape(2, -1)
        return hermite_data(jnp.real(gain * start), rows[:, 0],
                            gain_derivatives(gain, lam, start, rows[:, 1:ends]),
                            gain_derivatives(gain, lam, end, rows[:, ends:]),
                            jnp.real(gain * end))

    return peak_search(bound, hermite_of, jnp.max(jnp.abs(values)), PEAK_TOLERANCE)


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

    ``x''(t) = Re(A exp(lambda t)) = |A| exp(-zeta w t) cos(w_d t + phi)`` with
    ``A = K q_end``.  Its extrema (``d/dt Re(A exp(lambda t)) = Re(A lambda exp(lambda t)) = 0``)
    come every half damped period, at ``t_k = (pi/2 - arg(A lambda) mod pi) / w_d + k pi / w_d``,
    each ``|A| sqrt(1 - zeta^2) exp(-zeta w t_k)``: smaller than the one before.  So the
    maximum over ``[0, dwell]`` is at ``t = 0`` or at the first extremum, or at the dwell's
    end if that comes first (between, ``|x''|`` is monotonic).
    """
    lam = eigenvalue(omega, zeta)
    amplitude = mode_gain(omega, zeta) * q_end
    first = jnp.mod(jnp.pi / 2 - jnp.angle(amplitude * lam), jnp.pi) / jnp.imag(lam)
    t = jnp.minimum(first, dwell)
    return jnp.maximum(jnp.abs(jnp.real(amplitude)), jnp.abs(jnp.real(amplitude * jnp.exp(lam * t))))


def residual_amplitude(e, de, omega, zeta, dwell: float = 1.0):
    """The residual vibration (units of h/T^2) of a dwell of ``dwell`` motion periods that
    starts in the deflection state ``(e, e')``: the largest ``|x''|`` of the free vibration
    there (``residual_of_mode``)."""
    q = de - jnp.conj(eigenvalue(omega, zeta)) * e
    return residual_of_mode(q, omega, zeta, dwell)


def residual_of_mode(q, omega, zeta, dwell: float = 1.0):
    """The residual vibration of mode ``q``: the largest ``|x''|`` of its free vibration
    over a dwell of ``dwell`` motion periods (``dwell_peak``).

    Undamped, and wherever the dwell holds the first crest (half a natural period), it is
    the free vibration's amplitude ``w |q|``; damped, the envelope coefficient
    ``w |q| / sqrt(1 - zeta^2)`` at the dwell's start is no acceleration that occurs (each
    crest is ``sqrt(1 - zeta^2)`` of the envelope, decayed to its time) and grows without
    bound as ``zeta -> 1`` (353 at ``zeta = 0.999999`` where ``|x''|`` stays below 1).
    """
    return dwell_peak(q, omega, zeta, dwell)
