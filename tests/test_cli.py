"""The core commands: output shapes, files written, and exit status 2 on bad input."""

import json

import numpy as np
import pytest

import camjax
from camjax import laws
from camjax.cli import main


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
    np.testing.assert_allclose(entry["ct"], curve.ct, rtol=1e-12)
    np.testing.assert_allclose(entry["residual"], curve.residual, rtol=1e-12)
    np.testing.assert_allclose(entry["peak_in_motion"], curve.peak_in_motion, rtol=1e-12)
    assert entry["Ca"] == pytest.approx(5.52796, abs=1e-5) and "Cv" in entry and "Cj" in entry


def test_ct_writes_tables_and_figures(capsys, tmp_path):
    code, out, _ = run(capsys, "ct", "--law", "cycloidal", "--law", "modified-sine",
                       "--n", "1:20:120", "--out", str(tmp_path))
    assert code == 0 and "cycloidal" in out
    for name in ("ct.csv", "ct.json", "torsion_factor_fit.md", "ct_curves.png",
                 "residual_curves.png", "ca_ct.png"):
        assert (tmp_path / name).stat().st_size > 0
    rows = (tmp_path / "ct.csv").read_text().splitlines()
    assert rows[0] == "law,period_ratio,ct,residual,peak_in_motion,ca_ct" and len(rows) == 241
    assert "| cycloidal |" in (tmp_path / "torsion_factor_fit.md").read_text()


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
    ],
)
def test_bad_arguments_exit_2_with_one_line(capsys, argv, message):
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert message in err and len(err.strip().splitlines()) == 1
