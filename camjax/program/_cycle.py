"""One turn's response at one speed: the oscillator's modes propagated exactly over the
program's grid (``camjax.sdof.periodic_propagate``, or from a given start), and every output
of the turn (contact force, payload acceleration, drive torque, Hertz stress, residual
vibration, a train's own figures) in SI units with its extremes refined between nodes.
Jittable and vmappable in the speed: ``_dynamics.py`` runs it over blocks of speeds."""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..metrics import PEAK_TOLERANCE, bernstein_bound, hermite_data, peak_search, refined_peak
from ..sdof import (
    periodic_propagate,
    propagate,
    refined_extremes,
    series_kicks,
)
from ._contact import NodeContact, contact_stress_squared
from ._cycle_grid import CycleGrid
from ._oscillator import (
    CONTACT_FORCE,
    PAYLOAD_ACCELERATION,
    PAYLOAD_DISPLACEMENT,
    Oscillator,
    output_rows,
)
from ._torque import torque_figures, torque_jets


class TrainPeaks(NamedTuple):
    """A train's own figures of one turn (``Oscillator`` built with its rows): each body's
    peak ``|x''|`` (m/s^2), the spring's least and largest force at its seat (N), its
    largest surge (dynamic less static force, N), all refined between nodes, and the last
    body's largest distance from its kinematic lift at the nodes (mm)."""

    max_acceleration_m_s2: jax.Array
    min_seat_force_n: jax.Array
    max_seat_force_n: jax.Array
    max_surge_n: jax.Array
    max_lift_error_mm: jax.Array


class Cycle(NamedTuple):
    """Node series and refined extrema of one turn at one speed (s-time, mm).

    ``q`` is the complex modes at the nodes, ``(S, K + 1)``, in turn time (``T`` times the
    ``Oscillator``'s physical modes; periodic steady state unless built otherwise).
    Forces in N, accelerations in m/s^2 (the payload: the last body), the drive torque in
    N m (with its first three derivatives in turn time at both ends of every interval, and
    its peak, RMS, mean and energy fluctuation over the turn: docs/machine.md), energy in
    J, the Hertz stress in MPa (zero without a contact width) and the node where it peaks;
    ``residual_vibration_mm`` the last body's free vibration at the start of each dwell and
    constant-velocity segment (``residual_vibration``); ``train`` a train's own figures
    (``TrainPeaks``; ``None`` without the train's rows).
    """

    q: jax.Array
    payload_acceleration_m_s2: jax.Array
    contact_force_n: jax.Array
    max_payload_acceleration_m_s2: jax.Array
    min_contact_force_n: jax.Array
    max_contact_force_n: jax.Array
    residual_vibration_mm: jax.Array
    drive_torque_n_m: jax.Array
    max_drive_torque_n_m: jax.Array
    rms_drive_torque_n_m: jax.Array
    mean_drive_torque_n_m: jax.Array
    energy_fluctuation_j: jax.Array
    contact_stress_mpa: jax.Array
    max_contact_stress_mpa: jax.Array
    max_contact_stress_node: jax.Array
    max_contact_stress_radius_mm: jax.Array
    drive_torque_left: jax.Array
    drive_torque_right: jax.Array
    train: TrainPeaks | None = None
    outputs: dict = {}  # the compiled outputs' values (camjax.program.Outputs), filled by the speed batch


def _modes(grid: CycleGrid, oscillator: Oscillator, rpm, q_start=None, periodic=True):
    """The modes at the nodes over one turn at ``rpm`` in turn time, ``(S, K + 1)``: each
    through the engine's exact propagation with its own eigenvalue and forcing.

    A mode's forcing is ``a_j y_ss + b_j T^2 y``, so its kicks are the same sum of the
    law-only kicks of ``y_ss`` and of ``y`` (``camjax.sdof.series_kicks``): two products
    for every mode and speed, where building each mode's forcing and integrating it cost a
    ten-body chain's speed block 6.5 times as much (2026-11-29).  The series is exact
    where ``|lam| h <= MAX_PHASE_STEP``, which the program's grid guarantees for every
    mode (``program_grid``)."""
    period = 60.0 / rpm
    lam = period * jnp.asarray(oscillator.lam)
    weights = jnp.asarray(oscillator.forcing)
    motion = grid.motion
    widths, widest = jnp.asarray(motion.widths), jnp.max(jnp.asarray(motion.piece_width))

    def kicks(forcing):
        return jax.vmap(lambda l: series_kicks(jnp.asarray(forcing), widths, widest, l))(lam)  # (S, K)

    kick = weights[:, 1, None] * kicks(motion.forcing) + (weights[:, 0] * period**2)[:, None] * kicks(grid.lift)
    if periodic:
        return jax.vmap(lambda l, k: periodic_propagate(motion, None, None, lam=l, kick=k))(lam, kick)
    q_start = jnp.broadcast_to(jnp.asarray(q_start, dtype=complex), lam.shape)
    return jax.vmap(lambda l, k, q0: propagate(motion, None, None, q0=q0, lam=l, kick=k))(lam, kick, q_start)


