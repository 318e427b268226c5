"""Per-call time of the simplified estimates on wheel-rail patches.

For the patch of S1002 on 60E1 (1:40, 83.3 kN, 0.5 mm elements, the case file
``models/cases/s1002_60e1_dy-2mm.toml``) at the lateral displacements ``--lateral`` [mm],
solved once, it times what a cold start with estimates calls: INFCON's and KP's virtual
penetration under load control (the load secant included; the estimate grid 40 x 40), the
estimate re-meshed onto the BEM grid, FaStrip and FASTSIM on the BEM's patch (strips along
its contact rows) and FaStrip's traction re-meshed onto the BEM grid. Each figure is the
median over ``--repeat`` rounds of the mean over the patches, in microseconds and as a
ratio to the fixed workload of :mod:`bench_step` measured in the same run. It also prints
the load secant's evaluations per INFCON call.

Usage: python scripts/bench_estimates.py [--repeat 15] [--lateral -4 -2 0 2 4]
"""

from __future__ import annotations

import argparse
import copy
import statistics
import time
from pathlib import Path

from bench_step import fixed_workload

import railcontact as rc
from railcontact.contact import simplified_tangential
from railcontact.geometry.points import samples
from railcontact.normal import virtual
from railcontact.tangential.strips import remesh_strips

CASE = Path(__file__).resolve().parents[1] / "models" / "cases" / "s1002_60e1_dy-2mm.toml"


def patches(lateral_mm: list[float]) -> list:
    """(patch, elastic pair, tangential settings) of the solved case at each displacement
    (its geometry, normal and Hertz solution)."""
    case = rc.load_case(CASE)
    out = []
    for dy in lateral_mm:
        c = copy.deepcopy(case.to_dict())
        c["geometry"]["lateral_displacement"] = dy * 1e-3
        c["grid"] = {"dx": 0.5e-3, "dy": 0.5e-3}
        c["tangential"] = {"creepage": [2e-4, 2e-4, 0.2], "friction": 0.4,
                           "estimate": "fastrip"}
        this = type(case).from_dict(c)
        out.append((rc.solve(this).patches[0], this.pair, this.tangential))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--lateral", type=float, nargs="+", default=[-4, -2, 0, 2, 4])
    args = ap.parse_args()
    cases = patches(args.lateral)
    settings = cases[0][2]
    creepage = (2e-4, 2e-4, 0.2)
    calls = {
        "INFCON (load)": lambda p, pair: virtual.virtual_penetration(
            "infcon", *samples(p.geometry)[:3], pair,
            load=p.normal.force),
        "KP (load)": lambda p, pair: virtual.virtual_penetration(
            "kp", *samples(p.geometry)[:3], pair, load=p.normal.force),
        "FaStrip": lambda p, pair: simplified_tangential(
            "fastrip", p.hertz, pair, settings, p.normal, creepage),
        "FASTSIM": lambda p, pair: simplified_tangential(
            "fastsim", p.hertz, pair, settings, p.normal, creepage),
    }
    infcon = {id(p): calls["INFCON (load)"](p, pair) for p, pair, _ in cases}
    fastrip = {id(p): calls["FaStrip"](p, pair) for p, pair, _ in cases}
    grid_of = {id(p): p.normal.grid for p, _, _ in cases}
    if hasattr(infcon[id(cases[0][0])], "pressure_on"):
        calls["INFCON re-meshed"] = lambda p, pair: infcon[id(p)].pressure_on(grid_of[id(p)])
    else:  # older versions of the package without pressure_on
        calls["INFCON re-meshed"] = lambda p, pair: infcon[id(p)].pressure_at(
            *grid_of[id(p)].mesh())
    calls["FaStrip re-meshed"] = lambda p, pair: remesh_strips(fastrip[id(p)], grid_of[id(p)])
    evaluations = []
    evaluate = getattr(virtual, "_evaluate", None) or virtual._estimate_at
    name = "_evaluate" if hasattr(virtual, "_evaluate") else "_estimate_at"

    def counted(*a, **k):
        evaluations[-1] += 1
        return evaluate(*a, **k)

    setattr(virtual, name, counted)
    for p, pair, _ in cases:
        evaluations.append(0)
        calls["INFCON (load)"](p, pair)
    setattr(virtual, name, evaluate)
    times = {k: [] for k in calls}
    for fn in calls.values():  # (compiled or loaded from numba's cache: not timed)
        fn(*cases[0][:2])
    for _ in range(args.repeat):
        for k, fn in calls.items():
            t0 = time.perf_counter()
            for p, pair, _ in cases:
                fn(p, pair)
            times[k].append((time.perf_counter() - t0) / len(cases))
    ref = fixed_workload()
    print(f"fixed workload: {ref * 1e3:.1f} ms; {len(cases)} wheel-rail patches "
          f"(lateral {args.lateral} mm), median of {args.repeat} rounds")
    print(f"{'call':<20} {'us/call':>9} {'/ wkld':>9}")
    for k, v in times.items():
        t = statistics.median(v)
        print(f"{k:<20} {t * 1e6:9.1f} {t / ref:9.5f}")
    print(f"INFCON's load secant: {statistics.mean(evaluations):.2f} evaluations a call")


if __name__ == "__main__":
    main()
