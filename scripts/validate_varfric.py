"""railcontact beside CONTACT on CONTACT's variable-friction example ``mbench_a22_varfric``.

The example (``models/reference/contact/varfric/``, its README gives the provenance): the
right wheel of the Manchester benchmark wheelset, S1002 on UIC60, G = 82 GPa, nu = 0.28,
a vertical load of 10 kN (load control, creep forces counted), dx = ds = 0.2 mm, CONTACT's
tolerance 1e-5, a lateral sweep with yaw and the roll CONTACT was given; the coefficient of
friction interpolated against the contact angle, CONTACT's ``VARFRC``: 0.2 at -20 deg and
0.3 at -10 deg (CONTACT's sign: towards the right wheel's flange negative), constant
beyond. Each planar case is posed with the existing case keys and

* ``[tangential] friction = {angle = [-20 deg, -10 deg], mu = [0.2, 0.3], at = "patch"}``
  in ``convention = "contact"``: CONTACT's table as it is, read once per patch at its
  reference point, as CONTACT does in planar contact; the script also solves each case
  with ``at = "row"`` (a coefficient per lateral element row) and prints how much that
  changes;
* the wheelset's velocities as CONTACT was given them, in a ``[kinematics]`` table
  (``speed = VX_WS``, ``spin_speed = -VPITCH_WS``, ``lateral_velocity = -VY_WS``,
  ``yaw_rate = -VYAW_WS``, ``roll_rate = VROLL_WS``, SI units): each patch's creepages
  follow from rigid-body kinematics at its reference point, as CONTACT forms them; the
  script prints them beside CONTACT's (``CKSI, CETA, CPHI``). ``--creepages contact``
  instead gives each patch the creepages CONTACT printed for it (a case with two patches
  is then solved by the load loop of the wheel with each patch's own creepages,
  :func:`solve_own_creepages`), which separates the friction from the kinematics;
* the wheelset's lateral displacement, yaw and roll with railcontact's signs (Y to the
  left, Z up: ``lateral_displacement = -Y``, ``yaw = -YAW``, ``roll = ROLL``);
* the input's patch separation (``A_SEP`` 90 deg, ``D_SEP`` 6 mm, ``D_COMB`` 3 mm):
  ``[geometry] separation_distance``, ``combine_distance``, so that case 3's two patches,
  6.8 mm apart, have their contact angles turned towards each other as CONTACT turns them
  (:mod:`railcontact.geometry.separation`).

Case 6 varies friction along the track (CONTACT's ``VARFRC = 2``), which at one position
is one coefficient (0.26 at s = 60 mm): it is posed with that number. Cases 5 and 7 use
CONTACT's conformal approach (a curved contact surface), which railcontact does not have:
they are listed and skipped.

Per patch it prints railcontact beside CONTACT: the coefficient of friction at the patch,
F_N, F_x, F_s [N] and M_n [N mm] on the rail (CONTACT's convention), p_max [MPa], area
[mm^2] and the contact reference point (X, Y, Z in CONTACT's track frame [mm]) and
whether the patch meets its targets: forces within 2 % on the tread and 5 % in the flange
(|contact angle| > 0.2 rad), floor 0.2 % of mu F_N (the spin moment: that times the
patch's equivalent radius sqrt(area / pi)), p_max 1 %, area 3 %.

Usage: python scripts/validate_varfric.py [--cases 1,3,4] [--no-rows]
       [--creepages kinematics|contact]
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

import railcontact as rc
from railcontact.contact.loadloop import vertical_force
from railcontact.contact.patch import solve_patch_tangential
from railcontact.contact.wheelrail import (
    build_geometry,
    patch_friction,
    side_settings,
    solve_wheel_normal,
    vertical_approach,
)
from railcontact.settings import Control
from railcontact.settings.convention import side_creepage

HERE = Path(__file__).resolve().parent
REFERENCE = HERE.parent / "models" / "reference" / "contact" / "varfric"
PROFILES = HERE.parent / "models" / "profiles"
OUTPUT = REFERENCE / "mbench_a22_varfric.ref_out"
ALPHA = [math.radians(-20.0), math.radians(-10.0)]
"""The input's ``ALPHA`` [rad] (``-20d``, ``-10d``) with ``FSTAT = FKIN`` = :data:`MU`."""
MU = [0.2, 0.3]
SVF = ([0.0, 100.0], [0.2, 0.3])
"""Case 6's friction along the track: ``SVF`` [mm] and mu (``VARFRC = 2``)."""
LOAD = 10e3
D_SEP, D_COMB = 6e-3, 3e-3
"""The input's ``D_SEP``, ``D_COMB`` [m] (``A_SEP`` = 90 deg; ``D_TURN`` by default
``2 D_SEP - D_COMB`` = 9 mm): two patches 6-9 mm apart have their angles turned."""
DX = 0.2e-3
TOLERANCE = 1e-5
FLANGE_ANGLE = 0.2
"""|contact angle| [rad] beyond which a patch counts as a flange patch."""
TARGETS = {"tread": 0.02, "flange": 0.05, "pmax": 0.01, "area": 0.03, "floor": 0.002}


