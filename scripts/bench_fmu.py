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

Usage: python scripts/bench_fmu.py [--duration 2.0] [--csv FILE]
"""

from __future__ import annotations

import argparse
import csv
import math
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=2.0, help="simulated time [s]")
    ap.add_argument("--step", type=float, default=1e-3, help="communication step [s]")
    ap.add_argument("--csv", default="", help="per-step CSV output (optional)")
    args = ap.parse_args()

    from fmpy.model_description import read_model_description

    from railcontact.fmu import build_fmu

    with tempfile.TemporaryDirectory() as tmp:
        fmu = build_fmu(Path(tmp) / "RailContact.fmu")
        d = Path(tmp) / "x"
        with zipfile.ZipFile(fmu) as z:
            z.extractall(d)
        md = read_model_description(str(fmu))
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
