"""Flexible swinging follower: beam frequencies, quasi-static deflection, constraints, spectra."""

import json
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import cumulative_simpson
from scipy.optimize import brentq

import camjax
from camjax.models import FollowerOptions, SwingingFollower, spectral_peaks, spectrum


def pinned_pinned_rayleigh(model, k):
    """Closed-form k-th bending frequency of a pinned-pinned Rayleigh beam (rad/s)."""
    E, rho, A, I, l = model.youngs_modulus, model.density, model.area, model.second_moment, model.length
    wave = k * math.pi / l
    return math.sqrt(E * I * wave**4 / (rho * A * (1 + I / A * wave**2)))


@pytest.mark.parametrize("radius", [0.005, 0.010])
def test_bending_frequencies_match_pinned_pinned_rayleigh_beam(radius):
    model = SwingingFollower(modes=4, rod_radius=radius)
    freqs = np.asarray(model.natural_frequencies())
    assert freqs[0] == pytest.approx(pinned_pinned_rayleigh(model, 1), rel=1e-9)
    for k in (1, 2, 3):
        assert np.min(np.abs(freqs / pinned_pinned_rayleigh(model, k) - 1)) < 1e-9
    # The paper's spectral peak near the fundamental sits at about 41.5 Omega for l = 98 mm, r = 5 mm.
    if radius == 0.005:
        assert freqs[0] / model.omega == pytest.approx(41.5, abs=0.2)


def test_axial_frequency_converges_to_rod_with_end_mass():
    # At the low dwell the groove is tangent to the rod: the end slides axially, carrying the
    # roller mass plus its rolling inertia J_r / r_r^2 = m_r / 2.  Exact: z tan z = m_rod / m_end.
    model = SwingingFollower(modes=10)
    end_mass = 1.5 * model.roller_mass
    rod_mass = model.density * model.area * model.length
    z = brentq(lambda z: z * math.tan(z) - rod_mass / end_mass, 1e-6, math.pi / 2 - 1e-9)
    exact = z / model.length * math.sqrt(model.youngs_modulus / model.density)
    freqs = np.asarray(model.natural_frequencies())
    assert np.min(np.abs(freqs / exact - 1)) < 1e-4


def test_quasi_static_rigid_limit_and_constraints():
    """The forced response in the rise against the closed-form pinned-pinned beam under its
    inertia load (a rod 100 times stiffer, where the response is quasi-static), and the
    deflections' 1/E scaling.  Runs by default: 9 s on the loaded 2-core machine."""
    nominal = SwingingFollower(modes=3)
    stiff = SwingingFollower(modes=3, youngs_modulus=100 * nominal.youngs_modulus)
    turns = 0.2  # inside the 90-degree rise
    soft_run = camjax.solve(None, nominal, turns=turns, samples_per_turn=360)
    stiff_run = camjax.solve(None, stiff, turns=turns, samples_per_turn=360)
    # Rigid-rod limit: deflections scale with 1/E once the rod is far stiffer than the forcing.
    assert float(jnp.max(jnp.abs(stiff_run.transverse))) < 0.015 * float(jnp.max(jnp.abs(soft_run.transverse)))
    assert float(jnp.max(jnp.abs(stiff_run.axial_end))) < 0.015 * float(jnp.max(jnp.abs(soft_run.axial_end)))
    # Quasi-static check against the closed-form pinned-pinned beam under the triangular inertia
    # load q(x) = -rho A psi'' x (the uniform rotary-inertia moment bends nothing).  What remains
    # is the free vibration started at theta = 0 (about 2% of the static value at 100 E).
    theta = np.asarray(stiff_run.cam_angle)
    _, _, d2y, _ = stiff.program.evaluate(theta)
    psi_ddot = -(stiff.omega**2) * np.asarray(d2y)
    l, x = stiff.length, 0.5 * stiff.length
    E, I = stiff.youngs_modulus, stiff.second_moment
    q0 = -stiff.density * stiff.area * psi_ddot * l
    static = q0 * x * (7 * l**4 - 10 * l**2 * x**2 + 3 * x**4) / (360 * l * E * I)
    middle = (theta > 0.3) & (theta < 1.2)
    scale = np.max(np.abs(static))
    np.testing.assert_allclose(np.asarray(stiff_run.transverse)[middle], static[middle], atol=0.025 * scale)
    # The roller stays in the groove: drift far below the deflections (nm against um).
    for run in (soft_run, stiff_run):
        assert float(run.max_constraint_error) < 1e-10
        assert float(run.max_constraint_error) < 1e-4 * float(jnp.max(jnp.abs(run.transverse)))


