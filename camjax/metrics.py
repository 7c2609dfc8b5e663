"""Response metrics: refined peaks, torsion-factor envelope fits and Ca*Ct crossovers."""

from __future__ import annotations

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp
import numpy as np


@functools.cache
def _hermite_matrix(order: int) -> np.ndarray:
    """Monomial coefficients on ``sigma in [0, 1]`` from ``f, f', ..., f^(order)`` at 0 and 1
    (the interpolant of degree ``2 order + 1``: a septic for order 3)."""
    degree = 2 * order + 1
    basis = np.polynomial.Polynomial.basis
    rows = [
        [basis(m).deriv(d)(end) for m in range(degree + 1)]
        for end in (0.0, 1.0)
        for d in range(order + 1)
    ]
    return np.linalg.inv(np.array(rows))


def _polynomial(c, x):
    """Value, first and second derivative of ``sum_m c[..., m] x^m`` (Horner)."""
    p = dp = ddp = jnp.zeros_like(x)
    for m in range(c.shape[-1] - 1, -1, -1):
        ddp = ddp * x + 2 * dp
        dp = dp * x + p
        p = p * x + c[..., m]
    return p, dp, ddp


def _interval_peak(coefficients):
    """``max |p(sigma)|`` over ``[0, 1]`` for polynomials with one extremum at most inside
    (``_peak_and_location``'s peak)."""
    return _peak_and_location(coefficients)[0]


def _peak_and_location(coefficients):
    """``max |p(sigma)|`` over ``[0, 1]`` and the ``sigma`` where it is reached.

    Nine samples pick a start; three clipped Newton steps on ``p'`` then polish it (from
    within 1/16 of an interval of the extremum, the third step changes nothing at double
    precision).  The location carries no gradient (envelope theorem).
    """
    samples = jnp.linspace(0.0, 1.0, 9)
    values = jnp.abs(_polynomial(coefficients[..., None, :], samples)[0])
    start = jax.lax.stop_gradient(samples[jnp.argmax(values, axis=-1)])

    sigma = start
    for _ in range(3):  # unrolled: a loop costs more to compile than three steps
        _, dp, ddp = _polynomial(coefficients, sigma)
        safe = jnp.where(ddp != 0, ddp, 1.0)
        sigma = jnp.clip(jnp.where(ddp != 0, sigma - dp / safe, sigma), 0.0, 1.0)
    sigma = jax.lax.stop_gradient(sigma)
    polished = jnp.abs(_polynomial(coefficients, sigma)[0])
    sampled = jnp.max(values, axis=-1)
    return jnp.maximum(polished, sampled), jnp.where(polished >= sampled, sigma, start)


def refined_peak(value, widths, left, right):
    """``max |f(t)|`` of a sampled signal, refined between samples.

    Args:
        value: ``(K + 1,)`` samples of a continuous signal ``f`` at the nodes.
        widths: ``(K,)`` interval widths.
        left, right: ``(K, 3)`` first three derivatives of ``f`` at each interval's left
            and right end, as limits from inside the interval (``f`` may kink at nodes);
            ``(K, 5)``, five derivatives, give an interpolant of degree 11 instead.

    Every interval gets a septic Hermite interpolant (error about ``(w h)^8 / 1e7`` for a
    vibration of angular frequency ``w``; of degree 11: ``(w h)^12 / 2e12``) whose maximum
    is polished by Newton's method.
    All intervals, not only those next to the largest samples: where many crests are
    nearly equal (a long rise at a high period ratio) the sampling loss between nodes (up
    to ``1 - cos(w h / 2)``) reorders them, and the true peak may sit in any of them.
    Dense, so cheap to compile; ``peak_search`` gives the same answer refining only the
    intervals that can hold the peak, which pays where one program runs many times.
    """
    return jnp.max(_interval_peak(septic_coefficients(value, widths, left, right)))


