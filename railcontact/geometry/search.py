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


def _trace(track: Track, ws: Wheelset, pose: Pose, side: str):
    """Trace points of one wheel in the side frame: eta, X, u, Z, r, dr/deta."""
    sgn = SIDES[side]
    psi, phi = sgn * pose.yaw, sgn * pose.roll
    u_ws = sgn * pose.lateral
    eta, r, dr = _wheel_samples(ws)
    cz, sz = math.cos(psi), math.sin(psi)
    cx, sx = math.cos(phi), math.sin(phi)
    if psi == 0.0:  # no yaw: the trace is the wheel's lowest line (sin t = 0)
        x = np.zeros_like(eta)
        y, zw = eta, -r
    else:
        sin_t = np.clip(-math.tan(psi) * dr, -1.0, 1.0)
        rc = r * np.sqrt(1.0 - sin_t**2)
        rs = r * sin_t
        x = cz * rs - sz * eta  # yaw about the vertical axis ...
        y = sz * rs + cz * eta
        zw = -rc
    # ... then roll about the track axis
    return eta, x, cx * y - sx * zw + u_ws, sx * y + cx * zw + ws.radius, r, dr


def vertical_gap(track: Track, ws: Wheelset, pose: Pose, side: str):
    """Vertical gap g(eta) between the wheel trace and the rail [m], with the trace points.

    Returns ``(eta, x, u, z, g)`` restricted to trace points above the rail.
    """
    if side not in SIDES:
        raise RailContactError(f"side must be 'left' or 'right', got {side!r}")
    eta, x, u, z, _, _ = _trace(track, ws, pose, side)
    rail = track.side_rail
    lo, hi = rail.bounds
    keep = (u > lo) & (u < hi)
    if keep.sum() < 10:
        raise RailContactError(f"{side} wheel is beside its rail (lateral displacement "
                               f"{pose.lateral:g} m is beyond the profiles)")
    eta, x, u, z = eta[keep], x[keep], u[keep], z[keep]
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
    edges = np.flatnonzero(np.diff(np.concatenate([[0], inside.astype(int), [0]])))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


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

    # tangent-plane coordinates of both profiles around the contact point
    cg, sg = math.cos(gamma), math.sin(gamma)
    s_w = (u - u_c) * cg + (z - z_rail) * sg
    n_w = -(u - u_c) * sg + (z - z_rail) * cg
    ur, zr = rail.samples(N_RAIL)
    s_r = (ur - u_c) * cg + (zr - z_rail) * sg
    n_r = -(ur - u_c) * sg + (zr - z_rail) * cg
    half = 0.025
    s = np.linspace(-half, half, 1001)
    kw = int(np.argmin(np.abs(u - u_c)))
    kr = int(np.argmin(np.abs(ur - u_c)))
    f = _branch_interp(s, s_w, n_w, kw) - _branch_interp(s, s_r, n_r, kr)
    f = f - np.nanmin(f[np.abs(s) < 1e-3]) if np.isfinite(f[500]) else f
    f = np.where(np.isfinite(f), f, np.inf)
    # A(s) from the wheel at the same s
    eta_s = _branch_interp(s, s_w, eta, kw)
    S_s = ws.profile_coordinate(np.where(np.isfinite(eta_s), eta_s, eta_c))
    beta = np.arctan(ws.wheel.slope(S_s))
    a_of_s = np.cos(beta) / (2 * (ws.radius + ws.wheel.height(S_s)))
    k0 = 500
    B = float((f[k0 - 5] - 2 * f[k0] + f[k0 + 5]) / (2 * (s[5] - s[0]) ** 2))
    if not np.isfinite(B) or B <= 0:
        B = float("nan")
    return ContactPoint(side=side, gap=gap_c, wheel_s=s_c, rail_u=u_c,
                        rail_y=track.rail_coordinate(u_c, z_rail),
                        position=(x_c, sgn * u_c, z_rail),
                        contact_angle=gamma, rolling_radius=r_c, A=float(a_of_s[k0]), B=B,
                        s=s, f=f, a_of_s=a_of_s,
                        wheel_s_of_s=np.where(np.isfinite(eta_s), S_s, np.nan),
                        rail_u_of_s=_branch_interp(s, s_r, ur, kr),
                        rail_z_of_s=_branch_interp(s, s_r, zr, kr))


@dataclass(frozen=True)
class ReferencePoint:
    """CONTACT's contact reference point of a patch (SI units, side frame as
    :class:`ContactPoint`): the centre of the interpenetration area weighted by the squared
    interpenetration (CONTACT's ``m_wr_locatecp``, default gap weighting).

    Attributes
    ----------
    offset
        (x, y) of the point in the patch frame, from the rigid contact point [m].
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
    return ReferencePoint(offset=(xr, yr), position=(cp.position[0] + xr, sgn * u, z),
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
