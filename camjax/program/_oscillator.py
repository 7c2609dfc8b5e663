"""The follower's linear dynamics as one modal oscillator, in physical units: the classic
one-body follower and a chain of bodies alike.

Every follower the program drives is a linear system forced by the cam's lift ``y`` (mm).
Diagonalised, it is ``S`` complex modes (physical time, seconds)

    q_j' = lam_j q_j + b_j y + a_j y''        (a_j, b_j real),

and every output is ``o = Re(sum_j g_j q_j) + d0 y + d1 y' + d2 y'' + static``.  A mode's
forcing is a real combination of ``y`` and ``y''``: a complex factor of it is folded into
the gains, so each mode runs through the SDOF engine's propagation with a real forcing
(``camjax.sdof.periodic_propagate``).  Of a complex-conjugate pair one mode is kept and its
gains doubled (``Re(g q) + Re(conj(g q)) = 2 Re(g q)``).

- The classic follower (``Oscillator.of_follower``): one mode, the deflection's
  ``q = e' - conj(lam) e`` with ``q' = lam q + y'' + (k_s/m) y`` (``e = y - x``).
- A chain (``Oscillator.of_chain``): the chain's state space diagonalised in NumPy, its
  modes forced by ``y`` alone (the element's ``y'`` folded into each mode's start).

The rows of ``gain``, ``direct`` and ``static`` are the outputs ``OUTPUT_ROWS`` names: the
contact force at the cam, the payload's (the last body's) acceleration and displacement,
then, for a train (``train=True``), each body's acceleration, the spring's force at its
seat, its surge and the last body's distance from its kinematic lift.  ``state`` and
``modes`` convert between the modes and the physical state of the free coordinates (the
classic's: the deflection ``e`` and ``e'``), the one conversion every user reads.
``motion_gain`` and ``motion_direct`` are each body's displacement and velocity as rows of
the same form, read on the host over a turn (``camjax.program.response``), outside the
compiled turn's outputs (whose cost grows with their number).

A pytree of arrays: the compiled turn takes it as an argument, so another follower of the
same shape (the number of modes and of outputs) compiles nothing.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ._follower import Follower
from ._train import Chain

CONTACT_FORCE = 0  # N, at the cam
PAYLOAD_ACCELERATION = 1  # m/s^2, the last body's
PAYLOAD_DISPLACEMENT = 2  # mm, the last body's, from its static position
TRAIN_ROWS = 3  # a train's rows start here: each body's acceleration, seat force, surge, lift error
UNDAMPED_RATIO = 1e-12
"""A chain's mode whose damping ratio (``-Re(lambda) / |lambda|``) is not above this is
undamped: an undamped arm's modes come out of the eigensolver with ratios of about 1e-24
either side of zero, round-off that would otherwise pass for damping."""


def output_rows(bodies: int) -> dict[str, int | slice]:
    """Where each output sits in an ``Oscillator``'s rows built with ``train=True`` for a
    chain of ``bodies``."""
    return {
        "contact_force_n": CONTACT_FORCE,
        "payload_acceleration_m_s2": PAYLOAD_ACCELERATION,
        "payload_displacement_mm": PAYLOAD_DISPLACEMENT,
        "acceleration_m_s2": slice(TRAIN_ROWS, TRAIN_ROWS + bodies),
        "seat_force_n": TRAIN_ROWS + bodies,
        "surge_n": TRAIN_ROWS + bodies + 1,
        "lift_error_mm": TRAIN_ROWS + bodies + 2,
    }


class Oscillator(NamedTuple):
    """The follower's modes and outputs in physical units (seconds, lift in mm, outputs
    in N, m/s^2 and mm): see the module.

    Attributes:
        lam: ``(S,)`` complex eigenvalues (1/s), ``Re lam < 0``.
        forcing: ``(S, 2)`` real: each mode's weights of ``y`` and of ``y''``.
        gain: ``(O, S)`` complex: each output's gain of each mode.
        direct: ``(O, 3)`` real: each output's terms in ``y``, ``y'``, ``y''``.
        static: ``(O,)``: each output's value at rest (the preloads).
        state_gain: ``(2 N, S)`` complex: the free coordinates' displacements (mm) and
            velocities (mm/s) of a free vibration of the modes (``state``).
        state_inverse: ``(2 S, 2 N)`` real: the modes' real and imaginary parts of a
            free vibration's state (``modes``).
        motion_gain: ``(2 B, S)`` complex: each body's displacement (mm, from rest), then
            each body's velocity (m/s), as a row of ``gain`` (``B`` bodies, the classic's 1).
        motion_direct: ``(2 B, 3)`` real: those rows' terms in ``y``, ``y'``, ``y''`` (their
            static terms are zero).
    """

    lam: np.ndarray
    forcing: np.ndarray
    gain: np.ndarray
    direct: np.ndarray
    static: np.ndarray
    state_gain: np.ndarray
    state_inverse: np.ndarray
    motion_gain: np.ndarray
    motion_direct: np.ndarray

    @property
    def modes_count(self) -> int:
        return int(np.shape(self.lam)[0])

    @property
    def bodies(self) -> int:
        """Bodies whose accelerations the rows hold (0 without the train's rows)."""
        outputs = int(np.shape(self.gain)[0])
        return 0 if outputs == TRAIN_ROWS else outputs - TRAIN_ROWS - 3

    def state(self, q):
        """The free coordinates' displacements (mm) and velocities (mm/s), ``(2 N, ...)``,
        of the free vibration of the modes ``q`` (``(S, ...)``, physical time): the
        steady state's own where its lift terms vanish (the classic's deflection ``e``
        and ``e'`` in full)."""
        q = np.asarray(q)
        g = np.asarray(self.state_gain)
        return np.real(np.tensordot(g, q, axes=(1, 0)))

    def modes(self, state):
        """The modes ``(S, ...)`` of a free vibration whose state (``state``'s rows) is
        ``state``: the inverse of ``state``."""
        parts = np.tensordot(
            np.asarray(self.state_inverse), np.asarray(state, dtype=float), axes=(1, 0)
        )
        s = self.modes_count
        return parts[:s] + 1j * parts[s:]

    @classmethod
    def of(cls, program) -> Oscillator:
        """The oscillator of a program's follower: the classic's (``of_follower``) where its
        one-body dynamics are the program's (``Program.one_body``), with a train's rows
        where it is spelled as one; else its chain's (``of_chain``)."""
        if program.one_body:
            return cls.of_follower(program.follower, train=program.chain is not None)
        return cls.of_chain(program.chain)

    @classmethod
    def of_follower(cls, follower: Follower, *, train: bool = False) -> Oscillator:
        """The classic follower: ``m x'' = k (y - x) + c (y' - x') - k_s x``, one mode
        ``q = e' - conj(lam) e`` of the deflection ``e = y - x`` (mm) with
        ``q' = lam q + y'' + (k_s/m) y``; ``train``: with a one-body train's rows."""
        m, k, c, ks = (
            float(v)
            for v in (follower.mass_kg, follower.stiffness, follower.damping, follower.spring_rate)
        )
        preload = 0.0 if follower.form_closed else float(follower.preload_n)
        omega = 2 * math.pi * follower.natural_frequency_hz
        zeta = c / (2 * m * omega)
        lam = -zeta * omega + 1j * omega * math.sqrt(1.0 - zeta**2)
        e_gain, e_rate_gain = -1j / lam.imag, 1.0 - 1j * lam.real / lam.imag  # e = Re(G_e q)
        damped = omega * math.sqrt(1.0 - zeta**2)
        accel_gain = 2 * zeta * omega - 1j * omega**2 * (1 - 2 * zeta**2) / damped  # mm/s^2
        rows = [
            (1e-3 * k * e_gain + 1e-3 * c * e_rate_gain, (0.0, 0.0, 0.0), preload),
            (1e-3 * accel_gain, (-1e-3 * ks / m, 0.0, 0.0), 0.0),
            (-e_gain, (1.0, 0.0, 0.0), 0.0),
        ]
        if train:  # one body: its acceleration, the massless spring's force, no surge
            rows += [
                rows[PAYLOAD_ACCELERATION],
                (-1e-3 * ks * e_gain, (1e-3 * ks, 0.0, 0.0), preload),
                (0j, (0.0, 0.0, 0.0), 0.0),
                (-e_gain, (0.0, 0.0, 0.0), 0.0),
            ]
        state_gain = np.array([[e_gain], [e_rate_gain]])
        motion, motion_direct, _ = _rows(
            [
                (-e_gain, (1.0, 0.0, 0.0), 0.0),  # x = y - e (mm)
                (-1e-3 * e_rate_gain, (0.0, 1e-3, 0.0), 0.0),
            ]
        )  # x' (m/s)
        return cls(
            np.array([lam]),
            np.array([[ks / m, 1.0]]),
            *_rows(rows),
            state_gain,
            _state_inverse(state_gain),
            motion_gain=motion,
            motion_direct=motion_direct,
        )

    @classmethod
    def of_chain(cls, chain: Chain) -> Oscillator:
        """A chain's state space (``Chain.matrices``, the cam's coordinate held to ``y``)
        diagonalised: ``z' = A z + b0 y + b1 y'`` over the free coordinates' positions and
        velocities (shifted by ``G y`` so that ``y''`` drops out), whose modes
        ``xi = V^-1 z - V^-1 b1 y`` obey ``xi' = lam xi + (u + lam v) y``.  Lash and a seat
        are refused (the steady state is of the closed chain)."""
        for j, body in enumerate(chain.bodies, start=1):
            if body.lash_mm:
                raise ValueError(
                    f"[[train]] body {j} ({body.name}) lash_mm: the exact steady state is of the "
                    "closed chain; a chain with lash is simulated (ChainContacts)"
                )
        if chain.seat is not None:
            raise ValueError(
                "[seat]: the exact steady state is of the closed chain; a chain with a seat is "
                "simulated (ChainContacts)"
            )
        a = chain.matrices()
        free = np.arange(1, a.seat)
        n = free.size  # at least one: a chain with nothing to vibrate is refused (Chain)
        Mff, Cff, Kff = (x[np.ix_(free, free)] for x in (a.M, a.C, a.K))
        Minv = np.linalg.inv(Mff)
        G, b1_rate = _lift_shift(a)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Kff, -Minv @ Cff]])
        b0 = np.concatenate([np.zeros(n), Minv @ (Kff @ G - a.K[free, 0])])
        b1 = np.concatenate([np.zeros(n), b1_rate])
        lam, V = np.linalg.eig(A)
        if not np.all(-lam.real > UNDAMPED_RATIO * np.abs(lam)):  # round-off is not damping
            if chain.arm is not None and not chain.arm.damping_ratio:  # the arm's modes: its own
                raise ValueError(
                    "[arm] damping_ratio: the arm's modes have no damping (give the first mode's "
                    "ratio, e.g. 0.01): its periodic steady state does not exist"
                )
            undamped = [
                f"[[train]] {b.name} damping_n_s_per_m"
                for b in chain.bodies
                if not b.rides and not b.damping_n_s_per_m
            ]
            if chain.spring is not None and chain.spring.surges and not chain.spring.damping_ratio:
                undamped.append("[spring] damping_ratio")
            give = (
                " or ".join(undamped) or "the elements damping_n_s_per_m or [spring] damping_ratio"
            )
            raise ValueError(
                f"the chain has a mode without damping (give {give}): its periodic steady state "
                "does not exist"
            )
        if np.linalg.cond(V) > 1e10:
            raise ValueError(
                "the chain's modes are not independent (a critically damped mode): change "
                "a damping a little"
            )
        Vinv = np.linalg.inv(V)
        u, v = Vinv @ b0, Vinv @ b1
        rows, motion = [], []

        def output(aK, aC, aM, static=0.0, scale=1.0, into=rows):
            """An output ``aK x + aC x' + aM x''`` over the coordinates (SI, lift in m),
            as ``(gain of xi, direct terms, static)`` per mm of lift, times ``scale``,
            appended to ``into``."""
            c_z = np.concatenate([aK[free], aC[free]]) + aM[free] @ A[n:, :]
            e0 = aK[0] - aK[free] @ G + aM[free] @ b0[n:]
            e1 = aC[0] - aC[free] @ G + aM[free] @ b1[n:]
            e2 = aM[0] - aM[free] @ G
            g = c_z @ V
            direct = np.array([e0 + float(np.real(g @ v)), e1, e2])
            into.append((scale * g, 1e-3 * scale * direct, static))

        zero = np.zeros(a.seat + 1)

        def unit(i):
            e = zero.copy()
            e[i] = 1.0
            return e

        last = a.body_index[-1]
        output(a.K[0], a.C[0], a.M[0], chain.cam_preload_n)  # contact force at the cam
        output(zero, zero, unit(last))  # the payload's acceleration
        output(unit(last), zero, zero, scale=1e3)  # its displacement (mm)
        for i in a.body_index:  # each body's acceleration
            output(zero, zero, unit(i))
        preload = chain.spring.preload_n if chain.spring is not None else 0.0
        output(-a.K[a.seat], -a.C[a.seat], -a.M[a.seat], preload)  # the spring's force at its seat
        rate = 1e3 * chain.spring.rate_n_per_mm if chain.spring is not None else 0.0
        output(-a.K[a.seat] - rate * unit(last), -a.C[a.seat], -a.M[a.seat])  # surge
        output(unit(last), zero, zero, scale=1e3)  # the lift error: less the kinematic lift, below
        rows[-1] = (rows[-1][0], rows[-1][1] - np.array([chain.lever_ratio, 0.0, 0.0]), 0.0)
        for i in a.body_index:  # each body's displacement (mm), then its velocity (m/s)
            output(unit(i), zero, zero, scale=1e3, into=motion)
        for i in a.body_index:
            output(zero, unit(i), zero, into=motion)
        # A real system's modes come in conjugate pairs (LAPACK returns them exactly
        # conjugate): keep one of each pair, doubled, and every real (overdamped) mode once.
        keep = lam.imag >= 0
        weight = np.where(lam.imag[keep] > 0, 2.0, 1.0)
        # xi_j = f_j q_j with q_j' = lam_j q_j + y (mm): f_j, per m of lift, folded into the gains
        scale = 1e-3 * (u + lam * v)[keep] * weight
        gain, direct, static = _rows(rows)
        motion_gain, motion_direct, _ = _rows(motion)
        state_gain = (
            1e3 * V[:, keep] * scale
        )  # mm and mm/s of the free coordinates (shifted by G y)
        return cls(
            lam[keep],
            np.stack([np.ones(keep.sum()), np.zeros(keep.sum())], axis=1),
            gain[:, keep] * scale,
            direct,
            static,
            state_gain,
            _state_inverse(state_gain),
            motion_gain=motion_gain[:, keep] * scale,
            motion_direct=motion_direct,
        )


