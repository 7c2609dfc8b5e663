"""A per-speed output of a cam program is one probe: registered by name, reported by
``analyse``, printed and written by ``camjax program``."""

import csv
import io
import tomllib

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
        assert speed.as_dict()["mean_contact_force_n"] == speed.values["mean_contact_force_n"]
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
        _ = cp.SpeedReport(1.0, {}).nothing


def test_a_probe_lands_in_the_table_csv_json_and_summary_like_a_built_in_output(probe, capsys, tmp_path):
    """Every place ``camjax program`` writes per-speed outputs reads the one registry
    (``OUTPUTS``): the probe's value, against the mean lift's closed form, in each."""
    import json

    expected = _expected(cp.Program.load(cp.example_path("indexer")))
    args = ["program", "indexer", "--rpm", "300,450", "--no-flight"]
    assert main([*args, "--format", "json", "--out", str(tmp_path), "--points", "8"]) == 0
    printed = json.loads(capsys.readouterr().out)
    written = json.loads((tmp_path / "summary.json").read_text())
    assert written == printed
    for speed in printed["speeds"]:
        assert speed["mean_contact_force_n"] == pytest.approx(expected, rel=2e-5)
    assert main([*args, "--format", "csv"]) == 0
    header, *rows = list(csv.reader(io.StringIO(capsys.readouterr().out)))
    place = header.index("mean_contact_force_n")  # after the built-in outputs, before the lists
    assert header[place - 1] == "contact_half_width_mm" and header[place + 1] == "period_ratio_1"
    assert [float(r[place]) for r in rows] == pytest.approx([expected] * 2, rel=2e-5)
    assert main(args) == 0
    lines = capsys.readouterr().out.splitlines()
    title = next(i for i, line in enumerate(lines) if "mean Fc N" in line)
    assert lines[title].split() == ["rpm", "mean", "Fc", "N"]
    for line, rpm in zip(lines[title + 1:title + 3], (300, 450)):
        assert float(line.split()[0]) == rpm
        assert float(line.split()[1]) == pytest.approx(expected, rel=1e-5)  # 6 digits printed


def test_every_output_of_a_speed_is_a_probe_of_the_set_it_was_computed_with():
    """One keyed set: each built-in output is a ``Probe`` with a function (compiled or on
    the host), label and doc; a speed's row holds exactly the set's outputs, and its JSON is
    ``rpm``, those outputs and the structured fields."""
    assert all(p.built_in and (p.fn or p.host) and p.label and p.doc for p in cp.BUILT_IN)
    assert list(cp.Outputs()) == [p.name for p in cp.BUILT_IN]
    report = cp.analyse(cp.Program.load(cp.example_path("indexer")), [300.0], with_flight=False)
    speed = report.speeds[0]
    assert list(speed.values) == list(report.outputs) == [p.name for p in report.columns()]
    structured = {"rpm", "residual_vibration_mm", "period_ratios", "flight", "flights", "impacts",
                  "impacts_change_deg"}
    assert set(speed.as_dict()) == structured | set(cp.Outputs())
    with pytest.raises(ValueError, match="built-in output"):
        cp.Outputs([cp.BUILT_IN[0], cp.Probe("min_contact_force_n", _mean_force, "x")])


def _bench_report(bench, toml: str) -> dict:
    return bench.update(tomllib.loads(toml), "300,450")  # the program's structure, as the page posts it


def test_a_probe_registered_or_not_gives_each_analysis_its_own_report():
    """The same analysis in one process with a probe registered and not, through the
    library and the studio's workbench (its report cache keys on the outputs): each gets
    its own report; a probe passed in (``outputs=``) is reported without the registry, and
    another function under the same name is compiled anew (the set is the static argument,
    not the name)."""
    from camjax.studio import Workbench

    path = cp.example_path("indexer")
    program, toml = cp.Program.load(path), path.read_text()
    bench = Workbench(toml, "300,450", path.parent, with_flight=False)
    expected = _expected(program)

    def library():
        return cp.analyse(program, [300.0, 450.0], with_flight=False)

    plain, page = library(), _bench_report(bench, toml)
    cp.register_probe("mean_contact_force_n", _mean_force, label="mean Fc N", unit="N")
    try:
        probed, probed_page = library(), _bench_report(bench, toml)
        columns = bench.output_columns()
    finally:
        cp.unregister_probe("mean_contact_force_n")
    again, again_page = library(), _bench_report(bench, toml)
    for without in (plain.as_dict(), page, again.as_dict(), again_page):
        assert all("mean_contact_force_n" not in s for s in without["speeds"])
    for with_probe in (probed.as_dict(), probed_page):
        assert [s["mean_contact_force_n"] for s in with_probe["speeds"]] == pytest.approx([expected] * 2, rel=2e-5)
    assert {"name": "mean_contact_force_n", "label": "mean Fc N", "unit": "N"}.items() <= columns[-1].items()
    assert [c["name"] for c in columns[:-1]] == [p.name for p in cp.BUILT_IN]
    # the other outputs are the same numbers whichever set computed them
    for a, b in zip(plain.speeds, probed.speeds):
        assert a.values == {k: v for k, v in b.values.items() if k != "mean_contact_force_n"}
    # passed in, not registered; the same name with another function is another program
    passed = cp.analyse(program, [300.0], with_flight=False, outputs=[cp.probe("mean_contact_force_n", _mean_force)])
    doubled = cp.analyse(program, [300.0], with_flight=False,
                         outputs=[cp.probe("mean_contact_force_n", lambda c, t: 2 * _mean_force(c, t))])
    assert passed.speeds[0].mean_contact_force_n == pytest.approx(expected, rel=2e-5)
    assert doubled.speeds[0].mean_contact_force_n == pytest.approx(2 * expected, rel=2e-5)
    assert "mean_contact_force_n" not in cp.OUTPUTS
