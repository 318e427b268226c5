"""The potential-contact grid: rectangular elements of equal size in the tangent plane.

Fields on the grid are arrays of shape ``(nx, ny)`` indexed ``[i, j]`` with element
centres ``x[i] = x0 + i dx`` (rolling direction) and ``y[j] = y0 + j dy`` (lateral).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numba
import numpy as np

from ..errors import RailContactError, check_finite, check_positive

_INDICES = np.arange(1024.0)
_INDICES.flags.writeable = False


def _indices(n: int) -> np.ndarray:
    """0, 1, ..., n - 1 as floats (the same values ``np.arange(n)`` gives a product with
    a float; a slice of one array for the usual counts)."""
    return _INDICES[:n] if n <= _INDICES.size else np.arange(float(n))


@functools.lru_cache(maxsize=256, typed=True)
def element_centres(origin: float, size: float, n: int) -> np.ndarray:
    """The centres ``origin + size * i`` [m] of ``n`` elements (i = 0 ... n - 1) along one
    axis of a grid, read-only: one array for every grid with these values (a grid's
    :attr:`Grid.x` and :attr:`Grid.y`; most grids of a time step read neither)."""
    out = origin + size * _indices(n)
    out.flags.writeable = False
    return out


_BOUND_NAMES = {a: (f"grid.{a} lower bound", f"grid.{a} upper bound") for a in "xy"}
"""The names of the bounds in :meth:`Grid.from_bounds`'s messages (formed once)."""


@dataclass(frozen=True)
class Grid:
    """A rectangular grid of ``nx * ny`` elements of size ``dx * dy`` [m].

    Attributes
    ----------
    nx, ny
        Number of elements along x (rolling) and y (lateral).
    dx, dy
        Element size [m].
    x0, y0
        Centre of element (0, 0) [m].
    """

    nx: int
    ny: int
    dx: float
    dy: float
    x0: float
    y0: float

    def __post_init__(self) -> None:
        nx, ny, dx, dy, x0, y0 = self.nx, self.ny, self.dx, self.dy, self.x0, self.y0
        if (type(nx) is int and type(ny) is int and nx >= 1 and ny >= 1  # the common case
                and type(dx) is float and type(dy) is float and 0.0 < dx < math.inf
                and 0.0 < dy < math.inf and type(x0) is float and type(y0) is float
                and x0 - x0 == 0.0 and y0 - y0 == 0.0):  # (finite: x - x is 0, else NaN)
            return
        for name in ("nx", "ny"):
            n = getattr(self, name)
            if isinstance(n, bool) or int(n) != n or n < 1:
                raise RailContactError(f"grid.{name} must be a positive integer, got {n!r}")
        check_positive("grid.dx", self.dx, "m")
        check_positive("grid.dy", self.dy, "m")
        check_finite("grid.x0", self.x0, "m")
        check_finite("grid.y0", self.y0, "m")

    @classmethod
    def from_bounds(
        cls, xmin: float, xmax: float, ymin: float, ymax: float, nx: int, ny: int
    ) -> Grid:
        """Grid of ``nx * ny`` elements covering the rectangle [xmin, xmax] x [ymin, ymax] [m]."""
        for name, lo, hi in (("x", xmin, xmax), ("y", ymin, ymax)):
            check_finite(_BOUND_NAMES[name][0], lo, "m")
            check_finite(_BOUND_NAMES[name][1], hi, "m")
            if not hi > lo:
                raise RailContactError(f"grid.{name} range must be increasing, got [{lo}, {hi}]")
        dx = (xmax - xmin) / nx
        dy = (ymax - ymin) / ny
        return cls(int(nx), int(ny), dx, dy, xmin + dx / 2, ymin + dy / 2)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.nx, self.ny)

    @property
    def size(self) -> int:
        return self.nx * self.ny

    @property
    def element_area(self) -> float:
        """Area of one element dx * dy [m^2]."""
        return self.dx * self.dy

    @property
    def x(self) -> np.ndarray:
        """Element centres along x [m], shape (nx,); read-only (:func:`element_centres`)."""
        return element_centres(self.x0, self.dx, self.nx)

    @property
    def y(self) -> np.ndarray:
        """Element centres along y [m], shape (ny,); read-only (:func:`element_centres`)."""
        return element_centres(self.y0, self.dy, self.ny)

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """Element centres as two (nx, ny) arrays (x, y) [m]."""
        return np.meshgrid(self.x, self.y, indexing="ij")

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """Outer edges (xmin, xmax, ymin, ymax) [m]."""
        return (self.x0 - self.dx / 2, self.x0 + (self.nx - 0.5) * self.dx,
                self.y0 - self.dy / 2, self.y0 + (self.ny - 0.5) * self.dy)

    def same_elements(self, other: Grid) -> bool:
        """True when ``other`` has the same element count and size (so the same influence
        operator applies), whatever its position."""
        return (self.nx, self.ny) == (other.nx, other.ny) and np.isclose(
            self.dx, other.dx, rtol=1e-12) and np.isclose(self.dy, other.dy, rtol=1e-12)