def contact_cases(path: Path = OUTPUT) -> list[dict]:
    """CONTACT's cases from its ``.ref_out``: per case its number, the wheelset position
    (Y [mm], ROLL, YAW [rad], S [mm]), the V and D digits and per patch the reference point
    (XCP, YCP, ZCP (TR) [mm], DELTCP [rad]), FSTAT, the creepages (CKSI, CETA [-], CPHI
    [rad/mm]) and FN, FX, FS [N], MN [N mm], PMAX [MPa] and the contact elements."""
    lines = path.read_text().splitlines()
    cases: list[dict] = []
    case: dict | None = None
    patch: dict | None = None
    for i, line in enumerate(lines):
        def nums(k: int, i: int = i) -> list[float]:
            return [float(v) for v in lines[i + k].split()]
        if m := re.match(r"\s*Case\s+(\d+)", line):
            case = {"case": int(m.group(1)), "patches": []}
            cases.append(case)
        elif case is None:
            continue
        elif m := re.search(r"VARFRC\s+(\d+).*DISCNS\s+(\d+)", line):
            case["varfrc"], case["discns"] = int(m.group(1)), int(m.group(2))
        elif "S_WS" in line:
            s, y, _, roll, yaw, _ = nums(1)
            case.update(s=s, y=y, roll=roll, yaw=yaw)
        elif "VPITCH_WS" in line:
            vx, vy, _, vroll, vyaw, vpitch = nums(1)
            case.update(vx=vx, vy=vy, vroll=vroll, vyaw=vyaw, vpitch=vpitch)
        elif "DATA FOR CONTACT PATCH" in line:
            patch = {}
            case["patches"].append(patch)
        elif patch is None:
            continue
        elif "DELTCP(TR)" in line:
            x, y, z, d, *_ = nums(1)
            patch.update(xcp=x, ycp=y, zcp=z, delta=d)
        elif re.match(r"\s*FSTAT\s+FKIN\s*$", line):
            patch["mu"] = nums(1)[-2]
        elif "CKSI" in line:
            *_, cksi, ceta, cphi = nums(1)
            patch.update(cksi=cksi, ceta=ceta, cphi=cphi)
        elif re.match(r"\s*FN\s+FX\s+FS\s+MN", line):
            fn, fx, fs, mn, *_ = nums(1)
            patch.update(FN=fn, FX=fx, FS=fs, MN=mn)
        elif "PMAX" in line and "APPROACH" in line:
            patch["pmax"] = nums(1)[-1]
        elif "NPOT" in line and "NCON" in line:
            patch["ncon"] = int(nums(1)[1])
    for c in cases:
        for p in c["patches"]:
            p["area"] = p.get("ncon", 0) * 0.2 * 0.2  # [mm^2] (dx = ds = 0.2 mm)
    return cases


def friction_of(case: dict, at: str) -> float | dict:
    """The case's ``[tangential] friction``: CONTACT's table (``VARFRC = 1``) read ``at``
    "patch" or "row"; for friction along the track (``VARFRC = 2``) the number at the
    case's s."""
    if case["varfrc"] == 2:
        return float(np.interp(case["s"], *SVF))
    return {"angle": ALPHA, "mu": MU, "at": at}


