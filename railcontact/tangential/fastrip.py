"""FaStrip (Sichani, Enblom & Berg, VSD 54(6):748-764, 2016): strip theory scaled to Kalker.

Formulas as implemented in CONTACT's ``original_fastrip`` (``docs/algorithms.md`` Sec. 3), for a
Hertzian patch with semi-axes a, b and maximum pressure p0 = 3N/(2 pi a b). Creepages are
made dimensionless so that the strip theory reproduces Kalker's linear theory::

    xi'  = -G 4(1-nu) C11 xi  / (2 mu p0 pi^2)
    eta' = -G 4(1-nu) C22 eta / (2 mu p0 pi^2)
    phi' = -G 3 sqrt(ab) C23 phi / (2 mu p0 pi)

On strip y (half length a_y) the slip zone is ``[-a_y, -a_y + 2d]`` at the trailing edge,

    d = a/(1-nu) [sqrt(eta'^2 + (1-phi'^2)(xi' - phi' y/a)^2) + eta' phi'] / (1 - phi'^2)

(full sliding when d >= a_y, d < 0, or ``|phi'| >= 1``), and the adhesion zone carries

    p_x = (mu p0/a) [kappa sqrt(a_y^2 - x^2) - kappa sqrt((a_y-d)^2 - (x-d)^2)]
    p_y = (mu p0/a) [lambda sqrt(a_y^2 - x^2) - (lambda - phi') sqrt((a_y-d)^2 - (x-d)^2)]

with ``(kappa, lambda) = (xi' - phi' y/a, eta' + phi' d/a) / D`` normalised. For pure xi
this is Carter's solution on every strip. In the slip zone (and where an adhesion value
would exceed the bound) the traction has magnitude mu p_n and the direction of the FASTSIM
traction at the same point (CONTACT does the same, with a FASTSIM pass).

Uncertain (see ``docs/algorithms.md`` Sec. 10): Sichani's kappa' (CONTACT uses kappa) and the
placement of nu in d; these formulas are CONTACT's.
"""

from __future__ import annotations

import math
import time

import numba
import numpy as np

from ..errors import RailContactError, check_finite, check_positive
from ..halfspace.materials import ElasticPair
from .fastsim import _march_strips, flexibilities, hertz_bound
from .kalker import creep_coefficients
from .strips import (
    ADHESION,
    EXTERIOR,
    SLIP,
    StripResult,
    Strips,
    check_samples,
    strip_result,
    summarise,
    summary,
)


def fastrip_hertz(a: float, b: float, load: float, pair: ElasticPair, friction: float,
                  creepage: tuple[float, float, float], *, nx: int = 40, ny: int = 40,
                  quadrature: str = "uniform") -> StripResult:
    """FaStrip on the Hertz ellipse (a, b [m], load [N], elliptic pressure).

    Parameters
    ----------
    a, b
        Semi-axes along x and y [m].
    load
        Normal force [N].
    pair
        Combined elastic parameters.
    friction
        mu [-].
    creepage
        (xi, eta, phi) [-, -, 1/m].
    nx, ny
        Samples per strip and number of strips.
    """
    strips = Strips.ellipse(check_positive("a", a, "m"), check_positive("b", b, "m"), nx, ny,
                            quadrature)
    return fastrip(strips, hertz_bound(strips, a, b, load, "elliptic"), load, a, b, pair,
                   friction, creepage)


