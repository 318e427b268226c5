"""Contact tables: interpolation cost per wheelset step, interpolation error
against exact solves between the nodes, and (``--scaling``) the build's points per second
with 1, 2, ... Dask workers.

The table: the paper's wheel-rail case (S1002 on 60E1 at 1:40, 83.3 kN per wheel, 0.5 mm
elements, eps_n = 1e-3, eps_tau = 1e-2, mu = 0.3), both wheels, over the lateral
displacement (-4 .. 4 mm, 9 nodes: tread contact), the longitudinal and the lateral
creepage (-2e-3 .. 2e-3, 5 nodes each). 225 points x 2 wheels: modest, for a 2-core
machine (``--nodes`` sets the nodes per axis).

1. Cost: ``TableContact.solve`` (a whole wheelset step: both wheels, the FMU's result
   record) per call, linear and cubic, beside an exact warm-started ``WheelsetContact``
   step at the same states; and the fixed numpy workload of ``bench_step.py`` measured in
   the same run, to compare runs on a loaded machine.
2. Error: at random states strictly between the nodes, the exact cold solve
   (``railcontact solve`` of the case at that state, each wheel) against the table's
   linear and cubic values; errors of the forces relative to mu Q (the saturation force
   scale), of the contact angle in mrad, of the contact point in mm.
3. ``--scaling``: the same table built into a fresh store by a LocalCluster of 1, 2, ...
   worker processes; points per second of the solves (cluster start excluded, shown
   apart) and the efficiency rate_n / (n rate_1); with how busy the workers were (their
   batches' wall time / (n x the build's)) and how much of that they had a core (CPU time /
   wall time: below 1 when other processes share the cores).

Usage: python scripts/bench_table.py [--out DIR] [--workers N] [--samples M]
       [--nodes L X Y] [--scaling [N ...]]
"""

from __future__ import annotations

import argparse
import math
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from bench_step import fixed_workload

import railcontact as rc
from railcontact.table import ContactTable, parse_spec
from railcontact.table.build import build_table
from railcontact.table.solve import solve_point
from railcontact.table.step import TableContact

LOAD = 83.3e3
FRICTION = 0.3


def spec_dict(nodes: tuple[int, int, int]) -> dict:
    """The table spec (see the module docstring)."""
    return {
        "name": "paper_table",
        "material": {"young": 206e9, "poisson": 0.28},
        "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                     "inclination": math.atan(1 / 40), "gauge": 1.435,
                     "back_to_back": 1.360, "wheel_radius": 0.46},
        "grid": {"dx": 0.5e-3, "dy": 0.5e-3},
        "normal": {"load": LOAD, "estimate": "hertz", "tolerance": 1e-3},
        "tangential": {"creepage": [0.0, 0.0, 0.0], "friction": FRICTION,
                       "tolerance": 1e-2},
        "table": {"lateral_displacement": [-0.004, 0.004, nodes[0]],
                  "creepage_x": [-0.002, 0.002, nodes[1]],
                  "creepage_y": [-0.002, 0.002, nodes[2]]},
    }


def build(spec, out: Path, workers: int) -> float:
    t0 = time.perf_counter()
    rep = build_table(spec, out, workers=workers, progress=False)
    print(f"table {out}: {rep.points} points, computed {rep.computed} in "
          f"{time.perf_counter() - t0:.1f} s ({rep.rate:.3g} points/s on {rep.workers} "
          f"worker(s), cluster start excluded), {rep.skipped} already there, "
          f"{rep.not_ok} point-wheels not ok")
    return rep.rate


