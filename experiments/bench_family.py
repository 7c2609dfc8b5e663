"""Compiled programs and time of the standard laws' Ct curves, in one process.

For 1000 period ratios in [1, 30] and every standard law: the first call of ``ct_curve``
(trace, compile, run) and the best of five warm calls, with the number of programs XLA
compiled for it; then ``ct_curves`` of all seven at once (stacked by family), first and
warm.  A bare ``jnp.zeros(1)`` jit compile is timed first as the process's own baseline
(the machine is shared: compare ratios).  Writes results/bench_family/<label>.md.

    python experiments/bench_family.py [--label after]
"""

from __future__ import annotations

import argparse
import logging
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import camjax
from camjax import laws


class CompileCounter(logging.Handler):
    """Counts XLA compilations of the response programs (``jax_log_compiles`` messages)."""

    def __init__(self):
        super().__init__()
        self.count = 0

    def emit(self, record):
        message = record.getMessage()
        if message.startswith("Finished XLA compilation of jit(batch_metrics)"):
            self.count += 1


def seconds(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--label", default="after")
    parser.add_argument("--out", default="results/bench_family")
    args = parser.parse_args()
    counter = CompileCounter()
    logging.getLogger("jax").addHandler(counter)
    logging.getLogger("jax").setLevel(logging.WARNING)
    jax.config.update("jax_log_compiles", True)
    baseline = seconds(lambda: jax.jit(lambda x: x + 1)(jnp.zeros(1)).block_until_ready())
    n = np.linspace(1.0, 30.0, 1000)
    rows = []
    for law in laws.standard_laws():
        before = counter.count
        first = seconds(lambda law=law: camjax.ct_curve(law, n))
        warm = min(seconds(lambda law=law: camjax.ct_curve(law, n)) for _ in range(5))
        rows.append((law.name, first, warm, counter.count - before))
        print(f"{law.name:<20} first {first:6.2f} s  warm {warm * 1e3:6.1f} ms  "
              f"programs {counter.count - before}", flush=True)
    before = counter.count
    fresh = [laws.get(law.name) for law in laws.standard_laws()]
    all_first = seconds(lambda: camjax.ct_curves(fresh, n))
    all_warm = min(seconds(lambda: camjax.ct_curves(fresh, n)) for _ in range(3))
    all_programs = counter.count - before
    lines = [
        f"# Standard laws' Ct curves ({args.label}): 1000 period ratios, one process",
        "",
        f"Shared, loaded 2-core machine; a trivial jit compile took {baseline:.3f} s here.",
        "",
        "| law | first call s | warm ms | programs compiled |",
        "|---|---|---|---|",
        *(f"| {a} | {b:.2f} | {c * 1e3:.1f} | {d} |" for a, b, c, d in rows),
        f"| all seven, one after another | {sum(r[1] for r in rows):.2f} | "
        f"{sum(r[2] for r in rows) * 1e3:.1f} | {sum(r[3] for r in rows)} |",
        f"| `ct_curves` of all seven (after the above) | {all_first:.2f} | "
        f"{all_warm * 1e3:.1f} | {all_programs} |",
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{args.label}.md").write_text(text)


if __name__ == "__main__":
    main()
