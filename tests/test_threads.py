"""Two wheelsets stepping on two threads (the thread-safety contract of
``docs/performance.md``): the same results, bit for bit, as one after the other; and every
compiled kernel of the package that does more than a few microseconds of work releases the
GIL."""

from __future__ import annotations

import importlib
import math
import pkgutil
import threading

import numpy as np
import pytest

import railcontact as rc

numba = pytest.importorskip("numba")

TRAJECTORIES = ((3e-3, 1.5, 0.0), (2e-3, 2.1, 0.7))
"""Lateral amplitude [m], frequency [Hz] and phase [rad] of the two wheelsets' sines."""
STEPS = 6
KERNEL_PACKAGES = ("contact", "geometry", "halfspace", "normal", "tangential", "timestep")
"""The subpackages a time step runs (the tables' kernel needs the ``table`` extra)."""


def _fingerprint(result) -> tuple:
    """Per wheel: status, forces, moments, approach, iteration counts and each patch's
    pressure and traction as bytes (equal only when equal bit for bit)."""
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


def _run(wc: rc.WheelsetContact, trajectory, barrier: threading.Barrier | None = None
         ) -> list[tuple]:
    amplitude, frequency, phase = trajectory
    w = 2 * math.pi * frequency
    out = []
    for k in range(STEPS):
        t = k * 1e-3
        if barrier is not None:  # the two threads step together: their calls interleave
            barrier.wait()
        r = wc.solve(rc.Pose(amplitude * math.sin(w * t + phase)), loads=(83.3e3, 83.3e3),
                     kinematics=rc.Kinematics(30.0, amplitude * w * math.cos(w * t + phase)),
                     time=t)
        out.append(_fingerprint(r))
    return out


def test_two_wheelsets_on_two_threads_equal_one_after_the_other():
    """Two WheelsetContact instances sharing one track, wheelset, material pair and
    settings, stepped on two threads in lockstep, give the results of stepping them one
    after the other in one thread, bit for bit (forces, moments, iteration counts,
    pressures and tractions)."""
    track = rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40))
    wheelset = rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46)
    pair = rc.ElasticPair.of(rc.STEEL, rc.STEEL)
    settings = rc.ContactSettings(friction=0.4, element_size=0.5e-3,
                                  warm_start="previous+estimate")

    def wheelsets():
        return [rc.WheelsetContact(track, wheelset, pair, settings) for _ in TRAJECTORIES]

    sequential = [_run(wc, tr) for wc, tr in zip(wheelsets(), TRAJECTORIES, strict=True)]
    assert all(w[0] == 0 for steps in sequential for step in steps for w in step), \
        "the runs must solve (status ok) for the comparison to mean something"

    barrier = threading.Barrier(len(TRAJECTORIES))
    threaded: list = [None] * len(TRAJECTORIES)
    errors: list = []

    def work(k, wc, tr):
        try:
            threaded[k] = _run(wc, tr, barrier)
        except BaseException as exc:  # reported below
            errors.append(exc)
            barrier.abort()

    threads = [threading.Thread(target=work, args=(k, wc, tr))
               for k, (wc, tr) in enumerate(zip(wheelsets(), TRAJECTORIES, strict=True))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    assert sequential[0] != sequential[1]  # two different runs
    for k in range(len(TRAJECTORIES)):
        for step, (a, b) in enumerate(zip(threaded[k], sequential[k], strict=True)):
            assert a == b, f"wheelset {k}, step {step}: threaded != sequential"


def _dispatchers():
    """Every numba-compiled function in the package's modules (name, dispatcher)."""
    from numba.core.registry import CPUDispatcher

    names = [m.name for m in pkgutil.walk_packages(rc.__path__, "railcontact.")
             if m.name.split(".")[1] in KERNEL_PACKAGES]
    found = []
    for name in names:
        module = importlib.import_module(name)
        for attr, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.__module__ == name:
                found.append((f"{name}.{attr}", value))
    return found


SHORT_KERNELS = {
    "railcontact.contact.patch._uncovered", "railcontact.geometry.kernels.count_runs",
    "railcontact.geometry.kernels.gap_on_frame",
    "railcontact.geometry.kernels.gap_on_grid_part",
    "railcontact.geometry.kernels.merge_saddles",
    "railcontact.geometry.kernels.overlap_box_frame", "railcontact.halfspace.grid._bilinear",
    "railcontact.halfspace.sums.numpy_sum",
    "railcontact.normal.resolution._span", "railcontact.timestep.results._moment_sums",
    "railcontact.timestep.warmstart._pressure_start",
    "railcontact.timestep.warmstart._rate_on",
    "railcontact.timestep.warmstart._traction_start"}
"""Kernels a warm step calls from Python that take 2-9 us a call (scripts/bench_threads.py
--profile): they keep the GIL, since handing it to another thread and waiting to take it
back costs more than they do."""


def test_every_long_compiled_kernel_releases_the_gil():
    """The contract's premise: the package's numba kernels run without the GIL
    (``nogil=True``), so that two wheelsets overlap on two cores; only the short ones of
    :data:`SHORT_KERNELS` keep it."""
    kernels = dict(_dispatchers())
    assert len(kernels) > 50
    assert SHORT_KERNELS <= kernels.keys(), SHORT_KERNELS - kernels.keys()
    holding = {name for name, d in kernels.items() if not d.targetoptions.get("nogil")}
    assert holding == SHORT_KERNELS, (holding - SHORT_KERNELS, SHORT_KERNELS - holding)
