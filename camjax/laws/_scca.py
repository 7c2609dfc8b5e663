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
from ._base import AbstractMotionLaw, float_leaf, number_text, static_breakpoints

_PI = math.pi


def _piece_ends(a, b, c):
    """``(s, v)`` at the end of the sine, constant and cosine pieces, and ``s(1/2)``, for
    unit peak acceleration: plain arithmetic, so NumPy fractions stay NumPy."""
    d = 1.0 - a - b - c
    v1 = a / _PI
    s1 = a**2 * (1 / (2 * _PI) - 1 / _PI**2)
    v2 = v1 + b / 2
    s2 = s1 + v1 * b / 2 + (b / 2) ** 2 / 2
    v3 = v2 + c / _PI
    s3 = s2 + v2 * c / 2 + c**2 / _PI**2
    return (s1, v1), (s2, v2), (s3, v3), s3 + v3 * d / 2


def _half_rise(tau, a, b, c):
    """``(s, v, acc, jerk)`` of the first half for unit peak acceleration, plus ``s(1/2)``.

    Written with safe divisions so that values and gradients stay finite when a
    fraction is zero (its piece then has zero width and is never selected).
    """
    t1 = a / 2
    t2 = t1 + b / 2
    t3 = t2 + c / 2
    k1 = _PI / jnp.where(a > 0, a, 1.0)
    k3 = _PI / jnp.where(c > 0, c, 1.0)
    (s1, v1), (s2, v2), (s3, v3), s_half = _piece_ends(a, b, c)

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

    # Without a zero piece (d = 0) the half ends on the cosine piece: the midpoint itself
    # (tau = t3 = 1/2) reads the cosine's end, not the zero piece's (a jerk of 0 there).
    ends_on_cosine = t3 >= 0.5 - 1e-12

    def pick(i):
        return jnp.where(
            tau < t1, sine[i],
            jnp.where(tau < t2, const[i], jnp.where((tau < t3) | ends_on_cosine, cosine[i], zero[i])),
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
        return "scca:" + ",".join(map(number_text, fractions))

    def end_state(self):
        fractions = self._concrete_fractions()
        if fractions is None:
            return super().end_state()
        # v = 0 at both ends by construction; a starts at A only without a sine ramp.
        a0 = 0.5 / _piece_ends(*fractions)[3] if fractions[0] == 0 else 0.0
        return 0.0, a0, 0.0, -a0

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

CV_BASES = ("modified-trapezoid", "modified-sine", "cycloidal")
"""Members with a constant-velocity variant ``NAME-cv:P``: the member's fractions scaled by
``1 - P``, so that a zero-acceleration (constant-velocity) part ``d = P`` spans the middle."""


def constant_velocity_variant(member: str, share) -> SCCA:
    """``member`` (one of ``CV_BASES``) with a constant-velocity part ``d = share`` in
    ``[0, 1)`` in the middle: SCCA of the member's fractions times ``1 - share``."""
    share = float(share)
    require(member in CV_BASES, f"no constant-velocity variant of {member!r}; there are "
            + ", ".join(f"{m}-cv:P" for m in CV_BASES))
    require(0.0 <= share < 1.0, f"law {member}-cv:P: the constant-velocity fraction P must be "
            f"in [0, 1), got {share:g}")
    return SCCA(*((1.0 - share) * x for x in MEMBERS[member]))


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
