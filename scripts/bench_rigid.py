"""Cost of the rigid wheelset's vertical displacement and roll under load control.

The FMU reports ``wheelset_vertical_displacement`` and ``wheelset_roll`` every step under
``control = load``; they are found after the step's contact solve by load-controlled normal
solves of both wheels at other rolls (:mod:`railcontact.timestep.rigid`). This times a time
loop (S1002/60E1, 83.3 kN per wheel, creepages (1e-3, 0, 0), 1 ms steps, default warm
start) with the lateral displacement y(t) = amplitude sin(2 pi 1.5 Hz t), and prints per step
the median step time with the rigid wheelset's stage (``rigid_wheelset = "solve"``), the
median time of that stage (the same step without it, ``"skip"``, interleaved, subtracted),
its evaluations, and both as ratios to the fixed numpy workload of ``scripts/bench_step.py``
(measured in the same run: quote the ratios).

Usage: python scripts/bench_rigid.py [--steps 200] [--amplitudes 0.003,0.008]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_step import fixed_workload  # noqa: E402

from railcontact.geometry.profiles import read_profile  # noqa: E402
from railcontact.geometry.track import Pose, Track, Wheelset  # noqa: E402
from railcontact.halfspace.materials import ElasticPair, Material  # noqa: E402
from railcontact.timestep.wheelset import ContactSettings, WheelsetContact  # noqa: E402

Q = 83.3e3


def run(amplitude: float, steps: int) -> dict:
    steel = Material(206e9, 0.28)
    geometry = (Track(read_profile("60E1", "rail"), math.atan(1 / 40)),
                Wheelset(read_profile("S1002", "wheel"), 0.46), ElasticPair.of(steel, steel))
    with_rigid = WheelsetContact(*geometry, ContactSettings(rigid_wheelset="solve"))
    without = WheelsetContact(*geometry, ContactSettings(rigid_wheelset="skip"))
    solve, rigid, evaluations, failed = [], [], [], 0
    for k in range(steps):
        t = k * 1e-3
        pose = Pose(amplitude * math.sin(2 * math.pi * 1.5 * t))
        kw = {"loads": (Q, Q), "creepages": ((1e-3, 0, 0), (1e-3, 0, 0)), "time": t}
        t0 = time.perf_counter()
        r = with_rigid.solve(pose, **kw)
        t1 = time.perf_counter()
        without.solve(pose, **kw)
        t2 = time.perf_counter()
        s = r.rigid_solution
        if k:  # the first step compiles and plans
            solve.append(t1 - t0)
            rigid.append((t1 - t0) - (t2 - t1))
            evaluations.append(s.evaluations)
            failed += not s.converged
    return {"solve": statistics.median(solve), "rigid": statistics.median(rigid),
            "rigid_mean": statistics.fmean(rigid), "evaluations": statistics.fmean(evaluations),
            "failed": failed}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--amplitudes", default="0.003,0.008")
    args = ap.parse_args()
    run(0.0, 3)  # compile
    ref = fixed_workload()
    print(f"fixed workload: {ref * 1e3:.1f} ms")
    print(f"{'amplitude [mm]':>14} {'solve [ms]':>10} {'/ wl':>6} {'rigid [ms]':>10} "
          f"{'/ wl':>6} {'mean [ms]':>9} {'evals':>6} {'not conv.':>9}")
    for a in (float(x) for x in args.amplitudes.split(",")):
        r = run(a, args.steps)
        print(f"{a * 1e3:14.1f} {r['solve'] * 1e3:10.2f} {r['solve'] / ref:6.3f} "
              f"{r['rigid'] * 1e3:10.2f} {r['rigid'] / ref:6.3f} {r['rigid_mean'] * 1e3:9.2f} "
              f"{r['evaluations']:6.2f} {r['failed']:9d}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
