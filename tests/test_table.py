"""Contact tables: built on a 2-process Dask LocalCluster shared by the module's
tests, on a coarse grid (2 mm elements) so that a point solves in milliseconds.

The truth for the table is the exact solver itself, ``railcontact solve`` at each node:
the table must hold what the solver gives there, whatever the batching, the warm starts,
the workers, the resumes. The warm start changes only the solver's path, so with tight
tolerances (1e-13) a warm-started node equals the cold ``railcontact solve`` to 1e-9; with
the usual tolerances they differ by up to those tolerances (docs/tables.md).
"""

from __future__ import annotations

import json
import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")
pytest.importorskip("xarray")
pytest.importorskip("zarr")

from railcontact import solve  # noqa: E402
from railcontact.cli import main  # noqa: E402
from railcontact.errors import RailContactError  # noqa: E402
from railcontact.table import ContactTable, load_spec  # noqa: E402
from railcontact.table.store import open_dataset  # noqa: E402

SPEC = """
name = "table_test"
[material]
young = 206e9
poisson = 0.28
[geometry]
type = "wheel-rail"
wheel = "S1002"
rail = "60E1"
inclination = 0.024994793618920156
[grid]
dx = 0.002
dy = 0.002
[normal]
load = 80e3
estimate = "hertz"
tolerance = 1e-13
max_iterations = 2000
[tangential]
creepage = [0.0, 0.0, 0.0]
friction = 0.3
tolerance = 1e-13
max_iterations = 5000
[table]
lateral_displacement = [-0.002, 0.002, 3]
creepage_y = [0.0, 0.002, 2]
load = [60e3, 80e3, 2]
"""


@pytest.fixture(scope="module")
def scheduler():
    from distributed import LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=":0")
    yield cluster.scheduler_address
    cluster.close()


@pytest.fixture(scope="module")
def built(tmp_path_factory, scheduler):
    d = tmp_path_factory.mktemp("table")
    spec = d / "spec.toml"
    spec.write_text(SPEC)
    out = d / "t.zarr"
    assert main(["table", "build", str(spec), "-o", str(out), "--scheduler", scheduler,
                 "--quiet"]) == 0
    return spec, out


def _wheel(sol, side: str) -> dict[str, float]:
    """The solver's per-wheel quantities (contact frame of the side, as the table)."""
    ps = [p for p in sol.patches if p.geometry.side == side]
    sgn = 1.0 if side == "left" else -1.0
    main_p = max(ps, key=lambda p: p.normal.force)
    return {"normal_force": sum(p.normal.force for p in ps),
            "creep_force_x": sum(p.tangential.force[0] for p in ps),
            "creep_force_y": sgn * sum(p.tangential.force[1] for p in ps),
            "max_pressure": max(p.normal.max_pressure for p in ps),
            "area": sum(p.normal.area for p in ps),
            "contact_angle": main_p.geometry.contact_angle,
            "rolling_radius": main_p.geometry.rolling_radius}


def test_table_equals_solve_at_its_nodes(built):
    spec_path, out = built
    spec = load_spec(spec_path)
    ds = open_dataset(out)
    assert ds.sizes == {"lateral_displacement": 3, "creepage_y": 2, "load": 2, "side": 2,
                        "batch": 1}
    assert (ds["status"].values == 0).all() and ds["batch_done"].values.all()
    assert ds.attrs["railcontact_version"] and ds.attrs["complete"] == 1
    assert json.loads(ds.attrs["railcontact_table"])["case"] == spec.case
    assert ds["normal_force"].attrs["units"] == "N" and ds["normal_force"].attrs["long_name"]
    for index in np.ndindex(*spec.shape):
        sol = solve(spec.case_at(index))  # railcontact solve: both wheels, cold
        for side in ("left", "right"):
            exact = _wheel(sol, side)
            for name, value in exact.items():
                got = float(ds[name].values[(*index, spec.sides.index(side))])
                assert got == pytest.approx(value, rel=1e-9, abs=1e-9 * abs(value) + 1e-12), \
                    (index, side, name)
    # Coulomb: the creep force of a patch at most mu N (to the tangential tolerance)
    fx, fy, n = (ds[q].values for q in ("creep_force_x", "creep_force_y", "normal_force"))
    assert (np.hypot(fx, fy) <= 0.3 * n * (1 + 1e-9)).all()
    # not a trivial table: the axes change the forces
    fy = ds["creep_force_y"].sel(side="left").values
    assert np.abs(fy[:, 1, :]).min() > 1e3 and np.abs(fy[:, 0, :]).max() < 1.0


def test_rerun_computes_nothing(built, scheduler, capsys):
    spec, out = built
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*") if p.is_file()
              and not p.name.startswith(".")}
    assert main(["table", "build", str(spec), "-o", str(out), "--scheduler", scheduler,
                 "--quiet"]) == 0
    assert "computed 0 " in capsys.readouterr().out
    after = {p: p.stat().st_mtime_ns for p in before}
    assert before == after  # no chunk rewritten


def test_resume_completes_a_removed_batch(built, scheduler, tmp_path, capsys):
    """A client killed while writing batch (1, 0, 0): its data partly in the chunks (here:
    not computed, -1 and NaN, in some quantities, the others written), its done flag not
    set. The rerun computes that batch alone and the table equals the uninterrupted one."""
    import zarr

    spec, out = built
    cut = tmp_path / "cut.zarr"
    shutil.copytree(out, cut)
    g = zarr.open_group(str(cut), mode="r+")
    g["status"][1, 0] = -1
    g["normal_force"][1, 0] = np.nan
    done = g["batch_done"][...]
    done[1, 0, 0] = False
    g["batch_done"][...] = done
    ds = open_dataset(cut)
    assert (ds["status"].values[1, 0] == -1).all()
    assert np.isnan(ds["normal_force"].values[1, 0]).all()
    assert main(["table", "build", str(spec), "-o", str(cut), "--scheduler", scheduler,
                 "--quiet", "--resume"]) == 0
    assert "computed 2 " in capsys.readouterr().out  # the batch's 2 points, nothing else
    a, b = open_dataset(out), open_dataset(cut)
    for name in ("normal_force", "creep_force_y", "max_pressure", "status"):
        np.testing.assert_array_equal(a[name].values, b[name].values)
    assert b.attrs["complete"] == 1


def test_an_interrupted_build_keeps_what_finished_and_resumes_to_the_same_table(
        built, scheduler, tmp_path, capsys, monkeypatch):
    """Ctrl-C after the third finished batch of six: the build writes the batches that
    finished (exit status 130, the message says to resume), and --resume computes the
    others; the table equals the uninterrupted build value for value."""
    from railcontact.table import build

    spec, out = built
    cut = tmp_path / "cut.zarr"
    real, calls = build._messages, []

    def interrupted(*args):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(build, "_messages", interrupted)
    assert main(["table", "build", str(spec), "-o", str(cut), "--scheduler", scheduler,
                 "--quiet"]) == 130
    assert "rerun with --resume" in capsys.readouterr().err
    assert open_dataset(cut)["batch_done"].values.sum() == 2
    monkeypatch.setattr(build, "_messages", real)
    assert main(["table", "build", str(spec), "-o", str(cut), "--scheduler", scheduler,
                 "--quiet", "--resume"]) == 0
    assert "computed 8 " in capsys.readouterr().out
    a, b = open_dataset(out), open_dataset(cut)
    for name in ("normal_force", "creep_force_y", "max_pressure", "contact_angle", "status"):
        np.testing.assert_array_equal(a[name].values, b[name].values)


def test_interpolation_at_nodes_and_between(built):
    spec_path, out = built
    spec = load_spec(spec_path)
    table = ContactTable.open(out)
    for index in np.ndindex(*spec.shape):
        point = {n: float(spec.axes[n][i]) for n, i in zip(spec.names, index, strict=True)}
        for side in spec.sides:
            got, node = table(point, side), table.node(index, side)
            assert got.status == 0
            assert got.values == node.values  # exactly the node
    # between nodes: between the neighbours' values (linear along load at a node elsewhere)
    mid = table({"lateral_displacement": 0.0, "creepage_y": 0.002, "load": 70e3})
    lo, hi = table.node((1, 1, 0)), table.node((1, 1, 1))
    assert mid["normal_force"] == pytest.approx(0.5 * (lo["normal_force"] + hi["normal_force"]),
                                                rel=1e-12)


