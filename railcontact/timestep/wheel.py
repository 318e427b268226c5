"""One wheel at a time step: the wheel solver (:func:`railcontact.contact.wheelrail.
solve_wheel`) started from the previous step (:class:`StepStart`), and its
:class:`~.results.WheelContact` (:func:`solve_step_wheel`).

Each pass of the wheel's solve (:mod:`railcontact.contact.loadloop`) solves the normal BEM
of its patches, warm-started from the previous step's memory (or the pass before in this
step) re-meshed onto the new grids (:mod:`.warmstart`), then the tangential BEM of each
patch, and keeps what the next step starts from (:class:`~.warmstart.PatchMemory`). The
first normal share of the creep-load loop is the load less the previous step's creep share
(cold: Kalker's saturated linear estimate of it,
:func:`~railcontact.contact.loadloop.vertical_creep_estimate`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from time import perf_counter

from ..contact.loadloop import charge, vertical_approach, vertical_creep_estimate
from ..contact.patch import normal_estimate, solve_patch_tangential
from ..contact.start import NormalStart, StagedNormal, WarmStart, no_start
from ..contact.wheel import WheelPass, WheelProblem, WheelSettings, WheelSolution
from ..contact.wheelrail import solve_wheel, solve_wheel_normal, wheel_problem
from ..errors import RailContactError, SolverError
from ..geometry.points import ContactPoint, WheelSearch, at_reference, samples
from ..geometry.track import SIDES, Pose
from ..halfspace.grid import Grid
from ..halfspace.hertz import HertzSolution, hertz
from ..halfspace.materials import ElasticPair
from ..halfspace.sums import array_sum
from ..settings import Control, GridSettings, NormalSettings
from ..settings.case import MAX_PENETRATION
from ..settings.convention import wheel_frame_creepage
from ..status import Status
from .compiled import warm_normal, warm_tangential
from .inputs import Kinematics, WheelSetup, solver_settings
from .results import NOT_CONVERGED, OK, WheelContact, resultants
from .warmstart import (
    RATE_GAIN,
    PatchMemory,
    _previous_pressure,
    _previous_tangential,
    match,
    merged,
    previous_bounds,
    traction_rate,
)

Memory = tuple[PatchMemory, ...]
"""One wheel's remembered patches."""


