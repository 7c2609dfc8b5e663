"""Defects a new user met in the cam program: designs that end worse than their start, a
grooved cam's run refused or bounded before the work, many segments, join tolerances,
and absurd input accepted without a word."""

import dataclasses
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
    assert not result.kept_initial  # improved by the design, not kept by the fallback
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


def _feed_data(**changes):
    import tomllib

    data = tomllib.loads(example_path("feed").read_text())
    for key, value in changes.items():
        data[key] = value
    return data


def test_an_absurd_end_velocity_is_refused_on_its_own_segment():
    data = _feed_data()
    data["segment"][3]["end"]["velocity_mm_per_deg"] = -1e6
    with pytest.raises(ValueError, match=r"^segment 4: its end.velocity_mm_per_deg = -1e\+06 cannot be met"):
        Program.from_dict(data)


def test_the_join_check_is_relative_to_the_velocities_involved():
    """Segment 5 starts at -1e6 mm/deg and ends at rest to its round-off (7e-9 mm/deg):
    no velocity jump between segments 5 and 6, which the user did not touch."""
    from camjax.program._motion import joins, resolve_segments
    from camjax.program._spec import _segment

    data = _feed_data()
    data["segment"][3]["end"]["velocity_mm_per_deg"] = -1e6
    segments = resolve_segments(tuple(_segment(i, s, None) for i, s in enumerate(data["segment"], 1)))
    start = np.concatenate([[0.0], np.cumsum([s.angle_deg for s in segments])[:-1]])
    out = joins(segments, start)
    assert out[4].velocity_mm_per_deg == pytest.approx(0.0, abs=1e-6)
    assert abs(law_state(segments[4], True)[0]) < 1e-6
    # A real jump is still one: segment 4 made to start at -0.4 mm/deg against 0.3.
    jumped = dataclasses.replace(segments[3], law=laws.BoundaryPolynomial(v0=-0.4 * 55 / -3, v1=-0.4 * 55 / -3))
    with pytest.raises(ValueError, match="segments 3 and 4 meet at 140 deg"):
        joins((*segments[:3], jumped, *segments[4:]), start)


def test_a_swinging_flat_face_without_pivot_says_what_it_needs():
    data = _feed_data()
    data["follower"].update(kind="swinging-flat", arm_mm=100.0)
    del data["follower"]["roller_radius_mm"]
    with pytest.raises(ValueError, match="follower.pivot_mm is missing: a swinging-flat follower needs "
                                         "arm_mm and pivot_mm"):
        Program.from_dict(data)


def _sliced_indexer(dwell_pieces: int) -> dict:
    """The indexer with each dwell cut into ``dwell_pieces`` equal dwells."""
    data = _feed_data()
    data["segment"] = ([{"law": "cycloidal", "lift_mm": 20.0, "angle_deg": 100.0}]
                       + [{"angle_deg": 80.0 / dwell_pieces}] * dwell_pieces
                       + [{"law": "modified-sine", "lift_mm": -20.0, "angle_deg": 100.0}]
                       + [{"angle_deg": 80.0 / dwell_pieces}] * dwell_pieces)
    return data


def test_a_program_past_the_segment_limit_is_refused_before_any_work(tmp_path, capsys):
    from camjax.cli import main
    from camjax.program import MAX_SEGMENTS

    data = _sliced_indexer(MAX_SEGMENTS // 2)  # two more than the limit
    with pytest.raises(ValueError, match=f"the program has {MAX_SEGMENTS + 2} segments; the limit is {MAX_SEGMENTS}"):
        Program.from_dict(data)
    segments = [Program.from_dict(_sliced_indexer(2)).segments[0]] * (MAX_SEGMENTS + 1)
    with pytest.raises(ValueError, match=f"{MAX_SEGMENTS + 1} segments; the limit"):
        Program("many", segments, Program.load(example_path("indexer")).follower)
    lines = ["[program]", 'name = "slivers"']
    for seg in data["segment"]:
        lines += ["[[segment]]"] + [f"{k} = {v!r}".replace("'", '"') for k, v in seg.items()]
    lines += ["[follower]"] + [f"{k} = {v!r}".replace("'", '"') for k, v in data["follower"].items()]
    (tmp_path / "p.toml").write_text("\n".join(lines) + "\n")
    assert main(["program", str(tmp_path / "p.toml"), "--rpm", "300"]) == 2
    err = capsys.readouterr().err
    assert f"the program has {MAX_SEGMENTS + 2} segments; the limit is {MAX_SEGMENTS}" in err
    assert len(err.strip().splitlines()) == 1


def test_a_long_program_is_summarised_in_text_and_whole_in_json_and_csv():
    from camjax.cli.program import SHOWN, _csv, _table

    program = Program.from_dict(_sliced_indexer(20))  # 42 segments, 40 of them dwells
    report = analyse(program, [300.0], with_flight=False).as_dict()
    text = _table(report)
    assert len(report["joins"]) == 42 and len(report["segments"]) == 42
    assert len(report["speeds"][0]["residual_vibration_mm"]) == 40
    assert len(text.splitlines()) < 30 and max(map(len, text.splitlines())) < 250
    assert "42 segments (1 rise, 40 dwell, 1 return)" in text
    assert "42 joins:" in text and "40 from " in text
    header, row = _csv(report).splitlines()
    assert header.count("residual_vibration_mm_") == 40 and len(row.split(",")) == len(header.split(","))
    assert SHOWN < 40
