"""The warnings a program's report carries: sizes no machine has, a design past the usual
limits (pressure angle, Hertz half-width, moduli), an unsettled groove, a noisy or coarse
lift table."""

from __future__ import annotations

import math

import numpy as np

from ._program import Program
from ._speeds import speed_warnings
from ._train import CLASSIC_FIELDS

MODULUS_RANGE_GPA = (1.0, 1000.0)
"""Young's moduli of engineering solids, polymers to diamond: a value outside is taken for
a unit slip (a modulus in Pa or MPa)."""
MAX_HALF_WIDTH_RATIO = 0.1
"""Largest Hertz half-width ``b`` against the relative radius ``R'`` where the stress peaks
(``b / R' = 2 p / E*``) for which the Hertz line contact holds (it needs ``b << R'``)."""


ABSURD_SIZES = {"mm": 10_000.0, "kg": 10_000.0, "N": 1e6, "N/mm": 1e9, "": 100.0}
"""Sizes no cam machine has, by unit: a length past 10 m, a moving mass past 10 tonnes, a
force past a meganewton, a stiffness past 1e9 N/mm, a lever's ratio past 100.  A value past them is computed but
warned of (``size_warnings``): often a unit slip, and a length past 1e12 mm also loses the
cam's curvature to rounding."""
_SIZED_FIELDS = (("base_radius_mm", "mm"), ("roller_radius_mm", "mm"), ("offset_mm", "mm"), ("arm_mm", "mm"),
                 ("pivot_mm", "mm"), ("groove_clearance_mm", "mm"),  # contact_width_mm: against the base circle
                 ("mass_kg", "kg"), ("preload_n", "N"), ("stiffness_n_per_mm", "N/mm"),
                 ("spring_rate_n_per_mm", "N/mm"))


def size_warnings(program: Program) -> list[str]:
    """A line for each follower field and segment lift past ``ABSURD_SIZES``, naming the key
    and its value."""
    f = program.follower
    chain = program.chain
    given = [(f"follower.{name}", getattr(f, name), unit) for name, unit in _SIZED_FIELDS
             if getattr(f, name) is not None and not (name == "roller_radius_mm" and f.flat_face)
             and not (chain is not None and name in CLASSIC_FIELDS)]  # a chain's stand-in: its own below
    given += [] if chain is None else chain.sized_fields()
    given += [(f"segment {i}: lift_mm", s.lift_mm, "mm") for i, s in enumerate(program.segments, 1)]
    return [(f"{key} = {value:g} is more than {ABSURD_SIZES[unit]:,.0f} {unit}, larger than any cam machine's: "
             f"check its unit ({unit})") if unit else
            (f"{key} = {value:g} is more than {ABSURD_SIZES[unit]:,.0f}, larger than any cam machine's lever: "
             "check it (the body's motion over the body's before)")
            for key, value, unit in given if abs(value) > ABSURD_SIZES[unit]]


def sizes_first(program: Program) -> str:
    """The ``size_warnings`` a refusal says before its own remedy (empty where none): a size
    no machine has (a ratio of 1600, a stiffness in N/m) is the likelier cause of a grid or a
    step it asks for than the fields that remedy would name."""
    return "".join(f"{line}; else " for line in size_warnings(program))


MAX_SEAT_COMPRESSION_MM = 1.0
"""The most a valve's seat yields under the spring's preload at rest (mm): a seat is stiff
(tens of thousands of N/mm, a few microns under the preload); past this, or past the valve's
lift, its stiffness is taken for a unit slip."""


