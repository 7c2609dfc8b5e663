"""Per-speed outputs of a cam program, one keyed set: the built-in ones and the probes.

Every scalar the report gives at each speed is a ``Probe``: its name (the key in
``SpeedReport.values``, the JSON and the CSV), its function, table title, unit, number
format and a line of doc.  A probe's function is either compiled (``fn(cycle, turn)``: a
scalar of the turn's state, computed inside the compiled speed batch, at every speed, from
the periodic steady state's ``Cycle`` and the turn, ``PaddedTurn``, as diffrax's
``SaveAt(fn=...)`` keeps a function of the state) or, for a figure of the whole analysis,
``host(values, context)`` on the host from the compiled values (``ProbeContext``).

A set of outputs is a value, ``Outputs``: every built-in one and the probes it was made
with (``Outputs([probe(...), ...])``); ``BUILT_IN_OUTPUTS`` holds the built-in ones alone.
``analyse(..., outputs=...)``, ``camjax.studio.studio(..., outputs=...)`` and
``camjax program --probes`` take the set (a static argument of the compiled cycle; the
default is ``BUILT_IN_OUTPUTS``); no process-wide registry changes what a call reports.
The table of ``camjax program``, its ``--format csv`` and ``json`` columns and
``summary.json`` read the set the report was computed with (``Report.columns``).  A new
built-in output is one ``Probe`` in ``BUILT_IN`` below; a user's output is one ``probe``
passed in: see docs/extending.md.  The turn's padding (``PaddedTurn``) is empty intervals
at its end, so a probe integrating over ``turn.grid.motion.widths`` or taking extrema of
node series needs no care for it.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Iterable, Iterator, Mapping
from typing import NamedTuple

import numpy as np

from ._torque import flywheel_inertia_kg_m2


class ProbeContext(NamedTuple):
    """What a host output (``Probe.host``) reads beside the compiled values: the program,
    the speeds (rpm, a 1-D array), the coefficient of speed fluctuation, the turn's grid
    nodes in degrees, the stacked ``Cycle`` of every speed (cut to the turn's nodes) and the
    largest Hertz stress refined between the nodes (``RefinedStress``; ``None`` without
    ``follower.contact_width_mm``)."""

    program: object
    rpm: np.ndarray
    speed_fluctuation: float
    nodes_deg: np.ndarray
    cycles: object
    stress: object = None  # the Hertz peak refined between nodes (RefinedStress), with a contact width


@dataclasses.dataclass(frozen=True)
class Probe:
    """One per-speed output.

    Attributes:
        name: the key in ``SpeedReport.values`` (also an attribute of the row), the JSON and
            the CSV.
        fn: ``fn(cycle, turn) -> scalar``, compiled with the speed batch (jittable,
            vmappable), or ``None`` for a host output.
        label: the table's column title.
        doc: one line for the reader: what it is.
        unit: its unit (SI, as the name's suffix says; empty for a flag).
        fmt: the table's format of one value (``str.format``).
        table: the block of the text table that prints it (rows per speed, ``rpm`` first):
            ``speed`` (steady state and contact), ``drive`` (torque and Hertz contact) or
            ``probes``, in that order.
        optional: left out of the text table where no speed has a value (``None`` everywhere).
        host: ``host(values, context) -> array or None`` on the host, after the compiled
            outputs (``values``: name -> array of every output before it in the set;
            ``context``: ``ProbeContext``); with ``fn`` too it receives ``fn``'s value as
            ``values[name]``.  ``None`` means no value at any speed (the output does not
            apply to this program).
        built_in: one of the report's own outputs (the rest of the report reads it).
    """

    name: str
    fn: Callable | None
    label: str
    doc: str = ""
    unit: str = ""
    fmt: str = "{:.6g}"
    table: str = "probes"
    optional: bool = False
    host: Callable | None = None
    built_in: bool = False

    def cell(self, value) -> str:
        """``value`` as the table prints it (``-`` for none)."""
        return "-" if value is None else self.fmt.format(value)

    def as_dict(self) -> dict:
        """What a page shows of it: name, label, unit, format, doc and table."""
        return {"name": self.name, "label": self.label, "unit": self.unit, "fmt": self.fmt, "doc": self.doc,
                "table": self.table, "optional": self.optional, "built_in": self.built_in}


def min_preload_n(min_contact_force_n, preload_n, levers: float = 1.0):
    """Preload that just keeps contact: ``max(0, max over the cycle of -(k e + c e'))``; a
    chain's spring preload acts at the cam through its ``levers`` (their product)."""
    return np.maximum(0.0, preload_n - np.asarray(min_contact_force_n) / levers)


def cam_levers(program) -> float:
    """The product of a chain's lever ratios from the cam to its spring (1 without a chain)."""
    return 1.0 if program.chain is None else program.chain.lever_ratio


def kinematic_peak_m_s2(program, rpm: np.ndarray) -> np.ndarray:
    """``max |y''|`` over the turn at each speed, exactly: ``|lift| Ca / t_segment^2``."""
    peak = max((abs(s.lift_mm) * float(s.law.Ca) / (s.angle_deg / 360.0) ** 2 for s in program.segments if s.moving),
               default=0.0)
    return 1e-3 * peak * (rpm / 60.0) ** 2


def _field(name: str) -> Callable:
    """The compiled function reading the ``Cycle``'s own figure ``name``."""
    return lambda cycle, turn: getattr(cycle, name)


def _spring_loaded(compute: Callable) -> Callable:
    return lambda values, c: None if c.program.follower.form_closed else compute(values, c)


def _stressed(compute: Callable) -> Callable:
    return lambda values, c: compute(values, c) if c.program.follower.contact_width_mm is not None else None


BUILT_IN = (
    Probe("max_payload_acceleration_m_s2", _field("max_payload_acceleration_m_s2"), "max|x''| m/s2",
          "peak |x''| of the payload over the turn, refined between nodes", "m/s^2", table="speed"),
    Probe("max_kinematic_acceleration_m_s2", None, "max|y''| m/s2",
          "peak |y''| of the cam's motion, |lift| Ca / t_segment^2", "m/s^2", table="speed",
          host=lambda values, c: kinematic_peak_m_s2(c.program, c.rpm)),
    Probe("min_contact_force_n", _field("min_contact_force_n"), "min Fc N",
          "least contact force over the turn, contact held (a form-closed cam: signed flank force)", "N",
          table="speed"),
    Probe("max_contact_force_n", _field("max_contact_force_n"), "max Fc N",
          "greatest contact force over the turn, contact held", "N", table="speed"),
    Probe("min_preload_n", None, "min preload N",
          "the preload that just keeps contact (none for a form-closed cam)", "N", table="speed",
          host=_spring_loaded(lambda v, c: min_preload_n(v["min_contact_force_n"], c.program.follower.preload_n,
                                                       cam_levers(c.program)))),
    Probe("jump", None, "jump", "whether the contact force goes negative (a spring-loaded cam)", "",
          "{}", table="speed",
          host=lambda v, c: np.zeros(c.rpm.size, bool) if c.program.follower.form_closed
          else np.asarray(v["min_contact_force_n"]) < 0),
    Probe("max_drive_torque_n_m", _field("max_drive_torque_n_m"), "max|T| N m",
          "peak |T| of the drive torque T = F_c dy/dtheta", "N m", table="drive"),
    Probe("rms_drive_torque_n_m", _field("rms_drive_torque_n_m"), "rms T N m",
          "RMS of the drive torque over the turn", "N m", table="drive"),
    Probe("mean_drive_torque_n_m", _field("mean_drive_torque_n_m"), "mean T N m",
          "mean of the drive torque over the turn", "N m", table="drive"),
    Probe("energy_fluctuation_j", _field("energy_fluctuation_j"), "dE J",
          "max W - min W, W the integral of (T - mean T) over the cam angle", "J", table="drive"),
    Probe("flywheel_inertia_kg_m2", None, "flywheel kg m2",
          "the flywheel for the speed fluctuation Cs: energy fluctuation / (Cs Omega^2)", "kg m^2",
          table="drive",
          host=lambda v, c: flywheel_inertia_kg_m2(v["energy_fluctuation_j"], c.rpm, c.speed_fluctuation)),
    Probe("max_contact_stress_mpa", None, "max p MPa",
          "peak Hertz line-contact pressure over the turn, refined between the grid's nodes "
          "(with follower.contact_width_mm)", "MPa",
          table="drive", optional=True, host=_stressed(lambda v, c: c.stress.stress_mpa)),
    Probe("max_contact_stress_deg", None, "at deg", "the cam angle of that peak", "deg", "{:.5g}",
          table="drive", optional=True, host=_stressed(lambda v, c: c.stress.angle_deg)),
    Probe("contact_half_width_mm", None, "half-width mm",
          "the Hertz contact half-width there, 2 R' p / E*", "mm", "{:.4g}", table="drive", optional=True,
          host=_stressed(lambda v, c: 2 * c.stress.radius_mm * c.stress.stress_mpa
                         / c.program.materials.contact_modulus_mpa)),
)
BUILT_IN = tuple(dataclasses.replace(p, built_in=True) for p in BUILT_IN)
"""The report's own outputs, in the order of the table and the CSV (a new one: a ``Probe``
here, with a compiled ``fn`` of the ``Cycle`` or a ``host`` function of the others)."""


class Outputs(Mapping):
    """A keyed set of per-speed outputs (name -> ``Probe``), in order: every built-in one
    (``BUILT_IN``), then the probes it is made with (``Outputs([probe(...), ...])``; the
    built-in ones among ``probes`` are taken as they are).  Immutable and hashable: the
    compiled cycle takes it as a static argument, and a cache of reports keys on it."""

    def __init__(self, probes: Iterable[Probe] = ()):
        probes = tuple(probes.values() if isinstance(probes, Outputs) else probes)
        if not all(isinstance(p, Probe) for p in probes):
            raise ValueError(f"outputs: each must be a Probe (camjax.program.probe), got {probes!r}")
        extra = [p for p in probes if not p.built_in]
        built_in = {b.name for b in BUILT_IN}
        for i, p in enumerate(extra):
            if p.name in built_in or p.name in _RESERVED:
                raise ValueError(f"probe name {p.name!r} is a built-in output of the report: choose another")
            if any(q.name == p.name for q in extra[:i]):
                raise ValueError(f"two probes are named {p.name!r}: give each its own name")
        self._probes = (*BUILT_IN, *extra)
        self._by_name = {p.name: p for p in self._probes}

    @classmethod
    def of(cls, outputs) -> Outputs:
        """``outputs`` if an ``Outputs``; ``None``: ``BUILT_IN_OUTPUTS``; else the built-in
        outputs and the probes given (an iterable of ``Probe``)."""
        if outputs is None:
            return BUILT_IN_OUTPUTS
        if isinstance(outputs, Outputs):
            return outputs
        if isinstance(outputs, (str, Probe)) or not isinstance(outputs, Iterable):
            raise ValueError(f"outputs must be an Outputs or a list of Probe (camjax.program.probe), got {outputs!r}")
        return cls(outputs)

    def __getitem__(self, name: str) -> Probe:
        return self._by_name[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._by_name)

    def __len__(self) -> int:
        return len(self._probes)

    def __hash__(self) -> int:
        return hash(self._probes)

    def __eq__(self, other) -> bool:
        return isinstance(other, Outputs) and self._probes == other._probes

    def __repr__(self) -> str:
        return f"Outputs({[p.name for p in self._probes]})"

    @property
    def compiled(self) -> tuple[Probe, ...]:
        """The outputs computed inside the compiled speed batch (those with ``fn``)."""
        return tuple(p for p in self._probes if p.fn is not None)

    @property
    def probes(self) -> tuple[Probe, ...]:
        """The outputs beyond the built-in ones."""
        return tuple(p for p in self._probes if not p.built_in)

    def evaluate(self, compiled: Mapping, context: ProbeContext) -> dict:
        """Every output at every speed (an array, or ``None`` where it does not apply),
        from the compiled values and the host functions, in the set's order."""
        out = dict(compiled)
        for p in self._probes:
            if p.host is not None:
                out[p.name] = p.host(out, context)
        return {p.name: out[p.name] for p in self._probes}


_RESERVED = {"rpm", "values", "outputs", "flights", "flight", "impacts", "impacts_change_deg", "period_ratios",
             "residual_vibration_mm"}  # the report's per-speed fields that are no scalar output


def probe(name: str, fn: Callable, *, label: str | None = None, doc: str = "", unit: str = "",
          fmt: str = "{:.6g}") -> Probe:
    """A user's output ``fn(cycle, turn) -> scalar`` named ``name``, titled ``label`` in the
    table, which formats it with ``fmt``: report it with ``analyse(..., outputs=Outputs([...]))``
    (or a list of probes), ``camjax.studio.studio(..., outputs=...)`` or ``camjax program
    --probes``."""
    if not isinstance(name, str) or not re.fullmatch(r"[a-z_][a-z0-9_]*", name):
        raise ValueError(f"a probe's name must be a lower-case Python name, got {name!r}")
    if name in _RESERVED or name.startswith("max_contact_stress") or name in {p.name for p in BUILT_IN}:
        raise ValueError(f"probe name {name!r} is a built-in output of the report: choose another")
    if not callable(fn):
        raise ValueError(f"probe {name!r}: fn must be a function of (cycle, turn), got {fn!r}")
    try:
        fmt.format(1.0)
    except (ValueError, IndexError, KeyError, TypeError):
        raise ValueError(f"probe {name!r}: fmt must format one number, as '{{:.6g}}' does, got {fmt!r}") from None
    return Probe(name, fn, label or name, doc, unit, fmt)


BUILT_IN_OUTPUTS = Outputs()
"""The report's own outputs alone, in the order of the table and the CSV: the default set
of ``analyse``, the studio and ``camjax program`` (``Outputs([probe(...)])`` adds probes)."""
