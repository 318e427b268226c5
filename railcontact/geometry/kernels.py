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

from .spline import _interval, _interval_near, _piece

F, A_OF_S, WHEEL_S, RAIL_U, RAIL_Z = range(5)
"""Rows of a frame array."""


@numba.njit(cache=True)
def spline_at(x, c, t, nu):
    """The ``nu``-th derivative of the piecewise cubic (``x``, ``c``) at one point ``t``."""
    j = _interval(x, t)
    return _piece(c, j, t - x[j], nu)


@numba.njit(cache=True)
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


@numba.njit(cache=True)
def nearest_sorted(x, v):
    """:func:`nearest` for increasing ``x``: a binary search."""
    j = np.searchsorted(x, v)
    if j == 0:
        return 0
    if j == x.size:
        return x.size - 1
    return j - 1 if abs(x[j - 1] - v) <= abs(x[j] - v) else j


@numba.njit(cache=True)
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


@numba.njit(cache=True)
def run_bounds(mask, k):
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


@numba.njit(cache=True)
def interp_sorted(x, xp, fp):
    """``np.interp(x, xp, fp)`` at one point for increasing ``xp`` (numpy's algorithm:
    the end values beyond ``xp``, the sample's value where ``x`` falls on one, the other
    end of the piece where the first gives NaN)."""
    n = xp.size
    if math.isnan(x):
        return x
    if x < xp[0]:
        return fp[0]
    if x > xp[n - 1]:
        return fp[n - 1]
    j = np.searchsorted(xp, x, side="right") - 1
    if j >= n - 1:
        return fp[n - 1]
    if xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    v = slope * (x - xp[j]) + fp[j]
    if math.isnan(v):
        v = slope * (x - xp[j + 1]) + fp[j + 1]
        if math.isnan(v) and fp[j] == fp[j + 1]:
            v = fp[j]
    return v


@numba.njit(cache=True)
def interp_in_plane(s, u, z, a, b, u_c, z_c, cg, sg, k, out):
    """Along the branch through sample ``k`` of the curve (u, z) on which its coordinate
    s' = (u - u_c) cg + (z - z_c) sg increases, the curve's distance
    n = -(u - u_c) sg + (z - z_c) cg from the plane and the quantities ``a`` and ``b`` at
    its samples, linearly interpolated at the increasing ``s`` [m] (NaN off the branch) as
    :func:`np.interp` does on the branch; only the points between the ``s`` are rotated.
    ``out`` (3, len(s)): n, a, b."""
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


@numba.njit(cache=True)
def tangent_frame(eta, u, z, ur, zr, wx, wc, radius, half_bb, flange_back, u_c, z_c,
                  gamma, eta_c, kw, s, out):
    """Both profiles in the tangent plane through the rail point ``(u_c, z_c)`` inclined
    at ``gamma``, written to ``out`` (5, len(s)): the
    wheel's distance above the rail normal to the plane f(s) (NaN where a profile ends),
    A(s) = cos(beta) / (2 r), the wheel profile coordinate S (NaN where the wheel ends)
    and the rail point (u, Z) (the rail's samples ``ur`` increase). The wheel's
    S = eta - half_bb + flange_back, its radius ``radius`` plus the spline (``wx``,
    ``wc``) at S and its slope tan(beta) the spline's derivative there
    (``cos(atan(t)) = 1 / sqrt(1 + t^2)``). ``kw``: the wheel's trace sample nearest
    ``u_c`` (:func:`nearest`), where its branch is taken."""
    cg, sg = math.cos(gamma), math.sin(gamma)
    ns = s.size
    wheel = np.empty((3, ns))
    interp_in_plane(s, u, z, eta, eta, u_c, z_c, cg, sg, kw, wheel)
    interp_in_plane(s, ur, zr, ur, zr, u_c, z_c, cg, sg, nearest_sorted(ur, u_c), out[2:5])
    S = np.empty(ns)
    for i in range(ns):
        e = wheel[1, i]
        S[i] = ((e if math.isfinite(e) else eta_c) - half_bb) + flange_back
    j = 0  # the wheel spline's height and slope at S: one interval search for both
    for i in range(ns):
        si = S[i]
        if math.isnan(si):
            slope = height = math.nan
        else:
            j = _interval_near(wx, si, j)
            slope = _piece(wc, j, si - wx[j], 1)
            height = _piece(wc, j, si - wx[j], 0)
        out[F, i] = wheel[0, i] - out[2, i]  # the rail's distance, before row 2 is S
        out[A_OF_S, i] = 1.0 / (math.sqrt(1.0 + slope * slope) * (2 * (radius + height)))
        out[WHEEL_S, i] = si if math.isfinite(wheel[1, i]) else math.nan


