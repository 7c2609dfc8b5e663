"""The bounded peak search (``camjax.metrics.peak_search``) against refining every interval
(``refined_peak``, the dense answer)."""

from math import comb

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax.metrics import (
    PEAK_GROUP,
    PEAK_TOLERANCE,
    bernstein_bound,
    bounded_extremes,
    bounded_peak,
    hermite_data,
    interval_peaks,
    peak_search,
    refined_peak,
    septic_coefficients,
)


def sampled(f, t):
    """Values and one-sided jets ``(value, widths, left, right)`` of ``f`` (JAX-traceable)
    at the nodes ``t``: what ``refined_peak`` takes."""
    d1 = jax.vmap(jax.grad(f))
    d2 = jax.vmap(jax.grad(jax.grad(f)))
    d3 = jax.vmap(jax.grad(jax.grad(jax.grad(f))))
    jets = jnp.stack([d1(t), d2(t), d3(t)], axis=1)
    return jax.vmap(f)(t), jnp.diff(t), jets[:-1], jets[1:]


def dense_peak(value, widths, left, right):
    """Every interval's septic refined: what the search must reproduce."""
    return jnp.max(interval_peaks(septic_coefficients(value, widths, left, right)))


@pytest.mark.parametrize("amplitude, omega, phase", [(1.7, 7.0, 0.4), (-0.3, 23.0, 2.9), (2.5, 61.0, -1.1)])
def test_refined_peak_of_a_sampled_cosine_is_its_amplitude(amplitude, omega, phase):
    """``max |A cos(w t + phi)|`` on [0, 1] is ``|A|`` (a crest lies inside for ``w > 2 pi``),
    within the septic's ``(w h)^8 / 1e7``; the samples alone fall short by up to ``1 - cos(w h / 2)``."""
    t = jnp.linspace(0.0, 1.0, 41)
    args = sampled(lambda t: amplitude * jnp.cos(omega * t + phase), t)
    h = 1.0 / 40
    assert abs(float(refined_peak(*args)) - abs(amplitude)) <= abs(amplitude) * max((omega * h) ** 8 / 1e7, 1e-14)
    assert float(jnp.max(jnp.abs(args[0]))) < abs(amplitude) * (1 - 1e-6)  # the refinement did the work


def test_refined_peak_of_a_polynomial_is_exact_between_nodes():
    """A septic is its own septic Hermite interpolant: ``f = 1 - 5 u^2 + 3 u^7`` with
    ``u = t - 0.537`` has its maximum 1 at ``u = 0`` (``f' = u (21 u^5 - 10)``, the other root
    at ``u = 0.86`` outside), between the nodes 0.525 and 0.55 of [0.3, 0.8], where
    ``0 < f < 1`` at both ends."""
    def f(t):
        return 1.0 - 5.0 * (t - 0.537) ** 2 + 3.0 * (t - 0.537) ** 7

    t = jnp.linspace(0.3, 0.8, 21)
    args = sampled(f, t)
    assert float(jnp.max(jnp.abs(args[0]))) < 1.0 - 1e-4  # the samples miss the crest
    np.testing.assert_allclose(float(refined_peak(*args)), 1.0, rtol=1e-13)
    np.testing.assert_allclose(float(bounded_peak(*args)), 1.0, rtol=1e-13)


SIGNALS = {
    # one crest among many smaller ones
    "single crest": lambda t: jnp.exp(-((t - 0.37) ** 2) / 0.01) * jnp.cos(40 * t),
    # crests of equal height everywhere: every group is a candidate
    "equal crests": lambda t: jnp.cos(2 * jnp.pi * 9.5 * t),
    # a broad crest, and three sharp ones a little lower whose bounds rank first
    "sharp and broad": lambda t: jnp.exp(-((t - 0.8) ** 2) / 0.005) + 0.999 * sum(
        jnp.exp(-((t - c) ** 2) / 4e-4) for c in (0.1033, 0.3017, 0.5051)),
    # a plateau with a small ripple (a constant-acceleration piece at a high period ratio)
    "plateau": lambda t: 1.0 + 1e-3 * jnp.sin(2 * jnp.pi * 14.3 * t),
    # monotone: the peak is a node
    "monotone": lambda t: jnp.exp(2 * t) - 3.0,
    # the largest magnitude is negative
    "negative": lambda t: -2.0 * jnp.sin(3.1 * t) ** 3 + 0.3 * t,
}


