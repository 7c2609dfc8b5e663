"""Per-speed outputs of a cam program as probes: a function of the turn's state, by name.

A probe is computed inside the compiled speed batch, at every speed, from the periodic
steady state's ``Cycle`` (node series, one-sided derivatives, extrema) and the turn
(``PaddedTurn``: its grid, follower and contact factors), as diffrax's
``SaveAt(fn=...)`` keeps a function of the state.  ``analyse`` reports every registered
probe in ``SpeedReport.outputs`` (and as an attribute of the report), ``camjax program``
prints and writes it beside the built-in outputs (the table, ``--format csv`` and
``json``, ``summary.json``).  Adding an output is one ``register_probe`` call: see
docs/extending.md.  The turn's padding (``PaddedTurn``) is empty intervals at its end, so
a probe integrating over ``turn.grid.motion.widths`` or taking extrema of node series
needs no care for it.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable


@dataclasses.dataclass(frozen=True)
class Probe:
    """One per-speed output: ``fn(cycle, turn)`` gives a scalar (jittable, vmappable).

    Attributes:
        name: the key in ``SpeedReport.outputs``, the JSON and the CSV (a Python name).
        fn: the function of the turn's state.
        label: the table's column title.
        doc: one line for the reader: what it is, in which unit.
    """

    name: str
    fn: Callable
    label: str
    doc: str = ""


PROBES: dict[str, Probe] = {}
"""The registered probes, in registration order (``register_probe``)."""

_RESERVED = {"rpm", "outputs", "flights", "impacts", "jump", "period_ratios", "residual_vibration_mm"}


def register_probe(name: str, fn: Callable, *, label: str | None = None, doc: str = "") -> Probe:
    """Register ``fn(cycle, turn) -> scalar`` as the per-speed output ``name`` (replacing a
    probe of that name).  The next ``analyse`` compiles its speed batch once more with it."""
    if not isinstance(name, str) or not re.fullmatch(r"[a-z_][a-z0-9_]*", name):
        raise ValueError(f"a probe's name must be a lower-case Python name, got {name!r}")
    if name in _RESERVED or name.startswith("max_contact_stress") or name in _BUILT_IN:
        raise ValueError(f"probe name {name!r} is a built-in output of the report: choose another")
    if not callable(fn):
        raise ValueError(f"probe {name!r}: fn must be a function of (cycle, turn), got {fn!r}")
    PROBES[name] = probe = Probe(name, fn, label or name, doc)
    return probe


def unregister_probe(name: str) -> None:
    """Remove the probe ``name`` (a ``ValueError`` if there is none)."""
    if name not in PROBES:
        raise ValueError(f"no probe named {name!r}; registered: {', '.join(PROBES) or 'none'}")
    del PROBES[name]


_BUILT_IN = {"max_payload_acceleration_m_s2", "max_kinematic_acceleration_m_s2", "min_contact_force_n",
             "max_contact_force_n", "min_preload_n", "max_drive_torque_n_m", "rms_drive_torque_n_m",
             "mean_drive_torque_n_m", "energy_fluctuation_j", "flywheel_inertia_kg_m2",
             "contact_half_width_mm"}