def remesh(values: np.ndarray, source: Grid, target: Grid, conserve: bool = False,
           method: str = "linear") -> np.ndarray:
    """A field on ``source`` interpolated (bilinearly, zero outside) onto ``target``.

    ``method="nearest"`` takes the nearest source element instead (for maps of states).

    With ``conserve=True`` the result is scaled so that its integral (sum times element
    area) equals the source's, e.g. to keep the total force of a pressure estimate.

    ``values`` of shape ``(k, nx, ny)`` (e.g. a traction's two components) are ``k`` fields,
    remeshed each (without ``conserve``).
    """
    v = np.asarray(values, dtype=float)
    if v.ndim == 3 and v.shape[1:] == source.shape and not conserve:
        shift = (0, 0) if source is target else _lattice_shift(source, target)
        if shift is None:  # off the lattice: field by field
            return np.stack([remesh(c, source, target, method=method) for c in v])
        if shift == (0, 0) and source.shape == target.shape:
            return v.copy()
        return _shifted_copy(v, target.shape, *shift)
    if v.shape != source.shape:
        raise RailContactError(f"values must have the source grid's shape {source.shape}")
    shift = (0, 0) if source is target else _lattice_shift(source, target)
    if shift is not None:  # the same lattice: interpolation at element centres is a copy
        out = (v.copy() if shift == (0, 0) and v.shape == target.shape
               else _shifted_copy(v, target.shape, *shift))
        if conserve:
            total = out.sum() * target.element_area
            if total > 0:
                out *= v.sum() * source.element_area / total
        return out
    if method == "linear":  # (one compiled pass)
        out = _bilinear(np.ascontiguousarray(v), float(source.x0), float(source.dx),
                        float(source.y0), float(source.dy), target.nx, target.ny,
                        float(target.x0), float(target.dx), float(target.y0),
                        float(target.dy))
    else:
        from scipy.interpolate import RegularGridInterpolator  # (off the lattice only)

        # pad with a ring of zeros half an element outside, so the field falls to zero at
        # the edge of the source grid instead of stopping at its outer element centres
        x = np.concatenate([[source.x[0] - source.dx / 2], source.x,
                            [source.x[-1] + source.dx / 2]])
        y = np.concatenate([[source.y[0] - source.dy / 2], source.y,
                            [source.y[-1] + source.dy / 2]])
        interp = RegularGridInterpolator((x, y), np.pad(v, 1), method=method,
                                         bounds_error=False, fill_value=0.0)
        X, Y = target.mesh()
        out = interp(np.stack([X, Y], axis=-1))
    if conserve:
        total = out.sum() * target.element_area
        want = v.sum() * source.element_area
        if total > 0:
            out *= want / total
    return out


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def _bilinear(v, sx0, sdx, sy0, sdy, nx, ny, tx0, tdx, ty0, tdy):  # pragma: no cover
    """The field ``v`` (source grid: centres ``sx0 + i sdx``, ``sy0 + j sdy``) at the
    element centres of the target grid (``nx`` x ``ny``, ``tx0``, ``tdx``, ``ty0``,
    ``tdy``), bilinear between the source's centres and a ring of zeros half an element
    outside them (the field falls to zero at the source grid's edge), zero beyond it."""
    mx, my = v.shape
    out = np.zeros((nx, ny))
    ia = np.empty(ny, dtype=np.int64)  # per target column: the source columns' node
    fa = np.empty(ny)  # and the weight of the upper one (node -1, my: the zero ring)
    for b in range(ny):
        ia[b], fa[b] = _node(ty0 + b * tdy, sy0, sdy, my)
    for a in range(nx):
        i, fx = _node(tx0 + a * tdx, sx0, sdx, mx)
        if i < -1:
            continue
        for b in range(ny):
            j, fy = ia[b], fa[b]
            if j < -1:
                continue
            v00 = v[i, j] if i >= 0 and j >= 0 else 0.0
            v01 = v[i, j + 1] if i >= 0 and j + 1 < my else 0.0
            v10 = v[i + 1, j] if i + 1 < mx and j >= 0 else 0.0
            v11 = v[i + 1, j + 1] if i + 1 < mx and j + 1 < my else 0.0
            out[a, b] = ((1.0 - fx) * ((1.0 - fy) * v00 + fy * v01)
                         + fx * ((1.0 - fy) * v10 + fy * v11))
    return out


@numba.njit(cache=True, nogil=True)
def _node(t, s0, ds, m):  # pragma: no cover - compiled
    """The source node below the coordinate ``t`` [m] and the weight of the one above:
    nodes at the ``m`` centres ``s0 + k ds`` (k = 0 .. m - 1) and the zero ring at
    ``-1/2`` and ``m - 1/2`` elements (reported as nodes -1 and m - 1 with the weight
    over that half element); ``(-2, 0)`` outside the ring."""
    r = (t - s0) / ds
    if not (r >= -0.5 and r <= m - 0.5):
        return -2, 0.0
    if r < 0.0:  # between the ring and the first centre
        return -1, (r + 0.5) / 0.5
    if r >= m - 1:  # between the last centre and the ring
        return m - 1, (r - (m - 1)) / 0.5
    k = min(int(math.floor(r)), m - 2)
    return k, r - k


