"""Love's influence coefficients of a half-space for uniform traction on rectangles.

A unit traction on the element centred at the origin, of size ``dx * dy``, displaces the
surface point (X, Y). The coefficients are the combined displacement *differences* of the
two bodies (Kalker's convention) with the combined parameters G, nu, K of
:class:`railcontact.halfspace.materials.ElasticPair`. With the corner operator::

    [[F]] = F(X+dx/2, Y+dy/2) - F(X+dx/2, Y-dy/2) - F(X-dx/2, Y+dy/2) + F(X-dx/2, Y-dy/2)

(``F`` an antiderivative with ``d2F/dXdY`` equal to the point-load kernel):

=====  =======================================================  ==================================
block  value                                                    point-load kernel
=====  =======================================================  ==================================
zz     ``(1-nu)/(pi G) [[X asinh(Y/|X|) + Y asinh(X/|Y|)]]``    ``(1-nu)/(pi G r)``
xx     ``1/(pi G) [[(1-nu) X asinh(Y/|X|) + Y asinh(X/|Y|)]]``  ``((1-nu)/r + nu X^2/r^3)/(pi G)``
yy     ``1/(pi G) [[(1-nu) Y asinh(X/|Y|) + X asinh(Y/|X|)]]``  ``((1-nu)/r + nu Y^2/r^3)/(pi G)``
xy     ``nu/(pi G) [[-r]]``                                     ``nu X Y / (pi G r^3)``
xz     ``-K/(pi G) [[Y ln r + X atan(Y/X)]]``                   ``-K X / (pi G r^2)``
yz     ``-K/(pi G) [[X ln r + Y atan(X/Y)]]``                   ``-K Y / (pi G r^2)``
=====  =======================================================  ==================================

and ``yx = xy``, ``zx = -xz``, ``zy = -yz``. (``X ln(Y + r)`` is written as
``X asinh(Y/|X|)``: the two differ by ``X ln|X|``, which the corner operator cancels, and
the asinh form has no 0 * log(0).) Source: Kalker (1990) and CONTACT
``m_visc.f90:elascf_pcwcns``; see ``docs/algorithms.md`` Sec. 5.1.

All functions return arrays over the element offsets ``(i dx, j dy)`` with
``i = -(nx-1) .. nx-1`` and ``j = -(ny-1) .. ny-1``, shape ``(2 nx - 1, 2 ny - 1)``,
in units of m/Pa (displacement per unit traction).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .materials import ElasticPair

BLOCKS = ("zz", "xx", "yy", "xy", "yx", "xz", "yz", "zx", "zy")


def _xash(X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """X asinh(Y/|X|), with the limit 0 at X = 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        out = X * np.arcsinh(Y / np.abs(X))
    return np.where(X == 0.0, 0.0, out)


