"""Two-mass model: an elastic input drive (camshaft) and the output transmission (payload).

A motor turns at constant speed and drives the camshaft (inertia ``I``) through an input
shaft of torsional rigidity ``R``; the cam lifts the follower by ``h s(theta)``, where
``theta`` is the camshaft's actual angle over the rise angle ``beta`` (``theta = tau``
for a rigid input); the payload (mass ``W``) follows through the output transmission of
stiffness ``S``.  With the twist ``phi = tau - theta`` and the output deflection
``e = s(theta) - x``, the normalised equations are

    theta'' = w_i^2 phi - m w^2 e v(theta)                (camshaft; the cam's reaction)
    x''     = w^2 e                                       (payload)

with ``w = 2 pi n`` (``n`` the output period ratio, as in the SDOF),
``k = R beta^2 / (S h^2)`` the input-to-output stiffness ratio (the input rigidity
referred to the follower by the cam's nominal ratio ``h / beta``),
``m = W h^2 / (I beta^2)`` the payload's inertia referred to the camshaft, over the
camshaft's, and ``w_i^2 = k m w^2`` (the camshaft's own frequency, motor end held).
The cam's ratio ``v(theta)`` varies over the rise, so the model is nonlinear in
``theta``: no matrix exponential propagates it exactly, and diffrax integrates it.  As
``k -> inf`` (or ``m -> 0``) the camshaft turns rigidly and the model becomes the SDOF.
"""

from __future__ import annotations

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..laws import AbstractMotionLaw
from ..laws._base import is_concrete, require
from ..metrics import refined_peak
from ._spring_mass import check_period_ratios


class TwoMass(eqx.Module):
    """Camshaft on an elastic input shaft, driving the payload through the output transmission.

    Attributes:
        period_ratio: output period ratio ``n = T sqrt(S/W) / (2 pi)`` (> 0).
        stiffness_ratio: ``k = R beta^2 / (S h^2)``, input over output stiffness (> 0).
        inertia_ratio: ``m = W h^2 / (I beta^2)``, referred payload over camshaft inertia (>= 0).
    """

    period_ratio: float | jax.Array
    stiffness_ratio: float | jax.Array
    inertia_ratio: float | jax.Array

    def __check_init__(self):
        if is_concrete(self.period_ratio, self.stiffness_ratio, self.inertia_ratio):
            if jnp.ndim(self.period_ratio) == 0:
                check_period_ratios(self.period_ratio)
            if jnp.ndim(self.stiffness_ratio) == 0:
                k = float(self.stiffness_ratio)
                require(np.isfinite(k) and k > 0, f"stiffness_ratio must be positive and finite, got {k}")
            if jnp.ndim(self.inertia_ratio) == 0:
                m = float(self.inertia_ratio)
                require(np.isfinite(m) and m >= 0, f"inertia_ratio must be >= 0 and finite, got {m}")

    @property
    def omega(self):
        """Output natural frequency ``w = 2 pi n`` (radians per motion period)."""
        return 2 * jnp.pi * self.period_ratio

    @property
    def input_omega(self):
        """Camshaft natural frequency with the motor end held, ``w_i = w sqrt(k m)``."""
        return self.omega * jnp.sqrt(self.stiffness_ratio * self.inertia_ratio)


def _vector_field(t, y, args):
    law, model = args
    phi, dphi, e, de = y
    w2 = model.omega**2
    _, v, a, _ = law.evaluate(t - phi)
    ddtheta = model.input_omega**2 * phi - model.inertia_ratio * w2 * e * v
    dde = a * (1.0 - dphi) ** 2 + v * ddtheta - w2 * e
    return dphi, -ddtheta, de, dde


class TwoMassResponse(eqx.Module):
    """Time histories and metrics of the two-mass model (metrics in units of Ca).

    Attributes:
        tau: sample times over the rise and the dwell.
        twist: input-shaft twist ``phi = tau - theta`` (camshaft lag, units of the rise angle).
        twist_rate: ``phi'``.
        deflection: output deflection ``e = s(theta) - x`` (units of stroke).
        deflection_rate: ``e'``.
        response_acceleration: payload acceleration ``x'' = w^2 e``.
        ct: max ``|x''|`` over Ca, refined between samples (``camjax.metrics.refined_peak``).
        residual: amplitude of the payload vibration at the end of the dwell, over Ca.
        result: diffrax result.
        steps: solver steps taken.
    """

    tau: jax.Array
    twist: jax.Array
    twist_rate: jax.Array
    deflection: jax.Array
    deflection_rate: jax.Array
    response_acceleration: jax.Array
    ct: jax.Array
    residual: jax.Array
    result: diffrax.RESULTS
    steps: jax.Array


