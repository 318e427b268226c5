"""Benchmark of one wheelset time step: wall time, iterations and where the time goes.

The hunting-like run, in-process through :class:`railcontact.WheelsetContact`:
S1002 on 60E1 at 1:40, 0.5 mm elements, mu = 0.4, 83.3 kN per wheel (load control with the
creep forces counted), 30 m/s with kinematic creepages, a 3 mm lateral sine at 1.5 Hz
(lateral velocity from it, no yaw), 1 ms steps, ``--steps`` steps (300). For the warm
(``previous+estimate``) and cold (``none``) starts it prints the median step time and
iterations, and the breakdown of the step time by stage: contact search, meshing
(grids, gaps, re-meshing the previous step), reach check (whether the contact could
reach beyond a warm patch's area: its scan of the overlap, the gap it forms counted as
meshing), estimates (INFCON, FaStrip, previous-step
prediction), normal BEM (a warm patch's compiled normal stage whole: its gap, start and
reach check with the solve), tangential BEM (a warm patch's compiled stage whole: its traction
start and rate with the solve), operators (influence coefficients, kernel spectra
and FFT planning for a new grid shape) and the rest (load loop, resultants, Python).

A fixed numpy workload is timed in the same run (128 x 128 FFT round trips x 200, then a
600 x 600 matrix-vector product x 400), and every time is also given as a ratio to it, so
that figures compare across machines (the targets: warm step <= 0.03, cold step <= 0.25
of the workload). The resident memory (RSS) is printed at the end.

What no rewrite of the step's Python can go below: ``--kernels`` runs each mode once more
with every compiled kernel of the package and every DC-FFT product timed (as
``scripts/bench_threads.py --profile`` does, without the stage breakdown) and prints, per
step, the median time inside them - the contact search, the frame, the normal and the
tangential stage, the products, whatever Python calls them - against the whole step's, both
also as ratios to the workload: the floor of a step whose Python took no time at all, with
today's kernels, grids and iterations.

Usage: python scripts/bench_step.py [--steps 300] [--modes previous+estimate,none]
       [--solver steadygs|convexgs] [--patch-frame reference|rigid] [--kernels]
       [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import time
from collections import defaultdict
from contextlib import contextmanager
from pathlib import Path

import numpy as np

import railcontact as rc
import railcontact.contact.patch as patch_module
import railcontact.contact.wheelrail as wheelrail_module
import railcontact.geometry.search as geometry_search
import railcontact.tangential as tangential
import railcontact.timestep.warmstart as warmstart_module
import railcontact.timestep.wheelset as wheelset_module

try:
    import railcontact.timestep.wheel as step_wheel_module  # (a wheel of the step)
except ImportError:  # an older package: the step's wheels solved in its wheelset module
    step_wheel_module = wheelset_module
try:
    import railcontact.timestep.stages as step_stages_module  # (the step's stages)
except ImportError:  # an older package: the stages are the wheelset's methods
    step_stages_module = wheelset_module
try:
    import railcontact.timestep.compiled as stages_module  # (the warm step's compiled stages)
except ImportError:  # an older package: none
    stages_module = patch_module

STAGES = {  # stage: (module, function name) pairs timed as that stage
    "search": [(wheelrail_module, "contact_points"), (wheelrail_module, "count_contacts"),
               (step_wheel_module, "vertical_gap"), (step_stages_module, "search_wheel")],
    "meshing": [(patch_module, "make_grid"), (geometry_search.ContactPoint, "gap_on_grid"),
                (warmstart_module, "remesh")]
               + ([(stages_module, "make_grid")] if hasattr(stages_module, "warm_normal")
                  else []),
    "reach check": [(wheelrail_module, "uncovered"), (wheelrail_module, "overlap_box")],
    "estimate": [(patch_module, "virtual_penetration"), (patch_module, "remesh_strips"),
                 (patch_module, "fastrip"), (patch_module, "fastsim"),
                 (patch_module, "strips_on_contact"),
                 (patch_module, "strips_from_contact"), (patch_module, "sample_on_strips")],
    "normal BEM": [(patch_module, "solve_normal"), (step_wheel_module, "warm_normal")],
    "tangential BEM": ([(tangential.SOLVERS, name) for name in tangential.SOLVERS]
                       if hasattr(tangential, "SOLVERS")  # older versions: one solver
                       else [(patch_module, "solve_tangential")])
                      + [(step_wheel_module, "warm_tangential")],
    "operators": [(patch_module, "influence_operator"), (patch_module, "rolling_operator")]
                 + ([(stages_module, "rolling_operator")] if stages_module is not patch_module
                    else [])
                 + ([(stages_module, "influence_operator")]
                    if hasattr(stages_module, "warm_normal") else []),
}
LEGACY = frozenset({"strips_from_contact", "sample_on_strips", "uncovered", "overlap_box",
                    "vertical_gap", "search_wheel", "warm_tangential", "warm_normal"})
"""Targets that one version of the package has and another lacks (functions it no longer
has, or not yet: the reach check), timed when present: the script also runs against an
older package (bench_step_ab.py)."""


class Breakdown:
    """Exclusive wall time per stage: a timed call nested in another is taken out of the
    outer one."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self._stack: list[list[float]] = []

    def wrap(self, stage: str, fn):
        def timed(*args, **kwargs):
            self._stack.append([0.0])
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                dt = time.perf_counter() - t0
                inner = self._stack.pop()[0]
                self.seconds[stage] += dt - inner
                if self._stack:
                    self._stack[-1][0] += dt
        return timed

    @contextmanager
    def installed(self):
        saved = []
        for stage, targets in STAGES.items():
            for owner, name in targets:
                if name in LEGACY and not _has(owner, name):
                    continue
                fn = _get(owner, name)
                saved.append((owner, name, fn))
                _set(owner, name, self.wrap(stage, fn))
        try:
            yield self
        finally:
            for owner, name, fn in reversed(saved):
                _set(owner, name, fn)


