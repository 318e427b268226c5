"""A table's specification: a wheel–rail case file plus a ``[table]`` of axes.

The ``[table]`` keys are axes, each ``[start, stop, count]`` (count an integer >= 1; the
``count`` values from ``start`` to ``stop`` inclusive, evenly spaced) or an explicit list of
strictly increasing values (``{ values = [...] }``, or a plain list of any length but
three)::

    [table]
    lateral_displacement = [-0.004, 0.004, 9]   # m
    creepage_y = { values = [-0.002, 0.0, 0.002] }
    load = [60e3, 100e3, 3]                      # N
    friction = [0.2, 0.4]                        # coefficient of friction mu [-]

A ``friction`` axis sets the case's ``[tangential] friction`` (a number: each value above 0
and within the case's limits) at each point. An axis absent from ``[table]`` keeps the
case's value. The axes are stored in the order written; the last one is the fastest: a
batch of work runs along it, each point started from the previous one's solution
(:mod:`railcontact.table.build`). ``batch`` (an integer, optional) cuts the fastest axis
into runs of at most that many points (default: the whole axis). ``out_of_range``
(optional) says what a value outside an axis gives, ``"status"`` (the default) or
``"clamp"`` (:data:`POLICIES`), for every axis or per axis (``out_of_range = { load =
"clamp" }``); it is kept in the store (not part of the table's identity: it does not change
the values). Both wheels are solved unless the case's ``[geometry]`` sets ``side``.
``kind`` (optional) says what the table holds: ``"contact"`` (the default, this module's
table of exact solves: creep forces and patches), another kind of :data:`KINDS`
(``"geometry"``: :mod:`railcontact.table.geometry`), which parses its own ``[table]``, or
``"creep"``, a normalised creep table (:mod:`.creepspec`), whose spec
:func:`~.kinds.load_any_spec` reads.

All values in SI units; see :data:`AXES`.
"""

from __future__ import annotations

import hashlib
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import CaseError
from ..settings import Case, TangentialSettings
from ..settings.case import NormalSettings, WheelRailGeometry
from .variables import QUANTITIES

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


@dataclass(frozen=True)
class Axis:
    """What an axis sets in the case: ``table``/``key`` (and ``index`` into a tuple)."""

    table: str
    key: str
    index: int | None
    unit: str
    long_name: str


AXES: dict[str, Axis] = {
    "lateral_displacement": Axis("geometry", "lateral_displacement", None, "m",
                                 "lateral displacement of the wheelset"),
    "yaw": Axis("geometry", "yaw", None, "rad", "yaw angle of the wheelset"),
    "creepage_x": Axis("tangential", "creepage", 0, "1", "longitudinal creepage xi"),
    "creepage_y": Axis("tangential", "creepage", 1, "1", "lateral creepage eta"),
    "spin": Axis("tangential", "creepage", 2, "1/m", "spin creepage phi"),
    "load": Axis("normal", "load", None, "N", "vertical wheel load"),
    "friction": Axis("tangential", "friction", None, "1", "coefficient of friction mu"),
}
"""The axes a table may have."""
_SETTINGS = {"geometry": WheelRailGeometry, "tangential": TangentialSettings,
             "normal": NormalSettings}
"""The settings record each axis's table names (:attr:`Axis.table`)."""
CREEPAGE_AXES = ("creepage_x", "creepage_y", "spin")
"""The axes of a wheel's creepages (in its side frame)."""
OTHER_AXES: dict[str, Axis] = {
    "roll": Axis("geometry", "roll", None, "rad", "roll angle of the wheelset (left side up)"),
}
"""Axes of the other kinds of table (:data:`KINDS`) only."""


def axis_info(name: str) -> Axis:
    """The :class:`Axis` of any kind of table (:data:`AXES`, :data:`OTHER_AXES`)."""
    return AXES[name] if name in AXES else OTHER_AXES[name]


