"""A servo drive and its motor: the motor's torque over a cam turn, its checks, a catalogue's pick.

A servo cam's follower is driven by a motor through a transmission: a screw or a belt (mm
of lift per revolution of the drive's input) or a rotary axis (degrees per revolution),
behind a gearbox (motor revolutions per drive revolution).  At a master speed the motor
turns ``phi_m = 2 pi y / p`` (``p`` the lift per motor revolution) and carries

    T_m = J alpha_m + F_c r / eta   (F_c v >= 0, motoring: the motor drives the train)
    T_m = J alpha_m + F_c r eta     (F_c v <  0, regenerating: the train drives the motor)

with ``r = p / (2 pi)`` (m of lift per radian of the motor), ``J`` the rotor, the motor-side
parts, the gearbox and the load-side parts (over the gear ratio squared), and ``F_c`` the
train's force at its input: the contact force of the dynamic periodic steady state
(``camjax.program.response``) or, beside it, the rigid ``m y'' + k_s y + F_0``.  Every figure
is over one turn at constant master speed (time is uniform in cam angle), by the trapezoid
rule over the steady state's nodes (every law breakpoint is one).
"""

from __future__ import annotations

import csv
import dataclasses
import math
from pathlib import Path

import numpy as np

from ..checks import finite_number, read_text, read_toml

RMS_SHARE_LIMIT = 0.8
"""Default thermal check: the RMS torque over the cycle at most this share of the
continuous (stall) torque."""
INERTIA_RATIO_LIMIT = 10.0
"""Default inertia-ratio check: the load's inertia reflected to the motor (everything but
the rotor, the train's mass as ``m r^2``) at most this many times the rotor's (5 for
precision axes)."""

MOTOR_FIELDS = (
    "name",
    "rated_speed_rpm",
    "maximum_speed_rpm",
    "rated_torque_n_m",
    "maximum_torque_n_m",
    "continuous_stall_torque_n_m",
    "torque_constant_n_m_per_a",
    "rotor_inertia_kg_m2",
    "envelope",
)
"""A motor record's fields: the OPC UA powertrain model's (rated and maximum speed; rated,
maximum and continuous stall torque; torque constant), the rotor inertia and an optional
torque-speed envelope; the columns of a catalogue CSV."""
_NEEDED = (
    "maximum_speed_rpm",
    "maximum_torque_n_m",
    "continuous_stall_torque_n_m",
    "rotor_inertia_kg_m2",
)
DRIVE_FIELDS = (
    "travel_mm_per_rev",
    "degrees_per_rev",
    "arm_mm",
    "gear_ratio",
    "gearbox_efficiency",
    "transmission_efficiency",
    "motor_side_inertia_kg_m2",
    "gearbox_inertia_kg_m2",
    "load_side_inertia_kg_m2",
)


def _positive(value, what: str) -> float:
    value = finite_number(value, what)
    if value <= 0:
        raise ValueError(f"{what} must be positive, got {value:g}")
    return value


def _non_negative(value, what: str) -> float:
    value = finite_number(value, what)
    if value < 0:
        raise ValueError(f"{what} must be non-negative, got {value:g}")
    return value


