"""Defects a new user met outside the program's dynamics: each test failed before its fix."""

import dataclasses
import json
import math
import re
import warnings
from pathlib import Path

import jax
import pytest

import camjax
from camjax import distributed
from camjax.cli import main
from camjax.program import Program, Speeds, analyse, example_path, warn_implausible


@pytest.fixture(autouse=True)
def _no_user_cache(monkeypatch):
    """The commands here must not write into the user's compilation cache."""
    monkeypatch.setenv("CAMJAX_CACHE_DIR", "off")


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err.strip()


def _one_line_error(err: str, command: str) -> str:
    assert err.startswith(f"camjax {command}: error: ") and "\n" not in err, err
    return err[len(f"camjax {command}: error: "):]


# --- design --program: the program command's names, its options, one cam ---------------

def test_design_program_takes_a_built_in_example_by_name(capsys, tmp_path):
    """``feed`` is loaded (its segment count names the refusal), not "no such program file"."""
    code, _, err = run(capsys, "design", "--program", "feed", "--segment", "9", "--rpm", "100:200",
                       "--out", str(tmp_path / "o"), "--quiet")
    assert code == 2
    message = _one_line_error(err, "design")
    assert "no such program file" not in message
    assert "--segment" in message and str(len(Program.load(example_path("feed")).segments)) in message


@pytest.mark.parametrize("option, value", [("--band", "1:2"), ("--n", "3")])
def test_design_program_refuses_a_band_it_would_ignore(capsys, tmp_path, option, value):
    code, _, err = run(capsys, "design", "--program", "indexer", "--segment", "1", "--rpm",
                       "100:200", option, value, "--out", str(tmp_path / "o"))
    assert code == 2
    assert _one_line_error(err, "design") == (f"{option}: not with --program (the segment's band "
                                              "comes from --rpm)")
    assert not (tmp_path / "o").exists()  # refused before any work


def test_design_program_refuses_a_machine_file_as_such(capsys, tmp_path):
    machine = tmp_path / "press.toml"
    machine.write_text(f'[machine]\nname = "press"\n\n[[cam]]\nprogram = "{example_path()}"\n'
                       "phase_deg = 0\n")
    code, _, err = run(capsys, "design", "--program", str(machine), "--segment", "1", "--rpm",
                       "100:200", "--out", str(tmp_path / "o"))
    assert code == 2
    message = _one_line_error(err, "design")
    assert message.startswith(f"--program: {machine} is a machine file")
    assert "design takes one cam's program" in message and "unknown field" not in message


# --- errors after loading name the file --------------------------------------------------

def _program_file(tmp_path, old: str, new: str):
    path = tmp_path / "cam.toml"
    text = example_path().read_text()
    assert old in text
    path.write_text(text.replace(old, new))
    return path


def test_program_errors_after_loading_name_the_file(capsys, tmp_path):
    """No damping (the steady state's own check) and a grid too fine (too slow a speed):
    the message starts with the file, as the load-time checks' do."""
    path = _program_file(tmp_path, "damping_ratio = 0.05", "damping_ratio = 0")
    Program.load(path)  # loads: the steady state refuses it
    code, _, err = run(capsys, "program", str(path), "--rpm", "300")
    assert code == 2
    assert _one_line_error(err, "program") == (
        f"{path}: the periodic steady state needs follower.damping_ratio > 0 (without damping "
        "the start-up never settles)")
    code, _, err = run(capsys, "program", "--rpm", "0.01")  # the built-in indexer
    assert code == 2
    message = _one_line_error(err, "program")
    assert message.startswith(f"{example_path()}: a turn at 0.01 rpm needs ")
    # a load-time error keeps its single prefix
    code, _, err = run(capsys, "program", str(_program_file(tmp_path, "mass_kg = 1.5", "mass_kg = -1")))
    assert _one_line_error(err, "program") == f"{path}: follower.mass_kg must be positive, got -1"


def test_design_program_errors_after_loading_name_the_file(capsys, tmp_path):
    path = _program_file(tmp_path, "damping_ratio = 0.05", "damping_ratio = 0")
    code, _, err = run(capsys, "design", "--program", str(path), "--segment", "1", "--rpm",
                       "0.001:1", "--out", str(tmp_path / "o"), "--quiet")
    assert code == 2
    assert _one_line_error(err, "design").startswith(f"{path}: ")


# --- sweep spec advice, period_ratio's arguments -----------------------------------------

