"""A cam program at machine speed, through the one SDOF engine: periodic steady state and start-up.

The follower is an ``Oscillator`` (``_oscillator.py``): its modes in physical units, the
classic one-body follower's (the deflection ``e = y - x`` of
``m x'' = k (y - x) + c (y' - x') - k_s x``, one mode with forcing ``y'' + (k_s/m) y``) or a
chain's.  Time runs in turns (``s = t / T``, ``T = 60 / rpm``), so mode ``j``'s forcing is
``a_j y_ss + b_j T^2 y``, two arrays sampled once per program on the engine's grid
(``camjax.sdof.piecewise_grid``) and mixed per speed; the engine's periodic start
(``q(0) = F / (1 - E)``) gives each mode's steady state exactly, and the oscillator's gains
give every output (contact force, payload acceleration, drive torque, Hertz stress, residual
vibration, a train's own figures) in SI units, their extremes refined between nodes.  A
speed sweep runs in blocks of ``SPEED_BLOCK`` speeds through one compiled program per shape
of the turn (the number of modes and outputs, the bucketed grid), whose values are its
arguments (``PaddedTurn``): another follower, one body or a chain of the same shape, or an
edited one, compiles nothing.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .. import checks
from .._shapes import bucket
from .._traces import exported_jit, register_types
from .._traces import kept as traces_kept
from ..errors import RESULTS, raise_if_failed
from ..metrics import PEAK_TOLERANCE, bernstein_bound, hermite_data, peak_search, refined_peak
from ..sdof import (
    GAUSS_POINTS,
    MAX_GRID_INTERVALS,
    TARGET_PHASE_STEP,
    MotionGrid,
    mode_between,
    periodic_propagate,
    piecewise_grid,
    propagate,
    refined_extremes,
    to_monomial,
)
from ..sharding import resolve_devices, shard_batch
from ._machine import NodeContact, contact_stress_squared, node_contact, torque_figures, torque_jets
from ._oscillator import (
    CONTACT_FORCE,
    PAYLOAD_ACCELERATION,
    PAYLOAD_DISPLACEMENT,
    Oscillator,
    output_rows,
)
from ._outputs import Outputs, Probe
from ._spec import Program
from ._speeds import IMPLAUSIBLE_PERIOD_RATIO as IMPLAUSIBLE_PERIOD_RATIO
from ._speeds import IMPLAUSIBLE_RPM as IMPLAUSIBLE_RPM
from ._speeds import Speeds
from ._speeds import warn_implausible as warn_implausible

_MIN_PER_SEGMENT = 64
_MIN_PER_PIECE = 4


class CycleGrid(NamedTuple):
    """The engine's grid over one turn (``s`` in [0, 1]), with the law breakpoints and
    segment ends as nodes, and the program's samples on it.

    ``motion.forcing`` and ``lift`` are ``(K, 6)`` monomial coefficients (in the local
    ``sigma``) of ``y_ss`` and ``y`` on each interval (mm, time in turns); ``lift_nodes``
    and ``velocity_nodes`` are ``y`` and ``y_s`` at the nodes; ``segment_start`` the
    interval index where each segment starts (``residual_start``: each dwell and
    constant-velocity segment, where the residual vibration is measured).
    """

    motion: MotionGrid
    lift: np.ndarray
    lift_nodes: np.ndarray
    velocity_nodes: np.ndarray
    segment_start: np.ndarray
    residual_start: np.ndarray

    @property
    def nodes(self) -> np.ndarray:
        return np.asarray(self.motion.nodes)

    @property
    def piece_width(self) -> np.ndarray:
        return np.asarray(self.motion.piece_width)

    @property
    def intervals(self) -> int:
        return int(self.motion.piece.size)

    def with_forcing(self, forcing) -> MotionGrid:
        """The engine's grid of this turn with another forcing on it."""
        return self.motion._replace(forcing=forcing)


