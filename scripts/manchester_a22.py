"""Manchester contact benchmark, case A-2.2 (S1002 / UIC60 at 1:40, 10 kN per wheel).

Lateral shift 0 .. 10 mm in steps of 0.5 mm with yaw 2.4 y mrad (y in mm), the
benchmark's profile files (``models/profiles``; the rail file is canted already, so
inclination 0), gauge 1435 mm, flange-back distance 1360 mm, r0 = 460 mm. As in the
benchmark the roll is solved for equal wheel loads of 10 kN (``roll = "equal-loads"``; BEM,
load control); ``--roll rigid`` takes the rigid-contact roll, ``--roll 0`` none. Prints,
per shift and wheel, the roll beside the roll in CONTACT's input for this case
(``examples/mbench_a22_left.inp``, CONTACT's sign: left side down is positive), the
contact point on the wheel (profile coordinate S) and on the rail (rail profile y), the
contact angle, the rolling radius, the rolling-radius difference and the number of patches,
and writes a CSV.

Conventions: lateral shift positive to the left (the left wheel moves towards flange
contact); roll positive when the left side rises; profile coordinates positive to the
field side; contact angles positive towards the flange.

Usage: python scripts/manchester_a22.py [--profiles DIR] [--csv FILE]
                                        [--roll equal-loads|rigid|ANGLE]
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import railcontact as rc

HERE = Path(__file__).resolve().parent
CONTACT_ROLL = {  # [rad] per shift [mm], CONTACT examples/mbench_a22_left.inp (its sign)
    0.0: 0.0, 0.5: -0.00002304, 1.0: -0.00005049, 1.5: -0.00008103, 2.0: -0.00011280,
    2.5: -0.00014570, 3.0: -0.00018030, 3.5: -0.00021680, 4.0: -0.00025570,
    4.5: -0.00029770, 5.0: -0.00035540, 5.5: -0.00047770, 6.0: -0.00062720,
    6.5: -0.00437600, 7.0: -0.00639300, 7.5: -0.00764200, 8.0: -0.00860600,
    8.5: -0.00940800, 9.0: -0.01010113, 9.5: -0.01071386, 10.0: -0.01126431}


def case_for(shift: float, profiles: Path, roll: str | float = "equal-loads") -> dict:
    return {
        "name": f"A-2.2 shift {shift * 1e3:.1f} mm",
        "material": {"young": 2 * 82e9 * 1.28, "poisson": 0.28},  # G = 82 GPa
        "geometry": {
            "type": "wheel-rail",
            "wheel": str(profiles / "MBench_S1002_v3.prw"),
            "rail": str(profiles / "MBench_UIC60_v3.prr"),
            "inclination": 0.0, "gauge": 1.435, "back_to_back": 1.360,
            "wheel_radius": 0.46, "lateral_displacement": shift,
            "yaw": 2.4e-3 * (shift * 1e3), "side": "both",  # 2.4 y mrad, y in mm
            "roll": roll,
        },
        "grid": {"nx": 48, "ny": 48},
        "normal": {"load": 10e3, "tolerance": 1e-4, "estimate": "hertz"},
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--profiles", type=Path, default=HERE.parent / "models" / "profiles")
    ap.add_argument("--csv", type=Path, default=Path("manchester_a22.csv"))
    ap.add_argument("--roll", default="equal-loads",
                    help="'equal-loads' (default, as the benchmark), 'rigid' or an angle [rad]")
    args = ap.parse_args()
    roll = args.roll if args.roll in ("equal-loads", "rigid") else float(args.roll)
    rows = []
    hdr = (f"{'shift':>6} {'yaw':>6} {'roll':>8} {'CONTACT':>8} {'side':>5} {'S_wheel':>8} "
           f"{'y_rail':>7} {'angle':>6} {'r':>8} {'dr':>7} {'patches':>7}")
    print(hdr)
    print(f"{'mm':>6} {'mrad':>6} {'mrad':>8} {'mrad':>8} {'':>5} {'mm':>8} {'mm':>7} "
          f"{'deg':>6} {'mm':>8} {'mm':>7}")
    for shift_mm, contact_roll in CONTACT_ROLL.items():
        shift = shift_mm * 1e-3
        case = case_for(shift, args.profiles, roll)
        sol = rc.solve(case)
        per_side = {}
        for side in ("left", "right"):
            ps = [p for p in sol.patches if p.geometry.side == side]
            main_patch = max(ps, key=lambda p: p.normal.force)
            per_side[side] = (main_patch.geometry, len(ps))
        dr = per_side["left"][0].rolling_radius - per_side["right"][0].rolling_radius
        for side in ("left", "right"):
            g, n = per_side[side]
            row = {"shift_mm": shift * 1e3, "yaw_mrad": case["geometry"]["yaw"] * 1e3,
                   "roll_mrad": sol.roll * 1e3, "contact_roll_mrad": -contact_roll * 1e3,
                   "side": side, "wheel_S_mm": g.wheel_s * 1e3, "rail_y_mm": g.rail_y * 1e3,
                   "contact_angle_deg": math.degrees(g.contact_angle),
                   "rolling_radius_mm": g.rolling_radius * 1e3, "drr_mm": dr * 1e3,
                   "patches": n}
            rows.append(row)
            print(f"{row['shift_mm']:6.1f} {row['yaw_mrad']:6.1f} {row['roll_mrad']:8.4f} "
                  f"{row['contact_roll_mrad']:8.4f} {side:>5} "
                  f"{row['wheel_S_mm']:8.2f} {row['rail_y_mm']:7.2f} "
                  f"{row['contact_angle_deg']:6.2f} {row['rolling_radius_mm']:8.3f} "
                  f"{row['drr_mm']:7.3f} {n:7d}")
    with args.csv.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"written {args.csv}")


if __name__ == "__main__":
    main()
