"""The wheelset's vertical displacement and roll at which its wheels carry their loads.

Under load control each wheel is pressed into its rail by the vertical approach
``delta_s`` [m] its load needs, at the pose's roll ``phi0``, the two wheels independently.
A rigid wheelset has two vertical degrees of freedom; this finds the vertical displacement
``v`` [m] (of the centre, positive up, from the height ``r0`` above the rail tops, as the
input ``vertical`` of penetration control) and the roll ``phi`` [rad] at which the
penetration-controlled wheels, with the step's creepages, carry the step's loads ``Q_s``::

    delta_s(phi) = -(m_s(phi) + v),      s = left, right,

``m_s(phi)`` the first-contact gap of wheel ``s`` with the wheelset rolled to ``phi``
(:func:`railcontact.geometry.roll.first_contact_gap`) and ``delta_s(phi)`` the vertical
approach at which wheel ``s``, rolled to ``phi``, carries ``Q_s`` (the step's
load-controlled solve of the wheel, creep forces and all, at that roll: on the flange, and
between two contact points, rolling moves the contact and changes the load-approach
relation and the creep forces' share of the load, so ``delta_s(phi0)`` is not enough). The
difference of the two equations,

    G(phi) = m_L(phi) + delta_L(phi) - m_R(phi) - delta_R(phi) = 0,

is a root in ``phi`` alone (``G`` grows with ``phi``, :mod:`railcontact.geometry.roll`);
``v`` then follows from either equation (their mean). ``G(phi0)`` costs two contact
searches (the approaches are those of the step); the first step uses the geometric slope
``dG/dphi ~ l_L - r_L tan(gamma_L) + l_R - r_R tan(gamma_R)`` (``l`` the contact's lateral
distance from the centre, ``r`` its rolling radius), later ones the secant, and once the
root is bracketed false position (Illinois; bisection after four evaluations on one
side), until ``|G|`` is below :data:`RIGID_RTOL` of the larger approach. Each further
evaluation costs a load-controlled solve of both wheels (warm-started from the step). A
wheel without load counts as just touching (``delta = 0``). When no root is found in
:data:`MAX_EVALUATIONS` evaluations (or within +-:data:`MAX_ROLL`) the solution says so
(:attr:`RigidSolution.converged`, :attr:`RigidSolution.message`) and carries the best
iterate.

In a time loop (:class:`RigidWheelset` with the previous steps' roots, kept in the
wheelset's memory under ``"rigid"``, :class:`RigidMemory`) the search starts in time
instead: at the roll extrapolated from the last three steps' roots (quadratic in time;
linear from two, the last root from one) with the last step's slope ``dG/dphi``, so that
the first evaluation usually meets the tolerance (one load-controlled solve of both
wheels, and no ``G(phi0)``), else one secant step does; the same stopping test and the
same bracketing safety follow, so the root found meets the same tolerance. The memory
keeps each root's estimate ``roll - G/slope`` (closer than the roll accepted within the
tolerance: a smoother series to extrapolate), the slope, the wheels' approaches there and
``d delta_s/d phi``: each rolled wheel's solve forms its patch frame first at the
approach guessed from them (the previous roots' approaches extrapolated, then the last
evaluation's along the last secant), instead of at the step's approach at ``phi0``
(0.4-0.8 % away at 3 mm: a second frame pass every time); the solve forms the frame
again when its approach misses the guess by more than the frames' tolerance for a solve
started from an earlier one (:data:`~railcontact.contact.wheelrail.WARM_REFERENCE_RTOL`),
so ``G`` is as accurate as without the guess.
The wheels' solves at the root are kept as well (``rolled``, when ``approach_at`` gives
them, ``memory_at(phi)``): the next step's rolled solves start from them (its pose and
roll close to this root's) instead of from that step's solve at the pose's roll.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from ..contact.results import Work
from ..errors import RailContactError, SolverError
from ..geometry.roll import MAX_ROLL
from ..geometry.search import search_wheel
from ..geometry.track import SIDES, Pose, Track, Wheelset
from .warmstart import MAX_EXTRAPOLATION

RIGID_RTOL = 1e-4
"""Residual ``|G|`` of the two wheels' vertical positions, relative to the larger approach,
at which the iteration stops: the loads (``Q ~ delta^1.5``) are then met to 1.5e-4."""
RIGID_ATOL = 1e-10
"""Absolute floor [m] of that tolerance (wheels carrying almost nothing)."""
MAX_EVALUATIONS = 12
"""At most this many evaluations of ``G`` (the first costs two contact searches, every
later one also a load-controlled normal solve of both wheels)."""

MIN_SLOPE = 0.5
"""Least ``dG/dphi`` [m/rad] of the first step. With a wheel on its flange the geometric
slope is small or negative (``r tan(gamma) > l``), but the wheel's approach falls as the
wheelset rolls it up, and ``G`` grows at about 0.6 m/rad (S1002 on 60E1, 7-8 mm): a
smaller slope overshoots by a multiple of the root; the secant takes over after."""

ApproachAt = Callable[..., tuple[float, float]]
"""``(phi[, guess], found=...) -> (delta_L, delta_R)``: the wheels' vertical approaches [m]
at roll ``phi``; ``guess``, when given, the approaches [m] expected there (the wheels'
solves form their frames at them first); ``found``: the two wheels searched at that roll
(:func:`~railcontact.geometry.search.search_wheel`, left and right)."""


@dataclass(frozen=True)
class RigidSolution:
    """The rigid wheelset's vertical displacement and roll (module docstring)."""

    vertical: float
    """Vertical displacement of the centre [m], positive up."""
    roll: float
    """Roll angle [rad], positive when the left side rises."""
    converged: bool = True
    """False when no roll met the tolerance: ``vertical`` and ``roll`` are the best
    iterate, and :attr:`message` says by how much they miss."""
    message: str = "ok"
    evaluations: int = 0
    """Evaluations of ``G`` (module docstring)."""
    slope: float = 0.0
    """``dG/dphi`` [m/rad] the search last used (its last secant): the next step's."""
    estimate: float | None = None
    """The root estimated from the last evaluation, ``roll - G / slope`` [rad] (within the
    tolerance, a closer one than :attr:`roll`: what the next step's start is formed from);
    None when not converged."""
    approach_slopes: tuple[float, float] | None = None
    """``d delta_s / d phi`` [m/rad] (left, right) from the last evaluation at a roll other
    than the pose's: how the next step guesses the approaches at a roll; None if none."""
    approaches: tuple[float, float] | None = None
    """The wheels' approaches [m] at :attr:`roll` (the next step's guess); None if not
    converged."""
    wheel_work: tuple[Work, Work] = field(default_factory=lambda: (Work(load_passes=0),
                                                                   Work(load_passes=0)))
    """The work of each wheel's solves at the rolls evaluated (left, right): iterations,
    load passes, re-meshes and wall time [s] over every evaluation, none of them counted
    in the step's :class:`~railcontact.timestep.WheelContact` (zero when no evaluation
    solved a wheel: the pose's roll was the root, or the search was skipped)."""
    work: Work = field(init=False)
    """The work of the search's solves, both wheels' (:attr:`wheel_work` summed, as
    every solver result says its work: :class:`~railcontact.status.Work`)."""

    def __post_init__(self) -> None:  # (the sum, formed once with the record)
        object.__setattr__(self, "work", self.wheel_work[0].added(self.wheel_work[1]))


