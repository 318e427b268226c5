"""Building a table on Dask: the batches not yet in the store, solved by the workers of a
cluster, written by the client as they arrive.

The cluster is a ``dask.distributed.LocalCluster`` of N worker processes (one thread each)
by default, or any running Dask scheduler (``--scheduler tcp://host:8786``: SSH, Kubernetes,
HPC job queues...). Workers need railcontact installed (and the profile files at the same
paths when the spec names files); they only compute. The client writes each finished batch
into the store, then marks it done, so the store needs to be reachable by the client only,
and a worker lost mid-run loses its batch alone (Dask gives it to another worker). A rerun
into the same store, or ``--resume``, computes only the batches not marked done.

The client keeps the finished batches and writes them together every
:data:`WRITE_SECONDS` (and at the end, also of a run interrupted with Ctrl-C or stopped by
an error), each chunk of the store once per write (:meth:`.store.Store.write_batches`): a
client killed outright loses at most the batches of that interval. It creates the store
itself (metadata only: no chunk is written through the cluster), and prints a line and the
progress bar before it waits for the cluster. A cluster without any worker for
``lost_timeout`` seconds (all workers lost, or none ever came) is an error that says to
resume; the finished batches are kept.
"""

from __future__ import annotations

import importlib.util
import logging
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import RailContactError
from .solve import solve_batch
from .spec import DEFAULT_KIND, TableSpec
from .store import Store, create_store
from .variables import NOT_COMPUTED, STATUS_MEANINGS

CONNECT_TIMEOUT = "5s"
"""How long to wait for a scheduler given by address."""
WRITE_SECONDS = 5.0
"""The client writes the batches finished since its last write at most this often [s]."""
LOST_TIMEOUT = 120.0
"""How long a build waits for a cluster without workers before it stops with an error [s]
(``--lost-timeout``)."""
POLL_SECONDS = 1.0
"""How often the client looks at the cluster and refreshes the progress bar [s]."""
SLEEP_SECONDS = 0.05
"""The client's pause when no batch has finished [s]."""


@dataclass
class BuildReport:
    """What a build did (SI units: seconds)."""

    points: int
    """Grid points of the table."""
    computed: int = 0
    """Points computed by this run (each for every wheel)."""
    skipped: int = 0
    """Points already in the store."""
    failed_batches: list[str] = field(default_factory=list)
    """Batches whose task failed (not written: a rerun computes them)."""
    not_ok: int = 0
    """Point-wheels of the table whose status is not ok, when the run ends (also those of
    earlier runs; no contact counts: :attr:`statuses`)."""
    statuses: dict[str, int] = field(default_factory=dict)
    """Point-wheels of the table of each status but ok, by its meaning, when the run ends."""
    recovered: int = 0
    """Point-wheels of this run that failed from their first start and were solved from a
    later one (:data:`~.solve.STARTS`)."""
    seconds: float = 0.0
    task_seconds: float = 0.0
    """Wall time of the batches in their workers, summed [s]."""
    task_cpu_seconds: float = 0.0
    """CPU time of the batches in their workers, summed [s]: below ``task_seconds`` when
    the worker processes waited for a core (a loaded machine)."""
    workers: int = 0
    """The workers that computed this run's batches."""
    dashboard: str | None = None
    check: Any = None
    """The interpolation check made after the build (:class:`~.check.Check`), or None."""

    @property
    def rate(self) -> float:
        """Points per second of this run."""
        return self.computed / self.seconds if self.seconds > 0 else 0.0


