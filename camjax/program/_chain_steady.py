"""The exact periodic steady state of a chain of bodies over a program's turn.

``ChainModes`` is the chain's state-space system (``camjax.program.Chain``) diagonalised
once in NumPy (edits of values compile nothing), and ``chain_cycle`` its exact periodic
steady state over the turn: one complex mode per eigenvalue through the SDOF engine's
propagation (``camjax.sdof.periodic_propagate``), the one-body follower its first case.
``ChainSteadyState`` runs it over speeds, ``train_section`` is the report's ``train``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..metrics import PEAK_TOLERANCE, bernstein_bound, hermite_data, peak_search
from ..sdof import periodic_propagate
from ._dynamics import SPEED_BLOCK, PaddedTurn, cycle_grid
from ._machine import NodeContact
from ._speeds import Speeds
from ._train import Chain


class ChainModes(NamedTuple):
    """The chain's state-space system diagonalised (physical time, SI, lift in m): each
    output ``o = Re(sum_j g_j xi_j) + e0 y + e1 y' + e2 y'' + static`` where the modes obey
    ``xi_j' = lam_j xi_j + f_j y``.  Rows of ``gain``/``direct``/``static`` are the outputs
    in ``OUTPUTS`` order (the bodies' accelerations one row each).  A pytree of arrays: the
    compiled turn takes it as an argument, so an edit of values compiles nothing."""

    lam: np.ndarray  # (S,) complex, 1/s: one of each conjugate pair (S = the degrees of freedom
    # where every mode oscillates; one more per two overdamped ones)
    forcing: np.ndarray  # (S,) complex: f_j
    gain: np.ndarray  # (O, S) complex
    direct: np.ndarray  # (O, 3) real: e0, e1, e2
    static: np.ndarray  # (O,)

    @classmethod
    def of(cls, chain: Chain) -> ChainModes:
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
        n = free.size
        if n == 0:
            raise ValueError(
                "[[train]]: one body riding on the cam on a spring without mass has nothing to "
                "vibrate (its contact force is m y'' + k_s y + preload): give it an element "
                "(stiffness_n_per_mm) or use the classic follower"
            )
        Mff, Cff, Kff = (x[np.ix_(free, free)] for x in (a.M, a.C, a.K))
        G = np.linalg.solve(Mff, a.M[free, 0])
        Minv = np.linalg.inv(Mff)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Kff, -Minv @ Cff]])
        b0 = np.concatenate([np.zeros(n), Minv @ (Kff @ G - a.K[free, 0])])
        b1 = np.concatenate([np.zeros(n), Minv @ (Cff @ G - a.C[free, 0])])
        lam, V = np.linalg.eig(A)
        if not np.all(lam.real < 0):
            raise ValueError(
                "the chain has a mode without damping (give the elements damping_n_s_per_m "
                "or the spring damping_ratio): its periodic steady state does not exist"
            )
        if np.linalg.cond(V) > 1e10:
            raise ValueError(
                "the chain's modes are not independent (a critically damped mode): change "
                "a damping a little"
            )
        Vinv = np.linalg.inv(V)
        u, v = Vinv @ b0, Vinv @ b1
        rows, statics = [], []

        def output(aK, aC, aM, static=0.0):
            c_z = np.concatenate([aK[free], aC[free]]) + aM[free] @ A[n:, :]
            e0 = aK[0] - aK[free] @ G + aM[free] @ b0[n:]
            e1 = aC[0] - aC[free] @ G + aM[free] @ b1[n:]
            e2 = aM[0] - aM[free] @ G
            g = c_z @ V
            rows.append((g, [e0 + float(np.real(g @ v)), e1, e2]))
            statics.append(static)

        zero = np.zeros(a.seat + 1)

        def unit(i):
            e = zero.copy()
            e[i] = 1.0
            return e

        output(a.K[0], a.C[0], a.M[0], chain.cam_preload_n)  # contact force at the cam
        for i in a.body_index:  # each body's acceleration
            output(zero, zero, unit(i))
        output(unit(a.body_index[-1]), zero, zero)  # the last body's displacement (m)
        preload = chain.spring.preload_n if chain.spring is not None else 0.0
        output(-a.K[a.seat], -a.C[a.seat], -a.M[a.seat], preload)  # the spring's force at its seat
        rate = 1e3 * chain.spring.rate_n_per_mm if chain.spring is not None else 0.0
        output(-a.K[a.seat] - rate * unit(a.body_index[-1]), -a.C[a.seat], -a.M[a.seat])  # surge
        # A real system's modes come in conjugate pairs (LAPACK returns them exactly
        # conjugate), whose two terms sum to twice the real part of one: keep one of each
        # pair, doubled, and every real (overdamped) mode once.
        keep = lam.imag >= 0
        weight = np.where(lam.imag[keep] > 0, 2.0, 1.0)
        gain = np.array([r[0] for r in rows])[:, keep] * weight
        return cls(
            lam[keep],
            (u + lam * v)[keep],
            gain,
            np.array([r[1] for r in rows]),
            np.asarray(statics, dtype=float),
        )


def output_rows(bodies: int) -> dict[str, int | slice]:
    """Where each output sits in ``ChainModes``' rows for a chain of ``bodies``."""
    return {
        "contact_force_n": 0,
        "acceleration_m_s2": slice(1, 1 + bodies),
        "lift_m": 1 + bodies,
        "seat_force_n": 2 + bodies,
        "surge_n": 3 + bodies,
    }


def lift_jets(coefficients, widths):
    """``y`` and its first five derivatives in turn time at the left and right end of every
    interval, ``((K, 6), (K, 6))``, from its monomial coefficients in the local ``sigma``."""
    h = jnp.where(widths > 0, widths, 1.0)[:, None]
    powers = np.arange(6)
    falling = np.array(
        [[math.perm(int(m), d) for m in powers] for d in range(6)], dtype=float
    )  # (d, m)
    scale = h ** -powers[None, :]
    left = coefficients * falling.diagonal()[None, :] * scale
    right = (coefficients @ falling.T) * scale
    return left, right


class ChainCycle(NamedTuple):
    """One turn of the chain's periodic steady state at one speed: outputs at the nodes
    (rows as ``output_rows``); the refined least and largest contact force and seat force
    (``SIGNED_ROWS`` of ``low`` and ``high``), and the refined peak ``|f|`` of each
    body's acceleration and of the surge (``PEAK_ROWS`` of ``peak``)."""

    values: jax.Array
    low: jax.Array
    high: jax.Array
    peak: jax.Array


def signed_rows(bodies: int) -> list[int]:
    rows = output_rows(bodies)
    return [rows["contact_force_n"], rows["seat_force_n"]]


def peak_rows(bodies: int) -> list[int]:
    rows = output_rows(bodies)
    return [
        *range(rows["acceleration_m_s2"].start, rows["acceleration_m_s2"].stop),
        rows["surge_n"],
    ]


def chain_cycle(motion, lift, modes: ChainModes, rpm) -> ChainCycle:
    """The exact periodic steady state over one turn at ``rpm`` (jittable, vmappable in
    ``rpm``): ``motion`` is the turn's engine grid (``CycleGrid.motion``), ``lift`` its
    ``(K, 6)`` lift coefficients in mm.  One engine propagation per eigenvalue."""
    period = 60.0 / rpm
    lam = period * jnp.asarray(modes.lam)
    f = period * jnp.asarray(modes.forcing)
    lift = 1e-3 * jnp.asarray(lift)
    grid = motion._replace(forcing=lift)
    q = jax.vmap(lambda l: periodic_propagate(grid, None, None, lam=l))(lam)  # (S, K + 1)
    xi = f[:, None] * q
    gain = jnp.asarray(modes.gain)
    e0, e1, e2 = (jnp.asarray(modes.direct)[:, i] for i in range(3))
    direct = jnp.stack([e0, e1 / period, e2 / period**2], axis=1)  # per y, y_s, y_ss
    widths = grid.widths
    y_left, y_right = lift_jets(lift, widths)
    y_nodes = jnp.concatenate([y_left[:, :3], y_right[-1:, :3]])
    xr, xq = jnp.real(xi), jnp.imag(xi)

    def real_part(g, re, im):  # Re(g @ x) in real products (XLA's complex ones are slow on CPU)
        return jnp.real(g) @ re - jnp.imag(g) @ im

    values = real_part(gain, xr, xq) + direct @ y_nodes.T + jnp.asarray(modes.static)[:, None]

    def jets(ends, y_end):
        """``(O, K, 3)``: the outputs' first three derivatives at one end of each interval."""
        out = []
        for p in (1, 2, 3):
            d = real_part(gain * lam**p, xr[:, ends], xq[:, ends])
            for i in range(p):
                d = d + jnp.real(gain @ (lam ** (p - 1 - i) * f))[:, None] * y_end[None, :, i]
            d = d + direct @ y_end[:, p : p + 3].T
            out.append(d)
        return jnp.stack(out, axis=-1)

    left, right = jets(slice(None, -1), y_left), jets(slice(1, None), y_right)
    bodies = values.shape[0] - 4
    signed, peaks = np.asarray(signed_rows(bodies)), np.asarray(peak_rows(bodies))
    high = jax.vmap(_bounded_max, in_axes=(0, None, 0, 0))(
        values[signed], widths, left[signed], right[signed]
    )
    low = -jax.vmap(_bounded_max, in_axes=(0, None, 0, 0))(
        -values[signed], widths, -left[signed], -right[signed]
    )
    peak = jax.vmap(_bounded_peak, in_axes=(0, None, 0, 0))(
        values[peaks], widths, left[peaks], right[peaks]
    )
    return ChainCycle(values, low, high, peak)


def _bounded_peak(values, widths, left, right):
    """``max |f|`` between the nodes, refining only the intervals whose Bernstein bound can
    beat the best found (``camjax.metrics.peak_search``)."""
    bound = bernstein_bound(values, widths, tuple(left.T), tuple(right.T))
    data = hermite_data(values, widths, left, right)
    return peak_search(bound, lambda index: data[index], jnp.max(jnp.abs(values)), PEAK_TOLERANCE)


def _bounded_max(values, widths, left, right):
    """``max f`` (signed) between the nodes, refining only the intervals whose Bernstein
    bound can beat the best found (``camjax.metrics.peak_search``): the dense refinement of
    every output over every interval cost a chain ten times its propagation."""
    low = jnp.min(values)
    shift = low - (jnp.max(values) - low) - 1.0
    return _bounded_peak(values - shift, widths, left, right) + shift


@jax.jit
def _chain_cycles(rpm, motion, lift, modes: ChainModes) -> ChainCycle:
    """``chain_cycle`` at every speed of a block: one compiled program per shape (the
    chain's number of states and the padded grid), whatever the values."""
    return jax.vmap(lambda r: chain_cycle(motion, lift, modes, r))(rpm)


class ChainSummary(NamedTuple):
    """The chain's periodic steady state at every speed (``ChainSteadyState.summary``)."""

    rpm: np.ndarray
    min_contact_force_n: np.ndarray
    max_contact_force_n: np.ndarray
    max_acceleration_m_s2: np.ndarray  # (speeds, bodies): each body's peak |x''|
    max_lift_error_mm: np.ndarray  # the last body's largest distance from its kinematic lift
    min_seat_force_n: np.ndarray
    max_seat_force_n: np.ndarray
    max_surge_n: np.ndarray  # the seat force's largest distance from the spring's static force


class ChainSteadyState:
    """A program driving a chain, its exact periodic steady state at any speeds from
    ``rpm_min`` up: the grid resolves the chain's highest mode with the cam held at
    ``rpm_min``; the speeds run in blocks of ``SPEED_BLOCK`` through one compiled program
    per shape (number of states, bucketed grid), so another chain of the same shape or an
    edited program compiles nothing."""

    def __init__(self, program, chain: Chain, rpm_min: float):

        self.program, self.chain = program, chain
        self.rpm_min = Speeds.of(rpm_min, "rpm_min").min()
        self.modes = ChainModes.of(chain)
        self.grid = cycle_grid(program, self.rpm_min, chain.highest_frequency_hz())
        zeros = np.zeros(self.grid.intervals + 1)
        padded = PaddedTurn.of(self.grid, None, NodeContact(zeros, zeros, zeros, zeros)).grid
        self._motion, self._lift = padded.motion, padded.lift
        self._rows = output_rows(len(chain.bodies))
        # the kinematic lift of the last body: the cam's through every lever
        self.kinematic_ratio = float(np.prod([b.ratio for b in chain.bodies if not b.rides]))

    def cycles(self, rpm) -> ChainCycle:
        """The whole turn at every speed, ``(speeds, outputs, nodes)`` (nodes of the turn's own
        grid, the padding cut)."""

        rpm = np.asarray(Speeds.of(rpm))
        if rpm.min() < self.rpm_min * (1 - 1e-12):
            raise ValueError(
                f"rpm {rpm.min():g} below the steady state's slowest speed {self.rpm_min:g}"
            )
        padded = np.pad(rpm, (0, -rpm.size % SPEED_BLOCK), mode="edge").reshape(-1, SPEED_BLOCK)
        outs = [
            _chain_cycles(jnp.asarray(block), self._motion, self._lift, self.modes)
            for block in padded
        ]
        out = jax.tree.map(lambda *x: np.concatenate([np.asarray(v) for v in x])[: rpm.size], *outs)
        out = out._replace(values=out.values[..., : self.grid.intervals + 1])
        if not np.all(np.isfinite(out.values)):
            raise ValueError("the chain's steady state is not finite")
        return out

    def summary(self, rpm) -> ChainSummary:
        """What a valve-train engineer reads per speed (``ChainSummary``)."""
        c = self.cycles(rpm)
        bodies = len(self.chain.bodies)
        error = (
            1e3 * c.values[:, self._rows["lift_m"]]
            - self.kinematic_ratio * np.asarray(self.grid.lift_nodes)[None, :]
        )
        return ChainSummary(
            np.asarray(rpm, dtype=float),
            c.low[:, 0],
            c.high[:, 0],
            c.peak[:, :bodies],
            np.max(np.abs(error), axis=1),
            c.low[:, 1],
            c.high[:, 1],
            c.peak[:, bodies],
        )

    def jump_speed(
        self, rpm_max: float, *, tolerance_rpm: float = 1e-4, scan: int = 128
    ) -> float | None:
        """The lowest speed in ``[rpm_min, rpm_max]`` where the cam's contact force first
        reaches zero (the chain leaves the cam), ``None`` where the contact holds over the
        whole range: a scan of ``scan`` speeds, each local minimum of the least force
        looked at closer twice (a chain's resonances make narrow dips), then bisection to
        ``tolerance_rpm``."""
        speeds = np.linspace(self.rpm_min, float(rpm_max), scan)
        low = self.summary(speeds).min_contact_force_n
        for _ in range(2):
            if np.any(low <= 0):
                break
            dips = [
                i
                for i in range(1, speeds.size - 1)
                if low[i] <= low[i - 1] and low[i] <= low[i + 1]
            ]
            if not dips:
                break
            closer = np.concatenate(
                [np.linspace(speeds[i - 1], speeds[i + 1], 34)[1:-1] for i in dips]
            )
            speeds = np.concatenate([speeds, closer])
            low = np.concatenate([low, self.summary(closer).min_contact_force_n])
            order = np.argsort(speeds)
            speeds, low = speeds[order], low[order]
        if low[0] <= 0:
            return self.rpm_min
        lost = np.nonzero(low <= 0)[0]
        if lost.size == 0:
            return None
        a, b = speeds[lost[0] - 1], speeds[lost[0]]
        while b - a > tolerance_rpm:
            inner = np.linspace(a, b, 34)[1:-1]  # one block of speeds per step
            force = self.summary(inner).min_contact_force_n
            k = np.nonzero(force <= 0)[0]
            a, b = (inner[k[0] - 1] if k[0] > 0 else a, inner[k[0]]) if k.size else (inner[-1], b)
        return 0.5 * (a + b)


CHAIN_NOTE = (
    "a train: the rows give the chain's contact force at the cam (min Fc, max Fc, the "
    "preload that keeps it, jump) and its last body's peak acceleration as the payload's; "
    "the one-body outputs (drive torque, Hertz stress, residual vibration, period ratios, "
    "flights) are not computed for a chain and left empty"
)
ONE_BODY_NOTE = "a one-body train: the classic follower's rows are this chain's (the same numbers)"


def train_section(program, chain: Chain, rpm: np.ndarray) -> tuple[dict, ChainSummary]:
    """The report's ``train`` section over the speeds ``rpm``: the natural frequencies held
    and free with their mode shapes, the harmonic check over the speed range, the chain's
    ``ChainSummary`` per speed and its jump speed (``None`` where the contact holds over
    the range, only one speed is given, or it is lost at the lowest already:
    ``jump_below_range``); with the summary itself for the report's rows."""
    rpm = np.asarray(rpm, dtype=float)
    contacts = None
    if chain.has_contacts:  # lash or a seat: not linear, simulated (_chain_contacts.py)
        from ._chain_contacts import simulated_train

        summary, contacts, jump, below = simulated_train(program, chain, rpm)
    else:
        steady = ChainSteadyState(program, chain, float(rpm.min()))
        summary = steady.summary(rpm)
        spring = chain.spring is not None  # without one the cam is form-closed: no jump
        jump, below = None, spring and bool(summary.min_contact_force_n[np.argmin(rpm)] <= 0)
        if spring and not below and rpm.size > 1 and rpm.max() > rpm.min():
            jump = steady.jump_speed(float(rpm.max()))
    frequencies = {}
    for key, contact in (("held", True), ("free", False)):
        hz, shapes = chain.natural_frequencies(contact=contact)
        frequencies[f"natural_frequencies_{key}_hz"] = hz.tolist()
        frequencies[f"mode_shapes_{key}"] = shapes.T.tolist()  # one row per mode, over the bodies
    speeds = [
        {
            "rpm": float(r),
            "min_contact_force_n": float(summary.min_contact_force_n[i]),
            "max_contact_force_n": float(summary.max_contact_force_n[i]),
            "max_acceleration_m_s2": dict(
                zip(chain.names, summary.max_acceleration_m_s2[i].tolist())
            ),
            "max_lift_error_mm": float(summary.max_lift_error_mm[i]),
            "min_seat_force_n": float(summary.min_seat_force_n[i]),
            "max_seat_force_n": float(summary.max_seat_force_n[i]),
            "max_surge_n": float(summary.max_surge_n[i]),
        }
        for i, r in enumerate(rpm)
    ]
    section = {
        "one_body": chain.spells_follower,
        "note": ONE_BODY_NOTE if chain.spells_follower else CHAIN_NOTE,
        "bodies": list(chain.names),
        **frequencies,
        "harmonic_check": [
            {"frequency_hz": f, "orders": orders}
            for f, orders in chain.harmonic_check(float(rpm.min()), float(rpm.max()))
        ],
        "speeds": speeds,
        "jump_speed_rpm": jump,
        "jump_below_range": below,
        **({} if contacts is None else {"contacts": contacts}),
    }
    return section, summary
