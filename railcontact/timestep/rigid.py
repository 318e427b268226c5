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
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from ..errors import RailContactError
from ..geometry.roll import MAX_ROLL, first_contact_gap
from ..geometry.track import SIDES, Pose, Track, Wheelset

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

ApproachAt = Callable[[float], tuple[float, float]]
"""``phi -> (delta_L, delta_R)``: the wheels' vertical approaches [m] at roll ``phi``."""


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


def vertical_and_roll(track: Track, ws: Wheelset, pose: Pose,
                      approaches: Sequence[float],
                      contacts: Sequence[tuple[float, float, float] | None],
                      approach_at: ApproachAt | None = None) -> RigidSolution:
    """The vertical displacement [m] and roll [rad] of the rigid wheelset at which both
    wheels have their loads (module docstring).

    Parameters
    ----------
    track, ws, pose
        Geometry and the pose the wheels were solved at (its roll is the start).
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
    """
    slope = 0.0
    for side, c in zip(SIDES, contacts, strict=True):
        if c is None:  # the taping line on a flat tread
            lever, radius, angle = float(ws.axial_position(0.0)), ws.radius, 0.0
        else:
            lever, radius, angle = SIDES[side] * (c[0] - pose.lateral), c[1], c[2]
        slope += lever - radius * math.tan(angle)
    slope = max(slope, MIN_SLOPE)  # a flange: the approach falls as it rolls up
    tol = max(RIGID_RTOL * max(approaches), RIGID_ATOL)

    def evaluate(phi: float) -> tuple[float, float]:
        """(G, v) at roll ``phi``."""
        p = Pose(pose.lateral, pose.yaw, phi)
        dl, dr = (approaches if phi == pose.roll or approach_at is None
                  else approach_at(phi))
        hl = first_contact_gap(track, ws, p, "left") + dl
        hr = first_contact_gap(track, ws, p, "right") + dr
        return hl - hr, -0.5 * (hl + hr)

    points: list[tuple[float, float, float]] = []  # (phi, G, v)
    below: tuple[float, float] | None = None  # (phi, G) with G < 0: the root is above
    above: tuple[float, float] | None = None
    run = 0  # bracketed: evaluations in a row on the same side of the root
    phi, failure = pose.roll, ""
    for _ in range(MAX_EVALUATIONS):
        try:
            g, v = evaluate(phi)
        except RailContactError as exc:  # beyond the profiles, or a wheel not solved
            failure = f"at roll {phi:.6g} rad: {exc}"
            if not points:
                break
            phi = 0.5 * (phi + points[-1][0])  # back towards the last good roll
            continue
        same = bool(points) and (points[-1][1] < 0) == (g < 0)
        points.append((phi, g, v))
        if abs(g) <= tol:
            return RigidSolution(v, phi, evaluations=len(points))
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
                         message=(f"rigid wheelset's vertical displacement and roll not "
                                  f"converged: {why}; the two wheels' vertical positions "
                                  f"differ by {best[1] * 1e6:.4g} um (tolerance "
                                  f"{tol * 1e6:.3g} um) at roll {best[0]:.6g} rad"))


@dataclass(frozen=True)
class RigidWheelset:
    """The data of :func:`vertical_and_roll`, kept by a load-controlled step's result
    until its vertical displacement or roll is asked for (a picklable record).
    ``approach_at`` gives the wheels' approaches carrying their loads at another roll (the
    step's solve of each wheel at that roll); None: the first-order answer."""

    track: Track
    wheelset: Wheelset
    pose: Pose
    approaches: tuple[float, float]
    contacts: tuple[tuple[float, float, float] | None, ...]
    approach_at: ApproachAt | None = field(default=None, repr=False, compare=False)

    def solve(self) -> RigidSolution:
        """(:func:`vertical_and_roll`)."""
        return vertical_and_roll(self.track, self.wheelset, self.pose, self.approaches,
                                 self.contacts, self.approach_at)


__all__ = ["MAX_EVALUATIONS", "RIGID_RTOL", "RigidSolution", "RigidWheelset",
           "vertical_and_roll"]
