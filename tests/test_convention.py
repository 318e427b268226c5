"""CONTACT's conventions on request.

``convention = "contact"`` reads a wheel-rail case's creepages and reports its forces as
CONTACT's wheel-rail module does (the rail is body 1, its contact normal points into the
rail, the right wheel is mirrored): checked against CONTACT's own results for two of its
cases (``models/reference/contact/``), one per wheel, where the signs decide the
answer - on a flange the lateral creep force carries part of the wheel load, so a wrong
sign gives a wrong normal force, not only a wrong sign.
"""

from __future__ import annotations

import csv
import json
import math
import sys
from pathlib import Path

import pytest
from conftest import CONTACT_REFERENCE, PROFILES

import railcontact as rc
from railcontact import CaseError, RailContactError
from railcontact.io.jsonout import solution_json
from railcontact.settings.convention import side_creepage

ROOT = Path(__file__).resolve().parents[1]


def _row(side: str, y_mm: str) -> dict:
    with (CONTACT_REFERENCE / "wheelrail_dx0.5.csv").open() as f:
        return next(r for r in csv.DictReader(f) if r["tol"] == "default"
                    and r["side"] == side and r["y_mm"] == y_mm)


def _contact_case(row: dict, convention: str = "contact") -> dict:
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        from bench_wheelrail import wheel_case
    finally:
        sys.path.pop(0)
    return wheel_case(row, 0.5, (1e-5, 1e-5), ("infcon", "fastrip"), PROFILES, None,
                      convention=convention)


@pytest.mark.parametrize("side, y_mm", [("left", "-7.0"), ("right", "5.0")])
def test_contact_convention_gives_contacts_forces(side, y_mm):
    """The left wheel on its flange (CONTACT's y = -7 mm, 1.21 rad) and the right wheel at
    its flange root (+5 mm), CONTACT's creepages as CONTACT gives them: FN, FX, FS, MN
    are CONTACT's (flange: N within 0.3 %, the creep forces within 2 % of mu N)."""
    row = _row(side, y_mm)
    sol = rc.solve(_contact_case(row))
    (p,) = sol.patches
    fx, fs, mn = p.creep_forces
    mu_n = 0.4 * float(row["FN"])
    assert p.normal.force == pytest.approx(float(row["FN"]), rel=3e-3)
    assert fx == pytest.approx(float(row["FX"]), abs=0.02 * mu_n)
    assert fs == pytest.approx(float(row["FS"]), abs=0.02 * mu_n)
    assert mn * 1e3 == pytest.approx(float(row["MN"]), rel=0.03)  # CONTACT's N mm
    d = json.loads(solution_json(sol))
    assert d["convention"] == "contact"
    assert d["patches"][0]["tangential"]["force"] == pytest.approx([fx, fs])


@pytest.mark.parametrize("side", ["left", "right"])
def test_both_conventions_pose_the_same_problem(side):
    """CONTACT's creepages in "contact" and the same creepages turned into railcontact's
    roles in "railcontact" are one problem: the forces differ only by the map."""
    row = _row(side, "-3.0")
    a = rc.solve(_contact_case(row, "contact")).patches[0]
    b = rc.solve(_contact_case(row, "railcontact")).patches[0]
    s = 1.0 if side == "left" else -1.0
    fx, fs, mn = b.creep_forces
    assert a.creep_forces == pytest.approx((-fx, s * fs, s * mn), rel=1e-9)
    assert a.normal.force == pytest.approx(b.normal.force, rel=1e-12)
    assert side_creepage(side_creepage((1, 2, 3), side, "contact"), side, "contact") == (
        1, 2, 3)


def test_wheelset_contact_in_contacts_convention():
    """WheelsetContact(convention="contact") takes CONTACT's creepages for both wheels (the
    same numbers on the left and the right, as CONTACT's input has them) and returns
    CONTACT's creep forces: CONTACT's y = 5 mm, left on the tread, right at its flange root
    (0.17 rad)."""
    rows = [_row(s, "5.0") for s in ("left", "right")]
    steel = rc.Material(2 * 82e9 * 1.28, 0.28)
    wc = rc.WheelsetContact(
        rc.Track(rc.read_profile(str(PROFILES / "MBench_UIC60_v3.prr"), "rail"), 0.0),
        rc.Wheelset(rc.read_profile(str(PROFILES / "MBench_S1002_v3.prw"), "wheel"), 0.46),
        rc.ElasticPair.of(steel, steel),
        rc.ContactSettings(friction=0.4, normal_tolerance=1e-5, tangential_tolerance=1e-5,
                           load_tolerance=1e-5),
        convention="contact")
    creep = tuple((float(r["cksi"]), float(r["ceta"]), float(r["cphi"]) * 1e3) for r in rows)
    res = wc.solve(rc.Pose(-5e-3), loads=(83.3e3, 83.3e3), creepages=creep)
    for w, row in zip(res.wheels, rows, strict=True):
        mu_n = 0.4 * float(row["FN"])
        assert w.status == 0
        assert w.creepages[0] == pytest.approx(creep[0 if w.side == "left" else 1])
        assert w.normal_force == pytest.approx(float(row["FN"]), rel=1e-3)
        assert w.creep_force[0] == pytest.approx(float(row["FX"]), abs=0.02 * mu_n)
        assert w.creep_force[1] == pytest.approx(float(row["FS"]), abs=0.02 * mu_n)
        assert w.spin_moment * 1e3 == pytest.approx(float(row["MN"]), rel=0.03)
        assert w.patches[0].geometry.contact_angle == pytest.approx(
            abs(float(row["delta_rad"])), abs=1e-3)


def _s1002_case(convention, load=83.3e3) -> dict:
    return {"convention": convention, "material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "wheel-rail", "lateral_displacement": 0.002},
            "grid": {"dx": 1e-3, "dy": 1e-3}, "normal": {"load": load},
            "tangential": {"creepage": [2e-4, 2e-4, 0.1], "friction": 0.4}}


@pytest.mark.parametrize("value", ["CONTACT", "kontakt", 1, None])
def test_a_bad_convention_names_the_allowed_ones(value):
    with pytest.raises(CaseError, match="convention must be one of 'railcontact', 'contact'"):
        rc.solve(_s1002_case(value))
    with pytest.raises(CaseError, match="'railcontact', 'contact'"):
        rc.solve(_s1002_case("railcontact"), convention=value if value is not None else 0)
    with pytest.raises(RailContactError, match="'railcontact', 'contact'"):
        rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail")),
                           rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                           rc.ElasticPair.of(rc.STEEL, rc.STEEL), convention=value)


def test_no_contact_is_no_contact_in_contacts_convention():
    """Without interpenetration there is no reference point to form: no patch, no NaN (a
    case with zero load; a wheel of the wheelset unloaded)."""
    sol = rc.solve(_s1002_case("contact", load=0.0))
    assert sol.patches == []
    text = solution_json(sol)
    assert "NaN" not in text and json.loads(text)["convention"] == "contact"
    wc = rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail")),
                            rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                            rc.ElasticPair.of(rc.STEEL, rc.STEEL), convention="contact")
    r = wc.solve(rc.Pose(0.0), loads=(0.0, 83.3e3),
                 creepages=((2e-4, 2e-4, 0.0), (2e-4, 2e-4, 0.0)))
    assert r.left.status == 2 and r.left.creep_force == (0.0, 0.0)
    assert r.right.status == 0
    assert all(math.isfinite(v) for w in r.wheels for v in (*w.creep_force, w.spin_moment))
