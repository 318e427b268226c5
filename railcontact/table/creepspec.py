"""A normalised creep table's specification (``[table] kind = "creep"``) and its
normalisation.

A creep table holds the exact steady-rolling solution of Hertzian elliptic contacts in
the dimensionless variables of Kalker's simplified theory and his book of tables: the
tangential force and spin moment over ``mu N`` against normalised creepages, for each
ellipse ratio ``a/b``, at one Poisson's ratio. With ``c = sqrt(a b)``, the combined shear
modulus ``G``, the normal force ``N``, the coefficient of friction ``mu`` and Kalker's
creep coefficients ``C11, C22, C23`` at ``a/b`` and ``nu`` (Table E.3,
:func:`~railcontact.tangential.kalker.creep_coefficients`)::

    nu_x  = G c^2 C11 xi  / (3 mu N)        normalised longitudinal creepage [-]
    nu_y  = G c^2 C22 eta / (3 mu N)        normalised lateral creepage [-]
    psi   = G c^3 C23 phi / (3 mu N)        normalised spin creepage [-]
    f_x   = F_x / (mu N),  f_y = F_y / (mu N),  m_z = M_z / (mu N c)

so that in the linear theory (small creepages) ``f_x = -3 nu_x``, ``f_y = -3 (nu_y +
psi)``, and ``|f| -> 1`` in full slip; the solution in these variables depends on ``a/b``
and ``nu`` alone (the similarity of Hertzian rolling contact), so one table serves every
load, size, friction and modulus. Forces act on body 1 (the case's convention for a
quadratic gap: ``F_x = -G c^2 C11 xi`` in the linear theory).

The spec is a case file without ``[geometry]`` (the table makes the Hertzian gap of each
ellipse ratio) plus ``[table]``::

    [material]
    young = 206e9                  # Pa (a reference value: the results do not depend on it)
    poisson = 0.28                 # the table's Poisson's ratio (fixed)
    [grid]
    nx = 32                        # elements across the potential area, each patch
    ny = 32
    [tangential]
    friction = 0.3                 # reference values: the results do not depend on them
    [table]
    kind = "creep"
    ellipse_ratio = { values = [0.2, 0.5, 1.0, 2.0, 5.0] }   # a/b [-]
    creepage_x = [-1.5, 1.5, 13]   # nu_x [-]
    creepage_y = [-1.5, 1.5, 13]   # nu_y [-]
    spin = [-1.0, 1.0, 5]          # psi [-]
    out_of_range = "clamp"         # or "status", or per axis

``ellipse_ratio`` is required; a creepage axis left out is 0 (its value fixed). Axes take
the forms of contact tables (:func:`~.spec.axis_values`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import CaseError
from ..halfspace.hertz import curvature_ratio, hertz
from ..halfspace.materials import ElasticPair
from ..settings import Case
from ..settings.case import MAX_CREEPAGE
from ..tangential.kalker import creep_coefficients
from .spec import (
    CREEP_KIND,
    DEFAULT_POLICY,
    MAX_POINTS,
    AxisGrid,
    axis_count,
    axis_values,
    parse_policies,
)

KIND = CREEP_KIND
"""``[table] kind`` of a creep table (:data:`.spec.CREEP_KIND`)."""
RATIO = "ellipse_ratio"
CREEP_AXES: dict[str, tuple[str, str]] = {
    RATIO: ("1", "ellipse ratio a/b (a along the rolling direction)"),
    "creepage_x": ("1", "normalised longitudinal creepage nu_x = G c^2 C11 xi / (3 mu N)"),
    "creepage_y": ("1", "normalised lateral creepage nu_y = G c^2 C22 eta / (3 mu N)"),
    "spin": ("1", "normalised spin psi = G c^3 C23 phi / (3 mu N)"),
}
"""The axes of a creep table: name -> (unit, long name), in storage order."""
CREEPAGES = ("creepage_x", "creepage_y", "spin")
CREEPAGE_WORDS = ("longitudinal creepage", "lateral creepage", "spin")
"""What each of :data:`CREEPAGES` is as a physical creepage (xi [-], eta [-], phi [1/m])."""
OPTIONS = ("kind", "out_of_range")
REFERENCE_LOAD = 100e3
"""The normal force [N] of the solves when the case gives none (the results do not
depend on it)."""
REFERENCE_CURVATURE = 2.0
"""The smaller relative curvature [1/m] of the Hertzian gaps solved (a 0.5 m radius; the
results do not depend on it)."""
SMALLEST_RATIO, LARGEST_RATIO = 0.05, 20.0
"""The range of ellipse ratios a table may have (the BEM grid, nx by ny across the
potential area, resolves the short axis poorly beyond)."""


@dataclass(frozen=True)
class CreepSpec(AxisGrid):
    """A validated creep table specification.

    Attributes
    ----------
    case
        The case dictionary (every default filled in) without a geometry: the material,
        grid, normal load and tangential settings of every solve.
    axes
        Axis name -> strictly increasing node values, in :data:`CREEP_AXES` order (the
        creepage axes given; ``ellipse_ratio`` first).
    out_of_range
        Axis -> what a value outside it gives (``"status"`` or ``"clamp"``).
    """

    case: dict[str, Any]
    axes: dict[str, np.ndarray]
    out_of_range: dict[str, str] = field(default_factory=dict)

    kind = KIND

    @property
    def poisson(self) -> float:
        """The combined Poisson's ratio of the table [-]."""
        return self.pair.poisson

    @property
    def pair(self) -> ElasticPair:
        return Case.from_dict(self.case_at(1.0)).pair

    def policies(self) -> dict[str, str]:
        """Every axis's out-of-range policy."""
        return {n: self.out_of_range.get(n, DEFAULT_POLICY) for n in self.axes}

    def case_at(self, ratio: float, creepage: tuple[float, float, float] = (0.0, 0.0, 0.0)
                ) -> dict[str, Any]:
        """The quadratic case of the ellipse ratio ``ratio`` (a/b) with the physical
        creepages ``creepage`` (xi [-], eta [-], phi [1/m])."""
        A, B = curvatures(ratio)
        out = {k: dict(v) if isinstance(v, dict) else v for k, v in self.case.items()}
        out["geometry"] = {"type": "quadratic", "A": A, "B": B}
        out["tangential"]["creepage"] = [float(c) for c in creepage]
        return out

    def identity(self) -> dict[str, Any]:
        """What makes two creep tables the same: the kind, the case and the axes."""
        return {"kind": KIND, "case": self.case,
                "axes": {n: [float(x) for x in v] for n, v in self.axes.items()}}


