"""Lift tables: a segment, or a whole cam, given by its points.

A table is ``angle_deg, lift_mm`` rows: a CSV file (a header naming the two columns, tab,
semicolon or comma separated, ``.`` decimals) or inline ``points = [[angle, lift], ...]``.  A
segment's table runs from 0 to the segment's angle and becomes one ``TableLaw`` (rest to
rest); a whole cam's table starts at 0 and ends below 360 degrees and is fitted
periodically, then cut at its highest point into a rise and a return, so that the
program's lift (measured from the lift at 0 degrees) is the periodic spline itself.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from ..checks import finite_number
from ..laws import (
    MAX_TABLE_POINTS,
    MIN_TABLE_POINTS,
    TableFit,
    TableLaw,
    evaluate_pieces,
    peak_acceleration,
    spline_fit,
    table_checks,
)

COLUMNS = ("angle_deg", "lift_mm")
SEPARATORS = {"\t": "tab", ";": "semicolon", ",": "comma"}
"""A table's column separators, the first found in its header chosen."""
_LIFT_MATCH_MM = 1e-6
"""How closely a table segment's ``lift_mm`` must equal its table's last minus first lift
(plus its ``smoothing_mm``)."""


def read_csv(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """The ``angle_deg`` and ``lift_mm`` columns of a CSV file; a one-line ``ValueError``
    naming the file and the line where a row is short or holds text for a number."""
    if not path.exists():
        raise ValueError(f"lift table {str(path)!r} not found")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as error:
        raise ValueError(f"{path}: cannot be read as text ({error})") from None
    lines = [(n, line.strip()) for n, line in enumerate(text.splitlines(), 1)]
    lines = [(n, line) for n, line in lines if line and not line.startswith("#")]
    if not lines:
        raise ValueError(f"{path}: empty; a lift table has a header ({', '.join(COLUMNS)}) and rows")
    n_head, head = lines[0]
    sep = next((s for s in SEPARATORS if s in head), ",")
    names = [c.strip().strip('"').lower() for c in head.split(sep)]
    missing = [c for c in COLUMNS if c not in names]
    if missing:
        read_as = (f"read as {SEPARATORS[sep]}-separated" if sep in head else
                   "no tab, ';' or ',' separates its names")
        raise ValueError(f"{path}: line {n_head}: the header must name the columns "
                         f"{' and '.join(COLUMNS)} (found {len(names)} name(s), {read_as}); "
                         f"missing {', '.join(missing)}")
    columns = [names.index(c) for c in COLUMNS]
    rows, line_numbers = [], []
    for n, line in lines[1:]:
        cells = [c.strip().strip('"') for c in line.split(sep)]
        if len(cells) <= max(columns):
            raise ValueError(f"{path}: line {n}: {len(cells)} field(s), the header has {len(names)}")
        row = []
        for name, k in zip(COLUMNS, columns):
            try:
                value = float(cells[k])
            except ValueError:
                hint = " (decimals take '.', not ',')" if "," in cells[k] or (sep != "," and "," in line) else ""
                raise ValueError(f"{path}: line {n}: {name} (column {k + 1}) is not a number{hint}") from None
            if not math.isfinite(value):
                raise ValueError(f"{path}: line {n}: {name} (column {k + 1}) must be finite")
            row.append(value)
        rows.append(row)
        line_numbers.append(n)
    return _valid_table(np.array(rows).reshape(-1, 2), str(path), [f"line {n}" for n in line_numbers])


def read_points(points, where: str) -> tuple[np.ndarray, np.ndarray]:
    """``[[angle_deg, lift_mm], ...]`` from a program file (``where`` names it in errors)."""
    if not isinstance(points, (list, tuple)):
        raise ValueError(f"{where}: points must be a list of [angle_deg, lift_mm] pairs")
    rows = []
    for k, row in enumerate(points, 1):
        if not isinstance(row, (list, tuple)) or len(row) != 2:
            raise ValueError(f"{where}: points row {k} must be a pair [angle_deg, lift_mm], got {row!r}")
        for name, value in zip(COLUMNS, row):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"{where}: points row {k}: {name} {value!r} is not a number")
            if not math.isfinite(value):
                raise ValueError(f"{where}: points row {k}: {name} must be finite, got {value!r}")
        rows.append([float(row[0]), float(row[1])])
    return _valid_table(np.array(rows).reshape(-1, 2), where, [f"points row {k}" for k in range(1, len(rows) + 1)])


