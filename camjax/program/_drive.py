"""Tables for servo drives: the cam's motion as an electronic cam loads it.

The master is the cam angle in degrees over one turn; the slave is the lift in mm, or the
swing angle in degrees for a swinging follower (``lift / arm_mm`` in radians, as degrees).
Every derivative is per master degree (not per second): the drive scales by the master's
speed itself.  Four formats (docs/drive-tables.md):

- ``csv``: equidistant rows of master, slave, velocity, acceleration and jerk;
- ``xyva``: knots (master, slave, velocity, acceleration) at every segment end and, inside
  a segment that is not a quintic, wherever the quintic Hermite interpolation between
  knots needs one to stay within ``tolerance`` of the true motion;
- ``codesys``: the same knots as CODESYS SoftMotion ``SM3_CamBuilder`` calls
  (``Poly5`` and ``Line`` segments with explicit ``Bound(x, y, v, a)``);
- ``twincat``: the same knots as Beckhoff TwinCAT ``MC_MotionFunctionPoint`` rows
  (function type 15, a fifth-order polynomial motion to motion, or 1, a straight line).

An acceleration step at a join (allowed in a program) is written as two knots at the same
master angle: the first ends the piece before it, the second starts the piece after it.
"""

from __future__ import annotations

import csv
import math
import os
import re
import secrets
import warnings
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..laws import ConstantVelocity
from ._program import Program
from ._turn import JOIN_TOLERANCE_DEG

DRIVE_TABLE_FORMATS = ("csv", "xyva", "codesys", "twincat")
"""The drive-table formats ``write_drive_table`` writes and ``read_drive_table`` reads."""
DRIVE_TABLE_FILE_NAMES = {"csv": "drive-table.csv", "xyva": "drive-table-xyva.csv",
              "codesys": "drive-table-codesys.st", "twincat": "drive-table-twincat.csv"}
"""The file each format gets in ``camjax program --drive-table FORMAT --out DIR``."""
DEFAULT_STEP_DEG = 0.1
DEFAULT_TOLERANCE = 1e-4
MAX_ROWS = 1_000_000
"""Most rows of a table (an equidistant step of 0.00036 degrees, or knots): more is refused
before any work."""

_SAMPLES = 24  # interior points per piece at which the Hermite interpolation is checked
_MIN_PIECE = 1e-9
_JERK_OFFSET = 1e-9  # the jerk is read this far (a fraction of the segment) after its angle  # narrowest piece, as a fraction of its segment
_TWINCAT_FUNCTION = {"poly5": 15, "line": 1, "dwell": 1, "step": 1, "end": 0}
"""MC_MotionFunctionType of the piece starting at a knot: MOTIONFUNCTYPE_POLYNOM5_MM (15,
motion to motion), MOTIONFUNCTYPE_POLYNOM1 (1, synchronous: a line, with zero slope in a
dwell), MOTIONFUNCTYPE_NOTDEF (0) at the last point."""
_TWINCAT_COLUMNS = ("PointIndex", "FunctionType", "PointType", "RelIndexNextPoint", "MasterPos",
                    "SlavePos", "SlaveVelo", "SlaveAcc", "SlaveJerk")


class DriveTable(NamedTuple):
    """A drive table's rows: master in degrees, slave in ``slave_unit``, derivatives per degree.

    ``piece`` names what runs from each row to the next: ``"poly5"`` (a quintic matching
    slave, velocity and acceleration at both rows), ``"line"`` (constant velocity),
    ``"dwell"`` (a line with zero slope), ``"step"`` (the next row is at the same master
    angle, with the acceleration after a step) or ``"end"`` (the last row).  An
    equidistant (``csv``) table has ``piece`` all ``"sample"``.
    """

    master_deg: np.ndarray
    slave: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray
    piece: tuple[str, ...]
    slave_unit: str


def check_drive_table_arguments(format: str, step_deg: float, tolerance: float, names: dict | None = None) -> None:
    """A one-line ``ValueError`` naming the argument (or ``names[argument]``) that is bad."""
    names = names or {}
    if format not in DRIVE_TABLE_FORMATS:
        raise ValueError(f"{names.get('format', 'format')} must be one of {', '.join(DRIVE_TABLE_FORMATS)}, got {format!r}")
    what = names.get("step_deg", "step_deg")
    if not (isinstance(step_deg, int | float) and math.isfinite(step_deg) and step_deg > 0):
        raise ValueError(f"{what} must be a positive number of degrees, got {step_deg!r}")
    count = round(360.0 / step_deg)
    if count > MAX_ROWS:
        raise ValueError(f"{what} = {step_deg:g} gives {count:,} rows; the limit is {MAX_ROWS:,} "
                         f"(a step of at least {360.0 / MAX_ROWS:g} degrees)")
    if count < 1 or abs(count * step_deg - 360.0) > 1e-9 * 360.0:
        raise ValueError(f"{what} = {step_deg:g} does not divide 360 degrees into whole steps "
                         "(try 0.1, 0.25, 0.5 or 1)")
    what = names.get("tolerance", "tolerance")
    if not (isinstance(tolerance, int | float) and math.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"{what} must be positive, got {tolerance!r}")


