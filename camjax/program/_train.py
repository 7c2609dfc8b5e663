"""The follower as a chain of bodies: valve trains, a spring that surges (docs/valve-trains.md).

Bodies from the cam outward; element ``j`` joins body ``j - 1`` (the cam for ``j = 1``) to
body ``j`` with stiffness ``k_j``, damping ``c_j`` and lever ratio ``r_j``: it stretches by
``r_j x_(j-1) - x_j`` and pushes body ``j - 1`` back with ``r_j`` times its force.  A first
body with no element rides on the cam (``x_1 = y``).  The return spring acts on the last
body; with a mass it is a uniform bar cut into equal elements whose mass matrix is the mean
of the lumped and the consistent one (fourth-order accurate: 8 elements put the first three
surge frequencies within 0.5% of ``f_n = (n/2) sqrt(k_s/m_s)``, where equal lumped coils
need 28), and its internal damping is strain-rate (Kelvin-Voigt, ``tau = 2 zeta_1 / w_1``).

Every coordinate is a displacement from the preloaded rest; the cam's lift drives the
coordinate it holds.  ``ChainModes`` is the chain's state-space system diagonalised once in
NumPy (edits of values compile nothing), and ``chain_cycle`` its exact periodic steady
state over a program's turn: one complex mode per eigenvalue through the SDOF engine's
propagation (``camjax.sdof.periodic_propagate``), the one-body follower its first case.
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..metrics import PEAK_TOLERANCE, bernstein_bound, hermite_data, peak_search
from ..sdof import periodic_propagate
from ._follower import Follower

SURGE_TOLERANCE = 0.005
"""Default spring discretisation: the fewest elements whose first three surge frequencies
(both ends held) are within this share of the continuous spring's."""
MAX_SPRING_ELEMENTS = 64


