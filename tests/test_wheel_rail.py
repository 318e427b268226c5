"""Wheel–rail cases through the case API and the CLI."""

import copy
import json
import math
import subprocess
import sys

import pytest

import railcontact as rc
from railcontact import CaseError, hertz


@pytest.fixture(scope="module")
def base(request):
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    return rc.load_case(root / "models" / "cases" / "s1002_60e1_dy-2mm.toml").to_dict()


def variant(case, **geometry):
    c = copy.deepcopy(case)
    normal = geometry.pop("normal", None)
    c["geometry"].update(geometry)
    if normal is not None:
        c["normal"] = {"tolerance": 1e-8, "estimate": "none", **normal}
    return c


@pytest.mark.parametrize("dy", [0.0, -0.002])
def test_small_approach_is_hertz_of_the_local_curvatures(base, dy):
    """For a small approach the gap is locally quadratic: the wheel-rail BEM equals the
    quadratic-gap BEM with the contact point's A, B, and both approach Hertz."""
    case = variant(base, lateral_displacement=dy, normal={"penetration": 2e-6})
    sol = rc.solve(case)
    assert len(sol.patches) == 1
    p = sol.patches[0]
    A, B = p.curvatures
    delta_n = p.geometry.normal_penetration(2e-6)
    assert p.normal.penetration == pytest.approx(delta_n)
    quad = copy.deepcopy(case)
    quad["geometry"] = {"type": "quadratic", "A": A, "B": B}
    quad["normal"]["penetration"] = delta_n
    qn = rc.solve(quad).patches[0].normal
    hz = hertz(A, B, rc.validate_case(case).pair, penetration=delta_n)
    assert p.normal.force == pytest.approx(qn.force, rel=0.02)
    assert p.normal.force == pytest.approx(hz.load, rel=0.03)
    assert p.normal.max_pressure == pytest.approx(hz.max_pressure, rel=0.03)


def test_load_control_meets_the_wheel_load(base):
    sol = rc.solve(base)
    (p,) = sol.patches
    vertical = p.normal.force * math.cos(p.geometry.contact_angle)
    assert vertical == pytest.approx(83.3e3, rel=1e-9)
    assert p.normal.converged and not p.normal.touches_boundary


def test_two_patch_case_solves_each_patch(base):
    case = variant(base, lateral_displacement=0.005, normal={"penetration": 5e-5})
    # gap minima 0.0306 mm apart, saddle at 0.0597 mm: two patches for 0.05 mm
    sol = rc.solve(case)
    assert len(sol.patches) == 2
    angles = sorted(p.geometry.contact_angle for p in sol.patches)
    assert math.degrees(angles[0]) < 10 < math.degrees(angles[1])
    for p in sol.patches:
        assert p.normal.force > 0 and p.normal.converged


def test_both_wheels_symmetric_at_zero(base):
    sol = rc.solve(variant(base, lateral_displacement=0.0, side="both"))
    left, right = sol.patches
    assert left.normal.force == pytest.approx(right.normal.force, rel=1e-9)
    assert left.geometry.position[1] == pytest.approx(-right.geometry.position[1])


