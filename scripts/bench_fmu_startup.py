"""Start-up time of a freshly unpacked FMU in fmpy, with the kernel cache cold and warm.

Each run unpacks the FMU into a new temporary folder (as fmpy's ``simulate_fmu`` and most
hosts do for every simulation) and starts a new Python process that drives it through
fmpy's ``FMU2Slave``: instantiate (the FMU's start-up: the interpreter's packages and the
FMU's copy of railcontact imported), initialisation (``exitInitializationMode``: the first
solve, at the default inputs), and the first ``doStep`` (lateral displacement 1 mm,
creepages 1e-3 / -5e-4 / +-0.3 1/m); S1002 on 60E1, element size 0.5 mm, the default
settings. The per-user kernel cache is a temporary folder (``RAILCONTACT_CACHE_DIR``):

- *cold*: an empty cache, i.e. the first run in a new environment of an FMU that was not
  warmed (built with ``--no-warm``, or copied to another machine or environment); numba
  compiles every kernel;
- *warm*: the cache the cold run filled, i.e. every later unpacking in that environment
  (and the first one after ``railcontact fmu build``, which warms the kernels).

Also timed: ``railcontact fmu build``'s warm-up on an empty cache (its Python started as a
C host starts it, the kernels of a few representative steps compiled) and on the filled
one. Prints the median of the runs [s] and the kernels each run compiled and loaded.

Usage: python scripts/bench_fmu_startup.py [--warm-runs 5] [--cold-runs 1] [--fmu FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
from fmpy.fmi2 import FMU2Slave
from fmpy.model_description import read_model_description
t_fmpy = time.perf_counter() - t0
d = sys.argv[1]
md = read_model_description(d + "/modelDescription.xml")
vr = {v.name: v.valueReference for v in md.modelVariables}
s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
              instanceName="bench")
t = [time.perf_counter()]
s.instantiate()
t.append(time.perf_counter())
s.setupExperiment(startTime=0.0)
s.enterInitializationMode()
s.exitInitializationMode()
t.append(time.perf_counter())
names = ["lateral_displacement", "xi_left", "eta_left", "phi_left", "xi_right", "eta_right",
         "phi_right"]
s.setReal([vr[n] for n in names], [1e-3, 1e-3, -5e-4, 0.3, 1e-3, -5e-4, -0.3])
s.doStep(0.0, 1e-3)
t.append(time.perf_counter())
force = s.getReal([vr["normal_force_left"]])[0]
package = [m for m in sys.modules if m.startswith("railcontact_fmu_")
           and m.endswith("._kernelcache")]
compiled, loaded = sys.modules[package[0]].kernel_counts()
s.terminate()
s.freeInstance()
print(json.dumps({"fmpy_import": t_fmpy, "instantiate": t[1] - t[0],
                  "initialise": t[2] - t[1], "first_step": t[3] - t[2],
                  "total": t[3] - t[0], "compiled": compiled, "loaded": loaded,
                  "normal_force_left": force}))
"""


def fresh_run(fmu: Path, cache: Path) -> dict:
    """Unpack ``fmu`` into a new folder and time its start-up in a new Python process."""
    with tempfile.TemporaryDirectory(prefix="rc-startup-") as tmp:
        with zipfile.ZipFile(fmu) as z:
            z.extractall(tmp)
        env = dict(os.environ, RAILCONTACT_CACHE_DIR=str(cache))
        env.pop("RAILCONTACT_PYTHON", None)
        r = subprocess.run([sys.executable, "-c", CHILD, tmp], capture_output=True,
                           text=True, env=env, timeout=1800)
    if r.returncode != 0:
        raise SystemExit(f"the run failed:\n{r.stdout}\n{r.stderr}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def warm_up(fmu: Path, cache: Path) -> tuple[float, str]:
    """``railcontact fmu build``'s warm-up on an unpacked copy of ``fmu``: (wall time [s]
    with the Python's start-up, its report)."""
    from railcontact.fmu import warm_unpacked

    old = os.environ.get("RAILCONTACT_CACHE_DIR")
    os.environ["RAILCONTACT_CACHE_DIR"] = str(cache)
    try:
        with tempfile.TemporaryDirectory(prefix="rc-warm-") as tmp:
            with zipfile.ZipFile(fmu) as z:
                z.extractall(tmp)
            t0 = time.perf_counter()
            result = warm_unpacked(tmp)
            return time.perf_counter() - t0, result.text
    finally:
        if old is None:
            os.environ.pop("RAILCONTACT_CACHE_DIR", None)
        else:
            os.environ["RAILCONTACT_CACHE_DIR"] = old


def summary(label: str, runs: list[dict]) -> str:
    keys = ("instantiate", "initialise", "first_step", "total")
    med = {k: statistics.median(r[k] for r in runs) for k in keys}
    return (f"{label:<22s} {len(runs):>4d} {med['instantiate']:>12.2f} "
            f"{med['initialise']:>11.2f} {med['first_step']:>10.2f} {med['total']:>8.2f}   "
            f"{'/'.join(str(r['compiled']) for r in runs)} compiled, "
            f"{'/'.join(str(r['loaded']) for r in runs)} loaded")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--warm-runs", type=int, default=5, help="fresh unpackings, warm cache")
    ap.add_argument("--cold-runs", type=int, default=1,
                    help="fresh unpackings, each with an empty cache (each compiles "
                    "every kernel: 40-100 s)")
    ap.add_argument("--fmu", type=Path, help="an FMU to time (default: built now, unwarmed)")
    args = ap.parse_args(argv)

    with tempfile.TemporaryDirectory(prefix="rc-bench-startup-") as tmp:
        tmp = Path(tmp)
        fmu = args.fmu
        if fmu is None:
            from railcontact.fmu import build_fmu

            fmu = build_fmu(tmp / "RailContact.fmu", warm=False)
        cold = []
        for k in range(args.cold_runs):
            cold.append(fresh_run(fmu, tmp / f"cold-cache-{k}"))
            print(f"cold run {k + 1}: {json.dumps(cold[-1])}", flush=True)
        cache = tmp / "cache"
        build_cold, text_cold = warm_up(fmu, cache)
        print(f"fmu build's warm-up, empty cache: {build_cold:.1f} s ({text_cold})", flush=True)
        build_warm, text_warm = warm_up(fmu, cache)
        print(f"fmu build's warm-up, filled cache: {build_warm:.1f} s ({text_warm})",
              flush=True)
        warm = []
        for k in range(args.warm_runs):
            warm.append(fresh_run(fmu, cache))
            print(f"warm run {k + 1}: {json.dumps(warm[-1])}", flush=True)
        print()
        print(f"FMU start-up in fmpy, a fresh unpacking each run ({os.cpu_count()} CPUs, load "
              f"{os.getloadavg()[0]:.1f}); medians [s]:")
        print(f"{'kernel cache':<22s} {'runs':>4s} {'instantiate':>12s} {'initialise':>11s} "
              f"{'1st doStep':>10s} {'total':>8s}   kernels")
        if cold:
            print(summary("cold (new environment)", cold))
        print(summary("warm (after fmu build)", warm))
        print(f"fmu build's warm-up: {build_cold:.1f} s on an empty cache, {build_warm:.1f} s "
              "on a filled one")
    return 0


if __name__ == "__main__":
    sys.exit(main())
