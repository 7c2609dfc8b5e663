"""``camjax program``: a whole cam at machine speed: steady state, contact force, jump, profile."""

from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

from .._plain import DEFAULT_SPEED_FLUCTUATION, example_names
from ._common import CliError, add_probes_option, file_named, output_dir, outputs_of

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
            "which the preload loses contact).  The drive torque (peak, RMS, mean), the energy "
            "fluctuation and flywheel, the Hertz contact stress (with follower.contact_width_mm) "
            "and the cam's geometry.  FILE may be a machine file ([[cam]] tables: program files "
            "with phase angles on one shaft): each cam's report and the shaft's torque.  "
            "A program file with a [[train]] (the follower as a chain of bodies, docs/valve-trains.md) "
            "adds the train's table: natural frequencies, harmonic check, each body's peak "
            "acceleration, the spring's seat force and surge, the chain's jump speed.  "
            "Without FILE, the built-in 'indexer' example; FILE may also name a built-in "
            f"example ({', '.join(example_names())})."
        ),
    )
    parser.add_argument("file", nargs="?", metavar="FILE",
                        help="program or machine TOML file, or a built-in example name (default: indexer)")
    parser.add_argument("--rpm", default=None, metavar="RPM|V1,V2,...|START:STOP:COUNT",
                        help=f"cam speed(s) in rpm (default {DEFAULT_RPM}; not with --drive-table)")
    parser.add_argument("--no-flight", action="store_true", help="skip the flight simulation where contact is lost "
                        "(and a grooved cam's impacts)")
    parser.add_argument("--speed-fluctuation", type=float, default=DEFAULT_SPEED_FLUCTUATION, metavar="CS",
                        help="coefficient of speed fluctuation the flywheel is sized for, "
                        f"(max - min speed) / mean (default {DEFAULT_SPEED_FLUCTUATION})")
    parser.add_argument("--points", type=int, default=3600, help="profile points over the turn (default 3600)")
    parser.add_argument("--plot-rpm", type=float, default=None, metavar="RPM",
                        help="the speed whose turn the figures show, one of the --rpm speeds "
                        "(default: the speed given nearest the jump speed, else the highest)")
    parser.add_argument("--format", choices=("table", "json", "csv"), default=None,
                        help="output format on standard output (default table; not with --drive-table, "
                        "which writes its own format to --out)")
    parser.add_argument("--out", metavar="DIR", help="write profile.csv, profile.dxf, response.csv, "
                        "summary.json and figures here (response.csv at up to 10 speeds and the figures' "
                        "speed; with a [[train]], every body's displacement, velocity and acceleration, the "
                        "spring's seat force and surge, and the train's figures: train.png, modes.png, "
                        "seat_force.png, train_sweep.png)")
    parser.add_argument("--drive-table", metavar="FORMAT", help="instead of the analysis, write the "
                        "motion as a servo drive loads it to --out (csv, xyva, codesys or twincat; "
                        "docs/drive-tables.md); the analysis's options (--rpm, --format, --plot-rpm, "
                        "--no-flight) are refused with it, since nothing is analysed")
    parser.add_argument("--drive-step", type=float, default=0.1, metavar="DEG",
                        help="master step of the csv drive table in degrees (default 0.1)")
    parser.add_argument("--drive-tolerance", type=float, default=1e-4, metavar="TOL",
                        help="most deviation of the knot tables' quintic interpolation from the motion, "
                        "in mm (degrees for a swinging follower) (default 1e-4)")
    parser.add_argument("--motor", metavar="M.toml|CATALOGUE.csv", help="size the servo motor(s) of this file "
                        "(a [motor] TOML or a CSV catalogue) against the program's [drive] at each --rpm, from the "
                        "dynamic steady state and the rigid load; a catalogue's smallest passing motor is picked "
                        "(docs/servo.md); without it, the program's own [motor] tables, if any")
    parser.add_argument("--compensate", type=float, metavar="RPM", help="write to --out the cam lift that makes "
                        "the payload follow the law exactly at RPM (compensated-lift.csv, a whole-cam table, and "
                        "its drive table), and report its residual vibration at the --rpm speeds (docs/servo.md)")
    add_probes_option(parser)
    parser.set_defaults(func=run)