@pytest.mark.parametrize("point, match", [
    ({"lateral_displacement": 0.0025, "creepage_y": 0.0, "load": 70e3},
     "lateral_displacement = 0.0025 m is outside the table"),
    ({"lateral_displacement": 0.0, "creepage_y": 0.0, "load": 50e3}, "load = 50000 N is outside"),
    ({"lateral_displacement": 0.0, "creepage_y": 0.0}, "missing load"),
    ({"lateral_displacement": 0.0, "creepage_y": 0.0, "load": 7e4, "yaw": 0.0},
     "not axes of this table: yaw"),
    ({"lateral_displacement": float("nan"), "creepage_y": 0.0, "load": 7e4}, "outside"),
])
def test_outside_the_axes_is_an_error(built, point, match):
    table = ContactTable.open(built[1])
    with pytest.raises(RailContactError, match=match):
        table(point)


def test_cubic_needs_four_nodes(built):
    """Cubic interpolation on an axis of fewer than 4 nodes is an error where it is asked
    for: a table's call, and a TableContact's construction (else every step of a run
    would be out of range with zero forces)."""
    from railcontact.table.step import TableContact

    table = ContactTable.open(built[1])
    with pytest.raises(RailContactError, match="at least 4 nodes"):
        table({"lateral_displacement": 0.0, "creepage_y": 0.0, "load": 7e4}, method="cubic")
    with pytest.raises(RailContactError, match="at least 4 nodes"):
        TableContact(table, method="cubic")


def test_bad_input(built, tmp_path, capsys):
    spec, out = built
    text = Path(spec).read_text()
    cases = {
        "load = [80e3, 60e3, 2]": "start 80000 > stop 60000",
        "load = [60e3, 80e3, 0]": "count must be at least 1",
        "speed = [1.0, 2.0, 2]": "unknown axis speed",
    }
    for k, (line, match) in enumerate(cases.items()):
        bad = tmp_path / f"bad{k}.toml"
        bad.write_text(text.replace("load = [60e3, 80e3, 2]", line))
        assert main(["table", "build", str(bad), "-o", str(tmp_path / "b.zarr"),
                     "--quiet"]) == 2
        assert match in capsys.readouterr().err
    # another case into the same store: an error, the store untouched
    other = tmp_path / "other.toml"
    other.write_text(text.replace("friction = 0.3", "friction = 0.25"))
    assert main(["table", "build", str(other), "-o", str(out), "--quiet"]) == 2
    assert "another case or grid (differs in: case tangential)" in capsys.readouterr().err
    # an unreachable scheduler: a clear error, and no store left behind
    new = tmp_path / "new.zarr"
    assert main(["table", "build", str(spec), "-o", str(new), "--quiet",
                 "--scheduler", "tcp://127.0.0.1:9"]) == 2
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in capsys.readouterr().err
    assert not new.exists()
    assert main(["table", "build", str(spec), "-o", str(new), "--resume", "--quiet"]) == 2
    assert "no table at" in capsys.readouterr().err


def test_show(built, tmp_path, capsys):
    _, out = built
    plot = tmp_path / "t.png"
    assert main(["table", "show", str(out), "--plot", str(plot)]) == 0
    text = capsys.readouterr().out
    assert "batches done 6/6" in text and "left   ok 12" in text and "right  ok 12" in text
    assert "lateral_displacement   [m]     3 from -0.002 to 0.002" in text
    assert plot.stat().st_size > 1000


def test_table_mode_step_gives_the_fmu_outputs_of_the_nodes(built):
    """The FMU's table mode (railcontact.table.step.TableContact): a wheelset step at a
    node returns that node's values for each wheel in the FMU's result record (the right
    wheel's lateral creepage in its contact frame is the table's with the sign changed);
    outside the table: status out of range, zero outputs, a message naming the input."""
    from railcontact.fmu.variables import APPENDED_OUTPUTS, OUTPUTS
    from railcontact.geometry.track import Pose
    from railcontact.table.step import TableContact

    tc = TableContact.open(built[1])
    table = tc.table
    index = (2, 1, 0)
    y, eta, q = (float(table.axes[n][i]) for n, i in zip(table.axes, index, strict=True))
    res = tc.solve(Pose(y, 0.0, 0.0), loads=(q, q), creepages=((0.0, eta, 0.0),
                                                               (0.0, -eta, 0.0)))
    assert res.status == 0
    outputs = {v.name: v.value(res) for v in OUTPUTS + APPENDED_OUTPUTS}
    for side in ("left", "right"):
        node = table.node(index, side)
        assert outputs[f"normal_force_{side}"] == node["normal_force"]
        assert outputs[f"creep_force_y_{side}"] == node["creep_force_y"]
        assert outputs[f"force_lateral_{side}"] == node["force_lateral"]
        assert outputs[f"contact_angle_{side}"] == node["contact_angle"]
        assert outputs[f"contact_lateral_position_{side}"] == node["contact_y"]
        assert outputs[f"status_{side}"] == 0
        # the creep forces' power per unit speed from the node's forces and the creepages
        w = getattr(res, side)
        assert w.frictional_power_per_speed == pytest.approx(
            node["creep_force_y"] * w.creepages[0][1], rel=1e-12) and w.creepages[0][1] != 0
        assert w.frictional_power_per_speed < 0  # (dissipated)
    # the two wheels push the wheelset opposite ways along the creepage
    assert outputs["creep_force_y_left"] * outputs["creep_force_y_right"] < 0
    # outside the load axis on the right wheel: that wheel out of range, the left solved
    res = tc.solve(Pose(y, 0.0, 0.0), loads=(q, 1.5 * q), creepages=((0.0, eta, 0.0),
                                                                     (0.0, -eta, 0.0)))
    assert (res.left.status, res.right.status, res.status) == (0, 3, 3)
    assert "load = 90000 N is outside the table [60000, 80000]" in res.right.message
    assert res.right.normal_force == 0.0
    # a yaw the table does not have (its case's yaw is 0): out of range
    res = tc.solve(Pose(y, 1e-3, 0.0), loads=(q, q), creepages=((0.0, eta, 0.0),) * 2)
    assert res.status == 3 and "no yaw axis" in res.left.message
    # kinematic creepages: the spin of a coned contact, which this table has no axis for
    from railcontact.timestep.wheelset import Kinematics

    res = tc.solve(Pose(y, 0.0, 0.0), loads=(q, q), kinematics=Kinematics(30.0))
    assert res.status == 3 and "no creepage_x axis" in res.left.message
    with pytest.raises(RailContactError, match="by wheel load"):
        tc.solve(Pose(y, 0.0, 0.0), vertical=-1e-4)


