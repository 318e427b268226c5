"""The warm step's stages as single compiled calls.

On the wheel solver's Python path a warm patch's normal stage is five kernels with Python
between them: the undeformed gap on the patch's grid, the remembered pressure and
displacement extrapolated onto it (:func:`~.warmstart.previous_start`), the CG solve
(:func:`~railcontact.normal.bem.solve_normal`) and the check that the rigid overlap holds
no place beyond the grid the contact could reach (its box on the wheel's run, then the
places beyond the grid: :func:`~railcontact.contact.wheelrail._overlap_covered`). Its
tangential stage is three: the remembered traction advanced along its rate onto the
patch's grid (:func:`~.warmstart.previous_tangential`), SteadyGS on the window of the
contact (:func:`~railcontact.contact.patch.solve_patch_tangential`) and the traction's new
rate (:func:`~.warmstart.traction_rate`). Here each runs as one call that releases the
GIL (:func:`warm_normal`: :func:`_warm_normal`; :func:`warm_tangential`:
:func:`_warm_tangential`): the same kernels on the same arrays in the same order, so the
same bits, with Python only to gather the call's arguments and to form the result's
records.

Where a stage is not that one call the caller takes the Python path. The normal stage: a
patch at its rigid contact point (no frame at the reference point, or one whose samples
were all formed, as a merged patch's cold area forms them), one beside other patches
under approach control (its own gap), a later solve of a load pass at a frame formed
again (started from the solve before, its grid kept), penetration control or a load
below the solver's least, a start re-meshed off the lattice or without pressure, a grid
small enough for a dense product or no FFTW C interface. A solution the patch solver
would not keep as it is (its contact at the edge of its area, a place of the overlap
beyond the grid that could touch) is handed on with what the check found, and the solver
goes on from it.
The tangential stage: ConvexGS or a simplified model, a friction so small that the patch
is solved without it (:func:`~railcontact.contact.patch.negligible_friction`), a patch
without a remembered
traction rate or older step (the first warm steps; a later load pass of a step, which
starts from the pass before), zero creepage, a start off the grid's lattice, a window
small enough for a dense product or no FFTW C interface.
"""

from __future__ import annotations

import math
from time import perf_counter

import numba
import numpy as np

from ..contact.patch import (
    UNDEFINED_GAP,
    _uncovered,
    check_operator_memory,
    contact_window,
    make_grid,
    negligible_friction,
    tangential_solved,
)
from ..contact.results import PatchSolution
from ..contact.start import StagedNormal
from ..geometry.kernels import FRAME_GROW, gap_on_frame, overlap_box_frame
from ..geometry.points import FAR, K0, ContactPoint, WheelSearch
from ..halfspace.grid import Grid
from ..halfspace.hertz import MIN_LOAD
from ..halfspace.materials import ElasticPair
from ..halfspace.operator import influence_operator, resolve_backend
from ..normal.bem import (
    EMPTY_START,
    GAP_NOT_FINITE,
    HISTORY_CHUNK,
    MAX_LAST,
    PRECONDITIONERS,
    REUSE_GENERATIONS,
    START_NOT_FINITE,
    _kernel_addresses,
    _solve_compiled,
    compiled_products,
    solved_result,
)
from ..settings import Control, GridSettings, NormalSettings, TangentialSettings
from ..tangential.rolling import rolling_operator
from ..tangential.steadygs import (
    BLOCK_SCALE,
    OMEGA_H,
    OMEGA_S,
    STALL_GAIN,
    STALL_SWEEPS,
    _steady_solve_c,
    compiled_record,
    compiled_setup,
)
from .warmstart import (
    PatchMemory,
    _pressure_start,
    _rate_on,
    _traction_start,
    start_arguments,
    traction_rate,
)

ENABLED = True
"""Whether the stages run as their compiled calls where they can; False: every stage takes
the Python path (the same bits, slower), for a study that observes the solvers' own calls
(e.g. SteadyGS's warm starts, ``scripts/study_warm_relaxation.py``)."""
NO_RATE = (0, 0, 1.0, 1.0, 0.0, 0.0)
"""The older step's grid (nx, ny, dx, dy, x0, y0) passed where no rate is formed."""
_NO_FIELD = np.zeros((0, 0, 0))
_NO_BOX = (0.0, 0.0, 0.0, 0.0)
_LARGEST = 2.0**52
"""Largest element offset of a reach check's box that the compiled stage forms (beyond
it, or not finite, the Python path's check does, and raises)."""


