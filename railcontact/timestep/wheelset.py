"""Wheel–rail contact of a whole wheelset, one time step after the other.

:class:`WheelsetContact` is what a vehicle-dynamics code (and the FMU) calls every time
step: given the wheelset's pose, its wheel loads (or vertical displacement) and its creepages
(or velocities) it returns the contact forces of both wheels, each patch solved by the BEM,
warm-started as :attr:`ContactSettings.warm_start` says, and it remembers the solution for
the next step.

Frames and signs (SI units):

* Track frame ``(X, Y, Z)``: X forward, Y to the left, Z up; wheelset lateral displacement
  y and yaw psi as in :class:`railcontact.geometry.Pose`.
* Contact frame of a patch: x forward, y in the contact plane pointing to the left (towards
  +Y), n = x × y (up, normal to the contact plane). It is right-handed on both wheels.
* Creepages (xi, eta, phi) are the wheel's velocity relative to the rail at the contact
  point divided by the forward speed V: xi and eta [-] along x and y, phi [1/m] the
  relative angular velocity about n divided by V.
* Creep forces F_x, F_y and spin moment M_z act **on the wheel** in its contact frame; for
  small creepages F_x = -f11 xi (Kalker). The normal force N [N] is the rail's push on
  the wheel along n.
* ``contact_angle`` gamma [rad] is positive when the contact plane leans towards the
  flange (it is the same on both wheels for a centred wheelset).

Kinematic creepages (``Kinematics``; wheelset spin speed Omega about the axle, rolling
forward when positive; roll rate neglected), for a patch at lateral position Y_c, rolling
radius r and contact angle gamma, with side sign s = +1 left, -1 right::

    xi  = (V - Omega r - psi_dot (Y_c - y)) / V
    eta = (y_dot - V psi) / (V cos gamma)
    phi = (-s Omega sin gamma + psi_dot cos gamma) / V

A wheel load Q [N] is the rail's total vertical force on the wheel, as CONTACT's FZ and
:func:`railcontact.solve`: ``sum (N cos(gamma) + F_y sin(gamma)) = Q`` over the patches.
With creepages the creep forces carry part of it (most of it on a flange near Nadal's
limit), so a secant iteration on the normal forces' share solves the wheel (normal, then
tangential BEM) until the total is met to :attr:`ContactSettings.load_tolerance` (or to
``eps_tau`` of the creep forces' vertical share, the accuracy they have); the first
guess is Q less the previous step's creep share (with a warm start from it; cold, less
Kalker's saturated linear estimate of it,
:func:`~railcontact.contact.loadloop.vertical_creep_estimate`), later passes
start from the one before (in every warm-start mode: it is the same step), and
:attr:`WheelContact.load_passes` counts them. ``load_includes_creep=False`` lets the normal
forces alone carry Q (one pass).

Each wheel is solved in its side frame (:mod:`railcontact.geometry.track`), where the
right wheel is mirrored; lateral components and the spin change sign there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from time import perf_counter

import numba
import numpy as np

from ..contact.loadloop import (
    MAX_SHARE,
    charge,
    count_passes,
    creep_load_secant,
    first_root,
    load_met,
    load_unique,
    vertical_creep_estimate,
    vertical_force,
)
from ..contact.patch import normal_estimate, solve_patch_tangential
from ..contact.results import PatchSolution, Work
from ..contact.start import NormalStart, WarmStart
from ..contact.wheelrail import (
    MIN_LOBE,
    contact_points,
    solve_wheel_normal,
    vertical_approach,
)
from ..errors import (
    CaseError,
    RailContactError,
    SolverError,
    check_finite,
    check_positive,
)
from ..geometry.search import ContactPoint, at_reference, merge_approaches, vertical_gap
from ..geometry.track import SIDES, Pose, Track, Wheelset
from ..halfspace.grid import Grid
from ..halfspace.hertz import HertzSolution, hertz, negligible_load, no_contact_load
from ..halfspace.materials import ElasticPair
from ..halfspace.sums import array_sum, numpy_sum
from ..settings import ContactSettings, Control
from ..settings.case import MAX_PENETRATION, check_convention
from ..settings.convention import wheel_frame_creepage
from ..status import Status, status_of
from .memory import EMPTY as EMPTY_MEMORY
from .memory import StepMemory
from .rigid import RigidSolution, RigidWheelset
from .validity import Validity, check_validity, derailment_quotient
from .warmstart import (
    PatchMemory,
    match,
    merged,
    previous_bounds,
    previous_start,
    previous_tangential,
    traction_rate,
)

OK, NOT_CONVERGED, NO_CONTACT, OUT_OF_RANGE, OUTSIDE_VALIDITY = (
    Status.OK, Status.NOT_CONVERGED, Status.NO_CONTACT, Status.OUT_OF_RANGE,
    Status.OUTSIDE_VALIDITY)
STATUS_NAMES = {s: s.label for s in Status if s != Status.NOT_COMPUTED}
"""A wheel's status (:class:`~railcontact.status.Status`) and its label: ok; not converged
(a BEM solve or the load loop; forces given, less accurate); no contact (zero forces); out
of range (the pose or a patch beyond the model: nothing solved, zero forces); outside
validity (solved, but beyond a limit of :mod:`.validity`: Y/Q, Nadal's limit, flange
climb, penetration, wheel load, an under-resolved patch)."""
WARM_PROMISE = (0.01, 0.02)
"""What a warm step reported ok promises at the default tolerances (eps_n = 1e-3,
eps_tau = 1e-2, load tolerance 1e-3): its wheel's normal force N within this first share
of N, and each creep force component within the second share of mu N, of a cold solve
of the same state at tight tolerances. The previous step's solution starts the solves
and bounds each patch's potential area; the area is grown wherever the rigid overlap
beyond it may touch (:func:`railcontact.contact.patch.uncovered`), so no contact is
left out, and the solvers stop on the same criteria as from cold. Where the load is met
at more than one approach (two patches joining into one between them), warm and cold
starts return the same root, the smallest approach
(:func:`~railcontact.contact.loadloop.first_root`), and the wheel says that there is
another (:attr:`WheelContact.load_unique` False). Not promised: a steep patch's creep
force with another patch beside it (``mu tan(gamma) >= 1``,
:func:`~railcontact.contact.loadloop.load_unique`) may let the load be met at another
root than a cold solve's; the wheel says so too. ``scripts/fuzz_warm.py`` checks the
promise on seeded trajectories across the flange root and the flange (seeds 1, 3 and 4:
none beyond it)."""
SEVERITY = tuple(sorted(STATUS_NAMES, key=lambda s: s.severity))
"""The statuses from the least to the most severe (:attr:`Status.severity`): the
wheelset's status is its wheels' most severe."""


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
        """(xi, eta, phi) of the patch ``cp`` in its contact frame (module docstring)."""
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
        return xi, eta, phi


@dataclass(frozen=True)
class WheelSetup:
    """One wheel's problem at a step, formed once: its side, its rail (placed with the
    step's deviation), its wheelset (wheel profile) and its settings (with the step's
    friction)."""

    side: str
    track: Track
    wheelset: Wheelset
    settings: ContactSettings


SIDE_NAMES = ("left", "right")


def _sides(name: str, value, kind: type) -> tuple:
    """``value`` (one ``kind`` for both sides, or a pair (left, right)) as a pair."""
    if isinstance(value, kind):
        return value, value
    if isinstance(value, tuple) and len(value) == 2 and all(isinstance(v, kind)
                                                           for v in value):
        return value
    raise RailContactError(f"{name} must be a {kind.__name__} or a pair (left, right) of "
                           f"them, got {value!r}")


MAX_CURVATURE = 0.02
"""Largest track curvature [1/m] a step takes (a 50 m radius: tighter than any running
line; the kinematics assume the patch small against the radius)."""


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


@dataclass
class WheelContact:
    """Contact of one wheel at one time step (SI units; see the module docstring).

    Forces are summed over the wheel's patches; the contact-point quantities are those of
    the patch with the largest normal force.
    """

    side: str
    status: Status = NO_CONTACT
    message: str = "no contact"
    patches: list[PatchSolution] = field(default_factory=list)
    creepages: list[tuple[float, float, float]] = field(default_factory=list)
    normal_force: float = 0.0
    creep_force: tuple[float, float] = (0.0, 0.0)
    spin_moment: float = 0.0
    track_force: tuple[float, float, float] = (0.0, 0.0, 0.0)
    yaw_moment: float = 0.0
    wheel_position: float = 0.0
    rail_position: float = 0.0
    lateral_position: float = 0.0
    contact_angle: float = 0.0
    rolling_radius: float = 0.0
    area: float = 0.0
    max_pressure: float = 0.0
    slip_area_ratio: float = 0.0
    normal_iterations: int = 0
    """Normal CG iterations of the step, over all patches, load passes and re-meshes."""
    tangential_iterations: int = 0
    """Tangential sweeps of the step, over all patches, load passes and re-meshes."""
    load_passes: int = 0
    """Solves of the wheel this step: 0 without contact, more than one when a wheel load
    counts the creep forces (:attr:`ContactSettings.load_includes_creep`) or several
    patches share it."""
    remeshes: int = 0
    """Normal solves repeated on a grown potential area."""
    seconds: float = 0.0
    """Wall time of the wheel's patch solves [s] (estimates included)."""
    contact_point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """The rigid contact point of the main patch in the track frame (X, Y, Z) [m]."""
    load_unique: bool = True
    """False when the wheel load (counting the creep forces) has, or may have, more than
    one solution; the message says why. Two of the wheel's contact regions joining into
    one patch between two roots (:func:`~railcontact.contact.loadloop.first_root`): the
    step returns the smallest approach, from warm and cold starts alike. Several patches,
    one with ``mu tan(gamma) >= 1`` (:func:`~railcontact.contact.loadloop.load_unique`):
    the one continuous with the previous step, or, cold, the one reached from the normal
    share Q."""
    validity: int = 0
    """The limits of :mod:`~railcontact.timestep.validity` the solved wheel is beyond (bits
    Y_Q 1, NADAL 2, FLANGE_CLIMB 4, PENETRATION 8, LOAD 16, RESOLUTION 32; 0 within all);
    any makes an otherwise ok wheel's status OUTSIDE_VALIDITY."""
    derailment_quotient: float = 0.0
    """Y/Q [-]: the wheel's lateral force on the rail towards the field side over the
    vertical force (:func:`~railcontact.timestep.validity.derailment_quotient`)."""
    approach: float = 0.0
    """Vertical approach of the wheel into its rail beyond first contact [m]."""
    penetration: float = 0.0
    """Largest normal penetration of its patches [m]."""
    frictional_power_per_speed: float = 0.0
    """The creep forces' power per unit forward speed [N = W/(m/s)], summed over the
    patches: ``F_x xi + F_y eta + M_z phi`` with each patch's forces on the wheel and the
    creepages it was solved with (the traction times the slip integrated over the patch,
    in steady rolling; negative: dissipated)."""
    frictional_power: float | None = None
    """Frictional power of the wheel [W]: the forward speed V times
    :attr:`frictional_power_per_speed` when the step's kinematics give V; None when the
    creepages were given."""
    moment: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Moment of the rail's forces on the wheel about the point (0, y, 0) of the track
    frame (under the wheelset centre, at rail-top height), track components (X, Y, Z)
    [N m]: the pressure and traction over each patch (each element's force at its place
    in the patch's plane: the spin moment and the pressure's offsets from the contact
    point included)."""

    @property
    def n_patches(self) -> int:
        return len(self.patches)

    def mark_validity(self, validity: Validity) -> None:
        """Record a validity check: its bits in :attr:`validity`; an ok wheel beyond a
        limit becomes OUTSIDE_VALIDITY, its message naming each quantity and value (a
        wheel with another status keeps it, the limits added to its message)."""
        self.validity = validity.flags
        if not validity.flags:
            return
        if self.status == OK:
            note = self.message.removeprefix("ok")  # e.g. "; the load may have several ..."
            self.status = OUTSIDE_VALIDITY
            self.message = f"outside validity: {validity.message}{note}"
        else:
            self.message += f"; also outside validity: {validity.message}"


@dataclass
class WheelsetResult:
    """Both wheels at one time step, with the totals on the wheelset (track frame)."""

    left: WheelContact
    right: WheelContact
    wall_time: float = 0.0
    wheelset_radius: float = 0.0
    """Nominal rolling radius r0 [m]: the centre's height above the rail tops at
    ``vertical = 0``."""
    vertical: float | None = None
    """Vertical displacement of the wheelset centre [m], positive up, from one nominal
    radius above the rail tops: the input under penetration control; under load control
    the rigid wheelset's at which both wheels, penetration-controlled, carry their loads,
    when :attr:`ContactSettings.rigid_wheelset` is "solve" (:mod:`~railcontact.timestep.
    rigid`; whether it was found: :attr:`rigid_solution`); None when not solved (skipped,
    or out of range)."""
    roll: float | None = None
    """Roll angle of the wheelset [rad] (positive: left side up): the pose's under
    penetration control, the rigid wheelset's under load control (as :attr:`vertical`)."""
    rigid_solution: RigidSolution | None = None
    """:attr:`vertical` and :attr:`roll` with whether they were found
    (:class:`~railcontact.timestep.rigid.RigidSolution`: under load control check its
    ``converged`` and ``message``); None where they were not solved."""
    rigid_work: tuple[Work, Work] = field(
        default_factory=lambda: (Work(load_passes=0), Work(load_passes=0)))
    """The work (:class:`~railcontact.contact.results.Work`: iterations, load passes,
    re-meshes, wall time [s]) of the wheels' solves at the rolls the rigid wheelset's
    search evaluated, left and right; zero where it did not run. Not in the wheels' own
    counts: the step's whole work is the wheels' plus this."""

    @property
    def wheels(self) -> tuple[WheelContact, WheelContact]:
        return (self.left, self.right)

    @property
    def status(self) -> int:
        """The wheels' most severe status (:data:`SEVERITY`). Whether the rigid
        wheelset's :attr:`vertical` and :attr:`roll` were found under load control is
        :attr:`rigid_solution`'s (the FMU's ``status`` counts it)."""
        return Status.worst(w.status for w in self.wheels)

    @property
    def moment(self) -> tuple[float, float, float]:
        """Moment of the rails' forces on the wheelset about its centre (0, y, r0 +
        vertical; r0 when :attr:`vertical` was not solved), track components (M_X roll,
        M_Y pitch, M_Z yaw) [N m]: right-handed about X forward, Y left, Z up (M_X > 0
        lifts the left wheel, M_Z > 0 turns the nose to the left)."""
        h = self.wheelset_radius + (self.vertical or 0.0)
        fx, fy, _ = self.force
        m = [self.left.moment[k] + self.right.moment[k] for k in range(3)]
        return (m[0] + h * fy, m[1] - h * fx, m[2])

    @property
    def force(self) -> tuple[float, float, float]:
        """Total force (X, Y, Z) of the rails on the wheelset [N]."""
        return tuple(float(self.left.track_force[k] + self.right.track_force[k])
                     for k in range(3))

    @property
    def yaw_moment(self) -> float:
        """Total moment about the vertical axis through the wheelset centre [N m]."""
        return self.left.yaw_moment + self.right.yaw_moment


