"""The linear single-degree-of-freedom (SDOF) model of MISSION.md, and its two paths.

``x'' = w^2 (s - x) + 2 zeta w (s' - x')`` with ``w = 2 pi n``, in normalised time.  camjax
integrates the deflection ``e = s - x`` of the transmission, which obeys
``e'' + 2 zeta w e' + w^2 e = a(tau)`` (no cancellation between ``s`` and ``x``).

- ``method="exact"`` (default) propagates the complex mode ``q = e' - conj(lambda) e``
  in closed form over a grid with the law's breakpoints as nodes
  (``camjax.sdof``, the one engine of every linear path); peaks are refined between nodes, the dwell follows in
  closed form.
- any diffrax solver name (``"tsit5"``, ``"dopri8"``, ``"kvaerno5"``, ``"heun"``, ...)
  integrates the same equation, with ``jump_ts`` at the law's breakpoints, and is checked:
  a fixed-step solver whose numerical free vibration grows past
  ``MAX_FREE_VIBRATION_GROWTH`` over the rise is refused (``unstable_fixed_step``), and
  ``|q| <= Ca`` (its physical bound for ``zeta >= 0``) must hold at every node.
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import checks
from ..checks import require
from ..errors import RESULTS
from ..laws import AbstractMotionLaw, rest_to_rest
from ..sdof import (
    MAX_GRID_INTERVALS,
    MAX_PHASE_STEP,
    SUBSTEPS_PER_INTERVAL,
    MotionGrid,
    SampledLaw,
    check_grid_size,
    checked_peak_search,
    chunk_nodes,
    chunked_map,
    default_resolution,
    eigenvalue,
    integrate,
    mode_gain,
    motion_grid,
    peak_in_motion,
    period_ratio_reach,
    propagate,
    residual_of_mode,
    steps_within,
)
from ..solvers import SOLVERS
from ._base import AbstractModel, Metrics, Options, Response


@dataclasses.dataclass(frozen=True)
class SpringMassOptions(Options):
    """Static settings of an SDOF solution.

    Attributes:
        method: ``"exact"`` or a diffrax solver name (``camjax.solvers.SOLVERS``).
        dwell: dwell after the rise, in motion periods.
        resolution: grid intervals per unit tau; ``None`` picks one from the largest
            period ratio (``default_resolution`` at ``MAX_PHASE_STEP``: ``w h <= 1.5``).
            A coarser one than that is refused.
        rtol, atol: tolerances of adaptive diffrax solvers.
        steps: step count of fixed-step diffrax solvers over the rise (default: three
            times the grid's interval count, ``w h <= 0.5`` per step).
        max_steps: step limit of diffrax solvers; reaching it is an error.
        use_jump_ts: stop adaptive diffrax solvers at the law's breakpoints.
        peak_search: how the peak in motion is refined between nodes, ``"bounded"``
            (default) or ``"dense"`` (``camjax.sdof.PEAK_SEARCHES``): the same answer, the
            dense program cheaper to compile and slower to run.
    """

    method: str = "exact"
    resolution: int | None = None
    rtol: float = 1e-10
    atol: float = 1e-12
    steps: int | None = None
    max_steps: int = 100_000
    use_jump_ts: bool = True
    peak_search: str = "bounded"

    def checked(self, max_period_ratio: float) -> SpringMassOptions:
        base = super().checked(max_period_ratio)
        require(
            self.resolution is not None or max_period_ratio is not None,
            "give resolution= when the period ratio is traced (the grid's size is static)",
        )
        resolution = self.resolution or default_resolution(max_period_ratio, MAX_PHASE_STEP)
        require(int(resolution) >= 8, f"resolution must be at least 8 intervals, got {resolution}")
        reach = f"period ratios up to about {period_ratio_reach(MAX_PHASE_STEP):,.0f}"
        if self.resolution is None:
            check_grid_size(int(resolution), f"a rise at period ratio {max_period_ratio:g}",
                            f"{reach} at the default resolution")
        else:
            check_grid_size(int(resolution), f"a rise at resolution {int(resolution):,}",
                            f"pass resolution at most {MAX_GRID_INTERVALS:,} ({reach})")
        checked_peak_search(self.peak_search)
        for label, value in (("rtol", self.rtol), ("atol", self.atol)):
            require(math.isfinite(value) and value > 0, f"{label} must be positive, got {value}")
        options = dataclasses.replace(
            base, resolution=int(resolution),
            max_steps=checks.positive_integer(self.max_steps, "max_steps"),
            steps=None if self.steps is None else checks.positive_integer(self.steps, "steps"))
        require(max_period_ratio is None or max_period_ratio <= options.largest_period_ratio(),
                f"{options.too_coarse()}, got {max_period_ratio or 0:g}")
        return options

    def largest_period_ratio(self) -> float:
        """The largest period ratio that this grid resolves (``w h <= MAX_PHASE_STEP``)."""
        return period_ratio_reach(MAX_PHASE_STEP, self.resolution)

    def too_coarse(self) -> str:
        """The error for a period ratio past ``largest_period_ratio``."""
        return (f"period ratio must be at most {_down(self.largest_period_ratio()):.4g} on a grid of "
                f"resolution {self.resolution} (give resolution >= "
                f"{2 * math.pi / MAX_PHASE_STEP:.3g} n)")


def _down(value: float, digits: int = 4) -> float:
    """``value`` rounded down to ``digits`` significant digits: a printed limit that the
    largest value it admits does not exceed."""
    scale = 10.0 ** (math.floor(math.log10(value)) - digits + 1)
    return math.floor(value / scale) * scale


class SpringMassResponse(Response):
    """SDOF response; adds the command and the deflection to ``Response``.

    Attributes:
        command_acceleration: the law's acceleration ``s''`` (0 in the dwell).
        deflection: transmission deflection ``e = s - x`` (payload lag, units of stroke).
    """

    command_acceleration: jax.Array
    deflection: jax.Array


class SpringMass(AbstractModel):
    """Payload on an elastic transmission, driven by the cam: the normalised SDOF model.

    Attributes:
        period_ratio: ``n = T f``, motion period over natural period (> 0).
        damping: viscous damping ratio ``zeta`` in ``[0, 1)``.
    """

    period_ratio: float | jax.Array
    damping: float | jax.Array = 0.0
    methods: ClassVar[tuple[str, ...]] = ("exact", *SOLVERS)
    options_type: ClassVar[type[Options]] = SpringMassOptions

    def checked_parameters(self) -> dict:
        return {
            "period_ratio": checks.positive(self.period_ratio, "period ratio"),
            "damping": checks.damping_ratio(self.damping),
        }

    def response(self, law, options) -> SpringMassResponse:
        model = self.validated()
        grid, q, result, steps = _mode(law, model, options)
        metrics = _metrics(q, grid, model, law.Ca, options)
        omega, zeta = model.omega, model.damping
        lam = eigenvalue(omega, zeta)
        # Sampled at the nodes and, exactly, at SUBSTEPS_PER_INTERVAL parts of every interval
        # (w h / 3 <= 0.5: a smooth curve to plot), and as densely over the dwell.
        widest = jnp.max(grid.piece_width)
        inside = [steps_within(q[:-1], grid.forcing, grid.widths, widest, lam, k / SUBSTEPS_PER_INTERVAL)
                  for k in range(1, SUBSTEPS_PER_INTERVAL)]
        q_rise = jnp.concatenate([jnp.stack([q[:-1], *inside], axis=1).reshape(-1), q[-1:]])
        t_rise = grid.nodes[:-1, None] + grid.widths[:, None] * (
            np.arange(SUBSTEPS_PER_INTERVAL) / SUBSTEPS_PER_INTERVAL)
        dwell_samples = max(1, math.ceil(options.dwell * SUBSTEPS_PER_INTERVAL * options.resolution))
        t_dwell = jnp.linspace(0.0, options.dwell, dwell_samples + 1)[1:]
        q_all = jnp.concatenate([q_rise, q[-1] * jnp.exp(lam * t_dwell)])
        tau = jnp.concatenate([t_rise.reshape(-1), grid.nodes[-1:], 1.0 + t_dwell])
        return SpringMassResponse(
            tau=tau,
            payload_acceleration=jnp.real(mode_gain(omega, zeta) * q_all),
            metrics=metrics,
            result=result,
            stats={"steps": jnp.asarray(steps)},
            command_acceleration=law.a(tau),
            deflection=jnp.imag(q_all) / jnp.imag(lam),
        )

    def metrics(self, law, options):
        model = self.validated()
        grid, q, result, _ = _mode(law, model, options)
        return _metrics(q, grid, model, law.Ca, options), result

    def sweep(self, law, period_ratios, options):
        metrics, result, _ = batch_metrics(law, period_ratios, self.damping, options)
        return metrics, result

    def sweep_law(self, law, options, *, like=()):
        """On the exact path, the law's grid as data (``SampledLaw``), padded to as many
        pieces as any law in ``like`` needs: every standard law (and a designed spline
        beside them) then sweeps in one compiled program."""
        if options.method != "exact":
            return law
        pieces = [SampledLaw.pieces_if_sampled(x) for x in (law, *like)]
        if pieces[0] is None:
            return law
        return SampledLaw.of(law, options.resolution, max(p for p in pieces if p is not None))


# --- the two paths ------------------------------------------------------------------


def _grid(law, options: SpringMassOptions) -> MotionGrid:
    if isinstance(law, SampledLaw):
        if options.method != "exact":
            raise ValueError(f"a SampledLaw serves the exact path only, not {options.method!r}")
        return law.grid
    return motion_grid(law, options.resolution)


def _mode_at_nodes(law, grid, model: SpringMass, options: SpringMassOptions):
    """Complex mode at the nodes, result code and steps taken, by the engine's exact step
    or its diffrax path."""
    omega, zeta = model.omega, model.damping
    if options.method == "exact":
        q = propagate(grid, omega, zeta, resolved=True)  # _resolved, or the sweep's checks
        ok = jnp.all(jnp.isfinite(q))
        return q, RESULTS.where(ok, RESULTS.successful, RESULTS.nonfinite), grid.piece.size
    return integrate(law, grid, omega, zeta, method=options.method, steps=options.steps,
                     rtol=options.rtol, atol=options.atol, max_steps=options.max_steps,
                     use_jump_ts=options.use_jump_ts)


def _resolved(model: SpringMass, options: SpringMassOptions) -> SpringMass:
    """``model`` with its period ratio checked against the grid's ``MAX_PHASE_STEP``, which
    the exact propagation and every refined peak need (concretely now, traced when the
    computation runs; a sweep checks its ratios concretely before, ``checked_outside``)."""
    if options.resolution is None:
        return model
    n = checks.ensure(model.period_ratio, lambda v: v <= options.largest_period_ratio(),
                      options.too_coarse())
    return dataclasses.replace(model, period_ratio=n)


def _mode(law, model, options):
    grid = _grid(law, options)
    model = _resolved(model, options)
    q, result, steps = _mode_at_nodes(law, grid, model, options)
    return grid, q, result, steps


def _metrics(q, grid, model: SpringMass, ca, options: SpringMassOptions) -> Metrics:
    omega, zeta = model.omega, model.damping
    in_motion = peak_in_motion(q, grid, omega, zeta, options.peak_search)
    in_dwell = residual_of_mode(q[-1], omega, zeta, options.dwell)  # the residual: max |x''| in the dwell
    return Metrics(jnp.maximum(in_motion, in_dwell) / ca, in_dwell / ca, in_motion / ca)


def response_metrics(law: AbstractMotionLaw, model: SpringMass, options: SpringMassOptions) -> Metrics:
    """Metrics of one response, jittable and differentiable (inputs checked even traced)."""
    return model.metrics(law, options)[0]


@eqx.filter_jit
def batch_metrics(law, period_ratio, damping, options: SpringMassOptions):
    """Metrics over a batch of period ratios from one compiled, vmapped call.

    The grid and the sampled forcing depend on the law alone, so they are built once and
    shared across the batch, which runs through the engine's ``chunked_map``.  Returns ``(Metrics, result, steps)``.  The
    low-level engine of ``camjax.ct_curve``: it does not check its inputs (the callers do).
    ``law`` may be a ``SampledLaw`` (exact path only).
    """
    grid = _grid(law, options)

    def one(n):
        model = _resolved(SpringMass(n, damping), options)  # ct_curve checks concretely
        q, result, steps = _mode_at_nodes(law, grid, model, options)
        return _metrics(q, grid, model, law.Ca, options), result, steps

    return chunked_map(one, period_ratio, grid.nodes.shape[0], chunk_nodes(options.sweep))


TRACED_RESOLUTION = 704
"""Grid of ``torsion_factor`` and ``residual_vibration`` for a traced period ratio when no
``resolution`` is given (a concrete one sizes its own grid, ``default_resolution``, up to
``MAX_GRID_INTERVALS``): period ratios up to about 168 (``w h <= MAX_PHASE_STEP``).  A
grid's size is static under a trace, and one sized for the concrete call's reach (2**20
intervals, n up to 250,329) took 1.6 s a call and 1.4 GB where this one takes
milliseconds: past 168 the error says which ``resolution`` to pass."""


def _traced_too_coarse() -> str:
    """The error for a traced period ratio past ``TRACED_RESOLUTION``'s reach: how to pass
    a grid that reaches further (4.19 intervals per unit of n)."""
    per_n = 2 * math.pi / MAX_PHASE_STEP
    return (f"period ratio must be at most {_down(period_ratio_reach(MAX_PHASE_STEP, TRACED_RESOLUTION)):.4g} "
            f"on a traced period ratio's default grid (resolution {TRACED_RESOLUTION}; a concrete one "
            f"sizes its own): pass resolution >= {per_n:.3g} n, up to {MAX_GRID_INTERVALS:,} "
            f"(n <= {_down(period_ratio_reach(MAX_PHASE_STEP), 6):,.0f}), such as "
            f"torsion_factor(law, n, resolution=4096) for n <= {_down(4096 / per_n, 3):.3g}")


def _exact_metrics(law, period_ratio, damping, dwell, resolution, tool: str) -> Metrics:
    """Metrics of the exact path on a grid sized to the period ratio, or refused.

    A concrete period ratio gets the default grid (``SpringMassOptions``; refused above
    ``MAX_GRID_INTERVALS``); a traced one gets ``resolution`` (``TRACED_RESOLUTION`` if
    ``None``), and a period ratio past what that grid resolves raises, when the
    computation runs, instead of returning a wrong number.
    """
    law = rest_to_rest(law, tool)
    for value, name in ((period_ratio, "period_ratio"), (damping, "damping")):
        _one_number(value, name)
    model = SpringMass(period_ratio, damping)  # concrete values checked here
    if resolution is None and model._option_scale() is None:
        resolution = TRACED_RESOLUTION
        reach = period_ratio_reach(MAX_PHASE_STEP, TRACED_RESOLUTION)  # the grid's own check's
        model = SpringMass(checks.ensure(period_ratio, lambda v: v <= reach, _traced_too_coarse()), damping)
    options = model.options("exact", dwell, resolution=resolution)
    model = model.with_array_leaves()
    with checks.as_value_errors():
        return _compiled_metrics(law, model, options, checks.is_concrete(law, model))


def _one_number(value, name: str) -> None:
    """A ``ValueError`` naming ``name`` unless ``value`` is one real number (or a scalar
    tracer): an array belongs in ``ct_curve`` or under ``jax.vmap``."""
    try:
        numeric = jnp.issubdtype(jnp.result_type(value), jnp.number) and not isinstance(value, str)
    except TypeError:
        numeric = False
    if not numeric or jnp.iscomplexobj(value) or jnp.ndim(value) != 0:
        shown = f"shape {jnp.shape(value)}" if numeric and jnp.ndim(value) else repr(value)
        raise ValueError(f"{name} must be one real number (for several period ratios use "
                         f"camjax.ct_curve, or jax.vmap), got {shown}")


@eqx.filter_jit
def _compiled_metrics(law, model: SpringMass, options: SpringMassOptions, checked: bool):
    # One program per law type and grid size: eagerly, the path runs op by op.  Inside a
    # caller's jit it is inlined.  ``checked``: every input was checked concretely.
    with checks.checked_outside(checked):
        return response_metrics(law, model, options)


def torsion_factor(law, period_ratio, damping=0.0, *, dwell=1.0, resolution=None):
    """Ct of the exact path, jittable and differentiable in every argument's leaves.

    ``law`` is a motion law or its name.  A concrete period ratio sizes the grid
    (``resolution=None``); a traced one (inside ``jit``, ``vmap``, ``grad``) uses
    ``resolution`` (default ``TRACED_RESOLUTION``, n up to 168; pass at least 4.19 n for a
    larger one, such as ``resolution=4096`` for n up to 977).  A non-positive or NaN period ratio, one
    past what the grid resolves, damping outside ``[0, 1)`` or invalid law parameters
    raise, even under ``jit``, ``vmap`` and ``grad``.
    """
    return _exact_metrics(law, period_ratio, damping, dwell, resolution, "torsion_factor").ct


def residual_vibration(law, period_ratio, damping=0.0, *, resolution=None):
    """Residual vibration R (units of Ca) of the exact path, jittable and differentiable;
    the law, grid and checks as in ``torsion_factor``."""
    return _exact_metrics(law, period_ratio, damping, 1.0, resolution, "residual_vibration").residual


# --- physical inputs ------------------------------------------------------------------


def natural_frequency(
    *,
    mass: float | None = None,
    stiffness: float | None = None,
    inertia: float | None = None,
    torsional_rigidity: float | None = None,
) -> float:
    """Natural frequency in Hz: ``sqrt(S/W)/(2 pi)`` (linear) or ``sqrt(R/I)/(2 pi)`` (rotary)."""
    linear = mass is not None or stiffness is not None
    rotary = inertia is not None or torsional_rigidity is not None
    require(
        linear != rotary,
        "give either mass and stiffness (linear) or inertia and torsional_rigidity (rotary)",
    )
    pairs = (("mass", mass), ("stiffness", stiffness)) if linear else (
        ("inertia", inertia),
        ("torsional_rigidity", torsional_rigidity),
    )
    for label, value in pairs:
        require(value is not None, f"{label} is missing")
        require(_real(value, label) > 0, f"{label} must be positive, got {value}")
    inert, stiff = float(pairs[0][1]), float(pairs[1][1])
    return math.sqrt(stiff / inert) / (2 * math.pi)


def period_ratio(motion_time: float, **physical: float) -> float:
    """Period ratio ``n = T f`` from the motion time ``T`` (s) and physical properties.

    ``period_ratio(0.05, mass=2.0, stiffness=4e6)`` or
    ``period_ratio(0.05, inertia=0.01, torsional_rigidity=2e4)`` (SI units).
    """
    require(_real(motion_time, "motion_time") > 0, f"motion_time must be positive, got {motion_time}")
    return float(motion_time) * natural_frequency(**physical)


def _real(value, name: str) -> float:
    """``value`` as a finite float, or a one-line ``ValueError`` naming ``name`` (a string
    such as ``"0.05"`` is refused, not read)."""
    try:
        number = float(value) if not isinstance(value, str | bytes | bool) else None
    except (TypeError, ValueError):
        number = None
    require(number is not None and math.isfinite(number),
            f"{name} must be a finite number (SI units), got {value!r}")
    return number


