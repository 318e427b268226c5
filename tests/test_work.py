"""Every iteration counts: the work a result reports is all the work its solve did.

Each test wraps the BEM solvers so that every call (load passes, re-meshes, roll passes,
discarded secant steps) is counted independently of the bookkeeping under test, and
compares the totals the result reports with that count.
"""

from __future__ import annotations

import json

import pytest

import railcontact as rc
import railcontact.contact.patch as patch_module
import railcontact.timestep.wheel as step_wheel
from railcontact.io.jsonout import solution_json
from railcontact.status import Work

WORK_KEYS = {"normal_iterations", "tangential_iterations", "load_passes", "remeshes", "seconds"}


@pytest.fixture
def calls(monkeypatch):
    """Every normal and tangential BEM solve made through the patch solvers and the time
    step's compiled tangential stage."""
    log = {"normal": [], "tangential": []}
    normal = patch_module.solve_normal

    def counted_normal(*args, **kwargs):
        res = normal(*args, **kwargs)
        log["normal"].append(res.iterations)
        return res

    def counted(solver):
        def counted_tangential(*args, **kwargs):
            res = solver(*args, **kwargs)
            log["tangential"].append(res.iterations)
            return res
        return counted_tangential

    monkeypatch.setattr(patch_module, "solve_normal", counted_normal)
    for name, solver in patch_module.SOLVERS.items():
        monkeypatch.setitem(patch_module.SOLVERS, name, counted(solver))
    stage = step_wheel.warm_tangential  # (a warm patch's tangential solve in one call)

    def counted_stage(patch, *args, **kwargs):
        patch, done, rate = stage(patch, *args, **kwargs)
        if done:
            log["tangential"].append(patch.tangential.iterations)
        return patch, done, rate
    monkeypatch.setattr(step_wheel, "warm_tangential", counted_stage)
    normal_stage = step_wheel.warm_normal  # (a warm patch's first normal solve in one call)

    def counted_normal_stage(*args, **kwargs):
        staged = normal_stage(*args, **kwargs)
        if staged is not None:
            log["normal"].append(staged[0].iterations)
        return staged
    monkeypatch.setattr(step_wheel, "warm_normal", counted_normal_stage)
    return log


def wheel_rail(**geometry) -> dict:
    case = {"material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "wheel-rail", "lateral_displacement": -2e-3, **geometry},
            "grid": {"nx": 32, "ny": 32}, "normal": {"load": 83.3e3},
            "tangential": {"creepage": [2e-4, 2e-4, 0.2], "friction": 0.4}}
    return case


def test_regrown_potential_area_counts_every_solve(calls):
    """A potential area too small for the contact (margin 0.6) is grown and solved again;
    the work holds both solves."""
    case = {"material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "quadratic", "A": 1.0, "B": 5.0},
            "grid": {"dx": 5e-4, "dy": 2e-4, "margin": 0.6}, "normal": {"penetration": 1e-4}}
    sol = rc.solve(case)
    (p,) = sol.patches
    assert len(calls["normal"]) >= 2
    assert p.work.remeshes == len(calls["normal"]) - 1
    assert p.work.normal_iterations == sum(calls["normal"]) > p.normal.iterations
    assert p.work.load_passes == 1 and sol.work.seconds >= p.work.seconds > 0


def test_creep_load_passes_count_every_solve(calls):
    """A wheel load with creep forces takes several normal + tangential passes (and normal
    passes that form the patch frame again at the reference point); the patch reports all
    of them."""
    sol = rc.solve(wheel_rail())
    (p,) = sol.patches
    assert p.work.load_passes == len(calls["normal"]) - p.work.remeshes
    assert p.work.load_passes >= len(calls["tangential"]) >= 2
    assert p.work.normal_iterations == sum(calls["normal"]) > p.normal.iterations
    assert p.work.tangential_iterations == sum(calls["tangential"]) > p.tangential.iterations
    w = sol.work
    assert (w.normal_iterations, w.tangential_iterations) == (sum(calls["normal"]),
                                                              sum(calls["tangential"]))


def test_two_patch_approach_passes_count_every_solve(calls):
    """A wheel load shared by two patches (5 mm, 20 kN: tread and gauge corner) is met by a
    secant on the vertical approach; the totals over the patches are all the solves."""
    case = wheel_rail(lateral_displacement=5e-3)
    case["normal"]["load"] = 20e3
    del case["tangential"]
    sol = rc.solve(case)
    assert len(sol.patches) == 2
    assert sum(p.work.normal_iterations for p in sol.patches) == sum(calls["normal"])
    assert sol.work.normal_iterations == sum(calls["normal"])
    assert all(p.work.load_passes > 2 for p in sol.patches)


def test_equal_loads_roll_passes_count_every_solve(calls):
    """Both wheels at equal loads: every roll pass solves both wheels, and counts."""
    case = wheel_rail(roll="equal-loads", side="both")
    del case["tangential"]
    sol = rc.solve(case)
    assert len(sol.patches) == 2 and len(calls["normal"]) > 2
    assert sol.work.normal_iterations == sum(calls["normal"])
    assert sum(p.work.load_passes for p in sol.patches) == len(calls["normal"])
    assert sol.work.load_passes == len(calls["normal"])  # each wheel's passes, added


def test_json_reports_the_work_of_each_patch_and_the_total():
    d = json.loads(solution_json(rc.solve(wheel_rail())))
    assert set(d["work"]) == WORK_KEYS
    for p in d["patches"]:
        assert set(p["work"]) == WORK_KEYS
        assert p["work"]["normal_iterations"] >= p["normal"]["iterations"]
        assert p["work"]["tangential_iterations"] >= p["tangential"]["iterations"]