def test_sweep_spec_past_the_exact_reach_advises_a_smaller_stop(tmp_path):
    """At n = 1e6 no phase_step resolves the grid (the limit is 1.5): the advice is the
    exact path's reach, 2**20 * 1.5 / (2 pi) = 250,329.6, and a spec at that stop loads."""
    spec = 'output = "o"\n[period_ratio]\nvalues = [1.0, {}]\n[laws]\nnames = ["cycloidal"]\n'
    path = tmp_path / "spec.toml"
    path.write_text(spec.format("1e6"))
    with pytest.raises(ValueError) as error:
        distributed.load_spec(path)
    message = str(error.value)
    reach = math.floor(2**20 * 1.5 / (2 * math.pi))
    assert f"period ratios up to {reach:,} at phase_step 1.5: lower period_ratio.stop" in message
    assert "phase_step at least" not in message
    path.write_text(spec.format(reach))
    distributed.load_spec(path)
    path.write_text(spec.format(reach + 1))
    with pytest.raises(ValueError, match="period ratios up to"):
        distributed.load_spec(path)


def test_sweep_spec_advice_of_a_coarser_step_is_one_that_loads(tmp_path):
    """n = 1e5 at phase_step 0.5 needs a coarser step, which exists (below 1.5): the step
    advised loads."""
    spec = ('output = "o"\nphase_step = {}\n[period_ratio]\nvalues = [1.0, 1e5]\n[laws]\n'
            'names = ["cycloidal"]\n')
    path = tmp_path / "spec.toml"
    path.write_text(spec.format(0.5))
    with pytest.raises(ValueError, match=r"phase_step at least ([\d.]+), at most 1\.5$") as error:
        distributed.load_spec(path)
    advised = float(str(error.value).split("phase_step at least ")[1].split(",")[0])
    assert 2 * math.pi * 1e5 / 2**20 <= advised < 1.01 * 2 * math.pi * 1e5 / 2**20
    path.write_text(spec.format(advised))
    assert distributed.load_spec(path).phase_step == advised


@pytest.mark.parametrize("kwargs, name", [(dict(motion_time="0.05", mass=2.0, stiffness=4e6), "motion_time"),
                                          (dict(motion_time=0.05, mass="2", stiffness=4e6), "mass"),
                                          (dict(motion_time=None, inertia=0.01, torsional_rigidity=2e4),
                                           "motion_time")])
def test_period_ratio_refuses_a_string_naming_the_argument(kwargs, name):
    time = kwargs.pop("motion_time")
    with pytest.raises(ValueError, match=rf"^{name} must be a finite number \(SI units\), got "):
        camjax.period_ratio(time, **kwargs)
    # the same inputs as numbers: n = T sqrt(k/m) / (2 pi)
    assert camjax.period_ratio(0.05, mass=2.0, stiffness=4e6) == pytest.approx(
        0.05 * math.sqrt(2e6) / (2 * math.pi), rel=1e-15)


# --- implausible speeds ------------------------------------------------------------------

def test_an_implausible_speed_is_warned_of_by_the_library():
    """The indexer's shortest moving segment spans 100 degrees: its period ratio is
    f_n 60 / rpm * 100 / 360 with f_n = sqrt((k + k_s) / m) / (2 pi)."""
    program = Program.load(example_path())
    f_n = math.sqrt((2000e3 + 10e3) / 1.5) / (2 * math.pi)
    edge = f_n * 60 * (100 / 360) / 0.05  # the speed at which that ratio is 0.05: 61,370 rpm
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warn_implausible(program, Speeds([600.0, 0.99 * edge]))  # plausible: no warning
        Speeds([1e9])  # without a program: positive and finite is all
    ratio = f_n * 60 / (1.01 * edge) * 100 / 360
    with pytest.warns(UserWarning, match=rf"indexer at {1.01 * edge:g} rpm: the shortest moving "
                      rf"segment's period ratio is {ratio:.2g}, below 0.05: "
                      r"the follower cannot follow the motion at all \(check the speed's units\)$"):
        warn_implausible(program, Speeds([600.0, 1.01 * edge]))
    with pytest.warns(UserWarning, match=r"at 1e\+09 rpm: faster than any cam runs \(above 100,000 rpm\); "):
        warn_implausible(program, Speeds([1e9]))
    stiff = Program.load(example_path())  # 4 times as stiff: n = 0.061 at 101,000 rpm
    stiff = dataclasses.replace(stiff, follower=dataclasses.replace(stiff.follower, stiffness_n_per_mm=8000))
    with pytest.warns(UserWarning, match=r"at 101000 rpm: faster than any cam runs \(above 100,000 rpm\) \("):
        warn_implausible(stiff, Speeds([101_000.0]))


