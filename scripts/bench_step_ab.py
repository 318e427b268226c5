"""Two versions of the wheelset step side by side in one process: the run of bench_step.py,
each step solved by version A and then by version B (the order alternating), so that both
see the same load on a shared machine.

Version B is the ``railcontact`` on the path; version A is a copy of another revision's
package imported under another name::

    mkdir -p /tmp/ab && git archive REV railcontact | tar -x -C /tmp/ab
    mv /tmp/ab/railcontact /tmp/ab/rcbase
    python scripts/bench_step_ab.py /tmp/ab rcbase --mode none --steps 300

(the package's own imports are relative, so the copy runs as ``rcbase``). It prints the
median step time of each version, as a ratio to the fixed workload of bench_step.py (timed
every 50 steps, its median), and the ratio B/A.

``--clock cpu`` times each step by the CPU time of this thread (:func:`time.thread_time`)
instead of the wall time: a step during which another process took the core is not
charged the time it waited (on a shared machine). On a quiet machine the two clocks
scatter alike: B/A of two copies of one revision (A/A) read 0.993-1.007 by wall time and
0.981-1.016 by CPU time over 600 warm steps, three runs each. Read an A/B ratio against
such A/A runs, made alternately with it in separate processes. The workload is timed by
the wall clock either way.
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_step import fixed_workload  # noqa: E402


def hunting_contact(rc, mode: str, frame: str | None = None):
    """The hunting run's wheelset contact (bench_step.py) of package ``rc``."""
    extra = {} if frame is None else {"patch_frame": frame}
    return rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=0.4, element_size=0.5e-3, warm_start=mode, **extra))


def _step(rc, wc, k: int) -> None:
    """One step of the run; a step that is not ok stops the benchmark (a version that
    fails its steps would look faster)."""
    w = 2 * math.pi * 1.5
    t = k * 1e-3
    r = wc.solve(rc.Pose(3e-3 * math.sin(w * t)), loads=(83.3e3, 83.3e3),
                 kinematics=rc.Kinematics(30.0, 3e-3 * w * math.cos(w * t)), time=t)
    if r.status != 0:
        raise SystemExit(f"{rc.__name__}, step {k}: status {int(r.status)}: "
                         f"{[x.message for x in r.wheels]}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("path", help="folder holding version A's package")
    ap.add_argument("name", help="version A's package name (e.g. rcbase)")
    ap.add_argument("--mode", default="none", help="warm_start (none)")
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--patch-frame", default=None, choices=("reference", "rigid"))
    ap.add_argument("--clock", default="wall", choices=("wall", "cpu"),
                    help="time each step by the wall clock or this thread's CPU time")
    args = ap.parse_args()
    sys.path.insert(0, args.path)
    versions = {"A": importlib.import_module(args.name),
                "B": importlib.import_module("railcontact")}
    for rc in versions.values():  # compile the numba kernels outside the measurement
        wc = hunting_contact(rc, args.mode, args.patch_frame)
        for k in range(5):
            _step(rc, wc, k)
    contacts = {n: hunting_contact(rc, args.mode, args.patch_frame) for n, rc in versions.items()}
    times: dict[str, list[float]] = {n: [] for n in versions}
    workloads = []
    order = list(versions)
    clock = time.perf_counter if args.clock == "wall" else time.thread_time
    for k in range(args.steps):
        if k % 50 == 0:
            workloads.append(fixed_workload())
        for n in order if k % 2 == 0 else order[::-1]:
            t0 = clock()
            _step(versions[n], contacts[n], k)
            times[n].append(clock() - t0)
    ref = float(np.median(workloads))
    med = {n: float(np.median(v[1:])) for n, v in times.items()}
    print(f"{args.mode}, {args.steps} steps ({args.clock} time), workload median "
          f"{ref * 1e3:.1f} ms "
          f"(min {min(workloads) * 1e3:.1f})")
    for n in versions:
        print(f"  {n} ({versions[n].__name__}): median {med[n] * 1e3:.2f} ms = "
              f"{med[n] / ref:.3f} of the workload")
    print(f"  B/A {med['B'] / med['A']:.3f}")


if __name__ == "__main__":
    main()
