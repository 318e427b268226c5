"""FASTSIM: Kalker's simplified theory of rolling contact (Kalker 1982, VSD 11:1-13).

The surface is a bed of springs, ``u = L p``, with one flexibility per creepage chosen so
that full adhesion reproduces Kalker's linear theory (CONTACT ``m_hertz.f90:simpflex``)::

    L1 = 8 a / (3 C11 G),   L2 = 8 a / (3 C22 G),   L3 = pi a sqrt(a/b) / (4 C23 G)

Steady rolling in +x: along each strip the traction is integrated from zero at the leading
edge towards the trailing edge, ``dp = -h (xi/L1 - phi y/L3, eta/L2 + phi x_m/L3)`` over a
step ``h`` with midpoint ``x_m``, and limited to the traction bound ``mu p_n`` (slip).
Traction bound: ``"elliptic"`` (Hertz pressure, Vollebregt's recommendation) or
``"parabolic"`` (Kalker's original, ``p_n = 2N/(pi a b) (1 - x^2/a^2 - y^2/b^2)``), or an
actual pressure on the strips (non-elliptic patches).
"""

from __future__ import annotations

import math
import time

import numba
import numpy as np

from ..errors import RailContactError, check_finite, check_positive
from ..halfspace.materials import ElasticPair
from .kalker import CreepCoefficients, creep_coefficients
from .strips import ADHESION, EXTERIOR, SLIP, StripResult, Strips, check_samples, summarise


def flexibilities(a: float, b: float, pair: ElasticPair,
                  coefficients: CreepCoefficients | None = None) -> tuple[float, float, float]:
    """Kalker's flexibilities (L1, L2, L3) [m/Pa] for semi-axes a, b [m] (``coefficients``:
    Kalker's coefficients of that ellipse, when they are at hand)."""
    c = creep_coefficients(a, b, pair.poisson) if coefficients is None else coefficients
    g = pair.shear
    return (8 * a / (3 * c.c11 * g), 8 * a / (3 * c.c22 * g),
            math.pi * a * math.sqrt(a / b) / (4 * c.c23 * g))


def hertz_bound(strips: Strips, a: float, b: float, load: float,
                bound: str = "elliptic") -> np.ndarray:
    """Normal pressure at the strip samples (ny, nx) [Pa] for a Hertzian patch, scaled so
    that the samples carry ``load`` [N] (on coarse strips the sampled shape alone carries
    up to 24 % more, and the creep force, bounded by mu p per sample, would exceed mu N)."""
    s = 1 - (strips.x / a) ** 2 - (strips.y[:, None] / b) ** 2
    if bound == "elliptic":
        p = np.sqrt(np.clip(s, 0, None))
    elif bound == "parabolic":
        p = np.clip(s, 0, None)
    else:
        raise RailContactError(f"bound must be 'elliptic' or 'parabolic', got {bound!r}")
    carried = float((p * strips.area).sum())
    return p * (load / carried) if carried > 0 else p


def _march(strips: Strips, bound: np.ndarray, creepage, flex, spin_scale=(1.0, 1.0)):
    """FASTSIM marching on all strips at once. Returns traction (2, ny, nx) and state."""
    xi, eta, phi = creepage
    l1, l2, l3 = flex
    return _march_strips(strips.x_lo, strips.x_hi, strips.t, strips.y,
                         np.ascontiguousarray(bound, float), xi / l1, eta / l2,
                         spin_scale[0] * phi, spin_scale[1] * phi, l3)


