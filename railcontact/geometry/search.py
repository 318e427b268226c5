"""Contact search by the trace method, and the undeformed gap of each contact patch.

For a wheel with yaw ``psi`` the contact points lie on the *trace line*: the points of the
wheel surface whose normal has no component along the track (the rail is prismatic).
With the wheel surface ``(r sin t, eta, -r cos t)`` in the wheelset frame and
``r = r0 + F(S(eta))``, this gives ``sin t = -tan(psi) r'(eta)`` (``algorithms.md`` 7.4;
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
from dataclasses import dataclass, field

import numpy as np

try:
    import numba
except ImportError:  # pragma: no cover
    numba = None

from ..errors import RailContactError, check_positive
from ..halfspace.grid import Grid
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
    wheel_s_of_s: np.ndarray | None = field(default=None, repr=False)
    rail_u_of_s: np.ndarray | None = field(default=None, repr=False)
    rail_z_of_s: np.ndarray | None = field(default=None, repr=False)
    approach: float | None = None
    rigid: ContactPoint | None = field(default=None, repr=False)
    offset: tuple[float, float] = (0.0, 0.0)

    def normal_penetration(self, approach: float) -> float:
        """Normal penetration [m] of this patch for a vertical wheel approach [m]."""
        return max(approach - self.gap, 0.0) * math.cos(self.contact_angle)

    def gap_on_grid(self, grid: Grid) -> np.ndarray:
        """Undeformed gap h(x, y) = f(y) + A(y) x^2 at the element centres [m], with the
        grid's y along s. Where the profiles end (or fold away from this contact) the gap
        is :data:`FAR` - such elements can never touch."""
        y = grid.y  # f and A depend on y alone: interpolated per column
        f = np.interp(y, self.s, self.f, left=FAR, right=FAR)
        a = np.interp(y, self.s, np.where(np.isfinite(self.a_of_s), self.a_of_s, 0.0))
        h = f[None, :] + a[None, :] * grid.x[:, None] ** 2
        return np.where(np.isfinite(h), h, FAR)

    def lateral_extent(self, delta: float, margin: float = 1.0) -> tuple[float, float]:
        """Interval of s around 0 where f(s) <= delta (times margin) [m] (paper Sec. 2.1)."""
        k0 = int(np.argmin(np.abs(self.s)))
        inside = self.f <= delta
        inside[k0] = True
        outside = np.flatnonzero(~inside)
        i = int(np.searchsorted(outside, k0))  # the run of samples inside through k0
        lo = int(outside[i - 1]) + 1 if i > 0 else 0
        hi = int(outside[i]) - 1 if i < outside.size else len(self.s) - 1
        ds = self.s[1] - self.s[0]
        a, b = self.s[lo] - ds, self.s[hi] + ds
        return margin * a, margin * b


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


def _trace_on_rail(eta, r, dr, yawed, tan_psi, cz, sz, cx, sx, u_ws, radius, lo, hi, out):
    """Trace points of one wheel moved into the side frame (yaw about the vertical axis,
    then roll about the track axis), those with ``lo < u < hi`` (above the rail) written
    to ``out`` (4, n): eta, X, u, Z; returns how many."""
    m = 0
    for i in range(eta.size):
        if yawed:
            sin_t = min(max(-tan_psi * dr[i], -1.0), 1.0)
            rc = r[i] * math.sqrt(1.0 - sin_t * sin_t)
            rs = r[i] * sin_t
            x = cz * rs - sz * eta[i]
            y = sz * rs + cz * eta[i]
            zw = -rc
        else:  # no yaw: the trace is the wheel's lowest line (sin t = 0)
            x = 0.0
            y = eta[i]
            zw = -r[i]
        u = cx * y - sx * zw + u_ws
        if lo < u < hi:
            out[0, m] = eta[i]
            out[1, m] = x
            out[2, m] = u
            out[3, m] = sx * y + cx * zw + radius
            m += 1
    return m


_trace_on_rail_numba = (numba.njit(cache=True)(_trace_on_rail) if numba is not None
                        else _trace_on_rail)


def vertical_gap(track: Track, ws: Wheelset, pose: Pose, side: str):
    """Vertical gap g(eta) between the wheel trace and the rail [m], with the trace points.

    Returns ``(eta, x, u, z, g)`` restricted to trace points above the rail.
    """
    if side not in SIDES:
        raise RailContactError(f"side must be 'left' or 'right', got {side!r}")
    sgn = SIDES[side]
    psi, phi = sgn * pose.yaw, sgn * pose.roll
    eta, r, dr = _wheel_samples(ws)
    rail = track.side_rail
    lo, hi = rail.bounds
    out = np.empty((4, eta.size))
    n = _trace_on_rail_numba(eta, r, dr, psi != 0.0, math.tan(psi), math.cos(psi),
                             math.sin(psi), math.cos(phi), math.sin(phi),
                             float(sgn * pose.lateral), float(ws.radius), lo, hi, out)
    if n < 10:
        raise RailContactError(f"{side} wheel is beside its rail (lateral displacement "
                               f"{pose.lateral:g} m is beyond the profiles)")
    eta, x, u, z = out[:, :n]
    return eta, x, u, z, z - rail.height(u)


def contact_points(track: Track, ws: Wheelset, pose: Pose, side: str,
                   approach: float = 0.0) -> list[ContactPoint]:
    """Contact patches of one wheel for a vertical rigid approach ``approach`` [m].

    ``approach = 0`` gives the first point of contact only. Patches are ordered by gap
    (the first one has gap 0).
    """
    approach = check_positive("approach", approach, "m", allow_zero=True)
    last = _LAST_POINTS[0]  # a load iteration asks again for the same wheel's first contact
    if (last is not None and last[0] is track and last[1] is ws and last[2] == pose
            and last[3] == side and last[4] == approach):
        return list(last[5])
    eta, x, u, z, g = _vertical_gap_of_pose(track, ws, pose, side)
    g_min = g.min()
    g = g - g_min
    z = z - g_min  # the wheel lowered (or lifted) into first contact
    points = [_point(track, ws, pose, side, eta, x, u, z, g, a + int(np.argmin(g[a:b])))
              for a, b in _intervals(g, approach)]
    points.sort(key=lambda c: c.gap)
    _LAST_POINTS[0] = (track, ws, pose, side, approach, tuple(points))
    return points


_LAST_POINTS: list = [None]
"""The last call of :func:`contact_points` (its arguments and points)."""


def count_contacts(track: Track, ws: Wheelset, pose: Pose, side: str,
                   approach: float = 0.0) -> int:
    """The number of patches :func:`contact_points` finds, without their geometry."""
    approach = check_positive("approach", approach, "m", allow_zero=True)
    g = _vertical_gap_of_pose(track, ws, pose, side)[4]
    return len(_intervals(g - g.min(), approach))


def _intervals(g: np.ndarray, approach: float) -> list[tuple[int, int]]:
    """Index ranges [a, b) of the connected intervals where the gap above first contact
    ``g`` is at most ``approach``; the global minimum is always in one."""
    inside = g <= max(approach, 0.0)
    inside[int(np.argmin(g))] = True
    edges = (np.flatnonzero(inside[1:] != inside[:-1]) + 1).tolist()  # where runs change
    if inside[0]:
        edges.insert(0, 0)
    if inside[-1]:
        edges.append(len(inside))
    return list(zip(edges[::2], edges[1::2], strict=True))


_LAST_GAP: list = [None]


def _vertical_gap_of_pose(track: Track, ws: Wheelset, pose: Pose, side: str):
    """:func:`vertical_gap`, remembered for the last (track, wheelset, pose, side): a load
    iteration asks for the same wheel's contact several times."""
    last = _LAST_GAP[0]
    if (last is not None and last[0] is track and last[1] is ws and last[2] == pose
            and last[3] == side):
        return last[4]
    out = vertical_gap(track, ws, pose, side)
    for a in out:
        a.flags.writeable = False
    _LAST_GAP[0] = (track, ws, pose, side, out)
    return out


