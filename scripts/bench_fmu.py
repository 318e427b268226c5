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

``--part split`` says where the time of a step under ``control = penetration`` goes: for
the one-wheelset FMU (its in-process solve of the same motion beside it) fmpy's setReal
and getReal, and within doStep the slave's reading and checking of the inputs, the solve,
the outputs taken from its result, their writing and checks, and the rest (the C shim,
the slave's own); for the N-wheelset FMU in processes the same host side, the pool's step,
and within it the busiest process's solves, the time beyond them, when the last request
reached its worker and the slowest answer's way back (the pool's time stamps).

Usage: python scripts/bench_fmu.py [--part all|modes|penetration|wheelsets|split]
                                   [--duration 2.0] [--csv FILE] [--steps 400]
                                   [--repeats 3] [--wheelsets 4]
                                   [--workers both|processes|threads|P,...]
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
    its = [vr["normal_iterations"], vr["tangential_iterations"], vr["status"]]
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
        ni, nt, status = s.getInteger(its)
        if status != 0:  # (a step that failed would be timed as a cheap one)
            raise SystemExit(f"{mode}: the FMU's step at t = {t:g} s has status {status}")
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
        if r.status != 0:  # (the rigid wheelset's pose not found counts: the inputs' own)
            raise SystemExit(f"the motion's step at t = {t:g} s has status {int(r.status)}: "
                             f"{[x.message for x in r.wheels]}")
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
    seconds = time.perf_counter() - t0
    if r.status != 0:
        raise SystemExit(f"the in-process step at t = {m['time']:g} s has status "
                         f"{int(r.status)}: {[x.message for x in r.wheels]}")
    return seconds


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
        self.statuses = [self.vr["status" + x] for x in suffixes]

    def step(self, motions: list[dict]) -> tuple[float, list[float]]:
        """Set the inputs (one motion per wheelset), doStep, get the outputs: the wall time
        [s] and the outputs read."""
        t0 = time.perf_counter()
        self.s.setReal(self.ins, [m[n] for m in motions for n in INPUT_NAMES])
        self.s.doStep(motions[0]["time"], 1e-3)
        out = self.s.getReal(self.outs)
        seconds = time.perf_counter() - t0
        status = self.s.getInteger(self.statuses)  # (after the timing: not the host's work)
        if any(status):  # (a step that failed would be timed as a cheap one)
            raise SystemExit(f"the FMU's step at t = {motions[0]['time']:g} s has statuses "
                             f"{status}")
        return seconds, out

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


def _slave_named(name: str):
    """The Python slave of the fmpy instance ``name`` (fmpy is a Python host: the FMU's
    slave runs in this interpreter)."""
    import gc

    found = [o for o in gc.get_objects()
             if type(o).__name__ == "Slave" and getattr(o, "instance_name", None) == name]
    if len(found) != 1:
        raise RuntimeError(f"{len(found)} slaves named {name!r} in this process")
    return found[0]


class _Clock:
    """Wall time [s] spent in some methods of some objects during one step: each method
    wrapped in place (an instance attribute over the class's) until :meth:`undo`."""

    def __init__(self) -> None:
        self.spent: dict[str, float] = {}
        self._undo: list = []

    def wrap(self, obj, method: str, name: str) -> None:
        given = getattr(obj, method)
        had = method in vars(obj)

        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return given(*args, **kwargs)
            finally:
                self.spent[name] = self.spent.get(name, 0.0) + time.perf_counter() - t0

        setattr(obj, method, timed)
        self._undo.append((obj, method, given if had else None))

    def undo(self) -> None:
        for obj, method, given in reversed(self._undo):
            if given is None:
                delattr(obj, method)
            else:
                setattr(obj, method, given)
        self._undo.clear()


