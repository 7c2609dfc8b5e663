"""Backlash: the payload leaves the driving flank, flies across the clearance, strikes.

Two models of the same scene (MISSION.md conventions; ``bk = backlash/stroke``,
``dn = Dn T^2/h``, ``v = V T/h``):

* ``kinematic_impact`` - the reference note's kinematic analysis.  The payload rides
  the driving (lower) flank ``s(tau)`` while the contact force ``a(tau) + dn`` is
  non-negative; it departs at the first ``tau_d`` with ``a(tau_d) < -dn`` and flies on the
  parabola ``s_free(tau) = s(tau_d) + v(tau_d) u - dn u^2/2`` (``u = tau - tau_d``; ``dn`` is
  a constant retarding force: friction while moving forward, gravity or a preload spring).
  The gap ``g(tau) = s_free(tau) - s(tau)`` opens from 0; the payload strikes the other
  flank (at ``s + bk``) when ``g`` reaches ``+bk``, with impact velocity ``v = g'(tau_i)``.
  If ``g`` closes to 0 first, or the payload stops short of ``bk`` in the following dwell,
  it falls back onto the driving flank: no impact across the clearance.  Roots are found
  exactly (grid bracket, then bisection to machine precision); the flight after the
  rise (cam at rest) is solved in closed form.  Jittable, vmappable and differentiable in
  the law's parameters, ``bk`` and ``dn`` (implicit differentiation through the roots).
* ``Backlash`` (through ``camjax.solve`` and ``camjax.ct_curve``) - the SDOF
  of ``camjax.SpringMass`` whose transmission spring has a dead zone of width ``bk``:
  contact with either flank engages the spring (stiffness from the period ratio) and its
  viscous damping, the free flight feels only ``-dn``.  One smooth phase per contact
  state (``camjax.models._hybrid``): contact phases by diffrax, ended by an event at
  the next contact change; free flights in closed form, ended by an exact search that
  cannot step over a grazing strike.  The follower can separate and strike any number of
  times.
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import checks
from ..checks import is_concrete, require
from ..errors import RESULTS
from ..laws import AbstractMotionLaw, rest_to_rest
from ..sdof import residual_amplitude
from ..solvers import solver
from ._base import Metrics, Options, Response
from ._hybrid import AbstractHybridModel, bisect, sample_times

# Status codes of a kinematic case.
IMPACT = 0
"""The payload strikes the other flank."""
NO_SEPARATION = 1
"""The natural deceleration dn exceeds the law's peak deceleration: never leaves the driving flank."""
NO_IMPACT = 2
"""The payload leaves, but falls back onto the driving flank before crossing bk."""
STATUS_NAMES = {IMPACT: "impact", NO_SEPARATION: "no separation", NO_IMPACT: "no impact"}

_FALL_TOL = 1e-12  # a gap below -_FALL_TOL means the payload is back on the driving flank


class KinematicImpact(NamedTuple):
    """One kinematic backlash case; NaN where the event does not happen.

    Attributes:
        departure_tau: normalised time the payload leaves the driving flank.
        impact_tau: normalised time it strikes the other flank (> 1 in the dwell).
        impact_velocity: normalised impact velocity ``v = V T / h`` (relative to the flank).
        status: ``IMPACT``, ``NO_SEPARATION`` or ``NO_IMPACT`` (see ``STATUS_NAMES``).
    """

    departure_tau: jax.Array
    impact_tau: jax.Array
    impact_velocity: jax.Array
    status: jax.Array


def _first(mask):
    """Index of the first True of a 1-D mask (its length when there is none)."""
    return jnp.where(jnp.any(mask), jnp.argmax(mask), mask.shape[0])


def check_backlash_inputs(backlash, natural_deceleration) -> None:
    """``ValueError`` for a non-positive backlash or a negative natural deceleration."""
    if is_concrete(backlash, natural_deceleration):
        bk = np.asarray(backlash, dtype=float)
        dn = np.asarray(natural_deceleration, dtype=float)
        require(
            np.all(np.isfinite(bk)) and np.all(bk > 0), f"backlash bk must be positive, got {bk}"
        )
        require(
            np.all(np.isfinite(dn)) and np.all(dn >= 0),
            f"natural deceleration dn must be non-negative, got {dn}",
        )