SHOWN = 12
"""Most entries (numbers in a cell, segment and join lines) the text table lists one by one;
a longer list is summarised (the JSON and CSV outputs hold every entry)."""


def _numbers(values, fmt="{:.4g}") -> str:
    values = list(values)
    if len(values) > SHOWN:
        return f"{len(values)} from {fmt.format(min(values))} to {fmt.format(max(values))}"
    return " ".join(fmt.format(v) for v in values) or "-"


def _header(columns) -> str:
    return f"{'rpm':>16}" + "".join(f"{p.label:>16}" for p in columns)


def _row(speed, columns) -> str:
    return f"{speed.rpm:>16.6g}" + "".join(f"{p.cell(getattr(speed, p.name)):>16}" for p in columns)


def _rows(speeds, columns) -> list[str]:
    """A block of the table: ``rpm`` and ``columns`` (outputs of the report's set, ``Report.columns``)."""
    return [_header(columns)] + [_row(s, columns) for s in speeds]


def _block(report, table: str) -> tuple:
    """The outputs of ``report`` that the block ``table`` of the text table prints (an
    optional one only where some speed has a value)."""
    return tuple(p for p in report.columns() if p.table == table
                 and not (p.optional and all(getattr(s, p.name) is None for s in report.speeds)))


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


def _table(typed, grooved: bool = False) -> str:
    """The text table of a program's ``Report``: a block of rows per ``table`` of its outputs
    (``Report.columns``), then the flights, strikes, motion, jump speed and geometry."""
    report = typed.as_dict()
    lines = [f"program {typed.program}"]
    columns = _block(typed, "speed")
    lines.append(_header(columns) + "  period ratios   residual mm")
    for s in typed.speeds:
        lines.append(_row(s, columns) + f"  {_numbers(s.period_ratios, '{:.3f}'):<15} "
                     f"{_numbers(s.residual_vibration_mm)}")
    simulated = "contacts" in (typed.train or {})  # a chain with lash or a seat
    lines.append(("Fc: contact force at the cam of the simulated periodic steady state with the chain's "
                  "one-sided contacts (it pushes only: min Fc 0 where the cam carries nothing, noise below "
                  "zero clipped; jump: the cam separates)" if simulated else
                  "Fc: contact force of the periodic steady state with contact held (linear)")
                 + "; period ratios per moving segment; residual: vibration amplitude at the start of each "
                 "dwell and constant-velocity stroke")
    for table in dict.fromkeys(p.table for p in typed.columns() if p.table != "speed"):
        columns = _block(typed, table)
        if columns:
            lines += _rows(typed.speeds, columns)
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
    if report.get("train") is not None:
        lines += _train_lines(report["train"])
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


def _train_lines(train: dict) -> list[str]:
    """The train's block of the text table (``Report.train``)."""
    names = train["bodies"]
    lines = [f"train {' -> '.join(names)}: {train['note']}",
             "natural frequencies, cam held: " + _numbers(train["natural_frequencies_held_hz"], "{:.5g}") + " Hz",
             "natural frequencies, cam free: " + _numbers(train["natural_frequencies_free_hz"], "{:.5g}") + " Hz"]
    for check in train["harmonic_check"]:
        orders = check["orders"]
        lines.append(f"harmonic check: {check['frequency_hz']:.5g} Hz met by cam orders "
                     + (f"{orders[0]} to {orders[-1]}" if len(orders) > 1 else str(orders[0]) if orders else "none")
                     + " in the speed range")
    titles = ["min Fc N", "max Fc N", *(f"max|a| {n}"[:15] for n in names), "lift err mm", "min seat N",
              "max seat N", "surge N"]
    lines.append(f"{'rpm':>16}" + "".join(f"{t:>16}" for t in titles))
    for s in train["speeds"]:
        cells = [s["min_contact_force_n"], s["max_contact_force_n"], *s["max_acceleration_m_s2"].values(),
                 s["max_lift_error_mm"], s["min_seat_force_n"], s["max_seat_force_n"], s["max_surge_n"]]
        lines.append(f"{s['rpm']:>16.6g}" + "".join(f"{'-':>16}" if v is None else f"{v:>16.6g}" for v in cells))
    lines.append("max|a|: each body's peak acceleration (m/s2); lift err: the last body's largest distance "
                 "from its kinematic lift; seat: the spring's force at its seat; surge: that force's largest "
                 "distance from the static spring force")
    contacts = train.get("contacts")
    if contacts is not None:
        lines += _contact_lines(train, contacts)
    if train.get("arm") is not None:
        lines += _arm_lines(train["arm"])
    return lines


