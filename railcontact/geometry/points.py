"""A searched wheel's contact points and patch frames: pure functions of the search's
record (:class:`WheelSearch`, formed once per wheel and pose by
:func:`~.search.search_wheel`) and of the points they form.

For a vertical rigid approach ``delta`` (vertical) every connected interval of the trace's
``g - min g < delta`` is one contact patch, centred on its local minimum of g
(:func:`contact_points`); :func:`at_reference` places a patch's frame at CONTACT's
contact reference point. At each contact point the contact tangent plane is inclined by
the contact angle ``gamma = atan(dZ_rail/du)`` (side frame: positive when the normal
leans towards the track centre, i.e. towards the flange). In that plane, with ``s``
across and ``x`` along the track, the undeformed gap is taken as

    h(x, s) = f(s) + A(s) x^2,     A(s) = cos(beta(s)) / (2 r(s)),

``f(s)`` the distance between the profiles normal to the tangent plane (zero at the contact
point), ``r(s)`` the wheel radius and ``beta(s)`` the wheel profile angle there (Meusnier:
the wheel's curvature along the rolling direction; the rail is straight). ``A = A(0)`` and
``B = f''(0)/2`` are the curvatures Hertz needs. Yaw shifts the contact point along x (the
trace offset) but the gap is taken symmetric in x.

A point's scalar fields are formed with it. Its tangent plane's samples ``f(s)`` ... are
read through functions (:func:`samples`, :func:`gap_on_grid`, :func:`overlap_box`,
:func:`overlap_on_rail`, :func:`lateral_extent`) that form the samples they read, once,
in the point's :class:`TangentPlane`: a time step in the frame at the reference point reads
the samples over the patch's overlap only (and those its grids reach).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from ..errors import check_positive
from ..halfspace.grid import Grid
from . import kernels
from .separation import PatchRun
from .track import SIDES, Pose, Track, Wheelset

FAR = 1.0
"""Gap [m] given to elements beyond the profiles: far out of contact."""
HALF_WIDTH = 0.025
"""Half width [m] of the lateral samples of a patch's tangent plane."""
N_S = 1001
"""Lateral samples of a patch's tangent plane (0.05 mm apart)."""
K0 = N_S // 2
"""The sample at the patch origin, s = 0."""
S_SAMPLES = _S_SAMPLES = np.linspace(-HALF_WIDTH, HALF_WIDTH, N_S)
"""The lateral coordinates s [m] of a tangent plane's samples (read-only)."""
_S_SAMPLES.flags.writeable = False
_S_LIST = _S_SAMPLES.tolist()
"""The same as Python floats (read without numpy's scalars)."""
_DS = float(_S_SAMPLES[1] - _S_SAMPLES[0])
B_DENOMINATOR = _B_DENOMINATOR = 2 * float(_S_SAMPLES[5] - _S_SAMPLES[0]) ** 2
"""``2 h^2`` of the samples ``K0 - 5``, ``K0``, ``K0 + 5`` a curvature B is read from
(:func:`~.kernels.lateral_curvature`)."""

WEIGHT_POWER = 2.5
"""The reference point's weight is the vertical interpenetration to this power: its square
integrated along the track over the overlap ``e - x^2 / (2 r)`` gives ``e^(5/2)``
(CONTACT's default gap weighting; with 2.5 the points and angles of CONTACT's 34 cases are
matched to 0.01 mm and 0.001 rad, with 2 or 3 not)."""


MIN_LOBE = 0.05
"""Saddles whose shallower lobe is less deep than this share of the saddle's approach are
ripples of the profiles, not checked for another root (:func:`~railcontact.contact.
loadloop.first_root`): the lobe's own run carries about ``0.05^(3/2)`` ~ 1 % of the load
(Hertz, the same curvatures). The search forms the merges with it
(:attr:`WheelSearch.merges`)."""


