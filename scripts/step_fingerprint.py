"""Every step's results of bench_step's run, to check that a change keeps them.

``dump OUT.npz`` solves ``--steps`` steps (80) of :mod:`bench_step`'s hunting-like run for
the warm (``previous+estimate``) and cold (``none``) starts and writes, per step, the
wheelset's status and for each wheel its status, normal and tangential iterations, load
passes, forces, moments, area, peak pressure, approach, slip-area ratio, Y/Q and each
patch's normal force, penetration, iterations, pressure sum, creep forces, spin moment and
traction sum. ``--modes`` chooses the starts (e.g. ``estimate``, every step from the
normal estimate alone). ``compare A.npz B.npz`` prints, per start in both, how many values
differ and the largest relative difference (0 for a change that keeps every bit).

Usage: python scripts/step_fingerprint.py dump OUT.npz [--steps 80] [--modes a,b]
       python scripts/step_fingerprint.py compare A.npz B.npz
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import railcontact as rc

MODES = ("previous+estimate", "none")


def fingerprint(mode: str, steps: int) -> np.ndarray:
    """The run's values, one row per step (rows padded with NaN to one length)."""
    import bench_step  # (scripts/ is on the path when this script runs)

    bench_step.clear_caches()
    wc = rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=0.4, element_size=0.5e-3, warm_start=mode))
    w = 2 * math.pi * 1.5
    rows = []
    for k in range(steps):
        t = k * 1e-3
        r = wc.solve(rc.Pose(3e-3 * math.sin(w * t)), loads=(83.3e3, 83.3e3),
                     kinematics=rc.Kinematics(30.0, 3e-3 * w * math.cos(w * t)), time=t)
        row = [r.status]
        for x in r.wheels:
            row += [x.status, x.normal_iterations, x.tangential_iterations, x.load_passes,
                    x.normal_force, *x.creep_force, x.spin_moment, *x.track_force,
                    x.yaw_moment, *x.moment, x.slip_area_ratio, x.area, x.max_pressure,
                    x.approach, x.derailment_quotient]
            for p in x.patches:
                n = p.normal
                row += [n.force, n.penetration, n.iterations, float(n.pressure.sum())]
                if p.tangential is not None:
                    t_ = p.tangential
                    row += [*t_.force, t_.spin_moment, float(np.abs(t_.traction).sum())]
        rows.append(row)
    width = max(len(r) for r in rows)
    return np.array([r + [math.nan] * (width - len(r)) for r in rows], dtype=float)


def compare(a: dict, b: dict) -> None:
    for mode in [m for m in a if m in b]:
        x, y = a[mode], b[mode]
        if x.shape != y.shape:
            print(f"{mode}: different shapes {x.shape} and {y.shape}")
            continue
        same = (x == y) | (np.isnan(x) & np.isnan(y))
        rel = np.where(same, 0.0, np.abs(x - y) / np.maximum(np.abs(x), 1e-300))
        print(f"{mode}: {x.shape[0]} steps, {x.size} values, {int((~same).sum())} differ, "
              f"largest relative difference {float(np.nanmax(rel)):.3g}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    d = sub.add_parser("dump")
    d.add_argument("out", type=Path)
    d.add_argument("--steps", type=int, default=80)
    d.add_argument("--modes", default=",".join(MODES), help="starts, comma-separated")
    c = sub.add_parser("compare")
    c.add_argument("a", type=Path)
    c.add_argument("b", type=Path)
    args = ap.parse_args()
    if args.command == "dump":
        np.savez(args.out, **{m: fingerprint(m, args.steps) for m in args.modes.split(",")})
    else:
        compare(dict(np.load(args.a)), dict(np.load(args.b)))


if __name__ == "__main__":
    main()