class WheelsetContact:
    """The contact solver of a wheelset, with the memory that warm-starts the next step.

    Parameters
    ----------
    track, wheelset
        Geometry (:mod:`railcontact.geometry`): one for both sides, or a pair (left,
        right) for rails or wheels that differ (a worn wheelset, rails ground
        differently). A pair of wheelsets shares the wheel radius and back-to-back
        distance; their wheel profiles differ.
    pair
        Combined elastic parameters of wheel and rail.
    settings
        :class:`ContactSettings`.
    convention
        ``"railcontact"`` (the module docstring's frames and signs) or ``"contact"``: the
        creepages given to :meth:`solve` and the wheels' ``creepages``, ``creep_force`` and
        ``spin_moment`` (and each patch's ``creep_forces``) are CONTACT's (its body roles,
        signs and mirroring: :func:`railcontact.settings.convention.wheel_frame_creepage`),
        and each patch is solved in the frame at its reference point, as CONTACT poses it.
        The track-frame totals (``track_force``, ``yaw_moment``) and the geometry inputs
        stay railcontact's.
    patch_frame
        ``"reference"`` or ``"rigid"``: the origin of each patch's frame (where its contact
        angle, rolling radius and spin are taken) in railcontact's convention - CONTACT's
        reference point, the overlap's weighted centre (formed at the previous step's
        approach in a warm step), or the rigid contact point; None: ``settings``'
        ``patch_frame`` ("reference" by default). CONTACT's convention always uses the
        reference point.
    """

    def __init__(self, track: Track | tuple[Track, Track],
                 wheelset: Wheelset | tuple[Wheelset, Wheelset], pair: ElasticPair,
                 settings: ContactSettings | None = None, *,
                 convention: str = "railcontact", patch_frame: str | None = None) -> None:
        self.tracks: tuple[Track, Track] = _sides("track", track, Track)
        """The rails' tracks (left, right)."""
        self.wheelsets: tuple[Wheelset, Wheelset] = _sides("wheelset", wheelset, Wheelset)
        """The wheels' wheelsets (left, right)."""
        a, b = self.wheelsets
        if (a.radius, a.back_to_back) != (b.radius, b.back_to_back):
            raise RailContactError("the left and right wheelsets must have one wheel radius "
                                   f"and back-to-back distance, got {a.radius:g} / "
                                   f"{b.radius:g} m and {a.back_to_back:g} / "
                                   f"{b.back_to_back:g} m")
        self.track, self.wheelset = self.tracks[0], self.wheelsets[0]
        """The left side's track and wheelset (the only ones when both sides share them)."""
        self.pair = pair
        self._placed: dict = {}  # (side, deviation) -> the rail deviated (the last ones)
        self._settings_of: dict = {}  # friction -> the settings with it (the last ones)
        settings = settings or ContactSettings()
        self.convention = check_convention(convention)
        if patch_frame is not None:
            settings = replace(settings, patch_frame=patch_frame)
        if self.convention == "contact":  # CONTACT's: always at the reference point
            settings = replace(settings, patch_frame="reference")
        self.settings = settings
        self.memory: StepMemory = EMPTY_MEMORY
        """The last step's memory (:class:`~.memory.StepMemory`), where the next starts;
        a value that only :meth:`solve` replaces (an FMU saves and restores it as it
        is)."""

    def reset(self) -> None:
        """Forget the previous step (the next one starts without it)."""
        self.memory = EMPTY_MEMORY

    # -- the time step -----------------------------------------------------------------
    def solve(self, pose: Pose, *, loads: tuple[float, float] | None = None,
              vertical: float | None = None,
              creepages: tuple[tuple[float, float, float], tuple[float, float, float]]
              | None = None, kinematics: Kinematics | None = None,
              time: float | None = None, remember: bool = True,
              rails: tuple[RailDeviation, RailDeviation] | None = None,
              friction: tuple[float, float] | None = None) -> WheelsetResult:
        """Solve both wheels.

        Parameters
        ----------
        pose
            Lateral displacement, yaw and roll of the wheelset.
        loads
            Vertical wheel loads (left, right) [N] (load control) ...
        vertical
            ... or the wheelset's vertical displacement [m], positive up, from the position
            where its centre is one nominal radius above the top of the rails (penetration
            control; with roll from ``pose``).
        creepages
            ((xi, eta, phi) left, (xi, eta, phi) right) in the contact frames, the same for
            every patch of a wheel ...
        kinematics
            ... or the wheelset velocities (per-patch creepages); neither: normal problem
            only.
        time
            Simulation time [s] of this step; with the times of the two previous steps the
            warm start is extrapolated linearly (:mod:`railcontact.timestep.warmstart`).
        remember
            Keep this step's solution as the next step's warm start.
        rails
            The deviations (left, right) of the rails from their places at this step
            (:class:`RailDeviation`: irregularities, gauge changes); None: none.
        friction
            The coefficients of friction (left, right) at this step [-] (wet, contaminated
            or lubricated rail); None: the settings' ``friction`` on both.
        """
        t0 = perf_counter()
        if (loads is None) == (vertical is None):
            raise RailContactError("give exactly one of loads [N] and vertical [m]")
        if loads is not None:
            loads = _per_wheel("loads", loads, 1, "(left, right) [N]")
        if creepages is not None:
            creepages = _per_wheel("creepages", creepages, 3,
                                   "((xi, eta, phi) left, (xi, eta, phi) right)")
        if loads is not None:
            loads = tuple(check_positive(f"{s} wheel load", q, "N", allow_zero=True)
                          for s, q in zip(("left", "right"), loads, strict=True))
        else:
            check_finite("vertical", vertical, "m")
        if creepages is not None:
            creepages = tuple(tuple(check_finite(f"{s} creepage", c) for c in cs)
                              for s, cs in zip(("left", "right"), creepages, strict=True))
            if self.convention == "contact":
                creepages = tuple(wheel_frame_creepage(c) for c in creepages)
        if time is not None:
            time = check_finite("time", time, "s")
        setups = self._setups(rails, friction)
        wheels = []
        new_memory: dict[str, tuple[PatchMemory, ...]] = {}
        off_track = ""
        for k, side in enumerate(("left", "right")):
            try:  # a wheel that cannot be solved has its own status; the other still is
                control = Control(load=loads[k]) if loads is not None else Control(
                    penetration=self._approach(pose, setups[k], vertical))
                creep = None if creepages is None else creepages[k]
                wheel, mem = self._solve_side(setups[k], pose, control, creep, kinematics,
                                              time)
            except (CaseError, SolverError) as exc:  # the patch problem, the load loop
                wheel = WheelContact(side=side, status=status_of(exc), message=str(exc))
                mem = []
            except RailContactError as exc:  # the pose: beyond the profiles, into the rail
                off_track = off_track or f"{side} wheel: {exc}"
                wheel, mem = WheelContact(side=side), []
            wheels.append(wheel)
            new_memory[side] = tuple(mem)
        if off_track:  # a wheelset with a wheel off its rail has no contact forces to give
            msg = f"wheelset out of range: {off_track}"
            wheels = [WheelContact(side=s, status=OUT_OF_RANGE, message=msg)
                      for s in ("left", "right")]
            new_memory = {"left": (), "right": ()}
        else:
            for wheel, setup in zip(wheels, setups, strict=True):
                self._check_validity(wheel, setup)
        keep = remember and self.settings.uses_previous  # (what the next step starts from)
        step = StepMemory(new_memory["left"], new_memory["right"]) if keep else EMPTY_MEMORY
        result = WheelsetResult(wheels[0], wheels[1], 0.0, self.wheelset.radius)
        if vertical is not None:
            result.vertical, result.roll = vertical, pose.roll
            result.rigid_solution = RigidSolution(vertical, pose.roll)
        elif not off_track and self.settings.rigid_wheelset == "solve":
            last = self.memory if self.settings.uses_previous else EMPTY_MEMORY
            # the rolled wheels start from this step's solves (the previous step's when
            # this one is not remembered) and from the previous step's at its root
            rigid = RigidWheelset(
                *self._geometry(setups), pose, (wheels[0].approach, wheels[1].approach),
                tuple((w.lateral_position, w.rolling_radius, w.contact_angle)
                      if w.patches else None for w in wheels),
                _RolledApproaches(self, pose, loads, creepages, kinematics, time,
                                  step if remember else self.memory, last.rolled, setups),
                history=last.rigid, time=time)
            s = _rigid_stage(rigid)
            result.rigid_solution, result.rigid_work = s, s.work
            if s.evaluations:  # (found, or its best estimate; none when the search raised)
                result.vertical, result.roll = s.vertical, s.roll
            if keep:
                roots, rolled = rigid.remembered(s)
                step = replace(step, rigid=roots, rolled=rolled)
        if remember:
            self.memory = step
        result.wall_time = perf_counter() - t0
        return result

    def rolled_approaches(self, pose: Pose, *, loads: tuple[float, float],
                          creepages: tuple | None = None,
                          kinematics: Kinematics | None = None,
                          time: float | None = None) -> _RolledApproaches:
        """``phi -> (delta_L, delta_R)``: the vertical approaches [m] at which the wheels,
        the wheelset at ``pose`` rolled to ``phi`` [rad], carry ``loads`` [N] with the
        creepages - the function the rigid wheelset's stage searches
        (:class:`_RolledApproaches`), started from this contact's memory as that stage's
        is. Each call solves both wheels (for studies and tests; a step forms its own)."""
        rolled = self.memory.rolled if self.settings.uses_previous else None
        return _RolledApproaches(self, pose, loads, creepages, kinematics, time, self.memory,
                                 rolled, self._setups(None, None))

    def _check_validity(self, wheel: WheelContact, setup: WheelSetup) -> None:
        """Set the wheel's :attr:`~WheelContact.validity`; an ok wheel beyond a limit is
        OUTSIDE_VALIDITY, its message naming each quantity and value."""
        if not wheel.patches:
            return
        wheel.mark_validity(check_validity(SIDES[wheel.side], wheel.track_force,
                                           wheel.patches, setup.wheelset.flange_flank,
                                           setup.settings))

    def _setups(self, rails: tuple[RailDeviation, RailDeviation] | None,
                friction: tuple[float, float] | None) -> tuple[WheelSetup, WheelSetup]:
        """Each wheel's rail (placed with its deviation), wheelset and settings (with its
        friction) at a step."""
        if rails is not None:
            rails = _per_wheel("rails", rails, 1, "(left, right) RailDeviation")
            for r in rails:
                if not isinstance(r, RailDeviation):
                    raise RailContactError(f"rails must be RailDeviation records, got {r!r}")
        if friction is not None:
            friction = tuple(check_positive(f"{s} friction", float(mu), "")
                             for s, mu in zip(SIDE_NAMES,
                                              _per_wheel("friction", friction, 1,
                                                         "(left, right) [-]"), strict=True))
        out = []
        for k, side in enumerate(SIDE_NAMES):
            track = self.tracks[k]
            if rails is not None and rails[k] != NO_DEVIATION:
                track = self._placed_rail(side, track, rails[k])
            settings = self.settings
            if friction is not None and friction[k] != settings.friction:
                settings = self._with_friction(friction[k])
            out.append(WheelSetup(side, track, self.wheelsets[k], settings))
        return out[0], out[1]

    def _placed_rail(self, side: str, track: Track, rail: RailDeviation) -> Track:
        """``track`` with its ``side`` rail deviated by ``rail`` (the last few kept: a
        deviation held over steps places the rail once)."""
        key = (side, id(track), rail.offset, rail.roll)
        out = self._placed.get(key)
        if out is None:
            try:
                out = track.deviated(side, rail.offset, rail.roll)
                _ = out.side_rail  # (placed now: a rail that cannot be is an error here)
            except RailContactError as exc:
                raise RailContactError(f"{side} rail deviation {rail.offset} m, roll "
                                       f"{rail.roll:g} rad: {exc}") from None
            if len(self._placed) >= 8:
                self._placed.pop(next(iter(self._placed)))
            self._placed[key] = out
        return out

    def _with_friction(self, mu: float) -> ContactSettings:
        """The settings with the coefficient of friction ``mu`` (the last few kept)."""
        out = self._settings_of.get(mu)
        if out is None:
            out = replace(self.settings, friction=mu)
            if len(self._settings_of) >= 8:
                self._settings_of.pop(next(iter(self._settings_of)))
            self._settings_of[mu] = out
        return out

    @staticmethod
    def _geometry(setups: tuple[WheelSetup, WheelSetup]
                  ) -> tuple[tuple[Track, Track], tuple[Wheelset, Wheelset]]:
        """The (left, right) tracks and wheelsets of a step's wheels."""
        return ((setups[0].track, setups[1].track),
                (setups[0].wheelset, setups[1].wheelset))

    def _approach(self, pose: Pose, setup: WheelSetup, vertical: float) -> float:
        """Vertical approach [m] of a wheel into its rail for a wheelset lowered by
        ``-vertical``."""
        g = vertical_gap(setup.track, setup.wheelset, pose, setup.side)[4]
        approach = max(-(float(g.min()) + vertical), 0.0)
        if approach > MAX_PENETRATION:
            raise RailContactError(f"vertical = {vertical:g} m puts the wheel "
                                   f"{approach * 1e3:.4g} mm into its rail; a contact's "
                                   f"approach is at most {MAX_PENETRATION * 1e3:g} mm")
        return approach

    def _solve_side(self, setup: WheelSetup, pose: Pose, control: Control,
                    creep: tuple[float, float, float] | None, kin: Kinematics | None,
                    time: float | None, approach: float | None = None,
                    memory: tuple[tuple[PatchMemory, ...], ...] | None = None
                    ) -> tuple[WheelContact, list[PatchMemory]]:
        """``approach``: the vertical approach [m] expected, at which the first pass forms
        its frame (instead of the remembered step's, extrapolated: the rolled wheelset's
        solves, :class:`_RolledApproaches`). ``memory``: (the older step remembered, the
        solution the first pass starts from, the step whose creep share starts the load
        loop), the rolled wheelset's (with a warm start); None: this contact's memory of
        the previous step for all three."""
        side, settings = setup.side, setup.settings
        keep = self.settings.uses_previous  # remember this step for the next one
        own = previous = first = self.memory.wheel(side) if keep else ()
        if memory is not None and keep:
            previous, first, own = memory
        wheel = WheelContact(side=side)
        if control.value == 0.0:
            return wheel, []
        if control.by_load and negligible_load(control.load):
            wheel.message = f"no contact: {no_contact_load(control.load)}"
            return wheel, []
        tangential = creep is not None or kin is not None
        if not (control.by_load and tangential and settings.load_includes_creep):
            patches, creepages, mem = self._pass(setup, pose, control, creep, kin, time,
                                                 previous, first, approach)
            self._finish(wheel, patches, creepages, pose, kin and kin.speed)
            _mark_uniqueness(wheel, patches, settings.friction, bool(previous),
                             creep_in_load=False)
            return wheel, mem if keep else []
        # The load counts the creep forces: secant on the normal share (module docstring).
        q = control.load
        passes: list[tuple[list[PatchSolution], list, list[PatchMemory]]] = []

        def wheel_pass(normal: Control) -> tuple[float, tuple]:
            source = passes[-1][2] if passes else first  # later passes: the one before
            passes.append(self._pass(setup, pose, normal, creep, kin, time, previous,
                                     source, None if passes else approach))
            return vertical_force(passes[-1][0]) - q, passes[-1]

        def residual(qn: float) -> tuple[float, tuple]:
            return wheel_pass(Control(load=qn))

        def at_approach(a: float) -> tuple[float, tuple]:  # (after the load loop's passes)
            return wheel_pass(Control(penetration=a))

        estimate_seconds = 0.0  # the cold estimate's time, charged to the wheel's work
        if own:  # the previous step's creep share (the rolled solves: this step's)
            share = sum(m.vertical_creep for m in own)
        else:  # cold: estimated on the Hertz ellipse where the normal solve forms its frame
            t0 = perf_counter()
            cp = contact_points(setup.track, setup.wheelset, pose, side, 0.0)[0]
            if (settings.patch_frame == "reference" and math.isfinite(cp.B)
                    and cp.B > 0 and cp.A > 0):
                cosg = math.cos(cp.contact_angle)
                approach = hertz(cp.A, cp.B, self.pair, load=q / cosg).penetration / cosg
                cp = at_reference(cp, setup.track, setup.wheelset, pose, approach) or cp
            c = creep if creep is not None else kin.creepage(cp, pose, setup.wheelset.radius)
            sgn = SIDES[side]
            share = vertical_creep_estimate(cp, q, (c[0], sgn * c[1], sgn * c[2]), self.pair,
                                            settings.friction)
            estimate_seconds = perf_counter() - t0
        start = min(max(q - share, 0.05 * q), MAX_SHARE * q)
        (patches, creepages, mem), failure = creep_load_secant(
            residual, q, start, settings.load_tolerance)
        if not patches:
            return wheel, []
        if not failure:  # the smallest approach of the load with its creep forces
            (patches, creepages, mem), other = first_root(
                at_approach, (patches, creepages, mem), vertical_approach(patches),
                merge_approaches(setup.track, setup.wheelset, pose, side, MIN_LOBE), q,
                settings.load_tolerance, noisy=True)
            for p in patches:  # (the total's roots, not the normal share's of a pass)
                p.load_other = other
                p.load_unique = other is None and load_unique(patches, settings.friction)
            if other is not None and not load_met(patches, q, settings.load_tolerance,
                                                  settings.tangential_tolerance):
                failure = ("the vertical load with creep forces did not converge at the "
                           "smallest approach that carries it (vertical force "
                           f"{vertical_force(patches):.6g} N for load {q:.6g} N)")
        count_passes(patches, [p for p, _, _ in passes])  # the work of every pass counts
        patches[0].work.seconds += estimate_seconds
        self._finish(wheel, patches, creepages, pose, kin and kin.speed)
        if failure and not load_met(patches, q, settings.load_tolerance,
                                    settings.tangential_tolerance):
            wheel.status = NOT_CONVERGED
            wheel.message = failure
        _mark_uniqueness(wheel, patches, settings.friction, bool(previous),
                         creep_in_load=True)
        return wheel, mem if keep else []

    def _finish(self, wheel: WheelContact, patches: list[PatchSolution], creepages: list,
                pose: Pose, speed: float | None = None) -> WheelContact:
        if patches:
            wheel.creepages = creepages
            fill_resultants(wheel, patches, pose)
            if creepages:  # (side frame: the lateral and spin components mirrored)
                sgn = SIDES[wheel.side]
                per = 0.0
                for p, c in zip(patches, creepages, strict=True):
                    t = p.tangential
                    if t is not None:
                        fx, fy = t.force
                        per += fx * c[0] + sgn * (fy * c[1] + t.spin_moment * c[2])
                wheel.frictional_power_per_speed = per
                wheel.frictional_power = None if speed is None else speed * per
            if self.convention == "contact":  # the creepages and creep forces as CONTACT's
                wheel.creepages = [wheel_frame_creepage(c) for c in creepages]
                fx, fy = wheel.creep_force
                wheel.creep_force = (-fx, fy)
                for p in patches:
                    p.convention = "contact"
        return wheel

    def _pass(self, setup: WheelSetup, pose: Pose, control: Control,
              creep: tuple[float, float, float] | None, kin: Kinematics | None,
              time: float | None, previous: list[PatchMemory], source: list[PatchMemory],
              approach: float | None = None
              ) -> tuple[list[PatchSolution], list[tuple[float, float, float]],
                         list[PatchMemory]]:
        """One solve of a wheel's patches: the normal BEM under ``control``, then the
        tangential BEM; warm-started from ``source`` (the previous step's memory, or an
        earlier pass of this step), remembering ``previous`` as the older step."""
        side, settings = setup.side, setup.settings
        sgn = SIDES[side]
        pair = self.pair

        def estimate_for(cp: ContactPoint, hz: HertzSolution, ctrl: Control) -> WarmStart:
            def estimate() -> WarmStart:  # KP/INFCON cost a solve of their own: when needed
                return normal_estimate(settings.normal_settings, hz, cp.s, cp.f, cp.a_of_s,
                                       pair, ctrl)

            m = match(source, cp.rail_u, cp.position[2])
            if m is None:
                return estimate()

            def pressure_on(grid: Grid) -> NormalStart:  # (with A p, when the memory has it)
                p, shown = previous_start(m, grid, time)
                if shown is not None:  # (then p has pressure)
                    return NormalStart(p, shown)
                return NormalStart(p) if array_sum(p) > 0 else estimate().pressure_on(grid)
            # the potential area: where the contact was - unless the patch's rigid overlap
            # took in another remembered patch (two patches merged): then the rigid
            # overlap's, as from cold (the other's area lies outside this one's, and the
            # contact inside would not reach its edge); Hertz's penetration read only then
            bounds = (None if len(source) > 1 and merged(cp, m, source, hz.penetration)
                      else previous_bounds(m))
            return WarmStart("previous", pressure_on, bounds)

        # the frame at the reference point formed first at the approach of the step (or
        # pass) that starts this one, extrapolated in time: one pass in the common case
        start = _start(source, time) if source else None
        if start is not None and approach is not None and approach > 0:  # expected there
            start = (approach, start[1])
        patches = solve_wheel_normal(setup.track, setup.wheelset, pose, side, control,
                                     settings.patch_settings, pair, estimate_for,
                                     reference=settings.patch_frame == "reference",
                                     start=start)
        kept = [p for p in patches if p.normal.force > 0]
        charge(kept, [p for p in patches if p.normal.force <= 0])  # their work counts
        patches = kept
        creepages, memory = [], []
        approach = vertical_approach(patches)
        for patch in patches:
            cp = patch.geometry
            u, z = cp.rail_u, cp.position[2]
            m = match(source, u, z)  # None without warm start
            if creep is not None or kin is not None:
                c = creep if creep is not None else kin.creepage(cp, pose, setup.wheelset.radius)
                creepages.append(c)
                side_creep = [c[0], sgn * c[1], sgn * c[2]]
                t0 = perf_counter()
                # the traction extrapolated in time for SteadyGS only (previous_tangential)
                at = time if settings.tangential_solver != "convexgs" else None
                prev = previous_tangential(m, patch.normal.grid, at) if m else None
                patch.work.seconds += perf_counter() - t0
                solve_patch_tangential(patch, settings.tangential_settings, pair, settings.fft,
                                       creepage=side_creep, previous=prev)
            t = patch.tangential
            last = m if previous is source else match(previous, u, z)
            # the traction's rate smoothed over the steps (SteadyGS's extrapolation only;
            # its time is the patch's work, as the start it serves)
            rate = None
            if t is not None and settings.tangential_solver != "convexgs":
                t1 = perf_counter()
                rate = traction_rate(t.traction, patch.normal.grid, time, last)
                patch.work.seconds += perf_counter() - t1
            # what a newer step keeps of the older one: its traction and time for the
            # extrapolation, not its own older step or traction rate, which this step's
            # rate has taken in (the memory, and an FMU's saved state, stay two steps deep)
            older = None if last is None else replace(last, older=None, traction_rate=None)
            n = patch.normal
            memory.append(PatchMemory(
                grid=n.grid, pressure=n.pressure,
                traction=None if t is None else t.traction,
                state=None if t is None else t.state, u=u, z=z, time=time, older=older,
                vertical_creep=0.0 if t is None else
                float(t.force[1] * math.sin(cp.contact_angle)), approach=approach,
                vertical_normal=n.force * math.cos(cp.contact_angle), traction_rate=rate,
                displacement=n.displacement, element_box=n.contact_box))
        return patches, creepages, memory


