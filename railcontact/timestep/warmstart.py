"""Initial estimates for a time step: the previous steps' solutions on the new grid.

In a time-stepping simulation the contact patch moves and changes a little from one step
to the next. The previous step's pressure, traction and adhesion/slip map are kept in the
patch's own coordinates (x along the track, y across it in the contact plane, both from the
contact point), re-meshed onto the current BEM grid, and - when the two previous steps and
their times are known - extrapolated linearly in time to the current step::

    p_pred = p_k + (t - t_k) / (t_k - t_{k-1}) (p_k - p_{k-1}),   p_pred >= 0

(the factor is limited to [0, 2]). The traction is extrapolated with a rate smoothed over
the steps instead (:func:`traction_rate`): each solve stops a little way from its exact
solution, and ``2 p_k - p_{k-1}`` would double that iteration error in the start. That
field starts the BEM alone (``"previous"``; a patch
without a previous step starts cold) or with a simplified model's estimate as the fallback
(``"previous+estimate"``: a patch without a previous step - the first step, a flange
contact that has just appeared - starts from the estimate).

Why patch coordinates and not the rail's: measured on S1002/60E1 near 1 mm lateral
displacement, a 0.01 mm step of the wheelset moves the contact point 0.0065 mm on the rail,
but the pressure centroid 0.04 mm, and the pressure changes by 0.6 % (L1) whichever of the
two is held fixed (0.7 % on the rail, 0.6 % at the contact point). The linear
extrapolation brings this to 0.01 %, the traction's error from 1.2 % to 0.2 %.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from ..geometry.points import ContactPoint, overlap_on_rail
from ..halfspace.grid import (
    Grid,
    _shifted_copy,
    box_edges,
    lattice_offset,
    nonzero_box,
    remesh,
    widened,
)
from ..halfspace.sums import array_sum, numpy_sum
from ..normal.bem import REUSE_GENERATIONS, Displacement

MATCH_DISTANCE = 0.005
"""Largest move [m] of a contact point between steps for which the previous patch is used."""
MAX_EXTRAPOLATION = 2.0
RATE_GAIN = 0.5
"""Weight of the latest step's traction change in the remembered traction rate
(:func:`traction_rate`); 1 is the plain linear extrapolation of the last two steps."""
AREA_MARGIN_ELEMENTS = 2
AREA_MARGIN_SHARE = 0.05
"""The potential area of a warm-started patch: the previous steps' contact, widened on each
side by this many elements plus this share of its extent (:func:`previous_bounds`)."""


@dataclass(frozen=True, slots=True)
class PatchMemory:
    """What a time step keeps of one contact patch for the next one (SI units).

    Attributes
    ----------
    grid
        The patch's BEM grid (x along the track, y across it in the contact plane, origin at
        the contact point) [m].
    pressure
        Normal pressure [Pa], (nx, ny).
    traction
        Tangential traction [Pa], (2, nx, ny), in the side frame (see
        :mod:`railcontact.timestep.wheelset`), or None without a tangential solution.
    state
        Adhesion/slip map (0 exterior, 1 adhesion, 2 slip), (nx, ny), or None.
    u, z
        Contact point on the rail: lateral (side frame) and vertical [m].
    time
        Simulation time of the step [s], or None.
    older
        The same patch one step earlier (its own ``older`` dropped), or None.
    vertical_creep
        Vertical component ``F_s sin(gamma)`` of the patch's creep force [N]: the next
        step's first guess of the share of a wheel load the creep forces carry.
    approach
        Vertical approach [m] of the patch's wheel in the step: the next step forms a patch
        frame at the reference point there
        (:func:`railcontact.contact.wheelrail.solve_wheel_normal`).
    vertical_normal
        Vertical component ``N cos(gamma)`` of the patch's normal force [N].
    traction_rate
        The traction's rate of change [Pa/s] (2, nx, ny) on ``grid``, smoothed over the
        steps (:func:`traction_rate`), or None: the traction is then extrapolated from
        ``older``.
    displacement
        The normal solve's ``A p`` of ``pressure`` [m] (:class:`~railcontact.normal.bem.
        Displacement`), or None: the next step's start's ``A p`` is then convolved
        (:func:`previous_start`).
    element_box
        The rows ``i0:i1`` and columns ``j0:j1`` of ``grid`` that hold the elements with
        pressure (:func:`~railcontact.halfspace.grid.nonzero_box`; ``i0 < 0``: none);
        formed from ``pressure`` when not given (a normal solve knows it).
    contact_box
        Outer edges (xmin, xmax, ymin, ymax) [m] of the elements with pressure, or None;
        formed from ``element_box``.
    """

    grid: Grid
    pressure: np.ndarray
    traction: np.ndarray | None
    state: np.ndarray | None
    u: float
    z: float
    time: float | None = None
    older: PatchMemory | None = None
    vertical_creep: float = 0.0
    approach: float = 0.0
    vertical_normal: float = 0.0
    traction_rate: np.ndarray | None = None
    displacement: Displacement | None = None

    element_box: tuple[int, int, int, int] | None = None
    contact_box: tuple[float, float, float, float] | None = field(init=False)

    def __post_init__(self) -> None:  # (the frozen record's own fields, formed once)
        box = self.element_box
        if box is None:
            box = nonzero_box(np.asarray(self.pressure))
            object.__setattr__(self, "element_box", box)
        object.__setattr__(self, "contact_box", box_edges(box, self.grid))

    def without_older(self) -> PatchMemory:
        """This memory without its ``older`` step and traction rate: what a newer step
        keeps of it (its traction and time for the extrapolation; the newer step's rate
        has taken in the rest). ``dataclasses.replace(m, older=None, traction_rate=None)``,
        made directly (a per-pass path: ``replace`` reads the fields' descriptions)."""
        return PatchMemory(self.grid, self.pressure, self.traction, self.state, self.u,
                           self.z, self.time, None, self.vertical_creep, self.approach,
                           self.vertical_normal, None, self.displacement, self.element_box)

    def extrapolation(self, time: float | None) -> float:
        """The factor ``(t - t_k) / (t_k - t_{k-1})`` for a step at ``time`` [s]; 0 when
        it cannot be formed."""
        o = self.older
        if time is None or self.time is None or o is None or o.time is None:
            return 0.0
        dt = self.time - o.time
        if not dt > 0:
            return 0.0
        return min(max(float((time - self.time) / dt), 0.0), MAX_EXTRAPOLATION)


def match(memories: list[PatchMemory], u: float, z: float) -> PatchMemory | None:
    """The remembered patch closest to the contact point ``(u, z)`` (side frame) [m], if it
    lies within :data:`MATCH_DISTANCE`."""
    best, dist = None, MATCH_DISTANCE
    for m in memories:
        d = math.hypot(m.u - u, m.z - z)
        if d <= dist:
            best, dist = m, d
    return best


def merged(cp: ContactPoint, memory: PatchMemory, memories: list[PatchMemory],
           penetration: float) -> bool:
    """Whether the patch of ``cp``, matched to ``memory``, took in another remembered
    patch: the contact point of one of the other ``memories`` lies in the patch's rigid
    overlap at the normal ``penetration`` [m]
    (:func:`~railcontact.geometry.points.overlap_on_rail`).
    Two patches that merge into one: the potential area of the one remembered is not the
    merged patch's (without this, its other lobe was left out, its load lost, in that step
    and every later one). Without other memories (a wheel with one patch) nothing is
    formed."""
    others = [o for o in memories if o is not memory]
    if not others:
        return False
    span = overlap_on_rail(cp, penetration)
    return span is not None and any(span[0] <= o.u <= span[1] for o in others)


def previous_pressure(memory: PatchMemory, grid: Grid, time: float | None = None
                      ) -> np.ndarray:
    """The predicted pressure [Pa] on ``grid`` at ``time`` [s] (module docstring)."""
    c = memory.extrapolation(time)
    return _previous_pressure(memory, memory.older if c > 0 else None, c, grid, False)


def _previous_pressure(memory: PatchMemory, o: PatchMemory | None, c: float, grid: Grid,
                       reuse: bool) -> np.ndarray | tuple[np.ndarray, Displacement | None]:
    """:func:`previous_pressure` (``reuse`` False) or :func:`previous_start` (``reuse``:
    the pressure and, when it can be formed, its displacement) of the memory and its
    ``older`` step ``o`` (None: no extrapolation) with the factor ``c``: one compiled
    pass (:func:`_pressure_start`) on one lattice, else re-meshed."""
    args = start_arguments(memory, o, c, reuse)
    if args is not None:
        g = grid
        p, u, kind = _pressure_start(g.nx, g.ny, g.dx, g.dy, g.x0, g.y0, *args[0])
        if kind == 2:
            return p, Displacement(u, args[1])
        if kind == 1:
            return (p, None) if reuse else p
    p = remesh(memory.pressure, memory.grid, grid)
    if o is not None:
        p = np.maximum(p + c * (p - remesh(o.pressure, o.grid, grid)), 0.0)
    return (p, None) if reuse else p


def start_arguments(memory: PatchMemory, o: PatchMemory | None, c: float, reuse: bool
                    ) -> tuple[tuple, int] | None:
    """The arguments of :func:`_pressure_start` after the grid's (the remembered
    pressures, their displacements where ``reuse`` and they may be reused, their grids,
    ``c``) for the memory and its ``older`` step ``o`` (None: no extrapolation), and the
    generations of the displacement it would form; None where the pressures are not
    arrays of two dimensions (re-meshed instead)."""
    u1 = memory.displacement if reuse else None
    u0 = o.displacement if o is not None and u1 is not None else None
    if u1 is not None and not (c <= MAX_REUSE_EXTRAPOLATION
                               and (o is None or u0 is not None)
                               and max(u1.generations, u0.generations if u0 is not None
                                       else 0) < REUSE_GENERATIONS):
        u1 = None  # (the displacement is not reused: the pressure alone)
    g1 = memory.grid
    p1 = memory.pressure
    if not (p1.ndim == 2 and (o is None or o.pressure.ndim == 2)):
        return None
    g0 = g1 if o is None else o.grid
    generations = 0 if u1 is None else 1 + max(u1.generations, u0.generations
                                                if u0 is not None else 0)
    return ((p1, _NO_FIELD if u1 is None else u1.values, g1.nx, g1.ny, g1.dx, g1.dy,
             g1.x0, g1.y0, memory.element_box,
             p1 if o is None else o.pressure, _NO_FIELD if u0 is None else u0.values,
             g0.nx, g0.ny, g0.dx, g0.dy, g0.x0, g0.y0,
             memory.element_box if o is None else o.element_box,
             c, o is not None, u1 is not None), generations)


_NO_FIELD = np.zeros((0, 0))


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def _pressure_start(nx, ny, dx, dy, x0, y0, p1, u1, n1x, n1y, d1x, d1y, x1, y1, box1,
                    p0, u0, n0x, n0y, d0x, d0y, x00, y00, box0, c, extrapolate,
                    reuse):  # pragma: no cover - compiled
    """The start of a warm patch on the grid (nx, ny, dx, dy, x0, y0) from the remembered
    pressures ``p1`` (grid n1x, ..., y1; elements with pressure in ``box1``) and, when
    ``extrapolate``, ``p0`` (n0x, ...) with the factor ``c``: ``(p, u, 2)`` the pressure
    not floored and its displacement (``reuse``: from ``u1``, ``u0``, where the grid lies
    on one lattice inside both remembered grids and holds all their pressure, and ``p``
    has a positive element and both are finite, :func:`_extrapolated_pair`); else
    ``(p, -, 1)`` the floored pressure re-meshed on one lattice (:func:`_extrapolated`);
    ``(-, -, 0)`` off the lattice or a field not of its grid's shape (then re-meshed)."""
    none = np.empty((0, 0))
    i1, j1, on1 = _lattice_offset(d1x, d1y, x1, y1, dx, dy, x0, y0)
    on1 = on1 and p1.shape[0] == n1x and p1.shape[1] == n1y
    i0, j0, on0 = 0, 0, True
    if extrapolate:
        i0, j0, on0 = _lattice_offset(d0x, d0y, x00, y00, dx, dy, x0, y0)
        on0 = on0 and p0.shape[0] == n0x and p0.shape[1] == n0y
    if not (on1 and on0):
        return none, none, 0
    if (reuse and _holds(u1, n1x, n1y, i1, j1, box1, nx, ny)
            and (not extrapolate or _holds(u0, n0x, n0y, i0, j0, box0, nx, ny))):
        p, u, ok = _extrapolated_pair(p1, u1, i1, j1, p0, u0, i0, j0, c, extrapolate,
                                      nx, ny)
        if ok:
            return p, u, 2
    return _extrapolated(p1, i1, j1, p0, i0, j0, c, extrapolate, True, nx, ny), none, 1


@numba.njit(cache=True, nogil=True)
def _holds(u, n1x, n1y, i, j, box, nx, ny):  # pragma: no cover - compiled
    """Whether the grid (nx, ny) at the offset ``(i, j)`` lies inside the remembered grid
    (n1x, n1y), its displacement ``u`` is of that shape, and the grid holds the elements
    with pressure (``box``: rows i0:i1, columns j0:j1; ``i0 < 0``: none)."""
    if not (u.shape[0] == n1x and u.shape[1] == n1y):
        return False
    if i < 0 or j < 0 or i + nx > n1x or j + ny > n1y:
        return False
    b0, b1, c0, c1 = box
    return b0 < 0 or (i <= b0 and b1 <= i + nx and j <= c0 and c1 <= j + ny)


_lattice_offset = numba.njit(cache=True, nogil=True)(lattice_offset)


MAX_REUSE_EXTRAPOLATION = 1.0 + 1e-9
"""Largest extrapolation factor ``c`` with which :func:`previous_start` forms the start's
``A p`` from the remembered displacements: their round-off enters it with the factors
``1 + c`` and ``c``, which let it grow geometrically from step to step for ``c > 1``
(1, and the round-off of step times such as ``k * 1e-3``: ``c = 1.0000000000000009``)."""


def previous_start(memory: PatchMemory, grid: Grid, time: float | None = None
                   ) -> tuple[np.ndarray, Displacement | None]:
    """The predicted pressure [Pa] on ``grid`` at ``time`` [s] and, when the memory lets
    it be formed without a convolution, its displacement ``A p`` [m].

    The prediction is ``p = p_k + c (p_k - p_{k-1})`` (:func:`previous_pressure`), and
    the influence operator is translation invariant, so on one lattice::

        A p = u_k + c (u_k - u_{k-1}),   u = A p of each remembered pressure,

    each shifted onto ``grid`` by whole elements, wherever ``grid`` lies inside both
    remembered grids and holds all their pressure (else some of ``A p`` would be missing).
    Then the pressure is returned before its floor at zero (the normal solve floors it,
    :func:`~railcontact.normal.bem.solve_normal`, and takes the floored elements'
    influence columns out of ``A p``). Otherwise - no remembered displacement, another
    lattice, a grid reaching beyond a remembered one or cutting its pressure, ``c >``
    :data:`MAX_REUSE_EXTRAPOLATION`, a displacement :data:`~railcontact.normal.bem.
    REUSE_GENERATIONS` old, no pressure left or a NaN in it - the displacement is None and
    the pressure is :func:`previous_pressure`'s (floored)."""
    c = memory.extrapolation(time)
    return _previous_pressure(memory, memory.older if c > 0 else None, c, grid, True)


@numba.njit(cache=True, nogil=True)
def _extrapolated_pair(p1, u1, i1, j1, p0, u0, i0, j0, c, extrapolate, nx,
                       ny):  # pragma: no cover - compiled
    """``p = p1 + c (p1 - p0)`` and ``u = u1 + c (u1 - u0)`` on the (nx, ny) grid at the
    offsets ``(i1, j1)``, ``(i0, j0)`` inside the remembered ones (``p1``, ``u1`` alone
    without ``extrapolate``), ``p`` with the same operations as :func:`_extrapolated`
    (not floored); returns ``(p, u, ok)``, ``ok`` when ``p`` has a positive element and
    ``p`` and ``u`` are finite."""
    p = np.empty((nx, ny))
    u = np.empty((nx, ny))
    bad = positive = 0  # (integer flags: the loop vectorises)
    if not extrapolate:  # (p1 + 0 (p1 - p1) = p1)
        c, p0, u0, i0, j0 = 0.0, p1, u1, i1, j1
    for a in range(nx):
        pa, ua = p[a], u[a]
        q1, w1 = p1[a + i1, j1:j1 + ny], u1[a + i1, j1:j1 + ny]
        q0, w0 = p0[a + i0, j0:j0 + ny], u0[a + i0, j0:j0 + ny]
        for b in range(ny):
            x = q1[b] + c * (q1[b] - q0[b])
            v = w1[b] + c * (w1[b] - w0[b])
            pa[b] = x
            ua[b] = v
            bad |= not (abs(x) < np.inf and abs(v) < np.inf)
            positive |= x > 0.0
    return p, u, bad == 0 and positive != 0


def _on_lattice(memory: PatchMemory, grid: Grid) -> tuple[int, int] | None:
    """The whole-element offset of ``grid`` in ``memory``'s grid (as :func:`remesh` takes
    it), or None when the grids are not on one lattice or a field is not (nx, ny)."""
    source = memory.grid
    if memory.pressure.shape != (source.nx, source.ny):
        return None
    i, j, ok = lattice_offset(source.dx, source.dy, source.x0, source.y0, grid.dx, grid.dy,
                              grid.x0, grid.y0)
    return (i, j) if ok else None


@numba.njit(cache=True, nogil=True)
def _extrapolated(v1, i1, j1, v0, i0, j0, c, extrapolate, clip, nx, ny):  # pragma: no cover
    """``remesh`` on one lattice (``out[a, b] = v[a + i, b + j]``, zero outside ``v``) of
    ``v1`` and, when ``extrapolate``, ``v1 + c (v1 - v0)`` (``v0`` remeshed the same way),
    floored at zero as ``np.maximum(., 0)`` when ``clip``: the same operations, element by
    element, as the numpy form."""
    out = np.empty((nx, ny))
    n1x, n1y = v1.shape
    n0x, n0y = v0.shape
    for a in range(nx):
        for b in range(ny):
            x, y = a + i1, b + j1
            p = v1[x, y] if 0 <= x < n1x and 0 <= y < n1y else 0.0
            if extrapolate:
                x, y = a + i0, b + j0
                o = v0[x, y] if 0 <= x < n0x and 0 <= y < n0y else 0.0
                p = p + c * (p - o)
                if clip:
                    p = p if (p >= 0.0 or p != p) else 0.0
            out[a, b] = p
    return out


def traction_rate(traction: np.ndarray, grid: Grid, time: float | None,
                  older: PatchMemory | None, gain: float = RATE_GAIN) -> np.ndarray | None:
    """The traction's rate [Pa/s] (2, nx, ny) on ``grid`` after a step at ``time`` [s]
    that solved ``traction`` [Pa] (2, nx, ny), ``older`` being the step before::

        v_k = (1 - gain) v_{k-1} + gain (p_k - p_{k-1}) / (t_k - t_{k-1})

    (``v_{k-1}`` the older step's rate; without one, ``v_k = (p_k - p_{k-1}) / dt``). None
    when it cannot be formed (no older step with a traction, no times, ``t_k <= t_{k-1}``,
    or a rate that is not finite: a traction that was not would otherwise stay in every
    later step's average).

    Why not ``p_k - p_{k-1}`` alone: a warm SteadyGS solve stops at ``eps_tau`` about
    0.45 ``eps_tau`` from its exact traction, an error that changes from step to step, and
    the start ``2 p_k - p_{k-1}`` carries it with a factor ``sqrt(5)`` (for independent
    errors). On ``scripts/bench_step.py``'s hunting run that made the warm start 1.3e-2 off
    (L2, relative, median; 6.8e-3 with the steps solved tightly), and a sweep's measure is
    about 0.8 of the start's error: half the warm solves took a second sweep. The
    average of the changes halves the noise of the rate (for ``gain`` = 0.5), is exact
    for a traction changing linearly in time, and lags for a changing rate by
    ``(1 - gain) / gain`` steps of its change (``scripts/study_warm_prediction.py``
    compares the predictors).
    """
    o = older
    if (o is None or o.traction is None or time is None or o.time is None
            or not time - o.time > 0):
        return None
    dt = float(time - o.time)
    rate, g, g0 = o.traction_rate, grid, o.grid
    if traction.ndim == 3 and o.traction.ndim == 3 and (rate is None or rate.ndim == 3):
        out, total, ok = _rate_on(g.nx, g.ny, g.dx, g.dy, g.x0, g.y0, traction, o.traction,
                                  g0.nx, g0.ny, g0.dx, g0.dy, g0.x0, g0.y0,
                                  o.traction if rate is None else rate, rate is not None,
                                  float(gain), dt)
        if ok:
            return out if math.isfinite(total) else None
    out = (np.asarray(traction, dtype=float) - remesh(o.traction, o.grid, grid)) / dt
    if rate is not None:
        out = (1.0 - gain) * remesh(rate, o.grid, grid) + gain * out
    total = array_sum(out)
    return out if math.isfinite(total) else None


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def _rate_on(nx, ny, dx, dy, x0, y0, p, p0, n0x, n0y, d0x, d0y, x00, y00, v0, smooth,
             gain, dt):  # pragma: no cover - compiled
    """:func:`_rate` of the traction ``p`` (2, nx, ny) on the grid (nx, ny, dx, dy, x0,
    y0) and the older step's ``p0`` and rate ``v0`` on its grid (n0x, ...), where the two
    grids lie on one lattice and the fields have their grids' shapes: ``(rate, its sum,
    True)``; else ``(-, -, False)``."""
    i0, j0, on = _lattice_offset(d0x, d0y, x00, y00, dx, dy, x0, y0)
    if not (on and p.shape[0] == 2 and p.shape[1] == nx and p.shape[2] == ny
            and p0.shape[0] == 2 and p0.shape[1] == n0x and p0.shape[2] == n0y
            and (not smooth or v0.shape == p0.shape)):
        return np.empty((0, 0, 0)), 0.0, False
    out, total = _rate(p, p0, i0, j0, v0, smooth, gain, dt)
    return out, total, True


@numba.njit(cache=True, nogil=True)
def _rate(p, p0, i0, j0, v0, smooth, gain, dt):  # pragma: no cover - compiled
    """``(1 - gain) v0 + gain (p - p0) / dt`` (``smooth``; else ``(p - p0) / dt``) of
    the fields (2, nx, ny) ``p``, ``p0``, ``v0``, the last two read on ``p``'s grid at
    the lattice offset ``(i0, j0)`` (zero outside them), as :func:`remesh` does; and its
    sum as :func:`~railcontact.halfspace.sums.array_sum` gives it."""
    out = np.empty(p.shape)
    nx, ny = p.shape[1], p.shape[2]
    n0x, n0y = p0.shape[1], p0.shape[2]
    for k in range(2):
        for a in range(nx):
            for b in range(ny):
                x, y = a + i0, b + j0
                inside = 0 <= x < n0x and 0 <= y < n0y
                c = (p[k, a, b] - (p0[k, x, y] if inside else 0.0)) / dt
                if smooth:
                    c = (1.0 - gain) * (v0[k, x, y] if inside else 0.0) + gain * c
                out[k, a, b] = c
    return out, numpy_sum(out)


def previous_bounds(memory: PatchMemory) -> tuple[float, float, float, float] | None:
    """The potential contact area (xmin, xmax, ymin, ymax) [m] of a warm-started patch:
    the box around the contact of the previous two steps (patch coordinates), widened on
    each side by :data:`AREA_MARGIN_ELEMENTS` elements and :data:`AREA_MARGIN_SHARE` of
    its extent; None when the previous step had no contact.

    The BEM's answer does not depend on the potential area as long as the contact stays
    inside it (the grids share one lattice); one that the contact reaches is grown and
    solved again by the patch solver, and one beyond which the rigid overlap holds a place
    the solved pressure may not keep open (a second lobe of the gap: the tread beside a
    flange-root contact) is grown to hold it and solved again
    (:func:`railcontact.contact.wheelrail._overlap_covered`), so a tight area costs a
    re-mesh at worst and never leaves contact out. A warm
    step then transforms and iterates on a grid a third of the size the Hertz estimate
    would mesh (whose area, for the wheel load, is the rigid interpenetration area with a
    margin)."""
    b, o = memory.contact_box, memory.older
    ob = None if o is None else o.contact_box
    if b is None or ob is None:
        b = b or ob
        if b is None:
            return None
        x0, x1, y0, y1 = b
    else:  # (min and max of the two, as of a sequence: the first of equal ones)
        x0, x1 = (ob[0] if ob[0] < b[0] else b[0]), (ob[1] if ob[1] > b[1] else b[1])
        y0, y1 = (ob[2] if ob[2] < b[2] else b[2]), (ob[3] if ob[3] > b[3] else b[3])
    return widened((x0, x1, y0, y1), memory.grid, AREA_MARGIN_ELEMENTS, AREA_MARGIN_SHARE)


def _contact_box(pressure: np.ndarray, grid: Grid) -> tuple[float, float, float, float] | None:
    """Outer edges (xmin, xmax, ymin, ymax) [m] of the elements with pressure, or None."""
    return box_edges(nonzero_box(np.asarray(pressure)), grid)


def previous_tangential(memory: PatchMemory, grid: Grid, time: float | None = None
                        ) -> tuple[np.ndarray, np.ndarray] | tuple[None, None]:
    """The previous traction [Pa] (2, nx, ny) and adhesion/slip map on ``grid``; with the
    step's ``time`` [s] the traction extrapolated (the map is the previous step's): along
    the memory's smoothed :attr:`~PatchMemory.traction_rate`, ``p_k + (t - t_k) v_k``,
    when it has one, else linearly from the older step as the pressure is
    (:func:`previous_pressure`); the step ``t - t_k`` is limited as the pressure's
    factor.

    Whether to extrapolate depends on the solver. On the hunting wheelset of
    ``scripts/bench_step.py`` (S1002/60E1, 1.5 Hz, 1 ms steps, 300 steps) SteadyGS took
    30 % fewer sweeps from the extrapolated traction (920 against 1,319 for both wheels)
    and came twice as close to the tight reference (median creep force error 1.1e-4 of
    mu N against 2.3e-4); ConvexGS took 4x more sweeps from it (3,362 against 830; its
    under-relaxed updates stop early from a start that is good already), so the time step
    gives ``time`` only to SteadyGS.
    """
    if memory.traction is None or memory.state is None:
        return None, None
    return _previous_tangential(memory, memory.extrapolation(time), grid)


def _previous_tangential(memory: PatchMemory, c: float, grid: Grid
                         ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`previous_tangential` of a memory with a traction and a map, with the
    extrapolation factor ``c`` (:meth:`PatchMemory.extrapolation`): along its rate in one
    compiled pass (:func:`_traction_start`) on one lattice."""
    o = memory.older
    rate = memory.traction_rate
    tr, st, g1 = memory.traction, memory.state, memory.grid
    if c > 0 and rate is not None and rate.shape == tr.shape:
        h = c * float(memory.time - o.time)  # t - t_k, limited as c is
        if tr.ndim == 3 and memory.pressure.ndim == 2:
            mapped = st.ndim == 2 and st.dtype.kind in "iub"
            t, shifted, kind = _traction_start(
                grid.nx, grid.ny, grid.dx, grid.dy, grid.x0, grid.y0, tr, rate,
                st if mapped else _NO_MAP, mapped, memory.pressure.shape[0],
                memory.pressure.shape[1], g1.nx, g1.ny, g1.dx, g1.dy, g1.x0, g1.y0, h)
            if kind == 2:  # (one pass: the traction advanced, the map shifted as
                return t, shifted  # _state_on does)
            if kind == 1:
                return t, _state_on(memory, grid, None)  # (the map not of its grid)
        shift = _on_lattice(memory, grid)
        t = remesh(tr, g1, grid) + h * remesh(rate, g1, grid)
        return t, _state_on(memory, grid, shift)
    shift = _on_lattice(memory, grid)
    o = o if c > 0 and o is not None and o.traction is not None else None
    shift_o = _on_lattice(o, grid) if o is not None else (0, 0)
    if (shift is not None and shift_o is not None and memory.state.shape == memory.grid.shape
            and memory.traction.shape == (2, *memory.grid.shape)
            and (o is None or o.traction.shape == (2, *o.grid.shape))
            and memory.state.dtype.kind in "iub"):  # grids on one lattice: one pass each
        t = np.empty((2, *grid.shape))
        for k in range(2):
            t[k] = _extrapolated(memory.traction[k], *shift,
                                 o.traction[k] if o is not None else memory.traction[k],
                                 *shift_o, float(c), o is not None, False, *grid.shape)
        return t, _shifted_copy(memory.state.astype(np.int8, copy=False), grid.shape, *shift)
    t = remesh(memory.traction, memory.grid, grid)  # (both components at once)
    if o is not None:
        t = t + c * (t - remesh(o.traction, o.grid, grid))
    return t, _state_on(memory, grid, None)


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def _traction_start(nx, ny, dx, dy, x0, y0, v, rate, state, mapped, npx, npy, n1x, n1y,
                    d1x, d1y, x1, y1, h):  # pragma: no cover - compiled
    """The traction ``v + h rate`` (:func:`_advanced`) on the grid (nx, ny, dx, dy, x0,
    y0) from the remembered one's (n1x, ..., y1; its pressure (npx, npy)) and, when
    ``mapped`` and the map ``state`` is of the grid's shape, the map shifted:
    ``(traction, map, 2)``; ``(traction, -, 1)`` without the map; ``(-, -, 0)`` off the
    lattice or a field not of its grid's shape (then re-meshed)."""
    i, j, on = _lattice_offset(d1x, d1y, x1, y1, dx, dy, x0, y0)
    if not (on and npx == n1x and npy == n1y and v.shape[0] == 2 and v.shape[1] == n1x
            and v.shape[2] == n1y):
        return np.empty((0, 0, 0)), np.empty((0, 0), dtype=np.int8), 0
    if mapped and state.shape[0] == n1x and state.shape[1] == n1y:
        t, shifted = _advanced(v, rate, state, i, j, h, nx, ny)
        return t, shifted, 2
    t, shifted = _advanced(v, rate, state[:0, :0], i, j, h, nx, ny)
    return t, shifted, 1


def _state_on(memory: PatchMemory, grid: Grid, shift: tuple[int, int] | None) -> np.ndarray:
    """The memory's adhesion/slip map on ``grid`` (int8): shifted on one lattice
    (``shift``, the offset :func:`_on_lattice` gives), else the nearest element's."""
    st = memory.state
    if shift is not None and st.shape == memory.grid.shape and st.dtype.kind in "iub":
        return _shifted_copy(st.astype(np.int8, copy=False), grid.shape, *shift)
    return np.rint(remesh(st.astype(float), memory.grid, grid, method="nearest")
                   ).astype(np.int8)


_NO_MAP = np.zeros((0, 0), dtype=np.int8)


@numba.njit(cache=True, nogil=True)
def _advanced(v, rate, state, i, j, h, nx, ny):  # pragma: no cover - compiled
    """``v + h rate`` (fields (k, nx', ny')) on the grid (nx, ny) of one lattice
    (``out[:, a, b]`` from ``[:, a + i, b + j]`` of both, zero outside them), as
    ``remesh(v) + h remesh(rate)``; and the map ``state`` (nx', ny') shifted so (zero
    outside it), as :func:`_state_on` gives it (an empty map: an empty one)."""
    nc = v.shape[0]
    n1x, n1y = v.shape[1], v.shape[2]
    out = np.empty((nc, nx, ny))
    shifted = np.zeros((nx, ny) if state.size > 0 else (0, 0), dtype=np.int8)
    for k in range(nc):
        for a in range(nx):
            for b in range(ny):
                x, y = a + i, b + j
                out[k, a, b] = (v[k, x, y] + h * rate[k, x, y]
                                if 0 <= x < n1x and 0 <= y < n1y else 0.0)
    if state.size > 0:
        for a in range(max(0, -i), min(nx, n1x - i)):
            for b in range(max(0, -j), min(ny, n1y - j)):
                shifted[a, b] = state[a + i, b + j]
    return out, shifted
