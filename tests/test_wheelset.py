"""WheelsetContact: both wheels per time step, frames, kinematic creepages, warm start."""

from __future__ import annotations

import math

import numpy as np
import pytest

from railcontact.errors import RailContactError
from railcontact.geometry.profiles import read_profile
from railcontact.geometry.track import Pose, Track, Wheelset
from railcontact.halfspace.materials import ElasticPair, Material
from railcontact.timestep.validity import Y_Q
from railcontact.timestep.wheelset import (
    NO_CONTACT,
    NOT_CONVERGED,
    OK,
    OUTSIDE_VALIDITY,
    ContactSettings,
    Kinematics,
    WheelsetContact,
)

Q = 83.3e3


def contact(**settings) -> WheelsetContact:
    mat = Material(206e9, 0.28)
    return WheelsetContact(Track(read_profile("60E1", "rail"), math.atan(1 / 40)),
                           Wheelset(read_profile("S1002", "wheel"), 0.46),
                           ElasticPair.of(mat, mat), ContactSettings(**settings))


@pytest.fixture(scope="module")
def centred():
    """Centred wheelset, pure rolling at V = 30 m/s (kinematic creepages)."""
    wc = contact(warm_start="none")
    return wc.solve(Pose(0.0), loads=(Q, Q), kinematics=Kinematics(30.0))


def test_centred_wheelset_is_mirror_symmetric(centred):
    L, R = centred.left, centred.right
    assert L.status == R.status == OK
    # mirror symmetry of the track about its centre line
    assert R.normal_force == pytest.approx(L.normal_force, rel=1e-9)
    assert R.creep_force[0] == pytest.approx(L.creep_force[0], rel=1e-6)
    assert R.creep_force[1] == pytest.approx(-L.creep_force[1], rel=1e-6)
    assert R.spin_moment == pytest.approx(-L.spin_moment, rel=1e-6)
    assert R.track_force[1] == pytest.approx(-L.track_force[1], rel=1e-6)
    assert centred.force[1] == pytest.approx(0.0, abs=1e-6 * Q)
    assert centred.yaw_moment == pytest.approx(0.0, abs=1e-6 * Q)


def test_centred_forces_balance_the_load(centred):
    L = centred.left
    g = L.contact_angle
    # load control: the vertical force of the rail, normal and creep forces, is the load
    assert L.track_force[2] == pytest.approx(Q, rel=1e-3)
    assert L.track_force[2] == pytest.approx(
        L.normal_force * math.cos(g) + L.creep_force[1] * math.sin(g), rel=1e-12)
    # the rail pushes the left wheel towards the track centre (-Y) through the cone
    assert L.track_force[1] < 0


@pytest.mark.parametrize("eta", [0.01, -0.01])
def test_wheel_load_on_a_sliding_flange_follows_nadal(eta):
    """Left wheel on its 70 deg flange, sliding across it: the creep force is mu N and the
    wheel load Q = N cos(gamma) + F_s sin(gamma) gives N = Q / (cos(gamma) -+ mu sin(gamma))
    (Nadal's balance). N's error is the load tolerance's plus the few leading-edge elements
    still in adhesion (~1e-4 of mu N, which the climbing direction amplifies by
    mu sin(gamma) / (cos(gamma) - mu sin(gamma)) ~ 5). With the creep forces left out,
    N cos(gamma) = Q instead. At the rigid point, whose angle is the flange's 70 deg (the
    frame at the reference point takes the overlap's weighted angle, 64-69 deg here as N
    changes with the creep direction: Nadal's balance is checked at one known angle)."""
    mu, tol = 0.3, 1e-3
    creep = ((0.0, eta, 0.0), (0.0, 0.0, 0.0))
    for warm in ("none", "previous+estimate"):
        wc = contact(friction=mu, warm_start=warm, element_size=1e-3, load_tolerance=tol,
                     patch_frame="rigid")
        r = wc.solve(Pose(7e-3), loads=(Q, 0.6 * Q), creepages=creep)
        L = r.left
        g, n = L.contact_angle, L.normal_force
        # solved, and outside validity: full sliding on the flange, Y/Q >= Nadal's limit
        assert L.status == OUTSIDE_VALIDITY and L.validity & Y_Q
        assert math.degrees(g) == pytest.approx(70.0, abs=0.5)
        assert L.creep_force[1] == pytest.approx(-math.copysign(mu * n, eta), rel=3e-4)
        assert L.track_force[2] == pytest.approx(Q, rel=tol)
        assert n == pytest.approx(Q / (math.cos(g) - math.copysign(mu, eta) * math.sin(g)),
                                  rel=2 * tol)
        assert L.load_passes > 1
        assert r.right.track_force[2] == pytest.approx(0.6 * Q, rel=tol)
        # the same step again: the remembered creep share is the first guess
        if warm != "none":
            assert wc.solve(Pose(7e-3), loads=(Q, 0.6 * Q), creepages=creep
                            ).left.load_passes == 1
    wc = contact(friction=mu, warm_start="none", element_size=1e-3, load_includes_creep=False,
                 patch_frame="rigid")
    L = wc.solve(Pose(7e-3), loads=(Q, 0.6 * Q), creepages=creep).left
    assert L.normal_force * math.cos(L.contact_angle) == pytest.approx(Q, rel=1e-9)
    assert L.load_passes == 1


