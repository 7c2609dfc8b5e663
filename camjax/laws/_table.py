"""A motion law fitted to points: a quintic spline through (or near) a lift table.

The fit is a B-spline of degree 5 with a knot at every point (``spline_fit``), so the jerk
is continuous and the acceleration is a smooth cubic between points.  Interpolating, it
passes through every point; smoothing, it minimises the jerk energy ``int j^2`` while
staying within a stated distance of every point (the penalty found by bisection).  The
law keeps the spline as one degree-5 polynomial per piece (Taylor coefficients about the
piece's midpoint): its ``s, v, a, j`` are the spline's own, exactly.
"""

from __future__ import annotations

import dataclasses
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import Breakpoints, LawValues
from ._base import AbstractSearchedPeaksLaw, float_leaf
from ._spline import _basis, _derivative_matrix, max_abs_piecewise

DEGREE = 5
MIN_TABLE_POINTS = DEGREE + 1
MAX_TABLE_POINTS = 4000
"""Most points of one table: the fit solves a dense system of about that many unknowns."""
_LOG_PENALTY = (-14.0, 12.0)  # bisection range of log10 of the relative penalty
_BISECTIONS = 30


@dataclasses.dataclass(frozen=True, eq=False)
class TableFit:
    """Where a ``TableLaw`` came from and how well it fits (lengths in mm, angles in degrees).

    ``points``: the table's ``(angle_deg, lift_mm)`` rows that the law covers, angles from
    the law's start; ``deviation_mm``: the fit's largest distance from them;
    ``smoothing_mm``: the tolerance it was smoothed to (``None``: interpolating);
    ``noise_mm``: the points' scatter (``noise_estimate``);
    ``acceleration_ratio``: the fit's peak acceleration over that of a fit smoothed to
    three times the scatter (near 1 where the points' noise does not reach the
    acceleration); ``spacing_ratio``: the same over a fit through every other point (near
    1 where the spacing resolves the acceleration).  ``source``: the file or ``points``;
    ``turn``: the whole turn's points where the law is a piece of a periodic table.
    """

    points: tuple
    deviation_mm: float
    smoothing_mm: float | None = None
    noise_mm: float = 0.0
    acceleration_ratio: float = 1.0
    spacing_ratio: float = 1.0
    source: str = "points"
    turn: tuple | None = None
    """A piece of a whole cam's periodic table: that table's points (the program writes it back)."""

    # A record, not a part of the law's function: every record compares equal, so that laws
    # of the same knots share their compiled code (it is a static field of ``TableLaw``).
    def __eq__(self, other):
        return isinstance(other, TableFit)

    def __hash__(self):
        return hash(TableFit)