@pytest.mark.parametrize("name", sorted(SIGNALS))
@pytest.mark.parametrize("intervals", [1, 5, PEAK_GROUP, 3 * PEAK_GROUP + 5, 200])
def test_search_equals_refining_every_interval(name, intervals):
    """Equal to rounding (the search returns a node's own value where the dense form
    evaluates the septic there); an interval missed would cost far more."""
    t = jnp.linspace(0.0, 1.0, intervals + 1) ** 1.1  # unequal widths
    args = sampled(SIGNALS[name], t)
    np.testing.assert_allclose(bounded_peak(*args), dense_peak(*args), rtol=1e-12, atol=0)
    np.testing.assert_allclose(jax.jit(bounded_peak)(*args), dense_peak(*args), rtol=1e-12, atol=0)


@pytest.mark.parametrize("name", sorted(SIGNALS))
def test_bounded_extremes_equal_refining_every_interval(name):
    """``bounded_extremes`` (the signed least and largest value by the search, as a cam
    turn's contact force and torque take them) against ``refined_extremes`` (dense)."""
    from camjax.sdof import refined_extremes

    t = jnp.linspace(0.0, 1.0, 3 * PEAK_GROUP + 6) ** 1.1
    args = sampled(SIGNALS[name], t)
    scale = float(jnp.max(jnp.abs(args[0])))
    for got, want in zip(jax.jit(bounded_extremes)(*args), refined_extremes(*args)):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * scale)


def test_search_under_vmap_rows_needing_different_rounds():
    """Rows of one batch need one group (a single crest) or all of them (equal crests)."""
    t = jnp.linspace(0.0, 1.0, 97)
    rows = [sampled(lambda x, w=w, decay=decay: jnp.cos(w * x) * jnp.exp(-decay * x), t)
            for w in (7.0, 60.0, 200.0) for decay in (0.0, 3.0)]
    batch = jax.tree.map(lambda *x: jnp.stack(x), *rows)
    expected = jnp.stack([dense_peak(*row) for row in rows])
    np.testing.assert_allclose(jax.vmap(bounded_peak)(*batch), expected, rtol=1e-12, atol=0)


def test_gradient_is_the_dense_maximums():
    t = jnp.linspace(0.0, 1.0, 41)

    def peak(p, fn):
        return fn(*sampled(lambda x: jnp.sin(p * x) + 0.2 * x, t))

    for p in (2.5, 13.0):
        search = jax.grad(peak)(p, bounded_peak)
        dense = jax.grad(peak)(p, dense_peak)
        step = 1e-6
        central = (peak(p + step, bounded_peak) - peak(p - step, bounded_peak)) / (2 * step)
        forward = jax.jvp(lambda x: peak(x, bounded_peak), (p,), (1.0,))[1]
        np.testing.assert_allclose(search, dense, rtol=1e-12)
        np.testing.assert_allclose(forward, dense, rtol=1e-12)
        np.testing.assert_allclose(search, central, rtol=1e-7)


def test_bernstein_bound_is_the_largest_bernstein_coefficient_and_bounds_the_septic():
    rng = np.random.default_rng(3)
    value = rng.normal(size=51)
    widths = rng.uniform(0.01, 0.1, size=50)
    left, right = rng.normal(size=(50, 3)) * 30, rng.normal(size=(50, 3)) * 30
    monomial = np.asarray(septic_coefficients(value, widths, left, right))
    to_bernstein = np.array([[comb(i, j) / comb(7, j) if j <= i else 0.0 for j in range(8)]
                             for i in range(8)])
    expected = np.abs(monomial @ to_bernstein.T).max(axis=1)
    bound = np.asarray(bernstein_bound(value, widths, left.T, right.T))
    np.testing.assert_allclose(bound, expected, rtol=1e-12)
    sigma = np.linspace(0.0, 1.0, 2001)
    dense = np.abs(np.polynomial.polynomial.polyval(sigma, monomial.T)).max(axis=1)
    assert np.all(dense <= bound * (1 + 1e-12))


