"""One contact patch: grid -> initial estimate -> normal BEM -> tangential solution.

This is the generic problem that the quadratic case, the wheel-rail case and the time step
are built on: a patch is given by its gap as a function of the grid, its potential contact
area and its control (load or penetration); the settings records say how to solve it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import lru_cache

import numba
import numpy as np

from ..errors import CaseError, RailContactError
from ..geometry.points import FAR
from ..halfspace.grid import Grid, nonzero_box, remesh
from ..halfspace.hertz import MIN_LOAD, HertzSolution, hertz
from ..halfspace.materials import ElasticPair
from ..halfspace.operator import influence_operator, operator_bytes, resolve_backend
from ..normal import NormalResult, solve_normal
from ..normal.virtual import virtual_penetration
from ..settings import Control, GridSettings, NormalSettings, TangentialSettings
from ..settings.case import ELEMENT_BYTES, MAX_ELEMENTS, check_grid_size
from ..tangential import SOLVERS, TangentialResult, rolling_operator
from ..tangential.convexgs import EXTERIOR, SLIP
from ..tangential.fastrip import fastrip, fastrip_hertz
from ..tangential.fastsim import fastsim, fastsim_hertz, flexibilities
from ..tangential.strips import StripResult, remesh_strips, strips_on_contact
from .results import PatchSolution, Work
from .start import Bounds, NormalStart, WarmStart, no_start

UNDEFINED_GAP = 0.5 * FAR
"""Gaps [m] from this up mark elements where the profiles give no gap (the search's
:data:`~railcontact.geometry.points.FAR`); a contact that reaches them is cut off."""
GROW_FACTOR = 1.5
"""Factor by which an automatic potential area grows when the contact reaches its edge."""
MAX_GROW = 4
"""Enlargements of an automatic potential area at most."""



def potential_area(A: float, B: float, delta0: float, margin: float = 1.0) -> Bounds:
    """Potential contact area for a quadratic gap (paper Sec. 2.1) [m].

    ``A x^2 <= delta0`` and ``B y^2 <= delta0``, i.e. the rigid interpenetration region
    for the estimated penetration ``delta0``, scaled by ``margin``. It contains the Hertz
    ellipse, since ``A a^2 + B b^2 = delta0``.
    """
    xl = margin * math.sqrt(delta0 / A)
    yl = margin * math.sqrt(delta0 / B)
    return (-xl, xl, -yl, yl)


def _axis(lo: float, hi: float, n: int, h: float | None, q: int, centred: bool, snap: bool
          ) -> tuple[float, float, int]:
    """One axis of a grid: the counts, or the element size ``h`` with the quantum ``q``
    and the snap (or ``centred``) rules of :class:`~railcontact.settings.GridSettings`."""
    if h is None:
        return lo, hi, n
    if centred:  # edges at (i + 1/2) h: the origin is an element's centre
        first = math.floor(lo / h + 0.5)
        n = max(2, q * math.ceil((math.ceil(hi / h - 0.5) - first + 1) / q))
        return (first - 0.5) * h, (first - 0.5 + n) * h, n
    extra = 1 if snap else 0
    n = max(2, q * math.ceil(((hi - lo) / h + extra) / q - 1e-9))
    c = 0.5 * (lo + hi)
    c = round(c / h) * h if extra else c
    return c - n * h / 2, c + n * h / 2, n


def check_grid_budget(settings: GridSettings, bounds: Bounds, elements: str | None = None
                      ) -> None:
    """Raise a :class:`~railcontact.errors.CaseError` when the grid ``settings`` mesh on
    ``bounds`` [m] would have more elements than their ``max_elements`` (element sizes;
    element counts are checked with the settings). ``elements`` names the element sizes
    in the message (default: ``[grid] dx = ..., dy = ... m``)."""
    x0, x1, y0, y1 = bounds
    dx, dy = settings.dx, settings.dy
    sx = (x1 - x0) / dx if dx else settings.nx
    sy = (y1 - y0) / dy if dy else settings.ny
    if not sx * sy <= settings.max_elements:  # (the message formed only when it is needed)
        named = elements or f"[grid] dx = {dx}, dy = {dy} m"
        check_grid_size(f"the potential area {(x1 - x0) * 1e3:.4g} x {(y1 - y0) * 1e3:.4g} "
                        f"mm with {named}", sx, sy, settings.max_elements)


def make_grid(settings: GridSettings, bounds: Bounds) -> Grid:
    """The BEM grid on ``bounds`` [m] from the counts or element sizes of ``settings``.

    With element sizes, ``quantum`` rounds the counts up to a multiple (fewer distinct
    influence operators in a time series) and ``snap`` puts the grid centre on a multiple
    of the element size, so that the grids of consecutive time steps share one lattice
    around the contact point and a warm start is not smeared by interpolation.
    """
    x0, x1, y0, y1 = map(float, bounds)  # Python floats: an overflow is inf, silently
    check_grid_budget(settings, (x0, x1, y0, y1))
    dx, dy = settings.dx, settings.dy
    q, centred, snap = settings.quantum, settings.centred, settings.snap
    xmin, xmax, nx = _axis(x0, x1, settings.nx, dx, q, centred, snap)
    ymin, ymax, ny = _axis(y0, y1, settings.ny, dy, q, centred, snap)
    if (xmin < xmax and ymin < ymax and xmin - xmin == 0.0 and xmax - xmax == 0.0
            and ymin - ymin == 0.0 and ymax - ymax == 0.0):  # (finite: Grid.from_bounds'
        ex = (xmax - xmin) / nx  # checks passed; its element sizes and centres)
        ey = (ymax - ymin) / ny
        return Grid(int(nx), int(ny), ex, ey, xmin + ex / 2, ymin + ey / 2)
    return Grid.from_bounds(xmin, xmax, ymin, ymax, nx, ny)


def normal_estimate(settings: NormalSettings, hz: HertzSolution | None, s: np.ndarray,
                    f: np.ndarray, a_of_s: np.ndarray, pair: ElasticPair,
                    control: Control) -> WarmStart:
    """The start that ``settings.estimate`` asks for, as a :class:`~.start.WarmStart`.

    "hertz": Hertz's pressure at the element centres; "kp" / "infcon": the virtual
    penetration model on the lateral samples ``s`` [m] with the gap ``f(s)`` [m] and the
    longitudinal curvature ``a_of_s`` [1/m], its amplitude set on its own grid
    (``estimate_grid``), evaluated at the BEM element centres; "none": no estimate. A
    model that fails gives no start, labelled with why (the BEM does not need one).
    """
    method = settings.estimate
    if method == "hertz" and hz is not None:
        return WarmStart(method, lambda grid: NormalStart(hz.pressure(*grid.mesh())))
    if method in ("kp", "infcon"):
        nx, ny = settings.estimate_grid
        try:
            est = virtual_penetration(method, s, f, a_of_s, pair, nx=nx, ny=ny,
                                      **control.kwargs())
        except RailContactError as exc:  # the BEM does not need it: start without
            return no_start(f"{method} failed ({exc}); no estimate")
        return WarmStart(method, lambda grid: NormalStart(est.pressure_on(grid)))
    return no_start(method)


def check_operator_memory(grid: Grid, components: str, backend: str,
                          max_elements: int = MAX_ELEMENTS) -> None:
    """Raise a :class:`~railcontact.errors.CaseError` when the influence operator of
    ``components`` on ``grid`` with ``backend`` would take more memory than ``max_elements``
    elements are budgeted (:data:`~railcontact.settings.case.ELEMENT_BYTES` each), before
    anything is allocated: a dense product grows as the square of the element count."""
    why = _operator_memory_error(grid.nx, grid.ny, components, backend, max_elements)
    if why is not None:
        raise CaseError(why)


@lru_cache(maxsize=256)
def _operator_memory_error(nx: int, ny: int, components: str, backend: str,
                           max_elements: int) -> str | None:
    """:func:`check_operator_memory`'s message for an operator on ``nx`` x ``ny`` elements,
    None when it fits (formed once per grid shape and settings: the patches of a time
    series come back to a few shapes)."""
    concrete = resolve_backend(backend, nx * ny)
    need = operator_bytes(nx, ny, len(components), concrete)
    budget = float(max_elements) * ELEMENT_BYTES
    if need <= budget:
        return None
    n = len(components) * nx * ny
    what = (f"fft = 'dense' needs a {n} x {n} matrix" if concrete == "dense"
            else f"fft = {concrete!r} needs its spectra")
    return (f"[normal] {what} for {nx} x {ny} elements, {need / 2**30:.3g} "
            f"GiB, more than the {budget / 2**30:.3g} GiB that [grid] max_elements "
            f"= {max_elements} allows; set [normal] fft = 'auto' (an FFT product, "
            "memory in proportion to the elements) or use fewer elements")


def solve_patch_normal(gap_of: Callable[[Grid], np.ndarray], bounds: Bounds,
                       grid_settings: GridSettings, settings: NormalSettings,
                       pair: ElasticPair, control: Control, start: WarmStart,
                       automatic: tuple[bool, bool] = (True, True), grid: Grid | None = None,
                       profiles: bool = True, first: NormalResult | None = None
                       ) -> tuple[NormalResult, Work]:
    """BEM normal solution of one patch on the potential area ``bounds`` [m], and the work
    it took.

    ``grid`` (e.g. the grid of an earlier load pass of the same patch) is the first grid
    instead of the one meshed on ``bounds``, so that a solution on it can start the next
    solve without interpolation.

    ``first``: the solution of the first solve on ``grid``, made already (a time step's
    compiled stage, :attr:`~.start.WarmStart.normal_stage`): checked as the first solve's
    and grown from as it would be.

    ``gap_of(grid)`` gives the undeformed gap [m] on a grid, ``start.pressure_on(grid)``
    the initial pressure [Pa] (and its displacement, when known). ``automatic`` says
    along which axes (x, y) the area is the solver's: there it is grown by
    :data:`GROW_FACTOR` while the contact reaches its edge (each growth a re-mesh, its
    iterations counted in the work), at most
    :data:`MAX_GROW` times, after which the result is not converged; a user-given extent
    that the contact reaches is an error. A result that is not finite is not converged.

    A contact next to an element whose gap is :data:`UNDEFINED_GAP` or more is not
    converged: with ``profiles`` (the gap comes from profiles) the contact reaches where the
    profiles end; without (an analytic gap, defined everywhere) the elements are so large
    that the gap grows by that much from one element to the next.
    """
    t0 = time.perf_counter()
    iterations = 0
    for k in range(MAX_GROW + 1):
        if k == 0 and first is not None:
            res = first
            grid = res.grid
        else:
            if grid is None or k > 0:
                grid = make_grid(grid_settings, bounds)
            check_operator_memory(grid, "z", settings.fft, grid_settings.max_elements)
            op = influence_operator(grid, pair, "z", settings.fft)
            gap = gap_of(grid)
            # a grown area starts from the estimate again, not from the truncated
            # solution: that start (its pressure piled up at the old edge) let the CG stop
            # early, with the relative change small but the pressure wrong (a fuzzed
            # two-patch wheel)
            p0, shown = start.pressure_on(grid)
            res = solve_normal(gap, grid, op, initial_pressure=p0,
                               tolerance=settings.tolerance,
                               max_iterations=settings.max_iterations,
                               preconditioner=settings.preconditioner,
                               initial_displacement=shown, min_load=MIN_LOAD,
                               undefined_gap=UNDEFINED_GAP, **control.kwargs())
        iterations += res.iterations
        # the pressure array checked by the solver's summary of it (solve_normal: the
        # force is its sum, max_pressure its largest value or NaN when one is NaN; a
        # NaN or an infinity anywhere makes one of them not finite)
        if not (math.isfinite(res.force) and math.isfinite(res.penetration)
                and math.isfinite(res.max_pressure)):
            res = not_converged(res, f"the normal solution is not finite ({res.message})")
            break
        if res.next_to_undefined:  # (the solve's check of the gap beside its contact)
            if profiles:
                why = ("the contact reaches where the profiles end (or turn away), so the "
                       "patch is cut off there; the pose or the load is beyond the profiles "
                       f"({res.message})")
            else:
                why = (f"the undeformed gap next to the contact is {UNDEFINED_GAP:g} m or "
                       f"more: the elements ({grid.dx:.3g} x {grid.dy:.3g} m) are far larger "
                       "than the contact; give a smaller potential area ([grid] x, y) or "
                       f"smaller elements ({res.message})")
            res = not_converged(res, why)
            break
        if not res.touches_boundary:
            break
        c = res.contact
        edge = (bool(c[0].any() or c[-1].any()), bool(c[:, 0].any() or c[:, -1].any()))
        if any(e and not auto for e, auto in zip(edge, automatic, strict=True)):
            given = ", ".join(f"{k} = {list(v)} m" for k, v, e, auto in zip(
                "xy", (grid_settings.x, grid_settings.y), edge, automatic, strict=True)
                if e and not auto)
            raise CaseError(
                f"potential contact area too small: the contact reaches the edge of [grid] "
                f"{given}; enlarge it or leave it out for an automatic area")
        if k == MAX_GROW:
            res = not_converged(res, (
                f"the contact still reaches the edge of the potential area after {MAX_GROW} "
                f"enlargements by {GROW_FACTOR} (raise [grid] margin or the element counts): "
                f"{res.message}"))
            break
        bounds = _grown(grid.bounds, bounds, automatic)
    return res, Work(normal_iterations=iterations, remeshes=k,
                     seconds=time.perf_counter() - t0)


def not_converged(res, message: str):
    """The solver result ``res`` (normal or tangential) marked not converged with
    ``message``: a new record."""
    return replace(res, converged=False, message=message)


UNCOVERED_MARGIN = 2
"""Elements added around the places :func:`uncovered` finds when the area is grown to
hold them."""


def uncovered(gap_of: Callable[[Grid], np.ndarray], res: NormalResult, pair: ElasticPair,
              overlap: Bounds) -> Bounds | None:
    """The box (xmin, xmax, ymin, ymax) [m] of the element centres on the lattice of the
    solution ``res``'s grid, outside that grid and inside the box ``overlap`` [m] that
    holds the rigid overlap at its penetration, where the solution's deformed gap may be
    negative; None when there is none (the solution is then that of any larger grid).

    Outside the grid the pressure is zero and the deformed gap is ``h - delta + u``
    (``h`` the undeformed gap ``gap_of`` gives, ``delta`` the penetration, ``u`` the
    displacement of the solved pressure). A place with ``h >= delta`` cannot touch
    (``u >= 0``); elsewhere a lower bound of ``u`` decides: by Jensen's inequality for
    the convex ``1/r`` and Cauchy-Schwarz::

        u(x) = 1/(pi E*) int p(y) / |x - y| dy >= F / (pi E* sqrt(|x - c|^2 + s^2)),

    ``F`` the force, ``c`` the pressure's centroid and ``s^2`` its second moment about it
    (the elements' own spread ``(dx^2 + dy^2) / 12`` included). An element where
    ``h - delta`` plus this bound is negative is flagged. The bound is low for places far
    from a wide contact, so it flags some that would not touch (a re-mesh, not an error);
    it flags none of those that do. One pass over the lattice of the overlap box; the gap
    there is formed once."""
    g = res.grid
    pen = float(res.penetration)
    dx, dy = g.dx, g.dy
    b = g.bounds
    if (b[0] <= overlap[0] and overlap[1] <= b[1] and b[2] <= overlap[2]
            and overlap[3] <= b[3]):
        return None
    i0 = min(0, math.ceil((overlap[0] - g.x0) / dx))
    i1 = max(g.nx, math.floor((overlap[1] - g.x0) / dx) + 1)
    j0 = min(0, math.ceil((overlap[2] - g.y0) / dy))
    j1 = max(g.ny, math.floor((overlap[3] - g.y0) / dy) + 1)
    outer = Grid(int(i1 - i0), int(j1 - j0), dx, dy, g.x0 + i0 * dx, g.y0 + j0 * dy)
    h = gap_of(outer)
    p = np.asarray(res.pressure, dtype=float)
    found, a0, a1, c0, c1 = _uncovered(h, pen, p, int(-i0), int(-j0), float(g.x0), dx,
                                       float(g.y0), dy, float(outer.x0), float(outer.y0),
                                       1.0 / (math.pi * pair.e_star))
    if not found:
        return None
    return (outer.x0 + (a0 - 0.5) * dx, outer.x0 + (a1 + 0.5) * dx,
            outer.y0 + (c0 - 0.5) * dy, outer.y0 + (c1 + 0.5) * dy)


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def _uncovered(h, pen, p, ia, jb, x0, dx, y0, dy, ox, oy, k):  # pragma: no cover
    """:func:`uncovered`'s pass: the pressure's force, centroid and second moment on its
    grid (at the offset ``(ia, jb)`` in the outer one), then the outer elements outside
    it with ``h - pen + k F / sqrt(r^2 + s^2) < 0``; returns (found, first and last row,
    first and last column of them)."""
    nx, ny = p.shape
    w = sx = sy = 0.0
    for i in range(nx):
        for j in range(ny):
            q = p[i, j]
            if q > 0.0:
                w += q
                sx += q * (x0 + i * dx)
                sy += q * (y0 + j * dy)
    if not w > 0.0:
        return False, 0, 0, 0, 0
    cx, cy = sx / w, sy / w
    s2 = 0.0
    for i in range(nx):
        for j in range(ny):
            q = p[i, j]
            if q > 0.0:
                ex, ey = x0 + i * dx - cx, y0 + j * dy - cy
                s2 += q * (ex * ex + ey * ey)
    s2 = s2 / w + (dx * dx + dy * dy) / 12.0
    force = w * dx * dy
    mx, my = h.shape
    found = False
    a0 = c0 = 1 << 30
    a1 = c1 = -1
    for a in range(mx):
        inside_x = ia <= a < ia + nx
        ex = ox + a * dx - cx
        for c in range(my):
            if inside_x and jb <= c < jb + ny:
                continue
            d = h[a, c] - pen
            if d >= 0.0:
                continue
            ey = oy + c * dy - cy
            if d + k * force / math.sqrt(ex * ex + ey * ey + s2) < 0.0:
                found = True
                a0, a1 = min(a0, a), max(a1, a)
                c0, c1 = min(c0, c), max(c1, c)
    return found, a0, a1, c0, c1


def _grown(meshed: Bounds, asked: Bounds, automatic: tuple[bool, bool]) -> Bounds:
    """The area ``meshed`` (the grid's) scaled by :data:`GROW_FACTOR` about its centre
    along the automatic axes; along the others the area ``asked`` for, unchanged (a grid
    snapped to the element size is wider than that, and would creep)."""
    out = list(asked)
    for axis, auto in enumerate(automatic):
        if auto:
            lo, hi = meshed[2 * axis], meshed[2 * axis + 1]
            c = 0.5 * (lo + hi)
            out[2 * axis] = c + (lo - c) * GROW_FACTOR
            out[2 * axis + 1] = c + (hi - c) * GROW_FACTOR
    return (out[0], out[1], out[2], out[3])


def simplified_tangential(model: str, hz: HertzSolution, pair: ElasticPair,
                          settings: TangentialSettings, normal: NormalResult | None = None,
                          creepage: tuple[float, float, float] | None = None,
                          friction: float | None = None) -> StripResult:
    """FASTSIM or FaStrip (``model``) with the settings' friction, strips and bound.

    Without ``normal``: on the Hertz ellipse ``hz`` (elliptic or parabolic bound). With a
    normal solution: on the actual patch (strips along its contact rows, its pressure as the
    traction bound) with the coefficients of its equivalent ellipse - the adaptation for
    non-elliptic wheel-rail patches. ``creepage`` (xi, eta, phi) replaces the settings',
    ``friction`` [-] the settings' coefficient (a patch's own, of a friction table).
    """
    nx, ny = settings.strips
    mu = settings.friction if friction is None else friction
    creepage = settings.creepage if creepage is None else creepage
    if normal is None:
        args = (hz.a, hz.b, hz.load, pair, mu, creepage)
        if model == "fastsim":
            return fastsim_hertz(*args, nx=nx, ny=ny, bound=settings.bound)
        return fastrip_hertz(*args, nx=nx, ny=ny)
    # the samples carry the BEM's force (so |F| <= mu N holds in total); the coefficients
    # from the patch's equivalent ellipse
    strips, pn, (a_eq, b_eq) = strips_on_contact(normal.grid, normal.contact,
                                                 normal.pressure, normal.force, nx)
    if model == "fastsim":
        return fastsim(strips, pn, mu, creepage, flexibilities(a_eq, b_eq, pair))
    return fastrip(strips, pn, normal.force, a_eq, b_eq, pair, mu, creepage)


def start_pressure(patch: PatchSolution, grid: Grid) -> np.ndarray:
    """The pressure [Pa] of a solved ``patch`` on ``grid`` (a copy on its own lattice)."""
    return remesh(patch.normal.pressure, patch.normal.grid, grid)


def start_from(patch: PatchSolution, grid: Grid
               ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """The pressure [Pa], traction [Pa] (2, nx, ny) and adhesion/slip map of a solved
    ``patch`` on ``grid`` (a copy when it is the patch's own lattice; traction and map None
    without a BEM tangential solution): the start of another solve of the same patch."""
    src = patch.normal.grid
    p = start_pressure(patch, grid)
    t = patch.tangential
    if not isinstance(t, TangentialResult):
        return p, None, None
    traction = np.stack([remesh(t.traction[k], src, grid) for k in range(2)])
    state = np.rint(remesh(t.state.astype(float), src, grid, method="nearest"))
    return p, traction, state.astype(np.int8)


def solve_patch_tangential(patch: PatchSolution, settings: TangentialSettings,
                           pair: ElasticPair, fft: str,
                           creepage: tuple[float, float, float] | None = None,
                           previous: tuple | None = None,
                           friction: float | PatchFriction | None = None
                           ) -> PatchSolution:
    """``patch`` with its tangential solution (on the grid of its normal solution): a new
    record.

    ``creepage`` (xi [-], eta [-], phi [1/m]) replaces the settings' (a time step gives
    each patch its own); ``fft`` is the convolution backend. ``previous`` = (traction
    (2, nx, ny) [Pa], adhesion/slip map) on the patch's grid, e.g. the previous time
    step's: when it holds a traction it starts the BEM instead of the estimate asked for in
    ``settings``. ``friction`` replaces the settings' coefficient (which must then be a
    number): the patch's own [-], or (:class:`PatchFriction`) its coefficient at the
    reference point and one per lateral element row. The coefficient at the reference point
    is the new record's ``friction``; its ``work`` is the patch's with the sweeps and the
    time added.
    """
    t0 = time.perf_counter()
    if friction is None:
        friction = settings.friction
    if isinstance(friction, PatchFriction):
        reference = float(friction.reference)
    elif isinstance(friction, (int, float)):
        reference = float(friction)
    else:
        raise CaseError("a friction table is read per patch: give solve_patch_tangential "
                        "the patch's coefficient (friction=...)")
    t = _tangential(patch, settings, pair, fft, creepage, previous, friction, reference)
    return tangential_solved(patch, t, settings.creepage if creepage is None else creepage,
                             settings, reference, time.perf_counter() - t0)


def tangential_solved(patch: PatchSolution, t: TangentialResult | StripResult,
                      creepage: tuple[float, float, float], settings: TangentialSettings,
                      friction: float, seconds: float) -> PatchSolution:
    """``patch`` with its new tangential solution ``t`` (a new record): the ``creepage``
    (xi [-], eta [-], phi [1/m]), model and estimate of the ``settings`` and the
    ``friction`` [-] it was solved with, its sweeps and the ``seconds`` [s] it took added
    to the work; a solution that is not finite marked not converged."""
    fx, fy = t.force
    # the traction array checked by the solver's summary of it: max_traction is the
    # largest |p| or NaN when one is NaN, so finite only when every traction is
    if not (math.isfinite(fx) and math.isfinite(fy) and math.isfinite(t.spin_moment)
            and math.isfinite(t.max_traction)):
        t = not_converged(t, f"the tangential solution is not finite ({t.message})")
    elif (type(friction) is float and patch.normal.force > 0
          and negligible_friction(friction, patch.normal.max_pressure)):
        t = _frictionless(t, patch.normal.pressure, friction)
    w = patch.work
    work = Work(w.normal_iterations, w.tangential_iterations + t.iterations, w.load_passes,
                w.remeshes, w.seconds + seconds)
    return patch.replaced(tangential=t, tangential_model=settings.model,
                          tangential_estimate=settings.estimate, friction=friction,
                          creepage=tuple(map(float, creepage)), work=work)


def _tangential(patch: PatchSolution, settings: TangentialSettings, pair: ElasticPair,
                fft: str, creepage: tuple[float, float, float] | None,
                previous: tuple | None, friction: float | PatchFriction,
                reference: float) -> TangentialResult | StripResult:
    """The tangential solution of ``patch`` (:func:`solve_patch_tangential`; ``reference``
    the coefficient of friction at its reference point)."""
    res = patch.normal
    creepage = settings.creepage if creepage is None else tuple(creepage)
    model, estimate = settings.model, settings.estimate
    if (not isinstance(friction, PatchFriction)
            and negligible_friction(reference, res.max_pressure)):
        friction = reference = 0.0  # (solved as mu = 0: no NaN of subnormal bounds)
    p0, st0 = previous if previous is not None else (None, None)
    # The simplified models work on the Hertz ellipse that carries the BEM's normal force
    # (not needed when the BEM starts from a given traction).
    needs_hertz = model != "bem" or (p0 is None and estimate != "none")
    hz = (hertz(*patch.curvatures, pair, load=res.force) if res.force > 0 and needs_hertz
          else None)
    actual = res if patch.geometry is not None else None  # wheel-rail: non-elliptic patch
    if model != "bem":
        if hz is None:
            raise CaseError("no contact: the simplified tangential models need a load")
        if isinstance(friction, PatchFriction):
            raise CaseError(f"{model}: friction per element row needs the BEM")
        return simplified_tangential(model, hz, pair, settings, actual, creepage, friction)
    if p0 is None and estimate != "none" and hz is not None:
        p0, st0 = remesh_strips(
            simplified_tangential(estimate, hz, pair, settings, actual, creepage,
                                  reference), res.grid)
    grid, pn = res.grid, res.pressure
    solver = settings.solver
    window = None if solver == "convexgs" else contact_window(
        res.contact, box=res.contact_box or (-1, 0, -1, 0))
    if window is not None:  # solve on the contact's own window, return on the patch's grid
        sx, sy = window
        i0, j0, dx, dy = sx.start, sy.start, grid.dx, grid.dy
        grid = Grid(sx.stop - i0, sy.stop - j0, dx, dy, grid.x0 + i0 * dx, grid.y0 + j0 * dy)
        pn = pn[sx, sy]
        p0 = None if p0 is None else np.asarray(p0)[:, sx, sy]
        st0 = None if st0 is None else np.asarray(st0)[sx, sy]
    # (on a window: the result on the patch's grid, zero outside the window)
    check_operator_memory(grid, "xy", fft)
    mu = friction.rows(grid) if isinstance(friction, PatchFriction) else friction
    return SOLVERS[solver](
        grid, rolling_operator(grid, pair, fft), pn, mu, creepage, initial_traction=p0,
        initial_state=st0, tolerance=settings.tolerance,
        max_iterations=settings.max_iterations, spin_offset=settings.spin_offset,
        embed=None if window is None else (res.grid, window))


NEGLIGIBLE_BOUND = 2.0**-970
"""The largest traction bound mu p [Pa] (about 1e-292) below which a contact is solved
without friction (:func:`negligible_friction`): from it, every bound of an element whose
pressure is within 2**52 of the largest is a normal floating-point number; below it the
bounds are subnormal numbers of a few bits, on which the solvers' arithmetic gives NaN."""


