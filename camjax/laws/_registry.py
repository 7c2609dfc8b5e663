"""Look laws up by name: ``get("modsine")``, ``get("scca:0.25,0.5,0.25")``, ``get("poly:5")``.

``names()`` and ``standard_laws()`` list the rest-to-rest laws only; ``get`` also knows the
laws that start or end in motion (``constant-velocity``, ``polynomial5:V0,A0,V1,A1`` and
``polynomial7:V0,A0,J0,V1,A1,J1``, boundary values in normalised units).
"""

from __future__ import annotations

from collections.abc import Callable

from ._base import AbstractMotionLaw
from ._boundary import BoundaryPolynomial, ConstantVelocity
from ._polynomial import PolynomialLaw
from ._scca import (
    SCCA,
    Cycloidal,
    ModifiedSine,
    ModifiedTrapezoid,
    Parabolic,
    SimpleHarmonic,
)

_STANDARD: dict[str, Callable[[], AbstractMotionLaw]] = {
    "cycloidal": Cycloidal,
    "modified-sine": ModifiedSine,
    "modified-trapezoid": ModifiedTrapezoid,
    "harmonic": SimpleHarmonic,
    "parabolic": Parabolic,
    "poly345": lambda: PolynomialLaw(3),
    "poly4567": lambda: PolynomialLaw(4),
}

_IN_MOTION: dict[str, Callable[[], AbstractMotionLaw]] = {
    "constant-velocity": ConstantVelocity,
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


def names() -> list[str]:
    """Canonical names of the standard laws, in the order reports list them."""
    return list(_STANDARD)


def standard_laws() -> list[AbstractMotionLaw]:
    """One instance of every standard law."""
    return [make() for make in _STANDARD.values()]


def _parse_numbers(text: str, kind, name: str) -> list:
    try:
        return [kind(x) for x in text.split(",")]
    except ValueError:
        raise ValueError(f"cannot read the parameters of law {name!r}") from None


def get(name: str) -> AbstractMotionLaw:
    """The law called ``name``: a standard name, an alias, ``scca:A,B,C`` or ``poly:K``."""
    if not isinstance(name, str):
        raise TypeError(f"a law name must be a string, got {type(name).__name__}")
    key = name.strip().lower().replace("_", "-").replace(" ", "-")
    key = _ALIASES.get(key, key)
    if key in _STANDARD:
        return _STANDARD[key]()
    if key in _IN_MOTION:
        return _IN_MOTION[key]()
    if key.startswith(("polynomial5:", "polynomial7:")):
        degree = int(key[10])
        values = _parse_numbers(key[12:], float, name)
        keys = ("v0", "a0", "v1", "a1") if degree == 5 else ("v0", "a0", "j0", "v1", "a1", "j1")
        if len(values) != len(keys):
            raise ValueError(f"law {name!r}: polynomial{degree} takes {len(keys)} boundary values, "
                             f"'polynomial{degree}:{','.join(k.upper() for k in keys)}'")
        return BoundaryPolynomial(**dict(zip(keys, values)), degree=degree)
    if key.startswith("scca:"):
        fractions = _parse_numbers(key[5:], float, name)
        if len(fractions) != 3:
            raise ValueError(f"law {name!r}: scca takes three fractions, 'scca:A,B,C'")
        return SCCA(*fractions)
    if key.startswith("poly:"):
        (order,) = _parse_numbers(key[5:], int, name)
        return PolynomialLaw(order)
    valid = ", ".join(names() + sorted(_ALIASES) + ["scca:A,B,C", "poly:K"] + list(_IN_MOTION)
                      + ["polynomial5:V0,A0,V1,A1", "polynomial7:V0,A0,J0,V1,A1,J1"])
    raise ValueError(f"unknown law {name!r}; valid names: {valid}")


def as_law(law, what: str = "law") -> AbstractMotionLaw:
    """``law`` itself, or the law that a name gives (``get``): how every public function
    that takes a motion law reads it, so that ``ct_curve("cycloidal", ...)`` works."""
    if isinstance(law, AbstractMotionLaw):
        return law
    if isinstance(law, str):
        return get(law)
    raise TypeError(f"{what} must be a camjax motion law or a law name, got {type(law).__name__}")
