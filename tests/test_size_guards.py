"""Work too large to fit is refused before it starts, with what to change (a one-line
``ValueError`` at the API, exit 2 at the command line), never an out-of-memory traceback."""

import math
import re

import pytest
from helpers import FOLLOWER, compiled_programs, two_cycloids

from camjax import laws
from camjax.cli import main
from camjax.program import Follower, Program, Segment, SteadyState, analyse


def test_the_command_line_refuses_with_exit_2_and_one_line(tmp_path, capsys):
    path = tmp_path / "stiff.toml"
    path.write_text(two_cycloids(stiffness_n_per_mm=1e12).to_toml())
    assert main(["program", str(path), "--rpm", "600"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err and "grid intervals" in err


def test_a_program_of_the_most_segments_runs_in_bounded_memory():
    """3600 segments of 0.1 degree asked for 40 GB: the engine selected each interval's
    weights by a product with an intervals x pieces matrix.  Many pieces now gather them
    instead (the same numbers, next test); a program takes at most ``MAX_SEGMENTS`` (360)
    segments, and 360 of a degree each run in bounded memory."""
    from camjax.program import MAX_SEGMENTS

    law = laws.get("cycloidal")
    segments = tuple(Segment(360.0 / MAX_SEGMENTS, 0.01 if i % 2 == 0 else -0.01, law)
                     for i in range(MAX_SEGMENTS))
    out = SteadyState(Program("table", segments, Follower(**FOLLOWER)), 600.0).summary([600.0])
    # 0.01 mm wiggles at 3,600 per second barely move a 2000 N/mm train: the force stays
    # within a few N/mm of the preload's static value.
    assert 100.0 < float(out.min_contact_force_n[0]) <= 300.0 <= float(out.max_contact_force_n[0]) < 500.0


def test_gathered_and_multiplied_piece_weights_agree():
    import numpy as np

    from camjax import sdof

    edges = np.linspace(0.0, 1.0, 81)  # 80 pieces of 5 intervals: above the product's 64
    grid, times = sdof.piecewise_grid(edges, np.full(80, 5))
    grid = grid._replace(forcing=sdof.to_monomial(np.sin(7.0 * times) + times**2))
    for omega, zeta in ((40.0, 0.0), (300.0, 0.1)):
        product = sdof.propagate(grid, omega, zeta, gather=False)
        gathered = sdof.propagate(grid, omega, zeta, gather=True)
        assert np.max(np.abs(gathered - product)) <= 1e-13 * np.max(np.abs(product))


def test_a_sweep_of_too_many_period_ratios_is_refused_before_any_work(tmp_path, capsys):
    """--n 1:30:50000000 and a spec's count = 100000000 ran with no progress and no
    refusal; the API refuses the same (the count is checked before the array is built)."""
    import numpy as np

    import camjax
    from camjax.checks import MAX_PERIOD_RATIOS

    assert main(["ct", "--n", "1:30:50000000"]) == 2
    assert capsys.readouterr().err.strip() == (
        "camjax ct: error: --n: 50,000,000 period ratios is more than the 10,000,000 one sweep "
        "takes; sweep fewer, or split the range into several runs")
    spec = tmp_path / "spec.toml"
    spec.write_text(f'output = "{tmp_path / "out"}"\n[laws]\nnames = ["cycloidal"]\n'
                    "[period_ratio]\nstart = 1.0\nstop = 30.0\ncount = 100000000\n")
    assert main(["sweep", str(spec)]) == 2
    err = capsys.readouterr().err.strip()
    assert "period_ratio.count: 100,000,000 period ratios is more than" in err and "\n" not in err
    with pytest.raises(ValueError, match="10,000,001 period ratios is more than"):
        camjax.ct_curve("cycloidal", np.linspace(1.0, 2.0, MAX_PERIOD_RATIOS + 1))


# --- one grid-size check, one message shape, from every entry point that sizes a grid ----

GRID_REFUSAL = r"needs [\d,]+ grid intervals \(the limit is 1,048,576\): \S.*$"
"""``camjax.sdof.check_grid_size``'s message after the caller's ``what``: the remedy follows."""


def _spec_at_a_fine_step(tmp_path):
    from camjax import distributed

    path = tmp_path / "spec.toml"
    path.write_text('output = "o"\nphase_step = 1e-9\n[period_ratio]\nvalues = [1.0, 30.0]\n'
                    '[laws]\nnames = ["cycloidal"]\n')
    distributed.load_spec(path)


def _entry_points(tmp_path):
    """``{case: (call, what, remedy)}``; the programs are built here, outside the calls
    (a program's laws compile their evaluation when it is built)."""
    import camjax
    from camjax import law_design, studies
    from camjax.program import example_path

    stiff, plain = two_cycloids(stiffness_n_per_mm=1e12), two_cycloids()
    valve = Program.load(example_path("valve"))
    return {
        "a stiff train": (lambda: SteadyState(stiff, 600.0), r"^a turn at 600 rpm ",
                          "lower follower.stiffness_n_per_mm"),
        "a crawling speed": (lambda: analyse(plain, [1e-6, 600.0]), r"^a turn at 1e-06 rpm ", "run at "),
        "a chain at a crawl": (lambda: analyse(valve, [1e-6]), r"^a turn at 1e-06 rpm ", "run at "),
        "a rise of huge period ratio": (lambda: camjax.torsion_factor("cycloidal", 1e6),
                                        r"^a rise at period ratio 1e\+06 ", "period ratios up to about 250,329"),
        "a rise of huge resolution": (lambda: camjax.ct_curve("cycloidal", [2.0], resolution=2**21),
                                      r"^a rise at resolution 2,097,152 ", "pass resolution at most 1,048,576"),
        "a sweep spec's phase step": (lambda: _spec_at_a_fine_step(tmp_path),
                                      r"spec\.toml: a rise at period ratio 30 and phase_step 1e-09 ",
                                      "phase_step at least"),
        "a design's training grid": (lambda: law_design.MaxCaCt(1.0, 30000.0),
                                     r"^MaxCaCt: the training grid at period ratio 30000 ",
                                     "period ratios up to about 20,861"),
        "the study's reference": (lambda: studies.reference_resolution(1e5),
                                  r"^the reference \(.*\) at period ratio 100000 ", "period ratios up to 20,860"),
    }


@pytest.mark.parametrize("case", ["a stiff train", "a crawling speed", "a chain at a crawl",
                                  "a rise of huge period ratio", "a rise of huge resolution",
                                  "a sweep spec's phase step", "a design's training grid",
                                  "the study's reference"])
def test_every_entry_point_refuses_a_grid_past_the_limit_with_one_message_before_any_work(case, tmp_path):
    """Each caller names its request and what to change; the check is the engine's one
    (``camjax.sdof.check_grid_size``) and nothing is compiled before it refuses."""
    call, what, remedy = _entry_points(tmp_path)[case]
    with compiled_programs() as compiled, pytest.raises(ValueError) as error:
        call()
    message = str(error.value)
    assert re.search(what + GRID_REFUSAL, message), message
    assert remedy in message and "\n" not in message
    assert not [name for name in compiled if "cycle" in str(name)]  # the turn never compiled


def test_the_grid_check_passes_at_the_limit_and_asks_for_the_remedy_only_past_it():
    from camjax.sdof import MAX_GRID_INTERVALS, check_grid_size

    def remedy():
        raise AssertionError("the remedy is worded only for a refusal")

    check_grid_size(MAX_GRID_INTERVALS, "a grid at the limit", remedy)
    with pytest.raises(ValueError, match=r"^a grid needs 1,048,577 grid intervals \(the limit is "
                                         r"1,048,576\): use fewer$"):
        check_grid_size(MAX_GRID_INTERVALS + 1, "a grid", lambda: "use fewer")


def test_a_segmented_layout_meets_the_phase_step_and_each_minimum():
    """Counts by hand: 8 vibrations over a turn at w h <= 0.5 ask for 2 pi 8 / 0.5 = 100.5,
    so the floor of 256 per turn holds; a 90-degree rise with a breakpoint at 0.25 gets
    256 / 4 = 64 split 16 and 48, a 10-degree rise (the shortest) raises the turn to
    64 / (10/360) = 2304 intervals per turn (64 for it), a dwell gets its share."""
    import numpy as np

    from camjax.sdof import GridSegment, segment_layout

    few = segment_layout([GridSegment(0.0, 0.25, (0.25,)), GridSegment(0.25, 0.75, None)], 8.0)
    np.testing.assert_array_equal(few.counts, [16, 48, 192])
    np.testing.assert_allclose(few.edges, [0.0, 0.0625, 0.25, 1.0])
    np.testing.assert_array_equal(few.segment_start, [0, 64])
    short = segment_layout([GridSegment(0.0, 10 / 360, ()), GridSegment(10 / 360, 350 / 360, None)], 8.0)
    np.testing.assert_array_equal(short.counts, [64, 2240])
    fast = segment_layout([GridSegment(0.0, 1.0, ())], 1000.0)  # 2 pi 1000 / 0.5 = 12,566.4
    assert fast.intervals == 64 * math.ceil(2 * math.pi * 1000 / 0.5 / 64) == 12_608
    tiny = segment_layout([GridSegment(0.0, 0.5, (1e-6,)), GridSegment(0.5, 0.5, None)], 1.0)
    assert tiny.counts[0] == 4  # every piece gets four at least


def test_a_turn_too_large_for_the_memory_is_refused_with_the_slowest_speed_that_fits():
    """The flexible arm at a low speed asks for a grid within the interval limit but a block
    of speeds larger than the memory: refused before the turn compiles, naming the speed
    that fits; at that speed the steady state is built.  The budget is given (2 GB, so the
    test does not depend on the machine; by default half the device's memory)."""
    from camjax.program import block_memory_bytes, example_path

    arm = Program.load(example_path("swinging_arm"))
    with compiled_programs() as compiled, pytest.raises(ValueError) as refused:
        SteadyState(arm, 300.0, memory_bytes=2e9)
    assert not [name for name in compiled if "cycle" in str(name)]  # the turn never compiled
    message = str(refused.value)
    assert "\n" not in message and message.startswith("a turn at 300 rpm: ")
    need_gb, fits = re.search(r"need about ([\d.]+) GB .* run at ([\d,]+) rpm or faster", message).groups()
    faster = SteadyState(arm, float(fits.replace(",", "")), memory_bytes=2e9)
    held = block_memory_bytes(faster.grid.intervals, faster.oscillator)
    assert held <= 2e9 < 1e9 * float(need_gb)
    assert held > 0.8 * 2e9  # the speed named is near the slowest that fits, not far above it