def test_failed_points_have_their_status(scheduler, tmp_path, capsys):
    """A BEM that stops after 2 iterations (not converged: values kept, status 1) and a
    wheelset 30 mm off centre (the wheel has climbed its flange: out of range, status 3,
    NaN values): recorded with their messages; no NaN without a status."""
    text = SPEC.replace("max_iterations = 2000", "max_iterations = 2").replace(
        'lateral_displacement = [-0.002, 0.002, 3]\ncreepage_y = [0.0, 0.002, 2]\n'
        'load = [60e3, 80e3, 2]', "lateral_displacement = { values = [0.0, 0.03] }")
    spec = tmp_path / "fail.toml"
    spec.write_text(text)
    out = tmp_path / "fail.zarr"
    assert main(["table", "build", str(spec), "-o", str(out), "--scheduler", scheduler,
                 "--quiet"]) == 0
    assert "4 point-wheel(s) not ok" in capsys.readouterr().out
    ds = open_dataset(out)
    status = ds["status"].values
    assert status.tolist() == [[1, 1], [3, 3]]
    f = ds["normal_force"].values
    assert np.isfinite(f[0]).all() and np.isnan(f[1]).all()
    for name in ("normal_force", "creep_force_y", "contact_angle", "max_pressure"):
        assert not (np.isnan(ds[name].values) & (status == 0)).any()
    assert main(["table", "show", str(out)]) == 0
    shown = capsys.readouterr().out
    assert "left   not converged 1, out of range 1" in shown
    assert "climbed its flange" in shown and "did not converge" in shown
    assert "WARNING: 4 point-wheel(s) failed (2 not converged, 2 out of range)" in shown
    from railcontact.table.interpolate import TableHolesWarning

    with pytest.warns(TableHolesWarning, match=re.escape(
            "4 point-wheel(s) failed (2 not converged, 2 out of range)")):
        table = ContactTable.open(out)
    assert table.failed == {"not converged": 2, "out of range": 2}
    with pytest.raises(RailContactError, match="outside the table"):
        table({"lateral_displacement": 0.031})
    r = table({"lateral_displacement": 0.01})
    assert r.status == 3 and math.isnan(r["normal_force"])


def test_cubic_follows_the_creep_curve_between_nodes(scheduler, tmp_path):
    """Along the lateral creepage (5 nodes, 0 .. 4e-3: from linear creep to full slip) the
    cubic spline stays within 1 % of mu Q of exact solves between the nodes where the creep
    curve bends, closer than the linear interpolation; at full slip the force is mu N."""
    text = SPEC.replace('lateral_displacement = [-0.002, 0.002, 3]\ncreepage_y = [0.0, 0.002, 2]'
                        '\nload = [60e3, 80e3, 2]', "creepage_y = [0.0, 0.004, 5]")
    text = text.replace("tolerance = 1e-13", "tolerance = 1e-6")
    spec_path = tmp_path / "curve.toml"
    spec_path.write_text(text)
    out = tmp_path / "curve.zarr"
    assert main(["table", "build", str(spec_path), "-o", str(out), "--scheduler", scheduler,
                 "--quiet"]) == 0
    from railcontact.table.solve import solve_point

    spec = load_spec(spec_path)
    table = ContactTable.open(out)
    node = table.node((4,), "left")
    assert abs(node["creep_force_y"]) == pytest.approx(0.3 * node["normal_force"], rel=1e-3)
    mu_q = 0.3 * 80e3
    for eta in (0.0005, 0.0015, 0.0025):
        exact, _ = solve_point(spec.case_at_values({"creepage_y": eta}), "left")
        lin = table({"creepage_y": eta}, "left")["creep_force_y"]
        cub = table({"creepage_y": eta}, "left", method="cubic")["creep_force_y"]
        e_lin, e_cub = abs(lin - exact.creep_force[1]), abs(cub - exact.creep_force[1])
        assert e_cub < 0.01 * mu_q and e_cub < e_lin, (eta, e_lin, e_cub)


@pytest.mark.parametrize("entry, match", [
    ("[-0.002, 0.002, 2.5]", "needs an integer count, got 2.5"),
    ("[0.002, 0.001]", "strictly increasing"),
    ("{ values = [0.0, 0.0] }", "strictly increasing"),
    ("[0.0, 0.0, 3]", "give count 1"),
    ("[0.0, 0.001, 1]", "count 1 needs start = stop"),
    ('["a", 0.001, 2]', "finite numbers"),
    ("{ value = [0.0] }", "takes only 'values'"),
])
def test_bad_axes(entry, match):
    from railcontact.errors import CaseError
    from railcontact.table import parse_spec
    from railcontact.table.spec import tomllib

    raw = tomllib.loads(SPEC.replace("lateral_displacement = [-0.002, 0.002, 3]",
                                     f"lateral_displacement = {entry}"))
    with pytest.raises(CaseError, match=match):
        parse_spec(raw)
    ok = tomllib.loads(SPEC.replace("lateral_displacement = [-0.002, 0.002, 3]",
                                    "lateral_displacement = [-0.002, 0.002, 3.0]"))
    assert parse_spec(ok).shape == (3, 2, 2)


@pytest.mark.parametrize("axis, entry, match", [
    ("creepage_y", "[0.0, 2000.0, 2]",
     r"\[table\] creepage_y must be >= -1000 and <= 1000, got 2000"),
    ("creepage_x", "{ values = [-1500.0, 0.0] }",
     r"\[table\] creepage_x must be .* got -1500"),
    ("spin", "[0.0, 1e4, 2]", r"\[table\] spin must be .* got 10000"),
    ("load", "[60e3, 2e8, 2]", r"\[table\] load \[N\] must be .* got 2e\+08"),
    ("yaw", "[-0.2, 0.2, 3]", r"\[table\] yaw \[rad\] must be >= -0.1 and <= 0.1, got -0.2"),
])
def test_axis_nodes_beyond_their_settings_bounds_are_refused(axis, entry, match):
    """A node beyond the bounds its setting takes in a case (creepages within +-1000, a
    load up to 1e8 N) is refused up front, as a friction above 10 was; such points were
    built as holes (status out of range) of a table that said it was complete."""
    from railcontact.errors import CaseError
    from railcontact.table import parse_spec
    from railcontact.table.spec import tomllib

    text = SPEC.replace("creepage_y = [0.0, 0.002, 2]\n", "")
    text = text.replace("load = [60e3, 80e3, 2]\n", "") + f"{axis} = {entry}\n"
    with pytest.raises(CaseError, match=match):
        parse_spec(tomllib.loads(text))


@pytest.fixture(scope="module")
def table_fmu(tmp_path_factory):
    """The FMU (built once for this module), its model description and unzipped folder."""
    fmpy = pytest.importorskip("fmpy")
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    from fmpy.model_description import read_model_description

    from railcontact.fmu import build_fmu

    fmu = build_fmu(tmp_path_factory.mktemp("fmu") / "RailContact.fmu", [])
    return read_model_description(str(fmu)), fmpy.extract(str(fmu))


def _table_slave(table_fmu, model: str, table_file: str, **strings: str):
    """An FMU instance in initialization mode with contact_model = ``model`` (set through
    its enumeration, as FMI tools do), ``table_file`` and further String parameters."""
    from fmpy.fmi2 import FMU2Slave

    md, unzipped = table_fmu
    var = {v.name: v for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="table")
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    items = {i.name: int(i.value) for i in var["contact_model_choice"].declaredType.items}
    s.setInteger([var["contact_model_choice"].valueReference], [items[model]])
    s.setString([var["table_file"].valueReference], [table_file])
    for name, value in strings.items():
        s.setString([var[name].valueReference], [value])
    return s, var


@pytest.mark.parametrize("table_file, strings, words", [
    ("", {}, "needs the parameter table_file"),
    ("no/such/table.zarr", {}, "table_file = 'no/such/table.zarr'"),
    ("BUILT", {"control": "penetration"}, "set control = load"),
    ("BUILT", {"load_definition": "normal"}, "load_definition = total"),
    ("BUILT", {"convention": "contact"}, "set convention = railcontact (got convention = contact)"),
])
def test_fmu_table_mode_bad_parameters_are_an_error_at_initialization(
        built, table_fmu, table_file, strings, words, capsys):
    """contact_model = table without a table, with a path that holds none, or with modes a
    table cannot answer (control, load definition, CONTACT's convention): fmi2Error at
    exitInitializationMode, the logger naming why."""
    from fmpy.fmi1 import FMICallException

    table_file = str(built[1].resolve()) if table_file == "BUILT" else table_file
    s, _ = _table_slave(table_fmu, "table", table_file, **strings)
    with pytest.raises(FMICallException) as err:
        s.exitInitializationMode()
    assert err.value.status == 3  # fmi2Error, not fmi2Fatal
    s.freeInstance()
    log = capsys.readouterr().out  # fmpy's logger prints "[ERROR] message"
    assert "[ERROR]" in log and words in log, log


