"""Case files, the solve() API and the command line."""

import json
import subprocess
import sys

import pytest

from railcontact import CaseError, hertz, load_case, solve, validate_case


def paper_case(**normal):
    case = {
        "material": {"young": 206e9, "poisson": 0.28},
        "geometry": {"type": "quadratic", "A": 1.0, "B": 5.0},
        "grid": {"nx": 48, "ny": 48},
        "normal": {"penetration": 1e-4, "tolerance": 1e-3},
    }
    case["normal"].update(normal)
    return case


def test_shipped_paper_case(root):
    case = load_case(root / "models" / "cases" / "hertz_paper.toml")
    assert case.geometry.A == 1.0 and case.geometry.B == 5.0
    assert case.normal.penetration == 1e-4 and case.normal.tolerance == 1e-3
    assert case.material.to_dict() == {"young": 206e9, "poisson": 0.28}
    sol = solve(case)
    n = sol.patches[0].normal
    hz = hertz(1.0, 5.0, case.pair, penetration=1e-4)
    assert n.converged
    assert n.force == pytest.approx(hz.load, rel=0.01)
    assert n.max_pressure == pytest.approx(hz.max_pressure, rel=0.01)


def test_force_controlled_case():
    case = paper_case()
    del case["normal"]["penetration"]
    case["normal"]["load"] = 50e3
    n = solve(case).patches[0].normal
    assert n.force == pytest.approx(50e3, rel=1e-12)
    hz = hertz(1.0, 5.0, validate_case(case).pair, load=50e3)
    assert n.penetration == pytest.approx(hz.penetration, rel=0.01)


def test_estimate_reduces_iterations_through_api():
    none = solve(paper_case(estimate="none")).patches[0].normal
    hz = solve(paper_case(estimate="hertz")).patches[0].normal
    assert hz.iterations < none.iterations


def test_element_size_and_growing_automatic_area():
    case = paper_case()
    case["grid"] = {"dx": 5e-4, "dy": 2e-4, "margin": 0.6}  # too small: must grow
    sol = solve(case)
    n = sol.patches[0].normal
    assert not n.touches_boundary and n.converged
    assert n.grid.dx == pytest.approx(5e-4) and n.grid.dy == pytest.approx(2e-4)


@pytest.mark.parametrize("mutate, match", [
    (lambda c: c["normal"].update(penetration=-1e-4), r"\[normal\] penetration"),
    (lambda c: c["normal"].update(penetration=float("nan")), "finite"),
    (lambda c: (c["normal"].pop("penetration"), c["normal"].update(load=-5.0)), r"load"),
    (lambda c: c["normal"].update(load=1e3), "exactly one"),
    (lambda c: c["geometry"].update(A=0.0), r"\[geometry\] A"),
    (lambda c: c["geometry"].update(B=-2.0), r"\[geometry\] B"),
    (lambda c: c["grid"].update(x=[-1e-3, 1e-3], y=[-1e-3, 1e-3]), "too small"),
    (lambda c: c["normal"].update(estimate="magic"), "estimate"),
    (lambda c: c["normal"].update(lod=3), "unknown key"),
    (lambda c: c["geometry"].update(wheel="S1002"), "for type = 'wheel-rail'"),
    (lambda c: c.update(extra={}), "unknown table"),
    (lambda c: c.pop("material"), r"missing table \[material\]"),
    (lambda c: c["material"].update(poisson=0.7), "poisson"),
    (lambda c: c["grid"].update(nx=1.5), "nx"),
])
def test_bad_cases(mutate, match):
    case = paper_case()
    mutate(case)
    with pytest.raises(CaseError, match=match):
        solve(case)


def test_a_missing_key_and_a_bad_value_are_both_named():
    """All problems of a case at once: a missing required key does not hide a bad value
    given beside it in the same table."""
    case = paper_case()
    case["geometry"].pop("B")
    case["geometry"]["A"] = -1.0
    with pytest.raises(CaseError) as err:
        solve(case)
    text = str(err.value)
    assert "missing [geometry] B" in text and "[geometry] A [1/m] must be > 0" in text, text


def test_missing_and_broken_files(tmp_path):
    with pytest.raises(CaseError, match="not found"):
        load_case(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[normal\nload = ")
    with pytest.raises(CaseError, match="not valid TOML"):
        load_case(bad)


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "railcontact", *args], capture_output=True,
                          text=True, timeout=120)


