"""A time step forms no reference cycles: its records are freed when they are dropped.

Python frees an object whose last reference goes at once, except objects in a reference
cycle, which wait for the cyclic garbage collector. Its collections stop every thread
(they run under the GIL), and a full one traverses every object of the process (tens of
thousands with numba and SciPy imported: tens of ms), a pause a real-time host cannot
take. A step that forms no cycles leaves the collector nothing to do: here, steps with the
collector off leave no unreachable object behind, warm and cold, under load and
penetration control, on the flange and with two patches a wheel, with and without the
rigid wheelset's search (a patch start that its pass kept for after the normal solve was
such a cycle); and an FFT plan leaves nothing behind (the ctypes type of its dimensions,
a cycle, is formed once). The steps run in a new Python process (this file run as a
script), where no other thread - an event loop another test left running, pytest-xdist's
own - can leave cycles of its own while they run.
"""

from __future__ import annotations

import gc
import json
import math
import subprocess
import sys
from collections import Counter

import numpy as np
import pytest

import railcontact as rc
from railcontact.halfspace import fftw

STEEL = rc.Material(206e9, 0.28)
W = 2 * math.pi * 1.5


def _contact(**settings) -> rc.WheelsetContact:
    return rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
                              rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                              rc.ElasticPair.of(STEEL, STEEL),
                              rc.ContactSettings(friction=0.4, element_size=1e-3, **settings))


def _step(contact: rc.WheelsetContact, k: int, y0: float, amplitude: float,
          vertical: float | None, load: float) -> None:
    t = k * 1e-3
    y = y0 + amplitude * math.sin(W * t)
    kinematics = rc.Kinematics(30.0, amplitude * W * math.cos(W * t))
    if vertical is None:
        contact.solve(rc.Pose(y), loads=(load, load), kinematics=kinematics, time=t)
    else:
        contact.solve(rc.Pose(y), vertical=vertical, kinematics=kinematics, time=t)


def _unreachable(contact: rc.WheelsetContact, steps: int, **run) -> Counter:
    """The objects that ``steps`` steps (after as many to form the run's grids, plans and
    operators) leave for the garbage collector, by type."""
    for k in range(steps):
        _step(contact, k, **run)
    return _left_by(lambda: [_step(contact, k, **run) for k in range(steps, 2 * steps)])


def _left_by(work) -> Counter:
    """The objects ``work()`` leaves for the garbage collector (run with it off), by type;
    the collector's state as it was."""
    enabled, debug = gc.isenabled(), gc.get_debug()
    gc.collect()
    gc.disable()
    try:
        work()
        gc.set_debug(debug | gc.DEBUG_SAVEALL)
        gc.collect()
        return Counter(type(o).__name__ for o in gc.garbage)
    finally:
        gc.set_debug(debug)
        gc.garbage.clear()
        if enabled:
            gc.enable()


CASES = {  # name: (contact settings, run, the most patches a wheel)
    "hunting, warm": (dict(warm_start="previous+estimate"),
                      dict(y0=0.0, amplitude=3e-3, vertical=None, load=83.3e3), 1),
    "hunting, cold": (dict(warm_start="none"),  # every pass formed afresh
                      dict(y0=0.0, amplitude=3e-3, vertical=None, load=83.3e3), 1),
    "penetration control": (dict(warm_start="previous+estimate"),
                            dict(y0=0.0, amplitude=1e-3, vertical=-2.5e-4, load=None), 1),
    "on the flange": (dict(warm_start="previous+estimate"),
                      dict(y0=7e-3, amplitude=1e-3, vertical=None, load=83.3e3), 1),
    "two patches a wheel": (dict(warm_start="previous+estimate"),
                            dict(y0=5.1e-3, amplitude=1e-4, vertical=None, load=12e3), 2),
    "the rigid wheelset's search": (dict(warm_start="previous+estimate",
                                         rigid_wheelset="solve"),
                                    dict(y0=0.0, amplitude=3e-3, vertical=None, load=83.3e3), 1),
}


def _plan_left() -> Counter:
    """What FFT plans formed after a collection (which frees any ctypes type no longer
    held) leave for the collector."""
    a = np.zeros((6, 10), dtype=complex)
    b = np.zeros((6, 10), dtype=complex)
    plans = []
    left = _left_by(lambda: plans.extend(
        fftw.plan_dft(a, b, axes, "FFTW_FORWARD", ["FFTW_ESTIMATE"])
        for axes in ((0, 1), (1,))))
    fftw.destroy(plans)
    assert all(plans)
    return left


def _measure() -> dict:
    """Each case's objects left for the collector by type, its wheels' normal forces [N]
    and its most patches a wheel (one more step, at the run's centre); the FFT plans'."""
    out = {}
    for name, (settings, run, _) in CASES.items():
        contact = _contact(**settings)
        left = _unreachable(contact, 8, **run)
        load, vertical = run["load"], run["vertical"]
        result = contact.solve(rc.Pose(run["y0"]), vertical=vertical,
                               loads=None if load is None else (load, load),
                               kinematics=rc.Kinematics(30.0, 0.0), time=16e-3)
        out[name] = {"left": dict(left),
                     "forces": [result.left.normal_force, result.right.normal_force],
                     "patches": max(len(result.left.patches), len(result.right.patches))}
    if fftw.AVAILABLE:
        out["fft plans"] = {"left": dict(_plan_left())}
    return out


@pytest.fixture(scope="module")
def measured() -> dict:
    """:func:`_measure` in a new Python process (this file as a script)."""
    run = subprocess.run([sys.executable, __file__], capture_output=True, text=True,
                         timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    return json.loads(run.stdout.splitlines()[-1])


@pytest.mark.parametrize("case", list(CASES))
def test_steps_leave_nothing_to_the_garbage_collector(measured, case):
    m = measured[case]
    left = Counter(m["left"])
    assert not left, f"reference cycles left by the steps: {left.most_common(8)}"
    # (the run reaches what it is for: both wheels in contact, the patches a wheel)
    assert min(m["forces"]) > 0
    assert m["patches"] == CASES[case][2]


@pytest.mark.skipif(not fftw.AVAILABLE, reason="FFTW's C interface not found")
def test_an_fft_plan_leaves_nothing_to_the_garbage_collector(measured):
    left = Counter(measured["fft plans"]["left"])
    assert not left, f"reference cycles left by the plans: {left.most_common(8)}"


if __name__ == "__main__":
    print(json.dumps(_measure()))
