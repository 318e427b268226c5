"""Geometry tables (``[table] kind = "geometry"``): the nodes against ``railcontact solve``
(roll, each patch's contact point, rolling radius and contact angle), the wheelset's roll
and vertical position against a contact found by brute force on the profiles, the
equivalent conicity of the table's rolling radius difference against
:func:`railcontact.geometry.conicity.equivalent_conicity`, bad specs, show and export."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

pytest.importorskip("xarray")
pytest.importorskip("zarr")

from _tables import build_here  # noqa: E402

from railcontact.cli import main  # noqa: E402
from railcontact.contact.wheelrail import build_geometry  # noqa: E402
from railcontact.errors import CaseError, RailContactError  # noqa: E402
from railcontact.geometry.conicity import equivalent_conicity  # noqa: E402
from railcontact.geometry.roll import first_contact_gap  # noqa: E402
from railcontact.geometry.track import SIDES, Pose  # noqa: E402
from railcontact.settings import Case  # noqa: E402
from railcontact.table import ContactTable, GeometryTable, parse_spec  # noqa: E402
from railcontact.table.geometry import PATCH, PATCHES, WHEEL, WHEELSET  # noqa: E402
from railcontact.table.store import create_store  # noqa: E402

CASE = {"name": "geometry", "material": {"young": 206e9, "poisson": 0.28},
        "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                     "inclination": 0.024994793618920156}}
APPROACH = 1e-4
"""[normal] penetration of the rigid tables [m]: at 4.5 mm the flange root is a second
patch 90 um above the first contact (two-point contact)."""
RIGID = {**CASE, "normal": {"penetration": APPROACH},
         "table": {"kind": "geometry", "roll": "rigid",
                   "lateral_displacement": {"values": [-0.006, 0.0, 0.002, 0.0045, 0.0065]},
                   "yaw": {"values": [0.0, 0.004]}}}


def _spec(raw):
    return parse_spec(json.loads(json.dumps(raw)))


@pytest.fixture(scope="module")
def rigid(tmp_path_factory):
    spec = _spec(RIGID)
    out = build_here(spec, tmp_path_factory.mktemp("geometry") / "rigid.zarr")
    return spec, out, GeometryTable.open(out)


def _toml(case: dict) -> str:
    """A case file's TOML (tables of numbers, strings and lists of numbers: JSON's values
    are TOML's)."""
    lines = [f"{k} = {json.dumps(v)}" for k, v in case.items() if not isinstance(v, dict)]
    for k, v in case.items():
        if isinstance(v, dict):
            lines += [f"[{k}]", *(f"{a} = {json.dumps(b)}" for a, b in v.items())]
    return "\n".join(lines) + "\n"


