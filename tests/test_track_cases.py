"""Case files on real track - curvature, rail deviations, velocities instead of creepages -
against independent truth: CONTACT's track results (``models/reference/contact/track/``),
the equivalence of curvature and yaw rate, mirror symmetry, a rail offset as the opposite
wheelset displacement, the energy balance of the frictional power, and the rail placement
CONTACT printed."""

from __future__ import annotations

import json
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from conftest import PROFILES

import railcontact as rc
from railcontact.cli import main
from railcontact.geometry.kinematics import WheelsetMotion, patch_kinematics
from railcontact.geometry.track import Track

ROOT = Path(__file__).resolve().parents[1]


def _script():
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        import validate_track
    finally:
        sys.path.pop(0)
    return validate_track


V = _script()
ROWS = {r["case_id"]: r for r in V.contact_rows()}


@pytest.mark.parametrize("case_id", [
    "A4_L_036",   # curve R = 600 m and yaw 3 mrad
    "A5c_L_049",  # curve the other way, yaw and yaw rate
    "A0_R_010",   # flange root, full sliding
    "B5_L_077",   # rail offset lateral and vertical, rail roll, gauge widened
    "B7_R_084",   # rail velocities
    "B6_L_081",   # rail at 1:20
    "C1_L_089",   # upright idealised rail, canted
    "C1_R_092",   # measured worn wheel
])
def test_case_meets_contacts_targets(case_id):
    """The targets of ``scripts/validate_track.py`` (forces 2 % / 5 %, p_max 1 %, area 3 %,
    angle 1e-3 rad, rolling radius 0.02 mm, creepages 1 %, frictional power 3 %)."""
    row = ROWS[case_id]
    sol = rc.solve(V.track_case(row, PROFILES))
    assert sol.converged
    diff = V.differences(V.railcontact_values(sol), V.contact_values(row), V.zone(row))
    missed = {k: v for k, v in diff.items() if v[0] > 1.0}
    assert not missed, missed


@pytest.mark.parametrize("rail, cant", [("MBench_UIC60_v3.prr", 0.0),
                                        ("MBench_UIC60_v3.prr", 0.025),
                                        ("r300_wide.prr", 0.025)])
def test_rail_is_placed_where_contact_places_it(rail, cant):
    """The rail profile's origin (gauge 1435 mm at 14 mm below the top, the top at 0) is
    where CONTACT's debug print put it (columns ``rail_origin_*_tr``: y to the right, z
    down), to 1e-3 mm."""
    row = next(r for r in ROWS.values() if r["rail_profile"] == rail
               and float(r["cant_rad"]) == cant and float(r["gauge_mm"]) == 1435.0
               and float(r["rail_dy_mm"]) == 0.0 and float(r["rail_roll_rad"]) == 0.0
               and float(r["rail_dz_mm"]) == 0.0)
    track = Track(rc.read_profile(str(PROFILES / rail), "rail"), cant, 1.435, 0.014)
    u, z = track.rail_origin
    sgn = -1.0 if row["side"] == "left" else 1.0  # CONTACT's y of the side's rail
    assert sgn * u * 1e3 == pytest.approx(float(row["rail_origin_y_tr"]), abs=1e-3)
    assert -z * 1e3 == pytest.approx(float(row["rail_origin_z_tr"]), abs=1e-3)


def _case(side="left", lateral=0.0, yaw=0.0, curvature=0.0, rail_offset=(0.0, 0.0),
          rail_roll=0.0, **kinematics) -> dict:
    """S1002 on UIC60 (the benchmark's files), 83.3 kN, mu 0.4, 1 mm elements."""
    return {
        "material": {"young": 2 * 82e9 * 1.28, "poisson": 0.28},
        "geometry": {"type": "wheel-rail", "wheel": str(PROFILES / "MBench_S1002_v3.prw"),
                     "rail": str(PROFILES / "MBench_UIC60_v3.prr"), "inclination": 0.0,
                     "side": side, "lateral_displacement": lateral, "yaw": yaw,
                     "curvature": curvature, "rail_offset": list(rail_offset),
                     "rail_roll": rail_roll},
        "grid": {"dx": 1e-3, "dy": 1e-3},
        "normal": {"load": 83.3e3, "tolerance": 1e-6},
        "tangential": {"friction": 0.4, "tolerance": 1e-6},
        "kinematics": {"speed": 30.0, **kinematics},
    }


