"""A chain with its one-sided contacts (the cam, lash, the valve's seat), simulated to its periodic steady state.

A chain with a lash or a seat (``Chain.has_contacts``) is not linear, so its periodic steady
state is found by time integration (diffrax, Tsit5 with error control, vmapped over the
speeds) rather than by the exact propagation of the closed chain (``SteadyState``).  The contacts:

- **The cam.**  A first body that rides on the cam is held on it by a unilateral
  constraint: while its gap ``w = x_1 - y`` is zero the contact force ``lambda`` is what
  keeps ``x_1'' = y''`` (exact: no contact stiffness), and it leaves the cam where that
  force would pull.  Where it lands again the force brings the gap to zero critically
  damped (``w'' = -W^2 w - 2 W w'``, ``W`` from ``RIDER_CONTACT_HZ``): a nearly plastic
  landing, without the chatter of a bouncing switch.  A first body on an element: that
  element is the contact and is one-sided like a lash (below).
- **Lash.**  An element with ``lash_mm > 0`` carries force only once its compression has
  closed the clearance, and is open where it would pull: its force is
  ``max(0, k a + c a')`` while its approach ``a`` (compression past closing) is positive,
  zero otherwise (a Kelvin-Voigt contact whose force is clipped at zero).  Elements without
  lash are linear and carry tension as well.
- **The seat.**  A spring of ``Seat.stiffness_n_per_mm`` with its dashpot
  (``damping_n_s_per_m``) under the last body, pushing only, as a lash element.

**The rest state** (the cam on its base circle, everything still) is where the coordinates
are measured from, and it decides which elements carry the spring's preload ``P``:

- *with a seat*: the valve sits on its seat, which carries ``P`` (compressed by ``P / k_seat``);
  every element of the chain carries nothing: each lash is open by its ``lash_mm`` and the
  other elements just touch (the cam's contact force on the base circle is zero).  The
  cam's opening ramp must first close the lash and compress the chain by ``P`` over its
  stiffness before the valve leaves its seat;
- *without a seat*: the chain is the closed chain of ``SteadyState`` (every element
  carries ``P`` through the levers, a lash is closed); a lash opens only where the dynamic
  force would pull, so its size does not matter.

**Integration.**  State: every moving coordinate in mm and its rate in mm per turn, time in
turns; the cam's lift, velocity and acceleration are the program's turn on the engine's grid
(``cycle_grid``'s piecewise quintics of ``y`` and ``y_ss``), and the step control is told
where the motion's acceleration jumps (segment ends and law breakpoints).  Turns run from the
rest state until the state at the turn's start moves by less than ``settle_tolerance`` times
the lift (positions) and the lift's largest rate (velocities) from one turn to the next (at
most ``max_turns``; a chain that does not settle is a ``ValueError`` naming what to damp).
The last turn is sampled at ``samples`` points, dense enough for a seat contact
(``SAMPLES_PER_CONTACT``), and read on the host: the seating velocity (the last body's speed
at its first seat contact of the closing, extrapolated from the sample before with its
acceleration), the bounces (every later re-impact, with its velocity), each lash's openings
and the separations.  A design reads the seating velocity the same way in JAX, from the
turn's start state and its landing's sample (``seating_velocity``, ``MaxSeatingVelocity``).

**Figures between the samples.**  The samples also keep the state, from which each reported
signal (the cam's contact force, each body's acceleration, the spring's seat force and
surge, the lift's rate) gets its first three derivatives in turn time along the trajectory
(``_signal_jets``: nested forward derivatives of the chain's equations, exact given the
state).  Each sample interval then has the septic Hermite interpolant the exact path refines
on (``camjax.metrics``), straight where a contact switches or the motion's acceleration
jumps inside it; the extremes (the bounded peak search of the closed chain's own figures),
the drive torque's figures (``torque_jets``, ``torque_figures``) and the Hertz peak
(``refined_contact_stress``) are read from those, by the exact path's own rules.  The jump speed is searched between the speeds given
(``ChainContacts.jump_speed``, ``narrowed_crossing``).

**Flights.**  A chain without lash or seat whose exact steady state loses contact runs here
too, its cam's contact the only one-sided one (a force-closed flexible arm's too, its roller
riding on the cam): from a state of that steady state where the cam holds, two turns (``ChainContacts.flights``), whose flights ``cam_flights`` reads
(``flights_at``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .._shapes import bucket
from ..metrics import bounded_extremes, septic_coefficients
from ..sdof import narrowed_crossing
from ._contact import RefinedStress, contact_stress_squared, node_contact, refined_contact_stress
from ._contact_residual import contact_residual_mm
from ._cycle_grid import cycle_grid
from ._dynamics import SPEED_BLOCK
from ._flight import Flight
from ._speeds import Speeds, speed_warnings
from ._torque import TorqueFigures, torque_figures, torque_jets
from ._train import Chain

RIDER_CONTACT_HZ = 8.0
"""A body riding on the cam that lands on it is brought to the cam's motion critically
damped at this many times the chain's highest natural frequency (``ARM_CONTACT_HZ`` on a
flexible arm; or the seat's where that is higher): a nearly plastic landing; in lasting
contact the constraint holds exactly."""
ARM_CONTACT_HZ = 1.0
"""``RIDER_CONTACT_HZ`` of a roller on a flexible arm: its landing is critically damped at the
chain's highest natural frequency with the cam held, the reduced arm's quickest kept mode
(``Arm.modes``), itself.  The arm's kept modes already set the integration's step, so this
landing costs little more, where eight times it would multiply the steps and the samples
(measured 2026-11-29 on commit 6beae5c with this rule: diffrax's ``num_steps`` of a turn of
the example swinging_arm_spring from rest, its highest mode 67.8 kHz: 12,355 at 3000 rpm
and 37,670 at 1000 rpm, under ``turn_steps_refusal``'s 16,063 and 43,189; 42,157 and
215,476 at eight times it; 8,437 and 15,330 at eight times the first mode, 15.4 kHz).  Separation, flight and landing angle do not depend on it; the landing's
peak force is this model's."""
SAMPLES_PER_CONTACT = 12
"""Samples of the reported turn per half period of the stiffest contact (the seat's or the
landing's): the seat's impacts are read between samples."""
CLOSED_MM = 1e-5
"""An element, seat or cam contact is closed when its approach is past this (mm) and its
force positive; a riding body has left the cam when its gap passes it."""


STEPS_PER_CONTACT_CYCLE = 10.0
"""Integration steps a turn takes per period of the stiffest contact (``stiffest_hz``) at
the default tolerances: at slow speeds the step control holds the stiffest contact's
oscillation (or the landing's) to about this many steps a period all turn long, so a turn's
steps grow as ``stiffest_hz * 60 / rpm``.  Measured 2026-11-29 at commit 5c36854 (Tsit5,
rtol = atol = 1e-8): the example valve_lash 8.2 per period plus about 2,200 a turn (6,160
steps at 1000 rpm, 15,490 at 300), a seated chain without lash 10.4 plus about 1,800 (4,370
and 10,360), each diffrax's ``num_steps`` of one turn from rest.  ``turn_steps_refusal`` refuses a turn this estimate (with
``STEPS_PER_TURN``) puts past ``ContactOptions.max_steps`` before simulating it."""
STEPS_PER_TURN = 2_500.0
"""Integration steps a turn takes besides those of the stiffest contact's periods (the
motion's segment ends and breakpoints, the landings): the measurements of
``STEPS_PER_CONTACT_CYCLE``, rounded up, so that the estimate lies above each measured turn."""


_HELD_M = 1e-9
"""A riding body within this gap (m) of the cam is held on it: a band above the integration's
error in the body's position (the cam's lift and its acceleration are two fits that differ by
about 1e-12 m), so that no error lets a held body fly (a chattering switch costs the step
control millions of steps)."""


@dataclasses.dataclass(frozen=True)
class ContactOptions:
    """How a chain with contacts is simulated (``ChainContacts``).

    ``rtol``/``atol``: diffrax's error control on the state (mm and mm per turn);
    ``settle_tolerance``: the largest turn-to-turn change of the state at the turn's start,
    relative to the lift and to its largest rate, of a settled run; ``max_turns`` turns
    at most; ``samples``: points of the reported turn (default: ``SAMPLES_PER_CONTACT``
    per half period of the stiffest contact at the slowest speed, at least 4096);
    ``max_steps``: integrator steps per turn at most; ``jump_tolerance_rpm``: the width of
    the bracket to which the jump speed is searched between the speeds given."""

    rtol: float = 1e-8
    atol: float = 1e-8
    settle_tolerance: float = 1e-6
    max_turns: int = 40
    samples: int | None = None
    max_steps: int = 200_000
    jump_tolerance_rpm: float = 0.1

    def __post_init__(self):
        if self.samples is not None and (
            isinstance(self.samples, bool) or not isinstance(self.samples, int) or self.samples < 16
        ):
            raise ValueError(
                f"ContactOptions.samples must be a whole number of at least 16, got {self.samples!r}"
            )
        tolerance = self.jump_tolerance_rpm
        if (
            isinstance(tolerance, bool)
            or not isinstance(tolerance, int | float)
            or not math.isfinite(tolerance)
            or tolerance <= 0
        ):
            raise ValueError(
                f"ContactOptions.jump_tolerance_rpm must be a positive number, got {tolerance!r}"
            )