def _has(owner, name) -> bool:
    return name in owner if isinstance(owner, dict) else hasattr(owner, name)


def _get(owner, name):
    return owner[name] if isinstance(owner, dict) else getattr(owner, name)


def _set(owner, name, fn) -> None:
    if isinstance(owner, dict):
        owner[name] = fn
    else:
        setattr(owner, name, fn)


def fixed_workload() -> float:
    """Seconds of the reference numpy workload (best of 3)."""
    rng = np.random.default_rng(0)
    a = rng.standard_normal((128, 128))
    m = rng.standard_normal((600, 600))
    v = rng.standard_normal(600)
    best = math.inf
    for _ in range(3):
        t0 = time.perf_counter()
        for _ in range(200):
            a = np.fft.irfft2(np.fft.rfft2(a), s=a.shape)
        for _ in range(400):
            v = m @ v
            v /= np.linalg.norm(v)
        best = min(best, time.perf_counter() - t0)
    return best


def clear_caches() -> None:
    """Forget the influence operators, FFT plans and FFTW's wisdom, so that each run pays
    for its own planning."""
    import railcontact.halfspace.operator as operator_module
    import railcontact.tangential.rolling as rolling_module

    operator_module._cached_operator.cache_clear()
    rolling_module._cached.cache_clear()
    getattr(operator_module._local, "plans", {}).clear()
    if operator_module.HAVE_PYFFTW:
        operator_module.pyfftw.forget_wisdom()  # FFTW remembers what it measured
        wisdom = os.environ.get(getattr(operator_module, "WISDOM_ENV", ""), "")
        if wisdom:  # a wisdom file given to the run: its plans are the run's own
            operator_module.load_wisdom(wisdom)


