"""Spec-file sweeps: SCCA grids, chunked resumable runs, two processes on one coordinator."""

import os
import socket
import subprocess
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax import distributed
from camjax.laws import SCCA
from camjax.sweep import (
    ct_curve,
    prepare_sweep,
    resolution_bands,
    sweep_banded,
    sweep_law_stack,
)

ROOT = Path(__file__).resolve().parents[1]
SPEC = """
output = "out"
damping = [0.05]
laws_per_chunk = 2
[period_ratio]
start = 1.0
stop = 4.0
count = 5
[laws]
scca_step = 0.5
scca_face = true
"""  # 6 laws in 3 chunks


def _spec(tmp_path) -> Path:
    path = tmp_path / "spec.toml"
    path.write_text(SPEC)
    return path


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    """The sweep run in one go, in one process."""
    spec = distributed.load_spec(_spec(tmp_path_factory.mktemp("one")))
    distributed.run_sweep(spec, progress=False)
    with np.load(distributed.merge(spec)) as merged:
        return dict(merged)


def test_scca_grid_counts_and_fractions():
    face = distributed.scca_grid(0.01, face=True)
    assert len(face) == 5151  # (m + 1)(m + 2)/2 with m = 100
    assert all(abs(sum(map(float, law.fractions)) - 1.0) < 1e-12 for law in face)
    assert len(distributed.scca_grid(0.05)) == 1770  # C(23, 3) less the all-zero point
    with pytest.raises(ValueError, match="whole number of steps"):
        distributed.scca_grid(0.3)
    with pytest.raises(ValueError, match=r"^scca_step 0.0001 gives 166,766,685,000 SCCA laws; "
                       r"the limit is 1,000,000"):
        distributed.scca_grid(1e-4)  # refused before the laws are built
    assert len(distributed.scca_grid(1e-3, face=True)) == 501_501  # within the limit


@pytest.mark.parametrize("text, words", [
    ('output = "o"\n[period_ratio]\nvalues = [1.0]\n', "needs \\[laws\\]"),
    ('[period_ratio]\nvalues = [1.0]\n[laws]\nnames = ["cycloidal"]\n', "output directory"),
    ('output = "o"\n[laws]\nnames = ["cycloidal"]\n', "period_ratio"),
    ('output = "o"\n[period_ratio]\nvalues = [-1.0]\n[laws]\nnames = ["cycloidal"]\n',
     "positive"),
    ('output = "o"\ndamping = [1.5]\n[period_ratio]\nvalues = [1.0]\n[laws]\n'
     'names = ["cycloidal"]\n', "damping"),
    ('output = "o"\nspeed = 3\n', "unknown spec keys"),
    ('output = "o"\n[period_ratio]\nvalues = [1.0]\n[laws]\nnames = ["nope"]\n', "nope"),
    ('output = "o"\nphase_step = 0\n[period_ratio]\nvalues = [1.0]\n[laws]\n'
     'names = ["cycloidal"]\n', "phase_step"),
    ('output = "o"\nphase_step = 1.6\n[period_ratio]\nvalues = [1.0]\n[laws]\n'
     'names = ["cycloidal"]\n', r"phase_step must be in \(0, 1\.5\]"),
    ('output = "o"\nphase_step = 1e-9\n[period_ratio]\nvalues = [1.0, 30.0]\n[laws]\n'
     'names = ["cycloidal"]\n', r": a rise at period ratio 30 and phase_step 1e-09 needs 188,495,559,232 grid intervals "
     r"\(the limit is 1,048,576\): phase_step at least 0.00018"),
    ('output = "o"\ndamping = []\n[period_ratio]\nvalues = [1.0]\n[laws]\n'
     'names = ["cycloidal"]\n', r": damping must name at least one damping ratio, got \[\]$"),
    ('output = "o"\n[period_ratio]\nstart = 40\nstop = 30\ncount = 5\n[laws]\n'
     'names = ["cycloidal"]\n', ": period_ratio.stop must not be below period_ratio.start, got start 40, stop 30$"),
    ('output = "o"\n[period_ratio]\nvalues = [2.0]\nstart = 1\nstop = 3\ncount = 5\n[laws]\n'
     'names = ["cycloidal"]\n', ": \\[period_ratio\\] takes either values or start/stop/count, not both$"),
])
def test_bad_specs_name_the_problem(tmp_path, text, words):
    path = tmp_path / "spec.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=words):
        distributed.load_spec(path)


