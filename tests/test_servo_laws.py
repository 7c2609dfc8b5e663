"""The servo's coefficients of a law (RMS velocity and acceleration, peak power) against
closed forms and scipy at tight tolerance, and their gradients against finite differences."""

import math

import jax
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import minimize_scalar

from camjax import laws

PI = math.pi
CLOSED_FORMS = {  # Ca_rms, Cv_rms, Cva (None: no closed form, checked by scipy below)
    "cycloidal": (PI * math.sqrt(2), math.sqrt(1.5), 3 * math.sqrt(3) * PI / 2),
    "harmonic": (PI**2 / (2 * math.sqrt(2)), PI / (2 * math.sqrt(2)), PI**3 / 8),
    "parabolic": (4.0, math.sqrt(4 / 3), 8.0),
    "poly345": (math.sqrt(120 / 7), math.sqrt(10 / 7), None),
}


def _scipy_reference(law):
    """``(Ca_rms, Cv_rms, Cva)`` by scipy: adaptive quadrature split at the breakpoints,
    and a bounded scalar search of ``|v a|`` around the best of 20001 samples."""
    points = list(law.breakpoints())

    def integral(k):
        f = lambda t: float(law.evaluate(np.array([t]))[k][0]) ** 2  # noqa: E731
        return quad(f, 0.0, 1.0, points=points or None, epsabs=1e-14, epsrel=1e-13, limit=200)[0]

    tau = np.linspace(0.0, 1.0, 20001)
    _, v, a, _ = (np.asarray(x) for x in law.evaluate(tau))
    k = int(np.argmax(np.abs(v * a)))

    def negative_power(t):
        _, v, a, _ = law.evaluate(np.array([t]))
        return -abs(float(v[0]) * float(a[0]))

    best = minimize_scalar(
        negative_power,
        bounds=(tau[max(k - 1, 0)], tau[min(k + 1, tau.size - 1)]),
        method="bounded",
        options={"xatol": 1e-12},
    )
    return math.sqrt(integral(2)), math.sqrt(integral(1)), max(-best.fun, abs(v[k] * a[k]))


@pytest.mark.parametrize("name", list(CLOSED_FORMS))
def test_rms_coefficients_equal_closed_forms(name):
    c = laws.get(name).rms_coefficients()
    ca_rms, cv_rms, cva = CLOSED_FORMS[name]
    assert c["Ca_rms"] == pytest.approx(ca_rms, abs=1e-9)
    assert c["Cv_rms"] == pytest.approx(cv_rms, abs=1e-9)
    if cva is not None:
        assert c["Cva"] == pytest.approx(cva, abs=1e-9)


def test_poly345_peak_power_equals_the_root_of_its_derivative():
    # v a = 1800 t^3 (1-t)^3 (1-2t): its largest value is where the derivative vanishes.
    t = np.polynomial.Polynomial([0, 1])
    power = 1800 * t**3 * (1 - t) ** 3 * (1 - 2 * t)
    roots = power.deriv().roots()
    roots = roots[np.isreal(roots)].real
    expected = max(abs(power(r)) for r in roots if 0 < r < 1)
    assert laws.get("poly345").rms_coefficients()["Cva"] == pytest.approx(expected, abs=1e-9)


@pytest.mark.parametrize("name", [law.name for law in laws.standard_laws()])
def test_rms_coefficients_equal_scipy(name):
    law = laws.get(name)
    c = law.rms_coefficients()
    ca_rms, cv_rms, cva = _scipy_reference(law)
    assert c["Ca_rms"] == pytest.approx(ca_rms, abs=1e-9)
    assert c["Cv_rms"] == pytest.approx(cv_rms, abs=1e-9)
    assert c["Cva"] == pytest.approx(cva, abs=1e-9)


def test_no_standard_law_passes_the_floor_and_the_cubic_meets_it():
    assert laws.RMS_ACCELERATION_FLOOR == pytest.approx(math.sqrt(12.0), abs=1e-15)
    # The cubic 3 t^2 - 2 t^3: a = 6 - 12 t, so int a^2 = 12 (scipy, independently).
    assert math.sqrt(quad(lambda t: (6 - 12 * t) ** 2, 0, 1, epsabs=1e-14)[0]) == pytest.approx(
        laws.RMS_ACCELERATION_FLOOR, abs=1e-12
    )
    for law in laws.named_laws():
        assert law.rms_coefficients()["Ca_rms"] > laws.RMS_ACCELERATION_FLOOR


