"""Seeded fuzzer of railcontact's inputs (never a wrong answer reported as success).

Two kinds of input:

* case files built from the project's own cases (``models/cases/*.toml``) and variants of
  them (both geometries, every tangential model, two wheels, equal-loads roll, profile
  files), with keys mutated: numbers to extremes (0, negative, 1e-300, 1e300, inf, nan,
  huge integers), wrong types, lists of the wrong length, keys and tables deleted or
  added, choices misspelt. Each is written to a TOML file and run as
  ``railcontact solve FILE --json`` in a subprocess with a timeout and a 2 GB address-space
  limit;
* random ``WheelsetContact`` steps (pose, wheel loads or vertical displacement, creepages or
  kinematics, warm starts over sequences of steps, 2 mm elements, some bad API inputs),
  solved in a worker process (same limits) that keeps each sequence's solver.

Each input is classified: ``ok``, ``clean error`` (exit 2 with ``railcontact: error: ...``
and no traceback; ``RailContactError``; a documented status 2 or 3 with a message), ``not
converged`` (exit 1, status 1), ``rigid not found`` (a wheelset step whose wheels were
solved, and checked as a success's, but not the rigid wheelset's vertical displacement and
roll: status 1), ``traceback`` (any other exception), ``hang`` (timeout),
``silent-wrong`` (success, but a number not finite or out of range: see
:func:`check_solution` and :func:`check_wheelset`) and ``memory`` (``MemoryError``). The
script prints the counts and one line per finding; ``--json FILE`` saves the findings with
the inputs that reproduce them.

    python scripts/fuzz.py [--seed 1] [--cases 300] [--steps 3000] [--timeout 60] [--json F]

``tests/test_fuzz.py`` runs the same machinery in-process at a small size.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import os
import random
import re
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

try:
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
CASES = ROOT / "models" / "cases"
PROFILES = ROOT / "models" / "profiles"
KINDS = ("ok", "clean error", "not converged", "rigid not found", "traceback", "hang",
         "silent-wrong", "memory")
FINDINGS = ("traceback", "hang", "silent-wrong", "memory")
MEMORY_LIMIT = 2 << 30  # address space of a child [bytes]
P_MAX = 20e9  # largest plausible contact pressure of steel-like bodies [Pa]
LOAD_RTOL = 0.01  # a wheel or patch load may be missed by this much
R0 = 0.46  # nominal wheel radius of the wheelset steps [m]


@dataclass
class Outcome:
    kind: str
    detail: str = ""
    seconds: float = 0.0
    warnings: str = ""  # anything other than the error line on stderr (not a finding)


# ---------------------------------------------------------------------------------------
# TOML
class Raw(str):
    """A TOML token written as it is (a huge integer, a date, a hex integer); in-process it
    stands for :attr:`value`."""

    value: Any = None

    def __new__(cls, token: str, value: Any = None) -> Raw:
        obj = super().__new__(cls, token)
        obj.value = value
        return obj


def toml_value(v: Any) -> str:
    if isinstance(v, Raw):
        return str(v)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)  # a TOML basic string is a JSON string for what we write
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"no TOML for {v!r}")


def _key(k: str) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def to_toml(case: dict) -> str:
    lines = [f"{_key(k)} = {toml_value(v)}" for k, v in case.items() if not isinstance(v, dict)]
    for k, v in case.items():
        if isinstance(v, dict):
            lines.append(f"\n[{_key(k)}]")
            lines += [f"{_key(kk)} = {toml_value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


def in_process(value: Any) -> Any:
    """The Python value a case dictionary holds for ``value`` (Raw tokens resolved)."""
    if isinstance(value, Raw):
        return value.value
    if isinstance(value, dict):
        return {k: in_process(v) for k, v in value.items()}
    if isinstance(value, list):
        return [in_process(v) for v in value]
    return value


# ---------------------------------------------------------------------------------------
# Cases
def base_cases() -> list[dict]:
    """The project's cases and variants of them, on small grids (quick to solve)."""
    own = {}
    for f in sorted(CASES.glob("*.toml")):
        with f.open("rb") as fh:
            own[f.stem] = tomllib.load(fh)
    out = [copy.deepcopy(c) for c in own.values()]
    hz = own.get("hertz_paper_rolling") or next(iter(own.values()))
    wr = own.get("s1002_60e1_dy-2mm")
    small = {"nx": 24, "ny": 24}
    q = copy.deepcopy(hz)
    q["normal"] = {"load": 74e3, "estimate": "hertz"}
    q["tangential"] = {"creepage": [1e-3, 2e-3, 0.5], "friction": 0.3, "model": "fastsim"}
    q["grid"] = dict(small)
    out.append(q)
    q = copy.deepcopy(q)
    q["tangential"].update(model="fastrip", bound="parabolic")
    q["normal"]["estimate"] = "kp"
    out.append(q)
    q = copy.deepcopy(q)
    q["tangential"].update(model="bem", estimate="fastrip", solver="steadygs")
    q["material"] = {"young": [206e9, 70e9], "poisson": [0.28, 0.33]}
    out.append(q)
    if wr is not None:
        w = copy.deepcopy(wr)
        w["grid"] = {"dx": 5e-4, "dy": 5e-4}
        w["geometry"].update(side="both", lateral_displacement=0.004, yaw=0.002)
        w["normal"].update(estimate="infcon")
        w["tangential"] = {"creepage": [1e-3, -1e-3, 0.2], "friction": 0.3}
        out.append(w)
        w = copy.deepcopy(w)
        w["geometry"].update(lateral_displacement=0.007, side="left", roll="rigid")
        w["tangential"].update(estimate="fastsim", creepage=[-2e-3, 3e-3, -0.4])
        out.append(w)
        w = copy.deepcopy(wr)
        w["grid"] = dict(small)
        w["geometry"].update(side="both", roll="equal-loads", lateral_displacement=0.003)
        out.append(w)
        w = copy.deepcopy(wr)
        w["grid"] = dict(small)
        w["geometry"].update(wheel=str(PROFILES / "S1002.txt"), rail=str(PROFILES / "60E1.txt"),
                             profile_unit="mm", side="right")
        w["normal"] = {"penetration": 5e-5, "estimate": "kp"}
        out.append(w)
    for i, c in enumerate(out):
        c["name"] = f"fuzz_base_{i}"
    return out


