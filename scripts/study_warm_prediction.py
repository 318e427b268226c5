"""The warm start's prediction on bench_step's hunting run: iterations and accuracy.

The hunting run of ``scripts/bench_step.py`` (S1002 on 60E1 at 1:40, 0.5 mm elements,
mu = 0.4, 83.3 kN per wheel with the creep forces counted, 30 m/s, 3 mm lateral sine at
1.5 Hz, 1 ms steps, ``previous+estimate``) is run in process for ``--steps`` steps. Printed:
the normal CG iterations and tangential sweeps per step (both wheels; median, mean and the
share of steps at the floor of one CG iteration and one sweep a wheel), and, every
``--every``-th step, the forces against a tight cold solve of the same state (eps_n = 1e-6,
eps_tau = 1e-5, ``warm_start = "none"``): the creep force |dF| / (mu N) and the peak
pressure |dp| / p of each wheel, median and max. With ``--start-error`` every warm
SteadyGS solve of those steps is also solved tightly (eps_tau = 1e-9) from its start, and
the start's distance ``||p0 - p*|| / ||p*||`` is printed (median).

Usage: python scripts/study_warm_prediction.py [--steps 150] [--every 5] [--start-error]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import railcontact as rc
import railcontact.tangential as tangential
import railcontact.timestep.compiled as stages

REFERENCE = {"warm_start": "none", "normal_tolerance": 1e-6, "tangential_tolerance": 1e-5}


def contact(**settings) -> rc.WheelsetContact:
    """bench_step's wheelset with ``settings`` over its contact settings."""
    base = {"friction": 0.4, "element_size": 0.5e-3, "warm_start": "previous+estimate"}
    return rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL), rc.ContactSettings(**{**base, **settings}))


def run(steps: int, every: int, start_error: bool = False) -> dict:
    """The run's iterations per step, force errors every ``every``-th step and (with
    ``start_error``) the warm tangential starts' distances to their exact solutions."""
    wc, ref = contact(), contact(**REFERENCE)
    w = 2 * math.pi * 1.5
    normal, sweeps, df, dp, starts = [], [], [], [], []
    solver = tangential.SOLVERS["steadygs"]
    keep = [False]

    def spy(grid, operator, pressure, friction, creepage, *, initial_traction=None,
            initial_state=None, spin_offset=1.0 / 6.0, **kw):
        out = solver(grid, operator, pressure, friction, creepage,
                     initial_traction=initial_traction, initial_state=initial_state,
                     spin_offset=spin_offset, **kw)
        if keep[0] and initial_traction is not None and out.iterations > 0:
            # (a solve on the contact's window returns its traction on the patch's grid,
            # ``embed``: the exact solve starts from, and is compared on, the window)
            embed = kw.get("embed")
            solved = out.traction if embed is None else out.traction[:, embed[1][0],
                                                                     embed[1][1]]
            exact = solver(grid, operator, pressure, friction, creepage,
                           initial_traction=solved, tolerance=1e-9,
                           max_iterations=3000, spin_offset=spin_offset)
            if not exact.converged:
                raise RuntimeError(f"the tight solve did not converge: {exact.message}")
            n = np.linalg.norm(exact.traction)
            starts.append(np.linalg.norm(np.asarray(initial_traction) - exact.traction) / n)
        return out

    if start_error:  # (the solver's own calls: the time step's stages in Python)
        tangential.SOLVERS["steadygs"] = spy
        stages.ENABLED = False
    try:
        for k in range(steps):
            t = k * 1e-3
            pose = rc.Pose(3e-3 * math.sin(w * t))
            kin = rc.Kinematics(30.0, 3e-3 * w * math.cos(w * t))
            check = k > 0 and k % every == 0
            keep[0] = check
            r = wc.solve(pose, loads=(83.3e3, 83.3e3), kinematics=kin, time=t)
            if r.status != rc.Status.OK:  # (a study of failed steps would print nonsense)
                raise RuntimeError(f"step {k}: {[x.message for x in r.wheels]}")
            normal.append(sum(x.normal_iterations for x in r.wheels))
            sweeps.append(sum(x.tangential_iterations for x in r.wheels))
            if check:
                keep[0] = False
                q = ref.solve(pose, loads=(83.3e3, 83.3e3), kinematics=kin, time=t)
                if q.status != rc.Status.OK:
                    raise RuntimeError(f"reference at step {k}: "
                                       f"{[x.message for x in q.wheels]}")
                for a, b in zip(r.wheels, q.wheels, strict=True):
                    d = math.hypot(a.creep_force[0] - b.creep_force[0],
                                   a.creep_force[1] - b.creep_force[1])
                    df.append(d / (0.4 * b.normal_force))
                    dp.append(abs(a.max_pressure - b.max_pressure) / b.max_pressure)
    finally:
        tangential.SOLVERS["steadygs"] = solver
        stages.ENABLED = True
    return {"normal": np.array(normal[1:]), "sweeps": np.array(sweeps[1:]),
            "dF": np.array(df), "dp": np.array(dp), "starts": np.array(starts)}


def report(name: str, r: dict) -> str:
    """One Markdown row."""
    n, s = r["normal"], r["sweeps"]
    floor = np.mean((n <= 2) & (s <= 2))
    start = f" {np.median(r['starts']):.2e} |" if len(r["starts"]) else " |"
    return (f"| {name} | {np.median(n):.1f} / {n.mean():.2f} | {np.median(s):.1f} / "
            f"{s.mean():.2f} | {floor:.0%} | {np.median(r['dF']):.1e} / {r['dF'].max():.1e} "
            f"| {np.median(r['dp']):.1e} / {r['dp'].max():.1e} |{start}")


HEADER = ("| start | CG a step, median / mean | sweeps a step, median / mean | steps at the "
          "floor | dF/(mu N) median / max | dp/p median / max | start error (median) |\n"
          "|---|---|---|---|---|---|---|")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=150)
    ap.add_argument("--every", type=int, default=5)
    ap.add_argument("--start-error", action="store_true")
    args = ap.parse_args()
    t0 = time.perf_counter()
    print(HEADER)
    print(report("this version", run(args.steps, args.every, args.start_error)))
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
