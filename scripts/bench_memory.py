"""Resident memory over a long time series with changing grid shapes (bounded over 1e5
steps; flat over 2e4 steps under penetration control).

``WheelsetContact`` under penetration control (S1002 on 60E1 at 1:40, steel, mu 0.4), the
vertical displacement (-0.25 to -0.45 mm) and the lateral displacement (+-4 mm, with the roll at
which both wheels touch) varying at random every step, so that
the patches, their grids, operators and FFT plans change all the time; warm start
``previous+estimate``, creepages of a few 1e-4. It prints the resident set size (RSS,
from /proc) every ``--every`` steps, the number of distinct grid shapes met and the cached
operators and FFT plans, then the growth of RSS over the second half of the run.

Usage: python scripts/bench_memory.py [--steps 100000] [--every 10000]
       [--element-size 1e-3] [--seed 1]
"""

from __future__ import annotations

import argparse
import math
import time
from collections import Counter

import numpy as np

import railcontact as rc
import railcontact.halfspace.operator as operator_module
import railcontact.tangential.rolling as rolling_module
from railcontact.geometry.roll import contact_roll


def rss_mb() -> float:
    """The current resident set size [MB] (Linux)."""
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * 4096 / 2**20


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100_000)
    ap.add_argument("--every", type=int, default=10_000)
    ap.add_argument("--element-size", type=float, default=1e-3)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    wc = rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=0.4, element_size=args.element_size,
                           warm_start="previous+estimate"))
    shapes: set[tuple[int, int]] = set()
    statuses: Counter[rc.Status] = Counter()
    t0 = time.perf_counter()
    marks = []
    print(f"{'step':>8} {'RSS [MB]':>9} {'shapes':>7} {'operators':>9} {'plans':>6} "
          f"{'s':>7}")
    for k in range(1, args.steps + 1):
        lateral = rng.uniform(-4e-3, 4e-3)  # rolled so that both wheels touch
        pose = rc.Pose(lateral, 0.0, contact_roll(wc.track, wc.wheelset, lateral, 0.0))
        # approaches ~0.07-0.35 mm, so the patch sizes vary: wheel loads up to ~560 kN,
        # outside validity above max_wheel_load (400 kN) and solved all the same
        vertical = -rng.uniform(2.5e-4, 4.5e-4)
        creep = tuple(tuple(rng.uniform(-5e-4, 5e-4, 2)) + (0.0,) for _ in range(2))
        r = wc.solve(pose, vertical=vertical, creepages=creep, time=k * 1e-3)
        for w in r.wheels:
            statuses[rc.Status(w.status)] += 1
            shapes.update(p.normal.grid.shape for p in w.patches)
        if k % args.every == 0 or k == args.steps:
            plans = len(getattr(operator_module._local, "plans", {}))
            ops = (operator_module._cached_operator.cache_info().currsize
                   + rolling_module._cached.cache_info().currsize)
            marks.append((k, rss_mb()))
            print(f"{k:8d} {marks[-1][1]:9.1f} {len(shapes):7d} {ops:9d} {plans:6d} "
                  f"{time.perf_counter() - t0:7.0f}", flush=True)
    half = [m for m in marks if m[0] >= args.steps // 2]
    growth = half[-1][1] - half[0][1] if len(half) > 1 else 0.0
    counts = ", ".join(f"{s.label} {n}" for s, n in sorted(statuses.items()))
    print(f"RSS growth over the second half: {growth:+.1f} MB; wheel statuses: {counts}")


if __name__ == "__main__":
    main()