def curvatures(ratio: float) -> tuple[float, float]:
    """The relative curvatures (A, B) [1/m] of a Hertzian gap whose contact ellipse has
    ``a/b = ratio`` (a along x), the smaller one :data:`REFERENCE_CURVATURE`."""
    g = min(ratio, 1.0 / ratio)
    r = curvature_ratio(g)  # B_max / B_min: the larger curvature across the short axis
    k = REFERENCE_CURVATURE
    return (k * r, k) if ratio < 1.0 else (k, k * r)


@dataclass(frozen=True)
class CreepScales:
    """The normalisation of one contact (SI units).

    Attributes
    ----------
    a, b
        Semi-axes of the contact ellipse [m] (a along the rolling direction).
    mu_n
        mu N [N].
    coefficients
        Kalker's (C11, C22, C23) at a/b and the table's nu.
    shear
        Combined shear modulus G [Pa].
    """

    a: float
    b: float
    mu_n: float
    coefficients: tuple[float, float, float]
    shear: float

    @property
    def c(self) -> float:
        """sqrt(a b) [m]."""
        return math.sqrt(self.a * self.b)

    def per_creepage(self) -> np.ndarray:
        """d(nu_x, nu_y, psi) / d(xi, eta, phi): ``G c^2 C11 / (3 mu N)``, ``G c^2 C22 /
        (3 mu N)`` [-] and ``G c^3 C23 / (3 mu N)`` [m]."""
        c11, c22, c23 = self.coefficients
        k = self.shear / (3.0 * self.mu_n)
        return np.array([k * self.c**2 * c11, k * self.c**2 * c22, k * self.c**3 * c23])

    def normalised(self, creepage) -> np.ndarray:
        """(nu_x, nu_y, psi) [-] of the creepages (xi [-], eta [-], phi [1/m])."""
        return np.asarray(creepage, dtype=float) * self.per_creepage()

    def physical(self, normalised) -> np.ndarray:
        """(xi [-], eta [-], phi [1/m]) of the normalised creepages."""
        return np.asarray(normalised, dtype=float) / self.per_creepage()


def scales(a: float, b: float, load: float, friction: float, shear: float,
           poisson: float) -> CreepScales:
    """The normalisation of a contact of semi-axes ``a``, ``b`` [m], normal force
    ``load`` [N], coefficient of friction ``friction`` [-], combined shear modulus
    ``shear`` [Pa] and Poisson's ratio ``poisson`` [-]."""
    k = creep_coefficients(a, b, poisson)
    return CreepScales(a=a, b=b, mu_n=friction * load, coefficients=(k.c11, k.c22, k.c23),
                       shear=shear)


def case_scales(case: dict[str, Any]) -> CreepScales:
    """The normalisation of a quadratic case (:meth:`CreepSpec.case_at`): Hertz's
    semi-axes at its load."""
    c = Case.from_dict(case)
    hz = hertz(c.geometry.A, c.geometry.B, c.pair, load=c.normal.load)
    return scales(hz.a, hz.b, c.normal.load, float(c.tangential.friction), c.pair.shear,
                  c.pair.poisson)


