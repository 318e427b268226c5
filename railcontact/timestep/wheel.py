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
from dataclasses import dataclass
from time import perf_counter

from ..contact.loadloop import charge, vertical_approach, vertical_creep_estimate
from ..contact.patch import normal_estimate, solve_patch_tangential
from ..contact.start import NormalStart, WarmStart
from ..contact.wheel import WheelPass, WheelProblem, WheelSettings, WheelSolution
from ..contact.wheelrail import solve_wheel, solve_wheel_normal, wheel_problem
from ..errors import RailContactError, SolverError
from ..geometry.points import ContactPoint, WheelSearch, at_reference, samples
from ..geometry.track import SIDES, Pose
from ..halfspace.grid import Grid
from ..halfspace.hertz import HertzSolution, hertz
from ..halfspace.materials import ElasticPair
from ..halfspace.sums import array_sum
from ..settings import Control
from ..settings.case import MAX_PENETRATION
from ..settings.convention import wheel_frame_creepage
from ..status import Status
from .inputs import Kinematics, WheelSetup
from .results import NOT_CONVERGED, OK, WheelContact, fill_resultants
from .warmstart import (
    PatchMemory,
    match,
    merged,
    previous_bounds,
    previous_start,
    previous_tangential,
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
        if self.own:
            return sum(m.vertical_creep for m in self.own)
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
        memory, remembering :attr:`previous` as the older step."""
        s, pair, time = self.setup.settings, problem.pair, self.time
        source = self.first if before is None else before.memory
        previous = self.previous
        sgn = SIDES[problem.side]

        def estimate_for(cp: ContactPoint, hz: HertzSolution | None, ctrl: Control
                         ) -> WarmStart:
            def hertz_of() -> HertzSolution:  # (formed here only where it is needed)
                return hz or hertz(cp.A, cp.B, pair, **ctrl.kwargs())

            def estimate() -> WarmStart:  # KP/INFCON cost a solve of their own: when needed
                return normal_estimate(s.normal_settings, hertz_of(), *samples(cp)[:3],
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
            bounds = (None if len(source) > 1 and merged(cp, m, source,
                                                         hertz_of().penetration)
                      else previous_bounds(m))
            return WarmStart("previous", pressure_on, bounds)

        # the frame at the reference point formed first at the approach of the step (or
        # pass) that starts this one, extrapolated in time: one pass in the common case
        start = _start(source, time) if source else None
        approach = self.approach if before is None else None
        if start is not None and approach is not None and approach > 0:  # expected there
            start = (approach, start[1])
        patches = solve_wheel_normal(problem.track, problem.wheelset, problem.pose,
                                     problem.side, control, settings.patch, pair,
                                     estimate_for, reference=settings.reference,
                                     start=start, problem=problem)
        kept = [p for p in patches if p.normal.force > 0]
        charge(kept, [p for p in patches if p.normal.force <= 0])  # their work counts
        patches = kept
        creepages, memory = [], []
        approach = vertical_approach(patches)
        tangential = settings.tangential is not None
        for patch in patches:
            cp = patch.geometry
            u, z = cp.rail_u, cp.position[2]
            m = match(source, u, z)  # None without warm start
            if tangential:
                c = self.creepage(cp, problem)
                creepages.append(c)
                side_creep = [c[0], sgn * c[1], sgn * c[2]]
                t0 = perf_counter()
                # the traction extrapolated in time for SteadyGS only (previous_tangential)
                at = time if s.tangential_solver != "convexgs" else None
                prev = previous_tangential(m, patch.normal.grid, at) if m else None
                patch.work.seconds += perf_counter() - t0
                solve_patch_tangential(patch, settings.tangential, pair, s.fft,
                                       creepage=side_creep, previous=prev)
            t = patch.tangential
            last = m if previous is source else match(previous, u, z)
            # the traction's rate smoothed over the steps (SteadyGS's extrapolation only;
            # its time is the patch's work, as the start it serves)
            rate = None
            if t is not None and s.tangential_solver != "convexgs":
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
        return WheelPass(patches, creepages, memory)


def wheel_settings(setup: WheelSetup, tangential: bool) -> WheelSettings:
    """The wheel solver's settings of a step's wheel (``tangential``: creepages or
    velocities given)."""
    s = setup.settings
    return WheelSettings(s.patch_settings, s.tangential_settings if tangential else None,
                         s.patch_frame == "reference", s.load_tolerance, s.load_tolerance,
                         s.load_includes_creep)


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
    solution = solve_wheel(wheel_problem(setup.track, setup.wheelset, pose, side, pair,
                                         control, found),
                           wheel_settings(setup, tangential), start)
    wheel = wheel_contact(side, solution, pose, kin and kin.speed, convention)
    if solution.error is None and wheel.patches:
        creep_in_load = control.by_load and tangential and settings.load_includes_creep
        _mark_uniqueness(wheel, solution, bool(previous), creep_in_load)
    return wheel, tuple(solution.memory or ()) if keep else (), solution.error


def wheel_contact(side: str, solution: WheelSolution, pose: Pose, speed: float | None,
                  convention: str) -> WheelContact:
    """The :class:`~.results.WheelContact` of a wheel's ``solution``: its patches summed
    (:func:`~.results.fill_resultants`), the frictional power (with the forward
    ``speed`` [m/s], when known), the creepages and creep forces in ``convention``; a
    load loop not converged, or a solve that raised, is its status and message."""
    if solution.error is not None or not solution.patches:
        return WheelContact(side=side, status=solution.status, message=solution.message)
    wheel = WheelContact(side=side)
    patches, creepages = solution.patches, solution.creepages
    wheel.creepages = creepages
    fill_resultants(wheel, patches, pose)
    if creepages:  # (side frame: the lateral and spin components mirrored)
        sgn = SIDES[side]
        per = 0.0
        for p, c in zip(patches, creepages, strict=True):
            t = p.tangential
            if t is not None:
                fx, fy = t.force
                per += fx * c[0] + sgn * (fy * c[1] + t.spin_moment * c[2])
        wheel.frictional_power_per_speed = per
        wheel.frictional_power = None if speed is None else speed * per
    if convention == "contact":  # the creepages and creep forces as CONTACT's
        wheel.creepages = [wheel_frame_creepage(c) for c in creepages]
        fx, fy = wheel.creep_force
        wheel.creep_force = (-fx, fy)
        for p in patches:
            p.convention = "contact"
    if solution.status == Status.NOT_CONVERGED:  # the load loop's
        wheel.status, wheel.message = NOT_CONVERGED, solution.message
    return wheel


def _mark_uniqueness(wheel: WheelContact, solution: WheelSolution, warm: bool,
                     creep_in_load: bool) -> None:
    """Set the wheel's :attr:`~.results.WheelContact.load_unique`, and say in an ok
    wheel's message why its load may have another solution: a merge of patches
    (:attr:`~railcontact.contact.results.PatchSolution.load_other`; the smallest approach
    is returned, from warm and cold starts alike) or a steep patch's creep force
    (:func:`~railcontact.contact.loadloop.load_unique`; the root the start leads to), the
    latter only where the creep forces are in the load (``creep_in_load``: load control
    with :attr:`ContactSettings.load_includes_creep`)."""
    steep = creep_in_load and solution.steep
    other = solution.load_other
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


def penetration_approach(found: WheelSearch, vertical: float) -> float:
    """Vertical approach [m] of the searched wheel into its rail for a wheelset lowered by
    ``-vertical`` [m] (penetration control)."""
    approach = max(-(float(found.trace[4].min()) + vertical), 0.0)
    if approach > MAX_PENETRATION:
        raise RailContactError(f"vertical = {vertical:g} m puts the wheel "
                               f"{approach * 1e3:.4g} mm into its rail; a contact's "
                               f"approach is at most {MAX_PENETRATION * 1e3:g} mm")
    return approach


def _start(source: Memory, time: float | None) -> tuple[float, float]:
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


__all__ = ["StepStart", "penetration_approach", "solve_step_wheel", "wheel_contact",
           "wheel_settings"]
