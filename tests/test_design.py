"""Design of B-spline motion laws: residual quadrature, gradients, caps, a small run."""

import argparse
import json
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
import camjax.law_design as D
from camjax.laws import BSplineLaw, get, load

START = BSplineLaw.fit(get("cycloidal"), 10)


@pytest.mark.parametrize("name", ["cycloidal", "poly4567", "modified-trapezoid"])
@pytest.mark.parametrize("damping", [0.0, 0.05])
def test_quadrature_residual_matches_exact_path(name, damping):
    law = get(name)
    n = np.array([1.7, 6.3, 11.9])
    ours = np.asarray(D.residual(law, n, damping))
    exact = np.array([float(camjax.residual_vibration(law, x, damping)) for x in n])
    np.testing.assert_allclose(ours, exact, rtol=1e-9, atol=1e-13)


def test_quadrature_residual_matches_cycloidal_closed_form():
    n = np.linspace(1.2, 16.0, 301)
    closed = 2 * n * np.abs(np.sin(np.pi * n)) / np.abs(n**2 - 1)
    np.testing.assert_allclose(D.residual(get("cycloidal"), n), closed, rtol=1e-10, atol=1e-13)


def test_quadrature_residual_of_a_spline_matches_exact_path():
    n = np.array([3.3, 9.1])
    exact = [float(camjax.residual_vibration(START, x)) for x in n]
    np.testing.assert_allclose(D.residual(START, n), exact, rtol=1e-9)


OBJECTIVES = [
    D.Residual(7.3),
    D.MaxResidual(6.0, 12.0, samples=64),
    D.ExpectedResidual(8.0, 0.8, nodes=16, damping=0.02),
    D.CaCt(8.0),
    D.MaxCaCt(7.2, 8.8, samples=3),
    D.RmsAcceleration(),
]


@pytest.mark.parametrize("objective", OBJECTIVES, ids=lambda o: type(o).__name__)
def test_objective_gradient_matches_finite_differences(objective):
    direction = jnp.asarray(np.random.default_rng(0).standard_normal(10)) * 1e-2

    def f(t):
        law = BSplineLaw(START.coefficients + t * direction)
        return objective.train(law, 6.5, 16.0)

    derivative = float(jax.grad(f)(0.0))
    h = 1e-5
    central = (float(f(h)) - float(f(-h))) / (2 * h)
    assert derivative == pytest.approx(central, rel=1e-5, abs=1e-9)
    assert abs(derivative) > 1e-6  # a direction the objective actually moves in


@pytest.mark.parametrize("objective", [D.MaxResidual(6.0, 12.0, samples=32, damping=0.02),
                                       D.MaxCaCt(7.2, 8.8, samples=2)], ids=lambda o: type(o).__name__)
def test_linear_maps_reproduce_the_features(objective):
    # A design trains on offset + matrix @ c (``linear_maps``); that must be the objective's
    # features for any coefficients c, not only near the start.
    knots = 10

    def features(c):
        law = BSplineLaw(c)
        return objective.features(law), D.Caps(7.0, 90.0).features(law)

    offset, jacobian = D.linear_maps(features, knots)
    c = START.coefficients + jnp.asarray(np.random.default_rng(2).standard_normal(knots)) * 0.05
    linear = jax.tree.leaves(jax.tree.map(lambda b, m: b + m @ c, offset, jacobian))
    direct = jax.tree.leaves(features(c))
    for got, want in zip(linear, direct):
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * float(jnp.max(jnp.abs(want))))


def test_cap_penalty_gradient_matches_finite_differences():
    caps = D.Caps(max_ca=6.0, max_jerk=38.0)  # the cycloidal fit (6.28, 39.5) breaks both
    direction = jnp.asarray(np.random.default_rng(1).standard_normal(10)) * 1e-2

    def f(t):
        return caps.penalty(BSplineLaw(START.coefficients + t * direction), 1e-3)

    assert float(f(0.0)) > 0
    h = 1e-6
    central = (float(f(h)) - float(f(-h))) / (2 * h)
    assert float(jax.grad(f)(0.0)) == pytest.approx(central, rel=1e-5)


def test_bad_inputs_raise_clear_errors():
    with pytest.raises(ValueError, match="band"):
        D.MaxResidual(12.0, 6.0)
    with pytest.raises(ValueError, match="damping"):
        D.Residual(5.0, damping=1.5)
    with pytest.raises(ValueError, match="max_ca"):
        D.Caps(max_ca=3.0)
    with pytest.raises(ValueError, match="optimizer"):
        D.design(D.Residual(5.0), optimizer="sgd")
    with pytest.raises(ValueError, match="objective"):
        D.design([])


def _fine_grid_peaks(law):
    tau = jnp.linspace(0.0, 1.0, 200001)
    _, v, a, j = law.evaluate(tau)
    return float(jnp.min(v)), float(jnp.max(jnp.abs(a))), float(jnp.max(jnp.abs(j)))