def _lift_shift(a) -> tuple[np.ndarray, np.ndarray]:
    """``(G, b1)`` of a chain's assembly ``a`` (``Chain.matrices``) with the cam's coordinate
    held: its state ``z = (x + G y, x' + G y')`` over the free coordinates, ``G =
    M_ff^-1 M_f0`` (so that ``y''`` drops out), and the weight ``b1 = M_ff^-1 (C_ff G - C_f0)``
    of ``y'`` in ``z_v'`` (its modes are ``V^-1 (z - b1 y)``, ``Oscillator.of_chain``)."""
    free = np.arange(1, a.seat)
    Mff, Cff = a.M[np.ix_(free, free)], a.C[np.ix_(free, free)]
    G = np.linalg.solve(Mff, a.M[free, 0])
    return G, np.linalg.solve(Mff, Cff @ G - a.C[free, 0])


def chain_coordinates(chain, state, y_mm, y_rate_mm_s) -> tuple[np.ndarray, np.ndarray]:
    """The free coordinates' displacements (mm) and velocities (mm/s) of the closed chain
    (``Chain.matrices``, from its rest) whose modes have the state ``state`` (``(2 N, ...)``,
    ``Oscillator.state``) at a lift ``y_mm`` rising at ``y_rate_mm_s``: ``x = z_x - G y``,
    ``x' = z_v + b1 y - G y'`` (``_lift_shift``)."""
    G, b1 = _lift_shift(chain.matrices())
    n = G.size
    state = np.asarray(state, dtype=float)
    G, b1 = G.reshape((n,) + (1,) * (state.ndim - 1)), b1.reshape((n,) + (1,) * (state.ndim - 1))
    return state[:n] - G * y_mm, state[n:] + b1 * y_mm - G * y_rate_mm_s


def _rows(rows):
    gain = np.array([np.atleast_1d(np.asarray(r[0], dtype=complex)) for r in rows])
    direct = np.array([np.asarray(r[1], dtype=float) for r in rows])
    static = np.array([float(r[2]) for r in rows])
    return gain, direct, static


def _state_inverse(state_gain: np.ndarray) -> np.ndarray:
    """``(2 S, 2 N)``: the least-squares inverse of ``state = Re(state_gain q)`` over the
    modes' real and imaginary parts (exact where every mode oscillates)."""
    real = np.concatenate([state_gain.real, -state_gain.imag], axis=1)
    return np.linalg.pinv(real)
