"""Benchmark of the FMU: per-step wall time and iterations for each warm_start mode.

The FMU is built into a temporary folder and driven through fmpy (FMU2Slave) over
``--duration`` seconds (default 2 s) of sinusoidal wheelset motion at 1 kHz communication
steps: lateral displacement 4 mm sin(2 pi 1.5 Hz t), yaw 1 mrad cos(2 pi 1.5 Hz t), forward
speed 30 m/s, kinematic creepages (lateral velocity and yaw rate from the motion), wheel
loads 83.3 kN, S1002 on 60E1 at 1:40, element size 0.5 mm. For warm_start = none /
estimate (INFCON + FaStrip) / previous / previous+estimate it prints the median and mean
wall time per step (the median also as a ratio to the fixed numpy workload of
``scripts/bench_step.py``, measured before and after the runs: quote the ratios), the mean
normal and tangential iterations per step (both wheels) and their ratio to the cold start.
The first step (always cold) is left out of the means.

Then a bare C host (tests/fmu/host.c) measures the shim's own overhead: set + get of the
Real variables (no Python involved) and a Python round trip through the shim (a
fmi2GetString call: taking the GIL, calling the slave, returning), against a whole
set + doStep + get.

Under ``control = penetration`` (``--part penetration``; the host gives the vertical
displacement and roll, as a multibody code does) it compares the FMU's step with the
in-process step it wraps: the same wheelset motion (lateral 3 mm sine at 1.5 Hz, kinematic
creepages at 30 m/s, warm starts), its vertical displacement and roll those of a
load-controlled run (83.3 kN a wheel, the rigid wheelset solved, computed first), stepped
by :meth:`railcontact.WheelsetContact.solve` in this process and by the FMU through fmpy
(set the inputs, doStep, get the forces and moments), the two alternating step by step (so
that both meet the machine's load alike) over ``--repeats`` runs; it prints the median
per-step times, their ratio (FMU / in-process; the goal is at most 1.2) and the median of
the per-step ratios.

``--part wheelsets`` builds the FMU of ``--wheelsets`` N wheelsets and steps it, under
``control = penetration``, with its wheelsets in worker processes and on threads
(``--workers``; ``RAILCONTACT_FMU_WORKERS`` of each instance), against N one-wheelset FMU
instances stepped one after the other with the same inputs (N lateral sines of different
amplitude and phase), the three stepped alternately step by step (each first in turn):
the median time of the N-wheelset step each way, of the N single steps together, their
ratios (the parallel ratio: 1 no gain, 1/N perfectly parallel; processes / threads), and
whether every wheelset's outputs equal its single instance's bit for bit. Before and after,
two processes of pure Python work at once against one after the other say how many cores
were free for the job (0.5: two; 1: one, the other taken by other jobs).

Usage: python scripts/bench_fmu.py [--part all|modes|penetration|wheelsets]
                                   [--duration 2.0] [--csv FILE] [--steps 400]
                                   [--repeats 3] [--wheelsets 4]
                                   [--workers both|processes|threads]
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_step import fixed_workload  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MODES = ("none", "estimate", "previous", "previous+estimate")


def run_mode(fmu_dir: Path, md, mode: str, duration: float, step: float) -> dict:
    from fmpy.fmi2 import FMU2Slave

    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=str(fmu_dir),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName=mode)
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.setString([vr["warm_start"], vr["creepage_input"]], [mode, "kinematic"])
    s.exitInitializationMode()
    w = 2 * math.pi * 1.5
    ins = [vr[n] for n in ("lateral_displacement", "yaw", "lateral_velocity", "yaw_rate",
                           "speed")]
    its = [vr["normal_iterations"], vr["tangential_iterations"]]
    outs = [vr["force_lateral"], vr["yaw_moment"], vr["solve_time"]]
    rows = []
    n = int(round(duration / step))
    for k in range(n):
        t = k * step
        u = [4e-3 * math.sin(w * t), 1e-3 * math.cos(w * t), 4e-3 * w * math.cos(w * t),
             -1e-3 * w * math.sin(w * t), 30.0]
        t0 = time.perf_counter()
        s.setReal(ins, u)
        s.doStep(t, step)
        ni, nt = s.getInteger(its)
        fy, mz, solve = s.getReal(outs)
        rows.append((t, time.perf_counter() - t0, ni, nt, fy, mz, solve))
        if k % 100 == 0:
            print(f"\r  {mode:18s} {k:5d}/{n}", end="", file=sys.stderr, flush=True)
    print("\r", end="", file=sys.stderr)
    s.terminate()
    s.freeInstance()
    a = np.array(rows[1:])
    return {"mode": mode, "rows": rows, "median_ms": 1e3 * float(np.median(a[:, 1])),
            "mean_ms": 1e3 * float(a[:, 1].mean()), "normal": float(a[:, 2].mean()),
            "tangential": float(a[:, 3].mean()), "max_normal": int(a[:, 2].max()),
            "max_tangential": int(a[:, 3].max())}


def shim_overhead(fmu_dir: Path, md) -> str:
    import fmpy

    vr = {v.name: v.valueReference for v in md.modelVariables}
    with tempfile.TemporaryDirectory() as tmp:
        host = Path(tmp) / "host"
        subprocess.run(["gcc", "-O2", f"-I{Path(fmpy.__file__).parent / 'c-code'}",
                        str(ROOT / "tests" / "fmu" / "host.c"), "-o", str(host), "-ldl",
                        "-lm"], check=True)
        r = subprocess.run(
            ["env", "-i", "PATH=/usr/bin:/bin", f"VR_LAT={vr['lateral_displacement']}",
             f"VR_OUT={vr['normal_force_left']}", str(host),
             str(fmu_dir / "binaries" / "linux64" / "RailContact.so"),
             (fmu_dir / "resources").as_uri(), md.guid, "50", "1", "bench"],
            capture_output=True, text=True, timeout=600)
    return (r.stdout + r.stderr[-500:]).strip()


PENETRATION_OUTPUTS = ("force_longitudinal", "force_lateral", "force_vertical", "yaw_moment",
                       "roll_moment", "pitch_moment", "force_vertical_left",
                       "force_vertical_right")
"""What the host reads after each step of the penetration-control runs."""


def _motion(steps: int, amplitude: float = 3e-3, phase: float = 0.0,
            step: float = 1e-3) -> list[dict]:
    """Per step the kinematic inputs of a lateral sine at 1.5 Hz (30 m/s) and the vertical
    displacement and roll at which a rigid wheelset carries 83.3 kN a wheel there (a
    load-controlled in-process run, the rigid wheelset solved)."""
    import railcontact as rc

    wc = _contact("solve")
    w = 2 * math.pi * 1.5
    out = []
    for k in range(steps):
        t = k * step
        y, v = amplitude * math.sin(w * t + phase), amplitude * w * math.cos(w * t + phase)
        r = wc.solve(rc.Pose(y), loads=(83.3e3, 83.3e3), kinematics=rc.Kinematics(30.0, v),
                     time=t)
        out.append({"time": t, "lateral_displacement": y, "lateral_velocity": v,
                    "speed": 30.0, "vertical_displacement": r.vertical, "roll": r.roll})
    return out


def _contact(rigid: str = "skip"):
    """The in-process wheelset with the FMU's default parameters."""
    import railcontact as rc

    mat = rc.Material(206e9, 0.28)
    return rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40), 1.435),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46, 1.360), rc.ElasticPair.of(mat, mat),
        rc.ContactSettings(friction=0.4, warm_start="previous+estimate", rigid_wheelset=rigid))


