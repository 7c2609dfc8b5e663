"""Exact response of a cam program at machine speed: periodic steady state and start-up.

Payload displacement ``x`` from its static position on the base circle, cam lift ``y``:

    m x'' = k (y - x) + c (y' - x') - k_s x,    F_c = F_0 + k (y - x) + c (y' - x').

In the deflection ``e = y - x`` this is ``e'' + (c/m) e' + ((k + k_s)/m) e = y'' + (k_s/m) y``,
the linear SDOF of ``camjax.propagation`` with forcing ``y'' + (k_s/m) y``.  Time runs in
cycles (``s = t / T``, ``T = 60 / rpm``), so the forcing is ``y_ss + (k_s/m) T^2 y``: two
arrays sampled once per program, mixed per speed, which makes a speed sweep one vmapped
call.  One cycle maps the complex mode ``q = e_s - conj(lambda) e`` as
``q(1) = E q(0) + F`` with ``E = exp(lambda)``: the periodic steady state starts from the
fixed point ``q(0) = F / (1 - E)``, exactly.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..metrics import refined_peak
from ..propagation import MotionGrid, eigenvalue, propagate, psi
from ..sharding import resolve_devices, shard_batch
from ._spec import Program

_DEGREE = 5
_GAUSS = (np.polynomial.legendre.leggauss(_DEGREE + 1)[0] + 1) / 2
_TO_MONOMIAL = np.linalg.inv(np.vander(_GAUSS, _DEGREE + 1, increasing=True))
_PHASE_STEP = 0.5  # largest w h per interval (as camjax.propagation.default_resolution)
_MIN_PER_SEGMENT = 64
_CHUNK_NODES = 1 << 16


class CycleGrid(NamedTuple):
    """Nodes over one cycle (``s`` in [0, 1]) with the law breakpoints and segment ends as nodes.

    ``acceleration`` and ``lift`` are ``(K, 6)`` monomial coefficients (in the local
    ``sigma``) of ``y_ss`` and ``y`` on each interval (mm, time in cycles); ``lift_nodes``
    and ``velocity_nodes`` are ``y`` and ``y_s`` at the nodes; ``segment_start`` the node
    index where each segment starts (``dwell_start``: each dwell).
    """

    nodes: np.ndarray
    piece: np.ndarray
    piece_width: np.ndarray
    acceleration: np.ndarray
    lift: np.ndarray
    lift_nodes: np.ndarray
    velocity_nodes: np.ndarray
    segment_start: np.ndarray
    dwell_start: np.ndarray

    def motion_grid(self, forcing) -> MotionGrid:
        return MotionGrid(jnp.asarray(self.nodes), self.piece, jnp.asarray(self.piece_width), forcing)


def resolution(program: Program, rpm_min: float) -> int:
    """Intervals per cycle: ``w h <= 0.5`` at the slowest speed, 64 per moving segment at least."""
    cycles = program.follower.natural_frequency_hz * 60.0 / rpm_min
    needed = 2 * math.pi * cycles / _PHASE_STEP
    shortest = min((program.segments[i].angle_deg / 360 for i in program.moving_segments()), default=1.0)
    return 64 * math.ceil(max(needed, _MIN_PER_SEGMENT / shortest, 256) / 64)


def cycle_grid(program: Program, intervals: int) -> CycleGrid:
    """Sample the program's lift and acceleration on a grid of about ``intervals`` per cycle."""
    left, widths, acc, lift, lift_nodes, vel_nodes, starts, piece_width, piece = ([] for _ in range(9))
    for seg, start_deg, y0 in zip(program.segments, program.start_deg, program.start_lift_mm):
        s0, f = start_deg / 360.0, seg.angle_deg / 360.0
        starts.append(sum(len(x) for x in left))
        edges = np.array([0.0, *seg.law.breakpoints(), 1.0]) if seg.moving else np.array([0.0, 1.0])
        counts = [max(4, math.ceil(intervals * f * (b - a))) for a, b in zip(edges[:-1], edges[1:])]
        h = np.repeat(np.diff(edges) / counts, counts)
        tau_left = np.concatenate([a + (b - a) / n * np.arange(n) for a, b, n in zip(edges[:-1], edges[1:], counts)])
        tau_gauss = tau_left[:, None] + h[:, None] * _GAUSS
        if seg.moving:  # one evaluation of the law per segment (eager JAX calls are slow)
            values = seg.law.evaluate(np.concatenate([tau_gauss.ravel(), tau_left]))
            s_all, v_all, a_all = (np.asarray(x) for x in values[:3])
            n_gauss = tau_gauss.size
            y_g = y0 + seg.lift_mm * s_all[:n_gauss].reshape(tau_gauss.shape)
            yss_g = seg.lift_mm * a_all[:n_gauss].reshape(tau_gauss.shape) / f**2
            y_l, ys_l = y0 + seg.lift_mm * s_all[n_gauss:], seg.lift_mm * v_all[n_gauss:] / f
        else:
            y_g, yss_g = np.full_like(tau_gauss, y0), np.zeros_like(tau_gauss)
            y_l, ys_l = np.full_like(tau_left, y0), np.zeros_like(tau_left)
        left.append(s0 + f * tau_left)
        piece.append(np.repeat(len(piece_width) + np.arange(len(counts)), counts))
        piece_width.extend(f * np.diff(edges) / counts)
        acc.append(yss_g @ _TO_MONOMIAL.T)
        lift.append(y_g @ _TO_MONOMIAL.T)
        lift_nodes.append(y_l)
        vel_nodes.append(ys_l)
    return CycleGrid(
        nodes=np.concatenate([*left, [1.0]]),
        piece=np.concatenate(piece),
        piece_width=np.asarray(piece_width),
        acceleration=np.concatenate(acc),
        lift=np.concatenate(lift),
        lift_nodes=np.concatenate([*lift_nodes, [0.0]]),
        velocity_nodes=np.concatenate([*vel_nodes, vel_nodes[0][:1]]),
        segment_start=np.asarray(starts),
        dwell_start=np.asarray([starts[i] for i in program.dwell_segments()], dtype=int),
    )


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
    stop = grid.segment_start[index + 1] if index + 1 < len(program.segments) else grid.piece.size
    rows = slice(int(grid.segment_start[index]), int(stop))
    s0, f = program.start_deg[index] / 360.0, seg.angle_deg / 360.0
    y0, lift = program.start_lift_mm[index], seg.lift_mm
    tau_left = (grid.nodes[rows] - s0) / f
    h = grid.piece_width[grid.piece[rows]] / f
    tau_gauss = tau_left[:, None] + h[:, None] * _GAUSS
    s, v, a, _ = law.evaluate(jnp.asarray(np.concatenate([tau_gauss.ravel(), tau_left])))
    n_gauss = tau_gauss.size
    to_monomial = jnp.asarray(_TO_MONOMIAL.T)
    acceleration = (lift * a[:n_gauss].reshape(tau_gauss.shape) / f**2) @ to_monomial
    lift_samples = (y0 + lift * s[:n_gauss].reshape(tau_gauss.shape)) @ to_monomial
    velocity_nodes = jnp.asarray(grid.velocity_nodes).at[rows].set(lift * v[n_gauss:] / f)
    if index == 0:  # the closing node repeats the first one's velocity (periodic)
        velocity_nodes = velocity_nodes.at[-1].set(velocity_nodes[0])
    return grid._replace(
        acceleration=jnp.asarray(grid.acceleration).at[rows].set(acceleration),
        lift=jnp.asarray(grid.lift).at[rows].set(lift_samples),
        lift_nodes=jnp.asarray(grid.lift_nodes).at[rows].set(y0 + lift * s[n_gauss:]),
        velocity_nodes=velocity_nodes,
    )


