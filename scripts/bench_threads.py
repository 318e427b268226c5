"""Benchmark of two wheelsets stepping on two threads against one after the other.

Two :class:`railcontact.WheelsetContact` instances run the hunting-like run of
``scripts/bench_step.py`` (S1002 on 60E1 at 1:40, 0.5 mm elements, mu = 0.4, 83.3 kN per
wheel with the creep forces counted, 30 m/s, kinematic creepages, warm starts, 1 ms steps)
on two different lateral trajectories: A a 3 mm sine at 1.5 Hz, B a 2 mm sine at 2.1 Hz
with a phase of 0.7 rad; ``--element-size`` sets another element size (finer elements:
longer compiled calls beside about the same Python a step). Each repetition runs them

* one after the other on one worker thread (``sequential``), and
* at the same time, one on each of two worker threads (``threaded``),

each from new instances over ``--steps`` steps, the two orders interleaved (on a shared
machine the load of other processes changes over minutes). The worker threads live for
the whole run and are warmed up first (numba kernels, FFTW plans: plans are kept per
thread), so both ways pay the same per-step work. It prints the wall time of each way
per repetition, their medians and the ratio threaded / sequential (1.0: nothing runs in
parallel; 0.5: two cores fully used), the process's CPU time over the wall time of each
way (below 1 for the sequential way: other processes take the core; the threaded way can
reach 2 only with two cores free), and checks that the threaded results equal the
sequential ones (forces and tractions, bit for bit). After each repeat it times the
machine itself the same way (column ``machine``): two threads of a compiled loop without
the GIL and without Python, as long a step as the repeat's sequential step, in
:data:`MACHINE_CALLS` calls a step - the ratio two such runs reach on the cores free at
that moment (0.5 when both are), the bound the wheelsets' own ratio is to be read
against on a shared machine. Then it replays the two runs' own GIL-free calls (column
``kernels``: each trajectory's compiled calls, logged once on its thread after the
warm-up, made again with the same arguments, without the Python between them) one after
the other and on two threads: what the step's compiled work alone reaches on these cores
at that moment (memory-bound solvers share more than a compiled loop does: caches,
memory bandwidth), the ratio the wheelsets would have if their Python cost nothing. On
Linux it also prints the
process's voluntary context switches per wheelset step of each way (``/proc``): in the
threaded way each is a thread put to sleep waiting for the GIL, i.e. a hand-over of the GIL
between the threads that had to wake the other one.

Where the time under the GIL remains: ``--profile`` runs trajectory A on one thread with
every compiled kernel of the package that releases the GIL (numba's ``nogil=True``; the
short ones that keep it count as holding it) and every DC-FFT product
(FFTW's executes between compiled packing and spectral kernels) timed, and prints the
share of the step time that runs without the GIL, per kernel, and the ratio two threads
could reach at best on two free cores, ``max(0.5, 1 - share)`` (the GIL-holding rest of
the two runs cannot overlap). numpy's own loops, which release the GIL on large arrays,
count as holding it here.

Where a step holds it: ``--timeline`` runs trajectory A on one thread with every compiled
call logged in order (those that keep the GIL too) and prints the most common step's
sequence - the Python before each call, the call and whether it releases the GIL - with
the time a step holds the GIL and the stretches it holds it for between two GIL-free calls
(while one thread holds the GIL, the other, its GIL-free call done, waits).

What the shape of a step allows: ``--synthetic PYTHON_US,KERNEL_US,CALLS`` runs, instead
of the wheelsets, two threads whose steps have the same shape - ``CALLS`` GIL-free calls of
a compiled loop a step, ``KERNEL_US`` microseconds of them in all, each after its share of
``PYTHON_US`` microseconds of a plain Python loop - against one after the other, and prints
the ratio. A real step's Python reaches further into memory than such a loop (objects, their
reference counts, allocations), so its ratio is at least the synthetic one; how far above
it is what the Python itself costs on two threads, beyond the GIL. ``--synthetic
P1:K1,P2:K2,...`` replays a step's own pattern instead: Python of ``Pi`` microseconds, then
a GIL-free call of ``Ki`` (0: none), in turn (a real step's pattern: the Python before
each of its long GIL-free calls and the call, as ``--profile``'s times and a timeline of
one step give them).

What a hand-over costs: ``--handoff`` times a ping-pong between two threads (two
semaphores; after its turn each thread works 0, 20 or 100 us without the GIL), whose round
trip is that work and two hand-overs, each a thread blocked on a lock woken by the other and
taking the GIL, as at a GIL hand-over between two stepping wheelsets. On a virtual machine
whose idle cores halt (Linux's cpuidle ``haltpoll`` with ``guest_halt_poll_ns`` 0, printed
when present) a core that waited longer wakes slower.

Usage: python scripts/bench_threads.py [--steps 100] [--repeats 5] [--element-size 0.0005]
                                      [--profile | --timeline]
                                      [--switch-interval SECONDS]
                                      [--synthetic PYTHON_US,KERNEL_US,CALLS |
                                       --synthetic P1:K1,P2:K2,... | --handoff]
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import pkgutil
import queue
import sys
import threading
import time
from collections import defaultdict
from contextlib import contextmanager
from functools import partial
from pathlib import Path

import numpy as np

import railcontact as rc

MACHINE_CALLS = 8
"""GIL-free calls of a wheelset step (two wheels: the contact search, the reference
patch, the normal and the tangential stage each): the ``machine`` column's synthetic step
has as many, with no Python between them."""
TRAJECTORIES = {"A": (3e-3, 1.5, 0.0), "B": (2e-3, 2.1, 0.7)}
"""Lateral displacement amplitude [m], frequency [Hz] and phase [rad] of each run."""


ELEMENT_SIZE = 0.5e-3
"""The patch grids' element size [m] (``--element-size``; ``bench_step.py``'s 0.5 mm by
default)."""


def contact(mode: str = "previous+estimate") -> rc.WheelsetContact:
    """A new wheelset (its own track, profiles and settings, as two FMU instances have)."""
    return rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=0.4, element_size=ELEMENT_SIZE, warm_start=mode))


def run(name: str, steps: int, step: float = 1e-3) -> list[tuple]:
    """Trajectory ``name`` over ``steps`` steps on a new wheelset; per step the wheels'
    fingerprints (:func:`fingerprint`)."""
    amplitude, frequency, phase = TRAJECTORIES[name]
    w = 2 * math.pi * frequency
    wc = contact()
    out = []
    for k in range(steps):
        t = k * step
        r = wc.solve(rc.Pose(amplitude * math.sin(w * t + phase)), loads=(83.3e3, 83.3e3),
                     kinematics=rc.Kinematics(30.0, amplitude * w * math.cos(w * t + phase)),
                     time=t)
        out.append(fingerprint(r))
    return out


def fingerprint(result) -> tuple:
    """The values of a step that must not depend on the thread: per wheel its status,
    message, forces, moments, approach and iteration counts, and each patch's pressure and
    traction (as bytes: compared bit for bit)."""
    wheels = []
    for w in (result.left, result.right):
        patches = tuple((p.normal.pressure.tobytes(),
                         None if p.tangential is None else
                         np.asarray(p.tangential.traction).tobytes()) for p in w.patches)
        wheels.append((w.status, w.message, w.normal_force, w.creep_force, w.spin_moment,
                       w.track_force, w.yaw_moment, w.approach, w.moment,
                       w.normal_iterations, w.tangential_iterations, w.load_passes,
                       patches))
    return tuple(wheels)


class Worker:
    """A thread that runs the jobs given to it, one after the other."""

    def __init__(self, name: str) -> None:
        self.jobs: queue.Queue = queue.Queue()
        self.done: queue.Queue = queue.Queue()
        self.thread = threading.Thread(target=self._loop, name=name, daemon=True)
        self.thread.start()

    def _loop(self) -> None:
        while True:
            job = self.jobs.get()
            if job is None:
                return
            try:
                self.done.put((True, job()))
            except BaseException as exc:  # reported in the main thread
                self.done.put((False, exc))

    def submit(self, job) -> None:
        self.jobs.put(job)

    def result(self):
        ok, value = self.done.get()
        if not ok:
            raise value
        return value

    def stop(self) -> None:
        self.jobs.put(None)
        self.thread.join()


def context_switches() -> int | None:
    """The voluntary context switches of all this process's threads so far (Linux's
    ``/proc``; None elsewhere)."""
    total = 0
    try:
        tasks = os.listdir(f"/proc/{os.getpid()}/task")
    except OSError:
        return None
    for task in tasks:
        try:
            with open(f"/proc/{os.getpid()}/task/{task}/status") as f:
                for line in f:
                    if line.startswith("voluntary_ctxt_switches"):
                        total += int(line.split()[1])
        except OSError:  # a thread that ended meanwhile
            pass
    return total


def sequential(workers: list[Worker], steps: int) -> tuple[float, float, dict]:
    """A then B on the first worker; wall and process CPU time [s] and the results."""
    t0, c0 = time.perf_counter(), time.process_time()
    workers[0].submit(lambda: {n: run(n, steps) for n in TRAJECTORIES})
    out = workers[0].result()
    return time.perf_counter() - t0, time.process_time() - c0, out


def threaded(workers: list[Worker], steps: int) -> tuple[float, float, dict]:
    """A on the first worker and B on the second at the same time; wall and process CPU
    time [s] and the results."""
    names = list(TRAJECTORIES)
    t0, c0 = time.perf_counter(), time.process_time()
    for worker, n in zip(workers, names, strict=True):
        worker.submit(lambda n=n: run(n, steps))
    out = {n: worker.result() for worker, n in zip(workers, names, strict=True)}
    return time.perf_counter() - t0, time.process_time() - c0, out


class NogilTimer:
    """Wall time inside the GIL-free calls of one thread (outermost calls only)."""

    PACKAGES = ("contact", "geometry", "halfspace", "normal", "tangential", "timestep")

    def __init__(self, every: bool = False) -> None:
        self.every = every
        """Wrap the kernels that keep the GIL too (``nogil`` not set), not only those
        that release it."""
        self.seconds: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)
        self._depth = 0
        self._saved: list = []

    def wrap(self, name: str, fn):
        """``fn`` timed: each outermost call's start and end go to :meth:`record`."""
        free = bool(getattr(fn, "targetoptions", {"nogil": True}).get("nogil"))

        def timed(*args, **kwargs):
            if self._depth:
                return fn(*args, **kwargs)
            self._depth += 1
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self.record(name, t0, time.perf_counter(), free)
                self._depth -= 1
        return timed

    def record(self, name: str, start: float, end: float, gil_free: bool) -> None:
        """One outermost call of ``name`` from ``start`` to ``end`` [s]."""
        self.seconds[name] += end - start
        self.calls[name] += 1

    def install(self) -> None:
        """Wrap every numba dispatcher in the package's modules' globals that releases the
        GIL (every one with :attr:`every`; compiled already: run the same work once
        before) and the FFT plans' products."""
        from numba.core.registry import CPUDispatcher

        from railcontact.halfspace import operator

        wrapped: dict[int, object] = {}
        for info in pkgutil.walk_packages(rc.__path__, "railcontact."):
            if info.name.split(".")[1] not in self.PACKAGES:
                continue
            module = importlib.import_module(info.name)
            for attr, value in list(vars(module).items()):
                if isinstance(value, CPUDispatcher) and (
                        value.targetoptions.get("nogil") or self.every):
                    if id(value) not in wrapped:
                        wrapped[id(value)] = self.wrap(value.__name__, value)
                    self._saved.append((module, attr, value))
                    setattr(module, attr, wrapped[id(value)])
        for cls in (operator._PackedPlan, operator._PrunedPlan):
            self._saved.append((cls, "convolve", cls.convolve))
            cls.convolve = self.wrap(f"DC-FFT product ({cls.__name__})", cls.convolve)

    def uninstall(self) -> None:
        for owner, attr, value in reversed(self._saved):
            setattr(owner, attr, value)
        self._saved.clear()

    @contextmanager
    def installed(self):
        """:meth:`install` for the ``with`` block."""
        self.install()
        try:
            yield self
        finally:
            self.uninstall()


