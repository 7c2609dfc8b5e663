"""Physical invariants of whole cam programs, over a matrix of segment kinds and follower
kinds, each against an independent NumPy/SciPy computation: the energy balance of the
periodic steady state, the drive torque as the moment of the normal contact force, the
stiff-train (kinetostatic) limit, a swinging follower on a long arm against the
translating one, a flat face's curvature and width, a shaft of phased cams, and a program
rotated to start its turn elsewhere; and a second program of named laws, an asymmetric law and
a B-spline (``trade_segments``) on a spring-loaded and a grooved follower.

``MIXED`` holds every segment kind: dwells, a cycloidal rise, an SCCA return (modified
trapezoid), boundary quintics with ``"match"`` and with given end states, a rising and a
falling constant-velocity stroke, and a constant-velocity stroke whose join with the turn's
last segment is the wrap at 360 degrees (it starts the turn in motion).  Its angles are not
whole degrees.  The lift is rebuilt here from each law's positions alone (Chebyshev fits
per smooth piece, differentiated), so no derivative of camjax's is used as a reference.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from helpers import FOLLOWER, scipy_periodic_deflection

from camjax import laws
from camjax.program import (
    EndState,
    Follower,
    Program,
    Segment,
    SteadyState,
    cam_geometry,
    profile,
    response,
    shaft_torque,
)

RPM = 300.0
_CHEB_DEGREE = 40  # sin(6 pi tau) of the triple harmonic needs it: degree 24 leaves 2e-8

def mixed_segments():
    """Every segment kind over one turn (angles not whole degrees, the wrap in motion)."""
    return (
        Segment.constant_velocity(20.3, 3.0),                                   # G from the wrap
        Segment.polynomial(30.5, 2.0),                                          # match G -> R
        Segment(15.7),
        Segment(60.3, 12.0, laws.get("cycloidal")),
        Segment(15.2),
        Segment.polynomial(40.1, -4.0, start=EndState(0.0, 0.0), end=EndState(-0.12, 0.0)),  # given ends
        Segment.constant_velocity(25.0, -3.0),                                  # -0.12 mm/deg
        Segment.polynomial(35.4, -4.0),                                         # match G -> R
        Segment(40.0, -6.0, laws.get("modified-trapezoid")),                    # SCCA, down to the base circle
        Segment(24.0),                                                          # at 282.5 deg
        Segment(25.0, 1.5, laws.get("poly345")),
        Segment.polynomial(28.5, -1.5),  # rest -> the wrap's 3/20.3 mm/deg: dips below the base circle
    )


def mixed(**follower) -> Program:
    """``mixed_segments`` on a translating roller with offset, a train soft enough for a cheap
    SciPy reference (18 vibrations per turn at ``RPM``)."""
    return Program("mixed", mixed_segments(), Follower(**{**FOLLOWER, "offset_mm": 6.0, "contact_width_mm": 10.0,
                                                             "stiffness_n_per_mm": 500.0, **follower}))


class NumpyLift:
    """The program's lift and its first two derivatives (mm, per degree) from each law's
    positions alone: a Chebyshev fit of ``s`` on every smooth piece of every segment,
    differentiated in NumPy; ``side`` picks the segment ending or starting at a join."""

    def __init__(self, program: Program):
        self.pieces = []  # (theta0, theta1, y0, h, beta, tau0, tau1, chebyshev of s)
        for seg, start, y0 in zip(program.segments, program.start_deg, program.start_lift_mm):
            if not seg.moving:
                self.pieces.append((start, start + seg.angle_deg, y0, 0.0, seg.angle_deg, 0.0, 1.0, None))
                continue
            edges = [0.0, *seg.law.breakpoints(), 1.0]
            for a, b in zip(edges[:-1], edges[1:]):
                nodes = 0.5 * (a + b) + 0.5 * (b - a) * np.cos(np.pi * (np.arange(_CHEB_DEGREE + 1) + 0.5)
                                                             / (_CHEB_DEGREE + 1))
                s = np.asarray(seg.law.s(nodes))
                fit = np.polynomial.Chebyshev.fit(nodes, s, _CHEB_DEGREE, domain=[a, b])
                self.pieces.append((start + a * seg.angle_deg, start + b * seg.angle_deg, y0, seg.lift_mm,
                                    seg.angle_deg, a, b, fit))
        self.edges_deg = np.array([p[0] for p in self.pieces] + [360.0])
        self._coefficients = {}

    def __call__(self, theta_deg, side: str = "after"):
        theta = np.atleast_1d(np.mod(np.asarray(theta_deg, dtype=float), 360.0))
        if side == "before":
            theta = np.where(theta < 1e-9, 360.0, theta)
        k = np.searchsorted(self.edges_deg, theta, side="left" if side == "before" else "right") - 1
        k = np.clip(k, 0, len(self.pieces) - 1)
        out = np.zeros((3, theta.size))
        for i in np.unique(k):
            t0, _, y0, h, beta, a, _, fit = self.pieces[i]
            at = k == i
            out[0, at] = y0
            if fit is not None:
                tau = a + (theta[at] - t0) / beta
                out[:, at] += np.stack([h * fit(tau), h * fit.deriv(1)(tau) / beta, h * fit.deriv(2)(tau) / beta**2])
        return out

    def scalar(self, theta_deg):
        """``(y, y', y'')`` at one angle, quickly (the ODE's right-hand side)."""
        t = float(theta_deg) % 360.0
        k = min(max(int(np.searchsorted(self.edges_deg, t, side="right")) - 1, 0), len(self.pieces) - 1)
        t0, _, y0, h, beta, a, _, fit = self.pieces[k]
        if fit is None:
            return y0, 0.0, 0.0
        if k not in self._coefficients:
            self._coefficients[k] = (fit.mapparms(), [fit.deriv(d).coef if d else fit.coef for d in range(3)])
        (off, scl), coefficients = self._coefficients[k]
        u = off + scl * (a + (t - t0) / beta)
        s, v, acc = (np.polynomial.chebyshev.chebval(u, c) for c in coefficients)
        return y0 + h * s, h * v / beta, h * acc / beta**2


@pytest.fixture(scope="module")
def program():
    return mixed()


@pytest.fixture(scope="module")
def lift(program):
    return NumpyLift(program)


@pytest.fixture(scope="module")
def steady(program):
    return SteadyState(program, RPM)


@pytest.fixture(scope="module")
def history(program, steady):
    return response(program, RPM, steady=steady)


def rotated(program: Program, start: int, split: float | None = None) -> Program:
    """``program`` with its turn starting at segment ``start``'s start (0-based), or
    ``split`` degrees into that segment (a dwell) when given."""
    segments = list(program.segments)
    if split is None:
        out = segments[start:] + segments[:start]
    else:
        seg = segments[start]
        assert not seg.moving
        out = [Segment(seg.angle_deg - split)] + segments[start + 1:] + segments[:start] + [Segment(split)]
    return dataclasses.replace(program, segments=tuple(out))


# -- geometry alone ----------------------------------------------------------------------------


def test_the_numpy_lift_is_the_programs(program, lift):
    """The reference lift agrees with the program's own where both are smooth (a check of
    the reference, at angles off every join and breakpoint)."""
    theta = np.linspace(0.0, 360.0, 721)[1:-1] + 0.123
    y, dy, ddy = program.lift(theta)
    mine = lift(theta)
    assert np.abs(mine[0] - y).max() < 1e-9
    assert np.abs(mine[1] - dy).max() < 1e-9
    assert np.abs(mine[2] - ddy).max() < 1e-7


def flat_program(kind="translating-flat", **extra) -> Program:
    """Harmonic, cycloidal, a boundary quintic and a constant-velocity stroke under a flat face
    (acceleration steps at the harmonic's ends)."""
    follower = {**FOLLOWER, "kind": kind, "base_radius_mm": 60.0, **extra}
    follower.pop("roller_radius_mm")
    segments = (Segment(80.3, 10.0, laws.get("harmonic")), Segment(30.2),
                Segment.polynomial(40.1, 5.0, end=EndState(0.1, 0.0)), Segment.constant_velocity(30.0, 3.0),
                Segment.polynomial(35.6, 2.0), Segment(20.0), Segment(93.7, -20.0, laws.get("cycloidal")),
                Segment(30.1))
    return Program("flat", segments, Follower(**follower))


def test_a_flat_faces_curvature_and_width():
    """Translating flat face: the cam's radius of curvature is ``r_b + y + y''`` (y'' per
    radian squared), each side of every join, and the face spans ``max y' - min y'``."""
    program = flat_program()
    lift = NumpyLift(program)
    per_rad = 180.0 / math.pi
    prof = profile(program, 3600)
    y, dy, ddy = lift(prof.theta_deg)
    assert np.abs(prof.profile_radius_of_curvature_mm - (60.0 + y + ddy * per_rad**2)).max() < 1e-6
    geometry = cam_geometry(program, prof.theta_deg)
    for join in geometry.joins:
        for side, got in (("before", join.radius_before_mm), ("after", join.radius_after_mm)):
            y, _, ddy = lift(join.angle_deg, side)
            assert got == pytest.approx(60.0 + y[0] + ddy[0] * per_rad**2, rel=1e-9, abs=1e-5), (join, side)
    sampled = lift(prof.theta_deg)[1] * per_rad  # the width over the angles given, and between them
    assert geometry.face_width_mm == pytest.approx(np.ptp(sampled), rel=1e-9)
    dense = lift(np.linspace(0.0, 360.0, 200_001))[1] * per_rad
    assert geometry.face_width_mm == pytest.approx(np.ptp(dense), rel=1e-5)
    y, _, ddy = lift(prof.theta_deg)
    sides = [60.0 + lift(j.angle_deg, side)[0][0] + lift(j.angle_deg, side)[2][0] * per_rad**2
             for j in geometry.joins for side in ("before", "after")]
    assert geometry.min_radius_of_curvature_mm == pytest.approx(
        min((60.0 + y + ddy * per_rad**2).min(), *sides), rel=1e-7)


@pytest.mark.parametrize("flat", [False, True])
def test_a_swinging_follower_on_a_long_arm_approaches_the_translating_one(flat):
    """Swinging about a pivot far away, with the arm square to the radius at rest (a roller)
    or the face through the pivot tangent to the base circle (a flat face): the pressure
    angle and the radius of curvature tend to the translating follower's, the difference
    falling as 1/arm."""
    base = flat_program()
    if flat:
        translating = profile(base, 720)

        def swinging(arm):
            pivot = math.hypot(arm, 60.0)
            follower = dataclasses.replace(base.follower, kind="swinging-flat", arm_mm=arm, pivot_mm=pivot)
            return profile(dataclasses.replace(base, follower=follower), 720)
    else:
        roller = dataclasses.replace(base.follower, kind="translating-roller", roller_radius_mm=10.0)
        translating = profile(dataclasses.replace(base, follower=roller), 720)

        def swinging(arm):
            follower = dataclasses.replace(roller, kind="swinging-roller", arm_mm=arm, pivot_mm=math.hypot(arm, 70.0))
            return profile(dataclasses.replace(base, follower=follower), 720)

    errors = []
    for arm in (1e4, 1e5):
        swing = swinging(arm)
        radius = np.abs(swing.pitch_radius_of_curvature_mm - translating.pitch_radius_of_curvature_mm).max()
        pressure = np.abs(np.abs(swing.pressure_angle_deg) - np.abs(translating.pressure_angle_deg)).max()
        distance = np.abs(np.linalg.norm(swing.pitch, axis=1) - np.linalg.norm(translating.pitch, axis=1)).max()
        errors.append((radius, pressure, distance))
    (r1, p1, d1), (r2, p2, d2) = errors
    assert r2 < 0.2 * r1 + 1e-9 and r2 < 0.05  # mm (measured: 0.010 roller, 0.022 flat face at 1e5 mm)
    assert p2 < 0.2 * p1 + 1e-9 and p2 < 0.05  # degrees
    assert d2 < 0.2 * d1 + 1e-9 and d2 < 0.05  # mm


# -- the periodic steady state ---------------------------------------------------------------------


def test_energy_balance_of_the_steady_state(program, lift, steady, history):
    """With contact held, the work of the drive over a turn, ``2 pi mean T``, is the damper's
    dissipation ``c int e'^2 dt``: the deflection by SciPy's periodic solve of the physical
    equation, integrated by Gauss-Legendre per smooth piece; the response's deflection at
    the nodes against the same solve."""
    cycle = steady.cycle(RPM)
    assert cycle.min_contact_force_n > 0
    f = program.follower
    period = 60.0 / RPM
    x, w = np.polynomial.legendre.leggauss(24)
    edges = lift.edges_deg / 360.0 * period
    times = np.concatenate([0.5 * (a + b) + 0.5 * (b - a) * x for a, b in zip(edges[:-1], edges[1:])])
    weights = np.concatenate([0.5 * (b - a) * w for a, b in zip(edges[:-1], edges[1:])])
    nodes_t = history["theta_deg"][:-1] / 360.0 * period
    both = np.concatenate([times, nodes_t])
    order = np.argsort(both)
    solved = np.empty((2, both.size))
    solved[:, order] = scipy_periodic_deflection(f, RPM, lift.scalar, lift.edges_deg, both[order])
    e, de = solved[:, :times.size]
    dissipation = f.damping * np.sum(weights * de**2)  # J per turn
    assert 2 * math.pi * float(cycle.mean_drive_torque_n_m) == pytest.approx(dissipation, rel=1e-6)
    deflection = 1e-3 * (history["lift_mm"] - history["payload_displacement_mm"])[:-1]
    assert np.abs(deflection - solved[0, times.size:]).max() < 1e-7 * np.abs(deflection).max()


def _numpy_moment(kind: str, force, y, dy_rad):
    """Moment (N m) about the cam centre of the normal contact force, from the lift alone:
    the roller centre ``C`` in the frame the cam turns in (counter-clockwise), the pitch
    curve's tangent ``dC/dtheta - J C`` there, the force along its normal with its component
    along the follower's path equal to ``F_c``."""
    r0 = 52.0  # base 40 + roller 12
    if kind == "flat":  # the contact lies y' from the axis, the force square to the face
        return 1e-3 * force * dy_rad
    if kind.startswith("translating"):
        offset = {"translating": 0.0, "translating-offset": 6.0, "translating-negative-offset": -9.0}[kind]
        centre = np.stack([np.full_like(y, offset), math.sqrt(r0**2 - offset**2) + y])
        path = np.stack([np.zeros_like(y), np.ones_like(y)])  # unit direction of increasing lift
        d_centre = path * dy_rad
    else:  # swinging: pivot at (d, 0), arm square to the radius at rest, lift = arc length
        arm = 98.0
        d = math.hypot(arm, r0)
        psi = math.pi - math.atan2(r0, arm) - y / arm  # arm direction from the pivot
        centre = np.stack([d + arm * np.cos(psi), arm * np.sin(psi)])
        path = np.stack([np.sin(psi), -np.cos(psi)])  # outward at rest
        d_centre = path * dy_rad
    tangent = d_centre - np.stack([-centre[1], centre[0]])
    normal = np.stack([-tangent[1], tangent[0]]) / np.linalg.norm(tangent, axis=0)
    normal *= np.sign(np.sum(normal * path, axis=0))  # pushing the follower up its path
    normal_force = force / np.sum(normal * path, axis=0)
    return 1e-3 * normal_force * (centre[0] * normal[1] - centre[1] * normal[0])


@pytest.mark.parametrize("kind", ["translating", "translating-offset", "translating-negative-offset",
                                  "swinging", "flat"])
def test_drive_torque_is_the_moment_of_the_normal_force(kind, lift, history):
    """``T`` at every node (joins and the wrap in motion included) is the moment about the cam
    axis of the normal contact force, with the follower's geometry (translating with and
    without offset, swinging, flat face) and the lift's slope computed here: the torque the
    program reports (``F_c dy/dtheta``, the same for every follower of that lift) is the one
    every geometry's moment gives."""
    theta = history["theta_deg"]
    y, dy, _ = lift(theta)
    moment = _numpy_moment(kind, history["contact_force_n"], y, dy * 180.0 / math.pi)
    assert np.abs(moment - history["drive_torque_n_m"]).max() < 1e-9 * np.abs(moment).max()
    assert np.abs(moment).max() > 1.0


def test_drive_torque_is_the_moment_of_the_normal_force_where_a_turn_starts_at_rest(turned):
    """The same on the program turned to start in its dwell: the constant-velocity stroke
    that started the turn now starts at 77.5 degrees, and its first node's torque must be
    ``F_c y'`` there too (it reads ``y' = 0``: the grid node lands a hair before the
    segment's start)."""
    p, _, s = turned["segment"]
    history = response(p, RPM, steady=s)
    y, dy, _ = NumpyLift(p)(history["theta_deg"])
    moment = _numpy_moment("translating-offset", history["contact_force_n"], y, dy * 180.0 / math.pi)
    assert np.abs(moment - history["drive_torque_n_m"]).max() < 1e-9 * np.abs(moment).max()


def test_a_very_stiff_train_gives_the_kinetostatic_force(program, lift):
    """Train stiffness x 1e5: the contact force is the rigid one, ``m y_tt + k_s y + F_0``,
    with ``y_tt`` from the reference lift.  Every join of ``mixed`` is C2, so nothing rings
    but what the jerk steps excite, ``m |jump of y_ttt| / w_n``: 2.5 N at the 3-4-5's end
    (jerk 60 h / beta^3) into a quintic, 0.4% of the peak inertia force."""
    stiff = dataclasses.replace(program, follower=dataclasses.replace(program.follower, stiffness_n_per_mm=2e8))
    rpm = 600.0
    h = response(stiff, rpm)
    y, _, ddy = lift(h["theta_deg"])
    rate = 360.0 * rpm / 60.0  # deg/s
    f = stiff.follower
    inertia = f.mass_kg * 1e-3 * ddy * rate**2
    rigid = inertia + f.spring_rate * 1e-3 * y + f.preload_n
    assert np.abs(h["contact_force_n"] - rigid).max() < 1e-2 * np.abs(inertia).max()


# -- a program rotated, and a shaft of two cams --------------------------------------------------------


@pytest.fixture(scope="module")
def turned(program):
    """The program starting at its tenth segment's start (a dwell on the base circle at
    282.5 degrees), and 12.25 degrees into that dwell."""
    out = {}
    for key, start, split in (("segment", 9, None), ("inside", 9, 12.25)):
        p = rotated(program, start, split)
        shift = float(program.start_deg[start]) + (split or 0.0)
        out[key] = (p, shift, SteadyState(p, RPM))
    return out


FIGURES = ("max_payload_acceleration_m_s2", "min_contact_force_n", "max_contact_force_n", "max_drive_torque_n_m",
           "rms_drive_torque_n_m", "mean_drive_torque_n_m", "energy_fluctuation_j", "max_contact_stress_mpa")


@pytest.mark.parametrize("key", ["segment", "inside"])
def test_rotating_the_program_shifts_angles_and_keeps_every_magnitude(key, program, steady, turned):
    """Starting the turn at another segment's start, or inside a dwell at a non-whole angle,
    moves every angle by the shift and changes no magnitude: peak and least force, payload
    acceleration, the torque figures, the peak contact stress, the residuals as a set, and
    the force and torque at every node both grids share."""
    p, shift, s = turned[key]
    base, moved = steady.cycle(RPM), s.cycle(RPM)
    for name in FIGURES:
        a, b = float(getattr(base, name)), float(getattr(moved, name))
        assert b == pytest.approx(a, rel=1e-9, abs=1e-12), name
    residual, again = np.asarray(base.residual_vibration_mm), np.asarray(moved.residual_vibration_mm)
    # A dwell split in two adds its second part's (the decayed vibration there).
    assert again.size == residual.size + (key == "inside")
    for r in residual:
        assert np.abs(again - r).min() < 1e-9 * max(1.0, abs(r)), (r, again)
    theta = np.mod(360.0 * steady.grid.nodes[:-1], 360.0)
    theta_moved = np.mod(360.0 * s.grid.nodes[:-1] + shift, 360.0)
    distance = np.abs(theta[:, None] - theta_moved[None, :])
    distance = np.minimum(distance, 360.0 - distance)
    i, j = np.nonzero(distance < 1e-9)
    assert i.size > 0.8 * theta.size
    for name in ("contact_force_n", "drive_torque_n_m"):
        a, b = np.asarray(getattr(base, name))[:-1][i], np.asarray(getattr(moved, name))[:-1][j]
        assert np.abs(a - b).max() < 1e-9 * np.abs(a).max(), name
    peak = 360.0 * steady.grid.nodes[int(base.max_contact_stress_node)]
    peak_moved = 360.0 * s.grid.nodes[int(moved.max_contact_stress_node)] + shift
    assert abs((peak_moved - peak + 180.0) % 360.0 - 180.0) < 1e-9


def test_a_shaft_of_a_cam_and_its_rotation_put_back_in_phase_is_twice_the_cam(program, steady, turned):
    """The rotated program mounted at its shift is the same cam: the shaft's torque is twice
    the cam's at every node of the cam's grid, and at every other node of the union the sum
    of the two cams' torques (each the same function of the angle)."""
    p, shift, s = turned["segment"]
    cycles = [steady.cycle(RPM), s.cycle(RPM)]
    nodes, values, _, _ = shaft_torque(cycles, [steady.grid.nodes, s.grid.nodes], (0.0, shift))
    torque = np.asarray(cycles[0].drive_torque_n_m)
    at = np.searchsorted(nodes, steady.grid.nodes - 1e-12)
    assert np.abs(nodes[at] - steady.grid.nodes).max() < 1e-11
    assert np.abs(values[at] - 2 * torque).max() < 1e-9 * np.abs(torque).max()


# -- laws of the trade, an asymmetric law, a B-spline, a grooved follower ---------------------------


def trade_segments():
    """Named laws (Freudenstein 1-3, the zero-jerk triple harmonic), an asymmetric modified
    sine and a B-spline rise between dwells (angles not whole degrees)."""
    spline = laws.BSplineLaw(np.array([0.15, 0.35, 0.6, 0.85]))
    return (
        Segment(70.3, 9.0, laws.get("freudenstein-1-3")),
        Segment(20.0),
        Segment(55.5, -4.0, laws.get("modified-sine-asym:0.35")),
        Segment(15.0),
        Segment(60.0, 3.0, spline),
        Segment(25.0),
        Segment(50.0, -8.0, laws.get("triple-harmonic-zero-jerk")),
        Segment(64.2),
    )


TRADE_FOLLOWERS = {
    "spring": {},
    "grooved": {"spring_rate_n_per_mm": None, "preload_n": 0.0},
}


@pytest.fixture(scope="module", params=list(TRADE_FOLLOWERS))
def trade(request):
    """``(program, NumPy lift, steady state, response)`` of the trade laws on a spring-loaded
    and on a grooved (form-closed) translating roller."""
    follower = {**FOLLOWER, "offset_mm": 6.0, "stiffness_n_per_mm": 500.0, **TRADE_FOLLOWERS[request.param]}
    program = Program("trade", trade_segments(), Follower(**follower))
    steady = SteadyState(program, RPM)
    return program, NumpyLift(program), steady, response(program, RPM, steady=steady)


def test_the_numpy_lift_is_the_programs_for_the_trade_laws(trade):
    program, lift, _, _ = trade
    theta = np.linspace(0.0, 360.0, 721)[1:-1] + 0.123
    mine, theirs = lift(theta), np.stack(program.lift(theta))
    for d, tolerance in enumerate((1e-9, 1e-9, 1e-7)):
        assert np.abs(mine[d] - theirs[d]).max() < tolerance, d


def test_energy_balance_of_the_trade_laws(trade):
    """As ``test_energy_balance_of_the_steady_state``: the drive's work over a turn is the
    damper's dissipation, the deflection SciPy's periodic solve of the physical equation
    (no return spring for the grooved follower)."""
    program, lift, steady, history = trade
    cycle = steady.cycle(RPM)
    f = program.follower
    period = 60.0 / RPM
    x, w = np.polynomial.legendre.leggauss(24)
    edges = lift.edges_deg / 360.0 * period
    times = np.concatenate([0.5 * (a + b) + 0.5 * (b - a) * x for a, b in zip(edges[:-1], edges[1:])])
    weights = np.concatenate([0.5 * (b - a) * w for a, b in zip(edges[:-1], edges[1:])])
    nodes_t = history["theta_deg"][:-1] / 360.0 * period
    both = np.concatenate([times, nodes_t])
    order = np.argsort(both)
    solved = np.empty((2, both.size))
    solved[:, order] = scipy_periodic_deflection(f, RPM, lift.scalar, lift.edges_deg, both[order])
    e, de = solved[:, :times.size]
    dissipation = f.damping * np.sum(weights * de**2)
    assert 2 * math.pi * float(cycle.mean_drive_torque_n_m) == pytest.approx(dissipation, rel=1e-6)
    deflection = 1e-3 * (history["lift_mm"] - history["payload_displacement_mm"])[:-1]
    assert np.abs(deflection - solved[0, times.size:]).max() < 1e-7 * np.abs(deflection).max()


def test_drive_torque_of_the_trade_laws_is_the_moment_of_the_normal_force(trade):
    program, lift, _, history = trade
    y, dy, _ = lift(history["theta_deg"])
    moment = _numpy_moment("translating-offset", history["contact_force_n"], y, dy * 180.0 / math.pi)
    assert np.abs(moment - history["drive_torque_n_m"]).max() < 1e-9 * np.abs(moment).max()
    assert np.abs(moment).max() > 1.0


def test_a_very_stiff_train_gives_the_kinetostatic_force_for_the_trade_laws(trade):
    """Train stiffness x 4e5: the rigid force ``m y_tt + k_s y + F_0`` (no spring and no
    preload on the grooved follower).  The named laws and the B-spline are C2 at their ends;
    the asymmetric modified sine's and the Freudenstein's end jerks ring by ``m |jerk
    step| / w_n``, a fraction of a percent of the peak inertia force."""
    program, lift, _, _ = trade
    stiff = dataclasses.replace(program, follower=dataclasses.replace(program.follower, stiffness_n_per_mm=2e8))
    rpm = 600.0
    h = response(stiff, rpm)
    y, _, ddy = lift(h["theta_deg"])
    rate = 360.0 * rpm / 60.0
    f = stiff.follower
    inertia = f.mass_kg * 1e-3 * ddy * rate**2
    rigid = inertia + f.spring_rate * 1e-3 * y + (0.0 if f.form_closed else f.preload_n)
    assert np.abs(h["contact_force_n"] - rigid).max() < 1e-2 * np.abs(inertia).max()