@dataclasses.dataclass(frozen=True)
class _Train:
    """The follower's constants in SI (k, k_s in N/m; c in N s/m)."""

    m: float
    k: float
    ks: float
    c: float
    preload: float
    omega: float  # sqrt((k + k_s)/m), rad/s
    zeta: float  # of the whole oscillator: c / (2 m omega)

    @classmethod
    def of(cls, program: Program) -> _Train:
        f = program.follower
        omega = 2 * math.pi * f.natural_frequency_hz
        return cls(f.mass_kg, f.stiffness, f.spring_rate, f.damping, 0.0 if f.form_closed else f.preload_n,
                   omega, f.damping / (2 * f.mass_kg * omega))


def _signed_max(values, widths, left, right):
    """``max f`` (signed) of a sampled continuous signal, refined between samples."""
    low = jnp.min(values)
    shift = low - (jnp.max(values) - low) - 1.0
    return refined_peak(values - shift, widths, left, right) + shift


def _derivatives(gain, lam, q, one_sided):
    """First three derivatives of ``Re(gain q)`` from one-sided forcing ``(a, a', a'')``."""
    d1 = lam * q + one_sided[:, 0]
    d2 = lam * d1 + one_sided[:, 1]
    d3 = lam * d2 + one_sided[:, 2]
    return jnp.real(gain * jnp.stack([d1, d2, d3], axis=1))