def _lattice_shift(source: Grid, target: Grid) -> tuple[int, int] | None:
    """Whole-element offset (i, j) of ``target``'s element (0, 0) in ``source``, when both
    grids have the same element size and their centres lie on one lattice; else None
    (:func:`lattice_offset`)."""
    i, j, ok = lattice_offset(source.dx, source.dy, source.x0, source.y0, target.dx,
                              target.dy, target.x0, target.y0)
    return (i, j) if ok else None


def lattice_offset(sdx: float, sdy: float, sx0: float, sy0: float, tdx: float, tdy: float,
                   tx0: float, ty0: float) -> tuple[int, int, bool]:
    """Whole-element offset ``(i, j, True)`` of the element (0, 0) of a target grid (element
    size ``tdx``, ``tdy``, centre of element (0, 0) at ``tx0``, ``ty0`` [m]) in a source
    grid (``sdx``, ``sdy``, ``sx0``, ``sy0``), when the element sizes agree to 1e-12
    (relative) and the centres lie on one lattice to 1e-9 of an element; else
    ``(0, 0, False)``. Plain scalars, compiled as well (:mod:`railcontact.timestep.
    warmstart`'s kernels read it there)."""
    if not ((sdx == tdx and sdy == tdy)  # (the common case; else math.isclose's test)
            or (abs(sdx - tdx) <= 1e-12 * max(abs(sdx), abs(tdx))
                and abs(sdy - tdy) <= 1e-12 * max(abs(sdy), abs(tdy)))):
        return 0, 0, False
    fi = (tx0 - sx0) / sdx
    fj = (ty0 - sy0) / sdy
    i, j = round(fi), round(fj)
    if abs(fi - i) > 1e-9 or abs(fj - j) > 1e-9:
        return 0, 0, False
    return int(i), int(j), True


def _shifted_copy(v: np.ndarray, shape: tuple[int, int], i: int, j: int) -> np.ndarray:
    """``out[..., a, b] = v[..., a + i, b + j]`` where that lies in ``v``, else 0 (of
    ``v``'s dtype)."""
    out = np.zeros((*v.shape[:-2], *shape), dtype=v.dtype)
    a0, a1 = max(0, -i), min(shape[0], v.shape[-2] - i)
    b0, b1 = max(0, -j), min(shape[1], v.shape[-1] - j)
    if a1 > a0 and b1 > b0:
        out[..., a0:a1, b0:b1] = v[..., a0 + i:a1 + i, b0 + j:b1 + j]
    return out


@numba.njit(cache=True, nogil=True)
def nonzero_box(field):  # pragma: no cover - compiled
    """The rows ``i0:i1`` and columns ``j0:j1`` (ends exclusive) of a field (nx, ny) that
    hold its elements ``!= 0`` (a contact mask's set elements, a pressure's loaded ones;
    NaN counts, as in ``ndarray.any``), in one pass; ``(-1, -1, -1, -1)`` without any."""
    nx, ny = field.shape
    i0 = i1 = j0 = j1 = -1
    for i in range(nx):
        for j in range(ny):
            if field[i, j] != 0:
                if i0 < 0:
                    i0 = i
                i1 = i + 1
                if j0 < 0 or j < j0:
                    j0 = j
                if j + 1 > j1:
                    j1 = j + 1
    return i0, i1, j0, j1


def box_edges(box: tuple[int, int, int, int], grid: Grid
              ) -> tuple[float, float, float, float] | None:
    """Outer edges (xmin, xmax, ymin, ymax) [m] of the elements in the rows ``i0:i1`` and
    columns ``j0:j1`` of ``grid`` (``box``, as :func:`nonzero_box` gives it: None when
    empty, ``i0 < 0``), e.g. of a normal solution's
    :attr:`~railcontact.normal.NormalResult.contact_box` (its pressure's elements ``> 0``:
    the same as ``!= 0`` for a solved pressure, which is not negative and finite)."""
    if box[0] < 0:
        return None
    i0, i1, j0, j1 = box
    return (grid.x0 + (i0 - 0.5) * grid.dx, grid.x0 + (i1 - 0.5) * grid.dx,
            grid.y0 + (j0 - 0.5) * grid.dy, grid.y0 + (j1 - 0.5) * grid.dy)


def widened(bounds: tuple[float, float, float, float], grid: Grid, elements: float,
            share: float) -> tuple[float, float, float, float]:
    """The area ``bounds`` (xmin, xmax, ymin, ymax) [m] widened on each side by
    ``elements`` elements of ``grid`` and ``share`` of its extent along that axis (the
    potential area around a known contact)."""
    x0, x1, y0, y1 = bounds
    mx = elements * grid.dx + share * (x1 - x0)
    my = elements * grid.dy + share * (y1 - y0)
    return (x0 - mx, x1 + mx, y0 - my, y1 + my)
