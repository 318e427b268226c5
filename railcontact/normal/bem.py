"""Normal contact on a half-space by the Polonsky–Keer extended conjugate gradient method.

Problem (per element ``I`` of the potential-contact grid)::

    g_I = h_I + u_I - delta >= 0,   p_I >= 0,   g_I p_I = 0,   u = A_zz * p

with the undeformed gap ``h`` [m], the elastic displacement difference ``u`` [m] from the
influence operator, the rigid approach (penetration) ``delta`` [m] and the pressure ``p``
[Pa]. Either ``delta`` is prescribed (penetration control) or the total force
``F = dx dy sum p`` [N] (force control; ``delta`` is then the mean of ``h + u`` over the
contact set, Polonsky & Keer, Wear 231 (1999) 206–219).

Convergence: iteration ``k`` stops when the relative change of the pressure::

    eps_k = sum_I |p_I^k - p_I^(k-1)| / sum_I p_I^k

falls below the tolerance ``eps_n`` (the paper's normal tolerance). The iteration count is
the number of CG steps taken. Each costs one convolution, ``A t`` of the search direction,
and one more with the preconditioner: the displacements ``u = A p`` of the new pressure
are ``u - tau A t`` plus the influence columns of the few elements the step clipped or let
in (:data:`CHANGE_LIMIT`; beyond it, and at the start, ``A p`` is convolved - unless the
caller gives the start's ``A p``, as a time step does from the previous steps'
displacements: ``initial_displacement``, :class:`Displacement`).

Preconditioning (``preconditioner="fft"``, the default): the gradient on the contact set is
multiplied by an FFT approximate inverse of the influence matrix
(:meth:`~railcontact.halfspace.operator.InfluenceOperator.preconditioner`, the idea of CONTACT's
NormCG, Vollebregt, JCP 257A (2014) 333-351) and projected back onto the contact set
(and, under force control, onto zero mean), which keeps the step symmetric positive
definite on each active set. Plain Polonsky–Keer CG (``"none"``) reduces the pressure
change only about 1.5 times per iteration, from any start, because the half-space operator
damps element-scale pressure errors: the edge errors of an estimate then cost almost as
many iterations as a start on the whole grid. With the preconditioner the element-scale
errors go in a few steps, and how well the start's patch fits decides the count (the
paper's finding, Sec. 4.1.2).
Elements that interpenetrate without pressure enter the contact set with the pressure of
a preconditioned step (``-tau * kappa * g``, ``kappa`` the Rayleigh ratio of the
preconditioner on the gradient).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numba
import numpy as np

from ..errors import RailContactError, check_count, check_positive
from ..halfspace.grid import Grid
from ..halfspace.hertz import no_contact_load
from ..halfspace.operator import PRECONDITIONER_FLOOR, InfluenceOperator, packed_product
from ..halfspace.pointers import address, function_at
from ..halfspace.sums import array_sum, numpy_sum
from ..status import Work

PRECONDITIONERS = ("fft", "none")
STALL_ITERATIONS = 100
"""Iterations without progress after which the CG stops, not converged (a tolerance below
what round-off lets it reach would otherwise run to ``max_iterations``)."""
STALL_GAIN = 0.99
"""Progress: the relative pressure change falls below this fraction of its best so far."""
CHANGE_LIMIT = 96
"""Most elements whose pressure a CG step may clip to zero or let enter the contact with
``A p`` still updated from ``A t`` and their influence columns (each column costs ``nx ny``
multiply-adds, 0.2 ns each here; a convolution on 40 x 40 or 56 x 48 elements costs as
much as about 160 columns); beyond it ``A p`` is convolved anew."""
REFRESH_ITERATIONS = 20
"""Updates of ``A p`` without a convolution after which a converged step forms it anew
before its final check (round-off of the updates, far below any tolerance)."""
REUSE_GENERATIONS = 16
"""Solves in a row whose start's ``A p`` may come from the remembered displacements of
earlier solves (:class:`Displacement`) before one is convolved again: the round-off of
the updates is carried from solve to solve, and an extrapolated start adds up to
``1 + 2c`` times the remembered ones' (:func:`railcontact.timestep.warmstart.previous_start`)."""
SCALE_RANGE = (1e-100, 1e100)
"""A converged solution's largest pressure [Pa] and depth of interpenetration
``delta - min(h)`` [m] lie in this range, else it is reported not converged: the CG's inner
products are sums of their squares, which under- or overflow beyond it (a sphere scaled to
1e-170 - gap, load and pressure - "converged" in one iteration with a tenth of the peak
pressure; under penetration control at 1e150 with 0.6 % of the force)."""


@dataclass(frozen=True)
class Displacement:
    """The elastic displacement ``u = A p`` [m] of a pressure ``p`` on a grid, as a solve
    formed it (by a convolution, or carried by the CG's updates from one).

    Attributes
    ----------
    values
        ``u`` [m], (nx, ny): ``A p`` to round-off.
    generations
        Solves since ``values`` was last formed by a convolution: 0 when the solve that
        returned it convolved ``A p`` at its start or later; a start's displacement formed
        from remembered ones (a time step's extrapolation) counts one more than the
        largest of theirs. A start older than :data:`REUSE_GENERATIONS` is convolved.
    """

    values: np.ndarray
    generations: int = 0


@dataclass(frozen=True)
class NormalResult:
    """Solution of the normal contact problem on a grid (SI units).

    Attributes
    ----------
    grid
        The potential-contact grid.
    pressure
        Pressure per element [Pa], shape (nx, ny).
    contact
        Contact mask (pressure > 0), shape (nx, ny).
    gap
        Deformed gap ``h + u - delta`` [m] (zero in contact, positive outside).
    force
        Total normal force [N].
    penetration
        Rigid approach delta [m].
    max_pressure
        Largest element pressure [Pa].
    area
        Contact area (contact elements times element area) [m^2].
    iterations
        CG iterations taken.
    converged
        True when the tolerance was reached within ``max_iterations``.
    message
        What happened, in words.
    wall_time
        Solver wall time [s].
    error
        The final relative pressure change eps.
    history
        eps after each iteration.
    touches_boundary
        True when the contact reaches the outer ring of the potential area (the area is
        then probably too small).
    contact_box
        ``(i0, i1, j0, j1)``: the contact elements lie in the rows ``i0:i1`` and columns
        ``j0:j1``; None without contact.
    displacement
        ``A p`` of the pressure [m] as the solve carried it (its gap is ``h + u - delta``),
        for a later solve's start (:func:`solve_normal`'s ``initial_displacement``); None
        when the solve did not form it (no contact, a pressure that vanished).
    start
        The initial pressure [Pa] the solve was given (the caller's array, not copied; its
        error against :attr:`pressure` is formed only when asked,
        :func:`~railcontact.normal.starterror.estimate_error`); None when it started
        from its own uniform pressure.
    next_to_undefined
        True when a contact element is on or next to an element whose gap is undefined
        (:func:`solve_normal`'s ``undefined_gap`` or more); False without
        ``undefined_gap``.
    """

    grid: Grid
    pressure: np.ndarray
    contact: np.ndarray
    gap: np.ndarray
    force: float
    penetration: float
    max_pressure: float
    area: float
    iterations: int
    converged: bool
    message: str
    wall_time: float
    error: float
    history: np.ndarray = field(repr=False)
    touches_boundary: bool = False
    contact_box: tuple[int, int, int, int] | None = None
    displacement: Displacement | None = field(default=None, repr=False)
    start: np.ndarray | None = field(default=None, repr=False, compare=False)
    next_to_undefined: bool = False

    @property
    def work(self) -> Work:
        """The solve's work (:class:`~railcontact.status.Work`, the solver results'
        record): its CG iterations and wall time [s]."""
        return Work(normal_iterations=self.iterations, load_passes=0,
                    seconds=self.wall_time)


