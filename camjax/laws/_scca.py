"""The SCCA family (sine - constant - cosine acceleration) and its named members.

Fractions ``a`` (sine), ``b`` (constant), ``c`` (cosine), ``d = 1 - a - b - c`` (zero) are
totals over the whole rise.  The first half of the acceleration runs a quarter-sine ramp
of width ``a/2`` up to the peak ``A``, a constant ``A`` for ``b/2``, a quarter-cosine fall
of width ``c/2`` back to zero, then zero for ``d/2``; the second half is the point
reflection ``acc(tau) = -acc(1 - tau)``.  ``A`` follows from ``s(1/2) = 1/2``.

The named members (cycloidal, modified sine, ...) are ``SCCA`` values, not types: their
fractions are array leaves like any other SCCA's, so every SCCA law has one pytree
structure and one compiled program serves them all (stacked, or one after another).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from .. import checks
from .._custom_types import Breakpoints, LawValues
from ..checks import is_concrete, require
from ._base import AbstractMotionLaw, float_leaf, static_breakpoints

_PI = math.pi


def _half_rise(tau, a, b, c):
    """``(s, v, acc, jerk)`` of the first half for unit peak acceleration, plus ``s(1/2)``.

    Written with safe divisions so that values and gradients stay finite when a
    fraction is zero (its piece then has zero width and is never selected).
    """
    d = 1.0 - a - b - c
    t1 = a / 2
    t2 = t1 + b / 2
    t3 = t2 + c / 2
    k1 = _PI / jnp.where(a > 0, a, 1.0)
    k3 = _PI / jnp.where(c > 0, c, 1.0)
    # State at the end of each piece (unit peak acceleration).
    v1 = a / _PI
    s1 = a**2 * (1 / (2 * _PI) - 1 / _PI**2)
    v2 = v1 + b / 2
    s2 = s1 + v1 * b / 2 + (b / 2) ** 2 / 2
    v3 = v2 + c / _PI
    s3 = s2 + v2 * c / 2 + c**2 / _PI**2
    s_half = s3 + v3 * d / 2

    u1 = tau
    sine = (
        u1 / k1 - jnp.sin(k1 * u1) / k1**2,
        (1 - jnp.cos(k1 * u1)) / k1,
        jnp.sin(k1 * u1),
        k1 * jnp.cos(k1 * u1),
    )
    u2 = tau - t1
    const = (s1 + v1 * u2 + u2**2 / 2, v1 + u2, jnp.ones_like(tau), jnp.zeros_like(tau))
    u3 = tau - t2
    cosine = (
        s2 + v2 * u3 + (1 - jnp.cos(k3 * u3)) / k3**2,
        v2 + jnp.sin(k3 * u3) / k3,
        jnp.cos(k3 * u3),
        -k3 * jnp.sin(k3 * u3),
    )
    u4 = tau - t3
    zero = (s3 + v3 * u4, v3 * jnp.ones_like(tau), jnp.zeros_like(tau), jnp.zeros_like(tau))

    def pick(i):
        return jnp.where(
            tau < t1, sine[i], jnp.where(tau < t2, const[i], jnp.where(tau < t3, cosine[i], zero[i]))
        )

    return tuple(pick(i) for i in range(4)), s_half, v3


FRACTIONS_RULE = "SCCA fractions must be finite and non-negative with 0 < a + b + c <= 1"


def _require_valid(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> None:
    """``ValueError`` naming the first invalid set of concrete fractions (any shape)."""
    total = a + b + c
    finite = np.isfinite(a) & np.isfinite(b) & np.isfinite(c)
    for ok, rule in (
        (finite, "SCCA fractions must be finite"),
        (np.minimum(np.minimum(a, b), c) >= 0, "SCCA fractions must be non-negative"),
    ):
        if not np.all(ok):
            i = np.flatnonzero(~ok.ravel())[0]
            x, y, z = (float(v.ravel()[i]) for v in (a, b, c))
            require(False, f"{rule}, got a={x}, b={y}, c={z}")
    ok = (total > 0) & (total <= 1 + 1e-12)
    if not np.all(ok):
        bad = float(total.ravel()[np.flatnonzero(~ok.ravel())[0]])
        require(False, f"SCCA fractions must satisfy 0 < a + b + c <= 1, got a + b + c = {bad}")


class SCCA(AbstractMotionLaw):
    """The SCCA law with fractions ``(sine, constant, cosine)``, differentiable leaves.

    ``SCCA(a, b, c)`` takes the sine, constant and cosine fractions of MISSION.md.  Valid
    fractions are non-negative, finite, with ``0 < a + b + c <= 1``.  The fractions are
    stored as float arrays whatever is passed (NumPy for plain numbers), so all SCCA laws
    share compiled programs.
    """

    sine: jax.Array | np.ndarray
    constant: jax.Array | np.ndarray
    cosine: jax.Array | np.ndarray

    def __init__(self, sine, constant, cosine):
        fractions = tuple(float_leaf(x, "SCCA fractions") for x in (sine, constant, cosine))
        if not is_concrete(*fractions):
            # Traced (built inside jit, vmap or grad): the computation that uses the law
            # raises FRACTIONS_RULE when it runs with invalid fractions.  A law built
            # concrete and passed into a compiled function is checked here once, not there.
            a, b, c = fractions
            total = a + b + c
            valid = (jnp.minimum(jnp.minimum(a, b), c) >= 0) & (total > 0) & (total <= 1 + 1e-12)
            fractions = checks.guard(fractions, ~valid, FRACTIONS_RULE)  # NaN fails them all
        self.sine, self.constant, self.cosine = fractions

    def __check_init__(self):
        if is_concrete(self.sine, self.constant, self.cosine):
            a, b, c = (np.asarray(x, dtype=float) for x in self.fractions)
            _require_valid(*np.broadcast_arrays(a, b, c))

    @property
    def fractions(self):
        """``(sine, constant, cosine)``: the fractions a, b, c of MISSION.md."""
        return self.sine, self.constant, self.cosine

    def _concrete_fractions(self) -> tuple[float, float, float] | None:
        if is_concrete(*self.fractions) and jnp.ndim(self.sine) == 0:
            return tuple(float(x) for x in self.fractions)
        return None

    @property
    def name(self) -> str:
        """The member's name (``"cycloidal"``, ...) or ``"scca:A,B,C"`` (``"scca"`` if traced)."""
        fractions = self._concrete_fractions()
        if fractions is None:
            return "scca"
        for member, known in MEMBERS.items():
            if max(abs(x - y) for x, y in zip(fractions, known)) <= 1e-12:
                return member
        return "scca:{:g},{:g},{:g}".format(*fractions)

    @property
    def peak_acceleration(self):
        """The amplitude ``A`` (= Ca) that makes the rise end at ``s = 1``."""
        _, s_half, _ = _half_rise(jnp.zeros(()), *self.fractions)
        return 0.5 / s_half

    def rise(self, tau) -> LawValues:
        first = tau <= 0.5
        m = jnp.where(first, tau, 1.0 - tau)
        (s, v, acc, jerk), s_half, _ = _half_rise(m, *self.fractions)
        amp = 0.5 / s_half
        s = jnp.where(first, amp * s, 1.0 - amp * s)
        acc = jnp.where(first, acc, -acc)
        return s, amp * v, amp * acc, amp * jerk

    def breakpoints(self) -> Breakpoints:
        """Fixed points (a tuple) for concrete fractions, else seven traced points."""
        fractions = self._concrete_fractions()
        if fractions is not None:
            a, b, c = fractions
            half = (a / 2, (a + b) / 2, (a + b + c) / 2)
            return static_breakpoints([*half, 0.5, *(1 - x for x in half)])
        a, b, c = self.fractions
        half = (a / 2, (a + b) / 2, (a + b + c) / 2)
        return jnp.stack([*half, jnp.asarray(0.5), *(1 - x for x in half[::-1])])

    @property
    def Cv(self):
        _, s_half, v_half = _half_rise(jnp.zeros(()), *self.fractions)
        return 0.5 * v_half / s_half

    @property
    def Ca(self):
        return self.peak_acceleration

    @property
    def Cj(self):
        # Quarter-sine ramp peaks at A*pi/a, quarter-cosine fall at A*pi/c; a zero-width
        # ramp or fall means the acceleration steps, so the jerk is an impulse.
        a, _, c = self.fractions
        smooth = (a > 0) & (c > 0)
        width = jnp.minimum(jnp.where(smooth, a, 1.0), jnp.where(smooth, c, 1.0))
        return jnp.where(smooth, self.peak_acceleration * _PI / width, jnp.inf)


