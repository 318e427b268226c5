"""CONTACT's contact reference point against CONTACT's own results.

The cases of ``models/reference/contact/`` (S1002/UIC60 Manchester files, 83.3 kN,
0.5 mm, both wheels, -8 .. 8 mm): CONTACT reports the centre of the interpenetration area
weighted by the squared interpenetration, with the contact angle weighted the same way.
railcontact's ``reference_point`` must be the same point: the rail and wheel profile
coordinates, the contact angle and the lateral track position. CONTACT's y-like
quantities point the other way (its left wheel's y is ours negated; the right wheel is
mirrored), hence the signs below. CONTACT's rolling radius is its kinematic one
(``r_roll_kin_mm``): the wheel's along the contact normal through the point.
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import pytest
from conftest import CONTACT_REFERENCE, PROFILES

import railcontact as rc
from railcontact.io.jsonout import solution_json

ROOT = Path(__file__).resolve().parents[1]


def _rows() -> list[dict]:
    with (CONTACT_REFERENCE / "wheelrail_dx0.5.csv").open() as f:
        return [r for r in csv.DictReader(f) if r["tol"] == "default"]


def _case(row: dict) -> dict:
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        from bench_wheelrail import wheel_case
    finally:
        sys.path.pop(0)
    return wheel_case(row, 0.5, (1e-3, 1e-2), ("infcon", "fastrip"), PROFILES, None)


@pytest.mark.parametrize("row", _rows(), ids=lambda r: f"{r['side']}{r['y_mm']}")
def test_reference_point_is_contacts(row):
    sol = rc.solve(_case(row))
    (patch,) = sol.patches
    ref = json.loads(solution_json(sol))["patches"][0]["reference_point"]
    mirror = -1.0 if row["side"] == "left" else 1.0  # CONTACT's y against ours
    tread = abs(float(row["y_mm"])) <= 4.0
    # each patch is solved in the frame at its reference point, formed as CONTACT forms
    # it: CONTACT's point within 0.01 mm, its angle within 1e-4 rad on
    # the tread and 4e-4 rad on the flange, its kinematic rolling radius within 0.017 mm
    tol_mm, tol_rad = (0.015, 2e-4) if tread else (0.015, 1e-3)
    assert ref["rail_profile_coordinate"] * 1e3 == pytest.approx(
        mirror * float(row["ycp_r"]), abs=tol_mm)
    assert ref["wheel_profile_coordinate"] * 1e3 == pytest.approx(
        mirror * float(row["ycp_w"]), abs=tol_mm)
    assert ref["contact_angle"] == pytest.approx(-mirror * float(row["delta_rad"]),
                                                 abs=tol_rad)
    assert abs(ref["position"][1]) * 1e3 == pytest.approx(abs(float(row["ycp_tr"])),
                                                           abs=tol_mm)
    assert ref["rolling_radius"] * 1e3 == pytest.approx(float(row["r_roll_kin_mm"]),
                                                        abs=0.02)
    # the rigid contact point is not the reference point near the flange root
    if float(row["y_mm"]) * -mirror in (-5.0, 0.0):
        assert abs(patch.geometry.rigid.rail_y - ref["rail_profile_coordinate"]) > 1e-4
