"""Plain values that the library, the command line and the studio share, without JAX.

``json_ready`` turns a result into JSON's types, ``parse_range`` reads a speed range
written as text, ``DEFAULT_SPEED_FLUCTUATION`` is the flywheel's default coefficient, and
``example_names`` and ``example_file`` know the program files shipped with camjax.
Nothing here imports JAX (nor NumPy at import time), so that the command line's ``--help``
can show the defaults at once.  (Floor 1: imports nothing from the rest of camjax at import
time.)
"""

from __future__ import annotations

import math
from pathlib import Path

DEFAULT_SPEED_FLUCTUATION = 0.05
"""The coefficient of speed fluctuation ``Cs = (max - min speed) / mean`` the flywheel is
sized for unless another is given (``camjax.program.analyse``, ``camjax program``)."""


def json_ready(value):
    """Nested lists of floats for JSON, with inf and NaN as null (a typed result: its
    ``as_dict()``)."""
    import numpy as np

    if hasattr(value, "as_dict") and not isinstance(value, type):
        return json_ready(value.as_dict())
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [json_ready(v) for v in value]
    if isinstance(value, float | np.floating):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


def parse_float_list(text: str, what: str) -> list[float]:
    """``"1,2.5,4"`` as finite floats, or a one-line ``ValueError`` starting with ``what``."""
    try:
        values = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise ValueError(f"{what}: cannot read {text!r} as comma-separated numbers") from None
    if not values:
        raise ValueError(f"{what}: no values given")
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"{what}: values must be finite, got {text!r}")
    return values


def parse_range(text: str, what: str, check_count=None):
    """``START:STOP:COUNT`` (inclusive, ascending linspace) or ``V1,V2,...`` as an array, or
    a one-line ``ValueError`` that starts with ``what`` (the option or key the text came from).

    A range runs upward: ``START`` above ``STOP`` is refused (list values to go down).
    ``check_count(count, what)``, if given, checks ``COUNT`` before the range is built.
    """
    import numpy as np

    if ":" not in text:
        return np.asarray(parse_float_list(text, what))
    parts = text.split(":")
    if len(parts) != 3:
        raise ValueError(f"{what}: expected START:STOP:COUNT, got {text!r}")
    start, stop = parse_float_list(parts[0], what)[0], parse_float_list(parts[1], what)[0]
    try:
        count = int(parts[2])
    except ValueError:
        raise ValueError(f"{what}: COUNT must be an integer, got {parts[2]!r}") from None
    if count < 1:
        raise ValueError(f"{what}: COUNT must be at least 1, got {count}")
    if check_count is not None:
        check_count(count, what)
    if start > stop or (start == stop and count > 1):
        raise ValueError(f"{what}: START must be below STOP in START:STOP:COUNT, got {text!r} "
                         "(ranges run upward; give V1,V2,... for another order)")
    return np.linspace(start, stop, count)


def plot_speed(report, chosen: float | None = None) -> float:
    """The speed whose turn the figures draw: ``chosen``, else the speed given nearest the
    jump speed (the lowest speed when the jump lies below the range), else the highest.
    ``report`` is a program's ``Report`` or its ``as_dict()``."""
    if isinstance(report, dict):
        speeds, below, jump = [s["rpm"] for s in report["speeds"]], report["jump_below_range"], report["jump_speed_rpm"]
    else:
        speeds, below, jump = [s.rpm for s in report.speeds], report.jump_below_range, report.jump_speed_rpm
    if chosen is not None:
        return chosen
    if below:
        return min(speeds)
    if jump is not None:
        return min(speeds, key=lambda r: abs(r - jump))
    return max(speeds)


EXAMPLES = Path(__file__).parent / "program" / "examples"
"""The program files shipped with camjax (a chain's in its ``trains`` folder)."""


def example_file(name: str) -> Path:
    """The built-in example program ``name`` ('indexer', 'valve', ...): ``EXAMPLES`` or its
    ``trains`` folder (the path where it would be if there is none such)."""
    train = EXAMPLES / "trains" / f"{name}.toml"
    return train if train.exists() and not (EXAMPLES / f"{name}.toml").exists() else EXAMPLES / f"{name}.toml"


def example_names() -> list[str]:
    """The built-in example programs' names, sorted: every TOML file of ``EXAMPLES`` and its
    ``trains`` folder that holds a ``[follower]`` (a motor's record does not)."""
    files = [*EXAMPLES.glob("*.toml"), *(EXAMPLES / "trains").glob("*.toml")]
    return sorted({f.stem for f in files if "\n[follower]" in "\n" + f.read_text(encoding="utf-8")})
