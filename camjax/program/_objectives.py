"""Program-level design objectives over a speed range: the largest preload the program needs
(``MaxPreload``) and its largest residual vibration (``MaxProgramResidual``).

Kept apart from ``_design`` because it subclasses ``camjax.law_design``'s objective (which
imports optax): ``camjax.program`` stays light to import.
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..checks import speeds as checked_speeds
from ..law_design import EVALUATION_SAMPLES, AbstractObjective
from ._cycle import _cycle, residual_modes
from ._cycle_grid import program_grid, with_segment_law
from ._dynamics import SteadyState
from ._jump import even_periods, scan_speeds
from ._objective_rules import design_refusal
from ._oscillator import CONTACT_FORCE, Oscillator
from ._outputs import cam_levers, min_preload_n
from ._program import Program, segment_band, with_law

_SPEEDS_PER_CYCLE = 8  # training speeds per natural-frequency cycle the turn gains across the range


def _smooth_max(values, p):
    """``min + (mean (values - min)^p)^(1/p)``: a smooth ``max(values)``, exact as ``p`` grows.

    The shift keeps the power mean's arguments non-negative; it is differentiated (the
    power mean of shifted values is not shift-invariant).  The scale ``span`` is not
    (the power mean is homogeneous, so it cancels).
    """
    low = jnp.min(values)
    span = jax.lax.stop_gradient(jnp.max(values) - low) + 1e-300
    return low + span * jnp.mean(((values - low) / span) ** p) ** (1.0 / p)


def _segment_grid(objective, law):
    """The program with the objective's segment set to ``law`` (traced leaves allowed), its
    grid and oscillator: the layout comes from a copy of the law with its traced leaves zeroed
    (concrete, so built eagerly even under a trace), the segment's samples from the law."""
    # Concrete leaves (a corrected polynomial's base) stay: the program must keep its joins.
    placeholder = jax.tree.map(lambda x: np.zeros(np.shape(x)) if isinstance(x, jax.core.Tracer) else x, law)
    program = with_law(objective.program, objective.segment, placeholder)
    oscillator = Oscillator.of(program)
    with jax.ensure_compile_time_eval():
        grid = _same_points(program_grid(program, objective.rpm_lo, oscillator.lam), objective.program)
    return program, with_segment_law(grid, program, objective.segment - 1, law), oscillator


def _same_points(grid, original: Program):
    """``grid`` with its residual points at the ``original`` program's dwells and
    constant-velocity segments: a designed constant-velocity stroke is one no more, yet the
    vibration entering it is what the design and its start are compared on."""
    starts = np.asarray(grid.segment_start)[original.residual_segments()]
    return grid._replace(residual_start=np.asarray(starts, dtype=int))


def _plain_speed(name: str):
    """The converter of the speed bound ``name``: a concrete array as Python numbers (a
    scalar, or a tuple that the check refuses), as a static field holds no array; a traced
    one refused in ``camjax.checks.speeds``'s one line before it is set (where a static
    field would warn of a JAX array first): the speeds are chosen on the host."""

    def plain(value):
        if isinstance(value, jax.core.Tracer):
            checked_speeds(value, name)  # raises: not concrete
        if isinstance(value, np.ndarray | np.generic | jax.Array):
            return np.asarray(value).item() if np.ndim(value) == 0 else tuple(np.asarray(value).ravel().tolist())
        return value

    return plain


def _refuse(program: Program, objective: str) -> None:
    """A one-line ``ValueError`` where ``program`` cannot be designed for ``objective``
    (``design_refusal``: the one place of the rules on the program)."""
    refusal = design_refusal(program, objective)
    if refusal is not None:
        raise ValueError(refusal)


class AbstractProgramObjective(AbstractObjective):
    """An objective on the whole program with segment ``segment``'s (1-based) law, over
    the speed range ``[rpm_lo, rpm_hi]``: training at ``speeds`` (8 per natural-frequency
    cycle gained across the range), reports at ``EVALUATION_SAMPLES`` speeds evenly spaced
    in the period.  Subclasses write ``features``, ``value``, ``report`` and ``label``."""

    program: Program = eqx.field(static=True)
    segment: int = eqx.field(static=True)
    rpm_lo: float = eqx.field(static=True, converter=_plain_speed("rpm_lo"))
    rpm_hi: float = eqx.field(static=True, converter=_plain_speed("rpm_hi"))
    weight: float = eqx.field(static=True, default=1.0)
    damping: float = eqx.field(static=True, default=0.0)

    def __check_init__(self):
        segment_band(self.program, self.segment, self.rpm_lo, self.rpm_hi)
        if self.program.one_body and not self.program.follower.damping_ratio > 0:
            raise ValueError(f"the {self.what} objective needs follower.damping_ratio > 0 (a periodic steady state)")

    what: ClassVar[str] = "program"

    def speeds(self) -> np.ndarray:
        """Speeds (rpm) at which training evaluates the objective."""
        return scan_speeds(self.program, self.rpm_lo, self.rpm_hi, _SPEEDS_PER_CYCLE)

    def evaluation_speeds(self) -> np.ndarray:
        return even_periods(self.rpm_lo, self.rpm_hi, EVALUATION_SAMPLES)

    def evaluation_ratios(self) -> np.ndarray:
        angle = self.program.segments[self.segment - 1].angle_deg
        return np.sort(self.program.follower.vibrations_per_turn(self.evaluation_speeds()) * angle / 360.0)