@eqx.filter_jit
def _static_equilibrium(model, cam_angle=1.75 * math.pi):
    """Rest deflection in the low dwell, where L is stationary on the constraint's tangent space."""
    t = cam_angle / model.omega
    zero = jnp.zeros(model.size)
    load = jax.grad(model.lagrangian)(zero, zero, t)  # -dV/dq: gravity (strain energy has no linear term)
    stiffness = -jax.hessian(model.lagrangian)(zero, zero, t)
    _, _, vt = jnp.linalg.svd(jax.jacfwd(model.constraint)(zero, t))
    basis = vt[2:].T
    return basis @ jnp.linalg.solve(basis.T @ stiffness @ basis, basis.T @ load), model._swing(t)[0]


def test_gravity_static_deflection_matches_pinned_beam_and_bar():
    # In the low dwell the rod is perpendicular to the cam radius, so the groove is tangent to
    # the rod: it holds the roller end transversely (a pinned-pinned beam under the transverse
    # component of the rod's weight; the roller's weight goes straight into the groove) and lets
    # it slide axially (a bar pinned at the pivot under the axial component of the rod's and
    # the roller's weight).
    g = 9.81
    model = SwingingFollower(modes=5, gravity=jnp.asarray(g))
    q, psi = _static_equilibrium(model)
    psi = float(psi)
    E, rho, A, I, l = model.youngs_modulus, model.density, model.area, model.second_moment, model.length
    transverse_load, axial_load = -rho * A * g * math.cos(psi), -rho * A * g * math.sin(psi)
    assert abs(math.cos(psi)) > 0.5 and abs(math.sin(psi)) > 0.2  # both components matter here
    n = model.n_axial
    mid = float(model.shapes(jnp.array([l / 2]))[0][0] @ q[n : n + model.modes])
    beam = 5 * transverse_load * l**4 / (384 * E * I)
    # Ritz with sin(pi x/l), sin(3 pi x/l): 4 q l^4 / (pi^5 E I) (1 - 3^-5), 2.6e-4 below the beam.
    ritz = 4 * transverse_load * l**4 / (math.pi**5 * E * I) * (1 - 3.0**-5)
    assert mid == pytest.approx(ritz, rel=1e-9)
    assert mid == pytest.approx(beam, rel=5e-4)
    # The x/l mode alone gives the exact end displacement of the bar for any axial load (the
    # unit-load theorem: x/l is the bar's deflection under an end force), which is why dropping
    # the axial sin modes (axial_modes=1) leaves the quasi-static u(l) unchanged.
    end_force = -model.roller_mass * g * math.sin(psi)
    assert float(q[0]) == pytest.approx((axial_load * l**2 / 2 + end_force * l) / (E * A), rel=1e-9)
    # Gravity off (the default): no static deflection (same compiled function: g is traced).
    off, _ = _static_equilibrium(eqx.tree_at(lambda m: m.gravity, model, jnp.asarray(0.0)))
    assert float(jnp.max(jnp.abs(off[:-1]))) < 1e-9 * abs(mid)


