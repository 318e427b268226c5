"""Strip discretisation shared by the simplified tangential models (FASTSIM, FaStrip).

A patch is cut into strips along the rolling direction x. Strip ``j`` at lateral position
``y[j]`` with width (quadrature weight) ``width[j]`` spans ``[x_lo[j], x_hi[j]]`` and is
sampled at ``nx`` points at normalised positions ``t`` in (-1, 1) with weights ``w``
(sum 2): the centres of ``nx`` equal sub-intervals (midpoint rule, exact for tractions
linear in x, as FASTSIM gives in full adhesion for xi and eta), or Gauss–Legendre points
(exact up to degree 2 nx - 1, so also for the spin part).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.polynomial.legendre import leggauss

from ..errors import RailContactError
from ..halfspace.grid import Grid
from ..halfspace.interp import interp_on_piece, uniform_piece
from ..halfspace.sums import numpy_sum
from ..status import Work

EXTERIOR, ADHESION, SLIP = 0, 1, 2


@dataclass(frozen=True)
class Strips:
    """Strips across a contact patch [m]; see the module docstring."""

    y: np.ndarray
    width: np.ndarray
    x_lo: np.ndarray
    x_hi: np.ndarray
    t: np.ndarray
    w: np.ndarray

    @property
    def nx(self) -> int:
        return len(self.t)

    @property
    def x(self) -> np.ndarray:
        """Sample points (ny, nx) [m], increasing in x."""
        half = 0.5 * (self.x_hi - self.x_lo)
        mid = 0.5 * (self.x_hi + self.x_lo)
        return mid[:, None] + half[:, None] * self.t[None, :]

    @property
    def area(self) -> np.ndarray:
        """Area represented by each sample (ny, nx) [m^2]."""
        half = 0.5 * (self.x_hi - self.x_lo)
        return (self.width * half)[:, None] * self.w[None, :]

    @classmethod
    def ellipse(cls, a: float, b: float, nx: int = 40, ny: int = 40,
                quadrature: str = "uniform") -> Strips:
        """Strips across the ellipse ``x^2/a^2 + y^2/b^2 <= 1``.

        ``quadrature="uniform"``: ``ny`` strips of equal width (Kalker's FASTSIM);
        ``"gauss"``: Gauss–Legendre strip positions and weights, exact for forces that
        are polynomials of degree < 2 ny in y (the linear theory's F_x and F_y(eta)).
        """
        if nx < 1 or ny < 1:
            raise RailContactError("strip counts nx, ny must be positive")
        if quadrature not in ("uniform", "gauss"):
            raise RailContactError(f"quadrature must be 'uniform' or 'gauss', got {quadrature!r}")
        ty, wy = _rule(ny, quadrature)
        y, width = b * ty, b * wy
        half = a * np.sqrt(np.clip(1 - (y / b) ** 2, 0, None))
        t, w = _rule(nx, quadrature)
        return cls(y=y, width=width, x_lo=-half, x_hi=half, t=t, w=w)


def check_samples(strips: Strips, name: str, values: np.ndarray, leading: tuple = ()) -> None:
    """Raise a :class:`RailContactError` unless ``values`` has the shape of the strips'
    samples ``(*leading, ny, nx)`` (the compiled passes read them by these counts, and
    the strips' arrays by them: each of one length ny, and nx weights)."""
    ny = strips.y.size
    if (strips.width.shape, strips.x_lo.shape, strips.x_hi.shape, strips.w.shape) != (
            (ny,), (ny,), (ny,), strips.t.shape) or strips.y.ndim != 1 or strips.t.ndim != 1:
        raise RailContactError("strips: y, width, x_lo and x_hi must be 1-D of one length, "
                               "and t and w too")
    want = (*leading, ny, strips.nx)
    if np.shape(values) != want:
        raise RailContactError(f"{name} must have the strip shape {want}, got "
                               f"{np.shape(values)}")


def _check_grid_field(grid: Grid, name: str, values: np.ndarray) -> None:
    if np.shape(values) != grid.shape:
        raise RailContactError(f"{name} must have the grid's shape {grid.shape}, got "
                               f"{np.shape(values)}")


def strips_from_contact(grid: Grid, contact: np.ndarray, nx: int = 40) -> Strips:
    """Strips along the rows of a contact mask on a grid (non-elliptic patches): each row
    with contact is one strip of width dy, from the trailing to the leading edge of its
    contact elements (element edges); gaps inside a row are bridged."""
    return _strips_of_rows(grid, contact, nx)[0]


def _strips_of_rows(grid: Grid, contact: np.ndarray, nx: int) -> tuple:
    """:func:`strips_from_contact`, with the grid rows ``j`` of the strips, the first and
    last ``i`` with contact on any row and the count of elements in contact."""
    rows, first, last, i0, i1, count = _row_ends(np.ascontiguousarray(contact, dtype=np.bool_))
    if rows.size == 0:
        raise RailContactError("no contact elements to build strips from")
    lo = grid.x[first] - grid.dx / 2
    hi = grid.x[last] + grid.dx / 2
    t, w = _rule(nx, "uniform")
    strips = Strips(y=grid.y[rows], width=np.full(rows.size, grid.dy), x_lo=lo, x_hi=hi, t=t,
                    w=w)
    return strips, rows, i0, i1, count


@numba.njit(cache=True, nogil=True)
def _row_ends(contact):  # pragma: no cover - compiled
    """The grid rows ``j`` (along x) with contact in ``contact`` (nx, ny), the first and
    last element ``i`` in contact on each, the first and last ``i`` with contact on any
    row, and the count of elements in contact."""
    nx, ny = contact.shape
    first = np.full(ny, -1)
    last = np.full(ny, -1)
    i0 = -1
    i1 = -1
    count = 0
    for i in range(nx):
        for j in range(ny):
            if contact[i, j]:
                if first[j] < 0:
                    first[j] = i
                last[j] = i
                if i0 < 0:
                    i0 = i
                i1 = i
                count += 1
    rows = np.flatnonzero(first >= 0)
    return rows, first[rows], last[rows], i0, i1, count


def sample_on_strips(values: np.ndarray, grid: Grid, strips: Strips) -> np.ndarray:
    """A field on the grid (nx, ny) at the strip samples (ny_s, nx_s), linearly along x on
    the strip's grid row (strips made by :func:`strips_from_contact`)."""
    _check_grid_field(grid, "the sampled field", values)
    rows = np.searchsorted(grid.y, strips.y - 1e-12 * grid.dy)
    if rows.size and rows.max() >= grid.ny:  # (the compiled pass reads the row unchecked)
        raise RailContactError(f"strips beyond the grid's last row (y up to "
                               f"{strips.y.max():g} m, the grid's to {grid.y[-1]:g} m)")
    return _sample_rows(np.ascontiguousarray(values, dtype=float), grid.x, rows,
                        strips.x_lo, strips.x_hi, strips.t)


@numba.njit(cache=True, nogil=True)
def _sample_rows(values, gx, rows, x_lo, x_hi, t):  # pragma: no cover - compiled
    """``np.interp(x[k], gx, values[:, rows[k]])`` at every strip's samples ``x[k]``
    (:attr:`Strips.x`'s), (ny_s, nx_s)."""
    ns, nt = rows.size, t.size
    n = gx.size
    out = np.empty((ns, nt))
    h = gx[1] - gx[0] if n > 1 else 1.0
    for k in range(ns):
        half = 0.5 * (x_hi[k] - x_lo[k])
        mid = 0.5 * (x_hi[k] + x_lo[k])
        column = values[:, rows[k]]
        for m in range(nt):
            x = mid + half * t[m]
            j = uniform_piece(x, gx, gx[0], h)
            # the common case written out (a point between two samples), else numpy's
            # rules (on a sample, beyond the samples, NaN)
            if x > gx[0] and j < n - 1 and gx[j] < x:
                f0 = column[j]
                f1 = column[j + 1]
                v = (f1 - f0) / (gx[j + 1] - gx[j]) * (x - gx[j]) + f0
                if not math.isnan(v):
                    out[k, m] = v
                    continue
            out[k, m] = interp_on_piece(x, gx, column, j)
    return out


def strips_on_contact(grid: Grid, contact: np.ndarray, pressure: np.ndarray, force: float,
                      nx: int = 40) -> tuple[Strips, np.ndarray, tuple[float, float]]:
    """:func:`strips_from_contact`, the ``pressure`` [Pa] on the grid sampled on them
    (:func:`sample_on_strips`) and scaled so that the samples carry ``force`` [N] (when
    they carry any), and :func:`equivalent_ellipse` of the contact [m]: the same values,
    in one compiled pass over the contact."""
    _check_grid_field(grid, "the contact", contact)
    _check_grid_field(grid, "the pressure", pressure)
    strips, rows, i0, i1, count = _strips_of_rows(grid, contact, nx)
    pn = _sample_rows(np.ascontiguousarray(pressure, dtype=float), grid.x, rows, strips.x_lo,
                      strips.x_hi, strips.t)
    _carry(pn, strips.width, strips.x_lo, strips.x_hi, strips.w, float(force))
    area = count * grid.element_area
    length = (i1 - i0 + 1) * grid.dx
    across = (rows[-1] - rows[0] + 1) * grid.dy
    r = math.sqrt(area / math.pi)
    return strips, pn, (float(r * math.sqrt(length / across)),
                        float(r * math.sqrt(across / length)))


@numba.njit(cache=True, nogil=True)
def _carry(pn, width, x_lo, x_hi, w, force):  # pragma: no cover - compiled
    """Scale the samples ``pn`` (ny_s, nx_s) [Pa] in place so that they carry ``force``
    [N] (``pn * (force / sum(pn da))``, ``da`` as :attr:`Strips.area` forms it; unscaled
    when they carry nothing)."""
    ns, nt = pn.shape
    terms = np.empty((ns, nt))
    for k in range(ns):
        wh = width[k] * (0.5 * (x_hi[k] - x_lo[k]))
        for m in range(nt):
            terms[k, m] = pn[k, m] * (wh * w[m])
    carried = numpy_sum(terms)
    if carried > 0:
        scale = force / carried
        for k in range(ns):
            for m in range(nt):
                pn[k, m] = pn[k, m] * scale


def equivalent_ellipse(grid: Grid, contact: np.ndarray) -> tuple[float, float]:
    """Semi-axes (a, b) [m] of the ellipse with the patch's area and the aspect ratio of its
    overall length and width (Kik–Piotrowski / CONTACT's ``equiv_ellipse``)."""
    area = contact.sum() * grid.element_area
    ix = np.flatnonzero(contact.any(axis=1))
    iy = np.flatnonzero(contact.any(axis=0))
    length = (ix[-1] - ix[0] + 1) * grid.dx
    width = (iy[-1] - iy[0] + 1) * grid.dy
    r = np.sqrt(area / np.pi)
    return float(r * np.sqrt(length / width)), float(r * np.sqrt(width / length))


def _rule(n: int, quadrature: str) -> tuple[np.ndarray, np.ndarray]:
    """Points and weights on (-1, 1): midpoints of n equal cells, or Gauss–Legendre."""
    if quadrature == "gauss":
        return leggauss(n)
    return -1 + (2 * np.arange(n) + 1) / n, np.full(n, 2 / n)


@dataclass(frozen=True)
class StripResult:
    """Result of a simplified tangential model on strips (SI units).

    Attributes
    ----------
    strips
        The discretisation.
    traction
        (p_x, p_y) at the sample points [Pa], shape (2, ny, nx).
    state
        1 adhesion, 2 slip (0 outside the patch), shape (ny, nx).
    pressure
        Normal pressure used for the traction bound [Pa], (ny, nx).
    force, spin_moment, slip_area_ratio, max_traction, iterations, converged, message,
    wall_time
        As in :class:`railcontact.tangential.TangentialResult` (``iterations`` is 0: the
        simplified models do not iterate).
    """

    strips: Strips
    traction: np.ndarray
    state: np.ndarray
    pressure: np.ndarray
    force: tuple[float, float]
    spin_moment: float
    slip_area_ratio: float
    max_traction: float
    iterations: int = 0
    converged: bool = True
    message: str = ""
    wall_time: float = 0.0
    extra: dict = field(default_factory=dict, repr=False)

    @property
    def work(self) -> Work:
        """The solve's work (:class:`~railcontact.status.Work`, the solver results'
        record): its iterations (none: a strip model is not iterated) and wall time
        [s]."""
        return Work(tangential_iterations=self.iterations, load_passes=0,
                    seconds=self.wall_time)


def summarise(strips: Strips, traction: np.ndarray, state: np.ndarray, pressure: np.ndarray,
              message: str, t0: float) -> StripResult:
    """Integrate a strip traction field into a :class:`StripResult`."""
    check_samples(strips, "the traction", traction, (2,))
    check_samples(strips, "the state", state)
    traction = np.ascontiguousarray(traction, dtype=float)
    sums = summary(strips.x_lo, strips.x_hi, strips.width, strips.y, strips.t, strips.w,
                   traction, np.ascontiguousarray(state))
    return strip_result(strips, traction, state, pressure, sums, message, t0)


def strip_result(strips: Strips, traction: np.ndarray, state: np.ndarray,
                 pressure: np.ndarray, sums: tuple, message: str, t0: float) -> StripResult:
    """The :class:`StripResult` of a traction field and its :func:`summary`."""
    fx, fy, mz, ncon, nslip, tmax = sums
    ratio = float(nslip / ncon) if ncon else 0.0
    return StripResult(strips=strips, traction=traction, state=state, pressure=pressure,
                       force=(fx, fy), spin_moment=mz, slip_area_ratio=ratio,
                       max_traction=tmax, message=message,
                       wall_time=time.perf_counter() - t0)


@numba.njit(cache=True, nogil=True)
def summary(x_lo, x_hi, width, y, t, w, traction, state):  # pragma: no cover - compiled
    """The sums of :func:`summarise` as numpy forms them: the forces ``sum(p_c da)`` [N],
    the spin moment ``sum((x p_y - y p_x) da)`` [N m] (``da`` and ``x`` as
    :attr:`Strips.area` and :attr:`Strips.x` form them), the counts of samples in contact
    and in slip, and the largest ``|p|`` [Pa] (0 for none, NaN if one is NaN)."""
    ny, nx = state.shape
    terms = np.empty((3, ny, nx))
    ncon = 0
    nslip = 0
    tmax = 0.0
    for j in range(ny):
        half = 0.5 * (x_hi[j] - x_lo[j])
        mid = 0.5 * (x_hi[j] + x_lo[j])
        wh = width[j] * half
        for k in range(nx):
            da = wh * w[k]
            xk = mid + half * t[k]
            px, py = traction[0, j, k], traction[1, j, k]
            terms[0, j, k] = px * da
            terms[1, j, k] = py * da
            terms[2, j, k] = (xk * py - y[j] * px) * da
            if state[j, k] != EXTERIOR:
                ncon += 1
                if state[j, k] == SLIP:
                    nslip += 1
            m = math.hypot(px, py)
            if not m <= tmax and tmax == tmax:  # (a NaN kept: numpy's max)
                tmax = m
    return (numpy_sum(terms[0]), numpy_sum(terms[1]), numpy_sum(terms[2]), ncon, nslip,
            tmax)


def remesh_strips(result: StripResult, grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """Traction (2, nx, ny) [Pa] and state (nx, ny) of a strip result on a BEM grid.

    Along each strip the traction is interpolated linearly in the normalised coordinate
    (the trailing-end sample held to the trailing edge, zero at the leading edge, nothing
    beyond); across strips linearly between the two nearest strip centres (the nearest one
    beyond the outermost centres, nothing beyond the patch). The state is taken from the
    nearest sample of the nearest strip.
    """
    s = result.strips
    check_samples(s, "the traction", result.traction, (2,))
    check_samples(s, "the state", result.state)
    if s.y.size == 0 or s.nx == 0:  # (the compiled pass reads the first strip and sample)
        raise RailContactError("no strips or no samples on them to re-mesh")
    order = np.argsort(s.y)
    return _remesh(s.y, s.width, s.x_lo, s.x_hi, s.t, order,
                   np.ascontiguousarray(result.traction, dtype=float),
                   np.ascontiguousarray(result.state, dtype=np.int8), grid.x, grid.y)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _remesh(y, width, x_lo, x_hi, t, order, traction, state, gx, gy
            ):  # pragma: no cover - compiled
    """:func:`remesh_strips` on the grid with element centres ``gx``, ``gy`` [m] (the
    strips in the increasing order ``order`` of ``y``): numpy's operations of the
    interpolation, element by element."""
    ns, nt = y.size, t.size
    gnx, gny = gx.size, gy.size
    # along each strip: the grid's x at the strip's normalised coordinate
    along = np.zeros((2, ns, gnx))
    state_along = np.zeros((ns, gnx), dtype=np.int8)
    for m in range(ns):
        half = 0.5 * (x_hi[m] - x_lo[m])
        mid = 0.5 * (x_hi[m] + x_lo[m])
        for i in range(gnx):
            tg = (gx[i] - mid) / half
            if not abs(tg) <= 1.0:
                continue  # (outside: zero traction, exterior)
            k = 0  # np.searchsorted of the knots -1, t, 1 (the first at or after tg)
            while k < nt + 1 and (-1.0 if k == 0 else t[k - 1]) < tg:
                k += 1
            k = min(max(k, 1), nt + 1)
            lo = -1.0 if k == 1 else t[k - 2]
            hi = 1.0 if k == nt + 1 else t[k - 1]
            w = (tg - lo) / (hi - lo)
            for c in range(2):
                v0 = traction[c, m, max(k - 2, 0)]
                v1 = traction[c, m, k - 1] if k <= nt else 0.0
                along[c, m, i] = v0 * (1 - w) + v1 * w
            near = k - 2 if w < 0.5 else k - 1
            state_along[m, i] = state[m, min(max(near, 0), nt - 1)]
    # across the strips: between the two nearest strip centres
    out = np.zeros((2, gnx, gny))
    out_state = np.zeros((gnx, gny), dtype=np.int8)
    edge_lo = y[order[0]] - 0.5 * width[order[0]]
    edge_hi = y[order[ns - 1]] + 0.5 * width[order[ns - 1]]
    top = max(ns - 1, 1)
    for jj in range(gny):
        g = gy[jj]
        if ns == 1:
            tt = 0.0
            lo_idx = hi_idx = 0
        else:
            j = 0  # np.searchsorted(ys, g): the first strip centre at or after g
            while j < ns and y[order[j]] < g:
                j += 1
            j = min(max(j, 1), top)
            y0, y1 = y[order[j - 1]], y[order[j]]
            tt = (g - y0) / (y1 - y0)
            if tt < 0.0:
                tt = 0.0
            elif tt > 1.0:
                tt = 1.0
            lo_idx, hi_idx = order[j - 1], order[j]
        valid = 1.0 if g >= edge_lo and g <= edge_hi else 0.0
        nearest = lo_idx if tt < 0.5 else hi_idx
        for i in range(gnx):
            for c in range(2):
                out[c, i, jj] = ((1 - tt) * along[c, lo_idx, i]
                                 + tt * along[c, hi_idx, i]) * valid
            out_state[i, jj] = state_along[nearest, i] if valid > 0.0 else EXTERIOR
    return out, out_state
