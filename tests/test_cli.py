"""The core commands: output shapes, files written, and exit status 2 on bad input."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from helpers import COMPILED_RTOL, assert_same_numbers

import camjax
from camjax import laws
from camjax.cli import main


@pytest.fixture(autouse=True)
def _no_user_cache(monkeypatch):
    """The commands here must not write into the user's compilation cache."""
    monkeypatch.setenv("CAMJAX_CACHE_DIR", "off")


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_laws_json_lists_every_standard_law(capsys):
    code, out, _ = run(capsys, "laws", "--format", "json")
    table = json.loads(out)
    assert code == 0 and list(table) == laws.names()
    assert table["modified-sine"]["Ca"] == pytest.approx(5.52796, abs=1e-5)
    assert table["parabolic"]["Cj"] is None  # infinite jerk (acceleration step) -> null


def test_ct_json_matches_the_library(capsys):
    code, out, _ = run(capsys, "ct", "--law", "modsine", "--law", "cycloidal",
                       "--n", "2,5.5,9", "--damping", "0.05", "--format", "json")
    data = json.loads(out)
    assert code == 0
    assert data["period_ratio"] == [2.0, 5.5, 9.0] and data["damping"] == 0.05
    assert data["method"] == "exact" and list(data["laws"]) == ["modified-sine", "cycloidal"]
    curve = camjax.ct_curve(laws.ModifiedSine(), [2.0, 5.5, 9.0], damping=0.05)
    entry = data["laws"]["modified-sine"]
    np.testing.assert_allclose(entry["ct"], curve.ct, rtol=COMPILED_RTOL)
    np.testing.assert_allclose(entry["residual"], curve.residual, rtol=COMPILED_RTOL)
    np.testing.assert_allclose(entry["peak_in_motion"], curve.peak_in_motion, rtol=COMPILED_RTOL)
    assert entry["Ca"] == pytest.approx(5.52796, abs=1e-5) and "Cv" in entry and "Cj" in entry