def test_wheel_load_beyond_nadals_limit_is_reported():
    """mu = 0.4 on a 70 deg flange, sliding up: mu tan(gamma) = 1.1 > 1, the creep force
    pulls the wheel up more than the normal force pushes it; no normal force carries the
    load. The wheel says so (status 'not converged', message naming Nadal), the other
    wheel is solved. At the rigid point (70 deg): in the frame at the reference point the
    overlap's weighted angle is 64 deg, mu tan(gamma) = 0.82 < 1, and the load is carried
    (outside validity)."""
    wc = contact(friction=0.4, warm_start="none", element_size=1e-3, patch_frame="rigid")
    r = wc.solve(Pose(7e-3), loads=(Q, Q), creepages=((0.0, 0.01, 0.0), (0.0, 0.0, 0.0)))
    assert r.left.status == NOT_CONVERGED and "Nadal" in r.left.message
    assert r.left.track_force[2] < 0
    assert r.right.status == OK
    assert r.right.track_force[2] == pytest.approx(Q, rel=1e-3)


def test_kinematic_creepages_of_pure_rolling(centred):
    r0 = 0.46
    for w, s in ((centred.left, 1), (centred.right, -1)):
        xi, eta, phi = w.creepages[0]
        assert xi == pytest.approx(1 - w.rolling_radius / r0, abs=1e-12)
        assert eta == 0.0
        assert phi == pytest.approx(-s * math.sin(w.contact_angle) / r0, rel=1e-12)


def test_creep_force_opposes_creepage_and_is_linear_for_small_creepage():
    wc = contact(warm_start="none")
    f = []
    for xi in (1e-5, 2e-5):
        r = wc.solve(Pose(0.0), loads=(Q, Q), creepages=((xi, 0, 0), (xi, 0, 0)))
        f.append(r.left.creep_force[0])
    assert f[0] < 0  # F_x = -f11 xi on the wheel
    assert f[1] / f[0] == pytest.approx(2.0, rel=0.02)


def test_lift_off_and_out_of_range():
    wc = contact()
    r = wc.solve(Pose(0.0), loads=(0.0, Q), creepages=((1e-3, 0, 0), (1e-3, 0, 0)))
    assert r.left.status == NO_CONTACT and r.left.normal_force == 0.0
    assert r.right.status == OK and r.right.normal_force > 0
    with pytest.raises(RailContactError):
        wc.solve(Pose(0.0), loads=(float("nan"), Q))
    with pytest.raises(RailContactError):
        Kinematics(0.0)


