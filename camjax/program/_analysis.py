"""The per-speed report of a program: what ``camjax program`` prints and writes."""

from __future__ import annotations

import csv
import dataclasses
import io
import json

import numpy as np

from .._plain import json_ready, plot_speed
from ._dynamics import CheckedSpeed, SteadyState, check_rpm
from ._groove import Impact, groove_turns_checked
from ._jump import Flight, _Turns, flights_checked, jump_speed_checked, min_preload_n
from ._machine import (
    DEFAULT_SPEED_FLUCTUATION,
    Geometry,
    RefinedStress,
    cam_geometry,
    check_speed_fluctuation,
    design_warnings,
    flywheel_inertia_kg_m2,
    refined_contact_stress,
)
from ._motion import Join, segment_kinematics
from ._probes import OUTPUTS, Probe
from ._spec import Program


def kinematic_acceleration_m_s2(program: Program, rpm) -> np.ndarray:
    """``max |y''|`` over the turn at each speed, exactly: ``|lift| Ca / t_segment^2``."""
    return _kinematic(program, check_rpm(rpm))


def period_ratios(program: Program, rpm) -> np.ndarray:
    """``(speeds, moving segments)``: each segment's duration times the natural frequency."""
    return _period_ratios(program, check_rpm(rpm))


def _kinematic(program: Program, rpm: np.ndarray) -> np.ndarray:
    peak = max((abs(s.lift_mm) * float(s.law.Ca) / (s.angle_deg / 360.0) ** 2 for s in program.segments if s.moving),
               default=0.0)
    return 1e-3 * peak * (rpm / 60.0) ** 2


def _period_ratios(program: Program, rpm: np.ndarray) -> np.ndarray:
    fractions = np.array([program.segments[i].angle_deg / 360.0 for i in program.moving_segments()])
    return program.follower.vibrations_per_turn(rpm)[:, None] * fractions[None, :]


@dataclasses.dataclass(frozen=True)
class SpeedReport:
    """The periodic steady state of a program at one speed (SI units; see ``analyse``).

    Attributes:
        rpm: the cam's speed.
        max_payload_acceleration_m_s2, max_kinematic_acceleration_m_s2: peak ``|x''|`` of
            the payload (refined between nodes) and ``|y''|`` of the cam.
        min_contact_force_n, max_contact_force_n: extremes of the contact force over the
            turn (for a form-closed cam the signed flank force).
        jump: whether the contact force goes negative (a spring-loaded cam only).
        min_preload_n: the preload that just keeps contact (``None`` when form-closed).
        residual_vibration_mm: amplitude of the free vibration at the start of each dwell
            and constant-velocity segment (``Program.residual_segments``), in program order.
        period_ratios: each moving segment's duration times the natural frequency.
        flights: every flight of the turn where contact is lost (``None`` where it holds).
        impacts: a grooved cam's strikes on its flanks in a settled turn (else ``None``).
        impacts_change_deg: how far the strikes still moved from the turn before (degrees;
            at most ``camjax.program.SETTLED_DEG`` once settled; ``None`` without a groove).
        max_drive_torque_n_m, rms_drive_torque_n_m, mean_drive_torque_n_m: peak ``|T|``, RMS
            and mean of the camshaft torque ``T = F_c dy/dtheta`` over the turn.
        energy_fluctuation_j: ``max W - min W``, ``W = integral of (T - mean T) dtheta``.
        flywheel_inertia_kg_m2: ``energy_fluctuation / (Cs Omega^2)`` (``Report.speed_fluctuation``).
        max_contact_stress_mpa, max_contact_stress_deg: peak Hertz line-contact pressure over
            the turn, refined between the grid's nodes, and where (``None`` without
            ``follower.contact_width_mm``; ``camjax.program.refined_contact_stress``).
        contact_half_width_mm: the Hertz contact half-width there, ``2 R' p_max / E*``.
        outputs: the registered probes' values (``camjax.program.register_probe``), also
            read as attributes (``speed.rms_contact_force_n``) and flat in ``as_dict``.

    Every scalar field above but ``rpm`` is a built-in output of ``camjax.program.OUTPUTS``
    (its label, unit and doc line), read from there by the table and the CSV.
    """

    rpm: float
    max_payload_acceleration_m_s2: float
    max_kinematic_acceleration_m_s2: float
    min_contact_force_n: float
    max_contact_force_n: float
    jump: bool
    min_preload_n: float | None
    residual_vibration_mm: tuple[float, ...]
    period_ratios: tuple[float, ...]
    flights: tuple[Flight, ...] | None = None
    impacts: tuple[Impact, ...] | None = None
    impacts_change_deg: float | None = None
    max_drive_torque_n_m: float = 0.0
    rms_drive_torque_n_m: float = 0.0
    mean_drive_torque_n_m: float = 0.0
    energy_fluctuation_j: float = 0.0
    flywheel_inertia_kg_m2: float = 0.0
    max_contact_stress_mpa: float | None = None
    max_contact_stress_deg: float | None = None
    contact_half_width_mm: float | None = None
    outputs: dict[str, float] = dataclasses.field(default_factory=dict)

    def __getattr__(self, name):  # a registered probe's value, as an attribute
        outputs = self.__dict__.get("outputs", {})
        if name in outputs:
            return outputs[name]
        raise AttributeError(f"{type(self).__name__} has no attribute {name!r} (outputs: "
                             f"{', '.join(outputs) or 'none registered'})")

    @property
    def flight(self) -> Flight | None:
        """The first flight of the turn, or ``None``."""
        return self.flights[0] if self.flights else None

    def as_dict(self) -> dict:
        """Plain types for JSON, with ``flight`` (the first flight) beside ``flights``."""
        flights = None if self.flights is None else [x.as_dict() for x in self.flights]
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "outputs"}
        out.update(self.outputs)
        out.update(residual_vibration_mm=list(self.residual_vibration_mm),
                   period_ratios=list(self.period_ratios), flight=flights[0] if flights else None,
                   flights=flights,
                   impacts=None if self.impacts is None else [x.as_dict() for x in self.impacts])
        return out


