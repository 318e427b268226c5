"""SteadyGS: Vollebregt's Gauss–Seidel solver specialised for steady rolling.

The algorithm is the one of CONTACT's ``stdygs`` (E.A.H. Vollebregt, CONTACT,
``src/m_solvpt.f90``; Vollebregt, "A Gauss–Seidel type solver for special convex programs,
with application to frictional contact mechanics", JOTA 87, 1995), written anew in this
package's conventions (rolling in +x, traction ``(2, nx, ny)``, the slip
``S = W + B p`` of :mod:`railcontact.tangential.rolling`).

Idea
----
With ``B[k] = A[k] - A[k + 1]`` the slip is ``S = W + A dp`` with the *differences*
``dp_I = p_I - p_{I+1}`` along the rolling direction (``I + 1`` is the upstream neighbour,
towards the leading edge; ``p`` is zero off the grid). In the adhesion area the natural
unknown is ``dp`` (``A dp = -W`` is a problem of the normal problem's kind), whereas
ConvexGS updates ``p`` element by element, which moves the information from the leading
edge into the adhesion area only one element per sweep. SteadyGS therefore visits each row
from the trailing to the leading edge (increasing x), and a change ``delta`` of the
traction of element ``(ix, iy)`` is applied with the ``dp`` of the adhesion elements
behind it held fixed: the traction of the whole run of adhesion elements
``jx < j < ix`` trailing ``ix`` (up to the first slip or exterior element ``jx``) moves
by ``delta`` as well. In ``dp`` terms this is ``+delta`` at ``ix`` and ``-delta`` at
``jx``, so the element sees the 2x2 coefficient

    C = A[0] - A[ix - jx] = sum_{m = 0}^{ix - jx - 1} B[m]     (x offsets, same row)

instead of ConvexGS's ``B[0]``. With it the element is solved as in ConvexGS:
``S0 = S - C p_I``; adhesion ``p = -C^-1 S0`` (relaxed by ``omega_h``) when within the
bound ``g = mu p_n``, else slip ``p = g (cos a, sin a)`` with ``S0 + C p`` anti-parallel
to ``p`` (Newton on ``a``, relaxed by ``omega_s``). A trailing adhesion element pushed
over its bound by the shift is put on it (as CONTACT does), and the shift continues from
there.

Implementation
--------------
The shift of every element is exact at every element update: as in ConvexGS the rows are
grouped into blocks; the shift at the start of a block comes from one DC-FFT product
with the steady-rolling operator ``B`` and the changes made inside the block are added by
direct summation with ``B`` (all traction changes, including those of the shifted
adhesion runs): at the start of a row those of the block's rows before it, for the whole
row at once (16 to 32 targets at a time, vectorised over the targets), then at each
element those of its own row so far. Blocks hold about
:data:`BLOCK_SCALE` ``sqrt(nx ny)`` contact elements: on the wheelset step's windows one
or two blocks, so a sweep costs one or two DC-FFT products and compiled calls. The sweep
is compiled with numba; a numpy version (vectorised shift per element, no blocks) gives the same
iterates where numba is missing or on request. The result's slip field (one more
product) is formed only when read (:class:`~.convexgs.TangentialResult`).

Convergence as ConvexGS's: one iteration is one sweep over all contact elements and
``||p^k - p^(k-1)||_2 < tolerance ||p^k||_2`` with ``p^k`` the whole traction field after
sweep ``k`` (the shifted runs included). When that measure has not fallen below
:data:`~.convexgs.STALL_GAIN` of its best for :data:`STALL_SWEEPS` sweeps the iteration
stops, not converged, and says so; a non-finite measure stops it too. Set-up, loop and
result are ConvexGS's (:class:`~.convexgs.SweepProblem`, the loop
:func:`~.convexgs._sweep_loop_of`); only the sweep differs. Where the operator's product
is a compiled packed plan (FFTW's C interface) the whole solve runs as one compiled call
that releases the GIL (:func:`_steady_solve`: the set-up's layout, the sweeps and their
stopping rules, the result's fields and sums; the same kernels in the same order, the
same bits), with Python only to check the inputs before it and to form the result
record after it.

Relaxation: ``omega_h = 0.65``, ``omega_s = 0.9`` by default, the best on S1002/60E1
patches (about 20-25 sweeps from zero traction at eps 1e-5, 31-33 on the most
spin-dominated flange patch, against 50-120 of ConvexGS; without relaxation 25-40).
Over-relaxation, and sweeping the rows alternately forward and backward in y or from the
leading to the trailing edge, slowed the iteration down or made it diverge.
"""

from __future__ import annotations

import math
import time
from functools import lru_cache

import numpy as np

