"""The warm step's stages as single compiled calls.

A warm patch's tangential stage (:func:`warm_tangential`) is three compiled kernels with
Python between them: the remembered traction advanced along its rate onto the patch's grid
(:func:`~.warmstart.previous_tangential`), SteadyGS on the window of the contact
(:func:`~railcontact.contact.patch.solve_patch_tangential`) and the traction's new rate
(:func:`~.warmstart.traction_rate`). Here they run as one call that releases the GIL
(:func:`_warm_tangential`): the same kernels on the same arrays in the same order, so the
same bits, with Python only to gather the call's arguments and to form the result's
records. Where the stage is not that one call the caller takes the Python path: ConvexGS
or a simplified model, a patch without a remembered traction rate or older step (the
first warm steps; a later load pass of a step, which starts from the pass before), zero
creepage, a start off the grid's lattice, a window small enough for a dense product or no
FFTW C interface.
"""

from __future__ import annotations

import math
from time import perf_counter

import numba
import numpy as np

from ..contact.patch import check_operator_memory, contact_window, tangential_solved
from ..contact.results import PatchSolution
from ..halfspace.grid import Grid
from ..halfspace.materials import ElasticPair
from ..halfspace.operator import resolve_backend
from ..settings import TangentialSettings
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
from .warmstart import PatchMemory, _rate_on, _traction_start, traction_rate

ENABLED = True
"""Whether the stages run as their compiled calls where they can; False: every stage takes
the Python path (the same bits, slower), for a study that observes the solvers' own calls
(e.g. SteadyGS's warm starts, ``scripts/study_warm_relaxation.py``)."""
NO_RATE = (0, 0, 1.0, 1.0, 0.0, 0.0)
"""The older step's grid (nx, ny, dx, dy, x0, y0) passed where no rate is formed."""
_NO_FIELD = np.zeros((0, 0, 0))


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
                    gain: float) -> tuple[bool, np.ndarray | None]:
    """The tangential stage of a warm ``patch`` (its normal solution found) in one
    compiled call (:func:`_warm_tangential`), as the time step's Python path forms it:
    its start the remembered patch ``memory`` advanced along its traction rate by the
    extrapolation ``factor`` (:func:`~.warmstart.previous_tangential`), the solve
    :func:`~railcontact.contact.patch.solve_patch_tangential` with the ``settings``
    (SteadyGS), ``pair``, the FFT backend ``fft`` and the patch's ``creepage`` (side
    frame), then the traction's rate after ``last`` (the older step) at ``time``, smoothed
    with ``gain`` (:func:`~.warmstart.traction_rate`).

    Returns ``(done, rate)``: ``done`` False where the stage is not that call (nothing was
    changed: the caller takes the Python path); else the patch holds its tangential
    solution, its work counted, and ``rate`` is the traction's rate (None: not formed)."""
    t0 = perf_counter()
    friction, rate = settings.friction, memory.traction_rate
    tr, st, o = memory.traction, memory.state, memory.older
    if not (ENABLED and settings.solver == "steadygs" and settings.model == "bem"
            and type(friction) is float and 0.0 <= friction < math.inf
            and _steady_solve_c is not None and factor > 0 and o is not None
            and tr is not None and rate is not None and rate.shape == tr.shape
            and tr.ndim == 3 and st is not None and st.dtype == np.int8 and st.ndim == 2
            and memory.pressure.ndim == 2):
        return False, None
    xi, eta, phi = (float(c) for c in creepage)  # (as the solver's checks give them)
    if not (xi - xi == 0.0 and eta - eta == 0.0 and phi - phi == 0.0
            and (xi != 0.0 or eta != 0.0 or phi != 0.0)):
        return False, None
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
        return False, None  # (a dense product, small grids: no compiled solve)
    check_operator_memory(solved, "xy", fft)
    operator = rolling_operator(solved, pair, fft)
    setup = compiled_setup(operator, settings.tolerance, settings.max_iterations, OMEGA_H,
                           OMEGA_S, "auto")
    if setup is None:
        patch.work.seconds += perf_counter() - t0  # (the operator's, when it was formed)
        return False, None
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
        patch.work.seconds += perf_counter() - t0
        return False, None
    # (the solve's time with its start and rate, which ran in the same call)
    t = compiled_record(t_solve, solved, operator, embed, tol, out)
    patch.tangential_model, patch.tangential_estimate = settings.model, settings.estimate
    patch.friction = friction
    patch.tangential = t
    tangential_solved(patch, (xi, eta, phi))
    if not rated_at_all:
        rate_out = None
    elif rated:
        rate_out = v if math.isfinite(total) else None
    else:  # (off the lattice: the Python path's re-meshed rate)
        rate_out = traction_rate(t.traction, grid, time, last, gain)
    patch.work.seconds += perf_counter() - t0
    return True, rate_out


__all__ = ["warm_tangential"]