class KernelLog(NogilTimer):
    """The GIL-free calls of one thread, their arguments and results, in order (outermost
    calls only), to be replayed without the Python between them (:func:`replay`). A
    packed FFT plan's width, which the Python before a compiled product sets
    (:meth:`~railcontact.halfspace.operator._PackedPlan.kernel_arguments`: its input
    buffer's padding zeroed for another grid width), is logged as a call too, and the
    plans the calls were given are kept alive with the log: their products run on the
    plans' own buffers, and a plan dropped from its thread's cache would be freed.
    Install it on one thread at a time (it wraps module globals)."""

    def __init__(self) -> None:
        super().__init__()
        self.log: list[tuple] = []
        self.plans: list = []

    def wrap(self, name: str, fn):
        def logged(*args, **kwargs):
            if self._depth:
                return fn(*args, **kwargs)
            self._depth += 1
            try:
                out = fn(*args, **kwargs)
                self.log.append((partial(fn, **kwargs) if kwargs else fn, args,
                                 _copied(out)))
                return out
            finally:
                self._depth -= 1
        return logged

    def install(self) -> None:
        from railcontact.halfspace import operator

        super().install()
        plan = operator._fftw_plan
        width = operator._PackedPlan.kernel_arguments

        def kept(*args):
            out = plan(*args)
            self.plans.append(out)
            return out

        def widened(packed, operands, ny):
            self.log.append((width, (packed, operands, ny), None))
            return width(packed, operands, ny)

        self._saved += [(operator, "_fftw_plan", plan),
                        (operator._PackedPlan, "kernel_arguments", width)]
        operator._fftw_plan = kept
        operator._PackedPlan.kernel_arguments = widened