def test_ct_says_the_files_it_wrote_and_writes_to_the_current_directory_for_an_empty_out(
        capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, "ct", "--law", "cycloidal", "--n", "2,5", "--out", "")
    assert code == 0  # two ratios: no envelope to fit, so no Ca*Ct chart
    assert err.strip() == ("wrote ./: ct.csv, ct.json, torsion_factor_fit.md, ct_curves.png, "
                           "residual_curves.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "ct.csv", "ct.json", "ct_curves.png", "residual_curves.png", "torsion_factor_fit.md"]


def test_ct_writes_tables_and_figures(capsys, tmp_path):
    code, out, _ = run(capsys, "ct", "--law", "cycloidal", "--law", "modified-sine",
                       "--n", "1:20:120", "--out", str(tmp_path))
    assert code == 0 and "cycloidal" in out
    for name in ("ct.csv", "ct.json", "torsion_factor_fit.md", "ct_curves.png",
                 "residual_curves.png", "ca_ct.png"):
        assert (tmp_path / name).stat().st_size > 0
    rows = (tmp_path / "ct.csv").read_text().splitlines()
    assert rows[0] == "law,period_ratio,ct,residual,peak_in_motion,ca_ct,result" and len(rows) == 241
    assert all(row.endswith(",successful") for row in rows[1:])
    assert "| cycloidal |" in (tmp_path / "torsion_factor_fit.md").read_text()
    # Read back: the cycloidal law's undamped residual is 2 n |sin(pi n)| / |n^2 - 1| (pi at
    # n = 1), Ct and Ca*Ct those of ct_curve, for both laws.
    table = np.genfromtxt(tmp_path / "ct.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    cyc = table[table["law"] == "cycloidal"]
    n = cyc["period_ratio"]
    np.testing.assert_allclose(n, np.linspace(1.0, 20.0, 120), rtol=1e-9)
    with np.errstate(invalid="ignore", divide="ignore"):
        closed = np.where(n == 1.0, np.pi, 2 * n * np.abs(np.sin(np.pi * n)) / np.abs(n**2 - 1))
    np.testing.assert_allclose(cyc["residual"], closed, rtol=0, atol=1e-8)
    for name, law in (("cycloidal", laws.Cycloidal()), ("modified-sine", laws.ModifiedSine())):
        rows = table[table["law"] == name]
        curve = camjax.ct_curve(law, rows["period_ratio"])
        np.testing.assert_allclose(rows["ct"], curve.ct, rtol=1e-9)
        np.testing.assert_allclose(rows["ca_ct"], float(law.Ca) * curve.ct, rtol=1e-9)


def test_ct_finishes_a_sweep_with_failed_ratios_and_names_them(capsys, tmp_path):
    """Heun at the default grid for n <= 20 (three steps per interval) is stable up to n ~
    14: the ratios past it fail, the sweep goes on, exits 0, and marks them in every
    output."""
    code, _, err = run(capsys, "ct", "--law", "cycloidal", "--method", "heun", "--n", "1:20:12",
                       "--out", str(tmp_path))
    assert code == 0
    warning = [line for line in err.splitlines() if "warning" in line]
    assert warning == [
        "camjax ct: warning: cycloidal: the solver failed at 4 of 12 period ratios (n = 14.8182, "
        "16.5455, 18.2727, 20; unstable_fixed_step); their metrics are NaN in the output"
    ]
    curve = camjax.ct_curve(laws.Cycloidal(), np.linspace(1, 20, 12), method="heun", throw=False)
    failed = [False] * 8 + [True] * 4
    np.testing.assert_array_equal(curve.failed, failed)
    rows = [row.split(",") for row in (tmp_path / "ct.csv").read_text().splitlines()[1:]]
    assert [row[-1] for row in rows] == curve.result_names
    assert [row[2] == "nan" for row in rows] == failed
    np.testing.assert_allclose([float(row[2]) for row in rows[:8]], curve.ct[:8], rtol=1e-11)
    entry = json.loads((tmp_path / "ct.json").read_text())["laws"]["cycloidal"]
    assert entry["result"] == ["successful"] * 8 + ["unstable_fixed_step"] * 4
    assert [x is None for x in entry["ct"]] == failed


@pytest.mark.parametrize(
    "argv, message",
    [
        (("ct", "--law", "nope", "--n", "2"), "unknown law 'nope'"),
        (("ct", "--n", "2,-1"), "must be positive, got -1"),
        (("ct", "--n", "2,abc"), "cannot read"),
        (("ct", "--n", "1:5"), "START:STOP:COUNT"),
        (("ct", "--n", "2", "--damping", "1.5"), "damping ratio"),
        (("ct", "--n", "2", "--method", "rk99"), "unknown method"),
        (("ct", "--n", "nan"), "finite"),
        (("ct", "--n", "10:5:6"), "START must be below STOP"),
        (("ct", "--law", ",", "--n", "2"), "no law name"),
        (("bench", "--law", "nope"), "unknown law 'nope'"),
        (("design", "--band", "6:12", "--max-jerk", "31", "--out", "{tmp}"), "Cj >= 32"),
        (("design", "--band", "6:12", "--max-ca", "6", "--max-jerk", "35", "--out", "{tmp}"),
         "Cj >= 36"),
        (("design", "--band", "6:12", "--objective", "preload", "--out", "{tmp}"),
         "--objective preload needs --program"),
    ],
)
def test_bad_arguments_exit_2_with_one_line(capsys, tmp_path, argv, message):
    code, out, err = run(capsys, *(a.replace("{tmp}", str(tmp_path)) for a in argv))
    assert code == 2 and out == ""
    assert message in err and len(err.strip().splitlines()) == 1


_HELP_SCRIPT = """
import sys
from camjax.cli import COMMANDS, main
texts = {}
for argv in [["--help"]] + [[name, "--help"] for name in COMMANDS]:
    try:
        main(argv)
    except SystemExit:
        pass
assert "jax" not in sys.modules, "printing help imported JAX"
"""


def test_help_imports_no_jax_and_states_defaults():
    """Every --help runs without importing JAX, with defaults and no reST markup."""
    import os
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", _HELP_SCRIPT], capture_output=True, text=True,
                          env={**os.environ, "COLUMNS": "200"}, check=True)
    text = done.stdout
    assert "``" not in text
    assert "optimiser steps (default: 6000)" in text
    assert "damping ratio zeta in [0, 1) (dimensionless) (default: 0.0)" in text
    assert "or a law file written by `camjax design` (law.json)" in text


def test_cli_defaults_agree_with_the_library():
    from camjax import law_design
    from camjax.cli import design

    assert design.DEFAULT_STEPS == law_design.DEFAULT_STEPS


def test_least_jerk_matches_the_bang_bang_rise():
    """The bang-bang jerk +-32 (switches at 1/4, 3/4) travels exactly 1; others need more."""
    from camjax.law_design import MIN_CJ, least_jerk

    # From rest, s(1) = int j (1-t)^2/2, v(1) = int j (1-t), a(1) = int j: exact per piece.
    pieces = [(0.0, 0.25, MIN_CJ), (0.25, 0.75, -MIN_CJ), (0.75, 1.0, MIN_CJ)]
    s = sum(j * ((1 - a) ** 3 - (1 - b) ** 3) / 6 for a, b, j in pieces)
    v = sum(j * ((1 - a) ** 2 - (1 - b) ** 2) / 2 for a, b, j in pieces)
    acc = sum(j * (b - a) for a, b, j in pieces)
    assert s == pytest.approx(1.0, abs=1e-14) and v == 0 and acc == 0
    # With |a| <= A = 6 the trapezoid of ramps A/J travels A (1/2 - A/J) / 2 = 1 at J = 36.
    assert least_jerk(6.0) == pytest.approx(36.0)
    assert least_jerk(None) == least_jerk(9.0) == MIN_CJ
    for law in laws.standard_laws():
        assert float(law.Cj) > MIN_CJ


def test_cache_dir_follows_the_environment(monkeypatch, tmp_path):
    from camjax.cli import cache_dir

    monkeypatch.setenv("CAMJAX_CACHE_DIR", str(tmp_path))
    assert cache_dir() == tmp_path
    for off in ("0", "off", "OFF", ""):
        monkeypatch.setenv("CAMJAX_CACHE_DIR", off)
        assert cache_dir() is None
    monkeypatch.delenv("CAMJAX_CACHE_DIR")
    assert cache_dir().name == "jax" and "camjax" in str(cache_dir())


def test_the_executable_ends_early_without_losing_output_or_exit_status(capsys, tmp_path):
    """``python -m camjax`` skips interpreter shutdown (camjax.cli.command): its output, files
    and exit status must equal those of ``main`` run in this process (numbers to rounding:
    the executable compiles with XLA's classic CPU emitters, which round differently)."""
    import os
    import subprocess
    import sys

    argv = ["ct", "--law", "cycloidal", "--n", "2,3.5", "--format", "json"]
    env = {**os.environ, "CAMJAX_CACHE_DIR": "off"}
    done = subprocess.run([sys.executable, "-m", "camjax", *argv, "--out", str(tmp_path)],
                          capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode == 0, done.stderr
    code, out, _ = run(capsys, *argv)
    assert code == 0
    assert_same_numbers(json.loads(done.stdout), json.loads(out))
    assert done.stderr.startswith(f"wrote {tmp_path}/")
    rows = (tmp_path / "ct.csv").read_text().splitlines()
    assert len(rows) == 3 and rows[1].startswith("cycloidal,2,")
    for figure in ("ct_curves.png", "residual_curves.png"):
        data = (tmp_path / figure).read_bytes()  # a whole PNG ends with its IEND chunk
        assert data.startswith(b"\x89PNG") and data.endswith(b"IEND\xaeB`\x82")
    for argv, status in ((["ct", "--n", "0,1"], 2), (["ct", "--bogus"], 2), (["--help"], 0)):
        done = subprocess.run([sys.executable, "-m", "camjax", *argv], capture_output=True,
                              text=True, env=env, timeout=300)
        assert done.returncode == status, (argv, done.stderr)


@pytest.mark.parametrize("argv, expected", [
    (["ct", "--out", "d"], True),
    (["program", "feed"], True),
    (["ct", "--n", "1:30:200000"], False),  # a long sweep keeps XLA's default emitters
    (["ct", "--n=1:30:200000"], False),
    (["sweep", "spec.toml"], False),
    (["bench"], False),
])
def test_short_commands_compile_with_the_classic_cpu_emitters(monkeypatch, argv, expected):
    """... and pass the sweeps the dense peak search (cheaper to compile) and XLA's own
    vector width; long ones keep the library's defaults (no options given)."""
    from camjax.cli import build_parser, compile_for_one_run
    from camjax.sharding import SweepOptions

    monkeypatch.setenv("XLA_FLAGS", "--xla_force_host_platform_device_count=1")
    args = build_parser().parse_args(argv)
    assert args.sweep_options == {}
    compile_for_one_run(args)
    flags = os.environ["XLA_FLAGS"]
    assert ("--xla_cpu_use_fusion_emitters=false" in flags) == expected
    assert flags.startswith("--xla_force_host_platform_device_count=1")
    one_run = {"peak_search": "dense", "sweep": SweepOptions(cpu_compiler_options=())}
    assert args.sweep_options == (one_run if expected else {})


def test_a_short_commands_sweep_options_reach_the_library(monkeypatch, capsys):
    """``camjax ct`` run as the executable runs it (``one_run``) passes its sweep options to
    ``ct_curve`` (the exact path takes both; another model only ``sweep``), and reports
    the numbers of the library's defaults within the peak search's tolerance."""
    from camjax.cli import build_parser, sweep_options_for
    from camjax.metrics import PEAK_TOLERANCE
    from camjax.sharding import SweepOptions

    monkeypatch.setenv("XLA_FLAGS", os.environ.get("XLA_FLAGS", ""))  # restored afterwards
    argv = ["ct", "--law", "modified-trapezoid", "--n", "2,5.5,9", "--format", "json"]
    assert main(argv, one_run=True) == 0
    data = json.loads(capsys.readouterr().out)["laws"]["modified-trapezoid"]
    curve = camjax.ct_curve("modified-trapezoid", [2.0, 5.5, 9.0])
    for metric in ("ct", "residual", "peak_in_motion"):
        np.testing.assert_allclose(data[metric], getattr(curve, metric), rtol=PEAK_TOLERANCE)
    args = build_parser().parse_args(["ct"])
    args.sweep_options = {"peak_search": "dense", "sweep": SweepOptions.run_once()}
    assert sweep_options_for(args, camjax.SpringMass(1.0)) == args.sweep_options
    assert sweep_options_for(args, camjax.CoulombFriction(1.0, 0.05)) == {
        "sweep": SweepOptions.run_once()}


def test_a_users_emitter_flag_wins(monkeypatch):
    from camjax.cli import build_parser, compile_for_one_run

    monkeypatch.setenv("XLA_FLAGS", "--xla_cpu_use_fusion_emitters=true")
    compile_for_one_run(build_parser().parse_args(["ct"]))
    assert os.environ["XLA_FLAGS"] == "--xla_cpu_use_fusion_emitters=true"


def test_a_failed_solve_inside_a_command_is_one_line_not_a_traceback(capsys, monkeypatch):
    """A command whose solve fails (here a real unstable fixed-step solve in place of the
    follower's run) ends with one line naming the command and exit code 1."""
    from camjax.cli import follower

    def failing(args):
        camjax.solve("cycloidal", camjax.SpringMass(50.0), method="euler", steps=100)
        return 0

    monkeypatch.setattr(follower, "run", failing)
    code, out, err = run(capsys, "follower", "--law", "cycloidal")
    assert code == 1 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("camjax follower: error: ")
    assert "unstable" in lines[0] or "fixed-step" in lines[0]


@pytest.mark.parametrize("argv, user, expected", [
    (["follower", "--law", "cycloidal"], None, "nan"),
    (["follower", "--law", "cycloidal"], "raise", "raise"),  # the user's setting wins
    (["ct"], None, None),  # other commands keep equinox's runtime errors
])
def test_the_follower_command_checks_by_select_not_callback(monkeypatch, argv, user, expected):
    """The executable sets ``EQX_ON_ERROR=nan`` for ``camjax follower`` before equinox is
    imported, so that its solve carries no host callback (``store_checked_solves``)."""
    from camjax.cli import build_parser, compile_for_one_run

    monkeypatch.setenv("XLA_FLAGS", os.environ.get("XLA_FLAGS", ""))  # restored afterwards
    monkeypatch.delitem(sys.modules, "equinox")  # as in a fresh process (restored afterwards)
    if user is None:
        monkeypatch.delenv("EQX_ON_ERROR", raising=False)
    else:
        monkeypatch.setenv("EQX_ON_ERROR", user)
    compile_for_one_run(build_parser().parse_args(argv))
    assert os.environ.get("EQX_ON_ERROR") == expected


def test_the_follower_commands_solve_is_kept_in_the_persistent_cache(tmp_path):
    """Run as the executable, ``camjax follower`` stores its solve (``jit__response``) in
    JAX's persistent cache, which keeps no program with a host callback: the next run
    loads it instead of compiling it again."""
    env = dict(os.environ, CAMJAX_CACHE_DIR=str(tmp_path))
    env.pop("EQX_ON_ERROR", None)
    run = subprocess.run(
        [sys.executable, "-m", "camjax", "follower", "--law", "cycloidal", "--modes", "1",
         "--axial-modes", "1", "--format", "json"],
        env=env, capture_output=True, text=True, timeout=600,
    )
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["max_constraint_error"] < 1e-6
    assert list(tmp_path.rglob("jit__response-*")), sorted(p.name for p in tmp_path.iterdir())
