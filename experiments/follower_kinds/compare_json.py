"""Every number of ``camjax program --format json`` of two source trees, compared.

The built-in cams with their defaults, one program file of each follower kind no built-in
uses (this folder, at three speeds), and each of those cams read back from its own DXF
drawing (the drawing written once by the ``--base`` tree: the same input to both).  A
number differs where ``|a - b| > rtol * max(|a|, |b|)``; strings and the structure must be
equal.  Prints each case and the largest relative difference, and every difference found.

    git archive <main's commit> | tar -x -C /tmp/base
    python experiments/follower_kinds/compare_json.py --base /tmp/base --new . --work /tmp/compare
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).parent
BUILT_IN = ("indexer", "feed", "valve", "servo")
KINDS = ("swinging_roller", "swinging_roller_groove", "translating_roller_groove", "translating_flat",
         "swinging_flat")
DRAWN = ("swinging_roller", "translating_roller_groove", "translating_flat", "swinging_flat")


def run(tree: Path, args: list[str], out: Path | None = None) -> str:
    env = {**os.environ, "PYTHONPATH": str(tree.resolve()), "CAMJAX_CACHE_DIR": "off"}
    done = subprocess.run([sys.executable, "-m", "camjax", "program", *args], env=env, capture_output=True,
                          text=True, cwd=tree)
    if done.returncode:
        raise SystemExit(f"{tree}: camjax program {' '.join(args)} failed:\n{done.stderr}")
    if out is not None:
        out.write_text(done.stdout)
    return done.stdout


def differences(a, b, where: str, rtol: float, found: list[str]) -> float:
    """The largest relative difference of the numbers in ``a`` and ``b``; the rest into ``found``."""
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            found.append(f"{where}: keys {sorted(a.keys() ^ b.keys())} in one only")
        return max([differences(a[k], b[k], f"{where}.{k}", rtol, found) for k in a.keys() & b.keys()], default=0.0)
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            found.append(f"{where}: {len(a)} against {len(b)} items")
            return math.inf
        return max([differences(x, y, f"{where}[{i}]", rtol, found) for i, (x, y) in enumerate(zip(a, b))],
                   default=0.0)
    numbers = (int, float)
    if isinstance(a, numbers) and isinstance(b, numbers) and not isinstance(a, bool):
        if a == b or (math.isnan(a) and math.isnan(b)):
            return 0.0
        relative = abs(a - b) / max(abs(a), abs(b))
        if not relative <= rtol:
            found.append(f"{where}: {a!r} against {b!r} (relative {relative:.3g})")
        return relative
    if a != b:
        found.append(f"{where}: {a!r} against {b!r}")
    return 0.0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", type=Path, required=True, help="the tree compared against (main's)")
    parser.add_argument("--new", type=Path, required=True, help="the tree under test")
    parser.add_argument("--work", type=Path, required=True, help="a folder for the drawings and outputs")
    parser.add_argument("--rtol", type=float, default=1e-10)
    parser.add_argument("--skip-base", action="store_true", help="reuse the base tree's outputs in --work")
    args = parser.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    cases = {name: [name, "--format", "json"] for name in BUILT_IN}
    cases |= {kind: [str((HERE / f"{kind}.toml").resolve()), "--rpm", "300,600,900", "--format", "json"]
              for kind in KINDS}
    for kind in DRAWN:  # the cam drawn by the base tree, read back from its drawing
        folder = args.work / f"drawn_{kind}"
        if not (folder / "profile.dxf").exists():
            run(args.base, [str((HERE / f"{kind}.toml").resolve()), "--points", "720", "--no-flight",
                            "--out", str(folder.resolve())])
        text = (HERE / f"{kind}.toml").read_text().split("[[segment]]")[0]
        follower = "[follower]" + (HERE / f"{kind}.toml").read_text().split("[follower]")[1]
        follower = "\n".join(line for line in follower.splitlines() if not line.startswith("base_radius_mm"))
        (folder / "drawn.toml").write_text(text + 'dxf = "profile.dxf"\ndxf_points = 360\n\n' + follower + "\n")
        cases[f"drawn_{kind}"] = [str((folder / "drawn.toml").resolve()), "--rpm", "600", "--format", "json"]
    worst, failed = 0.0, False
    for name, argv in cases.items():
        base_out = args.work / f"{name}.base.json"
        if not (args.skip_base and base_out.exists()):
            run(args.base, argv, base_out)
        new = json.loads(run(args.new, argv, args.work / f"{name}.new.json"))
        found: list[str] = []
        largest = differences(json.loads(base_out.read_text()), new, name, args.rtol, found)
        worst = max(worst, largest)
        print(f"{name:28s} largest relative difference {largest:.3g}" + (f", {len(found)} beyond" if found else ""))
        for line in found[:20]:
            print("   ", line)
        failed |= bool(found)
    print(f"all cases: largest relative difference {worst:.3g} ({'FAIL' if failed else 'ok'} at {args.rtol:g})")
    return int(failed)


if __name__ == "__main__":
    raise SystemExit(main())