class WheelSearch(NamedTuple):
    """One wheel searched at a pose (:func:`~.search.search_wheel`): what every contact
    point and patch frame of the wheel at that pose is formed from (SI units, side frame;
    arrays read-only; a named tuple: one is formed per wheel and pose).

    Attributes
    ----------
    track, wheelset, pose, side
        The placed rail, the wheelset, its pose and the wheel ("left" or "right").
    trace
        (5, n): the wheel's trace points above the rail, ``eta, x, u, z, g``
        (:func:`~.search.vertical_gap`).
    least_gap
        The least vertical gap [m] of the trace above the rail (first contact).
    first_sample, increasing, ties
        The first trace sample with the least gap, whether the trace's u increase, and how
        many samples have the least gap.
    rail, wheel
        The placed rail and the wheel as the kernels read them (:func:`~.search.
        rail_arrays`, :func:`~.search.wheel_arrays`).
    first
        The first rigid contact point as the search formed it: its row of
        :func:`~.kernels.rigid_point` and its :func:`~.kernels.rigid_record`; None where
        the least gap is not on one sample (:func:`contact_points` forms it then).
    merges
        The approaches [m] at which its contact regions merge, with :data:`MIN_LOBE`
        (:func:`merge_approaches`), as the search formed them; None: formed when asked
        for.
    """

    track: Track
    wheelset: Wheelset
    pose: Pose
    side: str
    trace: np.ndarray
    least_gap: float
    first_sample: int
    increasing: bool
    ties: int
    rail: tuple
    wheel: tuple
    first: tuple | None = None
    merges: np.ndarray | None = None
    """:func:`merge_approaches` with :data:`MIN_LOBE`, as the search formed it (None: formed
    when asked for)."""

    def __repr__(self) -> str:  # (without the arrays)
        return (f"WheelSearch(track={self.track!r}, wheelset={self.wheelset!r}, "
                f"pose={self.pose!r}, side={self.side!r}, least_gap={self.least_gap!r}, "
                f"first_sample={self.first_sample!r}, increasing={self.increasing!r}, "
                f"ties={self.ties!r})")


class Samples(NamedTuple):
    """A tangent plane's lateral samples (SI units): the lateral coordinate ``s`` [m], the
    normal gap ``f(s)`` [m], ``A(s)`` [1/m], the wheel profile coordinate S [m] and the
    rail surface point (lateral ``u``, vertical Z; side frame) [m] (NaN where the profiles
    end)."""

    s: np.ndarray
    f: np.ndarray
    a_of_s: np.ndarray
    wheel_s_of_s: np.ndarray
    rail_u_of_s: np.ndarray
    rail_z_of_s: np.ndarray


class TangentPlane:
    """The samples of a point's tangent plane formed so far: none (a rigid contact point's
    until they are read), those over the patch's overlap (a frame at the reference point,
    :func:`at_reference`: ``frame`` valid at ``i0:i1``) or all of them (``full``).

    The functions that read samples form those they read, once (each sample's value does
    not depend on when it is formed: a reader of the samples formed earlier reads the same
    values); nothing is formed when a field of the point is read. ``what``: the arguments
    that form the others."""

    __slots__ = ("frame", "full", "i0", "i1", "what")

    def __init__(self, what: tuple, frame: np.ndarray | None = None, i0: int = 0,
                 i1: int = 0, full: Samples | None = None) -> None:
        self.what, self.frame, self.i0, self.i1, self.full = what, frame, i0, i1, full

    def __getstate__(self) -> tuple:
        return self.what, self.frame, self.i0, self.i1, self.full

    def __setstate__(self, state: tuple) -> None:
        self.what, self.frame, self.i0, self.i1, self.full = state