class ContactSystem(NamedTuple):
    """The chain's equations over its moving coordinates (SI), as arrays: the compiled
    turn's argument, so an edit of values compiles nothing.

    ``M a = -G^T f - K_s u - C_s u' + load + seat_row f_seat + e_0 lambda``: ``f`` the
    chain's element forces (element ``j`` approaches by ``d0_j + G_j u + g_cam_j y``,
    one-sided where ``one_sided_j``), ``K_s``/``C_s`` the return spring, ``load`` its
    preload on the last body, ``lambda`` the riding body's contact force (``rider``)."""

    Minv: np.ndarray
    Ks: np.ndarray
    Cs: np.ndarray
    load: np.ndarray
    G: np.ndarray
    g_cam: np.ndarray
    d0: np.ndarray
    k: np.ndarray
    c: np.ndarray
    one_sided: np.ndarray
    seat_row: np.ndarray
    seat_k: np.ndarray
    seat_c: np.ndarray
    seat_s0: np.ndarray
    rider: np.ndarray
    rider_k: np.ndarray
    rider_c: np.ndarray
    body_rows: np.ndarray
    spring_K: np.ndarray
    spring_C: np.ndarray
    spring_M: np.ndarray
    preload: np.ndarray
    rate: np.ndarray

    @classmethod
    def of(cls, chain: Chain) -> ContactSystem:
        if chain.arm is not None and chain.has_contacts:
            raise ValueError(
                "[arm]: a flexible arm with lash is not simulated (give its lash_mm 0)"
            )
        a = chain.matrices()
        rider = chain.bodies[0].rides
        start = 0 if rider else 1
        moving = np.arange(start, a.seat)
        n = moving.size
        size = a.seat + 1
        preload = chain.spring.preload_n if chain.spring is not None else 0.0
        seated = chain.seat is not None
        K_el, C_el = np.zeros((size, size)), np.zeros((size, size))
        G, g_cam, d0, k, c, one_sided = [], [], [], [], [], []
        carried = preload  # the static force each element carries without a seat
        elements = []
        for j, body in enumerate(chain.bodies):
            if body.rides:
                continue
            before = 0 if j == 0 else a.body_index[j - 1]
            elements.append((j, before, a.body_index[j], body))
        forces = {}
        for j, _, _, body in reversed(elements):
            forces[j] = carried
            carried *= body.ratio
        for j, before, after, body in elements:
            kj, cj, r = 1e3 * body.stiffness_n_per_mm, body.damping_n_s_per_m, body.ratio
            g = np.array([r, -1.0])
            idx = np.ix_([before, after], [before, after])
            K_el[idx] += kj * np.outer(g, g)
            C_el[idx] += cj * np.outer(g, g)
            row = np.zeros(size)
            row[after] -= 1.0
            cam = 0.0
            if before == 0 and not rider:
                cam = r
            else:
                row[before] += r
            G.append(row[moving])
            g_cam.append(cam)
            k.append(kj)
            c.append(cj)
            one_sided.append(float(body.lash_mm > 0 or (before == 0 and not rider)))
            d0.append(-1e-3 * body.lash_mm if seated else forces[j] / kj)
        spring_K = (a.K - K_el)[np.ix_(moving, moving)]
        spring_C = (a.C - C_el)[np.ix_(moving, moving)]
        last = int(a.body_index[-1]) - start
        load = np.zeros(n)
        load[last] = -preload
        if chain.arm is not None:  # from the rest, where the preload bends the arm and the
            beam = dataclasses.replace(chain, spring=None).matrices().K  # spring carries it:
            b = beam.shape[0] - 1  # the arm's coordinates, the first b; at u = 0 the preload
            bent = np.linalg.solve(beam[1:b, 1:b], load[1:b])  # and the bending leave
            load[:b] -= beam[:b, 1:b] @ bent  # the cam's static force alone (load[0])
        seat_row = np.zeros(n)
        seat_k = seat_c = seat_s0 = 0.0
        if seated:
            seat_row[last] = 1.0
            seat_k = 1e3 * chain.seat.stiffness_n_per_mm
            seat_c = chain.seat.damping_n_s_per_m
            seat_s0 = preload / seat_k
        top = max(chain.highest_frequency_hz(), 1.0)
        w_p = 2 * math.pi * (RIDER_CONTACT_HZ if chain.arm is None else ARM_CONTACT_HZ) * top
        if seated:
            w_p = max(w_p, math.sqrt(seat_k / chain.bodies[-1].mass_kg))
        M = a.M[np.ix_(moving, moving)]
        rate = 1e3 * chain.spring.rate_n_per_mm if chain.spring is not None else 0.0
        E = len(elements)
        return cls(
            Minv=np.linalg.inv(M),
            Ks=spring_K,
            Cs=spring_C,
            load=load,
            G=np.asarray(G).reshape(E, n),
            g_cam=np.asarray(g_cam, dtype=float),
            d0=np.asarray(d0, dtype=float),
            k=np.asarray(k, dtype=float),
            c=np.asarray(c, dtype=float),
            one_sided=np.asarray(one_sided, dtype=float),
            seat_row=seat_row,
            seat_k=np.asarray(seat_k),
            seat_c=np.asarray(seat_c),
            seat_s0=np.asarray(seat_s0),
            rider=np.asarray(float(rider)),
            rider_k=np.asarray(w_p**2),
            rider_c=np.asarray(2 * w_p),
            body_rows=np.asarray(a.body_index) - start,
            spring_K=a.K[a.seat, moving],
            spring_C=a.C[a.seat, moving],
            spring_M=a.M[a.seat, moving],
            preload=np.asarray(preload),
            rate=np.asarray(rate),
        )

    @property
    def stiffest_hz(self) -> float:
        """The frequency of the stiffest contact on its body (the seat's or a landing's)."""
        m_last = 1.0 / self.Minv[self.body_rows[-1], self.body_rows[-1]]
        seat = math.sqrt(float(self.seat_k) / m_last) if float(self.seat_k) else 0.0
        rider = math.sqrt(float(self.rider_k)) if float(self.rider) else 0.0
        return max(
            seat,
            rider,
            float(np.sqrt(np.max(self.k) * np.max(np.diag(self.Minv)))) if self.k.size else 0.0,
        ) / (2 * math.pi)


def _round_up(value: float) -> float:
    """``value`` rounded up to three significant digits (a speed to name in a message)."""
    scale = 10.0 ** (math.floor(math.log10(value)) - 2)
    return math.ceil(value / scale - 1e-9) * scale


def turn_steps_refusal(
    chain: Chain, system: ContactSystem, rpm: float, max_steps: int
) -> str | None:
    """Why a turn at ``rpm`` cannot be simulated within ``max_steps`` integration steps, with
    the slowest speed that fits and the field that sets the stiffest contact; ``None`` where
    it fits.  The steps are estimated as ``STEPS_PER_CONTACT_CYCLE`` per period of the
    stiffest contact (``ContactSystem.stiffest_hz``) and ``STEPS_PER_TURN``: read before
    simulating, where the integration itself would fail only after minutes."""
    hz = system.stiffest_hz
    cycles = hz * 60.0 / rpm
    steps = STEPS_PER_CONTACT_CYCLE * cycles + STEPS_PER_TURN
    if steps <= max_steps:
        return None
    room = max_steps - STEPS_PER_TURN
    if room <= 0:
        return (
            f"ContactOptions.max_steps = {max_steps:,}: fewer than the {STEPS_PER_TURN:,.0f} "
            "integration steps any turn takes; give it more"
        )
    slowest = _round_up(STEPS_PER_CONTACT_CYCLE * hz * 60.0 / room)
    m_last = 1.0 / system.Minv[system.body_rows[-1], system.body_rows[-1]]
    seat_hz = math.sqrt(float(system.seat_k) / m_last) / (2 * math.pi)
    if seat_hz >= hz * (1 - 1e-9):
        field = "[seat] stiffness_n_per_mm"
    elif chain.arm is not None:  # the landing on the cam, at the arm's highest mode
        field = chain.highest_mode_remedy().removeprefix("lower ")
    else:
        j, body = max(
            ((j, b) for j, b in enumerate(chain.bodies, 1) if not b.rides),
            key=lambda jb: jb[1].stiffness_n_per_mm,
        )
        field = f"[[train]] body {j} ({body.name}) stiffness_n_per_mm"
    return (
        f"[[train]]: a turn at {rpm:g} rpm would need about {steps:,.0f} integration steps (the "
        f"stiffest contact, {hz:.4g} Hz, vibrates {cycles:,.0f} times a turn, about "
        f"{STEPS_PER_CONTACT_CYCLE:g} steps each), more than ContactOptions.max_steps "
        f"({max_steps:,}): run at {slowest:g} rpm or faster, or lower {field}"
    )


def _valve_travel(program, chain: Chain):
    """The chain's elements ``(j, body)`` (from 1), each one's lash referred to the valve
    (``lash_j prod_{i > j} r_i``, mm), the cam's largest lift and the valve's lift through
    the chain (the cam's, ``Program.largest_lift_mm``, times the ratios, mm)."""
    elements = [(j, b) for j, b in enumerate(chain.bodies, 1) if not b.rides]
    after = np.cumprod([b.ratio for _, b in elements][::-1])[::-1]  # prod_{i >= j} r_i
    referred = [b.lash_mm * float(a / b.ratio) for (_, b), a in zip(elements, after)]
    lift = program.largest_lift_mm()
    return elements, referred, lift, lift * float(after[0])


def lash_refusal(program, chain: Chain) -> str | None:
    """Lash the cam's lift cannot take up: with a seat the valve leaves it only once the cam,
    through the levers, has closed every lash, so where the lash referred to the valve
    (``sum_j lash_j prod_{i > j} r_i``) is at least the valve's kinematic lift (the cam's
    largest lift times the ratios) the valve never opens and the bodies before the lash,
    held by no spring, never settle.  ``None`` where the lift exceeds it (or without a seat:
    there the preload closes the lash at rest)."""
    if chain.seat is None:
        return None
    elements, referred, lift, valve = _valve_travel(program, chain)
    total = sum(referred)
    if not total or total < valve:
        return None
    j, body = elements[int(np.argmax(referred))]
    return (
        f"[[train]] body {j} ({body.name}) lash_mm = {body.lash_mm:g}: the chain's lash "
        f"({total:.4g} mm at the valve) is not less than the valve's lift through the chain "
        f"({valve:.4g} mm: the cam's {lift:.4g} mm times the ratios): the lash never closes and "
        "the valve never leaves its seat (a valve's lash is a few tenths of a mm)"
    )


