"""Segments that start or end in motion (VDI 2143): end states, "match", and every join's check.

A join's state is R (rest: v = 0, a = 0), G (constant velocity: v != 0, a = 0), U
(reversal: v = 0, a != 0) or B (motion: v != 0, a != 0).  A velocity that jumps at a join
is an impact (infinite acceleration) and is refused; an acceleration step (a jerk impulse)
is allowed and reported: the join is then C1, else C2.  Units are the program's: mm and
degrees of cam angle.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import numpy as np

from ..checks import finite_number as _finite
from ..checks import is_concrete
from ..laws import AbstractMotionLaw, BoundaryPolynomial, ConstantVelocity

MATCH = "match"
END_STATE_KEYS = ("velocity_mm_per_deg", "acceleration_mm_per_deg2", "jerk_mm_per_deg3")
_VELOCITY_TOLERANCE = 1e-9  # mm/deg, relative to max(1, |v|)
_ACCELERATION_TOLERANCE = 1e-9  # mm/deg^2, relative to max(1, |a|)
_STATE_TOLERANCE = 1e-12


@dataclasses.dataclass(frozen=True)
class EndState:
    """The follower's state at one end of a polynomial segment (mm/deg, mm/deg^2, mm/deg^3).

    ``jerk_mm_per_deg3`` is for degree 7 only; ``None`` there means zero.
    """

    velocity_mm_per_deg: float
    acceleration_mm_per_deg2: float = 0.0
    jerk_mm_per_deg3: float | None = None

    def toml(self) -> str:
        items = [f"{k} = {getattr(self, k)!r}" for k in END_STATE_KEYS if getattr(self, k) is not None]
        return "{ " + ", ".join(items) + " }"


_ENDS: dict[int, tuple] = {}


def _law_ends(law) -> tuple:
    """``((v, a, j) at tau = 0, at tau = 1)`` of a concrete law, kept per law object: a
    program's joins ask each law for its ends many times, and every evaluation under
    ``ensure_compile_time_eval`` runs the law's formulas op by op."""
    kept = _ENDS.get(id(law))
    if kept is not None and kept[0] is law:
        return kept[1]
    with jax.ensure_compile_time_eval():  # concrete even when a design traces around it
        _, v, a, j = (np.asarray(x, dtype=float) for x in law.evaluate(np.array([0.0, 1.0])))
    ends = tuple((float(v[k]), float(a[k]), float(j[k])) for k in (0, 1))
    if len(_ENDS) >= 256:
        _ENDS.clear()
    _ENDS[id(law)] = (law, ends)
    return ends


def law_state(seg, at_end: bool) -> tuple[float, float, float]:
    """``(v, a, j)`` of a segment at its start or end (mm/deg, mm/deg^2, mm/deg^3); zeros for a dwell."""
    if not seg.moving:
        return 0.0, 0.0, 0.0
    v, a, j = _law_ends(seg.law)[1 if at_end else 0]
    beta, h = seg.angle_deg, seg.lift_mm
    return h * v / beta, h * a / beta**2, h * j / beta**3


def is_polynomial(seg) -> bool:
    """A segment of the ``polynomial`` kind: its law is solved from ``start`` and ``end``."""
    return seg.start is not None or seg.end is not None


def _check_spec(i: int, seg, key: str) -> None:

    spec = getattr(seg, key)
    if spec == MATCH:
        return
    if not isinstance(spec, EndState):
        raise ValueError(f'segment {i}: {key} must be "match" or an end state table '
                         f"({', '.join(END_STATE_KEYS)}), got {spec!r}")
    for name in END_STATE_KEYS:
        value = getattr(spec, name)
        if value is not None:
            _finite(value, f"segment {i}: {key}.{name}")
    if spec.jerk_mm_per_deg3 is not None and seg.law.degree == 5:
        raise ValueError(f"segment {i}: {key}.jerk_mm_per_deg3: a degree-5 polynomial meets "
                         "velocity and acceleration only (use degree = 7)")


