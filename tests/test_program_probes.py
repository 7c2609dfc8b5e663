"""A per-speed output of a cam program is one probe of a set passed in (``Outputs``):
reported by ``analyse``, printed and written by ``camjax program --probes``, shown by the
studio; no process-wide registry, so one process may analyse with a probe and without."""

import csv
import io
import json
import tomllib

import numpy as np
import pytest
from helpers import call

import camjax.program as cp
from camjax.cli import dump_json, main
from camjax.studio import Workbench, studio

RPM = [300.0, 450.0]
PROBE_NAME = "mean_contact_force_n"


def _mean_force(cycle, turn):
    widths = turn.grid.motion.widths
    force = cycle.contact_force_n
    return (widths * (force[:-1] + force[1:]) / 2).sum()


MEAN_FORCE = cp.probe(PROBE_NAME, _mean_force, label="mean Fc N", unit="N")
PROBED = cp.Outputs([MEAN_FORCE])


def _expected(program):
    """``F_0 + k k_s / (k + k_s) * mean lift``: the means of ``m x''`` and ``c e'`` vanish
    over a periodic steady state (independent of the engine: the lift alone)."""
    f = program.follower
    theta = np.linspace(0.0, 360.0, 72001)
    mean_lift = np.trapezoid(program.lift(theta)[0], theta) / 360.0
    k, k_s = f.stiffness_n_per_mm, f.spring_rate_n_per_mm
    return f.preload_n + k * k_s / (k + k_s) * mean_lift


def _same_numbers(a: dict, b: dict) -> None:
    """The same keys and values, numbers to 1e-9 relative (two compiled programs)."""
    assert a.keys() == b.keys()
    for key, x in a.items():
        y = b[key]
        if isinstance(x, float) and not isinstance(x, bool):
            assert y == pytest.approx(x, rel=1e-9, abs=1e-12), key
        elif isinstance(x, list):
            assert y == pytest.approx(x, rel=1e-9, abs=1e-12), key
        else:
            assert y == x, key


def _speeds(report: dict) -> list[dict]:
    """A report's speed rows as plain types, without the probe's column."""
    return [{k: v for k, v in s.items() if k != PROBE_NAME} for s in json.loads(dump_json(report))["speeds"]]


def test_the_same_analysis_with_a_probe_and_without_gets_each_its_own_report():
    """In one process, the library, the studio's workbenches (one report cache, which keys
    on the set of outputs) and two studios over HTTP analyse the same program with the probe
    and without, interleaved: the probe's column is in each report with it (its value the
    mean lift's closed form, and the studio's ``GET /api/outputs`` lists it) and in none
    without it, and every other number is the same."""
    path = cp.example_path("indexer")
    program, toml = cp.Program.load(path), path.read_text()
    expected = _expected(program)

    plain = cp.analyse(program, RPM, with_flight=False)
    probed = cp.analyse(program, RPM, with_flight=False, outputs=PROBED)
    again = cp.analyse(program, RPM, with_flight=False)
    listed = cp.analyse(program, RPM, with_flight=False, outputs=[MEAN_FORCE])  # a list of probes: the same set
    assert probed.outputs == listed.outputs == PROBED and plain.outputs == cp.BUILT_IN_OUTPUTS

    plain_bench = Workbench(tomllib.loads(toml), "300,450", path.parent, with_flight=False)
    probed_bench = Workbench(tomllib.loads(toml), "300,450", path.parent, with_flight=False,
                             cache=plain_bench.cache, outputs=PROBED)
    benches = [plain_bench.update(plain_bench.data), probed_bench.update(probed_bench.data),
               plain_bench.update(plain_bench.data)]
    assert len(plain_bench.cache) == 2  # one analysis each, the third from the cache

    with_probe = studio(path, rpm="300,450", outputs=PROBED)
    without = studio(path, rpm="300,450")
    try:
        served = {}
        for name, running in (("with", with_probe), ("without", without), ("with again", with_probe)):
            status, served[name] = call(running.url + "api/report")
            assert status == 200
        columns = {name: call(running.url + "api/outputs")[1] for name, running in
                   (("with", with_probe), ("without", without))}
    finally:
        with_probe.stop()
        without.stop()

    without_probe = [plain.as_dict(), again.as_dict(), benches[0], benches[2], served["without"]]
    with_it = [probed.as_dict(), listed.as_dict(), benches[1], served["with"], served["with again"]]
    for report in without_probe:
        assert all(PROBE_NAME not in s for s in report["speeds"])
    for report in with_it:
        assert [s[PROBE_NAME] for s in report["speeds"]] == pytest.approx([expected] * 2, rel=2e-5)
    # every other number is the same whichever set computed it
    reference = _speeds(plain.as_dict())
    for report in without_probe[1:] + with_it:
        for a, b in zip(reference, _speeds(report)):
            _same_numbers(a, b)
    # the page reads the labels from the set its studio was given
    assert [c["name"] for c in columns["without"]] == list(cp.BUILT_IN_OUTPUTS)
    assert [c["name"] for c in columns["with"]] == [*cp.BUILT_IN_OUTPUTS, PROBE_NAME]
    assert {"label": "mean Fc N", "unit": "N", "built_in": False}.items() <= columns["with"][-1].items()
    # the report's CSV: the probe after the built-in outputs, before the lists
    header, *rows = list(csv.reader(io.StringIO(probed.to_csv())))
    place = header.index(PROBE_NAME)
    assert header[place - 1] == "contact_half_width_mm" and header[place + 1] == "period_ratio_1"
    assert [float(r[place]) for r in rows] == pytest.approx([expected] * 2, rel=2e-5)
    assert PROBE_NAME not in plain.to_csv()


