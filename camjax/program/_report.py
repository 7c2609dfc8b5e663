"""The per-speed report of a program: what ``camjax program`` prints and writes."""

from __future__ import annotations

import csv
import dataclasses
import io
import json

import numpy as np

from .._plain import json_ready, plot_speed
from ._arm_report import arm_section
from ._chain_contacts import ChainContacts, simulated_train
from ._contact import Geometry, RefinedStress, cam_geometry, refined_contact_stress
from ._cycle import node_outputs
from ._dynamics import SteadyState
from ._groove import Impact, groove_turns
from ._jump import Flight, _Turns, flights_at, jump_speed_rpm
from ._motion import Join, segment_kinematics
from ._oscillator import PAYLOAD_DISPLACEMENT, output_rows
from ._outputs import BUILT_IN_OUTPUTS, Outputs, Probe, ProbeContext, kinematic_peak_m_s2
from ._program import Program
from ._speeds import Speeds
from ._torque import DEFAULT_SPEED_FLUCTUATION, check_speed_fluctuation
from ._warnings import design_warnings


def kinematic_acceleration_m_s2(program: Program, rpm) -> np.ndarray:
    """``max |y''|`` over the turn at each speed, exactly: ``|lift| Ca / t_segment^2``."""
    return kinematic_peak_m_s2(program, Speeds.of(rpm).rpm)


def period_ratios(program: Program, rpm) -> np.ndarray:
    """``(speeds, moving segments)``: each segment's duration times the natural frequency."""
    return _period_ratios(program, Speeds.of(rpm).rpm)


def _period_ratios(program: Program, rpm: np.ndarray) -> np.ndarray:
    fractions = np.array([program.segments[i].angle_deg / 360.0 for i in program.moving_segments()])
    return program.follower.vibrations_per_turn(rpm)[:, None] * fractions[None, :]


@dataclasses.dataclass(frozen=True)
class SpeedReport:
    """The periodic steady state of a program at one speed (SI units; see ``analyse``).

    Attributes:
        rpm: the cam's speed.
        values: every per-speed output of the set the report was computed with
            (``Outputs``: name -> value, ``None`` where it does not apply), also read as
            attributes (``speed.min_contact_force_n``); the built-in ones are documented in
            ``camjax.program.BUILT_IN_OUTPUTS`` (label, unit, doc line).
        residual_vibration_mm: amplitude of the free vibration at the start of each dwell
            and constant-velocity segment (``Program.residual_segments``), in program order.
        period_ratios: each moving segment's duration times the natural frequency.
        flights: every flight of the turn where contact is lost (``None`` where it holds).
        impacts: a grooved cam's strikes on its flanks in a settled turn (else ``None``).
        impacts_change_deg: how far the strikes still moved from the turn before (degrees;
            at most ``camjax.program.SETTLED_DEG`` once settled; ``None`` without a groove).
    """

    rpm: float
    values: dict
    residual_vibration_mm: tuple[float, ...] = ()
    period_ratios: tuple[float, ...] = ()
    flights: tuple[Flight, ...] | None = None
    impacts: tuple[Impact, ...] | None = None
    impacts_change_deg: float | None = None

    def __getattr__(self, name):  # an output's value, as an attribute
        values = self.__dict__.get("values", {})
        if name in values:
            return values[name]
        raise AttributeError(f"{type(self).__name__} has no attribute {name!r} (outputs: "
                             f"{', '.join(values) or 'none'})")

    @property
    def flight(self) -> Flight | None:
        """The first flight of the turn, or ``None``."""
        return self.flights[0] if self.flights else None

    def as_dict(self) -> dict:
        """Plain types for JSON: ``rpm``, every output flat, the lists, and ``flight`` (the
        first flight) beside ``flights``."""
        flights = None if self.flights is None else [x.as_dict() for x in self.flights]
        return {"rpm": self.rpm, **self.values, "residual_vibration_mm": list(self.residual_vibration_mm),
                "period_ratios": list(self.period_ratios), "flights": flights,
                "impacts": None if self.impacts is None else [x.as_dict() for x in self.impacts],
                "impacts_change_deg": self.impacts_change_deg, "flight": flights[0] if flights else None}


