"""Defects a new user met in the cam program: designs that end worse than their start, a
grooved cam's run refused or bounded before the work, many segments, join tolerances,
and absurd input accepted without a word."""

import dataclasses
import warnings

import numpy as np
import pytest

from camjax import law_design, laws
from camjax.program import Program, analyse, design_segment, example_path

RPM = (500.0, 650.0)


def _end_state(seg) -> tuple[float, float, float]:
    """``(v, a, j)`` at a moving segment's end (mm/deg, mm/deg^2, mm/deg^3), from its law's
    normalised derivatives at ``tau = 1``."""
    _, v, a, j = (float(x) for x in seg.law.evaluate(1.0))
    beta, h = seg.angle_deg, seg.lift_mm
    return h * v / beta, h * a / beta**2, h * j / beta**3


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
    assert _end_state(new.segments[2]) == pytest.approx(_end_state(feed.segments[2]), abs=1e-12)
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
    """The feed cam scaled by 1e6 (lifts and end velocities): segment 4 ends at -4e5
    mm/deg to its coefficients' round-off (5e-8 mm/deg off the -4e5 that segment 5
    starts at) and segment 5 at rest to 3e-10 mm/deg: no velocity jump, which an absolute
    tolerance (1e-9 mm/deg) would have reported."""
    data = _feed_data()
    for seg in data["segment"]:
        seg["lift_mm"] = 1e6 * seg.get("lift_mm", 0.0)
        if isinstance(seg.get("end"), dict):
            seg["end"] = {key: 1e6 * value for key, value in seg["end"].items()}
    big = Program.from_dict(data)
    out = big.joins()
    assert out[3].velocity_mm_per_deg == pytest.approx(-4e5, rel=1e-12)
    assert out[4].velocity_mm_per_deg == pytest.approx(0.0, abs=1e-6)
    assert abs(_end_state(big.segments[4])[0]) < 1e-6
    # A real jump is still one: segment 4 made to start at -0.4 mm/deg against 0.3.
    feed = Program.load(example_path("feed"))
    segments = feed.segments
    jumped = dataclasses.replace(segments[3], law=laws.BoundaryPolynomial(v0=-0.4 * 55 / -3, v1=-0.4 * 55 / -3),
                                 start=None, end=None)  # a law of its own, no end states to solve
    with pytest.raises(ValueError, match="segments 3 and 4 meet at 140 deg"):
        Program("jumped", (*segments[:3], jumped, *segments[4:]), feed.follower)


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


def _write_toml(data: dict, path) -> None:
    """A program's ``[[segment]]`` and ``[follower]`` tables as a TOML file (flat values only)."""
    lines = ["[program]", 'name = "slivers"']
    for seg in data["segment"]:
        lines += ["[[segment]]"] + [f"{k} = {v!r}".replace("'", '"') for k, v in seg.items()]
    lines += ["[follower]"] + [f"{k} = {v!r}".replace("'", '"') for k, v in data["follower"].items()]
    path.write_text("\n".join(lines) + "\n")