def captured(name: str, steps: int) -> KernelLog:
    """Trajectory ``name`` over ``steps`` steps on this thread with its GIL-free calls
    logged (:class:`KernelLog`; to be replayed on this thread, whose FFT plans they
    use)."""
    log = KernelLog()
    with log.installed():
        run(name, steps)
    return log


def replay(log: KernelLog) -> list[str]:
    """The logged GIL-free calls made again, in order, with their arguments: the step's
    compiled work without its Python. Returns the names of the calls whose result is
    not the logged one (their inputs changed after the call, e.g. an array the Python
    after it wrote into: not the same work)."""
    other = []
    for fn, args, out in log.log:
        again = fn(*args)
        if out is not None and not _same(again, out):
            other.append(getattr(fn, "__name__", str(fn)))
    return other


def _copied(out):
    """A result of a compiled call with its arrays copied (the caller may change them)."""
    if isinstance(out, tuple):
        return tuple(_copied(x) for x in out)
    return out.copy() if isinstance(out, np.ndarray) else out


def _same(a, b) -> bool:
    """Whether two results of a compiled call are equal (tuples item by item, arrays
    element by element, NaN equal to NaN)."""
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray)
                and a.shape == b.shape and np.array_equal(a, b, equal_nan=True))
    return a == b or (a != a and b != b)


