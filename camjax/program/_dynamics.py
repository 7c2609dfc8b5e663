"""A cam program at machine speed, through the one SDOF engine: the periodic steady state over
speeds, and start-up.

The follower is an ``Oscillator`` (``_oscillator.py``): its modes in physical units, the
classic one-body follower's (the deflection ``e = y - x`` of
``m x'' = k (y - x) + c (y' - x') - k_s x``, one mode with forcing ``y'' + (k_s/m) y``) or a
chain's.  The turn is sampled once per program on the engine's grid (``_cycle_grid.py``);
one turn at one speed is ``_cycle.py``'s ``_cycle`` (every mode's exact periodic steady
state and every output in SI units, refined between nodes).  This module runs it over the
speeds: in blocks of ``SPEED_BLOCK`` through one compiled program per shape of the turn (the
number of modes and outputs, the bucketed grid), whose values are its arguments
(``PaddedTurn``): another follower, one body or a chain of the same shape, or an edited one,
compiles nothing.
"""

from __future__ import annotations

import functools
import math
import os
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .. import checks
from .._shapes import bucket
from .._traces import exported_jit, register_types
from .._traces import kept as traces_kept
from ..errors import RESULTS, raise_if_failed
from ..sdof import (
    MotionGrid,
    mode_between,
)
from ..sharding import resolve_devices, shard_batch
from ._contact import NodeContact, node_contact
from ._cycle import Cycle, TrainPeaks, _cycle
from ._cycle_grid import CycleGrid, grid_intervals, program_grid, resolves, with_segment_law
from ._oscillator import (
    Oscillator,
)
from ._outputs import BUILT_IN_OUTPUTS, Outputs, Probe
from ._program import Program
from ._speeds import Speeds


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

BLOCK_BYTES = 170
"""Memory of one compiled block of speeds per interval, speed and mode or output row: XLA's
memory analysis of ``_cycles`` gave 120 to 166 bytes (the feed cam, a ten-body chain, the
flexible arm; 2026-11-29)."""
MEMORY_SHARE = 0.5
"""The share of a device's memory (the machine's, on the CPU) one block may take."""


def device_memory_bytes(device) -> int | None:
    """The memory a block of speeds may use on ``device``: its own limit where it reports
    one (an accelerator), else the machine's physical memory; None where neither is known."""
    stats = getattr(device, "memory_stats", lambda: None)() or {}
    if stats.get("bytes_limit"):
        return int(stats["bytes_limit"])
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return None


def block_memory_bytes(intervals: int, oscillator: Oscillator) -> int:
    """The memory one compiled block of ``SPEED_BLOCK`` speeds of a turn of ``intervals``
    takes, about: ``BLOCK_BYTES`` per interval, speed and mode or output row."""
    values = oscillator.modes_count + int(np.shape(oscillator.gain)[0])
    return BLOCK_BYTES * intervals * SPEED_BLOCK * values


def check_block_memory(program: Program, oscillator: Oscillator, rpm_min: float, budget: float | None) -> None:
    """Refuse, before anything compiles, a turn whose block of speeds needs more than
    ``budget`` bytes (``block_memory_bytes``), with the slowest speed that fits (the
    intervals grow as the slowest speed falls; found on the grid's layout alone), or none
    where the segments' least intervals alone do not fit."""
    def need(rpm):
        return block_memory_bytes(grid_intervals(program, rpm, oscillator.lam), oscillator)

    asked = need(rpm_min)
    if budget is None or asked <= budget:
        return
    values = oscillator.modes_count + int(np.shape(oscillator.gain)[0])
    speed, remedy = rpm_min, "with fewer segments"
    for _ in range(8):  # the intervals fall about as 1 / rpm, to the segments' least
        speed = math.ceil(speed * max(need(speed) / budget, 1.0001))
        if need(speed) <= budget:
            remedy = f"at {speed:,} rpm or faster"
            break
    raise ValueError(
        f"a turn at {rpm_min:g} rpm: {asked / (BLOCK_BYTES * SPEED_BLOCK * values):,.0f} intervals x "
        f"{values} modes and outputs x {SPEED_BLOCK} speeds need about {asked / 1e9:.1f} GB at once, "
        f"more than the {budget / 1e9:.1f} GB a block may take ({MEMORY_SHARE:.0%} of the device's memory "
        f"unless memory_bytes says): run {remedy}, or with fewer modes (a spring's or an arm's elements)")


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