def _point(track, ws, pose, side, eta, x, u, z, g, k) -> ContactPoint:
    rail = track.side_rail
    sgn = SIDES[side]
    # refine the minimum with a parabola through three samples
    if 0 < k < len(g) - 1:
        d = g[k - 1] - 2 * g[k] + g[k + 1]
        t = 0.5 * (g[k - 1] - g[k + 1]) / d if d > 0 else 0.0
    else:
        t = 0.0
    t = float(np.clip(t, -1, 1))
    j = k + (1 if t > 0 else -1) if 0 < k < len(g) - 1 else k
    w = abs(t)

    def lerp(a):
        return float((1 - w) * a[k] + w * a[j])

    eta_c, x_c, u_c, z_rail = lerp(eta), lerp(x), lerp(u), float(rail.height(lerp(u)))
    gap_c = max(float(lerp(g)), 0.0)
    gamma = math.atan(float(rail.slope(u_c)))
    s_c = float(ws.profile_coordinate(eta_c))
    r_c = ws.radius + float(ws.wheel.height(s_c))
    s, f, a_of_s, wheel_s_of_s, rail_u_of_s, rail_z_of_s = _tangent_frame(
        track, ws, eta, u, z, u_c, z_rail, gamma, eta_c)
    f = f - np.nanmin(f[np.abs(s) < 1e-3]) if np.isfinite(f[K0]) else f
    f = np.where(np.isfinite(f), f, np.inf)
    return ContactPoint(side=side, gap=gap_c, wheel_s=s_c, rail_u=u_c,
                        rail_y=track.rail_coordinate(u_c, z_rail),
                        position=(x_c, sgn * u_c, z_rail),
                        contact_angle=gamma, rolling_radius=r_c, A=float(a_of_s[K0]),
                        B=_lateral_curvature(s, f), s=s, f=f, a_of_s=a_of_s,
                        wheel_s_of_s=wheel_s_of_s, rail_u_of_s=rail_u_of_s,
                        rail_z_of_s=rail_z_of_s)


