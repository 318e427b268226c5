"""Hertz's solution for two elastic bodies with a quadratic undeformed gap.

The gap near the initial contact point is ``h(x, y) = A x^2 + B y^2`` with the
longitudinal and lateral relative curvatures ``A``, ``B`` [1/m]. The contact patch is the
ellipse ``x^2/a^2 + y^2/b^2 <= 1`` (``a`` along x) carrying

    p(x, y) = p0 sqrt(1 - x^2/a^2 - y^2/b^2),   p0 = 3 N / (2 pi a b).

The equations are solved directly (no table interpolation), following Johnson (1985,
eq. 4.39) and CONTACT (``m_hertz.f90:hzcalc3d``). With ``g = b_min / a_max`` and the
eccentricity ``e^2 = 1 - g^2``, ``K(e)`` and ``E(e)`` the complete elliptic integrals:

* shape:        ``B_max/B_min = (E(e)/g^2 - K(e)) / (K(e) - E(e))``  (larger curvature
  across the short axis),
* size:         ``c^3 = 3 N rho E(e) / (4 pi E* sqrt(g))``, ``c = sqrt(a b)``,
  ``rho = 2 / (A + B)``,
* approach:     ``delta = b_min^2 (A + B) K(e) / E(e)``.

An identity used by the virtual-penetration models: ``A a^2 + B b^2 = delta``.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from functools import cache, lru_cache

import numpy as np
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk, elliprd, elliprf

from ..errors import RailContactError, check_positive
from .materials import ElasticPair

_CIRCLE_TOL = 1e-12


def _shape_ratio(m: float) -> float:
    """Curvature ratio B_max/B_min of a Hertz ellipse with parameter m = e^2 = 1 - g^2.

    ``(E/(1-m) - K) / (K - E)`` written with Carlson's integrals (``K = R_F``,
    ``K - E = (m/3) R_D``, both at (0, 1-m, 1)) as ``(3 R_F/R_D - 1)/(1 - m)``, which does
    not cancel for nearly circular patches (m -> 0), where ``K - E`` loses all digits.
    """
    rf, rd = elliprf(0.0, 1.0 - m, 1.0), elliprd(0.0, 1.0 - m, 1.0)
    return (3.0 * rf / rd - 1.0) / (1.0 - m)


TABLE_NODES = 2049
"""Nodes of the table that starts the shape equation's Newton iteration: equally spaced
in ``log g`` from ``g = 1`` to :data:`TABLE_SMALLEST_G`."""
TABLE_SMALLEST_G = 1e-4
NEWTON_RTOL = 1e-10
"""The Newton iteration stops after a step of at most this fraction of ``m`` (its error
is then ~1e-17: the table's cubic starts it within ~1e-12 and knows the slope to ~1e-7)."""


@cache
def _shape_table() -> tuple[list[float], list[float], list[float]]:
    """``log(B_max/B_min)``, ``log g`` and ``d log(B_max/B_min) / d log g`` at the table's
    nodes (the derivative by a complex step: :func:`_shape_ratio` is analytic in m)."""
    w = np.linspace(0.0, math.log(TABLE_SMALLEST_G), TABLE_NODES)
    m = -np.expm1(2.0 * w)
    step = 1e-20
    r = _shape_ratio(m)
    drdm = _shape_ratio(m + 1j * step).imag / step
    r[0], drdm[0] = 1.0, 0.75  # the circle's limits (m = 0)
    dvdw = drdm / r * (-2.0 * (1.0 - m))  # dm/dlog g = -2 g^2
    return np.log(r).tolist(), w.tolist(), dvdw.tolist()


def _newton(r: float) -> float | None:
    """The root m of ``_shape_ratio(m) = r`` by Newton's method started from the table's
    cubic Hermite interpolant of ``log g`` in ``log r`` (whose derivative it keeps), or
    None beyond the table or without convergence in 4 steps."""
    v_nodes, w_nodes, slopes = _shape_table()
    v = math.log(r)
    k = bisect.bisect_right(v_nodes, v) - 1
    if not 0 <= k < len(v_nodes) - 1:
        return None
    h = v_nodes[k + 1] - v_nodes[k]
    t = (v - v_nodes[k]) / h
    w0, w1, s0, s1 = w_nodes[k], w_nodes[k + 1], h / slopes[k], h / slopes[k + 1]
    t2, t3 = t * t, t * t * t
    w = ((2 * t3 - 3 * t2 + 1) * w0 + (t3 - 2 * t2 + t) * s0 + (3 * t2 - 2 * t3) * w1
         + (t3 - t2) * s1)
    dwdv = ((6 * t2 - 6 * t) * (w0 - w1) + (3 * t2 - 4 * t + 1) * s0 + (3 * t2 - 2 * t) * s1) / h
    m = -math.expm1(2.0 * w)
    drdm = -r / (dwdv * 2.0 * (1.0 - m))
    for _ in range(4):
        step = (float(_shape_ratio(m)) - r) / drdm
        m -= step
        if abs(step) <= NEWTON_RTOL * m + 1e-15:
            return m if 0.0 < m < 1.0 else None
    return None


def axis_ratio(curvature_ratio: float) -> float:
    """Ratio ``g = b_min / a_max <= 1`` of the Hertz ellipse for ``B_max / B_min`` >= 1.

    Solves the shape equation for the parameter ``m = e^2`` by Newton's method from a
    table's interpolant (:func:`_newton`; Brent's method beyond the table), to round-off
    (remembered for the last few ratios: a time step asks for the same patch's ellipse
    several times).
    """
    return _axis_ratio(float(curvature_ratio))


@lru_cache(maxsize=64)
def _axis_ratio(r: float) -> float:
    if not r >= 1.0:
        raise RailContactError(f"curvature ratio must be >= 1, got {r}")
    if r - 1.0 < _CIRCLE_TOL:
        return 1.0
    m = _newton(r)
    if m is not None:
        return math.sqrt(1.0 - m)
    # _shape_ratio grows monotonically from 1 (m -> 0) to infinity (m -> 1).
    lo, hi = 0.0, 1.0 - 1e-16
    if _shape_ratio(hi) < r:  # more slender than double precision resolves
        raise RailContactError(f"curvature ratio {r:g} is too large for the Hertz solution")
    m = brentq(lambda mm: _shape_ratio(mm) - r, lo, hi, xtol=1e-300, rtol=4 * np.finfo(float).eps,
               maxiter=500)
    return math.sqrt(1.0 - m)


def curvature_ratio(g: float) -> float:
    """Inverse of :func:`axis_ratio`: ``B_max / B_min`` for the axis ratio ``g`` in (0, 1]."""
    g = float(g)
    if not 0.0 < g <= 1.0:
        raise RailContactError(f"axis ratio must lie in (0, 1], got {g}")
    if 1.0 - g < 1e-12:
        return 1.0
    return float(_shape_ratio(1.0 - g * g))


@dataclass(frozen=True)
class HertzSolution:
    """Hertz's solution. All quantities in SI units.

    Attributes
    ----------
    A, B
        Longitudinal and lateral relative curvatures [1/m].
    a, b
        Semi-axes along x (rolling) and y (lateral) [m].
    load
        Normal force N [N].
    penetration
        Approach of distant points delta [m].
    max_pressure
        p0 = 3 N / (2 pi a b) [Pa].
    e_star
        Contact modulus E* [Pa].
    """

    A: float
    B: float
    a: float
    b: float
    load: float
    penetration: float
    max_pressure: float
    e_star: float

    @property
    def area(self) -> float:
        """Contact area pi a b [m^2]."""
        return math.pi * self.a * self.b

    def pressure(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Pressure [Pa] at points (x, y) [m] (broadcast), zero outside the ellipse (and
        everywhere for no contact, ``a`` or ``b`` 0)."""
        x, y = np.asarray(x), np.asarray(y)
        if not (self.a > 0 and self.b > 0):
            return np.zeros(np.broadcast(x, y).shape)
        s = 1.0 - (x / self.a) ** 2 - (y / self.b) ** 2
        return self.max_pressure * np.sqrt(np.clip(s, 0.0, None))


SHAPE_BOUND_RATIO = 1e6
"""Largest curvature ratio for which :func:`semi_axis_bound` gives a bound (its axis ratio
``g`` is then above 1e-4, inside the Newton table of :func:`axis_ratio`)."""


def semi_axis_bound(A: float, B: float, pair: ElasticPair, *, load: float | None = None,
                    penetration: float | None = None) -> float:
    """An upper bound [m] of the larger semi-axis ``max(a, b)`` of :func:`hertz`, without
    solving the shape equation (infinite where :func:`hertz` might reject the arguments -
    ``A``, ``B`` finite and positive, one of ``load`` and ``penetration``, finite and
    non-negative - or the curvature ratio ``r = B_max/B_min`` exceeds
    :data:`SHAPE_BOUND_RATIO`): a wheel's patch within the model by it needs no Hertz
    solution (:attr:`~railcontact.settings.PatchSettings.hertz`).

    With ``g`` the axis ratio, ``a_max^3 = 3 N rho E(e) / (4 pi E* g^2)`` (module
    docstring) and ``a_max = b_min / g``, ``b_min^2 = delta E(e) / ((A + B) K(e))``;
    ``E(e) <= pi/2``, ``E(e) <= K(e)``, and the shape equation gives
    ``g >= r^(-2/3)`` (equal to first order at ``r = 1``, ``g ~ r^(-1/2)`` for slender
    ellipses; checked over 1 <= r <= 1e12); the bound takes ``g >= r^(-2/3) / 2``:
    ``a_max^3 <= 1.5 N rho r^(4/3) / E*``, ``a_max <= 2 r^(2/3) sqrt(delta / (A + B))``.
    """
    if not (0.0 < A < math.inf and 0.0 < B < math.inf):
        return math.inf
    r = max(A, B) / min(A, B)
    if not r <= SHAPE_BOUND_RATIO or (load is None) == (penetration is None):
        return math.inf
    if load is not None:
        if not 0.0 <= load < math.inf:
            return math.inf
        return (1.5 * load * (2.0 / (A + B)) * r ** (4.0 / 3.0) / pair.e_star) ** (1.0 / 3.0)
    if not 0.0 <= penetration < math.inf:
        return math.inf
    return 2.0 * r ** (2.0 / 3.0) * math.sqrt(penetration / (A + B))


MIN_LOAD = 1e-6
"""Smallest normal load [N] whose contact is solved. Hertz's patch grows as the cube root
of the load: at 1e-6 N that of steel wheels on rails (A = 1, B = 5 1/m) is 4 um long, less
than the smallest element a wheel-rail time step takes (10 um), and at 1e-300 N its semi-axes
and pressure underflow. A positive load below this is treated as no contact, as a zero load
is: zero forces, which differ from the exact ones by less than the load itself, so that a
wheel unloading towards zero (lifting) passes into no contact continuously and never into
an error."""


def negligible_load(load: float) -> bool:
    """Whether a load [N] is below :data:`MIN_LOAD` (zero included): no contact."""
    return load < MIN_LOAD


def no_contact_load(load: float) -> str:
    """Why a positive load [N] below :data:`MIN_LOAD` has no contact, in words."""
    return f"the load {load:g} N is below {MIN_LOAD:g} N, the smallest load solved"


def semi_axes(A: float, B: float, e_star: float, *, load: float | None = None,
              penetration: float | None = None) -> tuple[float, float, float, float]:
    """Hertz's semi-axes ``a`` (along x) and ``b`` [m], load [N] and penetration [m] for
    curvatures ``A``, ``B`` [1/m] (both > 0), the contact modulus ``e_star`` [Pa] and
    either the load or the penetration (given, not checked: :func:`hertz` checks them).
    """
    g = axis_ratio(max(A, B) / min(A, B))
    m = 1.0 - g * g
    # plain floats (the same values): numpy's scalars make every later operation slower
    k, e = (float(ellipk(m)), float(ellipe(m))) if m > 0 else (math.pi / 2, math.pi / 2)
    rho = 2.0 / (A + B)

    def from_load(n: float) -> tuple[float, float, float]:
        c = (3.0 * n * rho * e / (4.0 * math.pi * e_star * math.sqrt(g))) ** (1.0 / 3.0)
        major, minor = c / math.sqrt(g), c * math.sqrt(g)
        delta = minor**2 * (A + B) * k / e
        return major, minor, delta

    if load is not None:
        n = load
    else:
        _, _, delta1 = from_load(1.0)
        n = (penetration / delta1) ** 1.5
    major, minor, delta = from_load(n)
    if penetration is not None:
        delta = float(penetration)
    a, b = (major, minor) if A <= B else (minor, major)
    return a, b, n, delta


def hertz(
    A: float,
    B: float,
    pair: ElasticPair,
    *,
    load: float | None = None,
    penetration: float | None = None,
) -> HertzSolution:
    """Hertz's solution for curvatures ``A``, ``B`` and either the load or the penetration.

    Parameters
    ----------
    A, B
        Relative curvatures of the undeformed gap ``h = A x^2 + B y^2`` [1/m]; both > 0.
    pair
        Combined elastic parameters of the two bodies.
    load
        Normal force N [N] (give this or ``penetration``).
    penetration
        Approach delta [m] (give this or ``load``).

    Returns
    -------
    HertzSolution
    """
    A = check_positive("curvature A", A, "1/m")
    B = check_positive("curvature B", B, "1/m")
    if (load is None) == (penetration is None):
        raise RailContactError("give exactly one of load [N] and penetration [m]")
    e_star = pair.e_star
    if load is not None:
        load = check_positive("load", load, "N", allow_zero=True)
    else:
        penetration = check_positive("penetration", penetration, "m", allow_zero=True)
    a, b, n, delta = semi_axes(A, B, e_star, load=load, penetration=penetration)
    if n > 0 and a * b > 0:
        p0 = 3.0 * n / (2.0 * math.pi * a * b)
    elif n > 0:  # a * b underflows: p0 scales as n^(1/3) (from the solution at 1 N)
        a1, b1, _, _ = semi_axes(A, B, e_star, load=1.0)
        p0 = 3.0 / (2.0 * math.pi * a1 * b1) * n ** (1.0 / 3.0)
    else:
        p0 = 0.0
    return HertzSolution(A=A, B=B, a=a, b=b, load=n, penetration=delta, max_pressure=p0,
                         e_star=e_star)