@dataclass(frozen=True)
class ContactPoint:
    """One contact patch's geometry (SI units; side frame unless stated).

    Attributes
    ----------
    side
        "left" or "right".
    gap
        Vertical gap of this local minimum above the smallest gap of the wheel [m]; the
        patch's own approach is ``delta - gap`` (vertical).
    wheel_s
        Wheel profile coordinate S of the contact point [m].
    rail_u
        Lateral position on the placed rail, side frame [m] (the gauge point is at
        gauge/2).
    rail_y
        Rail profile coordinate of the contact point (uncanted rail frame) [m].
    position
        Contact point on the rail in the track frame (X, Y, Z) [m].
    contact_angle
        gamma [rad], side frame (positive towards the flange).
    rolling_radius
        Wheel radius at the contact point [m].
    A, B
        Longitudinal and lateral relative curvatures at the contact point [1/m].
    s
        The lateral coordinates of the tangent plane's samples [m] (:func:`samples`
        gives the values there).
    approach, rigid
        For a patch frame placed at the reference point (:func:`at_reference`): the
        vertical approach [m] it was formed at and the rigid contact point it was formed
        from; None, None for a rigid contact point (:func:`reference_offset` gives the
        frame's offset from that point).
    run
        What CONTACT's turning of neighbouring patches reads of a point formed by
        :func:`at_reference` (:func:`patch_run`); None for a rigid contact point.
    plane
        The tangent plane's samples formed so far (:class:`TangentPlane`).
    """

    side: str
    gap: float
    wheel_s: float
    rail_u: float
    rail_y: float
    position: tuple[float, float, float]
    contact_angle: float
    rolling_radius: float
    A: float
    B: float
    s: np.ndarray = field(repr=False)
    approach: float | None
    rigid: ContactPoint | None = field(repr=False)
    run: PatchRun | None = field(repr=False, compare=False)
    plane: TangentPlane = field(repr=False, compare=False)

    def normal_penetration(self, approach: float) -> float:
        """Normal penetration [m] of this patch for a vertical wheel approach [m]."""
        return max(approach - self.gap, 0.0) * math.cos(self.contact_angle)

    def gap_on_grid(self, grid: Grid) -> np.ndarray:
        """Undeformed gap h(x, y) = f(y) + A(y) x^2 of this patch at the element centres
        of ``grid`` [m], with the grid's y along s. Where the profiles end (or fold away
        from this contact) the gap is :data:`FAR` - such elements can never touch."""
        out = np.empty((grid.nx, grid.ny))  # f and A depend on y alone: one compiled pass
        plane = self.plane
        if plane.frame is None:
            full = samples(self)
            kernels.gap_on_grid(full.s, full.f, full.a_of_s, float(grid.x0),
                                float(grid.dx), grid.nx, float(grid.y0), float(grid.dy),
                                grid.ny, FAR, out)
            return out
        # a frame at the reference point formed over part of its samples: formed further
        # where the grid reads beyond them
        plane.i0, plane.i1 = kernels.gap_on_frame(
            plane.what, plane.frame, plane.i0, plane.i1, float(grid.x0), float(grid.dx),
            grid.nx, float(grid.y0), float(grid.dy), grid.ny, FAR, out)
        return out

    def lateral_extent(self, delta: float, margin: float = 1.0) -> tuple[float, float]:
        """:func:`lateral_extent` of this patch."""
        return lateral_extent(self, delta, margin)


def normal_penetration(cp: ContactPoint, approach: float) -> float:
    """Normal penetration [m] of the patch ``cp`` for a vertical wheel approach [m]
    (:meth:`ContactPoint.normal_penetration`)."""
    return cp.normal_penetration(approach)


def samples(cp: ContactPoint) -> Samples:
    """The tangent plane's samples of ``cp``, all of them (formed now where they are not
    yet, and kept in its :class:`TangentPlane`)."""
    plane = cp.plane
    full = plane.full
    if full is not None:
        return full
    if plane.frame is None:  # a rigid contact point's (:func:`~.kernels.rigid_frame`)
        trace, g_min, rail, wheel, u_c, z_rail, gamma, eta_c = plane.what
        out = np.empty((5, N_S))
        kernels.rigid_frame(trace[0], trace[2], trace[3], g_min, *rail[:2], *wheel, u_c,
                            z_rail, gamma, eta_c, _S_SAMPLES, K0, out)
    else:  # a frame at the reference point formed over part of its samples
        out = _extend(plane, 0, N_S)
    full = Samples(_S_SAMPLES, *out)
    plane.full, plane.frame = full, None
    return full


