"""Warm-started SteadyGS: does a previous-step start want a different relaxation?

The warm SteadyGS solves of ``scripts/bench_step.py``'s hunting run (S1002 on 60E1 at 1:40,
0.5 mm elements, mu = 0.4, 83.3 kN per wheel, 30 m/s, 3 mm lateral sine at 1.5 Hz, 1 ms
steps, ``previous+estimate``) are captured as they are posed - the patch, its pressure and
creepages and the previous step's extrapolated traction - every ``--every``-th step from
step 20 on. Each is solved tightly (cold, eps_tau = 1e-9) for its exact traction p*, then
warm with each relaxation variant for k = 1 .. 8 sweeps. Printed per variant: the sweeps
the stopping rule ``||p^k - p^(k-1)|| < eps_tau ||p^k||`` takes at eps_tau = 1e-2 (the
step's), the true error ``||p - p*|| / ||p*||`` at that stop and the creep-force error
``|dF| / (mu N)`` there, the stopping measure after sweep 1, and the median true error after
1, 2, 3, 4 sweeps (the relaxation's real speed from such a start, whatever the measure).
With ``--run-tolerance 1e-6`` the run's own steps are solved tightly, so the start error
printed is that of the prediction alone (time extrapolation, re-meshing), without the
previous steps' iteration error.

A variant is ``omega_h,omega_s`` (the same in every sweep) or ``omega_h,omega_s;omega_h,
omega_s`` (first sweep; later sweeps).

Usage: python scripts/study_warm_relaxation.py [--steps 200] [--every 9]
       [--run-tolerance 1e-2] [--variants "0.65,0.9" "1,1" "0.5,0.9" "1,1;0.65,0.9"]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import railcontact as rc
import railcontact.tangential as tangential
import railcontact.timestep.compiled as stages
from railcontact.tangential.convexgs import SweepProblem, _blocks_of
from railcontact.tangential.steadygs import (
    BLOCK_SCALE,
    _run_coefficients,
    _steady_kernels,
    _sweep_blocked,
    solve_steadygs,
)

EPS_TAU = 1e-2
MAX_SWEEPS = 8


def capture(steps: int, every: int, tolerance: float = EPS_TAU) -> list[dict]:
    """The warm SteadyGS problems of the hunting run (every ``every``-th step from 20), the
    run's steps solved to eps_tau = ``tolerance``."""
    found: list[dict] = []
    keep = [False]
    solver = tangential.SOLVERS["steadygs"]

    def spy(grid, operator, pressure, friction, creepage, *, initial_traction=None,
            initial_state=None, spin_offset=1.0 / 6.0, **kw):
        if keep[0] and initial_traction is not None:
            found.append({"args": (grid, operator, pressure, friction, creepage),
                          "start": np.array(initial_traction), "state": initial_state,
                          "spin_offset": spin_offset})
        return solver(grid, operator, pressure, friction, creepage,
                      initial_traction=initial_traction, initial_state=initial_state,
                      spin_offset=spin_offset, **kw)

    wc = rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=0.4, element_size=0.5e-3, warm_start="previous+estimate",
                           tangential_tolerance=tolerance))
    w = 2 * math.pi * 1.5
    tangential.SOLVERS["steadygs"] = spy
    stages.ENABLED = False  # (the solver's own calls: the time step's stages in Python)
    try:
        for k in range(steps):
            t = k * 1e-3
            keep[0] = k >= 20 and k % every == 0
            r = wc.solve(rc.Pose(3e-3 * math.sin(w * t)), loads=(83.3e3, 83.3e3),
                         kinematics=rc.Kinematics(30.0, 3e-3 * w * math.cos(w * t)), time=t)
            if r.status != rc.Status.OK:  # (a failed step's successor starts from cold:
                # its start would pass here as a previous step's)
                raise RuntimeError(f"step {k}: {[x.message for x in r.wheels]}")
    finally:
        tangential.SOLVERS["steadygs"] = solver
        stages.ENABLED = True
    return found


