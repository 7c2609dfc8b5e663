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
coordinate it holds.  This module holds the chain as a value (read, checked, written back,
its natural frequencies); its modes are ``_oscillator.py``'s ``Oscillator.of_chain``, and its
periodic steady state over a program's turn the program's own (``SteadyState``).
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import NamedTuple

import numpy as np

from ..geometry import SwingingRollerFollower
from ._arm import Arm, ArmAssembly, arm_from_dict
from ._follower import Follower
from ._follower import field_number as _number

SURGE_TOLERANCE = 0.005
"""Default spring discretisation: the fewest elements whose first three surge frequencies
(both ends held) are within this share of the continuous spring's."""
MAX_SPRING_ELEMENTS = 64
"""The most elements a spring is cut into (the default search's ceiling too; 0.5% takes 8)
and, as ``MAX_BODIES``, the most bodies: the chain's modes cost the cube of its coordinates.
Measured 2026-11-29 at commit dc06f88 on the shared 2-core machine (a three-body valve train,
``Oscillator.of_chain`` after ``natural_frequencies`` held and free): 64 elements 0.24 s and
0.3 s, 128 0.66 s and 0.08 s, 512 11.5 s and 4.5 s, 1000 115 s and 4.2 s; the memory check
refuses 100 elements at 1500 rpm anyway."""
MAX_BODIES = MAX_SPRING_ELEMENTS


