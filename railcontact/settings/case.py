"""The settings of a contact case, one frozen record per table of a case file.

A case file is TOML in SI units; :func:`load_case` reads one and :meth:`Case.from_dict`
builds the same :class:`Case` from a dictionary with the same tables. Keys not declared
here are rejected, so a typo never goes unnoticed; every problem of a case is reported at
once. The reference of every key (default, unit, rule) is generated from these
declarations: ``railcontact settings`` or ``docs/settings.md``.

Example::

    name = "optional title"

    [material]            # identical bodies, or [wheel, rail] pairs for two materials
    young = 206e9
    poisson = 0.28

    [geometry]
    type = "quadratic"    # h = A x^2 + B y^2 (or "wheel-rail": profiles, see below)
    A = 1.0
    B = 5.0

    [normal]
    penetration = 1e-4    # or load = ... [N]

    [tangential]          # optional: steady rolling in +x
    creepage = [1e-3, 0.0, 0.0]
    friction = 0.4

    [kinematics]          # wheel-rail, instead of creepage: velocities [m/s, rad/s]
    speed = 30.0
"""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from dataclasses import MISSING, dataclass, fields
from pathlib import Path
from typing import Any, ClassVar

from ..errors import CaseError
from ..geometry.kinematics import WheelsetMotion
from ..geometry.separation import PatchSeparation
from ..geometry.track import MAX_POSE_ANGLE, Track, Wheelset
from ..halfspace.materials import ElasticPair, Material
from .choices import (
    CASE_SIDES,
    CONVENTIONS,
    FFT_BACKENDS,
    GEOMETRY_TYPES,
    NORMAL_ESTIMATES,
    NORMAL_PRECONDITIONERS,
    PATCH_FRAMES,
    PROFILE_UNITS,
    ROLL_MODES,
    TANGENTIAL_ESTIMATES,
    TANGENTIAL_MODELS,
    TANGENTIAL_SOLVERS,
    TRACTION_BOUNDS,
)
from .fields import Record, close_keys, did_you_mean, document, setting
from .friction import MAX_MU, FrictionTable

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


@document
@dataclass(frozen=True)
class MaterialSettings(Record):
    """Elastic constants of the two bodies (one value: identical bodies)."""

    TABLE: ClassVar[str] = "material"
    young: tuple[float, ...] = setting((206e9,), "floats12", "Pa",
                                       "Young's modulus E (one value, or [body 1, body 2])",
                                       minimum=1e6, maximum=1e13, required=True)
    poisson: tuple[float, ...] = setting((0.28,), "floats12", "-",
                                         "Poisson's ratio (one value, or [body 1, body 2])",
                                         minimum=0.0, maximum=0.5, open_max=True,
                                         required=True)

    def elastic_pair(self) -> ElasticPair:
        """The combined elastic parameters of the two bodies."""
        ys, ns = list(self.young), list(self.poisson)
        ys = ys * 2 if len(ys) == 1 else ys
        ns = ns * 2 if len(ns) == 1 else ns
        return ElasticPair.of(*(Material(e, n) for e, n in zip(ys, ns, strict=True)))

    def to_dict(self) -> dict[str, Any]:
        return {k: v[0] if len(v) == 1 else list(v)
                for k, v in (("young", self.young), ("poisson", self.poisson))}


@document
@dataclass(frozen=True)
class QuadraticGeometry(Record):
    """A quadratic undeformed gap ``h = A x^2 + B y^2`` (``type = "quadratic"``)."""

    TABLE: ClassVar[str] = "geometry"
    TYPE: ClassVar[str] = "quadratic"
    A: float = setting(MISSING, "float", "1/m", "longitudinal relative curvature",
                       minimum=0.0, open_min=True, maximum=1e6, required=True)
    B: float = setting(MISSING, "float", "1/m", "lateral relative curvature",
                       minimum=0.0, open_min=True, maximum=1e6, required=True)

    def to_dict(self) -> dict[str, Any]:
        return {"type": self.TYPE, **super().to_dict()}


MAX_PENETRATION = 0.01
"""Largest rigid approach [m] of a contact (elastic approaches are micrometres; a wheel
10 mm into its rail is a wrong input)."""
MAX_ELEMENTS = 1 << 18
"""Default largest grid of a patch (512 x 512 elements, ~0.5 GB with the FFT buffers)."""
ELEMENT_BYTES = 2048
"""Memory [bytes] per element that [grid] max_elements budgets (an FFT operator and the
solvers' arrays take less): the influence operator of a patch may take max_elements times
this."""