def _segment_jet(program: Program, index: int, tau) -> tuple[np.ndarray, ...]:
    """Slave and its three derivatives per degree inside segment ``index`` at ``tau`` in [0, 1]."""
    scale, _ = program.follower.displacement_per_lift  # slave units per mm of lift
    tau = np.asarray(tau, dtype=float)
    # the jerk just after each angle (before it at the segment's end), the side the rows
    # take: at a law's breakpoint the jerk may step, and the law's own value there is
    # either side's (or neither: the SCCA laws give 0 at their midpoint)
    after = np.where(tau < 1.0, np.minimum(tau + _JERK_OFFSET, 1.0), 1.0 - _JERK_OFFSET)
    y, v, a, _ = program.turn.segment_jet(index, tau)
    j = program.turn.segment_jet(index, after)[3]
    return tuple(scale * np.asarray(x, dtype=float) for x in (y, v, a, j))


def _samples(program: Program, step_deg: float) -> DriveTable:
    count = round(360.0 / step_deg)
    master = np.arange(count + 1) * 360.0 / count  # exact at every whole-degree join
    # each angle read after it (the last, 360, before it: the turn's end), the joins
    # within rounding snapped to the join (``Turn.locate``)
    owner, tau = program.turn.locate(master[:-1], "after")
    last, last_tau = program.turn.locate(master[-1:], "before")
    owner, tau = np.append(owner, last), np.append(tau, last_tau)
    starts = np.append(program.start_deg, 360.0)
    near = np.abs(master[:, None] - starts[None, :]) <= JOIN_TOLERANCE_DEG
    master = np.where(near.any(axis=1), starts[np.argmax(near, axis=1)], master)
    out = [np.zeros_like(master) for _ in range(4)]
    for i in range(len(program.segments)):
        inside = owner == i
        if inside.any():
            for column, values in zip(out, _segment_jet(program, i, tau[inside])):
                column[inside] = values
    return DriveTable(master, *out, ("sample",) * master.size, program.follower.displacement_per_lift[1])


def _hermite(h, y0, v0, a0, y1, v1, a1, t):
    """The quintic matching value, slope and curvature at both ends of a piece of width ``h``."""
    t2, t3 = t * t, t * t * t
    t4, t5 = t3 * t, t3 * t2
    return (y0 * (1 - 10 * t3 + 15 * t4 - 6 * t5) + h * v0 * (t - 6 * t3 + 8 * t4 - 3 * t5)
            + h * h * a0 * (t2 - 3 * t3 + 3 * t4 - t5) / 2 + y1 * (10 * t3 - 15 * t4 + 6 * t5)
            + h * v1 * (-4 * t3 + 7 * t4 - 3 * t5) + h * h * a1 * (t3 - 2 * t4 + t5) / 2)


def _segment_knots(program: Program, index: int, tolerance: float) -> np.ndarray:
    """Knots (fractions of segment ``index``) at which the quintic Hermite interpolation is
    within ``tolerance`` of the motion: the law's breakpoints, then bisection of each piece
    that misses it, all pieces of a level evaluated together."""
    seg = program.segments[index]
    if not seg.moving or isinstance(seg.law, ConstantVelocity):
        return np.array([0.0, 1.0])
    breaks = np.asarray(seg.law.breakpoints(), dtype=float).ravel()
    knots = np.unique(np.concatenate([[0.0, 1.0], breaks[(breaks > 0) & (breaks < 1)]]))
    pending = list(zip(knots[:-1], knots[1:]))
    accepted = []
    t = np.arange(1, _SAMPLES + 1) / (_SAMPLES + 1)
    while pending:
        lo, hi = (np.array(x) for x in zip(*pending))
        width = hi - lo
        if width.min() < _MIN_PIECE or len(accepted) + len(pending) > MAX_ROWS:
            raise ValueError(f"tolerance = {tolerance:g} cannot be met in segment {index + 1} "
                             "(the pieces would be narrower than rounding allows): raise it")
        ends = _segment_jet(program, index, np.concatenate([lo, hi]))
        y0, v0, a0 = (x[: lo.size, None] for x in ends[:3])
        y1, v1, a1 = (x[lo.size:, None] for x in ends[:3])
        inner = lo[:, None] + width[:, None] * t
        true = _segment_jet(program, index, inner)[0]
        h = (width * seg.angle_deg)[:, None]
        error = np.max(np.abs(_hermite(h, y0, v0, a0, y1, v1, a1, t) - true), axis=1)
        good = error <= tolerance
        accepted += [float(x) for x in hi[good]]
        mid = (lo + hi) / 2
        pending = [p for b, l, m, u in zip(good, lo, mid, hi) if not b for p in ((l, m), (m, u))]
    return np.unique(np.concatenate([[0.0], accepted]))


