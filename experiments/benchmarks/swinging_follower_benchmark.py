"""Speed and accuracy of the swinging-follower simulation (three cam turns, base set).

    nice -n 5 python experiments/benchmarks/swinging_follower_benchmark.py [--no-vmap] [--old-vmap]

For each variant (solver, step-size controller, full model or axial sin modes dropped, i.e.
treated quasi-statically) it reports the compile time (trace + XLA: first call minus the best
repeat), the run time (best of ``--repeats`` calls after the compile), the step count, and the
error against a tight full-model reference (Dopri8, rtol 1e-10, atol 1e-14): largest mid-rod
|v| and pointwise differences of v and of the roller-end u (relative to their largest value),
and the worst relative error over the spectral peaks at 1, 3, 5 Omega and near the
fundamental (v and u).  Then the four-law study, vmapped through one ``LawBank``: compile and
run times.  Writes results/swinging_follower/benchmark.json; wall times depend on the load of
the machine, which is recorded (``os.getloadavg``) next to them, with the process CPU time of
the runs (less sensitive to other jobs; XLA may use both cores).
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import camjax  # noqa: F401  (float64)
from camjax.laws import Cycloidal, LawBank, ModifiedSine, ModifiedTrapezoid, PolynomialLaw
from camjax.models import SwingingFollower, spectral_peaks, spectrum

OUT = Path("results/swinging_follower")
TURNS, PER_TURN = 3, 512
LAWS = (Cycloidal(), ModifiedSine(), ModifiedTrapezoid(), PolynomialLaw(3))
I_CONTROLLER = {"pcoeff": 0.0, "icoeff": 1.0}
PI_CONTROLLER = {"pcoeff": 0.3, "icoeff": 0.3}
VARIANTS = {
    "full, tsit5, I controller (old default)": ({}, {"method": "tsit5", **I_CONTROLLER}),
    "full, tsit5, PI controller": ({}, {"method": "tsit5", **PI_CONTROLLER}),
    "full, dopri8, PI controller (default)": ({}, {"method": "dopri8", **PI_CONTROLLER}),
    "axial_modes=1, tsit5, PI controller": ({"axial_modes": 1}, {"method": "tsit5", **PI_CONTROLLER}),
    "axial_modes=1, dopri8, PI controller": ({"axial_modes": 1}, {"method": "dopri8", **PI_CONTROLLER}),
    "axial_modes=1, modes=2, dopri8, PI controller": ({"axial_modes": 1, "modes": 2}, {"method": "dopri8", **PI_CONTROLLER}),
}


def timed(fn, repeats):
    """``(output, compile_s, run_s, run_cpu_s)``: run times are the best of ``repeats`` calls."""
    start = time.perf_counter()
    out = jax.block_until_ready(fn())
    first = time.perf_counter() - start
    runs, cpu = [], []
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        out = jax.block_until_ready(fn())
        runs.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return out, first - min(runs), min(runs), min(cpu)


def peaks(response, order):
    out = []
    for signal in (response.transverse, response.axial_end):
        harmonics, near = spectral_peaks(spectrum(np.asarray(signal), TURNS), order)
        out += [a for _, a in harmonics[:3]] + [near[1]]
    return np.array(out)


def errors(response, reference, order):
    v, u = np.asarray(response.transverse), np.asarray(response.axial_end)
    v_ref, u_ref = np.asarray(reference.transverse), np.asarray(reference.axial_end)
    p, p_ref = peaks(response, order), peaks(reference, order)
    return {
        "max_v_rel": float(np.max(np.abs(v)) / np.max(np.abs(v_ref)) - 1),
        "max_u_rel": float(np.max(np.abs(u)) / np.max(np.abs(u_ref)) - 1),
        "pointwise_v_rel": float(np.max(np.abs(v - v_ref)) / np.max(np.abs(v_ref))),
        "pointwise_u_rel": float(np.max(np.abs(u - u_ref)) / np.max(np.abs(u_ref))),
        "peaks_v_worst_rel": float(np.max(np.abs(p[:4] / p_ref[:4] - 1))),
        "peaks_u_worst_rel": float(np.max(np.abs(p[4:] / p_ref[4:] - 1))),
    }


def vmapped_study(model_kwargs, solver_kwargs):
    @jax.jit
    def study(index):
        def one(i):
            bank = LawBank(LAWS, i)
            model = SwingingFollower(rise=bank, fall=bank, **model_kwargs)
            return camjax.solve(None, model, turns=TURNS, samples_per_turn=PER_TURN, throw=False, **solver_kwargs)

        return jax.vmap(one)(index)

    index = jnp.arange(len(LAWS))
    responses, compile_s, run_s, cpu_s = timed(lambda: study(index), 1)
    assert bool(jnp.all(responses.result == camjax.RESULTS.successful))
    return {"compile_s": compile_s, "run_s": run_s, "run_cpu_s": cpu_s, "steps_per_law": [int(s) for s in responses.stats["steps"]]}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--no-vmap", action="store_true", help="skip the vmapped four-law study")
    parser.add_argument("--old-vmap", action="store_true", help="also time the vmapped study with the old default")
    args = parser.parse_args()
    report = {"command": "nice -n 5 python experiments/benchmarks/swinging_follower_benchmark.py", "cpus": os.cpu_count()}
    report["load_before"] = os.getloadavg()
    base = SwingingFollower()
    order = float(base.fundamental_frequency()) / base.omega
    reference, compile_s, run_s, _ = timed(lambda: camjax.solve(None, base, turns=TURNS, samples_per_turn=PER_TURN, rtol=1e-10, atol=1e-14, method="dopri8"), 1)
    report["reference"] = {"solver": "dopri8", "rtol": 1e-10, "atol": 1e-14, "steps": int(reference.stats["steps"]), "run_s": run_s}
    print(f"reference: {int(reference.stats['steps'])} steps, {run_s:.2f} s")
    report["variants"] = {}
    for name, (model_kwargs, solver_kwargs) in VARIANTS.items():
        model = SwingingFollower(**model_kwargs)
        response, compile_s, run_s, cpu_s = timed(lambda m=model, k=solver_kwargs: camjax.solve(None, m, turns=TURNS, samples_per_turn=PER_TURN, **k), args.repeats)
        entry = {"compile_s": compile_s, "run_s": run_s, "run_cpu_s": cpu_s, "steps": int(response.stats["steps"])}
        entry |= {"max_constraint_error_m": float(response.max_constraint_error)} | errors(response, reference, order)
        report["variants"][name] = entry
        print(
            f"{name}: compile {compile_s:.1f} s, run {run_s:.2f} s (cpu {cpu_s:.2f} s), {entry['steps']} steps; "
            f"max|v| {entry['max_v_rel']:+.1e}, v {entry['pointwise_v_rel']:.1e}, u {entry['pointwise_u_rel']:.1e}, "
            f"peaks v {entry['peaks_v_worst_rel']:.1e} u {entry['peaks_u_worst_rel']:.1e}"
        )
    if not args.no_vmap:
        report["vmapped_four_laws"] = {}
        chosen = ["full, dopri8, PI controller (default)", "axial_modes=1, dopri8, PI controller"]
        if args.old_vmap:
            chosen.insert(0, "full, tsit5, I controller (old default)")
        for name in chosen:
            entry = vmapped_study(*VARIANTS[name])
            report["vmapped_four_laws"][name] = entry
            print(
                f"vmapped four laws, {name}: compile {entry['compile_s']:.1f} s, run {entry['run_s']:.1f} s "
                f"(cpu {entry['run_cpu_s']:.1f} s), steps {entry['steps_per_law']}"
            )
    report["load_after"] = os.getloadavg()
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "benchmark.json").write_text(json.dumps(report, indent=1) + "\n")


if __name__ == "__main__":
    main()