def _valid_table(table: np.ndarray, where: str, rows: list[str]):
    if len(table) < MIN_TABLE_POINTS:
        raise ValueError(f"{where}: {len(table)} point(s); a lift table needs at least {MIN_TABLE_POINTS} "
                         "(its spline is of degree 5)")
    if len(table) > MAX_TABLE_POINTS:
        raise ValueError(f"{where}: {len(table):,} points; the limit is {MAX_TABLE_POINTS:,} (thin the table)")
    angle = table[:, 0]
    for k in range(1, len(angle)):
        if angle[k] <= angle[k - 1]:
            raise ValueError(f"{where}: {rows[k]}: angle_deg {angle[k]:g} does not increase "
                             f"(the row before has {angle[k - 1]:g})")
    return angle, table[:, 1]


def table_points(data: dict, where: str, base: Path | None):
    """The points of a ``file`` or ``points`` entry and the name its errors carry."""
    if ("file" in data) == ("points" in data):
        raise ValueError(f'{where}: a lift table needs file = "....csv" or points = [[angle_deg, lift_mm], ...] '
                         "(one of them)")
    if "file" in data:
        name = data["file"]
        if not isinstance(name, str):
            raise ValueError(f"{where}: file must be a path, got {name!r}")
        path = Path(name) if base is None else base / name
        try:
            angle, lift = read_csv(path)
        except ValueError as error:
            raise ValueError(f"{where}: {error}") from None
        return angle, lift, name
    angle, lift = read_points(data["points"], where)
    return angle, lift, "points"


def smoothing(data: dict, where: str) -> float | None:
    value = data.get("smoothing_mm")
    if value is None:
        return None
    value = finite_number(value, f"{where}: smoothing_mm")
    if value <= 0:
        raise ValueError(f"{where}: smoothing_mm must be a positive tolerance in mm, got {value:g}")
    return value


def segment_law(where: str, angle_deg, lift_mm, data: dict, base: Path | None):
    """``(lift_mm, TableLaw)`` of a program file's ``law = "table"`` segment."""
    angle, lift, source = table_points(data, where, base)
    tolerance = smoothing(data, where)
    label = source
    if angle[0] != 0.0:
        raise ValueError(f"{where}: {label}: the first angle_deg must be 0 (angles run from the "
                         f"segment's start), got {angle[0]:g}")
    if abs(angle[-1] - angle_deg) > 1e-9 * max(1.0, angle_deg):
        raise ValueError(f"{where}: {label}: the last angle_deg ({angle[-1]:g}) must be the "
                         f"segment's angle_deg ({angle_deg:g})")
    rise = float(lift[-1] - lift[0])
    if lift_mm is None:
        lift_mm = rise
    elif abs(lift_mm - rise) > _LIFT_MATCH_MM * max(1.0, abs(rise)) + (tolerance or 0.0):
        raise ValueError(f"{where}: lift_mm = {lift_mm:g} but {label} rises {rise:.6g} mm "
                         "(its last lift minus its first); leave lift_mm out to take the table's")
    if lift_mm == 0:
        raise ValueError(f"{where}: {label}: the last lift equals the first; a lift table segment "
                         "rises or returns (a dwell needs no table)")
    try:
        law = TableLaw.fit(angle, lift, tolerance, lift=lift_mm, source=source)
    except ValueError as error:
        raise ValueError(f"{where}: {label}: {error}") from None
    return lift_mm, law