def seat_refusal(program, chain: Chain) -> str | None:
    """A seat the cam's lift cannot lift the valve off: at rest the spring's preload ``P``
    squeezes the seat by ``P / k_seat``, and the valve leaves it only once the cam, through
    the levers, has closed the lash and lifted it by that much, so where the squeeze and the
    lash referred to the valve reach the valve's lift through the chain, the valve never
    leaves its seat even with a rigid chain (a softer chain lifts it less).  ``None`` where
    the lift exceeds them, or without a seat."""
    if chain.seat is None or chain.spring is None:
        return None
    _, referred, lift, valve = _valve_travel(program, chain)
    squeeze = chain.spring.preload_n / chain.seat.stiffness_n_per_mm
    lash = sum(referred)
    if squeeze + lash < valve:
        return None
    return (
        f"[seat] stiffness_n_per_mm = {chain.seat.stiffness_n_per_mm:g}: the spring's preload "
        f"({chain.spring.preload_n:g} N) squeezes the seat by {squeeze:.4g} mm at rest, which with "
        f"the lash ({lash:.4g} mm at the valve) is not less than the valve's lift through the "
        f"chain ({valve:.4g} mm: the cam's {lift:.4g} mm times the ratios): the valve never "
        "leaves its seat (a valve's seat takes tens of thousands of N/mm)"
    )


def spring_hold_rpm(program, chain: Chain) -> float | None:
    """The highest speed at which the return spring holds the chain on the cam, the chain
    taken rigid: ``R (P + k R y) >= m (-y'')`` at every angle (``y`` the cam's lift, ``R`` the
    product of the ratios, ``P``/``k`` the spring's preload and rate, ``m`` the chain's mass
    referred to the cam: each body's and lever's times its squared ratio from the cam, a third
    of the spring's at the valve); ``None`` without a spring or where the cam never
    decelerates.  An estimate for a message: the flexible chain's own jump speed differs."""
    spring = chain.spring
    if spring is None:
        return None
    theta = np.arange(3600) * 0.1
    y, _, ydd = (np.asarray(v, dtype=float) for v in program.lift(theta))
    mass, ratio = 0.0, 1.0
    for body in chain.bodies:
        if not body.rides:
            mass += body.lever_mass_kg * ratio**2
            ratio *= body.ratio
        mass += body.mass_kg * ratio**2
    mass += spring.mass_kg / 3 * ratio**2
    falling = ydd < 0
    if not falling.any() or mass <= 0:
        return None
    hold = ratio * (spring.preload_n + 1e3 * spring.rate_n_per_mm * ratio * 1e-3 * y[falling])
    deg_per_s2 = hold / (mass * 1e-3 * -ydd[falling])  # (360 rpm / 60)^2 at the limit
    return float(np.sqrt(max(float(np.min(deg_per_s2)), 0.0)) / 6.0)


def _lift_at(nodes, lift, acceleration, s):
    """``y``, ``y_s`` and ``y_ss`` (mm, per turn) at turn time ``s`` (periodic) from the
    grid's quintics (``CycleGrid.lift`` and ``motion.forcing``)."""
    s = s - jnp.floor(s)
    i = jnp.clip(jnp.searchsorted(nodes, s, side="right") - 1, 0, nodes.size - 2)
    h = nodes[i + 1] - nodes[i]
    sigma = (s - nodes[i]) / jnp.where(h > 0, h, 1.0)
    powers = jnp.cumprod(jnp.concatenate([jnp.ones(1), jnp.full(5, sigma)]))  # not sigma**k: its
    y = lift[i] @ powers  # derivative at sigma = 0 is 0 * inf (the jets differentiate it)
    dy = (lift[i, 1:] * jnp.arange(1, 6)) @ powers[:5] / h
    return y, dy, acceleration[i] @ powers


def _state_forces(system: ContactSystem, y, yd, ydd, u, v):
    """Accelerations (m/s^2) and the contact forces of the chain at one instant (SI)."""
    s = system
    approach = s.d0 + s.G @ u + s.g_cam * y
    rate = s.G @ v + s.g_cam * yd
    raw = s.k * approach + s.c * rate
    closed = approach > 0
    f = jnp.where(s.one_sided > 0, jnp.where(closed, jnp.maximum(raw, 0.0), 0.0), raw)
    signal = jnp.minimum(s.k * approach, raw)  # positive while an element is closed
    seat_gap = s.seat_s0 - s.seat_row @ u  # the seat's approach
    seat_raw = s.seat_k * seat_gap - s.seat_c * (s.seat_row @ v)
    f_seat = jnp.where(seat_gap > 0, jnp.maximum(seat_raw, 0.0), 0.0)
    F = -s.G.T @ f - s.Ks @ u - s.Cs @ v + s.load + s.seat_row * f_seat
    a_free = s.Minv @ F
    w, wd = u[0] - y, v[0] - yd
    # held: the force that gives the gap w'' = -W^2 w - 2 W w' (critically damped onto the cam:
    # in lasting contact exactly the constraint's, and a landing never rebounds nor chatters)
    wanted = ydd - s.rider_k * w - s.rider_c * wd
    held = jnp.where(w <= _HELD_M, jnp.maximum(0.0, (wanted - a_free[0]) / s.Minv[0, 0]), 0.0)
    lam = s.rider * held
    acc = a_free + s.Minv[:, 0] * lam
    return acc, f, signal, f_seat, jnp.minimum(s.seat_k * seat_gap, seat_raw), lam, w


class _Grid(NamedTuple):
    nodes: jax.Array
    lift: jax.Array
    acceleration: jax.Array
    jumps: jax.Array


def contact_grid(cycle, breaks) -> _Grid:
    """The simulation's grid of a turn (``CycleGrid``: its lift and acceleration may be
    traced, ``with_segment_law``) padded to a bucket of 64 intervals, with the step
    control's jumps at ``breaks`` (turns) padded to a bucket of 8: one compile per bucket."""
    size = bucket(cycle.intervals, 64)
    nodes = np.concatenate([np.asarray(cycle.nodes), np.ones(size - cycle.intervals)])
    pad = np.zeros((size - cycle.intervals, 6))
    jumps = np.asarray(breaks, dtype=float)
    jumps = jumps[(jumps > 0) & (jumps < 1)]
    jumps = np.concatenate([jumps, np.full(bucket(jumps.size + 1, 8) - jumps.size, 0.5)])
    xp = jnp if isinstance(cycle.lift, jax.Array) else np
    return _Grid(
        nodes,
        xp.concatenate([cycle.lift, pad]),
        xp.concatenate([cycle.motion.forcing, pad]),
        np.sort(jumps),
    )


def _equations(rpm, system: ContactSystem, grid: _Grid):
    """The chain's equations at ``rpm`` in turn time (state ``z``: mm and mm per turn): the
    cam's jet (SI), the field ``dz/ds`` and the sampled ``signals`` (``_SIGNALS``)."""
    period = 60.0 / rpm
    n = system.Minv.shape[0]

    def jet(s):
        y, ys, yss = _lift_at(grid.nodes, grid.lift, grid.acceleration, s)
        return 1e-3 * y, 1e-3 * ys / period, 1e-3 * yss / period**2

    def field(s, z, args=None):
        y, yd, ydd = jet(s)
        u, v = 1e-3 * z[:n], 1e-3 * z[n:] / period
        acc = _state_forces(system, y, yd, ydd, u, v)[0]
        return jnp.concatenate([z[n:], 1e3 * period**2 * acc])

    def signals(s, z):
        """The signals whose extremes and integrals are reported (``_SIGNALS``)."""
        y, yd, ydd = jet(s)
        u, v = 1e-3 * z[:n], 1e-3 * z[n:] / period
        acc, f, _, _, _, lam, _ = _state_forces(system, y, yd, ydd, u, v)
        spring = system.preload - system.spring_K @ u - system.spring_C @ v - system.spring_M @ acc
        head = jnp.stack(
            [lam + system.g_cam @ f, 1e3 * yd * period, spring, _surge(system, u, v, acc)]
        )
        return jnp.concatenate([head, acc[system.body_rows]])

    return jet, field, signals


def _surge(system: ContactSystem, u, v, acc):
    """The spring's surge (N): its force at its seat less the static ``F_0 + k_s x_N``, from
    the state as the exact path's row (``-K_seat - k_s e_N``, its preload left out), so that a
    spring without mass, whose row is zero, has none: exactly 0, not the rounding of the force
    less its static part."""
    row = system.spring_K.at[system.body_rows[-1]].add(system.rate)
    return -(row @ u) - system.spring_C @ v - system.spring_M @ acc


_SIGNALS = ("cam", "lift_rate", "spring", "surge")
"""The leading rows of ``_equations``' signals (the cam's contact force N, the lift's rate
mm per turn, the spring's force at its seat N and its surge N), then each body's
acceleration (m/s^2)."""


def _signal_jets(z, rpm, system: ContactSystem, grid: _Grid):
    """``(signals, 4)``: every signal of ``_equations`` at turn time ``s`` and its first three
    derivatives in turn time along the trajectory through the state ``z`` (``D g = dg/ds +
    dg/dz . dz/ds``, nested: exact given the state, one-sided where a contact switches)."""
    s, z = z[0], z[1:]
    system, grid = jax.tree.map(jnp.asarray, (system, grid))
    _, field, signals = _equations(rpm, system, grid)

    def along(g):
        return lambda s, z: jax.jvp(g, (s, z), (jnp.ones_like(s), field(s, z)))[1]

    d1 = along(signals)
    d2 = along(d1)
    d3 = along(d2)
    return jnp.stack([signals(s, z), d1(s, z), d2(s, z), d3(s, z)], axis=-1)


def _turn(
    z0, rpm, t0, t1, system: ContactSystem, grid: _Grid, samples: int, options: ContactOptions
):
    """From state ``z0`` (mm, mm per turn) at turn time ``t0`` to ``t1`` (one turn from 0 to 1
    to settle; at most two) at ``rpm``: the end state, the samples ``(samples + 1, outputs)``
    evenly over ``[t0, t1]`` and whether the integration succeeded (jittable, vmappable)."""
    return _solve(z0, rpm, t0, t1, jnp.linspace(t0, t1, samples + 1), system, grid, options)


