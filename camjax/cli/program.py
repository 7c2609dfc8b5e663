"""``camjax program``: a whole cam at machine speed: steady state, contact force, jump, profile."""

from __future__ import annotations

import csv
import io
from pathlib import Path

from ._common import CliError, add_format, dump_json, output_dir, parse_range

DEFAULT_RPM = "600"


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
            "which the preload loses contact).  Without FILE, the built-in 'indexer' example; "
            "FILE may also name a built-in example ('indexer', 'feed')."
        ),
    )
    parser.add_argument("file", nargs="?", metavar="FILE", help="program TOML file or built-in example name (default: indexer)")
    parser.add_argument("--rpm", default=DEFAULT_RPM, metavar="RPM|V1,V2,...|START:STOP:COUNT",
                        help=f"cam speed(s) in rpm (default {DEFAULT_RPM})")
    parser.add_argument("--no-flight", action="store_true", help="skip the flight simulation where contact is lost "
                        "(and a grooved cam's impacts)")
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


def _cell(value, fmt):
    return "-" if value is None else fmt.format(value)


def _table(report: dict) -> str:
    lines = [f"program {report['program']}"]
    lines.append("".join(f"{title:>16}" for _, title, _ in _COLUMNS))
    for s in report["speeds"]:
        lines.append("".join(f"{_cell(s[key], fmt):>16}" for key, _, fmt in _COLUMNS))
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
    if len(report["speeds"]) > 1:
        lines.append("jump speed: " + ("none in the range" if speed is None else f"{speed:.1f} rpm"))
    return "\n".join(lines)


def _motion_lines(report: dict) -> list[str]:
    """The motion at any speed: each moving segment's peaks and every join's state."""
    lines = []
    for g in report["segments"]:
        if g["kind"] != "dwell":
            lines.append(
                f"segment {g['segment']} {g['kind']} ({g['law']}): peak y' {g['peak_velocity_mm_per_deg']:.4g} "
                f"mm/deg, y'' {g['peak_acceleration_mm_per_deg2']:.4g} mm/deg2, y''' "
                f"{g['peak_jerk_mm_per_deg3']:.4g} mm/deg3" + (", overshoots its ends" if g["overshoot"] else ""))
    lines += [f"join {j['before']}|{j['after']} at {j['angle_deg']:g} deg: {j['state']} {j['continuity']}, "
              f"y' {j['velocity_mm_per_deg']:.4g} mm/deg" for j in report["joins"]]
    return lines


def _csv(report: dict) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    keys = [key for key, _, _ in _COLUMNS]
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
    save_figures(out, program, report, histories[0], prof)


def run(args) -> int:
    from ..program import Program, SteadyState, analyse, example_path

    rpm = parse_range(args.rpm, "--rpm")
    if not all(r > 0 for r in rpm):
        raise CliError(f"--rpm: speeds must be positive, got {args.rpm!r}")
    if args.points < 8:
        raise CliError(f"--points: must be at least 8, got {args.points}")
    path = Path(args.file) if args.file else example_path()
    if args.file and args.file.isidentifier() and not path.exists() and example_path(args.file).exists():
        path = example_path(args.file)  # a built-in example by name
    program = Program.load(path)
    out = output_dir(args.out)
    steady = SteadyState(program, float(min(rpm)))
    report = analyse(program, rpm, with_flight=not args.no_flight, steady=steady).as_dict()
    if out is not None:
        _write_outputs(out, program, steady, report, rpm, args.points)
    if args.format == "json":
        print(dump_json(report))
    elif args.format == "csv":
        print(_csv(report))
    else:
        print(_table(report))
    return 0