def _contact_lines(train: dict, contacts: dict) -> list[str]:
    """The contacts' lines of a train with lash or a seat (``Report.train["contacts"]``)."""
    lines = [f"contacts: {contacts['note']}"]
    for s, c in zip(train["speeds"], contacts["speeds"]):
        seating = c["seating_velocity_m_s"]
        parts = [f"at {s['rpm']:g} rpm"]
        if seating is not None:
            parts.append(f"seating {seating:.4g} m/s")
            bounces = c["bounces"]
            parts.append(f"{c['bounce_count']} bounce(s)" + (
                " (" + ", ".join(f"{b['velocity_m_s']:.3g} m/s at {b['angle_deg']:.2f} deg" for b in bounces[:3])
                + (", ..." if len(bounces) > 3 else "") + ")" if bounces else ""))
        for name, o in c["lash_openings"].items():  # the first body's lash is the clearance at the cam
            where = f"cam clearance ({name})" if name == train["bodies"][0] else f"lash at {name}"
            parts.append(f"{where} opens {o['count']}x" + (
                " at " + ", ".join(f"{a:.2f}" for a in o["angles_deg"][:4]) + " deg" if o["angles_deg"] else ""))
        apart = [name for name, yes in c["separates"].items() if yes]
        parts.append("separates: " + (", ".join(apart) if apart else "none"))
        lines.append("; ".join(parts))
    lowest, below = contacts["lowest_separation_rpm"], contacts.get("separation_below_range", {})
    lines.append("lowest speed of separation: " + ", ".join(
        f"{name} {'none' if r is None else f'{r:.1f} rpm' + (' or below' if below.get(name) else '')}"
        for name, r in lowest.items()))
    return lines


def _arm_lines(arm: dict) -> list[str]:
    """The flexible arm's block: its first bending mode and the harmonics of its bending."""
    lines = [f"arm: first bending mode, cam held, {arm['fundamental_hz']:.5g} Hz = "
             f"{arm['fundamental_rad_s']:.5g} rad/s",
             f"arm bending at {arm['body']} (its displacement less the rigid swing's), amplitude of each "
             "cam order in mm:"]
    titles = ["fund. orders", "max mm", *(f"order {k}" for k in arm["orders"])]
    lines.append(f"{'rpm':>16}" + "".join(f"{t:>14}" for t in titles))
    for s in arm["speeds"]:
        cells = [s["fundamental_orders"], s["max_bending_mm"], *s["bending_harmonics_mm"]]
        lines.append(f"{s['rpm']:>16.6g}" + "".join(f"{v:>14.4g}" for v in cells))
    return lines


def _machine_table(report) -> str:
    """The text table of a ``MachineReport``: each cam's, then the shaft's totals."""
    lines = [f"machine {report.machine}"]
    for phase, cam in zip(report.phases_deg, report.cams):
        lines += ["", f"cam at phase {phase:g} deg:", _table(cam)]
    lines += ["", "shaft (sum of the cams' torques):"]
    lines += _rows(report.shaft, report.columns())
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


def program_path(text: str | None, default: str = "indexer") -> Path:
    """``camjax.program.program_path`` (imported when called: JAX loads late)."""
    from ..program import program_path as path_of

    return path_of(text, default)