def kernels_ratio(workers: list[Worker], logs: list[KernelLog]) -> float:
    """Threaded / sequential of the two runs' GIL-free calls replayed (:func:`replay`),
    each on the worker that logged it: one after the other, then at the same time."""
    t0 = time.perf_counter()
    for worker, log in zip(workers, logs, strict=True):
        worker.submit(lambda log=log: replay(log))
        worker.result()
    seq = time.perf_counter() - t0
    t0 = time.perf_counter()
    for worker, log in zip(workers, logs, strict=True):
        worker.submit(lambda log=log: replay(log))
    for worker in workers:
        worker.result()
    return (time.perf_counter() - t0) / seq


def profile(steps: int) -> None:
    """Trajectory A on this thread, the GIL-free calls timed; prints their share."""
    run("A", steps)  # compiled, planned
    timer = NogilTimer()
    timer.install()
    try:
        t0 = time.perf_counter()
        run("A", steps)
        total = time.perf_counter() - t0
    finally:
        timer.uninstall()
    free = sum(timer.seconds.values())
    print(f"trajectory A, {steps} steps on one thread: {total:.3f} s "
          f"({total / steps * 1e3:.2f} ms a step)")
    print(f"without the GIL (compiled kernels, DC-FFT products): {free:.3f} s = "
          f"{free / total:.1%}; holding it (Python, numpy): {1 - free / total:.1%}")
    print(f"best ratio on two free cores, max(0.5, 1 - share): "
          f"{max(0.5, 1 - free / total):.3f}")
    print(f"\n{'GIL-free call':<40} {'share':>6} {'calls/step':>10} {'us/call':>8}")
    for name, s in sorted(timer.seconds.items(), key=lambda kv: -kv[1])[:20]:
        n = timer.calls[name]
        print(f"{name:<40} {s / total:6.1%} {n / steps:10.1f} {s / n * 1e6:8.1f}")


