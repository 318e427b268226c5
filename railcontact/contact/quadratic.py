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

    def gap_of(grid: Grid) -> np.ndarray:
        X, Y = grid.mesh()
        return A * X**2 + B * Y**2

    t0 = time.perf_counter()
    s = np.linspace(bounds[2], bounds[3], 2001)
    est = normal_estimate(settings, hz, s, B * s**2, np.full_like(s, A), pair, control)
    res, work = solve_patch_normal(gap_of, bounds, grid_settings, settings, pair, control, est,
                                   grid_settings.automatic, profiles=False)
    work = replace(work, seconds=time.perf_counter() - t0)  # the estimate's set-up included
    patch = PatchSolution(normal=res, hertz=hz, estimate=est.label, curvatures=(A, B),
                          work=work, start=est)
    if case.tangential is not None and res.force > 0:
        patch = with_frictional_power(
            solve_patch_tangential(patch, case.tangential, pair, settings.fft))
    return patch
