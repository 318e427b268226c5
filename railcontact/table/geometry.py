"""Geometry tables (``[table] kind = "geometry"``): the rigid wheel-rail contact geometry of
a wheelset over lateral displacement, yaw and roll, as multibody codes read it (rolling
radius difference, contact angles, contact positions, roll and vertical position).

A point is a wheelset pose; its geometry is the contact search's
(:func:`railcontact.geometry.search.contact_points`), not a BEM solve: for each wheel the
*patches* are the separated runs of the vertical gap between the wheel's trace and its
rail within the wheel's vertical approach beyond first contact (one-point contact: one
patch; two-point contact: the tread and the flange each a patch), each described by its
rigid contact point (the run's least gap). The wheel's main contact is its first contact
(the patch of gap 0), whose rolling radius and contact angle make the rolling radius
difference ``delta_r = r_left - r_right`` (as
:func:`railcontact.geometry.conicity.rolling_radius_difference`).

``[table] roll`` gives the roll (:data:`ROLL_MODES`):

``"rigid"``
    The kinematic roll: the rigid wheelset touches both rails
    (:func:`railcontact.geometry.roll.contact_roll`, as ``railcontact solve`` with
    ``[geometry] roll = "rigid"``); each wheel's patches at the approach ``[normal]
    penetration`` (0, or no ``[normal]``: the rigid contact points alone). The classic
    ``delta_r`` table of ORE B 176 and Polach.
``"equal-loads"``
    The roll and vertical position at which both wheels carry ``[normal] load`` (the
    elastic normal contact solved by the BEM, as ``railcontact solve`` with ``[geometry]
    roll = "equal-loads"``); each wheel's patches at its vertical approach there.
an axis (``[start, stop, count]`` or a list of values [rad])
    The roll given; each wheel on its own at the approach ``[normal] penetration``.

Without ``[table] roll`` the case's ``[geometry] roll`` is taken (a number, ``"rigid"`` or
``"equal-loads"``). The wheelset's vertical position (of its centre, positive up, from the
axle at the nominal wheel radius above the rail tops) is that at which the wheel nearest
its rail has the approach (``"rigid"``: both do), or, with ``"equal-loads"``, both wheels
have theirs. Both wheels are solved (``[geometry] side`` is not taken); ``[tangential]``
and ``[kinematics]`` are refused (a geometry table has no creepages).

Stored quantities: :data:`WHEELSET` over the axes, :data:`WHEEL` over the axes and
``side``, :data:`PATCH` over the axes, ``side`` and ``patch`` (at most :data:`PATCHES`
patches, ordered from the field side: the tread's first, a flange's last; NaN beyond the
wheel's ``n_patches``); ``status`` per wheel. Read a table with
:class:`~.geometry_table.GeometryTable`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from ..contact.wheelrail import build_geometry, check_on_rail, solve_wheel_rail, vertical_approach
from ..errors import CaseError, RailContactError, SolverError
from ..geometry.points import ContactPoint
from ..geometry.roll import contact_roll, first_contact_gap
from ..geometry.search import contact_points
from ..geometry.track import SIDES, Pose, Track, Wheelset
from ..settings import Case
from ..status import status_of
from . import spec as _spec
from .solve import estimate_case
from .spec import TableSpec, axis_count, axis_values, check_size, parse_policies
from .variables import NOT_CONVERGED, OK, OUT_OF_RANGE

KIND = "geometry"
ROLL_MODES = ("rigid", "equal-loads")
"""``[table] roll`` as a word; else an axis of roll angles (module docstring)."""
AXIS_NAMES = ("lateral_displacement", "yaw", "roll")
"""The axes of a geometry table."""
OPTIONS = ("batch", "out_of_range", "kind")
PATCHES = 3
"""Most patches of a wheel a geometry table holds."""
MAX_ANGLE = 0.1
"""Largest yaw and roll of a pose, either sign [rad]
(:class:`~railcontact.geometry.track.Pose`)."""


@dataclass(frozen=True)
class GeometryQuantity:
    """One stored quantity (SI units): over the axes and ``per`` (``"wheelset"``: nothing
    more, ``"wheel"``: ``side``, ``"patch"``: ``side`` and ``patch``)."""

    name: str
    unit: str
    long_name: str
    per: str


WHEELSET: tuple[GeometryQuantity, ...] = (
    GeometryQuantity("rolling_radius_difference", "m", "rolling radius difference "
                     "r_left - r_right of the wheels' first contacts", "wheelset"),
    GeometryQuantity("contact_angle_difference", "rad", "contact angle difference "
                     "gamma_left - gamma_right of the wheels' first contacts", "wheelset"),
    GeometryQuantity("tan_contact_angle_difference", "1", "tan(gamma_left) - "
                     "tan(gamma_right) of the wheels' first contacts", "wheelset"),
    GeometryQuantity("wheelset_roll", "rad", "roll angle of the wheelset (left side up)",
                     "wheelset"),
    GeometryQuantity("wheelset_vertical", "m", "vertical position of the wheelset centre (up) from "
                     "the axle at the nominal wheel radius above the rail tops", "wheelset"),
)
WHEEL: tuple[GeometryQuantity, ...] = (
    GeometryQuantity("rolling_radius", "m", "wheel radius at the first contact", "wheel"),
    GeometryQuantity("contact_angle", "rad", "contact angle of the first contact (positive "
                     "towards the flange)", "wheel"),
    GeometryQuantity("wheel_position", "m", "wheel profile coordinate S of the first "
                     "contact", "wheel"),
    GeometryQuantity("rail_position", "m", "rail profile coordinate of the first contact",
                     "wheel"),
    GeometryQuantity("contact_y", "m", "first contact point on the rail, track Y", "wheel"),
    GeometryQuantity("contact_z", "m", "first contact point on the rail, track Z", "wheel"),
    GeometryQuantity("first_contact_gap", "m", "least vertical gap of the wheel above its "
                     "rail with the axle at the nominal wheel radius above the rail tops",
                     "wheel"),
    GeometryQuantity("approach", "m", "vertical approach of the wheel beyond first contact "
                     "at which its patches are found", "wheel"),
)
PATCH: tuple[GeometryQuantity, ...] = (
    GeometryQuantity("patch_rolling_radius", "m", "wheel radius at the patch's contact "
                     "point", "patch"),
    GeometryQuantity("patch_contact_angle", "rad", "contact angle of the patch (positive "
                     "towards the flange)", "patch"),
    GeometryQuantity("patch_wheel_position", "m", "wheel profile coordinate S of the "
                     "patch's contact point", "patch"),
    GeometryQuantity("patch_rail_position", "m", "rail profile coordinate of the patch's "
                     "contact point", "patch"),
    GeometryQuantity("patch_contact_y", "m", "patch's contact point on the rail, track Y",
                     "patch"),
    GeometryQuantity("patch_contact_z", "m", "patch's contact point on the rail, track Z",
                     "patch"),
    GeometryQuantity("patch_gap", "m", "vertical gap of the patch's contact point above the "
                     "wheel's first contact", "patch"),
)
QUANTITIES = WHEELSET + WHEEL + PATCH
"""Every interpolated quantity of a geometry table."""
N_PATCHES = GeometryQuantity("n_patches", "1", "number of patches of the wheel", "wheel")
"""The patch count (an integer, not interpolated)."""


def _read(cp: ContactPoint) -> dict[str, float]:
    """A contact point's values, by the names of :data:`PATCH` without ``patch_``."""
    return {"rolling_radius": cp.rolling_radius, "contact_angle": cp.contact_angle,
            "wheel_position": cp.wheel_s, "rail_position": cp.rail_y,
            "contact_y": cp.position[1], "contact_z": cp.position[2], "gap": cp.gap}


