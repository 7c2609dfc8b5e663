"""``camjax bench``: a small work-precision study (time against error of each method).

The study itself is :mod:`camjax.studies`; this module parses and prints.
"""

from __future__ import annotations

import sys

from ._common import (
    RANGE_METAVAR,
    CliError,
    add_format,
    add_law_option,
    dump_json,
    laws_of,
    options_named,
    parse_range,
)

DEFAULT_LAWS = ("poly4567", "modified-trapezoid")


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "bench",
        help="time against error of the solution methods (a small work-precision study)",
        description=(
            "Time each method over a batch of period ratios and measure its max Ct and R "
            "error against the exact path at high resolution. Timings are of this machine "
            "and this run; the full study is experiments/benchmarks/work_precision.py."
        ),
    )
    add_law_option(parser, default=DEFAULT_LAWS)
    parser.add_argument("--n", default="1:30:200", metavar=RANGE_METAVAR,
                        help="period ratios (dimensionless, rise time / natural period)")
    parser.add_argument("--level", choices=("quick", "medium", "full"), default="quick",
                        help="how many methods and settings (quick: six; full: slow to compile)")
    parser.add_argument("--repeats", type=int, default=2,
                        help="warm runs timed; the best counts")
    add_format(parser, ("table", "json"))
    parser.set_defaults(func=run)


def run(args) -> int:
    from ..studies import (
        ACCURACY_GOAL,
        default_method,
        format_table,
        reference_resolution,
        run_study,
        study_cases,
    )

    selected = laws_of(args, DEFAULT_LAWS, tool="camjax bench")
    n = parse_range(args.n, "--n")
    if (n < 1e-3).any() or n.size < 1:
        raise CliError("--n: period ratios must be positive")
    with options_named("--n"):
        reference_resolution(float(n.max()))  # refused here, before any work
    if args.repeats < 1:
        raise CliError(f"--repeats: must be at least 1, got {args.repeats}")
    cases = study_cases(args.level, float(n.max()))
    left_out = [case.label for case in study_cases(args.level) if case not in cases]
    if left_out:
        print(f"left out for period ratios up to {n.max():g} (a grid too coarse, w h > 1 per "
              f"interval): {', '.join(left_out)}", file=sys.stderr)
    rows = run_study(list(selected.values()), n, cases, repeats=args.repeats)
    best = default_method(rows)
    if args.format == "json":
        print(dump_json({"rows": rows, "default_method": best, "accuracy_goal": ACCURACY_GOAL}))
        return 0
    print(format_table(rows))
    if best is None:
        print(f"\nno method met {ACCURACY_GOAL:g} on every law")
    else:
        print(f"\nfastest method meeting {ACCURACY_GOAL:g} on every law: {best['method']} "
              f"({best['warm_s']:.3g} s in all)")
    return 0
