"""FaStrip (Sichani, Enblom & Berg, VSD 54(6):748-764, 2016): strip theory scaled to Kalker.

Formulas as implemented in CONTACT's ``original_fastrip`` (``algorithms.md`` Sec. 3), for a
Hertzian patch with semi-axes a, b and maximum pressure p0 = 3N/(2 pi a b). Creepages are
made dimensionless so that the strip theory reproduces Kalker's linear theory::

    xi'  = -G 4(1-nu) C11 xi  / (2 mu p0 pi^2)
    eta' = -G 4(1-nu) C22 eta / (2 mu p0 pi^2)
    phi' = -G 3 sqrt(ab) C23 phi / (2 mu p0 pi)

On strip y (half length a_y) the slip zone is ``[-a_y, -a_y + 2d]`` at the trailing edge,

    d = a/(1-nu) [sqrt(eta'^2 + (1-phi'^2)(xi' - phi' y/a)^2) + eta' phi'] / (1 - phi'^2)

(full sliding when d >= a_y, d < 0, or |phi'| >= 1), and the adhesion zone carries

    p_x = (mu p0/a) [kappa sqrt(a_y^2 - x^2) - kappa sqrt((a_y-d)^2 - (x-d)^2)]
    p_y = (mu p0/a) [lambda sqrt(a_y^2 - x^2) - (lambda - phi') sqrt((a_y-d)^2 - (x-d)^2)]

with ``(kappa, lambda) = (xi' - phi' y/a, eta' + phi' d/a) / D`` normalised. For pure xi
this is Carter's solution on every strip. In the slip zone (and where an adhesion value
would exceed the bound) the traction has magnitude mu p_n and the direction of the FASTSIM
traction at the same point (CONTACT does the same, with a FASTSIM pass).

Uncertain (see ``algorithms.md`` Sec. 10): Sichani's kappa' (CONTACT uses kappa) and the
placement of nu in d; these formulas are CONTACT's.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..errors import check_finite, check_positive
from ..halfspace.materials import ElasticPair
from .fastsim import _march, flexibilities, hertz_bound
from .kalker import creep_coefficients
from .strips import ADHESION, EXTERIOR, SLIP, StripResult, Strips, summarise


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
    (the local-ellipse adaptation for non-elliptic patches, ``algorithms.md`` Sec. 3)."""
    t0 = time.perf_counter()
    a = check_positive("a", a, "m")
    b = check_positive("b", b, "m")
    mu = check_positive("friction", friction, allow_zero=True)
    xi, eta, phi = (check_finite(n, v) for n, v in zip(("xi", "eta", "phi"), creepage,
                                                          strict=True))
    pn = np.asarray(pressure, dtype=float)
    flex = flexibilities(a, b, pair)
    fs_traction, _ = _march(strips, mu * pn, (xi, eta, phi), flex)
    if mu == 0.0 or load <= 0.0:
        return summarise(strips, np.zeros_like(fs_traction),
                         np.where(pn > 0, SLIP, EXTERIOR).astype(np.int8), pn,
                         "FaStrip: no friction or no load", t0)

    nu, g_mod = pair.poisson, pair.shear
    c = creep_coefficients(a, b, nu)
    p0 = 3 * load / (2 * math.pi * a * b)
    scale = 2 * mu * p0 * math.pi**2
    xi_ = -g_mod * 4 * (1 - nu) * c.c11 * xi / scale
    eta_ = -g_mod * 4 * (1 - nu) * c.c22 * eta / scale
    phi_ = -g_mod * 3 * math.sqrt(a * b) * c.c23 * phi / (2 * mu * p0 * math.pi)

    x = strips.x
    y = strips.y[:, None]
    ay = 0.5 * (strips.x_hi - strips.x_lo)[:, None]
    xs = x - 0.5 * (strips.x_hi + strips.x_lo)[:, None]
    bound = mu * pn
    ex = xi_ - phi_ * y / a
    with np.errstate(invalid="ignore", divide="ignore"):
        disc = eta_**2 + (1 - phi_**2) * ex**2
        d = a / (1 - nu) * (np.sqrt(np.clip(disc, 0, None)) + eta_ * phi_) / (1 - phi_**2)
        sliding = (abs(phi_) >= 1.0) | (disc < 0) | ~(d >= 0) | ~(d < ay)
        d = np.where(sliding, 0.0, d)
        ey = eta_ + phi_ * d / a
        den = np.hypot(ex, ey)
        kappa = np.where(den > 0, ex / den, 0.0)
        lam = np.where(den > 0, ey / den, 0.0)
    r1 = np.sqrt(np.clip(ay**2 - xs**2, 0, None))
    r2 = np.sqrt(np.clip((ay - d) ** 2 - (xs - d) ** 2, 0, None))
    qx = mu * p0 / a * (kappa * r1 - kappa * r2)
    qy = mu * p0 / a * (lam * r1 - (lam - phi_) * r2)
    adhesion = (~sliding & (den > 0) & (xs >= -ay + 2 * d) & (pn > 0)
                & (np.hypot(qx, qy) <= bound * (1 + 1e-12)))
    state = np.where(pn > 0, np.where(adhesion, ADHESION, SLIP), EXTERIOR).astype(np.int8)
    # slip: magnitude mu p_n in the direction of the FASTSIM traction at the same point
    fs_mag = np.hypot(fs_traction[0], fs_traction[1])
    with np.errstate(invalid="ignore", divide="ignore"):
        direction = np.where(fs_mag > 0, fs_traction / fs_mag, 0.0)
    traction = np.where(adhesion, np.stack([qx, qy]), bound * direction)
    return summarise(strips, traction, state, pn, "FaStrip", t0)