@dataclass
class WheelGeometry:
    """One wheel of a :class:`GeometryPoint` (SI units)."""

    side: str
    status: int = OK
    message: str = ""
    first: ContactPoint | None = None
    """The first contact (gap 0)."""
    patches: list[ContactPoint] = field(default_factory=list)
    """The patches, ordered from the field side (tread first, flange last)."""
    first_contact_gap: float = math.nan
    approach: float = math.nan


@dataclass
class GeometryPoint:
    """The geometry of one pose (SI units): roll [rad], vertical position [m], the
    wheels."""

    roll: float = math.nan
    vertical: float = math.nan
    wheels: dict[str, WheelGeometry] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return all(w.status == OK for w in self.wheels.values())

    def wheelset_values(self) -> dict[str, float]:
        """The :data:`WHEELSET` quantities (NaN unless both wheels are ok)."""
        if not self.ok:
            return {q.name: math.nan for q in WHEELSET}
        left, right = self.wheels["left"].first, self.wheels["right"].first
        return {"rolling_radius_difference": left.rolling_radius - right.rolling_radius,
                "contact_angle_difference": left.contact_angle - right.contact_angle,
                "tan_contact_angle_difference": (math.tan(left.contact_angle)
                                                 - math.tan(right.contact_angle)),
                "wheelset_roll": self.roll, "wheelset_vertical": self.vertical}