LIST2 = "list2"
SCHEMA: dict[str, dict[str, Any]] = {
    "material": {"young": "num", "poisson": "num"},
    "geometry": {"type": ("quadratic", "wheel-rail"), "A": "num", "B": "num",
                 "wheel": "profile", "rail": "profile",
                 "profile_unit": ("m", "mm", "cm", "in"), "inclination": "num",
                 "gauge": "num", "gauge_depth": "num", "back_to_back": "num",
                 "flange_back": "num", "wheel_radius": "num",
                 "lateral_displacement": "lateral", "yaw": "num",
                 "roll": ("rigid", "equal-loads", 0.0), "side": ("left", "right", "both")},
    "grid": {"nx": "count", "ny": "count", "dx": "size", "dy": "size", "x": LIST2,
             "y": LIST2, "margin": "num", "max_elements": "count", "quantum": "count",
             "snap": "bool"},
    "normal": {"load": "num", "penetration": "num",
               "estimate": ("none", "hertz", "kp", "infcon"), "estimate_grid": LIST2,
               "tolerance": "num", "max_iterations": "count",
               "fft": ("auto", "pyfftw", "scipy", "dense"), "preconditioner": ("fft", "none")},
    "tangential": {"creepage": "list3", "friction": "num",
                   "model": ("bem", "fastsim", "fastrip"),
                   "estimate": ("none", "fastsim", "fastrip"),
                   "solver": ("steadygs", "convexgs"), "tolerance": "num",
                   "max_iterations": "count", "bound": ("elliptic", "parabolic"),
                   "strips": LIST2, "spin_offset": "num"},
}
INF, NAN = float("inf"), float("nan")
EXTREMES = [0, 0.0, -0.0, -1, -1.0, 1, 1e-300, -1e-300, 5e-324, 1e300, -1e300,
            1.7976931348623157e308, INF, -INF, NAN, 2**31, 2**63 - 1, -(2**63), 1e-9, 1e9,
            0.5, 2]
RAW = [Raw("99999999999999999999", 99999999999999999999),  # beyond TOML's 64-bit integers
       Raw("0x7fffffffffffffff", 2**63 - 1), Raw("1979-05-27", "1979-05-27"),
       Raw("1e400", 10**400)]  # a float beyond the double range; in-process a huge int
WRONG = ["abc", "", "1e3", "nan", True, False, [], [1], [1, 2, 3], [[1, 2]], {"a": 1},
         [1, "a"]]


def _number(rng: random.Random, old: Any) -> Any:
    r = rng.random()
    if r < 0.3:
        return rng.choice(EXTREMES)
    if r < 0.37:
        return rng.choice(RAW)
    if r < 0.45:
        return rng.choice(WRONG)
    base = old if isinstance(old, (int, float)) and not isinstance(old, bool) and old else 1.0
    if r < 0.75:
        return float(base) * 10 ** rng.uniform(-1, 1)  # mostly in range
    if r < 0.92:
        return float(base) * 10 ** rng.uniform(-4, 4)
    return -float(base)


def _count(rng: random.Random, old: Any) -> Any:
    r = rng.random()
    if r < 0.4:
        return rng.choice([0, 1, 2, 3, -1, -64, 2**31, 2**63 - 1, 1e9, 2.5, 64.0, INF, NAN])
    if r < 0.5:
        return rng.choice(RAW)
    if r < 0.6:
        return rng.choice(WRONG)
    return rng.randint(2, 64)


def _size(rng: random.Random, old: Any) -> Any:
    r = rng.random()
    if r < 0.45:
        return rng.choice([0.0, -1e-3, 1e-300, 5e-324, 1e-9, 1e300, INF, NAN, -INF])
    if r < 0.55:
        return rng.choice(WRONG)
    return rng.uniform(3e-4, 3e-3)


def _list(rng: random.Random, old: Any, n: int) -> Any:
    r = rng.random()
    if r < 0.3:  # the wrong length
        return [rng.uniform(-1, 1) for _ in range(rng.choice([0, 1, n + 1, n + 3]))]
    if r < 0.45:
        return rng.choice(WRONG + EXTREMES[:6])
    new = list(old) if isinstance(old, list) and len(old) == n else [1.0] * n
    k = rng.randrange(n)
    new[k] = _number(rng, new[k])
    if r < 0.6 and n == 2:  # reversed or collapsed intervals, counts of the estimate grid
        new = rng.choice([[new[1], new[0]], [new[0], new[0]], [4, 4], [2049, 40], [3, 40]])
    return new


def _choice(rng: random.Random, choices: tuple) -> Any:
    r = rng.random()
    good = [c for c in choices if isinstance(c, str)]
    if r < 0.25 and good:
        return rng.choice(good)  # another valid choice
    if r < 0.8 and good:
        c = rng.choice(good)
        return rng.choice([c.upper(), c + "x", c[1:], c[:-1] + c[-1] * 2, " " + c,
                           c.replace("-", "_"), ""])
    return rng.choice(WRONG + [0, 1, NAN])


def _profile(rng: random.Random, old: Any, scratch: Path) -> Any:
    names = ["S1002", "60E1", "CN60", "UIC60", "s1002", "", "nonexistent.prr",
             str(PROFILES / "S1002.txt"), str(PROFILES / "60E1.txt"), "/dev/null", "/",
             str(scratch)]
    if rng.random() < 0.5:
        return rng.choice(names)
    return str(_profile_file(rng, scratch))


def _profile_file(rng: random.Random, scratch: Path) -> Path:
    """A two-column profile file: the built-in one scaled, shifted, cut, reversed or
    spoilt."""
    src = rng.choice(["S1002", "60E1"])
    rows = [ln.split() for ln in (PROFILES / f"{src}.txt").read_text().splitlines()
            if ln.strip() and not ln.startswith("#")]
    how = rng.choice(["scale", "cut", "reverse", "nan", "few", "noise", "empty", "text",
                      "duplicate"])
    if how == "scale":
        s = rng.choice([1e-3, 0.5, 2.0, 1e3])
        rows = [[f"{float(a) * s:.9g}", f"{float(b) * s:.9g}"] for a, b in rows]
    elif how == "cut":
        i = rng.randrange(len(rows) - 2)
        rows = rows[i:i + rng.randint(2, 30)]
    elif how == "reverse":
        rows = rows[::-1]
    elif how == "nan":
        rows[rng.randrange(len(rows))][1] = rng.choice(["nan", "inf", "1e300"])
    elif how == "few":
        rows = rows[:rng.randint(0, 3)]
    elif how == "noise":
        rows = [[a, f"{float(b) + rng.gauss(0, 0.05):.6f}"] for a, b in rows]
    elif how == "empty":
        rows = []
    elif how == "text":
        rows = [["y", "z"], ["a", "b"]]
    else:
        rows = rows + rows[-5:]
    path = scratch / f"{src}_{how}_{rng.randrange(10**9)}.txt"
    path.write_text("".join(" ".join(r) + "\n" for r in rows))
    return path