def fastrip(strips: Strips, pressure: np.ndarray, load: float, a: float, b: float,
            pair: ElasticPair, friction: float, creepage: tuple[float, float, float]
            ) -> StripResult:
    """FaStrip on any strips: the actual pressure bounds the traction, while Kalker's
    coefficients, the flexibilities and p0 = 3N/(2 pi a b) come from the (equivalent)
    ellipse with semi-axes a, b [m]; each strip uses its own half length and centre
    (the local-ellipse adaptation for non-elliptic patches, ``docs/algorithms.md`` Sec. 3)."""
    t0 = time.perf_counter()
    a = check_positive("a", a, "m")
    b = check_positive("b", b, "m")
    if np.ndim(friction) != 0:
        raise RailContactError("FaStrip takes one coefficient of friction per patch (a number); "
                               "friction per element needs the BEM")
    mu = check_positive("friction", friction, allow_zero=True)
    xi, eta, phi = (check_finite(n, v) for n, v in zip(("xi", "eta", "phi"), creepage,
                                                          strict=True))
    check_samples(strips, "pressure", pressure)
    pn = np.ascontiguousarray(pressure, dtype=float)
    c = creep_coefficients(a, b, pair.poisson)
    l1, l2, l3 = flexibilities(a, b, pair, c)
    if mu == 0.0 or load <= 0.0:
        return summarise(strips, np.zeros((2, *pn.shape)),
                         np.where(pn > 0, SLIP, EXTERIOR).astype(np.int8), pn,
                         "FaStrip: no friction or no load", t0)

    nu, g_mod = pair.poisson, pair.shear
    p0 = 3 * load / (2 * math.pi * a * b)
    scale = 2 * mu * p0 * math.pi**2
    xi_ = -g_mod * 4 * (1 - nu) * c.c11 * xi / scale
    eta_ = -g_mod * 4 * (1 - nu) * c.c22 * eta / scale
    phi_ = -g_mod * 3 * math.sqrt(a * b) * c.c23 * phi / (2 * mu * p0 * math.pi)

    traction, state, sums = _fastrip_all(
        strips.x_lo, strips.x_hi, strips.t, strips.w, strips.y, strips.width, pn, mu,
        xi / l1, eta / l2, phi, l3, xi_, eta_, phi_, _squared(eta_), 1 - _squared(phi_),
        a / (1 - nu), eta_ * phi_, mu * p0 / a, a)
    return strip_result(strips, traction, state, pn, sums, "FaStrip", t0)


def _squared(v: float) -> float:
    """``v ** 2`` (the C library's pow, as the formulas were written), inf where it
    overflows: a creepage scaled by a vanishing ``mu p0`` (``mu`` 1e-200), whose strips
    all slide (:func:`_fastrip_strips` reads inf so)."""
    try:
        return v ** 2
    except OverflowError:
        return math.inf


@numba.njit(cache=True, nogil=True)
def _fastrip_all(x_lo, x_hi, t, w, y, width, pn, mu, cx, cy, phi, l3, xi_, eta_, phi_, eta2,
                 one_phi2, d_scale, eta_phi, q_scale, a):  # pragma: no cover - compiled
    """FASTSIM's march (the slip directions), :func:`_fastrip_strips` and the sums of
    :func:`~.strips.summarise` in one call."""
    bound = np.empty(pn.shape)
    for j in range(pn.shape[0]):
        for k in range(pn.shape[1]):
            bound[j, k] = mu * pn[j, k]
    fs_traction, _ = _march_strips(x_lo, x_hi, t, y, bound, cx, cy, phi, phi, l3)
    traction, state = _fastrip_strips(x_lo, x_hi, t, w, y, pn, mu, fs_traction, xi_, eta_,
                                      phi_, eta2, one_phi2, d_scale, eta_phi, q_scale, a)
    return traction, state, summary(x_lo, x_hi, width, y, t, w, traction, state)