HALF_WIDTH = 0.025
"""Half width [m] of the lateral samples of a patch's tangent plane."""
N_S = 1001
"""Lateral samples of a patch's tangent plane (0.05 mm apart)."""
K0 = N_S // 2
"""The sample at the patch origin, s = 0."""
_S_SAMPLES = np.linspace(-HALF_WIDTH, HALF_WIDTH, N_S)
_S_SAMPLES.flags.writeable = False


def _tangent_frame(track: Track, ws: Wheelset, eta: np.ndarray, u: np.ndarray,
                   z: np.ndarray, u_c: float, z_c: float, gamma: float, eta_c: float):
    """Both profiles in the tangent plane through the rail point ``(u_c, z_c)`` (side frame)
    inclined at ``gamma``: at the samples ``s`` across the plane, the distance ``f(s)`` of
    the wheel (trace points ``eta, u, z``) above the rail normal to the plane [m] (negative
    where they overlap; NaN where the profiles end), ``A(s)`` [1/m], the wheel profile
    coordinate and the rail surface point (u, Z) [m] there.

    Each profile is taken along its branch through the point nearest ``u_c`` on which s
    increases (:func:`_branch`); :func:`_in_plane` rotates and interpolates in one compiled
    pass over the samples between the ``s``."""
    rail = track.side_rail
    cg, sg = math.cos(gamma), math.sin(gamma)
    ur, zr = rail.samples(N_RAIL)
    s = _S_SAMPLES
    kw = int(np.argmin(np.abs(u - u_c)))
    kr = int(np.argmin(np.abs(ur - u_c)))
    n_w, eta_s, _ = _in_plane(s, u, z, eta, eta, u_c, z_c, cg, sg, kw)
    n_r, ur_s, zr_s = _in_plane(s, ur, zr, ur, zr, u_c, z_c, cg, sg, kr)
    f = n_w - n_r
    # A(s) from the wheel at the same s
    S_s = ws.profile_coordinate(np.where(np.isfinite(eta_s), eta_s, eta_c))
    beta = np.arctan(ws.wheel.slope(S_s))
    a_of_s = np.cos(beta) / (2 * (ws.radius + ws.wheel.height(S_s)))
    return (s, f, a_of_s, np.where(np.isfinite(eta_s), S_s, np.nan), ur_s, zr_s)