@numba.njit(cache=True, nogil=True)
def _warm_tangential(nx, ny, dx, dy, x0, y0, tr, rate, state, npx, npy, n1x, n1y, d1x, d1y,
                     x1, y1, h,
                     window, pressure, block, fft, kern, cum, mu, xi, eta, phi, offset,
                     omega_h, omega_s, tolerance, max_iterations, stall_sweeps, stall_gain,
                     work, whole, older, older_rate, smooth, g0, gain, dt,
                     with_rate):  # pragma: no cover - compiled
    """A warm patch's tangential stage in one call: :func:`~.warmstart._traction_start`
    of the remembered traction ``tr`` (2, n1x, n1y), its rate and map ``state`` (its
    pressure (npx, npy)) on the patch's grid (nx, ny, dx, dy, x0, y0) advanced by ``h``
    [s]; the window ``window``
    (i0, i1, j0, j1) of it, of the ``pressure`` and of the start, copied as the solve
    reads them; :func:`~railcontact.tangential.steadygs._steady_solve` on it (``block``
    ... ``whole`` its arguments); with ``with_rate``, :func:`~.warmstart._rate_on` of the
    result's traction on the patch's grid against the ``older`` step's traction (its
    rate ``older_rate`` when ``smooth``; its grid ``g0``), ``gain``, ``dt``.

    Returns ``(kind, out, rate, total, rated)``: ``kind`` that of the traction start (2:
    the stage ran; else nothing else ran and the caller takes the Python path), the
    solve's outputs, the rate and its sum, and whether the rate was formed on one
    lattice (``rated``)."""
    t, shifted, kind = _traction_start(nx, ny, dx, dy, x0, y0, tr, rate, state, True, npx,
                                       npy, n1x, n1y, d1x, d1y, x1, y1, h)
    empty = np.empty((0, 0, 0))
    if kind != 2:
        return kind, None, empty, 0.0, False
    i0, i1, j0, j1 = window
    pn = np.ascontiguousarray(pressure[i0:i1, j0:j1])
    p0 = np.ascontiguousarray(t[:, i0:i1, j0:j1])
    st0 = np.ascontiguousarray(shifted[i0:i1, j0:j1])
    out = _steady_solve_c(block, fft, kern, cum, pn, mu, x0 + i0 * dx, dx, y0 + j0 * dy, dy,
                          xi, eta, phi, offset, p0, st0, True, omega_h, omega_s, tolerance,
                          max_iterations, stall_sweeps, stall_gain, work, whole)
    if not with_rate:
        return kind, out, empty, 0.0, False
    traction = out[1]
    if whole[0] > 0:
        v, total, rated = _rate_on(nx, ny, dx, dy, x0, y0, traction, older, g0[0], g0[1],
                                   g0[2], g0[3], g0[4], g0[5], older_rate, smooth, gain, dt)
    else:  # (the sweep layout's copy: the result's traction is its transpose)
        v, total, rated = _rate_on(nx, ny, dx, dy, x0, y0, traction.transpose(0, 2, 1),
                                   older, g0[0], g0[1], g0[2], g0[3], g0[4], g0[5],
                                   older_rate, smooth, gain, dt)
    return kind, out, v, total, rated