def test_another_function_under_the_same_name_is_another_set():
    """The set, not the probe's name, is the compiled cycle's static argument: the same name
    with another function is compiled anew, and neither set is changed by the other."""
    program = cp.Program.load(cp.example_path("indexer"))
    doubled = cp.Outputs([cp.probe(PROBE_NAME, lambda c, t: 2 * _mean_force(c, t))])
    assert doubled != PROBED and hash(doubled) != hash(PROBED)
    once = cp.analyse(program, [300.0], with_flight=False, outputs=PROBED)
    twice = cp.analyse(program, [300.0], with_flight=False, outputs=doubled)
    assert twice.speeds[0].mean_contact_force_n == pytest.approx(2 * once.speeds[0].mean_contact_force_n, rel=1e-12)
    assert once.speeds[0].mean_contact_force_n == pytest.approx(_expected(program), rel=2e-5)


def test_every_output_of_a_speed_is_a_probe_of_the_set_it_was_computed_with():
    """One keyed set: each built-in output is a ``Probe`` with a function (compiled or on
    the host), label and doc; a speed's row holds exactly the set's outputs, and its JSON is
    ``rpm``, those outputs and the structured fields; a set is a value (immutable, equal to
    another of the same probes)."""
    built_in = cp.BUILT_IN_OUTPUTS
    assert all(p.built_in and (p.fn or p.host) and p.label and p.doc for p in built_in.values())
    assert cp.Outputs() == built_in and list(PROBED) == [*built_in, PROBE_NAME]
    assert cp.Outputs(PROBED) == PROBED == cp.Outputs([*built_in.values(), MEAN_FORCE])
    with pytest.raises(TypeError):
        built_in[PROBE_NAME] = MEAN_FORCE  # no item assignment: a set is a value
    assert PROBE_NAME not in built_in
    report = cp.analyse(cp.Program.load(cp.example_path("indexer")), [300.0], with_flight=False)
    speed = report.speeds[0]
    assert list(speed.values) == list(report.outputs) == [p.name for p in report.columns()]
    structured = {"rpm", "residual_vibration_mm", "period_ratios", "flight", "flights", "impacts",
                  "impacts_change_deg"}
    assert set(speed.as_dict()) == structured | set(built_in)


