"""Compiled kernels of the contact search (:mod:`.search`): one call per contact point.

A wheelset time step forms a wheel's rigid contact point and the frame at its reference
point on every load pass. Written as numpy calls these took ~15-25 small array
operations each (masks, argmins, interpolations over the 3349-sample trace and the 1001
tangent-plane samples), so that the Python calls cost more than the arithmetic. Here each
is one numba pass with the same operations in the same order, so the results equal the
numpy forms to round-off (sums are taken in order, not pairwise; ``np.interp`` is
written out as numpy's own algorithm).

Arrays in (SI units, side frame as in :mod:`.search`): the trace ``eta, x, u, z, g`` of
:func:`~.search.vertical_gap`; the placed rail sampled at equal steps ``ur, zr``; the rail's
and the wheel's cubic spline pieces (breakpoints, coefficients: :mod:`.spline`); the
tangent plane's lateral samples ``s`` (equally spaced, increasing). A frame is written to
``out`` (5, len(s)): f, A(s), the wheel profile coordinate, the rail u and Z.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .spline import _interval, _interval_walk, _piece

F, A_OF_S, WHEEL_S, RAIL_U, RAIL_Z = range(5)
"""Rows of a frame array."""


@numba.njit(cache=True, nogil=True)
def spline_at(x, c, t, nu):
    """The ``nu``-th derivative of the piecewise cubic (``x``, ``c``) at one point ``t``."""
    j = _interval(x, t)
    return _piece(c, j, t - x[j], nu)


@numba.njit(cache=True, nogil=True)
def nearest(u, u_c):
    """The index of the sample of ``u`` nearest ``u_c`` (the first of equals)."""
    k = 0
    best = abs(u[0] - u_c)
    for i in range(1, u.size):
        d = abs(u[i] - u_c)
        if d < best:
            best = d
            k = i
    return k


@numba.njit(cache=True, nogil=True)
def nearest_sorted(x, v):
    """:func:`nearest` for increasing ``x``: a binary search."""
    j = np.searchsorted(x, v)
    if j == 0:
        return 0
    if j == x.size:
        return x.size - 1
    return j - 1 if abs(x[j - 1] - v) <= abs(x[j] - v) else j


@numba.njit(cache=True, nogil=True)
def nearest_point_sorted(pu, pz, order, pu_sorted, u, z):
    """The index of the point (pu, pz) nearest (u, z), the first of equals (as
    ``argmin((pu - u)**2 + (pz - z)**2)``), searched outward from ``u`` in ``pu_sorted`` =
    ``pu[order]`` (increasing) until the lateral distance alone exceeds the least found."""
    best = math.inf
    k = -1
    n = pu_sorted.size
    j = np.searchsorted(pu_sorted, u)
    for first, stop, step in ((j, n, 1), (j - 1, -1, -1)):  # at and beyond u, then before
        for i in range(first, stop, step):
            du = pu_sorted[i] - u
            if du * du > best:
                break
            m = order[i]
            d = (pu[m] - u) ** 2 + (pz[m] - z) ** 2
            if d < best or (d == best and m < k):
                best = d
                k = m
    return k


@numba.njit(cache=True, nogil=True)
def interp_sorted(x, xp, fp):
    """``np.interp(x, xp, fp)`` at one point for increasing ``xp`` (numpy's algorithm:
    the end values beyond ``xp``, the sample's value where ``x`` falls on one, the other
    end of the piece where the first gives NaN)."""
    return _interp(x, xp, fp, False)


@numba.njit(cache=True, nogil=True, inline="always")
def _at(fp, j, finite):
    """``fp[j]``, or 0 where it is not finite when ``finite``."""
    v = fp[j]
    return v if not finite or math.isfinite(v) else 0.0


@numba.njit(cache=True, nogil=True, inline="always")
def _interp(x, xp, fp, finite):
    """:func:`interp_sorted` of ``fp``, or (``finite``) of ``fp`` with its values that
    are not finite read as 0."""
    n = xp.size
    if math.isnan(x) or x < xp[0] or x > xp[n - 1]:
        return _interp_at(x, xp, fp, finite, 0)
    return _interp_at(x, xp, fp, finite, np.searchsorted(xp, x, side="right") - 1)


@numba.njit(cache=True, nogil=True, inline="always")
def _interp_at(x, xp, fp, finite, j):
    """:func:`_interp` with ``j`` = ``searchsorted(xp, x, side="right") - 1`` given
    (read only where ``x`` lies within ``xp``)."""
    n = xp.size
    if math.isnan(x):
        return x
    if x < xp[0]:
        return _at(fp, 0, finite)
    if x > xp[n - 1]:
        return _at(fp, n - 1, finite)
    if j >= n - 1:
        return _at(fp, n - 1, finite)
    f0 = _at(fp, j, finite)
    if xp[j] == x:
        return f0
    f1 = _at(fp, j + 1, finite)
    slope = (f1 - f0) / (xp[j + 1] - xp[j])
    v = slope * (x - xp[j]) + f0
    if math.isnan(v):
        v = slope * (x - xp[j + 1]) + f1
        if math.isnan(v) and f0 == f1:
            v = f0
    return v


@numba.njit(cache=True, nogil=True, inline="always")
def _right_of(xp, x):
    """``searchsorted(xp, x, side="right") - 1`` for ``x`` within the increasing ``xp``
    (``xp[0] <= x <= xp[-1]``), searched from the sample where ``x`` would lie were the
    samples equally spaced."""
    n = xp.size
    j = int((x - xp[0]) / (xp[n - 1] - xp[0]) * (n - 1)) if xp[n - 1] > xp[0] else 0
    j = min(max(j, 0), n - 1)
    while j > 0 and xp[j] > x:
        j -= 1
    while j < n - 1 and xp[j + 1] <= x:
        j += 1
    return j


@numba.njit(cache=True, nogil=True, inline="always")
def _along(u, z, za, zb, i, u_c, z_c, cg, sg):
    """The coordinate s' in the plane of sample ``i`` of the curve (u, (z - za) - zb)."""
    return (u[i] - u_c) * cg + (((z[i] - za) - zb) - z_c) * sg


@numba.njit(cache=True, nogil=True, inline="always")
def _normal(u, z, za, zb, i, u_c, z_c, cg, sg):
    """The distance n from the plane of sample ``i`` of the curve (u, (z - za) - zb)."""
    return -(u[i] - u_c) * sg + (((z[i] - za) - zb) - z_c) * cg


