"""``camjax design``: optimise a B-spline motion law and compare it with the standard laws."""

from __future__ import annotations

import sys
import warnings

import numpy as np

from .._plain import example_names
from ._common import (
    CliError,
    check_damping,
    dump_json,
    file_named,
    options_named,
    output_dir,
    parse_float_list,
    sweep_options_for,
)
from ._drawing import Figure, drawing_for
from .program import is_machine, program_path

DEFAULT_STEPS = 6000
"""The design's own default (``camjax.law_design.DEFAULT_STEPS``; a test checks they agree)."""



def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "design",
        help="design a B-spline motion law (residual vibration, Ca*Ct or RMS acceleration)",
        description="Optimise a B-spline rise for a period-ratio band under caps; write the "
        "law (JSON, CSV), figures and a comparison with every standard law.",
    )
    parser.add_argument("--objective", choices=("residual", "ca-ct", "rms-acceleration", "preload", "seating"),
                        default="residual",
                        help="what to minimise: residual vibration R (units of Ca) or the peak "
                        "inertia load Ca*Ct (units of h/T^2), worst case over the band; "
                        "'rms-acceleration': Ca_rms, a servo's heating (no band; reported against "
                        "the floor 2 sqrt(3) no rest-to-rest law passes; give --max-jerk); with "
                        "--program also 'preload': the largest preload (N) the whole program "
                        "needs over the speed range; 'seating': the valve's largest seating "
                        "velocity (m/s) over the speed range, for a chain with a [seat], simulated "
                        "with its contacts; for a --segment that starts or ends in "
                        "motion, 'residual' is the whole program's largest residual vibration (mm)")
    where = parser.add_mutually_exclusive_group()  # one is required unless --program (checked in run)
    where.add_argument("--band", metavar="N1:N2",
                       help="period-ratio band (dimensionless, rise time / natural period)")
    where.add_argument("--n", type=float, help="a single period ratio (dimensionless)")
    parser.add_argument("--max-ca", type=float, default=None,
                        help="cap on Ca, the peak acceleration in units of h/T^2 (>= 4; "
                        "default: none)")
    parser.add_argument("--max-jerk", type=float, default=None,
                        help="cap on Cj, the peak jerk in units of h/T^3 (>= 32, more "
                        "with --max-ca below 8; "
                        "default: none)")
    parser.add_argument("--damping", type=float, default=0.0,
                        help="damping ratio zeta in [0, 1) (dimensionless)")
    parser.add_argument("--knots", type=int, default=24, help="free B-spline coefficients")
    parser.add_argument("--seed", type=int, default=0,
                        help="seed of the random restarts of the optimiser")
    parser.add_argument("--steps", type=int, default=DEFAULT_STEPS, help="optimiser steps")
    parser.add_argument("--optimizer", choices=("lbfgs", "adam"), default="lbfgs",
                        help="optimisation method")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument("--program", metavar="FILE", help="design one segment of this cam program "
                        f"(a file, or a built-in example: {', '.join(example_names())}; with --segment and "
                        "--rpm; writes DIR/program.toml and the law beside it)")
    parser.add_argument("--segment", type=int, help="segment number (1-based) to design, with --program")
    parser.add_argument("--rpm", metavar="LO:HI", help="speed range in rpm, with --program (maps to the segment's band)")
    parser.add_argument("--seating-speeds", type=int, metavar="COUNT",
                        help="with --objective seating: speeds (evenly spaced in the period) over "
                        "--rpm at which the seating velocity is simulated (default 8 per natural-"
                        "frequency cycle the turn gains across the range)")
    parser.add_argument("--rounds", type=int, metavar="COUNT",
                        help="with --objective seating: rounds of its linear model (default 6), "
                        "each a design of --steps")
    parser.set_defaults(func=run)