class Cycle(NamedTuple):
    """Node series and refined extrema of one cycle at one speed (s-time, mm).

    ``q`` is the complex mode at the nodes (periodic steady state unless built otherwise).
    Forces in N, accelerations in m/s^2.
    """

    q: jax.Array
    payload_acceleration_m_s2: jax.Array
    contact_force_n: jax.Array
    max_payload_acceleration_m_s2: jax.Array
    min_contact_force_n: jax.Array
    max_contact_force_n: jax.Array
    residual_vibration_mm: jax.Array


def _cycle(grid: CycleGrid, train: _Train, rpm, q_start=None, periodic=True) -> Cycle:
    """The response over one cycle at ``rpm`` (jittable, vmappable in ``rpm``)."""
    period = 60.0 / rpm
    w = train.omega * period
    lam = eigenvalue(w, train.zeta)
    wd = jnp.imag(lam)
    beta = train.ks / train.m * period**2
    forcing = jnp.asarray(grid.acceleration) + beta * jnp.asarray(grid.lift)
    motion = grid.motion_grid(forcing)
    nodes = jnp.asarray(grid.nodes)
    q = propagate(motion, w, train.zeta)
    if periodic:
        q_start = q[-1] / (1.0 - jnp.exp(lam))
    if q_start is not None:
        q = q + q_start * jnp.exp(lam * nodes)
    # Gains: Re(G q) for the payload acceleration (s-time, less beta y) and the spring-train force.
    accel_gain = 2 * train.zeta * w - 1j * w**2 * (1 - 2 * train.zeta**2) / wd
    e_gain, e_rate_gain = -1j / wd, 1.0 - 1j * jnp.real(lam) / wd
    force_gain = 1e-3 * train.k * e_gain + 1e-3 * train.c / period * e_rate_gain  # N per mm
    y = jnp.asarray(grid.lift_nodes)
    left, right = motion.one_sided()
    lift_left, lift_right = grid.motion_grid(jnp.asarray(grid.acceleration)).one_sided()
    widths = motion.widths
    ys = jnp.asarray(grid.velocity_nodes)

    def lift_terms(ys_end, one_sided):
        return jnp.stack([ys_end, one_sided[:, 0], one_sided[:, 1]], axis=1)

    to_si = 1e-3 / period**2
    accel = (jnp.real(accel_gain * q) - beta * y) * to_si
    accel_left = (_derivatives(accel_gain, lam, q[:-1], left) - beta * lift_terms(ys[:-1], lift_left)) * to_si
    accel_right = (_derivatives(accel_gain, lam, q[1:], right) - beta * lift_terms(ys[1:], lift_right)) * to_si
    max_accel = refined_peak(accel, widths, accel_left, accel_right)
    force = train.preload + jnp.real(force_gain * q)
    f_left = _derivatives(force_gain, lam, q[:-1], left)
    f_right = _derivatives(force_gain, lam, q[1:], right)
    max_force = _signed_max(force, widths, f_left, f_right)
    min_force = -_signed_max(-force, widths, -f_left, -f_right)
    # Residual vibration in each dwell: distance of the mode from the dwell's static point.
    starts = jnp.asarray(grid.dwell_start)
    q_static = -beta * y[starts] / lam
    residual = jnp.abs(q[starts] - q_static) / wd
    return Cycle(q, accel, force, max_accel, min_force, max_force, residual)


