"""Where cam and follower touch: the contact's geometry and its Hertz stress.

Hertz line contact: ``p_max^2 = F_n E* / (pi L R')`` is the contact force times a factor of
the geometry alone, sampled once per program at the grid's nodes (both one-sided values at a
join, the larger taken); the largest stress is refined between the nodes
(``refined_contact_stress``).  ``cam_geometry`` gives the figures a designer checks on the
profile: pressure angle, radii of curvature, face width.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from ._export import _angle_ranges, shape
from ._program import Program


class ContactGeometry(NamedTuple):
    """The cam's contact geometry at angles ``theta_deg``, each array ``(2, n)``: the
    one-sided values before and after each angle (equal but at a join where the
    acceleration steps).

    ``cam_radius_mm`` is the signed radius of curvature of the cam surface the follower
    rides (negative where concave), ``outer_radius_mm`` a grooved cam's other wall as the
    roller sees it, ``normal_per_contact`` ``F_n / F_c`` (``1 / cos(pressure angle)``; under a
    swinging face ``arm / distance of the contact from the pivot``), ``face_position_mm`` the
    contact along a flat face (zeros for a roller).
    """

    theta_deg: np.ndarray
    pressure_angle_deg: np.ndarray
    cam_radius_mm: np.ndarray
    outer_radius_mm: np.ndarray
    normal_per_contact: np.ndarray
    face_position_mm: np.ndarray


def contact_geometry(program: Program, theta_deg) -> ContactGeometry:
    """The cam's contact geometry at ``theta_deg`` from both one-sided jets of the lift
    (the follower geometry's ``contact_terms``)."""
    theta_deg = np.asarray(theta_deg, dtype=float)
    f = program.follower
    follower = f.geometry
    sides = [follower.contact_terms(shape(program, theta_deg, side), f.groove_clearance_mm or 0.0)
             for side in ("before", "after")]
    pressure, radius, outer, normal, position = (np.stack(side) for side in zip(*sides))
    return ContactGeometry(theta_deg, np.degrees(pressure), radius, outer, normal, position)


class NodeContact(NamedTuple):
    """``p_max^2 = F_c * factor`` (MPa^2 per N) at the grid's nodes, for the flank the
    follower rides (``inner``) and a grooved cam's other wall (``outer``), with the
    effective radius ``R'`` (mm) there, the smaller of a join's two sides taken."""

    inner: np.ndarray
    outer: np.ndarray
    radius_inner: np.ndarray
    radius_outer: np.ndarray


def _effective_radius(program: Program, cam_radius: np.ndarray, where: str, theta_deg) -> np.ndarray:
    """``R'`` with ``1/R' = 1/r_roller + 1/rho_cam`` (``rho_cam`` alone under a flat face)."""
    with np.errstate(divide="ignore"):
        curvature = program.follower.geometry.contact_curvature(cam_radius)
    bad = ~(curvature > 0)
    if bad.any():
        angles = np.broadcast_to(theta_deg, bad.shape)
        raise ValueError(f"follower.roller_radius_mm: the roller does not fit the cam's {where} at "
                         f"{_angle_ranges(angles[0], bad.any(axis=0))} (an undercut): no contact stress")
    return 1.0 / curvature


def node_contact(program: Program, theta_deg) -> NodeContact:
    """The Hertz factors at cam angles ``theta_deg``: ``p_max^2 = F_c * factor``, what the
    steady state multiplies by its contact force at every grid node (zeros without
    ``follower.contact_width_mm``).  At a join, where the cam's radius of curvature
    jumps, an angle within a rounding of it takes the side of the larger stress."""
    f = program.follower
    n = np.asarray(theta_deg).size
    if f.contact_width_mm is None:
        zeros = np.zeros(n)
        return NodeContact(zeros, zeros, zeros, zeros)
    g = contact_geometry(program, theta_deg)
    scale = program.materials.contact_modulus_mpa / (math.pi * f.contact_width_mm)
    inner_radius = _effective_radius(program, g.cam_radius_mm, "profile", theta_deg)
    inner = (scale * g.normal_per_contact / inner_radius).max(axis=0)
    if f.form_closed and not f.flat_face:
        outer_radius = _effective_radius(program, g.outer_radius_mm, "outer wall", theta_deg)
        outer = (scale * g.normal_per_contact / outer_radius).max(axis=0)
        radius_outer = outer_radius.min(axis=0)
    else:
        outer, radius_outer = np.zeros(n), np.full(n, np.inf)
    return NodeContact(inner, outer, inner_radius.min(axis=0), radius_outer)


def contact_stress_squared(force, contact: NodeContact):
    """``p_max^2`` (MPa^2) at the nodes for the contact force there (no contact: zero)."""
    return jnp.maximum(force, 0.0) * contact.inner + jnp.maximum(-force, 0.0) * contact.outer


HERTZ_CANDIDATES = 4
"""Crests of the node stress (local maxima within ``_CANDIDATE_MARGIN`` of the largest) whose
two intervals ``refined_contact_stress`` searches at each speed: between nodes a crest rises
by far less than that margin, so the largest stress lies in one of them."""
_CANDIDATE_MARGIN = 1e-2
_FACTOR_POINTS = 8  # Chebyshev points per interval at which the Hertz factors are interpolated
_SCREEN_POINTS, _SCREEN_MARGIN = 9, 1e-4  # between 9 samples a crest hides far less than 1e-4
_ZOOM_POINTS, _ZOOM_ROUNDS = 17, 14  # each round narrows the bracket 8-fold: 1e-13 of an interval


class RefinedStress(NamedTuple):
    """The largest Hertz stress over a turn at each speed, refined between the grid's nodes:
    ``p_max`` (MPa), the cam angle where it lies (degrees) and the effective radius ``R'``
    (mm) there (the half-width is ``2 R' p_max / E*``)."""

    stress_mpa: np.ndarray
    angle_deg: np.ndarray
    radius_mm: np.ndarray


def refined_contact_stress(program: Program, nodes, stress, force_at) -> RefinedStress:
    """The largest ``p_max = sqrt(F_c * factor)`` at every speed, between the nodes as well
    as at them, as the contact force's own peaks are refined.

    ``nodes``: the grid's nodes (turns, ``(N + 1,)``); ``stress``: ``p_max`` there at every
    speed (``(S, N + 1)``); ``force_at(rows, s)``: the contact force (N) of speed ``rows`` at
    turn times ``s`` (arrays of one shape), exact anywhere (the steady state's own step).

    At each speed the two intervals beside each of its ``HERTZ_CANDIDATES`` largest crests
    are searched.  The Hertz factors of ``node_contact`` (geometry only, the same at every
    speed) are read once at ``_FACTOR_POINTS`` Chebyshev points inside each interval searched
    and interpolated there (degree 7 over an interval of the grid: within rounding); the
    force is exact.  A screen of 9 samples per interval keeps those within 1e-4 of their
    speed's best; a zoom of ``_ZOOM_POINTS`` points, narrowed 8-fold per round, finds the
    largest ``F_c * factor`` of each to within 1e-13 of its width.
    """
    nodes, stress = np.asarray(nodes, dtype=float), np.atleast_2d(np.asarray(stress, dtype=float))
    speeds, count = stress.shape
    intervals = count - 1
    rows, starts = _candidate_intervals(stress, intervals)
    unique, which = np.unique(starts, return_inverse=True)
    factors = _interpolated_factors(program, nodes, unique)  # (4, U, points) Chebyshev coefficients
    begin, width = nodes[unique][which], (nodes[unique + 1] - nodes[unique])[which]

    def at(pairs, sigma):
        return _stress_squared(factors, which[pairs], sigma, begin[pairs][:, None] + width[pairs][:, None] * sigma,
                               rows[pairs], force_at)

    # a screen of every candidate interval; only those within _SCREEN_MARGIN of their speed's
    # best sample are zoomed into, around their best sample
    screen = np.linspace(0.0, 1.0, _SCREEN_POINTS)
    value, _ = at(np.arange(rows.size), np.broadcast_to(screen, (rows.size, screen.size)))
    top = np.full(speeds, -np.inf)
    np.maximum.at(top, rows, value.max(axis=1))
    pairs = np.flatnonzero(value.max(axis=1) >= (1 - _SCREEN_MARGIN) * top[rows])
    step = np.full(pairs.size, screen[1])
    centre = screen[np.argmax(value[pairs], axis=1)]
    for _ in range(_ZOOM_ROUNDS):
        lo, hi = np.maximum(centre - step, 0.0), np.minimum(centre + step, 1.0)
        sigma = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, _ZOOM_POINTS)
        value, _ = at(pairs, sigma)
        centre = sigma[np.arange(pairs.size), np.argmax(value, axis=1)]
        step = (hi - lo) / (_ZOOM_POINTS - 1)
    value, radius = (x[:, 0] for x in at(pairs, centre[:, None]))
    times = begin[pairs] + width[pairs] * centre
    out = np.full(speeds, -np.inf)
    chosen = np.zeros(speeds, dtype=int)
    for i, r in enumerate(rows[pairs]):  # the best interval of each speed
        if value[i] > out[r]:
            out[r], chosen[r] = value[i], i
    return RefinedStress(np.sqrt(np.maximum(out, 0.0)), np.mod(360.0 * times[chosen], 360.0), radius[chosen])