def _uniform_start(gap: np.ndarray, operator: InfluenceOperator, penetration: float) -> np.ndarray:
    """Best uniform pressure for penetration control: minimises the complementary energy
    0.5 p.Ap - p.(delta - h) over p = c * 1, floored at a tiny positive value."""
    k1 = float(np.sum(operator.apply(np.ones_like(gap))))
    c = float(np.sum(penetration - gap)) / k1
    return np.full_like(gap, max(c, 1e-6 * penetration * gap.size / k1))


def _overlaps(h: np.ndarray, u: np.ndarray, p: np.ndarray, force_control: bool,
              delta: float, tolerance: float) -> bool:
    """Whether elements outside the contact overlap by more than the tolerance allows:
    the gap ``h + u - delta`` there below ``-tolerance`` times the approach (the
    complementarity the relative pressure change does not check; a start far from the
    answer can make that change small while elements that belong to the contact are
    still out of it)."""
    return bool(_overlaps_flat(np.ascontiguousarray(h, dtype=float).ravel(),
                               np.ascontiguousarray(u, dtype=float).ravel(),
                               np.ascontiguousarray(p, dtype=float).ravel(),
                               force_control, float(delta), float(tolerance)))


REASSOCIATE = {"reassoc", "contract"}
"""LLVM fast-math flags of the CG's passes: sums may be reordered (vectorised); no
assumption about NaN or infinities, which the solver must see."""

# The CG's array work, compiled: each function is one or two passes over the flat element
# arrays (row-major, as the grid's (nx, ny) arrays), in place of a dozen numpy calls with
# their masks and temporaries. ``c`` is the contact set of the iteration (bool).
# The three with fast-math flags that the iterations call (_gradient, _direction, _step)
# are called with one signature each (the solve's C-ordered, writeable arrays): the
# compiled solve (_solve_compiled) calls the code of that signature through
# pointers, the code Python's calls run (:mod:`~railcontact.halfspace.pointers`).
_F, _B = numba.types.float64, numba.types.boolean
_FLAT, _SET = numba.types.float64[::1], numba.types.boolean[::1]
_GRID = numba.types.float64[:, ::1]
_GRADIENT = _F(_FLAT, _FLAT, _FLAT, _F, _B, _SET, _FLAT, _FLAT)
_DIRECTION = numba.types.UniTuple(_F, 2)(_FLAT, _FLAT, _SET, _FLAT, _B, _B, _F)
_STEP = numba.types.Tuple((_F, _F, _F, numba.types.int64, _B, _B))(
    _FLAT, _FLAT, _FLAT, _FLAT, _FLAT, _SET, _FLAT, _F, _F, _B, _B, _F, _F, _F,
    numba.types.float64[:, ::1], numba.types.int64, numba.types.int64,
    numba.types.int64[::1], _FLAT)

@numba.njit(cache=True, nogil=True)
def _overlaps_flat(h, u, p, force_control, delta, tolerance):  # pragma: no cover - compiled
    n = p.size
    count = 0
    total = 0.0
    hmin = np.inf
    for i in range(n):
        hmin = min(hmin, h[i])
        if p[i] > 0.0:
            count += 1
            total += h[i] + u[i]
    if count == 0 or count == n:
        return False
    d = total / count if force_control else delta
    scale = max(abs(d - hmin), 1e-300)
    least = np.inf
    for i in range(n):
        if not p[i] > 0.0:
            least = min(least, h[i] + u[i] - d)
    return least < -tolerance * scale


@numba.njit(cache=True, nogil=True)
def _summary(h, u, p, delta, own_delta, gap, contact):  # pragma: no cover - compiled
    """The result's fields on the (nx, ny) arrays: the approach (``own_delta``: the mean
    of ``h + u`` on the contact, or the least ``h`` without contact), ``gap = h + u -
    delta`` and ``contact = p > 0`` (in place); returns ``(delta, sum p, max(p, 0),
    contact elements, whether the contact reaches the outer ring, (i0, i1, j0, j1))``:
    the contact in the rows ``i0:i1`` and columns ``j0:j1`` (-1 without contact)."""
    nx, ny = p.shape
    if own_delta:
        total = 0.0
        count = 0
        least = np.inf
        for i in range(nx):
            for j in range(ny):
                least = min(least, h[i, j])
                if p[i, j] > 0.0:
                    total += h[i, j] + u[i, j]
                    count += 1
        delta = total / count if count > 0 else least
    total = 0.0
    largest = 0.0
    nan = False
    count = 0
    edge = False
    i0 = j0 = -1
    i1 = j1 = 0
    for i in range(nx):
        for j in range(ny):
            gap[i, j] = h[i, j] + u[i, j] - delta
            c = p[i, j] > 0.0
            contact[i, j] = c
            total += p[i, j]
            largest = max(largest, p[i, j])
            nan = nan or p[i, j] != p[i, j]  # (max ignores NaN: a NaN must show)
            if c:
                count += 1
                if i == 0 or j == 0 or i == nx - 1 or j == ny - 1:
                    edge = True
                if i0 < 0:
                    i0 = i
                i1 = i + 1
                if j0 < 0 or j < j0:
                    j0 = j
                j1 = max(j1, j + 1)
    return delta, total, (np.nan if nan else largest), count, edge, (i0, i1, j0, j1)


