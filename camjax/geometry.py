"""Disk-cam geometry for roller followers: pitch curve, profile by envelopes, pressure angle.

Conventions: the cam centre is the origin, the cam turns counter-clockwise by ``theta``
(radians), and points on the cam are given in the cam-fixed frame, ``P = Rot(-theta) E``
where ``E`` is the roller centre in the fixed frame.  The pitch curve is the path of the
roller centre on the cam; the profile (both flanks of a groove) is the envelope of the
roller circles along it, ``C = P -/+ r_r n`` with ``n`` the outward unit normal.  Every
function is elementwise in ``theta``, jittable and differentiable in the follower's and
the program's leaves.
"""

from __future__ import annotations

import abc
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp

from ._custom_types import ArrayLike
from .checks import is_concrete, require
from .laws import RiseDwellFall


def _rot(angle, vector):
    c, s = jnp.cos(angle), jnp.sin(angle)
    return jnp.stack([c * vector[0] - s * vector[1], s * vector[0] + c * vector[1]])


class AbstractRollerFollower(eqx.Module):
    """A roller follower: where its roller centre is for a follower displacement ``y``."""

    roller_radius: jax.Array | float
    base_radius: jax.Array | float

    @property
    def pitch_radius(self):
        """Radius of the prime circle: base circle plus roller."""
        return self.base_radius + self.roller_radius

    @abc.abstractmethod
    def roller_centre(self, y) -> jax.Array:
        """Roller centre ``(2,)`` in the fixed frame at follower displacement ``y``."""

    def _check_radii(self):
        if is_concrete(self.roller_radius, self.base_radius):
            require(self.roller_radius > 0, f"roller_radius must be positive, got {self.roller_radius}")
            require(self.base_radius > 0, f"base_radius must be positive, got {self.base_radius}")


class SwingingRollerFollower(AbstractRollerFollower):
    """Arm of length ``arm_length`` pivoted at ``(pivot_distance, 0)``; ``y`` is the swing (rad).

    At ``y = 0`` the roller touches the base circle; a positive swing moves it outward.
    """

    pivot_distance: jax.Array | float = 0.110
    arm_length: jax.Array | float = 0.098
    roller_radius: jax.Array | float = 0.010
    base_radius: jax.Array | float = 0.040

    def __check_init__(self):
        self._check_radii()
        if is_concrete(self.pivot_distance, self.arm_length, self.roller_radius, self.base_radius):
            d, l, rp = self.pivot_distance, self.arm_length, self.pitch_radius
            require(d > 0 and l > 0, "pivot_distance and arm_length must be positive")
            require(abs(d - l) < rp < d + l, f"no triangle: |d - l| < r_b + r_r < d + l fails ({d}, {l}, {rp})")

    @property
    def initial_angle(self):
        """Angle at the pivot between the line to the cam centre and the arm, at ``y = 0``."""
        d, l, rp = self.pivot_distance, self.arm_length, self.pitch_radius
        return jnp.arccos((d**2 + l**2 - rp**2) / (2 * d * l))

    def arm_angle(self, y):
        """Direction of the arm (pivot to roller) in the fixed frame, radians."""
        return jnp.pi - (self.initial_angle + y)

    def roller_centre(self, y) -> jax.Array:
        psi = self.arm_angle(y)
        return jnp.stack([self.pivot_distance + self.arm_length * jnp.cos(psi), self.arm_length * jnp.sin(psi)])


class TranslatingRollerFollower(AbstractRollerFollower):
    """Follower sliding along the line ``x = offset``; ``y`` is the lift (length)."""

    offset: jax.Array | float = 0.0
    roller_radius: jax.Array | float = 0.010
    base_radius: jax.Array | float = 0.040

    def __check_init__(self):
        self._check_radii()
        if is_concrete(self.offset, self.roller_radius, self.base_radius):
            require(abs(self.offset) < self.pitch_radius, "|offset| must be below r_b + r_r")

    def roller_centre(self, y) -> jax.Array:
        rise0 = jnp.sqrt(self.pitch_radius**2 - self.offset**2)
        return jnp.stack([self.offset + 0.0 * y, rise0 + y])


