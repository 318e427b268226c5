"""A table on disk: an xarray Dataset in a Zarr store.

Layout (``railcontact table build``)::

    dims     the axes in spec order (the last the fastest), then ``side``
    coords   each axis [SI unit] and ``side`` ("left", "right")
    data     every quantity of :mod:`.variables` (float64; NaN where not defined), the work
             counters (int32) and ``status`` (int8: -1 not computed, 0 ok, 1 not converged,
             2 no contact, 3 out of range), each with ``units`` and ``long_name``; chunked
             one batch per chunk (1 along the slow axes, ``batch`` along the fastest)
    batch_done   bool over the batch grid (the slow axes and ``batch``): set only after all
             of a batch's data are written, so that a batch cut off while being written is
             not complete and is computed again
    attrs    ``railcontact_table`` (the identity: case, axes, sides, batch, as JSON),
             ``railcontact_version``, ``case_name``, ``complete`` (all batches done),
             ``messages`` (JSON: the message of every point that is not ok)

A store whose identity differs from the spec's is an error, never overwritten.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..errors import RailContactError
from .spec import AXES, TableSpec, comparable
from .variables import COUNTS, NOT_COMPUTED, QUANTITIES, STATUS_MEANINGS

IDENTITY = "railcontact_table"


def _libs():
    try:
        import xarray as xr
        import zarr
    except ImportError as exc:  # pragma: no cover - the [tables] extra
        raise RailContactError(f"tables need the [tables] extra (pip install "
                               f"'railcontact[tables]'): {exc}") from None
    return xr, zarr


def create_store(path: str | Path, spec: TableSpec) -> None:
    """Write an empty table (metadata, every point not computed) for ``spec``."""
    xr, _ = _libs()
    import dask.array as da

    dims = (*spec.names, "side")
    shape = (*spec.shape, len(spec.sides))
    chunks = (*(1,) * (len(spec.shape) - 1), spec.batch, len(spec.sides))
    coords: dict[str, Any] = {n: (n, v, {"units": AXES[n].unit, "long_name": AXES[n].long_name})
                              for n, v in spec.axes.items()}
    coords["side"] = ("side", list(spec.sides))
    data: dict[str, Any] = {}
    for q in QUANTITIES:
        data[q.name] = (dims, da.full(shape, np.nan, chunks=chunks),
                        {"units": q.unit, "long_name": q.long_name})
    for q in COUNTS:
        data[q.name] = (dims, da.zeros(shape, dtype=np.int32, chunks=chunks),
                        {"units": q.unit, "long_name": q.long_name})
    data["status"] = (dims, da.full(shape, NOT_COMPUTED, dtype=np.int8, chunks=chunks),
                      {"long_name": "status of the point", "flag_values": list(STATUS_MEANINGS),
                       "flag_meanings": " ".join(m.replace(" ", "_")
                                                 for m in STATUS_MEANINGS.values())})
    bdims = (*spec.names[:-1], "batch")
    data["batch_done"] = (bdims, da.zeros(spec.batch_shape, dtype=bool,
                                          chunks=(1,) * len(bdims)),
                          {"long_name": "every point of the batch is written"})
    ds = xr.Dataset(data, coords=coords, attrs={
        IDENTITY: json.dumps(spec.identity()), "railcontact_version": __version__,
        "case_name": spec.case.get("name", "case"), "complete": 0, "messages": "[]"})
    encoding = {v: {"chunks": ds[v].data.chunksize} for v in ds.data_vars}
    encoding["status"]["_FillValue"] = NOT_COMPUTED  # a lost chunk reads "not computed"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds.to_zarr(str(path), mode="w-", compute=False, encoding=encoding, zarr_format=2,
                   consolidated=False)
        # the fill values stand for "not computed": write them where zarr would not
        ds[["batch_done", "status"]].to_zarr(str(path), mode="r+", zarr_format=2,
                                             consolidated=False)


class Store:
    """An open table store for writing batches (the client side of a build)."""

    def __init__(self, path: str | Path, spec: TableSpec) -> None:
        _, zarr = _libs()
        self.path, self.spec = Path(path), spec
        try:
            self.group = zarr.open_group(str(path), mode="r+")
            found = self.group.attrs.get(IDENTITY)
        except Exception as exc:  # noqa: BLE001 - zarr raises several kinds
            raise RailContactError(f"{path} is not a railcontact table store: {exc}") from None
        if found is None:
            raise RailContactError(f"{path} is not a railcontact table store (no "
                                   f"{IDENTITY} attribute)")
        check_identity(path, json.loads(found), spec.identity())
        names = [q.name for q in QUANTITIES + COUNTS] + ["status", "batch_done"]
        self.arrays = {n: self.group[n] for n in names}  # opened once: metadata read once

    def done(self) -> np.ndarray:
        """The batches already complete (bool over :attr:`TableSpec.batch_shape`)."""
        return np.asarray(self.arrays["batch_done"][...], dtype=bool)

    def write(self, index: tuple[int, ...], result: dict[str, Any],
              messages: list[dict[str, Any]]) -> None:
        """Write a batch's arrays and the ``messages`` of its points that are not ok, then
        mark it done (the order that leaves a cut-off write incomplete)."""
        pts = self.spec.batch_points(index)
        *slow, _ = index
        sel = (*slow, slice(pts[0][-1], pts[-1][-1] + 1), slice(None))
        for name in [q.name for q in QUANTITIES + COUNTS] + ["status"]:
            self.arrays[name][sel] = result[name]
        old = json.loads(self.group.attrs.get("messages", "[]"))
        kept = [m for m in old if m.get("batch") != list(index)]  # a batch computed again
        if messages or len(kept) != len(old):
            self.group.attrs["messages"] = json.dumps(kept + messages)
        self.arrays["batch_done"][index] = True

    def finish(self, complete: bool) -> None:
        """Record whether every batch is done."""
        self.group.attrs["complete"] = int(complete)


def check_identity(path: str | Path, found: dict[str, Any], wanted: dict[str, Any]) -> None:
    """Raise when a store was written for another table, naming what differs (compared
    by :func:`~.spec.comparable`: not the spec's name nor the profiles' paths, but the
    profiles' contents)."""
    found, wanted = comparable(found), comparable(wanted)
    if found == wanted:
        return
    diffs = []
    for key in ("case", "axes"):
        a, b = found.get(key, {}), wanted.get(key, {})
        for k in sorted(set(a) | set(b)):
            if a.get(k) != b.get(k):
                diffs.append(f"{key} {k}")
    for key in ("sides", "batch"):
        if found.get(key) != wanted.get(key):
            diffs.append(key)
    raise RailContactError(f"{path} holds a table of another case or grid (differs in: "
                           f"{', '.join(diffs) or 'its identity'}); choose another output or "
                           "remove it")


def open_dataset(path: str | Path):
    """The table at ``path`` as an xarray Dataset (lazy), checked to be a table."""
    xr, _ = _libs()
    p = Path(path)
    if not p.exists():
        raise RailContactError(f"table not found: {p}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ds = xr.open_zarr(str(p), consolidated=False, mask_and_scale=False)
    except Exception as exc:  # noqa: BLE001
        raise RailContactError(f"{p} is not a readable table store: {exc}") from None
    if IDENTITY not in ds.attrs:
        raise RailContactError(f"{p} is not a railcontact table store")
    return ds