@numba.njit(cache=True, nogil=True)
def interp_in_plane(s, u, z, a, b, u_c, z_c, cg, sg, k, out):
    """Along the branch through sample ``k`` of the curve (u, z) on which its coordinate
    s' = (u - u_c) cg + (z - z_c) sg increases, the curve's distance
    n = -(u - u_c) sg + (z - z_c) cg from the plane and the quantities ``a`` and ``b`` at
    its samples, linearly interpolated at the increasing ``s`` [m] (NaN off the branch) as
    :func:`np.interp` does on the branch; only the points between the ``s`` are rotated.
    ``out`` (3, len(s)): n, a, b."""
    interp_in_plane_range(s, 0, s.size, u, z, 0.0, 0.0, a, b, True, u_c, z_c, cg, sg, k,
                          out, 0)


@numba.njit(cache=True, nogil=True)
def interp_in_plane_range(s, i0, i1, u, z, za, zb, a, b, with_b, u_c, z_c, cg, sg, k, out,
                          o):
    """:func:`interp_in_plane` of the curve (u, (z - za) - zb) at the samples
    ``s[i0:i1]`` only, written to ``out[:, i - o]`` (``b`` only ``with_b``): the same
    values as over all of ``s``. (The walks stop one point beyond ``s[i0]`` and
    ``s[i1 - 1]`` where these are not the ends of ``s``, so that a sample on a point of
    the curve is interpolated in the same segment as over all of ``s``.)"""
    _in_plane(s, i0, i1, u, z, za, zb, a, b, with_b, u_c, z_c, cg, sg, k, out, o,
              np.empty(u.size))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _in_plane(s, i0, i1, u, z, za, zb, a, b, with_b, u_c, z_c, cg, sg, k, out, o, along):
    """:func:`interp_in_plane_range` with a work array ``along`` (as long as ``u``): the
    coordinates s' of the samples the walks pass are kept there and read again where the
    samples of ``s`` are placed between them."""
    if i1 <= i0:
        return
    n = u.size
    first = s[i0]
    last = s[i1 - 1]
    inner_lo = i0 > 0
    inner_hi = i1 < s.size
    lo = k  # the samples of the branch that bracket s: lo ... hi
    s_lo = _along(u, z, za, zb, k, u_c, z_c, cg, sg)
    along[k] = s_lo
    s_k = s_lo
    while lo > 0 and (s_lo >= first if inner_lo else s_lo > first):
        s_prev = _along(u, z, za, zb, lo - 1, u_c, z_c, cg, sg)
        if not s_prev < s_lo:  # the branch ends: s' stops increasing towards k
            break
        lo -= 1
        s_lo = s_prev
        along[lo] = s_lo
    hi = k
    s_hi = s_k
    while hi < n - 1 and (s_hi <= last if inner_hi else s_hi < last):
        s_next = _along(u, z, za, zb, hi + 1, u_c, z_c, cg, sg)
        if not s_next > s_hi:
            break
        hi += 1
        s_hi = s_next
        along[hi] = s_hi
    j = lo
    x0 = s_lo
    x1 = along[j + 1] if hi > lo else s_lo
    jn = -2  # the segment whose ends' distances n0, n1 are at hand
    n0 = n1 = 0.0
    for i in range(i0, i1):
        x = s[i]
        if hi == lo or x < s_lo or x > s_hi:
            out[0, i - o] = math.nan
            out[1, i - o] = math.nan
            if with_b:
                out[2, i - o] = math.nan
            continue
        while j < hi - 1 and x1 <= x:  # the segment [x0, x1) that holds x
            j += 1
            x0 = x1
            x1 = along[j + 1]
        t = (x - x0) / (x1 - x0)
        if j != jn:
            n0 = n1 if j == jn + 1 else _normal(u, z, za, zb, j, u_c, z_c, cg, sg)
            n1 = _normal(u, z, za, zb, j + 1, u_c, z_c, cg, sg)
            jn = j
        out[0, i - o] = n0 + t * (n1 - n0)
        out[1, i - o] = a[j] + t * (a[j + 1] - a[j])
        if with_b:
            out[2, i - o] = b[j] + t * (b[j + 1] - b[j])


@numba.njit(cache=True, nogil=True)
def frame_samples(eta, u, z, za, zb, ur, zr, wx, wc, radius, half_bb, flange_back, u_c,
                  z_c, gamma, eta_c, kw, kr, s, i0, i1, out):
    """Both profiles in the tangent plane through the rail point ``(u_c, z_c)`` inclined
    at ``gamma``, the wheel trace lowered to ``(z - za) - zb``, at the samples
    ``s[i0:i1]`` only, written to ``out[:, i0:i1]`` (5, len(s)) (the same values as over
    all of ``s``): the wheel's distance above the rail normal to the plane f(s) (NaN where
    a profile ends), A(s) = cos(beta) / (2 r), the wheel profile coordinate S (NaN where
    the wheel ends) and the rail point (u, Z) (the rail's samples ``ur`` increase). The
    wheel's S = eta - half_bb + flange_back, its radius ``radius`` plus the spline
    (``wx``, ``wc``) at S and its slope tan(beta) the spline's derivative there
    (``cos(atan(t)) = 1 / sqrt(1 + t^2)``). ``kw``: the wheel's trace sample nearest
    ``u_c`` (:func:`nearest`), where its branch is taken; ``kr``: the rail sample nearest
    ``u_c`` (:func:`nearest_sorted`)."""
    if i1 <= i0:
        return
    cg, sg = math.cos(gamma), math.sin(gamma)
    wheel = np.empty((2, i1 - i0))
    interp_in_plane_range(s, i0, i1, u, z, za, zb, eta, eta, False, u_c, z_c, cg, sg, kw,
                          wheel, i0)  # (n, eta)
    interp_in_plane_range(s, i0, i1, ur, zr, 0.0, 0.0, ur, zr, True, u_c, z_c, cg, sg, kr,
                          out[2:5], 0)
    j = 0  # the wheel spline's height and slope at S: one interval search for both
    for i in range(i0, i1):
        e = wheel[1, i - i0]
        si = ((e if math.isfinite(e) else eta_c) - half_bb) + flange_back
        if math.isnan(si):
            slope = height = math.nan
        else:
            j = _interval_walk(wx, si, j)
            slope = _piece(wc, j, si - wx[j], 1)
            height = _piece(wc, j, si - wx[j], 0)
        out[F, i] = wheel[0, i - i0] - out[2, i]  # the rail's distance, before row 2 is S
        out[A_OF_S, i] = 1.0 / (math.sqrt(1.0 + slope * slope) * (2 * (radius + height)))
        out[WHEEL_S, i] = si if math.isfinite(e) else math.nan


