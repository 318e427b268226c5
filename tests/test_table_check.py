"""A table's interpolation error, measured between the nodes against the exact solver
(``table build --check``, ``table check``), and its refinement where the error or the
contact jumps (``table refine``).

The truth is ``railcontact solve`` at each checked state (off the nodes); tables on a
coarse grid (2 mm elements) so that a point solves in milliseconds.
"""

from __future__ import annotations

import math
import re
import shutil
import warnings

import numpy as np
import pytest

pytest.importorskip("distributed")
pytest.importorskip("xarray")
pytest.importorskip("zarr")

from railcontact import solve  # noqa: E402
from railcontact.cli import main  # noqa: E402
from railcontact.errors import RailContactError  # noqa: E402
from railcontact.table import ContactTable, load_spec  # noqa: E402
from railcontact.table.check import (  # noqa: E402
    Check,
    check_table,
    measure,
    read_check,
    regions,
    sample_states,
)

SPEC = """
name = "check_test"
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
[tangential]
creepage = [0.0, 0.0, 0.0]
friction = 0.3
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
def checked(tmp_path_factory, scheduler):
    """The 3 x 2 x 2 table built with ``--check 5`` (seed 7) on the cluster."""
    d = tmp_path_factory.mktemp("check")
    (d / "spec.toml").write_text(SPEC)
    out = d / "t.zarr"
    assert main(["table", "build", str(d / "spec.toml"), "-o", str(out), "--scheduler",
                 scheduler, "--quiet", "--check", "5", "--seed", "7"]) == 0
    return d / "spec.toml", out


def _exact(case: dict, side: str) -> dict[str, float]:
    """``railcontact solve`` of the case: the wheel's normal force, creep forces (its
    contact frame) and the main patch's contact angle."""
    sol = solve(case)
    ps = [p for p in sol.patches if p.geometry.side == side]
    sgn = 1.0 if side == "left" else -1.0
    main_p = max(ps, key=lambda p: p.normal.force)
    return {"N": sum(p.normal.force for p in ps),
            "Fx": sum(p.tangential.force[0] for p in ps),
            "Fy": sgn * sum(p.tangential.force[1] for p in ps),
            "angle": main_p.geometry.contact_angle}


def test_states_are_seeded_off_the_nodes_and_inside_the_axes():
    axes = {"lateral_displacement": np.array([-0.002, 0.0, 0.002]),
            "yaw": np.array([0.001]), "load": np.array([6e4, 8e4])}
    a, b = sample_states(axes, 50, seed=3), sample_states(axes, 50, seed=3)
    assert np.array_equal(a, b) and not np.array_equal(a, sample_states(axes, 50, seed=4))
    for k, nodes in enumerate(axes.values()):
        if len(nodes) == 1:
            assert (a[:, k] == nodes[0]).all()
        else:
            assert ((a[:, k] > nodes[0]) & (a[:, k] < nodes[-1])).all()
            assert not np.isin(a[:, k], nodes).any()
    with pytest.raises(RailContactError, match="at least 1 state"):
        sample_states(axes, 0)


def test_the_check_is_the_exact_solver_between_the_nodes(checked, capsys):
    """Each checked state's exact values are ``railcontact solve`` there; the stored errors
    are the table's interpolation against them (normal force over max(N, Q), creep force
    over mu max(N, Q), contact angle); the per-interval rows hold each sample once per axis;
    ``table show`` prints them."""
    spec_path, out = checked
    spec = load_spec(spec_path)
    chk = read_check(out)
    assert chk.size == 5 and chk.seed == 7 and chk.method == "linear"
    assert np.array_equal(chk.states, sample_states(spec.axes, 5, seed=7))
    table = ContactTable.open(out)
    errs = {"normal_force": [], "creep_force": [], "contact_angle": []}
    for i in range(chk.size):
        point = chk.point(i)
        for j, side in enumerate(spec.sides):
            ex = _exact(spec.case_at_values(point), side)
            assert chk.exact[i, j, :4].tolist() == [ex["N"], ex["Fx"], ex["Fy"], ex["angle"]]
            r = table(point, side)
            q = point["load"]
            scale = max(ex["N"], q)
            errs["normal_force"].append(abs(r["normal_force"] - ex["N"]) / scale)
            errs["creep_force"].append(math.hypot(r["creep_force_x"] - ex["Fx"],
                                                  r["creep_force_y"] - ex["Fy"]) / (0.3 * scale))
            errs["contact_angle"].append(abs(r["contact_angle"] - ex["angle"]))
    for m, want in errs.items():
        assert chk.errors[m].ravel().tolist() == pytest.approx(want, rel=1e-12), m
    # not a trivial check: linear interpolation of a curved creep curve errs between nodes
    assert max(errs["creep_force"]) > 1e-3 and max(errs["normal_force"]) > 0
    rows = regions(chk, spec.axes)
    assert [(r["axis"], r["lo"], r["hi"]) for r in rows] == [
        ("lateral_displacement", -0.002, 0.0), ("lateral_displacement", 0.0, 0.002),
        ("creepage_y", 0.0, 0.002), ("load", 60e3, 80e3)]
    lateral = [r for r in rows if r["axis"] == "lateral_displacement"]
    assert sum(r["samples"] for r in lateral) == 10
    inside = (chk.states[:, 0] >= 0.0)
    assert lateral[1]["normal_force"]["max"] == max(
        e for e, k in zip(errs["normal_force"], np.repeat(inside, 2), strict=True) if k)
    assert main(["table", "show", str(out)]) == 0
    text = capsys.readouterr().out
    assert "interpolation error (linear) at 5 random states (seed 7) x 2 wheel(s)" in text
    assert "0 in holes, 0 not solved exactly" in text
    assert re.search(r"lateral_displacement +-0\.002\.\.0 +m +\d+ ", text)