def test_penetration_control_from_vertical_displacement():
    wc = contact(warm_start="none")
    load = wc.solve(Pose(1e-3), loads=(Q, Q))
    # lower the wheelset by the approach the load needed: same forces back
    from railcontact.geometry.search import vertical_gap

    g = vertical_gap(wc.track, wc.wheelset, Pose(1e-3), "left")[4].min()
    approach = load.left.approach  # beyond first contact (in either patch frame)
    r = wc.solve(Pose(1e-3), vertical=-(g + approach))
    assert r.left.normal_force == pytest.approx(load.left.normal_force, rel=1e-3)
    # lifted: no contact
    assert wc.solve(Pose(1e-3), vertical=0.01).left.status == NO_CONTACT


def test_warm_start_from_previous_step_cuts_iterations_not_accuracy():
    """Hunting-like motion at 1 ms steps: 'previous' needs far fewer iterations than a
    cold start and gives the same forces within the solver tolerance."""
    runs = {}
    for mode in ("none", "previous"):
        wc = contact(warm_start=mode)
        its, fy = [], []
        for k in range(8):
            t = k * 1e-3
            y = 3e-3 * math.sin(2 * math.pi * 1.5 * t + 0.3)
            r = wc.solve(Pose(y, 1e-3 * math.cos(2 * math.pi * 1.5 * t)), loads=(Q, Q),
                         kinematics=Kinematics(30.0, 0.03), time=t)
            its.append(sum(w.normal_iterations + w.tangential_iterations for w in r.wheels))
            fy.append([r.left.creep_force[0], r.left.creep_force[1], r.right.creep_force[1],
                       r.left.normal_force])
        runs[mode] = (np.mean(its[2:]), np.array(fy))
    cold, warm = runs["none"][0], runs["previous"][0]
    assert warm < cold / 3
    # both stop at eps_tau = 1e-2: agree to a fraction of the largest creep force mu N
    np.testing.assert_allclose(runs["previous"][1], runs["none"][1], rtol=0,
                               atol=0.005 * 0.4 * Q)


def test_warm_step_meshes_where_the_contact_was_and_grows_when_it_moves():
    """A warm step meshes the previous steps' contact with a margin (far fewer elements
    than the Hertz potential area of a cold step); where the patch has moved or grown out
    of it, the area is grown and the patch solved again (a re-mesh). Either way the forces
    are those of a cold solve, within the solvers' tolerances. At the rigid point, where a
    cold step's Hertz area is the rigid point's curvatures' (in the frame at the reference
    point B is the overlap's parabola, a tighter area: 56 x 64 elements against the warm
    step's 48 x 64). The Hertz area compared with is the rigid interpenetration area with
    a margin of 1.2 (the default margin is 1.0: a cold step's area is then only a little
    larger than the warm box)."""
    kin = Kinematics(30.0, 0.02)
    rigid = {"patch_frame": "rigid"}
    warm, cold = contact(warm_start="previous", **rigid), contact(warm_start="none", **rigid)
    hertz_area = contact(warm_start="none", load_includes_creep=False, margin=1.2,
                         **rigid)  # one pass
    steps = [(0.0, Q), (1e-3, Q), (1.05e-3, Q), (1.1e-3, 2 * Q)]  # lateral [m], load [N]
    for k, (y, q) in enumerate(steps):
        t = k * 1e-3
        rw = warm.solve(Pose(y), loads=(q, q), kinematics=kin, time=t)
        rc_ = cold.solve(Pose(y), loads=(q, q), kinematics=kin, time=t)
        for w, c in zip(rw.wheels, rc_.wheels, strict=True):
            assert w.status == c.status == OK
            assert w.normal_force == pytest.approx(c.normal_force, rel=2e-3)
            np.testing.assert_allclose(w.creep_force, c.creep_force, rtol=0,
                                       atol=0.005 * 0.4 * q)
        if k == 2:  # a small move: the previous contact's box, no re-mesh
            rh = hertz_area.solve(Pose(y), loads=(Q, Q), kinematics=kin, time=t)
            for w, h in zip(rw.wheels, rh.wheels, strict=True):
                gw, gh = w.patches[0].normal.grid, h.patches[0].normal.grid
                assert gw.size < 0.75 * gh.size and w.remeshes == 0
    # the doubled load grew the left patch out of the box it was meshed on
    assert rw.left.remeshes >= 1
