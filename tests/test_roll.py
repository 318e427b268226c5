"""Wheelset roll: rigid contact on both rails and the Manchester benchmark's equal loads."""

import math

import pytest
from conftest import PROFILES

import railcontact as rc
from railcontact import CaseError
from railcontact.geometry.profiles import builtin_profile, read_profile
from railcontact.geometry.roll import contact_roll, first_contact_gap
from railcontact.geometry.search import contact_points
from railcontact.geometry.track import Pose, Track, Wheelset

# Roll angles [rad] of the Manchester benchmark case A-2.2 (10 kN per wheel, yaw 2.4 y mrad),
# solved by CONTACT for equal wheel loads: CONTACT examples/mbench_a22_left.inp, lateral
# shift [mm] -> roll in CONTACT's sign (left side down positive); ours is the opposite.
CONTACT_A22_ROLL = {2.0: -0.00011280, 4.5: -0.00029770, 8.0: -0.00860600,
                    10.0: -0.01126431}


@pytest.fixture(scope="module")
def s1002_60e1():
    return Track(builtin_profile("60E1")), Wheelset(builtin_profile("S1002"))


def test_centred_wheelset_does_not_roll(s1002_60e1):
    track, ws = s1002_60e1
    assert abs(contact_roll(track, ws, 0.0)) < 1e-9


def test_roll_is_odd_in_the_lateral_displacement(s1002_60e1):
    track, ws = s1002_60e1
    for y in (2e-3, 7e-3):
        assert contact_roll(track, ws, -y) == pytest.approx(-contact_roll(track, ws, y),
                                                            rel=1e-6)


def test_rigid_roll_closes_the_loop_through_both_contact_points(s1002_60e1):
    """Both wheels touch: the rolled axle reaches both contact points. With the contact
    points P_s (track frame) at rolling radius r_s and axial position eta_s, the axle
    centre is at P_s + (0, -s eta_s cos phi, r_s) rotated, so for small phi:
    phi (eta_L + eta_R) = (r_L - r_R) + (Z_L - Z_R)."""
    track, ws = s1002_60e1
    y = 3e-3
    phi = contact_roll(track, ws, y)
    pose = Pose(y, 0.0, phi)
    left, right = (contact_points(track, ws, pose, side)[0] for side in ("left", "right"))
    assert first_contact_gap(track, ws, pose, "left") == pytest.approx(
        first_contact_gap(track, ws, pose, "right"), abs=1e-10)
    eta_l = float(ws.axial_position(left.wheel_s))
    eta_r = float(ws.axial_position(right.wheel_s))
    lhs = phi * (eta_l + eta_r)
    rhs = (left.rolling_radius - right.rolling_radius) + (left.position[2] - right.position[2])
    assert phi > 0  # the left wheel runs on the larger radius: the left side rises
    assert lhs == pytest.approx(rhs, rel=1e-3)


def _a22(shift_mm: float, roll) -> dict:
    return {
        "material": {"young": 2 * 82e9 * 1.28, "poisson": 0.28},
        "geometry": {"type": "wheel-rail", "wheel": str(PROFILES / "MBench_S1002_v3.prw"),
                     "rail": str(PROFILES / "MBench_UIC60_v3.prr"), "inclination": 0.0,
                     "lateral_displacement": shift_mm * 1e-3, "yaw": 2.4e-3 * shift_mm,
                     "side": "both", "roll": roll},
        "grid": {"nx": 40, "ny": 40},
        "normal": {"load": 10e3, "tolerance": 1e-4},
    }


@pytest.mark.parametrize("shift_mm", sorted(CONTACT_A22_ROLL))
def test_equal_loads_roll_against_contact_manchester_a22(shift_mm):
    """Tread (2, 4.5 mm) and flange (8, 10 mm) contact: CONTACT's roll within 0.5 %.
    The rigid roll is further off: the elastic approaches differ between the wheels."""
    ref = -CONTACT_A22_ROLL[shift_mm]
    sol = rc.solve(_a22(shift_mm, "equal-loads"))
    assert sol.roll == pytest.approx(ref, rel=5e-3)
    rigid = rc.solve(_a22(shift_mm, "rigid")).roll
    assert abs(rigid - ref) > abs(sol.roll - ref)
    for side in ("left", "right"):  # each wheel carries 10 kN
        fz = sum(p.normal.force * math.cos(p.geometry.contact_angle)
                 for p in sol.patches if p.geometry.side == side)
        assert fz == pytest.approx(10e3, rel=1e-5)


