"""One interface over both solution paths: ``solve`` and the metrics of a response."""

from __future__ import annotations

import dataclasses

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import SolverError
from ..laws import AbstractMotionLaw
from ..metrics import refined_peak
from ..models import SpringMass
from ..models._spring_mass import check_damping, check_period_ratios
from ._exact import eigenvalue, propagate
from ._grid import MotionGrid, default_resolution, motion_grid
from ._ode import FIXED_STEP_SOLVERS, MAX_FREE_VIBRATION_GROWTH, check_method, integrate


@dataclasses.dataclass(frozen=True)
class SolveOptions:
    """Static settings of a solution (each distinct value compiles once).

    Attributes:
        method: ``"exact"`` or a diffrax solver name (see ``camjax.propagation.SOLVERS``).
        dwell: length of the dwell after the rise, in motion periods (Ct looks over it).
        resolution: grid intervals per unit tau; ``None`` picks one from the largest
            period ratio (``default_resolution``).
        rtol, atol: tolerances of adaptive diffrax solvers.
        steps: step count of fixed-step diffrax solvers over the rise (default: the
            grid's interval count).
        max_steps: step limit of diffrax solvers; reaching it is an error.
        use_jump_ts: stop adaptive diffrax solvers at the law's breakpoints.
    """

    method: str = "exact"
    dwell: float = 1.0
    resolution: int | None = None
    rtol: float = 1e-10
    atol: float = 1e-12
    steps: int | None = None
    max_steps: int = 100_000
    use_jump_ts: bool = True

    def checked(self, max_period_ratio: float) -> SolveOptions:
        """These options validated, with the resolution filled in."""
        method = check_method(self.method)
        dwell = float(self.dwell)
        if not (np.isfinite(dwell) and dwell >= 0):
            raise ValueError(f"dwell must be a non-negative number of motion periods, got {dwell}")
        resolution = self.resolution or default_resolution(max_period_ratio)
        if int(resolution) < 8:
            raise ValueError(f"resolution must be at least 8 intervals, got {resolution}")
        for label, value in (("rtol", self.rtol), ("atol", self.atol)):
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{label} must be positive, got {value}")
        if self.steps is not None and int(self.steps) < 1:
            raise ValueError(f"steps must be a positive integer, got {self.steps}")
        return dataclasses.replace(self, method=method, dwell=dwell, resolution=int(resolution))


class Metrics(eqx.Module):
    """Response metrics in units of the law's Ca (multiply by Ca for units of h/T^2).

    Attributes:
        ct: torsion factor, max |x''| over the rise and the following dwell, over Ca.
        residual: amplitude of the payload-acceleration vibration at the start of the
            dwell, over Ca (it decays as ``exp(-zeta w t)`` afterwards).
        peak_in_motion: max |x''| over the rise alone, over Ca.
    """

    ct: jax.Array
    residual: jax.Array
    peak_in_motion: jax.Array


def _mode_gain(omega, zeta):
    """``K`` with ``x'' = Re(K q)`` (payload acceleration from the complex mode)."""
    damped = omega * jnp.sqrt(1.0 - zeta**2)
    return 2 * zeta * omega - 1j * omega**2 * (1 - 2 * zeta**2) / damped


def _dwell_peak(q_end, omega, zeta, dwell: float):
    """Max |x''| over the free vibration of the dwell, in closed form.

    ``x''(t) = Re(K q_end exp(lambda t))``; its extrema shrink by ``exp(-zeta w pi/w_d)``
    each half period, so the maximum is at ``t = 0`` or at the first extremum (or the
    dwell's end if that comes first).
    """
    lam = eigenvalue(omega, zeta)
    amplitude = _mode_gain(omega, zeta) * q_end
    first = jnp.mod(jnp.pi / 2 - jnp.angle(amplitude * lam), jnp.pi) / jnp.imag(lam)
    t = jnp.minimum(first, dwell)
    return jnp.maximum(jnp.abs(jnp.real(amplitude)), jnp.abs(jnp.real(amplitude * jnp.exp(lam * t))))


