"""Ca*Ct, worst case over n = c +- 10% (c = 5 and 8): designed splines against every
standard law and against the best member of the SCCA family from a vmapped sweep.

Ca*Ct is the payload's peak acceleration in units of h/T^2, the figure laws are compared
by.  Designs: 24 knots, started from the modified trapezoid, with a jerk cap Cj <= 100 (the
honest comparison) and without one (where the jerk grows to hundreds).  The SCCA sweep
covers the simplex a + b + c + d = 1 (d the zero-acceleration fraction) in steps of 0.05,
then in steps of 0.01 around the best point; every member is one row of a vmapped
exact-path batch (``camjax.ct_curves`` stacks laws of one type).

Usage: python experiments/examples/design_caact.py  (writes results/design_caact/)
"""

from __future__ import annotations

import itertools
import json
import sys
import time
from pathlib import Path

import jax.numpy as jnp
import numpy as np
from scipy.optimize import linprog

import camjax
import camjax.law_design as D
from camjax.laws import SCCA, BSplineLaw, standard_laws

CENTRES = (5.0, 8.0)
SWEEP_RATIOS = 200  # per member in the sweep; the winner is re-evaluated on 2000
KNOTS = 24


def simplex(step, around=None, radius=None):
    """(a, b, c) with a, b, c >= 0 and a + b + c <= 1 on a grid of ``step``."""
    k = round(1 / step)
    points = [np.array(p) * step for p in itertools.product(range(k + 1), repeat=3) if sum(p) <= k]
    if around is not None:
        points = [p for p in points if np.max(np.abs(p - around)) <= radius + 1e-12]
    return [p for p in points if p.sum() > 0]


def worst_ca_ct(fractions, n1, n2, samples=SWEEP_RATIOS, chunk=64):
    """Worst Ca*Ct over [n1, n2] of each SCCA member, vmapped in chunks."""
    ratios = np.linspace(n1, n2, samples)
    out = []
    for i in range(0, len(fractions), chunk):
        laws = {j: SCCA(*map(float, f)) for j, f in enumerate(fractions[i:i + chunk])}
        curves = camjax.ct_curves(laws, ratios)
        out += [float(np.max(c.ca_ct)) for c in curves.values()]
    return np.array(out)


def sweep(n1, n2):
    coarse = simplex(0.05)
    values = worst_ca_ct(coarse, n1, n2)
    best = coarse[int(np.argmin(values))]
    fine = simplex(0.01, around=best, radius=0.05)
    fine_values = worst_ca_ct(fine, n1, n2)
    best = fine[int(np.argmin(fine_values))]
    law = SCCA(*map(float, best))
    return dict(fractions=[float(x) for x in best], members=len(coarse) + len(fine),
                worst_ca_ct=D.MaxCaCt(n1, n2).report(law), **law.peak_coefficients())


