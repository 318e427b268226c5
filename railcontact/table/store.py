"""A table on disk: an xarray Dataset in a Zarr store (format 2).

Layout (``railcontact table build``)::

    dims     the axes in spec order (the last the fastest), then ``side``
    coords   each axis [SI unit] and ``side`` ("left", "right")
    data     every quantity of :mod:`.variables` (float64; NaN where not defined; a store
             of an earlier railcontact may lack ``penetration``), the work
             counters (int32) and ``status`` (int8: -1 not computed, 0 ok, 1 not converged,
             2 no contact, 3 out of range), each with ``units`` and ``long_name``; chunked
             by axis blocks (:func:`chunk_shape`: the fastest axis and the sides whole, then
             as many of the slower axes as keep a chunk within :data:`CHUNK_VALUES` values),
             so a table is a few files per quantity whatever its batches; a chunk never
             written reads its fill value (NaN, 0, status -1: not computed)
    batch_done   bool over the batch grid (the slow axes and ``batch``): set only after all
             of a batch's data are written, so that a batch cut off while being written is
             not complete and is computed again
    attrs    ``railcontact_table`` (the identity: case, axes, sides, batch, as JSON),
             ``flange_flank`` (S [m] and angle [rad] of the wheel flange's steepest
             point, JSON), ``out_of_range`` (each axis's policy, JSON: the spec's),
             ``railcontact_version``, ``case_name``, ``complete`` (all batches done),
             ``failed`` (JSON: point-wheels of each failed status, when a build ends),
             ``messages`` (JSON: the message of every point that is not ok, gathered
             when a build ends)
    messages/w<n>   during a build, a group per write of the client that holds messages,
             in its attributes ``messages`` and ``batches`` (the batches it wrote); for
             each batch the latest write counts, and only once the batch is done
             (:func:`read_messages`); gathered into the root attribute and removed when the
             build ends

The client writes the batches that finished since its last write together
(:meth:`Store.write_batches`): each chunk they touch is read, filled and written once
(the store writes each chunk file whole, through a temporary file, so a write cut off
leaves the chunk as it was), then their ``batch_done``.

A store whose identity differs from the spec's is an error, never overwritten.
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..contact.wheelrail import build_geometry
from ..errors import RailContactError
from ..settings import Case
from ..status import Status
from .geometry import KIND as GEOMETRY_KIND
from .spec import CREEP_KIND, DEFAULT_KIND, TableSpec, axis_info, comparable
from .variables import (
    COUNTS,
    NOT_COMPUTED,
    QUANTITIES,
    STATUS_MEANINGS,
    VALIDITY_QUANTITIES,
    failed_counts,
)

IDENTITY = "railcontact_table"
FLANGE = "flange_flank"
"""The attribute holding the wheel's flange (:func:`wheel_flange`, JSON)."""
MESSAGES = "messages"
"""The group of the message groups (and the root attribute that gathers them)."""
POLICY_ATTR = "out_of_range"
"""The root attribute holding each axis's out-of-range policy (JSON)."""
FAILED_ATTR = "failed"
"""The root attribute counting the failed point-wheels by status (JSON)."""
CHUNK_VALUES = 1 << 17
"""Largest number of values (points x wheels) of a chunk of a quantity, when the fastest
axis and the sides fit (1 MiB of float64): a table of up to that many point-wheels is one
chunk per quantity."""
DONE_CHUNK = 1 << 22
"""Largest number of batches of a chunk of ``batch_done``."""


def _libs():
    """xarray and zarr (the [tables] extra)."""
    try:
        import xarray as xr
    except ImportError as exc:  # pragma: no cover - the [tables] extra
        raise RailContactError(f"tables need the [tables] extra (pip install "
                               f"'railcontact[tables]'): {exc}") from None
    return xr, _zarr()


def _zarr():
    """zarr alone (reading and writing a store need no xarray, which takes longer to
    import than a table to read)."""
    try:
        import zarr
    except ImportError as exc:  # pragma: no cover - the [tables] extra
        raise RailContactError(f"tables need the [tables] extra (pip install "
                               f"'railcontact[tables]'): {exc}") from None
    return zarr


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