class CallLog(NogilTimer):
    """Every compiled kernel of the package (those that keep the GIL too) and every
    DC-FFT product of one thread, logged in order: ``(name, start, end, gil_free)``
    (:func:`time.perf_counter`, outermost calls only)."""

    def __init__(self) -> None:
        super().__init__(every=True)
        self.calls_log: list[tuple[str, float, float, bool]] = []

    def record(self, name: str, start: float, end: float, gil_free: bool) -> None:
        self.calls_log.append((name, start, end, gil_free))


def timeline(steps: int) -> None:
    """Trajectory A on this thread, every compiled call of each step logged; prints the
    most common step's sequence: the Python before each call (with the compiled calls
    that keep the GIL, the time a step holds the GIL), each call and whether it releases
    the GIL, medians over the steps of that sequence."""
    run("A", steps)  # compiled, planned
    log = CallLog()
    bounds: list[tuple[float, float]] = []
    solve = rc.WheelsetContact.solve

    def marked(self, *args, **kwargs):
        t0 = time.perf_counter()
        try:
            return solve(self, *args, **kwargs)
        finally:
            bounds.append((t0, time.perf_counter()))

    rc.WheelsetContact.solve = marked
    try:
        with log.installed():
            run("A", steps)
    finally:
        rc.WheelsetContact.solve = solve
    patterns: dict[tuple, list] = defaultdict(list)
    calls, i = log.calls_log, 0
    for s0, s1 in bounds[1:]:  # (the first step is cold)
        while i < len(calls) and calls[i][1] < s0:
            i += 1
        seq, last = [], s0
        while i < len(calls) and calls[i][2] <= s1:
            name, a, b, free = calls[i]
            seq.append((name, free, a - last, b - a))
            last, i = b, i + 1
        seq.append(("(end of step)", False, s1 - last, 0.0))
        patterns[tuple((n, f) for n, f, _, _ in seq)].append(seq)
    key, runs = max(patterns.items(), key=lambda kv: len(kv[1]))
    med = [(name, free, float(np.median([r[k][2] for r in runs])) * 1e6,
            float(np.median([r[k][3] for r in runs])) * 1e6)
           for k, (name, free) in enumerate(key)]
    print(f"trajectory A, {steps} steps on one thread: {len(runs)} of {len(bounds) - 1} "
          f"warm steps run this sequence (medians over them, us)")
    print(f"{'Python before':>13}  {'call':<28} {'GIL':<5} {'us':>7}")
    held = free_us = 0.0
    stretch, stretches = 0.0, []
    for name, free, python_us, call_us in med:
        if name != "(end of step)":
            print(f"{python_us:13.1f}  {name:<28} {'free' if free else 'held':<5} "
                  f"{call_us:7.1f}")
        else:
            print(f"{python_us:13.1f}  {name}")
        held += python_us + (0.0 if free else call_us)
        stretch += python_us + (0.0 if free else call_us)
        if free:
            free_us += call_us
            stretches.append(stretch)
            stretch = 0.0
    stretches[0] += stretch  # (the end of a step runs on into the next one's start)
    total = held + free_us
    print(f"a step: {total:.0f} us, {held:.0f} us holding the GIL ({held / total:.1%}: "
          f"Python and the compiled calls that keep it), {free_us:.0f} us without it in "
          f"{len(stretches)} calls")
    print("the GIL held between two GIL-free calls (a step's stretches, the first one "
          "from the end of the step before), us: "
          + ", ".join(f"{x:.0f}" for x in stretches))