def kinematic_impact(
    law: AbstractMotionLaw, backlash, natural_deceleration, *, samples: int = 512
) -> KinematicImpact:
    """Departure, impact time and impact velocity of the kinematic backlash analysis.

    Args:
        law: the rise (followed by a dwell), or its name.
        backlash: normalised clearance ``bk > 0`` (scalar).
        natural_deceleration: normalised natural deceleration ``dn >= 0`` (scalar).
        samples: grid that brackets the first departure and the first flank crossing
            during the rise; an excursion narrower than ``1/samples`` may be missed.

    Gradients (in the law's parameters, ``bk``, ``dn``) are exact for a departure where
    the acceleration crosses ``-dn`` smoothly (every standard law; the parabolic law's
    step sits at the fixed crossover); a departure at an acceleration step whose position
    moves with the parameters is not differentiated through that motion.
    """
    check_backlash_inputs(backlash, natural_deceleration)
    bk = jnp.asarray(backlash, dtype=float)
    dn = jnp.asarray(natural_deceleration, dtype=float)
    return _kinematic_impact(rest_to_rest(law, "kinematic_impact"), bk, dn, samples)


@eqx.filter_jit
def _kinematic_impact(law, bk, dn, samples):
    """``kinematic_impact`` on validated array inputs (compiled once per law type)."""
    # Roots are located on constants (no tangents through the loops), then given their
    # implicit derivatives by one Newton step on the differentiable functions.
    law_c, bk_c, dn_c = jax.lax.stop_gradient((law, bk, dn))

    # Departure: first tau with a(tau) + dn < 0.
    grid = jnp.linspace(0.0, 1.0, samples + 1)
    k = _first(law_c.a(grid) + dn_c < 0)
    separates = k <= samples
    k = jnp.clip(k, 1, samples)
    tau_d = bisect(lambda t: -(law_c.a(t) + dn_c), grid[k - 1], grid[k])
    # The impact does not depend on tau_d to first order (a + dn = 0 there), so the
    # flight uses the stopped root; the reported time gets its implicit derivative.
    jerk = law.j(tau_d)
    smooth = jnp.abs(jerk) > 0
    departure = tau_d - jnp.where(smooth, (law.a(tau_d) + dn) / jnp.where(smooth, jerk, 1.0), 0.0)
    s_d, v_d = law.s(tau_d), law.v(tau_d)

    def gap(t, law=law, dn=dn, s_d=s_d, v_d=v_d):
        u = t - tau_d
        return s_d + v_d * u - 0.5 * dn * u**2 - law.s(t)

    def gap_c(t):
        return jax.lax.stop_gradient(gap(t, law_c, dn_c, law_c.s(tau_d), law_c.v(tau_d)))

    def gap_rate(t):
        return v_d - dn * (t - tau_d) - law.v(t)

    # During the rise: first grid point where the gap reaches bk or closes.
    taus = tau_d + (1.0 - tau_d) * jnp.linspace(0.0, 1.0, samples + 1)
    g = gap_c(taus)
    index = jnp.arange(samples + 1)
    first_cross = _first((g >= bk) & (index > 0))
    first_fall = _first((g < -_FALL_TOL) & (index > 0))
    hits_in_rise = first_cross < first_fall
    i = jnp.clip(first_cross, 1, samples)
    root = bisect(lambda t: gap_c(t) - bk_c, taus[i - 1], taus[i])
    rate = jax.lax.stop_gradient(gap_rate(root))
    tau_rise = root - (gap(root) - bk) / jnp.where(rate > 0, rate, 1.0)  # implicit derivative
    v_rise = gap_rate(tau_rise)

    # After the rise the cam rests at s = 1: g(1 + u) = g1 + w1 u - dn u^2 / 2.
    falls_in_rise = first_fall <= samples
    g1, w1 = gap(1.0), gap_rate(1.0)
    disc = w1**2 - 2 * dn * (bk - g1)
    reaches = (~falls_in_rise) & (w1 > 0) & (disc >= 0)
    root_disc = jnp.sqrt(jnp.where(reaches, disc, 1.0))
    tau_dwell = 1.0 + 2 * (bk - g1) / jnp.where(reaches, w1 + root_disc, 1.0)

    status = jnp.where(
        ~separates, NO_SEPARATION, jnp.where(hits_in_rise | reaches, IMPACT, NO_IMPACT)
    )
    nan = jnp.nan
    impact_tau = jnp.where(hits_in_rise, tau_rise, tau_dwell)
    impact_velocity = jnp.where(hits_in_rise, v_rise, root_disc)
    impacts = status == IMPACT
    return KinematicImpact(
        departure_tau=jnp.where(separates, departure, nan),
        impact_tau=jnp.where(impacts, impact_tau, nan),
        impact_velocity=jnp.where(impacts, impact_velocity, nan),
        status=status,
    )