@dataclass(frozen=True, slots=True)
class StepStart:
    """How a wheel's passes start at a time step (a :class:`~railcontact.contact.wheel.
    WheelStart`).

    Attributes
    ----------
    setup
        The wheel's rail, wheelset and settings at the step.
    creep
        The creepages (xi, eta, phi) of every patch ...
    kinematics
        ... or the wheelset velocities they follow from; neither: normal contact only.
    time
        The step's time [s] (None: no extrapolation in time).
    previous
        The older step remembered (the traction's rate and the extrapolation).
    first
        The solution the first pass starts from (later passes: the one before).
    own
        The step whose creep share starts the load loop; empty: cold (estimated).
    approach
        The vertical approach [m] expected, at which the first pass forms its frame
        (instead of the remembered step's, extrapolated); None: that one.
    """

    setup: WheelSetup
    creep: tuple[float, float, float] | None
    kinematics: Kinematics | None
    time: float | None
    previous: Memory = ()
    first: Memory = ()
    own: Memory = ()
    approach: float | None = None

    def share(self, problem: WheelProblem, settings: WheelSettings, load: float) -> float:
        """The creep forces' share [N] of the vertical ``load`` [N]: the remembered
        step's; cold, estimated on the Hertz ellipse where the normal solve forms its
        frame."""
        own = self.own
        if own:
            if len(own) == 1:  # (as sum() forms it: 0 + the one share)
                return 0 + own[0].vertical_creep
            return sum(m.vertical_creep for m in own)
        cp, s = problem.first, self.setup.settings
        if (s.patch_frame == "reference" and math.isfinite(cp.B) and cp.B > 0
                and cp.A > 0):
            cosg = math.cos(cp.contact_angle)
            approach = hertz(cp.A, cp.B, problem.pair, load=load / cosg).penetration / cosg
            cp = at_reference(problem.found, cp, approach) or cp
        c = self.creepage(cp, problem)
        sgn = SIDES[problem.side]
        return vertical_creep_estimate(cp, load, (c[0], sgn * c[1], sgn * c[2]),
                                       problem.pair, s.friction)

    def creepage(self, cp: ContactPoint, problem: WheelProblem
                 ) -> tuple[float, float, float]:
        """The creepages of the patch at ``cp`` (railcontact's, contact frame)."""
        if self.creep is not None:
            return self.creep
        return self.kinematics.creepage(cp, problem.pose, problem.wheelset.radius)

    def solve_pass(self, problem: WheelProblem, settings: WheelSettings, control: Control,
                   before: WheelPass | None) -> WheelPass:
        """One solve of the wheel's patches: the normal BEM under ``control``, then the
        tangential BEM; warm-started from :attr:`first` (the first pass) or ``before``'s
        memory (:class:`PassStart`), remembering :attr:`previous` as the older step."""
        s, pair, time = self.setup.settings, problem.pair, self.time
        source = self.first if before is None else before.memory
        previous = self.previous
        # the frame at the reference point formed first at the approach of the step (or
        # pass) that starts this one, extrapolated in time: one pass in the common case
        factor = source[0].extrapolation(time) if source else 0.0
        start = _start(source, factor) if source else None
        approach = self.approach if before is None else None
        if start is not None and approach is not None and approach > 0:  # expected there
            start = (approach, start[1])
        starts = PassStart(source, time, s, pair, factor, problem.found)
        patches = solve_wheel_normal(problem.track, problem.wheelset, problem.pose,
                                     problem.side, control, settings.patch, pair, starts,
                                     reference=settings.reference, start=start,
                                     problem=problem,
                                     load_tolerance=settings.normal_load_tolerance,
                                     load_acceptance=settings.load_acceptance)
        kept, dropped = [], []
        for p in patches:
            (kept if p.normal.force > 0 else dropped).append(p)
        if dropped:
            kept = charge(kept, dropped)  # their work counts
        creepages, memory, patches = [], [], []
        approach = vertical_approach(kept)
        tangential = settings.tangential is not None
        # the traction extrapolated in time, and its rate kept, for SteadyGS only
        # (previous_tangential, traction_rate)
        steady = s.tangential_solver != "convexgs"
        sgn = SIDES[problem.side]
        for patch in kept:
            cp, n = patch.geometry, patch.normal
            u, z = cp.rail_u, cp.position[2]
            ps = starts.last  # (the start of this patch's contact point: its match)
            if ps is not None and ps[0] is cp:
                m, c = ps[1], ps[2]
            else:
                m = match(source, u, z) if source else None  # None without warm start
                c = 0.0 if m is None else m.extrapolation(time)
            last = m if previous is source else match(previous, u, z)
            done = False
            if tangential:
                k = self.creepage(cp, problem)
                creepages.append(k)
                creepage = (k[0], sgn * k[1], sgn * k[2])
                # the warm stage in one compiled call where it is one (its work counted)
                if m is not None and steady:
                    patch, done, rate = warm_tangential(patch, settings.tangential, pair,
                                                        s.fft, creepage, m, c, last, time,
                                                        RATE_GAIN)
            if tangential and not done:
                t0 = perf_counter()
                prev = None
                if m is not None:  # (the factor at the step's time for SteadyGS, else 0)
                    prev = ((None, None) if m.traction is None or m.state is None else
                            _previous_tangential(m, c if steady else 0.0, n.grid))
                seconds = patch.work.seconds
                patch = solve_patch_tangential(patch, settings.tangential, pair, s.fft,
                                               creepage=list(creepage), previous=prev)
                seconds = patch.work.seconds - seconds  # (the solve's own, which it kept)
            t = patch.tangential
            # the traction's rate smoothed over the steps; its time, and the start's, is
            # the patch's work (the interval less the solve's own)
            if not done:
                rate = (traction_rate(t.traction, n.grid, time, last)
                        if t is not None and steady else None)
            if tangential and not done:
                patch = patch.replaced(work=patch.work.plus_seconds(
                    (perf_counter() - t0) - seconds))
            patches.append(patch)
            # what a newer step keeps of the older one: its traction and time for the
            # extrapolation, not its own older step or traction rate, which this step's
            # rate has taken in (the memory, and an FMU's saved state, stay two steps deep)
            g = cp.contact_angle
            memory.append(PatchMemory(
                n.grid, n.pressure, None if t is None else t.traction,
                None if t is None else t.state, u, z, time,
                None if last is None else last.without_older(),
                0.0 if t is None else float(t.force[1] * math.sin(g)), approach,
                n.force * math.cos(g), rate, n.displacement, n.contact_box))
        return WheelPass(patches, creepages, memory)


