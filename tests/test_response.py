"""The SDOF response engine against closed forms, scipy and diffrax."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import compiled_programs
from scipy.integrate import solve_ivp

import camjax
from camjax import laws
from camjax.metrics import PEAK_TOLERANCE
from camjax.models import TRACED_RESOLUTION, response_metrics
from camjax.sweep import sweep_program


def cycloidal_residual(n):
    return math.pi if n == 1 else 2 * n * abs(math.sin(math.pi * n)) / abs(n * n - 1)


def residual_by_quadrature(law, n, points=400):
    """R = w |int_0^1 a(u) exp(-i w u) du| / Ca (MISSION.md) by Gauss-Legendre per piece.

    Direct quadrature of the oscillatory integrand: independent of the engine's exact
    propagation, and converged for these n (400 points per smooth piece).
    """
    w = 2 * math.pi * n
    edges = np.array([0.0, *[float(b) for b in law.breakpoints()], 1.0])
    x, weights = np.polynomial.legendre.leggauss(points)
    lo, hi = edges[:-1, None], edges[1:, None]
    u = (lo + hi) / 2 + (hi - lo) / 2 * x
    integrand = np.asarray(law.a(u)) * np.exp(-1j * w * u)
    total = np.sum((hi - lo) / 2 * weights * integrand)
    return w * abs(total) / float(law.Ca)


def test_cycloidal_residual_matches_closed_form_over_wide_range():
    n = np.linspace(0.5, 50, 397)
    curve = camjax.ct_curve(laws.Cycloidal(), n)
    expected = np.array([cycloidal_residual(x) for x in n])
    np.testing.assert_allclose(curve.residual, expected, rtol=0, atol=1e-9)


@pytest.mark.parametrize("name", ["modified-sine", "modified-trapezoid", "harmonic",
                                  "parabolic", "poly345", "poly4567"])
def test_residual_matches_fourier_integral(name):
    law = laws.get(name)
    n = np.array([0.7, 3.3, 11.9, 41.3])
    curve = camjax.ct_curve(law, n)
    expected = [residual_by_quadrature(law, x) for x in n]
    np.testing.assert_allclose(curve.residual, expected, rtol=1e-9, atol=1e-10)


def test_residual_zeros_of_cycloidal_and_harmonic():
    cyc = camjax.ct_curve(laws.Cycloidal(), np.arange(2.0, 21.0))
    assert np.max(cyc.residual) < 1e-9
    shm = camjax.ct_curve(laws.SimpleHarmonic(), np.arange(1.5, 20.0, 1.0))
    assert np.max(shm.residual) < 1e-9


def test_parabolic_and_harmonic_torsion_factor_bounds():
    n = np.linspace(1, 30, 600)
    par = camjax.ct_curve(laws.Parabolic(), n)
    assert np.all(par.ct >= 2 - 1e-9) and np.all(par.ct <= 4 + 1e-9)
    assert par.ct.max() == pytest.approx(4.0, abs=1e-6)  # the worst case is reached
    # SHM: in the rise x'' = A w^2/(w^2 - pi^2) (cos(pi tau) - cos(w tau)), whose peak is
    # 2A (1 - 0.37/n^2) to leading order, just below 2A; the crests of Ct come from the
    # residual and tend to 2 from above.
    n = np.linspace(10, 30, 400)
    shm = camjax.ct_curve(laws.SimpleHarmonic(), n)
    assert np.all(shm.ct >= 2 - 0.8 / n**2) and np.all(shm.ct <= 2 + 1 / n**2)
    crests, values = camjax.metrics.upper_envelope(n, shm.ct)
    assert np.all(values >= 2) and np.all(np.diff(values) <= 1e-12)


@pytest.mark.parametrize("name", ["modified-trapezoid", "harmonic", "poly4567"])
def test_torsion_factor_converges_under_grid_refinement(name):
    law = laws.get(name)
    n = np.array([1.7, 6.2, 14.9, 28.4])
    values = [camjax.ct_curve(law, n, damping=0.03, resolution=r).ct for r in (512, 1024, 2048)]
    assert np.max(np.abs(values[1] / values[2] - 1)) < 1e-8
    coarse_error = np.max(np.abs(values[0] / values[2] - 1))
    # Down to the peak search's tolerance, below which it does not refine.
    assert np.max(np.abs(values[1] / values[2] - 1)) <= max(coarse_error, PEAK_TOLERANCE)


@pytest.mark.parametrize("name", ["modified-sine", "parabolic", "poly345"])
def test_diffrax_agrees_with_exact_path(name):
    law = laws.get(name)
    n = np.array([1.3, 4.6, 12.2])
    exact = camjax.ct_curve(law, n, damping=0.05)
    ode = camjax.ct_curve(law, n, damping=0.05, method="tsit5", rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(ode.ct, exact.ct, rtol=1e-7)
    np.testing.assert_allclose(ode.residual, exact.residual, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(ode.peak_in_motion, exact.peak_in_motion, rtol=1e-7)


def test_state_at_end_of_rise_matches_scipy():
    law, n, zeta = laws.ModifiedTrapezoid(), 3.7, 0.08
    w = 2 * math.pi * n
    response = camjax.solve(law, camjax.SpringMass(n, zeta))
    tau = np.asarray(response.tau)
    nodes = [int(np.argmin(np.abs(tau - t))) for t in (0.25, 0.6, 1.0)]

    def rhs(t, y):
        return [y[1], float(law.a(t)) - w * w * y[0] - 2 * zeta * w * y[1]]

    sol = solve_ivp(rhs, (0, 1), [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    t_eval=tau[nodes])
    for i, e in zip(nodes, sol.y[0]):
        assert float(response.deflection[i]) == pytest.approx(e, rel=1e-8, abs=1e-12)
    # Payload acceleration x'' = w^2 e + 2 zeta w e' at the end of the rise.
    e1, de1 = sol.y[0][-1], sol.y[1][-1]
    assert float(response.payload_acceleration[nodes[-1]]) == pytest.approx(
        w * w * e1 + 2 * zeta * w * de1, rel=1e-8)
    # Residual: the largest |x''| of the free vibration from (e1, de1) over the dwell (one
    # motion period), x'' = w^2 e + 2 zeta w e', sampled densely.
    assert float(response.metrics.residual) * float(law.Ca) == pytest.approx(
        free_vibration_peak(e1, de1, w, zeta, 1.0), rel=1e-8)


def free_vibration_peak(e0, de0, w, zeta, dwell, samples=400_001):
    """``max |x''|`` over ``[0, dwell]`` of ``e'' + 2 zeta w e' + w^2 e = 0`` from
    ``(e0, e0')``, ``x'' = w^2 e + 2 zeta w e'``, from the closed-form solution sampled densely
    (``sin(w_d t) / w_d`` as ``t sinc``: exact as ``zeta -> 1``)."""
    t = np.linspace(0.0, dwell, samples)
    a, wd = zeta * w, w * math.sqrt(1.0 - zeta**2)
    sin_over = t * np.sinc(wd * t / math.pi)
    decay = np.exp(-a * t)
    e = decay * (e0 * np.cos(wd * t) + (de0 + a * e0) * sin_over)
    de = decay * (de0 * np.cos(wd * t) - (a * de0 + w * w * e0) * sin_over)
    return float(np.abs(w * w * e + 2 * zeta * w * de).max())


@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.5, 0.9, 0.999999])
def test_residual_is_the_largest_acceleration_in_the_dwell(zeta):
    """R is the largest |x''| of the dwell's free vibration: against the state at the end of
    a cycloidal rise by scipy and the free vibration sampled densely, at light to almost
    critical damping (the envelope's start, w |q| / sqrt(1 - zeta^2), was 353 at
    zeta = 0.999999); undamped it keeps the closed form 2n|sin pi n| / |n^2 - 1| wherever
    the dwell holds the first crest (n >= 1/2)."""
    law = laws.Cycloidal()
    for n in (0.3, 0.7, 1.3, 2.6):
        w = 2 * math.pi * n

        def rhs(t, y, w=w):
            return [y[1], float(law.a(t)) - w * w * y[0] - 2 * zeta * w * y[1]]

        sol = solve_ivp(rhs, (0, 1), [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14)
        e1, de1 = sol.y[0][-1], sol.y[1][-1]
        got = float(camjax.residual_vibration(law, n, zeta))
        assert got == pytest.approx(free_vibration_peak(e1, de1, w, zeta, 1.0) / (2 * math.pi), rel=1e-7, abs=1e-12)
        if zeta == 0.0 and n >= 0.5:
            assert got == pytest.approx(cycloidal_residual(n), rel=1e-10)


def test_undamped_torsion_factor_is_max_of_motion_peak_and_residual():
    curve = camjax.ct_curve(laws.ModifiedSine(), np.linspace(1, 20, 77))
    np.testing.assert_allclose(curve.ct, np.maximum(curve.peak_in_motion, curve.residual),
                               rtol=1e-12)


def test_batch_equals_python_loop_and_jit_equals_eager():
    """The batch, the loop, the eager call and the jitted one run one grid each pair (the
    curve's 128 intervals are every ratio's default here; the jitted call's traced ratio
    gets TRACED_RESOLUTION, given to the eager call too) but different compiled programs.
    Those agree to the method's accuracy, not the last bits: the peak search leaves alone
    an interval within PEAK_TOLERANCE (relative) of the best value, so two programs that
    round differently may refine different near-equal crests (Ct differed by 1.05e-12 at
    n = 19.6); R, the end node's mode in closed form, has no search: rounding alone."""
    law = laws.Cycloidal()
    n = np.array([1.1, 2.9, 7.3, 19.6])
    curve = camjax.ct_curve(law, n, damping=0.02)
    loop = [camjax.solve(law, camjax.SpringMass(x, 0.02), resolution=128).metrics for x in n]
    np.testing.assert_allclose(curve.ct, [float(m.ct) for m in loop], rtol=2 * PEAK_TOLERANCE)
    np.testing.assert_allclose(curve.residual, [float(m.residual) for m in loop], rtol=1e-12)
    eager = camjax.torsion_factor(law, 7.3, 0.02, resolution=TRACED_RESOLUTION)
    jitted = jax.jit(lambda n, zeta: camjax.torsion_factor(law, n, zeta))(7.3, 0.02)
    assert float(jitted) == pytest.approx(float(eager), rel=2 * PEAK_TOLERANCE)
    # With the law traced, its pieces get traced interval counts (another grid, with the
    # same nodes at the breakpoints): the same Ct within the peak refinement's error.
    traced = jax.jit(camjax.torsion_factor)(law, 7.3, 0.02)
    assert float(traced) == pytest.approx(float(eager), rel=1e-9)


def test_laws_of_every_type_share_one_compiled_sweep():
    """The exact sweep reads a law's samples (SampledLaw, pieces padded): the seven standard
    laws are one program, and the padding leaves every number as the law's own grid gives."""
    n = np.array([2.5, 7.3])
    standard = laws.standard_laws()
    camjax.ct_curves(standard[:1], n)
    with compiled_programs() as compiled:
        curves = camjax.ct_curves(standard, n)
    assert f"jit({sweep_program.__name__})" not in compiled  # each law's sampling compiles; the sweep does not
    for law in (standard[0], standard[-1]):  # an SCCA law (8 pieces) and a polynomial (1)
        for k, x in enumerate(n):
            own = camjax.solve(law, camjax.SpringMass(x), resolution=512).metrics
            assert curves[law.name].ct[k] == pytest.approx(float(own.ct), rel=1e-9)
            assert curves[law.name].residual[k] == pytest.approx(float(own.residual), rel=1e-9, abs=1e-13)


def test_ct_curves_like_pads_for_a_law_swept_later():
    """``like`` pads the standard laws to a spline's piece count: the spline swept later
    (as the design command does) reuses their program, and every number equals the one
    swept with them."""
    n = np.array([3.1, 8.7])
    spline = laws.BSplineLaw.fit(laws.get("cycloidal"), 20)
    standard = {law.name: law for law in laws.standard_laws()[:3]}
    apart = camjax.ct_curves(standard, n, like=[laws.BSplineLaw(np.zeros(20))])
    assert set(apart) == set(standard)  # like is not swept
    with compiled_programs() as compiled:
        later = camjax.ct_curve(spline, n)
    assert f"jit({sweep_program.__name__})" not in compiled
    together = camjax.ct_curves({**standard, "spline": spline}, n)
    for name, curve in {**apart, "spline": later}.items():
        np.testing.assert_array_equal(curve.ct, together[name].ct)
        np.testing.assert_array_equal(curve.residual, together[name].residual)


def _central(f, x, h):
    return (f(x + h) - f(x - h)) / (2 * h)


@pytest.mark.parametrize("n", [2.37, 8.61])
def test_gradients_in_period_ratio_and_damping(n):
    law = laws.ModifiedSine()
    for fn in (camjax.torsion_factor, camjax.residual_vibration):
        d_n = jax.grad(lambda x, fn=fn: fn(law, x, 0.04))(n)
        fd_n = _central(lambda x, fn=fn: float(fn(law, x, 0.04)), n, 1e-5)
        assert float(d_n) == pytest.approx(fd_n, rel=1e-5, abs=1e-7)
        d_z = jax.grad(lambda z, fn=fn: fn(law, n, z))(0.04)
        fd_z = _central(lambda z, fn=fn: float(fn(law, n, z)), 0.04, 1e-6)
        assert float(d_z) == pytest.approx(fd_z, rel=1e-5, abs=1e-7)


def test_gradients_in_law_parameters():
    n = 5.3

    def metric(f, which):
        law = laws.SCCA(f[0], f[1], f[2])
        m = response_metrics(law, camjax.SpringMass(n, 0.0), camjax.models.SpringMassOptions(resolution=512))
        return getattr(m, which)

    f0 = jnp.array([0.3, 0.35, 0.3])
    for which in ("residual", "ct"):
        grad = jax.grad(metric)(f0, which)
        for i in range(3):
            e = jnp.zeros(3).at[i].set(1e-6)
            fd = (metric(f0 + e, which) - metric(f0 - e, which)) / 2e-6
            assert float(grad[i]) == pytest.approx(float(fd), rel=1e-5, abs=1e-7)


def test_physical_period_ratio():
    # 2 kg on 4e6 N/m: f = sqrt(2e6)/(2 pi) Hz; a 50 ms rise gives n = 0.05 f.
    assert camjax.period_ratio(0.05, mass=2.0, stiffness=4e6) == pytest.approx(
        0.05 * math.sqrt(2e6) / (2 * math.pi))
    assert camjax.period_ratio(0.1, inertia=0.01, torsional_rigidity=2e4) == pytest.approx(
        0.1 * math.sqrt(2e6) / (2 * math.pi))
    with pytest.raises(ValueError, match="stiffness must be positive"):
        camjax.period_ratio(0.05, mass=2.0, stiffness=-1.0)
    with pytest.raises(ValueError, match="either mass and stiffness"):
        camjax.period_ratio(0.05, mass=2.0, torsional_rigidity=1.0)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: camjax.ct_curve(laws.Cycloidal(), [1.0, -2.0]), "must be positive, got -2"),
        (lambda: camjax.ct_curve(laws.Cycloidal(), [0.0]), "must be positive, got 0"),
        (lambda: camjax.ct_curve(laws.Cycloidal(), [np.nan]), "finite"),
        (lambda: camjax.ct_curve(laws.Cycloidal(), []), "non-empty"),
        (lambda: camjax.ct_curve(laws.Cycloidal(), [2.0], damping=1.0), r"in \[0, 1\)"),
        (lambda: camjax.ct_curve(laws.Cycloidal(), [2.0], damping=-0.1), r"in \[0, 1\)"),
        (lambda: camjax.ct_curve(laws.Cycloidal(), [2.0], method="rk99"), "unknown method"),
        (lambda: camjax.ct_curve(laws.Cycloidal(), [2.0], dwell=-1), "dwell"),
        (lambda: camjax.SpringMass(-3.0), "must be positive"),
    ],
)
def test_bad_input_raises_clear_errors(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_solver_failure_raises():
    with pytest.raises(camjax.SolverError, match="maximum number of solver steps"):
        camjax.ct_curve(laws.ModifiedSine(), [25.0], method="tsit5", max_steps=16)


def test_fit_recovers_known_envelope():
    n = np.linspace(1, 30, 2901)  # includes every integer
    envelope = 2.5 / n**1.3 + 1.1
    ct = envelope * (1 - 0.5 * np.abs(np.sin(np.pi * n)))  # crests at the integers, on it
    curve = camjax.CtCurve(n, ct, ct, ct, 1.0, "synthetic")
    fit = camjax.fit_torsion_factor(curve)
    assert (fit.p, fit.q, fit.r) == pytest.approx((2.5, 1.3, 1.1), rel=1e-4)


def test_crossings_of_two_curves():
    n = np.linspace(1, 10, 901)
    a = camjax.CtCurve(n, 2 / n + 1, n * 0, n * 0, 1.0, "a")
    b = camjax.CtCurve(n, np.full_like(n, 1.5), n * 0, n * 0, 1.0, "b")
    assert camjax.ca_ct_crossings(a, b, envelope=False) == pytest.approx([4.0], abs=1e-4)


def test_batched_laws_equal_single_calls():
    family = [laws.SCCA(0.25, 0.5, 0.25), laws.SCCA(0.3, 0.2, 0.4)]
    n = np.array([2.2, 9.1])
    batched = camjax.ct_curves(family, n)
    for law in family:
        np.testing.assert_allclose(batched[law.name].ct, camjax.ct_curve(law, n).ct, rtol=1e-10)


def test_psi_matches_its_integral_on_both_branches():
    """``psi_m(z) = int_0^1 exp(z (1 - s)) s^m ds`` by Gauss-Legendre (8 panels of 40
    points: converged for |z| <= 11), for z inside the series' radius, across it and
    beyond (the recurrence), complex and real."""
    from camjax.sdof import psi

    x, w = np.polynomial.legendre.leggauss(40)
    s = ((np.arange(8)[:, None] + (x + 1) / 2) / 8).ravel()
    weights = np.tile(w / 16, 8)
    z = np.concatenate([(np.linspace(-6, 0.5, 14)[:, None]
                         + 1j * np.linspace(-9, 9, 19)[None, :]).ravel(),
                        [0j, 1e-9j, 0.999j, 1.001j, -0.999j, -1.001j, 0.999 + 0j,
                         1.001 + 0j, -0.999 + 0j, -1.001 + 0j, 3.0 + 0j]])
    reference = np.stack([(weights * np.exp(np.outer(z, 1 - s)) * s**m).sum(1)
                          for m in range(6)], axis=-1)
    got = np.asarray(psi(jnp.asarray(z)))
    np.testing.assert_allclose(got, reference, rtol=1e-12)
    real = np.array([-1.5, 0.25, 2.5])
    real_reference = np.stack([(weights * np.exp(np.outer(real, 1 - s)) * s**m).sum(1)
                               for m in range(6)], axis=-1)
    np.testing.assert_allclose(np.asarray(psi(jnp.asarray(real))), real_reference, rtol=1e-12)


@pytest.mark.parametrize("damping", [0.0, 0.05, 0.2, 0.9])
def test_resolved_propagation_equals_the_per_piece_psi_path(damping):
    """The exact path's law-only series kicks (``resolved=True``) against the per-piece
    ``psi`` kicks, up to the largest ``w h`` a grid may carry (``MAX_PHASE_STEP``): a
    polynomial, an SCCA with pieces of very different widths (short ones at 1e-3), and an
    SCCA laid out from traced breakpoints (eight pieces, some of zero width)."""
    from camjax.sdof import MAX_PHASE_STEP, SampledLaw, motion_grid, propagate

    grids = [SampledLaw.of(laws.get("poly4567"), 192).grid,
             SampledLaw.of(laws.SCCA(0.002, 0.996, 0.002), 192).grid,
             jax.jit(lambda f: motion_grid(laws.SCCA(*f), 192))(jnp.array([0.3, 0.0, 0.7]))]
    for grid in grids:
        widest = float(jnp.max(grid.piece_width))
        for fraction in (1e-3, 0.3, 1.0):
            w = fraction * MAX_PHASE_STEP / widest
            exact = propagate(grid, w, damping)
            fast = propagate(grid, w, damping, resolved=True)
            scale = float(jnp.max(jnp.abs(exact)))
            assert float(jnp.max(jnp.abs(fast - exact))) <= 1e-13 * scale


def test_a_sweep_on_a_grid_too_coarse_is_refused_before_any_work():
    """A grid of w h > MAX_PHASE_STEP (1.5) at the largest ratio would give untrusted
    refined peaks: refused at the sweep (and the solve) with the grid that would do, as a
    traced ratio is."""
    message = (r"period ratio must be at most 61\.11 on a grid of resolution 256 \(give "
               r"resolution >= 4\.19 n\), got 62")
    with pytest.raises(ValueError, match=message):
        camjax.ct_curve("cycloidal", [1.0, 62.0], resolution=256)
    with pytest.raises(ValueError, match=message):
        camjax.solve("cycloidal", camjax.SpringMass(62.0), resolution=256)
    camjax.ct_curve("cycloidal", [1.0, 61.0], resolution=256)  # within it


def test_raw_options_with_a_traced_ratio_past_the_grid_raise_when_run():
    """Options built without ``checked`` and a traced period ratio: the exact path checks
    the ratio against the grid when it runs, never returning a number from it."""
    options = camjax.models.SpringMassOptions(resolution=64)

    def ct(n):
        return response_metrics(laws.Cycloidal(), camjax.SpringMass(n), options).ct

    assert np.isfinite(float(jax.jit(ct)(15.0)))
    with pytest.raises(Exception, match=r"period ratio must be at most 15\.27 on a grid of resolution 64"):
        jax.block_until_ready(jax.jit(ct)(16.0))


def test_sampled_laws_are_kept_by_value_and_the_oldest_dropped():
    """``SampledLaw.of`` returns the kept sampling for a law of equal values (a law named
    again is a new object), samples anew for other values, resolution or padding, and
    keeps exactly ``SAMPLED_LAWS_KEPT``, the least recently used dropped first."""
    from camjax.sdof import SAMPLED_LAWS_KEPT, SampledLaw

    first = SampledLaw.of(laws.SCCA(0.3, 0.1, 0.6), 256)
    assert SampledLaw.of(laws.SCCA(0.3, 0.1, 0.6), 256) is first
    other = SampledLaw.of(laws.SCCA(0.3, 0.2, 0.5), 256)
    assert other is not first and not np.allclose(other.grid.forcing, first.grid.forcing)
    assert SampledLaw.of(laws.SCCA(0.3, 0.1, 0.6), 320) is not first
    assert SampledLaw.of(laws.SCCA(0.3, 0.1, 0.6), 256, 16) is not first
    assert SampledLaw.of(laws.SCCA(0.3, 0.1, 0.6), 256) is first  # the most recently used now
    filled = [SampledLaw.of(laws.SCCA(0.1 + 0.001 * i, 0.0, 0.5), 128) for i in range(SAMPLED_LAWS_KEPT)]
    # all of the last SAMPLED_LAWS_KEPT are kept (asked in the order they came: none dropped) ...
    assert all(SampledLaw.of(laws.SCCA(0.1 + 0.001 * i, 0.0, 0.5), 128) is kept
               for i, kept in enumerate(filled))
    # ... and no more: the one used just before them was dropped.
    again = SampledLaw.of(laws.SCCA(0.3, 0.1, 0.6), 256)
    assert again is not first
    np.testing.assert_array_equal(again.grid.forcing, first.grid.forcing)


def test_sampling_refuses_too_few_pieces_and_names_what_cannot_be_sampled():
    from camjax.sdof import SampledLaw

    law = laws.SCCA(0.2, 0.3, 0.3)  # with a constant-velocity part: 8 pieces
    with pytest.raises(ValueError, match="has 8 pieces, more than 4"):
        SampledLaw.of(law, 128, 4)
    SampledLaw.of(law, 128, 8)  # kept: a later refusal does not hit the kept sampling
    with pytest.raises(ValueError, match="has 8 pieces, more than 4"):
        SampledLaw.of(law, 128, 4)
    assert SampledLaw.padded_pieces(law) == 8 == SampledLaw.pieces_if_sampled(law)
    assert SampledLaw.padded_pieces(laws.get("cycloidal")) == 8
    assert SampledLaw.pieces_if_sampled("cycloidal") is None  # not a law object
    assert not SampledLaw.accepts("cycloidal")
    with pytest.raises(ValueError, match="cannot be sampled"):
        SampledLaw.of("cycloidal", 128)
    seen = []

    def traced(a):  # a law built from a traced fraction has traced breakpoints
        law = laws.SCCA(a, 0.3, 0.3)
        seen.append((SampledLaw.pieces_if_sampled(law), SampledLaw.accepts(law)))
        with pytest.raises(ValueError, match="cannot be sampled"):
            SampledLaw.of(law, 128)
        return a

    jax.jit(traced)(0.2)
    assert seen == [(None, False)]


def test_a_stack_of_boundary_polynomials_has_each_laws_exact_ca():
    """Nine degree-7 rest-to-rest laws sweep as one stack, whose Ca is taken traced; each
    has two nearly equal crests of |a| (the first 7.520366 at 0.277 and 7.520347 at 0.724),
    where refining only the best sample can find the lower one."""
    family = [laws.get(f"polynomial7:0,0,{j:g},0,0,0") for j in np.linspace(-0.4, 0.4, 9)]
    n = np.linspace(1.0, 5.0, 7)
    curves = camjax.ct_curves(family, n)
    for law in family:
        exact = law.peak_coefficients()["Ca"]  # roots of the polynomial's derivative
        assert curves[law.name].ca == pytest.approx(exact, rel=1e-12)
    assert family[0].peak_coefficients()["Ca"] == pytest.approx(7.520366, abs=1e-6)
    alone = camjax.ct_curve(family[0], n)
    np.testing.assert_allclose(curves[family[0].name].ca_ct, alone.ca_ct, rtol=1e-10)


def test_the_default_template_is_kept_and_bad_options_refused_every_time():
    from camjax.sweep import prepare_sweep

    for _ in range(2):
        with pytest.raises(ValueError, match="damping"):
            prepare_sweep([1.0, 2.0], damping=1.5)
        with pytest.raises(ValueError, match="resolution must be at least 8"):
            prepare_sweep([1.0, 2.0], resolution=4)
    _, template, options = prepare_sweep([1.0, 2.0], damping=0.1)
    _, again, same = prepare_sweep(np.array([1.0, 1.5, 2.0]), damping=0.1)
    assert again is template and same is options  # the same first and largest ratio
    _, _, finer = prepare_sweep([1.0, 2.0], damping=0.1, resolution=256)
    assert finer.resolution == 256 != options.resolution
    _, other, _ = prepare_sweep([1.0, 2.0], damping=0.2)
    assert float(other.damping) == 0.2
    # A refused float must not stand in for the equal integer, nor the reverse.
    with pytest.raises(ValueError, match="max_steps must be a positive integer"):
        prepare_sweep([1.0, 2.0], method="tsit5", max_steps=2.5)
    assert prepare_sweep([1.0, 2.0], method="tsit5", max_steps=1e5)[2].max_steps == 100_000
    assert isinstance(prepare_sweep([1.0, 2.0], method="tsit5", max_steps=100_000)[2].max_steps, int)
    # A call while tracing is refused before anything is built (a curve is concrete), so
    # it keeps no tracer.
    with pytest.raises(ValueError, match="runs outside jit, vmap and grad"):
        jax.jit(lambda a: camjax.ct_curve(laws.SCCA(a, 0.0, 1.0 - a), [1.0, 2.0],
                                          dwell=1.25).ct)(0.5)
    _, kept, _ = prepare_sweep([1.0, 2.0], dwell=1.25)
    assert not isinstance(kept.damping, jax.core.Tracer)
    assert np.isfinite(camjax.ct_curve("cycloidal", [1.0, 2.0], dwell=1.25).ct).all()


def test_response_between_nodes_matches_scipy():
    """``solve``'s samples at thirds of the grid's intervals (the exact states between
    nodes) and at the nodes, against scipy's DOP853 at tight tolerance, on the default
    grid: samples at most 0.5 radians of the vibration apart."""
    law, n, zeta = laws.Cycloidal(), 29.0, 0.05
    w = 2 * math.pi * n
    response = camjax.solve(law, camjax.SpringMass(n, zeta))
    tau = np.asarray(response.tau)
    rise = tau <= 1.0
    nodes, thirds, two_thirds = tau[rise][0::3], tau[rise][1::3], tau[rise][2::3]
    np.testing.assert_allclose(thirds, nodes[:-1] + (nodes[1:] - nodes[:-1]) / 3, rtol=1e-14)
    np.testing.assert_allclose(two_thirds, nodes[:-1] + 2 * (nodes[1:] - nodes[:-1]) / 3,
                               rtol=1e-14)
    assert nodes.size - 1 >= camjax.models.SpringMassOptions().checked(n).resolution
    assert w * np.max(np.diff(tau)) <= 0.5

    def rhs(t, y):
        return [y[1], float(law.a(t)) - w * w * y[0] - 2 * zeta * w * y[1]]

    sol = solve_ivp(rhs, (0, 1), [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    t_eval=tau[rise])
    np.testing.assert_allclose(np.asarray(response.deflection)[rise], sol.y[0],
                               rtol=0, atol=1e-10 * np.max(np.abs(sol.y[0])))


@pytest.mark.parametrize("damping", [0.0, 0.2])
def test_short_sine_pieces_at_the_coarsest_default_grid(damping):
    """An SCCA law of the face with quarter sines 0.005 wide, at the default grid of the
    coarsest band (128 intervals, n <= 20), against four times that grid: within 1e-10
    (with one interval per short piece it was 2.8e-9 at damping 0.2, near n = 0.89)."""
    n = np.linspace(0.5, 20.0, 400)
    law = laws.SCCA(0.01, 0.98, 0.01)
    default = camjax.ct_curve(law, n, damping=damping)
    fine = camjax.ct_curve(law, n, damping=damping, resolution=512)
    assert np.max(np.abs(default.ct - fine.ct)) < 1e-10
    assert np.max(np.abs(default.residual - fine.residual)) < 1e-11
