"""One chunked vmap for every batched sweep of the exact path."""

from __future__ import annotations

import jax
import jax.numpy as jnp

CHUNK_NODES = 65536
"""Grid nodes (batch members x nodes per member) that ``chunked_map`` vmaps over at once."""

SPILL = 8
"""Flagged members per chunk that ``with_fallback`` recomputes one by one (more: all)."""


def chunked_map(one, batch, nodes_per_member: int, *, batched: bool = False):
    """``jax.vmap(one)(batch)`` in sequential chunks of about ``CHUNK_NODES`` grid nodes.

    Chunks keep the working set in cache (twice as fast as one vmap over 1000 period
    ratios on CPU) and memory bounded.  ``batch`` is one array of leading axis ``B``; it is
    padded with copies of its last member (always valid input) to equal chunks, so one
    body compiles, and the padding is cut from every output leaf.  With ``batched=True``
    ``one`` maps a whole chunk itself (``with_fallback``, say).
    """
    size = batch.shape[0]
    chunks = -(-size // max(1, CHUNK_NODES // max(1, nodes_per_member)))
    padded = jnp.pad(batch, [(0, (-size) % chunks)] + [(0, 0)] * (batch.ndim - 1), mode="edge")
    body = one if batched else jax.vmap(one)
    out = jax.lax.map(body, padded.reshape(chunks, -1, *batch.shape[1:]))
    return jax.tree.map(lambda x: x.reshape(x.shape[0] * x.shape[1], *x.shape[2:])[:size], out)


def with_fallback(fast, careful, batch, spill: int = SPILL):
    """``jax.vmap(careful)(batch)`` computed as ``fast``, which returns ``(out, flag)``:
    the members ``fast`` flags (a bound it could not settle) are recomputed by ``careful``.

    Up to ``spill`` flagged members are gathered and recomputed alone; more, and the whole
    batch is.  The choice is a ``lax.switch`` on the batch's flags, so unflagged batches
    pay nothing for it (under an outer ``vmap`` it becomes a select, and both run).
    """
    out, flag = jax.vmap(fast)(batch)

    def some():
        chosen = jnp.nonzero(flag, size=spill, fill_value=jnp.argmax(flag))[0]
        fixed = jax.vmap(careful)(batch[chosen])
        return jax.tree.map(lambda o, f: o.at[chosen].set(f), out, fixed)

    def every():
        fixed = jax.vmap(careful)(batch)
        return jax.tree.map(
            lambda o, f: jnp.where(flag.reshape(-1, *[1] * (o.ndim - 1)), f, o), out, fixed)

    flagged = jnp.sum(flag)
    branch = jnp.where(flagged == 0, 0, jnp.where(flagged <= spill, 1, 2))
    return jax.lax.switch(branch, [lambda: out, some, every])
