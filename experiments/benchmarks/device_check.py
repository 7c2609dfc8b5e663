"""The exact path on an accelerator: kernel and host time, agreement with the CPU, chunk sizes.

Three cases, each warm (median of ``--repeats`` calls after a first, compiling one):
three standard laws' 1000-ratio Ct curves in [1, 30] through ``camjax.ct_curve``, one
law's 100,000-ratio curve, and 256 SCCA laws of the face x 1000 ratios through
``camjax.ct_curves`` (one stacked call).  The kernel (the compiled sweep of a pre-sampled
law, or of the stacked laws, run to completion) is timed apart, and host = call - kernel.  Every
result is compared with a reference written on another machine (``--write-reference``,
on the CPU) by its largest difference in Ct and residual.

On a backend other than the CPU, ``--configs`` times each pair ``K:E`` of
``camjax.sharding.SweepOptions(accelerator_chunk_nodes=2**K, accelerator_stack_evaluations=E)``,
passed to every sweep
(``17:1``: the CPU's chunks, a stack's laws one at a time) in one process (compiled anew for each), with the device's peak memory where it reports one.

    python experiments/benchmarks/device_check.py --write-reference ref.npz            # on the CPU
    python experiments/benchmarks/device_check.py --reference ref.npz --out results.json
    python experiments/benchmarks/device_check.py --reference ref.npz --configs 17:1 24:65536
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import jax
import numpy as np

import camjax
from camjax import distributed, sdof, sweep
from camjax.sharding import SweepOptions

LAWS = ("cycloidal", "modified-sine", "4-5-6-7")
BIG = "cycloidal"


def scca_laws(count: int = 256) -> dict:
    face = distributed.scca_grid(0.01, face=True)
    picked = np.unique(np.linspace(0, len(face) - 1, count).astype(int))
    return {face[i].name: face[i] for i in picked}


def timed(fn, repeats: int) -> tuple[float, float]:
    """(first call, median of ``repeats`` further calls), seconds."""
    start = time.perf_counter()
    jax.block_until_ready(fn())
    first = time.perf_counter() - start
    runs = []
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(fn())
        runs.append(time.perf_counter() - start)
    return first, float(np.median(runs))


def results(repeats: int, sizes: SweepOptions) -> tuple[dict, dict]:
    """(timings, arrays) of the three cases, every sweep with the options ``sizes``."""
    timings, arrays = {}, {}
    cases = [(name, 1000, repeats) for name in LAWS] + [(BIG, 100_000, max(3, repeats // 4))]
    for name, count, reps in cases:
        n = np.linspace(1.0, 30.0, count)
        law = camjax.laws.as_law(name)
        first, call = timed(lambda law=law, n=n: camjax.ct_curve(law, n, sweep=sizes).ct, reps)
        ratios, template, options = sweep.prepare_sweep(n, sweep=sizes)
        sampled = template.sweep_law(law, options)
        _, kernel = timed(lambda s=sampled, r=ratios, t=template, o=options: sweep.sweep_metrics(s, r, t, o),
                          reps)
        curve = camjax.ct_curve(law, n, sweep=sizes)
        key = f"{name} x {count}"
        timings[key] = {"first_s": first, "call_ms": 1e3 * call, "kernel_ms": 1e3 * kernel,
                        "host_ms": 1e3 * (call - kernel)}
        arrays[f"{key}/ct"], arrays[f"{key}/residual"] = curve.ct, curve.residual
    laws = scca_laws()
    n = np.linspace(1.0, 30.0, 1000)
    first, call = timed(lambda: camjax.ct_curves(laws, n, sweep=sizes), max(3, repeats // 4))
    ratios, template, options = sweep.prepare_sweep(n, sweep=sizes)
    stacked = sweep.stack_of(laws.values())
    _, kernel = timed(lambda: sweep.sweep_law_stack(stacked, ratios, template, options),
                      max(3, repeats // 4))
    curves = camjax.ct_curves(laws, n, sweep=sizes)
    key = f"{len(laws)} SCCA x 1000"
    timings[key] = {"first_s": first, "call_ms": 1e3 * call, "kernel_ms": 1e3 * kernel,
                    "host_ms": 1e3 * (call - kernel)}
    arrays[f"{key}/ct"] = np.stack([c.ct for c in curves.values()])
    arrays[f"{key}/residual"] = np.stack([c.residual for c in curves.values()])
    return timings, arrays


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference", type=Path, help="arrays to compare with (.npz)")
    parser.add_argument("--write-reference", type=Path, help="write this run's arrays (.npz)")
    parser.add_argument("--configs", nargs="+", default=[],
                        help="K:E pairs: accelerator chunks of 2**K nodes, E evaluations of a stack at once")
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--out", type=Path, help="write the timings here (.json)")
    args = parser.parse_args()
    device = jax.devices()[0]
    print(f"jax {jax.__version__}, {jax.device_count()} x {device.device_kind} ({device.platform})",
          flush=True)
    reference = dict(np.load(args.reference)) if args.reference else None
    accelerator = jax.default_backend() != "cpu"
    configs = [tuple(map(int, c.split(":"))) for c in args.configs] if accelerator else []
    rows = []
    for config in configs or [None]:
        sizes = SweepOptions() if config is None else SweepOptions(
            accelerator_chunk_nodes=2 ** config[0], accelerator_stack_evaluations=config[1])
        jax.clear_caches()  # each configuration timed from its first compilation
        setting = {"chunk_nodes": sdof.chunk_nodes(sizes), "stack_laws": sdof.stack_laws(1000, 1, sizes)}
        timings, arrays = results(args.repeats, sizes)
        stats = device.memory_stats() or {}
        for key, row in timings.items():
            if reference is not None:
                row["max_diff"] = max(float(np.max(np.abs(arrays[f"{key}/{m}"] - reference[f"{key}/{m}"])))
                                      for m in ("ct", "residual"))
            rows.append({**setting, "case": key, **row})
            print(json.dumps(rows[-1]), flush=True)
        if "peak_bytes_in_use" in stats:
            print(f"peak device memory so far: {stats['peak_bytes_in_use'] / 2**30:.2f} GiB", flush=True)
        if args.write_reference:
            np.savez_compressed(args.write_reference, **arrays)
    print(f"\n{'chunk':>8} {'stack':>5} {'case':<28} {'first s':>8} {'call ms':>9} {'kernel ms':>9} "
          f"{'host ms':>8} {'max diff':>9}")
    for r in rows:
        print(f"{r['chunk_nodes']:>8} {r['stack_laws']:>5} {r['case']:<28} {r['first_s']:8.2f} "
              f"{r['call_ms']:9.2f} {r.get('kernel_ms', float('nan')):9.2f} "
              f"{r.get('host_ms', float('nan')):8.2f} {r.get('max_diff', float('nan')):9.1e}")
    if args.out:
        args.out.write_text(json.dumps({"device": f"{device.device_kind} ({device.platform})",
                                        "jax": jax.__version__, "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