def _solve(tmp_path, capsys, geometry: dict, normal: dict, **more) -> dict:
    """``railcontact solve CASE --json`` of both wheels (each patch at its rigid contact
    point unless ``geometry`` says otherwise)."""
    case = {**CASE, "geometry": {**CASE["geometry"], "patch_frame": "rigid", **geometry,
                                 "side": "both"}, "normal": normal, **more}
    path = tmp_path / "case.toml"
    path.write_text(_toml(case))
    capsys.readouterr()
    assert main(["solve", str(path), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_rigid_nodes_are_railcontact_solve(rigid, tmp_path, capsys):
    """At every node: the roll of ``railcontact solve`` with roll = 'rigid', and each
    wheel's patches (count, and each one's contact point, rolling radius, contact angle and
    profile coordinates, ordered from the field side) those it solves at the approach."""
    spec, _, table = rigid
    two_point = 0
    for index in np.ndindex(*spec.shape):
        y, yaw = (float(spec.axes[n][i]) for n, i in zip(spec.names, index, strict=True))
        got = table.node(index)
        assert got.status == {"left": 0, "right": 0}
        sol = _solve(tmp_path, capsys, {"lateral_displacement": y, "yaw": yaw, "roll": "rigid"},
                     {"penetration": APPROACH})
        assert got["wheelset_roll"] == pytest.approx(sol["roll"], abs=1e-12)
        for side in SIDES:
            patches = sorted((p for p in sol["patches"] if p["side"] == side),
                             key=lambda p: -p["wheel_profile_coordinate"])
            w = got.wheels[side]
            assert got.n_patches[side] == len(patches), (y, yaw, side)
            two_point += len(patches) == 2
            for k, p in enumerate(patches):
                assert w["patch_rolling_radius"][k] == pytest.approx(p["rolling_radius"],
                                                                     abs=1e-9)
                assert w["patch_contact_angle"][k] == pytest.approx(p["contact_angle"],
                                                                    abs=1e-9)
                assert w["patch_wheel_position"][k] == pytest.approx(
                    p["wheel_profile_coordinate"], abs=1e-9)
                assert w["patch_rail_position"][k] == pytest.approx(
                    p["rail_profile_coordinate"], abs=1e-9)
                assert w["patch_contact_y"][k] == pytest.approx(p["contact_point"][1],
                                                                abs=1e-9)
                assert w["patch_contact_z"][k] == pytest.approx(p["contact_point"][2],
                                                                abs=1e-9)
            assert np.isnan(w["patch_rolling_radius"][len(patches):]).all()
            first = min(patches, key=lambda p: p["gap"])  # the first contact
            assert w["rolling_radius"] == pytest.approx(first["rolling_radius"], abs=1e-9)
            assert w["contact_angle"] == pytest.approx(first["contact_angle"], abs=1e-9)
        assert got["rolling_radius_difference"] == pytest.approx(
            got.wheels["left"]["rolling_radius"] - got.wheels["right"]["rolling_radius"],
            abs=1e-15)
    assert two_point >= 1  # the flange root's patch as a second patch


def _brute_force_gap(track, ws, pose: Pose, side: str, vertical: float
                     ) -> tuple[float, float, float]:
    """(least vertical gap [m], rolling radius [m], track Y [m]) of the wheel ``side`` with
    its wheelset at ``pose`` (no yaw) and ``vertical`` [m], from the profiles sampled
    densely: the wheel's lowest line rolled about the wheelset centre (at the nominal
    radius above the rail tops) above the placed rail."""
    sgn = SIDES[side]
    phi, u0 = sgn * pose.roll, sgn * pose.lateral
    rail = track.side_rail
    lo, hi = ws.wheel.bounds

    def gaps(s):
        r = ws.radius + ws.wheel.height(s)
        eta = ws.axial_position(s)
        u = math.cos(phi) * eta + math.sin(phi) * r + u0
        z = math.sin(phi) * eta - math.cos(phi) * r + ws.radius + vertical
        inside = (u > rail.bounds[0]) & (u < rail.bounds[1])
        g = np.where(inside, z - rail.height(np.clip(u, *rail.bounds)), np.inf)
        return g, r, u

    s = np.linspace(lo, hi, 40001)
    k = int(np.argmin(gaps(s)[0]))
    s = np.linspace(s[max(k - 2, 0)], s[min(k + 2, s.size - 1)], 4001)
    g, r, u = gaps(s)
    k = int(np.argmin(g))
    return float(g[k]), float(r[k]), float(sgn * u[k])


def test_roll_and_vertical_put_both_wheels_on_their_rails(rigid):
    """At the nodes without yaw: with the table's roll and vertical position, both wheels'
    least gaps (found by brute force on the profiles) are minus the approach, at the
    table's rolling radius and contact position."""
    spec, _, table = rigid
    track, ws, _ = build_geometry(Case.from_dict(spec.case).geometry)
    for i, y in enumerate(spec.axes["lateral_displacement"]):
        got = table.node((i, 0))
        pose = Pose(float(y), 0.0, got["wheelset_roll"])
        for side in SIDES:
            g, r, cy = _brute_force_gap(track, ws, pose, side, got["wheelset_vertical"])
            # the search samples the wheel's trace 23 um apart: on a 67 deg flange
            # (g'' ~ 1e3 /m) its least gap is within g'' h^2 / 8 ~ 0.1 um
            assert g == pytest.approx(-APPROACH, abs=1e-7), (y, side)
            assert r == pytest.approx(got.wheels[side]["rolling_radius"], abs=1e-6)
            assert cy == pytest.approx(got.wheels[side]["contact_y"], abs=2e-5)


def test_equal_loads_nodes_are_railcontact_solve(tmp_path, capsys):
    """roll = 'equal-loads': the roll of ``railcontact solve``, and the vertical position
    at which each wheel has the vertical approach of its solved patches (both wheels: the
    same position)."""
    raw = {**CASE, "grid": {"dx": 0.001, "dy": 0.001}, "normal": {"load": 80e3},
           "table": {"kind": "geometry", "roll": "equal-loads",
                     "lateral_displacement": {"values": [0.0, 0.003]}}}
    spec = _spec(raw)
    table = GeometryTable.open(build_here(spec, tmp_path / "eq.zarr"))
    track, ws, _ = build_geometry(Case.from_dict(spec.case).geometry)
    for i, y in enumerate(spec.axes["lateral_displacement"]):
        got = table.node((i,))
        sol = _solve(tmp_path, capsys, {"lateral_displacement": float(y),
                                        "roll": "equal-loads", "patch_frame": "reference"},
                     {"load": 80e3}, grid=raw["grid"])  # (the table's case's frame)
        assert got["wheelset_roll"] == pytest.approx(sol["roll"], abs=1e-12)
        pose = Pose(float(y), 0.0, sol["roll"])
        for side in SIDES:
            p = min((p for p in sol["patches"] if p["side"] == side), key=lambda p: p["gap"])
            approach = p["normal"]["penetration"] / math.cos(p["contact_angle"]) + p["gap"]
            assert got.wheels[side]["approach"] == pytest.approx(approach, rel=1e-9)
            v = -(first_contact_gap(track, ws, pose, side) + approach)
            # both wheels, to the roll's tolerance (1e-8 rad x ~1.5 m/rad)
            assert got["wheelset_vertical"] == pytest.approx(v, abs=2e-8)


def _conicity_table(tmp_path, nodes: int, amplitude: float) -> GeometryTable:
    raw = {**CASE, "table": {"kind": "geometry", "roll": {"values": [0.0]},
                             "lateral_displacement": [-amplitude, amplitude, nodes]}}
    return GeometryTable.open(build_here(_spec(raw), tmp_path / f"c{nodes}.zarr"))


def test_equivalent_conicity_of_the_table(tmp_path):
    """The harmonic linearisation of the table's delta_r(y) (roll 0, first contacts) is
    ``equivalent_conicity`` from the profiles: exactly on the same nodes, and within 0.1 %
    of it sampled 1601 times from a table of 0.25 mm between nodes (delta_r(y) of S1002 on
    60E1 has kinks where the contact moves along the profiles, so the interpolation error
    does not fall steadily with the spacing: 9, 17, 33, 65 nodes give 0.12, 0.04, 0.07,
    0.03 % at 4 mm)."""
    a = 0.004
    track, ws, _ = build_geometry(Case.from_dict({**CASE, "normal": {"penetration": 0.0}})
                                  .geometry)
    table = _conicity_table(tmp_path, 41, a)
    assert table.equivalent_conicity(a, roll=0.0) == pytest.approx(
        equivalent_conicity(track, ws, a, samples=41), rel=1e-12)
    direct = equivalent_conicity(track, ws, a, samples=1601)
    assert _conicity_table(tmp_path, 33, a).equivalent_conicity(a, roll=0.0) == pytest.approx(
        direct, rel=1e-3)
    assert 0.05 < direct < 0.5  # S1002 on 60E1 at 1:40, 4 mm: a wheel-rail conicity
    with pytest.raises(RailContactError, match="outside the table"):
        table.equivalent_conicity(2 * a, roll=0.0)


@pytest.mark.parametrize(("change", "match"), [
    ({"table": {"kind": "bogus", "lateral_displacement": [0, 0.001, 2]}},
     "kind must be one of contact, geometry, creep"),
    ({"table": {"kind": "geometry", "creepage_y": [0, 0.001, 2]}},
     "unknown key creepage_y"),
    ({"table": {"kind": "geometry", "roll": "floating", "lateral_displacement": [0, 0.001, 2]}},
     "roll must be one of 'rigid', 'equal-loads' or an axis"),
    ({"table": {"kind": "geometry", "roll": "rigid"}}, "needs at least one axis"),
    ({"table": {"kind": "geometry", "roll": 0.001, "yaw": [0, 0.001, 2]}},
     "one roll angle for the whole table is \\[geometry\\] roll"),
    ({"table": {"kind": "geometry", "yaw": [0.0, 0.2, 2]}}, "small angle"),
    ({"table": {"kind": "geometry", "roll": [0.001, -0.001, 2]}}, "start 0.001 > stop"),
    ({"tangential": {"creepage": [0, 0, 0], "friction": 0.3}}, r"\[tangential\]: a geometry"),
    ({"geometry": {**CASE["geometry"], "side": "left"}}, "takes both wheels"),
    ({"normal": {"load": 80e3}}, "takes \\[normal\\] penetration"),
    ({"table": {"kind": "geometry", "roll": "equal-loads", "lateral_displacement": [0, 0.001, 2]},
      "normal": {"penetration": 1e-4}}, "needs \\[normal\\] load"),
])
def test_bad_specs_are_refused(change, match):
    raw = {**RIGID, **change}
    with pytest.raises(CaseError, match=match):
        _spec(raw)


def test_kind_default_and_other_tables(rigid, tmp_path):
    """An explicit ``kind = "contact"`` is the default's table; a ContactTable does not
    open a geometry table, nor a GeometryTable a creep-force one."""
    force = {**CASE, "normal": {"load": 80e3}, "table": {"lateral_displacement": [0, 0.001, 2]}}
    plain = _spec(force)
    explicit = _spec({**force, "table": {**force["table"], "kind": "contact"}})
    assert explicit.identity() == plain.identity() and "kind" not in plain.identity()
    assert _spec(RIGID).identity()["kind"] == "geometry"
    _, out, _ = rigid
    with pytest.raises(RailContactError, match="is a geometry table"):
        ContactTable.open(out)
    create_store(tmp_path / "force.zarr", plain)
    with pytest.raises(RailContactError, match="not a geometry table"):
        GeometryTable.open(tmp_path / "force.zarr")
    assert main(["table", "refine", str(out)]) == 2


def test_lookup_between_nodes_and_policy(rigid):
    """Multilinear between nodes (a node's values exactly); a patch only where every node
    used has it; outside an axis an error naming it."""
    spec, out, table = rigid
    a, b = table.node((1, 0)), table.node((2, 0))
    mid = table(lateral_displacement=0.001, yaw=0.0)
    for q in WHEELSET:
        assert mid[q.name] == pytest.approx(0.5 * (a[q.name] + b[q.name]), rel=1e-12)
    two = table.node((3, 0))  # 4.5 mm: two-point contact on the left wheel
    assert two.n_patches["left"] == 2
    between = table(lateral_displacement=0.004, yaw=0.0)
    assert between.n_patches["left"] == 1 and np.isnan(
        between.wheels["left"]["patch_rolling_radius"][1])
    with pytest.raises(RailContactError, match="yaw = 0.01 rad is outside the table"):
        table(lateral_displacement=0.0, yaw=0.01)
    clamping = GeometryTable.open(out, out_of_range="clamp")
    assert clamping(lateral_displacement=1.0, yaw=0.0).clamped == ("lateral_displacement",)
    for bad in (float("nan"), float("inf"), -float("inf")):  # never clamped
        with pytest.raises(RailContactError, match=f"lateral_displacement = {bad:g} m is "
                           "outside the table"):
            clamping(lateral_displacement=bad, yaw=0.0)


def test_show_and_export(rigid, tmp_path, capsys):
    spec, out, table = rigid
    capsys.readouterr()
    assert main(["table", "show", str(out), "--plot", str(tmp_path / "g.png")]) == 0
    text = capsys.readouterr().out
    assert "geometry table: roll rigid" in text and "rolling_radius_difference" in text
    assert (tmp_path / "g.png").stat().st_size > 0
    path = tmp_path / "g.csv"
    assert main(["table", "export", str(out), str(path)]) == 0
    rows = list(csv.DictReader(path.open()))
    assert len(rows) == spec.size * 2
    for row in rows:
        index = tuple(int(np.flatnonzero(spec.axes[n] == float(row[n]))[0])
                      for n in spec.names)
        node = table.node(index)
        for q in WHEELSET:
            assert float(row[q.name]) == node[q.name]
        for q in WHEEL:
            assert float(row[q.name]) == node.wheels[row["side"]][q.name]
        for q in PATCH:
            for k in range(PATCHES):
                want = node.wheels[row["side"]][q.name][k]
                got = float(row[f"{q.name}_{k + 1}"])
                assert got == want or (math.isnan(got) and math.isnan(want))
        assert int(row["n_patches"]) == node.n_patches[row["side"]]
    import xarray as xr

    nc = tmp_path / "g.nc"
    assert main(["table", "export", str(out), str(nc)]) == 0
    with xr.open_dataset(nc) as ds:
        assert ds["patch_contact_angle"].dims == (*spec.names, "side", "patch")
        assert ds["rolling_radius_difference"].dims == tuple(spec.names)
        assert ds["patch_contact_angle"].attrs["units"] == "rad"
        got = ds["patch_contact_angle"].values[3, 0, 0, 1]  # 4.5 mm, left: the flange root
        assert got == table.node((3, 0)).wheels["left"]["patch_contact_angle"][1]