def _failed(point: GeometryPoint, status: int, message: str) -> GeometryPoint:
    for side in SIDES:
        w = point.wheels.setdefault(side, WheelGeometry(side))
        if w.status == OK:
            w.status, w.message = status, message
    return point


def _wheel(track: Track, ws: Wheelset, pose: Pose, side: str, approach: float
           ) -> WheelGeometry:
    """One wheel's patches at ``pose`` and vertical ``approach`` [m]."""
    w = WheelGeometry(side, approach=approach)
    try:
        w.first_contact_gap = first_contact_gap(track, ws, pose, side)
        cps = contact_points(track, ws, pose, side, approach)
        check_on_rail(cps[0], ws)
    except RailContactError as exc:
        w.status, w.message = OUT_OF_RANGE, f"{side} wheel: {exc}"
        return w
    if len(cps) > PATCHES:
        w.status = OUT_OF_RANGE
        w.message = (f"{side} wheel: {len(cps)} patches at the approach {approach:g} m; a "
                     f"geometry table holds at most {PATCHES}")
        return w
    w.first = cps[0]
    w.patches = sorted(cps, key=lambda c: -c.wheel_s)
    return w


def geometry_point(case: Case, track: Track, ws: Wheelset, lateral: float, yaw: float,
                   roll: float | str) -> GeometryPoint:
    """The geometry of the pose (``lateral`` [m], ``yaw`` [rad], ``roll`` [rad] or a word of
    :data:`ROLL_MODES`) of the wheel-rail ``case`` (its track and wheelset ``track``,
    ``ws``): each wheel's status is out of range or not converged, with its message, where
    the pose cannot be placed or solved; never an exception."""
    point = GeometryPoint()
    if roll == "equal-loads":
        return _equal_loads(case, track, ws, lateral, yaw, point)
    approach = float(case.normal.penetration or 0.0)
    if roll == "rigid":
        try:
            roll = contact_roll(track, ws, lateral, yaw)
        except RailContactError as exc:
            return _failed(point, OUT_OF_RANGE, str(exc))
    try:
        pose = Pose(lateral, yaw, float(roll))
    except RailContactError as exc:
        return _failed(point, OUT_OF_RANGE, str(exc))
    point.roll = pose.roll
    point.wheels = {s: _wheel(track, ws, pose, s, approach) for s in SIDES}
    if point.ok:
        point.vertical = -(min(w.first_contact_gap for w in point.wheels.values()) + approach)
    return point


def _equal_loads(case: Case, track: Track, ws: Wheelset, lateral: float, yaw: float,
                 point: GeometryPoint) -> GeometryPoint:
    """:func:`geometry_point` at the roll of equal loads (the BEM's normal solves)."""
    d = case.to_dict()
    d["geometry"].update(lateral_displacement=lateral, yaw=yaw)
    try:
        patches, pose = solve_wheel_rail(Case.from_dict(d))
    except (RailContactError, SolverError) as exc:
        return _failed(point, status_of(exc), str(exc))
    except Exception as exc:  # noqa: BLE001 - a fault of the solver: this point lost
        return _failed(point, OUT_OF_RANGE, f"the solver failed here ({type(exc).__name__}: "
                                            f"{exc})")
    point.roll = pose.roll
    for side in SIDES:
        own = [p for p in patches if p.geometry.side == side]
        if any(not p.normal.converged for p in own):
            point.wheels[side] = WheelGeometry(side, NOT_CONVERGED, next(
                p.normal.message for p in own if not p.normal.converged))
            continue
        point.wheels[side] = _wheel(track, ws, pose, side, vertical_approach(own))
    if point.ok:
        point.vertical = -float(np.mean([w.first_contact_gap + w.approach
                                         for w in point.wheels.values()]))
    return point


def _geometry_of(case: dict[str, Any]) -> tuple[Case, Track, Wheelset]:
    c = Case.from_dict(case)
    track, ws, _ = build_geometry(c.geometry)
    return c, track, ws