def _real_product(gain, q):
    """``Re(gain @ q)`` in real products (XLA's complex ones are slow on CPU)."""
    return jnp.real(gain) @ jnp.real(q) - jnp.imag(gain) @ jnp.imag(q)


def _cycle(grid: CycleGrid, oscillator: Oscillator, rpm, q_start=None, periodic=True,
           contact: NodeContact | None = None) -> Cycle:
    """The response over one turn at ``rpm`` (jittable, vmappable in ``rpm``): the program's
    forcing at this speed through the engine, mode by mode, and the oscillator's outputs in
    SI units, their extremes refined between nodes."""
    period = 60.0 / rpm
    lam = period * jnp.asarray(oscillator.lam)  # per turn
    weights = jnp.asarray(oscillator.forcing)
    q = _modes(grid, oscillator, rpm, q_start, periodic)
    gain = jnp.asarray(oscillator.gain) / period  # of the turn-time modes
    d = jnp.asarray(oscillator.direct)
    direct = jnp.stack([d[:, 0], d[:, 1] / period, d[:, 2] / period**2], axis=1)  # per y, y_s, y_ss
    y = jnp.asarray(grid.lift_nodes)
    ys = jnp.asarray(grid.velocity_nodes)
    lift_left, lift_right = grid.motion.one_sided(4)  # y_ss and three derivatives
    raw_left, raw_right = grid.with_forcing(jnp.asarray(grid.lift)).one_sided(3)  # y, y_s, y_ss
    widths = grid.motion.widths
    y_nodes = jnp.stack([y, ys, jnp.concatenate([lift_left[:, 0], lift_right[-1:, 0]])])
    values = _real_product(gain, q) + direct @ y_nodes + jnp.asarray(oscillator.static)[:, None]
    gains = jax.lax.optimization_barrier([gain * lam**p for p in range(4)])  # (O, S) each

    def jets(q_end, ys_end, acc_end, lift_end):
        """``(O, K, 3)``: every output's first three derivatives at one end of each interval:
        ``d^p Re(G q) = Re(G lam^p q) + sum_i Re(G lam^(p-1-i)) F^(i)`` with each mode's
        forcing ``F = a y_ss + b T^2 y``, and the direct terms' ``y^(p)`` to ``y^(p+2)``."""
        a_weights = [_real_product(gains[k], weights[:, 1]) for k in range(3)]  # (O,)
        b_weights = [_real_product(gains[k], weights[:, 0]) * period**2 for k in range(3)]
        y_jet = jnp.concatenate([ys_end[:, None], acc_end], axis=1)  # y^(1..5)
        out = []
        for p in (1, 2, 3):
            value = _real_product(gains[p], q_end)
            for i in range(p):
                value = (value + a_weights[p - 1 - i][:, None] * acc_end[None, :, i]
                         + b_weights[p - 1 - i][:, None] * lift_end[None, :, i])
            out.append(value + direct @ y_jet[:, p - 1 : p + 2].T)
        return jnp.stack(out, axis=-1)

    left = jets(q[:, :-1], ys[:-1], lift_left, raw_left)
    right = jets(q[:, 1:], ys[1:], lift_right, raw_right)
    force, accel = values[CONTACT_FORCE], values[PAYLOAD_ACCELERATION]
    force_left, force_right = left[CONTACT_FORCE], right[CONTACT_FORCE]
    max_accel = refined_peak(accel, widths, left[PAYLOAD_ACCELERATION], right[PAYLOAD_ACCELERATION])
    min_force, max_force = refined_extremes(force, widths, force_left, force_right)
    torque = torque_jets(force, force_left, force_right, ys, lift_left[:, :3], lift_right[:, :3])
    figures = torque_figures(torque[0], widths, *torque[1:])
    if contact is None:
        contact = NodeContact(*(jnp.zeros_like(force),) * 4)
    contact = jax.tree.map(jnp.asarray, contact)
    stress_sq = contact_stress_squared(force, contact)
    stress = jnp.sqrt(stress_sq)
    node = jnp.argmax(stress_sq)
    radius = jnp.where(force[node] >= 0, contact.radius_inner[node], contact.radius_outer[node])
    residual = residual_vibration(grid, oscillator, q, rpm)
    train = None
    if oscillator.bodies:  # a train's rows: static in the shape
        train = _train_peaks(values, left, right, widths, oscillator.bodies)
    return Cycle(q, accel, force, max_accel, min_force, max_force, residual, torque[0], *figures, stress,
                 stress[node], node, radius, torque[1], torque[2], train)


