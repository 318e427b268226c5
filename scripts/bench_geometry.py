"""Benchmark of a wheel pass's contact geometry: what one warm load pass of a wheelset time
step forms, timed part by part over poses with yaw and roll.

Per pose and wheel each part is timed 5 times and the least time kept (warm caches; the
least of repeats filters other processes on a shared machine): the trace and vertical gap,
the contact search (``contact_points``, its first point of contact), the frame at CONTACT's
reference point (``at_reference``), the patch count, Hertz's solution, the lateral extent
and the gap on a grid; and Hertz's axis ratio for new ratios (not remembered). Run it with
another checkout's ``PYTHONPATH`` to compare versions (`docs/performance.md`).

    python scripts/bench_geometry.py [--poses 300]
"""

from __future__ import annotations

import argparse
import importlib
import math
import time

import numpy as np

import railcontact as rc
from railcontact.geometry import search
from railcontact.halfspace.grid import Grid

hertz_module = importlib.import_module("railcontact.halfspace.hertz")


def least(fn, before=None, repeats: int = 5):
    """The least wall time [s] of ``repeats`` calls of ``fn`` and its last result."""
    best, out = math.inf, None
    for _ in range(repeats):
        if before is not None:
            before()
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def forget() -> None:
    """Clear the search's memory of the last pose (every pass of a new step misses it)."""
    if hasattr(search, "forget"):
        search.forget(traces=False)
    else:  # an older package (its memory a module global)
        search._LAST_POINTS[0] = None


APPROACH = 8e-5
"""Vertical approach [m] at which the frame at the reference point is formed."""


def wheel(track, ws, pair, pose, side, grid) -> dict[str, float]:
    """The least times [s] of each part for one wheel at one pose."""
    t = {"trace": least(lambda: search.vertical_gap(track, ws, pose, side))[0]}
    t["contact_points"], cps = least(
        lambda: search.contact_points(track, ws, pose, side, 0.0), forget)
    first = cps[0]
    t["at_reference"], ref = least(
        lambda: search.at_reference(first, track, ws, pose, APPROACH))
    cp = ref or first
    t["count_contacts"] = least(
        lambda: search.count_contacts(track, ws, pose, side, APPROACH))[0]
    t["hertz"] = least(lambda: rc.hertz(cp.A, cp.B, pair, load=83.3e3))[0]
    fresh = [cp]  # the gap on a grid of a frame just formed, as a time step reads it

    def form() -> None:
        fresh[0] = search.at_reference(first, track, ws, pose, APPROACH) or first

    t["gap_on_grid"] = least(lambda: fresh[0].gap_on_grid(grid), form)[0]
    t["lateral_extent"] = least(lambda: cp.lateral_extent(APPROACH, 1.2))[0]
    return t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=300)
    args = ap.parse_args()
    track = rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40))
    ws = rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46)
    pair = rc.ElasticPair.of(rc.STEEL, rc.STEEL)
    rng = np.random.default_rng(2)
    n = args.poses
    poses = [rc.Pose(float(y), float(p), float(f)) for y, p, f in zip(
        rng.uniform(-4e-3, 4e-3, n), rng.uniform(-2e-3, 2e-3, n), rng.uniform(-1e-3, 1e-3, n),
        strict=True)]
    grid = Grid.from_bounds(-5e-3, 5e-3, -6e-3, 6e-3, 20, 24)
    parts = ["trace", "contact_points", "at_reference", "count_contacts", "hertz",
             "lateral_extent", "gap_on_grid"]
    for _ in range(2):  # the first round compiles and warms up
        t = dict.fromkeys(parts, 0.0)
        for pose in poses:
            for side in ("left", "right"):
                for k, v in wheel(track, ws, pair, pose, side, grid).items():
                    t[k] += v
    us = {k: v / (2 * n) * 1e6 for k, v in t.items()}
    ratios = 1.0 + rng.uniform(0.5, 20.0, 400)
    solve = getattr(hertz_module._axis_ratio, "__wrapped__", hertz_module.axis_ratio)
    axis = sum(least(lambda r=r: solve(float(r)))[0] for r in ratios) / ratios.size * 1e6
    print(f"{2 * n} wheels ({n} poses with yaw and roll), least of 5 repeats, us per call:")
    for k in parts:
        print(f"  {k:16s} {us[k]:8.1f}")
    print(f"  {'axis ratio':16s} {axis:8.1f}   (Hertz, a new curvature ratio)")
    search_and_gap = (us["contact_points"] + us["count_contacts"] + us["lateral_extent"]
                      + us["gap_on_grid"])
    print(f"contact search and gap evaluation: {search_and_gap:.1f} us a wheel")
    print(f"a warm pass's geometry (with the reference frame and Hertz, a new ratio): "
          f"{search_and_gap + us['at_reference'] + us['hertz'] + axis:.1f} us a wheel")


if __name__ == "__main__":
    main()