def gap_on_grid(cp: ContactPoint, grid: Grid) -> np.ndarray:
    """Undeformed gap h(x, y) = f(y) + A(y) x^2 of the patch ``cp`` at the element centres
    of ``grid`` [m] (:meth:`ContactPoint.gap_on_grid`)."""
    return cp.gap_on_grid(grid)


def lateral_extent(cp: ContactPoint, delta: float, margin: float = 1.0
                   ) -> tuple[float, float]:
    """Interval of s around 0 where f(s) <= delta (times margin) [m] (paper Sec. 2.1)."""
    full = samples(cp)
    s = full.s
    k0 = K0 if s is _S_SAMPLES else kernels.nearest(s, 0.0)
    lo, hi = kernels.lateral_extent(s, full.f, float(delta), k0)  # the run through k0
    ds = s[1] - s[0]
    a, b = s[lo] - ds, s[hi] + ds
    return margin * a, margin * b


def overlap_box(cp: ContactPoint, penetration: float,
                run: tuple[float, float] | None = None) -> tuple[float, float, float, float]:
    """The box (xmin, xmax, ymin, ymax) [m] in the patch's plane around its rigid
    overlap at the normal ``penetration`` [m]: the points ``(x, s)`` of the run of lateral
    samples through the origin where ``f(s) <= penetration`` (the run the cold potential
    area is formed on, :func:`lateral_extent`) with ``f(s) + A(s) x^2 <=
    penetration``, widened by one sample spacing across. With ``run`` (the lateral
    positions on the rail [m] spanned by the patch's run of vertical overlap,
    :func:`run_on_rail`) also every other sample where ``f(s) <= penetration`` whose rail
    position lies in it: the plane of a patch whose run holds two lobes of the gap (the
    tread and the flange root joined) can show them apart, the second beyond a saddle
    of ``f`` above the penetration.

    Where the undeformed gap exceeds the penetration the surfaces cannot touch (the
    elastic displacements of a compressive pressure only open the gap), so a potential
    area that holds this box holds every place the patch's contact can reach. A frame
    at the reference point formed over part of its samples (:func:`at_reference`) forms
    more only where the overlap, or the run, reaches the part's edge."""
    penetration = float(penetration)
    lo_u, hi_u = run if run is not None else (math.inf, -math.inf)
    plane = cp.plane
    while plane.frame is not None:
        frame, i0, i1 = plane.frame, plane.i0, plane.i1
        f = frame[kernels.F, i0:i1]
        u = frame[kernels.RAIL_U, i0:i1]
        lo, hi = kernels.lobes_extent(f, u, penetration, min(max(K0 - i0, 0), i1 - i0 - 1),
                                      lo_u, hi_u)
        a = i0 - kernels.FRAME_GROW if i0 > 0 and (lo == 0 or lo_u <= u[0] <= hi_u) else i0
        b = i1 + kernels.FRAME_GROW if i1 < N_S and (
            hi == i1 - i0 - 1 or lo_u <= u[-1] <= hi_u) else i1
        if (a, b) == (i0, i1):
            return _box(_S_SAMPLES[i0:i1], f, frame[kernels.A_OF_S, i0:i1], lo, hi,
                        penetration)
        _extend(plane, max(a, 0), min(b, N_S))
    full = samples(cp)
    s, f = full.s, full.f
    k0 = K0 if s is _S_SAMPLES else kernels.nearest(s, 0.0)
    lo, hi = kernels.lobes_extent(f, full.rail_u_of_s, penetration, k0, lo_u, hi_u)
    return _box(s, f, full.a_of_s, lo, hi, penetration)