def split_single(fmu_dir: Path, md, steps: int) -> dict:
    """Where the one-wheelset FMU's step under penetration control goes: medians [s] of
    the host's setReal, doStep and getReal, and within doStep of the slave's input
    reading and checks (``_prepare``), the solve, the outputs taken from its result
    (``step_outputs``), their writing and checks (``_finish``); the in-process solve of
    the same motion (another instance, stepped alternately) beside it."""
    motion = _motion(steps)
    inst = _Instance(fmu_dir, md, "split1")
    slave = _slave_named("split1")
    module = sys.modules[type(slave).__module__]
    wc = _contact()
    rows = []
    for i, m in enumerate(motion):
        api = _in_process_step(wc, m)
        clock = _Clock()
        clock.wrap(slave, "_prepare", "prepare")
        clock.wrap(slave, "_finish", "finish")
        clock.wrap(slave.units[0].contact, "solve", "solve")
        clock.wrap(module, "step_outputs", "outputs")
        t0 = time.perf_counter()
        inst.s.setReal(inst.ins, [m[n] for n in INPUT_NAMES])
        t1 = time.perf_counter()
        inst.s.doStep(m["time"], 1e-3)
        t2 = time.perf_counter()
        inst.s.getReal(inst.outs)
        t3 = time.perf_counter()
        clock.undo()
        if i:
            c = clock.spent
            rows.append({"total": t3 - t0, "setReal": t1 - t0, "doStep": t2 - t1,
                         "getReal": t3 - t2, **c, "in-process": api, "ratio": (t3 - t0) / api,
                         "rest": t2 - t1 - c["prepare"] - c["solve"] - c["outputs"]
                         - c["finish"]})
    inst.free()
    return {k: float(np.median([r[k] for r in rows])) for k in rows[0]}


def split_multi(multi: tuple, wheelsets: int, steps: int) -> dict:
    """Where the N-wheelset FMU's step under penetration control goes, its wheelsets in
    processes (``RAILCONTACT_FMU_WORKERS`` as set): medians [s] of the host's setReal,
    doStep and getReal; within doStep the slave's input reading and checks of all
    wheelsets (``_prepare``), the pool's step, their output writing and checks
    (``_finish``); within the pool's step the solves of the busiest process (this one's
    share, or a worker's), the sum of all solves, and from the pool's time stamps the
    latest arrival of a request in a worker after sending and the latest answer's way
    back (:attr:`~railcontact.timestep.pool.WheelsetPool.spans`)."""
    motions = [_motion(steps, 3e-3 - 0.4e-3 * j, 0.9 * j) for j in range(wheelsets)]
    inst = _Instance(*multi, "splitN", wheelsets)
    slave = _slave_named("splitN")
    pool = slave._pool
    if pool is None:
        inst.free()
        raise RuntimeError("the N-wheelset FMU does not step its wheelsets in processes")
    rows = []
    for i in range(steps):
        ms = [mo[i] for mo in motions]
        clock = _Clock()
        clock.wrap(slave, "_prepare", "prepare")
        clock.wrap(slave, "_finish", "finish")
        clock.wrap(pool, "step", "pool step")
        t0 = time.perf_counter()
        inst.s.setReal(inst.ins, [m[n] for m in ms for n in INPUT_NAMES])
        t1 = time.perf_counter()
        inst.s.doStep(ms[0]["time"], 1e-3)
        t2 = time.perf_counter()
        inst.s.getReal(inst.outs)
        t3 = time.perf_counter()
        clock.undo()
        sec = pool.seconds
        busiest = max(sum(sec[k] for k in share) for share in pool.shares)
        remote = pool.shares[1:] if pool.here else pool.shares
        arrive = max((a - pool.sent for a, _, _ in pool.spans), default=0.0)
        back = max((c - b for _, b, c in pool.spans), default=0.0)
        if i:
            c = clock.spent
            rows.append({"total": t3 - t0, "setReal": t1 - t0, "doStep": t2 - t1,
                         "getReal": t3 - t2, **c, "busiest": busiest, "solves": sum(sec),
                         "beyond": c["pool step"] - busiest, "arrive": arrive, "back": back,
                         "rest": t2 - t1 - c["prepare"] - c["pool step"] - c["finish"],
                         "workers": float(len(remote))})
    here = pool.here
    inst.free()
    out = {k: float(np.median([r[k] for r in rows])) for k in rows[0]}
    out["here"] = here
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=2.0, help="simulated time [s]")
    ap.add_argument("--step", type=float, default=1e-3, help="communication step [s]")
    ap.add_argument("--csv", default="", help="per-step CSV output (optional)")
    ap.add_argument("--part", default="all",
                    choices=("all", "modes", "penetration", "wheelsets", "split"),
                    help="what to run: the warm_start modes and the C host's overhead, the "
                    "penetration-control FMU / in-process ratio, the N-wheelset FMU's "
                    "parallel ratio, where the one- and the N-wheelset FMU's steps' time "
                    "goes (split), or all but split")
    ap.add_argument("--steps", type=int, default=400,
                    help="steps of each penetration-control run (penetration, wheelsets)")
    ap.add_argument("--repeats", type=int, default=3,
                    help="repetitions of the penetration-control runs, interleaved")
    ap.add_argument("--wheelsets", type=int, default=4,
                    help="wheelsets of the FMU of --part wheelsets")
    ap.add_argument("--workers", default="both",
                    help="how the N-wheelset FMU of --part wheelsets steps its wheelsets: "
                    "comma-separated values of RAILCONTACT_FMU_WORKERS (processes: this "
                    "process and worker processes; a number: that many worker processes; "
                    "threads), each way stepped alternately with the others; both: "
                    "processes,threads")
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
            workers = (("processes", "threads") if args.workers == "both" else
                       tuple(w.strip() for w in args.workers.split(",") if w.strip()))
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
            if set(q["multi"]) == {"processes", "threads"}:
                print(f"  processes / threads: "
                      f"{q['multi']['processes'] / q['multi']['threads']:.3f}")
            print(f"  every wheelset's outputs equal its single instance's bit for bit: "
                  f"{q['equal']}")
        if args.part == "split":
            _print_split(split_single(d, md, args.steps), split_multi(
                _unpacked(build_fmu(Path(tmp) / f"RailContact{args.wheelsets}.fmu",
                                    warm=False, wheelsets=args.wheelsets),
                          Path(tmp) / f"x{args.wheelsets}"), args.wheelsets, args.steps),
                args.wheelsets)
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


