"""ConvexGS: Vollebregt's block Gauss–Seidel solver for the steady-rolling tangential problem.

Each sweep visits the elements in contact row by row (increasing y), within a row from the
trailing to the leading edge (increasing x), as CONTACT's ``cnvxgs`` does. For element ``I``
the shift ``S = W + sum_J B_IJ p_J`` is evaluated with the current tractions (including
``p_I``), ``S0 = S - C p_I`` with the 2x2 self-coefficient ``C = B_II``, and:

* adhesion: ``p = -C^-1 S0``, relaxed ``p_I + omega_h (p - p_I)``; accepted when within
  the bound ``g = mu p_n`` (a relaxed value outside the bound is scaled onto it when the
  unrelaxed one is inside);
* slip otherwise: ``p = g (cos a, sin a)`` with ``S(p)`` anti-parallel to ``p``, a scalar
  Newton iteration on the angle ``a`` from ``-S0/|S0|``, then relaxation of the angle
  ``a_I + omega_s (a - a_I)``.

Convergence (as CONTACT): ``||p^k - p^(k-1)||_2 < eps_tau ||p^k||_2`` over the elements.
Defaults ``omega_h = omega_s = 0.5`` are CONTACT's for ConvexGS in steady rolling.

The sweep is compiled with numba (``cache=True``); a numpy implementation of the same sweep
(vectorised shift per element) is used where numba is missing or on request.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from ..errors import RailContactError, check_count, check_finite, check_positive
from ..halfspace.grid import Grid
from ..halfspace.operator import InfluenceOperator
from ..halfspace.sums import numpy_sum
from ..status import Work
from .rolling import slip_x, slip_y

try:
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    numba = None
    HAVE_NUMBA = False

EXTERIOR, ADHESION, SLIP = 0, 1, 2
ENGINES = ("auto", "numba", "numpy")
STALL_SWEEPS = 200
"""Sweeps without progress after which ConvexGS stops, not converged (a tolerance below
what round-off lets it reach would otherwise run to ``max_iterations``)."""
STALL_GAIN = 0.99
"""Progress: the relative traction change falls below this fraction of its best so far."""


SMALL_TURN = 0.05
"""Turns [rad] below which :func:`_turn` takes cos and sin from their Taylor series (cos
to the t^8 term, sin to the t^9 term: the first terms left out, t^10/10! and t^11/11!,
are below 3e-20, i.e. round-off) instead of the library's calls."""


NOT_TINY = 1e-140
"""Bounds [Pa] above this have squares far from the subnormal numbers (whose round-off is
not relative): the test of :data:`SURELY_BELOW` holds, and a traction's square that
underflows is surely below the bound's."""
NOT_HUGE = 1e140
"""Bounds [Pa] below this have squares far from overflow: a traction's square that
overflows is surely above the bound's."""


def _turn(c, s, t):
    """The unit vector ``(c, s)`` turned by the angle ``t`` [rad]."""
    if abs(t) < SMALL_TURN:
        t2 = t * t
        ct = 1.0 - t2 * (0.5 - t2 * (1.0 / 24 - t2 * (1.0 / 720 - t2 * (1.0 / 40320))))
        st = t * (1.0 - t2 * (1.0 / 6 - t2 * (1.0 / 120 - t2 * (1.0 / 5040 - t2 * (
            1.0 / 362880)))))
    else:
        ct = math.cos(t)
        st = math.sin(t)
    return c * ct - s * st, s * ct + c * st


def _angle(cd, sd):
    """The angle [rad] of the unit vector ``(cd, sd)`` in [-pi, pi) (``atan2``, with the
    reversed direction at -pi as the angle difference's ``(d + pi) % 2 pi - pi`` has it;
    for ``|sd / cd| < SMALL_TURN``, ``cd > 0``, atan's series to the x^11 term)."""
    if cd > 0.0 and abs(sd) < SMALL_TURN * cd:
        x = sd / cd
        x2 = x * x
        return x * (1.0 - x2 * (1.0 / 3 - x2 * (1.0 / 5 - x2 * (1.0 / 7 - x2 * (
            1.0 / 9 - x2 * (1.0 / 11))))))
    a = math.atan2(sd, cd)
    return -math.pi if a == math.pi else a


def _norm(x, y):
    """``hypot(x, y)``, by the square root of the sum of squares where no square under- or
    overflows (the library's hypot costs more)."""
    m2 = x * x + y * y
    if 1e-280 < m2 < 1e280:
        return math.sqrt(m2)
    return math.hypot(x, y)


def _element_solve(px, py, s0x, s0y, g, c11, c12, c21, c22, omega_h, omega_s):
    """New traction (px, py) [Pa] and state of one element; see the module docstring.

    In slip the Newton iteration on the angle ``a`` carries ``(cos a, sin a)`` and turns
    it by each step (:func:`_turn`: the steps are small, their cos and sin are series),
    and the relaxation turns the old direction by ``omega_s`` times the angle between the
    old and new ones (:func:`_angle`): the iterates of the angle form, to round-off, with
    no trigonometric call in the common case (186 -> 84 ns a slip element on warm steps)."""
    if g <= 0.0:
        return 0.0, 0.0, EXTERIOR
    det = c11 * c22 - c12 * c21
    fx = (-c22 * s0x + c12 * s0y) / det  # full adhesion: C p = -S0
    fy = (c21 * s0x - c11 * s0y) / det
    rx = px + omega_h * (fx - px)
    ry = py + omega_h * (fy - py)
    if NOT_TINY < g < NOT_HUGE:  # squares, not hypot: none near g under- or overflows
        g2 = g * g
        inside = rx * rx + ry * ry <= g2
        free = fx * fx + fy * fy <= g2
    else:  # (a bound whose square leaves the normal numbers: the library's hypot)
        inside = math.hypot(rx, ry) <= g
        free = math.hypot(fx, fy) <= g
    if inside:
        return rx, ry, ADHESION
    if free:
        nr = _norm_c(rx, ry)
        return rx * g / nr, ry * g / nr, ADHESION
    m = _norm_c(s0x, s0y)  # > 0 here: S0 = 0 is adhesion
    c0 = -s0x / m  # the isotropic estimate: p against S0
    sn0 = -s0y / m
    c = c0
    s = sn0
    for _ in range(20):
        f = s * s0x - c * s0y + g * (c11 * c * s + c12 * s * s - c21 * c * c - c22 * s * c)
        df = c * s0x + s * s0y + g * ((c11 - c22) * (c * c - s * s) + 2.0 * (c12 + c21) * s * c)
        if df == 0.0:
            break
        step = f / df
        c, s = _turn_c(c, s, -step)
        if abs(step) < 1e-13:
            break
    n = math.sqrt(c * c + s * s)
    c /= n
    s /= n
    if c * (s0x + g * (c11 * c + c12 * s)) + s * (s0y + g * (c21 * c + c22 * s)) > 0.0:
        c = c0  # Newton left the dissipative branch: keep the isotropic estimate
        s = sn0
    if px != 0.0 or py != 0.0:
        po = _norm_c(px, py)
        ox = px / po
        oy = py / po
        d = _angle_c(ox * c + oy * s, ox * s - oy * c)  # from the old direction to the new
        c, s = _turn_c(ox, oy, omega_s * d)
    return g * c, g * s, SLIP


