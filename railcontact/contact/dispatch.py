"""``solve(case)``: dispatch a case to the quadratic or the wheel-rail solver."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..normal.resolution import under_resolved
from ..settings import Case, load_case, validate_case
from ..settings.case import check_convention
from .patch import not_converged
from .quadratic import solve_quadratic
from .results import PatchSolution, Solution
from .wheelrail import solve_wheel_rail


def solve(case: Case | Mapping[str, Any] | str | Path, *,
          convention: str | None = None) -> Solution:
    """Solve a contact case.

    Parameters
    ----------
    case
        A :class:`~railcontact.settings.Case`, a case dictionary with the tables of a case
        file (:mod:`railcontact.settings.case`), or the path of a TOML case file.
    convention
        ``"railcontact"`` or ``"contact"``: how a wheel-rail case's creepages are read and
        its forces reported (:mod:`railcontact.settings.convention`); replaces the case's
        top-level ``convention`` (default: the case's, ``"railcontact"`` unless it says).

    Returns
    -------
    Solution
        One :class:`~railcontact.contact.PatchSolution` per contact patch, each with the
        work it took over all load passes and re-meshes (``patch.work``; totals in
        ``solution.work``).

    Raises
    ------
    CaseError
        For a case that breaks the schema or cannot be solved as given.

    Notes
    -----
    A patch whose contact spans fewer than
    :data:`~railcontact.normal.resolution.MIN_ELEMENTS_ACROSS` elements along x (the rolling
    direction) is under-resolved: its normal result is not converged, with a message saying so.
    """
    t0 = time.perf_counter()
    case = load_case(case) if isinstance(case, (str, Path)) else validate_case(case)
    if convention is not None:
        case = replace(case, convention=check_convention(convention))
    if case.wheel_rail:
        patches, pose = solve_wheel_rail(case)  # with the tangential problem
        roll = pose.roll
    else:
        patches, roll = [solve_quadratic(case)], None
    patches = [_check_resolution(p) for p in patches]
    return Solution(case=case, patches=patches, roll=roll, seconds=time.perf_counter() - t0)


def _check_resolution(patch: PatchSolution) -> PatchSolution:
    """``patch``, or a new record of it marked not converged, its normal message saying
    so, when it converged but its contact spans fewer than
    :data:`~railcontact.normal.resolution.MIN_ELEMENTS_ACROSS` elements along x (the rolling
    direction): the solve met its tolerance, but its pressure has not converged under grid
    refinement (the case exits 1, as a contact cut off by elements far larger than it)."""
    n = patch.normal
    if not n.converged:
        return patch
    why = under_resolved(n.contact, n.grid.dx, n.grid.dy)
    if why:
        return patch.replaced(normal=not_converged(n, f"{why} ({n.message})"))
    return patch