def resolution(program: Program, rpm_min: float, vibration_hz: float | None = None) -> int:
    """Intervals per turn the slowest speed asks for: ``w h <= 0.5`` at ``rpm_min``, 64 per
    moving segment at least (``cycle_grid`` adds what each law piece needs); ``w`` is the
    follower's, or ``2 pi vibration_hz`` where given (a chain's highest mode)."""
    cycles = (program.follower.vibrations_per_turn(rpm_min) if vibration_hz is None
              else vibration_hz * 60.0 / rpm_min)
    needed = 2 * math.pi * cycles / TARGET_PHASE_STEP
    shortest = min((program.segments[i].angle_deg / 360 for i in program.moving_segments()), default=1.0)
    return 64 * math.ceil(max(needed, _MIN_PER_SEGMENT / shortest, 256) / 64)


def check_grid_size(program: Program, rpm_min: float, intervals: int) -> None:
    """The one refusal of a turn whose grid would pass ``MAX_GRID_INTERVALS``, before any
    work, with what to change: the speed or the stiffness where the follower's vibration
    asks for the intervals, the shortest segments where the laws' pieces do."""
    if intervals <= MAX_GRID_INTERVALS:
        return
    cycles = program.follower.vibrations_per_turn(rpm_min)
    by_speed = 2 * math.pi * cycles / TARGET_PHASE_STEP > MAX_GRID_INTERVALS / 2
    slowest = 2 * math.pi * program.follower.vibrations_per_turn(TARGET_PHASE_STEP * MAX_GRID_INTERVALS)
    shortest = min(s.angle_deg for s in program.segments)
    remedies = ([f"run at {slowest:.3g} rpm or faster, or lower follower.stiffness_n_per_mm"] if by_speed else [])
    remedies.append(f"widen or merge the shortest segments ({len(program.segments)} segments, the shortest "
                    f"{shortest:g} degrees)")
    raise ValueError(f"a turn at {rpm_min:g} rpm needs {intervals:,} grid intervals (the limit is "
                     f"{MAX_GRID_INTERVALS:,}): the follower vibrates {cycles:,.0f} times per turn; "
                     + "; or ".join(remedies))


def cycle_grid(program: Program, rpm_min: float, vibration_hz: float | None = None) -> CycleGrid:
    """Sample the program's lift and acceleration on the engine's grid for speeds from
    ``rpm_min`` up (``resolution``; every law piece gets at least four intervals); a grid
    past the limit is refused before it is built (``check_grid_size``)."""
    intervals = resolution(program, rpm_min, vibration_hz)
    edges, counts, first_piece = [0.0], [], []
    for seg, start_deg in zip(program.segments, program.start_deg):
        s0, f = start_deg / 360.0, seg.angle_deg / 360.0
        local = [0.0, *seg.law.breakpoints(), 1.0] if seg.moving else [0.0, 1.0]
        first_piece.append(len(counts))
        for a, b in zip(local[:-1], local[1:]):
            edges.append(s0 + f * b)
            counts.append(max(_MIN_PER_PIECE, math.ceil(intervals * f * (b - a))))
    edges[-1] = 1.0
    counts = np.asarray(counts)
    total = int(counts.sum())
    check_grid_size(program, rpm_min, total)
    motion, times = piecewise_grid(np.asarray(edges), counts)
    piece_start = np.concatenate([[0], np.cumsum(counts)])
    starts = piece_start[first_piece]
    stops = [*starts[1:], total]
    left = np.asarray(motion.nodes)[:-1]
    acc, lift = np.zeros_like(times), np.zeros_like(times)
    lift_nodes, velocity_nodes = np.zeros(total + 1), np.zeros(total + 1)
    for k, (a, b) in enumerate(zip(starts, stops)):
        lift_g, acc_g, lift_nodes[a:b], velocity_nodes[a:b] = _segment_samples(
            program.turn, k, times[a:b], left[a:b])
        lift[a:b], acc[a:b] = lift_g, acc_g
    velocity_nodes[-1] = velocity_nodes[0]  # the turn closes on its start
    return CycleGrid(
        motion=motion._replace(forcing=to_monomial(acc)),
        lift=to_monomial(lift),
        lift_nodes=lift_nodes,
        velocity_nodes=velocity_nodes,
        segment_start=np.asarray(starts),
        residual_start=np.asarray([starts[i] for i in program.residual_segments()], dtype=int),
    )


