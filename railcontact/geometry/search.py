"""Contact search by the trace method, and the undeformed gap of each contact patch.

For a wheel with yaw ``psi`` the contact points lie on the *trace line*: the points of the
wheel surface whose normal has no component along the track (the rail is prismatic).
With the wheel surface ``(r sin t, eta, -r cos t)`` in the wheelset frame and
``r = r0 + F(S(eta))``, this gives ``sin t = -tan(psi) r'(eta)`` (``docs/algorithms.md`` 7.4;
Wang Kaiyun's trace method). The trace points are moved with the wheelset pose (roll after
yaw) into the side frame and compared with the placed rail: ``g(eta)`` is the vertical
distance from the rail to the wheel. For a rigid approach ``delta`` (vertical) every
connected interval of ``g - min g < delta`` is one contact patch, centred on its local
minimum of g: one-point or two-point (several-point) contact.

At each contact point the contact tangent plane is inclined by the contact angle
``gamma = atan(dZ_rail/du)`` (side frame: positive when the normal leans towards the track
centre, i.e. towards the flange). In that plane, with ``s`` across and ``x`` along the
track, the undeformed gap is taken as

    h(x, s) = f(s) + A(s) x^2,     A(s) = cos(beta(s)) / (2 r(s)),

``f(s)`` the distance between the profiles normal to the tangent plane (zero at the contact
point), ``r(s)`` the wheel radius and ``beta(s)`` the wheel profile angle there (Meusnier:
the wheel's curvature along the rolling direction; the rail is straight). ``A = A(0)`` and
``B = f''(0)/2`` are the curvatures Hertz needs. Yaw shifts the contact point along x (the
trace offset) but the gap is taken symmetric in x.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, field, fields

import numpy as np

from ..errors import RailContactError, check_positive
from ..halfspace.grid import Grid
from . import kernels
from .separation import PatchRun
from .track import SIDES, Pose, Track, Wheelset

N_TRACE = 6001
N_RAIL = 8001
"""Rail samples from which a patch's tangent-plane gap is interpolated."""
FAR = 1.0
"""Gap [m] given to elements beyond the profiles: far out of contact."""


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
    s, f, a_of_s
        Lateral coordinate in the tangent plane [m], normal gap f(s) [m] and A(s) [1/m]
        (samples around the contact point).
    wheel_s_of_s, rail_u_of_s, rail_z_of_s
        At the same samples: the wheel profile coordinate S [m] and the rail surface point
        (lateral u, vertical Z, side frame) [m] (NaN where the profiles end).
    approach, rigid, offset
        For a patch frame placed at the reference point (:func:`at_reference`): the vertical
        approach [m] it was formed at, the rigid contact point it was formed from, and its
        offset (x, s) [m] from that point in the rigid point's tangent plane; None, None,
        (0, 0) for the rigid contact point itself.

    A point may form some fields when they are first read (:func:`_formed_later`): a
    rigid contact point of :func:`contact_points` its tangent plane's samples (``A``,
    ``B``, ``s`` ... ``rail_z_of_s``) and its ``rail_y``, a point of :func:`at_reference`
    its ``offset`` and its samples ``f`` ... ``rail_z_of_s`` (formed first over the
    overlap only; :meth:`gap_on_grid` forms those its grid reads), which a time step in
    the frame at the reference point does not read.
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
    s: np.ndarray
    f: np.ndarray
    a_of_s: np.ndarray
    wheel_s_of_s: np.ndarray = field(repr=False)
    rail_u_of_s: np.ndarray = field(repr=False)
    rail_z_of_s: np.ndarray = field(repr=False)
    approach: float | None
    rigid: ContactPoint | None = field(repr=False)
    offset: tuple[float, float]

    def __getattr__(self, name: str):
        # called only for an attribute not set: a field formed later (_formed_later)
        later = self.__dict__.get("_later")
        if later is None or name not in later:
            raise AttributeError(f"'ContactPoint' object has no attribute {name!r}")
        values = later[name](self)  # (an error here leaves it to form later)
        for key, value in values.items():
            object.__setattr__(self, key, value)
        if "f" in values:  # the samples formed in full: no part is kept
            self.__dict__.pop("_part", None)
        later = self.__dict__.get("_later")  # (another reader may have formed some)
        rest = {} if later is None else {k: v for k, v in later.items() if k not in values}
        if rest:
            self.__dict__["_later"] = rest
        else:
            self.__dict__.pop("_later", None)
        return self.__dict__[name]

    def __getstate__(self) -> dict:
        while "_later" in self.__dict__:  # pickled with every field formed
            getattr(self, next(iter(self.__dict__["_later"])))
        return self.__dict__

    def normal_penetration(self, approach: float) -> float:
        """Normal penetration [m] of this patch for a vertical wheel approach [m]."""
        return max(approach - self.gap, 0.0) * math.cos(self.contact_angle)

    def gap_on_grid(self, grid: Grid) -> np.ndarray:
        """Undeformed gap h(x, y) = f(y) + A(y) x^2 at the element centres [m], with the
        grid's y along s. Where the profiles end (or fold away from this contact) the gap
        is :data:`FAR` - such elements can never touch."""
        out = np.empty((grid.nx, grid.ny))  # f and A depend on y alone: one compiled pass
        part = self.__dict__.get("_part")
        if part is None:
            kernels.gap_on_grid(self.s, self.f, self.a_of_s, float(grid.x0), float(grid.dx),
                                grid.nx, float(grid.y0), float(grid.dy), grid.ny, FAR, out)
            return out
        while True:  # a frame at the reference point formed over part of its samples
            frame, i0, i1, _ = part
            done, a, b = kernels.gap_on_grid_part(
                _S_SAMPLES, frame, i0, i1, float(grid.x0), float(grid.dx), grid.nx,
                float(grid.y0), float(grid.dy), grid.ny, FAR, out)
            if done:
                return out
            part = _extended(part, a, b)
            self.__dict__["_part"] = part

    def lateral_extent(self, delta: float, margin: float = 1.0) -> tuple[float, float]:
        """Interval of s around 0 where f(s) <= delta (times margin) [m] (paper Sec. 2.1)."""
        k0 = K0 if self.s is _S_SAMPLES else kernels.nearest(self.s, 0.0)
        lo, hi = kernels.lateral_extent(self.s, self.f, float(delta), k0)  # the run through k0
        ds = self.s[1] - self.s[0]
        a, b = self.s[lo] - ds, self.s[hi] + ds
        return margin * a, margin * b