def case_dict(case: dict, creepage: dict | None, at: str = "patch") -> dict:
    """The railcontact case of a CONTACT case with the creepages of ``creepage`` (a patch
    of CONTACT's output), or with None the wheelset's velocities as CONTACT was given them
    (``[kinematics]``: each patch's creepages formed at its reference point)."""
    out = {
        "name": f"mbench_a22_varfric case {case['case']}",
        "convention": "contact",
        "material": {"young": 2 * 82e9 * 1.28, "poisson": 0.28},
        "geometry": {"type": "wheel-rail", "wheel": str(PROFILES / "MBench_S1002_v3.prw"),
                     "rail": str(PROFILES / "MBench_UIC60_v3.prr"), "inclination": 0.0,
                     "gauge": 1.435, "gauge_depth": 0.014, "back_to_back": 1.360,
                     "flange_back": -0.07, "wheel_radius": 0.46,
                     "lateral_displacement": -case["y"] * 1e-3, "yaw": -case["yaw"],
                     "roll": case["roll"], "side": "right",
                     "separation_angle": math.radians(90.0),
                     "separation_distance": D_SEP, "combine_distance": D_COMB},
        "grid": {"dx": DX, "dy": DX},
        "normal": {"load": LOAD, "tolerance": TOLERANCE, "estimate": "infcon"},
        "tangential": {"friction": friction_of(case, at), "tolerance": TOLERANCE,
                       "estimate": "fastrip"},
    }
    if creepage is None:  # CONTACT's wheelset velocities [mm/s, rad/s] in railcontact's frame
        out["kinematics"] = {"speed": case["vx"] * 1e-3, "spin_speed": -case["vpitch"],
                             "lateral_velocity": -case["vy"] * 1e-3,
                             "yaw_rate": -case["vyaw"], "roll_rate": case["vroll"]}
    else:
        out["tangential"]["creepage"] = [creepage["cksi"], creepage["ceta"],
                                         creepage["cphi"] * 1e3]
    return out


def solve_own_creepages(case: dict, at: str = "patch", contact_mu: bool = False
                        ) -> list[rc.PatchSolution]:
    """The wheel of a CONTACT case with several patches, each patch solved with its own
    creepages (CONTACT's, matched by contact angle), the vertical approach found so that
    the vertical force with the creep forces is the load (as CONTACT's load loop).
    ``contact_mu``: each patch with the coefficient CONTACT printed for it instead of the
    table's (a diagnosis: the friction read apart from the patch's geometry)."""
    theirs = sorted(case["patches"], key=lambda p: abs(p["delta"]))
    c = rc.Case.from_dict(case_dict(case, theirs[0], at))
    track, ws, pose = build_geometry(c.geometry)
    settings = c.patch_settings
    settings = replace(settings, grid=replace(settings.grid, centred=True))
    settings = side_settings(settings, "right", "contact")
    normal = replace(settings, tangential=None)
    t = settings.tangential

    def wheel(a: float) -> tuple[float, list[rc.PatchSolution]]:
        ps = solve_wheel_normal(track, ws, pose, "right", Control(penetration=a), normal,
                                c.pair, reference=True)
        ps = sorted(ps, key=lambda p: abs(p.geometry.contact_angle))
        solved = []
        for p, q in zip(ps, theirs, strict=False):
            cr = side_creepage((q["cksi"], q["ceta"], q["cphi"] * 1e3), "right", "contact")
            mu = q["mu"] if contact_mu else patch_friction(t.friction, p.geometry, track)
            solved.append(replace(solve_patch_tangential(p, t, c.pair, settings.normal.fft,
                                                         creepage=cr, friction=mu),
                                  convention="contact"))
        ps = solved + ps[len(solved):]
        return vertical_force(ps) - LOAD, ps

    a0 = vertical_approach(rc.solve(c).patches)  # the one-creepage solution's approach
    a = brentq(lambda a: wheel(a)[0], 0.8 * a0, 1.2 * a0, xtol=1e-12, rtol=1e-10)
    return wheel(a)[1]


def values(p: rc.PatchSolution, theirs: dict) -> dict[str, float]:
    """A patch's values as CONTACT prints them (its convention, mm, N mm, MPa); ``MN``
    about CONTACT's reference point of the patch (``theirs``), ``MN_own`` about
    railcontact's: the two points lie apart along the track by a few micrometres where the
    wheelset is yawed, which moves the spin moment of a sliding flange patch by ``dx F_s``
    (``M_n = x F_s - s F_x`` about the normal)."""
    fx, fs, mn = p.creep_forces
    X, Y, Z = p.geometry.position
    xcp, ycp = X * 1e3, -Y * 1e3
    moved = mn * 1e3 + (xcp - theirs["xcp"]) * fs
    return {"mu": p.friction, "FN": p.normal.force, "FX": fx, "FS": fs, "MN": moved,
            "pmax": p.normal.max_pressure * 1e-6, "area": p.normal.area * 1e6,
            "xcp": xcp, "ycp": ycp, "zcp": -Z * 1e3, "MN_own": mn * 1e3}


