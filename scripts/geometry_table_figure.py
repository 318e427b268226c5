"""A geometry table of S1002 on 60E1 at 1:40 (docs/tables.md, "Geometry tables"): the
rolling radius difference, the contact angles and the wheelset roll against the lateral
displacement, with the kinematic roll (``roll = "rigid"``) and the patches within 0.1 mm
of first contact.

Builds the table with ``railcontact table build``'s machinery (a local Dask cluster),
prints its figures (build rate, delta_r, contact angles and patches at a few
displacements, the flange contact's onset) and the equivalent conicity from the table
against :func:`railcontact.geometry.conicity.equivalent_conicity` from the profiles (which
takes the wheelset at roll 0: a second table at roll 0 gives the like-for-like figure);
``--plot FILE`` draws delta_r, the contact angles and the roll.

Usage: python scripts/geometry_table_figure.py [--out DIR] [--workers N] [--plot FILE]
"""

from __future__ import annotations

import argparse
import math
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from railcontact.contact.wheelrail import build_geometry
from railcontact.geometry.conicity import equivalent_conicity
from railcontact.settings import Case
from railcontact.table import GeometryTable, parse_spec
from railcontact.table.build import build_table

APPROACH = 1e-4
"""[normal] penetration [m]: the patches within 0.1 mm of first contact."""


def spec_dict(roll) -> dict:
    return {"name": "s1002_60e1_geometry",
            "material": {"young": 206e9, "poisson": 0.28},
            "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                         "inclination": math.atan(1 / 40)},
            "normal": {"penetration": APPROACH},
            "table": {"kind": "geometry", "roll": roll,
                      "lateral_displacement": [-0.010, 0.010, 201]}}


def build(roll, out: Path, workers: int) -> tuple[GeometryTable, float]:
    spec = parse_spec(spec_dict(roll))
    t0 = time.perf_counter()
    rep = build_table(spec, out, workers=workers, progress=False)
    seconds = time.perf_counter() - t0
    print(f"table roll = {roll!r}: {rep.points} points x 2 wheels, {rep.not_ok} not ok; "
          f"{seconds:.1f} s with the cluster's start, {rep.rate:.0f} points/s on "
          f"{rep.workers} worker(s)")
    return GeometryTable.open(out), seconds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="folder for the stores (default: a temporary one)")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--plot", help="write the figure to this PNG")
    args = ap.parse_args()
    tmp = Path(args.out or tempfile.mkdtemp(prefix="geometry_table_"))
    tmp.mkdir(parents=True, exist_ok=True)
    for name in ("rigid.zarr", "roll0.zarr"):
        shutil.rmtree(tmp / name, ignore_errors=True)
    rigid, _ = build("rigid", tmp / "rigid.zarr", args.workers)
    flat, _ = build({"values": [0.0]}, tmp / "roll0.zarr", args.workers)
    y = rigid.axes["lateral_displacement"]
    print("\n  y [mm]  delta_r [mm]  gamma_L [deg]  gamma_R [deg]  roll [mrad]  vertical [mm]  "
          "patches L/R")
    for v in (0.0, 0.002, 0.004, 0.0045, 0.005, 0.006, 0.0065, 0.007, 0.008):
        s = rigid(lateral_displacement=v)
        print(f"  {v * 1e3:6.2f}  {s['rolling_radius_difference'] * 1e3:12.4f}  "
              f"{math.degrees(s.wheels['left']['contact_angle']):13.3f}  "
              f"{math.degrees(s.wheels['right']['contact_angle']):13.3f}  "
              f"{s['wheelset_roll'] * 1e3:11.4f}  {s['wheelset_vertical'] * 1e3:13.4f}  "
              f"{s.n_patches['left']}/{s.n_patches['right']}")
    angle = rigid.stored("contact_angle")[:, 0]
    onset = y[(angle > math.radians(45)) & (y > 0)]
    print(f"\nthe left wheel's first contact on the flange (> 45 deg) from y = "
          f"{onset.min() * 1e3:.1f} mm" if onset.size else "\nno flange contact")
    case = {k: v for k, v in spec_dict("rigid").items() if k != "table"}
    track, ws, _ = build_geometry(Case.from_dict(case).geometry)
    print("\n  A [mm]  lambda table (roll 0)  lambda profiles (roll 0)  difference  "
          "lambda table (kinematic roll)")
    for a in (0.002, 0.003, 0.004, 0.006):
        direct = equivalent_conicity(track, ws, a, samples=1601)
        at0 = flat.equivalent_conicity(a, roll=0.0)
        kin = rigid.equivalent_conicity(a)
        print(f"  {a * 1e3:6.1f}  {at0:21.4f}  {direct:24.4f}  {(at0 - direct) / direct:+10.2%}"
              f"  {kin:29.4f}")
    if args.plot:
        plot(rigid, Path(args.plot))
        print(f"\nplot written to {args.plot}")


def plot(table: GeometryTable, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    y = table.axes["lateral_displacement"] * 1e3
    a = {n: table.stored(n) for n in ("rolling_radius_difference", "contact_angle",
                                      "patch_contact_angle", "n_patches", "wheelset_roll")}
    fig, axs = plt.subplots(1, 3, figsize=(12, 3.8))
    axs[0].plot(y, a["rolling_radius_difference"] * 1e3, "-", lw=1.2)
    axs[0].set_ylabel(r"$\Delta r = r_L - r_R$ [mm]")
    for j, (side, c) in enumerate((("left", "C0"), ("right", "C1"))):
        two = a["n_patches"][:, j] >= 2
        axs[1].plot(y, np.degrees(a["contact_angle"][:, j]), "-", color=c, lw=1.2,
                    label=f"{side} wheel, first contact")
        axs[1].plot(y[two], np.degrees(a["patch_contact_angle"][two, j, 1]), "x", color=c,
                    ms=5, label=f"{side} wheel, flange-side patch of two (within 0.1 mm)")
    axs[1].set_ylabel(r"contact angle $\gamma$ [deg]")
    axs[1].set_ylim(0, 100)
    axs[1].legend(fontsize=6.5, loc="upper center")
    axs[2].plot(y, a["wheelset_roll"] * 1e3, "-", lw=1.2)
    axs[2].set_ylabel("wheelset roll [mrad]")
    for ax in axs:
        ax.set_xlabel("lateral displacement y [mm]")
        ax.grid(alpha=0.3)
    fig.suptitle("S1002 on 60E1, 1:40, gauge 1435 mm, back-to-back 1360 mm, r0 = 0.46 m; "
                 "kinematic roll (roll = \"rigid\")", fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    main()
