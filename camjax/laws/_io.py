"""Save and load motion laws as JSON: B-spline and table laws by their coefficients, others by name."""

from __future__ import annotations

import json
from pathlib import Path

import jax.numpy as jnp
import numpy as np

from ..checks import read_text
from ._base import AbstractMotionLaw
from ._boundary import CorrectedPolynomial
from ._registry import get
from ._spline import BSplineLaw
from ._table import TableLaw

FORMAT = "camjax-law"
VERSION = 1


def to_dict(law: AbstractMotionLaw) -> dict:
    """A JSON-ready description that :func:`from_dict` turns back into ``law``."""
    if isinstance(law, BSplineLaw):
        return {
            "format": FORMAT,
            "version": VERSION,
            "kind": "bspline",
            "degree": law.degree,
            "zero_jerk": law.zero_jerk,
            "knots": [float(x) for x in law.knots],
            "control_points": [float(x) for x in np.asarray(law.control_points)],
            "coefficients": [float(x) for x in np.asarray(law.coefficients)],
        }
    if isinstance(law, TableLaw):
        return {
            "format": FORMAT,
            "version": VERSION,
            "kind": "table",
            "edges": list(law.edges),
            "coefficients": np.asarray(law.coefficients, dtype=float).tolist(),
        }
    if isinstance(law, CorrectedPolynomial):
        return {
            "format": FORMAT,
            "version": VERSION,
            "kind": "corrected-polynomial",
            "base": law.base.name,
            "spline_degree": law.spline_degree,
            "coefficients": [float(x) for x in np.asarray(law.coefficients)],
        }
    name = law.name
    rebuilt = get(name)
    tau = np.linspace(0.0, 1.0, 101)
    if type(rebuilt) is not type(law) or not np.allclose(rebuilt.s(tau), law.s(tau), atol=1e-14):
        raise ValueError(f"law {name!r} cannot be saved: its name does not rebuild it")
    return {"format": FORMAT, "version": VERSION, "kind": "named", "name": name}


def from_dict(data: dict) -> AbstractMotionLaw:
    """The law described by ``data`` (as written by :func:`to_dict`)."""
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ValueError(f"not a camjax law description (expected format {FORMAT!r})")
    if data.get("version") != VERSION:
        raise ValueError(f"unsupported camjax law version {data.get('version')!r}")
    kind = data.get("kind")
    if kind == "named":
        if not isinstance(data.get("name"), str):
            raise ValueError("named law description lacks its 'name'")
        return get(data["name"])
    if kind == "corrected-polynomial":
        try:
            return CorrectedPolynomial(get(data["base"]), jnp.asarray(np.asarray(data["coefficients"], dtype=float)),
                                       spline_degree=int(data["spline_degree"]))
        except KeyError as missing:
            raise ValueError(f"corrected-polynomial law description lacks {missing}") from None
    if kind == "table":
        try:
            return TableLaw(np.asarray(data["coefficients"], dtype=float), data["edges"])
        except KeyError as missing:
            raise ValueError(f"table law description lacks {missing}") from None
    if kind != "bspline":
        raise ValueError(f"unknown law kind {kind!r}; expected 'bspline', 'table', 'corrected-polynomial' "
                         "or 'named'")
    try:
        law = BSplineLaw(
            jnp.asarray(np.asarray(data["coefficients"], dtype=float)),
            degree=int(data["degree"]),
            zero_jerk=bool(data.get("zero_jerk", False)),
        )
    except KeyError as missing:
        raise ValueError(f"B-spline law description lacks {missing}") from None
    if "knots" in data and not np.allclose(np.asarray(data["knots"], dtype=float), law.knots,
                                           rtol=0, atol=1e-12):
        raise ValueError("B-spline law knots differ from the uniform clamped knots camjax builds")
    return law


def save(law: AbstractMotionLaw, path) -> Path:
    """Write ``law`` to ``path`` as JSON; returns the path."""
    path = Path(path)
    path.write_text(json.dumps(to_dict(law), indent=1) + "\n")
    return path


def load(path) -> AbstractMotionLaw:
    """Read a law written by :func:`save`; a ``ValueError`` naming the file if it cannot."""
    path = Path(path)
    text = read_text(path, "camjax law file", "JSON")
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not valid JSON ({error})") from None
    try:
        return from_dict(data)
    except (ValueError, TypeError) as error:
        raise ValueError(f"{path}: {error}") from None