def _synthetic_kernel():
    """A compiled loop that runs without the GIL (``n`` iterations)."""
    import numba

    @numba.njit(nogil=True)
    def spin(n):
        s = 0.0
        for i in range(n):
            s += (i % 7) * 1e-9
        return s

    return spin


def _python_loop(n: int) -> int:
    s = 0
    for i in range(n):
        s += i
    return s


def _per_microsecond(fn, n: int = 200_000) -> float:
    """Iterations of ``fn(n)`` a microsecond (the best of five)."""
    best = math.inf
    for _ in range(5):
        t0 = time.perf_counter()
        fn(n)
        best = min(best, time.perf_counter() - t0)
    return n / (best * 1e6)


def _pattern(shape: str) -> list[tuple[float, float]]:
    """The (Python, GIL-free) microseconds of each stretch of a ``--synthetic`` shape:
    "PYTHON_US,KERNEL_US,CALLS" (CALLS equal stretches) or "P1:K1,P2:K2,..."."""
    try:
        if ":" in shape:
            pattern = [tuple(float(x) for x in part.split(":")) for part in shape.split(",")]
            if not pattern or any(len(pk) != 2 for pk in pattern):
                raise ValueError
        else:
            python_us, kernel_us, calls = (float(x) for x in shape.split(","))
            if calls != int(calls) or calls < 1:
                raise ValueError
            pattern = [(python_us / calls, kernel_us / calls)] * int(calls)
        if not all(p >= 0 and k >= 0 and math.isfinite(p + k) for p, k in pattern):
            raise ValueError
    except ValueError:
        raise SystemExit("--synthetic takes PYTHON_US,KERNEL_US,CALLS or P1:K1,P2:K2,... "
                         f"(microseconds >= 0, CALLS >= 1), got {shape!r}") from None
    return pattern


def _synthetic_ratio(spin, counts: list[tuple[int, int]], steps: int) -> tuple[float, float]:
    """(threaded / sequential, the sequential wall time [s]) of two runs of ``steps``
    synthetic steps, each ``counts``' (Python loop iterations, ``spin`` iterations) in
    turn: one run after the other, then both at once on two threads."""

    def one() -> None:
        for _ in range(steps):
            for n_py, n_k in counts:
                _python_loop(n_py)
                if n_k:
                    spin(n_k)

    t0 = time.perf_counter()
    one()
    one()
    seq = time.perf_counter() - t0
    threads = [threading.Thread(target=one) for _ in range(2)]
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return (time.perf_counter() - t0) / seq, seq


def synthetic(shape: str, steps: int, repeats: int) -> None:
    """Two threads stepping a synthetic step of ``shape`` (:func:`_pattern`) against one
    after the other; prints the ratio per repeat and its median."""
    pattern = _pattern(shape)
    python_us = sum(p for p, _ in pattern)
    kernel_us = sum(k for _, k in pattern)
    spin = _synthetic_kernel()
    spin(10)
    per_py, per_k = _per_microsecond(_python_loop), _per_microsecond(spin, 2_000_000)
    counts = [(int(p * per_py), int(k * per_k)) for p, k in pattern]

    ratios = []
    for _ in range(repeats):
        ratio, seq = _synthetic_ratio(spin, counts, steps)
        ratios.append(ratio)
    step = seq / (2 * steps) * 1e6
    calls = sum(1 for _, k in pattern if k > 0)
    print(f"synthetic step: {python_us:g} us of Python and {kernel_us:g} us GIL-free in "
          f"{calls} calls (measured one after the other: {step:.0f} us a step)")
    print(f"ratio threaded / sequential per repeat: {', '.join(f'{r:.3f}' for r in ratios)}; "
          f"median {np.median(ratios):.3f} (the GIL's bound max(0.5, Python share) = "
          f"{max(0.5, python_us / (python_us + kernel_us)):.3f})")


