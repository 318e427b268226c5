"""The cold load loop's shortcuts: the first normal share from an estimate of the creep
forces' vertical share, and the first frame pass of a cold wheel solved as a probe."""

from __future__ import annotations

import math

import pytest

import railcontact as rc
import railcontact.contact.patch as patch_module
from railcontact.contact.loadloop import (
    PROBE_COARSE_TOLERANCE,
    PROBE_COARSENING,
    PROBE_FACTOR,
    probe_settings,
    vertical_creep_estimate,
)
from railcontact.geometry.search import contact_points
from railcontact.halfspace.hertz import hertz
from railcontact.tangential.fastrip import fastrip_hertz

Q = 83.3e3
MU = 0.4


def wheelset(**settings) -> rc.WheelsetContact:
    return rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
                              rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                              rc.ElasticPair.of(rc.STEEL, rc.STEEL),
                              rc.ContactSettings(friction=MU, **settings))


def test_creep_share_estimate_is_kalker_when_small_and_sliding_when_large():
    """Small creepages: Kalker's linear theory, as FaStrip (scaled to it) gives on the same
    Hertz ellipse (200 x 200 samples: its strip ends converge slowly, 2.7 % under Kalker's
    C22 here); large ones: full sliding, F_s = -mu N, so F_s sin(gamma) = -mu Q tan(gamma)
    for a vertical load Q."""
    wc = wheelset()
    cp = contact_points(wc.track, wc.wheelset, rc.Pose(3e-3), "left", 0.0)[0]
    g = cp.contact_angle
    assert abs(g) > 0.01  # a tilted contact: the share is not zero
    hz = hertz(cp.A, cp.B, wc.pair, load=Q / math.cos(g))
    for creepage in ((0.0, 1e-7, 0.0), (0.0, 0.0, 1e-4), (1e-7, -1e-7, 2e-4)):
        strip = fastrip_hertz(hz.a, hz.b, hz.load, wc.pair, MU, creepage, nx=200,
                              ny=200).force[1]
        est = vertical_creep_estimate(cp, Q, creepage, wc.pair, MU)
        assert est == pytest.approx(strip * math.sin(g), rel=0.04)
    for eta in (0.05, -0.05):
        est = vertical_creep_estimate(cp, Q, (0.0, eta, 0.0), wc.pair, MU)
        assert est == pytest.approx(-math.copysign(MU * Q * math.tan(g), eta), rel=1e-9)
    assert vertical_creep_estimate(cp, Q, (0.0, 0.0, 0.0), wc.pair, MU) == 0.0


@pytest.mark.parametrize("lateral", [0.0, 2e-3])
def test_cold_step_meets_the_load_near_the_estimated_share(lateral):
    """A cold wheelset step with kinematic creepages: each wheel carries its load to the
    load tolerance, creep forces included, and the estimate of their vertical share that
    started the load loop is within 30 % of the BEM's (83.3 kN, 1 mm elements)."""
    wc = wheelset(element_size=1e-3, warm_start="none")
    pose = rc.Pose(lateral)
    kin = rc.Kinematics(30.0, 0.03)
    r = wc.solve(pose, loads=(Q, Q), kinematics=kin)
    assert r.status == 0
    for w in r.wheels:
        (p,) = w.patches
        g = p.geometry.contact_angle
        share = p.tangential.force[1] * math.sin(g)
        vertical = p.normal.force * math.cos(g) + share
        assert vertical == pytest.approx(Q, rel=wc.settings.load_tolerance)
        sgn = 1.0 if w.side == "left" else -1.0
        c = kin.creepage(p.geometry, pose, wc.wheelset.radius)
        est = vertical_creep_estimate(p.geometry, Q, (c[0], sgn * c[1], sgn * c[2]), wc.pair,
                                      MU)
        assert abs(share) > 50.0
        assert est == pytest.approx(share, rel=0.3)


def test_a_cold_wheel_probes_its_frame_and_ends_at_the_full_tolerance(monkeypatch):
    """The first normal solve of a cold wheel in the reference frame is a probe at
    PROBE_FACTOR times the normal tolerance; every later solve, the one reported among
    them, is at the full tolerance; the result is the one without a probe (a probe at the
    full tolerance on the full grid) to that tolerance."""
    tolerances: list[float] = []
    normal = patch_module.solve_normal

    def logged(*args, **kwargs):
        tolerances.append(kwargs["tolerance"])
        return normal(*args, **kwargs)

    monkeypatch.setattr(patch_module, "solve_normal", logged)
    wc = wheelset(element_size=1e-3, warm_start="none")
    tol = wc.settings.normal_tolerance
    assert probe_settings(wc.settings.patch_settings).normal.tolerance == PROBE_FACTOR * tol
    r = wc.solve(rc.Pose(1e-3), loads=(Q, Q))  # normal contact only: one load pass a wheel
    assert r.status == 0
    assert tolerances.count(PROBE_FACTOR * tol) == 2  # one probe per wheel
    assert tolerances[0] == PROBE_FACTOR * tol and tolerances[-1] == tol
    assert len(tolerances) == sum(w.load_passes for w in r.wheels)

    monkeypatch.setattr("railcontact.contact.loadloop.PROBE_FACTOR", 1.0)
    monkeypatch.setattr("railcontact.contact.loadloop.PROBE_COARSENING", 1)
    assert probe_settings(wc.settings.patch_settings).normal.tolerance == tol
    ref = wheelset(element_size=1e-3, warm_start="none").solve(rc.Pose(1e-3), loads=(Q, Q))
    for w, v in zip(r.wheels, ref.wheels, strict=True):
        assert w.approach == pytest.approx(v.approach, rel=10 * tol)
        assert w.max_pressure == pytest.approx(v.max_pressure, rel=10 * tol)