def _mark_uniqueness(wheel: WheelContact, patches: list[PatchSolution], friction: float,
                     warm: bool, creep_in_load: bool) -> None:
    """Set the wheel's :attr:`~WheelContact.load_unique`, and say in an ok wheel's message
    why its load may have another solution: a merge of patches
    (:attr:`~railcontact.contact.results.PatchSolution.load_other`; the smallest approach
    is returned, from warm and cold starts alike) or a steep patch's creep force
    (:func:`~railcontact.contact.loadloop.load_unique`; the root the start leads to), the
    latter only where the creep forces are in the load (``creep_in_load``: load control
    with :attr:`ContactSettings.load_includes_creep`)."""
    steep = creep_in_load and not load_unique(patches, friction)
    other = next((p.load_other for p in patches if p.load_other is not None), None)
    wheel.load_unique = not steep and other is None
    if wheel.load_unique or wheel.status != OK:
        return
    why = []
    if other is not None:
        why.append("two of its contact regions join into one patch between this "
                   f"solution and another (approach {other * 1e6:.4g} um): the smallest "
                   "approach that carries the load is returned")
    if steep:
        which = ("the one continuous with the previous step" if warm else
                 "the one reached from the normal share Q (cold start)")
        why.append(f"several patches with mu tan(gamma) >= 1 on one: {which}")
    wheel.message = "ok; the load has more than one solution: " + "; ".join(why)


