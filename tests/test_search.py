"""The host-side root and peak searches (``camjax.sdof``'s ``narrowed_crossing``,
``first_roots``, ``polished_maxima``) against closed forms."""

import math

import numpy as np
import pytest

from camjax.sdof import first_roots, narrowed_crossing, polished_maxima


def test_a_crossing_is_narrowed_to_the_tolerance_in_few_batched_rounds():
    batches = []

    def crossed(t):
        batches.append(t.size)
        return t > math.sqrt(2.0)

    found = narrowed_crossing(crossed, 1.0, 2.0, 1e-9, 16)
    assert abs(found - math.sqrt(2.0)) <= 0.5e-9
    assert set(batches) == {16}  # one batch of 16 points a round
    assert len(batches) == math.ceil(math.log(1e9) / math.log(17))  # 17-fold a round


def test_the_first_crossing_is_found_where_the_event_comes_and_goes():
    """True on [1.2, 1.3] and from 1.6: the bracket follows the first true point."""
    found = narrowed_crossing(lambda t: ((t >= 1.2) & (t <= 1.3)) | (t >= 1.6), 1.0, 2.0, 1e-10, 16)
    assert found == pytest.approx(1.2, abs=1e-10)


def test_a_crossing_at_the_bracket_s_end_stays_there():
    found = narrowed_crossing(lambda t: t >= 2.0, 1.0, 2.0, 1e-6, 8)
    assert 2.0 - 1e-6 <= found <= 2.0


def test_first_roots_of_rows_against_their_closed_forms():
    """``c - t^2`` has the root ``sqrt(c)``: the secant over the final bracket ``h`` (the
    first one's 65^-3) errs by at most ``|f''| h^2 / (8 |f'|) = h^2 / (8 sqrt c)``, and comes
    within a fifth of it; ``cos t`` on [0, 8] has three roots, the first pi/2, ``-cos t`` on [2, 8] two, the first 3 pi/2 (``f'' = 0``
    there: to rounding)."""
    c = np.array([0.5, 2.0, 3.0, 10.0])
    roots = first_roots(lambda t: c[:, None] - t**2, np.zeros(4), np.full(4, 4.0))
    bound = (4.0 / 65**3) ** 2 / (8 * np.sqrt(c))
    error = np.abs(roots - np.sqrt(c))
    assert np.all(error <= bound) and np.all(error >= 0.2 * bound)
    sign = np.array([[1.0], [-1.0]])
    first = first_roots(lambda t: sign * np.cos(t), np.array([0.0, 2.0]), np.array([8.0, 8.0]))
    np.testing.assert_allclose(first, [math.pi / 2, 3 * math.pi / 2], rtol=1e-15)


def test_a_root_at_a_jump_is_bracketed_to_the_subdivision_s_width():
    """A step has no secant to draw: the bracket's middle, within 65^-3 of its width."""
    step = 0.3 + 0.1 * np.arange(3)
    roots = first_roots(lambda t: np.where(t < step[:, None], 1.0, -1.0), np.zeros(3), np.ones(3))
    assert np.all(np.abs(roots - step) <= 1.0 / 65**3)


def test_polished_maxima_against_the_closed_form_crest():
    """``a cos(w (t - c))`` peaks at ``a`` at ``t = c``: from a bracket of two samples, the
    polish finds it to rounding; a bracket where the samples' best is at an end keeps it."""
    a = np.array([1.0, 3.5, 0.2])
    c = np.array([0.31, 0.5, 0.77])
    w = np.array([5.0, 40.0, 200.0])

    def f(t):
        return a[:, None] * np.cos(w[:, None] * (t - c[:, None]))

    h = 0.6 / w  # about a tenth of a period either side
    lo, hi = c - 0.7 * h, c + 1.3 * h
    best = np.maximum(f(lo[:, None])[:, 0], f(hi[:, None])[:, 0])
    np.testing.assert_allclose(polished_maxima(f, lo, hi, best), a, rtol=1e-15)

    def rising(t):
        return t + 0.0 * c[:, None]

    out = polished_maxima(rising, np.zeros(3), np.ones(3), np.full(3, 0.5))
    assert np.all(out <= 1.0) and np.all(out >= 31 / 32)  # the linear rise: its last inner sample
