"""Kalker's creep coefficients C11, C22, C23 (and C33) of the linear theory.

Linear theory (Kalker 1967/1990), ``c = sqrt(a b)``, combined shear modulus ``G``::

    F_x = -G c^2 C11 xi
    F_y = -G c^2 C22 eta - G c^3 C23 phi
    M_z =  G c^3 C23 eta - G c^4 C33 phi

Table E.3 of Kalker (1990), App. E, as tabulated in CONTACT (``m_hertz.f90:linrol``), and
CONTACT's interpolation: linear in the axis ratio ``g`` between rows, quadratic Lagrange
in Poisson's ratio of ``1/C`` through nu = 0, 0.25, 0.5; for ``g < 0.1`` Kalker's
slender-ellipse asymptotes. The C33 column is from the literature, not from CONTACT, and is
marked unverified in ``docs/algorithms.md`` Sec. 2.2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..errors import RailContactError, check_positive

_G = np.round(np.arange(1, 11) * 0.1, 10)  # 0.1 .. 1.0

# [g index][coef C11, C22, C23, C33][nu = 0, 0.25, 0.5]; a <= b, g = a/b.
_A_LE_B = np.array([
    [[2.51, 3.31, 4.85], [2.51, 2.52, 2.53], [0.334, 0.473, 0.731], [6.42, 8.28, 11.7]],
    [[2.59, 3.37, 4.81], [2.59, 2.63, 2.66], [0.483, 0.603, 0.809], [3.46, 4.27, 5.66]],
    [[2.68, 3.44, 4.80], [2.68, 2.75, 2.81], [0.607, 0.715, 0.889], [2.49, 2.96, 3.72]],
    [[2.78, 3.53, 4.82], [2.78, 2.88, 2.98], [0.720, 0.823, 0.977], [2.02, 2.32, 2.77]],
    [[2.88, 3.62, 4.83], [2.88, 3.01, 3.14], [0.827, 0.929, 1.07], [1.74, 1.93, 2.22]],
    [[2.98, 3.72, 4.91], [2.98, 3.14, 3.31], [0.930, 1.03, 1.18], [1.56, 1.68, 1.86]],
    [[3.09, 3.81, 4.97], [3.09, 3.28, 3.48], [1.03, 1.14, 1.29], [1.43, 1.50, 1.60]],
    [[3.19, 3.91, 5.05], [3.19, 3.41, 3.65], [1.13, 1.25, 1.40], [1.34, 1.37, 1.42]],
    [[3.29, 4.01, 5.12], [3.29, 3.54, 3.82], [1.23, 1.36, 1.51], [1.27, 1.27, 1.27]],
    [[3.40, 4.12, 5.20], [3.40, 3.67, 3.98], [1.33, 1.47, 1.63], [1.21, 1.19, 1.16]],
])
# a >= b, g = b/a (rows g = 0.1 .. 1.0; the g = 1 row is shared with the table above).
_A_GE_B = np.array([
    [[10.7, 11.7, 12.9], [10.7, 12.8, 16.0], [12.2, 14.6, 18.0], [0.795, 0.526, 0.228]],
    [[6.96, 7.78, 8.82], [6.96, 8.14, 9.79], [5.72, 6.63, 7.89], [0.828, 0.601, 0.341]],
    [[5.57, 6.34, 7.34], [5.57, 6.40, 7.51], [3.79, 4.32, 5.01], [0.868, 0.674, 0.446]],
    [[4.84, 5.57, 6.57], [4.84, 5.48, 6.31], [2.88, 3.24, 3.70], [0.912, 0.747, 0.549]],
    [[4.37, 5.10, 6.11], [4.37, 4.90, 5.56], [2.35, 2.62, 2.96], [0.958, 0.819, 0.650]],
    [[4.06, 4.78, 5.80], [4.06, 4.50, 5.04], [2.01, 2.23, 2.50], [1.01, 0.892, 0.751]],
    [[3.82, 4.54, 5.58], [3.82, 4.21, 4.67], [1.76, 1.95, 2.18], [1.05, 0.965, 0.852]],
    [[3.65, 4.36, 5.42], [3.65, 3.99, 4.39], [1.58, 1.75, 1.94], [1.10, 1.04, 0.954]],
    [[3.51, 4.22, 5.30], [3.51, 3.81, 4.16], [1.44, 1.59, 1.77], [1.16, 1.11, 1.06]],
    [[3.40, 4.12, 5.20], [3.40, 3.67, 3.98], [1.33, 1.47, 1.63], [1.21, 1.19, 1.16]],
])


@dataclass(frozen=True)
class CreepCoefficients:
    """Kalker's coefficients for one ellipse and Poisson's ratio (dimensionless)."""

    c11: float
    c22: float
    c23: float
    c33: float


def _interp_nu(c: np.ndarray, nu: float) -> np.ndarray:
    """Quadratic Lagrange interpolation of 1/C in nu through nu = 0, 1/4, 1/2."""
    inv = (8 * (nu - 0.25) * (nu - 0.5) / c[..., 0] - 16 * (nu - 0.5) * nu / c[..., 1]
           + 8 * nu * (nu - 0.25) / c[..., 2])
    return 1.0 / inv


@lru_cache(maxsize=8)
def _rows(a_le_b: bool, nu: float) -> np.ndarray:
    """The table of ``a <= b`` (else ``a >= b``) at Poisson's ratio ``nu``
    (:func:`_interp_nu`), one row per coefficient (4, 10), formed once per ratio."""
    rows = _interp_nu(_A_LE_B if a_le_b else _A_GE_B, nu).T.copy()
    rows.flags.writeable = False
    return rows


def _asymptote(g: float, nu: float, a_le_b: bool) -> np.ndarray:
    """Kalker's slender-ellipse asymptotes (g < 0.1); C33 by table extrapolation."""
    if a_le_b:  # a << b
        c11 = math.pi**2 / (4 * (1 - nu))
        c22 = math.pi**2 / 4
        c23 = math.pi * math.sqrt(g) / (3 * (1 - nu)) * (1 + nu * (math.log(16 / g) - 5))
        c33 = math.pi**2 / (16 * (1 - nu) * g)
    else:  # a >> b
        lam = math.log(16 / g**2)
        c11 = 2 * math.pi / ((lam - 2 * nu) * g) * (1 + (3 - math.log(4)) / (lam - 2 * nu))
        d = (1 - nu) * lam + 2 * nu
        c22 = 2 * math.pi / g * (1 + (1 - nu) * (3 - math.log(4)) / d) / d
        c23 = 2 * math.pi / (3 * g**1.5 * ((1 - nu) * lam - 2 + 4 * nu))
        c33 = float(_interp_nu(_A_GE_B[0, 3], nu))
    return np.array([c11, c22, c23, c33])


def creep_coefficients(a: float, b: float, poisson: float) -> CreepCoefficients:
    """Kalker's C11, C22, C23, C33 for semi-axes ``a`` (rolling), ``b`` [m] and nu [-].

    Parameters
    ----------
    a, b
        Semi-axes of the contact ellipse along x and y [m] (only a/b matters).
    poisson
        Combined Poisson's ratio, in [0, 0.5].
    """
    a = check_positive("semi-axis a", a, "m")
    b = check_positive("semi-axis b", b, "m")
    nu = float(poisson)
    if not 0.0 <= nu <= 0.5:
        raise RailContactError(f"poisson must lie in [0, 0.5], got {poisson!r}")
    a_le_b = a <= b
    g = a / b if a_le_b else b / a
    if g < 0.1:
        c = _asymptote(g, nu, a_le_b)
    else:
        rows = _rows(a_le_b, nu)  # (4, 10)
        c = np.array([np.interp(g, _G, rows[k]) for k in range(4)])
    return CreepCoefficients(*map(float, c))
