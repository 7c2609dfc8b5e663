"""The named laws of the trade against closed forms written out here from the sources
(Rothbart's Cam Design Handbook eqs. 4.12 and 4.13, the triple harmonic of MechDesigner and
Pilz, the double harmonic), finite differences, dense NumPy peaks, and scipy quadrature."""

import json
import math

import jax
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq, minimize_scalar

import camjax
from camjax import laws
from camjax.cli import main

PI = math.pi


class TrigLaw:
    """``s = c0 + c1 t + sum_k b_k sin(w_k t + phi_k)`` written out term by term, with its
    derivatives by hand: ``d^m/dt^m sin(w t + phi) = w^m sin(w t + phi + m pi/2)``."""

    def __init__(self, c0, c1, terms):
        self.c0, self.c1, self.terms = c0, c1, terms

    def derivative(self, m):
        def f(t):
            t = np.asarray(t, dtype=float)
            out = sum(b * w**m * np.sin(w * t + phi + m * PI / 2) for b, w, phi in self.terms)
            return out + (self.c0 + self.c1 * t if m == 0 else self.c1 if m == 1 else 0.0)

        return f


def freudenstein_13():
    # s = tau - (1/2pi)[(27/28) sin 2pi tau + (1/84) sin 6pi tau]   (Rothbart eq. 4.12)
    return TrigLaw(0.0, 1.0, [(-27 / 28 / (2 * PI), 2 * PI, 0.0), (-1 / 84 / (2 * PI), 6 * PI, 0.0)])


def freudenstein_135(m):
    # s = tau - (m/2pi)[sin 2pi tau + (1/54) sin 6pi tau + (1/1250) sin 10pi tau]   (eq. 4.13)
    return TrigLaw(0.0, 1.0, [(-m / (2 * PI) * c, w, 0.0)
                              for c, w in ((1.0, 2 * PI), (1 / 54, 6 * PI), (1 / 1250, 10 * PI))])


def solve_freudenstein_m() -> float:
    """``m`` with ``s'(0) = 0``, by brentq on the hand-written derivative."""
    return brentq(lambda m: float(freudenstein_135(m).derivative(1)(0.0)), 0.5, 1.5, xtol=1e-16)


def triple_harmonic(a1, a2):
    """``a = A1 sin 2pi t + A2 sin 4pi t + A3 sin 6pi t`` with ``A3`` from s(1) = 1,
    integrated twice: s = sum A_k/w_k t - A_k/w_k^2 sin(w_k t), w_k = 2 pi k."""
    a3 = 6 * PI * (1 - a1 / (2 * PI) - a2 / (4 * PI))
    amps = {1: a1, 2: a2, 3: a3}
    return TrigLaw(0.0, sum(a / (2 * PI * k) for k, a in amps.items()),
                   [(-a / (2 * PI * k) ** 2, 2 * PI * k, 0.0) for k, a in amps.items()])


def double_harmonic():
    # s = [(1 - cos pi t) - (1 - cos 2pi t)/4]/2 = 3/8 - cos(pi t)/2 + cos(2 pi t)/8
    return TrigLaw(3 / 8, 0.0, [(-0.5, PI, PI / 2), (1 / 8, 2 * PI, PI / 2)])


REFERENCES = {  # name: (closed form, v(1), a(1))
    "freudenstein-1-3": (freudenstein_13(), 0.0, 0.0),
    "freudenstein-1-3-5": (freudenstein_135(solve_freudenstein_m()), 0.0, 0.0),
    "triple-harmonic-modified-sine": (triple_harmonic(5.1968, 1.769), 0.0, 0.0),
    "triple-harmonic-zero-jerk": (triple_harmonic(9 * PI / 4, 0.0), 0.0, 0.0),
    "triple-harmonic:6.5,-1.25": (triple_harmonic(6.5, -1.25), 0.0, 0.0),
    "double-harmonic": (double_harmonic(), 0.0, -PI**2),
}


def dense_peak(f) -> float:
    """``max |f|`` on [0, 1]: 20001 samples, the best crests polished by scipy."""
    t = np.linspace(0, 1, 20001)
    values = np.abs(f(t))
    best = values.max()
    for k in np.argsort(values)[-40:]:
        lo, hi = t[max(k - 1, 0)], t[min(k + 1, t.size - 1)]
        r = minimize_scalar(lambda x: -abs(f(np.array(x))), bounds=(lo, hi), method="bounded",
                            options={"xatol": 1e-12})
        best = max(best, -r.fun)
    return float(best)


