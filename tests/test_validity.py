"""Honest statuses beyond the model's validity, the moments about the wheelset
centre and the rigid wheelset's vertical displacement and roll under load control.

Truth: Nadal's formula by hand; the balance of a flange in full sliding (Y/Q equals
Nadal's value at the contact angle); mirror symmetry; statics of the contact forces about
the centre; Hertz's approach; and the penetration-controlled solve, which must give each
wheel back the load of the load-controlled one.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from railcontact.geometry.profiles import read_profile
from railcontact.geometry.track import Pose, Track, Wheelset
from railcontact.halfspace.materials import ElasticPair, Material
from railcontact.timestep.validity import (
    FLANGE_CLIMB,
    LOAD,
    NADAL,
    PENETRATION,
    Y_Q,
    derailment_quotient,
    nadal_limit,
)
from railcontact.timestep.wheelset import (
    NO_CONTACT,
    OK,
    OUT_OF_RANGE,
    OUTSIDE_VALIDITY,
    ContactSettings,
    WheelContact,
    WheelsetContact,
    WheelsetResult,
)

Q = 83.3e3
NONE = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


def contact(**settings) -> WheelsetContact:
    mat = Material(206e9, 0.28)
    return WheelsetContact(Track(read_profile("60E1", "rail"), math.atan(1 / 40)),
                           Wheelset(read_profile("S1002", "wheel"), 0.46),
                           ElasticPair.of(mat, mat),
                           ContactSettings(**{"warm_start": "none", "rigid_wheelset": "solve",
                                              **settings}))


@pytest.mark.parametrize(("degrees", "mu", "hand"), [
    (70.0, 0.0, 2.747477),   # tan(70 deg)
    (70.0, 0.3, 1.341639),   # (2.747477 - 0.3) / (1 + 0.824243)
    (70.0, 0.4, 1.118384),   # (2.747477 - 0.4) / (1 + 1.098991)
    (60.0, 0.5, 0.660254),   # (1.732051 - 0.5) / (1 + 0.866025)
])
def test_nadal_limit_against_hand_values(degrees, mu, hand):
    assert nadal_limit(math.radians(degrees), mu) == pytest.approx(hand, abs=2e-6)


def test_derailment_quotient_takes_y_towards_the_field_side():
    """The rail pushes a flanging left wheel to the right (-Y), a flanging right wheel to
    the left (+Y): both are Y > 0 on the rail towards its field side."""
    assert derailment_quotient(+1, (0.0, -50e3, 100e3)) == pytest.approx(0.5)
    assert derailment_quotient(-1, (0.0, +50e3, 100e3)) == pytest.approx(0.5)
    assert derailment_quotient(+1, (0.0, +50e3, 100e3)) == pytest.approx(-0.5)
    assert derailment_quotient(+1, (0.0, 1e3, 0.0)) == 0.0


def test_centred_wheelset_is_within_validity():
    r = contact().solve(Pose(0.0), loads=(Q, Q), creepages=NONE)
    for w in r.wheels:
        assert w.status == OK and w.validity == 0 and w.message == "ok"
        # without creep forces the rail pushes along the normal: Y/Q = tan(gamma)
        assert w.derailment_quotient == pytest.approx(math.tan(w.contact_angle), rel=1e-6)
    assert r.status == OK


@pytest.mark.parametrize("eta", [0.01, -0.01])
def test_full_sliding_on_the_flange_gives_nadals_quotient(eta):
    """Left wheel on its 70 deg flange, sliding across it: the creep force is mu N. With
    the rail's friction on the wheel pointing up the flank (as at a positive angle of
    attack) Y/Q = (tan(g) - mu) / (1 + mu tan(g)), Nadal's limit at the contact angle;
    pointing down it (the wheel sliding up) Y/Q = (tan(g) + mu) / (1 - mu tan(g)). Both
    are above 0.8, and the second beyond Nadal's limit: outside validity, saying which
    and how much."""
    mu = 0.3
    r = contact(friction=mu, element_size=1e-3).solve(
        Pose(7e-3), loads=(Q, 0.6 * Q), creepages=((0.0, eta, 0.0), (0.0, 0.0, 0.0)))
    w = r.left
    t = math.tan(w.contact_angle)
    # contact y runs up the flank (towards +Y); eta > 0 makes the friction point down it
    lifting = w.creep_force[1] > 0
    assert lifting == (eta < 0)
    want = (t - mu) / (1 + mu * t) if lifting else (t + mu) / (1 - mu * t)
    assert w.derailment_quotient == pytest.approx(want, rel=3e-3)
    assert w.status == OUTSIDE_VALIDITY and w.validity & Y_Q
    assert f"Y/Q = {w.derailment_quotient:.3g} above max_y_q = 0.8" in w.message
    if not lifting:  # far beyond the flange's Nadal limit (lifting sits on it)
        flank = Wheelset(read_profile("S1002", "wheel"), 0.46).flange_flank[1]
        assert w.validity & NADAL
        assert f"beyond Nadal's limit {nadal_limit(flank, mu):.3g}" in w.message
    assert r.right.status == OK and r.status == OUTSIDE_VALIDITY


def test_flange_climb_at_10_mm_is_outside_validity():
    """At 10 mm the left contact is past the flange's steepest point
    (61 deg at S = -41 mm against 70 deg at -38.5 mm) and, at mu = 0.4 with no creep
    forces, Y/Q = tan(61 deg) = 1.8 is beyond Nadal's 1.12: solved, outside validity,
    the message naming each quantity; the right wheel on its tread is ok. At the rigid
    point, where the case was reported (the frame at the reference point is at S = -40.99
    mm, 61.3 deg: the same flags)."""
    r = contact(friction=0.4, patch_frame="rigid").solve(Pose(10e-3), loads=(Q, Q),
                                                         creepages=NONE)
    w = r.left
    assert w.status == OUTSIDE_VALIDITY and r.status == OUTSIDE_VALIDITY
    assert w.validity == Y_Q | NADAL | FLANGE_CLIMB
    assert w.derailment_quotient == pytest.approx(math.tan(w.contact_angle), rel=1e-3)
    assert w.derailment_quotient > nadal_limit(math.radians(70.0), 0.4) == pytest.approx(
        1.118, abs=1e-3)
    assert "flange climb: contact at S = -41" in w.message and "Nadal's limit 1.12" in w.message
    assert w.track_force[2] == pytest.approx(Q, rel=1e-3)  # still solved
    assert r.right.status == OK and r.right.validity == 0


def test_load_and_penetration_limits():
    """Limits are settings: 500 kN is above the default max_wheel_load (400 kN); a
    max_penetration below the tread's Hertzian approach at 83.3 kN (0.067 mm) flags it."""
    r = contact().solve(Pose(0.0), loads=(500e3, Q), creepages=NONE)
    assert r.left.validity == LOAD and r.left.status == OUTSIDE_VALIDITY
    assert "wheel load Q = 500 kN above max_wheel_load = 400 kN" in r.left.message
    assert r.right.status == OK
    r = contact(max_penetration=0.05e-3, patch_frame="rigid").solve(Pose(0.0), loads=(Q, Q),
                                                                    creepages=NONE)
    for w in r.wheels:
        # one patch at first contact, its frame at the rigid point: the normal penetration
        # is the vertical approach projected on the normal
        assert w.penetration == pytest.approx(w.approach * math.cos(w.contact_angle),
                                              rel=1e-6)
        assert w.validity == PENETRATION and "normal penetration 0.0673 mm" in w.message
    # a looser Y/Q limit drops only that bit
    r = contact(friction=0.4, max_y_q=5.0).solve(Pose(10e-3), loads=(Q, Q), creepages=NONE)
    assert r.left.validity == NADAL | FLANGE_CLIMB