def _segment_objectives(text: str) -> str:
    """The objectives a segment of the program ``text`` names can be designed for, in words
    (``design_objectives``: the library's rule for this program)."""
    from ..program import Program, design_objectives

    path = program_path(text)
    if is_machine(path):
        return "design takes one cam's program, not a machine file"
    with file_named(path):
        takes = design_objectives(Program.load(path))
    if not takes:
        return "this program's segments have no design objective"
    listed = takes[0] if len(takes) == 1 else ", ".join(takes[:-1]) + " or " + takes[-1]
    return f"this program's segment design takes {listed}"


def _run_program(args, out) -> int:
    from ..law_design import Caps, DesignNotImproved
    from ..program import Program, design_segment, segment_band, write_program

    if args.segment is None or args.rpm is None:
        raise CliError("--program needs --segment and --rpm LO:HI")
    parts = args.rpm.split(":")
    if len(parts) != 2:
        raise CliError(f"--rpm: expected LO:HI, got {args.rpm!r}")
    rpm_lo, rpm_hi = (parse_float_list(p, "--rpm")[0] for p in parts)
    if not 0 < rpm_lo < rpm_hi:
        raise CliError(f"--rpm: need 0 < LO < HI, got {args.rpm!r}")
    path = program_path(args.program)
    if is_machine(path):
        raise CliError(f"--program: {path} is a machine file (several cams on one shaft); "
                       "design takes one cam's program: give the program file of the cam")
    seating = {key: value for key, value in (("seating_speeds", args.seating_speeds), ("rounds", args.rounds))
               if value is not None}
    with file_named(path), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DesignNotImproved)
        program = Program.load(path)
        with options_named(segment="--segment"):
            n1, n2 = segment_band(program, args.segment, rpm_lo, rpm_hi)
        new, result = design_segment(
            program, args.segment, rpm_lo, rpm_hi, objective=args.objective,
            caps=Caps(args.max_ca, args.max_jerk), knots=args.knots, seed=args.seed,
            optimizer=args.optimizer, progress=not args.quiet, **seating,
            **({} if args.steps is None else {"steps": args.steps}))
    path = write_program(new, out)
    (label, value), = result.values.items()
    start = result.initial_values[label]
    dump_json({"segment": args.segment, "rpm": [rpm_lo, rpm_hi], "band": [n1, n2],
               "objective": label, "initial_value": start, "value": value,
               "kept_initial": result.kept_initial, "law": new.segments[args.segment - 1].law.name},
              out / "summary.json")
    for w in caught:
        if issubclass(w.category, DesignNotImproved):
            print(f"warning: {w.message}", file=sys.stderr)
        else:
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    print(f"segment {args.segment}: band n = {n1:.4g}..{n2:.4g}; {label} = {value:.5g}; "
          + ("the segment's own law kept (the design did not improve on it)" if result.kept_initial
             else f"{start:.5g} with the segment's own law")
          + f"; wrote {path}")
    return 0


def _band(text: str) -> tuple[float, float]:
    parts = text.split(":")
    if len(parts) != 2:
        raise CliError(f"--band: expected N1:N2, got {text!r}")
    n1, n2 = (parse_float_list(p, "--band")[0] for p in parts)
    if not 0 < n1 < n2:
        raise CliError(f"--band: need 0 < N1 < N2, got {text!r}")
    return n1, n2


def _standard_laws_compared(ratios, damping: float, knots: int, sweep_options: dict,
                            csv_tau: np.ndarray) -> dict:
    """``(law, CtCurve, peak coefficients)`` of every standard law over ``ratios``, swept by
    the program that will sweep the designed spline of ``knots`` coefficients.

    Then the designed spline's own programs, compiled here while the design runs on the
    main thread (their values are thrown away; the designed spline has the same shapes, so
    it finds them compiled), in the order the design needs them: its peak search (the cap
    checks read it), its samples on the sweep's grid (the reports) and its evaluation on the
    CSV's points."""
    from ..laws import BSplineLaw, standard_laws
    from ..sweep import ct_curves, prepare_sweep

    laws = {law.name: law for law in standard_laws()}
    designed_size = BSplineLaw(np.zeros(knots))  # the designed law's pieces, any values
    curves = ct_curves(laws, ratios, damping=damping, like=[designed_size], **sweep_options)
    compared = {name: (law, curves[name], law.peak_coefficients()) for name, law in laws.items()}
    designed_size.peak_coefficients()
    _, template, options = prepare_sweep(ratios, damping=damping, **sweep_options)
    template.sweep_law(designed_size, options)
    designed_size.evaluate(csv_tau)
    return compared


