"""The convex reference problem of a residual design, solved as an LP (scipy's HiGHS).

With the caps fixed, ``min max_n w |int a e^{-i w u} du|`` subject to ``|a| <= C``,
``|j| <= J`` and ``v >= 0`` is convex in the spline coefficients (``a``, ``j``, ``v`` are
affine in them).  Writing ``|z| <= t`` as ``Re(z e^{-i theta_p}) <= t`` for P directions, and
the caps and band on grids, relaxes every constraint, so the LP value ``t`` over ``C`` is a
lower bound on ``max R`` of any spline of that size meeting the caps (``R = w|I|/Ca`` and
``Ca <= C``): a gradient design within 5% of it is within 5% of the global optimum.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from ..laws import BSplineLaw
from ._optimise import linear_maps
from ._residual import quadrature, residual_kernel


def affine_map(law_of, knots, fn):
    """``(M, b)`` with ``fn(law_of(c)).ravel() = M c + b`` (the map is affine in c)."""
    b, m = (np.asarray(x) for x in linear_maps(lambda c: fn(law_of(c)), knots))
    return m.reshape(b.size, knots), b.reshape(-1)


class ConvexBound:
    """The LP lower bound of a residual design over one band and spline size (the caps
    vary per solve; the affine maps are built once).  Needs scipy (``camjax[bench]``)."""

    def __init__(self, n1, n2, knots=24, degree=5, samples=400, directions=32, grid_per_span=24):
        self.n1, self.n2, self.knots, self.degree = n1, n2, knots, degree
        law_of = self.law_of
        template = law_of(jnp.zeros(knots))
        nodes, weights = quadrature(template, n2)
        kernel = residual_kernel(np.linspace(n1, n2, samples), 0.0, nodes, weights)
        a_m, a_b = affine_map(law_of, knots, lambda law: law.a(jnp.asarray(nodes)))
        z_m, z_b = kernel @ a_m, kernel @ a_b  # complex (samples, knots), (samples,)
        rot = np.exp(-2j * np.pi * np.arange(directions) / directions)[:, None, None]
        # Re(rot (z_m c + z_b)) <= t
        self.band_rows = np.concatenate(
            [(rot * z_m).real.reshape(-1, knots), -np.ones((directions * samples, 1))], 1)
        self.band_rhs = -(rot[:, :, 0] * z_b).real.reshape(-1)
        edges = np.unique(template.knots)
        tau = jnp.asarray(np.concatenate([np.linspace(lo, hi, grid_per_span + 1)
                                          for lo, hi in zip(edges[:-1], edges[1:])]))
        self.maps = {order: affine_map(law_of, knots, lambda law, k=order: law.evaluate(tau)[k])
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
        from scipy.optimize import linprog  # an optional dependency: only here

        result = linprog(cost, A_ub=np.concatenate(rows), b_ub=np.concatenate(rhs),
                         bounds=[(None, None)] * (self.knots + 1), method="highs")
        if result.status != 0:
            raise RuntimeError(f"the LP failed: {result.message}")
        return result.x[-1] / max_ca, self.law_of(jnp.asarray(result.x[:-1]))
