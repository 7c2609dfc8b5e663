"""Paired timing of a program edit in this checkout and another, turn about, on a shared machine.

``bench_program_edit.py`` times one checkout, then the other: on a machine whose load
changes by the minute the two halves see different loads.  Here two worker processes (this
checkout and ``--baseline``, each with its code first on ``PYTHONPATH``) load the program,
analyse it once (compiles), then take turns: each edit (every moving segment's lift scaled by
a factor near 1) is analysed by one worker, then the same edit by the other, with the jump
speed and the flights.  Prints every pair, the medians and the median of the pairs' ratios,
with the load average; and each edit's CPU time (all the worker's threads), which a loaded
machine inflates far less than the wall time.

    python experiments/benchmarks/ab_program_edit.py --baseline /work/main [--program feed] \\
        [--rpm 300:900:101] [--edits 10]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

TRANSFER = Path(__file__).resolve().parent / "transfer.toml"

WORKER = """
import dataclasses, json, sys, time
import numpy as np
import camjax.program as cp
name, spec = sys.argv[1], sys.argv[2]
program = cp.Program.load(name if name.endswith(".toml") else cp.example_path(name))
lo, hi, count = (float(x) for x in spec.split(":"))
rpm = np.linspace(lo, hi, int(count))
cp.analyse(program, rpm)
print("ready", flush=True)
for line in sys.stdin:
    factor = float(line)
    edited = dataclasses.replace(program, segments=tuple(
        dataclasses.replace(s, lift_mm=s.lift_mm * factor) if s.moving else s for s in program.segments))
    start, cpu = time.perf_counter(), time.process_time()
    report = cp.analyse(edited, rpm)
    print(json.dumps([time.perf_counter() - start, report.jump_speed_rpm, time.process_time() - cpu]), flush=True)
"""


def _worker(root: Path, program: str, rpm: str):
    env = dict(os.environ, PYTHONPATH=str(root))
    process = subprocess.Popen(
        [sys.executable, "-c", WORKER, program, rpm],
        env=env,
        cwd=root,  # ``python -c`` puts the working directory first on the path: the checkout's own
        text=True,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
    )
    return process


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", type=Path, required=True)
    parser.add_argument("--program", default="feed", help="feed, indexer, transfer or a TOML path")
    parser.add_argument("--rpm", default="300:900:101")
    parser.add_argument("--edits", type=int, default=10)
    args = parser.parse_args(argv)
    program = str(TRANSFER) if args.program == "transfer" else args.program
    workers = {
        "this": _worker(Path(__file__).resolve().parents[2], program, args.rpm),
        "baseline": _worker(args.baseline, program, args.rpm),
    }
    for process in workers.values():
        assert process.stdout.readline().strip() == "ready"
    rows = []
    for k in range(1, args.edits + 1):
        row = {}
        for label in (
            ("this", "baseline") if k % 2 else ("baseline", "this")
        ):  # alternate who goes first
            workers[label].stdin.write(f"{1.0 + 0.01 * k}\n")
            workers[label].stdin.flush()
            row[label] = json.loads(workers[label].stdout.readline())
        rows.append(row)
    for process in workers.values():
        process.stdin.close()
        process.wait()
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"],
        capture_output=True,
        text=True,
        cwd=Path(__file__).parent,
    ).stdout.strip()
    print(
        f"# {args.program} over --rpm {args.rpm}, edits in turn; commit {commit} against {args.baseline}, "
        f"{time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores"
    )
    print("| edit | this s | baseline s | ratio | same jump speed | this CPU s | baseline CPU s |")
    print("|---|---|---|---|---|---|---|")
    for k, row in enumerate(rows, 1):
        print(
            f"| {k} | {row['this'][0]:.3f} | {row['baseline'][0]:.3f} | "
            f"{row['this'][0] / row['baseline'][0]:.3f} | {row['this'][1] == row['baseline'][1]} | "
            f"{row['this'][2]:.3f} | {row['baseline'][2]:.3f} |"
        )
    this, base = ([r[lab][0] for r in rows] for lab in ("this", "baseline"))
    ratios = [a / b for a, b in zip(this, base)]
    print(
        f"| median | {statistics.median(this):.3f} | {statistics.median(base):.3f} | "
        f"{statistics.median(ratios):.3f} (median of the ratios) | | "
        f"{statistics.median(r['this'][2] for r in rows):.3f} | {statistics.median(r['baseline'][2] for r in rows):.3f} |"
    )
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