def test_cli_json_has_contact_geometry(root):
    r = subprocess.run([sys.executable, "-m", "railcontact", "solve",
                        str(root / "models/cases/s1002_60e1_dy-2mm.toml"), "--json"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    p = json.loads(r.stdout)["patches"][0]
    assert len(p["contact_point"]) == 3
    assert 0.70 < abs(p["contact_point"][1]) < 0.78  # on the left rail head (Y > 0)
    assert 0 < p["contact_angle"] < 0.2
    assert 0.45 < p["rolling_radius"] < 0.47
    assert p["normal"]["force"] * math.cos(p["contact_angle"]) == pytest.approx(83.3e3)


@pytest.mark.parametrize("geometry, match", [
    ({"wheel": "XYZ123"}, "wheel profile"),
    ({"rail": "no/such/file.prr"}, "nor an existing file"),
    ({"lateral_displacement": 0.3}, "beyond the profiles"),
    ({"side": "middle"}, "side"),
    ({"A": 1.0}, "quadratic"),
])
def test_bad_wheel_rail_cases(base, geometry, match):
    case = copy.deepcopy(base)
    case["geometry"].update(geometry)
    with pytest.raises(CaseError, match=match):
        rc.solve(case)


def test_patch_grid_beyond_the_profiles(base):
    """At 6.6 mm (gauge corner, 36 deg) the patch grid reaches past where the tangent-plane
    gap is defined; those elements are far out of contact, not an error."""
    sol = rc.solve(variant(base, lateral_displacement=0.0066))
    (p,) = sol.patches
    assert 30 < math.degrees(p.geometry.rigid.contact_angle) < 40  # (reference point: 42)
    assert p.normal.converged and not p.normal.touches_boundary


@pytest.mark.parametrize("eta", [0.01, -0.01])
def test_load_with_sliding_flange_follows_nadal(base, eta):
    """70 deg flange, lateral creepage large enough for full sliding: the creep force is
    mu N across the patch, and the vertical load Q = N cos(gamma) + F_s sin(gamma) gives
    N = Q / (cos(gamma) -+ mu sin(gamma)) (Nadal's balance; sliding up the flange, the
    friction nearly cancels the vertical support: mu tan(gamma) = 0.82)."""
    mu, q = 0.3, 83.3e3
    # the patch at the rigid point, on the flange's steepest point (at its reference point
    # the frame is inclined at the angle weighted over the overlap, 64-69 deg here)
    c = variant(base, lateral_displacement=7e-3, normal={"load": q, "tolerance": 1e-3},
                patch_frame="rigid")
    c["grid"] = {"nx": 40, "ny": 40}
    c["tangential"] = {"creepage": [0.0, eta, 0.0], "friction": mu, "estimate": "fastrip",
                       "tolerance": 1e-6}
    (patch,) = rc.solve(c).patches
    g, n, fs = patch.geometry.contact_angle, patch.normal.force, patch.tangential.force[1]
    assert math.degrees(g) == pytest.approx(70.0, abs=0.5)
    # full sliding: |p| = mu p_n everywhere, so |F| = mu N less the spread of the traction
    # directions (the xy coupling of the half-space turns them by a few mrad: 2e-5 of the
    # force converged, measured to eps_tau = 1e-7); the climbing direction amplifies a
    # deficit by tan(gamma) / (1 - mu tan(gamma)) ~ 15 in N
    assert patch.tangential.slip_area_ratio == 1.0
    assert math.hypot(*patch.tangential.force) <= mu * n * (1 + 1e-12)
    assert fs == pytest.approx(-math.copysign(mu * n, eta), rel=5e-5)
    assert n == pytest.approx(q / (math.cos(g) - math.copysign(mu, eta) * math.sin(g)),
                              rel=2e-4)


def test_load_beyond_nadals_limit_is_an_error(base):
    """mu tan(gamma) = 1.6 > 1 on the 70 deg flange, sliding up: the creep force pulls the
    wheel up more than the normal force pushes it, so no normal force carries the load.
    (The patch's frame is at its reference point, inclined at the angle weighted over the
    overlap, which falls to 64 deg as the normal force grows: mu = 0.6 is beyond the limit
    there too, mu tan(64 deg) = 1.2.)"""
    c = variant(base, lateral_displacement=7e-3, normal={"load": 83.3e3, "tolerance": 1e-3})
    c["grid"] = {"nx": 40, "ny": 40}
    c["tangential"] = {"creepage": [0.0, 0.01, 0.0], "friction": 0.6}
    with pytest.raises(rc.ConvergenceError, match="Nadal"):  # (a solver's, not an input's)
        rc.solve(c)


def test_creep_load_secant_on_model_functions():
    """The normal share qn that makes the vertical force Q: a smooth model of a flange
    (vertical = qn (1 - k qn^0.1)), the same with a noise floor of 50 N, and one beyond
    Nadal's limit (vertical falls as qn grows)."""
    from railcontact.contact.loadloop import MAX_STALLED, creep_load_secant

    q = 83.3e3
    calls = []

    def smooth(qn):
        calls.append(qn)
        return qn * (1 - 0.05 * (qn / q) ** 0.1) - q, qn

    qn, msg = creep_load_secant(smooth, q, q, 1e-9)
    assert msg == "" and smooth(qn)[0] == pytest.approx(0.0, abs=1e-9 * q)
    assert len(calls) < 10

    def noisy(qn):
        calls.append(qn)
        return qn * (1 - 0.05) - q + 50.0 * math.sin(1e3 * qn), qn

    calls.clear()
    qn, msg = creep_load_secant(noisy, q, q, 1e-5)
    assert "did not converge" in msg
    assert abs(noisy(qn)[0]) <= 100.0 and len(calls) <= 2 + MAX_STALLED + 4

    def climbing(qn):
        return -0.1 * qn - q, qn  # vertical force -0.1 qn

    first, msg = creep_load_secant(climbing, q, q, 1e-5)
    assert "Nadal" in msg and first == q


def test_creep_load_secant_closes_in_on_a_bracket_where_it_stalls_far_from_the_load():
    """A flange near Nadal's limit: the vertical force bends sharply with the normal share
    (a model of one at 90 kN: 6.6 kN at 168 kN, then a cubic rise to 1.09 MN at 2.28 MN).
    The damped secant stalls with the load missed by most of itself, though its shares
    bracket the load; closing in on the bracket (regula falsi, Illinois) meets it to the
    tolerance in a few more passes."""
    from railcontact.contact.loadloop import MAX_BRACKETED, creep_load_secant

    q, calls = 90e3, []

    def bent(qn):
        calls.append(qn)
        v = (6.6e3 + 1.08e6 * ((qn - 168e3) / 2.115e6) ** 3 if qn > 168e3
             else 6.6e3 * qn / 168e3)
        return v - q, qn

    qn, msg = creep_load_secant(bent, q, 168e3, 1e-3)
    assert msg == "" and abs(bent(qn)[0]) <= 1e-3 * q
    assert len(calls) <= 1 + 2 + 3 + MAX_BRACKETED  # (first, secant, stalled, bracket)
    assert 168e3 < qn < 2.28e6
