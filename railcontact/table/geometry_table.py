"""Using a geometry table (:mod:`railcontact.table.geometry`): :class:`GeometryTable`
interpolates its quantities at any pose inside the axes, multilinear (a pose on a node
returns the node's values exactly), and gives the equivalent conicity of its rolling radius
difference.

A quantity is interpolated from the nodes of the pose's cell that have a weight (a pose
within :data:`SNAP` of a cell's width from a node is on it); a node
whose wheel is not ok (status out of range, not converged, not computed) makes that
wheel's values (and the wheelset's) NaN with its status, as a patch that a node used does
not have makes that patch's values NaN: a patch is interpolated only where every node used
has it (:attr:`GeometryState.n_patches` counts those). A value outside an axis is an error
naming the axis and its range, unless the axis's out-of-range policy (the spec's ``[table]
out_of_range``, kept in the store) is ``clamp``: it is then moved to the axis's nearest end.
"""

from __future__ import annotations

import csv
import json
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import CaseError, RailContactError
from .geometry import KIND, N_PATCHES, PATCH, PATCHES, QUANTITIES, WHEEL, WHEELSET
from .interpolate import TableHolesWarning
from .spec import DEFAULT_POLICY, axis_info, parse_policies
from .store import IDENTITY, POLICY_ATTR, kind_of, read_table, reader_of
from .variables import NOT_COMPUTED, OK, failed_counts, failed_text

SIDES = ("left", "right")
SNAP = 1e-9
"""A pose within this fraction of a cell from a node is on the node (a value written as
the node's, e.g. 0.0045 for ``linspace(-0.01, 0.01, 201)[145]``, uses that node alone)."""


@dataclass(frozen=True)
class GeometryState:
    """A geometry table's quantities at one pose (SI units; names of
    :data:`~.geometry.QUANTITIES`).

    ``wheelset`` name -> value; ``wheels`` side -> (name -> value; a patch quantity an
    array over the patches, from the field side); ``status`` side -> the largest status
    of the nodes used; ``n_patches`` side -> the patches every node used has;
    ``clamped`` the axes whose value was clamped to their nearest end.
    """

    wheelset: dict[str, float]
    wheels: dict[str, dict[str, float | np.ndarray]]
    status: dict[str, int]
    n_patches: dict[str, int]
    clamped: tuple[str, ...] = ()

    def __getitem__(self, name: str) -> float:
        return self.wheelset[name]


def _require_geometry(path: str | Path, attrs: dict) -> None:
    kind = kind_of(attrs)
    if kind != KIND:
        raise RailContactError(f"{path} is a {kind} table, not a geometry table ([table] "
                               f"kind = 'geometry'): open it with {reader_of(kind)}")