@dataclass(frozen=True)
class _RolledApproaches:
    """``phi -> (delta_L, delta_R)``: the vertical approaches [m] at which the wheels,
    the wheelset rolled to ``phi``, carry the step's loads with its creepages (the step's
    solve of each wheel, which leaves the contact's memory as it is; :mod:`.rigid`).

    With a warm start each wheel's solve starts from the solution nearest in pose: this
    step's last rolled solve of the wheel, else the previous step's at its root
    (``rolled``: its memory, :attr:`StepMemory.rolled`), else this step's
    own at the pose's roll; the older step it remembers is the previous step's at its root
    (else this step's). The solves at the root found are what the next step keeps
    (:meth:`memory_at`)."""

    contact: WheelsetContact
    pose: Pose
    loads: tuple[float, float]
    creepages: tuple | None
    kinematics: Kinematics | None
    time: float | None
    step: StepMemory = EMPTY_MEMORY
    """The memory of the wheels' solves at the step's own roll (the step's, or the
    previous step's when the step is not remembered)."""
    rolled: tuple[tuple[PatchMemory, ...], tuple[PatchMemory, ...]] | None = None
    """The previous step's memory of its wheels (left, right) at its root; None: none
    kept."""
    setups: tuple[WheelSetup, WheelSetup] | None = None
    """The wheels' rails, wheelsets and settings at the step (:class:`WheelSetup`)."""
    solved: dict = field(default_factory=dict, repr=False, compare=False)
    """The last call's roll [rad] and memory of its solves (``"roll"``, ``"memory"``)."""
    work: dict[str, Work] = field(
        default_factory=lambda: {"left": Work(load_passes=0), "right": Work(load_passes=0)},
        repr=False, compare=False)
    """The work of every wheel solve of the calls so far, per wheel (iterations, load
    passes, re-meshes, wall time [s]): a running count over this step's searches
    (:attr:`RigidSolution.work` is the part one search added)."""

    def __call__(self, phi: float, guess: tuple[float, float] | None = None
                 ) -> tuple[float, float]:
        """``guess``: the approaches [m] expected, at which each wheel's first pass forms
        its frame (scaled to the pass's load as Hertz's: the ``start`` of
        :func:`~railcontact.contact.wheelrail.solve_wheel_normal`). The solve forms the
        frame again while its approach misses the one the frame was formed at by more than
        :data:`~railcontact.contact.wheelrail.WARM_REFERENCE_RTOL`, as every solve started
        from an earlier one's approach does; within that the frame moves the approach by
        at most about a fifth of the rigid search's tolerance (:data:`~.rigid.RIGID_RTOL`
        of the approach; 0.16 for a frame 0.9e-3 off, solved tightly on the flange; 0.005
        on the tread), far below the solves' own scatter at the step's tolerances. So a
        wheel is not solved a second time when its approach misses the guess by more than
        :data:`~railcontact.contact.wheelrail.REFERENCE_RTOL`: that repeat would cost a
        solve in every second warm step, and in cold ones, where a solve without memory
        forms its frame from Hertz's approach, it would repeat the same solve."""
        pose = Pose(self.pose.lateral, self.pose.yaw, phi)
        out = []
        last = self.solved.get("memory")
        memory: list[tuple[PatchMemory, ...]] = []
        self.solved.clear()  # (a call that raises leaves none)
        for k, side in enumerate(("left", "right")):
            if negligible_load(self.loads[k]):
                out.append(0.0)
                memory.append(())
                continue
            older = (self.rolled[k] if self.rolled else ()) or self.step.wheel(side)
            start = (last[k] if last else ()) or older
            creep = None if self.creepages is None else self.creepages[k]
            wheel, mem = self.contact._solve_side(self.setups[k], pose,
                                                  Control(load=self.loads[k]),
                                                  creep, self.kinematics, self.time,
                                                  None if guess is None else guess[k],
                                                  (older, start, self.step.wheel(side)))
            _count(self.work[side], wheel)
            if not wheel.patches or wheel.status == NOT_CONVERGED:  # no approach to give
                raise RailContactError(f"{side} wheel at roll {phi:.6g} rad: "
                                       + (wheel.message if wheel.patches else "no contact"))
            out.append(wheel.approach)
            memory.append(tuple(mem))
        self.solved.update(roll=phi, memory=(memory[0], memory[1]))
        return out[0], out[1]

    def memory_at(self, phi: float
                  ) -> tuple[tuple[PatchMemory, ...], tuple[PatchMemory, ...]] | None:
        """The memory of the wheels' solves (left, right) at roll ``phi`` [rad] when the
        last call was there (what the next step starts from), else None."""
        return self.solved["memory"] if self.solved.get("roll") == phi else None