@numba.njit(cache=True, nogil=True, inline="always")
def _trace_point(eta, r, dr, yawed, tan_psi, cz, sz, cx, sx, u_ws, radius):
    """One point of :func:`trace_gap`'s trace in the side frame: (X, u, Z)."""
    if yawed:
        sin_t = min(max(-tan_psi * dr, -1.0), 1.0)
        rs = r * sin_t
        y = sz * rs + cz * eta
        zw = -(r * math.sqrt(1.0 - sin_t * sin_t))
        return cz * rs - sz * eta, cx * y - sx * zw + u_ws, sx * y + cx * zw + radius
    zw = -r  # no yaw: the trace is the wheel's lowest line (sin t = 0)
    return 0.0, cx * eta - sx * zw + u_ws, sx * eta + cx * zw + radius


@numba.njit(cache=True, nogil=True)
def trace_gap(eta, r, dr, yawed, tan_psi, cz, sz, cx, sx, u_ws, radius, lo, hi, rx, rc, out):
    """The trace points of one wheel (axial positions ``eta``, radii ``r``, dr/deta ``dr``)
    moved into the side frame (yaw ``psi`` about the vertical axis, then roll ``phi``
    about the track axis: ``tan_psi``, ``cz, sz`` = cos, sin psi, ``cx, sx`` = cos, sin
    phi; lateral displacement ``u_ws``), those with ``lo < u < hi`` (above the rail, its
    spline ``rx``, ``rc``) written to ``out`` (5, n): eta, X, u, Z and the vertical gap
    g = Z - rail(u). Returns (how many, the least g, its first index, whether the kept
    u increase strictly, how many samples have the least g)."""
    m = 0
    j = 0
    g_min = math.inf
    k = 0
    ties = 0
    increasing = True
    u_last = -math.inf
    n = eta.size
    nyawed = n if yawed else 0  # yawed: all points first (a loop without branches)
    xs, us, zs = np.empty(nyawed), np.empty(nyawed), np.empty(nyawed)
    for i in range(nyawed):
        xs[i], us[i], zs[i] = _trace_point(eta[i], r[i], dr[i], True, tan_psi, cz, sz, cx,
                                           sx, u_ws, radius)
    for i in range(n):  # (no yaw: the point formed here, kept or not)
        if yawed:
            x, u, z = xs[i], us[i], zs[i]
        else:
            x, u, z = _trace_point(eta[i], r[i], dr[i], False, tan_psi, cz, sz, cx, sx,
                                   u_ws, radius)
        if not lo < u < hi:
            continue
        increasing = increasing and u > u_last
        u_last = u
        j = _interval_walk(rx, u, j)  # (ordered points: a step or two)
        g = z - _piece(rc, j, u - rx[j], 0)
        out[0, m] = eta[i]
        out[1, m] = x
        out[2, m] = u
        out[3, m] = z
        out[4, m] = g
        if g < g_min:
            g_min = g
            k = m
            ties = 1
        elif g == g_min:
            ties += 1
        m += 1
    return m, g_min, k, increasing, ties


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def count_runs(g, g_min, k, approach):
    """How many connected runs of samples the gap above first contact ``g - g_min`` is
    at most ``approach`` [m] on (the least gap's sample ``k`` always in one): the runs of
    :func:`rigid_points`, counted without forming them."""
    n = g.size
    lim = max(approach, 0.0)
    m = 0
    inside = False
    for i in range(n):
        here = g[i] - g_min <= lim or i == k
        if here and not inside:
            m += 1
        inside = here
    return m


@numba.njit(cache=True, nogil=True)
def rigid_point(eta, x, u, g, g_min, a, b, rx, rc, wx, wc, half_bb, flange_back):
    """The rigid contact point of the run ``a:b`` of the trace: its least gap above
    ``g_min``, refined by a parabola through three samples. Returns (eta, x, u, Z, gap,
    gamma, S, wheel radius increment)."""
    n = g.size
    k = a
    best = g[a] - g_min
    for i in range(a + 1, b):
        if g[i] - g_min < best:
            best = g[i] - g_min
            k = i
    t = 0.0
    inner = 0 < k < n - 1
    if inner:
        gm, g0, gp = g[k - 1] - g_min, g[k] - g_min, g[k + 1] - g_min
        d = gm - 2 * g0 + gp
        t = 0.5 * (gm - gp) / d if d > 0 else 0.0
    t = min(max(t, -1.0), 1.0)
    j = (k + (1 if t > 0 else -1)) if inner else k
    w = abs(t)
    eta_c = (1 - w) * eta[k] + w * eta[j]
    x_c = (1 - w) * x[k] + w * x[j]
    u_c = (1 - w) * u[k] + w * u[j]
    gap_c = max((1 - w) * (g[k] - g_min) + w * (g[j] - g_min), 0.0)
    z_rail = spline_at(rx, rc, u_c, 0)
    gamma = math.atan(spline_at(rx, rc, u_c, 1))
    s_c = (eta_c - half_bb) + flange_back
    return eta_c, x_c, u_c, z_rail, gap_c, gamma, s_c, spline_at(wx, wc, s_c, 0)


@numba.njit(cache=True, nogil=True)
def rigid_points(tr, g_min, k, approach, rx, rc, wx, wc, half_bb, flange_back):
    """:func:`rigid_point` of each run of the trace ``tr`` (5, n) (the index ranges
    ``a:b`` of the connected runs where the gap above first contact ``g - g_min`` is at
    most ``approach`` [m], the least gap's sample ``k`` always in one; :func:`count_runs`
    of them), one row each (m, 8) (the runs found by a scan, not formed)."""
    eta, x, u, g = tr[0], tr[1], tr[2], tr[4]
    n = g.size
    lim = max(approach, 0.0)
    out = np.empty((count_runs(g, g_min, k, approach), 8))
    m = 0
    i = 0
    while i < n:
        if g[i] - g_min <= lim or i == k:
            a = i
            while i < n and (g[i] - g_min <= lim or i == k):
                i += 1
            p = rigid_point(eta, x, u, g, g_min, a, i, rx, rc, wx, wc, half_bb, flange_back)
            for c in range(8):
                out[m, c] = p[c]
            m += 1
        else:
            i += 1
    return out


