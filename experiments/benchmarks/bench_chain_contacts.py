"""The lash-and-seat analysis of a valve train at 21 and 101 speeds against the closed
chain's exact steady state, in one process.

The chain is camjax/program/examples/trains/valve_lash.toml's (a tappet riding the cam, a
rocker of ratio 1.5 with 0.15 mm lash at the valve, a 40 N/mm spring with 250 N preload, a
50,000 N/mm seat) from 1000 to 3000 cam rpm.  Each case is timed warm (after one run that
compiles): the simulation (``ChainContacts.summary``: turns from rest until settled, the
last one sampled and read) and, as the baseline, the exact periodic steady state of the same
chain without lash and seat (``SteadyState.summary`` of the program with that chain).  The cold first run of each is
printed too (compilation included).

    python experiments/benchmarks/bench_chain_contacts.py [--repeats 2]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time

import numpy as np

from camjax.program import ChainContacts, Program, SteadyState


def timed(run, repeats: int) -> tuple[float, float]:
    start = time.perf_counter()
    run()
    cold = time.perf_counter() - start
    warm = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        warm.append(time.perf_counter() - start)
    return cold, min(warm)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    program = Program.load("camjax/program/examples/trains/valve_lash.toml")
    chain = program.chain
    closed = dataclasses.replace(
        chain, bodies=tuple(dataclasses.replace(b, lash_mm=0.0) for b in chain.bodies), seat=None
    )
    closed_program = dataclasses.replace(program, chain=closed)
    print(f"load {os.getloadavg()[0]:.1f}")
    for count in (21, 101):
        rpm = np.linspace(1000.0, 3000.0, count)
        contacts = timed(
            lambda rpm=rpm: ChainContacts(program, chain, 1000.0).summary(rpm), args.repeats
        )
        exact = timed(lambda rpm=rpm: SteadyState(closed_program, rpm).summary(rpm), args.repeats)
        turns = ChainContacts(program, chain, 1000.0).turns(rpm[:1])[0].turns
        print(
            f"{count} speeds: lash and seat {contacts[1]:.2f} s warm ({contacts[0]:.2f} s cold, "
            f"{turns} turns), closed chain exact {exact[1]:.3f} s warm ({exact[0]:.2f} s cold): "
            f"ratio {contacts[1] / exact[1]:.0f}"
        )


if __name__ == "__main__":
    main()