def test_wheelset_status_is_the_most_severe():
    def of(*codes):
        return WheelsetResult(WheelContact("left", codes[0]), WheelContact("right", codes[1]))
    assert of(OK, NO_CONTACT).status == NO_CONTACT
    assert of(OUTSIDE_VALIDITY, NO_CONTACT).status == OUTSIDE_VALIDITY
    assert of(OUTSIDE_VALIDITY, 1).status == 1
    assert of(OUTSIDE_VALIDITY, OUT_OF_RANGE).status == OUT_OF_RANGE


def test_moments_of_a_centred_wheelset():
    """Centred, no creepage: mirror symmetry, no moment. Opposite longitudinal creepages
    (xi_left = -xi_right): F_x,left = -F_x,right, a pure yaw couple M_Z = -(Y_L F_xL +
    Y_R F_xR) = -2 Y_L F_xL, positive (nose left) for xi_left > 0 (F_xL < 0): to 1 %, as
    the creep force acts at its traction centroid, not at the contact point (the
    tread patch is not symmetric across: 1.5 mm on the 0.75 m lever), which the spin
    moments about the normal add exactly. Equal
    creepages: no yaw, a pitch moment M_Y = -(h - Z_L) F_xL - (h - Z_R) F_xR about the axle
    at height h = r0 + vertical."""
    # the rigid frame: its patches are mirror images to round-off (the reference point's
    # frame leaves a few nm of longitudinal lever, 1.7e-4 N m, above the 1e-9 bound)
    wc = contact(patch_frame="rigid", rigid_wheelset="solve")
    r = wc.solve(Pose(0.0), loads=(Q, Q), creepages=NONE)
    scale = Q * 0.75
    assert all(abs(m) < 1e-9 * scale for m in r.moment), r.moment
    xi = 1e-3
    r = wc.solve(Pose(0.0), loads=(Q, Q), creepages=((xi, 0, 0), (-xi, 0, 0)))
    L, R = r.left, r.right
    assert L.creep_force[0] < 0 and R.creep_force[0] == pytest.approx(-L.creep_force[0])
    yl = L.contact_point[1]
    assert yl == pytest.approx(0.75, abs=0.01)
    mx, my, mz = r.moment
    assert mz == pytest.approx(-2 * yl * L.creep_force[0], rel=1e-2) and mz > 0
    spin = sum(w.spin_moment * math.cos(w.contact_angle) for w in r.wheels)
    assert mz == pytest.approx(-2 * yl * L.creep_force[0] + spin, rel=1e-9)
    assert mz == pytest.approx(r.yaw_moment, rel=1e-12)
    assert abs(my) < 1e-6 * abs(mz)
    r = wc.solve(Pose(0.0), loads=(Q, Q), creepages=((xi, 0, 0), (xi, 0, 0)))
    h = 0.46 + r.vertical
    want = -sum((h - w.contact_point[2]) * w.creep_force[0] for w in r.wheels)
    assert r.moment[1] == pytest.approx(want, rel=1e-3) and r.moment[1] > 0
    # the lever is the rolling radius: the contact is r below the axle
    assert h - r.left.contact_point[2] == pytest.approx(r.left.rolling_radius, abs=2e-4)
    assert abs(r.moment[2]) < 1e-6 * abs(r.moment[1])


