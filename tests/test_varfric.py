"""Friction that varies across the profile (``[tangential] friction`` as a table, CONTACT's
VARFRC): CONTACT's own example ``mbench_a22_varfric`` (its planar cases 1-4) within the
targets of ``scripts/validate_varfric.py`` (forces 2 % on the tread, 5 % in the flange,
floor 0.2 % of mu F_N; p_max 1 %, area 3 %), the traction bound ``mu p_n`` element by
element with mu per element, and a table equal everywhere giving exactly the constant
coefficient's solution."""

from __future__ import annotations

import copy
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_tangential import hertz_patch

import railcontact as rc
from railcontact.contact.wheelrail import build_geometry
from railcontact.errors import CaseError, RailContactError
from railcontact.settings import Case
from railcontact.settings.friction import FrictionTable, row_friction, side_friction
from railcontact.tangential import rolling_operator, solve_tangential
from railcontact.tangential.fastsim import fastsim_hertz
from railcontact.tangential.steadygs import solve_steadygs

ROOT = Path(__file__).resolve().parents[1]
SOLVERS = [solve_steadygs, solve_tangential]


def _script():
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        import validate_varfric
    finally:
        sys.path.pop(0)
    return validate_varfric


@pytest.fixture(scope="module")
def varfric():
    v = _script()
    return v, {c["case"]: c for c in v.contact_cases()}


@pytest.mark.parametrize("kinematic", [False, True], ids=["contact-creepages", "kinematics"])
@pytest.mark.parametrize("number", [1, 2, 4])
def test_contact_varfric_example(varfric, number, kinematic):
    """Cases 1 (tread, mu 0.3 beyond the table), 2 (tread, yawed) and 4 (flange, yawed, mu
    0.2076 interpolated) of CONTACT's example: mu read at the patch and the forces within
    the targets, with the creepages CONTACT printed and with those formed from the
    wheelset's velocities (``[kinematics]``, then within 1 % of CONTACT's, floor 1e-6)."""
    v, cases = varfric
    case = cases[number]
    (theirs,) = case["patches"]
    sol = rc.solve(v.case_dict(case, None if kinematic else theirs, "patch"))
    assert sol.converged
    (p,) = sol.patches
    ours = v.values(p, theirs)
    assert abs(ours["mu"] - theirs["mu"]) < 2e-3  # CONTACT's at the wheel's angle
    assert v.misses(ours, theirs) == [], (ours, theirs)
    if kinematic:
        xi, eta, phi = p.reported_creepage
        for a, b, floor in ((xi, theirs["cksi"], 1e-6), (eta, theirs["ceta"], 1e-6),
                            (phi * 1e-3, theirs["cphi"], 1e-9)):
            assert abs(a - b) <= max(0.01 * abs(b), floor), (a, b)


def test_contact_varfric_two_patches_with_contacts_creepages(varfric):
    """Case 3 (two patches 6.8 mm apart, within CONTACT's D_SEP 6 mm and D_TURN 9 mm: their
    angles turned towards each other as CONTACT turns them) with the creepages CONTACT
    printed for each patch: both patches within the targets, mu CONTACT's within 2e-3
    (the kinematic run: ``tests/test_separation.py``)."""
    v, cases = varfric
    case = cases[3]
    theirs = sorted(case["patches"], key=lambda p: abs(p["delta"]))
    ours = sorted(v.solve_own_creepages(case), key=lambda p: abs(p.geometry.contact_angle))
    assert len(ours) == 2
    for p, q in zip(ours, theirs, strict=True):
        got = v.values(p, q)
        assert abs(got["mu"] - q["mu"]) < 2e-3
        assert v.misses(got, q) == [], (got, q)


@pytest.fixture(scope="module")
def flange_case(varfric):
    """Case 4 of the example (a flange patch, contact angle 0.336 rad) as a case dict."""
    v, cases = varfric
    return v.case_dict(cases[4], cases[4]["patches"][0], "patch")


def _with_friction(d: dict, friction) -> dict:
    return {**d, "tangential": {**d["tangential"], "friction": friction}}


@pytest.mark.parametrize("axis, at", [("angle", "row"), ("angle", "patch"),
                                      ("rail_y", "row")])
def test_table_equal_everywhere_is_the_constant(flange_case, axis, at):
    """A table with one coefficient everywhere gives exactly (bit for bit) the solution of
    that coefficient as a number."""
    points = [-0.4, 0.0, 0.4] if axis == "angle" else [-0.04, 0.0, 0.03]
    table = {axis: points, "mu": [0.25] * 3, "at": at}
    const = rc.solve(_with_friction(flange_case, 0.25))
    varied = rc.solve(_with_friction(flange_case, table))
    (a,), (b,) = const.patches, varied.patches
    assert b.friction == a.friction == 0.25
    assert np.array_equal(a.normal.pressure, b.normal.pressure)
    assert np.array_equal(a.tangential.traction, b.tangential.traction)
    assert a.creep_forces == b.creep_forces