def warm_tangential(patch: PatchSolution, settings: TangentialSettings, pair: ElasticPair,
                    fft: str, creepage: tuple[float, float, float], memory: PatchMemory,
                    factor: float, last: PatchMemory | None, time: float | None,
                    gain: float) -> tuple[PatchSolution, bool, np.ndarray | None]:
    """The tangential stage of a warm ``patch`` (its normal solution found) in one
    compiled call (:func:`_warm_tangential`), as the time step's Python path forms it:
    its start the remembered patch ``memory`` advanced along its traction rate by the
    extrapolation ``factor`` (:func:`~.warmstart.previous_tangential`), the solve
    :func:`~railcontact.contact.patch.solve_patch_tangential` with the ``settings``
    (SteadyGS), ``pair``, the FFT backend ``fft`` and the patch's ``creepage`` (side
    frame), then the traction's rate after ``last`` (the older step) at ``time``, smoothed
    with ``gain`` (:func:`~.warmstart.traction_rate`).

    Returns ``(patch, done, rate)``: ``done`` False where the stage is not that call (the
    caller takes the Python path from the ``patch`` returned, which holds the time an
    operator's forming took, if any); else ``patch`` is the new record with its tangential
    solution, its work counted, and ``rate`` is the traction's rate (None: not
    formed)."""
    t0 = perf_counter()
    friction, rate = settings.friction, memory.traction_rate
    tr, st, o = memory.traction, memory.state, memory.older
    if not (ENABLED and settings.solver == "steadygs" and settings.model == "bem"
            and type(friction) is float and 0.0 <= friction < math.inf
            and (friction == 0.0
                 or not negligible_friction(friction, patch.normal.max_pressure))
            and _steady_solve_c is not None and factor > 0 and o is not None
            and tr is not None and rate is not None and rate.shape == tr.shape
            and tr.ndim == 3 and st is not None and st.dtype == np.int8 and st.ndim == 2
            and memory.pressure.ndim == 2):
        return patch, False, None
    xi, eta, phi = (float(c) for c in creepage)  # (as the solver's checks give them)
    if not (xi - xi == 0.0 and eta - eta == 0.0 and phi - phi == 0.0
            and (xi != 0.0 or eta != 0.0 or phi != 0.0)):
        return patch, False, None
    res = patch.normal
    grid = res.grid
    win = contact_window(res.contact, box=res.contact_box or (-1, 0, -1, 0))
    if win is None:
        i0, i1, j0, j1 = 0, grid.nx, 0, grid.ny
        solved, embed, whole = grid, None, (-1, 0, 0, 0)
    else:
        sx, sy = win
        i0, i1, j0, j1 = sx.start, sx.stop, sy.start, sy.stop
        solved = Grid(i1 - i0, j1 - j0, grid.dx, grid.dy, grid.x0 + i0 * grid.dx,
                      grid.y0 + j0 * grid.dy)
        embed, whole = (grid, win), (grid.nx, grid.ny, i0, j0)
    offset = settings.spin_offset
    if not (type(offset) is float and offset - offset == 0.0
            and resolve_backend(fft, solved.size) == "pyfftw"):
        return patch, False, None  # (a dense product, small grids: no compiled solve)
    check_operator_memory(solved, "xy", fft)
    operator = rolling_operator(solved, pair, fft)
    setup = compiled_setup(operator, settings.tolerance, settings.max_iterations, OMEGA_H,
                           OMEGA_S, "auto")
    if setup is None:  # (the operator's time, when it was formed)
        return _plus_seconds(patch, perf_counter() - t0), False, None
    block, products, kern, cum, tol, max_its, (omega_h, omega_s) = setup
    # the older step's traction and rate (traction_rate's conditions: a rate at all, then
    # one formed in the compiled pass)
    rated_at_all = (last is not None and last.traction is not None and time is not None
                    and last.time is not None and time - last.time > 0)
    with_rate = rated_at_all and last.traction.ndim == 3 and (
        last.traction_rate is None or last.traction_rate.ndim == 3)
    if with_rate:
        g0, v0 = last.grid, last.traction_rate
        older, smooth = last.traction, v0 is not None
        grid0 = (g0.nx, g0.ny, g0.dx, g0.dy, g0.x0, g0.y0)
        dt = float(time - last.time)
    else:
        older, v0, smooth, grid0, dt = _NO_FIELD, None, False, NO_RATE, 1.0
    g1 = memory.grid
    # (C-ordered arrays: one signature of the call; a solve on the whole grid remembers
    # its traction as a transposed view)
    tr, rate, st = np.ascontiguousarray(tr), np.ascontiguousarray(rate), np.ascontiguousarray(st)
    if with_rate:
        older = np.ascontiguousarray(older)
        v0 = None if v0 is None else np.ascontiguousarray(v0)
    t_solve = perf_counter()
    kind, out, v, total, rated = _warm_tangential(
        grid.nx, grid.ny, grid.dx, grid.dy, grid.x0, grid.y0, tr, rate, st,
        memory.pressure.shape[0], memory.pressure.shape[1], g1.nx, g1.ny, g1.dx, g1.dy,
        g1.x0, g1.y0, factor * float(memory.time - o.time), (i0, i1, j0, j1),
        np.ascontiguousarray(res.pressure, dtype=float), block, products, kern, cum,
        friction, xi, eta, phi, offset, omega_h, omega_s, tol, max_its, STALL_SWEEPS,
        STALL_GAIN, BLOCK_SCALE**2 * solved.size, whole, older,
        older if v0 is None else v0, smooth, grid0, float(gain), dt, with_rate)
    if kind != 2:  # (the start off the lattice: only it was formed)
        return _plus_seconds(patch, perf_counter() - t0), False, None
    # (the solve's time with its start and rate, which ran in the same call)
    t = compiled_record(t_solve, solved, operator, embed, tol, out)
    if not rated_at_all:
        rate_out = None
    elif rated:
        rate_out = v if math.isfinite(total) else None
    else:  # (off the lattice: the Python path's re-meshed rate)
        rate_out = traction_rate(t.traction, grid, time, last, gain)
    return (tangential_solved(patch, t, (xi, eta, phi), settings, friction,
                              perf_counter() - t0), True, rate_out)