class Solver:
    """A program's compiled steady-state response over a speed range.

    Build once per program and slowest speed (which fixes the grid); every call over any
    batch of speeds is one compiled call, vmapped over chunks of speeds whose grids hold
    about ``_CHUNK_NODES`` nodes in all (a chunk's width is padded to a multiple of 16, so
    that few shapes compile).  The speeds are split over ``devices`` (default: every local
    device; see ``camjax.sharding.shard_batch``), with results equal to one device's.
    """

    def __init__(self, program: Program, rpm_min: float, *, devices=None):
        if not program.follower.damping_ratio > 0:
            raise ValueError("the periodic steady state needs follower.damping_ratio > 0 "
                             "(without damping the start-up never settles)")
        self.program = program
        self.train = _Train.of(program)
        self.rpm_min = float(rpm_min)
        self.devices = resolve_devices(devices)
        self.grid = cycle_grid(program, resolution(program, rpm_min))
        # Chunks of speeds small enough to keep the working set bounded (as batch_metrics).
        self.chunk = max(1, _CHUNK_NODES // self.grid.nodes.size)
        self._batch = jax.jit(lambda rpm: jax.lax.map(jax.vmap(self._summary), rpm))
        self._one = jax.jit(lambda rpm: _cycle(self.grid, self.train, rpm))

    def _summary(self, rpm):
        c = _cycle(self.grid, self.train, rpm)
        return c.max_payload_acceleration_m_s2, c.min_contact_force_n, c.max_contact_force_n, c.residual_vibration_mm

    def summary(self, rpm) -> dict[str, np.ndarray]:
        """Refined extrema and residual vibration at every speed in ``rpm``."""
        rpm = check_rpm(rpm)
        if rpm.min() < self.rpm_min * (1 - 1e-12):
            raise ValueError(f"rpm {rpm.min():g} below the solver's slowest speed {self.rpm_min:g}")
        size = rpm.size
        # A device per 16 speeds at most: a short batch (a bisection step) stays on one.
        devices = self.devices[: max(1, min(len(self.devices), size // 16))]
        per_device = -(-size // len(devices))
        chunks = -(-per_device // self.chunk)  # per device
        width = 16 * -(-per_device // (16 * chunks))
        rows = len(devices) * chunks
        padded = np.pad(rpm, (0, rows * width - size), mode="edge").reshape(rows, width)
        out = shard_batch(self._batch, jnp.asarray(padded), devices=devices)
        accel, fmin, fmax, residual = (np.asarray(x).reshape(rows * width, *x.shape[2:])[:size]
                                       for x in out)
        if not np.all(np.isfinite(fmin)) or not np.all(np.isfinite(accel)):
            raise ValueError("non-finite response: check the follower's numbers")
        return {"rpm": rpm, "max_payload_acceleration_m_s2": accel, "min_contact_force_n": fmin,
                "max_contact_force_n": fmax, "residual_vibration_mm": residual}

    def cycle(self, rpm: float) -> Cycle:
        """Node series and extrema of the periodic steady state at one speed."""
        rpm = float(check_rpm(rpm)[0])
        return jax.tree.map(np.asarray, self._one(rpm))

    def lam(self, rpm: float) -> complex:
        """Eigenvalue of the train in cycle time (``lambda T``) at ``rpm``."""
        return complex(eigenvalue(self.train.omega * 60.0 / rpm, self.train.zeta))

    def mode_at(self, q_nodes, rpm: float, s) -> np.ndarray:
        """The complex mode at cycle times ``s`` (anywhere, exactly) from its node values."""
        s = np.mod(np.atleast_1d(np.asarray(s, dtype=float)), 1.0)
        g = self.grid
        k = np.clip(np.searchsorted(g.nodes, s, side="right") - 1, 0, g.piece.size - 1)
        period = 60.0 / rpm
        lam = self.lam(rpm)
        beta = self.train.ks / self.train.m * period**2
        coeff = g.acceleration[k] + beta * g.lift[k]
        delta = s - g.nodes[k]
        h = g.piece_width[g.piece[k]]
        weights = np.asarray(psi(jnp.asarray(lam * delta)))
        kick = delta * np.sum(coeff * (delta / h)[:, None] ** np.arange(_DEGREE + 1) * weights, axis=1)
        return np.exp(lam * delta) * np.asarray(q_nodes)[k] + kick


def check_rpm(rpm) -> np.ndarray:
    rpm = np.atleast_1d(np.asarray(rpm, dtype=float))
    if rpm.size == 0 or rpm.ndim != 1:
        raise ValueError("rpm must be one speed or a 1-D list of speeds")
    if not np.all(np.isfinite(rpm)) or np.any(rpm <= 0):
        raise ValueError(f"rpm must be positive and finite, got {rpm[~(np.isfinite(rpm) & (rpm > 0))][0]:g}")
    return rpm


def startup(program: Program, rpm: float, cycles: int, *, solver: Solver | None = None):
    """Start-up from rest on the base circle: ``(s, payload acceleration m/s^2, contact force N)``.

    ``s`` runs over ``cycles`` turns (grid nodes of each, the last node left to the next
    turn); the exact cycle map carries the state from turn to turn.
    """
    rpm = float(check_rpm(rpm)[0])
    grid = solver.grid if solver is not None else cycle_grid(program, resolution(program, rpm))
    train = _Train.of(program)
    run_cycle = jax.jit(lambda q0: _cycle(grid, train, rpm, q_start=q0, periodic=False))
    s, accel, force = [], [], []
    q_start = jnp.zeros((), complex)
    for c in range(int(cycles)):
        run = run_cycle(q_start)
        s.append(c + grid.nodes[:-1])
        accel.append(np.asarray(run.payload_acceleration_m_s2[:-1]))
        force.append(np.asarray(run.contact_force_n[:-1]))
        q_start = run.q[-1]
    return np.concatenate(s), np.concatenate(accel), np.concatenate(force)
