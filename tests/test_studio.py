"""camjax studio: the JSON API against ``camjax program`` and the program API, and the page
in a real browser (Debian's Chromium driven by Playwright; skipped where either is missing)."""

import contextlib
import dataclasses
import io
import json
import math
import os
import signal
import subprocess
import sys
import time
import tomllib
import urllib.error
import urllib.parse
import urllib.request
import zipfile
from pathlib import Path

import numpy as np
import pytest
from helpers import call

from camjax import program as cp
from camjax.cli import dump_json, main
from camjax.studio import kinematics, parse_program, studio

RPM = "400:1000:4"  # brackets the feed cam's jump speed (about 660 rpm)
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]
FEED = cp.example_path("feed").read_text()
EDITED = FEED.replace("lift_mm = 8\n", "lift_mm = 7\n").replace("lift_mm = -23\n", "lift_mm = -22\n")


STUDIO_KEYS = ("residual_segments", "design_objectives")
"""What the studio's report holds beside ``camjax program``'s JSON (for its page)."""


def assert_same(a, b, where="report"):
    """Equal structures, numbers to 1e-9 relative (the studio's own keys of a report left out)."""
    if where == "report" and isinstance(a, dict):
        a = {k: v for k, v in a.items() if k not in STUDIO_KEYS}
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), where
        for key in a:
            assert_same(a[key], b[key], f"{where}.{key}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, float) and not isinstance(b, bool):
        assert isinstance(b, int | float) and math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12), (where, a, b)
    else:
        assert a == b, (where, a, b)


def cli_json(*args) -> dict:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["program", *args, "--format", "json"]) == 0
    return json.loads(out.getvalue())


@pytest.fixture(scope="module")
def server():
    running = studio("feed", rpm=RPM)
    yield running
    running.stop()


@pytest.fixture(scope="module")
def edited(server):
    """Session ``b``'s report after posting the edited program."""
    return call(server.url + f"api/program?session=b&rpm={RPM}", EDITED)


def test_report_is_the_cli_json(server):
    status, report = call(server.url + "api/report")
    assert status == 200
    assert_same(report, cli_json("feed", "--rpm", RPM))
    assert report["jump_speed_rpm"] is not None
    assert "motor" not in report  # no [drive] and motors: no motor panel


def test_post_program_is_its_analysis(server, edited):
    status, report = edited
    assert status == 200
    rpm = np.linspace(400, 1000, 4)
    reference = json.loads(dump_json(cp.analyse(parse_program(EDITED), rpm).as_dict()))  # as the CLI writes it
    assert_same(report, reference)
    original = call(server.url + "api/report")[1]
    assert abs(report["jump_speed_rpm"] - original["jump_speed_rpm"]) > 1.0


def test_two_workbenches_are_independent(server, edited):
    original = call(server.url + "api/report")[1]
    assert call(server.url + "api/report?session=b")[1] == edited[1]
    assert original != edited[1]
    assert call(server.url + "api/program?session=b")[1]["program"] == tomllib.loads(EDITED)
    assert call(server.url + "api/program")[1]["program"] == tomllib.loads(FEED)
    assert call(server.url + "api/program")[1]["toml"] == parse_program(FEED).to_toml()  # the one writer
    # the same program in another layout (no comments, 8.0 for 8) is not analysed again
    analysed = len(server.reports)
    plain = cp.Program.load(cp.example_path("feed")).to_toml()
    status, report = call(server.url + f"api/program?session=d&rpm={RPM}", plain)
    assert status == 200 and report == original and len(server.reports) == analysed
    assert call(server.url + "api/close?session=b", "")[0] == 200
    assert "b" not in server.workbenches


def test_bad_program_is_a_400_with_the_library_message(server):
    bad = FEED.replace("lift_mm = 8\n", 'lift_mm = "eight"\n')
    with pytest.raises(ValueError) as expected:
        parse_program(bad)
    status, answer = call(server.url + "api/program?session=c", bad)
    assert status == 400 and answer == {"error": str(expected.value)}
    assert "\n" not in answer["error"] and "segment 2: lift_mm" in answer["error"]
    status, answer = call(server.url + "api/open?session=c", "toml = '[[segment]\\n'")  # a file opened
    assert status == 400 and answer["error"].startswith("not valid TOML")
    status, answer = call(server.url + "api/program?session=c&rpm=0:10:3", FEED)
    assert status == 400 and answer["error"].startswith("rpm:")
    status, answer = call(server.url + "api/curves?rpm=100")  # the default session's range
    assert status == 400 and "lowest speed of the range (400 rpm)" in answer["error"]
    status, answer = call(server.url + "api/curves?rpm=1e300")
    assert status == 400 and answer == {"error": "rpm: 1e+300 rpm is too fast to compute a turn at (a number overflows)"}


def test_a_number_too_large_for_an_integer_is_analysed_with_a_warning(server):
    """A radius written as a whole number beyond 64 bits is read as a float (no overflow, no
    500) and the report says that no cam machine has it."""
    huge = FEED.replace("base_radius_mm = 40", "base_radius_mm = 100000000000000000000")
    status, answer = call(server.url + "api/program?session=e", huge)
    assert status == 200
    assert any(w.startswith("follower.base_radius_mm = 1e+20 is more than") for w in answer["warnings"]), answer


DESIGN_STEPS = 12  # few steps: enough to lower the feed cam's preload, a few seconds each


def design_done(url: str, session: str) -> dict:
    """Poll ``GET /api/design`` until the design is no longer running; its last answer."""
    steps = []
    deadline = time.monotonic() + 600
    while time.monotonic() < deadline:
        status, job = call(url + f"api/design?session={session}")
        assert status == 200
        steps.append(job["step"])
        if job["state"] != "running":
            assert steps == sorted(steps)  # the progress only goes forward
            return job
        time.sleep(0.2)
    raise AssertionError("the design did not finish")


