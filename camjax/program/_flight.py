"""One loss of the cam's contact, as the report gives it: the classic follower's flights
(``_jump.py``, closed form) and a chain's (``_chain_contacts.py``, simulated) alike."""

from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True)
class Flight:
    """One loss of contact: separation and re-impact angles (degrees), impact velocity (m/s),
    peak contact force from the impact to the next separation (N)."""

    separation_deg: float
    reimpact_deg: float | None
    impact_velocity_m_s: float | None
    peak_impact_force_n: float | None

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)