def check_grid_size(what: str, nx: float, ny: float, budget: int) -> None:
    """Raise a :class:`CaseError` naming ``what`` when an nx x ny grid exceeds ``budget``
    (counts may be floats: those an element size would need, before any is formed)."""
    if not nx * ny <= budget:
        nx, ny = (float(n) if n < 1e300 else 1e300 for n in (nx, ny))  # ints beyond floats
        raise CaseError(f"{what} = {nx:.4g} x {ny:.4g} = {nx * ny:.3g} elements, more than "
                        f"the {budget} of [grid] max_elements (about 2 kB each); use fewer "
                        "or larger elements, or raise max_elements")


MIN_WHEEL_RADIUS, MAX_WHEEL_RADIUS = 0.2, 0.7
"""Range of a railway wheel's nominal rolling radius [m] (small tram and freight wheels to
locomotive wheels): a radius outside is a wrong input, often millimetres typed as metres."""
MIN_GAUGE, MAX_GAUGE = 0.5, 2.0
"""Range of a track gauge [m] (narrow gauges from 0.6 m, broad gauges to 1.676 m, with room
on both sides); the wheelset's flange-back distance is a little less than its gauge."""

MAX_ELEMENT_SIZE = 0.005
"""Coarsest element [m] that still resolves a wheel-rail patch."""
MIN_PATCH_ELEMENTS = 3
"""Fewest elements along each axis of a wheel-rail case's grid given by counts: with fewer
every element lies at the edge of the potential area (a contact inside it needs one free
element on each side)."""
_TOP_KEYS = ("name", "convention")
"""The keys of a case beside its tables."""
MAX_GAUGE_PLAY = 0.2
"""Largest gauge less back-to-back distance [m] of a wheelset on its track (both flanges'
thickness and their play: 75 mm on standard gauge, 1.435 - 1.36 m); beyond it a wheel is
off its rail."""

_TRACK = {f.name: f.default for f in fields(Track)}
_WHEELSET = {f.name: f.default for f in fields(Wheelset)}
_SEPARATION = {f.name: f.default for f in fields(PatchSeparation)}
"""The track and wheelset defaults, declared once by the geometry's own records."""


