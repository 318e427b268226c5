"""Wheel–rail geometry figures: profiles with contact points, rolling-radius difference and
contact angle against lateral displacement, and the contact patches at one displacement.

S1002 on 60E1 at 1:40 by default. Writes ``geometry_profiles.png``, ``geometry_sweep.png``
(+ ``geometry_sweep.csv``) and ``geometry_patches.png`` to ``--out``.

Usage: python scripts/geometry_plots.py [--wheel S1002] [--rail 60E1] [--dy 0.00778]
       [--out out/]
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import railcontact as rc  # noqa: E402
from railcontact.geometry.profiles import read_profile  # noqa: E402
from railcontact.geometry.search import contact_points  # noqa: E402
from railcontact.geometry.track import SIDES, Pose, Track, Wheelset  # noqa: E402

MM = 1e3


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--wheel", default="S1002")
    ap.add_argument("--rail", default="60E1")
    ap.add_argument("--inclination", type=float, default=math.atan(1 / 40))
    ap.add_argument("--dy", type=float, default=0.00778, help="displacement for the patches [m]")
    ap.add_argument("--load", type=float, default=83.3e3, help="vertical wheel load [N]")
    ap.add_argument("--out", type=Path, default=Path("out"))
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    track = Track(read_profile(args.rail, "rail"), args.inclination)
    ws = Wheelset(read_profile(args.wheel, "wheel"))

    # 1. profiles with contact points, at three displacements
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), constrained_layout=True)
    rail = track.side_rail
    for ax, side in zip(axes, ("right", "left"), strict=True):
        sgn = SIDES[side]
        ax.plot(sgn * rail.y * MM, rail.z * MM, "k", lw=1.5, label=f"rail {args.rail}")
        for dy, col in ((-0.004, "tab:blue"), (0.0, "tab:green"), (args.dy, "tab:red")):
            pose = Pose(lateral=dy)
            cps = contact_points(track, ws, pose, side, 0.0)
            # the wheel lowered into contact, drawn along its trace
            from railcontact.geometry.search import vertical_gap

            _, _, u, z, g = vertical_gap(track, ws, pose, side)
            ax.plot(sgn * u * MM, (z - g.min()) * MM, color=col, lw=1,
                    label=f"wheel, y = {dy * MM:+.2f} mm")
            for c in cps:
                ax.plot(c.position[1] * MM, c.position[2] * MM, "o", color=col)
        ax.set_xlabel("Y (track, positive to the left) [mm]")
        ax.set_ylabel("Z [mm]")
        ax.set_title(f"{side} wheel / rail")
        ax.set_ylim(-40, 20)
        ax.set_aspect("equal")
        ax.legend(fontsize=7)
    fig.savefig(args.out / "geometry_profiles.png", dpi=120)
    plt.close(fig)

    # 2. rolling-radius difference and contact angles against lateral displacement
    rows = []
    for dy in np.round(np.arange(-8.0, 8.0001, 0.1), 6) * 1e-3:
        pose = Pose(lateral=dy)
        left = contact_points(track, ws, pose, "left")[0]
        right = contact_points(track, ws, pose, "right")[0]
        rows.append({"dy_mm": dy * MM,
                     "drr_mm": (left.rolling_radius - right.rolling_radius) * MM,
                     "angle_left_deg": math.degrees(left.contact_angle),
                     "angle_right_deg": math.degrees(right.contact_angle)})
    with (args.out / "geometry_sweep.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    d = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4), constrained_layout=True)
    a1.plot(d["dy_mm"], d["drr_mm"])
    a1.set_xlabel("lateral displacement [mm]")
    a1.set_ylabel(r"$r_{left} - r_{right}$ [mm]")
    a1.grid(alpha=0.3)
    a2.plot(d["dy_mm"], d["angle_left_deg"], label="left")
    a2.plot(d["dy_mm"], d["angle_right_deg"], label="right")
    a2.set_xlabel("lateral displacement [mm]")
    a2.set_ylabel("contact angle [deg]")
    a2.legend()
    a2.grid(alpha=0.3)
    fig.suptitle(f"{args.wheel} on {args.rail}, inclination {args.inclination:.4f} rad")
    fig.savefig(args.out / "geometry_sweep.png", dpi=120)
    plt.close(fig)

    # 3. contact patches at one displacement (BEM, load control)
    case = {"material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "wheel-rail", "wheel": args.wheel, "rail": args.rail,
                         "inclination": args.inclination, "lateral_displacement": args.dy,
                         "side": "both"},
            "grid": {"nx": 64, "ny": 64},
            "normal": {"load": args.load, "estimate": "hertz"}}
    sol = rc.solve(case)
    fig, axes = plt.subplots(1, len(sol.patches), figsize=(5 * len(sol.patches), 4.5),
                             constrained_layout=True, squeeze=False)
    for ax, p in zip(axes[0], sol.patches, strict=True):
        g = p.normal.grid
        xmin, xmax, ymin, ymax = g.bounds
        im = ax.pcolormesh(np.linspace(xmin, xmax, g.nx + 1) * MM,
                           np.linspace(ymin, ymax, g.ny + 1) * MM,
                           np.ma.masked_where(~p.normal.contact, p.normal.pressure).T * 1e-6)
        fig.colorbar(im, ax=ax, label="pressure [MPa]")
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("s (to the field side) [mm]")
        ax.set_title(f"{p.geometry.side}: angle {math.degrees(p.geometry.contact_angle):.1f} "
                     f"deg, N = {p.normal.force / 1e3:.1f} kN", fontsize=9)
    fig.suptitle(f"contact patches at y = {args.dy * MM:+.2f} mm, {args.load / 1e3:.1f} kN")
    fig.savefig(args.out / "geometry_patches.png", dpi=120)
    plt.close(fig)
    for name in ("geometry_profiles.png", "geometry_sweep.png", "geometry_sweep.csv",
                 "geometry_patches.png"):
        print(args.out / name)


if __name__ == "__main__":
    main()