def _solve(
    z0, rpm, t0, t1, ts, system: ContactSystem, grid: _Grid, options: ContactOptions, adjoint=None
):
    """``_turn`` sampled at the turn times ``ts`` (in ``[t0, t1]``): the samples are the dense
    solution's there, so the steps, and every sample, are the same whichever are asked for;
    ``adjoint``: diffrax's (how it is differentiated; default its own)."""
    import diffrax

    system, grid = jax.tree.map(jnp.asarray, (system, grid))
    period = 60.0 / rpm
    n = z0.size // 2
    jet, field, _ = _equations(rpm, system, grid)

    def sample(s, z, args):
        y, yd, ydd = jet(s)
        u, v = 1e-3 * z[:n], 1e-3 * z[n:] / period
        acc, f, signal, f_seat, seat_signal, lam, w = _state_forces(system, y, yd, ydd, u, v)
        last = system.body_rows[-1]
        cam = lam + system.g_cam @ f
        spring = system.preload - system.spring_K @ u - system.spring_C @ v - system.spring_M @ acc
        return jnp.concatenate(
            [
                jnp.stack(
                    [
                        cam,
                        f_seat,
                        seat_signal,
                        w,
                        1e3 * u[last],
                        v[last],
                        acc[last],
                        spring,
                        _surge(system, u, v, acc),
                        1e3 * y,
                    ]
                ),
                f,
                signal,
                acc[system.body_rows],
                1e3 * u[system.body_rows],
                v[system.body_rows],
                jnp.concatenate([s[None], z]),  # the state, for the jets (_signal_jets)
            ]
        )

    controller = diffrax.ClipStepSizeController(
        diffrax.PIDController(rtol=options.rtol, atol=options.atol),
        jump_ts=jnp.concatenate([grid.jumps, grid.jumps + 1.0]),  # the turn's and the next one's
    )
    solution = diffrax.diffeqsolve(
        diffrax.ODETerm(field),
        diffrax.Tsit5(),
        t0,
        t1,
        None,
        z0,
        saveat=diffrax.SaveAt(
            subs=[
                diffrax.SubSaveAt(t1=True),
                diffrax.SubSaveAt(ts=ts, fn=sample),
            ]
        ),
        stepsize_controller=controller,
        max_steps=options.max_steps,
        throw=False,
        **({} if adjoint is None else {"adjoint": adjoint}),
    )
    end, samples_out = solution.ys
    return end[-1], samples_out, solution.result == diffrax.RESULTS.successful


def seating_velocity(
    z0, rpm, sample, system: ContactSystem, grid: _Grid, samples: int, options: ContactOptions
):
    """The turn from state ``z0`` at its start (``_turn``'s) and the last body's seating
    velocity (m/s) read from its sample ``sample`` of ``samples`` (``seat_landings``):
    ``(end state, velocity)``, jittable and differentiable in ``z0`` and the grid's lift.

    The landing is read as ``_read`` reads it, from the quadratic of the seat's approach
    ``g + r t + a t^2 / 2`` about the sample (``g <= 0``): its closing speed where the
    approach reaches zero, ``r + a t = sqrt(r^2 - 2 a g)``, so the landing time's dependence
    on the law is in the formula (the implicit function theorem on the sampled path)."""
    t = jnp.mod(sample, samples) / samples
    import diffrax

    end, x, _ = _solve(
        z0, rpm, 0.0, 1.0, jnp.stack([t]), system, grid, options, diffrax.ForwardMode()
    )
    column = {name: x[0, i] for i, name in enumerate(_COLUMNS)}
    gap = system.seat_s0 - 1e-3 * column["last_mm"]
    rate, accel = -column["last_v"], -column["last_a"]
    return end, jnp.sqrt(rate**2 - 2.0 * accel * gap)


_COLUMNS = (
    "cam",
    "seat",
    "seat_signal",
    "gap",
    "last_mm",
    "last_v",
    "last_a",
    "spring",
    "surge",
    "lift_mm",
)


def _turns_compiled():
    return jax.jit(
        jax.vmap(_turn, in_axes=(0, 0, 0, 0, None, None, None, None)), static_argnums=(6, 7)
    )


_turns = _turns_compiled()


def _state_before(
    z_after, s_target, rpm, system: ContactSystem, grid: _Grid, options: ContactOptions
):
    """The state (mm, mm per turn) at turn time ``s_target`` from a sample's ``(s, z)`` just
    after it (at most one sample interval), and whether the integration succeeded: the
    chain's equations (``_equations``) integrated back in time by the turn's own method
    (diffrax's Tsit5 under the simulation's error control, ``options.rtol``/``atol``), all
    on the segment's side of its start (where the motion's acceleration may jump: the field
    is read there from the segment's side), so the state is the turn's to its tolerance."""
    import diffrax

    system, grid = jax.tree.map(jnp.asarray, (system, grid))
    _, field, _ = _equations(rpm, system, grid)
    solution = diffrax.diffeqsolve(
        diffrax.ODETerm(field),
        diffrax.Tsit5(),
        z_after[0],
        s_target,
        None,
        z_after[1:],
        saveat=diffrax.SaveAt(t1=True),
        stepsize_controller=diffrax.PIDController(rtol=options.rtol, atol=options.atol),
        max_steps=options.max_steps,
        throw=False,
    )
    return solution.ys[-1], solution.result == diffrax.RESULTS.successful


_states_before = jax.jit(
    jax.vmap(
        jax.vmap(_state_before, in_axes=(0, 0, None, None, None, None)),
        in_axes=(0, None, 0, None, None, None),
    ),
    static_argnums=5,
)
_sample_jets = jax.jit(jax.vmap(_signal_jets, in_axes=(0, None, None, None)))
_jets = jax.jit(jax.vmap(_sample_jets, in_axes=(0, 0, None, None)))


def _cam_jets(states, indices: np.ndarray, rpm: float, system: ContactSystem, grid: _Grid):
    """The contact force's jets ``(indices, 4)`` (``_signal_jets``) at the samples
    ``indices`` of one run's ``states``, computed in a bucketed block of 64 (one compile)."""
    padded = np.pad(indices, (0, bucket(max(indices.size, 1), 64) - indices.size))
    jets = _sample_jets(states[padded], rpm, system, grid)
    return np.asarray(jets)[: indices.size, _SIGNALS.index("cam")]


def _straightened(values, left, right, widths, switched):
    """The derivatives ``left``/``right`` ``(samples, 3)`` of a signal at the ends of each
    sample interval, those of the straight line between its ends where a contact switches or
    the motion's acceleration jumps inside it (``switched``: there the one-sided derivatives
    belong to different equations): that interval's septic Hermite interpolant is then the
    line, its extremes at its ends."""
    slope = (values[1:] - values[:-1]) / widths
    line = jnp.stack([slope, jnp.zeros_like(slope), jnp.zeros_like(slope)], axis=1)
    return jnp.where(switched[:, None], line, left), jnp.where(switched[:, None], line, right)


def _extremes(values, left, right, widths):
    """``(min, max)`` of a signal between its samples: the exact path's bounded search of its
    septic interpolants (``camjax.metrics.bounded_extremes``, which refines only the
    intervals that can hold an extreme)."""
    return jnp.stack(bounded_extremes(values, widths, left, right))


def _turn_figures(jets, switched, widths):
    """One turn's figures from the signals' jets ``(samples + 1, signals, 4)``: the drive
    torque at the samples and its ``TorqueFigures`` (``torque_jets``, ``torque_figures``:
    the exact path's rules), every signal's ``(min, max)`` refined between the samples
    ``(signals, 2)`` and the contact force's interpolants ``(samples, 8)``, each interval
    straight where a contact switches or the acceleration jumps (``_straightened``)."""
    cam, rate = _SIGNALS.index("cam"), _SIGNALS.index("lift_rate")

    def straightened(values, left, right):
        return _straightened(values, left, right, widths, switched)

    values = jets[:, :, 0].T
    left, right = jax.vmap(straightened, in_axes=(0, 1, 1))(
        values, jets[:-1, :, 1:], jets[1:, :, 1:]
    )
    extremes = jax.vmap(_extremes, in_axes=(0, 0, 0, None))(values, left, right, widths)
    torque = torque_jets(values[cam], left[cam], right[cam], values[rate], left[rate], right[rate])
    figures = torque_figures(torque[0], widths, *straightened(*torque))
    septic = septic_coefficients(values[cam], widths, left[cam], right[cam])
    return torque[0], figures, extremes, septic


_figures = jax.jit(jax.vmap(_turn_figures, in_axes=(0, 0, None)))


@dataclasses.dataclass(frozen=True)
class Impact:
    """A landing of the last body on its seat: the cam angle (deg) and its speed (m/s, down)."""

    angle_deg: float
    velocity_m_s: float

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


class Refined(NamedTuple):
    """One settled turn's figures between its samples (``_turn_figures``): ``jets``
    ``(samples + 1, signals, 4)``, each signal (``_SIGNALS``, then each body's acceleration)
    and its first three derivatives in turn time; the drive torque at the samples and its
    figures; ``extremes`` ``(signals, 2)``, each signal's least and largest value over the
    turn; ``switched`` the sample intervals where a contact switches or the motion's
    acceleration jumps (their interpolants linear); ``force_septic`` ``(samples, 8)`` the
    contact force's interpolants (``septic_coefficients``)."""

    jets: np.ndarray
    drive_torque_n_m: np.ndarray
    torque: TorqueFigures
    extremes: np.ndarray
    switched: np.ndarray
    force_septic: np.ndarray


