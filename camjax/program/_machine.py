"""Several cams on one shaft: their drive torques add, each at its phase on the shaft.

A machine file lists program files and the shaft angle at which each cam's own angle 0
comes round (``phase_deg``): cam ``i`` turns through ``theta - phase_i`` when the shaft is at
``theta``, so the shaft's torque is ``sum_i T_i(theta - phase_i)``.  Each cam's torque is
the septic interpolant of its own steady state (``_torque.torque_figures``); on the union
of every cam's shifted nodes their sum is again septic per interval, so the shaft's mean,
RMS, peak and energy fluctuation are those of the exact sum of the interpolants.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
from pathlib import Path

import numpy as np

from .._plain import json_ready
from ..checks import read_toml
from ..metrics import septic_coefficients
from ._dynamics import SteadyState
from ._outputs import BUILT_IN, BUILT_IN_OUTPUTS, Outputs
from ._program import Program
from ._reader import no_unknown as _no_unknown
from ._report import Report, analyse
from ._speeds import Speeds
from ._torque import (
    DEFAULT_SPEED_FLUCTUATION,
    check_speed_fluctuation,
    flywheel_inertia_kg_m2,
    torque_figures,
)


@dataclasses.dataclass(frozen=True)
class Machine:
    """Cams on one shaft: ``(Program, phase_deg)`` pairs (see the module's docstring)."""

    name: str
    cams: tuple[tuple[Program, float], ...]

    def __post_init__(self):
        cams = tuple((p, float(phase)) for p, phase in self.cams)
        object.__setattr__(self, "cams", cams)
        if not cams:
            raise ValueError("a machine needs at least one cam")
        for i, (program, phase) in enumerate(cams, 1):
            if not isinstance(program, Program):
                raise ValueError(f"cam {i}: not a camjax.program.Program")
            if not math.isfinite(phase):
                raise ValueError(f"cam {i}: phase_deg must be finite, got {phase}")

    @classmethod
    def load(cls, path) -> Machine:
        """Read a machine TOML file (``[machine] name``, ``[[cam]] program, phase_deg``);
        program files are relative to it."""
        path = Path(path)
        data = read_toml(path, "machine file")
        try:
            return cls.from_dict(data, base=path.parent)
        except ValueError as error:
            raise ValueError(f"{path}: {error}") from None

    @classmethod
    def from_dict(cls, data: dict, *, base: Path | None = None) -> Machine:
        _no_unknown(data, {"machine", "cam"}, "top level")
        header = data.get("machine", {})
        _no_unknown(header, {"name"}, "[machine]")
        cams = data.get("cam")
        if not isinstance(cams, list) or not cams:
            raise ValueError("no [[cam]] tables: a machine needs at least one cam")
        out = []
        for i, cam in enumerate(cams, 1):
            _no_unknown(cam, {"program", "phase_deg"}, f"cam {i}")
            if not isinstance(cam.get("program"), str):
                raise ValueError(f"cam {i}: needs program (a program file)")
            phase = cam.get("phase_deg", 0.0)
            if isinstance(phase, bool) or not isinstance(phase, int | float):
                raise ValueError(f"cam {i}: phase_deg must be a number, got {phase!r}")
            file = Path(cam["program"]) if base is None else base / cam["program"]
            try:
                out.append((Program.load(file), float(phase)))
            except ValueError as error:
                raise ValueError(f"cam {i}: {error}") from None
        return cls(str(header.get("name", "machine")), tuple(out))


def is_machine_file(data: dict) -> bool:
    """Whether a parsed TOML file is a machine (``[[cam]]`` tables) rather than a program."""
    return "cam" in data or "machine" in data


@dataclasses.dataclass(frozen=True)
class ShaftSpeedReport:
    """The shaft's drive torque at one speed (N m), its energy fluctuation (J) and flywheel."""

    rpm: float
    max_drive_torque_n_m: float
    rms_drive_torque_n_m: float
    mean_drive_torque_n_m: float
    energy_fluctuation_j: float
    flywheel_inertia_kg_m2: float

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class MachineReport:
    """Each cam's ``Report`` (with its phase) and the shaft's totals at every speed."""

    machine: str
    phases_deg: tuple[float, ...]
    cams: tuple[Report, ...]
    shaft: tuple[ShaftSpeedReport, ...]
    speed_fluctuation: float

    def as_dict(self) -> dict:
        return {"machine": self.machine, "speed_fluctuation": self.speed_fluctuation,
                "cams": [dict(phase_deg=phase, **r.as_dict()) for phase, r in zip(self.phases_deg, self.cams)],
                "shaft": {"speeds": [s.as_dict() for s in self.shaft]}}

    def to_json(self) -> str:
        """The report as JSON text (``camjax program MACHINE --format json``, ``summary.json``)."""
        return json.dumps(json_ready(self.as_dict()), indent=1)

    def columns(self) -> tuple:
        """The shaft's per-speed outputs: the built-in outputs (``BUILT_IN``) it holds."""
        fields = {f.name for f in dataclasses.fields(ShaftSpeedReport)}
        return tuple(p for p in BUILT_IN if p.name in fields)

    def to_csv(self) -> str:
        """The shaft's totals, one row per speed (``camjax program MACHINE --format csv``)."""
        buffer = io.StringIO()
        writer = csv.writer(buffer)
        keys = ["rpm"] + [p.name for p in self.columns()]
        writer.writerow(keys)
        writer.writerows([getattr(s, k) for k in keys] for s in self.shaft)
        return buffer.getvalue().rstrip()


def _jets(coefficients, sigma, h):
    """Value and first three derivatives (per unit of ``s``) of septics at ``sigma``."""
    m = np.arange(8)
    out = []
    for d in range(4):
        falling = np.prod([m - j for j in range(d)], axis=0) if d else np.ones(8)
        power = np.where(m >= d, sigma[:, None] ** np.maximum(m - d, 0), 0.0)
        out.append(np.sum(coefficients * falling * power, axis=1) / h**d)
    return np.stack(out, axis=1)


def shaft_torque(cycles, grids_nodes, phases_deg):
    """The shaft's torque over one turn from each cam's ``Cycle`` and grid nodes:
    ``(nodes, values, left, right)`` on the union of the shifted nodes (turn time)."""
    shifts = [np.mod(p / 360.0, 1.0) for p in phases_deg]
    union = np.unique(np.concatenate([np.mod(n + s, 1.0) for n, s in zip(grids_nodes, shifts)] + [[0.0, 1.0]]))
    union = union[np.concatenate([[True], np.diff(union) > 1e-12])]
    union[-1] = 1.0
    widths = np.diff(union)
    mid = 0.5 * (union[:-1] + union[1:])
    left_end, right_end = np.zeros((widths.size, 4)), np.zeros((widths.size, 4))
    for cycle, nodes, shift in zip(cycles, grids_nodes, shifts):
        h_all = np.diff(nodes)
        c = np.asarray(septic_coefficients(np.asarray(cycle.drive_torque_n_m), h_all,
                                           np.asarray(cycle.drive_torque_left), np.asarray(cycle.drive_torque_right)))
        local = np.mod(mid - shift, 1.0)
        k = np.clip(np.searchsorted(nodes, local, side="right") - 1, 0, h_all.size - 1)
        h = h_all[k]
        left_end += _jets(c[k], (local - 0.5 * widths - nodes[k]) / h, h)
        right_end += _jets(c[k], (local + 0.5 * widths - nodes[k]) / h, h)
    values = np.concatenate([left_end[:, 0], right_end[-1:, 0]])
    return union, values, left_end[:, 1:], right_end[:, 1:]


def analyse_machine(machine, rpm, *, with_flight: bool = True,
                    speed_fluctuation: float = DEFAULT_SPEED_FLUCTUATION,
                    outputs: Outputs = BUILT_IN_OUTPUTS) -> MachineReport:
    """Every cam's ``analyse`` (with the per-speed ``outputs``) and the shaft's torque
    totals at every speed in ``rpm``.

    ``machine`` is a ``Machine`` or a list of ``(Program, phase_deg)``.
    """
    if not isinstance(machine, Machine):
        machine = Machine("machine", tuple(machine))
    rpm = Speeds.of(rpm)
    speed_fluctuation = check_speed_fluctuation(speed_fluctuation)
    steadies = [SteadyState(p, rpm) for p, _ in machine.cams]
    phases = [phase for _, phase in machine.cams]
    reports = tuple(analyse(p, rpm, with_flight=with_flight, steady=s, speed_fluctuation=speed_fluctuation,
                            outputs=outputs)
                    for (p, _), s in zip(machine.cams, steadies))
    shaft = []
    for r in rpm:
        nodes, values, left, right = shaft_torque([s.cycle(r) for s in steadies],
                                                  [s.grid.nodes for s in steadies], phases)
        figures = [float(x) for x in torque_figures(values, np.diff(nodes), left, right)]
        shaft.append(ShaftSpeedReport(float(r), *figures,
                                      float(flywheel_inertia_kg_m2(figures[3], r, speed_fluctuation))))
    return MachineReport(machine.name, tuple(phases), reports, tuple(shaft), speed_fluctuation)