PEAK_GROUP = 8
"""Intervals per group of ``peak_search``'s bounds: each step looks at the groups' largest
bounds first, then at the intervals of the groups it picked."""
PEAK_INTERVALS_PER_STEP = 1
"""Intervals that each step of ``peak_search`` refines, the best of one group each.  One:
with plateaus' bounds exact (``camjax.sdof.plateau_bound``), one or two steps
settle most peaks, and a smaller step ran the kernel 1.03-1.13x faster than four (2-core
CPU, 2026-11-26)."""


PEAK_TOLERANCE = 1e-11
"""Relative margin within which ``peak_search`` leaves an interval unrefined: one whose
bound is at most ``1 + PEAK_TOLERANCE`` times the best value found cannot change the
answer by more than that.  A bound that is exact for equal crests (an undamped
constant-acceleration piece: ``camjax.sdof.plateau_bound``) then closes them
after the first, where rounding (about 2e-12) would otherwise leave every one open."""


def peak_search(bound, hermite_of, largest_sample, tolerance: float = 0.0):
    """``max |p|`` over the intervals of a signal, each interval's septic ``p`` refined only
    where its bound says it could beat the best value found so far.

    Args:
        bound: ``(K,)`` upper bounds of ``|f|`` on each interval (``bernstein_bound``).
        hermite_of: ``index -> (len(index), 8)`` Hermite data (``hermite_data``) of those
            intervals, computed only for the intervals refined: the signal's derivatives
            need not exist on every interval at once.  Data of a higher order (``2 order +
            2`` columns, derivatives up to ``order`` at each end) gives a Hermite
            interpolant of degree ``2 order + 1`` instead of the septic.
        largest_sample: ``max |f|`` over the nodes.
        tolerance: relative margin: an interval whose bound is within it of the best value
            found is left alone (``PEAK_TOLERANCE`` for bounds that can be exact).

    Each step refines (nine samples, then Newton's method on the interpolant) the interval of
    largest bound in each of the ``PEAK_INTERVALS_PER_STEP`` groups of ``PEAK_GROUP``
    whose bounds are largest, until no bound beats the best value (by more than
    ``tolerance``).  The standard laws need one step at most ratios; plateaus (equal
    crests) a few, or one with bounds exact at their crests.  An interval left alone
    cannot hold a larger value (by more than ``tolerance``), so the answer is that of
    refining every interval.  The search carries no gradient: the answer is the septic of the winning interval at the
    location found (or the largest sample), and so is its gradient (the dense maximum's,
    but for ties within ``tolerance``, where it goes to the interval refined first: the
    equal crests of an undamped plateau tie in value, not in their derivatives, so there
    the derivative in the damping ratio is one crest's, as a kink's can only be).
    """
    size = bound.shape[0]
    group_size = min(PEAK_GROUP, size)
    groups = -(-size // group_size)
    picks = min(PEAK_INTERVALS_PER_STEP, groups)

    def coefficients(index):
        data = hermite_of(index)
        matrix = jnp.asarray(_hermite_matrix(data.shape[-1] // 2 - 1).T)
        return jnp.dot(data, matrix, precision=jax.lax.Precision.HIGHEST)

    def unfinished(state):
        best, _, _, open_bound = state
        return jnp.max(open_bound) > best * (1 + tolerance)

    def refine_next(state):
        best, winner, location, open_bound = state
        by_group = open_bound.reshape(groups, group_size)
        group_bound = jnp.max(by_group, axis=1)
        chosen = []
        for _ in range(picks):  # once few groups are open, some are picked twice: harmless
            chosen.append(jnp.argmax(group_bound))
            group_bound = jnp.where(jnp.arange(groups) == chosen[-1], -jnp.inf, group_bound)
        chosen = jnp.stack(chosen)
        index = chosen * group_size + jnp.argmax(by_group[chosen], axis=1)
        refined = (jnp.arange(groups * group_size) == index[:, None]).any(axis=0)
        peaks, where = _peak_and_location(jax.lax.stop_gradient(coefficients(index)))
        top = jnp.argmax(peaks)  # a NaN first: then it wins, and the answer is NaN
        better = (peaks[top] > best) | jnp.isnan(peaks[top])
        return (jnp.where(better, peaks[top], best), jnp.where(better, index[top], winner),
                jnp.where(better, where[top], location),
                jnp.where(refined, -jnp.inf, open_bound))

    # A bound a few ulp high keeps rounding from leaving out an interval that ties.
    slack = 1 + 64 * jnp.finfo(bound.dtype).eps
    bound = jax.lax.stop_gradient(jnp.where(jnp.isnan(bound), jnp.inf, bound * slack))
    padded = jnp.pad(bound, (0, groups * group_size - size), constant_values=-jnp.inf)
    start = (jax.lax.stop_gradient(largest_sample), jnp.zeros((), int),
             jnp.zeros((), largest_sample.dtype), padded)
    _, winner, location, _ = jax.lax.while_loop(unfinished, refine_next, start)
    found = _polynomial(coefficients(winner[None])[0], location)[0]
    return jnp.maximum(jnp.abs(found), largest_sample)


def bounded_peak(values, widths, left, right):
    """``refined_peak``'s answer (within ``PEAK_TOLERANCE``) by ``peak_search``: only the
    intervals whose Bernstein bound can beat the best value found are refined.  For a
    program run many times over long grids (a cam's turn at every speed of an edit), where
    the dense refinement of every interval costs more than the propagation."""
    bound = bernstein_bound(values, widths, tuple(left.T), tuple(right.T))
    data = hermite_data(values, widths, left, right)
    return peak_search(bound, lambda index: data[index], jnp.max(jnp.abs(values)), PEAK_TOLERANCE)


def bounded_max(values, widths, left, right):
    """``max f`` (signed) between the nodes, by ``bounded_peak`` of the signal shifted below
    its smallest node value (so that ``|f - shift| = f - shift``)."""
    low = jnp.min(values)
    shift = low - (jnp.max(values) - low) - 1.0
    return bounded_peak(values - shift, widths, left, right) + shift


def bounded_extremes(values, widths, left, right):
    """``(min f, max f)`` between the nodes by ``bounded_max``: ``refined_extremes``'s
    answer, refining only the intervals that can hold an extreme."""
    return -bounded_max(-values, widths, -left, -right), bounded_max(values, widths, left, right)


def bernstein_bound(value, widths, left, right):
    """``(K,)`` bounds of ``|p|`` over each interval for its septic Hermite interpolant
    ``p``: the largest of its Bernstein coefficients, in whose convex hull the polynomial
    lies.  ``b_0..b_3`` follow from the left end's derivatives, ``b_4..b_7`` from the
    right's.  Arguments as ``refined_peak``'s, but ``left`` and ``right`` as three
    ``(K,)`` arrays each (``left.T``): columns of a ``(K, 3)`` array are strided, and
    separate arrays need never be stored."""
    h = widths
    d1, d2, d3 = left[0] * h, left[1] * (h * h), left[2] * (h * h * h)
    e1, e2, e3 = right[0] * h, right[1] * (h * h), right[2] * (h * h * h)
    b0, b7 = value[:-1], value[1:]
    b1 = b0 + d1 * (1 / 7)
    b2 = d2 * (1 / 42) + 2 * b1 - b0
    b3 = d3 * (1 / 210) + 3 * (b2 - b1) + b0
    b6 = b7 - e1 * (1 / 7)
    b5 = e2 * (1 / 42) + 2 * b6 - b7
    b4 = b7 + 3 * (b5 - b6) - e3 * (1 / 210)
    bound = jnp.abs(b0)
    for b in (b1, b2, b3, b4, b5, b6, b7):
        bound = jnp.maximum(bound, jnp.abs(b))
    return bound


def hermite_data(value, widths, left, right, right_value=None):
    """``(K, 8)``: each interval's septic Hermite data in ``sigma`` (``t = t_k + sigma
    h_k``): the value and first three derivatives at ``sigma = 0``, then at ``sigma = 1``
    (``value`` holds the ``K + 1`` node values, or the left ends' with ``right_value``);
    ``(K, 2 m + 2)`` for ``m`` derivatives in ``left`` and ``right``."""
    if right_value is None:
        value, right_value = value[:-1], value[1:]
    h = widths[:, None]
    scale = [h]
    for _ in range(left.shape[1] - 1):
        scale.append(scale[-1] * h)  # not a power: pow is exp(log)
    scale = jnp.concatenate(scale, axis=1)
    return jnp.concatenate([value[:, None], left * scale, right_value[:, None], right * scale],
                           axis=1)


def interval_peaks(coefficients):
    """``max |p(sigma)|`` over ``[0, 1]`` of every septic in ``coefficients`` (``(..., 8)``,
    from ``septic_coefficients``), polished as in ``refined_peak``: several signals' peaks
    in one pass by stacking their intervals."""
    return _interval_peak(coefficients)


def septic_coefficients(value, widths, left, right):
    """``(K, 8)`` monomial coefficients in ``sigma`` (``t = t_k + sigma h_k``) of each
    interval's septic Hermite interpolant, from the arguments of ``refined_peak`` (``(K,
    12)``, degree 11, from five derivatives).

    Integrals and products of a sampled signal (a cam's drive torque, its energy) read
    the same interpolant that ``refined_peak`` searches.
    """
    matrix = jnp.asarray(_hermite_matrix(left.shape[1]).T)
    return jnp.dot(hermite_data(value, widths, left, right), matrix,
                   precision=jax.lax.Precision.HIGHEST)


@dataclasses.dataclass(frozen=True)
class TorsionFactorFit:
    """``Ct(n) ~ p / n^q + r`` fitted to the upper envelope of a Ct curve.

    ``rms_error`` is the fit's RMS relative deviation from the envelope points
    ``envelope_n, envelope_ct`` it was fitted to.
    """

    p: float
    q: float
    r: float
    rms_error: float
    envelope_n: np.ndarray
    envelope_ct: np.ndarray

    def __call__(self, period_ratio):
        return self.p / np.asarray(period_ratio) ** self.q + self.r


def upper_envelope(period_ratio, ct) -> tuple[np.ndarray, np.ndarray]:
    """Points of the upper envelope of a sampled Ct curve.

    The envelope is taken through the curve's local maxima over ``n`` (the crests of its
    oscillation), plus the end points where the curve is rising towards them; between
    crests the envelope is what the fit interpolates.  Points that another point at
    larger ``n`` exceeds are dropped, so the envelope never increases with ``n``
    (a curve that falls into its crests, as Ct curves do, is bounded from above).
    Non-finite points (ratios where a sweep's solver failed) are left out.
    """
    n = np.asarray(period_ratio, dtype=float)
    c = np.asarray(ct, dtype=float)
    solved = np.isfinite(c)
    n, c = n[solved], c[solved]
    order = np.argsort(n)
    n, c = n[order], c[order]
    padded = np.concatenate([[-np.inf], c, [-np.inf]])
    crest = (c >= padded[:-2]) & (c >= padded[2:])
    n, c = n[crest], c[crest]
    keep = c >= np.maximum.accumulate(c[::-1])[::-1] - 1e-12
    return n[keep], c[keep]


def fit_torsion_factor(curve, *, q_range: tuple[float, float] = (0.05, 6.0)) -> TorsionFactorFit:
    """Fit ``Ct = p / n^q + r`` to the upper envelope of ``curve`` (a ``CtCurve``).

    The fit minimises the relative error at the envelope points (so the tall crests at
    low ``n`` do not drown the rest) subject to ``r >= 1``: as ``n`` grows the payload
    follows the command and Ct tends to 1 or above, never below.  For each exponent ``q``
    on a fine grid, ``p`` and ``r`` follow by weighted linear least squares; the best
    ``q`` is then polished by golden-section search.  Needs three envelope points.
    """
    n, c = upper_envelope(curve.period_ratio, curve.ct)
    if n.size < 3:
        raise ValueError(
            f"the Ct curve has {n.size} envelope points; sample more period ratios to fit "
            "Ct = p/n^q + r (at least three crests are needed)"
        )

    u = 1 / c

    def solve(q):
        """``(p, r, rms)`` for every exponent in ``q`` (1-D): the 2x2 normal equations of
        the weighted least squares, with ``r`` clamped to 1 where it falls below."""
        basis = n ** -q[:, None] * u  # (Q, m)
        bb, bu, uu = (basis * basis).sum(1), basis @ u, u @ u
        b1, u1 = basis.sum(1), u.sum()
        det = bb * uu - bu**2
        p = (b1 * uu - bu * u1) / det
        r = (bb * u1 - bu * b1) / det
        clamp = r < 1.0
        r = np.where(clamp, 1.0, r)
        p = np.where(clamp, (b1 - bu) / bb, p)
        rms = np.sqrt(np.mean((p[:, None] * basis + r[:, None] * u - 1) ** 2, axis=1))
        return p, r, rms

    grid = np.linspace(*q_range, 400)
    errors = solve(grid)[2]
    i = int(np.argmin(errors))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    ratio = (math.sqrt(5) - 1) / 2
    for _ in range(60):
        x1, x2 = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        e1, e2 = solve(np.array([x1, x2]))[2]
        if e1 <= e2:
            hi = x2
        else:
            lo = x1
    q = 0.5 * (lo + hi)
    p, r, rms = (float(x[0]) for x in solve(np.array([q])))
    return TorsionFactorFit(p, float(q), r, rms, n, c)


def best_law_switches(curves: dict, fits: dict) -> list[tuple[float, str, str]]:
    """Where the law with the lowest fitted Ca*Ct envelope changes: ``(n, from, to)``.

    ``curves`` and ``fits`` map law names to ``CtCurve`` and ``TorsionFactorFit``.  The
    envelopes are compared on 4001 period ratios across the span every fitted curve covers,
    so each ``n`` is the last ratio before the change, within 1/4000 of that span."""
    names = [k for k in curves if k in fits]
    if not names:
        return []
    n = np.linspace(
        max(curves[k].period_ratio.min() for k in names),
        min(curves[k].period_ratio.max() for k in names),
        4001,
    )
    loads = np.array([curves[k].ca * fits[k](n) for k in names])
    best = np.argmin(loads, axis=0)
    changes = np.nonzero(best[1:] != best[:-1])[0]
    return [(float(n[i]), names[best[i]], names[best[i + 1]]) for i in changes]


def ca_ct_crossings(curve_a, curve_b, *, envelope: bool = True) -> list[float]:
    """Period ratios where the Ca*Ct curves of two laws cross.

    With ``envelope=True`` (default) the fitted envelopes ``Ca (p/n^q + r)`` are compared
    on the common ``n`` range (the reading a designer takes off a chart); otherwise the
    raw sampled curves, which oscillate and may cross many times.  Crossings are located
    by linear interpolation of the sign change of the difference.
    """
    n = np.asarray(curve_a.period_ratio, dtype=float)
    if not np.allclose(n, np.asarray(curve_b.period_ratio, dtype=float)):
        raise ValueError("the two curves must be sampled at the same period ratios")
    if envelope:
        fine = np.linspace(n.min(), n.max(), 20001)
        diff = curve_a.ca * fit_torsion_factor(curve_a)(fine) - curve_b.ca * fit_torsion_factor(
            curve_b
        )(fine)
        n = fine
    else:
        diff = np.asarray(curve_a.ca_ct) - np.asarray(curve_b.ca_ct)
    sign = np.sign(diff)
    crossings = []
    for i in range(len(diff) - 1):
        if sign[i] * sign[i + 1] < 0:
            crossings.append(float(n[i] - diff[i] * (n[i + 1] - n[i]) / (diff[i + 1] - diff[i])))
        elif sign[i + 1] == 0 and i + 2 < len(diff) and sign[i] * sign[i + 2] < 0:
            crossings.append(float(n[i + 1]))  # the curves meet exactly at a sample
    return crossings
