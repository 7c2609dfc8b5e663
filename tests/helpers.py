"""One table of every model for the generic tests (as diffrax's ``all_ode_solvers``), the
programs the program tests share, and a record of XLA compilations.

``EXAMPLES`` holds a small valid instance of every model in ``camjax.models.MODELS`` (a
test checks the two agree, so a new model cannot miss the generic tests); ``SDOF_LIMITS``
holds every swept model with its extra physics switched off, which must give the damped
SDOF's numbers (to the tolerance given; ``None``: a model with no damping to compare).
"""

import contextlib
import json
import math
import tomllib
import urllib.error
import urllib.parse
import urllib.request
from typing import NamedTuple

import jax
import numpy as np

from camjax import laws
from camjax.models import (
    MODELS,
    Backlash,
    CoulombFriction,
    SpringMass,
    SwingingFollower,
    TwoMass,
)

EXAMPLES = {
    "spring-mass": lambda: SpringMass(period_ratio=2.0, damping=0.05),
    "friction": lambda: CoulombFriction(period_ratio=2.0, friction=0.1),
    "backlash": lambda: Backlash(period_ratio=2.0, backlash=0.02),
    "two-mass": lambda: TwoMass(period_ratio=2.0, stiffness_ratio=1.0, inertia_ratio=1.0),
    "swinging-follower": lambda: SwingingFollower(),
}

SDOF_LIMITS = {
    "friction": (CoulombFriction(1.0, 0.0, 0.05), 1e-7),
    "backlash": (Backlash(1.0, 0.5, 20.0, 0.05), 1e-7),  # dn holds it on the flank
    "two-mass": (TwoMass(1.0, 1.0, 0.0), None),  # m = 0: a rigid camshaft
}


COMPILED_RTOL = 1e-10
"""Relative agreement of two compilations of one computation: eager and jit, one call and
a vmap, a law alone and in a stack, one device and a sharded batch, a trace read back
from disk, the executable's XLA flags and the library's.  XLA may fuse, reorder and
contract float64 operations differently, each rounding at 1.1e-16; the exact propagation
over up to 1e5 intervals, the peaks' root searches and the quadratures carry such
roundings to about 1e-12 relative (more where terms cancel).  1e-10 leaves that room and
stays far below what each method promises against an independent reference (1e-8 and
coarser), so a change of method still fails it."""

COMPILED_ATOL = 1e-13
"""Absolute agreement of the same, for values that are zero but for roundings (residual
vibration of a law at an integer period ratio): 1e-13 of values of order one."""


def assert_same_numbers(got, expected, rtol=COMPILED_RTOL, atol=COMPILED_ATOL):
    """Equal structure, strings and flags; numbers (in nested dicts and lists, as a JSON
    report holds them) equal to ``rtol`` (``COMPILED_RTOL``: two compilations)."""
    if isinstance(expected, dict):
        assert sorted(got) == sorted(expected)
        for key in expected:
            assert_same_numbers(got[key], expected[key], rtol, atol)
    elif isinstance(expected, list | tuple):
        assert len(got) == len(expected)
        for a, b in zip(got, expected):
            assert_same_numbers(a, b, rtol, atol)
    elif isinstance(expected, float) and not isinstance(got, bool):
        np.testing.assert_allclose(got, expected, rtol=rtol, atol=atol)
    else:
        assert got == expected


FOLLOWER = dict(kind="translating-roller", mass_kg=1.5, stiffness_n_per_mm=2000.0, damping_ratio=0.05,
                spring_rate_n_per_mm=10.0, preload_n=300.0, base_radius_mm=40.0, roller_radius_mm=12.0)
"""The program tests' follower (a ``camjax.program.Follower``'s fields)."""


class FollowerConstants(NamedTuple):
    """A classic follower's constants in SI (k, k_s in N/m; c in N s/m), read from its
    fields apart from the library's oscillator: the tests' reference."""

    m: float
    k: float
    ks: float
    c: float
    preload: float
    omega: float
    zeta: float

    def omega_per_turn(self, rpm):
        return self.omega * 60.0 / rpm


def follower_constants(program) -> FollowerConstants:
    f = program.follower
    m, k, ks = f.mass_kg, 1e3 * f.stiffness_n_per_mm, 1e3 * (f.spring_rate_n_per_mm or 0.0)
    c = 2 * f.damping_ratio * math.sqrt(k * m)
    omega = math.sqrt((k + ks) / m)
    return FollowerConstants(m, k, ks, c, 0.0 if f.spring_rate_n_per_mm is None else f.preload_n, omega,
                             c / (2 * m * omega))


def two_cycloids(**follower):
    """Rise 20 mm (cycloidal, 100 deg), dwell 80, return (cycloidal, 100), dwell 80, with
    ``FOLLOWER`` updated by ``follower``."""
    from camjax.program import Follower, Program, Segment

    law = laws.get("cycloidal")
    return Program("two-cycloids", (Segment(100, 20.0, law), Segment(80), Segment(100, -20.0, law), Segment(80)),
                   Follower(**{**FOLLOWER, **follower}))


def all_models(*, swept: bool | None = None):
    """``(entry, example)`` for every registered model (``swept``: only those that can, or
    cannot, sweep their period ratio)."""
    return [(entry, EXAMPLES[entry.name]()) for entry in MODELS
            if swept is None or entry.swept == swept]