def design_title(objective: str, caps, damping: float) -> str:
    """A design figure's title: the objective, the caps and the damping."""
    limits = [f"Ca <= {caps.max_ca:g}" if caps.max_ca is not None else "Ca free",
              f"Cj <= {caps.max_jerk:g}" if caps.max_jerk is not None else "Cj free"]
    if caps.monotone:
        limits.append("monotone rise")
    return (f"Designed B-spline law: minimise {objective}; caps {', '.join(limits)}; "
            f"SDOF damping zeta = {damping:g}")


def _law_figure(law, columns: np.ndarray, title: str, path) -> Figure:
    """``law.png``: the designed law drawn from the CSV's points (``columns``: tau, s, v,
    a, j), its leaves on the host so that the drawing process needs no JAX."""
    import jax

    on_host = jax.tree.map(np.asarray, law)
    return Figure("law_curves", path, ([on_host], columns.shape[0]),
                  {"title": title, "values": [tuple(columns[:, 1:].T)]})


def run(args) -> int:
    from concurrent.futures import ThreadPoolExecutor

    from tqdm import tqdm

    from .. import law_design as D
    from ..caches import carried
    from ..laws import save
    from ..sweep import ct_curve, prepare_sweep

    check_damping(args.damping)
    for option, value, most in (("--knots", args.knots, D.MAX_KNOTS), ("--steps", args.steps, D.MAX_STEPS)):
        if not 1 <= value <= most:
            raise CliError(f"{option}: must be from 1 to {most:,}, got {value}")
    with options_named(max_ca="--max-ca", max_jerk="--max-jerk"):
        D.Caps(args.max_ca, args.max_jerk)  # the caps checked before any work
    for option, value in (("--seating-speeds", args.seating_speeds), ("--rounds", args.rounds)):
        if value is not None and args.objective != "seating":
            raise CliError(f"{option}: only with --objective seating")
        if value is not None and value < 1:
            raise CliError(f"{option}: must be a whole number of at least 1, got {value}")
    if args.program and (args.band or args.n is not None):
        raise CliError(f"{'--band' if args.band else '--n'}: not with --program (the segment's "
                       "band comes from --rpm)")
    if args.program and args.objective == "rms-acceleration":
        raise CliError("--objective rms-acceleration: not with --program (it designs a free "
                       f"rise; {_segment_objectives(args.program)})")
    out = output_dir(args.out)
    if args.program:
        return _run_program(args, out)
    sweep_options = sweep_options_for(args)
    if args.objective in ("preload", "seating"):
        raise CliError(f"--objective {args.objective} needs --program (a whole cam with its follower)")
    if args.objective == "rms-acceleration":
        return _run_rms(args, out)
    if args.band is None and args.n is None:
        raise CliError("one of --band, --n or --program is required")
    if args.n is not None and not args.n > 0:
        raise CliError(f"--n: period ratio must be positive, got {args.n}")
    band = _band(args.band) if args.band else None
    with options_named("--band" if band else "--n"):
        if args.objective == "residual":
            objective = (D.MaxResidual(*band, damping=args.damping) if band
                         else D.Residual(args.n, damping=args.damping))
        else:
            objective = (D.MaxCaCt(*band, damping=args.damping) if band
                         else D.CaCt(args.n, damping=args.damping))
    caps = D.Caps(args.max_ca, args.max_jerk)
    steps = args.steps
    n1, n2 = band if band else (0.8 * args.n, 1.2 * args.n)
    ratios = np.linspace(n1, n2, D.EVALUATION_SAMPLES)
    drawing = drawing_for(args)  # before JAX starts (prepare_sweep starts it)
    # The comparison's ratios (0.8 to 1.2 times --n), checked before any work.
    with options_named("--band" if band else "--n (compared over 0.8 to 1.2 times it)"):
        prepare_sweep(ratios, damping=args.damping)
    # The standard laws' side of the comparison does not depend on the design: it is
    # traced, compiled and run on a thread beside the design (XLA releases the GIL while it
    # compiles and runs, so the two compiles share the machine's cores).
    tau = np.linspace(0.0, 1.0, 10001)  # the CSV's points
    with ThreadPoolExecutor(1) as pool:
        standard = pool.submit(carried(_standard_laws_compared), ratios, args.damping, args.knots,
                               sweep_options, tau)
        result = D.design(objective, caps=caps, knots=args.knots, seed=args.seed, steps=steps,
                          optimizer=args.optimizer, progress=not args.quiet,
                          sweep_options=sweep_options)
        law = result.law
        save(law, out / "law.json")
        columns = np.stack([tau, *(np.asarray(x) for x in law.evaluate(tau))], axis=1)
        np.savetxt(out / "law.csv", columns, delimiter=",", header="tau,s,v,a,j", comments="",
                   fmt="%.17g")
        # Every law is sampled on the exact path's grid, so the designed spline and the
        # standard laws share one compiled sweep.  The bar covers the rest of the command.
        bar = tqdm(total=3, desc="compare", unit="step", disable=args.quiet, file=sys.stderr)
        bar.set_postfix_str("designed law")
        sweeps = {"designed": ct_curve(law, ratios, damping=args.damping, **sweep_options)}
        # The design already refined its own peaks (one compiled call fewer).
        peaks = {"designed": result.coefficients}
        laws = {"designed": law}
        bar.update()
        bar.set_postfix_str("standard laws")
        for name, (each, curve, coefficients) in standard.result().items():
            laws[name], sweeps[name], peaks[name] = each, curve, coefficients
        bar.update()
    rows, curves = [], {}
    for name, each in laws.items():
        r, load = sweeps[name].residual, sweeps[name].ca_ct
        curves[name] = (r, load)
        # A band objective's report is the maximum over these same ratios.
        value = (float(r.max()) if isinstance(objective, D.MaxResidual) else
                 float(load.max()) if isinstance(objective, D.MaxCaCt)
                 else objective.report(each, **sweep_options))
        rows.append({"law": name, "objective": value, "Ca": peaks[name]["Ca"],
                     "Cj": peaks[name]["Cj"], "max_R": float(r.max()), "max_CaCt": float(load.max())})
    where = ("the objective on 2000 period ratios across the band" if band else
             f"the objective at n = {args.n:g}")
    _write_table(rows, f"{objective.label} ({where}; max R and max Ca*Ct over "
                       f"[{n1:g}, {n2:g}], 2000 ratios)", out)
    dump_json({"objective": objective.label, "value": result.values[objective.label],
               "caps": {"max_ca": args.max_ca, "max_jerk": args.max_jerk, "monotone": True},
               "coefficients": result.coefficients, "knots": args.knots, "seed": args.seed,
               "steps": steps, "repaired": result.restored, "seconds": result.seconds,
               "band": [n1, n2], "damping": args.damping}, out / "summary.json")
    bar.set_postfix_str("figures")
    title = design_title(objective.label, caps, args.damping)
    # Drawn from the CSV's points: the law is evaluated once.
    drawing.draw([_law_figure(law, columns, title, out / "law.png"),
                  Figure("design_comparison", out / "curves.png", (ratios, curves), {"title": title})])
    drawing.wait()
    bar.update()
    bar.close()
    print(f"{objective.label}: designed {rows[0]['objective']:.5g}; best standard "
          f"{min(rows[1:], key=lambda r: r['objective'])['law']} "
          f"{min(r['objective'] for r in rows[1:]):.5g}; wrote {out}")
    return 0


