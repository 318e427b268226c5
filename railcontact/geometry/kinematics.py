"""Rigid-body kinematics of a wheel on its rail: the creepages of a contact patch from the
wheelset's and the rail's velocities and the track curvature, as CONTACT forms them.

Everything is in the track frame ``(X, Y, Z)``: X forward, Y to the left, Z up, SI units
(:mod:`railcontact.geometry.track`). The frame follows the track: on a curve of curvature
``k`` (positive when the track turns left) the rails turn about the vertical axis through
the track centre line with the angular velocity ``-V k`` relative to it, so that a rail
point at ``Y`` moves forward with ``V k Y``; a wheelset that follows the curve has no yaw
rate in this frame. (The same rail motion with ``k = 0`` and the wheelset's yaw rate raised
by ``V k`` gives the same creepages when the wheelset is centred.)

At a patch, the contact frame has its origin at the patch's reference point ``P`` on the
rail, its x along the track, its normal ``n`` out of the rail (inclined by the contact angle
``gamma`` towards the track centre) and its lateral axis ``e`` in the contact plane towards
the field side. The wheel's point is ``Q = P - d n`` (``d`` the patch's normal approach:
the undeformed wheel surface). With ``v``, ``w`` the velocity and angular velocity of the
wheel at ``Q`` and of the rail at ``P``, and ``s = +1`` on the left and ``-1`` on the right
wheel (railcontact's side frame mirrors the right wheel)::

    xi  = (v_Q - v_P) . x / V_ref,   eta = (v_Q - v_P) . e / V_ref,
    phi = s (w_Q - w_P) . n / V_ref

(body 1 the wheel, as :mod:`railcontact.settings.convention`). The reference velocity is
CONTACT's: ``V_ref = (|v_est| + |v_pitch|) / 2`` with ``v_pitch`` the x-velocity of ``Q``
due to the wheelset's spin alone and ``v_est = v_Q,x - v_P,x - v_pitch`` (the forward
velocity of the wheel's point relative to the rail's without the spin). The wheelset's
angular velocity is ``R (roll_rate, spin_speed, yaw_rate)`` with ``R = R_x(roll) R_z(yaw)``
its orientation (the rates of its Euler angles taken as body rates, as CONTACT does).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import RailContactError

SIDE_SIGN = {"left": 1.0, "right": -1.0}


@dataclass(frozen=True)
class WheelsetMotion:
    """The velocities of a wheelset and of a rail (track frame, SI units).

    Attributes
    ----------
    speed
        Forward speed V of the wheelset along the track [m/s] (> 0).
    lateral_velocity, vertical_velocity
        Velocity of the wheelset centre along Y (to the left) and Z (up) [m/s].
    roll_rate, yaw_rate
        Rates of the wheelset's roll (about X) and yaw (about Z) [rad/s].
    spin_speed
        Angular speed of the axle [rad/s], positive when rolling forward (``V / r0`` rolls
        purely at the radius ``r0``).
    curvature
        Track curvature [1/m], positive when the track turns left (towards +Y).
    rail_velocity
        Velocity (Y, Z) of the rail [m/s].
    rail_roll_rate
        Angular velocity of the rail about X, about its profile origin [rad/s].
    """

    speed: float
    spin_speed: float
    lateral_velocity: float = 0.0
    vertical_velocity: float = 0.0
    roll_rate: float = 0.0
    yaw_rate: float = 0.0
    curvature: float = 0.0
    rail_velocity: tuple[float, float] = (0.0, 0.0)
    rail_roll_rate: float = 0.0


@dataclass(frozen=True)
class PatchKinematics:
    """The creepages of a patch and what they were formed from.

    Attributes
    ----------
    creepage
        (xi [-], eta [-], phi [1/m]) in railcontact's side frame (body 1 the wheel).
    velocity
        The reference velocity V_ref [m/s] the creepages are divided by (the rolling
        speed of the patch: frictional power = V_ref times the traction times the slip).
    rolling_radius
        Distance of the wheel's point Q from the axle, in the wheelset's frame [m].
    """

    creepage: tuple[float, float, float]
    velocity: float
    rolling_radius: float


def rotation(roll: float, yaw: float) -> np.ndarray:
    """The wheelset's orientation ``R_x(roll) R_z(yaw)`` (3, 3) (track frame; yaw first,
    as :mod:`railcontact.geometry.search` places the wheel)."""
    cr, sr, cy, sy = math.cos(roll), math.sin(roll), math.cos(yaw), math.sin(yaw)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return rx @ rz


def contact_axes(side: str, contact_angle: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The contact frame's axes in the track frame: x along the track, ``e`` in the
    contact plane towards the field side, ``n`` out of the rail, for the ``side`` wheel
    and its contact angle [rad] (side frame, positive towards the flange)."""
    s = SIDE_SIGN[side]
    c, g = math.cos(contact_angle), math.sin(contact_angle)
    return (np.array([1.0, 0.0, 0.0]), np.array([0.0, s * c, g]), np.array([0.0, -s * g, c]))


