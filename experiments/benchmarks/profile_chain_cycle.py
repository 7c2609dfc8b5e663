"""Where a chain's speed block spends its time: the ten-body chain of ``bench_chain_edit.py``,
one block of ``SPEED_BLOCK`` speeds, timed warm in one process for (1) the modes' propagation
alone, (2) the whole cycle without the train's own figures (the one-body outputs: jets, the
dense refinement of the contact force, payload acceleration and torque, Hertz, residual) and
(3) the whole cycle (with each body's peak, the seat force and the surge, bounded search).

    python experiments/benchmarks/profile_chain_cycle.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import jax
import jax.numpy as jnp
import numpy as np
from bench_chain_edit import chain, program

from camjax.program import SteadyState
from camjax.sdof import periodic_propagate

SPEED_BLOCK = 32
"""Speeds per compiled call of the program's steady state (one block)."""


def best(fn, *args, repeats):
    """The best of ``repeats`` warm calls (seconds)."""
    jax.block_until_ready(fn(*args))
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(fn(*args))
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    cam = dataclasses.replace(program(), chain=chain())
    steady = SteadyState(cam, 300.0)
    rpm = np.linspace(300.0, 1500.0, SPEED_BLOCK)
    osc, grid = steady.oscillator, steady.turn.grid
    no_train = osc._replace(gain=osc.gain[:3], direct=osc.direct[:3], static=osc.static[:3])
    one_body = SteadyState(cam, 300.0, oscillator=no_train)  # the one-body outputs alone

    @jax.jit
    def modes(rpm, lam, weights, acc, lift):
        """Every mode's periodic steady state at every speed (the cycle's propagation)."""

        def one(r):
            period = 60.0 / r
            forcing = (
                weights[:, 1, None, None] * acc + (weights[:, 0] * period**2)[:, None, None] * lift
            )
            return jax.vmap(
                lambda l, f: periodic_propagate(
                    grid._replace(motion=grid.motion._replace(forcing=f)).motion, None, None, lam=l
                )
            )(period * lam, forcing)

        return jax.vmap(one)(rpm)

    arrays = (
        jnp.asarray(osc.lam),
        jnp.asarray(osc.forcing),
        jnp.asarray(grid.motion.forcing),
        jnp.asarray(grid.lift),
    )
    parts = {
        "propagation of the modes": best(modes, jnp.asarray(rpm), *arrays, repeats=args.repeats),
        "cycle without the train's figures": best(one_body.cycles, rpm, repeats=args.repeats),
        "whole cycle": best(steady.cycles, rpm, repeats=args.repeats),
    }
    print(
        f"grid intervals {steady.grid.intervals}, modes {steady.oscillator.modes_count}, "
        f"speeds per block {SPEED_BLOCK}"
    )
    for name, seconds in parts.items():
        print(f"{name}: {1e3 * seconds:.0f} ms per block")


if __name__ == "__main__":
    main()