def block_chunks(shape: tuple[int, ...], limit: int, whole: int = 1) -> tuple[int, ...]:
    """Chunks of an array of ``shape``: its last ``whole`` dimensions whole, then, from the
    last of the others backwards, each whole while the chunk keeps within ``limit`` values,
    the next one in a block that keeps it there, the rest 1."""
    chunks = list(shape)
    size = math.prod(shape[len(shape) - whole:]) if whole else 1
    for k in range(len(shape) - whole - 1, -1, -1):
        take = max(min(shape[k], limit // max(size, 1)), 1)
        chunks[k] = take
        if take < shape[k]:
            chunks[:k] = [1] * k
            break
        size *= take
    return tuple(chunks)


def chunk_shape(spec: TableSpec) -> tuple[int, ...]:
    """Chunks of a quantity of ``spec``'s table (axes, then the sides): the fastest axis and
    the sides whole (a batch lies in one chunk), the slower axes in blocks within
    :data:`CHUNK_VALUES` values."""
    return block_chunks((*spec.shape, len(spec.sides)), CHUNK_VALUES, whole=2)


def data_arrays(spec: TableSpec) -> list[tuple[str, str, Any, dict[str, Any], tuple]]:
    """The data arrays of ``spec``'s table but ``status``: ``(name, dtype, fill value,
    attributes, trailing dims)``, each over the axes and then its trailing dims, each dim a
    name and a size (``("side", 2)``); another kind of table gives its own
    (``spec.data_arrays()``, :mod:`railcontact.table.geometry`)."""
    own = getattr(spec, "data_arrays", None)
    if own is not None:
        return own()
    side = (("side", len(spec.sides)),)
    return ([(q.name, "f8", np.nan, {"units": q.unit, "long_name": q.long_name}, side)
             for q in QUANTITIES]
            + [(q.name, "i4", 0, {"units": q.unit, "long_name": q.long_name}, side)
               for q in COUNTS])


READERS = {DEFAULT_KIND: "ContactTable", GEOMETRY_KIND: "GeometryTable",
           CREEP_KIND: "CreepTable"}
"""The class of :mod:`railcontact.table` that reads each kind of table."""


def reader_of(kind: str) -> str:
    """The class that reads a table of kind ``kind`` (``railcontact.table.ContactTable``
    ...)."""
    return f"railcontact.table.{READERS.get(kind, READERS[DEFAULT_KIND])}"


def kind_of(attrs: dict[str, Any]) -> str:
    """The kind of the table whose root attributes are ``attrs`` (``[table] kind``)."""
    return json.loads(attrs.get(IDENTITY, "{}")).get("kind", DEFAULT_KIND)


def refuse_kind(path: str | Path, attrs: dict[str, Any], what: str) -> None:
    """Raise unless the table at ``path`` (root attributes ``attrs``) is a creep-force
    table, which ``what`` needs."""
    kind = kind_of(attrs)
    if kind != DEFAULT_KIND:
        raise RailContactError(f"{path} is a {kind} table ([table] kind = {kind!r}), not a "
                               f"{DEFAULT_KIND} table, which {what} needs")


def create_store(path: str | Path, spec: TableSpec) -> None:
    """Write an empty table (metadata and the axes; every point not computed) for
    ``spec``: the data's chunks are not written (each reads its fill value until a batch
    is), so this takes no time and no cluster."""
    zarr = _zarr()
    chunks = chunk_shape(spec)
    flags = {"flag_values": list(STATUS_MEANINGS),
             "flag_meanings": " ".join(m.replace(" ", "_") for m in STATUS_MEANINGS.values())}
    path = Path(path)
    if path.exists():
        raise RailContactError(f"{path} exists: not overwritten")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zarr: format 2 and fixed-length strings
        root = zarr.open_group(str(path), mode="w-", zarr_format=2)
        for n, v in spec.axes.items():
            a = root.create_array(n, shape=(len(v),), dtype="f8", chunks=(len(v),),
                                  fill_value=np.nan, attributes={
                                      "units": axis_info(n).unit,
                                      "long_name": axis_info(n).long_name,
                                      "_ARRAY_DIMENSIONS": [n]})
            a[...] = np.asarray(v, dtype=float)
        side = np.array(list(spec.sides))
        a = root.create_array("side", shape=side.shape, dtype=side.dtype, chunks=side.shape,
                              attributes={"_ARRAY_DIMENSIONS": ["side"]})
        a[...] = side
        data = (data_arrays(spec)
                + [("status", "i1", NOT_COMPUTED, {"long_name": "status of the point", **flags},
                    (("side", len(spec.sides)),))])
        for name, dtype, fill, attrs, trailing in data:
            # the axes chunked as status's, whatever the trailing dims (a batch in one chunk)
            root.create_array(name, shape=(*spec.shape, *(n for _, n in trailing)),
                              dtype=dtype, chunks=(*chunks[:-1], *(n for _, n in trailing)),
                              fill_value=fill, attributes={
                                  **attrs, "_ARRAY_DIMENSIONS": [*spec.names,
                                                                 *(d for d, _ in trailing)]})
        bshape = spec.batch_shape
        root.create_array("batch_done", shape=bshape, dtype=bool,
                          chunks=block_chunks(bshape, DONE_CHUNK), fill_value=False,
                          attributes={"long_name": "every point of the batch is written",
                                      "_ARRAY_DIMENSIONS": [*spec.names[:-1], "batch"]})
        root.require_group(MESSAGES)
        root.attrs.update({
            IDENTITY: json.dumps(spec.identity()), "railcontact_version": __version__,
            FLANGE: json.dumps(wheel_flange(spec.case)),
            "case_name": spec.case.get("name", "case"), "complete": 0, "messages": "[]",
            POLICY_ATTR: json.dumps(spec.policies())})


def batch_key(index) -> str:
    """The key of a batch (its index, e.g. ``1.0.3``)."""
    return ".".join(str(int(i)) for i in index)


class Store:
    """An open table store for writing batches (the client side of a build)."""

    def __init__(self, path: str | Path, spec: TableSpec) -> None:
        zarr = _zarr()
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
        self.data = [a[0] for a in data_arrays(spec)] + ["status"]
        names = [*self.data, "batch_done"]
        lacking = [n for n in names if n not in self.group]
        if lacking:
            raise RailContactError(f"{path} was written by an earlier railcontact without "
                                   f"{', '.join(lacking)}: it cannot be resumed; build the "
                                   "table anew (another output, or remove it)")
        self.arrays = {n: self.group[n] for n in names}  # opened once: metadata read once
        if self.group.attrs.get(POLICY_ATTR) != json.dumps(spec.policies()):
            self.group.attrs[POLICY_ATTR] = json.dumps(spec.policies())  # the spec's now
        self.written = False
        self.messages = self.group.require_group(MESSAGES)
        # the batches that have messages somewhere: a write of one of them must say it
        # again (if only that it has none now), the latest write counting
        self._noted = set(_resolved(self.group, done=None))
        self._writes = 1 + max((int(k[1:]) for k in self.messages.group_keys()
                                if k.startswith("w") and k[1:].isdigit()), default=0)

    def done(self) -> np.ndarray:
        """The batches already complete (bool over :attr:`TableSpec.batch_shape`)."""
        return np.asarray(self.arrays["batch_done"][...], dtype=bool)

    def write(self, index: tuple[int, ...], result: dict[str, Any],
              messages: list[dict[str, Any]]) -> None:
        """Write one batch (:meth:`write_batches`)."""
        self.write_batches([(tuple(index), result, messages)])

    def write_batches(self, batches: list[tuple[tuple[int, ...], dict[str, Any],
                                                list[dict[str, Any]]]]) -> None:
        """Write batches ``(index, result, messages)`` (a result with ``fast``: only its
        points at those indices along the fastest axis): their arrays, each chunk they touch
        read, filled and written once; then the ``messages`` of their points that are not
        ok; then mark them done (the order that leaves a cut-off write incomplete)."""
        if not batches:
            return
        chunks = self.arrays["status"].chunks
        nslow = len(self.spec.shape) - 1
        by_chunk: dict[tuple[int, ...], list] = {}
        for item in batches:
            slow = item[0][:nslow]
            by_chunk.setdefault(tuple(i // c for i, c in zip(slow, chunks, strict=False)),
                                []).append(item)
        for name in self.data:
            arr = self.arrays[name]
            for c, items in by_chunk.items():
                lo = [k * n for k, n in zip(c, chunks, strict=False)]
                region = tuple(slice(a, min(a + n, size)) for a, n, size in
                               zip(lo, chunks, arr.shape, strict=False))
                block = arr[region]
                for index, result, _ in items:
                    pts = self.spec.batch_points(index)
                    at = tuple(i - a for i, a in zip(index[:nslow], lo, strict=False))
                    fast = result.get("fast")  # some of the batch's points (a refinement)
                    where = (slice(pts[0][-1], pts[-1][-1] + 1) if fast is None else
                             np.asarray(fast, dtype=np.intp))
                    block[(*at, where)] = result[name]
                arr[region] = block
        keys = [batch_key(ix) for ix, _, _ in batches]
        said = [m for _, _, msgs in batches for m in msgs]
        if said or self._noted & set(keys):
            self.messages.require_group(f"w{self._writes}").attrs.update(
                {MESSAGES: said, "batches": keys})
            self._writes += 1
            self._noted |= {batch_key(m["batch"]) for m in said}
        self.written = True
        done = self.arrays["batch_done"]
        flags = np.asarray(done[...], dtype=bool)
        for ix, _, _ in batches:
            flags[ix] = True
        done[...] = flags

    def finish(self, complete: bool) -> dict[str, int]:
        """Record whether every batch is done and the failed point-wheels (attribute
        ``failed``), and, when a batch was written, gather the messages into the root
        attribute ``messages`` and remove the message groups. Returns the failed counts
        (:func:`~.variables.failed_counts`)."""
        failed = failed_counts(self.arrays["status"][...])
        attrs: dict[str, Any] = {"complete": int(complete), FAILED_ATTR: json.dumps(failed)}
        if self.written or list(self.messages.group_keys()):
            attrs[MESSAGES] = json.dumps(_ordered(_resolved(self.group)))
        self.group.attrs.update(attrs)
        for key in list(self.messages.group_keys()):  # gathered: one file, not one a write
            del self.messages[key]
        return failed


def _ordered(by_batch: dict[str, list[dict[str, Any]]]) -> list[dict[str, Any]]:
    keys = sorted(by_batch, key=lambda k: tuple(int(i) for i in k.split(".")))
    return [m for k in keys for m in by_batch[k]]


def _resolved(group, done: np.ndarray | None | str = "read") -> dict[str, list[dict[str, Any]]]:
    """The messages of each batch of the store ``group``: the root attribute's, replaced
    by those of a per-batch group (an earlier layout), replaced by the latest write group
    that wrote the batch; only the batches done (``done``: their flags; "read": read them;
    None: every batch)."""
    out: dict[str, list[dict[str, Any]]] = {}
    for m in json.loads(group.attrs.get(MESSAGES, "[]")):
        out.setdefault(batch_key(m["batch"]), []).append(m)
    if MESSAGES in group:
        sub = group[MESSAGES]
        keys = list(sub.group_keys())
        for k in keys:  # one group per batch, named by it
            if not k.startswith("w"):
                out[k] = list(sub[k].attrs.get(MESSAGES, []))
        writes = sorted((int(k[1:]), k) for k in keys if k.startswith("w") and k[1:].isdigit())
        for _, k in writes:
            attrs = sub[k].attrs
            for b in attrs.get("batches", []):
                out[b] = []
            for m in attrs.get(MESSAGES, []):
                out[batch_key(m["batch"])].append(m)
    if isinstance(done, str):
        done = np.asarray(group["batch_done"][...], dtype=bool) if "batch_done" in group \
            else None
    if done is not None:
        out = {k: v for k, v in out.items()
               if v and bool(done[tuple(int(i) for i in k.split("."))])}
    return {k: v for k, v in out.items() if v}


def read_messages(path: str | Path) -> list[dict[str, Any]]:
    """The message of every point of the table at ``path`` that is not ok (each a dict:
    ``batch``, ``side``, ``status``, ``point`` {axis: value [SI]}, ``message``), in batch
    order, of the batches done; also from a build that was cut off."""
    zarr = _zarr()
    return _ordered(_resolved(zarr.open_group(str(path), mode="r")))


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
            ds = xr.open_zarr(str(p), consolidated=False, mask_and_scale=False, chunks=None)
    except Exception as exc:  # noqa: BLE001
        raise RailContactError(f"{p} is not a readable table store: {exc}") from None
    if IDENTITY not in ds.attrs:
        raise RailContactError(f"{p} is not a railcontact table store")
    check_identity_attr(p, ds.attrs)
    try:  # (every chunk read here: a damaged one is this error, not a reader's traceback)
        ds = ds.load()
    except Exception as exc:  # noqa: BLE001
        raise damaged(p, f"{type(exc).__name__}: {exc}") from None
    return ds


def check_contact_dataset(path: str | Path, ds) -> None:
    """:func:`check_contact_arrays` of the dataset ``ds`` of the table at ``path`` when it
    is a contact table (after :func:`require_status`: a store without its status says
    so)."""
    if kind_of(ds.attrs) == DEFAULT_KIND:
        check_contact_arrays(path, {n: ds[n].values for n in ds.data_vars})


def check_identity_attr(path: str | Path, attrs) -> None:
    """Raise the error of a damaged store when the table's identity attribute at ``path``
    is not a JSON object (its ``axes``, where it has them, one too)."""
    try:
        ident = json.loads(attrs[IDENTITY])
        ok = isinstance(ident, dict) and isinstance(ident.get("axes", {}), dict)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise damaged(path, f"its {IDENTITY} attribute is not a table's identity")


def check_contact_arrays(path: str | Path, arrays: dict[str, Any]) -> None:
    """Raise the error of a damaged contact table at ``path`` when ``arrays`` lack the
    status, the batch bookkeeping or the counts, or as :func:`check_quantities`."""
    lacking = [n for n in ("status", "batch_done", *(c.name for c in COUNTS))
               if n not in arrays]
    if lacking:
        raise damaged(path, f"no {', '.join(lacking)} array")
    check_quantities(path, arrays)


def check_quantities(path: str | Path, arrays: dict[str, Any]) -> None:
    """Raise the error of a damaged contact table at ``path`` when ``arrays`` (with the
    status) lack a quantity (only the validity quantities may be absent: a store written
    before them), or a quantity is not finite at a point solved ok (a chunk lost: zarr
    reads it as its fill value)."""
    lacking = [q.name for q in QUANTITIES
               if q.name not in arrays and q.name not in VALIDITY_QUANTITIES]
    if lacking:
        raise damaged(path, f"no {', '.join(lacking)} array")
    status = np.asarray(arrays["status"])
    solved = np.isin(status, (Status.OK, Status.OUTSIDE_VALIDITY))  # (every value finite)
    lost = [q.name for q in QUANTITIES if q.name in arrays
            and not np.isfinite(np.asarray(arrays[q.name], dtype=float)[solved]).all()]
    if lost:
        raise damaged(path, f"{', '.join(lost)} not finite at points solved ok: a chunk "
                      "lost")


def damaged(path: str | Path, why: str) -> RailContactError:
    """The error of the damaged table store at ``path`` (``why``: what is wrong in it)."""
    return RailContactError(f"{path}: a damaged table store ({why}); build it again")


def require_status(path: str | Path, ds) -> None:
    """Raise a :class:`RailContactError` when the contact or geometry table ``ds`` at
    ``path`` has no ``status`` array (a damaged store)."""
    if "status" not in ds.variables:
        raise damaged(path, "no status array")


def read_table(path: str | Path, names: list[str]) -> tuple[dict[str, Any], dict[str, Any]]:
    """The root attributes of the table at ``path`` and its arrays ``names`` present
    (numpy), ``side`` as a list of str: what an interpolating table needs, read by zarr
    alone (no xarray: a table opens in the time its few chunk files take to read).

    Raises
    ------
    RailContactError
        When there is no table at ``path``.
    """
    zarr = _zarr()
    p = Path(path)
    if not p.exists():
        raise RailContactError(f"table not found: {p}")
    try:
        group = zarr.open_group(str(p), mode="r")
        attrs = dict(group.attrs)
    except Exception as exc:  # noqa: BLE001
        raise RailContactError(f"{p} is not a readable table store: {exc}") from None
    if IDENTITY not in attrs:
        raise RailContactError(f"{p} is not a railcontact table store")
    check_identity_attr(p, attrs)
    if kind_of(attrs) == CREEP_KIND:
        raise RailContactError(f"{p} is a {CREEP_KIND} table, not a contact table (a "
                               f"{CREEP_KIND} table is read by {reader_of(CREEP_KIND)})")
    try:
        arrays = {n: group[n][...] for n in names if n in group}
        arrays["side"] = [str(x) for x in np.asarray(group["side"][...]).tolist()]
    except Exception as exc:  # noqa: BLE001 - a chunk damaged, an array lost
        raise damaged(p, f"{type(exc).__name__}: {exc}") from None
    if "status" in names and "status" not in arrays:
        raise damaged(p, "no status array")
    return attrs, arrays