def test_table_check_on_an_existing_table_replaces_the_check(checked, scheduler, tmp_path,
                                                            capsys):
    """``railcontact table check STORE N`` solves N new states (another seed: other states)
    and replaces the kept check; bad input is an error before any cluster."""
    _, out = checked
    copy = tmp_path / "c.zarr"
    shutil.copytree(out, copy)
    assert main(["table", "check", str(copy), "3", "--seed", "2", "--scheduler",
                 scheduler]) == 0
    said = capsys.readouterr().out
    assert "check (linear) at 3 random states x 2 wheel(s) against the exact solver" in said
    chk = read_check(copy)
    assert chk.size == 3 and chk.seed == 2
    assert not np.array_equal(chk.states[:3], read_check(out).states[:3])
    assert main(["table", "check", str(tmp_path / "none.zarr"), "3", "--workers", "0"]) == 2
    assert "table not found" in capsys.readouterr().err
    assert main(["table", "check", str(copy), "0", "--workers", "0"]) == 2
    assert main(["table", "check", str(copy), "2", "--workers", "0", "--method",
                 "cubic"]) == 2
    assert "cubic interpolation needs at least 4 nodes" in capsys.readouterr().err
    assert main(["table", "check", str(copy), "2", "--workers", "0", "--seed", "-1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--seed must be a non-negative integer" in err, err
    spec_path, _ = checked
    assert main(["table", "build", str(spec_path), "-o", str(tmp_path / "n.zarr"),
                 "--check", "-1"]) == 2
    assert "--check must be a number of states >= 0" in capsys.readouterr().err
    assert not (tmp_path / "n.zarr").exists()


def test_a_hole_is_the_whole_force_and_counted():
    """A table whose node failed (not converged, NaN) gives no value in the cells around
    it: the check counts those samples as holes and their error is the whole force (what a
    table step gives there: zero forces)."""
    from railcontact.table.variables import QUANTITIES

    ys = np.array([0.0, 1.0e-3, 2.0e-3])
    values = np.zeros((3, 1, len(QUANTITIES)))
    names = [q.name for q in QUANTITIES]
    values[:, 0, names.index("normal_force")] = 80e3
    values[:, 0, names.index("contact_angle")] = 0.05
    status = np.zeros((3, 1), dtype=np.int8)
    status[2, 0], values[2, 0] = 1, np.nan
    table = ContactTable({"lateral_displacement": ys}, ("left",), values, status,
                         {"normal": {"load": 80e3}}, flange=(-0.03845, 1.22193))
    states = np.array([[0.5e-3], [1.5e-3]])
    exact = np.array([[[80e3, 0.0, 0.0, 0.05, 1]], [[90e3, 0.0, 0.0, 0.05, 1]]])
    chk = Check(("lateral_displacement",), ("left",), states, exact,
                np.zeros((2, 1), dtype=np.int8), np.array([80e3, 80e3]), 0.3, 0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        measure(table, chk)
    assert chk.errors["normal_force"][:, 0].tolist() == [0.0, 1.0]
    assert chk.table_status[:, 0].tolist() == [0, 1]
    rows = regions(chk, table.axes)
    assert [r["holes"] for r in rows] == [0, 1]




FLANGE = """
name = "flange_root"
[material]
young = 206e9
poisson = 0.28
[geometry]
type = "wheel-rail"
wheel = "S1002"
rail = "60E1"
inclination = 0.024994793618920156
side = "left"
[grid]
dx = 0.002
dy = 0.002
[normal]
load = 80e3
[tangential]
creepage = [0.0, 0.0, 0.0]
friction = 0.3
[table]
"""
AXES_FIRST = {"lateral first": "lateral_displacement = [0.003, 0.007, 3]\n"
                               "creepage_y = [0.0, 0.002, 2]\n",
              "lateral last": "creepage_y = [0.0, 0.002, 2]\n"
                              "lateral_displacement = [0.003, 0.007, 3]\n"}


@pytest.mark.parametrize("order", list(AXES_FIRST))
def test_refinement_across_the_flange_root_reduces_the_checked_error(order, scheduler,
                                                                     tmp_path, capsys):
    """S1002 on 60E1, left wheel at 3, 5, 7 mm: the contact jumps to the flange root
    between 6.5 and 7 mm (contact angle from 0.55 to 1.18 rad, normal force from 102 to
    307 kN at 80 kN). Refining the lateral axis twice where the check's error or the
    contact angle step exceeds the targets adds nodes there only, solves only the new
    points (the old ones kept bit for bit), keeps the axis strictly increasing, and the
    error measured at other random states (another seed) against the exact solver falls.
    The lateral axis is the slow one (whole batches new) or the fastest (new points inside
    the batches)."""
    from railcontact.table.check import overall

    (tmp_path / "spec.toml").write_text(FLANGE + AXES_FIRST[order])
    out = tmp_path / "t.zarr"
    assert main(["table", "build", str(tmp_path / "spec.toml"), "-o", str(out),
                 "--scheduler", scheduler, "--quiet", "--check", "12", "--seed", "1"]) == 0
    before_table = ContactTable.open(out)

    def independent(path):  # another seed's states, on a copy (the kept check unchanged)
        copy = tmp_path / f"copy{len(list(tmp_path.iterdir()))}.zarr"
        shutil.copytree(path, copy)
        return check_table(copy, 12, seed=2)

    before = independent(out)
    capsys.readouterr()
    assert main(["table", "show", str(out)]) == 0  # the jump, seen before any check
    text = capsys.readouterr().out
    assert "contact jumps between neighbouring nodes" in text
    assert re.search(r"  lateral_displacement: [12] of 2 interval\(s\)", text)
    assert "  creepage_y:" not in text
    assert main(["table", "refine", str(out), "--axes", "lateral_displacement",
                 "--rounds", "2", "--scheduler", scheduler, "--quiet"]) == 0
    said = capsys.readouterr().out
    assert "round 1: lateral_displacement +2" in said and "round 2:" in said
    assert "; 10 points, 4 computed" in said  # only the new points: 2 new nodes x 2 etas
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        table = ContactTable.open(out)
    ys = table.axes["lateral_displacement"]
    assert np.all(np.diff(ys) > 0) and set(before_table.axes["lateral_displacement"]) <= set(ys)
    assert table.axes["creepage_y"].tolist() == [0.0, 0.002]
    assert 3 < len(ys) < 9  # not every interval split twice: where the contact jumps
    assert np.isclose(ys, 0.0065).any() and not np.isclose(ys, 0.0035).any()
    spec = load_spec(tmp_path / "spec.toml")
    for index in np.ndindex(*spec.shape):  # the old nodes: copied, not solved again
        new_index = tuple(int(np.searchsorted(table.axes[n], spec.axes[n][i]))
                          for n, i in zip(spec.names, index, strict=True))
        assert table.node(new_index).values == before_table.node(index).values
    # a new node where it is a batch's first point (a cold start): railcontact solve's
    y_new = [y for y in ys if y not in spec.axes["lateral_displacement"]]
    k = table.names.index("normal_force")
    if order == "lateral first":
        i = int(np.searchsorted(ys, y_new[0]))
        exact = _exact(spec.case_at_values({"lateral_displacement": y_new[0],
                                            "creepage_y": 0.0}), "left")
        assert table._values[i, 0, 0, k] == exact["N"]
    after = independent(out)
    assert np.array_equal(after.states, before.states)
    assert np.array_equal(after.exact, before.exact, equal_nan=True)  # the same truth
    b, a = overall(before), overall(after)
    assert a["normal_force"]["max"] < 0.5 * b["normal_force"]["max"]
    assert a["contact_angle"]["max"] < 0.5 * b["contact_angle"]["max"]
    assert b["normal_force"]["max"] > 0.3  # the jump: the coarse table errs by 30 % and more
    # the kept check was measured again at its states (the same exact values): show
    # prints the error after
    kept = read_check(out)
    assert overall(kept)["normal_force"]["max"] < 0.5 * b["normal_force"]["max"]
    assert main(["table", "show", str(out)]) == 0
    text = capsys.readouterr().out
    assert re.search(rf"lateral_displacement +\[m\] +{len(ys)} from 0.003 to 0.007", text)
    assert "refined, round 2: lateral_displacement +" in text


def test_jumps_flag_the_intervals_where_the_contact_changes():
    """A patch count or a contact angle step above the target, or contact that appears,
    flags the interval of that axis only."""
    from railcontact.table.refine import jumps

    axes = {"lateral_displacement": np.array([0.0, 1.0, 2.0, 3.0]),
            "creepage_y": np.array([0.0, 1.0])}
    status = np.zeros((4, 2, 1), dtype=np.int8)
    patches = np.ones((4, 2, 1))
    angle = np.tile(np.array([0.0, 0.01, 0.02, 0.03])[:, None, None], (1, 2, 1))
    assert [v.tolist() for v in jumps(axes, status, patches, angle, 0.05).values()] == [
        [False, False, False], [False]]
    patches[2, 1, 0] = 2  # a second patch at node 2 (creepage node 1)
    angle[3, 0, 0] = 0.2  # the contact angle jumps between nodes 2 and 3
    j = jumps(axes, status, patches, angle, 0.05)
    assert j["lateral_displacement"].tolist() == [False, True, True]
    assert j["creepage_y"].tolist() == [True]
    status[0, 0, 0] = 2  # no contact at node 0: contact appears between 0 and 1
    assert jumps(axes, status, patches, angle, 0.05)["lateral_displacement"].tolist() == [
        True, True, True]


def test_a_check_on_a_cluster_without_workers_is_an_error_after_the_timeout(checked, tmp_path,
                                                                           capsys):
    from distributed import LocalCluster

    _, out = checked
    copy = tmp_path / "c.zarr"
    shutil.copytree(out, copy)
    with LocalCluster(n_workers=0, processes=True, dashboard_address=":0") as cluster:
        code = main(["table", "check", str(copy), "2", "--scheduler",
                     cluster.scheduler_address, "--lost-timeout", "2"])
    assert code == 2
    assert "had no worker for 2 s during the check" in capsys.readouterr().err
    assert read_check(copy).size == 5  # the kept check unchanged


def test_refine_bad_input_and_nothing_to_do(checked, tmp_path, capsys):
    """Bad refine options are errors before anything is solved; targets that nothing
    exceeds (and no contact jump on the tread) leave the table unchanged."""
    _, out = checked
    copy = tmp_path / "c.zarr"
    shutil.copytree(out, copy)
    for extra, words in ((["--axes", "yaw"], "yaw not an axis of the table"),
                         (["--target", "pressure=1"], "--target takes MEASURE=VALUE"),
                         (["--target", "normal_force=-1"], "target normal_force must be > 0"),
                         (["--target", "normal_force=x"], "not a number"),
                         (["--rounds", "0"], "--rounds must be at least 1")):
        assert main(["table", "refine", str(copy), *extra, "--workers", "1"]) == 2
        assert words in capsys.readouterr().err
    before = {p: p.read_bytes() for p in copy.rglob("*") if p.is_file()}
    assert main(["table", "refine", str(copy), "--target", "normal_force=10", "--target",
                 "creep_force=10", "--target", "contact_angle=10", "--quiet"]) == 0
    assert "nothing exceeds the targets; unchanged" in capsys.readouterr().out
    assert {p: p.read_bytes() for p in copy.rglob("*") if p.is_file()} == before


def test_a_check_needs_a_complete_table_and_a_method_its_axes_fit(checked, tmp_path,
                                                                   capsys):
    """`table check` refuses a store not complete (its points not computed would be
    compared as zero forces), as `refine` does; `table build --check N --method cubic` on
    axes too short for it is refused before anything is built (after the build before)."""
    import zarr

    spec_path, out = checked
    partial = tmp_path / "partial.zarr"
    shutil.copytree(out, partial)
    zarr.open_group(str(partial), mode="r+").attrs["complete"] = 0
    assert main(["table", "check", str(partial), "4", "--workers", "0"]) == 2
    assert "the table is not complete" in capsys.readouterr().err
    fresh = tmp_path / "never.zarr"
    assert main(["table", "build", str(spec_path), "-o", str(fresh), "--check", "3",
                 "--method", "cubic", "--workers", "1", "--quiet"]) == 2
    assert "cubic interpolation needs at least 4 nodes" in capsys.readouterr().err
    assert not fresh.exists()