def overlap_box_on_run(found: WheelSearch, cp: ContactPoint, penetration: float,
                      approach: float) -> tuple[float, float, float, float]:
    """:func:`overlap_box` of the patch ``cp`` of the searched wheel at the normal
    ``penetration`` [m] with the run of the wheel's vertical overlap at the vertical
    ``approach`` [m] that holds the patch's point (:func:`run_on_rail`): of a frame at the
    reference point formed over part of its samples, one compiled pass
    (:func:`~.kernels.overlap_box_frame`)."""
    plane = cp.plane
    if plane.frame is None:
        return overlap_box(cp, penetration, run_on_rail(found, approach, cp.rail_u))
    trace = found.trace
    xmin, xmax, ymin, ymax, plane.i0, plane.i1 = kernels.overlap_box_frame(
        trace[4], trace[2], found.least_gap, float(approach), float(cp.rail_u),
        found.increasing, *plane.what, plane.frame, plane.i0, plane.i1,
        float(penetration), K0, kernels.FRAME_GROW)
    return xmin, xmax, ymin, ymax


def _box(s: np.ndarray, f: np.ndarray, a_of_s: np.ndarray, lo: int, hi: int,
         penetration: float) -> tuple[float, float, float, float]:
    """:func:`overlap_box` of the run ``lo..hi`` (inclusive) of the samples."""
    ds = float(s[1] - s[0])
    xl = kernels.overlap_half_length(f, a_of_s, lo, hi, penetration)
    return (-xl, xl, float(s[lo]) - ds, float(s[hi]) + ds)


def overlap_on_rail(cp: ContactPoint, penetration: float) -> tuple[float, float] | None:
    """The lateral positions on the rail [m] (side frame, as :attr:`ContactPoint.rail_u`)
    spanned by the lateral samples of ``cp`` where its gap ``f`` is below the normal
    ``penetration`` [m] (the rigid overlap there), or None without any; of a frame at the
    reference point formed over part of its samples (:func:`at_reference`), over that part
    (the patch's overlap and a margin), without forming the others."""
    plane = cp.plane
    if plane.frame is None:
        full = samples(cp)
        f, u = full.f, full.rail_u_of_s
    else:
        frame, i0, i1 = plane.frame, plane.i0, plane.i1
        f, u = frame[kernels.F, i0:i1], frame[kernels.RAIL_U, i0:i1]
    inside = (f < penetration) & np.isfinite(u)
    if not inside.any():
        return None
    return float(u[inside].min()), float(u[inside].max())


def run_on_rail(found: WheelSearch, approach: float, rail_u: float) -> tuple[float, float]:
    """The lateral positions on the rail [m] (side frame, as :attr:`ContactPoint.rail_u`)
    spanned by the run of the wheel's vertical overlap at the vertical ``approach`` [m]
    beyond first contact that holds (or lies nearest) the rail position ``rail_u`` [m]:
    the extent of one patch's rigid contact region (:func:`~.kernels.run_extent`)."""
    trace = found.trace
    return kernels.run_extent(trace[4], trace[2], found.least_gap, float(approach),
                              float(rail_u), found.increasing)


def contact_points(found: WheelSearch, approach: float = 0.0) -> list[ContactPoint]:
    """Contact patches of the searched wheel for a vertical rigid approach ``approach``
    [m].

    ``approach = 0`` gives the first point of contact only. Patches are ordered by gap
    (the first one has gap 0).
    """
    approach = _approach(approach)
    trace, g_min, k = found.trace, found.least_gap, found.first_sample
    wheel = found.wheel
    rail = found.rail[2:4]
    if approach == 0.0 and found.ties == 1 and math.isfinite(g_min):
        # first contact: the least gap's sample is the only one at most 0 above it, so
        # its run is that sample alone (rigid_points' scans of the trace find the same),
        # formed by the search
        if found.first is not None:
            return [_point(found, *found.first)]
        rows = [kernels.rigid_point(trace[0], trace[1], trace[2], trace[4], g_min, k, k + 1,
                                    *rail, *wheel[:2], *wheel[3:])]
    else:
        rows = kernels.rigid_points(trace, g_min, k, float(approach), *rail, *wheel[:2],
                                    *wheel[3:]).tolist()
    points = [_point(found, row) for row in rows]
    if len(points) > 1:
        points.sort(key=lambda c: c.gap)
    return points


