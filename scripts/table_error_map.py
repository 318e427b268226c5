"""The interpolation error of a realistic creep-force table before and after refinement
(docs/tables.md, "Error map and refinement").

The table: S1002 on 60E1 at 1:40, 0.5 mm elements, mu = 0.3, both wheels; lateral
displacement -8 .. 8 mm by 1 mm (17 nodes: tread, flange root and flange of both
wheels), wheel load 40/80/120 kN, xi and eta -2e-3/0/2e-3: 459 points x 2 wheels. Built
with ``--check`` (seed 1: the states refinement uses), refined along the lateral
displacement (``table refine``), and measured before and after at other random states
(seed 2: the same states and exact solves for both) against the exact solver.

Prints the build and refinement figures, the overall errors and the per-interval maxima
along the lateral displacement before and after; ``--plot FILE`` draws them (the error
map) with the normal force and contact angle of the left wheel against the lateral
displacement.

Usage: python scripts/table_error_map.py [--out DIR] [--workers N] [--states N]
       [--rounds R] [--plot FILE]
"""

from __future__ import annotations

import argparse
import math
import shutil
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from railcontact.table import ContactTable, parse_spec
from railcontact.table.build import build_table, close_client, connect
from railcontact.table.check import MEASURES, check_table, measure, overall, regions
from railcontact.table.refine import refine_table


def spec_dict() -> dict:
    return {
        "name": "error_map",
        "material": {"young": 206e9, "poisson": 0.28},
        "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                     "inclination": math.atan(1 / 40), "gauge": 1.435,
                     "back_to_back": 1.360, "wheel_radius": 0.46},
        "grid": {"dx": 0.5e-3, "dy": 0.5e-3},
        "normal": {"load": 80e3},
        "tangential": {"creepage": [0.0, 0.0, 0.0], "friction": 0.3},
        "table": {"lateral_displacement": [-0.008, 0.008, 17],
                  "load": [40e3, 120e3, 3],
                  "creepage_x": [-0.002, 0.002, 3],
                  "creepage_y": [-0.002, 0.002, 3]},
    }


def _open(path: Path) -> ContactTable:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ContactTable.open(path)


def _print_overall(label: str, chk) -> None:
    tot = overall(chk)
    parts = []
    for m in MEASURES:
        s, k = tot[m], 1e3 if m == "contact_angle" else 1.0
        unit = " mrad" if m == "contact_angle" else ""
        parts.append(f"{m} median {s['median'] * k:.3g}{unit} max {s['max'] * k:.3g}{unit}")
    print(f"  {label}: " + "; ".join(parts) + f"; holes {tot['holes']}, not solved "
          f"exactly {tot['unsolved']}")


def _lateral_rows(chk, table) -> list[dict]:
    return [r for r in regions(chk, table.axes) if r["axis"] == "lateral_displacement"]


