"""From a validated case to a solution: geometry -> grid -> estimate -> BEM -> result."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .case import load_case, validate_case
from .errors import CaseError
from .grid import Grid
from .hertz import HertzSolution, hertz
from .materials import ElasticPair, Material
from .normal import NormalResult, solve_normal
from .normal.virtual import virtual_penetration
from .operator import influence_operator
from .tangential import TangentialResult, rolling_operator, solve_tangential
from .tangential.fastrip import fastrip, fastrip_hertz
from .tangential.fastsim import fastsim, fastsim_hertz, flexibilities
from .tangential.strips import (
    StripResult,
    equivalent_ellipse,
    remesh_strips,
    sample_on_strips,
    strips_from_contact,
)

GROW_FACTOR = 1.5
MAX_GROW = 4


@dataclass
class PatchSolution:
    """Solution on one contact patch.

    Attributes
    ----------
    normal
        The BEM normal solution.
    hertz
        Hertz's solution for the same curvatures and the same load (force control) or
        penetration (penetration control), for comparison and as an estimate.
    estimate
        The name of the initial estimate used.
    """

    normal: NormalResult
    hertz: HertzSolution | None = None
    estimate: str = "none"
    tangential: TangentialResult | StripResult | None = None
    tangential_model: str = "bem"
    tangential_estimate: str = "none"
    curvatures: tuple[float, float] | None = None
    geometry: Any = None

    def to_dict(self) -> dict[str, Any]:
        n = self.normal
        d: dict[str, Any] = {
            "normal": {
                "force": n.force, "penetration": n.penetration,
                "max_pressure": n.max_pressure, "area": n.area,
                "iterations": n.iterations, "converged": n.converged,
                "message": n.message, "wall_time": n.wall_time, "error": n.error,
                "estimate": self.estimate,
                "grid": {"nx": n.grid.nx, "ny": n.grid.ny, "dx": n.grid.dx, "dy": n.grid.dy,
                         "bounds": list(n.grid.bounds)},
            }
        }
        if self.geometry is not None:
            g = self.geometry
            d["side"] = g.side
            d["contact_point"] = list(g.position)
            d["contact_angle"] = g.contact_angle
            d["rolling_radius"] = g.rolling_radius
            d["wheel_profile_coordinate"] = g.wheel_s
            d["rail_profile_coordinate"] = g.rail_y
            d["curvatures"] = [g.A, g.B]
            d["gap"] = g.gap
        if self.tangential is not None:
            t = self.tangential
            d["tangential"] = {
                "force": list(t.force), "spin_moment": t.spin_moment,
                "slip_area_ratio": t.slip_area_ratio, "max_traction": t.max_traction,
                "iterations": t.iterations, "converged": t.converged, "message": t.message,
                "wall_time": t.wall_time, "model": self.tangential_model,
                "estimate": self.tangential_estimate,
            }
        if self.hertz is not None:
            h = self.hertz
            d["hertz"] = {"a": h.a, "b": h.b, "force": h.load, "penetration": h.penetration,
                          "max_pressure": h.max_pressure, "area": h.area}
        return d


@dataclass
class Solution:
    """The solution of a case: one entry per contact patch.

    ``roll`` [rad] is the wheelset roll the wheel-rail patches were solved at (resolved
    when the case gives ``roll = "rigid"`` or ``"equal-loads"``); None for a quadratic case.
    """

    case: dict[str, Any]
    patches: list[PatchSolution] = field(default_factory=list)
    roll: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (SI units)."""
        d: dict[str, Any] = {"name": self.case.get("name", "case")}
        if self.roll is not None:
            d["roll"] = self.roll
        d["patches"] = [p.to_dict() for p in self.patches]
        return d


def elastic_pair(material: dict[str, Any]) -> ElasticPair:
    """Combined elastic parameters from the case's [material] table."""
    young, poisson = material["young"], material["poisson"]
    ys = young if isinstance(young, list) else [young]
    ns = poisson if isinstance(poisson, list) else [poisson]
    if len(ys) == 1 and len(ns) == 2:
        ys = ys * 2
    if len(ns) == 1 and len(ys) == 2:
        ns = ns * 2
    bodies = [Material(float(e), float(n)) for e, n in zip(ys, ns, strict=True)]
    return ElasticPair.of(*bodies)


def potential_area(A: float, B: float, delta0: float, margin: float = 1.0
                   ) -> tuple[float, float, float, float]:
    """Potential contact area for a quadratic gap (paper Sec. 2.1) [m].

    ``A x^2 <= delta0`` and ``B y^2 <= delta0``, i.e. the rigid interpenetration region
    for the estimated penetration ``delta0``, scaled by ``margin``. It contains the Hertz
    ellipse, since ``A a^2 + B b^2 = delta0``.
    """
    xl = margin * math.sqrt(delta0 / A)
    yl = margin * math.sqrt(delta0 / B)
    return (-xl, xl, -yl, yl)


