"""The one entry point: ``solve`` any model driven by any law."""

from __future__ import annotations

import functools

import jax.numpy as jnp

from .. import checks
from ..errors import RESULTS, promote, raise_if_failed
from ..laws import AbstractMotionLaw, rest_to_rest
from ..registry import model_class_names
from ..sharding import cpu_options_jit
from ._base import AbstractMachineModel, AbstractModel, Response


def _response(law, model: AbstractModel, options, checked: bool) -> Response:
    with checks.checked_outside(checked):
        return model.response(law, options)


@functools.cache
def _compiled(cpu_options: tuple):
    """The jitted solve, compiled on CPU with these XLA options (one program per option
    set; inside a caller's trace, none: ``camjax.sharding.cpu_options_jit``)."""
    return cpu_options_jit(_response, cpu_options)


def solve_program(model: AbstractModel):
    """The jitted program ``solve`` and ``trace_solve`` run for ``model``
    (``camjax.sharding.OptionsJit``): one per set of XLA options, compiled on CPU with the
    model class's ``cpu_compiler_options`` (XLA's defaults elsewhere, and inside a
    caller's trace), so every model that asks for none shares one program."""
    return _compiled(type(model).cpu_compiler_options)


def solve(
    law: AbstractMotionLaw | str | None,
    model: AbstractModel,
    *,
    dwell: float = 1.0,
    method: str | None = None,
    throw: bool = True,
    **options,
) -> Response:
    """Response of ``model`` driven by ``law``: time histories and metrics.

    Works for every model (``SpringMass``, ``CoulombFriction``,
    ``Backlash``, ``TwoMass``, ``SwingingFollower``); each picks a sound
    default ``method`` and lists the others in ``type(model).methods``.  ``options`` are
    the model's static settings (see its options class, e.g.
    ``camjax.models.SpringMassOptions``); an unknown one is a ``ValueError``.

    Args:
        law: the rise (followed by a dwell), or its name (``"cycloidal"``).  For ``SwingingFollower``, ``None`` keeps
            the model's own rise and fall laws; a law replaces both.
        model: the scene, with its parameters.
        dwell: dwell after the rise, in motion periods.
        method: solution method (``None``: the model's default).
        throw: raise ``camjax.SolverError`` if the solution failed (default); with
            ``throw=False`` the response comes back with its ``result`` code instead.
            Traced (inside jit, vmap or grad), the check runs with the computation and
            fails it with one message (equinox's runtime error inside ``jax.jit``).

    Raises:
        TypeError: ``model`` is not a camjax model, or ``law`` not a motion law.
        ValueError: a bad parameter or option, named.
        SolverError: the solution failed (with ``throw=True``).
    """
    opts, arguments = _arguments(law, model, dwell, method, options)
    with checks.as_value_errors():
        response = solve_program(model)(*arguments)
    if throw and not checks.is_concrete(response.result, response.payload_acceleration):
        # Traced (the caller's jit, vmap or grad): the check runs with the computation.
        result = promote(response.result)
        bad = result._value != RESULTS.successful._value
        if response.payload_acceleration is not None:
            bad = bad | ~jnp.all(jnp.isfinite(response.payload_acceleration))
        return checks.guard(response, bad, f"{opts.method} solve of {type(model).__name__} "
                            "failed or produced non-finite values (throw=False returns the "
                            "response with its result code instead)")
    if throw:
        reached = response.stats.get("reached")
        where = f" (reached tau = {float(reached):.6g})" if reached is not None else ""
        raise_if_failed(
            response.result,
            lambda i: f"{opts.method} solve of {model.describe()}{where}",
            *([response.payload_acceleration] if response.payload_acceleration is not None else []),
        )
    return response


def _arguments(law, model, dwell, method, options):
    """``solve``'s checked options, and the arguments of its compiled program."""
    if not isinstance(model, AbstractModel):
        raise TypeError(f"model must be a camjax model ({model_class_names()}), "
                        f"got {type(model).__name__}")
    law = None if law is None else rest_to_rest(law, "solve")
    if law is None and not isinstance(model, AbstractMachineModel):
        raise TypeError(f"{type(model).__name__} needs a motion law (law is None)")
    opts = model.options(method, dwell, **options)
    checked = checks.is_concrete(model)  # concrete parameters were checked at construction
    return opts, (law, model.with_array_leaves(), opts, checked)


def trace_solve(law, model: AbstractModel, *, dwell: float = 1.0, method: str | None = None,
                **options) -> None:
    """Trace and lower the program ``solve`` would compile for these arguments, without
    compiling or running it.

    JAX keeps both, so a later ``solve`` with arguments of the same structure goes straight
    to XLA's compile, which releases the GIL: a caller can trace first and then run the
    solve beside other Python work on a second thread (``camjax follower`` does).
    """
    solve_program(model).lower(*_arguments(law, model, dwell, method, options)[1])
