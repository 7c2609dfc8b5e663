"""The swinging follower's arm as a flexible Rayleigh beam in a train (docs/swinging-follower.md).

The arm is pinned at the pivot and carries the roller ``roller_mm`` from it; the cam holds
the roller's transverse displacement, which is the program's lift (the arc the roller
centre swings through: swing angle times ``arm_mm``).  Coordinates are absolute transverse
displacements ``w(x)`` (and slopes) of the arm swinging about its pivot, so the rigid swing
``w = x y / roller_mm`` strains nothing and the bending ``v = w - x y / roller_mm`` obeys
``EI v'''' + rho A v'' = -rho A x psi''`` (plus rotary inertia): the linear theory of the
paper's rod in its swinging frame, without the centrifugal and groove terms of second order.

The beam is cut into cubic Hermite elements (bending stiffness, consistent translational
and rotary mass); nodes sit at the pivot, the roller, every body clamped on the arm and the
tip.  Twelve elements (the default) put a uniform pinned arm's first three bending
frequencies within 3e-4 of the closed form (``bending_frequency_ratios``; the error falls as
the fourth power of the element size).  The chain keeps the bodies' displacements and the
arm's first ``modes`` modes with the bodies held (Craig-Bampton, ``ArmAssembly.reduced``):
the default four put the paper's rod's first two modes within 6e-5 and its third within
0.3%, and the steady state's grid resolves only the modes kept, not the elements' upper
ones.  Damping is strain-rate (Kelvin-Voigt, ``C = tau K`` with ``tau = 2 zeta_1 / w_1`` for
the first mode with the cam held), as the spring's: mode n is damped ``w_n / w_1`` times as
much, and the rigid swing not at all.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..geometry import SwingingRollerFollower
from ._follower import Follower, follower_kind
from ._follower import field_number as _number

DEFAULT_ELEMENTS = 12
"""Elements over the arm's length by default (``bending_frequency_ratios(12)``: 3e-6, 5e-5
and 2.6e-4 for the first three modes of a uniform pinned arm)."""
MAX_ELEMENTS = 64
DEFAULT_MODES = 4
"""The arm's modes kept, with its bodies held (Craig-Bampton; ``ArmAssembly.reduced``)."""


@dataclasses.dataclass(frozen=True)
class Arm:
    """The swinging follower's arm as a Rayleigh beam (SI beam properties, lengths in mm).

    ``roller_mm``: where the roller sits, from the pivot (the follower's ``arm_mm``; a
    program file sets it from there); ``length_mm``: the arm's whole length (default the
    roller's position; longer where the arm carries on past the roller to a tip).
    ``rotary_inertia_kg_m`` is ``rho I`` (0: an Euler-Bernoulli beam); ``damping_ratio`` the
    first mode's with the cam held (strain-rate: higher modes more); ``elements`` over the
    length (default ``DEFAULT_ELEMENTS``); ``modes``: the arm's modes the chain keeps, with
    its bodies held (default ``DEFAULT_MODES``)."""

    bending_stiffness_n_m2: float
    mass_per_length_kg_per_m: float
    roller_mm: float
    rotary_inertia_kg_m: float = 0.0
    damping_ratio: float = 0.0
    length_mm: float | None = None
    elements: int | None = None
    modes: int = DEFAULT_MODES

    def __post_init__(self):
        _number(self.bending_stiffness_n_m2, "[arm] bending_stiffness_n_m2", positive=True)
        _number(self.mass_per_length_kg_per_m, "[arm] mass_per_length_kg_per_m", positive=True)
        _number(self.roller_mm, "[arm] roller_mm (the follower's arm_mm)", positive=True)
        _number(self.rotary_inertia_kg_m, "[arm] rotary_inertia_kg_m", non_negative=True)
        zeta = _number(self.damping_ratio, "[arm] damping_ratio", non_negative=True)
        if zeta >= 1:
            raise ValueError(f"[arm] damping_ratio must be below 1, got {zeta:g}")
        if self.length_mm is not None:
            length = _number(self.length_mm, "[arm] length_mm", positive=True)
            if length < self.roller_mm * (1 - 1e-12):
                raise ValueError(
                    f"[arm] length_mm = {length:g} is shorter than the roller's place on it "
                    f"(the follower's arm_mm = {self.roller_mm:g})"
                )
        n = self.elements
        if n is not None and (
            isinstance(n, bool) or not isinstance(n, int) or not 2 <= n <= MAX_ELEMENTS
        ):
            raise ValueError(
                f"[arm] elements must be a whole number from 2 to {MAX_ELEMENTS} (2 resolve one "
                f"bending mode to 0.4%, the default {DEFAULT_ELEMENTS} three to 3e-4), got {n!r}"
            )

        m = self.modes
        if isinstance(m, bool) or not isinstance(m, int) or not 1 <= m <= 2 * MAX_ELEMENTS:
            raise ValueError(
                f"[arm] modes must be a whole number from 1 (the arm's modes kept, with its "
                f"bodies held; default {DEFAULT_MODES}), got {m!r}"
            )

    @property
    def length(self) -> float:
        """The arm's length, m."""
        return 1e-3 * (self.roller_mm if self.length_mm is None else self.length_mm)

    @property
    def element_count(self) -> int:
        return DEFAULT_ELEMENTS if self.elements is None else self.elements

    def pinned_frequencies_hz(self, modes: int = 3) -> np.ndarray:
        """The closed form of a uniform Rayleigh beam pinned at both ends over the roller's
        span (the arm with the cam held and nothing clamped on it):
        ``w_k^2 = EI (k pi / l)^4 / (rho A + rho I (k pi / l)^2)``, Hz."""
        k = np.arange(1, modes + 1) * math.pi / (1e-3 * self.roller_mm)
        w2 = (
            self.bending_stiffness_n_m2
            * k**4
            / (self.mass_per_length_kg_per_m + self.rotary_inertia_kg_m * k**2)
        )
        return np.sqrt(w2) / (2 * math.pi)

    def toml_lines(self) -> list[str]:
        """The ``[arm]`` table (``arm_from_dict``'s inverse; ``roller_mm`` is the follower's
        ``arm_mm`` and not written), defaults left out."""
        lines = ["[arm]"]
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if field.name == "roller_mm":
                continue
            if field.default is dataclasses.MISSING or value != field.default:
                lines.append(f"{field.name} = {value!r}")
        return [*lines, ""]


