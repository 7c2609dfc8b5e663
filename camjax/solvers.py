"""The diffrax solvers camjax offers, by name (floor 1: nothing here imports camjax).

The tables name diffrax's classes rather than hold them, so that importing camjax's exact
paths does not import diffrax; ``solver(name)`` makes one.  Fixed-step explicit solvers
carry their stability polynomial, which lets a solution path refuse a step count at which
the method's numerical free vibration grows (``free_vibration_growth``); adaptive solvers
bound it by error control.
"""

from __future__ import annotations

import jax.numpy as jnp

FIXED_STEP_SOLVERS = {
    "euler": "Euler",
    "heun": "Heun",
    "midpoint": "Midpoint",
    "ralston": "Ralston",
}
ADAPTIVE_SOLVERS = {
    "bosh3": "Bosh3",
    "tsit5": "Tsit5",
    "dopri5": "Dopri5",
    "dopri8": "Dopri8",
    "kvaerno3": "Kvaerno3",
    "kvaerno4": "Kvaerno4",
    "kvaerno5": "Kvaerno5",
}
SOLVERS = {**FIXED_STEP_SOLVERS, **ADAPTIVE_SOLVERS}
"""camjax's name of each solver -> the name of its diffrax class."""


def solver(name: str):
    """A new diffrax solver of ``SOLVERS`` by camjax's name (``"tsit5"``, ``"heun"``, ...)."""
    import diffrax

    return getattr(diffrax, SOLVERS[check_method(name, SOLVERS)])()

# Stability polynomials R(z) (coefficients of z^0, z^1, ...): one step maps y to R(h J) y.
STABILITY_POLYNOMIALS = {
    "euler": (1.0, 1.0),
    "heun": (1.0, 1.0, 0.5),
    "midpoint": (1.0, 1.0, 0.5),
    "ralston": (1.0, 1.0, 0.5),
}
MAX_FREE_VIBRATION_GROWTH = 1.1
"""Largest growth of a fixed-step solver's free vibration over the rise that is accepted."""


def check_method(method: str, valid) -> str:
    """Canonical (lower-case) method name if it is in ``valid``, else a ``ValueError``."""
    key = str(method).strip().lower()
    if key not in valid:
        raise ValueError(f"unknown method {method!r}; valid methods: {', '.join(valid)}")
    return key


def free_vibration_growth(method: str, omega, zeta, steps: int):
    """Factor by which ``method``'s numerical free vibration grows over ``steps`` steps.

    ``|R(lambda / steps)|^steps`` for the fixed-step explicit solvers, with
    ``lambda = -zeta w + i w sqrt(1 - zeta^2)`` (the exact factor, ``exp(-zeta w)``, is at
    most 1); 1 for adaptive solvers, whose error control bounds it.
    """
    if method not in STABILITY_POLYNOMIALS:
        return jnp.ones_like(jnp.asarray(omega, dtype=float))
    z = (-zeta * omega + 1j * omega * jnp.sqrt(1.0 - zeta**2)) / steps
    amplification = sum(c * z**k for k, c in enumerate(STABILITY_POLYNOMIALS[method]))
    return jnp.exp(steps * jnp.log(jnp.abs(amplification)))