def test_traction_bounded_by_the_local_coefficient(flange_case):
    """mu 0.1 on the steep side of the flange patch and 0.4 on the flat side, per element
    row: every element's traction within its own row's mu p_n, the slip elements on it,
    and the low coefficient binding where the high one would not be."""
    table = {"angle": [-0.345, -0.325], "mu": [0.1, 0.4], "at": "row"}  # CONTACT's sign
    d = _with_friction(flange_case, table)
    (p,) = rc.solve(d).patches
    case = Case.from_dict(d)
    track, _, _ = build_geometry(case.geometry)
    side_table = side_friction(case.tangential.friction, "right", "contact")
    mu = np.broadcast_to(row_friction(side_table, p.geometry, track)(p.normal.grid),
                         p.normal.pressure.shape)
    pn, t = p.normal.pressure, p.tangential
    loaded = pn > 0
    assert mu[loaded].min() == pytest.approx(0.1) and mu[loaded].max() == pytest.approx(0.4)
    size = np.hypot(*t.traction)
    assert np.all(size <= mu * pn * (1 + 1e-12))
    slip = t.state == 2
    assert np.allclose(size[slip], (mu * pn)[slip], rtol=1e-9)
    low = slip & (mu < 0.2)
    assert low.sum() > 10 and np.all(size[low] < 0.2 * pn[low])


@pytest.mark.parametrize("solver", SOLVERS)
def test_full_sliding_force_is_the_sum_of_local_bounds(solver):
    """In full sliding (xi = 0.1) every element carries its bound: the sum of |p| dA is
    the sum of mu p_n dA with mu per lateral row, an exact sum independent of the solver,
    and the force, its tractions nearly parallel, is that sum against the creepage."""
    pair = rc.ElasticPair.of(rc.Material(206e9, 0.28), rc.Material(206e9, 0.28))
    _, g, nr = hertz_patch(1.0, 31, pair=pair)
    mu = np.linspace(0.1, 0.5, g.ny)[None, :]
    res = solver(g, rolling_operator(g, pair), nr.pressure, mu, (0.1, 0.0, 0.0),
                 tolerance=1e-9)
    assert res.converged
    expected = float((mu * nr.pressure).sum() * g.dx * g.dy)
    loaded = nr.pressure > 0
    assert np.all(res.state[loaded] == 2)  # slip everywhere
    assert float(np.hypot(*res.traction).sum() * g.dx * g.dy) == pytest.approx(expected,
                                                                               rel=1e-12)
    assert math.hypot(*res.force) == pytest.approx(expected, rel=1e-5)
    assert res.force[0] == pytest.approx(-expected, rel=1e-5)


@pytest.mark.parametrize("solver", SOLVERS)
def test_per_element_array_equal_to_the_number(solver):
    """A coefficient per element equal everywhere gives the scalar's traction bit for
    bit."""
    pair = rc.ElasticPair.of(rc.Material(206e9, 0.28), rc.Material(206e9, 0.28))
    _, g, nr = hertz_patch(1.0, 25, pair=pair)
    op = rolling_operator(g, pair)
    a = solver(g, op, nr.pressure, 0.3, (2e-3, 1e-3, 0.5), tolerance=1e-6)
    b = solver(g, op, nr.pressure, np.full(g.shape, 0.3), (2e-3, 1e-3, 0.5), tolerance=1e-6)
    assert np.array_equal(a.traction, b.traction) and a.iterations == b.iterations


def test_bad_friction_arrays_are_refused():
    pair = rc.ElasticPair.of(rc.Material(206e9, 0.28), rc.Material(206e9, 0.28))
    _, g, nr = hertz_patch(1.0, 11, pair=pair)
    op = rolling_operator(g, pair)
    for bad in (np.full((3, 2), 0.3), np.full(g.shape, np.nan), np.full((1, g.ny), -0.1)):
        with pytest.raises(RailContactError, match="friction"):
            solve_steadygs(g, op, nr.pressure, bad, (1e-3, 0.0, 0.0))
    hz, _, _ = hertz_patch(1.0, 11, pair=pair)
    with pytest.raises(RailContactError, match="FASTSIM takes one coefficient"):
        fastsim_hertz(hz.a, hz.b, hz.load, pair, np.full(4, 0.3), (1e-3, 0.0, 0.0))


def test_table_interpolates_and_holds_the_ends():
    t = FrictionTable.from_mapping("f", {"angle": [-0.349, -0.1745], "mu": [0.2, 0.3]})
    assert t(-1.0) == 0.2 and t(0.5) == 0.3
    assert t(-0.26175) == pytest.approx(0.25)
    # CONTACT's convention, right wheel: the angles change sign in the side frame
    s = side_friction(t, "right", "contact")
    assert s.points == (0.1745, 0.349) and s.mu == (0.3, 0.2)
    assert side_friction(t, "left", "contact") is t


