"""Building a table on Dask: the batches not yet in the store, solved by the workers of a
cluster, written by the client as they arrive.

The cluster is a ``dask.distributed.LocalCluster`` of N worker processes (one thread each)
by default, or any running Dask scheduler (``--scheduler tcp://host:8786``: SSH, Kubernetes,
HPC job queues...). Workers need railcontact installed (and the profile files at the same
paths when the spec names files); they only compute. The client writes each finished batch
into the store, then marks it done, so the store needs to be reachable by the client only,
and a worker lost mid-run loses its batch alone (Dask gives it to another worker). A rerun
into the same store, or ``--resume``, computes only the batches not marked done.
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
from .spec import TableSpec
from .store import Store, create_store

CONNECT_TIMEOUT = "5s"
"""How long to wait for a scheduler given by address."""


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
    """Point-wheels of this run whose status is not ok (recorded in the store)."""
    seconds: float = 0.0
    task_seconds: float = 0.0
    """Wall time of the batches in their workers, summed [s]."""
    task_cpu_seconds: float = 0.0
    """CPU time of the batches in their workers, summed [s]: below ``task_seconds`` when
    the worker processes waited for a core (a loaded machine)."""
    workers: int = 0
    dashboard: str | None = None

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


def build_table(spec: TableSpec, out: str | Path, *, scheduler: str | None = None,
                workers: int | None = None, resume: bool = False, progress: bool = True,
                client: Any = None, say=None) -> BuildReport:
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
        A progress bar on stderr (points, rate, ETA).
    client
        An existing ``distributed.Client`` to use instead (not closed).
    say
        Called with one-line messages (the dashboard address); default: print to stderr.

    Returns
    -------
    BuildReport
    """
    say = say or (lambda msg: print(msg, file=sys.stderr))
    if workers is not None and workers < 1:
        raise RailContactError(f"--workers must be at least 1, got {workers}")
    if scheduler and workers is not None:
        raise RailContactError(
            f"--workers {workers} sizes a new local cluster; the cluster at --scheduler "
            f"{scheduler} has its own workers: give one or the other")
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
    report.skipped = sum(len(spec.batch_points(tuple(ix))) for ix in np.argwhere(done))
    if not todo:
        store.finish(True)
        return report
    own = client is None
    if own:
        client = connect(scheduler, workers)  # before the store: an error leaves nothing
    if store is None:
        try:
            create_store(out, spec)
            store = Store(out, spec)
        except BaseException:
            if own:
                client.close()
            raise
    t0 = time.perf_counter()
    try:
        from distributed import as_completed

        report.workers = len(client.scheduler_info().get("workers", {}))
        report.dashboard = getattr(client, "dashboard_link", None)
        if report.dashboard and progress:
            note = ""
            if own and importlib.util.find_spec("bokeh") is None:  # the scheduler is ours
                note = " (its status page needs bokeh >= 3.1: pip install bokeh)"
            say(f"Dask dashboard: {report.dashboard}{note}")
        futures = {}
        for ix in todo:
            pts = spec.batch_points(ix)
            values = [{n: float(spec.axes[n][k]) for n, k in zip(spec.names, p, strict=True)}
                      for p in pts]
            fut = client.submit(solve_batch, spec.case, spec.sides, values, pure=False,
                                key=f"railcontact-batch-{'-'.join(map(str, ix))}-"
                                    f"{time.time_ns()}")
            futures[fut] = ix
        bar = _bar(sum(len(spec.batch_points(ix)) for ix in todo), progress)
        try:
            for fut in as_completed(list(futures)):
                ix = futures.pop(fut)
                n = len(spec.batch_points(ix))
                try:
                    result = fut.result()
                except Exception as exc:  # noqa: BLE001 - a worker's failure, reported
                    report.failed_batches.append(f"batch {ix}: {type(exc).__name__}: {exc}")
                    continue
                slow = {n_: float(spec.axes[n_][k]) for n_, k in zip(spec.names[:-1], ix[:-1],
                                                                     strict=True)}
                fast = spec.axes[spec.names[-1]]
                messages = [{"batch": list(ix), "side": side, "status": status,
                             "point": {**slow, spec.names[-1]: float(fast[ix[-1] * spec.batch
                                                                         + i])},
                             "message": msg}
                            for i, side, status, msg in result["messages"]]
                store.write(ix, result, messages)
                report.not_ok += len(result["messages"])
                report.task_seconds += result["seconds"]
                report.task_cpu_seconds += result["cpu_seconds"]
                report.computed += n
                bar.update(n)
        finally:
            bar.close()
    finally:
        store.finish(bool(store.done().all()))
        if own:
            cluster = getattr(client, "cluster", None)
            client.close()
            if cluster is not None:
                cluster.close()
    report.seconds = time.perf_counter() - t0
    return report


def _bar(total: int, show: bool):
    """A tqdm progress bar (points, rate, ETA) on stderr, or a silent stand-in."""
    from tqdm import tqdm

    return tqdm(total=total, unit="pt", desc="table", disable=not show, file=sys.stderr,
                smoothing=0.1, dynamic_ncols=True)