DEFAULT_KIND = "contact"
"""``[table] kind`` of a spec that gives none: the table of exact solves of this module."""
CREEP_KIND = "creep"
"""``[table] kind`` of a normalised creep table (:mod:`.creepspec`, read by
:func:`~.kinds.load_any_spec`)."""
KINDS: dict[str, Any] = {}
"""The other kinds of table: ``[table] kind`` -> ``parse(raw, table)``, the parser of its
spec (the case's tables without ``[table]``, and ``[table]``), registered by its module
when the package is imported (:mod:`railcontact.table.geometry`)."""
OPTIONS = ("batch", "out_of_range", "kind")
"""Keys of ``[table]`` that are not axes."""
POLICIES = ("status", "clamp")
"""What a value outside an axis gives (``out_of_range``): ``status`` (out of range: the
table step's status 3 with zero outputs, an error from :class:`~.interpolate.ContactTable`)
or ``clamp`` (the axis's nearest end node's value, the step's message saying so)."""
DEFAULT_POLICY = "status"
MAX_POINTS = 10_000_000
"""Largest number of grid points of a table."""


class AxisGrid:
    """The grid of a spec's ``axes`` (name -> strictly increasing nodes): its names, shape
    and number of points."""

    axes: dict[str, np.ndarray]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self.axes)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for v in self.axes.values())

    @property
    def size(self) -> int:
        return math.prod(self.shape)