def test_a_program_past_the_segment_limit_is_refused_before_any_work(tmp_path, capsys):
    from camjax.cli import main
    from camjax.program import MAX_SEGMENTS

    data = _sliced_indexer(MAX_SEGMENTS // 2)  # two more than the limit
    with pytest.raises(ValueError, match=f"the program has {MAX_SEGMENTS + 2} segments; the limit is {MAX_SEGMENTS}"):
        Program.from_dict(data)
    segments = [Program.from_dict(_sliced_indexer(2)).segments[0]] * (MAX_SEGMENTS + 1)
    with pytest.raises(ValueError, match=f"{MAX_SEGMENTS + 1} segments; the limit"):
        Program("many", segments, Program.load(example_path("indexer")).follower)
    _write_toml(data, tmp_path / "p.toml")
    assert main(["program", str(tmp_path / "p.toml"), "--rpm", "300"]) == 2
    err = capsys.readouterr().err
    assert f"the program has {MAX_SEGMENTS + 2} segments; the limit is {MAX_SEGMENTS}" in err
    assert len(err.strip().splitlines()) == 1


def test_a_long_program_is_summarised_in_text_and_whole_in_json_and_csv(tmp_path, capsys):
    import json

    from camjax.cli import main
    from camjax.cli.program import SHOWN

    _write_toml(_sliced_indexer(20), tmp_path / "p.toml")  # 42 segments, 40 of them dwells
    printed = {}
    for fmt in ("json", "csv", "table"):
        assert main(["program", str(tmp_path / "p.toml"), "--rpm", "300", "--no-flight", "--format", fmt]) == 0
        printed[fmt] = capsys.readouterr().out
    report, text = json.loads(printed["json"]), printed["table"]
    assert len(report["joins"]) == 42 and len(report["segments"]) == 42
    assert len(report["speeds"][0]["residual_vibration_mm"]) == 40
    assert len(text.splitlines()) < 30 and max(map(len, text.splitlines())) < 250
    assert "42 segments (1 rise, 40 dwell, 1 return)" in text
    assert "42 joins:" in text and "40 from " in text
    header, row = printed["csv"].splitlines()
    assert header.count("residual_vibration_mm_") == 40 and len(row.split(",")) == len(header.split(","))
    assert SHOWN < 40


def _indexer_with(follower=None, materials=None) -> Program:
    import tomllib

    data = tomllib.loads(example_path("indexer").read_text())
    data["follower"].update(follower or {})
    if materials is not None:
        data["materials"] = materials
    return Program.from_dict(data)


@pytest.mark.parametrize(("follower", "materials", "expected"), [
    ({"contact_width_mm": 15.0}, {"cam_youngs_modulus_gpa": 1e12}, "materials.cam_youngs_modulus_gpa = 1e+12 lies outside 1-1000 GPa"),
    ({"contact_width_mm": 15.0}, {"follower_youngs_modulus_gpa": 210e9}, "materials.follower_youngs_modulus_gpa = 2.1e+11 lies outside"),
    ({}, {"cam_poisson_ratio": 0.29}, "[materials] is used only for the Hertz contact stress, which needs "
                                      "follower.contact_width_mm"),
    ({"contact_width_mm": 1e9}, None, "follower.contact_width_mm = 1e+09 is more than ten times"),
])
def test_absurd_input_is_warned_about_by_the_library(follower, materials, expected):
    from camjax.program import design_warnings

    assert design_warnings(_indexer_with()) == []
    assert design_warnings(_indexer_with({"contact_width_mm": 15.0}, {"cam_youngs_modulus_gpa": 200.0})) == []
    found = design_warnings(_indexer_with(follower, materials))
    assert len(found) == 1 and expected in found[0]


def test_a_hertz_half_width_past_the_contact_radius_is_warned_about():
    from camjax.program import MAX_HALF_WIDTH_RATIO, design_warnings

    program = _indexer_with({"contact_width_mm": 1e-9})
    report = analyse(program, [300.0], with_flight=False).as_dict()
    (found,) = design_warnings(program, report)
    assert report["warnings"] == [found]  # the report carries them, for the API and the CLI
    assert "at 300 rpm the Hertz contact half-width" in found and "past the 0.1 where Hertz theory holds" in found
    # The same contact 15 mm wide: p scales as 1/sqrt(L) and b as p (b = 2 R' p / E*).
    scale = (1e-9 / 15.0) ** 0.5
    speed = dict(report["speeds"][0])
    speed.update(max_contact_stress_mpa=speed["max_contact_stress_mpa"] * scale,
                 contact_half_width_mm=speed["contact_half_width_mm"] * scale)
    wide = _indexer_with({"contact_width_mm": 15.0})
    assert design_warnings(wide, dict(report, speeds=[speed])) == []
    # b / R' = 2 p / E* (E* = 115.4 GPa for two steels at 210 GPa, nu 0.3).
    e_star = 1 / (2 * (1 - 0.3**2) / 210e3)
    assert 2 * speed["max_contact_stress_mpa"] / e_star < MAX_HALF_WIDTH_RATIO


def test_plot_rpm_must_be_a_speed_of_the_table(capsys):
    from camjax.cli import main

    assert main(["program", "indexer", "--rpm", "300,600", "--plot-rpm", "5000"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.endswith("--plot-rpm: 5000 is not one of the --rpm speeds (300, 600): the figures show a "
                        "speed of the table; name one of them")
    assert len(err.splitlines()) == 1


def _grooved_indexer() -> Program:
    base = Program.load(example_path("indexer"))
    follower = dataclasses.replace(base.follower, spring_rate_n_per_mm=None, preload_n=0.0,
                                   groove_clearance_mm=0.05)
    return dataclasses.replace(base, follower=follower)


def _first_run_samples(rpm: float) -> int:
    """Samples of a groove run's first try, from the follower's numbers (indexer, grooved):
    128 a natural period, and turns enough for the contact vibration to decay by 1e9."""
    import math

    f_n = (2e6 / 1.5) ** 0.5 / (2 * math.pi)
    cycles = f_n * 60.0 / rpm
    return 128 * math.ceil(cycles) * (1 + max(1, math.ceil(math.log(1e9) / (2 * math.pi * 0.05 * cycles))))


def test_a_groove_run_past_its_budget_is_refused_before_any_work():
    import re

    from helpers import compiled_programs

    from camjax.program import MAX_GROOVE_SAMPLES, groove_turns

    program = _grooved_indexer()
    with compiled_programs() as compiled, pytest.raises(
            ValueError, match=r"^the grooved cam at 50 rpm: the follower vibrates 221 times a turn "
                              r"\(28,288 samples a turn\)") as error:
        groove_turns(program, [50.0])
    assert compiled == []  # refused before any work (its time: experiments/benchmarks/refusal_speed.py)
    message = str(error.value)
    assert "lower follower.stiffness_n_per_mm or raise follower.damping_ratio" in message
    faster = float(re.search(r"run at ([0-9.e+]+) rpm or faster", message).group(1))
    assert _first_run_samples(50.0) > MAX_GROOVE_SAMPLES
    assert _first_run_samples(faster) <= MAX_GROOVE_SAMPLES < _first_run_samples(faster / 1.01)
    # Turns asked for: in the same terms, not the solver's dwell and samples.
    with pytest.raises(ValueError, match=r"^400 groove turns at 4,736 samples a turn .* ask for at most 10 turns"):
        groove_turns(program, [300.0], turns=400)


def test_a_written_program_carries_a_file_only_for_a_law_it_cannot_name(tmp_path):
    """``write_program``: the feed cam's polynomials (end states) and registry laws need no
    file; a fitted B-spline on the indexer's first rise does, and loads back the same lift."""
    from camjax.program import example_path, with_law, write_program

    feed = Program.load(example_path("feed"))
    path = write_program(feed, tmp_path / "feed")
    assert sorted(p.name for p in path.parent.iterdir()) == ["program.toml"]
    theta = np.linspace(0.0, 360.0, 721)
    np.testing.assert_allclose(Program.load(path).lift(theta)[0], feed.lift(theta)[0], atol=1e-12)
    indexer = Program.load(example_path("indexer"))
    rise = indexer.moving_segments()[0] + 1
    spline = laws.BSplineLaw.fit(laws.ModifiedSine(), 8)
    designed = with_law(indexer, rise, spline)
    path = write_program(designed, tmp_path / "indexer")
    assert sorted(p.name for p in path.parent.iterdir()) == ["program.toml", f"segment{rise}.json"]
    np.testing.assert_allclose(Program.load(path).lift(theta)[0], designed.lift(theta)[0], atol=1e-12)
