"""``camjax laws``: every standard law with its peak coefficients."""

from __future__ import annotations

from ._common import add_format, dump_json


def register(sub) -> None:
    parser = sub.add_parser("laws", help="list the standard motion laws with Cv, Ca, Cj")
    add_format(parser, ("table", "json"))
    parser.set_defaults(func=run)


def run(args) -> int:
    from .. import laws

    table = {law.name: law.peak_coefficients() for law in laws.standard_laws()}
    if args.format == "json":
        print(dump_json(table))
        return 0
    print(f"{'law':<20} {'Cv':>8} {'Ca':>8} {'Cj':>8}")
    for name, c in table.items():
        print(f"{name:<20} {c['Cv']:8.4f} {c['Ca']:8.4f} {c['Cj']:8.4f}")
    print("Cj = inf: the acceleration steps, so the jerk is an impulse.")
    return 0
