"""railcontact: exact wheel–rail rolling contact with fast initial estimates.

Public API
----------
solve(case) -> Solution       solve a case dictionary or TOML file
load_case(path) -> dict       read and validate a TOML case file
hertz(A, B, pair, ...)        Hertz's solution
solve_normal(...)             the normal BEM (Polonsky–Keer CG) on plain arrays
"""

from .case import load_case, validate_case
from .errors import CaseError, RailContactError
from .grid import Grid
from .hertz import HertzSolution, hertz
from .materials import STEEL, ElasticPair, Material
from .normal import NormalResult, solve_normal
from .operator import InfluenceOperator, influence_operator
from .pipeline import PatchSolution, Solution, solve

__version__ = "0.1.0"

__all__ = [
    "STEEL", "CaseError", "ElasticPair", "Grid", "HertzSolution", "InfluenceOperator",
    "Material", "NormalResult", "PatchSolution", "RailContactError", "Solution",
    "hertz", "influence_operator", "load_case", "solve", "solve_normal", "validate_case",
]
