"""Traced programs kept on disk beside the compilation cache: a second process reads them
back and prints the same numbers as a process without any cache; a damaged file is traced
afresh and written again."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import assert_same_numbers

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
    for run in (first, second, third):
        assert_same_numbers(run, reference)


def _run_file(path, cache) -> dict:
    env = {**os.environ, "CAMJAX_CACHE_DIR": str(cache)}
    command = [sys.executable, "-m", "camjax", "program", str(path), "--rpm", "400,700", "--format", "json"]
    out = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300, check=True)
    return json.loads(out.stdout)


def test_the_key_tells_two_programs_of_one_shape_apart(tmp_path):
    """Two programs of one shape with other numbers (lift, preload, stiffness), one cache:
    the second reads the first's traces where they fit and still gives its own numbers,
    each equal to its run without the cache."""
    import camjax.program as cp

    feed = Path(cp.example_path("feed")).read_text()
    other = (feed.replace("lift_mm = 18", "lift_mm = 21").replace("lift_mm = -23", "lift_mm = -26")
             .replace("preload_n = 300", "preload_n = 420").replace("stiffness_n_per_mm = 2000",
                                                                    "stiffness_n_per_mm = 2300"))
    assert other != feed
    first, second = tmp_path / "feed.toml", tmp_path / "other.toml"
    first.write_text(feed)
    second.write_text(other)
    cache = tmp_path / "cache"
    cached = [_run_file(first, cache), _run_file(second, cache), _run_file(first, cache)]
    reference = [_run_file(first, "off"), _run_file(second, "off")]
    assert_same_numbers(cached[0], reference[0])
    assert_same_numbers(cached[2], reference[0])
    assert_same_numbers(cached[1], reference[1])
    assert cached[1]["speeds"][0]["min_contact_force_n"] != pytest.approx(
        cached[0]["speeds"][0]["min_contact_force_n"], rel=1e-3)  # the numbers of another program


def test_old_versions_are_pruned(tmp_path):
    from camjax import caches

    for age in range(6):
        folder = tmp_path / f"version{age}"
        folder.mkdir()
        os.utime(folder, (1e9 - age, 1e9 - age))  # version0 the newest
    removed = caches.prune_traces(tmp_path, keep=caches.KEPT_VERSIONS)
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"version{i}" for i in range(caches.KEPT_VERSIONS)]
    assert len(removed) == 6 - caches.KEPT_VERSIONS


def test_a_program_that_cannot_be_kept_is_marked_and_an_unexpected_failure_reported_once(tmp_path, monkeypatch):
    """A host callback (jax.export's known limit) is marked and traced without a word; any
    other failure to export is a warning naming the program, once (then the marker)."""
    import warnings

    import jax
    import jax.numpy as jnp
    import numpy as np
    import pytest

    from camjax import caches

    monkeypatch.setenv("CAMJAX_CACHE_DIR", str(tmp_path))

    def with_callback(x):  # a host callback: jax.export refuses it
        y = jax.pure_callback(lambda v: np.asarray(v) * 2.0, jax.ShapeDtypeStruct(x.shape, x.dtype), x)
        return y + 1.0

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        jitted = caches.exported_jit(with_callback, "callback-test")
        assert float(jitted(jnp.asarray(1.5))) == 4.0
        again = caches.exported_jit(with_callback, "callback-test")  # a new process's view: the marker
        assert float(again(jnp.asarray(0.5))) == 2.0
    assert list(tmp_path.rglob("callback-test-*.plain"))

    def refused(*args, **kwargs):
        raise ValueError("an export failure nobody expected")

    monkeypatch.setattr(jax.export, "export", refused)  # the module camjax keeps traces with
    broken = caches.exported_jit(lambda x: 3.0 * x, "broken-test")
    with pytest.warns(RuntimeWarning, match="'broken-test' cannot be kept on disk .ValueError: an export failure"):
        assert float(broken(jnp.asarray(2.0))) == 6.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert float(broken(jnp.asarray(2.5))) == 7.5  # remembered: no second warning
        assert float(caches.exported_jit(lambda x: 3.0 * x, "broken-test")(jnp.asarray(1.0))) == 3.0


def test_the_memo_is_bounded_and_the_setting_is_explicit(tmp_path, monkeypatch):
    import jax.numpy as jnp

    from camjax import caches

    monkeypatch.setenv("CAMJAX_CACHE_DIR", "off")
    assert not caches.traces_kept()
    monkeypatch.setenv("CAMJAX_CACHE_DIR", str(tmp_path))
    assert caches.traces_kept()
    square = caches.exported_jit(lambda x: x * x, "square-test", memo_size=2)
    for n in range(1, 5):
        assert float(square(jnp.full(n, 3.0)).sum()) == 9.0 * n
    assert len(square.loaded) == 2
    assert len(list((tmp_path / "traces").glob("*/square-test-*.bin"))) == 4
