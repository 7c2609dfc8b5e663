"""Throughput per device of a sharded sweep, 1 to 4 forced host devices, in one process.

A stack of traced SCCA laws against period ratios in [1, 30] (``camjax.sweep.sweep_law_stack``, the
atlas's path) and one law against many ratios (``ct_curve``'s path) are timed on 1, 2 and
4 devices of the same process; the figure of merit is the throughput per device over the
single-device throughput (1.0 = perfect scaling).  Forced host devices share the
machine's cores, so a ratio near 1 needs at least as many free cores as devices: on
c cores k devices get at most c / k each (``per_device_bound``; 0.5 for 4 devices on the
2-core machine, which therefore cannot show scaling beyond 2 devices); the figures say
how many cores there were and what the load was.

    python experiments/benchmarks/bench_sharding.py                # writes results/sharding/bench.json
    python experiments/benchmarks/bench_sharding.py --laws 16 --count 500
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--devices", type=int, nargs="+", default=[1, 2, 4])
    parser.add_argument("--laws", type=int, default=8, help="SCCA laws in the stack")
    parser.add_argument("--count", type=int, default=400, help="period ratios in [1, 30]")
    parser.add_argument("--ratios", type=int, default=4000, help="ratios of the one-law run")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=HERE.parents[1] / "results" / "sharding")
    args = parser.parse_args()
    flag = f"--xla_force_host_platform_device_count={max(args.devices)}"
    os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {flag}".strip()

    import jax
    import jax.numpy as jnp

    from camjax import distributed, laws
    from camjax.studies import timed
    from camjax.sweep import prepare_sweep, sweep_law_stack, sweep_metrics

    _, template, options = prepare_sweep([30.0])
    family = distributed.scca_grid(0.1, face=True)[: args.laws]
    stack = jax.tree.map(lambda *x: jnp.stack(x), *family)
    n_stack = jnp.linspace(1.0, 30.0, args.count)
    n_many = jnp.linspace(1.0, 30.0, args.ratios)
    law = laws.get("modified-sine")
    cases = {
        "scca-stack": (args.laws * args.count,
                       lambda k: sweep_law_stack(stack, n_stack, template, options, devices=k)),
        "one-law": (args.ratios,
                    lambda k: sweep_metrics(law, n_many, template, options, devices=k)),
    }
    report = {"cores": os.cpu_count(), "devices": jax.local_device_count(),
              "load_before": [round(x, 2) for x in os.getloadavg()], "cases": {},
              # forced host devices share the cores: k devices on c cores give each at
              # most c / k of a core, so the per-device ratio cannot pass this
              "per_device_bound": {k: round(min(1.0, os.cpu_count() / k), 3)
                                   for k in args.devices}}
    for name, (evaluations, run) in cases.items():
        rows = {}
        for k in args.devices:
            seconds = timed(lambda k=k, run=run: run(k), args.repeats).best_s
            rows[k] = {"seconds": round(seconds, 4),
                       "evaluations_per_s": round(evaluations / seconds, 1)}
        base = rows[args.devices[0]]["evaluations_per_s"] / args.devices[0]
        for k, row in rows.items():
            row["per_device_over_single"] = round(row["evaluations_per_s"] / k / base, 3)
            print(f"{name:11s} devices={k}: {row['evaluations_per_s']:10.0f} evaluations/s, "
                  f"per device {row['per_device_over_single']:.3f} x single "
                  f"(at most {report['per_device_bound'][k]:.2f} on {os.cpu_count()} cores)",
                  flush=True)
        report["cases"][name] = {"evaluations": evaluations, "runs": rows}
    report["uptime"] = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(report["uptime"])
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench.json").write_text(json.dumps(report, indent=1) + "\n")


if __name__ == "__main__":
    main()
