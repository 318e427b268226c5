"""Wheel–rail cases: profiles -> contact search -> one BEM problem per contact patch.

``[normal] penetration`` is the vertical approach of the wheel towards the rail [m] beyond
first contact; patch ``k`` (vertical gap ``g_k`` above the first contact, contact angle
``gamma_k``) then has the normal penetration ``(delta - g_k) cos(gamma_k)``.
``[normal] load`` is the vertical wheel load Q [N], the total vertical force of the rail on
the wheel as CONTACT's FZ: ``sum_k (N_k cos(gamma_k) + F_s,k sin(gamma_k)) = Q``, ``F_s,k``
the patch's creep force across the track (towards the field side, in the contact plane),
zero without a ``[tangential]`` table. For the normal forces' share: one patch, force
control with ``N = Q / cos(gamma)``, exact in one solve, started from Hertz's penetration
when an estimate is asked for; several patches, a secant iteration on the approach from
Hertz's value. With creep forces an outer secant iteration on that share (normal and
tangential BEM solved at each pass, :func:`~.loadloop.creep_load`) makes the total
vertical force Q to :data:`~.wheel.CREEP_LOAD_RTOL`, or as close as the tangential
tolerance lets it (an error beyond :data:`~.wheel.LOAD_ACCEPT_RTOL` and beyond ``eps_tau``
of the creep forces' share, :func:`~.loadloop.load_met`); on a flange the creep force
carries a large part of the load (``mu tan(gamma)`` ~ 0.8 at 70 deg with mu = 0.3), and
beyond Nadal's limit (``mu tan(gamma) > 1``, sliding up) no normal force carries it: an
error. Where two of the wheel's contact regions join into one patch, a load may be carried
at two approaches; the wheel takes the smallest (:func:`~.loadloop.first_root`, the merges from
:func:`~railcontact.geometry.points.merge_approaches`) and says that another exists.

``[geometry] roll`` is a number [rad], ``"rigid"`` (the roll at which both wheels of the rigid
wheelset touch their rails, :func:`railcontact.geometry.roll.contact_roll`) or
``"equal-loads"`` (both wheels carry ``[normal] load``, as in the Manchester benchmark): a
fixed point on the roll, each pass solving both wheels by the BEM and putting the difference
of their vertical approaches into :func:`~railcontact.geometry.roll.contact_roll`, until the
roll changes by less than :data:`ROLL_TOL` (Brent's method once two passes bracket the
root, see :func:`_equal_loads`).

The potential contact area of a patch follows the paper (Sec. 2.1): ``A x^2 <= delta_0``
along the track and ``f(s) <= delta_0`` across it (``delta_0`` the patch's normal
penetration), scaled by ``[grid] margin`` and grown when the contact reaches its edge.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np
from scipy.optimize import brentq

from ..errors import CaseError, ConvergenceError, RailContactError, SolverError
from ..geometry.kinematics import PatchKinematics, WheelsetMotion, patch_kinematics
from ..geometry.points import (
    MIN_LOBE,
    ContactPoint,
    ReferencePoint,
    WheelSearch,
    at_reference,
    contact_points,
    count_contacts,
    merge_approaches,
    overlap_box,
    overlap_box_on_run,
    patch_run,
    reference_offset,
    reference_point,
    samples,
)
from ..geometry.profiles import read_profile
from ..geometry.roll import contact_roll, first_contact_gap
from ..geometry.search import search_wheel
from ..geometry.separation import PatchSeparation, turned_angles
from ..geometry.track import SIDES, Pose, Track, Wheelset
from ..halfspace.grid import Grid, box_edges, widened
from ..halfspace.hertz import (
    HertzSolution,
    hertz,
    negligible_load,
    no_contact_load,
    semi_axis_bound,
)
from ..halfspace.materials import ElasticPair
from ..normal import NormalResult
from ..settings import Case, Control, GridSettings, PatchSettings, WheelRailGeometry
from ..settings.case import check_kinematic_creepage
from ..settings.convention import side_creepage
from ..settings.friction import FrictionTable, friction_at_point, row_friction, side_friction
from ..status import Status, status_of
from .loadloop import (
    approach_secant,
    count_passes,
    creep_load,
    first_root,
    other_root,
    probe_grid,
    probe_settings,
    vertical_approach,
    vertical_force,
)
from .patch import (
    UNCOVERED_MARGIN,
    PatchFriction,
    check_grid_budget,
    normal_estimate,
    not_converged,
    solve_patch_normal,
    solve_patch_tangential,
    start_from,
    start_pressure,
    uncovered,
)
from .results import PatchSolution, Work, with_frictional_power
from .start import NormalStart, WarmStart
from .wheel import (
    LOAD_ACCEPT_RTOL,
    LOAD_RTOL,
    WheelPass,
    WheelProblem,
    WheelSettings,
    WheelSolution,
    WheelStart,
)

EstimateFor = Callable[[ContactPoint, HertzSolution | None, Control], WarmStart]
"""``estimate_for(contact point, hertz, control)``: the start of a patch's solves (e.g. the
previous time step's, or a table's previous point), instead of the settings' estimate;
``hertz`` is None where the settings do not form it (:attr:`PatchSettings.hertz`: a time
step's; ``hertz(cp.A, cp.B, pair, **control.kwargs())`` forms it)."""
BoxOf = Callable[[ContactPoint, float, float], tuple[float, float, float, float]]
"""``box_of(cp, penetration, approach)``: the box [m] around the rigid overlap of a
wheel's patch ``cp`` at the normal ``penetration`` [m] with the wheel's run of vertical
overlap at the vertical ``approach`` [m] around the patch's point
(:func:`~railcontact.geometry.points.overlap_box_on_run` of a searched wheel)."""
Starts = Callable[[str], EstimateFor | None]
"""``starts(side)``: the ``estimate_for`` of a wheel (its :class:`CaseStart`), or None."""
ROLL_TOL = 1e-8
"""Convergence of the equal-loads roll [rad] (1e-8 rad moves a tread contact by ~3 nm)."""
MAX_ROLL_PASSES = 16
CLIMBED_SHARE = 0.5
"""A contact past the steepest point of the flange whose angle has fallen below this share
of the flange's steepest angle is out of range: the wheel has climbed its flange (S1002 on
60E1: beyond about 20 mm lateral displacement). Contacts on the upper flank above it, as
in the Manchester benchmark at 7-10 mm, are solved."""
MAX_PATCH_SHARE = 0.1
"""Largest Hertz semi-axis of a patch as a fraction of the wheel's rolling radius: beyond
it the patch is no longer small against the bodies (steel at 83 kN: 0.015)."""
KEEP_SLACK = 0.05
"""A later load pass keeps the grid of the one before when its potential area reaches at
most this fraction of the grid's size beyond it (the area has a margin over the contact);
else it meshes its own area and the earlier solution is interpolated onto it."""
REFERENCE_RTOL = 1e-4
"""A patch frame formed at the reference point for one vertical approach serves an approach
within this fraction of it: the point moves by far less than an element (0.5 mm elements,
83 kN: under 0.01 mm on the tread, 0.05 mm at the flange root) and the frame's angle by
less than 1e-3 rad."""
WARM_REFERENCE_RTOL = 1e-3
"""The same for a frame formed at an earlier solve's approach (``start`` of
:func:`solve_wheel_normal`, e.g. the previous time step's, extrapolated): a relative change
of 1e-3 in the approach moves the reference point by at most 2.3 um (under 0.005 of a
0.5 mm element), its contact angle by at most 3.3e-5 rad and its rolling radius by at most
0.3 um (S1002 on 60E1 at 1:40, approaches 50-120 um, lateral 0, 3, 5 and 7 mm; most at the
flange root), so one pass serves a warm time step. The same for a frame formed at a coarse
probe's approach (:func:`_single_patch`, at normal tolerances from
:data:`~.loadloop.PROBE_COARSE_TOLERANCE`)."""
MAX_REFERENCE_PASSES = 6
"""Solves of a single-patch wheel at most, each with its frame formed again at the approach
of the one before."""
PASS_MATCH = 1e-3
"""Largest distance [m] between the contact points of a patch in two load passes of a wheel
for the earlier one to start the later one."""


def build_geometry(geo: WheelRailGeometry) -> tuple[Track, Wheelset, Pose]:
    """Track, wheelset and pose from the ``[geometry]`` settings of a wheel-rail case.

    A roll given as ``"rigid"`` or ``"equal-loads"`` is returned as the rigid contact roll
    (the start of the equal-loads iteration).
    """
    try:
        track = Track(read_profile(geo.rail, "rail", geo.profile_unit), geo.inclination,
                      geo.gauge, geo.gauge_depth)
        ws = case_wheelset(geo)
        roll = geo.roll
        if isinstance(roll, str):
            roll = contact_roll(track, ws, geo.lateral_displacement, geo.yaw)
        pose = Pose(geo.lateral_displacement, geo.yaw, roll)
    except RailContactError as exc:
        raise CaseError(f"[geometry]: {exc}") from None
    return track, ws, pose


def case_wheelset(geo: WheelRailGeometry) -> Wheelset:
    """The wheelset of the ``[geometry]`` settings of a wheel-rail case."""
    return Wheelset(read_profile(geo.wheel, "wheel", geo.profile_unit), geo.wheel_radius,
                    geo.back_to_back, geo.flange_back)


def same_patch(patches: list[PatchSolution] | None, cp: ContactPoint
               ) -> PatchSolution | None:
    """The patch of ``patches`` (an earlier load pass of the wheel) whose contact point is
    nearest to ``cp``, within :data:`PASS_MATCH`."""
    best, dist = None, PASS_MATCH
    for p in patches or ():
        g = p.geometry
        d = math.hypot(g.rail_u - cp.rail_u, g.position[2] - cp.position[2])
        if d <= dist:
            best, dist = p, d
    return best


def check_on_rail(cp: ContactPoint, ws: Wheelset) -> None:
    """Raise a :class:`RailContactError` when the contact point ``cp`` says the wheel is off
    its rail: on the back of the flange (derailed), or past the flange's steepest point
    with an angle below :data:`CLIMBED_SHARE` of that point's (climbed its flange)."""
    s_steep, steepest = ws.flange_flank
    if not cp.wheel_s < s_steep:  # (the steepest point is at or beyond the tip: on the rail)
        return
    if cp.wheel_s < ws.flange_tip:
        raise RailContactError(
            f"contact at S = {cp.wheel_s * 1e3:.4g} mm, on the back of "
            f"the flange (tip at S = {ws.flange_tip * 1e3:.4g} mm): the wheel is off its "
            "rail (derailed)")
    if abs(cp.contact_angle) < CLIMBED_SHARE * steepest:
        raise RailContactError(
            f"contact at S = {cp.wheel_s * 1e3:.4g} mm at "
            f"{math.degrees(abs(cp.contact_angle)):.3g} deg, past the flange's steepest "
            f"point (S = {s_steep * 1e3:.4g} mm, {math.degrees(steepest):.3g} deg) and "
            f"below {CLIMBED_SHARE:g} of its angle: the wheel has climbed its flange "
            "(out of range)")


def _covers(outer: tuple[float, float, float, float],
            inner: tuple[float, float, float, float], by_count: bool) -> bool:
    """Whether an earlier pass's grid on ``outer`` [m] serves the area ``inner``: it holds
    ``inner`` but for :data:`KEEP_SLACK` of its size on each side; and, for a grid of
    given element counts (``by_count``: its element size follows its area), it is at most
    ``1 + 4 KEEP_SLACK`` times as large along each axis, so that it is not coarser than
    the grid meshed on ``inner`` would be. (A grid of given element size keeps it however
    large; the load loops' residuals then stay smooth from pass to pass.)"""
    wo, ho = outer[1] - outer[0], outer[3] - outer[2]
    wi, hi = inner[1] - inner[0], inner[3] - inner[2]
    sx, sy = KEEP_SLACK * wo, KEEP_SLACK * ho
    holds = (inner[0] >= outer[0] - sx and inner[1] <= outer[1] + sx
             and inner[2] >= outer[2] - sy and inner[3] <= outer[3] + sy)
    return holds and (not by_count or (wo <= (1 + 4 * KEEP_SLACK) * wi
                                       and ho <= (1 + 4 * KEEP_SLACK) * hi))


PROBE_MARGIN_ELEMENTS = 1
"""Elements of a coarse probe's grid added on each side of its contact box for the potential
area of the full pass after it (:func:`_probed_area`)."""
PROBE_MARGIN_SHARE = 0.05
"""Share of the probe's contact extent added on each side as well (as a time step's area,
:data:`~railcontact.timestep.warmstart.AREA_MARGIN_SHARE`)."""


def _probed_area(probe: NormalResult) -> tuple[float, float, float, float]:
    """The potential area (xmin, xmax, ymin, ymax) [m] of the full pass after a coarse
    probe whose solution is ``probe``: the box of its contact widened by
    :data:`PROBE_MARGIN_ELEMENTS` of its elements and :data:`PROBE_MARGIN_SHARE` of its
    extent a side. The frames of the two passes differ (the full pass's is formed at the
    probe's approach), so the area is checked against the rigid overlap after the solve
    and grown where the contact may reach beyond it (:func:`_overlap_covered`), as a time
    step's is. Used only for grids of given element sizes, whose answer does not depend
    on the area (a grid of given counts would get finer elements)."""
    return widened(box_edges(probe.contact_box, probe.grid), probe.grid,
                   PROBE_MARGIN_ELEMENTS, PROBE_MARGIN_SHARE)


def _patches(cps: list[ContactPoint], ws: Wheelset, approach: float, settings: PatchSettings,
             pair: ElasticPair, loads: list[float] | None = None,
             estimate_for: EstimateFor | None = None,
             previous: list[PatchSolution] | None = None,
             box_of: BoxOf | None = None, probe_grid: GridSettings | None = None,
             after_probe: bool = False, load_loop: bool = False) -> list[PatchSolution]:
    """The normal BEM solution of each contact point's patch: at the vertical ``approach``
    [m], or carrying the normal ``loads`` [N] (one per point).

    ``probe_grid``: the grid of a patch whose start gives no pressure (a coarse probe,
    :func:`~.loadloop.probe_grid`), else that of ``settings``. ``after_probe``: the
    patches of ``previous`` are such coarse probes: their grids are not kept, and with
    element sizes the potential area is their contact's (:func:`_probed_area`).

    Each solution is checked against the patch's rigid overlap (:func:`_overlap_covered`):
    on a potential area an estimate gave (a time step's) or a coarse probe's contact
    (after a coarse probe), and with ``box_of`` (the box
    around the patch's overlap with the wheel's run of vertical overlap at an approach,
    :func:`~railcontact.geometry.points.overlap_box_on_run`) on every area, so that a
    second lobe of the run that the patch's plane shows apart is not left out.

    A patch of ``previous`` (the wheel's last load pass) at the same contact point starts
    the solve: its pressure is the initial estimate, and its grid is kept when it serves
    the new potential area (:func:`_covers`). ``load_loop``: the patches are a pass of a
    load loop (their ``load_unique`` True until the loop finds another root; else None).
    Raises when the wheel is off its rail (:func:`check_on_rail`) or a patch is beyond
    the half-space model (:data:`MAX_PATCH_SHARE`)."""
    grid, normal = settings.grid, settings.normal
    out = []
    for k, cp in enumerate(cps):
        check_on_rail(cp.rigid or cp, ws)
        if loads is None:  # (under loads the normal force is given, not the penetration)
            dn = cp.normal_penetration(approach)
            if dn <= 0:
                continue
        # beside other patches: the patch's own run of the overlap alone (the others'
        # lobes, which its plane's gap also shows, are theirs)
        gap_of = (cp.gap_on_grid if len(cps) == 1 or loads is not None else
                  own_gap(cp, [o for o in cps if o is not cp]))
        if not (math.isfinite(cp.B) and cp.B > 0 and cp.A > 0):
            raise CaseError(f"{cp.side} wheel: no convex contact at S = {cp.wheel_s:.4g} m "
                            "(conformal or concave gap); cannot set up the patch")
        control = Control(load=loads[k]) if loads is not None else Control(penetration=dn)
        kwargs = control.kwargs()
        limit = MAX_PATCH_SHARE * cp.rolling_radius
        # Hertz's solution: for the patch's result when the settings ask for it, else only
        # where a bound of its semi-axes does not show the patch within the model (and
        # below, where the solve needs it)
        hz = None
        if settings.hertz or not semi_axis_bound(cp.A, cp.B, pair, **kwargs) < limit:
            hz = hertz(cp.A, cp.B, pair, **kwargs)
            if max(hz.a, hz.b) > limit:
                raise CaseError(
                    f"{cp.side} wheel: a contact patch of {2 * hz.a * 1e3:.4g} x "
                    f"{2 * hz.b * 1e3:.4g} mm (Hertz) on a wheel of radius "
                    f"{cp.rolling_radius * 1e3:.4g} mm is beyond the half-space model "
                    f"(more than {MAX_PATCH_SHARE:g} of the radius); check [material] "
                    "young and the load or penetration")
        t0 = time.perf_counter()
        last = same_patch(previous, cp)
        if last is not None:  # (its traction start that of the pass's own start)
            est = WarmStart(last.estimate,
                            lambda g, last=last: NormalStart(start_pressure(last, g)),
                            traction_on=last.start.traction_on)
        elif estimate_for is None:
            hz = hz or hertz(cp.A, cp.B, pair, **kwargs)
            est = normal_estimate(normal, hz, *samples(cp)[:3], pair, control)
        else:
            est = estimate_for(cp, hz, control)
        # a start may know a tighter area (a time step: where the contact was); else the
        # rigid overlap's, with the margin
        bounds = est.bounds
        given = bool(bounds)  # (a time step's: where the contact was, checked after)
        if (after_probe and not bounds and last is not None and grid.dx is not None
                and grid.dy is not None and last.normal.contact_box is not None):
            bounds = _probed_area(last.normal)
            given = True  # (checked after, as a time step's)
        if not bounds:
            if loads is not None:
                hz = hz or hertz(cp.A, cp.B, pair, **kwargs)
            d0 = hz.penetration if loads is not None else dn
            if loads is not None and cp.approach is not None:  # formed at one: its own
                d0 = max(d0, cp.normal_penetration(cp.approach))
            xl = grid.margin * math.sqrt(d0 / cp.A)
            ylo, yhi = cp.lateral_extent(d0, grid.margin)
            bounds = (-xl, xl, ylo, yhi)
        keep = (last is not None and not after_probe
                and _covers(last.normal.grid.bounds, bounds, grid.dx is None or grid.dy is None))
        mesh = probe_grid if probe_grid is not None and not est.gives_pressure else grid
        if mesh is not grid and mesh.dx is not None and mesh.dy is not None:
            # (a coarse probe beyond the budget: named as the probe, not as [grid])
            check_grid_budget(mesh, tuple(map(float, bounds)),
                              f"the coarse probe's dx = {mesh.dx:.4g}, dy = {mesh.dy:.4g} m "
                              f"({mesh.dx / grid.dx:g} x [grid] dx = {grid.dx:.4g}, "
                              f"dy = {grid.dy:.4g} m; its contact sets the area of the "
                              "[grid] elements)")
        # a start's compiled stage: the first solve and the overlap check in one call (on
        # a new grid, the patch's own gap and the run's overlap box, as below)
        stage = est.normal_stage
        staged = (stage(cp, bounds, mesh, normal, pair, control)
                  if stage is not None and not keep and box_of is not None
                  and (len(cps) == 1 or loads is not None) else None)
        if staged is not None and staged.final:  # (its result the patch's)
            res, work = staged.result, Work(normal_iterations=staged.result.iterations)
        else:
            res, work = solve_patch_normal(gap_of, bounds, mesh, normal, pair, control,
                                           est, grid=last.normal.grid if keep else None,
                                           first=None if staged is None else staged.result)
            if given or box_of is not None:
                # (the stage's reach check, when it found places beyond the grid: the
                # first check, made before the gap beyond the grid was formed)
                flagged = (staged.uncovered if staged is not None and res is staged.result
                           else None)
                res, work = _overlap_covered(cp, gap_of, bounds, mesh, normal, pair,
                                             control, est, res, work, box_of, flagged)
        work = work.timed(time.perf_counter() - t0)  # the estimate's set-up included
        out.append(PatchSolution(normal=res, hertz=hz, estimate=est.label,
                                 curvatures=(cp.A, cp.B), geometry=cp, work=work, start=est,
                                 started_from=None if last is None else "previous load pass",
                                 load_unique=True if load_loop else None))
    return out


MAX_OVERLAP_PASSES = 3
"""Solves of a patch on an area grown to hold where its contact could reach at most
(:func:`_overlap_covered`)."""


OTHER_PATCH_GAP = 0.01
"""Undeformed gap [m] given to the elements of a patch's grid that lie in another patch's
lobe of its overlap (:func:`own_gap`): far beyond any penetration, below the gaps that
mark where the profiles end (:data:`~.patch.UNDEFINED_GAP`)."""


def own_gap(cp: ContactPoint, others: list[ContactPoint]) -> Callable[[Grid], Any]:
    """The undeformed gap of the patch ``cp`` on a grid [m] (:func:`~railcontact.geometry.
    points.gap_on_grid`) with the columns beyond the watershed towards each
    of the wheel's ``others`` patches raised to :data:`OTHER_PATCH_GAP`.

    The gap in a patch's plane also shows the lobes of the other patches' overlaps (the
    tread seen from a flange-root patch's plane): a grid reaching them - an earlier load
    pass's, kept, or one grown to hold a lobe - would carry their load a second time
    beside the other patch's own solve. The watershed is the sample of the largest gap
    ``f(s)`` between the patch's origin and the other patch's point (its rail position
    read in this plane): it does not depend on the approach, so the load loops'
    residuals stay continuous, and up to it the gap rises, so no contact of this patch's
    own lobe is cut."""
    full = samples(cp)
    s, f = full.s, full.f
    u = full.rail_u_of_s
    ok = np.isfinite(u) & np.isfinite(f)
    k0 = int(np.argmin(np.abs(s)))
    lo, hi = -math.inf, math.inf
    hits = np.flatnonzero(ok)
    for o in others if hits.size >= 2 else ():
        k = int(hits[np.argmin(np.abs(u[hits] - o.rail_u))])  # the other's point here
        if k == k0:
            continue
        a, b = (k0, k) if k > k0 else (k, k0)
        seg = np.where(ok[a:b + 1], f[a:b + 1], -math.inf)
        w = float(s[a + int(np.argmax(seg))])
        if k > k0:
            hi = min(hi, w)
        else:
            lo = max(lo, w)

    def gap_of(grid: Grid):
        g = cp.gap_on_grid(grid)
        y = grid.y
        cols = (y < lo) | (y > hi)
        if cols.any():
            g[:, cols] = np.maximum(g[:, cols], OTHER_PATCH_GAP)
        return g
    return gap_of


def _overlap_covered(cp: ContactPoint, gap_of: Callable[[Grid], Any],
                     bounds: tuple[float, float, float, float], grid: GridSettings, normal,
                     pair: ElasticPair, control: Control, est: WarmStart, res, work,
                     box_of: BoxOf | None = None,
                     flagged: tuple[float, float, float, float] | None = None):
    """The normal solution ``res`` of the patch ``cp`` on a potential area ``bounds``
    [m] (a time step's: the previous contact's box with a margin; or the cold one),
    checked against the patch's rigid overlap at the penetration it found
    (:func:`~railcontact.geometry.points.overlap_box`, with every lobe of the wheel's
    run of vertical overlap at the approach it found with ``box_of``, which reads the run;
    :func:`~.patch.uncovered`): while
    the overlap beyond the grid holds places where the solution's deformed gap may be
    negative, the patch is solved again on the area grown to hold them (with
    :data:`~.patch.UNCOVERED_MARGIN` elements around), its work added to ``work``.

    A contact that does not reach the edge of the given area can still miss a region of
    the overlap beyond it (a second lobe of the gap across the flange root, the tread
    beside a flange-root contact) and carry the load on the part the area holds: the
    patch solver grows an area only where its contact reaches the edge. After the check
    the solution is the one a grid holding the whole overlap gives (a cold solve's),
    within the solver's tolerance. A solve still uncovered after
    :data:`MAX_OVERLAP_PASSES` is not converged. ``flagged``: the first check's places
    beyond the grid, found already (a compiled stage's, :class:`~.start.StagedNormal`).
    Returns the solution and ``work`` with the solves' added.
    """
    for k in range(MAX_OVERLAP_PASSES + 1):
        if not (res.force > 0 and math.isfinite(res.penetration) and res.penetration > 0):
            return res, work
        if k > 0 or flagged is None:
            box = (overlap_box(cp, res.penetration) if box_of is None else
                   box_of(cp, res.penetration, res.penetration / math.cos(cp.contact_angle)
                          + cp.gap))
            flagged = uncovered(gap_of, res, pair, box)
        if flagged is None:
            return res, work
        if k == MAX_OVERLAP_PASSES:
            break
        m = UNCOVERED_MARGIN
        bounds = (min(bounds[0], flagged[0] - m * res.grid.dx),
                  max(bounds[1], flagged[1] + m * res.grid.dx),
                  min(bounds[2], flagged[2] - m * res.grid.dy),
                  max(bounds[3], flagged[3] + m * res.grid.dy))
        res, more = solve_patch_normal(gap_of, bounds, grid, normal, pair, control, est)
        work = work.absorbed(more)
        work = replace(work, remeshes=work.remeshes + 1)
    if res.converged:
        res = not_converged(res, "the contact may reach beyond the potential area after "
                            f"{MAX_OVERLAP_PASSES} enlargements ({res.message})")
    return res, work


KinematicsOf = Callable[[PatchSolution, list[PatchSolution]], PatchKinematics]
"""``kinematics_of(patch, patches)``: the creepages of a normal-solved ``patch`` of a wheel
whose pass solved ``patches`` (:func:`wheel_kinematics`)."""


def wheel_kinematics(found: WheelSearch, motion: WheelsetMotion) -> KinematicsOf:
    """The creepages of the searched wheel's patches from the velocities ``motion``
    (:func:`~railcontact.geometry.kinematics.patch_kinematics`): at each patch's origin
    (its reference point), with the wheel's point at its normal approach below it, and the
    wheelset centre where the pass's vertical approach puts it (the wheel lowered from
    first contact by that approach). The rail's origin is that of ``track``'s rail (with
    its deviation)."""
    track, ws, pose, side = found.track, found.wheelset, found.pose, found.side
    sgn = SIDES[side]
    u0, z0 = track.rail_origin
    origin = (sgn * u0, z0)

    def of(patch: PatchSolution, patches: list[PatchSolution]) -> PatchKinematics:
        cp = patch.geometry
        height = ws.radius - found.least_gap - vertical_approach(patches)
        kin = patch_kinematics(side, cp.position, cp.contact_angle, patch.normal.penetration,
                               (0.0, pose.lateral, height), pose.roll, pose.yaw, origin,
                               motion)
        check_kinematic_creepage(side, kin.creepage, motion.speed,
                                 "the [kinematics] velocities")
        return kin
    return of


def patch_friction(friction: float | FrictionTable, cp: ContactPoint, track: Track
                   ) -> float | PatchFriction:
    """The coefficient of friction of the patch at ``cp``: ``friction`` itself when it
    is a number; of a friction table (in the side frame,
    :func:`~railcontact.settings.friction.side_friction`) the one at the patch's reference
    point, or with ``at = "row"`` that one and one per lateral element row."""
    if not isinstance(friction, FrictionTable):
        return friction
    mu = friction_at_point(friction, cp)
    if friction.at == "patch":
        return mu
    return PatchFriction(mu, row_friction(friction, cp, track))


def _add_tangential(patches: list[PatchSolution], settings: PatchSettings,
                    pair: ElasticPair, previous: list[PatchSolution] | None = None,
                    kinematics_of: KinematicsOf | None = None, track: Track | None = None
                    ) -> list[PatchSolution]:
    """The tangential solution of each loaded patch, started from the traction of the same
    patch in ``previous`` (the wheel's last load pass) where there is one, else from the
    patch's own start (:attr:`~.start.WarmStart.traction_on`). With ``kinematics_of`` each
    patch is solved with the creepages it gives at the patch (and keeps their reference
    velocity), else with the settings' creepages; with a friction table, each patch's
    coefficient read on ``track`` (:func:`patch_friction`)."""
    mu = settings.tangential.friction
    out = []
    for p in patches:
        if p.normal.force > 0:
            last = same_patch(previous, p.geometry)
            start = None if last is None else start_from(last, p.normal.grid)[1:]
            if start is None and p.start is not None:
                start = p.start.traction_on(p.normal.grid)
            if start is not None and start[0] is None:
                start = None
            creepage, solving = None, p
            if kinematics_of is not None:
                kin = kinematics_of(p, patches)
                creepage = kin.creepage
                solving = p.replaced(velocity=kin.velocity,
                                    kinematic_radius=kin.rolling_radius)
            p = solve_patch_tangential(solving, settings.tangential, pair,
                                       settings.normal.fft, creepage=creepage,
                                       previous=start,
                                       friction=patch_friction(mu, p.geometry, track))
        out.append(p)
    return out


def wheel_problem(track: Track, ws: Wheelset, pose: Pose, side: str, pair: ElasticPair,
                  control: Control, found: WheelSearch | None = None) -> WheelProblem:
    """The ``side`` wheel's problem at ``pose`` under ``control``, formed once for its
    passes: the wheel searched at the pose (``found``, when the caller searched it:
    :func:`~railcontact.geometry.search.search_wheel`), its first rigid contact point
    and, under load control, the approaches where two of its contact regions join
    (:class:`~.wheel.WheelProblem`; none of it without a load or an approach: nothing to
    solve). Raises a :class:`RailContactError` for a pose beyond the profiles."""
    if control.value == 0.0 or (control.by_load and negligible_load(control.load)):
        return WheelProblem(track, ws, pose, side, pair, control, None, _NO_MERGES)
    if found is None:
        found = search_wheel(track, ws, pose, side)
    first = contact_points(found, 0.0)[0]
    merges = merge_approaches(found, MIN_LOBE) if control.by_load else _NO_MERGES
    return WheelProblem(track, ws, pose, side, pair, control, first, merges, found)


_NO_MERGES = np.empty(0)
_NO_MERGES.flags.writeable = False


@dataclass(frozen=True, slots=True)
class CaseStart:
    """The passes of a case's wheel (``railcontact solve``, a table's point): each patch
    starts from the settings' estimate, or from ``estimate_for`` (e.g. a table's previous
    point, :mod:`railcontact.table.solve`), and a later load pass from the pass before
    (grid and pressure, traction: :func:`_patches`, :func:`_add_tangential`); the first
    normal share of a creep-load loop is the load itself. With the case's
    ``[kinematics]`` each patch's creepages follow from the velocities
    (:func:`wheel_kinematics`), else the tangential settings' creepages."""

    estimate_for: EstimateFor | None = None

    def share(self, problem: WheelProblem, settings: WheelSettings, load: float) -> float:
        return 0.0

    def solve_pass(self, problem: WheelProblem, settings: WheelSettings, control: Control,
                   before: WheelPass | None) -> WheelPass:
        last = None if before is None else before.patches
        ps = solve_wheel_normal(problem.track, problem.wheelset, problem.pose, problem.side,
                                control, settings.patch, problem.pair, self.estimate_for,
                                last, reference=settings.reference, problem=problem,
                                load_tolerance=settings.normal_load_tolerance,
                                load_acceptance=settings.load_acceptance)
        if settings.patch.tangential is not None:
            motion = settings.patch.kinematics
            kinematics_of = None if motion is None else wheel_kinematics(problem.found,
                                                                         motion)
            ps = _add_tangential(ps, settings.patch, problem.pair, last, kinematics_of,
                                 problem.track)
        return WheelPass(ps)


def solve_wheel(problem: WheelProblem, settings: WheelSettings,
                start: WheelStart | None = None) -> WheelSolution:
    """The BEM solution of one wheel's contact patches: the one wheel solver of a case,
    a table's point and a time step.

    ``problem.control`` is the vertical wheel load [N] or the vertical approach [m]; with
    ``settings.tangential`` the patches are solved for it too, and under load control
    with ``settings.load_includes_creep`` the load includes the creep forces' vertical
    components: the creep-load loop (:func:`~.loadloop.creep_load`, to
    ``settings.load_tolerance``), else one pass. ``start`` says how each pass starts
    (:class:`~.wheel.WheelStart`; None: :class:`CaseStart`, the case's estimates).

    A load not met, or a solve that raises a :class:`~railcontact.errors.CaseError` (a
    patch beyond the half-space model) or a :class:`~railcontact.errors.SolverError`, is
    the solution's status and message (:meth:`~.wheel.WheelSolution.check` raises it); a
    pose beyond the profiles or off the rail raises its :class:`RailContactError`.
    """
    start = start or _CASE_START
    control = problem.control
    if control.value == 0.0:
        return WheelSolution()
    if control.by_load and negligible_load(control.load):
        return WheelSolution(message=f"no contact: {no_contact_load(control.load)}")
    try:
        if (control.by_load and settings.tangential is not None
                and settings.load_includes_creep):
            return creep_load(problem, settings, start)
        one = start.solve_pass(problem, settings, control, None)
    except (CaseError, SolverError) as exc:  # a patch beyond the model, a load loop
        return WheelSolution(status=status_of(exc), message=str(exc), error=exc)
    if not one.patches:
        return WheelSolution(memory=one.memory)
    return WheelSolution(one.patches, Status.OK, "ok", one.creepages, one.memory,
                         load_other=other_root(one.patches))


_CASE_START = CaseStart()


def solve_wheel_normal(track: Track, ws: Wheelset, pose: Pose, side: str, control: Control,
                       settings: PatchSettings, pair: ElasticPair,
                       estimate_for: EstimateFor | None = None,
                       previous: list[PatchSolution] | None = None,
                       reference: bool = False,
                       start: tuple[float, float] | None = None,
                       problem: WheelProblem | None = None,
                       load_tolerance: float = LOAD_RTOL,
                       load_acceptance: float = LOAD_ACCEPT_RTOL) -> list[PatchSolution]:
    """The BEM normal solutions of one wheel's patches (creep forces not counted).

    ``control``: the vertical approach [m] beyond first contact, or the vertical load [N]
    that the normal forces carry (one patch: force control with ``N = Q / cos(gamma)``,
    exact in one solve; several patches: a secant iteration on the approach, each pass
    started from the one before). ``previous``: an earlier solve of the wheel whose patches
    start those at the same contact points (grid and pressure, see :func:`_patches`).
    ``reference``: each patch is solved in the frame at its reference point
    (:func:`~railcontact.geometry.points.at_reference`, formed at the approach; under load
    control a single patch is solved again until the approach it gives is the one its
    frame was formed at, :func:`_single_patch`), else at its rigid contact point.
    ``start``: the vertical approach [m] and the vertical load [N] its normal forces carried
    in an earlier solve of the wheel (e.g. the previous time step) when ``previous`` is
    not given: a single patch's frame is first formed at that approach scaled to
    ``control``'s load, and serves within :data:`WARM_REFERENCE_RTOL`. ``problem``: the
    wheel's problem at this pose (the wheel searched, its first contact point and merges:
    not searched again). ``load_tolerance``: relative tolerance on the load that several
    patches carry (the secant on the approach, and the check of another root); a loop
    that misses the load by more than ``load_acceptance`` raises a
    :class:`~railcontact.errors.ConvergenceError` (:attr:`~.wheel.WheelSettings.
    normal_load_tolerance`, :attr:`~.wheel.WheelSettings.load_acceptance`).
    """
    found = (problem.found if problem is not None and problem.found is not None
             else search_wheel(track, ws, pose, side))
    box_of = partial(overlap_box_on_run, found)
    if not control.by_load:
        approach = control.penetration
        if approach <= 0:
            return []
        return _patches(_points_at(found, approach, reference, settings.separation), ws,
                        approach, settings, pair, estimate_for=estimate_for,
                        previous=previous, box_of=box_of)
    q = control.load
    if negligible_load(q):
        return []
    # one patch: force control (exact) in the frame at the reference point, formed at the
    # approach of the pass before (or Hertz's) and again until the approach holds
    first = contact_points(found, 0.0)[0] if problem is None else problem.first
    single, passes = _single_patch(found, first, q, settings, pair, estimate_for,
                                   previous, reference, start, box_of)

    def residual(a: float) -> tuple[float, list[PatchSolution]]:
        ps = _patches(_points_at(found, a, reference, settings.separation), ws, a, settings,
                      pair, estimate_for=estimate_for, previous=passes[-1], box_of=box_of,
                      load_loop=True)
        passes.append(ps)
        return vertical_force(ps) - q, ps

    approach = vertical_approach(single)
    if count_contacts(found, approach) == 1:
        ps = single
    else:  # several patches: secant on the vertical approach
        ps, r = approach_secant(residual, approach, q, load_tolerance)
        _check_load(ps, r, q, side, load_acceptance)
    merges = merge_approaches(found, MIN_LOBE) if problem is None else problem.merges
    ps, other = first_root(residual, ps, vertical_approach(ps), merges, q, load_tolerance)
    if other is not None:
        _check_load(ps, vertical_force(ps) - q, q, side, load_acceptance)
    if len(passes) > 1:
        ps = count_passes(ps, passes)
    return mark_other(ps, other)


def _check_load(ps: list[PatchSolution], r: float, q: float, side: str,
                acceptance: float) -> None:
    """Raise a :class:`ConvergenceError` when the vertical force misses the load ``q``
    [N] by ``r`` [N] more than ``acceptance`` of it."""
    if abs(r) > acceptance * q:
        raise ConvergenceError(f"{side} wheel: load control did not converge (vertical "
                               f"force {r + q:.6g} N for load {q:.6g} N)", ps)


CENTRE_HINT = 5e-3
"""Lateral wheelset displacement [m] within which a wheel off its rail points at the
profiles (a wheelset near the track centre does not climb its flange on track profiles):
the error says so."""

def mark_other(ps: list[PatchSolution], other: float | None) -> list[PatchSolution]:
    """The patches with :attr:`~.results.PatchSolution.load_other` ``other`` [m] and
    ``load_unique`` False with another root, else True where not yet set (new records
    where they change; a load loop's pass forms its patches with True)."""
    if other is not None:
        return [p.replaced(load_other=other, load_unique=False) for p in ps]
    return [p if p.load_unique is not None else p.replaced(load_unique=True) for p in ps]


def _points_at(found: WheelSearch, approach: float, reference: bool,
               separation: PatchSeparation | None) -> list[ContactPoint]:
    """The contact points of a searched wheel at the vertical ``approach`` [m]: with
    ``reference`` each in the frame at its reference point (:func:`referenced`, with
    ``separation``), else the rigid ones (:func:`~railcontact.geometry.points.
    contact_points`)."""
    if reference:
        return referenced(found, approach, separation)
    return contact_points(found, approach)


def referenced(found: WheelSearch, approach: float,
               separation: PatchSeparation | None = None) -> list[ContactPoint]:
    """The contact points of a searched wheel at the vertical ``approach`` [m], each with its frame
    at the reference point (:func:`~railcontact.geometry.points.at_reference`) where it
    overlaps the rail, else at the rigid point. With ``separation`` (CONTACT's patch
    separation parameters) the planes of neighbouring patches that lie between its
    ``D_SEP`` and ``D_TURN`` apart are inclined at CONTACT's turned angles
    (:func:`~railcontact.geometry.separation.turned_angles`), their points kept."""
    points = [at_reference(found, cp, approach) or cp
              for cp in contact_points(found, approach)]
    if separation is None or len(points) < 2:
        return points
    at = [k for k, cp in enumerate(points) if patch_run(cp) is not None]
    runs = [patch_run(points[k]) for k in at]
    for k, run, angle in zip(at, runs, turned_angles(runs, separation), strict=True):
        if angle != run.angle:
            points[k] = at_reference(found, points[k].rigid, approach,
                                     turn=angle - run.angle) or points[k]
    return points


def _single_patch(found: WheelSearch, first: ContactPoint, q: float,
                  settings: PatchSettings, pair: ElasticPair,
                  estimate_for: EstimateFor | None,
                  previous: list[PatchSolution] | None, reference: bool = True,
                  start: tuple[float, float] | None = None, box_of: BoxOf | None = None
                  ) -> tuple[list[PatchSolution], list[list[PatchSolution]]]:
    """The patch of a wheel with one contact point ``first`` carrying the vertical load
    ``q`` [N] by its normal force, solved in the frame at its reference point, and the
    passes it took.

    The frame is formed at an approach - the previous pass's (or ``start``'s: approach [m],
    vertical load [N]) scaled to ``q`` as Hertz's (``q^(2/3)``), else Hertz's for the rigid
    point - and the patch solved by force
    control, ``N = q / cos(gamma)``; when the approach this gives differs from the one the
    frame was formed at by more than :data:`REFERENCE_RTOL` (:data:`WARM_REFERENCE_RTOL`
    from ``start``), the frame is formed again
    there (at most
    :data:`MAX_REFERENCE_PASSES` passes, each started from the one before; from the third
    on, a secant step on the difference of the two approaches: on a flange the frame's
    overlap can grow faster with the approach than the vertical motion's normal share, and
    the plain iteration then swings). From Hertz's approach (a cold wheel: no ``previous``,
    no ``start``) the first pass is a probe of the approach, solved to a looser normal
    tolerance (:func:`~.loadloop.probe_settings`) and always followed by a pass at the
    full one. A probe whose start gives no pressure is solved on a coarser grid where the
    normal tolerance allows (:func:`~.loadloop.probe_grid`); the frame formed at its
    approach, an estimate as an earlier solve's, then serves within
    :data:`WARM_REFERENCE_RTOL`, and the pass after it meshes the probe's contact
    (:func:`_probed_area`). Without
    ``reference``: one force-controlled solve at the rigid point."""
    if not reference:
        cosg = math.cos(first.contact_angle)
        single = _patches([first], found.wheelset, 0.0, settings, pair, loads=[q / cosg],
                          estimate_for=estimate_for, previous=previous, box_of=box_of,
                          load_loop=True)
        return single, [single]
    if previous:  # the pass before, its approach scaled to this load as Hertz's
        q_prev = sum(p.normal.force * math.cos(p.geometry.contact_angle) for p in previous)
        approach = vertical_approach(previous) * (q / q_prev) ** (2 / 3) if q_prev > 0 else \
            vertical_approach(previous)
    elif start is not None and start[0] > 0:  # an earlier solve's, scaled the same way
        approach = start[0] * (q / start[1]) ** (2 / 3) if start[1] > 0 else start[0]
    else:
        cosg = math.cos(first.contact_angle)
        approach = hertz(first.A, first.B, pair, load=q / cosg).penetration / cosg \
            if math.isfinite(first.B) and first.B > 0 and first.A > 0 else 0.0
    rtol = WARM_REFERENCE_RTOL if start is not None and not previous else REFERENCE_RTOL
    passes: list[list[PatchSolution]] = []
    last = previous
    tried: list[tuple[float, float]] = []  # (approach formed at, residual)
    # from Hertz's approach the first pass is a probe of the approach, solved to a looser
    # tolerance (its frame is formed again at the approach it gives: 1-60 % from Hertz's)
    probe = approach > 0 and not previous and start is None
    coarse = False  # (the pass before was a coarse probe: its start gave no pressure)
    for _ in range(MAX_REFERENCE_PASSES):
        coarse_grid = probe_grid(settings) if probe else None  # (None: the full grid)
        cp = at_reference(found, first, approach) if approach > 0 else None
        cp = cp or first
        ps = _patches([cp], found.wheelset, 0.0,
                      probe_settings(settings) if probe else settings, pair,
                      loads=[q / math.cos(cp.contact_angle)], estimate_for=estimate_for,
                      previous=last, box_of=box_of, probe_grid=coarse_grid,
                      after_probe=coarse, load_loop=True)
        passes.append(ps)
        coarse = coarse_grid is not None and bool(ps) and not ps[0].start.gives_pressure
        new = vertical_approach(ps)
        if cp is first and (approach <= 0 or at_reference(found, first, new) is None):
            if probe:  # the rigid point's patch is the answer: solved again, in full
                probe, last = False, ps
                continue
            break  # no reference point to form: the rigid point's patch is the answer
        if abs(new - approach) <= rtol * new and not probe:
            break
        if coarse:  # (a coarse probe's approach: an estimate, as an earlier solve's)
            rtol = WARM_REFERENCE_RTOL
        probe = False
        tried.append((approach, new - approach))
        last = ps
        if len(tried) >= 2 and tried[-1][1] != tried[-2][1]:  # secant on the residual
            (a0, r0), (a1, r1) = tried[-2:]
            new = min(max(a1 - r1 * (a1 - a0) / (r1 - r0), 0.5 * a1), 2.0 * a1)
        approach = new
    return passes[-1], passes


def _solve_sides(track: Track, ws: Wheelset, pose: Pose, sides: list[str], control: Control,
                 settings: PatchSettings, pair: ElasticPair, reference: bool = True,
                 convention: str = "railcontact", starts: Starts | None = None
                 ) -> dict[str, list[PatchSolution]]:
    out = {}
    for side in sides:
        start = _CASE_START if starts is None else CaseStart(starts(side))
        ps = side_settings(settings, side, convention)
        try:
            solution = solve_wheel(wheel_problem(track, ws, pose, side, pair, control),
                                   WheelSettings(ps, ps.tangential, reference), start)
            out[side] = solution.check(side).patches
        except ConvergenceError as exc:
            if len(sides) == 1 or not exc.partial:
                raise
            out[side] = _not_converged(exc.partial, str(exc))  # the other wheel kept
        except RailContactError as exc:
            if isinstance(exc, CaseError):
                raise
            raise CaseError(f"[geometry] lateral_displacement = {pose.lateral:g} m: "
                            f"{side} wheel: {exc}") from None
    return out


def _not_converged(patches: list[PatchSolution], why: str) -> list[PatchSolution]:
    """A wheel's ``patches`` of the last pass of a load loop that did not converge, each
    marked not converged with ``why`` (the load loop's failure) in its normal message: of
    a case with both wheels, the failed wheel is reported so, the other as it is."""
    return [p.replaced(normal=not_converged(
        p.normal, f"not converged: {why} (this pass: {p.normal.message})")) for p in patches]


def side_settings(settings: PatchSettings, side: str, convention: str) -> PatchSettings:
    """``settings`` with the creepages (and a friction table's angles) read in
    ``convention`` and turned into the side frame of the ``side`` wheel
    (:mod:`railcontact.settings.convention`, :mod:`railcontact.settings.friction`)."""
    t = settings.tangential
    if t is None or convention == "railcontact":
        return settings
    return replace(settings, tangential=replace(
        t, creepage=side_creepage(t.creepage, side, convention),
        friction=side_friction(t.friction, side, convention)))


def _equal_loads(track: Track, ws: Wheelset, pose: Pose, control: Control,
                 settings: PatchSettings, pair: ElasticPair, reference: bool = True,
                 convention: str = "railcontact", starts: Starts | None = None
                 ) -> tuple[Pose, dict[str, list[PatchSolution]]]:
    """Roll at which both wheels carry ``[normal] load``, with both wheels' solutions.

    The residual ``F(phi) = m_left - m_right - (delta_right - delta_left)`` (first-contact
    gaps minus the difference of the loaded wheels' vertical approaches) is driven to zero by
    the fixed point ``phi <- contact_roll(offset = delta_right - delta_left)``. Where a wheel
    switches between tread and flange the approaches jump (a flange carrying the vertical
    load needs a far larger vertical approach) and the fixed point oscillates, and on a
    flange it contracts slowly; so a pass takes the secant step on F when that goes
    further (at most 4 fixed-point steps), and as soon as two passes bracket a sign change
    of F, Brent's method finishes on the bracket. Where the contact jumps between the
    flange root and the flange, F itself jumps (one planar patch across the root carries
    its vertical load at the flange angle); the roll found is then the jump, to
    :data:`ROLL_TOL`, and the two wheels' vertical positions differ by up to the jump of the
    approach.
    """
    solved: dict[float, dict[str, list[PatchSolution]]] = {}
    values: dict[float, float] = {}

    def residual(phi: float) -> float:
        if phi in values:  # Brent's method asks again for the ends of its bracket
            return values[phi]
        p = Pose(pose.lateral, pose.yaw, phi)
        per_side = _solve_sides(track, ws, p, ["left", "right"], control, settings, pair,
                                reference, convention, starts)
        solved[phi] = per_side
        values[phi] = (first_contact_gap(track, ws, p, "left")
                       - first_contact_gap(track, ws, p, "right")
                       - vertical_approach(per_side["right"]) + vertical_approach(per_side["left"]))
        return values[phi]

    def offset(phi: float) -> float:
        return vertical_approach(solved[phi]["right"]) - vertical_approach(solved[phi]["left"])

    phi = pose.roll
    f = residual(phi)
    prev: tuple[float, float] | None = None
    try:
        for _ in range(MAX_ROLL_PASSES):
            new = contact_roll(track, ws, pose.lateral, pose.yaw, offset(phi))
            step = new - phi
            if abs(step) <= ROLL_TOL:
                break
            if prev is not None and f != prev[1]:  # secant on F, if it goes further
                secant = -f * (phi - prev[0]) / (f - prev[1])
                if secant * step > 0:
                    new = phi + math.copysign(min(max(abs(secant), abs(step)), 4 * abs(step)),
                                              step)
            f_new = residual(new)
            if (f_new > 0) != (f > 0):
                phi = brentq(residual, min(phi, new), max(phi, new), xtol=ROLL_TOL)
                if phi not in solved:
                    residual(phi)
                break
            prev, phi, f = (phi, f), new, f_new
        else:
            raise CaseError(f"[geometry] roll = 'equal-loads' did not converge in "
                            f"{MAX_ROLL_PASSES} passes (roll {phi:.6g} rad)")
    except RailContactError as exc:
        if isinstance(exc, CaseError):
            raise
        raise CaseError(f"[geometry] roll = 'equal-loads': {exc}") from None
    final = {side: count_passes(patches, [per_side[side] for per_side in solved.values()])
             for side, patches in solved[phi].items()}  # every roll pass counts
    return Pose(pose.lateral, pose.yaw, phi), final


def solve_wheel_rail(case: Case, starts: Starts | None = None, *,
                     frictional_power: bool = True) -> tuple[list[PatchSolution], Pose]:
    """All contact patches of the case's wheel(s), each with its BEM normal (and tangential)
    solution, and the wheelset pose they were solved at (its roll resolved when the case
    asks for ``"rigid"`` or ``"equal-loads"``).

    With ``case.convention == "contact"`` the creepages are read as CONTACT's
    (:mod:`railcontact.settings.convention`), each patch is solved at its reference point
    whatever ``[geometry] patch_frame`` says, and the patches report their forces as
    CONTACT's (:attr:`PatchSolution.convention`).

    ``starts(side)`` gives the ``estimate_for`` of each wheel (or None),
    e.g. a neighbouring solution's start (:mod:`railcontact.table.solve`); without it every
    patch starts as the case's estimates say, as ``railcontact solve`` does.
    ``frictional_power=False`` leaves each patch's frictional power unformed (None; forming
    it costs a product with the operator per patch, which a table does not store).
    """
    geo = case.geometry
    if not isinstance(geo, WheelRailGeometry):
        raise CaseError(f"a wheel-rail case needs a wheel-rail geometry, got {type(geo).__name__}")
    track, ws, pose = build_geometry(geo)
    control, settings, pair = case.normal.control, case.patch_settings, case.pair
    placed = track  # the other wheel's rail: where it is placed
    if geo.rail_deviated:  # (one side, Case checks) its rail deviated
        try:
            track = track.deviated(geo.side, geo.rail_offset, geo.rail_roll)
            _ = track.side_rail
        except RailContactError as exc:
            raise CaseError(f"[geometry] rail_offset, rail_roll: {exc}") from None
    convention = case.convention  # CONTACT's: always at the reference point
    reference = geo.patch_frame == "reference" or convention == "contact"
    if reference:  # the reference point is an element's centre, as in CONTACT's grids
        settings = replace(settings, grid=replace(settings.grid, centred=True))
    sides = ["left", "right"] if geo.side == "both" else [geo.side]
    for other in {"left", "right"} - set(sides):  # the wheelset is one body
        try:
            check_on_rail(contact_points(search_wheel(placed, ws, pose, other), 0.0)[0], ws)
        except RailContactError as exc:
            hint = ("; so near the track centre this points at the profiles rather than "
                    "the pose: check [geometry] wheel and rail (a rail's profile given as "
                    "the wheel's?)" if abs(pose.lateral) < CENTRE_HINT else "")
            raise CaseError(f"[geometry] lateral_displacement = {pose.lateral:g} m puts the "
                            f"{other} wheel off its rail: {exc}{hint}") from None
    if geo.roll == "equal-loads":
        pose, per_side = _equal_loads(track, ws, pose, control, settings, pair, reference,
                                      convention, starts)
    else:
        per_side = _solve_sides(track, ws, pose, sides, control, settings, pair, reference,
                                convention, starts)
    patches = []
    for p in (p for side in sides for p in per_side[side]):
        if frictional_power:
            p = with_frictional_power(p)
        n, cp = p.normal, p.geometry
        if cp.rigid is not None:  # solved in the frame at its reference point
            reference = ReferencePoint(offset=reference_offset(cp), position=cp.position,
                                       rail_y=cp.rail_y, wheel_s=cp.wheel_s,
                                       contact_angle=cp.contact_angle,
                                       rolling_radius=cp.rolling_radius)
        else:  # at the rigid point (no reference point formed): from its interpenetration
            X, Y = n.grid.mesh()
            reference = reference_point(cp, track, ws, X, Y,
                                        n.penetration - cp.gap_on_grid(n.grid))
        patches.append(p.replaced(convention=convention, reference=reference))
    return patches, pose