def _answer(ping, pong, spin, k: int, exchanges: int) -> None:
    """The other side of :func:`handoff`'s ping-pong."""
    for _ in range(exchanges):
        ping.acquire()
        pong.release()
        spin(k)


HANDOFF_WAITS = (0.0, 20.0, 100.0)
"""Microseconds each thread works without the GIL between two hand-overs (``--handoff``)."""


def handoff(exchanges: int, repeats: int) -> None:
    """The latency of a hand-over between two threads of this process: a ping-pong of
    two semaphores, each thread working :data:`HANDOFF_WAITS` microseconds without the
    GIL after its turn; a round trip is that work and two hand-overs (a thread blocked on
    a lock woken by the other, then taking the GIL), as a GIL hand-over between two
    stepping wheelsets is. Prints the hand-over's median over ``repeats`` runs for each
    wait."""
    spin = _synthetic_kernel()
    spin(10)
    per_k = _per_microsecond(spin, 2_000_000)
    poll = Path("/sys/module/haltpoll/parameters/guest_halt_poll_ns")
    if poll.exists():
        print(f"guest halt polling (cpuidle haltpoll): {poll.read_text().strip()} ns")
    for wait in HANDOFF_WAITS:
        k = int(wait * per_k)
        runs = []
        for _ in range(repeats):
            ping, pong = threading.Semaphore(0), threading.Semaphore(0)

            t = threading.Thread(target=_answer, args=(ping, pong, spin, k, exchanges))
            t.start()
            t0 = time.perf_counter()
            for _ in range(exchanges):
                ping.release()
                pong.acquire()
                spin(k)
            elapsed = time.perf_counter() - t0
            t.join()
            runs.append((elapsed / exchanges * 1e6 - wait) / 2)
        print(f"work {wait:5.0f} us between hand-overs: a hand-over takes "
              f"{np.median(runs):6.1f} us (runs {min(runs):.1f}-{max(runs):.1f})")


