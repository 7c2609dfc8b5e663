"""The engine's chunked batches: chunking changes nothing but speed, on any backend's sizes."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import COMPILED_ATOL, COMPILED_RTOL

import camjax
from camjax import distributed
from camjax.sdof import (
    ACCELERATOR_CHUNK_NODES,
    ACCELERATOR_STACK_EVALUATIONS,
    CHUNK_NODES,
    chunk_nodes,
    chunked_map,
    map_in_chunks,
    stack_laws,
)
from camjax.sharding import SweepOptions


def _member(tree):
    x, y = tree
    return {"sum": x.sum() + y, "scaled": 2.0 * x}


@pytest.mark.parametrize("members", [1, 3, 4, 10, 50])
def test_map_in_chunks_equals_one_vmap(members):
    """Ten members in chunks of 1 (a plain map), 3 (padded to 12 and cut), 4, 10 and more
    than there are: every leaf equals one vmap over the whole batch."""
    rng = np.random.default_rng(members)
    batch = (jnp.asarray(rng.normal(size=(10, 5))), jnp.asarray(rng.normal(size=10)))
    expected = jax.vmap(_member)(batch)
    got = jax.jit(lambda b: map_in_chunks(_member, b, members))(batch)
    for key in expected:
        assert got[key].shape == expected[key].shape
        np.testing.assert_allclose(got[key], expected[key], rtol=COMPILED_RTOL, atol=COMPILED_ATOL)


def test_chunked_map_sizes_chunks_by_nodes():
    """Chunks of ``chunk // nodes_per_member`` members: the same values whatever the chunk."""
    x = jnp.linspace(0.0, 1.0, 37)
    one = lambda v: jnp.sin(v) * v  # noqa: E731
    for chunk in (1, 64, 1000, 10**6):
        np.testing.assert_allclose(chunked_map(one, x, 16, chunk=chunk), jax.vmap(one)(x), rtol=COMPILED_RTOL)


def test_sizes_by_backend(monkeypatch):
    monkeypatch.setattr(jax, "default_backend", lambda: "cpu")
    assert chunk_nodes() == CHUNK_NODES and stack_laws(1000, 192) == 1
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    assert chunk_nodes() == ACCELERATOR_CHUNK_NODES
    assert stack_laws(1000, 192) == ACCELERATOR_STACK_EVALUATIONS // 1000 == 65
    assert stack_laws(10**6) == 1
    # a fine grid bounds the laws at once by nodes: 2**24 // (1000 * 4096)
    assert stack_laws(1000, 4096) == 4 and stack_laws(100, 2**20) == 1
    # A device's own sizes, passed in: min(1000 // 100, 2**14 // (100 * 4)) laws at once.
    tuned = SweepOptions(accelerator_chunk_nodes=2**14, accelerator_stack_evaluations=1000)
    assert chunk_nodes(tuned) == 2**14 and stack_laws(100, 4, tuned) == 10
    assert stack_laws(100, 64, tuned) == 2
    monkeypatch.setattr(jax, "default_backend", lambda: "cpu")
    assert chunk_nodes(tuned) == CHUNK_NODES and stack_laws(100, 4, tuned) == 1


def test_a_model_that_sweeps_in_turn_takes_its_laws_in_turn(monkeypatch):
    """Off the CPU a stack of the exact path's laws is vmapped, but a model that solves its
    ratios one after another (friction's events) keeps its laws in turn too."""
    from camjax.sweep import laws_at_once, prepare_sweep

    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    _, exact, options = prepare_sweep(np.linspace(1.0, 30.0, 1000))
    assert laws_at_once(exact, options, 1000) == 65
    friction = camjax.CoulombFriction(1.0, 0.05)
    _, template, options = prepare_sweep([1.0, 2.0], model=friction)
    assert template.sweeps_in_turn(options) and laws_at_once(template, options, 2) == 1


def test_map_in_chunks_refuses_a_ragged_batch():
    with pytest.raises(ValueError, match="same length"):
        map_in_chunks(_member, (jnp.zeros((3, 2)), jnp.zeros(4)), 2)
    with pytest.raises(ValueError, match="leading axis"):
        map_in_chunks(_member, (jnp.zeros(()), jnp.zeros(4)), 2)


