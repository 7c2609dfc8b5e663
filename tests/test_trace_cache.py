"""Traced programs kept on disk beside the compilation cache: a second process reads them
back and prints the same numbers as a process without any cache; a damaged file is traced
afresh and written again."""

import json
import os
import subprocess
import sys
from pathlib import Path

COMMAND = [sys.executable, "-m", "camjax", "program", "feed", "--rpm", "400,700", "--format", "json"]


def _run(cache) -> dict:
    env = {**os.environ, "CAMJAX_CACHE_DIR": str(cache)}
    out = subprocess.run(COMMAND, env=env, capture_output=True, text=True, timeout=300, check=True)
    return json.loads(out.stdout)


def test_kept_traces_give_the_numbers_of_a_run_without_them(tmp_path):
    cache = tmp_path / "cache"
    reference = _run("off")
    first = _run(cache)
    traces = sorted((cache / "traces").glob("*/*.bin"))
    assert any(p.name.startswith("program-cycles-") for p in traces)
    assert any(p.name.startswith("law-evaluate-") for p in traces)
    second = _run(cache)  # reads the traces back
    assert sorted((cache / "traces").glob("*/*.bin")) == traces  # found again: nothing new written
    for path in traces:  # damaged files: traced afresh, written whole again
        path.write_bytes(path.read_bytes()[:100])
    third = _run(cache)
    assert all(Path(p).stat().st_size > 100 for p in traces)
    assert first == reference and second == reference and third == reference
