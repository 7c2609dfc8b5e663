"""``camjax program``: a whole cam at machine speed: steady state, contact force, jump, profile."""

from __future__ import annotations

import csv
import io
import math
import sys
import warnings
from pathlib import Path

from ._common import CliError, add_format, dump_json, file_named, output_dir, parse_range

DEFAULT_RPM = "600"
DEFAULT_SPEED_FLUCTUATION = 0.05  # camjax.program.DEFAULT_SPEED_FLUCTUATION (not imported: JAX loads late)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "program",
        help="a cam program (TOML) at machine speed: acceleration, contact force, jump, profile",
        description=(
            "Periodic steady state of a cam program (rises, dwells and returns over 360 "
            "degrees, follower with mass, train stiffness and return spring) at each speed: "
            "peak payload and kinematic acceleration, contact force, minimum preload, "
            "residual vibration in the dwells and constant-velocity strokes, each segment's peaks "
            "and each join's state (VDI 2143), and where contact is lost the flight and "
            "re-impact.  With several speeds, the jump speed (lowest speed in the range at "
            "which the preload loses contact).  The drive torque (peak, RMS, mean), the energy "
            "fluctuation and flywheel, the Hertz contact stress (with follower.contact_width_mm) "
            "and the cam's geometry.  FILE may be a machine file ([[cam]] tables: program files "
            "with phase angles on one shaft): each cam's report and the shaft's torque.  "
            "Without FILE, the built-in 'indexer' example; FILE may also name a built-in "
            "example ('indexer', 'feed')."
        ),
    )
    parser.add_argument("file", nargs="?", metavar="FILE",
                        help="program or machine TOML file, or a built-in example name (default: indexer)")
    parser.add_argument("--rpm", default=DEFAULT_RPM, metavar="RPM|V1,V2,...|START:STOP:COUNT",
                        help=f"cam speed(s) in rpm (default {DEFAULT_RPM})")
    parser.add_argument("--no-flight", action="store_true", help="skip the flight simulation where contact is lost "
                        "(and a grooved cam's impacts)")
    parser.add_argument("--speed-fluctuation", type=float, default=DEFAULT_SPEED_FLUCTUATION, metavar="CS",
                        help="coefficient of speed fluctuation the flywheel is sized for, "
                        f"(max - min speed) / mean (default {DEFAULT_SPEED_FLUCTUATION})")
    parser.add_argument("--points", type=int, default=3600, help="profile points over the turn (default 3600)")
    parser.add_argument("--plot-rpm", type=float, default=None, metavar="RPM",
                        help="the speed whose turn the figures show, one of the --rpm speeds "
                        "(default: the speed given nearest the jump speed, else the highest)")
    add_format(parser)
    parser.add_argument("--out", metavar="DIR", help="write profile.csv, profile.dxf, response.csv, "
                        "summary.json and figures here (response.csv at up to 10 speeds)")
    parser.add_argument("--drive-table", metavar="FORMAT", help="instead of the analysis, write the "
                        "motion as a servo drive loads it to --out (csv, xyva, codesys or twincat; "
                        "docs/drive-tables.md)")
    parser.add_argument("--drive-step", type=float, default=0.1, metavar="DEG",
                        help="master step of the csv drive table in degrees (default 0.1)")
    parser.add_argument("--drive-tolerance", type=float, default=1e-4, metavar="TOL",
                        help="most deviation of the knot tables' quintic interpolation from the motion, "
                        "in mm (degrees for a swinging follower) (default 1e-4)")
    parser.set_defaults(func=run)


_COLUMNS = (
    ("rpm", "rpm", "{:.6g}"),
    ("max_payload_acceleration_m_s2", "max|x''| m/s2", "{:.6g}"),
    ("max_kinematic_acceleration_m_s2", "max|y''| m/s2", "{:.6g}"),
    ("min_contact_force_n", "min Fc N", "{:.6g}"),
    ("max_contact_force_n", "max Fc N", "{:.6g}"),
    ("min_preload_n", "min preload N", "{:.6g}"),
    ("jump", "jump", "{}"),
)
_DRIVE_COLUMNS = (
    ("rpm", "rpm", "{:.6g}"),
    ("max_drive_torque_n_m", "max|T| N m", "{:.6g}"),
    ("rms_drive_torque_n_m", "rms T N m", "{:.6g}"),
    ("mean_drive_torque_n_m", "mean T N m", "{:.6g}"),
    ("energy_fluctuation_j", "dE J", "{:.6g}"),
    ("flywheel_inertia_kg_m2", "flywheel kg m2", "{:.6g}"),
)
_CONTACT_COLUMNS = (
    ("max_contact_stress_mpa", "max p MPa", "{:.6g}"),
    ("max_contact_stress_deg", "at deg", "{:.5g}"),
    ("contact_half_width_mm", "half-width mm", "{:.4g}"),
)