from ..errors import RailContactError
from ..halfspace.grid import Grid
from ..halfspace.operator import InfluenceOperator, packed_product
from ..halfspace.pointers import address, function_at
from .convexgs import (
    ADHESION,
    HAVE_NUMBA,
    NOT_HUGE,
    NOT_TINY,
    STALL_GAIN,
    Embedding,
    SweepProblem,
    TangentialResult,
    _block_rows,
    _blocks_of,
    _bound_layout,
    _element_solve,
    _embedded_fields,
    _floor_above_c,
    _gs_kernels,
    _measure_c,
    _summary_sums,
    _sweep_loop_of,
    checked_inputs,
    checked_settings,
    pressure_error,
    result_record,
    slip_function,
    start_failure,
)

try:
    import numba
    from numba.core import cgutils
    from numba.extending import intrinsic
except ImportError:  # pragma: no cover
    numba = None

OMEGA_H, OMEGA_S = 0.65, 0.9
"""SteadyGS's default relaxation in adhesion and in slip (module docstring)."""
STALL_SWEEPS = 50
"""Sweeps without progress after which SteadyGS stops, not converged (a tolerance below
what round-off lets it reach would otherwise run to ``max_iterations``)."""
BLOCK_SCALE = 15.0
"""Target size of a row block, in contact elements: ``BLOCK_SCALE sqrt(nx ny)`` on an
``nx`` x ``ny`` grid. A block's direct sum costs about (its elements)^2 / 2 element pairs,
a block boundary one DC-FFT product, whose cost grows with the grid, so the best block
grows as the square root of the grid's size. With the cross-row sums vectorised over the
targets, 15 is the best of 8 / 10 / 12 / 15 / 18 (each solve timed with every value on
the same problem, the same sweeps): 5 % less time than 12 on the wheelset step's warm and
cold solves (24 x 48 elements, 250-1,000 in contact: one block up to about 760 contact
elements), 4 % on the 0.5 mm wheel-rail patches, 2 % on the 0.2 mm ones; 18 within 1 %
of 15."""


def _shift_run(px, py, g, dpx, dpy, iy, ix, jx, ex, ey):
    """Move the tractions [Pa] of the adhesion run ``jx < j < ix`` of row ``iy`` by
    ``(ex, ey)``, each put back on its bound ``g`` when pushed over it (the shift then goes
    on with that element's actual change); the changes are added to ``dpx``, ``dpy``."""
    j = ix - 1
    while j > jx and (ex != 0.0 or ey != 0.0):
        # the elements the shift leaves within their bounds, in a loop that leaves at the
        # first one it does not: a branch the processor predicts, where a test inside
        # the loop made each element wait for the one before (3 ns an element)
        while j > jx:
            gj = g[iy, j]
            qx = px[iy, j] + ex
            qy = py[iy, j] + ey
            if not NOT_TINY < gj < NOT_HUGE or qx * qx + qy * qy > gj * gj:
                break
            px[iy, j] = qx
            py[iy, j] = qy
            dpx[iy, j] += ex
            dpy[iy, j] += ey
            j -= 1
        if j <= jx:
            break
        ox = px[iy, j]  # pushed over its bound, or a bound whose square leaves the normal
        oy = py[iy, j]  # numbers (squares near it would under- or overflow: hypot)
        qx = ox + ex
        qy = oy + ey
        gj = g[iy, j]
        if NOT_TINY < gj < NOT_HUGE:
            m2 = qx * qx + qy * qy
            over = m2 > gj * gj
            m = math.sqrt(m2) if over else 0.0
        else:
            m = math.hypot(qx, qy)
            over = m > gj
        if over:
            qx *= gj / m
            qy *= gj / m
        ex = qx - ox
        ey = qy - oy
        px[iy, j] = qx
        py[iy, j] = qy
        dpx[iy, j] += ex
        dpy[iy, j] += ey
        j -= 1


def _run_start(state, iy, ix):
    """Index of the first non-adhesion element trailing ``ix`` in row ``iy`` (-1: none)."""
    jx = ix - 1
    while jx >= 0 and state[iy, jx] == ADHESION:
        jx -= 1
    return jx


def _row_dot(rxx, rxy, ryy, r, k0, dpx, dpy, jy, a, m):
    """``sum_j K[r, k0 + j] dp[jy, a + j]`` over ``j < m`` for both components (xx, xy;
    yx = xy, yy): the reversed kernels' row ``r`` against the changes of row ``jy``, as
    contiguous slices with local sums, a loop the compiler vectorises (three kernel
    streams, not four: 13 % less time)."""
    kxx = rxx[r, k0:k0 + m]
    kxy = rxy[r, k0:k0 + m]
    kyy = ryy[r, k0:k0 + m]
    qx = dpx[jy, a:a + m]
    qy = dpy[jy, a:a + m]
    ax = 0.0
    ay = 0.0
    for j in range(m):
        ax += kxx[j] * qx[j] + kxy[j] * qy[j]
        ay += kxy[j] * qx[j] + kyy[j] * qy[j]
    return ax, ay