def turn_segments(angle, lift, smoothing_mm: float | None, source: str, where: str = "[program]", *,
                  denser=None, notes: tuple[str, ...] = ()):
    """The segments ``(angle_deg, lift_mm, TableLaw)`` of a whole cam's periodic table: a
    rise from 0 degrees to its highest point and a return to 360.  ``denser``: the same
    cam's ``(angle, lift)`` at more angles (a drawing read again), against whose fit the
    spacing is checked instead of a fit through every other point; ``notes`` go to the
    report's warnings.  Errors start ``where: source:`` (``source:`` where ``where`` is empty)."""
    prefix = f"{where}: {source}" if where else source
    if angle[0] != 0.0:
        raise ValueError(f"{prefix}: a whole cam's table starts at angle_deg 0, got {angle[0]:g}")
    if angle[-1] >= 360.0:
        raise ValueError(f"{prefix}: the last angle_deg ({angle[-1]:g}) must be below 360 "
                         "(360 is 0 again: the table closes over the turn)")
    widest = float(np.max(np.diff(angle)))
    if 360.0 - angle[-1] > 2.0 * widest:
        raise ValueError(f"{prefix}: the table ends at {angle[-1]:g} deg and does not close "
                         f"over the turn (its gap to 360 is more than twice its widest spacing, "
                         f"{widest:g} deg); give the whole turn")
    try:
        (edges, taylor), deviation = spline_fit(angle / 360.0, lift, smoothing_mm, period=1.0, angle_scale=360.0)
    except ValueError as error:
        raise ValueError(f"{prefix}: {error}") from None
    info = table_checks(angle / 360.0, lift, smoothing_mm, deviation, taylor, period=1.0,
                        check_spacing=denser is None)
    if denser is not None:
        (dense_edges, dense), _ = spline_fit(np.asarray(denser[0]) / 360.0, denser[1], smoothing_mm, period=1.0)
        ratio = peak_acceleration(edges, taylor) / max(peak_acceleration(dense_edges, dense), 1e-300)
        info = dataclasses.replace(info, spacing_ratio=float(ratio),
                                   spacing_check=f"the drawing read at {len(denser[0])} angles")
    info = dataclasses.replace(info, notes=tuple(notes))
    slack = max(1e-6, smoothing_mm or 0.0, 3 * info.noise_mm)
    low = int(np.argmin(lift))
    if lift[low] < lift[0] - slack:
        raise ValueError(f"{prefix}: angle 0 must be on the base circle (the program's lift "
                         f"is measured from it), but the lift there is {lift[0]:g} mm and at "
                         f"{angle[low]:g} deg {lift[low]:g} mm; start the table at its lowest point")
    top = int(np.argmax(lift))
    if top == 0 or np.ptp(lift) == 0:
        raise ValueError(f"{prefix}: the highest lift must lie after angle 0 (angle 0 is "
                         "the base circle, where the program's lift is 0)")
    turn = tuple(zip(map(float, angle), map(float, lift)))
    y0 = _value(edges, taylor, 0)
    y_top = _value(edges, taylor, top)
    out = []
    for first, last, rise in ((0, top, y_top - y0), (top, len(angle), y0 - y_top)):
        x0, x1 = edges[first], edges[last]
        width = x1 - x0
        pieces = taylor[first:last] * width ** np.arange(6)
        pieces[:, 0] -= _value(edges, taylor, first)
        mine = np.arange(first, last)
        points = tuple((360.0 * (edges[k] - x0), float(lift[k])) for k in mine)
        fit = dataclasses.replace(
            info, points=points, source=source, smoothing_mm=smoothing_mm,
            deviation_mm=_deviation(edges, taylor, angle / 360.0, lift, mine), turn=turn)
        out.append((float(360.0 * width), float(rise), TableLaw(pieces / rise, (edges[first:last + 1] - x0) / width, fit)))
    return out


def _value(edges, taylor, k: int) -> float:
    """The spline's lift at knot ``k``, from its piece ``k`` (the left end of it)."""
    half = 0.5 * (edges[k + 1] - edges[k])
    return float(np.polynomial.polynomial.polyval(-half, taylor[k]))


def _deviation(edges, taylor, x, y, rows) -> float:
    return float(np.max(np.abs(evaluate_pieces(edges, taylor, x[rows]) - y[rows])))


def points_toml(points) -> str:
    """``[[angle, lift], ...]`` as TOML (full precision: a program written back reads the same)."""
    return "[" + ", ".join(f"[{a!r}, {y!r}]" for a, y in points) + "]"


__all__ = ["COLUMNS", "TableFit", "TableLaw", "read_csv", "read_points", "segment_law", "turn_segments"]