def _results(case: dict) -> tuple[np.ndarray, np.ndarray]:
    """(creepages, [F_N, F_x, F_s, M_n, p_max, Y, Z of the reference point]) of the
    case's one patch, railcontact's convention (side frame)."""
    (p,) = rc.solve(case).patches
    return (np.array(p.creepage),
            np.array([p.normal.force, *p.creep_forces, p.normal.max_pressure,
                      *p.reference.position[1:]]))


def test_curvature_is_the_yaw_rate_it_equals():
    """CONTACT's check: a curve of curvature k with no yaw rate gives the results of
    tangent track with the yaw rate V k (the wheelset centred). The rail turns about the
    track centre line at its point P, the wheel about its centre at its point Q, the
    normal approach d (~0.1 mm) below P: the creepages differ by about k d / xi (~1e-6
    relative; CONTACT's four printed digits agree)."""
    k = 1 / 600
    c1, r1 = _results(_case(curvature=k))
    c2, r2 = _results(_case(yaw_rate=30.0 * k))
    assert c1[0] != 0.0 and c1 == pytest.approx(c2, rel=1e-5, abs=1e-12)
    assert r1 == pytest.approx(r2, rel=1e-5)


def test_curvature_changes_xi_by_k_times_the_rails_lateral_position():
    """On a left curve the left (inner) rail moves forward with V k Y in the track's frame:
    the wheel's longitudinal creepage falls by about k Y (CONTACT's check: -1.25e-3 at
    R = 600 m, Y = 0.75 m), the spin by V k cos(gamma) / V."""
    k = 1 / 600
    c0, r0 = _results(_case())
    c1, _ = _results(_case(curvature=k))
    y = r0[5]
    assert c1[0] - c0[0] == pytest.approx(-k * y, rel=0.01)


def test_mirror_symmetry():
    """The right wheel at (y, yaw, k, lateral velocity, yaw rate, rail dY, rail roll, rail
    vY, rail roll rate) is the left wheel at the negated values (dZ, vZ kept): the same
    creepages and forces in railcontact's side frame, the contact point mirrored."""
    kin = {"lateral_velocity": 0.03, "yaw_rate": 0.02, "rail_velocity": [0.02, 0.01],
           "rail_roll_rate": 0.05, "spin_speed": 1.001 * 30 / 0.46}
    left = _case("left", 0.003, 0.002, 1 / 900, (0.001, 0.0005), 0.003, **kin)
    mirrored = {**kin, "lateral_velocity": -0.03, "yaw_rate": -0.02,
                "rail_velocity": [-0.02, 0.01], "rail_roll_rate": -0.05}
    right = _case("right", -0.003, -0.002, -1 / 900, (-0.001, 0.0005), -0.003, **mirrored)
    cl, rl = _results(left)
    cr, rr = _results(right)
    assert abs(cl[1]) > 1e-4 and abs(cl[2]) > 1e-2  # lateral and spin creepage present
    assert cl == pytest.approx(cr, rel=1e-9, abs=1e-14)
    assert rl * [1, 1, 1, 1, 1, -1, 1] == pytest.approx(rr, rel=1e-9)


def test_rail_offset_is_the_opposite_wheelset_displacement():
    """CONTACT's check: the left rail offset by dY (the wheelset centred) gives the results
    of the wheelset displaced by -dY (the rail in place), the contact point moved by dY."""
    d = 0.002
    c1, r1 = _results(_case(rail_offset=(d, 0.0)))
    c2, r2 = _results(_case(lateral=-d))
    assert c1 == pytest.approx(c2, rel=1e-6, abs=1e-12)
    assert r1[:5] == pytest.approx(r2[:5], rel=1e-6)
    assert r1[5] - r2[5] == pytest.approx(d, abs=1e-9)


