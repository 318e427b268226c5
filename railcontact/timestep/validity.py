"""Where a solved wheel is outside the model's validity, and why.

A wheel whose contact was solved (status ok) is *outside validity* when one of these holds
(SI units; each a bit of :attr:`~railcontact.timestep.WheelContact.validity`):

* ``Y_Q``: its derailment quotient ``Y/Q`` exceeds :attr:`ContactSettings.max_y_q`
  (EN 14363's 0.8 by default). ``Y`` is the lateral force of the wheel on the rail towards
  the rail's field side, ``Y = -s F_Y`` with ``F_Y`` the rail's force on the wheel along
  track Y and ``s = +1`` left, ``-1`` right; ``Q`` the rail's vertical force on the wheel.
* ``NADAL``: ``Y/Q`` exceeds Nadal's limit of the flange,
  ``(tan(beta) - mu) / (1 + mu tan(beta))`` with ``beta`` the steepest angle of the wheel's
  flange (:attr:`~railcontact.geometry.Wheelset.flange_flank`, S1002: 70 deg) and ``mu``
  the friction coefficient: the Y/Q of a flange in full sliding with the rail's friction
  on the wheel pointing up the flank (a leading wheel at a positive angle of attack),
  beyond which the wheel climbs.
* ``FLANGE_CLIMB``: a patch lies past the flange's steepest point, on its upper flank,
  at a contact angle more than :data:`FLANGE_CLIMB_MARGIN` below the steepest angle. (Past
  half of that angle the wheel has climbed its flange and the pose is out of range,
  :func:`~railcontact.contact.wheelrail.check_on_rail`.)
* ``PENETRATION``: a patch's normal penetration exceeds
  :attr:`ContactSettings.max_penetration`.
* ``LOAD``: ``Q`` exceeds :attr:`ContactSettings.max_wheel_load`.
* ``RESOLUTION``: a patch's contact spans fewer than
  :data:`~railcontact.normal.resolution.MIN_ELEMENTS_ACROSS` elements along x, the
  rolling direction (whatever y)
  (:func:`~railcontact.normal.resolution.under_resolved`): its
  pressure, area and creep forces are the grid's (the largest pressure 4 % to 50 % off
  Hertz's; a creep force along a narrow x 20-46 % off), not the contact's; smaller
  elements resolve it. A patch beside others that carries at most
  :attr:`ContactSettings.load_tolerance` of the wheel's normal force is not checked: the
  load loop's tolerance lets such a sliver appear or not (two starts of one step may end
  either side of its first touch), and whatever its grid makes of it moves the wheel's
  forces by less than that share.

The forces are still given; the status says not to trust them as a prediction.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from ..contact.results import PatchSolution
from ..normal.resolution import under_resolved
from ..settings import ContactSettings

Y_Q, NADAL, FLANGE_CLIMB, PENETRATION, LOAD, RESOLUTION = 1, 2, 4, 8, 16, 32
VALIDITY_NAMES = {Y_Q: "Y/Q above max_y_q", NADAL: "beyond Nadal's limit",
                  FLANGE_CLIMB: "flange climb", PENETRATION: "penetration above "
                  "max_penetration", LOAD: "wheel load above max_wheel_load",
                  RESOLUTION: "a patch under-resolved"}
"""The bits of a wheel's ``validity`` and their meaning."""
FLANGE_CLIMB_MARGIN = math.radians(1.0)
"""How far below the flange's steepest angle [rad] a contact past the steepest point
counts as climbing: the flank's straight part varies by less (S1002: 70.0 to 69.75 deg
over the first millimetre past its steepest point)."""


def nadal_limit(flange_angle: float, friction: float) -> float:
    """Nadal's limit ``(tan(beta) - mu) / (1 + mu tan(beta))`` of the derailment quotient
    Y/Q for a flange angle ``beta`` [rad] and friction coefficient ``mu`` [-]."""
    t = math.tan(flange_angle)
    return (t - friction) / (1.0 + friction * t)


def derailment_quotient(side_sign: int, track_force: Sequence[float]) -> float:
    """Y/Q [-] of a wheel from the rail's force on it in the track frame (X, Y, Z) [N]
    (module docstring); 0 without a vertical force."""
    q = float(track_force[2])
    return -side_sign * float(track_force[1]) / q if q > 0 else 0.0


@dataclass(frozen=True)
class Validity:
    """A wheel's validity check: the bits that are set and a message naming each
    quantity and its value ("" when none is)."""

    flags: int = 0
    message: str = ""


WITHIN = Validity()
"""A wheel within every limit."""


