"""Design one segment's law of a program for a speed range (a thin layer over ``camjax.design``).

A speed range ``[rpm_lo, rpm_hi]`` maps to the segment's period-ratio band
``n = f_n t_segment = f_n (angle / 360) 60 / rpm``, from ``n(rpm_hi)`` to ``n(rpm_lo)``,
with the oscillator's damping ratio ``zeta sqrt(k / (k + k_s))``.
"""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import jax.numpy as jnp
import numpy as np

from .. import laws
from ._motion import MATCH, is_polynomial
from ._objective_rules import design_refusal
from ._program import Program, segment_band, with_law


def design_segment(program: Program, segment: int, rpm_lo: float, rpm_hi: float, *,
                   objective: str = "residual", caps=None, **design_options):
    """Design segment ``segment``'s law for the speed range; returns ``(new program, DesignResult)``.

    ``objective`` is ``"residual"`` (largest residual vibration over the band), ``"ca-ct"``
    (largest Ca*Ct), both for the segment alone at the oscillator's damping, or
    ``"preload"`` (largest preload the whole program needs over the speed range,
    ``MaxPreload``); ``design_options`` go to ``camjax.design`` (``knots``, ``steps``, ``progress``, ...).
    For a chain of bodies (``Program.chain``) both are the whole chain's: ``"residual"`` the
    last body's residual vibration (``MaxProgramResidual``), ``"preload"`` the spring's
    preload that keeps the cam's contact (through the levers); ``"ca-ct"`` is refused.
    ``"seating"`` (a chain with a seat only) is the valve's largest seating velocity over the
    speed range, simulated with the chain's contacts (``MaxSeatingVelocity``: on
    ``seating_speeds`` speeds, default 8 per natural-frequency cycle gained, with
    ``contact_options``), designed in ``rounds`` of its linear model (``seating_design``).
    An objective the program does not take is refused in one line (``design_refusal``;
    ``design_objectives`` lists those it takes).

    A segment that starts or ends in motion (a polynomial, constant velocity, any law whose
    end velocity is not zero) is designed as a ``CorrectedPolynomial``
    from the ``BoundaryPolynomial`` of its end states, so every join keeps its state; for it
    ``"residual"`` is the largest residual vibration of the whole program over the speed
    range (``MaxProgramResidual``: the segment's own rise is not from rest to rest),
    ``"ca-ct"`` does not apply, and the monotone cap only where that polynomial is monotone.
    Where a neighbour is a degree-7 polynomial that matches this segment (it reads the end
    jerk too), the start is the degree-7 polynomial of the end states and jerks, so the
    design keeps the jerk and the neighbour's law stays what the design trained with.

    The result's ``initial_values`` hold the objective of the segment's own law, reported
    as the design's; a design that does not beat it returns the program unchanged (the
    result's ``law`` the segment's, ``kept_initial`` true) with a ``DesignNotImproved`` warning.
    """
    from .. import law_design
    from ._objectives import MaxPreload, MaxProgramResidual  # import optax: only when designing
    from ._seating import MaxSeatingVelocity, seating_design

    n1, n2 = segment_band(program, segment, rpm_lo, rpm_hi)
    f = program.follower
    zeta = f.damping_ratio * (f.stiffness / (f.stiffness + f.spring_rate)) ** 0.5
    seating_options = {key: design_options.pop(key) for key in ("seating_speeds", "contact_options")
                       if key in design_options}
    if seating_options and objective != "seating":
        raise ValueError(f"{', '.join(seating_options)}: only with objective 'seating', got {objective!r}")
    refusal = design_refusal(program, objective)
    if refusal is not None:
        raise ValueError(refusal)
    if objective == "seating":  # the valve's landing on its seat, simulated with the chain's contacts
        goal = MaxSeatingVelocity(program, segment, float(rpm_lo), float(rpm_hi),
                                  count=seating_options.get("seating_speeds"),
                                  options=seating_options.get("contact_options"))
    elif not program.one_body and objective == "residual":  # the last body's, through the chain
        goal = MaxProgramResidual(program, segment, float(rpm_lo), float(rpm_hi))
    elif objective == "residual":
        goal = law_design.MaxResidual(n1, n2, damping=zeta)
    elif objective == "ca-ct":
        goal = law_design.MaxCaCt(n1, n2, damping=zeta)
    else:
        goal = MaxPreload(program, segment, float(rpm_lo), float(rpm_hi), damping=zeta)
    seg = program.segments[segment - 1]
    caps = caps or law_design.Caps()
    jerk = _jerk_matched(program, segment)
    initial = _in_motion_start(seg.law, jerk)
    if initial is None:
        initial = seg.law
    elif _moves_at_ends(seg.law):
        if objective == "ca-ct":
            raise ValueError(f"segment {segment} starts or ends in motion: the ca-ct objective "
                             "measures a rise from rest to rest; use preload or residual")
        if objective == "residual" and program.one_body:
            goal = MaxProgramResidual(program, segment, float(rpm_lo), float(rpm_hi), damping=zeta)
    if isinstance(initial, laws.BoundaryPolynomial | laws.CorrectedPolynomial):
        base = initial if isinstance(initial, laws.BoundaryPolynomial) else initial.base
        monotone = float(jnp.min(base.v(jnp.linspace(0.0, 1.0, 20001)))) >= -1e-12
        caps = dataclasses.replace(caps, monotone=caps.monotone and monotone)
    run = seating_design if objective == "seating" else law_design.design
    result = run(goal, caps=caps, initial=initial, **design_options)
    # The figure to beat is the segment's own law's, reported by the same objective on the
    # same speeds: the design's start where that is the law itself (a polynomial rebuilt
    # from its end states), else reported apart (the start is a B-spline fit of it).
    label = goal.label
    exact = isinstance(initial, laws.BoundaryPolynomial) and isinstance(
        seg.law, laws.ConstantVelocity | laws.BoundaryPolynomial)
    start = result.initial_values[label] if exact else goal.report(seg.law)
    if result.kept_initial and exact:  # the design has warned already
        result = dataclasses.replace(result, law=seg.law)
    elif not result.values[label] < start:
        warnings.warn(f"segment {segment}: the design did not improve on the segment's own law "
                      f"({label}: {result.values[label]:.6g} designed against {start:.6g}); the "
                      "program is returned unchanged", law_design.DesignNotImproved, stacklevel=2)
        result = dataclasses.replace(result, law=seg.law, values={label: start}, kept_initial=True)
    result = dataclasses.replace(result, initial_values={label: start})
    return with_law(program, segment, result.law), result