class MaxPreload(AbstractProgramObjective):
    """Largest preload the program needs over ``[rpm_lo, rpm_hi]`` with segment ``segment``'s law.

    The required preload at a speed is ``max over the turn of -(k e + c e')`` of the whole
    program's periodic steady state (vibration carried in from the other segments counts),
    in N.  Training takes the signed value (it may be negative: contact margin) at the grid
    nodes of ``speeds`` and smooths the maximum over speeds and nodes by a power mean of the
    values shifted to ``[0, 1]``.  The report is ``max(0, .)`` by the program's own
    steady-state path (``SteadyState``, extrema refined between nodes) on
    ``EVALUATION_SAMPLES`` speeds.
    """

    what: ClassVar[str] = "preload"

    def __check_init__(self):
        _refuse(self.program, "preload")

    def features(self, law):
        """``k e + c e'`` (N) at every grid node and training speed: affine in the law."""
        _, grid, oscillator = _segment_grid(self, law)
        force = jax.vmap(lambda rpm: _cycle(grid, oscillator, rpm).contact_force_n)(jnp.asarray(self.speeds()))
        return (force - oscillator.static[CONTACT_FORCE]) / cam_levers(self.program)

    def value(self, features, ca, sharpness):
        return _smooth_max(-features.ravel(), sharpness)

    def required_preload(self, law) -> np.ndarray:
        """Required preload (N) at every evaluation speed, by ``SteadyState`` on the program with ``law``."""
        program = with_law(self.program, self.segment, law)
        force = SteadyState(program, self.rpm_lo).min_contact_force_n(self.evaluation_speeds())
        return min_preload_n(force, program.follower.preload_n, cam_levers(program))

    def report(self, law, **sweep_options) -> float:  # the program's engine: no sweep options
        return float(np.max(self.required_preload(law)))

    @property
    def label(self):
        return f"max preload (N) over [{self.rpm_lo:g}, {self.rpm_hi:g}] rpm"


class MaxProgramResidual(AbstractProgramObjective):
    """Largest residual vibration (mm) of the program over ``[rpm_lo, rpm_hi]`` with segment
    ``segment``'s law: the free vibration at the start of every dwell and constant-velocity
    segment of the whole program's periodic steady state (``SpeedReport.residual_vibration_mm``),
    the objective for a segment that starts or ends in motion, whose own rise is not from
    rest to rest.  Training smooths the maximum over the training speeds and residual
    points of ``|mode|``, whose real and imaginary parts are affine in the law; the report
    is the largest by ``SteadyState`` on ``EVALUATION_SAMPLES`` speeds.  The residual points
    are the given program's (a designed constant-velocity stroke keeps its point).
    """

    what: ClassVar[str] = "residual"

    def __check_init__(self):
        _refuse(self.program, "residual")
        if not self.program.residual_segments():
            raise ValueError("the program has no dwell or constant-velocity segment: no residual vibration to design for")

    def features(self, law):
        """Real and imaginary parts of the last body's residual modes (mm), ``(2, speeds,
        modes, points)`` (``residual_modes``: the residual is the sum of their moduli)."""
        _, grid, oscillator = _segment_grid(self, law)

        def modes(rpm):
            return residual_modes(grid, oscillator, _cycle(grid, oscillator, rpm).q, rpm)

        z = jax.vmap(modes)(jnp.asarray(self.speeds()))
        return jnp.stack([jnp.real(z), jnp.imag(z)])

    def value(self, features, ca, sharpness):
        return _smooth_max(jnp.sum(jnp.hypot(features[0], features[1]), axis=-2).ravel(), sharpness)

    def residual_mm(self, law) -> np.ndarray:
        """Largest residual vibration (mm) at every evaluation speed, by ``SteadyState``."""
        steady = SteadyState(with_law(self.program, self.segment, law), self.rpm_lo)
        steady.grid = _same_points(steady.grid, self.program)  # before its first (tracing) call
        out = steady.summary(self.evaluation_speeds())
        return np.max(out.residual_vibration_mm, axis=1)

    def report(self, law, **sweep_options) -> float:  # the program's engine: no sweep options
        return float(np.max(self.residual_mm(law)))

    @property
    def label(self):
        return f"max residual vibration (mm) over [{self.rpm_lo:g}, {self.rpm_hi:g}] rpm"