def _plus_seconds(patch: PatchSolution, seconds: float) -> PatchSolution:
    """``patch`` with ``seconds`` [s] added to its work (a new record)."""
    return patch.replaced(work=patch.work.plus_seconds(seconds))


@numba.njit(cache=True, nogil=True)
def _warm_normal(what, frame, fi0, fi1, nx, ny, dx, dy, x0, y0, far, p1, u1, n1x, n1y, d1x,
                 d1y, x1, y1, box1, p0, u0, n0x, n0y, d0x, d0y, x00, y00, box0, c,
                 extrapolate, reuse, use_shown, generations, kernels, kernel, product,
                 inverse, precondition, load, self_compliance, tolerance, max_iterations,
                 chunk, limit, pressure, q, u, gaps, contact, trace_gap, trace_u, g_min,
                 rail_u, increasing, cos_gamma, cp_gap, k0, grow,
                 compliance):  # pragma: no cover - compiled
    """A warm patch's first normal solve and the check of its overlap in one call, as
    the Python path makes them (:func:`warm_normal`): the gap on the grid (nx, ny, dx,
    dy, x0, y0) of the frame ``what``, ``frame`` (its samples ``fi0:fi1``; ``far``);
    :func:`~.warmstart._pressure_start` of the remembered pressures (``p1`` ... ``reuse``
    its arguments); the solve :func:`~railcontact.normal.bem._solve_compiled` under force
    control from it (its displacement with ``use_shown``, ``generations`` old;
    ``kernels`` ... ``limit`` and ``pressure`` ... ``contact`` its arguments and arrays);
    then, where the solution is one the patch solver keeps (finite, neither next to an
    undefined gap nor at its area's edge), with a force and a penetration, the box around
    the rigid overlap on the wheel's run
    (:func:`~railcontact.geometry.kernels.overlap_box_frame`: the trace's gap
    ``trace_gap`` and rail positions ``trace_u``, ``g_min``, ``rail_u``, ``increasing``;
    the approach ``penetration / cos_gamma + cp_gap``; ``k0``, ``grow``) and the elements
    beyond the grid where the deformed gap may be negative
    (:func:`~railcontact.contact.patch._uncovered`, ``compliance`` its ``1 / (pi E*)``).

    Returns ``(fi0, fi1, kind, out, start, shown, check, flagged)``: the frame's samples
    formed,
    the start's kind (:func:`~.warmstart._pressure_start`; -1: a start without pressure),
    the solve's outputs (None: nothing was solved - a start off the lattice or without
    pressure, a gap or start not finite, a start floored to nothing: the caller takes the
    Python path), the start's pressure and displacement, and ``check``: 0 the solution
    is not one the solver keeps, or the overlap was not checked; 1 the overlap holds no
    place beyond the grid that could touch (or the solution has no force or
    penetration): the solution is the patch's; 2 it holds such places, ``flagged`` the box
    (xmin, xmax, ymin, ymax) [m] around them (that of
    :func:`~railcontact.contact.patch.uncovered`)."""
    h = np.empty((nx, ny))
    fi0, fi1 = gap_on_frame(what, frame, fi0, fi1, x0, dx, nx, y0, dy, ny, far, h)
    p, shown, kind = _pressure_start(nx, ny, dx, dy, x0, y0, p1, u1, n1x, n1y, d1x, d1y,
                                     x1, y1, box1, p0, u0, n0x, n0y, d0x, d0y, x00, y00,
                                     box0, c, extrapolate, reuse)
    if kind == 0:
        return fi0, fi1, kind, None, p, shown, 0, _NO_BOX
    if kind == 1:
        bad = positive = False  # (array_sum(p) > 0 of the floored start, NaN kept)
        for v in p.ravel():
            bad |= v != v
            positive |= v > 0.0
        if bad or not positive:
            return fi0, fi1, -1, None, p, shown, 0, _NO_BOX
    use = use_shown and kind == 2
    out = _solve_compiled(kernels, h, p, True, shown if use else u, use,
                          generations if use else 0, pressure, q, u, gaps, contact, kernel,
                          product, inverse, precondition, True, load, 0.0, dx * dy,
                          self_compliance, tolerance, max_iterations, chunk, limit)
    outcome = out[0]
    if outcome == GAP_NOT_FINITE or outcome == START_NOT_FINITE or outcome == EMPTY_START:
        return fi0, fi1, kind, None, p, shown, 0, _NO_BOX
    delta, total, largest, edge, cut = out[5], out[6], out[7], out[9], out[14]
    force = total * (dx * dy)
    if not (math.isfinite(force) and math.isfinite(delta) and math.isfinite(largest)
            and not cut and not edge):
        return fi0, fi1, kind, out, p, shown, 0, _NO_BOX
    if not (force > 0 and math.isfinite(delta) and delta > 0):
        return fi0, fi1, kind, out, p, shown, 1, _NO_BOX
    xmin, xmax, ymin, ymax, fi0, fi1 = overlap_box_frame(
        trace_gap, trace_u, g_min, delta / cos_gamma + cp_gap, rail_u, increasing, what[0],
        what[1], what[2], what[3], what[4], what[5], what[6], what[7], what[8], what[9],
        what[10], what[11], what[12], what[13], what[14], what[15], what[16], what[17],
        what[18], what[19], frame, fi0, fi1, delta, k0, grow)
    if (x0 - dx / 2 <= xmin and xmax <= x0 + (nx - 0.5) * dx and y0 - dy / 2 <= ymin
            and ymax <= y0 + (ny - 0.5) * dy):
        return fi0, fi1, kind, out, p, shown, 1, _NO_BOX
    if not (abs((xmin - x0) / dx) < _LARGEST and abs((xmax - x0) / dx) < _LARGEST
            and abs((ymin - y0) / dy) < _LARGEST and abs((ymax - y0) / dy) < _LARGEST):
        # (not finite, or beyond the integers: the Python path's check raises)
        return fi0, fi1, kind, out, p, shown, 0, _NO_BOX
    i0 = min(0, math.ceil((xmin - x0) / dx))
    i1 = max(nx, math.floor((xmax - x0) / dx) + 1)
    j0 = min(0, math.ceil((ymin - y0) / dy))
    j1 = max(ny, math.floor((ymax - y0) / dy) + 1)
    mx, my = i1 - i0, j1 - j0
    ox, oy = x0 + i0 * dx, y0 + j0 * dy
    outer = np.empty((mx, my))
    fi0, fi1 = gap_on_frame(what, frame, fi0, fi1, ox, dx, mx, oy, dy, my, far, outer)
    solved = q if out[12] else pressure
    found, a0, a1, c0, c1 = _uncovered(outer, delta, solved, -i0, -j0, x0, dx, y0, dy, ox,
                                       oy, compliance)
    if not found:
        return fi0, fi1, kind, out, p, shown, 1, _NO_BOX
    return fi0, fi1, kind, out, p, shown, 2, (ox + (a0 - 0.5) * dx, ox + (a1 + 0.5) * dx,
                                              oy + (c0 - 0.5) * dy, oy + (c1 + 0.5) * dy)


