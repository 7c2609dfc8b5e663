"""The least seating velocity of a valve over a speed range as a design objective
(``MaxSeatingVelocity``) and its design (``seating_design``).

The seating velocity comes from the chain's simulation with its contacts (``ChainContacts``):
it is not linear in the law, so it is designed in rounds, each a ``camjax.design`` of its
linear model about the current law with a proximal step, the model's derivatives taken
through the integration and the periodic steady state (``MaxSeatingVelocity.linearised``).
"""

from __future__ import annotations

import time
import warnings
from typing import ClassVar, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..law_design import AbstractObjective, DesignNotImproved, DesignResult, design
from ..laws import BoundaryPolynomial, BSplineLaw, CorrectedPolynomial
from ._chain_contacts import ChainContacts, ContactOptions, contact_grid, seating_velocity
from ._cycle_grid import with_segment_law
from ._jump import even_periods, scan_speeds
from ._objectives import _SPEEDS_PER_CYCLE, AbstractProgramObjective, _refuse, _smooth_max
from ._program import with_law


class Linearised(NamedTuple):
    """The seating velocities' linear model about a law (``MaxSeatingVelocity.linearised``):
    ``values`` (m/s, per speed, as ``seating_velocity`` reads them), their derivatives
    ``jacobian`` ``(speeds, coefficients)`` and ``reported``, the simulation's own reading
    at the same speeds (``ContactTurn.seating_velocity_m_s``)."""

    values: np.ndarray
    jacobian: np.ndarray
    reported: np.ndarray


def _seating_row(z0, step, grid, lift_map, acceleration_map, rpm, sample, system, samples, options):
    """The turn's end state and the seating velocity (``seating_velocity``) in one vector,
    the grid's lift and acceleration moved by ``map @ step`` (affine in a law's coefficients)."""
    grid = grid._replace(
        lift=grid.lift + lift_map @ step, acceleration=grid.acceleration + acceleration_map @ step
    )
    end, velocity = seating_velocity(z0, rpm, sample, system, grid, samples, options)
    return jnp.concatenate([end, velocity[None]])


_SPEED_AXES = (0, None, None, None, None, 0, 0, None, None, None)
_seating_rows = jax.jit(jax.vmap(_seating_row, in_axes=_SPEED_AXES), static_argnums=(8, 9))
_seating_jacobians = jax.jit(
    jax.vmap(jax.jacfwd(_seating_row, argnums=(0, 1)), in_axes=_SPEED_AXES), static_argnums=(8, 9)
)
"""Per speed, the derivatives of the end state and the seating velocity in the turn's
start state and the law's coefficients, by forward mode through the integration (a few
bodies' states and tens of coefficients: fewer directions than reverse mode's recomputed
steps cost): compiled once per shape (bodies, grid bucket, coefficients, samples)."""


