"""Which design objectives a program takes: the one place of the rules that depend on the
program alone, read by ``design_segment``, the objectives, the command line and the studio
(light to import: no JAX)."""

from __future__ import annotations

from ._program import Program

OBJECTIVES = ("residual", "ca-ct", "preload", "seating")
"""The objectives ``design_segment`` knows, in the order the command line and the studio
offer them."""

SEAT_NEEDED = ("the seating objective needs a valve seat: give the program's chain of bodies ([[train]]) a "
               "[seat] (the seating velocity is the last body's landing on it)")


def design_refusal(program: Program, objective: str) -> str | None:
    """Why ``design_segment`` cannot design ``program`` for ``objective``, in one line, or
    ``None`` where it can: the one place of the rules that depend on the program alone
    (``design_objectives`` lists what passes them; a segment's own rules, as a segment in
    motion refusing ``"ca-ct"``, are ``design_segment``'s)."""
    if objective not in OBJECTIVES:
        return f"objective must be one of {', '.join(OBJECTIVES)}, got {objective!r}"
    chain = program.chain
    if objective == "seating":
        return None if chain is not None and chain.seat is not None else SEAT_NEEDED
    if objective == "ca-ct" and not program.one_body:
        others = [o for o in OBJECTIVES if o != "ca-ct" and design_refusal(program, o) is None]
        return (f"objective 'ca-ct': a chain of bodies ([[train]]) is designed at its last body through the "
                f"whole chain: {' or '.join(others) if others else 'no objective applies to this chain'}")
    if chain is not None and chain.has_contacts:
        given = [f"[[train]] {b.name} lash_mm" for b in chain.bodies if b.lash_mm]
        given += ["[seat]"] if chain.seat is not None else []
        return (f"objective {objective!r}: the residual and preload objectives design through the exact steady "
                f"state of a chain without lash or seat, and this chain has {', '.join(given)}"
                + ("; objective 'seating' designs a chain with a seat (its valve's seating velocity)"
                   if chain.seat is not None else "; a chain with lash and no seat has no design objective"))
    if objective == "preload" and program.follower.form_closed:
        return "the preload objective needs a return spring (a force-closed cam)"
    return None


def design_objectives(program: Program) -> tuple[str, ...]:
    """The objectives of ``OBJECTIVES`` that ``design_segment`` takes for ``program``
    (those ``design_refusal`` lets pass), in that order."""
    return tuple(o for o in OBJECTIVES if design_refusal(program, o) is None)
