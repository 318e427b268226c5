"""Tangential contact: steady-rolling BEM (SteadyGS, ConvexGS), FASTSIM, FaStrip, Kalker's
coefficients."""

from .convexgs import TangentialResult, solve_tangential
from .kalker import CreepCoefficients, creep_coefficients
from .rolling import rigid_slip, rolling_operator, steady_rolling_kernels
from .steadygs import solve_steadygs

SOLVERS = {"steadygs": solve_steadygs, "convexgs": solve_tangential}
"""The exact steady-rolling solvers by name (one signature, one result type); the first is
the default: the fastest."""

__all__ = ["SOLVERS", "CreepCoefficients", "TangentialResult", "creep_coefficients",
           "rigid_slip", "rolling_operator", "solve_steadygs", "solve_tangential",
           "steady_rolling_kernels"]
