"""The residual vibration of a chain with contacts (``ChainContacts``): the exact path's
figure (``residual_vibration``) read on a simulated state.

The exact path reports, at the start of each dwell and constant-velocity segment, the
envelope ``sum_j |g_j (xi_j - xi_j,static)|`` of the last body's free vibration: the
state's distance from the segment's particular (static) solution, split over the chain's
modes, each mode's share of the last body's displacement by modulus.  A chain with lash or
a seat has one linear system per set of closed contacts; the one that holds in a dwell is
the set its **static state** closes (``static_contacts``: with the valve lifted the closed
chain, on the base circle with a seat the valve on its seat and the lash open).  The figure
is then the same sum over that system's modes (``contact_residual_mm``) from the simulated
state at the segment's start: where no contact moves (a lash that never opens, no seat), it
is the exact path's number; bodies no closed contact ties to the last one (a tappet between
the cam and an open lash) do not move it and are left out.
"""

from __future__ import annotations

import numpy as np

_FORCE_TOLERANCE = 1e-9
"""A contact of the static state opens where its force is below minus this (relative to the
spring's preload plus 1 N) and closes where its approach passes this (m): a hysteresis that
keeps a contact touching with no force (a zero-lash element on the base circle) from
switching on round-off."""


class _Linear:
    """The chain's linear equations with a given set of closed contacts (SI), over the free
    coordinates ``free`` (a riding body held on the cam is the cam's lift, not free):
    ``M u'' + C u' + K u = F0 + F1 y + Fd y'`` (``y`` the lift at the chain's input, m)."""

    def __init__(self, system, closed: np.ndarray, seated: bool, held: bool):
        s = system
        n = s.Minv.shape[0]
        active = np.where(s.one_sided > 0, closed, 1.0)
        G = np.asarray(s.G)
        k, c = active * s.k, active * s.c
        r = np.asarray(s.seat_row)
        seat = float(seated)
        M = np.linalg.inv(s.Minv)
        K = G.T @ (k[:, None] * G) + s.Ks + seat * float(s.seat_k) * np.outer(r, r)
        C = G.T @ (c[:, None] * G) + s.Cs + seat * float(s.seat_c) * np.outer(r, r)
        F0 = -G.T @ (k * s.d0) + s.load + seat * float(s.seat_k * s.seat_s0) * r
        F1, Fd = -G.T @ (k * s.g_cam), -G.T @ (c * s.g_cam)
        free = np.arange(1 if held else 0, n)
        if held:  # the riding body moves with the cam: its terms join the forcing
            F1, Fd = F1 - K[:, 0], Fd - C[:, 0]
        ix = np.ix_(free, free)
        self.free, self.M, self.K, self.C = free, M[ix], K[ix], C[ix]
        self.F0, self.F1, self.Fd = F0[free], F1[free], Fd[free]
        self.closed, self.seated = closed, seated

    def component(self, row: int) -> np.ndarray:
        """Positions in ``free`` of the coordinates tied to coordinate ``row`` (the last
        body) through the mass, stiffness or damping: the only ones that move it."""
        tied = (np.abs(self.M) + np.abs(self.K) + np.abs(self.C)) > 0
        start = int(np.flatnonzero(self.free == row)[0])
        seen, todo = {start}, [start]
        while todo:
            i = todo.pop()
            for j in np.flatnonzero(tied[i]):
                if int(j) not in seen:
                    seen.add(int(j))
                    todo.append(int(j))
        return np.array(sorted(seen))

    def particular(self, part: np.ndarray, y0: float, ys: float):
        """The particular solution ``u = p + q t`` under ``y = y0 + ys t`` on the coordinates
        ``part`` (m, m/s): ``K q = F1 ys``, ``K p = F0 + F1 y0 + Fd ys - C q``."""
        ix = np.ix_(part, part)
        K, C = self.K[ix], self.C[ix]
        q = np.linalg.solve(K, self.F1[part] * ys)
        p = np.linalg.solve(K, self.F0[part] + self.F1[part] * y0 + self.Fd[part] * ys - C @ q)
        return p, q


def static_contacts(
    system, y0: float, ys: float
) -> tuple[_Linear, np.ndarray, np.ndarray, np.ndarray]:
    """The linear system of the contacts that the static state under ``y = y0 + ys t`` (m,
    m/s) closes, found by switching them until its forces and approaches agree (starting
    from every contact closed, the seat too where there is one); the last body's
    coordinates tied to it (``_Linear.component``, positions in the free coordinates) and
    the static displacements and velocities on them."""
    s = system
    E = s.k.size
    seat_given = float(s.seat_k) > 0
    held = float(s.rider) > 0
    closed, seated = np.ones(E), seat_given
    last = int(s.body_rows[-1])
    tolerance = _FORCE_TOLERANCE * (float(s.preload) + 1.0)
    for _ in range(2 * E + 4):
        linear = _Linear(s, closed, seated, held)
        part = linear.component(last)
        p, q = linear.particular(part, y0, ys)
        u, v = np.full(s.Minv.shape[0], np.nan), np.full(s.Minv.shape[0], np.nan)
        u[linear.free[part]], v[linear.free[part]] = p, q
        if held:
            u[0], v[0] = y0, ys
        approach = s.d0 + s.G @ np.nan_to_num(u) + s.g_cam * y0
        rate = s.G @ np.nan_to_num(v) + s.g_cam * ys
        force = s.k * approach + s.c * rate
        known = np.array([np.all(np.isfinite(u[np.asarray(g) != 0])) for g in s.G], dtype=bool)
        now = np.where(closed > 0, force >= -tolerance, approach > _FORCE_TOLERANCE) & known
        now = np.where(s.one_sided > 0, now, True).astype(float)
        if seat_given:
            gap = float(s.seat_s0 - s.seat_row @ np.nan_to_num(u))
            seat_force = float(s.seat_k) * gap - float(s.seat_c) * float(
                s.seat_row @ np.nan_to_num(v)
            )
            now_seated = seat_force >= -tolerance if seated else gap > _FORCE_TOLERANCE
        else:
            now_seated = False
        if np.array_equal(now, closed) and now_seated == seated:
            return linear, part, p, q
        closed, seated = now, now_seated
    return linear, part, p, q


def contact_residual_mm(system, u: np.ndarray, v: np.ndarray, y0: float, ys: float) -> float:
    """The residual vibration (mm) of the chain's state ``u``, ``v`` (m, m/s, its moving
    coordinates) at a segment's start where the lift is ``y0 + ys t`` (m, m/s): the
    envelope ``sum_j |V_last,j xi_j|`` of the last body's free vibration over the modes of
    the dwell's static contacts (``static_contacts``), ``xi`` the state's distance from the
    static state in those modes (a complex pair counted twice: the exact path's doubled
    gain)."""
    linear, part, p, q = static_contacts(system, y0, ys)
    ix = np.ix_(part, part)
    Minv = np.linalg.inv(linear.M[ix])
    n = part.size
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ linear.K[ix], -Minv @ linear.C[ix]]])
    lam, V = np.linalg.eig(A)
    coordinates = linear.free[part]
    distance = np.concatenate([u[coordinates] - p, v[coordinates] - q])
    xi = np.linalg.solve(V, distance)
    row = int(np.flatnonzero(coordinates == int(system.body_rows[-1]))[0])
    return 1e3 * float(np.sum(np.abs(V[row] * xi)))
