"""``solve(case)``: dispatch a case to the quadratic or the wheel-rail solver."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..settings import Case, load_case, validate_case
from ..settings.case import check_convention
from .quadratic import solve_quadratic
from .results import Solution
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
    """
    t0 = time.perf_counter()
    case = load_case(case) if isinstance(case, (str, Path)) else validate_case(case)
    if convention is not None:
        case = replace(case, convention=check_convention(convention))
    if case.wheel_rail:
        patches, pose = solve_wheel_rail(case)  # with the tangential problem
        return Solution(case=case, patches=patches, roll=pose.roll,
                        seconds=time.perf_counter() - t0)
    return Solution(case=case, patches=[solve_quadratic(case)],
                    seconds=time.perf_counter() - t0)
