"""Run a batched computation over several local devices, one shard of the batch each.

A sweep (period ratios, or a stack of laws of one pytree structure) is split along axis 0
over a 1-D device mesh with ``jax.shard_map``, so that every device runs its own adaptive
``while_loop``\\ s (plain ``jit`` auto-sharding of such loops runs them in lock step and is
slow, diffrax #407, jax #26586).  The batch is padded to a multiple of the device count
with copies of its last member (always valid input) and the padding is stripped from the
result, so callers see exactly the single-device answer.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
import re
from collections.abc import Sequence
from pathlib import Path

import equinox as eqx
import jax
import numpy as np
from jax.sharding import Mesh, PartitionSpec

AXIS = "batch"
"""Name of the mesh axis the batch is split along."""


_HOST_DEVICES_FLAG = re.compile(r"--xla_force_host_platform_device_count=(\d+)")


def available_cores(cpu_max: Path = Path("/sys/fs/cgroup/cpu.max")) -> int:
    """CPU cores this process may use: its affinity mask, within a cgroup's CPU quota
    (``cpu_max``: a container limited to 2 CPUs on a 64-core host has 2)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    cores = cores or 1
    try:
        quota, period = Path(cpu_max).read_text().split()[:2]
        if quota != "max":
            cores = min(cores, max(1, math.ceil(int(quota) / int(period))))
    except (OSError, ValueError):
        pass
    return cores


def use_cpu_cores(count: int | None = None) -> int:
    """Give JAX one CPU device per core (or ``count`` devices), so that sweeps split their
    batch over the cores (``shard_batch``) instead of running on one device.

    One CPU device already spreads some of its work over the cores, but a sweep of many
    laws ran 1.3x faster split over two devices on a 2-core machine (``camjax.ct_curves``
    of 256 SCCA laws x 1000 ratios, 2026-11-26, commit 40f1535).  The device count is
    fixed when JAX starts (building a law or any array starts it): call this right after
    ``import camjax``.  A count the user set already wins: ``XLA_FLAGS``
    (``--xla_force_host_platform_device_count=N``), ``JAX_NUM_CPU_DEVICES`` or JAX's
    ``jax_num_cpu_devices``.  ``count`` defaults to ``available_cores()``.  Returns the
    number of CPU devices JAX has (or will have).

    Raises:
        ValueError: ``count`` is not a positive integer.
        RuntimeError: JAX has already started with another device count.
    """
    if count is None:
        count = available_cores()
    if isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 1:
        raise ValueError(f"count must be a positive integer (CPU devices), got {count!r}")
    if not backends_started():
        given = _HOST_DEVICES_FLAG.search(os.environ.get("XLA_FLAGS", ""))
        if given:
            return int(given.group(1))
        if jax.config.jax_num_cpu_devices > 0:
            return int(jax.config.jax_num_cpu_devices)
        try:
            jax.config.update("jax_num_cpu_devices", int(count))
            return int(count)
        except RuntimeError:  # started after all (``backends_started`` could not tell)
            pass
    started = len(jax.devices("cpu"))
    if started != count:
        raise RuntimeError(
            f"JAX has already started with {started} CPU device(s); call "
            "camjax.sharding.use_cpu_cores before any JAX computation (right after "
            "import), or set XLA_FLAGS=--xla_force_host_platform_device_count="
            f"{count} before Python starts")
    return started


def on_cpu() -> bool:
    """Whether JAX's default backend is the CPU.  The engine sizes its work by it (chunks,
    scan blocks, bands of period ratios, compiler options): small for a CPU's cache, large
    for a GPU.  It follows the default backend, not the devices a call names."""
    return jax.default_backend() == "cpu"


CPU_COMPILER_OPTIONS: tuple[tuple[str, object], ...] = (("xla_cpu_prefer_vector_width", 512),)
"""XLA options of the sweeps' programs (``sweep_jit``) on CPU: vectors of 512 bits where
the CPU has them (AVX-512; XLA's default prefers 256).  On a 2-core AVX-512 machine
(2026-11-26) ``camjax.ct_curves`` of 256 SCCA laws ran 1.05-1.14x faster and a one-law
curve's kernel 1.05-1.08x, compiled as fast; a CPU without them keeps its widest.
``SweepOptions.run_once`` drops them."""

