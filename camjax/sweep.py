"""Batched sweeps: Ct and residual curves over many period ratios in one compiled call."""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Iterable, Mapping

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import checks
from .errors import RESULTS, mark_failures, promote, raise_if_failed, result_names
from .laws import AbstractMotionLaw, as_law, rest_to_rest
from .models import AbstractMachineModel, AbstractModel, SpringMass
from .sdof import MAX_PHASE_STEP, default_resolution, map_in_chunks, stack_laws
from .sharding import on_cpu, outside_traces, shard_batch, sweep_jit

STACK_FROM = 8
"""Laws of one structure are stacked into one mapped call from this many on (fewer are
called one by one: the compiled program is shared either way, and a stack re-traces)."""


class CtCurve(eqx.Module):
    """Ct, residual and peak-in-motion of one law over a set of period ratios.

    All values are in units of the law's Ca (multiply by ``ca`` for units of h/T^2).
    ``model`` names the model swept (its parameters other than the period ratio).
    ``result`` is the ``RESULTS`` code of each ratio (``None``: not recorded); a sweep with
    ``throw=False`` keeps the ratios where the solver failed, their metrics NaN.
    """

    period_ratio: np.ndarray
    ct: np.ndarray
    residual: np.ndarray
    peak_in_motion: np.ndarray
    ca: float
    name: str = eqx.field(static=True)
    damping: float = eqx.field(static=True, default=0.0)
    method: str = eqx.field(static=True, default="exact")
    model: str = eqx.field(static=True, default="SpringMass")
    result: RESULTS | None = None

    @property
    def failed(self) -> np.ndarray:
        """Whether the solver failed at each period ratio (its metrics are then NaN)."""
        if self.result is None:
            return np.zeros(np.shape(self.period_ratio), bool)
        return np.asarray(self.result._value) != np.asarray(RESULTS.successful._value)

    @property
    def result_names(self) -> list[str]:
        """The result code of each period ratio by name: ``"successful"`` or the failure's."""
        if self.result is None:
            return ["successful"] * np.size(self.period_ratio)
        return result_names(self.result)

    @property
    def ca_ct(self) -> np.ndarray:
        """Peak inertia load ``Ca * Ct`` in units of h/T^2 (the figure to compare laws by)."""
        return self.ca * self.ct


# The sweeps check their period ratios and template concretely (prepare_sweep), so they
# trace without runtime checks (``checks.checked_outside``): their programs then load
# from JAX's persistent compilation cache.


@sweep_jit
def sweep_program(law, template: AbstractModel, period_ratios, options):
    """``template.sweep`` of one law over period ratios, jitted (``sharding.sweep_jit``):
    the program ``sweep_metrics`` runs, split over devices by ``shard_batch``.  Checks
    nothing: its arguments come from :func:`prepare_sweep`."""
    with checks.checked_outside():
        return template.sweep(law, period_ratios, options)


@sweep_jit
def _sweep_stack(laws, template: AbstractModel, period_ratios, options):
    # On a CPU one law at a time (lax.map): memory stays that of one law's sweep whatever
    # the stack's size, and each law keeps its cache-sized ratio chunks (a vmap over laws
    # multiplies the working set and ran 1.4x slower).  A GPU takes several laws at once.
    with checks.checked_outside():
        return map_in_chunks(lambda law: template.sweep(law, period_ratios, options), laws,
                             laws_at_once(template, options, period_ratios.shape[0]))


def laws_at_once(template: AbstractModel, options, ratios: int) -> int:
    """Laws of a stack swept at once (``camjax.sdof.stack_laws``): bounded by the exact
    path's grid nodes; one at a time for a model that solves its ratios in turn (lockstep
    would run every law for the longest)."""
    if template.sweeps_in_turn(options):
        return 1
    return stack_laws(ratios, getattr(options, "resolution", None) or 1, options.sweep)


def stack_of(laws) -> AbstractMotionLaw:
    """Laws of one pytree structure stacked on a new leading axis of every leaf: NumPy where
    every law holds that leaf on the host (one transfer when the stack is swept, rather
    than one per law)."""
    def stack(*leaves):
        if all(isinstance(x, np.ndarray) for x in leaves):
            return np.stack(leaves)
        return jnp.stack(leaves)

    return jax.tree.map(stack, *laws)


@eqx.filter_jit
def stacked_ca(laws) -> jax.Array:
    """``Ca`` of every law of a stack (laws on axis 0 of every leaf), in one compiled call
    (law by law, eagerly, it runs op by op: 0.1 ms a law; compiled once per stack size,
    as the stack's sweep is)."""
    return jax.vmap(lambda law: jnp.asarray(law.Ca, float))(laws)


