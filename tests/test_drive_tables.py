"""Drive tables: each format read back with a parser of its own and checked against Program.lift."""

import csv
import dataclasses
import math
import os
import re
import stat
import warnings

import numpy as np
import pytest

from camjax.cli import main
from camjax.program import (
    Program,
    analyse,
    drive_table,
    example_path,
    read_drive_table,
    write_drive_table,
)

FORMATS = ("csv", "xyva", "codesys", "twincat")


@pytest.fixture(scope="module")
def feed():
    return Program.load(example_path("feed"))


@pytest.fixture(scope="module")
def indexer():
    return Program.load(example_path("indexer"))


def _rows(path):
    """A csv file's header and its rows as floats (the test's own reading)."""
    with open(path, newline="") as handle:
        lines = list(csv.reader(handle))
    return lines[0], np.array([[float(x) for x in row] for row in lines[1:]])


def _hermite(x0, x1, left, right, x):
    """The quintic through (y, y', y'') at both ends, solved as a 6x6 system (not the code's basis)."""
    def rows(t):
        return [[t**k for k in range(6)], [k * t ** (k - 1) if k else 0.0 for k in range(6)],
                [k * (k - 1) * t ** (k - 2) if k > 1 else 0.0 for k in range(6)]]
    coefficients = np.linalg.solve(np.array(rows(x0) + rows(x1)), np.array([*left, *right]))
    return np.polynomial.polynomial.polyval(x, coefficients)


def _interpolate(knots, theta):
    """Quintic Hermite between consecutive knots (master, y, v, a); repeated masters are steps."""
    out = np.full(theta.shape, np.nan)
    for k in range(len(knots) - 1):
        (x0, *left), (x1, *right) = knots[k], knots[k + 1]
        if x1 == x0:
            continue
        inside = (theta >= x0) & (theta <= x1)
        out[inside] = _hermite(0.0, x1 - x0, left, right, theta[inside] - x0)  # local origin: well scaled
    return out


