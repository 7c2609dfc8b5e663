"""Disk-cam geometry for roller and flat-faced followers: pitch curve, profile by envelopes,
pressure angle, the contact's terms, and the inverse (a drawn profile back to the lift).

Conventions: the cam centre is the origin, the cam turns counter-clockwise by ``theta``
(radians), and points on the cam are given in the cam-fixed frame, ``P = Rot(-theta) E``
where ``E`` is the roller centre in the fixed frame.  The pitch curve is the path of the
roller centre on the cam; the profile (both flanks of a groove) is the envelope of the
roller circles along it, ``C = P -/+ r_r n`` with ``n`` the outward unit normal.  Every
function is elementwise in ``theta``, jittable and differentiable in the follower's and
the program's leaves, except the inverse (``lift_from_polygon``), which is numpy.

Each follower kind is one class here (``name`` is its kind in a program file,
``camjax.program.Follower``): its geometry and its rules are its methods, so a new kind is
a new class (and its name in the program's reader, ``camjax.program.FOLLOWER_KINDS``).
"""

from __future__ import annotations

import abc
import math
from typing import ClassVar, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._custom_types import ArrayLike
from .checks import is_concrete, require
from .laws import RiseDwellFall


def _rot(angle, vector):
    c, s = jnp.cos(angle), jnp.sin(angle)
    return jnp.stack([c * vector[0] - s * vector[1], s * vector[0] + c * vector[1]])


