"""Benchmark of the full wheel-rail case beside CONTACT: time and iterations per wheel case.

The cases of ``models/reference/contact/``: S1002 on UIC60 (the Manchester
benchmark files, the rail canted in the file), G = 82 GPa, nu = 0.28, mu = 0.4, a vertical
wheel load of 83.3 kN (load control, creep forces counted), steady rolling with the
creepages CONTACT used (xi = eta = 2e-4, its kinematic spin), roll = yaw = 0, both wheels,
lateral displacement -8 .. 8 mm in 1 mm steps at 0.5 mm elements, and -6, -3, 0, 3, 6 mm at
0.2 mm (``--fine``). Each case is one ``railcontact.solve`` (geometry, contact search, all
load passes), at CONTACT's tolerance eps = 1e-5 for the normal and tangential solvers, and
at the paper's tolerances (eps_n = 1e-3, eps_tau = 1e-2) for comparison.

It prints, per tolerance set and start (``none``; ``infcon`` + ``fastrip``), the mean time
per wheel case, the summed iterations per case (normal CG, tangential sweeps, load passes),
and the time as a ratio to a fixed numpy workload measured in the same run (as
``bench_step.py``), beside CONTACT's figures from that folder (its time as the same ratio:
48-50 ms = 1.5x the workload on the machine where it was measured).

Usage: python scripts/bench_wheelrail.py [--fine] [--solver NAME] [--csv FILE]
       [--contact DIR] [--profiles DIR]
"""

from __future__ import annotations

import argparse
import csv
import math
import statistics
import sys
import time
from pathlib import Path

from _sweep import write_csv
from bench_step import clear_caches, fixed_workload

import railcontact as rc
from railcontact.settings.convention import side_creepage

HERE = Path(__file__).resolve().parent
CONTACT_REFERENCE = HERE.parent / "models" / "reference" / "contact"
"""CONTACT's results (``wheelrail_dx0.5.csv``; its README gives their provenance)."""
PROFILES = HERE.parent / "models" / "profiles"
"""The Manchester benchmark's profile files (``MBench_S1002_v3.prw``, ``MBench_UIC60_v3.prr``)."""
CONTACT_RATIO = {0.5: 1.5, 0.2: 64.0}
"""CONTACT's time per wheel case as a ratio to the fixed workload (its README)."""
CONTACT_FINE = {"cg": 31.8, "sweeps": 124.8}
"""CONTACT's iterations per case at 0.2 mm (its README; the folder has no per-case rows)."""
FINE_Y_MM = (-6.0, -3.0, 0.0, 3.0, 6.0)
"""Displacements of the 0.2 mm cases (with the 0.5 mm cases' creepages, as CONTACT's run
used the same velocities)."""
TOLERANCES = {"contact": (1e-5, 1e-5), "paper": (1e-3, 1e-2)}
STARTS = {"none": ("none", "none"), "infcon+fastrip": ("infcon", "fastrip")}


def contact_rows(folder: Path, dx_mm: float) -> list[dict]:
    """CONTACT's rows (default tolerance) of the cases at element size ``dx_mm``: for
    0.2 mm the 0.5 mm rows at :data:`FINE_Y_MM` (creepages and kinematics)."""
    with (folder / "wheelrail_dx0.5.csv").open() as f:
        rows = [r for r in csv.DictReader(f) if r["tol"] == "default"]
    if math.isclose(dx_mm, 0.2):
        return [r for r in rows if float(r["y_mm"]) in FINE_Y_MM]
    return [r for r in rows if math.isclose(float(r["dx_mm"]), dx_mm)]


def wheel_case(row: dict, dx_mm: float, tol: tuple[float, float], start: tuple[str, str],
               profiles: Path, solver: str | None, patch_frame: str = "reference",
               convention: str = "contact") -> dict:
    """The case of one CONTACT row: the wheel of the row's side at CONTACT's y negated (its
    wheelset y runs to the right), with CONTACT's creepages (``phi [1/m] = cphi [rad/mm] x
    1000``). In ``convention = "contact"`` they are read as CONTACT's and the forces are
    reported as CONTACT's (on the rail: compare FX, FS, MN directly); in
    ``"railcontact"`` they are turned into railcontact's roles here
    (:mod:`railcontact.settings.convention`: ``xi = -cksi``, ``(eta, phi) = s (ceta,
    cphi)``, s = 1 left, -1 right) and the forces compare as ``F_x = -FX``,
    ``(F_s, M_n) = s (FS, MN)``."""
    y = float(row["y_mm"]) * 1e-3
    creepage = [float(row["cksi"]), float(row["ceta"]), float(row["cphi"]) * 1e3]
    if convention == "railcontact":
        creepage = list(side_creepage(creepage, row["side"], "contact"))
    tangential = {"friction": 0.4, "estimate": start[1], "tolerance": tol[1],
                  "creepage": creepage}
    if solver:
        tangential["solver"] = solver
    return {
        "convention": convention,
        "material": {"young": 2 * 82e9 * 1.28, "poisson": 0.28},
        "geometry": {"type": "wheel-rail", "wheel": str(profiles / "MBench_S1002_v3.prw"),
                     "rail": str(profiles / "MBench_UIC60_v3.prr"), "inclination": 0.0,
                     "gauge": 1.435, "back_to_back": 1.360, "wheel_radius": 0.46,
                     "lateral_displacement": -y, "side": row["side"],
                     "patch_frame": patch_frame},
        "grid": {"dx": dx_mm * 1e-3, "dy": dx_mm * 1e-3},
        "normal": {"load": 83.3e3, "tolerance": tol[0], "estimate": start[0]},
        "tangential": tangential,
    }


