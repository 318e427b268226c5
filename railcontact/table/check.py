"""The interpolation error of a table, measured against the exact solver between the nodes.

:func:`sample_states` draws N states uniformly over the table's axes (seeded: the same
seed, the same states), off the nodes. Each state is solved exactly for every wheel, as
``railcontact solve`` would (a cold start, then the exact step's estimates:
:func:`~.solve.solve_recovering` without a previous point), and the table is interpolated
there as a table step reads it (:func:`table_values`). Per state and wheel
(:data:`MEASURES`):

``normal_force``
    ``|N_table - N| / max(N, Q)``: relative to the exact normal force, floored at the
    state's wheel load Q (the load axis, else the case's ``[normal] load``).
``creep_force``
    ``|F_table - F| / (mu max(N, Q))``: the creep force error vector (longitudinal and
    lateral, contact frame) over the saturation force, with the same floor (F/muN); mu is
    the state's own on a friction axis.
``contact_angle``
    ``|gamma_table - gamma|`` [rad] of the main patch; undefined (NaN) when either has no
    contact.

A wheel the exact solver cannot solve at a state (not converged, out of range) is left out
(counted, ``unsolved``); an exact answer of no contact counts with zero forces. Where the
table has no value (a failed node around the state, :data:`~.variables.FAILED`; or no
contact at some node around it) it gives what a table step gives: zero forces, so the
error is the whole force; such samples are counted as ``holes`` (failed nodes) too.

The errors are summarised per interval of each axis with more than one node
(:func:`regions`: the samples whose value on that axis lies in the interval, both wheels
pooled; count, median and max of each measure, holes) and over all samples
(:func:`overall`), and kept in the store's group ``check`` with the states and the exact
values (:func:`write_check`), so that a refined table is measured again at the same states
without solving them again (:func:`measure`).
"""

from __future__ import annotations

import json
import math
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import RailContactError
from .interpolate import METHODS, ContactTable, check_method_fits
from .solve import solve_recovering
from .spec import AXES, case_with
from .store import read_table
from .variables import FAILED, NO_CONTACT, OK

GROUP = "check"
"""The store's group holding the check."""
MEASURES = ("normal_force", "creep_force", "contact_angle")
"""The error measures (module docstring)."""
MEASURE_UNITS = {"normal_force": "1", "creep_force": "1", "contact_angle": "rad"}
MEASURE_TEXT = {"normal_force": "|dN| / max(N, Q)",
                "creep_force": "|dF| / (mu max(N, Q))",
                "contact_angle": "|d gamma| [mrad]"}
EXACT = ("normal_force", "creep_force_x", "creep_force_y", "contact_angle", "n_patches")
"""The exact values kept per state and wheel."""
CHUNK = 4
"""States per Dask task."""
LOST_TIMEOUT = 120.0
"""How long a check waits for a cluster without workers before it stops with an error
[s] (as :data:`~.build.LOST_TIMEOUT`)."""


@dataclass
class Check:
    """A check of a table: the states, the exact solves there and the errors (SI units).

    Attributes
    ----------
    names
        The axes, in the table's order.
    sides
        The wheels.
    states
        (n, axes) the states [SI].
    exact
        (n, sides, :data:`EXACT`) the exact solver's values (NaN where it has none).
    exact_status
        (n, sides) the exact solver's status.
    load
        (n,) the wheel load Q of each state [N] (the floor of the relative errors).
    friction
        The case's friction coefficient (NaN without ``[tangential]``); on a table with
        a friction axis each state has its own (:meth:`state_friction`).
    seed, method
        The random seed of the states; the interpolation measured (``linear``/``cubic``).
    errors
        Measure -> (n, sides) errors (NaN where undefined or left out).
    table_status
        (n, sides) the status of the interpolated value.
    seconds
        Wall time of the exact solves [s].
    """

    names: tuple[str, ...]
    sides: tuple[str, ...]
    states: np.ndarray
    exact: np.ndarray
    exact_status: np.ndarray
    load: np.ndarray
    friction: float
    seed: int
    method: str = "linear"
    errors: dict[str, np.ndarray] = field(default_factory=dict)
    table_status: np.ndarray | None = None
    seconds: float = 0.0

    @property
    def size(self) -> int:
        return int(self.states.shape[0])

    def state_friction(self) -> np.ndarray:
        """(n,) the coefficient of friction of each state: its friction axis value, else
        :attr:`friction` (the scale of the creep force error)."""
        if "friction" in self.names:
            return np.asarray(self.states[:, self.names.index("friction")], dtype=float)
        return np.full(self.size, float(self.friction))

    def point(self, i: int) -> dict[str, float]:
        """The state ``i`` as axis name -> value [SI]."""
        return {n: float(v) for n, v in zip(self.names, self.states[i], strict=True)}


