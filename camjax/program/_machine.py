"""What the machine designer sizes from a cam's motion: drive torque, energy, contact stress.

Drive torque (frictionless, power balance): the cam's power ``T Omega`` is the contact
force's power on the follower, ``F_c`` along the follower's path times the path's speed, so
``T = F_c dy/dtheta`` for a translating follower and, with the lift the arc length at
``arm_mm`` (the force referred to that radius), for a swinging one too (the arm's moment
``F_c arm`` times the swing rate ``dy/dtheta / arm``).  In turn time ``s`` (``theta =
2 pi s``) ``T = 1e-3 F_c y_s / (2 pi)`` N m with ``y_s`` in mm per turn; its derivatives
at both ends of every interval follow from the force's and the lift's one-sided ones, so
the torque has the same septic Hermite interpolant per interval as the refined peaks
(``camjax.metrics.septic_coefficients``), which is integrated exactly.

Hertz line contact: ``p_max^2 = F_n E* / (pi L R')`` is the contact force times a factor of
the geometry alone, sampled once per program at the grid's nodes (both one-sided values at a
join, the larger taken).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from .._plain import DEFAULT_SPEED_FLUCTUATION as DEFAULT_SPEED_FLUCTUATION
from ..metrics import interval_peaks, septic_coefficients
from ._export import _angle_ranges, shape
from ._spec import Program
from ._speeds import speed_warnings

TORQUE_PER_FORCE_VELOCITY = 1e-3 / (2 * math.pi)
"""N m of drive torque per N of contact force and mm per turn of lift velocity."""
_HILBERT = 1.0 / (np.arange(8)[:, None] + np.arange(8)[None, :] + 1.0)


def torque_jets(force, force_left, force_right, velocity, lift_left, lift_right):
    """Drive torque (N m) at the nodes and its first three derivatives in turn time at both
    ends of every interval, from the contact force's (``gain_derivatives``) and the lift's
    (``y_s`` at the nodes, ``(y_ss, y_sss, y_ssss)`` one-sided, ``MotionGrid.one_sided``)."""

    def ends(f, df, ys, dy):
        d1 = df[:, 0] * ys + f * dy[:, 0]
        d2 = df[:, 1] * ys + 2 * df[:, 0] * dy[:, 0] + f * dy[:, 1]
        d3 = df[:, 2] * ys + 3 * df[:, 1] * dy[:, 0] + 3 * df[:, 0] * dy[:, 1] + f * dy[:, 2]
        return TORQUE_PER_FORCE_VELOCITY * jnp.stack([d1, d2, d3], axis=1)

    values = TORQUE_PER_FORCE_VELOCITY * force * velocity
    return (values, ends(force[:-1], force_left, velocity[:-1], lift_left),
            ends(force[1:], force_right, velocity[1:], lift_right))


class TorqueFigures(NamedTuple):
    """Peak ``|T|``, RMS and mean torque (N m) over a turn and the energy fluctuation (J)."""

    max_abs: float
    rms: float
    mean: float
    energy_fluctuation: float


def torque_figures(values, widths, left, right) -> TorqueFigures:
    """The figures of a torque sampled over one turn (``sum(widths) == 1``), jittable.

    Mean and RMS integrate the septic interpolant exactly; ``W(s) = 2 pi int (T - mean) ds``
    is its running integral at the nodes, with ``W' = T - mean``, ``W'' = T'``, ``W''' = T''``
    at both ends of every interval.  ``max |T|``, ``max W`` and ``min W`` are refined between
    nodes as ``refined_peak`` does, in one pass over the three signals' intervals (``W``
    shifted below its smallest node value for its maximum, above its largest for its minimum).
    """
    c = septic_coefficients(values, widths, left, right)
    integrals = widths * (c @ jnp.asarray(1.0 / np.arange(1, 9)))
    mean = jnp.sum(integrals)
    rms = jnp.sqrt(jnp.maximum(jnp.sum(widths * jnp.einsum("ki,ij,kj->k", c, jnp.asarray(_HILBERT), c)), 0.0))
    work = jnp.concatenate([jnp.zeros(1), jnp.cumsum(integrals - mean * widths)])

    def work_ends(t, d):
        return jnp.stack([t - mean, d[:, 0], d[:, 1]], axis=1)

    w = septic_coefficients(work, widths, work_ends(values[:-1], left), work_ends(values[1:], right))
    span = jnp.max(work) - jnp.min(work) + 1.0
    below, above = jnp.min(work) - span, jnp.max(work) + span
    constant = jnp.zeros(8).at[0].set(1.0)
    peaks = interval_peaks(jnp.concatenate([c, w - below * constant, w - above * constant]))
    k = values.shape[0] - 1
    high = jnp.max(peaks[k:2 * k]) + below
    low = above - jnp.max(peaks[2 * k:])
    return TorqueFigures(jnp.max(peaks[:k]), rms, mean, 2 * math.pi * (high - low))


def flywheel_inertia_kg_m2(energy_fluctuation_j, rpm, speed_fluctuation: float):
    """``J = dE / (Cs Omega^2)``: the inertia that keeps the speed within ``Cs`` of its mean."""
    omega = 2 * math.pi * np.asarray(rpm) / 60.0
    return np.asarray(energy_fluctuation_j) / (speed_fluctuation * omega**2)


def check_speed_fluctuation(value, what: str = "speed_fluctuation") -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < value < 2 or not math.isfinite(value):
        raise ValueError(f"{what} must be a number in (0, 2), got {value!r}")
    return float(value)


# -- the cam's geometry for the contact ---------------------------------------------------------


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


MODULUS_RANGE_GPA = (1.0, 1000.0)
"""Young's moduli of engineering solids, polymers to diamond: a value outside is taken for
a unit slip (a modulus in Pa or MPa)."""
MAX_HALF_WIDTH_RATIO = 0.1
"""Largest Hertz half-width ``b`` against the relative radius ``R'`` where the stress peaks
(``b / R' = 2 p / E*``) for which the Hertz line contact holds (it needs ``b << R'``)."""


ABSURD_SIZES = {"mm": 10_000.0, "kg": 10_000.0, "N": 1e6, "N/mm": 1e9}
"""Sizes no cam machine has, by unit: a length past 10 m, a moving mass past 10 tonnes, a
force past a meganewton, a stiffness past 1e9 N/mm.  A value past them is computed but
warned of (``size_warnings``): often a unit slip, and a length past 1e12 mm also loses the
cam's curvature to rounding."""
_SIZED_FIELDS = (("base_radius_mm", "mm"), ("roller_radius_mm", "mm"), ("offset_mm", "mm"), ("arm_mm", "mm"),
                 ("pivot_mm", "mm"), ("groove_clearance_mm", "mm"),  # contact_width_mm: against the base circle
                 ("mass_kg", "kg"), ("preload_n", "N"), ("stiffness_n_per_mm", "N/mm"),
                 ("spring_rate_n_per_mm", "N/mm"))


def size_warnings(program: Program) -> list[str]:
    """A line for each follower field and segment lift past ``ABSURD_SIZES``, naming the key
    and its value."""
    f = program.follower
    given = [(f"follower.{name}", getattr(f, name), unit) for name, unit in _SIZED_FIELDS
             if getattr(f, name) is not None and not (name == "roller_radius_mm" and f.flat_face)]
    given += [(f"segment {i}: lift_mm", s.lift_mm, "mm") for i, s in enumerate(program.segments, 1)]
    return [f"{key} = {value:g} is more than {ABSURD_SIZES[unit]:,.0f} {unit}, larger than any cam machine's: "
            f"check its unit ({unit})" for key, value, unit in given if abs(value) > ABSURD_SIZES[unit]]


def design_warnings(program: Program, report=None) -> list[str]:
    """Where the input or a result lies outside what the design rules and the models hold,
    one line each (empty where all is well): the program's own numbers (sizes past
    ``ABSURD_SIZES``, a grooved cam's preload, a lift table's noise or spacing among them), and
    with ``report`` (``analyse``'s ``Report`` or its ``as_dict()``) its speeds
    (``speed_warnings``), the pressure angle, the Hertz contact and a grooved cam's strikes
    that did not settle.

    Each is a warning, not an error: the numbers are computed, but they are not to be
    trusted as they stand.  ``analyse`` puts them in its report (``Report.warnings``, in
    ``--format json`` and the studio); ``camjax program`` prints them on stderr.
    """
    out = table_warnings(program)  # first: a drawing's or table's note says what was read
    f, materials = program.follower, program.materials
    report = report.as_dict() if hasattr(report, "as_dict") else report
    limit = f.geometry.max_pressure_angle_deg  # a roller's: 30 degrees translating, 45 swinging
    angle = ((report or {}).get("geometry") or {}).get("max_pressure_angle_deg")
    if limit is not None and angle is not None and abs(angle) > limit:
        out.append(f"the pressure angle reaches {abs(angle):.3g} deg, above the {limit:g} deg a "
                   f"{f.kind} follower tolerates: enlarge follower.base_radius_mm "
                   "or lengthen the rises")
    out += size_warnings(program)
    if f.form_closed and f.preload_n != 0:
        out.append(f"follower.preload_n = {f.preload_n:g} does nothing on a grooved cam (no "
                   "spring_rate_n_per_mm: no return spring preloads the follower, the groove holds it): "
                   "remove it, or give the return spring's spring_rate_n_per_mm")
    stroke = max(abs(float(y)) for y in np.cumsum([s.lift_mm for s in program.segments]))
    if stroke > 2 * f.base_radius_mm:
        out.append(f"the lift ({stroke:g} mm) is more than twice the base circle's radius "
                   f"({f.base_radius_mm:g} mm): check the program's units")
    low, high = MODULUS_RANGE_GPA
    for part in ("cam", "follower"):
        modulus = getattr(materials, f"{part}_youngs_modulus_gpa")
        if not low <= modulus <= high:
            out.append(f"materials.{part}_youngs_modulus_gpa = {modulus:g} lies outside {low:g}-{high:g} "
                       "GPa (steel is about 210): check the unit (GPa, not Pa or MPa)")
    if f.contact_width_mm is None and materials != type(materials)():
        out.append("[materials] is used only for the Hertz contact stress, which needs "
                   "follower.contact_width_mm: without it no stress is computed")
    if f.contact_width_mm is not None and f.contact_width_mm > 20 * f.base_radius_mm:
        out.append(f"follower.contact_width_mm = {f.contact_width_mm:g} is more than ten times the "
                   f"base circle's diameter: check the unit (mm)")
    if report is None:
        return out
    out += speed_warnings(program, [s["rpm"] for s in report["speeds"]])
    worst = max((s for s in report["speeds"] if s.get("contact_half_width_mm")),
                key=lambda s: s["max_contact_stress_mpa"], default=None)
    if worst is not None:
        ratio = 2 * worst["max_contact_stress_mpa"] / materials.contact_modulus_mpa  # b / R'
        if ratio > MAX_HALF_WIDTH_RATIO:
            radius = worst["contact_half_width_mm"] / ratio
            out.append(f"at {worst['rpm']:g} rpm the Hertz contact half-width "
                       f"({worst['contact_half_width_mm']:.3g} mm) is {ratio:.3g} times the relative "
                       f"radius of the contact ({radius:.3g} mm), past the {MAX_HALF_WIDTH_RATIO:g} "
                       "where Hertz theory holds: its stress "
                       f"({worst['max_contact_stress_mpa']:.3g} MPa) is not to be trusted; check "
                       "follower.contact_width_mm and the moduli")
    out += _unsettled_grooves(report["speeds"])
    return out


def _unsettled_grooves(speeds) -> list[str]:
    """A grooved cam's strikes that still moved from turn to turn after the longest run."""
    from ._groove import MAX_GROOVE_SAMPLES, MAX_TURNS, SETTLED_DEG

    out = []
    for s in speeds:
        change = s.get("impacts_change_deg")
        if change is not None and not change <= SETTLED_DEG:
            out.append(f"at {s['rpm']:g} rpm the groove's strikes had not settled within the longest run "
                       f"allowed ({MAX_TURNS} turns, {MAX_GROOVE_SAMPLES:,} samples; "
                       + (f"they still move by {change:.3g} deg per turn" if math.isfinite(change) else
                          "they still differ in number or flank from turn to turn")
                       + "): the roller chatters without a period, and the last turn is reported; a "
                       "narrower groove (groove_clearance_mm) or more damping settles sooner")
    return out


NOISY_ACCELERATION_RATIO = 1.2
"""A table fit's peak acceleration this many times that of a fit smoothed to three times the
points' scatter: the noise, not the cam, sets its accelerations."""
COARSE_SPACING_CHANGE = 0.05
"""A change of the peak acceleration this large when every other point of a table is
dropped: the spacing does not resolve the acceleration."""


def table_warnings(program: Program) -> list[str]:
    """The lift tables' warnings: points noisy or sparse enough to make the accelerations
    unreliable (``camjax.laws.TableFit``'s two checks), once per table."""
    out, seen = [], set()
    for i, seg in enumerate(program.segments, 1):
        fit = getattr(seg.law, "fit_info", None)
        if fit is None or (fit.turn is not None and fit.turn in seen):
            continue
        where = "the cam's lift table" if fit.turn is not None else f"segment {i}: the lift table"
        if fit.turn is not None:
            seen.add(fit.turn)
        where += f" ({fit.source})"
        out += list(fit.notes)
        if fit.acceleration_ratio > NOISY_ACCELERATION_RATIO:
            out.append(f"{where}: the points scatter by about {fit.noise_mm:.2g} mm; the fit's peak "
                       f"acceleration is {fit.acceleration_ratio:.3g} times that of a fit within "
                       f"{3 * fit.noise_mm:.2g} mm of them, so its accelerations and forces follow the "
                       f"noise: set smoothing_mm = {3 * fit.noise_mm:.2g} (about three times the scatter)")
        elif math.isnan(fit.spacing_ratio):
            count = len(fit.turn if fit.turn is not None else fit.points)
            out.append(f"{where}: its {count} points are too few to check that they resolve the "
                       "acceleration (a fit through every other point needs 6); give points closer together")
        elif abs(fit.spacing_ratio - 1) > COARSE_SPACING_CHANGE:
            angles = [a for a, _ in (fit.turn if fit.turn is not None else fit.points)]
            spacing = max(np.diff(angles + ([360.0] if fit.turn is not None else [])))
            out.append(f"{where}: its points (up to {spacing:.3g} deg apart) are too sparse for its "
                       f"acceleration: against {fit.spacing_check}, the peak acceleration differs "
                       f"by {100 * abs(fit.spacing_ratio - 1):.3g}%; give points closer together")
    return out