class MaxSeatingVelocity(AbstractProgramObjective):
    """Largest seating velocity (m/s) of the valve over ``[rpm_lo, rpm_hi]`` with segment
    ``segment``'s law: the last body's closing speed onto its seat at the first landing of
    the closing (``ContactTurn.seating_velocity_m_s``), for a chain with a seat, simulated
    with its contacts to its periodic steady state (``ChainContacts``, ``options``).

    Training and report take the same ``speeds()``: ``count`` speeds evenly spaced in the
    period (default ``scan_speeds``, 8 per natural-frequency cycle gained across the range):
    each is a simulation.  The seating velocity is not linear in the law: it is designed by
    ``seating_design``, rounds of a linear model (``linearised``) with a proximal step.
    """

    count: int | None = eqx.field(static=True, default=None)
    options: ContactOptions | None = eqx.field(static=True, default=None)

    what: ClassVar[str] = "seating"

    def __check_init__(self):
        _refuse(self.program, "seating")
        if self.options is not None and not isinstance(self.options, ContactOptions):
            raise ValueError(
                f"the seating objective's options must be a ContactOptions, got {self.options!r}"
            )
        if self.count is not None and (
            isinstance(self.count, bool) or not isinstance(self.count, int) or self.count < 1
        ):
            raise ValueError(
                f"the seating objective's count of speeds must be a whole number of at least 1, "
                f"got {self.count!r}"
            )

    def speeds(self) -> np.ndarray:
        if self.count is None:
            return scan_speeds(self.program, self.rpm_lo, self.rpm_hi, _SPEEDS_PER_CYCLE)
        return even_periods(self.rpm_lo, self.rpm_hi, self.count)

    def evaluation_speeds(self) -> np.ndarray:
        return self.speeds()

    def simulation(self, law) -> ChainContacts:
        """The simulated chain of the program with ``law`` (from ``rpm_lo`` up)."""
        program = with_law(self.program, self.segment, law)
        return ChainContacts(program, program.chain, self.rpm_lo, self.options)

    def _turns(self, law):
        simulation = self.simulation(law)
        turns = simulation.turns(self.speeds(), refine=False)
        for t in turns:
            if t.seating_sample is None:
                raise ValueError(
                    f"segment {self.segment}: at {t.rpm:g} rpm the valve does not leave its "
                    "seat: no seating velocity to design for"
                )
        return simulation, turns

    def seating_m_s(self, law) -> np.ndarray:
        """The seating velocity (m/s) at every speed of ``speeds()``, as the report reads it."""
        return np.array([t.seating_velocity_m_s for t in self._turns(law)[1]])

    def _arguments(self, law):
        """The settled turns of ``law`` at ``speeds()`` and ``_seating_row``'s arguments for
        them: the grid's lift and acceleration recomputed from the law in JAX
        (``with_segment_law``) with their derivatives in its coefficients (affine: exact)."""
        simulation, turns = self._turns(law)
        program, index = simulation.program, self.segment - 1

        def padded(coefficients):
            moved = contact_grid(
                with_segment_law(
                    simulation.cycle, program, index, _with_coefficients(law, coefficients)
                ),
                simulation._breaks,
            )
            return moved.lift, moved.acceleration

        coefficients = jnp.asarray(law.coefficients)
        lift, acceleration = padded(coefficients)
        lift_map, acceleration_map = jax.jacfwd(padded)(coefficients)
        grid = jax.tree.map(
            jnp.asarray, simulation._grid._replace(lift=lift, acceleration=acceleration)
        )
        return turns, (
            jnp.asarray(np.stack([t.start_state for t in turns])),
            jnp.zeros(coefficients.size),
            grid,
            lift_map,
            acceleration_map,
            jnp.asarray([t.rpm for t in turns]),
            jnp.asarray([t.seating_sample for t in turns]),
            jax.tree.map(jnp.asarray, simulation.system),
            simulation.samples,
            simulation.options,
        )

    def read(self, law) -> np.ndarray:
        """The seating velocity (m/s) at every speed of ``speeds()`` as the objective computes
        it in JAX (``seating_velocity`` on the law's own grid from the settled start state):
        the simulation's reading (``seating_m_s``) to the integration's tolerance."""
        _, arguments = self._arguments(law)
        return np.asarray(_seating_rows(*arguments))[:, -1]

    def linearised(self, law) -> Linearised:
        """The seating velocity at every speed (m/s, ``read``) and its derivatives ``(speeds,
        coefficients)`` in ``law.coefficients``.

        Through the periodic steady state: the turn's map ``z -> Phi(z, c)`` and the seating
        velocity ``v(z, c)`` are differentiated by forward mode through the integration
        (diffrax's ``ForwardMode``; its step sizes are held, so the derivative is the computed
        path's), and the start state ``z = Phi(z, c)`` by the implicit function theorem:
        ``dv/dc = v_c + v_z (I - Phi_z)^-1 Phi_c``.  The landing's sample is held: the
        derivative is that of the reading from it (``seating_velocity``)."""
        turns, arguments = self._arguments(law)
        values = np.asarray(_seating_rows(*arguments))
        d_state, d_coefficients = (np.asarray(x) for x in _seating_jacobians(*arguments))
        n = arguments[0].shape[1]
        jacobian = []
        for k in range(len(turns)):
            phi_z, v_z = d_state[k, :n], d_state[k, n]
            phi_c, v_c = d_coefficients[k, :n], d_coefficients[k, n]
            w = np.linalg.solve((np.eye(n) - phi_z).T, v_z)
            jacobian.append(v_c + w @ phi_c)
        reported = np.array([t.seating_velocity_m_s for t in turns])
        return Linearised(values[:, n], np.asarray(jacobian), reported)

    def features(self, law):
        raise TypeError(
            "the seating velocity is not linear in the law: it is designed by seating_design "
            "(rounds of its linear model, MaxSeatingVelocity.linearised)"
        )

    def value(self, features, ca, sharpness):
        """The smoothed maximum of the seating velocities ``features`` (one per speed; one
        speed's own value: a single value has no spread to smooth over)."""
        return features[0] if features.size == 1 else _smooth_max(features, sharpness)

    def report(self, law, **sweep_options) -> float:  # the simulation: no sweep options
        return float(np.max(self.seating_m_s(law)))

    @property
    def label(self):
        return f"max seating velocity (m/s) over [{self.rpm_lo:g}, {self.rpm_hi:g}] rpm"


def _with_coefficients(law, coefficients):
    return eqx.tree_at(lambda x: x.coefficients, law, coefficients)