@dataclasses.dataclass(frozen=True)
class Drive:
    """The transmission from the motor to the follower.

    A linear drive gives ``travel_mm_per_rev`` (a screw's lead, a belt pulley's
    circumference: mm of lift per revolution of the drive's input); a rotary axis gives
    ``degrees_per_rev`` of the follower's swing and the arm that turns it into lift
    (``arm_mm``, else the follower's).  ``gear_ratio`` is motor revolutions per drive
    revolution; the efficiencies multiply.  Inertias in kg m^2: ``motor_side`` on the motor
    shaft (coupling, brake), ``gearbox`` referred to the motor shaft, ``load_side`` at the
    drive's input (screw, pulleys; divided by the gear ratio squared).
    """

    travel_mm_per_rev: float | None = None
    degrees_per_rev: float | None = None
    arm_mm: float | None = None
    gear_ratio: float = 1.0
    gearbox_efficiency: float = 1.0
    transmission_efficiency: float = 1.0
    motor_side_inertia_kg_m2: float = 0.0
    gearbox_inertia_kg_m2: float = 0.0
    load_side_inertia_kg_m2: float = 0.0

    def __post_init__(self):
        if (self.travel_mm_per_rev is None) == (self.degrees_per_rev is None):
            raise ValueError(
                "[drive] needs one of travel_mm_per_rev (a screw or belt) or degrees_per_rev "
                "(a rotary axis)"
            )
        for name in ("travel_mm_per_rev", "degrees_per_rev", "arm_mm"):
            if (
                getattr(self, name) is not None
                and finite_number(getattr(self, name), f"[drive] {name}") == 0
            ):
                raise ValueError(f"[drive] {name} is zero: a transmission of zero moves nothing")
        for name in ("travel_mm_per_rev", "degrees_per_rev", "arm_mm"):
            if getattr(self, name) is not None:
                _positive(getattr(self, name), f"[drive] {name}")
        if finite_number(self.gear_ratio, "[drive] gear_ratio") == 0:
            raise ValueError("[drive] gear_ratio is zero: a transmission of zero moves nothing")
        _positive(self.gear_ratio, "[drive] gear_ratio")
        for name in ("gearbox_efficiency", "transmission_efficiency"):
            value = finite_number(getattr(self, name), f"[drive] {name}")
            if not 0 < value <= 1:
                raise ValueError(f"[drive] {name} must be in (0, 1], got {value:g}")
        for name in (
            "motor_side_inertia_kg_m2",
            "gearbox_inertia_kg_m2",
            "load_side_inertia_kg_m2",
        ):
            _non_negative(getattr(self, name), f"[drive] {name}")

    @classmethod
    def from_dict(cls, data) -> Drive:
        if not isinstance(data, dict):
            raise ValueError("[drive] must be a table")
        unknown = sorted(set(data) - set(DRIVE_FIELDS))
        if unknown:
            raise ValueError(
                f"[drive]: unknown field(s) {', '.join(unknown)}; expected {', '.join(DRIVE_FIELDS)}"
            )
        return cls(**data)

    @property
    def efficiency(self) -> float:
        return self.gearbox_efficiency * self.transmission_efficiency

    def lift_mm_per_motor_rev(self, follower_arm_mm: float | None = None) -> float:
        """Lift (mm) per motor revolution: the drive's travel (or degrees times the arm) over
        the gear ratio."""
        if self.travel_mm_per_rev is not None:
            return self.travel_mm_per_rev / self.gear_ratio
        arm = self.arm_mm if self.arm_mm is not None else follower_arm_mm
        if arm is None:
            raise ValueError(
                "[drive] degrees_per_rev needs arm_mm (or a swinging follower's arm_mm) to turn "
                "the swing into lift"
            )
        return math.radians(self.degrees_per_rev) * arm / self.gear_ratio

    def rotating_inertia_kg_m2(self) -> float:
        """The drive's own inertia at the motor shaft (the rotor not included)."""
        return (
            self.motor_side_inertia_kg_m2
            + self.gearbox_inertia_kg_m2
            + self.load_side_inertia_kg_m2 / self.gear_ratio**2
        )

    def toml(self) -> str:
        return "\n".join(
            ["[drive]"]
            + [
                f"{f.name} = {getattr(self, f.name)!r}"
                for f in dataclasses.fields(self)
                if getattr(self, f.name) is not None
            ]
        )