def test_nan_anywhere_gives_nan():
    args = sampled(SIGNALS["single crest"], jnp.linspace(0.0, 1.0, 30))
    for which, index in ((0, 7), (2, 4), (3, 20)):
        broken = list(args)
        broken[which] = broken[which].at[index].set(jnp.nan)
        assert np.isnan(bounded_peak(*broken)), (which, index)


@pytest.mark.parametrize("damping", [0.0, 0.2])
def test_sdof_peak_in_motion_bounded_equals_dense(damping):
    """The Ct kernel's two searches (``peak_in_motion``'s ``search``) agree, on a law with
    a plateau (many equal crests) and one without, across n in [1, 60]: within
    ``PEAK_TOLERANCE``, by which the bounded search leaves a plateau's equal crests after
    the first (about 1.5e-12 here)."""
    from camjax import laws
    from camjax.sdof import motion_grid, peak_in_motion, propagate

    n = jnp.linspace(1.0, 60.0, 97)
    for name in ("modified-trapezoid", "poly4567"):
        grid = motion_grid(laws.as_law(name), 384)  # w h <= 0.98 at n = 60, within the SDOF path's step

        def peaks(kind, grid=grid):
            def one(x):
                w = 2 * jnp.pi * x
                return peak_in_motion(propagate(grid, w, damping), grid, w, damping, kind)

            return jax.jit(jax.vmap(one))(n)

        np.testing.assert_allclose(peaks("bounded"), peaks("dense"), rtol=PEAK_TOLERANCE, atol=0)


def _sdof_signal(spec, n, zeta, resolution=192):
    """A law's grid, and at period ratio ``n`` the payload acceleration's node values and
    five one-sided derivatives per interval end (``peak_in_motion``'s input)."""
    from camjax import laws
    from camjax.sdof import eigenvalue, gain_derivatives, mode_gain, motion_grid, propagate

    grid = motion_grid(laws.as_law(spec), resolution)
    w = 2 * jnp.pi * n
    q = propagate(grid, w, zeta, resolved=True)
    gain, lam = mode_gain(w, zeta), eigenvalue(w, zeta)
    one_left, one_right = grid.one_sided(5)
    return (grid, q, jnp.real(gain * q), gain_derivatives(gain, lam, q[:-1], one_left),
            gain_derivatives(gain, lam, q[1:], one_right))


@pytest.mark.parametrize("spec", ["parabolic", "scca:0.2,0.6,0.2", "modified-trapezoid"])
@pytest.mark.parametrize("zeta", [0.0, 0.05])
def test_plateau_bound_bounds_every_constant_interval_and_is_exact_at_crests(spec, zeta):
    """Finite exactly on the intervals of constant acceleration, never below the interval's
    own maximum (degree 11, refined), and undamped equal to it where a crest lies inside."""
    from camjax.sdof import plateau_bound

    for n in (3.7, 17.3, 29.0):
        grid, _, values, left, right = _sdof_signal(spec, n, zeta)
        w = 2 * jnp.pi * n
        bound = np.asarray(plateau_bound(values, left[:, 0], right[:, 0], grid.forcing, w, zeta))
        exact = np.asarray(interval_peaks(septic_coefficients(values, grid.widths, left, right)))
        constant = np.all(np.asarray(grid.forcing)[:, 1:] == 0, axis=1)
        assert constant.sum() >= 20
        np.testing.assert_array_equal(np.isfinite(bound), constant)
        # The interpolant's own rounding puts its value at an end up to 1.4e-12 off the
        # node's: the search's tolerance covers it.
        assert np.all(bound[constant] >= exact[constant] * (1 - PEAK_TOLERANCE)), n
        if zeta == 0.0:  # the plateau's highest crest: its bound is its value
            top = np.argmax(np.where(constant, exact, 0.0))
            np.testing.assert_allclose(bound[top], exact[top], rtol=PEAK_TOLERANCE)