if HAVE_NUMBA:
    @intrinsic
    def _stack_floats(typingctx, n):
        """A pointer to ``n`` (a literal int) float64 on the compiled function's stack: an
        array there (:func:`numba.carray`) is one LLVM sees no other pointer reach, so it
        keeps a small array of sums in vector registers across a loop (a heap array, which
        may alias the arrays read in the loop, is loaded and stored at every step)."""
        if not isinstance(n, numba.types.IntegerLiteral):
            return None
        size = n.literal_value

        def codegen(context, builder, sig, args):
            return cgutils.alloca_once(builder, context.get_value_type(numba.types.float64),
                                       size=size)

        return numba.types.CPointer(numba.types.float64)(n), codegen

    _carray = numba.carray
else:  # pragma: no cover
    _stack_floats = _carray = None

LANES = (16, 20, 24, 28, 32)
"""Target elements whose cross-row sums :func:`_cross_rows_of` forms at once: a row's
targets are taken in chunks of 32, the last of them in the smallest of these that holds
what is left (their sums held in vector registers, of four lanes for the last four of 20
and 28). 20 and 28 give the step's warm blocks 7 % fewer target lanes than 16/24/32
alone would (77.5 against 80.0 µs a block, the same bits)."""


def _cross_rows_of(lanes: int):
    """The function that adds the cross-row sums of ``lanes`` targets (a compile-time
    constant for numba: the loop over them is vectorised, its sums kept in registers)."""

    def cross_rows(fxx, fxy, fyy, dpx, dpy, lo, hi, r0, iy, c0, tx, ty):
        """Add to ``tx[c0 + l]``, ``ty[c0 + l]`` (``l < lanes``, up to the row's last
        contact element ``hi[iy]``) the shift [m] of the changes ``dp`` of rows
        ``r0 .. iy-1``.

        ``f..`` are the reversed kernels flipped along x (:func:`_cross_kernel`), so that
        the coefficients of one source element on consecutive targets are consecutive:
        each source element adds a vector multiple of a kernel slice to the targets' sums
        (an outer product, vectorised over the targets, no horizontal sums)."""
        ny, nx = dpx.shape
        ax = _carray(_stack_floats(lanes), lanes)
        ay = _carray(_stack_floats(lanes), lanes)
        for k in range(lanes):
            ax[k] = 0.0
            ay[k] = 0.0
        for jy in range(r0, iy):
            a = lo[jy]
            b = hi[jy]
            m = b + 1 - a
            if m <= 0:
                continue
            r = ny - 1 - iy + jy
            s = nx - 1 + c0 - b  # target c0 + k, source b - p: f[r, s + p + k]
            kxx = fxx[r, s:s + m + lanes - 1]
            kxy = fxy[r, s:s + m + lanes - 1]
            kyy = fyy[r, s:s + m + lanes - 1]
            qx = dpx[jy, a:b + 1][::-1]
            qy = dpy[jy, a:b + 1][::-1]
            for p in range(m):
                ex = qx[p]
                ey = qy[p]
                for k in range(lanes):
                    ax[k] += kxx[p + k] * ex + kxy[p + k] * ey
                    ay[k] += kxy[p + k] * ex + kyy[p + k] * ey
        for k in range(lanes):  # (a fixed count: a variable one kept the sums in memory)
            if c0 + k <= hi[iy]:
                tx[c0 + k] += ax[k]
                ty[c0 + k] += ay[k]

    return cross_rows


def _visit(rxx, rxy, ryy, cum, sx, sy, g, px, py, dpx, dpy, state, lo, iy, ix, jx,
           omega_h, omega_s):
    """Solve element (iy, ix) with its trailing adhesion run ``jx < j < ix`` (see
    :func:`_steady_block`); ``(sx, sy)`` is its shift [m] with the changes of the block's
    rows before this one."""
    ny, nx = g.shape
    # in this row the elements trailing this one have changed (elements are visited in
    # order; the runs shifted are trailing ones), the rest not yet (zero in dpx, dpy)
    a = lo[iy]
    ax, ay = _row_dot_c(rxx, rxy, ryy, ny - 1, nx - 1 - ix + a, dpx, dpy, iy, a, ix - a)
    sx += ax
    sy += ay
    n = ix - jx
    c11 = cum[0, n]
    c12 = cum[1, n]
    c21 = cum[2, n]
    c22 = cum[3, n]
    ox = px[iy, ix]
    oy = py[iy, ix]
    s0x = sx - c11 * ox - c12 * oy
    s0y = sy - c21 * ox - c22 * oy
    new_x, new_y, st = _element_solve_c(ox, oy, s0x, s0y, g[iy, ix], c11, c12, c21, c22,
                                        omega_h, omega_s)
    px[iy, ix] = new_x
    py[iy, ix] = new_y
    dpx[iy, ix] += new_x - ox
    dpy[iy, ix] += new_y - oy
    state[iy, ix] = st
    _shift_run_c(px, py, g, dpx, dpy, iy, ix, jx, new_x - ox, new_y - oy)


