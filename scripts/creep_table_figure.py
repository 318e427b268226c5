"""A normalised creep table (``[table] kind = "creep"``, docs/tables.md): build it (unless
the store exists), print its creep coefficients beside Kalker's Table E.3, the build's
points per second, the full-slip values, |F|/(mu N) at the ends of nu_x with the largest
spin, the interpolation error of ``CreepTable`` at random states between the nodes against
the exact solve there (``--check N``; the largest with their states), the time of a
``CreepTable.forces`` call (median), C33 at a/b = 5, nu = 0.25 under grid refinement
(``--c33``: the spec's case on 32, 64, 128 square grids and 143 x 28 elements), and draw
its creep curves (F/(mu N) against the normalised creepages for a few ellipse ratios, with
the linear theory) to a PNG.

Usage: python scripts/creep_table_figure.py [--spec models/tables/creep_nu028.toml]
       [--table OUT.zarr] [--figure docs/table_creep_curves.png] [--workers N]
       [--check N] [--seed S] [--c33]
       (``--workers 0``, the default: in this process)
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from railcontact.contact.dispatch import solve  # noqa: E402
from railcontact.table.build import close_client, connect  # noqa: E402
from railcontact.table.creep import build_creep_table  # noqa: E402
from railcontact.table.creepread import CreepTable, creep_summary  # noqa: E402
from railcontact.table.creepspec import CREEPAGES, RATIO, case_scales  # noqa: E402
from railcontact.table.kinds import load_any_spec  # noqa: E402
from railcontact.table.show import plot_table  # noqa: E402
from railcontact.table.store import open_dataset  # noqa: E402

SYMBOL = {RATIO: "a/b", "creepage_x": "nu_x", "creepage_y": "nu_y", "spin": "psi"}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spec", default=str(ROOT / "models" / "tables" / "creep_nu028.toml"))
    ap.add_argument("--table", default=None, help="the store (default: a temporary one)")
    ap.add_argument("--figure", default=str(ROOT / "docs" / "table_creep_curves.png"))
    ap.add_argument("--workers", type=int, default=0)
    ap.add_argument("--check", type=int, default=40, help="random off-node states")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--c33", action="store_true",
                    help="C33 at a/b = 5, nu = 0.25 on refined grids (a few minutes)")
    args = ap.parse_args()
    spec = load_any_spec(args.spec)
    table = Path(args.table) if args.table else Path(tempfile.mkdtemp()) / "creep.zarr"
    if not table.exists():
        client = connect(None, args.workers) if args.workers else None
        try:
            rep = build_creep_table(spec, table, client=client)
        finally:
            if client is not None:
                close_client(client)
        print(f"built {table}: {rep.points} points in {rep.seconds:.1f} s "
              f"({rep.rate:.0f} points/s, {args.workers or 'this'} "
              f"{'worker(s)' if args.workers else 'process'}); {rep.not_converged} not "
              "converged")
    print(creep_summary(table))
    ds = open_dataset(table)
    err = {n: 100 * (ds[n].values / ds[f"kalker_{n}"].values - 1) for n in ("c11", "c22",
                                                                              "c23")}
    print("exact linear limit vs Kalker's Table E.3 [%]: "
          + "; ".join(f"{n} {v.min():+.2f} .. {v.max():+.2f}" for n, v in err.items()))
    full = ds["force_x"].isel(creepage_x=-1)
    sel = {n: int(np.argmin(np.abs(ds[n].values))) for n in ("creepage_y", "spin")
           if n in ds.dims}
    print(f"F_x/(mu N) at nu_x = {float(ds['creepage_x'].values[-1]):g} (others 0), per "
          f"a/b: {np.round(full.isel(sel).values, 5).tolist()}")
    spun(ds)
    if args.check:
        check(spec, table, args.check, args.seed)
    if args.c33:
        c33_refinement(spec)
    print(f"figure written to {plot_table(table, args.figure)}")
    return 0


def spun(ds) -> None:
    """|F|/(mu N) at nu_x at its ends, nu_y at its node nearest 0 and psi at its ends (the
    largest spin), per ellipse ratio: the range over the four sign pairs."""
    if "spin" not in ds.dims or "creepage_x" not in ds.dims:
        return
    sel = {"creepage_y": int(np.argmin(np.abs(ds["creepage_y"].values)))} \
        if "creepage_y" in ds.dims else {}
    ends = {"creepage_x": [0, -1], "spin": [0, -1]}
    f = np.hypot(ds["force_x"].isel(sel).isel(ends).values,
                 ds["force_y"].isel(sel).isel(ends).values)
    f = f.reshape(f.shape[0], -1)
    nx, psi = ds["creepage_x"].values[[0, -1]], ds["spin"].values[[0, -1]]
    print(f"|F|/(mu N) at nu_x = {nx[0]:g}, {nx[1]:g}, psi = {psi[0]:g}, {psi[1]:g} "
          f"(nu_y nearest 0), per a/b: " + "; ".join(
              f"{r:g}: {lo:.3f} .. {hi:.3f}" for r, lo, hi in
              zip(ds[RATIO].values, f.min(axis=1), f.max(axis=1), strict=True)))


def c33_refinement(spec, ratio: float = 5.0, poisson: float = 0.25) -> None:
    """C33 of the exact solver at ``ratio`` (a/b) and ``poisson`` with the spec's case on
    refined grids, against the literature's C33 (the column beside Kalker's Table E.3)."""
    from railcontact.table.creep import linear_coefficients
    from railcontact.table.creepspec import CreepSpec
    from railcontact.tangential.kalker import creep_coefficients

    lit = creep_coefficients(ratio, 1.0, poisson).c33
    print(f"C33 at a/b = {ratio:g}, nu = {poisson:g} (literature {lit:.4f}):")
    for nx, ny in ((32, 32), (64, 64), (128, 128), (143, 28)):
        case = {k: dict(v) if isinstance(v, dict) else v for k, v in spec.case.items()}
        case["material"]["poisson"] = poisson
        case["grid"].update(nx=nx, ny=ny)
        one = CreepSpec(case=case, axes={RATIO: np.array([ratio])})
        t0 = time.perf_counter()
        c = linear_coefficients(one, ratio)["c33"]
        print(f"  {nx:4d} x {ny:3d} elements: {c:.4f} ({100 * (c / lit - 1):+.1f} %), "
              f"{time.perf_counter() - t0:.1f} s")


def check(spec, table: Path, n: int, seed: int) -> None:
    """The table's F/(mu N) at ``n`` random states (uniform in ln(a/b) and the creepage
    axes, inside the table) against the exact solve of each state's case; the time of a
    ``CreepTable.forces`` call."""
    tab = CreepTable(table)
    rng = np.random.default_rng(seed)
    errs, times, states = [], [], []
    for _ in range(n):
        state = {}
        for name, x in spec.axes.items():
            lo, hi = (np.log(x[0]), np.log(x[-1])) if name == RATIO else (x[0], x[-1])
            v = rng.uniform(lo, hi)
            state[name] = float(np.exp(v) if name == RATIO else v)
        sc = case_scales(spec.case_at(state[RATIO]))
        cr = sc.physical([state.get(c, 0.0) for c in CREEPAGES])
        t = solve(spec.case_at(state[RATIO], tuple(cr))).patches[0].tangential
        exact = np.array([t.force[0], t.force[1]]) / sc.mu_n
        got = tab.normalised(state)[0][:2]
        errs.append(float(np.max(np.abs(got - exact))))
        states.append(state)
        t0 = time.perf_counter()
        tab.forces(sc.a, sc.b, sc.mu_n / float(spec.case["tangential"]["friction"]),
                   float(spec.case["tangential"]["friction"]), sc.shear, *cr)
        times.append(time.perf_counter() - t0)
    e = np.array(errs)
    print(f"interpolation error of F/(mu N) (max over x, y) at {n} random states (seed "
          f"{seed}) against the exact solve: median {np.median(e):.3g}, 90 % "
          f"{np.quantile(e, 0.9):.3g}, max {e.max():.3g}; the largest:")
    for k in np.argsort(e)[::-1][:8]:
        print(f"  {e[k]:.3f} at " + ", ".join(f"{SYMBOL.get(m, m)} = {v:.3g}"
                                               for m, v in states[k].items()))
    print(f"CreepTable.forces: median {statistics.median(times) * 1e6:.0f} us per call")


if __name__ == "__main__":
    raise SystemExit(main())