def _cell(value, fmt):
    return "-" if value is None else fmt.format(value)


SHOWN = 12
"""Most entries (numbers in a cell, segment and join lines) the text table lists one by one;
a longer list is summarised (the JSON and CSV outputs hold every entry)."""


def _numbers(values, fmt="{:.4g}") -> str:
    values = list(values)
    if len(values) > SHOWN:
        return f"{len(values)} from {fmt.format(min(values))} to {fmt.format(max(values))}"
    return " ".join(fmt.format(v) for v in values) or "-"


def _rows(speeds: list, columns) -> list[str]:
    lines = ["".join(f"{title:>16}" for _, title, _ in columns)]
    lines += ["".join(f"{_cell(s[key], fmt):>16}" for key, _, fmt in columns) for s in speeds]
    return lines


def _geometry_lines(g: dict) -> list[str]:
    lines = [f"max pressure angle {g['max_pressure_angle_deg']:.4g} deg; "
             + "min radius of curvature of the cam "
             + ("-" if g["min_radius_of_curvature_mm"] is None else f"{g['min_radius_of_curvature_mm']:.5g} mm")
             + " (convex), "
             + ("none concave" if g["min_concave_radius_of_curvature_mm"] is None else
                f"{g['min_concave_radius_of_curvature_mm']:.5g} mm (concave)")]
    if g["face_width_mm"] is not None:
        lines.append(f"face width {g['face_width_mm']:.5g} mm (the contact's travel along the face; "
                     "add twice the contact half-width and a margin)")
    steps = [j for j in g["joins"] if j["radius_before_mm"] != j["radius_after_mm"]]
    if len(steps) > SHOWN:
        lines.append(f"the radius of curvature steps at {len(steps)} joins (each in --format json)")
        return lines
    for j in steps:
        lines.append(f"join at {j['angle_deg']:g} deg: radius of curvature {j['radius_before_mm']:.5g} mm "
                     f"before, {j['radius_after_mm']:.5g} mm after")
    return lines


def _table(report: dict, grooved: bool = False) -> str:
    lines = [f"program {report['program']}"]
    lines.append("".join(f"{title:>16}" for _, title, _ in _COLUMNS) + "  period ratios   residual mm")
    for s in report["speeds"]:
        lines.append("".join(f"{_cell(s[key], fmt):>16}" for key, _, fmt in _COLUMNS)
                     + f"  {_numbers(s['period_ratios'], '{:.3f}'):<15} {_numbers(s['residual_vibration_mm'])}")
    lines.append("Fc: contact force of the periodic steady state with contact held (linear); period "
                 "ratios per moving segment; residual: vibration amplitude at the start of each dwell "
                 "and constant-velocity stroke")
    stressed = any(s["max_contact_stress_mpa"] is not None for s in report["speeds"])
    lines += _rows(report["speeds"], _DRIVE_COLUMNS + (_CONTACT_COLUMNS if stressed else ()))
    probes = _probe_columns(report)
    if probes:
        lines += _rows(report["speeds"], (_DRIVE_COLUMNS[0], *probes))
    if grooved:
        lines.append("the strikes below are the groove's, with its clearance (the Backlash model): "
                     "their forces are not bounded by the contact-held Fc above")
    for s in report["speeds"]:
        for f in s["flights"] or []:
            lines.append(
                f"at {s['rpm']:g} rpm contact is lost at {f['separation_deg']:.3f} deg"
                + (f", re-impact at {f['reimpact_deg']:.3f} deg, {f['impact_velocity_m_s']:.4g} m/s, "
                   f"peak force {f['peak_impact_force_n']:.5g} N" if f["reimpact_deg"] is not None else
                   ", no re-impact within a turn")
            )
    for s in report["speeds"]:
        for i in s.get("impacts") or []:
            lines.append(f"at {s['rpm']:g} rpm the roller strikes the {i['flank']} flank at {i['angle_deg']:.3f} deg, "
                         f"{i['velocity_m_s']:.4g} m/s, peak force {i['peak_force_n']:.5g} N")
    lines += _motion_lines(report)
    speed = report["jump_speed_rpm"]
    if report["jump_below_range"]:
        lowest = min(s["rpm"] for s in report["speeds"])
        lines.append(f"jump speed: below the range (contact is already lost at {lowest:g} rpm, "
                     "the lowest speed given)")
    elif len(report["speeds"]) > 1:
        lines.append("jump speed: " + ("none in the range" if speed is None else f"{speed:.1f} rpm"))
    if report.get("geometry") is not None:
        lines += _geometry_lines(report["geometry"])
    return "\n".join(lines)