ARM_FIELDS = {f.name for f in dataclasses.fields(Arm)} - {"roller_mm"}
"""The keys of a program file's ``[arm]`` table (the studio's fields of an arm)."""


def arm_from_dict(table, follower: dict | None) -> Arm:
    """The ``[arm]`` table of a program file on its ``[follower]``: a swinging roller
    follower, whose ``arm_mm`` places the roller.  Errors are one line naming the field."""
    if not isinstance(table, dict):
        raise ValueError("[arm] must be a table")
    follower = follower or {}
    default = {f.name: f.default for f in dataclasses.fields(Follower)}["kind"]
    kind = follower.get("kind", default)
    if follower_kind(kind) is not SwingingRollerFollower:
        raise ValueError(
            "[arm]: a flexible arm belongs to a swinging roller follower ([follower] kind = "
            f"{SwingingRollerFollower.name!r}), not {kind!r}: a translating follower's train "
            "is [[train]] bodies on elements"
        )
    unknown = sorted(set(table) - ARM_FIELDS)
    if unknown:
        raise ValueError(
            f"[arm]: unknown field(s) {', '.join(unknown)}; expected {', '.join(sorted(ARM_FIELDS))}"
        )
    for required in ("bending_stiffness_n_m2", "mass_per_length_kg_per_m"):
        if required not in table:
            raise ValueError(f"[arm] needs {required}")
    if "arm_mm" not in follower:
        raise ValueError("[follower] arm_mm is missing: it places the roller on the [arm]")
    return Arm(roller_mm=follower["arm_mm"], **table)


# -- the beam's matrices ------------------------------------------------------------------


def element_matrices(
    length: float, bending: float, mass: float, rotary: float
) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and mass (translational plus rotary, both consistent) of one cubic Hermite
    beam element over ``(w_a, w_a', w_b, w_b')``, SI."""
    L = length
    k = (
        bending
        / L**3
        * np.array(
            [
                [12, 6 * L, -12, 6 * L],
                [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                [-12, -6 * L, 12, -6 * L],
                [6 * L, 2 * L * L, -6 * L, 4 * L * L],
            ]
        )
    )
    m = (
        mass
        * L
        / 420
        * np.array(
            [
                [156, 22 * L, 54, -13 * L],
                [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                [54, 13 * L, 156, -22 * L],
                [-13 * L, -3 * L * L, -22 * L, 4 * L * L],
            ]
        )
    )
    r = (
        rotary
        / (30 * L)
        * np.array(
            [
                [36, 3 * L, -36, 3 * L],
                [3 * L, 4 * L * L, -3 * L, -L * L],
                [-36, -3 * L, 36, -3 * L],
                [3 * L, -L * L, -3 * L, 4 * L * L],
            ]
        )
    )
    return k, m + r


def mesh(arm: Arm, stations_m) -> np.ndarray:
    """The nodes along the arm (m from the pivot): the pivot, every station (the roller and
    the bodies), the tip, and between them ``arm.element_count`` elements shared in
    proportion to the spans' lengths (one at least in each)."""
    ends = np.unique(np.concatenate([[0.0, arm.length], np.asarray(stations_m, float)]))
    nodes = [0.0]
    for a, b in zip(ends[:-1], ends[1:]):
        count = max(1, round(arm.element_count * (b - a) / arm.length))
        nodes.extend(np.linspace(a, b, count + 1)[1:])
    return np.asarray(nodes)