ACCELERATOR_CHUNK_NODES = 2**24
"""Grid nodes that ``camjax.sdof.chunked_map`` vmaps over at once on a GPU (or any backend
other than the CPU), which runs each operation over the whole chunk at once: small chunks
leave it waiting on launches (on an H200, a 100,000-ratio curve's kernel took 45 ms in
chunks of 2**17 nodes, 5 ms in 2**24, using 0.5 GiB).  It also bounds the grid nodes of a
stack's laws swept at once."""

ACCELERATOR_STACK_EVALUATIONS = 65536
"""(law, period ratio) pairs of a stack swept at once on a GPU: 65 laws of 1000 ratios (on
an H200, 256 SCCA laws' kernel took 125 ms one law at a time, 20 ms 64 at a time, using
0.8 GiB)."""


@dataclasses.dataclass(frozen=True)
class SweepOptions:
    """How a sweep's program is compiled and batched: the ``sweep`` field of every model's
    options (``camjax.models.Options``), so a call passes its choice (``ct_curve(...,
    sweep=SweepOptions.run_once())``) and each choice compiles its own program.  None of
    them changes a result.

    Attributes:
        cpu_compiler_options: XLA options of the sweeps' programs on CPU (default
            ``CPU_COMPILER_OPTIONS``); XLA's defaults on any other backend.
        accelerator_chunk_nodes: grid nodes vmapped at once off the CPU
            (``ACCELERATOR_CHUNK_NODES``; a CPU keeps ``camjax.sdof.CHUNK_NODES``).
        accelerator_stack_evaluations: (law, ratio) pairs of a stack swept at once off the
            CPU (``ACCELERATOR_STACK_EVALUATIONS``).  Both sizes are a device's own tuning,
            as experiments/benchmarks/device_check.py measures it.
    """

    cpu_compiler_options: tuple[tuple[str, object], ...] = CPU_COMPILER_OPTIONS
    accelerator_chunk_nodes: int = ACCELERATOR_CHUNK_NODES
    accelerator_stack_evaluations: int = ACCELERATOR_STACK_EVALUATIONS

    def __post_init__(self):
        for name in ("accelerator_chunk_nodes", "accelerator_stack_evaluations"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise ValueError(f"SweepOptions {name} must be a positive integer, got {value!r}")
            object.__setattr__(self, name, int(value))
        options = self.cpu_compiler_options
        try:
            options = tuple((str(key), value) for key, value in options)
            hash(options)
        except (TypeError, ValueError):
            raise ValueError("SweepOptions cpu_compiler_options must be (name, value) pairs of "
                             f"hashable values, got {self.cpu_compiler_options!r}") from None
        object.__setattr__(self, "cpu_compiler_options", options)

    @classmethod
    def run_once(cls) -> SweepOptions:
        """XLA's own CPU options (not ``CPU_COMPILER_OPTIONS``), for sweeps that each run
        once: under XLA's classic emitters, which a short ``camjax`` command uses, the
        wider vectors took 0.05 s longer to compile (``camjax ct``, 0.55 against 0.50 s),
        more than its 7000 ratios gain from them."""
        return cls(cpu_compiler_options=())

    def compiler_options(self) -> tuple[tuple[str, object], ...]:
        """The XLA options a sweep compiles with on JAX's default backend now."""
        return self.cpu_compiler_options if on_cpu() else ()


DEFAULT_SWEEP_OPTIONS = SweepOptions()
"""The library's defaults (a frozen value: a call that wants others passes its own)."""


@functools.cache
def _filter_jit(fun, options: tuple) -> eqx.Module:
    return eqx.filter_jit(fun, compiler_options=dict(options) or None)


try:  # JAX's own test (private): no trace is running
    from jax._src.core import trace_state_clean as _trace_state_clean
except ImportError:  # a JAX without it
    _trace_state_clean = None


def outside_traces() -> bool | None:
    """Whether no JAX transformation is tracing (not inside ``jit``, ``vmap``, ``grad``),
    or ``None`` where this JAX cannot say."""
    return None if _trace_state_clean is None else bool(_trace_state_clean())


class OptionsJit:
    """``equinox.filter_jit(fun)``, compiled with ``options(*args, **kwargs)`` (the XLA
    options the call's own arguments pick) when called outside any trace, and with XLA's
    defaults inside one: XLA takes options only for a top-level program (a caller's
    ``jit`` inlines this one; JAX refuses options there), and XLA's defaults where JAX
    cannot say.  Decided at each call, as the default backend may change.  ``fun`` itself
    is ``__wrapped__``."""

    def __init__(self, fun, options):
        functools.update_wrapper(self, fun)
        self._fun, self._options = fun, options

    def compiler_options(self, *args, **kwargs) -> tuple[tuple[str, object], ...]:
        """The XLA options a call with these arguments, made here and now, compiles with
        (none inside a trace)."""
        return self._options(*args, **kwargs) if outside_traces() else ()

    def program(self, *args, **kwargs) -> eqx.Module:
        """The jitted program a call with these arguments, made here and now, runs: one per
        function and options, shared by every ``OptionsJit`` of ``fun`` that picks the same
        options."""
        return _filter_jit(self._fun, self.compiler_options(*args, **kwargs))

    def __call__(self, *args, **kwargs):
        return self.program(*args, **kwargs)(*args, **kwargs)

    def lower(self, *args, **kwargs):
        """The program's ``lower`` (trace and lower without compiling)."""
        return self.program(*args, **kwargs).lower(*args, **kwargs)


def sweep_options_of(*args, **kwargs) -> SweepOptions:
    """The ``SweepOptions`` of a sweep's call: the ``sweep`` field of its last argument (a
    model's options), or the defaults."""
    options = kwargs.get("options", args[-1] if args else None)
    sweep = getattr(options, "sweep", None)
    return sweep if isinstance(sweep, SweepOptions) else DEFAULT_SWEEP_OPTIONS


def sweep_jit(fun) -> OptionsJit:
    """``equinox.filter_jit`` for the sweeps' programs (and ``shard_batch``'s split of
    them), which run the engine over whole batches and take the model's options last: on
    CPU they compile with those options' ``sweep.cpu_compiler_options``
    (``CPU_COMPILER_OPTIONS`` by default)."""
    return OptionsJit(fun, lambda *args, **kwargs: sweep_options_of(*args, **kwargs).compiler_options())


def cpu_options_jit(fun, cpu_options: tuple[tuple[str, object], ...]) -> OptionsJit:
    """``equinox.filter_jit`` that compiles with ``cpu_options`` on CPU (a model's
    ``cpu_compiler_options``, for its ``solve``)."""
    return OptionsJit(fun, lambda *args, **kwargs: cpu_options if on_cpu() else ())


def backends_started() -> bool | None:
    """Whether JAX's backends have started (its CPU device count is then fixed, and XLA's
    threads are running); ``None`` where this JAX cannot say (``use_cpu_cores`` then
    learns it from JAX's refusal; ``camjax.cli.can_fork`` does not fork)."""
    try:
        from jax._src import xla_bridge

        return bool(xla_bridge.backends_are_initialized())
    except (ImportError, AttributeError):
        return None


def resolve_devices(devices=None) -> list:
    """The devices to shard over.

    Args:
        devices: ``None`` for every local device, a positive int for the first that many
            local devices, or a sequence of devices.

    Raises:
        ValueError: for a count that is not positive or exceeds the local devices, or an
            empty list.
    """
    local = jax.local_devices()
    if devices is None:
        return local
    if isinstance(devices, int | np.integer) and not isinstance(devices, bool):
        if not 1 <= devices <= len(local):
            raise ValueError(
                f"devices must be between 1 and the {len(local)} local device(s), got {devices}"
            )
        return local[: int(devices)]
    if isinstance(devices, Sequence) and not isinstance(devices, str):
        chosen = list(devices)
        if not chosen:
            raise ValueError("devices must name at least one device, got an empty list")
        if not all(isinstance(d, jax.Device) for d in chosen):
            raise ValueError(f"devices must be jax.Device objects, got {chosen!r}")
        if any(d.process_index != jax.process_index() for d in chosen):
            raise ValueError("devices must belong to this process (jax.local_devices())")
        return chosen
    raise ValueError(f"devices must be None, a device count or a list of devices, got {devices!r}")


def batch_size(tree) -> int:
    """Length of axis 0 shared by every array leaf of ``tree`` (a ``ValueError`` if not)."""
    sizes = {np.shape(x)[0] if np.ndim(x) else None for x in jax.tree.leaves(tree)}
    if len(sizes) != 1 or None in sizes:
        raise ValueError(f"batched arguments need one common leading axis, got sizes {sizes}")
    return sizes.pop()


def _pad(x, extra: int):
    if extra == 0:
        return x
    tail = jax.numpy.repeat(x[-1:], extra, axis=0)
    return jax.numpy.concatenate([x, tail], axis=0)


def _sharded_call(fn, mesh, args, batched_argnums):
    """``fn(*args)`` with the ``batched_argnums`` split over ``mesh`` (jitted by
    ``_sharded_program``, once per shape)."""
    dynamic, static = eqx.partition(args, eqx.is_array)
    specs = tuple(
        jax.tree.map(lambda _, i=i: PartitionSpec(AXIS) if i in batched_argnums else PartitionSpec(), arg)
        for i, arg in enumerate(dynamic)
    )
    leaves, treedef = jax.tree.flatten(dynamic)
    flat_specs = jax.tree.leaves(specs, is_leaf=lambda x: isinstance(x, PartitionSpec))

    def body(*local):
        return fn(*eqx.combine(jax.tree.unflatten(treedef, local), static))

    return jax.shard_map(
        body, mesh=mesh, in_specs=tuple(flat_specs), out_specs=PartitionSpec(AXIS),
        check_vma=False,
    )(*leaves)


def _split_options(fn, mesh, args, batched_argnums) -> tuple:
    """The XLA options of ``shard_batch``'s split of ``fn``: those ``fn`` picks for its
    arguments where it is an ``OptionsJit`` (a sweep), so that the split batch compiles as
    the whole one would; XLA's defaults otherwise (a function that runs on one device, as
    a program's speed batch)."""
    return fn._options(*args) if isinstance(fn, OptionsJit) else ()


split_program = OptionsJit(_sharded_call, _split_options)
"""The jitted program ``shard_batch`` runs to split a batch over devices (``_split_options``)."""


def shard_batch(fn, *args, batched_argnums=(0,), devices=None):
    """``fn(*args)`` computed with the batch split over ``devices``.

    Args:
        fn: a jittable function whose every output leaf has the batch on axis 0, for
            example ``batch_metrics`` or a ``vmap`` of it over stacked laws.  Pass a
            module-level function (not a fresh lambda) so the compiled program is reused.
        args: the arguments.  Those at ``batched_argnums`` are pytrees whose every array
            leaf has the batch on axis 0; every device sees the others whole.  Non-array
            leaves (options, Python floats) are static.
        batched_argnums: positions of the batched arguments.
        devices: see :func:`resolve_devices`.  With one device ``fn`` is called directly.

    Returns:
        ``fn``'s output for the whole batch, the padding removed.
    """
    chosen = resolve_devices(devices)
    batched_argnums = tuple(sorted({int(i) for i in np.atleast_1d(batched_argnums)}))
    if len(chosen) == 1:
        with jax.default_device(chosen[0]):
            return fn(*args)
    size = batch_size([args[i] for i in batched_argnums])
    extra = (-size) % len(chosen)
    padded = tuple(
        jax.tree.map(lambda x: _pad(x, extra) if eqx.is_array(x) else x, arg)
        if i in batched_argnums else arg
        for i, arg in enumerate(args)
    )
    mesh = Mesh(np.asarray(chosen), (AXIS,))
    out = split_program(fn, mesh, padded, batched_argnums)
    return jax.tree.map(lambda x: x[:size], out)
