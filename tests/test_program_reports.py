"""Defects a new user met in the cam program: designs that end worse than their start, a
grooved cam's run refused or bounded before the work, many segments, join tolerances,
and absurd input accepted without a word."""

import warnings

import numpy as np
import pytest

from camjax import law_design, laws
from camjax.program import Program, analyse, design_segment, example_path
from camjax.program._motion import law_state

RPM = (500.0, 650.0)


@pytest.fixture(scope="module")
def feed():
    return Program.load(example_path("feed"))


@pytest.fixture(scope="module")
def designed_stroke(feed):
    """Segment 3 of the feed cam (a constant-velocity stroke between a quintic and a
    degree-7 polynomial that matches its jerk) designed for preload in a few steps."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", law_design.DesignNotImproved)
        return design_segment(feed, 3, *RPM, objective="preload", knots=8, steps=40, progress=False)


def _worst_preload(program, rpm):
    return max(s.min_preload_n for s in analyse(program, rpm, with_flight=False).speeds)


def test_designed_stroke_needs_no_more_preload_than_the_original(feed, designed_stroke):
    new, result = designed_stroke
    # The neighbour that matches the stroke's jerk (segment 4, degree 7) keeps its law:
    # the design keeps the stroke's end jerk (it changed it, and segment 4 with it).
    assert law_state(new.segments[2], True) == pytest.approx(law_state(feed.segments[2], True), abs=1e-12)
    assert new.segments[3].law == feed.segments[3].law
    # Independently, by the program's own analysis on speeds across the band.
    rpm = np.linspace(*RPM, 33)
    before, after = _worst_preload(feed, rpm), _worst_preload(new, rpm)
    assert after <= before
    (label, value), = result.values.items()
    start = result.initial_values[label]
    # The reports are maxima over 2000 speeds: at least the 33 speeds' maxima, and close.
    assert before <= start * (1 + 1e-9) and before >= 0.97 * start
    assert after <= value * (1 + 1e-9) + 1e-6
    assert value <= start


class _ReportedNegated(law_design.MaxResidual):
    """Trains on max R but reports -max R: every improvement reads as a loss."""

    def report(self, law):
        return -super().report(law)


def test_a_design_that_ends_worse_keeps_its_start_and_says_so():
    goal = _ReportedNegated(1.2, 1.6)
    with pytest.warns(law_design.DesignNotImproved, match="did not improve"):
        result = law_design.design(goal, knots=6, steps=20, progress=False)
    start = laws.BSplineLaw.fit(laws.get("cycloidal"), 6, 5)
    assert result.kept_initial
    np.testing.assert_allclose(np.asarray(result.law.coefficients), np.asarray(start.coefficients), atol=1e-12)
    assert result.values == result.initial_values