def sweep_metrics(law, period_ratios, template: AbstractModel, options, *, devices=None, like=()):
    """``(Metrics, result)`` of ``law`` at every period ratio, split over ``devices``.

    The low-level form of :func:`ct_curve` (no checks): ``template`` and ``options`` come
    from :func:`prepare_sweep`; ``like`` are laws that should share its compiled program
    (``AbstractModel.sweep_law``).
    """
    return shard_batch(sweep_program, template.sweep_law(law, options, like=like), template,
                       jnp.asarray(period_ratios), options, batched_argnums=2, devices=devices)


def sweep_law_stack(laws, period_ratios, template: AbstractModel, options, *, devices=None):
    """``(Metrics, result)`` of a stack of laws (laws on axis 0 of every leaf), shapes
    ``(laws, ratios)``; the laws are split over ``devices``."""
    return shard_batch(_sweep_stack, laws, template, jnp.asarray(period_ratios), options,
                       batched_argnums=0, devices=devices)


def resolution_bands(period_ratios, options, *, phase_step: float = MAX_PHASE_STEP
                     ) -> list[tuple[np.ndarray, object]]:
    """Groups of the period ratios that each get the default grid of their own largest.

    The exact path's grid is sized by the largest period ratio of a call
    (``default_resolution``: the same phase step ``w h`` at every ratio would need fewer
    intervals at small ratios).  Ratios whose own default resolution is the same form one
    band, solved with that resolution: every ratio then meets the default phase step,
    the error bound of the default grid, and a sweep over [1, 30] does about 60% of the
    work.  Each band is one compiled program (its grid size is static).

    Returns ``[(indices into period_ratios, options of the band)]``: each band's options
    are ``options`` with its own resolution (whatever ``options`` held); options of
    another method (no grid) give one band of every ratio.  Off the CPU every ratio
    takes the largest band's grid: a GPU sweeps the finer grid in about the time of the
    bands, and each band is one more program to compile (6-7 s each on an H200).
    """
    n = np.asarray(period_ratios, dtype=float)
    if getattr(options, "method", None) != "exact" or getattr(options, "resolution", None) is None:
        return [(np.arange(n.size), options)]
    needed = np.asarray([default_resolution(x, phase_step) for x in n])
    if not on_cpu():
        needed = np.full(n.size, needed.max())
    bands = []
    for resolution in np.unique(needed):
        chosen = np.flatnonzero(needed == resolution)
        bands.append((chosen, dataclasses.replace(options, resolution=int(resolution))))
    return bands


def sweep_banded(sweep, laws, period_ratios, template: AbstractModel, options, *, devices=None,
                 phase_step: float = MAX_PHASE_STEP):
    """``sweep`` (:func:`sweep_metrics` or :func:`sweep_law_stack`) run band by band of
    :func:`resolution_bands`, each band at its own grid, reassembled along the ratio axis
    (the last) in the order of ``period_ratios``.

    Only options with an exact-path grid are banded (``SpringMass``'s, whose grid needs
    depend on ``n`` alone); any other model's run as one band, unchanged.
    """
    n = np.asarray(period_ratios, dtype=float)
    parts = [(chosen, sweep(laws, jnp.asarray(n[chosen]), template, band_options, devices=devices))
             for chosen, band_options in resolution_bands(n, options, phase_step=phase_step)]
    if len(parts) == 1:
        return parts[0][1]
    order = np.argsort(np.concatenate([chosen for chosen, _ in parts]), kind="stable")
    return jax.tree.map(lambda *x: jnp.concatenate(x, axis=-1)[..., order],
                        *(out for _, out in parts))


def _template(model, damping) -> AbstractModel:
    if model is None:
        return SpringMass(1.0, damping)
    if not isinstance(model, AbstractModel):
        raise TypeError(f"model must be a camjax model, got {type(model).__name__}")
    if damping != 0.0:
        raise ValueError(
            "give the damping in the model (e.g. CoulombFriction(1.0, mu, damping=0.05)), "
            "not as the damping argument, when a model is given"
        )
    if isinstance(model, AbstractMachineModel):
        raise TypeError(f"{type(model).__name__} has no period-ratio sweep (it is not an SDOF-family model)")
    return model