def work_since(now: Work, then: Work) -> Work:
    """The work counted in ``now`` since it read ``then``: a record of its own (a counter
    that goes on counting does not change a solution that took it)."""
    return Work(now.normal_iterations - then.normal_iterations,
                now.tangential_iterations - then.tangential_iterations,
                now.load_passes - then.load_passes, now.remeshes - then.remeshes,
                now.seconds - then.seconds)


MAX_HISTORY = 3
"""Roots of this many previous steps kept for the start in time (quadratic in time)."""


@dataclass(frozen=True)
class RigidMemory:
    """A time step's root: what starts the next step's search (module docstring)."""

    time: float | None
    """Simulation time of the step [s]; None: not given (the root is the next start)."""
    roll: float
    """The root found [rad] (:attr:`RigidSolution.estimate`)."""
    slope: float
    """``dG/dphi`` [m/rad] at it (:attr:`RigidSolution.slope`)."""
    approach_slopes: tuple[float, float] | None = None
    """(:attr:`RigidSolution.approach_slopes`)."""
    approaches: tuple[float, float] | None = None
    """(:attr:`RigidSolution.approaches`)."""


def _weights(history: Sequence[RigidMemory], time: float | None) -> list[float]:
    """Lagrange's weights at ``time`` [s] of the previous steps (newest first) that
    :func:`predicted_roll` extrapolates from: ``[1.0]`` for the last one alone."""
    last = history[0]
    if time is None or last.time is None or not time > last.time:
        return [1.0]
    times = [last.time]
    for m in history[1:MAX_HISTORY]:
        if m.time is None or not m.time < times[-1]:
            break
        times.append(m.time)
    if len(times) > 1 and time - last.time > MAX_EXTRAPOLATION * (last.time - times[1]):
        return [1.0]
    weights = []
    for i, ti in enumerate(times):
        w = 1.0
        for j, tj in enumerate(times):
            if j != i:
                w *= (time - tj) / (ti - tj)
        weights.append(w)
    return weights