def overlap_box(cp: ContactPoint, penetration: float,
                run: tuple[float, float] | None = None) -> tuple[float, float, float, float]:
    """The box (xmin, xmax, ymin, ymax) [m] in the patch's plane around its rigid
    overlap at the normal ``penetration`` [m]: the points ``(x, s)`` of the run of lateral
    samples through the origin where ``f(s) <= penetration`` (the run the cold potential
    area is formed on, :meth:`ContactPoint.lateral_extent`) with ``f(s) + A(s) x^2 <=
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
    d = cp.__dict__
    part = d.get("_part")
    while part is not None and "f" not in d:
        frame, i0, i1, _ = part
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
        part = _extended(part, max(a, 0), min(b, N_S))
        d["_part"] = part
    s, f = cp.s, cp.f
    k0 = K0 if s is _S_SAMPLES else kernels.nearest(s, 0.0)
    lo, hi = kernels.lobes_extent(f, cp.rail_u_of_s, penetration, k0, lo_u, hi_u)
    return _box(s, f, cp.a_of_s, lo, hi, penetration)


def run_on_rail(track: Track, ws: Wheelset, pose: Pose, side: str, approach: float,
                rail_u: float) -> tuple[float, float]:
    """The lateral positions on the rail [m] (side frame, as :attr:`ContactPoint.rail_u`)
    spanned by the run of the wheel's vertical overlap at the vertical ``approach`` [m]
    beyond first contact that holds (or lies nearest) the rail position ``rail_u`` [m]:
    the extent of one patch's rigid contact region (:func:`~.kernels.run_extent`)."""
    trace, g_min, _, _, _ = _trace_of_pose(track, ws, pose, side)
    return kernels.run_extent(trace[4], trace[2], g_min, float(approach), float(rail_u))


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
    reference point not yet read in full (:func:`at_reference`), over the part it formed
    (the patch's overlap and a margin), without forming the others."""
    d = cp.__dict__
    part = d.get("_part")
    if part is None or "f" in d:
        f, u = cp.f, cp.rail_u_of_s
    else:
        frame, i0, i1, _ = part
        f, u = frame[kernels.F, i0:i1], frame[kernels.RAIL_U, i0:i1]
    inside = (f < penetration) & np.isfinite(u)
    if not inside.any():
        return None
    return float(u[inside].min()), float(u[inside].max())


_FIELDS = frozenset(f.name for f in fields(ContactPoint))


_FRAME = frozenset({"A", "B", "s", "f", "a_of_s", "wheel_s_of_s", "rail_u_of_s", "rail_z_of_s"})
"""The fields of a rigid contact point formed when first read (its tangent frame)."""
_SAMPLES = frozenset({"f", "a_of_s", "wheel_s_of_s", "rail_u_of_s", "rail_z_of_s"})
"""The samples of a point at the reference point formed in full when first read."""


def _formed_later(later: dict[str, Callable[[ContactPoint], dict]], **now) -> ContactPoint:
    """A :class:`ContactPoint` with the fields ``now``; each other field ``name`` is
    formed by ``later[name](point)`` (which returns it and the others it forms, by name)
    when it is first read. (The point is passed, not held by the functions: a point that
    its own functions held would be a reference cycle, freed - with its arrays - only by
    the garbage collector.)"""
    if not (later.keys().isdisjoint(now) and len(later) + len(now) == len(_FIELDS)):
        raise TypeError("a ContactPoint needs each field once, now or formed later")
    cp = object.__new__(ContactPoint)
    cp.__dict__.update(now)
    cp.__dict__["_later"] = later
    return cp


def _wheel_samples(ws: Wheelset) -> tuple[np.ndarray, ...]:
    """The pose-independent part of a wheel's trace: axial positions eta, radii r and
    dr/deta at the :data:`N_TRACE` samples [m], computed once per wheelset (read-only)."""
    cached = ws.__dict__.get("_trace_samples")
    if cached is None:
        s_lo, s_hi = ws.wheel.bounds
        eta = ws.axial_position(np.linspace(s_lo + 1e-6, s_hi - 1e-6, N_TRACE))
        S = ws.profile_coordinate(eta)
        r = ws.radius + ws.wheel.height(S)
        dr = ws.wheel.slope(S)
        for a in (eta, r, dr):
            a.flags.writeable = False
        cached = (eta, r, dr)
        object.__setattr__(ws, "_trace_samples", cached)  # a cache on a frozen record
    return cached


def vertical_gap(track: Track, ws: Wheelset, pose: Pose, side: str):
    """Vertical gap g(eta) between the wheel trace and the rail [m], with the trace points.

    Returns ``(eta, x, u, z, g)`` restricted to trace points above the rail.
    """
    return tuple(_trace(track, ws, pose, side)[0])


def _trace(track: Track, ws: Wheelset, pose: Pose, side: str):
    """:func:`vertical_gap` (one compiled pass, :func:`~.kernels.trace_gap`) as one array
    (5, n), with the least gap, its first sample, whether the trace's u increase and how
    many samples have the least gap."""
    if side not in SIDES:
        raise RailContactError(f"side must be 'left' or 'right', got {side!r}")
    sgn = SIDES[side]
    psi, phi = sgn * pose.yaw, sgn * pose.roll
    eta, r, dr = _wheel_samples(ws)
    out = np.empty((5, eta.size))
    n, g_min, k, increasing, ties = kernels.trace_gap(
        eta, r, dr, psi != 0.0, math.tan(psi), math.cos(psi), math.sin(psi), math.cos(phi),
        math.sin(phi), float(sgn * pose.lateral), float(ws.radius), *_rail_arrays(track)[4:],
        out)
    if n < 10:
        raise RailContactError(f"{side} wheel is beside its rail (lateral displacement "
                               f"{pose.lateral:g} m is beyond the profiles)")
    return out[:, :n], g_min, k, increasing, ties


def contact_points(track: Track, ws: Wheelset, pose: Pose, side: str,
                   approach: float = 0.0) -> list[ContactPoint]:
    """Contact patches of one wheel for a vertical rigid approach ``approach`` [m].

    ``approach = 0`` gives the first point of contact only. Patches are ordered by gap
    (the first one has gap 0).
    """
    approach = check_positive("approach", approach, "m", allow_zero=True)
    # a load iteration asks again for the same wheel's first contact
    last = getattr(_memo, "points", None)
    if (last is not None and last[0] is track and last[1] is ws
            and (last[2] is pose or last[2] == pose) and last[3] == side
            and last[4] == approach):
        return list(last[5])
    trace, g_min, k, _, ties = _trace_of_pose(track, ws, pose, side)
    wheel = _wheel_arrays(ws)
    rail = _rail_arrays(track)[2:4]
    if approach == 0.0 and ties == 1 and math.isfinite(g_min):
        # first contact: the least gap's sample is the only one at most 0 above it, so
        # its run is that sample alone (rigid_points' scans of the trace find the same)
        rows = [kernels.rigid_point(trace[0], trace[1], trace[2], trace[4], g_min, k, k + 1,
                                    *rail, *wheel[:2], *wheel[3:])]
    else:
        rows = kernels.rigid_points(trace, g_min, k, float(approach), *rail, *wheel[:2],
                                    *wheel[3:]).tolist()
    points = [_point(track, ws, side, trace, g_min, row) for row in rows]
    if len(points) > 1:
        points.sort(key=lambda c: c.gap)
    _memo.points = (track, ws, pose, side, approach, tuple(points))
    return points


_memo = threading.local()
"""This thread's memory of the search: ``points``, the last call of :func:`contact_points`
(its arguments and points), ``traces``, the last trace of :func:`_trace_of_pose` of
each side (track, wheelset, pose, trace), and ``merges``, the last
:func:`merge_approaches` of each side (the trace, ``min_lobe``, the approaches). Per
thread, so that wheelsets stepping on several threads neither share nor evict each
other's memory."""


def forget(traces: bool = True) -> None:
    """Clear this thread's memory of the last pose: the last :func:`contact_points` and,
    with ``traces``, the last trace of each side."""
    _memo.points = None
    if traces:
        _memo.traces = {}
        _memo.merges = {}


def count_contacts(track: Track, ws: Wheelset, pose: Pose, side: str,
                   approach: float = 0.0) -> int:
    """The number of patches :func:`contact_points` finds, without their geometry."""
    approach = check_positive("approach", approach, "m", allow_zero=True)
    trace, g_min, k, _, _ = _trace_of_pose(track, ws, pose, side)
    return kernels.count_runs(trace[4], g_min, k, float(approach))


def _trace_of_pose(track: Track, ws: Wheelset, pose: Pose, side: str):
    """:func:`_trace`, remembered for the last (track, wheelset, pose) of each side: a load
    iteration asks for the same wheel's contact several times, and the rigid wheelset's
    search for both wheels' least gaps after solving them (:func:`least_gap`)."""
    traces = getattr(_memo, "traces", None)
    if traces is None:
        traces = _memo.traces = {}
    last = traces.get(side)  # (a step passes one pose to every call: identity first)
    if (last is not None and last[0] is track and last[1] is ws
            and (last[2] is pose or last[2] == pose)):
        return last[3]
    out = _trace(track, ws, pose, side)
    out[0].flags.writeable = False  # (its rows too)
    traces[side] = (track, ws, pose, out)
    return out


def merge_approaches(track: Track, ws: Wheelset, pose: Pose, side: str,
                     min_lobe: float = 0.0) -> np.ndarray:
    """The vertical approaches [m] beyond first contact at which two of the wheel's rigid
    contact regions (runs of :func:`contact_points`) join into one patch, increasing: the
    saddles of the trace's gap (:func:`~.kernels.saddles`) whose shallower lobe is at least
    ``min_lobe`` times the saddle's approach deep (a lobe shallower than that is a ripple
    of the profiles: its run carries little of the load). Remembered, read-only, for the
    last trace of each side (:data:`_memo`)."""
    traced = _trace_of_pose(track, ws, pose, side)
    merges = getattr(_memo, "merges", None)
    if merges is None:
        merges = _memo.merges = {}
    last = merges.get(side)  # (a step asks once in the wheel's solve and once after it)
    if last is not None and last[0] is traced and last[1] == min_lobe:
        return last[2]
    trace, g_min, _, _, _ = traced
    s = kernels.saddles(trace[4], g_min)
    keep = s[:, 1] >= min_lobe * s[:, 0]
    out = np.sort(s[keep, 0])
    out.flags.writeable = False
    merges[side] = (traced, min_lobe, out)
    return out


def least_gap(track: Track, ws: Wheelset, pose: Pose, side: str) -> float:
    """The least vertical gap [m] of the wheel's trace above its rail (the least of
    :func:`vertical_gap`'s ``g``), from the trace the search remembers for the pose."""
    return float(_trace_of_pose(track, ws, pose, side)[1])


def _rail_arrays(track: Track) -> tuple[np.ndarray, ...]:
    """The placed rail as the kernels read it: :data:`N_RAIL` samples (u, Z) and its
    spline's breakpoints and coefficients, then its extent (lo, hi) [m] and the same
    breakpoints and coefficients (computed once per track; read-only)."""
    cached = track.__dict__.get("_kernel_arrays")
    if cached is None:
        rail = track.side_rail
        cached = (*rail.samples(N_RAIL), *rail._pieces, *rail.bounds, *rail._pieces)
        object.__setattr__(track, "_kernel_arrays", cached)  # a cache on a frozen record
    return cached


def _wheel_arrays(ws: Wheelset) -> tuple:
    """The wheel as the kernels read it: its spline's breakpoints and coefficients, the
    nominal radius [m], and ``back_to_back / 2``, ``flange_back`` [m] (profile coordinate
    S = eta - back_to_back / 2 + flange_back, :meth:`Wheelset.profile_coordinate`);
    formed once per wheelset."""
    cached = ws.__dict__.get("_kernel_arrays")
    if cached is None:
        cached = (*ws.wheel._pieces, float(ws.radius), ws.back_to_back / 2,
                  float(ws.flange_back))
        object.__setattr__(ws, "_kernel_arrays", cached)  # a cache on a frozen record
    return cached


def _point(track, ws, side, trace, g_min, row) -> ContactPoint:
    """The rigid contact point ``row`` of :func:`~.kernels.rigid_points` (a run of the
    trace: its least gap above ``g_min``, refined by a parabola through three samples),
    its tangent frame formed when first read (:func:`~.kernels.rigid_frame`)."""
    eta_c, x_c, u_c, z_rail, gap_c, gamma, s_c, dr = row

    def frame(_: ContactPoint) -> dict:
        out = np.empty((5, N_S))
        kernels.rigid_frame(trace[0], trace[2], trace[3], g_min, *_rail_arrays(track)[:2],
                            *_wheel_arrays(ws), u_c, z_rail, gamma, eta_c, _S_SAMPLES, K0,
                            out)
        f, a_of_s, wheel_s_of_s, rail_u_of_s, rail_z_of_s = out
        return dict(A=float(a_of_s[K0]), B=_lateral_curvature(_S_SAMPLES, f), s=_S_SAMPLES,
                    f=f, a_of_s=a_of_s, wheel_s_of_s=wheel_s_of_s, rail_u_of_s=rail_u_of_s,
                    rail_z_of_s=rail_z_of_s)

    def rail_y(_: ContactPoint) -> dict:
        return dict(rail_y=track.rail_coordinate(u_c, z_rail))

    later = dict.fromkeys(_FRAME, frame)
    later["rail_y"] = rail_y
    return _formed_later(later, side=side, gap=gap_c,
                         wheel_s=s_c, rail_u=u_c, position=(x_c, SIDES[side] * u_c, z_rail),
                         contact_angle=gamma, rolling_radius=ws.radius + dr, approach=None,
                         rigid=None, offset=(0.0, 0.0))


HALF_WIDTH = 0.025
"""Half width [m] of the lateral samples of a patch's tangent plane."""
N_S = 1001
"""Lateral samples of a patch's tangent plane (0.05 mm apart)."""
K0 = N_S // 2
"""The sample at the patch origin, s = 0."""
_S_SAMPLES = np.linspace(-HALF_WIDTH, HALF_WIDTH, N_S)
_S_SAMPLES.flags.writeable = False
_DS = float(_S_SAMPLES[1] - _S_SAMPLES[0])


WEIGHT_POWER = 2.5
"""The reference point's weight is the vertical interpenetration to this power: its square
integrated along the track over the overlap ``e - x^2 / (2 r)`` gives ``e^(5/2)``
(CONTACT's default gap weighting; with 2.5 the points and angles of CONTACT's 34 cases are
matched to 0.01 mm and 0.001 rad, with 2 or 3 not)."""


def _lateral_curvature(s: np.ndarray, f: np.ndarray) -> float:
    """B = f''(0) / 2 [1/m] from samples 5 apart; NaN where it is not positive or the
    gap is not finite there (a profile's end: no convex contact, which the caller says)."""
    lo, mid, hi = float(f[K0 - 5]), float(f[K0]), float(f[K0 + 5])
    if not (math.isfinite(lo) and math.isfinite(mid) and math.isfinite(hi)):
        return float("nan")
    B = (lo - 2 * mid + hi) / (2 * float(s[5] - s[0]) ** 2)
    return B if math.isfinite(B) and B > 0 else float("nan")


def at_reference(cp: ContactPoint, track: Track, ws: Wheelset, pose: Pose,
                 approach: float, turn: float = 0.0) -> ContactPoint | None:
    """The patch of the rigid contact point ``cp`` with its frame at CONTACT's contact
    reference point, for the wheel's vertical approach ``approach`` [m] beyond first
    contact, formed as CONTACT's ``m_wr_locatecp`` does (None when the wheel does not
    overlap the rail there).

    Along the trace, the wheel lowered by ``approach`` overlaps the rail by the vertical
    interpenetration ``e(u)`` over the patch's own run (around ``cp``). The reference point
    is the rail surface at the lateral position ``u`` averaged with the weight
    ``e^`` :data:`WEIGHT_POWER`, and the contact angle is the rail's inclination averaged
    the same way. The new frame's origin is that point, its plane inclined at that angle;
    the gap ``f(s)`` across it is the normal distance of the lowered wheel from the rail,
    shifted so that its least value is 0, and the patch's ``gap`` is set so that
    :meth:`ContactPoint.normal_penetration` of ``approach`` is the overlap there. The wheel
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
    trace, g_min, _, increasing, _ = _trace_of_pose(track, ws, pose, cp.side)
    # one compiled pass (:func:`~.kernels.reference_frame`): the patch's own run of
    # vertical interpenetration along the trace, its weighted point and angle, the frame
    # there with f shifted over the patch's own overlap, at the samples of the overlap
    # (the others formed when read); CONTACT's wheel profile coordinate of the point: the
    # wheel above it; its rolling radius: the wheel surface's along the contact normal
    # through it (where the rigid slip of the wheel is taken)
    frame = np.empty((5, N_S))
    rail, wheel = _rail_arrays(track), _wheel_arrays(ws)
    (ok, u_ref, z_ref, gamma, overlap, wheel_s, lo, hi, i0, i1, kw, kr, eta_c, g_lo,
     height, weight, u_a, z_a, u_b, z_b) = kernels.reference_frame(
        trace, g_min, increasing, approach, float(cp.rail_u), *rail[:4], *wheel, _S_SAMPLES,
        K0, WEIGHT_POWER, float(turn), frame)
    if not ok:
        return None
    s = _S_SAMPLES
    # B for Hertz's estimates: the parabola with the overlap's depth and width (the origin
    # is the weighted centre, not the gap's minimum, where f'' may be anything)
    width = float(s[hi - 1] - s[lo]) + _DS  # s increases
    B = overlap / (0.5 * width) ** 2 if hi - lo >= 5 else _lateral_curvature(s, frame[0])
    # what forms the other samples (:func:`_frame_arguments`)
    part = (frame, i0, i1, (trace, rail, wheel, g_lo, approach, u_ref, z_ref, gamma, eta_c,
                            kw, kr, overlap))

    def offset(_: ContactPoint) -> dict:  # the point in the rigid point's frame (when read)
        ok = np.isfinite(cp.rail_u_of_s)
        return dict(offset=(0.0, float(np.interp(u_ref, cp.rail_u_of_s[ok], cp.s[ok]))))

    def samples(ref: ContactPoint) -> dict:  # all the samples (formed when read)
        f, a_of_s, wheel_s_of_s, rail_u_of_s, rail_z_of_s = _extended(
            ref.__dict__.get("_part", part), 0, N_S)[0]
        return dict(f=f, a_of_s=a_of_s, wheel_s_of_s=wheel_s_of_s, rail_u_of_s=rail_u_of_s,
                    rail_z_of_s=rail_z_of_s)

    later = dict.fromkeys(_SAMPLES, samples)
    later["offset"] = offset
    ref = _formed_later(
        later, side=cp.side,
        gap=approach - overlap / math.cos(gamma), wheel_s=wheel_s, rail_u=u_ref,
        rail_y=track.rail_coordinate(u_ref, z_ref),
        position=(cp.position[0], SIDES[cp.side] * u_ref, z_ref), contact_angle=gamma,
        rolling_radius=ws.radius + height, A=float(frame[1, K0]),
        B=B if math.isfinite(B) else cp.B, s=s, approach=approach, rigid=cp)
    ref.__dict__["_part"] = part
    ref.__dict__["_run"] = PatchRun(u=u_ref, angle=gamma - float(turn), weight=weight,
                                    low_end=(u_a, z_a), high_end=(u_b, z_b))
    return ref


def patch_run(cp: ContactPoint) -> PatchRun | None:
    """What CONTACT's turning of neighbouring patches reads of a point formed by
    :func:`at_reference` (its reference point's lateral position, its weighted angle
    before any turn, its weight and the ends of its interpenetration on the rail); None
    for a rigid contact point."""
    return cp.__dict__.get("_run")


def _extended(part: tuple, a: int, b: int) -> tuple:
    """A frame at the reference point formed at the samples ``i0:i1`` (``part``: the
    frame (5, N_S), i0, i1 and what forms the others), formed also at ``a:b`` (the samples
    ``i0:i1`` as they were: a reader of the old ``part`` reads the same values)."""
    frame, i0, i1, what = part
    a, b = min(a, i0), max(b, i1)
    kernels.extend_frame(*_frame_arguments(what), i0, i1, a, b, frame)
    return frame, a, b, what


def _frame_arguments(what: tuple) -> tuple:
    """The arguments of :func:`~.kernels.frame_samples` (before ``i0``) of a frame at the
    reference point, and its overlap, from what :func:`at_reference` keeps: the trace
    lowered by the approach (``(z - g_min) - approach``), the frame's point and plane."""
    trace, rail, wheel, g_min, approach, u_ref, z_ref, gamma, eta_c, kw, kr, overlap = what
    return (trace[0], trace[2], trace[3], g_min, approach, *rail[:2], *wheel[:5], u_ref,
            z_ref, gamma, eta_c, kw, kr, _S_SAMPLES, overlap)


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
    if not total > 0 or cp.rail_u_of_s is None:
        return None
    xr = float((w * x).sum() / total)
    yr = float((w * y).sum() / total)
    ok = np.isfinite(cp.rail_u_of_s)
    rail = track.side_rail
    gamma_s = np.arctan(rail.slope(np.where(ok, cp.rail_u_of_s, cp.rail_u)))
    gamma = float((w * np.interp(y, cp.s[ok], gamma_s[ok])).sum() / total)
    u = float(np.interp(yr, cp.s[ok], cp.rail_u_of_s[ok]))
    z = float(np.interp(yr, cp.s[ok], cp.rail_z_of_s[ok]))
    okw = np.isfinite(cp.wheel_s_of_s)
    s_w = float(np.interp(yr, cp.s[okw], cp.wheel_s_of_s[okw]))
    sgn = SIDES[cp.side]
    return ReferencePoint(offset=(cp.offset[0] + xr, cp.offset[1] + yr),
                          position=(cp.position[0] + xr, sgn * u, z),
                          rail_y=track.rail_coordinate(u, z), wheel_s=s_w,
                          contact_angle=gamma,
                          rolling_radius=ws.radius + float(ws.wheel.height(s_w)))
