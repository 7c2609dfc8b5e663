"""The follower train a cam program drives, and the materials of its contact (mm, N, kg).

Every check names the field that fails, with a one-line ``ValueError``.  The follower's
kind is read here and nowhere else: ``FOLLOWER_KINDS`` maps each name to its
``camjax.geometry`` class, which holds that kind's geometry and rules
(``Follower.geometry``); a new kind is a new class there and its entry here.
"""

from __future__ import annotations

import dataclasses
import math
import re
import types

from .. import geometry
from ..checks import finite_number

FOLLOWER_KINDS = types.MappingProxyType({kind.name: kind for kind in (
    geometry.TranslatingRollerFollower, geometry.SwingingRollerFollower,
    geometry.TranslatingFlatFollower, geometry.SwingingFlatFollower)})
"""The follower kinds a program file names (``[follower] kind``), each its geometry's class."""
MAX_PRESSURE_ANGLE_DEG = types.MappingProxyType({name: kind.max_pressure_angle_deg for name, kind in FOLLOWER_KINDS.items()
                                                 if kind.max_pressure_angle_deg is not None})
"""The pressure angle above which a roller follower is taken to jam or wear (the design
rule of thumb: 30 degrees translating, 45 swinging), by kind (each class's
``max_pressure_angle_deg``); flat faces have their own checks."""
GEOMETRY_KEYS = types.MappingProxyType({"base_radius": "base_radius_mm", "roller_radius": "roller_radius_mm",
                                        "offset": "offset_mm", "arm_length": "arm_mm",
                                        "pivot_distance": "pivot_mm"})
"""The ``Follower`` field (mm) of each field of the ``camjax.geometry`` followers."""


def follower_kind(name) -> type[geometry.AbstractFollower]:
    """The ``camjax.geometry`` class of the kind ``name`` (a ``ValueError`` if none)."""
    kind = FOLLOWER_KINDS.get(name) if isinstance(name, str) else None
    if kind is None:
        raise ValueError(f"follower.kind must be one of {', '.join(FOLLOWER_KINDS)}, got {name!r}")
    return kind


def follower_keys(kind: type[geometry.AbstractFollower]) -> tuple[str, ...]:
    """The ``Follower`` fields (``[follower]`` keys) that shape a kind's geometry."""
    return tuple(GEOMETRY_KEYS[field.name] for field in dataclasses.fields(kind))


def follower_kinds() -> list[dict]:
    """Each kind with the keys of its geometry, whether it has a roller and whether it
    swings: what the studio offers and draws."""
    return [{"name": name, "keys": list(follower_keys(kind)), "roller": issubclass(kind, geometry.AbstractRollerFollower),
             "swinging": kind.swinging} for name, kind in FOLLOWER_KINDS.items()]


def _in_keys(message: str) -> str:
    """A ``camjax.geometry`` follower's message with its fields named by their keys."""
    return re.sub(r"\b(" + "|".join(GEOMETRY_KEYS) + r")\b", lambda m: GEOMETRY_KEYS[m.group(1)], message)


@dataclasses.dataclass(frozen=True)
class Follower:
    """The follower train, referred to the roller (lengths in mm, forces in N).

    ``spring_rate_n_per_mm=None`` is a form-closed (grooved) cam: no return spring, no
    preload, no jump; ``groove_clearance_mm`` (form-closed only) is how much wider than
    the roller its groove is: the roller then crosses it when the train force changes sign.

    ``kind`` names the follower's geometry (``FOLLOWER_KINDS``; ``geometry`` is its
    ``camjax.geometry`` follower, with the fields of ``follower_keys``).  For a swinging
    roller the lift is the arc length of the roller centre (swing angle times ``arm_mm``)
    and ``pivot_mm`` is the cam-centre to pivot distance.  A flat-faced follower has no
    roller: the swinging face is a plane through the pivot and its lift is the swing angle
    times ``arm_mm``.  ``contact_width_mm`` is the width of the line contact (the roller's, or
    the cam's under a flat face) for the Hertz stress; without it no stress is reported.
    """

    mass_kg: float
    stiffness_n_per_mm: float
    damping_ratio: float = 0.0
    spring_rate_n_per_mm: float | None = None
    preload_n: float = 0.0
    base_radius_mm: float = 40.0
    roller_radius_mm: float = 10.0
    offset_mm: float = 0.0
    kind: str = geometry.TranslatingRollerFollower.name
    arm_mm: float | None = None
    pivot_mm: float | None = None
    groove_clearance_mm: float | None = None
    contact_width_mm: float | None = None

    def __post_init__(self):
        _as_floats(self)

    @property
    def geometry(self) -> geometry.AbstractFollower:
        """The follower's geometry in mm: its kind's ``camjax.geometry`` class, built from
        the fields of ``follower_keys``."""
        kind = follower_kind(self.kind)
        return kind(**{field.name: getattr(self, GEOMETRY_KEYS[field.name]) for field in dataclasses.fields(kind)})

    @property
    def flat_face(self) -> bool:
        return not issubclass(follower_kind(self.kind), geometry.AbstractRollerFollower)

    @property
    def swinging(self) -> bool:
        return follower_kind(self.kind).swinging

    @property
    def swing_arm_mm(self) -> float | None:
        """The arm whose swing is the lift (the lift is the arc at it, mm per radian):
        ``arm_mm`` for a follower that swings, ``None`` for one that translates."""
        return self.arm_mm if self.swinging else None

    @property
    def displacement_per_lift(self) -> tuple[float, str]:
        """The follower's own displacement per mm of lift, and its unit: degrees of swing per
        mm of arc at the arm (``deg``), or the lift itself (``mm``)."""
        arm = self.swing_arm_mm
        return (1.0, "mm") if arm is None else (180.0 / (math.pi * arm), "deg")

    @property
    def form_closed(self) -> bool:
        return self.spring_rate_n_per_mm is None

    @property
    def spring_rate(self) -> float:
        """Return-spring rate in N/m (0 for a form-closed cam)."""
        return 0.0 if self.form_closed else 1e3 * self.spring_rate_n_per_mm

    @property
    def stiffness(self) -> float:
        """Train stiffness in N/m."""
        return 1e3 * self.stiffness_n_per_mm

    @property
    def damping(self) -> float:
        """Train damping ``c = 2 zeta sqrt(k m)`` in N s/m."""
        return 2 * self.damping_ratio * math.sqrt(self.stiffness * self.mass_kg)

    @property
    def natural_frequency_hz(self) -> float:
        """``sqrt((k + k_s) / m) / (2 pi)``."""
        return math.sqrt((self.stiffness + self.spring_rate) / self.mass_kg) / (2 * math.pi)

    def vibrations_per_turn(self, rpm):
        """Natural vibrations of the follower per cam turn at ``rpm``, ``f_n 60 / rpm``: the
        period ratio of the whole turn (a segment's is this times its angle over 360).  The
        one place where a speed becomes a period ratio."""
        return self.natural_frequency_hz * 60.0 / rpm


