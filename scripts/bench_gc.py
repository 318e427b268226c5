"""Benchmark of the garbage collector's pauses over a long run of wheelset time steps.

Python frees an object when its last reference goes, except objects in reference cycles,
which wait for the cyclic garbage collector. Its collections run under the GIL (every
thread waits) and a full one traverses every object of the process, tens of thousands
once numba and SciPy are imported: a pause of tens of ms, which a real-time host
cannot take. A step that forms no reference cycles frees what it allocates itself, and
the collector then has nothing to start for.

The hunting-like run of ``scripts/bench_step.py`` (S1002 on 60E1 at 1:40, 0.5 mm elements,
mu = 0.4, 83.3 kN per wheel with the creep forces counted, 30 m/s, kinematic creepages, a
3 mm lateral sine at 1.5 Hz, 1 ms steps), through :class:`railcontact.WheelsetContact`:
``--warmup`` steps first (700: one period of the sine, so that every grid shape's operator
and FFT plan is formed), then ``--steps`` timed steps (6000) during which every
collection is timed (``gc.callbacks``). It prints, per warm start (``--modes``), the
collections of each generation, their total and longest pause, that total's share of the
run's wall time, and the step times' median, 99th percentile and maximum. ``--freeze``
calls ``gc.freeze()`` after the warm-up, as a real-time host may after its set-up: the
objects alive then are never traversed again.

Uses only the public API, so it runs on an older checkout too (``PYTHONPATH=that tree``)
for a before/after comparison.

Usage: python scripts/bench_gc.py [--steps 6000] [--warmup 700]
       [--modes previous+estimate,none] [--freeze]
"""

from __future__ import annotations

import argparse
import gc
import math
import time

import numpy as np

import railcontact as rc

W = 2 * math.pi * 1.5  # [rad/s] the lateral sine's circular frequency


def run(mode: str, warmup: int, steps: int, freeze: bool) -> dict:
    """The run's collections (generation, pause [s]) and step times [s]."""
    contact = rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=0.4, element_size=0.5e-3, warm_start=mode))

    def step(k: int) -> bool:  # whether the step was ok (a failed one costs less)
        t = k * 1e-3
        r = contact.solve(rc.Pose(3e-3 * math.sin(W * t)), loads=(83.3e3, 83.3e3),
                          kinematics=rc.Kinematics(30.0, 3e-3 * W * math.cos(W * t)), time=t)
        return r.status == 0

    for k in range(warmup):
        step(k)
    if freeze:
        gc.collect()
        gc.freeze()
    pauses: list[tuple[int, float]] = []
    started = [0.0]

    def timed(phase: str, info: dict) -> None:
        if phase == "start":
            started[0] = time.perf_counter()
        else:
            pauses.append((info["generation"], time.perf_counter() - started[0]))

    times = np.empty(steps)
    ok = np.empty(steps, dtype=bool)
    gc.callbacks.append(timed)
    try:
        t_run = time.perf_counter()
        for i in range(steps):
            t0 = time.perf_counter()
            ok[i] = step(warmup + i)
            times[i] = time.perf_counter() - t0
        wall = time.perf_counter() - t_run
    finally:
        gc.callbacks.remove(timed)
        if freeze:
            gc.unfreeze()
    return {"pauses": pauses, "times": times, "wall": wall, "not ok": int(np.sum(~ok))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=6000)
    ap.add_argument("--warmup", type=int, default=700)
    ap.add_argument("--modes", default="previous+estimate,none")
    ap.add_argument("--freeze", action="store_true", help="gc.freeze() after the warm-up")
    args = ap.parse_args()
    print(f"{args.steps} steps of 1 ms after {args.warmup}, S1002/60E1, 0.5 mm, 83.3 kN with "
          f"creep, 30 m/s, 3 mm at 1.5 Hz{'; gc.freeze() after the warm-up' * args.freeze}")
    print(f"{'warm start':<18} {'gen 0':>6} {'gen 1':>6} {'gen 2':>6} {'GC [ms]':>8} "
          f"{'longest':>8} {'of wall':>8} {'median':>7} {'p99':>7} {'max':>7}  [ms]")
    for mode in args.modes.split(","):
        r = run(mode, args.warmup, args.steps, args.freeze)
        counts = [sum(1 for g, _ in r["pauses"] if g == k) for k in range(3)]
        total = sum(p for _, p in r["pauses"])
        longest = max((p for _, p in r["pauses"]), default=0.0)
        t = r["times"] * 1e3
        print(f"{mode:<18} {counts[0]:6d} {counts[1]:6d} {counts[2]:6d} {total * 1e3:8.1f} "
              f"{longest * 1e3:8.2f} {total / r['wall']:8.2%} {np.median(t):7.2f} "
              f"{np.percentile(t, 99):7.2f} {t.max():7.2f}")
        if r["not ok"]:
            print(f"  {r['not ok']} of {args.steps} steps not ok (their times included)")


if __name__ == "__main__":
    main()
