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
radius r and contact angle gamma, with side sign s = +1 left, -1 right, on a track of
curvature k (the rails turn with -V k relative to the track frame)::

    xi  = (V - Omega r - psi_dot (Y_c - y) - V k Y_c) / V
    eta = (y_dot - V psi) / (V cos gamma)
    phi = (-s Omega sin gamma + (psi_dot + V k) cos gamma) / V

The lateral creepage takes the wheel as following its rail's surface at the patch (its
vertical velocity ``y_dot tan gamma`` there: the constraint of a wheel in contact), where a
case file's ``[kinematics]`` (:mod:`railcontact.geometry.kinematics`, CONTACT's rigid
slip) takes the wheelset's vertical velocity as given: with ``vertical_velocity = 0`` a
flange patch's eta differs by ``1 / cos^2 gamma``. The rails' deviations
(:class:`RailDeviation`) are positions at the step: their rates do not enter the
creepages (rails moving alike: fold their lateral rate into ``lateral_velocity``).

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

from dataclasses import replace
from time import perf_counter

from ..errors import CaseError, RailContactError, SolverError
from ..geometry.points import WheelSearch
from ..geometry.search import search_wheel
from ..geometry.track import SIDES, Pose, Track, Wheelset
from ..halfspace.hertz import negligible_load
from ..halfspace.materials import ElasticPair
from ..settings import ContactSettings, Control
from ..settings.case import check_convention
from ..status import status_of
from .inputs import (  # noqa: F401  (the step's records, importable from here too)
    MAX_CURVATURE,
    NO_DEVIATION,
    SIDE_NAMES,
    Kinematics,
    RailDeviation,
    Setups,
    StepInputs,
    WheelSetup,
    per_wheel,
    sides,
    step_inputs,
)
from .memory import EMPTY as EMPTY_MEMORY
from .memory import StepMemory
from .results import (  # noqa: F401  (the step's records, importable from here too)
    NO_CONTACT,
    NOT_CONVERGED,
    OK,
    OUT_OF_RANGE,
    OUTSIDE_VALIDITY,
    SEVERITY,
    STATUS_NAMES,
    WheelContact,
    WheelsetResult,
    resultants,
)
from .rigid import RigidSolution, RigidWheelset
from .rolled import RolledApproaches, rigid_stage
from .validity import check_validity
from .warmstart import PatchMemory
from .wheel import penetration_approach, solve_step_wheel