def _number(value, where: str, *, positive: bool = False, non_negative: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{where} must be a finite number, got {value!r}")
    if positive and not value > 0:
        raise ValueError(f"{where} must be positive, got {value:g}")
    if non_negative and value < 0:
        raise ValueError(f"{where} must be non-negative, got {value:g}")
    return float(value)


@dataclasses.dataclass(frozen=True)
class Body:
    """One body of the chain and the element that joins it to the body before (the cam for
    the first).  ``stiffness_n_per_mm=None``: no element, the body rides on the cam (the
    first body only).  ``lever_mass_kg``: the lever's moment of inertia over the square of
    its arm on the side of the body before (a rocker's inertia at that end)."""

    name: str
    mass_kg: float
    stiffness_n_per_mm: float | None = None
    damping_n_s_per_m: float = 0.0
    ratio: float = 1.0
    lever_mass_kg: float = 0.0
    lash_mm: float = 0.0

    @property
    def rides(self) -> bool:
        return self.stiffness_n_per_mm is None


@dataclasses.dataclass(frozen=True)
class Spring:
    """The return spring on the last body: rate, preload (the static force every element
    carries, scaled by the levers), and optionally its own mass (surge) with its first
    surge mode's damping ratio; ``elements`` fixes its discretisation (default: the fewest
    that meet ``SURGE_TOLERANCE``; fewer run faster and resolve less)."""

    rate_n_per_mm: float
    preload_n: float = 0.0
    mass_kg: float = 0.0
    damping_ratio: float = 0.0
    elements: int | None = None

    @property
    def surges(self) -> bool:
        return self.mass_kg > 0

    def element_count(self) -> int:
        if not self.surges:
            return 1
        if self.elements is not None:
            return self.elements
        return next(
            n
            for n in range(1, MAX_SPRING_ELEMENTS + 1)
            if np.all(np.abs(_bar_surge_ratios(n) - 1) <= SURGE_TOLERANCE)
        )

    @property
    def surge_hz(self) -> float:
        """The continuous spring's first surge frequency, both ends held (Hz)."""
        return 0.5 * math.sqrt(1e3 * self.rate_n_per_mm / self.mass_kg)


@dataclasses.dataclass(frozen=True)
class Seat:
    """A stiff one-sided contact under the last body (the valve's seat)."""

    stiffness_n_per_mm: float


def _bar_mass(n: int, mass: float) -> np.ndarray:
    """One element's 2x2 mass matrix: the mean of the lumped and the consistent one."""
    return mass / n * np.array([[5 / 12, 1 / 12], [1 / 12, 5 / 12]])


def _bar_surge_ratios(n: int) -> np.ndarray:
    """First three surge frequencies of a unit bar in ``n`` elements, both ends held, over
    the continuous bar's (ones where fewer than three exist: such a bar resolves none)."""
    if n < 4:
        return np.full(3, np.inf)
    K, M = np.zeros((n + 1, n + 1)), np.zeros((n + 1, n + 1))
    for e in range(n):
        i = np.ix_([e, e + 1], [e, e + 1])
        K[i] += n * np.array([[1.0, -1.0], [-1.0, 1.0]])
        M[i] += _bar_mass(n, 1.0)
    import scipy.linalg  # the generalised symmetric eigenproblem (imported when a chain is solved)

    w = np.sqrt(scipy.linalg.eigh(K[1:-1, 1:-1], M[1:-1, 1:-1], eigvals_only=True))
    return w[:3] / (np.pi * np.arange(1, 4))


@dataclasses.dataclass(frozen=True)
class Chain:
    """A linear chain of bodies from the cam outward, its return spring and optional seat.

    ``Chain.of_follower`` is today's one-body follower; ``chain_from_dict`` reads the
    program file's ``[[train]]``, ``[spring]`` and ``[seat]`` tables.
    """

    bodies: tuple[Body, ...]
    spring: Spring | None = None
    seat: Seat | None = None

    def __post_init__(self):
        _check_chain(self)

    @classmethod
    def of_follower(cls, follower: Follower) -> Chain:
        """The classic follower as a one-body train: its mass on its elastic element
        (damping ``c = 2 zeta sqrt(k m)``), its return spring and preload."""
        body = Body("follower", follower.mass_kg, follower.stiffness_n_per_mm, follower.damping)
        spring = (
            None
            if follower.form_closed
            else Spring(follower.spring_rate_n_per_mm, follower.preload_n)
        )
        return cls((body,), spring)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.bodies)

    @property
    def spells_follower(self) -> bool:
        """Whether this chain is a classic follower spelled as a train (one body on its
        element, a spring without mass, no lever, lash or seat): then the program's one-body
        numbers are exactly the chain's."""
        (body, *rest), s = self.bodies, self.spring
        return (
            not rest
            and not body.rides
            and body.ratio == 1.0
            and not body.lever_mass_kg
            and not body.lash_mm
            and self.seat is None
            and (s is None or not s.surges)
            and body.damping_n_s_per_m < 2 * math.sqrt(1e3 * body.stiffness_n_per_mm * body.mass_kg)
        )

    def follower_fields(self) -> dict:
        """The classic ``[follower]`` fields this chain stands for: ``of_follower``'s inverse
        where the chain ``spells_follower``; else a one-body stand-in with the bodies'
        summed mass (less where needed) and the first natural frequency with the cam held,
        which only the period ratios of a speed's plausibility check and of a segment's
        design band read (the report gives a chain's own numbers, ``train_section``)."""
        s = self.spring
        rate = None if s is None else s.rate_n_per_mm
        preload = 0.0 if s is None else s.preload_n
        if self.spells_follower:
            body = self.bodies[0]
            k = 1e3 * body.stiffness_n_per_mm
            zeta = body.damping_n_s_per_m / (2 * math.sqrt(k * body.mass_kg))
            mass, stiffness = body.mass_kg, body.stiffness_n_per_mm
        else:
            w2 = (2 * math.pi * self.natural_frequencies(contact=True)[0][0]) ** 2
            mass, k_s = sum(b.mass_kg for b in self.bodies), 1e3 * (rate or 0.0)
            if mass * w2 <= 2 * k_s:
                mass = 2 * k_s / w2
            stiffness, zeta = 1e-3 * (mass * w2 - k_s), 0.0
        return {
            "mass_kg": float(mass),
            "stiffness_n_per_mm": float(stiffness),
            "damping_ratio": float(zeta),
            "spring_rate_n_per_mm": rate,
            "preload_n": preload,
        }

    def toml_lines(self) -> list[str]:
        """The ``[[train]]``, ``[spring]`` and ``[seat]`` tables (``chain_from_dict``'s
        inverse), defaults left out."""
        lines = []
        for body in self.bodies:
            lines += ["[[train]]", f"name = {json.dumps(body.name)}"]
            for field in dataclasses.fields(Body)[1:]:
                value = getattr(body, field.name)
                if value != field.default:
                    lines.append(f"{field.name} = {value!r}")
            lines.append("")
        for table, obj in (("spring", self.spring), ("seat", self.seat)):
            if obj is None:
                continue
            lines.append(f"[{table}]")
            for field in dataclasses.fields(obj):
                value = getattr(obj, field.name)
                if value != field.default or field.default is dataclasses.MISSING:
                    lines.append(f"{field.name} = {value!r}")
            lines.append("")
        return lines

    # -- the assembled system ------------------------------------------------------------

    def matrices(self, *, contact: bool = True) -> Assembly:
        """Mass, damping and stiffness (SI) over every coordinate: the cam's (index 0: the
        first body's own where it rides), the bodies', the spring's inner nodes and its
        seat (last).  ``contact=False`` drops the first element (the cam let go)."""
        rides = self.bodies[0].rides
        n_bodies = len(self.bodies)
        n_spring = self.spring.element_count() if self.spring is not None else 0
        body_index = list(range(0 if rides else 1, n_bodies + (0 if rides else 1)))
        inner = list(range(body_index[-1] + 1, body_index[-1] + max(n_spring, 1)))
        seat = (inner[-1] if inner else body_index[-1]) + 1
        size = seat + 1
        M, C, K = (np.zeros((size, size)) for _ in range(3))

        def element(a, b, k, c, r=1.0):
            g = np.array([r, -1.0])
            i = np.ix_([a, b], [a, b])
            K[i] += k * np.outer(g, g)
            C[i] += c * np.outer(g, g)

        for j, body in enumerate(self.bodies):
            M[body_index[j], body_index[j]] += body.mass_kg
            if body.rides or (j == 0 and not contact):
                continue
            before = 0 if j == 0 else body_index[j - 1]
            M[before, before] += body.lever_mass_kg
            element(
                before,
                body_index[j],
                1e3 * body.stiffness_n_per_mm,
                body.damping_n_s_per_m,
                body.ratio,
            )
        if self.spring is not None:
            s = self.spring
            nodes = [body_index[-1], *inner, seat]
            k_e = 1e3 * s.rate_n_per_mm * n_spring
            tau = 0.0
            if s.surges and s.damping_ratio > 0:
                tau = 2 * s.damping_ratio / (2 * math.pi * s.surge_hz)
            for a, b in zip(nodes[:-1], nodes[1:]):
                element(a, b, k_e, k_e * tau)
                if s.surges:
                    M[np.ix_([a, b], [a, b])] += _bar_mass(n_spring, s.mass_kg)
        return Assembly(M, C, K, np.asarray(body_index), size - 1)

    @property
    def cam_preload_n(self) -> float:
        """The static force at the cam: the spring's preload through every lever."""
        if self.spring is None:
            return 0.0
        levers = [b.ratio for b in self.bodies if not b.rides]
        return self.spring.preload_n * float(np.prod(levers))

    # -- natural frequencies -----------------------------------------------------------

    def natural_frequencies(self, *, contact: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Undamped natural frequencies (Hz, ascending) and mode shapes (columns over the
        bodies, each scaled to its largest body motion 1) with the cam contact held
        (``contact=True``: the cam's coordinate fixed) or free (in flight)."""
        import scipy.linalg  # the generalised symmetric eigenproblem

        a = self.matrices(contact=contact)
        moving = np.arange(1, a.seat) if contact else np.arange(0, a.seat)
        if not contact and not self.bodies[0].rides:
            moving = np.arange(1, a.seat)  # the cam's coordinate carries nothing in flight
        values, vectors = scipy.linalg.eigh(
            a.K[np.ix_(moving, moving)], a.M[np.ix_(moving, moving)]
        )
        hz = np.sqrt(np.maximum(values, 0.0)) / (2 * math.pi)
        rows = np.searchsorted(moving, a.body_index)
        shapes = np.zeros((len(self.bodies), hz.size))
        inside = (rows < moving.size) & (moving[np.minimum(rows, moving.size - 1)] == a.body_index)
        shapes[inside] = vectors[rows[inside]]
        scale = shapes[np.argmax(np.abs(shapes), axis=0), np.arange(hz.size)]
        return hz, shapes / np.where(scale == 0, 1.0, scale)

    def highest_frequency_hz(self) -> float:
        """The highest natural frequency with the cam held (Hz; 0 where nothing moves)."""
        return float(self.natural_frequencies(contact=True)[0].max(initial=0.0))

    def harmonic_check(
        self, rpm_min: float, rpm_max: float, *, modes: int = 3
    ) -> list[tuple[float, list[int]]]:
        """For each of the first ``modes`` held frequencies: ``(f_n, cam orders k)`` with
        ``k rpm / 60 = f_n`` at a speed inside ``[rpm_min, rpm_max]``."""
        hz = self.natural_frequencies(contact=True)[0][:modes]
        return [
            (float(f), list(range(math.ceil(60 * f / rpm_max), math.floor(60 * f / rpm_min) + 1)))
            for f in hz
        ]


class Assembly(NamedTuple):
    """The chain's matrices over its coordinates (``Chain.matrices``)."""

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    body_index: np.ndarray
    seat: int


def _check_chain(chain: Chain) -> None:
    if not chain.bodies:
        raise ValueError("[[train]]: a train needs at least one body")
    names = set()
    for j, body in enumerate(chain.bodies, start=1):
        where = f"[[train]] body {j} ({body.name})"
        if body.name in names:
            raise ValueError(f"{where}: name given twice")
        names.add(body.name)
        _number(body.mass_kg, f"{where} mass_kg", positive=True)
        if body.rides and j > 1:
            raise ValueError(
                f"{where}: stiffness_n_per_mm is needed after the first body (the element "
                "from the body before)"
            )
        if not body.rides:
            _number(body.stiffness_n_per_mm, f"{where} stiffness_n_per_mm", positive=True)
        _number(body.damping_n_s_per_m, f"{where} damping_n_s_per_m", non_negative=True)
        if _number(body.ratio, f"{where} ratio") <= 0:
            raise ValueError(
                f"{where} ratio must be positive (a lever's travel ratio), got {body.ratio:g}"
            )
        _number(body.lever_mass_kg, f"{where} lever_mass_kg", non_negative=True)
        _number(body.lash_mm, f"{where} lash_mm", non_negative=True)
        if body.rides and (
            body.ratio != 1.0 or body.lash_mm or body.lever_mass_kg or body.damping_n_s_per_m
        ):
            raise ValueError(
                f"{where}: ratio, lash_mm, lever_mass_kg and damping_n_s_per_m belong to an "
                "element, and a body that rides on the cam has none (give stiffness_n_per_mm)"
            )
    s = chain.spring
    if s is not None:
        _number(s.rate_n_per_mm, "[spring] rate_n_per_mm", positive=True)
        _number(s.preload_n, "[spring] preload_n", non_negative=True)
        _number(s.mass_kg, "[spring] mass_kg", non_negative=True)
        zeta = _number(s.damping_ratio, "[spring] damping_ratio", non_negative=True)
        if zeta >= 1:
            raise ValueError(f"[spring] damping_ratio must be below 1, got {zeta:g}")
        if zeta > 0 and not s.surges:
            raise ValueError("[spring] damping_ratio is its first surge mode's: it needs mass_kg")
        if s.elements is not None:
            if isinstance(s.elements, bool) or not isinstance(s.elements, int) or s.elements < 1:
                raise ValueError(
                    f"[spring] elements must be a positive whole number, got {s.elements!r}"
                )
            if not s.surges:
                raise ValueError(
                    "[spring] elements: a spring without mass_kg has no surge to resolve"
                )
            if s.elements < 4:
                raise ValueError(
                    f"[spring] elements = {s.elements} cannot resolve the first three surge "
                    "modes (4 at least; the default meets 0.5%)"
                )
        elif s.surges and s.element_count() > MAX_SPRING_ELEMENTS:
            raise ValueError("[spring]: its surge cannot be resolved")
    if chain.seat is not None:
        _number(chain.seat.stiffness_n_per_mm, "[seat] stiffness_n_per_mm", positive=True)
        if s is None or s.preload_n <= 0:
            raise ValueError(
                "[seat]: a seat needs a [spring] with preload_n > 0 to close the valve onto it"
            )
    if s is None and chain.bodies[-1].rides:
        raise ValueError(
            "[[train]]: a single body riding on the cam needs a [spring] (nothing holds it)"
        )


_BODY_FIELDS = {f.name for f in dataclasses.fields(Body)}
_SPRING_FIELDS = {f.name for f in dataclasses.fields(Spring)}
CLASSIC_FIELDS = (
    "mass_kg",
    "stiffness_n_per_mm",
    "damping_ratio",
    "spring_rate_n_per_mm",
    "preload_n",
)
"""The ``[follower]`` fields of the one-body train (the classic spelling)."""


def load_chain(path) -> Chain | None:
    """The chain of a program file (``chain_from_dict`` of its tables); errors name the file."""
    import tomllib

    try:
        with open(path, "rb") as file:
            return chain_from_dict(tomllib.load(file))
    except (ValueError, OSError) as error:
        raise ValueError(f"{path}: {error}") from None


def chain_from_dict(data: dict) -> Chain | None:
    """The chain of a program file's tables: ``[[train]]`` with ``[spring]`` and ``[seat]``,
    or ``None`` where the file has none (its ``[follower]`` fields are the one-body train).
    Bad input is one ``ValueError`` line naming the table, the body and the field."""
    train, spring, seat = data.get("train"), data.get("spring"), data.get("seat")
    if train is None:
        for table, value in (("[spring]", spring), ("[seat]", seat)):
            if value is not None:
                raise ValueError(
                    f"{table} belongs to a [[train]]; a one-body follower gives its spring in "
                    "[follower] (spring_rate_n_per_mm, preload_n)"
                )
        return None
    if not isinstance(train, list) or not all(isinstance(b, dict) for b in train):
        raise ValueError("[[train]] must be an array of tables, one per body")
    classic = [name for name in CLASSIC_FIELDS if name in (data.get("follower") or {})]
    if classic:
        raise ValueError(
            f"[follower] {', '.join(classic)}: a file with a [[train]] gives the bodies there, "
            "not the classic one-body fields"
        )
    bodies = []
    for j, table in enumerate(train, start=1):
        unknown = sorted(set(table) - _BODY_FIELDS)
        if unknown:
            raise ValueError(
                f"[[train]] body {j}: unknown field(s) {', '.join(unknown)}; expected "
                f"{', '.join(sorted(_BODY_FIELDS))}"
            )
        if "mass_kg" not in table:
            raise ValueError(f"[[train]] body {j} ({table.get('name', j)}): needs mass_kg")
        bodies.append(
            Body(
                **{
                    "name": str(table.get("name", f"body {j}")),
                    **{k: v for k, v in table.items() if k != "name"},
                }
            )
        )
    spring_obj = None
    if spring is not None:
        if not isinstance(spring, dict):
            raise ValueError("[spring] must be a table")
        unknown = sorted(set(spring) - _SPRING_FIELDS)
        if unknown:
            raise ValueError(
                f"[spring]: unknown field(s) {', '.join(unknown)}; expected "
                f"{', '.join(sorted(_SPRING_FIELDS))}"
            )
        if "rate_n_per_mm" not in spring:
            raise ValueError("[spring] needs rate_n_per_mm")
        spring_obj = Spring(**spring)
    seat_obj = None
    if seat is not None:
        if not isinstance(seat, dict) or set(seat) != {"stiffness_n_per_mm"}:
            raise ValueError("[seat] takes one field, stiffness_n_per_mm")
        seat_obj = Seat(seat["stiffness_n_per_mm"])
    return Chain(tuple(bodies), spring_obj, seat_obj)


# -- the exact periodic steady state -----------------------------------------------------


class ChainModes(NamedTuple):
    """The chain's state-space system diagonalised (physical time, SI, lift in m): each
    output ``o = Re(sum_j g_j xi_j) + e0 y + e1 y' + e2 y'' + static`` where the modes obey
    ``xi_j' = lam_j xi_j + f_j y``.  Rows of ``gain``/``direct``/``static`` are the outputs
    in ``OUTPUTS`` order (the bodies' accelerations one row each).  A pytree of arrays: the
    compiled turn takes it as an argument, so an edit of values compiles nothing."""

    lam: np.ndarray  # (S,) complex, 1/s: one of each conjugate pair (S = the degrees of freedom
    # where every mode oscillates; one more per two overdamped ones)
    forcing: np.ndarray  # (S,) complex: f_j
    gain: np.ndarray  # (O, S) complex
    direct: np.ndarray  # (O, 3) real: e0, e1, e2
    static: np.ndarray  # (O,)

    @classmethod
    def of(cls, chain: Chain) -> ChainModes:
        for j, body in enumerate(chain.bodies, start=1):
            if body.lash_mm:
                raise ValueError(
                    f"[[train]] body {j} ({body.name}) lash_mm: the steady state is of the "
                    "closed chain; lash (a clearance that opens) is not modelled yet"
                )
        if chain.seat is not None:
            raise ValueError(
                "[seat]: the steady state is of the closed chain; the seat's contact is not "
                "modelled yet"
            )
        a = chain.matrices()
        free = np.arange(1, a.seat)
        n = free.size
        if n == 0:
            raise ValueError(
                "[[train]]: one body riding on the cam on a spring without mass has nothing to "
                "vibrate (its contact force is m y'' + k_s y + preload): give it an element "
                "(stiffness_n_per_mm) or use the classic follower"
            )
        Mff, Cff, Kff = (x[np.ix_(free, free)] for x in (a.M, a.C, a.K))
        G = np.linalg.solve(Mff, a.M[free, 0])
        Minv = np.linalg.inv(Mff)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Kff, -Minv @ Cff]])
        b0 = np.concatenate([np.zeros(n), Minv @ (Kff @ G - a.K[free, 0])])
        b1 = np.concatenate([np.zeros(n), Minv @ (Cff @ G - a.C[free, 0])])
        lam, V = np.linalg.eig(A)
        if not np.all(lam.real < 0):
            raise ValueError(
                "the chain has a mode without damping (give the elements damping_n_s_per_m "
                "or the spring damping_ratio): its periodic steady state does not exist"
            )
        if np.linalg.cond(V) > 1e10:
            raise ValueError(
                "the chain's modes are not independent (a critically damped mode): change "
                "a damping a little"
            )
        Vinv = np.linalg.inv(V)
        u, v = Vinv @ b0, Vinv @ b1
        rows, statics = [], []

        def output(aK, aC, aM, static=0.0):
            c_z = np.concatenate([aK[free], aC[free]]) + aM[free] @ A[n:, :]
            e0 = aK[0] - aK[free] @ G + aM[free] @ b0[n:]
            e1 = aC[0] - aC[free] @ G + aM[free] @ b1[n:]
            e2 = aM[0] - aM[free] @ G
            g = c_z @ V
            rows.append((g, [e0 + float(np.real(g @ v)), e1, e2]))
            statics.append(static)

        zero = np.zeros(a.seat + 1)

        def unit(i):
            e = zero.copy()
            e[i] = 1.0
            return e

        output(a.K[0], a.C[0], a.M[0], chain.cam_preload_n)  # contact force at the cam
        for i in a.body_index:  # each body's acceleration
            output(zero, zero, unit(i))
        output(unit(a.body_index[-1]), zero, zero)  # the last body's displacement (m)
        preload = chain.spring.preload_n if chain.spring is not None else 0.0
        output(-a.K[a.seat], -a.C[a.seat], -a.M[a.seat], preload)  # the spring's force at its seat
        rate = 1e3 * chain.spring.rate_n_per_mm if chain.spring is not None else 0.0
        output(-a.K[a.seat] - rate * unit(a.body_index[-1]), -a.C[a.seat], -a.M[a.seat])  # surge
        # A real system's modes come in conjugate pairs (LAPACK returns them exactly
        # conjugate), whose two terms sum to twice the real part of one: keep one of each
        # pair, doubled, and every real (overdamped) mode once.
        keep = lam.imag >= 0
        weight = np.where(lam.imag[keep] > 0, 2.0, 1.0)
        gain = np.array([r[0] for r in rows])[:, keep] * weight
        return cls(
            lam[keep],
            (u + lam * v)[keep],
            gain,
            np.array([r[1] for r in rows]),
            np.asarray(statics, dtype=float),
        )