@dataclasses.dataclass(frozen=True)
class ContactTurn:
    """The settled turn at one speed: samples over the cam angle and what a valve-train
    engineer reads from them.

    ``seating_velocity_m_s``: the last body's speed at its first seat contact of the closing
    (the end of its longest time off the seat; ``None`` without a seat or a lift off it),
    read from the sample ``seating_sample`` (``seat_landings``, ``seating_velocity``);
    ``bounces``: every later landing in the turn; ``lash_openings_deg``: per lash element
    (by body name) the angles at which it opens; ``separates``: per contact (``cam``, each
    lash element's body, ``seat``) whether it separates: the cam or a lash opening while
    the valve is off its seat (anywhere without a seat), the seat bouncing; ``turns`` run and
    the ``change`` that remained (relative, ``ContactOptions.settle_tolerance``);
    ``residual_vibration_mm``: the last body's residual vibration at the start of each dwell
    and constant-velocity segment (``contact_residual_mm``; empty where not refined)."""

    rpm: float
    theta_deg: np.ndarray
    lift_mm: np.ndarray  # the cam's lift
    last_mm: np.ndarray  # the last body's displacement from rest
    last_velocity_m_s: np.ndarray
    cam_force_n: np.ndarray
    seat_contact_force_n: np.ndarray
    element_force_n: np.ndarray  # (elements, samples)
    acceleration_m_s2: np.ndarray  # (bodies, samples)
    displacement_mm: np.ndarray  # (bodies, samples): each body's from rest
    velocity_m_s: np.ndarray  # (bodies, samples)
    spring_seat_force_n: np.ndarray
    surge_n: np.ndarray
    seating_velocity_m_s: float | None
    seating_sample: int | None  # the sample the seating is read from (the last in flight)
    start_state: np.ndarray  # the state at the turn's start (mm, mm per turn): periodic
    bounces: tuple[Impact, ...]
    lash_openings_deg: dict
    separates: dict
    turns: int
    change: float
    refined: Refined | None  # the drive torque and the extremes refined between the samples
    residual_vibration_mm: tuple[float, ...] = ()  # at each dwell's start (contact_residual_mm)

    @property
    def drive_torque_n_m(self) -> np.ndarray:
        """``T = F_c dy/dtheta`` (N m) at the samples (``torque_jets``)."""
        return self.refined.drive_torque_n_m

    @property
    def torque(self) -> TorqueFigures:
        """The drive torque's peak, RMS, mean and energy fluctuation (``torque_figures``)."""
        return self.refined.torque