def test_wheelset_step_counts_every_solve(calls):
    """A time step with wheel loads and creepages: each wheel's iterations are all the
    solves made for it. At the rigid point, where each load pass is one normal and one
    tangential solve (in the frame at the reference point a cold pass may form the frame
    again, a normal solve without a tangential one: load_passes counts those too)."""
    wc = rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), 1 / 40),
                            rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                            rc.ElasticPair.of(rc.STEEL, rc.STEEL),
                            rc.ContactSettings(element_size=1e-3, warm_start="none",
                                               patch_frame="rigid"))
    r = wc.solve(rc.Pose(3e-3), loads=(83.3e3, 83.3e3),
                 creepages=((2e-4, 2e-4, 0.2), (2e-4, 2e-4, 0.2)))
    assert r.status == 0
    assert sum(w.normal_iterations for w in r.wheels) == sum(calls["normal"])
    assert sum(w.tangential_iterations for w in r.wheels) == sum(calls["tangential"])
    assert sum(w.load_passes for w in r.wheels) == len(calls["tangential"])
    assert all(w.seconds > 0 for w in r.wheels)


def _counts(works) -> tuple[int, int]:
    return (sum(w.normal_iterations for w in works), sum(w.tangential_iterations for w in works))


@pytest.mark.parametrize("warm", [False, True])
def test_rigid_wheelset_solves_count(calls, warm):
    """Under load control the rigid wheelset's stage solves the wheels again at other
    rolls; those solves are the step's work too (the FMU's iteration outputs): the
    wheels' counts plus :attr:`WheelsetResult.rigid_work` are every solve the step made
    (counted independently at the solvers), cold and from the previous step."""
    wc = rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), 1 / 40),
                            rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                            rc.ElasticPair.of(rc.STEEL, rc.STEEL),
                            rc.ContactSettings(element_size=1e-3, rigid_wheelset="solve",
                                               warm_start="previous" if warm else "none"))
    creep = ((2e-4, 2e-4, 0.2), (2e-4, 2e-4, 0.2))
    t = 0.0
    if warm:
        first = wc.solve(rc.Pose(2.9e-3), loads=(83.3e3, 83.3e3), creepages=creep, time=0.0)
        assert first.rigid_solution.converged  # its root starts this step's search
        t = 1e-3
        for log in calls.values():
            log.clear()
    r = wc.solve(rc.Pose(3e-3), loads=(83.3e3, 83.3e3), creepages=creep, time=t)
    s = r.rigid_solution
    assert s.converged and s.evaluations >= 1
    wheels, rigid = _counts(r.wheels), _counts(r.rigid_work)
    assert rigid[0] > 0  # the root is not the pose's roll: the wheels were solved again
    assert (sum(calls["normal"]), sum(calls["tangential"])) == (wheels[0] + rigid[0],
                                                                wheels[1] + rigid[1])
    assert all(w.load_passes >= 1 and w.seconds > 0 for w in r.rigid_work)
    assert r.rigid_work == s.wheel_work
    # the search's own work is a Work, as every solver result's: both wheels' solves
    assert isinstance(s.work, Work)
    assert (s.work.normal_iterations, s.work.tangential_iterations) == rigid
    assert s.work.load_passes == sum(w.load_passes for w in r.rigid_work)


def test_a_grown_area_keeps_the_fixed_extent_of_a_snapped_grid():
    """Review finding: with element sizes and snap, a grid is a little wider than the area
    asked for; growing the automatic y from the grid's bounds also widened the user's x,
    one element per growth. The given x stays as asked (to an element)."""
    from railcontact.contact import WarmStart
    from railcontact.contact.patch import make_grid, solve_patch_normal
    from railcontact.settings import Control, GridSettings, NormalSettings

    gs = GridSettings(dx=2e-4, dy=2e-4, snap=True)
    pair = rc.ElasticPair.of(rc.STEEL, rc.STEEL)

    def gap(g):
        X, Y = g.mesh()
        return 1.0 * X**2 + 5.0 * Y**2

    bounds = (-12e-3, 12e-3, -0.5e-3, 0.5e-3)  # y far too small: grown several times
    first = make_grid(gs, bounds)
    res, work = solve_patch_normal(gap, bounds, gs, NormalSettings(), pair,
                                   Control(load=74e3), WarmStart("none"), (False, True))
    assert work.remeshes >= 2
    assert res.grid.nx == first.nx


def test_rigid_work_is_each_step_own(calls):
    """The rigid stage's work is its own step's search, not a running counter over the
    steps: in each of three steps the solvers' own count is the wheels' plus the stage's."""
    wc = rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), 1 / 40),
                            rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                            rc.ElasticPair.of(rc.STEEL, rc.STEEL),
                            rc.ContactSettings(element_size=1e-3, rigid_wheelset="solve"))
    creep = ((2e-4, 2e-4, 0.2), (2e-4, 2e-4, 0.2))
    for k, y in enumerate((3e-3, 3.1e-3, 3.2e-3)):
        for log in calls.values():
            log.clear()
        r = wc.solve(rc.Pose(y), loads=(83.3e3, 83.3e3), creepages=creep, time=k * 1e-3)
        wheels, rigid = _counts(r.wheels), _counts(r.rigid_work)
        assert r.rigid_solution.converged and rigid[0] > 0
        assert (sum(calls["normal"]), sum(calls["tangential"])) == (wheels[0] + rigid[0],
                                                                    wheels[1] + rigid[1])