def _make_grid(spec: dict[str, Any], bounds: tuple[float, float, float, float]) -> Grid:
    """The BEM grid on ``bounds`` [m] from the counts or element sizes of ``spec``.

    With element sizes, ``quantum`` rounds the counts up to a multiple (fewer distinct
    influence operators in a time series) and ``snap`` puts the grid centre on a multiple
    of the element size, so that the grids of consecutive time steps share one lattice
    around the contact point and a warm start is not smeared by interpolation.
    """
    xmin, xmax, ymin, ymax = bounds
    nx, ny = spec["nx"], spec["ny"]
    q = spec.get("quantum", 1)
    extra = 1 if spec.get("snap") else 0
    if "dx" in spec:
        dx = spec["dx"]
        nx = max(2, q * math.ceil(((xmax - xmin) / dx + extra) / q - 1e-9))
        xc = 0.5 * (xmin + xmax)
        xc = round(xc / dx) * dx if extra else xc
        xmin, xmax = xc - nx * dx / 2, xc + nx * dx / 2
    if "dy" in spec:
        dy = spec["dy"]
        ny = max(2, q * math.ceil(((ymax - ymin) / dy + extra) / q - 1e-9))
        yc = 0.5 * (ymin + ymax)
        yc = round(yc / dy) * dy if extra else yc
        ymin, ymax = yc - ny * dy / 2, yc + ny * dy / 2
    return Grid.from_bounds(xmin, xmax, ymin, ymax, nx, ny)


def solve(case: dict[str, Any] | str | Path) -> Solution:
    """Solve a contact case.

    Parameters
    ----------
    case
        A case dictionary (schema in :mod:`railcontact.case`) or the path of a TOML file.

    Returns
    -------
    Solution
    """
    case = load_case(case) if isinstance(case, (str, Path)) else validate_case(case)
    pair = elastic_pair(case["material"])
    if case["geometry"]["type"] == "wheel-rail":
        from .wheelrail import solve_wheel_rail

        patches, pose = solve_wheel_rail(case, pair)  # with the tangential problem
        return Solution(case=case, patches=patches, roll=pose.roll)
    patch = _solve_quadratic(case, pair)
    if "tangential" in case and patch.normal.force > 0:
        solve_patch_tangential(patch, case["tangential"], pair, case["normal"]["fft"])
    return Solution(case=case, patches=[patch])


def normal_estimate(nspec: dict[str, Any], hz: HertzSolution | None, s: np.ndarray,
                    f: np.ndarray, a_of_s: np.ndarray, pair: ElasticPair,
                    control: dict[str, float]) -> Callable[[Grid], np.ndarray | None]:
    """The case's initial estimate of the pressure, as a function of the BEM grid.

    "hertz": Hertz's pressure at the element centres; "kp" / "infcon": the virtual
    penetration model, its amplitude set on its estimate grid (``[normal] estimate_grid``),
    evaluated at the BEM element centres; "none": no estimate.
    """
    method = nspec["estimate"]
    if method == "hertz" and hz is not None:
        return lambda grid: hz.pressure(*grid.mesh())
    if method in ("kp", "infcon"):
        nx, ny = nspec["estimate_grid"]
        est = virtual_penetration(method, s, f, a_of_s, pair, nx=nx, ny=ny, **control)
        return lambda grid: est.pressure_at(*grid.mesh())
    return lambda grid: None


def solve_patch_normal(gap_of: Callable[[Grid], np.ndarray], bounds, gspec: dict[str, Any],
                       nspec: dict[str, Any], pair: ElasticPair, control: dict[str, float],
                       estimate_of: Callable[[Grid], np.ndarray | None],
                       automatic: bool = True) -> NormalResult:
    """BEM normal solution of one patch on the potential area ``bounds`` [m].

    ``gap_of(grid)`` gives the undeformed gap on a grid, ``estimate_of(grid)`` the initial
    pressure (or None); ``control`` is ``{"load": N}`` or ``{"penetration": delta}``. An
    automatic area is grown by :data:`GROW_FACTOR` while the contact reaches its edge; a
    user-given one that is too small is an error.
    """
    for _ in range(MAX_GROW + 1):
        grid = _make_grid(gspec, bounds)
        op = influence_operator(grid, pair, "z", nspec["fft"])
        p0 = estimate_of(grid)
        res = solve_normal(gap_of(grid), grid, op, initial_pressure=p0,
                           tolerance=nspec["tolerance"], max_iterations=nspec["max_iterations"],
                           preconditioner=nspec.get("preconditioner", "fft"), **control)
        if not res.touches_boundary:
            return res
        if not automatic:
            raise CaseError(
                "potential contact area too small: the contact reaches the edge of [grid] "
                f"x = {gspec.get('x')} , y = {gspec.get('y')} m; enlarge it or leave x and y "
                "out for an automatic area")
        xmin, xmax, ymin, ymax = bounds
        xc, yc = 0.5 * (xmin + xmax), 0.5 * (ymin + ymax)
        bounds = (xc + (xmin - xc) * GROW_FACTOR, xc + (xmax - xc) * GROW_FACTOR,
                  yc + (ymin - yc) * GROW_FACTOR, yc + (ymax - yc) * GROW_FACTOR)
    return res