def test_small_design_meets_caps_and_comes_within_two_percent_of_the_optimum():
    caps = D.Caps(max_ca=7.5, max_jerk=100.0)
    result = D.design(D.MaxResidual(6.0, 12.0, samples=128), caps=caps, knots=12, steps=300,
                      progress=False)
    v_min, ca, cj = _fine_grid_peaks(result.law)
    assert v_min >= -1e-12 and ca <= 7.5 and cj <= 100.0
    # The reported max over 2000 ratios, checked by the independent exact path.
    ratios = np.linspace(6.0, 12.0, 2000)
    curve = camjax.ct_curve(result.law, ratios)
    reported = result.values["max R over [6, 12]"]
    assert reported == pytest.approx(float(curve.residual.max()), rel=1e-8)
    # No 12-knot spline within the caps does better than the LP bound (0.0430); the
    # design comes within 1% of it (0.0434), three times below 4-5-6-7 (0.151).
    bound, _ = D.ConvexBound(6.0, 12.0, knots=12).lower_bound(7.5, 100.0)  # an independent LP
    assert bound <= reported <= 1.02 * bound


def test_broken_caps_are_repaired_or_refused():
    # The 4-5-6-7 fit breaks Ca <= 6.5; the repair blends it onto the convex feasible set.
    broken = BSplineLaw.fit(get("poly4567"), 10)
    caps = D.Caps(max_ca=6.5, max_jerk=60.0)
    assert not caps.met(broken)
    repaired = caps.repair(broken)
    v_min, ca, cj = _fine_grid_peaks(repaired)
    assert v_min >= -1e-12 and ca <= 6.5 and cj <= 60.0
    assert ca > 6.49  # the nearest feasible point on the segment, not the anchor itself
    # Ca <= 4.5 with Cj <= 90 is feasible (least Cj 81), but no standard law meets it to
    # start a repair from: the result is refused.
    with pytest.raises(D.CapError, match="caps"):
        D.Caps(max_ca=4.5, max_jerk=90.0).repair(broken)
    # Cj <= 30 is below what any rise can have: refused before any work.
    with pytest.raises(ValueError, match="infeasible"):
        D.Caps(max_ca=4.5, max_jerk=30.0)


def test_same_seed_same_design():
    kwargs = dict(knots=10, steps=20, noise=1e-4, optimizer="adam", progress=False)
    a = D.design(D.Residual(7.3), seed=4, **kwargs)
    b = D.design(D.Residual(7.3), seed=4, **kwargs)
    c = D.design(D.Residual(7.3), seed=5, **kwargs)
    np.testing.assert_array_equal(a.law.coefficients, b.law.coefficients)
    assert not np.array_equal(a.law.coefficients, c.law.coefficients)


def test_a_design_reports_with_the_sweep_options_passed_in():
    """``design(sweep_options=...)`` reaches the sweeps that report the objectives: the dense
    peak search reports the design's Ca*Ct within ``PEAK_TOLERANCE`` of the default's
    (the same design: training does not sweep), and a bad option is named."""
    from camjax.metrics import PEAK_TOLERANCE

    kwargs = dict(knots=10, steps=20, optimizer="adam", progress=False)
    default = D.design(D.CaCt(7.3), **kwargs)
    dense = D.design(D.CaCt(7.3), sweep_options={"peak_search": "dense"}, **kwargs)
    np.testing.assert_array_equal(dense.law.coefficients, default.law.coefficients)
    label = D.CaCt(7.3).label
    assert dense.values[label] == pytest.approx(default.values[label], rel=PEAK_TOLERANCE)
    assert default.values[label] == pytest.approx(
        float(camjax.ct_curve(default.law, [7.3]).ca_ct[0]), rel=1e-12)
    with pytest.raises(ValueError, match="peak_search must be one of bounded, dense"):
        D.design(D.CaCt(7.3), sweep_options={"peak_search": "fast"}, **kwargs)


@pytest.mark.slow
def test_within_five_percent_of_the_convex_optimum():
    """Slow (30 s on the loaded 2-core machine, 2026-11-27): a whole 24-knot design at the default step count, and its 24-knot LP; the smaller designs of this file run by default."""
    bound, _ = D.ConvexBound(6.0, 12.0, knots=24).lower_bound(6.3, 100.0)
    result = D.design(D.MaxResidual(6.0, 12.0), caps=D.Caps(6.3, 100.0), knots=24,
                      progress=False)
    assert result.values["max R over [6, 12]"] <= 1.05 * bound


@pytest.mark.slow
def test_cli_outputs_reproduce_when_the_law_is_loaded(tmp_path):
    """Slow (32 s on the loaded 2-core machine, 2026-11-27): the design command end to end (a 12-knot design, its figures and the comparison with every standard law)."""
    from camjax.cli import design as cli

    parser = argparse.ArgumentParser()
    cli.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["design", "--band", "6:12", "--max-ca", "7.5", "--max-jerk",
                              "100", "--knots", "12", "--steps", "60", "--quiet",
                              "--out", str(tmp_path)])
    assert args.func(args) == 0
    law = load(tmp_path / "law.json")
    table = np.genfromtxt(tmp_path / "comparison.csv", delimiter=",", names=True, dtype=None,
                          encoding=None)
    assert table["law"][0] == "designed" and len(table) == 1 + len(camjax.laws.standard_laws())
    ratios = np.linspace(6.0, 12.0, 2000)
    assert float(jnp.max(D.residual(law, ratios))) == pytest.approx(table["objective"][0], rel=1e-12)
    csv = np.loadtxt(tmp_path / "law.csv", delimiter=",", skiprows=1)
    assert csv.shape == (10001, 5)
    np.testing.assert_allclose(csv[:, 1:], np.stack([np.asarray(x) for x in law.evaluate(csv[:, 0])], 1),
                               rtol=0, atol=1e-12)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["coefficients"]["Ca"] <= 7.5