class AbstractFollower(eqx.Module):
    """A follower's geometry: what every kind answers.

    The displacement ``y`` is a length for a translating follower and the swing (radians)
    for a swinging one, whose lift is the arc at ``arm_length``: ``lift = y *
    lift_per_displacement``.
    """

    name: ClassVar[str]
    """The kind's name in a program file (``[follower] kind``)."""
    swinging: ClassVar[bool]
    """Whether ``y`` is a swing about a pivot (radians) rather than a length."""
    max_pressure_angle_deg: ClassVar[float | None] = None
    """The pressure angle above which the follower is taken to jam or wear (the design rule
    of thumb), ``None`` where the pressure angle is no limit (a flat face)."""

    @property
    def lift_per_displacement(self):
        """Lift per unit of displacement: 1, or the arm for a swinging follower."""
        return self.arm_length if self.swinging else 1.0

    @abc.abstractmethod
    def profile_from_jet(self, theta, y, dy, ddy):
        """The cam's shape from the displacement's jet at each angle: a ``CamProfile`` for a
        roller, a ``FlatProfile`` for a flat face."""

    @abc.abstractmethod
    def contact_terms(self, shape, clearance=0.0) -> ContactTerms:
        """The contact's terms at each angle of ``profile_from_jet``'s ``shape``;
        ``clearance``: how much wider than the roller a groove is."""

    @abc.abstractmethod
    def contact_curvature(self, cam_radius):
        """``1/R'`` of the Hertz line contact on a cam surface of radius ``cam_radius``."""

    @abc.abstractmethod
    def lift_from_polygon(self, polygon: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """The inverse of the profile: the displacement ``y`` at each cam angle ``theta``
        (radians) of the cam whose profile is the closed ``polygon`` (``(m, 2)`` vertices,
        counter-clockwise, in the cam frame), measured from the base circle, with the roller
        centres in the cam frame (``(n, 2)``; ``None`` for a flat face).  Numpy; ``inf`` or
        ``nan`` where the follower does not reach the polygon."""


class ContactTerms(NamedTuple):
    """The contact between cam and follower at each angle of a shape.

    ``cam_radius``: the signed radius of curvature of the cam surface the follower rides
    (negative where concave); ``other_wall_radius``: a groove's other wall as the roller sees
    it (``inf`` under a flat face); ``normal_per_contact``: ``F_n / F_c``, the normal force
    per unit of the force along the follower's path (``1 / cos(pressure angle)``; under a
    swinging face ``arm / distance of the contact from the pivot``); ``face_position``: the
    contact along a flat face (zeros for a roller).
    """

    pressure_angle: np.ndarray
    cam_radius: np.ndarray
    other_wall_radius: np.ndarray
    normal_per_contact: np.ndarray
    face_position: np.ndarray


class AbstractRollerFollower(AbstractFollower):
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

    def profile_from_jet(self, theta, y, dy, ddy) -> CamProfile:
        return cam_profile_from_jet(self, theta, y, dy, ddy)

    def contact_terms(self, shape, clearance=0.0) -> ContactTerms:
        pitch = np.asarray(shape.pitch_radius_of_curvature)
        pressure = np.asarray(shape.pressure_angle)
        return ContactTerms(pressure, pitch - self.roller_radius, -(pitch + (self.roller_radius + clearance)),
                            1.0 / np.cos(pressure), np.zeros_like(pitch))

    def contact_curvature(self, cam_radius):
        return 1.0 / cam_radius + 1.0 / self.roller_radius


class SwingingRollerFollower(AbstractRollerFollower):
    """Arm of length ``arm_length`` pivoted at ``(pivot_distance, 0)``; ``y`` is the swing (rad).

    At ``y = 0`` the roller touches the base circle; a positive swing moves it outward.
    """

    name: ClassVar[str] = "swinging-roller"
    swinging: ClassVar[bool] = True
    max_pressure_angle_deg: ClassVar[float | None] = 45.0

    pivot_distance: jax.Array | float = 0.110
    arm_length: jax.Array | float = 0.098
    roller_radius: jax.Array | float = 0.010
    base_radius: jax.Array | float = 0.040

    def __check_init__(self):
        self._check_radii()
        if is_concrete(self.pivot_distance, self.arm_length, self.roller_radius, self.base_radius):
            d, l, rp = self.pivot_distance, self.arm_length, self.pitch_radius
            require(d > 0 and l > 0, "pivot_distance and arm_length must be positive")
            require(abs(d - l) < rp < d + l,
                    "arm_length, pivot_distance: the arm cannot reach the base circle (no triangle: "
                    "|pivot_distance - arm_length| < base_radius + roller_radius < pivot_distance + arm_length "
                    f"fails: {d:g}, {l:g}, {rp:g})")

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

    def lift_from_polygon(self, polygon, theta):
        """The arm swung as far out as the polygon pushes the roller, at each angle: the
        least arm direction (about the pivot, above the pivot-centre line) whose roller
        touches it (an endpoint circle or an edge's offset line, exactly); a polygon that
        reaches the pivot is refused."""
        _check_pivot_outside(polygon, self.pivot_distance)
        d, l, r = self.pivot_distance, self.arm_length, self.roller_radius
        rp = self.base_radius + r
        gamma0 = math.acos((d * d + l * l - rp * rp) / (2 * d * l))
        pivot = np.array([d, 0.0])

        def direction(z):
            return np.where(z[..., 1] > 0, np.arctan2(z[..., 1], z[..., 0]), np.inf)  # (0, pi) only

        def one(x):
            w = x - pivot
            rho = np.hypot(w[..., 0], w[..., 1])
            c = (l * l + rho * rho - r * r) / (2 * l * rho)
            phi = np.arctan2(w[..., 1], w[..., 0])
            half = np.arccos(np.clip(c, -1.0, 1.0))
            best = np.full(x.shape[0], np.inf)
            for sign in (-1.0, 1.0):
                psi = phi + sign * half
                z = np.stack([np.cos(psi), np.sin(psi)], axis=-1)
                best = np.minimum(best, np.min(np.where(np.abs(c) <= 1, direction(z), np.inf), axis=1))
            a, t, length = polygon_edges(x)
            nu = np.stack([t[..., 1], -t[..., 0]], axis=-1)
            for side in (-1.0, 1.0):
                start = a + side * r * nu - pivot
                b = np.sum(t * start, axis=-1)
                disc = b * b - (np.sum(start * start, axis=-1) - l * l)
                root = np.sqrt(np.maximum(disc, 0.0))
                for u in (-b - root, -b + root):
                    ok = (disc >= 0) & (u >= 0) & (u <= length)
                    best = np.minimum(best, np.min(np.where(ok, direction(start + u[..., None] * t), np.inf), axis=1))
            return best

        psi = _per_angle(polygon, theta, one)
        centre = np.stack([d + l * np.cos(psi), l * np.sin(psi)], axis=1)
        c, s = np.cos(theta), np.sin(theta)
        centres = np.stack([c * centre[:, 0] + s * centre[:, 1], -s * centre[:, 0] + c * centre[:, 1]], axis=1)
        return (math.pi - gamma0) - psi, centres


class TranslatingRollerFollower(AbstractRollerFollower):
    """Follower sliding along the line ``x = offset``; ``y`` is the lift (length)."""

    name: ClassVar[str] = "translating-roller"
    swinging: ClassVar[bool] = False
    max_pressure_angle_deg: ClassVar[float | None] = 30.0

    offset: jax.Array | float = 0.0
    roller_radius: jax.Array | float = 0.010
    base_radius: jax.Array | float = 0.040

    def __check_init__(self):
        self._check_radii()
        if is_concrete(self.offset, self.roller_radius, self.base_radius):
            require(abs(self.offset) < self.pitch_radius, "offset: |offset| must be below base_radius + roller_radius")

    def roller_centre(self, y) -> jax.Array:
        rise0 = jnp.sqrt(self.pitch_radius**2 - self.offset**2)
        return jnp.stack([self.offset + 0.0 * y, rise0 + y])

    def lift_from_polygon(self, polygon, theta):
        """The highest roller centre on ``x = offset`` whose roller touches the polygon, at
        each angle: the upper end of the polygon's roller-radius neighbourhood on the line
        (an endpoint circle or an edge's offset line, exactly)."""
        e, r = self.offset, self.roller_radius

        def one(x):
            dx = x[..., 0] - e
            cap = np.where(np.abs(dx) <= r, x[..., 1] + np.sqrt(np.maximum(r * r - dx * dx, 0.0)), -np.inf)
            a, t, length = polygon_edges(x)
            nu = np.stack([t[..., 1], -t[..., 0]], axis=-1)
            nu = np.where(nu[..., 1:2] < 0, -nu, nu)  # the offset line above the edge
            with np.errstate(divide="ignore", invalid="ignore"):
                u = (e - a[..., 0] - r * nu[..., 0]) / t[..., 0]
            side = np.where((u >= 0) & (u <= length), a[..., 1] + r * nu[..., 1] + u * t[..., 1], -np.inf)
            return np.max(np.maximum(cap, side), axis=1)

        height = _per_angle(polygon, theta, one)
        lift = height - math.sqrt((self.base_radius + r) ** 2 - e * e)
        centres = np.stack([e * np.cos(theta) + height * np.sin(theta),
                            -e * np.sin(theta) + height * np.cos(theta)], axis=1)
        return lift, centres


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


class AbstractFlatFollower(AbstractFollower):
    """A flat-faced follower: the line of its face in the fixed frame for a displacement ``y``,
    as the angle ``beta`` of its normal (pointing away from the cam) and its distance from
    the cam centre."""

    base_radius: jax.Array | float

    def profile_from_jet(self, theta, y, dy, ddy) -> FlatProfile:
        return flat_profile_from_jet(self, theta, y, dy, ddy)

    def contact_terms(self, shape, clearance=0.0) -> ContactTerms:
        radius, position = np.asarray(shape.radius_of_curvature), np.asarray(shape.face_position)
        return ContactTerms(np.zeros_like(radius), radius, np.full_like(radius, np.inf),
                            self.normal_per_contact(position), position)

    def contact_curvature(self, cam_radius):
        return 1.0 / cam_radius + 0.0

    def normal_per_contact(self, face_position):
        """``F_n / F_c`` with the contact at ``face_position``: 1 for a translating face."""
        return np.ones_like(face_position)

    def on_face(self, face_position):
        """Whether a contact at ``face_position`` lies on the face (every one but past a
        swinging face's pivot)."""
        return np.ones(np.shape(face_position), bool)

    @abc.abstractmethod
    def face(self, y) -> tuple[jax.Array, jax.Array]:
        """``(beta, distance)`` of the face at follower displacement ``y``."""

    @abc.abstractmethod
    def face_position(self, contact, beta) -> jax.Array:
        """Where the fixed-frame ``contact`` point lies along the face (mm from its origin)."""


class TranslatingFlatFollower(AbstractFlatFollower):
    """Face perpendicular to the follower's line ``x = 0``; ``y`` is the lift (length).
    The face position is the contact point's ``x``: ``dy/dtheta``."""

    name: ClassVar[str] = "translating-flat"
    swinging: ClassVar[bool] = False

    base_radius: jax.Array | float = 0.040

    def face(self, y):
        return jnp.pi / 2 + 0.0 * y, self.base_radius + y

    def face_position(self, contact, beta):
        return contact[0]

    def lift_from_polygon(self, polygon, theta):
        """The polygon's support function in the follower's direction, less the base circle."""
        return _per_angle(polygon, theta, lambda x: np.max(x[..., 1], axis=1)) - self.base_radius, None


class SwingingFlatFollower(AbstractFlatFollower):
    """Face on a plane through the pivot at ``(pivot_distance, 0)``; ``y`` is the swing (rad).

    At ``y = 0`` the face touches the base circle (``cos beta0 = r_b / d``) on the same side
    as ``SwingingRollerFollower``'s roller; a positive swing turns it away from the cam.  The
    face position is the contact point's distance from the pivot along the face.
    ``arm_length`` is the radius at which the swing is measured as a lift (its arc): it does
    not shape the cam.
    """

    name: ClassVar[str] = "swinging-flat"
    swinging: ClassVar[bool] = True

    pivot_distance: jax.Array | float = 0.110
    base_radius: jax.Array | float = 0.040
    arm_length: jax.Array | float = 0.098

    def __check_init__(self):
        if is_concrete(self.pivot_distance, self.base_radius, self.arm_length):
            require(self.arm_length > 0, f"arm_length must be positive, got {self.arm_length}")
            require(self.pivot_distance > self.base_radius,
                    "pivot_distance: the pivot must lie outside the base circle (pivot_distance > "
                    "base_radius) for its face to touch it")

    def face(self, y):
        beta = jnp.arccos(self.base_radius / self.pivot_distance) - y
        return beta, self.pivot_distance * jnp.cos(beta)

    def face_position(self, contact, beta):
        along = jnp.stack([-jnp.sin(beta), jnp.cos(beta)])
        return (contact - jnp.stack([self.pivot_distance, 0.0 * beta])) @ along

    def normal_per_contact(self, face_position):
        """The arm's moment over the contact's: ``arm / distance of the contact from the pivot``."""
        return self.arm_length / face_position

    def on_face(self, face_position):
        return np.asarray(face_position) > 0

    def lift_from_polygon(self, polygon, theta):
        """The face through the pivot tangent to the polygon: its normal's angle is the
        least direction of a vertex seen from the pivot, less 90 degrees; a polygon that
        reaches the pivot is refused."""
        _check_pivot_outside(polygon, self.pivot_distance)
        d = self.pivot_distance

        def one(x):
            return np.min(np.mod(np.arctan2(x[..., 1], x[..., 0] - d), 2 * np.pi), axis=1)

        beta = _per_angle(polygon, theta, one) - math.pi / 2
        return math.acos(self.base_radius / d) - beta, None


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


# -- closed polygons (a drawn profile) ---------------------------------------------------------

_ANGLES_PER_BLOCK = 128  # cam angles turned at once in ``lift_from_polygon`` (memory: angles x vertices)


def polygon_edges(points: np.ndarray):
    """Start points, unit directions and lengths of the closed polygon's edges (the last
    vertex joined to the first), over the last two axes of ``points`` (``(..., m, 2)``)."""
    step = np.roll(points, -1, axis=-2) - points
    length = np.hypot(step[..., 0], step[..., 1])
    return points, step / length[..., None], length


def _check_pivot_outside(polygon: np.ndarray, pivot_distance) -> None:
    """A swinging follower's pivot must lie beyond the polygon's largest radius: the
    profile turns past it otherwise (a ``ValueError`` naming ``pivot_distance``)."""
    largest = float(np.max(np.hypot(polygon[:, 0], polygon[:, 1])))
    if pivot_distance <= largest:
        raise ValueError(f"pivot_distance: the pivot ({pivot_distance:g}) lies within the profile's largest "
                         f"radius ({largest:.6g}); move the pivot out")


def _per_angle(polygon: np.ndarray, theta: np.ndarray, one) -> np.ndarray:
    """``one`` of the polygon turned into the fixed frame at each cam angle (``(n, m, 2)``
    blocks of angles), concatenated."""
    def turned(t):
        c, s = np.cos(t)[:, None], np.sin(t)[:, None]
        return np.stack([c * polygon[:, 0] - s * polygon[:, 1], s * polygon[:, 0] + c * polygon[:, 1]], axis=-1)

    return np.concatenate([one(turned(theta[i:i + _ANGLES_PER_BLOCK]))
                           for i in range(0, theta.size, _ANGLES_PER_BLOCK)])
