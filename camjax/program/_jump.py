"""Contact loss of a force-closed cam: minimum preload, jump speed, flight and re-impact.

While in contact, the contact force is ``F_c = F_0 + k e + c e'`` (``e = y - x``).  When it
reaches zero the roller leaves the cam.  The roller is massless, so in flight the train
carries no force: the payload moves under the return spring alone,
``m x'' = -(F_0 + k_s x)``, while the train relaxes, ``F_0 + k e_f + c e_f' = 0``, and the
roller rides at ``r = x + e_f``.  It re-impacts where ``r`` meets the cam lift ``y``; from
there contact holds again with ``e = y - x``, ``e' = y' - x'``, and the response is the
periodic steady state plus the free vibration of the difference.  Every phase is closed
form (the steady state by exact propagation), so the events are found by bracketing and
bisection on exact values.  The turn is taken to be on the contact-held steady state up
to its first separation (the linear answer is exact until then); from there every flight
of the following period is simulated (after a re-impact the roller may take off again).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..sdof import MotionGrid, mode_between
from ._dynamics import SteadyState

_BISECTIONS = 2  # rounds of 64-way subdivision before the secant: a bracket shrinks by 65^2
_SAMPLES_PER_INTERVAL = 8


def min_preload_n(min_contact_force_n, preload_n):
    """Preload that just keeps contact: ``max(0, max over the cycle of -(k e + c e'))``."""
    return np.maximum(0.0, preload_n - np.asarray(min_contact_force_n))


def _first_root(f, lo: float, hi: float) -> float:
    """A root of ``f`` (vectorised) in ``[lo, hi]`` with ``f(lo) > 0 >= f(hi)``: the first one.

    Two rounds of 64-way subdivision shrink the bracket 4225-fold around the first sign
    change; the root is then the secant's through the bracket's ends (the force is smooth
    there: its error is of the bracket's square, far below the bisection's 65^-4)."""
    f_lo = f_hi = None
    for _ in range(_BISECTIONS):
        t = np.linspace(lo, hi, 66)
        values = f(t)
        i = int(np.argmax(values <= 0)) if np.any(values[1:] <= 0) else 65
        i = max(i, 1)
        lo, hi, f_lo, f_hi = t[i - 1], t[i], values[i - 1], values[i]
    if f_lo > 0 >= f_hi and f_lo != f_hi:
        return float(lo + (hi - lo) * f_lo / (f_lo - f_hi))
    return 0.5 * (lo + hi)


def even_periods(rpm_lo: float, rpm_hi: float, count: int) -> np.ndarray:
    """``count`` speeds (rpm, ascending) over ``[rpm_lo, rpm_hi]``, evenly spaced in the
    period ``1/rpm`` (so every period ratio of a program moves by the same step)."""
    return np.sort(1.0 / np.linspace(1 / rpm_hi, 1 / rpm_lo, count))


def scan_speeds(program, rpm_lo: float, rpm_hi: float, per_cycle: float) -> np.ndarray:
    """``even_periods`` speeds: ``per_cycle`` for each natural-frequency cycle that one
    turn gains or loses across the range (every period ratio of the program moves by
    ``1/per_cycle`` between neighbours), 16 at least."""
    cycles = program.follower.natural_frequency_hz * 60 * (1 / rpm_lo - 1 / rpm_hi)
    return even_periods(rpm_lo, rpm_hi, max(16, math.ceil(per_cycle * cycles) + 1))


def jump_speed_rpm(steady: SteadyState, rpm_lo: float, rpm_hi: float, tolerance_rpm: float = 0.1):
    """Lowest speed in ``[rpm_lo, rpm_hi]`` at which the contact force goes negative, or ``None``.

    The scan samples evenly in ``1/rpm`` with 16 samples per natural-frequency cycle
    that a cycle of the cam gains or loses across the range (every period ratio of the
    program moves by 1/16 between samples), then bisects the first crossing to
    ``tolerance_rpm``.
    """
    if steady.program.follower.form_closed:
        return None
    rpm = scan_speeds(steady.program, rpm_lo, rpm_hi, 16)
    rpm[0], rpm[-1] = rpm_lo, rpm_hi
    force = steady.min_contact_force_n(rpm)
    if not np.any(force < 0):
        return None
    i = int(np.argmax(force < 0))
    if i == 0:
        return float(rpm_lo)
    lo, hi = rpm[i - 1], rpm[i]
    while hi - lo > tolerance_rpm:
        trial = np.linspace(lo, hi, 18)[1:-1]
        f = steady.min_contact_force_n(trial)
        below = np.flatnonzero(f < 0)
        if below.size:
            hi = trial[below[0]]
            lo = trial[below[0] - 1] if below[0] > 0 else lo
        else:
            lo = trial[-1]
    return float(0.5 * (lo + hi))


@dataclasses.dataclass(frozen=True)
class Flight:
    """One loss of contact: separation and re-impact angles (degrees), impact velocity (m/s),
    peak contact force from the impact to the next separation (N)."""

    separation_deg: float
    reimpact_deg: float | None
    impact_velocity_m_s: float | None
    peak_impact_force_n: float | None

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


class _SteadyState:
    """Exact contact-held steady state at one speed, in SI, at any time ``t`` (seconds).

    The lift is read from the turn's grid (its degree-5 interpolant of ``y`` per interval,
    the one the steady state was computed from: within 1e-12 of the laws), on the host:
    the event search calls it many times with a few points each."""

    def __init__(self, steady: SteadyState, rpm: float):
        self.steady, self.rpm = steady, rpm
        self.period = 60.0 / rpm
        self.lam = steady.lam(rpm)
        self.cycle = steady.cycle(rpm)
        grid = steady.grid
        self._nodes = np.asarray(grid.nodes)
        self._widths = np.asarray(grid.piece_width)[np.asarray(grid.motion.piece)]
        self._lift = np.asarray(grid.lift)
        beta = float(steady.train.ks / steady.train.m) * self.period**2
        # NumPy throughout (converted once): the searches call these thousands of times.
        self._motion = MotionGrid(self._nodes, np.asarray(grid.motion.piece), np.asarray(grid.piece_width),
                                  np.asarray(grid.motion.forcing) + beta * self._lift)
        tr = steady.train
        self._force_gains = (float(tr.preload), float(tr.k), float(tr.c))

    def _at(self, t):
        """Interval index and local time ``sigma`` of times ``t`` (periodic), by index."""
        s = np.mod(np.atleast_1d(np.asarray(t, dtype=float)) / self.period, 1.0)
        k = np.clip(np.searchsorted(self._nodes, s, side="right") - 1, 0, self._widths.size - 1)
        return k, (s - self._nodes[k]) / self._widths[k]

    def lift(self, t):
        """Cam lift (m) and its rate (m/s) at times ``t``."""
        k, sigma = self._at(t)
        c = self._lift[k]
        y = c[:, 5]
        dy = 5 * c[:, 5]
        for m in range(4, -1, -1):
            y = y * sigma + c[:, m]
            if m:
                dy = dy * sigma + m * c[:, m]
        return 1e-3 * y, 1e-3 * dy / self._widths[k] / self.period

    def deflection(self, t):
        """``e`` (m) and ``e'`` (m/s) of the steady state at times ``t``."""
        s = np.mod(np.atleast_1d(np.asarray(t, dtype=float)) / self.period, 1.0)
        q = mode_between(self._motion, self.cycle.q, self.lam, s)
        e = q.imag / self.lam.imag
        e_rate = (q.real + self.lam.real * e) / self.period
        return 1e-3 * e, 1e-3 * e_rate

    def contact_force(self, t):
        preload, k, c = self._force_gains
        e, e_rate = self.deflection(t)
        return preload + k * e + c * e_rate


def flights(steady: SteadyState, rpm: float) -> list[Flight]:
    """Every flight in one turn at ``rpm`` (empty where contact holds).

    The turn starts at the steady state's first separation (the linear answer is exact
    until then) and runs for one period: after each re-impact contact holds (steady state
    plus the free vibration of the difference) until the force reaches zero again, and the
    follower takes off again; the turn ends one period after the first separation.
    """
    if steady.program.follower.form_closed:
        return []
    ss = _SteadyState(steady, rpm)
    if not ss.cycle.min_contact_force_n < 0:
        return []
    period = ss.period
    t_sep = _first_separation(steady, ss)
    y0, dy0 = ss.lift(t_sep)
    e0, de0 = ss.deflection(t_sep)
    state = (float(y0[0] - e0[0]), float(dy0[0] - de0[0]), float(e0[0]))
    t_end = t_sep + period
    # After each impact the next separation is the force's first sign change on a fine
    # sample of the following period (``_SAMPLES_PER_INTERVAL`` per grid interval, at
    # fixed times of the turn, so the steady state's share is computed once), then bisected.
    count = _SAMPLES_PER_INTERVAL * (steady.grid.nodes.size - 1)
    step = period / count
    steady_force = ss.contact_force(step * np.arange(count))
    out = []
    while t_sep < t_end:
        t_i, impact = _fly(steady, ss, t_sep, *state)
        if t_i is None:
            out.append(Flight(_angle(t_sep, period), None, None, None))
            break
        velocity, (x_i, v_i) = impact
        force_after = _contact_after(ss, t_i, x_i, v_i)
        ticks = np.arange(int(t_i // step) + 1, int(t_i // step) + 1 + count)
        samples = np.concatenate([[0.0], step * ticks - t_i])
        values = np.concatenate([force_after(samples[:1]),
                                 steady_force[ticks % count] + force_after.difference(samples[1:])])
        again = np.flatnonzero(values[1:] < 0)
        stop = again[0] + 1 if again.size else values.size
        out.append(Flight(_angle(t_sep, period), _angle(t_i, period), velocity,
                          _peak(force_after, samples, values, stop)))
        if not again.size:
            break
        tau = _first_root(force_after, samples[stop - 1], samples[stop])
        t_sep = t_i + tau
        state = _contact_state(ss, t_i, x_i, v_i, tau)
    return out


def flight(steady: SteadyState, rpm: float) -> Flight | None:
    """The first flight of the turn at ``rpm`` (``flights``), or ``None`` where contact holds."""
    found = flights(steady, rpm)
    return found[0] if found else None


def _angle(t: float, period: float) -> float:
    return float(np.mod(360 * t / period, 360))


def _first_separation(steady: SteadyState, ss: _SteadyState) -> float:
    """Time of the steady state's first loss of contact after its largest force."""
    T = ss.period
    force = ss.cycle.contact_force_n
    s_nodes = steady.grid.nodes
    start = int(np.argmax(force))
    order = (start + np.arange(force.size - 1)) % (force.size - 1)
    j = order[int(np.argmax(force[order] < 0))]
    if force[j] >= 0:  # negative between nodes only: find the refined dip
        dense = np.linspace(0, T, 16 * force.size)
        values = ss.contact_force(dense)
        j_t = dense[int(np.argmin(values))]
        return _first_root(ss.contact_force, j_t - T / force.size, j_t)
    prev = (j - 1) % (force.size - 1)
    t_lo = s_nodes[prev] * T
    t_hi = s_nodes[j] * T + (T if s_nodes[j] < s_nodes[prev] else 0.0)
    return _first_root(ss.contact_force, t_lo, t_hi)


def _fly(steady: SteadyState, ss: _SteadyState, t_sep: float, x0: float, v0: float, e0: float):
    """Flight from separation at ``t_sep`` (payload ``x0``, ``v0``; train ``e0``) to re-impact.

    Returns ``(t_impact, (impact velocity, (x, v) at impact))``, or ``(None, None)`` if the
    roller does not come back within a turn.
    """
    tr = steady.train
    T = ss.period
    w_f = math.sqrt(tr.ks / tr.m)
    x_eq = -tr.preload / tr.ks
    e_eq = -tr.preload / tr.k

    def payload(tau):
        return (x_eq + (x0 - x_eq) * np.cos(w_f * tau) + v0 / w_f * np.sin(w_f * tau),
                -(x0 - x_eq) * w_f * np.sin(w_f * tau) + v0 * np.cos(w_f * tau))

    def train(tau):
        if tr.c == 0:
            return np.full_like(tau, e_eq), np.zeros_like(tau)
        decay = (e0 - e_eq) * np.exp(-tr.k * tau / tr.c)
        return e_eq + decay, -tr.k / tr.c * decay

    def gap(tau):
        x, _ = payload(tau)
        ef, _ = train(tau)
        return x + ef - ss.lift(t_sep + tau)[0]

    step = T * float(np.min(steady.grid.piece_width)) / 2
    tau = np.arange(1, int(T / step) + 2) * step
    hits = np.flatnonzero(gap(tau) <= 0)
    if hits.size == 0:
        return None, None
    i = int(hits[0])
    tau_i = _first_root(gap, tau[i - 1] if i else 0.5 * step, tau[i])
    t_i = t_sep + tau_i
    x_i, v_i = (float(v) for v in payload(tau_i))
    _, def_i = (float(v[0]) for v in train(np.array([tau_i])))
    dy_i = float(ss.lift(t_i)[1][0])
    return t_i, (dy_i - (v_i + def_i), (x_i, v_i))  # cam surface velocity relative to the roller


def _difference_mode(ss: _SteadyState, t_i: float, x_i: float, v_i: float):
    """Complex mode of the contact phase's departure from the steady state, from impact."""
    y_i, dy_i = (float(v[0]) for v in ss.lift(t_i))
    es, des = (float(v[0]) for v in ss.deflection(t_i))
    u0, du0 = (y_i - x_i) - es, (dy_i - v_i) - des
    lam = ss.lam / ss.period
    return du0 - np.conj(lam) * u0, lam


def _contact_after(ss: _SteadyState, t_i: float, x_i: float, v_i: float):
    """Contact force ``t`` seconds after an impact: steady state plus the free vibration."""
    tr = ss.steady.train
    qu, lam = _difference_mode(ss, t_i, x_i, v_i)

    def difference(t):
        z = qu * np.exp(lam * t)
        u = z.imag / lam.imag
        return tr.k * u + tr.c * (z.real + lam.real * u)

    def force_after(t):
        return ss.contact_force(t_i + t) + difference(t)

    force_after.difference = difference  # the free vibration's share alone
    return force_after


def _contact_state(ss: _SteadyState, t_i: float, x_i: float, v_i: float, tau: float):
    """``(x, v, e)`` of the contact phase ``tau`` seconds after an impact."""
    qu, lam = _difference_mode(ss, t_i, x_i, v_i)
    z = qu * np.exp(lam * tau)
    u = z.imag / lam.imag
    du = z.real + lam.real * u
    t = np.array([t_i + tau])
    y, dy = (float(v[0]) for v in ss.lift(t))
    es, des = (float(v[0]) for v in ss.deflection(t))
    e, de = es + u, des + du
    return y - e, dy - de, e


def _peak(force_after, samples, values, stop: int) -> float:
    """Largest contact force from the impact to ``samples[stop]``, polished by zooming: three
    rounds of 32 samples around the best one (the bracket shrinks 16-fold each), then
    the vertex of the parabola through the best three (the force is smooth there)."""
    k = int(np.argmax(values[:stop]))
    peak = float(values[k])
    if 0 < k < stop - 1:
        lo, hi = samples[k - 1], samples[k + 1]
        for _ in range(3):
            t = np.linspace(lo, hi, 33)
            f = force_after(t)
            j = int(np.clip(np.argmax(f), 1, 31))
            peak = max(peak, float(f[j]))
            lo, hi = t[j - 1], t[j + 1]
        (fa, fb, fc), h = force_after(np.array([lo, 0.5 * (lo + hi), hi])), 0.5 * (hi - lo)
        curvature = fa - 2 * fb + fc
        if curvature < 0:
            vertex = 0.5 * (lo + hi) + 0.5 * h * (fa - fc) / curvature
            peak = max(peak, float(force_after(np.array([vertex]))[0]))
    return peak
