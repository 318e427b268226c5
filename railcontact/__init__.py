"""railcontact: exact wheel–rail rolling contact with fast initial estimates.

The package is layered; each layer imports only the ones below it (checked by
import-linter, contract in ``pyproject.toml``; see ``docs/architecture.md``)::

    cli                         the railcontact command
    sim                         wheelset dynamics, co-simulation, demo
    fmu  | io  | table          the FMU's variables and build | JSON, plots | contact tables
    timestep                    WheelsetContact: both wheels per step, warm start
    contact                     one patch; quadratic and wheel-rail cases; load loop; results
    settings                    typed settings records, case files
    geometry | normal | tangential   profiles, contact search | normal BEM, KP, INFCON |
                                tangential BEM, FASTSIM, FaStrip, Kalker
    halfspace                   materials, grid, influence coefficients, DC-FFT, Hertz
    status                      the one status vocabulary (Status, status_of)
    errors

Public API
----------
solve(case) -> Solution        solve a case (Case, dictionary or TOML file)
load_case(path) -> Case        read and validate a TOML case file
hertz(A, B, pair, ...)         Hertz's solution
solve_normal(...)              the normal BEM (Polonsky–Keer CG) on plain arrays
solve_tangential(...)          the steady-rolling tangential BEM (ConvexGS) on plain arrays
WheelsetContact, ContactSettings, Kinematics   the time-step solver
WheelsetPool, WheelsetDescription   wheelsets stepped at once in worker processes
"""

from . import _kernelcache  # noqa: F401  (first: keys the kernels' caches)
from ._moved import install as _install_moved
from .contact import PatchSolution, Solution, solve
from .errors import CaseError, ConvergenceError, RailContactError, SolverError
from .geometry import Profile, read_profile
from .geometry.track import Pose, Track, Wheelset
from .halfspace import (
    STEEL,
    ElasticPair,
    Grid,
    HertzSolution,
    InfluenceOperator,
    Material,
    hertz,
    influence_operator,
)
from .normal import NormalResult, solve_normal
from .settings import (
    Case,
    ContactSettings,
    GridSettings,
    NormalSettings,
    TangentialSettings,
    load_case,
    validate_case,
)
from .status import Status
from .tangential import TangentialResult, rolling_operator, solve_tangential
from .timestep import (
    Kinematics,
    RailDeviation,
    WheelContact,
    WheelsetContact,
    WheelsetDescription,
    WheelsetPool,
    WheelsetResult,
)

_install_moved()  # the module paths of 0.1 still import, with a DeprecationWarning

__version__ = "0.1.0"

__all__ = [
    "STEEL", "Case", "CaseError", "ContactSettings", "ConvergenceError", "ElasticPair", "Grid",
    "GridSettings", "HertzSolution", "InfluenceOperator", "Kinematics", "Material", "RailDeviation",
    "NormalResult", "NormalSettings", "PatchSolution", "Pose", "Profile", "RailContactError",
    "Solution", "SolverError", "Status", "TangentialResult", "TangentialSettings", "Track",
    "WheelContact", "Wheelset", "WheelsetContact", "WheelsetDescription", "WheelsetPool",
    "WheelsetResult", "hertz",
    "influence_operator", "load_case", "read_profile", "rolling_operator", "solve",
    "solve_normal", "solve_tangential", "validate_case",
]