def _rigid_stage(rigid: RigidWheelset) -> RigidSolution:
    """The rigid wheelset's vertical displacement and roll (:meth:`RigidWheelset.solve`),
    or, when a wheel cannot be solved at a roll its search tries, a solution not
    converged that says why, with the work done until then."""
    try:
        return rigid.solve()
    except (RailContactError, SolverError) as exc:  # a wheel not solved at a roll
        done = rigid.approach_at.work  # (this step's: all of it is this search's)
        return RigidSolution(0.0, 0.0, converged=False,
                             message=f"rigid wheelset's vertical displacement and roll: {exc}",
                             work=(replace(done["left"]), replace(done["right"])))


def _count(work: Work, wheel: WheelContact) -> None:
    """Add a wheel solve's iterations, load passes, re-meshes and time to ``work``."""
    work.normal_iterations += wheel.normal_iterations
    work.tangential_iterations += wheel.tangential_iterations
    work.load_passes += wheel.load_passes
    work.remeshes += wheel.remeshes
    work.seconds += wheel.seconds


def _start(source: list[PatchMemory], time: float | None) -> tuple[float, float]:
    """The vertical approach [m] of a wheel and the vertical load [N] of its normal forces
    in the step ``source`` remembers, extrapolated linearly to ``time`` [s] from the step
    before it when both are known (:meth:`PatchMemory.extrapolation`)."""
    a, q = source[0].approach, sum([m.vertical_normal for m in source])
    older = [m.older for m in source]
    f = source[0].extrapolation(time)
    if f > 0 and None not in older and older[0].approach > 0:
        a_o, q_o = older[0].approach, sum([o.vertical_normal for o in older])
        a, q = max(a + f * (a - a_o), 0.5 * a), max(q + f * (q - q_o), 0.5 * q)
    return a, q