class TableLaw(AbstractSearchedPeaksLaw):
    """A rise given by points: ``s(tau)`` a piecewise quintic with continuous jerk.

    ``edges`` (static, ``0 = edges[0] < ... < edges[-1] = 1``) are the spline's knots and
    the law's breakpoints; ``coefficients`` (``(pieces, 6)``, a leaf) are each piece's
    Taylor coefficients in ``tau - midpoint``.  Build one with ``TableLaw.fit`` (or a
    program's ``law = "table"``); ``fit`` records the points and the fit's deviation.
    """

    coefficients: jax.Array
    edges: tuple = eqx.field(static=True)
    fit_info: TableFit | None = eqx.field(static=True, default=None)

    def __init__(self, coefficients, edges, fit_info: TableFit | None = None):
        self.coefficients = float_leaf(coefficients, "TableLaw coefficients")
        self.edges = tuple(float(x) for x in edges)
        self.fit_info = fit_info

    def __check_init__(self):
        edges = np.asarray(self.edges)
        if edges.size < 2 or edges[0] != 0.0 or edges[-1] != 1.0 or np.any(np.diff(edges) <= 0):
            raise ValueError("TableLaw edges must increase from 0 to 1")
        if jnp.shape(self.coefficients) != (edges.size - 1, DEGREE + 1):
            raise ValueError(f"TableLaw coefficients must have shape ({edges.size - 1}, {DEGREE + 1}), "
                             f"got {jnp.shape(self.coefficients)}")

    @property
    def name(self) -> str:
        return f"table:{len(self.edges)}"

    @classmethod
    def fit(cls, angle_deg, lift_mm, smoothing_mm: float | None = None, lift: float | None = None,
            source: str = "points") -> TableLaw:
        """The law of a table rising from rest to rest: ``angle_deg`` from 0 to the rise's
        angle, ``lift_mm`` the lift there.  The spline passes through the first point and
        ``lift`` (default: the last point's lift) above it, with ``v = a = 0`` at both ends,
        and through every other point (``smoothing_mm=None``) or within ``smoothing_mm`` of
        it with the least jerk energy.  ``ValueError`` where a tolerance cannot be met."""
        x, y = np.asarray(angle_deg, float), np.asarray(lift_mm, float)
        beta = x[-1] - x[0]
        tau = (x - x[0]) / beta
        y0 = y[0]
        rise = y[-1] - y0 if lift is None else float(lift)
        if rise == 0:
            raise ValueError("the table's last lift equals its first: a rise needs a lift")
        curve, deviation = spline_fit(tau, y, smoothing_mm, ends=(y0, y0 + rise), angle_scale=beta)
        edges, taylor = curve
        coefficients = (taylor - np.eye(1, DEGREE + 1)[0] * y0) / rise
        info = table_checks(tau, y, smoothing_mm, deviation, taylor, ends=(y0, y0 + rise))
        info = dataclasses.replace(info, points=tuple(zip(map(float, x - x[0]), map(float, y))), source=source)
        return cls(coefficients, edges, info)

    def rise(self, tau) -> LawValues:
        return _table_rise(self, tau)

    def _derivatives(self, tau):
        edges = np.asarray(self.edges)
        tau = jnp.asarray(tau, dtype=float)
        k = jnp.clip(jnp.searchsorted(jnp.asarray(edges), tau, side="right") - 1, 0, edges.size - 2)
        u = tau - jnp.asarray(0.5 * (edges[:-1] + edges[1:]))[k]
        c = jnp.asarray(self.coefficients)[k]
        out = []
        for order in range(4):
            terms = [math.perm(m, order) * c[..., m] for m in range(order, DEGREE + 1)]
            value = terms[-1]
            for term in reversed(terms[:-1]):  # Horner in u
                value = value * u + term
            out.append(value)
        return tuple(out)

    def breakpoints(self) -> Breakpoints:
        return self.edges[1:-1]

    def peak(self, order: int):
        return _table_peak(self, order)


@eqx.filter_jit
def _table_rise(law: TableLaw, tau) -> LawValues:
    return law._derivatives(tau)


@eqx.filter_jit
def _table_peak(law: TableLaw, order: int):
    return max_abs_piecewise(lambda t: law._derivatives(t)[order], np.asarray(law.edges), 8)


# -- the fit ------------------------------------------------------------------------------

def _design(knots: np.ndarray, x: np.ndarray, order: int) -> np.ndarray:
    """Rows taking B-spline coefficients to the ``order``-th derivative at ``x``."""
    matrix = _derivative_matrix(tuple(map(float, knots)), DEGREE, order)
    trimmed = knots[order: len(knots) - order]
    return np.asarray(_basis(trimmed, DEGREE - order, np.asarray(x, float))) @ matrix