@numba.njit(cache=True, nogil=True)
def rigid_frame(eta, u, z, g_min, ur, zr, wx, wc, radius, half_bb, flange_back, u_c, z_c,
                gamma, eta_c, s, k0, out):
    """The tangent frame of a rigid contact point (:func:`rigid_point`):
    :func:`frame_samples` over all of ``s`` of the wheel lowered into first contact
    (``z - g_min``), ``f`` shifted to 0 at its least value within 1 mm of the point
    (where ``f`` is finite at ``s[k0]`` = 0), NaN made infinite."""
    frame_samples(eta, u, z, g_min, 0.0, ur, zr, wx, wc, radius, half_bb, flange_back,
                  u_c, z_c, gamma, eta_c, nearest(u, u_c), nearest_sorted(ur, u_c), s, 0,
                  s.size, out)
    f = out[F]
    if math.isfinite(f[k0]):
        m = math.inf
        for i in range(s.size):
            if abs(s[i]) < 1e-3 and f[i] < m:  # NaN compares False: nanmin
                m = f[i]
        for i in range(s.size):
            f[i] = f[i] - m
    for i in range(s.size):
        if not math.isfinite(f[i]):
            f[i] = math.inf


@numba.njit(cache=True, nogil=True)
def nearest_first(u, v, increasing):
    """:func:`nearest` (the first of equals), by bisection when ``u`` increases strictly
    (the distances then fall, rounded, towards ``v`` and rise after it: the first of
    the least ones is at or before the nearer bracketing sample)."""
    if not increasing or math.isnan(v):
        return nearest(u, v)
    m = nearest_sorted(u, v)
    while m > 0 and abs(u[m - 1] - v) == abs(u[m] - v):
        m -= 1
    return m


FRAME_MARGIN = 32
"""Samples of the tangent plane (1.6 mm) formed beyond those of the overlap's rail points:
the samples a patch's grid reads in a time step (more are formed when read)."""
FRAME_GROW = 32
"""Samples added at a time where the overlap's run reaches the formed samples' edge."""


@numba.njit(cache=True, nogil=True)
def reference_frame(tr, g_min_trace, increasing, approach, u_rigid, ur, zr, rx, rc, wx,
                    wc, radius, half_bb, flange_back, s, k0, power, turn, out):
    """CONTACT's reference point of the patch around the rigid point at ``u_rigid``, the
    wheel lowered by ``approach`` beyond first contact, and its tangent frame
    (:func:`~.search.at_reference`), the frame written to ``out`` with ``f`` shifted so
    that its least value over the patch's own overlap is 0 - at the samples ``i0:i1``
    only: those of the overlap's rail points with :data:`FRAME_MARGIN` beyond and
    ``k0 +- 5`` (:func:`extend_frame` forms others, the same values as over all).

    ``tr``: the trace (5, n) of :func:`trace_gap`, with its least gap and whether its u
    increase. ``turn`` [rad] is added to the weighted angle before the plane is formed
    (0: the plane at the weighted angle; :func:`~.separation.turned_angles`). Returns
    (ok, u, Z, gamma, overlap [m], wheel profile coordinate S above the point, lo, hi
    (the overlap's samples of ``s``), i0, i1, the trace's and the rail's samples nearest
    the point, the trace's eta there, the least gap, the wheel's radius increment at the
    S of sample ``k0`` (or above the point where that is NaN), the run's weight
    integrated across the rail [m^3.5 for ``power`` 2.5] and its two ends on the rail
    (u, Z) where the interpenetration is zero, the end of least u first); ``ok`` False
    where the wheel does not overlap the rail there."""
    nan = math.nan
    eta, u, z, g = tr[0], tr[2], tr[3], tr[4]
    n = g.size
    ns = s.size
    # the run of positive interpenetration through the sample nearest u_rigid (the least
    # gap is the trace's; NaN where the first gap is, as a scan from it would give)
    g_min = g_min_trace if not math.isnan(g[0]) else nan
    k = nearest_first(u, u_rigid, increasing)
    if not approach - (g[k] - g_min) > 0:
        return (False, nan, nan, nan, nan, nan, 0, 0, 0, 0, 0, 0, nan, g_min, nan, nan, nan,
                nan, nan, nan)
    lo = k
    while lo > 0 and approach - (g[lo - 1] - g_min) > 0:
        lo -= 1
    hi = k + 1
    while hi < n and approach - (g[hi] - g_min) > 0:
        hi += 1
    total = 0.0
    su = 0.0
    sgam = 0.0
    weight = 0.0  # the run's weight integrated across the rail: each sample's weight
    # times its share of the rail, half the distance between its neighbours
    u_lo = u[lo]
    u_hi = u[lo]
    inc = True
    j = 0  # the rail's piece at u[i]
    for i in range(lo, hi):
        e = approach - (g[i] - g_min)
        w = e * e * math.sqrt(e) if power == 2.5 else e**power
        total += w
        su += w * u[i]
        ui = u[i]
        if math.isnan(ui):
            slope = math.nan
        else:
            j = _interval_walk(rx, ui, j)
            slope = _piece(rc, j, ui - rx[j], 1)
        sgam += w * math.atan(slope)
        u_lo = min(u_lo, u[i])
        u_hi = max(u_hi, u[i])
        if i > lo and not u[i] > u[i - 1]:
            inc = False
        weight += w * 0.5 * abs(u[min(i + 1, n - 1)] - u[max(i - 1, 0)])
    u_ref = su / total
    gamma = sgam / total + turn
    # the run's ends: where the interpenetration, linear between the last sample in and
    # the first out, is zero
    u_a = u[lo]
    if lo > 0:
        e_in, e_out = approach - (g[lo] - g_min), approach - (g[lo - 1] - g_min)
        if math.isfinite(u[lo - 1]) and math.isfinite(e_out):
            u_a = u[lo] + e_in / (e_in - e_out) * (u[lo - 1] - u[lo])
    u_b = u[hi - 1]
    if hi < n:
        e_in, e_out = approach - (g[hi - 1] - g_min), approach - (g[hi] - g_min)
        if math.isfinite(u[hi]) and math.isfinite(e_out):
            u_b = u[hi - 1] + e_in / (e_in - e_out) * (u[hi] - u[hi - 1])
    u_a, u_b = min(u_a, u_b), max(u_a, u_b)
    z_a, z_b = spline_at(rx, rc, u_a, 0), spline_at(rx, rc, u_b, 0)
    z_ref = spline_at(rx, rc, u_ref, 0)
    # the wheel above the point: the trace's eta at u_ref (ordered by u)
    if inc:
        eta_ref = interp_sorted(u_ref, u[lo:hi], eta[lo:hi])
    else:
        order = np.argsort(u[lo:hi], kind="mergesort")
        eta_ref = interp_sorted(u_ref, u[lo:hi][order], eta[lo:hi][order])
    wheel_s = (eta_ref - half_bb) + flange_back
    kw = nearest_first(u, u_ref, increasing)  # the trace sample nearest u_ref
    kr = nearest_sorted(ur, u_ref)
    # the samples of s over the overlap's rail points (u_lo ... u_hi), with a margin
    cg, sg = math.cos(gamma), math.sin(gamma)
    sa = (u_lo - u_ref) * cg + (spline_at(rx, rc, u_lo, 0) - z_ref) * sg
    sb = (u_hi - u_ref) * cg + (spline_at(rx, rc, u_hi, 0) - z_ref) * sg
    ds = s[1] - s[0]
    i0, i1 = 0, ns
    if math.isfinite(sa) and math.isfinite(sb) and ds > 0:
        ia = min(max((min(sa, sb) - s[0]) / ds, -1.0), ns + 1.0)
        ib = min(max((max(sa, sb) - s[0]) / ds, -1.0), ns + 1.0)
        i0 = max(min(int(math.floor(ia)) - FRAME_MARGIN, k0 - 5), 0)
        i1 = min(max(int(math.ceil(ib)) + 1 + FRAME_MARGIN, k0 + 6), ns)
    eta_c = eta[kw]
    frame_samples(eta, u, z, g_min, approach, ur, zr, wx, wc, radius, half_bb, flange_back,
                  u_ref, z_ref, gamma, eta_c, kw, kr, s, i0, i1, out)
    f = out[F]
    ru_s = out[RAIL_U]
    # the patch's own overlap: the run through the origin, more samples formed where it
    # reaches the edge of those formed
    if not _own(f, ru_s, u_lo, u_hi, k0):
        return (False, nan, nan, nan, nan, nan, 0, 0, 0, 0, 0, 0, nan, g_min, nan, nan, nan,
                nan, nan, nan)
    lo = k0
    while True:
        while lo > i0 and _own(f, ru_s, u_lo, u_hi, lo - 1):
            lo -= 1
        if lo > i0 or i0 == 0:
            break
        a = max(i0 - FRAME_GROW, 0)
        frame_samples(eta, u, z, g_min, approach, ur, zr, wx, wc, radius, half_bb,
                      flange_back, u_ref, z_ref, gamma, eta_c, kw, kr, s, a, i0, out)
        i0 = a
    hi = k0 + 1
    while True:
        while hi < i1 and _own(f, ru_s, u_lo, u_hi, hi):
            hi += 1
        if hi < i1 or i1 == ns:
            break
        b = min(i1 + FRAME_GROW, ns)
        frame_samples(eta, u, z, g_min, approach, ur, zr, wx, wc, radius, half_bb,
                      flange_back, u_ref, z_ref, gamma, eta_c, kw, kr, s, i1, b, out)
        i1 = b
    least = f[lo]
    for i in range(lo + 1, hi):
        least = min(least, f[i])
    overlap = -least
    _shift(f, overlap, i0, i1)
    s_normal = out[WHEEL_S, k0]
    height = spline_at(wx, wc, s_normal if math.isfinite(s_normal) else wheel_s, 0)
    return (True, u_ref, z_ref, gamma, overlap, wheel_s, lo, hi, i0, i1, kw, kr, eta_c,
            g_min, height, weight, u_a, z_a, u_b, z_b)


