"""Benchmark of a vehicle step: four wheelsets, one after the other, on worker threads or in
worker processes.

Four :class:`railcontact.WheelsetContact` instances (S1002 on 60E1 at 1:40, 0.5 mm
elements, mu = 0.4, load control with the creep forces counted, 30 m/s, kinematic
creepages, 1 ms steps) follow the lateral motion of a hunting two-bogie coach: a sine of
1.5 Hz (a 20 m wavelength at 30 m/s) that reaches each wheelset later by its distance
behind the leading one over the speed (wheelsets at 0, 2.5, 19 and 21.5 m: a bogie
wheelbase of 2.5 m, bogie centres 19 m apart), with amplitudes 3, 2.4, 2 and 1.6 mm, a
yaw of half the kinematic one (``psi = 0.5 dy/dx``, its rate from it) and wheel loads
that shift between the sides by 4 % with the motion (83.3 kN mean). A *vehicle step*
solves all four for one time.

Each repetition runs the same steps from new instances in three ways, the order rotating
(on a shared machine the load of other processes changes over minutes):

* ``sequential``: one worker thread steps the four wheelsets one after the other;
* ``threaded``: ``--threads`` worker threads (2), wheelset ``i`` on thread ``i mod N``,
  all started on a step at once and waited for (as a co-simulation host steps its
  wheelsets);
* ``processes``: a :class:`railcontact.WheelsetPool` of ``--processes`` worker processes
  (2), wheelset ``i`` in process ``i mod N``, one round trip per process and step; each
  worker sends back the step's fingerprint (below), not the whole result;
* ``host+workers``: a pool of ``--processes`` processes of which this one is the first
  (``WheelsetPool(here=True)``, the multi-wheelset FMU's default): it steps its share of
  the wheelsets while ``--processes - 1`` workers step theirs.

The worker threads and processes live for the whole run and are warmed up first (numba
kernels, each thread's and process's FFTW plans; a pool's wheelsets are built anew for
each run, :meth:`~railcontact.WheelsetPool.reset`). For the warm (``previous+estimate``)
and cold (``none``) starts it
prints, per way, the wall time of a vehicle step (median, mean, 99th percentile over the
steps of every repetition, each run's first step left out), each as a ratio to the fixed
numpy workload of ``scripts/bench_step.py`` (timed before every repetition, its median),
the real-time factor at 1 kHz (the median vehicle step over the 1 ms it simulates: below
1 is faster than real time), the CPU time over the wall time (this process's, and for the
processes way its worker processes' as well: below 1 other processes take the core; the
threaded and processes ways reach 2 only with two cores free), and the ratios threaded /
sequential and processes / sequential of the medians. It checks that the threaded and
processes results equal the sequential ones bit for bit (forces, moments, iterations,
pressures, tractions). For the processes way it prints the wheelsets' solve time in the
workers and the wall time of a step beyond the busiest worker's solves (the pool's cost:
sending, waking, pickling).

Goal (issue: a vehicle in real time): a warm vehicle step <= 0.03 of the workload.

Usage: python scripts/bench_vehicle.py [--steps 150] [--cold-steps 30] [--repeats 3]
                                       [--threads 2] [--processes 2]
                                       [--modes previous+estimate,none]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

import railcontact as rc

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_step import fixed_workload  # noqa: E402
from bench_threads import Worker, fingerprint  # noqa: E402

SPEED = 30.0
"""Forward speed [m/s]."""
FREQUENCY = 1.5
"""Hunting frequency [Hz]."""
POSITIONS = (0.0, 2.5, 19.0, 21.5)
"""Distance of each wheelset behind the leading one [m]."""
AMPLITUDES = (3e-3, 2.4e-3, 2e-3, 1.6e-3)
"""Lateral amplitude of each wheelset [m]."""
LOAD = 83.3e3
"""Mean wheel load [N]."""
LOAD_SHIFT = 0.04
"""Share of the wheel load that moves between the sides with the lateral motion."""
YAW_SHARE = 0.5
"""Yaw as this share of the kinematic yaw dy/dx."""


def description(mode: str) -> rc.WheelsetDescription:
    """A new wheelset's description (its own track, profiles and settings, as FMU instances
    have)."""
    return rc.WheelsetDescription(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=0.4, element_size=0.5e-3, warm_start=mode))


def wheelset(mode: str) -> rc.WheelsetContact:
    """A new wheelset."""
    return description(mode).build()


def inputs(i: int, k: int, step: float = 1e-3) -> dict:
    """The keyword arguments of :meth:`WheelsetContact.solve` for wheelset ``i`` at step
    ``k``."""
    t = k * step
    w = 2 * math.pi * FREQUENCY
    a = AMPLITUDES[i]
    phase = w * (t - POSITIONS[i] / SPEED)
    y, y_dot = a * math.sin(phase), a * w * math.cos(phase)
    psi = YAW_SHARE * y_dot / SPEED  # (dy/dx = y_dot / V)
    psi_dot = -YAW_SHARE * a * w * w * math.sin(phase) / SPEED
    shift = LOAD_SHIFT * LOAD * math.sin(phase)
    return dict(pose=rc.Pose(y, psi), loads=(LOAD + shift, LOAD - shift),
                kinematics=rc.Kinematics(SPEED, y_dot, psi_dot), time=t)


def _stepper(contacts: list, which: list[int], k: int):
    """A job: step the wheelsets ``which`` of ``contacts`` at step ``k``."""
    def job():
        return [(i, fingerprint(contacts[i].solve(**inputs(i, k)))) for i in which]
    return job


def run(workers: list[Worker], mode: str, steps: int) -> tuple[list[float], float, list]:
    """The vehicle's ``steps`` steps from new wheelsets, wheelset ``i`` on worker ``i mod
    len(workers)``; the wall time of each vehicle step [s], the process CPU time over the
    wall time of the run, and each step's fingerprints (wheelset order)."""
    contacts = [wheelset(mode) for _ in POSITIONS]
    n = len(workers)
    share = [[i for i in range(len(POSITIONS)) if i % n == j] for j in range(n)]
    times, results = [], []
    c0, t_run = time.process_time(), time.perf_counter()
    for k in range(steps):
        t0 = time.perf_counter()
        for worker, which in zip(workers, share, strict=True):
            worker.submit(_stepper(contacts, which, k))
        out = [x for worker in workers for x in worker.result()]
        times.append(time.perf_counter() - t0)
        results.append(tuple(f for _, f in sorted(out, key=lambda x: x[0])))
    cpu = (time.process_time() - c0) / (time.perf_counter() - t_run)
    return times, cpu, results


