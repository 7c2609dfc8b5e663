"""Ratios in lockstep (``vmap``) or in turn (``lax.map``): warm time of one sweep per model.

A sweep of a phase-by-phase model (friction's events, backlash) runs loops whose trip
counts differ from ratio to ratio; vmapped, every ratio runs in lockstep for as long as the
longest, with the whole loop state selected at every trip.  This times both forms of the
same program in one process, for the models whose sweeps run diffrax, checks that they
agree, and prints the ratio; ``AbstractModel.sweeps_in_turn`` picks the faster per model.

    python experiments/benchmarks/sweep_in_turn.py [--count 16] [--repeats 3]
"""

from __future__ import annotations

import argparse
import functools

import jax
import numpy as np

import camjax
from camjax.checks import checked_outside
from camjax.models import Backlash, CoulombFriction, TwoMass
from camjax.studies import timed
from camjax.sweep import prepare_sweep

CASES = {
    "friction (events)": (CoulombFriction(1.0, 0.05), None),
    "friction (regularised)": (CoulombFriction(1.0, 0.05), "regularised"),
    "backlash": (Backlash(1.0, 0.01, 0.1, 0.02), None),
    "two-mass": (TwoMass(1.0, 4.0, 0.5), None),
}


def program(form: str, options):
    """The sweep of one model's ratios, vmapped or mapped in turn (options are static)."""
    @jax.jit
    def sweep(law, template, ratios):
        def one(n):
            return template.with_period_ratio(n).metrics(law, options)

        with checked_outside():
            return jax.lax.map(one, ratios) if form == "in turn" else jax.vmap(one)(ratios)

    return sweep


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=16, help="period ratios in [2, 20]")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    law = camjax.laws.get("cycloidal")
    print(f"{args.count} period ratios in [2, 20], cycloidal; warm seconds, best of {args.repeats}")
    print(f"{'model':<24} {'lockstep':>9} {'in turn':>9} {'in turn / lockstep':>19} {'picked':>9}")
    for name, (model, method) in CASES.items():
        n, template, options = prepare_sweep(np.linspace(2.0, 20.0, args.count), model, method=method)
        seconds, ct = {}, {}
        for form in ("lockstep", "in turn"):
            call = functools.partial(program(form, options), law, template, jax.numpy.asarray(n))
            ct[form] = np.asarray(call()[0].ct)
            seconds[form] = timed(call, args.repeats).best_s
        np.testing.assert_allclose(ct["in turn"], ct["lockstep"], rtol=1e-9)
        picked = "in turn" if template.sweeps_in_turn(options) else "lockstep"
        print(f"{name:<24} {seconds['lockstep']:9.3f} {seconds['in turn']:9.3f} "
              f"{seconds['in turn'] / seconds['lockstep']:19.2f} {picked:>9}", flush=True)


if __name__ == "__main__":
    main()