def _print_split(one: dict, many: dict, n: int) -> None:
    ms = {k: 1e3 * v for k, v in one.items()}
    print(f"where a step's time goes under control = penetration (medians [ms]; load "
          f"average {' '.join(f'{x:.2f}' for x in os.getloadavg())})")
    print(f"  1 wheelset: set, doStep, get {ms['total']:.3f} (in-process solve of the same "
          f"motion {ms['in-process']:.3f}; median of the per-step ratios {one['ratio']:.3f})")
    rest = ms["rest"]
    print(f"    fmpy setReal {ms['setReal']:.3f}, getReal {ms['getReal']:.3f}; doStep "
          f"{ms['doStep']:.3f}: inputs read and checked {ms['prepare']:.3f}, solve "
          f"{ms['solve']:.3f}, outputs taken {ms['outputs']:.3f}, written and checked "
          f"{ms['finish']:.3f}, the rest (shim, slave) {rest:.3f}")
    mm = {k: 1e3 * v for k, v in many.items() if k != "here"}
    who = (f"this process and {many['workers']:.0f} worker process(es)" if many["here"]
           else f"{many['workers']:.0f} worker processes")
    print(f"  {n} wheelsets in {who}: set, doStep, get {mm['total']:.3f}")
    rest = mm["rest"]
    print(f"    fmpy setReal {mm['setReal']:.3f}, getReal {mm['getReal']:.3f}; doStep "
          f"{mm['doStep']:.3f}: inputs read and checked {mm['prepare']:.3f}, pool step "
          f"{mm['pool step']:.3f}, outputs written and checked {mm['finish']:.3f}, the rest "
          f"{rest:.3f}")
    print(f"    in the pool step: the busiest process's solves {mm['busiest']:.3f} (all "
          f"solves {mm['solves']:.3f}, /{n} x 2 = {mm['solves'] / n * 2:.3f}), beyond them "
          f"{mm['beyond']:.3f}; the last request arrived {mm['arrive']:.3f} after sending, "
          f"the slowest answer's way back {mm['back']:.3f} (with this process stepping a "
          f"share, an answer waits for it to end its own)")


if __name__ == "__main__":
    main()