def _probe_columns(report: dict) -> tuple:
    """Columns of the registered probes the report carries (``camjax.program.register_probe``)."""
    from ..program import PROBES

    first = report["speeds"][0] if report["speeds"] else {}
    return tuple((name, probe.label, "{:.6g}") for name, probe in PROBES.items() if name in first)


def _machine_table(report: dict) -> str:
    lines = [f"machine {report['machine']}"]
    for cam in report["cams"]:
        lines += ["", f"cam at phase {cam['phase_deg']:g} deg:", _table(cam)]
    lines += ["", "shaft (sum of the cams' torques):"]
    lines += _rows(report["shaft"]["speeds"], _DRIVE_COLUMNS)
    return "\n".join(lines)


def _motion_lines(report: dict) -> list[str]:
    """The motion at any speed: each moving segment's peaks and every join's state."""
    lines = []
    if len(report["segments"]) > SHOWN:
        return _motion_summary(report)
    for g in report["segments"]:
        if g["kind"] != "dwell":
            lines.append(
                f"segment {g['segment']} {g['kind']} ({g['law']}): peak y' {g['peak_velocity_mm_per_deg']:.4g} "
                f"mm/deg, y'' {g['peak_acceleration_mm_per_deg2']:.4g} mm/deg2, y''' "
                f"{g['peak_jerk_mm_per_deg3']:.4g} mm/deg3" + (", overshoots its ends" if g["overshoot"] else "")
                + ("" if g.get("fit_deviation_mm") is None else
                   f", table fit within {g['fit_deviation_mm']:.3g} mm of its points"))
    lines += [f"join {j['before']}|{j['after']} at {j['angle_deg']:g} deg: {j['state']} {j['continuity']}, "
              f"y' {j['velocity_mm_per_deg']:.4g} mm/deg" for j in report["joins"]]
    return lines


def _tally(items) -> str:
    counts = {}
    for item in items:
        counts[item] = counts.get(item, 0) + 1
    return ", ".join(f"{count} {item}" for item, count in counts.items())


def _motion_summary(report: dict) -> list[str]:
    """``_motion_lines`` for a long program: counts and the largest peaks."""
    segments, joins = report["segments"], report["joins"]
    lines = [f"{len(segments)} segments ({_tally(g['kind'] for g in segments)}), each with its "
             "peaks in --format json"]
    moving = [g for g in segments if g["kind"] != "dwell"]
    for key, name, unit in (("peak_velocity_mm_per_deg", "y'", "mm/deg"),
                            ("peak_acceleration_mm_per_deg2", "y''", "mm/deg2"),
                            ("peak_jerk_mm_per_deg3", "y" + "'" * 3, "mm/deg3")):
        if moving:
            top = max(moving, key=lambda g: g[key])
            lines.append(f"largest peak {name} {top[key]:.4g} {unit} (segment {top['segment']})")
    lines.append(f"{len(joins)} joins: {_tally(j['state'] + ' ' + j['continuity'] for j in joins)} "
                 "(each in --format json)")
    return lines


def _csv(report: dict) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    keys = [key for key, _, _ in _COLUMNS + _DRIVE_COLUMNS[1:] + _CONTACT_COLUMNS + _probe_columns(report)]
    segments = len(report["speeds"][0]["period_ratios"])
    dwells = len(report["speeds"][0]["residual_vibration_mm"])
    writer.writerow(keys + [f"period_ratio_{i + 1}" for i in range(segments)]
                    + [f"residual_vibration_mm_{i + 1}" for i in range(dwells)]
                    + ["jump_speed_rpm", "jump_below_range"])
    for s in report["speeds"]:
        writer.writerow(["" if s[k] is None else s[k] for k in keys] + list(s["period_ratios"])
                        + list(s["residual_vibration_mm"])
                        + [report["jump_speed_rpm"] or "", report["jump_below_range"]])
    return buffer.getvalue().rstrip()


