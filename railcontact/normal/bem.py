"""Normal contact on a half-space by the Polonsky–Keer extended conjugate gradient method.

Problem (per element ``I`` of the potential-contact grid)::

    g_I = h_I + u_I - delta >= 0,   p_I >= 0,   g_I p_I = 0,   u = A_zz * p

with the undeformed gap ``h`` [m], the elastic displacement difference ``u`` [m] from the
influence operator, the rigid approach (penetration) ``delta`` [m] and the pressure ``p``
[Pa]. Either ``delta`` is prescribed (penetration control) or the total force
``F = dx dy sum p`` [N] (force control; ``delta`` is then the mean of ``h + u`` over the
contact set, Polonsky & Keer, Wear 231 (1999) 206–219).

Convergence: iteration ``k`` stops when the relative change of the pressure

    eps_k = sum_I |p_I^k - p_I^(k-1)| / sum_I p_I^k

falls below the tolerance ``eps_n`` (the paper's normal tolerance). The iteration count is
the number of CG steps taken (each costs two convolutions, three with the preconditioner).

Preconditioning (``preconditioner="fft"``, the default): the gradient on the contact set is
multiplied by an FFT approximate inverse of the influence matrix
(:meth:`~railcontact.halfspace.operator.InfluenceOperator.preconditioner`, the idea of CONTACT's
NormCG, Vollebregt, JCP 257A (2014) 333-351) and projected back onto the contact set
(and, under force control, onto zero mean), which keeps the step symmetric positive
definite on each active set. Plain Polonsky–Keer CG (``"none"``) reduces the pressure
change only about 1.5 times per iteration, from any start, because the half-space operator
damps element-scale pressure errors: the edge errors of an estimate then cost almost as
many iterations as a start on the whole grid. With the preconditioner the element-scale
errors go in a few steps, and how well the start's patch fits decides the count (the
paper's finding, Sec. 4.1.2).
Elements that interpenetrate without pressure enter the contact set with the pressure of
a preconditioned step (``-tau * kappa * g``, ``kappa`` the Rayleigh ratio of the
preconditioner on the gradient).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import RailContactError, check_count, check_positive
from ..halfspace.grid import Grid, touches_boundary
from ..halfspace.operator import InfluenceOperator

PRECONDITIONERS = ("fft", "none")
STALL_ITERATIONS = 100
"""Iterations without progress after which the CG stops, not converged (a tolerance below
what round-off lets it reach would otherwise run to ``max_iterations``)."""
STALL_GAIN = 0.99
"""Progress: the relative pressure change falls below this fraction of its best so far."""


@dataclass
class NormalResult:
    """Solution of the normal contact problem on a grid (SI units).

    Attributes
    ----------
    grid
        The potential-contact grid.
    pressure
        Pressure per element [Pa], shape (nx, ny).
    contact
        Contact mask (pressure > 0), shape (nx, ny).
    gap
        Deformed gap ``h + u - delta`` [m] (zero in contact, positive outside).
    force
        Total normal force [N].
    penetration
        Rigid approach delta [m].
    max_pressure
        Largest element pressure [Pa].
    area
        Contact area (contact elements times element area) [m^2].
    iterations
        CG iterations taken.
    converged
        True when the tolerance was reached within ``max_iterations``.
    message
        What happened, in words.
    wall_time
        Solver wall time [s].
    error
        The final relative pressure change eps.
    history
        eps after each iteration.
    touches_boundary
        True when the contact reaches the outer ring of the potential area (the area is
        then probably too small).
    """

    grid: Grid
    pressure: np.ndarray
    contact: np.ndarray
    gap: np.ndarray
    force: float
    penetration: float
    max_pressure: float
    area: float
    iterations: int
    converged: bool
    message: str
    wall_time: float
    error: float
    history: np.ndarray = field(repr=False)
    touches_boundary: bool = False


def _check_field(name: str, value: np.ndarray | None, shape: tuple[int, int]) -> np.ndarray | None:
    if value is None:
        return None
    a = np.asarray(value, dtype=float)
    if a.shape != shape:
        raise RailContactError(f"{name} must have the grid shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise RailContactError(f"{name} contains NaN or infinite values")
    return a


def _uniform_start(gap: np.ndarray, operator: InfluenceOperator, penetration: float) -> np.ndarray:
    """Best uniform pressure for penetration control: minimises the complementary energy
    0.5 p.Ap - p.(delta - h) over p = c * 1, floored at a tiny positive value."""
    k1 = float(np.sum(operator.apply(np.ones_like(gap))))
    c = float(np.sum(penetration - gap)) / k1
    return np.full_like(gap, max(c, 1e-6 * penetration * gap.size / k1))


def _overlaps(h: np.ndarray, u: np.ndarray, p: np.ndarray, force_control: bool,
              delta: float, tolerance: float) -> bool:
    """Whether elements outside the contact overlap by more than the tolerance allows:
    the gap ``h + u - delta`` there below ``-tolerance`` times the approach (the
    complementarity the relative pressure change does not check; a start far from the
    answer can make that change small while elements that belong to the contact are
    still out of it)."""
    c = p > 0.0
    if not c.any() or c.all():
        return False
    g = h + u
    d = float(g[c].mean()) if force_control else delta
    scale = max(abs(d - float(h.min())), 1e-300)
    return bool(float((g[~c] - d).min()) < -tolerance * scale)


def solve_normal(
    gap: np.ndarray,
    grid: Grid,
    operator: InfluenceOperator,
    *,
    load: float | None = None,
    penetration: float | None = None,
    initial_pressure: np.ndarray | None = None,
    initial_contact: np.ndarray | None = None,
    tolerance: float = 1e-3,
    max_iterations: int = 500,
    preconditioner: str = "fft",
) -> NormalResult:
    """Solve the frictionless normal contact problem by Polonsky–Keer's CG method.

    Parameters
    ----------
    gap
        Undeformed gap h [m] at the element centres, shape (nx, ny). Any constant offset
        is allowed under force control; under penetration control ``delta`` is measured
        from ``h = 0``.
    grid
        The potential-contact grid.
    operator
        Influence operator with component ``"z"`` for this grid's element size.
    load
        Total normal force [N] (force control). Give this or ``penetration``.
    penetration
        Rigid approach delta [m] (penetration control).
    initial_pressure
        Initial estimate of the pressure [Pa] on this grid (e.g. Hertz, INFCON, the
        previous time step). Negative values are set to zero; under force control it is
        rescaled to the load. Default: a uniform pressure on the whole grid (the paper's
        "w/o initial estimate"; under penetration control at the level that minimises the
        complementary energy).
    initial_contact
        Initial contact mask; elements outside it start with zero pressure.
    tolerance
        eps_n, the relative pressure change at which iteration stops (see module doc).
    max_iterations
        Largest number of CG iterations.
    preconditioner
        "fft" (default) or "none" (the plain Polonsky–Keer CG of the paper); see the
        module doc.

    Returns
    -------
    NormalResult
    """
    t0 = time.perf_counter()
    shape = grid.shape
    h = _check_field("gap", gap, shape)
    if h is None:
        raise RailContactError("gap is required")
    if operator.components != "z" or (operator.nx, operator.ny) != shape:
        raise RailContactError("operator must be a 'z' influence operator for this grid")
    tolerance = check_positive("tolerance", tolerance)
    if preconditioner not in PRECONDITIONERS:
        raise RailContactError(f"preconditioner must be one of {PRECONDITIONERS}, "
                               f"got {preconditioner!r}")
    precondition = operator.preconditioner() if preconditioner == "fft" else None
    max_iterations = check_count("max_iterations", max_iterations)
    if (load is None) == (penetration is None):
        raise RailContactError("give exactly one of load [N] and penetration [m]")
    force_control = load is not None
    if force_control:
        load = check_positive("load", load, "N", allow_zero=True)
    else:
        penetration = check_positive("penetration", penetration, "m", allow_zero=True)
    p = _check_field("initial_pressure", initial_pressure, shape)
    mask = None if initial_contact is None else np.asarray(initial_contact, dtype=bool)
    if mask is not None and mask.shape != shape:
        raise RailContactError(f"initial_contact must have the grid shape {shape}, "
                               f"got {mask.shape}")
    area_el = grid.element_area
    self_compliance = float(operator.self_coefficient[0, 0])  # [m/Pa]

    def finish(p, u, delta, its, converged, message, err, hist):
        contact = p > 0.0
        return NormalResult(
            grid=grid, pressure=p, contact=contact, gap=h + u - delta,
            force=float(p.sum() * area_el), penetration=float(delta),
            max_pressure=float(p.max(initial=0.0)), area=float(contact.sum() * area_el),
            iterations=its, converged=converged, message=message,
            wall_time=time.perf_counter() - t0, error=float(err), history=np.asarray(hist),
            touches_boundary=touches_boundary(contact))

    zeros = np.zeros(shape)
    # Trivial cases: no load, or no interpenetration anywhere.
    if force_control and load == 0.0:
        return finish(zeros, zeros, float(h.min()), 0, True, "no contact: zero load", 0.0, [])
    if not force_control and np.all(h >= penetration):
        return finish(zeros, zeros, penetration, 0, True,
                      "no contact: penetration below the smallest gap", 0.0, [])

    # Start.
    if p is None:
        p = (np.ones(shape) if force_control else _uniform_start(h, operator, penetration))
    else:
        p = np.clip(p, 0.0, None)
    if mask is not None:
        p = np.where(mask, p, 0.0)
    if not np.any(p > 0):
        p = np.where(h <= np.min(h) + 0.0, 1.0, 0.0) if force_control else \
            _uniform_start(h, operator, penetration)
    if force_control:
        p *= load / (area_el * p.sum())

    t = np.zeros(shape)
    g_old = 1.0
    conjugate = False
    hist: list[float] = []
    err = np.inf
    its = 0
    converged = stalled = False
    best, best_its = np.inf, 0
    delta = penetration if not force_control else 0.0
    u_next = None  # u = A p of the current p when already formed
    for its in range(1, int(max_iterations) + 1):
        u = operator.apply(p) if u_next is None else u_next
        u_next = None
        c = p > 0.0
        if not c.any():  # pressure vanished (possible under penetration control)
            c = (h + u - delta) < 0
        g = h + u
        if force_control:
            delta = float(g[c].mean())
        g -= delta
        gc = g[c]  # (the gradient on the contact set, used three times below)
        if precondition is None:
            z = g
        else:
            z = precondition(np.where(c, g, 0.0))
            if force_control:
                z = z - z[c].mean()
        gg = float(np.dot(gc, gc if z is g else z[c]))
        t = np.where(c, z + (gg / g_old if conjugate and g_old > 0 else 0.0) * t, 0.0)
        g_old = gg
        r = operator.apply(t)
        if force_control:
            r -= r[c].mean()
        tc = t[c]
        rt = float(np.dot(r[c], tc))
        if rt <= 0.0 or gg <= 0.0:  # exact solution on the current set
            tau = 0.0
        else:
            tau = float(np.dot(gc, tc)) / rt
        p_old = p
        p = p - tau * t
        np.maximum(p, 0.0, out=p)
        overlap = (p == 0.0) & (g < 0.0)
        conjugate = not overlap.any()
        if not conjugate:
            if tau > 0.0:
                kappa = 1.0 if precondition is None else gg / max(float(np.dot(gc, gc)),
                                                                   1e-300)
                p[overlap] -= tau * kappa * g[overlap]
            else:  # exact on the current set (e.g. a start on two symmetric elements):
                p[overlap] = -g[overlap] / self_compliance  # each closes its own gap
        if force_control:
            total = p.sum()
            if total <= 0.0:
                return finish(p, u, delta, its, False, "pressure vanished", np.inf, hist)
            p *= load / (area_el * total)
        total = p.sum()
        err = float(np.abs(p - p_old).sum() / total) if total > 0 else 0.0
        hist.append(err)
        if not np.isfinite(err):
            break
        if err < tolerance:
            u_next = operator.apply(p)  # reused by the next iteration or the result
            if not _overlaps(h, u_next, p, force_control, delta, tolerance):
                converged = True
                break
        if err < STALL_GAIN * best:
            best, best_its = err, its
        elif its - best_its >= STALL_ITERATIONS:  # at round-off: a tolerance out of reach
            stalled = True
            break

    u = operator.apply(p) if u_next is None else u_next
    c = p > 0.0
    if force_control:
        delta = float((h + u)[c].mean()) if c.any() else float(h.min())
    if converged:
        message = f"converged in {its} iterations (eps = {err:.3g} < {tolerance:g})"
    else:
        message = (f"not converged: eps = {err:.3g} after {its} iterations "
                   f"(tolerance {tolerance:g})")
        if stalled:
            message += (f"; stalled: eps has not fallen below {STALL_GAIN:g} of its best in "
                        f"{STALL_ITERATIONS} iterations")
    res = finish(p, u, delta, its, converged, message, err, hist)
    if res.touches_boundary:
        res.message += "; contact reaches the edge of the potential contact area"
    return res
