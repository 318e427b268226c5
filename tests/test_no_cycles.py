"""A time step forms no reference cycles: its records are freed when they are dropped.

Python frees an object whose last reference goes at once, except objects in a reference
cycle, which wait for the cyclic garbage collector. Its collections stop every thread
(they run under the GIL), and a full one traverses every object of the process (tens of
thousands with numba, SciPy and Dask imported: tens of ms), a pause a real-time host cannot
take. A step that forms no cycles leaves the collector nothing to do: here, steps with the
collector off leave no unreachable object behind, warm and cold, under load and
penetration control, on one patch and on two, with and without the rigid wheelset's
search (a patch start that its pass kept for after the normal solve, and an FFT plan's
ctypes dimension type formed at each plan, were such cycles).
"""

from __future__ import annotations

import gc
import math
from collections import Counter

import pytest

import railcontact as rc

STEEL = rc.Material(206e9, 0.28)
W = 2 * math.pi * 1.5


def _contact(**settings) -> rc.WheelsetContact:
    return rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
                              rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                              rc.ElasticPair.of(STEEL, STEEL),
                              rc.ContactSettings(friction=0.4, element_size=1e-3, **settings))


def _step(contact: rc.WheelsetContact, k: int, y0: float, amplitude: float,
          vertical: float | None) -> None:
    t = k * 1e-3
    y = y0 + amplitude * math.sin(W * t)
    kinematics = rc.Kinematics(30.0, amplitude * W * math.cos(W * t))
    if vertical is None:
        contact.solve(rc.Pose(y), loads=(83.3e3, 83.3e3), kinematics=kinematics, time=t)
    else:
        contact.solve(rc.Pose(y), vertical=vertical, kinematics=kinematics, time=t)


def _unreachable(contact: rc.WheelsetContact, steps: int, **run) -> Counter:
    """The objects that ``steps`` steps (after as many to form the run's grids, plans and
    operators) leave for the garbage collector, by type."""
    for k in range(steps):
        _step(contact, k, **run)
    gc.collect()
    gc.disable()
    try:
        for k in range(steps, 2 * steps):
            _step(contact, k, **run)
        gc.set_debug(gc.DEBUG_SAVEALL)
        gc.collect()
        left = Counter(type(o).__name__ for o in gc.garbage)
    finally:
        gc.set_debug(0)
        gc.garbage.clear()
        gc.enable()
    return left


@pytest.mark.parametrize("warm_start, rigid, y0, amplitude, vertical", [
    ("previous+estimate", "skip", 0.0, 3e-3, None),  # the hunting run, warm
    ("none", "skip", 0.0, 3e-3, None),  # cold: every pass formed afresh
    ("previous+estimate", "skip", 0.0, 1e-3, -2.5e-4),  # penetration control
    ("previous+estimate", "skip", 7e-3, 1e-3, None),  # at the flange: two patches
    ("previous+estimate", "solve", 0.0, 3e-3, None),  # the rigid wheelset's search
])
def test_steps_leave_nothing_to_the_garbage_collector(warm_start, rigid, y0, amplitude,
                                                      vertical):
    contact = _contact(warm_start=warm_start, rigid_wheelset=rigid)
    left = _unreachable(contact, 8, y0=y0, amplitude=amplitude, vertical=vertical)
    assert not left, f"reference cycles left by the steps: {left.most_common(8)}"