@eqx.filter_jit
def _impact_table(law, bk, dn, samples):
    per_bk = jax.vmap(lambda b, d: _kinematic_impact(law, b, d, samples), (0, None))
    return jax.vmap(per_bk, (None, 0))(bk, dn)


def kinematic_impact_table(
    law: AbstractMotionLaw, backlash, natural_deceleration, *, samples: int = 512
) -> KinematicImpact:
    """``kinematic_impact`` for every ``(dn, bk)`` pair: arrays of shape ``(n_dn, n_bk)``."""
    bk = jnp.atleast_1d(jnp.asarray(backlash, dtype=float))
    dn = jnp.atleast_1d(jnp.asarray(natural_deceleration, dtype=float))
    require(bk.ndim == 1 and dn.ndim == 1, "backlash and natural deceleration must be 1-D lists")
    check_backlash_inputs(bk, dn)
    return _impact_table(rest_to_rest(law, "kinematic_impact_table"), bk, dn, samples)


# --- physical units -------------------------------------------------------------------


def _positive(label, value):
    require(value is not None, f"{label} is missing")
    require(math.isfinite(value) and value > 0, f"{label} must be positive, got {value}")
    return float(value)


def normalised_backlash(backlash: float, stroke: float) -> float:
    """``bk = backlash / stroke`` (same length or angle units)."""
    return _positive("backlash", backlash) / _positive("stroke", stroke)


def normalised_deceleration(deceleration: float, stroke: float, motion_time: float) -> float:
    """``dn = Dn T^2 / h`` from the payload's natural deceleration ``Dn`` (m/s^2 or rad/s^2)."""
    require(math.isfinite(deceleration) and deceleration >= 0, "deceleration must be >= 0")
    return deceleration * _positive("motion_time", motion_time) ** 2 / _positive("stroke", stroke)


def impact_velocity(normalised_velocity: float, stroke: float, motion_time: float) -> float:
    """Physical impact velocity ``V = v h / T`` (m/s, or rad/s for an angular stroke)."""
    return (
        float(normalised_velocity)
        * _positive("stroke", stroke)
        / _positive("motion_time", motion_time)
    )


def impact_force(
    velocity: float,
    *,
    mass: float | None = None,
    stiffness: float | None = None,
    inertia: float | None = None,
    torsional_rigidity: float | None = None,
) -> float:
    """Impact force ``V sqrt(S W)`` (N) or torque ``V sqrt(R I)`` (N m), SI units.

    The peak force of an undamped spring ``S`` stopping a mass ``W`` that strikes at
    ``V``; give ``mass`` and ``stiffness`` (linear) or ``inertia`` and
    ``torsional_rigidity`` (rotary, ``velocity`` in rad/s).
    """
    linear = mass is not None or stiffness is not None
    rotary = inertia is not None or torsional_rigidity is not None
    require(
        linear != rotary,
        "give either mass and stiffness (linear) or inertia and torsional_rigidity (rotary)",
    )
    require(math.isfinite(velocity) and velocity >= 0, f"velocity must be >= 0, got {velocity}")
    if linear:
        return velocity * math.sqrt(_positive("mass", mass) * _positive("stiffness", stiffness))
    return velocity * math.sqrt(
        _positive("inertia", inertia) * _positive("torsional_rigidity", torsional_rigidity)
    )


# --- dynamic model: SDOF with a dead zone ----------------------------------------------

# Contact states of the dynamic model.
DRIVING_FLANK = 0
"""Deflection e = s - x > 0: the transmission pushes the payload."""
FREE = 1
"""-bk < e < 0: free flight, only the natural deceleration acts."""
OTHER_FLANK = 2
"""E < -bk: the other flank holds the payload back."""