@numba.njit(cache=True, nogil=True, inline="always")
def _own(f, ru_s, u_lo, u_hi, i):
    """Whether sample ``i`` of a frame lies in the overlap whose rail points are
    ``u_lo ... u_hi``."""
    return math.isfinite(f[i]) and f[i] < 0 and ru_s[i] >= u_lo and ru_s[i] <= u_hi


@numba.njit(cache=True, nogil=True, inline="always")
def _shift(f, overlap, i0, i1):
    """``f + overlap`` at the samples ``i0:i1``, infinite where ``f`` is not finite."""
    for i in range(i0, i1):
        f[i] = f[i] + overlap if math.isfinite(f[i]) else math.inf


@numba.njit(cache=True, nogil=True)
def extend_frame(eta, u, z, za, zb, ur, zr, wx, wc, radius, half_bb, flange_back, u_c, z_c,
                 gamma, eta_c, kw, kr, s, overlap, i0, i1, a, b, out):
    """A frame of :func:`reference_frame` formed at the samples ``i0:i1`` of ``out``,
    formed also at ``a:i0`` and ``i1:b`` (``a <= i0 <= i1 <= b``) and shifted by its
    ``overlap`` as there. (Formed in a buffer first: a value written to ``out`` is final,
    so that a reader of the samples ``i0:i1`` meanwhile, or another extension of the same
    samples, reads the same values.)"""
    buf = np.empty_like(out)
    for lo, hi in ((a, i0), (i1, b)):
        frame_samples(eta, u, z, za, zb, ur, zr, wx, wc, radius, half_bb, flange_back, u_c,
                      z_c, gamma, eta_c, kw, kr, s, lo, hi, buf)
        _shift(buf[F], overlap, lo, hi)
        out[:, lo:hi] = buf[:, lo:hi]