def _centroid_s(wheel: WheelContact) -> float:
    """The wheel's pressure centroid [m] along the contact plane's lateral axis s (towards
    the field side) from the contact point, from its pressure field."""
    p = wheel.patches[0].normal
    return float((p.grid.y[None, :] * p.pressure).sum() / p.pressure.sum())


def test_roll_moment_of_unequal_loads():
    """Centred, loads 90 and 70 kN, no creepage: each wheel's force is its load Q along
    the normal, leaning by the contact angle g towards the track centre, and acts at the
    pressure's centroid, c along the contact plane from the contact point (field side
    +); about the centre at height h that is M_X = (Q_L - Q_R) (e - h tan(g)) + N_L c_L
    - N_R c_R with e the contact's lateral distance (statics by hand; the centroid's
    share, 2.9 mm x 20 kN, is 0.4 % here)."""
    # the rigid frame: its contact point (e, g, h) is the same for both loads, as the hand
    # formula takes it; at the reference point it moves with the load (the field
    # integration below checks that frame)
    r = contact(patch_frame="rigid").solve(Pose(0.0), loads=(90e3, 70e3), creepages=NONE)
    L, R = r.left, r.right
    e, g = L.contact_point[1], L.contact_angle
    h = 0.46 + r.vertical - L.contact_point[2]
    cl, cr = _centroid_s(L), _centroid_s(R)
    assert abs(cl) > 1e-3 and abs(cr) > 1e-3  # 2.9 mm towards the flange
    hand = (20e3 * (e - h * math.tan(g)) + L.normal_force * cl - R.normal_force * cr)
    assert r.moment[0] == pytest.approx(hand, rel=2e-4)
    assert r.moment[0] > 0  # the heavier left wheel is pushed up harder


