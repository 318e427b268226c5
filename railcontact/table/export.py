"""A table in the formats other tools read (``railcontact table export``).

``netcdf``
    The table's Dataset (the axes and ``side`` as coordinates, every quantity, the work
    counters and ``status`` with their ``units`` and ``long_name``, the store's attributes)
    written by xarray, with the netCDF engine it finds (netCDF4 or h5netcdf when
    installed, else scipy's netCDF3, which the ``[tables]`` extra has). The per-batch
    bookkeeping (``batch_done``) is left out.
``csv``
    Long format: a header row of names, then one row per node and wheel, the axes first
    (in the table's order), then ``side``, every quantity, ``status`` and the work
    counters; SI units as in the store; floats as the shortest decimal that reads back to
    the same value; ``nan`` where a quantity is undefined (no contact, a failed point).
    A geometry table (:mod:`railcontact.table.geometry`): its wheelset's quantities on
    both rows of a node, each patch's as ``<name>_<k>``
    (:func:`~.geometry_table.export_csv`).

A creep table (``kind = "creep"``): its Dataset as netCDF, or a CSV row per node (the
axes, the normalised values, status and the creep coefficients of the node's ellipse
ratio; :func:`~.creepread.export_creep_csv`).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from ..errors import RailContactError
from .creepread import export_creep_csv, is_creep_table
from .geometry import KIND
from .geometry_table import data_names, export_csv
from .store import IDENTITY, check_contact_dataset, kind_of, open_dataset, require_status
from .variables import COUNTS, QUANTITIES

FORMATS = {".nc": "netcdf", ".csv": "csv"}
"""File suffix -> format."""


def _format(out: Path, fmt: str | None) -> str:
    if fmt is None:
        fmt = FORMATS.get(out.suffix.lower())
        if fmt is None:
            raise RailContactError(f"cannot tell the format of {out} from its suffix "
                                   f"({', '.join(FORMATS)}): give --format "
                                   f"{'|'.join(FORMATS.values())}")
    if fmt not in FORMATS.values():
        raise RailContactError(f"--format must be one of {', '.join(FORMATS.values())}, "
                               f"got {fmt!r}")
    return fmt


def export_table(path: str | Path, out: str | Path, fmt: str | None = None) -> Path:
    """Write the table at ``path`` to ``out`` as ``fmt`` (``netcdf`` or ``csv``; None: from
    the suffix, ``.nc`` or ``.csv``). Returns ``out``.

    Raises
    ------
    RailContactError
        For no table at ``path``, an unknown format, a folder that does not exist.
    """
    out = Path(out)
    fmt = _format(out, fmt)
    if not out.parent.is_dir():
        raise RailContactError(f"folder {out.parent} does not exist")
    ds = open_dataset(path)
    creep = is_creep_table(ds)
    if creep and fmt == "csv":
        return export_creep_csv(ds, out)
    if not creep:
        require_status(path, ds)
        check_contact_dataset(path, ds)
    names = list(json.loads(ds.attrs[IDENTITY])["axes"])
    geometry = kind_of(ds.attrs) == KIND
    data = (list(ds.data_vars) if creep else data_names() if geometry else
            [q.name for q in QUANTITIES] + ["status"] + [q.name for q in COUNTS])
    data = [n for n in data if n in ds]
    if fmt == "netcdf":
        keep = ds[data].load()
        keep.attrs = dict(ds.attrs)
        for v in keep.variables.values():  # the store's encodings are zarr's, not netCDF's
            v.encoding = {}
            v.attrs.pop("_FillValue", None)
        try:
            keep.to_netcdf(out)
        except (OSError, ValueError) as exc:
            raise RailContactError(f"cannot write {out}: {exc}") from None
        return out
    if geometry:
        return export_csv(ds, names, out)
    order = [*names, "side"]
    arrays = {n: ds[n].transpose(*order).values for n in data}
    grids = np.meshgrid(*[ds[n].values for n in names], indexing="ij")
    sides = ds["side"].values.tolist()
    ints = {"status"} | {q.name for q in COUNTS}
    with out.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow([*names, "side", *data])
        for index in np.ndindex(*grids[0].shape) if names else [()]:
            axes = [repr(float(g[index])) for g in grids]
            for j, side in enumerate(sides):
                w.writerow([*axes, side, *(str(int(arrays[n][(*index, j)])) if n in ints
                                           else repr(float(arrays[n][(*index, j)]))
                                           for n in data)])
    return out
