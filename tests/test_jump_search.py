"""The jump speed's search: the bound that rules out low speeds without a steady state, and
the answer against a plain scan and bisection (every scan speed computed)."""

from pathlib import Path

import numpy as np
import pytest
from helpers import FOLLOWER, two_cycloids

import camjax.program as cp
from camjax import laws
from camjax.program import ContactForceBound, SteadyState, scan_speeds

TRANSFER = Path(__file__).resolve().parents[1] / "experiments" / "benchmarks" / "transfer.toml"


def _harmonic_with_jumps():
    """Simple harmonic rise and return: the acceleration jumps at every segment end, the
    bound's first-order remainder."""
    law = laws.get("simple-harmonic")
    return cp.Program(
        "harmonic",
        (cp.Segment(120, 25.0, law), cp.Segment(60), cp.Segment(120, -25.0, law), cp.Segment(60)),
        cp.Follower(**{**FOLLOWER, "preload_n": 500.0}),
    )


def _stiff_modified_sine():
    law = laws.get("modified-sine")
    return cp.Program(
        "stiff",
        (cp.Segment(90, 30.0, law), cp.Segment(90), cp.Segment(140, -30.0, law), cp.Segment(40)),
        cp.Follower(**{**FOLLOWER, "stiffness_n_per_mm": 5000.0, "damping_ratio": 0.08}),
    )


OWN = {
    "two-cycloids": lambda: two_cycloids(preload_n=250.0),
    "harmonic": _harmonic_with_jumps,
    "stiff-modified-sine": _stiff_modified_sine,
}
BUILT_IN = {
    "feed": lambda: cp.Program.load(cp.example_path("feed")),
    "indexer": lambda: cp.Program.load(cp.example_path("indexer")),
    "transfer": lambda: cp.Program.load(TRANSFER),
}


def plain_jump_speed(steady, rpm_lo, rpm_hi, tolerance_rpm=0.1):
    """The search without the bound: every scan speed's steady state, then 17-way bisection."""
    rpm = scan_speeds(steady.program, rpm_lo, rpm_hi, 16)
    rpm[0], rpm[-1] = rpm_lo, rpm_hi
    force = steady.min_contact_force_n(rpm)
    if not np.any(force < 0):
        return None
    i = int(np.argmax(force < 0))
    if i == 0:
        return rpm_lo
    lo, hi = rpm[i - 1], rpm[i]
    while hi - lo > tolerance_rpm:
        trial = np.linspace(lo, hi, 18)[1:-1]
        below = np.flatnonzero(steady.min_contact_force_n(trial) < 0)
        if below.size:
            lo, hi = (trial[below[0] - 1] if below[0] else lo), trial[below[0]]
        else:
            lo = trial[-1]
    return 0.5 * (lo + hi)


@pytest.mark.parametrize("name", [*BUILT_IN, *OWN])
def test_bound_is_below_the_least_contact_force(name):
    program = {**BUILT_IN, **OWN}[name]()
    steady = SteadyState(program, 200.0)
    rpm = np.geomspace(200.0, 1400.0, 32)
    force = steady.min_contact_force_n(rpm)
    bound = ContactForceBound(steady)(rpm)
    assert np.all(bound <= force), (rpm[bound > force], bound[bound > force], force[bound > force])


def test_bound_rules_out_the_low_speeds_of_the_scan():
    """The point of the bound: most of the transfer cam's scan (even in the period, so
    densest at low speeds) needs no steady state."""
    steady = SteadyState(cp.Program.load(TRANSFER), 200.0)
    rpm = scan_speeds(steady.program, 200.0, 1400.0, 16)
    held = ContactForceBound(steady)(rpm) > 0
    assert held[: rpm.size // 2].all()
    assert held.mean() > 0.75


@pytest.mark.parametrize("name", [*BUILT_IN, *OWN])
def test_jump_speed_equals_the_plain_search(name):
    steady = SteadyState({**BUILT_IN, **OWN}[name](), 200.0)
    found = cp.jump_speed_rpm(steady, 200.0, 1400.0)
    expected = plain_jump_speed(steady, 200.0, 1400.0)
    assert expected is not None and 200.0 < expected < 1400.0  # a search with something to find
    assert found == pytest.approx(expected, abs=0.01)