@dataclasses.dataclass(frozen=True)
class BacklashOptions(Options):
    """Static settings of a dynamic backlash solution.

    Attributes:
        method: diffrax solver of the contact phases (``"tsit5"``; ``"kvaerno5"`` for very
            stiff contact).  Free flights are solved in closed form.
        dwell: dwell after the rise, in motion periods.
        samples: equal sample steps over the rise (the dwell is sampled as finely).
        rtol, atol: tolerances of the contact phases.
        max_steps: step limit of one contact phase.
        max_segments: most contact phases and flights in one solve.
        max_step: largest step of a contact phase, in natural periods ``1/n`` (default
            1/8), so that a step cannot span a short loss of contact; ``None`` leaves the
            step to error control, which a very stiff contact solved with an implicit
            method needs (hundreds of steps instead of ``8 n``); a separation shorter
            than a step could then go unseen between samples.
    """

    method: str = "tsit5"
    samples: int = 1024
    rtol: float = 1e-9
    atol: float = 1e-12
    max_steps: int = 16384
    max_segments: int = 64
    max_step: float | None = 0.125

    def checked(self, max_period_ratio: float) -> BacklashOptions:
        base = super().checked(max_period_ratio)
        require(int(self.samples) >= 2, f"samples must be at least 2, got {self.samples}")
        require(int(self.max_segments) >= 1, f"max_segments must be positive, got {self.max_segments}")
        require(int(self.max_steps) >= 1, f"max_steps must be positive, got {self.max_steps}")
        require(self.max_step is None or self.max_step > 0, f"max_step must be positive or None, got {self.max_step}")
        return base


class BacklashResponse(Response):
    """Dynamic backlash response; impact arrays hold ``n_impacts`` valid entries, NaN after.

    Attributes:
        deflection: ``e = s - x`` at ``tau`` (``e < -bk``: pressed on the other flank).
        contact: contact state at ``tau`` (``DRIVING_FLANK``, ``FREE``, ``OTHER_FLANK``).
        impact_tau, impact_velocity, impact_flank: every impact (entry into contact):
            time, normalised relative velocity ``|e'|``, and the flank struck.
        n_impacts: number of impacts.
    """

    deflection: jax.Array
    contact: jax.Array
    impact_tau: jax.Array
    impact_velocity: jax.Array
    impact_flank: jax.Array
    n_impacts: jax.Array

    @property
    def first_impact_velocity(self):
        """Velocity of the first strike on the other flank (NaN if there is none)."""
        other = (self.impact_flank == OTHER_FLANK) & jnp.isfinite(self.impact_velocity)
        return jnp.where(jnp.any(other), self.impact_velocity[jnp.argmax(other)], jnp.nan)

    @property
    def first_impact_tau(self):
        """Time of the first strike on the other flank (NaN if there is none)."""
        other = (self.impact_flank == OTHER_FLANK) & jnp.isfinite(self.impact_velocity)
        return jnp.where(jnp.any(other), self.impact_tau[jnp.argmax(other)], jnp.nan)


