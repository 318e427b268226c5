"""Study: mean iterations over the lateral sweep (paper Fig. 7 and 15).

S1002 on 60E1 at 1:40, 83.3 kN per wheel (the paper: S1002CN on CN60), lateral wheelset
displacement -8 .. 8 mm (left wheel). As in the paper, the vertical approach that carries
83.3 kN is found first and the solves are penetration-controlled with it (``--control
load``: load-controlled, the estimates then carry the load too). Normal: estimates none /
Hertz / KP / INFCON at eps_n = 1e-3, with railcontact's default solver (Polonsky–Keer CG
with the FFT preconditioner) and with the paper's plain Polonsky–Keer CG (columns
``normal_pk_*``). Tangential (normal started from INFCON): none /
FASTSIM / FaStrip at eps_tau = 1e-2, mu = 0.4, for the creepages of the paper's Table 5
(xi = eta = c, phi = c /mm with c = 0.5e-4, 2e-4, 5e-4). Patches of two-point contact
count separately. Under load control the creep forces count in the wheel load and the
load loop solves the tangential problem once a pass, each pass after the first started
from the one before: a patch's count is then all of its sweeps (its work's). Writes a CSV
and a PNG and prints the means beside the paper's
(normal 13.84 / 14.90 / 5.65 / 4.27; tangential 23.02 / 22.71 / 9.92).

The wheelset is not rolled (the paper says nothing of roll); ``--roll equal-loads`` (or
``rigid``) rolls it as a wheelset on both rails carrying 83.3 kN per wheel (or touching both
rails), the roll found once per displacement and then held for every solve.

Another profile pair (the paper's S1002CN on CN60, when their files are at hand): ``--wheel``
and ``--rail`` take built-in names or profile files, ``--back-to-back`` [m] and
``--inclination`` [rad] the wheelset and track (defaults 1.360 m, 1:40).

Usage: python scripts/study_sweep.py [--step 0.1] [--control penetration|load]
                                     [--roll 0|rigid|equal-loads] [--out out/]
                                     [--wheel S1002] [--rail 60E1] [--back-to-back 1.360]
                                     [--inclination 0.025]
                                     [--patch-frame rigid|reference]
(0.01 mm: 1601 cases)
"""

from __future__ import annotations

import argparse
import copy
import functools
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

CASE = {**paper_case(), "normal": {"load": 83.3e3, "tolerance": 1e-3}}
CREEP = {"case1": 0.5e-4, "case2": 2e-4, "case3": 5e-4}
NORMAL = ("none", "hertz", "kp", "infcon")
SOLVERS = {"fft": "normal", "none": "normal_pk"}  # preconditioner -> column prefix
PAPER = {"normal_none": 13.84, "normal_hertz": 14.90, "normal_kp": 5.65, "normal_infcon": 4.27,
         "tangential_none": 23.02, "tangential_fastsim": 22.71, "tangential_fastrip": 9.92}


def wheelset_roll(dy: float, mode: str) -> float:
    """Roll [rad] of the wheelset at ``dy`` on both rails: ``mode`` "rigid" or
    "equal-loads" (83.3 kN per wheel)."""
    c = copy.deepcopy(CASE)
    c["geometry"].update(lateral_displacement=dy, side="both", roll=mode)
    c["normal"]["estimate"] = "infcon"
    return rc.solve(c).roll