def connect(scheduler: str | None, workers: int | None):
    """A ``dask.distributed.Client``: to the scheduler at ``scheduler``, else to a new
    LocalCluster of ``workers`` processes (default: the machine's CPUs)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:  # pragma: no cover - the [tables] extra
        raise RailContactError(f"tables need the [tables] extra (pip install "
                               f"'railcontact[tables]'): {exc}") from None
    if scheduler:
        try:
            return Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError) as exc:
            raise RailContactError(f"cannot reach the Dask scheduler at {scheduler} (waited "
                                   f"{CONNECT_TIMEOUT}): {exc}") from None
    n = workers or os.cpu_count() or 1
    if n < 1:
        raise RailContactError(f"--workers must be at least 1, got {n}")
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                           dashboard_address=":0", silence_logs=logging.CRITICAL)
    return Client(cluster)


def _solve_on_worker(case: dict[str, Any], sides: tuple[str, ...],
                     points: list[dict[str, float]], solver=solve_batch) -> dict[str, Any]:
    """``solver`` (:func:`~.solve.solve_batch`, or another kind of table's,
    ``spec.solver``), with the address of the worker that ran it."""
    out = solver(case, sides, points)
    try:
        from distributed import get_worker

        out["worker"] = get_worker().address
    except (ImportError, ValueError):  # pragma: no cover - not on a worker
        out["worker"] = ""
    return out


def build_table(spec: TableSpec, out: str | Path, *, scheduler: str | None = None,
                workers: int | None = None, resume: bool = False, progress: bool = True,
                client: Any = None, say=None, lost_timeout: float = LOST_TIMEOUT,
                check: int = 0, check_seed: int = 0, check_method: str = "linear",
                subset: dict[tuple[int, ...], list[int]] | None = None) -> BuildReport:
    """Compute the points of ``spec`` missing from the store ``out`` (created if absent).

    Parameters
    ----------
    spec
        The table.
    out
        The Zarr store. An existing store must hold the same table (else an error).
    scheduler, workers
        The Dask scheduler's address, or the number of local worker processes (not both:
        an error).
    resume
        The store must exist (a rerun without it also computes only what is missing).
    progress
        A line at the start and a progress bar on stderr (points, rate, ETA, workers).
    client
        An existing ``distributed.Client`` to use instead (not closed).
    say
        Called with one-line messages (the dashboard address); default: print to stderr.
    lost_timeout
        Seconds the cluster may have no worker before the build stops with an error [s].
    check, check_seed, check_method
        When ``check`` > 0 and the table is complete: solve ``check`` random off-node
        states exactly on the cluster and keep the interpolation error in the store
        (:func:`~.check.check_table`; seeded by ``check_seed``, of ``check_method``).
    subset
        Batch index -> the indices along the fastest axis of the points to compute in that
        batch (the others are in the store already: a refined table,
        :mod:`.refine`); a batch not named computes all its points.

    Returns
    -------
    BuildReport

    Raises
    ------
    RailContactError
        For bad options, an unreachable scheduler, a store of another table, a cluster
        without workers for ``lost_timeout`` or a lost scheduler (the finished batches are
        in the store: resume).
    """
    say = say or (lambda msg: print(msg, file=sys.stderr))
    if workers is not None and workers < 1:
        raise RailContactError(f"--workers must be at least 1, got {workers}")
    if scheduler and workers is not None:
        raise RailContactError(
            f"--workers {workers} sizes a new local cluster; the cluster at --scheduler "
            f"{scheduler} has its own workers: give one or the other")
    if not lost_timeout > 0:
        raise RailContactError(f"--lost-timeout must be > 0 s, got {lost_timeout}")
    if check < 0:
        raise RailContactError(f"--check must be a number of states >= 0, got {check}")
    if check > 0 and getattr(spec, "kind", DEFAULT_KIND) != DEFAULT_KIND:
        raise RailContactError(f"--check measures a {DEFAULT_KIND} table's interpolation "
                               f"error; this is a {spec.kind} table")
    if check > 0:  # (its method's needs, before any solve)
        from .interpolate import check_method_fits

        check_method_fits(spec.axes, check_method)
    out = Path(out)
    store = None
    if out.exists():
        store = Store(out, spec)
        done = store.done()
    elif resume:
        raise RailContactError(f"--resume: no table at {out} to resume")
    else:
        done = np.zeros(spec.batch_shape, dtype=bool)
    todo = [tuple(int(i) for i in ix) for ix in np.argwhere(~done)]
    report = BuildReport(points=spec.size)
    subset = subset or {}
    report.skipped = spec.size - sum(len(_points(spec, ix, subset)) for ix in todo)
    own = client is None
    if not todo:
        store.finish(True)
        _statuses(report, store)
        if check > 0:
            c = connect(scheduler, workers) if own else client
            try:
                report.check = _check(out, check, check_seed, check_method, c, say, progress,
                                      lost_timeout)
            finally:
                if own:
                    close_client(c)
        return report
    if progress:
        where = (f"the Dask scheduler at {scheduler}" if scheduler else
                 "a local Dask cluster of "
                 f"{workers or os.cpu_count() or 1} worker process(es)") if own else \
            "the given Dask client"
        say(f"table {out}: {spec.size} points x {len(spec.sides)} wheel(s) in "
            f"{len(todo) + int(done.sum())} batches, {report.skipped} points already there; "
            f"{len(todo)} batches to compute on {where}")
    total = spec.size - report.skipped
    bar = _bar(total, progress)
    t0 = time.perf_counter()
    finished = False
    try:
        if own:
            bar.set_postfix_str("starting the cluster" if not scheduler else "connecting",
                                refresh=True)
            client = connect(scheduler, workers)  # before the store: an error leaves nothing
            t0 = time.perf_counter()  # the rate: of the solves, not of the cluster's start
        try:
            if store is None:
                create_store(out, spec)
                store = Store(out, spec)
            _run(spec, out, store, client, todo, report, bar, say, progress, own,
                 lost_timeout, subset)
            report.seconds = time.perf_counter() - t0
            complete = bool(store.done().all())
            store.finish(complete)
            _statuses(report, store)
            finished = True
            if check > 0 and complete and not report.failed_batches:
                bar.close()
                report.check = _check(out, check, check_seed, check_method, client, say,
                                      progress, lost_timeout)
        finally:
            if store is not None and not finished:
                store.finish(bool(store.done().all()))
                _statuses(report, store)
            if own:
                close_client(client)
    finally:
        bar.close()
    report.seconds = report.seconds or time.perf_counter() - t0
    return report


def _points(spec: TableSpec, ix: tuple[int, ...], subset: dict[tuple[int, ...], list[int]]
            ) -> list[tuple[int, ...]]:
    """The grid indices of the points of batch ``ix`` to compute (all, or ``subset``'s)."""
    pts = spec.batch_points(ix)
    if ix not in subset:
        return pts
    keep = set(subset[ix])
    return [p for p in pts if p[-1] in keep]


def close_client(client: Any) -> None:
    """Close a client this build started, and its local cluster."""
    cluster = getattr(client, "cluster", None)
    client.close()
    if cluster is not None:
        cluster.close()


def _check(out: Path, n: int, seed: int, method: str, client: Any, say, progress: bool,
           lost_timeout: float):
    """:func:`~.check.check_table` of the finished table on ``client``."""
    from .check import check_table

    if progress:
        say(f"table {out}: checking the interpolation at {n} random states (seed {seed}) "
            "against the exact solver")
    return check_table(out, n, seed, method, client, lost_timeout)


def _statuses(report: BuildReport, store: Store) -> None:
    """The table's statuses but ok into ``report`` (no contact counted too)."""
    status = np.asarray(store.arrays["status"][...])
    counts = {STATUS_MEANINGS[int(k)]: int(c)
              for k, c in zip(*np.unique(status, return_counts=True), strict=True)
              if int(k) not in (0, NOT_COMPUTED)}
    report.statuses = counts
    report.not_ok = sum(counts.values())


def _run(spec: TableSpec, out: Path, store: Store, client: Any, todo: list, report: BuildReport,
         bar, say, progress: bool, own: bool, lost_timeout: float,
         subset: dict[tuple[int, ...], list[int]] | None = None) -> None:
    """Submit the batches ``todo``, write them as they finish (every
    :data:`WRITE_SECONDS`, and whatever finished when stopped), watch the cluster."""
    from distributed import as_completed

    dashboard = getattr(client, "dashboard_link", None)
    report.dashboard = dashboard
    if dashboard and progress:
        note = ""
        if own and importlib.util.find_spec("bokeh") is None:  # the scheduler is ours
            note = " (its status page needs bokeh >= 3.1: pip install bokeh)"
        say(f"Dask dashboard: {dashboard}{note}")
    pending = {}
    subset = subset or {}
    for ix in todo:
        pts = _points(spec, ix, subset)
        values = [{n: float(spec.axes[n][k]) for n, k in zip(spec.names, p, strict=True)}
                  for p in pts]
        fut = client.submit(_solve_on_worker, spec.case, spec.sides, values,
                            getattr(spec, "solver", solve_batch), pure=False,
                            key=f"railcontact-batch-{'-'.join(map(str, ix))}-"
                                f"{time.time_ns()}")
        pending[fut] = ix
    finished: list = []
    seen: set[str] = set()
    last_write = last_look = time.perf_counter()
    alone_since: float | None = None
    arriving = as_completed(list(pending))  # (a wait with a timeout leaves its watchers)
    try:
        while pending:
            done = arriving.next_batch(block=False) if arriving.has_ready() else []
            if not done:
                time.sleep(SLEEP_SECONDS)
            for fut in done:
                ix = pending.pop(fut)
                try:
                    result = fut.result()
                except Exception as exc:  # noqa: BLE001 - a worker's failure, reported
                    report.failed_batches.append(f"batch {ix}: {type(exc).__name__}: {exc}")
                    continue
                if ix in subset:  # where its points go along the fastest axis
                    result["fast"] = [p[-1] for p in _points(spec, ix, subset)]
                finished.append((ix, result, _messages(spec, ix, result)))
                seen.add(result.get("worker", ""))
                report.recovered += len(result.get("recovered", ()))
                report.task_seconds += result["seconds"]
                report.task_cpu_seconds += result["cpu_seconds"]
                n = len(_points(spec, ix, subset))
                report.computed += n
                bar.update(n)
            if finished and (not pending or time.perf_counter() - last_write >= WRITE_SECONDS):
                store.write_batches(finished)
                finished, last_write = [], time.perf_counter()
            if not pending:
                break
            if time.perf_counter() - last_look < POLL_SECONDS:
                continue
            last_look = time.perf_counter()
            try:
                n_workers = len(client.scheduler_info(n_workers=-1).get("workers", {}))
            except Exception as exc:  # noqa: BLE001 - the scheduler is gone
                raise RailContactError(
                    f"lost the Dask scheduler ({type(exc).__name__}: {exc}); the finished "
                    f"batches are in {out}: rerun with --resume to complete it") from None
            if client.status not in ("running", "connecting"):
                raise RailContactError(
                    f"lost the Dask scheduler (client {client.status}); the finished "
                    f"batches are in {out}: rerun with --resume to complete it")
            bar.set_postfix_str(f"{n_workers} worker(s)", refresh=True)
            if n_workers:
                alone_since = None
            elif alone_since is None:
                alone_since = time.perf_counter()
            elif time.perf_counter() - alone_since > lost_timeout:
                raise RailContactError(
                    f"the Dask cluster has had no worker for {lost_timeout:g} s (all workers "
                    f"lost, or none started); the finished batches are in {out}: rerun "
                    "with --resume to complete it when workers are back")
    finally:
        if finished:  # whatever finished, also when interrupted or stopped
            store.write_batches(finished)
        report.workers = len(seen - {""}) or len(seen)
        for fut in pending:
            fut.cancel()


def _messages(spec: TableSpec, ix: tuple[int, ...], result: dict[str, Any]
              ) -> list[dict[str, Any]]:
    """The store's messages of a batch's points that are not ok."""
    slow = {n_: float(spec.axes[n_][k]) for n_, k in zip(spec.names[:-1], ix[:-1], strict=True)}
    fast = spec.axes[spec.names[-1]]
    at = result.get("fast") or range(ix[-1] * spec.batch, ix[-1] * spec.batch + spec.batch)
    at = list(at)
    return [{"batch": list(ix), "side": side, "status": status,
             "point": {**slow, spec.names[-1]: float(fast[at[i]])},
             "message": msg}
            for i, side, status, msg in result["messages"]]


def _bar(total: int, show: bool):
    """A tqdm progress bar (points, rate, ETA) on stderr, or a silent stand-in."""
    from tqdm import tqdm

    return tqdm(total=total, unit="pt", desc="table", disable=not show, file=sys.stderr,
                smoothing=0.1, dynamic_ncols=True)