@eqx.filter_jit
def _energy_along(model, q, qdot, t):
    """Energy function and its supply along a motion, minus their values for the rigid rod.

    The supply's two batches (the motion and the rigid rod) go through one vmap: two
    independent batched LU solves in one program can wedge XLA's CPU runtime on two cores
    (both pool threads wait inside LAPACK's batch split for workers the other holds; seen
    in CI as a hang of this test, every thread in a futex wait)."""
    zero = jnp.zeros_like(q)
    h = jax.vmap(model.energy_function)
    both = jax.vmap(model.energy_supply)(jnp.concatenate([q, zero]), jnp.concatenate([qdot, zero]),
                                         jnp.concatenate([t, t]))
    supply, rigid = jnp.split(both, 2)
    return h(q, qdot, t) - h(zero, zero, t), supply - rigid


def test_energy_balance_over_rise_and_conservation_in_dwell():
    # The swing frame and the cam speed are prescribed, so T + U + V is not conserved.  What the
    # model must satisfy is Jacobi's balance dh/dt = -dL/dt - lambda . Phi_q qdot: the energy
    # function h = qdot . dL/dqdot - L changes by the power that the prescribed motions and the
    # groove feed in.  The rigid rod (q = 0) obeys it trivially, so the check is made on the
    # part due to the deflections, e = h - h_rigid, against the integral of the supply minus
    # the rigid rod's: it tests the AD-derived mass matrix and velocity terms, the multipliers
    # and the solver together.  In the dwell the groove is a circle about the cam centre and
    # the swing is at rest: the supply vanishes and e is the rod's vibration energy, which
    # must stay constant (neither Baumgarte nor the solver may dissipate it).
    # Rise and high dwell, one bending mode, gravity on.
    model = SwingingFollower(modes=2, axial_modes=1, gravity=9.81)
    run = camjax.solve(None, model, turns=0.5, samples_per_turn=4096)
    angle, t = np.degrees(np.asarray(run.cam_angle)), np.asarray(run.t)
    e, supply = (np.asarray(x) for x in _energy_along(model, run.coordinates, run.velocities, run.t))
    work = cumulative_simpson(supply, x=t, initial=0.0)
    assert np.max(np.abs(e - e[0] - work)) < 1e-5 * np.max(np.abs(e))  # measured 5e-7
    dwell = (angle > 92) & (angle < 178)
    assert np.max(np.abs(supply[dwell])) < 1e-6 * np.max(np.abs(supply))
    assert np.min(e[dwell]) > 0
    assert np.ptp(e[dwell]) < 1e-5 * np.mean(e[dwell])  # measured 3e-7
    assert float(run.max_constraint_error) < 1e-10


def test_spectrum_recovers_harmonic_amplitudes():
    turns, per_turn = 3, 256
    phase = 2 * math.pi * np.arange(turns * per_turn) / per_turn
    signal = 0.7 * np.sin(3 * phase + 0.4) + 0.2 * np.cos(5 * phase) + 0.05 * np.sin(124 / 3 * phase)
    harmonics, near = spectral_peaks(spectrum(signal, turns), natural_order=41.4)
    assert dict(harmonics)[3.0] == pytest.approx(0.7, rel=1e-12)
    assert dict(harmonics)[5.0] == pytest.approx(0.2, rel=1e-12)
    assert dict(harmonics)[1.0] < 1e-3
    assert near == pytest.approx((124 / 3, 0.05), rel=1e-12)


@pytest.mark.parametrize(
    "kwargs, message",
    [({"modes": 0}, "modes"), ({"length": -0.1}, "length"), ({"total_swing": 2.0}, "total_swing")],
)
def test_bad_parameters_raise(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SwingingFollower(**kwargs)


def _cli(argv):
    import argparse

    from camjax.cli import CliError, follower

    parser = argparse.ArgumentParser(prog="camjax")
    follower.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["follower", *argv])
    try:
        return args.func(args)
    except (CliError, ValueError) as error:
        return str(error)


