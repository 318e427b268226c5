"""Virtual-penetration estimates of the normal contact: Kik–Piotrowski and INFCON.

Both work on the gap ``h(x, s) = f(s) + A(s) x^2`` of a patch (``f`` the lateral gap with
minimum 0, ``A(s)`` the longitudinal curvature) and a normal penetration ``delta``, with
``s`` measured from the gap's minimum, the point of maximum interpenetration (samples given
in another frame, e.g. from CONTACT's reference point, are read from the zero of the gap
nearest their origin: :attr:`NormalEstimate.offset`). The patch is the region of
*virtual* interpenetration: strip ``s`` is in contact for ``|x| <= x_l(s)``, with the
pressure semi-elliptic along x,

    p(x, s) = c(s) sqrt(x_l(s)^2 - x^2),

on the strips (rows) of an estimate grid of ``(nx, ny)`` elements over the virtual patch
(Love's coefficients, as CONTACT does it); for a prescribed force the penetration is found
by a secant. The two differ in the outline ``x_l`` and the amplitude ``c``.

Kik–Piotrowski (Piotrowski & Kik, VSD 46:27-48, 2008): ``x_l(s)^2 = (eps delta - f(s)) /
A(s)`` with the virtual penetration factor ``eps = 0.55``, and one amplitude ``c`` for the
patch (the pressure along the strips' centres proportional to their half lengths), set so
that the elastic displacement at ``(0, 0)``, the point of maximum penetration, is
``delta``.

INFCON (An & Wang; the paper's Sec. 2.2.3, ``chi = n_e^2 B_e / (r_e (A + B_e))``). The
original definition of the "equivalent" quantities was not available; railcontact resolves
it as follows (``docs/algorithms.md`` 4.3 marks this as uncertain):

* ``B_e`` is the curvature of the parabola through the ends of the rigid interpenetration
  region ``{f(s) <= delta}`` (``B_e = delta / w^2``, ``w`` its half width);
* ``n_e, r_e`` are Hertz's coefficients (``docs/algorithms.md`` 1.2) for the curvatures
  ``(A, B_e)``, so ``chi = B_e b^2 / delta`` is Hertz's lateral virtual-penetration factor
  (chi = 1/2 for a circle, and ``A a^2 / delta = 1 - chi`` along x);
* each side of the patch (s < 0, s > 0) has its own lateral factor ``chi_-``, ``chi_+``,
  the same with ``B_e`` from that side's reach ``w_-``, ``w_+`` of the rigid overlap
  (``B_e = delta / w_-^2``: a gap that rises slowly on one side is in contact further out
  there, relative to its overlap, than on a steep side);
* the patch is KP's construction with ``delta_0 = chi_+- delta`` on each side and the
  longitudinal half-lengths Hertz's along the paper's ``a(y) = a_e sqrt(g(y) / (chi
  delta))``: ``x_l(s)^2 = (1-chi) delta / A(s) (1 - f(s) / (chi_+- delta))``, continuous at
  s = 0;
* the pressure is the paper's strip-like Boussinesq integral: one amplitude ``c_j`` per
  strip, from the strips' mutual influence, such that the elastic displacement at each
  strip's centre ``(0, s_j)`` equals the rigid interpenetration there, ``delta - f(s_j)``
  (``ny`` equations; a strip whose amplitude would be negative is left without pressure
  and the others solved again). Between the strips' centres ``c`` is interpolated
  linearly in ``s`` when the estimate is re-meshed onto the BEM grid.

With these choices INFCON reproduces Hertz for a quadratic gap (its pressure ``p0
sqrt(1 - x^2/a^2 - y^2/b^2)`` is one of the family, with ``c = p0 / a`` on every strip, and
displaces the line x = 0 by ``delta - B y^2``), and follows the actual lateral gap ``f(s)``
otherwise (non-elliptic patches, several patches): the pressure across the track comes
from the gap itself, not from the strips' lengths.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numba
import numpy as np

from ..errors import RailContactError, check_positive
from ..halfspace.ellipse import hertz_penetration, lateral_factor, shape_table
from ..halfspace.grid import Grid
from ..halfspace.hertz import hertz, semi_axes
from ..halfspace.influence import _zz_antiderivative, zz_displacement_centred
from ..halfspace.interp import interp_walk_sloped, slopes_of
from ..halfspace.materials import ElasticPair
from ..halfspace.sums import numpy_sum

KP_FACTOR = 0.55
METHODS = ("kp", "infcon")
SCALED_LOAD = 1e-3
"""INFCON's load secant stops when an evaluation carries the load within this share, and
its pressure is scaled to the load (the strips' equations then hold for the interpenetration
scaled by as much, the outline for a penetration 2/3 as much off; each further evaluation
solves them again): the share of the normal BEM's default tolerance ε_n, below which the
start's load error is lost in the BEM's own."""
START_PASSES = 3
"""Passes of INFCON's start of the load secant: Hertz's penetration for the curvature
``A(0)`` along and, across, the parabola's ``B_e = delta / w^2`` through the ends of the
rigid overlap at the penetration before (:func:`_equivalent_hertz`)."""
SEARCH_SAMPLES = 801
"""Points from one end of the virtual patch to the other at which its largest half
length is sought (the estimate grid's extent along x)."""


@dataclass
class NormalEstimate:
    """A simplified normal solution on its own grid (SI units).

    Attributes
    ----------
    grid
        Estimate grid (n_x, n_y) covering the virtual patch.
    pressure
        Pressure [Pa], (nx, ny).
    contact
        Contact mask.
    force, penetration, max_pressure, area
        As for the BEM [N, m, Pa, m^2].
    factor
        Virtual-penetration factor used (0.55 for KP, chi for INFCON).
    method, message, wall_time
    """

    grid: Grid
    pressure: np.ndarray
    contact: np.ndarray
    force: float
    penetration: float
    max_pressure: float
    area: float
    factor: float
    method: str
    message: str
    wall_time: float
    half_length: Callable[[np.ndarray], np.ndarray] = field(repr=False, default=None)
    offset: float = 0.0
    """The lateral coordinate [m] of the gap's minimum in the frame of the samples given,
    the model's ``s = 0`` (:func:`_offset`: 0 where the gap at the sample nearest ``s =
    0`` is 0). The grid, the pressure and the half lengths are in the samples' frame."""
    amplitude: np.ndarray = field(repr=False, default=None)
    """The pressure's amplitude [Pa/m] on each strip (row) of the estimate grid, (ny,):
    ``p(x, y_j) = amplitude[j] sqrt(x_l(y_j)^2 - x^2)`` (one value for all strips in
    KP; between the strips' centres it is interpolated linearly in y, beyond them held)."""
    shape_data: tuple | None = field(repr=False, default=None, compare=False)
    """(s, f, a_of_s, the slopes of f and a_of_s, d0, stretch) of :func:`_shape` (``d0``
    and ``stretch`` for the sides s < 0 and s >= 0), for the compiled evaluations."""

    def pressure_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The model's pressure [Pa] at any points (x, y) [m]: this is how the estimate is
        re-meshed onto the BEM grid (the estimate grid only fixes the amplitudes)."""
        y = np.asarray(y, dtype=float)
        xl = self.half_length(y)
        inside = (y >= self.grid.bounds[2]) & (y <= self.grid.bounds[3])
        c = np.interp(y, self.grid.y, self.amplitude)
        return np.where(inside, c * np.sqrt(np.clip(xl**2 - np.asarray(x) ** 2, 0, None)),
                        0.0)

    def pressure_on(self, grid: Grid) -> np.ndarray:
        """:meth:`pressure_at` the element centres of ``grid`` [Pa], (nx, ny): the same
        values, in one compiled pass (each row's half length formed once)."""
        if self.shape_data is None:
            return self.pressure_at(*grid.mesh())
        _, _, ylo, yhi = self.grid.bounds
        o = self.offset  # (the compiled pass in the model's frame)
        ys = self.grid.y - o
        return _pressure_on(grid.x, grid.y - o, *self.shape_data, ylo - o, yhi - o, ys,
                            self.amplitude, slopes_of(ys, self.amplitude))


_UNIT_PAIR = ElasticPair(shear=1.0, poisson=0.0)


def infcon_factor(A: float, B_e: float) -> float:
    """chi = n^2 B_e / (r (A + B_e)) = B_e b^2 / delta from Hertz for curvatures (A, B_e).

    Hertz's semi-axes at a unit penetration (G = 1, nu = 0;
    :func:`~railcontact.halfspace.hertz.semi_axes`, the same value as
    :func:`~railcontact.halfspace.hertz.hertz` without forming its solution record: the
    load secant asks for it at every step)."""
    A = check_positive("A", A, "1/m")
    B_e = check_positive("B_e", B_e, "1/m")
    _, b, _, _ = semi_axes(A, B_e, _UNIT_PAIR.e_star, penetration=1.0)
    return B_e * b**2  # (over the unit penetration)


def _half_width(s: np.ndarray, f: np.ndarray, level: float) -> tuple[float, float]:
    """Ends (lo, hi) of the connected region around s = 0 where f <= level (interpolated)."""
    return _half_width_at(s, f, float(level))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _half_width_at(s, f, level):  # pragma: no cover - compiled
    """:func:`_half_width`: the run of samples ``f <= level`` (NaN: not) through the
    sample nearest s = 0 (``np.argmin(abs(s))``: the first such, or the first NaN),
    widened at each end to where the gap crosses ``level`` on the piece beyond (the end
    sample itself where that is outside the arrays or its gap is not finite)."""
    n = s.size
    k0 = 0
    best = abs(s[0])
    if not math.isnan(best):
        for k in range(1, n):
            v = abs(s[k])
            if math.isnan(v):
                k0 = k
                break
            if v < best:
                best, k0 = v, k
    lo = k0
    while lo > 0 and f[lo - 1] <= level:
        lo -= 1
    hi = k0
    while hi < n - 1 and f[hi + 1] <= level:
        hi += 1
    ends = np.empty(2)
    for e, (i_in, i_out) in enumerate(((lo, lo - 1), (hi, hi + 1))):
        if i_out < 0 or i_out >= n or not math.isfinite(f[i_out]):
            ends[e] = s[i_in]
        else:
            t = (level - f[i_in]) / (f[i_out] - f[i_in])
            ends[e] = s[i_in] + t * (s[i_out] - s[i_in])
    return ends[0], ends[1]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _squared_half_length(y, s, f, a_of_s, sf, sa, d0, stretch, j
                         ):  # pragma: no cover - compiled
    """The square of the virtual patch's half length [m^2] at ``y`` (of :func:`_shape`'s
    ``x_half``: ``max(stretch[k] (d0[k] - f(y)) / A(y), 0)`` with ``k`` 0 for y < 0 and 1
    else, NaN kept; ``sf``, ``sa`` the slopes of ``f`` and ``A``) and the piece of ``s``
    it is on."""
    fy, j = interp_walk_sloped(y, s, f, sf, j)
    ay, _ = interp_walk_sloped(y, s, a_of_s, sa, j)
    k = 0 if y < 0.0 else 1
    v = stretch[k] * (d0[k] - fy) / ay
    if not v > 0.0 and not math.isnan(v):
        v = 0.0
    return v, j


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _pressure_on(x, y, s, f, a_of_s, sf, sa, d0, stretch, ylo, yhi, ys, amplitude, slopes
                 ):  # pragma: no cover - compiled
    """:meth:`NormalEstimate.pressure_at` the points ``(x[i], y[j])`` [Pa], (nx, ny) (the
    strips' amplitudes ``amplitude`` at their centres ``ys``, with their ``slopes``)."""
    out = np.zeros((x.size, y.size))
    j_s = -1
    j_c = -1
    for j in range(y.size):
        c, j_c = interp_walk_sloped(y[j], ys, amplitude, slopes, j_c)
        xl, j_s = _squared_half_length(y[j], s, f, a_of_s, sf, sa, d0, stretch, j_s)
        xl = math.sqrt(xl)
        if not (y[j] >= ylo and y[j] <= yhi):
            continue
        xl2 = xl * xl
        for i in range(x.size):
            v = xl2 - x[i] * x[i]
            if not v > 0.0 and not math.isnan(v):
                v = 0.0
            out[i, j] = c * math.sqrt(v)
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _strip_influence(shape, dx, dy):  # pragma: no cover - compiled
    """The strips' mutual influence ``C`` (ny, ny) [m per (Pa/m)] without the factor
    ``(1-nu)/(pi G)``: ``C[j, k]`` is the normal displacement at the centre ``(0, y_j)``
    of strip ``j`` of the pressure ``shape[:, k]`` on strip ``k`` alone (Love's
    coefficients of the zz block, :func:`~railcontact.halfspace.influence.coefficients_at`,
    on a grid of ``shape.shape`` elements ``dx * dy`` [m] centred on x = 0).

    The corner antiderivative is formed once per x edge and row offset (the corners the
    elements share), the coefficients once per column and row offset, then summed over
    each strip's elements."""
    nx, ny = shape.shape
    half = 0.5 * nx
    # F at x = -(edge e), e = 0 .. nx, and y = (t - ny + 1/2) dy, t = 0 .. 2 ny - 1; F is
    # odd in each argument: formed for x >= 0 and y > 0 (a quarter), the rest by sign
    corner = np.empty((nx + 1, 2 * ny))
    for e in range(nx // 2 + 1):
        a = (half - e) * dx
        for t in range(ny, 2 * ny):
            v = _zz_antiderivative(a, (t - ny + 0.5) * dy)
            corner[e, t] = v
            corner[e, 2 * ny - 1 - t] = -v
            corner[nx - e, t] = -v
            corner[nx - e, 2 * ny - 1 - t] = v
    # the coefficient of column i at the row offset d = j - k: coef[i, d + ny - 1]
    coef = np.empty((nx, 2 * ny - 1))
    for i in range(nx):
        for d in range(-(ny - 1), ny):
            t = d + ny
            coef[i, d + ny - 1] = (corner[i, t] - corner[i, t - 1] - corner[i + 1, t]
                                   + corner[i + 1, t - 1])
    # the columns i and nx - 1 - i have the same coefficients (the zz block is even in
    # x): each pair's shapes added and summed once
    out = np.empty((ny, ny))
    column = np.empty(ny)
    for k in range(ny):
        column[:] = 0.0
        for i in range((nx + 1) // 2):
            mirror = nx - 1 - i
            w = shape[i, k] + shape[mirror, k] if mirror != i else shape[i, k]
            if w != 0.0:  # (a slice: a loop on its plain index runs vectorised)
                c = coef[i, ny - 1 - k:2 * ny - 1 - k]
                for j in range(ny):
                    column[j] += w * c[j]
        for j in range(ny):
            out[j, k] = column[j]
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _solved(a, b):  # pragma: no cover - compiled
    """``x`` with ``a x = b`` (Gaussian elimination with partial pivoting, in place on
    ``a`` and ``b``; a zero pivot gives a non-finite ``x``): the strips' few dozen
    equations without a LAPACK call, whose threads on a loaded machine cost more than the
    elimination."""
    n = b.size
    for k in range(n):
        piv = k
        big = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > big:
                big, piv = abs(a[i, k]), i
        if piv != k:
            for j in range(n):
                a[k, j], a[piv, j] = a[piv, j], a[k, j]
            b[k], b[piv] = b[piv], b[k]
        d = a[k, k]
        pivot_row = a[k, k + 1:]
        for i in range(k + 1, n):
            m = a[i, k] / d
            if m != 0.0:
                row = a[i, k + 1:]  # (slices: the loop on their plain index vectorised)
                for j in range(n - k - 1):
                    row[j] -= m * pivot_row[j]
                b[i] -= m * b[k]
    x = np.empty(n)
    for k in range(n - 1, -1, -1):
        v = b[k]
        for j in range(k + 1, n):
            v -= a[k, j] * x[j]
        x[k] = v / a[k, k]
    return x


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _strip_amplitudes(influence, rhs):  # pragma: no cover - compiled
    """The strips' amplitudes ``c`` (ny) that solve the strip-wise Boussinesq equations
    ``influence[j] . c = rhs[j]`` on the strips that carry pressure, ``c >= 0``: strips
    whose shape is empty (a zero column) take no part; a strip whose amplitude comes out
    negative is set to zero and the rest solved again (at most ny times). Returns ``c``
    and whether each strip is in the final set (bool, ny)."""
    ny = rhs.size
    active = _nonzero_columns(influence)
    c = np.zeros(ny)
    for _ in range(ny):
        idx = np.flatnonzero(active)
        m = idx.size
        if m == 0:
            break
        sub = np.empty((m, m))
        b = np.empty(m)
        for a in range(m):
            b[a] = rhs[idx[a]]
            for q in range(m):
                sub[a, q] = influence[idx[a], idx[q]]
        x = _solved(sub, b)
        negative = False
        for a in range(m):
            if not x[a] >= 0.0:
                active[idx[a]] = False
                negative = True
        if not negative:
            c[:] = 0.0
            for a in range(m):
                c[idx[a]] = x[a]
            break
    return c, active


@numba.njit(cache=True, nogil=True)
def _nonzero_columns(a):  # pragma: no cover - compiled
    """Whether each column of the 2-D array ``a`` holds a nonzero value (bool, a.shape[1])."""
    out = np.zeros(a.shape[1], dtype=numba.boolean)
    for k in range(a.shape[1]):
        for j in range(a.shape[0]):
            if a[j, k] != 0.0:
                out[k] = True
                break
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _hold_into_empty(shape, amplitudes):  # pragma: no cover - compiled
    """Give each strip whose shape is empty (``x_l`` within half an element of 0: no
    element centre inside) the amplitude of the nearest strip that has one (the lower on
    a tie), in place: on a finer grid such a strip's rows do carry pressure."""
    nx, ny = shape.shape
    full = _nonzero_columns(shape)
    source = amplitudes.copy()
    for j in range(ny):
        if full[j]:
            continue
        for step in range(1, ny):
            if j - step >= 0 and full[j - step]:
                amplitudes[j] = source[j - step]
                break
            if j + step < ny and full[j + step]:
                amplitudes[j] = source[j + step]
                break


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _virtual_patch(s, f, a_of_s, sf, sa, d0, stretch, delta, scale, nx, ny, strips
                   ):  # pragma: no cover - compiled
    """The virtual patch of :func:`_shape`'s ``d0``, ``stretch`` (per side; at the
    penetration ``delta`` [m]; ``sf``, ``sa`` the slopes of ``f`` and ``a_of_s``): its
    lateral ends ``lo``, ``hi`` [m] (:func:`_half_width` at ``d0[0]``, ``d0[1]``), its
    largest half length ``xmax``
    [m] at :data:`SEARCH_SAMPLES` points ``np.linspace(lo, hi)`` (NaN if one is NaN) and,
    when ``xmax > 0`` (and the ends are finite), on the estimate grid
    ``Grid.from_bounds(-xmax, xmax, lo, hi, nx, ny)``: the pressure [Pa], the semi-elliptic
    shape ``sqrt(x_l(y)^2 - x^2)`` times an amplitude [Pa/m] per strip (row), the
    amplitudes (ny), the force [N] (numpy's sum times the element area), the largest
    pressure [Pa] and the count of elements in contact.

    One amplitude for all strips (``strips`` False, Kik–Piotrowski): the displacement at
    (0, 0) is ``delta`` (``amplitude = delta / u``, ``u`` the shape's displacement,
    :func:`zz_displacement_centred` times ``scale = (1-nu)/(pi G)``). One per strip
    (``strips`` True, INFCON's strip-wise Boussinesq integral): the displacement at each
    strip's centre ``(0, y_j)`` is the rigid interpenetration there, ``delta - f(y_j)``
    (:func:`_strip_influence`, :func:`_strip_amplitudes`)."""
    lo, _ = _half_width_at(s, f, d0[0])
    _, hi = _half_width_at(s, f, d0[1])
    num = SEARCH_SAMPLES
    div = num - 1
    step = (hi - lo) / div
    xmax = -math.inf  # (the largest square: the root of the largest is the largest root)
    n = s.size
    j = 0
    for k in range(num):  # np.linspace's points
        if k == div:
            yk = hi
        elif step == 0.0:
            yk = (k / div) * (hi - lo) + lo
        else:
            yk = k * step + lo
        # the common case written out (the points increase: the piece found by walking
        # on); a point on a sample, beyond the samples or a NaN as np.interp has it
        v = math.nan
        inner = yk >= s[0] and yk <= s[n - 1]
        if inner:
            while j + 1 < n and s[j + 1] <= yk:
                j += 1
            inner = j < n - 1 and s[j] != yk
        if inner:
            fy = sf[j] * (yk - s[j]) + f[j]
            ay = sa[j] * (yk - s[j]) + a_of_s[j]
            inner = not (math.isnan(fy) or math.isnan(ay))
            k = 0 if yk < 0.0 else 1
            v = stretch[k] * (d0[k] - fy) / ay
            if not v > 0.0 and not math.isnan(v):
                v = 0.0
        if not inner:
            v, _ = _squared_half_length(yk, s, f, a_of_s, sf, sa, d0, stretch, -1)
        if math.isnan(v):
            xmax = v
            break
        xmax = max(xmax, v)
    xmax = math.sqrt(xmax)
    shape = np.zeros((nx, ny))
    amplitudes = np.zeros(ny)
    if not (xmax > 0.0 and hi > lo and xmax < math.inf and math.isfinite(lo)
            and math.isfinite(hi)):
        return lo, hi, xmax, shape, amplitudes, 0.0, 0.0, 0
    xmin = -xmax
    dx = (xmax - xmin) / nx
    dy = (hi - lo) / ny
    x0 = xmin + dx / 2
    y0 = lo + dy / 2
    j_s = -1
    for j in range(ny):
        xl, j_s = _squared_half_length(y0 + dy * float(j), s, f, a_of_s, sf, sa, d0,
                                       stretch, j_s)
        xl = math.sqrt(xl)
        xl2 = xl * xl
        for i in range(nx):
            xi = x0 + dx * float(i)
            v = xl2 - xi * xi
            if not v > 0.0 and not math.isnan(v):
                v = 0.0
            shape[i, j] = math.sqrt(v)
    if strips:
        rhs = np.empty(ny)
        j_s = -1
        for j in range(ny):
            fy, j_s = interp_walk_sloped(y0 + dy * float(j), s, f, sf, j_s)
            rhs[j] = (delta - fy) / scale
        amplitudes, _ = _strip_amplitudes(_strip_influence(shape, dx, dy), rhs)
        _hold_into_empty(shape, amplitudes)
    else:
        u = zz_displacement_centred(0.0, dx, lo, dy, shape) * scale
        amplitudes[:] = delta / u
    p = shape  # (in place: the pressure)
    count = 0
    for i in range(nx):
        for j in range(ny):
            p[i, j] = shape[i, j] * amplitudes[j]
            if p[i, j] > 0.0:
                count += 1
    return lo, hi, xmax, p, amplitudes, numpy_sum(p) * (dx * dy), p.max(), count


def _shape(method: str, samples: tuple, a0: float, delta: float
           ) -> tuple[float, np.ndarray, np.ndarray]:
    """The virtual-penetration factor, and the virtual penetrations [m] and stretches of
    the half lengths on the two sides (s < 0, s >= 0) at the penetration ``delta`` [m]
    (KP: 0.55, 0.55 delta and 1 on both; INFCON: see the module doc, in one compiled
    pass, :func:`_infcon_shape`; where that gives no factor, the same with
    :func:`infcon_factor`, which raises or searches beyond the compiled table)."""
    if method == "kp":
        return KP_FACTOR, np.full(2, KP_FACTOR * delta), np.ones(2)
    factor, d0, stretch = _infcon_shape(samples[0], samples[1], a0, delta, *shape_table())
    if factor == factor:  # (not NaN)
        return factor, d0, stretch
    lo, hi = _half_width_at(samples[0], samples[1], delta)
    w = 0.5 * (hi - lo)
    if not w > 0:  # (it raised the same error for B_e = inf, with a numpy warning)
        raise RailContactError(f"INFCON estimate: the undeformed gap has no width at "
                               f"penetration {delta:g} m")
    factor = infcon_factor(a0, delta / w**2)
    if lo < 0 < hi:
        sides = np.array([infcon_factor(a0, delta / lo**2), infcon_factor(a0, delta / hi**2)])
    else:
        sides = np.full(2, factor)
    d0 = sides * delta
    return factor, d0, (1 - factor) * delta / d0


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _infcon_shape(s, f, a0, delta, v_nodes, w_nodes, slopes):  # pragma: no cover - compiled
    """INFCON's :func:`_shape` (factor, d0, stretch) with the compiled
    :func:`~railcontact.halfspace.ellipse.lateral_factor` (the table of
    :func:`~railcontact.halfspace.ellipse.shape_table`); the factor NaN where the rigid
    overlap has no width or a factor is not found."""
    lo, hi = _half_width_at(s, f, delta)
    w = 0.5 * (hi - lo)
    d0 = np.empty(2)
    stretch = np.empty(2)
    if not w > 0.0:
        return math.nan, d0, stretch
    factor = lateral_factor(a0, delta / (w * w), v_nodes, w_nodes, slopes)
    if lo < 0.0 < hi:
        d0[0] = lateral_factor(a0, delta / (lo * lo), v_nodes, w_nodes, slopes)
        d0[1] = lateral_factor(a0, delta / (hi * hi), v_nodes, w_nodes, slopes)
    else:
        d0[0] = factor
        d0[1] = factor
    if math.isnan(d0[0]) or math.isnan(d0[1]):
        factor = math.nan
    for k in range(2):
        d0[k] *= delta
        stretch[k] = (1.0 - factor) * delta / d0[k]
    return factor, d0, stretch


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _equivalent_hertz(s, f, a0, e_star, load, delta, passes, v_nodes, w_nodes, slopes
                      ):  # pragma: no cover - compiled
    """Hertz's penetration [m] under ``load`` [N] for the curvatures ``a0`` along and
    ``B_e = delta / w^2`` across (``w`` the half width of the rigid overlap ``f <=
    delta``, :func:`_half_width_at`; the curvatures of INFCON's factor), ``passes`` times
    from the penetration ``delta`` [m] (the last finite one where the overlap has no
    width or Hertz no solution): the penetration at which INFCON, exact for a quadratic
    gap, carries about the load (its load secant's start)."""
    for _ in range(passes):
        lo, hi = _half_width_at(s, f, delta)
        w = 0.5 * (hi - lo)
        if not w > 0.0:
            break
        d = hertz_penetration(a0, delta / (w * w), e_star, load, v_nodes, w_nodes, slopes)
        if not (d > 0.0 and d < math.inf):
            break
        delta = d
    return delta


def _evaluate(method: str, samples: tuple, a0: float, delta: float, scale: float, nx: int,
              ny: int) -> tuple:
    """The virtual patch at the penetration ``delta`` [m] (``samples`` = (s, f, a_of_s and
    the slopes of f and a_of_s), ``a0 = A(0)`` [1/m], ``scale = (1-nu)/(pi G)`` [m/Pa /
    m]): factor, d0, stretch and :func:`_virtual_patch`'s values, checked."""
    factor, d0, stretch = _shape(method, samples, a0, delta)
    out = _virtual_patch(*samples, d0, stretch, delta, scale, nx, ny, method == "infcon")
    lo, hi, xmax = out[:3]
    if not xmax > 0 or hi <= lo:
        raise RailContactError(f"{method}: no virtual interpenetration for delta = {delta:g} m")
    if not (xmax < math.inf and math.isfinite(lo) and math.isfinite(hi)):
        Grid.from_bounds(-xmax, xmax, lo, hi, nx, ny)  # (raises: not finite)
    if not out[5] > 0:  # (no strip with a positive amplitude)
        raise RailContactError(f"{method}: no pressure on the virtual patch for delta = "
                               f"{delta:g} m")
    return (factor, d0, stretch, *out)


def _scaled(evaluation: tuple, ratio: float) -> tuple:
    """An :func:`_evaluate` with its pressure, amplitudes, force and largest pressure
    multiplied by ``ratio``."""
    out = list(evaluation)
    for k in (6, 7, 8, 9):  # pressure, amplitudes, force, largest pressure
        out[k] = out[k] * ratio
    return tuple(out)


def _estimate(method: str, samples: tuple, delta: float, evaluation: tuple, nx: int, ny: int,
              t0: float, offset: float = 0.0) -> NormalEstimate:
    """The :class:`NormalEstimate` of an :func:`_evaluate` at ``delta`` [m] (``samples`` in
    the model's frame, ``offset`` [m] its origin in the samples' frame)."""
    factor, d0, stretch, lo, hi, xmax, p, amplitude, force, pmax, count = evaluation
    s, f, a_of_s = samples[:3]

    def x_half(sv):
        sv = np.asarray(sv) - offset
        k = (sv >= 0).astype(int)
        g = d0[k] - np.interp(sv, s, f)
        return np.sqrt(np.clip(stretch[k] * g / np.interp(sv, s, a_of_s), 0, None))

    grid = Grid.from_bounds(-xmax, xmax, lo + offset, hi + offset, nx, ny)
    return NormalEstimate(grid=grid, pressure=p, contact=p > 0, force=float(force),
                          penetration=delta, max_pressure=float(pmax),
                          area=float(count * grid.element_area), factor=factor,
                          method=method, message=f"{method}: factor {factor:.4f}",
                          wall_time=time.perf_counter() - t0, half_length=x_half,
                          amplitude=amplitude, shape_data=(*samples, d0, stretch),
                          offset=offset)


def _offset(s: np.ndarray, f: np.ndarray) -> float:
    """Where [m] the virtual patch is centred: the patch's smallest gap, the sample nearest
    ``s = 0`` whose gap is 0 or less (the lower ``s`` of two as near; 0 where the sample
    nearest ``s = 0`` is one, or none is). The samples of a patch solved in the frame at
    CONTACT's reference point (the weighted centre of its own run of interpenetration) have
    their gap shifted to 0 at the run's lowest sample, which need not be at ``s = 0``;
    those of one of several patches may be below 0 in another patch's run, further out."""
    k = _nearest_floor(f, int(np.argmin(np.abs(s))))
    return float(s[k]) if k >= 0 else 0.0


@numba.njit(cache=True, nogil=True)
def _nearest_floor(f, k0):  # pragma: no cover - compiled
    """The index nearest ``k0`` with ``f <= 0`` (the lower of two as near); -1 where it is
    ``k0`` itself or there is none."""
    if f[k0] <= 0.0:
        return -1
    for step in range(1, f.size):
        if k0 - step >= 0 and f[k0 - step] <= 0.0:
            return k0 - step
        if k0 + step < f.size and f[k0 + step] <= 0.0:
            return k0 + step
        if k0 - step < 0 and k0 + step >= f.size:
            break
    return -1


def virtual_penetration(method: str, s: np.ndarray, f: np.ndarray, a_of_s: np.ndarray,
                        pair: ElasticPair, *, penetration: float | None = None,
                        load: float | None = None, nx: int = 40, ny: int = 40
                        ) -> NormalEstimate:
    """Kik–Piotrowski (``"kp"``) or INFCON (``"infcon"``) estimate of one patch.

    Parameters
    ----------
    method
        "kp" or "infcon".
    s, f, a_of_s
        Lateral coordinate [m] (increasing), lateral gap f(s) [m] (minimum 0) and
        longitudinal curvature A(s) [1/m] of the patch; the model is centred on the
        gap's zero nearest ``s = 0`` (:attr:`NormalEstimate.offset`), its grid and
        pressure are in the frame of ``s``.
    pair
        Combined elastic parameters.
    penetration, load
        Normal penetration [m] or normal force [N] (one of them).
    nx, ny
        Estimate grid (the paper's (n_x, n_y)).
    """
    t0 = time.perf_counter()
    if method not in METHODS:
        raise RailContactError(f"method must be one of {METHODS}, got {method!r}")
    # (own writable copies: a read-only input would compile the kernels a second time)
    s, f, a_of_s = (np.array(v, dtype=float, order="C") for v in (s, f, a_of_s))
    if s.ndim != 1 or s.size < 2 or f.shape != s.shape or a_of_s.shape != s.shape:
        raise RailContactError(f"s, f and a_of_s must be 1-D samples of one length (2 or "
                               f"more), got shapes {s.shape}, {f.shape}, {a_of_s.shape}")
    if (penetration is None) == (load is None):
        raise RailContactError("give exactly one of load [N] and penetration [m]")
    for name, n in (("nx", nx), ("ny", ny)):  # (the compiled patch is formed before its grid)
        if isinstance(n, bool) or not (float(n).is_integer() and n >= 1):
            raise RailContactError(f"estimate grid {name} must be a positive integer, got {n!r}")
    nx, ny = int(nx), int(ny)
    offset = _offset(s, f)
    if offset != 0.0:  # (the model's frame: s from the gap's minimum)
        s = s - offset
    samples = (s, f, a_of_s, slopes_of(s, f), slopes_of(s, a_of_s))
    a0 = float(np.interp(0.0, s, a_of_s))
    scale = (1 - pair.poisson) / (math.pi * pair.shear)
    if penetration is not None:
        delta = check_positive("penetration", penetration, "m")
        return _estimate(method, samples, delta,
                         _evaluate(method, samples, a0, delta, scale, nx, ny), nx, ny, t0,
                         offset)
    load = check_positive("load", load, "N")
    # secant on delta, started from Hertz with the curvatures at s = 0 (each step's
    # patch evaluated; the estimate formed of the last)
    force = 8  # (the place of the force in an evaluation)
    k0 = int(np.argmin(np.abs(s)))
    k = min(k0 + 5, len(s) - 1) if k0 + 1 < len(s) else max(k0 - 5, 0)
    b0 = max(float(f[k] / s[k] ** 2), 1e-9) if s[k] != 0 else 1.0
    if method == "infcon":  # (KP's secant starts as it did)
        table = shape_table()
        d1 = hertz_penetration(a0, b0, pair.e_star, load, *table)  # (compiled: NaN where
        if not d1 > 0:  # hertz() raises or searches beyond the table)
            d1 = hertz(a0, b0, pair, load=load).penetration
        d1 = _equivalent_hertz(s, f, a0, pair.e_star, load, d1, START_PASSES, *table)
    else:
        d1 = hertz(a0, b0, pair, load=load).penetration
    e1 = _evaluate(method, samples, a0, d1, scale, nx, ny)
    d2 = d1 * (load / e1[force]) ** (2 / 3)
    for _ in range(30):
        e2 = _evaluate(method, samples, a0, d2, scale, nx, ny)
        if abs(e2[force] - load) < 1e-6 * load:
            break
        if method == "infcon" and abs(e2[force] - load) < SCALED_LOAD * load:
            e2 = _scaled(e2, load / e2[force])
            break
        # secant in log-log (force ~ delta^(3/2))
        slope = (math.log(e2[force]) - math.log(e1[force])) / (math.log(d2) - math.log(d1)) \
            if e2[force] != e1[force] and d2 != d1 else 1.5
        d1, e1 = d2, e2
        d2 = d2 * (load / e2[force]) ** (1 / max(slope, 0.5))
    else:  # not met in 30 steps: the last evaluation (the step after it not evaluated)
        d2 = d1
    return _estimate(method, samples, d2, e2, nx, ny, t0, offset)
