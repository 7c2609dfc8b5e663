"""Input checks that hold on concrete values and under ``jit``, ``vmap`` and ``grad``.

On concrete values a failed check raises ``ValueError`` naming the problem and the value.
On traced values (inside ``jax.jit``, ``jax.vmap``, ``jax.grad``) it goes through
``equinox.error_if``: the computation raises a runtime error carrying the same message
when it runs, instead of returning a plausible number.  (Floor 1: imports nothing from
the rest of camjax.)
"""

from __future__ import annotations

import contextlib
import contextvars
import math
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np


def is_concrete(*values) -> bool:
    """True when no value is a JAX tracer, so that Python-side checks can run."""
    return not any(isinstance(v, jax.core.Tracer) for v in jax.tree.leaves(values))


def require(condition: bool, message: str) -> None:
    """Raise ``ValueError(message)`` when a concrete validity condition fails."""
    if not bool(condition):
        raise ValueError(message)


_CHECKED_OUTSIDE = contextvars.ContextVar("camjax_outside_checks", default=False)


@contextlib.contextmanager
def checked_outside(flag: bool = True):
    """Trace without the runtime checks of traced values, because the caller has checked
    the same values concretely (``camjax.solve`` and the sweeps do).

    A runtime check is a host callback, and JAX's persistent compilation cache does not
    store programs with host callbacks: dropping checks that cannot fail lets a command's
    programs load from the cache.  Entry points pass the flag as a static argument of
    their compiled function, so a program traced with it is never reused without it.
    """
    token = _CHECKED_OUTSIDE.set(bool(flag))
    try:
        yield
    finally:
        _CHECKED_OUTSIDE.reset(token)


def ensure(value, predicate, message: str):
    """``value`` unchanged if ``predicate(value)`` holds everywhere; else a clear error.

    ``predicate`` maps an array to booleans (NaN must give False) and works on NumPy and
    JAX arrays.  Concrete ``value``: ``ValueError`` naming the first bad value.  Traced:
    ``value`` is wrapped with ``equinox.error_if``, so the compiled computation raises
    ``message`` when it runs with a bad value.
    """
    if is_concrete(value):
        array = np.asarray(value, dtype=float)
        ok = np.asarray(predicate(array))
        if not np.all(ok):
            bad = np.broadcast_to(array, ok.shape)[~ok].ravel()[0]
            raise ValueError(f"{message}, got {bad:g}")
        return value
    return guard(value, ~predicate(jnp.asarray(value)), message)


def guard(value, bad, message: str):
    """``value`` (any pytree) made to raise ``message`` when the computation runs with the
    traced condition ``bad`` true (``equinox.error_if``); unchanged under
    ``checked_outside``.  For checks that ``ensure``'s one-array predicate cannot state
    (several leaves at once, such as fractions that must sum to at most 1)."""
    if _CHECKED_OUTSIDE.get():
        return value
    bad = jnp.any(bad)
    # The message's index is computed from ``bad`` (always 0): with a constant index,
    # ``jax.ensure_compile_time_eval`` (which laws meet inside grid builders) would run the
    # raising callback while tracing, whatever ``bad`` turns out to be.
    index = bad.astype(jnp.int32) * 0
    with as_value_errors():  # evaluated at once under grad or vmap without jit: one line
        return eqx.branched_error_if(value, bad, index, [message])


_EQUINOX_MESSAGE = "equinox.EquinoxRuntimeError: "


@contextlib.contextmanager
def as_value_errors():
    """Inside, a failed runtime check of a program compiled by ``equinox.filter_jit`` (a
    camjax entry point's own) comes out as ``ValueError(message)``: one line, as if checked
    concretely, instead of equinox's report with the message on its third line.  (Inside a
    caller's ``jax.jit`` the error is raised by the caller's program, out of camjax's reach:
    docs/conventions.md says how to read it.)"""
    try:
        yield
    except eqx.EquinoxRuntimeError as error:
        lines = str(error).splitlines()
        messages = [x[len(_EQUINOX_MESSAGE):] for x in lines if x.startswith(_EQUINOX_MESSAGE)]
        if not messages:
            raise
        raise ValueError(messages[-1]) from None


def finite_number(value, what: str) -> float:
    """``value`` as a float: a real number (not a bool, not a string) and finite."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{what} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{what} must be finite, got {value}")
    return value


def positive_integer(value, name: str) -> int:
    """``value`` as an ``int`` if it is a whole number >= 1 (``100000`` or ``1e5``), else a
    ``ValueError`` naming ``name`` (a count the solver loops over: a float must not reach it)."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = 0.0
    require(number.is_integer() and number >= 1, f"{name} must be a positive integer, got {value}")
    return int(number)


def positive(value, name: str):
    """``value`` if every entry is finite and > 0 (period ratios, stiffnesses)."""
    return ensure(value, lambda v: (v > 0) & (v < np.inf), f"{name} must be positive and finite")


