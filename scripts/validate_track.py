"""railcontact beside CONTACT on real track: curves, rail deviations, other profiles.

The public cases of ``models/reference/contact/track/`` (its README): one wheel on its rail
per case, 83.3 kN vertical load, G = 82 GPa, nu = 0.28, mu = 0.4, 0.5 mm elements, CONTACT's
tolerance 1e-5, CONTACT's velocities (30 m/s) - not creepages: each case is a case file with a
``[kinematics]`` table, the track curvature, the rail's deviation and velocities, in
railcontact's track frame and SI units (:func:`track_case` says how CONTACT's inputs map),
solved in CONTACT's convention (forces on the rail, its creepages).

Per case it compares, in CONTACT's convention: the normal force F_N, the creep forces F_x,
F_s [N], the spin moment M_n [N m], p_max [MPa], the contact area [mm^2], the contact angle
[rad], the rolling radius at the wheel's point [mm], the creepages xi, eta [-], phi [1/m] the
patch was solved with, and the frictional power [W]; and prints per group (A curves, B rail
deviations, C profiles) the largest differences against the targets:

* forces and spin moment within 2 % on the tread (|y| <= 4 mm) and 5 % at the flange root
  and the flange (floor 0.2 % of mu F_N; for M_n times the patch's equivalent radius);
* p_max within 1 %, area within 3 %, contact angle within 1e-3 rad, rolling radius within
  0.02 mm, creepages within 1 % (floor 1e-6, phi's in 1/m: 1e-3), frictional power within 3 %.

It writes the rows to a CSV and a figure of the relative differences per case.

Usage: python scripts/validate_track.py [--reference CSV] [--csv FILE] [--plot FILE]
       [--cases ID ...]

``--reference`` reads another CSV of CONTACT's results with the same columns (e.g. the cases
kept back) instead of ``track_public.csv``.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from pathlib import Path

import railcontact as rc

HERE = Path(__file__).resolve().parent
TRACK_REFERENCE = HERE.parent / "models" / "reference" / "contact" / "track"
"""CONTACT's track results (``track_public.csv``; its README gives their provenance)."""
PROFILES = HERE.parent / "models" / "profiles"
DOCS = HERE.parent / "docs"
MU = 0.4
TOLERANCE = 1e-5
"""CONTACT's eps (its default) for the normal and tangential solvers."""
TREAD_MM = 4.0
"""|y| up to this (CONTACT's wheelset y) is the tread; beyond it, flange root and flange."""
FORCE = {"tread": 0.02, "flange": 0.05}
FLOOR = 0.002
"""Force floor as a share of mu F_N."""
PMAX, AREA, ANGLE, RADIUS_MM, CREEP, CREEP_FLOOR, POWER = 0.01, 0.03, 1e-3, 0.02, 0.01, 1e-6, 0.03
GROUPS = {"A": "curves, yaw, velocities", "B": "rail deviations", "C": "profiles"}
QUANTITIES = [  # (key, label, unit, kind)
    ("FN", "normal force F_N", "N", "force"),
    ("FX", "longitudinal creep force F_x", "N", "force"),
    ("FS", "lateral creep force F_s", "N", "force"),
    ("MN", "spin moment M_n", "N m", "moment"),
    ("pmax", "maximum pressure", "MPa", "pmax"),
    ("area", "contact area", "mm^2", "area"),
    ("angle", "contact angle", "rad", "angle"),
    ("radius", "rolling radius", "mm", "radius"),
    ("xi", "creepage xi", "-", "creep"),
    ("eta", "creepage eta", "-", "creep"),
    ("phi", "spin creepage phi", "1/m", "spin"),
    ("power", "frictional power", "W", "power"),
]


