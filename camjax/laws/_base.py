"""The motion-law interface shared by every law family."""

from __future__ import annotations

import abc
import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import ArrayLike, Breakpoints, LawValues
from .._shapes import power_of_two
from .._traces import exported_jit
from ..checks import is_concrete


def float_leaf(value, what: str = "a law parameter"):
    """A law parameter as a float array leaf.

    Plain numbers and NumPy arrays become a read-only NumPy copy: building, checking and
    naming a law then wait on no device (each wait costs up to a millisecond on a GPU),
    and no array of the caller's can change a checked law afterwards.  Anything holding a
    JAX array or tracer (a list of them too) becomes a float JAX array.
    """
    if any(isinstance(v, jax.Array) for v in jax.tree.leaves(value)):
        return jnp.asarray(value, dtype=float)
    kind = np.asarray(value).dtype.kind if value is not None else "O"
    if kind not in "biuf":
        raise TypeError(f"{what} must be a number or an array of numbers, got {value!r}")
    leaf = np.array(value, dtype=float)
    leaf.setflags(write=False)
    return leaf


class AbstractMotionLaw(eqx.Module):
    """A normalised rise: ``s`` goes from 0 at ``tau = 0`` to 1 at ``tau = 1``.

    Subclasses implement :meth:`rise` on ``[0, 1]``; outside that interval the law
    continues as a dwell (``s = 0`` before, ``s = 1`` after, all derivatives zero), which
    is what the response engine integrates through.  Every method is elementwise in
    ``tau`` (scalar or array), jittable, vmappable and differentiable in the law's
    parameters (its pytree leaves).
    """

    ends_in_reversal: ClassVar[bool] = False
    """True for a law that ends in a reversal (``v = 0``, ``a != 0``) to join its return
    without a dwell (the double harmonic): the rest-to-rest tools refuse it."""

    @property
    @abc.abstractmethod
    def name(self) -> str:
        """Canonical registry name (``camjax.laws.get(law.name)`` rebuilds the law)."""

    @abc.abstractmethod
    def rise(self, tau: jax.Array) -> LawValues:
        """``(s, v, a, j)`` for ``tau`` in ``[0, 1]``."""

    @abc.abstractmethod
    def breakpoints(self) -> Breakpoints:
        """Interior points of ``(0, 1)`` where the acceleration or jerk is not smooth.

        A tuple of Python floats when the points are fixed by the law's type (the grid
        can then place nodes in proportion to piece widths), otherwise a 1-D array of
        fixed length (entries may coincide).
        """

    @property
    @abc.abstractmethod
    def Cv(self) -> jax.Array | float:
        """Peak normalised velocity ``max |ds/dtau|``."""

    @property
    @abc.abstractmethod
    def Ca(self) -> jax.Array | float:
        """Peak normalised acceleration ``max |d2s/dtau2|``."""

    @property
    @abc.abstractmethod
    def Cj(self) -> jax.Array | float:
        """Peak normalised jerk ``max |d3s/dtau3|``; ``inf`` where the acceleration steps."""

    def evaluate(self, tau: ArrayLike) -> LawValues:
        """``(s, v, a, j)`` at ``tau``, with dwells outside ``[0, 1]``."""
        if is_concrete(self, tau):
            # Called eagerly, the formulas would run op by op, and each op compiles its own
            # small program on first use: one program per law type is far quicker, and
            # the points padded to a bucketed count keep it to a few sizes.
            tau = np.asarray(tau, dtype=float)
            flat = tau.ravel()
            padded = np.pad(flat, (0, power_of_two(flat.size) - flat.size), constant_values=0.5)
            out = _compiled_evaluate(self, jnp.asarray(padded))
            if not is_concrete(out):  # concrete inputs inside another trace: staged with it
                return tuple(x[: flat.size].reshape(tau.shape) for x in out)
            return tuple(jnp.asarray(np.asarray(x)[: flat.size].reshape(tau.shape)) for x in out)
        return self._evaluate(jnp.asarray(tau, dtype=float))

    def _evaluate(self, tau: jax.Array) -> LawValues:
        inside = (tau >= 0.0) & (tau <= 1.0)
        s, v, a, j = self.rise(jnp.clip(tau, 0.0, 1.0))
        s = jnp.where(inside, s, jnp.where(tau > 1.0, 1.0, 0.0))
        v, a, j = (jnp.where(inside, x, 0.0) for x in (v, a, j))
        return s, v, a, j

    def s(self, tau: ArrayLike) -> jax.Array:
        """Normalised displacement."""
        return self.evaluate(tau)[0]

    def v(self, tau: ArrayLike) -> jax.Array:
        """Normalised velocity ``ds/dtau``."""
        return self.evaluate(tau)[1]

    def a(self, tau: ArrayLike) -> jax.Array:
        """Normalised acceleration ``d2s/dtau2``."""
        return self.evaluate(tau)[2]

    def j(self, tau: ArrayLike) -> jax.Array:
        """Normalised jerk ``d3s/dtau3``."""
        return self.evaluate(tau)[3]

    def end_state(self) -> tuple[float, float, float, float] | None:
        """``(v(0), a(0), v(1), a(1))`` as Python floats (one-sided, inside the rise), or
        ``None`` where the law is traced, or where the rest-to-rest check does not apply
        (a program's periodic turn); the rest-to-rest check reads it."""
        if not is_concrete(self):
            return None
        with jax.ensure_compile_time_eval():  # concrete, even when asked inside a trace
            _, v, a, _ = jax.device_get(_compiled_rise(self, np.array([0.0, 1.0])))
        return float(v[0]), float(a[0]), float(v[1]), float(a[1])

    @property
    def Cv_rms(self) -> jax.Array:
        """RMS normalised velocity ``sqrt(int_0^1 v^2 dtau)`` (Gauss-Legendre per smooth piece)."""
        nodes, weights = _piece_quadrature(self)
        return jnp.sqrt(jnp.dot(weights, self.rise(nodes)[1] ** 2))

    @property
    def Ca_rms(self) -> jax.Array:
        """RMS normalised acceleration ``sqrt(int_0^1 a^2 dtau)``: a servo's heating (its RMS
        torque) per ``h/T^2``; never below ``RMS_ACCELERATION_FLOOR`` for a rest-to-rest law."""
        nodes, weights = _piece_quadrature(self)
        return jnp.sqrt(jnp.dot(weights, self.rise(nodes)[2] ** 2))

    @property
    def Cva(self) -> jax.Array:
        """Peak power coefficient ``max |v a|`` (a servo's peak power per ``m h^2/T^3``).

        The largest sample of ``|v a|`` on the quadrature nodes and piece ends, refined by a
        golden-section search between its neighbours (to rounding); differentiable in the
        law through the value at the located point (the location carries no gradient).
        """
        nodes, _ = _piece_quadrature(self)
        tau = jnp.sort(jnp.concatenate([jnp.array([0.0, 1.0]), nodes, _piece_edges(self)]))

        def power(t):
            _, v, a, _ = self.rise(t)
            return jnp.abs(v * a)

        return refined_max(power, tau)

    def rms_coefficients(self) -> dict[str, float]:
        """``{"Cv_rms", "Ca_rms", "Cva"}`` as Python floats: the servo's coefficients beside
        ``peak_coefficients`` (RMS velocity and acceleration, peak ``|v a|``)."""
        values = _compiled_rms(self) if is_concrete(self) else (self.Cv_rms, self.Ca_rms, self.Cva)
        return dict(zip(("Cv_rms", "Ca_rms", "Cva"), map(float, jax.device_get(values))))

    def peak_coefficients(self) -> dict[str, float]:
        """``{"Cv", "Ca", "Cj"}`` as Python floats (``inf`` for an acceleration step)."""
        # One transfer for the three (on a GPU each float() of a device value is a wait).
        peaks = jax.device_get(_compiled_peaks(self)) if is_concrete(self) else (self.Cv, self.Ca, self.Cj)
        return dict(zip(("Cv", "Ca", "Cj"), map(float, peaks)))