def test_fmu_table_mode_reproduces_the_table_at_its_nodes(built, table_fmu):
    """The FMU with contact_model = table (fmu_src/slave.py making TableContact its
    contact, docs/tables.md) through fmpy: every node of the table, both wheels, exactly;
    outside the table status 3. The mode is set through the FMU's enumeration, as FMI
    tools set it."""
    s, var = _table_slave(table_fmu, "table", str(built[1].resolve()))
    s.exitInitializationMode()
    table = ContactTable.open(built[1])
    t = 0.0
    for index in np.ndindex(*(len(v) for v in table.axes.values())):
        y, eta, q = (float(table.axes[n][i]) for n, i in zip(table.axes, index, strict=True))
        inputs = {"lateral_displacement": y, "load_left": q, "load_right": q,
                  "eta_left": eta, "eta_right": -eta}
        s.setReal([var[k].valueReference for k in inputs], list(inputs.values()))
        s.doStep(t, 1e-3)
        t += 1e-3
        for side in ("left", "right"):
            node = table.node(index, side)
            for name in ("normal_force", "creep_force_y", "contact_angle"):
                got = s.getReal([var[f"{name}_{side}"].valueReference])[0]
                assert got == node[name], (index, side, name)
            assert s.getInteger([var[f"status_{side}"].valueReference])[0] == 0
    from fmpy.fmi1 import FMICallException

    s.setReal([var["lateral_displacement"].valueReference], [0.01])
    with pytest.raises(FMICallException) as err:
        s.doStep(t, 1e-3)  # nothing solved: fmi2Discard, not a warning with zero forces
    assert err.value.status == 2
    assert s.getInteger([var["status"].valueReference])[0] == 3
    s.terminate()
    s.freeInstance()


def test_fmu_table_mode_clamps_an_axis_whose_policy_is_clamp(built, table_fmu, tmp_path):
    """The table's out-of-range policy, recorded in the store by a build of the same table
    with ``[table] out_of_range = { lateral_displacement = "clamp" }``, is the FMU's: a
    lateral displacement beyond the axis gives the end node's outputs exactly (status 0);
    the load axis, left at status, is still out of range (status 3)."""
    from railcontact.table.store import Store

    spec_path, out = built
    copy = tmp_path / "clamp.zarr"
    shutil.copytree(out, copy)
    clamped = tmp_path / "spec.toml"
    clamped.write_text(spec_path.read_text().replace(
        "[table]\n", '[table]\nout_of_range = { lateral_displacement = "clamp" }\n'))
    Store(copy, load_spec(clamped))  # what a build (or a rerun) into the store does first
    s, var = _table_slave(table_fmu, "table", str(copy.resolve()))
    s.exitInitializationMode()
    table = ContactTable.open(copy)
    inputs = {"lateral_displacement": 0.003, "load_left": 80e3, "load_right": 80e3,
              "eta_left": 0.002, "eta_right": -0.002}
    s.setReal([var[k].valueReference for k in inputs], list(inputs.values()))
    s.doStep(0.0, 1e-3)
    for side in ("left", "right"):
        node = table.node((2, 1, 1), side)  # y = 2 mm, eta = 2e-3, 80 kN
        for name in ("normal_force", "creep_force_y", "contact_angle"):
            assert s.getReal([var[f"{name}_{side}"].valueReference])[0] == node[name]
        assert s.getInteger([var[f"status_{side}"].valueReference])[0] == 0
    from fmpy.fmi1 import FMICallException

    s.setReal([var["load_left"].valueReference, var["load_right"].valueReference],
              [90e3, 90e3])
    with pytest.raises(FMICallException):
        s.doStep(1e-3, 1e-3)
    assert s.getInteger([var["status"].valueReference])[0] == 3
    s.terminate()
    s.freeInstance()


def _cubic_field_table(bad: dict[tuple[int, int], int]) -> tuple[ContactTable, object]:
    """A 6 x 5 table (lateral displacement, lateral creepage) whose every quantity is the
    bicubic ``f`` on both wheels, except the nodes ``bad`` (index -> status) of the left
    wheel: NaN there, as a build records them."""
    from railcontact.table.variables import QUANTITIES

    ys = np.linspace(-0.005, 0.005, 6)
    etas = np.array([0.0, 0.5e-3, 1.5e-3, 2.5e-3, 4e-3])  # uneven on purpose

    def f(y, eta):
        return 1.0 + 2e2 * y - 3e6 * y**3 + 1e3 * eta + 4e8 * eta**3 + 5e8 * y * eta**2

    grid = f(*np.meshgrid(ys, etas, indexing="ij"))
    values = np.repeat(grid[:, :, None, None], 2, axis=2).repeat(len(QUANTITIES), axis=3)
    status = np.zeros((6, 5, 2), dtype=np.int8)
    for index, st in bad.items():
        status[(*index, 0)] = st
        values[(*index, 0)] = np.nan
    axes = {"lateral_displacement": ys, "creepage_y": etas}
    # (the flange of S1002, which a table step's validity needs: this case has no wheel)
    return ContactTable(axes, ("left", "right"), values, status, {},
                        flange=(-0.03845, 1.22193)), f


def test_cubic_spline_reproduces_a_bicubic_and_returns_the_nodes():
    """On a wheel whose nodes are all ok, ``cubic`` is the not-a-knot tensor-product
    spline, which reproduces any polynomial of degree 3 in each axis: the bicubic field of
    :func:`_cubic_field_table` to round-off between the nodes (uneven ones on one axis),
    and each node's stored values. (scipy's RegularGridInterpolator, method "cubic",
    solves for its spline iteratively and missed both by up to 5.6e-4.)"""
    table, f = _cubic_field_table({})
    for y in np.linspace(-0.005, 0.005, 23):
        for eta in np.linspace(0.0, 4e-3, 19):
            got = table({"lateral_displacement": float(y), "creepage_y": float(eta)},
                        "right", "cubic")
            assert got.status == 0
            assert got["creep_force_y"] == pytest.approx(f(y, eta), rel=1e-12, abs=1e-12)
    for i, y in enumerate(table.axes["lateral_displacement"]):
        for k, eta in enumerate(table.axes["creepage_y"]):
            got = table({"lateral_displacement": float(y), "creepage_y": float(eta)},
                        "left", "cubic")
            np.testing.assert_allclose(list(got.values.values()),
                                       list(table.node((i, k), "left").values.values()),
                                       rtol=1e-13, atol=1e-13)


def test_cubic_with_failed_nodes_is_local_or_linear_never_a_traceback():
    """A no-contact node (status 2, NaN) and a not-computed node (-1, NaN) on the left wheel
    only: cubic is exact for a bicubic where its 4 x 4 stencil is ok (the local cubic), the
    multilinear value with the linear status where the stencil touches a bad node, never a
    traceback and never NaN with status ok; not computed wins over the other statuses as in
    the linear path; the right wheel (all ok) keeps the spline."""
    from railcontact.table.variables import NO_CONTACT, NOT_COMPUTED, OK

    table, f = _cubic_field_table({(0, 4): NO_CONTACT, (5, 0): NOT_COMPUTED})
    for y in np.linspace(-0.005, 0.005, 23):
        for eta in np.linspace(0.0, 4e-3, 19):
            point = {"lateral_displacement": float(y), "creepage_y": float(eta)}
            cub, lin = table(point, "left", "cubic"), table(point, "left", "linear")
            got = cub["creep_force_y"]
            assert cub.status != OK or math.isfinite(got)
            if y < -0.001 and eta >= 1.5e-3 or y >= 0.001 and eta < 1.5e-3:
                assert cub.status == lin.status  # the stencil touches a bad node: linear
                np.testing.assert_equal(cub.values, lin.values)
            else:
                assert cub.status == OK and got == pytest.approx(f(y, eta), rel=1e-12, abs=1e-12)
            right = table(point, "right", "cubic")
            assert right.status == OK
            assert math.isfinite(right["creep_force_y"])  # the spline, as before
    # in the cell of the not-computed node: not computed
    corner = table({"lateral_displacement": 0.0045, "creepage_y": 0.0002}, "left", "cubic")
    assert corner.status == NOT_COMPUTED and math.isnan(corner["normal_force"])
    only_nc, _ = _cubic_field_table({(5, 0): NOT_COMPUTED})
    r = only_nc({"lateral_displacement": 0.0045, "creepage_y": 0.0002}, "left", "cubic")
    assert r.status == NOT_COMPUTED  # was ok (the max over the wheel) before