def predicted_roll(history: Sequence[RigidMemory], time: float | None) -> float | None:
    """The roll [rad] extrapolated to ``time`` [s] from the previous steps' roots
    (newest first): through the last three (quadratic in time), two (linear) or the last
    one; the last root when the times do not allow it (not given, not increasing, or a
    step more than :data:`~.warmstart.MAX_EXTRAPOLATION` times the last one). None without
    a history."""
    if not history:
        return None
    phi = sum(w * m.roll for w, m in zip(_weights(history, time), history, strict=False))
    return phi if abs(phi) < MAX_ROLL else history[0].roll


def predicted_approaches(history: Sequence[RigidMemory], time: float | None
                         ) -> tuple[float, float] | None:
    """The wheels' approaches [m] at the root extrapolated to ``time`` [s] as
    :func:`predicted_roll` extrapolates the roll; None when a step did not keep them."""
    if not history:
        return None
    weights = _weights(history, time)
    used = history[:len(weights)]
    if any(m.approaches is None for m in used):
        return None
    return tuple(sum(w * m.approaches[k] for w, m in zip(weights, used, strict=True))
                 for k in range(2))


def vertical_and_roll(track: Track | tuple[Track, Track],
                      ws: Wheelset | tuple[Wheelset, Wheelset], pose: Pose,
                      approaches: Sequence[float],
                      contacts: Sequence[tuple[float, float, float] | None],
                      approach_at: ApproachAt | None = None, *,
                      start: float | None = None, start_slope: float = 0.0,
                      approach_slopes: tuple[float, float] | None = None,
                      anchor: tuple[float, tuple[float, float]] | None = None,
                      gaps: tuple[float, float] | None = None) -> RigidSolution:
    """The vertical displacement [m] and roll [rad] of the rigid wheelset at which both
    wheels have their loads (module docstring).

    Parameters
    ----------
    track, ws, pose
        Geometry - one track and wheelset for both sides, or pairs (left, right) - and
        the pose the wheels were solved at (its roll is the start).
    approaches
        Vertical approach of the left and right wheel beyond first contact at the pose's
        roll [m].
    contacts
        Per wheel, (lateral position Y of the contact point [m], rolling radius [m],
        contact angle [rad]) of its main patch, or None without contact: the first step's
        slope.
    approach_at
        The wheels' approaches at another roll; None: those at the pose's roll for every
        roll (a first-order answer, right only where rolling does not move the contacts).
    start, start_slope
        The first roll [rad] to evaluate and the slope ``dG/dphi`` [m/rad] of the first
        step from it (a positive one: the previous step's, :func:`predicted_roll`); None
        and 0: the pose's roll and the geometric slope.
    approach_slopes
        ``d delta_s / d phi`` [m/rad] (left, right) that guess the approaches at a roll for
        ``approach_at`` (the previous step's, then this search's); None: no guess.
    anchor
        A roll [rad] and the approaches [m] expected there, from which the first guess
        is formed (the previous steps' at their roots, extrapolated); None: the pose's
        roll and ``approaches``. Later guesses start from the last evaluation.
    gaps
        The wheels' least gaps [m] (left, right) at the pose's roll, when the step searched
        them there (:attr:`~railcontact.geometry.points.WheelSearch.least_gap`); None:
        searched here. At every other roll each wheel is searched once, for its least gap
        and ``approach_at``'s solve.
    """
    tracks = track if isinstance(track, tuple) else (track, track)
    wheelsets = ws if isinstance(ws, tuple) else (ws, ws)
    slope = 0.0
    for k, (side, c) in enumerate(zip(SIDES, contacts, strict=True)):
        if c is None:  # the taping line on a flat tread
            w = wheelsets[k]
            lever, radius, angle = float(w.axial_position(0.0)), w.radius, 0.0
        else:
            lever, radius, angle = SIDES[side] * (c[0] - pose.lateral), c[1], c[2]
        slope += lever - radius * math.tan(angle)
    geometric = slope = max(slope, MIN_SLOPE)  # a flange: the approach falls as it rolls up
    if start_slope > 0:
        slope = start_slope
    tol = max(RIGID_RTOL * max(approaches), RIGID_ATOL)

    # the guesses: from the anchor (then the last evaluation) along the rates (the
    # previous step's, else the secant from the pose's roll, then the last two
    # evaluations'); a wheel's solve checks its guess (:class:`~.rolled.RolledApproaches`)
    rates, base = approach_slopes, anchor or (pose.roll, tuple(approaches))
    last: tuple[float, tuple[float, float]] | None = None  # the last full evaluation

    def evaluate(phi: float) -> tuple[float, float]:
        """(G, v) at roll ``phi``."""
        nonlocal rates, base, last
        p = Pose(pose.lateral, pose.yaw, phi)
        if phi == pose.roll and gaps is not None:
            found = None
            gl, gr = gaps
        else:  # the two wheels searched at this roll, once
            found = (search_wheel(tracks[0], wheelsets[0], p, "left"),
                     search_wheel(tracks[1], wheelsets[1], p, "right"))
            gl, gr = found[0].least_gap, found[1].least_gap
        if phi == pose.roll or approach_at is None:
            dl, dr = approaches
        else:
            dl, dr = (approach_at(phi, found=found) if rates is None else approach_at(
                phi, tuple(a + k * (phi - base[0])
                           for a, k in zip(base[1], rates, strict=True)), found=found))
            ref = last or (pose.roll, approaches)
            if phi != ref[0]:
                rates = tuple((d - a) / (phi - ref[0])
                              for d, a in zip((dl, dr), ref[1], strict=True))
            last = base = (phi, (dl, dr))
        hl = gl + dl
        hr = gr + dr
        return hl - hr, -0.5 * (hl + hr)

    points: list[tuple[float, float, float]] = []  # (phi, G, v)
    below: tuple[float, float] | None = None  # (phi, G) with G < 0: the root is above
    above: tuple[float, float] | None = None
    run = 0  # bracketed: evaluations in a row on the same side of the root
    phi, failure = (pose.roll if start is None else start), ""
    for _ in range(MAX_EVALUATIONS):
        try:
            g, v = evaluate(phi)
        except (RailContactError, SolverError) as exc:  # beyond the profiles, not solved
            failure = f"at roll {phi:.6g} rad: {exc}"
            if not points and phi != pose.roll:  # the start in time: from the pose's roll
                phi, slope, rates, base = pose.roll, geometric, None, (pose.roll, approaches)
                continue
            if not points:
                break
            phi = 0.5 * (phi + points[-1][0])  # back towards the last good roll
            continue
        same = bool(points) and (points[-1][1] < 0) == (g < 0)
        points.append((phi, g, v))
        if abs(g) <= tol:
            if len(points) > 1:  # the last secant, the next step's slope
                (p0, g0, _), (p1, g1, _) = points[-2], points[-1]
                if p1 != p0 and (g1 - g0) / (p1 - p0) > 0:
                    slope = (g1 - g0) / (p1 - p0)
            return RigidSolution(v, phi, evaluations=len(points), slope=slope,
                                 estimate=phi - g / slope,
                                 approach_slopes=rates, approaches=(
                                     last[1] if last and last[0] == phi
                                     else tuple(approaches) if phi == pose.roll else None))
        bracketed = below is not None and above is not None
        run = run + 1 if bracketed and same else 0
        if g < 0:
            below = (phi, g)
            if run and above is not None:  # Illinois: the end that stays weighs half
                above = (above[0], 0.5 * above[1])
        else:
            above = (phi, g)
            if run and below is not None:
                below = (below[0], 0.5 * below[1])
        if below is not None and above is not None:  # false position, bisection if slow
            (a, ga), (b, gb) = below, above
            phi = a - ga * (b - a) / (gb - ga)
            if run >= 3 or not min(a, b) < phi < max(a, b):  # a jump: halve the bracket
                phi = 0.5 * (a + b)
            continue
        if len(points) > 1:
            (p0, g0, _), (p1, g1, _) = points[-2], points[-1]
            if p1 != p0 and (g1 - g0) / (p1 - p0) > 0:
                slope = (g1 - g0) / (p1 - p0)
        step = min(max(phi - g / slope, -MAX_ROLL), MAX_ROLL)
        if step == phi:  # at the end of the range and still not there
            failure = (f"no roll within +-{MAX_ROLL} rad gives both wheels their loads "
                       f"(residual {g * 1e6:.4g} um at roll {phi:.6g} rad)")
            break
        phi = step
    if not points:
        raise RailContactError(f"rigid wheelset: {failure}")
    best = min(points, key=lambda q: abs(q[1]))
    why = failure or (f"no convergence in {MAX_EVALUATIONS} evaluations")
    if not failure and below is not None and above is not None:
        why += (f" (between rolls {below[0]:.9g} and {above[0]:.9g} rad the residual goes "
                f"from {below[1] * 1e6:.4g} to {above[1] * 1e6:.4g} um"
                + (": a jump, where a wheel's contact moves (tread to flange), and no roll "
                   "gives both loads)" if abs(above[0] - below[0]) < 1e-6 else ")"))
    return RigidSolution(best[2], best[0], converged=False, evaluations=len(points),
                         slope=slope,
                         message=(f"rigid wheelset's vertical displacement and roll not "
                                  f"converged: {why}; the two wheels' vertical positions "
                                  f"differ by {best[1] * 1e6:.4g} um (tolerance "
                                  f"{tol * 1e6:.3g} um) at roll {best[0]:.6g} rad"))


