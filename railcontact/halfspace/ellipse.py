"""Hertz's ellipse in compiled code: its shape for a curvature ratio and the lateral
virtual-penetration factor of INFCON, for kernels and loops that ask for it many times.

The complete elliptic integrals come from the arithmetic-geometric mean (Abramowitz &
Stegun 17.6.1-4): with ``a_0 = 1``, ``b_0 = sqrt(1 - m)``, ``c_0^2 = m``,

    K(m) = pi / (2 a_N),    K(m) - E(m) = K(m) sum_n 2^(n-1) c_n^2,

with ``c_(n+1) = (a_n - b_n) / 2 = c_n^2 / (4 a_(n+1))``, so that ``K - E`` is a sum of
positive terms without cancellation for nearly circular patches (m -> 0). The shape
equation ``B_max/B_min = (E/(1-m) - K) / (K - E)`` (see :mod:`~railcontact.halfspace.hertz`)
is then ``(m - S) / ((1 - m) S)`` with ``S = (K - E)/K``, solved for ``m`` by Newton's
method from the cubic table interpolant of :func:`~railcontact.halfspace.hertz._shape_table`
as :func:`~railcontact.halfspace.hertz.axis_ratio` does it (the same root within
round-off; NaN beyond the table, where the caller uses :mod:`~railcontact.halfspace.hertz`'s
Brent search).
"""

from __future__ import annotations

import math
from functools import cache

import numba
import numpy as np

from .hertz import _CIRCLE_TOL, NEWTON_RTOL, _shape_table


@cache
def shape_table() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`~railcontact.halfspace.hertz._shape_table` as arrays (``log(B_max/B_min)``,
    ``log g`` and the slope of the one in the other at its nodes) for the kernels."""
    return tuple(np.asarray(v, dtype=float) for v in _shape_table())


@numba.njit(cache=True, nogil=True, error_model="numpy")
def elliptic_k_excess(m):  # pragma: no cover - compiled
    """``K(m)`` and ``(K(m) - E(m)) / K(m)`` for ``0 <= m < 1`` by the AGM (module doc)."""
    a = 1.0
    b = math.sqrt(1.0 - m)
    c = math.sqrt(m)
    total = 0.5 * m  # 2^(-1) c_0^2
    weight = 0.5
    for _ in range(60):
        a, b = 0.5 * (a + b), math.sqrt(a * b)
        c = c * c / (4.0 * a)  # (a_n - b_n) / 2 without cancelling
        weight *= 2.0
        total += weight * c * c
        if c <= 1e-17 * a:
            break
    return 0.5 * math.pi / a, total


@numba.njit(cache=True, nogil=True, error_model="numpy")
def shape_ratio(m):  # pragma: no cover - compiled
    """``B_max/B_min`` of a Hertz ellipse with the parameter ``m = 1 - g^2`` (module doc)."""
    _, excess = elliptic_k_excess(m)
    return (m - excess) / ((1.0 - m) * excess)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def ellipse_parameter(r, v_nodes, w_nodes, slopes):  # pragma: no cover - compiled
    """The parameter ``m = 1 - g^2`` of the Hertz ellipse for the curvature ratio
    ``r = B_max/B_min >= 1`` (0 for a circle; NaN for ``r < 1``, beyond the table or
    without convergence in 4 Newton steps); the table of :func:`shape_table`."""
    if not r >= 1.0:
        return math.nan
    if r - 1.0 < _CIRCLE_TOL:
        return 0.0
    v = math.log(r)
    k = np.searchsorted(v_nodes, v, side="right") - 1
    if not (k >= 0 and k < v_nodes.size - 1):
        return math.nan
    h = v_nodes[k + 1] - v_nodes[k]
    t = (v - v_nodes[k]) / h
    w0, w1, s0, s1 = w_nodes[k], w_nodes[k + 1], h / slopes[k], h / slopes[k + 1]
    t2 = t * t
    t3 = t2 * t
    w = ((2 * t3 - 3 * t2 + 1) * w0 + (t3 - 2 * t2 + t) * s0 + (3 * t2 - 2 * t3) * w1
         + (t3 - t2) * s1)
    dwdv = ((6 * t2 - 6 * t) * (w0 - w1) + (3 * t2 - 4 * t + 1) * s0
            + (3 * t2 - 2 * t) * s1) / h
    m = -math.expm1(2.0 * w)
    drdm = -r / (dwdv * 2.0 * (1.0 - m))
    for _ in range(4):
        step = (shape_ratio(m) - r) / drdm
        m -= step
        if abs(step) <= NEWTON_RTOL * m + 1e-15:
            return m if 0.0 < m < 1.0 else math.nan
    return math.nan


@numba.njit(cache=True, nogil=True, error_model="numpy")
def lateral_factor(A, B, v_nodes, w_nodes, slopes):  # pragma: no cover - compiled
    """Hertz's lateral virtual-penetration factor ``chi = B b^2 / delta`` for the
    curvatures ``A`` (along x) and ``B`` (across) [1/m] (``b`` the semi-axis across; the
    same as :func:`~railcontact.normal.virtual.infcon_factor`), NaN where
    :func:`ellipse_parameter` gives none or a curvature is not positive and finite.

    At a unit penetration the shorter semi-axis is ``sqrt(E / ((A + B) K))``; ``b`` is it
    when ``A <= B``, else the longer, ``/ g``."""
    if not (A > 0.0 and B > 0.0 and A < math.inf and B < math.inf):
        return math.nan
    m = ellipse_parameter(max(A, B) / min(A, B), v_nodes, w_nodes, slopes)
    if math.isnan(m):
        return math.nan
    _, excess = elliptic_k_excess(m)
    minor2 = (1.0 - excess) / (A + B)  # E / K / (A + B)
    return B * (minor2 if A <= B else minor2 / (1.0 - m))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def hertz_penetration(A, B, e_star, load, v_nodes, w_nodes, slopes
                      ):  # pragma: no cover - compiled
    """Hertz's penetration [m] for the curvatures ``A``, ``B`` [1/m], the contact
    modulus ``e_star`` [Pa] and the load [N] (as :func:`~railcontact.halfspace.hertz.
    semi_axes`: ``c^3 = 3 N rho E / (4 pi E* sqrt(g))``, ``rho = 2 / (A + B)``, ``delta =
    c^2 g (A + B) K / E``); NaN where :func:`ellipse_parameter` gives none or an input is
    not positive and finite."""
    if not (A > 0.0 and B > 0.0 and A < math.inf and B < math.inf and e_star > 0.0
            and load > 0.0 and e_star < math.inf and load < math.inf):
        return math.nan
    m = ellipse_parameter(max(A, B) / min(A, B), v_nodes, w_nodes, slopes)
    if math.isnan(m):
        return math.nan
    k, excess = elliptic_k_excess(m)
    e_over_k = 1.0 - excess
    g = math.sqrt(1.0 - m)
    c3 = 3.0 * load * (2.0 / (A + B)) * k * e_over_k / (4.0 * math.pi * e_star * math.sqrt(g))
    minor = c3 ** (1.0 / 3.0) * math.sqrt(g)
    return minor * minor * (A + B) / e_over_k