def _in_process_step(wc, m: dict) -> float:
    """Wall time [s] of the in-process step of motion ``m`` under penetration control."""
    import railcontact as rc

    t0 = time.perf_counter()
    r = wc.solve(rc.Pose(m["lateral_displacement"], 0.0, m["roll"]),
                 vertical=m["vertical_displacement"],
                 kinematics=rc.Kinematics(m["speed"], m["lateral_velocity"]), time=m["time"])
    _read = (r.force, r.moment, r.yaw_moment, r.left.track_force, r.right.track_force)
    return time.perf_counter() - t0


INPUT_NAMES = ("lateral_displacement", "lateral_velocity", "speed", "vertical_displacement",
               "roll")


class _Instance:
    """An FMU instance through fmpy under control = penetration, kinematic creepages."""

    def __init__(self, fmu_dir: Path, md, name: str, wheelsets: int | None = None) -> None:
        from fmpy.fmi2 import FMU2Slave

        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.s = FMU2Slave(guid=md.guid, unzipDirectory=str(fmu_dir),
                           modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.s.instantiate()
        self.s.setupExperiment(startTime=0.0)
        self.s.enterInitializationMode()
        self.s.setString([self.vr["control"], self.vr["creepage_input"]],
                         ["penetration", "kinematic"])
        self.s.exitInitializationMode()
        suffixes = [""] if wheelsets is None else [f"_{k}" for k in range(1, wheelsets + 1)]
        self.ins = [self.vr[n + x] for x in suffixes for n in INPUT_NAMES]
        self.outs = [self.vr[n + x] for x in suffixes for n in PENETRATION_OUTPUTS]
        self.all_outs = [[v.valueReference for v in md.modelVariables
                          if v.causality == "output" and v.type == "Real"
                          and v.name.endswith(x) and not v.name.startswith("solve_time")]
                         for x in suffixes]

    def step(self, motions: list[dict]) -> tuple[float, list[float]]:
        """Set the inputs (one motion per wheelset), doStep, get the outputs: the wall time
        [s] and the outputs read."""
        t0 = time.perf_counter()
        self.s.setReal(self.ins, [m[n] for m in motions for n in INPUT_NAMES])
        self.s.doStep(motions[0]["time"], 1e-3)
        out = self.s.getReal(self.outs)
        return time.perf_counter() - t0, out

    def free(self) -> None:
        self.s.terminate()
        self.s.freeInstance()


def _unpacked(fmu: Path, where: Path):
    from fmpy.model_description import read_model_description

    with zipfile.ZipFile(fmu) as z:
        z.extractall(where)
    return where, read_model_description(str(fmu))


def penetration_ratio(fmu_dir: Path, md, steps: int, repeats: int) -> dict:
    """Median per-step wall times [s] of the in-process step and of the FMU's under
    penetration control over the same motion, the two stepped alternately (step k
    in-process, then step k through the FMU: both see the machine's load alike), over
    ``repeats`` runs from new instances; and the median of the per-step ratios."""
    motion = _motion(steps)
    api, fmu = [], []
    for k in range(repeats):
        wc = _contact()
        inst = _Instance(fmu_dir, md, f"penetration{k}")
        for i, m in enumerate(motion):
            a, f = _in_process_step(wc, m), inst.step([m])[0]
            if i:  # (the first step is cold)
                api.append(a)
                fmu.append(f)
        inst.free()
    return {"api": float(np.median(api)), "fmu": float(np.median(fmu)), "steps": len(api),
            "paired": float(np.median(np.array(fmu) / np.array(api)))}


def _burn(n: int) -> float:
    """Wall time [s] of ``n`` rounds of pure Python arithmetic (one core's work)."""
    t0 = time.perf_counter()
    x = 0
    for i in range(n):
        x += i * i
    return time.perf_counter() - t0


def cores_free(n: int = 3_000_000) -> float:
    """Two processes of the same pure-Python work at once, wall time over one of them
    alone twice: 0.5 when two cores are free for this job, 1 when one is (a machine shared
    with other jobs)."""
    import multiprocessing

    with multiprocessing.get_context("spawn").Pool(2) as pool:
        pool.map(_burn, [1000, 1000])  # (the workers started)
        one = _burn(n) + _burn(n)
        t0 = time.perf_counter()
        pool.map(_burn, [n, n])
        return (time.perf_counter() - t0) / one


WORKERS_ENV = "RAILCONTACT_FMU_WORKERS"
"""How an N-wheelset FMU instance steps its wheelsets (read at its initialisation; the
slave runs in this process under fmpy)."""


def parallel_ratio(single: tuple, multi: tuple, wheelsets: int, steps: int,
                   repeats: int, workers: tuple[str, ...] = ("processes", "threads")) -> dict:
    """Median wall time [s] of the N-wheelset FMU's step with each of ``workers`` and of N
    single-wheelset instances stepped one after the other, over the same motions, stepped
    alternately; and whether each wheelset's Real outputs equal its single instance's bit
    for bit (solve_time apart)."""
    motions = [_motion(steps, 3e-3 - 0.4e-3 * j, 0.9 * j) for j in range(wheelsets)]
    many: dict[str, list[float]] = {w: [] for w in workers}
    ones, equal = [], True
    before = os.environ.get(WORKERS_ENV)
    for k in range(repeats):
        ms = {}
        for w in workers:
            os.environ[WORKERS_ENV] = w
            ms[w] = _Instance(*multi, f"multi{k}-{w}", wheelsets)
        singles = [_Instance(*single, f"single{k}-{j}") for j in range(wheelsets)]
        ways = [*workers, "singles"]
        for i in range(steps):
            for way in ways[i % len(ways):] + ways[:i % len(ways)]:  # each first in turn
                if way == "singles":
                    t = sum(s.step([mo[i]])[0] for s, mo in zip(singles, motions, strict=True))
                else:
                    t = ms[way].step([mo[i] for mo in motions])[0]
                if i:  # (the first step is cold)
                    (ones if way == "singles" else many[way]).append(t)
            for m in ms.values():
                for j, s in enumerate(singles):
                    equal &= m.s.getReal(m.all_outs[j]) == s.s.getReal(s.all_outs[0])
        for m in [*ms.values(), *singles]:
            m.free()
    if before is None:
        os.environ.pop(WORKERS_ENV, None)
    else:
        os.environ[WORKERS_ENV] = before
    return {"multi": {w: float(np.median(t)) for w, t in many.items()},
            "singles": float(np.median(ones)), "equal": equal, "steps": len(ones)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=2.0, help="simulated time [s]")
    ap.add_argument("--step", type=float, default=1e-3, help="communication step [s]")
    ap.add_argument("--csv", default="", help="per-step CSV output (optional)")
    ap.add_argument("--part", default="all",
                    choices=("all", "modes", "penetration", "wheelsets"),
                    help="what to run: the warm_start modes and the C host's overhead, the "
                    "penetration-control FMU / in-process ratio, the N-wheelset FMU's "
                    "parallel ratio, or all")
    ap.add_argument("--steps", type=int, default=400,
                    help="steps of each penetration-control run (penetration, wheelsets)")
    ap.add_argument("--repeats", type=int, default=3,
                    help="repetitions of the penetration-control runs, interleaved")
    ap.add_argument("--wheelsets", type=int, default=4,
                    help="wheelsets of the FMU of --part wheelsets")
    ap.add_argument("--workers", default="both", choices=("both", "processes", "threads"),
                    help="how the N-wheelset FMU of --part wheelsets steps its wheelsets "
                    "(RAILCONTACT_FMU_WORKERS): in worker processes, on threads, or both")
    args = ap.parse_args()

    from railcontact.fmu import build_fmu

    with tempfile.TemporaryDirectory() as tmp:
        fmu = build_fmu(Path(tmp) / "RailContact.fmu")
        d, md = _unpacked(fmu, Path(tmp) / "x")
        if args.part in ("all", "penetration"):
            ref = fixed_workload()
            p = penetration_ratio(d, md, args.steps, args.repeats)
            ref = 0.5 * (ref + fixed_workload())
            print(f"control = penetration, {p['steps']} warm steps (lateral 3 mm sine at "
                  f"1.5 Hz, 30 m/s, kinematic creepages), medians; fixed workload "
                  f"{ref * 1e3:.1f} ms")
            print(f"  in-process WheelsetContact.solve: {p['api'] * 1e3:.3f} ms "
                  f"({p['api'] / ref:.4f} of the workload)")
            print(f"  FMU through fmpy (set, doStep, get): {p['fmu'] * 1e3:.3f} ms "
                  f"({p['fmu'] / ref:.4f} of the workload)")
            print(f"  ratio FMU / in-process: {p['fmu'] / p['api']:.3f} (goal <= 1.2); median "
                  f"of the per-step ratios {p['paired']:.3f}")
        if args.part in ("all", "wheelsets"):
            n = args.wheelsets
            multi = build_fmu(Path(tmp) / f"RailContact{n}.fmu", warm=False, wheelsets=n)
            workers = ("processes", "threads") if args.workers == "both" else (args.workers,)
            free = cores_free()
            q = parallel_ratio((d, md), _unpacked(multi, Path(tmp) / f"x{n}"), n,
                               args.steps, args.repeats, workers)
            free = (free, cores_free())
            print(f"{n}-wheelset FMU under control = penetration, {q['steps']} warm steps, "
                  f"medians ({os.cpu_count()} cores; load average "
                  f"{' '.join(f'{x:.2f}' for x in os.getloadavg())} at the end; two "
                  f"processes of pure Python work at once / one after the other "
                  f"{free[0]:.2f} before, {free[1]:.2f} after: 0.5 two cores free, 1 one)")
            print(f"  {n} one-wheelset FMU steps one after the other: "
                  f"{q['singles'] * 1e3:.3f} ms")
            for w, t in q["multi"].items():
                print(f"  one step of the {n}-wheelset FMU, {w}: {t * 1e3:.3f} ms; parallel "
                      f"ratio ({n}-wheelset / {n} single) {t / q['singles']:.3f} (1: no gain; "
                      f"{1 / n:.2f}: perfectly parallel)")
            if len(q["multi"]) == 2:
                print(f"  processes / threads: "
                      f"{q['multi']['processes'] / q['multi']['threads']:.3f}")
            print(f"  every wheelset's outputs equal its single instance's bit for bit: "
                  f"{q['equal']}")
        if args.part not in ("all", "modes"):
            return
        ref = fixed_workload()
        results = [run_mode(d, md, m, args.duration, args.step) for m in MODES]
        ref = 0.5 * (ref + fixed_workload())  # (before and after the runs)
        overhead = shim_overhead(d, md)

    cold = results[0]
    print(f"FMU, {args.duration:g} s of hunting-like motion at {1 / args.step:g} Hz "
          f"communication steps ({len(cold['rows'])} steps), S1002/60E1, both wheels")
    print(f"fixed workload (scripts/bench_step.py, mean of before and after the runs): "
          f"{ref * 1e3:.1f} ms")
    print(f"{'warm_start':18s} {'median ms':>9s} {'/ wl':>6s} {'mean ms':>8s} {'normal':>7s} "
          f"{'tang.':>7s} {'max n/t':>8s} {'iter. ratio':>11s} {'time ratio':>10s}")
    for r in results:
        tot = r["normal"] + r["tangential"]
        ratio = (cold["normal"] + cold["tangential"]) / tot
        print(f"{r['mode']:18s} {r['median_ms']:9.2f} {r['median_ms'] * 1e-3 / ref:6.3f} "
              f"{r['mean_ms']:8.2f} "
              f"{r['normal']:7.2f} {r['tangential']:7.2f} "
              f"{r['max_normal']:>3d}/{r['max_tangential']:<4d} {ratio:10.2f}x "
              f"{cold['mean_ms'] / r['mean_ms']:9.2f}x")
    print("normal / tangential ratios to cold for 'previous': "
          f"{cold['normal'] / results[2]['normal']:.2f}x / "
          f"{cold['tangential'] / results[2]['tangential']:.2f}x")
    fy = {r["mode"]: np.array([row[4] for row in r["rows"]]) for r in results}
    for m in MODES[1:]:
        dev = np.max(np.abs(fy[m] - fy["none"])) / 83.3e3
        print(f"max |F_lateral - cold| / Q for {m}: {dev:.2e}")
    print("C host (env -i):", overhead)
    if args.csv:
        out = Path(args.csv)
        out.parent.mkdir(parents=True, exist_ok=True)
        with out.open("w", newline="") as f:
            wr = csv.writer(f)
            wr.writerow(["warm_start", "time_s", "wall_s", "normal_iterations",
                         "tangential_iterations", "force_lateral_N", "yaw_moment_Nm",
                         "solve_time_s"])
            for r in results:
                for row in r["rows"]:
                    wr.writerow([r["mode"], *row])
        print(f"per-step data written to {out}")


if __name__ == "__main__":
    main()