def test_design_from_the_api(server, tmp_path):
    """Design the feed cam's first rise for the least preload over 400-1000 rpm: discard
    leaves the program as it was; keep gives the report of the designed program as
    ``camjax.program.analyse`` gives it for the saved program and its law file."""
    url, session = server.url, "design"
    original = call(url + f"api/report?session={session}")[1]
    before = [s["min_preload_n"] for s in original["speeds"]]  # at 400, 600, 800, 1000 rpm
    # bad requests: the library's one-line message, before any work
    program = parse_program(FEED)
    for segment, rpm in ((1, "400:1000"), (2, "1000:400"), (9, "400:1000")):
        with pytest.raises(ValueError) as expected:
            cp.segment_band(program, segment, *map(float, rpm.split(":")))
        status, answer = call(url + f"api/design?session={session}&segment={segment}&rpm={rpm}", "")
        assert status == 400 and answer == {"error": str(expected.value)}
    for query, start in (("segment=two&rpm=400:1000", "segment: "), ("segment=2&rpm=400", "rpm: "),
                         ("segment=2&rpm=400:1000&objective=speed", "objective: "),
                         ("segment=2&rpm=400:1000&steps=0", "steps: ")):
        status, answer = call(url + f"api/design?session={session}&{query}", "")
        assert status == 400 and answer["error"].startswith(start) and "\n" not in answer["error"], answer
    assert call(url + f"api/design/keep?session={session}", "")[0] == 400  # nothing designed yet
    start = f"api/design?session={session}&segment=2&objective=preload&rpm=400:1000&steps={DESIGN_STEPS}"

    status, job = call(url + start, "")
    assert status == 202 and job["state"] == "running" and job["steps"] == DESIGN_STEPS
    status, answer = call(url + start, "")  # a second while one runs
    assert status == 409 and "\n" not in answer["error"], (answer, call(url + f"api/design?session={session}")[1])
    assert call(url + f"api/design/keep?session={session}", "")[0] == 409
    job = design_done(url, session)
    assert job["state"] == "done", job
    assert job["step"] == job["steps"] and not job["kept_initial"]
    # the objective is the largest preload over the band, its ends among its speeds
    assert math.isclose(job["before"], max(before), rel_tol=1e-6) and job["after"] < 0.9 * job["before"]
    assert job["curves"]["before"]["min_preload_n"] == before
    after = job["curves"]["after"]["min_preload_n"]
    assert job["after"] >= max(after[0], after[-1]) * (1 - 1e-9)
    assert call(url + f"api/design/discard?session={session}", "")[1]["state"] == "discarded"
    assert call(url + f"api/report?session={session}")[1] == original
    assert call(url + f"api/design/keep?session={session}", "")[0] == 400  # discarded

    assert call(url + start, "")[0] == 202
    job = design_done(url, session)
    assert job["state"] == "done" and job["curves"]["after"]["min_preload_n"] == after  # deterministic
    status, kept = call(url + f"api/design/keep?session={session}", "")
    assert status == 200 and call(url + f"api/report?session={session}")[1] == kept
    assert max(s["min_preload_n"] for s in kept["speeds"]) < 0.9 * max(before)
    state = call(url + f"api/program?session={session}")[1]
    assert state["bundle"] and state["program"]["segment"][1]["law"].endswith(".json")
    # the saved program with its law file: the same report
    with urllib.request.urlopen(url + f"api/program.zip?session={session}", timeout=60) as response:
        archive = zipfile.ZipFile(io.BytesIO(response.read()))
    assert "program.toml" in archive.namelist() and "segment2.json" in archive.namelist()
    archive.extractall(tmp_path)
    saved = cp.Program.load(tmp_path / "program.toml")
    reference = json.loads(cp.analyse(saved, np.linspace(400, 1000, 4)).to_json())
    assert_same(kept, reference)


SEATING_RPM = "2500:3000:2"  # the valve with lash and a seat: two simulated speeds
CLOSING = 4  # valve_lash's closing onto its closing ramp
SEATING = {"steps": 12, "knots": 8, "rounds": 1, "seating_speeds": 2}  # a short design, as the page posts it


@pytest.fixture(scope="module")
def valve_lash():
    """A studio on the valve with lash and a seat (``valve_lash``)."""
    running = studio("valve_lash", rpm=SEATING_RPM)
    yield running
    running.stop()


def _offered(report: dict) -> list[str]:
    return [o["name"] for o in report["design_objectives"]]


def test_design_offers_what_the_program_takes_and_refuses_the_rest_in_one_line(server, valve_lash):
    """The report names the objectives a design of its program takes, as
    ``camjax.program.design_objectives`` rules (the page draws its choice from it): seating
    exactly where the chain has a seat, and only it where the chain has contacts; an
    objective the program does not take is refused before any work with the library's
    one line (``design_refusal``); the seating design's own options only with it."""
    feed = cp.Program.load(cp.example_path("feed"))
    valve = cp.Program.load(cp.example_path("valve"))  # a chain without a seat
    lash = cp.Program.load(cp.example_path("valve_lash"))
    report = call(server.url + "api/report")[1]
    assert _offered(report) == ["preload", "residual"] and "seating" not in cp.design_objectives(feed)
    assert call(server.url + "api/program")[1]["design"]["objectives"] == report["design_objectives"]
    status, report = call(server.url + "api/program?session=no-seat&rpm=2000", cp.example_path("valve").read_text())
    assert status == 200 and _offered(report) == ["preload", "residual"]
    assert cp.design_objectives(valve) == ("residual", "preload")
    report = call(valve_lash.url + "api/report")[1]
    assert _offered(report) == ["seating"] and cp.design_objectives(lash) == ("seating",)
    for url, program in ((server.url + "api/design?session=no-seat&segment=1", valve),
                         (server.url + "api/design?segment=2", feed)):
        status, answer = call(url + "&objective=seating&rpm=400:1000", "")
        assert status == 400 and answer == {"error": cp.design_refusal(program, "seating")}
        assert "needs a valve seat" in answer["error"] and "\n" not in answer["error"]
    for objective in ("preload", "residual"):  # a chain with lash and a seat: the exact path does not apply
        status, answer = call(valve_lash.url + f"api/design?segment={CLOSING}&objective={objective}&rpm=2500:3000", "")
        assert status == 400 and answer == {"error": cp.design_refusal(lash, objective)}
        assert "objective 'seating' designs a chain with a seat" in answer["error"]
    status, answer = call(server.url + "api/design?segment=2&objective=preload&rpm=400:1000&rounds=2", "")
    assert status == 400 and answer == {"error": "rounds: only with objective 'seating', got 'preload'"}
    status, answer = call(valve_lash.url + f"api/design?segment={CLOSING}&objective=seating&rpm=2500:3000"
                          "&seating_speeds=0", "")
    assert status == 400 and answer["error"].startswith("seating_speeds: must be from 1 to ")
    assert call(server.url + "api/design?session=no-seat")[1] == {"state": "none"}  # nothing started


def _seating_m_s(program, rpm) -> float:
    """The largest seating velocity (m/s) of ``program`` at ``rpm``, simulated apart."""
    turns = cp.ChainContacts(program, program.chain, min(rpm)).turns(rpm, refine=False)
    return max(t.seating_velocity_m_s for t in turns)


