"""Seeded warm-start trajectories against cold tight solves (a warm step never misses
contact).

Random trajectories of a wheelset (S1002 on 60E1 at 1:40) between 4.5 and 9 mm lateral
on either side - the flange root and the flange, with the tread beside them - with random
yaw, wheel loads (25-45 kN), creepages, friction (0.15-0.4), the patch frame at the rigid
point or the reference point, with and without the creep forces' share of the load. Each
step is solved warm (``previous+estimate``, after the trajectory's earlier steps) and cold
at tight tolerances (1e-6); every wheel the warm step reports ok must equal the cold one
within :data:`railcontact.timestep.wheelset.WARM_PROMISE` (|dN| / N and max |dF| /
(mu N)). Prints the count, the worst differences and each step beyond the promise (the
seed, trajectory and step reproduce it); exit status 1 when there is one.

    python scripts/fuzz_warm.py [--seed 1] [--trajectories 100] [--steps 20]
                                [--element-size 1e-3]

``tests/test_warmstart_reach.py`` runs the same check on 16 trajectories.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

import railcontact as rc
from railcontact.timestep.wheelset import OK, WARM_PROMISE, WheelsetContact

TIGHT = {"warm_start": "none", "normal_tolerance": 1e-6, "tangential_tolerance": 1e-6,
         "load_tolerance": 1e-6}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--trajectories", type=int, default=100)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--element-size", type=float, default=1e-3, help="[m]")
    args = ap.parse_args(argv)
    steel = rc.Material(206e9, 0.28)
    pair = rc.ElasticPair.of(steel, steel)
    geometry = (rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
                rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46))
    rng = np.random.default_rng(args.seed)
    t0 = time.perf_counter()
    compared, beyond, worst = 0, [], (0.0, 0.0)
    statuses: dict[int, int] = {}
    for k in range(args.trajectories):
        base = {"friction": float(rng.uniform(0.15, 0.4)),
                "element_size": args.element_size,
                "patch_frame": ("rigid", "reference")[k % 2],
                "load_includes_creep": bool(k // 2 % 2)}
        warm = WheelsetContact(*geometry, pair, rc.ContactSettings(
            **base, warm_start="previous+estimate"))
        tight = WheelsetContact(*geometry, pair, rc.ContactSettings(**base, **TIGHT))
        y = float(rng.uniform(4.5e-3, 8.5e-3)) * float(rng.choice([-1.0, 1.0]))
        dy = 0.0
        for j in range(args.steps):
            dy = 0.6 * dy + float(rng.normal(0.0, 0.25e-3))
            y = float(np.clip(y + dy, -9e-3, 9e-3))
            pose = rc.Pose(y, float(rng.normal(0.0, 2e-3)))
            loads = tuple(float(q) for q in rng.uniform(25e3, 45e3, 2))
            xi, eta = (float(c) for c in rng.uniform(-0.01, 0.01, 2))
            creep = ((xi, eta, float(rng.uniform(-2.5, 2.5))),
                     (xi, -eta, float(rng.uniform(-2.5, 2.5))))
            rw = warm.solve(pose, loads=loads, creepages=creep, time=(j + 1) * 5e-3)
            if j == 0:  # (cold: no previous step)
                continue
            rt = tight.solve(pose, loads=loads, creepages=creep)
            for w, t in zip(rw.wheels, rt.wheels, strict=True):
                statuses[int(w.status)] = statuses.get(int(w.status), 0) + 1
                if w.status != OK:
                    continue
                n = t.normal_force
                dn = abs(w.normal_force - n) / n if n > 0 else math.inf
                df = (max(abs(a - b) for a, b in zip(w.creep_force, t.creep_force,
                                                     strict=True)) / (base["friction"] * n)
                      if n > 0 else math.inf)
                compared += 1
                worst = (max(worst[0], dn), max(worst[1], df))
                if not (dn <= WARM_PROMISE[0] and df <= WARM_PROMISE[1]):
                    beyond.append((k, j, w.side, y, dn, df, len(w.patches), len(t.patches)))
    print(f"seed {args.seed}: {compared} warm wheels ok compared with tight cold solves "
          f"({args.trajectories} trajectories x {args.steps} steps, statuses {statuses}), "
          f"{time.perf_counter() - t0:.1f} s")
    print(f"worst: dN = {worst[0]:.3%} of N, dF = {worst[1]:.3%} of mu N (promise "
          f"{WARM_PROMISE[0]:.0%}, {WARM_PROMISE[1]:.0%})")
    for k, j, side, y, dn, df, nw, nt in beyond:
        print(f"beyond the promise: trajectory {k} step {j} {side} y = {y * 1e3:.3f} mm: "
              f"dN = {dn:.3%}, dF = {df:.3%} of mu N, patches warm {nw} / tight {nt}")
    return 1 if beyond else 0


if __name__ == "__main__":
    sys.exit(main())
