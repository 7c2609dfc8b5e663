"""Host-side root and peak searches on exact values: NumPy, batched, one evaluation per round.

The program's events (the jump speed, a separation, a re-impact, the largest force after an
impact) are found on functions that are exact but costly to evaluate (each value a steady
state or a closed-form flight): these searches evaluate them in batches, a round of points
at a time (one dispatch each), rather than one point per step.

- ``narrowed_crossing``: where a monotone event first happens on ``[lo, hi]`` (a speed where
  contact is lost), to a tolerance, by rounds of evenly spaced points;
- ``first_roots``: the first root of each row's bracket, by rounds of subdivision and a
  final secant;
- ``polished_maxima``: the largest value of each row near a sampled maximum, by zooming
  rounds and a final parabola's vertex.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

ROOT_ROUNDS = 3
"""Rounds of 64-way subdivision before ``first_roots``' secant: a bracket shrinks 65^3-fold
(274,625), so the secant's error, of the bracket's square, is at rounding for a smooth
function over a bracket of a sample interval."""
ROOT_POINTS = 64

PEAK_ROUNDS = 3
"""Zooming rounds of ``polished_maxima``: 32 points around the best each, the bracket shrinks
16-fold a round."""
PEAK_POINTS = 32


def narrowed_crossing(crossed: Callable[[np.ndarray], np.ndarray], lo: float, hi: float,
                      tolerance: float, points: int) -> float:
    """The middle of a bracket, narrower than ``tolerance``, of where ``crossed`` first turns
    true on ``[lo, hi]`` (false at ``lo``, true at ``hi``).

    ``crossed`` maps an array of points to booleans (one batch a round: ``points`` evenly
    spaced inside the bracket); the bracket becomes the first true point and the one before
    it, so the answer is the first crossing even where the event is not monotone.  Each
    round shrinks the bracket ``points + 1``-fold.
    """
    while hi - lo > tolerance:
        trial = np.linspace(lo, hi, points + 2)[1:-1]
        hit = np.flatnonzero(crossed(trial))
        if hit.size:
            lo, hi = (trial[hit[0] - 1] if hit[0] > 0 else lo), trial[hit[0]]
        else:
            lo = trial[-1]
    return 0.5 * (lo + hi)


def first_roots(f: Callable[[np.ndarray], np.ndarray], lo, hi, rounds: int = ROOT_ROUNDS,
                points: int = ROOT_POINTS) -> np.ndarray:
    """The first root of ``f`` in each row's ``[lo, hi]`` (``f(lo) > 0 >= f(hi)``).

    ``f`` maps points ``(rows, m)`` to values ``(rows, m)``.  ``rounds`` rounds of
    ``points``-way subdivision shrink each bracket around its first sign change (to where
    ``f <= 0`` first); the root is then the secant's through the bracket's ends (the error
    is of the bracket's square for a smooth ``f``), or the bracket's middle where the ends
    do not change sign.
    """
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    rows = np.arange(lo.size)
    f_lo = f_hi = np.zeros_like(lo)
    for _ in range(rounds):
        t = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, points + 2)
        values = f(t)
        hit = values[:, 1:] <= 0
        i = np.where(hit.any(axis=1), hit.argmax(axis=1) + 1, points + 1)
        lo, hi, f_lo, f_hi = t[rows, i - 1], t[rows, i], values[rows, i - 1], values[rows, i]
    secant = (f_lo > 0) & (f_hi <= 0) & (f_lo != f_hi)
    return np.where(secant, lo + (hi - lo) * f_lo / np.where(secant, f_lo - f_hi, 1.0), 0.5 * (lo + hi))


def polished_maxima(f: Callable[[np.ndarray], np.ndarray], lo, hi, best, rounds: int = PEAK_ROUNDS,
                    points: int = PEAK_POINTS) -> np.ndarray:
    """The largest value of ``f`` in each row's ``[lo, hi]``, around a maximum sampled there
    (``best``: the sampled value, a lower bound that the result never falls below).

    ``f`` maps points ``(rows, m)`` to values ``(rows, m)``.  Each of ``rounds`` rounds
    samples ``points + 1`` evenly and keeps the two samples around the best one (the
    bracket shrinks ``points / 2``-fold); the result is then the larger of the best sample
    and the value at the vertex of the parabola through the bracket's ends and middle,
    where that parabola is concave (error of the bracket's fourth power for a smooth ``f``).
    """
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    best = np.asarray(best, dtype=float)
    here = np.arange(lo.size)
    for _ in range(rounds):
        t = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, points + 1)
        values = f(t)
        j = np.clip(values.argmax(axis=1), 1, points - 1)
        best = np.maximum(best, values[here, j])
        lo, hi = t[here, j - 1], t[here, j + 1]
    mid = 0.5 * (lo + hi)
    fa, fb, fc = (f(x[:, None])[:, 0] for x in (lo, mid, hi))
    curvature = fa - 2 * fb + fc
    ok = curvature < 0
    vertex = mid + 0.25 * (hi - lo) * (fa - fc) / np.where(ok, curvature, -1.0)
    return np.where(ok, np.maximum(best, f(np.where(ok, vertex, mid)[:, None])[:, 0]), best)