def _block_sweep(rxx, rxy, ryx, ryy, ux, uy, g, px, py, dpx, dpy, state, lo, hi, r0, r1,
                 c11, c12, c21, c22, omega_h, omega_s, measure=1.0):
    """Gauss–Seidel over the elements of rows r0 .. r1-1 (numba-compiled).

    ``(ux, uy)`` is the shift ``W + B p`` for the tractions at the start of the block;
    the changes made inside the block (``dpx``, ``dpy``, zero on entry) are added by a
    direct sum, so every element sees the newest tractions of all elements. Fields are
    (ny, nx), kernels (2ny-1, 2nx-1) reversed so the inner sum runs over contiguous
    memory. Returns the squared norm of the updates, each scaled by ``measure`` (a power of
    two, :attr:`SweepProblem.measure`).
    """
    ny, nx = g.shape
    dif = 0.0
    for iy in range(r0, r1):
        for ix in range(lo[iy], hi[iy] + 1):
            gi = g[iy, ix]
            if gi <= 0.0:
                continue
            sx = ux[iy, ix]
            sy = uy[iy, ix]
            bx = nx - 1 - ix
            for jy in range(r0, r1):
                r = ny - 1 - iy + jy
                for jx in range(lo[jy], hi[jy] + 1):
                    k = bx + jx
                    qx = dpx[jy, jx]
                    qy = dpy[jy, jx]
                    sx += rxx[r, k] * qx + rxy[r, k] * qy
                    sy += ryx[r, k] * qx + ryy[r, k] * qy
            ox = px[iy, ix]
            oy = py[iy, ix]
            s0x = sx - c11 * ox - c12 * oy
            s0y = sy - c21 * ox - c22 * oy
            new_x, new_y, st = _element_solve_c(ox, oy, s0x, s0y, gi, c11, c12, c21, c22,
                                                omega_h, omega_s)
            px[iy, ix] = new_x
            py[iy, ix] = new_y
            dpx[iy, ix] += new_x - ox
            dpy[iy, ix] += new_y - oy
            state[iy, ix] = st
            dif += ((new_x - ox) * measure) ** 2 + ((new_y - oy) * measure) ** 2
    return dif


def _sweep_numpy(rxx, rxy, ryx, ryy, wx, wy, g, px, py, state, lo, hi, c11, c12, c21, c22,
                 omega_h, omega_s, measure=1.0):
    """The plain sweep: the shift of each element as a vectorised sum over all elements."""
    ny, nx = g.shape
    dif = 0.0
    for iy in range(ny):
        for ix in range(lo[iy], hi[iy] + 1):
            if g[iy, ix] <= 0.0:
                continue
            win = (slice(ny - 1 - iy, 2 * ny - 1 - iy), slice(nx - 1 - ix, 2 * nx - 1 - ix))
            sx = wx[iy, ix] + np.vdot(rxx[win], px) + np.vdot(rxy[win], py)
            sy = wy[iy, ix] + np.vdot(ryx[win], px) + np.vdot(ryy[win], py)
            ox, oy = px[iy, ix], py[iy, ix]
            new_x, new_y, st = _element_solve(ox, oy, sx - c11 * ox - c12 * oy,
                                              sy - c21 * ox - c22 * oy, g[iy, ix], c11, c12,
                                              c21, c22, omega_h, omega_s)
            px[iy, ix], py[iy, ix], state[iy, ix] = new_x, new_y, st
            dif += ((new_x - ox) * measure) ** 2 + ((new_y - oy) * measure) ** 2
    return dif


if HAVE_NUMBA:
    _turn_c = numba.njit(cache=True, nogil=True, inline="always")(_turn)
    _slip_x_c = numba.njit(cache=True, nogil=True, inline="always")(slip_x)
    _slip_y_c = numba.njit(cache=True, nogil=True, inline="always")(slip_y)
    _norm_c = numba.njit(cache=True, nogil=True, inline="always")(_norm)
    _angle_c = numba.njit(cache=True, nogil=True, inline="always")(_angle)
    _element_solve_c = numba.njit(cache=True, nogil=True, inline="always")(_element_solve)
    _block_sweep_numba = numba.njit(cache=True, nogil=True, fastmath=True)(_block_sweep)
else:  # pragma: no cover
    _turn_c = _turn
    _slip_x_c = slip_x
    _slip_y_c = slip_y
    _norm_c = _norm
    _angle_c = _angle
    _element_solve_c = _element_solve
    _block_sweep_numba = None

Embedding = tuple[Grid, tuple[slice, slice]]
"""A larger grid and the window ``(sx, sy)`` of it that a solve's grid is: the solvers'
``embed``."""

DIRECT_WORK = 60_000
"""Target size of a row block in the blocked sweep: (contact elements in the block)^2."""


def _sweep_blocked(kern, op, w_t, g, px, py, state, lo, hi, rows, c, omega_h, omega_s,
                   measure=1.0):
    """One Gauss–Seidel sweep, row block by row block (see :func:`_block_sweep`); between
    blocks the shift is brought up to date with one DC-FFT convolution of the block's
    changes. Same iterates as the plain sweep, at a fraction of its O(k^2) cost."""
    u = w_t + op.apply(np.stack([px.T, py.T])).transpose(0, 2, 1)
    ux, uy = np.ascontiguousarray(u[0]), np.ascontiguousarray(u[1])
    dpx = np.zeros_like(px)
    dpy = np.zeros_like(py)
    dif = 0.0
    for b, (r0, r1) in enumerate(rows):
        dif += _block_sweep_numba(*kern, ux, uy, g, px, py, dpx, dpy, state, lo, hi, r0, r1,
                                  *c, omega_h, omega_s, measure)
        if b + 1 < len(rows):
            du = op.apply(np.stack([dpx.T, dpy.T]))
            ux += du[0].T
            uy += du[1].T
            dpx[r0:r1] = 0.0
            dpy[r0:r1] = 0.0
    return dif