@dataclasses.dataclass(frozen=True)
class Motor:
    """A servo motor: the OPC UA powertrain model's ratings, the rotor inertia, an envelope.

    ``envelope`` is the peak torque the motor gives at each speed, a polyline of
    ``(rpm, N m)`` points with speeds strictly increasing from 0 (a function of speed);
    without it the envelope is ``maximum_torque_n_m`` up to ``maximum_speed_rpm``.
    """

    name: str
    maximum_speed_rpm: float
    maximum_torque_n_m: float
    continuous_stall_torque_n_m: float
    rotor_inertia_kg_m2: float
    rated_speed_rpm: float | None = None
    rated_torque_n_m: float | None = None
    torque_constant_n_m_per_a: float | None = None
    envelope: tuple[tuple[float, float], ...] | None = None

    def __post_init__(self):
        where = f"motor {self.name!r}"
        for name in _NEEDED:
            _positive(getattr(self, name), f"{where}: {name}")
        for name in ("rated_speed_rpm", "rated_torque_n_m", "torque_constant_n_m_per_a"):
            if getattr(self, name) is not None:
                _positive(getattr(self, name), f"{where}: {name}")
        if self.envelope is not None:
            points = np.asarray(self.envelope, dtype=float)
            if (
                points.ndim != 2
                or points.shape[1] != 2
                or len(points) < 2
                or not np.all(np.isfinite(points))
            ):
                raise ValueError(f"{where}: envelope must be two or more finite [rpm, N m] points")
            if points[0, 0] != 0 or np.any(np.diff(points[:, 0]) <= 0):
                raise ValueError(
                    f"{where}: envelope is not a function of speed: its speeds must start at 0 and "
                    f"rise strictly, got {points[:, 0].tolist()}"
                )
            if np.any(points[:, 1] < 0):
                raise ValueError(f"{where}: envelope torques must be non-negative")
            object.__setattr__(self, "envelope", tuple(map(tuple, points.tolist())))

    @classmethod
    def from_dict(cls, data, where: str = "[motor]") -> Motor:
        if not isinstance(data, dict):
            raise ValueError(f"{where} must be a table")
        unknown = sorted(set(data) - set(MOTOR_FIELDS))
        if unknown:
            raise ValueError(
                f"{where}: unknown field(s) {', '.join(unknown)}; expected {', '.join(MOTOR_FIELDS)}"
            )
        name = str(data.get("name", "motor"))
        missing = [f for f in _NEEDED if f not in data]
        if missing:
            raise ValueError(
                f"{where} (motor {name!r}): missing {', '.join(missing)}, which the checks need"
            )
        try:
            return cls(**{**data, "name": name})
        except (TypeError, ValueError) as error:
            raise ValueError(f"{where}: {error}") from None

    def envelope_torque(self, rpm) -> np.ndarray:
        """Peak torque the motor gives at each speed (0 past its last speed or the maximum)."""
        rpm = np.abs(np.asarray(rpm, dtype=float))
        if self.envelope is None:
            return np.where(rpm <= self.maximum_speed_rpm, self.maximum_torque_n_m, 0.0)
        points = np.asarray(self.envelope)
        return np.where(rpm <= points[-1, 0], np.interp(rpm, points[:, 0], points[:, 1]), 0.0)

    def toml(self) -> str:
        lines = ["[motor]"]
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if value is None:
                continue
            if f.name == "envelope":
                value = [list(p) for p in value]
            lines.append(
                f'{f.name} = "{value}"' if isinstance(value, str) else f"{f.name} = {value!r}"
            )
        return "\n".join(lines)


def read_motors(path) -> tuple[Motor, ...]:
    """Motors from a TOML file (``[motor]`` or ``[[motor]]``) or a CSV catalogue (a header of
    ``MOTOR_FIELDS``; the envelope as ``rpm:Nm`` pairs separated by spaces), in listed order."""
    path = Path(path)
    try:
        if path.suffix.lower() == ".csv":
            return _read_catalogue(path)
        data = read_toml(path, "motor file")
        unknown = sorted(set(data) - {"motor"})
        if unknown or "motor" not in data:
            raise ValueError("a motor file holds [motor] (one) or [[motor]] tables (a catalogue)")
        records = data["motor"] if isinstance(data["motor"], list) else [data["motor"]]
        return tuple(
            Motor.from_dict(r, f"[motor] {i}" if len(records) > 1 else "[motor]")
            for i, r in enumerate(records, 1)
        )
    except ValueError as error:
        message = str(error)
        raise ValueError(
            message if message.startswith(str(path)) else f"{path}: {message}"
        ) from None


