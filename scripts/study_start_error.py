"""Study: normal CG iterations against the error of the start (the paper's -69 %, Sec. 4.1.2).

S1002 on CN60 (``--rail``) at 1:40, 83.3 kN, left wheel, 64 x 64 elements, each patch
penetration-controlled at the approach that carries 83.3 kN (as ``study_sweep.py``). Per
displacement the BEM is converged to eps_n = 1e-10 from INFCON; its solution ``p*`` is the
reference and INFCON's start ``p_I`` on the same grid (``PatchSolution.estimate_error``)
gives the estimate's error. Three tables:

1. **Iterations against the start's error.** On ``--table`` displacements (default seven,
   -6 .. 6 mm), starts blended from ``p*`` towards ``p_I``, ``p* + t (p_I - p*)``, with
   ``t`` chosen for an L1 error ``sum |p - p*| / sum p*`` of 0.5, 1, 2, 5, 10, 20 % (only
   where that is at most INFCON's own error, ``t <= 1``; else "-"), solved at eps_n = 1e-3
   with the plain Polonsky-Keer CG and with the FFT preconditioner. Mean iterations and
   the number of displacements in each column; "INFCON" is ``t = 1``.
2. **Looser stops.** Over the displacements -8 .. 8 mm in ``--step`` mm: mean iterations
   from no estimate and from INFCON at eps_n = 1e-3 and 1e-2, both solvers, and the force
   error of the 1e-2 solution against ``p*``. "force stop on the start" is the count when
   a start whose force is within eps_n of the converged force is accepted without a CG
   step (0 iterations) - an oracle test (it knows the converged force), the most any stop
   tested on the estimate itself can save.
3. **The start's error** over the same displacements: INFCON's L1 error, elements missing
   and extra, per region of the sweep.

Usage: python scripts/study_start_error.py [--rail CN60] [--step 0.5]
                                           [--table -6 -4 -2 0 2 4 6] [--out out/]
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np
from _sweep import approach_for_load, paper_case, report_failed, run_sweep, write_csv

import railcontact as rc
from railcontact.halfspace.operator import influence_operator
from railcontact.normal import solve_normal
from railcontact.normal.starterror import estimate_error

TARGETS = (0.005, 0.01, 0.02, 0.05, 0.10, 0.20)
SOLVERS = ("none", "fft")  # preconditioner
REFERENCE_TOLERANCE = 1e-10
PAPER = {"none": 13.84, "infcon": 4.27, "infcon 1e-2": 0.69}
"""The paper's mean iterations (Fig. 7 at eps_n = 1e-3; Sec. 4.1.3 at 1e-2)."""


def reference(dy: float, rail: str) -> dict:
    """The converged patch at ``dy`` [m] on ``rail``: its grid, gap, penetration, the
    converged pressure and INFCON's start on its grid."""
    c = paper_case()
    c["geometry"].update(rail=rail, lateral_displacement=dy)
    pen = approach_for_load(c, 83.3e3)
    c = copy.deepcopy(c)
    c["normal"] = {"penetration": pen, "tolerance": REFERENCE_TOLERANCE, "estimate": "infcon"}
    case = rc.Case.from_dict(c)
    patches = rc.solve(case).patches
    if len(patches) != 1:
        raise rc.RailContactError(f"{len(patches)} patches at {dy * 1e3:+.2f} mm")
    patch = patches[0]
    n = patch.normal
    if not n.converged or n.start is None:
        raise rc.RailContactError(f"reference at {dy * 1e3:+.2f} mm: {n.message} "
                                  f"({patch.estimate})")
    return {"grid": n.grid, "gap": patch.geometry.gap_on_grid(n.grid),
            "penetration": n.penetration, "pressure": n.pressure, "force": n.force,
            "infcon": np.maximum(n.start, 0.0), "pair": case.pair}


def solve_from(ref: dict, start: np.ndarray | None, tolerance: float, pre: str):
    """The CG from ``start`` on the reference's grid (penetration control)."""
    op = influence_operator(ref["grid"], ref["pair"], "z")
    return solve_normal(ref["gap"], ref["grid"], op, penetration=ref["penetration"],
                        initial_pressure=start, tolerance=tolerance, preconditioner=pre)


def blended_row(dy: float, rail: str) -> list[dict]:
    """Table 1 at one displacement: iterations from starts of each target error."""
    ref = reference(dy, rail)
    p, pi = ref["pressure"], ref["infcon"]
    l1 = estimate_error(pi, p).l1
    row = {"dy_mm": dy * 1e3, "infcon_l1": l1}
    for target in (*TARGETS, None):
        t = 1.0 if target is None else target / l1
        name = "infcon" if target is None else f"{target * 100:g}%"
        for pre in SOLVERS:
            its = None
            if t <= 1.0:
                start = p + t * (pi - p)
                its = solve_from(ref, start, 1e-3, pre).iterations
            row[f"{pre}_{name}"] = its
    return [row]


def stop_row(dy: float, rail: str) -> list[dict]:
    """Tables 2 and 3 at one displacement."""
    ref = reference(dy, rail)
    p, pi = ref["pressure"], ref["infcon"]
    e = estimate_error(pi, p)
    area = ref["grid"].element_area
    start_force_error = abs(pi.sum() * area - ref["force"]) / ref["force"]
    row = {"dy_mm": dy * 1e3, "l1": e.l1, "missing": e.missing_share,
           "extra": e.extra_share, "start_force_error": start_force_error}
    for pre in SOLVERS:
        for tol in (1e-3, 1e-2):
            for name, start in (("none", None), ("infcon", pi)):
                res = solve_from(ref, start, tol, pre)
                key = f"{pre}_{name}_{tol:g}"
                row[key] = res.iterations
                row[f"{key}_force_error"] = abs(res.force - ref["force"]) / ref["force"]
            row[f"{pre}_infcon_{tol:g}_forcestop"] = (0 if start_force_error < tol
                                                      else row[f"{pre}_infcon_{tol:g}"])
    return [row]


