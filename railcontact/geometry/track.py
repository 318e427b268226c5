"""Track and wheelset: where the rails and wheels are, in one frame per side.

Track frame: X along the track (forward), Y lateral **positive to the left**, Z up.
Each side is handled in its own *side frame* ``(X, u, Z)`` with ``u = s Y``, ``s = +1`` for
the left and ``-1`` for the right rail, so that ``u`` points to that side's field side and
one profile (written with y to the field side) serves both sides. Mirroring Y reverses
rotations about Z and X: in the side frame the yaw is ``s psi`` and the roll ``s phi``.

Rail placement (side frame): the profile is canted by the inclination with its top towards
the track centre, its highest point at ``Z = 0``, and its gauge point - the gauge-side
point ``gauge_depth`` (14 mm) below the top - at ``u = gauge / 2``. A deviation of the rail
from that place (an irregularity, a gauge change) then turns the placed profile about its
own origin by ``tilt`` (the same sense as the inclination) and shifts it by ``shift``
``(du, dZ)``, as CONTACT places a rail with its deviations (so a tilted rail's gauge point
and top move a little); :meth:`Track.deviated` sets them from the track frame's values.

Wheel placement: the wheel profile coordinate ``S`` (y of the wheel profile) and the axial
coordinate ``eta`` (from the wheelset centre towards the field side) are related by the
flange-back distance: the flange back ``S = flange_back`` sits at ``eta = back_to_back/2``,
so ``S = eta - back_to_back/2 + flange_back`` (S1002: taping line at eta = 0.75 m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import RailContactError, check_finite, check_positive
from ..formed import formed_once
from . import kernels
from .profiles import Profile

SIDES = {"left": 1, "right": -1}
MAX_RAIL_SHIFT = 0.05
"""The largest deviation [m] of a rail from its place, laterally and vertically."""
MAX_POSE_ANGLE = 0.1
"""Largest wheelset yaw and roll [rad] of a :class:`Pose` (small angles)."""
MAX_RAIL_ROLL = 0.1
"""The largest roll [rad] of a rail about the track's X axis."""


