"""The exact kernel against a compiled CPU peer in one process, for several checkouts in turn.

Each checkout runs as a worker process (its code first on ``PYTHONPATH``) that times, warm,
in turn call by call:

- **per curve**: the compiled sweep of a pre-sampled law over 1000 period ratios in [1, 30]
  (``sweep.sweep_metrics``, the kernel of ``warm_curve.py``), cycloidal, modified sine and
  4-5-6-7, on one CPU device;
- **per 256 laws**: ``camjax.ct_curves`` of 256 SCCA laws of the face x 1000 ratios (the
  call of ``bench_scca_laws.py``), one device per core;
- **the peer**: an XLA-compiled product of two 512 x 512 float64 matrices (0.27 GFLOP, the
  work of about six 1000-ratio curves by the hand count on the performance page), timed
  between the kernel's calls in the same process.

Each figure is printed as milliseconds (wall, and CPU time of the process's threads) and as
a ratio to the peer's median in the same process, both ways: the ratio travels between
machines and hours, the milliseconds do not; on a loaded machine the CPU-time ratio holds
better than the wall one.  The
checkouts take turns, round by round, so a drift of the machine falls on all of them.

    python experiments/benchmarks/kernel_vs_peer.py --checkouts . /tmp/old [--rounds 3] [--repeats 30]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

WORKER = r"""
import json, sys, time
mode, repeats = sys.argv[1], int(sys.argv[2])
if mode == "stack":
    from camjax.sharding import use_cpu_cores
    use_cpu_cores(None)
import jax, jax.numpy as jnp, numpy as np
import camjax
from camjax import distributed, sweep

a = jnp.asarray(np.random.default_rng(0).standard_normal((512, 512)))
peer = jax.jit(lambda x: x @ x)
jax.block_until_ready(peer(a))
n = np.linspace(1.0, 30.0, 1000)
if mode == "curve":
    ratios, template, options = sweep.prepare_sweep(n)
    cases = {}
    for name in ("cycloidal", "modified-sine", "4-5-6-7"):
        sampled = template.sweep_law(camjax.laws.get(name), options)
        cases[name] = lambda s=sampled: sweep.sweep_metrics(s, ratios, template, options)
else:
    face = distributed.scca_grid(0.01, face=True)
    picked = np.unique(np.linspace(0, len(face) - 1, 256).astype(int))
    chosen = {face[i].name: face[i] for i in picked}
    cases = {"256 SCCA laws": lambda: camjax.ct_curves(chosen, n)}
for fn in cases.values():
    jax.block_until_ready(fn())
times = {name: [] for name in cases}
times["peer"] = []
for _ in range(repeats):
    for name, fn in [*cases.items(), ("peer", lambda: peer(a))]:
        start, cpu = time.perf_counter(), time.process_time()
        jax.block_until_ready(fn())
        times[name].append((time.perf_counter() - start, time.process_time() - cpu))
print(json.dumps(times))
"""


def run_worker(root: Path, mode: str, repeats: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(root))
    done = subprocess.run(
        [sys.executable, "-c", WORKER, mode, str(repeats)],
        env=env,
        cwd=root,
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        raise RuntimeError(f"worker in {root} failed:\n{done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def commit_of(root: Path) -> str:
    done = subprocess.run(
        ["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    )
    return done.stdout.strip() or str(root)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkouts", nargs="+", default=["."])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=30, help="calls of each case per worker")
    parser.add_argument("--modes", default="curve,stack")
    args = parser.parse_args()
    roots = [Path(c).resolve() for c in args.checkouts]
    ratios: dict = {}
    for round_ in range(args.rounds):
        for mode in args.modes.split(","):
            for root in roots:
                times = run_worker(root, mode, args.repeats)
                peer = [statistics.median(t) for t in zip(*times.pop("peer"))]
                load = os.getloadavg()[0]
                for name, pairs in times.items():
                    kernel = [statistics.median(t) for t in zip(*pairs)]
                    wall, cpu = (k / p for k, p in zip(kernel, peer))
                    ratios.setdefault((commit_of(root), name), []).append((wall, cpu))
                    print(
                        f"round {round_ + 1} {commit_of(root):>8} {name:<14} wall {1e3 * kernel[0]:8.2f} ms"
                        f" cpu {1e3 * kernel[1]:8.2f} ms; peer {1e3 * peer[0]:6.2f} / {1e3 * peer[1]:6.2f} ms;"
                        f" ratio wall {wall:5.2f} cpu {cpu:5.2f}; load {load:.1f}",
                        flush=True,
                    )
    print("\n| checkout | case | kernel / peer, wall (rounds) | kernel / peer, CPU time (rounds) |")
    print("|---|---|---|---|")
    for (commit, name), values in ratios.items():
        walls, cpus = zip(*values)
        print(
            f"| {commit} | {name} | {statistics.median(walls):.2f} ({', '.join(f'{v:.2f}' for v in walls)}) "
            f"| {statistics.median(cpus):.2f} ({', '.join(f'{v:.2f}' for v in cpus)}) |"
        )


if __name__ == "__main__":
    main()
