"""Cam geometry and motion programs against closed forms."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from camjax import geometry
from camjax.laws import Cycloidal, LawBank, ModifiedSine, PolynomialLaw, RiseDwellFall

THETA = jnp.linspace(0.0, 2 * math.pi, 721)[:-1]


def test_program_segments_and_derivatives():
    lift = 0.3
    program = RiseDwellFall(Cycloidal(), ModifiedSine(), lift)
    y, dy, d2y, _ = program.evaluate(THETA)
    beta = math.pi / 2
    # Closed-form cycloidal rise and the dwells / mirrored fall.
    rise = THETA < beta
    t = np.asarray(THETA[rise]) / beta
    np.testing.assert_allclose(y[rise], lift * (t - np.sin(2 * np.pi * t) / (2 * np.pi)), atol=1e-14)
    np.testing.assert_allclose(y[(THETA >= beta) & (THETA <= math.pi)], lift, atol=1e-14)
    np.testing.assert_allclose(y[THETA >= 1.5 * math.pi], 0.0, atol=1e-14)
    # Derivatives are with respect to theta: compare with autodiff of the displacement.
    grad = jax.jit(jax.vmap(jax.grad(program.displacement)))(THETA)
    np.testing.assert_allclose(dy, grad, atol=1e-12)
    grad2 = jax.jit(jax.vmap(jax.grad(jax.grad(program.displacement))))(THETA + 1e-3)
    np.testing.assert_allclose(program.evaluate(THETA + 1e-3)[2], grad2, atol=1e-10)
    # Periodic.
    np.testing.assert_allclose(program.displacement(THETA + 2 * math.pi), y, atol=1e-12)


def test_program_rejects_overlong_segments():
    with pytest.raises(ValueError, match="exceeds a turn"):
        RiseDwellFall(Cycloidal(), Cycloidal(), 1.0, rise_angle=3.0, dwell_angle=3.0, fall_angle=1.0)


def test_law_bank_matches_each_law():
    laws = (Cycloidal(), ModifiedSine(), PolynomialLaw(3))
    tau = jnp.linspace(-0.1, 1.1, 97)
    evaluate = jax.jit(lambda law, t: law.evaluate(t))
    for i, law in enumerate(laws):
        bank = LawBank(laws, i)
        for got, want in zip(evaluate(bank, tau), evaluate(law, tau)):
            np.testing.assert_allclose(got, want, atol=1e-14)
        assert float(bank.Ca) == pytest.approx(float(law.Ca))
    values = jax.vmap(lambda i: LawBank(laws, i).s(0.3))(jnp.arange(3))
    np.testing.assert_allclose(values, [float(law.s(0.3)) for law in laws], atol=1e-14)


@pytest.mark.parametrize(
    "follower",
    [geometry.SwingingRollerFollower(), geometry.TranslatingRollerFollower(offset=0.01)],
)
def test_zero_lift_gives_circle_cam(follower):
    program = RiseDwellFall(Cycloidal(), Cycloidal(), 0.0)
    prof = geometry.cam_profile(follower, program, THETA)
    rp, rr = follower.pitch_radius, follower.roller_radius
    np.testing.assert_allclose(jnp.linalg.norm(prof.pitch, axis=1), rp, rtol=1e-12)
    np.testing.assert_allclose(jnp.linalg.norm(prof.inner, axis=1), rp - rr, rtol=1e-12)
    np.testing.assert_allclose(jnp.linalg.norm(prof.outer, axis=1), rp + rr, rtol=1e-12)
    np.testing.assert_allclose(prof.pitch_radius_of_curvature, rp, rtol=1e-10)
    np.testing.assert_allclose(prof.inner_radius_of_curvature, rp - rr, rtol=1e-10)
    assert not bool(jnp.any(geometry.undercut(prof, rr).inner))


@pytest.mark.parametrize("offset", [0.0, 0.012, -0.008])
def test_translating_pressure_angle_closed_form(offset):
    follower = geometry.TranslatingRollerFollower(offset=offset, roller_radius=0.01, base_radius=0.04)
    program = RiseDwellFall(PolynomialLaw(3), Cycloidal(), 0.02)
    prof = geometry.cam_profile(follower, program, THETA)
    s, ds, _, _ = program.evaluate(THETA)
    s0 = math.sqrt(follower.pitch_radius**2 - offset**2)
    # tan(alpha) = (ds/dtheta - e) / (s + sqrt(r_p^2 - e^2)); zero offset: ds/(r_b + r_r + s).
    expected = np.arctan((np.asarray(ds) - offset) / (np.asarray(s) + s0))
    np.testing.assert_allclose(np.abs(prof.pressure_angle), np.abs(expected), atol=1e-12)


def test_flanks_are_envelopes_of_roller_circles():
    follower = geometry.SwingingRollerFollower()
    program = RiseDwellFall(Cycloidal(), Cycloidal(), math.pi / 18)
    prof = geometry.cam_profile(follower, program, THETA)
    rr = follower.roller_radius
    # Each flank point is r_r from its roller centre, and the joining line is normal to the pitch curve.
    for flank in (prof.inner, prof.outer):
        np.testing.assert_allclose(jnp.linalg.norm(flank - prof.pitch, axis=1), rr, rtol=1e-12)
    tangent = jax.jit(jax.vmap(jax.jacfwd(lambda t: geometry.pitch_point(follower, program, t))))(THETA)
    np.testing.assert_allclose(jnp.sum(tangent * (prof.outer - prof.pitch), axis=1), 0.0, atol=1e-14)
    # Envelope: distance from a fixed flank point to nearby roller circles is stationary (>= r_r).
    k = 100
    neighbours = jax.vmap(lambda t: geometry.pitch_point(follower, program, t))(THETA[k] + jnp.linspace(-0.02, 0.02, 41))
    dist = jnp.linalg.norm(neighbours - prof.inner[k], axis=1)
    assert float(dist.min()) == pytest.approx(rr, rel=1e-6)


def test_swinging_pressure_angle_against_instant_centre():
    # Independent route: the roller centre's velocity relative to the cam is tangent to the pitch curve.
    follower = geometry.SwingingRollerFollower()
    program = RiseDwellFall(Cycloidal(), Cycloidal(), math.pi / 12)
    theta = jnp.asarray(0.6)
    y, dy, _, _ = program.evaluate(theta)
    e = follower.roller_centre(y)
    psi = follower.arm_angle(y)
    v_follower = -dy * follower.arm_length * jnp.array([-jnp.sin(psi), jnp.cos(psi)])  # dE/dtheta
    v_cam = jnp.array([-e[1], e[0]])  # velocity of the cam point under E, per unit cam rate
    relative = v_follower - v_cam
    normal = jnp.array([-relative[1], relative[0]])
    cosine = abs(normal @ v_follower) / (jnp.linalg.norm(normal) * jnp.linalg.norm(v_follower))
    prof = geometry.cam_profile(follower, program, theta)
    assert float(abs(prof.pressure_angle[0])) == pytest.approx(float(jnp.arccos(cosine)), abs=1e-12)


def test_undercut_detected_for_large_roller():
    follower = geometry.TranslatingRollerFollower(roller_radius=0.03, base_radius=0.01)
    program = RiseDwellFall(Cycloidal(), Cycloidal(), 0.03, rise_angle=0.5, dwell_angle=0.5, fall_angle=0.5)
    prof = geometry.cam_profile(follower, program, THETA)
    flags = geometry.undercut(prof, follower.roller_radius)
    assert bool(jnp.any(flags.inner))
    ok = geometry.undercut(geometry.cam_profile(geometry.TranslatingRollerFollower(), RiseDwellFall(Cycloidal(), Cycloidal(), 0.01), THETA), 0.01)
    assert not bool(jnp.any(ok.inner)) and not bool(jnp.any(ok.outer))


def test_geometry_rejects_impossible_linkage():
    with pytest.raises(ValueError, match="triangle"):
        geometry.SwingingRollerFollower(pivot_distance=0.5, arm_length=0.098)


def test_pressure_angle_gradient_matches_finite_difference():
    program = RiseDwellFall(Cycloidal(), Cycloidal(), math.pi / 18)

    @jax.jit
    def peak(d):
        f = geometry.SwingingRollerFollower(pivot_distance=d)
        return jnp.max(jnp.abs(geometry.cam_profile(f, program, THETA[::8]).pressure_angle))

    g = jax.grad(peak)(0.11)
    h = 1e-6
    assert float(g) == pytest.approx(float((peak(0.11 + h) - peak(0.11 - h)) / (2 * h)), rel=1e-5)
