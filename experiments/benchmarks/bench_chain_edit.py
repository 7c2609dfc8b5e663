"""An edit of a ten-body chain analysed at 101 speeds, against warm Ct curves, in one process.

The chain (bodies 0.05 kg on 500 N/mm elements, 40 N s/m, a 30 N/mm return spring) drives
the two-cycloids test program from 300 to 1500 rpm.  After one warm-up analysis (masses 5% up), an edit
(masses 6-8% up, the spring's rate and preload changed: the grid stays in its bucket) is
analysed again: a new ``SteadyState`` of the program with the chain and its summary at 101
speeds (every output of the report's rows and the train's own figures), with the XLA
compilations it caused counted.  The baseline is ``camjax.ct_curve`` of the cycloidal law over 1000 period ratios,
warm; the target is the edit in at most about 150 of those.

    python experiments/benchmarks/bench_chain_edit.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import jax
import numpy as np

import camjax
from camjax import laws
from camjax.program import Body, Chain, Follower, Program, Segment, Spring, SteadyState


def program() -> Program:
    law = laws.get("cycloidal")
    follower = Follower(
        kind="translating-roller",
        mass_kg=1.5,
        stiffness_n_per_mm=2000.0,
        damping_ratio=0.05,
        spring_rate_n_per_mm=10.0,
        preload_n=300.0,
        base_radius_mm=40.0,
        roller_radius_mm=12.0,
    )
    return Program(
        "two-cycloids",
        (Segment(100, 20.0, law), Segment(80), Segment(100, -20.0, law), Segment(80)),
        follower,
    )


def chain(scale: float = 1.0, rate: float = 30.0, preload: float = 400.0) -> Chain:
    bodies = tuple(Body(f"b{j}", 0.05 * scale, 500.0, 40.0) for j in range(10))
    return Chain(bodies, Spring(rate, preload))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    cam = program()
    rpm = np.linspace(300.0, 1500.0, 101)
    SteadyState(dataclasses.replace(cam, chain=chain(1.05)), 300.0).summary(
        rpm
    )  # compile and warm up
    compiled = []

    def listener(event, duration, **kwargs):
        if event == "/jax/core/compile/backend_compile_duration":
            compiled.append(kwargs.get("fun_name"))

    jax.monitoring.register_event_duration_secs_listener(listener)
    edits = []
    for i in range(args.repeats):
        start = time.perf_counter()
        edited = dataclasses.replace(cam, chain=chain(1.06 + 0.01 * i, 32.0 + i, 420.0 + i))
        steady = SteadyState(edited, 300.0)
        steady.summary(rpm)
        edits.append(time.perf_counter() - start)
    jax.monitoring.unregister_event_duration_listener(listener)
    n = np.linspace(1, 30, 1000)
    cycloidal = laws.get("cycloidal")
    camjax.ct_curve(cycloidal, n)  # compile
    curves = []
    for _ in range(max(args.repeats, 5)):
        start = time.perf_counter()
        jax.block_until_ready(camjax.ct_curve(cycloidal, n).ct)
        curves.append(time.perf_counter() - start)
    edit, curve = min(edits), min(curves)
    print(
        f"grid intervals {steady.grid.intervals}, modes {steady.oscillator.modes_count}, speeds {rpm.size}"
    )
    print(f"edit of the ten-body chain at 101 speeds: {1e3 * edit:.0f} ms (best of {args.repeats})")
    print(f"warm Ct curve (cycloidal, 1000 ratios): {1e3 * curve:.1f} ms")
    print(f"ratio: {edit / curve:.0f} Ct curves (target: about 150 or fewer)")
    print(f"compilations during the edits: {len(compiled)} {sorted(set(map(str, compiled)))}")


if __name__ == "__main__":
    main()
