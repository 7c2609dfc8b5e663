"""Saving and loading motion laws as JSON."""

import json

import numpy as np
import pytest

from camjax.laws import BSplineLaw, from_dict, get, load, names, save, to_dict

TAU = np.linspace(-0.1, 1.1, 10001)


def _same(a, b):
    for x, y in zip(a.evaluate(TAU), b.evaluate(TAU)):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


@pytest.mark.parametrize("zero_jerk", [False, True])
def test_bspline_round_trip_is_exact(tmp_path, zero_jerk):
    law = BSplineLaw.fit(get("modsine"), 14, zero_jerk=zero_jerk)
    rng = np.random.default_rng(3)
    law = BSplineLaw(law.coefficients + 1e-3 * rng.standard_normal(14), zero_jerk=zero_jerk)
    loaded = load(save(law, tmp_path / "law.json"))
    assert isinstance(loaded, BSplineLaw) and loaded.zero_jerk == zero_jerk
    _same(law, loaded)
    data = json.loads((tmp_path / "law.json").read_text())
    assert len(data["knots"]) == law.n_basis + law.degree + 1
    np.testing.assert_allclose(data["control_points"][:3], 0.0)
    np.testing.assert_allclose(data["control_points"][-3:], 1.0)


@pytest.mark.parametrize("name", names() + ["scca:0.3,0.2,0.4", "poly:6"])
def test_named_laws_round_trip(tmp_path, name):
    law = get(name)
    loaded = load(save(law, tmp_path / "law.json"))
    assert type(loaded) is type(law)
    _same(law, loaded)


def test_bad_descriptions_are_rejected(tmp_path):
    good = to_dict(BSplineLaw.fit(get("cycloidal"), 10))
    with pytest.raises(ValueError, match="format"):
        from_dict({"kind": "bspline"})
    with pytest.raises(ValueError, match="knots"):
        from_dict({**good, "knots": list(np.linspace(0, 1, len(good["knots"])))})
    with pytest.raises(ValueError, match="kind"):
        from_dict({**good, "kind": "fourier"})
    with pytest.raises(ValueError, match="lacks"):
        from_dict({k: v for k, v in good.items() if k != "degree"})
    path = tmp_path / "broken.json"
    path.write_text("{not json")
    with pytest.raises(ValueError, match="JSON"):
        load(path)
    with pytest.raises(ValueError, match="finite"):
        from_dict({**good, "coefficients": [float("nan")] * 10})