def _segment_samples(turn, k: int, gauss, left, law=None):
    """Segment ``k``'s lift and acceleration at its Gauss points ``gauss`` and its lift and
    velocity at the left nodes ``left`` of its intervals (times in turns; mm and per
    turn).  The nodes belong to the segment by index: their local time is clipped to
    ``[0, 1]``, so a node that rounds a hair before the segment's start reads the segment's
    own start (not the dwell before it).  One evaluation of the law per segment."""
    s0, f = turn.start_deg[k] / 360.0, turn.angle_deg[k] / 360.0
    tau_gauss = (gauss - s0) / f
    tau_left = np.clip((left - s0) / f, 0.0, 1.0)
    xp = np if law is None else jnp
    y, dy, ddy, _ = turn.segment_jet(k, xp.concatenate([xp.ravel(tau_gauss), tau_left]), law)
    n = tau_gauss.size
    return (y[:n].reshape(tau_gauss.shape), 360.0**2 * ddy[:n].reshape(tau_gauss.shape),
            y[n:], 360.0 * dy[n:])


def program_grid(program: Program, rpm_min: float) -> CycleGrid:
    """``cycle_grid`` for the program's follower: a chain's resolves its highest mode with
    the cam held (``Chain.highest_frequency_hz``), the classic's its one."""
    chain = None if program.one_body else program.chain
    return cycle_grid(program, rpm_min, None if chain is None else chain.highest_frequency_hz())


def with_segment_law(grid: CycleGrid, program: Program, index: int, law) -> CycleGrid:
    """``grid`` with segment ``index``'s (0-based) samples recomputed from ``law`` in JAX.

    The law may be traced (a design differentiates through it); it must have the same
    breakpoints as the segment's law the grid was built for, so the nodes stay valid.
    Every sample is linear in the law's displacement, so the response is affine in it.
    """
    seg = program.segments[index]
    if not seg.moving:
        raise ValueError(f"segment {index + 1} is a dwell: it has no law to replace")
    if tuple(law.breakpoints()) != tuple(seg.law.breakpoints()):
        raise ValueError(f"segment {index + 1}: the new law's breakpoints differ from the grid's")
    stop = grid.segment_start[index + 1] if index + 1 < len(program.segments) else grid.intervals
    rows = slice(int(grid.segment_start[index]), int(stop))
    left = grid.nodes[rows]
    h = grid.piece_width[np.asarray(grid.motion.piece)[rows]]
    gauss = left[:, None] + h[:, None] * GAUSS_POINTS
    lift_samples, acceleration, lift_nodes, velocity = _segment_samples(program.turn, index, gauss, left, law)
    velocity_nodes = jnp.asarray(grid.velocity_nodes).at[rows].set(velocity)
    if index == 0:  # the closing node repeats the first one's velocity (periodic)
        velocity_nodes = velocity_nodes.at[-1].set(velocity_nodes[0])
    return grid._replace(
        motion=grid.with_forcing(jnp.asarray(grid.motion.forcing).at[rows].set(to_monomial(acceleration))),
        lift=jnp.asarray(grid.lift).at[rows].set(to_monomial(lift_samples)),
        lift_nodes=jnp.asarray(grid.lift_nodes).at[rows].set(lift_nodes),
        velocity_nodes=velocity_nodes,
    )


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


def mode_forcing(grid: CycleGrid, oscillator: Oscillator, period):
    """``(S, K, 6)``: each mode's forcing in turn time, ``a_j y_ss + b_j T^2 y``, on the grid."""
    weights = jnp.asarray(oscillator.forcing)
    acc, lift = jnp.asarray(grid.motion.forcing), jnp.asarray(grid.lift)
    return weights[:, 1, None, None] * acc + (weights[:, 0] * period**2)[:, None, None] * lift