class AbstractSearchedPeaksLaw(AbstractMotionLaw):
    """A law whose ``Cv``, ``Ca`` and ``Cj`` come from one search over the order of the
    derivative (splines, boundary polynomials): subclasses write ``peak(order)``."""

    @abc.abstractmethod
    def peak(self, order: int) -> jax.Array | float:
        """``max |d^order s / dtau^order|`` over ``[0, 1]``."""

    @property
    def Cv(self):
        return self.peak(1)

    @property
    def Ca(self):
        return self.peak(2)

    @property
    def Cj(self):
        return self.peak(3)


RMS_ACCELERATION_FLOOR = 2.0 * 3.0**0.5
"""The least ``Ca_rms`` of any rest-to-rest law: ``int a^2`` with ``s(0) = 0``, ``s(1) = 1``,
``v(0) = v(1) = 0`` is least for the cubic ``s = 3 tau^2 - 2 tau^3`` (``a = 6 - 12 tau``,
``int a^2 = 12``), whose acceleration steps at both ends; a law with ``a = 0`` at the ends
approaches it as its jerk grows."""

_GOLDEN = (5.0**0.5 - 1.0) / 2.0
_QUADRATURE_ORDER = 16  # Gauss-Legendre points per panel
_PANELS_PER_UNIT = 16  # panels per unit of tau on a piece with fixed ends
_PANELS_PER_TRACED_PIECE = 8  # panels on each piece whose ends are traced