def mutate_case(rng: random.Random, case: dict, scratch: Path) -> tuple[dict, list[str]]:
    """A copy of ``case`` with 1-3 mutations, and what they were."""
    case = copy.deepcopy(case)
    notes = []
    for _ in range(rng.choice([1, 1, 1, 2, 2, 3])):
        r = rng.random()
        tables = [t for t in SCHEMA if isinstance(case.get(t), dict)]
        if r < 0.05 and tables:  # a table deleted
            t = rng.choice(tables)
            del case[t]
            notes.append(f"del [{t}]")
            continue
        if r < 0.08:  # an unknown table, a name that is not a string, a table not a table
            k, v = rng.choice([("name", {"x": 1}), ("name", 3), ("extra", {"a": 1}),
                               ("tangential", 1.0), ("grid", [1, 2]), ("normal", "x")])
            case[k] = v
            notes.append(f"{k} = {toml_value(v)}")
            continue
        table = rng.choice(list(SCHEMA))
        tab = case.setdefault(table, {}) if isinstance(case.get(table, {}), dict) else None
        if tab is None:
            continue
        if table == "tangential" and set(tab) <= {"model"}:  # make a tangential table
            tab.update(creepage=[1e-3, 0.0, 0.0], friction=0.4)
        if r < 0.13 and tab:  # a key deleted
            k = rng.choice(list(tab))
            del tab[k]
            notes.append(f"del [{table}] {k}")
            continue
        if r < 0.17:  # an unknown key or a misspelt one
            k = rng.choice(["bogus", "Young", "nX", "load ", "creepages", "tolerence", "type"])
            tab[k] = rng.choice(["x", 1.0, 2, [1, 2]])
            notes.append(f"[{table}] {k} = {toml_value(tab[k])}")
            continue
        key = rng.choice(list(SCHEMA[table]))
        kind, old = SCHEMA[table][key], tab.get(key)
        if isinstance(kind, tuple):
            new = _choice(rng, kind) if rng.random() < 0.85 else _number(rng, old)
            if key == "roll" and rng.random() < 0.5:
                new = rng.choice([0.01, -0.01, 0.2, 1e-300, NAN, INF, "RIGID"])
        elif kind == "count":
            new = _count(rng, old)
        elif kind == "size":
            new = _size(rng, old)
        elif kind == LIST2:
            new = _list(rng, old, 2)
        elif kind == "list3":
            new = _list(rng, old, 3)
        elif kind == "profile":
            new = _profile(rng, old, scratch)
        elif kind == "bool":
            new = rng.choice([True, False, 1, "yes", NAN])
        elif kind == "lateral":
            new = rng.choice([rng.uniform(-0.02, 0.02), rng.uniform(-0.02, 0.02),
                              rng.choice(EXTREMES), 0.1, -0.1, 0.0105])
        else:
            new = _number(rng, old)
            if key in ("young", "poisson") and rng.random() < 0.3:
                other = (old[0] if old else 0.3) if isinstance(old, list) else old
                new = [new, 0.3 if other is None else other][:rng.choice([1, 2, 2, 3])]
        tab[key] = new
        notes.append(f"[{table}] {key} = {toml_value(new)}")
    return case, notes


# ---------------------------------------------------------------------------------------
# Checks of a successful answer
def _strict_constant(token: str) -> float:
    raise ValueError(f"non-standard JSON token {token}")


def strict_json(text: str) -> Any:
    """``json.loads`` that refuses NaN, Infinity and -Infinity."""
    return json.loads(text, parse_constant=_strict_constant)


def _walk_numbers(obj: Any, path: str = ""):
    """(path, value) of every number and null in a JSON-like object."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _walk_numbers(v, f"{path}.{k}" if path else k)
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            yield from _walk_numbers(v, f"{path}[{i}]")
    elif obj is None or (isinstance(obj, (int, float)) and not isinstance(obj, bool)):
        yield path, obj


def _get(case: dict, table: str, key: str, default: Any = None) -> Any:
    t = case.get(table)
    return t.get(key, default) if isinstance(t, dict) else default


def _pressure_range(where: str, pmax: float, p_hertz: float | None) -> list[str]:
    """A maximum pressure beyond P_MAX where Hertz's (same curvatures, same force or
    approach) is below half of it, or beyond 3 x Hertz's; a huge approach (penetration
    control) may give a huge pressure, and Hertz's then says so too."""
    if p_hertz is not None and p_hertz > 0:
        if pmax > P_MAX and p_hertz <= P_MAX / 2:
            return [f"{where}: max pressure {pmax / 1e9:.4g} GPa > {P_MAX / 1e9:g} GPa "
                    f"(Hertz {p_hertz / 1e9:.4g} GPa)"]
        if pmax > 3 * p_hertz:
            return [f"{where}: max pressure {pmax / 1e9:.4g} GPa > 3 x Hertz "
                    f"{p_hertz / 1e9:.4g} GPa"]
    elif pmax > P_MAX:
        return [f"{where}: max pressure {pmax / 1e9:.4g} GPa > {P_MAX / 1e9:g} GPa"]
    return []