@numba.njit(cache=True, nogil=True)
def _least(h):  # pragma: no cover - compiled
    """The smallest value of ``h`` (any shape, C-ordered; +inf when empty) and whether
    all its values are finite, in one pass."""
    flat = h.reshape(h.size)
    least = np.inf
    finite = True
    for i in range(flat.size):
        x = flat[i]
        finite = finite and x - x == 0.0
        least = min(least, x)
    return float(least), finite


@numba.njit(cache=True, nogil=True)
def _floored(p, q, index, change, load, area):  # pragma: no cover - compiled
    """The start ``q = np.maximum(p, 0.0)`` (in place, both C-ordered (nx, ny); NaN kept
    and -0 made 0, as numpy's) of ``p`` and its sum, added as numpy adds it; with a
    ``load`` > 0 [N] and a positive sum, ``q`` scaled to it: ``q *= load / (area *
    sum)`` (``area`` of an element [m^2]). The elements set to zero (negative): the first
    ``index.size`` of them (flat index, and the change ``0 - p``) in ``index`` and
    ``change``. Returns ``(sum, how many were negative, the scale, whether all of ``p``
    is finite)`` (scale 1 when not scaled)."""
    flat, qf = p.reshape(p.size), q.reshape(q.size)
    changes = 0
    finite = True
    for i in range(flat.size):
        x = flat[i]
        finite = finite and x - x == 0.0
        if x > 0.0 or x != x:
            qf[i] = x
        else:
            qf[i] = 0.0
            if x < 0.0:
                if changes < index.size:
                    index[changes] = i
                    change[changes] = -x
                changes += 1
    total = numpy_sum(q)
    scale = 1.0
    if load > 0.0 and total > 0.0:
        scale = load / (area * total)
        for i in range(qf.size):
            qf[i] *= scale
    return total, changes, scale, finite


@numba.njit(cache=True, nogil=True, fastmath=REASSOCIATE)
def _gradient(h, u, p, delta, force_control, c, g, gm):  # pragma: no cover - compiled
    """The contact set ``c`` (p > 0, or where the bodies interpenetrate if no pressure is
    left), the approach (force control: the mean of ``h + u`` on ``c``), the gradient
    ``g = h + u - delta`` and ``gm``, the gradient on ``c`` and zero elsewhere; returns
    the approach."""
    n = p.size
    count = 0
    for i in range(n):
        c[i] = p[i] > 0.0
        if c[i]:
            count += 1
    if count == 0:  # pressure vanished (possible under penetration control)
        for i in range(n):
            c[i] = (h[i] + u[i] - delta) < 0.0
            if c[i]:
                count += 1
    if force_control and count > 0:
        total = 0.0
        for i in range(n):
            if c[i]:
                total += h[i] + u[i]
        delta = total / count
    for i in range(n):
        gi = h[i] + u[i] - delta
        g[i] = gi
        gm[i] = gi if c[i] else 0.0
    return delta


@numba.njit(cache=True, nogil=True, fastmath=REASSOCIATE, inline="always")
def _mean_on(x, c):  # pragma: no cover - compiled
    """The mean of ``x`` over the elements set in ``c`` (0 without any)."""
    total = 0.0
    count = 0
    for i in range(x.size):
        if c[i]:
            total += x[i]
            count += 1
    return total / max(count, 1)


@numba.njit(cache=True, nogil=True, fastmath=REASSOCIATE)
def _direction(g, z, c, t, project, conjugate, g_old):  # pragma: no cover - compiled
    """The search direction ``t`` (in place): the correction ``z`` on ``c`` (minus its mean
    there when ``project``) plus the conjugate share of the previous ``t``; returns
    ``(g.z, g.g)`` on ``c``."""
    n = g.size
    zmean = _mean_on(z, c) if project else 0.0
    gz = 0.0
    gg = 0.0
    for i in range(n):
        if c[i]:
            gz += g[i] * (z[i] - zmean)
            gg += g[i] * g[i]
    beta = gz / g_old if conjugate and g_old > 0.0 else 0.0
    for i in range(n):
        t[i] = (z[i] - zmean) + beta * t[i] if c[i] else 0.0
    return gz, gg


@numba.njit(cache=True, nogil=True, fastmath=REASSOCIATE)
def _add_columns(u, kernel, nx, ny, index, change, changes):  # pragma: no cover - compiled
    """``u += sum_k change[k] * A[:, index[k]]``: the columns of the influence matrix are
    the offset kernel (2nx-1, 2ny-1) shifted to each element; a row of ``u`` at a time,
    so that it stays in cache while the columns are added."""
    u2 = u.reshape((nx, ny))
    for ix in range(nx):
        urow = u2[ix]
        for k in range(changes):
            j = index[k]
            jx = j // ny
            jy = j - jx * ny
            krow = kernel[nx - 1 + ix - jx, ny - 1 - jy:2 * ny - 1 - jy]
            dj = change[k]
            for iy in range(ny):
                urow[iy] += dj * krow[iy]


@numba.njit(cache=True, nogil=True)
def _shown_start(values, u, scale, kernel, index, change, changes):  # pragma: no cover
    """``u = scale (values + sum_k change[k] A[:, index[k]])`` (:func:`_add_columns`):
    ``A p`` of a start from ``A`` of the pressure before it was floored (``values``,
    (nx, ny)) and scaled; returns whether ``values`` are finite (else ``u`` is not
    formed)."""
    nx, ny = u.shape
    for i in range(nx):
        for j in range(ny):
            v = values[i, j]
            if not v - v == 0.0:
                return False
            u[i, j] = v
    uf = u.reshape(u.size)
    _add_columns(uf, kernel, nx, ny, index, change, changes)
    if scale != 1.0:
        for i in range(uf.size):
            uf[i] *= scale
    return True