def _crossings(closed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sample indices ``i`` where a periodic contact closes (open at ``i``, closed at
    ``i + 1``) and where it opens (closed at ``i``, open at ``i + 1``)."""
    nxt = np.roll(closed, -1)
    return np.flatnonzero(~closed & nxt), np.flatnonzero(closed & ~nxt)


def seat_landings(seat_closed: np.ndarray, approach: np.ndarray) -> list[int]:
    """The samples from which each landing of a turn on the seat is read: the last one in
    flight (``approach``, the seat's in m, not yet positive) before each closing of
    ``seat_closed`` (per sample of the turn), the seating first (the closing that ends the
    longest time off the seat), then the bounces in turn order.

    A closing with no sample in flight since the seat last opened is no landing: the seat's
    force only dipped (its dashpot unloading it) while the valve stayed on it.  A turn whose
    valve never leaves its seat, or never lands on it, has none."""
    closes, opens = _crossings(seat_closed)
    m = seat_closed.size
    landings, lengths = [], []
    for i, length in zip(closes, _interval_lengths(seat_closed, closes, opens)):
        flight = [k % m for k in range(int(i), int(i) - int(length), -1) if approach[k % m] <= 0]
        if flight:  # the last sample in flight (touching already at the closing's sample)
            landings.append(int(flight[0]))
            lengths.append(int(length))
    if not landings:
        return []
    first = int(np.argmax(lengths))
    return landings[first:] + landings[:first]


def _interval_lengths(closed: np.ndarray, closings: np.ndarray, openings: np.ndarray) -> np.ndarray:
    """For each closing, the samples the contact was open before it (periodic)."""
    m = closed.size
    out = []
    for i in closings:
        before = openings[openings < i]
        start = before[-1] if before.size else (openings[-1] - m if openings.size else i - m)
        out.append(i - start)
    return np.asarray(out)


class ContactSummary(NamedTuple):
    """The simulated chain's figures at every speed (``ChainContacts.summary``): the
    settled turn's extremes refined between its samples (``Refined``), as the closed chain's
    train section gives them, the drive torque's figures and the largest Hertz stress."""

    rpm: np.ndarray
    min_contact_force_n: np.ndarray
    max_contact_force_n: np.ndarray
    max_acceleration_m_s2: np.ndarray  # (speeds, bodies): each body's peak |x''|
    max_lift_error_mm: np.ndarray  # the last body's largest distance from its kinematic lift
    min_seat_force_n: np.ndarray  # the spring's force at its seat
    max_seat_force_n: np.ndarray
    max_surge_n: np.ndarray  # the seat force's largest distance from the spring's static force
    max_drive_torque_n_m: np.ndarray  # the drive torque's figures (TorqueFigures)
    rms_drive_torque_n_m: np.ndarray
    mean_drive_torque_n_m: np.ndarray
    energy_fluctuation_j: np.ndarray
    stress: RefinedStress | None  # the largest Hertz stress (with follower.contact_width_mm)
    residual_vibration_mm: np.ndarray  # (speeds, points): at each dwell's start


class ChainContacts:
    """A program driving a chain with contacts: its periodic steady state by simulation at
    any speeds from ``rpm_min`` up (``ContactOptions``), in blocks of ``SPEED_BLOCK`` speeds
    through one compiled turn per shape (coordinates, elements, grid and samples)."""

    def __init__(
        self, program, chain: Chain, rpm_min: float, options: ContactOptions | None = None
    ):
        self.program, self.chain = program, chain
        self.options = options or ContactOptions()
        self.rpm_min = Speeds.of(rpm_min, "rpm_min").min()
        self.system = ContactSystem.of(chain)
        for refusal in (
            lash_refusal(program, chain),
            seat_refusal(program, chain),
            turn_steps_refusal(chain, self.system, self.rpm_min, self.options.max_steps),
        ):
            if refusal is not None:
                raise ValueError(refusal)
        grid = cycle_grid(program, self.rpm_min, chain.highest_frequency_hz())
        self.cycle = grid
        """The program's turn on the engine's grid (``cycle_grid``), from which the simulation's
        is padded (``contact_grid``): a design recomputes a segment's samples on it."""
        breaks = program.turn.breakpoints_deg() / 360.0
        self._breaks = np.unique(np.mod(breaks, 1.0))  # where the motion's acceleration may jump
        self._grid = contact_grid(grid, breaks)
        self.kinematic_ratio = chain.lever_ratio
        period = 60.0 / self.rpm_min
        wanted = SAMPLES_PER_CONTACT * period * 2 * self.system.stiffest_hz
        self.samples = int(self.options.samples or bucket(max(4096, math.ceil(wanted)), 1024))
        lift = np.asarray(grid.lift_nodes)
        self._scale = (
            max(float(np.ptp(lift)), 1e-3) * max(self.kinematic_ratio, 1.0),
            max(float(np.max(np.abs(grid.velocity_nodes))), 1e-3) * max(self.kinematic_ratio, 1.0),
        )
        starts = np.asarray(grid.residual_start, dtype=int)
        self._residual_at = np.asarray(grid.nodes, dtype=float)[starts]  # turn time
        self._residual_lift = (  # the lift there (mm) and its rate (mm per turn)
            np.asarray(grid.lift_nodes, dtype=float)[starts],
            np.asarray(grid.velocity_nodes, dtype=float)[starts],
        )
        self._kept: dict[float, ContactTurn] = {}
        """The last batch of ``turns``, by speed: ``turn`` reads them (the report's files)."""

    def _block(self, rpm: np.ndarray, done=()):
        """Turns from rest at the speeds ``rpm`` (one block) until settled: the last
        turn's samples, the turns run and the change that remained per speed; ``done``: the
        speeds of earlier blocks, settled (named where this block does not settle)."""
        o = self.options
        n = self.system.Minv.shape[0]
        z = jnp.zeros((rpm.size, 2 * n))
        speeds = jnp.asarray(rpm)
        zeros = jnp.zeros(rpm.size)
        change = np.full(rpm.size, np.inf)
        for turn in range(1, o.max_turns + 1):
            end, samples, ok = _turns(
                z, speeds, zeros, zeros + 1.0, self.system, self._grid, self.samples, o
            )
            ok = np.asarray(ok)
            if not ok.all():
                bad = float(rpm[np.argmin(ok)])
                raise ValueError(
                    f"[[train]]: the chain's contacts at {bad:g} rpm could not be followed within "
                    f"{o.max_steps:,} steps a turn (ContactOptions.max_steps): a stiffer seat or "
                    "lash element than the integration can resolve"
                )
            d = np.asarray(end - z)
            change = np.maximum(
                np.max(np.abs(d[:, :n]), axis=1) / self._scale[0],
                np.max(np.abs(d[:, n:]), axis=1) / self._scale[1],
            )
            z = end
            if turn >= 2 and np.all(change <= o.settle_tolerance):
                return np.asarray(samples), turn, change
        settled = np.unique(rpm[change <= o.settle_tolerance])
        raise ValueError(
            self._unsettled(
                float(rpm[np.argmax(change)]), float(np.max(change)), np.union1d(done, settled)
            )
        )

    def _unsettled(self, rpm: float, change: float, settled=()) -> str:
        """Why the chain does not settle at ``rpm``: the return spring where it cannot hold
        the chain, taken rigid, on the cam there (``spring_hold_rpm``), else the damping to
        add (``_damp_hint``), with the other likely causes; and the speeds that did settle
        (``settled``), to be run alone."""
        o, damp = self.options, self._damp_hint()
        done = ""
        if len(settled):
            them = "it" if len(settled) == 1 else "them"
            done = f"; {', '.join(f'{r:g}' for r in settled)} rpm settled: run {them} alone"
        what = (
            f"the chain at {rpm:g} rpm does not settle within {o.max_turns} turns (its state "
            f"still moves by {change:.2g} of the lift a turn, against {o.settle_tolerance:g}{done})"
        )
        hold = spring_hold_rpm(self.program, self.chain)
        if hold is not None and rpm > hold:
            spring = self.chain.spring
            return (
                f"[spring] preload_n: {what}: the return spring (preload {spring.preload_n:g} N, "
                f"rate {spring.rate_n_per_mm:g} N/mm) holds the chain, taken rigid, on the cam "
                f"only up to about {hold:.3g} rpm: give it more preload or rate, or damping "
                f"({damp or '[[train]] damping_n_s_per_m'})"
            )
        spring = (
            "check the return spring ([spring] preload_n, rate_n_per_mm: too weak to return the "
            "chain onto the cam)"
        )
        free = self._held_by_nothing()
        if damp is None and free is not None:
            return f"{free[0]}: {what}: {free[1]}; or {spring}"
        lash = "; or lash the cam's lift barely takes up (lash_mm)" if self.chain.seat else ""
        return (
            f"{damp or '[[train]] damping_n_s_per_m'}: {what}: give it damping; or {spring}{lash}"
        )

    def _held_by_nothing(self) -> tuple[str, str] | None:
        """The bodies between the cam and the first lash of a seated chain: with the lash
        open (the valve on its seat) no spring holds them, only the cam pushes them and the
        lash's element stops them, so they rattle between the two, damped only by the
        elements among them and the lash's: ``(their names, what to give)``; ``None``
        without a seat or with no body before the lash."""
        bodies = self.chain.bodies
        first = next((j for j, b in enumerate(bodies) if b.lash_mm > 0), None)
        if self.chain.seat is None or not first:
            return None
        names = ", ".join(f"body {j} ({b.name})" for j, b in enumerate(bodies[:first], 1))
        dampers = [
            f"body {j} ({b.name}) damping_n_s_per_m = {b.damping_n_s_per_m:g}"
            for j, b in enumerate(bodies[: first + 1], 1)
            if not b.rides
        ]
        lash = bodies[first]
        them, they = ("it", "it rattles") if first == 1 else ("them", "they rattle")
        return (
            f"[[train]] {names}",
            f"between the cam and the open lash of body {first + 1} ({lash.name}, lash_mm = "
            f"{lash.lash_mm:g}) nothing holds {them} (no spring): {they} there with only the "
            f"damping of {'; '.join(dampers)}: give more damping_n_s_per_m, or less lash",
        )

    def _damp_hint(self) -> str | None:
        """The damping field missing from the seat or an element (``None`` where each has
        some): its mode rings undamped."""
        seat = self.chain.seat
        if seat is not None and not seat.damping_n_s_per_m:
            return "[seat] damping_n_s_per_m"
        for j, body in enumerate(self.chain.bodies, start=1):
            if not body.rides and not body.damping_n_s_per_m:
                return f"[[train]] body {j} ({body.name}) damping_n_s_per_m"
        return None

    def turns(self, rpm, refine: bool = True) -> list[ContactTurn]:
        """The settled turn at every speed of ``rpm`` (without ``refine``: its ``refined``
        is ``None``, for a search that reads only the contacts)."""
        rpm = np.asarray(Speeds.of(rpm), dtype=float)
        if rpm.min() < self.rpm_min * (1 - 1e-12):
            raise ValueError(
                f"rpm {rpm.min():g} below the simulation's slowest speed {self.rpm_min:g}"
            )
        for line in speed_warnings(self.program, rpm):  # the exact path's warning, refused here
            raise ValueError(
                f"{line}; a chain with lash or a seat is simulated, which does not settle there"
            )
        out = []
        for start in range(0, rpm.size, SPEED_BLOCK):
            block = rpm[start : start + SPEED_BLOCK]
            padded = np.pad(block, (0, SPEED_BLOCK - block.size), mode="edge")
            samples, turns, change = self._block(padded, rpm[:start])
            if not refine:
                out += [
                    self._read(float(r), samples[i], turns, float(change[i]), None)
                    for i, r in enumerate(block)
                ]
                continue
            states = samples[:, :, -(1 + self.system.Minv.shape[0] * 2) :]
            jets = _jets(jnp.asarray(states), jnp.asarray(padded), self.system, self._grid)
            switched = self._switched(samples)
            widths = jnp.full(self.samples, 1.0 / self.samples)
            torque, figures, extremes, septic = (
                jax.tree.map(np.asarray, x) for x in _figures(jets, jnp.asarray(switched), widths)
            )
            jets = np.asarray(jets)
            residual = self._residual(samples, padded)
            out += [
                self._read(
                    float(r),
                    samples[i],
                    turns,
                    float(change[i]),
                    Refined(
                        jets[i],
                        torque[i],
                        TorqueFigures(*(float(x[i]) for x in figures)),
                        extremes[i],
                        switched[i],
                        septic[i],
                    ),
                    tuple(residual[i]),
                )
                for i, r in enumerate(block)
            ]
        if refine:  # the report's turns, kept for its files (a search's are not)
            self._kept = {t.rpm: t for t in out}
        return out

    def turn(self, rpm: float) -> ContactTurn:
        """The settled turn at one speed: read from the last batch of ``turns`` where it was
        computed there, else simulated."""
        rpm = Speeds.of(rpm)[0]
        return self._kept[rpm] if rpm in self._kept else self.turns([rpm])[0]

    def flights(self, rpm, start, end, state, until) -> list[list[Flight]]:
        """Every flight of the cam's contact that starts before turn time ``until`` at each
        speed of ``rpm``, simulated from turn time ``start`` (the state ``state``, ``(speeds,
        2 N)``: mm and mm per turn) to ``end`` (at most two turns later) with the cam's
        contact one-sided (``cam_flights``): ``flights_at`` starts on the exact steady state
        where the cam holds and reads one period from its first separation.  ``2 samples``
        points over the run, in blocks of ``SPEED_BLOCK`` speeds."""
        rpm = np.asarray(Speeds.of(rpm), dtype=float)
        if rpm.min() < self.rpm_min * (1 - 1e-12):
            raise ValueError(
                f"rpm {rpm.min():g} below the simulation's slowest speed {self.rpm_min:g}"
            )
        start, end = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
        until = np.asarray(until, dtype=float)
        state = np.asarray(state, dtype=float)
        count = 2 * self.samples
        grid = jax.tree.map(jnp.asarray, self._grid)
        lift_at = jax.vmap(_lift_at, in_axes=(None, None, None, 0))
        out = []
        for first in range(0, rpm.size, SPEED_BLOCK):
            rows = np.arange(first, min(first + SPEED_BLOCK, rpm.size))
            padded = np.pad(rows, (0, SPEED_BLOCK - rows.size), mode="edge")
            _, samples, ok = _turns(
                jnp.asarray(state[padded]),
                jnp.asarray(rpm[padded]),
                jnp.asarray(start[padded]),
                jnp.asarray(end[padded]),
                self.system,
                self._grid,
                count,
                self.options,
            )
            if not np.asarray(ok).all():
                bad = float(rpm[padded][np.argmin(np.asarray(ok))])
                raise ValueError(
                    f"[[train]]: the chain's flights at {bad:g} rpm could not be followed within "
                    f"{self.options.max_steps:,} steps (ContactOptions.max_steps)"
                )
            states = samples[:, :, -(1 + self.system.Minv.shape[0] * 2) :]
            lift = np.asarray(
                lift_at(grid.nodes, grid.lift, grid.acceleration, states[:, :, 0].ravel())
            )
            lift = lift.reshape(3, padded.size, count + 1)
            samples = np.asarray(samples)

            out += [
                cam_flights(
                    self.chain,
                    self.system,
                    float(rpm[r]),
                    samples[i],
                    lambda indices, z=states[i], r=float(rpm[r]): _cam_jets(
                        z, indices, r, self.system, self._grid
                    ),
                    lift[:, i],
                    until[r],
                )
                for i, r in enumerate(rows)
            ]
        return out

    def jump_speed(self, rpm, separates) -> float:
        """The lowest speed at which the cam separates (``separation_speed`` of ``"cam"``)."""
        return self.separation_speed(rpm, separates, "cam")

    def separation_speed(self, rpm, separates, contact: str) -> float:
        """The lowest speed at which ``contact`` separates (a key of ``ContactTurn.separates``:
        ``"cam"``, a lash element's body, ``"seat"``), between the highest speed of ``rpm``
        where it holds below the lowest where it separates (``separates``, per speed) and
        that one: ``narrowed_crossing`` with a block of ``SPEED_BLOCK`` simulated speeds a
        round (33-fold narrower a round), to ``ContactOptions.jump_tolerance_rpm`` (the middle
        of the last bracket: within half of it of the first separation found)."""
        rpm, separates = np.asarray(rpm, dtype=float), np.asarray(separates, bool)
        hi = float(rpm[separates].min())
        held = rpm[~separates & (rpm < hi)]
        if not held.size:
            what = "the cam" if contact == "cam" else f"the contact {contact!r}"
            raise ValueError(
                f"{what} separates at the lowest speed given ({hi:g} rpm): no "
                f"{'jump' if contact == 'cam' else 'separation'} to search"
            )
        lo = float(held.max())

        def contact_separates(trial: np.ndarray) -> np.ndarray:
            turns = self.turns(trial, refine=False)
            return np.array([t.separates.get(contact, False) for t in turns])

        return float(
            narrowed_crossing(
                contact_separates, lo, hi, self.options.jump_tolerance_rpm, SPEED_BLOCK
            )
        )

    def _switched(self, samples: np.ndarray) -> np.ndarray:
        """``(speeds, samples)``: whether a contact switches (the cam's, a one-sided
        element's, the seat's force starts or stops) or the motion's acceleration jumps
        inside each sample interval of the block's turns."""
        E = self.system.k.size
        col = {name: samples[:, :, i] for i, name in enumerate(_COLUMNS)}
        signals = samples[:, :, len(_COLUMNS) + E : len(_COLUMNS) + 2 * E]
        states = [col["cam"] > 0, col["seat_signal"] > 0]
        states += [signals[:, :, e] > 0 for e in np.flatnonzero(self.system.one_sided > 0)]
        switched = np.zeros(samples[:, :-1, 0].shape, bool)
        for closed in states:
            switched |= closed[:, 1:] != closed[:, :-1]
        for jump in self._breaks:  # a jump at a sample: both intervals beside it
            k = jump * self.samples
            switched[:, int(np.ceil(k) - 1) % self.samples] = True
            switched[:, int(np.floor(k)) % self.samples] = True
        return switched

    def _residual(self, samples: np.ndarray, rpm: np.ndarray) -> np.ndarray:
        """``(speeds, points)``: the residual vibration (mm) at the start of each dwell and
        constant-velocity segment (``contact_residual_mm``) of the block's settled turns,
        from the state there (``_state_before``: back from the first sample at or after it)."""
        at = self._residual_at
        if not at.size:
            return np.zeros((rpm.size, 0))
        n = self.system.Minv.shape[0]
        after = np.minimum(np.ceil(at * self.samples - 1e-9).astype(int), self.samples)
        states = samples[:, after, -(1 + 2 * n) :]
        z, ok = _states_before(
            jnp.asarray(states),
            jnp.asarray(at),
            jnp.asarray(rpm),
            self.system,
            self._grid,
            self.options,
        )
        z, ok = np.asarray(z), np.asarray(ok)
        if not ok.all():
            bad = float(rpm[np.argmin(ok.all(axis=1))])
            raise ValueError(
                f"[[train]]: the chain's state at a dwell's start at {bad:g} rpm could not be "
                f"followed back within {self.options.max_steps:,} steps (ContactOptions.max_steps)"
            )
        y0, ys = self._residual_lift
        out = np.zeros((rpm.size, at.size))
        for i, r in enumerate(rpm):
            period = 60.0 / float(r)
            for j in range(at.size):
                out[i, j] = contact_residual_mm(
                    self.system,
                    1e-3 * z[i, j, :n],
                    1e-3 * z[i, j, n:] / period,
                    1e-3 * y0[j],
                    1e-3 * ys[j] / period,
                )
        return out

    def _read(
        self,
        rpm: float,
        x: np.ndarray,
        turns: int,
        change: float,
        refined: Refined | None,
        residual: tuple[float, ...] = (),
    ) -> ContactTurn:
        """What the samples ``x`` (samples + 1, outputs) of one settled turn say, with the
        figures ``refined`` between them."""
        if not np.all(np.isfinite(x)):
            raise ValueError(f"[[train]]: the chain's simulation at {rpm:g} rpm is not finite")
        chain, s = self.chain, self.system
        col = {name: x[:, i] for i, name in enumerate(_COLUMNS)}
        E = s.k.size
        forces = x[:, len(_COLUMNS) : len(_COLUMNS) + E].T
        signals = x[:, len(_COLUMNS) + E : len(_COLUMNS) + 2 * E].T
        B = len(chain.bodies)
        acc, displacement, velocity = (
            x[:, len(_COLUMNS) + 2 * E + b * B : len(_COLUMNS) + 2 * E + (b + 1) * B].T
            for b in range(3)
        )
        theta = np.linspace(0.0, 360.0, x.shape[0])
        step = theta[1] - theta[0]
        period = 60.0 / rpm
        dt = period / (x.shape[0] - 1)
        turn = slice(0, -1)  # the last sample is the first one's turn later
        seated = chain.seat is not None
        seat_closed = (col["seat_signal"][turn] > s.seat_k * 1e-3 * CLOSED_MM) if seated else None
        off_seat = ~seat_closed if seated else np.ones(x.shape[0] - 1, bool)
        elements = [b for b in chain.bodies if not b.rides]

        def angle(i, a, b):  # the zero of a signal between samples i and i + 1 (linear)
            return float(theta[i] + step * a / (a - b) if a != b else theta[i])

        lash_openings, separates = {}, {}
        for e, body in enumerate(elements):
            if not (s.one_sided[e] > 0):
                continue
            sig = signals[e][turn]
            closed = sig > s.k[e] * 1e-3 * CLOSED_MM
            _, opens = _crossings(closed)
            nxt = (opens + 1) % sig.size
            angles = [angle(i, sig[i], sig[j]) for i, j in zip(opens, nxt)]
            separated = bool(np.any(~closed & off_seat))
            if body.lash_mm:
                lash_openings[body.name] = angles
                separates[body.name] = separated
            else:  # the first element: the cam's contact
                separates["cam"] = separated
        if chain.bodies[0].rides:
            gap = col["gap"][turn]
            separates["cam"] = bool(np.any((gap > 1e-3 * CLOSED_MM) & off_seat))
        seating, bounces, landings = None, (), []
        if seated:
            approach = s.seat_s0 - 1e-3 * col["last_mm"]  # the seat's (m)
            landings = seat_landings(seat_closed, approach)
            impacts = []
            for i in landings:
                gap0 = approach[i]
                rate, accel = -col["last_v"][i], -col["last_a"][i]
                tau = _first_root(gap0, rate, accel, dt)
                impacts.append(
                    Impact(float(theta[i] + 360.0 * tau / period), float(rate + accel * tau))
                )
            if impacts:
                seating = impacts[0].velocity_m_s
                bounces = tuple(impacts[1:])
            separates["seat"] = bool(bounces)
        return ContactTurn(
            rpm=rpm,
            theta_deg=theta,
            lift_mm=col["lift_mm"],
            last_mm=col["last_mm"],
            last_velocity_m_s=col["last_v"],
            cam_force_n=col["cam"],
            seat_contact_force_n=col["seat"],
            element_force_n=forces,
            acceleration_m_s2=acc,
            displacement_mm=displacement,
            velocity_m_s=velocity,
            spring_seat_force_n=col["spring"],
            surge_n=col["surge"],
            seating_velocity_m_s=seating,
            seating_sample=landings[0] if landings else None,
            start_state=x[0, -2 * s.Minv.shape[0] :],
            bounces=bounces,
            lash_openings_deg=lash_openings,
            separates=separates,
            turns=turns,
            change=change,
            refined=refined,
            residual_vibration_mm=residual,
        )

    def summary(self, rpm) -> tuple[ContactSummary, list[ContactTurn]]:
        """The ``ContactSummary`` of the simulated turns (extremes refined between the
        samples, ``Refined``; the lift error at the samples) and the turns themselves."""
        turns = self.turns(rpm)
        cam, spring, surge = (_SIGNALS.index(name) for name in ("cam", "spring", "surge"))
        body = len(_SIGNALS)

        def each(f):
            return np.asarray([f(t) for t in turns])

        return ContactSummary(
            np.asarray([t.rpm for t in turns]),
            one_sided(each(lambda t: t.refined.extremes[cam, 0])),
            one_sided(each(lambda t: t.refined.extremes[cam, 1])),
            each(lambda t: np.max(np.abs(t.refined.extremes[body:]), axis=1)),
            each(lambda t: np.max(np.abs(t.last_mm - self.kinematic_ratio * t.lift_mm))),
            each(lambda t: t.refined.extremes[spring, 0]),
            each(lambda t: t.refined.extremes[spring, 1]),
            each(lambda t: np.max(np.abs(t.refined.extremes[surge]))),
            each(lambda t: t.torque.max_abs),
            each(lambda t: t.torque.rms),
            each(lambda t: t.torque.mean),
            each(lambda t: t.torque.energy_fluctuation),
            self.contact_stress(turns),
            np.asarray([t.residual_vibration_mm for t in turns]).reshape(len(turns), -1),
        ), turns

    def contact_stress(self, turns: list[ContactTurn]) -> RefinedStress | None:
        """The largest Hertz stress of each turn (``None`` without
        ``follower.contact_width_mm``): ``p_max^2 = F_c * factor`` (``contact_stress_squared``
        with ``node_contact``'s factors) at the samples, refined between them by
        ``refined_contact_stress`` on the contact force's interpolants (``Refined``); where
        the peak falls in an interval where a contact switches or the motion's acceleration
        jumps (the cam's curvature with it), the largest sample's."""
        if self.program.follower.contact_width_mm is None or not turns:
            return None
        contact = node_contact(self.program, turns[0].theta_deg)
        squared = np.stack(
            [np.asarray(contact_stress_squared(t.cam_force_n, contact)) for t in turns]
        )
        septic = np.stack([t.refined.force_septic for t in turns])
        m = self.samples

        def force_at(rows, s):
            k = np.clip(np.floor(s * m).astype(int), 0, m - 1)
            sigma = s * m - k
            c = septic[rows, k]
            value = np.zeros_like(sigma)
            for j in range(c.shape[-1] - 1, -1, -1):  # Horner
                value = value * sigma + c[..., j]
            return value

        refined = refined_contact_stress(
            self.program, np.linspace(0.0, 1.0, m + 1), np.sqrt(np.maximum(squared, 0.0)), force_at
        )
        best = np.argmax(squared[:, :-1], axis=1)
        rows = np.arange(len(turns))
        force = np.array([t.cam_force_n[i] for t, i in zip(turns, best)])
        radius = np.where(force >= 0, contact.radius_inner[best], contact.radius_outer[best])
        sampled = RefinedStress(
            np.sqrt(np.maximum(squared[rows, best], 0.0)), turns[0].theta_deg[best], radius
        )
        where = np.clip(np.floor(refined.angle_deg / 360.0 * m).astype(int), 0, m - 1)
        switched = np.array([t.refined.switched[k] for t, k in zip(turns, where)])
        return RefinedStress(*(np.where(switched, a, b) for a, b in zip(sampled, refined)))


def one_sided(force: np.ndarray) -> np.ndarray:
    """A one-sided contact's force (N) clipped at zero: it pushes only, so a value below zero
    is the refinement's undershoot between the samples (about 1e-9 N), and ``-0`` reads as
    ``0`` (the least force of a contact that carries nothing for a while)."""
    force = np.asarray(force, dtype=float)
    return np.where(force > 0, force, 0.0)


def _first_root(gap0: float, rate: float, accel: float, dt: float) -> float:
    """The first time in ``[0, dt]`` at which ``gap0 + rate t + accel t^2 / 2`` reaches zero
    (``gap0 <= 0`` at the sample before a contact; ``dt`` where it does not)."""
    if accel == 0.0:
        return float(np.clip(-gap0 / rate, 0.0, dt)) if rate else dt
    disc = rate * rate - 2.0 * accel * gap0
    if disc < 0:
        return dt
    roots = [(-rate + sign * math.sqrt(disc)) / accel for sign in (-1.0, 1.0)]
    inside = [t for t in roots if -1e-15 <= t <= dt * (1 + 1e-9)]
    return float(max(min(inside), 0.0)) if inside else dt


def cam_flights(
    chain: Chain,
    system: ContactSystem,
    rpm: float,
    x: np.ndarray,
    jets_at,
    lift,
    until: float,
) -> list[Flight]:
    """Every flight of the cam's contact that starts before turn time ``until`` in one run
    (``ChainContacts.flights``): ``x`` its samples ``(count + 1, outputs)``, ``jets_at`` the
    contact force and its first three derivatives in turn time at the samples of some
    indices ``(indices, 4)``, ``lift`` the cam's ``y``, ``y_s``, ``y_ss`` (mm, turns).

    The cam holds where its contact force is positive.  **Separation**: the zero of the
    force's cubic Taylor polynomial from the last held sample (the held equations'
    derivatives, exact given the state).  **Re-impact**: the cam's approach ``a = d_0 + r y -
    x_1`` (m; a riding body's ``y - x_1``) reaching zero, on its quadratic in time from the
    last sample in flight (``_first_root``; where the approach stays positive, the element's
    force only unloading and loading again, the zero of ``k a + c a'`` between the samples);
    the **impact velocity** is ``a'`` there over ``r``: the cam's surface against the
    follower's end at the cam (m/s, closing).  **Peak force**: the largest contact force
    from the landing to the next separation (or the run's end), on the cubic Taylor
    polynomials of the intervals beside the largest sample.  The landing is the
    simulation's: on an element the Kelvin-Voigt contact (the classic follower's), a riding
    body the critically damped one (``RIDER_CONTACT_HZ``), whose peak is that model's."""
    force = x[:, 0]
    held = force > 0
    count = force.size - 1
    turn_time = x[:, -(1 + system.Minv.shape[0] * 2)]
    h = (turn_time[-1] - turn_time[0]) / count  # turns between samples
    period = 60.0 / rpm
    rider = chain.bodies[0].rides
    ratio = 1.0 if rider else chain.bodies[0].ratio
    d0 = 0.0 if rider else float(system.d0[0])
    E, B = system.k.size, len(chain.bodies)
    body = len(_COLUMNS) + 2 * E  # the first body's acceleration, then displacement, velocity
    y, y_s, y_ss = (np.asarray(v) for v in lift)
    approach = d0 + 1e-3 * (ratio * y - x[:, body + B])
    rate = 1e-3 * ratio * y_s / period - x[:, body + 2 * B]
    accel = 1e-3 * ratio * y_ss / period**2 - x[:, body]

    def angle(i, tau):  # tau turns after sample i
        return float(np.mod(360.0 * (turn_time[i] + tau), 360.0))

    def taylor(i, tau):
        f = jets[i]
        return f[0] + tau * (f[1] + tau * (f[2] / 2 + tau * f[3] / 6))

    opens = np.flatnonzero(held[:-1] & ~held[1:])
    closes = np.flatnonzero(~held[:-1] & held[1:])

    def landing(i):  # the last sample in flight, the next separation's and the largest force's
        later = closes[closes > i]
        if not later.size:
            return None
        j = int(later[0])
        nxt = opens[opens > j]
        stop = int(nxt[0]) if nxt.size else count
        return j, stop, j + 1 + int(np.argmax(force[j + 1 : stop + 1]))

    needed = set(opens.tolist())
    for i in opens:
        if (found := landing(i)) is not None:
            needed |= {found[2] - 1, found[2]}
    needed = np.array(sorted(needed), dtype=int)
    jets = dict(zip(needed.tolist(), jets_at(needed)))
    flights = []
    for i in opens:
        roots = np.roots((jets[i] / [1.0, 1.0, 2.0, 6.0])[::-1])  # the cubic, in turns from i
        tau = [r.real for r in roots if abs(r.imag) <= 1e-6 * h]
        tau = [t for t in tau if 0 <= t <= h]
        tau = min(tau) if tau else h / 2
        if turn_time[i] + tau >= until:
            break
        separation = angle(i, tau)
        if (found := landing(i)) is None:
            flights.append(Flight(separation, None, None, None))
            break
        j, stop, best = found
        dt = h * period
        if rider or approach[j] < 0:
            t = _first_root(approach[j], rate[j], accel[j], dt)
        else:  # the element unloads and loads again without a gap: the zero of k a + c a'
            k0, c0 = float(system.k[0]), float(system.c[0])
            a, b = (k0 * approach[n] + c0 * rate[n] for n in (j, j + 1))
            t = dt * (0.0 if a == b else -a / (b - a))
        peak = float(force[best])
        if rider:  # the landing's force is largest at the touch (w' = -v, w = 0), between samples
            closing = rate[j] + accel[j] * t
            touch = (accel[j] + float(system.rider_c) * closing) / float(system.Minv[0, 0])
            peak = max(peak, float(touch))
        sigma = np.linspace(0.0, h, 65)
        for n in (best - 1, best):
            if j + 1 <= n < stop:  # held at both ends
                peak = max(peak, float(np.max(taylor(n, sigma))))
        flights.append(
            Flight(
                separation,
                angle(j, t / period),
                float((rate[j] + accel[j] * t) / ratio),
                peak,
            )
        )
    return flights


def contact_section(chain: Chain, turns: list[ContactTurn]) -> dict:
    """The contacts' part of the report's ``train`` section: per speed (same order as the
    section's ``speeds``) the seating velocity, the bounces, the lash's openings and the
    separations; per contact the lowest speed given at which it separates (``simulated_train``
    searches it between the speeds)."""
    per_speed = []
    for t in turns:
        per_speed.append(
            {
                "seating_velocity_m_s": t.seating_velocity_m_s,
                "bounce_count": len(t.bounces),
                "bounces": [b.as_dict() for b in t.bounces],
                "lash_openings": {
                    name: {"count": len(a), "angles_deg": a}
                    for name, a in t.lash_openings_deg.items()
                },
                "separates": dict(t.separates),
                "turns": t.turns,
                "change": t.change,
            }
        )
    contacts = list(turns[0].separates) if turns else []
    lowest = {}
    for name in contacts:
        hit = [t.rpm for t in turns if t.separates.get(name)]
        lowest[name] = min(hit) if hit else None
    return {"speeds": per_speed, "lowest_separation_rpm": lowest}


def contacts_note(chain: Chain) -> str:
    """The note of the report's ``contacts``: how the chain is simulated, its rest state as
    this chain has it (``ContactSystem.of``: the valve on its seat with each lash open, or,
    without a seat, the closed chain carrying the spring's preload, each lash closed) and
    what separation means for it."""
    lash = any(b.lash_mm for b in chain.bodies)
    if chain.seat is not None:
        rest = "the rest state has the valve on its seat carrying the spring's preload, " + (
            "the lash open" if lash else "the elements just touching"
        )
        separates = (
            "a contact separates where it opens while the valve is off its seat, the seat where "
            "the valve bounces"
        )
    else:
        carried = (
            "carrying the spring's preload through the levers, the lash closed by it"
            if chain.spring is not None and chain.spring.preload_n
            else "with each lash just closed (no spring preloads it)"
        )
        rest = f"no seat: the rest state is the closed chain {carried}"
        separates = "a contact separates where it opens"
    return (
        "lash or a seat: the chain's periodic steady state is simulated (diffrax) with its one-sided "
        f"contacts; {rest}; extremes are refined between the samples of the settled turn; "
        f"{separates}; jump speed: the lowest speed at which the cam separates, searched between "
        "the speeds given to ContactOptions.jump_tolerance_rpm; lowest_separation_rpm: the same "
        "for each contact (the cam's is the jump speed), the lowest speed given where it "
        "separates there already (separation_below_range true), none where it holds at every speed"
    )


def simulated_train(
    program,
    chain: Chain,
    rpm: np.ndarray,
    options: ContactOptions | None = None,
    simulation: ChainContacts | None = None,
):
    """``train_section``'s figures for a chain with contacts: the ``ContactSummary``, the
    ``contacts`` part of the section (``contact_section``, its ``lowest_separation_rpm`` each
    contact's lowest speed of separation searched between the speeds of ``rpm`` as the jump
    speed is, the lowest given where it separates there already: ``separation_below_range``),
    the jump speed (the lowest speed at which the cam separates, searched between the speeds
    of ``rpm``: ``ChainContacts.jump_speed``; ``None`` where it holds at every one, or at the
    lowest already: then ``below`` is true).
    ``simulation``: the ``ChainContacts`` to run (default: one built for ``rpm`` with
    ``options``), which keeps the turns for the report's files."""
    rpm = np.asarray(rpm, dtype=float)
    simulation = simulation or ChainContacts(program, chain, float(rpm.min()), options)
    summary, turns = simulation.summary(rpm)
    contacts = {"note": contacts_note(chain), **contact_section(chain, turns)}
    cam = np.array([t.separates.get("cam", False) for t in turns])
    below = bool(cam[np.argmin(rpm)])
    jump = None
    if not below and cam.any():
        jump = simulation.jump_speed(rpm, cam)
    lowest, under = {}, {}
    for name, given in contacts["lowest_separation_rpm"].items():
        hit = np.array([t.separates.get(name, False) for t in turns])
        under[name] = bool(hit[np.argmin(rpm)])
        if not hit.any() or under[name]:
            lowest[name] = given
        else:
            lowest[name] = jump if name == "cam" else simulation.separation_speed(rpm, hit, name)
    contacts["lowest_separation_rpm"], contacts["separation_below_range"] = lowest, under
    return summary, contacts, jump, below
