"""A form-closed cam whose groove is wider than the roller: the hand-over to ``Backlash``.

With a groove clearance ``g`` the roller leaves one flank when the train's force changes
sign and crosses the groove to strike the other.  That is ``camjax.models.Backlash``, the
SDOF whose transmission spring has a dead zone, driven by the whole turn instead of one
rise.  The mapping (docs/program.md states it): lengths in units of the program's
largest lift ``h`` (``s = y / h``, ``bk = g / h``), time in turns (``tau = t / T``,
``T = 60 / rpm``), so the period ratio is ``n = f_n T`` with ``f_n = sqrt(k / m) / (2 pi)``
(no return spring), the damping ratio is the follower's, and ``dn = 0`` (nothing but the
train acts on the payload).  The inner flank (the one that lifts the follower) is the
driving flank: ``e = y - x > 0`` presses it, ``e < -g`` the outer one.  Back in physical
units an impact velocity is ``v h / T`` and the train force ``F = m x''`` is
``m h / T^2`` times the model's normalised payload acceleration.

The periodic state is approached by running turns from rest on the base circle until the
strikes of the last two turns agree (same flanks, angles within ``SETTLED_DEG``, velocities
within ``SETTLED_REL``): a measured criterion, since the damping acts only in contact and a
turn count from the contact decay alone left the strikes moving by 5e-4 degrees.  The
impacts of the last turn are reported, with the change that remained.
"""

from __future__ import annotations

import dataclasses
import math
import sys

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from tqdm import tqdm

from ..errors import SolverError
from ..laws import AbstractMotionLaw
from ._program import Program
from ._speeds import Speeds
from ._turn import Turn

_SETTLE = math.log(1e9)  # decay of the contact vibration over the first turns tried
SETTLED_DEG = 1e-6
"""Largest change of a strike's angle between the last two turns of a settled run."""
SETTLED_REL = 1e-6
"""Largest relative change of a strike's velocity between the last two turns of a settled run."""
MAX_TURNS = 1024
"""Most turns a groove run takes from rest before it reports that it has not settled."""
MAX_GROOVE_SAMPLES = 50_000
"""Most samples (turns times samples per turn) of one groove run: the doubling of the turns
stops before a run would pass it (the turn is then reported unsettled), and a speed whose
first run passes it is refused before any work.  A run of 28,000 samples (the indexer at
300 rpm, six turns) took about 40 s on two cores."""
_SAMPLES_PER_PERIOD = 128  # samples per natural period (force peaks sampled: within 0.03%)
FLANKS = {0: "inner", 2: "outer"}


class TurnLaw(AbstractMotionLaw):
    """A program's lift over ``turns`` turns, normalised, as the hybrid models' motion law.

    ``s(tau) = y(T tau) / h``, periodic with period 1 (``tau`` in turns), read from the
    program's ``Turn``.  ``breakpoints`` lists the segment ends and the laws' breakpoints
    over all ``turns`` turns (the hybrid solver's step control lands on them), so unlike a
    rise they run past 1.  ``Ca`` (and ``Cv``, ``Cj``) are exact: the largest of each
    segment's ``|lift| C / (h f^k)``.
    """

    turn: Turn
    stroke_mm: float = eqx.field(static=True)
    points: tuple = eqx.field(static=True)  # the turn's breakpoints, in turns
    peaks: tuple = eqx.field(static=True)  # (Cv, Ca, Cj)
    turns: int = eqx.field(static=True, default=1)

    @classmethod
    def of(cls, program: Program, stroke_mm: float, turns: int) -> TurnLaw:
        segs = [program.segments[i] for i in program.moving_segments()]
        peaks = tuple(
            max(abs(s.lift_mm) / stroke_mm * float(getattr(s.law, c)) / (s.angle_deg / 360.0) ** k for s in segs)
            for k, c in ((1, "Cv"), (2, "Ca"), (3, "Cj"))
        )
        points = tuple((program.turn.breakpoints_deg() / 360.0).tolist())
        return cls(program.turn, float(stroke_mm), points, peaks, int(turns))

    @property
    def name(self) -> str:
        return "program-turn"

    def evaluate(self, tau):
        """``(s, v, a, j)`` at ``tau`` (in turns): the turn's jet, normalised."""
        y, dy, ddy, dddy = self.turn.jet(360.0 * jnp.asarray(tau, dtype=float))
        return tuple(x * 360.0**p / self.stroke_mm for p, x in enumerate((y, dy, ddy, dddy)))

    def rise(self, tau):
        return self.evaluate(tau)

    def end_state(self):
        """None: a periodic turn, not a rise, so the rest-to-rest check does not apply."""
        return None

    def breakpoints(self):
        return tuple(sorted(k + p for k in range(self.turns) for p in self.points if 0 < k + p < self.turns))

    @property
    def Cv(self):
        return self.peaks[0]

    @property
    def Ca(self):
        return self.peaks[1]

    @property
    def Cj(self):
        return self.peaks[2]


