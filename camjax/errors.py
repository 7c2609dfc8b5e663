"""Errors and result codes (floor 1: nothing here imports the rest of camjax).

Every solution path returns a ``result`` code of ``RESULTS``; ``camjax.solve`` and the
sweeps turn a failure into ``SolverError`` unless asked for the code with ``throw=False``.
The codes are camjax's own, so that the exact paths never import diffrax (a third of a
second of every command's start); a diffrax solve's code is converted by name
(``promote``).
"""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np


class SolverError(RuntimeError):
    """A solution path failed (step limit, non-finite values, a broken invariant): no result."""


class RESULTS(eqx.Enumeration):
    """Result codes of every solution path.

    The codes a diffrax solve can return keep diffrax's names (``max_steps_reached``,
    ``dt_min_reached``, ...); the last three are camjax's own checks of a response.
    """

    successful = ""
    max_steps_reached = (
        "the maximum number of solver steps was reached: raise max_steps, or loosen rtol/atol"
    )
    singular = "a linear solve inside the implicit solver returned non-finite values"
    breakdown = "an iterative linear solve inside the solver broke down"
    stagnation = "an iterative linear solve inside the solver stagnated"
    conlim = "a linear system inside the solver is too ill-conditioned to solve"
    nonfinite_input = "a linear solve inside the solver was given non-finite values"
    nonlinear_max_steps_reached = (
        "the maximum number of steps in the implicit solver's nonlinear (Newton) iteration "
        "was reached"
    )
    nonlinear_divergence = "the implicit solver's nonlinear (Newton) iteration diverged"
    nonfinite = "non-finite values (inf or NaN) appeared in the solution"
    dt_min_reached = "the solver's step fell to its minimum size"
    event_occurred = "the solve stopped at an event"
    max_steps_rejected = "the solver rejected too many steps in a row"
    internal_error = "diffrax reported an internal error (a bug in diffrax)"
    solver_failed = "the diffrax solve failed with a result code camjax does not know"
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


@functools.cache
def _by_name(enumeration) -> np.ndarray:
    """Our index of each of ``enumeration``'s codes, matched by name (unknown names:
    ``solver_failed``)."""
    table = np.empty(len(enumeration), dtype=np.int32)
    for name, item in enumeration._name_to_item.items():
        ours = RESULTS._name_to_item.get(name, RESULTS.solver_failed)
        table[int(item._value)] = int(ours._value)
    return table


def promote(result) -> RESULTS:
    """A result code as a camjax ``RESULTS`` code: diffrax's (or optimistix's) by name."""
    if isinstance(result, RESULTS):
        return result
    with jax.ensure_compile_time_eval():
        value = jnp.asarray(_by_name(result._enumeration))[result._value]
    return type(RESULTS.successful)(value, RESULTS)


def first_failure(result) -> int | None:
    """Index of the first failed entry of a (batched) result code, or ``None``."""
    codes = np.atleast_1d(np.asarray(result._value))
    failed = np.flatnonzero(codes != np.asarray(RESULTS.successful._value))
    return int(failed[0]) if failed.size else None


def result_names(result) -> list[str]:
    """The name of each entry of a (batched) result code: ``"successful"`` or the
    failure's (``"invariant_violated"``, ``"max_steps_reached"``, ...)."""
    names = {int(item._value): name for name, item in RESULTS._name_to_item.items()}
    return [names[int(code)] for code in np.atleast_1d(np.asarray(promote(result)._value))]


def mark_failures(result, *values):
    """A batch's result code and values with its failures marked, for a caller that
    reports them rather than raising (``throw=False``).

    An entry that succeeded with a non-finite value becomes ``nonfinite``; every value of
    a failed entry becomes NaN.  Returns ``(result, values)``: the codes and the values
    as NumPy arrays, batched like ``result`` on their first axis.
    """
    result = promote(result)
    codes = np.atleast_1d(np.asarray(result._value)).copy()
    arrays = [np.array(np.atleast_1d(np.asarray(v)), dtype=float) for v in values]
    finite = np.ones(codes.shape, bool)
    for array in arrays:
        finite &= np.isfinite(array).reshape(array.shape[0], -1).all(axis=1)
    success = int(RESULTS.successful._value)
    codes[(codes == success) & ~finite] = int(RESULTS.nonfinite._value)
    failed = codes != success
    for array in arrays:
        array[failed] = np.nan
    # The codes stay a NumPy array: a device array would cost a transfer per curve (a
    # wait of up to a millisecond on a GPU, for each of a stack's laws).
    marked = type(RESULTS.successful)(codes, RESULTS)
    return marked, tuple(arrays)


def raise_if_failed(result, describe, *values, entries: str = "") -> None:
    """Raise ``SolverError`` for the first bad batch entry: a failed one, or a non-finite
    value where it succeeded (whichever comes first in the batch).

    Args:
        result: a ``RESULTS`` code, scalar or batched.
        describe: ``describe(i)`` names batch entry ``i`` (the model and its parameters).
        values: arrays (batched like ``result``) that must be finite where it succeeded.
        entries: what the batch's entries are, for the count of failures ("(3 of 8
            law and ratio pairs failed)"); plain "(3 of 8 failed)" by default.
    """
    result = promote(result)
    failed = first_failure(result)
    nonfinite = None
    for value in values:
        finite = np.atleast_1d(np.isfinite(np.asarray(value)))
        finite = finite.reshape(finite.shape[0], -1).all(axis=1) if finite.ndim > 1 else finite
        if not finite.all():
            i = int(np.flatnonzero(~finite)[0])
            nonfinite = i if nonfinite is None else min(nonfinite, i)
    if failed is not None and (nonfinite is None or failed <= nonfinite):
        codes = np.atleast_1d(np.asarray(result._value))
        code = jax.tree.map(lambda x: jnp.atleast_1d(x)[failed], result)
        count = int(np.sum(codes != np.asarray(RESULTS.successful._value)))
        of = f" ({count} of {codes.size}{' ' * bool(entries)}{entries} failed)" if codes.size > 1 else ""
        raise SolverError(f"{describe(failed)} failed{of}: {RESULTS[code]}")
    if nonfinite is not None:
        raise SolverError(f"{describe(nonfinite)} produced non-finite values")