def negligible_friction(friction: float, max_pressure: float) -> bool:
    """Whether a contact whose largest pressure is ``max_pressure`` [Pa] has no friction to
    speak of: ``friction`` mu [-] is 0, or its largest traction bound ``mu p`` is below
    :data:`NEGLIGIBLE_BOUND` (the creep force it could carry is below 1e-290 N). Such a
    contact is solved with mu = 0: zero traction, the whole contact slides."""
    return friction == 0.0 or 0.0 < friction * max_pressure < NEGLIGIBLE_BOUND


def _frictionless(t: TangentialResult, pressure: np.ndarray,
                  friction: float) -> TangentialResult:
    """The tangential solution ``t`` of a contact (its ``pressure`` [Pa], on ``t``'s grid)
    solved without friction (``friction`` mu [-] the case's, :func:`negligible_friction`):
    the BEM solvers, whose traction bound mu p is zero everywhere, see no element in
    contact; the whole contact slides with zero traction."""
    if pressure.shape != t.state.shape:
        return t
    why = "mu = 0" if friction == 0.0 else (f"mu = {friction:.3g}: mu p below "
                                            f"{NEGLIGIBLE_BOUND:.3g} Pa")
    return replace(t, state=np.where(pressure > 0, SLIP, EXTERIOR).astype(t.state.dtype),
                   slip_area_ratio=1.0, message=f"no friction ({why}): zero traction, the "
                   "whole contact slides")