def run(args) -> int:
    from ..program import (
        MAX_PROFILE_POINTS,
        Program,
        Speeds,
        analyse,
        steady_state,
        write_report,
    )

    if args.drive_table is not None:
        return _drive_table(args)
    args.format = args.format or "table"
    args.rpm = args.rpm or DEFAULT_RPM
    try:
        rpm = Speeds.parse(args.rpm, "--rpm")
    except ValueError as error:
        raise CliError(str(error)) from None
    if args.compensate is not None and args.out is None:
        raise CliError("--compensate needs --out DIR: the directory the compensated table is written to")
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
    outputs = outputs_of(args.probes)
    path = program_path(args.file)
    if is_machine(path):
        if args.motor is not None or args.compensate is not None:
            raise CliError("--motor and --compensate take a program file, not a machine file")
        return _run_machine(args, path, rpm, outputs)
    with file_named(path), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # the library's speed warnings, shown below
        program = Program.load(path)
        simulated = program.chain is not None and program.chain.has_contacts  # lash or a seat
        if simulated and args.compensate is not None:
            raise CliError(COMPENSATE_CONTACTS)
        motors = _motors(args, program)  # before the analysis: a bad motor file fails at once
        out = output_dir(args.out)
        # a chain with contacts: its simulation, which keeps the turns for --out's files
        steady = steady_state(program, rpm)
        report = analyse(program, rpm, with_flight=not args.no_flight, steady=steady,
                         speed_fluctuation=args.speed_fluctuation, outputs=outputs)
        if out is not None:
            write_report(out, program, report, steady=steady, points=args.points, plot_rpm=args.plot_rpm)
        servo = _servo(args, program, motors, rpm, steady, report, out)
    for line in dict.fromkeys([*_messages(caught), *report.warnings]):
        print(f"warning: {line}", file=sys.stderr)
    if args.format == "json":
        if servo:
            import json

            from .._plain import json_ready

            print(json.dumps(json_ready({**report.as_dict(), **servo}), indent=1))
        else:
            print(report.to_json())
    elif args.format == "csv":
        if report.train is not None:
            print(CSV_TRAIN_NOTE, file=sys.stderr)
        print(report.to_csv())
    else:
        print(_table(report, grooved=bool(program.follower.form_closed and program.follower.groove_clearance_mm
                                          and not args.no_flight)))
        for line in _servo_lines(servo):
            print(line)
    return 0


CSV_TRAIN_NOTE = ("note: --format csv has the speeds' rows only; the chain's train section (its natural "
                  "frequencies, each body's figures, the contacts) is in --format json and --out's summary.json")


def _motors(args, program) -> tuple:
    """The motors to size: ``--motor``'s file, else the program's [motor]; checked against
    the program's [drive]."""
    from ..program import read_motors

    motors = read_motors(Path(args.motor)) if args.motor is not None else program.motors
    if motors and program.drive is None:
        raise ValueError("motor sizing needs the program's [drive] (travel_mm_per_rev or degrees_per_rev, "
                         "gear_ratio, efficiencies, inertias: docs/servo.md)")
    if args.compensate is not None:
        from ..program import check_smooth

        check_smooth(program)  # before the analysis: a law too rough fails at once
    return motors


COMPENSATE_CONTACTS = (
    "--compensate: a chain with lash or a seat has no compensated lift: while its lash is open or its "
    "valve sits on its seat the valve does not move with the cam, so no cam lift makes it follow the "
    "law there (the inverse the compensation solves exists only for a linear chain)"
)


def _servo(args, program, motors, rpm, steady, report, out) -> dict:
    """The motor sizing (``--motor`` or the program's [motor]) and the compensation
    (``--compensate``), as the JSON keys ``motor`` and ``compensation``."""
    from ..program import program_motor_choice

    result = {}
    if motors:
        choice = program_motor_choice(program, rpm, steady=steady, motors=motors)
        result["motor"] = choice.as_dict()
        result["motor_summary"] = choice.summary()
        if out is not None:
            from ..program import motor_figure

            motor_figure(choice.sizings[list(motors).index(choice.shown)], out / "motor.png")
    if args.compensate is not None:
        from ..program import compensate, deviation_from_law, write_drive_table

        compensation = compensate(program, args.compensate)
        (out / "compensated-lift.csv").write_text(compensation.csv())
        write_drive_table(compensation.program, out / "compensated-drive.csv", "csv")
        speeds = []
        for r in rpm:
            turn, dwell = deviation_from_law(program, compensation.program, r)
            law_turn, law_dwell = deviation_from_law(program, program, r)
            speeds.append({"rpm": r, "max_deviation_mm": turn, "dwell_vibration_mm": dwell,
                           "law_max_deviation_mm": law_turn, "law_dwell_vibration_mm": law_dwell})
        result["compensation"] = {**compensation.as_dict(), "table": str(out / "compensated-lift.csv"),
                                  "drive_table": str(out / "compensated-drive.csv"), "speeds": speeds}
    return result


