"""Warm time of ``camjax.ct_curves`` for many SCCA laws at once (one stacked, compiled call).

256 distinct laws of the SCCA face (``a + b + c = 1``, step 0.01, evenly picked) against
1000 period ratios in [1, 30], undamped: the first call (trace, compile, run), then the
median of ``--repeats`` warm calls, with the per-law time.  Run it in two checkouts to
compare revisions (one process each, in turn; the machine's speed drifts between
processes, so repeat the pair).

    python experiments/benchmarks/bench_scca_laws.py [--laws 256] [--repeats 3] [--devices 1]

``--devices``: CPU devices (``camjax.sharding.use_cpu_cores``; default one per core), over
which ``ct_curves`` splits the stack.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import camjax
from camjax import distributed
from camjax.sharding import use_cpu_cores


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--laws", type=int, default=256)
    parser.add_argument("--count", type=int, default=1000, help="period ratios in [1, 30]")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--devices", type=int, help="CPU devices (default: one per core)")
    args = parser.parse_args()
    devices = use_cpu_cores(args.devices)
    face = distributed.scca_grid(0.01, face=True)
    picked = np.unique(np.linspace(0, len(face) - 1, args.laws).astype(int))
    chosen = {face[i].name: face[i] for i in picked}
    n = np.linspace(1.0, 30.0, args.count)
    start = time.perf_counter()
    camjax.ct_curves(chosen, n)
    first = time.perf_counter() - start
    warm = []
    for _ in range(args.repeats):
        start = time.perf_counter()
        camjax.ct_curves(chosen, n)
        warm.append(time.perf_counter() - start)
    median = float(np.median(warm))
    print(f"{len(chosen)} SCCA laws x {n.size} ratios, {devices} CPU device(s): first call {first:.2f} s, warm "
          f"median {median:.2f} s ({1e3 * median / len(chosen):.2f} ms per law; runs "
          + ", ".join(f"{t:.2f}" for t in warm) + ")")


if __name__ == "__main__":
    main()