@pytest.mark.parametrize("friction, message", [
    ({"angle": [0.1, 0.1], "mu": [0.2, 0.3]}, "strictly increasing"),
    ({"angle": [0.2, 0.1], "mu": [0.2, 0.3]}, "strictly increasing"),
    ({"angle": [0.1, 0.2], "mu": [0.0, 0.3]}, "mu must be positive"),
    ({"angle": [0.1, 0.2], "mu": [0.2, float("nan")]}, "finite"),
    ({"angle": [0.1, 0.2], "mu": [0.2]}, "same length"),
    ({"angle": [10.0, 20.0], "mu": [0.2, 0.3]}, "radians"),
    ({"rail_y": [], "mu": []}, "non-empty"),
    ({"angle": [0.1], "rail_y": [0.1], "mu": [0.2]}, "a number or a table"),
    ({"angle": [0.1], "mu": [0.2], "at": "element"}, "at must be one of"),
])
def test_bad_tables_are_refused(flange_case, friction, message):
    with pytest.raises(CaseError, match=message):
        Case.from_dict(_with_friction(flange_case, friction))


def test_a_table_needs_a_wheel_rail_case_and_rows_the_bem(flange_case):
    table = {"angle": [0.1, 0.2], "mu": [0.2, 0.3]}
    quadratic = {"material": {"young": 206e9, "poisson": 0.28},
                 "geometry": {"type": "quadratic", "A": 1.0, "B": 1.0},
                 "normal": {"load": 1e4},
                 "tangential": {"creepage": [1e-3, 0, 0], "friction": table}}
    with pytest.raises(CaseError, match="needs a wheel-rail case"):
        Case.from_dict(quadratic)
    d = _with_friction(flange_case, table)
    with pytest.raises(CaseError, match="needs model = 'bem'"):
        Case.from_dict({**d, "tangential": {**d["tangential"], "model": "fastsim"}})
    # one coefficient per patch: FASTSIM takes it
    fastsim = {**d["tangential"], "model": "fastsim", "friction": {**table, "at": "patch"}}
    assert Case.from_dict({**d, "tangential": fastsim}).tangential.friction.at == "patch"


def test_case_file_round_trip(flange_case):
    table = {"rail_y": [-0.03, -0.02], "mu": [0.1, 0.35], "at": "patch"}
    case = Case.from_dict(_with_friction(flange_case, table))
    assert case.to_dict()["tangential"]["friction"] == table
    assert Case.from_dict(case.to_dict()) == case


def test_case_file_with_a_table_through_the_cli(varfric, tmp_path):
    """A TOML case file with an inline friction table: ``railcontact solve --json --plot``
    reports the patch's coefficient, CONTACT's for case 4 of its example."""
    v, cases = varfric
    case = cases[4]
    d = v.case_dict(case, case["patches"][0], "row")
    g, t = d["geometry"], d["tangential"]
    text = "\n".join([
        'convention = "contact"',
        "[material]", "young = 209.92e9", "poisson = 0.28",
        "[geometry]", 'type = "wheel-rail"', f'wheel = "{g["wheel"]}"', f'rail = "{g["rail"]}"',
        "inclination = 0.0", f"lateral_displacement = {g['lateral_displacement']!r}",
        f"yaw = {g['yaw']!r}", f"roll = {g['roll']!r}", 'side = "right"',
        "[grid]", "dx = 2e-4", "dy = 2e-4",
        "[normal]", "load = 1e4",
        "[tangential]", f"creepage = {list(t['creepage'])!r}",
        "friction = {angle = [-0.3490658504, -0.1745329252], mu = [0.2, 0.3]}", ""])
    path = tmp_path / "varfric.toml"
    path.write_text(text)
    png = tmp_path / "patch.png"
    r = subprocess.run([sys.executable, "-m", "railcontact", "solve", str(path), "--json",
                        "--plot", str(png)], capture_output=True, text=True, timeout=300,
                       cwd=ROOT)
    assert r.returncode == 0, r.stderr
    (patch,) = json.loads(r.stdout)["patches"]
    assert abs(patch["tangential"]["friction"] - case["patches"][0]["mu"]) < 2e-3
    assert png.stat().st_size > 10_000


def test_a_contact_table_refuses_a_friction_table(flange_case):
    """A contact table takes one coefficient of friction: a spec with a friction table is
    refused when it is read, before anything is solved."""
    from railcontact.table.spec import parse_spec

    spec = copy.deepcopy(flange_case)
    spec["table"] = {"lateral_displacement": [0.0, 0.001]}
    with pytest.raises(rc.CaseError, match="one coefficient of friction"):
        parse_spec(spec)