@dataclasses.dataclass(frozen=True)
class Impact:
    """One strike of the roller on a groove flank: angle (deg), velocity (m/s), peak force (N).

    ``peak_force_n`` is the train force of largest magnitude from the strike to the next
    strike, the turn's last one running on across 360 degrees to the next turn's first
    (sampled at 128 per natural period; signed: positive on the inner flank, negative on
    the outer).  Strikes closer together than one sample (a chattering roller)
    get the force at the first sample after the strike.
    """

    angle_deg: float
    flank: str
    velocity_m_s: float
    peak_force_n: float

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def stroke_mm(program: Program) -> float:
    """The program's largest lift (mm): the length unit of the hand-over."""
    return float(max(np.max(np.cumsum([s.lift_mm for s in program.segments])), 1e-300))


def settling_turns(program: Program, rpm_max: float) -> int:
    """Turns from rest after which contact vibration has decayed by 1e-9 at every speed up
    to ``rpm_max`` (at least 2: the reported turn follows one full turn)."""
    f = program.follower
    n = f.vibrations_per_turn(rpm_max)
    return 1 + max(1, math.ceil(_SETTLE / (2 * math.pi * f.damping_ratio * n)))


@dataclasses.dataclass(frozen=True)
class GrooveTurn:
    """The last simulated turn at one speed: samples of the train force and every impact.

    ``theta_deg`` runs over [0, 360]; ``force_n`` is ``m x''``, the force on the payload
    (positive: the inner flank pushes; zero while the roller crosses the groove).
    """

    rpm: float
    theta_deg: np.ndarray
    force_n: np.ndarray
    impacts: list[Impact]
    turns: int = 0
    """Turns run from rest (this one is the last)."""
    change_deg: float = 0.0
    """Largest change of a strike's angle from the turn before (``inf`` where the strikes
    differ in number or flank): at most ``SETTLED_DEG`` once settled."""

    @property
    def settled(self) -> bool:
        """Whether the strikes repeated from the turn before (``SETTLED_DEG``)."""
        return self.change_deg <= SETTLED_DEG

    @classmethod
    def from_response(cls, rpm, response, turns: int, mass: float, stroke_m: float,
                      period: float, *, turn: int | None = None) -> GrooveTurn:
        """Turn ``turn`` (0-based; default the last) of a ``turns``-turn ``Backlash``
        response (``camjax.solve``) in physical units: ``mass`` in kg, ``stroke_m`` the
        length unit, ``period`` in s."""
        turn = turns - 1 if turn is None else int(turn)
        count = int(response.n_impacts)
        tau = np.asarray(response.impact_tau)[:count]
        velocity = np.asarray(response.impact_velocity)[:count]
        flank = np.asarray(response.impact_flank)[:count]
        ts = np.asarray(response.tau)
        force = mass * stroke_m / period**2 * np.asarray(response.payload_acceleration)
        impacts = []
        here = np.flatnonzero((tau >= turn) & (tau < turn + 1))
        for i in here:
            first = min(int(np.searchsorted(ts, tau[i])), ts.size - 1)
            if i + 1 < count:
                window = force[first:max(int(np.searchsorted(ts, tau[i + 1], side="right")), first + 1)]
            else:  # the run ends before the next strike: the turn is periodic, so the force
                # from its end on to the next turn's first strike is the force from its start
                # to its own first strike
                wrap = force[int(np.searchsorted(ts, turn)):int(np.searchsorted(ts, tau[here[0]], side="right"))]
                window = np.concatenate([force[first:max(int(np.searchsorted(ts, turn + 1, side="right")), first + 1)],
                                         wrap])
            peak = float(window[np.argmax(np.abs(window))])
            impacts.append(Impact(float(360.0 * (tau[i] - turn)), FLANKS[int(flank[i])],
                                  float(velocity[i] * stroke_m / period), peak))
        inside = (ts >= turn) & (ts <= turn + 1)
        return cls(rpm, 360.0 * (ts[inside] - turn), force[inside], impacts, turns)

    def change_from(self, before: GrooveTurn) -> float:
        """Largest change of a strike angle (degrees) from ``before``; ``inf`` where the
        strikes differ in number, flank, or velocity by more than ``SETTLED_REL``."""
        if [i.flank for i in self.impacts] != [i.flank for i in before.impacts]:
            return math.inf
        change = 0.0
        for now, then in zip(self.impacts, before.impacts):
            if abs(now.velocity_m_s - then.velocity_m_s) > SETTLED_REL * abs(then.velocity_m_s):
                return math.inf
            change = max(change, abs(now.angle_deg - then.angle_deg))
        return change


