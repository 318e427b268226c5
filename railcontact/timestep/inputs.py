"""What a wheelset step is given besides its pose and loads: the wheelset's velocities
(:class:`Kinematics`, with the track curvature) and the rails' deviations
(:class:`RailDeviation`), in the track frame (X forward, Y left, Z up) and SI units."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from ..contact.wheel import WheelSettings
from ..errors import RailContactError, check_finite, check_positive
from ..geometry.points import ContactPoint
from ..geometry.track import SIDES, Pose, Track, Wheelset
from ..settings import ContactSettings
from ..settings.case import MAX_CREEPAGE, check_kinematic_creepage
from ..settings.convention import wheel_frame_creepage


@dataclass(frozen=True)
class Kinematics:
    """Wheelset velocities from which the creepages are computed.

    Attributes
    ----------
    speed
        Forward speed V [m/s] (> 0).
    lateral_velocity
        dy/dt [m/s].
    yaw_rate
        dpsi/dt [rad/s].
    spin_speed
        Angular speed Omega of the wheelset about its axle [rad/s] (V / r0 for pure
        rolling at the nominal radius).
    curvature
        Track curvature k [1/m], positive when the track turns left (towards +Y). The
        track frame follows the curve: the rails turn relative to it with ``-V k`` about
        the vertical, so a rail point at Y moves forward with ``V k Y`` (module
        docstring); a wheelset following the curve has no yaw rate in this frame.
    """

    speed: float
    lateral_velocity: float = 0.0
    yaw_rate: float = 0.0
    spin_speed: float | None = None
    curvature: float = 0.0

    def __post_init__(self) -> None:
        check_positive("speed", self.speed, "m/s")
        check_finite("lateral_velocity", self.lateral_velocity, "m/s")
        check_finite("yaw_rate", self.yaw_rate, "rad/s")
        if self.spin_speed is not None:
            check_finite("spin_speed", self.spin_speed, "rad/s")
        if abs(check_finite("curvature", self.curvature, "1/m")) > MAX_CURVATURE:
            raise RailContactError(f"curvature must be within +-{MAX_CURVATURE:g} 1/m (a "
                                   f"radius of {1 / MAX_CURVATURE:g} m or more), got "
                                   f"{self.curvature:g} 1/m")

    def creepage(self, cp: ContactPoint, pose: Pose, r0: float) -> tuple[float, float, float]:
        """(xi, eta, phi) of the patch ``cp`` in its contact frame (module docstring).
        Raises a :class:`~railcontact.errors.CaseError` where one is beyond
        :data:`~railcontact.settings.case.MAX_CREEPAGE` (a speed too small for the other
        velocities)."""
        v = self.speed
        omega = v / r0 if self.spin_speed is None else self.spin_speed
        s = SIDES[cp.side]
        g = cp.contact_angle
        d = cp.position[1] - pose.lateral
        k = self.curvature
        if k == 0.0:
            xi = (v - omega * cp.rolling_radius - self.yaw_rate * d) / v
            phi = (-s * omega * math.sin(g) + self.yaw_rate * math.cos(g)) / v
        else:  # the rail point at Y moves forward with V k Y, the rail turns with -V k
            xi = (v - omega * cp.rolling_radius - self.yaw_rate * d
                  - v * k * cp.position[1]) / v
            phi = (-s * omega * math.sin(g) + (self.yaw_rate + v * k) * math.cos(g)) / v
        eta = (self.lateral_velocity - v * pose.yaw) / (v * math.cos(g))
        return check_kinematic_creepage(cp.side, (xi, eta, phi), v)


MAX_CURVATURE = 0.1
"""Largest track curvature [1/m] a step takes, as a case file's ``[geometry] curvature``
(a 10 m radius: tighter than any running line)."""


@dataclass(frozen=True)
class RailDeviation:
    """A rail's deviation from its place at one instant (track frame, SI units): an
    irregularity, or a gauge change (a lateral offset).

    Attributes
    ----------
    offset
        (dY, dZ) [m]: the rail moved to the left (+Y) and up (+Z).
    roll
        Rotation of the rail about X [rad] (right-handed about the track's X, with Y to
        the left and Z up), about the rail profile's origin after the rail is placed.
    """

    offset: tuple[float, float] = (0.0, 0.0)
    roll: float = 0.0

    def __post_init__(self) -> None:
        try:
            dy, dz = self.offset
        except (TypeError, ValueError):
            raise RailContactError(f"rail offset must be (dY, dZ) [m], got "
                                   f"{self.offset!r}") from None
        dy, dz = (float(check_finite(f"rail offset {n}", v, "m"))
                  for n, v in (("dY", dy), ("dZ", dz)))
        object.__setattr__(self, "offset", (dy, dz))
        check_finite("rail roll", self.roll, "rad")


NO_DEVIATION = RailDeviation()
"""A rail where it is placed."""


SIDE_NAMES = ("left", "right")


def sides(name: str, value, kind: type) -> tuple:
    """``value`` (one ``kind`` for both sides, or a pair (left, right)) as a pair."""
    if isinstance(value, kind):
        return value, value
    if isinstance(value, tuple) and len(value) == 2 and all(isinstance(v, kind)
                                                           for v in value):
        return value
    raise RailContactError(f"{name} must be a {kind.__name__} or a pair (left, right) of "
                           f"them, got {value!r}")


def per_wheel(name: str, value, size: int, shape: str) -> tuple:
    """``value`` as a pair (left, right) of numbers (``size`` 1) or of ``size``-tuples."""
    try:
        pair = tuple(value)
        if len(pair) != 2:
            ok = False
        elif size > 1:
            pair = (tuple(pair[0]), tuple(pair[1]))
            ok = len(pair[0]) == size and len(pair[1]) == size
        else:
            ok = not hasattr(pair[0], "__len__") and not hasattr(pair[1], "__len__")
    except TypeError:
        ok = False
    if not ok:
        raise RailContactError(f"{name} must be {shape}, got {value!r}")
    return pair


@dataclass(frozen=True)
class WheelSetup:
    """One wheel's problem at a step, formed once: its side, its rail (placed with the
    step's deviation), its wheelset (wheel profile) and its settings (with the step's
    friction)."""

    side: str
    track: Track
    wheelset: Wheelset
    settings: ContactSettings
    solvers: tuple[WheelSettings, WheelSettings] | None = field(default=None, repr=False,
                                                                 compare=False)
    """The wheel solver's settings of :attr:`settings` without and with the tangential
    problem (:func:`solver_settings`); None: formed where they are needed."""


def solver_settings(settings: ContactSettings, tangential: bool) -> WheelSettings:
    """The wheel solver's settings of a step's wheel with ``settings`` (``tangential``:
    creepages or velocities given)."""
    s = settings
    return WheelSettings(s.patch_settings, s.tangential_settings if tangential else None,
                         s.patch_frame == "reference", s.load_tolerance, s.load_tolerance,
                         s.load_includes_creep)


@dataclass(frozen=True, slots=True)
class StepInputs:
    """A step's inputs, checked (:meth:`~railcontact.timestep.WheelsetContact.solve`'s
    parameters), with each wheel's setup.

    Attributes
    ----------
    pose
        The wheelset's pose.
    loads, vertical
        The wheel loads (left, right) [N], or the vertical displacement [m]; the other None.
    creepages, kinematics
        Each wheel's creepages (railcontact's), or the wheelset's velocities; or neither.
    time
        The step's time [s], or None.
    setups
        Each wheel's rail, wheelset and settings at the step (:class:`WheelSetup`).
    """

    pose: Pose
    loads: tuple[float, float] | None
    vertical: float | None
    creepages: tuple | None
    kinematics: Kinematics | None
    time: float | None
    setups: tuple[WheelSetup, WheelSetup]

    def creep(self, k: int) -> tuple[float, float, float] | None:
        """The creepages of wheel ``k`` (0 left, 1 right), None without them."""
        return None if self.creepages is None else self.creepages[k]

    def geometry(self) -> tuple[tuple[Track, Track], tuple[Wheelset, Wheelset]]:
        """The (left, right) tracks and wheelsets of the step's wheels."""
        return ((self.setups[0].track, self.setups[1].track),
                (self.setups[0].wheelset, self.setups[1].wheelset))