def _blocks_of(per_row: np.ndarray, work: int) -> list[list[int]]:
    """Split the rows that hold contact (``per_row``: contact elements per row) into blocks
    of about ``work^(1/2)`` elements: rows are added to a block until it holds
    ``total / nblocks`` elements (the last block takes the rest). Returns ``[start,
    stop]`` pairs of rows."""
    return _block_rows(per_row, work).tolist()


def _block_rows(per_row, work):
    """:func:`_blocks_of`'s blocks as an array (nblocks, 2), in one pass (compiled): the
    same integers as ``nonzero``, ``cumsum``, ``round`` (half to even) and
    ``searchsorted`` over the running count formed them."""
    n = per_row.size
    cum = np.empty(n, dtype=np.int64)
    total = 0
    nrows = 0
    first = last = 0
    for i in range(n):
        c = per_row[i]
        total += c
        cum[i] = total  # integers: "the block holds >= target" is exact
        if c != 0:
            if nrows == 0:
                first = i
            last = i
            nrows += 1
    out = np.empty((max(nrows, 1), 2), dtype=np.int64)
    if nrows == 0:
        return out[:0]
    q = total / math.sqrt(work)
    whole = math.floor(q)
    if q - whole > 0.5 or (q - whole == 0.5 and whole % 2 == 1):  # round(q)
        whole += 1
    nblocks = max(1, min(nrows, int(whole)))
    target = total / nblocks
    k = 0
    start = r = first
    base = 0
    for _ in range(nblocks - 1):
        while r < n and cum[r] - base < target:  # first row where the block is full
            r += 1
        if r >= n:
            break
        out[k, 0] = start
        out[k, 1] = r + 1
        k += 1
        start, base = r + 1, cum[r]
    out[k, 0] = start
    out[k, 1] = last + 1
    return out[:k + 1]


def _bound_layout(pn, mu, x0, dx, y0, dy, xi, eta, phi, offset, p0, st0, start):
    """The traction bound ``g = mu p_n`` [Pa] of the pressure ``pn`` (nx, ny) in the
    sweep layout (ny, nx), its states (adhesion where ``g > 0``, else exterior), the
    contact mask, per row the first and last contact element (``lo`` 1 > ``hi`` 0 in a
    row without contact) and their count; ``ok`` is False when a pressure is negative or
    not finite; the rigid slip ``wx``, ``wy`` [m] of the creepage ``(xi, eta, phi)`` on
    the grid ``(x0, dx, y0, dy)`` (:func:`~.rolling.rigid_slip_lines`' values, the same
    operations) in that layout; the largest ``g`` and the number of contact elements;
    the initial traction ``p`` (2, ny, nx): with ``start`` the start ``p0`` (2, nx, ny)
    clipped to the bound (:func:`_clip_start`, with the states ``st0``; ``start_ok``
    False when a value of it is not finite), else zero. One compiled call (numba) in
    place of a few dozen array operations; the float fields are returned as one array
    (5, ny, nx) (``g``, ``wx``, ``wy``, ``p``), ``lo``, ``hi`` and the counts as one
    (3, ny): each array a compiled function returns costs about 0.4 µs to box."""
    nx, ny = pn.shape
    fields = np.empty((5, ny, nx))
    g = fields[0]
    wx = fields[1]
    wy = fields[2]
    traction = fields[3:]
    rows = np.zeros((3, ny), dtype=np.int64)
    lo = rows[0]
    hi = rows[1]
    count = rows[2]
    lo[:] = 1
    state = np.zeros((ny, nx), dtype=np.int8)
    contact = np.zeros((ny, nx), dtype=np.bool_)
    shift = offset * dx
    ly = np.empty(nx)
    for ix in range(nx):  # rigid_slip_lines' W_y(x) and W_x(y)
        ly[ix] = _slip_y_c(dx, eta, phi, x0 + dx * float(ix), shift)
    for iy in range(ny):
        lx = _slip_x_c(dx, xi, phi, y0 + dy * float(iy))
        for ix in range(nx):
            wx[iy, ix] = lx
            wy[iy, ix] = ly[ix]
    ok = True
    gmax = 0.0
    for ix in range(nx):  # (the pressure read along its rows)
        for iy in range(ny):
            p = pn[ix, iy]
            if not (0.0 <= p < math.inf):
                ok = False
            gi = mu * p
            g[iy, ix] = gi
            if gi > 0.0:
                contact[iy, ix] = True
                state[iy, ix] = ADHESION
                if count[iy] == 0:
                    lo[iy] = ix
                hi[iy] = ix
                count[iy] += 1
                gmax = max(gmax, gi)
    total = 0
    for iy in range(ny):
        total += count[iy]
    start_ok = True
    if start:
        start_ok = _clip_start(p0, st0, g, traction)
    else:
        traction[:] = 0.0
    return fields, rows, state, contact, ok, gmax, total, start_ok


SURELY_BELOW = 1.0 - 1e-12
"""``x^2 + y^2 < SURELY_BELOW * c^2`` (in floating point, ``c`` > :data:`NOT_TINY`) proves
``hypot(x, y) < c`` (both sides are within a few units of round-off of the exact ones,
and ``math.hypot`` within one): the kernels skip ``hypot`` there, where it decides
nothing."""


def _clip_start(p0, st0, g, out):
    """An initial traction ``p0`` (2, nx, ny) [Pa] in the sweep layout ``out`` (2, ny, nx),
    scaled onto the bound ``g`` where it exceeds it or where the state ``st0`` (nx, ny;
    empty: none) marks a slip element, zero outside the contact; returns False when a
    value is not finite."""
    ny, nx = g.shape
    px = out[0]
    py = out[1]
    has_state = st0.size > 0
    ok = True
    for ix in range(nx):  # (the start read along its rows)
        for iy in range(ny):
            x = p0[0, ix, iy]
            y = p0[1, ix, iy]
            if not (math.isfinite(x) and math.isfinite(y)):
                ok = False
            gi = g[iy, ix]
            if gi <= 0:  # outside the contact
                x = 0.0
                y = 0.0
            elif (has_state and st0[ix, iy] == SLIP) or not (
                    gi > NOT_TINY and x * x + y * y < SURELY_BELOW * (gi * gi)):
                m = math.hypot(x, y)
                if (has_state and st0[ix, iy] == SLIP and m > 0) or m > gi:
                    s = gi / (m if m > 0 else 1.0)
                    x *= s
                    y *= s
            px[iy, ix] = x
            py[iy, ix] = y
    return ok


