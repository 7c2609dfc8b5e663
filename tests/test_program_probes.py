"""A per-speed output of a cam program is one probe: registered by name, reported by
``analyse``, printed and written by ``camjax program``."""

import csv
import io

import numpy as np
import pytest

import camjax.program as cp
from camjax.cli import main


def _mean_force(cycle, turn):
    widths = turn.grid.motion.widths
    force = cycle.contact_force_n
    return (widths * (force[:-1] + force[1:]) / 2).sum()


@pytest.fixture
def probe():
    cp.register_probe("mean_contact_force_n", _mean_force, label="mean Fc N")
    yield
    cp.unregister_probe("mean_contact_force_n")


def _expected(program):
    """``F_0 + k k_s / (k + k_s) * mean lift``: the means of ``m x''`` and ``c e'`` vanish
    over a periodic steady state (independent of the engine: the lift alone)."""
    f = program.follower
    theta = np.linspace(0.0, 360.0, 72001)
    mean_lift = np.trapezoid(program.lift(theta)[0], theta) / 360.0
    k, k_s = f.stiffness_n_per_mm, f.spring_rate_n_per_mm
    return f.preload_n + k * k_s / (k + k_s) * mean_lift


def test_a_probe_is_reported_printed_and_written(probe, capsys):
    program = cp.Program.load(cp.example_path("indexer"))
    report = cp.analyse(program, [300.0, 450.0], with_flight=False)
    expected = _expected(program)
    for speed in report.speeds:
        assert speed.mean_contact_force_n == pytest.approx(expected, rel=2e-5)  # trapezoid rules
        assert speed.as_dict()["mean_contact_force_n"] == speed.outputs["mean_contact_force_n"]
    assert main(["program", "indexer", "--rpm", "300,450", "--no-flight", "--format", "csv"]) == 0
    rows = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert [float(r["mean_contact_force_n"]) for r in rows] == pytest.approx(
        [s.mean_contact_force_n for s in report.speeds], rel=1e-12)
    assert main(["program", "indexer", "--rpm", "300,450", "--no-flight"]) == 0
    assert "mean Fc N" in capsys.readouterr().out


def test_probe_names_are_checked():
    with pytest.raises(ValueError, match="built-in output"):
        cp.register_probe("min_contact_force_n", _mean_force)
    with pytest.raises(ValueError, match="lower-case Python name"):
        cp.register_probe("Mean force", _mean_force)
    with pytest.raises(ValueError, match="no probe named"):
        cp.unregister_probe("nothing")
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        _ = cp.SpeedReport(1.0, 0, 0, 0, 0, False, None, (), ()).nothing