@pytest.mark.parametrize("frame", ["rigid", "reference"])
def test_moments_integrate_the_pressure_and_traction_fields(frame):
    """The moment of the rails' forces about the wheelset centre is the sum over every
    element of every patch of (its place - centre) x (its force): pressure along the
    normal n and traction along x and s, each element at x e_x + s e_s from its contact
    point in the contact plane (e_s = (0, sgn cos(g), sin(g)), n = (0, -sgn sin(g),
    cos(g)) in the track frame; sgn +1 left, -1 right). 5 mm lateral, yawed, with
    creepages: at the rigid point the pressure's centroid shifts M_X by 1.0 %, which the
    contact points alone miss (0.9997-1.0004 % as the load loop meets the wheel loads to
    its tolerance, 1e-3, from one start or another)."""
    wc = contact(patch_frame=frame)
    r = wc.solve(Pose(5e-3, 2e-3), loads=(Q, 0.9 * Q),
                 creepages=((1e-3, 2e-3, 0.1), (-1e-3, 2e-3, -0.1)))
    centre = np.array([0.0, 5e-3, 0.46 + r.vertical])
    total = np.zeros(3)
    at_points = np.zeros(3)
    for w in r.wheels:
        sgn = 1.0 if w.side == "left" else -1.0
        for p in w.patches:
            cp, n, t = p.geometry, p.normal, p.tangential
            g = cp.contact_angle
            ex = np.array([1.0, 0.0, 0.0])
            es = np.array([0.0, sgn * math.cos(g), math.sin(g)])
            en = np.array([0.0, -sgn * math.sin(g), math.cos(g)])
            x, s = n.grid.mesh()
            da = n.grid.element_area
            place = (np.asarray(cp.position)[None, None, :] + x[..., None] * ex
                     + s[..., None] * es - centre)
            force = (t.traction[0][..., None] * ex + t.traction[1][..., None] * es
                     + n.pressure[..., None] * en) * da
            total += np.cross(place, force).sum(axis=(0, 1))
            at_points += np.cross(np.asarray(cp.position) - centre, force.sum(axis=(0, 1)))
    assert np.allclose(r.moment, total, rtol=1e-9, atol=1e-9 * Q)
    if frame == "rigid":
        assert abs(total[0] - at_points[0]) > 0.009 * abs(total[0])  # the centroid matters


@pytest.mark.parametrize(("lateral", "loads"), [
    (0.0, (Q, Q)), (0.0, (90e3, 70e3)), (3e-3, (Q, Q)), (6.5e-3, (Q, Q)), (8e-3, (Q, Q)),
    (10e-3, (Q, Q))])
def test_vertical_and_roll_under_load_control(lateral, loads):
    """The rigid wheelset's vertical displacement and roll that the load-controlled step
    reports, given to a penetration-controlled step, give each wheel its load back: to
    the grid's accuracy (the two controls mesh differently), on the tread (0, 3 mm), at
    the flange's root (6.5 mm: two-point contact) and on the flange (8, 10 mm), where
    rolling the wheelset moves the contacts (the approaches at the pose's roll alone gave
    31.6/0, 748/0 and 429/0 kN back at 6.5, 8 and 10 mm). Centred with equal loads the
    roll is zero; at +3 mm the left wheel runs on the larger radius and the wheelset rolls
    left side up, by about ((Z_L + r_L) - (Z_R + r_R)) / (Y_L - Y_R) from the contact
    points (the approaches and the wheels' own contact points left out: 5 %); with the
    left wheel on its flange it rolls further."""
    wc = contact()
    r = wc.solve(Pose(lateral), loads=loads, creepages=NONE)
    assert r.status in (OK, OUTSIDE_VALIDITY)
    rigid = r.rigid_solution
    assert rigid.converged, rigid.message
    v, phi = r.vertical, r.roll
    p = wc.solve(Pose(lateral, 0.0, phi), vertical=v, creepages=NONE)
    assert p.vertical == v and p.roll == phi
    for b, q in zip(p.wheels, loads, strict=True):
        assert b.track_force[2] == pytest.approx(q, rel=3e-3)
    if lateral == 0.0 and loads[0] == loads[1]:
        assert abs(phi) < 1e-12
    if lateral == 3e-3:
        L, R = r.left, r.right
        hand = ((L.contact_point[2] + L.rolling_radius) - (R.contact_point[2]
                + R.rolling_radius)) / (L.contact_point[1] - R.contact_point[1])
        assert phi > 0 and phi == pytest.approx(hand, rel=0.05)
    if lateral > 3e-3:
        assert phi > 3e-4
    if loads[0] > loads[1]:
        assert phi < 0  # the heavier left wheel sinks further


