"""Time the studio through its JSON API, as the page uses it.

Starts ``camjax studio FILE --no-browser --port 0`` in a fresh process, then times

- the cold start: from launching the process to the first report (``GET /api/report``),
  and to the first curves (``GET /api/curves``);
- a sequence of edits that keep the program's shape (the number and kinds of segments):
  each ``POST /api/program`` (the report) and the ``GET /api/curves`` after it.

    python experiments/benchmarks/bench_studio.py [--file feed] [--rpm 200:1400:7] [--edits 4]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _get(url: str):
    with urllib.request.urlopen(url, timeout=900) as response:
        return json.load(response)


def _post(url: str, text: str):
    request = urllib.request.Request(url, data=text.encode(), method="POST")
    with urllib.request.urlopen(request, timeout=900) as response:
        return json.load(response)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--file", default="feed", help="program file or built-in example (default feed)")
    parser.add_argument("--rpm", default="200:1400:7", help="speed range (default 200:1400:7)")
    parser.add_argument("--edits", type=int, default=4, help="edits that keep the shape (default 4)")
    args = parser.parse_args()

    start = time.perf_counter()
    server = subprocess.Popen([sys.executable, "-m", "camjax", "studio", args.file, "--rpm", args.rpm,
                               "--no-browser", "--port", "0"], stdout=subprocess.PIPE, text=True, cwd=ROOT)
    try:
        line = server.stdout.readline()
        url = line[line.index("http://"):].split()[0]
        listening = time.perf_counter() - start
        report = _get(url + "api/report")
        first_report = time.perf_counter() - start
        _get(url + "api/curves")
        first_curves = time.perf_counter() - start
        print(f"cold start: serving after {listening:.2f} s, first report after {first_report:.1f} s, "
              f"first curves after {first_curves:.1f} s (jump speed {report['jump_speed_rpm']})")

        state = _get(url + "api/program")
        text, program = state["toml"], state["program"]
        rises = [s for s in program["segment"] if s.get("lift_mm", 0) > 0]
        falls = [s for s in program["segment"] if s.get("lift_mm", 0) < 0]
        rise, fall = rises[0]["lift_mm"], falls[-1]["lift_mm"]
        posts, curves = [], []
        for i in range(1, args.edits + 1):
            delta = 0.25 * i * (-1) ** i  # the first rise and the last return change together
            edited = text.replace(f"lift_mm = {rise}\n", f"lift_mm = {rise + delta}\n", 1)
            edited = edited.replace(f"lift_mm = {fall}\n", f"lift_mm = {fall - delta}\n", 1)
            assert edited != text, "the edit did not apply"
            t = time.perf_counter()
            jump = _post(url + f"api/program?rpm={args.rpm}", edited)["jump_speed_rpm"]
            posts.append(time.perf_counter() - t)
            t = time.perf_counter()
            _get(url + "api/curves")
            curves.append(time.perf_counter() - t)
            print(f"edit {i}: lift {rise + delta:g}/{fall - delta:g} mm: report {posts[-1]:.2f} s, "
                  f"curves {curves[-1]:.2f} s (jump speed {jump})")
        print(f"per edit (median of {args.edits}): report {statistics.median(posts):.2f} s, "
              f"curves {statistics.median(curves):.2f} s")
    finally:
        server.terminate()
        server.wait(timeout=30)


if __name__ == "__main__":
    main()