def _xatan(X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """X atan(Y/X), with the limit 0 at X = 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        out = X * np.arctan(Y / X)
    return np.where(X == 0.0, 0.0, out)


def _yln_r(X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Y ln r, with the limit 0 at r = 0."""
    r2 = X * X + Y * Y
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 0.5 * Y * np.log(r2)
    return np.where(r2 == 0.0, 0.0, out)


def _corners(F, X: np.ndarray, Y: np.ndarray, dx: float, dy: float) -> np.ndarray:
    hx, hy = dx / 2, dy / 2
    return F(X + hx, Y + hy) - F(X + hx, Y - hy) - F(X - hx, Y + hy) + F(X - hx, Y - hy)


def offsets(nx: int, ny: int, dx: float, dy: float) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (X, Y) [m] of all element pairs, each of shape (2 nx - 1, 2 ny - 1)."""
    return np.meshgrid(dx * np.arange(-(nx - 1), nx), dy * np.arange(-(ny - 1), ny), indexing="ij")


def coefficients_at(
    block: str, X: np.ndarray, Y: np.ndarray, dx: float, dy: float, pair: ElasticPair
) -> np.ndarray:
    """Influence coefficient ``block`` at observation points (X, Y) [m] relative to the
    centre of a ``dx * dy`` element [m], for unit traction [m/Pa]."""
    X = np.asarray(X, dtype=float)
    Y = np.asarray(Y, dtype=float)
    g, nu, k = pair.shear, pair.poisson, pair.difference
    c = 1.0 / (np.pi * g)
    if block == "zz":
        return c * (1 - nu) * _corners(lambda a, b: _xash(a, b) + _xash(b, a), X, Y, dx, dy)
    if block == "xx":
        return c * _corners(lambda a, b: (1 - nu) * _xash(a, b) + _xash(b, a), X, Y, dx, dy)
    if block == "yy":
        return c * _corners(lambda a, b: (1 - nu) * _xash(b, a) + _xash(a, b), X, Y, dx, dy)
    if block in ("xy", "yx"):
        return c * nu * _corners(lambda a, b: -np.hypot(a, b), X, Y, dx, dy)
    if block in ("xz", "zx"):
        if k == 0.0:
            return np.zeros(np.broadcast(X, Y).shape)
        val = -c * k * _corners(lambda a, b: _yln_r(a, b) + _xatan(a, b), X, Y, dx, dy)
        return val if block == "xz" else -val
    if block in ("yz", "zy"):
        if k == 0.0:
            return np.zeros(np.broadcast(X, Y).shape)
        val = -c * k * _corners(lambda a, b: _yln_r(b, a) + _xatan(b, a), X, Y, dx, dy)
        return val if block == "yz" else -val
    raise ValueError(f"unknown influence block {block!r}; choose from {BLOCKS}")


def influence_kernel(
    block: str, nx: int, ny: int, dx: float, dy: float, pair: ElasticPair
) -> np.ndarray:
    """Coefficients of ``block`` at all element offsets, shape (2 nx - 1, 2 ny - 1) [m/Pa].

    Element ``[i + nx - 1, j + ny - 1]`` is the displacement at an element centre due to
    unit traction on the element ``i`` steps behind in x and ``j`` steps in y.
    """
    X, Y = offsets(nx, ny, dx, dy)
    return coefficients_at(block, X, Y, dx, dy, pair)


@numba.njit(cache=True, nogil=True)
def _zz_antiderivative(a, b):  # pragma: no cover - compiled
    """``a asinh(b/|a|) + b asinh(a/|b|)`` (0 where ``a`` or ``b`` is 0): the zz block's
    ``F`` without ``(1-nu)/(pi G)``, as ``sign(a b) (|a| ln((|b| + r)/|a|) + |b| ln((|a| +
    r)/|b|))`` with ``r = hypot(a, b)`` (``asinh(t) = ln(t + sqrt(1 + t^2))``: the same
    within round-off, two logarithms and a root for two inverse sines)."""
    if a == 0.0 or b == 0.0:
        return 0.0
    aa = abs(a)
    ab = abs(b)
    r = math.sqrt(aa * aa + ab * ab)
    out = aa * math.log((ab + r) / aa) + ab * math.log((aa + r) / ab)
    return out if (a > 0.0) == (b > 0.0) else -out


@numba.njit(cache=True, nogil=True)
def zz_displacement_at(x, y, xmin, dx, ymin, dy, traction):  # pragma: no cover - compiled
    """The normal displacement difference [m] at the point (x, y) [m] of a normal traction
    [Pa] given on a grid of ``traction.shape`` elements of size ``dx * dy`` whose outer
    edges start at (xmin, ymin) [m], without the factor ``(1-nu)/(pi G)`` [m/Pa / m]:
    ``sum_ij [[F]](x - x_i, y - y_j) traction_ij`` (the zz block of
    :func:`coefficients_at`), with ``F`` formed once at each of the ``(nx+1)(ny+1)``
    element corners that neighbouring elements share (a quarter of the corner operator's
    evaluations; the same sum within round-off)."""
    nx, ny = traction.shape
    prev = np.empty(ny + 1)  # F at the corners of edge i (an x edge), then of edge i + 1
    here = np.empty(ny + 1)
    for j in range(ny + 1):
        prev[j] = _zz_antiderivative(x - xmin, y - (ymin + j * dy))
    total = 0.0
    for i in range(nx):
        xe = x - (xmin + (i + 1) * dx)
        for j in range(ny + 1):
            here[j] = _zz_antiderivative(xe, y - (ymin + j * dy))
        for j in range(ny):
            w = traction[i, j]
            if w != 0.0:
                total += (prev[j] - prev[j + 1] - here[j] + here[j + 1]) * w
        prev, here = here, prev
    return total


@numba.njit(cache=True, nogil=True)
def zz_displacement_centred(y, dx, ymin, dy, traction):  # pragma: no cover - compiled
    """:func:`zz_displacement_at` the point (0, y) [m] for a grid centred on x = 0 (its x
    edges ``(k - nx/2) dx``, k = 0 .. nx): the coefficients of the columns ``i`` and
    ``nx - 1 - i`` are the same (the zz block is even in x), so each pair's tractions are
    added and its corners formed once (half the evaluations of ``F``), and only at the
    corners of elements with traction."""
    nx, ny = traction.shape
    ncols = (nx + 1) // 2
    pair = np.zeros((ncols, ny))  # the columns' tractions, each with its mirror's
    first = np.full(ncols + 2, ny)  # the rows with traction (first, last) a column pair,
    last = np.full(ncols + 2, -1)  # with empty columns at both ends (index i + 1)
    for i in range(ncols):
        mirror = nx - 1 - i
        for j in range(ny):
            w = traction[i, j] + traction[mirror, j] if mirror != i else traction[i, j]
            pair[i, j] = w
            if w != 0.0:
                first[i + 1] = min(first[i + 1], j)
                last[i + 1] = max(last[i + 1], j)
    half = 0.5 * nx
    prev = np.zeros(ny + 1)
    here = np.zeros(ny + 1)
    total = 0.0
    for e in range(ncols + 1):  # the edge at (half - e) dx, between the columns e-1, e
        lo = min(first[e], first[e + 1]) if e < ncols else first[e]
        hi = max(last[e], last[e + 1]) if e < ncols else last[e]
        xe = (half - e) * dx
        for j in range(lo, hi + 2):
            here[j] = _zz_antiderivative(xe, y - (ymin + j * dy))
        if e > 0:
            i = e - 1
            for j in range(first[e], last[e] + 1):
                w = pair[i, j]
                if w != 0.0:
                    total += (prev[j] - prev[j + 1] - here[j] + here[j + 1]) * w
        prev, here = here, prev
    return total
