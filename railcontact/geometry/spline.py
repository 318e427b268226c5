"""Compiled evaluation of a profile's cubic spline at many points.

``scipy.interpolate.CubicSpline`` evaluates about 15 ns per point plus its call overhead;
the contact search evaluates the rail at thousands of trace points and the wheel at a
thousand tangent-plane samples in every time step. This is the same piecewise cubic
(the spline's breakpoints ``x`` and power-basis coefficients ``c``, highest power first,
extrapolated with the end pieces as ``CubicSpline`` does), evaluated by a numba loop that
starts each interval search from the previous point's interval (the samples are mostly
ordered). Values equal ``CubicSpline``'s to round-off.
"""

from __future__ import annotations

import math

import numba
import numpy as np

MIN_POINTS = 32
"""Arrays shorter than this are left to ``CubicSpline`` (the call overhead dominates)."""


@numba.njit(cache=True, nogil=True)
def _interval(x, ti):
    """The piece of breakpoints ``x`` that holds ``ti`` (the end pieces beyond them)."""
    n = x.size - 1
    if ti < x[0]:
        return 0
    if ti >= x[n]:
        return n - 1
    return np.searchsorted(x, ti, side="right") - 1


@numba.njit(cache=True, nogil=True, inline="always")
def _piece(c, j, s, nu):
    """The ``nu``-th derivative (0, 1 or 2) of piece ``j`` at ``s`` from its start."""
    if nu == 0:
        return ((c[0, j] * s + c[1, j]) * s + c[2, j]) * s + c[3, j]
    if nu == 1:
        return (3.0 * c[0, j] * s + 2.0 * c[1, j]) * s + c[2, j]
    return 6.0 * c[0, j] * s + 2.0 * c[1, j]


@numba.njit(cache=True, nogil=True, inline="always")
def _interval_near(x, ti, j):
    """:func:`_interval` for ``ti`` (not NaN) searched from piece ``j``: a walk when
    ``ti`` lies within 16 pieces of it, else bisection (the same piece either way)."""
    n = x.size - 1
    if ti < x[0]:
        return 0
    if ti >= x[n]:
        return n - 1
    if ti >= x[min(j + 16, n)] or ti < x[max(j - 16, 0)]:
        lo, hi = 0, n  # x[lo] <= ti < x[hi]
        while hi - lo > 1:
            mid = (lo + hi) >> 1
            if ti >= x[mid]:
                lo = mid
            else:
                hi = mid
        return lo
    while ti >= x[j + 1]:
        j += 1
    while ti < x[j]:
        j -= 1
    return j


@numba.njit(cache=True, nogil=True, inline="always")
def _interval_walk(x, ti, j):
    """:func:`_interval_near`, walking forward first where ``ti`` lies in one of the
    four pieces from ``j`` on (points ordered along the breakpoints: a step or two)."""
    if x[j] <= ti < x[min(j + 4, x.size - 1)]:
        while ti >= x[j + 1]:
            j += 1
        return j
    return _interval_near(x, ti, j)


@numba.njit(cache=True, nogil=True)
def _evaluate(x, c, t, nu, out):
    """``out[i]`` = the ``nu``-th derivative of the piecewise cubic at ``t[i]``; each
    interval search starts from the previous point's interval."""
    j = 0
    for i in range(t.size):
        ti = t[i]
        if math.isnan(ti):
            out[i] = math.nan
            continue
        j = _interval_walk(x, ti, j)
        out[i] = _piece(c, j, ti - x[j], nu)


@numba.njit(cache=True, nogil=True)
def _evaluate_one(x, c, ti, nu):
    """The ``nu``-th derivative of the piecewise cubic at the one point ``ti``."""
    if math.isnan(ti):
        return math.nan
    j = _interval(x, ti)
    return _piece(c, j, ti - x[j], nu)


def evaluate(x: np.ndarray, c: np.ndarray, t, nu: int = 0):
    """The spline with breakpoints ``x`` [m] and coefficients ``c`` (4, n) at ``t`` [m]
    (derivative ``nu`` in 0, 1, 2), or None when ``t`` is neither a float nor a float array
    of at least :data:`MIN_POINTS` points (the caller then uses ``CubicSpline``). A float
    gives a 0-d array, as ``CubicSpline`` does."""
    if nu not in (0, 1, 2):
        return None
    if isinstance(t, float):
        return np.array(_evaluate_one(x, c, t, nu))
    if not isinstance(t, np.ndarray) or t.dtype != np.float64 or t.size < MIN_POINTS:
        return None
    flat = np.ascontiguousarray(t).reshape(-1)
    out = np.empty(flat.size)
    _evaluate(x, c, flat, nu, out)
    return out.reshape(t.shape)