def _solve_quadratic(case: dict[str, Any], pair: ElasticPair) -> PatchSolution:
    geo, gspec, nspec = case["geometry"], case["grid"], case["normal"]
    A, B = float(geo["A"]), float(geo["B"])
    control = {"load": nspec["load"]} if "load" in nspec else {
        "penetration": nspec["penetration"]}
    hz = hertz(A, B, pair, **control)
    automatic = "x" not in gspec or "y" not in gspec
    auto = potential_area(A, B, hz.penetration if hz.penetration > 0 else 1e-12,
                          gspec["margin"])
    bounds = (*gspec.get("x", auto[:2]), *gspec.get("y", auto[2:]))

    def gap_of(grid: Grid) -> np.ndarray:
        X, Y = grid.mesh()
        return A * X**2 + B * Y**2

    s = np.linspace(bounds[2], bounds[3], 2001)
    est = normal_estimate(nspec, hz, s, B * s**2, np.full_like(s, A), pair, control)
    res = solve_patch_normal(gap_of, bounds, gspec, nspec, pair, control, est, automatic)
    return PatchSolution(normal=res, hertz=hz, estimate=nspec["estimate"], curvatures=(A, B))


def simplified_tangential(model: str, hz: HertzSolution, pair: ElasticPair,
                          tspec: dict[str, Any], normal: NormalResult | None = None
                          ) -> StripResult:
    """FASTSIM or FaStrip with the case's settings.

    Without ``normal``: on the Hertz ellipse ``hz`` (elliptic or parabolic bound). With a
    normal solution: on the actual patch (strips along its contact rows, its pressure as the
    traction bound) with the coefficients of its equivalent ellipse - the adaptation for
    non-elliptic wheel-rail patches.
    """
    nx, ny = tspec["strips"]
    mu, creepage = tspec["friction"], tuple(tspec["creepage"])
    if normal is None:
        args = (hz.a, hz.b, hz.load, pair, mu, creepage)
        if model == "fastsim":
            return fastsim_hertz(*args, nx=nx, ny=ny, bound=tspec["bound"])
        return fastrip_hertz(*args, nx=nx, ny=ny)
    strips = strips_from_contact(normal.grid, normal.contact, nx)
    pn = sample_on_strips(normal.pressure, normal.grid, strips)
    a_eq, b_eq = equivalent_ellipse(normal.grid, normal.contact)
    if model == "fastsim":
        return fastsim(strips, pn, mu, creepage, flexibilities(a_eq, b_eq, pair))
    return fastrip(strips, pn, normal.force, a_eq, b_eq, pair, mu, creepage)


def solve_patch_tangential(patch: PatchSolution, tspec: dict[str, Any], pair: ElasticPair,
                           fft: str, previous: tuple | None = None) -> None:
    """Add the tangential solution to ``patch`` (same grid as its normal solution).

    ``previous`` = (traction (2, nx, ny) [Pa], adhesion/slip map) on the patch's grid, e.g.
    the previous time step's: when it holds a traction it starts the BEM instead of the
    estimate asked for in ``tspec``.
    """
    res = patch.normal
    A, B = patch.curvatures
    # The simplified models work on the Hertz ellipse that carries the BEM's normal force.
    hz = hertz(A, B, pair, load=res.force) if res.force > 0 else None
    model, estimate = tspec["model"], tspec["estimate"]
    patch.tangential_model, patch.tangential_estimate = model, estimate
    actual = res if patch.geometry is not None else None  # wheel-rail: non-elliptic patch
    if model != "bem":
        if hz is None:
            raise CaseError("no contact: the simplified tangential models need a load")
        patch.tangential = simplified_tangential(model, hz, pair, tspec, actual)
        return
    p0, st0 = previous if previous is not None else (None, None)
    if p0 is None and estimate != "none" and hz is not None:
        p0, st0 = remesh_strips(simplified_tangential(estimate, hz, pair, tspec, actual),
                                res.grid)
    patch.tangential = solve_tangential(
        res.grid, rolling_operator(res.grid, pair, fft), res.pressure, tspec["friction"],
        tuple(tspec["creepage"]), initial_traction=p0, initial_state=st0,
        tolerance=tspec["tolerance"], max_iterations=tspec["max_iterations"],
        spin_offset=tspec["spin_offset"])

