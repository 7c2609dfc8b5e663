"""Gradient-based design of B-spline motion laws with optax.

A design minimises a weighted sum of objectives (residual vibration R at one period
ratio, the maximum of R over a band, its expectation under a normal distribution of n,
Ca*Ct at one n or its worst case over a band) over the free coefficients of a
``BSplineLaw``, subject to caps ``Ca <= C``, ``Cj <= J`` and a monotone rise ``v >= 0``.

How the pieces fit:

- R comes from its closed form ``R = w |int_0^1 a(u) exp(lambda (1 - u)) du| / (sqrt(1 -
  zeta^2) Ca)`` (``lambda`` the oscillator's eigenvalue; for ``zeta = 0`` this is MISSION.md's
  ``w |int a exp(-i w u) du| / Ca``), integrated by Gauss-Legendre on every smooth piece of
  the law: one matrix-vector product per batch of period ratios, so thousands of n cost
  little.  Ca*Ct needs the whole response: the payload acceleration by exact propagation
  (``camjax.sdof.propagate``) on a fine grid, and the dwell's peak in closed form.
- Every quantity an objective or a cap needs (the residual's Fourier integral, the payload
  acceleration on a fine grid, the law's a, j, v on a dense grid) is linear in the spline
  coefficients, because the law is and the SDOF model is linear.  A design computes these
  maps once (one jitted Jacobian) and trains on small dense matrices: thousands of
  optimiser steps cost a second or two.
- A maximum (over a band, or over time) trains as a power mean ``(mean x^p)^(1/p)``.  L-BFGS
  runs in stages whose exponent grows fourfold (8 to 8192 by default), each stage starting
  from the last: smooth early, within 0.1% of the true max at the end.  Reports are true
  maxima over 2000 period ratios that are not the training samples.
- Caps train as quadratic penalties on a dense grid, aimed a little inside the caps.
  The constraint set is convex in the coefficients, so a result that still breaks a cap is
  blended towards a strictly feasible spline (a fit of a standard law) by bisection; then
  the caps are verified on a fine grid with refined peaks.  If no feasible point is known,
  ``CapError`` is raised: a result that breaks a requested cap is never returned.
"""

from ._caps import MIN_CJ as MIN_CJ
from ._caps import CapError as CapError
from ._caps import Caps as Caps
from ._caps import least_jerk as least_jerk
from ._convex import ConvexBound as ConvexBound
from ._convex import affine_map as affine_map
from ._objectives import EVALUATION_SAMPLES as EVALUATION_SAMPLES
from ._objectives import AbstractObjective as AbstractObjective
from ._objectives import CaCt as CaCt
from ._objectives import ExpectedResidual as ExpectedResidual
from ._objectives import MaxCaCt as MaxCaCt
from ._objectives import MaxResidual as MaxResidual
from ._objectives import Residual as Residual
from ._objectives import RmsAcceleration as RmsAcceleration
from ._objectives import peak_loads as peak_loads
from ._optimise import DEFAULT_STEPS as DEFAULT_STEPS
from ._optimise import MAX_KNOTS as MAX_KNOTS
from ._optimise import MAX_STEPS as MAX_STEPS
from ._optimise import DesignNotImproved as DesignNotImproved
from ._optimise import DesignResult as DesignResult
from ._optimise import design as design
from ._optimise import linear_maps as linear_maps
from ._residual import dense_tau as dense_tau
from ._residual import percentage_vibration as percentage_vibration
from ._residual import quadrature as quadrature
from ._residual import residual as residual
from ._residual import residual_amplitude as residual_amplitude
from ._residual import residual_kernel as residual_kernel
from ._residual import vibration_band as vibration_band