def _read_catalogue(path: Path) -> tuple[Motor, ...]:
    lines = [
        line
        for line in read_text(path, "motor catalogue", "CSV").splitlines()
        if line.strip() and not line.lstrip().startswith("#")
    ]
    rows = list(csv.DictReader(lines))
    if not rows:
        raise ValueError(
            "the catalogue lists no motor (a header row of field names, then one row per motor)"
        )
    motors = []
    for i, row in enumerate(rows, 2):
        where = f"row {i}"
        record = {}
        for key, text in row.items():
            if key is None:
                raise ValueError(f"{where}: more cells than the header names")
            key, text = key.strip(), (text or "").strip()
            if not text:
                continue
            if key == "name":
                record[key] = text
            elif key == "envelope":
                record[key] = _envelope_text(text, where)
            else:
                try:
                    record[key] = float(text)
                except ValueError:
                    raise ValueError(f"{where}: {key} = {text!r} is not a number") from None
        motors.append(Motor.from_dict(record, where))
    return tuple(motors)


def _envelope_text(text: str, where: str) -> list[list[float]]:
    try:
        return [[float(x) for x in pair.split(":")] for pair in text.split()]
    except ValueError:
        raise ValueError(
            f"{where}: envelope must be rpm:Nm pairs separated by spaces, got {text!r}"
        ) from None


@dataclasses.dataclass(frozen=True)
class Check:
    """One sizing check: ``value`` against ``limit`` (passes when ``value <= limit``);
    ``margin`` is ``1 - value / limit`` (negative: failed by that share)."""

    name: str
    value: float
    limit: float
    passed: bool
    margin: float

    @classmethod
    def of(cls, name: str, value: float, limit: float) -> Check:
        value, limit = float(value), float(limit)
        return cls(
            name, value, limit, value <= limit, 1.0 - value / limit if limit > 0 else -math.inf
        )

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)

    def shortfall(self) -> str:
        """How far a failed check misses, in words: ``"3.6 against 1 (by 260.0%)"``, or where
        the value has no bound (a torque asked at a speed past the envelope, where the motor
        gives none) that in place of ``inf``."""
        if not math.isfinite(self.value):
            return (
                f"no bound against {self.limit:.4g} (a torque asked at a speed past the envelope, "
                "where the motor gives none)"
            )
        return f"{self.value:.4g} against {self.limit:.4g} (by {-100 * self.margin:.1f}%)"

    def text(self) -> str:
        verdict = "passes" if self.passed else "FAILS"
        return f"{self.name} {verdict}: {self.value:.4g} against {self.limit:.4g} (margin {100 * self.margin:+.1f}%)"


@dataclasses.dataclass(frozen=True)
class MotorLoad:
    """The motor's duty over one turn for one force model (``"dynamic"`` or ``"rigid"``).

    Torques in N m at the motor shaft, speeds in rpm of the motor; ``points`` are the
    (speed, torque) pairs at every node; ``envelope_use`` the largest ``|T| / envelope(|n|)``;
    ``regenerated_energy_j`` the energy the train returns to the motor per turn
    (``integral of max(0, -T omega)``); ``thermal_use`` RMS over continuous stall torque.
    """

    model: str
    peak_torque_n_m: float
    rms_torque_n_m: float
    max_speed_rpm: float
    regenerated_energy_j: float
    thermal_use: float
    envelope_use: float
    checks: tuple[Check, ...]
    speed_rpm: np.ndarray
    torque_n_m: np.ndarray

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)

    @property
    def worst(self) -> Check:
        return min(self.checks, key=lambda c: c.margin)

    def as_dict(self, points: bool = True) -> dict:
        out = {
            f.name: getattr(self, f.name)
            for f in dataclasses.fields(self)
            if f.name not in ("checks", "speed_rpm", "torque_n_m")
        }
        out.update(passed=self.passed, checks=[c.as_dict() for c in self.checks])
        if points:
            out.update(points=np.stack([self.speed_rpm, self.torque_n_m], axis=1).tolist())
        return out


