"""How fast work too large to fit is refused: the times the tests used to assert.

Two refusals that must come before any work (the tests check that nothing compiles):
a turn of a train stiff past the grid's limit (``SteadyState``, 1e12 N/mm at 600 rpm;
it once ran 105 s and ended out of memory) and a grooved cam's run past its sample budget
(``groove_turns`` at 50 rpm).  Each, the program's construction included, is timed
``--repeats`` times in one process: the first also imports and compiles the laws'
evaluation (the tests' old bounds, 5 s and 2 s, were on the refusal alone; the median is
the figure to compare); the median and the largest are printed with the load average,
since the machine may be shared.

    python experiments/benchmarks/refusal_speed.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import subprocess
import time
from pathlib import Path


def _stiff_turn():
    from camjax import laws
    from camjax.program import Follower, Program, Segment, SteadyState

    law = laws.get("cycloidal")
    follower = Follower(
        kind="translating-roller",
        mass_kg=1.5,
        stiffness_n_per_mm=1e12,
        damping_ratio=0.05,
        spring_rate_n_per_mm=10.0,
        preload_n=300.0,
        base_radius_mm=40.0,
        roller_radius_mm=12.0,
    )
    program = Program(
        "stiff",
        (Segment(100, 20.0, law), Segment(80), Segment(100, -20.0, law), Segment(80)),
        follower,
    )
    SteadyState(program, 600.0)


def _groove_budget():
    from camjax.program import Program, example_path, groove_turns

    base = Program.load(example_path("indexer"))
    follower = dataclasses.replace(
        base.follower, spring_rate_n_per_mm=None, preload_n=0.0, groove_clearance_mm=0.05
    )
    groove_turns(dataclasses.replace(base, follower=follower), [50.0])


CASES = {"stiff train (SteadyState)": _stiff_turn, "groove budget (groove_turns)": _groove_budget}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"],
        capture_output=True,
        text=True,
        cwd=Path(__file__).parent,
    ).stdout.strip()
    print(
        f"# refusals before any work; commit {commit}, {time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores"
    )
    print("| refusal | first s | median s | largest s |")
    print("|---|---|---|---|")
    for name, case in CASES.items():
        seconds = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            try:
                case()
            except ValueError:
                seconds.append(time.perf_counter() - start)
            else:
                raise SystemExit(f"{name}: not refused")
        print(
            f"| {name} | {seconds[0]:.3f} | {statistics.median(seconds):.3f} | {max(seconds):.3f} |"
        )
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
