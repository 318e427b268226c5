"""Refining a table where it errs: nodes added along an axis where the checked
interpolation error or a contact jump between neighbouring nodes exceeds a target.

An interval of an axis (two neighbouring nodes) is split at its middle when

- the kept check (:mod:`.check`) has a sample in it whose error exceeds its target
  (:class:`Targets`: each measure of :data:`~.check.MEASURES`) and that error is the
  axis's (:func:`blame`), or
- the contact jumps across it: at some node pair along that axis (any other axes' nodes,
  any wheel) both ok with a different number of patches or contact angles differing by
  more than ``jump_angle``, or one ok and the other without contact,

and it is wider than :data:`MIN_FRACTION` of the axis's range. A check's sample lies in an
interval of every axis; its error is the axis's when the linear interpolation error that
the nodes' second differences along that axis predict in its cell
(``|f''| h^2 / 8``, from the nodes on either side; the measures' scales) exceeds half the
target. An axis of two nodes has no second difference: it is blamed for a sample no other
axis explains. ``axes`` limits the refinement to some axes.

Only the new points are solved (on a Dask cluster, by :func:`~.build.build_table` with the
batches' points not in the store yet; each run along the fastest axis warm-started from
the point before it, as a build); the old nodes' values, statuses and messages are copied.
The refined table is written beside the store and then takes its place (an interrupted
refinement leaves the store as it was). With a kept check, the refined table is measured
again at the check's states against their exact values (no new exact solve), so that
``table show`` gives the error after. A refined node equals a fresh build's to the
solvers' tolerances (another warm-start path), as a warm-started node equals a cold one.
"""

from __future__ import annotations

import json
import shutil
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import RailContactError
from .check import MEASURES, measure, read_check, write_check
from .interpolate import ContactTable
from .spec import TableSpec, check_size
from .store import (
    IDENTITY,
    POLICY_ATTR,
    _zarr,
    create_store,
    read_messages,
    read_table,
    refuse_kind,
)
from .variables import COUNTS, NO_CONTACT, OK, QUANTITIES

MIN_FRACTION = 1.0 / 1024
"""An interval narrower than this fraction of its axis's range is not split."""
REFINED = "refinement"
"""The store's attribute listing the refinements (JSON: per round the nodes added)."""


@dataclass(frozen=True)
class Targets:
    """The largest errors accepted (the check's measures) and the largest contact angle
    step between neighbouring nodes [rad]."""

    normal_force: float = 1e-2
    """``|dN| / max(N, Q)``."""
    creep_force: float = 5e-2
    """``|dF| / (mu max(N, Q))``."""
    contact_angle: float = 5e-3
    """``|d gamma|`` [rad]."""
    jump_angle: float = 0.05
    """Contact angle step between neighbouring nodes [rad] above which the contact
    jumps."""

    def __post_init__(self) -> None:
        for k in ("normal_force", "creep_force", "contact_angle", "jump_angle"):
            v = getattr(self, k)
            if not (isinstance(v, (int, float)) and v > 0):
                raise RailContactError(f"target {k} must be > 0, got {v!r}")


@dataclass
class RefineReport:
    """What a refinement did."""

    rounds: list[dict[str, Any]] = field(default_factory=list)
    """Per round: ``added`` (axis -> new nodes [SI]), ``by_error`` and ``by_jump`` (axis ->
    intervals flagged), ``points`` (the table's points after), ``computed``."""
    before: dict[str, Any] | None = None
    """The check's overall errors before (:func:`~.check.overall`), None without one."""
    after: dict[str, Any] | None = None


def spec_of(path: str | Path) -> TableSpec:
    """The :class:`TableSpec` a store was built for (its identity)."""
    attrs, _ = read_table(path, [])
    refuse_kind(path, attrs, "table refine")
    ident = json.loads(attrs[IDENTITY])
    return TableSpec(case=ident["case"], axes={n: np.asarray(v, dtype=float)
                                                for n, v in ident["axes"].items()},
                     sides=tuple(ident["sides"]), batch=int(ident["batch"]),
                     out_of_range=json.loads(attrs.get(POLICY_ATTR, "{}")))


