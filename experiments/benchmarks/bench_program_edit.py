"""A cam program at the speed of an edit: analyse, edit a lift, analyse again.

For each program (the built-in feed cam and indexer, and ``transfer``: the transfer cam
of ``transfer.toml`` beside this script, a 368 Hz follower whose jump speed lies inside
the studio's default range 200:1400:7) in one process: the first ``analyse`` over
``--rpm`` (compiles), then ``--edits`` edits that keep the program's shape (every moving
segment's lift scaled by a factor near 1), each analysed with the jump speed and the
flights, timed (wall) with the number of XLA compilations it caused (``jax.monitoring``'s
backend-compile events), and the median of the edits.  ``--baseline DIR`` runs the same
measurement on another checkout (its code first on ``PYTHONPATH``) in a subprocess of
the same run, and prints both side by side with their ratios; the load average
(``os.getloadavg``) is printed with each run, since the machine may be shared.

    python experiments/benchmarks/bench_program_edit.py [--rpm 300:900:101] [--edits 3] [--baseline DIR]
    python experiments/benchmarks/bench_program_edit.py --rpm 200:1400:7 --edits 10 --programs transfer \
        --baseline /work/main --baseline-edits 10
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

PROGRAMS = ("feed", "indexer", "transfer")
TRANSFER = Path(__file__).resolve().parent / "transfer.toml"


def measure(rpm_spec: str, edits: int, programs) -> dict:
    import dataclasses

    import jax
    import numpy as np

    import camjax.program as cp

    compiles = []
    jax.monitoring.register_event_duration_secs_listener(
        lambda event, duration, **kw: compiles.append(duration)
        if event == "/jax/core/compile/backend_compile_duration" else None)
    lo, hi, count = (float(x) for x in rpm_spec.split(":"))
    rpm = np.linspace(lo, hi, int(count))
    out = {}
    for name in programs:
        program = cp.Program.load(TRANSFER if name == "transfer" else cp.example_path(name))
        rows = []
        for k in range(edits + 1):
            factor = 1.0 + 0.01 * k
            edited = dataclasses.replace(program, segments=tuple(
                dataclasses.replace(s, lift_mm=s.lift_mm * factor) if s.moving
                else s for s in program.segments)) if k else program
            before = len(compiles)
            start = time.perf_counter()
            try:
                report = cp.analyse(edited, rpm)
                jump = report.jump_speed_rpm
            except ValueError as error:  # an edit that breaks a join: keep the first program
                jump = f"refused: {error}"
            rows.append({"edit": k, "seconds": time.perf_counter() - start,
                         "compilations": len(compiles) - before, "jump_speed_rpm": jump})
        out[name] = rows
    out["load"] = os.getloadavg()
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rpm", default="300:900:101", help="LO:HI:COUNT (default %(default)s)")
    parser.add_argument("--edits", type=int, default=3)
    parser.add_argument("--programs", default=",".join(PROGRAMS))
    parser.add_argument("--baseline", type=Path, help="another checkout to time in the same run")
    parser.add_argument("--baseline-edits", type=int, default=1,
                        help="edits timed on the baseline (default %(default)s: a slow baseline's first look "
                        "and one edit)")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # a child's output
    args = parser.parse_args(argv)
    programs = args.programs.split(",")
    if args.json:
        print(json.dumps(measure(args.rpm, args.edits, programs)))
        return 0
    runs = {}
    for label, root in (("this", Path(__file__).resolve().parents[2]), ("baseline", args.baseline)):
        if root is None:
            continue
        env = dict(os.environ, PYTHONPATH=str(root))
        edits = args.edits if label == "this" else min(args.edits, args.baseline_edits)
        child = subprocess.run([sys.executable, __file__, "--json", "--rpm", args.rpm, "--edits", str(edits),
                                "--programs", args.programs], env=env, capture_output=True, text=True)
        if child.returncode:
            print(child.stderr[-2000:], file=sys.stderr)
            return 1
        runs[label] = json.loads(child.stdout.strip().splitlines()[-1])
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=Path(__file__).parent).stdout.strip()
    print(f"# analyse over --rpm {args.rpm} with jump speed and flights; commit {commit}, "
          f"{time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores")
    print("| program | edit | " + " | ".join(f"{lab} s | {lab} compilations" for lab in runs) +
          (" | ratio |" if len(runs) == 2 else " |"))
    print("|---" * (2 + 2 * len(runs) + (len(runs) == 2)) + "|")
    for name in programs:
        for k in range(args.edits + 1):
            cells = []
            for lab in runs:
                rows = runs[lab][name]
                cells += [f"{rows[k]['seconds']:.3f}", str(rows[k]["compilations"])] if k < len(rows) else ["-", "-"]
            ratio = ""
            if len(runs) == 2:
                base = runs["baseline"][name]
                ratio = f" {runs['this'][name][k]['seconds'] / base[k]['seconds']:.4f} |" if k < len(base) else " - |"
            print(f"| {name} | {'first' if k == 0 else k} | " + " | ".join(cells) + " |" + ratio)
        medians = {lab: statistics.median(r["seconds"] for r in runs[lab][name][1:])
                   for lab in runs if len(runs[lab][name]) > 1}
        print(f"| {name} | median of edits | " + " | ".join(
            f"{medians[lab]:.3f} | -" if lab in medians else "- | -" for lab in runs) + " |"
            + (f" {medians['this'] / medians['baseline']:.4f} |" if len(medians) == 2 else ""))
        for lab in runs:
            jumps = {str(r["jump_speed_rpm"]) for r in runs[lab][name]}
            print(f"  {lab}: jump speeds {sorted(jumps)}")
    for lab in runs:
        print(f"  {lab}: load average after the run {' '.join(f'{x:.2f}' for x in runs[lab]['load'])}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
