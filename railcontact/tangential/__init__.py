"""Tangential contact: steady-rolling BEM (ConvexGS), FASTSIM, FaStrip, Kalker's coefficients."""

from .convexgs import TangentialResult, solve_tangential
from .kalker import CreepCoefficients, creep_coefficients
from .rolling import rigid_slip, rolling_operator, steady_rolling_kernels

__all__ = ["CreepCoefficients", "TangentialResult", "creep_coefficients", "rigid_slip",
           "rolling_operator", "solve_tangential", "steady_rolling_kernels"]