@numba.njit(cache=True, nogil=True)
def _arc_integral(x, c, r):  # pragma: no cover - compiled
    """The antiderivative ``int sqrt(r^2 - (x - c)^2) dx`` at ``x`` [m^2], for the
    circle of radius ``r`` [m] about ``c`` [m]; ``x`` beyond it is clamped to its ends."""
    u = x - c
    if u >= r:
        return 0.25 * math.pi * r * r
    if u <= -r:
        return -0.25 * math.pi * r * r
    return 0.5 * (u * math.sqrt(r * r - u * u) + r * r * math.asin(u / r))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _fastrip_strips(x_lo, x_hi, t, w, y, pn, mu, fs_traction, xi_, eta_, phi_, eta2,
                    one_phi2, d_scale, eta_phi, q_scale, a):  # pragma: no cover - compiled
    """FaStrip's traction (2, ny, nx) [Pa] and state (ny, nx) at the samples ``t`` (weights
    ``w``) of the strips at ``y`` [m] from ``x_lo`` to ``x_hi`` [m] (:attr:`Strips.x`),
    pressure ``pn`` [Pa], friction ``mu`` and the FASTSIM traction ``fs_traction`` (its
    direction in the slip zone); the scaled creepages and the factors of :func:`fastrip`
    (``eta2 = eta'^2``, ``one_phi2 = 1 - phi'^2``, ``d_scale = a/(1-nu)``,
    ``eta_phi = eta' phi'``, ``q_scale = mu p0 / a``).

    Each sample's traction is the mean over its cell of the strip (the cells of the
    weights: sample ``k`` stands for ``[-1 + sum(w[:k]), -1 + sum(w[:k+1])]`` in ``t``),
    so that the samples carry the strip's force as the formulas integrate it. The
    adhesion part of a cell is integrated exactly (the two arcs' integrals,
    :func:`_arc_integral`): the adhesion traction rises within about ``d`` of the
    slip zone to ``mu p_n`` there, a peak the midpoint of a cell does not see (values at
    the midpoints give the linear theory's forces 6 % low on 40 samples a strip, 2 % on
    200). The slip part holds ``mu p_n`` at the sample in FASTSIM's direction; a cell's
    mean is held to the bound ``mu p_n`` at its sample. A sample is in adhesion where it
    lies in the adhesion zone and the mean of the adhesion traction over its cell's
    adhesion part is within that bound."""
    ny, nx = pn.shape
    traction = np.zeros((2, ny, nx))
    state = np.zeros((ny, nx), dtype=np.int8)
    spinning = abs(phi_) >= 1.0
    for j in range(ny):
        ay = 0.5 * (x_hi[j] - x_lo[j])
        centre = 0.5 * (x_hi[j] + x_lo[j])
        ex = xi_ - phi_ * y[j] / a
        disc = eta2 + one_phi2 * (ex * ex)
        root = disc if disc > 0.0 or math.isnan(disc) else 0.0
        d = d_scale * (math.sqrt(root) + eta_phi) / one_phi2
        sliding = spinning or disc < 0 or not d >= 0 or not d < ay
        if sliding:
            d = 0.0
        ey = eta_ + phi_ * d / a
        den = math.hypot(ex, ey)
        kappa = ex / den if den > 0 else 0.0
        lam = ey / den if den > 0 else 0.0
        start = -ay + 2 * d  # (the adhesion zone: from it to ay)
        edge = -1.0  # (the cell's trailing edge in t)
        for k in range(nx):
            xs = (centre + ay * t[k]) - centre  # (Strips.x: mid + half t)
            x0 = ay * edge
            edge = edge + w[k]
            x1 = ay * edge
            length = x1 - x0
            lo = max(x0, start)
            hi = min(x1, ay)
            qx = qy = 0.0  # (the adhesion traction's mean over the cell's adhesion part)
            part = 0.0  # (that part's share of the cell)
            if not sliding and den > 0 and hi > lo and length > 0:
                i1 = _arc_integral(hi, 0.0, ay) - _arc_integral(lo, 0.0, ay)
                i2 = _arc_integral(hi, d, ay - d) - _arc_integral(lo, d, ay - d)
                qx = q_scale * (kappa * i1 - kappa * i2) / (hi - lo)
                qy = q_scale * (lam * i1 - (lam - phi_) * i2) / (hi - lo)
                part = (hi - lo) / length
            p = pn[j, k]
            bound = mu * p
            adhesion = (not sliding and den > 0 and xs >= start and p > 0 and part > 0
                        and math.hypot(qx, qy) <= bound * (1 + 1e-12))
            state[j, k] = (ADHESION if adhesion else SLIP) if p > 0 else EXTERIOR
            # slip: mu p_n in the direction of the FASTSIM traction
            fx, fy = fs_traction[0, j, k], fs_traction[1, j, k]
            fs_mag = math.hypot(fx, fy)
            sx = bound * (fx / fs_mag if fs_mag > 0 else 0.0)
            sy = bound * (fy / fs_mag if fs_mag > 0 else 0.0)
            if not adhesion and (xs >= start or part == 0.0 or p <= 0
                                 or not math.hypot(qx, qy) <= bound * (1 + 1e-12)):
                traction[0, j, k] = sx  # (the whole cell slides)
                traction[1, j, k] = sy
                continue
            # the slip part's mean bound: mu p_n at the sample, shaped along the cell as
            # the strip's elliptic arc (exact for Hertz's pressure; p_n is known at the
            # sample only)
            shape = 1.0
            if part < 1.0:
                r1 = ay * ay - xs * xs
                r1 = math.sqrt(r1) if r1 > 0.0 else 0.0
                cut = min(max(start, x0), x1)
                if r1 > 0.0 and cut > x0:
                    shape = ((_arc_integral(cut, 0.0, ay) - _arc_integral(x0, 0.0, ay))
                             / (cut - x0)) / r1
            vx = part * qx + (1.0 - part) * shape * sx
            vy = part * qy + (1.0 - part) * shape * sy
            m = math.hypot(vx, vy)
            if m > bound:  # (a cell across the zones' border: within the bound)
                vx, vy = vx * (bound / m), vy * (bound / m)
            traction[0, j, k] = vx
            traction[1, j, k] = vy
    return traction, state
