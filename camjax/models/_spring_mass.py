"""The linear single-degree-of-freedom (SDOF) model of MISSION.md."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..laws._base import is_concrete, require


def check_period_ratios(period_ratio, *, what: str = "period ratio") -> np.ndarray:
    """Concrete period ratios as a 1-D float array, or a ``ValueError`` naming the fault."""
    n = np.atleast_1d(np.asarray(period_ratio, dtype=float))
    require(n.ndim == 1 and n.size > 0, f"{what} must be a non-empty 1-D list of numbers")
    require(bool(np.all(np.isfinite(n))), f"{what} must be finite (got NaN or inf)")
    if np.any(n <= 0):
        raise ValueError(f"{what} must be positive, got {n[n <= 0][0]:g}")
    return n


def check_damping(damping) -> float:
    """A concrete damping ratio in ``[0, 1)``, or a ``ValueError`` naming the fault."""
    z = float(damping)
    require(math.isfinite(z), f"damping ratio must be finite, got {z}")
    require(
        0.0 <= z < 1.0,
        f"damping ratio must be in [0, 1) (an underdamped payload), got {z:g}",
    )
    return z


class SpringMass(eqx.Module):
    """Payload on an elastic transmission, driven by the cam: the normalised SDOF model.

    ``x'' = w^2 (s - x) + 2 zeta w (s' - x')`` with ``w = 2 pi n``, in normalised time.
    camjax integrates the deflection ``e = s - x`` of the transmission, which obeys
    ``e'' + 2 zeta w e' + w^2 e = a(tau)`` (no cancellation between ``s`` and ``x``).

    Attributes:
        period_ratio: ``n = T f``, motion period over natural period (> 0).
        damping: viscous damping ratio ``zeta`` in ``[0, 1)``.
    """

    period_ratio: float | jax.Array
    damping: float | jax.Array = 0.0

    def __check_init__(self):
        if is_concrete(self.period_ratio, self.damping):
            if jnp.ndim(self.period_ratio) == 0:
                check_period_ratios(self.period_ratio)
            if jnp.ndim(self.damping) == 0:
                check_damping(self.damping)

    @property
    def omega(self):
        """Normalised natural angular frequency ``w = 2 pi n`` (radians per motion period)."""
        return 2 * jnp.pi * self.period_ratio


def natural_frequency(
    *,
    mass: float | None = None,
    stiffness: float | None = None,
    inertia: float | None = None,
    torsional_rigidity: float | None = None,
) -> float:
    """Natural frequency in Hz: ``sqrt(S/W)/(2 pi)`` (linear) or ``sqrt(R/I)/(2 pi)`` (rotary)."""
    linear = mass is not None or stiffness is not None
    rotary = inertia is not None or torsional_rigidity is not None
    require(
        linear != rotary,
        "give either mass and stiffness (linear) or inertia and torsional_rigidity (rotary)",
    )
    pairs = (("mass", mass), ("stiffness", stiffness)) if linear else (
        ("inertia", inertia),
        ("torsional_rigidity", torsional_rigidity),
    )
    for label, value in pairs:
        require(value is not None, f"{label} is missing")
        require(math.isfinite(value) and value > 0, f"{label} must be positive, got {value}")
    inert, stiff = pairs[0][1], pairs[1][1]
    return math.sqrt(stiff / inert) / (2 * math.pi)


def period_ratio(motion_time: float, **physical: float) -> float:
    """Period ratio ``n = T f`` from the motion time ``T`` (s) and physical properties.

    ``period_ratio(0.05, mass=2.0, stiffness=4e6)`` or
    ``period_ratio(0.05, inertia=0.01, torsional_rigidity=2e4)`` (SI units).
    """
    require(
        math.isfinite(motion_time) and motion_time > 0,
        f"motion_time must be positive, got {motion_time}",
    )
    return motion_time * natural_frequency(**physical)