class GeometryTable:
    """A geometry table read into memory (use :meth:`open`): ``axes`` each axis's nodes,
    ``case`` the case dictionary, ``roll_mode`` (``"rigid"``, ``"equal-loads"`` or
    ``"given"``), ``out_of_range`` each axis's policy, ``failed`` the failed point-wheels
    by status."""

    def __init__(self, axes: dict[str, np.ndarray], arrays: dict[str, np.ndarray],
                 case: dict, path: str = "", out_of_range: dict[str, str] | None = None
                 ) -> None:
        self.axes = {n: np.asarray(v, dtype=float) for n, v in axes.items()}
        self.case, self.path = case, path
        roll = case["geometry"]["roll"]
        self.roll_mode = roll if isinstance(roll, str) else "given"
        self._arrays = arrays
        self.status = np.asarray(arrays["status"]).astype(np.int8)
        self.failed = failed_counts(self.status)
        self.out_of_range = {n: DEFAULT_POLICY for n in self.axes}
        try:
            self.out_of_range.update(parse_policies(out_of_range, tuple(self.axes)))
        except CaseError as exc:
            raise RailContactError(str(exc).replace("[table] ", "")) from None

    @classmethod
    def open(cls, path: str | Path, out_of_range: dict[str, str] | str | None = None
             ) -> GeometryTable:
        """Read the geometry table at ``path`` (``out_of_range``: a policy for every axis,
        or axis -> policy, over the store's).

        Raises
        ------
        RailContactError
            When there is no table at ``path`` or it is not a geometry table.
        """
        attrs, _ = read_table(path, [])
        _require_geometry(path, attrs)
        _, arrays = read_table(path, ["status", N_PATCHES.name, *(q.name for q in QUANTITIES)])
        ident = json.loads(attrs[IDENTITY])
        axes = {n: np.asarray(v, dtype=float) for n, v in ident["axes"].items()}
        policies = json.loads(attrs.get(POLICY_ATTR, "{}"))
        if isinstance(out_of_range, str):
            out_of_range = {n: out_of_range for n in axes}
        policies.update(out_of_range or {})
        table = cls(axes, arrays, ident["case"], str(path), policies)
        if table.failed:
            warnings.warn(f"table {path}: {failed_text(table.failed)}; interpolation at a "
                          "pose using one of them returns its status, not a value "
                          "('railcontact table show' lists them)", TableHolesWarning,
                          stacklevel=2)
        return table

    def node(self, index: tuple[int, ...]) -> GeometryState:
        """The stored values of the node ``index`` (one index per axis)."""
        return self(**{n: float(v[i]) for (n, v), i in zip(self.axes.items(), index,
                                                           strict=True)})

    def _cells(self, state: dict[str, np.ndarray]) -> tuple[list, tuple[str, ...]]:
        """Per axis: (lower node, upper node, fraction) arrays at the poses ``state``, and
        the axes clamped."""
        unknown = sorted(set(state) - set(self.axes))
        if unknown:
            raise RailContactError(f"the table has no axis {', '.join(unknown)}; its axes: "
                                   f"{', '.join(self.axes)}")
        lacking = [n for n in self.axes if n not in state]
        if lacking:
            raise RailContactError(f"give a value of each axis: {', '.join(lacking)} lacking")
        cells, clamped = [], []
        for n, nodes in self.axes.items():
            x = np.atleast_1d(np.asarray(state[n], dtype=float))
            lo_end, hi_end = nodes[0], nodes[-1]
            bad = ~((x >= lo_end) & (x <= hi_end))
            if bad.any():
                finite = np.isfinite(x)
                if self.out_of_range[n] != "clamp" or not finite.all():  # (never clamped)
                    v = float(x[np.flatnonzero(bad if finite.all() else ~finite)[0]])
                    raise RailContactError(f"{n} = {v:g} {axis_info(n).unit} is outside the "
                                           f"table [{lo_end:g}, {hi_end:g}]")
                x = np.clip(x, lo_end, hi_end)
                clamped.append(n)
            if len(nodes) == 1:
                zero = np.zeros(x.shape, dtype=np.intp)
                cells.append((zero, zero, np.zeros(x.shape)))
                continue
            lo = np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, len(nodes) - 2)
            t = (x - nodes[lo]) / (nodes[lo + 1] - nodes[lo])
            t = np.where(t < SNAP, 0.0, np.where(t > 1.0 - SNAP, 1.0, t))
            cells.append((lo, lo + 1, t))
        return cells, tuple(clamped)

    def _corners(self, cells: list):
        """(index arrays, weight) of each corner of the cells (weight 0: not used)."""
        corners = [((), np.ones(cells[0][0].shape))]
        for lo, hi, t in cells:
            corners = [c for ix, w in corners
                       for c in (((*ix, lo), w * (1.0 - t)), ((*ix, hi), w * t))]
        return corners

    def values(self, name: str, **state) -> np.ndarray:
        """The quantity ``name`` interpolated at the poses ``state`` (axis -> value or array
        of values, every axis): an array over the poses (then the sides, then the
        patches); NaN where a node used is not ok (or lacks the patch)."""
        if name not in self._arrays or name in ("status", N_PATCHES.name, "side"):
            raise RailContactError(f"no quantity {name!r}; the quantities: "
                                   f"{', '.join(q.name for q in QUANTITIES)}")
        cells, _ = self._cells(state)
        return self._interpolate(self._masked(name), cells)

    def stored(self, name: str) -> np.ndarray:
        """The node values of ``name`` over the axes (then the sides, then the patches):
        NaN where their wheel (a wheelset's quantity: a wheel) is not ok; ``n_patches`` as
        stored (0 where not ok)."""
        if name == N_PATCHES.name:
            return np.asarray(self._arrays[name]).copy()
        if name not in self._arrays or name in ("status", "side"):
            raise RailContactError(f"no quantity {name!r}; the quantities: "
                                   f"{', '.join(q.name for q in QUANTITIES)}, n_patches")
        return self._masked(name)

    def _masked(self, name: str) -> np.ndarray:
        """The stored values of ``name``, NaN where their wheel (or a wheel, for the
        wheelset's) is not ok."""
        a = np.asarray(self._arrays[name], dtype=float).copy()
        ok = self.status == OK
        if a.ndim == ok.ndim - 1:
            a[~ok.all(axis=-1)] = np.nan
        else:
            a[~ok] = np.nan
        return a

    def _interpolate(self, a: np.ndarray, cells: list) -> np.ndarray:
        out = None
        for ix, w in self._corners(cells):
            used = w > 0
            v = a[ix]
            wt = w.reshape(w.shape + (1,) * (v.ndim - w.ndim))
            term = np.where(used.reshape(wt.shape), wt * v, 0.0)
            out = term if out is None else out + term
        return out

    def __call__(self, **state: float) -> GeometryState:
        """Every quantity at one pose (axis -> value, every axis)."""
        cells, clamped = self._cells(state)
        wheelset = {q.name: float(self._interpolate(self._masked(q.name), cells)[0])
                    for q in WHEELSET}
        status = {s: int(OK) for s in SIDES}
        for ix, w in self._corners(cells):
            used = w[0] > 0
            if used:
                for j, s in enumerate(SIDES):
                    st = int(self.status[tuple(i[0] for i in ix)][j])
                    if st == NOT_COMPUTED or (status[s] != NOT_COMPUTED and st > status[s]):
                        status[s] = st
        wheels = {s: {} for s in SIDES}
        for q in WHEEL + PATCH:
            v = self._interpolate(self._masked(q.name), cells)[0]
            for j, s in enumerate(SIDES):
                wheels[s][q.name] = float(v[j]) if q in WHEEL else v[j].copy()
        n = {s: int(np.count_nonzero(np.isfinite(wheels[s]["patch_rolling_radius"])))
             for s in SIDES}
        return GeometryState(wheelset, wheels, status, n, clamped)

    def rolling_radius_difference(self, lateral: np.ndarray, **others: float) -> np.ndarray:
        """``delta_r`` [m] at the lateral displacements ``lateral`` [m] (the other axes at
        ``others``)."""
        if "lateral_displacement" not in self.axes:
            raise RailContactError("the table has no lateral_displacement axis")
        y = np.asarray(lateral, dtype=float)
        state = {n: np.full(y.shape, float(others[n])) for n in others}
        return self.values("rolling_radius_difference", lateral_displacement=y, **state)

    def equivalent_conicity(self, amplitude: float, **others: float) -> float:
        """The equivalent conicity [-] for the lateral ``amplitude`` [m] by harmonic
        linearisation of the table's ``delta_r(y)`` (the other axes at ``others``): as
        :func:`railcontact.geometry.conicity.equivalent_conicity` (2000 points of theta),
        with ``delta_r`` interpolated between the table's nodes.

        Raises
        ------
        RailContactError
            For an amplitude that is not positive or beyond the lateral axis (clamped
            under the clamp policy), a NaN ``delta_r`` (a node not ok).
        """
        a = float(amplitude)
        if not a > 0 or not math.isfinite(a):
            raise RailContactError(f"amplitude must be a positive length [m], got {amplitude!r}")
        theta = np.linspace(0.0, 2 * math.pi, 2000, endpoint=False)
        dr = self.rolling_radius_difference(a * np.sin(theta), **others)
        if not np.isfinite(dr).all():
            raise RailContactError(f"delta_r is not defined within +-{a:g} m (a node there "
                                   "is not ok: 'railcontact table show')")
        return float(np.mean(dr * np.sin(theta)) / a)