def _piece_edges(law: AbstractMotionLaw) -> jax.Array:
    points = law.breakpoints()
    if isinstance(points, tuple):
        return jnp.asarray(np.array(points, dtype=float))
    return jnp.clip(jnp.sort(jnp.asarray(points, dtype=float).ravel()), 0.0, 1.0)


def _piece_quadrature(law: AbstractMotionLaw) -> tuple[jax.Array, jax.Array]:
    """Gauss-Legendre nodes and weights over ``[0, 1]`` whose panels never straddle a
    breakpoint: the integral of a smooth function of ``(s, v, a, j)`` to rounding (every
    law is a polynomial or a few sines on each piece).  Traced breakpoints give traced
    nodes, so the integral stays differentiable in them."""
    x, w = np.polynomial.legendre.leggauss(_QUADRATURE_ORDER)
    points = law.breakpoints()
    if isinstance(points, tuple):
        edges = np.array([0.0, *points, 1.0])
        cuts = np.concatenate([np.linspace(lo, hi, max(1, math.ceil((hi - lo) * _PANELS_PER_UNIT)) + 1)[:-1]
                               for lo, hi in zip(edges[:-1], edges[1:])] + [[1.0]])
    else:
        edges = jnp.concatenate([jnp.zeros(1), _piece_edges(law), jnp.ones(1)])
        steps = jnp.linspace(0.0, 1.0, _PANELS_PER_TRACED_PIECE + 1)[:-1]
        cuts = jnp.concatenate([(edges[:-1, None] + (edges[1:] - edges[:-1])[:, None] * steps).ravel(),
                                jnp.ones(1)])
    lo, width = cuts[:-1, None], (cuts[1:] - cuts[:-1])[:, None]
    return (jnp.asarray(lo + width * (x + 1) / 2).ravel(), jnp.asarray(width / 2 * w).ravel())