def lp_lower_bound(n1, n2, max_jerk, knots=KNOTS, samples=64, directions=32):
    """A lower bound on the worst Ca*Ct over [n1, n2] of any spline of this size with
    Cj <= max_jerk and v >= 0 (undamped, dwell of at least half a vibration period).

    Ca*Ct is max |x''| over the rise and the dwell, and x'' is affine in the coefficients;
    sampling n and t, and writing the dwell amplitude w|q_end| <= t with ``directions``
    half-planes, relaxes the problem into an LP (scipy HiGHS) whose value is a lower bound.
    """
    ratios = np.linspace(n1, n2, samples)
    law_of = lambda c: BSplineLaw(c)  # noqa: E731
    features = D.MaxCaCt(n1, n2, samples=samples).features  # x'' and the dwell's mode, linear in c
    (b, e_b), (m, e_m) = (tuple(np.asarray(x) for x in pair) for pair in D.linear_maps(
        lambda c: features(law_of(c)), knots))
    m, b = m.reshape(b.size, knots), b.reshape(-1)
    e_m, e_b = e_m.reshape(e_b.size, knots), e_b.reshape(-1)
    omega = 2 * np.pi * ratios
    q_m = (e_m[0::2] + 1j * e_m[1::2]) * omega[:, None]  # rows alternate Re, Im per ratio
    q_b = (e_b[0::2] + 1j * e_b[1::2]) * omega
    rot = np.exp(-2j * np.pi * np.arange(directions) / directions)[:, None, None]
    ones = lambda k: -np.ones((k, 1))  # noqa: E731
    rows = [np.concatenate([m, ones(len(m))], 1), np.concatenate([-m, ones(len(m))], 1),
            np.concatenate([(rot * q_m).real.reshape(-1, knots), ones(directions * samples)], 1)]
    rhs = [-b, b, -(rot[:, :, 0] * q_b).real.reshape(-1)]
    template = law_of(jnp.zeros(knots))
    tau = D.dense_tau(template)
    for order, cap in ((3, max_jerk), (1, None)):
        mm, bb = D.affine_map(law_of, knots, lambda law, k=order: law.evaluate(tau)[k])
        zero = np.zeros((len(mm), 1))
        if cap is not None:
            rows += [np.concatenate([mm, zero], 1), np.concatenate([-mm, zero], 1)]
            rhs += [cap - bb, cap + bb]
        else:  # v >= 0
            rows.append(np.concatenate([-mm, zero], 1))
            rhs.append(bb)
    cost = np.zeros(knots + 1)
    cost[-1] = 1.0
    result = linprog(cost, A_ub=np.concatenate(rows), b_ub=np.concatenate(rhs),
                     bounds=[(None, None)] * (knots + 1), method="highs")
    if result.status != 0:
        raise RuntimeError(f"LP failed: {result.message}")
    return float(result.x[-1]), law_of(jnp.asarray(result.x[:-1]))


def study(centre):
    n1, n2 = 0.9 * centre, 1.1 * centre
    objective = D.MaxCaCt(n1, n2, samples=16)
    rows = {}
    for label, caps in (("designed, Cj <= 100", D.Caps(max_jerk=100.0)), ("designed, no caps", D.Caps())):
        result = D.design(objective, caps=caps, knots=KNOTS, initial="modified-trapezoid", progress=False)
        rows[label] = dict(worst_ca_ct=result.values[objective.label], seconds=result.seconds,
                           **result.coefficients)
        print(centre, label, rows[label], flush=True)
    t0 = time.perf_counter()
    bound, lp_law = lp_lower_bound(n1, n2, 100.0)
    rows["global optimum, Cj <= 100 (LP lower bound)"] = dict(
        worst_ca_ct=bound, seconds=time.perf_counter() - t0, **lp_law.peak_coefficients())
    t0 = time.perf_counter()
    rows["best SCCA (sweep)"] = sweep(n1, n2)
    rows["best SCCA (sweep)"]["seconds"] = time.perf_counter() - t0
    print(centre, rows["best SCCA (sweep)"], flush=True)
    for law in standard_laws():
        rows[law.name] = dict(worst_ca_ct=objective.report(law), **law.peak_coefficients())
    standard = {k: v for k, v in rows.items() if not k.startswith(("designed", "best SCCA", "global"))}
    best = min(standard, key=lambda k: standard[k]["worst_ca_ct"])
    return dict(band=[n1, n2], rows=rows, best_standard=best)


def main(out=Path("results/design_caact")):
    out.mkdir(parents=True, exist_ok=True)
    studies = [study(c) for c in CENTRES]
    (out / "caact.json").write_text(json.dumps(studies, indent=1, default=float))
    lines = []
    for s in studies:
        best = s["rows"][s["best_standard"]]["worst_ca_ct"]
        lines += [f"Worst-case Ca*Ct over n in [{s['band'][0]:g}, {s['band'][1]:g}] (2000 period ratios); "
                  f"best standard law: {s['best_standard']}", "",
                  "| law | worst Ca*Ct | vs best standard | Ca | Cj | s |", "|---|---|---|---|---|---|"]
        for name, r in s["rows"].items():
            label = name + (f" {tuple(r['fractions'])}" if "fractions" in r else "")
            seconds = f"{r['seconds']:.1f}" if "seconds" in r else ""
            lines.append(f"| {label} | {r['worst_ca_ct']:.4f} | {100 * (r['worst_ca_ct'] / best - 1):+.1f}% | "
                         f"{r['Ca']:.4g} | {r['Cj']:.4g} | {seconds} |")
        lines.append("")
    (out / "caact.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main(*(Path(a) for a in sys.argv[1:]))