def summary_lines(ds) -> list[str]:
    """The lines of ``railcontact table show`` particular to a geometry table."""
    ok = (ds["status"].values == OK).all(axis=-1)
    ident = json.loads(ds.attrs[IDENTITY])
    roll = ident["case"]["geometry"]["roll"]
    lines = [f"geometry table: roll {roll if isinstance(roll, str) else 'given'}"
             + ("" if isinstance(roll, str) or "roll" in ident["axes"]
                else f" ({roll:g} rad)")
             + f"; patches at most {PATCHES} per wheel"]
    counts = ds[N_PATCHES.name].values[ds["status"].values == OK]
    if counts.size:
        lines.append("  patches per wheel (ok wheels): " + ", ".join(
            f"{k}: {int(np.count_nonzero(counts == k))}" for k in range(1, PATCHES + 1)
            if np.any(counts == k)))
    lines.append("values (points with both wheels ok):")
    for q in WHEELSET:
        x = ds[q.name].values[ok]
        if x.size:
            lines.append(f"  {q.name:28s} [{q.unit}] from {x.min():.6g} to {x.max():.6g}")
    return lines


def export_csv(ds, names: list[str], out: Path) -> Path:
    """A geometry table as CSV, one row per node and wheel: the axes, ``side``, the
    wheelset's quantities (the same on both rows of a node), the wheel's, ``status``,
    ``n_patches`` and each patch's quantities as ``<name>_<k>`` (k = 1 from the field
    side); SI units; ``nan`` where undefined."""
    order = [*names, "side"]
    sides = ds["side"].values.tolist()
    wheelset = {q.name: ds[q.name].transpose(*names).values for q in WHEELSET}
    wheel = {q.name: ds[q.name].transpose(*order).values for q in WHEEL}
    patch = {q.name: ds[q.name].transpose(*order, "patch").values for q in PATCH}
    status = ds["status"].transpose(*order).values
    count = ds[N_PATCHES.name].transpose(*order).values
    grids = np.meshgrid(*[ds[n].values for n in names], indexing="ij")
    with out.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow([*names, "side", *wheelset, *wheel, "status", N_PATCHES.name,
                    *(f"{n}_{k + 1}" for n in patch for k in range(PATCHES))])
        for index in np.ndindex(*grids[0].shape):
            axes = [repr(float(g[index])) for g in grids]
            for j, side in enumerate(sides):
                w.writerow([*axes, side, *(repr(float(a[index])) for a in wheelset.values()),
                            *(repr(float(a[(*index, j)])) for a in wheel.values()),
                            str(int(status[(*index, j)])), str(int(count[(*index, j)])),
                            *(repr(float(a[(*index, j, k)])) for a in patch.values()
                              for k in range(PATCHES))])
    return out