def misses(ours: dict[str, float], theirs: dict[str, float]) -> list[str]:
    """The quantities of a patch outside their targets (module docstring)."""
    zone = "flange" if abs(theirs["delta"]) > FLANGE_ANGLE else "tread"
    floor = TARGETS["floor"] * theirs["mu"] * theirs["FN"]
    a_eq = math.sqrt(theirs["area"] / math.pi)  # [mm]
    out = []
    for key in ("FN", "FX", "FS", "MN"):
        f = floor * a_eq if key == "MN" else floor
        if abs(ours[key] - theirs[key]) > max(TARGETS[zone] * abs(theirs[key]), f):
            out.append(key)
    for key in ("pmax", "area"):
        if abs(ours[key] - theirs[key]) > TARGETS[key] * abs(theirs[key]):
            out.append(key)
    return out


COLUMNS = ("mu", "FN", "FX", "FS", "MN", "pmax", "area", "xcp", "ycp", "zcp")


def run(numbers: list[int] | None, rows: bool, kinematic: bool = True) -> list[dict]:
    """Solve the planar cases (or those of ``numbers``); one row per patch; ``kinematic``:
    the creepages from the wheelset's velocities, else CONTACT's printed ones."""
    out = []
    for case in contact_cases():
        if numbers and case["case"] not in numbers:
            continue
        if case["discns"] == 4:
            print(f"case {case['case']}: CONTACT's conformal approach (DISCNS = 4), not "
                  "in railcontact: skipped")
            continue
        t0 = time.perf_counter()
        modes = ("patch", "row") if rows and case["varfrc"] == 1 else ("patch",)
        solved = {}
        for at in modes:
            if kinematic:
                solved[at] = rc.solve(case_dict(case, None, at)).patches
            elif len(case["patches"]) == 1:
                solved[at] = rc.solve(case_dict(case, case["patches"][0], at)).patches
            else:
                solved[at] = solve_own_creepages(case, at)
        seconds = time.perf_counter() - t0
        theirs = sorted(case["patches"], key=lambda p: abs(p["delta"]))
        ours = sorted(solved["patch"], key=lambda p: abs(p.geometry.contact_angle))
        by_row = (sorted(solved["row"], key=lambda p: abs(p.geometry.contact_angle))
                  if "row" in solved else [None] * len(ours))
        if len(ours) != len(theirs) or len(by_row) != len(ours):
            # (patches cannot be paired: every one of CONTACT's counts as missed)
            out.append({"case": case["case"], "patches": len(theirs),
                        "mismatch": f"railcontact found {len(ours)} patches "
                                    f"({len(by_row)} with mu per row), CONTACT "
                                    f"{len(theirs)}"})
            continue
        diagnosis = None
        if len(ours) > 1 and any(misses(values(p, q), q) for p, q in zip(ours, theirs,
                                                                          strict=True)):
            diagnosis = sorted(solve_own_creepages(case, contact_mu=True),
                               key=lambda p: abs(p.geometry.contact_angle))
        for k, (p, q, r) in enumerate(zip(ours, theirs, by_row, strict=True)):
            v = values(p, q)
            solves = [x for x in (p, r) if x is not None]
            converged = all(x.normal.converged and (x.tangential is None or x.tangential.converged)
                            for x in solves)
            row = {"case": case["case"], "patch": k + 1, "y": case["y"],
                   "yaw": case["yaw"], "seconds": seconds, "ours": v, "theirs": q,
                   "misses": misses(v, q) + ([] if converged else ["not converged"]),
                   "rows": None if r is None else values(r, q),
                   "angle": p.geometry.contact_angle,
                   "creepage": p.reported_creepage,
                   "contact_mu": None if diagnosis is None else values(diagnosis[k], q)}
            out.append(row)
    return out