_finite = finite_number  # a program file's numbers are checked as every other input


def _as_floats(record) -> None:
    """A frozen dataclass's Python ``int`` fields made floats: a TOML integer such as
    ``roller_radius_mm = 1000000000000`` is a length, not an index, and JAX refuses an
    integer past 64 bits (an ``OverflowError`` traceback) where it takes the float."""
    for field in dataclasses.fields(record):
        value = getattr(record, field.name)
        if type(value) is int:
            object.__setattr__(record, field.name, float(value))


def field_number(value, where: str, *, positive: bool = False, non_negative: bool = False) -> float:
    """A program file's number ``value`` as a float, finite (and positive or non-negative if
    asked), else a ``ValueError`` naming ``where`` (the table, body and field)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{where} must be a finite number, got {value!r}")
    if positive and not value > 0:
        raise ValueError(f"{where} must be positive, got {value:g}")
    if non_negative and value < 0:
        raise ValueError(f"{where} must be non-negative, got {value:g}")
    return float(value)


def _positive(value, what: str) -> float:
    value = _finite(value, what)
    if value <= 0:
        raise ValueError(f"{what} must be positive, got {value:g}")
    return value


def _check_follower(f: Follower) -> None:
    kind = follower_kind(f.kind)
    for name in ("mass_kg", "stiffness_n_per_mm", "base_radius_mm", "roller_radius_mm"):
        _positive(getattr(f, name), f"follower.{name}")
    zeta = _finite(f.damping_ratio, "follower.damping_ratio")
    if not 0 <= zeta < 1:
        raise ValueError(f"follower.damping_ratio must be in [0, 1), got {zeta:g}")
    if not f.form_closed:
        _positive(f.spring_rate_n_per_mm, "follower.spring_rate_n_per_mm")
    if f.groove_clearance_mm is not None:
        if not f.form_closed:
            raise ValueError("follower.groove_clearance_mm: only a form-closed cam (no "
                             "spring_rate_n_per_mm) has a groove")
        _positive(f.groove_clearance_mm, "follower.groove_clearance_mm")
    if _finite(f.preload_n, "follower.preload_n") < 0:
        raise ValueError(f"follower.preload_n must be non-negative, got {f.preload_n:g}")
    if f.contact_width_mm is not None:
        _positive(f.contact_width_mm, "follower.contact_width_mm")
    offset = _finite(f.offset_mm, "follower.offset_mm")
    if f.flat_face and f.groove_clearance_mm is not None:
        raise ValueError("follower.groove_clearance_mm: a flat-faced follower runs on no groove")
    if kind is geometry.TranslatingFlatFollower and offset != 0:
        raise ValueError("follower.offset_mm: a flat face's profile does not depend on an offset; "
                         "leave it 0")
    keys = follower_keys(kind)
    needed = [field.name for field in dataclasses.fields(Follower) if field.name in keys and field.default is None]
    for key in needed:
        if getattr(f, key) is None:
            raise ValueError(f"follower.{key} is missing: a {f.kind} follower needs {' and '.join(needed)}")
    for key in needed:
        _positive(getattr(f, key), f"follower.{key}")
    try:
        f.geometry  # noqa: B018  (its own checks)
    except ValueError as error:
        raise ValueError(f"follower.{_in_keys(str(error))}") from None


@dataclasses.dataclass(frozen=True)
class Materials:
    """Elastic constants of the cam and the follower (roller or face) for the Hertz stress."""

    cam_youngs_modulus_gpa: float = 210.0
    cam_poisson_ratio: float = 0.3
    follower_youngs_modulus_gpa: float = 210.0
    follower_poisson_ratio: float = 0.3

    def __post_init__(self):
        _as_floats(self)
        for part in ("cam", "follower"):
            _positive(getattr(self, f"{part}_youngs_modulus_gpa"), f"materials.{part}_youngs_modulus_gpa")
            nu = _finite(getattr(self, f"{part}_poisson_ratio"), f"materials.{part}_poisson_ratio")
            if not -1.0 < nu < 0.5:
                raise ValueError(f"materials.{part}_poisson_ratio must be in (-1, 0.5), got {nu:g}")

    @property
    def contact_modulus_mpa(self) -> float:
        """``E*`` with ``1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2``, in MPa (N/mm^2)."""
        compliance = sum((1 - getattr(self, f"{p}_poisson_ratio") ** 2) / getattr(self, f"{p}_youngs_modulus_gpa")
                         for p in ("cam", "follower"))
        return 1e3 / compliance