@document
@dataclass(frozen=True)
class WheelRailGeometry(Record):
    """A wheel on a rail (``type = "wheel-rail"``): profiles, track, wheelset position.

    Profiles are written with y to the field side (wheel: y = S, z = radius increment;
    rail: uncanted, crown at 0, z up); with a load, ``[normal] load`` is the vertical wheel
    load and ``penetration`` the vertical approach of the wheel.
    """

    TABLE: ClassVar[str] = "geometry"
    TYPE: ClassVar[str] = "wheel-rail"
    wheel: str = setting("S1002", "str", "",
                         "wheel profile: built-in name (S1002) or file (.prw, two columns y z)")
    rail: str = setting("60E1", "str", "",
                        "rail profile: built-in name (60E1, UIC60, CN60) or file (.prr, two "
                        "columns)")
    profile_unit: str = setting("mm", "choice", "", "unit of two-column profile files",
                                choices=PROFILE_UNITS)
    inclination: float = setting(_TRACK["inclination"], "float", "rad",
                                 "rail cant (1:40; 0 for a file that is canted already)")
    gauge: float = setting(_TRACK["gauge"], "float", "m", "track gauge, measured gauge_depth "
                           "below the top of rail (narrow 0.6 m to broad 1.676 m gauges)",
                           minimum=MIN_GAUGE, maximum=MAX_GAUGE)
    gauge_depth: float = setting(_TRACK["gauge_depth"], "float", "m", "depth below the top of "
                                 "rail at which the gauge is measured (14 mm in EN 13848)",
                                 minimum=0.0, open_min=True, maximum=0.05)
    back_to_back: float = setting(_WHEELSET["back_to_back"], "float", "m",
                                  "flange-back distance of the wheelset (a little less than "
                                  "the gauge)", minimum=MIN_GAUGE - 0.1, maximum=MAX_GAUGE)
    flange_back: float = setting(_WHEELSET["flange_back"], "float", "m",
                                 "wheel profile coordinate S of the flange back (S1002: "
                                 "-0.07 m)", minimum=-0.2, maximum=0.2)
    wheel_radius: float = setting(_WHEELSET["radius"], "float", "m", "nominal rolling radius "
                                  "(tram to locomotive wheels)", minimum=MIN_WHEEL_RADIUS,
                                  maximum=MAX_WHEEL_RADIUS)
    lateral_displacement: float = setting(0.0, "float", "m",
                                          "wheelset lateral displacement, positive to the left")
    yaw: float = setting(0.0, "float", "rad", "wheelset yaw angle (a small angle)",
                         minimum=-MAX_POSE_ANGLE, maximum=MAX_POSE_ANGLE)
    roll: float | str = setting(0.0, "float|choice", "rad",
                                "wheelset roll (left side up), or 'rigid' (both wheels touch) "
                                "or 'equal-loads' (both carry [normal] load)",
                                choices=ROLL_MODES)
    side: str = setting("left", "choice", "", "wheel(s) to solve", choices=CASE_SIDES)
    curvature: float = setting(0.0, "float", "1/m", "track curvature, positive when the track "
                               "turns left (towards +Y); enters the [kinematics] creepages "
                               "only", minimum=-0.1, maximum=0.1)
    rail_offset: tuple[float, float] = setting((0.0, 0.0), "floats2", "m",
                                               "deviation [dY, dZ] of the rail of the "
                                               "case's side from its place (Y to the left, "
                                               "Z up; a gauge change is a lateral offset)",
                                               minimum=-0.05, maximum=0.05)
    rail_roll: float = setting(0.0, "float", "rad", "roll of the rail of the case's side "
                               "about X (right-hand rule: positive turns its head to the "
                               "right), about the rail profile's origin after the rail is "
                               "placed", minimum=-0.1, maximum=0.1)
    patch_frame: str = setting("reference", "choice", "",
                               "origin of each patch's frame (where its contact angle, rolling "
                               "radius, spin and moments are taken): 'reference' = CONTACT's "
                               "reference point, the overlap's weighted centre; 'rigid' = the "
                               "rigid contact point", choices=PATCH_FRAMES)
    separation_angle: float = setting(_SEPARATION["angle"], "float", "rad",
                                      "CONTACT's A_SEP: neighbouring patches whose contact "
                                      "angles differ by more are never turned",
                                      minimum=0.0, maximum=math.pi)
    separation_distance: float = setting(_SEPARATION["distance"], "float", "m",
                                         "CONTACT's D_SEP: neighbouring patches from this "
                                         "far apart up to turn_distance have their contact "
                                         "angles turned towards their combined angle "
                                         "(CONTACT combines closer ones; railcontact keeps "
                                         "them apart)", minimum=0.0, maximum=0.1)
    combine_distance: float = setting(_SEPARATION["combine"], "float", "m",
                                      "CONTACT's D_COMB: sets the default turn_distance",
                                      minimum=0.0, maximum=0.1)
    turn_distance: float | None = setting(None, "float", "m",
                                          "CONTACT's D_TURN: how far apart neighbouring "
                                          "patches still turn (default 2 "
                                          "separation_distance - combine_distance)",
                                          minimum=0.0, maximum=0.1)

    def __post_init__(self) -> None:
        super().__post_init__()
        play = self.gauge - self.back_to_back
        if not 0.0 < play <= MAX_GAUGE_PLAY:
            raise CaseError(
                f"[geometry] gauge = {self.gauge:g} m less back_to_back = "
                f"{self.back_to_back:g} m is {play * 1e3:.4g} mm; a wheelset on its track "
                f"has more than 0 and at most {MAX_GAUGE_PLAY * 1e3:g} mm there (both "
                "flanges' thickness and their play: 75 mm on standard gauge, 1.435 - 1.36 "
                "m)")

    def to_dict(self) -> dict[str, Any]:
        return {"type": self.TYPE, **super().to_dict()}

    @property
    def separation(self) -> PatchSeparation:
        """CONTACT's patch separation parameters of the case."""
        return PatchSeparation(self.separation_angle, self.separation_distance,
                               self.combine_distance, self.turn_distance)

    @property
    def rail_deviated(self) -> bool:
        """Whether the rail of the case's side is offset or rolled."""
        return self.rail_offset != (0.0, 0.0) or self.rail_roll != 0.0


