"""The largest Hertz stress, its angle and its half-width refined between the grid's nodes,
against an independent reference on the four follower kinds: the Hertz formula of the
mission (``p = sqrt(F_n E* / (pi L R'))``, ``F_n = F_c / cos(phi)``, ``1/R' = 1/r_r +
1/rho``) on the program's contact geometry at any angle, with the exact contact force of
the steady state there (``SteadyState.mode_at``), maximised densely and then by scipy."""

import math

import numpy as np
import pytest
from helpers import FOLLOWER, follower_constants
from scipy.optimize import minimize_scalar

from camjax import laws
from camjax.program import (
    Follower,
    Program,
    Segment,
    SteadyState,
    analyse,
    contact_geometry,
    response,
)
from camjax.sdof import deflection_gains

RPM = (500.0, 900.0)


def cam(kind: str, **follower) -> Program:
    """A cycloidal rise of 12 mm over 120 degrees, a dwell, a modified-sine return, a dwell."""
    base = {**FOLLOWER, "kind": kind, "contact_width_mm": 10.0, **follower}
    if kind.endswith("-flat"):
        base.pop("roller_radius_mm")
    segments = (
        Segment(120, 12.0, laws.get("cycloidal")),
        Segment(60),
        Segment(110, -12.0, laws.get("modified-sine")),
        Segment(70),
    )
    return Program(kind, segments, Follower(**base))


KINDS = {
    "translating-roller": cam("translating-roller"),
    "swinging-roller": cam("swinging-roller", arm_mm=90.0, pivot_mm=110.0),
    "translating-flat": cam("translating-flat"),
    "swinging-flat": cam("swinging-flat", arm_mm=90.0, pivot_mm=110.0),
}


def hertz(program: Program, steady: SteadyState, rpm: float):
    """``theta_deg -> (p_max, R')`` from the mission's formula, the force exact anywhere."""
    train, f = follower_constants(steady.program), program.follower
    q_nodes = steady.cycle(rpm).q
    ge, gr = (complex(g) for g in deflection_gains(train.omega_per_turn(rpm), train.zeta))
    gain = 1e-3 * train.k * ge + 1e-3 * train.c / (60.0 / rpm) * gr
    e_star = program.materials.contact_modulus_mpa

    def at(theta_deg):
        theta_deg = np.atleast_1d(np.asarray(theta_deg, dtype=float))
        force = train.preload + np.real(gain * steady.mode_at(q_nodes, rpm, theta_deg / 360.0)[0])
        g = contact_geometry(program, theta_deg)
        rho = g.cam_radius_mm[1]  # inside an interval both sides agree
        curvature = 1.0 / rho + (0.0 if f.flat_face else 1.0 / f.roller_radius_mm)
        normal = force * g.normal_per_contact[1]
        r_eff = 1.0 / curvature
        return np.sqrt(
            np.maximum(normal, 0.0) * e_star / (math.pi * f.contact_width_mm * r_eff)
        ), r_eff

    return at


def reference(program: Program, steady: SteadyState, rpm: float):
    """``(p_max, angle, half-width)``: the best of 72,000 angles, then scipy's bounded search
    within one spacing of it."""
    at = hertz(program, steady, rpm)
    theta = np.linspace(0.0, 360.0, 72001)[:-1]
    i = int(np.argmax(at(theta)[0]))
    step = theta[1] - theta[0]
    best = minimize_scalar(
        lambda t: -float(at(t)[0][0]),
        bounds=(theta[i] - step, theta[i] + step),
        method="bounded",
        options={"xatol": 1e-11},
    )
    p, r_eff = (float(v[0]) for v in at(best.x))
    return p, float(best.x) % 360.0, 2 * r_eff * p / program.materials.contact_modulus_mpa


@pytest.mark.parametrize("kind", list(KINDS))
def test_largest_hertz_stress_is_refined_between_the_nodes(kind):
    program = KINDS[kind]
    steady = SteadyState(program, min(RPM))
    report = analyse(program, list(RPM), steady=steady, with_flight=False)
    for rpm, speed in zip(RPM, report.speeds):
        p, angle, half_width = reference(program, steady, rpm)
        assert speed.max_contact_stress_mpa == pytest.approx(p, rel=1e-8)
        assert speed.contact_half_width_mm == pytest.approx(half_width, rel=1e-8)
        assert abs(speed.max_contact_stress_deg - angle) < 1e-6  # measured 3e-7: the crest is flat
        nodes = response(program, rpm, steady=steady)["contact_stress_mpa"]
        assert speed.max_contact_stress_mpa >= nodes.max()  # the nodes' largest is a lower bound