def non_negative(value, name: str):
    """``value`` if every entry is finite and >= 0 (friction, deceleration)."""
    return ensure(value, lambda v: (v >= 0) & (v < np.inf), f"{name} must be >= 0 and finite")


def damping_ratio(value, name: str = "damping ratio"):
    """``value`` if every entry is in ``[0, 1)`` (an underdamped payload)."""
    return ensure(value, lambda v: (v >= 0) & (v < 1), f"{name} must be in [0, 1) (an underdamped payload)")


MAX_PERIOD_RATIOS = 10_000_000
"""Most period ratios one sweep takes (about 5 minutes per law on two CPU cores, 80 MB
per metric): a larger request is refused before any work."""


def period_ratio_count(count: int, what: str = "period ratios") -> int:
    """``count`` checked against ``MAX_PERIOD_RATIOS`` (a ``ValueError`` saying what to do)."""
    if count > MAX_PERIOD_RATIOS:
        raise ValueError(f"{what}: {count:,} period ratios is more than the {MAX_PERIOD_RATIOS:,} one "
                         "sweep takes; sweep fewer, or split the range into several runs")
    return count


def period_ratios(values, *, what: str = "period ratio") -> np.ndarray:
    """Concrete period ratios as a non-empty 1-D float array, or a ``ValueError``."""
    try:
        n = np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError) as error:
        raise ValueError(f"{what} must be numbers, got {values!r}") from error
    require(n.ndim == 1 and n.size > 0, f"{what} must be a non-empty 1-D list of numbers")
    period_ratio_count(n.size, f"{what}s")
    require(bool(np.all(np.isfinite(n))), f"{what} must be finite (got NaN or inf)")
    if np.any(n <= 0):
        raise ValueError(f"{what} must be positive, got {n[n <= 0][0]:g}")
    return n


MAX_SPEEDS = 5_000
"""Most speeds one cam program's analysis takes: it holds about 0.45 MB a speed (10,000
speeds took 4.5 GB, 100,000 had the kernel kill a 16 GB machine), so a larger request is
refused before any work."""


def speed_count(count: int, name: str = "rpm") -> int:
    """``count`` speeds checked against ``MAX_SPEEDS`` (a ``ValueError`` naming ``name``, the
    caller's option, with the limit and what to change); a range's ``COUNT`` is checked so
    before the range is built (``camjax._plain.parse_range``'s ``check_count``)."""
    if count > MAX_SPEEDS:
        raise ValueError(f"{name} has {count:,} speeds, more than the {MAX_SPEEDS:,} one analysis takes "
                         "(about 0.45 MB of memory a speed); give fewer speeds (a smaller COUNT in "
                         "START:STOP:COUNT) or split the range into several runs")
    return count


def speeds(values, name: str = "rpm") -> np.ndarray:
    """Concrete machine speeds (rpm) as a non-empty 1-D float array, each positive and
    finite, at most ``MAX_SPEEDS`` of them, or a one-line ``ValueError`` naming ``name`` (the
    caller's option).  A string, a bool or anything else that is not a number is refused,
    not converted."""
    if not is_concrete(values):
        raise ValueError(f"{name} must be concrete speeds here (not traced inside jit, vmap or grad)")
    try:
        raw = np.asarray(values)
        ok = raw.dtype.kind in "iuf"
    except (TypeError, ValueError):  # a ragged list
        ok = False
    if not ok:
        shown = repr(values).replace("\n", " ")
        shown = shown if len(shown) <= 60 else shown[:57] + "..."
        raise ValueError(f"{name} must be a speed in rpm or a 1-D list of speeds, got {shown}")
    rpm = np.atleast_1d(raw.astype(float))
    if rpm.size == 0 or rpm.ndim != 1:
        raise ValueError(f"{name} must be one speed or a 1-D list of speeds")
    speed_count(rpm.size, name)
    bad = ~(np.isfinite(rpm) & (rpm > 0))
    if np.any(bad):
        raise ValueError(f"{name} must be positive and finite, got {rpm[bad][0]:g}")
    return rpm


def read_text(path, what: str, form: str) -> str:
    """The UTF-8 text of the file ``path``, or a one-line ``ValueError`` naming it: missing,
    unreadable, or not text (``what``: "program file"; ``form``: "TOML")."""
    path = Path(path)
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ValueError(f"{path}: no such {what}") from None
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a {what} ({form} text), it is not UTF-8") from None
    except OSError as error:
        raise ValueError(f"{path}: cannot read the {what} ({error.strerror})") from None


def read_toml(path, what: str) -> dict:
    """The TOML file ``path`` parsed, or a one-line ``ValueError`` naming it (``read_text``)."""
    import tomllib

    try:
        return tomllib.loads(read_text(path, what, "TOML"))
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{path}: not valid TOML ({error})") from None
