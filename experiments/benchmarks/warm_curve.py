"""Warm time of one law's 1000-ratio Ct curve through ``camjax.ct_curve`` (what a user's
second call costs), against the bare kernel on a pre-sampled law, in one process.

    python experiments/benchmarks/warm_curve.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import time

import jax
import numpy as np

import camjax
from camjax import sweep


def best_ms(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - start)
    return 1e3 * min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    n = np.linspace(1, 30, 1000)
    ratios, template, options = sweep.prepare_sweep(n)
    print(f"{'law':<20} {'ct_curve ms':>12} {'kernel ms':>10}")
    for law in camjax.laws.standard_laws():
        camjax.ct_curve(law, n)  # compile
        sampled = template.sweep_law(law, options)
        curve = best_ms(lambda law=law: camjax.ct_curve(law, n).ct, args.repeats)
        kernel = best_ms(lambda s=sampled: sweep.sweep_metrics(s, ratios, template, options),
                         args.repeats)
        print(f"{law.name:<20} {curve:12.1f} {kernel:10.1f}")


if __name__ == "__main__":
    main()