@pytest.mark.parametrize("step, resolutions", [(0.5, [128, 192, 256, 320, 384]),
                                                (0.8, [128, 192, 256]), (1.5, [128])])
def test_resolution_bands_meet_the_phase_step(step, resolutions, monkeypatch):
    monkeypatch.setattr(jax, "default_backend", lambda: "cpu")  # bands are the CPU's
    n, _, options = prepare_sweep(np.linspace(1.0, 30.0, 1000))
    bands = resolution_bands(n, options, phase_step=step)
    assert [o.resolution for _, o in bands] == resolutions
    chosen = np.concatenate([c for c, _ in bands])
    np.testing.assert_array_equal(np.sort(chosen), np.arange(n.size))  # each ratio once
    for c, o in bands:  # w h <= step at every ratio, and the next smaller grid would not do
        assert np.all(2 * np.pi * n[c] / o.resolution <= step)
        assert o.resolution == 128 or np.any(2 * np.pi * n[c] / (o.resolution - 64) > step)
    _, _, tsit5 = prepare_sweep(n, method="tsit5")
    assert len(resolution_bands(n, tsit5)) == 1  # grids of the exact path only


def test_off_the_cpu_one_band_takes_the_finest_grid(monkeypatch):
    """On a GPU every ratio takes the largest band's grid (one program to compile), so each
    still meets the phase step."""
    n, _, options = prepare_sweep(np.linspace(1.0, 30.0, 1000))
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    [(chosen, band)] = resolution_bands(n, options, phase_step=0.5)
    np.testing.assert_array_equal(chosen, np.arange(n.size))
    assert band.resolution == 384 and np.all(2 * np.pi * n / band.resolution <= 0.5)


@pytest.mark.slow
def test_banded_sweep_within_tolerance_of_ct_curve():
    """Slow: a banded stacked sweep at two phase steps compiles one program per band and step, and ``ct_curve`` one per law family."""
    laws = [SCCA(0.5, 0.0, 0.5), SCCA(0.99, 0.0, 0.01), SCCA(0.0, 1.0, 0.0)]
    n, template, options = prepare_sweep(np.linspace(1.0, 30.0, 60))
    stack = jax.tree.map(lambda *x: jnp.stack(x), *laws)
    for step, tolerance in ((0.5, 1e-9), (0.8, 1e-8)):
        metrics, _ = sweep_banded(sweep_law_stack, stack, n, template, options,
                                  phase_step=step)
        for i, law in enumerate(laws):
            curve = ct_curve(law, n)
            np.testing.assert_allclose(metrics.ct[i], curve.ct, rtol=tolerance)
            np.testing.assert_allclose(metrics.residual[i], curve.residual, atol=1e-11)


def test_a_spec_of_laws_of_several_kinds_sweeps_at_its_phase_step(tmp_path):
    path = tmp_path / "spec.toml"
    path.write_text('output = "o"\nphase_step = 0.5\n[period_ratio]\nvalues = [2.0, 7.5, 30.0]\n'
                    '[laws]\nnames = ["cycloidal", "poly345"]\n')
    spec = distributed.load_spec(path)
    distributed.run_sweep(spec, progress=False)
    with np.load(distributed.merge(spec)) as merged:
        ct = merged["ct"][0]
    finer = camjax.ct_curves(["cycloidal", "poly345"], spec.period_ratio, resolution=384)
    default = camjax.ct_curves(["cycloidal", "poly345"], spec.period_ratio)
    for i, name in enumerate(("cycloidal", "poly345")):  # the finer grid's numbers, exactly
        np.testing.assert_array_equal(ct[i], finer[name].ct)
        np.testing.assert_allclose(ct[i], default[name].ct, rtol=1e-10)
    assert not all(np.array_equal(ct[i], default[name].ct)
                   for i, name in enumerate(("cycloidal", "poly345")))


def test_merged_sweep_matches_ct_curve(uninterrupted):
    names = list(uninterrupted["law"])
    assert uninterrupted["ct"].shape == (1, 6, 5)
    curve = ct_curve(SCCA(0.5, 0.0, 0.5), uninterrupted["period_ratio"], damping=0.05)
    i = names.index(SCCA(0.5, 0.0, 0.5).name)
    np.testing.assert_allclose(uninterrupted["ct"][0, i], curve.ct, rtol=0, atol=1e-12)
    np.testing.assert_allclose(uninterrupted["residual"][0, i], curve.residual, atol=1e-12)
    assert uninterrupted["ca"][i] == pytest.approx(2 * np.pi)  # cycloidal's Ca


