"""Work too large to fit is refused before it starts, with what to change (a one-line
``ValueError`` at the API, exit 2 at the command line), never an out-of-memory traceback."""

import pytest
from helpers import FOLLOWER, compiled_programs, two_cycloids

from camjax import laws
from camjax.cli import main
from camjax.program import Follower, Program, Segment, SteadyState, analyse


def test_a_very_stiff_train_is_refused_with_the_speed_that_would_fit():
    """1e12 N/mm ran 105 s and ended out of memory; now refused at once."""
    program = two_cycloids(stiffness_n_per_mm=1e12)  # its laws' evaluation compiles here
    with compiled_programs() as compiled, pytest.raises(
            ValueError, match=r"a turn at 600 rpm needs [\d,]+ grid intervals \(the limit is "
                              r"1,048,576\).*run at .* rpm or faster, or lower follower.stiffness_n_per_mm"):
        SteadyState(program, 600.0)
    assert compiled == []  # refused before any work (its time: experiments/benchmarks/refusal_speed.py)


def test_a_very_low_speed_is_refused_before_any_work():
    """--rpm 1e-6 asked for 287 GiB."""
    with pytest.raises(ValueError, match=r"a turn at 1e-06 rpm needs .* grid intervals"):
        analyse(two_cycloids(), [1e-6, 600.0])


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