def output_rows(bodies: int) -> dict[str, int | slice]:
    """Where each output sits in ``ChainModes``' rows for a chain of ``bodies``."""
    return {
        "contact_force_n": 0,
        "acceleration_m_s2": slice(1, 1 + bodies),
        "lift_m": 1 + bodies,
        "seat_force_n": 2 + bodies,
        "surge_n": 3 + bodies,
    }


def lift_jets(coefficients, widths):
    """``y`` and its first five derivatives in turn time at the left and right end of every
    interval, ``((K, 6), (K, 6))``, from its monomial coefficients in the local ``sigma``."""
    h = jnp.where(widths > 0, widths, 1.0)[:, None]
    powers = np.arange(6)
    falling = np.array(
        [[math.perm(int(m), d) for m in powers] for d in range(6)], dtype=float
    )  # (d, m)
    scale = h ** -powers[None, :]
    left = coefficients * falling.diagonal()[None, :] * scale
    right = (coefficients @ falling.T) * scale
    return left, right


class ChainCycle(NamedTuple):
    """One turn of the chain's periodic steady state at one speed: outputs at the nodes
    (rows as ``output_rows``); the refined least and largest contact force and seat force
    (``SIGNED_ROWS`` of ``low`` and ``high``), and the refined peak ``|f|`` of each
    body's acceleration and of the surge (``PEAK_ROWS`` of ``peak``)."""

    values: jax.Array
    low: jax.Array
    high: jax.Array
    peak: jax.Array