def test_program_command_warns_of_an_implausible_speed_on_one_line(capsys):
    code, out, err = run(capsys, "program", "--rpm", "1e5", "--no-flight", "--format", "json")
    assert code == 0
    lines = [x for x in err.splitlines() if x.startswith("warning: ")]
    assert len(lines) == 1 and lines[0].startswith("warning: indexer at 100000 rpm: ")
    assert json.loads(out)["warnings"] == [lines[0][len("warning: "):]]  # in the report, as JSON shows it
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # one mechanism: the report's warnings, not a UserWarning too
        report = analyse(Program.load(example_path()), [1e5], with_flight=False)
    assert [w for w in report.warnings if "the follower cannot follow" in w] == [lines[0][len("warning: "):]]


# --- a traced period ratio past the default grid -----------------------------------------

def test_a_traced_period_ratio_past_the_default_grid_says_which_grid_to_pass():
    """n = 200 under jit: refused on the traced default grid (704 intervals, n <= 168) with
    the resolution to pass, 2 pi n / 1.5 per rise; with it, jit gives the concrete call's Ct
    (two grids, 838 and the concrete 896 intervals: each within the exact path's accuracy,
    about 1e-11, docs/work-precision.md)."""
    law = camjax.laws.get("modified-sine")
    concrete = float(camjax.torsion_factor(law, 200.0))
    with pytest.raises(Exception, match=r"period ratio must be at most 168 .*: pass resolution >= "
                       r"4\.19 n, up to 1,048,576 \(n <= 250,329\), such as torsion_factor\(law, n, "
                       r"resolution=4096\) for n <= 977"):
        jax.block_until_ready(jax.jit(lambda n: camjax.torsion_factor(law, n))(200.0))
    needed = math.ceil(2 * math.pi * 200.0 / 1.5)
    assert needed == 838
    jitted = jax.jit(lambda n: camjax.torsion_factor(law, n, resolution=needed))(200.0)
    assert float(jitted) == pytest.approx(concrete, rel=1e-10)
    assert float(jitted) != pytest.approx(1.0, abs=1e-4)  # Ct of a real response, not a fill


# --- docs that mislead -------------------------------------------------------------------

ROOT = Path(__file__).parents[1]


def test_the_sweep_page_documents_every_key_and_its_example_loads(tmp_path):
    page = (ROOT / "docs" / "sweep.md").read_text()
    for key in distributed.SPEC_KEYS | {"start", "stop", "count", "values", "names", "scca_step", "scca_face"}:
        assert f"`{key}`" in page or f"`[{key}]`" in page, key
    spec = tmp_path / "spec.toml"
    spec.write_text(re.search(r"```toml\n(.*?)```", page, re.S).group(1))
    loaded = distributed.load_spec(spec)
    assert (len(loaded.laws), loaded.period_ratio.size, len(loaded.chunks())) == (2 + 231, 1000, 8)
    assert "sweep.md" in (ROOT / "mkdocs.yml").read_text()
    assert "docs/sweep.md" in (ROOT / "README.md").read_text()


def test_getting_started_states_the_exact_paths_reach_from_the_code():
    from camjax.sdof import MAX_GRID_INTERVALS, MAX_PHASE_STEP

    reach = math.floor(MAX_GRID_INTERVALS * MAX_PHASE_STEP / (2 * math.pi))
    page = (ROOT / "docs" / "getting-started.md").read_text()
    assert f"n above about {reach:,}" in page and "83,000" not in page
    with pytest.raises(ValueError, match="grid intervals"):
        camjax.ct_curve("cycloidal", [reach + 1.0])
    install = re.search(r'pip install "jax\[(cuda\d+)\]', page).group(1)
    assert f"`jax[{install}]` for a CUDA {install[4:]} driver, as below" in page


def test_the_program_page_says_which_damping_the_steady_state_needs():
    page = " ".join((ROOT / "docs" / "program.md").read_text().split())
    assert "`damping_ratio > 0`" in page
    program = Program.load(example_path())
    undamped = dataclasses.replace(program, follower=dataclasses.replace(program.follower, damping_ratio=0.0))
    with pytest.raises(ValueError, match=r"needs follower\.damping_ratio > 0"):
        analyse(undamped, [300.0])


def test_a_cam_without_phase_deg_is_documented_at_zero(tmp_path):
    page = " ".join((ROOT / "docs" / "machine.md").read_text().split())
    assert "without `phase_deg`" in page
    machine = tmp_path / "m.toml"
    machine.write_text(f'[machine]\nname = "m"\n\n[[cam]]\nprogram = "{example_path()}"\n')
    assert camjax.program.Machine.load(machine).cams[0][1] == 0.0
