"""The flights of a chain (``flights_at``: the chain simulated with its cam's contact
one-sided from the exact steady state, ``ChainContacts.flights``) against the exact
steady state's summary at the same speeds, in one process.

The chain is camjax/program/examples/trains/valve.toml's (a tappet riding the cam, the valve
on a 200 N/mm element, a surging spring) at ``--speeds`` speeds from 3500 to 4500 cam rpm,
above its jump (3428 rpm), where every speed loses contact.  Each is timed cold (its first
run, compilation included) and warm (the best of ``--repeats`` later runs; the flights on a
``ChainContacts`` built once, as ``analyse`` passes it).

    python experiments/benchmarks/bench_chain_flights.py [--speeds 8] [--repeats 2]
"""

from __future__ import annotations

import argparse
import os

import numpy as np
from bench_chain_contacts import timed  # cold, then the best of the warm runs

from camjax.program import ChainContacts, Program, SteadyState, flights_at


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speeds", type=int, default=8)
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    here = os.path.dirname(os.path.abspath(__file__))
    program = Program.load(os.path.join(here, "../../camjax/program/examples/trains/valve.toml"))
    rpm = np.linspace(3500.0, 4500.0, args.speeds)
    steady = SteadyState(program, rpm.min())
    simulation = ChainContacts(program, program.chain, rpm.min())
    exact = timed(lambda: steady.summary(rpm), args.repeats)
    flights = timed(lambda: flights_at(steady, rpm, simulation=simulation), args.repeats)
    count = sum(len(f) for f in flights_at(steady, rpm, simulation=simulation))
    print(f"{rpm.size} speeds, {count} flights, {simulation.samples} samples a turn (x2 per run)")
    print(f"exact steady state:  cold {exact[0]:7.2f} s  warm {exact[1]:7.3f} s")
    print(f"flights (simulated): cold {flights[0]:7.2f} s  warm {flights[1]:7.3f} s")
    print(f"ratio warm flights / steady state: {flights[1] / exact[1]:.1f}")


if __name__ == "__main__":
    main()