def _modes(grid: CycleGrid, oscillator: Oscillator, rpm, q_start=None, periodic=True):
    """The modes at the nodes over one turn at ``rpm`` in turn time, ``(S, K + 1)``: each
    through the engine's exact propagation with its own eigenvalue and forcing."""
    period = 60.0 / rpm
    lam = period * jnp.asarray(oscillator.lam)
    forcing = mode_forcing(grid, oscillator, period)
    if periodic:
        return jax.vmap(lambda l, f: periodic_propagate(grid.with_forcing(f), None, None, lam=l))(lam, forcing)
    q_start = jnp.broadcast_to(jnp.asarray(q_start, dtype=complex), lam.shape)
    return jax.vmap(lambda l, f, q0: propagate(grid.with_forcing(f), None, None, q0=q0, lam=l))(
        lam, forcing, q_start)


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


class SpeedSummary(NamedTuple):
    """The periodic steady state at every speed: ``values``, each compiled output of the
    set (``Outputs.compiled``, name -> array over the speeds), and the stacked ``Cycle``
    (its node series and figures; ``residual_vibration_mm`` per residual segment).  An
    output reads as an attribute (``summary.min_contact_force_n``)."""

    rpm: np.ndarray
    values: dict
    cycles: Cycle

    @property
    def residual_vibration_mm(self) -> np.ndarray:
        return self.cycles.residual_vibration_mm

    def __getattr__(self, name):
        values = self[1]
        if name in values:
            return values[name]
        raise AttributeError(f"SpeedSummary has no attribute {name!r} (outputs: {', '.join(values)})")


