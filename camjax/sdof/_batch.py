"""One chunked vmap for every batched sweep of the exact path."""

from __future__ import annotations

import jax
import jax.numpy as jnp

CHUNK_NODES = 131072
"""Grid nodes (batch members x nodes per member) that ``chunked_map`` vmaps over at once on
a CPU: a working set that stays in cache."""

ACCELERATOR_CHUNK_NODES = 2**24
"""The same on a GPU (or any backend other than the CPU), which runs each operation over
the whole chunk at once: small chunks leave it waiting on launches (on an H200, a
100,000-ratio curve's kernel took 45 ms in chunks of 2**17 nodes, 5 ms in 2**24, using
0.5 GiB)."""

ACCELERATOR_STACK_EVALUATIONS = 65536
"""(law, period ratio) pairs of a stack (``camjax.sweep.sweep_law_stack``) swept at once on
a GPU: 65 laws of 1000 ratios (on an H200, 256 SCCA laws' kernel took 125 ms one law at
a time, 20 ms 64 at a time, using 0.8 GiB).  A CPU sweeps a stack's laws one at a time (a
vmap over laws outgrows its cache)."""


def chunk_nodes() -> int:
    """Grid nodes per chunk for the backend being compiled for (JAX's default backend)."""
    return CHUNK_NODES if jax.default_backend() == "cpu" else ACCELERATOR_CHUNK_NODES


def stack_laws(ratios: int) -> int:
    """Laws of a stack swept at once, each against ``ratios`` period ratios, on the default
    backend."""
    if jax.default_backend() == "cpu":
        return 1
    return max(1, ACCELERATOR_STACK_EVALUATIONS // max(1, int(ratios)))


def map_in_chunks(one, batch, members: int):
    """``jax.vmap(one)(batch)`` as a sequential map over chunks of ``members`` members.

    ``batch`` is a pytree whose leaves share a leading axis ``B``; it is padded with copies
    of its last member (always valid input) to equal chunks, so one body compiles, and the
    padding is cut from every output leaf.  One member per chunk is a plain ``lax.map``.
    """
    size = jax.tree.leaves(batch)[0].shape[0]
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