class PassStart:
    """The start of each patch of a wheel's pass (``estimate_for`` of
    :func:`~railcontact.contact.wheelrail.solve_wheel_normal`): the remembered patch the
    contact point matches (:func:`~.warmstart.match`), else the settings' estimate.

    Parameters
    ----------
    source
        The remembered patches the pass starts from (empty: cold).
    time
        The step's time [s] (None: no extrapolation in time).
    settings
        The wheel's :class:`~railcontact.settings.ContactSettings`.
    pair
        The elastic pair.
    factor
        The extrapolation factor of the first remembered patch to ``time``.
    found
        The wheel searched at the step's pose, whose run the compiled normal stage's
        reach check reads (:func:`~.compiled.warm_normal`; None: no such stage).
    """

    __slots__ = ("factor", "found", "last", "pair", "settings", "source", "time")

    def __init__(self, source: Memory, time: float | None, settings, pair: ElasticPair,
                 factor: float, found: WheelSearch | None = None) -> None:
        self.source, self.time, self.settings, self.pair = source, time, settings, pair
        self.factor = factor
        """The extrapolation factor of the first remembered patch to ``time``
        (:meth:`~.warmstart.PatchMemory.extrapolation`)."""
        self.found = found
        """The wheel searched at the step's pose (None: no compiled normal stage)."""
        self.last: tuple[ContactPoint, PatchMemory | None, float] | None = None
        """The last patch start formed: its contact point, the remembered patch it matches
        and that patch's extrapolation factor (read again after the normal solve). Not the
        :class:`PatchStart`, which holds this pass: a step's records form no reference
        cycle, so that they are freed when dropped, not by the garbage collector."""

    def __call__(self, cp: ContactPoint, hz: HertzSolution | None, ctrl: Control
                 ) -> WarmStart:
        """The start of the patch at ``cp`` (Hertz's solution ``hz`` when formed, the
        normal ``ctrl``): the remembered patch's (:class:`PatchStart`), with the potential
        area where its contact was - unless the patch's rigid overlap took in another
        remembered patch (two patches merged): then the rigid overlap's, as from cold
        (the other's area lies outside this one's, and the contact inside would not reach
        its edge); Hertz's penetration read only then."""
        source = self.source
        m = match(source, cp.rail_u, cp.position[2]) if source else None
        start = PatchStart(self, cp, hz, ctrl, m)
        self.last = (cp, m, start.factor)
        if m is None:
            return start.estimate()
        bounds = (None if len(source) > 1 and merged(cp, m, source,
                                                     start.hertz().penetration)
                  else previous_bounds(m))
        return WarmStart("previous", start.pressure_on, bounds, normal_stage=start.solve)


class PatchStart:
    """One patch's start in a pass (:class:`PassStart`): the remembered patch ``memory``
    (None: none) extrapolated to the step's time, else the settings' estimate on the
    Hertz solution at ``cp`` (``hz``, or formed when needed under ``ctrl``; KP/INFCON cost
    a solve of their own: formed only when needed)."""

    __slots__ = ("cp", "ctrl", "factor", "hz", "memory", "of")

    def __init__(self, of: PassStart, cp: ContactPoint, hz: HertzSolution | None,
                 ctrl: Control, memory: PatchMemory | None) -> None:
        self.of, self.cp, self.hz, self.ctrl, self.memory = of, cp, hz, ctrl, memory
        self.factor = (0.0 if memory is None else of.factor if memory is of.source[0]
                       else memory.extrapolation(of.time))

    def hertz(self) -> HertzSolution:
        """Hertz's solution at the contact point (formed here only where it is needed)."""
        if self.hz is None:
            cp = self.cp
            self.hz = hertz(cp.A, cp.B, self.of.pair, **self.ctrl.kwargs())
        return self.hz

    def estimate(self) -> WarmStart:
        """The settings' estimate (a patch without a remembered one, or one whose
        remembered pressure is gone)."""
        of = self.of
        settings = of.settings.normal_settings
        if settings.estimate == "none":  # (normal_estimate's answer, without its inputs)
            return no_start("none")
        return normal_estimate(settings, self.hertz(), *samples(self.cp)[:3], of.pair,
                               self.ctrl)

    def solve(self, cp: ContactPoint, bounds: tuple[float, float, float, float],
              grid_settings: GridSettings, settings: NormalSettings, pair: ElasticPair,
              control: Control) -> StagedNormal | None:
        """The patch's first normal solve from this start and the check of its overlap in
        one compiled call (:func:`~.compiled.warm_normal`; the start's
        :attr:`~railcontact.contact.start.WarmStart.normal_stage`)."""
        return warm_normal(cp, bounds, grid_settings, settings, pair, control, self.of.found,
                           self.memory, self.factor)

    def pressure_on(self, grid: Grid) -> NormalStart:
        """The remembered pressure extrapolated onto ``grid``, with its ``A p`` when the
        memory has it (:func:`~.warmstart.previous_start`); without pressure left, the
        estimate's."""
        m, c = self.memory, self.factor
        p, shown = _previous_pressure(m, m.older if c > 0 else None, c, grid, True)
        if shown is not None:  # (then p has pressure)
            return NormalStart(p, shown)
        return NormalStart(p) if array_sum(p) > 0 else self.estimate().pressure_on(grid)


