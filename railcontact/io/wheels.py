"""The wheels of a wheel-rail case's solution, as a time step reports its wheels: each
wheel's force from the rail in the track frame, its derailment quotient Y/Q and whether it
is within the model's validity (:func:`~railcontact.timestep.validity.check_validity`:
Y/Q against ``max_y_q`` and Nadal's limit, flange climb, penetration, wheel load, a patch
under-resolved; the limits are :class:`~railcontact.settings.ContactSettings`' defaults).

A case's solve answers the contact problem it poses, whatever the pose; this says where
that pose lies beyond what the model predicts well (e.g. a wheel that has climbed past its
flange's steepest point), as a time step's status ``OUTSIDE_VALIDITY`` does. Nadal's
limit takes the case's coefficient of friction (with a friction table, the largest of
its patches'); a case without a tangential problem has no creep forces, and its limit is
that of a frictionless flange.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..contact import Solution
from ..contact.wheelrail import case_wheelset
from ..geometry.track import SIDES, Pose
from ..settings import ContactSettings, WheelRailGeometry
from ..timestep.results import resultants
from ..timestep.validity import Validity, check_validity


@dataclass(frozen=True)
class CaseWheel:
    """One wheel of a wheel-rail case's solution (SI units)."""

    side: str
    """"left" or "right"."""
    track_force: tuple[float, float, float]
    """The rail's force on the wheel (X, Y, Z) in the track frame [N]."""
    derailment_quotient: float
    """Y/Q [-]: the wheel's lateral force on the rail towards its field side over its
    vertical force (:func:`~railcontact.timestep.validity.derailment_quotient`)."""
    validity: Validity
    """The bits of the limits it is beyond and a message naming each (0 and "" within
    them)."""

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return {"side": self.side, "track_force": list(self.track_force),
                "derailment_quotient": self.derailment_quotient,
                "validity": self.validity.flags, "validity_message": self.validity.message}


_LIMITS = ContactSettings()
"""The limits of validity checked (the time step's defaults)."""


def case_wheels(solution: Solution) -> list[CaseWheel]:
    """The wheels of ``solution`` that carry a load (left first), with their resultants
    and validity (module docstring); none for a quadratic case."""
    geo = solution.case.geometry
    if not isinstance(geo, WheelRailGeometry):
        return []
    wheelset = case_wheelset(geo)  # (read by the solve already)
    # the roll the patches were solved at (resolved for "rigid" or "equal-loads")
    pose = Pose(geo.lateral_displacement, geo.yaw, solution.roll)
    tangential = solution.case.tangential
    out = []
    for side in SIDES:
        patches = [p for p in solution.patches if p.geometry is not None
                   and p.geometry.side == side and p.normal.force > 0]
        if not patches:
            continue
        values = resultants(side, patches, pose)
        mu = 0.0  # (no creep forces: a frictionless flange)
        if tangential is not None:
            mu = max((p.friction for p in patches if p.friction is not None),
                     default=tangential.friction if isinstance(tangential.friction, float)
                     else 0.0)
        validity = check_validity(SIDES[side], values["track_force"], patches,
                                  wheelset.flange_flank, _LIMITS, friction=mu)
        out.append(CaseWheel(side, tuple(values["track_force"]),
                             values["derailment_quotient"], validity))
    return out


__all__ = ["CaseWheel", "case_wheels"]
