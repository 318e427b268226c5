"""A table on disk: an xarray Dataset in a Zarr store.

Layout (``railcontact table build``)::

    dims     the axes in spec order (the last the fastest), then ``side``
    coords   each axis [SI unit] and ``side`` ("left", "right")
    data     every quantity of :mod:`.variables` (float64; NaN where not defined; a store
             of an earlier railcontact may lack ``penetration``), the work
             counters (int32) and ``status`` (int8: -1 not computed, 0 ok, 1 not converged,
             2 no contact, 3 out of range), each with ``units`` and ``long_name``; chunked
             one batch per chunk (1 along the slow axes, ``batch`` along the fastest)
    batch_done   bool over the batch grid (the slow axes and ``batch``): set only after all
             of a batch's data are written, so that a batch cut off while being written is
             not complete and is computed again
    attrs    ``railcontact_table`` (the identity: case, axes, sides, batch, as JSON),
             ``flange_flank`` (S [m] and angle [rad] of the wheel flange's steepest
             point, JSON), ``railcontact_version``, ``case_name``, ``complete`` (all batches done),
             ``messages`` (JSON: the message of every point that is not ok, gathered
             when a build ends)
    messages/<batch>   a group per batch with points that are not ok (``<batch>`` its
             index, e.g. ``1.0.3``), their messages in its attribute ``messages``: a batch
             writes only its own, so that a build with many such batches does not rewrite
             one growing document per batch (:func:`read_messages` reads them)

A store whose identity differs from the spec's is an error, never overwritten.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..contact.wheelrail import build_geometry
from ..errors import RailContactError
from ..settings import Case
from .spec import AXES, TableSpec, comparable
from .variables import COUNTS, NOT_COMPUTED, QUANTITIES, STATUS_MEANINGS

IDENTITY = "railcontact_table"
FLANGE = "flange_flank"
"""The attribute holding the wheel's flange (:func:`wheel_flange`, JSON)."""
MESSAGES = "messages"
"""The group of the per-batch message groups (and the root attribute that gathers them)."""


def _libs():
    try:
        import xarray as xr
        import zarr
    except ImportError as exc:  # pragma: no cover - the [tables] extra
        raise RailContactError(f"tables need the [tables] extra (pip install "
                               f"'railcontact[tables]'): {exc}") from None
    return xr, zarr


def wheel_flange(case: dict[str, Any]) -> list[float]:
    """The steepest point of the case's wheel flange: its profile coordinate S [m] and angle
    [rad] (:attr:`~railcontact.geometry.Wheelset.flange_flank`), which the validity of a
    table step needs (Nadal's limit, flange climb); kept in the store so that a table is
    used without its profile files.

    Raises
    ------
    RailContactError
        When the case's wheel profile cannot be read.
    """
    _, ws, _ = build_geometry(Case.from_dict(case).geometry)
    return list(ws.flange_flank)


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
        FLANGE: json.dumps(wheel_flange(spec.case)),
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
        lacking = [n for n in names if n not in self.group]
        if lacking:
            raise RailContactError(f"{path} was written by an earlier railcontact without "
                                   f"{', '.join(lacking)}: it cannot be resumed; build the "
                                   "table anew (another output, or remove it)")
        self.arrays = {n: self.group[n] for n in names}  # opened once: metadata read once
        self.written = False
        if MESSAGES in self.group:
            self.messages = self.group[MESSAGES]
        else:  # (a store written before per-batch messages: its messages moved there once)
            old = json.loads(self.group.attrs.get(MESSAGES, "[]"))
            self.messages = self.group.require_group(MESSAGES)
            for key in sorted({".".join(map(str, m["batch"])) for m in old}):
                self.messages.require_group(key).attrs[MESSAGES] = [
                    m for m in old if ".".join(map(str, m["batch"])) == key]

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
        key = ".".join(map(str, index))
        if messages:
            self.messages.require_group(key).attrs[MESSAGES] = messages
        elif key in self.messages:  # a batch computed again, now without messages
            del self.messages[key]
        self.written = True
        self.arrays["batch_done"][index] = True

    def finish(self, complete: bool) -> None:
        """Record whether every batch is done, and gather the batches' messages into the
        root attribute ``messages`` when a batch was written."""
        attrs = {"complete": int(complete)}
        if self.written:
            attrs[MESSAGES] = json.dumps(_gathered(self.messages))
        self.group.attrs.update(attrs)


def _gathered(messages) -> list[dict[str, Any]]:
    """The messages of the per-batch groups of ``messages``, in batch order."""
    keys = sorted(messages.group_keys(), key=lambda k: tuple(int(i) for i in k.split(".")))
    return [m for k in keys for m in messages[k].attrs[MESSAGES]]


def read_messages(path: str | Path) -> list[dict[str, Any]]:
    """The message of every point of the table at ``path`` that is not ok (each a dict:
    ``batch``, ``side``, ``status``, ``point`` {axis: value [SI]}, ``message``), in batch
    order; read from the per-batch groups, so also from a build that was cut off."""
    _, zarr = _libs()
    group = zarr.open_group(str(path), mode="r")
    if MESSAGES in group:
        return _gathered(group[MESSAGES])
    return json.loads(group.attrs.get(MESSAGES, "[]"))


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
