"""Manchester contact benchmark, case A-2.2 (S1002 / UIC60 at 1:40, 10 kN per wheel).

Lateral shift 0 .. 10 mm with yaw 2.4 y mrad (y in mm), the benchmark's profile files
(``../shared/profiles``; the rail file is canted already, so inclination 0), gauge 1435 mm,
flange-back distance 1360 mm, r0 = 460 mm. Prints, per shift and wheel, the contact point
on the wheel (profile coordinate S) and on the rail (rail profile y), the contact angle,
the rolling radius, the rolling-radius difference and the number of patches under 10 kN
(load control with the BEM), and writes a CSV.

Conventions: lateral shift positive to the left (the left wheel moves towards flange
contact); profile coordinates positive to the field side; contact angles positive towards
the flange. The benchmark solves the roll for equal wheel loads; here the wheelset is not
rolled (roll = 0) and each wheel carries 10 kN.

Usage: python scripts/manchester_a22.py [--profiles DIR] [--csv FILE]
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import railcontact as rc

HERE = Path(__file__).resolve().parent


def case_for(shift: float, profiles: Path) -> dict:
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
        },
        "grid": {"nx": 48, "ny": 48},
        "normal": {"load": 10e3, "tolerance": 1e-4, "estimate": "hertz"},
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--profiles", type=Path, default=HERE.parents[1] / "shared" / "profiles")
    ap.add_argument("--csv", type=Path, default=Path("manchester_a22.csv"))
    args = ap.parse_args()
    rows = []
    hdr = (f"{'shift':>6} {'yaw':>6} {'side':>5} {'S_wheel':>8} {'y_rail':>7} {'angle':>6} "
           f"{'r':>8} {'dr':>7} {'patches':>7}")
    print(hdr)
    print(f"{'mm':>6} {'mrad':>6} {'':>5} {'mm':>8} {'mm':>7} {'deg':>6} {'mm':>8} {'mm':>7}")
    for k in range(11):
        shift = k * 1e-3
        case = case_for(shift, args.profiles)
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
                   "side": side, "wheel_S_mm": g.wheel_s * 1e3, "rail_y_mm": g.rail_y * 1e3,
                   "contact_angle_deg": math.degrees(g.contact_angle),
                   "rolling_radius_mm": g.rolling_radius * 1e3, "drr_mm": dr * 1e3,
                   "patches": n}
            rows.append(row)
            print(f"{row['shift_mm']:6.1f} {row['yaw_mrad']:6.1f} {side:>5} "
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
