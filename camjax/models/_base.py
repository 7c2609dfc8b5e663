"""The model interface: every dynamic model is reached through ``camjax.solve`` and
the sweeps (``camjax.ct_curve``) in the same way.

A model is an equinox module whose parameters are pytree leaves (so ``jit``, ``vmap`` and
``grad`` see them).  Subclasses supply the few pieces that differ: the methods they offer,
their static options, a traced-safe check of their parameters, and one jittable
``response(law, options)`` that never raises but reports failure in ``result``.  The base
supplies the rest: option checking, the period-ratio sweep and the failure convention.
"""

import abc
import dataclasses
import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from equinox import AbstractVar

from ..checks import is_concrete, require
from ..errors import RESULTS
from ..laws import AbstractMotionLaw
from ..sharding import DEFAULT_SWEEP_OPTIONS, SweepOptions


@dataclasses.dataclass(frozen=True)
class Options:
    """Static settings of a solution (each distinct value compiles once).

    Attributes:
        method: solution method; each model lists its own (``Model.methods``).
        dwell: length of the dwell after the rise, in motion periods (Ct looks over it).
        sweep: how a period-ratio sweep's program is compiled and batched
            (``camjax.sharding.SweepOptions``; no result depends on it).
    """

    method: str
    dwell: float = 1.0
    sweep: SweepOptions = DEFAULT_SWEEP_OPTIONS

    def checked(self, max_period_ratio: float) -> "Options":
        """These options validated (``ValueError`` naming the field), filled in."""
        dwell = float(self.dwell)
        require(
            math.isfinite(dwell) and dwell >= 0,
            f"dwell must be a non-negative number of motion periods, got {self.dwell}",
        )
        require(isinstance(self.sweep, SweepOptions),
                f"sweep must be a camjax.sharding.SweepOptions, got {self.sweep!r}")
        return dataclasses.replace(self, dwell=dwell)


class Metrics(eqx.Module):
    """Response metrics in units of the law's Ca (multiply by Ca for units of h/T^2).

    The same definitions hold for every model:

    Attributes:
        ct: torsion factor, max |x''| over the rise and the following dwell, over Ca,
            refined between samples.
        residual: the residual vibration, over Ca: the largest ``|x''|`` in the dwell of
            the free vibration of the transmission that the state at ``tau = 1`` starts
            (``camjax.sdof.residual_of_mode``, in closed form from its crest times).
            Undamped, with the dwell holding the first crest (half a natural period), it
            is the vibration's amplitude ``w^2 |e|``; damped, each crest is
            ``sqrt(1 - zeta^2)`` of the envelope ``exp(-zeta w t)``, taken at its time, so
            the residual stays below the envelope's start and bounded as ``zeta -> 1``.
        peak_in_motion: max |x''| over the rise alone, over Ca.
    """

    ct: jax.Array
    residual: jax.Array
    peak_in_motion: jax.Array


class Response(eqx.Module):
    """What every model's solution returns; models subclass it to add their own fields.

    Attributes:
        tau: normalised time of the samples (the rise, then the dwell).
        payload_acceleration: the payload's acceleration ``x''`` at ``tau`` (units of
            h/T^2), or ``None`` for a model without a single payload.
        metrics: ``Metrics`` (units of Ca), or ``None`` likewise.
        result: a ``camjax.errors.RESULTS`` code (``successful`` unless it failed).
        stats: solver statistics (``steps``, and ``segments`` for event models).
    """

    tau: jax.Array
    payload_acceleration: jax.Array | None
    metrics: Metrics | None
    result: RESULTS
    stats: dict


