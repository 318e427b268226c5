"""A quadratic gap ``h = A x^2 + B y^2``: one patch, the paper's Hertzian cases."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ..errors import CaseError
from ..halfspace.grid import Grid
from ..halfspace.hertz import hertz
from ..settings import Case, QuadraticGeometry
from .patch import (
    normal_estimate,
    not_converged,
    potential_area,
    solve_patch_normal,
    solve_patch_tangential,
)
from .results import PatchSolution, with_frictional_power


def solve_quadratic(case: Case) -> PatchSolution:
    """The patch of a quadratic case: the normal BEM, then the tangential problem when the
    case has one and the patch carries a load.

    The potential area is the case's ``[grid] x, y`` or the paper's automatic one from
    Hertz's penetration (:func:`~railcontact.contact.patch.potential_area`).
    """
    geo = case.geometry
    if not isinstance(geo, QuadraticGeometry):
        raise CaseError(f"a quadratic case needs a quadratic geometry, got {type(geo).__name__}")
    grid_settings, settings, pair = case.grid, case.normal, case.pair
    A, B = geo.A, geo.B
    control = settings.control
    hz = hertz(A, B, pair, **control.kwargs())
    auto = potential_area(A, B, hz.penetration if hz.penetration > 0 else 1e-12,
                          grid_settings.margin)
    bounds = (*(grid_settings.x or auto[:2]), *(grid_settings.y or auto[2:]))
    if not (bounds[0] < bounds[1] and bounds[2] < bounds[3]):  # (an automatic side)
        key, value = (("load", control.load) if control.by_load
                      else ("penetration", control.penetration))
        raise CaseError(f"[normal] {key} = {value:g} gives a contact too small for floating "
                        f"point numbers: its automatic potential area, {2 * auto[1]:.3g} x "
                        f"{2 * auto[3]:.3g} m, has no extent; give [grid] x and y, or a "
                        f"larger {key}")

    def gap_of(grid: Grid) -> np.ndarray:
        X, Y = grid.mesh()
        return A * X**2 + B * Y**2

    t0 = time.perf_counter()
    s = np.linspace(bounds[2], bounds[3], 2001)
    est = normal_estimate(settings, hz, s, B * s**2, np.full_like(s, A), pair, control)
    res, work = solve_patch_normal(gap_of, bounds, grid_settings, settings, pair, control, est,
                                   grid_settings.automatic, profiles=False)
    work = replace(work, seconds=time.perf_counter() - t0)  # the estimate's set-up included
    if res.force == 0 and res.converged and not control.by_load and res.gap.size:
        res = _between_centres(res, control.penetration, bounds)
    patch = PatchSolution(normal=res, hertz=hz, estimate=est.label, curvatures=(A, B),
                          work=work, start=est)
    if case.tangential is not None and res.force > 0:
        patch = with_frictional_power(
            solve_patch_tangential(patch, case.tangential, pair, settings.fft))
    return patch


def _between_centres(res, penetration: float, bounds: tuple[float, float, float, float]):
    """The normal result ``res`` of a quadratic case under ``penetration`` [m] with no
    element in contact, marked not converged when the contact is there but falls between
    the element centres: the gap's least value, 0 at the origin, lies inside the potential
    area ``bounds`` [m] and below the penetration, yet every element centre's gap is above
    it (a grid too coarse for the contact ellipse, e.g. 2 x 2 elements with none at the
    centre). A potential area that leaves the origin out has no contact: ``res``
    unchanged."""
    x0, x1, y0, y1 = bounds
    if not (penetration > 0 and x0 < 0.0 < x1 and y0 < 0.0 < y1):
        return res
    grid = res.grid
    return not_converged(res, (
        "under-resolved patch: its contact falls between the element centres (the smallest "
        f"gap at one, {(float(res.gap.min()) + penetration) * 1e3:.3g} mm, is above the "
        f"penetration {penetration * 1e3:.3g} mm), elements of {grid.dx * 1e3:.3g} x "
        f"{grid.dy * 1e3:.3g} mm; use smaller elements"))