def test_cli_json_and_plot(root, tmp_path):
    png = tmp_path / "patch.png"
    r = run_cli("solve", str(root / "models/cases/hertz_paper.toml"), "--json", "--plot",
                str(png))
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    normal = out["patches"][0]["normal"]
    for key in ("force", "penetration", "max_pressure", "area", "iterations", "converged"):
        assert key in normal
    assert normal["converged"] is True
    assert normal["penetration"] == 1e-4
    assert png.stat().st_size > 10_000


def test_cli_plot_draws_every_patch(root, tmp_path, capsys):
    """A case with two patches (``side = "both"``: one per wheel) has a figure for each:
    patch 0 in the file given, patch 1 beside it; each figure names its patch and wheel
    (only patch 0 was drawn)."""
    from railcontact.cli import main

    text = (root / "models/cases/s1002_60e1_dy-2mm.toml").read_text()
    for old, new in (('side = "left"', 'side = "both"'), ("nx = 64", "nx = 16"),
                     ("ny = 64", "ny = 16")):
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "both.toml"
    path.write_text(text)
    png = tmp_path / "both.png"
    assert main(["solve", str(path), "--plot", str(png)]) in (0, 1)
    out = capsys.readouterr().out
    second = tmp_path / "both-patch1.png"
    assert png.stat().st_size > 10_000 and second.stat().st_size > 10_000
    assert f"plot written to {png}" in out and f"plot written to {second}" in out


def test_cli_errors_are_one_line(tmp_path):
    r = run_cli("solve", str(tmp_path / "missing.toml"))
    assert r.returncode == 2
    assert r.stderr == f"railcontact: error: case file not found: {tmp_path / 'missing.toml'}\n"
    bad = tmp_path / "neg.toml"
    bad.write_text('[material]\nyoung = 206e9\npoisson = 0.28\n[geometry]\nA = 1.0\nB = 5.0\n'
                   '[normal]\nload = -10.0\n')
    r = run_cli("solve", str(bad))
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stderr.startswith(f"railcontact: error: {bad}: [normal] load")


def test_rolling_case_json(root, tmp_path):
    png = tmp_path / "rolling.png"
    r = run_cli("solve", str(root / "models/cases/hertz_paper_rolling.toml"), "--json",
                "--plot", str(png))
    assert r.returncode == 0, r.stderr
    tan = json.loads(r.stdout)["patches"][0]["tangential"]
    for key in ("force", "spin_moment", "slip_area_ratio", "max_traction", "iterations",
                "converged"):
        assert key in tan
    assert tan["converged"] and tan["force"][0] < 0  # xi > 0
    assert 0 < tan["slip_area_ratio"] < 1
    assert png.stat().st_size > 10_000


@pytest.mark.parametrize("model", ["fastsim", "fastrip"])
def test_simplified_models_through_api(root, model):
    case = load_case(root / "models/cases/hertz_paper_rolling.toml").to_dict()
    case["tangential"]["model"] = model
    t = solve(case).patches[0].tangential
    assert t.iterations == 0 and t.force[0] < 0


@pytest.mark.parametrize("mutate, match", [
    (lambda t: t.update(creepage=[1e-3, 0]), "creepage"),
    (lambda t: t.update(creepage=[float("nan"), 0, 0]), "finite"),
    (lambda t: t.pop("friction"), "friction"),
    (lambda t: t.update(friction=-0.2), "friction"),
    (lambda t: t.update(model="kalker"), "model"),
    (lambda t: t.update(estimate="hertz"), "estimate"),
])
def test_bad_tangential_cases(root, mutate, match):
    case = load_case(root / "models/cases/hertz_paper_rolling.toml").to_dict()
    mutate(case["tangential"])
    with pytest.raises(CaseError, match=match):
        solve(case)


@pytest.mark.parametrize(("lateral", "words"), [
    (-0.05, "climbed its flange"),      # the other (right) wheel past its flange
    (0.03, "climbed its flange"),       # the solved (left) wheel past half its flange angle
    (0.08, "off its rail"),             # the left wheel's flange back on the rail
    (0.3, "beyond the profiles"),       # nowhere near the rail
])
def test_a_lateral_displacement_beyond_the_profiles_is_a_clear_error(root, tmp_path,
                                                                      lateral, words):
    """CLI: nothing is solved: one line naming the input and why, exit 2."""
    text = (root / "models" / "cases" / "s1002_60e1_dy-2mm.toml").read_text()
    case = tmp_path / "far.toml"
    case.write_text(text.replace("lateral_displacement = -0.002",
                                 f"lateral_displacement = {lateral}"))
    r = run_cli("solve", str(case))
    assert r.returncode == 2 and r.stdout == "" and "Traceback" not in r.stderr
    (line,) = r.stderr.strip().splitlines()
    assert line.startswith(f"railcontact: error: {case}: [geometry] lateral_displacement = ")
    assert f"{lateral:g} m" in line and words in line, line