@numba.njit(cache=True, nogil=True, fastmath=REASSOCIATE)
def _step(p, q, t, g, r, c, u, gz, gg, preconditioned, force_control, load, area,
          self_compliance, kernel, nx, ny, index, change):  # pragma: no cover - compiled
    """One CG step from ``p`` into ``q``; ``r = A t`` (before its mean is taken out).

    The step length ``tau`` along ``t``, the update ``q = max(p - tau t, 0)``, the
    elements that interpenetrate without pressure entering with a preconditioned step's
    pressure, and (force control) the scaling to the load. ``u = A p`` becomes ``A q``
    without a convolution: ``A (p - tau t) = u - tau r``, plus, for every element where
    ``q`` is not the linear update (clipped or entering), its change times its column of
    the influence matrix (the kernel shifted), when there are at most ``index.size`` such
    elements. Returns ``(tau, sum |q - p|, sum q, number of changed elements, whether an
    element entered, whether u was updated)``; ``sum q <= 0`` under force control returns
    at once (the pressure vanished; ``q`` unscaled, ``u`` untouched).
    """
    n = p.size
    rmean = _mean_on(r, c) if force_control else 0.0
    rt = 0.0
    gt = 0.0
    for i in range(n):
        if c[i]:
            rt += (r[i] - rmean) * t[i]
            gt += g[i] * t[i]
    tau = 0.0 if (rt <= 0.0 or gz <= 0.0) else gt / rt  # 0: exact on the current set
    kappa = gz / max(gg, 1e-300) if preconditioned else 1.0
    changes = 0
    entered = False
    total = 0.0
    for i in range(n):
        linear = p[i] - tau * t[i]
        qi = 0.0 if linear < 0.0 else linear
        if qi == 0.0 and g[i] < 0.0:
            entered = True
            if tau > 0.0:
                qi = qi - tau * kappa * g[i]
            else:  # exact on the current set: each element closes its own gap
                qi = -g[i] / self_compliance
        q[i] = qi
        total += qi
        if qi != linear:
            if changes < index.size:
                index[changes] = i
                change[changes] = qi - linear
            changes += 1
    if force_control and not total > 0.0:
        return tau, np.inf, total, changes, entered, False
    scale = load / (area * total) if force_control else 1.0
    moved = 0.0
    total = 0.0
    for i in range(n):
        qi = q[i] * scale if force_control else q[i]
        q[i] = qi
        total += qi
        moved += abs(qi - p[i])
    updated = changes <= index.size
    if updated:
        for i in range(n):
            u[i] = u[i] - tau * r[i]
        _add_columns(u, kernel, nx, ny, index, change, changes)
        if force_control:
            for i in range(n):
                u[i] *= scale
    return tau, moved, total, changes, entered, updated


RAN_OUT, CONVERGED, STALLED, VANISHED, HISTORY_FULL = range(5)
"""How :func:`_iterate_py` ended: ``last`` iteration reached or a non-finite eps (not
converged), converged, stalled (:data:`STALL_ITERATIONS`), the pressure vanished (force
control), or its history array full (call it again to go on)."""
HISTORY_CHUNK = 512
"""Length of the history array :func:`_iterate_py` is given per call."""
MAX_LAST = 2**62
"""The iteration limit :func:`_iterate_py` is given at most (a machine integer; no solve
comes near it)."""


def _apply(product, x: np.ndarray, out: np.ndarray) -> None:
    """``out = A x`` (or the preconditioner's ``M x``) by a product of one solve: from
    Python ``product`` is a function ``f(x, out)``
    (:meth:`~railcontact.halfspace.operator.InfluenceOperator.bound`); in compiled code
    the arguments of the packed plan's compiled product (:meth:`~railcontact.halfspace.
    operator.InfluenceOperator.compiled_product`, run by
    :data:`~railcontact.halfspace.operator.packed_product`; the same bits). ``x`` and
    ``out`` (nx, ny) float, C-ordered."""
    product(x, out)


if packed_product[1] is not None:
    from numba.extending import overload

    _packed_rows = packed_product[1]

    @overload(_apply, jit_options={"nogil": True})
    def _apply_compiled(product, x, out):  # pragma: no cover - compiled
        def apply(product, x, out):
            plans, z_in, z_s, w_s, w_out, a, b, n = product
            _packed_rows(plans, x, z_in, z_s, w_s, w_out, a, b, n, out)
        return apply


def _iterate_py(gradient, direction, step, h, p, q, u, work, c, kernel, index, change,
                product, inverse, precondition, force_control, load, area, self_compliance,
                tolerance, last, state, counts, hist):  # pragma: no cover - also compiled
    """The CG iterations of :func:`solve_normal` on its arrays (all C-ordered): the gap
    ``h``, the pressures ``p`` (the current one) and ``q`` and ``u = A p`` (nx, ny), the
    work rows ``work`` (5, nx ny: the gradient, its part on the contact, the direction,
    its product, the preconditioned gradient) and the contact set ``c``.

    One source, run two ways: as Python, ``gradient``, ``direction`` and ``step`` the
    kernels :func:`_gradient`, :func:`_direction` and :func:`_step` and ``product`` and
    ``inverse`` functions ``f(x, out)`` (any backend); compiled (within
    :func:`_solve_compiled`, one call that releases the GIL for the whole solve), the
    kernels first-class functions that call the same kernels' own code through pointers
    (:mod:`~railcontact.halfspace.pointers`: linked into this loop, LLVM could compile
    their fast-math sums anew and change their last bits) and the products the packed plan's
    arguments (:func:`_apply`). Both run the same compiled code in the same order: the
    same bits. ``inverse`` is not used without ``precondition`` (give ``product``).

    The state carried between calls (and out): ``state`` (float) the approach, the
    previous ``g.z``, the best eps and the last eps; ``counts`` (int) the iterations
    taken, the iteration of the best eps, the updates of ``u`` since its last
    convolution, the solves since then (:class:`Displacement`), whether the next
    direction is conjugate and whether ``p`` and ``q`` have been swapped (the current
    pressure in the given ``q``). It iterates up to iteration ``last`` and writes each
    iteration's eps into ``hist``; returns (how it ended, :data:`RAN_OUT` ..
    :data:`HISTORY_FULL`; the number of eps written). On :data:`VANISHED` the unscaled
    pressure is in the array that is not the current one."""
    nx, ny = h.shape
    n = h.size
    hf, uf, pf, qf = h.reshape(n), u.reshape(n), p.reshape(n), q.reshape(n)
    gf, gmf, tf, rf = work[0], work[1], work[2], work[3]
    gm, t, r = gmf.reshape((nx, ny)), tf.reshape((nx, ny)), rf.reshape((nx, ny))
    zf = work[4] if precondition else gf
    z = zf.reshape((nx, ny))
    delta, g_old, best, err = (float(state[0]), float(state[1]), float(state[2]),
                               float(state[3]))
    its, best_its, fresh, generations = counts[0], counts[1], counts[2], counts[3]
    conjugate, swapped = counts[4] != 0, counts[5] != 0
    status = RAN_OUT
    k = 0
    while its < last:
        if k == hist.size:
            status = HISTORY_FULL
            break
        its += 1
        delta = gradient(hf, uf, pf, delta, force_control, c, gf, gmf)
        if precondition:
            _apply(inverse, gm, z)
        gz, gg = direction(gf, zf, c, tf, force_control and precondition, conjugate, g_old)
        g_old = gz
        _apply(product, t, r)
        _, moved, total, changes, entered, updated = step(
            pf, qf, tf, gf, rf, c, uf, gz, gg, precondition, force_control, load, area,
            self_compliance, kernel, nx, ny, index, change)
        conjugate = not entered
        if force_control and not total > 0.0:
            status = VANISHED
            break
        p, q, pf, qf = q, p, qf, pf
        swapped = not swapped
        if updated:
            fresh += 1
        else:  # too many elements left or entered the contact: convolve
            _apply(product, p, u)
            fresh = generations = 0
        err = moved / total if total > 0 else (0.0 if total == 0 else np.nan)  # NaN stops
        hist[k] = err
        k += 1
        if not math.isfinite(err):
            break
        if err < tolerance:
            if fresh > REFRESH_ITERATIONS:  # the updates' round-off, renewed
                _apply(product, p, u)
                fresh = generations = 0
            if not _overlaps_flat(hf, uf, pf, force_control, delta, tolerance):
                status = CONVERGED
                break
        if err < STALL_GAIN * best:
            best, best_its = err, its
        elif its - best_its >= STALL_ITERATIONS:  # at round-off: a tolerance out of reach
            status = STALLED
            break
    state[0], state[1], state[2], state[3] = delta, g_old, best, err
    counts[0], counts[1], counts[2], counts[3] = its, best_its, fresh, generations
    counts[4], counts[5] = conjugate, swapped
    return status, k