@dataclasses.dataclass(frozen=True)
class MotorSizing:
    """A motor against a program's duty at one master speed: the dynamic load (from the
    steady state) and the rigid one beside it, the inertia ratio and the limits used."""

    motor: Motor
    rpm: float
    inertia_ratio: float
    dynamic: MotorLoad
    rigid: MotorLoad
    rms_share_limit: float = RMS_SHARE_LIMIT
    inertia_ratio_limit: float = INERTIA_RATIO_LIMIT

    @property
    def passed(self) -> bool:
        return self.dynamic.passed

    def as_dict(self) -> dict:
        return {
            "motor": self.motor.name,
            "rpm": self.rpm,
            "inertia_ratio": self.inertia_ratio,
            "passed": self.passed,
            "rms_share_limit": self.rms_share_limit,
            "inertia_ratio_limit": self.inertia_ratio_limit,
            "dynamic": self.dynamic.as_dict(),
            "rigid": self.rigid.as_dict(),
        }


@dataclasses.dataclass(frozen=True)
class DutyCycle:
    """What the motor must do over one turn, independent of the motor: at the nodes
    ``theta_deg``, the motor's speed (rpm) and acceleration (rad/s^2), and the load torque
    at the motor shaft (train force through the transmission, efficiency applied) for the
    dynamic and the rigid force; ``load_inertia_kg_m2`` is everything but the rotor."""

    rpm: float
    theta_deg: np.ndarray
    motor_speed_rpm: np.ndarray
    motor_acceleration_rad_s2: np.ndarray
    dynamic_torque_n_m: np.ndarray
    rigid_torque_n_m: np.ndarray
    drive_inertia_kg_m2: float
    load_inertia_kg_m2: float


def duty_cycle(program, drive: Drive, rpm: float, response: dict) -> DutyCycle:
    """The motor's duty over one turn at master speed ``rpm`` (see the module's equations);
    ``response`` is the steady state there, ``camjax.program.response(program, rpm)``."""
    rpm = float(rpm)
    follower = program.follower
    theta, dynamic_force = _with_breakpoints(
        program,
        np.asarray(response["theta_deg"], dtype=float),
        np.asarray(response["contact_force_n"], dtype=float),
    )
    y, dy, ddy = program.lift(theta)
    omega_deg = 360.0 * rpm / 60.0  # cam degrees per second
    lift_per_rev = drive.lift_mm_per_motor_rev(follower.swing_arm_mm)
    r = 1e-3 * lift_per_rev / (2 * math.pi)  # m of lift per motor radian
    velocity = 1e-3 * dy * omega_deg  # m/s
    acceleration = 1e-3 * ddy * omega_deg**2
    rigid_force = (
        follower.mass_kg * acceleration + follower.spring_rate * 1e-3 * y + follower.preload_n
    )
    eta = drive.efficiency

    def through(force):  # motoring divides by the efficiency, regenerating multiplies
        return np.where(force * velocity >= 0, force * r / eta, force * r * eta)

    drive_inertia = drive.rotating_inertia_kg_m2()
    return DutyCycle(
        rpm,
        theta,
        60.0 * velocity / (2 * math.pi * r),
        acceleration / r,
        through(dynamic_force),
        through(rigid_force),
        drive_inertia,
        drive_inertia + follower.mass_kg * r**2,
    )