def _steady_block(rxx, rxy, ryy, fxx, fxy, fyy, cum, ux, uy, g, px, py, dpx, dpy, state,
                  lo, hi, r0, r1, omega_h, omega_s, measure=1.0):
    """SteadyGS over the elements of rows r0 .. r1-1 (numba-compiled); returns the squared
    norm of the block's traction change [Pa^2], scaled by ``measure`` (a power of two,
    :attr:`~.convexgs.SweepProblem.measure`).

    ``(ux, uy)`` is the shift ``W + B p`` [m] for the tractions at the start of the block
    (its rows r0 .. r1-1 are summed into in place: the sweep reads them no more);
    the changes made inside the block (``dpx``, ``dpy``, zero on entry) are added by a
    direct sum with the reversed kernels ``r..`` (as ConvexGS's ``_block_sweep``), so
    every element sees the newest tractions: at the start of a row, those of the block's
    rows before it (final for this sweep: a row's changes stay in the row) for the whole
    row at once, 16 to 32 targets at a time with the flipped kernels ``f..``
    (:func:`_cross_rows_of`); at each element, those of its own row so far.
    ``cum[:, L]`` holds the run coefficient ``sum_{m<L} B[m]`` (c11, c12, c21, c22) for
    a run of ``L`` elements. On return ``dpx``, ``dpy`` hold the block's changes (the runs
    shifted included), whose squared sum is the sweep's measure of this block.
    """
    dif = 0.0
    for iy in range(r0, r1):
        a, b = lo[iy], hi[iy]
        tx = ux[iy]  # (the block's rows of the shift are its own: summed in place)
        ty = uy[iy]
        c0 = a
        while iy > r0 and c0 <= b:
            rest = b - c0  # (targets left, less one)
            if rest >= 28:
                _cross_rows32_c(fxx, fxy, fyy, dpx, dpy, lo, hi, r0, iy, c0, tx, ty)
                c0 += 32
            elif rest >= 24:
                _cross_rows28_c(fxx, fxy, fyy, dpx, dpy, lo, hi, r0, iy, c0, tx, ty)
                c0 += 28
            elif rest >= 20:
                _cross_rows24_c(fxx, fxy, fyy, dpx, dpy, lo, hi, r0, iy, c0, tx, ty)
                c0 += 24
            elif rest >= 16:
                _cross_rows20_c(fxx, fxy, fyy, dpx, dpy, lo, hi, r0, iy, c0, tx, ty)
                c0 += 20
            else:
                _cross_rows16_c(fxx, fxy, fyy, dpx, dpy, lo, hi, r0, iy, c0, tx, ty)
                c0 += 16
        jx = a - 1  # the run start (:func:`_run_start`), kept up to date along the row
        for ix in range(a, b + 1):
            if g[iy, ix] > 0.0:
                _visit_c(rxx, rxy, ryy, cum, tx[ix], ty[ix], g, px, py, dpx, dpy, state,
                         lo, iy, ix, jx, omega_h, omega_s)
            if state[iy, ix] != ADHESION:
                jx = ix
        for ix in range(a, b + 1):
            ex = dpx[iy, ix] * measure
            ey = dpy[iy, ix] * measure
            dif += ex * ex + ey * ey
    return dif


if HAVE_NUMBA:
    # numpy's error model: a division by zero gives inf/NaN (which the sweep's measure
    # catches) instead of raising, so the compiled code carries no zero-divisor checks
    # (the same bits, 3-5 % less time per block)
    _jit = numba.njit(cache=True, nogil=True, inline="always", error_model="numpy")
    _element_solve_c = _jit(_element_solve)
    _shift_run_c = _jit(_shift_run)
    _row_dot_c = _jit(_row_dot)
    # (compiled inside the block only: the five share one name, which numba's cache
    # would take for one function)
    _cross_rows16_c, _cross_rows20_c, _cross_rows24_c, _cross_rows28_c, _cross_rows32_c = (
        numba.njit(nogil=True, inline="always", fastmath=True,
                   error_model="numpy")(_cross_rows_of(n))
        for n in LANES)
    _visit_c = _jit(_visit)
    # (called with one signature, _BLOCK, the sweep's C-ordered arrays: the compiled sweeps
    # call the code of that signature through a pointer, the code Python's calls run,
    # :mod:`~railcontact.halfspace.pointers`)
    _PLANE = numba.types.float64[:, ::1]
    _BLOCK = numba.types.float64(*[_PLANE] * 14, numba.types.int8[:, ::1],
                                 numba.types.int64[::1], numba.types.int64[::1],
                                 numba.types.int64, numba.types.int64, numba.types.float64,
                                 numba.types.float64, numba.types.float64)
    _steady_block_numba = numba.njit(cache=True, nogil=True, fastmath=True,
                                     error_model="numpy")(_steady_block)
    _block_at = function_at(_BLOCK)
