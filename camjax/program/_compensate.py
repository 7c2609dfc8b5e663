"""Dynamic compensation (polydyne, a servo's model-based feed forward): the cam lift that makes
the payload follow the chosen law exactly at one design speed, for a linear train.

A chain of bodies ``j = 1..N`` (masses ``m_j``); element ``j`` joins body ``j-1`` (the cam
for ``j = 1``) to body ``j`` with stiffness ``k_j``, viscous damping ``c_j`` and lever ratio
``r_j`` (it sees ``r_j x_{j-1}`` and pushes body ``j-1`` back with ``r_j`` times its force);
the return spring ``k_s`` with preload ``F_0`` holds the last body.  Given the last body's
motion ``x_N``, going back from the last body to the cam:

    f_N = m_N x_N'' + k_s x_N + F_0                       (the last element's force)
    k_j (r_j x_{j-1} - x_j) + c_j (r_j x_{j-1}' - x_j') = f_j
    f_{j-1} = m_{j-1} x_{j-1}'' + r_j f_j,                y = x_0.

Undamped, each step is algebraic: one body gives ``y = x + (m x'' + k_s x + F_0) / k``, the
closed form; with damping in the element each step is a first-order equation whose periodic
solution is exact harmonic by harmonic.  So the inverse runs on the Fourier series of one
period (``compensated_lift``): exact for the sampled harmonics, and for a law with ``2N + 2``
continuous derivatives its truncation is far below a nanometre at the sampling used here.
The cam is two derivatives per body rougher than the law: its velocity carries the law's
jerk and its acceleration the law's fourth derivative, so for one body a law whose
acceleration, jerk or fourth derivative steps is refused (``check_smooth``).
"""

from __future__ import annotations

import dataclasses
import math

import jax
import numpy as np

SAMPLES_PER_DEGREE = 1
"""Points per degree of the compensated whole-cam table (360 over the turn: the periodic
quintic fit solves a dense system, minutes for 3600 points)."""
OVERSAMPLING = 16
"""Fourier samples per table point: the inverse runs on ``OVERSAMPLING`` times the table's
points, so that the aliasing of the law's harmonics stays below the table's fit."""
NOISE_FLOOR = 1e-15
"""Harmonics of the law smaller than this share of its largest are round-off and dropped."""
NOISE_MARGIN = 10.0
"""How far above the samples' noise (the largest harmonic of the upper half) the last kept
harmonic must stand."""
_SMOOTH_RTOL = 1e-6


def _chain(values, name: str, count: int, positive: bool = True) -> np.ndarray:
    values = np.atleast_1d(np.asarray(values, dtype=float))
    if values.shape != (count,):
        raise ValueError(f"{name} must hold one value per body ({count}), got shape {values.shape}")
    if not np.all(np.isfinite(values)) or (np.any(values <= 0) if positive else np.any(values < 0)):
        raise ValueError(
            f"{name} must be {'positive' if positive else 'non-negative'} and finite, got {values.tolist()}"
        )
    return values