@dataclass(frozen=True)
class RigidWheelset:
    """The data of :func:`vertical_and_roll` for one load-controlled step: the problem
    the step's rigid-wheelset stage solves (a picklable record).
    ``approach_at`` gives the wheels' approaches carrying their loads at another roll (the
    step's solve of each wheel at that roll); None: the first-order answer."""

    track: Track | tuple[Track, Track]
    wheelset: Wheelset | tuple[Wheelset, Wheelset]
    pose: Pose
    approaches: tuple[float, float]
    contacts: tuple[tuple[float, float, float] | None, ...]
    approach_at: ApproachAt | None = field(default=None, repr=False, compare=False)
    history: tuple[RigidMemory, ...] = ()
    """The previous steps' roots, newest first (:class:`RigidMemory`): the start in time."""
    time: float | None = None
    """Simulation time of the step [s]."""
    gaps: tuple[float, float] | None = None
    """The wheels' least gaps [m] (left, right) at the pose, from the step's search; None:
    searched where needed."""

    def solve(self) -> RigidSolution:
        """(:func:`vertical_and_roll`, started in time from :attr:`history`; what the
        next step keeps of it: :meth:`remembered`)."""
        start = predicted_roll(self.history, self.time)
        approaches = predicted_approaches(self.history, self.time)
        work = getattr(self.approach_at, "work", None)  # its count over all its calls
        before = None if work is None else {k: replace(w) for k, w in work.items()}
        s = vertical_and_roll(self.track, self.wheelset, self.pose, self.approaches,
                              self.contacts, self.approach_at, start=start,
                              start_slope=self.history[0].slope if self.history else 0.0,
                              approach_slopes=(self.history[0].approach_slopes
                                               if self.history else None),
                              anchor=(None if start is None or approaches is None
                                      else (start, approaches)), gaps=self.gaps)
        if work is not None:  # the wheels' solves at other rolls: the step's work too
            s = replace(s, wheel_work=tuple(work_since(work[k], before[k])
                                            for k in ("left", "right")))
        return s

    def remembered(self, s: RigidSolution) -> tuple[tuple[RigidMemory, ...], Any]:
        """What the next step keeps of the solution ``s`` of :meth:`solve`: the roots
        (``s``'s first, then :attr:`history`'s, at most :data:`MAX_HISTORY`), and the
        wheels' solves at ``s``'s root when ``approach_at`` has ``memory_at`` (where the
        next step's rolled solves start; else None); nothing when ``s`` did not
        converge."""
        if not s.converged:
            return (), None
        roots = (RigidMemory(self.time, s.estimate, s.slope, s.approach_slopes, s.approaches),
                 *self.history[:MAX_HISTORY - 1])
        at = getattr(self.approach_at, "memory_at", None)
        return roots, None if at is None else at(s.roll)


__all__ = ["MAX_EVALUATIONS", "RIGID_RTOL", "RigidMemory", "RigidSolution", "RigidWheelset",
           "predicted_approaches", "predicted_roll", "vertical_and_roll"]