def sample_states(axes: dict[str, np.ndarray], n: int, seed: int = 0) -> np.ndarray:
    """``n`` states drawn uniformly over the axes' ranges (numpy's default generator,
    seeded), each value off the nodes on every axis with more than one node; an axis of
    one node keeps it. Returns (n, axes) [SI]."""
    if not isinstance(n, (int, np.integer)) or isinstance(n, bool) or n < 1:
        raise RailContactError(f"a check needs at least 1 state, got {n!r}")
    rng = np.random.default_rng(seed)
    cols = []
    for nodes in axes.values():
        nodes = np.asarray(nodes, dtype=float)
        if len(nodes) == 1:
            cols.append(np.full(n, nodes[0]))
            continue
        x = rng.uniform(nodes[0], nodes[-1], n)
        on = np.isin(x, nodes)
        while on.any():  # (a value on a node: a draw of probability zero, drawn again)
            x[on] = rng.uniform(nodes[0], nodes[-1], int(on.sum()))
            on = np.isin(x, nodes)
        cols.append(x)
    return np.column_stack(cols) if cols else np.zeros((n, 0))


def solve_states(case: dict[str, Any], sides: tuple[str, ...],
                 states: list[dict[str, float]]) -> dict[str, np.ndarray]:
    """The exact solver at each state (axis name -> value) for each wheel, each from its
    own cold start (:func:`~.solve.solve_recovering` without a previous point). Returns
    ``values`` (states, sides, :data:`EXACT`; NaN where undefined) and ``status``."""
    values = np.full((len(states), len(sides), len(EXACT)), np.nan)
    status = np.zeros((len(states), len(sides)), dtype=np.int8)
    for i, point in enumerate(states):
        for j, side in enumerate(sides):
            wheel, _, _ = solve_recovering(case_with(case, point), side)
            status[i, j] = wheel.status
            if wheel.status == NO_CONTACT:
                values[i, j, :3] = 0.0
                values[i, j, 4] = 0
            elif wheel.patches:
                values[i, j] = (wheel.normal_force, wheel.creep_force[0],
                                wheel.creep_force[1], wheel.contact_angle, wheel.n_patches)
    return {"values": values, "status": status}


def _solve_all(case: dict[str, Any], sides: tuple[str, ...], states: list[dict[str, float]],
               client: Any = None, lost_timeout: float = LOST_TIMEOUT
               ) -> dict[str, np.ndarray]:
    """:func:`solve_states` in-process, or on a Dask ``client`` in tasks of
    :data:`CHUNK` states; a cluster without workers for ``lost_timeout`` seconds is an
    error (as a build's)."""
    if client is None:
        return solve_states(case, sides, states)
    from distributed import as_completed

    parts = [states[k:k + CHUNK] for k in range(0, len(states), CHUNK)]
    futures = {client.submit(solve_states, case, sides, p, pure=False,
                             key=f"railcontact-check-{k}-{time.time_ns()}"): k
               for k, p in enumerate(parts)}
    results: dict[int, dict[str, np.ndarray]] = {}
    arriving = as_completed(list(futures))
    alone_since: float | None = None
    last_look = time.perf_counter()
    try:
        while len(results) < len(parts):
            if arriving.has_ready():
                for fut in arriving.next_batch(block=False):
                    try:
                        results[futures[fut]] = fut.result()
                    except Exception as exc:  # noqa: BLE001 - a worker's failure
                        raise RailContactError(f"the check's exact solves failed on the "
                                               f"cluster: {type(exc).__name__}: {exc}"
                                               ) from None
                continue
            time.sleep(0.05)
            if time.perf_counter() - last_look < 1.0:
                continue
            last_look = time.perf_counter()
            try:
                workers = len(client.scheduler_info(n_workers=-1).get("workers", {}))
            except Exception as exc:  # noqa: BLE001 - the scheduler is gone
                raise RailContactError(f"lost the Dask scheduler during the check "
                                       f"({type(exc).__name__}: {exc})") from None
            if workers:
                alone_since = None
            elif alone_since is None:
                alone_since = time.perf_counter()
            elif time.perf_counter() - alone_since > lost_timeout:
                raise RailContactError(f"the Dask cluster has had no worker for "
                                       f"{lost_timeout:g} s during the check (all workers "
                                       "lost); the table is complete: run 'railcontact "
                                       "table check' when workers are back")
    finally:
        for fut in futures:
            fut.cancel()
    ordered = [results[k] for k in range(len(parts))]
    return {"values": np.concatenate([r["values"] for r in ordered]),
            "status": np.concatenate([r["status"] for r in ordered])}