def refined_max(f, tau: jax.Array) -> jax.Array:
    """``max f`` over ``[0, 1]`` for a non-negative ``f`` (elementwise, jittable): its largest
    sample on the sorted points ``tau``, refined by a golden-section search between that
    sample's neighbours, to rounding where ``f`` has one crest there.  Differentiable in
    what ``f`` closes over through the value at the located point (the location carries no
    gradient: at a maximum the value's derivative does not depend on it)."""
    k = jnp.argmax(f(tau))
    lo = jax.lax.stop_gradient(tau[jnp.maximum(k - 1, 0)])
    hi = jax.lax.stop_gradient(tau[jnp.minimum(k + 1, tau.size - 1)])

    def shrink(_, bracket):
        lo, hi = bracket
        x1 = hi - _GOLDEN * (hi - lo)
        x2 = lo + _GOLDEN * (hi - lo)
        f1, f2 = f(jnp.stack([x1, x2]))
        return jnp.where(f1 >= f2, lo, x1), jnp.where(f1 >= f2, x2, hi)

    lo, hi = jax.lax.fori_loop(0, 80, shrink, (lo, hi))
    return jnp.max(f(jax.lax.stop_gradient(jnp.stack([lo, hi, tau[k]]))))


@eqx.filter_jit
def _compiled_rms(law: AbstractMotionLaw):
    return law.Cv_rms, law.Ca_rms, law.Cva


def _evaluate_law(law: AbstractMotionLaw, tau: jax.Array) -> LawValues:
    return law._evaluate(tau)


_compiled_evaluate = exported_jit(_evaluate_law, "law-evaluate")  # its trace kept for the next process


@eqx.filter_jit
def _compiled_rise(law: AbstractMotionLaw, tau: jax.Array) -> LawValues:
    return law.rise(tau)


@eqx.filter_jit
def _compiled_peaks(law: AbstractMotionLaw):
    return jnp.asarray(law.Cv, float), jnp.asarray(law.Ca, float), jnp.asarray(law.Cj, float)


def static_breakpoints(points) -> tuple[float, ...]:
    """Sorted distinct interior points of ``(0, 1)`` from Python floats."""
    out: list[float] = []
    for p in sorted(float(x) for x in points):
        if 1e-12 < p < 1.0 - 1e-12 and (not out or p - out[-1] > 1e-12):
            out.append(p)
    return tuple(out)


def polynomial_critical_points(coefficients: np.ndarray) -> np.ndarray:
    """The ends of ``[0, 1]`` and every root of the derivative there: where a polynomial
    (ascending coefficients) takes its extremes over ``[0, 1]``.

    The derivative's leading coefficients that are round-off against the others (a
    quintic whose top term cancels) are dropped before its roots are found: kept, they put
    a huge root in the companion matrix and spoil the others.  On ``[0, 1]`` a dropped term
    changes the derivative by at most ``1e-12`` of its largest coefficient.  Every root's
    real part inside ``[0, 1]`` is a candidate, however far off the real axis (a near-double
    root splits into a complex pair): evaluating the polynomial there never exceeds its true
    extreme, and the true extremes are among the candidates.
    """
    d = np.polynomial.polynomial.polyder(np.asarray(coefficients, dtype=float))
    scale = np.max(np.abs(d)) if d.size else 0.0
    if not scale > 0:
        return np.array([0.0, 1.0])
    d = d[: int(np.nonzero(np.abs(d) > 1e-12 * scale)[0][-1]) + 1]
    roots = np.polynomial.polynomial.polyroots(d).real if d.size > 1 else np.array([])
    return np.concatenate([[0.0, 1.0], roots[(roots >= 0.0) & (roots <= 1.0)]])


def polynomial_peaks(coefficients: np.ndarray) -> float:
    """``max |p(tau)|`` over ``[0, 1]`` of a polynomial (ascending coefficients), exactly."""
    poly = np.polynomial.Polynomial(coefficients)
    return float(max(abs(poly(polynomial_critical_points(poly.coef)))))


def number_text(value) -> str:
    """A law parameter as it appears in the law's name: ``%.12g`` where that reads back
    within rounding noise (``-5.5``, not ``-5.499999999999999``), else the exact ``repr``,
    so that ``get(law.name)`` rebuilds the law."""
    x = float(value)
    short = f"{x:.12g}"
    if abs(float(short) - x) <= 4e-15 * abs(x):
        return "0" if short == "-0" else short
    return repr(x)