def print_table(rows: list[dict]) -> None:
    unpaired = [r for r in rows if "mismatch" in r]
    rows = [r for r in rows if "mismatch" not in r]
    for r in unpaired:
        print(f"case {r['case']}: {r['mismatch']}: its patches miss every target")
    print(f"{'case':>4} {'y':>4} {'yaw':>6} " + " ".join(f"{k:>17}" for k in COLUMNS)
          + "  targets missed")
    for r in rows:
        o, t = r["ours"], r["theirs"]
        vals = " ".join(f"{o[k]:8.4g}/{t[k]:<8.4g}" for k in COLUMNS)
        print(f"{r['case']:>3}{'abcd'[r['patch'] - 1]} {r['y']:4.1f} {r['yaw'] * 1e3:5.1f}m "
              f"{vals}  {' '.join(r['misses']) or '-'}")
    print("(railcontact/CONTACT: mu at the patch, F_N, F_x, F_s [N] on the rail, M_n [N mm], "
          "p_max [MPa], area [mm^2], reference point X, Y, Z [mm] in CONTACT's track frame; "
          "yaw in mrad)")
    print("relative differences [%] (railcontact - CONTACT) / CONTACT:")
    for r in rows:
        o, t = r["ours"], r["theirs"]
        d = " ".join(f"{k} {100 * (o[k] / t[k] - 1):+6.2f}" for k in COLUMNS[:7])
        print(f"  case {r['case']} patch {r['patch']}: {d}")
    print("spin moment about railcontact's own reference point, M_n [N mm]: "
          + ", ".join(f"case {r['case']}{'abcd'[r['patch'] - 1]} {r['ours']['MN_own']:.4g}"
                      for r in rows))
    print("contact angle of the patch [rad], railcontact/CONTACT (CONTACT's sign): "
          + ", ".join(f"case {r['case']}{'abcd'[r['patch'] - 1]} {-r['angle']:.4f}/"
                      f"{r['theirs']['delta']:.4f}" for r in rows))
    kin = [r for r in rows if r["creepage"] is not None]
    if kin:
        print("creepages (xi, eta [-], phi [1/mm]) railcontact/CONTACT, CONTACT's convention: "
              + ", ".join(f"case {r['case']}{'abcd'[r['patch'] - 1]} "
                          + " ".join(f"{a:.4g}/{b:.4g}" for a, b in zip(
                              (r["creepage"][0], r["creepage"][1], r["creepage"][2] * 1e-3),
                              (r["theirs"]["cksi"], r["theirs"]["ceta"],
                               r["theirs"]["cphi"]), strict=True))
                          for r in kin))
    diag = [r for r in rows if r["contact_mu"] is not None]
    if diag:
        print("with the coefficient CONTACT printed for each patch instead of the table's at "
              "railcontact's angle [%]:")
        for r in diag:
            o, t = r["contact_mu"], r["theirs"]
            d = " ".join(f"{k} {100 * (o[k] / t[k] - 1):+6.2f}" for k in COLUMNS[:7])
            print(f"  case {r['case']} patch {r['patch']}: {d}  missed: "
                  f"{' '.join(misses(o, t)) or '-'}")
    per_row = [r for r in rows if r["rows"] is not None]
    if per_row:
        print("mu per element row (at = 'row') against one mu per patch (at = 'patch'), "
              "railcontact [%]:")
        for r in per_row:
            o, w = r["ours"], r["rows"]
            d = " ".join(f"{k} {100 * (w[k] / o[k] - 1):+6.2f}" for k in ("FN", "FX", "FS"))
            print(f"  case {r['case']} patch {r['patch']}: {d}")
    met = sum(not r["misses"] for r in rows)
    total = len(rows) + sum(r["patches"] for r in unpaired)
    print(f"{met} of {total} patches meet every target (converged, within the targets)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="", help="case numbers, e.g. 1,3,4 (default: all)")
    ap.add_argument("--no-rows", action="store_true", help="skip the at = 'row' solves")
    ap.add_argument("--creepages", choices=("kinematics", "contact"), default="kinematics",
                    help="each patch's creepages from the wheelset's velocities (default) "
                         "or those CONTACT printed")
    args = ap.parse_args()
    numbers = [int(c) for c in args.cases.split(",") if c]
    rows = run(numbers, not args.no_rows, args.creepages == "kinematics")
    print_table(rows)
    sys.exit(0 if all(not r.get("misses", True) for r in rows) else 1)


if __name__ == "__main__":
    main()