def signed_rows(bodies: int) -> list[int]:
    rows = output_rows(bodies)
    return [rows["contact_force_n"], rows["seat_force_n"]]


def peak_rows(bodies: int) -> list[int]:
    rows = output_rows(bodies)
    return [
        *range(rows["acceleration_m_s2"].start, rows["acceleration_m_s2"].stop),
        rows["surge_n"],
    ]


def chain_cycle(motion, lift, modes: ChainModes, rpm) -> ChainCycle:
    """The exact periodic steady state over one turn at ``rpm`` (jittable, vmappable in
    ``rpm``): ``motion`` is the turn's engine grid (``CycleGrid.motion``), ``lift`` its
    ``(K, 6)`` lift coefficients in mm.  One engine propagation per eigenvalue."""
    period = 60.0 / rpm
    lam = period * jnp.asarray(modes.lam)
    f = period * jnp.asarray(modes.forcing)
    lift = 1e-3 * jnp.asarray(lift)
    grid = motion._replace(forcing=lift)
    q = jax.vmap(lambda l: periodic_propagate(grid, None, None, lam=l))(lam)  # (S, K + 1)
    xi = f[:, None] * q
    gain = jnp.asarray(modes.gain)
    e0, e1, e2 = (jnp.asarray(modes.direct)[:, i] for i in range(3))
    direct = jnp.stack([e0, e1 / period, e2 / period**2], axis=1)  # per y, y_s, y_ss
    widths = grid.widths
    y_left, y_right = lift_jets(lift, widths)
    y_nodes = jnp.concatenate([y_left[:, :3], y_right[-1:, :3]])
    xr, xq = jnp.real(xi), jnp.imag(xi)

    def real_part(g, re, im):  # Re(g @ x) in real products (XLA's complex ones are slow on CPU)
        return jnp.real(g) @ re - jnp.imag(g) @ im

    values = real_part(gain, xr, xq) + direct @ y_nodes.T + jnp.asarray(modes.static)[:, None]

    def jets(ends, y_end):
        """``(O, K, 3)``: the outputs' first three derivatives at one end of each interval."""
        out = []
        for p in (1, 2, 3):
            d = real_part(gain * lam**p, xr[:, ends], xq[:, ends])
            for i in range(p):
                d = d + jnp.real(gain @ (lam ** (p - 1 - i) * f))[:, None] * y_end[None, :, i]
            d = d + direct @ y_end[:, p : p + 3].T
            out.append(d)
        return jnp.stack(out, axis=-1)

    left, right = jets(slice(None, -1), y_left), jets(slice(1, None), y_right)
    bodies = values.shape[0] - 4
    signed, peaks = np.asarray(signed_rows(bodies)), np.asarray(peak_rows(bodies))
    high = jax.vmap(_bounded_max, in_axes=(0, None, 0, 0))(
        values[signed], widths, left[signed], right[signed]
    )
    low = -jax.vmap(_bounded_max, in_axes=(0, None, 0, 0))(
        -values[signed], widths, -left[signed], -right[signed]
    )
    peak = jax.vmap(_bounded_peak, in_axes=(0, None, 0, 0))(
        values[peaks], widths, left[peaks], right[peaks]
    )
    return ChainCycle(values, low, high, peak)


