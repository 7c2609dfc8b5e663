"""Time of a lift table's fit against its number of points: the sparse banded fit of
``camjax.laws.TableLaw.fit`` against the dense one it replaced (read from git at
``--baseline``, run only up to ``--dense-max`` points: it grows as the cube), interpolating
and smoothed to a band that holds uniform noise, in one process; and the whole
``Program.from_dxf`` of the feed cam's drawing at ``dxf_points`` 720 and 4000.

The table is a 20 mm cycloidal rise over 100 degrees; the noise is uniform within +/-1 um
and ``smoothing_mm = 0.001`` (its bound); the last column is the smoothed fit's peak
acceleration over the cycloid's.

    python experiments/benchmarks/bench_table_fit.py [--baseline aa405fe] [--dense-max 1440]
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from camjax.laws import TableLaw
from camjax.program import Program, example_path, profile, write_dxf


def dense_table_law(commit: str):
    """``TableLaw`` as it was at ``commit`` (its dense fit), loaded beside today's."""
    root = Path(__file__).resolve().parents[2]
    source = subprocess.run(
        ["git", "show", f"{commit}:camjax/laws/_table.py"],
        cwd=root,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    spec = importlib.util.spec_from_loader("table_law_at_baseline", loader=None)
    module = importlib.util.module_from_spec(spec)
    module.__package__ = "camjax.laws"
    sys.modules[spec.name] = module
    exec(compile(source, f"{commit}:camjax/laws/_table.py", "exec"), module.__dict__)
    return module.TableLaw


def seconds(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def peak_acceleration(law) -> float:
    """The largest ``|s''|`` of a table law, from its pieces' Taylor coefficients (NumPy)."""
    edges, c = np.asarray(law.edges), np.asarray(law.coefficients)
    u = 0.5 * np.diff(edges)[:, None] * np.linspace(-1.0, 1.0, 9)
    a = 2 * c[:, 2:3] + 6 * c[:, 3:4] * u + 12 * c[:, 4:5] * u**2 + 20 * c[:, 5:6] * u**3
    return float(np.max(np.abs(a)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--baseline", default="aa405fe")
    parser.add_argument("--dense-max", type=int, default=1440)
    args = parser.parse_args()
    laws = {"dense": dense_table_law(args.baseline), "sparse": TableLaw}
    rng = np.random.default_rng(0)
    print(
        f"{'points':>6} {'interp dense s':>15} {'interp sparse s':>16} {'smooth dense s':>15} "
        f"{'smooth sparse s':>16} {'smooth peak acc./exact':>23}"
    )
    for n in (90, 180, 360, 720, 1440, 2000, 4000):
        angle = np.linspace(0.0, 100.0, n)
        tau = angle / 100.0
        lift = 20.0 * (tau - np.sin(2 * math.pi * tau) / (2 * math.pi))
        noisy = lift + rng.uniform(-0.001, 0.001, n)
        noisy[[0, -1]] = lift[[0, -1]]
        cells = []
        for kind in ("interp", "smooth"):
            for name, law in laws.items():
                if name == "dense" and n > args.dense_max:
                    cells.append("-")
                    continue
                if kind == "interp":
                    cells.append(f"{seconds(lambda law=law, y=lift, a=angle: law.fit(a, y)):.3f}")
                else:
                    cells.append(
                        f"{seconds(lambda law=law, y=noisy, a=angle: law.fit(a, y, 0.001)):.3f}"
                    )
        ratio = peak_acceleration(TableLaw.fit(angle, noisy, 0.001)) / (2 * math.pi)
        print(f"{n:>6} {cells[0]:>15} {cells[1]:>16} {cells[2]:>15} {cells[3]:>16} {ratio:>23.4f}")
    feed = Program.load(example_path("feed"))
    with tempfile.TemporaryDirectory() as folder:
        path = write_dxf(profile(feed), Path(folder) / "feed.dxf")
        for points in (720, 4000):
            took = seconds(lambda p=points: Program.from_dxf("feed", path, feed.follower, points=p))
            print(f"Program.from_dxf(feed.dxf, points={points}): {took:.2f} s")


if __name__ == "__main__":
    main()