def one_case(dy: float, control: str = "penetration", roll: str = "0") -> list[dict]:
    rows = []
    base = copy.deepcopy(CASE)
    base["geometry"]["lateral_displacement"] = dy
    solved = roll in ("rigid", "equal-loads")
    base["geometry"]["roll"] = wheelset_roll(dy, roll) if solved else float(roll)
    if control == "penetration":
        nspec = base.pop("normal")
        base["normal"] = {"penetration": approach_for_load(base, nspec["load"]),
                          "tolerance": nspec["tolerance"]}
    normal_its: dict[str, list[int]] = {}
    start_errors: dict[str, list[float | None]] = {}
    for pre, prefix in SOLVERS.items():
        for est in NORMAL:
            c = copy.deepcopy(base)
            c["normal"].update(estimate=est, preconditioner=pre)
            sol = rc.solve(c)
            normal_its[f"{prefix}_{est}"] = [p.normal.iterations for p in sol.patches]
            if pre == "fft" and est in ("kp", "infcon"):  # how good the start was
                errs = [p.estimate_error for p in sol.patches]
                start_errors[f"{est}_l1"] = [None if e is None else e.l1 for e in errs]
                start_errors[f"{est}_missing"] = [None if e is None else e.missing_share
                                                  for e in errs]
                start_errors[f"{est}_extra"] = [None if e is None else e.extra_share
                                                for e in errs]
    for k, patch_its in enumerate(zip(*normal_its.values(), strict=True)):
        rows.append({"dy_mm": dy * 1e3, "patch": k, "roll_mrad": base["geometry"]["roll"] * 1e3,
                     **dict(zip(normal_its, patch_its, strict=True)),
                     **{name: v[k] for name, v in start_errors.items()}})
    for name, cr in CREEP.items():
        tan_its = {}
        for est in ("none", "fastsim", "fastrip"):
            c = copy.deepcopy(base)
            c["normal"]["estimate"] = "infcon"
            c["tangential"] = {"creepage": [cr, cr, cr * 1e3], "friction": 0.4,
                               "tolerance": 1e-2, "estimate": est, "solver": "convexgs"}
            sol = rc.solve(c)
            # under load control the creep forces count in the load: the loop solves the
            # tangential problem once a pass, each pass after the first from the one
            # before, so a patch's sweeps are its work's (the first pass's, from the
            # estimate, and about one a later pass)
            tan_its[est] = [p.work.tangential_iterations if control == "load"
                            else p.tangential.iterations for p in sol.patches]
        for k in range(len(rows)):
            for est, v in tan_its.items():
                rows[k][f"{name}_{est}"] = v[k]
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=0.1, help="displacement step [mm]")
    ap.add_argument("--control", choices=("penetration", "load"), default="penetration",
                    help="penetration (the approach for 83.3 kN, as the paper) or load")
    ap.add_argument("--roll", default="0",
                    help="wheelset roll: an angle [rad], 'rigid' or 'equal-loads'")
    ap.add_argument("--out", type=Path, default=Path("out"))
    ap.add_argument("--wheel", default="S1002", help="built-in wheel or profile file")
    ap.add_argument("--rail", default="60E1", help="built-in rail or profile file")
    ap.add_argument("--back-to-back", type=float, default=1.360, help="flange-back distance [m]")
    ap.add_argument("--inclination", type=float, default=math.atan(1 / 40), help="rail cant [rad]")
    ap.add_argument("--patch-frame", choices=("rigid", "reference"), default="rigid",
                    help="each patch at its rigid contact point (as the paper) or at CONTACT's "
                         "reference point")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    CASE["geometry"].update(wheel=args.wheel, rail=args.rail, back_to_back=args.back_to_back,
                            inclination=args.inclination, patch_frame=args.patch_frame)
    dys = displacements(args.step)
    rows, failed = run_sweep(dys, functools.partial(one_case, control=args.control,
                                                    roll=args.roll))
    print(f"{args.wheel} on {args.rail}, back-to-back {args.back_to_back} m, cant "
          f"{args.inclination:.5f} rad; {args.control} control, roll {args.roll}, patch "
          f"frame at the {args.patch_frame} point")
    keys = list(rows[0])
    write_csv(args.out / "study_sweep.csv", rows)
    mean = {k: float(np.mean([r[k] for r in rows])) for k in keys
            if k not in ("dy_mm", "patch", "roll_mrad") and not k.startswith(("kp_", "infcon_"))}
    print(f"{len(dys)} displacements, {len(rows)} patches, {len(failed)} failed")
    report_failed(failed)
    print(f"{'normal':<22} {'none':>7} {'hertz':>7} {'kp':>7} {'infcon':>7}")
    for label, prefix in (("railcontact", "normal"), ("plain PK CG", "normal_pk")):
        print(f"{label:<22} " + " ".join(f"{mean[f'{prefix}_{e}']:7.2f}" for e in NORMAL))
    print(f"{'paper (Fig. 7)':<22} " + " ".join(f"{PAPER[f'normal_{e}']:7.2f}" for e in NORMAL))
    worse = sum(r["normal_hertz"] > r["normal_none"] for r in rows)
    print(f"Hertz start costs more than none on {worse} of {len(rows)} patches")
    # the estimates' errors against the solution of their own (penetration-controlled:
    # the only) solve, in % (PatchSolution.estimate_error)
    for est in ("kp", "infcon"):
        err = {q: np.array([r[f"{est}_{q}"] for r in rows
                            if r.get(f"{est}_{q}") is not None], dtype=float) * 100
               for q in ("l1", "missing", "extra")}
        if err["l1"].size:
            print(f"{est} start error [%] over {err['l1'].size} patches: L1 mean "
                  f"{err['l1'].mean():.2f}, median {np.median(err['l1']):.2f}, p90 "
                  f"{np.percentile(err['l1'], 90):.2f}; elements missing "
                  f"{err['missing'].mean():.2f}, extra {err['extra'].mean():.2f} (of the "
                  "contact)")
    print(f"{'tangential':<22} {'none':>7} {'fastsim':>7} {'fastrip':>7}")
    for name in CREEP:
        print(f"{'railcontact ' + name:<22} " + " ".join(
            f"{mean[f'{name}_{e}']:7.2f}" for e in ("none", "fastsim", "fastrip")))
    allt = {e: float(np.mean([mean[f"{n}_{e}"] for n in CREEP]))
            for e in ("none", "fastsim", "fastrip")}
    print(f"{'railcontact, all':<22} " + " ".join(f"{allt[e]:7.2f}" for e in allt))
    print(f"{'paper (Fig. 15)':<22} " + " ".join(f"{PAPER[f'tangential_{e}']:7.2f}"
                                                for e in ("none", "fastsim", "fastrip")))

    plt = _pyplot()

    d = {k: np.array([r[k] for r in rows]) for k in keys}
    order = np.argsort(d["dy_mm"], kind="stable")
    fig, (a0, a1, a2) = plt.subplots(1, 3, figsize=(17, 4.2), constrained_layout=True)
    for ax, prefix, title in ((a0, "normal_pk", "plain PK CG (paper)"),
                              (a1, "normal", "PK CG + FFT preconditioner")):
        for e in NORMAL:
            ax.plot(d["dy_mm"][order], d[f"{prefix}_{e}"][order], ".-", ms=4, lw=0.5,
                    label=f"{e} (mean {mean[f'{prefix}_{e}']:.2f})")
        ax.set_title(f"normal, {title}, eps_n = 1e-3, {args.control} control", fontsize=9)
    for e in ("none", "fastsim", "fastrip"):
        a2.plot(d["dy_mm"][order], d[f"case2_{e}"][order], ".", ms=4,
                label=f"{e} (mean {mean[f'case2_{e}']:.2f})")
    a2.set_title("tangential BEM, Table 5 case 2, eps_tau = 1e-2", fontsize=9)
    save_figure(fig, (a0, a1, a2), args.out, "study_sweep")


if __name__ == "__main__":
    main()