def _approach(approach: float) -> float:
    """A vertical ``approach`` [m] checked: finite and not negative (a float of those
    passed as it is, without the checks' calls)."""
    if type(approach) is float and 0.0 <= approach < math.inf:
        return approach
    return check_positive("approach", approach, "m", allow_zero=True)


def count_contacts(found: WheelSearch, approach: float = 0.0) -> int:
    """The number of patches :func:`contact_points` finds, without their geometry."""
    approach = _approach(approach)
    return kernels.count_runs(found.trace[4], found.least_gap, found.first_sample,
                              float(approach))


def merge_approaches(found: WheelSearch, min_lobe: float = 0.0) -> np.ndarray:
    """The vertical approaches [m] beyond first contact at which two of the wheel's rigid
    contact regions (runs of :func:`contact_points`) join into one patch, increasing: the
    saddles of the trace's gap whose shallower lobe is at least ``min_lobe`` times the
    saddle's approach deep (a lobe shallower than that is a ripple of the profiles: its run
    carries little of the load; :func:`~.kernels.merge_saddles`; with :data:`MIN_LOBE`
    formed by the search itself, :attr:`WheelSearch.merges`). Read-only."""
    if min_lobe == MIN_LOBE and found.merges is not None:
        return found.merges
    out = kernels.merge_saddles(found.trace[4], found.least_gap, float(min_lobe))
    out.flags.writeable = False
    return out


def _point(found: WheelSearch, row, rec=None) -> ContactPoint:
    """The rigid contact point ``row`` of :func:`~.kernels.rigid_points` (a run of the
    trace: its least gap above the least gap, refined by a parabola through three
    samples): its curvatures from the samples of its tangent frame near the point and its
    rail profile coordinate (``rec``, :func:`~.kernels.rigid_record`: formed here when
    not given), the others formed when read (:func:`samples`)."""
    eta_c, x_c, u_c, z_rail, gap_c, gamma, s_c, dr = row
    trace, g_min, rail, wheel = found.trace, found.least_gap, found.rail, found.wheel
    if rec is None:
        rec = kernels.rigid_record(trace[0], trace[2], trace[3], g_min, *rail[:2], *wheel,
                                   u_c, z_rail, gamma, eta_c, _S_SAMPLES, K0,
                                   _B_DENOMINATOR, found.increasing,
                                   *rail[8:])
    A, B, rail_y = rec
    if rail_y != rail_y:  # NaN: the point is not finite (raises)
        found.track.rail_coordinate(u_c, z_rail)
    side = found.side
    return ContactPoint(
        side=side, gap=gap_c, wheel_s=s_c, rail_u=u_c, rail_y=rail_y,
        position=(x_c, SIDES[side] * u_c, z_rail), contact_angle=gamma,
        rolling_radius=found.wheelset.radius + dr, A=A, B=B, s=_S_SAMPLES, approach=None,
        rigid=None, run=None,
        plane=TangentPlane((trace, g_min, rail, wheel, u_c, z_rail, gamma, eta_c)))