def test_resume_recomputes_only_missing_chunks(tmp_path, uninterrupted):
    """A run that stopped after its first chunk (here: process 0 of 3, which takes only
    that one) leaves the others missing; the next run computes those and no other."""
    spec = distributed.load_spec(_spec(tmp_path))
    assert distributed.run_sweep(spec, process_id=0, num_processes=3, progress=False) == spec.chunks()[:1]
    assert distributed.missing_chunks(spec) == spec.chunks()[1:]
    assert not list((spec.output / "chunks").glob(".*tmp"))  # nothing half-written left
    with pytest.raises(ValueError, match="2 of 3 chunks are missing"):
        distributed.merge(spec)

    done = distributed.run_sweep(spec, progress=False)
    assert done == spec.chunks()[1:]
    assert distributed.run_sweep(spec, progress=False) == []  # nothing left to do
    with np.load(distributed.merge(spec)) as merged:
        for key in ("ct", "residual", "peak_in_motion", "ca", "period_ratio"):
            np.testing.assert_array_equal(merged[key], uninterrupted[key])


def test_changed_spec_refuses_old_output(tmp_path, uninterrupted):
    path = _spec(tmp_path)
    spec = distributed.load_spec(path)
    chunks = len(spec.chunks())  # a process with no chunk to compute claims the output only
    assert distributed.run_sweep(spec, process_id=chunks, num_processes=chunks + 1, progress=False) == []
    path.write_text(SPEC.replace("count = 5", "count = 6"))
    with pytest.raises(ValueError, match="different sweep"):
        distributed.run_sweep(distributed.load_spec(path), progress=False)


def test_two_processes_merge_to_the_one_process_result(tmp_path, uninterrupted):
    path = _spec(tmp_path)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "JAX_PLATFORMS": "cpu"}
    env.pop("XLA_FLAGS", None)
    procs = [
        subprocess.Popen(
            [sys.executable, "-m", "camjax", "sweep", str(path), "--coordinator",
             f"127.0.0.1:{port}", "--num-processes", "2", "--process-id", str(i)],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )
        for i in range(2)
    ]
    try:
        logs = [p.communicate(timeout=300) for p in procs]
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
    assert [p.returncode for p in procs] == [0, 0], logs
    with np.load(tmp_path / "out" / "sweep.npz") as merged:
        for key in ("ct", "residual", "peak_in_motion", "ca"):
            np.testing.assert_allclose(merged[key], uninterrupted[key], rtol=0, atol=1e-12)
    assert "wrote" in logs[0][1]


def test_cli_one_process_sweeps_on_a_device_per_core(tmp_path, uninterrupted):
    path = _spec(tmp_path)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "JAX_PLATFORMS": "cpu"}
    env.pop("XLA_FLAGS", None)
    done = subprocess.run([sys.executable, "-m", "camjax", "sweep", str(path)], env=env,
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    from camjax.sharding import available_cores

    expected = min(64, 1 << (available_cores().bit_length() - 1))
    assert f"on {expected} local device(s)" in done.stderr
    with np.load(tmp_path / "out" / "sweep.npz") as merged:
        for key in ("ct", "residual", "peak_in_motion", "ca"):
            np.testing.assert_allclose(merged[key], uninterrupted[key], rtol=0, atol=1e-12)


def test_cli_bad_spec_is_one_line_exit_2(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "JAX_PLATFORMS": "cpu"}
    bad = tmp_path / "bad.toml"
    bad.write_text("output = [")
    done = subprocess.run([sys.executable, "-m", "camjax", "sweep", str(bad)], env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.startswith("camjax sweep: error:") and done.stderr.count("\n") == 1


def test_cli_partial_distributed_arguments_exit_2(tmp_path, capsys):
    from camjax.cli import main

    path = _spec(tmp_path)
    assert main(["sweep", str(path), "--coordinator", "127.0.0.1:1"]) == 2
    assert "go together" in capsys.readouterr().err
    args = ["--coordinator", "127.0.0.1:1", "--num-processes", "2", "--process-id", "2"]
    assert main(["sweep", str(path), *args]) == 2
    assert "--process-id must be in 0..1" in capsys.readouterr().err