def check_solution(d: dict, case: dict) -> list[str]:
    """What is wrong with a solution reported as a success (``d``: its JSON, ``case``: the
    case dictionary that was solved, valid since it was solved)."""
    bad = []
    for path, v in _walk_numbers(d):
        if v is None or not math.isfinite(v):
            bad.append(f"{path} = {v} (not finite)")
    if bad:
        return bad
    wheel_rail = _get(case, "geometry", "type", "quadratic") == "wheel-rail"
    mu = _get(case, "tangential", "friction")
    load = _get(case, "normal", "load")
    vertical: dict[str, float] = {}
    for k, p in enumerate(d.get("patches", [])):
        n, t, h = p["normal"], p.get("tangential"), p.get("hertz")
        where = f"patch {k}"
        if not n["converged"] or (t is not None and not t["converged"]):
            bad.append(f"{where}: not converged in a success")
        force, pmax, area = n["force"], n["max_pressure"], n["area"]
        if force < 0:
            bad.append(f"{where}: normal force {force:.4g} N < 0")
        if pmax < 0:
            bad.append(f"{where}: max pressure {pmax:.4g} Pa < 0")
        bad += _pressure_range(where, pmax, None if h is None else h["max_pressure"])
        if force > 0 and area <= 0:
            bad.append(f"{where}: force {force:.4g} N on an area {area:.4g} m^2 <= 0")
        g = n["grid"]
        if area > g["nx"] * g["ny"] * g["dx"] * g["dy"] * (1 + 1e-9):
            bad.append(f"{where}: contact area {area:.4g} m^2 larger than the grid")
        if t is not None and mu is not None:
            f = math.hypot(*t["force"])
            if f > mu * force * (1 + 1e-6) + 1e-300:
                bad.append(f"{where}: |creep force| {f:.6g} N > mu N = {mu * force:.6g} N")
            if t.get("model", "bem") == "bem" and \
                    t["max_traction"] > mu * pmax * (1 + 1e-6) + 1e-300:
                bad.append(f"{where}: max traction {t['max_traction']:.4g} Pa > mu p_max "
                           f"{mu * pmax:.4g} Pa")
            if not 0 <= t["slip_area_ratio"] <= 1:
                bad.append(f"{where}: slip area ratio {t['slip_area_ratio']}")
        if wheel_rail:
            gam = p["contact_angle"]
            if not -math.pi / 2 < gam < math.pi / 2:
                bad.append(f"{where}: contact angle {gam:.4g} rad outside (-pi/2, pi/2)")
            if p["rolling_radius"] <= 0:
                bad.append(f"{where}: rolling radius {p['rolling_radius']:.4g} m")
            fs = t["force"][1] if t is not None else 0.0
            side = p["side"]
            if case.get("convention", "railcontact") == "contact":
                from railcontact.settings.convention import SIDE_SIGN

                fs = SIDE_SIGN[side] * fs  # CONTACT's F_s (on the rail, mirrored) -> the wheel's
            vertical[side] = vertical.get(side, 0.0) + force * math.cos(gam) + fs * math.sin(gam)
        else:
            vertical["-"] = vertical.get("-", 0.0) + force
    if isinstance(load, (int, float)) and load > 0:
        if not d.get("patches"):
            bad.append(f"load {load:.6g} N and no contact patch")
        for side, fz in vertical.items():
            if abs(fz - load) > LOAD_RTOL * load:
                bad.append(f"{side} vertical force {fz:.6g} N misses the load {load:.6g} N "
                           f"by {abs(fz - load) / load:.2%}")
    return bad


# ---------------------------------------------------------------------------------------
# Running a case
_ERROR = re.compile(r"railcontact: error: .+\n(  .*\n)*\Z")


def classify_cli(code: int | None, out: str, err: str, case: dict) -> Outcome:
    """The kind of one ``railcontact solve --json`` run (``code`` None: timed out)."""
    if code is None:
        return Outcome("hang", "no answer within the time limit")
    if "MemoryError" in err or code in (-signal.SIGKILL, -signal.SIGSEGV) and not err:
        return Outcome("memory", _last_line(err) or f"killed by signal {-code}")
    if "Traceback" in err or code not in (0, 1, 2, 3):
        return Outcome("traceback", _last_line(err) or f"exit {code}")
    err, warnings = _split_warnings(err)
    if code == 3:  # no contact: nothing solved, one warning line (documented)
        if not re.fullmatch(r"railcontact: warning: .*nothing was solved\n", err):
            return Outcome("traceback", f"exit 3 without the warning: {err[:200]!r}")
        try:
            strict_json(out)
        except ValueError as exc:
            return Outcome("traceback", f"exit 3 with JSON that is not strict: {exc}")
        return Outcome("clean error", "no contact: nothing was solved", warnings=warnings)
    if code == 2:
        if not _ERROR.match(err):
            return Outcome("traceback", f"exit 2 without a one-line error: {err[:200]!r}")
        if "\n" in err.rstrip("\n") and not re.match(r"railcontact: error: (.+: )?\d+ problems",
                                                    err):  # (named with its file)
            return Outcome("traceback", f"multi-line error: {err[:200]!r}")
        try:  # (the file's {"file", "error"} object)
            if "error" not in strict_json(out):
                return Outcome("traceback", f"exit 2 without the error's JSON: {out[:200]!r}")
        except ValueError as exc:
            return Outcome("traceback", f"exit 2 with JSON that is not strict: {exc}")
        return Outcome("clean error", err.strip().splitlines()[0][20:], warnings=warnings)
    try:
        d = strict_json(out)
    except ValueError as exc:
        return Outcome("silent-wrong" if code == 0 else "traceback",
                       f"exit {code} with JSON that is not strict: {exc}", warnings=warnings)
    if code == 1:
        conv = [p["normal"]["converged"] and (p.get("tangential") or {"converged": True})
                ["converged"] for p in d.get("patches", [])]
        if all(conv):
            return Outcome("traceback", "exit 1 but every patch says converged",
                           warnings=warnings)
        return Outcome("not converged", _not_converged_message(d), warnings=warnings)
    problems = check_solution(d, in_process(case))
    if problems:
        return Outcome("silent-wrong", "; ".join(problems[:4]), warnings=warnings)
    return Outcome("ok", warnings=warnings)


_WARNING = re.compile(r"^\S.*:\d+: \w*Warning: .*\n(  .*\n)?", re.M)


def _split_warnings(err: str) -> tuple[str, str]:
    """(stderr without Python's warning lines, those lines)."""
    return _WARNING.sub("", err), "".join(m.group(0) for m in _WARNING.finditer(err))


def _not_converged_message(d: dict) -> str:
    for p in d.get("patches", []):
        for part in ("normal", "tangential"):
            s = p.get(part)
            if s is not None and not s["converged"]:
                return f"{part}: {s['message']}"
    return ""


def _last_line(text: str) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return lines[-1] if lines else ""


