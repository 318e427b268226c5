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

import numpy as np

try:
    import numba
except ImportError:  # pragma: no cover
    numba = None

MIN_POINTS = 32
"""Arrays shorter than this are left to ``CubicSpline`` (the call overhead dominates)."""


def _evaluate(x, c, t, nu, out):
    """``out[i]`` = the ``nu``-th derivative (0, 1 or 2) of the piecewise cubic at ``t[i]``."""
    n = x.size - 1
    j = 0
    for i in range(t.size):
        ti = t[i]
        if math.isnan(ti):
            out[i] = math.nan
            continue
        if x[j] <= ti < x[j + 1]:  # the last point's interval
            pass
        elif j + 2 <= n and x[j + 1] <= ti < x[j + 2]:  # the next one
            j += 1
        else:  # search
            if ti < x[0]:
                j = 0
            elif ti >= x[n]:
                j = n - 1
            else:
                j = np.searchsorted(x, ti, side="right") - 1
        s = ti - x[j]
        if nu == 0:
            out[i] = ((c[0, j] * s + c[1, j]) * s + c[2, j]) * s + c[3, j]
        elif nu == 1:
            out[i] = (3.0 * c[0, j] * s + 2.0 * c[1, j]) * s + c[2, j]
        else:
            out[i] = 6.0 * c[0, j] * s + 2.0 * c[1, j]


def _evaluate_one(x, c, ti, nu):
    """The ``nu``-th derivative of the piecewise cubic at the one point ``ti``."""
    if math.isnan(ti):
        return math.nan
    n = x.size - 1
    if ti < x[0]:
        j = 0
    elif ti >= x[n]:
        j = n - 1
    else:
        j = np.searchsorted(x, ti, side="right") - 1
    s = ti - x[j]
    if nu == 0:
        return ((c[0, j] * s + c[1, j]) * s + c[2, j]) * s + c[3, j]
    if nu == 1:
        return (3.0 * c[0, j] * s + 2.0 * c[1, j]) * s + c[2, j]
    return 6.0 * c[0, j] * s + 2.0 * c[1, j]


_evaluate_numba = numba.njit(cache=True)(_evaluate) if numba is not None else None
_evaluate_one_numba = numba.njit(cache=True)(_evaluate_one) if numba is not None else None


def evaluate(x: np.ndarray, c: np.ndarray, t, nu: int = 0):
    """The spline with breakpoints ``x`` [m] and coefficients ``c`` (4, n) at ``t`` [m]
    (derivative ``nu`` in 0, 1, 2), or None when ``t`` is neither a float nor a float array
    of at least :data:`MIN_POINTS` points (the caller then uses ``CubicSpline``). A float
    gives a 0-d array, as ``CubicSpline`` does."""
    if isinstance(t, float) and _evaluate_one_numba is not None and nu in (0, 1, 2):
        return np.array(_evaluate_one_numba(x, c, t, nu))
    if (_evaluate_numba is None or not isinstance(t, np.ndarray) or t.dtype != np.float64
            or t.size < MIN_POINTS or nu not in (0, 1, 2)):
        return None
    flat = np.ascontiguousarray(t).reshape(-1)
    out = np.empty(flat.size)
    _evaluate_numba(x, c, flat, nu, out)
    return out.reshape(t.shape)