@numba.njit(cache=True, nogil=True)
def _samples_read(y, s):
    """The first and the last sample of ``s`` that :func:`interp_sorted` reads at ``y``."""
    n = s.size
    if y < s[0]:
        return 0, 0
    if y > s[n - 1]:
        return n - 1, n - 1
    j = np.searchsorted(s, y, side="right") - 1
    if j >= n - 1:
        return n - 1, n - 1
    if s[j] == y:
        return j, j
    return j, j + 1


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def gap_on_grid_part(s, frame, i0, i1, x0, dx, nx, y0, dy, ny, far, out):
    """:func:`gap_on_grid` from a frame (5, len(s)) formed at the samples ``i0:i1`` only.
    Returns (done, a, b): not done (``out`` not written) when the grid reads samples
    beyond them, ``a:b`` the samples to form then (those formed included)."""
    f = frame[F]
    a_of_s = frame[A_OF_S]
    ra = _samples_read(y0, s)[0]
    rb = _samples_read(y0 + dy * (ny - 1), s)[1] + 1
    if ra < i0 or rb > i1:
        return False, min(ra, i0), max(rb, i1)
    _gap_rows(s, f, a_of_s, x0, dx, nx, y0, dy, ny, far, out)
    return True, i0, i1


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def gap_on_frame(what, frame, i0, i1, x0, dx, nx, y0, dy, ny, far, out):
    """:func:`gap_on_grid` of a frame at the reference point formed at the samples
    ``i0:i1`` of ``frame`` (``what``: the arguments of :func:`extend_frame` before
    ``i0``, as :class:`~.points.TangentPlane` keeps them, its samples ``s`` the 19th),
    formed further (:func:`extend_frame`) where the grid reads beyond them
    (:func:`gap_on_grid_part`); returns the samples formed then (i0, i1)."""
    s = what[18]
    while True:
        done, a, b = gap_on_grid_part(s, frame, i0, i1, x0, dx, nx, y0, dy, ny, far, out)
        if done:
            return i0, i1
        a, b = min(a, i0), max(b, i1)
        extend_frame(what[0], what[1], what[2], what[3], what[4], what[5], what[6],
                     what[7], what[8], what[9], what[10], what[11], what[12], what[13],
                     what[14], what[15], what[16], what[17], what[18], what[19], i0, i1, a,
                     b, frame)
        i0, i1 = a, b


@numba.njit(cache=True, nogil=True, inline="always")
def _gap_rows(s, f, a_of_s, x0, dx, nx, y0, dy, ny, far, out):
    """``out[ix, jy]`` = f(y) + A(y) x^2 interpolated from the samples (``f`` = ``far``
    beyond them, ``A`` = 0 where it is not finite; ``far`` wherever the sum is not
    finite)."""
    ns = s.size
    fy = np.empty(ny)
    ay = np.empty(ny)
    for jy in range(ny):
        y = y0 + dy * jy
        if math.isnan(y) or y < s[0] or y > s[ns - 1]:
            fy[jy] = far if not math.isnan(y) else interp_sorted(y, s, f)
            ay[jy] = _interp(y, s, a_of_s, True)
        else:  # one search of the samples for both
            j = _right_of(s, y)
            fy[jy] = _interp_at(y, s, f, False, j)
            ay[jy] = _interp_at(y, s, a_of_s, True, j)
    for ix in range(nx):
        xi = x0 + dx * ix
        x2 = xi * xi
        for jy in range(ny):
            h = fy[jy] + ay[jy] * x2
            out[ix, jy] = h if math.isfinite(h) else far


@numba.njit(cache=True, nogil=True)
def gap_on_grid(s, f, a_of_s, x0, dx, nx, y0, dy, ny, far, out):
    """``h = f(y) + A(y) x^2`` at the element centres of a grid ((nx, ny) written to
    ``out``) with ``f`` and ``A`` interpolated at ``y`` from the samples ``s`` as
    ``np.interp`` does (``f`` beyond the samples and where ``A`` is not finite: ``far``
    for f, 0 for A); ``far`` wherever the sum is not finite."""
    _gap_rows(s, f, a_of_s, x0, dx, nx, y0, dy, ny, far, out)


@numba.njit(cache=True, nogil=True)
def lateral_extent(s, f, delta, k0):
    """``(lo, hi)``: the run of samples through ``k0`` where ``f <= delta`` (``k0``
    always in it)."""
    lo = k0
    while lo > 0 and f[lo - 1] <= delta:
        lo -= 1
    hi = k0
    while hi < s.size - 1 and f[hi + 1] <= delta:
        hi += 1
    return lo, hi


@numba.njit(cache=True, nogil=True)
def saddles(g, g_min):
    """The saddles of the gap ``g - g_min`` [m] along the trace: for each interior local
    maximum, (its height above first contact, the depth below it of the shallower of the
    two lobes it separates) (m, 2). A lobe is the connected part on one side that lies
    below the saddle (up to the first higher sample); at the saddle's height the two runs
    of :func:`count_runs` on either side join into one."""
    n = g.size
    out = np.empty((max(n - 2, 0), 2))
    m = 0
    for i in range(1, n - 1):
        h = g[i]
        if not (h > g[i - 1] and h >= g[i + 1]):
            continue
        j = i + 1  # a plateau: a saddle only where the gap falls again after it
        while j < n and g[j] == h:
            j += 1
        if j == n or g[j] > h:
            continue
        lo_left = h
        j = i - 1
        while j >= 0 and g[j] <= h:
            lo_left = min(lo_left, g[j])
            j -= 1
        lo_right = h
        j = i + 1
        while j < n and g[j] <= h:
            lo_right = min(lo_right, g[j])
            j += 1
        out[m, 0] = h - g_min
        out[m, 1] = min(h - lo_left, h - lo_right)
        m += 1
    return out[:m]


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def merge_saddles(g, g_min, min_lobe):
    """The heights above first contact [m] of the :func:`saddles` of the gap whose
    shallower lobe is at least ``min_lobe`` times the height deep, increasing."""
    s = saddles(g, g_min)
    out = np.empty(s.shape[0])
    m = 0
    for i in range(s.shape[0]):
        if s[i, 1] >= min_lobe * s[i, 0]:
            out[m] = s[i, 0]
            m += 1
    return np.sort(out[:m])


@numba.njit(cache=True, nogil=True)
def run_extent(g, u, g_min, approach, u_c, increasing):
    """``(u_lo, u_hi)``: the lateral positions on the rail [m] spanned by the run of the
    trace (gap above first contact ``g - g_min`` at most ``approach`` [m], rail positions
    ``u``) that holds the run's sample nearest ``u_c`` [m]; ``(u_c, u_c)`` without any
    run. ``increasing``: whether ``u`` increase strictly (the nearest sample then searched
    outward from ``u_c``, :func:`_nearest_in_run`)."""
    n = g.size
    if increasing and math.isfinite(u_c):
        best = _nearest_in_run(g, u, g_min, approach, u_c)
    else:
        best = -1
        dist = np.inf
        for i in range(n):
            if g[i] - g_min <= approach and abs(u[i] - u_c) < dist:
                dist = abs(u[i] - u_c)
                best = i
    if best < 0:
        return u_c, u_c
    a = best
    while a > 0 and g[a - 1] - g_min <= approach:
        a -= 1
    b = best
    while b < n - 1 and g[b + 1] - g_min <= approach:
        b += 1
    return min(u[a], u[b]), max(u[a], u[b])


