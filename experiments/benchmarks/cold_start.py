"""Time to first answer: each command as a fresh process, cold and with a warm cache.

Every command of the table below runs as a new Python process (what a user waits for),
``--repeats`` times with an empty compilation cache (cold: a new ``CAMJAX_CACHE_DIR``
each run) and ``--repeats`` times with a cache the first cold run filled (warm).  The
bare start of JAX, ``import jax; jax.numpy.zeros(1).block_until_ready()``, is timed in
the same run, so every median is also printed as a ratio to it (the machine is shared:
ratios travel better than seconds), in wall time and in CPU time (user and system seconds of
the child process, all its threads: on a loaded machine the CPU ratio holds better, while
on a quiet one the wall ratio is what a user waits for).  The load average is printed with
the table.  Writes results/cold_start/<name>.md and .json, the
name being the date and the short commit of the timed checkout, then ``--label`` if given
(``2026-11-23-5a18caf-follower``), so that every record says when and what it measured.

    python experiments/benchmarks/cold_start.py [--repeats 3] [--only ct,help] [--root DIR]
                                     [--baseline DIR] [--label follower]

``--root`` times another checkout (its code is put first on ``PYTHONPATH``); ``--baseline``
times a second one in turn with it, run by run, and adds the ratios of the two.  Code that
has no persistent cache ignores ``CAMJAX_CACHE_DIR``; its warm runs then equal its cold.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BARE = "import jax; jax.numpy.zeros(1).block_until_ready()"
CT_CURVES = (
    "import numpy as np, camjax; "
    "camjax.ct_curves(camjax.laws.standard_laws(), np.linspace(1, 30, 1000))"
)

# name -> argv after the Python executable ({out} is a fresh temporary directory).
COMMANDS = {
    "bare-jax": ["-c", BARE],
    "help": ["-m", "camjax", "--help"],
    "ct-help": ["-m", "camjax", "ct", "--help"],
    "design-help": ["-m", "camjax", "design", "--help"],
    "ct": ["-m", "camjax", "ct", "--out", "{out}"],
    "ct_curves": ["-c", CT_CURVES],
    "design": ["-m", "camjax", "design", "--objective", "residual", "--band", "6:12",
               "--max-ca", "7.5", "--max-jerk", "100", "--out", "{out}"],
    "follower": ["-m", "camjax", "follower", "--law", "cycloidal"],
    "program": ["-m", "camjax", "program", "--rpm", "200:1200:101", "--no-flight"],
    "program-feed": ["-m", "camjax", "program", "feed", "--rpm", "300:900:101"],
}


SHOWN = {
    "bare-jax": 'python -c "import jax; jax.numpy.zeros(1).block_until_ready()"',
    "ct_curves": "python: camjax.ct_curves(standard_laws(), 1000 ratios in [1, 30])",
}


def record_name(root: Path, label: str | None) -> str:
    """Today's date and the short commit of the checkout at ``root`` (``2026-11-23-5a18caf``),
    then the label; without git, the date alone."""
    parts = [datetime.date.today().isoformat()]
    commit = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True)
    if commit.returncode == 0:
        parts.append(commit.stdout.strip())
    return "-".join([*parts, label] if label else parts)


def run_once(argv, root: Path, cache: str) -> tuple[float, float]:
    """Wall and CPU seconds of one fresh process (raises if it fails)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(root) + os.pathsep + env.get("PYTHONPATH", "")
    env["CAMJAX_CACHE_DIR"] = cache
    env.pop("JAX_COMPILATION_CACHE_DIR", None)
    env.pop("JAX_LOG_COMPILES", None)
    with tempfile.TemporaryDirectory() as out:
        args = [sys.executable, *(a.replace("{out}", out) for a in argv)]
        used = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        done = subprocess.run(args, env=env, cwd=out, capture_output=True, text=True)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - used.ru_utime) + (after.ru_stime - used.ru_stime)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} failed:\n{done.stderr[-2000:]}")
    return wall, cpu


