"""Roll angle of a rigid wheelset standing on both rails.

A wheelset displaced laterally by ``y`` (and yawed by ``psi``) rolls about the track axis
X because its two wheels touch the rails at different rolling radii. With both wheels
lowered together by the same vertical distance, the wheelset is in contact on both sides
when the first-contact heights of the two wheels agree; with elastic approaches
``delta_left`` and ``delta_right`` (the rigid interpenetrations that carry each wheel's
load) they must differ by ``delta_right - delta_left``:

    m_left(phi) - m_right(phi) = delta_right - delta_left,

``m_s(phi)`` the smallest vertical gap between wheel ``s`` and its rail for roll ``phi``
(:func:`first_contact_gap`). Rolling by ``phi`` about the track axis raises the left contact
by about ``l phi`` (``l`` ~ 0.75 m, half the contact-point distance) and moves it towards
the field side by ``r phi`` (``r`` the wheel radius), which on a contact angle ``gamma``
closes the gap by ``r phi tan(gamma)``; with the right wheel mirrored, the left-hand side
grows at ``2 l - r tan(gamma_left) - ...`` per radian: fast on the treads (about 1.5 m/rad),
slowly with a 70 deg flange in contact (about 0.2 m/rad), and strictly while
``tan(gamma) < 2 l / r`` (gamma below ~73 deg, above any S1002 flange angle). The root is
found by Brent's method on +-:data:`MAX_ROLL`.

``offset = 0`` is the kinematic (rigid-body) roll used for rolling-radius-difference
tables; the Manchester contact benchmark solves the roll for equal wheel loads
(:func:`railcontact.contact.wheelrail.solve_wheel_rail` with ``roll = "equal-loads"``).
"""

from __future__ import annotations

from scipy.optimize import brentq

from ..errors import RailContactError, check_finite
from .search import least_gap
from .track import Pose, Track, Wheelset

MAX_ROLL = 0.05
"""Largest roll angle searched [rad] (both directions)."""
ROLL_XTOL = 1e-10
"""Absolute tolerance on the roll angle [rad]."""


def first_contact_gap(track: Track, ws: Wheelset, pose: Pose, side: str) -> float:
    """Smallest vertical gap [m] between the wheel ``side`` and its rail at ``pose``.

    Measured with the wheelset axle at the nominal height (axle ``wheel_radius`` above the
    top of rail); negative when the wheel penetrates the rail.
    """
    return least_gap(track, ws, pose, side)  # (vertical_gap's least g, the trace remembered)


def contact_roll(track: Track, ws: Wheelset, lateral: float, yaw: float = 0.0,
                 offset: float = 0.0) -> float:
    """Roll angle [rad] at which the rigid wheelset touches both rails.

    Parameters
    ----------
    track, ws
        Track and wheelset.
    lateral
        Wheelset lateral displacement [m], positive to the left.
    yaw
        Yaw angle [rad].
    offset
        Required first-contact gap of the left wheel minus that of the right wheel [m]:
        0 for rigid contact on both sides, ``delta_right - delta_left`` (vertical
        approaches of the loaded wheels) for elastic contact.

    Returns
    -------
    float
        Roll angle phi [rad], positive when the left side rises (right-hand rule about X).

    Raises
    ------
    RailContactError
        When no roll within +-:data:`MAX_ROLL` rad puts both wheels on their rails.
    """
    check_finite("offset", offset, "m")

    def residual(phi: float) -> float:
        pose = Pose(lateral, yaw, phi)
        return (first_contact_gap(track, ws, pose, "left")
                - first_contact_gap(track, ws, pose, "right") - offset)

    lo, hi = residual(-MAX_ROLL), residual(MAX_ROLL)
    if lo > 0 or hi < 0:
        raise RailContactError(
            f"no roll angle within +-{MAX_ROLL} rad puts both wheels on their rails "
            f"(lateral displacement {lateral:g} m, yaw {yaw:g} rad)")
    return float(brentq(residual, -MAX_ROLL, MAX_ROLL, xtol=ROLL_XTOL))