def wheel_settings(setup: WheelSetup, tangential: bool) -> WheelSettings:
    """The wheel solver's settings of a step's wheel (``tangential``: creepages or
    velocities given): its setup's (:attr:`~.inputs.WheelSetup.solvers`), else formed
    (:func:`~.inputs.solver_settings`)."""
    solvers = setup.solvers
    if solvers is not None:
        return solvers[1] if tangential else solvers[0]
    return solver_settings(setup.settings, tangential)


def solve_step_wheel(setup: WheelSetup, pose: Pose, control: Control,
                     creep: tuple[float, float, float] | None, kin: Kinematics | None,
                     time: float | None, pair: ElasticPair, convention: str,
                     memory: tuple[Memory, Memory, Memory], approach: float | None = None,
                     found: WheelSearch | None = None
                     ) -> tuple[WheelContact, Memory, RailContactError | SolverError | None]:
    """One wheel of a step: its :class:`~.results.WheelContact`, what the next step keeps
    of it, and the exception its solve raised (None; the wheel's status and message are
    then its).

    ``memory``: (the older step remembered, the solution the first pass starts from, the
    step whose creep share starts the load loop) - the previous step's for all three, or
    the rolled wheelset's (:class:`~.rolled.RolledApproaches`); none of it is read, and
    nothing kept, when the settings' warm start does not use the previous step.
    ``approach``: the vertical approach [m] expected, where the first pass forms its frame.
    ``found``: the wheel searched at ``pose`` (:func:`~railcontact.geometry.search.
    search_wheel`; None: searched here). Raises a :class:`RailContactError` for a pose
    beyond the profiles or off the rail."""
    side, settings = setup.side, setup.settings
    keep = settings.uses_previous
    previous, first, own = memory if keep else ((), (), ())
    tangential = creep is not None or kin is not None
    start = StepStart(setup, creep, kin, time, previous, first, own, approach)
    problem = wheel_problem(setup.track, setup.wheelset, pose, side, pair, control, found)
    solver = wheel_settings(setup, tangential)
    solution = solve_wheel(problem, solver, start)
    if (first or own) and solution.status == Status.NOT_CONVERGED and solution.error is None:
        # a load loop that stalled from the remembered step (on a flange at the tangential
        # BEM's noise floor the vertical force depends on the start by about the load
        # tolerance): solved again cold, as a table point is; the answer kept is the one
        # that meets the load, the work of both counted
        cold = solve_wheel(problem, solver, StepStart(setup, creep, kin, time, previous))
        if cold.status != Status.NOT_CONVERGED and cold.error is None:
            solution = replace(cold, patches=charge(cold.patches, solution.patches),
                               seconds=cold.seconds + solution.seconds)
    creep_in_load = control.by_load and tangential and settings.load_includes_creep
    wheel = wheel_contact(side, solution, pose, kin and kin.speed, convention,
                          warm=bool(previous), creep_in_load=creep_in_load)
    return wheel, tuple(solution.memory or ()) if keep else (), solution.error