def _per_wheel(name: str, value, size: int, shape: str) -> tuple:
    """``value`` as a pair (left, right) of numbers (``size`` 1) or of ``size``-tuples."""
    try:
        pair = tuple(value)
        if len(pair) == 2 and size > 1:
            pair = tuple(tuple(v) for v in pair)
            ok = all(len(v) == size for v in pair)
        else:
            ok = len(pair) == 2 and all(not hasattr(v, "__len__") for v in pair)
    except TypeError:
        ok = False
    if not ok:
        raise RailContactError(f"{name} must be {shape}, got {value!r}")
    return pair


def _first_moments(grid: Grid, pressure: np.ndarray) -> tuple[float, float]:
    """The pressure's first moments ``sum x p dA``, ``sum y p dA`` [N m] about the grid's
    origin: ``(grid.x[:, None] * pressure).sum() * dA`` and the same with ``grid.y``, the
    products formed and added in numpy's order in one compiled pass (the same bits)."""
    da = grid.element_area
    if not pressure.flags.c_contiguous:  # (numpy's products would be laid out otherwise)
        return (float((grid.x[:, None] * pressure).sum() * da),
                float((grid.y[None, :] * pressure).sum() * da))
    sx, sy = _moment_sums(grid.x0, grid.dx, grid.y0, grid.dy, pressure)
    return float(sx * da), float(sy * da)