class ArmAssembly:
    """The arm's beam over the chain's coordinates: index 0 the roller's displacement (the
    cam's), then every other node's displacement and slope from the pivot outward (the
    pivot's displacement held at zero), with ``body_index`` the coordinates of the bodies at
    ``positions_mm`` (the first, the roller's, is 0)."""

    def __init__(self, arm: Arm, positions_mm):
        positions = 1e-3 * np.asarray(positions_mm, dtype=float)
        roller = 1e-3 * arm.roller_mm
        self.nodes = mesh(arm, [roller, *positions])
        on = lambda x: int(np.argmin(np.abs(self.nodes - x)))  # noqa: E731
        roller_node = on(roller)
        index, count = {}, 1  # (node, 0 displacement | 1 slope) -> coordinate
        index[(roller_node, 0)] = 0
        for node in range(self.nodes.size):
            for dof in (0, 1):
                if (node == 0 and dof == 0) or (node, dof) in index:
                    continue  # the pivot is held; the roller's displacement is the cam's
                index[(node, dof)] = count
                count += 1
        self.size = count
        self.index = index
        self.body_index = np.asarray([index[(on(x), 0)] for x in positions], dtype=int)
        K, M = np.zeros((count, count)), np.zeros((count, count))
        for e in range(self.nodes.size - 1):
            k, m = element_matrices(
                self.nodes[e + 1] - self.nodes[e],
                arm.bending_stiffness_n_m2,
                arm.mass_per_length_kg_per_m,
                arm.rotary_inertia_kg_m,
            )
            dofs = [index.get((node, dof), -1) for node in (e, e + 1) for dof in (0, 1)]
            keep = [i for i, d in enumerate(dofs) if d >= 0]
            rows = [dofs[i] for i in keep]
            K[np.ix_(rows, rows)] += k[np.ix_(keep, keep)]
            M[np.ix_(rows, rows)] += m[np.ix_(keep, keep)]
        self.K, self.M = K, M

    def reduced(self, modes: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Craig-Bampton: the bodies' displacements kept as they are (the roller's, the
        cam's, first), every other node's motion as their static shape plus the arm's first
        ``modes`` modes with those held (``T = [[1, 0], [-K_ii^-1 K_ib, Phi]]``).  Returns
        ``(K, M, body_index)`` over the bodies' displacements then the modes: the arm's
        modes well below the highest kept are exact to a few parts in a million, and the
        steady state's grid resolves only those it keeps, not the elements' upper ones."""
        import scipy.linalg

        kept = list(dict.fromkeys(int(i) for i in self.body_index))
        inner = np.setdiff1d(np.arange(self.size), kept)
        K, M = self.K, self.M
        Kii, Mii = K[np.ix_(inner, inner)], M[np.ix_(inner, inner)]
        static = -np.linalg.solve(Kii, K[np.ix_(inner, kept)])
        count = min(modes, inner.size)
        _, shapes = scipy.linalg.eigh(Kii, Mii, subset_by_index=[0, count - 1])
        T = np.zeros((self.size, len(kept) + count))
        T[kept, np.arange(len(kept))] = 1.0
        T[np.ix_(inner, np.arange(len(kept)))] = static
        T[np.ix_(inner, len(kept) + np.arange(count))] = shapes
        body_index = np.asarray([kept.index(int(i)) for i in self.body_index], dtype=int)
        return T.T @ K @ T, T.T @ M @ T, body_index


def bending_frequency_ratios(elements: int, *, rotary: float = 0.0, modes: int = 3) -> np.ndarray:
    """The first ``modes`` frequencies of a uniform pinned arm (unit length, ``EI``, ``rho A``;
    ``rho I = rotary``) in ``elements``, cam held, over the closed form: how the default
    element count was chosen (``DEFAULT_ELEMENTS``)."""
    import scipy.linalg

    arm = Arm(1.0, 1.0, 1e3, rotary_inertia_kg_m=rotary, elements=elements)
    a = ArmAssembly(arm, [])
    free = np.arange(1, a.size)
    w2 = scipy.linalg.eigh(a.K[np.ix_(free, free)], a.M[np.ix_(free, free)], eigvals_only=True)
    return np.sqrt(w2[:modes]) / (2 * math.pi) / arm.pinned_frequencies_hz(modes)[: w2[:modes].size]


# -- what the report gives of an arm ----------------------------------------------------