def warm_normal(cp: ContactPoint, bounds: tuple[float, float, float, float],
                grid_settings: GridSettings, settings: NormalSettings, pair: ElasticPair,
                control: Control, found: WheelSearch | None, memory: PatchMemory,
                factor: float) -> StagedNormal | None:
    """A warm patch's first normal solve and the check of its rigid overlap in one
    compiled call (:func:`_warm_normal`), as the wheel solver's Python path makes them
    (:attr:`~railcontact.contact.start.WarmStart.normal_stage`): the patch at the
    contact point ``cp`` (a frame at its reference point) of the searched wheel
    ``found``, on the grid the ``grid_settings`` mesh on ``bounds`` [m], under force
    control (``control``), started from the remembered patch ``memory`` extrapolated with
    ``factor`` (:func:`~.warmstart.previous_start`), solved with the normal ``settings``
    and ``pair`` (:func:`~railcontact.contact.patch.solve_patch_normal`'s first solve),
    its overlap on the wheel's run checked (the first check of
    :func:`~railcontact.contact.wheelrail._overlap_covered`).

    Returns a :class:`~railcontact.contact.start.StagedNormal` (its result's
    ``wall_time`` that of the whole stage: the gap, the start, the solve and the check),
    or None where the stage is not that one call (nothing was solved: the caller takes
    the Python path): a rigid contact point's frame, no searched wheel, penetration
    control or a load the solver treats apart, a start re-meshed off the lattice or
    without pressure, settings the solver would reject, no compiled FFT product (small
    grids), a gap or a start not finite, a start floored to nothing."""
    plane = cp.plane
    frame = plane.frame
    load = control.load
    if not (ENABLED and frame is not None and found is not None and load is not None
            and MIN_LOAD <= load < math.inf and load > 0.0):
        return None
    tol, max_its = settings.tolerance, settings.max_iterations
    if not (type(tol) is float and 0.0 < tol < math.inf and type(max_its) is int
            and max_its > 0 and settings.preconditioner in PRECONDITIONERS):
        return None
    c = factor
    args = start_arguments(memory, memory.older if c > 0 else None, c, True)
    if args is None:
        return None
    (p1, u1, n1x, n1y, d1x, d1y, x1, y1, box1, p0, u0, n0x, n0y, d0x, d0y, x00, y00, box0,
     c, extrapolate, reuse), generations = args
    grid = make_grid(grid_settings, bounds)
    check_operator_memory(grid, "z", settings.fft, grid_settings.max_elements)
    operator = influence_operator(grid, pair, "z", settings.fft)
    precondition = settings.preconditioner == "fft"
    products = compiled_products(operator, precondition)
    if products is None:
        return None
    t0 = perf_counter()
    kernel, self_compliance = operator.first_kernel
    shape = grid.shape
    pressure, q, u, gaps = np.empty(shape), np.empty(shape), np.empty(shape), np.empty(shape)
    contact = np.empty(shape, dtype=bool)
    trace = found.trace
    fi0, fi1, kind, out, start, shown, check, flagged = _warm_normal(
        plane.what, frame, plane.i0, plane.i1, grid.nx, grid.ny, grid.dx, grid.dy, grid.x0,
        grid.y0, FAR, p1, u1, n1x, n1y, d1x, d1y, x1, y1, box1, p0, u0, n0x, n0y, d0x,
        d0y, x00, y00, box0, c, extrapolate, reuse, generations <= REUSE_GENERATIONS,
        generations, _kernel_addresses(), kernel, *products, precondition, float(load),
        self_compliance, float(tol), min(max_its, MAX_LAST), HISTORY_CHUNK,
        float(UNDEFINED_GAP), pressure, q, u, gaps, contact, trace[4], trace[2],
        found.least_gap, float(cp.rail_u), found.increasing,
        math.cos(cp.contact_angle), cp.gap, K0, FRAME_GROW, 1.0 / (math.pi * pair.e_star))
    plane.i0, plane.i1 = fi0, fi1
    if out is None:
        return None
    res = solved_result(out, grid, pressure, q, u, gaps, contact, start, tol, t0)
    return StagedNormal(res, check == 1, flagged if check == 2 else None)


__all__ = ["warm_normal", "warm_tangential"]