def point_geometry(case: dict[str, Any], values: dict[str, float]) -> GeometryPoint:
    """The geometry of a spec's point: its case dictionary (:attr:`TableSpec.case` of a
    geometry table) and the axes' ``values`` (axis name -> value [SI])."""
    c, track, ws = _geometry_of(case)
    return _at(c, track, ws, values)


def _at(c: Case, track: Track, ws: Wheelset, values: dict[str, float]) -> GeometryPoint:
    geo = c.geometry
    return geometry_point(c, track, ws, values.get("lateral_displacement",
                                                   geo.lateral_displacement),
                          values.get("yaw", geo.yaw), values.get("roll", geo.roll))


def solve_geometry_batch(case: dict[str, Any], sides: tuple[str, ...],
                         points: list[dict[str, float]]) -> dict[str, Any]:
    """The geometry of the ``points`` (axis name -> value) for both wheels: as
    :func:`~.solve.solve_batch` (its ``status``, ``messages``, ``recovered``, ``seconds``,
    ``cpu_seconds``), each quantity of :data:`QUANTITIES` an array over the points (and
    the sides, and the patches), ``n_patches`` an int32 array (points, sides). A point
    that fails with the case's estimate under ``"equal-loads"`` is solved again from the
    exact step's (:func:`~.solve.estimate_case`)."""
    t0, c0 = time.perf_counter(), time.process_time()
    n, ns = len(points), len(sides)
    out: dict[str, Any] = {q.name: np.full(_shape(q, n, ns), np.nan) for q in QUANTITIES}
    out[N_PATCHES.name] = np.zeros((n, ns), dtype=np.int32)
    out["status"] = np.zeros((n, ns), dtype=np.int8)
    out["messages"], out["recovered"] = [], []
    c, track, ws = _geometry_of(case)
    fallback = estimate_case(case) if c.geometry.roll == "equal-loads" else None
    for i, values in enumerate(points):
        point = _at(c, track, ws, values)
        if not point.ok and fallback is not None:
            again = point_geometry(fallback, values)
            if again.ok:
                point = again
                out["recovered"].extend((i, s, "estimate") for s in sides)
        for name, v in point.wheelset_values().items():
            out[name][i] = v
        for j, side in enumerate(sides):
            w = point.wheels[side]
            out["status"][i, j] = w.status
            if w.status != OK:
                out["messages"].append((i, side, int(w.status), w.message))
                continue
            for name, v in _read(w.first).items():
                if name != "gap":
                    out[name][i, j] = v
            out["first_contact_gap"][i, j] = w.first_contact_gap
            out["approach"][i, j] = w.approach
            out[N_PATCHES.name][i, j] = len(w.patches)
            for k, cp in enumerate(w.patches):
                for name, v in _read(cp).items():
                    out[f"patch_{name}"][i, j, k] = v
    out["seconds"] = time.perf_counter() - t0
    out["cpu_seconds"] = time.process_time() - c0
    return out


def _shape(q: GeometryQuantity, n: int, sides: int) -> tuple[int, ...]:
    return {"wheelset": (n,), "wheel": (n, sides), "patch": (n, sides, PATCHES)}[q.per]


@dataclass(frozen=True)
class GeometrySpec(TableSpec):
    """A validated geometry table spec (:class:`TableSpec`, both wheels; the case's
    ``[geometry] roll`` is the roll's mode, :data:`ROLL_MODES`, or the first roll)."""

    kind: ClassVar[str] = KIND
    solver: ClassVar[Any] = staticmethod(solve_geometry_batch)

    @property
    def roll_mode(self) -> str:
        """``"rigid"``, ``"equal-loads"`` or ``"given"`` (an axis, or the case's roll)."""
        roll = self.case["geometry"]["roll"]
        return roll if isinstance(roll, str) else "given"

    def identity(self) -> dict[str, Any]:
        return {**super().identity(), "kind": KIND}

    def data_arrays(self) -> list[tuple[str, str, Any, dict[str, Any], tuple]]:
        """(:func:`~.store.data_arrays`)."""
        trailing = {"wheelset": (), "wheel": (("side", 2),),
                    "patch": (("side", 2), ("patch", PATCHES))}
        return ([(q.name, "f8", np.nan, {"units": q.unit, "long_name": q.long_name},
                  trailing[q.per]) for q in QUANTITIES]
                + [(N_PATCHES.name, "i4", 0, {"units": "1", "long_name": N_PATCHES.long_name},
                    trailing["wheel"])])