def test_probe_names_and_sets_are_checked():
    with pytest.raises(ValueError, match="built-in output"):
        cp.probe("min_contact_force_n", _mean_force)
    with pytest.raises(ValueError, match="lower-case Python name"):
        cp.probe("Mean force", _mean_force)
    with pytest.raises(ValueError, match="built-in output"):
        cp.Outputs([cp.Probe("min_contact_force_n", _mean_force, "x")])
    with pytest.raises(ValueError, match="two probes are named 'mean_contact_force_n'"):
        cp.Outputs([MEAN_FORCE, cp.probe(PROBE_NAME, _mean_force)])
    with pytest.raises(ValueError, match="outputs must be an Outputs or a list of Probe"):
        cp.Outputs.of(MEAN_FORCE)
    with pytest.raises(ValueError, match="each must be a Probe"):
        cp.Outputs(["mean_contact_force_n"])
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        _ = cp.SpeedReport(1.0, {}).nothing


PROBES_FILE = '''
import camjax.program as cp


def mean_force(cycle, turn):
    widths = turn.grid.motion.widths
    force = cycle.contact_force_n
    return (widths * (force[:-1] + force[1:]) / 2).sum()


MEAN_FORCE = cp.probe("mean_contact_force_n", mean_force, label="mean Fc N", unit="N")
NOT_A_PROBE = 3
'''


def test_camjax_program_probes_reports_them_in_the_table_json_and_summary(capsys, tmp_path):
    """``camjax program --probes FILE.py:NAME``: the probe's value, against the mean lift's
    closed form, in the table (a block of its own), the JSON and ``summary.json``."""
    (tmp_path / "probes.py").write_text(PROBES_FILE)
    expected = _expected(cp.Program.load(cp.example_path("indexer")))
    args = ["program", "indexer", "--rpm", "300,450", "--no-flight", "--probes", f"{tmp_path / 'probes.py'}:MEAN_FORCE"]
    assert main([*args, "--format", "json", "--out", str(tmp_path / "out"), "--points", "8"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert json.loads((tmp_path / "out" / "summary.json").read_text()) == printed
    assert [s[PROBE_NAME] for s in printed["speeds"]] == pytest.approx([expected] * 2, rel=2e-5)
    assert main(args) == 0
    lines = capsys.readouterr().out.splitlines()
    title = next(i for i, line in enumerate(lines) if "mean Fc N" in line)
    assert lines[title].split() == ["rpm", "mean", "Fc", "N"]
    for line, rpm in zip(lines[title + 1:title + 3], (300, 450)):
        assert float(line.split()[0]) == rpm
        assert float(line.split()[1]) == pytest.approx(expected, rel=1e-5)  # 6 digits printed


@pytest.mark.parametrize(("given", "message"), [
    ("probes.py", "expected FILE.py:NAME"),
    ("missing.py:MEAN_FORCE", "no file"),
    ("probes.py:OTHER", "defines no 'OTHER'"),
    ("probes.py:NOT_A_PROBE", "NOT_A_PROBE in .*: outputs must be an Outputs or a list of Probe"),
    ("broken.py:MEAN_FORCE", "running .*broken.py failed: ZeroDivisionError"),
])
def test_camjax_program_refuses_bad_probes_on_one_line(capsys, tmp_path, given, message):
    import re

    (tmp_path / "probes.py").write_text(PROBES_FILE)
    (tmp_path / "broken.py").write_text("1 / 0\n")
    assert main(["program", "indexer", "--probes", str(tmp_path / given)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and re.search(f"camjax program: error: --probes: .*{message}", err), err


def test_a_machine_reports_each_cam_with_the_set_given():
    """``analyse_machine(..., outputs=...)``: each cam's report holds the probe (its value the
    mean lift's closed form, at that cam's own phase: a mean over the turn), the shaft's
    totals only the built-in outputs they sum."""
    program = cp.Program.load(cp.example_path("indexer"))
    report = cp.analyse_machine([(program, 0.0), (program, 90.0)], [300.0], with_flight=False, outputs=PROBED)
    for cam in report.cams:
        assert cam.outputs == PROBED
        assert cam.speeds[0].mean_contact_force_n == pytest.approx(_expected(program), rel=2e-5)
    assert PROBE_NAME not in [p.name for p in report.columns()]
    plain = cp.analyse_machine([(program, 0.0)], [300.0], with_flight=False)
    assert PROBE_NAME not in plain.cams[0].speeds[0].values
