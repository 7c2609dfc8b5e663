"""Errors and result codes (floor 1: nothing here imports the rest of camjax).

Every solution path returns a ``result`` code of ``RESULTS`` (diffrax's codes plus
camjax's own); ``camjax.solve`` and the sweeps turn a failure into
``SolverError`` unless asked for the code with ``throw=False``.
"""

from __future__ import annotations

import diffrax
import jax
import jax.numpy as jnp
import numpy as np


class SolverError(RuntimeError):
    """A solution path failed (step limit, non-finite values, a broken invariant): no result."""


class RESULTS(diffrax.RESULTS):  # type: ignore[misc]
    """Result codes: diffrax's (``successful``, ``max_steps_reached``, ...) and camjax's."""

    unstable_fixed_step = (
        "the fixed-step solver's numerical free vibration grew past its stability limit "
        "(w*dt too large): take more steps, or use an adaptive solver or the exact path"
    )
    too_many_segments = (
        "the contact or stick state changed more often than max_segments allows "
        "(repeated impacts or chattering): raise max_segments or add damping"
    )
    invariant_violated = (
        "the response broke an invariant of the model (a contact state inconsistent with "
        "the deflection, constraint drift, or a value outside its physical bound)"
    )


def promote(result) -> RESULTS:
    """A diffrax or optimistix result code as a camjax ``RESULTS`` code."""
    return RESULTS.promote(result) if not isinstance(result, RESULTS) else result


def first_failure(result) -> int | None:
    """Index of the first failed entry of a (batched) result code, or ``None``."""
    codes = np.atleast_1d(np.asarray(result._value))
    failed = np.flatnonzero(codes != np.asarray(RESULTS.successful._value))
    return int(failed[0]) if failed.size else None


def raise_if_failed(result, describe, *values) -> None:
    """Raise ``SolverError`` for the first failed batch entry, or a non-finite value.

    Args:
        result: a ``RESULTS`` code, scalar or batched.
        describe: ``describe(i)`` names batch entry ``i`` (the model and its parameters).
        values: arrays (batched like ``result``) that must be finite where it succeeded.
    """
    result = promote(result)
    i = first_failure(result)
    if i is not None:
        codes = np.atleast_1d(np.asarray(result._value))
        code = jax.tree.map(lambda x: jnp.atleast_1d(x)[i], result)
        count = int(np.sum(codes != np.asarray(RESULTS.successful._value)))
        of = f" ({count} of {codes.size} failed)" if codes.size > 1 else ""
        raise SolverError(f"{describe(i)} failed{of}: {RESULTS[code]}")
    for value in values:
        finite = np.atleast_1d(np.isfinite(np.asarray(value)))
        finite = finite.reshape(finite.shape[0], -1).all(axis=1) if finite.ndim > 1 else finite
        if not finite.all():
            i = int(np.flatnonzero(~finite)[0])
            raise SolverError(f"{describe(i)} produced non-finite values")