def resolve_segments(segments: tuple) -> tuple:
    """Segments with every polynomial's law solved from its end states, ``"match"`` read
    from the neighbour (cyclically: the first segment's start meets the last one's end).

    Quintics are solved first, so that a degree-7 polynomial can match a quintic's jerk.
    """
    n = len(segments)
    for i, seg in enumerate(segments, 1):
        if not is_polynomial(seg):
            continue
        if not isinstance(seg.law, BoundaryPolynomial):
            raise ValueError(f"segment {i}: start and end belong to a polynomial segment "
                             "(law camjax.laws.BoundaryPolynomial)")
        if seg.lift_mm == 0:
            raise ValueError(f"segment {i}: a polynomial cannot meet its end states with lift_mm = 0 "
                             "(its law is normalised by the lift)")
        for key in ("start", "end"):
            _check_spec(i, seg, key)
    if not any(is_polynomial(s) for s in segments) or not is_concrete([s.law for s in segments]):
        return segments
    built = list(segments)

    def facing(k: int, at_end: bool, asking: int) -> tuple[float, float, float]:
        seg = built[k]
        spec = seg.end if at_end else seg.start
        if not is_polynomial(seg):
            return law_state(seg, at_end)
        if spec == MATCH:
            mine, theirs = ("end", "start") if at_end else ("start", "end")
            raise ValueError(f'segment {asking + 1}: {theirs} = "match" meets segment {k + 1}\'s '
                             f'{mine} = "match": give one of them its state')
        jerk = spec.jerk_mm_per_deg3
        if jerk is None:
            jerk = 0.0 if seg.law.degree == 7 else law_state(seg, at_end)[2]
        return spec.velocity_mm_per_deg, spec.acceleration_mm_per_deg2, jerk

    for degree in (5, 7):
        for k, seg in enumerate(segments):
            if not is_polynomial(seg) or seg.law.degree != degree:
                continue
            start = facing((k - 1) % n, True, k) if seg.start == MATCH else _state(seg.start)
            end = facing((k + 1) % n, False, k) if seg.end == MATCH else _state(seg.end)
            beta, h = seg.angle_deg, seg.lift_mm
            scale = np.array([beta / h, beta**2 / h, beta**3 / h])
            v0, a0, j0 = np.asarray(start) * scale + 0.0  # + 0.0: no negative zeros in names
            v1, a1, j1 = np.asarray(end) * scale + 0.0
            if degree == 5:
                j0 = j1 = 0.0
            law = BoundaryPolynomial(v0=v0, a0=a0, v1=v1, a1=a1, j0=j0, j1=j1, degree=degree)
            built[k] = dataclasses.replace(seg, law=law)
    return tuple(built)


MAX_EXCURSION = 100.0
"""How far (in program strokes) a polynomial's lift may swing past its ends: further is an
end state out of proportion to the segment (a velocity in the wrong unit, a typo)."""


def check_excursions(segments, start_lift_mm) -> None:
    """Refuse a polynomial segment whose lift swings more than ``MAX_EXCURSION`` program
    strokes past its ends, naming the segment that gives the end state responsible: its
    own (explicit ones first) or, through ``"match"``, the neighbour's."""
    stroke = max([abs(float(y)) for y in np.cumsum([s.lift_mm for s in segments])]
                 + [abs(s.lift_mm) for s in segments])
    n = len(segments)
    polys = [k for k, s in enumerate(segments) if is_polynomial(s) and s.moving]
    explicit = sorted(polys, key=lambda k: not any(isinstance(x, EndState) for x in (segments[k].start, segments[k].end)))
    for k in explicit:
        seg = segments[k]
        with jax.ensure_compile_time_eval():  # concrete even when a design traces around it
            low, high = displacement_range(seg.law)
        y0 = float(start_lift_mm[k])
        ends = sorted((y0, y0 + seg.lift_mm))
        swing = max(ends[0] - min(y0 + seg.lift_mm * low, y0 + seg.lift_mm * high),
                    max(y0 + seg.lift_mm * low, y0 + seg.lift_mm * high) - ends[1], 0.0)
        if swing <= MAX_EXCURSION * stroke:
            continue
        given = [f"{key}.velocity_mm_per_deg = {spec.velocity_mm_per_deg:g}" for key, spec in
                 (("start", seg.start), ("end", seg.end)) if isinstance(spec, EndState)]
        if given:
            source = f"segment {k + 1}: its {' and '.join(given)}"
        else:
            other = (k - 1) % n if seg.start == MATCH else (k + 1) % n
            source = (f"segment {other + 1}'s end state (which segment {k + 1} matches); "
                      f"segment {k + 1}")
        raise ValueError(
            f"{source} cannot be met by a polynomial of lift {seg.lift_mm:g} mm over "
            f"{seg.angle_deg:g} deg without swinging the lift {swing:.3g} mm past its ends "
            f"(the program's stroke is {stroke:g} mm): the end state is out of proportion to "
            "the segment; check its value and unit (mm per degree of cam angle)")


def _state(spec: EndState) -> tuple[float, float, float]:
    return (float(spec.velocity_mm_per_deg), float(spec.acceleration_mm_per_deg2),
            float(spec.jerk_mm_per_deg3 or 0.0))


def vdi_state(v: float, a: float) -> str:
    """The VDI 2143 letter of a state: R, G, U or B."""
    moving, accelerating = abs(v) > _STATE_TOLERANCE, abs(a) > _STATE_TOLERANCE
    return {(False, False): "R", (True, False): "G", (False, True): "U", (True, True): "B"}[(moving, accelerating)]