@pytest.mark.slow
def test_a_seating_design_from_the_api_is_the_librarys(valve_lash):
    """Slow: two seating designs (the studio's and the library's) and three simulations
    apart, about two minutes on two shared cores (2026-11-29).  The valve's closing designed from the page for the least seating velocity over
    2500-3000 rpm (one round of 12 steps on 2 speeds): the studio runs ``design_segment``,
    whose seating design (``seating_design``) is the command line's, so its before and
    after are the library's own for the same inputs; the after, the designed program's
    seating velocity simulated apart, is below the before, the valve's own simulated apart;
    kept, the workbench holds that program."""
    url = valve_lash.url
    query = "&".join(f"{k}={v}" for k, v in SEATING.items())
    status, job = call(url + f"api/design?segment={CLOSING}&objective=seating&rpm=2500:3000&{query}", "")
    assert status == 202 and job["objective"] == "seating"
    job = design_done(url, "default")
    assert job["state"] == "done", job
    assert job["step"] == job["steps"] == SEATING["steps"] * SEATING["rounds"]  # the rounds' steps as one count
    lash = cp.Program.load(cp.example_path("valve_lash"))
    designed, result = cp.design_segment(lash, CLOSING, 2500.0, 3000.0, objective="seating", progress=False,
                                         **SEATING)
    (label,) = result.values
    assert job["label"] == label and not job["kept_initial"] and not result.kept_initial
    assert job["before"] == pytest.approx(result.initial_values[label], rel=1e-9)
    assert job["after"] == pytest.approx(result.values[label], rel=1e-9)
    speeds = [2500.0, 3000.0]
    assert job["before"] == pytest.approx(_seating_m_s(lash, speeds), rel=1e-6)  # the law as the design holds it
    assert job["after"] < job["before"]
    status, kept = call(url + "api/design/keep", "")
    assert status == 200
    kept_program = cp.Program.from_dict(call(url + "api/program")[1]["program"])
    assert job["after"] == pytest.approx(_seating_m_s(kept_program, speeds), rel=1e-9)
    assert job["after"] == pytest.approx(_seating_m_s(designed, speeds), rel=1e-9)
    seating = [c["seating_velocity_m_s"] for c in kept["train"]["contacts"]["speeds"]]
    assert max(seating) == pytest.approx(job["after"], rel=1e-6)  # the report's reading, refined
    assert job["curves"]["after"]["seating_velocity_m_s"] == seating  # the page's before and after
    assert max(job["curves"]["before"]["seating_velocity_m_s"]) == pytest.approx(job["before"], rel=1e-6)


SERVO_RPM = "60:120:2"


def test_servo_report_carries_the_motor_sizing():
    """The studio's report for the servo example carries the sizing of the picked motor at
    every speed analysed, equal (1e-9) to ``choose_motor`` on duty cycles computed here from
    the steady state."""
    running = studio("servo", rpm=SERVO_RPM)
    try:
        status, report = call(running.url + "api/report")
    finally:
        running.stop()
    assert status == 200
    program = cp.Program.load(cp.example_path("servo"))
    speeds = [60.0, 120.0]
    steady = cp.SteadyState(program, speeds)  # the nodes the studio's analysis solves on
    duties = [cp.duty_cycle(program, program.drive, r, cp.response(program, r, steady=steady)) for r in speeds]
    choice = cp.choose_motor(program.motors, duties)
    assert choice.picked is not None and len(program.motors) > 1
    index = list(program.motors).index(choice.picked)
    sizings = [json.loads(dump_json(s.as_dict())) for s in choice.sizings[index]]
    motor = report["motor"]
    assert motor["picked"] == motor["shown"] == choice.picked.name
    assert motor["closest"] is None and motor["closest_failed_check"] is None
    assert [s["rpm"] for s in motor["sizings"]] == speeds
    assert_same(motor["sizings"], sizings, "motor.sizings")
    assert motor["envelope"] == [list(p) for p in choice.picked.envelope]
    dynamic = motor["sizings"][1]["dynamic"]
    assert dynamic["rms_torque_n_m"] != motor["sizings"][1]["rigid"]["rms_torque_n_m"]
    assert {c["name"] for c in dynamic["checks"]} >= {"inertia ratio (load reflected / rotor)"}


def test_jerk_is_the_derivative_of_the_acceleration():
    """The page's jerk against central differences of ``Program.lift``'s acceleration."""
    program = parse_program(FEED)
    theta = np.array([40.0, 62.5, 150.0, 170.0, 240.0, 290.0])  # inside the moving segments
    step = 1e-4
    plus, minus = (program.lift(theta + s)[2] for s in (step, -step))
    jerk = kinematics(program, theta)["jerk_mm_per_deg3"]
    np.testing.assert_allclose(jerk, (plus - minus) / (2 * step), rtol=1e-6, atol=1e-12)
    assert np.abs(jerk).max() > 1e-4


