"""Contact problems built on the solvers: one patch (grid -> estimate -> normal BEM ->
tangential solution), the quadratic case, the wheel-rail case and its load loop, and the
result types. Modules import downwards only::

    dispatch    solve(case): the quadratic or the wheel-rail solver
    quadratic   wheelrail   the two kinds of case
    loadloop                vertical force, the creep-load loop of every wheel solve
    wheel                   WheelProblem, WheelSettings, WheelSolution: one wheel's records
    patch                   one patch: grid, estimate, normal and tangential solve
    results                 PatchSolution, Solution
    start                   WarmStart: how a patch's solves start
"""

from .dispatch import solve
from .patch import (
           normal_estimate,
           simplified_tangential,
           solve_patch_normal,
           solve_patch_tangential,
)
from .results import PatchSolution, Solution
from .start import NormalStart, TangentialStart, WarmStart

__all__ = ["NormalStart", "PatchSolution", "Solution", "TangentialStart", "WarmStart",
           "normal_estimate", "simplified_tangential", "solve",
           "solve_patch_normal", "solve_patch_tangential"]
