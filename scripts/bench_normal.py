"""Benchmark of the normal BEM on the paper's Hertz case (Sec. 4.1.1).

A = 1/m, B = 5/m, E = 206 GPa, nu = 0.28, penetration 0.1 mm, eps_n = 1e-3, potential area
from the paper's rule (A x^2 <= delta, B y^2 <= delta). For 32^2, 64^2 and 128^2 elements,
both FFT backends, both starts (none / Hertz estimate) and both solvers (plain
Polonsky–Keer CG, and with the FFT preconditioner) it prints the median wall time of the
solve (operator and FFT plans built beforehand, as in a time-stepping simulation, and
reported separately as "setup") and the iteration count.

Usage: python scripts/bench_normal.py [--repeat N]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from railcontact import ElasticPair, Grid, Material, hertz, solve_normal
from railcontact.halfspace.operator import HAVE_PYFFTW, InfluenceOperator


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=21, help="solves per configuration")
    args = ap.parse_args()

    pair = ElasticPair.of(Material(206e9, 0.28))
    A, B, delta, tol = 1.0, 5.0, 1e-4, 1e-3
    hz = hertz(A, B, pair, penetration=delta)
    backends = ["pyfftw", "scipy"] if HAVE_PYFFTW else ["scipy"]
    rows = []
    for n in (32, 64, 128):
        xl, yl = np.sqrt(delta / A), np.sqrt(delta / B)
        grid = Grid.from_bounds(-xl, xl, -yl, yl, n, n)
        X, Y = grid.mesh()
        gap = A * X**2 + B * Y**2
        p_hertz = hz.pressure(X, Y)
        for backend in backends:
            t = time.perf_counter()
            op = InfluenceOperator(grid, pair, "z", backend)
            setup = time.perf_counter() - t
            for pre in ("none", "fft"):
                for estimate, p0 in (("none", None), ("hertz", p_hertz)):
                    times, res = [], None
                    for _ in range(args.repeat):
                        t = time.perf_counter()
                        res = solve_normal(gap, grid, op, penetration=delta,
                                           initial_pressure=p0, tolerance=tol,
                                           preconditioner=pre)
                        times.append(time.perf_counter() - t)
                    rows.append((n, backend, pre, estimate, statistics.median(times),
                                 res.iterations, setup, res.force / hz.load - 1))

    ref = {r[0]: r[4] for r in rows if r[1:4] == (backends[0], "none", "none")}
    print(f"paper Hertz case, penetration-controlled, eps_n = {tol:g}, median of {args.repeat}")
    print(f"{'grid':>8} {'backend':>8} {'precond':>8} {'estimate':>9} {'median ms':>10} "
          f"{'iter':>5} {'ratio':>7} {'setup ms':>9} {'F/F_Hertz-1':>12}")
    for n, backend, pre, est, med, its, setup, ferr in rows:
        print(f"{n:>5}^2 {backend:>8} {pre:>8} {est:>9} {med * 1e3:10.3f} {its:5d} "
              f"{med / ref[n]:7.2f} {setup * 1e3:9.1f} {ferr:12.2e}")
    print("ratio: median time relative to the first backend, plain CG, no estimate, same grid")


if __name__ == "__main__":
    main()
