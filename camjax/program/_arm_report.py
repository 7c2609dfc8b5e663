"""The report of a program whose chain has a flexible arm: the last body's bending over the
turn, from the steady state's modes, and its cam-order harmonics (``arm_section``)."""

from __future__ import annotations

import math

import numpy as np

from ._oscillator import output_rows

HARMONIC_ORDERS = tuple(range(1, 10))
"""Cam orders whose amplitude of the arm's bending the report gives."""


def harmonic_amplitudes(turn_nodes, signal, orders=HARMONIC_ORDERS) -> np.ndarray:
    """Amplitudes of the cam orders ``orders`` of a periodic ``signal`` over one turn given
    at the nodes ``turn_nodes`` (turn fractions, 0 to 1, any spacing; ``(..., nodes)``): the
    Fourier integrals of its piecewise-linear interpolant, exactly (the one-sided amplitude
    ``2 |c_k|``, as an FFT spectrum's)."""
    s = np.asarray(turn_nodes, dtype=float)
    f = np.asarray(signal, dtype=float)
    h = np.diff(s)
    out = []
    for k in orders:
        w = 2 * math.pi * k
        # int over [s_i, s_i + h] of (f_i + (f_{i+1} - f_i) u / h) e^{-i w u} du, u from s_i
        z = -1j * w * h
        e = np.exp(z)
        small = np.abs(z) < 1e-3
        zs = np.where(small, 1.0, z)
        first = np.where(small, h * (1 + z / 2 + z * z / 6), h * (e - 1) / zs)  # int e^{zu/h}
        second = np.where(
            small, h * (0.5 + z / 3 + z * z / 8), h * (e * (zs - 1) + 1) / zs**2
        )  # int (u/h) e^{zu/h}
        phase = np.exp(-1j * w * s[:-1])
        c = np.sum(phase * (f[..., :-1] * first + (f[..., 1:] - f[..., :-1]) * second), axis=-1)
        out.append(2 * np.abs(c))
    return np.stack(out, axis=-1)


def arm_bending(steady, cycles, rpm) -> np.ndarray:
    """The last body's bending over the turn, ``(speeds, nodes)`` mm at ``steady.grid``'s
    nodes: its distance from its rigid swing (``at_mm / arm_mm`` times the lift), the
    oscillator's ``lift_error_mm`` row of the steady state ``steady`` (a ``SteadyState`` of a
    program whose chain has an arm) from its ``cycles`` (modes at the nodes) at ``rpm``."""
    grid, oscillator = steady.grid, steady.oscillator
    row = output_rows(len(steady.program.chain.bodies))["lift_error_mm"]
    left, right = grid.motion.one_sided(1)
    y = np.stack(
        [
            np.asarray(grid.lift_nodes),
            np.asarray(grid.velocity_nodes),
            np.concatenate([np.asarray(left)[:, 0], np.asarray(right)[-1:, 0]]),
        ]
    )  # y, y_s, y_ss at the nodes (turn time)
    gain, direct = np.asarray(oscillator.gain)[row], np.asarray(oscillator.direct)[row]
    bending = []
    for i, r in enumerate(np.asarray(rpm, dtype=float)):
        period = 60.0 / r
        terms = direct * np.array([1.0, 1.0 / period, 1.0 / period**2])
        modes = np.real((gain / period) @ np.asarray(cycles.q[i]))  # turn-time modes
        bending.append(modes + terms @ y + float(oscillator.static[row]))
    return np.asarray(bending)


def arm_section(steady, cycles, rpm) -> dict:
    """The report's ``arm`` part of a train's section (``arm_bending`` at the speeds
    ``rpm``): the last body's largest bending and the amplitudes of its cam orders
    ``HARMONIC_ORDERS``; the first bending frequency with the cam held, also as cam orders
    at each speed."""
    chain = steady.program.chain
    rpm = np.asarray(rpm, dtype=float)
    bending = arm_bending(steady, cycles, rpm)
    amplitudes = harmonic_amplitudes(steady.grid.nodes, bending)
    fundamental = float(chain.natural_frequencies(contact=True)[0][0])
    return {
        "body": chain.names[-1],
        "fundamental_hz": fundamental,
        "fundamental_rad_s": 2 * math.pi * fundamental,
        "orders": list(HARMONIC_ORDERS),
        "speeds": [
            {
                "rpm": float(r),
                "fundamental_orders": fundamental * 60.0 / float(r),
                "max_bending_mm": float(np.max(np.abs(bending[i]))),
                "bending_harmonics_mm": amplitudes[i].tolist(),
            }
            for i, r in enumerate(rpm)
        ],
    }
