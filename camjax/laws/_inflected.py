"""Asymmetric rises: a symmetric law with its inflection point moved from 1/2 to ``L``.

The industrial inclined sine, modified sine and modified trapezoid take such a point.  For a
base law point-symmetric about (1/2, 1/2) (every classic law), the rise keeps the base's
acceleration pulse on ``[0, L]`` time-scaled by ``2L`` and its braking pulse on ``[L, 1]``
time-scaled by ``2(1 - L)``, with amplitudes ``1/(2L)`` and ``1/(2(1 - L))`` times the base's:

    tau <= L:  s = 2L s_b(tau/(2L)),                  v = v_b(u),  a = a_b(u)/(2L)
    tau >= L:  s = 1 - 2(1-L)(1 - s_b(u)),  u = 1 - (1 - tau)/(2(1-L)),  a = a_b(u)/(2(1-L))

These amplitudes are the ones that give ``v(1) = 0`` and ``s(1) = 1``: the pulses' areas
(velocity gained and lost) are equal, ``v(L) = v_b(1/2)`` from both sides and
``s(L) = L``.  So ``v`` is continuous, and ``a`` is wherever the base's is (``a_b(1/2) = 0``;
the parabolic law's step stays a step).  The jerk steps at ``L`` unless ``L = 1/2``.
Cv = the base's; Ca = Ca_b / (2 min(L, 1-L)); Cj = Cj_b / (4 min(L, 1-L)^2).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import Breakpoints, LawValues
from ..checks import is_concrete, require
from ._base import AbstractMotionLaw, float_leaf, number_text, static_breakpoints


def _symmetric(law: AbstractMotionLaw) -> bool:
    """``s(1 - tau) = 1 - s(tau)`` at a few points (concrete laws)."""
    tau = np.array([0.1, 0.23, 0.37, 0.45])
    with jax.ensure_compile_time_eval():  # concrete, even when built inside a trace
        s = np.asarray(law.s(np.concatenate([tau, 1 - tau])))
    return bool(np.max(np.abs(s[: tau.size] + s[tau.size:] - 1.0)) <= 1e-9)


class Inflected(AbstractMotionLaw):
    """``base`` (point-symmetric) with its inflection point at ``inflection`` in (0, 1).

    ``inflection = 1/2`` is the base law itself.  Named ``NAME-asym:L`` (``get`` rebuilds it
    for a base with a plain name, e.g. ``modified-sine-asym:0.4``).  The inflection is a
    differentiable leaf.
    """

    base: AbstractMotionLaw
    inflection: object

    def __init__(self, base: AbstractMotionLaw, inflection):
        if not isinstance(base, AbstractMotionLaw):
            raise TypeError(f"Inflected needs a motion law as its base, got {type(base).__name__}")
        self.base = base
        self.inflection = float_leaf(inflection, "the inflection point")

    def __check_init__(self):
        require(jnp.ndim(self.inflection) == 0, "the inflection point must be one number")
        if is_concrete(self.inflection):
            L = float(self.inflection)
            require(0.0 < L < 1.0, f"law {self.base.name}-asym:L: the inflection point L must be in (0, 1), "
                    f"got {L:g}")
        if is_concrete(self.base):
            require(_symmetric(self.base), f"law {self.base.name}-asym:L: the base law must be point-symmetric "
                    "about (1/2, 1/2) (every classic law is)")

    @property
    def name(self) -> str:
        if not is_concrete(self.inflection):
            return f"{self.base.name}-asym"
        return f"{self.base.name}-asym:{number_text(self.inflection)}"

    def rise(self, tau) -> LawValues:
        L = self.inflection
        first = tau <= L
        u = jnp.where(first, tau / (2 * L), 1.0 - (1.0 - tau) / (2 * (1.0 - L)))
        s, v, a, j = self.base.rise(jnp.clip(u, 0.0, 1.0))
        scale = jnp.where(first, 2 * L, 2 * (1.0 - L))
        s = jnp.where(first, scale * s, 1.0 - scale * (1.0 - s))
        return s, v, a / scale, j / scale**2

    def breakpoints(self) -> Breakpoints:
        points = self.base.breakpoints()
        L = self.inflection

        def moved(b, xp):
            return xp.where(b <= 0.5, 2 * L * b, 1.0 - 2 * (1.0 - L) * (1.0 - b))

        if isinstance(points, tuple) and is_concrete(L):
            return static_breakpoints([*(float(moved(b, np)) for b in points), float(L)])
        points = jnp.asarray(points, dtype=float).reshape(-1)
        return jnp.sort(jnp.concatenate([moved(points, jnp), jnp.reshape(jnp.asarray(L, float), (1,))]))

    def end_state(self):
        ends = self.base.end_state()
        if ends is None or not is_concrete(self.inflection):
            return None
        L = float(self.inflection)
        v0, a0, v1, a1 = ends
        return v0, a0 / (2 * L), v1, a1 / (2 * (1 - L))

    def _shortest(self):
        return 2 * jnp.minimum(self.inflection, 1.0 - self.inflection) if not is_concrete(self.inflection) \
            else 2 * min(float(self.inflection), 1 - float(self.inflection))

    @property
    def Cv(self):
        return self.base.Cv

    @property
    def Ca(self):
        return self.base.Ca / self._shortest()

    @property
    def Cj(self):
        return self.base.Cj / self._shortest() ** 2