@numba.njit(cache=True, nogil=True)
def _march_strips(x_lo, x_hi, t, y, bound, cx, cy, spin_x, spin_y, l3
                  ):  # pragma: no cover - compiled
    """:func:`_march` on the strips at ``y`` (ny,) [m] from ``x_lo`` to ``x_hi`` [m]
    sampled at ``t`` (:attr:`Strips.x`), the bound ``bound`` (ny, nx) [Pa]: each strip
    from its leading to its trailing sample, ``dp = -h (cx - spin_x y / l3, cy + spin_y x_m / l3)``
    (``cx = xi/L1``, ``cy = eta/L2``, ``spin_* = phi`` times the spin scale), clipped to the
    bound (the same operations, in the same order, as numpy's column by column)."""
    ny, nx = bound.shape
    x = np.empty((ny, nx))
    for j in range(ny):
        half = 0.5 * (x_hi[j] - x_lo[j])
        mid = 0.5 * (x_hi[j] + x_lo[j])
        for k in range(nx):
            x[j, k] = mid + half * t[k]
    traction = np.zeros((2, ny, nx))
    state = np.zeros((ny, nx), dtype=np.int8)
    px = np.zeros(ny)
    py = np.zeros(ny)
    x_up = x_hi.copy()
    tx = np.empty(ny)
    for j in range(ny):
        tx[j] = cx - spin_x * y[j] / l3
    for k in range(nx - 1, -1, -1):  # leading edge (large x) to trailing edge; the strips
        for j in range(ny):  # side by side (independent: their chains overlap)
            xk = x[j, k]
            h = x_up[j] - xk
            xm = 0.5 * (x_up[j] + xk)
            hx = px[j] - h * tx[j]
            hy = py[j] - h * (cy + spin_y * xm / l3)
            g = bound[j, k]
            mag = math.hypot(hx, hy)
            slip = mag > g
            scale = g / (mag if mag > 0 else 1.0) if slip else 1.0
            px[j], py[j] = hx * scale, hy * scale
            traction[0, j, k] = px[j]
            traction[1, j, k] = py[j]
            state[j, k] = (SLIP if slip else ADHESION) if g > 0 else EXTERIOR
            x_up[j] = xk
    return traction, state


def fastsim(
    strips: Strips,
    pressure: np.ndarray,
    friction: float,
    creepage: tuple[float, float, float],
    flexibility: tuple[float, float, float],
) -> StripResult:
    """Kalker's FASTSIM on strips.

    Parameters
    ----------
    strips
        The strip discretisation of the patch.
    pressure
        Normal pressure at the strip samples [Pa], shape (ny, nx); see :func:`hertz_bound`.
    friction
        mu [-].
    creepage
        (xi, eta, phi) [-, -, 1/m].
    flexibility
        (L1, L2, L3) [m/Pa], e.g. from :func:`flexibilities`.
    """
    t0 = time.perf_counter()
    if np.ndim(friction) != 0:
        raise RailContactError("FASTSIM takes one coefficient of friction per patch (a number); "
                               "friction per element needs the BEM")
    mu = check_positive("friction", friction, allow_zero=True)
    cr = tuple(check_finite(n, v) for n, v in zip(("xi", "eta", "phi"), creepage, strict=True))
    flex = tuple(check_positive(f"L{i + 1}", v, "m/Pa") for i, v in enumerate(flexibility))
    check_samples(strips, "pressure", pressure)
    pn = np.asarray(pressure, dtype=float)
    if mu == 0.0:  # (the march tells the contact by its bound mu p > 0: none without mu)
        return summarise(strips, np.zeros((2, *pn.shape)),
                         np.where(pn > 0, SLIP, EXTERIOR).astype(np.int8), pn,
                         "FASTSIM: no friction", t0)
    traction, state = _march(strips, mu * pn, cr, flex)
    return summarise(strips, traction, state, pn, "FASTSIM", t0)


def fastsim_hertz(a: float, b: float, load: float, pair: ElasticPair, friction: float,
                  creepage: tuple[float, float, float], *, nx: int = 40, ny: int = 40,
                  bound: str = "elliptic", quadrature: str = "uniform") -> StripResult:
    """FASTSIM on the Hertz ellipse (a, b [m], load [N]) with Kalker's flexibilities."""
    strips = Strips.ellipse(a, b, nx, ny, quadrature)
    return fastsim(strips, hertz_bound(strips, a, b, load, bound), friction, creepage,
                   flexibilities(a, b, pair))