@dataclass(frozen=True)
class Track:
    """Rail profile and track layout.

    Attributes
    ----------
    rail
        Rail profile (railcontact frame: y to the field side, z up).
    inclination
        Rail cant [rad], top towards the track centre (1:40 -> atan(1/40)). Give 0 for a
        profile file that is canted already.
    gauge
        Track gauge [m], measured ``gauge_depth`` below the top of rail.
    gauge_depth
        Depth of the gauge measurement [m] (14 mm).
    shift
        Deviation of the placed rail (du, dZ) [m], side frame: du towards the field side,
        dZ up.
    tilt
        Deviation of the placed rail's angle [rad], side frame, about the profile's origin:
        positive turns its top towards the track centre (as the inclination).
    """

    rail: Profile
    inclination: float = math.atan(1 / 40)
    gauge: float = 1.435
    gauge_depth: float = 0.014
    shift: tuple[float, float] = (0.0, 0.0)
    tilt: float = 0.0

    def __post_init__(self) -> None:
        if self.rail.kind != "rail":
            raise RailContactError(f"track.rail must be a rail profile, got a {self.rail.kind}")
        inc = check_finite("inclination", self.inclination, "rad")
        if abs(inc) > 0.2:
            raise RailContactError(f"inclination must be a small cant angle in rad (1:40 = "
                                   f"0.025), got {inc:g}")
        check_positive("gauge", self.gauge, "m")
        check_positive("gauge_depth", self.gauge_depth, "m")
        du, dz = (check_finite("rail shift", v, "m") for v in self.shift)
        if max(abs(du), abs(dz)) > MAX_RAIL_SHIFT:
            raise RailContactError(f"a rail deviation must be small (|shift| <= "
                                   f"{MAX_RAIL_SHIFT:g} m), got ({du:g}, {dz:g}) m")
        object.__setattr__(self, "shift", (float(du), float(dz)))
        if abs(check_finite("rail tilt", self.tilt, "rad")) > MAX_RAIL_ROLL:
            raise RailContactError(f"a rail's roll must be a small angle (|roll| <= "
                                   f"{MAX_RAIL_ROLL:g} rad), got {self.tilt:g}")

    def deviated(self, side: str, offset: tuple[float, float] = (0.0, 0.0),
                 roll: float = 0.0) -> Track:
        """This track with the ``side`` rail deviated (the other rail of the returned track
        is not meant to be used): ``offset`` (dY, dZ) [m] and ``roll`` [rad, about X] in the
        track frame (Y to the left, Z up), the roll about the rail profile's origin after
        the rail is placed."""
        sgn = SIDES[side]
        return Track(self.rail, self.inclination, self.gauge, self.gauge_depth,
                     (sgn * float(offset[0]), float(offset[1])), sgn * float(roll))

    @property
    def rail_origin(self) -> tuple[float, float]:
        """The rail profile's origin placed in the side frame (u, Z) [m]."""
        _, _, _, du, dz = self.placement
        return du, dz

    @formed_once
    def placement(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
        """The rail profile canted: profile y, canted (u, z) and the offsets (du, dz) that
        place it (gauge point at gauge/2, top at 0), so that placed = (u + du, z + dz).
        With a deviation (:attr:`shift`, :attr:`tilt`) the offsets are those of the rail
        without it plus the shift, and (u, z) are turned by the tilt too."""
        r = self.rail
        y = np.linspace(*r.bounds, 4001)
        z = r.height(y)
        c, s = math.cos(self.inclination), math.sin(self.inclination)
        uc, zc = y * c - z * s, y * s + z * c  # top towards -y (the gauge side)
        dz = -float(zc.max())
        top = int(np.argmax(zc))
        gauge_side = slice(0, top + 1)
        if (zc[gauge_side] + dz).min() > -self.gauge_depth:
            raise RailContactError(f"rail profile {r.name!r} does not reach {self.gauge_depth} m "
                                   "below its top on the gauge side; cannot place the gauge")
        ug = float(np.interp(-self.gauge_depth, zc[gauge_side] + dz, uc[gauge_side]))
        du = self.gauge / 2 - ug
        if self.tilt != 0.0:
            c, s = math.cos(self.inclination + self.tilt), math.sin(self.inclination + self.tilt)
            uc, zc = y * c - z * s, y * s + z * c
        return y, uc, zc, du + self.shift[0], dz + self.shift[1]

    @formed_once
    def side_rail(self) -> Profile:
        """The rail in the side frame: Z(u), canted and placed (see the module docstring)."""
        _, uc, zc, du, dz = self.placement
        # drop any fold-back of the flank (an undercut the wheel cannot reach: the points
        # not beyond every point before them)
        keep = np.concatenate([[True], uc[1:] > np.maximum.accumulate(uc)[:-1]])
        try:
            return Profile(uc[keep] + du, zc[keep] + dz, "rail", self.rail.name + " (placed)")
        except RailContactError as exc:
            if self.inclination == 0.0:
                raise
            raise RailContactError(
                f"rail profile {self.rail.name!r} canted by inclination = "
                f"{self.inclination:g} rad folds back on itself ({exc}); is the file canted "
                "already (as the Manchester benchmark's UIC60)? Then give inclination = 0"
            ) from None

    def rail_coordinate(self, u: float, z: float) -> float:
        """Rail profile coordinate y [m] of the point (u, Z) of the placed rail.

        Raises
        ------
        RailContactError
            For a non-finite ``u`` or ``z`` (no nearest point: the search would give an
            end of the profile).
        """
        u, z = float(u), float(z)
        if not (math.isfinite(u) and math.isfinite(z)):
            raise RailContactError(f"rail point (u, Z) = ({u:g}, {z:g}) m is not finite")
        return float(kernels.rail_coordinate(*self.placed_search, u, z))

    @formed_once
    def placed_search(self) -> tuple[np.ndarray, ...]:
        """What :meth:`rail_coordinate`'s search reads (:func:`~.kernels.rail_coordinate`):
        :attr:`_placed_points` (u, Z) [m], their order in u (stable), the u so ordered and
        the rail profile coordinate y [m] of each point."""
        pu, pz = self._placed_points
        order = np.argsort(pu, kind="stable")
        return pu, pz, order, pu[order], self.placement[0]

    @formed_once
    def _placed_points(self) -> tuple[np.ndarray, np.ndarray]:
        """The samples of :attr:`placement` placed in the side frame (u, Z) [m]."""
        _, uc, zc, du, dz = self.placement
        return uc + du, zc + dz


@dataclass(frozen=True)
class Wheelset:
    """Wheel profile and wheelset dimensions.

    Attributes
    ----------
    wheel
        Wheel profile (y = S to the field side, z = radius increment).
    radius
        Nominal rolling radius r0 at the taping line [m].
    back_to_back
        Flange-back distance [m] (1360 mm).
    flange_back
        S of the flange back in the wheel profile [m] (S1002: -70 mm).
    """

    wheel: Profile
    radius: float = 0.46
    back_to_back: float = 1.360
    flange_back: float = -0.070

    def __post_init__(self) -> None:
        if self.wheel.kind != "wheel":
            raise RailContactError(f"wheelset.wheel must be a wheel profile, got a "
                                   f"{self.wheel.kind}")
        check_positive("wheel_radius", self.radius, "m")
        check_positive("back_to_back", self.back_to_back, "m")
        check_finite("flange_back", self.flange_back, "m")

    def profile_coordinate(self, eta: np.ndarray) -> np.ndarray:
        """Wheel profile coordinate S [m] of the axial position eta [m] (side frame)."""
        return np.asarray(eta) - self.back_to_back / 2 + self.flange_back

    def axial_position(self, s: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`profile_coordinate`."""
        return np.asarray(s) + self.back_to_back / 2 - self.flange_back

    @formed_once
    def flange_tip(self) -> float:
        """Profile coordinate S [m] of the flange tip (the largest radius increment): a
        contact at smaller S is on the back of the flange, the wheel off its rail."""
        return float(self.wheel.y[int(np.argmax(self.wheel.z))])

    @formed_once
    def flange_flank(self) -> tuple[float, float]:
        """Profile coordinate S [m] of the steepest point of the flange's running flank
        (between the flange tip and the tread) and its angle [rad] (S1002: -39 mm, 70 deg).
        A contact between it and the tip means the wheel is climbing its flange."""
        tip = self.flange_tip
        s = np.linspace(tip, min(tip + 0.04, self.wheel.bounds[1]), 4001)
        slope = np.abs(self.wheel.slope(s))
        k = int(np.argmax(slope))
        return float(s[k]), float(np.arctan(slope[k]))


@dataclass(frozen=True)
class Pose:
    """Wheelset displacement relative to the centred position (track frame).

    Attributes
    ----------
    lateral
        Lateral displacement y [m], positive to the left.
    yaw
        Yaw angle psi [rad] about Z (positive: nose to the left).
    roll
        Roll angle phi [rad] about X (positive: left side up, right-hand rule about X).
    """

    lateral: float = 0.0
    yaw: float = 0.0
    roll: float = 0.0

    def __post_init__(self) -> None:
        check_finite("lateral_displacement", self.lateral, "m")
        check_finite("yaw", self.yaw, "rad")
        check_finite("roll", self.roll, "rad")
        if abs(self.yaw) > MAX_POSE_ANGLE or abs(self.roll) > MAX_POSE_ANGLE:
            raise RailContactError(f"yaw and roll must be small angles (|angle| < "
                                   f"{MAX_POSE_ANGLE:g} rad)")