def state_loads(case: dict[str, Any], names: tuple[str, ...], states: np.ndarray
                ) -> np.ndarray:
    """The wheel load Q [N] of each state: its load axis, else the case's load (NaN for a
    penetration-controlled case)."""
    if "load" in names:
        return np.asarray(states[:, names.index("load")], dtype=float)
    q = (case.get("normal") or {}).get("load")
    return np.full(states.shape[0], np.nan if q is None else float(q))


def table_values(table: ContactTable, point: dict[str, float], side: str,
                 method: str = "linear") -> tuple[np.ndarray, int]:
    """The table at ``point`` as a table step reads it: (normal force, F_x, F_y, contact
    angle) and the status; zero forces and a NaN angle where it has no value (no contact
    at a node around the point, or a failed node without values), as
    :class:`~.step.TableContact` gives."""
    r = table(point, side, method)
    v = np.array([r["normal_force"], r["creep_force_x"], r["creep_force_y"],
                  r["contact_angle"]])
    if r.status == OK or (r.status != NO_CONTACT and bool(np.all(np.isfinite(v[:3])))):
        return v, r.status
    return np.array([0.0, 0.0, 0.0, np.nan]), r.status


def measure(table: ContactTable, chk: Check, method: str | None = None) -> Check:
    """The errors of ``table`` at the states of ``chk`` against its exact values (module
    docstring), into ``chk.errors`` and ``chk.table_status`` (and ``chk.method`` when
    given). The table must have the check's axes (any nodes) and wheels."""
    if method is not None:
        if method not in METHODS:
            raise RailContactError(f"method must be one of {', '.join(METHODS)}, got "
                                   f"{method!r}")
        chk.method = method
    if tuple(table.axes) != chk.names:
        raise RailContactError(f"the check's axes {', '.join(chk.names)} are not the table's "
                               f"({', '.join(table.axes)})")
    n, s = chk.size, len(chk.sides)
    errs = {m: np.full((n, s), np.nan) for m in MEASURES}
    tstat = np.zeros((n, s), dtype=np.int8)
    mus = chk.state_friction()
    for i in range(n):
        point = chk.point(i)
        for j, side in enumerate(chk.sides):
            got, tstat[i, j] = table_values(table, point, side, chk.method)
            if chk.exact_status[i, j] not in (OK, NO_CONTACT):
                continue
            ex = chk.exact[i, j]
            scale = np.nanmax([abs(ex[0]), chk.load[i]])
            if not scale > 0:
                continue
            errs["normal_force"][i, j] = abs(got[0] - ex[0]) / scale
            if math.isfinite(mus[i]) and mus[i] > 0:
                errs["creep_force"][i, j] = math.hypot(got[1] - ex[1], got[2] - ex[2]) / (
                    mus[i] * scale)
            errs["contact_angle"][i, j] = abs(got[3] - ex[3])  # NaN without contact
    chk.errors, chk.table_status = errs, tstat
    return chk


def _stats(e: np.ndarray) -> dict[str, float | int]:
    e = e[np.isfinite(e)]
    if not e.size:
        return {"n": 0, "median": math.nan, "max": math.nan}
    return {"n": int(e.size), "median": float(np.median(e)), "max": float(e.max())}