def plot(before_rows, after_rows, before: ContactTable, after: ContactTable, chk,
         out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(2, 2, figsize=(10, 6.4), sharex=True)
    titles = {"normal_force": "|dN| / max(N, Q)", "creep_force": "|dF| / (mu max(N, Q))",
              "contact_angle": "|d gamma| [mrad]"}
    for ax, m in zip(axs.ravel()[:3], MEASURES, strict=True):
        k = 1e3 if m == "contact_angle" else 1.0
        for rows, label, style in ((before_rows, "before", "C3"),
                                   (after_rows, "after", "C0")):
            for r in rows:
                v = r[m]["max"]
                if v is not None and r[m]["n"]:
                    ax.plot([r["lo"] * 1e3, r["hi"] * 1e3], [v * k, v * k], color=style,
                            lw=2, label=label)
                    label = None
        ax.set_yscale("log")
        ax.set_title(f"max {titles[m]} per lateral interval", fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    ax = axs[1, 1]
    mid = {"load": 80e3, "creepage_x": 0.0, "creepage_y": 0.0}
    for table, label, style in ((before, "before", "C3o-"), (after, "after", "C0.-")):
        ys = table.axes["lateral_displacement"]
        n = [table({"lateral_displacement": y, **mid}, "left")["normal_force"] for y in ys]
        ax.plot(ys * 1e3, np.array(n) / 1e3, style, ms=4, label=f"{label}: {len(ys)} nodes")
    ax.set_ylabel("left normal force [kN] (80 kN, no creep)")
    ax.set_title("the nodes along the lateral displacement", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    for ax in axs[1]:
        ax.set_xlabel("lateral displacement [mm]")
    fig.suptitle(f"S1002/60E1 creep-force table: error at {chk.size} random states x "
                 f"{len(chk.sides)} wheels against the exact solver", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", help="keep the tables in this folder")
    ap.add_argument("--workers", type=int, default=2, help="Dask workers (2)")
    ap.add_argument("--states", type=int, default=100,
                    help="random states of each check (100)")
    ap.add_argument("--rounds", type=int, default=2, help="refinement rounds (2)")
    ap.add_argument("--plot", help="write the error map to this file")
    args = ap.parse_args(argv)
    spec = parse_spec(spec_dict())
    tmp = None
    folder = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="error_map_"))
    if args.out:
        folder.mkdir(parents=True, exist_ok=True)
    else:
        tmp = folder
    client = connect(None, args.workers)
    try:
        store = folder / "table.zarr"
        if store.exists():
            shutil.rmtree(store)
        t0 = time.perf_counter()
        rep = build_table(spec, store, client=client, progress=False, check=args.states,
                          check_seed=1)
        print(f"table: {spec.size} points x {len(spec.sides)} wheels "
              f"({' x '.join(f'{n} {len(v)}' for n, v in spec.axes.items())}); built in "
              f"{rep.seconds:.0f} s ({rep.rate:.3g} points/s, {args.workers} workers), "
              f"checked at {args.states} states (seed 1) in {rep.check.seconds:.0f} s; "
              f"{rep.not_ok} point-wheels not ok {rep.statuses}")
        copy = folder / "before.zarr"
        if copy.exists():
            shutil.rmtree(copy)
        shutil.copytree(store, copy)
        t1 = time.perf_counter()
        chk = check_table(copy, args.states, seed=2, client=client)
        print(f"independent check (seed 2): {args.states} states x 2 wheels solved in "
              f"{time.perf_counter() - t1:.0f} s")
        before = _open(copy)
        before_rows = _lateral_rows(chk, before)
        _print_overall("before", chk)
        t2 = time.perf_counter()
        ref = refine_table(store, axes=("lateral_displacement",), rounds=args.rounds,
                           client=client, progress=False)
        for k, r in enumerate(ref.rounds, 1):
            print(f"refine round {k}: added {r['added']['lateral_displacement']} m "
                  f"(by error {r['by_error'].get('lateral_displacement', [])}, by jump "
                  f"{r['by_jump'].get('lateral_displacement', [])}); {r['points']} points, "
                  f"{r['computed']} computed")
        print(f"refinement took {time.perf_counter() - t2:.0f} s in all")
        after = _open(store)
        measure(after, chk)
        after_rows = _lateral_rows(chk, after)
        _print_overall("after ", chk)
        print("max errors per lateral interval [mm]: before | after (the intervals of the "
              "refined axis inside it)")
        for r in before_rows:
            inner = [a for a in after_rows if a["lo"] >= r["lo"] and a["hi"] <= r["hi"]]

            def fmt(rows, m):
                vals = [x[m]["max"] for x in rows if x[m]["n"]]
                k = 1e3 if m == "contact_angle" else 1.0
                return f"{max(vals) * k:9.3g}" if vals else f"{'-':>9s}"
            print(f"  {r['lo'] * 1e3:5.1f}..{r['hi'] * 1e3:5.1f} ({len(inner)} after): "
                  + "  ".join(f"{m} {fmt([r], m)} | {fmt(inner, m)}" for m in MEASURES))
        print(f"store {store}: {sum(1 for p in store.rglob('*') if p.is_file())} files")
        if args.plot:
            plot(before_rows, after_rows, before, after, chk, Path(args.plot))
            print(f"plot written to {args.plot}")
        print(f"total {time.perf_counter() - t0:.0f} s")
    finally:
        close_client(client)
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