def _one_body_mismatch(case: dict) -> tuple[float, rc.Solution]:
    """Solve ``case``; return the difference [m] of the two wheels' lowering (first-contact
    gap plus loaded approach), zero for one rigid wheelset."""
    sol = rc.solve(case)
    geo = case["geometry"]
    track = Track(read_profile(geo["rail"], "rail"), geo.get("inclination", math.atan(1 / 40)))
    ws = Wheelset(read_profile(geo["wheel"], "wheel"))
    pose = Pose(geo["lateral_displacement"], geo.get("yaw", 0.0), sol.roll)
    lowered = []
    for side in ("left", "right"):
        p = min((q for q in sol.patches if q.geometry.side == side),
                key=lambda q: q.geometry.gap)
        approach = p.normal.penetration / math.cos(p.geometry.contact_angle) + p.geometry.gap
        lowered.append(approach + first_contact_gap(track, ws, pose, side))
    return lowered[0] - lowered[1], sol


def test_equal_loads_wheelset_is_one_rigid_body():
    """Lowered by one vertical distance, the wheels reach their approaches together (to
    50 nm, 0.1 % of the approaches: the roll is converged to 1e-8 rad)."""
    mismatch, _ = _one_body_mismatch(_a22(6.0, "equal-loads"))
    assert abs(mismatch) < 5e-8


def test_equal_loads_roll_on_the_flange_under_a_heavy_load():
    """S1002/60E1 at 6.4 mm, 83.3 kN per wheel: on the flange (70 deg) the left wheel needs
    a vertical approach of ~0.6 mm, which takes 2.5 mrad off the rigid roll and, on the
    way, drops the contact back to the tread - the fixed point alone oscillates. The
    solution must still be one rigid wheelset, with the left wheel on its flange."""
    case = {"material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                         "lateral_displacement": 6.4e-3, "side": "both",
                         "roll": "equal-loads"},
            "grid": {"nx": 40, "ny": 40}, "normal": {"load": 83.3e3, "estimate": "infcon"}}
    mismatch, sol = _one_body_mismatch(case)
    assert abs(mismatch) < 5e-7  # 0.1 % of the flange's approach
    track, ws = Track(builtin_profile("60E1")), Wheelset(builtin_profile("S1002"))
    rigid = contact_roll(track, ws, 6.4e-3)
    assert 0 < sol.roll < rigid - 1e-3
    left = [p for p in sol.patches if p.geometry.side == "left"]
    assert max(math.degrees(p.geometry.contact_angle) for p in left) > 60


def test_roll_modes_in_case_and_json(tmp_path):
    base = {"material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "wheel-rail", "lateral_displacement": 3e-3, "roll": "rigid"},
            "grid": {"nx": 24, "ny": 24}, "normal": {"penetration": 5e-5}}
    sol = rc.solve(base)
    track, ws = Track(builtin_profile("60E1")), Wheelset(builtin_profile("S1002"))
    assert sol.roll == pytest.approx(contact_roll(track, ws, 3e-3), abs=1e-12)
    assert sol.to_dict()["roll"] == sol.roll
    bad = {**base, "geometry": {**base["geometry"], "roll": "equal-loads"}}
    with pytest.raises(CaseError, match="needs \\[normal\\] load"):
        rc.solve(bad)
    bad["geometry"]["roll"] = "level"
    with pytest.raises(CaseError, match="roll must be one of"):
        rc.solve(bad)


def test_first_contact_gap_is_the_least_sampled_gap(s1002_60e1):
    """The first-contact gap (from the trace the search remembers for each side) is the
    least of the trace's gaps ``vertical_gap`` forms afresh, to the bit, over random poses
    of both wheels, whichever side was searched last."""
    import numpy as np

    from railcontact.geometry.search import vertical_gap

    track, ws = s1002_60e1
    rng = np.random.default_rng(18)
    for _ in range(60):
        pose = Pose(rng.uniform(-9e-3, 9e-3), rng.uniform(-8e-3, 8e-3),
                    rng.uniform(-3e-3, 3e-3))
        gaps = {side: first_contact_gap(track, ws, pose, side) for side in ("left", "right")}
        for side in ("right", "left", "right"):  # (each side's trace remembered)
            g = vertical_gap(track, ws, pose, side)[4]
            assert first_contact_gap(track, ws, pose, side) == gaps[side] == float(g.min())
