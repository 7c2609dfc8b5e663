"""The cost of refining the largest Hertz stress between the grid's nodes, in one process.

The indexer with ``contact_width_mm = 15``, warm (every program compiled by a first run): the
whole ``analyse`` (no flights) at 7 and at 101 speeds from 200 to 1400 rpm, and the
refinement alone (``camjax.program.max_contact_stress`` on the same steady state), with its
share of the analysis.  Median of 5 runs each.

    PYTHONPATH=. python experiments/benchmarks/hertz_refinement.py
"""

from __future__ import annotations

import dataclasses
import statistics
import time

import numpy as np

from camjax.program import Program, SteadyState, analyse, example_path, max_contact_stress


def median_seconds(fn, runs: int = 5) -> float:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def measure(program: Program, count: int) -> tuple[float, float]:
    """``(analyse, refinement)`` seconds, warm, at ``count`` speeds."""
    rpm = np.linspace(200.0, 1400.0, count)
    steady = SteadyState(program, rpm.min())
    analyse(program, rpm, steady=steady, with_flight=False)  # compile
    whole = median_seconds(lambda: analyse(program, rpm, steady=steady, with_flight=False))
    return whole, median_seconds(lambda: max_contact_stress(steady, rpm))


def main() -> None:
    program = Program.load(example_path())
    program = dataclasses.replace(
        program, follower=dataclasses.replace(program.follower, contact_width_mm=15.0)
    )
    for count in (7, 101):
        whole, alone = measure(program, count)
        print(
            f"{count:4d} speeds: analyse {whole:.3f} s, refinement {alone:.3f} s ({100 * alone / whole:.0f}%)"
        )


if __name__ == "__main__":
    main()