class CamProfile(NamedTuple):
    """A cam over the angles ``theta``; points are ``(n, 2)`` in the cam frame (metres)."""

    theta: jax.Array
    pitch: jax.Array
    inner: jax.Array
    """Flank ``P - r_r n`` (toward the cam centre; the one a roller pushed outward rides)."""
    outer: jax.Array
    """Flank ``P + r_r n`` (the other wall of a groove)."""
    pressure_angle: jax.Array
    """Signed angle between the contact normal and the roller centre's path (rad)."""
    pitch_radius_of_curvature: jax.Array
    """Positive where the pitch curve is convex."""
    inner_radius_of_curvature: jax.Array
    outer_radius_of_curvature: jax.Array


def pitch_point(follower: AbstractRollerFollower, program: RiseDwellFall, theta) -> jax.Array:
    """Roller centre in the cam frame at one cam angle (scalar ``theta``)."""
    return _rot(-theta, follower.roller_centre(program.displacement(theta)))


def _profile_at(follower, program, theta, roller_radius):
    point = lambda t: pitch_point(follower, program, t)  # noqa: E731
    pitch, tangent = jax.jvp(point, (theta,), (jnp.ones_like(theta),))
    _, second = jax.jvp(lambda t: jax.jvp(point, (t,), (jnp.ones_like(t),))[1], (theta,), (jnp.ones_like(theta),))
    speed = jnp.linalg.norm(tangent)
    normal = jnp.stack([-tangent[1], tangent[0]]) / speed  # outward for the clockwise trace
    cross = tangent[0] * second[1] - tangent[1] * second[0]
    radius = -(speed**3) / cross
    # Pressure angle in the fixed frame: contact normal against the roller-centre path.
    y = program.displacement(theta)
    path = jax.jvp(follower.roller_centre, (y,), (jnp.ones_like(y),))[1]
    normal_fixed = _rot(theta, normal)
    along = normal_fixed @ path
    across = normal_fixed[0] * path[1] - normal_fixed[1] * path[0]
    pressure = jnp.arctan(across / along)
    return (
        pitch,
        pitch - roller_radius * normal,
        pitch + roller_radius * normal,
        pressure,
        radius,
        radius - roller_radius,
        radius + roller_radius,
    )


def cam_profile(follower: AbstractRollerFollower, program: RiseDwellFall, theta: ArrayLike) -> CamProfile:
    """Pitch curve, both groove flanks, pressure angle and radii of curvature at ``theta``."""
    return _cam_profile(follower, program, jnp.atleast_1d(jnp.asarray(theta, dtype=float)))


@eqx.filter_jit
def _cam_profile(follower, program, theta) -> CamProfile:
    parts = jax.vmap(lambda t: _profile_at(follower, program, t, follower.roller_radius))(theta)
    return CamProfile(theta, *parts)


class Undercut(NamedTuple):
    inner: jax.Array
    """True where the inner flank is undercut (``0 < rho_pitch < r_r``): the roller cannot follow."""
    outer: jax.Array
    """True where the outer flank is undercut (``-r_r < rho_pitch < 0``)."""
    min_inner_radius: jax.Array
    min_outer_radius: jax.Array


def undercut(profile: CamProfile, roller_radius) -> Undercut:
    """Where each flank loops (cusp) because the roller is larger than the pitch curvature allows."""
    rho = profile.pitch_radius_of_curvature
    return Undercut(
        inner=(rho > 0) & (rho < roller_radius),
        outer=(rho < 0) & (rho > -roller_radius),
        min_inner_radius=jnp.min(jnp.abs(profile.inner_radius_of_curvature)),
        min_outer_radius=jnp.min(jnp.abs(profile.outer_radius_of_curvature)),
    )


class _LocalLift(eqx.Module):
    """The lift near ``theta0`` from its value and first two derivatives there (a jet).

    Geometry from a jet takes the curvature from the derivatives the caller chose, one-sided
    at a join where the acceleration steps (autodiff through a law's clip halves them there).
    """

    theta0: jax.Array
    y: jax.Array
    dy: jax.Array
    ddy: jax.Array

    def displacement(self, theta):
        d = theta - self.theta0
        return self.y + self.dy * d + 0.5 * self.ddy * d**2


def cam_profile_from_jet(follower: AbstractRollerFollower, theta, y, dy, ddy) -> CamProfile:
    """``cam_profile`` from the follower displacement and its first two derivatives in
    ``theta`` (radians) at each angle instead of a program: one-sided values at a join give
    the one-sided curvature there."""
    theta, y, dy, ddy = (jnp.atleast_1d(jnp.asarray(x, dtype=float)) for x in (theta, y, dy, ddy))
    return _cam_profile_from_jet(follower, theta, y, dy, ddy)


