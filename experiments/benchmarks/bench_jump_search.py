"""The jump speed's search with and without its bound, in one process, in turn.

For each case (a program and a speed range) one ``SteadyState`` is built and its compiled
program warmed; then ``jump_speed_rpm`` runs ``--repeats`` times each way, in turn
(with the bound and the scan in waves, and ``rule_out=False``: every scan speed computed in
one dispatch), so both see the same load.  Prints the medians, the median of the paired
ratios, the scan's size, how many scan speeds the bound rules out, and whether the two
answers are the same number.

    python experiments/benchmarks/bench_jump_search.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import time
from pathlib import Path

TRANSFER = Path(__file__).resolve().parent / "transfer.toml"
CASES = (
    ("feed", 300.0, 900.0),
    ("feed", 200.0, 1400.0),
    ("indexer", 200.0, 1400.0),
    ("transfer", 200.0, 1400.0),
    ("transfer", 300.0, 900.0),
)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    import camjax.program as cp

    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"],
        capture_output=True,
        text=True,
        cwd=Path(__file__).parent,
    ).stdout.strip()
    print(
        f"# jump speed search, bound and waves against every scan speed, in turn; commit {commit}, "
        f"{time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores"
    )
    print(
        "| program | rpm | scan speeds | ruled out | with bound s | every speed s | ratio | same |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name, lo, hi in CASES:
        program = cp.Program.load(TRANSFER if name == "transfer" else cp.example_path(name))
        steady = cp.SteadyState(program, lo)
        rpm = cp.scan_speeds(program, lo, hi, 16)
        ruled_out = cp.ContactForceBound(steady).first_unheld(rpm)
        steady.min_contact_force_n(rpm[:1])  # compiles
        times = {True: [], False: []}
        answers = set()
        for k in range(args.repeats):
            for rule_out in (True, False) if k % 2 == 0 else (False, True):
                start = time.perf_counter()
                answers.add((rule_out, cp.jump_speed_rpm(steady, lo, hi, rule_out=rule_out)))
                times[rule_out].append(time.perf_counter() - start)
        ratios = [a / b for a, b in zip(times[True], times[False])]
        same = len({a for _, a in answers}) == 1
        print(
            f"| {name} | {lo:g}-{hi:g} | {rpm.size} | {ruled_out} | {statistics.median(times[True]):.3f} | "
            f"{statistics.median(times[False]):.3f} | {statistics.median(ratios):.3f} | {same} |"
        )
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