@numba.njit(cache=True)
def trace_gap(eta, r, dr, yawed, tan_psi, cz, sz, cx, sx, u_ws, radius, lo, hi, rx, rc, out):
    """The trace points of one wheel (axial positions ``eta``, radii ``r``, dr/deta ``dr``)
    moved into the side frame (yaw ``psi`` about the vertical axis, then roll ``phi``
    about the track axis: ``tan_psi``, ``cz, sz`` = cos, sin psi, ``cx, sx`` = cos, sin
    phi; lateral displacement ``u_ws``), those with ``lo < u < hi`` (above the rail, its
    spline ``rx``, ``rc``) written to ``out`` (5, n): eta, X, u, Z and the vertical gap
    g = Z - rail(u). Returns (how many, the least g, its first index)."""
    n = eta.size
    xs = np.empty(n)  # all points first (a loop without branches: vectorised)
    us = np.empty(n)
    zs = np.empty(n)
    if yawed:
        for i in range(n):
            sin_t = min(max(-tan_psi * dr[i], -1.0), 1.0)
            rs = r[i] * sin_t
            xs[i] = cz * rs - sz * eta[i]
            y = sz * rs + cz * eta[i]
            zw = -(r[i] * math.sqrt(1.0 - sin_t * sin_t))
            us[i] = cx * y - sx * zw + u_ws
            zs[i] = sx * y + cx * zw + radius
    else:  # no yaw: the trace is the wheel's lowest line (sin t = 0)
        for i in range(n):
            xs[i] = 0.0
            zw = -r[i]
            us[i] = cx * eta[i] - sx * zw + u_ws
            zs[i] = sx * eta[i] + cx * zw + radius
    m = 0
    j = 0
    g_min = math.inf
    k = 0
    for i in range(n):
        u = us[i]
        if lo < u < hi:
            z = zs[i]
            j = _interval_near(rx, u, j)
            g = z - _piece(rc, j, u - rx[j], 0)
            out[0, m] = eta[i]
            out[1, m] = xs[i]
            out[2, m] = u
            out[3, m] = z
            out[4, m] = g
            if g < g_min:
                g_min = g
                k = m
            m += 1
    return m, g_min, k