def _limit_memory() -> None:  # in the child, before exec
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def run_cli(case: dict, timeout: float, folder: Path, name: str = "case") -> Outcome:
    """``railcontact solve FILE --json`` on ``case`` in a subprocess."""
    path = folder / f"{name}.toml"
    path.write_text(to_toml(case))
    exe = Path(sys.executable).with_name("railcontact")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "railcontact"]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd + ["solve", str(path), "--json"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, errors="replace",
                            preexec_fn=_limit_memory, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
        code: int | None = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        code = None
    res = classify_cli(code, out, err, case)
    res.seconds = time.perf_counter() - t0
    return res


class Hang(BaseException):
    """Raised by the alarm of :func:`time_limit` (not an Exception: nothing catches it)."""


@contextmanager
def time_limit(seconds: float):
    """Raise :class:`Hang` in the main thread after ``seconds`` (SIGALRM)."""
    def on_alarm(signum, frame):
        raise Hang()

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def solve_in_process(case: dict, timeout: float) -> Outcome:
    """``railcontact.solve(case)`` in this process, classified as the CLI run would be
    (the solution through ``solution_json`` and a strict parse)."""
    import railcontact as rc
    from railcontact.io.jsonout import solution_json

    case = in_process(case)
    t0 = time.perf_counter()
    try:
        with time_limit(timeout):
            sol = rc.solve(case)
            text = solution_json(sol)
    except Hang:
        return Outcome("hang", "no answer within the time limit", time.perf_counter() - t0)
    except MemoryError as exc:
        return Outcome("memory", f"MemoryError: {exc}", time.perf_counter() - t0)
    except rc.SolverError as exc:  # valid input, a load loop that did not converge
        return Outcome("not converged", str(exc).splitlines()[0], time.perf_counter() - t0)
    except rc.RailContactError as exc:
        return Outcome("clean error", str(exc).splitlines()[0], time.perf_counter() - t0)
    except Exception as exc:
        return Outcome("traceback", _where(exc), time.perf_counter() - t0)
    dt = time.perf_counter() - t0
    try:
        d = strict_json(text)
    except ValueError as exc:
        return Outcome("silent-wrong", f"JSON not strict: {exc}", dt)
    if not sol.converged:
        return Outcome("not converged", _not_converged_message(d), dt)
    problems = check_solution(d, case) + _cut_patches(sol.patches, "case")
    return Outcome("silent-wrong", "; ".join(problems[:4]), dt) if problems else Outcome("ok",
                                                                                         "", dt)


def _where(exc: BaseException) -> str:
    """``Type: message`` and the innermost railcontact frame."""
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if "railcontact" in f.filename]
    at = f" at {Path(frames[-1].filename).name}:{frames[-1].lineno} ({frames[-1].name})" \
        if frames else ""
    return f"{type(exc).__name__}: {str(exc)[:160]}{at}"


def random_cases(rng: random.Random, n: int, scratch: Path) -> list[tuple[dict, list[str]]]:
    """``n`` mutated cases (about one in eight left as it is, as a control)."""
    bases = base_cases()
    out = []
    for _ in range(n):
        base = rng.choice(bases)
        if rng.random() < 0.12:
            out.append((copy.deepcopy(base), ["(unmutated)"]))
        else:
            out.append(mutate_case(rng, base, scratch))
    return out


