"""A motion law fitted to points: a quintic spline through (or near) a lift table.

The fit is a B-spline of degree 5 with a knot at every point (``spline_fit``), so the jerk
is continuous and the acceleration is a smooth cubic between points.  Interpolating, it
passes through every point; smoothing, it is the spline of least jerk energy ``int j^2``
within a stated distance of every point (``smoothest_within``: a quadratic programme
solved by an interior-point method).  Every matrix is sparse and banded.  The
law keeps the spline as one degree-5 polynomial per piece (Taylor coefficients about the
piece's midpoint): its ``s, v, a, j`` are the spline's own, exactly.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import Breakpoints, LawValues
from ._base import AbstractSearchedPeaksLaw, float_leaf
from ._spline import max_abs_piecewise

if TYPE_CHECKING:  # scipy is imported where a table is fitted, not when camjax starts
    import scipy.sparse as sp

DEGREE = 5
MIN_TABLE_POINTS = DEGREE + 1
MAX_TABLE_POINTS = 4000
"""Most points of one table: each point is a piece of the law, which the engine's grid and
peak searches visit (the fit itself is sparse, about 2 s at 4000 points)."""
_INTERIOR_STEPS = 100
"""Most steps of the smoothing fit's interior-point search (it converges in a few tens)."""


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
    spacing_check: str = "a fit through every other point"
    """What ``spacing_ratio`` compares with; its ratio is NaN where the table has too few
    points to drop every other one."""
    notes: tuple = ()
    """Lines for the report's warnings: what was read from a drawing, and how."""

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

def _derivative_operator(knots: np.ndarray, order: int) -> sp.csr_matrix:
    """Sparse map from B-spline coefficients to those of the ``order``-th derivative (a
    spline of degree ``DEGREE - order`` on ``knots[order:-order]``)."""
    import scipy.sparse as sp
    operator = sp.identity(len(knots) - DEGREE - 1, format="csr")
    for r in range(order):
        p = DEGREE - r
        t = knots[r: len(knots) - r]
        m = len(t) - p - 1
        span = t[p + 1: p + m] - t[1:m]
        w = np.where(span > 0, p / np.where(span > 0, span, 1.0), 0.0)
        operator = sp.diags([-w, w], [0, 1], shape=(m - 1, m), format="csr") @ operator
    return operator.tocsr()


def _design(knots: np.ndarray, x: np.ndarray, order: int) -> sp.csr_matrix:
    """Sparse rows taking B-spline coefficients to the ``order``-th derivative at ``x``."""
    from scipy.interpolate import BSpline
    trimmed = knots[order: len(knots) - order]
    basis = BSpline.design_matrix(np.asarray(x, float), trimmed, DEGREE - order)
    return (basis @ _derivative_operator(knots, order)).tocsr()


def _weighted_jerk(knots: np.ndarray, edges: np.ndarray) -> sp.csr_matrix:
    """``L`` with ``|L c|^2 = int j^2`` over ``edges``: the jerk at 3 Gauss nodes a piece,
    each row times its weight's root (exact: ``j^2`` is a quartic); banded."""
    import scipy.sparse as sp
    nodes, weights = np.polynomial.legendre.leggauss(3)
    mid, half = 0.5 * (edges[:-1] + edges[1:]), 0.5 * np.diff(edges)
    x = (mid[:, None] + half[:, None] * nodes).ravel()
    w = (half[:, None] * weights).ravel()
    return (sp.diags(np.sqrt(w)) @ _design(knots, x, 3)).tocsr()