class PaddedTurn(NamedTuple):
    """A turn's grid, follower and contact factors padded to bucketed shapes: the compiled
    turn's arguments.  The padding is empty intervals (width 0) at the end of the turn in a
    piece of their own, which carry the mode unchanged and add nothing to any integral;
    node arrays repeat the closing node."""

    grid: CycleGrid
    oscillator: Oscillator
    contact: NodeContact

    @classmethod
    def of(cls, grid: CycleGrid, oscillator: Oscillator, contact: NodeContact) -> PaddedTurn:
        intervals = grid.intervals
        pieces = int(np.asarray(grid.motion.piece_width).size)
        extra = bucket(intervals, 64) - intervals
        piece_pad = 8 * -(-(pieces + 1) // 8) - pieces

        def nodes(x):
            x = np.asarray(x)
            return np.concatenate([x, np.repeat(x[-1:], extra, axis=0)])

        def rows(x):
            x = np.asarray(x)
            return np.concatenate([x, np.zeros((extra, *x.shape[1:]), x.dtype)])

        m = grid.motion
        motion = m._replace(
            nodes=nodes(m.nodes),
            piece=np.concatenate([np.asarray(m.piece), np.full(extra, pieces)]).astype(np.int32),
            piece_width=np.concatenate([np.asarray(m.piece_width), np.zeros(piece_pad)]),
            forcing=rows(m.forcing))
        padded = grid._replace(motion=motion, lift=rows(grid.lift), lift_nodes=nodes(grid.lift_nodes),
                               velocity_nodes=nodes(grid.velocity_nodes),
                               segment_start=np.asarray(grid.segment_start, dtype=np.int32),
                               residual_start=np.asarray(grid.residual_start, dtype=np.int32))
        return cls(padded, oscillator, NodeContact(*(nodes(x) for x in contact)))


SPEED_BLOCK = 32
"""Speeds per compiled call: every batch of speeds runs in blocks of this width (the last
padded), so a turn's shape compiles one program whatever the number of speeds."""


def _node_arrays_cut(cycle: Cycle, intervals: int) -> Cycle:
    """A ``Cycle`` of a padded turn cut back to the turn's own nodes and intervals."""
    nodes = intervals + 1
    return cycle._replace(
        q=cycle.q[..., :nodes], payload_acceleration_m_s2=cycle.payload_acceleration_m_s2[..., :nodes],
        contact_force_n=cycle.contact_force_n[..., :nodes], drive_torque_n_m=cycle.drive_torque_n_m[..., :nodes],
        contact_stress_mpa=cycle.contact_stress_mpa[..., :nodes],
        max_contact_stress_node=np.minimum(cycle.max_contact_stress_node, intervals),
        drive_torque_left=cycle.drive_torque_left[..., :intervals, :],
        drive_torque_right=cycle.drive_torque_right[..., :intervals, :])


@functools.partial(jax.jit, static_argnames="outputs")
def _cycles(rpm, turn: PaddedTurn, outputs: tuple[Probe, ...]) -> Cycle:
    """The periodic steady state's whole ``Cycle`` at every speed of a block, with the
    values of the compiled ``outputs`` (``Outputs.compiled``, a static argument): one
    compiled program per shape of the turn and set of outputs, whatever the program's
    values."""

    def one(r):
        cycle = _cycle(turn.grid, turn.oscillator, r, contact=turn.contact)
        return cycle._replace(outputs={p.name: jnp.asarray(p.fn(cycle, turn), dtype=float) for p in outputs})

    return jax.vmap(one)(rpm)


register_types(PaddedTurn, CycleGrid, MotionGrid, Oscillator, NodeContact, Cycle, TrainPeaks)


_BUILT_IN_COMPILED = Outputs().compiled


def _cycles_built_in(rpm, turn: PaddedTurn) -> Cycle:
    return _cycles(rpm, turn, _BUILT_IN_COMPILED)


_kept_cycles = exported_jit(_cycles_built_in, "program-cycles")
"""``_cycles`` of the built-in outputs, its trace kept on disk for the next process (``camjax._traces``)."""


@jax.jit
def _started_cycle(rpm, turn: PaddedTurn, q_start) -> Cycle:
    """One turn from the mode ``q_start`` at its start (a start-up's turns)."""
    return _cycle(turn.grid, turn.oscillator, rpm, q_start=q_start, periodic=False, contact=turn.contact)


class SteadyState:
    """A program's periodic steady state, compiled once per shape.

    Build once per program and slowest speed (which fixes the grid).  The program's values
    (its grid, forcing, follower and contact factors) are arguments of module-level compiled
    functions, padded to bucketed shapes (``bucket``), so another program of the same
    shape, or an edited one, reuses the compiled program in this process and from JAX's
    persistent cache.  The speeds run in blocks of ``SPEED_BLOCK`` through one compiled
    program (the whole ``Cycle`` at every speed of a block); each block is split over
    ``devices`` (default: every local device; see ``camjax.sharding.shard_batch``), with
    results equal to one device's.  A response that is not finite is a ``SolverError``
    (``RESULTS.nonfinite``).  The follower is ``Oscillator.of(program)`` unless
    ``oscillator`` is given (another realisation of the same follower, or an edit of its
    values: the same shape compiles nothing).
    """

    def __init__(self, program: Program, rpm_min: float | Speeds, *, devices=None,
                 oscillator: Oscillator | None = None):
        if program.one_body and not program.follower.damping_ratio > 0:
            raise ValueError("the periodic steady state needs follower.damping_ratio > 0 "
                             "(without damping the start-up never settles)")
        self.program = program
        # a chain's refuses an undamped mode
        self.oscillator = Oscillator.of(program) if oscillator is None else oscillator
        self.rpm_min = Speeds.of(rpm_min, "rpm_min").min()  # an entry point's speeds: their slowest
        self.devices = resolve_devices(devices)
        self.grid = program_grid(program, self.rpm_min)
        self.contact = node_contact(program, 360.0 * self.grid.nodes)
        self.turn = PaddedTurn.of(self.grid, self.oscillator, self.contact)
        self._kept: tuple[dict[float, int], Cycle | None] = ({}, None)
        """The last batch of ``cycles``: its row of each speed, and the stacked ``Cycle``."""

    def summary(self, rpm, outputs: Outputs | None = None) -> SpeedSummary:
        """Refined extrema and residual vibration at every speed in ``rpm`` (``Speeds``),
        with the compiled values of ``outputs`` (default: ``default_outputs()``); the
        cycles computed on the way are kept for ``cycle`` (the flights read them)."""
        rpm = Speeds.of(rpm)
        cycles = self.cycles(rpm, outputs)
        return SpeedSummary(rpm.rpm, dict(cycles.outputs), cycles)

    def cycles(self, rpm, outputs: Outputs | None = None) -> Cycle:
        """The whole ``Cycle`` at every speed of ``rpm`` (``Speeds``), stacked on axis 0,
        with the compiled values of ``outputs`` (``Cycle.outputs``)."""
        rpm = Speeds.of(rpm).rpm
        outputs = Outputs.of(outputs)
        self._check_slowest(rpm)
        out = _node_arrays_cut(self._blocks(_cycles, rpm, outputs=outputs), self.grid.intervals)
        for p in outputs.compiled:
            values = out.outputs[p.name]
            if not p.built_in and not np.all(np.isfinite(values)):
                raise ValueError(f"probe {p.name!r} is not finite at {rpm[~np.isfinite(values)][0]:g} rpm")
        raise_if_failed(RESULTS.successful, lambda i: f"the steady state at {rpm[i]:g} rpm",
                        *(out.outputs[p.name] for p in outputs.compiled if p.built_in))
        self._kept = {float(r): i for i, r in enumerate(rpm)}, out
        return out

    def cycles_at(self, rpm) -> Cycle:
        """``cycles`` at the speeds ``rpm``: read from the last batch where every one of them
        was computed (``summary`` keeps it), else computed."""
        rpm = Speeds.of(rpm).rpm
        kept, cycles = self._kept
        if all(float(r) in kept for r in rpm):
            rows = np.array([kept[float(r)] for r in rpm], dtype=int)
            return jax.tree.map(lambda x: x[rows], cycles)
        return self.cycles(rpm)

    def min_contact_force_n(self, rpm) -> np.ndarray:
        """``summary(rpm).min_contact_force_n`` alone (the jump's scan and bisection): the
        same compiled program, so a program's first look compiles one."""
        rpm = Speeds.of(rpm).rpm
        self._check_slowest(rpm)
        force = self._blocks(_cycles, rpm, keep=lambda c: c.min_contact_force_n)
        raise_if_failed(RESULTS.successful, lambda i: f"the steady state at {rpm[i]:g} rpm", force)
        return force

    def _check_slowest(self, rpm: np.ndarray) -> None:
        if rpm.min() < self.rpm_min * (1 - 1e-12):
            raise ValueError(f"rpm {rpm.min():g} below the steady state's slowest speed {self.rpm_min:g}")

    def _blocks(self, program, rpm: np.ndarray, keep=None, outputs: Outputs | None = None):
        """``program`` over the speeds in blocks of ``SPEED_BLOCK`` (the last padded), each
        split over the devices (all of them, or one where the block does not split
        evenly: one compiled program for every call), with the compiled ``outputs``
        (default: the built-in ones); the blocks are dispatched before any is waited for,
        and ``keep`` picks the outputs to bring back."""
        size = rpm.size
        padded = np.pad(rpm, (0, -size % SPEED_BLOCK), mode="edge").reshape(-1, SPEED_BLOCK)
        devices = self.devices if SPEED_BLOCK % len(self.devices) == 0 else self.devices[:1]
        keep = keep or (lambda out: out)
        compiled = _BUILT_IN_COMPILED if outputs is None else outputs.compiled
        if program is _cycles and compiled == _BUILT_IN_COMPILED and len(devices) == 1 and traces_kept():  # from disk
            def run(block):
                with jax.default_device(devices[0]):
                    return _kept_cycles(block, self.turn)
        else:
            def run(block):
                return shard_batch(program, block, self.turn, compiled, devices=devices)
        outs = [keep(run(jnp.asarray(block))) for block in padded]
        return jax.tree.map(lambda *x: np.concatenate([np.asarray(v) for v in x])[:size], *outs)

    def cycle(self, rpm: float, q_start=None) -> Cycle:
        """Node series and extrema of the periodic steady state at one speed (or of the
        turn from the mode ``q_start`` at its start, if given)."""
        rpm = Speeds.of(rpm)[0]
        if q_start is None:
            kept, cycles = self._kept
            if rpm not in kept:
                self._check_slowest(np.array([rpm]))
                cycles, kept = self._blocks(_cycles, np.array([rpm])), {rpm: 0}
                cycles = _node_arrays_cut(cycles, self.grid.intervals)
            return jax.tree.map(lambda x: x[kept[rpm]], cycles)
        out = _started_cycle(jnp.asarray(rpm), self.turn, jnp.asarray(q_start, dtype=complex))
        return _node_arrays_cut(jax.tree.map(np.asarray, out), self.grid.intervals)

    def lam(self, rpm: float) -> np.ndarray:
        """The oscillator's eigenvalues in turn time (``lambda T``) at ``rpm``, ``(S,)``."""
        return 60.0 / float(rpm) * np.asarray(self.oscillator.lam)

    def mode_at(self, q_nodes, rpm: float, s) -> np.ndarray:
        """The complex modes at turn times ``s`` (anywhere, exactly) from their node values
        (``(S, K + 1)``, ``Cycle.q``): ``(S, times)``."""
        period = 60.0 / float(rpm)
        weights = np.asarray(self.oscillator.forcing)
        acc, lift = np.asarray(self.grid.motion.forcing), np.asarray(self.grid.lift)
        s = np.mod(np.atleast_1d(np.asarray(s, dtype=float)), 1.0)
        return np.stack([
            mode_between(self.grid.with_forcing(w[1] * acc + w[0] * period**2 * lift), q, lam, s)
            for w, q, lam in zip(weights, np.atleast_2d(q_nodes), self.lam(rpm))])


def startup(program: Program, rpm: float, cycles: int, *, steady: SteadyState | None = None):
    """Start-up from rest on the base circle: ``(s, payload acceleration m/s^2, contact force N)``.

    ``s`` runs over ``cycles`` turns (grid nodes of each, the last node left to the next
    turn); the engine's exact step carries the state from turn to turn.
    """
    rpm = Speeds.of(rpm)[:1]
    steady = steady or SteadyState(program, rpm)
    s, accel, force = [], [], []
    q_start = np.zeros(steady.oscillator.modes_count, complex)
    for c in range(int(cycles)):
        run = steady.cycle(rpm, q_start=q_start)
        s.append(c + steady.grid.nodes[:-1])
        accel.append(run.payload_acceleration_m_s2[:-1])
        force.append(run.contact_force_n[:-1])
        q_start = run.q[:, -1]
    return np.concatenate(s), np.concatenate(accel), np.concatenate(force)


def node_contact_force(program: Program, rpm, laws: dict | None = None, *, rpm_min: float | None = None):
    """Contact force (N) of the periodic steady state at every grid node and speed,
    ``(speeds, nodes)``, with the laws of some segments replaced (``{segment: law}``,
    1-based; the laws may be traced: the force is affine in each, so it differentiates).

    A replacement keeps the breakpoints of the law it replaces (``with_segment_law``).
    The grid is the one for ``rpm_min`` (default: the slowest of ``rpm``, which must then
    be concrete).  Concrete speeds are checked as ``Speeds`` checks them; traced ones
    make the computation raise the same message when it runs with a bad one.
    """
    if rpm_min is not None:
        rpm_min = Speeds.of(rpm_min, "rpm_min").min()
    if checks.is_concrete(rpm):
        speeds = Speeds.of(rpm)
        rpm_min = speeds.min() if rpm_min is None else rpm_min
        rpm = jnp.asarray(speeds.rpm)
    else:
        if rpm_min is None:
            raise ValueError("rpm_min is needed where rpm is traced (it fixes the grid)")
        rpm = jnp.atleast_1d(jnp.asarray(rpm, dtype=float))
        if rpm.ndim != 1 or rpm.size == 0:
            raise ValueError("rpm must be one speed or a 1-D list of speeds")
        rpm = checks.ensure(rpm, lambda v: (v > 0) & (v < np.inf), "rpm must be positive and finite")
    with jax.ensure_compile_time_eval():
        grid = program_grid(program, rpm_min)
    for segment, law in (laws or {}).items():
        grid = with_segment_law(grid, program, segment - 1, law)
    oscillator = Oscillator.of(program)
    return jax.vmap(lambda r: _cycle(grid, oscillator, r).contact_force_n)(rpm)