def jumps(axes: dict[str, np.ndarray], status: np.ndarray, n_patches: np.ndarray,
          angle: np.ndarray, jump_angle: float) -> dict[str, np.ndarray]:
    """Axis -> bool per interval: the contact jumps across it somewhere (module
    docstring). Arrays ``(*axes, side)``."""
    out = {}
    for a, name in enumerate(axes):
        if len(axes[name]) < 2:
            continue
        lo = [slice(None)] * status.ndim
        hi = [slice(None)] * status.ndim
        lo[a], hi[a] = slice(None, -1), slice(1, None)
        lo, hi = tuple(lo), tuple(hi)
        ok = (status[lo] == OK) & (status[hi] == OK)
        with np.errstate(invalid="ignore"):
            jump = ok & ((n_patches[lo] != n_patches[hi])
                         | (np.abs(angle[hi] - angle[lo]) > jump_angle))
        appear = ((status[lo] == OK) & (status[hi] == NO_CONTACT)) | (
            (status[lo] == NO_CONTACT) & (status[hi] == OK))
        flag = jump | appear
        others = tuple(k for k in range(status.ndim) if k != a)
        out[name] = flag.any(axis=others)
    return out


def _predicted(nodes: np.ndarray, f: np.ndarray, i: int) -> np.ndarray:
    """The linear interpolation error on the interval ``i`` of ``nodes`` predicted by the
    second divided differences of ``f`` (nodes along the first dimension) at its ends:
    ``max |f''| h^2 / 8`` (NaN where no neighbour node: two nodes, or NaN values)."""
    h = np.diff(nodes)
    d2 = []
    for k in (i, i + 1):
        if 1 <= k <= len(nodes) - 2:
            d2.append(2.0 * ((f[k + 1] - f[k]) / h[k] - (f[k] - f[k - 1]) / h[k - 1])
                      / (h[k - 1] + h[k]))
    if not d2:
        return np.full(f.shape[1:], np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return np.nanmax(np.abs(np.stack(d2)), axis=0) * h[i] ** 2 / 8.0


def blame(table: ContactTable, chk: Any, targets: Targets) -> dict[str, set[int]]:
    """Axis -> the intervals whose check samples exceed a target with an error that axis
    explains (module docstring)."""
    names = list(table.axes)
    q = [table.names.index(n) for n in ("normal_force", "creep_force_x", "creep_force_y",
                                         "contact_angle")]
    values = table._values[..., q]  # (*axes, side, 4)
    out: dict[str, set[int]] = {n: set() for n in names}
    for s, j in ((s, j) for s in range(chk.size) for j in range(len(chk.sides))):
        over = [m for m in MEASURES if chk.errors[m][s, j] > getattr(targets, m)]
        if not over:
            continue
        x = chk.states[s]
        cell = [min(max(int(np.searchsorted(v, xv, side="right")) - 1, 0), max(len(v) - 2, 0))
                for v, xv in zip(table.axes.values(), x, strict=True)]
        scale = np.nanmax([abs(chk.exact[s, j, 0]), chk.load[s]])
        est: dict[str, float] = {}
        for a, name in enumerate(names):
            nodes = table.axes[name]
            if len(nodes) < 2:
                continue
            # the cell's edges along a: the other axes at the cell's two corners each
            sl = tuple(slice(None) if b == a else slice(cell[b], cell[b] + 2)
                       for b in range(len(names)))
            f = np.moveaxis(values[(*sl, j)], a, 0)  # (nodes along a, corners..., 4)
            e = _predicted(nodes, f, cell[a])  # (corners..., 4)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                e = e.reshape(-1, 4)
                per = {"normal_force": np.nanmax(e[:, 0]) / scale,
                       "creep_force": np.nanmax(np.hypot(e[:, 1], e[:, 2]))
                       / (chk.state_friction()[s] * scale),
                       "contact_angle": np.nanmax(e[:, 3])}
            est[name] = max((per[m] / getattr(targets, m) for m in over
                             if np.isfinite(per[m])), default=np.nan)
        known = [n for n, v in est.items() if np.isfinite(v)]
        hit = [n for n in known if est[n] > 0.5]
        if not hit:  # nothing the nodes explain: the axes without a second difference
            hit = [n for n in est if not np.isfinite(est[n])] or list(est)
        for n in hit:
            out[n].add(cell[names.index(n)])
    return out


def flagged(axes: dict[str, np.ndarray], blamed: dict[str, set[int]] | None,
            jump: dict[str, np.ndarray], only: tuple[str, ...] | None
            ) -> tuple[dict[str, list[int]], dict[str, list[int]]]:
    """The intervals to split per axis, by the check's error (``blamed``,
    :func:`blame`) and by a contact jump (indices of their lower nodes), of the axes
    ``only`` (None: all), each wider than :data:`MIN_FRACTION` of its axis."""
    by_error: dict[str, list[int]] = {}
    by_jump: dict[str, list[int]] = {}
    for name, nodes in axes.items():
        if len(nodes) < 2 or (only is not None and name not in only):
            continue
        wide = np.diff(nodes) > MIN_FRACTION * (nodes[-1] - nodes[0])
        if blamed:
            by_error[name] = sorted(i for i in blamed.get(name, ()) if wide[i])
        j = jump.get(name)
        if j is not None:
            by_jump[name] = [i for i in np.flatnonzero(j).tolist() if wide[i]]
    return by_error, by_jump


def _with_nodes(spec: TableSpec, added: dict[str, np.ndarray]) -> TableSpec:
    axes = {n: np.union1d(v, added.get(n, [])) for n, v in spec.axes.items()}
    for n, v in axes.items():
        if np.any(np.diff(v) <= 0):  # pragma: no cover - union1d sorts and dedups
            raise RailContactError(f"refined axis {n} is not strictly increasing")
    check_size({n: len(v) for n, v in axes.items()}, len(spec.sides))
    fast_old, fast_new = len(spec.axes[spec.names[-1]]), len(axes[spec.names[-1]])
    batch = fast_new if spec.batch == fast_old else spec.batch
    return TableSpec(case=spec.case, axes=axes, sides=spec.sides, batch=batch,
                     out_of_range=spec.out_of_range)


def _copy_into(old: str | Path, tmp: Path, spec: TableSpec, new: TableSpec
               ) -> dict[tuple[int, ...], list[int]]:
    """Copy the old table's points into the new store ``tmp`` (created for ``new``), mark
    the batches all of whose points are old done; returns the other batches that hold old
    points -> the fast indices of their new points."""
    names = [q.name for q in QUANTITIES + COUNTS] + ["status"]
    _, arrays = read_table(old, names)
    where = [np.searchsorted(new.axes[n], spec.axes[n]) for n in spec.names]
    is_old = [np.isin(new.axes[n], spec.axes[n]) for n in spec.names]
    zarr = _zarr()
    g = zarr.open_group(str(tmp), mode="r+")
    at = np.ix_(*where, np.arange(len(spec.sides)))
    for name in names:
        arr = g[name]
        full = np.full(arr.shape, arr.fill_value, dtype=arr.dtype)
        full[at] = np.asarray(arrays[name])
        arr[...] = full
    done = np.zeros(new.batch_shape, dtype=bool)
    subset: dict[tuple[int, ...], list[int]] = {}
    for ix in np.ndindex(*new.batch_shape):
        if not all(is_old[a][i] for a, i in enumerate(ix[:-1])):
            continue  # a new node on a slow axis: all its points are new
        fast = [p[-1] for p in new.batch_points(ix)]
        fresh = [k for k in fast if not is_old[-1][k]]
        if not fresh:
            done[ix] = True
        else:
            subset[ix] = fresh
    g["batch_done"][...] = done
    return subset


def _moved_messages(messages: list[dict[str, Any]], new: TableSpec) -> list[dict[str, Any]]:
    """The old points' messages with their batches in the new grid."""
    out = []
    for m in messages:
        idx = [int(np.searchsorted(new.axes[n], m["point"][n])) for n in new.names]
        out.append({**m, "batch": [*idx[:-1], idx[-1] // new.batch]})
    return out


def refine_table(path: str | Path, targets: Targets | None = None, *,
                 axes: tuple[str, ...] | None = None, rounds: int = 1, client: Any = None,
                 scheduler: str | None = None, workers: int | None = None,
                 progress: bool = True, say=None, lost_timeout: float | None = None
                 ) -> RefineReport:
    """Refine the table at ``path`` (module docstring), ``rounds`` times or until nothing
    exceeds the targets; rewrites the store.

    Parameters
    ----------
    path
        The store (built, complete).
    targets
        The largest errors and contact angle step accepted (default :class:`Targets`).
    axes
        The axes to refine (default: all of more than one node).
    rounds
        At most this many refinements, each measured again before the next.
    client, scheduler, workers, lost_timeout
        The Dask cluster solving the new points and how long it may have no worker [s]
        (as :func:`~.build.build_table`).

    Raises
    ------
    RailContactError
        For an incomplete table, an unknown axis, bad targets, a table growing beyond
        :data:`~.spec.MAX_POINTS`.
    """
    from .build import build_table, close_client, connect

    say = say or (lambda msg: print(msg, file=sys.stderr))
    targets = targets or Targets()
    path = Path(path)
    spec = spec_of(path)
    if axes is not None:
        unknown = [a for a in axes if a not in spec.axes]
        if unknown:
            raise RailContactError(f"--axes: {', '.join(unknown)} not an axis of the table "
                                   f"({', '.join(spec.axes)})")
        axes = tuple(axes)
    if not isinstance(rounds, int) or rounds < 1:
        raise RailContactError(f"--rounds must be at least 1, got {rounds!r}")
    attrs, _ = read_table(path, [])
    if not attrs.get("complete"):
        raise RailContactError(f"{path}: the table is not complete: build it first "
                               "(railcontact table build --resume)")
    report = RefineReport()
    chk = read_check(path)
    if chk is not None:
        from .check import overall

        report.before = overall(chk)
    own = client is None
    try:
        for r in range(rounds):
            spec = spec_of(path)
            _, arrays = read_table(path, ["status", "n_patches", "contact_angle"])
            jump = jumps(spec.axes, np.asarray(arrays["status"]),
                         np.asarray(arrays["n_patches"]), np.asarray(arrays["contact_angle"]),
                         targets.jump_angle)
            if chk is not None:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")  # holes: counted by the check
                    blamed = blame(ContactTable.open(path), chk, targets)
            else:
                blamed = None
            by_error, by_jump = flagged(spec.axes, blamed, jump, axes)
            split = {n: sorted(set(by_error.get(n, [])) | set(by_jump.get(n, [])))
                     for n in spec.axes}
            added = {n: 0.5 * (spec.axes[n][ix] + spec.axes[n][np.asarray(ix) + 1])
                     for n, ix in split.items() if ix}
            if not added:
                break
            new = _with_nodes(spec, added)
            if progress:
                say(f"table {path}: round {r + 1}: "
                    + "; ".join(f"{n} +{len(v)} node(s)" for n, v in added.items())
                    + f" -> {new.size} points")
            if client is None:
                client = connect(scheduler, workers)
            tmp = path.with_name(path.name + ".refining")
            if tmp.exists():
                shutil.rmtree(tmp)
            create_store(tmp, new)
            subset = _copy_into(path, tmp, spec, new)
            rep = build_table(new, tmp, client=client, progress=progress, say=say,
                              subset=subset, **({} if lost_timeout is None else
                                                {"lost_timeout": lost_timeout}))
            if rep.failed_batches:
                raise RailContactError(f"refining {path}: {len(rep.failed_batches)} batch(es) "
                                       f"failed ({rep.failed_batches[0]}); the table is "
                                       "unchanged")
            g = _zarr().open_group(str(tmp), mode="r+")
            kept = _moved_messages(read_messages(path), new)
            msgs = sorted(kept + read_messages(tmp),
                          key=lambda m: (tuple(m["batch"]), m["side"]))
            history = json.loads(attrs.get(REFINED, "[]"))
            history.append({"added": {n: v.tolist() for n, v in added.items()},
                            "by_error": {n: len(v) for n, v in by_error.items() if v},
                            "by_jump": {n: len(v) for n, v in by_jump.items() if v}})
            g.attrs.update({"messages": json.dumps(msgs), REFINED: json.dumps(history)})
            if chk is not None:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")  # holes: counted by the check
                    measure(ContactTable.open(tmp), chk)
                write_check(tmp, chk, new.axes)
            old = path.with_name(path.name + ".old")
            if old.exists():
                shutil.rmtree(old)
            path.rename(old)
            tmp.rename(path)
            shutil.rmtree(old)
            attrs, _ = read_table(path, [])
            report.rounds.append({"added": {n: v.tolist() for n, v in added.items()},
                                  "by_error": {n: v for n, v in by_error.items() if v},
                                  "by_jump": {n: v for n, v in by_jump.items() if v},
                                  "points": new.size, "computed": rep.computed})
    finally:
        if own and client is not None:
            close_client(client)
    if chk is not None:
        from .check import overall

        report.after = overall(chk)
    return report


def parse_targets(items: list[str] | None, jump_angle: float | None = None) -> Targets:
    """:class:`Targets` from ``MEASURE=VALUE`` strings (``--target``)."""
    kw: dict[str, float] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or key not in MEASURES:
            raise RailContactError(f"--target takes MEASURE=VALUE with MEASURE one of "
                                   f"{', '.join(MEASURES)}, got {item!r}")
        try:
            kw[key] = float(value)
        except ValueError:
            raise RailContactError(f"--target {key}: not a number: {value!r}") from None
    if jump_angle is not None:
        kw["jump_angle"] = jump_angle
    return Targets(**kw)


__all__ = ["MIN_FRACTION", "REFINED", "RefineReport", "Targets", "blame", "flagged", "jumps",
           "parse_targets", "refine_table", "spec_of"]

