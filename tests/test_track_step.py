"""Real track in the time step: curvature, rail deviations, profiles per side and friction
per wheel in :class:`~railcontact.timestep.WheelsetContact`, checked against independent
truth - the equivalent yaw rate, the equivalent wheelset displacement, mirror symmetry,
the energy balance of steady rolling and a cold solve of the same step."""

from __future__ import annotations

import math

import numpy as np
import pytest

import railcontact as rc
from railcontact.errors import RailContactError
from railcontact.geometry.profiles import read_profile
from railcontact.timestep.wheelset import OK, Kinematics, RailDeviation, WheelsetContact

STEEL = rc.Material(206e9, 0.28)
PAIR = rc.ElasticPair.of(STEEL, STEEL)
Q = 80e3
V = 30.0


def contact(**settings) -> WheelsetContact:
    track = rc.Track(read_profile("60E1", "rail"), math.atan(1 / 40))
    ws = rc.Wheelset(read_profile("S1002", "wheel"), 0.46)
    return WheelsetContact(track, ws, PAIR, rc.ContactSettings(
        **{"friction": 0.4, "element_size": 0.5e-3, **settings}))


def forces(r) -> np.ndarray:
    return np.array([[w.normal_force, *w.creep_force, w.spin_moment] for w in r.wheels])


