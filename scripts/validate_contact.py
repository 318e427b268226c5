"""railcontact beside CONTACT on CONTACT's own wheel-rail cases, in CONTACT's convention.

The cases of ``models/reference/contact/``: S1002 on UIC60 (the
Manchester benchmark files, the rail canted in the file), G = 82 GPa, nu = 0.28, mu = 0.4,
a vertical wheel load of 83.3 kN (load control, creep forces counted), steady rolling with
CONTACT's creepages (xi = eta = 2e-4 and its kinematic spin), roll = yaw = 0, both wheels,
CONTACT's y = -8 .. 8 mm at 0.5 mm elements, CONTACT's tolerance eps = 1e-5. Each case is
solved with ``convention = "contact"``: CONTACT's creepages as they are, the forces on the
rail as CONTACT reports them, each patch at its reference point.

Per case it prints railcontact beside CONTACT: normal force F_N, creep forces F_x, F_s
[N], spin moment M_n [N m], maximum pressure [MPa], contact area [mm^2], contact angle
[rad], rolling radius [mm] and the reference point (rail profile coordinate [mm]), and
whether the case meets its targets:

* tread (|y| <= 4 mm): forces within 2 % (or 0.2 % of mu F_N, CONTACT's), M_n within 2 %
  (or 0.2 % of mu F_N times the patch's equivalent radius sqrt(area / pi)), p_max and area
  within 1 %, rolling radius within 0.02 mm;
* flange root and flange (|y| >= 5 mm): the same quantities within 5 % (same floors),
  rolling radius within 0.02 mm.

It writes the rows to a CSV and a figure with each quantity against y for both codes (and
both wheels).

Usage: python scripts/validate_contact.py [--csv FILE] [--plot FILE] [--contact DIR]
       [--profiles DIR]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from _sweep import write_csv
from bench_wheelrail import contact_rows, wheel_case

import railcontact as rc

HERE = Path(__file__).resolve().parent
CONTACT_REFERENCE = HERE.parent / "models" / "reference" / "contact"
"""CONTACT's results (``wheelrail_dx0.5.csv``; its README gives their provenance)."""
PROFILES = HERE.parent / "models" / "profiles"
"""The Manchester benchmark's profile files (``MBench_S1002_v3.prw``, ``MBench_UIC60_v3.prr``)."""
DOCS = HERE.parent / "docs"
MU = 0.4
TOLERANCE = (1e-5, 1e-5)
"""CONTACT's eps for the normal and tangential solvers (its default)."""
TREAD_MM = 4.0
"""|y| up to this is the tread; beyond it, flange root and flange."""
TARGETS = {"tread": {"force": 0.02, "local": 0.01}, "flange": {"force": 0.05, "local": 0.05}}
"""Relative targets: forces and spin moment ("force"), p_max and area ("local")."""
FLOOR = 0.002
"""Force floor as a share of mu F_N (CONTACT's)."""
RADIUS_MM = 0.02
"""Rolling radius target [mm]."""
QUANTITIES = [  # (key, label, unit, kind)
    ("FN", "normal force F_N", "kN", "force"),
    ("FX", "longitudinal creep force F_x", "kN", "force"),
    ("FS", "lateral creep force F_s", "kN", "force"),
    ("MN", "spin moment M_n", "N m", "moment"),
    ("pmax", "maximum pressure", "MPa", "local"),
    ("area", "contact area", "mm^2", "local"),
    ("angle", "contact angle", "rad", None),
    ("radius", "rolling radius", "mm", "radius"),
    ("ycp_r", "reference point on the rail", "mm", None),
]
SCALE = {"FN": 1e-3, "FX": 1e-3, "FS": 1e-3, "MN": 1.0, "pmax": 1.0, "area": 1.0,
         "angle": 1.0, "radius": 1.0, "ycp_r": 1.0}


def contact_values(row: dict) -> dict[str, float]:
    """CONTACT's values of one row in SI units but MPa, mm^2 and mm (its y-like values in
    its own signs: the forces are compared in CONTACT's convention)."""
    return {"FN": float(row["FN"]), "FX": float(row["FX"]), "FS": float(row["FS"]),
            "MN": float(row["MN"]) * 1e-3, "pmax": float(row["pmax"]),
            "area": float(row["area_mm2"]), "angle": float(row["delta_rad"]),
            "radius": float(row["r_roll_kin_mm"]), "ycp_r": float(row["ycp_r"])}


def railcontact_values(sol: rc.Solution, side: str) -> dict[str, float]:
    """railcontact's values of a solved CONTACT case, as :func:`contact_values` has them:
    the forces in CONTACT's convention (the case's), the contact angle and the rail
    coordinate of the reference point with CONTACT's signs (its y-like values point the
    other way on the left wheel)."""
    (p,) = sol.patches
    fx, fs, mn = p.creep_forces
    ref = p.reference
    mirror = -1.0 if side == "left" else 1.0
    return {"FN": p.normal.force, "FX": fx, "FS": fs, "MN": mn,
            "pmax": p.normal.max_pressure * 1e-6, "area": p.normal.area * 1e6,
            "angle": -mirror * ref.contact_angle, "radius": ref.rolling_radius * 1e3,
            "ycp_r": mirror * ref.rail_y * 1e3}


def misses(ours: dict[str, float], theirs: dict[str, float], zone: str) -> list[str]:
    """The quantities of one case outside their targets (module docstring)."""
    out = []
    floor = FLOOR * MU * theirs["FN"]
    a_eq = math.sqrt(theirs["area"] / math.pi) * 1e-3  # [m]
    for key, _, _, kind in QUANTITIES:
        d = abs(ours[key] - theirs[key])
        if kind == "force":
            ok = d <= max(TARGETS[zone]["force"] * abs(theirs[key]), floor)
        elif kind == "moment":
            ok = d <= max(TARGETS[zone]["force"] * abs(theirs[key]), floor * a_eq)
        elif kind == "local":
            ok = d <= TARGETS[zone]["local"] * abs(theirs[key])
        elif kind == "radius":
            ok = d <= RADIUS_MM
        else:
            ok = True
        if not ok:
            out.append(key)
    return out


