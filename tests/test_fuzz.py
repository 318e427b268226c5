"""A seeded fuzz of case keys and WheelsetContact inputs, at a small size:
never a traceback, never a hang, and a success only with finite numbers in range.

The machinery is ``scripts/fuzz.py`` (its longer run prints the counts table); here the cases
are solved in-process (``railcontact.solve(dict)`` and the strict JSON of the solution), a
few through the command line (exit codes, nothing but one error line on stderr), and the
WheelsetContact steps in-process, each under an alarm.
"""

from __future__ import annotations

import importlib.util
import random
import sys
from pathlib import Path

import pytest

import railcontact as rc

ROOT = Path(__file__).resolve().parents[1]
SEED = 22  # fixed seed
N_CASES = 300  # in-process
N_CLI = 6  # through the command line
N_STEPS = 300  # WheelsetContact steps
TIMEOUT = 20.0  # seconds per input: a hang (the inputs solve in well under a second)


def _load_fuzz():
    name = "railcontact_fuzz_script"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, ROOT / "scripts" / "fuzz.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


fuzz = _load_fuzz()


def _report(findings: list[str]) -> str:
    return f"{len(findings)} finding(s):\n" + "\n".join(findings[:20])


def test_strict_json_refuses_nan_and_infinity():
    assert fuzz.strict_json('{"a": [1.5, null]}') == {"a": [1.5, None]}
    for token in ("NaN", "Infinity", "-Infinity"):
        with pytest.raises(ValueError):
            fuzz.strict_json(f'{{"a": {token}}}')


def test_the_checks_catch_wrong_answers():
    """The range checks themselves: a made-up success with a NaN, a negative force, a creep
    force beyond mu N and a missed load is reported, the real answer is not."""
    from railcontact.io.jsonout import solution_json

    case = {"material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "quadratic", "A": 1.0, "B": 5.0},
            "grid": {"nx": 16, "ny": 16}, "normal": {"load": 74e3},
            "tangential": {"creepage": [1e-3, 0.0, 0.0], "friction": 0.3}}
    text = solution_json(rc.solve(case))
    assert fuzz.check_solution(fuzz.strict_json(text), case) == []
    n_force = fuzz.strict_json(text)["patches"][0]["normal"]["force"]
    for part, key, value, match in [
            ("normal", "max_pressure", None, "not finite"),
            ("normal", "force", -1.0, "< 0"),
            ("tangential", "force", [0.31 * n_force, 0.0], "mu N"),
            ("normal", "force", 0.9 * n_force, "misses the load")]:
        bad = fuzz.strict_json(text)
        bad["patches"][0][part][key] = value
        assert any(match in p for p in fuzz.check_solution(bad, case)), match


def test_fuzzed_cases_in_process(tmp_path):
    """Mutated case dictionaries: a clean CaseError, not converged, or a success whose every
    number is finite and in range; strict JSON."""
    rng = random.Random(SEED)
    findings, kinds = [], {}
    for i, (case, notes) in enumerate(fuzz.random_cases(rng, N_CASES, tmp_path)):
        res = fuzz.solve_in_process(case, TIMEOUT)
        kinds[res.kind] = kinds.get(res.kind, 0) + 1
        if res.kind in fuzz.FINDINGS:
            findings.append(f"case {i} {res.kind}: {res.detail} <- {', '.join(notes)}")
    assert not findings, _report(findings)
    assert kinds.get("ok", 0) >= N_CASES // 10  # the fuzz still reaches the solvers
    assert kinds.get("clean error", 0) >= N_CASES // 4


def test_fuzzed_cases_through_the_command_line(tmp_path):
    """A few through ``railcontact solve --json``: exit 0, 1 or 2, nothing on stderr but the
    error line (and Python's warnings), no traceback, strict JSON, and exit 0 only for a
    finite answer in range."""
    rng = random.Random(SEED + 1)
    findings = []
    for i, (case, notes) in enumerate(fuzz.random_cases(rng, N_CLI, tmp_path)):
        res = fuzz.run_cli(case, 120.0, tmp_path, f"cli{i}")  # an interpreter start each
        if res.kind in fuzz.FINDINGS:
            findings.append(f"case {i} {res.kind}: {res.detail} <- {', '.join(notes)}")
    assert not findings, _report(findings)


def test_fuzzed_wheelset_steps_in_process():
    """Random WheelsetContact steps (warm-started sequences, some bad API inputs): a
    RailContactError or a status; status 0 only with finite forces, mu N respected, the
    load met to 1 % and the contact angle within (-pi/2, pi/2)."""
    rng = random.Random(SEED + 2)
    findings, kinds = [], {}
    for seq in fuzz.random_sequences(rng, N_STEPS):
        settings = fuzz.decode(fuzz.encode(seq["settings"]))
        try:
            wc = fuzz.new_wheelset(settings)
        except rc.RailContactError:
            kinds["clean error"] = kinds.get("clean error", 0) + 1
            continue
        except Exception as exc:
            findings.append(f"traceback: {fuzz._where(exc)} <- settings {settings}")
            continue
        for j, step in enumerate(seq["steps"]):
            res = fuzz.run_step(wc, fuzz.decode(fuzz.encode(step)), settings, TIMEOUT)
            kinds[res.kind] = kinds.get(res.kind, 0) + 1
            if res.kind in fuzz.FINDINGS:
                findings.append(f"{res.kind}: {res.detail} <- settings {settings}, step {j} "
                                f"{step}")
    assert not findings, _report(findings)
    # at least half the steps with their wheels solved and checked (a pose beyond the
    # flange's steepest point has no rigid wheelset's roll: its wheels are solved, its
    # status says the roll was not found)
    assert kinds.get("ok", 0) + kinds.get("rigid not found", 0) >= N_STEPS // 2


def test_the_load_check_reads_contact_convention():
    """Under ``convention = "contact"`` the JSON's lateral creep forces are CONTACT's (on the
    rail, the right wheel mirrored); the vertical-load check turns them back into the
    wheel's before it sums N cos(gamma) + F_s sin(gamma). On the right wheel's flange root
    (large F_s, steep angle) a misread sign misses the load by far more than LOAD_RTOL."""
    from railcontact.io.jsonout import solution_json

    case = {"convention": "contact",
            "material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                         "lateral_displacement": -5.5e-3, "side": "right"},
            "grid": {"dx": 0.5e-3, "dy": 0.5e-3},
            "normal": {"load": 83.3e3},
            "tangential": {"creepage": [0.0, 1e-3, 0.0], "friction": 0.4}}
    d = fuzz.strict_json(solution_json(rc.solve(case)))
    assert fuzz.check_solution(d, case) == []
    railcontact_case = {**case, "convention": "railcontact"}  # the same JSON, misread
    assert any("misses the load" in p for p in fuzz.check_solution(d, railcontact_case))