def seat_warnings(program: Program) -> list[str]:
    """A line where the seat's static compression under the spring's preload
    (``preload_n / stiffness_n_per_mm``) is more than ``MAX_SEAT_COMPRESSION_MM`` or the
    valve's lift through the chain (the cam's largest lift times the ratios): the valve sinks
    into its seat, and may never leave it."""
    chain = program.chain
    if chain is None or chain.seat is None or chain.spring is None:
        return []
    squeeze = chain.spring.preload_n / chain.seat.stiffness_n_per_mm
    lift = chain.lever_ratio * program.largest_lift_mm()
    limit = min(MAX_SEAT_COMPRESSION_MM, lift)
    if squeeze <= limit:
        return []
    return [f"[seat] stiffness_n_per_mm = {chain.seat.stiffness_n_per_mm:g}: the spring's preload "
            f"({chain.spring.preload_n:g} N) compresses the seat by {squeeze:.3g} mm at rest, more than "
            f"{limit:.3g} mm (the lesser of {MAX_SEAT_COMPRESSION_MM:g} mm and the valve's lift, {lift:.3g} mm): "
            "a valve's seat yields microns; check its unit (N/mm)"]


LIFT_ERROR_RATIO = 0.5
"""A train's last body whose largest lift error reaches this part of its kinematic lift (the
cam's largest lift times the ratios) does not follow the cam: a valve that barely opens, or
never leaves its seat, is not a result to read as it stands (``lift_error_warnings``)."""


def _softest_give(chain, preload: float) -> str:
    """The chain's field that takes most of the valve's lift, with how much: each element's
    compression under the spring's preload ``P`` at the last body, ``P (prod_{i > j} r_i)^2 /
    k_j`` (its force and its compression both referred through the levers after it), the
    seat's ``P / k_seat`` and, with a seat (the lash open at rest), each lash at the last body,
    ``lash_j prod_{i > j} r_i``; without a preload, the element of the largest compliance there."""
    if chain.arm is not None:  # the bodies sit on the arm, which bends: no element of their own
        return "[arm] (its bending)"
    gives, after = [], 1.0  # (field, mm at the last body, compliance there, what it does, action)
    for j in range(len(chain.bodies), 0, -1):
        body = chain.bodies[j - 1]
        if body.rides or not body.stiffness_n_per_mm:
            continue
        field = f"[[train]] body {j} ({body.name})"
        compliance = after**2 / body.stiffness_n_per_mm
        gives.append((f"{field} stiffness_n_per_mm = {body.stiffness_n_per_mm:g}", preload * compliance,
                      compliance, "the spring's preload, {P} N, compresses it by {mm} mm", "stiffen it"))
        if body.lash_mm and chain.seat is not None:
            gives.append((f"{field} lash_mm = {body.lash_mm:g}", body.lash_mm * after, 0.0,
                          "{mm} mm of it", "lessen it"))
        after *= body.ratio
    if chain.seat is not None:
        compliance = 1.0 / chain.seat.stiffness_n_per_mm
        gives.append((f"[seat] stiffness_n_per_mm = {chain.seat.stiffness_n_per_mm:g}", preload * compliance,
                      compliance, "the spring's preload, {P} N, squeezes it by {mm} mm", "stiffen it"))
    if not gives:
        return "[[train]] stiffness_n_per_mm"
    field, mm, _, what, action = max(gives, key=lambda g: (g[1], g[2]) if preload else g[2])
    if not preload:
        return f"{field}: {action}"
    return f"{field} ({what.format(P=f'{preload:g}', mm=f'{mm:.4g}')} at the last body): {action}"


def lift_error_warnings(program: Program, report: dict) -> list[str]:
    """One line where a train's last body misses its kinematic lift (the cam's largest lift
    times the ratios) by ``LIFT_ERROR_RATIO`` of it or more at some speed of ``report``:
    the valve barely follows the cam (with a seat, it may never leave it), so the forces and
    the seating are those of a valve that does not open.  It names the speeds and the field
    that takes most of the valve's lift (``_softest_give``), with how much."""
    chain, train = program.chain, (report or {}).get("train")
    if chain is None or not train:
        return []
    valve = chain.lever_ratio * program.largest_lift_mm()
    bad = [s for s in train["speeds"] if s["max_lift_error_mm"] >= LIFT_ERROR_RATIO * valve]
    if not bad or valve <= 0:
        return []
    worst = max(bad, key=lambda s: s["max_lift_error_mm"])
    preload = chain.spring.preload_n if chain.spring is not None else 0.0
    name, speeds = chain.bodies[-1].name, ", ".join(f"{s['rpm']:g}" for s in bad)
    return [f"at {speeds} rpm the last body ({name}) misses its "
            f"kinematic lift ({valve:.4g} mm: the cam's lift times the ratios) by up to "
            f"{worst['max_lift_error_mm']:.4g} mm ({100 * worst['max_lift_error_mm'] / valve:.3g}%, "
            f"at {worst['rpm']:g} rpm): it barely follows the cam"
            + (" and may never leave its seat" if chain.seat is not None else "")
            + f"; the chain gives most at {_softest_give(chain, preload)}"]


