"""``camjax program``: a whole cam at machine speed: steady state, contact force, jump, profile."""

from __future__ import annotations

import csv
import io
from pathlib import Path

from ._common import CliError, add_format, dump_json, output_dir, parse_range

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
            "residual vibration in the dwells, and where contact is lost the flight and "
            "re-impact.  With several speeds, the jump speed (lowest speed in the range at "
            "which the preload loses contact).  The drive torque (peak, RMS, mean), the energy "
            "fluctuation and flywheel, the Hertz contact stress (with follower.contact_width_mm) "
            "and the cam's geometry.  FILE may be a machine file ([[cam]] tables: program files "
            "with phase angles on one shaft): each cam's report and the shaft's torque.  "
            "Without FILE, the built-in 'indexer' example."
        ),
    )
    parser.add_argument("file", nargs="?", metavar="FILE",
                        help="program or machine TOML file (default: built-in indexer)")
    parser.add_argument("--rpm", default=DEFAULT_RPM, metavar="RPM|V1,V2,...|START:STOP:COUNT",
                        help=f"cam speed(s) in rpm (default {DEFAULT_RPM})")
    parser.add_argument("--no-flight", action="store_true", help="skip the flight simulation where contact is lost "
                        "(and a grooved cam's impacts)")
    parser.add_argument("--speed-fluctuation", type=float, default=DEFAULT_SPEED_FLUCTUATION, metavar="CS",
                        help="coefficient of speed fluctuation the flywheel is sized for, "
                        f"(max - min speed) / mean (default {DEFAULT_SPEED_FLUCTUATION})")
    parser.add_argument("--points", type=int, default=3600, help="profile points over the turn (default 3600)")
    add_format(parser)
    parser.add_argument("--out", metavar="DIR", help="write profile.csv, profile.dxf, response.csv, "
                        "summary.json and figures here (response.csv at up to 10 speeds)")
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
    for j in g["joins"]:
        if j["radius_before_mm"] != j["radius_after_mm"]:
            lines.append(f"join at {j['angle_deg']:g} deg: radius of curvature {j['radius_before_mm']:.5g} mm "
                         f"before, {j['radius_after_mm']:.5g} mm after")
    return lines


def _table(report: dict) -> str:
    lines = [f"program {report['program']}"]
    lines += _rows(report["speeds"], _COLUMNS)
    stressed = any(s["max_contact_stress_mpa"] is not None for s in report["speeds"])
    lines += _rows(report["speeds"], _DRIVE_COLUMNS + (_CONTACT_COLUMNS if stressed else ()))
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
    speed = report["jump_speed_rpm"]
    if len(report["speeds"]) > 1:
        lines.append("jump speed: " + ("none in the range" if speed is None else f"{speed:.1f} rpm"))
    if report.get("geometry") is not None:
        lines += _geometry_lines(report["geometry"])
    return "\n".join(lines)


def _machine_table(report: dict) -> str:
    lines = [f"machine {report['machine']}"]
    for cam in report["cams"]:
        lines += ["", f"cam at phase {cam['phase_deg']:g} deg:", _table(cam)]
    lines += ["", "shaft (sum of the cams' torques):"]
    lines += _rows(report["shaft"]["speeds"], _DRIVE_COLUMNS)
    return "\n".join(lines)


def _csv(report: dict) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    keys = [key for key, _, _ in _COLUMNS + _DRIVE_COLUMNS[1:] + _CONTACT_COLUMNS]
    writer.writerow(keys + ["jump_speed_rpm"])
    for s in report["speeds"]:
        writer.writerow(["" if s[k] is None else s[k] for k in keys] + [report["jump_speed_rpm"] or ""])
    return buffer.getvalue().rstrip()


def _write_outputs(out: Path, program, steady, report: dict, rpm, points: int) -> None:
    from ..program import profile, response, write_csv, write_dxf
    from ..program.figures import save_figures

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
    save_figures(out, program, report, histories, prof)


def _write_machine(out: Path, machine, report: dict, rpm, points: int) -> None:
    from ..program import SteadyState
    from ..program.figures import shaft_figures

    dump_json(report, out / "summary.json")
    for i, ((program, _), cam) in enumerate(zip(machine.cams, report["cams"]), 1):
        folder = out / f"cam{i}-{program.name}"
        folder.mkdir(exist_ok=True)
        _write_outputs(folder, program, SteadyState(program, float(min(rpm))), cam, rpm, points)
    shaft_figures(out, machine, report, rpm)


def run(args) -> int:
    from ..program import Program, SteadyState, analyse, example_path

    rpm = parse_range(args.rpm, "--rpm")
    if not all(r > 0 for r in rpm):
        raise CliError(f"--rpm: speeds must be positive, got {args.rpm!r}")
    if args.points < 8:
        raise CliError(f"--points: must be at least 8, got {args.points}")
    if not 0 < args.speed_fluctuation < 2:
        raise CliError(f"--speed-fluctuation: must be in (0, 2), got {args.speed_fluctuation:g}")
    path = Path(args.file) if args.file else example_path()
    if _is_machine(path):
        return _run_machine(args, path, rpm)
    program = Program.load(path)
    out = output_dir(args.out)
    steady = SteadyState(program, float(min(rpm)))
    report = analyse(program, rpm, with_flight=not args.no_flight, steady=steady,
                     speed_fluctuation=args.speed_fluctuation).as_dict()
    if out is not None:
        _write_outputs(out, program, steady, report, rpm, args.points)
    if args.format == "json":
        print(dump_json(report))
    elif args.format == "csv":
        print(_csv(report))
    else:
        print(_table(report))
    return 0


def _is_machine(path: Path) -> bool:
    """A file with ``[[cam]]`` or ``[machine]`` tables (unreadable files: left to ``Program.load``)."""
    import tomllib

    from ..program import is_machine_file

    try:
        return is_machine_file(tomllib.loads(path.read_text()))
    except (OSError, tomllib.TOMLDecodeError):
        return False


def _run_machine(args, path: Path, rpm) -> int:
    from ..program import Machine, analyse_machine

    machine = Machine.load(path)
    out = output_dir(args.out)
    report = analyse_machine(machine, rpm, with_flight=not args.no_flight,
                             speed_fluctuation=args.speed_fluctuation).as_dict()
    if out is not None:
        _write_machine(out, machine, report, rpm, args.points)
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