@pytest.mark.parametrize("spec", ["parabolic", "scca:0.2,0.6,0.2"])
def test_plateaus_close_after_their_first_crest(spec):
    """Undamped, the crests of a constant-acceleration piece tie.  ``peak_search`` with the
    plateau bound (``camjax.sdof.plateau_bound``, as ``peak_in_motion`` takes it) settles the
    peak in at most three rounds of refinement, against 7-15 with the Bernstein bounds
    alone (rounds counted as the search runs); the same answer, the dense one."""
    from camjax.sdof import plateau_bound

    def rounds(values, widths, left, right, bound):
        calls = []

        def hermite_of(index):
            jax.debug.callback(lambda: calls.append(1))
            return hermite_data(values[index], widths[index], left[index], right[index],
                                values[index + 1])

        peak = jax.block_until_ready(peak_search(bound, hermite_of, jnp.max(jnp.abs(values)),
                                                 PEAK_TOLERANCE))
        return peak, len(calls) - 1  # the last call evaluates the winner

    for n in (17.3, 29.0):
        grid, _, values, left, right = _sdof_signal(spec, n, 0.0)
        w = 2 * jnp.pi * n
        bernstein = bernstein_bound(values, grid.widths, left[:, :3].T, right[:, :3].T)
        bernstein = bernstein + 1e-5 * jnp.max(bernstein)  # the septic's bound for degree 11
        plateau = jnp.minimum(bernstein, plateau_bound(values, left[:, 0], right[:, 0], grid.forcing, w, 0.0))
        dense = jnp.max(interval_peaks(septic_coefficients(values, grid.widths, left, right)))
        (fast, few), (slow, many) = (rounds(values, grid.widths, left, right, b) for b in (plateau, bernstein))
        assert few <= 3 and many >= 7, (n, few, many)
        np.testing.assert_allclose([fast, slow], dense, rtol=PEAK_TOLERANCE, atol=0)


def test_plateau_bound_does_not_depend_on_the_signals_scale():
    """The slopes' product and the envelope's squares underflowed near 1e-160 (the bound
    fell 9e-6 below the crest); signs and hypot keep it at any scale."""
    from camjax.sdof import plateau_bound

    grid, _, values, left, right = _sdof_signal("parabolic", 7.3, 0.0)
    w = 2 * jnp.pi * 7.3
    unit = plateau_bound(values, left[:, 0], right[:, 0], grid.forcing, w, 0.0)
    for scale in (1e-160, 1e-300, 1e150):
        scaled = plateau_bound(values * scale, left[:, 0] * scale, right[:, 0] * scale,
                               grid.forcing * scale, w, 0.0)
        np.testing.assert_allclose(scaled / scale, unit, rtol=1e-13)


def test_equal_samples_give_an_exact_constant_with_the_interpolants_gradient():
    """``to_monomial`` of equal samples is ``(a, 0, ..., 0)`` exactly (NumPy and JAX);
    its derivatives in the samples stay those of the interpolant."""
    from camjax.sdof import GAUSS_POINTS, INTERPOLATION_DEGREE, to_monomial

    # The interpolant through the samples at the Gauss points, from the Vandermonde matrix.
    to_monomial_matrix = np.linalg.inv(np.vander(GAUSS_POINTS, INTERPOLATION_DEGREE + 1, increasing=True))

    samples = np.array([[0.3] * 6, [1.0, 1.0, 1.0, 1.0, 1.0, 1.0 + 1e-15], [-7.1] * 6])
    for result in (to_monomial(samples), np.asarray(to_monomial(jnp.asarray(samples)))):
        np.testing.assert_array_equal(result[[0, 2]], [[0.3, 0, 0, 0, 0, 0], [-7.1, 0, 0, 0, 0, 0]])
        np.testing.assert_allclose(result[1], samples[1] @ to_monomial_matrix.T, rtol=0, atol=1e-12)
        assert np.all(result[1][1:] != 0)  # unequal samples: the interpolant as it is
    huge = np.array([[np.inf] * 6, [1e308] * 6])  # NumPy and JAX alike, no NaN
    for result in (to_monomial(huge), np.asarray(to_monomial(jnp.asarray(huge)))):
        np.testing.assert_array_equal(result, [[np.inf, 0, 0, 0, 0, 0], [1e308, 0, 0, 0, 0, 0]])
    jacobian = jax.jacobian(lambda s: to_monomial(s))(jnp.full(6, 0.3))
    np.testing.assert_allclose(jacobian, to_monomial_matrix, rtol=1e-15)