def main() -> None:
    global ELEMENT_SIZE
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--profile", action="store_true", help="time the GIL-free calls of "
                    "one run instead (where the time under the GIL remains)")
    ap.add_argument("--timeline", action="store_true", help="the sequence of one step "
                    "instead: the Python before each compiled call, each call, whether it "
                    "releases the GIL")
    ap.add_argument("--element-size", type=float, default=ELEMENT_SIZE, help="the patch "
                    "grids' element size [m] (finer: longer compiled calls for the same "
                    "Python a step)")
    ap.add_argument("--switch-interval", type=float, default=None, help="sys."
                    "setswitchinterval [s] for the run (Python's default: 0.005)")
    ap.add_argument("--synthetic", metavar="PYTHON_US,KERNEL_US,CALLS", default=None,
                    help="two threads of a synthetic step of this shape instead")
    ap.add_argument("--handoff", action="store_true", help="the latency of a hand-over "
                    "between two threads instead (a ping-pong of --steps x 100 exchanges, "
                    "--repeats runs)")
    args = ap.parse_args()
    ELEMENT_SIZE = args.element_size
    if args.handoff:
        handoff(100 * args.steps, args.repeats)
        return
    if args.synthetic is not None:
        synthetic(args.synthetic, args.steps, args.repeats)
        return
    if args.switch_interval is not None:
        sys.setswitchinterval(args.switch_interval)
    if args.profile:
        profile(args.steps)
        return
    if args.timeline:
        timeline(args.steps)
        return
    workers = [Worker("wheelset-1"), Worker("wheelset-2")]
    try:
        for worker in workers:  # numba kernels and each thread's FFTW plans
            worker.submit(lambda: [run(n, args.steps) for n in TRAJECTORIES])
        for worker in workers:
            worker.result()
        logs = []  # (column 'kernels': logged one worker after the other)
        for worker, n in zip(workers, TRAJECTORIES, strict=True):
            worker.submit(lambda n=n: captured(n, args.steps))
            logs.append(worker.result())
        for worker, log in zip(workers, logs, strict=True):  # (the same results?)
            worker.submit(lambda log=log: replay(log))
            other = worker.result()
            print(f"{len(other)} of {len(log.log)} replayed calls returned another result "
                  f"than logged ({', '.join(sorted(set(other))) or 'none'})")
        print(f"{os.cpu_count()} cores; {args.steps} steps of 1 ms per wheelset, two "
              f"wheelsets (trajectories {', '.join(TRAJECTORIES)}), elements "
              f"{ELEMENT_SIZE * 1e3:g} mm")
        spin = _synthetic_kernel()
        spin(10)
        per_k = _per_microsecond(spin, 2_000_000)
        print(f"{'repeat':>6} {'sequential [s]':>14} {'threaded [s]':>12} {'ratio':>6} "
              f"{'CPU/wall seq.':>13} {'CPU/wall thr.':>13} {'switches/step thr.':>18} "
              f"{'machine':>7} {'kernels':>7}")
        seq, thr, machine, alone = [], [], [], []
        reference = None
        for k in range(args.repeats):
            ways = (sequential, threaded) if k % 2 == 0 else (threaded, sequential)
            times, cpu, switches = {}, {}, {}
            for way in ways:
                before = context_switches()
                seconds, cpu_seconds, results = way(workers, args.steps)
                after = context_switches()
                times[way.__name__] = seconds
                cpu[way.__name__] = cpu_seconds / seconds
                switches[way.__name__] = (math.nan if before is None or after is None
                                          else (after - before) / (2 * args.steps))
                if reference is None:
                    bad = sum(w[0] != 0 for run in results.values() for fp in run for w in fp)
                    if bad:  # (a failed step is a cheap one: the ratio would not be a step's)
                        raise SystemExit(f"{bad} wheel steps of the run are not ok")
                    reference = results
                elif results != reference:
                    raise SystemExit(f"repeat {k}: the {way.__name__} results differ from "
                                     "the first run's")
            seq.append(times["sequential"])
            thr.append(times["threaded"])
            # the machine's own ratio now: a GIL-free compiled loop of the same wall time
            # a step, in as many calls as the step's long GIL-free ones, no Python
            n_k = int(per_k * seq[-1] / (2 * args.steps) * 1e6 / MACHINE_CALLS)
            machine.append(_synthetic_ratio(spin, [(0, n_k)] * MACHINE_CALLS,
                                            args.steps)[0])
            alone.append(kernels_ratio(workers, logs))
            print(f"{k:6d} {seq[-1]:14.3f} {thr[-1]:12.3f} {thr[-1] / seq[-1]:6.3f} "
                  f"{cpu['sequential']:13.2f} {cpu['threaded']:13.2f} "
                  f"{switches['threaded']:18.1f} {machine[-1]:7.3f} {alone[-1]:7.3f}")
    finally:
        for worker in workers:
            worker.stop()
    ms, mt = float(np.median(seq)), float(np.median(thr))
    ratios = np.array(thr) / np.array(seq)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan
    print(f"load average (1 min) at the end: {load:.1f}")
    print(f"median sequential {ms:.3f} s ({ms / (2 * args.steps) * 1e3:.2f} ms a step), "
          f"threaded {mt:.3f} s")
    print(f"ratio threaded / sequential: {mt / ms:.3f} (of the medians), per repeat "
          f"median {np.median(ratios):.3f}, min {ratios.min():.3f}, max {ratios.max():.3f}")
    print(f"the machine's ratio for compiled loops without Python of the same length "
          f"(column 'machine', {MACHINE_CALLS} calls a step; 0.5 on two free cores): per "
          f"repeat median {np.median(machine):.3f}, min {min(machine):.3f}, max "
          f"{max(machine):.3f}")
    print(f"the wheelsets' own GIL-free calls replayed without the Python between them "
          f"(column 'kernels'): per repeat median {np.median(alone):.3f}, min "
          f"{min(alone):.3f}, max {max(alone):.3f}")
    print("threaded results equal the sequential ones bit for bit")


if __name__ == "__main__":
    main()