AbstractSCCA = SCCA
"""Former base class of the SCCA laws, kept as a name: every SCCA law is an ``SCCA``."""

MEMBERS: dict[str, tuple[float, float, float]] = {
    "cycloidal": (0.5, 0.0, 0.5),
    "modified-sine": (0.25, 0.0, 0.75),
    "modified-trapezoid": (0.25, 0.5, 0.25),
    "harmonic": (0.0, 0.0, 1.0),
    "parabolic": (0.0, 1.0, 0.0),
}
"""Fractions ``(sine, constant, cosine)`` of the named SCCA laws."""


def Cycloidal() -> SCCA:
    """Cycloidal rise, ``s = tau - sin(2 pi tau)/(2 pi)``: SCCA (1/2, 0, 1/2)."""
    return SCCA(*MEMBERS["cycloidal"])


def ModifiedSine() -> SCCA:
    """Modified sine: SCCA (1/4, 0, 3/4); Ca = 4 pi^2/(pi + 4)."""
    return SCCA(*MEMBERS["modified-sine"])


def ModifiedTrapezoid() -> SCCA:
    """Modified trapezoid: SCCA (1/4, 1/2, 1/4); Ca = 8 pi/(pi + 2)."""
    return SCCA(*MEMBERS["modified-trapezoid"])


def SimpleHarmonic() -> SCCA:
    """Simple harmonic motion, ``s = (1 - cos pi tau)/2``: SCCA (0, 0, 1).

    Its acceleration steps from 0 to pi^2/2 at the start and end of the rise.
    """
    return SCCA(*MEMBERS["harmonic"])


def Parabolic() -> SCCA:
    """Constant acceleration and deceleration (parabolic): SCCA (0, 1, 0); Ca = 4."""
    return SCCA(*MEMBERS["parabolic"])