def test_an_unknown_peak_search_is_refused_in_one_line():
    """``peak_in_motion``, ``SpringMassOptions`` and a sweep name the option and the kinds."""
    from camjax.models import SpringMassOptions
    from camjax.sdof import motion_grid, peak_in_motion

    grid = motion_grid(camjax.laws.as_law("cycloidal"), 16)
    message = "peak_search must be one of bounded, dense, got 'fast'"
    with pytest.raises(ValueError, match=message):
        peak_in_motion(jnp.zeros(grid.nodes.shape, complex), grid, 2.0, 0.0, "fast")
    with pytest.raises(ValueError, match=message):
        SpringMassOptions(peak_search="fast").checked(3.0)
    with pytest.raises(ValueError, match=message):
        camjax.ct_curve("cycloidal", [1.0, 2.0], peak_search="fast")
    with pytest.raises(ValueError, match="unknown option 'peak_search' for CoulombFriction"):
        camjax.ct_curve("cycloidal", [1.0], model=camjax.CoulombFriction(1.0, 0.05),
                        peak_search="dense")


def test_a_sweep_with_each_peak_search_in_one_process():
    """The peak search is a sweep's option, not a process switch: both in one process,
    alternately, give the same curve (within ``PEAK_TOLERANCE``) and the default is
    unchanged by a dense sweep run before it."""
    n = np.linspace(1.0, 30.0, 60)
    first = camjax.ct_curve("modified-trapezoid", n)
    dense = camjax.ct_curve("modified-trapezoid", n, peak_search="dense")
    again = camjax.ct_curve("modified-trapezoid", n)
    np.testing.assert_array_equal(again.ct, first.ct)
    for metric in ("ct", "residual", "peak_in_motion"):
        np.testing.assert_allclose(getattr(dense, metric), getattr(first, metric),
                                   rtol=PEAK_TOLERANCE, atol=0)


@pytest.mark.parametrize("damping", [0.0, 0.1])
def test_sdof_peak_at_the_grid_step_against_septics_eight_times_finer(damping):
    """The SDOF path's refinement (degree 11 on its grid, ``w h <= MAX_PHASE_STEP``)
    against the septic refinement (three derivatives, ``refined_peak``) on a grid eight
    times finer (``w h <= 1/8``: error about 6e-15), both searches, n in [0.5, 60]: laws
    whose forcing both grids interpolate to 1e-13 or exactly."""
    from camjax import laws
    from camjax.metrics import refined_peak
    from camjax.sdof import (
        MAX_PHASE_STEP,
        default_resolution,
        mode_gain,
        motion_grid,
        output_jets,
        peak_in_motion,
        propagate,
    )

    n = jnp.linspace(0.5, 60.0, 41)
    resolution = default_resolution(60.0, MAX_PHASE_STEP)
    for name in ("poly4567", "cycloidal", "modified-trapezoid", "harmonic"):
        law = laws.as_law(name)
        grid, fine = motion_grid(law, resolution), motion_grid(law, 8 * resolution)

        def reference(x, fine=fine):
            w = 2 * jnp.pi * x
            q = propagate(fine, w, damping)
            values, left, right = output_jets(mode_gain(w, damping), q, fine, w, damping)
            return refined_peak(values, fine.widths, left, right)

        expected = np.asarray(jax.jit(jax.vmap(reference))(n))
        for kind in ("bounded", "dense"):
            got = jax.jit(jax.vmap(lambda x, grid=grid, kind=kind: peak_in_motion(
                propagate(grid, 2 * jnp.pi * x, damping, resolved=True), grid,
                2 * jnp.pi * x, damping, kind)))(n)
            np.testing.assert_allclose(np.asarray(got), expected, rtol=1e-11, atol=0,
                                       err_msg=f"{name}, {kind}")


