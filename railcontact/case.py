"""Case files: TOML in SI units, loaded into a validated plain dictionary.

Schema (keys not listed here are rejected, so that a typo never goes unnoticed)::

    name = "optional title"

    [material]            # identical bodies, or [wheel, rail] pairs for two materials
    young = 206e9         # Young's modulus E [Pa]
    poisson = 0.28        # Poisson's ratio [-]

    [geometry]
    type = "quadratic"    # undeformed gap h = A x^2 + B y^2
    A = 1.0               # longitudinal relative curvature [1/m]
    B = 5.0               # lateral relative curvature [1/m]

    [geometry]            # ... or a wheel on a rail (railcontact.geometry)
    type = "wheel-rail"
    wheel = "S1002"       # built-in name or file (.prw SIMPACK or two columns y z)
    rail = "60E1"         # built-in (60E1/UIC60, CN60) or file (.prr or two columns)
    profile_unit = "mm"   # unit of two-column profile files
    inclination = 0.025   # rail cant [rad] (1:40); 0 for a file that is canted already
    gauge = 1.435         # [m], measured gauge_depth = 0.014 m below the top of rail
    back_to_back = 1.360  # flange-back distance [m]
    wheel_radius = 0.46   # nominal rolling radius [m]
    lateral_displacement = -0.002  # wheelset, positive to the left [m]
    yaw = 0.0             # [rad]
    roll = 0.0            # [rad], or "rigid" (both wheels touch their rails) or
                          # "equal-loads" (both wheels carry [normal] load; Manchester)
    side = "left"         # "left" | "right" | "both"
    # with wheel-rail, [normal] load is the vertical wheel load [N] and penetration the
    # vertical approach of the wheel [m]

    [grid]                # all optional
    nx = 64               # element counts (default 64 x 64) ...
    ny = 64
    dx = 1e-4             # ... or element sizes [m] (override the counts)
    dy = 1e-4
    x = [-8e-3, 8e-3]     # potential contact area [m]; default automatic (paper Sec. 2.1:
    y = [-4e-3, 4e-3]     #   A x^2 <= delta0, B y^2 <= delta0, delta0 from Hertz), grown
    margin = 1.0          #   when the contact reaches its edge; margin scales it

    [normal]
    load = 83.3e3         # normal force [N] ... (give one of the two)
    penetration = 1e-4    # ... or rigid approach [m]
    estimate = "none"     # initial estimate: "none" | "hertz" | "kp" | "infcon"
    estimate_grid = [40, 40]  # KP/INFCON estimate grid (n_x, n_y), re-meshed onto the BEM
    tolerance = 1e-3      # eps_n, relative pressure change between iterations
    max_iterations = 500
    fft = "auto"          # "auto" | "pyfftw" | "scipy" | "dense"
    preconditioner = "fft"  # "fft" | "none" (plain Polonsky-Keer CG, as in the paper)

    [tangential]          # optional: steady rolling in +x
    creepage = [1e-3, 0.0, 0.0]  # xi [-], eta [-], phi [1/m]
    friction = 0.4        # Coulomb coefficient mu [-]
    model = "bem"         # "bem" | "fastsim" | "fastrip"
    estimate = "none"     # initial estimate of the BEM: "none" | "fastsim" | "fastrip"
    tolerance = 1e-2      # eps_tau, relative traction change between sweeps
    max_iterations = 1000
    bound = "elliptic"    # FASTSIM traction bound: "elliptic" | "parabolic"
    strips = [40, 40]     # samples per strip and strips of FASTSIM/FaStrip
    spin_offset = 0.1667  # where the spin slip is taken in a rolling step (CONTACT: 1/6)
"""

from __future__ import annotations

import copy
import math
import sys
from pathlib import Path
from typing import Any

from .errors import CaseError
from .normal.bem import PRECONDITIONERS
from .operator import BACKENDS

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

NORMAL_ESTIMATES = ("none", "hertz", "kp", "infcon")
TANGENTIAL_MODELS = ("bem", "fastsim", "fastrip")
TANGENTIAL_ESTIMATES = ("none", "fastsim", "fastrip")
GEOMETRY_TYPES = ("quadratic", "wheel-rail")
ROLL_MODES = ("rigid", "equal-loads")

_SCHEMA: dict[str, dict[str, str]] = {
    "material": {"young": "Young's modulus [Pa]", "poisson": "Poisson's ratio [-]"},
    "geometry": {"type": "geometry type", "A": "curvature [1/m]", "B": "curvature [1/m]",
                 "wheel": "profile", "rail": "profile", "inclination": "rad",
                 "gauge": "m", "back_to_back": "m", "wheel_radius": "m",
                 "lateral_displacement": "m", "yaw": "rad", "roll": "rad or mode", "side": "side",
                 "profile_unit": "unit of profile files", "gauge_depth": "m",
                 "flange_back": "m"},
    "grid": {"nx": "element count", "ny": "element count", "dx": "element size [m]",
             "dy": "element size [m]", "x": "x range [m]", "y": "y range [m]",
             "margin": "potential-area scale [-]"},
    "normal": {"load": "force [N]", "penetration": "approach [m]", "estimate": "estimate",
               "tolerance": "eps_n", "max_iterations": "count", "fft": "FFT backend",
               "estimate_grid": "[nx, ny] of KP/INFCON", "preconditioner": "preconditioner"},
    "tangential": {"creepage": "[xi, eta, phi]", "friction": "mu [-]", "model": "model",
                   "estimate": "estimate", "tolerance": "eps_tau", "max_iterations": "count",
                   "bound": "traction bound", "strips": "[nx, ny]",
                   "spin_offset": "fraction of dx"},
}
_REQUIRED_TABLES = ("material", "geometry", "normal")


