"""The convex reference problem of a residual design, solved as an LP with scipy (HiGHS).

With the caps fixed, ``min max_n w |int a e^{-i w u} du|`` subject to ``|a| <= C``,
``|j| <= J`` and ``v >= 0`` is convex in the spline coefficients (``a``, ``j``, ``v`` are
affine in them).  Writing ``|z| <= t`` as ``Re(z e^{-i theta_p}) <= t`` for P directions, and
the caps and band on grids, relaxes every constraint, so the LP value ``t`` over ``C`` is a
lower bound on ``max R`` of any spline of that size meeting the caps (``R = w|I|/Ca`` and
``Ca <= C``).  A gradient design within 5% of this bound is within 5% of the global optimum.

Usage: python experiments/design_convex.py  (writes results/design_convex/)
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import jax.numpy as jnp
import numpy as np
from scipy.optimize import linprog

import camjax.law_design as D
from camjax.laws import BSplineLaw


def _affine(law_of, knots, fn):
    """``(M, b)`` with ``fn(law_of(c)).ravel() = M c + b`` (the map is affine in c)."""
    b, m = (np.asarray(x) for x in D.linear_maps(lambda c: fn(law_of(c)), knots))
    return m.reshape(b.size, knots), b.reshape(-1)


class ConvexProblem:
    """The LP of one band and spline size; the caps vary per solve (maps built once)."""

    def __init__(self, n1, n2, knots=24, degree=5, samples=400, directions=32, grid_per_span=24):
        self.n1, self.n2, self.knots, self.degree = n1, n2, knots, degree
        law_of = self.law_of
        template = law_of(jnp.zeros(knots))
        nodes, weights = D.quadrature(template, n2)
        kernel = D._residual._kernel(np.linspace(n1, n2, samples), 0.0, nodes, weights)
        a_m, a_b = _affine(law_of, knots, lambda law: law.a(jnp.asarray(nodes)))
        z_m, z_b = kernel @ a_m, kernel @ a_b  # complex (samples, knots), (samples,)
        rot = np.exp(-2j * np.pi * np.arange(directions) / directions)[:, None, None]
        # Re(rot (z_m c + z_b)) <= t
        self.band_rows = np.concatenate(
            [(rot * z_m).real.reshape(-1, knots), -np.ones((directions * samples, 1))], 1)
        self.band_rhs = -(rot[:, :, 0] * z_b).real.reshape(-1)
        edges = np.unique(template.knots)
        tau = jnp.asarray(np.concatenate([np.linspace(lo, hi, grid_per_span + 1)
                                          for lo, hi in zip(edges[:-1], edges[1:])]))
        self.maps = {order: _affine(law_of, knots, lambda law, k=order: law.evaluate(tau)[k])
                     for order in (1, 2, 3)}

    def law_of(self, c):
        return BSplineLaw(c, self.degree)

    def lower_bound(self, max_ca, max_jerk):
        """LP lower bound on max R over the band for these caps, and the LP's spline."""
        rows, rhs = [self.band_rows], [self.band_rhs]
        zero = np.zeros((self.maps[1][0].shape[0], 1))
        for order, cap in ((2, max_ca), (3, max_jerk)):
            if cap is None:
                continue
            m, b = self.maps[order]
            for sign in (1, -1):
                rows.append(np.concatenate([sign * m, zero], 1))
                rhs.append(cap - sign * b)
        m, b = self.maps[1]  # v >= 0
        rows.append(np.concatenate([-m, zero], 1))
        rhs.append(b)
        cost = np.zeros(self.knots + 1)
        cost[-1] = 1.0
        result = linprog(cost, A_ub=np.concatenate(rows), b_ub=np.concatenate(rhs),
                         bounds=[(None, None)] * (self.knots + 1), method="highs")
        if result.status != 0:
            raise RuntimeError(f"LP failed: {result.message}")
        return result.x[-1] / max_ca, self.law_of(jnp.asarray(result.x[:-1]))


def convex_lower_bound(n1, n2, max_ca, max_jerk, knots=24, **kwargs):
    """LP lower bound on max R over [n1, n2] and the LP's spline (a BSplineLaw)."""
    return ConvexProblem(n1, n2, knots, **kwargs).lower_bound(max_ca, max_jerk)


def main(out=Path("results/design_convex")):
    """The three cases of the issue against their LP bounds, one design each."""
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    cases = [(6, 12, 7.5, 100.0, 24), (6, 12, 6.3, 100.0, 24), (6, 12, 7.5, 100.0, 32)]
    for n1, n2, ca, cj, knots in cases:
        t0 = time.perf_counter()
        bound, lp_law = convex_lower_bound(n1, n2, ca, cj, knots)
        t_lp = time.perf_counter() - t0
        lp_true = float(jnp.max(D.residual(lp_law, np.linspace(n1, n2, 2000))))
        res = D.design(D.MaxResidual(n1, n2), caps=D.Caps(ca, cj), knots=knots, progress=False)
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
    main(*(Path(a) for a in sys.argv[1:]))