def _with_breakpoints(program, theta_deg: np.ndarray, force: np.ndarray):
    """The points of a history and its contact force with the motion's breakpoints added where
    it lacks them (the simulated chain's evenly spaced samples), the force interpolated
    linearly between its samples (it is continuous there): the torque steps at a breakpoint
    where the efficiency switches (a dwell's end) and the acceleration may jump, and the
    trapezoid rule is exact to its order only with a point there (the exact path's nodes
    hold every breakpoint already, and are kept as they are)."""
    breaks = np.mod(np.asarray(program.turn.breakpoints_deg(), dtype=float), 360.0)
    breaks = breaks[(breaks > theta_deg[0]) & (breaks < theta_deg[-1])]
    nearest = np.min(np.abs(breaks[:, None] - theta_deg[None, :]), axis=1, initial=np.inf)
    missing = np.unique(breaks[nearest > 1e-9])
    if not missing.size:
        return theta_deg, force
    theta = np.union1d(theta_deg, missing)
    return theta, np.interp(theta, theta_deg, force)


def _mean_over_turn(theta_deg: np.ndarray, values: np.ndarray) -> float:
    """Mean over the turn by the trapezoid rule on the nodes (the last node is 360)."""
    return float(np.trapezoid(values, theta_deg) / (theta_deg[-1] - theta_deg[0]))


def _load(
    model: str, motor: Motor, duty: DutyCycle, load_torque: np.ndarray, rms_share: float
) -> MotorLoad:
    torque = (
        motor.rotor_inertia_kg_m2 + duty.drive_inertia_kg_m2
    ) * duty.motor_acceleration_rad_s2 + load_torque
    speed = duty.motor_speed_rpm
    rms = math.sqrt(_mean_over_turn(duty.theta_deg, torque**2))
    power = torque * speed * (2 * math.pi / 60.0)
    turn_s = 60.0 / duty.rpm
    regenerated = turn_s * _mean_over_turn(duty.theta_deg, np.maximum(0.0, -power))
    available = motor.envelope_torque(speed)
    with np.errstate(divide="ignore", invalid="ignore"):
        use = np.where(np.abs(torque) > 0, np.abs(torque) / available, 0.0)
    peak = float(np.max(np.abs(torque)))
    max_speed = float(np.max(np.abs(speed)))
    checks = (
        Check.of(
            "rms torque / continuous stall torque",
            rms / motor.continuous_stall_torque_n_m,
            rms_share,
        ),
        Check.of("peak torque / envelope (worst point)", float(np.max(use)), 1.0),
        Check.of("peak torque / maximum torque", peak / motor.maximum_torque_n_m, 1.0),
        Check.of("max speed / maximum speed", max_speed / motor.maximum_speed_rpm, 1.0),
    )
    return MotorLoad(
        model,
        peak,
        rms,
        max_speed,
        float(regenerated),
        rms / motor.continuous_stall_torque_n_m,
        float(np.max(use)),
        checks,
        speed,
        torque,
    )


def size_motor(
    motor: Motor,
    duty: DutyCycle,
    *,
    rms_share_limit: float = RMS_SHARE_LIMIT,
    inertia_ratio_limit: float = INERTIA_RATIO_LIMIT,
) -> MotorSizing:
    """``motor`` against ``duty``: every check (``Check``) for the dynamic and the rigid load.

    Defaults: RMS torque at most ``RMS_SHARE_LIMIT`` (80%) of the continuous stall torque,
    every (speed, torque) point within the envelope, the peak within the maximum torque,
    the largest speed within the maximum speed, inertia ratio at most ``INERTIA_RATIO_LIMIT``
    (10).  The motor passes when the dynamic load passes.
    """
    rms_share_limit = _positive(rms_share_limit, "rms_share_limit")
    inertia_ratio_limit = _positive(inertia_ratio_limit, "inertia_ratio_limit")
    ratio = duty.load_inertia_kg_m2 / motor.rotor_inertia_kg_m2
    ratio_check = Check.of("inertia ratio (load reflected / rotor)", ratio, inertia_ratio_limit)
    loads = [
        _load(model, motor, duty, torque, rms_share_limit)
        for model, torque in (
            ("dynamic", duty.dynamic_torque_n_m),
            ("rigid", duty.rigid_torque_n_m),
        )
    ]
    loads = [dataclasses.replace(load, checks=load.checks + (ratio_check,)) for load in loads]
    return MotorSizing(motor, duty.rpm, ratio, *loads, rms_share_limit, inertia_ratio_limit)