else:  # pragma: no cover
    _element_solve_c = _element_solve
    _shift_run_c = _shift_run
    _row_dot_c = _row_dot
    _cross_rows16_c, _cross_rows20_c, _cross_rows24_c, _cross_rows28_c, _cross_rows32_c = (
        _cross_rows_of(n) for n in LANES)
    _visit_c = _visit
    _steady_block_numba = None


def _add_product(ux, uy, bx, by, u, r0):
    """``ux = bx + u[0].T``, ``uy = by + u[1].T`` [m] on the rows ``r0`` on: a product
    ``u`` (2, nx, ny) of the operator added in the sweep layout (ny, nx)."""
    ny, nx = ux.shape
    for iy in range(r0, ny):
        for ix in range(nx):
            ux[iy, ix] = bx[iy, ix] + u[0, ix, iy]
            uy[iy, ix] = by[iy, ix] + u[1, ix, iy]


_add_product_c = numba.njit(cache=True, nogil=True)(_add_product) if HAVE_NUMBA else _add_product


def _sweep_blocked(kern, cum, product, wx, wy, g, p, state, lo, hi, rows, omega_h, omega_s,
                   measure=1.0):
    """One SteadyGS sweep of the traction ``p`` (2, ny, nx) (the sweep layout), row block
    by row block (on the wheelset step's windows one block); between blocks the shift of
    the rows still to come is brought up to date with one DC-FFT product of the block's
    changes (as ConvexGS's sweep). The products read ``p`` and the changes through
    (2, nx, ny) views, with no stacked copy. Returns the squared norm of the sweep's
    traction change [Pa^2]. ``product(x, None)`` is the steady-rolling operator's product
    of a (2, nx, ny) traction (:meth:`~railcontact.halfspace.operator.InfluenceOperator.bound`,
    formed once per solve)."""
    px, py = p[0], p[1]
    work = np.zeros((4, *g.shape))  # the shift and the changes: one allocation
    ux, uy, dp = work[0], work[1], work[2:]
    _add_product_c(ux, uy, wx, wy, product(p.transpose(0, 2, 1), None), 0)
    dpx, dpy = dp[0], dp[1]
    dif = 0.0
    for b, (r0, r1) in enumerate(rows):
        dif += _steady_block_numba(*kern, cum, ux, uy, g, px, py, dpx, dpy, state, lo, hi,
                                   r0, r1, omega_h, omega_s, measure)
        if b + 1 < len(rows):
            _add_product_c(ux, uy, ux, uy, product(dp.transpose(0, 2, 1), None), r1)
            dp[:, r0:r1] = 0.0
    return dif


def _steady_sweep(args):  # pragma: no cover - compiled
    """One sweep of :func:`_sweep_blocked`, compiled, on the arrays of :func:`_steady_solve`
    (``args``): the DC-FFT products run through the operator's compiled packed plan, the
    blocks :func:`_steady_block_numba`'s own code called through its pointer (linked into
    the caller, LLVM could compile its fast-math sums anew and change their last bits).
    The same steps on the same arrays as :func:`_sweep_blocked`: the same bits. Returns the
    squared norm of the sweep's traction change [Pa^2] (scaled by the measure)."""
    (block_address, fft, kern, cum, wx, wy, g, p, state, lo, hi, rows, shift, prod, omega_h,
     omega_s, measure) = args
    block = _block_at(block_address)
    plans, z_in, z_s, w_s, w_out, a, b, n = fft
    rxx, rxy, ryy, fxx, fxy, fyy = kern
    px = p[0]
    py = p[1]
    pt = p.transpose(0, 2, 1)  # (the traction as (2, nx, ny), for the products)
    ux = shift[0]
    uy = shift[1]
    dpx = shift[2]
    dpy = shift[3]
    dp = shift[2:]
    dpt = dp.transpose(0, 2, 1)
    nb = rows.shape[0]
    dp[:] = 0.0  # (the shift's rows are all written by the first product)
    _packed_pair(plans, pt, z_in, z_s, w_s, w_out, a, b, n, prod)
    _add_product_c(ux, uy, wx, wy, prod, 0)
    dif = 0.0
    for k in range(nb):
        r0 = rows[k, 0]
        r1 = rows[k, 1]
        dif += block(rxx, rxy, ryy, fxx, fxy, fyy, cum, ux, uy, g, px, py, dpx, dpy, state,
                     lo, hi, r0, r1, omega_h, omega_s, measure)
        if k + 1 < nb:
            _packed_pair(plans, dpt, z_in, z_s, w_s, w_out, a, b, n, prod)
            _add_product_c(ux, uy, ux, uy, prod, r1)
            dp[:, r0:r1] = 0.0
    return dif


