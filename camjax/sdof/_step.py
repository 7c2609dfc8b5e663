"""Exact propagation of the linear SDOF over each grid interval.

With ``lambda = -zeta w + i w_d`` the deflection equation ``e'' + 2 zeta w e' + w^2 e = a``
diagonalises to one complex mode ``q = e' - conj(lambda) e`` with ``q' = lambda q + a``.
Over an interval of width ``h`` on which ``a`` is the polynomial ``sum_m c_m sigma^m``
(``sigma`` = local time / h), the step is closed form:

    q(h) = exp(lambda h) q(0) + h sum_m c_m psi_m(lambda h),
    psi_m(z) = integral_0^1 exp(z (1 - sigma)) sigma^m d sigma.

``psi_m`` comes from its Taylor series for ``|z| < 1`` (18 terms: truncation below
1e-17) and from the upward recurrence ``psi_m = (m psi_(m-1) - 1) / z`` above, whose
rounding grows by at most ``5!`` at ``|z| = 1`` (about 2e-13 relative).  Grids refined
septic by septic keep ``|z| = w h`` at most 0.5, so the series is the path that runs; it
is the propagation's largest cost per period ratio, hence the short radius (18 terms
instead of the 25 a radius of 2 needs made the kernel 1.08x faster over n <= 30).  The SDOF
path's grid (``w h <= MAX_PHASE_STEP``, 1.5) takes its kicks from one law-only matrix of
the same series instead (``series_kicks``).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from ..checks import is_concrete
from ..sharding import on_cpu
from ._grid import INTERPOLATION_DEGREE, MAX_PHASE_STEP, MotionGrid


def _series_table(terms: int) -> np.ndarray:
    """``(6, terms + 1)``: the coefficient of ``z^k`` in ``psi_m(z)``, ``m! / (k + m + 1)!``."""
    return np.array([[math.factorial(m) / math.factorial(k + m + 1) for k in range(terms + 1)]
                     for m in range(INTERPOLATION_DEGREE + 1)])


_SERIES_TERMS = 18
_SERIES_RADIUS = 1.0
_SERIES = _series_table(_SERIES_TERMS)
_KICK_TERMS = next(k for k in range(1, 100)
                   if MAX_PHASE_STEP ** (k + 1) / math.factorial(k + 1) < 1e-17)
"""Terms of the kicks' series (``series_kicks``): truncation below 1e-17 at ``|z| =
MAX_PHASE_STEP`` (21 at 1.5)."""
_KICK_SERIES = _series_table(_KICK_TERMS)


def psi(z: jax.Array) -> jax.Array:
    """``psi_m(z)`` for ``m = 0..5``, shape ``z.shape + (6,)``.

    The six series share the powers of ``z``: one real product of the powers' real and
    imaginary parts with the series' coefficients evaluates all of them (1.1x faster for the
    whole kernel on CPU than six Horner loops in complex arithmetic).
    """
    small = jnp.abs(z) < _SERIES_RADIUS
    powers = [jnp.ones_like(z)]
    inside = jnp.where(small, z, 0.0)
    for _ in range(_SERIES_TERMS):
        powers.append(powers[-1] * inside)
    powers = jnp.stack(powers, axis=-1)
    series = jax.lax.complex(powers.real @ _SERIES.T, powers.imag @ _SERIES.T)
    zs = jnp.where(small, _SERIES_RADIUS, z)
    terms = [jnp.expm1(zs) / zs]
    for m in range(1, INTERPOLATION_DEGREE + 1):
        terms.append((m * terms[-1] - 1.0) / zs)
    return jnp.where(small[..., None], series, jnp.stack(terms, axis=-1))


def psi_host(z) -> np.ndarray:
    """``psi`` in NumPy on the host, the same series and recurrence: for root finding on
    exact values, which calls it many times with a few points (an eager JAX call per
    point costs far more than the arithmetic)."""
    z = np.asarray(z, dtype=complex)
    small = np.abs(z) < _SERIES_RADIUS
    inside = np.where(small, z, 0.0)
    powers = np.empty((_SERIES_TERMS + 1, *z.shape), complex)
    powers[0] = 1.0
    for k in range(1, _SERIES_TERMS + 1):
        np.multiply(powers[k - 1], inside, out=powers[k])
    flat = powers.reshape(_SERIES_TERMS + 1, -1)
    series = (_SERIES @ flat.real + 1j * (_SERIES @ flat.imag)).T.reshape(*z.shape, -1)
    if small.all():
        return series
    zs = np.where(small, _SERIES_RADIUS, z)
    terms = [(np.exp(zs) - 1.0) / zs]  # |zs| >= 1: no cancellation
    for m in range(1, INTERPOLATION_DEGREE + 1):
        terms.append((m * terms[-1] - 1.0) / zs)
    return np.where(small[..., None], series, np.stack(terms, axis=-1))


def eigenvalue(omega, zeta):
    """``lambda = -zeta w + i w sqrt(1 - zeta^2)`` of the damped oscillator (NumPy for
    concrete values: no eager JAX op, which compiles for each new size)."""
    if is_concrete(omega, zeta):
        omega, zeta = np.asarray(omega, dtype=float), np.asarray(zeta, dtype=float)
        return -zeta * omega + 1j * omega * np.sqrt(1.0 - zeta**2)
    return -zeta * omega + 1j * omega * jnp.sqrt(1.0 - zeta**2)


_CPU_BLOCK = 4
"""Intervals per block of the propagation's scan on CPU.  Measured in one process (2-core
CPU, 2026-11-25): blocks of 1, 2 or 4 are equally fast and 1.15-1.19x faster than 32 over
n <= 30 and n <= 100, since XLA computes a block's cumulative products and sums as windowed
reductions there.  Other backends keep ``_BLOCK`` (a longer scan costs a launch per step
on a GPU; not measured)."""
_BLOCK = 32
_DENSE_PIECES = 64  # above this many pieces, gather each interval's weights


def propagate(grid: MotionGrid, omega, zeta, q0=None, *, gather: bool | None = None,
              resolved: bool = False, lam=None, kick=None) -> jax.Array:
    """Complex mode ``q`` at every node of ``grid``, starting from rest (or from ``q0``
    at the first node).  ``gather`` picks how each interval finds its piece's step factor
    and weights (``None``: up to 64 pieces without a gather, the factors by a chain of
    selects and the weights by a matrix product; a gather above; the same numbers).
    ``resolved``: the caller guarantees ``w h <= MAX_PHASE_STEP`` on every interval (the
    SDOF's exact path refuses coarser grids); the kicks then come from one law-only
    matrix (``series_kicks``), with no per-piece ``psi``.  ``lam`` (complex, in the grid's
    time unit) replaces ``eigenvalue(omega, zeta)``: any mode of a linear chain, overdamped
    ones included (``omega`` and ``zeta`` are then unused).  ``kick`` (``(K,)`` complex)
    replaces the intervals' kicks computed from ``grid.forcing``: a caller whose forcing is
    a sum of law-only forcings with weights per mode adds their ``series_kicks`` (one
    product each for all modes and speeds, where the per-mode forcing would be built and
    integrated mode by mode).

    The recurrence ``q_(k+1) = E_k q_k + F_k`` runs in blocks of a few intervals: inside a
    block, ``q = G cumsum(F / G)`` with ``G`` the running product of the step factors
    (vectorised, and bounded since a block is short); a scan then carries the state
    from block to block.
    """
    lam = eigenvalue(omega, zeta) if lam is None else lam
    z = lam * grid.piece_width
    step = jnp.exp(z)
    # Each interval's kick uses its own piece's weights.  With few pieces (a law's rise)
    # the selection is a product with the law-only matrix ``piece_forcing`` (one row per
    # interval, its forcing placed in its piece's columns): the piece layout may be
    # traced, and under vmap over period ratios it is one matrix product, not a gather.
    # With many (a program's turn: a piece per law piece of every segment) that matrix
    # grows as intervals x pieces, so the weights are gathered instead.
    if gather is None:
        gather = grid.piece_width.shape[0] > _DENSE_PIECES
    factor = step[grid.piece] if gather else _by_piece(grid.piece, step)
    if kick is not None:
        kick = jnp.asarray(kick)
    elif resolved:
        kick = series_kicks(grid.forcing, grid.widths, jnp.max(grid.piece_width), lam)
    elif not gather:
        # Real and imaginary parts side by side in one product each: XLA would otherwise
        # evaluate psi's series once for each part.
        weights = psi(z).reshape(-1)  # (P * 6,): every piece's weights
        kick = _complex_product(grid.piece_forcing(), weights) * grid.widths
    else:
        kick = jnp.sum(grid.forcing * psi(z)[grid.piece], axis=1) * grid.widths
    block = _CPU_BLOCK if on_cpu() else _BLOCK
    n_intervals = kick.shape[0]
    n_blocks = -(-n_intervals // block)
    pad = n_blocks * block - n_intervals
    kick = jnp.pad(kick, (0, pad)).reshape(n_blocks, block)
    growth = jnp.cumprod(jnp.pad(factor, (0, pad), constant_values=1.0).reshape(n_blocks, block), axis=1)
    # kick / growth as a product with 1 / growth built from a real reciprocal: XLA's
    # complex division (scaled against overflow) was the kernel's costliest operation on CPU.
    inverse = 1.0 / (growth.real**2 + growth.imag**2)
    inside = growth * jnp.cumsum(kick * jax.lax.complex(growth.real * inverse, -growth.imag * inverse), axis=1)

    def carry(q, block):
        block_growth, block_end = block
        return block_growth * q + block_end, q

    start, q0 = q0, jnp.zeros((), kick.dtype)
    _, q_start = jax.lax.scan(carry, q0, (growth[:, -1], inside[:, -1]))
    q = (inside + q_start[:, None] * growth).reshape(-1)[:n_intervals]
    q = jnp.concatenate([q0[None], q])
    if start is not None:  # the free vibration from the start, exactly
        q = q + start * jnp.exp(lam * (grid.nodes - grid.nodes[0]))
    return q


def series_kicks(forcing, widths, widest, lam) -> jax.Array:
    """Kicks ``h sum_m c_m psi_m(lam h)`` of intervals of ``widths`` with forcing rows
    ``forcing``, through ``psi``'s series reassociated: ``sum_t (lam H)^t D_t`` with
    ``H = widest`` and the law-only ``D_t = h (h / H)^t sum_m c_m s_(m,t)``.  One real
    product of ``(K, 22)`` with the powers of one complex number replaces the per-piece
    ``psi`` and the piece selection (1.2-1.3x faster for a whole 1000-ratio kernel on CPU).
    Needs ``|lam H| <= MAX_PHASE_STEP`` and ``widths <= H``: the series (``_KICK_TERMS``)
    is then exact to double precision, its terms at most ``1.5^t / t!``, so float32
    neither overflows nor underflows.
    """
    terms = np.arange(_KICK_TERMS + 1)
    law_only = (forcing @ _KICK_SERIES) * (widths[:, None] * (widths / widest)[:, None] ** terms)
    z = lam * widest
    powers = [jnp.ones_like(z)]
    for _ in range(_KICK_TERMS):
        powers.append(powers[-1] * z)
    return _complex_product(law_only, jnp.stack(powers))


def steps_within(q_start, forcing, widths, widest, lam, fraction: float) -> jax.Array:
    """The mode ``fraction`` (in ``(0, 1]``) of the way across intervals (forcing rows
    ``(n, 6)``, ``widths`` ``(n,)``), exactly, from the mode at their starts: part of a step
    of ``propagate``, on a grid whose widest interval is ``widest`` and resolved (``|lam|
    widest <= MAX_PHASE_STEP``).  The forcing on the part, in its own ``sigma``, has the
    coefficients ``c_m fraction^m``."""
    powers = fraction ** np.arange(INTERPOLATION_DEGREE + 1)
    kicks = series_kicks(forcing * powers, widths * fraction, widest, lam)
    return jnp.exp(lam * (widths * fraction)) * q_start + kicks


def _by_piece(piece, values):
    """``values[piece]`` for a grid's piece index (each in ``[0, P)``, traced or not), as a
    chain of selects: one fused pass.  A product with the one-hot piece selector, and the
    assembly of its complex result, cost a 1000-ratio kernel about a tenth of its time on
    CPU; up to ``_DENSE_PIECES`` pieces the chain is never slower (2-core CPU, 2026-11-26)."""
    out = jnp.broadcast_to(values[0], jnp.shape(piece))
    for p in range(1, values.shape[0]):
        out = jnp.where(piece >= p, values[p], out)
    return out


def _complex_product(real_matrix, vector):
    """``real_matrix @ vector`` for a complex ``vector``, as one real product."""
    parts = real_matrix @ jnp.stack([vector.real, vector.imag], axis=-1)
    return jax.lax.complex(parts[..., 0], parts[..., 1])


def periodic_propagate(grid: MotionGrid, omega, zeta, *, lam=None, kick=None) -> jax.Array:
    """Complex mode at every node of the periodic steady state of a forcing that repeats
    with the grid's span (a cam's turn): the start is the fixed point of the span's map
    ``q(end) = E q(start) + F``, ``q0 = F / (1 - E)``, exactly (needs ``zeta > 0``, or
    ``Re lam < 0`` where ``lam`` is given; ``lam`` and ``kick`` as in ``propagate``)."""
    lam = eigenvalue(omega, zeta) if lam is None else lam
    from_rest = propagate(grid, omega, zeta, lam=lam, kick=kick)
    span = grid.nodes[-1] - grid.nodes[0]
    q0 = from_rest[-1] / (1.0 - jnp.exp(lam * span))
    return from_rest + q0 * jnp.exp(lam * (grid.nodes - grid.nodes[0]))


def mode_between(grid: MotionGrid, q_nodes, lam, t) -> np.ndarray:
    """The complex mode at any times ``t`` inside the grid's span, exactly, from its node
    values: the step of ``propagate`` over the part of an interval up to ``t``.

    NumPy on the host (root finding on exact values calls it many times with few points);
    ``lam`` is the eigenvalue in the grid's time unit (``eigenvalue(omega, zeta)``).
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    nodes = np.asarray(grid.nodes)
    piece = np.asarray(grid.piece)
    k = np.clip(np.searchsorted(nodes, t, side="right") - 1, 0, piece.size - 1)
    h = np.asarray(grid.piece_width)[piece[k]]
    return step_within_host(np.asarray(q_nodes)[k], np.asarray(grid.forcing)[k], h, t - nodes[k], lam)


def step_within_host(q_start, forcing, widths, delta, lam) -> np.ndarray:
    """The mode ``delta`` into intervals of ``widths`` with forcing rows ``forcing``
    (``(..., 6)``) from the mode ``q_start`` at their starts: ``propagate``'s exact step over
    part of an interval, in NumPy on the host (every argument broadcasts, ``lam`` too)."""
    weights = psi_host(lam * delta)
    powers = (delta / widths)[..., None] ** np.arange(INTERPOLATION_DEGREE + 1)
    return np.exp(lam * delta) * q_start + delta * np.sum(forcing * powers * weights, axis=-1)
