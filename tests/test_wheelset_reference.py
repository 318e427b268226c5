"""The time step's patch frame at CONTACT's reference point in railcontact's own
convention.

``WheelsetContact`` (the time loop and the FMU) solves each patch in the frame at the
weighted centre of the interpenetration, as ``solve()`` does: at the flange root and on the
flange its contact angle, rolling radius and normal force are CONTACT's (its own results in
``models/reference/contact``, S1002/UIC60 Manchester files, 83.3 kN, mu 0.4) within the
targets of ``scripts/validate_contact.py`` and the reference-point tolerances of
``tests/test_reference_point.py``; ``patch_frame="rigid"`` keeps the rigid contact point.
CONTACT's y is our lateral displacement negated; its creepages are turned into
WheelsetContact's (:func:`railcontact.settings.convention.wheel_frame_creepage`: xi changes
sign) and its creep forces compare as ``F_x = -FX``, ``F_s = FS``.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pytest
from conftest import CONTACT_REFERENCE, PROFILES

import railcontact as rc
from railcontact.settings.convention import wheel_frame_creepage
from railcontact.timestep.wheelset import OK, OUTSIDE_VALIDITY

ROOT = Path(__file__).resolve().parents[1]
FLANGE_TARGET = 0.05  # scripts/validate_contact.py TARGETS["flange"]["force"]
TREAD_TARGET = 0.02   # ... ["tread"]["force"]
RADIUS = 0.02e-3      # ... RADIUS_MM [m]
ANGLE = {"tread": 2e-4, "flange": 1e-3}  # tests/test_reference_point.py [rad]


def _rows(y_mm: str) -> list[dict]:
    with (CONTACT_REFERENCE / "wheelrail_dx0.5.csv").open() as f:
        rows = {r["side"]: r for r in csv.DictReader(f)
                if r["tol"] == "default" and r["y_mm"] == y_mm}
    return [rows["left"], rows["right"]]


def _contact(patch_frame: str | None = None) -> rc.WheelsetContact:
    steel = rc.Material(2 * 82e9 * 1.28, 0.28)  # CONTACT's G = 82 GPa, nu = 0.28
    return rc.WheelsetContact(
        rc.Track(rc.read_profile(str(PROFILES / "MBench_UIC60_v3.prr"), "rail"), 0.0),
        rc.Wheelset(rc.read_profile(str(PROFILES / "MBench_S1002_v3.prw"), "wheel"), 0.46),
        rc.ElasticPair.of(steel, steel),
        rc.ContactSettings(friction=0.4, normal_tolerance=1e-5, tangential_tolerance=1e-5,
                           load_tolerance=1e-5),
        patch_frame=patch_frame)


def _solve(wc: rc.WheelsetContact, rows: list[dict]) -> rc.WheelsetResult:
    creep = tuple(wheel_frame_creepage((float(r["cksi"]), float(r["ceta"]),
                                        float(r["cphi"]) * 1e3)) for r in rows)
    return wc.solve(rc.Pose(-float(rows[0]["y_mm"]) * 1e-3), loads=(83.3e3, 83.3e3),
                    creepages=creep)


@pytest.mark.parametrize("y_mm", ["5.0", "7.0"])  # right wheel: flange root, flange
def test_wheelset_contact_is_at_contacts_reference_point(y_mm):
    rows = _rows(y_mm)
    res = _solve(_contact(), rows)  # the default frame: the reference point
    for w, row in zip(res.wheels, rows, strict=True):
        zone = "flange" if w.side == "right" else "tread"
        target = FLANGE_TARGET if zone == "flange" else TREAD_TARGET
        (p,) = w.patches
        assert p.geometry.rigid is not None  # solved in the frame at the reference point
        # ok, or outside validity (Y/Q on the flange): solved either way
        assert w.status in (OK, OUTSIDE_VALIDITY), w.message
        assert w.contact_angle == pytest.approx(abs(float(row["delta_rad"])),
                                                abs=ANGLE[zone])
        assert w.rolling_radius == pytest.approx(float(row["r_roll_kin_mm"]) * 1e-3,
                                                 abs=RADIUS)
        assert w.normal_force == pytest.approx(float(row["FN"]), rel=target)
        # the creep forces as well
        floor = 0.002 * 0.4 * float(row["FN"])
        assert w.creep_force[0] == pytest.approx(
            -float(row["FX"]), abs=max(target * abs(float(row["FX"])), floor))
        assert w.creep_force[1] == pytest.approx(
            float(row["FS"]), abs=max(target * abs(float(row["FS"])), floor))


def test_the_rigid_frame_stays_available():
    """``patch_frame="rigid"``: each patch at its rigid contact point, whose angle at the
    flange root is not CONTACT's (the issue's 8-30 % in F_x came from it)."""
    rows = _rows("5.0")
    res = _solve(_contact("rigid"), rows)
    right = res.right
    (p,) = right.patches
    assert p.geometry.rigid is None  # no reference-point frame formed
    assert right.contact_angle == pytest.approx(p.geometry.contact_angle)
    assert abs(right.contact_angle - abs(float(rows[1]["delta_rad"]))) > ANGLE["flange"]
    assert math.isfinite(right.normal_force) and right.normal_force > 0


def test_warm_steps_form_the_frame_at_the_previous_approach():
    """A time series towards the flange root (normal problem: every load pass is a frame
    formed again): from the third step on, the tread wheel takes one pass a step (its frame
    formed at the previous steps' approach, extrapolated in time) and the flange-root wheel
    at most two (its approach is steeper in y); the last step's frame is the one a cold
    solve of the same pose forms, within the tolerance of
    :data:`~railcontact.contact.wheelrail.WARM_REFERENCE_RTOL` (angle 3.3e-5 rad, rolling
    radius 0.3 um for 1e-3 of the approach)."""
    wc = _contact()
    for k in range(8):  # 0.02 mm per 1 ms step towards the right flange
        y = -5e-3 - 2e-5 * k
        res = wc.solve(rc.Pose(y), loads=(83.3e3, 83.3e3), time=1e-3 * k)
        if k >= 2:
            assert res.left.load_passes == 1
            assert res.right.load_passes <= 2
    cold = _contact().solve(rc.Pose(y), loads=(83.3e3, 83.3e3))
    for w, c in zip(res.wheels, cold.wheels, strict=True):
        assert w.contact_angle == pytest.approx(c.contact_angle, abs=3.3e-5)
        assert w.rolling_radius == pytest.approx(c.rolling_radius, abs=0.3e-6)
        assert w.normal_force == pytest.approx(c.normal_force, rel=1e-3)