@pytest.mark.parametrize(("name", "step"), [("feed", 0.1), ("indexer", 0.5)])
def test_csv_rows_are_the_lift_and_the_jerk_its_derivative(name, step, request, tmp_path):
    program = request.getfixturevalue(name)
    header, rows = _rows(write_drive_table(program, tmp_path / "t.csv", "csv", step_deg=step))
    assert header == ["master_deg", "slave_mm", "velocity_mm_per_deg", "acceleration_mm_per_deg2",
                      "jerk_mm_per_deg3"]
    master = rows[:, 0]
    np.testing.assert_allclose(master, np.linspace(0.0, 360.0, round(360 / step) + 1), atol=1e-12)
    assert set(np.append(program.start_deg, 360.0)) <= set(master)  # the joins exactly
    y, dy, ddy = program.lift(master[:-1])  # each angle the segment after it
    end = program.lift(360.0, side="before")
    for column, expected in zip(rows.T[1:4], (y, dy, ddy)):
        np.testing.assert_allclose(column[:-1], expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(rows[-1, 1:4], [float(e) for e in end], atol=1e-12)
    # jerk: a central difference of the lift's acceleration, away from the joins and the
    # laws' breakpoints (where the jerk may step, and the difference straddles the step)
    h = 1e-3
    joins = [*program.start_deg, 360.0]
    for start, seg in zip(program.start_deg, program.segments):
        if seg.moving:
            joins += [start + b * seg.angle_deg for b in np.ravel(seg.law.breakpoints())]
    clear = np.min(np.abs(master[:, None] - np.array(joins)[None, :]), axis=1) > 10 * h
    difference = (program.lift(master + h)[2] - program.lift(master - h)[2]) / (2 * h)
    scale = np.max(np.abs(rows[:, 4]))
    assert scale > 0
    np.testing.assert_allclose(rows[clear, 4], difference[clear], atol=1e-5 * scale)


@pytest.mark.parametrize(("name", "tolerance"), [("feed", 1e-4), ("indexer", 1e-4), ("feed", 1e-6)])
def test_xyva_knots_interpolate_the_lift_within_the_tolerance(name, tolerance, request, tmp_path):
    program = request.getfixturevalue(name)
    header, knots = _rows(write_drive_table(program, tmp_path / "t.csv", "xyva", tolerance=tolerance))
    assert header == ["master_deg", "slave_mm", "velocity_mm_per_deg", "acceleration_mm_per_deg2"]
    assert knots[0, 0] == 0.0 and knots[-1, 0] == 360.0 and np.all(np.diff(knots[:, 0]) >= 0)
    # every segment end is a knot
    assert set(np.append(program.start_deg, 360.0)) <= set(knots[:, 0])
    theta = np.linspace(0.0, 360.0, 72_001)
    error = np.abs(_interpolate(knots, theta) - program.lift(theta)[0])
    assert np.max(error) <= tolerance
    # a moving segment that is not a quintic needs interior knots at this tolerance
    interior = [k for k in knots[:, 0] if k not in set(program.start_deg)]
    assert len(interior) > 1
    # the knots' velocity and acceleration are the lift's (the segment after; before at 360)
    distinct = np.append(np.diff(knots[:, 0]) > 0, False)
    _, dy, ddy = program.lift(knots[distinct, 0])
    np.testing.assert_allclose(knots[distinct, 2], dy, atol=1e-12)
    np.testing.assert_allclose(knots[distinct, 3], ddy, atol=1e-12)


def test_a_quintic_segment_is_one_piece_and_a_cv_stroke_a_line(feed):
    table = drive_table(feed, "xyva")
    # the feed's 50-degree degree-5 polynomial from 30 to 80 degrees: one knot at each end
    inside = table.master_deg[(table.master_deg > 30.0) & (table.master_deg < 80.0)]
    assert inside.size == 0
    start = list(table.master_deg).index(30.0)
    assert table.piece[start] == "poly5" and table.piece[list(table.master_deg).index(80.0)] == "line"
    assert table.piece[0] == "dwell" and table.piece[-1] == "end"


def test_an_acceleration_step_is_two_knots_at_one_angle(feed, tmp_path):
    """Harmonic rise and return between dwells: the acceleration steps at all four joins."""
    from camjax import laws
    from camjax.program import Segment

    harmonic = laws.get("harmonic")
    segments = (Segment(90.0), Segment(90.0, 10.0, harmonic), Segment(90.0), Segment(90.0, -10.0, harmonic))
    program = dataclasses.replace(feed, segments=segments)
    _, knots = _rows(write_drive_table(program, tmp_path / "k.csv", "xyva"))
    for join in (90.0, 180.0, 270.0):
        pair = knots[knots[:, 0] == join]
        assert pair.shape == (2, 4)
        before, after = (program.lift(join, side=side) for side in ("before", "after"))
        np.testing.assert_allclose(pair[:, 1:], [[float(x) for x in before], [float(x) for x in after]], atol=1e-12)
        assert pair[0, 3] != pair[1, 3]
    theta = np.linspace(0.0, 360.0, 36_001)
    assert np.max(np.abs(_interpolate(knots, theta) - program.lift(theta)[0])) <= 1e-4
    # CamBuilder: explicit bounds either side, so the step needs no repeated segment
    segments_st = _codesys(write_drive_table(program, tmp_path / "k.st", "codesys"))
    assert all(right[0] > left[0] for _, left, right in segments_st)
    steps = [(a[2], b[1]) for a, b in zip(segments_st, segments_st[1:]) if a[2] != b[1]]
    assert [(r[0], r[3], l[3]) for r, l in steps] == [(k, *knots[knots[:, 0] == k, 3]) for k in (90.0, 180.0, 270.0)]
    for got, expected in zip(read_drive_table(tmp_path / "k.st"), knots.T):
        np.testing.assert_array_equal(got, expected)


def _codesys(path):
    """(kind, left bound, right bound) of each Append in a CamBuilder file."""
    pattern = re.compile(r"camBuilder\.Append\(SMCB\.(Poly5|Line)\(SMCB\.Bound\(([^)]*)\), SMCB\.Bound\(([^)]*)\)\)\);")
    segments = []
    for line in open(path).read().splitlines():
        match = pattern.fullmatch(line)
        if match:
            segments.append((match[1], *(tuple(float(x) for x in match[i].split(",")) for i in (2, 3))))
        else:
            assert line.startswith("(*") or line == "camBuilder.Init();", line
    return segments


@pytest.mark.parametrize("name", ["feed", "indexer"])
def test_codesys_and_twincat_files_hold_the_xyva_knots(name, request, tmp_path):
    program = request.getfixturevalue(name)
    _, knots = _rows(write_drive_table(program, tmp_path / "k.csv", "xyva"))
    segments = _codesys(write_drive_table(program, tmp_path / "k.st", "codesys"))
    # contiguous pieces covering the turn, each from one knot to the next
    distinct = [k for k in range(len(knots) - 1) if knots[k + 1, 0] > knots[k, 0]]
    assert len(segments) == len(distinct)
    for (kind, left, right), k in zip(segments, distinct):
        np.testing.assert_array_equal(left, knots[k])
        np.testing.assert_array_equal(right, knots[k + 1])
        if kind == "Line":  # constant velocity, or a dwell: zero acceleration, slope = v
            assert left[3] == right[3] == 0.0
            assert right[1] - left[1] == pytest.approx(left[2] * (right[0] - left[0]), abs=1e-9)
    lines = {(left[0], right[0]) for kind, left, right in segments if kind == "Line"}
    expected = {(float(s), float(s + seg.angle_deg)) for s, seg in zip(program.start_deg, program.segments)
                if not seg.moving or seg.law.name == "constant-velocity"}
    assert lines == expected

    header, points = _rows(write_drive_table(program, tmp_path / "k.twincat.csv", "twincat"))
    assert header[:4] == ["PointIndex", "FunctionType", "PointType", "RelIndexNextPoint"]
    np.testing.assert_array_equal(points[:, 4:8], knots)
    np.testing.assert_array_equal(points[:, 0], np.arange(1, len(knots) + 1))
    assert set(points[:, 3]) == {1.0}
    for (kind, _, _), k in zip(segments, distinct):
        assert points[k, 1] == (15 if kind == "Poly5" else 1)  # POLYNOM5_MM, POLYNOM1
    v, a = points[:, 6], points[:, 7]
    rest, smooth = np.abs(v) < 1e-12, np.abs(a) < 1e-12
    expected_type = np.where(rest, np.where(smooth, 1, 4), np.where(smooth, 2, 8))
    np.testing.assert_array_equal(points[:, 2], expected_type)
    # the jerk column is the third derivative: a one-sided difference of the acceleration
    h = 1e-4
    for point in points[1:-1]:
        x = point[4]
        step = (program.lift(x + h)[2] - program.lift(x)[2]) / h
        assert point[8] == pytest.approx(step, abs=1e-3 * max(1e-6, np.max(np.abs(points[:, 8]))))


@pytest.mark.parametrize("format", FORMATS)
def test_read_drive_table_round_trips(format, feed, tmp_path):
    path = write_drive_table(feed, tmp_path / f"t.{format}", format)
    table = drive_table(feed, format)
    for got, expected in zip(read_drive_table(path), table[:4]):
        np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize(("text", "message"), [("", "not a camjax drive table"),
                                               ("x,y\n1,2\n", "not a camjax drive table"),
                                               ("master_deg,slave_mm\n", "no drive-table rows"),
                                               ("master_deg,a,b,c\n0,1,x,3\n", "not a number")])
def test_read_drive_table_names_a_file_that_is_none(text, message, tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=f"{re.escape(str(path))}: .*{message}"):
        read_drive_table(path)


def test_a_swinging_follower_slave_is_its_swing_angle_in_degrees(feed, tmp_path):
    follower = dataclasses.replace(feed.follower, kind="swinging-roller", arm_mm=98.0, pivot_mm=110.0)
    swinging = dataclasses.replace(feed, follower=follower)
    header, rows = _rows(write_drive_table(swinging, tmp_path / "s.csv", "csv", step_deg=1.0))
    assert header[1:] == ["slave_deg", "velocity_deg_per_deg", "acceleration_deg_per_deg2", "jerk_deg_per_deg3"]
    y, dy, ddy = swinging.lift(rows[:-1, 0])
    per_mm = 180.0 / (math.pi * 98.0)
    np.testing.assert_allclose(rows[:-1, 1], np.degrees(y / 98.0), atol=1e-12)
    np.testing.assert_allclose(rows[:-1, 2:4], np.stack([dy, ddy], axis=1) * per_mm, atol=1e-12)
    knots = drive_table(swinging, "xyva", tolerance=1e-5)
    theta = np.linspace(0.0, 360.0, 36_001)
    rows = np.stack(knots[:4], axis=1)
    assert np.max(np.abs(_interpolate(rows, theta) - np.degrees(swinging.lift(theta)[0] / 98.0))) <= 1e-5


@pytest.mark.parametrize(("kwargs", "message"), [
    (dict(format="dxf"), "format must be one of csv, xyva, codesys, twincat"),
    (dict(format="csv", step_deg=0.0), "step_deg must be a positive number"),
    (dict(format="csv", step_deg=-1.0), "step_deg must be a positive number"),
    (dict(format="csv", step_deg=0.7), "step_deg = 0.7 does not divide 360"),
    (dict(format="csv", step_deg=1e-5), "step_deg = 1e-05 gives 36,000,000 rows"),
    (dict(format="xyva", tolerance=0.0), "tolerance must be positive"),
    (dict(format="xyva", tolerance=float("nan")), "tolerance must be positive"),
])
def test_bad_arguments_are_one_line_errors_naming_them(kwargs, message, feed, tmp_path):
    with pytest.raises(ValueError, match=re.escape(message)) as caught:
        write_drive_table(feed, tmp_path / "t", **kwargs)
    assert "\n" not in str(caught.value)
    assert list(tmp_path.iterdir()) == []


def test_a_failed_export_leaves_the_old_file_whole(feed, tmp_path, monkeypatch):
    path = tmp_path / "t.csv"
    path.write_text("old\n")
    with pytest.raises(ValueError, match="tolerance = 1e-30 cannot be met"):
        write_drive_table(feed, path, "xyva", tolerance=1e-30)

    def fail(*args):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", fail)  # the writer's rename
    with pytest.raises(OSError, match="disk full"):
        write_drive_table(feed, path, "csv", step_deg=1.0)
    assert path.read_text() == "old\n" and [p.name for p in tmp_path.iterdir()] == ["t.csv"]


def test_cli_writes_the_table_and_refuses_bad_options(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("CAMJAX_CACHE_DIR", "off")
    assert main(["program", "indexer", "--drive-table", "codesys", "--out", str(tmp_path)]) == 0
    written = tmp_path / "drive-table-codesys.st"
    assert capsys.readouterr().out.strip() == str(written)
    np.testing.assert_array_equal(read_drive_table(written)[0], drive_table(Program.load(example_path()), "codesys")[0])
    for argv, message in ((["--drive-table", "dxf", "--out", str(tmp_path)], "--drive-table must be one of"),
                          (["--drive-table", "csv", "--drive-step", "0.7", "--out", str(tmp_path)], "--drive-step"),
                          (["--drive-table", "xyva", "--drive-tolerance", "-1", "--out", str(tmp_path)],
                           "--drive-tolerance must be positive"),
                          (["--drive-table", "csv"], "--drive-table needs --out")):
        assert main(["program", "feed", *argv]) == 2
        err = capsys.readouterr().err.strip()
        assert message in err and "\n" not in err


def test_a_written_table_read_back_as_a_table_cam_has_the_same_dynamics(tmp_path):
    """The round trip a designer makes: the feed cam's csv drive table at 0.5 degree, read
    back (``read_drive_table``) as a whole-cam lift table (``Program.from_table``), analysed
    through the same paths: its peaks and contact forces within 1%, its jump speed within
    0.5% of the cam's own (an independent fit of the written points, not the laws)."""
    program = Program.load(example_path("feed"))
    path = write_drive_table(program, tmp_path / "feed.csv", "csv", step_deg=0.5)
    master, slave, _, _ = read_drive_table(path)
    keep = master < 360.0
    table = Program.from_table("feed-table", master[keep], slave[keep], program.follower)
    rpm = [400.0, 600.0, 900.0]
    ours, theirs = analyse(table, rpm, with_flight=False), analyse(program, rpm, with_flight=False)
    for a, b in zip(ours.speeds, theirs.speeds):
        for key in ("max_payload_acceleration_m_s2", "max_kinematic_acceleration_m_s2",
                    "max_contact_force_n", "min_contact_force_n"):
            assert getattr(a, key) == pytest.approx(getattr(b, key), rel=1e-2), key
    assert ours.jump_speed_rpm == pytest.approx(theirs.jump_speed_rpm, rel=5e-3)


def test_a_step_too_coarse_for_the_motion_is_warned_of_with_its_rows(capsys, tmp_path, monkeypatch):
    """The indexer's shortest moving segment spans 100 degrees: a step of 360 writes 2 rows
    (0 and 360), none inside it; 10 degrees puts 10 across it and is quiet."""
    monkeypatch.setenv("CAMJAX_CACHE_DIR", "off")
    program = Program.load(example_path())
    with pytest.warns(UserWarning, match=r"^a step of 360 deg gives a table of 2 rows, about 0\.278 across "
                      r"segment 1 \(100 deg, the shortest moving one\): .* a step of at most 10 deg puts 10 rows"):
        assert drive_table(program, "csv", step_deg=360.0).master_deg.tolist() == [0.0, 360.0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert drive_table(program, "csv", step_deg=10.0).master_deg.size == 37
        drive_table(program, "xyva")  # knots: no step to warn of
    assert main(["program", "--drive-table", "csv", "--drive-step", "360", "--out", str(tmp_path)]) == 0
    out, err = capsys.readouterr()
    assert out.strip() == str(tmp_path / "drive-table.csv")
    assert err.startswith("warning: --drive-step 360 deg gives a table of 2 rows") and err.count("\n") == 1


@pytest.mark.parametrize("option", [["--rpm", "600"], ["--format", "json"], ["--plot-rpm", "600"], ["--no-flight"],
                                    ["--probes", "probes.py:MEAN_FORCE"]])
def test_the_analysis_options_are_refused_with_a_drive_table(option, capsys, tmp_path):
    assert main(["program", "--drive-table", "csv", "--out", str(tmp_path), *option]) == 2
    assert capsys.readouterr().err.strip() == (
        f"camjax program: error: {option[0]}: not with --drive-table, which analyses nothing and writes the "
        "table to --out in its own format; run the analysis apart")
    assert list(tmp_path.iterdir()) == []


def test_a_drive_table_gets_the_mode_every_output_gets(feed, tmp_path):
    """0666 less the umask (a temporary file's 0600 before), as ``Path.write_text`` gives."""
    old = os.umask(0o027)
    try:
        written = write_drive_table(feed, tmp_path / "t.csv", "csv", step_deg=1.0)
        (tmp_path / "plain.txt").write_text("x")
    finally:
        os.umask(old)
    assert stat.S_IMODE(written.stat().st_mode) == 0o640 == stat.S_IMODE((tmp_path / "plain.txt").stat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plain.txt", "t.csv"]  # no temporary left
