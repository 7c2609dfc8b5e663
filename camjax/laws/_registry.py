"""Look laws up by name: ``get("modsine")``, ``get("scca:0.25,0.5,0.25")``, ``get("poly:5")``.

``names()`` lists the rest-to-rest laws with fixed names (the seven classic laws that
``standard_laws()`` gives first, then the named laws of the trade); ``get`` also takes the
parameterised rest-to-rest families (``scca:A,B,C``, ``poly:K``, ``triple-harmonic:A1,A2``,
``NAME-cv:P``, ``NAME-asym:L``) and the laws that start or end in motion
(``constant-velocity``, ``double-harmonic``, ``polynomial5:V0,A0,V1,A1`` and
``polynomial7:V0,A0,J0,V1,A1,J1``, boundary values in normalised units).
"""

from __future__ import annotations

from collections.abc import Callable

from ._base import AbstractMotionLaw
from ._boundary import BoundaryPolynomial, ConstantVelocity
from ._harmonic import (
    TRIPLE_HARMONIC_PRESETS,
    DoubleHarmonic,
    FreudensteinOneThree,
    FreudensteinOneThreeFive,
    TripleHarmonic,
)
from ._inflected import Inflected
from ._polynomial import PolynomialLaw
from ._scca import (
    CV_BASES,
    SCCA,
    Cycloidal,
    ModifiedSine,
    ModifiedTrapezoid,
    Parabolic,
    SimpleHarmonic,
    constant_velocity_variant,
)
from ._shaped import SHAPERS, ShapedLaw, Shaper

_STANDARD: dict[str, Callable[[], AbstractMotionLaw]] = {
    "cycloidal": Cycloidal,
    "modified-sine": ModifiedSine,
    "modified-trapezoid": ModifiedTrapezoid,
    "harmonic": SimpleHarmonic,
    "parabolic": Parabolic,
    "poly345": lambda: PolynomialLaw(3),
    "poly4567": lambda: PolynomialLaw(4),
}

_NAMED: dict[str, Callable[[], AbstractMotionLaw]] = {
    "freudenstein-1-3": FreudensteinOneThree,
    "freudenstein-1-3-5": FreudensteinOneThreeFive,
    **{name: (lambda a=a: TripleHarmonic(*a)) for name, a in TRIPLE_HARMONIC_PRESETS.items()},
}
"""Rest-to-rest laws of the trade with fixed names, beyond the classic seven."""

_IN_MOTION: dict[str, Callable[[], AbstractMotionLaw]] = {
    "constant-velocity": ConstantVelocity,
    "double-harmonic": DoubleHarmonic,
}

_ALIASES = {
    "cycloid": "cycloidal",
    "modsine": "modified-sine",
    "modified-sinusoid": "modified-sine",
    "modtrap": "modified-trapezoid",
    "modified-trapezoidal": "modified-trapezoid",
    "shm": "harmonic",
    "simple-harmonic": "harmonic",
    "constant-acceleration": "parabolic",
    "3-4-5": "poly345",
    "4-5-6-7": "poly4567",
}

FAMILIES = ("scca:A,B,C", "poly:K", "triple-harmonic:A1,A2",
            *(f"{name}-cv:P" for name in CV_BASES), "NAME-asym:L", "zv-NAME:N,ZETA", "zvd-NAME:N,ZETA",
            "ei-NAME:N,0,VTOL")
"""The parameterised rest-to-rest families ``get`` reads (``NAME``: a name of ``names()``)."""

IN_MOTION_FAMILIES = ("polynomial5:V0,A0,V1,A1", "polynomial7:V0,A0,J0,V1,A1,J1")


def names() -> list[str]:
    """Canonical names of the rest-to-rest laws with fixed names: the classic seven of
    ``standard_laws()`` first, then the named laws of the trade (``camjax laws`` lists them)."""
    return list(_STANDARD) + list(_NAMED)


def standard_laws() -> list[AbstractMotionLaw]:
    """One instance of each of the seven classic laws, the set reports compare by default."""
    return [make() for make in _STANDARD.values()]


def named_laws() -> list[AbstractMotionLaw]:
    """One instance of every law of ``names()``."""
    return [make() for make in (*_STANDARD.values(), *_NAMED.values())]


def _parameters(name: str, form: str, meaning: str, whole: bool = False) -> list:
    """The numbers after the colon of the law name ``name`` (as typed, case kept), one for
    each letter of ``form`` (``"scca:A,B,C"``), or a one-line ``ValueError`` saying which
    parameter is wrong and what it must be (``meaning``: what the letters stand for)."""
    letters = form.partition(":")[2].split(",")
    parts = [x.strip() for x in name.strip().partition(":")[2].split(",")]
    if len(parts) != len(letters):
        raise ValueError(f"law {name!r}: {form} takes {len(letters)} number{'s' if len(letters) > 1 else ''} "
                         f"after the colon ({meaning}), got {len(parts)}")
    values = []
    for letter, part in zip(letters, parts):
        if not part:
            raise ValueError(f"law {name!r}: {letter} is missing: {form} takes a number there ({meaning})")
        try:
            value = float(part)
        except ValueError:
            typed = f": in {form}, write a number in place of {letter}" if part.upper() == letter else ""
            raise ValueError(f"law {name!r}: {letter} must be a number ({meaning}), got {part!r}{typed}") from None
        if whole and not value.is_integer():
            raise ValueError(f"law {name!r}: {letter} must be a whole number ({meaning}), got {part!r}")
        values.append(int(value) if whole else value)
    return values


