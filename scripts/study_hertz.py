"""Study: iterations with and without initial estimates on Hertz cases (paper Fig. 3, 11).

A = 0.001 /mm (1 /m), B from 2e-4 to 1e-2 /mm (0.2 .. 10 /m), steel, penetration 0.1 mm,
eps_n = 1e-3; rolling with xi = 0.001, mu = 0.4, eps_tau = 1e-2. Normal estimates none /
Hertz / KP / INFCON, tangential none / FASTSIM / FaStrip. Writes a CSV and a PNG and prints
the table beside the paper's ranges (normal: none 13-17, INFCON 1-5; tangential: none
24-33, FaStrip 8-19).

``--preconditioner none`` runs the normal BEM as the paper's plain Polonsky–Keer CG
(default: with railcontact's FFT preconditioner).

Usage: python scripts/study_hertz.py [--n 12] [--grid 64] [--preconditioner fft|none]
       [--out out/]
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np
from _sweep import save_figure, write_csv

import railcontact as rc
from railcontact.io.plotting import _pyplot

BASE = {
    "material": {"young": 206e9, "poisson": 0.28},
    "geometry": {"type": "quadratic", "A": 1.0, "B": 5.0},
    "grid": {"nx": 64, "ny": 64},
    "normal": {"penetration": 1e-4, "tolerance": 1e-3},
    "tangential": {"creepage": [1e-3, 0.0, 0.0], "friction": 0.4, "tolerance": 1e-2,
                   "solver": "convexgs"},  # the paper's solver
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=12, help="number of B values")
    ap.add_argument("--grid", type=int, default=64, help="elements per direction")
    ap.add_argument("--preconditioner", choices=("fft", "none"), default="fft",
                    help="normal BEM: with the FFT preconditioner, or plain PK CG (paper)")
    ap.add_argument("--out", type=Path, default=Path("out"))
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    rows = []
    print(f"{'B [1/mm]':>9} | normal iterations: {'none':>5} {'hertz':>5} {'kp':>5} "
          f"{'infcon':>6} | tangential sweeps: {'none':>5} {'fastsim':>7} {'fastrip':>7}")
    for b in np.geomspace(2e-4, 1e-2, args.n):
        row = {"B_per_mm": b}
        for est in ("none", "hertz", "kp", "infcon"):
            c = copy.deepcopy(BASE)
            c["geometry"]["B"] = b * 1e3
            c["grid"] = {"nx": args.grid, "ny": args.grid}
            c["normal"].update(estimate=est, preconditioner=args.preconditioner)
            if est != "none":
                del c["tangential"]
            sol = rc.solve(c)
            row[f"normal_{est}"] = sol.patches[0].normal.iterations
            if est == "none":
                row["tangential_none"] = sol.patches[0].tangential.iterations
                for test in ("fastsim", "fastrip"):
                    c2 = copy.deepcopy(c)
                    c2["tangential"]["estimate"] = test
                    row[f"tangential_{test}"] = rc.solve(c2).patches[0].tangential.iterations
        rows.append(row)
        print(f"{b:9.2e} | {'':19}{row['normal_none']:5d} {row['normal_hertz']:5d} "
              f"{row['normal_kp']:5d} {row['normal_infcon']:6d} | {'':18}"
              f"{row['tangential_none']:5d} {row['tangential_fastsim']:7d} "
              f"{row['tangential_fastrip']:7d}")
    keys = list(rows[0])
    means = {k: float(np.mean([r[k] for r in rows])) for k in keys[1:]}
    print("mean      | " + " ".join(f"{k}={v:.2f}" for k, v in means.items()))
    print("paper     | normal: none 13-17, INFCON 1-5; tangential: none 24-33, FaStrip 8-19")
    write_csv(args.out / "study_hertz.csv", rows)

    plt = _pyplot()

    bs = [r["B_per_mm"] for r in rows]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4), constrained_layout=True)
    for est in ("none", "hertz", "kp", "infcon"):
        a1.semilogx(bs, [r[f"normal_{est}"] for r in rows], "o-", label=est)
    a1.set_title("normal BEM (PK CG), eps_n = 1e-3")
    for est in ("none", "fastsim", "fastrip"):
        a2.semilogx(bs, [r[f"tangential_{est}"] for r in rows], "o-", label=est)
    a2.set_title("tangential BEM (ConvexGS), eps_tau = 1e-2")
    save_figure(fig, (a1, a2), args.out, "study_hertz", xlabel="B [1/mm] (A = 0.001 /mm)",
                legend_size=None)


if __name__ == "__main__":
    main()
