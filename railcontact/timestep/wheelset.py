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

import math
from dataclasses import replace
from time import perf_counter

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
from ..contact.results import PatchSolution
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
from ..halfspace.sums import array_sum
from ..settings import ContactSettings, Control
from ..settings.case import MAX_PENETRATION, check_convention
from ..settings.convention import wheel_frame_creepage
from ..status import status_of
from .inputs import (  # noqa: F401  (the step's records, importable from here too)
    MAX_CURVATURE,
    NO_DEVIATION,
    SIDE_NAMES,
    Kinematics,
    RailDeviation,
    WheelSetup,
    per_wheel,
    sides,
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
    fill_resultants,
)
from .rigid import RigidSolution, RigidWheelset
from .rolled import RolledApproaches, rigid_stage
from .validity import check_validity
from .warmstart import (
    PatchMemory,
    match,
    merged,
    previous_bounds,
    previous_start,
    previous_tangential,
    traction_rate,
)

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
        self._placed: dict = {}  # (side, deviation) -> the rail deviated (the last ones)
        self._settings_of: dict = {}  # friction -> the settings with it (the last ones)
        self._friction_base: ContactSettings | None = None  # (what they were made from)
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
            loads = per_wheel("loads", loads, 1, "(left, right) [N]")
        if creepages is not None:
            creepages = per_wheel("creepages", creepages, 3,
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
                RolledApproaches(self._solve_side, pose, loads, creepages, kinematics, time,
                                  step if remember else self.memory, last.rolled, setups),
                history=last.rigid, time=time)
            s = rigid_stage(rigid)
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
                          time: float | None = None) -> RolledApproaches:
        """``phi -> (delta_L, delta_R)``: the vertical approaches [m] at which the wheels,
        the wheelset at ``pose`` rolled to ``phi`` [rad], carry ``loads`` [N] with the
        creepages - the function the rigid wheelset's stage searches
        (:class:`RolledApproaches`), started from this contact's memory as that stage's
        is. Each call solves both wheels (for studies and tests; a step forms its own)."""
        rolled = self.memory.rolled if self.settings.uses_previous else None
        return RolledApproaches(self._solve_side, pose, loads, creepages, kinematics, time,
                                self.memory, rolled, self._setups(None, None))

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
            rails = per_wheel("rails", rails, 1, "(left, right) RailDeviation")
            for r in rails:
                if not isinstance(r, RailDeviation):
                    raise RailContactError(f"rails must be RailDeviation records, got {r!r}")
        if friction is not None:
            friction = tuple(check_positive(f"{s} friction", float(mu), "")
                             for s, mu in zip(SIDE_NAMES,
                                              per_wheel("friction", friction, 1,
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

    def _with_friction(self, mu: float) -> ContactSettings:
        """The settings with the coefficient of friction ``mu`` (the last few kept)."""
        if self._friction_base is not self.settings:  # (the settings were replaced)
            self._friction_base, self._settings_of = self.settings, {}
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
        solves, :class:`RolledApproaches`). ``memory``: (the older step remembered, the
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
            older = None if last is None else last.without_older()
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


__all__ = ["WARM_PROMISE", "WheelsetContact"]