# ---------------------------------------------------------------------------------------
# WheelsetContact steps
def encode(obj: Any) -> Any:
    """JSON-able form of a step (non-finite floats as {"float": "nan"})."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return {"float": repr(obj)}
    if isinstance(obj, dict):
        return {k: encode(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [encode(v) for v in obj]
    return obj


def decode(obj: Any) -> Any:
    if isinstance(obj, dict):
        if set(obj) == {"float"}:
            return float(obj["float"])
        return {k: decode(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return tuple(decode(v) for v in obj)
    return obj


SETTINGS_CHOICES = {
    "warm_start": ("none", "estimate", "previous", "previous+estimate"),
    "normal_estimate": ("none", "hertz", "kp", "infcon"),
    "tangential_estimate": ("none", "fastsim", "fastrip"),
    "tangential_solver": ("steadygs", "convexgs"),
    "load_includes_creep": (True, True, False),
}
BAD_SETTINGS = {"quantum": [0, -1, 2.5, NAN], "estimate_grid": [(0, 0), (4,), (1e9, 4)],
                "strips": [(0, 0), (2, 2, 2), ("a", 4)], "element_size": [1e-7, 0.0, NAN, 1.0],
                "friction": [0.0, -0.1, NAN, INF, 1e300], "margin": [0.0, 1e-300, 1e300],
                "normal_tolerance": [0.0, 1.0, 1e-300], "load_tolerance": [0.0, 2.0, NAN],
                "spin_offset": [-1.0, 2.0], "max_iterations_normal": [0, 1, 2**63],
                "fft": ["fftw", ""], "warm_start": ["prev", None]}


def random_settings(rng: random.Random, bad: bool = False) -> dict:
    s = {"friction": round(rng.uniform(0.1, 0.6), 3), "element_size": 2e-3}
    for k, cs in SETTINGS_CHOICES.items():
        s[k] = rng.choice(cs)
    if rng.random() < 0.15:
        s["element_size"] = 1e-3
    if rng.random() < 0.1:
        s["max_iterations_normal"] = rng.choice([1, 3, 10])
    if bad:
        k = rng.choice(list(BAD_SETTINGS))
        s[k] = rng.choice(BAD_SETTINGS[k])
    return s


def random_step(rng: random.Random, prev: dict | None, walk: bool, t: float) -> dict:
    """One step: a small move from ``prev`` (walk) or a random jump."""
    def near(x: float, lo: float, hi: float, d: float) -> float:
        return min(max(x + rng.gauss(0, d), lo), hi)

    if walk and prev is not None and "pose" in prev:
        lat, yaw, roll = prev["pose"]
        pose = [near(lat, -0.02, 0.02, 3e-4), near(yaw, -0.01, 0.01, 2e-4), roll]
    else:
        pose = [rng.uniform(-0.02, 0.02), rng.uniform(-0.01, 0.01),
                rng.choice([0.0, 0.0, rng.uniform(-0.005, 0.005)])]
    step: dict[str, Any] = {"pose": pose, "time": t}
    if rng.random() < 0.85:
        step["loads"] = [rng.choice([0.0, rng.uniform(0, 2e5)]) if rng.random() < 0.1
                         else rng.uniform(0, 2e5) for _ in range(2)]
    else:
        step["vertical"] = rng.uniform(-1e-3, 1e-4)
    r = rng.random()
    if r < 0.55:
        step["creepages"] = [[rng.uniform(-0.01, 0.01), rng.uniform(-0.01, 0.01),
                              rng.uniform(-1, 1)] for _ in range(2)]
    elif r < 0.9:
        v = rng.choice([rng.uniform(1, 100), rng.uniform(0.05, 1)])
        step["kinematics"] = {"speed": v, "lateral_velocity": rng.uniform(-0.1, 0.1),
                              "yaw_rate": rng.uniform(-0.1, 0.1),
                              "spin_speed": None if rng.random() < 0.5 else
                              v / R0 * (1 + rng.uniform(-0.01, 0.01))}
    if rng.random() < 0.1:
        step["remember"] = False
    return step


def spoil_step(rng: random.Random, step: dict) -> dict:
    """A step with one bad API input (wrong shape, type or value)."""
    step = copy.deepcopy(step)
    what = rng.choice(["loads", "creepages", "vertical", "pose", "kinematics", "both",
                       "time"])
    bad = rng.choice([NAN, INF, -1.0, -1e300, 1e300, "a", None, 2**64, True])
    if what == "loads":
        step.pop("vertical", None)
        step["loads"] = rng.choice([[bad, 1e4], [1e4], 8e4, [1e4, 1e4, 1e4], [[1e4], [1e4]]])
    elif what == "creepages":
        step.pop("kinematics", None)
        step["creepages"] = rng.choice([[[bad, 0, 0], [0, 0, 0]], [[0, 0], [0, 0]],
                                        [0, 0, 0], [[0, 0, 0]], [[0, 0, 0, 0], [0, 0, 0, 0]]])
    elif what == "vertical":
        step.pop("loads", None)
        step["vertical"] = rng.choice([bad, -0.011, -1.0, 1.0, 1e-300])
    elif what == "pose":
        step["pose"] = rng.choice([[bad, 0, 0], [0, bad, 0], [0.1, 0, 0], [-0.1, 0, 0],
                                   [0, 0.2, 0], [0.05, 0, 0]])
    elif what == "kinematics":
        step.pop("creepages", None)
        step["kinematics"] = rng.choice([{"speed": bad}, {"speed": 0.0}, {"speed": 1e-300},
                                         {"speed": 30.0, "spin_speed": bad},
                                         {"speed": 30.0, "yaw_rate": 1e300}])
    elif what == "both":
        step["loads"], step["vertical"] = [1e4, 1e4], -1e-4
    else:
        step["time"] = rng.choice([NAN, -1.0, "t", step["time"] - 1.0])
    step["spoilt"] = what
    return step


def random_sequences(rng: random.Random, n_steps: int) -> list[dict]:
    """Sequences of steps, each with its own settings (a fresh WheelsetContact)."""
    seqs, total = [], 0
    while total < n_steps:
        n = min(rng.choice([1, 2, 5, 10, 20, 40]), n_steps - total)
        bad_settings = rng.random() < 0.03
        walk = rng.random() < 0.6
        steps, prev, t = [], None, 0.0
        for _ in range(n):
            t += rng.choice([1e-3, 1e-3, 5e-3, 0.0]) if walk else 1e-3
            s = random_step(rng, prev, walk, t)
            if rng.random() < 0.04:
                s = spoil_step(rng, s)
            steps.append(s)
            prev = s
        seqs.append({"settings": random_settings(rng, bad_settings), "steps": steps})
        total += n
    return seqs


_STEEL_WS: dict[str, Any] = {}


def new_wheelset(settings: dict):
    """A WheelsetContact for S1002 on 60E1 at 1:40 with these settings."""
    import railcontact as rc

    if not _STEEL_WS:
        _STEEL_WS["track"] = rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40))
        _STEEL_WS["ws"] = rc.Wheelset(rc.read_profile("S1002", "wheel"), R0)
        _STEEL_WS["pair"] = rc.ElasticPair.of(rc.STEEL, rc.STEEL)
    return rc.WheelsetContact(_STEEL_WS["track"], _STEEL_WS["ws"], _STEEL_WS["pair"],
                              rc.ContactSettings(**{"rigid_wheelset": "solve", **settings}))


def call_step(wc, step: dict):
    """``wc.solve(...)`` for a decoded step."""
    import railcontact as rc

    kw: dict[str, Any] = {}
    for k in ("loads", "vertical", "creepages", "time", "remember"):
        if k in step:
            kw[k] = step[k]
    if "kinematics" in step:
        kw["kinematics"] = rc.Kinematics(**step["kinematics"])
    return wc.solve(rc.Pose(*step["pose"]), **kw)


def cut_by_profile_end(patch) -> bool:
    """Whether a wheel-rail patch's contact is cut where the profiles end (gap ``FAR``):
    an element next to a ``FAR`` one carries at least half the maximum pressure, on a
    contact at least 5 elements across (a narrower one is just under-resolved). An
    internal check (the gap of the patch's grid)."""
    import numpy as np

    try:
        from railcontact.geometry.search import FAR
        h = patch.geometry.gap_on_grid(patch.normal.grid)
    except (AttributeError, ImportError, TypeError):  # the internals moved: no check
        return False
    p = np.asarray(patch.normal.pressure)
    c = p > 0
    if np.count_nonzero(c.any(axis=0)) < 5 or not c.any():
        return False
    far = h >= FAR
    near = np.zeros_like(far)
    near[1:] |= far[:-1]
    near[:-1] |= far[1:]
    near[:, 1:] |= far[:, :-1]
    near[:, :-1] |= far[:, 1:]
    edge = near & c
    return bool(edge.any() and p[edge].max() >= 0.5 * p.max())


def _cut_patches(patches, where: str) -> list[str]:
    return [f"{where} patch {j}: the contact is cut where the profiles end (gap FAR next to "
            f"an element with >= p_max / 2), p_max {p.normal.max_pressure / 1e9:.4g} GPa"
            for j, p in enumerate(patches) if p.geometry is not None and cut_by_profile_end(p)]


def check_wheelset(r, step: dict, settings: dict) -> list[str]:
    """What is wrong with the wheels of a step reported solved (status 0 ok, or 4
    outside validity: solved, beyond a limit of railcontact.timestep.validity)."""
    bad = []
    mu = settings.get("friction", 0.4)
    loads = step.get("loads")
    with_creep = settings.get("load_includes_creep", True) and (
        "creepages" in step or "kinematics" in step)
    if not all(math.isfinite(x) for x in r.force) or not math.isfinite(r.yaw_moment):
        if r.status in (0, 4):
            bad.append(f"wheelset force {r.force} / yaw moment {r.yaw_moment} not finite")
    rigid = (*r.moment, r.vertical, r.roll)  # the rigid wheelset's (None: not solved)
    if r.status in (0, 4) and not all(x is None or math.isfinite(x) for x in rigid):
        bad.append(f"wheelset moment {r.moment}, vertical {r.vertical}, roll {r.roll} "
                   "not finite")
    for k, w in enumerate(r.wheels):
        q = loads[k] if loads is not None else None
        if w.status == 2 and q is not None and q > 0:
            bad.append(f"{w.side}: status 2 (no contact) under a load of {q:.6g} N")
        if w.status not in (0, 4):
            continue
        vals = {"normal_force": w.normal_force, "spin_moment": w.spin_moment,
                "yaw_moment": w.yaw_moment, "contact_angle": w.contact_angle,
                "rolling_radius": w.rolling_radius, "area": w.area,
                "max_pressure": w.max_pressure, "slip_area_ratio": w.slip_area_ratio,
                "wheel_position": w.wheel_position, "rail_position": w.rail_position,
                "lateral_position": w.lateral_position,
                "derailment_quotient": w.derailment_quotient, "approach": w.approach,
                "penetration": w.penetration}
        vals.update({f"moment[{i}]": v for i, v in enumerate(w.moment)})
        vals.update({f"creep_force[{i}]": v for i, v in enumerate(w.creep_force)})
        vals.update({f"track_force[{i}]": v for i, v in enumerate(w.track_force)})
        nonfinite = [f"{k2} = {v}" for k2, v in vals.items() if not math.isfinite(v)]
        if nonfinite:
            bad.append(f"{w.side}: " + ", ".join(nonfinite))
            continue
        if q is not None and q > 0 and not w.patches:
            bad.append(f"{w.side}: status ok, load {q:.6g} N, no patch")
        if w.normal_force < 0:
            bad.append(f"{w.side}: normal force {w.normal_force:.4g} N < 0")
        if w.normal_force > 0 and w.area <= 0:
            bad.append(f"{w.side}: normal force {w.normal_force:.4g} N on area {w.area}")
        if w.max_pressure < 0:
            bad.append(f"{w.side}: max pressure {w.max_pressure / 1e9:.4g} GPa")
        if not 0 <= w.slip_area_ratio <= 1:
            bad.append(f"{w.side}: slip area ratio {w.slip_area_ratio}")
        if w.patches and not 0.35 < w.rolling_radius < 0.6:
            bad.append(f"{w.side}: rolling radius {w.rolling_radius:.4g} m")
        bad += _cut_patches(w.patches, w.side)
        nz = 0.0
        for j, p in enumerate(w.patches):
            n, t, cp = p.normal, p.tangential, p.geometry
            bad += _pressure_range(f"{w.side} patch {j}", n.max_pressure,
                                   None if p.hertz is None else p.hertz.max_pressure)
            if not -math.pi / 2 < cp.contact_angle < math.pi / 2:
                bad.append(f"{w.side} patch {j}: contact angle {cp.contact_angle:.4g} rad")
            if t is not None:
                f = math.hypot(*t.force)
                if f > mu * n.force * (1 + 1e-6):
                    bad.append(f"{w.side} patch {j}: |creep force| {f:.6g} N > mu N = "
                               f"{mu * n.force:.6g} N")
            nz += n.force * math.cos(cp.contact_angle)
        if q is not None and q > 0:
            fz = w.track_force[2] if with_creep else nz
            if abs(fz - q) > LOAD_RTOL * q:
                what = "vertical force" if with_creep else "normal forces' vertical share"
                bad.append(f"{w.side}: {what} {fz:.6g} N misses the load {q:.6g} N by "
                           f"{abs(fz - q) / q:.2%} (N = {w.normal_force:.6g} N)")
    return bad


def run_step(wc, step: dict, settings: dict, timeout: float | None = None) -> Outcome:
    """One step, classified (``timeout``: an alarm in this process)."""
    import railcontact as rc

    t0 = time.perf_counter()
    try:
        if timeout is None:
            r = call_step(wc, step)
        else:
            with time_limit(timeout):
                r = call_step(wc, step)
    except Hang:
        return Outcome("hang", "no answer within the time limit", time.perf_counter() - t0)
    except MemoryError as exc:
        return Outcome("memory", f"MemoryError: {exc}", time.perf_counter() - t0)
    except rc.SolverError as exc:
        return Outcome("not converged", str(exc)[:200], time.perf_counter() - t0)
    except rc.RailContactError as exc:
        return Outcome("clean error", str(exc)[:200], time.perf_counter() - t0)
    except Exception as exc:
        return Outcome("traceback", _where(exc), time.perf_counter() - t0)
    dt = time.perf_counter() - t0
    problems = check_wheelset(r, step, settings)
    if problems:
        return Outcome("silent-wrong", "; ".join(problems[:4]), dt)
    if r.status in (0, 4):  # solved (4: outside validity, a documented status)
        return Outcome("ok", "" if r.status == 0 else _status_text(r), dt)
    if r.status == 1:
        rigid = r.rigid_solution
        if (rigid is not None and not rigid.converged
                and all(w.status in (0, 4) for w in r.wheels)):  # (the wheels checked above)
            return Outcome("rigid not found", f"{rigid.message[:120]} | {_status_text(r)}",
                           dt)
        return Outcome("not converged", _status_text(r), dt)
    if all(w.message for w in r.wheels) and r.status in (2, 3):
        return Outcome("clean error" if r.status == 3 else "ok", _status_text(r), dt)
    return Outcome("traceback", f"status {r.status} without a message: {_status_text(r)}", dt)


def _status_text(r) -> str:
    return " | ".join(f"{w.side} {w.status}: {w.message[:90]}" for w in r.wheels)


def worker() -> None:
    """The step worker: JSON lines in ({"settings", "step"} or {"reset"}), outcomes out."""
    _limit_memory()
    import warnings

    warnings.simplefilter("ignore")
    import railcontact as rc

    wc = settings = None
    out = sys.stdout
    sys.stdout = sys.stderr  # nothing but answers on the pipe
    for line in sys.stdin:
        msg = json.loads(line)
        if "settings" in msg:
            settings = decode(msg["settings"])
            try:
                wc = new_wheelset(settings)
                res = Outcome("ok")
            except MemoryError as exc:
                wc, res = None, Outcome("memory", f"MemoryError: {exc}")
            except rc.RailContactError as exc:
                wc, res = None, Outcome("clean error", str(exc)[:200])
            except Exception as exc:
                wc, res = None, Outcome("traceback", _where(exc))
        else:
            step = decode(msg["step"])
            if wc is None:
                res = Outcome("clean error", "no solver (its settings were refused)")
            else:
                res = run_step(wc, step, settings)
        out.write(json.dumps(asdict(res)) + "\n")
        out.flush()


class StepWorker:
    """A worker process (this script with ``--worker``); restarted after a hang or crash."""

    def __init__(self) -> None:
        self.proc: subprocess.Popen | None = None

    def _start(self) -> None:
        self.proc = subprocess.Popen([sys.executable, __file__, "--worker"],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL, text=True, bufsize=1,
                                     start_new_session=True)

    def ask(self, msg: dict, timeout: float) -> Outcome:
        import selectors

        if self.proc is None or self.proc.poll() is not None:
            self._start()
        assert self.proc is not None and self.proc.stdin and self.proc.stdout
        t0 = time.perf_counter()
        try:
            self.proc.stdin.write(json.dumps(encode(msg)) + "\n")
            self.proc.stdin.flush()
        except BrokenPipeError:
            self.stop()
            return Outcome("traceback", "the worker died", 0.0)
        sel = selectors.DefaultSelector()
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        ready = sel.select(timeout)
        sel.close()
        if not ready:
            self.stop()
            return Outcome("hang", "no answer within the time limit", time.perf_counter() - t0)
        line = self.proc.stdout.readline()
        if not line:
            code = self.proc.wait()
            self.stop()
            kind = "memory" if code in (-signal.SIGKILL, -signal.SIGSEGV) else "traceback"
            return Outcome(kind, f"the worker died (exit {code})", time.perf_counter() - t0)
        return Outcome(**json.loads(line))

    def stop(self) -> None:
        if self.proc is not None:
            if self.proc.poll() is None:
                os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()
            self.proc = None


# ---------------------------------------------------------------------------------------
@dataclass
class Tally:
    counts: dict[str, dict[str, int]] = field(default_factory=dict)
    findings: list[dict] = field(default_factory=list)
    warnings: list[dict] = field(default_factory=list)

    def add(self, group: str, res: Outcome, reproducer: dict) -> None:
        c = self.counts.setdefault(group, dict.fromkeys(KINDS, 0))
        c[res.kind] += 1
        if res.kind in FINDINGS:
            self.findings.append({"group": group, "kind": res.kind, "detail": res.detail,
                                  "seconds": round(res.seconds, 3), **reproducer})
        elif res.warnings.strip():
            self.warnings.append({"group": group, "kind": res.kind,
                                  "stderr": res.warnings.strip()[-300:], **reproducer})

    def table(self) -> str:
        head = ["inputs", "ok", "clean errors", "not converged", "rigid not found",
                "tracebacks", "hangs", "silent-wrong", "memory"]
        rows = [f"{'':10s}" + "".join(f"{h:>16s}" for h in head)]
        total = dict.fromkeys(KINDS, 0)
        for g, c in self.counts.items():
            rows.append(f"{g:10s}" + f"{sum(c.values()):16d}" +
                        "".join(f"{c[k]:16d}" for k in KINDS))
            for k in KINDS:
                total[k] += c[k]
        rows.append(f"{'total':10s}" + f"{sum(total.values()):16d}" +
                    "".join(f"{total[k]:16d}" for k in KINDS))
        return "\n".join(rows)


def fuzz_cases(rng: random.Random, n: int, timeout: float, tally: Tally, scratch: Path,
               progress: bool = True) -> None:
    for i, (case, notes) in enumerate(random_cases(rng, n, scratch)):
        res = run_cli(case, timeout, scratch, f"case{i}")
        tally.add("cases", res, {"input": i, "mutations": notes, "toml": to_toml(case)})
        if progress:
            print(f"\rcases {i + 1}/{n}", end="", file=sys.stderr, flush=True)
    if progress:
        print(file=sys.stderr)


def fuzz_steps(rng: random.Random, n: int, timeout: float, tally: Tally,
               progress: bool = True) -> None:
    w = StepWorker()
    done = 0
    try:
        for seq in random_sequences(rng, n):
            res = w.ask({"settings": seq["settings"]}, timeout)
            if res.kind != "ok":  # settings refused (or worse): counted as one input
                tally.add("steps", res, {"settings": encode(seq["settings"]), "history": []})
            for j, step in enumerate(seq["steps"]):
                if res.kind != "ok" and j == 0:
                    break
                out = w.ask({"step": step}, timeout)
                rep = {"settings": encode(seq["settings"]),
                       "history": encode(seq["steps"][:j]), "step": encode(step)}
                if out.kind in FINDINGS and out.kind != "hang" and j > 0:  # history needed?
                    w.ask({"settings": seq["settings"]}, timeout)
                    cold = w.ask({"step": step}, timeout)
                    rep["fresh_solver"] = f"{cold.kind}: {cold.detail[:120]}"
                    w.ask({"settings": seq["settings"]}, timeout)
                    for s in seq["steps"][:j + 1]:  # back to where the sequence was
                        w.ask({"step": s}, timeout)
                tally.add("steps", out, rep)
                if out.kind == "hang":  # the worker was killed: start the sequence afresh
                    w.ask({"settings": seq["settings"]}, timeout)
            done += len(seq["steps"])
            if progress:
                print(f"\rsteps {done}/{n}", end="", file=sys.stderr, flush=True)
    finally:
        w.stop()
        if progress:
            print(file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cases", type=int, default=300, help="case files through the CLI (300)")
    ap.add_argument("--steps", type=int, default=3000,
                    help="random WheelsetContact steps (3000)")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds per input (60)")
    ap.add_argument("--json", metavar="FILE", help="save the counts and findings")
    ap.add_argument("--quiet", action="store_true", help="no progress on stderr")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        worker()
        return 0
    t0 = time.perf_counter()
    tally = Tally()
    with tempfile.TemporaryDirectory(prefix="railcontact_fuzz_") as tmp:
        fuzz_cases(random.Random(args.seed), args.cases, args.timeout, tally, Path(tmp),
                   not args.quiet)
    fuzz_steps(random.Random(args.seed + 1), args.steps, args.timeout, tally, not args.quiet)
    dt = time.perf_counter() - t0
    print(f"seed {args.seed}, {args.cases} cases, {args.steps} steps, timeout {args.timeout:g} s:"
          f" {dt:.0f} s")
    print(tally.table())
    for f in tally.findings:
        where = ", ".join(f["mutations"]) if "mutations" in f else json.dumps(f.get("step"))
        print(f"{f['kind']:12s} {f['group']} #{f.get('input', '')}: {f['detail'][:200]}\n"
              f"{'':12s}   input: {where[:300]}")
    if tally.warnings:
        print(f"{len(tally.warnings)} input(s) wrote warnings on stderr (not findings), e.g.:")
        for w in tally.warnings[:5]:
            print(f"  {w['kind']}: {', '.join(w.get('mutations', []))[:120]}: "
                  f"{w['stderr'].splitlines()[-1][:160]}")
    if args.json:
        Path(args.json).write_text(json.dumps(
            {"seed": args.seed, "cases": args.cases, "steps": args.steps,
             "timeout": args.timeout, "seconds": dt, "counts": tally.counts,
             "findings": tally.findings, "warnings": tally.warnings}, indent=1,
            default=str))
    return 1 if tally.findings else 0


if __name__ == "__main__":
    sys.exit(main())
