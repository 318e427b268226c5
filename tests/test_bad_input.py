"""Bad input from the fuzzing reproducers in ../shared/reliability: a clear one-line error
(exit 2) where there was a traceback, a hang, unbounded memory or a wrong answer."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import railcontact as rc
from railcontact.cli import main

RELIABILITY = Path(__file__).resolve().parents[2] / "shared" / "reliability"
needs_shared = pytest.mark.skipif(not RELIABILITY.is_dir(),
                                  reason="../shared/reliability not present")


@needs_shared
@pytest.mark.parametrize("name, match", [
    ("F09_wrong_profile_unit_accepted", "is its unit right"),
    ("F10_traceback_non_utf8", "not UTF-8"),
    ("F10b_traceback_nx_int64max", r"\[grid\] nx \* ny"),
    ("F10c_traceback_dx_1e-300", r"\[grid\] dx = 1e-300"),
    ("F10d_traceback_deep_nesting", "too deeply"),
    ("F10e_traceback_profile_huge_coords", "is its unit right"),
    ("F10f_traceback_prw_units_str", "spline.units.len.f"),
    ("F11_memory_nx4096", "max_elements"),
    ("F11b_memory_hang_dx_1e-7", "max_elements"),
    ("F11c_memory_estimate_grid", r"estimate_grid\[0\] must be an integer <= 2048"),
    ("F14_tolerance_10_accepted", r"tolerance must be > 0 and < 1"),
])
def test_reproducer_ends_in_a_clear_error(name, match, monkeypatch, capsys):
    monkeypatch.chdir(RELIABILITY)  # their profile paths are relative to that folder
    code = main(["solve", f"{name}.toml", "--json"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("railcontact: error: ") and err.count("\n") == 1
    assert re.search(match, err), err


def test_vanishing_friction_gives_vanishing_traction():
    """mu = 1e-300 (F10g divided by an underflowed norm): the traction bound mu p is ~0, so
    the whole patch slides with a traction of the order of mu N."""
    case = {"material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "quadratic", "A": 1.0, "B": 5.0},
            "grid": {"nx": 32, "ny": 32}, "normal": {"load": 74e3},
            "tangential": {"creepage": [1e-3, 0.0, 0.0], "friction": 1e-300}}
    t = rc.solve(case).patches[0].tangential
    assert t.converged
    assert abs(t.force[0]) <= 1e-300 * 74e3 * (1 + 1e-9)


def test_the_grid_budget_is_checked_before_allocating_and_settable():
    with pytest.raises(rc.CaseError, match=r"600 x 600 = 3.6e\+05 elements"):
        rc.GridSettings(nx=600, ny=600)
    assert rc.GridSettings(nx=600, ny=600, max_elements=400_000).nx == 600
    case = {"material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "quadratic", "A": 1.0, "B": 5.0},
            "grid": {"dx": 1e-5, "dy": 1e-5}, "normal": {"load": 74e3}}
    with pytest.raises(rc.CaseError, match="max_elements"):
        rc.solve(case)  # ~2000 x 900 elements for the automatic area