def _iterations(gradient, direction, step, h, p, q, u, work, c, kernel, index, change,
                product, inverse, precondition, force_control, load, area, self_compliance,
                tolerance, last, state, counts, hist):
    """:func:`_iterate_py` as Python; in compiled code its compiled twin (the loop of
    :func:`_solve_py` run either way)."""
    return _iterate_py(gradient, direction, step, h, p, q, u, work, c, kernel, index,
                       change, product, inverse, precondition, force_control, load, area,
                       self_compliance, tolerance, last, state, counts, hist)


_iterate = numba.njit(cache=True, nogil=True)(_iterate_py)
if packed_product[1] is not None:

    @overload(_iterations, jit_options={"nogil": True})
    def _iterations_compiled(gradient, direction, step, h, p, q, u, work, c, kernel, index,
                             change, product, inverse, precondition, force_control, load,
                             area, self_compliance, tolerance, last, state, counts,
                             hist):  # pragma: no cover - compiled
        def iterations(gradient, direction, step, h, p, q, u, work, c, kernel, index,
                       change, product, inverse, precondition, force_control, load, area,
                       self_compliance, tolerance, last, state, counts, hist):
            return _iterate(gradient, direction, step, h, p, q, u, work, c, kernel, index,
                            change, product, inverse, precondition, force_control, load,
                            area, self_compliance, tolerance, last, state, counts, hist)
        return iterations


@numba.njit(cache=True, nogil=True)
def _next_to(contact, gap, limit):  # pragma: no cover - compiled
    """Whether an element with ``gap >= limit`` (NaN: not) is in ``contact`` or has a
    neighbour along x or y that is, in one pass (the gap is read; the contact only
    around such elements)."""
    nx, ny = gap.shape
    for i in range(nx):
        for j in range(ny):
            if gap[i, j] >= limit and (
                    contact[i, j] or (i > 0 and contact[i - 1, j])
                    or (i + 1 < nx and contact[i + 1, j]) or (j > 0 and contact[i, j - 1])
                    or (j + 1 < ny and contact[i, j + 1])):
                return True
    return False


SOLVED, GAP_NOT_FINITE, START_NOT_FINITE, NO_OVERLAP, EMPTY_START = range(5)
"""What :func:`_solve_py` did: solved (the iterations' end in its status), found the gap
or the start's pressure not finite, found no interpenetration (penetration control: the
result is no contact), or found no pressure in the floored start (the caller forms
another start, :func:`_formed_start`, and calls it again)."""


