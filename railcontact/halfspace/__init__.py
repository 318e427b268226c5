"""The elastic half-space: what every contact problem here is solved on.

- :mod:`.materials`: ``Material``, the combined constants of two bodies ``ElasticPair``;
- :mod:`.grid`: the rectangular element grid and re-meshing between grids;
- :mod:`.influence`: Love's influence coefficients of uniform tractions on rectangles;
- :mod:`.operator`: the DC-FFT convolution ``InfluenceOperator`` (FFT plans cached);
- :mod:`.hertz`: Hertz's solution, the analytic reference and the simplest estimate.
"""

from .grid import Grid, remesh
from .hertz import HertzSolution, hertz
from .materials import STEEL, ElasticPair, Material
from .operator import InfluenceOperator, influence_operator

__all__ = ["STEEL", "ElasticPair", "Grid", "HertzSolution", "InfluenceOperator", "Material",
           "hertz", "influence_operator", "remesh"]