def run(rows: list[dict], dx_mm: float, tol: tuple[float, float], start: tuple[str, str],
        profiles: Path, solver: str | None) -> list[dict]:
    """Solve every case once (operators and plans from empty caches, as CONTACT's run
    sets up its own); per case: seconds and summed work."""
    clear_caches()
    out = []
    for row in rows:
        case = wheel_case(row, dx_mm, tol, start, profiles, solver)
        t0 = time.perf_counter()
        try:
            sol = rc.solve(case)
            ok = all(p.normal.converged and (p.tangential is None or p.tangential.converged)
                     for p in sol.patches)  # (Solution.converged in newer versions)
        except (rc.RailContactError, rc.SolverError) as exc:
            print(f"  y = {row['y_mm']} {row['side']}: {exc}", file=sys.stderr)
            continue
        dt = time.perf_counter() - t0
        w = sol.work
        out.append({"y_mm": float(row["y_mm"]), "side": row["side"], "seconds": dt,
                    "normal": w.normal_iterations, "tangential": w.tangential_iterations,
                    "passes": w.load_passes, "converged": ok,
                    "cg_contact": int(row["cg_its_sum"]),
                    "sweeps_contact": int(row["tang_its_sum"]),
                    "passes_contact": int(row["nr_its"])})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fine", action="store_true", help="also the 0.2 mm cases (minutes)")
    ap.add_argument("--solver", default=None, help="[tangential] solver (default: the "
                    "case default)")
    ap.add_argument("--csv", type=Path, default=None, help="write the per-case rows")
    ap.add_argument("--contact", type=Path, default=CONTACT_REFERENCE)
    ap.add_argument("--profiles", type=Path, default=PROFILES)
    args = ap.parse_args()

    sizes = [0.5] + ([0.2] if args.fine else [])
    warm = contact_rows(args.contact, 0.5)[:2]
    for start in STARTS.values():  # jit (or numba's cache loaded), each start's kernels
        run(warm, 0.5, TOLERANCES["contact"], start, args.profiles, args.solver)
    ref = fixed_workload()
    print(f"fixed workload (128^2 FFT round trips x 200 + 600^2 mat-vec x 400): "
          f"{ref * 1e3:.1f} ms")
    print(f"{'dx':>4} {'tol':<8} {'start':<15} {'cases':>5} {'ms/case':>8} {'/ wkld':>7} "
          f"{'CONTACT':>7} {'ratio':>6} {'CG':>6} {'sweeps':>6} {'passes':>6} {'failed':>6}")
    all_rows = []
    for dx in sizes:
        rows = contact_rows(args.contact, dx)
        if not rows:
            print(f"  no CONTACT rows for dx = {dx} mm in {args.contact}", file=sys.stderr)
            continue
        if dx == 0.5:
            cg = statistics.mean(int(r["cg_its_sum"]) for r in rows)
            sw = statistics.mean(int(r["tang_its_sum"]) for r in rows)
            nr = f"{statistics.mean(int(r['nr_its']) for r in rows):6.1f}"
        else:
            cg, sw, nr = CONTACT_FINE["cg"], CONTACT_FINE["sweeps"], f"{'':>6}"
        print(f"{dx:4.1f} {'CONTACT':<8} {'(its own)':<15} {len(rows):5d} {'':>8} "
              f"{CONTACT_RATIO[dx]:7.2f} {'':>7} {'':>6} {cg:6.1f} {sw:6.1f} {nr}")
        for tname, tol in TOLERANCES.items():
            for sname, start in STARTS.items():
                res = run(rows, dx, tol, start, args.profiles, args.solver)
                ms = statistics.mean(r["seconds"] for r in res) * 1e3
                ratio = ms / 1e3 / ref
                failed = len(rows) - sum(r["converged"] for r in res)
                print(f"{dx:4.1f} {tname:<8} {sname:<15} {len(res):5d} {ms:8.1f} "
                      f"{ratio:7.2f} {CONTACT_RATIO[dx]:7.2f} "
                      f"{ratio / CONTACT_RATIO[dx]:6.2f} "
                      f"{statistics.mean(r['normal'] for r in res):6.1f} "
                      f"{statistics.mean(r['tangential'] for r in res):6.1f} "
                      f"{statistics.mean(r['passes'] for r in res):6.1f} {failed:6d}",
                      flush=True)
                all_rows += [{"dx_mm": dx, "tol": tname, "start": sname, **r,
                              "ratio": r["seconds"] / ref} for r in res]
    print("ratio: railcontact's time / CONTACT's, both relative to the fixed workload "
          "(target <= 0.7 at eps = 1e-5)")
    if args.csv:
        write_csv(args.csv, all_rows)
        print(f"written {args.csv}")


if __name__ == "__main__":
    main()