def groove_turns(program: Program, rpm, *, turns: int | None = None,
                 progress: bool | None = None) -> list[GrooveTurn]:
    """The settled turn at every speed: turns from rest until the strikes of the last two
    agree (``GrooveTurn.settled``; doubling the turns from ``settling_turns``, up to
    ``MAX_TURNS`` and as long as a run stays within ``MAX_GROOVE_SAMPLES``), or exactly
    ``turns`` turns when given.  A first run past ``MAX_GROOVE_SAMPLES`` is a ``ValueError``
    before any work, naming the speed, stiffness or damping to change.  ``progress``: a bar
    on stderr (``None``: on a terminal, where the work is long).

    Needs a form-closed follower with ``groove_clearance_mm``.  One compiled solve serves
    every speed with the same turn count (the model's numbers are traced).  A run that has
    not settled by ``MAX_TURNS`` (a roller that chatters without a period) is returned with
    its ``change_deg`` (a roller that chatters in a wide groove, ``groove_clearance_mm``);
    the command line warns about it.
    """
    rpm = Speeds.of(rpm).rpm
    from ..models import Backlash, solve

    f = program.follower
    if not (f.form_closed and f.groove_clearance_mm):
        raise ValueError("groove impacts need a form-closed follower with groove_clearance_mm > 0")
    if not f.damping_ratio > 0:
        raise ValueError("groove impacts need follower.damping_ratio > 0 (the start-up must settle)")
    h = stroke_mm(program)
    samples = _samples_per_turn(program, float(rpm.min()))
    first = settling_turns(program, float(rpm.max())) if turns is None else max(2, int(turns))
    _check_work(program, rpm, samples, first, turns is not None)
    most = max(first, min(MAX_TURNS, MAX_GROOVE_SAMPLES // samples))  # turns of the longest run

    def run(r: float, count: int) -> GrooveTurn:
        period = 60.0 / r
        model = Backlash(f.vibrations_per_turn(r), f.groove_clearance_mm / h, 0.0, f.damping_ratio)
        response = solve(TurnLaw.of(program, h, count), model.with_array_leaves(), dwell=count - 1,
                         samples=samples, max_segments=64 * count)  # a failure is a SolverError
        last, before = (GrooveTurn.from_response(r, response, count, f.mass_kg, 1e-3 * h, period, turn=k)
                        for k in (count - 1, count - 2))
        return dataclasses.replace(last, change_deg=last.change_from(before))

    out = []
    if progress is None:  # on a terminal, where the work is long
        progress = sys.stderr.isatty() and first * samples * rpm.size > 20_000
    with tqdm(total=rpm.size, desc="groove", unit="speed", disable=not progress, file=sys.stderr) as bar:
        for r in map(float, rpm):
            count = first  # the same count at every speed: one compiled solve
            bar.set_postfix_str(f"{r:g} rpm, {count} turns")
            try:
                turn = run(r, count)
            except SolverError as error:
                raise SolverError(f"the grooved cam at {r:g} rpm: the strikes could not be followed over "
                                  f"{count} turns ({error}); a narrower groove (groove_clearance_mm), more "
                                  "damping or --no-flight") from None
            while turns is None and not turn.settled and 2 * count <= most:
                count *= 2
                bar.set_postfix_str(f"{r:g} rpm, {count} turns")
                try:
                    turn = run(r, count)
                except SolverError:  # the longer run failed: the last one is reported, unsettled
                    break
            out.append(turn)
            bar.update()
    return out


def _samples_per_turn(program: Program, rpm: float) -> int:
    return _SAMPLES_PER_PERIOD * math.ceil(program.follower.vibrations_per_turn(rpm))


def _check_work(program: Program, rpm: np.ndarray, samples: int, first: int, given: bool) -> None:
    """Refuse, before any work, a first run past ``MAX_GROOVE_SAMPLES``, saying what to change."""
    if first * samples <= MAX_GROOVE_SAMPLES:
        return
    f = program.follower
    cycles = f.vibrations_per_turn(float(rpm.min()))
    if given:
        raise ValueError(f"{first} groove turns at {samples:,} samples a turn (the follower vibrates "
                         f"{cycles:.0f} times a turn at {rpm.min():g} rpm) are {first * samples:,} samples; "
                         f"the limit is {MAX_GROOVE_SAMPLES:,}: ask for at most "
                         f"{max(2, MAX_GROOVE_SAMPLES // samples)} turns")
    # The slowest speed whose first run fits, the others as they are.
    fits = next((x for x in np.geomspace(rpm.min(), 100 * rpm.max(), 2000)
                 if _samples_per_turn(program, x) * settling_turns(program, max(x, rpm.max())) <= MAX_GROOVE_SAMPLES),
                None)
    faster = f"run at {fits:.3g} rpm or faster, " if fits is not None else ""
    raise ValueError(
        f"the grooved cam at {rpm.min():g} rpm: the follower vibrates {cycles:.0f} times a turn "
        f"({samples:,} samples a turn) and its contact vibration (damping_ratio {f.damping_ratio:g}) "
        f"needs {first} turns from rest to settle: {first * samples:,} samples, past the "
        f"{MAX_GROOVE_SAMPLES:,} a groove run may take (minutes of work); {faster}lower "
        "follower.stiffness_n_per_mm or raise follower.damping_ratio, or leave out the groove's "
        "strikes (camjax program --no-flight)")