def contact_rows(path: Path = TRACK_REFERENCE / "track_public.csv") -> list[dict]:
    """The rows of CONTACT's ``track_public.csv`` (or another CSV with its columns)."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def zone(row: dict) -> str:
    """"tread" or "flange" (the targets' zones) by the wheelset's y towards the flange
    (CONTACT's y: the left wheel's flange at negative y, the right's at positive)."""
    y = float(row["y_mm"]) * (-1.0 if row["side"] == "left" else 1.0)
    return "flange" if y > TREAD_MM or abs(float(row["delta_rad"])) > 0.2 else "tread"


def track_case(row: dict, profiles: Path = PROFILES, dx_mm: float = 0.5,
               tolerance: float = TOLERANCE) -> dict:
    """The case file (as a dictionary) of one CONTACT row, in railcontact's track frame (X
    forward, Y to the left, Z up) and SI units. CONTACT's track frame has y to the right and
    z down, so: ``lateral_displacement = -Y``, ``yaw = -YAW``, ``curvature = -CURV`` (CONTACT's
    is positive for a right-hand curve), ``rail_offset = [-DY, -DZ]``, ``rail_roll = ROLL``
    (right-hand rule about the same x axis), ``inclination = CANT``, ``lateral_velocity =
    -VY``, ``yaw_rate = -VYAW``, ``spin_speed = -VPITCH``, ``rail_velocity = [-VY_rail,
    -VZ_rail]``, ``rail_roll_rate = VROLL_rail``; lengths mm -> m."""
    f = float
    mm = 1e-3
    return {
        "name": row["case_id"],
        "convention": "contact",
        "material": {"young": 2 * 82e9 * 1.28, "poisson": 0.28},
        "geometry": {
            "type": "wheel-rail", "wheel": str(profiles / row["wheel_profile"]),
            "rail": str(profiles / row["rail_profile"]), "inclination": f(row["cant_rad"]),
            "gauge": f(row["gauge_mm"]) * mm, "gauge_depth": f(row["gaught_mm"]) * mm,
            "back_to_back": f(row["fbdist_mm"]) * mm, "flange_back": f(row["fbpos_mm"]) * mm,
            "wheel_radius": f(row["nomrad_mm"]) * mm,
            "lateral_displacement": -f(row["y_mm"]) * mm, "yaw": -f(row["yaw_rad"]),
            "roll": f(row["roll_rad"]), "side": row["side"],
            "curvature": -f(row["curv_per_mm"]) / mm,
            "rail_offset": [-f(row["rail_dy_mm"]) * mm, -f(row["rail_dz_mm"]) * mm],
            "rail_roll": f(row["rail_roll_rad"]),
        },
        "grid": {"dx": dx_mm * mm, "dy": dx_mm * mm},
        "normal": {"load": f(row["FZ_prescribed"]), "tolerance": tolerance,
                   "estimate": "infcon"},
        "tangential": {"friction": MU, "tolerance": tolerance, "estimate": "fastrip"},
        "kinematics": {
            "speed": f(row["VS"]) * mm, "lateral_velocity": -f(row["VY"]) * mm,
            "vertical_velocity": -f(row["VZ"]) * mm, "roll_rate": f(row["VROLL"]),
            "yaw_rate": -f(row["VYAW"]), "spin_speed": -f(row["VPITCH"]),
            "rail_velocity": [-f(row["rail_vy_mm_s"]) * mm, -f(row["rail_vz_mm_s"]) * mm],
            "rail_roll_rate": f(row["rail_vroll_rad_s"]),
        },
    }


def contact_values(row: dict) -> dict[str, float]:
    """CONTACT's values of a row: forces [N], M_n [N m], p_max [MPa], area [mm^2], angle
    [rad], rolling radius [mm], creepages [-, -, 1/m], frictional power [W]."""
    f = float
    return {"FN": f(row["FN"]), "FX": f(row["FX"]), "FS": f(row["FS"]),
            "MN": f(row["MN"]) * 1e-3, "pmax": f(row["pmax"]), "area": f(row["area_mm2"]),
            "angle": f(row["delta_rad"]), "radius": f(row["r_cp_mm"]),
            "xi": f(row["cksi_6d"]), "eta": f(row["ceta_6d"]), "phi": f(row["cphi_6d"]) * 1e3,
            "power": f(row["fric_power"])}


def railcontact_values(sol: rc.Solution) -> dict[str, float]:
    """railcontact's values of a solved case (one patch) as :func:`contact_values` has them:
    CONTACT's convention (the case's), its contact angle in the real track sense."""
    (p,) = sol.patches
    fx, fs, mn = p.creep_forces
    xi, eta, phi = p.reported_creepage
    sgn = 1.0 if p.geometry.side == "left" else -1.0
    return {"FN": p.normal.force, "FX": fx, "FS": fs, "MN": mn,
            "pmax": p.normal.max_pressure * 1e-6, "area": p.normal.area * 1e6,
            "angle": sgn * p.reference.contact_angle, "radius": p.kinematic_radius * 1e3,
            "xi": xi, "eta": eta, "phi": phi, "power": p.frictional_power}


def differences(ours: dict[str, float], theirs: dict[str, float], where: str
                ) -> dict[str, tuple[float, float]]:
    """Per quantity: (the difference as a share of its target, the difference in the
    quantity's own measure: relative for forces, p_max, area and power, absolute else).
    A share above 1 misses the target."""
    out = {}
    floor = FLOOR * MU * theirs["FN"]
    a_eq = math.sqrt(theirs["area"] / math.pi) * 1e-3  # [m]
    for key, _, _, kind in QUANTITIES:
        a, b = ours[key], theirs[key]
        d = abs(a - b)
        rel = d / abs(b) if b != 0 else math.inf if d else 0.0
        if kind == "force":
            share, measure = d / max(FORCE[where] * abs(b), floor), rel
        elif kind == "moment":
            share, measure = d / max(FORCE[where] * abs(b), floor * a_eq), rel
        elif kind == "pmax":
            share, measure = d / (PMAX * abs(b)), rel
        elif kind == "area":
            share, measure = d / (AREA * abs(b)), rel
        elif kind == "angle":
            share, measure = d / ANGLE, d
        elif kind == "radius":
            share, measure = d / RADIUS_MM, d
        elif kind == "creep":
            share, measure = d / max(CREEP * abs(b), CREEP_FLOOR), d
        elif kind == "spin":
            share, measure = d / max(CREEP * abs(b), CREEP_FLOOR * 1e3), d
        else:  # power
            share, measure = d / (POWER * abs(b)), rel
        out[key] = (share, measure)
    return out


def run(rows: list[dict], profiles: Path = PROFILES) -> list[dict]:
    """Solve each row's case; per case the values of both codes and the differences."""
    out = []
    for row in rows:
        try:
            sol = rc.solve(track_case(row, profiles))
        except (rc.RailContactError, rc.SolverError) as exc:
            print(f"  {row['case_id']}: {exc}", file=sys.stderr)
            out.append({"case": row["case_id"], "group": row["group"], "error": str(exc)})
            continue
        ours, theirs = railcontact_values(sol), contact_values(row)
        where = zone(row)
        diff = differences(ours, theirs, where)
        r = {"case": row["case_id"], "group": row["group"], "subgroup": row["subgroup"],
             "desc": row["desc"], "side": row["side"], "zone": where,
             "converged": sol.converged, "seconds": sol.seconds, "error": ""}
        for key in ours:
            r[f"{key}_railcontact"] = ours[key]
            r[f"{key}_contact"] = theirs[key]
            r[f"{key}_share"] = diff[key][0]
            r[f"{key}_diff"] = diff[key][1]
        r["misses"] = " ".join(k for k in ours if diff[k][0] > 1.0)
        out.append(r)
    return out


def summary(rows: list[dict]) -> list[str]:
    """Per group the largest difference of each quantity (relative in % or absolute) and
    the share of its target (> 1: missed), and the cases that miss a target."""
    lines = []
    for g, what in GROUPS.items():
        rs = [r for r in rows if r["group"] == g and not r["error"]]
        failed = [r["case"] for r in rows if r["group"] == g and r["error"]]
        if not rs and not failed:
            continue
        met = [r for r in rs if not r["misses"] and r["converged"]]
        lines.append(f"group {g} ({what}): {len(met)} of {len(rs) + len(failed)} cases meet "
                     "every target" + (f"; not solved: {', '.join(failed)}" if failed else ""))
        for key, _, unit, kind in QUANTITIES:
            if not rs:
                break
            worst = max(rs, key=lambda r: r[f"{key}_share"])
            d = worst[f"{key}_diff"]
            text = (f"{100 * d:7.3f} %" if kind in ("force", "moment", "pmax", "area", "power")
                    else f"{d:9.3g} {unit}")
            lines.append(f"  {key:6} largest {text}  ({worst[f'{key}_share']:5.2f} of its "
                         f"target, {worst['case']})")
        for r in rs:
            if r["misses"] or not r["converged"]:
                lines.append(f"  {r['case']} ({r['desc']}, {r['zone']}): misses "
                             f"{r['misses'] or '-'}{'' if r['converged'] else ', not converged'}")
    return lines


def write_csv(path: Path, rows: list[dict]) -> None:
    keys: list[str] = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)


def plot(rows: list[dict], path: Path) -> None:
    """The share of its target of each quantity's difference, per case (1 = the target)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rs = [r for r in rows if not r["error"]]
    fig, ax = plt.subplots(figsize=(12, 5))
    for i, (key, label, _, _) in enumerate(QUANTITIES):
        ax.plot(range(len(rs)), [max(r[f"{key}_share"], 1e-4) for r in rs],
                "osv^<>Dph*xP"[i], ms=4, mfc="none", label=label)
    ax.axhline(1.0, color="k", lw=1)
    ax.set_yscale("log")
    ax.set_xticks(range(len(rs)), [r["case"] for r in rs], rotation=90, fontsize=6)
    ax.set_ylabel("|railcontact - CONTACT| / target")
    ax.set_title("CONTACT's track cases (curves A, rail deviations B, profiles C): the "
                 "difference of each quantity as a share of its target", fontsize=10)
    ax.legend(fontsize=6, ncol=4, loc="upper left")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=70)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reference", type=Path, default=TRACK_REFERENCE / "track_public.csv")
    ap.add_argument("--csv", type=Path, default=DOCS / "validate_track.csv")
    ap.add_argument("--plot", type=Path, default=DOCS / "validate_track.png")
    ap.add_argument("--cases", nargs="*", help="case ids (default: all)")
    args = ap.parse_args()
    rows = contact_rows(args.reference)
    if args.cases:
        rows = [r for r in rows if r["case_id"] in args.cases]
    out = run(rows)
    for r in out:
        if r["error"]:
            continue
        print(f"{r['case']:10} {r['zone']:6} " + " ".join(
            f"{k}={r[f'{k}_railcontact']:.5g}/{r[f'{k}_contact']:.5g}" for k, *_ in QUANTITIES)
            + f"  misses: {r['misses'] or '-'}")
    print("\n".join(summary(out)))
    write_csv(args.csv, out)
    plot(out, args.plot)
    print(f"written {args.csv} and {args.plot}")


if __name__ == "__main__":
    main()
