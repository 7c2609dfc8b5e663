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

import dataclasses
from typing import ClassVar

import diffrax
import jax
import jax.numpy as jnp

from .. import checks
from ..checks import require
from ..errors import promote
from ..metrics import refined_peak
from ..solvers import solver
from ._base import AbstractModel, Metrics, Options, Response
from ._hybrid import sample_times


@dataclasses.dataclass(frozen=True)
class TwoMassOptions(Options):
    """Static settings of a two-mass solution.

    Attributes:
        method: ``"dopri8"`` or ``"kvaerno5"`` (implicit, for a very stiff input shaft).
        dwell: dwell after the rise, in motion periods.
        samples: equal sample steps over the rise (the dwell is sampled as finely); Ct is
            refined between them.
        rtol, atol, max_steps: diffrax tolerances and step limit.
    """

    method: str = "dopri8"
    samples: int = 2048
    rtol: float = 1e-10
    atol: float = 1e-12
    max_steps: int = 200_000

    def checked(self, max_period_ratio: float) -> TwoMassOptions:
        base = super().checked(max_period_ratio)
        require(int(self.samples) >= 8, f"samples must be at least 8, got {self.samples}")
        require(int(self.max_steps) >= 1, f"max_steps must be positive, got {self.max_steps}")
        return base


class TwoMass(AbstractModel):
    """Camshaft on an elastic input shaft, driving the payload through the output transmission.

    Attributes:
        period_ratio: output period ratio ``n = T sqrt(S/W) / (2 pi)`` (> 0).
        stiffness_ratio: ``k = R beta^2 / (S h^2)``, input over output stiffness (> 0).
        inertia_ratio: ``m = W h^2 / (I beta^2)``, referred payload over camshaft inertia (>= 0).
    """

    period_ratio: float | jax.Array
    stiffness_ratio: float | jax.Array
    inertia_ratio: float | jax.Array
    methods: ClassVar[tuple[str, ...]] = ("dopri8", "kvaerno5")
    options_type: ClassVar[type[Options]] = TwoMassOptions

    def checked_parameters(self) -> dict:
        return {
            "period_ratio": checks.positive(self.period_ratio, "period ratio"),
            "stiffness_ratio": checks.positive(self.stiffness_ratio, "stiffness_ratio"),
            "inertia_ratio": checks.non_negative(self.inertia_ratio, "inertia_ratio"),
        }

    @property
    def input_omega(self):
        """Camshaft natural frequency with the motor end held, ``w_i = w sqrt(k m)``."""
        return self.omega * jnp.sqrt(self.stiffness_ratio * self.inertia_ratio)

    def response(self, law, options: TwoMassOptions) -> TwoMassResponse:
        model = self.validated()
        ts = sample_times(options.samples, options.dwell)
        w = model.omega
        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(_vector_field),
            solver(options.method),
            t0=0.0,
            t1=ts[-1],
            dt0=None,
            y0=tuple(jnp.zeros(()) for _ in range(4)),
            args=(law, model),
            saveat=diffrax.SaveAt(ts=ts),
            stepsize_controller=diffrax.PIDController(rtol=options.rtol, atol=options.atol),
            max_steps=options.max_steps,
            throw=False,
        )
        phi, dphi, e, de = sol.ys
        acc = w**2 * e
        # The law's breakpoints fall at camshaft angles, not at sample times: a node lies
        # inside a piece (almost surely), and both of its sides see the same derivatives.
        derivatives = _acceleration_derivatives(law, model, ts, (phi, dphi, e, de))
        widths = jnp.diff(ts)
        rise = ts <= 1.0
        in_motion = refined_peak(
            jnp.where(rise, acc, 0.0), jnp.where(rise[1:], widths, 0.0), derivatives[:-1], derivatives[1:]
        )
        peak = refined_peak(acc, widths, derivatives[:-1], derivatives[1:])
        i_end = options.samples  # tau = 1: the output transmission is undamped
        residual = w**2 * jnp.sqrt(e[i_end] ** 2 + (de[i_end] / w) ** 2)
        return TwoMassResponse(
            tau=ts,
            payload_acceleration=acc,
            metrics=Metrics(peak / law.Ca, residual / law.Ca, in_motion / law.Ca),
            result=promote(sol.result),
            stats={"steps": jnp.asarray(sol.stats["num_steps"])},
            twist=phi,
            twist_rate=dphi,
            deflection=e,
            deflection_rate=de,
        )


def _vector_field(t, y, args):
    law, model = args
    phi, dphi, e, de = y
    w2 = model.omega**2
    _, v, a, _ = law.evaluate(t - phi)
    ddtheta = model.input_omega**2 * phi - model.inertia_ratio * w2 * e * v
    dde = a * (1.0 - dphi) ** 2 + v * ddtheta - w2 * e
    return dphi, -ddtheta, de, dde


class TwoMassResponse(Response):
    """Time histories of the two-mass model (adds to ``camjax.models.Response``).

    Attributes:
        twist: input-shaft twist ``phi = tau - theta`` (camshaft lag, units of the rise angle).
        twist_rate: ``phi'``.
        deflection: output deflection ``e = s(theta) - x`` (units of stroke).
        deflection_rate: ``e'``.
    """

    twist: jax.Array
    twist_rate: jax.Array
    deflection: jax.Array
    deflection_rate: jax.Array


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