def test_accelerator_sizes_give_the_cpu_curves(monkeypatch):
    """The GPU's sizing (one chunk for a whole curve, a stack's laws vmapped together), run
    on the CPU: a single curve and a stack of 12 SCCA laws (over the stacking threshold)
    equal the CPU-sized sweep to rounding and the peak search's tolerance (an undamped
    plateau's equal crests may settle on another crest, whose refinement differs by about
    1e-11 at ``w h`` near ``MAX_PHASE_STEP``)."""
    n = np.linspace(0.5, 30.0, 300)
    face = distributed.scca_grid(0.1, face=True)[:12]
    laws = {law.name: law for law in face}
    single = camjax.ct_curve("modified-sine", n, damping=0.05)
    stack = camjax.ct_curves(laws, n)
    jax.clear_caches()
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    sweep = SweepOptions(accelerator_stack_evaluations=5 * n.size)  # 3 chunks of 5, padded
    try:
        assert stack_laws(n.size, 1, sweep) == 5
        single_gpu = camjax.ct_curve("modified-sine", n, damping=0.05, sweep=sweep)
        stack_gpu = camjax.ct_curves(laws, n, sweep=sweep)
    finally:
        jax.clear_caches()  # no program sized for another backend outlives the test
    for a, b in [(single, single_gpu), *((stack[k], stack_gpu[k]) for k in laws)]:
        for metric in ("ct", "residual", "peak_in_motion"):
            np.testing.assert_allclose(getattr(b, metric), getattr(a, metric), rtol=1e-11, atol=1e-11)
        assert b.ca == a.ca


def test_a_curves_result_codes_stay_on_the_host():
    """A curve's result codes are a NumPy array: no device transfer per curve (a wait on a
    GPU, once for each of a stack's laws)."""
    curve = camjax.ct_curve("cycloidal", np.linspace(1.0, 5.0, 7))
    assert isinstance(curve.result._value, np.ndarray)
    assert curve.result_names == ["successful"] * 7 and not curve.failed.any()


def test_a_stack_of_host_laws_stays_on_the_host():
    """``stack_of``: NumPy leaves where every law holds them on the host (one transfer when
    swept), JAX where any law holds a device array; the values either way."""
    from camjax.laws import SCCA
    from camjax.sweep import stack_of

    host = [SCCA(0.5, 0.0, 0.5), SCCA(1, 0, 0)]
    stacked = stack_of(host)
    assert all(isinstance(x, np.ndarray) for x in jax.tree.leaves(stacked))
    mixed = stack_of([host[0], SCCA(*map(jnp.asarray, (1.0, 0.0, 0.0)))])
    assert all(isinstance(x, jax.Array) for x in jax.tree.leaves(mixed))
    for s in (stacked, mixed):
        np.testing.assert_array_equal(s.sine, [0.5, 1.0])
        np.testing.assert_array_equal(s.cosine, [0.5, 0.0])


def test_sweep_options_are_checked_values():
    """Sizes positive integers, compiler options (name, value) pairs, the ``sweep`` option
    a ``SweepOptions``: each a one-line ``ValueError`` naming the field; equal options are
    one static value (one compiled program)."""
    for bad in (0, -4, 2.5, True):
        with pytest.raises(ValueError, match="accelerator_chunk_nodes must be a positive integer"):
            SweepOptions(accelerator_chunk_nodes=bad)
        with pytest.raises(ValueError, match="accelerator_stack_evaluations must be a positive"):
            SweepOptions(accelerator_stack_evaluations=bad)
    with pytest.raises(ValueError, match="cpu_compiler_options must be"):
        SweepOptions(cpu_compiler_options=("xla_cpu_prefer_vector_width",))
    with pytest.raises(ValueError, match="sweep must be a camjax.sharding.SweepOptions"):
        camjax.ct_curve("cycloidal", [1.0], sweep={"accelerator_chunk_nodes": 4})
    assert SweepOptions(accelerator_chunk_nodes=np.int64(64)) == SweepOptions(accelerator_chunk_nodes=64)
    assert hash(SweepOptions()) == hash(SweepOptions(cpu_compiler_options=[("xla_cpu_prefer_vector_width", 512)]))
    default = SweepOptions()
    assert (default.accelerator_chunk_nodes, default.accelerator_stack_evaluations) == (
        ACCELERATOR_CHUNK_NODES, ACCELERATOR_STACK_EVALUATIONS) == (2**24, 65536)
