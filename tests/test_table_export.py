"""``railcontact table export``: a table as netCDF (read back by xarray) and as CSV (read
back by the standard library's csv module), value for value against the store (read by
zarr, as :class:`ContactTable` reads it)."""

from __future__ import annotations

import csv
import json
import math
import re

import numpy as np
import pytest

pytest.importorskip("xarray")
pytest.importorskip("zarr")

from _tables import build_here  # noqa: E402

from railcontact.cli import main  # noqa: E402
from railcontact.table import ContactTable, parse_spec  # noqa: E402
from railcontact.table.variables import COUNTS, QUANTITIES  # noqa: E402

RAW = {"name": "export", "material": {"young": 206e9, "poisson": 0.28},
       "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                    "inclination": 0.024994793618920156},
       "grid": {"dx": 0.002, "dy": 0.002}, "normal": {"load": 80e3},
       "tangential": {"creepage": [0.0, 0.0, 0.0], "friction": 0.3},
       "table": {"lateral_displacement": {"values": [0.0, 0.003]},
                 "creepage_y": [0.0, 0.001, 2], "out_of_range": {"creepage_y": "clamp"}}}


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    """The 2 x 2 table (both wheels) built in this process; one point's contact angle made
    NaN and its status no contact (as a point without contact has its geometry: NaN at a
    point solved ok is a damaged store, refused)."""
    import zarr

    spec = parse_spec(RAW)
    out = tmp_path_factory.mktemp("export") / "t.zarr"
    build_here(spec, out)
    arr = zarr.open_group(str(out), mode="r+")["contact_angle"]
    a = arr[...]
    a[1, 0, 1] = np.nan
    arr[...] = a
    status = zarr.open_group(str(out), mode="r+")["status"]
    s = status[...]
    s[1, 0, 1] = 2
    status[...] = s
    return spec, out


def test_netcdf_reads_back_in_xarray(table, tmp_path, capsys):
    import xarray as xr

    spec, out = table
    nc = tmp_path / "t.nc"
    assert main(["table", "export", str(out), str(nc)]) == 0
    assert f"written to {nc}" in capsys.readouterr().out
    t = ContactTable.open(out)
    with xr.open_dataset(nc) as ds:
        assert list(ds["normal_force"].dims) == ["lateral_displacement", "creepage_y", "side"]
        assert ds["side"].values.tolist() == ["left", "right"]
        for n in spec.names:
            assert ds[n].values.tolist() == spec.axes[n].tolist()
        assert ds["normal_force"].attrs["units"] == "N"
        assert json.loads(ds.attrs["out_of_range"]) == {"lateral_displacement": "status",
                                                        "creepage_y": "clamp"}
        assert json.loads(ds.attrs["railcontact_table"])["axes"]["creepage_y"] == [0.0, 0.001]
        assert ds["status"].dtype == np.int8 and "batch_done" not in ds
        for index in np.ndindex(*spec.shape):
            for j, side in enumerate(spec.sides):
                node = t.node(index, side)
                for q in QUANTITIES:
                    got = float(ds[q.name].values[(*index, j)])
                    want = node[q.name]
                    assert got == want or (math.isnan(got) and math.isnan(want)), q.name
                assert int(ds["status"].values[(*index, j)]) == node.status
        assert math.isnan(float(ds["contact_angle"].values[1, 0, 1]))
        assert ds["n_patches"].values.min() >= 1


def test_csv_is_one_row_per_node_and_wheel(table, tmp_path):
    spec, out = table
    path = tmp_path / "t.csv"
    assert main(["table", "export", str(out), str(path)]) == 0
    t = ContactTable.open(out)
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    head = rows[0]
    assert head[:3] == ["lateral_displacement", "creepage_y", "side"]
    assert head[3:] == [q.name for q in QUANTITIES] + ["status"] + [q.name for q in COUNTS]
    assert len(rows) == 1 + spec.size * 2
    seen = set()
    for row in rows[1:]:
        rec = dict(zip(head, row, strict=True))
        index = tuple(int(np.flatnonzero(spec.axes[n] == float(rec[n]))[0])
                      for n in spec.names)
        seen.add((index, rec["side"]))
        node = t.node(index, rec["side"])
        for q in QUANTITIES:
            got, want = float(rec[q.name]), node[q.name]
            assert got == want or (math.isnan(got) and math.isnan(want)), q.name
        assert int(rec["status"]) == node.status
    assert len(seen) == spec.size * 2
    assert rows[1 + 2 * 2 + 1][head.index("contact_angle")] == "nan"  # node (1, 0), right


