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

import numpy as np

from ..errors import RailContactError
from ..geometry.track import Pose, Track, Wheelset
from ..halfspace.materials import ElasticPair
from ..settings import ContactSettings
from ..settings.case import check_convention
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
from .rolled import RolledApproaches
from .stages import Found, rigid_wheelset_stage, search_wheels, solve_wheels  # noqa: F401

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
        if not isinstance(pair, ElasticPair):
            raise RailContactError(f"pair must be an ElasticPair, got {pair!r}")
        if settings is not None and not isinstance(settings, ContactSettings):
            raise RailContactError(f"settings must be ContactSettings, got {settings!r}")
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
        """Solve both wheels: the step's stages (:mod:`~.stages`) on its checked inputs -
        each wheel searched, both wheels solved from the previous step's memory, the rigid
        wheelset's vertical displacement and roll where the settings ask for them - and
        the result formed from them; the memory they give is the next step's start.

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
        if not isinstance(remember, (bool, np.bool_)):  # ("no" would read as True)
            raise RailContactError(f"remember must be True or False, got {remember!r}")
        step = self._inputs(pose, loads, vertical, creepages, kinematics, time, rails,
                            friction)
        found = search_wheels(step)
        wheels, memory, off_track = solve_wheels(step, found, self.memory, self.pair,
                                                 self.convention)
        rigid, memory = rigid_wheelset_stage(step, found, wheels, memory, self.memory,
                                             self.settings, self.pair, self.convention,
                                             remember, off_track)
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
        k = self.pair.difference
        if k != 0.0 and (creepages is not None or kinematics is not None):
            raise RailContactError(f"the pair's bodies are dissimilar (Kalker's K = {k:.3g}), "
                                   "which couples normal and tangential contact; the "
                                   "tangential BEM takes quasi-identical bodies only (K = 0)")
        return step_inputs(pose, loads, vertical, creepages, kinematics, time,
                           self._setups.at(self.settings, rails, friction), self.convention)

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



__all__ = ["WARM_PROMISE", "WheelsetContact"]