@dataclasses.dataclass(frozen=True)
class Body:
    """One body of the chain and the element that joins it to the body before (the cam for
    the first).  ``stiffness_n_per_mm=None``: no element, the body rides on the cam (the
    first body only).  ``lever_mass_kg``: the lever's moment of inertia over the square of
    its arm on the side of the body before (a rocker's inertia at that end; not on the first
    element, whose cam side moves with the cam: such a lever is a riding first body).  ``at_mm``: on a
    chain with a flexible ``Arm``, where the body is clamped on it (mm from the pivot; the
    first body rides on the cam at the roller and needs none); a body on an arm has no
    element (the arm is its element) and may have no mass (a point of the arm watched)."""

    name: str
    mass_kg: float
    stiffness_n_per_mm: float | None = None
    damping_n_s_per_m: float = 0.0
    ratio: float = 1.0
    lever_mass_kg: float = 0.0
    lash_mm: float = 0.0
    at_mm: float | None = None

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
    """A stiff one-sided contact under the last body (the valve's seat): a spring of
    ``stiffness_n_per_mm`` with a dashpot of ``damping_n_s_per_m`` beside it, pushing only
    (docs/valve-trains.md, "Lash and the seat")."""

    stiffness_n_per_mm: float
    damping_n_s_per_m: float = 0.0


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
    program file's ``[[train]]``, ``[spring]``, ``[seat]`` and ``[arm]`` tables.  With an
    ``arm`` the bodies sit on a swinging follower's flexible arm (``camjax.program.Arm``):
    the first rides on the cam at the roller, the others are clamped at their ``at_mm``.
    """

    bodies: tuple[Body, ...]
    spring: Spring | None = None
    seat: Seat | None = None
    arm: Arm | None = None

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
            self.arm is None
            and not rest
            and not body.rides
            and body.ratio == 1.0
            and not body.lever_mass_kg
            and not body.lash_mm
            and self.seat is None
            and (s is None or not s.surges)
            and body.damping_n_s_per_m < 2 * math.sqrt(1e3 * body.stiffness_n_per_mm * body.mass_kg)
        )

    @property
    def has_contacts(self) -> bool:
        """Whether the chain has a one-sided contact besides the cam's (a lash or a seat):
        then it is not linear, and its steady state is simulated (``_chain_contacts.py``)."""
        return self.seat is not None or any(b.lash_mm for b in self.bodies)

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
        if self.arm is not None:
            lines += self.arm.toml_lines()
        return lines

    # -- the assembled system ------------------------------------------------------------

    def matrices(self, *, contact: bool = True) -> Assembly:
        """Mass, damping and stiffness (SI) over every coordinate: the cam's (index 0: the
        first body's own where it rides), the bodies', the spring's inner nodes and its
        seat (last).  ``contact=False`` drops the first element (the cam let go).  With an
        arm: the roller's displacement (the cam's), the arm's nodes (``ArmAssembly``), the
        spring's inner nodes and its seat."""
        if self.arm is not None:
            return self._arm_matrices()
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
        self._add_spring(M, C, K, [body_index[-1], *inner, seat])
        return Assembly(M, C, K, np.asarray(body_index), size - 1)

    def _add_spring(self, M, C, K, nodes) -> None:
        """The return spring's elements (and its mass) over ``nodes``, the last body's
        coordinate first and its seat last."""
        s = self.spring
        if s is None:
            return
        n_spring = len(nodes) - 1
        k_e = 1e3 * s.rate_n_per_mm * n_spring
        tau = 0.0
        if s.surges and s.damping_ratio > 0:
            tau = 2 * s.damping_ratio / (2 * math.pi * s.surge_hz)
        g = np.array([1.0, -1.0])
        for a, b in zip(nodes[:-1], nodes[1:]):
            i = np.ix_([a, b], [a, b])
            K[i] += k_e * np.outer(g, g)
            C[i] += k_e * tau * np.outer(g, g)
            if s.surges:
                M[i] += _bar_mass(n_spring, s.mass_kg)

    def _arm_matrices(self) -> Assembly:
        """The bodies on the flexible arm: its beam (``ArmAssembly``), each body's mass at
        its node, the spring on the last body, and the arm's strain-rate damping scaled to
        its first mode with the cam held."""
        import scipy.linalg  # the generalised symmetric eigenproblem

        arm = self.arm
        beam = ArmAssembly(arm, [arm.roller_mm, *(b.at_mm for b in self.bodies[1:])])
        beam_K, beam_M, body_index = beam.reduced(arm.modes)
        n_beam = beam_K.shape[0]
        n_spring = self.spring.element_count() if self.spring is not None else 1
        size = n_beam + n_spring
        seat = size - 1
        M, C, K = (np.zeros((size, size)) for _ in range(3))
        M[:n_beam, :n_beam] += beam_M
        K[:n_beam, :n_beam] += beam_K
        for body, i in zip(self.bodies, body_index):
            M[i, i] += body.mass_kg
        self._add_spring(M, C, K, [body_index[-1], *range(n_beam, seat), seat])
        free = np.arange(1, seat)
        w2 = scipy.linalg.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True)
        tau = 2 * arm.damping_ratio / math.sqrt(w2[0])
        C[:n_beam, :n_beam] += tau * beam_K
        return Assembly(M, C, K, body_index, seat)

    @property
    def lever_ratio(self) -> float:
        """The last body's travel per unit of the cam's lift with the elements rigid (its
        kinematic lift's scale), and by virtual work the factor of the spring's preload at
        the cam: the product of the levers, or on an arm the last body's place over the
        roller's (``at_mm / arm_mm``, the rigid swing)."""
        if self.arm is not None:
            last = self.bodies[-1]  # the first rides at the roller; the others sit at at_mm
            return 1.0 if len(self.bodies) == 1 else float(last.at_mm) / self.arm.roller_mm
        return float(np.prod([b.ratio for b in self.bodies if not b.rides]))

    @property
    def cam_preload_n(self) -> float:
        """The static force at the cam: the spring's preload through every lever."""
        if self.spring is None:
            return 0.0
        return self.spring.preload_n * self.lever_ratio

    def check_follower(self, follower: Follower) -> None:
        """A chain with an arm needs the swinging roller follower whose ``arm_mm`` is the
        arm's roller place; a groove's strikes are the one-body follower's alone (one line
        naming the field otherwise)."""
        if follower.groove_clearance_mm is not None and not self.spells_follower:
            raise ValueError(
                "follower.groove_clearance_mm: a groove's strikes are simulated for the one-body "
                "follower only; a chain without a [spring] runs in a tight groove (leave it out)"
            )
        if self.arm is None:
            return
        if not isinstance(follower.geometry, SwingingRollerFollower):
            raise ValueError(
                f"[arm]: a flexible arm belongs to a swinging roller follower, not {follower.kind!r}"
            )
        if abs(follower.arm_mm - self.arm.roller_mm) > 1e-9 * follower.arm_mm:
            raise ValueError(
                f"[arm] roller_mm = {self.arm.roller_mm:g} is not the follower's arm_mm = "
                f"{follower.arm_mm:g} (where the roller sits)"
            )

    # -- natural frequencies -----------------------------------------------------------

    def natural_frequencies(self, *, contact: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Undamped natural frequencies (Hz, ascending) and mode shapes (columns over the
        bodies, each scaled to its largest body motion 1) with the cam contact held
        (``contact=True``: the cam's coordinate fixed) or free (in flight)."""
        hz, shapes, a = self.coordinate_modes(contact=contact)
        shapes = shapes[a.body_index]
        scale = shapes[np.argmax(np.abs(shapes), axis=0), np.arange(hz.size)]
        return hz, shapes / np.where(scale == 0, 1.0, scale)

    def coordinate_modes(self, *, contact: bool = True) -> tuple[np.ndarray, np.ndarray, Assembly]:
        """``natural_frequencies`` with the mode shapes over every coordinate of
        ``matrices`` (rows; the held cam's and the seat's zero), each scaled to its largest
        motion 1, and the ``Assembly`` that says which row is which (the bodies' and the
        spring's coils along the chain; an arm's are its reduced coordinates)."""
        import scipy.linalg  # the generalised symmetric eigenproblem

        a = self.matrices(contact=contact)
        moving = np.arange(1, a.seat) if contact else np.arange(0, a.seat)
        if not contact and not self.bodies[0].rides:
            moving = np.arange(1, a.seat)  # the cam's coordinate carries nothing in flight
        values, vectors = scipy.linalg.eigh(
            a.K[np.ix_(moving, moving)], a.M[np.ix_(moving, moving)]
        )
        # a chain that nothing holds once the cam lets go (no spring) moves as one rigid
        # body: its eigenvalue is zero but for rounding
        values = np.where(
            values <= 1e3 * np.finfo(float).eps * values.max(initial=0.0), 0.0, values
        )
        hz = np.sqrt(values) / (2 * math.pi)
        shapes = np.zeros((a.seat + 1, hz.size))
        shapes[moving] = vectors
        scale = shapes[np.argmax(np.abs(shapes), axis=0), np.arange(hz.size)]
        return hz, shapes / scale, a

    def highest_frequency_hz(self) -> float:
        """The highest natural frequency with the cam held (Hz; 0 where nothing moves)."""
        return float(self.natural_frequencies(contact=True)[0].max(initial=0.0))

    def highest_mode_remedy(self) -> str:
        """The chain's own fields that set its highest held natural frequency (what a turn's
        grid resolves), said as what to change to lower it: the body that moves most in that
        mode and the elements beside it, or the spring's discretisation, or the arm's."""
        if self.arm is not None:
            return (
                "lower [arm] modes or bending_stiffness_n_m2, or raise its mass_per_length_kg_per_m"
            )
        hz, shapes, a = self.coordinate_modes(contact=True)
        if hz.size == 0:
            return "lower the elements' stiffness_n_per_mm"
        where = int(np.argmax(np.abs(shapes[:, -1])))
        bodies = [int(i) for i in a.body_index]
        if where not in bodies:
            return (
                f"give [spring] fewer elements (now {self.spring.element_count()}) or more mass_kg"
            )
        j = bodies.index(where)
        elements = [
            self.bodies[i].name
            for i in (j, j + 1)
            if i < len(self.bodies) and not self.bodies[i].rides
        ]
        said = " and ".join(f"[[train]] {name} stiffness_n_per_mm" for name in elements)
        return f"raise [[train]] {self.bodies[j].name} mass_kg" + (
            f" or lower {said}" if said else ""
        )

    def sized_fields(self) -> list[tuple[str, float, str]]:
        """``(key, value, unit)`` of the chain's sizes as the file names them: each body's
        mass, element stiffness, lash and lever ratio (unit ``""``), the spring's rate,
        preload and mass, the seat's stiffness (the absurd-size warnings read them in place
        of the follower's one-body stand-in)."""
        out = []
        for j, body in enumerate(self.bodies, start=1):
            where = f"[[train]] body {j} ({body.name})"
            out.append((f"{where} mass_kg", body.mass_kg, "kg"))
            if body.stiffness_n_per_mm is not None:
                out.append((f"{where} stiffness_n_per_mm", body.stiffness_n_per_mm, "N/mm"))
            out += [(f"{where} lash_mm", body.lash_mm, "mm"), (f"{where} ratio", body.ratio, "")]
        if self.spring is not None:
            out += [
                ("[spring] rate_n_per_mm", self.spring.rate_n_per_mm, "N/mm"),
                ("[spring] preload_n", self.spring.preload_n, "N"),
                ("[spring] mass_kg", self.spring.mass_kg, "kg"),
            ]
        if self.seat is not None:
            out.append(("[seat] stiffness_n_per_mm", self.seat.stiffness_n_per_mm, "N/mm"))
        return out

    def harmonic_check(
        self, rpm_min: float, rpm_max: float, *, modes: int = 3
    ) -> list[tuple[float, list[int]]]:
        """For each of the first ``modes`` held frequencies: ``(f_n, cam orders k)`` with
        ``k rpm / 60 = f_n`` at a speed inside ``[rpm_min, rpm_max]``."""
        low, high = (
            _number(v, f"harmonic_check {n}")
            for n, v in (("rpm_min", rpm_min), ("rpm_max", rpm_max))
        )
        if not 0 < low <= high:
            raise ValueError(
                f"harmonic_check: the speed range must be positive and rising (0 < rpm_min <= "
                f"rpm_max), got rpm_min = {low:g}, rpm_max = {high:g}"
            )
        hz = self.natural_frequencies(contact=True)[0][:modes]
        return [
            (float(f), list(range(math.ceil(60 * f / high), math.floor(60 * f / low) + 1)))
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
    if len(chain.bodies) > MAX_BODIES:
        raise ValueError(
            f"[[train]]: {len(chain.bodies)} bodies are more than the {MAX_BODIES} a chain may "
            "have (its modes cost the cube of its bodies)"
        )
    names = set()
    for j, body in enumerate(chain.bodies, start=1):
        where = f"[[train]] body {j} ({body.name})"
        if not isinstance(body.name, str) or not body.name.strip():
            raise ValueError(
                f"[[train]] body {j}: name must be a non-empty text (it heads the body's "
                f"columns and rows), got {body.name!r}"
            )
        if body.name in names:
            raise ValueError(f"{where}: name given twice")
        names.add(body.name)
        if chain.arm is not None:
            _check_arm_body(chain.arm, body, j, where)
            continue
        if body.at_mm is not None:
            raise ValueError(f"{where} at_mm: a place on the arm needs an [arm] table")
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
        if j == 1 and not body.rides and body.lever_mass_kg:
            raise ValueError(
                f"{where} lever_mass_kg: a lever on the cam's side of the first element moves "
                f"with the cam; give it as a first [[train]] body of mass_kg = "
                f"{body.lever_mass_kg:g} with no stiffness_n_per_mm (it rides on the cam)"
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
            if s.elements > MAX_SPRING_ELEMENTS:
                raise ValueError(
                    f"[spring] elements = {s.elements} is more than {MAX_SPRING_ELEMENTS} (the "
                    "default meets 0.5% with fewer; the modes cost the cube of the elements)"
                )
            if s.elements < 4:
                raise ValueError(
                    f"[spring] elements = {s.elements} cannot resolve the first three surge "
                    "modes (4 at least; the default meets 0.5%)"
                )
        elif s.surges and s.element_count() > MAX_SPRING_ELEMENTS:
            raise ValueError("[spring]: its surge cannot be resolved")
    if chain.seat is not None:
        if chain.arm is not None:
            raise ValueError("[seat]: a valve seat belongs to a valve train, not to a swinging arm")
        _number(chain.seat.stiffness_n_per_mm, "[seat] stiffness_n_per_mm", positive=True)
        _number(chain.seat.damping_n_s_per_m, "[seat] damping_n_s_per_m", non_negative=True)
        if s is None or s.preload_n <= 0:
            raise ValueError(
                "[seat]: a seat needs a [spring] with preload_n > 0 to close the valve onto it"
            )
    if (
        chain.arm is None
        and len(chain.bodies) == 1
        and chain.bodies[0].rides
        and (s is None or not s.surges)
    ):
        raise ValueError(
            f"[[train]] body 1 ({chain.bodies[0].name}): a single body riding on the cam is rigid "
            "and has nothing to vibrate (its contact force is m y'' + k_s y + preload); give it "
            "stiffness_n_per_mm (its own stiffness against the cam: the classic one-body "
            "follower), a body behind it on an element, or a [spring] mass_kg (its surge)"
        )
    if s is None and chain.arm is None:
        lashed = [(j, b.name) for j, b in enumerate(chain.bodies, start=1) if b.lash_mm]
        if lashed:
            raise ValueError(
                "[[train]] body {} ({}) lash_mm: a chain".format(*lashed[0])
                + " without a [spring] is form-closed "
                "(grooved) and nothing closes a lash in it; give a [spring] (rate_n_per_mm, "
                "preload_n)"
            )


def _check_arm_body(arm: Arm, body: Body, j: int, where: str) -> None:
    """A body on a flexible arm: the first rides on the cam at the roller, the others are
    clamped at ``at_mm`` along it with no element of their own (the arm is theirs)."""
    if not isinstance(arm, Arm):
        raise ValueError(f"arm must be a camjax.program.Arm or None, got {arm!r}")
    if j == 1:
        if not body.rides:
            raise ValueError(
                f"{where}: on an [arm] the first body rides on the cam at the roller (no "
                "stiffness_n_per_mm: the arm joins the bodies)"
            )
        _number(body.mass_kg, f"{where} mass_kg", positive=True)
        if body.at_mm is not None and abs(body.at_mm - arm.roller_mm) > 1e-9 * arm.roller_mm:
            raise ValueError(
                f"{where} at_mm: the body riding on the cam sits at the roller ({arm.roller_mm:g} "
                "mm, the follower's arm_mm); leave at_mm out"
            )
        if body.ratio != 1.0 or body.lash_mm or body.lever_mass_kg or body.damping_n_s_per_m:
            raise ValueError(
                f"{where}: ratio, lash_mm, lever_mass_kg and damping_n_s_per_m belong to an "
                "element, and a body riding on the cam has none"
            )
        return
    _number(body.mass_kg, f"{where} mass_kg", non_negative=True)
    if body.at_mm is None:
        raise ValueError(f"{where}: needs at_mm, its place on the [arm] (mm from the pivot)")
    at = _number(body.at_mm, f"{where} at_mm", positive=True)
    if at > 1e3 * arm.length * (1 + 1e-12):
        raise ValueError(
            f"{where} at_mm = {at:g} is past the arm's end ({1e3 * arm.length:g} mm; give [arm] "
            "length_mm for an arm that carries on past the roller)"
        )
    extra = [
        name
        for name, value, default in (
            ("stiffness_n_per_mm", body.stiffness_n_per_mm, None),
            ("damping_n_s_per_m", body.damping_n_s_per_m, 0.0),
            ("ratio", body.ratio, 1.0),
            ("lever_mass_kg", body.lever_mass_kg, 0.0),
            ("lash_mm", body.lash_mm, 0.0),
        )
        if value != default
    ]
    if extra:
        raise ValueError(
            f"{where} {', '.join(extra)}: a body on the [arm] is joined by the arm itself (its "
            "bending_stiffness_n_m2 and damping_ratio), not by an element"
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
    arm = data.get("arm")
    if train is None:
        if arm is not None:
            raise ValueError(
                "[arm] needs [[train]] bodies: the first rides on the cam at the roller (its "
                "mass_kg), the others sit at their at_mm on the arm"
            )
        if spring is not None:
            raise ValueError(
                "[spring] belongs to a [[train]]; a one-body follower gives its spring in "
                "[follower] (spring_rate_n_per_mm, preload_n)"
            )
        if seat is not None:
            raise ValueError(
                "[seat] belongs to a [[train]]: a seat sits under a chain's last body, and the "
                "classic [follower] has none (give the follower as a one-body [[train]] with a "
                "[spring] to seat it)"
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
                f"[[train]] body {j} ({table.get('name', j)}): unknown field(s) "
                f"{', '.join(unknown)}; expected "
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
        if not isinstance(seat, dict):
            raise ValueError("[seat] must be a table")
        unknown = sorted(set(seat) - {"stiffness_n_per_mm", "damping_n_s_per_m"})
        if unknown or "stiffness_n_per_mm" not in seat:
            raise ValueError(
                (f"[seat]: unknown field(s) {', '.join(unknown)}; " if unknown else "[seat]: ")
                + "it takes stiffness_n_per_mm and optionally damping_n_s_per_m"
            )
        seat_obj = Seat(**seat)
    arm_obj = None if arm is None else arm_from_dict(arm, data.get("follower"))
    return Chain(tuple(bodies), spring_obj, seat_obj, arm_obj)


# -- the exact periodic steady state -----------------------------------------------------
