"""Case-file inputs read wrongly or reported misleadingly, from the reproducers in
tests/data/reliability/round2: each now ends in a clear one-line error or an honest status."""

from __future__ import annotations

import json
import re

import pytest
from conftest import RELIABILITY

import railcontact as rc
from railcontact.cli import main
from railcontact.settings import WheelRailGeometry

ROUND2 = RELIABILITY / "round2"


def _solve(name: str, monkeypatch, capsys) -> tuple[int, str, str]:
    monkeypatch.chdir(ROUND2)
    code = main(["solve", name, "--json"])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("name, match", [
    ("T1c_wheel_radius_mm_accepted.toml",
     r"\[geometry\] wheel_radius \[m\] must be >= 0.2 and <= 0.7, got 460; 460 looks like "
     r"millimetres: 460 mm is 0.46 m"),
    ("T1d_gauge_mm_blames_lateral.toml",
     r"\[geometry\] gauge \[m\] must be .*, got 1435; 1435 looks like millimetres"),
])
def test_a_length_in_millimetres_is_refused_with_its_unit(name, match, monkeypatch, capsys):
    code, _, err = _solve(name, monkeypatch, capsys)
    assert code == 2
    assert err.startswith("railcontact: error: ") and err.count("\n") == 1
    assert re.search(match, err), err
    assert "lateral_displacement" not in err


@pytest.mark.parametrize("key, value, mm", [
    ("wheel_radius", 0.1, False), ("wheel_radius", 460.0, True), ("wheel_radius", 2.0, False),
    ("gauge", 1435.0, True), ("gauge", 0.1, False), ("back_to_back", 1360.0, True),
    ("gauge_depth", 14.0, True), ("flange_back", -70.0, True),
])
def test_wheelset_and_track_lengths_have_a_range(key, value, mm):
    """The range is declared once with the setting: a case file and the FMU's parameters
    (which build the same record) are checked by it, and millimetres are named as such."""
    with pytest.raises(rc.CaseError, match=rf"\[geometry\] {key} \[m\] must be") as err:
        WheelRailGeometry(**{key: value})
    assert ("looks like millimetres" in str(err.value)) == mm
    from railcontact.fmu import variables as V
    name = {"back_to_back": "flange_back_distance"}.get(key, key)
    if any(p[0] == name for p in V.PARAMETER_SOURCES):
        with pytest.raises(rc.RailContactError, match=name):
            V.parameter_settings({name: value})


def test_the_defaults_and_common_gauges_are_in_range():
    for gauge, b2b in ((1.435, 1.360), (1.0, 0.93), (1.676, 1.60), (0.6, 0.55)):
        assert WheelRailGeometry(gauge=gauge, back_to_back=b2b).gauge == gauge
    for radius in (0.2, 0.33, 0.46, 0.625, 0.7):
        assert WheelRailGeometry(wheel_radius=radius).wheel_radius == radius


def test_a_quadratic_case_is_not_told_about_profiles(monkeypatch, capsys):
    """[grid] x, y of +-1000 km on 32 x 32 elements: the contact is one element whose
    neighbours' gap is kilometres. Not converged (exit 1), and the message names the
    element size and the gap, not profiles a quadratic case does not have."""
    code, out, _ = _solve("T1e_quadratic_message_says_profiles.toml", monkeypatch, capsys)
    assert code == 1
    normal = json.loads(out)["patches"][0]["normal"]
    assert not normal["converged"]
    assert "profiles" not in normal["message"]
    assert re.search(r"the undeformed gap next to the contact is 0.5 m or more: the elements "
                     r"\(6.25e\+04 x 6.25e\+04 m\) are far larger than the contact",
                     normal["message"]), normal["message"]