def _holes(chk: Check, rows: np.ndarray) -> int:
    st = chk.table_status[rows]
    ok = np.isin(chk.exact_status[rows], (OK, NO_CONTACT))
    return int(np.count_nonzero(np.isin(st, FAILED) & ok))


def overall(chk: Check) -> dict[str, Any]:
    """Count, median and max of each measure over all samples; ``holes`` and
    ``unsolved`` (exact not solved) counts of samples (state-wheels)."""
    rows = np.arange(chk.size)
    return {"samples": int(chk.size * len(chk.sides)), "holes": _holes(chk, rows),
            "unsolved": int(np.count_nonzero(~np.isin(chk.exact_status, (OK, NO_CONTACT)))),
            **{m: _stats(chk.errors[m]) for m in MEASURES}}


def regions(chk: Check, axes: dict[str, np.ndarray]) -> list[dict[str, Any]]:
    """Per interval of each axis with more than one node: ``axis``, ``lo``, ``hi`` [SI],
    ``samples`` (state-wheels in it), ``holes`` and, per measure, its count, median and max
    (:func:`_stats`)."""
    out = []
    for a, name in enumerate(chk.names):
        nodes = np.asarray(axes[name], dtype=float)
        if len(nodes) < 2:
            continue
        k = np.clip(np.searchsorted(nodes, chk.states[:, a], side="right") - 1, 0,
                    len(nodes) - 2)
        for i in range(len(nodes) - 1):
            rows = np.flatnonzero(k == i)
            out.append({"axis": name, "lo": float(nodes[i]), "hi": float(nodes[i + 1]),
                        "samples": int(rows.size * len(chk.sides)),
                        "holes": _holes(chk, rows),
                        **{m: _stats(chk.errors[m][rows]) for m in MEASURES}})
    return out


def new_check(table: ContactTable, n: int, seed: int = 0, method: str = "linear",
              client: Any = None, lost_timeout: float = LOST_TIMEOUT) -> Check:
    """Solve ``n`` random off-node states of ``table`` exactly (:func:`sample_states`;
    in-process, or on the Dask ``client``) and measure the table there."""
    names = tuple(table.axes)
    states = sample_states(table.axes, n, seed)
    points = [{k: float(v) for k, v in zip(names, row, strict=True)} for row in states]
    t0 = time.perf_counter()
    solved = _solve_all(table.case, table.sides, points, client, lost_timeout)
    tangential = table.case.get("tangential") or {}
    chk = Check(names=names, sides=table.sides, states=states, exact=solved["values"],
                exact_status=solved["status"], load=state_loads(table.case, names, states),
                friction=float(tangential.get("friction", math.nan)), seed=int(seed),
                method=method, seconds=time.perf_counter() - t0)
    return measure(table, chk, method)


