"""Every living study in ``experiments/examples/`` runs in its quick mode (small sizes, into a
temporary folder, as a fresh process), so that a study cannot silently stop working as the
library changes.  The benchmarks (``experiments/benchmarks/``) time things and are not run."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "experiments" / "examples"

QUICK = {
    "design_convex.py": ["--quick"],
    "friction.py": ["--quick"],
    "laws_table.py": ["--quick"],
    "motion_tasks.py": ["--quick"],
    "robust_laws.py": ["--quick"],
    "scca_atlas.py": ["--quick", "--no-cache", "--devices", "1"],
    "stability_atlas.py": ["--quick"],
    "two_mass.py": ["--quick"],
}
"""The arguments of each example's quick mode (``--out`` is added)."""

SLOW = {"stability_atlas.py", "robust_laws.py"}
"""Quick modes kept out of the default run: the stability atlas's still builds five panels
(fixed-step maps, adaptive solvers with and without ``jump_ts``, a float32 child process,
Tsit5 up to n = 300, four default grids), 138 s on the loaded 2-core machine against 18-36 s
for each of the others (2026-11-27); the robust laws' quick mode compiles and runs two
designs, 108 s there (24 s of CPU, 2026-11-29)."""

NOT_RUN = {
    "backlash.py": "no quick mode yet: its four parts (charts, dynamic impacts, solver limits, an optax design) take minutes",
    "design_caact.py": "no quick mode yet: 24-knot designs and an SCCA sweep",
    "design_pareto.py": "no quick mode yet: one design and one LP per Ca cap",
    "docs_screenshots.py": "needs a built site (mkdocs build --strict) and Chromium",
    "swinging_arm_program.py": "no quick mode yet: the paper's rod through a program file, four laws and seven "
                               "parameter sets at about 10 s of CPU each; tests/test_swinging_arm.py checks its numbers",
    "swinging_follower.py": "no quick mode yet: three cam turns of the flexible rod per law",
    "valve_seating.py": "draws the docs' figure docs/valve-seating.png (one file, not a folder); "
                        "tests/test_chain_contacts.py checks its numbers",
}
"""Examples not run here, and why."""


def test_every_example_is_run_or_says_why_not():
    assert not set(QUICK) & set(NOT_RUN)
    assert sorted(QUICK | NOT_RUN) == sorted(p.name for p in EXAMPLES.glob("*.py"))


def _outputs(folder):
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())


@pytest.mark.parametrize("script", [pytest.param(name, marks=pytest.mark.slow) if name in SLOW else name
                                    for name in sorted(QUICK)])
def test_example_runs_in_its_quick_mode(script, tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, str(EXAMPLES / script), *QUICK[script], "--out", str(out)],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    written = _outputs(tmp_path)
    assert written
    for name in written:  # every JSON record it wrote reads back
        if name.endswith(".json"):
            json.loads((tmp_path / name).read_text())
    assert not (tmp_path / "results").exists()  # nothing outside --out