def _in_plane(s: np.ndarray, u: np.ndarray, z: np.ndarray, a: np.ndarray, b: np.ndarray,
              u_c: float, z_c: float, cg: float, sg: float, k: int) -> np.ndarray:
    """Along the branch through sample ``k`` of the curve (u, z) on which its coordinate
    s' = (u - u_c) cg + (z - z_c) sg increases (:func:`_branch`), the curve's distance
    n = -(u - u_c) sg + (z - z_c) cg from the plane and the quantities ``a`` and ``b`` at
    its samples, linearly interpolated at the increasing ``s`` [m] (NaN off the branch) as
    :func:`np.interp` does on the branch; only the points between the ``s`` are rotated.
    Returns (3, len(s)): n, a, b."""
    out = np.empty((3, s.size))
    _interp_in_plane_numba(s, u, z, a, b, float(u_c), float(z_c), float(cg), float(sg),
                           int(k), out)
    return out


def _interp_in_plane(s, u, z, a, b, u_c, z_c, cg, sg, k, out):
    """:func:`_in_plane`'s loop (``out`` filled)."""
    n = u.size
    lo = k  # the samples of the branch that bracket s: lo ... hi
    s_lo = (u[k] - u_c) * cg + (z[k] - z_c) * sg
    s_k = s_lo
    while lo > 0 and s_lo > s[0]:
        s_prev = (u[lo - 1] - u_c) * cg + (z[lo - 1] - z_c) * sg
        if not s_prev < s_lo:  # the branch ends: s' stops increasing towards k
            break
        lo -= 1
        s_lo = s_prev
    hi = k
    s_hi = s_k
    while hi < n - 1 and s_hi < s[s.size - 1]:
        s_next = (u[hi + 1] - u_c) * cg + (z[hi + 1] - z_c) * sg
        if not s_next > s_hi:
            break
        hi += 1
        s_hi = s_next
    j = lo
    x0 = s_lo
    x1 = (u[j + 1] - u_c) * cg + (z[j + 1] - z_c) * sg if hi > lo else s_lo
    for i in range(s.size):
        x = s[i]
        if hi == lo or x < s_lo or x > s_hi:
            out[0, i] = math.nan
            out[1, i] = math.nan
            out[2, i] = math.nan
            continue
        while j < hi - 1 and x1 <= x:  # the segment [x0, x1) that holds x
            j += 1
            x0 = x1
            x1 = (u[j + 1] - u_c) * cg + (z[j + 1] - z_c) * sg
        t = (x - x0) / (x1 - x0)
        n0 = -(u[j] - u_c) * sg + (z[j] - z_c) * cg
        n1 = -(u[j + 1] - u_c) * sg + (z[j + 1] - z_c) * cg
        out[0, i] = n0 + t * (n1 - n0)
        out[1, i] = a[j] + t * (a[j + 1] - a[j])
        out[2, i] = b[j] + t * (b[j + 1] - b[j])


_interp_in_plane_numba = (numba.njit(cache=True)(_interp_in_plane) if numba is not None
                          else _interp_in_plane)


WEIGHT_POWER = 2.5
"""The reference point's weight is the vertical interpenetration to this power: its square
integrated along the track over the overlap ``e - x^2 / (2 r)`` gives ``e^(5/2)``
(CONTACT's default gap weighting; with 2.5 the points and angles of CONTACT's 34 cases are
matched to 0.01 mm and 0.001 rad, with 2 or 3 not)."""