def _steady_solve(block_address, fft, kern, cum, pn, mu, x0, dx, y0, dy, xi, eta, phi,
                  offset, p0, st0, start, omega_h, omega_s, tolerance, max_iterations,
                  stall_sweeps, stall_gain, work, whole):  # pragma: no cover - compiled
    """A whole SteadyGS solve of rolling contact (``xi, eta, phi`` not all zero) in one
    compiled call that releases the GIL: :class:`~.convexgs.SweepProblem`'s set-up
    (:func:`~.convexgs._bound_layout` of the pressure ``pn`` (nx, ny) [Pa], ``mu``, the
    grid ``(x0, dx, y0, dy)`` and the start ``p0``, ``st0`` when ``start``), its sweeps
    and their stopping rules (:func:`~.convexgs._sweep_loop_of` around
    :func:`_steady_sweep`, the blocks :func:`~.convexgs._block_rows` of ``work``) and the
    result's fields and sums: on the solve's grid, or with ``whole = (nx, ny, i0, j0)``
    (``nx`` > 0) on the larger grid of which it is the window at ``(i0, j0)``
    (:func:`~.convexgs._embedded_fields`). The same kernels in the same order as the
    Python solve: the same bits. ``block_address``: :func:`_block_address`; ``fft``:
    :meth:`~railcontact.halfspace.operator.InfluenceOperator.compiled_product`'s
    arguments; ``kern``: :func:`_steady_kernels`; ``cum``: :func:`_run_coefficients`.

    Returns ``(fields, traction, st, sums, history, counts, error)``: the layout's fields
    (5, ny, nx) (``g``, ``wx``, ``wy``, ``p``); the result's traction [Pa] and states
    ``st`` (nx, ny) (with ``whole`` those of the larger grid, the solve's states their
    window): the traction with ``whole`` (2, nx, ny), else in the sweep layout
    (2, ny, nx), a copy of ``p`` (its transpose is the traction);
    :func:`~.convexgs._summary_sums`' sums (``sum p_x``, ``sum p_y``, ``sum (x p_y - y
    p_x)``, the elements in contact and in slip, the largest ``|p|``) over the solve's
    grid; the error after each sweep; ``counts``: the sweeps, whether
    they converged, stalled, the pressure was valid (finite, non-negative), the start
    valid (finite), the elements in contact (the layout's); the last error. With an
    invalid pressure or start no sweep is run (the caller raises)."""
    fields, rows_, state, contact, ok, gmax, ncon, start_ok = _bound_layout(
        pn, mu, x0, dx, y0, dy, xi, eta, phi, offset, p0, st0, start)
    ny, nx = state.shape
    g = fields[0]
    wx = fields[1]
    wy = fields[2]
    p = fields[3:]
    measure = _measure_c(gmax)
    shift = np.empty((4, ny, nx))  # the shift and the changes, as _sweep_blocked's
    prod = np.empty((2, nx, ny))
    squares = np.empty((ny, nx))
    args = (block_address, fft, kern, cum, wx, wy, g, p, state, rows_[0], rows_[1],
            _block_rows(rows_[2], work), shift, prod, omega_h, omega_s, measure)
    its, err, converged, stalled, hist = _steady_loop(
        args, p[0], p[1], g, squares, measure, _floor_above_c(ncon, gmax, measure), tolerance,
        max_iterations, stall_sweeps, stall_gain, ok and start_ok and ncon > 0)
    if whole[0] > 0:  # the fields on the larger grid; the sums over the solve's
        traction, st, sx, sy, sm, nc, nslip, pmax = _embedded_fields(
            p, state, whole[0], whole[1], whole[2], whole[3], x0, dx, y0, dy)
    else:  # the traction in the sweep layout (a copy of p), the states as (nx, ny)
        traction = p.copy()
        st = np.ascontiguousarray(state.T)
        sx, sy, sm, nc, nslip, pmax = _summary_sums(traction, st, x0, dx, y0, dy)
    return (fields, traction, st, (sx, sy, sm, nc, nslip, pmax), hist,
            (its, converged, stalled, ok, start_ok, ncon), err)


COMPILED_MAX_SWEEPS = 2**62
"""Sweep limits below this run the solve compiled (:func:`_steady_solve`); a larger one
(no machine integer holds it) runs its sweeps in Python."""

if HAVE_NUMBA and packed_product[2] is not None:
    _packed_pair = packed_product[2]
    # (the sweep and its loop compiled into the solve alone, which is cached: the loop
    # calls the sweep as a constant of its code, _sweep_loop_of)
    _steady_sweep_c = numba.njit(nogil=True)(_steady_sweep)
    _steady_loop = numba.njit(nogil=True)(_sweep_loop_of(_steady_sweep_c))
    _steady_solve_c = numba.njit(cache=True, nogil=True)(_steady_solve)

    @lru_cache(maxsize=1)
    def _block_address() -> int:
        """The address of :func:`_steady_block_numba`'s code for :func:`_steady_sweep`,
        formed once."""
        return address(_steady_block_numba, _BLOCK)