def _acceleration_derivatives(law, model, t, y):
    """First three time derivatives of the payload acceleration ``w^2 e`` at ``(t, y)``.

    ``e''`` is the vector field's; its derivative along the motion uses the law's jerk at
    the camshaft angle and ``theta''' = w_i^2 phi' - m w^2 (e' v + e a theta')``.
    """
    phi, dphi, e, de = y
    w2 = model.omega**2
    _, v, a, j = law.evaluate(t - phi)
    dtheta = 1.0 - dphi
    ddtheta = model.input_omega**2 * phi - model.inertia_ratio * w2 * e * v
    dddtheta = model.input_omega**2 * dphi - model.inertia_ratio * w2 * (de * v + e * a * dtheta)
    dde = a * dtheta**2 + v * ddtheta - w2 * e
    ddde = j * dtheta**3 + 3 * a * dtheta * ddtheta + v * dddtheta - w2 * de
    return jnp.stack([w2 * de, w2 * dde, w2 * ddde], axis=-1)


def two_mass_response(
    law: AbstractMotionLaw,
    model: TwoMass,
    *,
    dwell: float = 1.0,
    samples: int = 4096,
    solver: str = "dopri8",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    max_steps: int = 200_000,
) -> TwoMassResponse:
    """Integrate the two-mass model over the rise and ``dwell`` motion periods.

    Jittable and vmappable over the model's leaves.  ``solver`` is ``"dopri8"`` or
    ``"kvaerno5"`` (implicit, for a very stiff input shaft).  ``samples`` equal steps
    sample the response; Ct is refined between them by ``camjax.metrics.refined_peak``
    (septic Hermite interpolation from the acceleration's first three derivatives).
    """
    model = jax.tree.map(jnp.asarray, model)  # traced leaves: one compilation for all values
    ts = jnp.linspace(0.0, 1.0 + dwell, samples + 1)
    w = model.omega
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(_vector_field),
        {"dopri8": diffrax.Dopri8, "kvaerno5": diffrax.Kvaerno5}[solver](),
        t0=0.0,
        t1=1.0 + dwell,
        dt0=None,
        y0=tuple(jnp.zeros(()) for _ in range(4)),
        args=(law, model),
        saveat=diffrax.SaveAt(ts=ts),
        stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol),
        max_steps=max_steps,
        throw=False,
    )
    phi, dphi, e, de = sol.ys
    acc = w**2 * e

    # The law's breakpoints fall at camshaft angles, not at sample times: a node lies
    # inside a piece (almost surely), and both of its sides see the same derivatives.
    derivatives = _acceleration_derivatives(law, model, ts, (phi, dphi, e, de))

    residual = w**2 * jnp.sqrt(e[-1] ** 2 + (de[-1] / w) ** 2)
    return TwoMassResponse(
        tau=ts,
        twist=phi,
        twist_rate=dphi,
        deflection=e,
        deflection_rate=de,
        response_acceleration=acc,
        ct=refined_peak(acc, jnp.diff(ts), derivatives[:-1], derivatives[1:]) / law.Ca,
        residual=residual / law.Ca,
        result=sol.result,
        steps=sol.stats["num_steps"],
    )


@eqx.filter_jit
def _batch(law, period_ratio, stiffness_ratio, inertia_ratio, options):
    def one(n):
        r = two_mass_response(law, TwoMass(n, stiffness_ratio, inertia_ratio), **dict(options))
        return r.ct, r.residual, r.result

    return jax.vmap(one)(period_ratio)


def two_mass_ct_curve(
    law: AbstractMotionLaw,
    period_ratios,
    stiffness_ratio: float,
    inertia_ratio: float,
    **options,
) -> tuple[np.ndarray, np.ndarray]:
    """``(ct, residual)`` over ``period_ratios`` in one vmapped call (units of Ca).

    ``options`` as :func:`two_mass_response`.  Raises ``SolverError`` if any member fails.
    """
    from ..propagation._response import raise_on_failure

    n = check_period_ratios(period_ratios)
    TwoMass(1.0, float(stiffness_ratio), float(inertia_ratio))  # validates the ratios
    ct, residual, result = _batch(
        law,
        jnp.asarray(n),
        jnp.asarray(float(stiffness_ratio)),
        jnp.asarray(float(inertia_ratio)),
        tuple(sorted(options.items())),
    )
    raise_on_failure(result, (ct, residual), n, options.get("solver", "dopri8"))
    return np.asarray(ct), np.asarray(residual)