@dataclasses.dataclass(frozen=True)
class Report:
    """A program's report over a list of speeds: one ``SpeedReport`` each, and the jump
    speed, the lowest speed in the range at which contact is lost (``None`` if contact
    holds over the whole range, or if it is lost already at the lowest speed given: then
    ``jump_below_range`` is true and the jump speed lies below the range); ``segments``
    (``segment_kinematics``) and ``joins`` (``Program.joins``) describe the motion itself,
    at any speed; the cam's ``Geometry`` and the coefficient of speed fluctuation the
    flywheel is sized for.  ``to_json`` and ``to_csv`` write it as ``camjax program`` prints
    it, its per-speed columns read from the set of outputs it was computed with
    (``outputs``, ``columns``).  ``train``: a program with a chain of bodies
    (``Program.chain``): its natural frequencies, harmonic check, per-speed
    ``ChainSummary`` and jump speed (``train_section``; its ``note`` says what the rows
    mean for the chain), else ``None``."""

    program: str
    speeds: tuple[SpeedReport, ...]
    jump_speed_rpm: float | None
    jump_below_range: bool = False
    segments: tuple[dict, ...] = ()
    joins: tuple[Join, ...] = ()
    geometry: Geometry | None = None
    speed_fluctuation: float = DEFAULT_SPEED_FLUCTUATION
    warnings: tuple[str, ...] = ()  # design_warnings: input or results past the design rules
    outputs: Outputs = BUILT_IN_OUTPUTS  # the per-speed outputs computed
    train: dict | None = None

    def as_dict(self) -> dict:
        train = {} if self.train is None else {"train": self.train}
        return {"program": self.program, "speeds": [s.as_dict() for s in self.speeds],
                "jump_speed_rpm": self.jump_speed_rpm, "jump_below_range": self.jump_below_range,
                "segments": list(self.segments), "joins": [j.as_dict() for j in self.joins],
                "geometry": None if self.geometry is None else self.geometry.as_dict(),
                "speed_fluctuation": self.speed_fluctuation, "warnings": list(self.warnings), **train}

    def columns(self) -> tuple[Probe, ...]:
        """The per-speed outputs this report holds, in order: every built-in one and the
        probes of the set it was computed with."""
        return tuple(self.outputs.values())

    def to_json(self) -> str:
        """The report as JSON text (``camjax program --format json``, ``summary.json``):
        ``as_dict`` with inf and NaN as null."""
        return json.dumps(json_ready(self.as_dict()), indent=1)

    def to_csv(self) -> str:
        """One row per speed (``camjax program --format csv``): ``rpm``, every column of
        ``columns`` (empty where there is no value), each moving segment's period ratio,
        each residual vibration, and the jump speed."""
        buffer = io.StringIO()
        writer = csv.writer(buffer)
        keys = ["rpm"] + [p.name for p in self.columns()]
        first = self.speeds[0]
        writer.writerow(keys + [f"period_ratio_{i + 1}" for i in range(len(first.period_ratios))]
                        + [f"residual_vibration_mm_{i + 1}" for i in range(len(first.residual_vibration_mm))]
                        + ["jump_speed_rpm", "jump_below_range"])
        for s in self.speeds:
            writer.writerow([_blank(getattr(s, k)) for k in keys] + list(s.period_ratios)
                            + list(s.residual_vibration_mm) + [self.jump_speed_rpm or "", self.jump_below_range])
        return buffer.getvalue().rstrip()

    def plot_rpm(self, chosen: float | None = None) -> float:
        """The speed whose turn the figures draw: ``chosen``, else the speed given nearest
        the jump speed (the lowest when the jump lies below the range), else the highest."""
        return plot_speed(self, chosen)


def _blank(value):
    return "" if value is None else value


def steady_state(program: Program, rpm) -> SteadyState | ChainContacts:
    """The steady state that ``analyse``, ``response`` and the report's files read for
    ``program`` at the speeds ``rpm`` (from the slowest up): a chain with lash or a seat
    (``Chain.has_contacts``) simulated (``ChainContacts``, which keeps its turns), else the
    exact one (``SteadyState``)."""
    chain = program.chain
    if chain is not None and chain.has_contacts:
        return ChainContacts(program, chain, Speeds.of(rpm).min())
    return SteadyState(program, rpm)