def _bounded_peak(values, widths, left, right):
    """``max |f|`` between the nodes, refining only the intervals whose Bernstein bound can
    beat the best found (``camjax.metrics.peak_search``)."""
    bound = bernstein_bound(values, widths, tuple(left.T), tuple(right.T))
    data = hermite_data(values, widths, left, right)
    return peak_search(bound, lambda index: data[index], jnp.max(jnp.abs(values)), PEAK_TOLERANCE)


def _bounded_max(values, widths, left, right):
    """``max f`` (signed) between the nodes, refining only the intervals whose Bernstein
    bound can beat the best found (``camjax.metrics.peak_search``): the dense refinement of
    every output over every interval cost a chain ten times its propagation."""
    low = jnp.min(values)
    shift = low - (jnp.max(values) - low) - 1.0
    return _bounded_peak(values - shift, widths, left, right) + shift


@jax.jit
def _chain_cycles(rpm, motion, lift, modes: ChainModes) -> ChainCycle:
    """``chain_cycle`` at every speed of a block: one compiled program per shape (the
    chain's number of states and the padded grid), whatever the values."""
    return jax.vmap(lambda r: chain_cycle(motion, lift, modes, r))(rpm)


class ChainSummary(NamedTuple):
    """The chain's periodic steady state at every speed (``ChainSteadyState.summary``)."""

    rpm: np.ndarray
    min_contact_force_n: np.ndarray
    max_contact_force_n: np.ndarray
    max_acceleration_m_s2: np.ndarray  # (speeds, bodies): each body's peak |x''|
    max_lift_error_mm: np.ndarray  # the last body's largest distance from its kinematic lift
    min_seat_force_n: np.ndarray
    max_seat_force_n: np.ndarray
    max_surge_n: np.ndarray  # the seat force's largest distance from the spring's static force


