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
A chain's flights are its simulation with the cam's contact one-sided (``ChainContacts``),
started on the same steady state.
"""

from __future__ import annotations

import math

import numpy as np

from ..sdof import first_roots, narrowed_crossing, polished_maxima, psi_host, step_within_host
from ._chain_contacts import ChainContacts
from ._dynamics import SPEED_BLOCK, SteadyState
from ._flight import Flight as Flight
from ._oscillator import CONTACT_FORCE, chain_coordinates
from ._outputs import min_preload_n as min_preload_n
from ._speeds import Speeds

_SAMPLES_PER_INTERVAL = 8


def even_periods(rpm_lo: float, rpm_hi: float, count: int) -> np.ndarray:
    """``count`` speeds (rpm, ascending) over ``[rpm_lo, rpm_hi]``, evenly spaced in the
    period ``1/rpm`` (so every period ratio of a program moves by the same step)."""
    return np.sort(1.0 / np.linspace(1 / rpm_hi, 1 / rpm_lo, count))


def scan_speeds(program, rpm_lo: float, rpm_hi: float, per_cycle: float) -> np.ndarray:
    """``even_periods`` speeds: ``per_cycle`` for each natural-frequency cycle that one
    turn gains or loses across the range (every period ratio of the program moves by
    ``1/per_cycle`` between neighbours), 16 at least."""
    cycles = program.follower.vibrations_per_turn(rpm_lo) - program.follower.vibrations_per_turn(rpm_hi)
    return even_periods(rpm_lo, rpm_hi, max(16, math.ceil(per_cycle * cycles) + 1))


def jump_speed_rpm(steady: SteadyState, rpm_lo: float, rpm_hi: float, tolerance_rpm: float = 0.1, *,
                   rule_out: bool = True):
    """Lowest speed in ``[rpm_lo, rpm_hi]`` at which the contact force goes negative, or ``None``.

    The scan samples evenly in ``1/rpm`` with 16 samples per natural-frequency cycle
    that a cycle of the cam gains or loses across the range (every period ratio of the
    program moves by 1/16 between samples), then bisects the first crossing to
    ``tolerance_rpm``.  The scan's low speeds where ``ContactForceBound`` holds contact are
    not computed (``rule_out=False``: every scan speed is, as the benchmarks' baseline).
    """
    rpm_lo, rpm_hi = Speeds.of(rpm_lo, "rpm_lo")[0], Speeds.of(rpm_hi, "rpm_hi")[0]
    if not rpm_lo <= rpm_hi:
        raise ValueError(f"need rpm_lo <= rpm_hi, got {rpm_lo:g}, {rpm_hi:g}")
    return _jump_speed(steady, rpm_lo, rpm_hi, tolerance_rpm, rule_out=rule_out)


def _jump_speed(steady: SteadyState, rpm_lo: float, rpm_hi: float, tolerance_rpm: float = 0.1,
                *, rule_out: bool = True):
    """``jump_speed_rpm`` over speeds already made ``Speeds`` (``rpm_lo <= rpm_hi``).

    The scan's speeds up to the first one where ``ContactForceBound`` does not hold
    contact are ruled out without computing their steady state (the bound is a lower bound
    of the least contact force); the rest of the scan runs in waves of speed blocks up to
    the first loss of contact, and each round of the bisection is one block.  The scan's
    speeds and the rounds are the ones of a plain scan, so the answer is the same.
    ``rule_out=False`` is that plain scan: every scan speed computed, in one dispatch (the
    benchmarks' baseline).
    """
    if steady.program.follower.form_closed:
        return None
    rpm = scan_speeds(steady.program, rpm_lo, rpm_hi, 16)
    rpm[0], rpm[-1] = rpm_lo, rpm_hi
    if rule_out:
        i = _first_loss(steady, rpm)
    else:
        lost = np.flatnonzero(steady.min_contact_force_n(rpm) < 0)
        i = int(lost[0]) if lost.size else None
    if i is None:
        return None
    if i == 0:
        return float(rpm_lo)
    return float(narrowed_crossing(lambda trial: steady.min_contact_force_n(trial) < 0, rpm[i - 1], rpm[i],
                                   tolerance_rpm, _ROUND_SPEEDS))


_ROUND_SPEEDS = 16
"""Speeds of each round of the jump speed's bisection (one block): the bracket shrinks 17-fold."""


_BOUND_MARGIN = 0.01
"""Share of the preload the bound must clear to rule a speed out: room for its minimum,
which is taken over samples (``_BOUND_SAMPLES`` per grid interval) of a smooth curve."""
_BOUND_SAMPLES = 3
_BOUND_ORDER = 3  # derivatives of the forcing in the quasi-static part
_BOUND_CHUNK = 256  # speeds per evaluation of the bound (a (chunk, samples) array)


_SCAN_WAVE = 2 * SPEED_BLOCK
"""Scan speeds per wait: the scan stops at the first wave with a loss of contact."""


def _first_loss(steady: SteadyState, rpm: np.ndarray) -> int | None:
    """Index of the first speed of the scan ``rpm`` (ascending) where contact is lost, or
    None: the speeds that ``ContactForceBound`` holds in contact are skipped, the rest
    computed in waves of ``_SCAN_WAVE`` speeds up to the first wave with a loss."""
    for start in range(ContactForceBound(steady).first_unheld(rpm), rpm.size, _SCAN_WAVE):
        force = steady.min_contact_force_n(rpm[start : start + _SCAN_WAVE])
        lost = np.flatnonzero(force < 0)
        if lost.size:
            return start + int(lost[0])
    return None


class ContactForceBound:
    """A lower bound of the periodic steady state's least contact force at any speed, from
    the program's forcing alone (no propagation): what rules out whole speed ranges of the
    jump's scan.

    Each mode obeys ``q_j' = lam_j q_j + f_j`` in turn time (``f_j = a_j y_ss + b_j T^2 y``
    on each interval, ``Oscillator``); its periodic solution is
    ``q_j(s) = int_0^inf exp(lam_j u) f_j(s - u) du``.  Integrating by parts three times,
    ``q_j = -f_j/lam_j - f_j'/lam_j^2 - f_j''/lam_j^3 + R_j`` with
    ``|R_j| <= (J_f/|lam_j| + J_f'/|lam_j|^2 + V_f''/|lam_j|^3) / (1 - exp(Re lam_j))``, where
    ``J_g`` sums the jumps of ``g`` over a turn (at most ``|a_j| J_(y_ss) + |b_j| T^2 J_y``)
    and ``V_f''`` is the total variation of ``f''`` (its jumps included).  The contact force
    is ``F_0 + Re(sum_j G_j q_j) + d0 y + d1 y_s + d2 y_ss`` (``G_j`` its gains, the direct
    terms exact), so it is at least the quasi-static force less ``sum_j |G_j| |R_j|``, a
    remainder that grows with the speed.  At low speeds, where the scan is densest (it is
    even in the period), the bound holds contact and those speeds need no steady state.
    """

    def __init__(self, steady: SteadyState):
        grid = steady.grid
        widths = np.asarray(grid.piece_width)[np.asarray(grid.motion.piece)][:, None]

        def sampled(coefficients, count):
            """``(f, f', f'')`` at ``count`` points of every interval, from its monomial
            coefficients in the local ``sigma``."""
            sigma = np.linspace(0.0, 1.0, count)[:, None]
            c = np.asarray(coefficients, dtype=float)
            m = np.arange(6)
            return tuple(
                c[:, n:] @ (_falling(m[n:], n) * sigma ** m[: 6 - n]).T / widths**n
                for n in range(_BOUND_ORDER)
            )

        def jumps(v):  # the turn closes on its start
            return float(np.abs(v[:, 0] - np.roll(v[:, -1], 1)).sum())

        def variation(v):  # a polynomial sampled at 33 points per interval, and its jumps
            return float(np.abs(np.diff(v, axis=1)).sum()) + jumps(v)

        fine = sampled(grid.motion.forcing, 33), sampled(grid.lift, 33)
        self.jumps = [[jumps(v[n]) for v in fine] for n in range(_BOUND_ORDER - 1)]
        self.variation = [variation(v[-1]) for v in fine]
        coarse = sampled(grid.motion.forcing, _BOUND_SAMPLES), sampled(grid.lift, _BOUND_SAMPLES)
        # rows: (y_ss, y) and their first two derivatives, then y_s for the direct term
        self.samples = np.stack([v[n].ravel() for n in range(_BOUND_ORDER) for v in coarse] + [coarse[1][1].ravel()])
        self.oscillator = steady.oscillator
        self.preload = float(steady.oscillator.static[CONTACT_FORCE])

    def __call__(self, rpm) -> np.ndarray:
        """The bound (N) at each speed of ``rpm``."""
        osc = self.oscillator
        rpm = np.asarray(rpm, dtype=float)
        period = (60.0 / rpm)[:, None]
        lam = period * np.asarray(osc.lam)[None, :]  # (speeds, S), per turn
        gain = np.asarray(osc.gain)[CONTACT_FORCE][None, :] / period  # of the turn-time modes
        a, b = np.asarray(osc.forcing)[:, 1], np.asarray(osc.forcing)[:, 0] * period**2
        terms = [(-gain / lam ** (n + 1)).real for n in range(_BOUND_ORDER)]
        e0, e1, e2 = np.asarray(osc.direct)[CONTACT_FORCE]
        columns = []
        for n, t in enumerate(terms):
            columns += [(t * a).sum(axis=1) + (e2 / period[:, 0] ** 2 if n == 0 else 0.0),
                        (t * b).sum(axis=1) + (e0 if n == 0 else 0.0)]
        columns.append(np.full(rpm.size, e1) / period[:, 0])
        quasi_static = (np.stack(columns, axis=1) @ self.samples).min(axis=1)
        rest = sum(
            (np.abs(a) * acc + np.abs(b) * lift) / np.abs(lam) ** (n + 1)
            for n, (acc, lift) in enumerate(self.jumps)
        )
        rest = rest + (np.abs(a) * self.variation[0] + np.abs(b) * self.variation[1]) / np.abs(lam) ** _BOUND_ORDER
        return self.preload + quasi_static - (np.abs(gain) * rest / -np.expm1(lam.real)).sum(axis=1)

    def first_unheld(self, rpm) -> int:
        """Index of the first speed of ``rpm`` (ascending) where the bound, less
        ``_BOUND_MARGIN`` of the preload, does not hold contact (``rpm.size`` if none):
        the speeds before it need no steady state."""
        rpm = np.asarray(rpm, dtype=float)
        for start in range(0, rpm.size, _BOUND_CHUNK):
            held = self(rpm[start : start + _BOUND_CHUNK]) > _BOUND_MARGIN * self.preload
            if not held.all():
                return start + int(np.argmin(held))
        return rpm.size


def _falling(m, n):
    """``m (m - 1) ... (m - n + 1)``: the factor of ``sigma^(m - n)`` in the n-th derivative of ``sigma^m``."""
    out = np.ones_like(m)
    for j in range(n):
        out = out * (m - j)
    return out


class _Turns:
    """The contact-held periodic steady states at several speeds (rows), exact at any time,
    in SI, on the host (NumPy): every method takes the rows and the times (seconds) as
    arrays that broadcast, so the event searches of every speed run at once.

    The lift is read from the turn's grid (its degree-5 interpolants of ``y`` and ``y''``
    per interval, the ones the steady state was computed from: within 1e-12 of the laws);
    the modes are the engine's exact step from the node before
    (``camjax.sdof.step_within_host``), the outputs the ``Oscillator``'s.  The flight's
    own constants (``k``, ``c``, ``k_s``, ``m``, the preload) are the classic follower's.
    """

    def __init__(self, steady: SteadyState, rpm: Speeds):
        grid, osc = steady.grid, steady.oscillator
        self.oscillator = osc
        self.period = 60.0 / np.asarray(rpm, dtype=float)
        self.lam = self.period[:, None] * np.asarray(osc.lam)[None, :]  # (rows, S), per turn
        self.q = steady.cycles_at(rpm).q  # (rows, S, K + 1)
        self.nodes = np.asarray(grid.nodes)
        self.piece = np.asarray(grid.motion.piece)
        self.piece_width = np.asarray(grid.piece_width)
        self.widths = self.piece_width[self.piece]
        self.lift_coefficients = np.asarray(grid.lift)
        self.acceleration = np.asarray(grid.motion.forcing)
        weights = np.asarray(osc.forcing)
        self.a = weights[:, 1]
        self.beta = weights[None, :, 0] * self.period[:, None] ** 2  # (rows, S)
        f = steady.program.follower
        self.preload = float(osc.static[CONTACT_FORCE])
        self.k, self.c, self.ks, self.m = float(f.stiffness), float(f.damping), float(f.spring_rate), float(f.mass_kg)

    def _locate(self, rows, t):
        s = np.mod(t / self.period[rows], 1.0)
        k = np.clip(np.searchsorted(self.nodes, s, side="right") - 1, 0, self.widths.size - 1)
        return k, s - self.nodes[k]

    def lift(self, rows, t):
        """Cam lift (m) and its rate (m/s)."""
        y, dy, _ = self._lift_jet(rows, t)
        return 1e-3 * y, 1e-3 * dy

    def _lift_jet(self, rows, t):
        """``y`` (mm), ``y'`` (mm/s) and ``y''`` (mm/s^2) from the grid's interpolants."""
        k, delta = self._locate(rows, t)
        c = self.lift_coefficients[k]
        sigma = delta / self.widths[k]
        y, dy = c[..., 5], 5 * c[..., 5]
        for m in range(4, -1, -1):
            y = y * sigma + c[..., m]
            if m:
                dy = dy * sigma + m * c[..., m]
        a = self.acceleration[k]
        ddy = a[..., 5]
        for m in range(4, -1, -1):
            ddy = ddy * sigma + a[..., m]
        period = self.period[rows]
        return y, dy / self.widths[k] / period, ddy / period**2

    def modes(self, rows, t):
        """The physical modes (``Oscillator``) of the steady state, ``(S, ...)``."""
        k, delta = self._locate(rows, t)
        out = []
        for j in range(self.lam.shape[1]):
            forcing = self.a[j] * self.acceleration[k] + self.beta[rows, j][..., None] * self.lift_coefficients[k]
            out.append(step_within_host(self.q[rows, j, k], forcing, self.widths[k], delta, self.lam[rows, j])
                       / self.period[rows])
        return np.stack(out)

    def deflection(self, rows, t):
        """``e`` (m) and ``e'`` (m/s) of the classic follower's steady state."""
        e, e_rate = self.oscillator.state(self.modes(rows, t))
        return 1e-3 * e, 1e-3 * e_rate

    def contact_force(self, rows, t):
        """The contact force (N) of the steady state, the ``Oscillator``'s row."""
        osc = self.oscillator
        y, dy, ddy = self._lift_jet(rows, t)
        e0, e1, e2 = np.asarray(osc.direct)[CONTACT_FORCE]
        gain = np.asarray(osc.gain)[CONTACT_FORCE]
        modes = np.real(np.tensordot(gain, self.modes(rows, t), axes=(0, 0)))
        return self.preload + modes + e0 * y + e1 * dy + e2 * ddy

    def sampled_force(self):
        """The contact force at ``_SAMPLES_PER_INTERVAL`` fixed fractions of every interval:
        ``(times in turns (S,), force (rows, S))`` (the propagation's weights are taken per
        piece, not per sample)."""
        fractions = np.arange(_SAMPLES_PER_INTERVAL) / _SAMPLES_PER_INTERVAL
        delta = self.widths[:, None] * fractions
        times = (self.nodes[:-1, None] + delta).ravel()
        powers = fractions[:, None] ** np.arange(6)
        out = np.empty((self.period.size, times.size))
        osc = self.oscillator
        gain = np.asarray(osc.gain)[CONTACT_FORCE]
        e0, e1, e2 = np.asarray(osc.direct)[CONTACT_FORCE]
        rows = np.arange(self.period.size)
        y, dy, ddy = self._lift_jet(rows[:, None], times[None, :] * self.period[:, None])
        for r in rows:  # one speed at a time: (K, samples, 6) at most
            force = self.preload + e0 * y[r] + e1 * dy[r] + e2 * ddy[r]
            for j, lam in enumerate(self.lam[r]):
                weights = psi_host(lam * self.piece_width[:, None] * fractions)[self.piece]
                forcing = self.a[j] * self.acceleration + self.beta[r, j] * self.lift_coefficients
                q = (np.exp(lam * delta) * self.q[r, j, :-1, None]
                     + delta * np.einsum("kc,jc,kjc->kj", forcing, powers, weights))
                force = force + np.real(gain[j] * q / self.period[r]).ravel()
            out[r] = force
        return times, out


def flights(steady: SteadyState, rpm: float) -> list[Flight]:
    """Every flight in one turn at ``rpm`` (empty where contact holds); see ``flights_at``."""
    return flights_at(steady, Speeds.of(rpm)[:1])[0]


def flights_at(steady: SteadyState, rpm, *, simulation=None) -> list[list[Flight]]:
    """Every flight in one turn at each speed of ``rpm`` (empty where contact holds).

    A chain's (``Program.chain``): where its exact steady state loses contact, the flights of
    its simulated periodic steady state with the cam's contact one-sided
    (``ChainContacts.flights``; ``simulation``: that ``ChainContacts``, default one built for
    the speeds that lose contact; given, a one-body chain's are simulated too).  The classic
    follower's:

    The turn starts at the steady state's first separation (the linear answer is exact
    until then) and runs for one period: after each re-impact contact holds (steady state
    plus the free vibration of the difference) until the force reaches zero again, and the
    follower takes off again; the turn ends one period after the first separation.  The
    speeds' events are searched together, flight by flight.
    """
    rpm = Speeds.of(rpm)
    out = [[] for _ in rpm]
    if steady.program.follower.form_closed:
        return out
    lost = np.flatnonzero(steady.cycles_at(rpm).min_contact_force_n < 0)
    if lost.size == 0:
        return out
    if not steady.program.one_body or simulation is not None:
        return _chain_flights(steady, rpm, lost, out, simulation)
    turns = _Turns(steady, rpm[lost])
    times, table = turns.sampled_force()
    period = turns.period
    rows = np.arange(lost.size)
    t_sep = _first_separations(turns, times, table)
    y0, dy0 = turns.lift(rows, t_sep)
    e0, de0 = turns.deflection(rows, t_sep)
    x, v, e = y0 - e0, dy0 - de0, e0
    t_end = t_sep + period
    while rows.size:
        t_i, velocity, x_i, v_i = _fly(turns, rows, t_sep[rows], x[rows], v[rows], e[rows])
        for r in rows[np.isnan(t_i)]:  # the roller does not come back within a turn
            out[lost[r]].append(Flight(_angle(t_sep[r], period[r]), None, None, None))
        back = ~np.isnan(t_i)
        rows, t_i, velocity, x_i, v_i = rows[back], t_i[back], velocity[back], x_i[back], v_i[back]
        if not rows.size:
            break
        contact = _Contact(turns, rows, t_i, x_i, v_i)
        samples, values = contact.sampled(times, table)
        negative = values[:, 1:] < 0
        again = negative.any(axis=1)
        stop = np.where(again, negative.argmax(axis=1) + 1, values.shape[1])
        peaks = _peaks(contact, samples, values, stop)
        for j, r in enumerate(rows):
            out[lost[r]].append(Flight(_angle(t_sep[r], period[r]), _angle(t_i[j], period[r]),
                                       float(velocity[j]), float(peaks[j])))
        sub = np.flatnonzero(again)
        if not sub.size:
            break
        here = np.arange(sub.size)
        tau = first_roots(lambda t, c=contact, rows_=sub[here, None]: c.force(rows_, t),
                           samples[sub, stop[sub] - 1], samples[sub, stop[sub]])
        rows = rows[sub]
        t_sep[rows] = t_i[sub] + tau
        x[rows], v[rows], e[rows] = contact.state(sub, tau)
        rows = rows[t_sep[rows] < t_end[rows]]
    return out


def _chain_flights(steady: SteadyState, rpm: Speeds, lost: np.ndarray, out: list, simulation) -> list:
    """``flights_at`` of a chain at the speeds ``lost``: its simulation with the cam's
    contact one-sided (``ChainContacts.flights``), started on the exact steady state at its
    largest contact force (``_Turns``; the chain's coordinates from its modes,
    ``chain_coordinates``) and run to one period after the steady state's first separation
    (``_first_separations``), the classic follower's turn."""
    program = steady.program
    chain = program.chain
    if chain is None:
        raise ValueError(f"program {program.name!r} has no [[train]]: its flights are not simulated")
    speeds = Speeds.of(np.asarray(rpm, dtype=float)[lost])
    turns = _Turns(steady, speeds)
    times, table = turns.sampled_force()
    period = turns.period
    rows = np.arange(lost.size)
    start = times[table.argmax(axis=1)]  # turns: the largest force, the cam held
    separation = _first_separations(turns, times, table) / period
    separation = separation + np.ceil(start - separation)  # the first after the start
    modes = turns.modes(rows, start * period)
    y, dy, _ = turns._lift_jet(rows, start * period)
    state = steady.oscillator.state(modes)
    if program.one_body:  # the classic's oscillator: its state is the deflection e = y - x
        x, v = y - state[:1], dy - state[1:]
    else:
        x, v = chain_coordinates(chain, state, y, dy)
    if chain.bodies[0].rides:  # the riding body is a coordinate of the simulation: on the cam
        x, v = np.concatenate([y[None], x]), np.concatenate([dy[None], v])
    state = np.concatenate([x, v * period], axis=0).T  # mm, mm per turn
    simulation = simulation or ChainContacts(program, chain, float(speeds.min()))
    for i, found in zip(lost, simulation.flights(speeds, start, start + 2.0, state, separation + 1.0)):
        out[i] = found
    return out


def flight(steady: SteadyState, rpm: float) -> Flight | None:
    """The first flight of the turn at ``rpm`` (``flights``), or ``None`` where contact holds."""
    found = flights_at(steady, Speeds.of(rpm)[:1])[0]
    return found[0] if found else None


def _angle(t: float, period: float) -> float:
    return float(np.mod(360 * t / period, 360))


def _first_separations(turns: _Turns, times: np.ndarray, table: np.ndarray) -> np.ndarray:
    """Time (s) of each steady state's first loss of contact after its largest force: the
    first sign change of the sampled force after its largest sample, bisected (where the
    force dips below zero only between samples, around its smallest sample)."""
    m, n = table.shape
    rows = np.arange(m)
    order = (table.argmax(axis=1)[:, None] + np.arange(n)) % n
    negative = np.take_along_axis(table, order, axis=1) < 0
    first = negative.argmax(axis=1)
    j, prev = order[rows, first], order[rows, first - 1]
    lo, hi = times[prev], times[j] + (times[j] < times[prev])
    for r in np.flatnonzero(~negative.any(axis=1)):  # a dip between samples: find a negative point
        a = int(table[r].argmin())
        lo[r], hi[r] = times[a - 1] - (a == 0), times[(a + 1) % n] + (a == n - 1)
        for _ in range(3):
            t = np.linspace(lo[r], hi[r], 33)
            i = int(np.clip(turns.contact_force(r, t * turns.period[r]).argmin(), 1, 31))
            lo[r], hi[r] = t[i - 1], t[i]
    period = turns.period
    return first_roots(lambda t: turns.contact_force(rows[:, None], t), lo * period, hi * period)


def _fly(turns: _Turns, rows, t_sep, x0, v0, e0):
    """Flight from separation at ``t_sep`` (payload ``x0``, ``v0``; train ``e0``) to re-impact,
    for each row: ``(t_impact, impact velocity, x, v at impact)``, NaN where the roller does
    not come back within a turn."""
    w_f = math.sqrt(turns.ks / turns.m)
    x_eq, e_eq = -turns.preload / turns.ks, -turns.preload / turns.k

    def payload(i, tau):  # i broadcasts with tau
        x_rel, v_i = x0[i] - x_eq, v0[i]
        return (x_eq + x_rel * np.cos(w_f * tau) + v_i / w_f * np.sin(w_f * tau),
                -x_rel * w_f * np.sin(w_f * tau) + v_i * np.cos(w_f * tau))

    def train(i, tau):
        if turns.c == 0:
            return np.full_like(tau, e_eq), np.zeros_like(tau)
        decay = (e0[i] - e_eq) * np.exp(-turns.k * tau / turns.c)
        return e_eq + decay, -turns.k / turns.c * decay

    def gap(i, tau):
        return payload(i, tau)[0] + train(i, tau)[0] - turns.lift(rows[i], t_sep[i] + tau)[0]

    every = np.arange(rows.size)
    step = turns.period[rows] * float(np.min(turns.piece_width)) / 2
    tau = np.arange(1, int(2.0 / float(np.min(turns.piece_width))) + 2) * step[:, None]
    hits = gap(every[:, None], tau) <= 0
    back = np.flatnonzero(hits.any(axis=1))
    t_i, velocity, x_i, v_i = (np.full(rows.size, np.nan) for _ in range(4))
    if not back.size:
        return t_i, velocity, x_i, v_i
    first = hits[back].argmax(axis=1)
    lo = np.where(first > 0, tau[back, first - 1], 0.5 * step[back])
    here = np.arange(back.size)
    tau_i = first_roots(lambda t: gap(back[here, None], t), lo, tau[back, first])
    x, v = payload(back, tau_i)
    _, e_rate = train(back, tau_i)
    t_i[back] = t_sep[back] + tau_i
    _, dy = turns.lift(rows[back], t_i[back])
    velocity[back] = dy - (v + e_rate)  # the cam surface's velocity relative to the roller
    x_i[back], v_i[back] = x, v
    return t_i, velocity, x_i, v_i


class _Contact:
    """Contact after each row's impact: the steady state plus the free vibration of the
    difference, ``tau`` seconds after the impact at ``t_i`` (the classic follower: one
    mode, converted to and from the deflection by the ``Oscillator``)."""

    def __init__(self, turns: _Turns, rows, t_i, x_i, v_i):
        self.turns, self.rows, self.t_i = turns, rows, t_i
        y_i, dy_i = turns.lift(rows, t_i)
        es, des = turns.deflection(rows, t_i)
        u0, du0 = (y_i - x_i) - es, (dy_i - v_i) - des
        self.lam = turns.lam[rows, 0] / turns.period[rows]
        self.q = turns.oscillator.modes(np.stack([1e3 * u0, 1e3 * du0]))[0]

    def _difference(self, i, tau):
        z = self.q[i] * np.exp(self.lam[i] * tau)
        u, du = self.turns.oscillator.state(z[None])
        return 1e-3 * u, 1e-3 * du

    def force(self, i, tau):
        """Contact force (N) of rows ``i`` at ``tau``."""
        u, du = self._difference(i, tau)
        steady = self.turns.contact_force(self.rows[i], self.t_i[i] + tau)
        return steady + self.turns.k * u + self.turns.c * du

    def sampled(self, times, table):
        """The force over one period after each impact: at the impact, then at the turn's
        fixed samples (``_Turns.sampled_force``), whose steady share is read from the table."""
        count = times.size
        s_i = self.t_i / self.turns.period[self.rows]
        base = np.floor(s_i)
        ticks = np.searchsorted(times, s_i - base, side="right")[:, None] + np.arange(count)
        at = (base[:, None] + ticks // count + times[ticks % count]) * self.turns.period[self.rows][:, None]
        tau = np.concatenate([np.zeros((self.rows.size, 1)), at - self.t_i[:, None]], axis=1)
        i = np.arange(self.rows.size)[:, None]
        u, du = self._difference(i, tau[:, 1:])
        after = table[self.rows[:, None], ticks % count] + self.turns.k * u + self.turns.c * du
        return tau, np.concatenate([self.force(i, tau[:, :1]), after], axis=1)

    def state(self, i, tau):
        """``(x, v, e)`` of rows ``i`` ``tau`` seconds after their impacts."""
        u, du = self._difference(i, tau)
        t = self.t_i[i] + tau
        y, dy = self.turns.lift(self.rows[i], t)
        es, des = self.turns.deflection(self.rows[i], t)
        e, de = es + u, des + du
        return y - e, dy - de, e


def _peaks(contact: _Contact, samples, values, stop) -> np.ndarray:
    """Largest contact force of each row from the impact to ``samples[stop]``: the largest
    sample, polished between its neighbours (``polished_maxima``; the force is smooth)."""
    masked = np.where(np.arange(values.shape[1]) < stop[:, None], values, -np.inf)
    k = masked.argmax(axis=1)
    peak = masked[np.arange(k.size), k]
    sub = np.flatnonzero((k > 0) & (k < stop - 1))
    if sub.size:
        peak[sub] = polished_maxima(lambda t: contact.force(sub[:, None], t), samples[sub, k[sub] - 1],
                                    samples[sub, k[sub] + 1], peak[sub])
    return peak