@pytest.mark.parametrize("name", list(REFERENCES))
def test_named_law_matches_its_closed_form(name):
    reference, v1, a1 = REFERENCES[name]
    law = laws.get(name)
    assert laws.get(law.name) == law  # the name rebuilds it
    t = np.linspace(0.0, 1.0, 401)
    s, v, a, j = (np.asarray(x) for x in law.evaluate(t))
    for m, x in enumerate((s, v, a, j)):
        np.testing.assert_allclose(x, reference.derivative(m)(t), rtol=0, atol=1e-12 * 10**m)
    assert s[0] == 0.0 and s[-1] == pytest.approx(1.0, abs=1e-14)
    assert abs(v[0]) < 1e-14 and abs(a[0]) < 1e-12
    assert v[-1] == pytest.approx(v1, abs=1e-13) and a[-1] == pytest.approx(a1, abs=1e-12)
    # v, a, j against central differences of the law's own s, v, a.
    inner = np.linspace(0.01, 0.99, 97)
    h = 1e-5
    for lower, higher, scale in ((0, 1, 2.0), (1, 2, 10.0), (2, 3, 100.0)):
        f = (np.asarray(law.evaluate(inner + h)[lower]) - np.asarray(law.evaluate(inner - h)[lower])) / (2 * h)
        np.testing.assert_allclose(np.asarray(law.evaluate(inner)[higher]), f, rtol=0, atol=1e-6 * scale)
    # Cv, Ca, Cj against dense peaks of the closed form's derivatives.
    peaks = law.peak_coefficients()
    for order, key in ((1, "Cv"), (2, "Ca"), (3, "Cj")):
        assert peaks[key] == pytest.approx(dense_peak(reference.derivative(order)), rel=1e-9), key


def test_freudenstein_1_3_5_m_closes_the_velocity():
    m = solve_freudenstein_m()
    assert m == pytest.approx(1 / (1 + 1 / 18 + 1 / 250), rel=1e-12)
    law = laws.get("freudenstein-1-3-5")
    assert abs(float(law.v(0.0))) < 1e-14 and float(law.s(1.0)) == pytest.approx(1.0, abs=1e-14)


def test_triple_harmonic_presets_close_and_the_zero_jerk_one_has_zero_end_jerk():
    for name, (a1, a2) in {"triple-harmonic-modified-sine": (5.1968, 1.769),
                           "triple-harmonic-zero-jerk": (9 * PI / 4, 0.0)}.items():
        a3 = 6 * PI * (1 - a1 / (2 * PI) - a2 / (4 * PI))
        assert a1 / (2 * PI) + a2 / (4 * PI) + a3 / (6 * PI) == pytest.approx(1.0, abs=1e-15)
        end_jerk = 2 * PI * (a1 + 2 * a2 + 3 * a3)
        law = laws.get(name)
        assert float(law.j(0.0)) == pytest.approx(end_jerk, abs=1e-12)
        assert float(law.j(1.0)) == pytest.approx(end_jerk, abs=1e-12)
        if name.endswith("zero-jerk"):
            assert a3 == pytest.approx(-3 * PI / 4, abs=1e-14) and abs(end_jerk) < 1e-12
            assert law.peak_coefficients()["Ca"] == pytest.approx(3 * PI, rel=1e-12)
        else:  # a jerk step at both ends, as the modified sine's own
            assert end_jerk == pytest.approx(66.2987, abs=1e-4)
    assert laws.get("triple-harmonic:5.1968,1.769").name == "triple-harmonic-modified-sine"
    with pytest.raises(ValueError, match="two amplitudes"):
        laws.get("triple-harmonic:1")


@pytest.mark.parametrize("member, fractions", [("modified-trapezoid", (0.25, 0.5, 0.25)),
                                               ("modified-sine", (0.25, 0.0, 0.75)),
                                               ("cycloidal", (0.5, 0.0, 0.5))])
def test_constant_velocity_variants_are_scca_with_a_zero_part(member, fractions):
    P = 0.3
    law = laws.get(f"{member}-cv:{P}")
    scaled = laws.SCCA(*((1 - P) * x for x in fractions))
    t = np.linspace(0, 1, 1001)
    np.testing.assert_array_equal(np.asarray(law.s(t)), np.asarray(scaled.s(t)))
    # An SCCA law by its fractions; its name prints them without float noise (0.525, not
    # 0.5249999999999999), so the law it names back agrees to rounding, not to the last bit.
    assert law.name == scaled.name
    np.testing.assert_allclose(np.asarray(laws.get(law.name).fractions), np.asarray(law.fractions), rtol=4e-15)
    # The middle P of the rise runs at constant velocity Cv with zero acceleration.
    middle = np.linspace(0.5 - P / 2 + 1e-9, 0.5 + P / 2 - 1e-9, 51)
    assert np.max(np.abs(np.asarray(law.a(middle)))) < 1e-12
    np.testing.assert_allclose(np.asarray(law.v(middle)), float(law.Cv), rtol=1e-13)
    with pytest.raises(ValueError, match=r"in \[0, 1\)"):
        laws.get(f"{member}-cv:1")