@pytest.mark.parametrize(
    "argv, message",
    [(["--law", "nope"], "unknown law"), (["--law", "cycloidal", "--omega", "-3"], "--omega"), (["--law", "cycloidal", "--modes", "0"], "modes")],
)
def test_cli_rejects_bad_arguments(argv, message):
    assert message in _cli(argv)


@pytest.mark.slow
def test_cli_json_report(tmp_path, capsys):
    """Slow: the follower command end to end (four laws, their spectra and figures)."""
    import json

    assert _cli(["--law", "cycloidal", "--format", "json", "--out", str(tmp_path)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report == json.loads((tmp_path / "follower.json").read_text())
    model = SwingingFollower()
    assert report["natural_frequency_rad_s"] == pytest.approx(pinned_pinned_rayleigh(model, 1), rel=1e-9)
    orders = [p["order"] for p in report["transverse_peaks"]]
    assert orders[:5] == [1.0, 3.0, 5.0, 7.0, 9.0] and abs(orders[5] - report["natural_order"]) <= 3
    # The paper: the transverse spectrum peaks at 3 Omega, and axial amplitudes are far smaller.
    amplitudes = [p["amplitude_mm"] for p in report["transverse_peaks"]]
    assert max(amplitudes) == amplitudes[1]
    assert max(p["amplitude_mm"] for p in report["axial_peaks"]) < 0.1 * max(amplitudes)
    assert report["max_constraint_error"] < 1e-10


def _lagrangian_by_quadrature(model, q, qdot, t, jets):
    """``T - V`` integrated over the rod at the quadrature nodes, the roller's translation
    and spin written apart: the model's energies as first written, independent of its
    ``RodIntegrals``."""
    swing, contact = jets
    x, w = model._quadrature()
    a, b, delta = model._split(q)
    adot, bdot, ddelta = model._split(qdot)
    psi, psidot = model._swing(t, swing)
    phi, dphi, ddphi = model.shapes(x)
    phi_a, dphi_a, _ = model.shapes(x, model.n_axial)
    u, v, udot, vdot, slope_rate = phi_a @ a, phi @ b, phi_a @ adot, phi @ bdot, dphi @ bdot
    rho, area, inertia = model.density, model.area, model.second_moment
    along, across = udot - v * psidot, vdot + (x + u) * psidot
    t_rod = 0.5 * rho * jnp.sum(w * (area * (along**2 + across**2) + inertia * (psidot + slope_rate) ** 2))
    end_along, end_across = adot[0] - b[0] * psidot, bdot[0] + (model.length + a[0]) * psidot
    theta_c = model.omega * t + delta
    pitch = lambda s: camjax.geometry.pitch_point(model.follower, contact, s)  # noqa: E731
    pitch_speed = jnp.linalg.norm(jax.jvp(pitch, (theta_c,), (jnp.ones_like(theta_c),))[1])
    spin = model.omega - pitch_speed * (model.omega + ddelta) / model.roller_radius
    t_roller = 0.5 * model.roller_mass * (end_along**2 + end_across**2) + 0.5 * model.roller_inertia * spin**2
    strain = 0.5 * model.youngs_modulus * jnp.sum(w * (area * (dphi_a @ a) ** 2 + inertia * (ddphi @ b) ** 2))
    height = (x + u) * jnp.sin(psi) + v * jnp.cos(psi)
    end_height = (model.length + a[0]) * jnp.sin(psi) + b[0] * jnp.cos(psi)
    potential = model.gravity * (rho * area * jnp.sum(w * height) + model.roller_mass * end_height)
    return t_rod + t_roller - strain - potential


@eqx.filter_jit
def _accelerations_by_differentiation(model, q, qdot, t):
    """``(qddot, lambda)`` with the mass matrix, the forces and the constraint's terms all
    from automatic differentiation of the quadrature Lagrangian and ``model.constraint``."""
    jets = model.expansions(q, t)
    lagrangian = lambda q_, qd_, t_: _lagrangian_by_quadrature(model, q_, qd_, t_, jets)  # noqa: E731
    momentum = jax.grad(lagrangian, argnums=1)
    mass = jax.jacfwd(momentum, argnums=1)(q, qdot, t)
    _, momentum_rate = jax.jvp(momentum, (q, qdot, t), (qdot, jnp.zeros_like(qdot), jnp.ones_like(t)))
    force = jax.grad(lagrangian)(q, qdot, t) - momentum_rate
    constraint = lambda q_, t_: model.constraint(q_, t_, jets)  # noqa: E731
    jac = jax.jacfwd(constraint)(q, t)
    velocity = lambda q_, t_: jax.jvp(constraint, (q_, t_), (qdot, jnp.ones_like(t_)))[1]  # noqa: E731
    phi_dot, phi_ddot_free = jax.jvp(velocity, (q, t), (qdot, jnp.ones_like(t)))
    beta = model.baumgarte
    rhs = -phi_ddot_free - 2 * beta * phi_dot - beta**2 * constraint(q, t)
    system = jnp.block([[mass, jac.T], [jac, jnp.zeros((2, 2))]])
    solution = jnp.linalg.solve(system, jnp.concatenate([force, rhs]))
    return solution[: model.size], solution[model.size :], lagrangian(q, qdot, t)


@pytest.mark.parametrize("kwargs", [{}, {"modes": 4, "axial_modes": 2, "gravity": 9.81}])
def test_written_out_equations_equal_the_lagrangian_differentiated(kwargs):
    # The equations of motion are written out from the rod's integrated energies; here the
    # Lagrangian integrated at the quadrature nodes, differentiated by JAX, with the
    # constraint's terms by JAX too, gives the same accelerations and multipliers, in the
    # rise, the return and the low dwell, deflected and moving.
    model = SwingingFollower(**kwargs).with_array_leaves()
    keys = jax.random.split(jax.random.PRNGKey(0), 2)
    q = 1e-4 * jax.random.normal(keys[0], (model.size,))
    qdot = 1e-1 * jax.random.normal(keys[1], (model.size,))
    accelerations = eqx.filter_jit(lambda m, q, qdot, t: m.accelerations(q, qdot, t))
    energy = eqx.filter_jit(lambda m, q, qdot, t: m.lagrangian(q, qdot, t, m.expansions(q, t)))
    for angle in (0.3 * math.pi, 1.2 * math.pi, 1.75 * math.pi):
        t = jnp.asarray(angle / model.omega)
        qddot, multipliers, lagrangian = _accelerations_by_differentiation(model, q, qdot, t)
        got_qddot, got_multipliers = accelerations(model, q, qdot, t)
        np.testing.assert_allclose(got_qddot, qddot, rtol=0, atol=1e-13 * float(jnp.max(jnp.abs(qddot))))
        np.testing.assert_allclose(got_multipliers, multipliers, rtol=0,
                                   atol=1e-13 * float(jnp.max(jnp.abs(multipliers))))
        assert float(energy(model, q, qdot, t)) == pytest.approx(float(lagrangian), rel=1e-13)


@eqx.filter_jit
def _frequencies_by_differentiation(model, cam_angle):
    """The rod's stiffness and mass at rest at ``cam_angle`` on the motions the groove allows:
    the quadrature Lagrangian's Hessians and the constraint's Jacobian, all by automatic
    differentiation (their generalised eigenvalues are the frequencies squared)."""
    t = cam_angle / model.omega
    zero = jnp.zeros(model.size)
    jets = model.expansions(zero, t)
    lagrangian = lambda q, qdot: _lagrangian_by_quadrature(model, q, qdot, t, jets)  # noqa: E731
    mass = jax.hessian(lagrangian, argnums=1)(zero, zero)
    stiffness = -jax.hessian(lagrangian)(zero, zero)
    _, _, vt = jnp.linalg.svd(jax.jacfwd(model.constraint)(zero, t, jets))
    basis = vt[2:].T
    return basis.T @ stiffness @ basis, basis.T @ mass @ basis


@pytest.mark.parametrize("angle", [0.3 * math.pi, 1.2 * math.pi, 1.75 * math.pi])
def test_written_out_frequencies_equal_the_lagrangian_differentiated(angle):
    # In the rise and the return the swing's rate softens the rod and the pitch curve's
    # speed changes along the cam (the spin's stiffness), so both terms are exercised.
    model = SwingingFollower(modes=3, axial_modes=2, omega=2000.0)
    stiffness, mass = (np.asarray(x) for x in _frequencies_by_differentiation(model, angle))
    expected = np.sqrt(np.clip(scipy.linalg.eigh(stiffness, mass, eigvals_only=True), 0.0, None))
    np.testing.assert_allclose(model.natural_frequencies(angle), expected, rtol=1e-9)


@pytest.mark.slow  # 10 s of compiling; the energy balance test covers the same path by default
def test_accelerations_through_the_hoisted_jets_equal_the_laws_own_derivatives():
    # accelerations() evaluates the program once, as cubic jets about the primal cam angles, and
    # differentiates those; the equations of motion need derivatives up to third order only, so
    # this must equal differentiating the laws' piecewise formulas directly, mid-rise and
    # mid-return, deflected and moving.
    model = SwingingFollower(modes=2, axial_modes=1, gravity=9.81).with_array_leaves()
    keys = jax.random.split(jax.random.PRNGKey(3), 2)
    q = 1e-4 * jax.random.normal(keys[0], (model.size,))
    qdot = 1e-1 * jax.random.normal(keys[1], (model.size,))
    accelerations = eqx.filter_jit(lambda m, q, qdot, t, jets: m.accelerations(q, qdot, t, jets))
    for angle in (0.3 * math.pi, 1.2 * math.pi):
        t = angle / model.omega
        direct = accelerations(model, q, qdot, t, (model.program, model.program))
        for got, want in zip(accelerations(model, q, qdot, t, None), direct):
            np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10 * float(jnp.max(jnp.abs(want))))


def test_a_deflection_larger_than_the_rod_is_warned_about(capsys):
    """At 100,000 rad/s the cam outruns the rod's fundamental (0.13 Omega) and the rod
    deflects by more than its radius: the run reports, and says on stderr that it lies
    outside the small-deflection beam model."""
    from camjax.cli import main

    assert main(["follower", "--law", "cycloidal", "--omega", "1e5", "--format", "json"]) == 0
    captured = capsys.readouterr()
    report = json.loads(captured.out)
    deflection = max(report["max_transverse_mm"], report["max_axial_mm"])
    assert deflection > report["radius_mm"]
    assert captured.err.strip() == (
        f"warning: the rod deflects by {deflection:.3g} mm, more than its radius (5 mm): far "
        "outside the small-deflection beam model; lower --omega or stiffen the rod (--radius, --length)")


def test_solve_inside_a_callers_jit_equals_the_solve_outside():
    """The follower's solve compiles with its own XLA options on CPU; inside a caller's
    ``jit`` it is inlined without them (JAX refuses options on a nested program, which
    used to fail the call) and gives the same response, within the solver's absolute
    tolerance (the two programs round differently, and the adaptive steps follow: 3.3e-12
    measured, on deflections up to 1.8e-5)."""
    model = SwingingFollower(modes=2, axial_modes=1)
    outside = camjax.solve(None, model, turns=0.25, samples_per_turn=256)
    inside = jax.jit(lambda: camjax.solve(None, model, turns=0.25, samples_per_turn=256))()
    np.testing.assert_allclose(np.asarray(inside.coordinates), np.asarray(outside.coordinates),
                               rtol=0, atol=FollowerOptions().atol)
