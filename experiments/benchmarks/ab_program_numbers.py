"""Every number of ``camjax program --format json`` and ``camjax ct`` in this checkout against
another checkout: a refactoring that must not move results is checked with it.

Each case runs in both checkouts (each with its own code first on ``PYTHONPATH``, the
trace cache off so both compute), and every number of the two JSON documents is compared
at ``--rtol`` relative to the larger magnitude of the pair (absolute below ``--atol``); any
difference in structure, text or a number past the tolerance is printed and the exit
status is 1.

    python experiments/benchmarks/ab_program_numbers.py --baseline /path/to/other/checkout
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[2]
TRANSFER = Path(__file__).resolve().parent / "transfer.toml"
KINDS = Path(__file__).resolve().parent / "follower_kinds"
"""One program file of each follower kind and set-up no built-in cam uses."""

CASES = (
    ("program", "indexer", "--rpm", "200:1400:7"),
    ("program", "feed", "--rpm", "300:900:4"),
    ("program", "valve", "--rpm", "1000:4000:4"),
    ("program", str(TRANSFER), "--rpm", "200:1400:7"),
    ("program", "servo"),
    *(("program", str(path), "--rpm", "300:900:3") for path in sorted(KINDS.glob("*.toml"))),
    ("ct", "--n", "1:30:60"),
    ("ct", "--law", "scca:0.1,0.5,0.3", "--n", "1:20:40", "--damping", "0.1"),
)


def run(checkout: Path, case: tuple[str, ...]) -> object:
    """The JSON document of ``camjax <case> --format json`` in ``checkout``."""
    env = {**os.environ, "PYTHONPATH": str(checkout), "CAMJAX_CACHE_DIR": "off"}
    done = subprocess.run([sys.executable, "-m", "camjax", *case, "--format", "json"],
                          env=env, capture_output=True, text=True, cwd=checkout)
    if done.returncode != 0:
        raise SystemExit(f"{checkout}: camjax {' '.join(case)} failed: {done.stderr.strip()}")
    return json.loads(done.stdout)


def differences(a, b, rtol: float, atol: float, where: str = ""):
    """``(path, a, b)`` for every place where the documents differ past the tolerance."""
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            yield where, sorted(a.keys() - b.keys()), sorted(b.keys() - a.keys())
        for key in a.keys() & b.keys():
            yield from differences(a[key], b[key], rtol, atol, f"{where}/{key}")
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            yield where, len(a), len(b)
        for i, (x, y) in enumerate(zip(a, b)):
            yield from differences(x, y, rtol, atol, f"{where}[{i}]")
    elif (isinstance(a, (int, float)) and isinstance(b, (int, float))
          and not isinstance(a, bool) and not isinstance(b, bool)):
        if math.isnan(a) and math.isnan(b):
            return
        scale = max(abs(a), abs(b))
        if abs(a - b) > max(rtol * scale, atol):
            yield where, a, b
    elif a != b:
        yield where, a, b


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--baseline", type=Path, required=True, help="the other checkout")
    parser.add_argument("--rtol", type=float, default=1e-10)
    parser.add_argument("--atol", type=float, default=1e-300)
    parser.add_argument("--keep", type=Path, help="folder keeping the baseline's documents "
                        "(read from it where present: the baseline runs once)")
    args = parser.parse_args()
    failed = 0
    for number, case in enumerate(CASES):
        kept = args.keep and args.keep / f"case{number}.json"
        if kept and kept.exists():
            theirs = json.loads(kept.read_text())
        else:
            theirs = run(args.baseline, case)
            if kept:
                kept.parent.mkdir(parents=True, exist_ok=True)
                kept.write_text(json.dumps(theirs))
        ours = run(HERE, case)
        found = list(differences(ours, theirs, args.rtol, args.atol))
        count = sum(1 for _ in differences(ours, theirs, -1.0, -1.0))  # every leaf compared
        label = " ".join(Path(x).name if x.endswith(".toml") else x for x in case)
        print(f"camjax {label}: {count:,} values, {len(found)} past rtol {args.rtol:g}")
        for where, a, b in found[:20]:
            print(f"    {where}: {a!r} (this checkout) against {b!r}")
        failed += bool(found)
    return int(failed > 0)


if __name__ == "__main__":
    sys.exit(main())