def test_cli_refuses_bad_arguments(capsys):
    assert main(["studio", "--port", "70000", "--no-browser"]) == 2
    assert main(["studio", "no-such-file.toml", "--no-browser", "--port", "0"]) == 2
    assert main(["studio", "--probes", "no-such-probes.py:MEAN", "--no-browser", "--port", "0"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines[0].startswith("camjax studio: error: --port")
    assert lines[1].startswith("camjax studio: error: ") and "no-such-file.toml" in lines[1]
    assert lines[2] == "camjax studio: error: --probes: no file no-such-probes.py"


def test_cli_serves_the_page_and_stops_on_ctrl_c():
    """``camjax studio`` prints its address, serves the page and its script, and Ctrl-C
    stops it with status 0 and no traceback."""
    # Ctrl-C as a terminal gives it, whatever this runner's own disposition (a shell's
    # background job starts with SIGINT ignored, and a child inherits that): the child
    # takes SIGINT's default handler itself (a preexec_fn would run Python in a fork of
    # this multithreaded process)
    start = ("import runpy, signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
             "sys.argv = ['camjax'] + sys.argv[1:]; runpy.run_module('camjax', run_name='__main__')")
    server = subprocess.Popen([sys.executable, "-c", start, "studio", "indexer", "--no-browser", "--port", "0"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = server.stdout.readline()
        assert line.startswith("camjax studio: indexer.toml at http://127.0.0.1:"), line
        url = line[line.index("http://"):].split()[0]
        with urllib.request.urlopen(url, timeout=60) as page:
            assert "<title>camjax studio</title>" in page.read().decode()
        with urllib.request.urlopen(url + "static/uPlot.iife.min.js", timeout=60) as script:
            assert script.status == 200 and b"uPlot" in script.read()
        assert call(url + "static/../_server.py")[0] == 404
    finally:
        server.send_signal(signal.SIGINT)
        _, err = server.communicate(timeout=60)
    assert server.returncode == 0 and "Traceback" not in err and err.strip() == "camjax studio: stopped"


# -- the page in a browser --------------------------------------------------------------------

def _browser():
    if not Path(CHROMIUM).exists():
        pytest.skip(f"no Chromium at {CHROMIUM} (apt-get install chromium)")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.skip("playwright is not installed (pip install 'camjax[test]')")
    return sync_playwright


@contextlib.contextmanager
def opened_page(url: str, *, height: int = 1250, **options):
    """``(page, errors)``: Debian's Chromium on ``url`` in a 1600 x ``height`` viewport
    (``options`` for ``new_page``), the page's JavaScript errors collected; closed after."""
    sync_playwright = _browser()
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1600, "height": height}, **options)
            errors = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(url)
            yield page, errors
        finally:
            browser.close()


REDRAW_MS = 180_000  # an analysis compiles today: tens of seconds on a busy machine


def test_page_edits_saves_and_reloads(server, tmp_path):
    shots = os.environ.get("CAMJAX_STUDIO_SCREENSHOTS")
    idle = "document.body.dataset.busy === '0'"
    with opened_page(server.url, accept_downloads=True) as (page, errors):
        page.wait_for_selector("#jump", timeout=2 * REDRAW_MS)
        page.wait_for_function(idle, timeout=REDRAW_MS)
        first = float(page.get_attribute("#jump", "data-rpm"))
        if shots:
            page.screenshot(path=str(Path(shots) / "studio.png"))
            page.screenshot(path=str(Path(shots) / "studio-full.png"), full_page=True)
        # change the lift of the first rise and of the last return (the turn closes)
        page.fill('input[data-seg="2"][data-key="lift_mm"]', "7")
        page.fill('input[data-seg="5"][data-key="lift_mm"]', "-22")
        page.wait_for_function(f"document.querySelector('#jump') && "
                               f"document.querySelector('#jump').dataset.rpm !== '{first!r}' && {idle}",
                               timeout=REDRAW_MS)
        shown = float(page.get_attribute("#jump", "data-rpm"))
        with page.expect_download() as download:
            page.click("#save")
        saved = tmp_path / "saved.toml"
        download.value.save_as(saved)
        assert saved.read_text() == parse_program(EDITED).to_toml()  # the one writer of a program file
        expected = cli_json(str(saved), "--rpm", RPM)["jump_speed_rpm"]
        assert math.isclose(shown, expected, rel_tol=1e-9)
        assert page.inner_text("#jump") == f"{expected:.1f} rpm"
        # a bad value: the library's message beside the field, the last good state kept
        page.fill('input[data-seg="2"][data-key="lift_mm"]', "seven")
        page.wait_for_selector(".err", timeout=REDRAW_MS)
        bad = saved.read_text().replace("lift_mm = 7.0\n", 'lift_mm = "seven"\n')
        assert bad != saved.read_text()
        with pytest.raises(ValueError) as message:
            parse_program(bad)
        assert page.inner_text(".err") == str(message.value)
        assert float(page.get_attribute("#jump", "data-rpm")) == shown
        if shots:
            page.screenshot(path=str(Path(shots) / "studio-error.png"))
        # open the saved file: the same report
        page.set_input_files("#open", str(saved))
        page.wait_for_function(f"!document.querySelector('.err') && {idle}", timeout=REDRAW_MS)
        assert float(page.get_attribute("#jump", "data-rpm")) == shown
        assert page.input_value('input[data-seg="2"][data-key="lift_mm"]') == "7"
        # design the first rise with few steps: the bar reaches its end, before and after shown
        page.select_option("#d-seg", "2")
        page.fill("#d-lo", "400")
        page.fill("#d-hi", "1000")
        page.fill("#d-steps", str(DESIGN_STEPS))
        page.click("#d-start")
        page.wait_for_function("document.querySelector('#design').dataset.state === 'done'", timeout=2 * REDRAW_MS)
        assert page.eval_on_selector("#d-bar", "bar => bar.value === bar.max && bar.max > 0")
        before, after = (float(page.get_attribute(f"#d-{key}", "data-value")) for key in ("before", "after"))
        preload = {s["rpm"]: s["min_preload_n"] for s in cli_json(str(saved), "--rpm", RPM)["speeds"]}
        assert math.isclose(before, preload[1000.0], rel_tol=1e-6) and after < 0.9 * before
        if shots:
            page.screenshot(path=str(Path(shots) / "studio-design.png"), full_page=True)
        page.click("#d-keep")
        page.wait_for_function(f"document.querySelector('#design').dataset.state === 'kept' && {idle}",
                               timeout=REDRAW_MS)
        assert page.input_value('input[data-seg="2"][data-key="law"]').endswith(".json")
        assert page.inner_text("#save") == "Save TOML + laws (zip)"
        assert not errors, errors


def test_page_says_what_an_edit_does(server):
    """A bad chosen speed's message goes when a good one is chosen; while an error of the
    program stands the views are marked stale and Save says it saves the last good program; a parameterised law typed into the law cell reaches the library (its message
    shown) and keeps the lift; a flat face clears the roller's radius; an empty spring rate
    says the cam is grooved, whose rigid force has no preload (the preload warned of)."""
    idle = "document.body.dataset.busy === '0'"
    no_error = f"!document.querySelector('.err') && {idle}"
    with opened_page(server.url) as (page, errors):
        page.wait_for_selector("#jump", timeout=2 * REDRAW_MS)
        page.wait_for_function(idle, timeout=REDRAW_MS)
        for speed in ("fast", "700"):  # a bad chosen speed's message goes with a good one
            page.fill("#chosen", speed)
            page.dispatch_event("#chosen", "change")
            page.wait_for_function(f"{'!' if speed == '700' else ''}document.querySelector('.err') && {idle}",
                                   timeout=REDRAW_MS)
            assert page.evaluate("document.body.dataset.stale") == "0"  # the program is good
        mass = '#follower input[data-key="mass_kg"]'
        page.fill(mass, "heavy")
        page.wait_for_selector(".err", timeout=REDRAW_MS)
        assert page.evaluate("document.body.dataset.stale") == "1"
        assert page.inner_text("#save") == "Save TOML (last good program)"
        page.fill(mass, "1.5")  # the starting program again
        page.wait_for_function(no_error, timeout=REDRAW_MS)
        assert page.evaluate("document.body.dataset.stale") == "0" and page.inner_text("#save") == "Save TOML"
        # a law with a parameter, typed: the library's own message for it, the lift kept
        law = 'input[data-seg="2"][data-key="law"]'
        page.fill(law, "poly:7")
        page.press(law, "Enter")
        page.wait_for_selector(".err", timeout=REDRAW_MS)
        segment = ('law = "polynomial"\ndegree = 5\nlift_mm = 8\nangle_deg = 50\nstart = "match"        '
                   "# the dwell's rest\nend = \"match\"          # the working stroke's 0.3 mm/deg")
        typed = FEED.replace(segment, 'law = "poly:7"\nlift_mm = 8\nangle_deg = 50')
        assert typed != FEED
        with pytest.raises(ValueError) as message:
            parse_program(typed)
        assert page.inner_text(".err") == str(message.value)
        assert page.evaluate("model.segment[1]") == {"law": "poly:7", "lift_mm": 8, "angle_deg": 50}
        page.fill(law, "polynomial")
        page.press(law, "Enter")
        page.wait_for_function(no_error, timeout=REDRAW_MS)
        assert page.evaluate("model.segment[1]") == {"law": "polynomial", "lift_mm": 8, "angle_deg": 50, "degree": 5,
                                                     "start": "match", "end": "match"}
        # a flat face: the roller's radius cleared, so the library judges the face (a cusp here)
        note = lambda key: page.inner_text(f'#follower .fnote[data-note="{key}"]')  # noqa: E731
        kind = '#follower select[data-key="kind"]'
        page.select_option(kind, "translating-flat")
        assert page.evaluate("model.follower.roller_radius_mm") is None
        assert note("roller_radius_mm") == "a flat face has no roller: cleared"
        page.wait_for_selector(".err", timeout=REDRAW_MS)
        assert page.inner_text(".err").startswith("follower.kind = 'translating-flat': the cam's radius of curvature")
        # back to a roller (its radius left empty) without a spring: notes, and that machine's analysis
        page.select_option(kind, "translating-roller")
        page.fill('#follower input[data-key="spring_rate_n_per_mm"]', "")
        page.wait_for_function(f"document.querySelector('#status').textContent === 'ready' && {no_error}",
                               timeout=2 * REDRAW_MS)
        assert note("spring_rate_n_per_mm") == "empty: no return spring, a grooved (form-closed) cam"
        assert note("preload_n") == "does nothing on a grooved cam (no spring)"
        assert note("roller_radius_mm") == "empty: 10 (the default)"
        assert note("contact_width_mm") == "empty: none" and note("mass_kg") == ""
        response = page.evaluate("curves.response")
        np.testing.assert_allclose(response["rigid_contact_force_n"],
                                   1.5 * np.asarray(response["kinematic_acceleration_m_s2"]), rtol=1e-12, atol=1e-9)
        assert "follower.preload_n = 300 N does nothing on a grooved cam" in page.inner_text("#warnings")
        assert not errors, errors


def test_page_shows_a_table_cam_read_only():
    """A whole cam from one lift table: its segments shown, not edited, with the note; the
    follower stays editable and the report follows it."""
    feed = parse_program(FEED)
    angle = np.arange(0.0, 360.0, 5.0)
    table = cp.Program.from_table("feed table", angle, feed.lift(angle)[0], feed.follower)
    rpm = "400:1000:3"
    running = studio(table, rpm=rpm)
    idle = "document.body.dataset.busy === '0'"
    try:
        with opened_page(running.url) as (page, errors):
            page.wait_for_selector("#jump", timeout=2 * REDRAW_MS)
            page.wait_for_function(idle, timeout=REDRAW_MS)
            assert page.is_visible("#table-note") and page.inner_text("#table-note") == "a table cam: edit its file"
            assert page.locator("#segments input, #segments select").count() == 0
            assert page.locator("#segments tbody tr").count() == len(table.segments)
            assert not page.is_visible("#design") and not page.is_visible("#add")
            posted = lambda r: "/api/program" in r.url and r.request.method == "POST"  # noqa: E731
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.fill('#follower input[data-key="preload_n"]', "400")
            page.wait_for_function(f"document.querySelector('#status').textContent === 'ready' && {idle}",
                                   timeout=REDRAW_MS)
            session = page.evaluate("SESSION")
            state = call(running.url + f"api/program?session={session}")[1]
            edited = cp.Program.from_dict(state["program"])
            assert edited.follower.preload_n == 400 and "points" in state["program"]["program"]
            expected = dataclasses.replace(table, follower=dataclasses.replace(table.follower, preload_n=400))
            assert edited.to_toml() == expected.to_toml()
            report = call(running.url + f"api/report?session={session}")[1]
            assert_same(report, json.loads(cp.analyse(expected, np.linspace(400, 1000, 3)).to_json()))
            assert not errors, errors
    finally:
        running.stop()



def test_design_progress_is_the_loss_history():
    """``camjax.design(progress=f)`` calls ``f(step, total, loss)`` after each compiled chunk:
    the steps grow to the total, and each loss is the training history's at that step."""
    from camjax import law_design as D

    calls = []
    result = D.design(D.Residual(7.3), knots=8, steps=400, optimizer="adam",  # two chunks of 200
                      progress=lambda *a: calls.append(a))
    steps = [c[0] for c in calls]
    assert steps == [200, 400] and calls[-1][1] == result.loss_history.size == 400
    np.testing.assert_array_equal([c[2] for c in calls], result.loss_history[np.array(steps) - 1])


def test_page_shows_the_servo_motor_panel():
    """The servo example's page shows the motor panel: the picked motor, a row per speed, a
    row per check and the torque-speed plot drawn; an edit keeps the [drive] and [motor] (the
    panel is there after it, from the edited program's report)."""
    idle = "document.body.dataset.busy === '0'"
    running = studio("servo", rpm=SERVO_RPM)
    try:
        with opened_page(running.url) as (page, errors):
            page.wait_for_selector("#motor-box:not([hidden])", timeout=2 * REDRAW_MS)
            page.wait_for_function(idle, timeout=REDRAW_MS)
            report = call(running.url + "api/report")[1]["motor"]
            assert page.get_attribute("#motor-verdict", "data-motor") == report["picked"]
            assert page.locator("#motor-speeds tbody tr").count() == 2
            checks = report["sizings"][0]["dynamic"]["checks"]
            assert page.locator("#motor-checks tbody tr").count() == len(checks)
            drawn = "(() => { const c = document.getElementById('motor-plot'); const d = c.getContext('2d')" \
                    ".getImageData(0, 0, c.width, c.height).data; return d.some((v, i) => i % 4 === 3 && v > 0); })()"
            assert page.evaluate(drawn)
            # the RMS limit drawn as motor.png draws it: 80% of the shown motor's continuous stall torque
            shown = next(m for m in cp.Program.load(cp.example_path("servo")).motors if m.name == report["shown"])
            limit = float(page.get_attribute("#motor-plot", "data-rms-limit"))
            assert limit == pytest.approx(0.8 * shown.continuous_stall_torque_n_m, rel=1e-12)
            if shots := os.environ.get("CAMJAX_STUDIO_SCREENSHOTS"):
                page.locator("#motor-box").screenshot(path=str(Path(shots) / "studio-motor.png"))
            page.fill('input[data-seg="2"][data-key="lift_mm"]', "30")
            page.fill('input[data-seg="4"][data-key="lift_mm"]', "-30")
            page.wait_for_function(f"!document.querySelector('.err') && {idle} && "
                                   "document.querySelector('#motor-speeds td:nth-child(2)').textContent !== "
                                   f"{json.dumps(page.inner_text('#motor-speeds td:nth-child(2)'))}",
                                   timeout=REDRAW_MS)
            assert page.is_visible("#motor-box")
            assert errors == []
    finally:
        running.stop()


def test_page_edits_materials_undoes_and_draws_the_swinging_arm():
    """A swinging roller: its arm and pivot drawn beyond the cam; a ``[materials]`` field
    edited scales the Hertz peak by the square root of the contact modulus (the force does
    not depend on it); Ctrl+Z and the Undo button give back the program before each edit."""
    indexer = cp.Program.load(cp.example_path("indexer"))
    swinging = dataclasses.replace(indexer, follower=dataclasses.replace(
        indexer.follower, kind="swinging-roller", arm_mm=98.0, pivot_mm=110.0, contact_width_mm=10.0))
    rpm = "300:600:2"
    running = studio(swinging, rpm=rpm)
    idle = "document.body.dataset.busy === '0'"
    ready = f"document.querySelector('#status').textContent === 'ready' && {idle}"
    posted = lambda r: "/api/program" in r.url and r.request.method == "POST"  # noqa: E731
    try:
        with opened_page(running.url) as (page, errors):
            page.wait_for_selector("#jump", timeout=2 * REDRAW_MS)
            page.wait_for_function(ready, timeout=REDRAW_MS)
            session = page.evaluate("SESSION")
            assert "counter-clockwise" in page.inner_text("#rotation")
            assert page.is_disabled("#undo")
            # red (the follower's colour) beyond the cam's reach: only the arm and its pivot are there
            beyond = page.evaluate("""() => {
                const canvas = document.getElementById('profile'), p = curves.profile, f = curves.follower;
                const pts = [...p.pitch, ...p.profile];
                const cam = Math.max(...pts.map(([x, y]) => Math.hypot(x, y))) + f.roller_radius_mm;
                const reach = Math.max(cam + f.roller_radius_mm + 5, f.pivot_mm + 8);
                const scale = canvas.width / 2 / reach, from = Math.ceil(canvas.width / 2 + scale * (cam + 2));
                const data = canvas.getContext('2d').getImageData(from, 0, canvas.width - from, canvas.height).data;
                let red = 0;
                for (let i = 0; i < data.length; i += 4) if (data[i] > 180 && data[i + 1] < 90 && data[i + 2] < 90) red++;
                return red;
            }""")
            assert beyond > 20, beyond
            stress = lambda: [s["max_contact_stress_mpa"]  # noqa: E731
                              for s in call(running.url + f"api/report?session={session}")[1]["speeds"]]
            before = stress()
            assert all(s > 0 for s in before)
            field = '#materials input[data-key="cam_youngs_modulus_gpa"]'
            assert page.locator("#materials input").count() == 4
            assert page.inner_text('#materials .fnote[data-note="cam_youngs_modulus_gpa"]') == "empty: 210 (the default)"
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.fill(field, "70")
            page.wait_for_function(ready, timeout=REDRAW_MS)
            state = call(running.url + f"api/program?session={session}")[1]
            assert state["program"]["materials"] == {"cam_youngs_modulus_gpa": 70}
            # 1/E* = 0.91/70 + 0.91/210 against 2 * 0.91/210: E* halves, the stress goes as its root
            np.testing.assert_allclose(stress(), np.sqrt(0.5) * np.asarray(before), rtol=1e-6)
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.fill('#follower input[data-key="preload_n"]', "350")
            page.wait_for_function(ready, timeout=REDRAW_MS)
            assert page.evaluate("undoStack.length") == 2
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.keyboard.press("Control+z")  # the preload back
            page.wait_for_function(ready, timeout=REDRAW_MS)
            state = call(running.url + f"api/program?session={session}")[1]
            assert state["program"]["follower"]["preload_n"] == 300
            assert state["program"]["materials"] == {"cam_youngs_modulus_gpa": 70}
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.click("#undo")  # the materials back: the program as it was
            page.wait_for_function(ready, timeout=REDRAW_MS)
            state = call(running.url + f"api/program?session={session}")[1]
            assert cp.Program.from_dict(state["program"]) == swinging
            assert page.input_value(field) == "" and page.is_disabled("#undo")
            np.testing.assert_allclose(stress(), before, rtol=1e-12)
            assert not errors, errors
    finally:
        running.stop()


def test_page_edits_a_chain_and_draws_its_modes(tmp_path):
    """The valve train: its bodies, spring and seat as tables; a body added (the library's
    one-line message for what it lacks, at its row and then at the field), named and given
    its mass and element, then moved toward the cam: each time the report's chain (bodies,
    natural frequencies) is the edited program's, and a plot per mode shape over the bodies
    with its frequency in the legend, and the harmonic check, are drawn."""
    shots = Path(os.environ.get("CAMJAX_STUDIO_SCREENSHOTS") or tmp_path)
    rpm = "400:1200:3"
    running = studio("valve", rpm=rpm)
    idle = "document.body.dataset.busy === '0'"
    ready = f"document.querySelector('#status').textContent === 'ready' && {idle}"
    posted = lambda r: "/api/program" in r.url and r.request.method == "POST"  # noqa: E731

    def chain_drawn(session):
        """The page's chain against the studio's program: rows, mode plots, legends."""
        state = call(running.url + f"api/program?session={session}")[1]
        report = call(running.url + f"api/report?session={session}")[1]
        chain = cp.Program.from_dict(state["program"], base=cp.example_path("valve").parent).chain
        held, _ = chain.natural_frequencies(contact=True)
        free, _ = chain.natural_frequencies(contact=False)
        np.testing.assert_allclose(report["train"]["natural_frequencies_held_hz"], held, rtol=1e-12)
        assert report["train"]["bodies"] == list(chain.names)
        assert page.locator("#train tbody tr").count() == len(chain.bodies)
        modes = page.locator("#train-modes .chart")
        assert modes.count() == max(len(held), len(free))  # each order held and free
        legend = page.inner_text("#c-mode-1 .u-legend")
        assert f"held {float(held[0]):.5g} Hz" in legend, legend
        assert page.locator("#c-harmonics canvas").count() == 1
        return state, report

    try:
        with opened_page(running.url) as (page, errors):
            page.wait_for_selector("#train-held", timeout=2 * REDRAW_MS)
            page.wait_for_function(ready, timeout=REDRAW_MS)
            session = page.evaluate("SESSION")
            assert page.is_visible("#chain-box") and page.is_visible("#train-box")
            # a chain gives the one-body fields in its own tables
            assert page.locator('#follower input[data-key="mass_kg"]').count() == 0
            assert page.input_value('#spring input[data-key="rate_n_per_mm"]') == "52"
            chain_drawn(session)
            page.screenshot(path=str(shots / "studio-chain-start.png"), full_page=True)
            # a body added at the end: the library names what it lacks
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.click("#add-body")
            page.wait_for_function(idle, timeout=REDRAW_MS)
            assert page.get_attribute('#train tr[data-body="3"]', "class") == "bad"
            assert page.inner_text('#train tr[data-body="3"] .err') == "[[train]] body 3 (3): needs mass_kg"
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.fill('#train input[data-body="3"][data-key="mass_kg"]', "0.02")
            page.wait_for_function(idle, timeout=REDRAW_MS)
            message = page.inner_text("#train .err")
            assert message.startswith("[[train]] body 3 (body 3): stiffness_n_per_mm is needed after the first body")
            assert page.evaluate("document.querySelector('#train .err').previousElementSibling.dataset.key") == "mass_kg"
            page.fill('#train input[data-body="3"][data-key="name"]', "retainer")
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.fill('#train input[data-body="3"][data-key="stiffness_n_per_mm"]', "400")
            page.wait_for_function(f"{ready} && !document.querySelector('.err')", timeout=REDRAW_MS)
            state, _ = chain_drawn(session)
            assert [b["name"] for b in state["program"]["train"]] == ["tappet", "valve", "retainer"]
            # moved toward the cam: between the tappet and the valve
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.click('#train tr[data-body="3"] button[title^="move up"]')
            page.wait_for_function(f"{ready} && !document.querySelector('.err')", timeout=REDRAW_MS)
            state, report = chain_drawn(session)
            assert report["train"]["bodies"] == ["tappet", "retainer", "valve"]
            assert page.inner_text("#c-mode-1 .u-legend").count("Hz") == 2  # held and free
            page.screenshot(path=str(shots / "studio-chain-edited.png"), full_page=True)
            page.locator("#chain-box").screenshot(path=str(shots / "studio-chain-editor.png"))
            page.locator("#train-box").screenshot(path=str(shots / "studio-chain.png"))
            assert not errors, errors
    finally:
        running.stop()


def test_page_edits_a_flexible_arm_and_draws_its_report(tmp_path):
    """The swinging arm example: its ``[arm]`` fields (the library's ``ARM_FIELDS``) with the
    file's values; a bad bending stiffness (the library's one-line message at the field);
    four times the stiffness (every held frequency doubles: the arm's masses are the beam's,
    the roller held); the arm removed (the library names the body still placed on it) and
    added again empty (its message at the field it names), then given the file's values
    (the starting report again).  Each time the page's frequencies are
    ``Chain.natural_frequencies`` of the program the studio holds, to 1e-12, and the
    report's arm section is drawn: its first bending mode, a row per speed, its plots."""
    shots = Path(os.environ.get("CAMJAX_STUDIO_SCREENSHOTS") or tmp_path)
    rpm = "2000:3200:3"
    running = studio("swinging_arm", rpm=rpm)
    file_arm = tomllib.loads(cp.example_path("swinging_arm").read_text())["arm"]
    idle = "document.body.dataset.busy === '0'"
    ready = f"document.querySelector('#status').textContent === 'ready' && {idle}"
    clean = f"{ready} && !document.querySelector('.err')"
    posted = lambda r: "/api/program" in r.url and r.request.method == "POST"  # noqa: E731
    arm_input = lambda key: f'#arm input[data-key="{key}"]'  # noqa: E731

    def arm_drawn(session):
        """The page's frequencies and arm section against the program the studio holds."""
        state = call(running.url + f"api/program?session={session}")[1]
        chain = cp.Program.from_dict(state["program"]).chain
        held, _ = chain.natural_frequencies(contact=True)
        free, _ = chain.natural_frequencies(contact=False)
        np.testing.assert_allclose(json.loads(page.get_attribute("#train-held", "data-hz")), held, rtol=1e-12)
        np.testing.assert_allclose(json.loads(page.get_attribute("#train-free", "data-hz")), free,
                                   rtol=1e-12, atol=1e-9)  # the free chain's first: the rigid swing, 0 Hz
        fundamental = float(page.get_attribute("#arm-fundamental", "data-hz"))
        assert abs(fundamental / held[0] - 1) < 1e-12
        assert f"{held[0]:.6g}" in page.inner_text("#arm-facts")
        for key, value in state["program"]["arm"].items():  # the table shows the program's fields
            assert float(page.input_value(arm_input(key))) == value
        assert page.locator("#arm-speeds tbody tr").count() == 3
        assert page.locator("#c-arm-speeds canvas").count() == page.locator("#c-arm-orders canvas").count() == 1
        return held

    def message_of(edit) -> str:
        """The library's message for the studio's program changed by ``edit``."""
        data = call(running.url + f"api/program?session={session}")[1]["program"]
        edit(data)
        with pytest.raises(ValueError) as error:
            cp.Program.from_dict(data)
        return str(error.value)

    try:
        with opened_page(running.url, height=1300) as (page, errors):
            page.wait_for_selector("#arm-fundamental", timeout=2 * REDRAW_MS)
            page.wait_for_function(ready, timeout=REDRAW_MS)
            session = page.evaluate("SESSION")
            assert page.is_visible("#arm-box") and not page.is_visible("#add-arm")
            assert page.locator("#arm input").count() == len(cp.ARM_FIELDS)
            assert "the roller sits 98 mm from the pivot" in page.inner_text("#arm-notes")
            assert f"empty: {cp.DEFAULT_ELEMENTS} over the length" in page.inner_text("#arm")
            start = arm_drawn(session)
            closed = cp.Program.load(cp.example_path("swinging_arm")).chain.arm.pinned_frequencies_hz(1)[0]
            assert abs(start[0] / closed - 1) < 1e-4  # the pinned Rayleigh beam's closed form
            page.screenshot(path=str(shots / "studio-arm-start.png"), full_page=True)

            # a bad stiffness: the library's message at the field, the views stale
            stiffness = arm_input("bending_stiffness_n_m2")
            expected = message_of(lambda d: d["arm"].update(bending_stiffness_n_m2=-1))
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.fill(stiffness, "-1")
            page.wait_for_function(f"!!document.querySelector('#arm .err') && {idle}", timeout=REDRAW_MS)
            assert page.inner_text("#arm .err") == expected == "[arm] bending_stiffness_n_m2 must be positive, got -1"
            key = "document.querySelector('#arm .err').previousElementSibling.dataset.key"
            assert page.evaluate(key) == "bending_stiffness_n_m2"
            assert page.evaluate("document.body.dataset.stale") == "1"
            # four times as stiff: every held frequency twice
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.fill(stiffness, repr(4 * file_arm["bending_stiffness_n_m2"]))
            page.wait_for_function(clean, timeout=REDRAW_MS)
            stiffer = arm_drawn(session)
            np.testing.assert_allclose(stiffer, 2 * start, rtol=1e-12)
            page.locator("#arm-report").screenshot(path=str(shots / "studio-arm.png"))

            # removed: the library names the body still placed on the arm, at its row
            expected = message_of(lambda d: d.pop("arm"))
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.click("#remove-arm")
            page.wait_for_function(f"!!document.querySelector('.err') && {idle}", timeout=REDRAW_MS)
            assert page.inner_text('#train tr[data-body="2"] .err') == expected
            assert expected == "[[train]] body 2 (mid-rod) at_mm: a place on the arm needs an [arm] table"
            assert not page.is_visible("#arm-box") and page.is_visible("#add-arm")
            # added again, empty: the library's message at the field it names
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.click("#add-arm")
            page.wait_for_function(f"!!document.querySelector('#arm .err') && {idle}", timeout=REDRAW_MS)
            assert page.inner_text("#arm .err") == "[arm] needs bending_stiffness_n_m2"
            assert page.evaluate(key) == "bending_stiffness_n_m2"
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.fill(stiffness, repr(file_arm["bending_stiffness_n_m2"]))
            page.wait_for_function(f"!!document.querySelector('#arm .err') && {idle}", timeout=REDRAW_MS)
            assert page.inner_text("#arm .err") == "[arm] needs mass_per_length_kg_per_m"  # at its field
            assert page.evaluate(key) == "mass_per_length_kg_per_m"
            with page.expect_response(posted, timeout=REDRAW_MS):  # one edit, typed within the debounce
                for name in ("mass_per_length_kg_per_m", "rotary_inertia_kg_m", "damping_ratio"):
                    page.fill(arm_input(name), repr(file_arm[name]))
            page.wait_for_function(clean, timeout=REDRAW_MS)
            state = call(running.url + f"api/program?session={session}")[1]
            assert state["program"]["arm"] == file_arm
            assert cp.Program.from_dict(state["program"]) == cp.Program.load(cp.example_path("swinging_arm"))
            np.testing.assert_allclose(arm_drawn(session), start, rtol=1e-12)
            assert "[arm]\n" in state["toml"]  # the one writer's
            page.locator("#arm-box").screenshot(path=str(shots / "studio-arm-editor.png"))
            page.screenshot(path=str(shots / "studio-arm-end.png"), full_page=True)
            assert not errors, errors
    finally:
        running.stop()


def test_page_adds_a_flexible_arm_to_a_one_body_swinging_follower():
    """*+ flexible arm* on a one-body swinging roller (the indexer's cam): an empty ``[arm]``
    and a chain whose first body is the roller; the library then names, one at a time and
    at the field or row it names, the one-body ``[follower]`` fields the chain replaces, the
    roller's mass, the arm's stiffness and its damping (the steady state needs it).  Given them, the page's held frequencies are
    ``Chain.natural_frequencies`` of the program the studio holds (1e-12), the first within
    1e-4 of the pinned Rayleigh beam's closed form (the roller held, nothing else on the
    arm), and the studio's TOML reads back to that program."""
    indexer = cp.Program.load(cp.example_path("indexer"))
    swinging = dataclasses.replace(indexer, follower=dataclasses.replace(
        indexer.follower, kind="swinging-roller", arm_mm=98.0, pivot_mm=110.0))
    rod = tomllib.loads(cp.example_path("swinging_arm").read_text())["arm"]
    running = studio(swinging, rpm="2000:3200:2")
    idle = "document.body.dataset.busy === '0'"
    clean = f"document.querySelector('#status').textContent === 'ready' && {idle} && !document.querySelector('.err')"
    failed = f"!!document.querySelector('.err') && {idle}"
    posted = lambda r: "/api/program" in r.url and r.request.method == "POST"  # noqa: E731
    before_error = "document.querySelector('.err').previousElementSibling"

    def message_of(data) -> str:
        with pytest.raises(ValueError) as error:
            cp.Program.from_dict(data)
        return str(error.value)

    try:
        with opened_page(running.url) as (page, errors):
            page.wait_for_selector("#jump", timeout=2 * REDRAW_MS)
            page.wait_for_function(clean, timeout=REDRAW_MS)
            session = page.evaluate("SESSION")
            assert page.is_visible("#add-arm") and not page.is_visible("#arm-box")
            assert not page.is_visible("#chain-box") and not page.is_visible("#train-box")
            data = call(running.url + f"api/program?session={session}")[1]["program"]
            classic = [key for key in cp.CLASSIC_FIELDS if key in data["follower"]]
            assert classic == list(cp.CLASSIC_FIELDS)  # the indexer gives all five
            # added: the chain's fields replace the one-body ones, which the library names
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.click("#add-arm")
            page.wait_for_function(failed, timeout=REDRAW_MS)
            data.update(arm={}, train=[{"name": "roller"}])
            assert page.inner_text(".err") == message_of(dict(data))
            assert page.inner_text(".err").startswith(f"[follower] {', '.join(classic)}: a file with a [[train]]")
            assert page.evaluate(f"{before_error}.closest('#follower') !== null && {before_error}.dataset.key") == "mass_kg"
            with page.expect_response(posted, timeout=REDRAW_MS):  # one edit, typed within the debounce
                for key in classic:
                    page.fill(f'#follower input[data-key="{key}"]', "")
            page.wait_for_function(failed, timeout=REDRAW_MS)
            for key in classic:
                del data["follower"][key]
            assert page.inner_text('#train tr[data-body="1"] .err') == message_of(dict(data))
            assert message_of(dict(data)) == "[[train]] body 1 (roller): needs mass_kg"
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.fill('#train input[data-body="1"][data-key="mass_kg"]', "0.025")
            page.wait_for_function(failed, timeout=REDRAW_MS)
            assert page.inner_text("#arm .err") == "[arm] needs bending_stiffness_n_m2"
            assert page.evaluate(f"{before_error}.dataset.key") == "bending_stiffness_n_m2"
            with page.expect_response(posted, timeout=REDRAW_MS):
                for key in ("bending_stiffness_n_m2", "mass_per_length_kg_per_m"):
                    page.fill(f'#arm input[data-key="{key}"]', repr(rod[key]))
            page.wait_for_function(failed, timeout=REDRAW_MS)  # the steady state needs the arm damped
            assert page.inner_text("#arm .err").startswith("[arm] damping_ratio: the arm's modes have no damping")
            assert page.evaluate(f"{before_error}.dataset.key") == "damping_ratio"
            with page.expect_response(posted, timeout=REDRAW_MS):
                page.fill('#arm input[data-key="damping_ratio"]', repr(rod["damping_ratio"]))
            page.wait_for_function(clean, timeout=REDRAW_MS)
            state = call(running.url + f"api/program?session={session}")[1]
            program = cp.Program.from_dict(state["program"])
            assert state["program"]["train"] == [{"name": "roller", "mass_kg": 0.025}]
            given = ("bending_stiffness_n_m2", "mass_per_length_kg_per_m", "damping_ratio")
            assert state["program"]["arm"] == {k: rod[k] for k in given}
            assert cp.Program.from_dict(tomllib.loads(state["toml"])) == program
            held, _ = program.chain.natural_frequencies(contact=True)
            np.testing.assert_allclose(json.loads(page.get_attribute("#train-held", "data-hz")), held, rtol=1e-12)
            assert float(page.get_attribute("#arm-fundamental", "data-hz")) == held[0]
            closed = program.chain.arm.pinned_frequencies_hz(1)[0]  # an Euler-Bernoulli beam here
            assert abs(held[0] / closed - 1) < 1e-4, (held[0], closed)
            assert page.locator("#arm-speeds tbody tr").count() == 2
            assert not errors, errors
    finally:
        running.stop()