class AbstractModel(eqx.Module):
    """A scene the cam drives: its parameters, methods and one jittable solution.

    A new model subclasses this (or ``AbstractMachineModel``) and writes:

    - ``period_ratio``: a field, or a property derived from physical parameters;
    - ``methods`` (class variable; the first is the default) and ``options_type`` (an
      ``Options`` dataclass of its static settings);
    - ``checked_parameters()``: its parameters checked (``camjax.checks``: concrete and traced);
    - ``response(law, options)``: the jittable solution, reporting failure in ``result``;

    and may override ``metrics`` (a lighter path to the metrics), ``sweeps_in_turn`` and
    ``sweep_law``.  The base supplies ``solve``'s checks, the period-ratio sweep and the
    failure convention.  docs/extending.md has a complete example.
    """

    period_ratio: AbstractVar[float | jax.Array]
    methods: ClassVar[tuple[str, ...]]
    options_type: ClassVar[type[Options]]
    cpu_compiler_options: ClassVar[tuple[tuple[str, object], ...]] = ()
    """XLA options for compiling this model's ``solve`` on CPU (none: XLA's defaults)."""

    @property
    def omega(self):
        """Normalised natural angular frequency ``w = 2 pi n`` (radians per motion period)."""
        return 2 * jnp.pi * self.period_ratio

    def __check_init__(self):
        if is_concrete(self):
            self.checked_parameters()  # ValueError naming the parameter

    @abc.abstractmethod
    def checked_parameters(self) -> dict:
        """The parameters that need checks, checked (``camjax.checks``), by field name."""

    def validated(self) -> "AbstractModel":
        """This model with every parameter checked, on concrete and traced values alike:
        a bad value raises ``ValueError`` now, or a runtime error from inside ``jit``,
        ``vmap`` or ``grad`` when the computation runs."""
        return dataclasses.replace(self, **self.checked_parameters())

    @abc.abstractmethod
    def response(self, law, options: Options) -> Response:
        """The solution: jittable, vmappable, never raising (failures go in ``result``)."""

    def metrics(self, law, options: Options) -> tuple[Metrics, RESULTS]:
        """Metrics and result code of one solution (a lighter path where a model has one)."""
        response = self.response(law, options)
        return response.metrics, response.result

    def sweep(self, law, period_ratios: jax.Array, options: Options):
        """Metrics and result codes over a batch of period ratios, in one program: vmapped,
        or solved one ratio after another where ``sweeps_in_turn`` says so."""
        def one(n):
            return self.with_period_ratio(n).metrics(law, options)

        if self.sweeps_in_turn(options):
            return jax.lax.map(one, period_ratios)
        return jax.vmap(one)(period_ratios)

    def sweeps_in_turn(self, options: Options) -> bool:
        """Whether a sweep solves its ratios one after another (``lax.map``) rather than in
        lockstep (``vmap``): right for solutions whose loops run a different number of
        times per ratio, where lockstep runs every ratio for the longest."""
        return False

    def sweep_law(self, law, options: Options, *, like=()):
        """The form of a concrete ``law`` that ``sweep`` takes: the law itself, or (on a
        path that reads only samples of it) those samples as data, which lets laws of
        different types share one compiled sweep (with every law in ``like``)."""
        return law

    def with_array_leaves(self) -> "AbstractModel":
        """This model with its numeric leaves as float arrays: traced, so one compilation
        serves every value (Python floats would be static under ``filter_jit``), and at
        JAX's default precision at least (a float16 or float32 value, concrete or traced,
        is widened: computed in it, R was off by 4e-4 and 6e-8).  A law inside the model
        keeps its own leaves."""
        return jax.tree.map(_as_float, self, is_leaf=lambda x: isinstance(x, AbstractMotionLaw))

    def with_period_ratio(self, period_ratio) -> "AbstractModel":
        """This model at another period ratio (the template of a sweep)."""
        return eqx.tree_at(lambda m: m.period_ratio, self, period_ratio)

    def options(self, method: str | None = None, dwell: float = 1.0, *,
                max_period_ratio: float | None = None, **options) -> "Options":
        """Validated static options for this model (``ValueError`` naming what is wrong)."""
        method = self.methods[0] if method is None else str(method).strip().lower()
        if method not in self.methods:
            raise ValueError(
                f"unknown method {method!r} for {type(self).__name__}; valid methods: "
                f"{', '.join(self.methods)}"
            )
        fields = {f.name for f in dataclasses.fields(self.options_type)} - {"method", "dwell"}
        unknown = sorted(set(options) - fields)
        if unknown:
            raise ValueError(
                f"unknown option {unknown[0]!r} for {type(self).__name__}; valid options: "
                f"{', '.join(sorted(fields)) or 'none'}"
            )
        n = max_period_ratio if max_period_ratio is not None else self._option_scale()
        return self.options_type(method=method, dwell=dwell, **options).checked(n)

    def _option_scale(self) -> float | None:
        """The period ratio that sizes default options (a grid's resolution); ``None``
        when it is traced (then such options must be given explicitly)."""
        return float(self.period_ratio) if is_concrete(self.period_ratio) else None

    def describe(self) -> str:
        """The model and its concrete parameters, for messages."""
        parts = []
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if isinstance(value, float | int) or (hasattr(value, "ndim") and value.ndim == 0):
                try:
                    parts.append(f"{field.name.replace('_', ' ')} {float(value):g}")
                except (TypeError, jax.errors.ConcretizationTypeError):
                    pass
        return f"{type(self).__name__}({', '.join(parts)})"


class AbstractMachineModel(AbstractModel):
    """A model of a whole machine that holds its own cam motion (its rise and fall laws):
    ``camjax.solve(None, model)`` drives it with them, and it has no period-ratio sweep
    (it is not an SDOF-family model)."""


def _as_float(x):
    """A numeric leaf as a float array of at least JAX's default float precision."""
    if isinstance(x, float | int):
        return jnp.asarray(x, dtype=float)
    dtype = getattr(x, "dtype", None)
    if dtype is not None and jnp.issubdtype(dtype, jnp.floating) and (
            jnp.finfo(dtype).bits < jnp.finfo(jax.dtypes.canonicalize_dtype(float)).bits):
        return jnp.asarray(x, dtype=float)
    return x
