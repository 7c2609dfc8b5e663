"""``camjax ct``: Ct, residual and Ca*Ct curves of motion laws over period ratios."""

from __future__ import annotations

import csv
import io
import sys
from collections import Counter

import numpy as np

from ..registry import MODELS
from ._common import (
    RANGE_METAVAR,
    CliError,
    add_format,
    add_law_option,
    check_damping,
    dump_json,
    laws_of,
    options_named,
    output_dir,
    parse_range,
    sweep_options_for,
)
from ._drawing import Figure, drawing_for

DEFAULT_N = "1:30:1000"
SECONDS_PER_RATIO = 1.5e-5  # a warm exact-path curve on two cores (2026-11-25): 9-15 ms per 1000
SWEPT_MODELS = [m.usage for m in MODELS if m.swept]


def register(sub) -> None:
    parser = sub.add_parser(
        "ct",
        help="torsion factor, residual vibration and Ca*Ct curves over period ratios",
        description="Sweep period ratios for one or more motion laws (default: every "
        "standard law, n from 1 to 30) and report Ct, residual vibration R and Ca*Ct, with "
        "the fitted torsion-factor envelope Ct = p/n^q + r of each law.  A period ratio "
        "where the solver fails does not end the sweep: its metrics are NaN (null in JSON), "
        "its result code is in the output's result column, and one line on stderr names "
        "the failed ratios.",
    )
    add_law_option(parser)
    parser.add_argument("--n", default=DEFAULT_N, metavar=RANGE_METAVAR,
                        help="period ratios n = rise time / natural period (dimensionless); "
                        "a range runs upward")
    parser.add_argument("--damping", type=float, default=0.0,
                        help="damping ratio zeta in [0, 1) (dimensionless)")
    parser.add_argument("--dwell", type=float, default=1.0,
                        help="dwell after the rise over which Ct looks, in rise durations")
    parser.add_argument("--model", default="spring-mass", metavar="MODEL",
                        help="the model whose period ratio is swept: "
                        f"{', '.join(SWEPT_MODELS)} (normalised parameters; --damping "
                        "applies to it)")
    parser.add_argument("--method", default=None,
                        help="solution method (default: the model's own; spring-mass: exact, "
                        "closed-form propagation, or a diffrax solver name such as tsit5; an "
                        "unknown name lists them)")
    parser.add_argument("--out", metavar="DIR", help="write CSV, JSON, figures and tables here")
    add_format(parser)
    parser.set_defaults(func=run)


def parse_model(text: str, damping: float):
    """The model template named by ``--model`` (its period ratio is swept), from the
    models' registry."""
    from .. import models  # only the model named is imported (the others import diffrax)

    name, _, values = str(text).strip().lower().partition(":")
    try:
        numbers = [float(v) for v in values.split(",")] if values else []
    except ValueError as error:
        raise CliError(f"--model {text!r}: parameters must be numbers") from error
    try:
        entry = models.model_entry(name, swept=True)
    except ValueError as error:
        raise CliError(f"--model {text!r}: {error}") from None
    with options_named(f"--model {text!r}"):
        entry.counted(numbers)  # in the registry's words (its model name may be a field's)
    # The API's messages name the model's fields; the user gave the registry's placeholders.
    with options_named(f"--model {text!r}", **{field: placeholder for field, placeholder in entry.parameters}):
        return entry.template(numbers, damping)


def _fit_or_none(curve):
    from ..metrics import fit_torsion_factor

    try:
        return fit_torsion_factor(curve)
    except ValueError:
        return None


def _table(curves, fits) -> str:
    width = max([20, *(len(name) + 1 for name in curves)])
    lines = [f"{'law':<{width}} {'Ca':>7} {'max Ct':>7} {'max CaCt':>8} {'max R':>7} "
             f"{'p':>7} {'q':>6} {'r':>6}"]
    for name, c in curves.items():
        f = fits.get(name)
        fit = f"{f.p:7.3f} {f.q:6.3f} {f.r:6.3f}" if f else f"{'-':>7} {'-':>6} {'-':>6}"
        lines.append(f"{name:<{width}} {c.ca:7.4f} {_largest(c.ct):7.4f} {_largest(c.ca_ct):8.4f} "
                     f"{_largest(c.residual):7.4f} {fit}")
    lines.append("Ca and Ca*Ct in units of h/T^2 (stroke over rise time squared); Ct and R in "
                 "units of Ca; maxima over the period ratios given (those solved).")
    lines.append("p, q, r: the fit Ct ~ p/n^q + r of the upper envelope; '-' where it cannot "
                 "be fitted (too few period ratios or envelope points).")
    return "\n".join(lines)


def _largest(values) -> float:
    """Largest of the values solved (NaN marks a failed ratio); NaN if none was."""
    finite = np.asarray(values)[np.isfinite(values)]
    return float(finite.max()) if finite.size else float("nan")


def _csv(curves) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(["law", "period_ratio", "ct", "residual", "peak_in_motion", "ca_ct", "result"])
    for name, c in curves.items():
        for *row, code in zip(c.period_ratio, c.ct, c.residual, c.peak_in_motion, c.ca_ct,
                              c.result_names):
            writer.writerow([name, *(f"{x:.12g}" for x in row), code])
    return buffer.getvalue()