def _solve_py(gradient, direction, step, shown_start, h, start, floor, shown, use_shown,
              generations, p, q, u, gap, contact, kernel, product, inverse, precondition,
              force_control, load, penetration, area, self_compliance, tolerance,
              max_iterations, chunk, limit):  # pragma: no cover - also compiled
    """:func:`solve_normal` on its checked arrays (all C-ordered, (nx, ny)), from the
    check of the gap ``h`` to the result's fields, as :func:`_iterate_py` one source run
    two ways: as Python (``gradient``, ``direction``, ``step`` and ``shown_start`` the
    kernels :func:`_gradient`, :func:`_direction`, :func:`_step` and
    :func:`_shown_start`, ``product`` and ``inverse`` functions ``f(x, out)``), or
    compiled (:func:`_solve_compiled`, one call that releases the GIL: the kernels called
    through pointers, the products the packed plan's arguments).

    The start: with ``floor``, the given pressure ``start`` floored at zero into ``p``
    and (force control) scaled to the ``load`` [N] (:func:`_floored`); else ``p`` holds
    the start, formed. Its ``A p``: with ``use_shown``, from ``shown`` (``A`` of
    ``start``, :class:`Displacement`'s values, formed ``generations`` solves ago) less the
    columns of the elements the floor set to zero (:func:`_shown_start`), else
    convolved. The iterations (:func:`_iterate_py`) in ``p`` and ``q`` with ``u = A p``,
    their history in chunks of ``chunk``; then the result's ``gap`` and ``contact`` (in
    place, :func:`_summary`) and, with a finite ``limit`` [m], whether the contact is
    next to an element whose gap is ``limit`` or more (:func:`_next_to`).

    Returns ``(outcome, status, history, iterations, eps, penetration, sum of the
    pressure, largest pressure, contact elements, whether the contact reaches the edge,
    (i0, i1, j0, j1), generations of u, whether the result's pressure is in q, least gap,
    whether the contact is next to the limit)``: the outcome :data:`SOLVED` ..
    :data:`EMPTY_START`, the iterations' end :data:`RAN_OUT` .. :data:`VANISHED`."""
    n = h.size
    hmin, finite = _least(h)
    index = np.empty(CHANGE_LIMIT, dtype=np.int64)
    change = np.empty(CHANGE_LIMIT)
    outcome = SOLVED
    floored = 0  # elements the start set to zero (their columns leave A p)
    scale = 1.0  # the start's scale to the load
    if not finite:
        outcome = GAP_NOT_FINITE
    else:
        total = 1.0
        if floor:  # np.maximum(start, 0.0), its sum, scaled
            total, floored, scale, finite = _floored(
                start, p, index if use_shown else index[:0], change,
                load if force_control else 0.0, area)
        if not finite:
            outcome = START_NOT_FINITE
        elif not force_control and hmin >= penetration:  # (np.all(h >= penetration))
            outcome = NO_OVERLAP
        elif not total > 0.0:  # (p >= 0: no element has pressure)
            outcome = EMPTY_START
    status = RAN_OUT
    hist = np.empty(0)
    its = 0
    err = 0.0
    delta = penetration
    final = False  # under force control, the approach from the solution's own u
    in_q = False
    if outcome == SOLVED:
        # u = A p of the current p, kept up to date by the iterations: the start's shown
        # displacement less the columns of the elements the start set to zero, or
        # convolved
        if not (use_shown and floored <= CHANGE_LIMIT
                and shown_start(shown, u, scale, kernel, index, change, floored)):
            _apply(product, p, u)
            generations = 0
        # work rows (_iterate_py): the gradient, its part on the contact, the direction
        # (the first one's previous one zero), its product, the preconditioned gradient
        work = np.empty((5, n))
        work[2, :] = 0.0
        c = np.empty(n, dtype=np.bool_)
        state = np.array([0.0 if force_control else penetration, 1.0, np.inf, np.inf])
        counts = np.zeros(6, dtype=np.int64)
        counts[3] = generations
        size = min(max_iterations, chunk)
        hist = np.empty(size)
        filled = 0
        while True:
            status, k = _iterations(gradient, direction, step, h, p, q, u, work, c, kernel,
                                    index, change, product, inverse, precondition,
                                    force_control, load, area, self_compliance, tolerance,
                                    max_iterations, state, counts, hist[filled:])
            filled += k
            if status != HISTORY_FULL:
                break
            grown = np.empty(filled + size)
            grown[:filled] = hist[:filled]
            hist = grown
        hist = hist[:filled]
        in_q = counts[5] != 0
        if in_q:  # p and q swapped: the current pressure is in q's array
            p, q = q, p
        delta, err = state[0], state[3]
        its, fresh, generations = counts[0], counts[2], counts[3]
        if status == VANISHED:  # the result: the unscaled pressure, in the other array
            p, in_q, err = q, not in_q, np.inf
        else:
            if status != CONVERGED and (fresh > 0 or generations > 0):
                _apply(product, p, u)  # the gap from a convolution
                generations = 0
            final = force_control
    elif outcome == NO_OVERLAP:
        p[:, :] = 0.0
        u[:, :] = 0.0
    total = largest = 0.0
    count = 0
    edge = cut = False
    box = (-1, 0, -1, 0)
    if outcome == SOLVED or outcome == NO_OVERLAP:
        delta, total, largest, count, edge, box = _summary(h, u, p, delta, final, gap,
                                                           contact)
        cut = limit < np.inf and _next_to(contact, h, limit)
    return (outcome, status, hist, its, err, delta, total, largest, count, edge, box,
            generations, in_q, hmin, cut)


_solve = numba.njit(cache=True, nogil=True)(_solve_py)
_SHOWN = _B(_GRID, _GRID, _F, _GRID, numba.types.int64[::1], _FLAT, numba.types.int64)
_gradient_at, _direction_at, _step_at, _shown_at = (
    function_at(s) for s in (_GRADIENT, _DIRECTION, _STEP, _SHOWN))


@numba.njit(cache=True, nogil=True)
def _solve_compiled(kernels, h, start, floor, shown, use_shown, generations, p, q, u, gap,
                    contact, kernel, product, inverse, precondition, force_control, load,
                    penetration, area, self_compliance, tolerance, max_iterations, chunk,
                    limit):  # pragma: no cover - compiled
    """:func:`_solve_py` compiled, one call: ``kernels`` the addresses of the code of
    :func:`_gradient`, :func:`_direction`, :func:`_step` and :func:`_shown_start`
    (:func:`_kernel_addresses`), called through pointers; ``product`` and ``inverse`` the
    packed plan's arguments
    (:meth:`~railcontact.halfspace.operator.InfluenceOperator.compiled_product`)."""
    return _solve(_gradient_at(kernels[0]), _direction_at(kernels[1]), _step_at(kernels[2]),
                  _shown_at(kernels[3]), h, start, floor, shown, use_shown, generations, p,
                  q, u, gap, contact, kernel, product, inverse, precondition, force_control,
                  load, penetration, area, self_compliance, tolerance, max_iterations,
                  chunk, limit)


@lru_cache(maxsize=1)
def _kernel_addresses() -> np.ndarray:
    """The addresses of the code of :func:`_gradient`, :func:`_direction`, :func:`_step`
    and :func:`_shown_start` (their one signature each) for :func:`_solve_compiled`,
    formed once."""
    return np.array([address(f, s) for f, s in ((_gradient, _GRADIENT),
                                                (_direction, _DIRECTION), (_step, _STEP),
                                                (_shown_start, _SHOWN))],
                    dtype=np.int64)


COMPILED_LOOP = packed_product[1] is not None
"""Whether :func:`solve_normal` runs as one compiled call (:func:`_solve_compiled`) where
both products are compiled packed-plan products; else (or without FFTW's C interface) the
same solve runs as Python between the kernels (:func:`_solve_py`)."""


def _checked(h: np.ndarray, p: np.ndarray | None) -> float:
    """Raise when the gap ``h`` or the initial pressure ``p`` (in that order) holds a NaN
    or an infinity (the compiled solve's checks, where it does not make them); else
    return the least gap [m]."""
    hmin, finite = _least(h)
    if not finite:
        raise RailContactError("gap contains NaN or infinite values")
    if p is not None:
        _check_finite("initial_pressure", p)
    return hmin


def _check_finite(name: str, a: np.ndarray) -> None:
    # a NaN or an infinity anywhere makes the sum NaN or infinite: the elementwise test
    # only when the sum is not finite (or overflows)
    total = array_sum(a)
    if not math.isfinite(total) and not np.isfinite(a).all():
        raise RailContactError(f"{name} contains NaN or infinite values")


