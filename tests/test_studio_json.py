"""The page posts the program as JSON (its structure, as the TOML reader gives it) and the
server writes TOML with ``Program.to_toml``, the one writer: every built-in program and a
chain posted as JSON are the ``Program`` read from their file, and the studio's TOML is that
program's ``to_toml``.  No browser: the JSON interface as the page calls it."""

import copy
import dataclasses
import json
import tomllib
import urllib.error
import urllib.parse
import urllib.request

import numpy as np
import pytest

from camjax import program as cp
from camjax.cli import dump_json
from camjax.studio import Studio

RPM = "600"  # one speed: the round trip is about the program, not the analysis
CHAIN_RPM = "2000"  # a chain's grid resolves its highest mode at the speed: a lighter one here
ARM_RPM = "3055.7749"  # the flexible arm's paper's 320 rad/s
BUILT_IN = ["feed", "indexer", "servo", "valve"]
CHAIN = """
[program]
name = "rocker"

[[segment]]
angle_deg = 120
lift_mm = 6
law = "cycloidal"

[[segment]]
angle_deg = 30

[[segment]]
angle_deg = 120
lift_mm = -6
law = "modified-sine"

[[segment]]
angle_deg = 90

[follower]
kind = "translating-roller"
base_radius_mm = 30
roller_radius_mm = 10

[[train]]
name = "tappet"
mass_kg = 0.04

[[train]]
name = "pushrod"
mass_kg = 0.03
stiffness_n_per_mm = 900
damping_n_s_per_m = 8

[[train]]
name = "valve"
mass_kg = 0.05
stiffness_n_per_mm = 1500
damping_n_s_per_m = 6
ratio = 1.5
lever_mass_kg = 0.02

[spring]
rate_n_per_mm = 40
preload_n = 300
mass_kg = 0.03
damping_ratio = 0.04
elements = 10
"""


def call(studio: Studio, path: str, body=None, content_type="application/json"):
    """(status, decoded JSON or text) of a GET, or of a POST of ``body`` (JSON-encoded unless
    a ``str``) from the studio's own origin."""
    data = None if body is None else (body if isinstance(body, str) else json.dumps(body)).encode()
    headers = {} if data is None else {"Origin": studio.origin, "Content-Type": content_type}
    request = urllib.request.Request(
        studio.url + path, data=data, headers=headers, method="GET" if data is None else "POST"
    )
    try:
        with urllib.request.urlopen(request, timeout=600) as response:
            text = response.read().decode()
            status = response.status
    except urllib.error.HTTPError as error:
        text, status = error.read().decode(), error.code
    try:
        return status, json.loads(text)
    except json.JSONDecodeError:
        return status, text


@pytest.fixture(scope="module")
def running():
    studio = Studio(
        cp.example_path("feed").read_text(), base=cp.example_path("feed").parent, rpm=RPM
    )
    studio.start(warm=False)
    yield studio
    studio.stop()


def _round_trip(studio: Studio, session: str, text: str, base, rpm: str = RPM):
    """Post ``text``'s structure as JSON: the workbench's program, its TOML download and the
    structure ``GET /api/program`` gives back."""
    data = tomllib.loads(text)
    status, report = call(studio, f"api/program?session={session}&rpm={rpm}", data)
    assert status == 200, report
    status, toml = call(studio, f"api/program.toml?session={session}")
    assert status == 200
    state = call(studio, f"api/program?session={session}")[1]
    return studio.workbenches[session].program, toml, state, report


@pytest.mark.parametrize("name", BUILT_IN)
def test_a_built_in_program_posted_as_json_is_its_file(running, name):
    path = cp.example_path(name)
    expected = cp.Program.load(path)
    rpm = CHAIN_RPM if expected.chain is not None else RPM
    program, toml, state, _ = _round_trip(running, name, path.read_text(), path.parent, rpm)
    assert program == expected
    assert toml == expected.to_toml()  # the one writer: the studio writes nothing of its own
    assert state["toml"] == toml and state["program"] == tomllib.loads(path.read_text())
    again = cp.Program.from_dict(tomllib.loads(toml), base=path.parent)  # the download reads back
    assert again == expected and again.to_toml() == toml