@pytest.mark.parametrize("lateral", [1e-3, 6e-3])  # tread; flange root
def test_a_probe_without_an_estimate_is_coarse_and_the_answer_is_the_full_grids(
        monkeypatch, lateral):
    """Without an estimate the probe is solved on elements PROBE_COARSENING times as large,
    the full pass on the full grid (on the probe's contact box, checked against the rigid
    overlap); the answer is that of solving without the coarse probe, to the solvers'
    tolerance. With the INFCON estimate the probe stays on the full grid."""
    sizes: list[tuple[float, float]] = []
    normal = patch_module.solve_normal

    def logged(gap, grid, op, **kwargs):
        sizes.append((grid.dx, kwargs["tolerance"]))
        return normal(gap, grid, op, **kwargs)

    monkeypatch.setattr(patch_module, "solve_normal", logged)
    h = 0.5e-3
    kin = rc.Kinematics(30.0, 0.02)
    r = wheelset(element_size=h, warm_start="none").solve(rc.Pose(lateral), loads=(Q, Q),
                                                          kinematics=kin)
    assert r.status == 0
    tol = wheelset(element_size=h).settings.normal_tolerance
    probes = [dx for dx, t in sizes if t == PROBE_FACTOR * tol]
    full = [dx for dx, t in sizes if t == tol]
    assert len(probes) == 2 and full  # one probe a wheel
    assert probes == pytest.approx([PROBE_COARSENING * h] * 2, rel=1e-9)
    assert full == pytest.approx([h] * len(full), rel=1e-9)

    sizes.clear()
    assert wheelset(element_size=h, warm_start="estimate").solve(
        rc.Pose(lateral), loads=(Q, Q), kinematics=kin).status == 0
    assert [dx for dx, _ in sizes] == pytest.approx([h] * len(sizes), rel=1e-9)

    monkeypatch.setattr(patch_module, "solve_normal", normal)
    monkeypatch.setattr("railcontact.contact.loadloop.PROBE_COARSENING", 1)
    ref = wheelset(element_size=h, warm_start="none").solve(rc.Pose(lateral), loads=(Q, Q),
                                                            kinematics=kin)
    for w, v in zip(r.wheels, ref.wheels, strict=True):
        assert w.approach == pytest.approx(v.approach, rel=1e-4)
        assert w.max_pressure == pytest.approx(v.max_pressure, rel=tol)
        mu_n = MU * v.normal_force
        assert abs(w.normal_force - v.normal_force) < 1e-4 * v.normal_force
        df = max(abs(a - b) for a, b in zip(w.creep_force, v.creep_force, strict=True))
        assert df < 1e-3 * mu_n


@pytest.mark.parametrize("grid", [{"dx": 0.5e-3, "dy": 0.5e-3}, {"nx": 64, "ny": 64},
                                  {"dx": 0.5e-3, "ny": 40}])  # sizes, counts, mixed
@pytest.mark.parametrize("lateral", [-2e-3, 6e-3])
def test_the_coarse_probe_keeps_estimate_starts_and_the_elements(root, monkeypatch, grid,
                                                                   lateral):
    """A wheel-rail case under load control (``railcontact.solve``), against the same case
    without the coarse probe (PROBE_COARSENING = 1): started from INFCON, or without an
    estimate at a normal tolerance below PROBE_COARSE_TOLERANCE, the same bits (such a
    probe stays on the full grid); without an estimate at the case's 1e-3, the final
    patch's elements within 0.2 % of the same size (given counts: meshed on the cold
    pass's area, not on the probe's contact) and its penetration and largest pressure
    within the normal tolerance."""
    import copy

    import numpy as np

    base = rc.load_case(root / "models" / "cases" / "s1002_60e1_dy-2mm.toml").to_dict()
    base["grid"] = dict(grid)
    base["geometry"]["lateral_displacement"] = lateral
    for estimate, tolerance in (("infcon", 1e-3), ("none", 1e-5), ("none", 1e-3)):
        case = copy.deepcopy(base)
        case["normal"]["estimate"] = estimate
        case["normal"]["tolerance"] = tolerance
        monkeypatch.setattr("railcontact.contact.loadloop.PROBE_COARSENING", 2)
        got = rc.solve(case).patches[0].normal
        monkeypatch.setattr("railcontact.contact.loadloop.PROBE_COARSENING", 1)
        want = rc.solve(case).patches[0].normal
        if estimate == "infcon" or tolerance < PROBE_COARSE_TOLERANCE:
            assert got.grid == want.grid
            assert np.array_equal(got.pressure, want.pressure)
            assert got.iterations == want.iterations
            continue
        tol = case["normal"]["tolerance"]
        assert got.grid.dx == pytest.approx(want.grid.dx, rel=2e-3)
        assert got.grid.dy == pytest.approx(want.grid.dy, rel=2e-3)
        assert got.penetration == pytest.approx(want.penetration, rel=tol)
        assert got.max_pressure == pytest.approx(want.max_pressure, rel=tol)


