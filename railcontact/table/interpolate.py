"""Using a table: :class:`ContactTable` interpolates its quantities at any point inside the
axes.

``linear`` is multilinear over the axes (the nodes around the point, weights the products
of the fractions along each axis; a point on a node returns the node's values exactly);
``cubic`` needs at least 4 nodes on every axis: on a wheel whose nodes are all ok it is
the tensor-product not-a-knot cubic spline through all of them (:func:`cubic_spline`; it
reproduces a cubic polynomial and returns each node's values); when
some node of that wheel is not ok (NaN values: no contact, out of range, not converged, not
computed) a spline, which depends on whole grid lines, cannot be fitted, so it is the local
tensor-product cubic through the 4 nodes around the point on each axis when all of those are
ok, else the multilinear value with the linear status. A point outside an axis is a
:class:`~railcontact.errors.RailContactError` naming the axis and its range, unless the
axis's out-of-range policy (``out_of_range``: the spec's ``[table] out_of_range``, kept in
the store) is ``clamp``: its value is then moved to the axis's nearest end (named in
:attr:`Interpolated.clamped`). The status of
an interpolated point is the largest status of the nodes it uses (ok only when all of them
are; not computed when any is); a node not ok (or not computed) makes the values NaN with
that status.
"""

from __future__ import annotations

import bisect
import json
import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from ..errors import CaseError, RailContactError, check_number
from .spec import AXES, DEFAULT_POLICY, parse_policies
from .store import (
    FLANGE,
    IDENTITY,
    POLICY_ATTR,
    check_quantities,
    read_table,
    refuse_kind,
    wheel_flange,
)
from .variables import (
    NOT_COMPUTED,
    OK,
    QUANTITIES,
    STATUS_MEANINGS,
    failed_counts,
    failed_text,
)

METHODS = ("linear", "cubic")


class TableHolesWarning(UserWarning):
    """A table opened with failed points (not converged, out of range, not computed):
    interpolation at a state that uses one returns its status, not a value."""


@dataclass(frozen=True)
class Interpolated:
    """The table's quantities at one point for one wheel (SI units; names of
    :data:`~.variables.QUANTITIES`), with the status of the nodes used."""

    values: dict[str, float]
    status: int
    clamped: tuple[str, ...] = ()
    """The axes whose value was outside and clamped to their nearest end (policy
    ``clamp``)."""

    def __getitem__(self, name: str) -> float:
        return self.values[name]


@numba.njit(cache=True, nogil=True)
def _multilinear(knots, meta, x, table, out):  # pragma: no cover - jit
    """``out`` = the multilinear value at ``x`` (inside the axes) of ``table`` (nodes in C
    order, quantities); ``meta`` = (starts, counts, strides) of the ``d`` axes: the nodes
    of axis ``a`` are ``knots[starts[a]:starts[a] + counts[a]]``, its stride
    ``strides[a]`` (one array: fewer arguments to dispatch). Corners of zero weight are not read (a
    point on a node is that node exactly). Returns the flat index of the cell's first
    node. A point outside axis ``a``: returns ``-1 - a``, ``out`` untouched."""
    d = x.shape[0]
    starts, counts, strides = meta[:d], meta[d:2 * d], meta[2 * d:]
    base = 0
    ncorner = 1
    offs = np.zeros(1 << d, np.int64)
    ws = np.ones(1 << d)
    for a in range(d):
        n = counts[a]
        if n == 1:
            continue
        s0 = starts[a]
        v = x[a]
        if not knots[s0] <= v <= knots[s0 + n - 1]:  # NaN too
            return -1 - a
        lo, hi = 0, n - 1
        while hi - lo > 1:
            mid = (lo + hi) >> 1
            if knots[s0 + mid] <= v:
                lo = mid
            else:
                hi = mid
        t = (v - knots[s0 + lo]) / (knots[s0 + lo + 1] - knots[s0 + lo])
        base += lo * strides[a]
        if t == 0.0:
            continue
        if t == 1.0:
            base += strides[a]
            continue
        for c in range(ncorner):
            offs[ncorner + c] = offs[c] + strides[a]
            ws[ncorner + c] = ws[c] * t
            ws[c] *= 1.0 - t
        ncorner *= 2
    nq = table.shape[1]
    for q in range(nq):
        out[q] = 0.0
    for c in range(ncorner):
        w = ws[c]
        r = base + offs[c]
        for q in range(nq):
            out[q] += w * table[r, q]
    return base