@pytest.mark.parametrize("lateral", [3e-3, 8e-3, 10e-3])
def test_vertical_and_roll_with_creepages(lateral):
    """With creepages a wheel load counts the creep forces, whose share on the flange
    (F_y sin(gamma), gamma ~ 70 deg) changes as the wheelset rolls: the rigid wheelset's
    vertical displacement and roll, given to a penetration-controlled step with the same
    creepages, give the loads (90 and 75 kN) back (matching the normal forces' share alone
    gave 0.52 Q at 8 mm and 1.8 Q at 10 mm)."""
    wc = contact()
    creep = ((1e-3, 2e-3, 0.2), (1e-3, 2e-3, -0.2))
    loads = (90e3, 75e3)
    r = wc.solve(Pose(lateral), loads=loads, creepages=creep)
    assert r.rigid_solution.converged, r.rigid_solution.message
    p = wc.solve(Pose(lateral, 0.0, r.roll), vertical=r.vertical, creepages=creep)
    for b, q in zip(p.wheels, loads, strict=True):
        assert b.track_force[2] == pytest.approx(q, rel=3e-3)


def test_vertical_and_roll_not_found_is_said(monkeypatch):
    """On the flange the roll needs several evaluations; allowed only one, the solution
    says it did not converge (with by how much) instead of passing its first guess as
    ok, and so does the wheelset's status (the FMU's): its wheels carry their loads (each
    solved under load control), but its vertical displacement, roll and moment about its
    centre are that guess's."""
    from railcontact.fmu.variables import table
    from railcontact.status import Status
    from railcontact.timestep import rigid

    monkeypatch.setattr(rigid, "MAX_EVALUATIONS", 1)
    r = contact().solve(Pose(8e-3), loads=(Q, Q), creepages=NONE)
    s = r.rigid_solution
    assert not s.converged and s.evaluations == 1
    assert "not converged" in s.message and "um" in s.message
    assert all(w.status in (OK, OUTSIDE_VALIDITY) for w in r.wheels)  # (solved)
    assert all(w.track_force[2] == pytest.approx(Q, rel=1e-3) for w in r.wheels)
    assert r.status == Status.NOT_CONVERGED
    status = next(v for v in table() if v.name == "status")
    assert status.value(r) == Status.NOT_CONVERGED  # (the FMU's output)
    monkeypatch.undo()  # found: the wheels' status again
    r = contact().solve(Pose(8e-3), loads=(Q, Q), creepages=NONE)
    assert r.rigid_solution.converged and r.status in (OK, OUTSIDE_VALIDITY)
    assert r.status == Status.worst(w.status for w in r.wheels)


def test_a_result_pickles_with_its_roll():
    """A load-controlled result is values (no closure, no solver): it survives pickling (a
    worker process's result) with the same numbers."""
    import pickle

    r = contact().solve(Pose(3e-3), loads=(Q, Q), creepages=NONE)
    again = pickle.loads(pickle.dumps(r))
    assert (again.vertical, again.roll) == (r.vertical, r.roll) and r.roll > 0


def test_out_of_range_has_no_vertical_or_roll():
    r = contact().solve(Pose(0.08), loads=(Q, Q), creepages=NONE)
    assert r.status == OUT_OF_RANGE and (r.vertical, r.roll) == (None, None)
    assert r.moment == (0.0, 0.0, 0.0)


def test_a_flange_near_nadal_whose_secant_stalls_is_solved_on_its_bracket():
    """8 mm to the left with spin, 90 kN on the left wheel at roll 0: the flange's creep
    forces nearly cancel what its normal force carries up (mu tan(gamma) ~ 1.1), so the
    vertical force bends sharply with the normal share (6.6 kN at 168 kN, 1.08 MN at
    2.28 MN). The secant, damped to halving, stalled far from the load, and a pass at a
    share it tried was refused as a patch beyond the model: the wheel read "out of range"
    though two shares bracketed the load. Closing in on the bracket, the wheel carries the
    load to the tolerance, with the validity status its Y/Q calls for (beyond Nadal's
    limit), and a penetration-controlled solve at its approach gives the load back."""
    wc = contact(rigid_wheelset="skip")
    creep = ((1e-3, 2e-3, 0.2), (1e-3, 2e-3, -0.2))
    r = wc.solve(Pose(8e-3), loads=(90e3, 75e3), creepages=creep)
    left = r.left
    assert left.status == 4 and "Nadal" in left.message, left.message
    assert left.track_force[2] == pytest.approx(90e3, rel=1e-3)
    assert abs(left.track_force[1]) / left.track_force[2] > 1.12  # (beyond Nadal's limit)
    from railcontact.settings import Control
    from railcontact.timestep.wheel import solve_step_wheel
    setup = wc._setups.at(wc.settings, None, None)[0]
    again, _, err = solve_step_wheel(setup, Pose(8e-3), Control(penetration=left.approach),
                                     creep[0], None, None, wc.pair, "railcontact",
                                     ((), (), ()))
    assert err is None and again.track_force[2] == pytest.approx(90e3, rel=3e-3)