@numba.njit(cache=True, nogil=True)
def _moment_sums(x0, dx, y0, dy, p):  # pragma: no cover - compiled
    """``sum x p`` and ``sum y p`` over the grid's element centres (as :attr:`Grid.x`,
    :attr:`Grid.y` form them: ``x0 + dx i``), each product array added as numpy adds it."""
    nx, ny = p.shape
    out = np.empty((2, nx, ny))
    for i in range(nx):
        x = x0 + dx * float(i)
        for j in range(ny):
            out[0, i, j] = x * p[i, j]
            out[1, i, j] = (y0 + dy * float(j)) * p[i, j]
    return numpy_sum(out[0]), numpy_sum(out[1])


def fill_resultants(wheel: WheelContact, patches: list[PatchSolution], pose: Pose) -> None:
    """Fill ``wheel`` with the sums over its patches (module docstring for the frames).

    Scalars and 3-vectors in plain floats (a per-step path: numpy's calls cost more than
    their arithmetic here), in the order of operations the array forms had."""
    sgn = SIDES[wheel.side]
    u_ws = sgn * pose.lateral
    fx = fs = mn = n_tot = 0.0
    fu = fz = mz = 0.0
    m0 = m1 = m2 = 0.0
    converged = True
    work = Work()
    for p in patches:
        cp, n = p.geometry, p.normal
        g = cp.contact_angle
        cos_g, sin_g = math.cos(g), math.sin(g)
        t = p.tangential
        px, ps, pm = (0.0, 0.0, 0.0) if t is None else (*t.force, t.spin_moment)
        n_tot += n.force
        fx, fs, mn = fx + px, fs + ps, mn + pm
        f_u = ps * cos_g - n.force * sin_g
        fu += f_u
        f_z = ps * sin_g + n.force * cos_g
        fz += f_z
        # the pressure's first moments about the patch's origin (the contact point) along
        # x and s: the normal force acts at the pressure's centroid, not at the point
        first_x, first_s = _first_moments(n.grid, n.pressure)
        x, y, z = cp.position
        mz += (x * f_u - (cp.rail_u - u_ws) * px + pm * cos_g - first_x * sin_g)
        # track frame, about (0, y, 0): r x F, plus the spin couple (sgn pm) n (the
        # traction's moment about n through the origin), plus the pressure's offsets
        # x e_x + s e_s crossed with its normal n; e_s = (0, sgn cos(g), sin(g)),
        # n = (0, -sgn sin(g), cos(g)): e_x x n = (0, -cos(g), -sgn sin(g)), e_s x n =
        # (sgn, 0, 0)
        lx, ly, lz = float(x), float(y - pose.lateral), float(z)  # the lever r
        gx, gy, gz = float(px), float(sgn * f_u), float(f_z)  # the force F
        m0 += (ly * gz - lz * gy) + sgn * first_s
        m1 += (lz * gx - lx * gz) + (-pm * sin_g - first_x * cos_g)
        m2 += (lx * gy - ly * gx) + sgn * (pm * cos_g - first_x * sin_g)
        converged &= n.converged and (t is None or t.converged)
        work.absorb(p.work)
        work.load_passes = max(work.load_passes, p.work.load_passes)
    single = len(patches) == 1  # (the common case: no generators)
    main = patches[0] if single else max(patches, key=lambda p: p.normal.force)
    cp = main.geometry
    wheel.normal_force = n_tot
    wheel.creep_force = (fx, sgn * fs)
    wheel.spin_moment = sgn * mn
    wheel.track_force = (fx, sgn * fu, fz)
    wheel.yaw_moment = sgn * mz
    wheel.moment = (float(m0), float(m1), float(m2))
    wheel.derailment_quotient = derailment_quotient(sgn, wheel.track_force)
    wheel.approach = vertical_approach(patches)
    wheel.penetration = float(main.normal.penetration if single else
                              max(p.normal.penetration for p in patches))
    wheel.wheel_position = cp.wheel_s
    wheel.rail_position = cp.rail_y
    wheel.lateral_position = cp.position[1]
    wheel.contact_point = cp.position
    wheel.contact_angle = cp.contact_angle
    wheel.rolling_radius = cp.rolling_radius
    if single:
        wheel.area, wheel.max_pressure = float(main.normal.area), float(main.normal.max_pressure)
    else:
        wheel.area = float(sum(p.normal.area for p in patches))
        wheel.max_pressure = float(max(p.normal.max_pressure for p in patches))
    ts = [p.tangential for p in patches if p.tangential is not None]
    if len(ts) == 1:  # one patch: its own ratio, the same count (slip over non-exterior)
        wheel.slip_area_ratio = ts[0].slip_area_ratio
    elif ts:
        n_el = [int(np.count_nonzero(t.state)) for t in ts]
        n_slip = [int(np.count_nonzero(t.state == 2)) for t in ts]
        wheel.slip_area_ratio = sum(n_slip) / max(sum(n_el), 1)
    wheel.normal_iterations, wheel.tangential_iterations = (work.normal_iterations,
                                                            work.tangential_iterations)
    wheel.load_passes, wheel.remeshes, wheel.seconds = (work.load_passes, work.remeshes,
                                                        work.seconds)
    wheel.patches = patches
    if converged:
        wheel.status, wheel.message = OK, "ok"
    else:
        failed = [r.message for p in patches for r in (p.normal, p.tangential)
                  if r is not None and not r.converged]
        wheel.status = NOT_CONVERGED
        wheel.message = f"a BEM solve did not converge: {failed[0]}"


__all__ = ["ContactSettings", "Kinematics", "WheelContact", "WheelsetContact",
           "WheelsetResult", "STATUS_NAMES", "WARM_PROMISE"]
