"""Sharded sweeps equal single-device ones (4 host devices from ``use_cpu_cores``, in a
subprocess): Ct curves, law stacks, the design's band evaluation and the program speed
sweep."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import equinox as eqx
import jax
import numpy as np
import pytest

import camjax
from camjax.sharding import (
    available_cores,
    batch_size,
    resolve_devices,
    shard_batch,
    use_cpu_cores,
)

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = textwrap.dedent(
    """
    import camjax
    from camjax.sharding import use_cpu_cores
    assert use_cpu_cores(4) == 4  # before JAX starts
    import jax
    from helpers import COMPILED_RTOL
    import numpy as np
    from camjax import laws
    from camjax.laws import SCCA
    from camjax.law_design import peak_loads
    from camjax.metrics import PEAK_TOLERANCE
    from camjax.program import Follower, Program, Segment, SteadyState
    from camjax.sweep import ct_curve, ct_curves

    assert jax.local_device_count() == 4, jax.devices()

    def worst(a, b, first=0):  # b against a's entries from first on (b may be a's tail)
        return max(float(np.max(np.abs(getattr(a, k)[first:] - getattr(b, k))))
                   for k in ("ct", "residual", "peak_in_motion"))

    law = laws.get("modified-sine")
    errors = {}
    # Batches that do not / do divide by the device count: the tail of one single-device
    # curve (the same largest ratio, hence the same grid), so that both sharded batches
    # pad to one compiled program.
    n = np.linspace(1.0, 6.0, 8)
    single = ct_curve(law, n, devices=1)
    for first in (1, 0):
        errors[f"exact-{8 - first}"] = worst(single, ct_curve(law, n[first:]), first)
    n = np.linspace(1.5, 4.0, 4)
    options = dict(method="tsit5", rtol=1e-8, atol=1e-10)
    single_tsit5 = ct_curve(law, n, devices=1, **options)
    for first in (1, 0):
        many = ct_curve(law, n[first:], devices=4, **options)
        errors[f"tsit5-{4 - first}"] = worst(single_tsit5, many, first)
    # 9 laws: one stacked call (more than STACK_FROM), on 4 devices
    family = [SCCA(a, 0.0, 1.0 - a) for a in np.linspace(0.1, 0.9, 9)]
    n = np.linspace(1.0, 6.0, 6)
    one, many = ct_curves(family, n, devices=1), ct_curves(family, n, devices=4)
    errors["scca-stack"] = max(worst(one[k], many[k]) for k in one)
    errors["scca-stack-ca"] = max(abs(many[law.name].ca - float(law.Ca)) for law in family)
    # the design's band evaluation (Ca*Ct over a band: 7 ratios on 4 devices) against the
    # single-device curve (the same exact path through ct_curve)
    loads = peak_loads(law, single.period_ratio[1:], devices=4)
    errors["peak-loads"] = float(np.max(np.abs(loads - single.ca_ct[1:]) / single.ca_ct[1:]))
    # the program speed sweep: 70 speeds in blocks of 32, each split over the 4 devices
    cam = Program("two-cycloids", (Segment(100, 20.0, law), Segment(80),
                                   Segment(100, -20.0, law), Segment(80)),
                  Follower(kind="translating-roller", mass_kg=1.5, stiffness_n_per_mm=2000.0,
                           damping_ratio=0.05, spring_rate_n_per_mm=10.0, preload_n=300.0,
                           base_radius_mm=40.0, roller_radius_mm=12.0))
    solo, split = SteadyState(cam, 300.0, devices=1), SteadyState(cam, 300.0)
    assert len(split.devices) == 4
    rpm = np.linspace(300.0, 900.0, 70)
    a, b = solo.summary(rpm), split.summary(rpm)
    errors["program"] = max(float(np.max(np.abs(x - y) / np.abs(x).max()))
                            for x, y in zip([*a.values.values(), a.residual_vibration_mm],
                                            [*b.values.values(), b.residual_vibration_mm]))
    print("ERRORS", errors)
    assert all(e <= COMPILED_RTOL for e in errors.values()), errors
    # The sharded stack equals each law alone (not just the same program twice): another
    # compiled program on the same grid, so Ct and the peak agree to the peak search's
    # PEAK_TOLERANCE (it leaves alone a crest within it of the best), R (no search) to
    # rounding.
    alone, stacked = ct_curve(family[1], n, devices=1), many[family[1].name]
    for key, tolerance in (("ct", 2 * PEAK_TOLERANCE), ("peak_in_motion", 2 * PEAK_TOLERANCE),
                           ("residual", COMPILED_RTOL)):
        a, b = getattr(alone, key), getattr(stacked, key)
        assert np.max(np.abs(a - b) / np.abs(a)) <= tolerance, (key, a, b)
    """
)


def test_sharded_sweeps_equal_single_device():
    env = {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{ROOT / 'tests'}", "JAX_PLATFORMS": "cpu"}
    env.pop("XLA_FLAGS", None)
    done = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-4000:]
    assert "ERRORS" in done.stdout


def test_use_cpu_cores_checks_and_defers_to_the_users_count(monkeypatch):
    started = len(jax.devices("cpu"))
    assert use_cpu_cores(started) == started  # what JAX already has: nothing to change
    monkeypatch.setenv("XLA_FLAGS", "--xla_force_host_platform_device_count=7")
    assert use_cpu_cores(started) == started  # started: the devices JAX has, not the flag's
    with pytest.raises(RuntimeError, match="before any JAX computation"):
        use_cpu_cores(started + 1)
    for bad in (0, -2, 1.5, "2", True):
        with pytest.raises(ValueError, match="count must be a positive integer"):
            use_cpu_cores(bad)
    assert use_cpu_cores(np.int64(started)) == started
    # Before JAX starts, a count the user set wins (a fresh process for each).
    script = ("from camjax.sharding import use_cpu_cores; n = use_cpu_cores(2); "
              "import jax; print(n, jax.local_device_count())")
    for variable, value, expected in (("XLA_FLAGS", "--xla_force_host_platform_device_count=3", "3 3"),
                                      ("JAX_NUM_CPU_DEVICES", "1", "1 1"), (None, None, "2 2")):
        env = {**os.environ, "PYTHONPATH": str(ROOT), "JAX_PLATFORMS": "cpu"}
        env.pop("XLA_FLAGS", None)
        env.pop("JAX_NUM_CPU_DEVICES", None)
        if variable:
            env[variable] = value
        done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                              text=True, timeout=120)
        assert done.stdout.split() == expected.split(), done.stderr[-2000:]


def test_available_cores_keep_within_a_cgroup_quota(tmp_path):
    cores = len(os.sched_getaffinity(0))
    quota = tmp_path / "cpu.max"
    quota.write_text("150000 100000\n")  # 1.5 CPUs
    assert available_cores(quota) == min(cores, 2)
    quota.write_text("max 100000\n")
    assert available_cores(quota) == cores
    assert available_cores(tmp_path / "absent") == cores


def test_resolve_devices():
    local = jax.local_devices()
    assert resolve_devices(None) == local
    assert resolve_devices(1) == local[:1]
    assert resolve_devices(local[:1]) == local[:1]
    for bad, words in ((0, "between 1"), (len(local) + 1, "between 1"), ([], "at least one"),
                       ("cpu", "device count"), (["cpu"], "jax.Device")):
        with pytest.raises(ValueError, match=words):
            resolve_devices(bad)


def test_shard_batch_one_device_and_batch_checks():
    x = np.arange(5.0)
    np.testing.assert_array_equal(shard_batch(lambda v, k: v * k, x, 3.0, devices=1), 3 * x)
    assert batch_size({"a": np.zeros((4, 2)), "b": np.ones(4)}) == 4
    with pytest.raises(ValueError, match="common leading axis"):
        batch_size({"a": np.zeros(4), "b": np.ones(3)})


def test_sweeps_compile_with_the_cpu_options_only_at_the_top_level():
    """``sweep_jit``: on CPU a sweep's program compiles with its options'
    ``sweep.cpu_compiler_options`` (``CPU_COMPILER_OPTIONS`` by default, none with
    ``SweepOptions.run_once``; XLA refuses options on a nested jit, so a call inside a
    caller's trace takes none); the options change no number beyond the peak search's
    tolerance (``PEAK_TOLERANCE``, 1e-11 relative: rounding may settle a crest in another
    interval; 7e-13 measured at n = 30)."""
    import dataclasses

    from camjax import sharding
    from camjax.sweep import prepare_sweep, sweep_program

    n, template, options = prepare_sweep(np.linspace(1.0, 30.0, 200), damping=0.05)
    law = template.sweep_law(camjax.laws.get("modified-sine"), options)
    args = (law, template, jax.numpy.asarray(n), options)
    once = dataclasses.replace(options, sweep=sharding.SweepOptions.run_once())
    on_cpu = jax.default_backend() == "cpu"
    chosen = sharding.CPU_COMPILER_OPTIONS if on_cpu else ()
    assert options.sweep == sharding.SweepOptions() and options.sweep.cpu_compiler_options == (
        sharding.CPU_COMPILER_OPTIONS)
    assert sweep_program.compiler_options(*args) == chosen
    assert sweep_program.compiler_options(*args[:3], options=options) == chosen
    assert sweep_program.compiler_options(*args[:3], once) == ()
    plain = eqx.filter_jit(sweep_program.__wrapped__)  # XLA's defaults
    # Split over devices, a sweep compiles with the same options; any other function
    # (a program's speed batch) with XLA's defaults, as it runs on one device.
    split = (jax.numpy.asarray(n), args, 2)
    assert sharding.split_program.compiler_options(sweep_program, *split) == chosen
    assert sharding.split_program.compiler_options(sweep_program, split[0], (*args[:3], once),
                                                   2) == ()
    assert sharding.split_program.compiler_options(plain, *split) == ()
    picked = []
    jax.jit(lambda r: picked.append(sweep_program.compiler_options(*args)) or r)(n)
    assert picked == [()]
    if on_cpu:
        assert sharding.CPU_COMPILER_OPTIONS == (("xla_cpu_prefer_vector_width", 512),)
    run_once = sweep_program(*args[:3], once)[0]
    np.testing.assert_allclose(run_once.ct, plain(*args)[0].ct, rtol=1e-11, atol=0)
    with_options, without = sweep_program(*args)[0], plain(*args)[0]
    for field in ("ct", "residual", "peak_in_motion"):
        np.testing.assert_allclose(getattr(with_options, field), getattr(without, field),
                                   rtol=1e-11, atol=0)
    # Inside a caller's jit the program is inlined, options or not.
    inside = jax.jit(lambda r: sweep_program(law, template, r, options)[0].ct)(jax.numpy.asarray(n))
    np.testing.assert_allclose(inside, with_options.ct, rtol=1e-11)