@document
@dataclass(frozen=True)
class GridSettings(Record):
    """The BEM grid of a patch: element counts or sizes, and the potential contact area.

    By default the area is the paper's (Sec. 2.1): ``A x^2 <= delta0``, ``B y^2 <= delta0``
    with delta0 from Hertz, scaled by ``margin``, grown when the contact reaches its edge.
    """

    TABLE: ClassVar[str] = "grid"
    nx: int = setting(64, "int", "", "elements along x (rolling)", minimum=2)
    ny: int = setting(64, "int", "", "elements along y (lateral)", minimum=2)
    dx: float | None = setting(None, "float", "m", "element size along x (overrides nx)",
                               minimum=0.0, open_min=True)
    dy: float | None = setting(None, "float", "m", "element size along y (overrides ny)",
                               minimum=0.0, open_min=True)
    x: tuple[float, float] | None = setting(None, "range", "m",
                                            "potential contact area along x [min, max] "
                                            "(quadratic cases; default automatic)")
    y: tuple[float, float] | None = setting(None, "range", "m",
                                            "potential contact area along y [min, max] "
                                            "(quadratic cases; default automatic)")
    margin: float = setting(1.0, "float", "-", "scale of the automatic potential area",
                            minimum=0.0, open_min=True, maximum=100.0)
    max_elements: int = setting(MAX_ELEMENTS, "int", "", "largest grid (nx * ny) a patch may "
                                "have, checked before anything is allocated (a memory budget: "
                                "~2 kB per element; the influence operator, dense ones "
                                "included, must fit in it)", minimum=4)
    quantum: int = setting(1, "int", "", "element counts rounded up to a multiple of this "
                           "(fewer operators in a time series)", minimum=1, case=False)
    snap: bool = setting(False, "bool", "", "grid centre on a multiple of the element size "
                         "(consecutive time steps share one lattice)", case=False)
    centred: bool = setting(False, "bool", "", "element centres on multiples of the element "
                            "size from the patch origin, which is an element's centre (as "
                            "CONTACT's grids; solve() sets it for patches at their reference "
                            "point)", case=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.dx is None and self.dy is None:
            check_grid_size("[grid] nx * ny", self.nx, self.ny, self.max_elements)

    @property
    def automatic(self) -> tuple[bool, bool]:
        """Whether the potential area along x and along y is chosen (and grown) by the
        solver: where the user gave it, it is never changed."""
        return self.x is None, self.y is None


@dataclass(frozen=True)
class Control:
    """What fixes a normal problem: the normal force [N] or the rigid approach [m]."""

    load: float | None = None
    penetration: float | None = None

    def __post_init__(self) -> None:
        if (self.load is None) == (self.penetration is None):
            raise CaseError("give exactly one of load [N] and penetration [m]")

    @property
    def by_load(self) -> bool:
        return self.load is not None

    @property
    def value(self) -> float:
        """The load [N] or the penetration [m]."""
        return self.load if self.load is not None else self.penetration  # type: ignore

    def kwargs(self) -> dict[str, float]:
        """``{"load": N}`` or ``{"penetration": m}``, the keyword of the solvers."""
        return {"load": self.load} if self.load is not None else {
            "penetration": self.penetration}  # type: ignore[dict-item]


@document
@dataclass(frozen=True)
class NormalSettings(Record):
    """The normal problem and its BEM solver (Polonsky–Keer CG)."""

    TABLE: ClassVar[str] = "normal"
    load: float | None = setting(None, "float", "N", "normal force (quadratic) or vertical "
                                 "wheel load (wheel-rail); give load or penetration",
                                 minimum=0.0, maximum=1e8)
    penetration: float | None = setting(None, "float", "m", "rigid approach (quadratic) or "
                                        "vertical approach of the wheel (wheel-rail)",
                                        minimum=0.0, maximum=MAX_PENETRATION)
    estimate: str = setting("none", "choice", "", "initial estimate of the pressure",
                            choices=NORMAL_ESTIMATES)
    estimate_grid: tuple[int, int] = setting((40, 40), "ints2", "",
                                             "KP/INFCON estimate grid [nx, ny]", minimum=4,
                                             maximum=2048)
    tolerance: float = setting(1e-3, "float", "-", "eps_n, relative pressure change between "
                               "iterations", minimum=0.0, open_min=True, maximum=1.0,
                               open_max=True)
    max_iterations: int = setting(500, "int", "", "CG iterations at most", minimum=1)
    fft: str = setting("auto", "choice", "", "convolution backend", choices=FFT_BACKENDS)
    preconditioner: str = setting("fft", "choice", "", "'fft' or 'none' (plain "
                                  "Polonsky-Keer CG, as in the paper)",
                                  choices=NORMAL_PRECONDITIONERS)

    @property
    def control(self) -> Control:
        """The case's load or penetration (an error when it gives neither or both)."""
        try:
            return Control(self.load, self.penetration)
        except CaseError as exc:
            raise CaseError(f"[normal] needs exactly one of load and penetration: {exc}"
                            ) from None


MAX_CREEPAGE = 1e3
"""Largest magnitude of a creepage (xi, eta [-]; phi [1/m]) a solve takes, given or
formed from velocities: far beyond full sliding (a wheel-rail patch slides fully at
creepages of about 1e-2), so the bound only keeps the creep forces' products (the
frictional power) finite."""


def check_kinematic_creepage(side: str, creepage: tuple[float, float, float], speed: float,
                             velocities: str = "the velocities"
                             ) -> tuple[float, float, float]:
    """The ``side`` wheel's creepages (xi, eta, phi) that its ``velocities`` give at the
    forward ``speed`` [m/s], checked within :data:`MAX_CREEPAGE` as a case's creepage is;
    a :class:`~railcontact.errors.CaseError` naming them and the speed (too small for the
    other velocities) where one is beyond, or not a number."""
    xi, eta, phi = creepage
    if not (abs(xi) <= MAX_CREEPAGE and abs(eta) <= MAX_CREEPAGE
            and abs(phi) <= MAX_CREEPAGE):
        raise CaseError(f"{side} wheel: {velocities} give the creepages ({xi:.4g}, "
                        f"{eta:.4g}, {phi:.4g} 1/m) beyond +-{MAX_CREEPAGE:g} (speed "
                        f"{speed:g} m/s too small for them)")
    return creepage


@document
@dataclass(frozen=True)
class TangentialSettings(Record):
    """The tangential problem: steady rolling in +x, and its model and solver."""

    TABLE: ClassVar[str] = "tangential"
    creepage: tuple[float, float, float] = setting((0.0, 0.0, 0.0), "floats3", "-, -, 1/m",
                                                   "creepages [xi, eta, phi]",
                                                   minimum=-MAX_CREEPAGE,
                                                   maximum=MAX_CREEPAGE, required=True)
    friction: float | FrictionTable = setting(
        0.4, "float|friction", "-", "Coulomb coefficient mu, or a table of mu across the "
        "profile (against the rail's surface inclination or profile coordinate)", minimum=0.0,
        maximum=MAX_MU, required=True)
    model: str = setting("bem", "choice", "", "tangential model", choices=TANGENTIAL_MODELS)
    estimate: str = setting("none", "choice", "", "initial estimate of the BEM",
                            choices=TANGENTIAL_ESTIMATES)
    solver: str = setting(TANGENTIAL_SOLVERS[0], "choice", "", "the BEM's solver: steadygs "
                          "(the fastest) or convexgs (the paper's)",
                          choices=TANGENTIAL_SOLVERS)
    tolerance: float = setting(1e-2, "float", "-", "eps_tau, relative traction change between "
                               "sweeps", minimum=0.0, open_min=True, maximum=1.0,
                               open_max=True)
    max_iterations: int = setting(1000, "int", "", "Gauss-Seidel sweeps at most", minimum=1)
    bound: str = setting("elliptic", "choice", "", "FASTSIM traction bound",
                         choices=TRACTION_BOUNDS)
    strips: tuple[int, int] = setting((40, 40), "ints2", "",
                                      "FASTSIM/FaStrip samples per strip and strips [nx, ny]",
                                      minimum=2, maximum=2048)
    spin_offset: float = setting(1.0 / 6.0, "float", "-", "where the spin slip is taken in a "
                                 "rolling step, as a fraction of dx (CONTACT: 1/6)",
                                 minimum=0.0, maximum=1.0)


@document
@dataclass(frozen=True)
class KinematicsSettings(Record):
    """The wheelset's and the rail's velocities (wheel-rail cases), instead of
    ``[tangential] creepage``: each patch's creepages follow from rigid-body kinematics at
    its reference point, with the track curvature (``[geometry] curvature``), as CONTACT
    forms them (:mod:`railcontact.geometry.kinematics`). Track frame: X forward, Y to the
    left, Z up."""

    TABLE: ClassVar[str] = "kinematics"
    speed: float = setting(MISSING, "float", "m/s", "forward speed V of the wheelset",
                           minimum=0.0, open_min=True, maximum=1000.0, required=True)
    lateral_velocity: float = setting(0.0, "float", "m/s", "lateral velocity of the wheelset "
                                      "centre (to the left)", minimum=-100.0, maximum=100.0)
    vertical_velocity: float = setting(0.0, "float", "m/s", "vertical velocity of the "
                                       "wheelset centre (up)", minimum=-100.0, maximum=100.0)
    roll_rate: float = setting(0.0, "float", "rad/s", "roll rate of the wheelset (about X)",
                               minimum=-100.0, maximum=100.0)
    yaw_rate: float = setting(0.0, "float", "rad/s", "yaw rate of the wheelset (about Z: "
                              "positive turns its nose to the left)", minimum=-100.0,
                              maximum=100.0)
    spin_speed: float | None = setting(None, "float", "rad/s", "angular speed of the axle, "
                                       "positive when rolling forward (default: speed / "
                                       "[geometry] wheel_radius, pure rolling at the "
                                       "nominal radius)", minimum=-1e4, maximum=1e4)
    rail_velocity: tuple[float, float] = setting((0.0, 0.0), "floats2", "m/s",
                                                 "velocity [vY, vZ] of the rail of the "
                                                 "case's side", minimum=-100.0, maximum=100.0)
    rail_roll_rate: float = setting(0.0, "float", "rad/s", "roll rate of the rail of the "
                                    "case's side about X, about its profile's origin",
                                    minimum=-100.0, maximum=100.0)


@dataclass(frozen=True)
class PatchSettings:
    """How every patch of a problem is solved: its grid, the normal BEM and, when there is
    a tangential problem, the tangential model (None: normal contact only); with
    ``kinematics`` each patch's creepages follow from the velocities (the tangential
    settings' creepage is then not used)."""

    grid: GridSettings
    normal: NormalSettings
    tangential: TangentialSettings | None = None
    kinematics: WheelsetMotion | None = None
    separation: PatchSeparation | None = PatchSeparation()
    hertz: bool = True
    """Each patch carries Hertz's solution for its curvatures and load or penetration (a
    case reports it); False: formed only where the solve needs it (an estimate, a
    potential area, a patch that a bound does not show within the half-space model), as
    a time step does."""


CASE_TABLES: dict[str, tuple[type[Record], ...]] = {
    "material": (MaterialSettings,),
    "geometry": (QuadraticGeometry, WheelRailGeometry),
    "grid": (GridSettings,),
    "normal": (NormalSettings,),
    "tangential": (TangentialSettings,),
    "kinematics": (KinematicsSettings,),
}
"""The tables of a case file and the records they become."""
_REQUIRED_TABLES = ("material", "geometry", "normal")


@dataclass(frozen=True)
class Case:
    """A validated contact case: one settings record per table (SI units).

    Build it with :meth:`from_dict` (or :func:`load_case` from a file); the constructor
    takes the records themselves.
    """

    material: MaterialSettings
    geometry: QuadraticGeometry | WheelRailGeometry
    normal: NormalSettings
    grid: GridSettings = GridSettings()
    tangential: TangentialSettings | None = None
    name: str = "case"
    convention: str = "railcontact"
    kinematics: KinematicsSettings | None = None

    def __post_init__(self) -> None:
        _ = self.normal.control  # raises unless exactly one of load and penetration
        check_convention(self.convention)
        geo = self.geometry
        if self.kinematics is not None:
            if not isinstance(geo, WheelRailGeometry):
                raise CaseError("[kinematics] is for wheel-rail cases (a quadratic case "
                                "takes [tangential] creepage)")
            if self.tangential is None:
                raise CaseError("[kinematics] needs a [tangential] table (friction, model)")
        if isinstance(geo, WheelRailGeometry) and geo.rail_deviated and (
                geo.side == "both" or isinstance(geo.roll, str)):
            raise CaseError("[geometry] rail_offset and rail_roll deviate the rail of the "
                            "case's side: give side = 'left' or 'right' and a roll angle "
                            "(not 'rigid' or 'equal-loads', which place both wheels)")
        k = self.kinematics
        if (k is not None and isinstance(geo, WheelRailGeometry) and geo.side == "both"
                and (tuple(k.rail_velocity) != (0.0, 0.0) or k.rail_roll_rate != 0.0)):
            raise CaseError("[kinematics] rail_velocity and rail_roll_rate move the rail of "
                            "the case's side: give side = 'left' or 'right'")
        t = self.tangential
        if t is not None and isinstance(t.friction, FrictionTable):
            if not isinstance(geo, WheelRailGeometry):
                raise CaseError("[tangential] friction as a table (across the profile) needs "
                                "a wheel-rail case; a quadratic case takes a number")
            if t.friction.at == "row" and t.model != "bem":
                raise CaseError(f"[tangential] friction varying per element row needs model "
                                f"= 'bem' ({t.model!r} takes one coefficient per patch: set "
                                "at = 'patch' in the friction table)")
        if isinstance(geo, WheelRailGeometry):
            if geo.roll == "equal-loads" and self.normal.load is None:
                raise CaseError("[geometry] roll = 'equal-loads' needs [normal] load (the load "
                                "of each wheel [N]); with a penetration use roll = 'rigid' or "
                                "a number")
            if self.grid.x is not None or self.grid.y is not None:
                raise CaseError("[grid] x and y are for quadratic cases; a wheel-rail case "
                                "sets the potential area of each patch automatically (use "
                                "margin, nx/ny or dx/dy)")

    def __getitem__(self, table: str):
        raise TypeError(f"a Case holds typed settings, not a dictionary: use case.{table} "
                        f"(or case.to_dict()[{table!r}] for a copy as a dictionary; changing "
                        "that copy does not change the case)")

    @property
    def wheel_rail(self) -> bool:
        return isinstance(self.geometry, WheelRailGeometry)

    @property
    def patch_settings(self) -> PatchSettings:
        """The grid, normal and tangential settings of the case's patches."""
        separation = self.geometry.separation if self.wheel_rail else None
        return PatchSettings(self.grid, self.normal, self.tangential, self.motion, separation)

    @property
    def motion(self) -> WheelsetMotion | None:
        """The velocities of ``[kinematics]`` with the track curvature of ``[geometry]``
        (the spin speed for pure rolling at the nominal radius when not given); None
        without ``[kinematics]``."""
        k, geo = self.kinematics, self.geometry
        if k is None or not isinstance(geo, WheelRailGeometry):
            return None
        spin = k.spin_speed if k.spin_speed is not None else k.speed / geo.wheel_radius
        return WheelsetMotion(k.speed, spin, k.lateral_velocity, k.vertical_velocity,
                              k.roll_rate, k.yaw_rate, geo.curvature, k.rail_velocity,
                              k.rail_roll_rate)

    @property
    def pair(self) -> ElasticPair:
        """The combined elastic parameters of the two bodies."""
        return self.material.elastic_pair()

    @classmethod
    def from_dict(cls, case: Mapping[str, Any]) -> Case:
        """Check a case dictionary (the tables of a case file) and build the case.

        Raises
        ------
        CaseError
            Naming the table and key at fault; all problems at once when there are several.
        """
        if not isinstance(case, Mapping):
            raise CaseError(f"a case must be a dictionary of tables, got {type(case).__name__}")
        unknown = set(case) - set(CASE_TABLES) - set(_TOP_KEYS)
        if unknown:
            spec = ("; a [table] is a table's spec: build it with `railcontact table "
                    "build FILE -o STORE`" if "table" in unknown else "")
            raise CaseError(f"unknown table(s) {sorted(unknown)}"
                            f"{did_you_mean(unknown, [*CASE_TABLES, *_TOP_KEYS])}; known: "
                            f"{sorted(CASE_TABLES)} and the keys {list(_TOP_KEYS)}{spec}")
        problems: list[str] = [f"missing table [{t}]" for t in _REQUIRED_TABLES
                               if t not in case]
        records: dict[str, Any] = {}
        tangential = case.get("tangential")
        by_kinematics = "kinematics" in case and isinstance(tangential, Mapping)
        if by_kinematics and "creepage" in tangential:
            problems.append("give [tangential] creepage or a [kinematics] table, not both "
                            "(the kinematics give each patch its creepages)")
        for table in CASE_TABLES:
            if table not in case:
                continue
            values = case[table]
            if table == "tangential" and by_kinematics and "creepage" not in values:
                values = {**values, "creepage": (0.0, 0.0, 0.0)}  # not used: kinematics
            try:
                records[table] = _record(table, values)
            except CaseError as exc:
                problems.append(str(exc))
        normal = case.get("normal")
        # (a misspelt load or penetration was named already, with the key it is close to)
        misspelt = isinstance(normal, Mapping) and bool(
            set(close_keys(normal, ("load", "penetration")).values()) - set(normal))
        if "normal" not in records and isinstance(normal, Mapping) and not misspelt and (
                ("load" in normal) == ("penetration" in normal)):
            problems.append("[normal] needs exactly one of load [N] and penetration [m]")
        name = case.get("name", "case")
        if not isinstance(name, str):
            problems.append(f"name must be a string, got {name!r}")
        convention = case.get("convention", "railcontact")
        try:
            check_convention(convention)
        except CaseError as exc:
            problems.append(str(exc))
        grid = records.get("grid")
        if isinstance(records.get("geometry"), WheelRailGeometry) and grid is not None:
            for key, size in (("nx", grid.dx), ("ny", grid.dy)):
                count = getattr(grid, key)
                if size is None and count < MIN_PATCH_ELEMENTS:
                    problems.append(
                        f"[grid] {key} = {count} elements cannot hold a wheel-rail patch: "
                        f"every element is at the edge of its area, so its contact always "
                        f"reaches the edge and the area would grow without end; give at "
                        f"least {MIN_PATCH_ELEMENTS} (or the element size [grid] "
                        f"d{key[1]})")
            for key in ("dx", "dy"):
                size = getattr(grid, key)
                if size is not None and size > MAX_ELEMENT_SIZE:
                    mm = (f"; {size:g} looks like millimetres: {size:g} mm is "
                          f"{size / 1000.0:g} m" if size / 1000.0 <= MAX_ELEMENT_SIZE else "")
                    problems.append(f"[grid] {key} = {size:g} m is coarser than the "
                                    f"{MAX_ELEMENT_SIZE:g} m that still resolves a wheel-rail "
                                    f"patch{mm}")
        material, tangential = records.get("material"), records.get("tangential")
        if material is not None and tangential is not None and tangential.model == "bem":
            k = material.elastic_pair().difference
            if k != 0.0:
                problems.append(f"[material] gives dissimilar bodies (Kalker's K = {k:.3g}), "
                                "which couple normal and tangential contact; the tangential "
                                "BEM takes quasi-identical bodies only (K = 0: one young "
                                "and poisson, or pairs with equal (1 - 2 nu) / G)")
        if problems:
            raise CaseError(problems[0] if len(problems) == 1 else
                            f"{len(problems)} problems in the case:\n  " + "\n  ".join(problems))
        return cls(name=name, convention=convention, **records)

    def to_dict(self) -> dict[str, Any]:
        """The case as a dictionary of tables with every default filled in (SI units)."""
        out: dict[str, Any] = {"name": self.name, "convention": self.convention}
        for table in CASE_TABLES:
            rec = getattr(self, table)
            if rec is not None:
                out[table] = rec.to_dict()
        if self.kinematics is not None and "tangential" in out:
            del out["tangential"]["creepage"]  # the kinematics give them
        return out


def check_convention(value: Any) -> str:
    """``value`` when it names a convention (:data:`~.choices.CONVENTIONS`), else a
    :class:`CaseError` naming the allowed ones."""
    if not isinstance(value, str) or value not in CONVENTIONS:
        raise CaseError(f"convention must be one of {', '.join(map(repr, CONVENTIONS))}, got "
                        f"{value!r}")
    return value


def _record(table: str, values: Any) -> Record:
    if table != "geometry":
        return CASE_TABLES[table][0].from_mapping(values)
    if not isinstance(values, Mapping):
        raise CaseError(f"[geometry] must be a table, got {values!r}")
    kind = values.get("type", "quadratic")
    if kind not in GEOMETRY_TYPES:
        raise CaseError(f"[geometry] type must be one of "
                        f"{', '.join(map(repr, GEOMETRY_TYPES))}, got {kind!r}")
    rest = {k: v for k, v in values.items() if k != "type"}
    if kind == "wheel-rail":
        for key in ("A", "B"):
            if key in rest:
                raise CaseError(f"[geometry] {key} is for type = 'quadratic'; a wheel-rail "
                                "case computes its curvatures from the profiles")
        return WheelRailGeometry.from_mapping(rest)
    wheel_rail_keys = sorted(set(rest) & {f.name for f in fields(WheelRailGeometry)})
    if wheel_rail_keys:
        said = "" if "type" in values else " (type is 'quadratic' when not given)"
        raise CaseError(f"[geometry] {', '.join(wheel_rail_keys)}: for type = 'wheel-rail'; a "
                        f"quadratic case takes A and B{said}")
    return QuadraticGeometry.from_mapping(rest)


def validate_case(case: Mapping[str, Any] | Case) -> Case:
    """A :class:`Case` from a case dictionary (a Case is returned as it is).

    Raises
    ------
    CaseError
        Naming the table and key at fault.
    """
    return case if isinstance(case, Case) else Case.from_dict(case)


def load_case(path: str | Path) -> Case:
    """Read a TOML case file (SI units) and return the validated case.

    Profile files named by a relative path (``[geometry] wheel``, ``rail``) are looked up
    beside the case file first, then in the working directory.

    Raises
    ------
    CaseError
        When the file does not exist, does not parse, or breaks the schema.
    """
    p = Path(path)
    if not p.is_file():
        raise CaseError(f"{p} is a folder, not a case file" if p.is_dir() else
                        f"case file not found: {p}")
    try:
        with p.open("rb") as f:
            raw = tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"case file {p} is not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise CaseError(f"case file {p} is not UTF-8 text ({exc.reason} at byte "
                        f"{exc.start})") from None
    except RecursionError:
        raise CaseError(f"case file {p} nests arrays or tables too deeply") from None
    except ValueError as exc:  # e.g. an integer literal of more than 4300 digits
        raise CaseError(f"case file {p}: {exc}") from None
    raw.setdefault("name", p.stem)
    geo = raw.get("geometry")
    if isinstance(geo, dict):  # profile files relative to the case file, as a user means
        for key in ("wheel", "rail"):
            value = geo.get(key)
            if isinstance(value, str) and value and not Path(value).is_absolute() \
                    and (p.parent / value).is_file():
                geo[key] = str(p.parent / value)
    return Case.from_dict(raw)