def test_a_chain_posted_as_json_is_its_file(running, tmp_path):
    path = tmp_path / "rocker.toml"
    path.write_text(CHAIN)
    expected = cp.Program.load(path)
    assert expected.chain is not None and len(expected.chain.bodies) == 3
    program, toml, state, report = _round_trip(running, "chain", CHAIN, tmp_path)
    assert program == expected and program.chain == expected.chain
    assert toml == expected.to_toml()
    assert cp.Program.from_dict(tomllib.loads(toml)) == expected
    assert report["train"]["bodies"] == ["tappet", "pushrod", "valve"]
    # the page's chain fields come from the chain's own types
    fields = state["fields"]
    assert [f["name"] for f in fields["body"]] == [
        "name",
        "mass_kg",
        "stiffness_n_per_mm",
        "damping_n_s_per_m",
        "ratio",
        "lever_mass_kg",
        "lash_mm",
        "at_mm",  # a body's place on a swinging follower's flexible [arm]
    ]
    spring = {f["name"]: (f["required"], f["default"]) for f in fields["spring"]}
    assert spring["rate_n_per_mm"] == (True, None) and spring["elements"] == (False, None)
    assert spring["preload_n"] == (False, 0.0)
    assert fields["chain_replaces"] == list(cp.CLASSIC_FIELDS)
    assert fields["follower_kinds"] == cp.follower_kinds()  # the reader's one registry
    assert [k["name"] for k in fields["follower_kinds"]] == list(cp.FOLLOWER_KINDS)
    assert [k["name"] for k in fields["follower_kinds"] if not k["roller"]] == [
        "translating-flat",
        "swinging-flat",
    ]


def test_a_flexible_arm_posted_as_json_is_its_file(running):
    """The swinging arm example posted as JSON: its ``[arm]`` is the file's, the studio's TOML
    is ``to_toml``'s (with the ``[arm]``), the page's arm fields are the library's
    ``ARM_FIELDS`` in ``Arm``'s order, and the report's arm section is ``analyse``'s: its
    first bending mode (cam held) within 1e-4 of the pinned Rayleigh beam's closed form."""
    path = cp.example_path("swinging_arm")
    expected = cp.Program.load(path)
    program, toml, state, report = _round_trip(
        running, "arm", path.read_text(), path.parent, ARM_RPM
    )
    assert program == expected and program.chain.arm == expected.chain.arm is not None
    assert toml == expected.to_toml() and "\n[arm]\n" in toml
    assert cp.Program.from_dict(tomllib.loads(toml)) == expected
    assert state["program"]["arm"] == tomllib.loads(path.read_text())["arm"]
    arm_fields = state["fields"]["arm"]
    names = [f.name for f in dataclasses.fields(cp.Arm) if f.name in cp.ARM_FIELDS]
    assert [f["name"] for f in arm_fields] == names and set(names) == cp.ARM_FIELDS
    assert [f["name"] for f in arm_fields if f["required"]] == [
        "bending_stiffness_n_m2",
        "mass_per_length_kg_per_m",
    ]
    by_name = {f["name"]: f for f in arm_fields}
    assert (
        by_name["modes"]["default"] == cp.Arm.modes and by_name["damping_ratio"]["default"] == 0.0
    )
    assert by_name["elements"]["empty"].startswith(f"{cp.DEFAULT_ELEMENTS} ")
    # the report's arm section: camjax.program.analyse's, as the CLI writes it
    arm = report["train"]["arm"]
    reference = json.loads(dump_json(cp.analyse(expected, [float(ARM_RPM)]).as_dict()))["train"][
        "arm"
    ]
    assert arm["body"] == reference["body"] == "mid-rod" and arm["orders"] == reference["orders"]
    assert arm["fundamental_hz"] == reference["fundamental_hz"]
    (row,), (ref,) = arm["speeds"], reference["speeds"]
    np.testing.assert_allclose(
        row["bending_harmonics_mm"], ref["bending_harmonics_mm"], rtol=1e-9, atol=1e-12
    )
    np.testing.assert_allclose(row["max_bending_mm"], ref["max_bending_mm"], rtol=1e-9)
    closed = expected.chain.arm.pinned_frequencies_hz(1)[0]
    assert abs(arm["fundamental_hz"] / closed - 1) < 1e-4
    assert arm["fundamental_hz"] == report["train"]["natural_frequencies_held_hz"][0]


