"""The stages of a wheelset's time step, each a function of plain values.

:meth:`~railcontact.timestep.wheelset.WheelsetContact.solve` runs them in order on the
step's checked inputs (:class:`~.inputs.StepInputs`):

1. :func:`search_wheels` - each wheel searched at the pose, once
   (:func:`~railcontact.geometry.search.search_wheel`): every contact point, patch frame
   and load loop of the step is formed from that record;
2. :func:`solve_wheels` - both wheels solved from the previous step's memory
   (:func:`~.wheel.solve_step_wheel`), their validity checked, and what the next step
   keeps of them (a :class:`~.memory.StepMemory`);
3. :func:`rigid_wheelset_stage` - under load control, when the settings ask for it, the
   rigid wheelset's vertical displacement and roll at which both wheels carry their loads
   (:func:`~.rolled.rigid_stage`).

The result (:class:`~.results.WheelsetResult`) is formed from what they return; none of
them reads or writes the :class:`~.wheelset.WheelsetContact` itself: the memory they
start from is an argument, the memory for the next step a return value.
"""

from __future__ import annotations

from dataclasses import replace

from ..errors import CaseError, RailContactError, SolverError
from ..geometry.points import WheelSearch
from ..geometry.search import search_wheel
from ..geometry.track import SIDES, Pose
from ..halfspace.hertz import negligible_load
from ..halfspace.materials import ElasticPair
from ..settings import ContactSettings, Control
from ..status import status_of
from .inputs import SIDE_NAMES, StepInputs, WheelSetup
from .memory import EMPTY as EMPTY_MEMORY
from .memory import StepMemory
from .results import OUT_OF_RANGE, WheelContact
from .rigid import RigidSolution, RigidWheelset
from .rolled import RolledApproaches, rigid_stage
from .validity import check_validity
from .warmstart import PatchMemory
from .wheel import penetration_approach, solve_step_wheel

Found = tuple["WheelSearch | RailContactError", "WheelSearch | RailContactError"]
"""The step's search of each wheel (left, right): its record, or the error of a wheel beside
its rail."""


def search_wheels(step: StepInputs) -> Found:
    """Each wheel searched at the step's pose (:func:`~railcontact.geometry.search.
    search_wheel`): what its contact points and patch frames are formed from, or the
    :class:`RailContactError` of a wheel beside its rail."""
    left, right = step.setups
    return _searched(left, step.pose), _searched(right, step.pose)


def solve_wheels(step: StepInputs, found: Found, memory: StepMemory, pair: ElasticPair,
                 convention: str) -> tuple[list[WheelContact], StepMemory, bool]:
    """Both wheels solved (:func:`~.wheel.solve_step_wheel`) on their searches
    (``found``), each warm-started from the previous step's ``memory``, with the elastic
    ``pair`` in the ``convention`` of the creepages and creep forces; their validity
    checked. Returns the wheels, what the next step keeps of them, and whether a wheel is
    off its rail. A wheel that cannot be solved has its own status (the other still is);
    a wheel off its rail (beside it: its search's error, raised where the wheel has a load
    or a penetration to solve) puts the whole wheelset out of range."""
    wheels = []
    kept: list[tuple[PatchMemory, ...]] = []
    off_track = ""
    loads = step.loads
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
                control = Control(penetration=penetration_approach(searched, step.vertical))
            own = memory.wheel(side)
            wheel, remembered, _ = solve_step_wheel(
                setup, step.pose, control, step.creep(k), step.kinematics, step.time, pair,
                convention, (own, own, own), None,
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


def rigid_wheelset_stage(step: StepInputs, found: Found, wheels: list[WheelContact],
                         memory: StepMemory, last: StepMemory, settings: ContactSettings,
                         pair: ElasticPair, convention: str, remember: bool,
                         off_track: bool) -> tuple[tuple, StepMemory]:
    """The rigid wheelset's part of the step's result - ``(vertical, roll,
    rigid_solution, rigid_work)`` of :class:`~.results.WheelsetResult`, none where not
    solved - and the memory the next step starts from: this step's wheels' ``memory``
    (:func:`solve_wheels`) with the rigid wheelset's roots, or empty when the step is not
    remembered (``remember``) or the warm start does not use it (``settings``).

    Under penetration control the pose's vertical displacement and roll. Under load
    control, when ``settings.rigid_wheelset`` is "solve", no wheel is off its rail
    (``off_track``) and none is out of range, the vertical displacement and roll at which
    both ``wheels``,
    penetration-controlled, carry their loads (:func:`~.rolled.rigid_stage`): the wheels'
    least gaps at the step's roll from their searches ``found``, each other roll searched
    once; the wheels solved at other rolls start from this step's solves (the previous
    step's ``last`` memory when this one is not remembered) and from ``last``'s at its
    root."""
    keep = remember and settings.uses_previous  # (what the next step starts from)
    out = memory if keep else EMPTY_MEMORY
    pose = step.pose
    if step.vertical is not None:
        return (step.vertical, pose.roll, RigidSolution(step.vertical, pose.roll)), out
    if (off_track or settings.rigid_wheelset != "solve"
            or any(w.status == OUT_OF_RANGE for w in wheels)):
        # (none solved: the record's defaults; a wheel out of range - creepages beyond
        # the solver's, a patch beyond the half-space - has no solution for the rigid
        # wheelset to balance)
        return (), out
    older = last if settings.uses_previous else EMPTY_MEMORY
    rigid = RigidWheelset(
        *step.geometry(), pose, (wheels[0].approach, wheels[1].approach),
        tuple((w.lateral_position, w.rolling_radius, w.contact_angle)
              if w.patches else None for w in wheels),
        RolledApproaches(pose, step.loads, step.creepages, step.kinematics, step.time, pair,
                         convention, out if remember else last, older.rolled, step.setups),
        history=older.rigid, time=step.time,
        gaps=None if any(isinstance(f, RailContactError) for f in found) else
        (found[0].least_gap, found[1].least_gap))
    s = rigid_stage(rigid)
    if keep:
        roots, rolled = rigid.remembered(s)
        out = replace(out, rigid=roots, rolled=rolled)
    # (vertical and roll: found, or the best estimate; none when the search raised)
    return ((s.vertical, s.roll) if s.evaluations else (None, None)) + (s, s.wheel_work), out


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


__all__ = ["Found", "rigid_wheelset_stage", "search_wheels", "solve_wheels"]