def states(table: ContactTable, n: int, seed: int = 1) -> list[dict[str, float]]:
    """``n`` random states strictly between the nodes (never on a node along any axis)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        s = {}
        for name, nodes in table.axes.items():
            i = rng.integers(0, len(nodes) - 1)
            s[name] = float(nodes[i] + rng.uniform(0.2, 0.8) * (nodes[i + 1] - nodes[i]))
        out.append(s)
    return out


def cost(table: ContactTable, spec) -> None:
    pts = states(table, 200, seed=2)
    pose = [rc.Pose(p["lateral_displacement"], 0.0, 0.0) for p in pts]
    creep = [((p["creepage_x"], p["creepage_y"], 0.0), (p["creepage_x"], -p["creepage_y"], 0.0))
             for p in pts]
    work = fixed_workload()
    print(f"fixed numpy workload: {work * 1e3:.1f} ms (bench_step.py's; compare runs by it)")
    per = {}
    for method in ("linear", "cubic"):
        tc = TableContact(table, method)
        reps = 50 if method == "linear" else 5
        best = math.inf
        for _ in range(3):
            t0 = time.perf_counter()
            for _ in range(reps):
                for ps, cr in zip(pose, creep, strict=True):
                    tc.solve(ps, loads=(LOAD, LOAD), creepages=cr)
            best = min(best, (time.perf_counter() - t0) / (reps * len(pts)))
        per[method] = best
        r = tc.solve(pose[0], loads=(LOAD, LOAD), creepages=creep[0])
        assert r.status == 0, [w.message for w in r.wheels]
    # an exact warm-started step at the same states (a slow walk through them)
    geo, tan = spec.case["geometry"], spec.case["tangential"]
    wc = rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), geo["inclination"], geo["gauge"]),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), geo["wheel_radius"],
                    geo["back_to_back"]),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=tan["friction"], element_size=0.5e-3))
    y = np.linspace(-1e-3, 1e-3, 21)
    wc.solve(rc.Pose(y[0], 0.0, 0.0), loads=(LOAD, LOAD), creepages=creep[0])
    times = []
    for k, yk in enumerate(y[1:]):
        t0 = time.perf_counter()
        wc.solve(rc.Pose(float(yk), 0.0, 0.0), loads=(LOAD, LOAD),
                 creepages=((1e-3, 1e-3 * k / 20, 0.0), (1e-3, -1e-3 * k / 20, 0.0)))
        times.append(time.perf_counter() - t0)
    exact = statistics.median(times)
    print("cost per wheelset step (both wheels; best of 3):")
    for m, t in per.items():
        print(f"  table, {m:6s}  {t * 1e6:9.1f} us  = {t / exact * 100:.3f} % of an exact "
              f"step, {t / work:.2e} x the workload")
    print(f"  exact (warm)   {exact * 1e3:9.2f} ms  (median of 20 steps)")


def error(table: ContactTable, spec, samples: int) -> None:
    pts = states(table, samples)
    scale = FRICTION * LOAD
    rows = {m: {"N": [], "Fx": [], "Fy": [], "angle": [], "y": []} for m in ("linear", "cubic")}
    t0 = time.perf_counter()
    for p in pts:
        for side in spec.sides:
            exact, _ = solve_point(spec.case_at_values(p), side)
            if exact.status != 0:
                print(f"  exact solve not ok at {p} {side}: {exact.message}")
                continue
            for m in rows:
                r = table(p, side, m)
                if r.status != 0:  # (a hole or a state out of the table's range)
                    print(f"  {m} interpolation not ok at {p} {side}: status {r.status}")
                    continue
                rows[m]["N"].append(abs(r["normal_force"] - exact.normal_force) / LOAD)
                rows[m]["Fx"].append(abs(r["creep_force_x"] - exact.creep_force[0]) / scale)
                rows[m]["Fy"].append(abs(r["creep_force_y"] - exact.creep_force[1]) / scale)
                rows[m]["angle"].append(abs(r["contact_angle"] - exact.contact_angle) * 1e3)
                rows[m]["y"].append(abs(r["contact_y"] - exact.contact_point[1]) * 1e3)
    n = len(rows["linear"]["N"])
    print(f"interpolation error at {len(pts)} random states between the nodes x "
          f"{len(spec.sides)} wheels ({n} exact cold solves, {time.perf_counter() - t0:.1f} s):")
    print("  method  quantity                        median        max")
    names = {"N": "normal force / Q", "Fx": "F_x / (mu Q)", "Fy": "F_y / (mu Q)",
             "angle": "contact angle [mrad]", "y": "contact point Y [mm]"}
    for m, qs in rows.items():
        for q, v in qs.items():
            print(f"  {m:6s}  {names[q]:28s} {statistics.median(v):10.2e} {max(v):10.2e}")


def nodes_vs_cold(table: ContactTable, spec, samples: int) -> None:
    """The warm-started nodes against cold solves of the same states (the warm start
    changes the solver's path, not its grid: they differ by the solvers' tolerances)."""
    rng = np.random.default_rng(3)
    dn, df, dp, cold_first = [], [], [], []
    for _ in range(samples):
        index = tuple(int(rng.integers(0, n)) for n in spec.shape)
        for side in spec.sides:
            node = table.node(index, side)
            exact, _ = solve_point(spec.case_at(index), side)
            if exact.status != 0 or node.status != 0:
                print(f"  node {index} {side}: not compared (node status "
                      f"{node.status}, cold solve: {exact.message})")
                continue
            dn.append(abs(node["normal_force"] - exact.normal_force) / LOAD)
            df.append(max(abs(node["creep_force_x"] - exact.creep_force[0]),
                          abs(node["creep_force_y"] - exact.creep_force[1])) / (FRICTION * LOAD))
            dp.append(abs(node["max_pressure"] - exact.max_pressure) / exact.max_pressure)
            if index[-1] % spec.batch == 0:  # a batch's first point: started cold too
                cold_first.append(dn[-1] + df[-1] + dp[-1])
    print(f"stored nodes against cold solves ({samples} nodes x {len(spec.sides)} wheels; "
          f"eps_n = 1e-3, eps_tau = 1e-2):")
    print(f"  normal force / Q: max {max(dn, default=math.nan):.2e}; creep forces / (mu Q): "
          f"max {max(df, default=math.nan):.2e}; "
          f"p_max relative: max {max(dp, default=math.nan):.2e}; first points of batches: "
          f"{len(cold_first)}, max difference {max(cold_first, default=0.0):.1e}")


def scaling(spec, counts: list[int]) -> None:
    rates = {}
    for n in counts:
        with tempfile.TemporaryDirectory() as d:
            t0 = time.perf_counter()
            rep = build_table(spec, Path(d) / "s.zarr", workers=n, progress=False)
            wall = time.perf_counter() - t0
        rates[n] = rep.rate
        print(f"  {n} worker(s): {rep.computed} points in {rep.seconds:.1f} s = "
              f"{rep.rate:.3g} points/s (wall with cluster start {wall:.1f} s), "
              f"efficiency {rep.rate / (n * rates[counts[0]] / counts[0]):.2f}; workers "
              f"busy {rep.task_seconds / (n * rep.seconds):.2f} of the time, on a core "
              f"{rep.task_cpu_seconds / rep.task_seconds:.2f} of their busy time")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", help="keep the table in this folder (reused when present)")
    ap.add_argument("--workers", type=int, default=2, help="workers building the table (2)")
    ap.add_argument("--samples", type=int, default=20,
                    help="random states for the error study (20)")
    ap.add_argument("--nodes", type=int, nargs=3, default=(9, 5, 5), metavar=("L", "X", "Y"),
                    help="nodes of the lateral displacement and the two creepages (9 5 5)")
    ap.add_argument("--scaling", type=int, nargs="*",
                    help="also build the table with these numbers of workers (default 1 2)")
    args = ap.parse_args(argv)
    if min(args.nodes) < 4:  # (the cubic interpolation's least, which the study times)
        ap.error(f"--nodes: at least 4 per axis (cubic interpolation), got {args.nodes}")
    spec = parse_spec(spec_dict(tuple(args.nodes)))
    tmp = None
    if args.out:
        folder = Path(args.out)
        folder.mkdir(parents=True, exist_ok=True)
    else:
        folder = tmp = Path(tempfile.mkdtemp(prefix="bench_table_"))
    try:
        out = folder / f"paper_{'x'.join(map(str, args.nodes))}.zarr"
        build(spec, out, args.workers)
        table = ContactTable.open(out)
        cost(table, spec)
        nodes_vs_cold(table, spec, args.samples)
        error(table, spec, args.samples)
        if args.scaling is not None:
            counts = args.scaling or [1, 2]
            print(f"scaling (the same table, {spec.size} points x {len(spec.sides)} wheels, "
                  "into a fresh store each time; a shared 2-core machine):")
            scaling(spec, counts)
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