@dataclass(frozen=True)
class PatchFriction:
    """A patch's coefficient of friction when it varies across the patch: ``reference``
    [-] at its reference point (what a single number stands for: the load loop's checks,
    the output), ``rows(grid)`` one per lateral row of elements of a grid of the patch,
    an array (1, ny) [-] (:func:`~railcontact.settings.friction.row_friction`)."""

    reference: float
    rows: Callable[[Grid], np.ndarray]


WINDOW_QUANTUM = 8
"""Element counts of a tangential window are multiples of this (few operators and plans)."""


def contact_window(contact: np.ndarray, quantum: int = WINDOW_QUANTUM,
                   box: tuple[int, int, int, int] | None = None) -> tuple[slice, slice] | None:
    """The part of a grid (slices along x and y) on which a tangential solve gives the
    same answer as on the whole grid: the box around the ``contact`` elements, its counts
    rounded up to multiples of ``quantum`` (within the grid). Outside the contact the
    traction bound is zero, so those elements take no part in the steady-rolling problem;
    a window a fraction of the potential area makes every sweep's transforms that much
    cheaper. None when it would be the whole grid, or there is no contact. ``box`` (e.g.
    the normal solution's :attr:`~railcontact.normal.NormalResult.contact_box`; ``i0 <
    0``: no contact) is the box of ``contact``, given."""
    i0, i1, j0, j1 = nonzero_box(contact) if box is None else box
    if i0 < 0:
        return None
    nx, ny = contact.shape
    mx = min(nx, quantum * math.ceil((i1 - i0) / quantum))
    my = min(ny, quantum * math.ceil((j1 - j0) / quantum))
    if mx == nx and my == ny:
        return None
    sx = min(max(i0 - (mx - (i1 - i0)) // 2, 0), nx - mx)
    sy = min(max(j0 - (my - (j1 - j0)) // 2, 0), ny - my)
    return slice(sx, sx + mx), slice(sy, sy + my)