def _formed_start(h: np.ndarray, p: np.ndarray | None, mask: np.ndarray | None,
                  operator: InfluenceOperator, force_control: bool, load: float | None,
                  penetration: float | None, area: float) -> np.ndarray:
    """The start of the CG where the compiled solve does not floor the given pressure
    ``p`` itself: none given (a uniform pressure), a mask, a pressure not C-ordered, or a
    floored pressure without any (then the elements of the least gap, or the uniform
    pressure); under force control scaled to the load. C-ordered, writeable."""
    if p is None:
        p = np.ones(h.shape) if force_control else _uniform_start(h, operator, penetration)
    else:
        p = np.maximum(p, 0.0)
    total = float(p.sum())
    if mask is not None:
        p = np.where(mask, p, 0.0)
        total = float(p.sum())
    if not total > 0.0:  # (p >= 0: no element has pressure)
        p = np.where(h <= np.min(h) + 0.0, 1.0, 0.0) if force_control else \
            _uniform_start(h, operator, penetration)
        total = float(p.sum())
    if force_control:
        p *= load / (area * total)
    return np.ascontiguousarray(p, dtype=float)


def solve_normal(
    gap: np.ndarray,
    grid: Grid,
    operator: InfluenceOperator,
    *,
    load: float | None = None,
    penetration: float | None = None,
    initial_pressure: np.ndarray | None = None,
    initial_contact: np.ndarray | None = None,
    tolerance: float = 1e-3,
    max_iterations: int = 500,
    preconditioner: str = "fft",
    initial_displacement: Displacement | None = None,
    min_load: float = 0.0,
    undefined_gap: float | None = None,
) -> NormalResult:
    """Solve the frictionless normal contact problem by Polonsky–Keer's CG method.

    Parameters
    ----------
    gap
        Undeformed gap h [m] at the element centres, shape (nx, ny). Any constant offset
        is allowed under force control; under penetration control ``delta`` is measured
        from ``h = 0``.
    grid
        The potential-contact grid.
    operator
        Influence operator with component ``"z"`` for this grid's element size.
    load
        Total normal force [N] (force control). Give this or ``penetration``.
    penetration
        Rigid approach delta [m] (penetration control).
    initial_pressure
        Initial estimate of the pressure [Pa] on this grid (e.g. Hertz, INFCON, the
        previous time step). Negative values are set to zero; under force control it is
        rescaled to the load. Default: a uniform pressure on the whole grid (the paper's
        "w/o initial estimate"; under penetration control at the level that minimises the
        complementary energy).
    initial_contact
        Initial contact mask; elements outside it start with zero pressure.
    tolerance
        eps_n, the relative pressure change at which iteration stops (see module doc).
    max_iterations
        Largest number of CG iterations.
    preconditioner
        "fft" (default) or "none" (the plain Polonsky–Keer CG of the paper); see the
        module doc.
    initial_displacement
        ``A p`` [m] of ``initial_pressure`` as given (its negative values included), when
        the caller has it at hand (a time step: from the previous steps' displacements,
        :func:`railcontact.timestep.warmstart.previous_start`): the solve's first product
        is then not formed. The elements the start sets to zero (negative) are taken out
        by their influence columns (beyond :data:`CHANGE_LIMIT` of them ``A p`` is
        convolved). Ignored (``A p`` convolved) with ``initial_contact``, when not finite,
        not of the grid's shape, or older than :data:`REUSE_GENERATIONS`
        (:class:`Displacement`).
    min_load
        A ``load`` [N] below this, as a zero load, is no contact (zero pressure, converged):
        the contact solvers pass :data:`~railcontact.halfspace.hertz.MIN_LOAD`; the default
        solves any positive load, e.g. a problem scaled to test the CG's range.
    undefined_gap
        Gaps [m] from this up mark elements where the gap is undefined (a profile's end):
        the result's :attr:`NormalResult.next_to_undefined` tells whether the contact
        reaches one. None: no such elements.

    Returns
    -------
    NormalResult
    """
    t0 = time.perf_counter()
    shape = grid.shape
    if gap is None:
        raise RailContactError("gap is required")
    h = np.ascontiguousarray(gap, dtype=float)
    if not h.flags.writeable:  # (the CG kernels' one signature: writeable arrays)
        h = h.copy()
    if h.shape != shape:
        raise RailContactError(f"gap must have the grid shape {shape}, got {h.shape}")
    p = mask = None
    try:  # (the gap's own check, NaN or infinity, comes first: made where one fails)
        if operator.components != "z" or (operator.nx, operator.ny) != shape:
            raise RailContactError("operator must be a 'z' influence operator for this grid")
        tolerance = check_positive("tolerance", tolerance)
        if preconditioner not in PRECONDITIONERS:
            raise RailContactError(f"preconditioner must be one of {PRECONDITIONERS}, "
                                   f"got {preconditioner!r}")
        precondition = preconditioner == "fft"
        max_iterations = check_count("max_iterations", max_iterations)
        if (load is None) == (penetration is None):
            raise RailContactError("give exactly one of load [N] and penetration [m]")
        force_control = load is not None
        if force_control:
            load = check_positive("load", load, "N", allow_zero=True)
        else:
            penetration = check_positive("penetration", penetration, "m", allow_zero=True)
        if initial_pressure is not None:
            p = np.asarray(initial_pressure, dtype=float)
            if p.shape != shape:
                raise RailContactError(f"initial_pressure must have the grid shape {shape}, "
                                       f"got {p.shape}")
        if initial_contact is not None:
            if p is not None:
                _check_finite("initial_pressure", p)
            mask = np.asarray(initial_contact, dtype=bool)
            if mask.shape != shape:
                raise RailContactError(f"initial_contact must have the grid shape {shape}, "
                                       f"got {mask.shape}")
    except Exception:
        if not _least(h)[1]:
            raise RailContactError("gap contains NaN or infinite values") from None
        raise
    given = p
    area_el = grid.element_area
    kernel, self_compliance = operator.first_kernel  # "zz" (2nx-1, 2ny-1), its centre [m/Pa]

    # Trivial case: no load.
    if force_control and (load == 0.0 or load < min_load):
        _checked(h, p)
        zeros = np.zeros(shape)
        why = "zero load" if load == 0.0 else no_contact_load(load)
        gaps, contact = np.empty(shape), np.empty(shape, dtype=bool)
        summary = _summary(h, zeros, zeros, float(h.min()), False, gaps, contact)
        return _result(grid, zeros, gaps, contact, summary, 0, True, f"no contact: {why}",
                       0.0, np.empty(0), None, given, t0, undefined_gap is not None
                       and _next_to(contact, h, float(undefined_gap)))

    # The start: the given pressure floored (and its shown displacement) in the solve,
    # else formed here.
    shown = initial_displacement  # A p of the start, if the caller knows it
    floor = p is not None and mask is None and p.flags.c_contiguous
    values = None
    if floor:
        start = p if p.flags.writeable else p.copy()
        if shown is not None and shown.generations <= REUSE_GENERATIONS \
                and shown.values.shape == shape:
            values = np.asarray(shown.values, dtype=float)
            if not values.flags.carray:
                values = np.array(values, order="C")
    else:
        hmin = _checked(h, p)
        if not force_control and hmin >= penetration:
            start = np.zeros(shape)  # (no contact: the solve finds it)
        else:
            start = _formed_start(h, p, mask, operator, force_control, load, penetration,
                                  area_el)
    # The solve (_solve_py): one compiled call that releases the GIL where both products
    # are compiled packed-plan products, else the same run as Python.
    products = compiled_products(operator, precondition)
    if products is not None:
        solve, kernels = _solve_compiled, (_kernel_addresses(),)
    else:  # (the kernels called from Python; the preconditioner's M x bound as A x)
        product = operator.bound()
        solve, kernels = _solve_py, (_gradient, _direction, _step, _shown_start)
        products = product, operator.bound(PRECONDITIONER_FLOOR) if precondition else product
    limit = math.inf if undefined_gap is None else float(undefined_gap)
    q, u, gaps = np.empty(shape), np.empty(shape), np.empty(shape)
    contact = np.empty(shape, dtype=bool)
    while True:
        pressure = np.empty(shape) if floor else start  # (the start floored into it)
        out = solve(*kernels, h, start, floor, u if values is None else values,
                    values is not None, 0 if values is None else int(shown.generations),
                    pressure, q, u, gaps, contact, kernel, *products, precondition,
                    force_control, float(load) if force_control else 0.0,
                    0.0 if force_control else float(penetration), float(area_el),
                    self_compliance, float(tolerance), min(max_iterations, MAX_LAST),
                    HISTORY_CHUNK, limit)
        outcome = out[0]
        if outcome == GAP_NOT_FINITE:
            raise RailContactError("gap contains NaN or infinite values")
        if outcome == START_NOT_FINITE:
            raise RailContactError("initial_pressure contains NaN or infinite values")
        if outcome != EMPTY_START:
            break
        # the floored start holds no pressure: formed here, A p convolved
        start = _formed_start(h, pressure, None, operator, force_control, load, penetration,
                              area_el)
        floor, values = False, None
    return solved_result(out, grid, pressure, q, u, gaps, contact, given, tolerance, t0)