def test_curvature_equals_the_equivalent_yaw_rate_on_a_centred_wheelset():
    """On a curve of curvature k the rails turn with -V k relative to the track frame:
    for a centred wheelset that is the same relative motion as a yaw rate V k on tangent
    track (CONTACT: CURV = k equals VYAW = V k), so creepages and forces agree."""
    k = -1 / 600  # a right-hand curve
    a = contact(warm_start="none").solve(rc.Pose(0.0), loads=(Q, Q),
                                          kinematics=Kinematics(V, curvature=k))
    b = contact(warm_start="none").solve(rc.Pose(0.0), loads=(Q, Q),
                                          kinematics=Kinematics(V, yaw_rate=V * k))
    for wa, wb in zip(a.wheels, b.wheels, strict=True):
        assert wa.status == wb.status == OK
        np.testing.assert_allclose(wa.creepages, wb.creepages, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(forces(a), forces(b), rtol=1e-9, atol=1e-6)
    # the outer (left) wheel's rail runs ahead: its xi rises by |k| Y_c (about 1.25e-3)
    plain = contact(warm_start="none").solve(rc.Pose(0.0), loads=(Q, Q),
                                              kinematics=Kinematics(V))
    dxi = a.left.creepages[0][0] - plain.left.creepages[0][0]
    # (the contact point moves a little with the creep forces in the load)
    assert dxi == pytest.approx(-k * a.left.patches[0].geometry.position[1], rel=1e-5)
    assert 1.2e-3 < dxi < 1.3e-3


def test_mirror_symmetry_of_curvature_and_rail_deviations():
    """The right wheel at (y, psi, k, rail dY, rail roll, ...) is the left wheel at the
    negated values: lateral forces, spin moment, lateral creepage and spin negated, the
    rest equal."""
    def step(sign: float):
        rails = (RailDeviation((sign * 1e-3, 2e-4), sign * 2e-3),
                 RailDeviation((sign * 1e-3, 2e-4), sign * 2e-3))
        loads = (Q, 0.9 * Q) if sign > 0 else (0.9 * Q, Q)
        return contact(warm_start="none").solve(
            rc.Pose(sign * 2e-3, sign * 1e-3), loads=loads,
            kinematics=Kinematics(V, sign * 0.05, sign * 0.01, curvature=sign / 800),
            rails=rails)
    a, b = step(1.0), step(-1.0)
    wl, wr = a.left, b.right
    assert wl.status == wr.status == OK
    assert wr.normal_force == pytest.approx(wl.normal_force, rel=1e-6)
    assert wr.creep_force[0] == pytest.approx(wl.creep_force[0], rel=1e-6, abs=1e-3)
    # (the contact frames' y points to the left on both wheels: y-like values mirror)
    assert wr.creep_force[1] == pytest.approx(-wl.creep_force[1], rel=1e-6, abs=1e-3)
    assert wr.spin_moment == pytest.approx(-wl.spin_moment, rel=1e-6, abs=1e-6)
    assert wr.lateral_position == pytest.approx(-wl.lateral_position, abs=1e-9)
    assert abs(wl.creep_force[1]) > 1e3 and abs(wl.spin_moment) > 1.0  # (not trivially)
    for ca, cb in zip(wl.creepages, wr.creepages, strict=True):
        np.testing.assert_allclose(cb, (ca[0], -ca[1], -ca[2]), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("dy", [1.5e-3, -2e-3])
def test_a_rail_offset_equals_the_opposite_wheelset_displacement(dy):
    """Both rails moved by dY: the contact is that of the wheelset moved by -dY (forces,
    creepages, contact angles), the contact points moved by dY."""
    kin = Kinematics(V, 0.02)
    rails = (RailDeviation((dy, 0.0)), RailDeviation((dy, 0.0)))
    a = contact(warm_start="none").solve(rc.Pose(1e-3), loads=(Q, Q), kinematics=kin,
                                          rails=rails)
    b = contact(warm_start="none").solve(rc.Pose(1e-3 - dy), loads=(Q, Q), kinematics=kin)
    for wa, wb in zip(a.wheels, b.wheels, strict=True):
        assert wa.status == wb.status == OK
        assert wa.contact_angle == pytest.approx(wb.contact_angle, abs=2e-4)
        assert wa.lateral_position == pytest.approx(wb.lateral_position + dy, abs=2e-5)
    np.testing.assert_allclose(forces(a), forces(b), rtol=3e-3, atol=0.002 * 0.4 * Q)


def test_profiles_per_side_equal_the_one_profile_wheelset_on_each_side():
    """A wheelset given a pair (the same profiles on both sides) is the wheelset given one;
    with a different rail on the right, the left wheel is unchanged."""
    rail, other = read_profile("60E1", "rail"), read_profile("CN60", "rail")
    wheel = read_profile("S1002", "wheel")
    settings = rc.ContactSettings(friction=0.4, element_size=0.5e-3, warm_start="none")
    inc = math.atan(1 / 40)
    one = WheelsetContact(rc.Track(rail, inc), rc.Wheelset(wheel, 0.46), PAIR, settings)
    pair = WheelsetContact((rc.Track(rail, inc), rc.Track(rail, inc)),
                           (rc.Wheelset(wheel, 0.46), rc.Wheelset(wheel, 0.46)), PAIR, settings)
    mixed = WheelsetContact((rc.Track(rail, inc), rc.Track(other, inc)),
                            rc.Wheelset(wheel, 0.46), PAIR, settings)
    kin = Kinematics(V, 0.02)
    a, b, c = (w.solve(rc.Pose(2e-3), loads=(Q, Q), kinematics=kin) for w in (one, pair, mixed))
    np.testing.assert_array_equal(forces(a), forces(b))
    np.testing.assert_array_equal(forces(a)[0], forces(c)[0])
    assert c.right.status == OK and c.right.contact_angle != a.right.contact_angle
    with pytest.raises(RailContactError, match="one wheel radius"):
        WheelsetContact(rc.Track(rail, inc), (rc.Wheelset(wheel, 0.46), rc.Wheelset(wheel, 0.45)),
                        PAIR, settings)


def test_frictional_power_is_the_traction_times_the_slip():
    """The wheel's frictional power V (F_x xi + F_y eta + M_z phi) is what V times the
    traction times the local slip, integrated over its patches, converges to under grid
    refinement (the energy balance of steady rolling): on the grid the slip integral is
    first-order accurate (its difference halves with the element size) while the balance
    holds to 3 % from 1 mm elements. It is negative (dissipated), and None when the
    creepages are given (no speed)."""
    diff, power = {}, {}
    for h in (1e-3, 0.5e-3):
        r = contact(warm_start="none", element_size=h, tangential_tolerance=1e-4).solve(
            rc.Pose(3e-3, 2e-3), loads=(Q, Q), kinematics=Kinematics(V, 0.05, curvature=1 / 600))
        for w in r.wheels:
            assert w.status == OK and w.frictional_power < 0
            integral = sum(float(np.sum(np.asarray(p.tangential.traction)
                                        * p.tangential.relative_slip()))
                           * p.tangential.grid.dx * p.tangential.grid.dy for p in w.patches)
            diff[h, w.side] = abs(w.frictional_power - V * integral)
            power[h, w.side] = w.frictional_power
    for side in ("left", "right"):
        assert diff[0.5e-3, side] < 0.6 * diff[1e-3, side], diff
        assert power[0.5e-3, side] == pytest.approx(power[1e-3, side], rel=0.03)
    given = contact().solve(rc.Pose(0.0), loads=(Q, Q),
                            creepages=((1e-3, 0.0, 0.0), (1e-3, 0.0, 0.0)))
    assert given.left.frictional_power is None
    assert given.left.frictional_power_per_speed < 0


def test_warm_steps_survive_a_change_of_friction_and_rail_position():
    """A warm step after the friction and the rails changed is the cold step's answer to
    the step's tolerances (the remembered patches still start it)."""
    kin = Kinematics(V, 0.02)
    warm = contact()
    warm.solve(rc.Pose(2e-3), loads=(Q, Q), kinematics=kin, time=0.0)
    rails = (RailDeviation((5e-4, -2e-4), 1e-3), RailDeviation((5e-4, 1e-4)))
    a = warm.solve(rc.Pose(2.05e-3), loads=(Q, Q), kinematics=kin, time=1e-3, rails=rails,
                   friction=(0.25, 0.35))
    b = contact(warm_start="none").solve(rc.Pose(2.05e-3), loads=(Q, Q), kinematics=kin,
                                          rails=rails, friction=(0.25, 0.35))
    for wa, wb in zip(a.wheels, b.wheels, strict=True):
        assert wa.status == wb.status == OK
        assert all(p.estimate == "previous" for p in wa.patches)
        assert wa.normal_force == pytest.approx(wb.normal_force, rel=2e-3)
        for k in range(2):
            assert abs(wa.creep_force[k] - wb.creep_force[k]) <= 0.01 * 0.25 * Q
    # the friction was the step's: full slip on the left would be mu N = 0.25 N
    assert math.hypot(*a.left.creep_force) <= 0.25 * a.left.normal_force * (1 + 1e-6)


def test_a_warm_step_at_negligible_friction_slides_without_force():
    """A step whose friction drops to 5e-324 (a subnormal number: every bound mu p too)
    after warm steps at 0.4: both wheels slide without creep force (Coulomb's |F| <= mu N,
    below 1e-300 N), status ok; it was "initial_traction must be finite" (out of range),
    the warm start's tractions scaled by NaN."""
    kin = Kinematics(V, 0.02)
    wc = contact()
    for k in range(2):
        wc.solve(rc.Pose(2e-3), loads=(Q, Q), kinematics=kin, time=k * 1e-3)
    r = wc.solve(rc.Pose(2e-3), loads=(Q, Q), kinematics=kin, time=2e-3,
                 friction=(5e-324, 5e-324))
    assert r.status == OK, r.message
    for w in r.wheels:
        assert w.creep_force == (0.0, 0.0) and w.normal_force > 0.5 * Q
        assert all(p.tangential.slip_area_ratio == 1.0 for p in w.patches)


@pytest.mark.parametrize("kwargs, words", [
    ({"friction": (0.3, -0.1)}, "right friction"),
    ({"friction": (0.3,)}, "friction must be"),
    ({"rails": (RailDeviation(), None)}, "RailDeviation"),
])
def test_bad_step_inputs_are_errors(kwargs, words):
    with pytest.raises(RailContactError, match=words):
        contact().solve(rc.Pose(0.0), loads=(Q, Q), kinematics=Kinematics(V), **kwargs)


@pytest.mark.parametrize("value, words", [
    (dict(offset=(math.nan, 0.0)), "rail offset dY"),
    (dict(offset=(0.0,)), "rail offset must be"),
    (dict(roll=math.inf), "rail roll"),
])
def test_bad_rail_deviations_are_errors(value, words):
    with pytest.raises(RailContactError, match=words):
        RailDeviation(**value)


def test_a_curvature_beyond_any_track_is_an_error():
    with pytest.raises(RailContactError, match="curvature"):
        Kinematics(V, curvature=0.2)


def test_friction_per_step_follows_replaced_settings():
    """A step's friction is applied to the contact's current settings: replacing them
    between steps (a finer element size) is not hidden by the settings kept for a
    friction."""
    from dataclasses import replace

    kin = Kinematics(V, 0.02)
    c = contact(warm_start="none", element_size=1e-3)
    c.solve(rc.Pose(2e-3), loads=(Q, Q), kinematics=kin, friction=(0.3, 0.3))
    c.settings = replace(c.settings, element_size=0.5e-3)
    a = c.solve(rc.Pose(2e-3), loads=(Q, Q), kinematics=kin, friction=(0.3, 0.3))
    b = contact(warm_start="none", element_size=0.5e-3).solve(
        rc.Pose(2e-3), loads=(Q, Q), kinematics=kin, friction=(0.3, 0.3))
    np.testing.assert_array_equal(forces(a), forces(b))