Found = tuple["WheelSearch | RailContactError", "WheelSearch | RailContactError"]
"""The step's search of each wheel (left, right): its record, or the error of a wheel beside
its rail."""

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
        self.tracks: tuple[Track, Track] = sides("track", track, Track)
        """The rails' tracks (left, right)."""
        self.wheelsets: tuple[Wheelset, Wheelset] = sides("wheelset", wheelset, Wheelset)
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
        self._setups = Setups(self.tracks, self.wheelsets)
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
        step = self._inputs(pose, loads, vertical, creepages, kinematics, time, rails,
                            friction)
        found = self._search(step)
        wheels, memory, off_track = self._wheels(step, found)
        rigid, memory = self._rigid_stage(step, found, wheels, memory, remember, off_track)
        if remember:
            self.memory = memory
        return WheelsetResult(wheels[0], wheels[1], perf_counter() - t0,
                              self.wheelset.radius, *rigid)

    # -- its stages --------------------------------------------------------------------
    def _inputs(self, pose: Pose, loads: tuple[float, float] | None, vertical: float | None,
                creepages: tuple | None, kinematics: Kinematics | None, time: float | None,
                rails: tuple[RailDeviation, RailDeviation] | None,
                friction: tuple[float, float] | None) -> StepInputs:
        """The step's inputs checked (:meth:`solve`'s parameters), with each wheel's
        setup (:class:`WheelSetup`)."""
        return step_inputs(pose, loads, vertical, creepages, kinematics, time,
                           self._setups.at(self.settings, rails, friction), self.convention)

    def _search(self, step: StepInputs) -> Found:
        """Each wheel searched at the step's pose (:func:`~railcontact.geometry.search.
        search_wheel`): what its contact points and patch frames are formed from, or the
        :class:`RailContactError` of a wheel beside its rail."""
        left, right = step.setups
        return _searched(left, step.pose), _searched(right, step.pose)

    def _wheels(self, step: StepInputs, found: Found
                ) -> tuple[list[WheelContact], StepMemory, bool]:
        """Both wheels solved (:func:`~.wheel.solve_step_wheel`) on their searches
        (``found``), each warm-started from this contact's memory, their validity checked,
        what the next step keeps of them, and whether a wheel is off its rail. A wheel
        that cannot be solved has its own status (the other still is); a wheel off its
        rail (beside it: its search's error, raised where the wheel has a load or a
        penetration to solve) puts the whole wheelset out of range."""
        wheels = []
        kept: list[tuple[PatchMemory, ...]] = []
        off_track = ""
        loads, memory = step.loads, self.memory
        for k, setup in enumerate(step.setups):
            side = setup.side
            try:
                searched = found[k]
                if loads is not None:
                    control = Control(load=loads[k])
                    if isinstance(searched, RailContactError) and not negligible_load(
                            control.load) and control.value != 0.0:
                        raise searched
                else:
                    if isinstance(searched, RailContactError):
                        raise searched
                    control = Control(penetration=penetration_approach(searched,
                                                                       step.vertical))
                own = memory.wheel(side)
                wheel, remembered, _ = solve_step_wheel(
                    setup, step.pose, control, step.creep(k), step.kinematics, step.time,
                    self.pair, self.convention, (own, own, own), None,
                    None if isinstance(searched, RailContactError) else searched)
            except (CaseError, SolverError) as exc:  # (the penetration's control)
                wheel, remembered = WheelContact(side, status_of(exc), str(exc)), ()
            except RailContactError as exc:  # the pose: beyond the profiles, into the rail
                text = str(exc)  # (it may name its wheel already)
                off_track = off_track or (text if text.startswith(f"{side} wheel")
                                          else f"{side} wheel: {text}")
                wheel, remembered = WheelContact(side=side), ()
            wheels.append(wheel)
            kept.append(remembered)
        if off_track:  # a wheelset with a wheel off its rail has no contact forces to give
            msg = f"wheelset out of range: {off_track}"
            return ([WheelContact(side=s, status=OUT_OF_RANGE, message=msg)
                     for s in SIDE_NAMES], EMPTY_MEMORY, True)
        wheels = [_checked(wheel, setup) for wheel, setup in zip(wheels, step.setups,
                                                                  strict=True)]
        return wheels, StepMemory(kept[0], kept[1]), False

    def _rigid_stage(self, step: StepInputs, found: Found, wheels: list[WheelContact],
                     memory: StepMemory, remember: bool, off_track: bool
                     ) -> tuple[tuple, StepMemory]:
        """The rigid wheelset's part of the step's result - ``(vertical, roll,
        rigid_solution, rigid_work)`` of :class:`WheelsetResult` - under load control
        solved when the settings ask for it (:func:`~.rolled.rigid_stage`; the wheels'
        least gaps at the step's roll from their searches ``found``, each other roll
        searched once), and the memory the next step starts from (empty when it is not
        remembered or the warm start does not use it)."""
        keep = remember and self.settings.uses_previous  # (what the next step starts from)
        out = memory if keep else EMPTY_MEMORY
        pose = step.pose
        values: tuple = ()  # (none solved: the record's defaults)
        if step.vertical is not None:
            values = (step.vertical, pose.roll, RigidSolution(step.vertical, pose.roll))
        elif not off_track and self.settings.rigid_wheelset == "solve":
            last = self.memory if self.settings.uses_previous else EMPTY_MEMORY
            # the rolled wheels start from this step's solves (the previous step's when
            # this one is not remembered) and from the previous step's at its root
            rigid = RigidWheelset(
                *step.geometry(), pose, (wheels[0].approach, wheels[1].approach),
                tuple((w.lateral_position, w.rolling_radius, w.contact_angle)
                      if w.patches else None for w in wheels),
                RolledApproaches(pose, step.loads, step.creepages, step.kinematics,
                                 step.time, self.pair, self.convention,
                                 out if remember else self.memory, last.rolled, step.setups),
                history=last.rigid, time=step.time,
                gaps=None if any(isinstance(f, RailContactError) for f in found) else
                (found[0].least_gap, found[1].least_gap))
            s = rigid_stage(rigid)
            if keep:
                roots, rolled = rigid.remembered(s)
                out = replace(out, rigid=roots, rolled=rolled)
            # (vertical and roll: found, or the best estimate; none when the search raised)
            values = ((s.vertical, s.roll) if s.evaluations else (None, None)) + (s, s.work)
        return values, out

    def rolled_approaches(self, pose: Pose, *, loads: tuple[float, float],
                          creepages: tuple | None = None,
                          kinematics: Kinematics | None = None,
                          time: float | None = None) -> RolledApproaches:
        """``phi -> (delta_L, delta_R)``: the vertical approaches [m] at which the wheels,
        the wheelset at ``pose`` rolled to ``phi`` [rad], carry ``loads`` [N] with the
        creepages - the function the rigid wheelset's stage searches
        (:class:`RolledApproaches`), started from this contact's memory as that stage's
        is. Each call solves both wheels (for studies and tests; a step forms its own)."""
        rolled = self.memory.rolled if self.settings.uses_previous else None
        return RolledApproaches(pose, loads, creepages, kinematics, time, self.pair,
                                self.convention, self.memory, rolled,
                                self._setups.at(self.settings, None, None))



def _checked(wheel: WheelContact, setup: WheelSetup) -> WheelContact:
    """The solved ``wheel`` with its validity checked (:func:`~.validity.check_validity`):
    an ok wheel beyond a limit is OUTSIDE_VALIDITY, its message naming each quantity and
    value (:meth:`~.results.WheelContact.with_validity`)."""
    if not wheel.patches:
        return wheel
    return wheel.with_validity(check_validity(SIDES[wheel.side], wheel.track_force,
                                              wheel.patches, setup.wheelset.flange_flank,
                                              setup.settings))


def _searched(setup: WheelSetup, pose: Pose) -> WheelSearch | RailContactError:
    """The wheel of ``setup`` searched at ``pose`` (:func:`~railcontact.geometry.search.
    search_wheel`), or the :class:`RailContactError` of a wheel beside its rail."""
    try:
        return search_wheel(setup.track, setup.wheelset, pose, setup.side)
    except RailContactError as exc:
        return exc


__all__ = ["WARM_PROMISE", "WheelsetContact"]