@dataclasses.dataclass(frozen=True)
class MotorChoice:
    """A catalogue against a program at its master speeds: every motor's sizing (one per
    speed, in listed order), the smallest that passes at every speed (by continuous stall
    torque, then listed order) or ``None`` and the closest (the one whose worst check fails
    by the least) with that check."""

    sizings: tuple[tuple[MotorSizing, ...], ...]
    picked: Motor | None
    closest: Motor | None = None
    closest_check: Check | None = None

    def as_dict(self) -> dict:
        return {
            "picked": None if self.picked is None else self.picked.name,
            "closest": None if self.closest is None else self.closest.name,
            "closest_failed_check": None
            if self.closest_check is None
            else self.closest_check.as_dict(),
            "motors": [[s.as_dict() for s in per_speed] for per_speed in self.sizings],
        }

    @property
    def shown(self) -> Motor:
        """The motor a report shows: the picked one, else the closest."""
        return self.picked if self.picked is not None else self.closest

    def shown_dict(self) -> dict:
        """The pick (or the closest and its failing check), the summary and the shown motor's
        envelope and sizing at every speed (with its (speed, torque) points): what a page draws
        without every motor's points."""
        index = next(
            i for i, per_speed in enumerate(self.sizings) if per_speed[0].motor is self.shown
        )
        envelope = self.shown.envelope
        if envelope is None:  # the flat envelope envelope_torque assumes
            top = self.shown.maximum_speed_rpm
            envelope = [[0.0, self.shown.maximum_torque_n_m], [top, self.shown.maximum_torque_n_m]]
        out = self.as_dict()
        del out["motors"]
        return {
            **out,
            "summary": self.summary(),
            "shown": self.shown.name,
            "envelope": [list(map(float, point)) for point in envelope],
            "sizings": [s.as_dict() for s in self.sizings[index]],
        }

    def summary(self) -> str:
        if self.picked is not None:
            return f"picked motor: {self.picked.name} (the smallest that passes every check at every speed)"
        return (
            f"no motor passes; the closest, {self.closest.name}, fails {self.closest_check.name}: "
            f"{self.closest_check.shortfall()}"
        )


def choose_motor(motors, duties, **limits) -> MotorChoice:
    """Size every motor of ``motors`` against every ``DutyCycle`` of ``duties`` and pick."""
    motors, duties = tuple(motors), tuple(duties)
    if not motors:
        raise ValueError("no motor to size")
    sizings = tuple(tuple(size_motor(m, d, **limits) for d in duties) for m in motors)
    order = sorted(range(len(motors)), key=lambda i: (motors[i].continuous_stall_torque_n_m, i))
    for i in order:
        if all(s.passed for s in sizings[i]):
            return MotorChoice(sizings, motors[i])
    worst = [
        min((s.dynamic.worst for s in per_speed), key=lambda c: c.margin) for per_speed in sizings
    ]
    best = max(range(len(motors)), key=lambda i: worst[i].margin)
    return MotorChoice(sizings, None, motors[best], worst[best])


def motors_from_program_file(data, base: Path | None) -> tuple[Motor, ...]:
    """A program file's ``[motor]``: one record, ``[[motor]]`` records, or ``file = "..."``
    (a motor TOML or a catalogue CSV, relative to the program file)."""
    if isinstance(data, dict) and set(data) == {"file"}:
        name = data["file"]
        if not isinstance(name, str):
            raise ValueError(f"[motor] file must be a path, got {name!r}")
        return read_motors(Path(name) if base is None else base / name)
    records = data if isinstance(data, list) else [data]
    return tuple(
        Motor.from_dict(r, f"[motor] {i}" if len(records) > 1 else "[motor]")
        for i, r in enumerate(records, 1)
    )
