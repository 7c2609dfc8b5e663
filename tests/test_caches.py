"""The caches' one setting is explicit (the command passes it, never writes the
environment), and the studies' in-process cache is keyed by a law's values and bounded."""

import os
import threading

import numpy as np
import pytest

from camjax import caches


def test_a_block_s_setting_wins_over_the_environment_and_ends_with_it(monkeypatch, tmp_path):
    monkeypatch.setenv(caches.SETTING, "off")
    assert caches.configured_dir() is None and not caches.traces_kept()
    with caches.using_cache_dir(tmp_path):
        assert caches.configured_dir() == tmp_path and caches.traces_kept()
        with caches.using_cache_dir(None):
            assert not caches.traces_kept()
        assert caches.configured_dir() == tmp_path
    assert caches.configured_dir() is None and os.environ[caches.SETTING] == "off"


def test_work_handed_to_a_thread_carries_the_setting(tmp_path):
    seen = {}

    def look(key):
        seen[key] = caches.configured_dir()

    with caches.using_cache_dir(tmp_path):
        plain = threading.Thread(target=look, args=("plain",))
        carried = threading.Thread(target=caches.carried(look), args=("carried",))
        for thread in (plain, carried):
            thread.start()
            thread.join()
    assert seen["carried"] == tmp_path
    assert seen["plain"] != tmp_path  # a thread starts without its creator's context


def test_the_command_gives_its_run_the_setting_and_leaves_the_environment_alone(monkeypatch, tmp_path):
    """Run in-process (a test worker, a notebook), the command's cache directory holds for
    its run alone: the environment is not written, so later library calls are as before."""
    import jax

    import camjax.cli.laws as laws_command
    from camjax.cli import main

    monkeypatch.delenv(caches.SETTING, raising=False)
    before = jax.config.jax_compilation_cache_dir
    jax.config.update("jax_compilation_cache_dir", str(tmp_path))  # the command uses it as it is
    seen = []
    monkeypatch.setattr(laws_command, "run", lambda args: seen.append(caches.configured_dir()) or 0)
    try:
        assert main(["laws"]) == 0
    finally:
        jax.config.update("jax_compilation_cache_dir", before)
    assert seen == [tmp_path]
    assert caches.SETTING not in os.environ and caches.configured_dir() is None
    monkeypatch.setenv(caches.SETTING, "off")  # off: the command's run is off too
    seen.clear()
    assert main(["laws"]) == 0
    assert seen == [None]


def test_the_scipy_reference_compiles_each_law_s_own_acceleration():
    """Two B-spline laws share a name (``bspline:6``) but not their values: each reference
    is its own law's, against the exact path (it was keyed by the name: the second law
    got the first one's acceleration)."""
    import camjax
    from camjax import studies
    from camjax.laws import BSplineLaw

    plain, shaped = BSplineLaw(np.zeros(6)), BSplineLaw(np.array([0.3, -0.2, 0.1, 0.2, -0.3, 0.1]))
    assert plain.name == shaped.name
    for law in (plain, shaped):
        ct, residual, _ = studies.scipy_reference(law, 3.0, "DOP853", 1e-11)
        curve = camjax.ct_curve(law, [3.0])
        assert ct == pytest.approx(float(curve.ct[0]), rel=1e-7)
        assert residual == pytest.approx(float(curve.residual[0]), rel=1e-6, abs=1e-9)


def test_the_studies_cache_keeps_a_bounded_number_of_laws():
    """The last ``COMPILED_ACCELERATIONS_KEPT`` laws are kept (the same compiled function
    again), an older one is dropped (compiled afresh).  jit compiles when called: cheap."""
    from camjax import studies
    from camjax.laws import BSplineLaw

    first = BSplineLaw(np.full(6, -0.01))
    kept = studies.compiled_acceleration(first)
    assert studies.compiled_acceleration(BSplineLaw(np.full(6, -0.01))) is kept  # by value
    others = [BSplineLaw(np.full(6, 0.01 * i)) for i in range(studies.COMPILED_ACCELERATIONS_KEPT)]
    last = [studies.compiled_acceleration(law) for law in others][-1]
    assert studies.compiled_acceleration(others[-1]) is last
    assert studies.compiled_acceleration(first) is not kept


def test_a_crowded_process_lets_its_compiled_programs_go():
    """Each compiled program holds memory maps; past the given share of the system's limit
    JAX's caches are cleared and the maps come back; a function used again compiles again
    and gives the same numbers.  The count is checked against maps the test adds itself."""
    import mmap

    import jax
    import jax.numpy as jnp

    counted = caches.memory_maps()
    if counted is None:
        pytest.skip("this system does not count a process's memory maps")
    before, limit = counted
    assert limit > before > 0
    regions = [mmap.mmap(-1, 2 * mmap.PAGESIZE) for _ in range(200)]
    assert caches.memory_maps()[0] >= before + 100  # separate anonymous regions, counted
    del regions

    programs = [jax.jit(lambda x, k=k: jnp.sin(x) ** k + jnp.cumsum(x)) for k in range(1, 21)]
    x = jnp.linspace(0.0, 1.0, 7)
    first = [np.asarray(f(x)) for f in programs]
    compiled = caches.memory_maps()[0]
    assert not caches.relieve_memory_maps(fraction=1.0)  # a process never holds more than the limit
    assert all(f._cache_size() == 1 for f in programs)

    assert caches.relieve_memory_maps(fraction=0.0)  # any count is crowded at 0
    assert all(f._cache_size() == 0 for f in programs)
    let_go = compiled - caches.memory_maps()[0]
    assert let_go > 20, f"20 programs let go gave back only {let_go} maps"
    np.testing.assert_array_equal([np.asarray(f(x)) for f in programs], first)
    assert all(f._cache_size() == 1 for f in programs)