def get(name: str) -> AbstractMotionLaw:
    """The law called ``name``: a name of ``names()``, an alias, a family member
    (``FAMILIES``: ``scca:A,B,C``, ``modified-sine-asym:0.4``, ...) or a law that starts or
    ends in motion (``constant-velocity``, ``double-harmonic``, ``polynomial5:...``)."""
    if not isinstance(name, str):
        raise TypeError(f"a law name must be a string, got {type(name).__name__}")
    key = name.strip().lower().replace("_", "-").replace(" ", "-")
    key = _ALIASES.get(key, key)
    for table in (_STANDARD, _NAMED, _IN_MOTION):
        if key in table:
            return table[key]()
    family, _, text = key.partition(":")
    if family == "table":
        raise ValueError(f"law {name!r} is a lift table, fitted to points: camjax.laws.TableLaw.fit(angle_deg, "
                         'lift_mm), or in a program law = "table" with file = "....csv" or points')
    if key.startswith(("polynomial5:", "polynomial7:")):
        degree = int(key[10])
        keys = ("v0", "a0", "v1", "a1") if degree == 5 else ("v0", "a0", "j0", "v1", "a1", "j1")
        form = f"polynomial{degree}:{','.join(k.upper() for k in keys)}"
        values = _parameters(name, form, "boundary values in normalised units")
        return BoundaryPolynomial(**dict(zip(keys, values)), degree=degree)
    if family == "scca":
        return SCCA(*_parameters(name, "scca:A,B,C", "the fractions of the rise"))
    if family == "poly":
        (order,) = _parameters(name, "poly:K", "the polynomial's order, 2 to 12", whole=True)
        return PolynomialLaw(order)
    if family == "triple-harmonic":
        amplitudes = _parameters(name, "triple-harmonic:A1,A2", "two amplitudes; A3 closes the rise")
        return TripleHarmonic(*amplitudes)
    if family.endswith("-cv") and ":" in key:
        base = _ALIASES.get(family[:-3], family[:-3])
        (share,) = _parameters(name, f"{base}-cv:P", "the constant-velocity fraction, in [0, 1)")
        return constant_velocity_variant(base, share)
    if family.endswith("-asym") and ":" in key:
        base = _ALIASES.get(family[:-5], family[:-5])
        if base not in _STANDARD and base not in _NAMED:
            raise ValueError(f"law {name!r}: NAME-asym:L takes a law of {', '.join(names())}")
        (inflection,) = _parameters(name, f"{base}-asym:L", "the inflection point, in (0, 1)")
        return Inflected(get(base), inflection)
    shaper, _, base = family.partition("-")
    if shaper in SHAPERS and base and text:
        base = _ALIASES.get(base, base)
        if base not in _STANDARD and base not in _NAMED:
            raise ValueError(f"law {name!r}: {shaper}-NAME:N,ZETA takes a law of {', '.join(names())}")
        form = f"{shaper}-{base}:N,0,VTOL" if shaper == "ei" else f"{shaper}-{base}:N,ZETA"
        values = _parameters(name, form, "the base's design period ratio and the damping"
                             + (" (0), and the tolerated vibration" if shaper == "ei" else ""))
        return ShapedLaw(get(base), Shaper(shaper, *values[1:]), values[0])
    valid = ", ".join(names() + sorted(_ALIASES) + list(FAMILIES) + list(_IN_MOTION)
                      + list(IN_MOTION_FAMILIES))
    raise ValueError(f"unknown law {name!r}; valid names: {valid}")


def as_law(law, what: str = "law") -> AbstractMotionLaw:
    """``law`` itself, or the law that a name gives (``get``): how every public function
    that takes a motion law reads it, so that ``ct_curve("cycloidal", ...)`` works."""
    if isinstance(law, AbstractMotionLaw):
        return law
    if isinstance(law, str):
        return get(law)
    raise TypeError(f"{what} must be a camjax motion law or a law name, got {type(law).__name__}")


def rest_to_rest_fault(law: AbstractMotionLaw) -> str | None:
    """Why ``law`` is not a rise from rest to rest (``None`` if it is, or if it is traced).

    A rise from rest to rest starts and ends with ``v = 0`` (an acceleration step at an
    end, as in the simple harmonic and parabolic laws, is a jerk impulse the tools model;
    rising from rest to rest, it has Ca > 0, which Ct and R are per unit of) and is not
    meant to turn back without a dwell (``ends_in_reversal``).  Read from the law's
    concrete end states (``end_state``).
    """
    if law.ends_in_reversal:
        return "ends in a reversal (v = 0, a != 0) to turn back without a dwell"
    ends = law.end_state()
    if ends is None:
        return None
    v0, _, v1, _ = ends
    if abs(v0) > 1e-9 or abs(v1) > 1e-9:
        return f"starts or ends in motion (v(0) = {v0:.6g}, v(1) = {v1:.6g})"
    return None


def rest_to_rest_names() -> str:
    """The laws the rest-to-rest tools take, as their errors list them."""
    return ", ".join(names() + list(FAMILIES) + ["polynomial5/7 with V0 = V1 = 0", "B-spline and table laws (law files)"])


def rest_to_rest(law, tool: str, what: str = "law") -> AbstractMotionLaw:
    """``law`` (or the law its name gives) if it rises from rest to rest, else a one-line
    ``ValueError`` naming ``tool`` and the laws it takes: the one check of every tool that
    follows a rise with a dwell (Ct, residual vibration, backlash, the follower, sweeps)."""
    law = as_law(law, what)
    fault = rest_to_rest_fault(law)
    if fault is not None:
        raise ValueError(f"{tool} needs a rise from rest to rest; {what} {law.name!r} {fault}; "
                         f"{tool} takes {rest_to_rest_names()}")
    return law