def step_inputs(pose: Pose, loads, vertical, creepages, kinematics: Kinematics | None,
                time: float | None, setups: tuple[WheelSetup, WheelSetup],
                convention: str) -> StepInputs:
    """A step's inputs checked (:meth:`~railcontact.timestep.WheelsetContact.solve`'s
    parameters, :func:`checked_inputs`) with each wheel's ``setups``."""
    return StepInputs(*checked_inputs(pose, loads, vertical, creepages, kinematics, time,
                                      convention), setups)


def checked_inputs(pose: Pose, loads, vertical, creepages, kinematics: Kinematics | None,
                   time: float | None, convention: str) -> tuple:
    """A step's inputs checked, ``(pose, loads, vertical, creepages, kinematics, time)``:
    :meth:`~railcontact.timestep.WheelsetContact.solve`'s parameters as numbers of their
    kinds (a :class:`RailContactError` naming the first that is not; the loads and
    creepages as floats, creepages given in CONTACT's ``convention`` turned into
    railcontact's). A table step (:class:`~railcontact.table.TableContact`) checks its
    inputs here too."""
    if not isinstance(pose, Pose):
        raise RailContactError(f"pose must be a Pose, got {pose!r}")
    if (loads is None) == (vertical is None):
        raise RailContactError("give exactly one of loads [N] and vertical [m]")
    if creepages is not None and kinematics is not None:
        raise RailContactError("give at most one of creepages and kinematics (the "
                               "creepages follow from the kinematics)")
    if kinematics is not None and not isinstance(kinematics, Kinematics):
        raise RailContactError(f"kinematics must be a Kinematics record, got "
                               f"{kinematics!r}")
    if loads is not None:
        loads = per_wheel("loads", loads, 1, "(left, right) [N]")
    if creepages is not None:
        creepages = per_wheel("creepages", creepages, 3,
                               "((xi, eta, phi) left, (xi, eta, phi) right)")
    if loads is not None:
        loads = (check_positive("left wheel load", loads[0], "N", allow_zero=True),
                 check_positive("right wheel load", loads[1], "N", allow_zero=True))
    else:
        check_finite("vertical", vertical, "m")
    if creepages is not None:
        creepages = tuple(tuple(_creepage(f"{s} creepage", c) for c in cs)
                          for s, cs in zip(SIDE_NAMES, creepages, strict=True))
        if convention == "contact":
            creepages = tuple(wheel_frame_creepage(c) for c in creepages)
    if time is not None:
        time = check_finite("time", time, "s")
    return pose, loads, vertical, creepages, kinematics, time


