"""The wheelset's vertical displacement and roll that give each wheel its approach.

Under load control each wheel is pressed into its rail by the vertical approach
``delta_s`` [m] its load needs, at the pose's roll ``phi0``, the two wheels independently.
A rigid wheelset has two vertical degrees of freedom; this finds the vertical displacement
``v`` [m] (of the centre, positive up, from the height ``r0`` above the rail tops, as the
input ``vertical`` of penetration control) and the roll ``phi`` [rad] at which both wheels
have those approaches::

    delta_s = -(m_s(phi) + v),      s = left, right,

``m_s(phi)`` the first-contact gap of wheel ``s`` with the wheelset rolled to ``phi``
(:func:`railcontact.geometry.roll.first_contact_gap`). The difference of the two equations,
``F(phi) = m_L + delta_L - m_R - delta_R = 0``, is solved by Newton's method from ``phi0``
with the slope of :mod:`railcontact.geometry.roll`: rolling by ``dphi`` raises the left
contact by ``l dphi`` and moves it towards its field side by ``r dphi``, closing its gap by
``r tan(gamma) dphi``, and the right one the other way round, so
``dF/dphi = l_L - r_L tan(gamma_L) + l_R - r_R tan(gamma_R)`` (``l`` the contact's lateral
distance from the centre, ``r`` its rolling radius); then a secant step, and ``v`` from the
mean of the two equations. A wheel without contact counts as just touching (``delta = 0``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from ..errors import RailContactError
from ..geometry.roll import MAX_ROLL, first_contact_gap
from ..geometry.track import SIDES, Pose, Track, Wheelset

RIGID_TOL = 1e-8
"""Residual [m] of the two wheels' vertical positions at which the iteration stops: each
wheel's approach (about 0.1 mm) is then met to 5 nm, 5e-5 of it, a load error below the
load loop's tolerance (1e-3)."""
MAX_EVALUATIONS = 3
"""At most this many evaluations of both wheels' first-contact gaps."""


def vertical_and_roll(track: Track, ws: Wheelset, pose: Pose,
                      approaches: Sequence[float],
                      contacts: Sequence[tuple[float, float, float] | None]
                      ) -> tuple[float, float]:
    """``(v, phi)``: vertical displacement [m] and roll [rad] of the rigid wheelset at
    which the left and right wheels have the vertical ``approaches`` [m] (module
    docstring).

    Parameters
    ----------
    track, ws, pose
        Geometry and the pose the wheels were solved at (its roll is the start).
    approaches
        Vertical approach of the left and right wheel beyond first contact [m].
    contacts
        Per wheel, (lateral position Y of the contact point [m], rolling radius [m],
        contact angle [rad]) of its main patch, or None without contact.
    """
    slope = 0.0
    for side, c in zip(SIDES, contacts, strict=True):
        if c is None:  # the taping line on a flat tread
            lever, radius, angle = float(ws.axial_position(0.0)), ws.radius, 0.0
        else:
            lever, radius, angle = SIDES[side] * (c[0] - pose.lateral), c[1], c[2]
        slope += lever - radius * math.tan(angle)
    slope = max(slope, 0.1)  # a 73 deg flange on both wheels: keep the direction

    def gaps(phi: float) -> tuple[float, float]:
        p = Pose(pose.lateral, pose.yaw, phi)
        return (first_contact_gap(track, ws, p, "left") + approaches[0],
                first_contact_gap(track, ws, p, "right") + approaches[1])

    phi = pose.roll
    last: tuple[float, float] | None = None
    for _ in range(MAX_EVALUATIONS):
        try:
            hl, hr = gaps(phi)
        except RailContactError:  # rolled beyond the profiles: keep the last one
            if last is None:
                raise
            break
        f = hl - hr
        if last is not None and f != last[1] and phi != last[0]:
            secant = (f - last[1]) / (phi - last[0])
            if secant > 0:
                slope = secant
        last = (phi, f)
        v = -0.5 * (hl + hr)
        if abs(f) <= RIGID_TOL:
            break
        phi = min(max(phi - f / slope, -MAX_ROLL), MAX_ROLL)
    return v, last[0]


@dataclass(frozen=True)
class RigidWheelset:
    """The data of :func:`vertical_and_roll`, kept by a load-controlled step's result
    until its vertical displacement or roll is asked for (a picklable record)."""

    track: Track
    wheelset: Wheelset
    pose: Pose
    approaches: tuple[float, float]
    contacts: tuple[tuple[float, float, float] | None, ...]

    def solve(self) -> tuple[float, float]:
        """``(v, phi)`` [m, rad] (:func:`vertical_and_roll`)."""
        return vertical_and_roll(self.track, self.wheelset, self.pose, self.approaches,
                                 self.contacts)


__all__ = ["RigidWheelset", "vertical_and_roll"]