def cpu_seconds(pids: list[int]) -> float:
    """User + system CPU time of the processes ``pids`` [s] (NaN where it cannot be read)."""
    try:
        import psutil
    except ImportError:
        return math.nan
    return sum(sum(psutil.Process(pid).cpu_times()[:2]) for pid in pids)


def run_pool(pool: rc.WheelsetPool, steps: int, split: dict | None = None
             ) -> tuple[list[float], float, list]:
    """As :func:`run` with the wheelsets in ``pool``'s worker processes (built anew); the CPU
    time counts this process's and the workers'. ``split``: per step (the first left out)
    appends to ``"solves"`` the sum of the wheelsets' solve times in their workers [s] and
    to ``"overhead"`` the step's wall time beyond its busiest worker's solves [s] (sending,
    waking, pickling, reading)."""
    pool.reset()
    pids = [p.pid for p in pool._processes]
    times, results = [], []
    c0, w0, t_run = time.process_time(), cpu_seconds(pids), time.perf_counter()
    for k in range(steps):
        t0 = time.perf_counter()
        out = pool.step([inputs(i, k) for i in range(len(POSITIONS))])
        times.append(time.perf_counter() - t0)
        results.append(tuple(out))
        if split is not None and k > 0:
            split["solves"].append(sum(pool.seconds))
            split["overhead"].append(times[-1] - max(sum(pool.seconds[i] for i in which)
                                                     for which in pool.shares))
    wall = time.perf_counter() - t_run
    cpu = (time.process_time() - c0 + cpu_seconds(pids) - w0) / wall
    return times, cpu, results


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=150, help="vehicle steps of a warm run")
    ap.add_argument("--cold-steps", type=int, default=30, help="vehicle steps of a cold run")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--modes", default="previous+estimate,none")
    args = ap.parse_args()
    modes = args.modes.split(",")
    workers = [Worker(f"wheelsets-{j}") for j in range(max(args.threads, 1))]
    pools = {mode: rc.WheelsetPool([description(mode) for _ in POSITIONS], args.processes,
                                   reduce=fingerprint) for mode in modes}
    hosts = {mode: rc.WheelsetPool([description(mode) for _ in POSITIONS], args.processes,
                                   reduce=fingerprint, here=True) for mode in modes}
    ways = {"sequential": workers[:1], "threaded": workers, "processes": None,
            "host+workers": None}
    try:
        for mode in modes:  # numba kernels, each worker thread's and process's FFTW plans
            for j in range(len(workers)):
                run(workers[j:j + 1], mode, 5)
            run_pool(pools[mode], 5)
            run_pool(hosts[mode], 5)
        print(f"{os.cpu_count()} cores; four wheelsets (at {', '.join(f'{x:g}' for x in POSITIONS)}"
              f" m), {args.threads} worker threads in the threaded way, "
              f"{pools[modes[0]].processes} worker processes in the processes way, this "
              f"process and {hosts[modes[0]].processes - 1} worker(s) in the host+workers "
              "way")
        for mode in modes:
            steps = args.steps if mode != "none" else args.cold_steps
            times = {w: [] for w in ways}
            medians = {w: [] for w in ways}
            cpu = {w: [] for w in ways}
            workloads = []
            split: dict[str, list[float]] = {"solves": [], "overhead": []}
            reference = None
            for r in range(args.repeats):
                workloads.append(fixed_workload())
                order = list(ways)
                for way in order[r % len(order):] + order[:r % len(order)]:
                    if way == "processes":
                        t, c, results = run_pool(pools[mode], steps, split)
                    elif way == "host+workers":
                        t, c, results = run_pool(hosts[mode], steps)
                    else:
                        t, c, results = run(ways[way], mode, steps)
                    if reference is None:
                        bad = sum(w[0] != 0 for step in results for fp in step for w in fp)
                        if bad:  # (a failed step is a cheap one: not a vehicle step's time)
                            raise SystemExit(f"{mode}: {bad} wheel steps are not ok")
                        reference = results
                    elif results != reference:
                        raise SystemExit(f"{mode}, repeat {r}: the {way} results differ "
                                         "from the first run's")
                    times[way] += t[1:]
                    medians[way].append(float(np.median(t[1:])))
                    cpu[way].append(c)
            ref = float(np.median(workloads))
            print(f"\n{mode}: {args.repeats} repeats of {steps} vehicle steps of 1 ms, "
                  f"workload median {ref * 1e3:.1f} ms (min {min(workloads) * 1e3:.1f})")
            print(f"{'way':<12} {'median [ms]':>11} {'/ workload':>10} {'mean [ms]':>9} "
                  f"{'/ workload':>10} {'p99 [ms]':>8} {'/ workload':>10} {'RTF 1 kHz':>9} "
                  f"{'CPU/wall':>8}")
            for way in ways:
                x = np.array(times[way])
                med, mean, p99 = float(np.median(x)), float(x.mean()), \
                    float(np.percentile(x, 99))
                print(f"{way:<12} {med * 1e3:11.2f} {med / ref:10.4f} {mean * 1e3:9.2f} "
                      f"{mean / ref:10.4f} {p99 * 1e3:8.2f} {p99 / ref:10.4f} "
                      f"{med / 1e-3:9.2f} {float(np.median(cpu[way])):8.2f}")
            for way in ("threaded", "processes", "host+workers"):
                ratios = np.array(medians[way]) / np.array(medians["sequential"])
                print(f"ratio {way} / sequential: "
                      f"{np.median(times[way]) / np.median(times['sequential']):.3f} "
                      f"(of the medians); per repeat {', '.join(f'{q:.3f}' for q in ratios)}")
            solves = np.median(split["solves"])
            print(f"processes: the wheelsets' solves in the workers {solves * 1e3:.2f}"
                  f" ms per vehicle step (sum, median); wall time beyond the busiest worker's "
                  f"solves {np.median(split['overhead']) * 1e3:.2f} ms (median)")
            print("threaded, processes and host+workers results equal the sequential ones "
                  "bit for bit")
    finally:
        for worker in workers:
            worker.stop()
        for pool in (*pools.values(), *hosts.values()):
            pool.close()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan
    print(f"\nload average (1 min) at the end: {load:.1f}")


if __name__ == "__main__":
    main()