def run(mode: str, steps: int, step: float = 1e-3, solver: str | None = None,
        patch_frame: str | None = None, kernels=None) -> dict:
    """The hunting-like run with one warm-start mode, from empty operator caches; per-step
    times and iterations. ``kernels``: a :class:`bench_threads.NogilTimer` installed
    instead of the stage breakdown; the result then also holds the median time a step
    spent in its kernels (``kernels``)."""
    clear_caches()
    extra = {} if solver is None else {"tangential_solver": solver}
    if patch_frame is not None:  # older versions without patch_frame: the rigid point only
        extra["patch_frame"] = patch_frame
    wc = rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=0.4, element_size=0.5e-3, warm_start=mode, **extra))
    w = 2 * math.pi * 1.5
    times, normal, tangential, passes, inside = [], [], [], [], []
    bd = Breakdown()
    with bd.installed() if kernels is None else kernels.installed():
        for k in range(steps):
            t = k * step
            before = 0.0 if kernels is None else sum(kernels.seconds.values())
            t0 = time.perf_counter()
            r = wc.solve(rc.Pose(3e-3 * math.sin(w * t)), loads=(83.3e3, 83.3e3),
                         kinematics=rc.Kinematics(30.0, 3e-3 * w * math.cos(w * t)), time=t)
            times.append(time.perf_counter() - t0)
            if kernels is not None:
                inside.append(sum(kernels.seconds.values()) - before)
            normal.append(sum(x.normal_iterations for x in r.wheels))
            tangential.append(sum(x.tangential_iterations for x in r.wheels))
            passes.append(sum(x.load_passes for x in r.wheels))
            if r.status != 0:
                print(f"  step {k}: status {r.status} ({r.left.message}; {r.right.message})")
    total = sum(times)
    out = {} if kernels is None else {"kernels": float(np.median(inside[1:]))}
    return out | {"mode": mode, "median": float(np.median(times[1:])),
            "mean": float(np.mean(times[1:])),
            "normal": float(np.median(normal[1:])),
            "tangential": float(np.median(tangential[1:])),
            "passes": float(np.mean(passes[1:])), "first": times[0],
            "breakdown": {s: bd.seconds.get(s, 0.0) / total for s in STAGES}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--modes", default="previous+estimate,none")
    ap.add_argument("--solver", default=None, help="tangential solver (default: the "
                    "settings' default)")
    ap.add_argument("--patch-frame", default=None, choices=("reference", "rigid"),
                    help="origin of the patch frames (default: the settings' default)")
    ap.add_argument("--kernels", action="store_true", help="also the median time a step "
                    "spends in the compiled kernels (a run of each mode with them timed)")
    ap.add_argument("--json", type=Path, default=None, help="write the results (for "
                    "scripts/plot_performance.py)")
    args = ap.parse_args()
    run("none", 5, solver=args.solver)  # compile the numba sweeps, outside the measurements
    ref = fixed_workload()
    print(f"fixed workload (128^2 FFT round trips x 200 + 600^2 mat-vec x 400): "
          f"{ref * 1e3:.1f} ms")
    results = [run(m, args.steps, solver=args.solver, patch_frame=args.patch_frame)
               for m in args.modes.split(",")]
    print(f"\n{args.steps} steps of 1 ms, S1002/60E1, 0.5 mm, 83.3 kN with creep, 30 m/s, "
          "3 mm at 1.5 Hz; medians per step (both wheels), first step left out")
    print(f"{'warm start':<18} {'median [ms]':>11} {'/ workload':>10} {'mean [ms]':>9} "
          f"{'/ workload':>10} {'normal it':>9} {'tang. it':>8} {'passes':>6} "
          f"{'first [ms]':>10}")
    for r in results:
        print(f"{r['mode']:<18} {r['median'] * 1e3:11.2f} {r['median'] / ref:10.3f} "
              f"{r['mean'] * 1e3:9.2f} {r['mean'] / ref:10.3f} {r['normal']:9.1f} "
              f"{r['tangential']:8.1f} {r['passes']:6.2f} {r['first'] * 1e3:10.1f}")
    print("\nshare of the total step time by stage (exclusive):")
    print(f"{'stage':<16}" + "".join(f"{r['mode']:>20}" for r in results))
    for s in [*STAGES, "rest"]:
        shares = [r["breakdown"][s] if s != "rest" else 1 - sum(r["breakdown"].values())
                  for r in results]
        print(f"{s:<16}" + "".join(f"{x:20.1%}" for x in shares))
    if args.kernels:
        from bench_threads import NogilTimer

        print("\ntime inside the compiled kernels and DC-FFT products (a run of each mode "
              "with them timed; medians per step): the step's floor without Python")
        print(f"{'warm start':<18} {'step [ms]':>9} {'/ workload':>10} {'kernels [ms]':>12} "
              f"{'/ workload':>10} {'share':>6}")
        for m in args.modes.split(","):
            r = run(m, args.steps, solver=args.solver, patch_frame=args.patch_frame,
                    kernels=NogilTimer())
            print(f"{m:<18} {r['median'] * 1e3:9.2f} {r['median'] / ref:10.4f} "
                  f"{r['kernels'] * 1e3:12.2f} {r['kernels'] / ref:10.4f} "
                  f"{r['kernels'] / r['median']:6.1%}")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"\npeak RSS {rss:.0f} MB")
    if args.json:
        args.json.write_text(json.dumps({"workload": ref, "rss_mb": rss, "runs": results},
                                        indent=1))
        print(f"written {args.json}")


if __name__ == "__main__":
    main()