def failure_warning(name: str, curve, shown: int = 5) -> str | None:
    """One line naming the period ratios where ``curve``'s solver failed, or ``None``."""
    failed = np.flatnonzero(curve.failed)
    if not failed.size:
        return None
    ratios = ", ".join(f"{curve.period_ratio[i]:.6g}" for i in failed[:shown])
    more = ", ..." if failed.size > shown else ""
    counts = Counter(curve.result_names[i] for i in failed)
    codes = ", ".join(f"{code}" if len(counts) == 1 else f"{code} x{k}" for code, k in counts.items())
    return (f"camjax ct: warning: {name}: the solver failed at {failed.size} of "
            f"{curve.period_ratio.size} period ratios (n = {ratios}{more}; {codes}); their "
            "metrics are NaN in the output")


def _json(curves, args, selected) -> dict:
    first = next(iter(curves.values()))
    return {
        "period_ratio": first.period_ratio,
        "damping": args.damping,
        "model": args.model,
        "method": first.method,
        "laws": {
            name: {
                **selected[name].peak_coefficients(),
                "ct": c.ct,
                "residual": c.residual,
                "peak_in_motion": c.peak_in_motion,
                "result": c.result_names,
            }
            for name, c in curves.items()
        },
    }


def _fit_report(curves, fits) -> str:
    from ..metrics import best_law_switches, ca_ct_crossings

    rows = ["| law | Ca | p | q | r | rms error |", "|---|---|---|---|---|---|"]
    for name, f in fits.items():
        rows.append(f"| {name} | {curves[name].ca:.4f} | {f.p:.4f} | {f.q:.4f} | {f.r:.4f} "
                    f"| {f.rms_error:.4f} |")
    rows += ["", "Where the law with the lowest fitted Ca*Ct envelope changes:", ""]
    rows += [f"- n = {n:.3f}: {a} -> {b}" for n, a, b in best_law_switches(curves, fits)]
    if {"modified-sine", "cycloidal"} <= fits.keys():
        cross = ca_ct_crossings(curves["modified-sine"], curves["cycloidal"])
        text = ", ".join(f"{x:.3f}" for x in cross) or "none in range"
        rows += ["", f"Fitted Ca*Ct envelopes of modified-sine and cycloidal cross at n = {text}."]
    return "\n".join(rows) + "\n"


def run(args) -> int:
    from tqdm import tqdm

    from ..sweep import ct_curve

    selected = laws_of(args, tool="camjax ct")
    n = parse_range(args.n, "--n")
    check_damping(args.damping)
    if not args.dwell >= 0:
        raise CliError(f"--dwell: must be a non-negative number of rise durations, got {args.dwell:g}")
    model = parse_model(args.model, args.damping)
    with options_named("--method"):
        model.options(args.method, args.dwell)  # the method named, before any work
    out = output_dir(args.out)
    drawing = drawing_for(args) if out is not None else None  # before the sweep
    minutes = len(selected) * n.size * SECONDS_PER_RATIO / 60
    if minutes > 0.5:  # said before a long sweep starts (the bar below counts laws)
        print(f"camjax ct: {len(selected)} law(s) x {n.size:,} period ratios: about {minutes:.0f} "
              "minute(s) on two CPU cores (the exact path; the other models take longer)", file=sys.stderr)
    curves = {}
    for name, law in tqdm(selected.items(), desc="camjax ct", unit="law", file=sys.stderr,
                          disable=not sys.stderr.isatty()):
        # A failed ratio does not end the sweep: it is NaN in the output, named on stderr.
        curves[name] = ct_curve(law, n, model=model, method=args.method, dwell=args.dwell,
                                throw=False, **sweep_options_for(args, model))
    for name, curve in curves.items():
        warning = failure_warning(name, curve)
        if warning:
            print(warning, file=sys.stderr)
    fits = {k: f for k, f in ((k, _fit_or_none(c)) for k, c in curves.items()) if f}
    if out is not None:
        figures = [Figure("ct_curves", out / "ct_curves.png", (curves,), {"dwell": args.dwell}),
                   Figure("residual_curves", out / "residual_curves.png", (curves,))]
        if fits:  # the chart needs a fitted envelope
            figures.append(Figure("ca_ct_chart", out / "ca_ct.png", (curves, fits), {"dwell": args.dwell}))
        drawing.draw(figures)
        (out / "ct.csv").write_text(_csv(curves))
        dump_json(_json(curves, args, selected), out / "ct.json")
        (out / "torsion_factor_fit.md").write_text(_fit_report(curves, fits))
        drawing.wait()
        written = ["ct.csv", "ct.json", "torsion_factor_fit.md", *(f.path.name for f in figures)]
        print(f"wrote {out}/: {', '.join(written)}", file=sys.stderr)
    if args.format == "json":
        print(dump_json(_json(curves, args, selected)))
    elif args.format == "csv":
        sys.stdout.write(_csv(curves))
    else:
        print(_table(curves, fits))
    return 0