def analyse(program: Program, rpm, *, with_flight: bool = True,
            steady: SteadyState | ChainContacts | None = None,
            devices=None, speed_fluctuation: float = DEFAULT_SPEED_FLUCTUATION,
            outputs: Outputs = BUILT_IN_OUTPUTS) -> Report:
    """The steady-state report at every speed in ``rpm`` (see docs/program.md).

    Every output but ``flights`` and ``impacts`` is the periodic steady state with contact
    held (linear); where that says contact is lost, ``flights`` lists every flight of the
    turn from the event simulation (``None`` where contact holds).  For a form-closed cam
    ``min_contact_force_n`` is the signed flank force (negative: the outer wall pushes),
    ``jump`` is false and ``min_preload_n`` is ``None``; with a groove clearance
    ``impacts`` lists the roller's strikes on the flanks in one settled turn (the
    ``Backlash`` hand-over, ``camjax.program.groove_turns``).  The speeds are split over
    ``devices`` (``SteadyState``) when no ``steady`` is given.  The drive torque, energy
    fluctuation and flywheel (for ``speed_fluctuation`` ``Cs``) and the Hertz stress come
    from the same steady state; ``geometry`` from the profile at the grid's nodes and 3600
    angles over the turn (a flat face over a cusp is a ``ValueError`` naming the angles).
    ``rpm``: ``Speeds`` or what one is built from; an implausible speed is warned of
    (in the report's warnings).  ``outputs``: the per-speed outputs (``Outputs``, or a list of
    ``probe``s beside the built-in ones; default ``BUILT_IN_OUTPUTS``).  A chain with lash
    or a seat is simulated (``ChainContacts``; ``steady``, where given, is that simulation,
    which keeps its turns for ``response``).
    """
    speeds = Speeds.of(rpm)  # an implausible speed is said in the report's warnings
    rpm = speeds.rpm
    outputs = Outputs.of(outputs)
    speed_fluctuation = check_speed_fluctuation(speed_fluctuation)
    if program.chain is not None and program.chain.has_contacts:  # lash or a seat: simulated
        return _contacts_analysis(program, speeds, outputs, speed_fluctuation, steady)
    steady = steady or SteadyState(program, speeds, devices=devices)
    out = steady.summary(speeds, outputs)
    closed = program.follower.form_closed
    theta_nodes = 360.0 * steady.grid.nodes
    stress = (max_contact_stress(steady, speeds)
              if program.follower.contact_width_mm is not None else None)
    values = outputs.evaluate(out.values, ProbeContext(program, rpm, speed_fluctuation, theta_nodes, out.cycles,
                                                       stress))
    ratios = _period_ratios(program, rpm)
    grooved = closed and bool(program.follower.groove_clearance_mm) and with_flight
    turns = groove_turns(program, speeds) if grooved else [None] * rpm.size
    simulated = with_flight and not closed
    lost = np.flatnonzero(values["jump"]) if simulated else np.zeros(0, int)
    found = dict(zip(lost.tolist(), flights_at(steady, speeds[lost]) if lost.size else []))
    rows = []
    for i, r in enumerate(rpm):
        rows.append(SpeedReport(
            rpm=float(r),
            values={name: None if v is None else np.asarray(v)[i].item() for name, v in values.items()},
            residual_vibration_mm=tuple(float(v) for v in out.residual_vibration_mm[i]),
            period_ratios=tuple(float(v) for v in ratios[i]),
            flights=tuple(found[i]) if i in found else None,
            impacts=None if turns[i] is None else tuple(turns[i].impacts),
            impacts_change_deg=None if turns[i] is None else turns[i].change_deg,
        ))
    jump_speed = None
    below = not closed and bool(values["jump"][np.argmin(rpm)])
    if not closed and not below and rpm.size > 1 and rpm.max() > rpm.min():
        jump_speed = jump_speed_rpm(steady, speeds.min(), speeds.max())
    geometry = cam_geometry(program, np.union1d(theta_nodes[:-1], np.arange(3600) * 0.1))
    train = None if program.chain is None else train_section(program, out, rpm, jump_speed, below)
    if train is not None and program.chain.arm is not None:  # its bending's cam orders
        train["arm"] = arm_section(steady, out.cycles, rpm)
    report = Report(program.name, tuple(rows), jump_speed, below, tuple(segment_kinematics(program)),
                    tuple(program.joins()), geometry, speed_fluctuation, outputs=outputs, train=train)
    return dataclasses.replace(report, warnings=tuple(design_warnings(program, report)))


