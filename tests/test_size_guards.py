"""Work too large to fit is refused before it starts, with what to change (a one-line
``ValueError`` at the API, exit 2 at the command line), never an out-of-memory traceback."""

import time

import pytest

from camjax import laws
from camjax.cli import main
from camjax.program import Follower, Program, Segment, SteadyState, analyse

FOLLOWER = dict(kind="translating-roller", mass_kg=1.5, stiffness_n_per_mm=2000.0, damping_ratio=0.05,
                spring_rate_n_per_mm=10.0, preload_n=300.0, base_radius_mm=40.0, roller_radius_mm=12.0)


def _cam(**follower):
    law = laws.get("cycloidal")
    return Program("two-cycloids", (Segment(100, 20.0, law), Segment(80), Segment(100, -20.0, law), Segment(80)),
                   Follower(**{**FOLLOWER, **follower}))


def test_a_very_stiff_train_is_refused_with_the_speed_that_would_fit():
    """1e12 N/mm ran 105 s and ended out of memory; now refused at once."""
    start = time.perf_counter()
    with pytest.raises(ValueError, match=r"a turn at 600 rpm needs [\d,]+ grid intervals \(the limit is "
                                         r"1,048,576\).*run at .* rpm or faster, or lower "
                                         r"follower.stiffness_n_per_mm"):
        SteadyState(_cam(stiffness_n_per_mm=1e12), 600.0)
    assert time.perf_counter() - start < 5.0  # refused before any work (a generous bound)


def test_a_very_low_speed_is_refused_before_any_work():
    """--rpm 1e-6 asked for 287 GiB."""
    with pytest.raises(ValueError, match=r"a turn at 1e-06 rpm needs .* grid intervals"):
        analyse(_cam(), [1e-6, 600.0])


def test_thousands_of_tiny_segments_are_refused():
    """A lift table imported as 3600 segments of 0.1 degree asked for 40 GB."""
    law = laws.get("cycloidal")
    segments = tuple(Segment(0.1, 0.01 if i % 2 == 0 else -0.01, law) for i in range(3600))
    program = Program("table", segments, Follower(**FOLLOWER))
    with pytest.raises(ValueError, match="grid intervals"):
        SteadyState(program, 600.0)


def test_the_command_line_refuses_with_exit_2_and_one_line(tmp_path, capsys):
    path = tmp_path / "stiff.toml"
    path.write_text(_cam(stiffness_n_per_mm=1e12).to_toml())
    assert main(["program", str(path), "--rpm", "600"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err and "grid intervals" in err
