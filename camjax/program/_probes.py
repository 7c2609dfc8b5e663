"""Per-speed outputs of a cam program, one registry: the built-in ones and the probes.

Every scalar the report gives at each speed is a ``Probe`` of ``OUTPUTS``, with its name
(the key in ``SpeedReport``, the JSON and the CSV), its table title, unit, number format
and a line of doc.  The table of ``camjax program``, its ``--format csv`` and ``json`` columns and
``summary.json`` are all read from this registry (``Report.columns``), so a new output
lands in each by the same code.

The built-in outputs are computed by the compiled steady state (``analyse``).  A user's
output is a **probe**: a function of the turn's state, computed inside the compiled speed
batch, at every speed, from the periodic steady state's ``Cycle`` (node series, one-sided
derivatives, extrema) and the turn (``PaddedTurn``: its grid, follower and contact
factors), as diffrax's ``SaveAt(fn=...)`` keeps a function of the state.  ``analyse``
reports every registered probe in ``SpeedReport.outputs`` (and as an attribute of the
report).  Adding an output is one ``register_probe`` call: see docs/extending.md.  The
turn's padding (``PaddedTurn``) is empty intervals at its end, so a probe integrating over
``turn.grid.motion.widths`` or taking extrema of node series needs no care for it.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Iterator, Mapping


@dataclasses.dataclass(frozen=True)
class Probe:
    """One per-speed output: ``fn(cycle, turn)`` gives a scalar (jittable, vmappable);
    ``fn`` is ``None`` for a built-in output, which ``analyse`` computes itself.

    Attributes:
        name: the key in ``SpeedReport`` (a field, or ``outputs``), the JSON and the CSV.
        fn: the function of the turn's state (``None``: built in).
        label: the table's column title.
        doc: one line for the reader: what it is.
        unit: its unit (SI, as the name's suffix says; empty for a flag).
        fmt: the table's format of one value (``str.format``).
        table: the block of the text table that prints it (rows per speed, ``rpm`` first):
            ``speed`` (steady state and contact), ``drive`` (torque and Hertz contact) or
            ``probes``, in that order.
        optional: left out of the text table where no speed has a value (``None`` everywhere).
    """

    name: str
    fn: Callable | None
    label: str
    doc: str = ""
    unit: str = ""
    fmt: str = "{:.6g}"
    table: str = "probes"
    optional: bool = False

    @property
    def built_in(self) -> bool:
        return self.fn is None

    def cell(self, value) -> str:
        """``value`` as the table prints it (``-`` for none)."""
        return "-" if value is None else self.fmt.format(value)


_BUILT_IN = (
    Probe("max_payload_acceleration_m_s2", None, "max|x''| m/s2",
          "peak |x''| of the payload over the turn, refined between nodes", "m/s^2", table="speed"),
    Probe("max_kinematic_acceleration_m_s2", None, "max|y''| m/s2",
          "peak |y''| of the cam's motion, |lift| Ca / t_segment^2", "m/s^2", table="speed"),
    Probe("min_contact_force_n", None, "min Fc N",
          "least contact force over the turn, contact held (a form-closed cam: signed flank force)", "N",
          table="speed"),
    Probe("max_contact_force_n", None, "max Fc N", "greatest contact force over the turn, contact held", "N",
          table="speed"),
    Probe("min_preload_n", None, "min preload N",
          "the preload that just keeps contact (none for a form-closed cam)", "N", table="speed"),
    Probe("jump", None, "jump", "whether the contact force goes negative (a spring-loaded cam)", "",
          "{}", table="speed"),
    Probe("max_drive_torque_n_m", None, "max|T| N m", "peak |T| of the drive torque T = F_c dy/dtheta",
          "N m", table="drive"),
    Probe("rms_drive_torque_n_m", None, "rms T N m", "RMS of the drive torque over the turn", "N m",
          table="drive"),
    Probe("mean_drive_torque_n_m", None, "mean T N m", "mean of the drive torque over the turn", "N m",
          table="drive"),
    Probe("energy_fluctuation_j", None, "dE J",
          "max W - min W, W the integral of (T - mean T) over the cam angle", "J", table="drive"),
    Probe("flywheel_inertia_kg_m2", None, "flywheel kg m2",
          "the flywheel for the speed fluctuation Cs: energy fluctuation / (Cs Omega^2)", "kg m^2",
          table="drive"),
    Probe("max_contact_stress_mpa", None, "max p MPa",
          "peak Hertz line-contact pressure over the turn, refined between the grid's nodes (with follower.contact_width_mm)", "MPa",
          table="drive", optional=True),
    Probe("max_contact_stress_deg", None, "at deg", "the cam angle of that peak", "deg", "{:.5g}",
          table="drive", optional=True),
    Probe("contact_half_width_mm", None, "half-width mm", "the Hertz contact half-width there, 2 R' p / E*",
          "mm", "{:.4g}", table="drive", optional=True),
)

OUTPUTS: dict[str, Probe] = {p.name: p for p in _BUILT_IN}
"""Every per-speed output, in the order of the table and the CSV: the built-in ones, then
the registered probes in registration order (``register_probe``)."""


class _Probes(Mapping):
    """The registered probes: the outputs of ``OUTPUTS`` that have a function."""

    def __getitem__(self, name: str) -> Probe:
        probe = OUTPUTS.get(name)
        if probe is None or probe.built_in:
            raise KeyError(name)
        return probe

    def __iter__(self) -> Iterator[str]:
        return (name for name, p in OUTPUTS.items() if not p.built_in)

    def __len__(self) -> int:
        return sum(not p.built_in for p in OUTPUTS.values())

    def __repr__(self) -> str:
        return f"PROBES({list(self)})"


PROBES: Mapping[str, Probe] = _Probes()
"""The registered probes, in registration order (``register_probe``): a view of ``OUTPUTS``."""

_RESERVED = {"rpm", "outputs", "flights", "flight", "impacts", "impacts_change_deg", "period_ratios",
             "residual_vibration_mm"}  # the report's per-speed fields that are no scalar output


def register_probe(name: str, fn: Callable, *, label: str | None = None, doc: str = "", unit: str = "",
                   fmt: str = "{:.6g}") -> Probe:
    """Register ``fn(cycle, turn) -> scalar`` as the per-speed output ``name`` (replacing a
    probe of that name), titled ``label`` in the table, which formats it with ``fmt``.  The
    next ``analyse`` compiles its speed batch once more with it."""
    if not isinstance(name, str) or not re.fullmatch(r"[a-z_][a-z0-9_]*", name):
        raise ValueError(f"a probe's name must be a lower-case Python name, got {name!r}")
    if name in _RESERVED or name.startswith("max_contact_stress") or (name in OUTPUTS and OUTPUTS[name].built_in):
        raise ValueError(f"probe name {name!r} is a built-in output of the report: choose another")
    if not callable(fn):
        raise ValueError(f"probe {name!r}: fn must be a function of (cycle, turn), got {fn!r}")
    try:
        fmt.format(1.0)
    except (ValueError, IndexError, KeyError, TypeError):
        raise ValueError(f"probe {name!r}: fmt must format one number, as '{{:.6g}}' does, got {fmt!r}") from None
    OUTPUTS[name] = probe = Probe(name, fn, label or name, doc, unit, fmt)
    return probe


def unregister_probe(name: str) -> None:
    """Remove the probe ``name`` (a ``ValueError`` if there is none)."""
    if name not in PROBES:
        raise ValueError(f"no probe named {name!r}; registered: {', '.join(PROBES) or 'none'}")
    del OUTPUTS[name]
