"""A command's figures drawn in a forked process beside its work (``camjax.cli._drawing``)."""

import os
import subprocess
import sys
import textwrap

import jax.numpy as jnp
import pytest

from camjax.cli import can_fork, main

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the fork is Linux's")


def _run(script: str, tmp_path) -> subprocess.CompletedProcess:
    env = dict(os.environ, CAMJAX_CACHE_DIR="off")
    return subprocess.run([sys.executable, "-c", textwrap.dedent(script)], capture_output=True,
                          text=True, timeout=300, env=env, cwd=tmp_path)


@linux_only
def test_the_executables_forked_figures_equal_those_drawn_in_process(tmp_path):
    # The executable (python -m camjax) forks the drawing; main() in this process, where
    # JAX has started, draws in-process: the same PNG files, byte for byte.
    argv = ["ct", "--n", "1:30:60", "--law", "cycloidal,modified-sine"]
    forked = subprocess.run([sys.executable, "-m", "camjax", *argv, "--out", str(tmp_path / "forked")],
                            capture_output=True, text=True, timeout=600,
                            env=dict(os.environ, CAMJAX_CACHE_DIR="off"))
    assert forked.returncode == 0, forked.stderr
    jnp.zeros(1).block_until_ready()  # JAX's backends started: no fork here
    assert not can_fork()
    assert main([*argv, "--out", str(tmp_path / "here")]) == 0
    names = ["ct_curves.png", "residual_curves.png", "ca_ct.png"]
    assert sorted(p.name for p in (tmp_path / "forked").glob("*.png")) == sorted(names)
    for name in names:
        assert (tmp_path / "forked" / name).read_bytes() == (tmp_path / "here" / name).read_bytes(), name


@linux_only
@pytest.mark.parametrize("failing", [0, 1])
def test_a_figure_that_fails_in_a_drawing_process_fails_the_wait(tmp_path, failing):
    # The drawing process draws the first figure and a fork of it the second: a failure in
    # either comes back to the command's wait, and the other figure is still drawn.
    done = _run(f"""
        import numpy as np
        from camjax.cli import Drawing, Figure, can_fork
        assert can_fork()
        drawing = Drawing(aside=True)
        assert drawing.forked
        good = Figure("design_comparison", "good.png",
                      (np.linspace(1, 2, 5), {{"designed": (np.ones(5), np.ones(5))}}), {{"title": "t"}})
        bad = Figure("no_such_figure", "bad.png")
        drawing.draw([bad, good] if {failing} == 0 else [good, bad])
        try:
            drawing.wait()
        except RuntimeError as error:
            print(error)
        """, tmp_path)
    assert done.returncode == 0, done.stderr
    assert "the figures' drawing process failed" in done.stdout
    assert "AttributeError" in done.stdout and "no_such_figure" in done.stdout
    assert ("a drawing helper failed" in done.stdout) == (failing == 1)
    assert (tmp_path / "good.png").stat().st_size > 1000


@linux_only
def test_a_drawing_process_left_without_figures_ends_with_its_parent(tmp_path):
    # A command that fails after forking (a bad option, a failed solve) never draws: its
    # child sees the pipe close and ends, quietly, rather than outliving it.
    done = _run("""
        import os, time
        from camjax.cli import Drawing
        drawing = Drawing(aside=True)
        os.close(drawing._jobs)  # what the parent's exit does
        print("reported", repr(drawing._child.result()))
        """, tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "reported ''"
    assert done.stderr == ""


@linux_only
def test_a_command_that_ends_without_waiting_ends_its_drawing_process(tmp_path):
    # A command that fails after forking (an error found late, an interrupt) exits without
    # waiting: its exit ends and reaps the drawing process, which does not outlive it.
    done = _run("""
        from camjax.cli import Drawing
        drawing = Drawing(aside=True)
        print(drawing._child.pid)
        raise SystemExit(2)
        """, tmp_path)
    assert done.returncode == 2
    with pytest.raises(ProcessLookupError):
        os.kill(int(done.stdout), 0)


@pytest.mark.slow  # two cold designs (20 s)
@linux_only
def test_the_designed_laws_figure_is_the_same_forked_and_in_process(tmp_path):
    # camjax design draws law.png from the CSV's points, the law's leaves on the host, so
    # that the drawing process runs no JAX: the same file as main() draws in this process.
    argv = ["design", "--objective", "rms-acceleration", "--knots", "6", "--steps", "20", "--quiet"]
    forked = subprocess.run([sys.executable, "-m", "camjax", *argv, "--out", str(tmp_path / "forked")],
                            capture_output=True, text=True, timeout=600,
                            env=dict(os.environ, CAMJAX_CACHE_DIR="off"))
    assert forked.returncode == 0, forked.stderr
    assert main([*argv, "--out", str(tmp_path / "here")]) == 0
    for name in ("law.png", "law.csv"):
        assert (tmp_path / "forked" / name).read_bytes() == (tmp_path / "here" / name).read_bytes(), name