def test_kinematics_mirror_and_equivalence_exactly():
    """:func:`patch_kinematics` alone: mirrored inputs give the same side-frame creepages;
    the curvature equals the yaw rate V k for a centred wheelset (to k times the normal
    approach, the distance of the wheel's point from the rail's); pure rolling at the
    radius of the wheel's point gives no longitudinal creepage."""
    rng = np.random.default_rng(1)
    for _ in range(20):
        p = (rng.normal() * 1e-3, 0.75 + rng.normal() * 0.01, rng.normal() * 1e-4)
        gamma, d = rng.normal() * 0.3, abs(rng.normal()) * 1e-4
        centre = (0.0, rng.normal() * 0.005, 0.46 + rng.normal() * 1e-3)
        roll, yaw = rng.normal() * 1e-3, rng.normal() * 3e-3
        motion = WheelsetMotion(30.0, 30 / 0.46 * (1 + rng.normal() * 1e-3),
                                *(rng.normal(size=4) * [0.03, 0.01, 0.05, 0.05]),
                                rng.normal() * 1e-3, tuple(rng.normal(size=2) * 0.02),
                                rng.normal() * 0.05)
        origin = (0.76, 0.0)
        left = patch_kinematics("left", p, gamma, d, centre, roll, yaw, origin, motion)
        mirror = replace(motion, lateral_velocity=-motion.lateral_velocity,
                         roll_rate=-motion.roll_rate, yaw_rate=-motion.yaw_rate,
                         curvature=-motion.curvature,
                         rail_velocity=(-motion.rail_velocity[0], motion.rail_velocity[1]),
                         rail_roll_rate=-motion.rail_roll_rate)
        right = patch_kinematics("right", (p[0], -p[1], p[2]), gamma, d,
                                 (0.0, -centre[1], centre[2]), -roll, -yaw,
                                 (-origin[0], origin[1]), mirror)
        assert left.creepage == pytest.approx(right.creepage, rel=1e-12, abs=1e-15)
        assert left.velocity == pytest.approx(right.velocity, rel=1e-14)
        centred = (0.0, 0.0, centre[2])
        k = motion.curvature
        a = patch_kinematics("left", p, gamma, d, centred, 0.0, yaw, origin,
                             replace(motion, yaw_rate=0.0))
        b = patch_kinematics("left", p, gamma, d, centred, 0.0, yaw, origin,
                             replace(motion, yaw_rate=motion.speed * k, curvature=0.0))
        # equal but for the rail's point P being d above the wheel's Q (k d)
        assert a.creepage == pytest.approx(b.creepage, rel=1e-6, abs=2 * abs(k) * d)
    r = patch_kinematics("left", (0.0, 0.75, 0.0), 0.05, 1e-4, (0.0, 0.0, 0.47), 0.0, 0.0,
                         (0.76, 0.0), WheelsetMotion(30.0, 1.0))
    rolling = WheelsetMotion(30.0, 30.0 / r.rolling_radius)
    xi, eta, phi = patch_kinematics("left", (0.0, 0.75, 0.0), 0.05, 1e-4, (0.0, 0.0, 0.47),
                                    0.0, 0.0, (0.76, 0.0), rolling).creepage
    assert abs(xi) < 1e-14 and eta == 0.0
    # the spin of a coned wheel rolling purely: -sin(gamma) / r (the wheel's angular
    # velocity about the outward rail normal, over V; its sign in the side frame)
    assert phi == pytest.approx(-math.sin(0.05) / r.rolling_radius, rel=1e-12)


def _quadratic(n: int, creepage) -> rc.PatchSolution:
    case = {"material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "quadratic", "A": 1.0, "B": 5.0},
            "grid": {"nx": n, "ny": n}, "normal": {"load": 74e3},
            "tangential": {"creepage": list(creepage), "friction": 0.3, "tolerance": 1e-6}}
    return rc.solve(case).patches[0]


@pytest.mark.parametrize("creepage", [(1e-3, 0.0, 0.0), (5e-4, 5e-4, 0.3)])
def test_frictional_power_is_the_creep_forces_power(creepage):
    """Energy balance of steady rolling: the traction times the local slip integrated over
    the patch equals F_x xi + F_y eta + M_z phi (per unit rolling speed): the elastic
    displacements carry no net power. On a grid the steady-rolling difference dissipates
    a little more (a first-order error): halving the elements halves the difference, and
    the extrapolation to zero elements meets the balance."""
    errors = []
    for n in (16, 32, 64):
        p = _quadratic(n, creepage)
        fx, fy, mz = p.creep_forces
        balance = fx * creepage[0] + fy * creepage[1] + mz * creepage[2]
        assert balance < 0 and p.frictional_power_per_speed < 0
        errors.append(p.frictional_power_per_speed / balance - 1)
    assert 1.6 < errors[0] / errors[1] < 2.4 and 1.6 < errors[1] / errors[2] < 2.4
    assert abs(2 * errors[2] - errors[1]) < 0.03