def test_a_solver_exception_loses_only_its_point(tmp_path, monkeypatch):
    """A solver that raises something other than RailContactError (here ZeroDivisionError)
    at one point: that point is recorded out of range with the exception in its message, the
    other points of the batch are solved as by ``railcontact solve`` (the truth at a node)."""
    from railcontact.table import solve as table_solve
    from railcontact.table.variables import OUT_OF_RANGE

    spec_path = tmp_path / "spec.toml"
    spec_path.write_text(SPEC)
    spec = load_spec(spec_path)
    real = table_solve.solve_wheel_rail

    def flaky(case, starts=None, **kwargs):
        if case.tangential.creepage[1] == 0.002:
            raise ZeroDivisionError("float division by zero")
        return real(case, starts, **kwargs)

    monkeypatch.setattr(table_solve, "solve_wheel_rail", flaky)
    points = [{"creepage_y": 0.0}, {"creepage_y": 0.002}]
    out = table_solve.solve_batch(spec.case, ("left",), points)
    assert out["status"][:, 0].tolist() == [0, OUT_OF_RANGE]
    assert math.isnan(out["normal_force"][1, 0])
    (i, side, st, message), = out["messages"]
    assert (i, side, st) == (1, "left", OUT_OF_RANGE)
    assert "ZeroDivisionError: float division by zero" in message
    exact = _wheel(solve(spec.case_at((0, 0, 0))), "left")  # the first values: eta = 0
    assert out["normal_force"][0, 0] == pytest.approx(exact["normal_force"], rel=1e-9)


def test_workers_with_a_scheduler_is_an_error(tmp_path, capsys):
    """--workers sizes a local cluster, which --scheduler replaces: giving both is an error
    naming both (was: --workers silently ignored), before any store is made."""
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    out = tmp_path / "t.zarr"
    assert main(["table", "build", str(spec), "-o", str(out), "--quiet",
                 "--scheduler", "tcp://127.0.0.1:9", "--workers", "2"]) == 2
    err = capsys.readouterr().err
    assert "--workers 2 sizes a new local cluster" in err and "--scheduler tcp://127.0.0.1:9" in err
    assert not out.exists()


@pytest.mark.parametrize("pose, loads, creepages, kinematics, words", [
    ((0.0, 0.0), (8e4, float("nan")), None, None, "right wheel load [N] must be finite"),
    ((0.0, 0.0), (8e4, 8e4), ((0.0, float("nan"), 0.0), (0.0, 0.0, 0.0)), None,
     "left creepage must be finite"),
    ((0.0, 0.0), (8e4, 8e4), ((0.0, "0.1", 0.0), (0.0, 0.0, 0.0)), None,
     "left creepage must be a number, got '0.1'"),
    ((0.0, 0.0), (8e4, 8e4), ((0.0, 1j, 0.0), (0.0, 0.0, 0.0)), None,
     "left creepage must be a number, got 1j"),
    ((0.0, 0.0), (8e4, 8e4), ((0.0, 1e-3), (0.0, 0.0, 0.0)), None,
     "creepages must be ((xi, eta, phi) left, (xi, eta, phi) right)"),
    ((0.0, 0.0), (8e4,), None, None, "loads must be (left, right) [N], got (80000.0,)"),
    ((0.0, 0.0), (None, 8e4), None, None, "left wheel load [N] must be a number"),
    ((0.0, 0.0), (8e4, 8e4), None, (30.0, 0.0),
     "kinematics must be a Kinematics record, got (30.0, 0.0)"),
    (None, (8e4, 8e4), None, None, "pose must be a Pose, got None"),
])
def test_table_step_names_the_input_that_is_not_a_number(pose, loads, creepages,
                                                         kinematics, words):
    """An input to TableContact.solve that is not a finite number of its kind: an error
    naming that input, the same as WheelsetContact's (was: a TypeError, ValueError or
    AttributeError from inside for a string, a complex number, None, a creepage of two
    components, one load, kinematics as a tuple or no Pose; "creepages must be finite"
    named no wheel)."""
    from railcontact.geometry.track import Pose
    from railcontact.table.step import TableContact

    table, _ = _cubic_field_table({})
    table.case = {"geometry": {"lateral_displacement": 0.0, "yaw": 0.0},
                  "normal": {"load": 8e4}, "tangential": {"creepage": [0.0, 0.0, 0.0]}}
    with pytest.raises(RailContactError, match=re.escape(words)):
        TableContact(table).solve(None if pose is None else Pose(*pose), loads=loads,
                                  creepages=creepages, kinematics=kinematics)


@pytest.mark.parametrize("call, words", [
    (lambda t: t({"lateral_displacement": None, "creepage_y": 0.0}),
     "lateral_displacement [m] must be a number, got None"),
    (lambda t: t({"lateral_displacement": "0.001", "creepage_y": 0.0}),
     "lateral_displacement [m] must be a number, got '0.001'"),
    (lambda t: t({"lateral_displacement": 0.0, "creepage_y": 1j}),
     "creepage_y must be a number, got 1j"),
    (lambda t: t([0.0, 0.0]), "a table's point is a mapping of axis name to value"),
    (lambda t: t.node((6, 0)), "lateral_displacement: 0 .. 5, creepage_y: 0 .. 4), got (6, 0)"),
    (lambda t: t.node((0, -1)), "got (0, -1)"),
    (lambda t: t.node("a"), "a node's index is one integer per axis"),
    (lambda t: t.node((0,)), "a node's index is one integer per axis"),
])
def test_table_lookups_name_what_is_not_a_point_or_a_node(call, words):
    """A ContactTable's point with a value that is not a real number, a point that is not
    a mapping, a node index out of range (a negative one too: it would count from the end)
    or not one integer per axis: an error naming it (was: TypeError, ValueError,
    IndexError, or another node's values)."""
    table, _ = _cubic_field_table({})
    with pytest.raises(RailContactError, match=re.escape(words)):
        call(table)


def test_table_step_refuses_what_is_not_a_table_or_settings():
    """TableContact of something that is not a ContactTable, or with settings that are not
    ContactSettings: an error naming it (was: AttributeError)."""
    from railcontact.table.step import TableContact

    with pytest.raises(RailContactError, match="table must be a ContactTable"):
        TableContact(None)
    table, _ = _cubic_field_table({})
    with pytest.raises(RailContactError, match="settings must be ContactSettings"):
        TableContact(table, settings={"friction": 0.3})


def test_store_identity_survives_a_rename_and_a_move_not_a_changed_profile(tmp_path):
    """An unnamed spec (its name the file's stem) with a profile file beside it: renamed
    and moved with its profile to another folder it still names the same table (was:
    another case, the stem and the absolute path differed); the profile file changed in
    place (one height by 1 micrometre) names another (was: the same, only its path
    compared)."""
    from railcontact.table.store import check_identity

    src = (Path(__file__).parent.parent / "models" / "profiles" / "S1002.txt").read_text()
    text = SPEC.replace('name = "table_test"\n', "").replace('wheel = "S1002"',
                                                              'wheel = "w.txt"')
    a, b = tmp_path / "a", tmp_path / "moved" / "b"
    for d, spec_name in ((a, "spec.toml"), (b, "renamed.toml")):
        d.mkdir(parents=True)
        (d / "w.txt").write_text(src)
        (d / spec_name).write_text(text)
    first = load_spec(a / "spec.toml").identity()
    check_identity("t.zarr", first, load_spec(b / "renamed.toml").identity())  # no error
    lines = src.splitlines()
    y, z = lines[2].split()
    lines[2] = f"{y} {float(z) + 1e-3:.6f}"
    (b / "w.txt").write_text("\n".join(lines) + "\n")
    with pytest.raises(RailContactError, match="differs in: case geometry"):
        check_identity("t.zarr", first, load_spec(b / "renamed.toml").identity())


