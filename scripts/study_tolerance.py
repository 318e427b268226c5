"""Study: the tolerances eps_n and eps_tau against a tight reference (paper Tables 4 and 6).

The lateral sweep of ``study_sweep.py`` (S1002 on 60E1 at 1:40, left wheel, -8 .. 8 mm,
64 x 64 elements). For each displacement the vertical approach that carries 83.3 kN is
found first (load control, eps_n = 1e-9); the normal BEM is then run penetration-controlled
with that approach (as the paper does, so that the force has an error), INFCON estimate, at
eps_n = 1e-2, 1e-3, 1e-5, 1e-7 against eps_n = 1e-10; the tangential BEM (FaStrip estimate,
Table 5 case 2: xi = eta = 2e-4, phi = 0.2 /m, mu = 0.4) on the reference pressure at
eps_tau = 1e-1, 1e-2, 1e-3, 1e-5 against eps_tau = 1e-8. Per patch: iterations and the
relative errors of the maximum pressure, contact area and normal force (normal) and of the
maximum traction, slip area and creep force |F| (tangential). Prints the means beside the
paper's tables, writes a CSV and a PNG.

Usage: python scripts/study_tolerance.py [--step 0.1] [--out out/]
"""

from __future__ import annotations

import argparse
import copy
import math
from pathlib import Path

import numpy as np
from _sweep import (
    approach_for_load,
    displacements,
    paper_case,
    report_failed,
    run_sweep,
    save_figure,
    write_csv,
)

import railcontact as rc
from railcontact.io.plotting import _pyplot

BASE = paper_case()
NORMAL_TOLS = (1e-2, 1e-3, 1e-5, 1e-7)
NORMAL_REF = 1e-10
TANGENTIAL_TOLS = (1e-1, 1e-2, 1e-3, 1e-5)
TANGENTIAL_REF = 1e-8
CREEPAGE = [2e-4, 2e-4, 0.2]
PAPER_NORMAL = {1e-2: (0.69, 1.56, 3.73, 0.63), 1e-3: (4.40, 0.40, 2.05, 0.10),
                1e-5: (13.46, 0.34, 1.58, 0.04), 1e-7: (22.42, 0.14, 0.60, 0.01)}
PAPER_TANGENTIAL = {1e-1: (3.17, 1.23, 1.67, 3.38), 1e-2: (10.61, 0.14, 0.27, 7.87e-2),
                    1e-3: (29.55, 5.9e-2, 7.98e-2, 6.51e-3),
                    1e-5: (66.21, 5.58e-4, 3.34e-4, 1.26e-4)}


def _rel(a: float, b: float) -> float:
    return abs(a - b) / abs(b) if b != 0 else (0.0 if a == 0 else math.inf)


def one_case(dy: float) -> list[dict]:
    base = copy.deepcopy(BASE)
    base["geometry"]["lateral_displacement"] = dy
    approach = approach_for_load(base, 83.3e3)

    def normal(tol: float):
        c = copy.deepcopy(base)
        c["normal"] = {"penetration": approach, "tolerance": tol, "estimate": "infcon",
                       "max_iterations": 2000}
        return rc.solve(c)

    def tangential(tol: float):
        c = copy.deepcopy(base)
        c["normal"] = {"penetration": approach, "tolerance": NORMAL_REF, "estimate": "infcon",
                       "max_iterations": 2000}
        c["tangential"] = {"creepage": CREEPAGE, "friction": 0.4, "tolerance": tol,
                           "estimate": "fastrip", "max_iterations": 5000,
                           "solver": "convexgs"}  # the paper's solver
        return rc.solve(c)

    ref_n = normal(NORMAL_REF)
    if not ref_n.converged:  # (every error of the rows is measured against it)
        raise rc.SolverError(f"{dy * 1e3:+.2f} mm: the normal reference did not converge")
    rows = [{"dy_mm": dy * 1e3, "patch": k} for k in range(len(ref_n.patches))]
    for tol in NORMAL_TOLS:
        sol = normal(tol)
        if len(sol.patches) != len(ref_n.patches):
            raise rc.RailContactError("patch count changed with eps_n")
        for row, p, r in zip(rows, sol.patches, ref_n.patches, strict=True):
            row[f"n{tol:g}_it"] = p.normal.iterations
            row[f"n{tol:g}_p"] = _rel(p.normal.max_pressure, r.normal.max_pressure)
            row[f"n{tol:g}_area"] = _rel(p.normal.area, r.normal.area)
            row[f"n{tol:g}_force"] = _rel(p.normal.force, r.normal.force)
    ref_t = tangential(TANGENTIAL_REF)
    for tol in TANGENTIAL_TOLS:
        sol = tangential(tol)
        for row, p, r in zip(rows, sol.patches, ref_t.patches, strict=True):
            t, tr = p.tangential, r.tangential
            row[f"t{tol:g}_it"] = t.iterations
            row[f"t{tol:g}_q"] = _rel(t.max_traction, tr.max_traction)
            row[f"t{tol:g}_slip"] = _rel(t.slip_area_ratio, tr.slip_area_ratio)
            row[f"t{tol:g}_force"] = _rel(float(np.hypot(*t.force)), float(np.hypot(*tr.force)))
    for row, r in zip(rows, ref_t.patches, strict=True):
        row["ref_t_converged"] = int(r.tangential.converged)
    return rows


