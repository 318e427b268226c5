"""Elastic constants of the two contacting bodies and their combined parameters.

Wheel and rail are both modelled as linearly elastic half-spaces. Kalker's combined
parameters (as in CONTACT, ``m_hierarch_data.f90:combin_mater``) describe the pair:

* ``1/G = (1/G1 + 1/G2) / 2``                       combined shear modulus [Pa]
* ``nu = (G/2) (nu1/G1 + nu2/G2)``                   combined Poisson's ratio [-]
* ``K = (G/4) ((1-2 nu1)/G1 - (1-2 nu2)/G2)``        difference parameter [-]
* ``E* = G / (1 - nu)``                              contact modulus [Pa]

For two identical bodies ``E* = E / (2 (1 - nu^2))`` (Johnson's E*), and in general
``1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2``. ``K = 0`` for quasi-identical materials, which
decouples the normal and tangential problems.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import RailContactError, check_positive


@dataclass(frozen=True)
class Material:
    """An isotropic linearly elastic material.

    Parameters
    ----------
    young
        Young's modulus E [Pa].
    poisson
        Poisson's ratio nu [-], in [0, 0.5).
    """

    young: float
    poisson: float

    def __post_init__(self) -> None:
        check_positive("young", self.young, "Pa")
        nu = float(self.poisson)
        if not (0.0 <= nu < 0.5):
            raise RailContactError(f"poisson must lie in [0, 0.5), got {self.poisson!r}")

    @property
    def shear(self) -> float:
        """Shear modulus G = E / (2 (1 + nu)) [Pa]."""
        return self.young / (2.0 * (1.0 + self.poisson))


STEEL = Material(young=206e9, poisson=0.28)
"""Wheel and rail steel as used in the paper (E = 206 GPa, nu = 0.28)."""


@dataclass(frozen=True)
class ElasticPair:
    """Combined elastic parameters of two bodies in contact (Kalker's convention).

    Attributes
    ----------
    shear
        Combined shear modulus G [Pa].
    poisson
        Combined Poisson's ratio nu [-].
    difference
        Kalker's difference parameter K [-]; zero for quasi-identical materials.
    """

    shear: float
    poisson: float
    difference: float = 0.0

    @property
    def e_star(self) -> float:
        """Contact modulus E* = G / (1 - nu) [Pa] (Johnson's E* of the pair)."""
        return self.shear / (1.0 - self.poisson)

    @classmethod
    def of(cls, body1: Material, body2: Material | None = None) -> ElasticPair:
        """Combine two materials (or one material with itself)."""
        body2 = body1 if body2 is None else body2
        g1, g2 = body1.shear, body2.shear
        g = 2.0 / (1.0 / g1 + 1.0 / g2)
        nu = 0.5 * g * (body1.poisson / g1 + body2.poisson / g2)
        k = 0.25 * g * ((1.0 - 2.0 * body1.poisson) / g1 - (1.0 - 2.0 * body2.poisson) / g2)
        return cls(shear=g, poisson=nu, difference=k)

    @classmethod
    def from_shear(cls, shear: float, poisson: float) -> ElasticPair:
        """Identical bodies given by their shear modulus G [Pa] and Poisson's ratio."""
        return cls.of(Material(young=2.0 * shear * (1.0 + poisson), poisson=poisson))