def test_table_node_equals_the_exact_wheelset_step():
    """A table node read through TableContact is the exact time step's answer at the same
    state (both in the frame at the reference point): the paper's wheel pair, 2 mm
    elements, y = 2 mm, xi = eta = 1e-3, 83.3 kN. Normal force to the load tolerance, creep
    forces to eps_tau mu N, contact angle and point to what forming the frame at an approach
    within 1e-3 moves them (3.3e-5 rad, 2.3 um)."""
    import railcontact as rc
    from railcontact.table import TableContact, parse_spec
    from railcontact.table.solve import solve_batch
    from railcontact.table.variables import QUANTITIES

    y, xi, eta, q, mu = 2e-3, 1e-3, 1e-3, 83.3e3, 0.3
    geo = {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
           "inclination": math.atan(1 / 40), "gauge": 1.435, "back_to_back": 1.360,
           "wheel_radius": 0.46}
    spec = parse_spec({"name": "node", "material": {"young": 206e9, "poisson": 0.28},
                       "geometry": geo, "grid": {"dx": 2e-3, "dy": 2e-3},
                       "normal": {"load": q, "estimate": "hertz"},
                       "tangential": {"friction": mu, "creepage": [xi, 0.0, 0.0]},
                       "table": {"lateral_displacement": [y, y, 1],
                                 "creepage_y": [eta, eta, 1]}})
    r = solve_batch(spec.case, spec.sides, [{"lateral_displacement": y, "creepage_y": eta}])
    values = np.stack([r[k.name] for k in QUANTITIES], -1).reshape(1, 1, 2, len(QUANTITIES))
    table = ContactTable(spec.axes, spec.sides, values, r["status"].reshape(1, 1, 2),
                         spec.case)
    creep = ((xi, eta, 0.0), (xi, -eta, 0.0))
    got = TableContact(table).solve(rc.Pose(y), loads=(q, q), creepages=creep)
    settings = rc.ContactSettings(friction=mu, element_size=2e-3)
    step = rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), geo["inclination"], geo["gauge"]),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46, 1.360),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL), settings)
    want = step.solve(rc.Pose(y), loads=(q, q), creepages=creep)
    for a, b in zip(got.wheels, want.wheels, strict=True):
        assert a.status == b.status == 0
        assert a.normal_force == pytest.approx(b.normal_force,
                                               rel=settings.load_tolerance)
        bound = settings.tangential_tolerance * mu * b.normal_force
        assert np.allclose(a.creep_force, b.creep_force, rtol=0, atol=bound)
        assert a.contact_angle == pytest.approx(b.contact_angle, abs=1e-4)
        assert np.allclose(a.contact_point, b.contact_point, rtol=0, atol=1e-5)


def test_messages_are_written_per_write_and_gathered_when_the_build_ends(tmp_path):
    """A write of batches records their messages (and which batches it wrote: a batch
    written again counts its latest write, also when it has none then); messages count
    once their batch is done (a write cut off before its done flags leaves them out); a
    build cut off before its end keeps them readable; the root attribute gathers them when
    the build ends and the write groups go; a store of the earlier layout (a group per
    batch, and the root attribute) keeps them."""
    import zarr

    from railcontact.table.store import Store, create_store, read_messages
    from railcontact.table.variables import COUNTS, QUANTITIES

    spec_path = tmp_path / "spec.toml"
    spec_path.write_text(SPEC.replace("[table]", "[table]\nbatch = 2"))
    spec = load_spec(spec_path)
    out = tmp_path / "m.zarr"
    create_store(out, spec)

    def result(ix):
        n = len(spec.batch_points(ix))
        r = {q.name: np.zeros((n, len(spec.sides))) for q in QUANTITIES}
        r.update({q.name: np.zeros((n, len(spec.sides)), dtype=np.int32) for q in COUNTS})
        r["status"] = np.ones((n, len(spec.sides)), dtype=np.int8)
        return r

    def msg(ix, text):
        return [{"batch": list(ix), "side": "left", "status": 1, "point": {"load": 1.0},
                 "message": text}]

    batches = list(np.ndindex(*spec.batch_shape))
    a, b, c = batches[0], batches[-1], batches[1]
    store = Store(out, spec)
    store.write_batches([(b, result(b), msg(b, "b first")), (a, result(a), msg(a, "a"))])
    # cut off here (no finish): the messages are there, in batch order
    assert [m["message"] for m in read_messages(out)] == ["a", "b first"]
    root = zarr.open_group(str(out), mode="r")
    assert json.loads(root.attrs["messages"]) == []  # not gathered yet
    # a write cut off before its done flags: its messages do not count
    g = zarr.open_group(str(out), mode="r+")
    g["messages"].require_group("w99").attrs.update({"messages": msg(c, "c cut"),
                                                     "batches": ["0.1.0"]})
    assert [m["message"] for m in read_messages(out)] == ["a", "b first"]
    store = Store(out, spec)  # resumed: b computed again, now ok; a again, other text
    store.write(b, result(b), [])
    store.write(a, result(a), msg(a, "a again"))
    store.finish(False)
    assert [m["message"] for m in read_messages(out)] == ["a again"]
    root = zarr.open_group(str(out), mode="r")
    assert json.loads(root.attrs["messages"]) == msg(a, "a again")
    assert list(root["messages"].group_keys()) == []  # gathered: the groups removed
    assert json.loads(root.attrs["failed"]) == {"not converged": 8, "not computed": 16}

    old = tmp_path / "old.zarr"  # the earlier layout: a group per batch, and the root's
    create_store(old, spec)
    g = zarr.open_group(str(old), mode="r+")
    g.attrs["messages"] = json.dumps(msg(a, "old a") + msg(b, "old b"))
    g["messages"].require_group(".".join(map(str, b))).attrs["messages"] = msg(b, "old b")
    done = g["batch_done"][...]
    done[a] = done[b] = True
    g["batch_done"][...] = done
    assert read_messages(old) == msg(a, "old a") + msg(b, "old b")
    store = Store(old, spec)
    store.write(b, result(b), msg(b, "new b"))
    store.finish(False)
    assert [m["message"] for m in read_messages(old)] == ["old a", "new b"]


