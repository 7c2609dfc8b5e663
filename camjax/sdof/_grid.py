"""The sample grid of a piecewise-smooth forcing over an interval: a rise, or a whole turn.

``piecewise_grid`` lays out any pieces (edges and interval counts) with one set of
constants (the interpolant's degree, its Gauss points, the map to monomial coefficients);
``motion_grid`` and ``SampledLaw`` lay out a law's rise on it, and the program's turn
(``camjax.program``) lays out its segments on it.

Over a rise, each smooth piece of the law (between breakpoints) is cut into equal intervals,
``PIECE_MINIMUM`` and about ``resolution * width`` more; the grid always has ``resolution +
PIECE_MINIMUM * pieces`` intervals, so its shape depends on the law's type alone and laws
whose breakpoints are traced (an SCCA with free fractions, or several SCCA laws stacked)
get the same grid as fixed ones.  On every interval the acceleration is replaced by its
degree-5 interpolant through six Gauss-Legendre points, which never sit on a breakpoint,
so one-sided limits at jumps come out right.  For polynomial laws of acceleration degree
<= 5 the interpolant is exact; for the sinusoidal SCCA pieces its error is O(h^6): about
1e-12 of the acceleration at 128 intervals per rise, 1.5e-7 on a quarter sine over its
two (a piece that short moves Ct by about 1e-11).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable, Sequence
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..laws import AbstractMotionLaw

INTERPOLATION_DEGREE = 5
GAUSS_POINTS = (np.polynomial.legendre.leggauss(INTERPOLATION_DEGREE + 1)[0] + 1) / 2
"""Where each interval samples its forcing, as fractions of the interval (never an end)."""
_TO_MONOMIAL = np.linalg.inv(np.vander(GAUSS_POINTS, INTERPOLATION_DEGREE + 1, increasing=True))

MAX_GRID_INTERVALS = 2**20
"""Largest exact-path grid (intervals per rise, or per turn of a program): a larger
request is refused before any work, with what to change."""


def to_monomial(samples):
    """Monomial coefficients in ``sigma`` (``(..., 6)``) of the interpolant through samples
    at ``GAUSS_POINTS`` (``(..., 6)``); NumPy in, NumPy out, else JAX.

    Equal samples (a constant-acceleration piece) give exactly ``(a, 0, 0, 0, 0, 0)``
    rather than that plus rounding: the peak search recognises such intervals, whose
    undamped crests are all equal (``camjax.sdof.plateau_bound``).  Their gradient
    is the interpolant's.
    """
    xp = np if isinstance(samples, np.ndarray) else jnp
    with np.errstate(over="ignore", invalid="ignore"):  # huge samples: inf, as JAX gives
        coefficients = samples @ xp.asarray(_TO_MONOMIAL.T)
    constant = xp.all(samples == samples[..., :1], axis=-1, keepdims=True)
    exact = xp.where(np.arange(INTERPOLATION_DEGREE + 1) == 0, samples[..., :1], 0.0)
    snapped = xp.where(constant, exact, coefficients)
    if xp is np:
        return snapped
    # Zero in value and the interpolant's in gradient (zero where a sample is not finite).
    tangent = coefficients - jax.lax.stop_gradient(coefficients)
    return jax.lax.stop_gradient(snapped) + jnp.where(jnp.isfinite(tangent), tangent, 0.0)


TARGET_PHASE_STEP = 0.5
"""Largest ``w * h`` (radians of vibration per interval) that a refined peak's septic spans
(refinement error below 4e-10 relative): the default step of a grid whose peaks are refined
interval by interval (a cam program's turn, the training grid of a design)."""


MAX_PHASE_STEP = 1.5
"""The exact SDOF path's grid: ``w h`` at most this, by default and on any grid a caller
chooses.  Its peaks are refined by interpolants of degree 11 (``peak_in_motion``: within
``(w h)^12 / 2e12``, 6.5e-11 of the vibration's amplitude at this step; Ct within 1e-11
measured over n <= 30) and its propagation's series (``propagate(resolved=True)``) is
exact up to it.  The default grid over n in [1, 30] then has 128 intervals per rise rather
than 192 at 1.0 (a 1000-ratio kernel 1.4x faster, 2026-11-26).  A sweep refuses a coarser grid before any
work, a traced period ratio raises when it runs."""


SUBSTEPS_PER_INTERVAL = math.ceil(MAX_PHASE_STEP / TARGET_PHASE_STEP)
"""Parts of an interval of the exact SDOF grid that turn the vibration by at most
``TARGET_PHASE_STEP`` each (three): a fixed-step solver's default steps per interval, and
``solve``'s samples per interval (a smooth curve to plot)."""


def default_resolution(max_period_ratio: float, phase_step: float = TARGET_PHASE_STEP,
                       minimum: float = 128) -> int:
    """Intervals per unit of tau that keep ``w h <= phase_step`` (a multiple of 64), and
    at least ``minimum``.

    The step bounds the error of a septic peak refinement near ``(w h)^8 / 1e7`` (4e-10
    relative at the default 0.5; the SDOF path's grid, at ``MAX_PHASE_STEP``, refines by
    degree 11 instead); node values are exact at any resolution.  Rounding to multiples
    of 64 limits recompilation across nearby requests.
    """
    needed = 2 * math.pi * max_period_ratio / phase_step
    return 64 * math.ceil(max(needed, minimum) / 64)


def period_ratio_reach(phase_step: float, intervals: int = MAX_GRID_INTERVALS) -> float:
    """The largest period ratio (vibrations per unit of tau) that a grid of ``intervals``
    resolves at ``w h <= phase_step``: what a refusal of a larger grid can offer instead."""
    return intervals * phase_step / (2 * math.pi)


def check_grid_size(intervals: int, what: str, remedy: str | Callable[[], str]) -> None:
    """The one refusal of a grid of more than ``MAX_GRID_INTERVALS`` intervals, made by every
    caller that sizes one (a rise, a turn, a sweep's spec, a design's training grid, a
    reference), before any work.

    Raises ``ValueError("{what} needs {intervals} grid intervals (the limit is
    {MAX_GRID_INTERVALS}): {remedy}")``: ``what`` names the request in the caller's terms
    (``"a turn at 1e-06 rpm"``) and ``remedy`` says what to change there (a callable is
    called only when the grid is refused).
    """
    if intervals <= MAX_GRID_INTERVALS:
        return
    text = remedy() if callable(remedy) else remedy
    raise ValueError(f"{what} needs {int(intervals):,} grid intervals (the limit is "
                     f"{MAX_GRID_INTERVALS:,}): {text}")


class MotionGrid(NamedTuple):
    """Nodes over ``[0, 1]`` and the interpolated forcing on each interval.

    Attributes:
        nodes: ``(K + 1,)`` node times, from 0 to 1.
        piece: ``(K,)`` index of the law piece that each interval belongs to (NumPy for
            fixed breakpoints, traced when the breakpoints are).
        piece_width: ``(P,)`` interval width used inside each piece.
        forcing: ``(K, 6)`` monomial coefficients of the acceleration in ``sigma``.
    """

    nodes: jax.Array
    piece: np.ndarray | jax.Array
    piece_width: jax.Array
    forcing: jax.Array

    @property
    def widths(self) -> jax.Array:
        return self.piece_width[self.piece]

    def piece_selector(self) -> jax.Array:
        """``(K, P)`` one-hot rows: ``selector @ x`` gives each interval its piece's ``x``."""
        pieces = self.piece_width.shape[0]
        return (self.piece[:, None] == jnp.arange(pieces)).astype(self.forcing.dtype)

    def piece_forcing(self) -> jax.Array:
        """``(K, P * 6)``: each interval's forcing in the six columns of its piece, zero
        elsewhere, so that ``piece_forcing() @ w.reshape(-1)`` applies per-piece weights."""
        rows = self.piece_selector()[:, :, None] * self.forcing[:, None, :]
        return rows.reshape(self.forcing.shape[0], -1)

    def one_sided(self, derivatives: int = 3) -> tuple[jax.Array, jax.Array]:
        """Acceleration and its next ``derivatives - 1`` derivatives (jerk, snap, ...) at
        both ends of every interval.

        Returns ``(left, right)``, each ``(K, derivatives)``, taken from the interval's own
        interpolant: limits from inside the interval, right even where the law jumps.
        """
        c = self.forcing
        h = self.widths
        h = jnp.where(h > 0, h, 1.0)[:, None]
        powers = np.arange(INTERPOLATION_DEGREE + 1)
        falling = np.array([[math.perm(int(m), j) for m in powers] for j in range(derivatives)])
        scale = [jnp.ones_like(h)]
        for _ in range(derivatives - 1):
            scale.append(scale[-1] * h)  # not a power: pow is exp(log)
        scale = jnp.concatenate(scale, axis=1)
        left = c[:, :derivatives] * np.diag(falling[:, :derivatives]) / scale
        right = (c @ falling.T) / scale
        return left, right


PIECE_MINIMUM = 2
"""Intervals that every piece of positive width gets at least: a short sinusoidal piece
(an SCCA law's quarter sine 0.005 wide) on one interval put Ct off by 2.8e-9 at damping
0.2 and n <= 20 (128 intervals per rise); on two, 1e-11 (four gain nothing more)."""


def piece_counts(widths, total: int, minimum: int = 1):
    """Interval counts of pieces of ``widths`` (summing to 1) that add up to ``total``.

    Every piece of positive width gets at least ``minimum`` intervals and the rest in
    proportion to its width (largest remainders first, ties to the earlier piece);
    zero-width pieces get none.  NumPy in, NumPy out (fixed breakpoints, no JAX dispatch);
    JAX arrays work too (traced breakpoints: only the total is static).
    """
    xp = np if isinstance(widths, np.ndarray) else jnp
    positive = widths > 0
    spare = total - minimum * xp.sum(positive)
    share = widths / xp.sum(widths) * spare
    base = xp.floor(share).astype(int)
    remainder = xp.where(positive, share - base, -1.0)
    order = np.argsort(-remainder, kind="stable") if xp is np else jnp.argsort(-remainder)
    rank = xp.argsort(order)
    counts = minimum * positive + base + ((rank < spare - xp.sum(base)) & positive)
    # Rounding cannot leave the sum off by more than a piece's share; the widest piece
    # takes up any difference so that the grid's shape holds exactly.
    widest = xp.arange(widths.shape[0]) == xp.argmax(widths)
    return counts + widest * (total - xp.sum(counts))


def motion_grid(law: AbstractMotionLaw, resolution: int) -> MotionGrid:
    """Grid over the rise with ``resolution`` intervals plus ``PIECE_MINIMUM`` per law piece."""
    # A law without traced parameters gives a constant grid: compute it now rather than
    # leave it to XLA's constant folder, which takes minutes over the sampled forcing.
    with jax.ensure_compile_time_eval():
        grid, sample_times = _layout(law.breakpoints(), resolution)
        return grid._replace(forcing=to_monomial(law.a(sample_times)))


def _layout(breakpoints, resolution: int, pieces: int | None = None):
    """The grid without its forcing (``None``), and the Gauss points to sample it at.

    Fixed breakpoints (a tuple) are laid out in NumPy; ``pieces`` pads them with empty
    pieces up to that count.  Traced breakpoints give the same layout as a computation.
    """
    if isinstance(breakpoints, tuple):
        xp = np
        padding = 0 if pieces is None else pieces - len(breakpoints) - 1
        edges = np.array([0.0, *breakpoints, *([1.0] * padding), 1.0])
    else:
        xp = jnp
        inner = jnp.sort(jnp.clip(breakpoints, 0.0, 1.0))
        edges = jnp.concatenate([jnp.zeros(1), inner, jnp.ones(1)])
    widths = xp.diff(edges)
    total = int(resolution) + PIECE_MINIMUM * widths.shape[0]
    return piecewise_grid(edges, piece_counts(widths, total, PIECE_MINIMUM), total)


def piecewise_grid(edges, counts, total: int | None = None):
    """The grid (forcing ``None``) of pieces ``edges[p]..edges[p + 1]``, each cut into
    ``counts[p]`` equal intervals, and the times ``(K, 6)`` at which to sample the forcing
    (``to_monomial`` of the samples is the grid's forcing).

    NumPy edges and counts give a NumPy layout (no JAX dispatch); JAX arrays (traced
    breakpoints) give the same layout as a computation: then ``total``, the sum of the
    counts, must be given (it fixes the grid's shape).
    """
    xp = np if isinstance(edges, np.ndarray) and isinstance(counts, np.ndarray) else jnp
    widths = xp.diff(edges)
    if total is None:
        total = int(np.sum(counts))
    stops = xp.cumsum(counts)
    interval = xp.arange(total)
    piece = xp.searchsorted(stops, interval, side="right")
    step = interval - (stops - counts)[piece]
    piece_width = widths / xp.maximum(counts, 1)
    left = edges[piece] + piece_width[piece] * step
    nodes = xp.concatenate([left, edges[-1:]])
    sample_times = left[:, None] + piece_width[piece][:, None] * GAUSS_POINTS
    return MotionGrid(jnp.asarray(nodes), piece, jnp.asarray(piece_width), None), sample_times


SEGMENT_MINIMUM = 64
"""Intervals that every moving segment of a segmented interval (a cam program's turn) gets
at least, however fast its follower: a short rise sampled by a handful of intervals would
read its peaks off a coarse interpolant of its motion."""

SEGMENT_PIECE_MINIMUM = 4
"""Intervals that every piece of a segment (a law's smooth piece, or a dwell) gets at least."""

SEGMENTED_MINIMUM = 256
"""Intervals per unit (a turn) of a segmented interval's grid at least."""


class GridSegment(NamedTuple):
    """One segment of a segmented interval: from ``start`` over ``width`` (fractions of the
    interval), cut at its law's ``breakpoints`` (fractions of the segment; ``None`` for a
    segment whose forcing is flat, such as a dwell: one piece, no segment minimum)."""

    start: float
    width: float
    breakpoints: tuple[float, ...] | None


class SegmentLayout(NamedTuple):
    """Pieces of a segmented interval: ``edges`` (``(P + 1,)``, from 0 to 1), interval
    ``counts`` (``(P,)``) and the index of each segment's first piece (``first_piece``)."""

    edges: np.ndarray
    counts: np.ndarray
    first_piece: np.ndarray

    @property
    def intervals(self) -> int:
        return int(self.counts.sum())

    @property
    def segment_start(self) -> np.ndarray:
        """The interval index where each segment starts."""
        return np.concatenate([[0], np.cumsum(self.counts)])[self.first_piece]

    def grid(self):
        """``piecewise_grid`` of these pieces: the grid (forcing ``None``) and its sample times."""
        return piecewise_grid(self.edges, self.counts)


def segment_layout(segments: Sequence[GridSegment], vibrations: float,
                   phase_step: float = TARGET_PHASE_STEP) -> SegmentLayout:
    """Interval counts of an interval cut into segments (a cam program's turn), for a
    forcing that vibrates ``vibrations`` times over it.

    The interval gets ``default_resolution(vibrations, phase_step)`` intervals per unit
    (``w h <= phase_step``), or enough that its shortest moving segment gets
    ``SEGMENT_MINIMUM``, and ``SEGMENTED_MINIMUM`` at least; each piece gets its share of
    that, rounded up, and ``SEGMENT_PIECE_MINIMUM`` at least.  Check the total with
    ``check_grid_size`` before building the grid (``SegmentLayout.grid``).
    """
    shortest = min((s.width for s in segments if s.breakpoints is not None), default=1.0)
    per_unit = default_resolution(vibrations, phase_step, max(SEGMENT_MINIMUM / shortest, SEGMENTED_MINIMUM))
    edges, counts, first_piece = [0.0], [], []
    for segment in segments:
        s0, f = segment.start, segment.width
        local = [0.0, 1.0] if segment.breakpoints is None else [0.0, *segment.breakpoints, 1.0]
        first_piece.append(len(counts))
        for a, b in zip(local[:-1], local[1:]):
            edges.append(s0 + f * b)
            counts.append(max(SEGMENT_PIECE_MINIMUM, math.ceil(per_unit * f * (b - a))))
    edges[-1] = 1.0
    return SegmentLayout(np.asarray(edges), np.asarray(counts), np.asarray(first_piece, dtype=int))


PIECE_BLOCK = 8
"""Sampled laws pad their piece count to a multiple of this (SCCA laws have 8 pieces,
polynomials 1): laws of every type then share a handful of grid shapes."""


class SampledLaw(eqx.Module):
    """A concrete law as the exact path reads it: its grid as data, and its ``Ca``.

    A law's own grid is built while tracing and baked into each compiled program as
    constants, so every law type (and every law with fixed breakpoints) compiles its own
    program.  Sampled first, laws differ only in array values: one compiled program serves
    all of them (the seven standard laws in one compile instead of three).
    """

    grid: MotionGrid
    Ca: jax.Array

    @classmethod
    def of(cls, law: AbstractMotionLaw, resolution: int, pieces: int | None = None) -> SampledLaw:
        """Sample ``law`` (concrete, fixed breakpoints) on its grid of ``resolution``,
        its pieces padded to ``pieces`` (default: ``padded_pieces(law)``).

        The last ``SAMPLED_LAWS_KEPT`` samplings are kept, keyed by the law's values: a
        warm ``ct_curve`` of a law swept before skips its sampling (0.6 ms of about 6).
        """
        pieces = pieces or cls.padded_pieces(law)
        key = (law_value_key(law), int(resolution), pieces)
        if key in _SAMPLED:  # checked when it was sampled
            _SAMPLED.move_to_end(key)
            return _SAMPLED[key]
        breakpoints = law.breakpoints()
        if pieces < len(breakpoints) + 1:
            raise ValueError(f"{law.name} has {len(breakpoints) + 1} pieces, more than {pieces}")
        grid, times = _layout(breakpoints, resolution, pieces)
        forcing, ca = _sample(law, times)  # one small program per law type, not per value
        grid = grid._replace(piece=jnp.asarray(grid.piece, dtype=jnp.int32), forcing=forcing)
        _SAMPLED[key] = sampled = cls(grid, ca)
        if len(_SAMPLED) > SAMPLED_LAWS_KEPT:
            _SAMPLED.popitem(last=False)
        return sampled

    @staticmethod
    def padded_pieces(law: AbstractMotionLaw) -> int:
        """The law's piece count rounded up to a multiple of ``PIECE_BLOCK``."""
        pieces = SampledLaw.pieces_if_sampled(law)
        if pieces is None:
            raise ValueError(f"{getattr(law, 'name', law)!r} cannot be sampled: it is not a motion "
                             "law with fixed breakpoints")
        return pieces

    @staticmethod
    def accepts(law) -> bool:
        """Whether ``law`` can be sampled: a motion law whose breakpoints are fixed."""
        return SampledLaw.pieces_if_sampled(law) is not None

    @staticmethod
    def pieces_if_sampled(law) -> int | None:
        """``padded_pieces(law)`` if ``law`` can be sampled, else ``None``: one call to the
        law's breakpoints for both questions."""
        if not isinstance(law, AbstractMotionLaw):
            return None
        breakpoints = law.breakpoints()
        if not isinstance(breakpoints, tuple):
            return None
        return PIECE_BLOCK * -(-(len(breakpoints) + 1) // PIECE_BLOCK)


SAMPLED_LAWS_KEPT = 32
"""Samplings ``SampledLaw.of`` keeps (least recently used dropped first)."""
_SAMPLED: OrderedDict = OrderedDict()


def law_value_key(law: AbstractMotionLaw):
    """A hashable key equal for laws of one structure and equal values (concrete): what a
    cache of anything computed from a law is keyed by (not its name, which two laws of
    different values may share)."""
    leaves, structure = jax.tree.flatten(law)
    values = tuple((x.dtype.str, x.shape, x.tobytes()) if isinstance(x, np.ndarray) else x
                   for x in (np.asarray(leaf) if eqx.is_array(leaf) else leaf for leaf in leaves))
    return structure, values


@eqx.filter_jit
def _sample(law: AbstractMotionLaw, times):
    """Forcing coefficients at the Gauss points ``times``, and ``Ca``, in one program
    (evaluated op by op, a law's formulas compile dozens of tiny programs)."""
    return to_monomial(law.a(times)), jnp.asarray(law.Ca, dtype=float)