def _json(x: Any) -> Any:
    """JSON with NaN as null."""
    if isinstance(x, dict):
        return {k: _json(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_json(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def write_check(path: str | Path, chk: Check, axes: dict[str, np.ndarray]) -> None:
    """Keep ``chk`` in the store at ``path`` (group :data:`GROUP`, replacing one there):
    the states, exact values and statuses, loads, errors and table statuses as arrays; the
    seed, method, friction, :func:`overall` and :func:`regions` (JSON) as attributes."""
    from .store import _zarr

    zarr = _zarr()
    root = zarr.open_group(str(path), mode="r+")
    if GROUP in root:
        del root[GROUP]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zarr: format 2
        g = root.create_group(GROUP)
        arrays = {"states": chk.states, "exact": chk.exact, "exact_status": chk.exact_status,
                  "load": chk.load, "table_status": chk.table_status,
                  "errors": np.stack([chk.errors[m] for m in MEASURES], axis=-1)}
        for name, a in arrays.items():
            a = np.asarray(a)
            g.create_array(name, shape=a.shape, dtype=a.dtype, chunks=a.shape or None,
                           fill_value=None)[...] = a
        g.attrs.update({
            "names": list(chk.names), "sides": list(chk.sides), "exact_values": list(EXACT),
            "measures": list(MEASURES), "seed": chk.seed, "method": chk.method,
            "friction": _json(chk.friction), "seconds": chk.seconds,
            "overall": json.dumps(_json(overall(chk))),
            "regions": json.dumps(_json(regions(chk, axes)))})


def read_check(path: str | Path) -> Check | None:
    """The check kept in the store at ``path`` (None when it has none)."""
    from .store import _zarr

    zarr = _zarr()
    root = zarr.open_group(str(path), mode="r")
    if GROUP not in root:
        return None
    g = root[GROUP]
    a = g.attrs
    errs = np.asarray(g["errors"][...])
    fr = a.get("friction")
    return Check(names=tuple(a["names"]), sides=tuple(a["sides"]),
                 states=np.asarray(g["states"][...]), exact=np.asarray(g["exact"][...]),
                 exact_status=np.asarray(g["exact_status"][...]),
                 load=np.asarray(g["load"][...]), friction=math.nan if fr is None else fr,
                 seed=int(a["seed"]), method=str(a["method"]),
                 errors={m: errs[..., k] for k, m in enumerate(a["measures"])},
                 table_status=np.asarray(g["table_status"][...]),
                 seconds=float(a.get("seconds", 0.0)))


def read_summary(path: str | Path) -> tuple[dict[str, Any], list[dict[str, Any]]] | None:
    """The kept check's :func:`overall` and :func:`regions` (None without a check)."""
    from .store import _zarr

    root = _zarr().open_group(str(path), mode="r")
    if GROUP not in root:
        return None
    a = root[GROUP].attrs
    return json.loads(a["overall"]), json.loads(a["regions"])


def _fmt(s: dict[str, Any], scale: float = 1.0) -> str:
    if not s or not s.get("n"):
        return f"{'-':>9s} {'-':>9s}"
    return f"{s['median'] * scale:9.2e} {s['max'] * scale:9.2e}"


def check_text(path: str | Path) -> list[str]:
    """Lines of ``railcontact table show`` for the kept check (none without one): the
    overall errors, then a line per interval of each axis."""
    got = read_summary(path)
    if got is None:
        return []
    tot, rows = got
    from .store import _zarr

    a = _zarr().open_group(str(path), mode="r")[GROUP].attrs
    n = tot["samples"]
    head = (f"interpolation error ({a['method']}) at {n // max(len(a['sides']), 1)} random "
            f"states (seed {a['seed']}) x {len(a['sides'])} wheel(s) against the exact "
            f"solver: {tot['holes']} in holes, {tot['unsolved']} not solved exactly")
    lines = [head, f"  {'':24s} {'median':>9s} {'max':>9s}"]
    for m in MEASURES:
        scale = 1e3 if m == "contact_angle" else 1.0
        lines.append(f"  {MEASURE_TEXT[m]:24s} {_fmt(tot[m], scale)}")
    lines.append("  per interval (samples; median and max of each):")
    lines.append(f"  {'axis':22s} {'interval [unit]':>27s} {'n':>4s} {'N med':>9s} {'N max':>9s} "
                 f"{'F/muN med':>9s} {'F/muN max':>9s} {'mrad med':>9s} {'mrad max':>9s}"
                 " holes")
    for r in rows:
        unit = AXES[r["axis"]].unit
        lines.append(f"  {r['axis']:22s} {r['lo']:10.4g}..{r['hi']:<10.4g} {unit:>4s} "
                     f"{r['samples']:4d} {_fmt(r['normal_force'])} {_fmt(r['creep_force'])} "
                     f"{_fmt(r['contact_angle'], 1e3)} {r['holes']:5d}")
    return lines


def check_table(path: str | Path, n: int, seed: int = 0, method: str = "linear",
                client: Any = None, lost_timeout: float = LOST_TIMEOUT) -> Check:
    """Check the table at ``path`` at ``n`` random states (:func:`new_check`; on the Dask
    ``client`` when given, which may have no worker for ``lost_timeout`` seconds) and keep
    the check in the store (:func:`write_check`)."""
    attrs, _ = read_table(path, [])
    if not attrs.get("complete"):  # (its points not computed would read as zero forces)
        raise RailContactError(f"{path}: the table is not complete: build it first "
                               "(railcontact table build --resume)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # holes: counted by the check
        table = ContactTable.open(path)
    check_method_fits(table.axes, method)  # before any solve
    chk = new_check(table, n, seed, method, client, lost_timeout)
    write_check(path, chk, table.axes)
    return chk
