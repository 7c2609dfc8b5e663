"""Motion programs over a full cam turn: rise - dwell - fall - dwell in cam angle.

A program maps the cam angle ``theta`` (radians, periodic in ``2 pi``) to the follower
displacement ``lift * s(theta)`` and its derivatives with respect to ``theta``.  Any
motion law can drive the rise and the fall; the fall is the mirror ``1 - s``.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import ArrayLike, Breakpoints, LawValues
from ..checks import is_concrete, require
from ._base import AbstractMotionLaw, static_breakpoints

_QUARTER = math.pi / 2


class RiseDwellFall(eqx.Module):
    """Rise over ``rise_angle``, dwell, fall over ``fall_angle``, dwell to ``2 pi``.

    ``lift`` is the total rise in the follower's unit (radians of swing for a swinging
    follower, length for a translating one).  The angles are static (they fix where the
    forcing jumps); the laws and the lift are differentiable leaves.
    """

    rise: AbstractMotionLaw
    fall: AbstractMotionLaw
    lift: jax.Array | float
    rise_angle: float = eqx.field(static=True, default=_QUARTER)
    dwell_angle: float = eqx.field(static=True, default=_QUARTER)
    fall_angle: float = eqx.field(static=True, default=_QUARTER)

    def __check_init__(self):
        angles = (self.rise_angle, self.dwell_angle, self.fall_angle)
        require(all(a > 0 for a in (self.rise_angle, self.fall_angle)), "rise_angle and fall_angle must be positive")
        require(self.dwell_angle >= 0, "dwell_angle must be non-negative")
        require(sum(angles) <= 2 * math.pi + 1e-12, f"rise + dwell + fall = {sum(angles):.6g} rad exceeds a turn")
        if is_concrete(self.lift):
            require(np.all(np.isfinite(np.asarray(self.lift))), "lift must be finite")

    @property
    def fall_start(self) -> float:
        return self.rise_angle + self.dwell_angle

    def evaluate(self, theta: ArrayLike) -> LawValues:
        """``(y, dy/dtheta, d2y/dtheta2, d3y/dtheta3)`` with ``y = lift * s``, periodic in theta."""
        theta = jnp.mod(jnp.asarray(theta, dtype=float), 2 * math.pi)
        rise = self.rise.evaluate(theta / self.rise_angle)
        fall = self.fall.evaluate((theta - self.fall_start) / self.fall_angle)
        out = []
        for k, (r, f) in enumerate(zip(rise, fall)):
            out.append(self.lift * (r / self.rise_angle**k - f / self.fall_angle**k))
        return tuple(out)

    def displacement(self, theta: ArrayLike) -> jax.Array:
        return self.evaluate(theta)[0]

    def jump_angles(self) -> tuple[float, ...] | jax.Array:
        """Cam angles in ``[0, 2 pi)`` where the acceleration or jerk may be non-smooth.

        A sorted tuple of floats when both laws' breakpoints are fixed; a sorted array
        (entries may repeat) when either law's are traced (an SCCA law passed into jit).
        """
        points = [0.0, self.rise_angle, self.fall_start, self.fall_start + self.fall_angle]
        traced = []
        for law, start, width in ((self.rise, 0.0, self.rise_angle), (self.fall, self.fall_start, self.fall_angle)):
            bps = law.breakpoints()
            if isinstance(bps, tuple):
                points += [start + width * b for b in bps]
            else:
                traced.append(start + width * jnp.asarray(bps))
        fixed = tuple(sorted({round(p, 15) for p in points if p < 2 * math.pi}))
        if not traced:
            return fixed
        return jnp.sort(jnp.concatenate([jnp.asarray(fixed), *traced]))


class LawBank(AbstractMotionLaw):
    """One of several laws, picked by an integer ``index`` leaf.

    Laws of different types have different pytree structures and cannot be stacked; a
    bank has one structure whatever the index, so ``jax.vmap`` over ``index`` runs
    several laws through one compiled computation (every law is evaluated, one kept).
    """

    laws: tuple[AbstractMotionLaw, ...]
    index: jax.Array | int = 0

    def __check_init__(self):
        require(len(self.laws) > 0, "LawBank needs at least one law")
        if is_concrete(self.index):
            require(0 <= int(self.index) < len(self.laws), f"index {self.index} outside 0..{len(self.laws) - 1}")

    def _pick(self, values):
        return jnp.choose(jnp.asarray(self.index), jnp.stack(jnp.broadcast_arrays(*values)), mode="clip")

    @property
    def name(self) -> str:
        return "bank(" + ",".join(law.name for law in self.laws) + ")"

    def rise(self, tau) -> LawValues:
        each = [law.rise(tau) for law in self.laws]
        return tuple(self._pick([e[k] for e in each]) for k in range(4))

    def breakpoints(self) -> Breakpoints:
        """Every banked law's breakpoints: a tuple if all are fixed, else a sorted array."""
        points, traced = [], []
        for law in self.laws:
            bps = law.breakpoints()
            if isinstance(bps, tuple):
                points += list(bps)
            else:
                traced.append(jnp.asarray(bps))
        if not traced:
            return static_breakpoints(points)
        return jnp.sort(jnp.concatenate([jnp.asarray(points, dtype=float), *traced]))

    @property
    def Cv(self):
        return self._pick([law.Cv for law in self.laws])

    @property
    def Ca(self):
        return self._pick([law.Ca for law in self.laws])

    @property
    def Cj(self):
        return self._pick([law.Cj for law in self.laws])