class ChainSteadyState:
    """A program driving a chain, its exact periodic steady state at any speeds from
    ``rpm_min`` up: the grid resolves the chain's highest mode with the cam held at
    ``rpm_min``; the speeds run in blocks of ``SPEED_BLOCK`` through one compiled program
    per shape (number of states, bucketed grid), so another chain of the same shape or an
    edited program compiles nothing."""

    def __init__(self, program, chain: Chain, rpm_min: float):
        from ._dynamics import PaddedTurn, cycle_grid
        from ._machine import NodeContact
        from ._speeds import Speeds

        self.program, self.chain = program, chain
        self.rpm_min = Speeds.of(rpm_min, "rpm_min").min()
        self.modes = ChainModes.of(chain)
        self.grid = cycle_grid(program, self.rpm_min, chain.highest_frequency_hz())
        zeros = np.zeros(self.grid.intervals + 1)
        padded = PaddedTurn.of(self.grid, None, NodeContact(zeros, zeros, zeros, zeros)).grid
        self._motion, self._lift = padded.motion, padded.lift
        self._rows = output_rows(len(chain.bodies))
        # the kinematic lift of the last body: the cam's through every lever
        self.kinematic_ratio = float(np.prod([b.ratio for b in chain.bodies if not b.rides]))

    def cycles(self, rpm) -> ChainCycle:
        """The whole turn at every speed, ``(speeds, outputs, nodes)`` (nodes of the turn's own
        grid, the padding cut)."""
        from ._dynamics import SPEED_BLOCK
        from ._speeds import Speeds

        rpm = np.asarray(Speeds.of(rpm))
        if rpm.min() < self.rpm_min * (1 - 1e-12):
            raise ValueError(
                f"rpm {rpm.min():g} below the steady state's slowest speed {self.rpm_min:g}"
            )
        padded = np.pad(rpm, (0, -rpm.size % SPEED_BLOCK), mode="edge").reshape(-1, SPEED_BLOCK)
        outs = [
            _chain_cycles(jnp.asarray(block), self._motion, self._lift, self.modes)
            for block in padded
        ]
        out = jax.tree.map(lambda *x: np.concatenate([np.asarray(v) for v in x])[: rpm.size], *outs)
        out = out._replace(values=out.values[..., : self.grid.intervals + 1])
        if not np.all(np.isfinite(out.values)):
            raise ValueError("the chain's steady state is not finite")
        return out

    def summary(self, rpm) -> ChainSummary:
        """What a valve-train engineer reads per speed (``ChainSummary``)."""
        c = self.cycles(rpm)
        bodies = len(self.chain.bodies)
        error = (
            1e3 * c.values[:, self._rows["lift_m"]]
            - self.kinematic_ratio * np.asarray(self.grid.lift_nodes)[None, :]
        )
        return ChainSummary(
            np.asarray(rpm, dtype=float),
            c.low[:, 0],
            c.high[:, 0],
            c.peak[:, :bodies],
            np.max(np.abs(error), axis=1),
            c.low[:, 1],
            c.high[:, 1],
            c.peak[:, bodies],
        )

    def jump_speed(
        self, rpm_max: float, *, tolerance_rpm: float = 1e-4, scan: int = 128
    ) -> float | None:
        """The lowest speed in ``[rpm_min, rpm_max]`` where the cam's contact force first
        reaches zero (the chain leaves the cam), ``None`` where the contact holds over the
        whole range: a scan of ``scan`` speeds, each local minimum of the least force
        looked at closer twice (a chain's resonances make narrow dips), then bisection to
        ``tolerance_rpm``."""
        speeds = np.linspace(self.rpm_min, float(rpm_max), scan)
        low = self.summary(speeds).min_contact_force_n
        for _ in range(2):
            if np.any(low <= 0):
                break
            dips = [
                i
                for i in range(1, speeds.size - 1)
                if low[i] <= low[i - 1] and low[i] <= low[i + 1]
            ]
            if not dips:
                break
            closer = np.concatenate(
                [np.linspace(speeds[i - 1], speeds[i + 1], 34)[1:-1] for i in dips]
            )
            speeds = np.concatenate([speeds, closer])
            low = np.concatenate([low, self.summary(closer).min_contact_force_n])
            order = np.argsort(speeds)
            speeds, low = speeds[order], low[order]
        if low[0] <= 0:
            return self.rpm_min
        lost = np.nonzero(low <= 0)[0]
        if lost.size == 0:
            return None
        a, b = speeds[lost[0] - 1], speeds[lost[0]]
        while b - a > tolerance_rpm:
            inner = np.linspace(a, b, 34)[1:-1]  # one block of speeds per step
            force = self.summary(inner).min_contact_force_n
            k = np.nonzero(force <= 0)[0]
            a, b = (inner[k[0] - 1] if k[0] > 0 else a, inner[k[0]]) if k.size else (inner[-1], b)
        return 0.5 * (a + b)