def _creepage(name: str, value) -> float:
    """``value`` as a finite float within :data:`~railcontact.settings.case.MAX_CREEPAGE`
    (else a :class:`~railcontact.errors.RailContactError`)."""
    c = check_finite(name, value)
    if abs(c) > MAX_CREEPAGE:
        raise RailContactError(f"{name} must be within +-{MAX_CREEPAGE:g}, got {c:g}")
    return c


class Setups:
    """Each wheel's :class:`WheelSetup` at a step, from a contact's tracks and wheelsets
    (left, right): its rail placed with the step's deviation, its settings with the step's
    friction (the last few of each kept: a deviation or a friction held over steps is
    formed once)."""

    def __init__(self, tracks: tuple[Track, Track], wheelsets: tuple[Wheelset, Wheelset]
                 ) -> None:
        self.tracks, self.wheelsets = tracks, wheelsets
        self._placed: dict = {}  # (side, deviation) -> the rail deviated (the last ones)
        self._settings_of: dict = {}  # friction -> the settings with it (the last ones)
        self._friction_base: ContactSettings | None = None  # (what they were made from)
        self._solvers: dict = {}  # id(settings) -> (settings, its solvers) (the last ones)
        self._plain: tuple = (None, None)  # (settings, their setups without deviations
        # or friction given: formed once, frozen records shared by the steps)

    def at(self, settings: ContactSettings, rails: tuple[RailDeviation, RailDeviation] | None,
           friction: tuple[float, float] | None) -> tuple[WheelSetup, WheelSetup]:
        """Each wheel's rail (placed with its deviation), wheelset and ``settings`` (with
        its friction) at a step."""
        if rails is None and friction is None:
            plain = self._plain
            if plain[0] is not settings:
                plain = self._plain = (settings, self._formed(settings, None, None))
            return plain[1]
        return self._formed(settings, rails, friction)

    def _formed(self, settings: ContactSettings,
                rails: tuple[RailDeviation, RailDeviation] | None,
                friction: tuple[float, float] | None) -> tuple[WheelSetup, WheelSetup]:
        """:meth:`at`'s setups, formed."""
        if rails is not None:
            rails = per_wheel("rails", rails, 1, "(left, right) RailDeviation")
            for r in rails:
                if not isinstance(r, RailDeviation):
                    raise RailContactError(f"rails must be RailDeviation records, got {r!r}")
        if friction is not None:
            friction = tuple(check_positive(f"{s} friction", mu, "")
                             for s, mu in zip(SIDE_NAMES,
                                              per_wheel("friction", friction, 1,
                                                         "(left, right) [-]"), strict=True))
        out = []
        for k, side in enumerate(SIDE_NAMES):
            track = self.tracks[k]
            if rails is not None and rails[k] != NO_DEVIATION:
                track = self._placed_rail(side, track, rails[k])
            s = settings
            if friction is not None and friction[k] != settings.friction:
                s = self._with_friction(settings, friction[k])
            out.append(WheelSetup(side, track, self.wheelsets[k], s, self._solvers_of(s)))
        return out[0], out[1]

    def _solvers_of(self, settings: ContactSettings) -> tuple[WheelSettings, WheelSettings]:
        """The wheel solver's settings of ``settings`` without and with the tangential
        problem (:attr:`WheelSetup.solvers`; the last few kept)."""
        held = self._solvers.get(id(settings))
        if held is None or held[0] is not settings:
            held = (settings, (solver_settings(settings, False),
                               solver_settings(settings, True)))
            if len(self._solvers) >= 8:
                self._solvers.pop(next(iter(self._solvers)))
            self._solvers[id(settings)] = held  # (the settings kept: the id is not reused)
        return held[1]

    def _placed_rail(self, side: str, track: Track, rail: RailDeviation) -> Track:
        """``track`` with its ``side`` rail deviated by ``rail`` (the last few kept: a
        deviation held over steps places the rail once)."""
        key = (side, id(track), rail.offset, rail.roll)
        held = self._placed.get(key)
        out = held[1] if held is not None and held[0] is track else None
        if out is None:
            try:
                out = track.deviated(side, rail.offset, rail.roll)
                _ = out.side_rail  # (placed now: a rail that cannot be is an error here)
            except RailContactError as exc:
                raise RailContactError(f"{side} rail deviation {rail.offset} m, roll "
                                       f"{rail.roll:g} rad: {exc}") from None
            if len(self._placed) >= 8:
                self._placed.pop(next(iter(self._placed)))
            self._placed[key] = (track, out)  # (the track kept: its id is not reused)
        return out

    def _with_friction(self, settings: ContactSettings, mu: float) -> ContactSettings:
        """``settings`` with the coefficient of friction ``mu`` (the last few kept)."""
        if self._friction_base is not settings:  # (the settings were replaced)
            self._friction_base, self._settings_of = settings, {}
        out = self._settings_of.get(mu)
        if out is None:
            out = replace(settings, friction=mu)
            if len(self._settings_of) >= 8:
                self._settings_of.pop(next(iter(self._settings_of)))
            self._settings_of[mu] = out
        return out