def _knots(program: Program, tolerance: float) -> DriveTable:
    scale, unit = program.follower.displacement_per_lift  # slave units per mm of lift
    floor = 1e-11 * scale * max(1.0, float(np.max(np.abs(np.append(program.start_lift_mm, 0.0)))))
    if tolerance < floor:  # below the float rounding of the slave: no bisection can meet it
        raise ValueError(f"tolerance = {tolerance:g} cannot be met: it is below the rounding of the "
                         f"slave ({floor:.1g} {unit}); raise it")
    rows = []  # (master, y, v, a, j, piece)
    # an acceleration this much apart either side of a join is rounding, not a step
    lifts = [abs(s.lift_mm) for s in program.segments]
    same = 1e-9 * scale * max(lifts) / min(s.angle_deg for s in program.segments) ** 2
    for i, seg in enumerate(program.segments):
        tau = _segment_knots(program, i, tolerance)
        y, v, a, j = _segment_jet(program, i, tau)
        master = program.start_deg[i] + tau * seg.angle_deg
        master[-1] = program.start_deg[i] + seg.angle_deg if i + 1 < len(program.segments) else 360.0
        kind = "dwell" if not seg.moving else "line" if isinstance(seg.law, ConstantVelocity) else "poly5"
        if rows:  # the join: one knot, or two where the acceleration steps
            before = rows.pop()
            if abs(before[3] - a[0]) > same:
                rows.append((*before[:5], "step"))
        rows += [(master[k], y[k], v[k], a[k], j[k], kind) for k in range(tau.size)]
    rows[-1] = (*rows[-1][:5], "end")
    master, y, v, a, j = (np.array(c, dtype=float) for c in list(zip(*rows))[:5])
    return DriveTable(master, y, v, a, j, tuple(r[5] for r in rows), unit)


def drive_table(program: Program, format: str = "csv", *, step_deg: float = DEFAULT_STEP_DEG,
                tolerance: float = DEFAULT_TOLERANCE) -> DriveTable:
    """The rows ``write_drive_table`` writes: equidistant every ``step_deg`` degrees (``csv``,
    0 to 360 both included), or the knots of the quintic Hermite interpolation within
    ``tolerance`` (slave units: mm, or degrees of swing) of the motion (the other formats).
    A ``csv`` step too coarse for the motion (``coarse_step``) is a ``UserWarning``."""
    check_drive_table_arguments(format, step_deg, tolerance)
    if format != "csv":
        return _knots(program, tolerance)
    coarse = coarse_step(program, step_deg)
    if coarse is not None:
        warnings.warn(coarse, stacklevel=2)
    return _samples(program, step_deg)


MIN_ROWS_PER_SEGMENT = 10
"""Fewest rows of an equidistant table across the shortest moving segment: with fewer, the
drive's interpolation between rows does not follow the segment's motion."""


def coarse_step(program: Program, step_deg: float) -> str | None:
    """The line saying that an equidistant step of ``step_deg`` degrees puts fewer than
    ``MIN_ROWS_PER_SEGMENT`` rows across the shortest moving segment (with the table's count
    of rows and the step that gives enough), or ``None``."""
    moving = [(s.angle_deg, i) for i, s in enumerate(program.segments, 1) if s.moving]
    if not moving:
        return None
    angle, index = min(moving)
    if angle / step_deg >= MIN_ROWS_PER_SEGMENT:
        return None
    rows = round(360.0 / step_deg) + 1
    return (f"a step of {step_deg:g} deg gives a table of {rows:,} rows, about {angle / step_deg:.3g} across "
            f"segment {index} ({angle:g} deg, the shortest moving one): the drive's interpolation between "
            f"rows does not follow its motion; a step of at most {angle / MIN_ROWS_PER_SEGMENT:.3g} deg puts "
            f"{MIN_ROWS_PER_SEGMENT} rows across it (one that divides 360, such as 0.1)")


def _real(x: float) -> str:
    """An IEC 61131-3 LREAL literal that reads back to the same float (a point in the mantissa)."""
    text = repr(float(x) + 0.0)
    if "e" in text:
        mantissa, exponent = text.split("e")
        text = (mantissa if "." in mantissa else mantissa + ".0") + "E" + exponent
    return text