def _mean(rows: list[dict], key: str) -> tuple[float, int]:
    v = [r[key] for r in rows if r[key] is not None]
    return (float(np.mean(v)) if v else float("nan")), len(v)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rail", default="CN60")
    ap.add_argument("--step", type=float, default=0.5, help="displacement step [mm]")
    ap.add_argument("--table", type=float, nargs="+", default=[-6, -4, -2, 0, 2, 4, 6],
                    help="displacements of table 1 [mm]")
    ap.add_argument("--out", type=Path, default=Path("out"))
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    rows, failed = run_sweep(np.array(args.table) * 1e-3,
                             lambda dy: blended_row(dy, args.rail))
    report_failed(failed)
    write_csv(args.out / "study_start_error_blend.csv", rows)
    names = [f"{t * 100:g}%" for t in TARGETS] + ["infcon"]
    print(f"S1002 on {args.rail}, 64 x 64, penetration control (83.3 kN), eps_n = 1e-3; "
          f"{len(rows)} displacements {args.table} mm")
    l1 = [r["infcon_l1"] * 100 for r in rows]
    print(f"1. iterations against the start's L1 error (converged pressure blended towards "
          f"INFCON; INFCON's own error here {np.mean(l1):.2f} % on the mean, "
          f"{min(l1):.2f} .. {max(l1):.2f} %)")
    print("| start L1 error | " + " | ".join(n if n != "infcon" else "INFCON itself"
                                            for n in names) + " |")
    print("|---|" + "---|" * len(names))
    for pre, label in (("none", "plain PK CG"), ("fft", "FFT-preconditioned CG")):
        cells = []
        for n in names:
            m, k = _mean(rows, f"{pre}_{n}")
            cells.append("–" if k == 0 else (f"{m:.2f}" if k == len(rows) else
                                             f"{m:.2f} ({k})"))
        print(f"| {label}, mean iterations | " + " | ".join(cells) + " |")
    print("(in brackets: the displacements where INFCON's error is at least the target)")

    step_rows, failed = run_sweep(np.round(np.arange(-8.0, 8.0 + 1e-9, args.step), 6) * 1e-3,
                                  lambda dy: stop_row(dy, args.rail))
    report_failed(failed)
    write_csv(args.out / "study_start_error_stop.csv", step_rows)
    n = len(step_rows)
    print(f"\n2. looser stops, {n} displacements -8 .. 8 mm in {args.step} mm steps "
          f"(mean iterations; force error of the solution against eps_n = 1e-10, %)")
    print("| eps_n | solver | none | INFCON | INFCON, force stop on the start (oracle) "
          "| force error: none / INFCON |")
    print("|---|---|---|---|---|---|")
    for tol in (1e-3, 1e-2):
        for pre, label in (("none", "plain"), ("fft", "preconditioned")):
            k = f"{pre}_{{}}_{tol:g}"
            print(f"| {tol:g} | {label} | {_mean(step_rows, k.format('none'))[0]:.2f} | "
                  f"{_mean(step_rows, k.format('infcon'))[0]:.2f} | "
                  f"{_mean(step_rows, k.format('infcon') + '_forcestop')[0]:.2f} | "
                  f"{100 * _mean(step_rows, k.format('none') + '_force_error')[0]:.3f} / "
                  f"{100 * _mean(step_rows, k.format('infcon') + '_force_error')[0]:.3f} |")
    accepted = {tol: sum(r["start_force_error"] < tol for r in step_rows)
                for tol in (1e-3, 1e-2)}
    print(f"INFCON's start carries the converged force within 1e-3 on {accepted[1e-3]} and "
          f"within 1e-2 on {accepted[1e-2]} of {n} displacements (start force error: mean "
          f"{100 * _mean(step_rows, 'start_force_error')[0]:.2f} %)")
    print(f"paper: none {PAPER['none']}, INFCON {PAPER['infcon']} at 1e-3; INFCON "
          f"{PAPER['infcon 1e-2']} at 1e-2")

    print(f"\n3. INFCON's start error over the {n} displacements (% of the converged "
          "pressure / contact elements)")
    print("| Δy [mm] | cases | L1 mean | L1 median | missing | extra |")
    print("|---|---|---|---|---|---|")
    edges = [(-8.0, -0.4), (-0.3, 4.8), (4.9, 6.6), (6.7, 8.0), (-8.0, 8.0)]
    for lo, hi in edges:
        sel = [r for r in step_rows if lo - 1e-9 <= r["dy_mm"] <= hi + 1e-9]
        if not sel:
            continue
        v = np.array([[r["l1"], r["missing"], r["extra"]] for r in sel], dtype=float) * 100
        print(f"| {lo:g} … {hi:g} | {len(sel)} | {v[:, 0].mean():.2f} | "
              f"{np.median(v[:, 0]):.2f} | {v[:, 1].mean():.2f} | {v[:, 2].mean():.2f} |")
    print(args.out / "study_start_error_blend.csv", args.out / "study_start_error_stop.csv")


if __name__ == "__main__":
    main()
