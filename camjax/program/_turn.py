"""A program's lift over one turn: the one object every reader of the motion asks.

The grid's sampler, the kinematics and geometry (``Program.lift``), the groove's motion law
(``TurnLaw``), the drive tables and the JAX displacement of ``camjax.geometry`` all read
the turn through ``Turn.locate`` (which segment an angle belongs to, and its local time)
and ``Turn.segment_jet`` (a segment's lift and derivatives at its local time).  A join is
decided here once: an angle within ``JOIN_TOLERANCE_DEG`` of a join *is* the join, read
at the end of the segment before it or the start of the one after it (``side``); every
other angle belongs to the segment that starts at or before it, at a local time clipped
to ``[0, 1]`` (so a rounding never reads the dwell beyond a law's end).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

JOIN_TOLERANCE_DEG = 1e-9
"""Angles closer than this to a join are the join (and segment angles must close the turn
to within it)."""

SIDES = ("before", "after")


def _traced(*values) -> bool:
    return any(isinstance(x, jax.core.Tracer) for x in values)


def _check_side(side: str) -> None:
    if side not in SIDES:
        raise ValueError(f"side must be 'before' or 'after', got {side!r}")


class Turn(eqx.Module):
    """The lift (mm) over the turn's cam angle (degrees), segment by segment.

    Attributes:
        laws: each segment's motion law, ``None`` for a dwell (JAX leaves: a law may be
            replaced by a traced one, as a design does).
        start_deg, angle_deg: where each segment starts and how long it lasts.
        lift_mm, start_lift_mm: each segment's lift and the lift at its start.
    """

    laws: tuple
    start_deg: np.ndarray
    angle_deg: np.ndarray
    lift_mm: np.ndarray
    start_lift_mm: np.ndarray

    @classmethod
    def of(cls, segments) -> Turn:
        """The turn of a program's segments (``Program.segments``)."""
        angle = np.array([s.angle_deg for s in segments], dtype=float)
        lift = np.array([s.lift_mm for s in segments], dtype=float)
        return cls(
            laws=tuple(s.law if s.moving else None for s in segments),
            start_deg=np.concatenate([[0.0], np.cumsum(angle)[:-1]]),
            angle_deg=angle,
            lift_mm=lift,
            start_lift_mm=np.concatenate([[0.0], np.cumsum(lift)[:-1]]),
        )

    @property
    def segments(self) -> int:
        return len(self.laws)

    def locate(self, theta_deg, side: str = "after"):
        """``(segment index, local time in [0, 1])`` of each cam angle (periodic).

        NumPy arrays for concrete angles, JAX arrays when traced.
        """
        _check_side(side)
        traced = _traced(theta_deg, self.start_deg, self.angle_deg)
        xp = jnp if traced else np
        theta = xp.asarray(theta_deg, dtype=float)
        if not traced and not np.all(np.isfinite(theta)):
            raise ValueError(f"cam angles must be finite, got {theta[~np.isfinite(theta)].ravel()[0]!r}")
        theta = xp.mod(theta, 360.0)
        n = self.segments
        starts, widths = xp.asarray(self.start_deg), xp.asarray(self.angle_deg)
        bounds = xp.concatenate([starts, xp.full((1,), 360.0)])
        above = xp.clip(xp.searchsorted(bounds, theta), 1, n)  # the nearest join: above or below
        nearest = xp.where(bounds[above] - theta < theta - bounds[above - 1], above, above - 1)
        at_join = xp.abs(theta - bounds[nearest]) <= JOIN_TOLERANCE_DEG
        index = xp.clip(xp.searchsorted(bounds, theta, side="right") - 1, 0, n - 1)
        index = xp.where(at_join, (nearest - 1) % n if side == "before" else nearest % n, index)
        raw = (theta - starts[index]) / widths[index]
        tau = xp.where(at_join, 1.0 if side == "before" else 0.0, xp.clip(raw, 0.0, 1.0))
        if traced:  # the value snapped to the segment, the derivative d tau / d theta kept
            tau = raw + jax.lax.stop_gradient(tau - raw)
        return index, tau

    def segment_jet(self, k: int, tau, law=None):
        """``(y, y', y'', y''')`` in segment ``k`` at local times ``tau`` in ``[0, 1]``: mm
        and mm per degree of cam angle to the power 1, 2, 3.  ``law`` (same breakpoints)
        replaces the segment's own, as a design's traced law does."""
        law = self.laws[k] if law is None else law
        y0 = self.start_lift_mm[k]
        if law is None:
            zero = (jnp if _traced(tau, y0) else np).zeros_like(tau, dtype=float)
            return y0 + zero, zero, zero, zero
        s, v, a, j = law.evaluate(tau)
        if not _traced(s, v, a, j, self.lift_mm, self.angle_deg):  # NumPy: no eager JAX ops
            s, v, a, j = (np.asarray(x) for x in (s, v, a, j))
        h, beta = self.lift_mm[k], self.angle_deg[k]
        return y0 + h * s, h * v / beta, h * a / beta**2, h * j / beta**3

    def jet(self, theta_deg, side: str = "after"):
        """``(y, y', y'', y''')`` at cam angles ``theta_deg`` (periodic): mm and mm per
        degree^k; at a join, the derivatives of the segment on ``side`` of it.

        NumPy arrays for concrete input (each segment evaluated at its own angles only);
        JAX arrays when traced (every segment evaluated, the angle's own selected).
        """
        index, tau = self.locate(theta_deg, side)
        if isinstance(index, np.ndarray) and not _traced(*jax.tree.leaves(self)):
            out = [np.zeros(index.shape) for _ in range(4)]
            for k in range(self.segments):
                inside = index == k
                if inside.any():
                    for column, values in zip(out, self.segment_jet(k, tau[inside])):
                        column[inside] = np.asarray(values)
            return tuple(out)
        index, tau = jnp.asarray(index), jnp.asarray(tau)
        out = [jnp.zeros(index.shape) for _ in range(4)]
        for k in range(self.segments):
            mine = index == k
            out = [jnp.where(mine, values, column) for column, values in zip(out, self.segment_jet(k, tau))]
        return tuple(out)

    def breakpoints_deg(self) -> np.ndarray:
        """Every segment's start and end and its law's breakpoints, in degrees (sorted)."""
        points = set(np.append(self.start_deg, 360.0).tolist())
        for law, start, angle in zip(self.laws, self.start_deg, self.angle_deg):
            inner = law.breakpoints() if law is not None else ()
            if isinstance(inner, tuple):
                points.update(float(start + angle * b) for b in inner)
        return np.array(sorted(points))