class Backlash(AbstractHybridModel):
    """The SDOF of ``camjax.SpringMass`` with a clearance ``bk`` in its transmission.

    In deflection ``e = s - x`` (normalised, ``w = 2 pi n``):
    ``e'' = a(tau) + dn - w^2 c(e) - 2 zeta w e' [in contact]`` with the dead-zone spring
    ``c(e) = e`` (driving flank, ``e > 0``), ``0`` (free, ``-bk < e < 0``),
    ``e + bk`` (other flank, ``e < -bk``).  Contact damping is Kelvin-Voigt (it acts only
    in contact).  ``dn`` is a constant retarding force (gravity, a preload spring, or
    friction while the payload moves forward); it holds the payload on the driving flank
    at rest, where it starts (``e = dn / w^2``).  Contact phases are integrated with
    diffrax; a free flight is the parabola ``x'' = -dn``, solved in closed form, and its
    end is found by ``camjax.models._hybrid.first_exit``, which cannot miss a grazing
    strike.

    Attributes:
        period_ratio: ``n`` of the transmission (contact) stiffness, > 0.
        backlash: normalised clearance ``bk`` > 0.
        natural_deceleration: normalised ``dn`` >= 0.
        damping: contact damping ratio ``zeta`` in ``[0, 1)``.
    """

    period_ratio: float | jax.Array
    backlash: float | jax.Array
    natural_deceleration: float | jax.Array = 0.0
    damping: float | jax.Array = 0.0
    methods: ClassVar[tuple[str, ...]] = ("tsit5", "dopri5", "dopri8", "bosh3", "kvaerno3", "kvaerno4", "kvaerno5")
    options_type: ClassVar[type[Options]] = BacklashOptions

    def checked_parameters(self) -> dict:
        return {
            "period_ratio": checks.positive(self.period_ratio, "period ratio"),
            "backlash": checks.positive(self.backlash, "backlash bk"),
            "natural_deceleration": checks.non_negative(self.natural_deceleration, "natural deceleration dn"),
            "damping": checks.damping_ratio(self.damping),
        }

    # --- phases ---

    def _stretch(self, e, mode):
        stretch = jnp.where(mode == DRIVING_FLANK, e, jnp.where(mode == OTHER_FLANK, e + self.backlash, 0.0))
        return stretch, mode != FREE

    def _restoring(self, e, de, mode):
        stretch, touching = self._stretch(e, mode)
        w = self.omega
        return w**2 * stretch + jnp.where(touching, 2 * self.damping * w * de, 0.0)

    def phase_field(self, t, y, law, mode):
        e, de = y
        return de, law.a(t) + self.natural_deceleration - self._restoring(e, de, mode)

    def phase_exit(self, t, y, law, mode):
        e = y[0]
        return jnp.where(
            mode == DRIVING_FLANK, -e, jnp.where(mode == FREE, e * (e + self.backlash), e + self.backlash)
        )

    def next_phase(self, t, y, law, mode):
        strike = jnp.where(y[0] > -0.5 * self.backlash, DRIVING_FLANK, OTHER_FLANK)
        return jnp.where(mode == FREE, strike, FREE), y

    def closed_form(self, mode):
        return mode == FREE

    def closed_state(self, t, t0, y0, law, mode):
        """Free flight ``x'' = -dn``: ``x = x0 + x0' u - dn u^2 / 2`` and ``e = s - x``."""
        s0, v0, _, _ = law.evaluate(t0)
        x0, dx0 = s0 - y0[0], v0 - y0[1]
        u = t - t0
        s, v, _, _ = law.evaluate(t)
        dn = self.natural_deceleration
        return s - x0 - dx0 * u + 0.5 * dn * u**2, v - dx0 + dn * u

    def closed_exits(self, t0, y0, law, mode):
        def g(t):
            e = self.closed_state(t, t0, y0, law, mode)[0]
            return jnp.stack([e, -self.backlash - e])

        def dg(t):
            de = self.closed_state(t, t0, y0, law, mode)[1]
            return jnp.stack([de, -de])

        return g, dg, law.Ca + self.natural_deceleration  # |e''| = |a + dn|

    def phase_acceleration(self, t, y, law, mode):
        return self._restoring(y[0], y[1], mode) - self.natural_deceleration

    # --- solution ---

    def response(self, law, options: BacklashOptions) -> BacklashResponse:
        model = self.validated()
        ts = sample_times(options.samples, options.dwell)
        rest = model.natural_deceleration / model.omega**2  # at rest on the driving flank
        sol = model._integrate(
            law, ts, (rest, jnp.zeros(())), DRIVING_FLANK,
            solver=solver(options.method), rtol=options.rtol, atol=options.atol,
            max_steps=options.max_steps, max_segments=options.max_segments, max_step=options.max_step,
        )
        e, de = sol.y
        # Invariant: every sample's contact state agrees with its deflection.
        tol = 1e-9 * (1.0 + model.backlash)
        consistent = jnp.where(
            sol.mode == DRIVING_FLANK, e >= -tol,
            jnp.where(sol.mode == FREE, (e <= tol) & (e >= -model.backlash - tol), e <= -model.backlash + tol),
        )
        result = RESULTS.where(
            (sol.result == RESULTS.successful) & ~jnp.all(consistent), RESULTS.invariant_violated, sol.result
        )
        acceleration = jax.vmap(lambda t, y, m: model.phase_acceleration(t, y, law, m))(ts, sol.y, sol.mode)
        in_motion, peak = model._peaks(law, ts, sol)
        i_end = options.samples  # tau = 1
        residual = residual_amplitude(e[i_end] - rest, de[i_end], model.omega, model.damping, options.dwell)
        # Impacts are the events that end a free flight, in order.
        impact = jnp.isfinite(sol.event_t) & (sol.event_mode[:, 0] == FREE)
        slot = jnp.where(impact, jnp.cumsum(impact) - 1, impact.shape[0])
        nan = jnp.full(impact.shape, jnp.nan)
        return BacklashResponse(
            tau=ts,
            payload_acceleration=acceleration,
            metrics=Metrics(peak / law.Ca, residual / law.Ca, in_motion / law.Ca),
            result=result,
            stats={"steps": sol.steps, "segments": sol.segments, "reached": sol.reached},
            deflection=e,
            contact=sol.mode,
            impact_tau=nan.at[slot].set(sol.event_t, mode="drop"),
            impact_velocity=nan.at[slot].set(jnp.abs(sol.event_y[1]), mode="drop"),
            impact_flank=jnp.full(impact.shape, -1).at[slot].set(sol.event_mode[:, 1], mode="drop"),
            n_impacts=jnp.sum(impact),
        )