def at_reference(found: WheelSearch, cp: ContactPoint, approach: float, turn: float = 0.0
                 ) -> ContactPoint | None:
    """The patch of the rigid contact point ``cp`` of the searched wheel with its frame at
    CONTACT's contact reference point, for the wheel's vertical approach ``approach`` [m]
    beyond first contact, formed as CONTACT's ``m_wr_locatecp`` does (None when the wheel
    does not overlap the rail there).

    Along the trace, the wheel lowered by ``approach`` overlaps the rail by the vertical
    interpenetration ``e(u)`` over the patch's own run (around ``cp``). The reference point
    is the rail surface at the lateral position ``u`` averaged with the weight
    ``e^`` :data:`WEIGHT_POWER`, and the contact angle is the rail's inclination averaged
    the same way. The new frame's origin is that point, its plane inclined at that angle;
    the gap ``f(s)`` across it is the normal distance of the lowered wheel from the rail,
    shifted so that its least value is 0, and the patch's ``gap`` is set so that
    :func:`normal_penetration` of ``approach`` is the overlap there. The wheel
    moves vertically, not along the new normal, so the frame holds for that approach; the
    load loops form it again as the approach changes.

    ``turn`` [rad] is added to the weighted angle before the plane is formed: CONTACT's
    turning of neighbouring patches (:func:`~.separation.turned_angles`; the point stays).
    :func:`patch_run` gives what that turning reads of the point.
    """
    approach = float(approach)  # plain floats in the point: numpy's scalars cost more
    d = cp.normal_penetration(approach)  # in every use after (Hertz's Newton iteration)
    if not d > 0:
        return None
    trace, g_min, increasing = found.trace, found.least_gap, found.increasing
    # one compiled pass (:func:`~.kernels.reference_frame`): the patch's own run of
    # vertical interpenetration along the trace, its weighted point and angle, the frame
    # there with f shifted over the patch's own overlap, at the samples of the overlap
    # (the others formed when read); CONTACT's wheel profile coordinate of the point: the
    # wheel above it; its rolling radius: the wheel surface's along the contact normal
    # through it (where the rigid slip of the wheel is taken)
    frame = np.empty((5, N_S))
    rail, wheel = found.rail, found.wheel
    turn = float(turn)
    ((ok, u_ref, z_ref, gamma, overlap, wheel_s, lo, hi, i0, i1, kw, kr, eta_c, g_lo,
      height, weight, u_a, z_a, u_b, z_b), B, rail_y) = kernels.reference_patch(
        trace, g_min, increasing, approach, float(cp.rail_u), *rail[:4], *wheel,
        _S_SAMPLES, K0, _B_DENOMINATOR, WEIGHT_POWER, turn, *rail[8:],
        frame)
    if not ok:
        return None
    if rail_y != rail_y:  # NaN: the point is not finite (raises)
        found.track.rail_coordinate(u_ref, z_ref)
    # B for Hertz's estimates: the parabola with the overlap's depth and width (the origin
    # is the weighted centre, not the gap's minimum, where f'' may be anything), else f''
    # at the origin (Python's ``** 2``: the C library's pow)
    if hi - lo >= 5:
        B = overlap / (0.5 * ((_S_LIST[hi - 1] - _S_LIST[lo]) + _DS)) ** 2
    # what forms the other samples (:func:`_frame_arguments`)
    what = (trace[0], trace[2], trace[3], g_lo, approach, *rail[:2], *wheel[:5], u_ref,
            z_ref, gamma, eta_c, kw, kr, _S_SAMPLES, overlap)
    side = cp.side
    return ContactPoint(
        side=side, gap=approach - overlap / math.cos(gamma), wheel_s=wheel_s, rail_u=u_ref,
        rail_y=rail_y, position=(cp.position[0], SIDES[side] * u_ref, z_ref),
        contact_angle=gamma, rolling_radius=found.wheelset.radius + height,
        A=frame.item(1, K0), B=B if math.isfinite(B) else cp.B, s=_S_SAMPLES,
        approach=approach, rigid=cp,
        run=PatchRun(u_ref, gamma - turn, weight, (u_a, z_a), (u_b, z_b)),
        plane=TangentPlane(what, frame, i0, i1))


def patch_run(cp: ContactPoint) -> PatchRun | None:
    """What CONTACT's turning of neighbouring patches reads of a point formed by
    :func:`at_reference` (its reference point's lateral position, its weighted angle
    before any turn, its weight and the ends of its interpenetration on the rail); None
    for a rigid contact point."""
    return cp.run


def reference_offset(cp: ContactPoint) -> tuple[float, float]:
    """The offset (x, s) [m] of the frame of ``cp`` from its rigid contact point, in the
    rigid point's tangent plane: (0, 0) for a rigid contact point."""
    if cp.rigid is None:
        return (0.0, 0.0)
    rigid = samples(cp.rigid)
    ok = np.isfinite(rigid.rail_u_of_s)
    return (0.0, float(np.interp(cp.rail_u, rigid.rail_u_of_s[ok], rigid.s[ok])))