CHAIN_NOTE = (
    "a train: the rows are the chain's, through the same steady state as the one-body follower's "
    "(contact force, drive torque and Hertz stress at the cam; payload acceleration and residual "
    "vibration the last body's, the residual the envelope sum_j |g_j (xi_j - xi_j,static)| of its "
    "modes; period ratios at the first mode with the cam held); flights: where the steady state "
    "loses contact, the chain simulated with the cam's contact one-sided (ChainContacts) from the "
    "steady state, one period from its first separation"
)
ONE_BODY_NOTE = "a one-body train: the classic follower's rows are this chain's (the same numbers)"


SPRING_KEYS = ("min_seat_force_n", "max_seat_force_n", "max_surge_n")
"""The train rows' return-spring figures: ``None`` for a chain without one (form-closed)."""


def train_section(program: Program, summary, rpm: np.ndarray, jump: float | None, below: bool) -> dict:
    """The report's ``train`` section over the speeds ``rpm``: the natural frequencies held
    and free with their mode shapes, the harmonic check over the speed range, and per
    speed the train's own figures of the steady state (``TrainPeaks``), with the report's
    jump speed."""
    chain = program.chain
    peaks = summary.cycles.train
    speeds = [
        {
            "rpm": float(r),
            "min_contact_force_n": float(summary.cycles.min_contact_force_n[i]),
            "max_contact_force_n": float(summary.cycles.max_contact_force_n[i]),
            "max_acceleration_m_s2": dict(zip(chain.names, np.asarray(peaks.max_acceleration_m_s2[i]).tolist())),
            "max_lift_error_mm": float(peaks.max_lift_error_mm[i]),
            **({key: None for key in SPRING_KEYS} if chain.spring is None else {  # form-closed: no spring
                "min_seat_force_n": float(peaks.min_seat_force_n[i]),
                "max_seat_force_n": float(peaks.max_seat_force_n[i]),
                "max_surge_n": float(peaks.max_surge_n[i]),
            }),
        }
        for i, r in enumerate(rpm)
    ]
    return {
        "one_body": chain.spells_follower,
        "note": ONE_BODY_NOTE if chain.spells_follower else CHAIN_NOTE,
        **_train_modes(chain, rpm),
        "speeds": speeds,
        "jump_speed_rpm": jump,
        "jump_below_range": below,
    }


def _train_modes(chain, rpm: np.ndarray) -> dict:
    """The train section's bodies, natural frequencies held and free with their mode shapes,
    and the harmonic check over the speed range."""
    frequencies = {}
    for key, contact in (("held", True), ("free", False)):
        hz, shapes = chain.natural_frequencies(contact=contact)
        frequencies[f"natural_frequencies_{key}_hz"] = hz.tolist()
        frequencies[f"mode_shapes_{key}"] = shapes.T.tolist()  # one row per mode, over the bodies
    return {
        "bodies": list(chain.names),
        **frequencies,
        "harmonic_check": [
            {"frequency_hz": f, "orders": orders}
            for f, orders in chain.harmonic_check(float(rpm.min()), float(rpm.max()))
        ],
    }


