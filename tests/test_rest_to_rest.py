"""Laws that do not rise from rest to rest are refused, in one line, by every tool that
follows a rise with a dwell (API and CLI), and traced laws still pass."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import COMPILED_RTOL

import camjax
from camjax import laws
from camjax.cli import main
from camjax.distributed import spec_from_dict
from camjax.models import SwingingFollower, kinematic_impact, kinematic_impact_table
from camjax.studies import run_study

NOT_REST_TO_REST = {
    "constant-velocity": "starts or ends in motion (v(0) = 1, v(1) = 1)",
    "polynomial7:1,0,0,-1,0,0": "starts or ends in motion (v(0) = 1, v(1) = -1)",
    "double-harmonic": "ends in a reversal",
}

TOOLS = {
    "torsion_factor": lambda law: camjax.torsion_factor(law, 5.0),
    "residual_vibration": lambda law: camjax.residual_vibration(law, 5.0),
    "solve": lambda law: camjax.solve(law, camjax.SpringMass(5.0, 0.0)),
    "ct_curve": lambda law: camjax.ct_curve(law, [5.0]),
    "ct_curves": lambda law: camjax.ct_curves(["cycloidal", law], [5.0]),
    "kinematic_impact": lambda law: kinematic_impact(law, 0.01, 0.0),
    "kinematic_impact_table": lambda law: kinematic_impact_table(law, [0.01], [0.0]),
    "SwingingFollower": lambda law: SwingingFollower(rise=laws.get(law)),
    "run_study": lambda law: run_study([law], np.array([5.0]), []),
    "a sweep spec": lambda law: spec_from_dict({"output": "out", "period_ratio": {"values": [5.0]},
                                                "laws": {"names": [law]}}),
}


def check_message(text: str, tool: str, law: str) -> None:
    assert len(text.splitlines()) == 1
    assert text.count(f"{tool} needs a rise from rest to rest") == 1
    assert f"'{laws.get(law).name}' {NOT_REST_TO_REST[law]}" in text
    listed = text.rsplit(" takes ", 1)[1]
    assert all(name in listed.split(", ") for name in laws.names())


@pytest.mark.parametrize("tool", list(TOOLS))
@pytest.mark.parametrize("law", list(NOT_REST_TO_REST))
def test_every_tool_refuses_a_law_that_does_not_rest_at_both_ends(tool, law):
    with pytest.raises(ValueError) as error:
        TOOLS[tool](law)
    check_message(str(error.value), tool, law)


@pytest.mark.parametrize("argv, tool", [
    (["ct", "--n", "5"], "camjax ct"),
    (["backlash", "--bk", "0.01", "--dn", "0"], "camjax backlash"),
    (["bench", "--n", "5"], "camjax bench"),
])
@pytest.mark.parametrize("law", list(NOT_REST_TO_REST))
def test_commands_refuse_it_with_exit_status_2(capsys, argv, tool, law):
    code = main([*argv, "--law", law])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.startswith(f"camjax {argv[0]}: error: --law: ")
    check_message(err.strip().split("--law: ", 1)[1], tool, law)


def test_follower_and_sweep_commands_refuse_it(capsys, tmp_path):
    code = main(["follower", "--law", "double-harmonic"])
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1
    check_message(err.strip().split("--law: ", 1)[1], "camjax follower", "double-harmonic")
    spec = tmp_path / "spec.toml"
    spec.write_text('output = "out"\n[period_ratio]\nvalues = [5.0]\n[laws]\nnames = ["constant-velocity"]\n')
    code = main(["sweep", str(spec)])
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "laws.names entry 'constant-velocity' starts or ends in motion" in err


def test_every_named_law_and_family_member_passes():
    for name in laws.names() + ["scca:0.3,0.2,0.4", "poly:5", "triple-harmonic:6,1",
                                "modified-sine-cv:0.2", "cycloidal-asym:0.3",
                                "polynomial5:0,3,0,-3"]:
        assert laws.rest_to_rest(name, "t").name == laws.get(name).name
    # The unknown-name error lists the same rest-to-rest names.
    with pytest.raises(ValueError) as error:
        laws.get("nope")
    valid = str(error.value).split("valid names: ", 1)[1].split(", ")
    assert set(laws.names()) <= set(valid) and "double-harmonic" in valid


def test_traced_laws_still_pass():
    @jax.jit
    def ct(coefficients, inflection):
        spline = laws.BSplineLaw(coefficients, degree=5)
        asym = laws.Inflected(laws.get("cycloidal"), inflection)
        assert laws.rest_to_rest_fault(spline) is None and laws.rest_to_rest_fault(asym) is None
        return camjax.torsion_factor(asym, 3.0, resolution=256)

    free = laws.BSplineLaw.fit(laws.get("cycloidal"), 4, 5).coefficients
    value = ct(jnp.asarray(free), 0.4)
    assert np.isfinite(float(value)) and float(value) == pytest.approx(
        float(camjax.torsion_factor("cycloidal-asym:0.4", 3.0, resolution=256)), rel=COMPILED_RTOL)
