"""A contact table's store: its files, the client's writes, opening it, and the FMU's start
in table mode.

The table (by default) is the shape of a realistic creep-force table: S1002 on 60E1,
0.5 mm elements, lateral displacement -8 .. 8 mm by 0.5 mm (33), yaw 0 and +-5 mrad,
loads 40/80/120 kN, spin -2/0/2 1/m, xi and eta 5 values each: 22,275 points x 2 wheels,
4,455 batches of 5 points along eta. Without ``--table`` its store is written here by the
build's own writer (``Store.write_batches``: every batch, in groups of ``--per-write``
batches as a build's client writes what finished in its last interval) with random
values: the layout, the sizes and the file count are those of a build, only the numbers
differ (opening does not depend on them). ``--table PATH`` times a built store instead.

Printed: the files and bytes of the store; the client's write per batch (median over the
writes); ``ContactTable.open`` in a fresh Python process (railcontact imported before,
zarr's import counted: it is the open's; median of ``--runs``); ``railcontact table
show``'s wall time with the Python start; and, with ``--fmu``, the FMU's start in table
mode in fmpy (instantiate, then initialisation with ``contact_model = table`` and the
store as ``table_file``: the slave opens the table), median of ``--runs`` fresh
processes, its kernel cache filled first.

Usage: python scripts/bench_table_store.py [--table PATH] [--runs 5] [--per-write 60]
       [--fmu]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

SPEC = {
    "name": "creep_table",
    "material": {"young": 206e9, "poisson": 0.28},
    "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                 "inclination": math.atan(1 / 40)},
    "grid": {"dx": 0.5e-3, "dy": 0.5e-3},
    "normal": {"load": 80e3, "estimate": "hertz"},
    "tangential": {"creepage": [0.0, 0.0, 0.0], "friction": 0.3},
    "table": {"lateral_displacement": [-0.008, 0.008, 33], "yaw": [-0.005, 0.005, 3],
              "load": [40e3, 120e3, 3], "spin": [-2.0, 2.0, 3],
              "creepage_x": [-0.002, 0.002, 5], "creepage_y": [-0.002, 0.002, 5]},
}

OPEN = r"""
import json, sys, time
from railcontact.table import ContactTable
t0 = time.perf_counter()
t = ContactTable.open(sys.argv[1])
print(json.dumps({"open": time.perf_counter() - t0, "points": int(t._status.size)}))
"""

FMU = r"""
import json, sys, time
t0 = time.perf_counter()
from fmpy.fmi2 import FMU2Slave
from fmpy.model_description import read_model_description
d, table = sys.argv[1], sys.argv[2]
md = read_model_description(d + "/modelDescription.xml")
var = {v.name: v for v in md.modelVariables}
s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
              instanceName="bench")
t = [time.perf_counter()]
s.instantiate()
t.append(time.perf_counter())
s.setupExperiment(startTime=0.0)
s.enterInitializationMode()
items = {i.name: int(i.value) for i in var["contact_model_choice"].declaredType.items}
s.setInteger([var["contact_model_choice"].valueReference], [items["table"]])
s.setString([var["table_file"].valueReference], [table])
s.exitInitializationMode()
t.append(time.perf_counter())
s.terminate()
s.freeInstance()
print(json.dumps({"instantiate": t[1] - t[0], "initialise": t[2] - t[1],
                  "start": t[2] - t[0]}))
