"""Benchmark of the steady-rolling tangential BEM (ConvexGS) on the paper's Hertz case.

The paper's rolling case (Sec. 4.2.1): A = 1/m, B = 5/m, steel, penetration 0.1 mm, xi =
0.001, mu = 0.4, eps_tau = 1e-2. For 32^2 and 64^2 elements and each initial estimate
(none / FASTSIM / FaStrip) it prints the median wall time of the tangential solve
(estimate + re-meshing + ConvexGS; operators built beforehand), the sweeps, and the time
of one ConvexGS sweep over a 40 x 40 grid fully in contact (1600 elements).

Usage: python scripts/bench_tangential.py [--repeat N]
"""

from __future__ import annotations

import argparse
import statistics
import time
from functools import partial

import numpy as np

from railcontact import ElasticPair, Grid, Material, hertz, influence_operator, solve_normal
from railcontact.contact import simplified_tangential
from railcontact.settings import TangentialSettings
from railcontact.tangential import rolling_operator, solve_tangential
from railcontact.tangential.convexgs import (
    DIRECT_WORK,
    HAVE_NUMBA,
    _blocks_of,
    _gs_kernels,
    _sweep_blocked,
    _sweep_numpy,
)
from railcontact.tangential.strips import remesh_strips


def rolling_solve(estimate, hz, pair, tspec, grid, op, normal, mu, creepage, tol):
    """Estimate (FASTSIM / FaStrip on the Hertz ellipse), re-meshing and ConvexGS."""
    p0 = st0 = None
    if estimate != "none":
        p0, st0 = remesh_strips(simplified_tangential(estimate, hz, pair, tspec), grid)
    return solve_tangential(grid, op, normal.pressure, mu, creepage, initial_traction=p0,
                            initial_state=st0, tolerance=tol)


def median_time(fn, repeat):
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=11)
    args = ap.parse_args()

    pair = ElasticPair.of(Material(206e9, 0.28))
    A, B, delta, mu, creepage, tol = 1.0, 5.0, 1e-4, 0.4, (1e-3, 0.0, 0.0), 1e-2
    tspec = TangentialSettings(creepage=creepage, friction=mu)
    print(f"paper rolling case: xi = {creepage[0]:g}, mu = {mu:g}, eps_tau = {tol:g}, "
          f"median of {args.repeat}, numba: {HAVE_NUMBA}")
    print(f"{'grid':>7} {'estimate':>9} {'median ms':>10} {'sweeps':>7} {'ratio':>6} "
          f"{'ms/sweep':>9} {'Fx [N]':>10}")
    for n in (32, 64):
        xl, yl = np.sqrt(delta / A), np.sqrt(delta / B)
        grid = Grid.from_bounds(-xl, xl, -yl, yl, n, n)
        X, Y = grid.mesh()
        nr = solve_normal(A * X**2 + B * Y**2, grid, influence_operator(grid, pair),
                          penetration=delta, tolerance=1e-3)
        hz = hertz(A, B, pair, load=nr.force)
        op = rolling_operator(grid, pair)
        base = None
        for est in ("none", "fastsim", "fastrip"):
            run = partial(rolling_solve, est, hz, pair, tspec, grid, op, nr, mu, creepage, tol)
            run()  # compile / warm caches
            med, res = median_time(run, args.repeat)
            base = base or med
            print(f"{n:>4}^2 {est:>9} {med * 1e3:10.2f} {res.iterations:7d} "
                  f"{med / base:6.2f} {med / res.iterations * 1e3:9.3f} {res.force[0]:10.1f}")

    # one sweep over 1600 elements, all in contact
    grid = Grid(40, 40, 0.4e-3, 0.2e-3, 0.0, 0.0)
    op = rolling_operator(grid, pair)
    kern = _gs_kernels(op)
    c = op.self_coefficient
    cc = (float(c[0, 0]), float(c[0, 1]), float(c[1, 0]), float(c[1, 1]))
    g = np.full((40, 40), 4e8)
    w = np.zeros((2, 40, 40))
    w[0] = 1e-3 * grid.dx
    lo = np.zeros(40, np.int64)
    hi = np.full(40, 39, np.int64)
    state = np.ones((40, 40), np.int8)
    rows = _blocks_of((g > 0).sum(axis=1), DIRECT_WORK)

    def sweep_numba():
        return _sweep_blocked(kern, op, w, g, px, py, state, lo, hi, rows, cc, 0.5, 0.5)

    def sweep_numpy():
        return _sweep_numpy(*kern, w[0], w[1], g, px, py, state, lo, hi, *cc, 0.5, 0.5)

    for name, fn in (("numba (blocked)", sweep_numba), ("numpy", sweep_numpy)):
        if name.startswith("numba") and not HAVE_NUMBA:
            continue
        px = np.zeros((40, 40))
        py = np.zeros((40, 40))
        fn()
        med, _ = median_time(fn, max(args.repeat, 21) if name.startswith("numba") else 3)
        print(f"one ConvexGS sweep, 1600 elements in contact, {name}: {med * 1e3:.3f} ms")


if __name__ == "__main__":
    main()
