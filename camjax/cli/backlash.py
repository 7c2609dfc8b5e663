"""``camjax backlash``: kinematic backlash impact velocity against bk and dn."""

from __future__ import annotations

from ._common import (
    CliError,
    add_format,
    add_law_option,
    dump_json,
    laws_of,
    output_dir,
    parse_float_list,
)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "backlash",
        help="kinematic backlash impact velocity v(bk, dn) of motion laws",
        description=(
            "The payload leaves the driving flank when the law's deceleration exceeds the "
            "natural deceleration dn = Dn T^2/h, flies across the clearance bk = "
            "backlash/stroke and strikes the other flank with normalised velocity v = V T/h. "
            "In the table '-' is no separation and 'fall' a payload that falls back onto "
            "the driving flank without crossing (null velocity and a status in JSON)."
        ),
    )
    add_law_option(parser)
    parser.add_argument("--bk", required=True, metavar="V1,V2,...",
                        help="backlash over stroke, bk = backlash/h (dimensionless, > 0)")
    parser.add_argument("--dn", required=True, metavar="V1,V2,...",
                        help="natural deceleration dn = Dn T^2/h (dimensionless, >= 0)")
    add_format(parser, choices=("table", "json"))
    parser.add_argument("--out", metavar="DIR", help="also write backlash.json into DIR")
    parser.set_defaults(func=run)


def backlash_report(selected: dict, bk: list[float], dn: list[float]) -> dict:
    """The JSON document: per law of ``selected`` (laws by name), ``[dn][bk]`` tables (NaN
    where the event is absent)."""
    if any(b <= 0 for b in bk):
        raise CliError(f"--bk: backlash must be positive, got {bk}")
    if any(d < 0 for d in dn):
        raise CliError(f"--dn: natural deceleration must be non-negative, got {dn}")
    import numpy as np

    from ..models import STATUS_NAMES, kinematic_impact_table

    report = {}
    for name, law in selected.items():
        table = kinematic_impact_table(law, bk, dn)
        status = np.asarray(table.status)
        report[name] = {
            "bk": bk,
            "dn": dn,
            "impact_velocity": np.asarray(table.impact_velocity),
            "departure_tau": np.asarray(table.departure_tau),
            "impact_tau": np.asarray(table.impact_tau),
            "status": [[STATUS_NAMES[int(c)] for c in row] for row in status],
        }
    return {"laws": report}


_SHORT = {"no separation": "-", "no impact": "fall"}


def _format_table(report: dict) -> str:
    import numpy as np

    lines = []
    for name, entry in report["laws"].items():
        lines.append(f"{name}: impact velocity v (rows dn, columns bk)")
        lines.append("dn \\ bk  " + "".join(f"{b:>10.4g}" for b in entry["bk"]))
        for d, row, states in zip(
            entry["dn"], entry["impact_velocity"], entry["status"], strict=True
        ):
            cells = (
                f"{v:>10.4f}" if np.isfinite(v) else f"{_SHORT[state]:>10}"
                for v, state in zip(row, states, strict=True)
            )
            lines.append(f"{d:<9.4g}" + "".join(cells))
        lines.append("")
    return "\n".join(lines).rstrip()


def run(args) -> int:
    bk = parse_float_list(args.bk, "--bk")
    dn = parse_float_list(args.dn, "--dn")
    selected = laws_of(args, tool="camjax backlash")
    out = output_dir(args.out)
    report = backlash_report(selected, bk, dn)
    text = dump_json(report, out / "backlash.json" if out else None)
    print(text if args.format == "json" else _format_table(report))
    return 0