@dataclasses.dataclass(frozen=True)
class Report:
    """A program's report over a list of speeds: one ``SpeedReport`` each, and the jump
    speed, the lowest speed in the range at which contact is lost (``None`` if contact
    holds over the whole range, or if it is lost already at the lowest speed given: then
    ``jump_below_range`` is true and the jump speed lies below the range); ``segments``
    (``segment_kinematics``) and ``joins`` (``Program.joins``) describe the motion itself,
    at any speed; the cam's ``Geometry`` and the coefficient of speed fluctuation the
    flywheel is sized for.  ``to_json`` and ``to_csv`` write it as ``camjax program`` prints
    it, its per-speed columns read from the registry ``OUTPUTS`` (``columns``)."""

    program: str
    speeds: tuple[SpeedReport, ...]
    jump_speed_rpm: float | None
    jump_below_range: bool = False
    segments: tuple[dict, ...] = ()
    joins: tuple[Join, ...] = ()
    geometry: Geometry | None = None
    speed_fluctuation: float = DEFAULT_SPEED_FLUCTUATION
    warnings: tuple[str, ...] = ()  # design_warnings: input or results past the design rules

    def as_dict(self) -> dict:
        return {"program": self.program, "speeds": [s.as_dict() for s in self.speeds],
                "jump_speed_rpm": self.jump_speed_rpm, "jump_below_range": self.jump_below_range,
                "segments": list(self.segments), "joins": [j.as_dict() for j in self.joins],
                "geometry": None if self.geometry is None else self.geometry.as_dict(),
                "speed_fluctuation": self.speed_fluctuation, "warnings": list(self.warnings)}

    def columns(self) -> tuple[Probe, ...]:
        """The per-speed outputs this report holds, in the registry's order (``OUTPUTS``):
        every built-in one and the probes registered when it was computed."""
        held = self.speeds[0].outputs if self.speeds else {}
        return tuple(p for p in OUTPUTS.values() if p.built_in or p.name in held)

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


def analyse(program: Program, rpm, *, with_flight: bool = True, steady: SteadyState | None = None,
            devices=None, speed_fluctuation: float = DEFAULT_SPEED_FLUCTUATION) -> Report:
    """The steady-state report at every speed in ``rpm`` (see docs/program.md).

    Every field but ``flights`` and ``impacts`` is the periodic steady state with contact
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
    """
    return analyse_checked(program, check_rpm(rpm), with_flight=with_flight, steady=steady,
                           devices=devices, speed_fluctuation=speed_fluctuation)  # an implausible speed: in warnings