def _squares(px, py, out, measure=1.0):
    """``(px * px + py * py).sum()`` of the (ny, nx) C-contiguous ``px``, ``py``, each
    scaled by ``measure`` (a power of two, :attr:`SweepProblem.measure`; 1: the same
    bits): the squares (in ``out``) added in numpy's order
    (:mod:`~railcontact.halfspace.sums`)."""
    ny, nx = px.shape
    for iy in range(ny):
        for ix in range(nx):
            x = px[iy, ix] * measure
            y = py[iy, ix] * measure
            out[iy, ix] = x * x + y * y
    return numpy_sum(out)


MEASURED_RANGE = (2.0 ** -400, 2.0 ** 400)
"""Traction bounds [Pa] (about 3.9e-121 to 2.6e120) whose squared sums the convergence
measures form as they are; beyond it they are scaled (:attr:`SweepProblem.measure`): a
bound of 1e-170 Pa made every change square to 0, and a sweep "converged" at once."""


MAX_MEASURE_EXPONENT = 1000
"""The largest power of two (2**1000) a measure scales by: a largest bound below 2**-1000 Pa
(friction near 1e-300 and below; subnormal numbers from 2**-1022 down to 2**-1074) is
brought to 2**-74 and above, not scaled by a power of two that overflows."""


def _measure(largest_bound):
    """:attr:`SweepProblem.measure` for the largest traction bound [Pa] (also compiled, in
    the compiled solves)."""
    lo, hi = MEASURED_RANGE
    if lo <= largest_bound <= hi or not (0.0 < largest_bound < math.inf):
        return 1.0
    # (a subnormal bound, below 2**-1022: the power of two that brings it near 1 would
    # overflow; 2**1000 brings it to 2**-74 and above, whose squares are normal numbers)
    return math.ldexp(1.0, min(-math.frexp(largest_bound)[1], MAX_MEASURE_EXPONENT))


def _floor_above(contact_count, largest_bound, measure):
    """:attr:`SweepProblem.floor_above` of ``contact_count`` elements in contact, the
    largest bound [Pa] and the :attr:`~SweepProblem.measure` (also compiled)."""
    return 1.01e-9 * math.sqrt(contact_count) * largest_bound * measure


def _floor_of(g, measure, squares):
    """The convergence measure's floor ``1e-9 ||g||`` [Pa] of the bound ``g`` (ny, nx),
    scaled by ``measure``: the squares (in ``squares``) added in numpy's order, as
    ``((g * measure) ** 2).sum()`` adds them."""
    ny, nx = g.shape
    for iy in range(ny):
        for ix in range(nx):
            v = g[iy, ix] * measure
            squares[iy, ix] = v * v
    return 1e-9 * math.sqrt(numpy_sum(squares))


def _sweep_loop_of(sweep):
    """The sweeps of a Gauss–Seidel solve and their stopping rules around one sweep
    ``sweep(args)`` (which returns the squared norm of its traction change [Pa^2], scaled
    by the measure): one source, run as Python (``sweep`` a Python function,
    :meth:`SweepProblem.iterate`) or compiled with a compiled sweep (SteadyGS's compiled
    solve: the function made of this one with numba, the sweep a compiled function it
    calls by name, a constant of the code, so that the caller is cached as any kernel).
    Both run the same compiled kernels (:func:`_squares`, :func:`_floor_of`) in the same
    order: the same bits."""

    def iterate(args, px, py, g, squares, measure, floor_above, tolerance, max_iterations,
                stall_sweeps, stall_gain, active):
        """Sweep until ``||p^k - p^(k-1)|| < tolerance ||p^k||`` (the norms of the
        traction ``px``, ``py`` (ny, nx) [Pa] and of its change, scaled by ``measure``),
        stopping when the error is not finite or has not fallen below ``stall_gain`` of
        its best in ``stall_sweeps`` sweeps, at ``max_iterations`` sweeps at most. The
        norm is at least the floor ``1e-9 ||g||`` (formed only below ``floor_above``,
        :attr:`SweepProblem.floor_above`). Not ``active`` (no contact or no creepage):
        no sweep, converged. ``squares`` (ny, nx): work. Returns ``(sweeps, error,
        converged, stalled, history)``."""
        hist = np.empty(max(min(max_iterations, 64), 1))
        have_floor = False
        floor = 0.0
        best = math.inf
        best_its = 0
        its = 0
        err = 0.0
        converged = False
        stalled = False
        if not active:
            converged = True
        while active and its < max_iterations:
            its += 1
            dif = sweep(args)
            norm = math.sqrt(_squares(px, py, squares, measure))  # (px*px + py*py).sum()
            if not norm > floor_above:
                if not have_floor:
                    floor = _floor_of(g, measure, squares)
                    have_floor = True
                # max(norm, floor): 0 only when mu p underflows (mu ~ 1e-300)
                scale = floor if floor > norm else norm
            else:
                scale = norm
            if scale > 0:
                err = math.sqrt(dif) / scale
            elif dif == 0:
                err = 0.0
            else:
                err = math.inf
            if its > hist.size:
                more = np.empty(2 * hist.size)
                more[:hist.size] = hist
                hist = more
            hist[its - 1] = err
            if not math.isfinite(err):
                break
            if err < tolerance:
                converged = True
                break
            if err < stall_gain * best:
                best = err
                best_its = its
            elif its - best_its >= stall_sweeps:  # round-off: a tolerance out of reach
                stalled = True
                break
        return its, err, converged, stalled, hist[:its].copy()

    return iterate


_NO_STATE = np.zeros((0, 0), dtype=np.int8)
_NO_START = np.zeros((2, 0, 0))

if HAVE_NUMBA:
    _clip_start = numba.njit(cache=True, nogil=True)(_clip_start)
    _bound_layout = numba.njit(cache=True, nogil=True)(_bound_layout)
    _squares = numba.njit(cache=True, nogil=True)(_squares)
    _floor_of = numba.njit(cache=True, nogil=True)(_floor_of)
    _measure_c = numba.njit(cache=True, nogil=True)(_measure)
    _floor_above_c = numba.njit(cache=True, nogil=True)(_floor_above)
else:  # pragma: no cover
    _measure_c = _measure
    _floor_above_c = _floor_above


@lru_cache(maxsize=16)
def _gs_kernels(operator: InfluenceOperator) -> tuple[np.ndarray, ...]:
    """The operator's 2x2 kernels reversed and transposed to (2ny-1, 2nx-1) for the sweep."""
    k = operator.kernels
    return tuple(np.ascontiguousarray(k[a, b][::-1, ::-1].T) for a in (0, 1) for b in (0, 1))