@dataclass(frozen=True)
class TableSpec(AxisGrid):
    """A validated table specification.

    Attributes
    ----------
    case
        The case dictionary (every default filled in), its axes at their first values.
    axes
        Axis name -> strictly increasing node values (SI units), in storage order; the last
        axis is the fastest.
    sides
        The wheels solved: ``("left", "right")`` or one of them.
    batch
        Points per batch along the fastest axis.
    out_of_range
        Axis -> what a value outside it gives (``"status"`` or ``"clamp"``).
    """

    case: dict[str, Any]
    axes: dict[str, np.ndarray]
    sides: tuple[str, ...]
    batch: int
    out_of_range: dict[str, str] = field(default_factory=dict)
    """Axis -> policy (:data:`POLICIES`) of the axes given one; the others
    :data:`DEFAULT_POLICY` (:meth:`policies`)."""

    def policies(self) -> dict[str, str]:
        """Every axis's out-of-range policy."""
        return {n: self.out_of_range.get(n, DEFAULT_POLICY) for n in self.axes}

    @property
    def batch_shape(self) -> tuple[int, ...]:
        """The batch grid: every axis but the fastest, then the runs along it."""
        *slow, fast = self.shape
        return (*slow, -(-fast // self.batch))

    def batch_points(self, index: tuple[int, ...]) -> list[tuple[int, ...]]:
        """The grid indices of the batch ``index`` (of :attr:`batch_shape`), in order."""
        *slow, b = index
        fast = self.shape[-1]
        return [(*slow, k) for k in range(b * self.batch, min((b + 1) * self.batch, fast))]

    def case_at(self, index: tuple[int, ...], side: str | None = None) -> dict[str, Any]:
        """The case dictionary of the grid point ``index`` (and of one wheel)."""
        return case_with(self.case, {n: float(self.axes[n][i])
                                     for n, i in zip(self.axes, index, strict=True)}, side)

    def case_at_values(self, values: dict[str, float], side: str | None = None
                       ) -> dict[str, Any]:
        """The case dictionary at any state (axis name -> value [SI]), e.g. between the
        nodes."""
        return case_with(self.case, values, side)

    def identity(self) -> dict[str, Any]:
        """What makes two tables the same: the case, the axes, the sides, the batch, and the
        SHA-256 of each profile file the case names (``profiles``: wheel/rail -> hex; a
        built-in profile has none). Compare identities with :func:`comparable`."""
        geo = self.case.get("geometry", {})
        profiles = {k: _sha256(geo[k]) for k in ("wheel", "rail")
                    if isinstance(geo.get(k), str) and Path(geo[k]).is_file()}
        return {"case": self.case, "axes": {n: [float(x) for x in v] for n, v in
                                           self.axes.items()},
                "sides": list(self.sides), "batch": self.batch, "profiles": profiles}


def _sha256(path: str) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def comparable(identity: dict[str, Any]) -> dict[str, Any]:
    """The part of an identity that decides whether a store holds a spec's table: without
    the case's ``name`` (the spec file's stem when unnamed) and with each profile file
    that has a hash stood for by its hash (not its absolute path), so that renaming the
    spec or moving the project keeps a table resumable, and a profile file changed in
    place does not."""
    case = {k: dict(v) if isinstance(v, dict) else v for k, v in identity.get("case", {}).items()
            if k != "name"}
    for key, digest in identity.get("profiles", {}).items():
        if isinstance(case.get("geometry"), dict) and key in case["geometry"]:
            case["geometry"][key] = f"sha256:{digest}"
    return {**{k: v for k, v in identity.items() if k != "profiles"}, "case": case}


def case_with(case: dict[str, Any], values: dict[str, float], side: str | None = None
              ) -> dict[str, Any]:
    """A copy of the case dictionary with the axes' ``values`` (and the wheel ``side``)."""
    out = {k: dict(v) if isinstance(v, dict) else v for k, v in case.items()}
    for name, x in values.items():
        ax = AXES[name]
        tab = out[ax.table]
        if ax.index is None:
            tab[ax.key] = x
            if name == "load":
                tab.pop("penetration", None)
        else:
            c = list(tab.get(ax.key, (0.0, 0.0, 0.0)))
            c[ax.index] = x
            tab[ax.key] = c
    if side is not None:
        out["geometry"]["side"] = side
    return out


def axis_count(name: str, value: Any) -> int:
    """The number of nodes of an axis from its ``[table]`` entry, without making the nodes
    (so that a huge count is refused before any memory is taken); at least 1, and 1 for an
    entry :func:`axis_values` refuses (with its own message)."""
    if isinstance(value, dict):
        value = value.get("values")
        explicit = True
    else:
        explicit = not (isinstance(value, list) and len(value) == 3)
    if not isinstance(value, list):
        return 1
    if explicit:
        return max(len(value), 1)
    count = value[2]
    if (not isinstance(count, (int, float)) or isinstance(count, bool)
            or not math.isfinite(count) or count != int(count)):
        return 1
    return max(int(count), 1)


def table_bytes(points: int, sides: int = 2) -> int:
    """Memory [bytes] of a table of ``points`` grid points and ``sides`` wheels read to
    interpolate (:class:`~.interpolate.ContactTable`: every quantity as float64, the status
    as int8)."""
    return points * sides * (8 * len(QUANTITIES) + 1)


def check_size(counts: dict[str, int], sides: int = 2) -> None:
    """Refuse a table of more than :data:`MAX_POINTS` points, naming each axis's count and
    the memory it would take (:func:`table_bytes`), before any axis is made.

    Raises
    ------
    CaseError
        When the product of ``counts`` (axis name -> number of nodes) exceeds
        :data:`MAX_POINTS`.
    """
    total = math.prod(counts.values())
    if total > MAX_POINTS:
        each = " x ".join(f"{n} {c}" for n, c in counts.items())
        raise CaseError(f"[table]: {total} points ({each}); at most {MAX_POINTS} (the table "
                        f"would take {table_bytes(total, sides) / 2**30:.3g} GiB in memory, "
                        f"its axes alone {8 * sum(counts.values()) / 2**30:.3g} GiB)")


def axis_values(name: str, value: Any) -> np.ndarray:
    """The node values of an axis from its ``[table]`` entry (module docstring)."""
    where = f"[table] {name}"
    if isinstance(value, dict):
        if set(value) != {"values"}:
            raise CaseError(f"{where}: an inline table takes only 'values', got "
                            f"{sorted(value)}")
        value = value["values"]
        explicit = True
    else:
        explicit = not (isinstance(value, list) and len(value) == 3)
    if not isinstance(value, list) or not value:
        raise CaseError(f"{where} must be [start, stop, count] or a list of values, got "
                        f"{value!r}")
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
               for v in value):
        raise CaseError(f"{where}: values must be finite numbers, got {value!r}")
    if explicit:
        x = np.array(value, dtype=float)
        if np.any(np.diff(x) <= 0):
            raise CaseError(f"{where}: the values must be strictly increasing, got {value!r}")
        return x
    start, stop, count = float(value[0]), float(value[1]), value[2]
    if count != int(count):
        raise CaseError(f"{where}: [start, stop, count] needs an integer count, got {count!r} "
                        "(three explicit values: { values = [a, b, c] })")
    count = int(count)
    if count < 1:
        raise CaseError(f"{where}: count must be at least 1, got {count}")
    if start > stop:
        raise CaseError(f"{where}: start {start:g} > stop {stop:g}")
    if count == 1 and start != stop:
        raise CaseError(f"{where}: count 1 needs start = stop, got {start:g} and {stop:g}")
    if count > 1 and start == stop:
        raise CaseError(f"{where}: start = stop = {start:g} with count {count}: give "
                        "count 1")
    return np.linspace(start, stop, count)


def parse_spec(raw: dict[str, Any]) -> TableSpec:
    """A :class:`TableSpec` from the tables of a spec file (a case plus ``[table]``).

    Raises
    ------
    CaseError
        For a bad case, a missing or empty ``[table]``, an unknown axis, a bad range.
    """
    raw = dict(raw)
    table = raw.pop("table", None)
    if not isinstance(table, dict) or not table:
        raise CaseError("a table spec needs a [table] with at least one axis (known: "
                        f"{', '.join(AXES)})")
    kind = table.get("kind", DEFAULT_KIND)
    if kind == CREEP_KIND:
        raise CaseError(f"[table] kind = {kind!r} is not a contact table: read the spec with "
                        "railcontact.table.load_any_spec")
    if kind != DEFAULT_KIND:
        if kind not in KINDS:
            raise CaseError("[table] kind must be one of "
                            f"{', '.join([DEFAULT_KIND, *KINDS, CREEP_KIND])}, got {kind!r}")
        return KINDS[kind](raw, table)
    unknown = sorted(set(table) - set(AXES) - set(OPTIONS))
    if unknown:
        raise CaseError(f"[table]: unknown axis {', '.join(unknown)}; known: "
                        f"{', '.join(AXES)} (and the option {', '.join(OPTIONS)})")
    names = [k for k in table if k in AXES]
    if not names:
        raise CaseError(f"[table] has no axis (known: {', '.join(AXES)})")
    check_size({n: axis_count(n, table[n]) for n in names})  # before any axis is made
    axes = {n: axis_values(n, table[n]) for n in names}
    geo = raw.get("geometry")
    if not isinstance(geo, dict) or geo.get("type") != "wheel-rail":
        raise CaseError("a table spec needs a wheel-rail case ([geometry] type = "
                        "'wheel-rail')")
    sides_given = "side" in geo
    if any(AXES[n].table == "tangential" for n in names) and "tangential" not in raw:
        raise CaseError("[table]: a creepage or spin axis needs a [tangential] table in the "
                        "case")
    friction = raw.get("tangential", {}).get("friction") if isinstance(
        raw.get("tangential"), dict) else None
    if isinstance(friction, dict):
        raise CaseError("[tangential] friction: a contact table takes one coefficient of "
                        "friction (a number); a friction table across the profile is for "
                        "railcontact solve and the exact step")
    for n in names:  # (each node within its setting's bounds, as a case's value is)
        check_axis_values(n, axes[n])
    if "friction" in names:
        for mu in axes["friction"]:
            if not mu > 0.0:
                raise CaseError(f"[table] friction: each coefficient of friction must be "
                                f"above 0, got {mu:g}")
    if "load" in names and "penetration" in raw.get("normal", {}):
        raise CaseError("[table] load: the case controls the penetration ([normal] "
                        "penetration); a load axis needs [normal] load")
    first = {n: float(v[0]) for n, v in axes.items()}
    case = Case.from_dict(case_with(raw, first) if isinstance(raw.get("normal"), dict)
                          else raw)
    d = case.to_dict()
    side = d["geometry"]["side"] if sides_given else "both"
    sides = ("left", "right") if side == "both" else (side,)
    d["geometry"]["side"] = side
    shape = [len(v) for v in axes.values()]
    batch = table.get("batch", shape[-1])
    if not isinstance(batch, int) or isinstance(batch, bool) or batch < 1:
        raise CaseError(f"[table] batch must be an integer >= 1, got {batch!r}")
    return TableSpec(case=d, axes=axes, sides=sides, batch=min(batch, shape[-1]),
                     out_of_range=parse_policies(table.get("out_of_range"), names))


def check_axis_values(name: str, values: np.ndarray) -> None:
    """Refuse a node of the axis ``name`` beyond the bounds of the setting it sets (a
    creepage beyond +-1000, a load above 1e8 N, a friction above 10: the points there
    would be built as holes, status out of range).

    Raises
    ------
    CaseError
        Naming the axis, the bounds and the node.
    """
    axis = AXES[name]
    settings = _SETTINGS[axis.table]
    for v in values:
        if axis.index is None:
            settings.check_value(axis.key, float(v), f"[table] {name}")
        else:
            settings.check_item(axis.key, float(v), f"[table] {name}")


def parse_policies(value: Any, names: list[str] | tuple[str, ...]) -> dict[str, str]:
    """Axis -> out-of-range policy from ``[table] out_of_range`` (a policy for every axis,
    or a table axis -> policy; None: none given).

    Raises
    ------
    CaseError
        For an unknown policy or an axis the table does not have.
    """
    if value is None:
        return {}
    if isinstance(value, str):
        value = {n: value for n in names}
    if not isinstance(value, dict):
        raise CaseError(f"[table] out_of_range must be one of {', '.join(POLICIES)} or a "
                        f"table axis -> policy, got {value!r}")
    out = {}
    for n, p in value.items():
        if n not in names:
            raise CaseError(f"[table] out_of_range: {n} is not an axis of the table "
                            f"({', '.join(names)})")
        if p not in POLICIES:
            raise CaseError(f"[table] out_of_range {n}: the policy must be one of "
                            f"{', '.join(POLICIES)}, got {p!r}")
        out[n] = p
    return out


def read_spec_file(path: str | Path) -> tuple[Path, dict[str, Any]]:
    """The path and the tables of a TOML table spec of any kind (``name`` defaults to the
    file's stem).

    Raises
    ------
    CaseError
        When the file does not exist or does not parse.
    """
    p = Path(path)
    if not p.is_file():
        raise CaseError(f"table spec not found: {p}")
    try:
        with p.open("rb") as f:
            raw = tomllib.load(f)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, ValueError) as exc:
        raise CaseError(f"table spec {p} is not valid TOML: {exc}") from None
    raw.setdefault("name", p.stem)
    return p, raw


def load_spec(path: str | Path) -> TableSpec:
    """Read a TOML table spec (a case file plus ``[table]``; SI units).

    Profile files named by a relative path are looked up beside the spec first.

    Raises
    ------
    CaseError
        When the file does not exist, does not parse or is not a valid spec.
    """
    return spec_of_file(*read_spec_file(path))


def spec_of_file(p: Path, raw: dict[str, Any]) -> TableSpec:
    """:func:`parse_spec` of the tables ``raw`` read from the file ``p`` (its relative
    profile paths looked up beside it first)."""
    geo = raw.get("geometry")
    if isinstance(geo, dict):
        for key in ("wheel", "rail"):
            value = geo.get(key)
            if isinstance(value, str) and value and not Path(value).is_absolute() \
                    and (p.parent / value).is_file():
                geo[key] = str((p.parent / value).resolve())
    return parse_spec(raw)