def wheel_contact(side: str, solution: WheelSolution, pose: Pose, speed: float | None,
                  convention: str, warm: bool = False, creep_in_load: bool = False
                  ) -> WheelContact:
    """The :class:`~.results.WheelContact` of a wheel's ``solution``: its patches summed
    (:func:`~.results.resultants`), the frictional power (with the forward ``speed``
    [m/s], when known), the creepages and creep forces in ``convention``, whether its
    load has one solution (:func:`_uniqueness`: ``warm``, ``creep_in_load``); a load
    loop not converged, or a solve that raised, is its status and message."""
    if solution.error is not None or not solution.patches:
        return WheelContact(side=side, status=solution.status, message=solution.message)
    patches, creepages = solution.patches, solution.creepages
    values = resultants(side, patches, pose)
    values["work"] = solution.work  # (its patches' and the load loop's own)
    values["creepages"] = creepages
    if creepages:  # (side frame: the lateral and spin components mirrored)
        sgn = SIDES[side]
        per = 0.0
        for p, c in zip(patches, creepages, strict=True):
            t = p.tangential
            if t is not None:
                fx, fy = t.force
                per += fx * c[0] + sgn * (fy * c[1] + t.spin_moment * c[2])
        values["frictional_power_per_speed"] = per
        values["frictional_power"] = None if speed is None else speed * per
    if convention == "contact":  # the creepages and creep forces as CONTACT's
        values["creepages"] = [wheel_frame_creepage(c) for c in creepages]
        fx, fy = values["creep_force"]
        values["creep_force"] = (-fx, fy)
        values["patches"] = [p.replaced(convention="contact") for p in patches]
    if solution.status == Status.NOT_CONVERGED:  # the load loop's
        values["status"], values["message"] = NOT_CONVERGED, solution.message
    values["load_unique"], why = _uniqueness(solution, warm, creep_in_load)
    if why and values["status"] == OK:
        values["message"] = "ok; the load has more than one solution: " + why
    return WheelContact(**values)


def _uniqueness(solution: WheelSolution, warm: bool, creep_in_load: bool
                ) -> tuple[bool, str]:
    """Whether a solved wheel's load has one solution, and if not why: a merge of patches
    (:attr:`~railcontact.contact.results.PatchSolution.load_other`; the smallest approach
    is returned, from warm and cold starts alike) or a steep patch's creep force
    (:func:`~railcontact.contact.loadloop.load_unique`; the root the start leads to, from
    a ``warm`` start or cold), the latter only where the creep forces are in the load
    (``creep_in_load``: load control with :attr:`ContactSettings.load_includes_creep`)."""
    steep = creep_in_load and solution.steep
    other = solution.load_other
    if not steep and other is None:
        return True, ""
    why = []
    if other is not None:
        why.append("two of its contact regions join into one patch between this "
                   f"solution and another (approach {other * 1e6:.4g} um): the smallest "
                   "approach that carries the load is returned")
    if steep:
        which = ("the one continuous with the previous step" if warm else
                 "the one reached from the normal share Q (cold start)")
        why.append(f"several patches with mu tan(gamma) >= 1 on one: {which}")
    return False, "; ".join(why)


def penetration_approach(found: WheelSearch, vertical: float) -> float:
    """Vertical approach [m] of the searched wheel into its rail for a wheelset lowered by
    ``-vertical`` [m] (penetration control)."""
    approach = max(-(float(found.trace[4].min()) + vertical), 0.0)
    if approach > MAX_PENETRATION:
        raise RailContactError(f"vertical = {vertical:g} m puts the wheel "
                               f"{approach * 1e3:.4g} mm into its rail; a contact's "
                               f"approach is at most {MAX_PENETRATION * 1e3:g} mm")
    return approach


def _start(source: Memory, f: float) -> tuple[float, float]:
    """The vertical approach [m] of a wheel and the vertical load [N] of its normal forces
    in the step ``source`` remembers, extrapolated linearly with the factor ``f`` of its
    first patch to the step's time from the step before it when both are known
    (:meth:`PatchMemory.extrapolation`)."""
    first = source[0]
    a = first.approach
    if len(source) == 1:  # (the common case: sum([q]) is 0 + q)
        q, o = 0 + first.vertical_normal, first.older
        if f > 0 and o is not None and o.approach > 0:
            q_o = 0 + o.vertical_normal
            a, q = max(a + f * (a - o.approach), 0.5 * a), max(q + f * (q - q_o), 0.5 * q)
        return a, q
    q = sum([m.vertical_normal for m in source])
    older = [m.older for m in source]
    if f > 0 and None not in older and older[0].approach > 0:
        a_o, q_o = older[0].approach, sum([o.vertical_normal for o in older])
        a, q = max(a + f * (a - a_o), 0.5 * a), max(q + f * (q - q_o), 0.5 * q)
    return a, q


__all__ = ["StepStart", "penetration_approach", "solve_step_wheel", "wheel_contact",
           "wheel_settings"]
