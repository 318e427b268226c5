"""Where a wheelset step's wall time goes: compiled code or Python, by sampling.

Runs ``--steps`` steps (1000) of :mod:`bench_step`'s hunting-like run (S1002 on 60E1,
0.5 mm elements, 83.3 kN, mu 0.4, kinematic creepages, load control with the creep forces
counted) in a child process sampled by `py-spy <https://github.com/benfred/py-spy>`_
(``pip install py-spy``, or the ``bench`` extra; ``--native``, ``--rate`` samples a
second), and sorts the samples taken inside :meth:`railcontact.WheelsetContact.solve` by
the code running when each was taken:

* **compiled**: numba's machine code (frames without a symbol) and FFTW;
* **C libraries**: the C runtime and libm called from Python (allocation, copies; called
  from compiled code they count as compiled);
* **numpy**: numpy's C functions called from Python (small array operations);
* **Python**: the interpreter running the package's Python, numba's dispatch of a call
  into compiled code included.

The step's median wall time is timed in this process on ``--timed`` steps (300) without
the sampler (each sample stops the sampled process). The compiled share times that median
is the step's cost were its Python gone (the floor of a step compiled end to end that does
the same work); the Python and numpy shares are what a compiled step removes. It prints
the shares, that floor as a ratio to the fixed workload of :mod:`bench_step`, and the
innermost package functions of the time not compiled. cProfile (which times calls)
inflates Python's share two- to threefold here; sampling does not.

Usage: python scripts/step_sampling.py [--steps 1000] [--timed 300]
       [--mode previous+estimate] [--rate 200] [--top 25]
(with ``PYTHONPATH`` at the tree to measure when the environment's ``railcontact`` is
another's)
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

STEP_FRAME = "WheelsetContact.solve"
"""The frame a sample must be inside to count (the step; the set-up and warm-up are not)."""
JIT_FRAME = re.compile(r"^0x[0-9a-f]+ \(\?\)$")
"""A native frame without a symbol: numba's machine code (the only unnamed code here)."""


def hunting(mode: str, steps: int, ready: Path | None = None) -> list[float]:
    """Wall times [s] of ``steps`` steps of the hunting run after 50 not timed; with
    ``ready``, that file is written after those 50 and the steps start 2 s later (for
    the sampler to attach)."""
    from bench_step_ab import hunting_contact

    import railcontact as rc

    wc = hunting_contact(rc, mode)
    w = 2 * math.pi * 1.5
    times = []
    for k in range(steps + 50):
        if k == 50 and ready is not None:
            ready.write_text("")
            time.sleep(2.0)
        t = k * 1e-3
        t0 = time.perf_counter()
        wc.solve(rc.Pose(3e-3 * math.sin(w * t)), loads=(83.3e3, 83.3e3),
                 kinematics=rc.Kinematics(30.0, 3e-3 * w * math.cos(w * t)), time=t)
        if k >= 50:
            times.append(time.perf_counter() - t0)
    return times


def child(mode: str, steps: int, out: Path) -> None:
    """The sampled run: ``out`` written when its first 50 steps are done (the sampler
    attaches then: the first steps form the search's samples, operators and plans), then
    the package's path to ``out.json``. Its step times are the sampler's, not the step's
    (each sample stops the process)."""
    import railcontact as rc

    hunting(mode, steps, ready=out)
    out.with_suffix(".json").write_text(json.dumps({"package": rc.__file__}))


def kind(frames: list[str]) -> str:
    """The kind of code of a sample (its frames, outermost first; see the module's
    docstring). A C library's function counts as the code that called it: compiled when
    the nearest frame above it is numba's or FFTW's, else the Python's."""
    leaf = frames[-1]
    if JIT_FRAME.match(leaf) or "fftw" in leaf.lower():
        return "compiled"
    if "numpy" in leaf or "_multiarray" in leaf:
        return "numpy"
    if "(libc." in leaf or "(libm." in leaf or "(libpthread" in leaf:
        for f in reversed(frames[:-1]):
            if JIT_FRAME.match(f) or "fftw" in f.lower():
                return "compiled"
            if ".py:" in f:
                return "C libraries"
    return "Python"


def classify(raw: Path) -> tuple[Counter, Counter]:
    """(samples by kind, samples not compiled by innermost package function) of py-spy's
    raw (collapsed) output, inside the step only."""
    kinds: Counter = Counter()
    where: Counter = Counter()
    for line in raw.read_text().splitlines():
        stack, _, count = line.rpartition(" ")
        if STEP_FRAME not in stack:
            continue
        frames = stack.split(";")
        k = kind(frames)
        kinds[k] += int(count)
        if k != "compiled":
            own = [f for f in frames if "railcontact/" in f and ".py:" in f]
            where[own[-1].split(" (")[0] if own else "?"] += int(count)
    return kinds, where


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=1000, help="steps sampled")
    ap.add_argument("--timed", type=int, default=300, help="steps timed (not sampled)")
    ap.add_argument("--mode", default="previous+estimate")
    ap.add_argument("--rate", type=int, default=200, help="samples a second")
    ap.add_argument("--top", type=int, default=25, help="package functions listed")
    ap.add_argument("--raw", type=Path, default=None, help="keep py-spy's samples here")
    ap.add_argument("--child", type=Path, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child is not None:
        child(args.mode, args.steps, args.child)
        return
    spy = shutil.which("py-spy") or str(Path(sys.executable).with_name("py-spy"))
    if not Path(spy).exists():
        sys.exit("py-spy not found: pip install py-spy")
    from bench_step import fixed_workload

    with tempfile.TemporaryDirectory() as tmp:
        raw, ready = Path(tmp) / "raw.txt", Path(tmp) / "ready"
        run = subprocess.Popen([sys.executable, __file__, "--child", str(ready), "--mode",
                                args.mode, "--steps", str(args.steps)], env=os.environ.copy())
        while not ready.exists():
            if run.poll() is not None:
                sys.exit("the sampled run ended before its steps")
            time.sleep(0.05)
        subprocess.run([spy, "record", "--native", "-r", str(args.rate), "-f", "raw", "-o",
                        str(raw), "--pid", str(run.pid)], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        if run.wait() != 0:
            sys.exit("the sampled run failed")
        if args.raw is not None:
            shutil.copy(raw, args.raw)
        kinds, where = classify(raw)
        run = json.loads(ready.with_suffix(".json").read_text())
    ref = fixed_workload()
    median = float(np.median(hunting(args.mode, args.timed)))
    total = sum(kinds.values())
    print(f"package {run['package']}")
    print(f"{args.mode}: {args.steps} steps sampled; {args.timed} timed, median "
          f"{median * 1e3:.3f} ms = "
          f"{median / ref:.4f} of the fixed workload ({ref * 1e3:.1f} ms); "
          f"{total} samples inside the step")
    print(f"{'code running':<14} {'share':>7} {'ms/step':>8} {'/ workload':>10}")
    for k in ("compiled", "C libraries", "numpy", "Python"):
        share = kinds[k] / total
        print(f"{k:<14} {share:7.1%} {share * median * 1e3:8.3f} "
              f"{share * median / ref:10.4f}")
    floor = kinds["compiled"] / total * median
    print(f"\nfloor (the compiled share of the median): {floor * 1e3:.3f} ms = "
          f"{floor / ref:.4f} of the workload")
    print(f"\nnot compiled, by innermost package function (share of the step), top {args.top}:")
    for name, n in where.most_common(args.top):
        print(f"  {n / total:6.1%}  {name}")


if __name__ == "__main__":
    main()