def check_validity(side_sign: int, track_force: Sequence[float],
                   patches: Sequence[PatchSolution], flange_flank: tuple[float, float],
                   settings: ContactSettings, friction: float | None = None) -> Validity:
    """The validity of a solved wheel (module docstring): :func:`check_limits` with each
    patch's contact point and the largest normal penetration of the patches, and
    ``RESOLUTION`` for a patch whose contact spans too few elements.

    Parameters
    ----------
    side_sign
        +1 for the left wheel, -1 for the right.
    track_force
        The rail's force on the wheel (X, Y, Z) in the track frame [N].
    patches
        The wheel's solved patches (their contact points and normal penetrations).
    flange_flank
        Profile coordinate S [m] and angle [rad] of the flange's steepest point.
    settings
        The limits (and the friction coefficient).
    friction
        The friction coefficient of Nadal's limit [-] (None: ``settings.friction``).
    """
    if len(patches) == 1:  # (the common case, as below without the generators)
        p = patches[0]
        g, n = p.geometry, p.normal
        contacts = [] if g is None else [(g.wheel_s, g.contact_angle)]
        v = check_limits(side_sign, track_force, contacts, n.penetration, flange_flank,
                         settings, friction)
        m = under_resolved(n.contact, n.grid.dx, n.grid.dy) if n.force > 0 else None
        coarse = [m] if m else []
    else:
        contacts = [(p.geometry.wheel_s, p.geometry.contact_angle) for p in patches
                    if p.geometry is not None]
        penetration = max((p.normal.penetration for p in patches), default=0.0)
        v = check_limits(side_sign, track_force, contacts, penetration, flange_flank,
                         settings, friction)
        # (a sliver within the load loop's tolerance: not checked, module docstring)
        least = settings.load_tolerance * sum(p.normal.force for p in patches)
        coarse = [m for m in (under_resolved(p.normal.contact, p.normal.grid.dx,
                                             p.normal.grid.dy)
                              for p in patches if p.normal.force > least) if m]
    if not coarse:
        return v
    return Validity(v.flags | RESOLUTION, "; ".join([m for m in (v.message, coarse[0]) if m]))


def check_limits(side_sign: int, track_force: Sequence[float],
                 contacts: Sequence[tuple[float, float]], penetration: float,
                 flange_flank: tuple[float, float], settings: ContactSettings,
                 friction: float | None = None) -> Validity:
    """The validity of a wheel from its resultants (module docstring); what
    :func:`check_validity` checks, also for a wheel without its patches (a table step).

    Parameters
    ----------
    side_sign
        +1 for the left wheel, -1 for the right.
    track_force
        The rail's force on the wheel (X, Y, Z) in the track frame [N].
    contacts
        Wheel profile coordinate S [m] and contact angle [rad] of each patch's contact
        point (for flange climb).
    penetration
        The largest normal penetration of the patches [m].
    flange_flank
        Profile coordinate S [m] and angle [rad] of the flange's steepest point.
    settings
        The limits (``max_y_q``, ``max_penetration``, ``max_wheel_load``) and the friction
        coefficient.
    friction
        The friction coefficient of Nadal's limit [-] (None: ``settings.friction``).
    """
    mu = settings.friction if friction is None else friction
    flags, why = 0, []
    yq = derailment_quotient(side_sign, track_force)
    q = float(track_force[2])
    if yq > settings.max_y_q:
        flags |= Y_Q
        why.append(f"Y/Q = {yq:.3g} above max_y_q = {settings.max_y_q:g}")
    s_steep, steepest = flange_flank
    limit = nadal_limit(steepest, mu)
    if yq > limit:
        flags |= NADAL
        why.append(f"Y/Q = {yq:.3g} beyond Nadal's limit {limit:.3g} (flange "
                   f"{math.degrees(steepest):.3g} deg, mu {mu:g})")
    for wheel_s, angle in contacts:
        if wheel_s < s_steep and abs(angle) < steepest - FLANGE_CLIMB_MARGIN:
            flags |= FLANGE_CLIMB
            why.append(f"flange climb: contact at S = {wheel_s * 1e3:.4g} mm at "
                       f"{math.degrees(abs(angle)):.3g} deg, past the flange's "
                       f"steepest point (S = {s_steep * 1e3:.4g} mm, "
                       f"{math.degrees(steepest):.3g} deg)")
            break
    if penetration > settings.max_penetration:
        flags |= PENETRATION
        why.append(f"normal penetration {penetration * 1e3:.3g} mm above max_penetration = "
                   f"{settings.max_penetration * 1e3:g} mm")
    if q > settings.max_wheel_load:
        flags |= LOAD
        why.append(f"wheel load Q = {q / 1e3:.4g} kN above max_wheel_load = "
                   f"{settings.max_wheel_load / 1e3:g} kN")
    return Validity(flags, "; ".join(why)) if flags else WITHIN


__all__ = ["FLANGE_CLIMB", "FLANGE_CLIMB_MARGIN", "LOAD", "NADAL", "PENETRATION",
           "RESOLUTION", "VALIDITY_NAMES", "WITHIN", "Y_Q", "Validity", "check_limits",
           "check_validity", "derailment_quotient", "nadal_limit"]