def modified_sine_acceleration(t):
    """Modified sine, written out: sine ramp to A over [0, 1/8], one cosine over [1/8, 7/8]
    down to -A, sine ramp back over [7/8, 1]; A = 4 pi^2/(pi + 4)."""
    A = 4 * PI**2 / (PI + 4)
    return np.where(t < 1 / 8, A * np.sin(4 * PI * t),
                    np.where(t < 7 / 8, A * np.cos(4 * PI / 3 * (t - 1 / 8)), -A * np.sin(4 * PI * (1 - t))))


@pytest.mark.parametrize("L", [0.35, 0.6])
def test_asymmetric_modified_sine_closes_and_keeps_v_and_a_continuous(L):
    def acc(t):
        t = np.asarray(t, dtype=float)
        return np.where(t <= L, modified_sine_acceleration(t / (2 * L)) / (2 * L),
                        modified_sine_acceleration(1 - (1 - t) / (2 * (1 - L))) / (2 * (1 - L)))

    # The construction closes: v(1) = int a = 0 and s(1) = int (1 - u) a(u) du = 1.
    opts = dict(points=[L, L / 4, 1 - (1 - L) / 4], epsabs=1e-13, epsrel=1e-13, limit=200)
    assert quad(acc, 0, 1, **opts)[0] == pytest.approx(0.0, abs=1e-12)
    assert quad(lambda u: (1 - u) * acc(u), 0, 1, **opts)[0] == pytest.approx(1.0, abs=1e-12)
    law = laws.get(f"modified-sine-asym:{L}")
    t = np.linspace(0, 1, 301)
    np.testing.assert_allclose(np.asarray(law.a(t)), acc(t), rtol=0, atol=1e-12)
    for x in (0.2, L, 0.9):
        v_ref = quad(acc, 0, x, points=[p for p in opts["points"] if p < x] or None, epsabs=1e-13)[0]
        assert float(law.v(x)) == pytest.approx(v_ref, abs=1e-11)
    assert float(law.s(L)) == pytest.approx(L, abs=1e-14)
    eps = 1e-9
    _, v, a, _ = (np.asarray(x) for x in law.evaluate(np.array([L - eps, L + eps])))
    assert abs(v[1] - v[0]) < 1e-8 and abs(a[1] - a[0]) < 1e-6
    # Peaks: Cv the symmetric law's (at L), Ca and Cj dense over the written-out pulses.
    peaks = law.peak_coefficients()
    assert peaks["Cv"] == pytest.approx(quad(acc, 0, L, points=[L / 4], epsabs=1e-14)[0], rel=1e-10)
    assert peaks["Ca"] == pytest.approx(dense_peak(acc), rel=1e-9)
    jerk = lambda t: np.gradient(acc(t), t)  # noqa: E731 - a dense numerical jerk
    dense = np.linspace(0, 1, 400001)
    assert peaks["Cj"] == pytest.approx(np.max(np.abs(jerk(dense))), rel=1e-4)
    assert peaks["Ca"] == pytest.approx(4 * PI**2 / (PI + 4) / (2 * min(L, 1 - L)), rel=1e-12)
    assert sorted(law.breakpoints()) == sorted({L / 4, L, 1 - (1 - L) / 4})


def test_asymmetric_law_at_one_half_is_the_symmetric_law():
    t = np.linspace(0, 1, 201)
    for name in ("cycloidal", "modified-trapezoid", "poly345"):
        law = laws.get(f"{name}-asym:0.5")
        np.testing.assert_allclose(np.asarray(law.s(t)), np.asarray(laws.get(name).s(t)), atol=1e-15)
    with pytest.raises(ValueError, match=r"in \(0, 1\)"):
        laws.get("cycloidal-asym:1.2")


def test_names_print_without_float_noise():
    assert laws.get("polynomial7:-5.499999999999999,0,0,0,0,0").name == "polynomial7:-5.5,0,0,0,0,0"
    third = laws.BoundaryPolynomial(v0=1 / 3, degree=5)
    assert laws.get(third.name) == third  # a value %.12g would round keeps its digits
    assert laws.SCCA(0.3, 0.2, 0.4).name == "scca:0.3,0.2,0.4"


def residual_by_quad(acc, ca, n):
    """``R(n) = w |int_0^1 a(u) e^(-i w u) du| / Ca``, ``w = 2 pi n``, by scipy."""
    w = 2 * PI * n
    opts = dict(epsabs=1e-13, epsrel=1e-13, limit=400)
    re = quad(lambda u: acc(u) * math.cos(w * u), 0, 1, **opts)[0]
    im = quad(lambda u: acc(u) * math.sin(w * u), 0, 1, **opts)[0]
    return w * math.hypot(re, im) / ca