"""


def write_store(out: Path, per_write: int) -> list[float]:
    """The table of :data:`SPEC` written by the build's writer with random values; the
    seconds per batch of each write."""
    from railcontact.table import parse_spec
    from railcontact.table.store import Store, create_store
    from railcontact.table.variables import COUNTS, QUANTITIES

    spec = parse_spec(SPEC)
    t0 = time.perf_counter()
    create_store(out, spec)
    print(f"store created in {time.perf_counter() - t0:.2f} s (metadata and axes only)")
    store = Store(out, spec)
    rng = np.random.default_rng(1)
    batches = list(np.ndindex(*spec.batch_shape))
    per_batch = []
    for k in range(0, len(batches), per_write):
        items = []
        for ix in batches[k:k + per_write]:
            n = len(spec.batch_points(ix))
            r = {q.name: rng.normal(size=(n, len(spec.sides))) for q in QUANTITIES}
            r.update({q.name: rng.integers(0, 50, size=(n, len(spec.sides)), dtype=np.int32)
                      for q in COUNTS})
            r["status"] = np.zeros((n, len(spec.sides)), dtype=np.int8)
            items.append((ix, r, []))
        t0 = time.perf_counter()
        store.write_batches(items)
        per_batch.append((time.perf_counter() - t0) / len(items))
    store.finish(True)
    return per_batch


def files(path: Path) -> tuple[int, int]:
    ps = [p for p in path.rglob("*") if p.is_file()]
    return len(ps), sum(p.stat().st_size for p in ps)


def child(code: str, *args: str, env: dict | None = None) -> dict:
    r = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                       cwd=ROOT, env=env, timeout=1800)
    if r.returncode != 0:
        raise SystemExit(f"the run failed:\n{r.stdout}\n{r.stderr}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--table", type=Path, help="a built store to time (default: written "
                    "here, the shape of the module docstring)")
    ap.add_argument("--runs", type=int, default=5, help="fresh processes per timing (5)")
    ap.add_argument("--per-write", type=int, default=60,
                    help="batches per write of the client (60: 5 s of a 60 points/s build)")
    ap.add_argument("--fmu", action="store_true", help="also the FMU's start in table mode")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="rc-bench-store-") as tmp:
        tmp = Path(tmp)
        table = args.table
        if table is None:
            table = tmp / "creep.zarr"
            per = write_store(table, args.per_write)
            print(f"client writes: {len(per)} writes of {args.per_write} batches; "
                  f"{statistics.median(per) * 1e3:.2f} ms a batch (median; "
                  f"max {max(per) * 1e3:.2f} ms)")
        n, size = files(table)
        print(f"store {table}: {n} files, {size / 2**20:.2f} MiB on disk")
        opened = [child(OPEN, str(table)) for _ in range(args.runs)]
        med = statistics.median(r["open"] for r in opened)
        print(f"ContactTable.open ({opened[0]['points']} point-wheels), fresh process, "
              f"railcontact imported before, zarr's import included: median {med:.3f} s "
              f"(max {max(r['open'] for r in opened):.3f} s, {args.runs} runs)")
        shows = []
        for _ in range(args.runs):
            t0 = time.perf_counter()
            r = subprocess.run([sys.executable, "-m", "railcontact", "table", "show",
                                str(table)], capture_output=True, text=True, cwd=ROOT)
            shows.append(time.perf_counter() - t0)
            if r.returncode != 0:
                raise SystemExit(r.stderr)
        print(f"railcontact table show, wall with the Python start: median "
              f"{statistics.median(shows):.2f} s")
        if args.fmu:
            import zipfile

            from railcontact.fmu import build_fmu

            fmu = build_fmu(tmp / "RailContact.fmu", [])
            cache = tmp / "cache"
            env = dict(os.environ, RAILCONTACT_CACHE_DIR=str(cache))
            env.pop("RAILCONTACT_PYTHON", None)
            runs = []
            for k in range(args.runs + 1):  # the first fills the kernel cache: not counted
                d = tmp / f"unpacked{k}"
                with zipfile.ZipFile(fmu) as z:
                    z.extractall(d)
                r = child(FMU, str(d), str(table.resolve()), env=env)
                if k:
                    runs.append(r)
            med = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
            print(f"FMU table mode, fresh unpacking and process, kernel cache filled: "
                  f"instantiate {med['instantiate']:.2f} s, initialise (opens the table) "
                  f"{med['initialise']:.2f} s, start {med['start']:.2f} s (median of "
                  f"{len(runs)}; max start {max(r['start'] for r in runs):.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