@pytest.mark.parametrize("lateral", [-2e-3, 7e-3])  # tread; flange
def test_a_tight_solve_does_not_depend_on_its_start(root, lateral):
    """At a normal tolerance of 1e-7 (below PROBE_COARSE_TOLERANCE: no coarse probe, the
    cold frame tolerance) a wheel-rail case under load control reaches the same patch
    from no estimate and from Hertz's pressure: penetration and largest pressure within
    1e-5, the contact angle within 1e-6 rad (a frame formed within 1e-3 of the approach
    moves them by about 1e-4)."""
    import copy

    base = rc.load_case(root / "models" / "cases" / "s1002_60e1_dy-2mm.toml").to_dict()
    base["grid"] = {"dx": 0.5e-3, "dy": 0.5e-3}
    base["geometry"]["lateral_displacement"] = lateral
    base["normal"]["tolerance"] = 1e-7
    got = {}
    for estimate in ("none", "hertz"):
        case = copy.deepcopy(base)
        case["normal"]["estimate"] = estimate
        got[estimate] = rc.solve(case).patches[0]
    a, b = got["none"], got["hertz"]
    assert a.normal.penetration == pytest.approx(b.normal.penetration, rel=1e-5)
    assert a.normal.max_pressure == pytest.approx(b.normal.max_pressure, rel=1e-5)
    assert a.geometry.contact_angle == pytest.approx(b.geometry.contact_angle, abs=1e-6)


def test_the_cold_share_estimate_counts_in_the_wheels_time(monkeypatch):
    """The cold estimate of the creep share is work of the step: its time is in the
    wheel's ``seconds`` (the sum of its patches' work), here made to take 50 ms."""
    import time

    import railcontact.timestep.wheel as wheel_module

    def slow(*args, **kwargs):
        time.sleep(0.05)
        return vertical_creep_estimate(*args, **kwargs)

    monkeypatch.setattr(wheel_module, "vertical_creep_estimate", slow)
    r = wheelset(warm_start="none").solve(rc.Pose(1e-3), loads=(Q, Q),
                                          creepages=((1e-3, 1e-3, 0.0),) * 2)
    assert all(w.status == 0 and w.seconds >= 0.05 for w in r.wheels)


def test_a_warm_flange_step_that_stalls_in_its_load_loop_is_solved_again_cold():
    """S1002 on 60E1, yaw -4 mrad, the left flange at 65.5 deg beyond Nadal's limit
    (Y/Q 2.2), the creep force mostly longitudinal (F_x 73 kN, F_s 1.3 kN). From the
    previous steps' start the third step's load loop stalls 150-180 N off the load (the
    vertical force at one normal share depends on the start by some hundred newtons
    here, SteadyGS's tolerance); cold it meets the load. The step is solved again cold:
    the load met to its tolerance, status 4 (outside validity, for its Y/Q), within what
    a warm step promises against a tight cold solve."""
    from railcontact.timestep.wheelset import WARM_PROMISE

    steel = rc.Material(206e9, 0.28)
    geometry = (rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
                rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                rc.ElasticPair.of(steel, steel))
    warm = rc.WheelsetContact(*geometry, rc.ContactSettings(
        friction=0.4, element_size=5e-4, warm_start="previous+estimate"))
    loads = (83.3e3, 83.3e3)
    for k in (99, 100, 101):
        pose = rc.Pose(9e-3 * (1 - abs(k - 100) / 100), yaw=-0.004)
        kin = rc.Kinematics(30.0, 0.09 if k < 100 else -0.09)
        w = warm.solve(pose, loads=loads, kinematics=kin, time=k * 1e-3).left
    tight = rc.WheelsetContact(*geometry, rc.ContactSettings(
        friction=0.4, element_size=5e-4, warm_start="none", normal_tolerance=1e-6,
        tangential_tolerance=1e-6, load_tolerance=1e-6)).solve(
            pose, loads=loads, kinematics=kin).left
    assert tight.status == w.status == rc.Status.OUTSIDE_VALIDITY, w.message
    assert abs(w.track_force[2] - loads[0]) <= 1e-3 * loads[0]  # (load_tolerance)
    n = tight.normal_force
    assert abs(w.normal_force - n) / n <= WARM_PROMISE[0]
    assert max(abs(a - b) for a, b in zip(w.creep_force, tight.creep_force, strict=True)) \
        <= WARM_PROMISE[1] * 0.4 * n