def test_rms_coefficients_differentiate_like_finite_differences():
    def coefficients(a1):
        law = laws.TripleHarmonic(a1, 1.769)
        return jax.numpy.stack([law.Ca_rms, law.Cv_rms, law.Cva])

    a1, h = 5.1968, 1e-5
    grad = np.asarray(jax.jacfwd(coefficients)(a1))
    fd = (np.asarray(coefficients(a1 + h)) - np.asarray(coefficients(a1 - h))) / (2 * h)
    np.testing.assert_allclose(grad, fd, rtol=1e-6, atol=1e-8)


def test_traced_breakpoints_give_the_same_coefficients():
    law = laws.SCCA(0.3, 0.4, 0.3)
    traced = jax.jit(lambda a, b, c: laws.SCCA(a, b, c).Ca_rms)(0.3, 0.4, 0.3)
    assert float(traced) == pytest.approx(law.rms_coefficients()["Ca_rms"], abs=1e-12)


JERK_CAP = 200.0  # docs/laws.md states it: the least-RMS design is within 5% of the floor here


def test_least_rms_design_is_within_five_percent_of_the_floor():
    from camjax import law_design as D

    result = D.design(D.RmsAcceleration(), caps=D.Caps(max_jerk=JERK_CAP), progress=False)
    law = result.law
    # Independently: adaptive quadrature of a^2 and the jerk on a dense grid.
    points = list(law.breakpoints())
    a_squared = lambda t: float(law.a(np.array([t]))[0]) ** 2  # noqa: E731
    ca_rms = math.sqrt(quad(a_squared, 0, 1, points=points, epsabs=1e-13, limit=400)[0])
    assert result.values[D.RmsAcceleration().label] == pytest.approx(ca_rms, rel=1e-9)
    assert laws.RMS_ACCELERATION_FLOOR < ca_rms <= 1.05 * laws.RMS_ACCELERATION_FLOOR
    assert np.max(np.abs(np.asarray(law.j(np.linspace(0, 1, 20001))))) <= JERK_CAP * (1 + 1e-9)
    # Below every standard law with a finite jerk (the modified sine's 3.909 is the best).
    assert ca_rms < min(
        x.rms_coefficients()["Ca_rms"] for x in laws.standard_laws() if math.isfinite(x.Cj)
    )


def test_laws_command_lists_the_servo_coefficients(capsys, monkeypatch):
    import json

    from camjax.cli import main

    monkeypatch.setenv("CAMJAX_CACHE_DIR", "off")
    assert main(["laws", "--format", "json"]) == 0
    table = json.loads(capsys.readouterr().out)
    assert table["cycloidal"]["Ca_rms"] == pytest.approx(PI * math.sqrt(2), abs=1e-9)
    assert table["poly345"]["Ca_rms"] == pytest.approx(math.sqrt(120 / 7), abs=1e-9)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--n", "3"], "--n: not with --objective rms-acceleration"),
        (["--damping", "0.1"], "--damping: not with --objective rms-acceleration"),
        (["--program", "indexer", "--segment", "1", "--rpm", "100:200"], "not with --program"),
    ],
)
def test_rms_design_refuses_a_period_ratio_in_one_line(
    capsys, monkeypatch, tmp_path, extra, message
):
    from camjax.cli import main

    monkeypatch.setenv("CAMJAX_CACHE_DIR", "off")
    argv = ["design", "--objective", "rms-acceleration", "--out", str(tmp_path / "o"), *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


@pytest.mark.slow
def test_rms_design_command_reports_against_the_floor(capsys, monkeypatch, tmp_path):
    import json

    from camjax.cli import main

    monkeypatch.setenv("CAMJAX_CACHE_DIR", "off")
    out = tmp_path / "rms"
    argv = ["design", "--objective", "rms-acceleration", "--max-jerk", str(JERK_CAP), "--quiet"]
    assert main([*argv, "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    law = laws.load(out / "law.json")
    assert summary["value"] == pytest.approx(law.rms_coefficients()["Ca_rms"], rel=1e-12)
    assert summary["value_over_floor"] == pytest.approx(summary["value"] / math.sqrt(12), rel=1e-12)
    assert 1 < summary["value_over_floor"] <= 1.05
    rows = (out / "comparison.csv").read_text().splitlines()
    assert [r.split(",")[0] for r in rows[1:]] == ["designed", *laws.names()[:7]]


def test_rms_objective_trains_on_the_exact_integral():
    from camjax import law_design as D

    law = laws.BSplineLaw.fit(laws.ModifiedSine(), 16, 5)
    trained = float(D.RmsAcceleration().train(law, 1.0, 8.0))
    assert trained == pytest.approx(law.rms_coefficients()["Ca_rms"], rel=1e-12)