def cubic_spline(axes: tuple[np.ndarray, ...], values: np.ndarray):
    """The tensor-product cubic spline with not-a-knot ends through ``values`` (shape
    (n1, ..., nd, ...): a node's quantities last) on the nodes ``axes`` (each at least 4,
    increasing): scipy's ``NdBSpline``, its coefficients solved exactly along one axis after
    the other (``make_interp_spline``'s banded solve; scipy's ``RegularGridInterpolator``
    with ``method="cubic"`` solves the whole system iteratively, to about 1e-6, and misses
    the nodes by that much)."""
    from scipy.interpolate import NdBSpline, make_interp_spline

    c, knots = np.asarray(values, dtype=float), []
    for k, nodes in enumerate(axes):
        b = make_interp_spline(np.asarray(nodes, dtype=float), c, k=3, axis=k)
        knots.append(b.t)
        c = np.moveaxis(b.c, 0, k)  # (the BSpline's coefficients: its axis first)
    return NdBSpline(tuple(knots), c, 3)


def check_method_fits(axes: dict[str, np.ndarray], method: str) -> None:
    """Raise a :class:`RailContactError` for an interpolation ``method`` unknown, or one
    the table's ``axes`` (name -> nodes) are too short for (cubic: 4 nodes an axis)."""
    if method not in METHODS:
        raise RailContactError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    short = [f"{n} ({len(v)})" for n, v in axes.items() if len(v) < 4]
    if method == "cubic" and short:
        raise RailContactError("cubic interpolation needs at least 4 nodes on every axis: "
                               f"{', '.join(short)}; use method 'linear'")


def _lagrange4(nodes: list[float], v: float) -> np.ndarray:
    """The weights of the 4 ``nodes`` in the cubic through them, evaluated at ``v``."""
    w = np.ones(4)
    for a in range(4):
        for b in range(4):
            if b != a:
                w[a] *= (v - nodes[b]) / (nodes[a] - nodes[b])
    return w


def outside(name: str, value: float, nodes: list[float]) -> str:
    """The message for a value outside an axis."""
    return (f"{name} = {value:g} {AXES[name].unit} is outside the table "
            f"[{nodes[0]:g}, {nodes[-1]:g}]")


def _cells_ok(ok: np.ndarray) -> np.ndarray:
    """For each node: whether it and the nodes after it along every axis (the 2^d corners
    of the cell it starts) are all ok; nodes beyond the last count as ok (never used)."""
    out = ok.copy()
    for a in range(ok.ndim):
        if ok.shape[a] < 2:
            continue
        nxt = np.ones_like(out)
        src = [slice(None)] * ok.ndim
        dst = [slice(None)] * ok.ndim
        src[a], dst[a] = slice(1, None), slice(None, -1)
        nxt[tuple(dst)] = out[tuple(src)]
        out &= nxt
    return out