def run(folder: Path, profiles: Path) -> list[dict]:
    """Solve every CONTACT case (0.5 mm, default tolerance) in CONTACT's convention."""
    rows = []
    for row in contact_rows(folder, 0.5):
        y = float(row["y_mm"])
        case = wheel_case(row, 0.5, TOLERANCE, ("infcon", "fastrip"), profiles, None,
                          convention="contact")
        zone = "tread" if abs(y) <= TREAD_MM else "flange"
        try:
            sol = rc.solve(case)
        except (rc.RailContactError, rc.SolverError) as exc:  # (a case that misses all)
            print(f"  y = {y:g} {row['side']}: {exc}", file=sys.stderr)
            rows.append({"y_mm": y, "side": row["side"], "zone": zone, "converged": False,
                         "misses": "", "error": str(exc)})
            continue
        theirs = contact_values(row)
        ours = railcontact_values(sol, row["side"])
        out = {"y_mm": y, "side": row["side"], "zone": zone, "converged": sol.converged}
        for key in ours:
            out[f"{key}_railcontact"] = ours[key]
            out[f"{key}_contact"] = theirs[key]
        out["misses"] = " ".join(misses(ours, theirs, zone))
        rows.append(out)
    return rows


def met_every_target(r: dict) -> bool:
    """Whether a case was solved, converged and is within every target."""
    return not r.get("error") and r["converged"] and not r["misses"]


def print_table(rows: list[dict]) -> None:
    head = " ".join(f"{k:>15}" for k, *_ in QUANTITIES)
    print(f"{'side':5} {'y':>5} {head}   targets missed")
    failed = [r for r in rows if r.get("error")]
    rows = [r for r in rows if not r.get("error")]
    for r in failed:
        print(f"{r['side']:5} {r['y_mm']:5.1f} not solved: {r['error']}")
    for r in rows:
        vals = " ".join(
            f"{r[f'{k}_railcontact'] * SCALE[k]:7.4g}/{r[f'{k}_contact'] * SCALE[k]:<7.4g}"
            for k, *_ in QUANTITIES)
        note = "" if r["converged"] else ", not converged"
        print(f"{r['side']:5} {r['y_mm']:5.1f} {vals}   {r['misses'] or '-'}{note}")
    print("(railcontact/CONTACT: F_N, F_x, F_s [kN] on the rail, M_n [N m], p_max [MPa], "
          "area [mm^2], angle [rad], rolling radius [mm], reference point on the rail [mm])")
    for zone in ("tread", "flange"):
        zr = [r for r in rows if r["zone"] == zone]
        met = [r for r in zr if met_every_target(r)]
        lost = [r for r in failed if r["zone"] == zone]
        print(f"{zone}: {len(met)} of {len(zr) + len(lost)} cases meet every target (solved, "
              f"converged, within the targets)")
        for key, *_ in QUANTITIES:
            bad = [f"{r['side']} {r['y_mm']:g}" for r in zr if key in r["misses"].split()]
            if bad:
                print(f"  {key} missed in {len(bad)}: {', '.join(bad)}")
        for key, _, unit, kind in QUANTITIES:
            if kind in ("force", "moment", "local"):
                rel = [abs(r[f"{key}_railcontact"] / r[f"{key}_contact"] - 1)
                       for r in zr if r[f"{key}_contact"] != 0]
                print(f"  {key:6} median |diff| {100 * sorted(rel)[len(rel) // 2]:6.2f} %, "
                      f"largest {100 * max(rel):6.2f} %")
            elif kind == "radius" or key in ("angle", "ycp_r"):
                d = [abs(r[f"{key}_railcontact"] - r[f"{key}_contact"]) for r in zr]
                print(f"  {key:6} largest |diff| {max(d):.4g} {unit}")


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 3, figsize=(12, 9), sharex=True)
    for ax, (key, label, unit, _) in zip(axes.flat, QUANTITIES, strict=True):
        for side, colour in (("left", "C0"), ("right", "C3")):
            rs = sorted((r for r in rows if r["side"] == side and not r.get("error")),
                        key=lambda r: r["y_mm"])
            y = [r["y_mm"] for r in rs]
            ax.plot(y, [r[f"{key}_contact"] * SCALE[key] for r in rs], "o", mfc="none",
                    color=colour, label=f"CONTACT, {side}")
            ax.plot(y, [r[f"{key}_railcontact"] * SCALE[key] for r in rs], "-",
                    color=colour, label=f"railcontact, {side}")
        ax.set_title(label, fontsize=10)
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("CONTACT's lateral displacement y [mm]")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("S1002 on UIC60, 83.3 kN, mu 0.4, 0.5 mm elements, eps 1e-5: railcontact "
                 "(lines, convention 'contact') and CONTACT (circles)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=65)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--csv", type=Path, default=DOCS / "validate_contact.csv")
    ap.add_argument("--plot", type=Path, default=DOCS / "validate_contact.png")
    ap.add_argument("--contact", type=Path, default=CONTACT_REFERENCE)
    ap.add_argument("--profiles", type=Path, default=PROFILES)
    args = ap.parse_args()
    rows = run(args.contact, args.profiles)
    print_table(rows)
    write_csv(args.csv, rows)
    plot(rows, args.plot)
    print(f"written {args.csv} and {args.plot}")


if __name__ == "__main__":
    main()
