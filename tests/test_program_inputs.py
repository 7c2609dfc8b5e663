"""A cam program's inputs: integers of any size read as numbers, sizes no machine has and a
grooved cam's preload warned of in the report, the speed's warning in the report."""

import tomllib

import numpy as np
import pytest

from camjax.program import ABSURD_SIZES, Program, cam_geometry, design_warnings, example_path

INDEXER = example_path().read_text()


def _with(text: str, key: str, value: str) -> Program:
    lines = [
        f"{key} = {value}" if line.split("=")[0].strip() == key else line
        for line in text.splitlines()
    ]
    return Program.from_dict(tomllib.loads("\n".join(lines)))


@pytest.mark.parametrize("key, value", [("roller_radius_mm", 10**12), ("base_radius_mm", 10**20)])
def test_a_huge_toml_integer_is_a_float_and_warned_of(key, value):
    """A JAX OverflowError traceback before: the integer reached a jitted function."""
    program = _with(INDEXER, key, str(value))
    assert isinstance(getattr(program.follower, key), float)
    geometry = cam_geometry(program, np.arange(360.0))  # the profile's jitted geometry runs
    assert np.isfinite(geometry.max_pressure_angle_deg)
    assert f"follower.{key} = {float(value):g} is more than 10,000 mm" in "\n".join(
        design_warnings(program)
    )


@pytest.mark.parametrize(
    "key, value, unit",
    [
        ("preload_n", "1e12", "N"),
        ("mass_kg", "20000", "kg"),
        ("stiffness_n_per_mm", "1e10", "N/mm"),
        ("roller_radius_mm", "12000", "mm"),
    ],
)
def test_an_absurd_size_is_warned_of_with_its_key_and_value(key, value, unit):
    lines = design_warnings(_with(INDEXER, key, value))
    expected = (
        f"follower.{key} = {float(value):g} is more than {ABSURD_SIZES[unit]:,.0f} {unit}, larger "
        f"than any cam machine's: check its unit ({unit})"
    )
    assert expected in lines
    assert not [x for x in design_warnings(Program.load(example_path())) if "larger than any" in x]


def test_a_huge_lift_is_warned_of_by_segment():
    text = INDEXER.replace("lift_mm = 20", "lift_mm = 20000").replace(
        "lift_mm = -20", "lift_mm = -20000"
    )
    program = Program.from_dict(
        tomllib.loads(text.replace("base_radius_mm = 40", "base_radius_mm = 40000"))
    )
    lines = [x for x in design_warnings(program) if "larger than any" in x]
    assert [x.split(" is ")[0] for x in lines] == [
        "follower.base_radius_mm = 40000",
        "segment 1: lift_mm = 20000",
        "segment 3: lift_mm = -20000",
    ]


def test_a_grooved_cams_preload_is_said_to_do_nothing():
    grooved = INDEXER.replace("spring_rate_n_per_mm = 10 ", "# no spring ")
    program = Program.from_dict(tomllib.loads(grooved))
    assert program.follower.form_closed and program.follower.preload_n == 300
    assert [x for x in design_warnings(program) if "preload" in x] == [
        "follower.preload_n = 300 does nothing on a grooved cam (no spring_rate_n_per_mm: no return spring "
        "preloads the follower, the groove holds it): remove it, or give the return spring's "
        "spring_rate_n_per_mm"
    ]
    quiet = Program.from_dict(tomllib.loads(grooved.replace("preload_n = 300", "preload_n = 0")))
    assert not [x for x in design_warnings(quiet) if "preload" in x]