def _contacts_analysis(program: Program, speeds: Speeds, outputs: Outputs, speed_fluctuation: float,
                       simulation: ChainContacts | None = None) -> Report:
    """``analyse`` of a chain with lash or a seat (``Chain.has_contacts``), simulated
    (``simulated_train``): the rows hold the contact force at the cam, jump (the cam
    separates), the last body's peak acceleration, the cam's own, the drive torque's figures
    with the flywheel and the Hertz stress, through the same output set as the exact path
    (``Outputs.evaluate``); the least preload is ``None`` (the seated chain's base-circle
    force is zero by design) and so is a compiled probe (it reads the exact ``Cycle``); the
    train section adds the ``contacts``."""
    rpm = speeds.rpm
    chain = program.chain
    summary, contacts, jump, below = simulated_train(program, chain, rpm, simulation=simulation)
    cam = np.array([s["separates"].get("cam", False) for s in contacts["speeds"]])
    simulated = {
        "max_payload_acceleration_m_s2": summary.max_acceleration_m_s2[:, -1],
        "min_contact_force_n": summary.min_contact_force_n,
        "max_contact_force_n": summary.max_contact_force_n,
        "max_drive_torque_n_m": summary.max_drive_torque_n_m,
        "rms_drive_torque_n_m": summary.rms_drive_torque_n_m,
        "mean_drive_torque_n_m": summary.mean_drive_torque_n_m,
        "energy_fluctuation_j": summary.energy_fluctuation_j,
    }
    compiled = {p.name: simulated.get(p.name) for p in outputs.compiled}
    context = ProbeContext(program, rpm, speed_fluctuation, None, None, summary.stress)
    known = {**outputs.evaluate(compiled, context), "jump": cam, "min_preload_n": None}
    rows = tuple(SpeedReport(rpm=float(r), values={
        name: None if known.get(name) is None else np.asarray(known[name])[i].item() for name in outputs},
        residual_vibration_mm=tuple(float(v) for v in summary.residual_vibration_mm[i]))
        for i, r in enumerate(rpm))
    section = {
        "one_body": False,
        "note": "a train with lash or a seat, simulated: the rows give the chain's contact force at the "
                "cam, jump (the cam separates), the last body's peak acceleration, the drive torque and the "
                "Hertz stress from the simulated contact force; the residual vibration the envelope of the last "
                "body's free vibration at each dwell's start over the modes of the contacts the dwell's static "
                "state closes (the closed chain's where the valve is lifted, the valve on its seat on the base "
                "circle); the contact force pushes only (its least value 0 where the cam carries nothing, "
                "separated or unloaded; noise below zero clipped); the least preload and user probes are "
                "not computed and left empty",
        **_train_modes(chain, rpm),
        "speeds": [
            {
                "rpm": float(r),
                "min_contact_force_n": float(summary.min_contact_force_n[i]),
                "max_contact_force_n": float(summary.max_contact_force_n[i]),
                "max_acceleration_m_s2": dict(zip(chain.names, summary.max_acceleration_m_s2[i].tolist())),
                "max_lift_error_mm": float(summary.max_lift_error_mm[i]),
                "min_seat_force_n": float(summary.min_seat_force_n[i]),
                "max_seat_force_n": float(summary.max_seat_force_n[i]),
                "max_surge_n": float(summary.max_surge_n[i]),
            }
            for i, r in enumerate(rpm)
        ],
        "jump_speed_rpm": jump,
        "jump_below_range": below,
        "contacts": contacts,
    }
    geometry = cam_geometry(program, np.union1d(program.start_deg, np.arange(3600) * 0.1))
    report = Report(program.name, rows, jump, below, tuple(segment_kinematics(program)), tuple(program.joins()),
                    geometry, speed_fluctuation, outputs=outputs, train=section)
    return dataclasses.replace(report, warnings=tuple(design_warnings(program, report)))


def max_contact_stress(steady: SteadyState, rpm) -> RefinedStress:
    """The largest Hertz stress of the steady state at every speed of ``rpm``, where and its
    effective radius, refined between the grid's nodes (``refined_contact_stress``) with the
    contact force exact anywhere (the steady state's own step between nodes)."""
    speeds = Speeds.of(rpm)
    held = _Turns(steady, speeds)  # the contact-held steady states, exact at any time
    stress = np.asarray(steady.cycles_at(speeds).contact_stress_mpa)
    return refined_contact_stress(steady.program, steady.grid.nodes, stress,
                                  lambda rows, s: held.contact_force(rows, s * held.period[rows]))