def patch_kinematics(side: str, point: Sequence[float], contact_angle: float,
                     approach: float, centre: Sequence[float], roll: float, yaw: float,
                     rail_origin: Sequence[float], motion: WheelsetMotion) -> PatchKinematics:
    """The creepages of a patch from rigid-body kinematics (module docstring).

    Parameters
    ----------
    side
        ``"left"`` or ``"right"``.
    point
        The patch's reference point P on the rail (X, Y, Z) [m], track frame.
    contact_angle
        Its contact angle [rad] (side frame, positive towards the flange).
    approach
        The patch's normal approach d [m]: the wheel's point is ``Q = P - d n``.
    centre
        The wheelset centre (X, Y, Z) [m].
    roll, yaw
        The wheelset's roll and yaw angles [rad].
    rail_origin
        The rail profile's origin (Y, Z) [m], the centre of the rail's roll rate.
    motion
        The velocities (:class:`WheelsetMotion`).

    Returns
    -------
    PatchKinematics
        The creepages, the reference velocity and the rolling radius at Q.

    Raises
    ------
    RailContactError
        For an unknown side or a reference velocity that is not positive (no rolling).
    """
    if side not in SIDE_SIGN:
        raise RailContactError(f"side must be 'left' or 'right', got {side!r}")
    s = SIDE_SIGN[side]
    ex, e, n = contact_axes(side, contact_angle)
    p = np.asarray(point, dtype=float)
    q = p - approach * n
    r = q - np.asarray(centre, dtype=float)
    rot = rotation(roll, yaw)
    m = motion
    spin_axis = rot @ np.array([0.0, m.spin_speed, 0.0])
    w_wheel = rot @ np.array([m.roll_rate, m.spin_speed, m.yaw_rate])
    v_wheel = np.array([m.speed, m.lateral_velocity, m.vertical_velocity]) + np.cross(w_wheel, r)
    v_pitch = float(np.cross(spin_axis, r)[0])
    w_rail = np.array([m.rail_roll_rate, 0.0, -m.speed * m.curvature])
    arm = p - np.array([0.0, rail_origin[0], rail_origin[1]])
    v_rail = (np.array([0.0, m.rail_velocity[0], m.rail_velocity[1]])
              + np.cross([m.rail_roll_rate, 0.0, 0.0], arm)
              + np.cross([0.0, 0.0, -m.speed * m.curvature], p))
    v_est = float(v_wheel[0] - v_rail[0]) - v_pitch
    v_ref = 0.5 * (abs(v_est) + abs(v_pitch))
    if not v_ref > 0:
        raise RailContactError(f"{side} wheel: no rolling (reference velocity {v_ref:g} m/s "
                               "from speed and spin speed)")
    dv, dw = v_wheel - v_rail, w_wheel - w_rail
    creepage = (float(dv @ ex) / v_ref, float(dv @ e) / v_ref, s * float(dw @ n) / v_ref)
    radius = -float((rot.T @ r)[2])
    return PatchKinematics(creepage, v_ref, radius)