def prepare_sweep(period_ratios, model=None, damping=0.0, method=None, dwell=1.0, **solver_options):
    """Checked period ratios, the model template (array leaves) and its static options."""
    if outside_traces() is False:
        raise ValueError(
            "a sweep (ct_curve, ct_curves) runs outside jit, vmap and grad, since its results "
            "are NumPy arrays; inside them use camjax.torsion_factor or "
            "camjax.residual_vibration, which trace")
    n = checks.period_ratios(period_ratios)
    if model is None:  # the default model: its template and options depend on numbers alone
        key = _typed((damping, method, dwell, *sorted(solver_options.items())))
        try:
            hash(key)
        except TypeError:  # an array or other unhashable value: built (and checked) anew
            key = None
        if key is not None:
            return (n, *_default_template(key, float(n[0]), float(n.max())))
    return (n, *_template_and_options(model, damping, method, dwell, n[0], n.max(), solver_options))


def _typed(values) -> tuple:
    """``values`` with their types, so that equal numbers of other types (``1e5`` and
    ``100000``, ``True`` and ``1``) are kept apart: the checks tell them apart."""
    return tuple((type(v), _typed(v) if isinstance(v, tuple) else v) for v in values)


def _template_and_options(model, damping, method, dwell, first, largest, solver_options):
    template = _template(model, damping).with_period_ratio(float(first)).validated()
    options = template.options(method, dwell, max_period_ratio=float(largest), **solver_options)
    return template.with_array_leaves(), options


@functools.lru_cache(maxsize=16)
def _default_template(key, first, largest):
    """The default model's template and options for ``prepare_sweep``'s typed ``key``, kept
    (a warm ``ct_curve`` spent 0.3-0.5 ms building them).  Built as concrete arrays even
    when called while tracing (a ``ct_curve`` inside ``jit``), so that no tracer is kept."""
    damping, method, dwell = (value for _, value in key[:3])
    options = {name: value for _, ((_, name), (_, value)) in key[3:]}
    with jax.ensure_compile_time_eval():
        return _template_and_options(None, damping, method, dwell, first, largest, options)


def _curves(names, laws, n, template, options, metrics, result, throw: bool, cas=None, *,
            name_laws: bool = True) -> list[CtCurve]:
    """The curves of laws swept alike (``metrics`` and ``result`` with a leading law axis):
    raising at the first failed ratio (``throw``; the error names its law with
    ``name_laws``), or with the failed ratios marked (NaN metrics, their codes in
    ``result``).  ``names``: each law's name, as the caller has it; ``cas``: each law's Ca
    when the caller has them (a stack's, from ``stacked_ca``).

    The checks run once over the whole ``(laws, ratios)`` batch: law by law they took 33
    ms of a 256-law stack's 0.41 s ``ct_curves``, now 20 ms with the curves built."""
    count = len(laws)
    if throw:
        def describe(i):
            law, ratio = divmod(i, n.size)
            return (f"{options.method} solve of {template.with_period_ratio(n[ratio]).describe()}"
                    + (f" with {names[law]}" if name_laws else ""))

        raise_if_failed(_flat(result), describe, *(np.reshape(v, -1) for v in
                                                   (metrics.ct, metrics.residual)),
                        entries="law and ratio pairs" if count > 1 else "")
    result, values = mark_failures(_flat(result), *(np.reshape(v, -1) for v in
                                                     (metrics.ct, metrics.residual, metrics.peak_in_motion)))
    ct, residual, peak_in_motion = (v.reshape(count, n.size) for v in values)
    codes = np.asarray(result._value).reshape(count, n.size)
    damping = float(getattr(template, "damping", 0.0))
    model = type(template).__name__
    if cas is None:
        cas = [law.peak_coefficients()["Ca"] for law in laws]
    return [CtCurve(period_ratio=n, ct=ct[i], residual=residual[i], peak_in_motion=peak_in_motion[i],
                    ca=float(cas[i]), name=names[i], damping=damping, method=options.method,
                    model=model, result=type(result)(codes[i], RESULTS))
            for i in range(count)]


def _stacked(*sweeps):
    """``(Metrics, result)`` of several one-law sweeps with a leading law axis."""
    return jax.tree.map(lambda *x: np.stack([np.asarray(v) for v in x]), *sweeps)


def _flat(result) -> RESULTS:
    """A batch's result codes on one axis (the checks' batch)."""
    return jax.tree.map(lambda codes: np.reshape(np.asarray(codes), -1), promote(result))