@eqx.filter_jit
def _cam_profile_from_jet(follower, theta, y, dy, ddy) -> CamProfile:
    parts = jax.vmap(lambda t, a, b, c: _profile_at(follower, _LocalLift(t, a, b, c), t, follower.roller_radius))(
        theta, y, dy, ddy)
    return CamProfile(theta, *parts)


class AbstractFlatFollower(eqx.Module):
    """A flat-faced follower: the line of its face in the fixed frame for a displacement ``y``,
    as the angle ``beta`` of its normal (pointing away from the cam) and its distance from
    the cam centre."""

    base_radius: jax.Array | float

    @abc.abstractmethod
    def face(self, y) -> tuple[jax.Array, jax.Array]:
        """``(beta, distance)`` of the face at follower displacement ``y``."""

    @abc.abstractmethod
    def face_position(self, contact, beta) -> jax.Array:
        """Where the fixed-frame ``contact`` point lies along the face (mm from its origin)."""


class TranslatingFlatFollower(AbstractFlatFollower):
    """Face perpendicular to the follower's line ``x = 0``; ``y`` is the lift (length).
    The face position is the contact point's ``x``: ``dy/dtheta``."""

    base_radius: jax.Array | float = 0.040

    def face(self, y):
        return jnp.pi / 2 + 0.0 * y, self.base_radius + y

    def face_position(self, contact, beta):
        return contact[0]


class SwingingFlatFollower(AbstractFlatFollower):
    """Face on a plane through the pivot at ``(pivot_distance, 0)``; ``y`` is the swing (rad).

    At ``y = 0`` the face touches the base circle (``cos beta0 = r_b / d``) on the same side
    as ``SwingingRollerFollower``'s roller; a positive swing turns it away from the cam.  The
    face position is the contact point's distance from the pivot along the face.
    """

    pivot_distance: jax.Array | float = 0.110
    base_radius: jax.Array | float = 0.040

    def face(self, y):
        beta = jnp.arccos(self.base_radius / self.pivot_distance) - y
        return beta, self.pivot_distance * jnp.cos(beta)

    def face_position(self, contact, beta):
        along = jnp.stack([-jnp.sin(beta), jnp.cos(beta)])
        return (contact - jnp.stack([self.pivot_distance, 0.0 * beta])) @ along


class FlatProfile(NamedTuple):
    """A cam under a flat face over the angles ``theta``: contact points in the cam frame,
    the cam's radius of curvature there (``r_b + y + y''`` for the translating face; not
    positive is a cusp) and where the contact lies along the face."""

    theta: jax.Array
    profile: jax.Array
    radius_of_curvature: jax.Array
    face_position: jax.Array


def flat_profile_from_jet(follower: AbstractFlatFollower, theta, y, dy, ddy) -> FlatProfile:
    """The envelope of the face's lines from the displacement's jet at each angle.

    In the cam frame the face has normal angle ``alpha = beta - theta`` and distance ``p``
    from the centre; the envelope is ``p n(alpha) + p_alpha t(alpha)`` with radius of
    curvature ``p + p_alpha_alpha`` (the support-function form).
    """
    theta, y, dy, ddy = (jnp.atleast_1d(jnp.asarray(x, dtype=float)) for x in (theta, y, dy, ddy))
    return _flat_profile(follower, theta, y, dy, ddy)


@eqx.filter_jit
def _flat_profile(follower, theta, y, dy, ddy) -> FlatProfile:
    def one(t, a, b, c):
        lift = _LocalLift(t, a, b, c)

        def support(u):
            beta, p = follower.face(lift.displacement(u))
            return jnp.stack([beta - u, p])

        first = lambda u: jax.jvp(support, (u,), (jnp.ones_like(u),))[1]  # noqa: E731
        (alpha, p), (da, dp) = support(t), first(t)
        dda, ddp = jax.jvp(first, (t,), (jnp.ones_like(t),))[1]
        p_alpha = dp / da
        radius = p + (ddp * da - dp * dda) / da**3
        normal, tangent = jnp.stack([jnp.cos(alpha), jnp.sin(alpha)]), jnp.stack([-jnp.sin(alpha), jnp.cos(alpha)])
        point = p * normal + p_alpha * tangent
        return point, radius, follower.face_position(_rot(t, point), alpha + t)

    return FlatProfile(theta, *jax.vmap(one)(theta, y, dy, ddy))
