"""A program's turn on the engine's grid: the intervals each segment and law piece gets
(``camjax.sdof.segment_layout``) and the lift and acceleration sampled on them once per
program, in turn time (mm, ``s = t / T``); a segment's samples are recomputed from a traced
law for design (``with_segment_law``)."""

from __future__ import annotations

import math
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from ..sdof import (
    GAUSS_POINTS,
    MAX_GRID_INTERVALS,
    MAX_PHASE_STEP,
    TARGET_PHASE_STEP,
    GridSegment,
    MotionGrid,
    check_grid_size,
    period_ratio_reach,
    segment_layout,
    to_monomial,
)
from ._oscillator import Oscillator
from ._program import Program
from ._warnings import sizes_first


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


def _grid_refusal(program: Program, rpm_min: float, cycles: float) -> str:
    """What to change where a turn's grid is too large (``check_grid_size``'s remedy): the
    speed or the stiffness where the vibration asks for the intervals, the shortest
    segments where the laws' pieces do; a size past ``ABSURD_SIZES`` first (``sizes_first``)."""
    by_speed = 2 * math.pi * cycles / TARGET_PHASE_STEP > MAX_GRID_INTERVALS / 2
    slowest = rpm_min * cycles / period_ratio_reach(TARGET_PHASE_STEP)
    shortest = min(s.angle_deg for s in program.segments)
    chain = program.chain
    lower = "lower follower.stiffness_n_per_mm" if chain is None else chain.highest_mode_remedy()
    remedies = ([f"run at {slowest:.3g} rpm or faster, or {lower}"] if by_speed else [])
    remedies.append(f"widen or merge the shortest segments ({len(program.segments)} segments, the shortest "
                    f"{shortest:g} degrees)")
    who = "the follower vibrates" if chain is None else "the chain's highest mode vibrates"
    return sizes_first(program) + f"{who} {cycles:,.0f} times per turn; " + "; or ".join(remedies)


def _layout(program: Program, rpm_min: float, vibration_hz: float | None):
    """The turn's ``SegmentLayout`` and the vibrations per turn it resolves."""
    cycles = (program.follower.vibrations_per_turn(rpm_min) if vibration_hz is None
              else vibration_hz * 60.0 / rpm_min)
    return segment_layout([GridSegment(start_deg / 360.0, seg.angle_deg / 360.0,
                                       tuple(seg.law.breakpoints()) if seg.moving else None)
                           for seg, start_deg in zip(program.segments, program.start_deg)], cycles), cycles


def cycle_grid(program: Program, rpm_min: float, vibration_hz: float | None = None) -> CycleGrid:
    """Sample the program's lift and acceleration on the engine's grid for speeds from
    ``rpm_min`` up (``camjax.sdof.segment_layout``: ``w h <= TARGET_PHASE_STEP`` at
    ``rpm_min``, ``w`` the follower's or ``2 pi vibration_hz`` where given, a chain's
    highest mode); a grid past the limit is refused before it is built (``check_grid_size``)."""
    layout, cycles = _layout(program, rpm_min, vibration_hz)
    total = layout.intervals
    check_grid_size(total, f"a turn at {rpm_min:g} rpm", lambda: _grid_refusal(program, rpm_min, cycles))
    motion, times = layout.grid()
    starts = layout.segment_start
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


def program_grid(program: Program, rpm_min: float, lam=None) -> CycleGrid:
    """``cycle_grid`` for the program's follower: the classic's resolves its one mode; a
    chain's its fastest, the highest natural frequency with the cam held
    (``Chain.highest_frequency_hz``) or the largest ``|lam|`` of its modes (1/s; an
    overdamped mode may be faster), ``lam`` its ``Oscillator``'s where given.  Every mode
    then turns by at most ``TARGET_PHASE_STEP`` per interval at ``rpm_min``, within the
    reach of the propagation's series (``camjax.sdof.series_kicks``)."""
    return cycle_grid(program, rpm_min, _fastest_hz(program, lam))


def grid_intervals(program: Program, rpm_min: float, lam=None) -> int:
    """The intervals of ``program_grid(program, rpm_min, lam)``, without sampling the turn."""
    return _layout(program, rpm_min, _fastest_hz(program, lam))[0].intervals


def _fastest_hz(program: Program, lam) -> float | None:
    """The frequency a program's grid resolves (``program_grid``): None for the classic
    follower's own."""
    if program.one_body:
        return None
    if lam is None:
        lam = Oscillator.of_chain(program.chain).lam
    return max(program.chain.highest_frequency_hz(), float(np.max(np.abs(lam), initial=0.0)) / (2 * math.pi))


def resolves(grid: CycleGrid, lam, rpm_min: float) -> bool:
    """Whether every mode of eigenvalues ``lam`` (1/s) turns by at most ``MAX_PHASE_STEP``
    per interval of ``grid`` at ``rpm_min`` and above (the propagation's series is exact)."""
    widest = float(np.max(grid.piece_width))
    return float(np.max(np.abs(lam), initial=0.0)) * 60.0 / rpm_min * widest <= MAX_PHASE_STEP


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
