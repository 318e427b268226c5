"""Contact problems built on the solvers: one patch (grid -> estimate -> normal BEM ->
tangential solution), the quadratic case, the wheel-rail case and its load loop, and the
result types. Modules import downwards only::

    solve       solve(case): dispatch
    quadratic   wheelrail   the two kinds of case
    loadloop                vertical force, the creep-load secant
    patch                   one patch: grid, estimate, normal and tangential solve
    results                 PatchSolution, Solution
"""

from .patch import (
           normal_estimate,
           simplified_tangential,
           solve_patch_normal,
           solve_patch_tangential,
)
from .results import PatchSolution, Solution
from .solve import solve

__all__ = ["PatchSolution", "Solution", "normal_estimate", "simplified_tangential", "solve",
           "solve_patch_normal", "solve_patch_tangential"]
