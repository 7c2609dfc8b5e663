"""Input shapers as laws and laws robust to the frequency: the shapers' closed forms and
published 5% bands, the shaped laws' exact derivatives, the percentage vibration against an
independent simulation, and a designed law of no added duration holding 5% over +/-20%."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from camjax import law_design as D
from camjax import laws


@pytest.mark.parametrize("damping", [0.0, 0.1, 0.3])
def test_zv_and_zvd_cancel_the_design_frequency(damping):
    K = math.exp(-damping * math.pi / math.sqrt(1 - damping**2))
    zv, zvd = laws.Shaper("zv", damping), laws.Shaper("zvd", damping)
    np.testing.assert_allclose(zv.amplitudes, [1 / (1 + K), K / (1 + K)], rtol=1e-15)
    np.testing.assert_allclose(
        zvd.amplitudes, np.array([1, 2 * K, K * K]) / (1 + K) ** 2, rtol=1e-15
    )
    assert zv.vibration(np.array([1.0]))[0] < 1e-15
    assert zvd.vibration(np.array([1.0]))[0] < 1e-15
    # ZVD: the derivative in the frequency vanishes there too (central difference).
    h = 1e-5
    assert (
        abs(zvd.vibration(np.array([1 + h]))[0] - zvd.vibration(np.array([1 - h]))[0]) / (2 * h)
        < 1e-8
    )
    # A unit step (one impulse) leaves V = 1: the reference the percentage is of.
    assert zv.vibration(np.array([1e-9]))[0] == pytest.approx(1.0, abs=1e-6)


def test_ei_holds_vtol_at_the_design_frequency_with_zero_slope():
    ei = laws.Shaper("ei", vtol=0.05)
    np.testing.assert_allclose(ei.amplitudes, [1.05 / 4, 0.95 / 2, 1.05 / 4], rtol=1e-15)
    assert ei.vibration(np.array([1.0]))[0] == pytest.approx(0.05, abs=1e-15)
    h = 1e-5
    assert abs(ei.vibration(np.array([1 + h]))[0] - ei.vibration(np.array([1 - h]))[0]) < 1e-9


# Undamped, V <= 5%: |cos(pi r / 2)| for ZV, cos^2 for ZVD, |(1-V)/2 + (1+V)/2 cos(pi r)| for EI.
EXACT_BANDS = {
    "zv": 2 / math.pi * math.asin(0.05),
    "zvd": 2 / math.pi * math.asin(math.sqrt(0.05)),
    "ei": 1 - math.acos((3 * 0.05 - 1) / (1 + 0.05)) / math.pi,
}
PUBLISHED = {"zv": 0.032, "zvd": 0.144, "ei": 0.20}


@pytest.mark.parametrize("kind", laws.SHAPERS)
def test_undamped_bands_reproduce_the_published_ones(kind):
    lo, hi = D.vibration_band(laws.Shaper(kind).vibration, 0.05)
    assert 1 - lo == pytest.approx(EXACT_BANDS[kind], abs=1e-9)
    assert hi - 1 == pytest.approx(EXACT_BANDS[kind], abs=1e-9)
    assert abs((hi - 1) - PUBLISHED[kind]) <= 0.002  # 0.2 percentage points


def test_shaped_law_is_the_sum_of_shifted_scaled_copies():
    base, n0 = laws.ModifiedSine(), 1.5
    law = laws.ShapedLaw(base, laws.Shaper("zvd", 0.1), n0)
    damped_period = 1 / (n0 * math.sqrt(1 - 0.01))
    assert law.stretch == pytest.approx(1 + damped_period, rel=1e-15)  # one damped period longer
    tau = np.linspace(0.0, 1.0, 4001)
    s, v, a, j = (np.asarray(x) for x in law.evaluate(tau))
    u = law.stretch * tau
    amplitudes, shifts = law.shaper.amplitudes, np.array([0, 0.5, 1.0]) * damped_period
    expected = sum(A * np.asarray(base.s(u - t)) for A, t in zip(amplitudes, shifts))
    np.testing.assert_allclose(s, expected, atol=1e-14)
    assert s[0] == 0 and s[-1] == pytest.approx(1.0, abs=1e-15)
    # Derivatives against central differences of the one below (away from jerk steps).
    h = 1e-6
    for low, high in ((0, 1), (1, 2), (2, 3)):
        up = np.asarray(law.evaluate(tau[1:-1] + h)[low])
        down = np.asarray(law.evaluate(tau[1:-1] - h)[low])
        fd = (up - down) / (2 * h)
        exact = (s, v, a, j)[high][1:-1]
        smooth = np.abs(fd - exact) < 1e-3 * max(1.0, np.abs(exact).max())
        assert smooth.mean() > 0.99
    assert laws.get(law.name).name == law.name


@pytest.mark.parametrize("n", [0.5, 1.5, 2.5, 3.3])
def test_percentage_vibration_of_the_cycloidal_is_its_closed_form(n):
    expected = abs(math.sin(math.pi * n) / (math.pi * n * (1 - n * n)))
    assert float(D.percentage_vibration(laws.Cycloidal(), [n])[0]) == pytest.approx(
        expected, abs=1e-12
    )


@pytest.mark.parametrize(("name", "n", "zeta"), [("cycloidal", 1.3, 0.1), ("poly345", 0.8, 0.25)])
def test_percentage_vibration_equals_a_simulation(name, n, zeta):
    # e'' + 2 zeta w e' + w^2 e = -a(t): the payload's deviation; at t = 1 its envelope over a
    # unit step's applied then (1 / sqrt(1 - zeta^2)).
    law = laws.get(name)
    w = 2 * math.pi * n
    wd = w * math.sqrt(1 - zeta**2)

    def rhs(t, y):
        return [y[1], -float(law.a(np.array([t]))[0]) - 2 * zeta * w * y[1] - w * w * y[0]]

    e, de = solve_ivp(
        rhs,
        (0, 1),
        [0.0, 0.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-14,
        first_step=1e-4,
        max_step=1e-2,
    ).y[:, -1]
    envelope = math.hypot(e, (de + zeta * w * e) / wd)
    expected = envelope * math.sqrt(1 - zeta**2)
    assert float(D.percentage_vibration(law, [n], zeta)[0]) == pytest.approx(expected, rel=1e-8)


def test_shaped_vibration_is_the_base_times_the_shaper():
    n0, zeta = 1.5, 0.1
    shaper = laws.Shaper("zv", zeta)
    law = laws.ShapedLaw(laws.Cycloidal(), shaper, n0)
    r = np.array([0.7, 0.93, 1.0, 1.1, 1.4])
    shaped = np.asarray(D.percentage_vibration(law, law.stretch * n0 * r, zeta))
    product = np.asarray(D.percentage_vibration(laws.Cycloidal(), n0 * r, zeta)) * shaper.vibration(
        r
    )
    np.testing.assert_allclose(shaped, product, atol=1e-13)


def test_designed_law_holds_five_percent_over_twenty_percent_with_no_added_duration():
    n0, zeta = 1.75, 0.1
    result = D.design(
        D.MaxResidual(0.8 * n0, 1.2 * n0, damping=zeta), caps=D.Caps(8.0, 150.0), progress=False
    )
    r = np.linspace(0.8, 1.2, 2001)
    v = np.asarray(D.percentage_vibration(result.law, n0 * r, zeta))
    assert v.max() <= 0.05
    lo, hi = D.vibration_band(
        lambda x: np.asarray(D.percentage_vibration(result.law, n0 * np.asarray(x), zeta))
    )
    assert lo <= 0.8 and hi >= 1.2
    # The cycloidal of the same duration does not (its V reaches 15% in the band).
    assert np.asarray(D.percentage_vibration(laws.Cycloidal(), n0 * r, zeta)).max() > 0.05


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: laws.Shaper("zvdd"), "shaper must be one of zv, zvd, ei"),
        (lambda: laws.Shaper("ei", 0.1), "only the undamped closed form"),
        (lambda: laws.Shaper("zv", 1.0), "damping ratio must be in [0, 1)"),
        (
            lambda: laws.ShapedLaw(laws.Cycloidal(), laws.Shaper("zv"), 0.0),
            "period ratio must be positive",
        ),
        (lambda: laws.get("zv-cycloidal:2"), "zv-cycloidal:N,ZETA takes 2 numbers"),
        (lambda: laws.get("zv-nolaw:2,0"), "takes a law of"),
        (lambda: D.vibration_band(laws.Shaper("zv").vibration, 1.5), "limit must be in (0, 1)"),
        (lambda: D.vibration_band(lambda r: np.ones_like(r)), "above the limit"),
    ],
)
def test_bad_input_is_one_line(make, message):
    with pytest.raises(ValueError, match=None) as error:
        make()
    assert message in str(error.value) and "\n" not in str(error.value)


def test_shaped_law_traces_and_differentiates_through_its_base():
    import jax

    def ca_rms(b):
        return laws.ShapedLaw(laws.SCCA(0.25, b, 0.25), laws.Shaper("zv", 0.1), 1.75).Ca_rms

    concrete = laws.ShapedLaw(laws.SCCA(0.25, 0.4, 0.25), laws.Shaper("zv", 0.1), 1.75)
    assert float(jax.jit(ca_rms)(0.4)) == pytest.approx(
        concrete.rms_coefficients()["Ca_rms"], abs=1e-12
    )
    h = 1e-6
    fd = (float(ca_rms(0.4 + h)) - float(ca_rms(0.4 - h))) / (2 * h)
    assert float(jax.grad(ca_rms)(0.4)) == pytest.approx(fd, rel=1e-6)