def design_warnings(program: Program, report=None) -> list[str]:
    """Where the input or a result lies outside what the design rules and the models hold,
    one line each (empty where all is well): the program's own numbers (sizes past
    ``ABSURD_SIZES``, a grooved cam's preload, a lift table's noise or spacing among them), and
    with ``report`` (``analyse``'s ``Report`` or its ``as_dict()``) its speeds
    (``speed_warnings``), the pressure angle, the Hertz contact and a grooved cam's strikes
    that did not settle.

    Each is a warning, not an error: the numbers are computed, but they are not to be
    trusted as they stand.  ``analyse`` puts them in its report (``Report.warnings``, in
    ``--format json`` and the studio); ``camjax program`` prints them on stderr.
    """
    out = table_warnings(program)  # first: a drawing's or table's note says what was read
    f, materials = program.follower, program.materials
    report = report.as_dict() if hasattr(report, "as_dict") else report
    limit = f.geometry.max_pressure_angle_deg  # a roller's: 30 degrees translating, 45 swinging
    angle = ((report or {}).get("geometry") or {}).get("max_pressure_angle_deg")
    if limit is not None and angle is not None and abs(angle) > limit:
        out.append(f"the pressure angle reaches {abs(angle):.3g} deg, above the {limit:g} deg a "
                   f"{f.kind} follower tolerates: enlarge follower.base_radius_mm "
                   "or lengthen the rises")
    out += size_warnings(program)
    out += seat_warnings(program)
    if f.form_closed and f.preload_n != 0:
        out.append(f"follower.preload_n = {f.preload_n:g} does nothing on a grooved cam (no "
                   "spring_rate_n_per_mm: no return spring preloads the follower, the groove holds it): "
                   "remove it, or give the return spring's spring_rate_n_per_mm")
    stroke = max(abs(float(y)) for y in np.cumsum([s.lift_mm for s in program.segments]))
    if stroke > 2 * f.base_radius_mm:
        out.append(f"the lift ({stroke:g} mm) is more than twice the base circle's radius "
                   f"({f.base_radius_mm:g} mm): check the program's units")
    low, high = MODULUS_RANGE_GPA
    for part in ("cam", "follower"):
        modulus = getattr(materials, f"{part}_youngs_modulus_gpa")
        if not low <= modulus <= high:
            out.append(f"materials.{part}_youngs_modulus_gpa = {modulus:g} lies outside {low:g}-{high:g} "
                       "GPa (steel is about 210): check the unit (GPa, not Pa or MPa)")
    if f.contact_width_mm is None and materials != type(materials)():
        out.append("[materials] is used only for the Hertz contact stress, which needs "
                   "follower.contact_width_mm: without it no stress is computed")
    if f.contact_width_mm is not None and f.contact_width_mm > 20 * f.base_radius_mm:
        out.append(f"follower.contact_width_mm = {f.contact_width_mm:g} is more than ten times the "
                   f"base circle's diameter: check the unit (mm)")
    if report is None:
        return out
    out += speed_warnings(program, [s["rpm"] for s in report["speeds"]])
    worst = max((s for s in report["speeds"] if s.get("contact_half_width_mm")),
                key=lambda s: s["max_contact_stress_mpa"], default=None)
    if worst is not None:
        ratio = 2 * worst["max_contact_stress_mpa"] / materials.contact_modulus_mpa  # b / R'
        if ratio > MAX_HALF_WIDTH_RATIO:
            radius = worst["contact_half_width_mm"] / ratio
            out.append(f"at {worst['rpm']:g} rpm the Hertz contact half-width "
                       f"({worst['contact_half_width_mm']:.3g} mm) is {ratio:.3g} times the relative "
                       f"radius of the contact ({radius:.3g} mm), past the {MAX_HALF_WIDTH_RATIO:g} "
                       "where Hertz theory holds: its stress "
                       f"({worst['max_contact_stress_mpa']:.3g} MPa) is not to be trusted; check "
                       "follower.contact_width_mm and the moduli")
    out += _unsettled_grooves(report["speeds"])
    out += lift_error_warnings(program, report)
    return out