def test_the_store_is_a_few_files_whatever_its_batches(tmp_path):
    """The same 3 x 2 x 8 table cut into 48 batches of one point and into 6 of 8: the
    stores have the same files, a few per quantity (the chunks are axis blocks, not
    batches), and hold the same values; an empty store has no data chunk at all."""
    import zarr

    from railcontact.table.store import Store, create_store
    from railcontact.table.variables import COUNTS, QUANTITIES

    files = {}
    tables = {}
    for batch in (1, 8):
        spec_path = tmp_path / f"spec{batch}.toml"
        spec_path.write_text(SPEC.replace("load = [60e3, 80e3, 2]",
                                          f"load = [60e3, 80e3, 8]\nbatch = {batch}"))
        spec = load_spec(spec_path)
        assert spec.batch_shape == (3, 2, 8 // batch)
        out = tmp_path / f"b{batch}.zarr"
        create_store(out, spec)
        names = [q.name for q in QUANTITIES + COUNTS] + ["status"]
        empty = {p.relative_to(out) for p in out.rglob("*") if p.is_file()}
        assert not any(p.parts[0] in names and not p.name.startswith(".") for p in empty)
        store = Store(out, spec)
        items = []
        for ix in np.ndindex(*spec.batch_shape):
            pts = spec.batch_points(ix)
            r = {q.name: np.array([[float(sum(p) * 10 + j) for j in range(2)] for p in pts])
                 for q in QUANTITIES}
            r.update({q.name: np.ones((len(pts), 2), dtype=np.int32) for q in COUNTS})
            r["status"] = np.zeros((len(pts), 2), dtype=np.int8)
            items.append((ix, r, []))
        store.write_batches(items[: len(items) // 2])
        store.write_batches(items[len(items) // 2:])
        store.finish(True)
        files[batch] = {p.relative_to(out) for p in out.rglob("*") if p.is_file()}
        tables[batch] = zarr.open_group(str(out), mode="r")
        assert tables[batch]["batch_done"][...].all()
    assert files[1] == files[8]
    assert len(files[1]) <= 3 * (len(QUANTITIES) + len(COUNTS) + 6) + 4
    for name in ("normal_force", "status", "n_patches"):
        np.testing.assert_array_equal(tables[1][name][...], tables[8][name][...])
    want = np.add.outer(np.add.outer(np.arange(3), np.arange(2)), np.arange(8)) * 10.0
    np.testing.assert_array_equal(tables[1]["normal_force"][..., 1], want + 1)


def test_a_cluster_without_workers_is_an_error_after_the_timeout(tmp_path, capsys):
    """A scheduler whose workers are all gone (here: none): the build stops after
    --lost-timeout with an error saying to resume, the store is there (empty: nothing
    finished) and a progress line was printed before the wait."""
    from distributed import LocalCluster

    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    out = tmp_path / "t.zarr"
    with LocalCluster(n_workers=0, processes=True, dashboard_address=":0") as cluster:
        code = main(["table", "build", str(spec), "-o", str(out), "--scheduler",
                     cluster.scheduler_address, "--lost-timeout", "2"])
    err = capsys.readouterr().err
    assert code == 2
    assert "had no worker for 2 s" in err and "rerun with --resume" in err
    assert f"table {out}: 12 points x 2 wheel(s) in 6 batches" in err
    assert open_dataset(out)["batch_done"].values.sum() == 0


FLANGE_SPEC = """
name = "flange"
[material]
young = 206e9
poisson = 0.28
[geometry]
type = "wheel-rail"
wheel = "S1002"
rail = "60E1"
[grid]
dx = 2e-3
dy = 2e-3
[normal]
load = 83.3e3
[tangential]
creepage = [0.002, -0.002, 0.3]
friction = 0.3
[table]
lateral_displacement = [0.006, 0.008, 2]
"""


@pytest.fixture(scope="module")
def flange_table(tmp_path_factory, scheduler):
    """A table of the flange (the left wheel at y = 6 and 8 mm: Y/Q about 3.6 at 8 mm)."""
    d = tmp_path_factory.mktemp("flange")
    (d / "spec.toml").write_text(FLANGE_SPEC)
    out = d / "flange.zarr"
    assert main(["table", "build", str(d / "spec.toml"), "-o", str(out), "--scheduler",
                 scheduler, "--quiet"]) == 0
    return out


def test_table_step_checks_validity_as_the_exact_step(flange_table):
    """On the flange (y = 8 mm, 83.3 kN, creepages (2e-3, -2e-3, 0.3 1/m), mu 0.3) the
    exact step is outside validity (status 4, validity Y_Q | NADAL | FLANGE_CLIMB, Y/Q
    3.64): the table step gives the same status and bits, its Y/Q and penetration to the
    solvers' tolerances (was: status 0, Y/Q 0, validity 0, penetration 0). The limits are
    the step's settings (a tighter max_penetration and max_wheel_load set their bits;
    Nadal's limit with the table's friction, whatever the settings' friction); between the
    nodes Y/Q is that of the interpolated forces."""
    import railcontact as rc
    from railcontact.geometry.track import Pose
    from railcontact.table.step import TableContact
    from railcontact.timestep.validity import (
        FLANGE_CLIMB,
        LOAD,
        NADAL,
        PENETRATION,
        Y_Q,
        nadal_limit,
    )
    from railcontact.timestep.wheelset import WheelsetContact

    tc = TableContact.open(flange_table)
    steel = rc.Material(206e9, 0.28)
    bem = WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), 0.0249948),
                          rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                          rc.ElasticPair.of(steel, steel),
                          rc.ContactSettings(friction=0.3, element_size=2e-3,
                                             warm_start="none"))
    cr = ((0.002, -0.002, 0.3), (0.002, 0.002, -0.3))
    loads = (83.3e3, 83.3e3)
    got = tc.solve(Pose(0.008), loads=loads, creepages=cr).left
    want = bem.solve(Pose(0.008), loads=loads, creepages=cr).left
    assert want.status == got.status == 4
    assert want.validity == got.validity == Y_Q | NADAL | FLANGE_CLIMB
    other = tc.solve(Pose(0.006), loads=loads, creepages=cr).left  # the other node
    assert other.validity == bem.solve(Pose(0.006), loads=loads, creepages=cr).left.validity
    assert got.derailment_quotient == pytest.approx(want.derailment_quotient, rel=0.01)
    assert got.derailment_quotient == pytest.approx(
        -got.track_force[1] / got.track_force[2])
    assert got.penetration == pytest.approx(want.penetration, rel=0.05)
    assert got.message.startswith("outside validity: Y/Q = 3.6")
    assert "Nadal's limit" in got.message and "flange climb" in got.message
    # the step's limits; the table's friction for Nadal's limit
    tight = TableContact.open(flange_table, settings=rc.ContactSettings(
        friction=0.9, max_y_q=10.0, max_penetration=0.1e-3, max_wheel_load=80e3))
    assert tight.limits.friction == 0.3
    w = tight.solve(Pose(0.008), loads=loads, creepages=cr).left
    assert w.status == 4 and w.validity == NADAL | FLANGE_CLIMB | PENETRATION | LOAD
    assert f"Nadal's limit {nadal_limit(tc.flange[1], 0.3):.3g}" in w.message
    # between the nodes: the interpolated forces' Y/Q, the same checks
    lo, hi = (tc.solve(Pose(y), loads=loads, creepages=cr).left for y in (0.006, 0.008))
    mid = tc.solve(Pose(0.007), loads=loads, creepages=cr).left
    assert mid.derailment_quotient == pytest.approx(
        -(lo.track_force[1] + hi.track_force[1]) / (lo.track_force[2] + hi.track_force[2]))
    assert mid.status == 4 and mid.validity & (Y_Q | NADAL) == Y_Q | NADAL


def test_table_step_outside_the_axes_is_out_of_range_never_clamped(flange_table):
    """A state just outside the table's axis (below or above it) is out of range (status
    3) with zero forces and a message naming the axis, the value and the table's range,
    never the nearest node's values; a negative load is an error, as in the exact step."""
    from railcontact.geometry.track import Pose
    from railcontact.table.step import TableContact

    tc = TableContact.open(flange_table)
    cr = ((0.002, -0.002, 0.3), (0.002, 0.002, -0.3))
    for y in (0.006 - 1e-9, 0.008 + 1e-9):
        res = tc.solve(Pose(y), loads=(83.3e3, 83.3e3), creepages=cr)
        for w in res.wheels:
            assert (w.status, w.normal_force, w.track_force, w.derailment_quotient,
                    w.validity) == (3, 0.0, (0.0, 0.0, 0.0), 0.0, 0)
            assert f"lateral_displacement = {y:g} m is outside the table [0.006, 0.008]" \
                in w.message
        assert res.status == 3
    # the case's load (83.3 kN) only: another is out of range, named
    res = tc.solve(Pose(0.008), loads=(83.3e3, 90e3), creepages=cr)
    assert (res.left.status, res.right.status) == (4, 3)
    assert "no load axis" in res.right.message
    with pytest.raises(RailContactError, match="right wheel load .N. must be non-negative"):
        tc.solve(Pose(0.008), loads=(83.3e3, -1.0), creepages=cr)


def test_a_store_without_the_validity_quantities_is_read_and_refused_by_a_step(
        flange_table, tmp_path, capsys):
    """A store written before penetration, the patch nearest the flange tip and the wheel's
    flange were stored: it is read (those quantities NaN, named in ``missing``; the flange
    from the case's wheel profile), a table step refuses it naming what it lacks, a build
    does not resume it, ``railcontact table show`` still shows it."""
    import zarr

    from railcontact.table.step import TableContact
    from railcontact.table.store import Store

    old = tmp_path / "old.zarr"
    shutil.copytree(flange_table, old)
    g = zarr.open_group(str(old), mode="r+")
    for name in ("penetration", "tip_position", "tip_angle"):
        del g[name]
    flange = json.loads(g.attrs["flange_flank"])
    del g.attrs["flange_flank"]
    table = ContactTable.open(old)
    assert table.missing == ("penetration", "tip_position", "tip_angle")
    assert np.isnan(table.node((1,), "left")["penetration"])
    assert table.flange == pytest.approx(flange)
    assert ContactTable.open(flange_table).flange == tuple(flange)
    with pytest.raises(RailContactError, match="without penetration, tip_position, "
                       "tip_angle, which a table step needs.*build it anew"):
        TableContact(table)
    spec = tmp_path / "spec.toml"
    spec.write_text(FLANGE_SPEC)
    with pytest.raises(RailContactError, match="without penetration, tip_position, "
                       "tip_angle: it cannot be resumed"):
        Store(old, load_spec(spec))
    assert main(["table", "show", str(old)]) == 0  # still shown
    assert "left   ok 2" in capsys.readouterr().out


@pytest.mark.parametrize("axes, words", [
    ({"lateral_displacement": [0.0, 0.004, 10_000_000_000]},
     "10000000000 points (lateral_displacement 10000000000); at most 10000000"),
    ({"lateral_displacement": [0.0, 0.004, 100_000], "load": [60e3, 80e3, 100_000]},
     "10000000000 points (lateral_displacement 100000 x load 100000)"),
    ({"load": [60e3, 80e3, 0], "lateral_displacement": [0.0, 0.004, 10_000_000_000]},
     "at most 10000000"),
])
def test_a_huge_axis_count_is_refused_before_any_allocation(axes, words, tmp_path, capsys):
    """An axis count of 1e10 (or a product of counts beyond the limit): a one-line error
    naming the counts, the limit and the memory the table would take, raised before any
    axis is made (was: np.linspace allocated 74.5 GiB, a MemoryError); also from the
    command line (exit 2)."""
    import tracemalloc

    from railcontact.errors import CaseError
    from railcontact.table import parse_spec
    from railcontact.table.spec import tomllib

    raw = tomllib.loads(FLANGE_SPEC.split("[table]")[0])
    raw["table"] = axes
    tracemalloc.start()
    try:
        with pytest.raises(CaseError, match="GiB in memory") as err:
            parse_spec(raw)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert words in str(err.value)
    assert peak < 10 * 2**20
    spec = tmp_path / "spec.toml"
    spec.write_text(FLANGE_SPEC.split("[table]")[0] + "[table]\n" + "".join(
        f"{k} = {v!r}\n" for k, v in axes.items()))
    assert main(["table", "build", str(spec), "-o", str(tmp_path / "t.zarr"),
                 "--workers", "1", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "at most 10000000" in err and "Traceback" not in err
    assert not (tmp_path / "t.zarr").exists()


def test_fmu_table_mode_uses_its_limits_of_validity(flange_table, table_fmu):
    """The FMU's parameters max_y_q, max_penetration and max_wheel_load are the table
    step's limits too: on the flange table's 8 mm node (Y/Q 3.6, beyond Nadal's limit,
    flange climb) max_y_q = 10 leaves the Y/Q bit out, the other two stay."""
    from railcontact.timestep.validity import FLANGE_CLIMB, NADAL

    s, var = _table_slave(table_fmu, "table", str(flange_table.resolve()))
    s.setReal([var["max_y_q"].valueReference], [10.0])
    s.exitInitializationMode()
    inputs = {"lateral_displacement": 0.008, "load_left": 83.3e3, "load_right": 83.3e3,
              "xi_left": 0.002, "eta_left": -0.002, "phi_left": 0.3,
              "xi_right": 0.002, "eta_right": 0.002, "phi_right": -0.3}
    s.setReal([var[k].valueReference for k in inputs], list(inputs.values()))
    s.doStep(0.0, 1e-3)
    assert s.getInteger([var["status_left"].valueReference])[0] == 4
    assert s.getInteger([var["validity_left"].valueReference])[0] == NADAL | FLANGE_CLIMB
    assert s.getReal([var["derailment_quotient_left"].valueReference])[0] > 3.0
    s.terminate()
    s.freeInstance()


def _flange_spec(dx: float, creepage: list[float], load: float, etas: list[float]):
    """The right wheel on its flange (wheelset 7.5 mm to the right, yaw -5 mrad), S1002 on
    60E1 1:40, the case's default tolerances and starts, over the lateral creepage."""
    from railcontact.table import parse_spec

    geo = {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1", "side": "right",
           "inclination": math.atan(1 / 40), "lateral_displacement": -0.0075, "yaw": -0.005}
    return parse_spec({"name": "flange_start", "material": {"young": 206e9, "poisson": 0.28},
                       "geometry": geo, "grid": {"dx": dx, "dy": dx},
                       "normal": {"load": load},
                       "tangential": {"creepage": creepage, "friction": 0.3},
                       "table": {"creepage_y": {"values": etas}}})


def test_a_point_failing_from_the_previous_one_is_solved_again_cold():
    """On the flange (right wheel, y = -7.5 mm, yaw -5 mrad, 40 kN, xi = -5e-3, 1 mm
    elements) the point eta = 0 started from eta = -5e-3 stalls in its load loop (vertical
    force 0.11 % off); solved cold it converges. The table holds the cold solve - the truth
    at a node, ``railcontact solve`` - and no failed point."""
    from railcontact.table.solve import solve_batch

    spec = _flange_spec(1e-3, [-0.005, 0.0, 0.0], 40e3, [-0.005, 0.0])
    out = solve_batch(spec.case, spec.sides, [{"creepage_y": e} for e in (-0.005, 0.0)])
    assert out["status"][:, 0].tolist() == [0, 0] and out["messages"] == []
    assert out["recovered"] == [(1, "right", "cold")]  # it did fail from the warm start
    exact = _wheel(solve(spec.case_at((1,))), "right")
    for name, value in exact.items():
        assert out[name][1, 0] == value, name  # the cold solve, bit for bit
    # the load is carried: the rail's vertical force on the wheel is Q (load tolerance)
    assert out["force_vertical"][1, 0] == pytest.approx(40e3, rel=1e-3)


def test_a_point_failing_cold_is_solved_from_the_exact_steps_estimates():
    """On the flange (right wheel, y = -7.5 mm, yaw -5 mrad, 40 kN, xi = 5e-3,
    eta = -1e-2, phi = 2 /m, 0.5 mm elements) the case's cold start stalls in the load loop
    at the tangential BEM's noise floor (0.11 % off); from the simplified models' estimates
    (the exact step's: infcon, fastrip) the load is met. The truth: the vertical force is
    Q, and the creep forces are those of a cold solve at ten times tighter tangential
    tolerance (which converges from the case's start) to eps_tau mu N."""
    from railcontact.table.solve import solve_batch, solve_point

    spec = _flange_spec(0.5e-3, [0.005, -0.01, 2.0], 40e3, [-0.01])
    out = solve_batch(spec.case, spec.sides, [{"creepage_y": -0.01}])
    assert out["status"].tolist() == [[0]] and out["recovered"] == [(0, "right", "estimate")]
    assert out["force_vertical"][0, 0] == pytest.approx(40e3, rel=1e-3)
    tight = spec.case_at((0,))
    tight["tangential"] = {**tight["tangential"], "tolerance": 1e-3}
    ref, _ = solve_point(tight, "right")
    assert ref.status == 0
    bound = 1e-2 * 0.3 * ref.normal_force
    assert abs(out["creep_force_x"][0, 0] - ref.creep_force[0]) < bound
    assert abs(out["creep_force_y"][0, 0] - ref.creep_force[1]) < bound