def test_bad_export_is_an_error(table, tmp_path, capsys):
    _, out = table
    assert main(["table", "export", str(out), str(tmp_path / "t.txt")]) == 2
    assert "cannot tell the format" in capsys.readouterr().err
    assert main(["table", "export", str(out), str(tmp_path / "no" / "t.nc")]) == 2
    assert main(["table", "export", str(tmp_path / "none.zarr"), str(tmp_path / "t.nc")]) == 2
    assert main(["table", "export", str(out), str(tmp_path / "t.txt"), "--format",
                 "csv"]) == 0


def test_a_damaged_store_is_one_clear_error(table, tmp_path, capsys):
    """A store whose chunk of a quantity is lost (zarr then reads its fill value, NaN, at
    points solved ok) or holds garbage (the decompressor fails) is refused as damaged -
    by ContactTable.open, show and export alike - never read as NaN with status ok nor a
    reader's traceback."""
    import shutil

    from railcontact.errors import RailContactError

    _, out = table
    lost = tmp_path / "lost.zarr"
    shutil.copytree(out, lost)
    for f in (lost / "normal_force").iterdir():
        if not f.name.startswith("."):
            f.unlink()
    with pytest.raises(RailContactError, match=r"a damaged table store \(normal_force not "
                                               "finite at points solved ok"):
        ContactTable.open(lost)
    garbled = tmp_path / "garbled.zarr"
    shutil.copytree(out, garbled)
    for f in (garbled / "creep_force_y").iterdir():
        if not f.name.startswith("."):
            f.write_bytes(b"garbage\n")
    capsys.readouterr()
    for args in (["show", str(garbled)], ["export", str(garbled), str(tmp_path / "g.csv")]):
        assert main(["table", *args]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "a damaged table store" in err, err
    with pytest.raises(RailContactError, match="a damaged table store"):
        ContactTable.open(garbled)


def test_a_store_without_its_status_is_refused(table, tmp_path, capsys):
    """A store whose status array is gone: show and export refuse it in one line (a
    KeyError traceback, and an export without a status column, before)."""
    import shutil

    _, out = table
    bare = tmp_path / "bare.zarr"
    shutil.copytree(out, bare)
    shutil.rmtree(bare / "status")
    capsys.readouterr()
    for args in (["show", str(bare)], ["export", str(bare), str(tmp_path / "b.csv")]):
        assert main(["table", *args]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "no status array" in err, err
    assert not (tmp_path / "b.csv").exists()


def test_a_store_missing_a_quantity_or_its_identity_is_refused(table, tmp_path, capsys):
    """A store copied without a whole quantity's array (normal_force), without its batch
    bookkeeping, or with its identity attribute garbled: refused as damaged by
    ContactTable.open, show and export alike - not read as NaN forces with status ok nor
    a KeyError or JSON traceback. The lost chunk read as NaN at points solved ok is
    refused by show and export too (ContactTable.open did already)."""
    import shutil

    from railcontact.errors import RailContactError

    _, out = table
    stores = {}
    for name, why in (("normal_force", r"no normal_force array"),
                      ("batch_done", r"no batch_done array")):
        bad = tmp_path / f"no_{name}.zarr"
        shutil.copytree(out, bad)
        shutil.rmtree(bad / name)
        stores[bad] = why
    ident = tmp_path / "ident.zarr"
    shutil.copytree(out, ident)
    attrs_file = ident / ".zattrs" if (ident / ".zattrs").exists() else ident / "zarr.json"
    attrs = json.loads(attrs_file.read_text())
    if ".zattrs" in attrs_file.name:
        attrs["railcontact_table"] = "{not json"
    else:
        attrs["attributes"]["railcontact_table"] = "{not json"
    attrs_file.write_text(json.dumps(attrs))
    stores[ident] = r"railcontact_table attribute is not a table's identity"
    lost = tmp_path / "lost.zarr"
    shutil.copytree(out, lost)
    for f in (lost / "normal_force").iterdir():
        if not f.name.startswith("."):
            f.unlink()
    stores[lost] = r"normal_force not finite at points solved ok"
    for store, why in stores.items():
        capsys.readouterr()
        for args in (["show", str(store)], ["export", str(store), str(tmp_path / "x.csv")]):
            assert main(["table", *args]) == 2, (store, args)
            err = capsys.readouterr().err
            assert err.count("\n") == 1 and re.search(why, err), err
        if store.name != "no_batch_done.zarr":  # (an interpolating table needs no batches)
            with pytest.raises(RailContactError, match=why):
                ContactTable.open(store)