def print_table(title: str, header: str, d: dict, prefix: str, tols: tuple,
                errors: tuple[str, str, str], fmt: str, paper: dict) -> None:
    """One Markdown table: per tolerance the mean iterations and errors [%] beside the
    paper's."""
    print(f"\n{title}")
    print(header)
    print("|---|---|---|---|---|---|---|---|---|")
    for tol in tols:
        k = f"{prefix}{tol:g}"
        errs = " | ".join(f"{100 * d[f'{k}_{e}'].mean():{fmt}}" for e in errors)
        print(f"| {tol:g} | {d[k + '_it'].mean():.2f} | {errs} | "
              + " | ".join(str(x) for x in paper[tol]) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=0.1, help="displacement step [mm]")
    ap.add_argument("--out", type=Path, default=Path("out"))
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    dys = displacements(args.step)
    rows, failed = run_sweep(dys, one_case)
    keys = list(rows[0])
    write_csv(args.out / "study_tolerance.csv", rows)
    d = {k: np.array([r[k] for r in rows], dtype=float) for k in keys}
    print(f"{len(dys)} displacements, {len(rows)} patches, {len(failed)} failed; "
          f"tangential reference converged on {int(d['ref_t_converged'].sum())}")
    report_failed(failed)
    print_table(f"normal (INFCON estimate, penetration control), mean over patches; "
                f"reference eps_n = {NORMAL_REF:g}",
                "| eps_n | iterations | max pressure err. % | area err. % | force err. % | "
                "paper: iterations | pressure % | area % | force % |",
                d, "n", NORMAL_TOLS, ("p", "area", "force"), ".3f", PAPER_NORMAL)
    print_table(f"tangential (FaStrip estimate, Table 5 case 2), mean over patches; "
                f"reference eps_tau = {TANGENTIAL_REF:g}",
                "| eps_tau | sweeps | max traction err. % | slip area err. % | "
                "creep force err. % | paper: iterations | col. 2 % | col. 3 % | col. 4 % |",
                d, "t", TANGENTIAL_TOLS, ("q", "slip", "force"), ".3g", PAPER_TANGENTIAL)

    plt = _pyplot()

    fig, ax = plt.subplots(1, 2, figsize=(12, 4.2), constrained_layout=True)
    for tol in NORMAL_TOLS:
        k = f"n{tol:g}"
        ax[0].semilogy(d["dy_mm"], np.maximum(d[k + "_force"], 1e-12), ".", ms=3,
                       label=f"eps_n = {tol:g} ({d[k + '_it'].mean():.1f} it.)")
    for tol in TANGENTIAL_TOLS:
        k = f"t{tol:g}"
        ax[1].semilogy(d["dy_mm"], np.maximum(d[k + "_force"], 1e-12), ".", ms=3,
                       label=f"eps_tau = {tol:g} ({d[k + '_it'].mean():.1f} sweeps)")
    ax[0].set_title("normal force, relative error (penetration control)", fontsize=10)
    ax[1].set_title("creep force |F|, relative error (Table 5 case 2)", fontsize=10)
    save_figure(fig, ax, args.out, "study_tolerance", ylabel="relative error")


if __name__ == "__main__":
    main()
