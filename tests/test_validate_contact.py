"""railcontact beside CONTACT on a few of CONTACT's own wheel-rail cases: the targets
of ``scripts/validate_contact.py`` - tread (|y| <= 4 mm): forces
within 2 % (floor 0.2 % of mu N), p_max and area within 1 %, rolling radius within 0.02 mm;
flange root and flange (|y| >= 5 mm): within 5 %. The cases are those where the targets
were missed before the patch frame was at the reference point and its grid on it (the
tread near the flange root, both wheels) and the flange root and the flange; the whole
sweep is the script's (7 s).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from conftest import CONTACT_REFERENCE, PROFILES

import railcontact as rc

ROOT = Path(__file__).resolve().parents[1]


def _script():
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        import validate_contact
    finally:
        sys.path.pop(0)
    return validate_contact


@pytest.mark.parametrize("side, y_mm", [("left", -2.0), ("right", 1.0), ("left", -5.0),
                                        ("right", 8.0)])
def test_case_meets_the_targets(side, y_mm):
    v = _script()
    row = next(r for r in v.contact_rows(CONTACT_REFERENCE, 0.5)
               if r["side"] == side and float(r["y_mm"]) == y_mm)
    case = v.wheel_case(row, 0.5, v.TOLERANCE, ("infcon", "fastrip"), PROFILES,
                        None, convention="contact")
    sol = rc.solve(case)
    assert sol.converged
    ours, theirs = v.railcontact_values(sol, side), v.contact_values(row)
    zone = "tread" if abs(y_mm) <= v.TREAD_MM else "flange"
    assert v.misses(ours, theirs, zone) == [], (ours, theirs)