@numba.njit(cache=True, nogil=True)
def _nearest_in_run(g, u, g_min, approach, u_c):
    """The first of the samples with ``g - g_min <= approach`` nearest ``u_c`` (as a scan
    of all, -1 without any) for strictly increasing ``u``: the distances ``|u - u_c|``
    (rounded) do not rise towards ``u_c`` and do not fall beyond it, so the nearest are the
    last such sample before ``u_c`` (or the first of equal distance before it) and the
    first at or beyond it."""
    n = g.size
    j = np.searchsorted(u, u_c)  # u[j - 1] < u_c <= u[j]
    right = j
    while right < n and not g[right] - g_min <= approach:
        right += 1
    left = j - 1
    while left >= 0 and not g[left] - g_min <= approach:
        left -= 1
    if left >= 0:
        d = abs(u[left] - u_c)
        i = left - 1
        while i >= 0 and abs(u[i] - u_c) == d:
            if g[i] - g_min <= approach:
                left = i
            i -= 1
        if right == n or d <= abs(u[right] - u_c):
            return left
    return right if right < n else -1


@numba.njit(cache=True, nogil=True)
def lobes_extent(f, u, delta, k0, u_lo, u_hi):
    """``(lo, hi)``: the samples from the first to the last where ``f <= delta`` and the
    rail position ``u`` lies in ``[u_lo, u_hi]``, together with the run through ``k0``
    where ``f <= delta`` (:func:`lateral_extent`; all of it when ``u_lo > u_hi``)."""
    lo, hi = lateral_extent(f, f, delta, k0)
    if u_lo <= u_hi:
        for i in range(f.size):
            if f[i] <= delta and u_lo <= u[i] <= u_hi:
                lo = min(lo, i)
                hi = max(hi, i)
    return lo, hi


@numba.njit(cache=True, nogil=True)
def overlap_half_length(f, a_of_s, lo, hi, delta):
    """The half length ``max sqrt((delta - f) / A)`` [m] along x of the overlap ``f(s) +
    A(s) x^2 <= delta`` over the samples ``lo..hi`` (inclusive) where ``delta - f > 0``
    and ``A > 0``; 0 without any. The square root of the largest quotient, as
    ``sqrt(max(q))`` of the numpy form (the same bits)."""
    q_max = -1.0
    for i in range(lo, hi + 1):
        depth = delta - f[i]
        a = a_of_s[i]
        if depth > 0.0 and a > 0.0:
            q = depth / a
            if q > q_max:
                q_max = q
    return math.sqrt(q_max) if q_max >= 0.0 else 0.0


@numba.njit(cache=True, nogil=True)
def rigid_curvature_samples(eta, u, z, g_min, ur, zr, wx, wc, radius, half_bb, flange_back,
                            u_c, z_c, gamma, eta_c, s, k0, increasing, out):
    """What a rigid contact point's curvatures read of its tangent frame
    (:func:`rigid_frame`), formed at the samples within 1 mm of ``s[k0]`` = 0 and at
    ``k0 +- 5`` only (the same values as over all of ``s``): (A(0), f at ``k0 - 5``,
    ``k0``, ``k0 + 5``) with ``f`` shifted and made infinite as there. ``out`` (5,
    len(s)) holds the samples formed; ``increasing``: whether the trace's ``u`` increase
    strictly (the sample nearest ``u_c`` then found by bisection)."""
    ns = s.size
    i0 = max(k0 - 5, 0)
    while i0 > 0 and abs(s[i0 - 1]) < 1e-3:
        i0 -= 1
    i1 = min(k0 + 6, ns)
    while i1 < ns and abs(s[i1]) < 1e-3:
        i1 += 1
    frame_samples(eta, u, z, g_min, 0.0, ur, zr, wx, wc, radius, half_bb, flange_back,
                  u_c, z_c, gamma, eta_c, nearest_first(u, u_c, increasing),
                  nearest_sorted(ur, u_c), s, i0, i1, out)
    f = out[F]
    m = 0.0
    if math.isfinite(f[k0]):
        m = math.inf
        for i in range(i0, i1):
            if abs(s[i]) < 1e-3 and f[i] < m:  # NaN compares False: nanmin
                m = f[i]
    three = np.empty(3)
    for j, i in enumerate((k0 - 5, k0, k0 + 5)):
        v = f[i] - m if math.isfinite(f[k0]) else f[i]
        three[j] = v if math.isfinite(v) else math.inf
    return out[A_OF_S, k0], three[0], three[1], three[2]


@numba.njit(cache=True, nogil=True)
def rail_coordinate(pu, pz, order, pu_sorted, py, u, z):
    """The rail profile coordinate ``py`` [m] of the placed rail's point (``pu``, ``pz``)
    nearest (u, Z) (:func:`nearest_point_sorted`; ``order``, ``pu_sorted`` its search's
    order), NaN where ``u`` or ``z`` is not finite (no nearest point)."""
    if not (math.isfinite(u) and math.isfinite(z)):
        return math.nan
    return py[nearest_point_sorted(pu, pz, order, pu_sorted, u, z)]


@numba.njit(cache=True, nogil=True)
def lateral_curvature(lo, mid, hi, denominator):
    """B = f''(0) / 2 [1/m] from three samples of f ``h`` [m] apart (the middle at the
    origin), ``denominator`` = ``2 h^2`` (formed by the caller: Python's ``h ** 2`` is the
    C library's ``pow``, which a compiled ``h ** 2`` is not, to the last bit); NaN where
    it is not positive or a sample is not finite (a profile's end: no convex contact)."""
    if not (math.isfinite(lo) and math.isfinite(mid) and math.isfinite(hi)):
        return math.nan
    b = (lo - 2 * mid + hi) / denominator
    return b if math.isfinite(b) and b > 0 else math.nan