else:  # pragma: no cover
    _steady_solve_c = None


def _sweep_numpy(kern, cum, wx, wy, g, px, py, state, lo, hi, omega_h, omega_s):
    """The plain sweep: the shift of each element as a vectorised sum over all elements."""
    rxx, rxy, ryx, ryy = kern
    ny, nx = g.shape
    scratch = np.zeros_like(px), np.zeros_like(py)
    for iy in range(ny):
        for ix in range(lo[iy], hi[iy] + 1):
            gi = g[iy, ix]
            if gi <= 0.0:
                continue
            win = (slice(ny - 1 - iy, 2 * ny - 1 - iy), slice(nx - 1 - ix, 2 * nx - 1 - ix))
            sx = wx[iy, ix] + np.vdot(rxx[win], px) + np.vdot(rxy[win], py)
            sy = wy[iy, ix] + np.vdot(ryx[win], px) + np.vdot(ryy[win], py)
            jx = _run_start(state, iy, ix)
            c11, c12, c21, c22 = cum[:, ix - jx]
            ox, oy = px[iy, ix], py[iy, ix]
            new_x, new_y, st = _element_solve(ox, oy, sx - c11 * ox - c12 * oy,
                                              sy - c21 * ox - c22 * oy, gi, c11, c12, c21,
                                              c22, omega_h, omega_s)
            px[iy, ix], py[iy, ix], state[iy, ix] = new_x, new_y, st
            _shift_run(px, py, g, *scratch, iy, ix, jx, new_x - ox, new_y - oy)


@lru_cache(maxsize=16)
def _steady_kernels(operator: InfluenceOperator) -> tuple[np.ndarray, ...]:
    """The reversed kernels xx, xy, yy of :func:`_gs_kernels` for the compiled sweep, which
    uses xy for yx: the steady-rolling operator of quasi-identical materials is reciprocal
    (``B_xy = B_yx``, the same coefficients to the bit); then the same three flipped along
    x for the cross-row sums (:func:`_cross_kernel`)."""
    rxx, rxy, ryx, ryy = _gs_kernels(operator)
    if not np.array_equal(rxy, ryx):
        raise RailContactError("SteadyGS needs a reciprocal steady-rolling operator "
                               "(equal xy and yx kernels)")
    return (rxx, rxy, ryy) + tuple(_cross_kernel(k) for k in (rxx, rxy, ryy))


def _cross_kernel(reversed_kernel: np.ndarray) -> np.ndarray:
    """A reversed kernel (2ny-1, 2nx-1) flipped along x, ``f[r, t] = k[r, 2nx-2-t]``, with
    ``max(LANES)`` zero columns after it (read by the targets past a row's end)."""
    n0, n1 = reversed_kernel.shape
    out = np.zeros((n0, n1 + max(LANES)))
    out[:, :n1] = reversed_kernel[:, ::-1]
    return out


@lru_cache(maxsize=16)
def _run_coefficients(operator: InfluenceOperator) -> np.ndarray:
    """``cum[:, L] = sum_{m<L} B[m, 0]`` (xx, xy, yx, yy) [m/Pa] for runs of L = 0 .. nx
    elements: the coefficient of a traction change applied to an element and the L - 1
    elements trailing it in its row."""
    k = operator.kernels[:, :, operator.nx - 1:, operator.ny - 1]  # offsets 0 .. nx-1
    cum = np.zeros((4, operator.nx + 1))
    cum[:, 1:] = np.cumsum(k.reshape(4, operator.nx), axis=1)
    return cum


def compiled_setup(operator: InfluenceOperator, tolerance, max_iterations, omega_h, omega_s,
                   engine) -> tuple | None:
    """What the compiled solve (:func:`_steady_solve`) with the steady-rolling ``operator``
    reads beyond the problem: ``(block, fft, kernels, run coefficients, tolerance, sweep
    limit, (omega_h, omega_s))`` - the block's code address (:func:`_block_address`), the
    operator's compiled product (:meth:`~railcontact.halfspace.operator.InfluenceOperator.
    compiled_product`), :func:`_steady_kernels` and :func:`_run_coefficients` - with the
    settings checked (:func:`~.convexgs.checked_settings`); None where the solve is not one
    compiled call (no numba or no FFTW C interface, the numpy engine, a sweep limit no
    machine integer holds, settings that do not pass their checks: the Python solve raises
    for them in the order of its checks)."""
    if _steady_solve_c is None:
        return None
    try:
        tol, max_its, use_numba = checked_settings(tolerance, max_iterations, omega_h,
                                                   omega_s, engine)
        kern = (_steady_kernels(operator) if use_numba and max_its < COMPILED_MAX_SWEEPS
                else None)
    except RailContactError:  # (raised by the Python solve, in the order of the checks)
        return None
    fft = None if kern is None else operator.compiled_product()
    if fft is None:
        return None
    return (_block_address(), fft, kern, _run_coefficients(operator), tol, max_its,
            (float(omega_h), float(omega_s)))


