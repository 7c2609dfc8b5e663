"""``camjax laws``: every rest-to-rest law with a fixed name, with its peak coefficients."""

from __future__ import annotations

from ._common import add_format, dump_json


def register(sub) -> None:
    parser = sub.add_parser(
        "laws", help="list the named motion laws with Cv, Ca, Cj and the servo coefficients",
        description="The rest-to-rest laws with fixed names (the classic seven, then the named "
        "laws of the trade) with their peak coefficients Cv, Ca, Cj and the servo's coefficients: the RMS "
        "velocity and acceleration Cv_rms, Ca_rms and the peak power coefficient Cva = max |v a|.  --law also takes the families "
        "scca:A,B,C, poly:K, triple-harmonic:A1,A2, NAME-cv:P, NAME-asym:L and, in program "
        "files, the laws that start or end in motion (constant-velocity, double-harmonic, "
        "polynomial5/7); docs/laws.md describes them all.")
    add_format(parser, ("table", "json"))
    parser.set_defaults(func=run)


def run(args) -> int:
    from .. import laws

    table = {law.name: law.peak_coefficients() | law.rms_coefficients() for law in laws.named_laws()}
    if args.format == "json":
        print(dump_json(table))
        return 0
    width = max(map(len, table)) + 1
    keys = ("Cv", "Ca", "Cj", "Cv_rms", "Ca_rms", "Cva")
    print(f"{'law':<{width}}" + "".join(f" {k:>8}" for k in keys))
    for name, c in table.items():
        print(f"{name:<{width}}" + "".join(f" {c[k]:8.4f}" for k in keys))
    print("Cj = inf: the acceleration steps, so the jerk is an impulse.  Cv_rms, Ca_rms: RMS of v "
          "and a over the rise; Cva: the largest |v a| (peak power).")
    print(f"No rest-to-rest law has Ca_rms below 2 sqrt(3) = {laws.RMS_ACCELERATION_FLOOR:.4f} "
          "(the cubic 3 tau^2 - 2 tau^3).")
    print("Families: " + ", ".join(laws.FAMILIES) + " (NAME: a law above).")
    return 0