def response(program: Program, rpm: float, *, steady: SteadyState | ChainContacts | None = None
             ) -> dict[str, np.ndarray]:
    """Steady state over one turn at ``rpm``: every history of the follower, the one place
    that computes them (``camjax program --out``'s ``response.csv`` and figures, the studio).

    Keys: ``theta_deg``, ``lift_mm``, ``payload_displacement_mm``, ``kinematic_acceleration_m_s2``
    (``y''``), ``payload_acceleration_m_s2`` (``x''``, the last body's), ``contact_force_n``,
    ``drive_torque_n_m`` (``F_c dy/dtheta``) and ``contact_stress_mpa`` (Hertz, zero where
    contact is lost; absent without ``follower.contact_width_mm``, where none is computed), at the grid's nodes (law
    breakpoints included).  A program with a chain (``Program.chain``) adds every body's
    ``<name>_displacement_mm`` (from rest), ``<name>_velocity_m_s`` and
    ``<name>_acceleration_m_s2``, the return spring's force at its seat ``seat_force_n``, its
    surge ``surge_n`` (that force less the static ``F_0 + k_s x_N``) and the last body's
    distance from its kinematic lift ``lift_error_mm``.  A chain with lash or a seat is
    simulated (``steady``: its ``ChainContacts``, default one for ``rpm``): its histories
    are the settled turn's samples, with the valve's seat contact force
    ``seat_contact_force_n`` where it has a seat and no drive torque or contact stress.
    """
    rpm = Speeds.of(rpm)[0]
    chain = program.chain
    if chain is not None and chain.has_contacts:
        return _simulated_response(program, rpm, steady or ChainContacts(program, chain, rpm))
    steady = steady or SteadyState(program, rpm)
    cycle = steady.cycle(rpm)
    g = steady.grid
    theta = 360.0 * g.nodes
    y, _, ddy = program.lift(theta)
    osc = steady.oscillator
    values = np.asarray(node_outputs(g, cycle.q, rpm, osc.gain, osc.direct, osc.static))
    out = {
        "theta_deg": theta,
        "lift_mm": y,
        "payload_displacement_mm": values[PAYLOAD_DISPLACEMENT],
        "kinematic_acceleration_m_s2": 1e-3 * ddy * (360.0 * rpm / 60.0) ** 2,
        "payload_acceleration_m_s2": cycle.payload_acceleration_m_s2,
        "contact_force_n": cycle.contact_force_n,
        "drive_torque_n_m": cycle.drive_torque_n_m,
    }
    if program.follower.contact_width_mm is not None:  # else none computed (the JSON's null)
        out["contact_stress_mpa"] = cycle.contact_stress_mpa
    if chain is None:
        return out
    if osc.bodies != len(chain.bodies):
        raise ValueError("response: the steady state's oscillator has no train rows for the program's chain "
                         f"of {len(chain.bodies)} bodies (Oscillator.of(program) has them)")
    motion = np.asarray(node_outputs(g, cycle.q, rpm, osc.motion_gain, osc.motion_direct))
    rows = output_rows(osc.bodies)
    spring = {} if chain.spring is None else {  # form-closed: no spring, no seat force
        "seat_force_n": values[rows["seat_force_n"]], "surge_n": values[rows["surge_n"]]}
    return _with_bodies(out, chain, motion[: osc.bodies], motion[osc.bodies :], values[rows["acceleration_m_s2"]],
                        **spring, lift_error_mm=values[rows["lift_error_mm"]])


def _with_bodies(out: dict, chain, displacement, velocity, acceleration, **more) -> dict:
    """``out`` with every body's displacement, velocity and acceleration (rows over the
    bodies) under its name, then ``more``; a body's name that would repeat a key is a
    ``ValueError``."""
    for j, name in enumerate(chain.names):
        for what, rows in (("displacement_mm", displacement), ("velocity_m_s", velocity),
                           ("acceleration_m_s2", acceleration)):
            key = f"{name}_{what}"
            if key in out:
                raise ValueError(f"[[train]] body {j + 1} ({name}): its history {key!r} would repeat a "
                                 "column of the response: rename the body")
            out[key] = np.asarray(rows[j])
    return {**out, **more}


def _simulated_response(program: Program, rpm: float, simulation: ChainContacts) -> dict[str, np.ndarray]:
    """``response`` of a chain with lash or a seat: its settled turn's samples."""
    turn = simulation.turn(rpm)
    theta = turn.theta_deg
    ddy = program.lift(theta)[2]
    out = {
        "theta_deg": theta,
        "lift_mm": turn.lift_mm,
        "payload_displacement_mm": turn.last_mm,
        "kinematic_acceleration_m_s2": 1e-3 * ddy * (360.0 * rpm / 60.0) ** 2,
        "payload_acceleration_m_s2": turn.acceleration_m_s2[-1],
        "contact_force_n": turn.cam_force_n,
    }
    more = {"seat_force_n": turn.spring_seat_force_n, "surge_n": turn.surge_n,
            "lift_error_mm": turn.last_mm - simulation.kinematic_ratio * turn.lift_mm}
    if program.chain.seat is not None:
        more["seat_contact_force_n"] = turn.seat_contact_force_n
    return _with_bodies(out, program.chain, turn.displacement_mm, turn.velocity_m_s, turn.acceleration_m_s2,
                        **more)
