"""Two-mass model (elastic input drive): limits that reduce it to the SDOF, energy balance."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

import camjax
from camjax.models import TwoMass

OPTIONS = dict(samples=1024)  # one static setting: the model compiles once per law


def two_mass_ct_curve(law, n, k, m, **options):
    curve = camjax.ct_curve(law, n, model=TwoMass(1.0, k, m), **options)
    return curve.ct, curve.residual


def two_mass_response(law, model, **options):
    return camjax.solve(law, model, **options)


@pytest.fixture(scope="module")
def law():
    return camjax.laws.ModifiedSine()


@pytest.fixture(scope="module")
def rigid(law):
    return camjax.ct_curve(law, [3.0, 6.4])


def test_converges_to_rigid_input_sdof_as_stiffness_ratio_grows(law, rigid):
    errors = []
    for k in (10.0, 100.0, 1000.0):
        ct, residual = two_mass_ct_curve(law, rigid.period_ratio, k, 1.0, **OPTIONS)
        errors.append(np.max(np.abs(ct - rigid.ct)))
        if k == 1000.0:
            np.testing.assert_allclose(residual, rigid.residual, rtol=2e-2)
    # The camshaft's lag falls as 1/k, and so does the distortion of the command.
    assert errors[0] > 5 * errors[1] > 25 * errors[2]
    assert errors[2] < 2e-3


def test_unloaded_camshaft_is_exactly_the_sdof(law, rigid):
    """With no payload inertia on the camshaft (m = 0) it turns rigidly: the SDOF exactly."""
    ct, residual = two_mass_ct_curve(law, rigid.period_ratio, 1.0, 0.0, **OPTIONS)
    # Both refine Ct between samples with camjax.metrics.refined_peak (Hermite); what is
    # left is the integration error (Dopri8, rtol 1e-10): 3e-9 at n = 3 (a parabola
    # through three of the 2048 samples was good to 1e-6 only).
    np.testing.assert_allclose(ct, rigid.ct, rtol=1e-8)
    np.testing.assert_allclose(residual, rigid.residual, rtol=1e-7)


def test_energy_balance_motor_work_equals_stored_energy(law):
    """The motor's work, integral of w_i^2 phi, equals the system's energy gain.

    Energy per ``I beta^2 / T^2``: camshaft ``theta'^2 / 2``, input shaft ``w_i^2 phi^2 / 2``,
    payload ``m (x'^2 + w^2 e^2) / 2`` with ``x' = v(theta) theta' - e'``.  A wrong sign or
    factor in the cam's reaction torque breaks the balance.
    """
    model = TwoMass(4.0, 2.0, 0.5)
    r = two_mass_response(law, model, **OPTIONS)
    w, wi, m = float(model.omega), float(model.input_omega), 0.5
    tau, phi, e = np.asarray(r.tau), np.asarray(r.twist), np.asarray(r.deflection)
    dphi, de = np.asarray(r.twist_rate), np.asarray(r.deflection_rate)
    h = tau[1] - tau[0]
    theta = tau - phi
    dtheta = 1.0 - dphi
    dx = np.asarray(law.v(theta)) * dtheta - de
    energy = 0.5 * dtheta**2 + 0.5 * wi**2 * phi**2 + m * 0.5 * (dx**2 + w**2 * e**2)
    work = cumulative_simpson(wi**2 * phi, dx=h, initial=0.0)
    scale = np.max(np.abs(energy - energy[0]))
    assert scale > 1e-2  # the balance is not trivially zero
    np.testing.assert_allclose(energy - energy[0], work, atol=1e-6 * scale)


@pytest.mark.slow
def test_stiff_and_implicit_solvers_agree(law):
    """Slow (21 s on the loaded 2-core machine, 2026-11-27): Kvaerno5, an implicit solver, compiles apart from Dopri8."""
    model = TwoMass(6.4, 3.0, 1.0)
    explicit = two_mass_response(law, model, **OPTIONS)
    implicit = two_mass_response(law, model, method="kvaerno5", **OPTIONS)
    assert float(explicit.metrics.ct) == pytest.approx(float(implicit.metrics.ct), rel=1e-6)
    np.testing.assert_allclose(explicit.deflection, implicit.deflection, atol=1e-9)


def test_vmap_equals_loop(law):
    ns = np.array([3.0, 6.4])
    ct, _ = two_mass_ct_curve(law, ns, 3.0, 1.0, **OPTIONS)
    for k, n in enumerate(ns):
        one = two_mass_response(law, TwoMass(float(n), 3.0, 1.0), **OPTIONS)
        assert float(one.metrics.ct) == pytest.approx(ct[k], rel=1e-8)


def test_bad_parameters_are_clear_errors(law):
    with pytest.raises(ValueError, match="stiffness_ratio"):
        TwoMass(5.0, 0.0, 1.0)
    with pytest.raises(ValueError, match="inertia_ratio"):
        TwoMass(5.0, 1.0, -1.0)
    with pytest.raises(ValueError, match="period ratio"):
        two_mass_ct_curve(law, [0.0], 1.0, 1.0)


def test_step_limit_raises_solver_error(law):
    """A step limit no solve can meet is a ``SolverError`` (7 s on the loaded 2-core
    machine, most of it compiling the solve for the new static limit)."""
    with pytest.raises(camjax.SolverError):
        two_mass_ct_curve(law, [6.4], 3.0, 1.0, samples=1024, max_steps=10)


@pytest.mark.slow
def test_gradient_of_ct_in_stiffness_ratio_matches_finite_differences(law):
    """Slow (22 s on the loaded 2-core machine, 2026-11-27): reverse mode through the two-mass Dopri8 solve compiles a program of its own."""
    def ct(k):
        return camjax.solve(law, TwoMass(4.0, k, 1.0), throw=False, **OPTIONS).metrics.ct

    g = float(jax.grad(ct)(jnp.asarray(3.0)))
    h = 1e-4
    fd = (float(ct(jnp.asarray(3.0 + h))) - float(ct(jnp.asarray(3.0 - h)))) / (2 * h)
    assert g == pytest.approx(fd, rel=1e-4)


def test_coupled_response_against_scipy_in_physical_coordinates():
    """At k = 3, m = 1 (far from both limits), against scipy (DOP853, rtol 1e-12) of the
    equations in the camshaft angle and the payload position from rest at speed:
    ``theta'' = w_i^2 (tau - theta) - m w^2 (s(theta) - x) v(theta)``, ``x'' = w^2 (s(theta) - x)``,
    ``theta(0) = x(0) = x'(0) = 0``, ``theta'(0) = 1``, with the cycloidal law in closed form."""
    from scipy.integrate import solve_ivp

    n, k, m = 4.0, 3.0, 1.0
    model = TwoMass(n, k, m)
    response = camjax.solve(camjax.laws.Cycloidal(), model, samples=256)
    w = 2 * np.pi * n
    wi2 = k * m * w**2

    def law(theta):
        if theta <= 0.0:
            return 0.0, 0.0
        if theta >= 1.0:
            return 1.0, 0.0
        return theta - np.sin(2 * np.pi * theta) / (2 * np.pi), 1.0 - np.cos(2 * np.pi * theta)

    def rhs(t, z):
        theta, dtheta, x, dx = z
        s, v = law(theta)
        e = s - x
        return [dtheta, wi2 * (t - theta) - m * w**2 * e * v, dx, w**2 * e]

    tau = np.asarray(response.tau)
    sol = solve_ivp(rhs, (0.0, tau[-1]), [0.0, 1.0, 0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    t_eval=tau)
    theta, _, x, _ = sol.y
    e = np.array([law(t)[0] for t in theta]) - x
    np.testing.assert_allclose(np.asarray(response.twist), tau - theta, rtol=0, atol=1e-7 * np.abs(tau - theta).max())
    np.testing.assert_allclose(np.asarray(response.payload_acceleration), w**2 * e, rtol=0,
                               atol=1e-6 * np.abs(w**2 * e).max())
    assert np.abs(tau - theta).max() > 1e-3  # the camshaft does lag