def test_a_misspelt_key_or_table_is_named_with_the_key_it_is_close_to():
    """A misspelt penetration is one error naming 'penetration' (not also "needs exactly
    one of load and penetration", a knock-on of the typo); a misspelt table likewise; a
    key close to none gets no guess, and a [normal] without load or penetration still
    says it needs one."""
    case = paper_case()
    case["normal"]["penetraton"] = case["normal"].pop("penetration")
    with pytest.raises(CaseError) as err:
        validate_case(case)
    assert str(err.value).startswith("unknown key(s) ['penetraton'] in [normal] (did you "
                                     "mean 'penetration'?); known:")
    assert "exactly one" not in str(err.value)
    case = paper_case()
    case["materal"] = case.pop("material")
    with pytest.raises(CaseError, match=r"\['materal'\] \(did you mean 'material'\?\)"):
        validate_case(case)
    case = paper_case()
    case["normal"]["zzz"] = case["normal"].pop("penetration")
    with pytest.raises(CaseError) as err:
        validate_case(case)
    assert "did you mean" not in str(err.value) and "exactly one of load" in str(err.value)


def test_one_file_in_error_is_named_and_json_gets_its_object(root, tmp_path):
    """CLI: a single case file in error is named on stderr as one of several is, and with
    --json stdout holds its ``{"file", "error"}`` object (a script always reads JSON);
    a table's spec given to ``solve`` points to ``railcontact table build``."""
    text = (root / "models" / "cases" / "hertz_paper.toml").read_text()
    case = tmp_path / "typo.toml"
    case.write_text(text.replace("penetration = 1.0e-4", "penetraton = 1.0e-4"))
    r = run_cli("solve", str(case), "--json")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    (line,) = r.stderr.strip().splitlines()
    assert line.startswith(f"railcontact: error: {case}: unknown key(s) ['penetraton']")
    out = json.loads(r.stdout)
    assert out["file"] == str(case) and "did you mean 'penetration'" in out["error"]
    spec = root / "models" / "tables" / "creep_nu028.toml"
    r = run_cli("solve", str(spec))
    assert r.returncode == 2 and r.stdout == ""
    assert "unknown table(s) ['table']" in r.stderr
    assert "`railcontact table build FILE -o STORE`" in r.stderr


def test_inputs_that_misname_the_pose_are_named_themselves(tmp_path):
    """Errors an outsider's case file met blamed the wheelset's lateral displacement: a
    gauge that the wheelset's back-to-back distance does not fit, dissimilar materials
    under the tangential BEM; they are named as such. A misspelt top-level key gets its
    suggestion, and a folder given for a case file is called one."""
    case = paper_case()
    case["convetion"] = "contact"
    with pytest.raises(CaseError, match=r"\['convetion'\] \(did you mean 'convention'\?\)"):
        validate_case(case)
    wheel = {"material": {"young": 206e9, "poisson": 0.28},
             "geometry": {"type": "wheel-rail", "gauge": 1.0}, "normal": {"load": 8e4}}
    with pytest.raises(CaseError, match=r"gauge = 1 m less back_to_back = 1.36 m is -360 mm"):
        validate_case(wheel)
    wheel["geometry"]["back_to_back"] = 0.93  # (metre gauge: fits)
    validate_case(wheel)
    wheel = {"material": {"young": [206e9, 100e9], "poisson": [0.28, 0.3]},
             "geometry": {"type": "wheel-rail"}, "normal": {"load": 8e4},
             "tangential": {"creepage": [1e-3, 0.0, 0.0], "friction": 0.4}}
    with pytest.raises(CaseError, match=r"^\[material\] gives dissimilar bodies"):
        validate_case(wheel)
    del wheel["tangential"]  # (the normal problem takes them)
    validate_case(wheel)
    wheel = {"material": {"young": 206e9, "poisson": 0.28}, "geometry": {"type": "wheel-rail"},
             "normal": {"load": 8e4}, "grid": {"dx": 0.5, "dy": 5e-4}}
    with pytest.raises(CaseError, match=r"\[grid\] dx = 0.5 m is coarser than the 0.005 m "
                       r"that still resolves a wheel-rail patch; 0.5 looks like millimetres"):
        validate_case(wheel)
    r = run_cli("solve", str(tmp_path))
    assert r.returncode == 2 and r.stderr == f"railcontact: error: {tmp_path} is a folder, " \
                                             "not a case file\n"