def _text(program: Program, table: DriveTable, format: str) -> str:
    unit = table.slave_unit
    columns = ["master_deg", f"slave_{unit}", f"velocity_{unit}_per_deg", f"acceleration_{unit}_per_deg2"]
    rows = zip(table.master_deg, table.slave, table.velocity, table.acceleration, table.jerk)
    if format in ("csv", "xyva"):
        lines = [",".join(columns + ([f"jerk_{unit}_per_deg3"] if format == "csv" else []))]
        lines += [",".join(repr(float(x) + 0.0) for x in (r if format == "csv" else r[:4])) for r in rows]
        return "\n".join(lines) + "\n"
    if format == "twincat":
        lines = [",".join(_TWINCAT_COLUMNS)]
        # MC_MotionPointType: rest 1, velocity 2, turn (reversal) 4, motion 8; rounding is zero
        v_zero = 1e-12 * max(np.max(np.abs(table.velocity)), 1e-300)
        a_zero = 1e-12 * max(np.max(np.abs(table.acceleration)), 1e-300)
        for k, (row, piece) in enumerate(zip(rows, table.piece), 1):
            rest, smooth = abs(row[2]) <= v_zero, abs(row[3]) <= a_zero
            point = (1 if smooth else 4) if rest else (2 if smooth else 8)
            lines.append(",".join([str(k), str(_TWINCAT_FUNCTION[piece]), str(point), "1"]
                                  + [repr(float(x) + 0.0) for x in row]))
        return "\n".join(lines) + "\n"
    # codesys: one CamBuilder segment per piece, explicit bounds on both sides
    knots = list(zip(table.master_deg, table.slave, table.velocity, table.acceleration))
    segments = [(table.piece[k], knots[k], knots[k + 1]) for k in range(len(knots) - 1)
                if table.piece[k] != "step"]
    bound = "SMCB.Bound({}, {}, {}, {})".format
    lines = [f"(* camjax drive table of program {program.name!r}: master X in degrees over one turn, "
             f"slave Y in {unit}, V in {unit}/deg, A in {unit}/deg^2 (per master degree). *)",
             f"(* {len(segments)} segments: SM3_CamBuilder's library parameter MAX_CAM_SEGMENT_COUNT "
             "must allow them. *)",
             "(* VAR camBuilder : SMCB.CamBuilder; END_VAR *)",
             "camBuilder.Init();"]
    for piece, left, right in segments:
        kind = "Poly5" if piece == "poly5" else "Line"
        lines.append(f"camBuilder.Append(SMCB.{kind}({bound(*map(_real, left))}, {bound(*map(_real, right))}));")
    return "\n".join(lines) + "\n"


def write_drive_table(program: Program, path, format: str = "csv", *, step_deg: float = DEFAULT_STEP_DEG,
                      tolerance: float = DEFAULT_TOLERANCE) -> Path:
    """Write ``program``'s motion as a drive table (``DRIVE_TABLE_FORMATS``) to ``path``, atomically: the
    text goes to a temporary file beside ``path`` and is renamed over it only when whole.  The
    file gets the mode every other output gets (0666 less the umask), not a temporary file's 0600."""
    table = drive_table(program, format, step_deg=step_deg, tolerance=tolerance)
    text = _text(program, table, format)
    path = Path(path)
    temporary = path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp"
    try:
        descriptor = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # the umask applies
        with open(descriptor, "w", newline="") as handle:
            handle.write(text)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    return path


_BOUND = re.compile(r"Bound\(([^()]*)\)")


def read_drive_table(path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(master, slave, velocity, acceleration)`` read back from a file of any of the
    ``DRIVE_TABLE_FORMATS`` (told apart by its first line); a ``ValueError`` names a file that is none."""
    path = Path(path)
    text = path.read_text()
    first = text.split("\n", 1)[0]
    try:
        if first.startswith("(*"):
            bounds = [tuple(float(x) for x in m.split(",")) for m in _BOUND.findall(text)]
            rows = [b for k, b in enumerate(bounds) if k == 0 or b != bounds[k - 1]]
        else:
            reader = list(csv.reader(text.splitlines())) or [[]]
            header = reader[0]
            if header[:2] == list(_TWINCAT_COLUMNS[:2]):
                rows = [tuple(float(x) for x in r[4:8]) for r in reader[1:] if r]
            elif header and header[0] == "master_deg":
                rows = [tuple(float(x) for x in r[:4]) for r in reader[1:] if r]
            else:
                raise ValueError(f"{path}: not a camjax drive table (first line {first[:60]!r})")
    except ValueError as error:
        if str(error).startswith(f"{path}: "):
            raise
        raise ValueError(f"{path}: a drive table with a value that is not a number ({error})") from None
    if not rows or any(len(r) != 4 for r in rows):
        raise ValueError(f"{path}: no drive-table rows of master, slave, velocity, acceleration")
    master, slave, velocity, acceleration = (np.array(c) for c in zip(*rows))
    return master, slave, velocity, acceleration