def _extend(plane: TangentPlane, a: int, b: int) -> np.ndarray:
    """The frame at the reference point of ``plane``, formed at its samples ``i0:i1``,
    formed also at ``a:b`` (the samples ``i0:i1`` as they were: a reader of those reads
    the same values); returns the frame."""
    frame, i0, i1 = plane.frame, plane.i0, plane.i1
    a, b = min(a, i0), max(b, i1)
    kernels.extend_frame(*plane.what, i0, i1, a, b, frame)
    plane.i0, plane.i1 = a, b
    return frame


def _frame_arguments(what: tuple) -> tuple:
    """The arguments of :func:`~.kernels.frame_samples` (before ``i0``) of a frame at the
    reference point, and its overlap: what :func:`at_reference` keeps (the trace lowered
    by the approach, ``(z - g_min) - approach``, the frame's point and plane), as it is."""
    return what


@dataclass(frozen=True)
class ReferencePoint:
    """CONTACT's contact reference point of a patch (SI units, side frame as
    :class:`ContactPoint`): the centre of the interpenetration area weighted by the squared
    interpenetration (CONTACT's ``m_wr_locatecp``, default gap weighting).

    Attributes
    ----------
    offset
        (x, y) of the point from the rigid contact point [m], in the rigid point's tangent
        plane (the patch frame of a patch solved there).
    position
        The point on the rail surface in the track frame (X, Y, Z) [m].
    rail_y, wheel_s
        Its rail and wheel profile coordinates [m].
    contact_angle
        The contact angle weighted as the point [rad].
    rolling_radius
        The wheel radius at ``wheel_s`` [m].
    """

    offset: tuple[float, float]
    position: tuple[float, float, float]
    rail_y: float
    wheel_s: float
    contact_angle: float
    rolling_radius: float


def reference_point(cp: ContactPoint, track: Track, ws: Wheelset, x: np.ndarray,
                    y: np.ndarray, interpenetration: np.ndarray) -> ReferencePoint | None:
    """The reference point of a patch from its undeformed interpenetration [m] at the
    element centres ``(x, y)`` [m] of its grid (patch frame; positive where the bodies
    overlap); None without interpenetration.

    ``x``, ``y`` and the contact angle ``gamma(y)`` of the rail surface are averaged with
    the weight ``interpenetration^2`` over the elements that overlap (CONTACT's
    ``compute_wgt_center``): the point where a patch that is not symmetric - a flange root
    - has its centre, rather than the point of first contact.
    """
    e = np.where(interpenetration > 0, interpenetration, 0.0)
    w = e * e
    total = float(w.sum())
    if not total > 0:
        return None
    full = samples(cp)
    xr = float((w * x).sum() / total)
    yr = float((w * y).sum() / total)
    ok = np.isfinite(full.rail_u_of_s)
    rail = track.side_rail
    gamma_s = np.arctan(rail.slope(np.where(ok, full.rail_u_of_s, cp.rail_u)))
    gamma = float((w * np.interp(y, full.s[ok], gamma_s[ok])).sum() / total)
    u = float(np.interp(yr, full.s[ok], full.rail_u_of_s[ok]))
    z = float(np.interp(yr, full.s[ok], full.rail_z_of_s[ok]))
    okw = np.isfinite(full.wheel_s_of_s)
    s_w = float(np.interp(yr, full.s[okw], full.wheel_s_of_s[okw]))
    sgn = SIDES[cp.side]
    offset = reference_offset(cp)
    return ReferencePoint(offset=(offset[0] + xr, offset[1] + yr),
                          position=(cp.position[0] + xr, sgn * u, z),
                          rail_y=track.rail_coordinate(u, z), wheel_s=s_w,
                          contact_angle=gamma,
                          rolling_radius=ws.radius + float(ws.wheel.height(s_w)))