def compiled_record(t0: float, grid: Grid, operator: InfluenceOperator,
                    embed: Embedding | None, tolerance: float, out: tuple
                    ) -> TangentialResult:
    """The :class:`~.convexgs.TangentialResult` of a compiled solve on ``grid`` (with
    ``embed``: on its larger grid) from :func:`_steady_solve`'s outputs ``out``, started
    at ``t0`` (:func:`time.perf_counter`) to ``tolerance``; raises for a pressure or a
    start that the solve found not valid (not finite, or a negative pressure)."""
    fields, traction, st, sums, hist, counts, err = out
    its, converged, stalled, ok, start_ok, ncon = counts
    if not ok:
        raise pressure_error(grid)
    if not start_ok:
        raise start_failure(grid, None)
    if embed is None:  # (the traction's sweep layout, transposed)
        traction, state = traction.transpose(0, 2, 1), st
    else:  # (the solve's states: the window of the result's)
        state = st[embed[1][0], embed[1][1]]
    return result_record(
        "SteadyGS", STALL_SWEEPS, t0, grid, embed, tolerance, ncon > 0, True, its, err,
        converged, stalled, hist, traction, st, sums,
        slip_function(operator, grid.dx, fields[1], fields[2], fields[3:], state))


def solve_steadygs(
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
    omega_h: float = OMEGA_H,
    omega_s: float = OMEGA_S,
    engine: str = "auto",
    spin_offset: float = 1.0 / 6.0,
    embed: Embedding | None = None,
) -> TangentialResult:
    """Solve steady rolling with Coulomb friction by SteadyGS.

    Same problem, inputs and result as :func:`railcontact.tangential.solve_tangential`
    (ConvexGS); ``iterations`` counts sweeps over all contact elements.

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
        Initial estimate (2, nx, ny) [Pa]; default zero traction. It is clipped to the
        traction bound.
    initial_state
        Adhesion/slip map (nx, ny) of the estimate (1 adhesion, 2 slip): slip elements start
        on the traction bound.
    tolerance
        eps_tau for ``||p^k - p^(k-1)|| < eps_tau ||p^k||``.
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
        ``(whole, (sx, sy))``: the result on the larger grid ``whole`` of which ``grid``
        is the window ``sx``, ``sy`` (see :func:`railcontact.tangential.solve_tangential`).
    """
    t0 = time.perf_counter()
    pn, mu, xi, eta, phi, offset, rolling, p0, st0, start, start_error = checked_inputs(
        grid, operator, pressure, friction, creepage, initial_traction, initial_state,
        spin_offset)
    setup = None
    if rolling and start_error is None:
        setup = compiled_setup(operator, tolerance, max_iterations, omega_h, omega_s, engine)
    if setup is not None:  # the whole solve one compiled call
        whole = (-1, 0, 0, 0) if embed is None else (
            embed[0].nx, embed[0].ny, embed[1][0].start, embed[1][1].start)
        block, fft, kern, cum, tol, max_its, omegas = setup
        out = _steady_solve_c(block, fft, kern, cum, pn, mu, grid.x0, grid.dx, grid.y0,
                              grid.dy, xi, eta, phi, offset, p0, st0, start, *omegas, tol,
                              max_its, STALL_SWEEPS, STALL_GAIN,
                              BLOCK_SCALE**2 * grid.size, whole)
        return compiled_record(t0, grid, operator, embed, tol, out)
    prob = SweepProblem.set_up(grid, operator, pressure, friction, creepage, initial_traction,
                               initial_state, tolerance, max_iterations, omega_h, omega_s,
                               engine, spin_offset)
    px, py = prob.px, prob.py
    cum = _run_coefficients(operator)
    oh, os_ = float(omega_h), float(omega_s)
    rows = _blocks_of(prob.row_counts, BLOCK_SCALE**2 * grid.size)
    if prob.use_numba:
        kern = _steady_kernels(operator)
        product = operator.bound()  # the FFT plan fetched once for all the sweeps

    def sweep() -> float:
        if prob.use_numba:  # the blocks measure their changes, the shifted runs included
            return _sweep_blocked(kern, cum, product, prob.wx, prob.wy, prob.g, prob.p,
                                  prob.state, prob.lo, prob.hi, rows, oh, os_, prob.measure)
        qx, qy = px.copy(), py.copy()  # the runs move many elements: measure the whole field
        _sweep_numpy(_gs_kernels(operator), cum, prob.wx, prob.wy, prob.g, px, py, prob.state,
                     prob.lo, prob.hi, oh, os_)
        m = prob.measure
        return float(np.sum(((px - qx) * m) ** 2 + ((py - qy) * m) ** 2))

    return prob.solve(sweep, "SteadyGS", STALL_SWEEPS, t0, embed)
