"""CONTACT's turning of the contact angles of neighbouring patches
(:mod:`railcontact.geometry.separation`, CONTACT's ``turn_cpatch_refangle``): the rule's
formula at its limits, the window it applies in, and CONTACT's own two-patch case of
``mbench_a22_varfric`` (case 3, whose shallow patch CONTACT turns by 0.115 rad) within the
targets of ``scripts/validate_varfric.py``; a wheel whose patches lie apart beyond the
window is solved exactly as without the rule."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import railcontact as rc
from railcontact.errors import CaseError, RailContactError
from railcontact.geometry.separation import PatchRun, PatchSeparation, turned_angles
from railcontact.settings import Case

ROOT = Path(__file__).resolve().parents[1]
SEP = PatchSeparation(angle=math.pi / 2, distance=0.008, combine=0.004)  # D_TURN 12 mm


def _pair(dist: float, a_outer: float = 0.1, a_inner: float = 0.3, w_outer: float = 1.0,
          w_inner: float = 3.0) -> list[PatchRun]:
    """Two patches on a flat rail (Z = 0), the inner one's end ``dist`` [m] from the outer
    one's, listed inner first."""
    inner = PatchRun(u=0.720, angle=a_inner, weight=w_inner, low_end=(0.719, 0.0),
                     high_end=(0.721, 0.0))
    lo = 0.721 + dist
    outer = PatchRun(u=lo + 0.002, angle=a_outer, weight=w_outer, low_end=(lo, 0.0),
                     high_end=(lo + 0.004, 0.0))
    return [inner, outer]


def test_default_turn_distance_is_contacts():
    """D_TURN = 2 D_SEP - D_COMB unless given (CONTACT's default): 12 mm from its examples'
    8 and 4 mm, 9 mm from the varfric example's 6 and 3 mm."""
    assert SEP.turn_distance == pytest.approx(0.012)
    assert PatchSeparation(distance=0.006, combine=0.003).turn_distance == pytest.approx(0.009)
    assert PatchSeparation(turn=0.010).turn_distance == 0.010
    with pytest.raises(RailContactError, match="distance"):
        PatchSeparation(distance=-1.0)


def test_at_the_separation_distance_both_take_the_combined_angle():
    """fac = 1 at D_SEP: both angles become the weighted mean (0.1 * 1 + 0.3 * 3) / 4."""
    inner, outer = turned_angles(_pair(0.008), SEP)
    assert inner == pytest.approx(0.25) and outer == pytest.approx(0.25)


@pytest.mark.parametrize("dist, fac", [(0.009, 0.75), (0.010, 0.5), (0.0115, 0.125),
                                       (0.012, 0.0)])
def test_between_the_distances_the_angles_move_linearly(dist, fac):
    """Each angle moves (D_TURN - dist) / (D_TURN - D_SEP) of the way to the combined
    angle 0.25: the difference of the two shrinks by 1 - fac."""
    inner, outer = turned_angles(_pair(dist), SEP)
    assert inner == pytest.approx(0.3 + fac * (0.25 - 0.3), abs=1e-12)
    assert outer == pytest.approx(0.1 + fac * (0.25 - 0.1), abs=1e-12)
    assert inner - outer == pytest.approx((1 - fac) * 0.2, abs=1e-12)


@pytest.mark.parametrize("runs, sep", [
    (_pair(0.0079), SEP),  # closer than D_SEP: CONTACT has combined them already
    (_pair(0.0121), SEP),  # beyond D_TURN
    (_pair(0.010, a_outer=0.1, a_inner=1.8), SEP),  # angles further apart than A_SEP
    (_pair(0.010), PatchSeparation(distance=0.008, combine=0.008)),  # D_TURN = D_SEP
])
def test_outside_the_window_nothing_turns(runs, sep):
    assert turned_angles(runs, sep) == [r.angle for r in runs]


def test_the_distance_is_across_the_rail_section():
    """dist is measured between the facing ends in the (u, Z) section: 6 mm across and
    8 mm down is 10 mm apart (fac 0.5), not 6 mm (no turn)."""
    inner = PatchRun(u=0.720, angle=0.3, weight=3.0, low_end=(0.719, -0.008),
                     high_end=(0.721, -0.008))
    outer = PatchRun(u=0.729, angle=0.1, weight=1.0, low_end=(0.727, 0.0),
                     high_end=(0.731, 0.0))
    assert turned_angles([outer, inner], SEP) == pytest.approx([0.175, 0.275])


def test_a_middle_patch_is_turned_by_both_neighbours():
    """Three patches 10 mm apart (fac 0.5 each pair): the middle one moves by both pairs'
    turns, each computed from the angles before turning (CONTACT's a-priori angles)."""
    runs = [PatchRun(u=0.76, angle=0.0, weight=1.0, low_end=(0.755, 0.0), high_end=(0.765, 0.0)),
            PatchRun(u=0.74, angle=0.2, weight=1.0, low_end=(0.735, 0.0), high_end=(0.745, 0.0)),
            PatchRun(u=0.72, angle=0.4, weight=2.0, low_end=(0.715, 0.0), high_end=(0.725, 0.0))]
    a, b, c = turned_angles(runs, SEP)
    comb_ab, comb_bc = 0.1, (0.2 + 0.8) / 3
    assert a == pytest.approx(0.0 + 0.5 * (comb_ab - 0.0))
    assert b == pytest.approx(0.2 + 0.5 * (comb_ab - 0.2) + 0.5 * (comb_bc - 0.2))
    assert c == pytest.approx(0.4 + 0.5 * (comb_bc - 0.4))
    assert turned_angles(runs[::-1], SEP) == pytest.approx([c, b, a])  # order given kept