_BUILT_IN_COMPILED = BUILT_IN_OUTPUTS.compiled


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
    values: the same shape compiles nothing).  A turn whose block of speeds needs more than
    ``memory_bytes`` (default: ``MEMORY_SHARE`` of the device's memory) is refused before
    anything compiles (``block_memory_bytes``), with the slowest speed that fits.
    """

    def __init__(self, program: Program, rpm_min: float | Speeds, *, devices=None,
                 oscillator: Oscillator | None = None, memory_bytes: float | None = None):
        if program.one_body and not program.follower.damping_ratio > 0:
            raise ValueError("the periodic steady state needs follower.damping_ratio > 0 "
                             "(without damping the start-up never settles)")
        self.program = program
        # a chain's refuses an undamped mode
        self.oscillator = Oscillator.of(program) if oscillator is None else oscillator
        self.rpm_min = Speeds.of(rpm_min, "rpm_min").min()  # an entry point's speeds: their slowest
        self.devices = resolve_devices(devices)
        self.grid = program_grid(program, self.rpm_min, self.oscillator.lam)
        if memory_bytes is None:
            limit = device_memory_bytes(self.devices[0])
            memory_bytes = None if limit is None else MEMORY_SHARE * limit
        check_block_memory(program, self.oscillator, self.rpm_min, memory_bytes)
        if not resolves(self.grid, self.oscillator.lam, self.rpm_min):
            raise ValueError("oscillator: its fastest mode turns too far per interval of the program's grid "
                             "(give SteadyState an oscillator of the program's own follower)")
        self.contact = node_contact(program, 360.0 * self.grid.nodes)
        self.turn = PaddedTurn.of(self.grid, self.oscillator, self.contact)
        self._kept: tuple[dict[float, int], Cycle | None] = ({}, None)
        """The last batch of ``cycles``: its row of each speed, and the stacked ``Cycle``."""

    def summary(self, rpm, outputs: Outputs = BUILT_IN_OUTPUTS) -> SpeedSummary:
        """Refined extrema and residual vibration at every speed in ``rpm`` (``Speeds``),
        with the compiled values of ``outputs`` (default: the built-in ones); the
        cycles computed on the way are kept for ``cycle`` (the flights read them)."""
        rpm = Speeds.of(rpm)
        cycles = self.cycles(rpm, outputs)
        return SpeedSummary(rpm.rpm, dict(cycles.outputs), cycles)

    def cycles(self, rpm, outputs: Outputs = BUILT_IN_OUTPUTS) -> Cycle:
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

    def _blocks(self, program, rpm: np.ndarray, keep=None, outputs: Outputs = BUILT_IN_OUTPUTS):
        """``program`` over the speeds in blocks of ``SPEED_BLOCK`` (the last padded), each
        split over the devices (all of them, or one where the block does not split
        evenly: one compiled program for every call), with the compiled ``outputs``
        (default: the built-in ones); the blocks are dispatched before any is waited for,
        and ``keep`` picks the outputs to bring back."""
        size = rpm.size
        padded = np.pad(rpm, (0, -size % SPEED_BLOCK), mode="edge").reshape(-1, SPEED_BLOCK)
        devices = self.devices if SPEED_BLOCK % len(self.devices) == 0 else self.devices[:1]
        keep = keep or (lambda out: out)
        compiled = outputs.compiled
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
    oscillator = Oscillator.of(program)
    with jax.ensure_compile_time_eval():
        grid = program_grid(program, rpm_min, oscillator.lam)
    for segment, law in (laws or {}).items():
        grid = with_segment_law(grid, program, segment - 1, law)
    return jax.vmap(lambda r: _cycle(grid, oscillator, r).contact_force_n)(rpm)