def compensated_lift(
    payload,
    period_s: float,
    masses,
    stiffnesses,
    dampings,
    ratios,
    spring_rate: float = 0.0,
    preload: float = 0.0,
) -> np.ndarray:
    """The input motion ``y`` (the cam's lift) that makes the last body of the chain follow
    ``payload`` exactly, in the steady state of one period.

    Args:
        payload: the last body's motion at ``M`` equally spaced instants over one period
            (the period's end excluded), in m (or any length unit, with the forces in that
            unit times N/m).
        period_s: the period's duration in s.
        masses: per body from the cam outward (kg).
        stiffnesses: each element's stiffness (N/m), element ``j`` before body ``j``.
        dampings: each element's viscous damping (N s/m).
        ratios: each element's lever ratio (dimensionless).
        spring_rate: the return spring on the last body (N/m).
        preload: the return spring's preload (N).

    Returns ``y`` at the same instants, including the constant static compression the
    preload sets (``F_0 / k`` for one body); the steady state of the period is exact
    harmonic by harmonic (see the module's equations).
    """
    x = np.asarray(payload, dtype=float)
    if x.ndim != 1 or x.size < 8 or not np.all(np.isfinite(x)):
        raise ValueError("payload must be a 1-D array of at least 8 finite samples over one period")
    period_s = float(period_s)
    if not (math.isfinite(period_s) and period_s > 0):
        raise ValueError(f"period_s must be positive and finite, got {period_s!r}")
    masses = np.atleast_1d(np.asarray(masses, dtype=float))
    count = masses.size
    masses = _chain(masses, "masses", count)
    stiffnesses = _chain(stiffnesses, "stiffnesses", count)
    dampings = _chain(dampings, "dampings", count, positive=False)
    ratios = _chain(ratios, "ratios", count)
    for value, name in ((spring_rate, "spring_rate"), (preload, "preload")):
        if not (math.isfinite(float(value)) and float(value) >= 0):
            raise ValueError(f"{name} must be non-negative and finite, got {value!r}")
    spectrum = np.fft.rfft(x)
    # Harmonics at the samples' noise floor carry no law, only noise the inverse would amplify
    # (by (omega / omega_n)^2 per body): the series ends at the last harmonic above the floor,
    # NOISE_FLOOR of the largest or NOISE_MARGIN times the largest of the upper half (a law
    # sampled finely enough has nothing there but the noise of its samples), whichever is higher.
    size = np.abs(spectrum)
    floor = max(NOISE_FLOOR * size.max(), NOISE_MARGIN * float(size[size.size // 2 :].max()))
    spectrum[np.flatnonzero(size >= floor)[-1] + 1 :] = 0.0
    omega = 2 * math.pi * np.arange(spectrum.size) / period_s
    preload_term = np.zeros_like(spectrum)
    preload_term[0] = float(preload) * x.size  # a constant force in rfft's scaling
    position = spectrum
    force = (float(spring_rate) - masses[-1] * omega**2) * position + preload_term
    for j in range(count - 1, -1, -1):
        position = (position + force / (stiffnesses[j] + 1j * omega * dampings[j])) / ratios[j]
        if j > 0:
            force = -masses[j - 1] * omega**2 * position + ratios[j] * force
    return np.fft.irfft(position, n=x.size)


def _fourth_derivatives(law, tau) -> np.ndarray:
    """The law's second, third and fourth derivatives at local times ``tau``, shape
    ``(3, len(tau))`` (the fourth by autodiff of its jerk)."""
    tau = np.atleast_1d(np.asarray(tau, dtype=float))
    _, _, a, j = law.evaluate(tau)
    snap = jax.vmap(jax.grad(lambda t: law.evaluate(t)[3]))(tau)
    return np.stack([np.asarray(a), np.asarray(j), np.asarray(snap)])


def _law_name(turn, k: int) -> str:
    return "dwell" if turn.laws[k] is None else turn.laws[k].name


def check_smooth(program) -> None:
    """Refuse, with one line, a program whose lift's second, third or fourth derivative
    steps at a join or inside a segment (at a law's breakpoint): the compensated cam of one
    body is two derivatives rougher than the law, and a continuous acceleration of the cam
    needs a continuous fourth derivative of the law."""
    turn = program.turn
    sides = []  # (angle, where, before-values, after-values) at every join and breakpoint
    n = turn.segments
    names = ("acceleration", "jerk", "fourth derivative")

    def at(k, tau):  # mm/deg^2, ^3, ^4 of segment k at local times tau
        law, h, beta = turn.laws[k], turn.lift_mm[k], turn.angle_deg[k]
        if law is None:
            return np.zeros((3, np.size(tau)))
        return _fourth_derivatives(law, tau) * (h / beta ** np.arange(2, 5))[:, None]

    eps = 1e-9
    for k in range(n):
        before = at((k - 1) % n, 1.0 - eps)[:, 0]
        sides.append(
            (
                turn.start_deg[k],
                f"the join of segments {(k - 1) % n + 1} ({_law_name(turn, (k - 1) % n)}) "
                f"and {k + 1} ({_law_name(turn, k)})",
                before,
                at(k, eps)[:, 0],
            )
        )
        law = turn.laws[k]
        for b in law.breakpoints() if law is not None else ():
            sides.append(
                (
                    turn.start_deg[k] + b * turn.angle_deg[k],
                    f"segment {k + 1} ({_law_name(turn, k)})",
                    at(k, b - eps)[:, 0],
                    at(k, b + eps)[:, 0],
                )
            )
    # each derivative's largest size over the turn: the scale a step is measured against
    scale = np.max([np.abs(at(k, np.linspace(0.0, 1.0, 65))).max(axis=1) for k in range(n)], axis=0)
    for angle, label, before, after in sides:
        steps = np.abs(after - before) > _SMOOTH_RTOL * scale
        if steps.any():
            order = int(np.argmax(steps))
            raise ValueError(
                f"at {label}: the lift's {names[order]} steps at {angle:.6g} deg ({before[order]:.6g} to {after[order]:.6g} "
                f"mm/deg^{order + 2}); compensation needs the law's derivatives continuous up to the fourth (the "
                "cam's velocity and acceleration take the law's third and fourth): the symmetric polynomial of "
                "degree 9 (camjax.laws.PolynomialLaw(5)) or more, triple-harmonic-zero-jerk and a whole-cam lift "
                "table pass; polynomials of degree 5 and 7 (3-4-5, 4-5-6-7) and the cycloidal (a jerk step at "
                "each end) do not"
            )


@dataclasses.dataclass(frozen=True)
class Compensation:
    """A program compensated at ``rpm``: the whole-cam table (``angle_deg``, ``lift_mm``,
    from the base circle, 0 at angle 0), the ``program`` read back from it, the law's
    lift at the same angles (``law_lift_mm``), the correction's largest size (mm and share
    of the stroke), the preload's constant compression ``static_compression_mm`` (not in the
    lift: displacements are from the preloaded rest) and the least contact force of the
    compensated cam over the turn (the rigid force of the law, ``F_0 + m x'' + k_s x``)."""

    rpm: float
    angle_deg: np.ndarray
    lift_mm: np.ndarray
    law_lift_mm: np.ndarray
    program: object
    max_correction_mm: float
    correction_share: float
    static_compression_mm: float
    min_contact_force_n: float

    def csv(self) -> str:
        """The table as docs/tables.md reads it back (``[program] file = ...``)."""
        rows = "\n".join(f"{a:.10g},{y:.12g}" for a, y in zip(self.angle_deg, self.lift_mm))
        return f"# compensated at {self.rpm:g} rpm\nangle_deg,lift_mm\n{rows}\n"

    def as_dict(self) -> dict:
        return {
            "rpm": self.rpm,
            "max_correction_mm": self.max_correction_mm,
            "correction_share": self.correction_share,
            "static_compression_mm": self.static_compression_mm,
            "min_contact_force_n": self.min_contact_force_n,
        }


def check_compensable(program) -> None:
    """Refuse in one line a program ``compensate`` has no lift for, from its file alone: a
    chain with lash or a seat (no cam lift moves a valve that sits or whose lash is open), any
    other chain of bodies (not built: ``compensated_lift`` takes a chain's arrays), a groove's
    clearance (lash), a law not smooth enough (``check_smooth``)."""
    chain = program.chain
    if chain is not None and chain.has_contacts:
        raise ValueError(
            "a chain with lash or a seat has no compensated lift: while its lash is open or its "
            "valve sits on its seat the valve does not move with the cam, so no cam lift makes "
            "it follow the law there (the inverse the compensation solves exists only for a "
            "linear chain)"
        )
    if not program.one_body:
        raise ValueError(
            "compensation of a chain of bodies ([[train]]) is not built yet: "
            "compensated_lift takes a chain's arrays, compensate only the one-body follower"
        )
    if program.follower.groove_clearance_mm is not None:
        raise ValueError(
            "compensation needs a linear train: this follower has lash (groove_clearance_mm)"
        )
    check_smooth(program)


def compensate(
    program, rpm: float, *, samples_per_degree: int = SAMPLES_PER_DEGREE
) -> Compensation:
    """The cam lift that makes ``program``'s payload follow its law exactly at ``rpm``.

    Refused with one line: what ``check_compensable`` refuses, a train whose contact is lost
    at ``rpm`` (the inverse is linear only).
    """
    from ._program import Program
    from ._speeds import Speeds

    speeds = Speeds.of(rpm)
    if len(speeds) != 1:
        raise ValueError(f"rpm: compensation is designed at one speed, got {len(speeds)}")
    rpm = speeds[0]
    check_compensable(program)
    follower = program.follower
    if int(samples_per_degree) != samples_per_degree or samples_per_degree < 1:
        raise ValueError(
            f"samples_per_degree must be a whole number >= 1, got {samples_per_degree!r}"
        )
    fine = 360 * int(samples_per_degree) * OVERSAMPLING
    theta = np.arange(fine) * (360.0 / fine)
    x, _, ddx = program.lift(theta)
    omega_deg = 360.0 * rpm / 60.0
    force = (
        follower.preload_n
        + follower.mass_kg * 1e-3 * ddx * omega_deg**2
        + follower.spring_rate * 1e-3 * x
    )
    if not follower.form_closed and force.min() < 0:
        where = theta[np.argmin(force)]
        raise ValueError(
            f"compensation needs contact held at {rpm:g} rpm: the law's contact force falls to "
            f"{force.min():.4g} N at {where:.4g} deg (raise preload_n or lower the speed)"
        )
    y = 1e3 * compensated_lift(
        1e-3 * x,
        60.0 / rpm,
        [follower.mass_kg],
        [follower.stiffness],
        [follower.damping],
        [1.0],
        follower.spring_rate,
        0.0,
    )
    static = follower.preload_n / follower.stiffness * 1e3
    table = slice(None, None, OVERSAMPLING)
    angle, lift, law_lift = theta[table], y[table] - y[0], x[table]
    stroke = float(x.max() - x.min())
    correction = float(np.max(np.abs(y - x)))
    try:
        compensated = Program.from_table(
            f"{program.name}-compensated-{rpm:g}rpm",
            angle,
            lift,
            follower,
            materials=program.materials,
        )
    except ValueError as error:
        raise ValueError(
            f"the compensated lift at {rpm:g} rpm is not a cam the program reads back: {error}"
        ) from None
    return Compensation(
        rpm,
        angle,
        lift,
        law_lift,
        compensated,
        correction,
        correction / stroke,
        static,
        float(force.min()),
    )


def deviation_from_law(program, driven, rpm: float) -> tuple[float, float]:
    """How far ``driven``'s payload strays from ``program``'s law in the steady state at
    ``rpm``, at ``driven``'s grid nodes: ``(largest |x - law| over the turn, largest
    vibration in the law's dwells)`` in mm, the vibration being half the spread of
    ``x - law`` over each dwell (a static offset, as the return spring's compression of the
    train, is not vibration).  With ``driven`` the compensated program, the residual of the
    compensation at a speed other than its design speed (zero at it); with ``driven =
    program``, the uncompensated cam's, for comparison."""
    from ._report import response

    history = response(driven, rpm)
    theta = history["theta_deg"]
    law, _, _ = program.lift(theta)
    deviation = history["payload_displacement_mm"] - law
    index, _ = program.turn.locate(theta)
    spreads = [
        np.ptp(deviation[index == k]) / 2
        for k, segment in enumerate(program.segments)
        if not segment.moving and np.any(index == k)
    ]
    return float(np.abs(deviation).max()), float(max(spreads, default=0.0))