@numba.njit(cache=True, nogil=True)
def rigid_record(eta, u, z, g_min, ur, zr, wx, wc, radius, half_bb, flange_back, u_c, z_c,
                 gamma, eta_c, s, k0, denominator, increasing, pu, pz, order, pu_sorted,
                 py):
    """What a rigid contact point (:func:`rigid_point`: ``u_c``, ``z_c``, ``gamma``,
    ``eta_c``) holds beyond its row: (A, B) from the samples of its tangent frame near it
    (:func:`rigid_curvature_samples`, :func:`lateral_curvature` of the samples ``k0 - 5``,
    ``k0``, ``k0 + 5`` with its ``denominator``) and its rail profile coordinate
    (:func:`rail_coordinate`: NaN where the point is not finite)."""
    near = np.empty((5, s.size))
    a, lo, mid, hi = rigid_curvature_samples(eta, u, z, g_min, ur, zr, wx, wc, radius,
                                             half_bb, flange_back, u_c, z_c, gamma, eta_c,
                                             s, k0, increasing, near)
    return (a, lateral_curvature(lo, mid, hi, denominator),
            rail_coordinate(pu, pz, order, pu_sorted, py, u_c, z_c))


@numba.njit(cache=True, nogil=True)
def search_wheel(eta, r, dr, yawed, tan_psi, cz, sz, cx, sx, u_ws, lo, hi, ur, zr, rx, rc,
                 wx, wc, radius, half_bb, flange_back, s, k0, denominator, pu, pz, order,
                 pu_sorted, py, min_lobe, out):
    """One wheel searched at a pose in one pass: its trace (:func:`trace_gap`, written to
    ``out``), the heights at which its contact regions merge (:func:`merge_saddles` of the
    trace's gap with ``min_lobe``) and, where its least gap is finite and on one sample,
    its first rigid contact point (:func:`rigid_point` of that sample alone) with what
    :func:`rigid_record` gives of it. Returns (n, the least gap, its first index, whether u
    increase, how many samples have the least gap, the merges, whether the point is formed,
    its row (8) and (A, B, rail coordinate)); neither the merges nor the point are formed
    for fewer than 10 trace points."""
    n, g_min, k, increasing, ties = trace_gap(eta, r, dr, yawed, tan_psi, cz, sz, cx, sx,
                                              u_ws, radius, lo, hi, rx, rc, out)
    nan = math.nan
    no_point = (nan, nan, nan, nan, nan, nan, nan, nan)
    if n < 10:
        return n, g_min, k, increasing, ties, np.empty(0), False, no_point, (nan, nan, nan)
    merges = merge_saddles(out[4, :n], g_min, min_lobe)
    if ties != 1 or not math.isfinite(g_min):
        return n, g_min, k, increasing, ties, merges, False, no_point, (nan, nan, nan)
    e, x, u, z, g = out[0, :n], out[1, :n], out[2, :n], out[3, :n], out[4, :n]
    row = rigid_point(e, x, u, g, g_min, k, k + 1, rx, rc, wx, wc, half_bb, flange_back)
    rec = rigid_record(e, u, z, g_min, ur, zr, wx, wc, radius, half_bb, flange_back, row[2],
                       row[3], row[5], row[0], s, k0, denominator, increasing, pu, pz, order,
                       pu_sorted, py)
    return n, g_min, k, increasing, ties, merges, True, row, rec


@numba.njit(cache=True, nogil=True)
def reference_patch(tr, g_min_trace, increasing, approach, u_rigid, ur, zr, rx, rc, wx, wc,
                    radius, half_bb, flange_back, s, k0, denominator, power, turn, pu, pz,
                    order, pu_sorted, py, out):
    """:func:`reference_frame`, with :func:`lateral_curvature` of the frame's samples
    ``k0 - 5``, ``k0``, ``k0 + 5`` (its ``denominator``) and the rail profile coordinate
    of its point (:func:`rail_coordinate`, NaN where the point is not finite): returns its
    tuple, that B and that coordinate."""
    r = reference_frame(tr, g_min_trace, increasing, approach, u_rigid, ur, zr, rx, rc, wx,
                        wc, radius, half_bb, flange_back, s, k0, power, turn, out)
    if not r[0]:
        return r, math.nan, math.nan
    return (r, lateral_curvature(out[F, k0 - 5], out[F, k0], out[F, k0 + 5], denominator),
            rail_coordinate(pu, pz, order, pu_sorted, py, r[1], r[2]))


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def overlap_box_frame(g, u_trace, g_min, approach, rail_u, increasing, eta, u, z, za, zb, ur,
                      zr, wx, wc, radius, half_bb, flange_back, u_c, z_c, gamma, eta_c, kw,
                      kr, s, overlap, frame, i0, i1, penetration, k0, grow):
    """The box (xmin, xmax, ymin, ymax) [m] around a patch's rigid overlap at the normal
    ``penetration`` [m] (:func:`~.points.overlap_box`) with the run of the wheel's
    vertical overlap at the vertical ``approach`` [m] that holds ``rail_u``
    (:func:`run_extent` of the trace's gap ``g`` and rail positions ``u_trace``), of a
    frame of :func:`reference_frame` formed at the samples ``i0:i1`` of ``frame``: formed
    further (:func:`extend_frame`, ``grow`` samples a time; its arguments from ``eta`` to
    ``overlap``) where the overlap, or the run, reaches the edge of those formed. Returns
    the box and the samples formed then (i0, i1)."""
    lo_u, hi_u = run_extent(g, u_trace, g_min, approach, rail_u, increasing)
    ns = s.size
    while True:
        f = frame[F, i0:i1]
        ru = frame[RAIL_U, i0:i1]
        m = i1 - i0
        lo, hi = lobes_extent(f, ru, penetration, min(max(k0 - i0, 0), m - 1), lo_u, hi_u)
        a = i0 - grow if i0 > 0 and (lo == 0 or lo_u <= ru[0] <= hi_u) else i0
        b = i1 + grow if i1 < ns and (hi == m - 1 or lo_u <= ru[m - 1] <= hi_u) else i1
        if a == i0 and b == i1:
            ds = s[i0 + 1] - s[i0]
            xl = overlap_half_length(f, frame[A_OF_S, i0:i1], lo, hi, penetration)
            return -xl, xl, s[i0 + lo] - ds, s[i0 + hi] + ds, i0, i1
        a, b = min(max(a, 0), i0), max(min(b, ns), i1)
        extend_frame(eta, u, z, za, zb, ur, zr, wx, wc, radius, half_bb, flange_back, u_c,
                     z_c, gamma, eta_c, kw, kr, s, overlap, i0, i1, a, b, frame)
        i0, i1 = a, b
