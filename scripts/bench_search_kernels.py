"""The contact search's compiled kernels as a warm wheelset step calls them, timed per call:
two versions side by side in one process.

Each version solves bench_step.py's hunting run (``warm_start = previous+estimate``) for
``--warm`` steps, then records every call of a kernel of ``railcontact.geometry.kernels``
(and of ``nearest_point_sorted`` as ``geometry.track`` calls it) over ``--steps`` steps:
its arguments, copied before the call. Each recorded call is then replayed ``--repeats``
times (A and B alternating, call by call, so that both see the same load on a shared
machine) and its median time kept; the table prints, per kernel, the calls a step and the
summed medians a step [us] of each version, and B/A. Version B is the ``railcontact`` on
the path, version A a copy of another revision's package imported under another name
(as :mod:`bench_step_ab`)::

    mkdir -p /tmp/ab && git archive REV railcontact | tar -x -C /tmp/ab
    mv /tmp/ab/railcontact /tmp/ab/rcbase
    python scripts/bench_search_kernels.py /tmp/ab rcbase [--steps 20 --repeats 30]

The replays include numba's dispatch of the arguments, as the step pays it. Where the two
versions call a kernel with the same arguments (the same count and call order), each
call's result is compared too, bit for bit: "same" or the number of calls that differ.
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
import time
from collections import defaultdict

import numpy as np


def _contact(rc):
    return rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=0.4, element_size=0.5e-3, warm_start="previous+estimate"))


def _step(rc, wc, k: int) -> None:
    """One step of the run, whose calls are captured; a step that is not ok stops the
    benchmark (its calls would not be a solved step's)."""
    w = 2 * math.pi * 1.5
    t = k * 1e-3
    r = wc.solve(rc.Pose(3e-3 * math.sin(w * t)), loads=(83.3e3, 83.3e3),
                 kinematics=rc.Kinematics(30.0, 3e-3 * w * math.cos(w * t)), time=t)
    if r.status != 0:
        raise SystemExit(f"{rc.__name__}, step {k}: status {int(r.status)}: "
                         f"{[x.message for x in r.wheels]}")


def _copy(a):
    """``a`` copied, an array with its strides (a trace is a view of wider rows)."""
    if isinstance(a, np.ndarray):
        if a.flags.c_contiguous or a.ndim != 2:
            return a.copy()
        wide = np.empty((a.shape[0], a.strides[0] // a.itemsize))
        wide[:, :a.shape[1]] = a
        return wide[:, :a.shape[1]]
    if isinstance(a, tuple):
        return tuple(_copy(x) for x in a)
    return a


def record(rc, warm: int, steps: int) -> dict[str, list[tuple]]:
    """The kernels' calls of ``steps`` warm steps of version ``rc``: name -> [args]."""
    kernels = importlib.import_module(rc.__name__ + ".geometry.kernels")
    track = importlib.import_module(rc.__name__ + ".geometry.track")
    wc = _contact(rc)
    for k in range(warm):
        _step(rc, wc, k)
    calls: dict[str, list[tuple]] = defaultdict(list)
    patched = []

    def wrap(module, name, fn):
        def recorded(*args):
            calls[name].append((fn, _copy(args)))
            return fn(*args)
        patched.append((module, name, fn))
        setattr(module, name, recorded)

    for name in dir(kernels):
        fn = getattr(kernels, name)
        if hasattr(fn, "py_func"):
            wrap(kernels, name, fn)
    if hasattr(track, "nearest_point_sorted"):  # (a version whose track calls it)
        wrap(track, "nearest_point_sorted", track.nearest_point_sorted)
    try:
        for k in range(warm, warm + steps):
            _step(rc, wc, k)
    finally:
        for module, name, fn in patched:
            setattr(module, name, fn)
    return calls


def _same(x, y) -> bool:
    if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
        x, y = np.asarray(x), np.asarray(y)
        return x.shape == y.shape and x.dtype == y.dtype and bool(
            np.all((x == y) | (np.isnan(x) & np.isnan(y)) if x.dtype.kind == "f" else x == y))
    if isinstance(x, tuple) and isinstance(y, tuple):
        return len(x) == len(y) and all(_same(a, b) for a, b in zip(x, y, strict=True))
    if isinstance(x, float) and isinstance(y, float) and math.isnan(x) and math.isnan(y):
        return True
    return type(x) is type(y) and x == y


def _result(fn, args):
    """The call's result and its array arguments after it (what it wrote)."""
    mine = _copy(args)
    out = fn(*mine)
    return out, tuple(a for a in mine if isinstance(a, np.ndarray))


def _signature(args) -> tuple:
    return tuple(a.shape if isinstance(a, np.ndarray) else type(a).__name__ for a in args)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("path", help="folder holding version A's package")
    ap.add_argument("name", help="version A's package name (e.g. rcbase)")
    ap.add_argument("--warm", type=int, default=50, help="steps before the record (50)")
    ap.add_argument("--steps", type=int, default=20, help="steps recorded (20)")
    ap.add_argument("--repeats", type=int, default=30, help="replays of each call (30)")
    args = ap.parse_args()
    sys.path.insert(0, args.path)
    versions = {"A": importlib.import_module(args.name),
                "B": importlib.import_module("railcontact")}
    calls = {n: record(rc, args.warm, args.steps) for n, rc in versions.items()}
    names = sorted(set(calls["A"]) | set(calls["B"]))
    for n in versions:  # compile each signature outside the measurement
        for name in names:
            for fn, a in calls[n].get(name, []):
                fn(*_copy(a))
    per_step: dict[str, dict[str, float]] = {n: {} for n in versions}
    check: dict[str, str] = {}
    for name in names:
        ca, cb = calls["A"].get(name, []), calls["B"].get(name, [])
        totals = {"A": 0.0, "B": 0.0}
        for i in range(max(len(ca), len(cb))):
            pair = {"A": ca[i] if i < len(ca) else None, "B": cb[i] if i < len(cb) else None}
            t = {n: [] for n, p in pair.items() if p is not None}
            for r in range(args.repeats):
                for n in (("A", "B") if r % 2 == 0 else ("B", "A")):
                    if n not in t:
                        continue
                    fn, a = pair[n][0], _copy(pair[n][1])  # (each call its own copy)
                    t0 = time.perf_counter()
                    fn(*a)
                    t[n].append(time.perf_counter() - t0)
            for n in t:
                totals[n] += float(np.median(t[n]))
        for n in versions:
            per_step[n][name] = totals[n] / args.steps * 1e6
        if len(ca) != len(cb):
            check[name] = f"calls {len(ca)} / {len(cb)}"
        elif any(_signature(x[1]) != _signature(y[1]) for x, y in zip(ca, cb, strict=True)):
            check[name] = "other arguments"
        else:
            bad = sum(not _same(_result(*x), _result(y[0], x[1])) for x, y in
                      zip(ca, cb, strict=True))
            check[name] = "same" if bad == 0 else f"{bad} differ"
    steps = args.steps
    print(f"{steps} warm steps recorded, median of {args.repeats} replays a call, "
          f"us a step (calls a step)")
    print(f"  {'kernel':26s} {'A':>14s} {'B':>14s} {'B/A':>6s}  B on A's arguments")
    ta = tb = 0.0
    for name in sorted(names, key=lambda m: -per_step["A"].get(m, 0.0)):
        a, b = per_step["A"][name], per_step["B"][name]
        ta, tb = ta + a, tb + b
        na, nb = len(calls["A"].get(name, [])) / steps, len(calls["B"].get(name, [])) / steps
        ratio = f"{b / a:6.2f}" if a > 0 else "     -"
        print(f"  {name:26s} {a:7.1f} ({na:4.1f}) {b:7.1f} ({nb:4.1f}) {ratio}  {check[name]}")
    print(f"  {'all':26s} {ta:14.1f} {tb:14.1f} {tb / ta:6.2f}")


if __name__ == "__main__":
    main()
