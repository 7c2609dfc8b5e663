"""The convex reference problem of a residual design, solved as an LP with scipy (HiGHS).

With the caps fixed, ``min max_n w |int a e^{-i w u} du|`` subject to ``|a| <= C``,
``|j| <= J`` and ``v >= 0`` is convex in the spline coefficients (``a``, ``j``, ``v`` are
affine in them).  Writing ``|z| <= t`` as ``Re(z e^{-i theta_p}) <= t`` for P directions, and
the caps and band on grids, relaxes every constraint, so the LP value ``t`` over ``C`` is a
lower bound on ``max R`` of any spline of that size meeting the caps (``R = w|I|/Ca`` and
``Ca <= C``).  A gradient design within 5% of this bound is within 5% of the global optimum.

Usage: python experiments/examples/design_convex.py [OUT] [--quick]  (writes results/design_convex/)
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import jax.numpy as jnp
import numpy as np

import camjax.law_design as D


def convex_lower_bound(n1, n2, max_ca, max_jerk, knots=24, **kwargs):
    """LP lower bound on max R over [n1, n2] and the LP's spline (a BSplineLaw)."""
    return D.ConvexBound(n1, n2, knots, **kwargs).lower_bound(max_ca, max_jerk)


def main(argv=None):
    """The three cases of the issue against their LP bounds, one design each (``--quick``:
    one 10-knot case with a 60-step design, a smoke run)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", type=Path, default=Path("results/design_convex"))
    parser.add_argument("--out", dest="out_option", type=Path, help="the same as the positional OUT")
    parser.add_argument("--quick", action="store_true", help="one small case (a smoke run)")
    args = parser.parse_args(argv)
    out = args.out_option or args.out
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    cases = [(6, 12, 7.5, 100.0, 24), (6, 12, 6.3, 100.0, 24), (6, 12, 7.5, 100.0, 32)]
    if args.quick:
        cases = [(6, 12, 7.5, 100.0, 10)]
    for n1, n2, ca, cj, knots in cases:
        t0 = time.perf_counter()
        bound, lp_law = convex_lower_bound(n1, n2, ca, cj, knots)
        t_lp = time.perf_counter() - t0
        lp_true = float(jnp.max(D.residual(lp_law, np.linspace(n1, n2, 2000))))
        res = D.design(D.MaxResidual(n1, n2), caps=D.Caps(ca, cj), knots=knots, progress=False,
                       **({"steps": 60} if args.quick else {}))
        r = res.values[f"max R over [{n1:g}, {n2:g}]"]
        rows.append(dict(band=[n1, n2], max_ca=ca, max_jerk=cj, knots=knots, lp_bound=bound,
                         lp_law_max_r=lp_true, design_max_r=r, ratio=r / bound,
                         design_ca=res.coefficients["Ca"], design_cj=res.coefficients["Cj"],
                         design_seconds=res.seconds, lp_seconds=t_lp))
        print(rows[-1], flush=True)
    (out / "convex.json").write_text(json.dumps(rows, indent=1))
    lines = ["| band | Ca cap | Cj cap | knots | LP lower bound | LP spline max R | design max R | design / bound | design s |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| [{r['band'][0]}, {r['band'][1]}] | {r['max_ca']} | {r['max_jerk']} | {r['knots']} | "
                     f"{r['lp_bound']:.4g} | {r['lp_law_max_r']:.4g} | {r['design_max_r']:.4g} | "
                     f"{r['ratio']:.3f} | {r['design_seconds']:.1f} |")
    (out / "convex.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