@dataclasses.dataclass(frozen=True)
class Join:
    """Where segment ``before`` ends and ``after`` starts (1-based; the last wraps to the first)."""

    before: int
    after: int
    angle_deg: float
    velocity_mm_per_deg: float
    acceleration_before_mm_per_deg2: float
    acceleration_after_mm_per_deg2: float

    @property
    def continuity(self) -> str:
        """``C2`` where the acceleration is continuous, ``C1`` where it steps."""
        a, b = self.acceleration_before_mm_per_deg2, self.acceleration_after_mm_per_deg2
        return "C2" if abs(a - b) <= _ACCELERATION_TOLERANCE * max(1.0, abs(a), abs(b)) else "C1"

    @property
    def state(self) -> str:
        """The VDI 2143 state, ``"R/U"`` style (before/after) where the acceleration steps."""
        v = self.velocity_mm_per_deg
        before = vdi_state(v, self.acceleration_before_mm_per_deg2)
        after = vdi_state(v, self.acceleration_after_mm_per_deg2)
        return before if self.continuity == "C2" else f"{before}/{after}"

    def as_dict(self) -> dict:
        out = dataclasses.asdict(self)
        out.update(continuity=self.continuity, state=self.state)
        return out


def joins(segments, start_deg) -> list[Join]:
    """Every join of the turn, checked: a velocity jump is a ``ValueError`` naming both segments."""
    n = len(segments)
    out = []
    states = [(law_state(s, False), law_state(s, True)) for s in segments]
    for k in range(n):
        after = (k + 1) % n
        (v0, a0, _), (v1, a1, _) = states[k][1], states[after][0]
        angle = float(start_deg[after]) if after else 360.0
        # Relative to every end velocity of the two segments: a polynomial that starts at
        # 1e6 mm/deg ends at rest only to about 1e-9 of that (its coefficients' round-off).
        scale = max(1.0, *(abs(state[0]) for ends in (states[k], states[after]) for state in ends))
        if abs(v0 - v1) > _VELOCITY_TOLERANCE * scale:
            raise ValueError(
                f"segments {k + 1} and {after + 1} meet at {angle:g} deg with velocity {v0:.6g} mm/deg "
                f"(end of segment {k + 1}) and {v1:.6g} mm/deg (start of segment {after + 1}): a "
                "velocity that jumps is an impact; match the two")
        out.append(Join(k + 1, after + 1, angle, *(_snap(x) for x in (0.5 * (v0 + v1), a0, a1))))
    return out


def _snap(value: float) -> float:
    """Round-off (below ``1e-12``) reported as zero."""
    return 0.0 if abs(value) < _STATE_TOLERANCE else float(value)


def displacement_range(law: AbstractMotionLaw) -> tuple[float, float]:
    """``(min s, max s)`` over ``[0, 1]``: exact where the law knows it, else 20001 samples."""
    exact = getattr(law, "displacement_range", None)
    if exact is not None:
        return exact()
    s = np.asarray(law.s(np.linspace(0.0, 1.0, 20001)))
    return float(s.min()), float(s.max())


def segment_kinematics(program) -> list[dict]:
    """Per segment: kind, peak |y'|, |y''|, |y'''| (mm/deg^k) whether the lift overshoots its
    ends, and for a lift table (``TableLaw``) the fit's largest distance from its points
    (``fit_deviation_mm``, else ``None``)."""
    out = []
    for i, seg in enumerate(program.segments, 1):
        row = {"segment": i, "law": None if seg.law is None else seg.law.name,
               "kind": "dwell" if not seg.moving else
               "polynomial" if is_polynomial(seg) else
               "constant-velocity" if isinstance(seg.law, ConstantVelocity) else "rise" if seg.lift_mm > 0
               else "return",
               "angle_deg": float(seg.angle_deg), "lift_mm": float(seg.lift_mm),
               "peak_velocity_mm_per_deg": 0.0, "peak_acceleration_mm_per_deg2": 0.0,
               "peak_jerk_mm_per_deg3": 0.0, "overshoot": False,
               "fit_deviation_mm": getattr(getattr(seg.law, "fit_info", None), "deviation_mm", None)}
        if seg.moving:
            peaks = seg.law.peak_coefficients()
            h, beta = abs(seg.lift_mm), seg.angle_deg
            low, high = displacement_range(seg.law)
            row.update(peak_velocity_mm_per_deg=h * peaks["Cv"] / beta,
                       peak_acceleration_mm_per_deg2=h * peaks["Ca"] / beta**2,
                       peak_jerk_mm_per_deg3=h * peaks["Cj"] / beta**3 if math.isfinite(peaks["Cj"]) else math.inf,
                       overshoot=bool(low < -1e-9 or high > 1 + 1e-9))
        out.append(row)
    return out