class _SeatingModel(AbstractObjective):
    """One round of ``seating_design``: the seating velocities' linear model about the law
    of coefficients ``center`` (``values``, ``jacobian``), the smoothed maximum over the
    speeds plus the proximal term ``weight_step / 2 |c - center|^2`` that keeps the step
    where the model holds; reported by the simulation (``goal``), so a round's design is
    kept only where the true seating velocity went down."""

    goal: MaxSeatingVelocity = eqx.field(static=True)
    values: np.ndarray
    jacobian: np.ndarray
    center: np.ndarray
    weight_step: np.ndarray
    reported: float = eqx.field(static=True)
    weight: float = eqx.field(static=True, default=1.0)
    damping: float = eqx.field(static=True, default=0.0)

    def features(self, law):
        step = law.coefficients - self.center
        return self.values + self.jacobian @ step, step

    def value(self, features, ca, sharpness):
        seating, step = features
        return self.goal.value(seating, ca, sharpness) + 0.5 * self.weight_step * jnp.sum(step**2)

    def report(self, law, **sweep_options) -> float:
        if np.array_equal(np.asarray(law.coefficients), np.asarray(self.center)):
            return self.reported  # the simulation's at the center (linearised read it)
        return self.goal.report(law)

    def evaluation_ratios(self):
        return self.goal.evaluation_ratios()

    @property
    def label(self):
        return self.goal.label


def _round_progress(progress, round_: int, rounds: int):
    """``progress(step, total, loss)`` of a round's design as the whole design's: the
    steps of the rounds before it counted, ``total`` every round's."""
    return lambda step, total, loss: progress(round_ * total + step, rounds * total, loss)


FIRST_STEP = 0.02
"""The first round's step in the designed law's coefficients (a fraction of the lift) that
the proximal term aims at: ``weight_step = |grad| / FIRST_STEP``."""


def seating_design(
    goal: MaxSeatingVelocity,
    *,
    caps=None,
    initial,
    rounds: int = 6,
    knots: int = 24,
    degree: int = 5,
    **design_options,
):
    """Design segment ``goal.segment``'s law for the least seating velocity over the speeds
    of ``goal``: ``rounds`` rounds, each a ``camjax.design`` (caps, knots and
    ``design_options`` as there) of the seating velocities' linear model about the current
    law (``MaxSeatingVelocity.linearised``) with a proximal step (``_SeatingModel``).  A round
    whose simulated seating velocity is no lower keeps its law and quadruples the proximal
    weight; one that is halves it.  A ``progress`` function (``camjax.design``'s) counts the
    rounds' steps as one run.  Returns a ``DesignResult`` whose ``initial_values`` are
    the start's (the law in the design's family: ``initial`` fitted or corrected) and whose
    law is the start with a ``DesignNotImproved`` warning where no round improved on it."""
    started_at = time.perf_counter()
    if isinstance(rounds, bool) or not isinstance(rounds, int) or rounds < 1:
        raise ValueError(f"rounds must be a whole number of at least 1, got {rounds!r}")
    if isinstance(initial, BoundaryPolynomial):
        law = CorrectedPolynomial(initial, jnp.zeros(knots), degree)
    elif isinstance(initial, CorrectedPolynomial):
        law = initial
    else:
        law = BSplineLaw.fit(initial, knots, degree)
    started = law
    weight_step, best, history, coefficients, accepted = None, None, [], None, False
    progress = design_options.pop("progress", True)
    for round_ in range(rounds):
        if callable(progress):  # the rounds' steps as one count: the progress only goes forward
            design_options["progress"] = _round_progress(progress, round_, rounds)
        else:
            design_options["progress"] = progress
        values, jacobian, reported = goal.linearised(law)
        if best is None:
            start_value = best = float(np.max(reported))
        if weight_step is None:
            weight_step = float(np.max(np.linalg.norm(jacobian, axis=1))) / FIRST_STEP
        model = _SeatingModel(
            goal,
            np.asarray(values),
            np.asarray(jacobian),
            np.asarray(law.coefficients),
            np.asarray(weight_step),
            float(np.max(reported)),
        )
        with warnings.catch_warnings():
            warnings.simplefilter(
                "ignore", DesignNotImproved
            )  # a round that does not improve: said below
            # the round's result holds its model (arrays) as a static field: read here and dropped
            warnings.filterwarnings("ignore", "A JAX array is being set as static", UserWarning)
            result = design(
                model, caps=caps, initial=law, knots=knots, degree=degree, **design_options
            )
        history.append(result.loss_history)
        coefficients = coefficients or result.coefficients
        if not result.kept_initial and result.values[goal.label] < best:
            law, best, accepted = result.law, result.values[goal.label], True
            coefficients = result.coefficients
            weight_step /= 2.0
        else:
            weight_step *= 4.0
    if not accepted:
        warnings.warn(
            f"the design did not improve on the law it started from ({goal.label}: {start_value:.6g})",
            DesignNotImproved,
            stacklevel=2,
        )
    return DesignResult(
        law=law if accepted else started,
        objectives=(goal,),
        values={goal.label: best},
        coefficients=coefficients,
        loss_history=np.concatenate(history),
        restored=False,
        seconds=time.perf_counter() - started_at,
        initial_values={goal.label: start_value},
        kept_initial=not accepted,
    )
