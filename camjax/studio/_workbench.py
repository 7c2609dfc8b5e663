"""One workbench's state: the program (as TOML text), the speed range and its report.

Everything the page shows comes from the public program API (``camjax.program``): the
report is ``camjax.program.analyse``'s, as ``camjax program --format json`` prints it.
"""

from __future__ import annotations

import dataclasses
import json
import math
import threading
import time
import tomllib
from pathlib import Path

import numpy as np

from .._plain import DEFAULT_SPEED_FLUCTUATION, json_ready, parse_range, plot_speed

DEFAULT_RPM = "200:1400:7"
"""The speed range a workbench starts with (wide enough to show the examples' jump speeds)."""
TURN_POINTS = 721
"""Cam angles over the turn for the kinematic curves (every half degree)."""
PROFILE_POINTS = 720
"""Profile points the page draws."""
CACHED_REPORTS = 16
"""Analyses a studio keeps (oldest dropped first), shared by its workbenches."""
_CACHE_LOCK = threading.Lock()


def parse_toml(text: str) -> dict:
    """TOML text as its structure, or a one-line ``ValueError``."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"not valid TOML ({error})") from None


def parse_program(text: str, base: Path | None = None):
    """A ``Program`` from TOML text (law files relative to ``base``), or a one-line ``ValueError``."""
    from ..program import Program

    return Program.from_dict(parse_toml(text), base=base)


def parse_speeds(text: str) -> np.ndarray:
    """The speed range ``text`` (``START:STOP:COUNT`` or ``V1,V2,...``, rpm), or a ValueError."""
    try:
        rpm = parse_range(str(text), "rpm")
    except ValueError as error:
        raise ValueError(str(error)) from None
    if not all(r > 0 for r in rpm):
        raise ValueError(f"rpm: speeds must be positive, got {text!r}")
    return rpm


def kinematics(program, theta_deg: np.ndarray) -> dict[str, np.ndarray]:
    """Lift and its first three derivatives in cam angle (mm/deg^k) at ``theta_deg``, from
    the program's turn (``Program.turn``)."""
    y, dy, ddy, jerk = program.turn.jet(theta_deg)
    return {"lift_mm": y, "velocity_mm_per_deg": dy, "acceleration_mm_per_deg2": ddy,
            "jerk_mm_per_deg3": jerk}


def rigid_contact_force_n(program, lift_mm: np.ndarray, acceleration_m_s2: np.ndarray) -> np.ndarray:
    """The contact force of a rigid follower train: ``F_0 + k_s y + m y''`` (docs/program.md,
    the limit ``k -> inf``)."""
    f = program.follower
    return f.preload_n + f.spring_rate * 1e-3 * lift_mm + f.mass_kg * acceleration_m_s2


def _canonical(value):
    """A TOML structure with every number a float: ``8`` and ``8.0`` are the same lift."""
    if isinstance(value, dict):
        return {k: _canonical(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_canonical(v) for v in value]
    if isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


@dataclasses.dataclass
class Workbench:
    """A program being edited: its last good TOML text, speeds, report and steady state."""

    toml: str
    rpm_text: str = DEFAULT_RPM
    base: Path | None = None
    with_flight: bool = True
    speed_fluctuation: float = DEFAULT_SPEED_FLUCTUATION
    program: object = None
    rpm: np.ndarray | None = None
    report: dict | None = None
    steady: object = None
    warnings: list = dataclasses.field(default_factory=list)
    used: float = dataclasses.field(default_factory=time.monotonic)
    lock: threading.Lock = dataclasses.field(default_factory=threading.Lock, repr=False)
    cache: dict = dataclasses.field(default_factory=dict, repr=False)

    def touch(self) -> None:
        self.used = time.monotonic()

    def ensure(self) -> dict:
        """The report, computed on first need."""
        if self.report is None:
            self.update(self.toml, self.rpm_text)
        return self.report

    def update(self, toml: str, rpm_text: str | None = None) -> dict:
        """Replace the program (and the speeds): the new report, or a ValueError that
        leaves the last good state as it was.  The same program (the same TOML structure,
        whatever its layout and comments) at the same speeds is analysed once per ``cache``."""
        from ..program import Program, SteadyState, analyse

        rpm_text = self.rpm_text if rpm_text is None else str(rpm_text)
        data = parse_toml(toml)
        program = Program.from_dict(data, base=self.base)
        rpm = parse_speeds(rpm_text)
        key = (json.dumps(_canonical(data), sort_keys=True, default=str), tuple(rpm.tolist()), self.with_flight,
               self.speed_fluctuation, str(self.base))
        hit = self.cache.get(key)
        if hit is None:
            steady = SteadyState(program, float(min(rpm)))
            report = json_ready(analyse(program, rpm, with_flight=self.with_flight, steady=steady,
                                        speed_fluctuation=self.speed_fluctuation))
            hit = (program, steady, report, list(report.get("warnings", ())))
            with _CACHE_LOCK:
                self.cache[key] = hit
                while len(self.cache) > CACHED_REPORTS:
                    self.cache.pop(next(iter(self.cache)))
        self.program, self.steady, self.report, self.warnings = hit
        self.toml, self.rpm_text, self.rpm = toml, rpm_text, rpm
        return self.report

    def curves(self, rpm: float | None = None) -> dict:
        """Everything the page draws beside the report: the kinematics over the turn, the
        histories at ``rpm`` (default: ``plot_speed``'s choice), the profile."""
        from ..program import profile, response

        report = self.ensure()
        program = self.program
        lowest = float(min(self.rpm))
        if rpm is None:
            rpm = plot_speed(report, None)
        if not (isinstance(rpm, int | float) and math.isfinite(rpm) and rpm >= lowest):
            raise ValueError(f"rpm: the chosen speed must be at or above the lowest speed of the "
                             f"range ({lowest:g} rpm), got {rpm!r}")
        theta = np.linspace(0.0, 360.0, TURN_POINTS)
        h = response(program, float(rpm), steady=self.steady)
        prof = profile(program, PROFILE_POINTS)
        f = program.follower
        return json_ready({
            "rpm": float(rpm),
            "kinematics": {"theta_deg": theta, **kinematics(program, theta)},
            "response": {**h, "rigid_contact_force_n":
                         rigid_contact_force_n(program, h["lift_mm"], h["kinematic_acceleration_m_s2"])},
            "profile": {"theta_deg": prof.theta_deg, "pitch": prof.pitch, "profile": prof.profile,
                        "outer": prof.outer if f.form_closed else None,
                        "flat_face": prof.flat_face},
            "follower": dataclasses.asdict(f) | {"form_closed": f.form_closed},
            "warnings": self.warnings,
        })

    def state(self) -> dict:
        """The program as its TOML structure (for the page's tables), its text and the speeds."""
        from .. import laws

        return {"toml": self.toml, "program": tomllib.loads(self.toml), "rpm": self.rpm_text,
                "laws": [*laws.names(), "constant-velocity", "polynomial"]}