def _train_peaks(values, left, right, widths, bodies: int) -> TrainPeaks:
    """A train's figures from its rows (``output_rows``): the bounded peak search
    (``camjax.metrics.peak_search``), which refines only the intervals that can hold the
    peak (the dense refinement of every row cost a chain ten times its propagation)."""
    rows = output_rows(bodies)
    accelerations = np.arange(rows["acceleration_m_s2"].start, rows["acceleration_m_s2"].stop)
    peaks = np.concatenate([accelerations, [rows["surge_n"]]])
    peak = jax.vmap(_bounded_peak, in_axes=(0, None, 0, 0))(values[peaks], widths, left[peaks], right[peaks])
    seat = rows["seat_force_n"]
    high = _bounded_max(values[seat], widths, left[seat], right[seat])
    low = -_bounded_max(-values[seat], widths, -left[seat], -right[seat])
    lift_error = jnp.max(jnp.abs(values[rows["lift_error_mm"]]))
    return TrainPeaks(peak[:bodies], low, high, peak[bodies], lift_error)


def _bounded_peak(values, widths, left, right):
    """``max |f|`` between the nodes, refining only the intervals whose Bernstein bound can
    beat the best found (``camjax.metrics.peak_search``)."""
    bound = bernstein_bound(values, widths, tuple(left.T), tuple(right.T))
    data = hermite_data(values, widths, left, right)
    return peak_search(bound, lambda index: data[index], jnp.max(jnp.abs(values)), PEAK_TOLERANCE)


def _bounded_max(values, widths, left, right):
    """``max f`` (signed) between the nodes, by ``_bounded_peak`` of the shifted signal."""
    low = jnp.min(values)
    shift = low - (jnp.max(values) - low) - 1.0
    return _bounded_peak(values - shift, widths, left, right) + shift


def residual_modes(grid: CycleGrid, oscillator: Oscillator, q, rpm):
    """The last body's free vibration at the start of each dwell and constant-velocity
    segment, mode by mode, ``(S, points)`` complex (mm): ``g_j (q_j - q_j,static)`` with
    ``g_j`` the payload displacement's gain, whose modulus is that mode's share of the
    residual vibration.  The forcing there is ``b T^2 (y0 + y_s sigma)`` (no ``y_ss``),
    whose particular solution of ``q_s = lam q + forcing`` is
    ``-b T^2 (y0 + y_s / lam) / lam``.  Affine in the lift's samples."""
    period = 60.0 / rpm
    lam = (period * jnp.asarray(oscillator.lam))[:, None]
    beta = (jnp.asarray(oscillator.forcing)[:, 0] * period**2)[:, None]
    starts = jnp.asarray(grid.residual_start)
    y, ys = jnp.asarray(grid.lift_nodes)[starts], jnp.asarray(grid.velocity_nodes)[starts]
    q_static = -beta * (y + ys / lam) / lam
    gain = (jnp.asarray(oscillator.gain)[PAYLOAD_DISPLACEMENT] / period)[:, None]
    return gain * (q[:, starts] - q_static)


def residual_vibration(grid: CycleGrid, oscillator: Oscillator, q, rpm):
    """The residual vibration (mm) at the start of each dwell and constant-velocity
    segment: ``sum_j |g_j (q_j - q_j,static)|`` (``residual_modes``), the envelope of the
    last body's free vibration there, a bound of its amplitude that is exact for one mode
    (the classic follower: the deflection's free amplitude) and for several modes the
    largest the free vibration can reach where their phases meet."""
    return jnp.sum(jnp.abs(residual_modes(grid, oscillator, q, rpm)), axis=0)
