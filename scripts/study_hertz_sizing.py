"""Check: is the Hertz estimate worse when sized by the wheel load instead of the penetration?

The lateral sweep (``study_sweep.py``) solves every case penetration-controlled with the
approach that carries 83.3 kN, and sizes each estimate for that penetration. The paper
computes its potential area from "the penetration calculated by the Hertz contact theory"
for the load (Sec. 2.1), so its Hertz estimate may have been sized by the load. This
script runs the sweep's normal problem three ways - no estimate, Hertz for the
penetration, Hertz for the normal load Q / cos(gamma) - and prints the mean iterations.

Usage: python scripts/study_hertz_sizing.py [--step 0.5] [--preconditioner fft|none]
"""

from __future__ import annotations

import argparse
import copy
import math

import numpy as np
from _sweep import approach_for_load, displacements, paper_case, run_sweep

from railcontact.contact import NormalStart, WarmStart
from railcontact.contact.wheel import WheelSettings
from railcontact.contact.wheelrail import CaseStart, build_geometry, solve_wheel, wheel_problem
from railcontact.halfspace.hertz import hertz
from railcontact.settings import validate_case

Q = 83.3e3
CASE = paper_case()
COLUMNS = ("none", "hertz_penetration", "hertz_load")


def hertz_by_load(pair):
    """An ``estimate_for`` hook: Hertz's pressure for the normal load Q / cos(gamma)."""
    def estimate_for(cp, hz, control):
        h = hertz(cp.A, cp.B, pair, load=Q / math.cos(cp.contact_angle))
        return WarmStart("hertz", lambda grid: NormalStart(h.pressure(*grid.mesh())))
    return estimate_for


def one_case(dy: float, preconditioner: str) -> list[dict]:
    base = copy.deepcopy(CASE)
    base["geometry"]["lateral_displacement"] = dy
    approach = approach_for_load(base, Q)
    its = {}
    for column in COLUMNS:
        c = copy.deepcopy(base)
        c["normal"] = {"penetration": approach, "tolerance": 1e-3,
                       "preconditioner": preconditioner,
                       "estimate": "none" if column == "none" else "hertz"}
        c = validate_case(c)
        pair = c.pair
        track, ws, pose = build_geometry(c.geometry)
        problem = wheel_problem(track, ws, pose, "left", pair, c.normal.control)
        start = CaseStart(hertz_by_load(pair) if column == "hertz_load" else None)
        patches = solve_wheel(problem, WheelSettings(c.patch_settings, reference=False),
                              start).check("left").patches
        its[column] = patches[0].normal.iterations
    return [{"dy_mm": dy * 1e3, **its}]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=0.5, help="displacement step [mm]")
    ap.add_argument("--preconditioner", choices=("fft", "none"), default="fft")
    args = ap.parse_args()
    rows, failed = run_sweep(displacements(args.step),
                             lambda dy: one_case(dy, args.preconditioner))
    print(f"{len(rows)} cases ({len(failed)} failed), preconditioner {args.preconditioner}, "
          "mean normal iterations at eps_n = 1e-3:")
    for column in COLUMNS:
        print(f"  {column:<18} {np.mean([r[column] for r in rows]):6.2f}")
    worse = sum(r["hertz_load"] > r["none"] for r in rows)
    print(f"Hertz sized by the load costs more than none on {worse} of {len(rows)} cases")


if __name__ == "__main__":
    main()