def _arm_data(edit) -> dict:
    data = tomllib.loads(cp.example_path("swinging_arm").read_text())
    edit(data)
    return data


@pytest.mark.parametrize(
    "edit",
    [
        lambda d: d["arm"].update(damping_ratio=1.5),
        lambda d: d["arm"].update(bending_stiffness_n_m2=-1),
        lambda d: d.update(arm={}),  # added by the page: empty
        lambda d: d.pop("arm"),  # removed: a body still placed on it
        lambda d: d["arm"].update(width_mm=5),
        lambda d: d["follower"].update(kind="translating-roller"),
        lambda d: d.pop("train"),
    ],
    ids=["damping", "negative", "empty", "removed", "unknown", "translating", "no-train"],
)
def test_a_bad_arm_is_a_400_with_the_library_message(running, edit):
    data = _arm_data(edit)
    with pytest.raises(ValueError) as expected:
        cp.Program.from_dict(copy.deepcopy(data))
    status, answer = call(running, f"api/program?session=bad-arm&rpm={ARM_RPM}", data)
    assert status == 400 and answer == {"error": str(expected.value)}
    assert "\n" not in answer["error"] and "arm" in answer["error"], answer


def test_an_undamped_arm_is_a_400_naming_its_damping_ratio(running):
    """The steady state of an arm without damping does not exist: the analysis's one line
    names the ``[arm]`` field to give (the page shows it there)."""
    data = _arm_data(lambda d: d["arm"].pop("damping_ratio"))
    status, answer = call(running, f"api/program?session=bad-arm&rpm={ARM_RPM}", data)
    assert status == 400 and answer["error"].startswith(
        "[arm] damping_ratio: the arm's modes have no damping"
    )
    assert "\n" not in answer["error"]


def test_the_report_names_the_residual_segments(running):
    """Which segments each speed's residual vibrations belong to is the program's rule
    (``Program.residual_segments``), served in the report, not re-derived by the page."""
    report = call(running, "api/report")[1]
    feed = cp.Program.load(cp.example_path("feed"))
    assert report["residual_segments"] == [i + 1 for i in feed.residual_segments()]
    assert len(report["residual_segments"]) == len(report["speeds"][0]["residual_vibration_mm"]) > 0


def test_an_opened_file_is_read_by_the_server(running):
    text = cp.example_path("indexer").read_text()
    status, report = call(running, f"api/open?session=open&rpm={RPM}", {"toml": text})
    assert status == 200 and report["program"] == "indexer"
    assert running.workbenches["open"].program == cp.Program.load(cp.example_path("indexer"))
    status, answer = call(running, "api/open?session=open", {"toml": "[program\nname = 1"})
    assert status == 400 and answer["error"].startswith("not valid TOML (")
    status, answer = call(running, "api/open?session=open", {"text": text})
    assert (
        status == 400 and answer["error"] == 'the body must be {"toml": the program file\'s text}'
    )


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ("[1, 2]", "the program must be a JSON object (its tables by name), got list"),
        (
            '{"program": {"name": null}}',
            "program.name: null is no value (TOML has none): leave the key out",
        ),
        ('{"segment": [{"angle_deg": NaN}]}', "the program holds NaN: every number must be finite"),
        (
            '{"segment": [{"angle_deg": Infinity}]}',
            "the program holds Infinity: every number must be finite",
        ),
        (
            "{",
            "not valid JSON (Expecting property name enclosed in double quotes: line 1 column 2 (char 1))",
        ),
    ],
)
def test_a_bad_json_body_is_a_400_in_one_line(running, body, message):
    status, answer = call(running, "api/program?session=bad", body)
    assert status == 400 and answer == {"error": message}
    assert "bad" not in running.workbenches or running.workbenches["bad"].report is None


def test_a_whole_number_past_32_bits_is_read_as_a_float(running):
    """JSON has one kind of number: a whole one this large is a length, read as a float (as a
    TOML file's float), so no integer overflows the arrays."""
    from camjax.studio import parse_json_program

    data = parse_json_program(
        '{"a": 5, "b": 100000000000000000000, "c": -2147483648, "d": 2147483647}'
    )
    assert data == {"a": 5, "b": 1e20, "c": -2147483648.0, "d": 2147483647}
    assert type(data["a"]) is int and type(data["b"]) is float and type(data["d"]) is int