def ct_curve(
    law: AbstractMotionLaw | str,
    period_ratios,
    *,
    model: AbstractModel | None = None,
    damping: float = 0.0,
    method: str | None = None,
    dwell: float = 1.0,
    devices=None,
    throw: bool = True,
    **solver_options,
) -> CtCurve:
    """Ct, residual vibration and peak in motion of ``law`` at every period ratio.

    One compiled, vmapped call covers the whole batch.

    Args:
        law: the rise, or its name (``"cycloidal"``, ``"scca:0.25,0,0.75"``).
        period_ratios: positive finite period ratios (1-D).
        model: a model instance used as a template whose period ratio is swept
            (``SpringMass`` by default; also ``CoulombFriction``,
            ``Backlash``, ``TwoMass``), e.g.
            ``model=TwoMass(period_ratio=1.0, stiffness_ratio=1.0, inertia_ratio=1.0)``.
        damping: damping ratio of the default SpringMass (give it in ``model`` otherwise).
        method: solution method (default: the model's; for SpringMass ``"exact"``).
        dwell: dwell after the rise, in motion periods.
        devices: the local devices to split the ratios over (default: every local device;
            see ``camjax.sharding.shard_batch``); results equal the single-device run.
        throw: raise ``SolverError`` if the solver failed at any period ratio (default, as
            ``camjax.solve``); with ``throw=False`` the sweep finishes, and the failed
            ratios have NaN metrics and their code in the curve's ``result``.
        solver_options: the model's static options (e.g. ``resolution``, ``rtol``).

    Raises:
        ValueError: bad input, named; or a call inside ``jit``, ``vmap`` or ``grad`` (the
            curve is NumPy: ``camjax.torsion_factor`` and ``camjax.residual_vibration``
            trace).
        SolverError: the solver failed at any period ratio (the first is named), with
            ``throw=True``.
    """
    law = rest_to_rest(law, "ct_curve")
    n, template, options = prepare_sweep(period_ratios, model, damping, method, dwell, **solver_options)
    metrics, result = jax.device_get(sweep_metrics(law, n, template, options, devices=devices))
    return _curves([law.name], [law], n, template, options, *_stacked((metrics, result)), throw,
                   name_laws=False)[0]


def ct_curves(
    laws: Iterable[AbstractMotionLaw] | Mapping[str, AbstractMotionLaw],
    period_ratios,
    *,
    model: AbstractModel | None = None,
    damping: float = 0.0,
    method: str | None = None,
    dwell: float = 1.0,
    devices=None,
    like: Iterable[AbstractMotionLaw] = (),
    throw: bool = True,
    **solver_options,
) -> dict[str, CtCurve]:
    """``ct_curve`` for several laws (or law names), keyed by name (or by the mapping's
    keys); ``throw`` as there.

    On the exact path every law with fixed breakpoints is swept from its samples
    (``camjax.sdof.SampledLaw``, padded to the piece count of the longest law
    given, in ``laws`` or ``like``), so laws of any type share one compiled program;
    elsewhere laws of one pytree structure (any ``SCCA``, or ``BSplineLaw`` of one size)
    do.  A stack of more than a few laws of one structure is mapped in one call, split over
    ``devices``.  ``like`` (not swept) lets a later call share the program: a spline of the
    size being designed, say.
    """
    if isinstance(laws, str):
        raise TypeError("laws must be a list of laws or law names (or a mapping), not one name")
    if isinstance(laws, Mapping):
        named = {key: rest_to_rest(law, "ct_curves") for key, law in laws.items()}
        names = {key: law.name for key, law in named.items()}
    else:
        named = {law.name: law for law in (rest_to_rest(x, "ct_curves") for x in laws)}
        names = {key: key for key in named}  # each name computed once (an SCCA's: 20 us)
    like = [*named.values(), *map(as_law, like)]
    n, template, options = prepare_sweep(period_ratios, model, damping, method, dwell, **solver_options)
    groups: dict = {}
    for key, law in named.items():
        groups.setdefault(jax.tree.structure(law), []).append(key)
    curves = {}
    ratios = jnp.asarray(n)
    for keys in groups.values():
        members = [named[k] for k in keys]
        if len(members) <= STACK_FROM or not jax.tree.leaves(members[0]):
            # A few laws: one call each reuses the compiled program of the structure.
            out = _stacked(*(jax.device_get(sweep_metrics(m, ratios, template, options,
                                                          devices=devices, like=like))
                             for m in members))
            cas = None
        else:
            stacked = stack_of(members)
            # One transfer out; the curves are NumPy slices of it.
            out = jax.device_get(sweep_law_stack(stacked, ratios, template, options, devices=devices))
            cas = np.asarray(stacked_ca(stacked))
        found = _curves([names[k] for k in keys], members, n, template, options, *out, throw, cas)
        curves.update(zip(keys, found))
    return {key: curves[key] for key in named}