def analyse_checked(program: Program, rpm: np.ndarray, *, with_flight: bool = True,
                    steady: SteadyState | None = None, devices=None,
                    speed_fluctuation: float = DEFAULT_SPEED_FLUCTUATION) -> Report:
    """``analyse`` at speeds already checked (``check_rpm``): the machine's cams."""
    speed_fluctuation = check_speed_fluctuation(speed_fluctuation)
    steady = steady or SteadyState(program, CheckedSpeed(rpm.min()), devices=devices)
    out = steady.summary_checked(rpm)
    closed = program.follower.form_closed
    preload = min_preload_n(out.min_contact_force_n, program.follower.preload_n)
    kinematic = _kinematic(program, rpm)  # rpm is checked once, above
    ratios = _period_ratios(program, rpm)
    grooved = closed and bool(program.follower.groove_clearance_mm) and with_flight
    turns = groove_turns_checked(program, rpm) if grooved else [None] * rpm.size
    flywheel = flywheel_inertia_kg_m2(out.energy_fluctuation_j, rpm, speed_fluctuation)
    stressed = program.follower.contact_width_mm is not None
    theta_nodes = 360.0 * steady.grid.nodes
    lost = np.flatnonzero(out.min_contact_force_n < 0) if with_flight and not closed else np.zeros(0, int)
    found = dict(zip(lost.tolist(), flights_checked(steady, rpm[lost]) if lost.size else []))
    if stressed:  # the largest Hertz stress refined between the nodes, as the force's peaks are
        refined = max_contact_stress(steady, rpm)
        stress, stress_deg = refined.stress_mpa, refined.angle_deg
        half_width = 2 * refined.radius_mm * stress / program.materials.contact_modulus_mpa
    computed = {  # each built-in output of the registry (OUTPUTS) at every speed
        "max_payload_acceleration_m_s2": out.max_payload_acceleration_m_s2,
        "max_kinematic_acceleration_m_s2": kinematic,
        "min_contact_force_n": out.min_contact_force_n,
        "max_contact_force_n": out.max_contact_force_n,
        "min_preload_n": None if closed else preload,
        "jump": None if closed else out.min_contact_force_n < 0,
        "max_drive_torque_n_m": out.max_drive_torque_n_m,
        "rms_drive_torque_n_m": out.rms_drive_torque_n_m,
        "mean_drive_torque_n_m": out.mean_drive_torque_n_m,
        "energy_fluctuation_j": out.energy_fluctuation_j,
        "flywheel_inertia_kg_m2": flywheel,
        "max_contact_stress_mpa": stress if stressed else None,
        "max_contact_stress_deg": stress_deg if stressed else None,
        "contact_half_width_mm": half_width if stressed else None,
    }
    built_in = {p.name: computed[p.name] for p in OUTPUTS.values() if p.built_in}
    speeds = []
    for i, r in enumerate(rpm):
        values = {name: None if v is None else v[i].item() for name, v in built_in.items()}
        values["jump"] = bool(values["jump"])  # false for a form-closed cam
        speeds.append(SpeedReport(
            rpm=float(r),
            **values,
            residual_vibration_mm=tuple(float(v) for v in out.residual_vibration_mm[i]),
            period_ratios=tuple(float(v) for v in ratios[i]),
            flights=tuple(found[i]) if i in found else None,
            impacts=None if turns[i] is None else tuple(turns[i].impacts),
            impacts_change_deg=None if turns[i] is None else turns[i].change_deg,
            outputs={name: float(values[i]) for name, values in out.probes.items()},
        ))
    jump_speed = None
    below = not closed and bool(out.min_contact_force_n[np.argmin(rpm)] < 0)
    if not closed and not below and rpm.size > 1 and rpm.max() > rpm.min():
        jump_speed = jump_speed_checked(steady, float(rpm.min()), float(rpm.max()))
    geometry = cam_geometry(program, np.union1d(theta_nodes[:-1], np.arange(3600) * 0.1))
    report = Report(program.name, tuple(speeds), jump_speed, below, tuple(segment_kinematics(program)),
                    tuple(program.joins()), geometry, speed_fluctuation)
    return dataclasses.replace(report, warnings=tuple(design_warnings(program, report)))


def max_contact_stress(steady: SteadyState, rpm) -> RefinedStress:
    """The largest Hertz stress of the steady state at every speed of ``rpm``, where and its
    effective radius, refined between the grid's nodes (``refined_contact_stress``) with the
    contact force exact anywhere (the steady state's own step between nodes)."""
    rpm = check_rpm(rpm)
    held = _Turns(steady, rpm)  # the contact-held steady states, exact at any time
    return refined_contact_stress(steady.program, steady.grid.nodes, steady.cycles_at_checked(rpm).contact_stress_mpa,
                                  lambda rows, s: held.contact_force(rows, s * held.period[rows]))


def response(program: Program, rpm: float, *, steady: SteadyState | None = None) -> dict[str, np.ndarray]:
    """Steady state over one turn at ``rpm``, at the grid nodes (law breakpoints included).

    Keys: ``theta_deg``, ``lift_mm``, ``payload_displacement_mm``, ``kinematic_acceleration_m_s2``
    (``y''``), ``payload_acceleration_m_s2`` (``x''``), ``contact_force_n``,
    ``drive_torque_n_m`` (``F_c dy/dtheta``) and ``contact_stress_mpa`` (Hertz, zero without
    ``follower.contact_width_mm`` and where contact is lost).
    """
    rpm = float(check_rpm(rpm)[0])
    steady = steady or SteadyState(program, CheckedSpeed(rpm))
    cycle = steady.cycle_checked(rpm)
    g = steady.grid
    theta = 360.0 * g.nodes
    y, _, ddy = program.lift(theta)
    deflection = np.imag(cycle.q) / float(np.imag(steady.lam(rpm)))
    return {
        "theta_deg": theta,
        "lift_mm": y,
        "payload_displacement_mm": y - deflection,
        "kinematic_acceleration_m_s2": 1e-3 * ddy * (360.0 * rpm / 60.0) ** 2,
        "payload_acceleration_m_s2": cycle.payload_acceleration_m_s2,
        "contact_force_n": cycle.contact_force_n,
        "drive_torque_n_m": cycle.drive_torque_n_m,
        "contact_stress_mpa": cycle.contact_stress_mpa,
    }