def time_command(argv, roots: dict, repeats: int, scratch: str) -> dict:
    """Cold and warm runs of one command for every root, the roots taking turns run by run
    (so that a drift of the machine's speed falls on all of them alike)."""
    times = {label: {"cold": [], "warm": [], "cold_cpu": [], "warm_cpu": []} for label in roots}
    warm_cache = {label: tempfile.mkdtemp(dir=scratch) for label in roots}
    for i in range(repeats):
        for label, root in roots.items():
            cache = warm_cache[label] if i == 0 else tempfile.mkdtemp(dir=scratch)
            for key, value in zip(("cold", "cold_cpu"), run_once(argv, root, cache)):
                times[label][key].append(value)
    for _ in range(repeats):
        for label, root in roots.items():
            for key, value in zip(("warm", "warm_cpu"), run_once(argv, root, warm_cache[label])):
                times[label][key].append(value)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", help="comma-separated command names (default: all)")
    parser.add_argument("--root", default=str(Path(__file__).resolve().parents[2]),
                        help="checkout whose camjax is timed")
    parser.add_argument("--baseline", help="another checkout, timed in turn with --root")
    parser.add_argument("--label", help="what the run compares, appended to the file name")
    parser.add_argument("--out", default="results/cold_start")
    args = parser.parse_args()
    roots = {"now": Path(args.root).resolve()}
    name_of_record = record_name(roots["now"], args.label)
    if args.baseline:
        roots["baseline"] = Path(args.baseline).resolve()
    names = args.only.split(",") if args.only else list(COMMANDS)
    if "bare-jax" not in names:
        names.insert(0, "bare-jax")
    rows, bare, bare_cpu = {}, [], []
    with tempfile.TemporaryDirectory() as scratch:
        for name in names:
            # The bare start again before every command: the load drifts during a run.
            wall, cpu = run_once(COMMANDS["bare-jax"], roots["now"], str(Path(scratch) / "bare"))
            bare.append(wall)
            bare_cpu.append(cpu)
            rows[name] = time_command(COMMANDS[name], roots, args.repeats, scratch)
            print(name, "  ".join(f"{label}: cold {statistics.median(t['cold']):6.2f} s, warm "
                                  f"{statistics.median(t['warm']):6.2f} s"
                                  for label, t in rows[name].items()), flush=True)
    base = statistics.median(bare + rows["bare-jax"]["now"]["cold"] + rows["bare-jax"]["now"]["warm"])
    base_cpu = statistics.median(bare_cpu + rows["bare-jax"]["now"]["cold_cpu"]
                                 + rows["bare-jax"]["now"]["warm_cpu"])
    load = " ".join(f"{x:.1f}" for x in os.getloadavg())
    compared = "baseline" in roots
    header = ("| command | cold s | warm-cache s | cold / bare | warm / bare | cold CPU s "
              "| cold CPU / bare CPU | warm CPU / bare CPU |")
    if compared:
        header += " baseline cold s | baseline warm s | cold now / baseline | warm now / baseline |"
    lines = [
        f"# Cold start ({name_of_record}): whole-process wall time, median of {args.repeats}",
        "",
        "Shared 2-core machine under load from other jobs: read the ratios to the bare JAX",
        f"start (`python -c \"{BARE}\"`, median {base:.2f} s in this run, timed again before",
        "every command) rather than the seconds.  Cold: an empty compilation cache; warm: the",
        "cache the first cold run filled (code without a persistent cache: two more cold runs).",
        f"Bare start: {base_cpu:.2f} CPU s.  Load average at the end: {load}.",
        *([f"Baseline: `{roots['baseline']}`, run in turn with this checkout."] if compared else []),
        "",
        header,
        "|" + "---|" * (header.count("|") - 1),
    ]
    for name, r in rows.items():
        c, w = (statistics.median(r["now"][k]) for k in ("cold", "warm"))
        shown = SHOWN.get(name) or " ".join(COMMANDS[name]).replace("-m camjax", "camjax")
        shown = shown.replace("{out}", "DIR")
        cc, wc = (statistics.median(r["now"][k]) for k in ("cold_cpu", "warm_cpu"))
        line = (f"| `{shown}` | {c:.2f} | {w:.2f} | {c / base:.1f} | {w / base:.1f} | {cc:.2f} "
                f"| {cc / base_cpu:.1f} | {wc / base_cpu:.1f} |")
        if compared:
            bc, bw = (statistics.median(r["baseline"][k]) for k in ("cold", "warm"))
            line += f" {bc:.2f} | {bw:.2f} | {c / bc:.2f} | {w / bw:.2f} |"
        lines.append(line)
    text = "\n".join(lines) + "\n"
    print(text)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{name_of_record}.md").write_text(text)
    (out / f"{name_of_record}.json").write_text(json.dumps(
        {"label": name_of_record, "roots": {k: str(v) for k, v in roots.items()},
         "repeats": args.repeats, "bare_s": base, "bare_runs": bare, "bare_cpu_s": base_cpu,
         "bare_cpu_runs": bare_cpu, "load_average": os.getloadavg(),
         "commands": {k: {**v, "argv": COMMANDS[k]} for k, v in rows.items()}}, indent=1) + "\n")


if __name__ == "__main__":
    main()