def parse_creep_spec(raw: dict[str, Any]) -> CreepSpec:
    """A :class:`CreepSpec` from the tables of a spec file (a case without
    ``[geometry]`` plus ``[table]`` with ``kind = "creep"``).

    Raises
    ------
    CaseError
        For a geometry given, an unknown or missing axis, a bad range, a ratio outside
        [:data:`SMALLEST_RATIO`, :data:`LARGEST_RATIO`], a friction table, a penetration
        instead of a load, a tangential model other than the BEM.
    """
    raw = dict(raw)
    table = dict(raw.pop("table", None) or {})
    if table.get("kind") != KIND:
        raise CaseError(f"a creep table needs [table] kind = '{KIND}', got "
                        f"{table.get('kind')!r}")
    unknown = sorted(set(table) - set(CREEP_AXES) - set(OPTIONS))
    if unknown:
        raise CaseError(f"[table] kind = 'creep': unknown axis {', '.join(unknown)}; known: "
                        f"{', '.join(CREEP_AXES)} (and the option {', '.join(OPTIONS)})")
    if RATIO not in table:
        raise CaseError(f"[table] kind = 'creep' needs an {RATIO} axis (a/b [-], a along "
                        "the rolling direction)")
    names = [n for n in CREEP_AXES if n in table]
    total = math.prod(axis_count(n, table[n]) for n in names)
    if total > MAX_POINTS:
        raise CaseError(f"[table]: {total} points; at most {MAX_POINTS}")
    axes = {n: axis_values(n, table[n]) for n in names}
    ratios = axes[RATIO]
    if ratios[0] < SMALLEST_RATIO or ratios[-1] > LARGEST_RATIO:
        raise CaseError(f"[table] {RATIO}: each a/b must lie in [{SMALLEST_RATIO:g}, "
                        f"{LARGEST_RATIO:g}], got {ratios[0]:g} .. {ratios[-1]:g}")
    if "geometry" in raw:
        raise CaseError("[table] kind = 'creep': the table makes the Hertzian gap of each "
                        "ellipse ratio; remove [geometry]")
    normal = dict(raw.get("normal") or {})
    if "penetration" in normal:
        raise CaseError("[table] kind = 'creep': give [normal] load (a reference value), "
                        "not a penetration")
    normal.setdefault("load", REFERENCE_LOAD)
    tang = dict(raw.get("tangential") or {})
    if "creepage" in tang:
        raise CaseError("[table] kind = 'creep': the creepages are the table's axes; remove "
                        "[tangential] creepage")
    if isinstance(tang.get("friction"), dict):
        raise CaseError("[tangential] friction: a creep table takes one coefficient of "
                        "friction (a reference value)")
    if tang.get("model", "bem") != "bem":
        raise CaseError(f"[table] kind = 'creep' is solved by the exact BEM: [tangential] "
                        f"model must be 'bem', got {tang.get('model')!r}")
    tang["creepage"] = [0.0, 0.0, 0.0]  # each solve's are its node's
    raw["normal"], raw["tangential"] = normal, tang
    probe = Case.from_dict({**raw, "geometry": {"type": "quadratic", "A": 1.0, "B": 1.0}})
    d = probe.to_dict()
    d.pop("geometry", None)
    if not float(probe.tangential.friction) > 0.0:
        raise CaseError("[tangential] friction must be above 0 for a creep table (F/(mu N))")
    if probe.pair.difference != 0.0:
        raise CaseError("[table] kind = 'creep' takes quasi-identical bodies (one material, "
                        "or two of the same (1 - 2 nu)/G): the normalised solution depends on "
                        "a/b and nu alone only then")
    spec = CreepSpec(case=d, axes=axes, out_of_range=parse_policies(table.get("out_of_range"),
                                                                     names))
    _check_physical_creepages(spec)
    return spec


def _check_physical_creepages(spec: CreepSpec) -> None:
    """Raise a :class:`CaseError` naming the creepage axis whose largest node is, at some
    ellipse ratio of the table, a creepage beyond the solver's
    :data:`~railcontact.settings.case.MAX_CREEPAGE` (the nodes are normalised; each solve
    takes the physical creepages of the reference load)."""
    for ratio in spec.axes[RATIO]:
        per = case_scales(spec.case_at(float(ratio))).per_creepage()
        for k, name in enumerate(CREEPAGES):
            nodes = spec.axes.get(name)
            if nodes is None:
                continue
            node = max(nodes, key=abs)
            physical = node / per[k]
            if not abs(physical) <= MAX_CREEPAGE:
                unit = " 1/m" if name == "spin" else ""
                raise CaseError(
                    f"[table] {name}: the node {node:g} is, at {RATIO} = {ratio:g} and the "
                    f"reference load, a {CREEPAGE_WORDS[k]} of {physical:.6g}{unit}; the "
                    f"solver takes at most +-{MAX_CREEPAGE:g}, a normalised "
                    f"{abs(node) * MAX_CREEPAGE / abs(physical):.3g} there (the creep forces "
                    "saturate, full slip, long before)")
