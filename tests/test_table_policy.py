"""A table's out-of-range policy per axis (``[table] out_of_range``: ``status`` or
``clamp``), in Python (:class:`ContactTable`) and in a table step (the FMU's table mode).

A tiny table (the left and right wheels at y = 2 and 4 mm, 2 mm elements) is built in this
process (no cluster): each batch solved by the build's own ``solve_batch`` and written by
its ``Store``. The truth at a clamped state is the exact solve at the axis's end
(``railcontact solve``), which the table holds at that node.
"""

from __future__ import annotations

import json

import pytest

pytest.importorskip("xarray")
pytest.importorskip("zarr")

from _tables import build_here  # noqa: E402

from railcontact import solve  # noqa: E402
from railcontact.errors import CaseError, RailContactError  # noqa: E402
from railcontact.geometry.track import Pose  # noqa: E402
from railcontact.table import ContactTable, parse_spec  # noqa: E402
from railcontact.table.step import TableContact  # noqa: E402
from railcontact.table.store import Store  # noqa: E402


def _raw(out_of_range=None) -> dict:
    table = {"lateral_displacement": {"values": [0.002, 0.004]},
             "creepage_y": [0.0, 0.001, 2]}
    if out_of_range is not None:
        table["out_of_range"] = out_of_range
    return {"name": "policy", "material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                         "inclination": 0.024994793618920156},
            "grid": {"dx": 0.002, "dy": 0.002}, "normal": {"load": 80e3},
            "tangential": {"creepage": [0.0, 0.0, 0.0], "friction": 0.3},
            "table": table}


def _build_here(spec, out) -> None:
    """The table of ``spec`` into ``out`` in this process (the build's solver and
    writer)."""
    build_here(spec, out)


@pytest.fixture(scope="module")
def clamped(tmp_path_factory):
    spec = parse_spec(_raw({"lateral_displacement": "clamp"}))
    out = tmp_path_factory.mktemp("policy") / "t.zarr"
    _build_here(spec, out)
    return spec, out


def test_the_policy_is_parsed_per_axis_and_not_part_of_the_identity():
    default = parse_spec(_raw())
    assert default.policies() == {"lateral_displacement": "status", "creepage_y": "status"}
    every = parse_spec(_raw("clamp"))
    assert every.policies() == {"lateral_displacement": "clamp", "creepage_y": "clamp"}
    one = parse_spec(_raw({"creepage_y": "clamp"}))
    assert one.policies() == {"lateral_displacement": "status", "creepage_y": "clamp"}
    assert default.identity() == every.identity() == one.identity()
    with pytest.raises(CaseError, match="out_of_range creepage_y: the policy must be one of "
                       "status, clamp, got 'nearest'"):
        parse_spec(_raw({"creepage_y": "nearest"}))
    with pytest.raises(CaseError, match="out_of_range: load is not an axis of the table"):
        parse_spec(_raw({"load": "clamp"}))
    with pytest.raises(CaseError, match="out_of_range must be one of"):
        parse_spec(_raw(3))


def test_clamp_gives_the_end_node_and_says_so(clamped, capsys):
    """Lateral displacement 5 mm on a table of 2..4 mm clamped: both wheels have the
    exact solve at 4 mm (the batch's first point: ``railcontact solve`` bit for bit), status
    ok, a message naming the clamped input; a creepage outside its axis (policy status)
    stays out of range; NaN and +-inf are never clamped."""
    spec, out = clamped
    table = ContactTable.open(out)
    assert table.out_of_range == {"lateral_displacement": "clamp", "creepage_y": "status"}
    sol = solve(spec.case_at_values({"lateral_displacement": 0.004, "creepage_y": 0.0}))
    exact = {s: sum(p.normal.force for p in sol.patches if p.geometry.side == s)
             for s in ("left", "right")}
    r = table({"lateral_displacement": 0.005, "creepage_y": 0.0}, "left")
    assert r.clamped == ("lateral_displacement",) and r.status == 0
    assert r["normal_force"] == exact["left"]
    assert table({"lateral_displacement": 0.004, "creepage_y": 0.0}, "left").clamped == ()
    step = TableContact(table)
    res = step.solve(Pose(0.005), loads=(80e3, 80e3), creepages=((0, 0, 0), (0, 0, 0)))
    for w in res.wheels:
        assert w.status == 0 and w.normal_force == exact[w.side]
        assert "lateral_displacement = 0.005 m clamped to 0.004" in w.message
    res = step.solve(Pose(0.001), loads=(80e3, 80e3), creepages=((0, 0, 0), (0, 0, 0)))
    low = solve(spec.case_at_values({"lateral_displacement": 0.002, "creepage_y": 0.0}))
    assert res.left.normal_force == sum(p.normal.force for p in low.patches
                                        if p.geometry.side == "left")
    # the creepage axis keeps the default: out of range, zero forces
    res = step.solve(Pose(0.005), loads=(80e3, 80e3),
                     creepages=((0, 0.002, 0), (0, -0.002, 0)))
    assert (res.left.status, res.left.normal_force) == (3, 0.0)
    assert "creepage_y = 0.002 1 is outside the table [0, 0.001]" in res.left.message
    for bad in (float("nan"), float("inf"), -float("inf")):  # (inf read ok at the end node)
        with pytest.raises(RailContactError, match=f"lateral_displacement = {bad:g} m is "
                           "outside the table"):
            table({"lateral_displacement": bad, "creepage_y": 0.0}, "left")
    from railcontact.cli import main

    assert main(["table", "show", str(out)]) == 0
    text = capsys.readouterr().out
    assert "from 0.002 to 0.004; out of range: clamp" in text
    assert "from 0 to 0.001; out of range: status" in text


def test_status_is_the_default_and_the_store_policy_can_be_overridden(clamped, tmp_path):
    """``out_of_range="status"`` at opening overrides the store's clamp: an error in
    Python, status 3 with zero outputs in a step; a build into the store with another
    policy (the same table) records the new one."""
    spec, out = clamped
    table = ContactTable.open(out, out_of_range="status")
    with pytest.raises(RailContactError, match="lateral_displacement = 0.005 m is outside "
                       r"the table \[0.002, 0.004\]"):
        table({"lateral_displacement": 0.005, "creepage_y": 0.0}, "left")
    step = TableContact.open(out, out_of_range={"lateral_displacement": "status"})
    res = step.solve(Pose(0.005), loads=(80e3, 80e3), creepages=((0, 0, 0), (0, 0, 0)))
    assert [(w.status, w.normal_force) for w in res.wheels] == [(3, 0.0), (3, 0.0)]
    with pytest.raises(RailContactError, match="the policy must be one of"):
        ContactTable.open(out, out_of_range={"lateral_displacement": "wrap"})
    import shutil

    import zarr

    copy = tmp_path / "c.zarr"
    shutil.copytree(out, copy)
    Store(copy, parse_spec(_raw()))  # the same table, the default policy now
    assert json.loads(zarr.open_group(str(copy), mode="r").attrs["out_of_range"]) == {
        "lateral_displacement": "status", "creepage_y": "status"}
    assert ContactTable.open(copy).out_of_range["lateral_displacement"] == "status"