def parse_geometry_spec(raw: dict[str, Any], table: dict[str, Any]) -> GeometrySpec:
    """A :class:`GeometrySpec` from a spec's case tables ``raw`` and its ``[table]``.

    Raises
    ------
    CaseError
        For a key of ``[table]`` a geometry table does not have, a bad axis or roll, a
        ``[tangential]`` or ``[kinematics]``, a ``[normal]`` that does not fit the roll.
    """
    unknown = sorted(set(table) - set(AXIS_NAMES) - set(OPTIONS))
    if unknown:
        raise CaseError(f"[table] kind = 'geometry': unknown key {', '.join(unknown)}; its "
                        f"axes are {', '.join(AXIS_NAMES)} (roll also "
                        f"{' or '.join(repr(m) for m in ROLL_MODES)}), its options "
                        f"{', '.join(o for o in OPTIONS if o != 'kind')}")
    geo = raw.get("geometry")
    if not isinstance(geo, dict) or geo.get("type") != "wheel-rail":
        raise CaseError("a geometry table needs a wheel-rail case ([geometry] type = "
                        "'wheel-rail')")
    for name in ("tangential", "kinematics"):
        if name in raw:
            raise CaseError(f"[{name}]: a geometry table holds the contact geometry alone "
                            f"(no creepages, no forces); remove [{name}]")
    if geo.get("side", "both") != "both":
        raise CaseError(f"[geometry] side = {geo['side']!r}: a geometry table takes both "
                        "wheels (the rolling radius difference); remove side")
    roll = table.get("roll", geo.get("roll", 0.0))
    mode = roll if isinstance(roll, str) else "given"
    if isinstance(roll, str) and roll not in ROLL_MODES:
        raise CaseError(f"[table] roll must be one of {', '.join(map(repr, ROLL_MODES))} or "
                        f"an axis of roll angles [rad], got {roll!r}")
    if isinstance(table.get("roll"), (int, float)):
        raise CaseError(f"[table] roll = {table['roll']!r}: give 'rigid', 'equal-loads' or an "
                        "axis ([start, stop, count] or a list of values [rad]); one roll angle "
                        "for the whole table is [geometry] roll")
    names = [n for n in table if n in AXIS_NAMES and not (n == "roll" and mode != "given")]
    if not names:
        raise CaseError("[table] kind = 'geometry' needs at least one axis: "
                        f"{', '.join(AXIS_NAMES)}")
    check_size({n: axis_count(n, table[n]) for n in names}, 2)
    axes = {n: axis_values(n, table[n]) for n in names}
    for n in ("yaw", "roll"):
        if n in axes and np.any(np.abs(axes[n]) >= MAX_ANGLE):
            raise CaseError(f"[table] {n}: each value must be a small angle (|{n}| < "
                            f"{MAX_ANGLE:g} rad), got {axes[n].tolist()}")
    normal = raw.get("normal")
    if mode == "equal-loads":
        if not isinstance(normal, dict) or "load" not in normal:
            raise CaseError("[table] roll = 'equal-loads' needs [normal] load (each wheel's "
                            "vertical load [N]) in the case")
    elif isinstance(normal, dict) and "load" in normal:
        raise CaseError(f"[normal] load: a geometry table with a {mode} roll takes [normal] "
                        "penetration (the vertical approach at which each wheel's patches are "
                        "found; none: 0, the rigid contact points); "
                        "for the roll at which both wheels carry a load give roll = "
                        "'equal-loads'")
    case = {k: dict(v) if isinstance(v, dict) else v for k, v in raw.items()}
    case["normal"] = dict(normal) if isinstance(normal, dict) else {"penetration": 0.0}
    case["geometry"] = {**geo, "side": "both",
                        "roll": mode if mode != "given" else (
                            float(axes["roll"][0]) if "roll" in axes else roll)}
    for n in ("lateral_displacement", "yaw"):
        if n in axes:
            case["geometry"][n] = float(axes[n][0])
    d = Case.from_dict(case).to_dict()
    shape = [len(v) for v in axes.values()]
    batch = table.get("batch", shape[-1])
    if not isinstance(batch, int) or isinstance(batch, bool) or batch < 1:
        raise CaseError(f"[table] batch must be an integer >= 1, got {batch!r}")
    return GeometrySpec(case=d, axes=axes, sides=("left", "right"), batch=min(batch, shape[-1]),
                        out_of_range=parse_policies(table.get("out_of_range"), names))


_spec.KINDS[KIND] = parse_geometry_spec