@dataclass(frozen=True)
class TangentialResult:
    """Solution of the steady-rolling tangential problem (SI units).

    Attributes
    ----------
    grid
        The grid.
    traction
        Tangential traction (p_x, p_y) on body 1 [Pa], shape (2, nx, ny).
    state
        0 exterior, 1 adhesion, 2 slip, shape (nx, ny).
    slip_of
        ``slip_of()`` forms the relative slip ``S/dx`` (slip velocity divided by rolling
        speed) [-], (2, nx, ny), of the solve: it costs one more product with the operator,
        which a time step never needs, so it is formed only by an explicit call
        (:meth:`relative_slip`), each time anew; None after unpickling.
    force
        (F_x, F_y) [N].
    spin_moment
        M_z = sum (x p_y - y p_x) dA about the grid origin [N m].
    slip_area_ratio
        Slip elements / contact elements [-].
    max_traction
        Largest ``|p|`` [Pa].
    iterations, converged, message, wall_time, error, history
        As for the normal solver; ``error`` is ``||dp|| / ||p||`` of the last sweep.

    A pickled result carries its relative slip formed (the function of its solve is not
    picklable), which :meth:`relative_slip` then returns.
    """

    grid: Grid
    traction: np.ndarray
    state: np.ndarray
    slip_of: Callable[[], np.ndarray] | None = field(repr=False, compare=False)
    force: tuple[float, float]
    spin_moment: float
    slip_area_ratio: float
    max_traction: float
    iterations: int
    converged: bool
    message: str
    wall_time: float
    error: float
    history: np.ndarray = field(repr=False)
    _formed_slip: np.ndarray | None = field(default=None, repr=False, compare=False)

    def relative_slip(self) -> np.ndarray:
        """The relative slip ``S/dx`` [-], (2, nx, ny): zero outside the slip area, in it
        opposite to the traction (formed by this call: a product with the operator)."""
        if self._formed_slip is not None:
            return self._formed_slip
        return np.asarray(self.slip_of())

    def __getstate__(self) -> dict:
        """Pickled with its slip formed (the function that forms it is a closure)."""
        state = dict(self.__dict__)
        if state.get("_formed_slip") is None:
            state["_formed_slip"] = self.relative_slip()
        state["slip_of"] = None
        return state

    @property
    def work(self) -> Work:
        """The solve's work (:class:`~railcontact.status.Work`, the solver results'
        record): its sweeps and wall time [s]."""
        return Work(tangential_iterations=self.iterations, load_passes=0,
                    seconds=self.wall_time)


def _summarised(grid: Grid, sx, sy, sm, ncon, nslip, pmax
                ) -> tuple[tuple[float, float], float, float, float]:
    """Forces (F_x, F_y) [N], M_z [N m], slip-area ratio and largest ``|p|`` [Pa] of a
    traction field from its :func:`_summary_sums`."""
    da = grid.element_area
    ratio = float(nslip / ncon) if ncon else 0.0
    return (float(sx * da), float(sy * da)), float(sm * da), ratio, float(pmax)


def _embedded_slip(slip_of: Callable[[], np.ndarray], shape: tuple[int, int], sx: slice,
                   sy: slice) -> Callable[[], np.ndarray]:
    """The slip (2, nx, ny) on a larger grid of shape ``shape`` of a solve on its window
    ``(sx, sy)`` (``slip_of``: the window's), zero outside it: formed when called."""
    def slip() -> np.ndarray:
        out = np.zeros((2, *shape))
        out[:, sx, sy] = slip_of()
        return out
    return slip


def _counts_and_max(traction, state):
    """Elements in contact and in slip, and the largest ``|p|`` [Pa] (0 without elements, NaN
    when a traction is NaN), in one pass (a maximum is the same in any order)."""
    ncon = 0
    nslip = 0
    pmax = 0.0
    nan = False
    for ix in range(state.shape[0]):
        for iy in range(state.shape[1]):
            st = state[ix, iy]
            if st != EXTERIOR:
                ncon += 1
                if st == SLIP:
                    nslip += 1
            x = traction[0, ix, iy]
            y = traction[1, ix, iy]
            if pmax > NOT_TINY and x * x + y * y < SURELY_BELOW * (pmax * pmax):
                continue  # |p| < pmax, surely
            h = math.hypot(x, y)
            if h > pmax:
                pmax = h
            elif h != h:
                nan = True
    return ncon, nslip, (math.nan if nan else pmax)


def _summary_sums(swept, state, x0, dx, y0, dy):
    """The sums of the result's summary (:func:`_summarised`) of the traction ``swept``
    (2, ny, nx) (C order) with the states (nx, ny): ``sum p_x``, ``sum p_y`` and
    ``sum (x p_y - y p_x)`` (``x``, ``y`` the element centres as :attr:`Grid.x`,
    :attr:`Grid.y` form them), each added in numpy's order over the traction's memory, as
    ``traction[k].sum()`` and the sum of numpy's broadcast product (laid out as
    ``traction[1]``) add them; and
    :func:`_counts_and_max`."""
    ny, nx = swept.shape[1], swept.shape[2]
    arm = np.empty((ny, nx))
    for iy in range(ny):
        y = y0 + dy * float(iy)
        for ix in range(nx):
            arm[iy, ix] = (x0 + dx * float(ix)) * swept[1, iy, ix] - y * swept[0, iy, ix]
    ncon, nslip, pmax = _counts_and_max(swept.transpose(0, 2, 1), state)
    return (numpy_sum(swept[0]), numpy_sum(swept[1]), numpy_sum(arm), ncon, nslip, pmax)


def _embedded_fields(swept, state, nx, ny, i0, j0, x0, dx, y0, dy):
    """The traction ``swept`` (2, ny', nx') [Pa] and states ``state`` (ny', nx') of a
    solve in the sweep layout as fields (2, nx, ny) and (nx, ny) (int8) of a larger grid
    whose elements ``i0 + ix``, ``j0 + iy`` they are, zero elsewhere (what ``np.zeros``
    and a slice assignment of the solver's fields give), and :func:`_summary_sums` of
    the solve's own fields on its grid ``(x0, dx, y0, dy)``: one compiled call."""
    wy, wx = state.shape
    traction = np.zeros((2, nx, ny))
    st = np.zeros((nx, ny), dtype=np.int8)
    for ix in range(wx):
        for iy in range(wy):
            traction[0, i0 + ix, j0 + iy] = swept[0, iy, ix]
            traction[1, i0 + ix, j0 + iy] = swept[1, iy, ix]
            st[i0 + ix, j0 + iy] = state[iy, ix]
    return (traction, st) + _summary_sums(swept, state.T, x0, dx, y0, dy)


