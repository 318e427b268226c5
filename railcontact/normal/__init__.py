"""Normal contact: the half-space BEM (Polonsky–Keer) and simplified models."""

from .bem import NormalResult, solve_normal

__all__ = ["NormalResult", "solve_normal"]