def _jerk_matched(program: Program, segment: int) -> bool:
    """Whether a neighbour is a degree-7 polynomial whose facing end is ``"match"``: it
    reads this segment's end jerk, so a design that moved it would change the neighbour."""
    n = len(program.segments)
    before, after = program.segments[(segment - 2) % n], program.segments[segment % n]
    return any(is_polynomial(s) and s.law.degree == 7 and getattr(s, key) == MATCH
               for s, key in ((before, "end"), (after, "start")))


def _moves_at_ends(law) -> bool:
    _, v, _, _ = (np.asarray(x, dtype=float) for x in law.evaluate(np.array([0.0, 1.0])))
    return bool(np.any(np.abs(v) >= 1e-12))


def _in_motion_start(law, keep_jerk: bool = False):
    """The law a design of a segment in motion starts from, or ``None`` for a rest-to-rest law.

    With ``keep_jerk`` (a neighbour matches this segment's jerk) the start is a degree-7
    polynomial meeting the law's end jerk too, and the design's correction keeps it.
    """
    degree = 7 if keep_jerk else 5
    if isinstance(law, laws.BoundaryPolynomial) and law.degree >= degree:
        return law
    if isinstance(law, laws.CorrectedPolynomial) and law.base.degree >= degree:
        return law
    if not keep_jerk and laws.rest_to_rest_fault(law) is None:  # from and to rest: the rest-to-rest B-spline meets it
        return None
    # In motion, or a reversal (the double harmonic): keep the end states.
    _, v, a, j = (np.asarray(x, dtype=float) for x in law.evaluate(np.array([0.0, 1.0])))
    if keep_jerk:
        return laws.BoundaryPolynomial(v0=v[0], a0=a[0], v1=v[1], a1=a[1], j0=j[0], j1=j[1], degree=7)
    return laws.BoundaryPolynomial(v0=v[0], a0=a[0], v1=v[1], a1=a[1], degree=5)


def write_program(program: Program, directory) -> Path:
    """Write ``program.toml`` into ``directory``, with laws not in the registry as JSON beside it."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    files = {}
    for i, law in program.unnamed_laws().items():
        files[i] = f"segment{i}.json"
        laws.save(law, directory / files[i])
    path = directory / "program.toml"
    path.write_text(program.to_toml(law_files=files))
    return path