if HAVE_NUMBA:
    _block_rows = numba.njit(cache=True, nogil=True)(_block_rows)
    _counts_and_max = numba.njit(cache=True, nogil=True)(_counts_and_max)
    _summary_sums = numba.njit(cache=True, nogil=True)(_summary_sums)
    _embedded_fields = numba.njit(cache=True, nogil=True)(_embedded_fields)


def _bound_of(friction, pressure: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The traction bound ``mu p_n`` [Pa] of a coefficient of friction given per element
    (an array broadcastable to the grid's ``shape`` (nx, ny), e.g. (1, ny): one per
    lateral row), checked finite and non-negative; the pressure as it is when its shape
    is not the grid's (the caller's check names it)."""
    mu = np.asarray(friction, dtype=float)
    try:
        mu = np.broadcast_to(mu, shape)
    except ValueError:
        raise RailContactError(f"friction must be a number or an array broadcastable to the "
                               f"grid {shape}, got shape {mu.shape}") from None
    if not np.all(np.isfinite(mu)) or np.any(mu < 0):
        raise RailContactError("friction must be finite and non-negative in every element")
    if pressure.shape != shape or not (np.all(np.isfinite(pressure))
                                       and pressure.min(initial=0.0) >= 0.0):
        return pressure  # (refused as it is)
    return mu * pressure


@dataclass
class SweepProblem:
    """A steady-rolling problem in the Gauss–Seidel solvers' layout, and their common loop.

    Fields are (ny, nx), x contiguous: the traction bound ``g = mu p_n`` [Pa], the rigid
    slip ``wx``, ``wy`` [m] (:func:`~.rolling.rigid_slip`), the traction ``px``,
    ``py`` [Pa] being solved for (the two rows of one array ``p`` (2, ny, nx):
    ``p.transpose(0, 2, 1)`` is the traction (2, nx, ny) without a copy), the element
    states, the contact mask and per row the first and last element in contact (``lo``,
    ``hi``) and their count. ConvexGS and SteadyGS differ only in their sweep.
    """

    grid: Grid
    operator: InfluenceOperator
    g: np.ndarray
    wx: np.ndarray
    wy: np.ndarray
    p: np.ndarray
    px: np.ndarray
    py: np.ndarray
    state: np.ndarray
    contact: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    row_counts: np.ndarray
    rolling: bool
    tolerance: float
    max_iterations: int
    use_numba: bool
    largest_bound: float
    """The largest ``g`` [Pa]."""
    contact_count: int
    """Elements in contact."""
    measure: float = 1.0
    """A power of two by which the tractions are scaled in the convergence measures (their
    squared sums): 1 for traction bounds from :data:`MEASURED_RANGE` [Pa], else the one
    that brings the largest bound to [0.5, 1), so that the squares neither underflow nor
    overflow (exact: the measure's ratio is the same)."""

    @classmethod
    def set_up(cls, grid: Grid, operator: InfluenceOperator, pressure, friction, creepage,
               initial_traction, initial_state, tolerance, max_iterations, omega_h, omega_s,
               engine, spin_offset) -> SweepProblem:
        """Check the inputs of a solver (see :func:`solve_tangential`) and lay them out."""
        inputs = checked_inputs(grid, operator, pressure, friction, creepage,
                                initial_traction, initial_state, spin_offset)
        pn, mu, xi, eta, phi, spin_offset, rolling, p0, st0, start, start_error = inputs
        fields, (lo, hi, count), state, contact, ok, gmax, ncon, start_ok = _bound_layout(
            pn, mu, grid.x0, grid.dx, grid.y0, grid.dy, xi, eta, phi, spin_offset, p0, st0,
            start)
        if not ok:
            raise pressure_error(grid)
        tolerance, max_iterations, use_numba = checked_settings(tolerance, max_iterations,
                                                                omega_h, omega_s, engine)
        if start_error is not None or not start_ok:
            raise start_failure(grid, start_error)
        g, wx, wy, p = fields[0], fields[1], fields[2], fields[3:]
        return cls(
            grid=grid, operator=operator, g=g, wx=wx, wy=wy, p=p, px=p[0], py=p[1], state=state,
            contact=contact, lo=lo, hi=hi, row_counts=count, rolling=rolling, tolerance=tolerance,
            max_iterations=max_iterations, use_numba=use_numba, largest_bound=float(gmax),
            contact_count=int(ncon), measure=_measure(float(gmax)))

    def solve(self, sweep: Callable[[], float], name: str, stall_sweeps: int,
              t0: float, embed: Embedding | None = None) -> TangentialResult:
        """Sweep until ``||p^k - p^(k-1)|| < tolerance ||p^k||`` (``sweep()`` returns the
        squared norm of its change), stopping when the error is not finite or has not
        fallen below :data:`STALL_GAIN` of its best in ``stall_sweeps`` sweeps; the result
        on the problem's grid, or with ``embed`` on that larger grid (see
        :func:`solve_tangential`)."""
        return self.result(name, stall_sweeps, t0, embed, *self.iterate(sweep, stall_sweeps))

    @property
    def floor_above(self) -> float:
        """The norm [Pa] (scaled by :attr:`measure`) above which the convergence measure's
        floor ``1e-9 ||g||`` cannot matter: ``1.01e-9 sqrt(ncon) max(g)`` bounds it, so the
        floor is formed only for a norm below this (it is then the same value as always)."""
        return _floor_above(self.contact_count, self.largest_bound, self.measure)

    def iterate(self, sweep: Callable[[], float], stall_sweeps: int
                ) -> tuple[int, float, bool, bool, np.ndarray]:
        """:meth:`solve`'s sweeps (:func:`_sweep_loop_of`'s loop, run as Python):
        ``(sweeps, error, converged, stalled, history)``."""
        loop = _sweep_loop_of(lambda _: sweep())
        return loop(None, self.px, self.py, self.g, np.empty_like(self.px), self.measure,
                    self.floor_above, self.tolerance, self.max_iterations, stall_sweeps,
                    STALL_GAIN, self.contact_count > 0 and self.rolling)

    def result(self, name: str, stall_sweeps: int, t0: float, embed: Embedding | None,
               its: int, err: float, converged: bool, stalled: bool, hist: np.ndarray
               ) -> TangentialResult:
        """The :class:`TangentialResult` of the sweeps :meth:`iterate` ran: ``its``
        sweeps, the last ``err``, whether they converged or stalled, the error after each
        (``hist``)."""
        grid = self.grid
        if embed is None:
            # (2, nx, ny) over the sweep layout's memory, as np.stack([px.T, py.T]) lays it
            # out (its sums keep their order, so their bits): one copy of ``p``
            traction = self.p.transpose(0, 2, 1).copy(order="K")
            st = np.ascontiguousarray(self.state.T)
            sums = _summary_sums(traction.transpose(0, 2, 1), st, grid.x0, grid.dx,
                                 grid.y0, grid.dy)
        else:  # the fields on the larger grid; the sums over the problem's, as above
            big, (sx, sy) = embed
            traction, st, *sums = _embedded_fields(self.p, self.state, big.nx, big.ny,
                                                   sx.start, sy.start, grid.x0, grid.dx,
                                                   grid.y0, grid.dy)
        return result_record(name, stall_sweeps, t0, grid, embed, self.tolerance,
                             self.contact_count > 0, self.rolling, its, err, converged,
                             stalled, hist, traction, st, sums,
                             slip_function(self.operator, grid.dx, self.wx, self.wy, self.p,
                                           self.state.T))


def slip_function(operator: InfluenceOperator, dx: float, wx: np.ndarray, wy: np.ndarray,
                  p: np.ndarray, state: np.ndarray) -> Callable[[], np.ndarray]:
    """The function that forms the relative slip ``S/dx = (W + B p)/dx`` [-] (2, nx, ny)
    of a solve's traction ``p`` (2, ny, nx) [Pa] with the rigid slip ``wx``, ``wy`` [m]
    (the sweep layout) and the states (nx, ny), zero outside the slip area (in adhesion
    it is zero at convergence; exterior elements are not in contact); ``dx`` [m] the
    element length. The arrays are the solver's, not changed once it returns."""
    def slip() -> np.ndarray:
        w = np.stack([wx.T, wy.T])
        out = (w + operator.apply(np.stack([p[0].T, p[1].T]))) / dx
        out[:, state != SLIP] = 0.0
        return out
    return slip


def result_record(name: str, stall_sweeps: int, t0: float, grid: Grid,
                  embed: Embedding | None, tolerance: float, in_contact: bool, rolling: bool,
                  its: int, err: float, converged: bool, stalled: bool, hist: np.ndarray,
                  traction: np.ndarray, st: np.ndarray, sums, slip: Callable[[], np.ndarray]
                  ) -> TangentialResult:
    """The :class:`TangentialResult` of a solve on ``grid`` (with ``embed`` given on its
    larger grid): ``its`` sweeps (:func:`_sweep_loop_of`), the last ``err``, whether they
    converged or stalled, the error after each (``hist``); the traction and states on the
    result's grid, :func:`_summary_sums`' ``sums`` of the solve's own grid and the
    solve's ``slip`` function (:func:`slip_function`)."""
    force, mz, ratio, pmax = _summarised(grid, *sums)
    if embed is not None:
        big, (sx, sy) = embed
        slip = _embedded_slip(slip, big.shape, sx, sy)
        grid = big
    if not in_contact:
        message = "no contact: zero normal pressure"
    elif not rolling:
        message = "zero creepage: zero traction, no iterations"
    elif converged:
        message = f"{name} converged in {its} sweeps (eps = {err:.3g} < {tolerance:g})"
    else:
        message = (f"{name} not converged: eps = {err:.3g} after {its} sweeps "
                   f"(tolerance {tolerance:g})")
        if stalled:
            message += (f"; stalled: eps has not fallen below {STALL_GAIN:g} of its best "
                        f"in {stall_sweeps} sweeps")
    return TangentialResult(
        grid=grid, traction=traction, state=st, slip_of=slip, force=force,
        spin_moment=mz, slip_area_ratio=ratio, max_traction=pmax, iterations=its,
        converged=converged, message=message, wall_time=time.perf_counter() - t0, error=err,
        history=hist)


def checked_inputs(grid: Grid, operator: InfluenceOperator, pressure, friction, creepage,
                   initial_traction, initial_state, spin_offset) -> tuple:
    """The problem's inputs checked (the first of the solvers' checks, raising as they
    find a fault) and as the set-up's compiled layout (:func:`_bound_layout`) reads them:
    ``(pn, mu, xi, eta, phi, spin_offset, rolling, p0, st0, start, start_error)``, the
    pressure ``pn`` (nx, ny) [Pa] (the bound ``mu p_n`` with ``mu`` 1 where the friction
    is given per element), the start's arrays and whether there is one; a fault of the
    start (``start_error``, a message or None) and of the pressure's values
    (:func:`pressure_error`, which the layout finds) are raised after the pressure's and
    the settings' checks (:func:`checked_settings`), in that order."""
    shape = grid.shape
    if operator.components != "xy" or (operator.nx, operator.ny) != shape:
        raise RailContactError("operator must be the 'xy' steady-rolling operator of "
                               "this grid")
    pn = np.ascontiguousarray(pressure, dtype=float)  # (one compiled layout)
    if type(friction) is float or np.ndim(friction) == 0:  # (a number: no numpy call)
        mu = check_positive("friction", friction, allow_zero=True)
    else:  # per element: the bound mu p_n formed here, the layout's own mu 1 (exact)
        pn = _bound_of(friction, pn, shape)
        mu = 1.0
    if len(creepage) != 3:
        raise RailContactError(f"creepage must be (xi, eta, phi), got {creepage!r}")
    xi = check_finite("xi", creepage[0], "-")  # (rigid_slip_lines' checks)
    eta = check_finite("eta", creepage[1], "-")
    phi = check_finite("phi", creepage[2], "1/m")
    spin_offset = check_finite("spin_offset", spin_offset)
    rolling = xi != 0.0 or eta != 0.0 or phi != 0.0
    start_error = None  # (raised after the other checks)
    p0, st0 = _NO_START, _NO_STATE
    if initial_traction is not None and rolling:  # no creepage: no traction, exactly
        p0, st0, start_error = _start_arrays(initial_traction, initial_state, shape)
    start = initial_traction is not None and rolling and start_error is None
    if pn.shape != shape:
        raise pressure_error(grid)
    return pn, mu, xi, eta, phi, spin_offset, rolling, p0, st0, start, start_error


def pressure_error(grid: Grid) -> RailContactError:
    """The error of a pressure of the wrong shape or with a value that is negative or not
    finite."""
    return RailContactError(f"pressure must be finite, non-negative, shape {grid.shape}")


def start_failure(grid: Grid, start_error: str | None) -> RailContactError:
    """The error of an initial traction or state of the wrong shape (``start_error``) or
    with a value that is not finite (None)."""
    return RailContactError(start_error or "initial_traction must be finite, "
                            f"shape {(2, *grid.shape)}")


def checked_settings(tolerance, max_iterations, omega_h, omega_s, engine
                     ) -> tuple[float, int, bool]:
    """The solvers' settings checked (after the pressure's values): the tolerance, the
    sweep limit and whether the sweeps are compiled (numba). Settings of the plain types
    (the time step's, the same at every solve) are checked once (:data:`_checked_once`)."""
    if (type(tolerance) is float and type(max_iterations) is int
            and type(omega_h) is float and type(omega_s) is float and type(engine) is str):
        return _checked_once(tolerance, max_iterations, omega_h, omega_s, engine)
    return _settings_of(tolerance, max_iterations, omega_h, omega_s, engine)


def _settings_of(tolerance, max_iterations, omega_h, omega_s, engine
                 ) -> tuple[float, int, bool]:
    """:func:`checked_settings`' checks."""
    tolerance = check_positive("tolerance", tolerance)
    for name, om in (("omega_h", omega_h), ("omega_s", omega_s)):
        if not 0.0 < check_finite(name, om) <= 1.5:
            raise RailContactError(f"{name} must lie in (0, 1.5], got {om}")
    max_iterations = check_count("max_iterations", max_iterations)
    if engine not in ENGINES:
        raise RailContactError(f"engine must be one of {ENGINES}, got {engine!r}")
    if engine == "numba" and not HAVE_NUMBA:
        raise RailContactError("engine 'numba' requested but numba is not installed")
    return tolerance, max_iterations, engine in ("auto", "numba") and HAVE_NUMBA


_checked_once = lru_cache(maxsize=16)(_settings_of)
""":func:`_settings_of` of hashable settings, formed once per value (an error is raised
at every call: it is not kept)."""


def _start_arrays(initial_traction, initial_state, shape: tuple[int, int]
                  ) -> tuple[np.ndarray, np.ndarray, str | None]:
    """An initial traction (2, nx, ny) [Pa] and adhesion/slip map (nx, ny) as the arrays
    the compiled clip (:func:`_clip_start`, in :func:`_bound_layout`) reads (float; int8,
    empty without a map), and the error of a wrong shape (None: none)."""
    p0 = np.ascontiguousarray(initial_traction, dtype=float)  # (one compiled layout)
    if p0.shape != (2, *shape):
        return _NO_START, _NO_STATE, f"initial_traction must be finite, shape {(2, *shape)}"
    st0 = _NO_STATE
    if initial_state is not None:
        st0 = np.ascontiguousarray(initial_state)
        if st0.shape != shape:
            return _NO_START, _NO_STATE, f"initial_state must have shape {shape}"
        if st0.dtype != np.int8:  # (the compiled clip reads the states as int8)
            st0 = np.where(st0 == SLIP, SLIP, 0).astype(np.int8)
    return p0, st0, None


def solve_tangential(
    grid: Grid,
    operator: InfluenceOperator,
    pressure: np.ndarray,
    friction: float | np.ndarray,
    creepage: tuple[float, float, float],
    *,
    initial_traction: np.ndarray | None = None,
    initial_state: np.ndarray | None = None,
    tolerance: float = 1e-2,
    max_iterations: int = 1000,
    omega_h: float = 0.5,
    omega_s: float = 0.5,
    engine: str = "auto",
    spin_offset: float = 1.0 / 6.0,
    embed: Embedding | None = None,
) -> TangentialResult:
    """Solve steady rolling with Coulomb friction by ConvexGS.

    Parameters
    ----------
    grid
        Potential-contact grid, the same as the normal solution's.
    operator
        Steady-rolling operator from :func:`railcontact.tangential.rolling_operator`.
    pressure
        Normal pressure [Pa], shape (nx, ny) (from the normal solution).
    friction
        Coefficient of friction mu [-]: a number, or one per element (an array
        broadcastable to the grid (nx, ny), e.g. (1, ny) for one per lateral row); the
        traction bound of an element is ``mu p_n`` with its own mu.
    creepage
        (xi, eta, phi): longitudinal, lateral creepage [-] and spin [1/m].
    initial_traction
        Initial estimate (2, nx, ny) [Pa]; default zero traction (all adhesion), the paper's
        "w/o initial estimate". It is clipped to the traction bound.
    initial_state
        Adhesion/slip map (nx, ny) of the estimate (1 adhesion, 2 slip): slip elements start
        on the traction bound.
    tolerance
        eps_tau for ``||dp|| < eps_tau ||p||``.
    max_iterations
        Largest number of sweeps.
    omega_h, omega_s
        Relaxation in adhesion and slip (0 < omega <= 1.5).
    engine
        "auto" (numba when installed), "numba" or "numpy".
    spin_offset
        Where in the rolling step the spin part of the rigid slip is taken, as a fraction
        of dx (see :func:`railcontact.tangential.rigid_slip`).
    embed
        ``(whole, (sx, sy))``: ``grid`` is the window ``sx``, ``sy`` (element slices) of
        the grid ``whole`` (as :func:`railcontact.contact.patch.contact_window` gives
        it), and the result is given on ``whole``: traction, slip and states zero
        outside the window (forces and moments are the window's, which holds every
        element in contact). Default: on ``grid``.
    """
    t0 = time.perf_counter()
    prob = SweepProblem.set_up(grid, operator, pressure, friction, creepage, initial_traction,
                               initial_state, tolerance, max_iterations, omega_h, omega_s,
                               engine, spin_offset)
    kern = _gs_kernels(operator)
    c = operator.self_coefficient
    cc = (float(c[0, 0]), float(c[0, 1]), float(c[1, 0]), float(c[1, 1]))
    rows = _blocks_of(prob.row_counts, DIRECT_WORK)
    w_t = np.stack([prob.wx, prob.wy])
    oh, os_ = float(omega_h), float(omega_s)

    def sweep() -> float:
        if prob.use_numba:
            return _sweep_blocked(kern, operator, w_t, prob.g, prob.px, prob.py, prob.state,
                                  prob.lo, prob.hi, rows, cc, oh, os_, prob.measure)
        return _sweep_numpy(*kern, prob.wx, prob.wy, prob.g, prob.px, prob.py, prob.state,
                            prob.lo, prob.hi, *cc, oh, os_, prob.measure)

    return prob.solve(sweep, "ConvexGS", STALL_SWEEPS, t0, embed)