def _servo_lines(servo: dict) -> list[str]:
    lines = []
    if "motor" in servo:
        for per_speed in servo["motor"]["motors"]:
            for s in per_speed:
                d, g = s["dynamic"], s["rigid"]
                lines.append(f"motor {s['motor']} at {s['rpm']:g} rpm: peak {d['peak_torque_n_m']:.4g} N m "
                             f"(rigid {g['peak_torque_n_m']:.4g}), RMS {d['rms_torque_n_m']:.4g} N m (rigid "
                             f"{g['rms_torque_n_m']:.4g}), max speed {d['max_speed_rpm']:.5g} rpm, inertia ratio "
                             f"{s['inertia_ratio']:.3g}, regenerated {d['regenerated_energy_j']:.4g} J per turn, "
                             f"thermal use {100 * d['thermal_use']:.1f}%: " + ("passes" if s["passed"] else "fails"))
                lines += ["    " + _check_text(c) for c in d["checks"] if not c["passed"]]
        lines.append(servo["motor_summary"])
    if "compensation" in servo:
        c = servo["compensation"]
        lines.append(f"compensated at {c['rpm']:g} rpm: correction up to {c['max_correction_mm']:.4g} mm "
                     f"({100 * c['correction_share']:.3g}% of the stroke), written to {c['table']}")
        for s in c["speeds"]:
            lines.append(f"  at {s['rpm']:g} rpm the payload strays from the law by {s['max_deviation_mm']:.3g} mm "
                         f"at most and vibrates {s['dwell_vibration_mm']:.3g} mm in the dwells; the uncompensated "
                         f"cam {s['law_max_deviation_mm']:.3g} mm and {s['law_dwell_vibration_mm']:.3g} mm")
    return lines


def _check_text(c: dict) -> str:
    return (f"{c['name']} fails: {c['value']:.4g} against {c['limit']:.4g} "
            f"(by {-100 * c['margin']:.1f}%)")


def _drive_table(args) -> int:
    """``--drive-table``: the motion as a servo drive loads it (kinematic: nothing else runs)."""
    from ..program import (
        DRIVE_TABLE_FILE_NAMES,
        Program,
        check_drive_table_arguments,
        write_drive_table,
    )

    ignored = [option for option, given in (("--rpm", args.rpm is not None), ("--format", args.format is not None),
                                            ("--plot-rpm", args.plot_rpm is not None), ("--no-flight", args.no_flight),
                                            ("--probes", args.probes is not None))
               if given]
    if ignored:
        raise CliError(f"{ignored[0]}: not with --drive-table, which analyses nothing and writes the table to "
                       "--out in its own format; run the analysis apart")
    names = {"format": "--drive-table", "step_deg": "--drive-step", "tolerance": "--drive-tolerance"}
    try:
        check_drive_table_arguments(args.drive_table, args.drive_step, args.drive_tolerance, names)
    except ValueError as error:
        raise CliError(str(error)) from None
    if args.out is None:
        raise CliError("--drive-table needs --out DIR: the directory the table is written to")
    path = program_path(args.file)
    with file_named(path), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # a step too coarse for the motion, shown below
        program = Program.load(path)
        out = output_dir(args.out)
        written = write_drive_table(program, out / DRIVE_TABLE_FILE_NAMES[args.drive_table], args.drive_table,
                                    step_deg=args.drive_step, tolerance=args.drive_tolerance)
    for line in _messages(caught):
        print(f"warning: {line.replace('a step of', '--drive-step', 1)}", file=sys.stderr)
    print(written)
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


def _run_machine(args, path: Path, rpm, outputs) -> int:
    from ..program import Machine, analyse_machine, write_machine_report

    with file_named(path), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        machine = Machine.load(path)
        out = output_dir(args.out)
        report = analyse_machine(machine, rpm, with_flight=not args.no_flight,
                                 speed_fluctuation=args.speed_fluctuation, outputs=outputs)
        if out is not None:
            write_machine_report(out, machine, report, points=args.points)
    for line in _messages(caught):
        print(f"warning: {line}", file=sys.stderr)
    for phase, cam in zip(report.phases_deg, report.cams):
        for line in cam.warnings:
            print(f"warning: cam {cam.program} at phase {phase:g} deg: {line}", file=sys.stderr)
    if args.format == "json":
        print(report.to_json())
    elif args.format == "csv":
        print(report.to_csv())
    else:
        print(_machine_table(report))
    return 0
