"""``camjax laws``: every rest-to-rest law with a fixed name, with its peak coefficients."""

from __future__ import annotations

from ._common import add_format, dump_json


def register(sub) -> None:
    parser = sub.add_parser(
        "laws", help="list the named motion laws with Cv, Ca, Cj",
        description="The rest-to-rest laws with fixed names (the classic seven, then the named "
        "laws of the trade) with their peak coefficients.  --law also takes the families "
        "scca:A,B,C, poly:K, triple-harmonic:A1,A2, NAME-cv:P, NAME-asym:L and, in program "
        "files, the laws that start or end in motion (constant-velocity, double-harmonic, "
        "polynomial5/7); docs/laws.md describes them all.")
    add_format(parser, ("table", "json"))
    parser.set_defaults(func=run)


def run(args) -> int:
    from .. import laws

    table = {law.name: law.peak_coefficients() for law in laws.named_laws()}
    if args.format == "json":
        print(dump_json(table))
        return 0
    width = max(map(len, table)) + 1
    print(f"{'law':<{width}} {'Cv':>8} {'Ca':>8} {'Cj':>8}")
    for name, c in table.items():
        print(f"{name:<{width}} {c['Cv']:8.4f} {c['Ca']:8.4f} {c['Cj']:8.4f}")
    print("Cj = inf: the acceleration steps, so the jerk is an impulse.")
    print("Families: " + ", ".join(laws.FAMILIES) + " (NAME: a law above).")
    return 0
