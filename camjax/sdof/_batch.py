"""One chunked vmap for every batched sweep of the exact path."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..sharding import ACCELERATOR_CHUNK_NODES as ACCELERATOR_CHUNK_NODES
from ..sharding import ACCELERATOR_STACK_EVALUATIONS as ACCELERATOR_STACK_EVALUATIONS
from ..sharding import DEFAULT_SWEEP_OPTIONS, SweepOptions, on_cpu

CHUNK_NODES = 131072
"""Grid nodes (batch members x nodes per member) that ``chunked_map`` vmaps over at once on
a CPU: a working set that stays in cache."""


def chunk_nodes(sweep: SweepOptions = DEFAULT_SWEEP_OPTIONS) -> int:
    """Grid nodes per chunk of ``chunked_map``: ``CHUNK_NODES`` (131,072) on a CPU, the
    accelerator's chunk (``sweep.accelerator_chunk_nodes``, default
    ``ACCELERATOR_CHUNK_NODES``, 2**24) on JAX's default backend otherwise
    (``camjax.sharding.on_cpu``)."""
    return CHUNK_NODES if on_cpu() else sweep.accelerator_chunk_nodes


def stack_laws(ratios: int, nodes_per_ratio: int = 1, sweep: SweepOptions = DEFAULT_SWEEP_OPTIONS) -> int:
    """Laws of a stack swept at once, each against ``ratios`` period ratios on a grid of
    ``nodes_per_ratio`` nodes: one on a CPU (a vmap over laws outgrows its cache);
    otherwise up to ``sweep``'s accelerator stack evaluations ((law, ratio) pairs) and
    chunk nodes at once."""
    if on_cpu():
        return 1
    ratios, nodes = max(1, int(ratios)), max(1, int(nodes_per_ratio))
    chunk, evaluations = sweep.accelerator_chunk_nodes, sweep.accelerator_stack_evaluations
    return max(1, min(evaluations // ratios, chunk // (ratios * nodes)))


def map_in_chunks(one, batch, members: int):
    """``jax.vmap(one)(batch)`` as a sequential map over chunks of ``members`` members.

    ``batch`` is a pytree whose leaves share a leading axis ``B``; it is padded with copies
    of its last member (always valid input) to equal chunks, so one body compiles, and the
    padding is cut from every output leaf.  One member per chunk is a plain ``lax.map``.
    """
    sizes = {jnp.shape(x)[0] if jnp.ndim(x) else None for x in jax.tree.leaves(batch)}
    if len(sizes) != 1 or None in sizes:
        raise ValueError("map_in_chunks: every leaf of the batch needs one leading axis of the "
                         f"same length, got leading sizes {sorted(map(str, sizes))}")
    size = sizes.pop()
    members = max(1, min(int(members), size))
    if members == 1:
        return jax.lax.map(one, batch)
    chunks = -(-size // members)
    members = -(-size // chunks)  # equal chunks with the least padding

    def chunked(x):
        x = jnp.pad(x, [(0, chunks * members - size)] + [(0, 0)] * (x.ndim - 1), mode="edge")
        return x.reshape(chunks, members, *x.shape[1:])

    out = jax.lax.map(jax.vmap(one), jax.tree.map(chunked, batch))
    return jax.tree.map(lambda x: x.reshape(chunks * members, *x.shape[2:])[:size], out)


def chunked_map(one, batch, nodes_per_member: int, chunk: int | None = None):
    """``jax.vmap(one)(batch)`` in sequential chunks of about ``chunk`` grid nodes.

    Chunks keep the working set in cache on a CPU (twice as fast as one vmap over 1000
    period ratios) and memory bounded everywhere; ``chunk`` defaults to
    :func:`chunk_nodes`.  ``batch`` is one array of leading axis ``B`` (see
    :func:`map_in_chunks`).
    """
    chunk = chunk_nodes() if chunk is None else chunk
    return map_in_chunks(one, batch, chunk // max(1, nodes_per_member))