def _peak_in_motion(q, grid: MotionGrid, omega, zeta):
    """Max |x''| over the rise: ``x'' = Re(K q)`` sampled at the nodes, then refined.

    The refinement needs the next three derivatives at the ends of every interval,
    ``Re(K (lambda^k q + lambda^(k-1) a + ...))`` with one-sided ``a``, jerk and snap.
    """
    lam = eigenvalue(omega, zeta)
    gain = _mode_gain(omega, zeta)

    def at(q_end, forcing):
        d1 = lam * q_end + forcing[:, 0]
        d2 = lam * d1 + forcing[:, 1]
        d3 = lam * d2 + forcing[:, 2]
        return jnp.real(gain * jnp.stack([d1, d2, d3], axis=1))

    left, right = grid.one_sided()
    return refined_peak(jnp.real(gain * q), grid.widths, at(q[:-1], left), at(q[1:], right))


def _mode_at_nodes(law, grid, model: SpringMass, options: SolveOptions):
    """Complex mode at the nodes, diffrax result (or ``None``) and steps taken."""
    omega, zeta = model.omega, model.damping
    if options.method == "exact":
        return propagate(grid, omega, zeta), diffrax.RESULTS.successful, grid.piece.size
    steps = options.steps or grid.piece.size
    e, de, result, n_steps = integrate(
        law, grid, omega, zeta, method=options.method, rtol=options.rtol, atol=options.atol,
        steps=steps, max_steps=options.max_steps, use_jump_ts=options.use_jump_ts,
    )
    return de - jnp.conj(eigenvalue(omega, zeta)) * e, result, n_steps


def _metrics(q, grid, model: SpringMass, ca, dwell: float) -> Metrics:
    omega, zeta = model.omega, model.damping
    in_motion = _peak_in_motion(q, grid, omega, zeta)
    in_dwell = _dwell_peak(q[-1], omega, zeta, dwell)
    residual = omega * jnp.abs(q[-1]) / jnp.sqrt(1.0 - zeta**2)
    return Metrics(jnp.maximum(in_motion, in_dwell) / ca, residual / ca, in_motion / ca)


def response_metrics(law: AbstractMotionLaw, model: SpringMass, options: SolveOptions) -> Metrics:
    """Metrics of one response, jittable and differentiable (no failure checks)."""
    grid = motion_grid(law, options.resolution)
    q, _, _ = _mode_at_nodes(law, grid, model, options)
    return _metrics(q, grid, model, law.Ca, options.dwell)


CHUNK_NODES = 65536
"""Grid nodes (ratios x nodes per ratio) that ``batch_metrics`` vmaps over at once."""