class ContactTable:
    """A contact table read into memory, ready to interpolate.

    Use :meth:`open`. ``axes`` maps each axis to its nodes, ``sides`` the wheels,
    ``case`` the case dictionary the table was built from, ``names`` the quantities.
    """

    def __init__(self, axes: dict[str, np.ndarray], sides: tuple[str, ...],
                 values: np.ndarray, status: np.ndarray, case: dict, path: str = "",
                 flange: tuple[float, float] | None = None,
                 missing: tuple[str, ...] = (),
                 out_of_range: dict[str, str] | str | None = None) -> None:
        self.axes = {n: np.asarray(v, dtype=float) for n, v in axes.items()}
        self.sides = tuple(sides)
        self.names = tuple(q.name for q in QUANTITIES)
        self.case, self.path = case, path
        self.missing = tuple(missing)
        """Quantities the store lacks (written by an earlier railcontact): NaN here."""
        self._flange = None if flange is None else (float(flange[0]), float(flange[1]))
        self._values = values  # (*axes, side, quantity)
        self._status = status  # (*axes, side)
        self._nodes = [list(map(float, v)) for v in self.axes.values()]
        shape = values.shape[:-2]
        self._strides = [int(math.prod(shape[k + 1:])) for k in range(len(shape))]
        self._axes_info = list(zip(self._nodes, self._strides, strict=True))
        self._knots = np.concatenate([np.asarray(v, float) for v in self._nodes])
        counts = np.array([len(v) for v in self._nodes], dtype=np.int64)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        self._meta = np.concatenate([starts, counts, self._strides]).astype(np.int64)
        flat = values.reshape(-1, len(self.sides), len(self.names))
        self._side_values = [np.ascontiguousarray(flat[:, j]) for j in range(len(self.sides))]
        self._flat_status = status.reshape(-1, len(self.sides))
        self._cell_ok = [_cells_ok(status[..., j] == OK).ravel().tolist()
                         for j in range(len(self.sides))]
        self._cubic: dict[str, object] = {}
        self.failed = failed_counts(status)
        """Point-wheels of each failed status (:func:`~.variables.failed_counts`): empty
        for a table without holes."""
        self.out_of_range = {n: DEFAULT_POLICY for n in self.axes}
        """Axis -> what a value outside it gives: ``"status"`` (an error here, status 3 in
        a table step) or ``"clamp"`` (the nearest end's value)."""
        try:
            self.out_of_range.update(parse_policies(out_of_range, tuple(self.axes)))
        except CaseError as exc:
            raise RailContactError(str(exc).replace("[table] ", "")) from None
        self._clamp = [(k, n, nodes[0], nodes[-1]) for k, (n, nodes) in
                       enumerate(zip(self.axes, self._nodes, strict=True))
                       if self.out_of_range[n] == "clamp"]

    @classmethod
    def open(cls, path: str | Path, out_of_range: dict[str, str] | str | None = None
             ) -> ContactTable:
        """Read the table at ``path`` (a store of ``railcontact table build``).

        ``out_of_range`` (a policy for every axis, or axis -> policy: ``"status"`` or
        ``"clamp"``) overrides the store's (the spec's ``[table] out_of_range``).

        Warns (:class:`TableHolesWarning`) when some points failed: how many of each
        status (also in :attr:`failed`).

        Raises
        ------
        RailContactError
            When there is no table at ``path``.
        """
        attrs, arrays = read_table(path, ["status"] + [q.name for q in QUANTITIES])
        refuse_kind(path, attrs, "ContactTable (table check, the FMU's table mode)")
        ident = json.loads(attrs[IDENTITY])
        axes = {n: np.asarray(v, dtype=float) for n, v in ident["axes"].items()}
        check_quantities(path, arrays)
        missing = tuple(q.name for q in QUANTITIES if q.name not in arrays)
        status = np.asarray(arrays["status"]).astype(np.int8)
        values = np.stack([np.full(status.shape, np.nan) if q.name in missing else
                           np.asarray(arrays[q.name], dtype=float) for q in QUANTITIES], axis=-1)
        flange = json.loads(attrs[FLANGE]) if FLANGE in attrs else None
        policies = json.loads(attrs.get(POLICY_ATTR, "{}"))
        if isinstance(out_of_range, str):
            out_of_range = {n: out_of_range for n in axes}
        policies.update(out_of_range or {})
        table = cls(axes, tuple(arrays["side"]), values, status, ident["case"],
                    str(path), flange, missing, policies)
        if table.failed:
            warnings.warn(f"table {path}: {failed_text(table.failed)}; interpolation at a "
                          "state using one of them returns its status, not a value "
                          "('railcontact table show' lists them)", TableHolesWarning,
                          stacklevel=2)
        return table

    @property
    def flange(self) -> tuple[float, float]:
        """Profile coordinate S [m] and angle [rad] of the steepest point of the wheel's
        flange (the store's, else from the case's wheel profile,
        :func:`~.store.wheel_flange`).

        Raises
        ------
        RailContactError
            When the store does not hold it and the wheel profile cannot be read.
        """
        if self._flange is None:
            try:
                self._flange = tuple(wheel_flange(self.case))
            except RailContactError as exc:
                raise RailContactError(f"the table {self.path} does not hold its wheel's "
                                       f"flange, and its wheel profile cannot be read: {exc}"
                                       ) from None
        return self._flange

    # -- lookup --------------------------------------------------------------------------
    def _side(self, side: str) -> int:
        try:
            return self.sides.index(side)
        except ValueError:
            raise RailContactError(f"the table has no {side!r} wheel (it has "
                                   f"{', '.join(self.sides)})") from None

    def _coordinates(self, point: dict[str, float]) -> list[float]:
        if not isinstance(point, Mapping):
            raise RailContactError("a table's point is a mapping of axis name to value "
                                   f"(its axes: {', '.join(self.axes)}), got {point!r}")
        missing = [n for n in self.axes if n not in point]
        extra = [n for n in point if n not in self.axes]
        if missing or extra:
            raise RailContactError(
                f"the table's axes are {', '.join(self.axes)}; "
                + (f"missing {', '.join(missing)}" if missing else "")
                + ("; " if missing and extra else "")
                + (f"not axes of this table: {', '.join(extra)}" if extra else ""))
        x = [check_number(n, point[n], "" if AXES[n].unit == "1" else AXES[n].unit)
             for n in self.axes]
        x, _ = self.clamp(x)
        for n, nodes, v in zip(self.axes, self._nodes, x, strict=True):
            if not nodes[0] <= v <= nodes[-1]:  # NaN fails too
                raise RailContactError(outside(n, v, nodes))
        return x

    def clamp(self, x: list[float]) -> tuple[list[float], tuple[str, ...]]:
        """The coordinates ``x`` (in axis order) with each finite value of an axis whose
        policy is ``clamp`` moved to the nearest end of the axis when outside it, and the
        names of those axes (a value that is not finite is never clamped: left for the
        range check, which refuses it)."""
        if not self._clamp:
            return x, ()
        x = list(x)
        moved = []
        for k, name, lo, hi in self._clamp:
            v = x[k]
            if (v < lo or v > hi) and math.isfinite(v):
                x[k] = lo if v < lo else hi
                moved.append(name)
        return x, tuple(moved)

    def __call__(self, point: dict[str, float], side: str = "left",
                 method: str = "linear") -> Interpolated:
        """The quantities at ``point`` (axis name -> value [SI]) for the wheel ``side``.

        Raises
        ------
        RailContactError
            For a point outside the axes, a missing axis, an unknown side or method.
        """
        j = self._side(side)
        x = self._coordinates(point)
        clamped = tuple(n for n, v in zip(self.axes, x, strict=True) if v != float(point[n]))
        check_method_fits(self.axes, method)
        if method == "linear":
            vals, status = self.linear(x, j)
        else:
            vals, status = self._cubic_at(x, j)
        return Interpolated(dict(zip(self.names, vals.tolist(), strict=True)), status,
                            clamped)

    def linear(self, x: list[float], j: int) -> tuple[np.ndarray, int]:
        """Multilinear values (quantities in :attr:`names` order) and status at the
        coordinates ``x`` (inside the axes, in axis order) for the wheel index ``j``
        (the time loop's path: a compiled kernel on the nodes around ``x``)."""
        out = np.empty(len(self.names))
        base = _multilinear(self._knots, self._meta, np.array(x, dtype=float),
                            self._side_values[j], out)
        if base < 0:
            self._coordinates(dict(zip(self.axes, x)))  # noqa: B905 - raises, naming it
        if self._cell_ok[j][base]:  # every node around x is ok (the common case)
            return out, OK
        st = self._flat_status[self._corners(x), j]
        return out, (NOT_COMPUTED if st.min() == NOT_COMPUTED else int(st.max()))

    def _corners(self, x: list[float]) -> list[int]:
        """The flat indices of the nodes with a non-zero weight at ``x``."""
        idx = [0]
        for (nodes, stride), v in zip(self._axes_info, x):  # noqa: B905 - same length
            n = len(nodes)
            if n == 1:
                continue
            i = min(max(bisect.bisect_right(nodes, v) - 1, 0), n - 2)
            t = (v - nodes[i]) / (nodes[i + 1] - nodes[i])
            lo = [k + i * stride for k in idx]
            idx = (lo if t == 0.0 else [k + stride for k in lo] if t == 1.0 else
                   lo + [k + stride for k in lo])
        return idx

    def _cubic_at(self, x: list[float], j: int) -> tuple[np.ndarray, int]:
        key = self.sides[j]
        if bool(np.all(self._status[..., j] == OK)):  # a spline over the whole grid
            if key not in self._cubic:
                self._cubic[key] = cubic_spline(tuple(self.axes.values()),
                                                self._values[..., j, :])
            return self._cubic[key](np.array([x]))[0], OK
        # Some node of this wheel is not ok (NaN values): a spline would depend on it along
        # whole grid lines, so use the local cubic through the 4 nodes around x on each axis
        # when all of them are ok, else the multilinear value with its status.
        lo, weights = [], []
        for nodes, v in zip(self._nodes, x, strict=True):
            i = min(max(bisect.bisect_right(nodes, v) - 2, 0), len(nodes) - 4)
            lo.append(slice(i, i + 4))
            weights.append(_lagrange4(nodes[i:i + 4], v))
        if not bool(np.all(self._status[(*lo, j)] == OK)):
            return self.linear(x, j)
        vals = self._values[(*lo, j)]
        for w in weights:  # contract the first remaining axis each time
            vals = np.tensordot(w, vals, axes=(0, 0))
        return vals, OK

    def node(self, index: tuple[int, ...], side: str = "left") -> Interpolated:
        """The stored values of the node ``index`` (one index per axis, each from 0 to the
        axis's nodes less one)."""
        j = self._side(side)
        shape = tuple(len(v) for v in self._nodes)
        try:
            ok = (len(index) == len(shape)
                  and all(isinstance(i, (int, np.integer)) and not isinstance(i, bool)
                          and 0 <= i < n for i, n in zip(index, shape, strict=True)))
        except TypeError:  # (not a sequence)
            ok = False
        if not ok:
            ranges = ", ".join(f"{a}: 0 .. {n - 1}"
                               for a, n in zip(self.axes, shape, strict=True))
            raise RailContactError(f"a node's index is one integer per axis ({ranges}), "
                                   f"got {index!r}")
        index = tuple(int(i) for i in index)
        return Interpolated(dict(zip(self.names, map(float, self._values[(*index, j)]),
                                     strict=True)), int(self._status[(*index, j)]))

    def describe_status(self, status: int) -> str:
        return STATUS_MEANINGS.get(status, str(status))

    @property
    def complete(self) -> bool:
        """Every point computed and ok."""
        return bool(np.all(self._status == OK))