def _candidate_intervals(stress: np.ndarray, intervals: int) -> tuple[np.ndarray, np.ndarray]:
    """``(speed row, first node)`` of every interval to search: the two beside each of a
    speed's ``HERTZ_CANDIDATES`` largest crests (the turn is periodic: node 0 is node N)."""
    turn = stress[:, :intervals]
    before, after = np.roll(turn, 1, axis=1), np.roll(turn, -1, axis=1)
    crest = (turn >= before) & (turn >= after) & (turn >= (1 - _CANDIDATE_MARGIN) * turn.max(axis=1, keepdims=True))
    rows, starts = [], []
    for r in range(turn.shape[0]):
        nodes = np.flatnonzero(crest[r])
        nodes = nodes[np.argsort(turn[r, nodes])[::-1][:HERTZ_CANDIDATES]]
        for k in nodes:
            for first in ((k - 1) % intervals, k):
                rows.append(r)
                starts.append(first)
    return np.asarray(rows, dtype=int), np.asarray(starts, dtype=int)


_FACTOR_BLOCK = 256  # angles per call of the geometry (one compiled shape)


def _interpolated_factors(program: Program, nodes: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Chebyshev coefficients ``(4, intervals, _FACTOR_POINTS)`` over ``sigma`` in [0, 1] of the
    inner and outer factors and effective radii of ``node_contact`` in each interval."""
    x = np.cos(np.pi * (np.arange(_FACTOR_POINTS) + 0.5) / _FACTOR_POINTS)  # inside (-1, 1): no join
    sigma = 0.5 * (1.0 + x)
    width = nodes[starts + 1] - nodes[starts]
    angles = (360.0 * (nodes[starts][:, None] + width[:, None] * sigma)).ravel()
    padded = np.pad(angles, (0, -angles.size % _FACTOR_BLOCK), mode="edge")
    parts = [node_contact(program, padded[i:i + _FACTOR_BLOCK]) for i in range(0, padded.size, _FACTOR_BLOCK)]
    values = np.stack([np.concatenate([np.asarray(getattr(p, name)) for p in parts])[:angles.size]
                       for name in NodeContact._fields])
    values = values.reshape(4, starts.size, _FACTOR_POINTS)
    values[3] = np.where(np.isfinite(values[3]), values[3], 0.0)  # no other wall: R' unused
    return np.polynomial.chebyshev.chebfit(x, values.reshape(-1, _FACTOR_POINTS).T, _FACTOR_POINTS - 1).T.reshape(
        4, starts.size, _FACTOR_POINTS)


def _stress_squared(factors, which, sigma, times, rows, force_at):
    """``p_max^2`` and ``R'`` at ``sigma`` (``(P, points)``) of the intervals ``which``."""
    x = 2.0 * sigma - 1.0
    inner, outer, radius_inner, radius_outer = (
        np.polynomial.chebyshev.chebval(x.T, factors[j][which].T, tensor=False).T for j in range(4))
    force = force_at(np.broadcast_to(rows[:, None], times.shape), times)
    value = np.maximum(force, 0.0) * inner + np.maximum(-force, 0.0) * outer
    return value, np.where(force >= 0, radius_inner, radius_outer)


@dataclasses.dataclass(frozen=True)
class JoinCurvature:
    """The cam surface's radius of curvature (mm) on both sides of a segment join."""

    angle_deg: float
    radius_before_mm: float
    radius_after_mm: float

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class Geometry:
    """The cam's shape as the designer checks it (mm, degrees).

    ``min_radius_of_curvature_mm`` is the cam surface's where convex (the smaller one-sided
    value at a join); ``min_concave_radius_of_curvature_mm`` the smallest ``|rho|`` where
    concave (``None`` if nowhere); ``face_width_mm`` (flat faces) is the span of the contact
    along the face, ``max y' - min y'`` for a translating one, before any margin.
    """

    max_pressure_angle_deg: float
    min_radius_of_curvature_mm: float | None
    min_concave_radius_of_curvature_mm: float | None
    face_width_mm: float | None
    joins: tuple[JoinCurvature, ...]

    def as_dict(self) -> dict:
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        out["joins"] = [j.as_dict() for j in self.joins]
        return out


def cam_geometry(program: Program, theta_deg) -> Geometry:
    """``Geometry`` over ``theta_deg`` and every segment join (both sides)."""
    joins_deg = np.asarray(program.start_deg, dtype=float)
    g = contact_geometry(program, np.concatenate([np.asarray(theta_deg, dtype=float), joins_deg]))
    rho = g.cam_radius_mm
    convex, concave = rho[rho > 0], -rho[rho < 0]
    width = None
    if program.follower.flat_face:
        width = float(g.face_position_mm.max() - g.face_position_mm.min())
    n = joins_deg.size
    joins = tuple(JoinCurvature(float(a), float(rho[0, -n + i]), float(rho[1, -n + i])) for i, a in enumerate(joins_deg))
    return Geometry(
        max_pressure_angle_deg=float(np.abs(g.pressure_angle_deg).max()),
        min_radius_of_curvature_mm=float(convex.min()) if convex.size else None,
        min_concave_radius_of_curvature_mm=float(concave.min()) if concave.size else None,
        face_width_mm=width,
        joins=joins,
    )