@numba.njit(cache=True)
def intervals(g, g_min, k, approach):
    """Index ranges [a, b) (rows of an (m, 2) array) of the connected runs where the gap
    above first contact ``g - g_min`` is at most ``approach``; the least gap's sample
    ``k`` is always in one."""
    n = g.size
    lim = max(approach, 0.0)
    out = np.empty((n // 2 + 1, 2), dtype=np.int64)
    m = 0
    i = 0
    while i < n:
        if g[i] - g_min <= lim or i == k:
            a = i
            while i < n and (g[i] - g_min <= lim or i == k):
                i += 1
            out[m, 0] = a
            out[m, 1] = i
            m += 1
        else:
            i += 1
    return out[:m]


@numba.njit(cache=True)
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


@numba.njit(cache=True)
def rigid_frame(eta, u, z, g_min, ur, zr, wx, wc, radius, half_bb, flange_back, u_c, z_c,
                gamma, eta_c, s, k0, out):
    """The tangent frame of a rigid contact point (:func:`rigid_point`): :func:`tangent_frame`
    of the wheel lowered into first contact (``z - g_min``), ``f`` shifted to 0 at its
    least value within 1 mm of the point (where ``f`` is finite at ``s[k0]`` = 0), NaN
    made infinite."""
    n = z.size
    zs = np.empty(n)
    for i in range(n):
        zs[i] = z[i] - g_min
    tangent_frame(eta, u, zs, ur, zr, wx, wc, radius, half_bb, flange_back, u_c, z_c,
                  gamma, eta_c, nearest(u, u_c), s, out)
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


@numba.njit(cache=True)
def overlap_run(g, u, approach, u_c):
    """On the trace (vertical gaps ``g`` at lateral positions ``u``) of a wheel lowered by
    ``approach`` beyond first contact: ``(g_min, lo, hi)``, the least gap and the run
    ``lo:hi`` of positive vertical interpenetration ``approach - (g - g_min)`` that holds
    the sample nearest ``u_c`` (``lo == hi`` when that sample does not overlap)."""
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


@numba.njit(cache=True)
def reference_frame(eta, u, z, g, approach, u_rigid, ur, zr, rx, rc, wx, wc, radius,
                    half_bb, flange_back, s, k0, power, out):
    """CONTACT's reference point of the patch around the rigid point at ``u_rigid``, the
    wheel lowered by ``approach`` beyond first contact, and its tangent frame
    (:func:`~.search.at_reference`), the frame written to ``out`` with ``f`` shifted so
    that its least value over the patch's own overlap is 0.

    Returns (ok, u, Z, gamma, overlap [m], wheel profile coordinate S above the point, lo,
    hi (the overlap's samples of ``s``)); ``ok`` False where the wheel does not overlap
    the rail there."""
    nan = math.nan
    g_min, lo, hi = overlap_run(g, u, approach, u_rigid)
    if hi <= lo:
        return False, nan, nan, nan, nan, nan, 0, 0
    total = 0.0
    su = 0.0
    sgam = 0.0
    u_lo = u[lo]
    u_hi = u[lo]
    increasing = True
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
            j = _interval_near(rx, ui, j)
            slope = _piece(rc, j, ui - rx[j], 1)
        sgam += w * math.atan(slope)
        u_lo = min(u_lo, u[i])
        u_hi = max(u_hi, u[i])
        if i > lo and not u[i] > u[i - 1]:
            increasing = False
    u_ref = su / total
    gamma = sgam / total
    z_ref = spline_at(rx, rc, u_ref, 0)
    # the wheel above the point: the trace's eta at u_ref (ordered by u)
    if increasing:
        eta_ref = interp_sorted(u_ref, u[lo:hi], eta[lo:hi])
    else:
        order = np.argsort(u[lo:hi], kind="mergesort")
        eta_ref = interp_sorted(u_ref, u[lo:hi][order], eta[lo:hi][order])
    wheel_s = (eta_ref - half_bb) + flange_back
    n = z.size
    zs = np.empty(n)
    k = 0  # the trace sample nearest u_ref (the first of equals), in the same pass
    best = abs(u[0] - u_ref)
    for i in range(n):
        zs[i] = (z[i] - g_min) - approach  # the wheel lowered by the approach
        d = abs(u[i] - u_ref)
        if d < best:
            best = d
            k = i
    tangent_frame(eta, u, zs, ur, zr, wx, wc, radius, half_bb, flange_back, u_ref, z_ref,
                  gamma, eta[k], k, s, out)
    f = out[F]
    ru_s = out[RAIL_U]
    # the patch's own overlap through the origin
    own = np.empty(s.size, dtype=np.bool_)
    for i in range(s.size):
        own[i] = math.isfinite(f[i]) and f[i] < 0 and ru_s[i] >= u_lo and ru_s[i] <= u_hi
    lo, hi = run_bounds(own, k0)
    if hi <= lo:
        return False, nan, nan, nan, nan, nan, 0, 0
    least = f[lo]
    for i in range(lo + 1, hi):
        least = min(least, f[i])
    overlap = -least
    for i in range(s.size):
        f[i] = f[i] + overlap if math.isfinite(f[i]) else math.inf
    return True, u_ref, z_ref, gamma, overlap, wheel_s, lo, hi


@numba.njit(cache=True)
def gap_on_grid(s, f, a_of_s, x0, dx, nx, y0, dy, ny, far, out):
    """``h = f(y) + A(y) x^2`` at the element centres of a grid ((nx, ny) written to
    ``out``) with ``f`` and ``A`` interpolated at ``y`` from the samples ``s`` as
    ``np.interp`` does (``f`` beyond the samples and where ``A`` is not finite: ``far``
    for f, 0 for A); ``far`` wherever the sum is not finite."""
    ns = s.size
    a_fin = np.empty(ns)
    for i in range(ns):
        a_fin[i] = a_of_s[i] if math.isfinite(a_of_s[i]) else 0.0
    fy = np.empty(ny)
    ay = np.empty(ny)
    for jy in range(ny):
        y = y0 + dy * jy
        if y < s[0] or y > s[ns - 1]:
            fy[jy] = far
        else:
            fy[jy] = interp_sorted(y, s, f)
        ay[jy] = interp_sorted(y, s, a_fin)
    for ix in range(nx):
        xi = x0 + dx * ix
        x2 = xi * xi
        for jy in range(ny):
            h = fy[jy] + ay[jy] * x2
            out[ix, jy] = h if math.isfinite(h) else far


@numba.njit(cache=True)
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