def _run_bounds(mask, k):
    """``(lo, hi)``: the connected run ``mask[lo:hi]`` of True that holds sample ``k``
    (``lo == hi`` when ``mask[k]`` is False)."""
    if not mask[k]:
        return k, k
    lo = k
    while lo > 0 and mask[lo - 1]:
        lo -= 1
    hi = k + 1
    while hi < mask.size and mask[hi]:
        hi += 1
    return lo, hi


_run_bounds_numba = (numba.njit(cache=True)(_run_bounds) if numba is not None
                     else _run_bounds)


def _overlap_run(g, u, approach, u_c):
    """On the trace (vertical gaps ``g`` at lateral positions ``u``) of a wheel lowered by
    ``approach`` beyond first contact: ``(g_min, lo, hi)``, the least gap and the run
    ``lo:hi`` of positive vertical interpenetration ``approach - (g - g_min)`` that holds
    the sample nearest ``u_c`` (``lo == hi`` when that sample does not overlap) - the masks
    of :func:`_around` in one pass."""
    n = g.size
    g_min = g[0]
    k = 0
    best = abs(u[0] - u_c)
    for i in range(1, n):
        if g[i] < g_min:
            g_min = g[i]
        d = abs(u[i] - u_c)
        if d < best:
            best = d
            k = i
    if not approach - (g[k] - g_min) > 0:
        return g_min, k, k
    lo = k
    while lo > 0 and approach - (g[lo - 1] - g_min) > 0:
        lo -= 1
    hi = k + 1
    while hi < n and approach - (g[hi] - g_min) > 0:
        hi += 1
    return g_min, lo, hi


def _nearest(u, u_c):
    """The index of the sample of ``u`` nearest ``u_c`` (the first of equals)."""
    k = 0
    best = abs(u[0] - u_c)
    for i in range(1, u.size):
        d = abs(u[i] - u_c)
        if d < best:
            best = d
            k = i
    return k


_overlap_run_numba = (numba.njit(cache=True)(_overlap_run) if numba is not None
                      else _overlap_run)
_nearest_numba = numba.njit(cache=True)(_nearest) if numba is not None else _nearest


def _around(mask: np.ndarray, k: int) -> np.ndarray:
    """The connected run of ``mask`` that holds sample ``k`` (all False when it does not):
    a patch's own interpenetration, not a neighbour's."""
    out = np.zeros_like(mask)
    lo, hi = _run_bounds_numba(mask, int(k))
    out[lo:hi] = True
    return out


def _around_origin(mask: np.ndarray) -> np.ndarray:
    """:func:`_around` the origin sample :data:`K0`."""
    return _around(mask, K0)


def _lateral_curvature(s: np.ndarray, f: np.ndarray) -> float:
    """B = f''(0) / 2 [1/m] from samples 5 apart; NaN where it is not positive."""
    B = float((f[K0 - 5] - 2 * f[K0] + f[K0 + 5]) / (2 * (s[5] - s[0]) ** 2))
    return B if np.isfinite(B) and B > 0 else float("nan")