def _run_rms(args, out) -> int:
    """Least RMS acceleration under the caps: the law, its coefficients against the floor
    and every standard law's."""
    from .. import law_design as D
    from ..laws import RMS_ACCELERATION_FLOOR, save, standard_laws

    if args.band or args.n is not None:
        raise CliError(f"{'--band' if args.band else '--n'}: not with --objective rms-acceleration "
                       "(the RMS acceleration does not depend on the period ratio)")
    if args.damping:
        raise CliError("--damping: not with --objective rms-acceleration (no vibration in it)")
    objective = D.RmsAcceleration()
    caps = D.Caps(args.max_ca, args.max_jerk)
    drawing = drawing_for(args)  # before the design starts JAX
    result = D.design(objective, caps=caps, knots=args.knots, seed=args.seed, steps=args.steps,
                      optimizer=args.optimizer, progress=not args.quiet)
    law = result.law
    save(law, out / "law.json")
    tau = np.linspace(0.0, 1.0, 10001)
    columns = np.stack([tau, *(np.asarray(x) for x in law.evaluate(tau))], axis=1)
    np.savetxt(out / "law.csv", columns, delimiter=",", header="tau,s,v,a,j", comments="", fmt="%.17g")
    keys = ("Cv", "Ca", "Cj", "Cv_rms", "Ca_rms", "Cva")
    rows = [{"law": "designed", **result.coefficients, **law.rms_coefficients()}]
    rows += [{"law": each.name, **each.peak_coefficients(), **each.rms_coefficients()}
             for each in standard_laws()]
    for row in rows:
        row["Ca_rms_over_floor"] = row["Ca_rms"] / RMS_ACCELERATION_FLOOR
    lines = [",".join(("law", *keys, "Ca_rms_over_floor"))]
    lines += [",".join(str(r[k]) for k in ("law", *keys, "Ca_rms_over_floor")) for r in rows]
    (out / "comparison.csv").write_text("\n".join(lines) + "\n")
    md = [f"Objective: {objective.label}; caps Ca <= {args.max_ca}, Cj <= {args.max_jerk}", "",
          "| law | Cv | Ca | Cj | Cv_rms | Ca_rms | Cva | Ca_rms / floor |",
          "|---|---|---|---|---|---|---|---|"]
    md += ["| " + " | ".join([r["law"], *(f"{r[k]:.4f}" for k in keys), f"{r['Ca_rms_over_floor']:.4f}"])
           + " |" for r in rows]
    (out / "comparison.md").write_text("\n".join(md) + "\n")
    value = result.values[objective.label]
    dump_json({"objective": objective.label, "value": value, "floor": RMS_ACCELERATION_FLOOR,
               "value_over_floor": value / RMS_ACCELERATION_FLOOR,
               "caps": {"max_ca": args.max_ca, "max_jerk": args.max_jerk, "monotone": True},
               "coefficients": rows[0] | {"law": law.name}, "knots": args.knots, "seed": args.seed,
               "steps": args.steps, "repaired": result.restored, "seconds": result.seconds},
              out / "summary.json")
    drawing.draw([_law_figure(law, columns, design_title(objective.label, caps, 0.0), out / "law.png")])
    drawing.wait()
    best = min(rows[1:], key=lambda r: r["Ca_rms"])
    print(f"Ca_rms: designed {value:.5g} ({value / RMS_ACCELERATION_FLOOR:.4f} of the floor "
          f"2 sqrt(3) = {RMS_ACCELERATION_FLOOR:.5g}); best standard {best['law']} "
          f"{best['Ca_rms']:.5g}; wrote {out}")
    return 0


def _write_table(rows, label, out) -> None:
    keys = ["law", "objective", "Ca", "Cj", "max_R", "max_CaCt"]
    lines = [",".join(keys)] + [",".join(str(r[k]) for k in keys) for r in rows]
    (out / "comparison.csv").write_text("\n".join(lines) + "\n")
    md = [f"Objective: {label}", "",
          "| law | objective | Ca | Cj | max R | max Ca*Ct |", "|---|---|---|---|---|---|"]
    md += [f"| {r['law']} | {r['objective']:.5g} | {r['Ca']:.4g} | {r['Cj']:.4g} | "
           f"{r['max_R']:.4g} | {r['max_CaCt']:.4g} |" for r in rows]
    (out / "comparison.md").write_text("\n".join(md) + "\n")