def compiled_products(operator: InfluenceOperator, precondition: bool) -> tuple | None:
    """The packed-plan products ``(A, M)`` of :func:`_solve_compiled` for ``operator``
    (``M`` its FFT preconditioner's with ``precondition``, else ``A``), or None where the
    solve cannot run as one compiled call (:data:`COMPILED_LOOP`)."""
    fft = operator.compiled_product() if COMPILED_LOOP else None
    fft_inverse = (operator.compiled_product(PRECONDITIONER_FLOOR)
                   if precondition and fft is not None else fft)
    if fft is None or fft_inverse is None:
        return None
    return fft, fft_inverse


def solved_result(out: tuple, grid: Grid, pressure: np.ndarray, q: np.ndarray,
                  u: np.ndarray, gaps: np.ndarray, contact: np.ndarray,
                  given: np.ndarray | None, tolerance: float, t0: float) -> NormalResult:
    """The :class:`NormalResult` of a solve (:func:`_solve_py`, compiled or not) that ran
    to its end (``out``'s outcome neither an error nor :data:`EMPTY_START`) on ``grid``:
    its arrays ``pressure`` (the start floored into it), ``q``, ``u``, ``gaps`` and
    ``contact``, the initial pressure ``given``, the ``tolerance`` and ``t0``
    (:func:`time.perf_counter` at the solve's start)."""
    (outcome, status, hist, its, err, delta, total, largest, count, edge, box, generations,
     in_q, hmin, cut) = out
    if in_q:
        pressure = q
    summary = (delta, total, largest, count, edge, box)
    if outcome == NO_OVERLAP:
        return _result(grid, pressure, gaps, contact, summary, 0, True,
                       "no contact: penetration below the smallest gap", 0.0, hist, None,
                       given, t0, cut)
    its = int(its)
    if status == VANISHED:
        return _result(grid, pressure, gaps, contact, summary, its, False,
                       "pressure vanished", np.inf, hist, None, given, t0, cut)
    err = float(err)
    converged, stalled = status == CONVERGED, status == STALLED
    if converged:
        message = f"converged in {its} iterations (eps = {err:.3g} < {tolerance:g})"
    else:
        message = (f"not converged: eps = {err:.3g} after {its} iterations "
                   f"(tolerance {tolerance:g})")
        if stalled:
            message += (f"; stalled: eps has not fallen below {STALL_GAIN:g} of its best in "
                        f"{STALL_ITERATIONS} iterations")
    res = _result(grid, pressure, gaps, contact, summary, its, converged, message, err, hist,
                  Displacement(u, int(generations)), given, t0, cut)
    lo, hi = SCALE_RANGE
    depth = res.penetration - hmin
    if converged and res.max_pressure > 0 and not (lo <= res.max_pressure <= hi
                                                   and lo <= depth <= hi):
        res = replace(res, converged=False, message=(
            f"not converged: the largest pressure {res.max_pressure:.3g} Pa or the depth "
            f"of interpenetration {depth:.3g} m lies outside {lo:g} .. {hi:g}, where the "
            f"CG's inner products (squares) under- or overflow ({message})"))
    if res.touches_boundary:
        res = replace(res, message=res.message
                      + "; contact reaches the edge of the potential contact area")
    return res


def _result(grid: Grid, pressure: np.ndarray, gap: np.ndarray, contact: np.ndarray,
            summary: tuple, iterations: int, converged: bool, message: str, error: float,
            history: np.ndarray, shown: Displacement | None, start: np.ndarray | None,
            t0: float, cut: bool) -> NormalResult:
    """The :class:`NormalResult` of a solve from :func:`_summary`'s values ``summary``
    (the approach, the pressure's sum and largest value, the contact elements, whether
    they reach the edge, their box) on ``grid``; ``t0`` the solve's start
    (:func:`time.perf_counter`); ``cut`` its :attr:`~NormalResult.next_to_undefined`."""
    delta, total, largest, count, edge, box = summary
    area = grid.element_area
    return NormalResult(
        grid=grid, pressure=pressure, contact=contact, gap=gap, force=float(total * area),
        penetration=float(delta), max_pressure=float(largest), area=float(count * area),
        iterations=iterations, converged=converged, message=message,
        wall_time=time.perf_counter() - t0, error=float(error), history=history,
        touches_boundary=bool(edge), contact_box=box if box[0] >= 0 else None,
        displacement=shown, start=start, next_to_undefined=bool(cut))