CHAIN_NOTE = (
    "a train: the rows give the chain's contact force at the cam (min Fc, max Fc, the "
    "preload that keeps it, jump) and its last body's peak acceleration as the payload's; "
    "the one-body outputs (drive torque, Hertz stress, residual vibration, period ratios, "
    "flights) are not computed for a chain and left empty"
)
ONE_BODY_NOTE = "a one-body train: the classic follower's rows are this chain's (the same numbers)"


def train_section(program, chain: Chain, rpm: np.ndarray) -> tuple[dict, ChainSummary]:
    """The report's ``train`` section over the speeds ``rpm``: the natural frequencies held
    and free with their mode shapes, the harmonic check over the speed range, the chain's
    ``ChainSummary`` per speed and its jump speed (``None`` where the contact holds over
    the range, only one speed is given, or it is lost at the lowest already:
    ``jump_below_range``); with the summary itself for the report's rows."""
    rpm = np.asarray(rpm, dtype=float)
    steady = ChainSteadyState(program, chain, float(rpm.min()))
    summary = steady.summary(rpm)
    spring = chain.spring is not None  # without one the cam is form-closed: no jump
    jump, below = None, spring and bool(summary.min_contact_force_n[np.argmin(rpm)] <= 0)
    if spring and not below and rpm.size > 1 and rpm.max() > rpm.min():
        jump = steady.jump_speed(float(rpm.max()))
    frequencies = {}
    for key, contact in (("held", True), ("free", False)):
        hz, shapes = chain.natural_frequencies(contact=contact)
        frequencies[f"natural_frequencies_{key}_hz"] = hz.tolist()
        frequencies[f"mode_shapes_{key}"] = shapes.T.tolist()  # one row per mode, over the bodies
    speeds = [
        {
            "rpm": float(r),
            "min_contact_force_n": float(summary.min_contact_force_n[i]),
            "max_contact_force_n": float(summary.max_contact_force_n[i]),
            "max_acceleration_m_s2": dict(
                zip(chain.names, summary.max_acceleration_m_s2[i].tolist())
            ),
            "max_lift_error_mm": float(summary.max_lift_error_mm[i]),
            "min_seat_force_n": float(summary.min_seat_force_n[i]),
            "max_seat_force_n": float(summary.max_seat_force_n[i]),
            "max_surge_n": float(summary.max_surge_n[i]),
        }
        for i, r in enumerate(rpm)
    ]
    section = {
        "one_body": chain.spells_follower,
        "note": ONE_BODY_NOTE if chain.spells_follower else CHAIN_NOTE,
        "bodies": list(chain.names),
        **frequencies,
        "harmonic_check": [
            {"frequency_hz": f, "orders": orders}
            for f, orders in chain.harmonic_check(float(rpm.min()), float(rpm.max()))
        ],
        "speeds": speeds,
        "jump_speed_rpm": jump,
        "jump_below_range": below,
    }
    return section, summary
