"""The wheels of a wheel-rail case's solution (``railcontact solve``): each loaded wheel's
force in the track frame, Y/Q and validity, as a time step reports its wheels."""

from __future__ import annotations

import json
import math

import pytest

import railcontact as rc
from railcontact.cli import main
from railcontact.io.wheels import case_wheels
from railcontact.timestep.validity import FLANGE_CLIMB, NADAL, Y_Q


def _case(lateral: float, tangential: bool = False) -> dict:
    """S1002 on 60E1 at 1:40, the left wheel, 83.3 kN, 0.5 mm elements."""
    case = {"material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                         "inclination": math.atan(1 / 40), "lateral_displacement": lateral,
                         "side": "left"},
            "grid": {"dx": 5e-4, "dy": 5e-4},
            "normal": {"load": 83.3e3, "tolerance": 1e-3}}
    if tangential:
        case["tangential"] = {"friction": 0.3}
        case["kinematics"] = {"speed": 30.0}
    return case


def _toml(case: dict) -> str:
    """A case of tables of numbers and strings as TOML."""
    return "".join(f"[{table}]\n" + "".join(f"{k} = {json.dumps(v)}\n" for k, v in keys.items())
                   for table, keys in case.items())


@pytest.mark.parametrize("lateral", [0.008, 0.02])
def test_a_frictionless_flange_has_y_q_tan_gamma_and_is_flagged_past_its_steepest_point(
        lateral):
    """Without creep forces a single patch pushes along its normal: Y/Q = tan(gamma),
    its contact angle (side frame). S1002's flange is steepest (70 deg) at S = -38.45
    mm; these poses put the contact past it, lower on the flank (68.9 and 35.1 deg): a
    flange climb, as the time step says of the same contact. Its exit status stays the
    solve's."""
    sol = rc.solve(_case(lateral))
    (patch,) = sol.patches
    (wheel,) = case_wheels(sol)
    assert wheel.side == "left"
    assert wheel.derailment_quotient == pytest.approx(math.tan(patch.geometry.contact_angle),
                                                      rel=1e-12)
    assert wheel.track_force[2] == pytest.approx(83.3e3, rel=1e-3)
    assert wheel.validity.flags & FLANGE_CLIMB
    assert not wheel.validity.flags & NADAL  # (a frictionless flange's limit: tan 70 deg)
    assert bool(wheel.validity.flags & Y_Q) == (wheel.derailment_quotient > 0.8)


def test_solve_reports_the_wheels_in_its_json_and_warns_outside_validity(tmp_path, capsys):
    """``railcontact solve --json`` carries ``wheels``; a wheel outside validity is a
    warning on stderr naming it (exit 0: solved as asked), one within it none. The time
    step at the same pose with the same kinematics flags the same flange climb."""
    for lateral, outside in ((-0.002, False), (0.02, True)):
        path = tmp_path / f"c{lateral}.toml"
        path.write_text(_toml(_case(lateral, tangential=True)))
        assert main(["solve", str(path), "--json"]) == 0
        out = capsys.readouterr()
        (wheel,) = json.loads(out.out)["wheels"]
        assert wheel["side"] == "left"
        assert bool(wheel["validity"] & FLANGE_CLIMB) == outside
        assert ("left wheel outside the model's validity: " in out.err) == outside
        if outside:
            assert "flange climb: contact at S = -47" in wheel["validity_message"]
    steel = rc.Material(206e9, 0.28)
    step = rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46), rc.ElasticPair.of(steel, steel),
        rc.ContactSettings(friction=0.4, element_size=5e-4, warm_start="none"))
    r = step.solve(rc.Pose(0.02), loads=(83.3e3, 83.3e3), kinematics=rc.Kinematics(30.0))
    assert r.left.validity & FLANGE_CLIMB


def test_nadals_limit_takes_the_cases_friction():
    """On the flange at 12 mm (54.8 deg, past the steepest point) with mu = 0.3 the wheel
    is beyond Nadal's limit of S1002's 70 deg flange for mu = 0.3, (tan 70 - 0.3) / (1 +
    0.3 tan 70) = 1.342, named with that mu (not the time step's default 0.4)."""
    (wheel,) = case_wheels(rc.solve(_case(0.012, tangential=True)))
    limit = (math.tan(math.radians(70)) - 0.3) / (1 + 0.3 * math.tan(math.radians(70)))
    assert wheel.derailment_quotient > limit
    assert wheel.validity.flags & NADAL
    assert f"beyond Nadal's limit {limit:.3g} (flange 70 deg, mu 0.3)" in \
        wheel.validity.message, wheel.validity.message


def test_a_quadratic_case_has_no_wheels(root):
    sol = rc.solve(root / "models" / "cases" / "hertz_paper.toml")
    assert case_wheels(sol) == []