def test_one_sided_derivatives_are_the_interpolants():
    """``MotionGrid.one_sided(5)``: the forcing polynomial's derivatives 0..4 at each end,
    against NumPy's derivatives of the same polynomial; the default three are its first
    columns."""
    from numpy.polynomial import polynomial

    from camjax import laws
    from camjax.sdof import motion_grid

    grid = motion_grid(laws.SCCA(0.3, 0.1, 0.6), 64)
    left, right = (np.asarray(x) for x in grid.one_sided(5))
    c, h = np.asarray(grid.forcing), np.asarray(grid.widths)
    for k in (0, 17, 40, c.shape[0] - 1):
        for j in range(5):
            derivative = polynomial.polyder(c[k], j) if j else c[k]
            assert left[k, j] == pytest.approx(polynomial.polyval(0.0, derivative) / h[k]**j, rel=1e-12)
            assert right[k, j] == pytest.approx(polynomial.polyval(1.0, derivative) / h[k]**j, rel=1e-12)
    three = grid.one_sided()
    np.testing.assert_array_equal(np.asarray(three[0]), left[:, :3])
    np.testing.assert_array_equal(np.asarray(three[1]), right[:, :3])


@pytest.mark.parametrize("damping", [0.0, 0.3])
def test_steps_within_are_the_exact_state_between_nodes(damping):
    """The mode a third, half and all of the way across every interval (the series step)
    against ``mode_between`` (the per-piece ``psi`` step, on the host), at ``w h`` up to
    ``MAX_PHASE_STEP``."""
    from camjax import laws
    from camjax.sdof import eigenvalue, mode_between, motion_grid, propagate, steps_within

    grid = motion_grid(laws.SCCA(0.002, 0.5, 0.498), 256)
    w = 2 * np.pi * 61.0  # w h = 1.497 on the widest interval
    lam = eigenvalue(w, damping)
    q = propagate(grid, w, damping)
    scale = float(jnp.max(jnp.abs(q)))
    for fraction in (1 / 3, 0.5, 1.0):
        inside = steps_within(q[:-1], grid.forcing, grid.widths, jnp.max(grid.piece_width),
                              lam, fraction)
        t = np.asarray(grid.nodes[:-1] + grid.widths * fraction)
        expected = mode_between(grid, np.asarray(q), complex(lam), t)
        assert np.max(np.abs(np.asarray(inside) - expected)) <= 1e-13 * scale


def test_float32_peaks_refine_septics_and_stay_near_single_precision():
    """In float32 (a child process) the SDOF refinement takes septics: the fifth
    derivative's rounding put the degree-11 refinement's Ct off by 2.5e-3 on the parabolic
    law; with septics Ct stays within 2e-4 of float64, as before the grid at w h <= 1."""
    import ast
    import os
    import subprocess
    import sys

    import camjax

    code = ("import numpy as np, camjax; "
            "print(repr(camjax.ct_curve('parabolic', np.linspace(1, 30, 200)).ct.tolist()))")
    out = subprocess.run([sys.executable, "-c", code], env={**os.environ, "JAX_ENABLE_X64": "0"},
                         capture_output=True, text=True, check=True).stdout
    single = np.array(ast.literal_eval(out.strip().splitlines()[-1]))
    double = camjax.ct_curve("parabolic", np.linspace(1, 30, 200)).ct
    assert 1e-9 < np.max(np.abs(single - double)) < 2e-4