def load_case(path: str | Path) -> dict[str, Any]:
    """Read a TOML case file and return the validated case dictionary.

    Raises
    ------
    CaseError
        When the file does not exist, does not parse, or breaks the schema.
    """
    p = Path(path)
    if not p.is_file():
        raise CaseError(f"case file not found: {p}")
    try:
        with p.open("rb") as f:
            raw = tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"case file {p} is not valid TOML: {exc}") from None
    raw.setdefault("name", p.stem)
    return validate_case(raw)


def _number(table: str, key: str, value: Any, *, positive: bool = True,
            allow_zero: bool = False) -> float:
    where = f"[{table}] {key}"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise CaseError(f"{where} must be a number, got {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise CaseError(f"{where} must be finite, got {x}")
    if positive and (x < 0 or (x == 0 and not allow_zero)):
        raise CaseError(f"{where} must be {'non-negative' if allow_zero else 'positive'}, "
                        f"got {x:g}")
    return x


def _integer(table: str, key: str, value: Any, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise CaseError(f"[{table}] {key} must be an integer >= {minimum}, got {value!r}")
    return value


def _choice(table: str, key: str, value: Any, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise CaseError(f"[{table}] {key} must be one of {', '.join(map(repr, choices))}, "
                        f"got {value!r}")
    return value


def _range(table: str, key: str, value: Any) -> list[float]:
    if not isinstance(value, list) or len(value) != 2:
        raise CaseError(f"[{table}] {key} must be a list [min, max] in m, got {value!r}")
    lo = _number(table, f"{key}[0]", value[0], positive=False)
    hi = _number(table, f"{key}[1]", value[1], positive=False)
    if not hi > lo:
        raise CaseError(f"[{table}] {key} must be increasing, got {value!r}")
    return [lo, hi]


def validate_case(case: dict[str, Any]) -> dict[str, Any]:
    """Check a case dictionary against the schema, fill defaults, return a new dictionary.

    Raises
    ------
    CaseError
        Naming the table and key at fault.
    """
    if not isinstance(case, dict):
        raise CaseError(f"a case must be a dictionary of tables, got {type(case).__name__}")
    c = copy.deepcopy(case)
    unknown = set(c) - set(_SCHEMA) - {"name"}
    if unknown:
        raise CaseError(f"unknown table(s) {sorted(unknown)}; known: {sorted(_SCHEMA)}")
    for t in _REQUIRED_TABLES:
        if t not in c:
            raise CaseError(f"missing table [{t}]")
    c.setdefault("grid", {})
    for table, keys in _SCHEMA.items():
        if table not in c:
            continue
        if not isinstance(c[table], dict):
            raise CaseError(f"[{table}] must be a table, got {c[table]!r}")
        bad = set(c[table]) - set(keys)
        if bad:
            raise CaseError(f"unknown key(s) {sorted(bad)} in [{table}]; known: {sorted(keys)}")

    mat = c["material"]
    for key in ("young", "poisson"):
        if key not in mat:
            raise CaseError(f"missing [material] {key}")
        vals = mat[key] if isinstance(mat[key], list) else [mat[key]]
        if len(vals) not in (1, 2):
            raise CaseError(f"[material] {key} must be one value or two (body 1, body 2)")
        for i, v in enumerate(vals):
            x = _number("material", key if len(vals) == 1 else f"{key}[{i}]", v,
                        positive=key == "young", allow_zero=False)
            if key == "poisson" and not 0.0 <= x < 0.5:
                raise CaseError(f"[material] poisson must lie in [0, 0.5), got {x:g}")

    geo = c["geometry"]
    geo["type"] = _choice("geometry", "type", geo.get("type", "quadratic"), GEOMETRY_TYPES)
    if geo["type"] == "quadratic":
        for key in ("A", "B"):
            if key not in geo:
                raise CaseError(f"missing [geometry] {key} (curvature [1/m])")
            _number("geometry", key, geo[key])
    else:
        _validate_wheel_rail(geo)

    grid = c["grid"]
    for key in ("nx", "ny"):
        grid[key] = _integer("grid", key, grid.get(key, 64), 2)
    for key in ("dx", "dy"):
        if key in grid:
            _number("grid", key, grid[key])
    for key in ("x", "y"):
        if key in grid:
            grid[key] = _range("grid", key, grid[key])
    grid["margin"] = _number("grid", "margin", grid.get("margin", 1.0))

    nor = c["normal"]
    has_load, has_pen = "load" in nor, "penetration" in nor
    if has_load == has_pen:
        raise CaseError("[normal] needs exactly one of load [N] and penetration [m]")
    key = "load" if has_load else "penetration"
    nor[key] = _number("normal", key, nor[key], allow_zero=True)
    nor["estimate"] = _choice("normal", "estimate", nor.get("estimate", "none"),
                              NORMAL_ESTIMATES)
    nor["tolerance"] = _number("normal", "tolerance", nor.get("tolerance", 1e-3))
    nor["max_iterations"] = _integer("normal", "max_iterations", nor.get("max_iterations", 500),
                                     1)
    nor["fft"] = _choice("normal", "fft", nor.get("fft", "auto"), BACKENDS)
    nor["preconditioner"] = _choice("normal", "preconditioner",
                                    nor.get("preconditioner", "fft"), PRECONDITIONERS)
    eg = nor.get("estimate_grid", [40, 40])
    if not isinstance(eg, list) or len(eg) != 2:
        raise CaseError(f"[normal] estimate_grid must be [nx, ny], got {eg!r}")
    nor["estimate_grid"] = [_integer("normal", f"estimate_grid[{i}]", v, 4)
                            for i, v in enumerate(eg)]
    if geo.get("roll") == "equal-loads" and not has_load:
        raise CaseError("[geometry] roll = 'equal-loads' needs [normal] load (the load of each "
                        "wheel [N]); with a penetration use roll = 'rigid' or a number")
    if "tangential" in c:
        _validate_tangential(c["tangential"])
    c.setdefault("name", "case")
    return c


def _validate_wheel_rail(geo: dict[str, Any]) -> None:
    for key in ("A", "B"):
        if key in geo:
            raise CaseError(f"[geometry] {key} is for type = 'quadratic'; a wheel-rail case "
                            "computes its curvatures from the profiles")
    geo.setdefault("wheel", "S1002")
    geo.setdefault("rail", "60E1")
    for key in ("wheel", "rail"):
        if not isinstance(geo[key], str) or not geo[key]:
            raise CaseError(f"[geometry] {key} must be a built-in name or a file path")
    defaults = {"inclination": math.atan(1 / 40), "gauge": 1.435, "back_to_back": 1.360,
                "wheel_radius": 0.46, "gauge_depth": 0.014, "flange_back": -0.070}
    for key, val in defaults.items():
        geo[key] = _number("geometry", key, geo.get(key, val),
                           positive=key not in ("inclination", "flange_back"))
    for key in ("lateral_displacement", "yaw"):
        geo[key] = _number("geometry", key, geo.get(key, 0.0), positive=False)
    roll = geo.get("roll", 0.0)
    if isinstance(roll, str):
        geo["roll"] = _choice("geometry", "roll", roll, ROLL_MODES)
    else:
        geo["roll"] = _number("geometry", "roll", roll, positive=False)
    geo["side"] = _choice("geometry", "side", geo.get("side", "left"),
                          ("left", "right", "both"))
    geo["profile_unit"] = _choice("geometry", "profile_unit", geo.get("profile_unit", "mm"),
                                  ("m", "mm", "cm", "in"))


def _validate_tangential(tan: dict[str, Any]) -> None:
    cr = tan.get("creepage")
    if not isinstance(cr, list) or len(cr) != 3:
        raise CaseError(f"[tangential] creepage must be [xi, eta, phi] (-, -, 1/m), got {cr!r}")
    tan["creepage"] = [_number("tangential", f"creepage[{i}]", v, positive=False)
                       for i, v in enumerate(cr)]
    if "friction" not in tan:
        raise CaseError("missing [tangential] friction (Coulomb coefficient mu)")
    tan["friction"] = _number("tangential", "friction", tan["friction"], allow_zero=True)
    tan["model"] = _choice("tangential", "model", tan.get("model", "bem"), TANGENTIAL_MODELS)
    tan["estimate"] = _choice("tangential", "estimate", tan.get("estimate", "none"),
                              TANGENTIAL_ESTIMATES)
    tan["tolerance"] = _number("tangential", "tolerance", tan.get("tolerance", 1e-2))
    tan["max_iterations"] = _integer("tangential", "max_iterations",
                                     tan.get("max_iterations", 1000), 1)
    tan["bound"] = _choice("tangential", "bound", tan.get("bound", "elliptic"),
                           ("elliptic", "parabolic"))
    strips = tan.get("strips", [40, 40])
    if not isinstance(strips, list) or len(strips) != 2:
        raise CaseError(f"[tangential] strips must be [nx, ny], got {strips!r}")
    tan["strips"] = [_integer("tangential", f"strips[{i}]", v, 2) for i, v in enumerate(strips)]
    off = _number("tangential", "spin_offset", tan.get("spin_offset", 1.0 / 6.0),
                  positive=True, allow_zero=True)
    if off > 1.0:
        raise CaseError(f"[tangential] spin_offset must lie in [0, 1], got {off:g}")
    tan["spin_offset"] = off