def _unsettled_grooves(speeds) -> list[str]:
    """A grooved cam's strikes that still moved from turn to turn after the longest run."""
    from ._groove import MAX_GROOVE_SAMPLES, MAX_TURNS, SETTLED_DEG

    out = []
    for s in speeds:
        change = s.get("impacts_change_deg")
        if change is not None and not change <= SETTLED_DEG:
            out.append(f"at {s['rpm']:g} rpm the groove's strikes had not settled within the longest run "
                       f"allowed ({MAX_TURNS} turns, {MAX_GROOVE_SAMPLES:,} samples; "
                       + (f"they still move by {change:.3g} deg per turn" if math.isfinite(change) else
                          "they still differ in number or flank from turn to turn")
                       + "): the roller chatters without a period, and the last turn is reported; a "
                       "narrower groove (groove_clearance_mm) or more damping settles sooner")
    return out


NOISY_ACCELERATION_RATIO = 1.2
"""A table fit's peak acceleration this many times that of a fit smoothed to three times the
points' scatter: the noise, not the cam, sets its accelerations."""
COARSE_SPACING_CHANGE = 0.05
"""A change of the peak acceleration this large when every other point of a table is
dropped: the spacing does not resolve the acceleration."""


def table_warnings(program: Program) -> list[str]:
    """The lift tables' warnings: points noisy or sparse enough to make the accelerations
    unreliable (``camjax.laws.TableFit``'s two checks), once per table."""
    out, seen = [], set()
    for i, seg in enumerate(program.segments, 1):
        fit = getattr(seg.law, "fit_info", None)
        if fit is None or (fit.turn is not None and fit.turn in seen):
            continue
        where = "the cam's lift table" if fit.turn is not None else f"segment {i}: the lift table"
        if fit.turn is not None:
            seen.add(fit.turn)
        where += f" ({fit.source})"
        out += list(fit.notes)
        if fit.acceleration_ratio > NOISY_ACCELERATION_RATIO:
            out.append(f"{where}: the points scatter by about {fit.noise_mm:.2g} mm; the fit's peak "
                       f"acceleration is {fit.acceleration_ratio:.3g} times that of a fit within "
                       f"{3 * fit.noise_mm:.2g} mm of them, so its accelerations and forces follow the "
                       f"noise: set smoothing_mm = {3 * fit.noise_mm:.2g} (about three times the scatter)")
        elif math.isnan(fit.spacing_ratio):
            count = len(fit.turn if fit.turn is not None else fit.points)
            out.append(f"{where}: its {count} points are too few to check that they resolve the "
                       "acceleration (a fit through every other point needs 6); give points closer together")
        elif abs(fit.spacing_ratio - 1) > COARSE_SPACING_CHANGE:
            angles = [a for a, _ in (fit.turn if fit.turn is not None else fit.points)]
            spacing = max(np.diff(angles + ([360.0] if fit.turn is not None else [])))
            out.append(f"{where}: its points (up to {spacing:.3g} deg apart) are too sparse for its "
                       f"acceleration: against {fit.spacing_check}, the peak acceleration differs "
                       f"by {100 * abs(fit.spacing_ratio - 1):.3g}%; give points closer together")
    return out