def test_frictional_power_is_v_times_the_power_per_speed():
    """With [kinematics] the patch knows its rolling speed: frictional power [W] = V_ref
    times the traction times the relative slip, and V_ref is CONTACT's (about the speed)."""
    (p,) = rc.solve(_case(lateral=0.002)).patches
    assert p.velocity == pytest.approx(30.0, rel=2e-3)
    assert p.frictional_power == pytest.approx(p.velocity * p.frictional_power_per_speed,
                                               rel=1e-14)


def test_case_file_reports_creepage_and_frictional_power(tmp_path, capsys):
    """``railcontact solve CASE --json``: each patch reports the creepages it was solved
    with (in the case's convention) and its frictional power; CONTACT's convention gives
    CONTACT's creepages (a braking wheel's xi is negative in railcontact's, cksi > 0)."""
    row = ROWS["A0_L_002"]
    case = V.track_case(row, PROFILES)
    lines = []
    for table, values in case.items():
        if isinstance(values, dict):
            lines.append(f"[{table}]")
            lines += [f"{k} = {json.dumps(v)}" for k, v in values.items()]
        else:
            lines.insert(0, f"{table} = {json.dumps(values)}")
    path = tmp_path / "track.toml"
    path.write_text("\n".join(lines) + "\n")
    assert main(["solve", str(path), "--json"]) == 0
    (patch,) = json.loads(capsys.readouterr().out)["patches"]
    cksi, ceta, cphi = patch["creepage"]
    assert cksi == pytest.approx(float(row["cksi_6d"]), rel=0.01)
    assert cphi == pytest.approx(float(row["cphi_6d"]) * 1e3, rel=0.01)
    assert patch["frictional_power"] == pytest.approx(float(row["fric_power"]), rel=0.03)


def test_kinematics_and_creepage_exclude_each_other():
    case = _case()
    case["tangential"]["creepage"] = [0.0, 0.0, 0.0]
    with pytest.raises(rc.CaseError, match="creepage or a \\[kinematics\\] table, not both"):
        rc.solve(case)
    case = _case(rail_offset=(0.001, 0.0))
    case["geometry"]["side"] = "both"
    with pytest.raises(rc.CaseError, match="rail of the case's side"):
        rc.solve(case)
    case = _case()  # a rail's velocities, too, are of the case's side's rail
    case["geometry"]["side"] = "both"
    case["kinematics"]["rail_velocity"] = [0.02, 0.0]
    with pytest.raises(rc.CaseError, match="rail_velocity and rail_roll_rate move the rail"):
        rc.solve(case)


def test_kinematic_creepages_beyond_the_solvers_are_refused():
    """Creepages a case's [kinematics] give beyond +-1e3 (a speed too small for the
    lateral velocity) are refused as a case's [tangential] creepage is, naming the
    wheel, the creepages and the speed: the solver's range, as the time step's."""
    case = _case(lateral_velocity=0.05)
    case["kinematics"]["speed"] = 1e-6
    with pytest.raises(rc.CaseError, match=r"left wheel: the \[kinematics\] velocities "
                       r"give the creepages \(.*e\+04.*\) beyond \+-1000 \(speed 1e-06"):
        rc.solve(case)


def test_example_case_file_is_contacts_curve_case(root):
    """``models/cases/mbench_curve_r600.toml`` poses CONTACT's case A1_L_013 (curve of
    600 m to the right, left wheel): its results meet the targets against CONTACT's."""
    row = ROWS["A1_L_013"]
    sol = rc.solve(root / "models" / "cases" / "mbench_curve_r600.toml")
    assert sol.converged
    diff = V.differences(V.railcontact_values(sol), V.contact_values(row), V.zone(row))
    assert not {k: v for k, v in diff.items() if v[0] > 1.0}