def data_names() -> list[str]:
    """The data variables of a geometry table (an export's)."""
    return [q.name for q in QUANTITIES] + ["status", N_PATCHES.name]


def plot_geometry(ds, names: list[str], out: Path):
    """Figure of a geometry table against its first axis (the others at their middle
    nodes): ``delta_r``, both wheels' contact angles and the roll."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = names[0]
    mid = {m: ds.sizes[m] // 2 for m in names if m != n}
    cut = ds.isel(mid)
    ok = (cut["status"] == OK).all("side").values
    x = cut[n].values
    scale = 1e3 if axis_info(n).unit in ("m", "rad") else 1.0
    fig, axs = plt.subplots(1, 3, figsize=(12, 3.6))
    axs[0].plot(x * scale, np.where(ok, cut["rolling_radius_difference"].values, np.nan) * 1e3,
                "o-", ms=3)
    axs[0].set_ylabel("rolling radius difference [mm]")
    for s in cut["side"].values.tolist():
        a = cut["contact_angle"].sel(side=s).values
        axs[1].plot(x * scale, np.degrees(np.where(ok, a, np.nan)), "o-", ms=3, label=s)
    axs[1].set_ylabel("contact angle of the first contact [deg]")
    axs[1].legend(fontsize=8)
    axs[2].plot(x * scale, np.where(ok, cut["wheelset_roll"].values, np.nan) * 1e3, "o-", ms=3)
    axs[2].set_ylabel("roll [mrad]")
    unit = {"m": "mm", "rad": "mrad"}.get(axis_info(n).unit, axis_info(n).unit)
    for ax in axs:
        ax.set_xlabel(f"{n} [{unit}]")
        ax.grid(alpha=0.3)
    fig.suptitle(", ".join(f"{m} = {float(cut[m].values):g}" for m in mid) or None,
                 fontsize=8)
    fig.tight_layout()
    return fig


__all__ = ["GeometryState", "GeometryTable", "data_names", "export_csv", "plot_geometry",
           "summary_lines"]
