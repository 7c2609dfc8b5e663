"""A stiff seat with zero lash against the closed chain, as the chain's element stiffens.

The valve of ``valve.toml`` (a tappet riding a cycloidal 8 mm rise over 100 deg, no ramps)
behind a rocker (ratio 1.5, ``k`` N/mm, 20 N s/m), a massless spring (52 N/mm, 250 N) and a
seat (50,000 N/mm, 500 N s/m), at 1000 rpm, for ``k`` 200, 2,000 and 20,000 N/mm: the
seated chain (``ChainContacts``) against the closed chain (``SteadyState`` for the extremes,
``ChainContacts`` without a seat for the samples).  Prints per ``k`` the cam lift that
compresses the chain by the preload (``delta``), the difference of the spring's largest
seat force and of the largest contact force with their static prediction (``-k_s P / (k +
k_s)`` and ``r`` times it), the valve's peak acceleration over the opening (before the
nose, away from the landing) with the lift-off transient's estimate ``r y'(t_0) omega``
(the valve leaves its seat at rest where the closed chain's moves with the cam).

Run: ``PYTHONPATH=. python experiments/benchmarks/chain_seat_limit.py [rpm] [k ...]``.
"""

import dataclasses
import math
import sys
import time

import numpy as np

from camjax.program import Body, Chain, ChainContacts, Program, Seat, Spring, SteadyState

RATIO, PRELOAD, RATE, SEAT = 1.5, 250.0, 52.0, 50000.0
MASS = 0.05


def main():
    program = Program.load("camjax/program/examples/trains/valve.toml")
    rpm = float(sys.argv[1]) if len(sys.argv) > 1 else 1000.0
    stiffnesses = [float(x) for x in sys.argv[2:]] or [200.0, 2000.0, 20000.0]
    print(
        f"rpm {rpm:g}; k (N/mm), delta (mm of cam lift), spring max seat force diff (pred),"
        " cam max force diff (pred), valve peak acc over the opening: seated, closed, r y'(t0) w"
    )
    for k in stiffnesses:
        t0 = time.perf_counter()
        valve = Body("valve", MASS, k, 20.0, RATIO)
        closed = Chain((Body("tappet", 0.03), valve), Spring(RATE, PRELOAD))
        seated = dataclasses.replace(closed, seat=Seat(SEAT, 500.0))
        exact = SteadyState(dataclasses.replace(program, chain=closed), [rpm]).summary([rpm]).cycles
        summary, (turn,) = ChainContacts(program, seated, rpm).summary([rpm])
        (plain,) = ChainContacts(program, closed, rpm).turns([rpm], refine=False)
        K, ks = 1e3 * k, 1e3 * RATE
        s0 = PRELOAD / (1e3 * SEAT)
        delta = (PRELOAD + (K + ks) * s0) / (K * RATIO)  # m of cam lift at lift-off
        x = _cycloid_inverse(1e3 * delta / 8.0)
        v0 = RATIO * 8e-3 * (1 - math.cos(2 * math.pi * x)) / 100.0 * 6 * rpm  # m/s
        omega = math.sqrt((K + ks) / MASS)
        opening = turn.theta_deg < 50.0
        spring = summary.max_seat_force_n[0] - float(exact.train.max_seat_force_n[0])
        cam = summary.max_contact_force_n[0] - float(exact.max_contact_force_n[0])
        static = ks * PRELOAD / (K + ks)
        print(
            f"{k:8g} {1e3 * delta:.5f}  {spring:+9.4f} ({-static:+9.4f})  {cam:+9.4f} "
            f"({-RATIO * static:+9.4f})  {np.abs(turn.acceleration_m_s2[-1][opening]).max():8.1f} "
            f"{np.abs(plain.acceleration_m_s2[-1][plain.theta_deg < 50.0]).max():8.1f} {v0 * omega:8.1f}"
            f"   ({time.perf_counter() - t0:.0f} s)"
        )


def _cycloid_inverse(fraction: float) -> float:
    """The fraction of a cycloidal rise at which it has risen by ``fraction`` of its lift."""
    lo, hi = 0.0, 0.5
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (
            (mid, hi) if mid - math.sin(2 * math.pi * mid) / (2 * math.pi) < fraction else (lo, mid)
        )
    return lo


if __name__ == "__main__":
    main()
