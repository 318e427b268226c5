"""A friction axis in contact tables (``[table] friction``): each point solved with the
case's ``[tangential] friction`` set to the axis value.

The truth at the nodes is ``railcontact solve`` of the same case with that friction; between
the nodes the exact solution at the middle friction; in full slip (all elements sliding)
Coulomb's law, ``|F| = mu N``. The table is built in this process on a 1 mm grid, a
longitudinal creepage in partial slip and one in full slip, friction 0.2 and 0.4.
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("xarray")
pytest.importorskip("zarr")

from _tables import build_here  # noqa: E402

from railcontact import solve  # noqa: E402
from railcontact.cli import main  # noqa: E402
from railcontact.errors import CaseError, RailContactError  # noqa: E402
from railcontact.geometry.track import Pose  # noqa: E402
from railcontact.settings import ContactSettings  # noqa: E402
from railcontact.table import ContactTable, TableContact, parse_spec  # noqa: E402
from railcontact.table.store import open_dataset  # noqa: E402

LOAD = 80e3
XI = (0.001, 0.02)  # partial slip, full slip
MU = (0.2, 0.4)
RAW = {"name": "friction", "material": {"young": 206e9, "poisson": 0.28},
       "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                    "inclination": 0.024994793618920156},
       "grid": {"dx": 0.001, "dy": 0.001},
       "normal": {"load": LOAD, "tolerance": 1e-13, "max_iterations": 2000},
       "tangential": {"creepage": [0.0, 0.0, 0.0], "friction": 0.3, "tolerance": 1e-13,
                      "max_iterations": 5000},
       "table": {"creepage_x": {"values": list(XI)}, "friction": list(MU)}}


def _raw(**table) -> dict:
    out = {k: dict(v) if isinstance(v, dict) else v for k, v in RAW.items()}
    out["table"] = table
    return out


def _build(spec, out: Path) -> Path:
    """The table of ``spec`` built in this process (through the build's point solve)."""
    return build_here(spec, out)


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    spec = parse_spec(_raw(**RAW["table"]))
    return spec, _build(spec, tmp_path_factory.mktemp("friction") / "t.zarr")


def _wheel(sol, side: str) -> dict[str, float]:
    """The solver's per-wheel quantities (contact frame of the side, as the table)."""
    ps = [p for p in sol.patches if p.geometry.side == side]
    sgn = 1.0 if side == "left" else -1.0
    return {"normal_force": sum(p.normal.force for p in ps),
            "creep_force_x": sum(p.tangential.force[0] for p in ps),
            "creep_force_y": sgn * sum(p.tangential.force[1] for p in ps),
            "area": sum(p.normal.area for p in ps)}


def test_the_spec_takes_a_friction_axis_with_the_cases_rules():
    spec = parse_spec(_raw(friction={"values": [0.2, 0.4]}))
    assert list(spec.axes["friction"]) == [0.2, 0.4]
    assert spec.case_at((1,))["tangential"]["friction"] == 0.4
    for bad, words in (([0.0, 0.4], "above 0"), ([0.4, 0.2], "strictly increasing"),
                       ([0.2, 11.0], "[table] friction")):
        with pytest.raises(CaseError, match=words.replace("[", r"\[").replace("]", r"\]")):
            parse_spec(_raw(friction={"values": bad}))
    raw = _raw(friction=[0.2, 0.4])
    del raw["tangential"]
    with pytest.raises(CaseError, match="needs a \\[tangential\\]"):
        parse_spec(raw)


def test_nodes_equal_railcontact_solve_with_that_friction(table):
    spec, out = table
    ds = open_dataset(out)
    assert ds.sizes["friction"] == 2 and ds["friction"].attrs["units"] == "1"
    assert (ds["status"].values == 0).all()
    for index in np.ndindex(*spec.shape):
        case = spec.case_at(index)
        assert case["tangential"]["friction"] == MU[index[1]]
        sol = solve(case)  # railcontact solve: both wheels, cold, that friction
        for side in spec.sides:
            for name, value in _wheel(sol, side).items():
                got = float(ds[name].values[(*index, spec.sides.index(side))])
                assert got == pytest.approx(value, rel=1e-9, abs=1e-9 * abs(value) + 1e-12), \
                    (index, side, name)


def test_full_slip_creep_force_is_mu_n_and_scales_with_mu(table):
    """At xi = 0.02 every element slides: |F| = mu N (Coulomb) at both nodes, so that the
    force doubles from mu = 0.2 to 0.4, and linear interpolation in mu is exact there."""
    _, out = table
    t = ContactTable.open(out)
    for mu in (*MU, 0.3):
        r = t({"creepage_x": XI[1], "friction": mu}, "left")
        assert r.status == 0
        if mu in MU:
            assert r["slip_area_ratio"] == 1.0
        f = math.hypot(r["creep_force_x"], r["creep_force_y"])
        assert f == pytest.approx(mu * r["normal_force"], rel=1e-3), mu


def test_mid_friction_lies_between_the_nodes_as_the_exact_solve(table):
    """In partial slip the creep force grows with mu (the adhesion area grows): the table
    at mu = 0.3 lies between its nodes, and so does the exact solve at mu = 0.3, within
    the nodes' difference of it."""
    spec, out = table
    t = ContactTable.open(out)
    lo, mid, hi = (abs(t({"creepage_x": XI[0], "friction": mu}, "left")["creep_force_x"])
                   for mu in (0.2, 0.3, 0.4))
    assert lo < mid < hi and hi - lo > 0.1 * hi
    exact = abs(_wheel(solve(spec.case_at_values({"creepage_x": XI[0], "friction": 0.3})),
                       "left")["creep_force_x"])
    assert lo < exact < hi
    assert abs(mid - exact) < 0.5 * (hi - lo)


def test_table_step_looks_each_wheel_up_at_its_own_friction(table, tmp_path):
    spec, out = table
    t = ContactTable.open(out)
    step = TableContact(t, settings=ContactSettings(friction=0.4))
    creep = ((XI[0], 0.0, 0.0), (XI[0], 0.0, 0.0))
    res = step.solve(Pose(0.0, 0.0), loads=(LOAD, LOAD), creepages=creep,
                     friction=(0.2, 0.4))
    for wheel, k in ((res.left, 0), (res.right, 1)):
        node = t.node((0, k), wheel.side)
        assert wheel.status == 0
        assert wheel.creep_force[0] == node["creep_force_x"]
        assert wheel.normal_force == node["normal_force"]
    # without friction: settings.friction (0.4) on both wheels
    res = step.solve(Pose(0.0, 0.0), loads=(LOAD, LOAD), creepages=creep)
    assert res.left.creep_force[0] == t.node((0, 1), "left")["creep_force_x"]
    mid = step.solve(Pose(0.0, 0.0), loads=(LOAD, LOAD), creepages=creep,
                     friction=(0.3, 0.3)).left.creep_force[0]
    assert mid == t({"creepage_x": XI[0], "friction": 0.3}, "left")["creep_force_x"]
    # outside the axis: its policy (status by default; clamp when asked)
    res = step.solve(Pose(0.0, 0.0), loads=(LOAD, LOAD), creepages=creep,
                     friction=(0.5, 0.3))
    assert res.left.status == 3 and "friction = 0.5" in res.left.message
    assert res.left.normal_force == 0.0 and res.right.status == 0
    clamp = TableContact.open(out, out_of_range={"friction": "clamp"})
    res = clamp.solve(Pose(0.0, 0.0), loads=(LOAD, LOAD), creepages=creep,
                      friction=(0.5, 0.3))
    assert res.left.status == 0 and "friction = 0.5 1 clamped to 0.4" in res.left.message
    assert res.left.creep_force[0] == t.node((0, 1), "left")["creep_force_x"]
    for bad in ((0.0, 0.3), (0.3,), (math.nan, 0.3)):
        with pytest.raises(RailContactError, match="friction"):
            step.solve(Pose(0.0, 0.0), loads=(LOAD, LOAD), creepages=creep, friction=bad)


def test_a_table_without_a_friction_axis_refuses_a_friction_per_step(tmp_path):
    spec = parse_spec(_raw(creepage_x={"values": [XI[1]]}))
    step = TableContact.open(_build(spec, tmp_path / "one.zarr"))
    creep = ((XI[1], 0.0, 0.0), (XI[1], 0.0, 0.0))
    res = step.solve(Pose(0.0, 0.0), loads=(LOAD, LOAD), creepages=creep)
    assert res.left.status == 0  # the table's own friction, 0.3: full slip
    assert math.hypot(*res.left.creep_force) == pytest.approx(0.3 * res.left.normal_force,
                                                              rel=1e-3)
    with pytest.raises(RailContactError, match=r"no friction axis \(\[table\] friction"):
        step.solve(Pose(0.0, 0.0), loads=(LOAD, LOAD), creepages=creep, friction=(0.3, 0.3))
    # the FMU: inputs <= 0 the table's own friction; an input above 0 discards the step
    s = _slave(tmp_path, table_file=str(tmp_path / "one.zarr"))
    for k, v in {"load_left": LOAD, "load_right": LOAD, "xi_left": XI[1],
                 "xi_right": XI[1]}.items():
        s[k] = v
    assert s.exit_initialization() == 0, s.pop_log()
    assert s["creep_force_x_left"] == res.left.creep_force[0]
    s["friction_left"] = 0.3
    s.control[:] = (0.0, 1e-3, 0.0)
    assert s.do_step() == 2  # fmi2Discard
    assert "no friction axis" in s.pop_log() and s["status_left"] == 3


def _slave(resources: Path, **parameters):
    """The FMU's slave (fmu_src/slave.py, which the FMU holds as ``<package>/_fmu_slave.py``)
    in this process, in table mode."""
    path = Path(__file__).resolve().parents[1] / "fmu_src" / "slave.py"
    spec = importlib.util.spec_from_file_location("railcontact._fmu_slave", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    s = module.Slave(str(resources), "friction")
    s["contact_model"] = "table"
    for k, v in parameters.items():
        s[k] = v
    return s


def test_fmu_table_mode_takes_the_friction_inputs(table, tmp_path):
    """friction_left/right > 0: each wheel's own coefficient on the friction axis; <= 0:
    the parameter friction; a parameter outside the axis is an error at initialisation."""
    _, out = table
    t = ContactTable.open(out)
    s = _slave(tmp_path, table_file=str(out), friction=0.4)
    inputs = {"load_left": LOAD, "load_right": LOAD, "xi_left": XI[0], "xi_right": XI[0],
              "friction_left": 0.2, "friction_right": 0.0}
    for k, v in inputs.items():
        s[k] = v
    assert s.exit_initialization() == 0, s.pop_log()
    assert s["creep_force_x_left"] == t.node((0, 0), "left")["creep_force_x"]
    assert s["creep_force_x_right"] == t.node((0, 1), "right")["creep_force_x"]
    assert s["status_left"] == 0 and s["status_right"] == 0
    bad = _slave(tmp_path, table_file=str(out), friction=0.6)
    assert bad.exit_initialization() == 3
    assert "parameter friction = 0.6 is outside the friction axis [0.2, 0.4]" in bad.pop_log()


def test_show_check_and_export_read_the_friction_axis(table, tmp_path, capsys):
    """``table show`` lists the axis; ``table check`` scales the creep force error by each
    state's own mu; ``table export`` writes it as a column."""
    from railcontact.table.check import read_check

    _, out = table
    assert main(["table", "show", str(out)]) == 0
    assert "friction" in capsys.readouterr().out
    assert main(["table", "check", str(out), "2", "--workers", "0"]) == 0
    chk = read_check(out)
    mu = chk.states[:, chk.names.index("friction")]
    assert np.all((mu > 0.2) & (mu < 0.4))
    assert np.array_equal(chk.state_friction(), mu)
    for i in range(chk.size):
        ex = chk.exact[i, 0]
        got = ContactTable.open(out)(chk.point(i), "left")
        scale = max(abs(ex[0]), chk.load[i])
        want = math.hypot(got["creep_force_x"] - ex[1], got["creep_force_y"] - ex[2]) / (
            mu[i] * scale)
        assert chk.errors["creep_force"][i, 0] == pytest.approx(want, rel=1e-12, abs=1e-15)
    csv = tmp_path / "t.csv"
    assert main(["table", "export", str(out), str(csv)]) == 0
    assert csv.read_text().splitlines()[0].startswith("creepage_x,friction,side")


def test_refine_splits_the_friction_axis_and_its_new_nodes_are_railcontact_solve(
        table, tmp_path, capsys):
    """``table refine --axes friction`` on a copy of the checked table: the friction axis
    gains its middle node, which equals ``railcontact solve`` at that friction."""
    import shutil

    spec, out = table
    copy = tmp_path / "r.zarr"
    shutil.copytree(out, copy)
    if not (copy / "check").exists():
        assert main(["table", "check", str(copy), "2", "--workers", "0"]) == 0
    assert main(["table", "refine", str(copy), "--axes", "friction", "--target",
                 "creep_force=1e-9", "--workers", "1", "--quiet"]) == 0
    capsys.readouterr()
    t = ContactTable.open(copy)
    mu = t.axes["friction"]
    assert list(mu) == pytest.approx([0.2, 0.3, 0.4], rel=1e-15)
    assert list(t.axes["creepage_x"]) == list(XI)
    for k, xi in enumerate(XI):
        sol = solve(spec.case_at_values({"creepage_x": xi, "friction": float(mu[1])}))
        for side in spec.sides:
            node = t.node((k, 1), side)
            for name, value in _wheel(sol, side).items():
                assert node[name] == pytest.approx(value, rel=1e-9,
                                                   abs=1e-9 * abs(value) + 1e-12), (k, side)
