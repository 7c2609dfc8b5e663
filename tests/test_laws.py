"""Motion laws against independent references: MISSION.md coefficients, textbook
acceleration shapes integrated by scipy, autodiff, and property tests."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from camjax import laws

PI = math.pi
KNOWN = {  # MISSION.md: Cv, Ca, Cj (None: not listed)
    "cycloidal": (2.0, 2 * PI, 4 * PI**2),
    "modified-sine": (1.7596, 4 * PI**2 / (PI + 4), None),
    "modified-trapezoid": (2.0, 8 * PI / (PI + 2), None),
    "harmonic": (PI / 2, PI**2 / 2, math.inf),
    "parabolic": (2.0, 4.0, math.inf),
    "poly345": (1.875, 5.7735, 60.0),
    "poly4567": (2.1875, 7.5132, 52.5),
}


@pytest.mark.parametrize("name", list(KNOWN))
def test_coefficients_match_mission(name):
    law = laws.get(name)
    cv, ca, cj = KNOWN[name]
    c = law.peak_coefficients()
    assert c["Cv"] == pytest.approx(cv, abs=1e-4)
    assert c["Ca"] == pytest.approx(ca, abs=1e-4)
    if cj is not None:
        assert c["Cj"] == pytest.approx(cj, rel=1e-9) if math.isfinite(cj) else c["Cj"] == cj


@pytest.mark.parametrize("name", list(KNOWN))
def test_coefficients_match_dense_sampling(name):
    law = laws.get(name)
    tau = np.linspace(0, 1, 200001)
    c = law.peak_coefficients()
    assert float(jnp.max(jnp.abs(law.v(tau)))) == pytest.approx(c["Cv"], rel=1e-9)
    assert float(jnp.max(jnp.abs(law.a(tau)))) == pytest.approx(c["Ca"], rel=1e-9)
    if math.isfinite(c["Cj"]):
        assert float(jnp.max(jnp.abs(law.j(tau)))) == pytest.approx(c["Cj"], rel=1e-6)


def _textbook_acceleration(name):
    """Acceleration shapes as the textbooks define them, written independently of SCCA."""
    if name == "modified-sine":
        A = 4 * PI**2 / (PI + 4)

        def acc(t):
            if t <= 1 / 8:
                return A * math.sin(4 * PI * t)
            if t <= 7 / 8:
                return A * math.cos(4 * PI * (t - 1 / 8) / 3)
            return A * math.sin(4 * PI * t)

        return acc
    if name == "modified-trapezoid":
        A = 8 * PI / (PI + 2)

        def acc(t):
            if t <= 1 / 8 or t >= 7 / 8:
                return A * math.sin(4 * PI * t)
            if t <= 3 / 8:
                return A
            if t <= 5 / 8:
                return A * math.cos(4 * PI * (t - 3 / 8))
            return -A

        return acc
    if name == "cycloidal":
        return lambda t: 2 * PI * math.sin(2 * PI * t)
    if name == "harmonic":
        return lambda t: PI**2 / 2 * math.cos(PI * t)
    if name == "parabolic":
        return lambda t: 4.0 if t < 0.5 else -4.0
    raise KeyError(name)


@pytest.mark.parametrize(
    "name", ["modified-sine", "modified-trapezoid", "cycloidal", "harmonic", "parabolic"]
)
def test_scca_members_match_textbook_shapes(name):
    acc = _textbook_acceleration(name)
    law = laws.get(name)
    breaks = [1 / 8, 3 / 8, 1 / 2, 5 / 8, 7 / 8]
    for t in [0.05, 0.2, 0.37, 0.49, 0.61, 0.8, 0.93, 1.0]:
        pts = [b for b in breaks if b < t]
        v = quad(acc, 0, t, points=pts or None, epsabs=1e-13, epsrel=1e-13)[0]
        s = quad(lambda u: quad(acc, 0, u, points=[b for b in breaks if b < u] or None,
                                epsabs=1e-13, epsrel=1e-13)[0], 0, t, points=pts or None,
                 epsabs=1e-12, epsrel=1e-12)[0]
        assert float(law.a(t)) == pytest.approx(acc(t), abs=1e-12)
        assert float(law.v(t)) == pytest.approx(v, abs=1e-11)
        assert float(law.s(t)) == pytest.approx(s, abs=1e-10)


@pytest.mark.parametrize("name", ["modified-sine", "modified-trapezoid", "cycloidal",
                                  "harmonic", "parabolic"])
def test_general_scca_equals_named_member(name):
    named = laws.get(name)
    general = laws.SCCA(*(jnp.asarray(x) for x in named.fractions))
    tau = jnp.linspace(0, 1, 1001)
    for f, g in zip(named.evaluate(tau), general.evaluate(tau)):
        np.testing.assert_allclose(f, g, rtol=0, atol=1e-13)
    assert float(general.Ca) == pytest.approx(float(named.Ca), rel=1e-15)


@pytest.mark.parametrize("name", list(KNOWN))
def test_closed_form_derivatives_match_autodiff(name):
    law = laws.get(name)
    tau = jnp.linspace(0.013, 0.987, 211)
    for lower, upper in ((law.s, law.v), (law.v, law.a), (law.a, law.j)):
        np.testing.assert_allclose(jax.vmap(jax.grad(lower))(tau), upper(tau), atol=2e-11,
                                   rtol=1e-12)


def test_outside_the_rise_is_a_dwell():
    law = laws.ModifiedSine()
    s, v, a, j = law.evaluate(jnp.array([-0.5, 1.5]))
    np.testing.assert_array_equal(s, [0.0, 1.0])
    for x in (v, a, j):
        np.testing.assert_array_equal(x, [0.0, 0.0])


fractions = st.tuples(*(st.floats(0, 1) for _ in range(3))).filter(lambda f: 0.05 < sum(f) <= 1)


@settings(max_examples=40, deadline=None)
@given(fractions)
@example((1e-12, 0.0, 0.5))  # a sine ramp narrower than the breakpoints' merging distance
def test_scca_invariants(f):
    law = laws.SCCA(*f)
    tau = jnp.linspace(0, 1, 401)
    s, v, a, _ = law.evaluate(tau)
    assert float(law.s(0.0)) == pytest.approx(0.0, abs=1e-14)
    assert float(law.s(1.0)) == pytest.approx(1.0, abs=1e-12)
    assert float(law.v(0.0)) == pytest.approx(0.0, abs=1e-12)
    assert float(law.v(1.0)) == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(s + s[::-1], 1.0, atol=1e-12)  # point symmetry
    assert bool(jnp.all(v >= -1e-12))  # monotone rise
    # The peak |a| = Ca is reached at a breakpoint (the end of the sine ramp, the start of
    # the cosine fall, or tau = 0), perhaps only as a one-sided limit where the acceleration
    # steps; a uniform sample misses it when the plateau is narrow.  The pieces' own edges:
    # ``breakpoints()`` merges an edge within 1e-12 of another (a sine ramp of 1e-12).
    a_, b_, c_ = f
    half = (a_ / 2, (a_ + b_) / 2, (a_ + b_ + c_) / 2)
    edges = jnp.asarray([0.0, *half, 0.5, *(1 - x for x in half), 1.0])
    at_breaks = jnp.abs(law.a(jnp.concatenate([edges - 1e-13, edges, edges + 1e-13])))
    assert float(jnp.max(jnp.abs(a))) <= float(law.Ca) * (1 + 1e-12)
    assert float(jnp.max(at_breaks)) == pytest.approx(float(law.Ca), rel=1e-9)


@settings(max_examples=12, deadline=None)
@given(st.lists(st.floats(-2, 3), min_size=6, max_size=6), st.booleans(),
       st.sampled_from([3, 4, 5, 7]))
def test_bspline_boundary_conditions_hold_for_any_coefficients(coefs, zero_jerk, degree):
    law = laws.BSplineLaw(jnp.asarray(coefs), degree=degree, zero_jerk=zero_jerk)
    s, v, a, j = law.evaluate(jnp.array([0.0, 1.0]))
    np.testing.assert_allclose(s, [0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(v, [0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(a, [0.0, 0.0], atol=1e-7)
    if zero_jerk and degree >= 4:
        np.testing.assert_allclose(j, [0.0, 0.0], atol=1e-5)


def test_bspline_derivatives_and_peaks():
    law = laws.BSplineLaw.fit(laws.Cycloidal(), 14)
    tau = jnp.linspace(0.01, 0.99, 157)
    np.testing.assert_allclose(jax.vmap(jax.grad(law.s))(tau), law.v(tau), atol=1e-10)
    np.testing.assert_allclose(jax.vmap(jax.grad(law.a))(tau), law.j(tau), atol=1e-8)
    dense = jnp.linspace(0, 1, 100001)
    assert float(law.Ca) == pytest.approx(float(jnp.max(jnp.abs(law.a(dense)))), rel=1e-9)
    assert float(law.Cj) == pytest.approx(float(jnp.max(jnp.abs(law.j(dense)))), rel=1e-6)
    # A least-squares fit of the cycloidal law is close to it.
    assert float(jnp.max(jnp.abs(law.s(tau) - laws.Cycloidal().s(tau)))) < 1e-4


def test_polynomial_family():
    np.testing.assert_allclose(laws.PolynomialLaw(3)._coefficients(0), [0, 0, 0, 10, -15, 6],
                               atol=1e-12)
    np.testing.assert_allclose(laws.PolynomialLaw(4)._coefficients(0),
                               [0, 0, 0, 0, 35, -84, 70, -20], atol=1e-10)
    assert laws.PolynomialLaw(5).name == "poly56789"
    assert laws.get("poly:5").name == "poly56789"


def test_registry_names_and_aliases():
    for name in laws.names():
        assert laws.get(name).name == name
    assert laws.get("modsine").name == "modified-sine"
    assert laws.get("ModTrap").name == "modified-trapezoid"
    assert laws.get("SHM").name == "harmonic"
    assert float(laws.get("scca:0.25,0.5,0.25").Ca) == pytest.approx(8 * PI / (PI + 2))


@pytest.mark.parametrize(
    "build, message",
    [
        (lambda: laws.get("nope"), "unknown law 'nope'; valid names: cycloidal"),
        (lambda: laws.SCCA(-0.1, 0.5, 0.5), "non-negative"),
        (lambda: laws.SCCA(0.5, 0.5, 0.5), "a + b + c <= 1"),
        (lambda: laws.SCCA(0.0, 0.0, 0.0), "0 < a + b + c"),
        (lambda: laws.SCCA(float("nan"), 0.5, 0.5), "finite"),
        (lambda: laws.get("scca:0.1,0.2"), "scca:A,B,C takes 3 numbers"),
        (lambda: laws.get("scca:x,y,z"), "A must be a number"),
        (lambda: laws.PolynomialLaw(1), "order must be"),
        (lambda: laws.BSplineLaw(jnp.array([0.5, jnp.nan])), "finite"),
        (lambda: laws.BSplineLaw(jnp.zeros(3), degree=2), "degree must be"),
    ],
)
def test_bad_parameters_raise_clear_errors(build, message):
    with pytest.raises(ValueError, match=message.replace("+", r"\+")):
        build()


def test_scca_gradients_match_finite_differences():
    def peak_and_value(f):
        law = laws.SCCA(f[0], f[1], f[2])
        return law.Ca + law.Cv + law.s(0.37) + law.a(0.62)  # away from breakpoints

    f0 = jnp.array([0.3, 0.3, 0.3])
    grad = jax.grad(peak_and_value)(f0)
    for i in range(3):
        e = jnp.zeros(3).at[i].set(1e-6)
        fd = (peak_and_value(f0 + e) - peak_and_value(f0 - e)) / 2e-6
        assert float(grad[i]) == pytest.approx(float(fd), rel=1e-6, abs=1e-8)



def test_scca_keeps_plain_numbers_on_the_host():
    """Plain numbers give NumPy float leaves (building, checking and naming a law wait on no
    device); JAX input stays JAX.  Both name and value the law alike."""
    host = laws.SCCA(0, 1, 0)  # integers: stored as floats all the same
    device = laws.SCCA(*map(jnp.asarray, (0.0, 1.0, 0.0)))
    assert all(isinstance(x, np.ndarray) and x.dtype == np.float64 for x in host.fractions)
    assert all(isinstance(x, jax.Array) and x.dtype == jnp.float64 for x in device.fractions)
    assert host.name == device.name == "parabolic"
    assert float(host.Ca) == float(device.Ca) == pytest.approx(4.0, rel=1e-15)


def test_a_law_is_not_changed_through_the_callers_arrays():
    """Host leaves are read-only copies: the caller's array, or an in-place operation on
    the leaf, cannot change a law that was checked when built."""
    a = np.array([0.5, 0.25])
    law = laws.SCCA(a, 0.0, np.array([0.5, 0.75]))
    a[0] = 5.0
    np.testing.assert_array_equal(law.sine, [0.5, 0.25])
    with pytest.raises(ValueError, match="read-only"):
        law.sine += 0.7
    assert laws.SCCA(0.5, 0.0, 0.5).name == "cycloidal"
    poly = laws.get("polynomial5:0.5,0,0,0")
    with pytest.raises(ValueError, match="read-only"):
        poly.v0[...] = 2.0


def test_fractions_holding_tracers_are_traced():
    """A list that holds tracers (under jit, grad, vmap) becomes a JAX leaf."""
    def ca(x):
        return laws.SCCA([x, 0.25], 0.0, [0.5, 0.75]).Ca

    expected = [laws.SCCA(0.4, 0.0, 0.5).Ca, laws.get("modified-sine").Ca]
    np.testing.assert_allclose(jax.jit(ca)(0.4), expected, rtol=1e-14)
    h = 1e-6
    fd = (ca(0.4 + h)[0] - ca(0.4 - h)[0]) / (2 * h)
    assert float(jax.grad(lambda x: ca(x)[0])(0.4)) == pytest.approx(float(fd), rel=1e-7)


@pytest.mark.parametrize("bad", [None, "0.5", "x", 1j])
def test_fractions_must_be_numbers(bad):
    with pytest.raises(TypeError, match="SCCA fractions must be a number or an array of numbers"):
        laws.SCCA(bad, 0.0, 0.5)


@pytest.mark.parametrize("name", ["cycloidal", "modified-sine", "modified-trapezoid", "harmonic"])
def test_scca_jerk_at_the_midpoint_is_its_limit(name):
    """A law without a zero piece ends its half on the cosine: at tau = 1/2 exactly the jerk
    is the limit from both sides (it read 0, the empty zero piece's), -Ca (pi/c)."""
    law = laws.get(name)
    a, b, c = (float(x) for x in law.fractions)
    near = np.asarray(law.j(np.array([0.5 - 1e-9, 0.5, 0.5 + 1e-9])))
    assert near[1] == pytest.approx(-float(law.Ca) * np.pi / c, rel=1e-12)
    assert near[1] == pytest.approx(near[0], rel=1e-7) and near[1] == pytest.approx(near[2], rel=1e-7)


@pytest.mark.parametrize("degree, zero_jerk", [(5, False), (7, True), (3, False)])
def test_bspline_law_is_scipys_bspline(degree, zero_jerk):
    """``BSplineLaw``'s ``s, v, a, j`` on its clamped uniform basis against
    ``scipy.interpolate.BSpline`` of the same knots and control points (and its derivatives)."""
    from scipy.interpolate import BSpline

    from camjax.laws import BSplineLaw

    free = np.random.default_rng(degree).uniform(0.1, 0.9, 9)
    law = BSplineLaw(np.sort(free), degree=degree, zero_jerk=zero_jerk)
    fixed = 4 if zero_jerk else 3
    control = np.concatenate([np.zeros(fixed), np.sort(free), np.ones(fixed)])
    interior = control.size - degree  # uniform interior knots, clamped ends
    knots = np.concatenate([np.zeros(degree), np.linspace(0.0, 1.0, interior + 1), np.ones(degree)])
    np.testing.assert_allclose(law.knots, knots, rtol=0, atol=1e-15)
    reference = BSpline(knots, control, degree)
    tau = (np.arange(256) + 0.5) / 256  # off the knots, where a cubic's jerk steps
    s, v, a, j = (np.asarray(x) for x in law.evaluate(jnp.asarray(tau)))
    for order, got in enumerate((s, v, a, j)):
        want = reference.derivative(order)(tau) if order else reference(tau)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * max(1.0, np.abs(want).max()),
                                   err_msg=f"derivative {order}")