def plot_speed(report: dict, chosen: float | None) -> float:
    """The speed whose turn the figures draw: ``chosen``, else the speed given nearest the
    jump speed (the first that jumps when the jump lies below the range), else the highest."""
    speeds = [s["rpm"] for s in report["speeds"]]
    if chosen is not None:
        return chosen
    if report["jump_below_range"]:
        return min(speeds)
    if report["jump_speed_rpm"] is not None:
        return min(speeds, key=lambda r: abs(r - report["jump_speed_rpm"]))
    return max(speeds)


def _write_outputs(out: Path, program, steady, report: dict, rpm, points: int, plot_rpm: float) -> None:
    from ..program import groove_turns, profile, response, save_figures, write_csv, write_dxf

    dump_json(report, out / "summary.json")
    prof = profile(program, points)
    write_csv(prof, out / "profile.csv", outer=program.follower.form_closed)
    write_dxf(prof, out / "profile.dxf", outer=program.follower.form_closed)
    histories = [(float(r), response(program, float(r), steady=steady)) for r in list(rpm)[:10]]
    with (out / "response.csv").open("w", newline="") as handle:
        writer = csv.writer(handle)
        keys = list(histories[0][1])
        writer.writerow(["rpm", *keys])
        for r, h in histories:
            for i in range(h["theta_deg"].size):
                writer.writerow([r] + [f"{h[k][i]:.10g}" for k in keys])
    shown = next((h for r, h in histories if r == plot_rpm), None)
    shown = shown if shown is not None else response(program, plot_rpm, steady=steady)
    groove = None
    if program.follower.form_closed and program.follower.groove_clearance_mm:
        groove = groove_turns(program, [plot_rpm])[0]
    save_figures(out, program, report, (plot_rpm, shown), prof, histories=histories, groove=groove)


def _write_machine(out: Path, machine, report: dict, rpm, points: int) -> None:
    from ..program import SteadyState, shaft_figures

    dump_json(report, out / "summary.json")
    for i, ((program, _), cam) in enumerate(zip(machine.cams, report["cams"]), 1):
        folder = out / f"cam{i}-{program.name}"
        folder.mkdir(exist_ok=True)
        _write_outputs(folder, program, SteadyState(program, float(min(rpm))), cam, rpm, points,
                       plot_speed(cam, None))
    shaft_figures(out, machine, report, rpm)


def program_path(text: str | None, default: str = "indexer") -> Path:
    """The program file ``text`` names: a path, or a built-in example's name ('indexer',
    'feed') where no such file exists; without ``text``, the example ``default``."""
    from ..program import example_path

    if not text:
        return example_path(default)
    path = Path(text)
    if text.isidentifier() and not path.exists() and example_path(text).exists():
        return example_path(text)  # a built-in example by name
    return path


def program_report(program, rpm, *, with_flight: bool = True, steady=None,
                   speed_fluctuation: float = DEFAULT_SPEED_FLUCTUATION) -> dict:
    """The report that ``camjax program --format json`` prints (before ``json_ready``):
    ``camjax.program.analyse`` at the speeds ``rpm``, as plain types."""
    from ..program import analyse

    return analyse(program, rpm, with_flight=with_flight, steady=steady,
                   speed_fluctuation=speed_fluctuation).as_dict()