def at_reference(cp: ContactPoint, track: Track, ws: Wheelset, pose: Pose,
                 approach: float) -> ContactPoint | None:
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
    """
    d = cp.normal_penetration(approach)
    if not d > 0 or cp.rail_u_of_s is None:
        return None
    eta, _, u, z, g = _vertical_gap_of_pose(track, ws, pose, cp.side)
    # the patch's own run of vertical interpenetration along the trace (:func:`_around`)
    g_min, lo, hi = _overlap_run_numba(g, u, float(approach), float(cp.rail_u))
    if hi <= lo:
        return None
    g_min = float(g_min)
    run = slice(lo, hi)
    u_run = u[run]
    w = (approach - (g[run] - g_min)) ** WEIGHT_POWER
    total = float(w.sum())
    rail = track.side_rail
    u_ref = float((w * u_run).sum() / total)
    gamma = float((w * np.arctan(rail.slope(u_run))).sum() / total)
    z_ref = float(rail.height(u_ref))
    u_lo, u_hi = float(u_run.min()), float(u_run.max())
    okr = np.isfinite(cp.rail_u_of_s)
    s_ref = float(np.interp(u_ref, cp.rail_u_of_s[okr], cp.s[okr]))
    z = z - g_min - approach  # the wheel lowered by the approach beyond first contact
    k = int(_nearest_numba(u, u_ref))
    s, f, a_of_s, wheel_s_of_s, rail_u_of_s, rail_z_of_s = _tangent_frame(
        track, ws, eta, u, z, u_ref, z_ref, gamma, float(eta[k]))
    with np.errstate(invalid="ignore"):
        own = (rail_u_of_s >= u_lo) & (rail_u_of_s <= u_hi)
    lo, hi = _run_bounds_numba(np.isfinite(f) & (f < 0) & own, K0)  # :func:`_around_origin`
    if hi <= lo:
        return None
    overlap = -float(f[lo:hi].min())
    f = np.where(np.isfinite(f), f + overlap, np.inf)
    # CONTACT's wheel profile coordinate of the point: the wheel above it; its rolling
    # radius: the wheel surface's along the contact normal through it (where the rigid
    # slip of the wheel is taken)
    order = np.argsort(u_run)
    wheel_s = float(ws.profile_coordinate(np.interp(u_ref, u_run[order], eta[run][order])))
    s_normal = float(wheel_s_of_s[K0])
    # B for Hertz's estimates: the parabola with the overlap's depth and width (the origin
    # is the weighted centre, not the gap's minimum, where f'' may be anything)
    width = float(s[hi - 1] - s[lo]) + (s[1] - s[0])  # s increases
    B = overlap / (0.5 * width) ** 2 if hi - lo >= 5 else _lateral_curvature(s, f)
    sgn = SIDES[cp.side]
    return ContactPoint(side=cp.side, gap=approach - overlap / math.cos(gamma),
                        wheel_s=wheel_s, rail_u=u_ref,
                        rail_y=track.rail_coordinate(u_ref, z_ref),
                        position=(cp.position[0], sgn * u_ref, z_ref), contact_angle=gamma,
                        rolling_radius=ws.radius + float(ws.wheel.height(
                            s_normal if math.isfinite(s_normal) else wheel_s)),
                        A=float(a_of_s[K0]), B=B if math.isfinite(B) else cp.B, s=s, f=f,
                        a_of_s=a_of_s, wheel_s_of_s=wheel_s_of_s, rail_u_of_s=rail_u_of_s,
                        rail_z_of_s=rail_z_of_s, approach=approach, rigid=cp,
                        offset=(0.0, s_ref))


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


_BRANCHES: list = []
"""The last few (samples, k, branch) of :func:`_branch_interp`: a patch interpolates
several quantities along the same branch of the same samples."""


def _branch(x: np.ndarray, k: int) -> slice:
    """The samples of the branch of the curve through sample ``k`` on which x increases
    (rotated into a steep tangent plane a profile can fold back over itself, e.g. over the
    flange tip; the other branches are not part of this contact). Remembered for the last
    arrays asked about (held here, so that ``is`` identifies them; read, not changed)."""
    for xs, ks, b in _BRANCHES:
        if xs is x and ks == k:
            return b
    breaks = np.flatnonzero(np.diff(x) <= 0)  # sample i where x stops increasing to i + 1
    i = int(np.searchsorted(breaks, k))
    lo = int(breaks[i - 1]) + 1 if i > 0 else 0
    hi = int(breaks[i]) if i < len(breaks) else len(x) - 1
    b = slice(lo, hi + 1)
    _BRANCHES.insert(0, (x, k, b))
    del _BRANCHES[2:]
    return b


def _branch_interp(x_new: np.ndarray, x: np.ndarray, y: np.ndarray, k: int) -> np.ndarray:
    """Interpolate y(x) along the branch of the curve through sample ``k`` on which x
    increases (:func:`_branch`); NaN off it."""
    b = _branch(x, k)
    return np.interp(x_new, x[b], y[b], left=np.nan, right=np.nan)