def test_residual_through_the_engine_matches_the_closed_form():
    ratios = [1.7, 3.3, 4.0, 5.5]
    acc = freudenstein_13().derivative(2)
    curve = camjax.ct_curve("freudenstein-1-3", ratios)
    ca = laws.get("freudenstein-1-3").peak_coefficients()["Ca"]
    for n, r in zip(ratios, curve.residual):
        assert r == pytest.approx(residual_by_quad(lambda u: float(acc(u)), ca, n), abs=1e-8)
    # A sine series of K harmonics leaves no residual vibration at any integer n > K.
    assert curve.residual[2] < 1e-9


@pytest.mark.parametrize("name, zeros", [("freudenstein-1-3", (2, 4, 5, 6, 7, 8)),
                                         ("freudenstein-1-3-5", (2, 4, 6, 7, 8))])
def test_freudenstein_residual_is_zero_at_the_integers_docs_laws_names(name, zeros):
    """docs/laws.md: at an integer n the residual is pi n |A_n| / Ca (the series' harmonic at
    w = 2 pi n, zero past its last harmonic K): zero at 2 and from K + 1 on, not at the odd
    k <= K (1-3-5 at 5: 0.2 pi^2 m / Ca = 0.368).  Checked by scipy and by ct_curve."""
    m = solve_freudenstein_m()
    hand = freudenstein_13() if name == "freudenstein-1-3" else freudenstein_135(m)
    acc = hand.derivative(2)
    ca = laws.get(name).peak_coefficients()["Ca"]
    ratios = np.arange(1.0, 9.0)
    curve = camjax.ct_curve(name, ratios, damping=0.0)
    for n, r in zip(ratios, curve.residual):
        reference = residual_by_quad(lambda u: float(acc(u)), ca, n)
        assert r == pytest.approx(reference, abs=1e-8)
        if int(n) in zeros:
            assert reference < 1e-9
        else:
            assert reference > 0.3
    if name == "freudenstein-1-3-5":
        assert curve.residual[4] == pytest.approx(0.2 * PI**2 * m / ca, rel=1e-8)  # 0.368 at n = 5
        assert curve.residual[4] == pytest.approx(0.368, abs=5e-4)


def test_gradient_in_a_triple_harmonic_amplitude_matches_finite_differences():
    n = 2.6

    @jax.jit
    def residual(a1):
        return camjax.residual_vibration(laws.TripleHarmonic(a1, 1.0), n, resolution=512)

    g = float(jax.grad(residual)(6.0))
    h = 1e-5
    fd = (float(residual(6.0 + h)) - float(residual(6.0 - h))) / (2 * h)
    assert np.isfinite(g) and g == pytest.approx(fd, rel=1e-5)


def test_laws_command_lists_the_named_laws(capsys):
    code = main(["laws", "--format", "json"])
    table = json.loads(capsys.readouterr().out)
    assert code == 0 and list(table) == laws.names()
    assert {"freudenstein-1-3", "freudenstein-1-3-5", "triple-harmonic-zero-jerk"} <= set(table)
    assert table["freudenstein-1-3"]["Ca"] == pytest.approx(laws.get("freudenstein-1-3").Ca, rel=1e-12)


PROGRAM = """
[program]
name = "named"
[[segment]]
angle_deg = 30
[[segment]]          # rest to reversal
law = "double-harmonic"
lift_mm = 10
angle_deg = 120
[[segment]]          # turn back at once, from the reversal's state to rest
law = "polynomial"
degree = 5
lift_mm = -10
angle_deg = 120
start = "match"
end = "match"
[[segment]]
angle_deg = 30
[[segment]]
law = "LAW"
lift_mm = 5
angle_deg = 30
[[segment]]
law = "cycloidal"
lift_mm = -5
angle_deg = 30
[follower]
kind = "translating-roller"
mass_kg = 1.5
stiffness_n_per_mm = 2000
damping_ratio = 0.05
spring_rate_n_per_mm = 10
preload_n = 300
base_radius_mm = 40
roller_radius_mm = 12
"""


def test_a_program_takes_the_named_laws_and_turns_back_from_the_double_harmonic(tmp_path):
    from camjax.program import Program

    for law in ("freudenstein-1-3-5", "modified-sine-asym:0.4", "triple-harmonic:6,1"):
        path = tmp_path / "p.toml"
        path.write_text(PROGRAM.replace("LAW", law))
        program = Program.load(path)
        assert program.segments[4].law.name == laws.get(law).name
        # A U join (v = 0) with the acceleration continuous: -pi^2 h / beta^2 on both sides.
        top = program.joins()[1]
        assert (top.before, top.after, top.velocity_mm_per_deg) == (2, 3, 0.0)
        assert top.state == "U" and top.continuity == "C2"
        assert top.acceleration_before_mm_per_deg2 == pytest.approx(-PI**2 * 10 / 120**2, rel=1e-12)