def _solve(matrix, rhs) -> np.ndarray:
    """A sparse square system by LU (SuperLU); ``None`` where it is singular."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import splu
    try:
        out = splu(sp.csc_matrix(matrix)).solve(np.asarray(rhs, float))
    except RuntimeError:  # "Factor is exactly singular"
        return None
    return out if np.all(np.isfinite(out)) else None


def spline_fit(x, y, smoothing_mm=None, *, ends=None, period: float | None = None,
               angle_scale: float | None = None):
    """A quintic spline with knots at the points ``x`` (increasing) near the lifts ``y``.

    ``ends=(y_first, y_last)``: clamped at ``x[0]`` and ``x[-1]`` (those lifts, ``v = a = 0``
    there); ``period``: periodic over ``[x[0], x[0] + period)`` instead.  Interpolating
    where ``smoothing_mm`` is ``None``, else the least ``int j^2`` within ``smoothing_mm``
    of every point (``smoothest_within``).  Returns ``((edges, taylor), deviation)``: the
    knots, each piece's Taylor coefficients about its midpoint (``(pieces, 6)``), and the
    largest ``|f(x) - y|``.  ``angle_scale`` (degrees per unit of ``x``) puts the point's
    angle in a tolerance's error.  Every matrix is sparse (banded): time and memory grow
    as the number of points.
    """
    import scipy.sparse as sp
    x, y = np.asarray(x, float), np.asarray(y, float)
    n = x.size
    if period is None:
        knots = np.concatenate([np.full(DEGREE + 1, x[0]), x[1:-1], np.full(DEGREE + 1, x[-1])])
        edges = x
        fold = sp.identity(n + DEGREE - 1, format="csr")
        constraint = sp.vstack([_design(knots, x[[0, -1]], k) for k in range(3)]).tocsr()
        target = np.array([ends[0], ends[1], 0, 0, 0, 0], float)
        boxed = np.arange(1, n - 1)  # the end points are the end conditions'
    else:
        # Knots wrapped past both ends; the first DEGREE basis functions are the last
        # DEGREE shifted by a period, so they share coefficients (``fold``).
        index = np.arange(-DEGREE, n + DEGREE + 1)
        knots = x[index % n] + period * np.floor_divide(index, n)
        edges = np.append(x, x[0] + period)
        rows = np.arange(n + DEGREE)
        fold = sp.csr_matrix((np.ones(rows.size), (rows, rows % n)), shape=(n + DEGREE, n))
        constraint, target = sp.csr_matrix((0, n)), np.zeros(0)
        boxed = np.arange(n)
    collocation = (_design(knots, x, 0) @ fold).tocsr()
    constraint = (constraint @ fold).tocsr() if period is None else constraint
    interpolating = sp.vstack([collocation[boxed], constraint])
    coefficients = _solve(interpolating, np.concatenate([y[boxed], target]))
    if coefficients is None:
        raise ValueError("the points do not determine an interpolating spline (angles too close together)")
    residual = collocation @ coefficients - y
    deviation = float(np.max(np.abs(residual)))
    if smoothing_mm is not None:
        if deviation > smoothing_mm:
            k = int(np.argmax(np.abs(residual)))
            angle = (x[k] - x[0]) * (angle_scale or 1.0)
            raise ValueError(f"smoothing_mm = {smoothing_mm:g} cannot be met: even the interpolating "
                             f"spline is {deviation:.3g} mm from point {k + 1} (angle_deg {angle:g}); "
                             "give a larger tolerance or none")
        jerk = (_weighted_jerk(knots, edges) @ fold).tocsr()
        coefficients = smoothest_within(jerk, collocation, y, smoothing_mm, constraint, target, boxed)
        deviation = float(np.max(np.abs(collocation @ coefficients - y)))
    full = fold @ coefficients
    mids = 0.5 * (edges[:-1] + edges[1:])
    taylor = np.stack([_design(knots, mids, k) @ full / math.factorial(k) for k in range(DEGREE + 1)], axis=1)
    return (edges, taylor), deviation


def _saddle(hessian, blocks) -> sp.csr_matrix:
    """The KKT matrix ``[[H, B'], [B, 0]]`` of ``H`` under the constraint rows ``B`` (the
    non-empty ``blocks`` stacked)."""
    import scipy.sparse as sp
    rows = [b for b in blocks if b.shape[0]]
    if not rows:
        return hessian
    b = sp.vstack(rows).tocsr()
    return sp.bmat([[hessian, b.T], [b, None]]).tocsr()


def smoothest_within(jerk, collocation, y, tolerance: float, constraint, target, boxed) -> np.ndarray:
    """The coefficients ``c`` of least ``c' E c = |L c|^2`` (the jerk energy, ``L`` the
    weighted ``jerk`` rows) with every boxed point within ``tolerance``, ``|(A c)_i - y_i|
    <= tolerance``, and ``C c = target``.  The energy's gradient is taken as ``L' (L c)``,
    not ``E c``: with thousands of points the jerk energy of a smooth lift is far below the
    round-off of ``E c``'s cancelling terms.

    A convex quadratic programme, solved by a primal-dual interior-point method (Mehrotra's
    predictor-corrector): each step solves one sparse banded KKT system ``[[E + A' W A,
    C'], [C, 0]]``, and some twenty steps reach the KKT conditions to round-off.  It
    starts from the least-squares spline through the points (inside every band).
    ``ValueError`` where it does not converge (the message says so).
    """
    import scipy.sparse as sp
    a = collocation[boxed].tocsr()
    yb = y[boxed]
    energy = (jerk.T @ jerk).tocsr()
    unit = float(energy.diagonal().mean())
    e = (energy / unit).tocsr()
    lower = (jerk / math.sqrt(unit)).tocsr()

    def gradient(c):
        return lower.T @ (lower @ c)

    k, m = e.shape[0], yb.size
    g = sp.vstack([a, -a]).tocsr()
    h = np.concatenate([yb + tolerance, tolerance - yb])
    start = _solve(_saddle(a.T @ a + 1e-12 * sp.identity(k), [constraint]), np.concatenate([a.T @ yb, target]))
    if start is None:
        raise ValueError(f"smoothing_mm = {tolerance:g}: the points do not determine a spline")
    c = start[:k]
    s = np.maximum(h - g @ c, 1e-3 * tolerance)
    z = np.ones(2 * m) * max(1e-12, float(np.max(np.abs(gradient(c))))) / tolerance
    mu_eq = np.zeros(constraint.shape[0])

    def direction(r_d, r_p, r_i, r_c):
        w = z / s
        matrix = _saddle((e + g.T @ sp.diags(w) @ g).tocsr(), [constraint])
        rhs = np.concatenate([-r_d - g.T @ ((-r_c + z * r_i) / s), -r_p])
        out = _solve(matrix, rhs)
        if out is None:
            return None
        dc, dmu = out[:k], out[k:]
        ds = -r_i - g @ dc
        dz = (-r_c - z * ds) / s
        return dc, ds, dz, dmu

    def step_to_boundary(v, dv):
        shrinking = dv < 0
        return min(1.0, float(np.min(-v[shrinking] / dv[shrinking]))) if shrinking.any() else 1.0

    for _ in range(_INTERIOR_STEPS):
        r_d = gradient(c) + g.T @ z + (constraint.T @ mu_eq if mu_eq.size else 0.0)
        r_p = constraint @ c - target if mu_eq.size else np.zeros(0)
        r_i = g @ c + s - h
        gap = float(s @ z) / s.size
        # Judged against the energy's gradient now, not at the start's: the noise's jerk
        # makes that some ten orders of magnitude larger than the answer's.  The dual
        # residual stalls at round-off (a few per cent of the gradient at 4000 points)
        # while the complementarity gap still falls; the gap decides.
        scale_d = float(np.max(np.abs(gradient(c)))) + 1e-300
        if (np.max(np.abs(r_d)) <= 0.1 * scale_d and np.max(np.abs(r_i), initial=0.0) <= 1e-12 * float(np.max(np.abs(h)))
                and gap <= 1e-12 * scale_d * tolerance):
            break
        affine = direction(r_d, r_p, r_i, s * z)
        if affine is None:
            break
        alpha = min(step_to_boundary(s, affine[1]), step_to_boundary(z, affine[2]))
        sigma = (float((s + alpha * affine[1]) @ (z + alpha * affine[2])) / s.size / gap) ** 3
        step = direction(r_d, r_p, r_i, s * z + affine[1] * affine[2] - sigma * gap)
        if step is None:
            break
        dc, ds, dz, dmu = step
        alpha = 0.99 * min(step_to_boundary(s, ds), step_to_boundary(z, dz))
        c, s, z = c + alpha * dc, s + alpha * ds, z + alpha * dz
        mu_eq = mu_eq + alpha * dmu
    slack = 1e-9 * tolerance + 1e-12 * float(np.max(np.abs(y)))
    if not np.all(np.isfinite(c)) or np.max(np.abs(collocation @ c - y)) > tolerance + slack:
        raise ValueError(f"smoothing_mm = {tolerance:g}: the smoothest spline within it was not found "
                         "(the interior-point search did not converge); give a slightly different tolerance")
    return c


def evaluate_pieces(edges, taylor, x, order: int = 0) -> np.ndarray:
    """The ``order``-th derivative of a piecewise polynomial (``spline_fit``'s) at ``x``, in NumPy."""
    edges, x = np.asarray(edges), np.asarray(x, float)
    k = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, edges.size - 2)
    u = x - 0.5 * (edges[:-1] + edges[1:])[k]
    out = np.zeros_like(u)
    for m in range(DEGREE, order - 1, -1):
        out = out * u + math.perm(m, order) * taylor[k, m]
    return out


def peak_acceleration(edges, taylor) -> float:
    """The largest ``|f''|`` of ``spline_fit``'s pieces (sampled 9 to a piece)."""
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


def table_checks(x, y, smoothing_mm, deviation, taylor, *, ends=None, period=None,
                 check_spacing: bool = True) -> TableFit:
    """The fit's record with the two checks of its acceleration: against a fit smoothed to
    three times the points' scatter, and (``check_spacing``) against a fit through every
    other point (NaN where too few points are left for a spline)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    edges = np.append(x, x[0] + period) if period is not None else x
    peak = peak_acceleration(edges, taylor)
    noise = noise_estimate(x, y)
    noise = noise if noise > 1e-7 * max(1.0, float(np.ptp(y))) else 0.0
    reference_tol = max(smoothing_mm or 0.0, 3 * noise) or None
    reference = peak
    if reference_tol is not None and reference_tol != smoothing_mm:
        (_, smooth), _ = spline_fit(x, y, reference_tol, ends=ends, period=period)
        reference = peak_acceleration(edges, smooth)
    spacing = 1.0
    keep = np.arange(0, x.size, 2)
    if period is None and keep[-1] != x.size - 1:
        keep = np.append(keep, x.size - 1)
    if noise == 0 and check_spacing:
        if keep.size < MIN_TABLE_POINTS:
            spacing = math.nan
        else:
            (half_edges, half), _ = spline_fit(x[keep], y[keep], reference_tol, ends=ends, period=period)
            spacing = peak_acceleration(half_edges, half) / max(reference, 1e-300)
    ratio = peak / max(reference, 1e-300)
    return TableFit(points=(), deviation_mm=float(deviation), smoothing_mm=smoothing_mm, noise_mm=noise,
                    acceleration_ratio=float(ratio), spacing_ratio=float(spacing))