def test_case_keys():
    base = {"material": {"young": 210e9, "poisson": 0.28},
            "geometry": {"type": "wheel-rail"}, "normal": {"load": 80e3}}
    case = Case.from_dict(base)
    assert case.patch_settings.separation == SEP
    given = Case.from_dict({**base, "geometry": {"type": "wheel-rail",
                                                 "separation_distance": 0.006,
                                                 "combine_distance": 0.003}})
    assert given.patch_settings.separation.turn_distance == pytest.approx(0.009)
    assert Case.from_dict(given.to_dict()) == given
    with pytest.raises(CaseError, match="separation_distance"):
        Case.from_dict({**base, "geometry": {"type": "wheel-rail",
                                             "separation_distance": -0.001}})


def _varfric():
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        import validate_varfric
    finally:
        sys.path.pop(0)
    return validate_varfric, {c["case"]: c for c in validate_varfric.contact_cases()}


@pytest.fixture(scope="module")
def case3():
    """CONTACT's case 3 of mbench_a22_varfric (two patches 6.8 mm apart, its D_SEP 6 mm
    and D_TURN 9 mm) solved from the wheelset's velocities, with CONTACT's patches."""
    v, cases = _varfric()
    case = cases[3]
    sol = rc.solve(v.case_dict(case, None, "patch"))
    theirs = sorted(case["patches"], key=lambda p: abs(p["delta"]))
    ours = sorted(sol.patches, key=lambda p: abs(p.geometry.contact_angle))
    return v, case, sol, ours, theirs


def test_contact_two_patch_case_within_the_targets(case3):
    """Both patches of case 3 meet every target of the validation (forces 2 % / 5 %, floor
    0.2 % of mu F_N; p_max 1 %, area 3 %), their contact angles are CONTACT's turned ones
    (0.2480 and 0.2930 rad, where the rail under the shallow patch is at 0.133 rad) within
    1e-3 rad, the coefficient read there CONTACT's within 2e-3, and the creepages formed at
    the patches CONTACT's within 1 % (the spin, which follows the angle, included)."""
    v, _, sol, ours, theirs = case3
    assert sol.converged and len(ours) == 2
    for p, q in zip(ours, theirs, strict=True):
        got = v.values(p, q)
        assert v.misses(got, q) == [], (got, q)
        assert abs(-p.geometry.contact_angle - q["delta"]) < 1e-3
        assert abs(got["mu"] - q["mu"]) < 2e-3
        xi, eta, phi = p.reported_creepage
        for a, b, floor in ((xi, q["cksi"], 1e-6), (eta, q["ceta"], 1e-6),
                            (phi * 1e-3, q["cphi"], 1e-9)):
            assert abs(a - b) <= max(0.01 * abs(b), floor), (a, b)


def test_without_turning_the_shallow_patch_misses(case3):
    """The same case with the turning window closed (D_TURN = D_SEP): the shallow patch is
    solved at the rail's own angle, 0.115 rad from CONTACT's, and misses its targets - the
    check above can fail."""
    v, case, _, _, theirs = case3
    d = v.case_dict(case, None, "patch")
    d["geometry"]["turn_distance"] = d["geometry"]["separation_distance"]
    sol = rc.solve(d)
    ours = sorted(sol.patches, key=lambda p: abs(p.geometry.contact_angle))
    assert abs(-ours[0].geometry.contact_angle - theirs[0]["delta"]) > 0.1
    assert v.misses(v.values(ours[0], theirs[0]), theirs[0]) != []


def test_patches_apart_beyond_the_window_are_unchanged(case3):
    """Case 3 with a window that ends below the patches' 6.8 mm (D_SEP 3 mm, D_TURN 4.5 mm):
    nothing is turned - each patch's angle is its rail's weighted inclination, and the
    solution is bit for bit the one with the rule switched off."""
    v, case, _, _, _ = case3
    d = v.case_dict(case, None, "patch")
    near = {**d, "geometry": {**d["geometry"], "separation_distance": 0.003,
                              "combine_distance": 0.0015}}
    off = {**d, "geometry": {**d["geometry"], "separation_distance": 0.003,
                             "turn_distance": 0.003}}
    a, b = rc.solve(near), rc.solve(off)
    assert len(a.patches) == len(b.patches) == 2
    for p, q in zip(a.patches, b.patches, strict=True):
        assert p.geometry.contact_angle == q.geometry.contact_angle
        assert np.array_equal(p.normal.pressure, q.normal.pressure)
        assert np.array_equal(p.tangential.traction, q.tangential.traction)
        assert p.creep_forces == q.creep_forces
    angles = sorted(abs(p.geometry.contact_angle) for p in a.patches)
    assert angles[0] == pytest.approx(0.1326, abs=5e-4)  # the rail's, not CONTACT's 0.248