@eqx.filter_jit
def batch_metrics(law, period_ratio, damping, options: SolveOptions):
    """Metrics over a batch of period ratios from one compiled, vmapped call.

    The grid and the sampled forcing depend on the law alone, so they are built once and
    shared across the batch.  The batch runs in vmapped chunks of about ``CHUNK_NODES``
    grid nodes, which keeps the working set in cache (twice as fast as one vmap over
    1000 ratios on CPU) and memory bounded.  Returns ``(Metrics, diffrax result, steps)``.
    """
    grid = motion_grid(law, options.resolution)

    def one(n):
        model = SpringMass(n, damping)
        q, result, steps = _mode_at_nodes(law, grid, model, options)
        return _metrics(q, grid, model, law.Ca, options.dwell), result, steps

    size = period_ratio.shape[0]
    chunks = -(-size // max(1, CHUNK_NODES // grid.nodes.shape[0]))
    padded = jnp.pad(period_ratio, (0, (-size) % chunks), mode="edge")  # equal chunks: one body
    out = jax.lax.map(jax.vmap(one), padded.reshape(chunks, -1))
    return jax.tree.map(lambda x: x.reshape(-1, *x.shape[2:])[:size], out)


def raise_on_failure(result, values, period_ratio, method: str) -> None:
    """Raise ``SolverError`` naming the cause if any batch member failed."""
    period_ratio = np.atleast_1d(np.asarray(period_ratio))
    failed = ~np.asarray(result == diffrax.RESULTS.successful)
    if failed.any():
        i = int(np.flatnonzero(np.atleast_1d(failed))[0])
        message = diffrax.RESULTS[jax.tree.map(lambda x: jnp.atleast_1d(x)[i], result)]
        if method in FIXED_STEP_SOLVERS:
            message += (
                " The fixed-step solver's numerical free vibration grew by more than "
                f"{MAX_FREE_VIBRATION_GROWTH} over the rise (w*dt past its stability limit): "
                "take more steps, or use an adaptive solver or the exact path."
            )
        raise SolverError(
            f"method {method!r} failed at period ratio {period_ratio[i]:g} "
            f"({int(failed.sum())} of {failed.size} failed): {message}"
        )
    finite = np.all([np.isfinite(np.asarray(v)) for v in values], axis=0)
    if not np.all(finite):
        i = int(np.flatnonzero(~np.atleast_1d(finite))[0])
        raise SolverError(
            f"method {method!r} produced non-finite values at period ratio {period_ratio[i]:g}"
        )


class Response(eqx.Module):
    """The payload's response over the rise and the following dwell.

    Attributes:
        tau: normalised time of the samples (rise nodes, then the dwell).
        command_acceleration: the law's acceleration ``s''`` (0 in the dwell).
        response_acceleration: the payload's acceleration ``x''``.
        deflection: transmission deflection ``e = s - x`` (payload lag, units of stroke).
        metrics: Ct, residual vibration and peak in motion (units of Ca).
        steps: steps the solver took over the rise.
    """

    tau: jax.Array
    command_acceleration: jax.Array
    response_acceleration: jax.Array
    deflection: jax.Array
    metrics: Metrics
    steps: jax.Array


def solve(
    law: AbstractMotionLaw,
    model: SpringMass,
    *,
    method: str = "exact",
    dwell: float = 1.0,
    resolution: int | None = None,
    **solver_options,
) -> Response:
    """Response of ``model`` driven by ``law``: time histories and metrics.

    ``method="exact"`` propagates the linear model in closed form; any name in
    ``camjax.propagation.SOLVERS`` integrates it with diffrax (``rtol``, ``atol``, ``steps``,
    ``max_steps``, ``use_jump_ts`` tune it).  Raises ``SolverError`` if the solver fails.
    """
    n = float(check_period_ratios(model.period_ratio)[0])
    zeta = check_damping(model.damping)
    options = SolveOptions(method, dwell, resolution, **solver_options).checked(n)
    grid, q, result, steps = _solve_one(law, SpringMass(n, zeta), options)
    metrics = _metrics(q, grid, SpringMass(n, zeta), law.Ca, options.dwell)
    raise_on_failure(result, (metrics.ct, metrics.residual), n, options.method)
    omega = 2 * np.pi * n
    lam = eigenvalue(omega, zeta)
    dwell_samples = int(np.ceil(options.dwell / float(jnp.max(grid.widths))))
    t_dwell = jnp.linspace(0.0, options.dwell, dwell_samples + 1)[1:]
    q_all = jnp.concatenate([q, q[-1] * jnp.exp(lam * t_dwell)])
    tau = jnp.concatenate([grid.nodes, 1.0 + t_dwell])
    deflection = jnp.imag(q_all) / jnp.imag(lam)
    return Response(
        tau=tau,
        command_acceleration=law.a(tau),
        response_acceleration=jnp.real(_mode_gain(omega, zeta) * q_all),
        deflection=deflection,
        metrics=metrics,
        steps=jnp.asarray(steps),
    )


@eqx.filter_jit
def _solve_one(law, model, options):
    grid = motion_grid(law, options.resolution)
    q, result, steps = _mode_at_nodes(law, grid, model, options)
    return grid, q, result, steps


def torsion_factor(law, period_ratio, damping=0.0, *, dwell=1.0, resolution=1024):
    """Ct of the exact path, jittable and differentiable in every argument's leaves."""
    options = SolveOptions(dwell=dwell, resolution=resolution)
    return response_metrics(law, SpringMass(period_ratio, damping), options).ct


def residual_vibration(law, period_ratio, damping=0.0, *, resolution=1024):
    """Residual vibration R (units of Ca) of the exact path, jittable and differentiable."""
    options = SolveOptions(resolution=resolution)
    return response_metrics(law, SpringMass(period_ratio, damping), options).residual