def test_expected_residual_against_a_quadrature_of_the_closed_form():
    """``ExpectedResidual``: the mean of the cycloidal law's undamped residual
    ``2 n |sin(pi n)| / |n^2 - 1|`` over a normal ``n`` (8.5, 0.1), by scipy's quadrature
    against the normal density; its training value is the same mean in units of Ca."""
    from scipy.integrate import quad
    from scipy.stats import norm

    objective = D.ExpectedResidual(8.5, 0.1)
    law = get("cycloidal")

    def residual(n):
        return 2 * n * abs(math.sin(math.pi * n)) / abs(n**2 - 1)

    expected, _ = quad(lambda n: residual(n) * norm.pdf(n, 8.5, 0.1), 7.5, 9.5, points=[8.0, 9.0],
                       epsabs=1e-13, epsrel=1e-12)
    assert objective.report(law) == pytest.approx(expected, rel=1e-6)
    value = float(objective.value(objective.features(law), float(law.Ca), 1.0))
    assert value == pytest.approx(expected, rel=1e-6)


def test_a_second_design_of_one_shape_compiles_nothing():
    """The design's steps are module-level compiled functions with the law map, the
    objectives and the optimiser as arguments: a second design in a process reuses them."""
    from helpers import compiled_programs

    kwargs = dict(knots=10, steps=20, optimizer="adam", progress=False)
    first = D.design(D.Residual(7.3), **kwargs)
    with compiled_programs() as names:
        second = D.design(D.Residual(7.3), **kwargs)
    assert names == []
    np.testing.assert_array_equal(first.law.coefficients, second.law.coefficients)


def test_an_optax_transformation_in_place_of_a_name():
    """Adam written out (its direction and the decaying rate) and L-BFGS as objects give
    the named optimisers' designs; the same object again compiles nothing."""
    import optax
    from helpers import compiled_programs

    steps = 20
    adam = optax.chain(optax.scale_by_adam(), optax.scale_by_learning_rate(optax.exponential_decay(1e-2, steps, 0.01)))
    kwargs = dict(knots=10, steps=steps, progress=False)
    named = D.design(D.Residual(7.3), optimizer="adam", **kwargs)
    given = D.design(D.Residual(7.3), optimizer=adam, **kwargs)
    # The named Adam's rates come from NumPy and the chain's from XLA, each rounded its own
    # way; Adam divides by the root of tiny second moments, which carries that to ~1e-9.
    np.testing.assert_allclose(given.law.coefficients, named.law.coefficients, rtol=1e-6, atol=1e-12)
    assert given.values["R(n=7.3)"] == pytest.approx(named.values["R(n=7.3)"], rel=1e-6)
    with compiled_programs() as names:
        D.design(D.Residual(7.3), optimizer=adam, **kwargs)
    assert names == []
    lbfgs = D.design(D.Residual(7.3), optimizer=optax.lbfgs(memory_size=40), **{**kwargs, "steps": 40})
    named = D.design(D.Residual(7.3), optimizer="lbfgs", **{**kwargs, "steps": 40})
    np.testing.assert_allclose(lbfgs.law.coefficients, named.law.coefficients, rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="optimizer must be"):
        D.design(D.Residual(7.3), optimizer="sgd", **kwargs)


def test_cap_checks_and_ct_curves_share_the_splines_peak_search():
    """The cap checks read the law's own ``peak_coefficients``, the compiled program its Ct
    curves read: after a check, another spline of the shape compiles nothing for its peaks.
    The caps' excess is the refined Ca and Cj against the caps, and those peaks bound a
    dense NumPy sampling of the spline from above, within 1e-7."""
    from helpers import compiled_programs

    caps = D.Caps(max_ca=7.0, max_jerk=60.0)
    violations = caps.violations(START)
    other = BSplineLaw(jnp.asarray(np.asarray(START.coefficients) * 1.03))
    with compiled_programs() as names:
        peaks = other.peak_coefficients()
    assert names == []
    own = START.peak_coefficients()
    assert violations["Ca"] == own["Ca"] / 7.0 - 1
    assert violations["Cj"] == own["Cj"] / 60.0 - 1
    tau = np.linspace(0.0, 1.0, 400_001)
    for law, found in ((START, own), (other, peaks)):
        _, v, a, j = (np.abs(np.asarray(x)) for x in law.evaluate(tau))
        for key, sampled in (("Cv", v.max()), ("Ca", a.max()), ("Cj", j.max())):
            assert sampled <= found[key] * (1 + 1e-12)
            assert found[key] == pytest.approx(sampled, rel=1e-7)
