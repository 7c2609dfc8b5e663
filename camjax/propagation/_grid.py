"""The sample grid over a rise, with the law's breakpoints as nodes.

Each smooth piece of the law (between breakpoints) is cut into equal intervals.  On every
interval the acceleration is replaced by its degree-5 interpolant through six
Gauss-Legendre points, which never sit on a breakpoint, so one-sided limits at jumps come
out right.  For polynomial laws of acceleration degree <= 5 the interpolant is exact; for
the sinusoidal SCCA pieces its error is O(h^6) and far below 1e-12 at default resolution.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..laws import AbstractMotionLaw

INTERPOLATION_DEGREE = 5
_GAUSS_POINTS = (np.polynomial.legendre.leggauss(INTERPOLATION_DEGREE + 1)[0] + 1) / 2
# Maps the acceleration at the Gauss points to monomial coefficients in sigma = local/width.
_TO_MONOMIAL = np.linalg.inv(np.vander(_GAUSS_POINTS, INTERPOLATION_DEGREE + 1, increasing=True))

TARGET_PHASE_STEP = 0.5
"""Largest ``w * h`` (radians of vibration per interval) the default resolution allows."""


def default_resolution(max_period_ratio: float) -> int:
    """Intervals per unit of tau that keep ``w h <= TARGET_PHASE_STEP`` (a multiple of 64).

    The step bounds the peak-refinement error near ``(w h)^8 / 1e7`` (4e-10 relative);
    node values are exact at any resolution.  Rounding to multiples of 64 limits
    recompilation across nearby requests.
    """
    needed = 2 * math.pi * max_period_ratio / TARGET_PHASE_STEP
    return max(128, 64 * math.ceil(needed / 64))


class MotionGrid(NamedTuple):
    """Nodes over ``[0, 1]`` and the interpolated forcing on each interval.

    Attributes:
        nodes: ``(K + 1,)`` node times, from 0 to 1.
        piece: ``(K,)`` NumPy index of the law piece that each interval belongs to.
        piece_width: ``(P,)`` interval width used inside each piece.
        forcing: ``(K, 6)`` monomial coefficients of the acceleration in ``sigma``.
    """

    nodes: jax.Array
    piece: np.ndarray
    piece_width: jax.Array
    forcing: jax.Array

    @property
    def widths(self) -> jax.Array:
        return self.piece_width[self.piece]

    def piece_slices(self) -> list[tuple[int, int]]:
        """``(start, stop)`` interval indices of each piece (pieces are contiguous)."""
        stops = np.cumsum(np.bincount(self.piece, minlength=self.piece_width.shape[0]))
        return list(zip(np.concatenate([[0], stops[:-1]]).tolist(), stops.tolist()))

    def one_sided(self) -> tuple[jax.Array, jax.Array]:
        """Acceleration, jerk and snap at both ends of every interval.

        Returns ``(left, right)``, each ``(K, 3)``, taken from the interval's own
        interpolant: limits from inside the interval, right even where the law jumps.
        """
        c = self.forcing
        h = self.widths
        h = jnp.where(h > 0, h, 1.0)[:, None]
        powers = np.arange(INTERPOLATION_DEGREE + 1)
        scale = h ** np.arange(3)
        left = c[:, :3] * np.array([1.0, 1.0, 2.0]) / scale
        right = jnp.stack(
            [c.sum(1), (c * powers).sum(1), (c * powers * (powers - 1)).sum(1)], axis=1
        ) / scale
        return left, right


def _piece_counts(law: AbstractMotionLaw, resolution: int):
    """Edges of the law's pieces and a static interval count for each."""
    breakpoints = law.breakpoints()
    if isinstance(breakpoints, tuple):
        edges = np.array([0.0, *breakpoints, 1.0])
        counts = [max(2, math.ceil(resolution * w)) for w in np.diff(edges)]
        return jnp.asarray(edges), counts
    # Traced breakpoints (an SCCA law with free fractions): the widths are unknown when
    # the grid's shape is fixed, so every piece gets the intervals a piece of half the
    # rise needs; no SCCA piece is wider, since each lies within one half of the rise.
    n_pieces = breakpoints.shape[0] + 1
    edges = jnp.concatenate([jnp.zeros(1), jnp.sort(jnp.clip(breakpoints, 0.0, 1.0)), jnp.ones(1)])
    return edges, [math.ceil(resolution / 2)] * n_pieces


def motion_grid(law: AbstractMotionLaw, resolution: int) -> MotionGrid:
    """Grid over the rise with about ``resolution`` intervals per unit tau."""
    # A law without traced parameters gives a constant grid: compute it now rather than
    # leave it to XLA's constant folder, which takes minutes over the sampled forcing.
    with jax.ensure_compile_time_eval():
        return _motion_grid(law, resolution)


def _motion_grid(law: AbstractMotionLaw, resolution: int) -> MotionGrid:
    edges, counts = _piece_counts(law, resolution)
    piece = np.repeat(np.arange(len(counts)), counts)
    step = np.concatenate([np.arange(m) for m in counts]).astype(float)
    piece_width = (edges[1:] - edges[:-1]) / np.asarray(counts, dtype=float)
    left = edges[piece] + piece_width[piece] * step
    nodes = jnp.concatenate([left, jnp.ones(1)])
    sample_times = left[:, None] + piece_width[piece][:, None] * _GAUSS_POINTS
    forcing = law.a(sample_times) @ jnp.asarray(_TO_MONOMIAL.T)
    return MotionGrid(nodes, piece, piece_width, forcing)