def _jerk_energy(knots: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """``P`` with ``c' P c = int j^2`` over ``edges`` (3-point Gauss: ``j^2`` is a quartic)."""
    nodes, weights = np.polynomial.legendre.leggauss(3)
    mid, half = 0.5 * (edges[:-1] + edges[1:]), 0.5 * np.diff(edges)
    x = (mid[:, None] + half[:, None] * nodes).ravel()
    w = (half[:, None] * weights).ravel()
    jerk = _design(knots, x, 3)
    return jerk.T @ (w[:, None] * jerk)


def spline_fit(x, y, smoothing_mm=None, *, ends=None, period: float | None = None,
               angle_scale: float | None = None):
    """A quintic spline with knots at the points ``x`` (increasing) near the lifts ``y``.

    ``ends=(y_first, y_last)``: clamped at ``x[0]`` and ``x[-1]`` (those lifts, ``v = a = 0``
    there); ``period``: periodic over ``[x[0], x[0] + period)`` instead.  Interpolating
    where ``smoothing_mm`` is ``None``, else the least ``int j^2`` within ``smoothing_mm``
    of every point.  Returns ``((edges, taylor), deviation)``: the knots, each piece's
    Taylor coefficients about its midpoint (``(pieces, 6)``), and the largest ``|f(x) - y|``.
    ``angle_scale`` (degrees per unit of ``x``) puts the point's angle in a tolerance's error.
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    n = x.size
    if period is None:
        knots = np.concatenate([np.full(DEGREE + 1, x[0]), x[1:-1], np.full(DEGREE + 1, x[-1])])
        edges = x
        fold = np.eye(n + DEGREE - 1)
        value, slope, curve = (_design(knots, x[[0, -1]], k) for k in range(3))
        constraint = np.concatenate([value, slope, curve])
        target = np.array([ends[0], ends[1], 0, 0, 0, 0], float)
    else:
        # Knots wrapped past both ends; the first DEGREE basis functions are the last
        # DEGREE shifted by a period, so they share coefficients (``fold``).
        index = np.arange(-DEGREE, n + DEGREE + 1)
        knots = x[index % n] + period * np.floor_divide(index, n)
        edges = np.append(x, x[0] + period)
        fold = np.zeros((n + DEGREE, n))
        fold[np.arange(n + DEGREE), np.arange(n + DEGREE) % n] = 1.0
        constraint, target = np.zeros((0, n)), np.zeros(0)
    collocation = _design(knots, x, 0) @ fold
    energy = fold.T @ _jerk_energy(knots, edges) @ fold
    constraint = constraint @ fold if constraint.size else constraint
    # Every fit is c = base + Z z (``Z`` spans the end conditions' null space), z minimising
    # |A c - y|^2 + p c' E c.  With N = Z'A'AZ = L L' and L^-1 Z'EZ L^-T = U diag(d) U',
    # z(p) = L^-T U (1 + p d)^-1 U' L^-1 (g - p h): one decomposition, then each penalty
    # of the bisection is a few matrix-vector products.
    if constraint.size:
        base = np.linalg.lstsq(constraint, target, rcond=None)[0]
        _, _, vt = np.linalg.svd(constraint)
        null = vt[constraint.shape[0]:].T
    else:
        base, null = np.zeros(n), np.eye(n)
    reduced = collocation @ null
    factor = np.linalg.cholesky(reduced.T @ reduced)
    inv_factor = np.linalg.inv(factor)
    weighted = inv_factor @ (null.T @ energy @ null) @ inv_factor.T
    d, u = np.linalg.eigh(0.5 * (weighted + weighted.T))
    d = np.maximum(d, 0.0)
    g = u.T @ (inv_factor @ (reduced.T @ (y - collocation @ base)))
    h = u.T @ (inv_factor @ (null.T @ (energy @ base)))
    back = null @ inv_factor.T @ u
    positive = d[d > d.max() * 1e-12]
    scale = 1.0 / float(np.median(positive)) if positive.size else 1.0

    def solve(log_penalty: float | None):
        if log_penalty is None:  # interpolating: the points and the end conditions fix the spline
            rows = slice(1, -1) if constraint.size else slice(None)
            coefficients = np.linalg.solve(np.concatenate([collocation[rows], constraint]),
                                           np.concatenate([y[rows], target]))
        else:
            penalty = scale * 10.0**log_penalty
            coefficients = base + back @ ((g - penalty * h) / (1.0 + penalty * d))
        return coefficients, float(np.max(np.abs(collocation @ coefficients - y)))

    coefficients, deviation = solve(None)
    if smoothing_mm is not None:
        if deviation > smoothing_mm:
            k = int(np.argmax(np.abs(collocation @ coefficients - y)))
            angle = (x[k] - x[0]) * (angle_scale or 1.0)
            raise ValueError(f"smoothing_mm = {smoothing_mm:g} cannot be met: even the interpolating "
                             f"spline is {deviation:.3g} mm from point {k + 1} (angle_deg {angle:g}); "
                             "give a larger tolerance or none")
        lo, hi = _LOG_PENALTY
        best = solve(hi)
        if best[1] > smoothing_mm:
            best = (coefficients, deviation)
            for _ in range(_BISECTIONS):
                mid = 0.5 * (lo + hi)
                trial = solve(mid)
                if trial[1] <= smoothing_mm:
                    lo, best = mid, trial
                else:
                    hi = mid
        coefficients, deviation = best
    full = fold @ coefficients
    mids = 0.5 * (edges[:-1] + edges[1:])
    taylor = np.stack([_design(knots, mids, k) @ full / math.factorial(k) for k in range(DEGREE + 1)], axis=1)
    return (edges, taylor), deviation


def evaluate_pieces(edges, taylor, x, order: int = 0) -> np.ndarray:
    """The ``order``-th derivative of a piecewise polynomial (``spline_fit``'s) at ``x``, in NumPy."""
    edges, x = np.asarray(edges), np.asarray(x, float)
    k = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, edges.size - 2)
    u = x - 0.5 * (edges[:-1] + edges[1:])[k]
    out = np.zeros_like(u)
    for m in range(DEGREE, order - 1, -1):
        out = out * u + math.perm(m, order) * taylor[k, m]
    return out


def _peak_acceleration(edges, taylor) -> float:
    x = np.concatenate([np.linspace(a, b, 9) for a, b in zip(edges[:-1], edges[1:])])
    return float(np.max(np.abs(evaluate_pieces(edges, taylor, x, 2))))


def noise_estimate(x, y) -> float:
    """The points' scatter (mm): over every 7 neighbouring points, the part of ``y`` that no
    quintic through them explains (a unit null vector of their degree-5 Vandermonde matrix:
    the sixth difference over ``sqrt(924)`` for equal spacing), whose robust spread (the
    median) is ``sigma`` for independent noise and near 0 for a smooth curve sampled
    finely.  0 where those residuals are not noise's: noise gives neighbouring windows a
    correlation near -792/924 (they share six points with alternating weights); a smooth
    curve sampled coarsely gives near +1 (that is spacing, not noise: its own check)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if y.size < 3 * MIN_TABLE_POINTS:
        return 0.0
    window = np.arange(y.size - 6)[:, None] + np.arange(7)
    local = x[window] - x[window].mean(axis=1, keepdims=True)
    local /= np.max(np.abs(local), axis=1, keepdims=True)
    vandermonde = local[..., None] ** np.arange(DEGREE + 1)
    null = np.linalg.svd(vandermonde, full_matrices=True)[0][..., -1]
    null *= np.sign(null[:, -1:])  # one sign convention, as the sixth difference's +1 last
    r = np.sum(null * y[window], axis=1)
    power = float(np.sum(r * r))
    if power == 0 or float(np.sum(r[:-1] * r[1:])) / power > -0.5:
        return 0.0
    return float(np.median(np.abs(r)) / 0.6745)


def table_checks(x, y, smoothing_mm, deviation, taylor, *, ends=None, period=None) -> TableFit:
    """The fit's record with the two checks of its acceleration: against a fit smoothed to
    three times the points' scatter, and against a fit through every other point."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    edges = np.append(x, x[0] + period) if period is not None else x
    peak = _peak_acceleration(edges, taylor)
    noise = noise_estimate(x, y)
    noise = noise if noise > 1e-7 * max(1.0, float(np.ptp(y))) else 0.0
    reference_tol = max(smoothing_mm or 0.0, 3 * noise) or None
    reference = peak
    if reference_tol is not None and reference_tol != smoothing_mm:
        (_, smooth), _ = spline_fit(x, y, reference_tol, ends=ends, period=period)
        reference = _peak_acceleration(edges, smooth)
    spacing = 1.0
    if noise == 0 and x.size >= 2 * MIN_TABLE_POINTS + 1 and (period is None or x.size % 2 == 0):
        keep = np.arange(0, x.size, 2)
        if period is None and keep[-1] != x.size - 1:
            keep = np.append(keep, x.size - 1)
        (half_edges, half), _ = spline_fit(x[keep], y[keep], reference_tol, ends=ends, period=period)
        spacing = _peak_acceleration(half_edges, half) / max(reference, 1e-300)
    ratio = peak / max(reference, 1e-300)
    return TableFit(points=(), deviation_mm=float(deviation), smoothing_mm=smoothing_mm, noise_mm=noise,
                    acceleration_ratio=float(ratio), spacing_ratio=float(spacing))
