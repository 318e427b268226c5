"""The walk of a pose through one time step: how often it enters the contact search and
how often it climbs back up to the step's top level.

Runs ``--warm`` warm steps (5) of :mod:`bench_step`'s hunting-like run (S1002 on 60E1,
83.3 kN, mu 0.4, kinematic creepages, load control with the creep forces counted), then
profiles one more step with :func:`sys.setprofile` and prints:

* entries into the contact search: calls of a function of
  :mod:`railcontact.geometry.search` (the search of a wheel at a pose and the functions
  of a wheel given by track, wheelset, pose and side) from outside that module, per
  wheel, and by function;
* for the record, the calls of :mod:`railcontact.geometry.points` from outside it: the
  contact points and patch frames formed from the search's record
  (:class:`~railcontact.geometry.points.WheelSearch`) at the approaches the load loops
  try, and the gaps, boxes and samples read of them (:class:`ContactPoint`'s methods
  included) - pure functions of the record's arrays, not searches;
* climbs to the top level: returns of Python functions into the frame of
  :meth:`WheelsetContact.solve` (each a stage, or a helper, the step calls itself).

``--rigid`` solves the rigid wheelset's stage too; ``--cold`` profiles a cold step.

Usage: python scripts/step_walk.py [--warm 5] [--rigid] [--cold]
(with ``PYTHONPATH`` at the tree to measure when the environment's ``railcontact`` is
another's)
"""

from __future__ import annotations

import argparse
import math
import sys
from collections import Counter
from pathlib import Path

import railcontact as rc
from railcontact.timestep import wheelset as wheelset_module

SEARCH = str(Path(rc.__file__).parent / "geometry" / "search.py")
POINTS = str(Path(rc.__file__).parent / "geometry" / "points.py")
STEP = wheelset_module.WheelsetContact.solve.__code__


def walk(contact: rc.WheelsetContact, **step) -> tuple[Counter, int, Counter, Counter]:
    """(entries into the search by function, climbs to the step's top level, climbs by
    function, calls of :mod:`railcontact.geometry.points` by function) of
    ``contact.solve(**step)``."""
    entries: Counter = Counter()
    climbs: Counter = Counter()
    formed: Counter = Counter()

    def profile(frame, event, arg) -> None:
        if event == "call":
            name = frame.f_code.co_filename
            if name == SEARCH or name == POINTS:
                back = frame.f_back
                if back is None or back.f_code.co_filename != name:
                    (entries if name == SEARCH else formed)[frame.f_code.co_name] += 1
        elif event == "return":
            back = frame.f_back
            if back is not None and back.f_code is STEP:
                climbs[frame.f_code.co_name] += 1

    sys.setprofile(profile)
    try:
        contact.solve(**step)
    finally:
        sys.setprofile(None)
    return entries, sum(climbs.values()), climbs, formed


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--warm", type=int, default=5, help="warm steps before the one profiled")
    ap.add_argument("--rigid", action="store_true", help="solve the rigid wheelset's stage")
    ap.add_argument("--cold", action="store_true", help="profile a cold step")
    args = ap.parse_args()
    settings = rc.ContactSettings(friction=0.4, element_size=0.5e-3,
                                  warm_start="none" if args.cold else "previous+estimate",
                                  rigid_wheelset="solve" if args.rigid else "skip")
    wc = rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
                            rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                            rc.ElasticPair.of(rc.STEEL, rc.STEEL), settings)
    w = 2 * math.pi * 1.5

    def step(k: int) -> dict:
        t = k * 1e-3
        return dict(pose=rc.Pose(3e-3 * math.sin(w * t)), loads=(83.3e3, 83.3e3),
                    kinematics=rc.Kinematics(30.0, 3e-3 * w * math.cos(w * t)), time=t)

    for k in range(args.warm):
        wc.solve(**step(k))
    entries, climbs, by, formed = walk(wc, **step(args.warm))
    kind = "cold" if args.cold else "warm"
    print(f"{kind} step{' with the rigid stage' if args.rigid else ''}: "
          f"{sum(entries.values())} entries into the contact search "
          f"({sum(entries.values()) / 2:g} per wheel), {climbs} climbs to the step's top level")
    print("  entries: " + ", ".join(f"{n} {c}" for n, c in entries.most_common()))
    print("  climbs:  " + ", ".join(f"{n} {c}" for n, c in by.most_common()))
    print(f"  calls of the points formed from the search's record: {sum(formed.values())}: "
          + ", ".join(f"{n} {c}" for n, c in formed.most_common()))


if __name__ == "__main__":
    main()