def run(args) -> int:
    from ..program import (
        MAX_GROOVE_SAMPLES,
        MAX_PROFILE_POINTS,
        MAX_TURNS,
        SETTLED_DEG,
        Program,
        SteadyState,
    )

    if args.drive_table is not None:
        return _drive_table(args)
    rpm = parse_range(args.rpm, "--rpm")
    if not all(r > 0 for r in rpm):
        raise CliError(f"--rpm: speeds must be positive, got {args.rpm!r}")
    if not 8 <= args.points <= MAX_PROFILE_POINTS:
        raise CliError(f"--points: must be from 8 to {MAX_PROFILE_POINTS:,}, got {args.points}")
    if args.plot_rpm is not None and not any(math.isclose(args.plot_rpm, r, rel_tol=1e-9) for r in rpm):
        shown = ", ".join(f"{r:g}" for r in list(rpm)[:SHOWN]) + (", ..." if len(rpm) > SHOWN else "")
        raise CliError(f"--plot-rpm: {args.plot_rpm:g} is not one of the --rpm speeds ({shown}): "
                       "the figures show a speed of the table; name one of them")
    if args.plot_rpm is not None:
        args.plot_rpm = next(r for r in rpm if math.isclose(args.plot_rpm, r, rel_tol=1e-9))
    if not 0 < args.speed_fluctuation < 2:
        raise CliError(f"--speed-fluctuation: must be in (0, 2), got {args.speed_fluctuation:g}")
    path = program_path(args.file)
    if is_machine(path):
        return _run_machine(args, path, rpm)
    with file_named(path), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # the library's speed warnings, shown below
        program = Program.load(path)
        out = output_dir(args.out)
        steady = SteadyState(program, float(min(rpm)))
        report = program_report(program, rpm, with_flight=not args.no_flight, steady=steady,
                                speed_fluctuation=args.speed_fluctuation)
        if out is not None:
            _write_outputs(out, program, steady, report, rpm, args.points, plot_speed(report, args.plot_rpm))
    for line in dict.fromkeys([*_messages(caught), *report["warnings"]]):
        print(f"warning: {line}", file=sys.stderr)
    for s in report["speeds"]:
        change = s["impacts_change_deg"]
        if change is not None and not change <= SETTLED_DEG:
            print(f"warning: at {s['rpm']:g} rpm the groove's strikes had not settled within "
                  f"the longest run allowed ({MAX_TURNS} turns, {MAX_GROOVE_SAMPLES:,} samples; "
                  + (f"they still move by {change:.3g} deg per turn" if math.isfinite(change) else
                     "they still differ in number or flank from turn to turn")
                  + "): the roller chatters without a "
                  "period, and the last turn is reported; a narrower groove "
                  "(groove_clearance_mm) or more damping settles sooner", file=sys.stderr)
    if args.format == "json":
        print(dump_json(report))
    elif args.format == "csv":
        print(_csv(report))
    else:
        print(_table(report, grooved=bool(program.follower.form_closed and program.follower.groove_clearance_mm
                                          and not args.no_flight)))
    return 0


def _drive_table(args) -> int:
    """``--drive-table``: the motion as a servo drive loads it (kinematic: nothing else runs)."""
    from ..program import Program, write_drive_table
    from ..program._drive import FILE_NAMES, check_arguments

    names = {"format": "--drive-table", "step_deg": "--drive-step", "tolerance": "--drive-tolerance"}
    try:
        check_arguments(args.drive_table, args.drive_step, args.drive_tolerance, names)
    except ValueError as error:
        raise CliError(str(error)) from None
    if args.out is None:
        raise CliError("--drive-table needs --out DIR: the directory the table is written to")
    path = program_path(args.file)
    with file_named(path):
        program = Program.load(path)
        out = output_dir(args.out)
        print(write_drive_table(program, out / FILE_NAMES[args.drive_table], args.drive_table,
                                step_deg=args.drive_step, tolerance=args.drive_tolerance))
    return 0


def _messages(caught) -> list[str]:
    """The text of each warning in ``caught`` (``warnings.catch_warnings``), once each."""
    return list(dict.fromkeys(str(w.message) for w in caught))


def is_machine(path: Path) -> bool:
    """A file with ``[[cam]]`` or ``[machine]`` tables (unreadable files: left to ``Program.load``)."""
    from ..checks import read_toml
    from ..program import is_machine_file

    try:
        return is_machine_file(read_toml(path, "program file"))
    except ValueError:
        return False


def _run_machine(args, path: Path, rpm) -> int:
    from ..program import Machine, analyse_machine

    with file_named(path), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        machine = Machine.load(path)
        out = output_dir(args.out)
        report = analyse_machine(machine, rpm, with_flight=not args.no_flight,
                                 speed_fluctuation=args.speed_fluctuation).as_dict()
        if out is not None:
            _write_machine(out, machine, report, rpm, args.points)
    for line in _messages(caught):
        print(f"warning: {line}", file=sys.stderr)
    for cam in report["cams"]:
        for line in cam.get("warnings", []):
            print(f"warning: cam {cam['program']} at phase {cam['phase_deg']:g} deg: {line}", file=sys.stderr)
    if args.format == "json":
        print(dump_json(report))
    elif args.format == "csv":
        buffer = io.StringIO()
        writer = csv.writer(buffer)
        keys = [key for key, _, _ in _DRIVE_COLUMNS]
        writer.writerow(keys)
        for s in report["shaft"]["speeds"]:
            writer.writerow([s[k] for k in keys])
        print(buffer.getvalue().rstrip())
    else:
        print(_machine_table(report))
    return 0