def sweeps(problem: dict, schedule: list[tuple[float, float]], count: int) -> list[np.ndarray]:
    """The iterates (2, nx, ny) [Pa] after sweeps 1 .. count from the captured start, the
    relaxation of sweep k being ``schedule[min(k, len - 1)]``; also the stopping measure
    of each sweep, as the last element (a 1-D array)."""
    grid, operator, pressure, friction, creepage = problem["args"]
    prob = SweepProblem.set_up(grid, operator, pressure, friction, creepage, problem["start"],
                               problem["state"], EPS_TAU, count, 0.65, 0.9, "auto",
                               problem["spin_offset"])
    kern, cum = _steady_kernels(operator), _run_coefficients(operator)
    product = operator.bound()
    rows = _blocks_of(prob.row_counts, BLOCK_SCALE**2 * grid.size)
    out, measure = [], []
    for k in range(count):
        oh, os_ = schedule[min(k, len(schedule) - 1)]
        dif = _sweep_blocked(kern, cum, product, prob.wx, prob.wy, prob.g, prob.p,
                             prob.state, prob.lo, prob.hi, rows, oh, os_)  # squared change
        measure.append(math.sqrt(dif) / math.sqrt(float(np.sum(prob.px ** 2 + prob.py ** 2))))
        out.append(np.stack([prob.px.T, prob.py.T]))
    return [*out, np.asarray(measure)]


def parse(variant: str) -> list[tuple[float, float]]:
    """'oh,os' or 'oh,os;oh,os' -> [(omega_h, omega_s), ...]."""
    return [tuple(float(x) for x in part.split(",")) for part in variant.split(";")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--every", type=int, default=9)
    ap.add_argument("--run-tolerance", type=float, default=EPS_TAU,
                    help="eps_tau of the run's own steps (the start's history; default 1e-2)")
    ap.add_argument("--variants", nargs="+",
                    default=["0.65,0.9", "1,1", "1,1;0.65,0.9", "0.8,0.9", "0.5,0.9",
                             "0.65,1"])
    args = ap.parse_args()
    t0 = time.perf_counter()
    problems = capture(args.steps, args.every, args.run_tolerance)
    exact = [solve_steadygs(*p["args"], tolerance=1e-9, max_iterations=3000,
                            spin_offset=p["spin_offset"]) for p in problems]
    if not all(e.converged for e in exact):  # (the errors are measured against these)
        raise RuntimeError("a tight solve did not converge: "
                           + "; ".join(e.message for e in exact if not e.converged))
    start_err = [np.linalg.norm(p["start"] - e.traction) / np.linalg.norm(e.traction)
                 for p, e in zip(problems, exact, strict=True)]
    print(f"{len(problems)} warm SteadyGS solves of the hunting run; start error "
          f"||p0 - p*|| / ||p*|| median {np.median(start_err):.2e}, max {np.max(start_err):.2e}")
    print("| omega_h,omega_s | sweeps (mean) | error at stop, median / max | dF/(mu N) at stop, "
          "median / max | sweep-1 measure (median) | error after 1, 2, 3, 4 sweeps (median) |")
    print("|---|---|---|---|---|---|")
    for variant in args.variants:
        stops, errs, ferrs, first, curve = [], [], [], [], []
        for p, e in zip(problems, exact, strict=True):
            *its, measure = sweeps(p, parse(variant), MAX_SWEEPS)
            stop = next((k + 1 for k, m in enumerate(measure) if m < EPS_TAU), MAX_SWEEPS)
            grid, _, pressure, friction, _ = p["args"]
            mu_n = friction * float(pressure.sum()) * grid.dx * grid.dy
            norm = np.linalg.norm(e.traction)
            err = [np.linalg.norm(x - e.traction) / norm for x in its]
            force = np.array([x[k].sum() for x in its[stop - 1:stop] for k in range(2)])
            stops.append(stop)
            errs.append(err[stop - 1])
            ferrs.append(np.hypot(*(force * grid.dx * grid.dy - np.array(e.force))) / mu_n)
            first.append(measure[0])
            curve.append(err[:4])
        c = np.median(curve, axis=0)
        print(f"| {variant} | {np.mean(stops):.2f} | {np.median(errs):.2e} / {np.max(errs):.2e} "
              f"| {np.median(ferrs):.1e} / {np.max(ferrs):.1e} | {np.median(first):.4f} | "
              + ", ".join(f"{x:.2e}" for x in c) + " |")
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