@contextlib.contextmanager
def compiled_programs():
    """The names of the programs XLA compiles inside the block, from ``jax.monitoring``'s
    backend-compile events (``jit(sweep_program)``, ``jit(_response)``, ...): a test that a call
    reuses a compiled program asserts that its name is not among them."""
    names = []

    def listener(event, duration, **kwargs):
        if event == "/jax/core/compile/backend_compile_duration":
            names.append(kwargs.get("fun_name"))

    jax.monitoring.register_event_duration_secs_listener(listener)
    try:
        yield names
    finally:
        jax.monitoring.unregister_event_duration_listener(listener)


def scipy_periodic_deflection(follower, rpm, lift, edges_deg, times, rtol=1e-12):
    """Periodic deflection ``e, e'`` (m, m/s) of a cam program's physical SDOF at ``times``
    (s, within one turn), by scipy shooting: one turn from three starts, then the fixed point.

    ``follower`` is a ``camjax.program.Follower``; ``lift(theta_deg)`` gives the lift (mm) and
    its first two derivatives in degrees, whose second jumps only at ``edges_deg`` (0 to 360),
    where each solve restarts; ``rtol`` is the solver's (DOP853).
    """
    from scipy.integrate import solve_ivp

    m, k, ks, c = follower.mass_kg, follower.stiffness, follower.spring_rate, follower.damping
    rate = 360.0 * rpm / 60.0  # deg/s

    def rhs(t, z):
        y, _, ddy = lift(rate * t)
        return [z[1], 1e-3 * (ddy * rate**2 + ks / m * y) - c / m * z[1] - (k + ks) / m * z[0]]

    def run(z0, t_eval=None):
        edges = np.asarray(edges_deg, float) / rate
        z, out = np.asarray(z0, float), []
        for a, b in zip(edges[:-1], edges[1:]):
            sol = solve_ivp(rhs, (a, b), z, method="DOP853", rtol=rtol, atol=1e-16, dense_output=True)
            if t_eval is not None:
                inside = t_eval[(t_eval >= a) & (t_eval < b)]
                if inside.size:
                    out.append(sol.sol(inside))
            z = sol.y[:, -1]
        return z, (np.concatenate(out, axis=1) if out else None)

    b, _ = run([0.0, 0.0])
    monodromy = np.column_stack([run(e)[0] - b for e in ([1.0, 0.0], [0.0, 1.0])])
    return run(np.linalg.solve(np.eye(2) - monodromy, b), times)[1]


def scipy_deflection(follower, rpm, lift, edges_deg, times, start=(0.0, 0.0)):
    """Deflection ``e, e'`` (m, m/s) of a cam program's physical SDOF at ``times`` (s, over
    any number of turns) from the state ``start`` at ``t = 0``, by scipy (DOP853, rtol 1e-12):
    ``m x'' = k (y - x) + c (y' - x') - k_s x`` in ``e = y - x``.  ``lift`` and ``edges_deg``
    as in ``scipy_periodic_deflection`` (one turn; the edges repeat every turn)."""
    from scipy.integrate import solve_ivp

    m, k, ks, c = follower.mass_kg, follower.stiffness, follower.spring_rate, follower.damping
    rate = 360.0 * rpm / 60.0  # deg/s
    times = np.asarray(times, float)
    turns = int(np.ceil(times.max() * rate / 360.0 + 1e-12))
    edges = np.unique(np.concatenate([np.asarray(edges_deg, float) + 360.0 * j for j in range(turns)])) / rate

    def rhs(t, z):
        y, _, ddy = lift(rate * t)
        return [z[1], 1e-3 * (ddy * rate**2 + ks / m * y) - c / m * z[1] - (k + ks) / m * z[0]]

    z, out = np.asarray(start, float), np.empty((2, times.size))
    for a, b in zip(edges[:-1], edges[1:]):
        sol = solve_ivp(rhs, (a, b), z, method="DOP853", rtol=1e-12, atol=1e-16, dense_output=True)
        inside = (times >= a) & (times <= b)
        out[:, inside] = sol.sol(times[inside])
        z = sol.y[:, -1]
    return out


def program_lift(program):
    """``lift(theta_deg) -> (y, y', y'')`` of one angle from ``Program.lift``, for the scipy
    references above."""
    def lift(theta):
        return tuple(float(v[0]) for v in program.lift(np.array([theta])))

    return lift


def call(url: str, data: str | None = None):
    """(status, decoded JSON) of a GET of the studio's ``url``, or of a POST of ``data`` (a
    program's TOML text) as the page sends it: its structure as JSON, from the studio's own
    origin.  An error status comes back with its JSON body, not raised."""
    parts = urllib.parse.urlsplit(url)
    headers = {} if data is None else {"Origin": f"{parts.scheme}://{parts.netloc}", "Content-Type": "application/json"}
    body = None if data is None else (json.dumps(tomllib.loads(data)) if data else "").encode()
    request = urllib.request.Request(url, data=body, headers=headers, method="GET" if data is None else "POST")
    try:
        with urllib.request.urlopen(request, timeout=600) as response:
            return response.status, json.load(response)
    except urllib.error.HTTPError as error:
        return error.code, json.load(error)
