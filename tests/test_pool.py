"""Wheelsets stepped in worker processes (railcontact.timestep.pool): the same results as
the in-process WheelsetContact (whose physics the time-step tests verify) bit for bit over
warm steps, errors raised in the host with the pool still working, workers ended by
close(); and the vehicle's contact stepped in processes equal to the in-process one."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import railcontact as rc
from railcontact.errors import RailContactError
from railcontact.sim.vehicle_contact import InProcessContact, WheelsetStates
from railcontact.timestep.memory import StepMemory
from railcontact.timestep.pool import WheelsetDescription, WheelsetPool

STEPS = 3
"""Warm steps compared (the first one cold)."""


def description() -> WheelsetDescription:
    """S1002 on 60E1 at 1:40, coarse elements (quick)."""
    return WheelsetDescription(rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
                               rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                               rc.ElasticPair.of(rc.STEEL, rc.STEEL),
                               rc.ContactSettings(friction=0.4, element_size=1.5e-3))


def inputs(i: int, k: int) -> dict:
    """Wheelset ``i``'s solve arguments at step ``k`` (1 ms steps): a lateral sine of its
    own amplitude and phase, load control, kinematic creepages."""
    w = 2 * math.pi * 1.5
    a, phase = 2e-3 + 1e-3 * i, 0.7 * i
    y, y_dot = a * math.sin(w * k * 1e-3 + phase), a * w * math.cos(w * k * 1e-3 + phase)
    return dict(pose=rc.Pose(y, 0.2 * y_dot / 30.0), loads=(83e3 + 2e3 * i, 83e3 - 2e3 * i),
                kinematics=rc.Kinematics(30.0, y_dot), time=k * 1e-3)


def same(a: rc.WheelsetResult, b: rc.WheelsetResult) -> None:
    """Every reported value of two wheelset results equal bit for bit."""
    assert a.status == b.status and a.vertical == b.vertical and a.roll == b.roll
    for wa, wb in zip(a.wheels, b.wheels, strict=True):
        for name in ("status", "message", "normal_force", "creep_force", "spin_moment",
                     "track_force", "yaw_moment", "approach", "moment", "rolling_radius",
                     "contact_angle", "derailment_quotient", "normal_iterations",
                     "tangential_iterations", "load_passes", "area", "max_pressure"):
            assert getattr(wa, name) == getattr(wb, name), name
        assert len(wa.patches) == len(wb.patches)
        for pa, pb in zip(wa.patches, wb.patches, strict=True):
            assert pa.normal.pressure.tobytes() == pb.normal.pressure.tobytes()
            assert np.asarray(pa.tangential.traction).tobytes() == \
                np.asarray(pb.tangential.traction).tobytes()
            assert pa.tangential.relative_slip().tobytes() == \
                pb.tangential.relative_slip().tobytes()


@pytest.fixture(scope="module")
def pool():
    with WheelsetPool([description() for _ in range(3)], processes=2) as p:
        yield p


def _steps_equal_in_process(pool):
    """STEPS steps of the three wheelsets through ``pool`` equal the same wheelsets solved
    in this process bit for bit, each solve's time recorded."""
    here = [description().build() for _ in range(3)]
    for k in range(STEPS):
        there = pool.step([inputs(i, k) for i in range(3)])
        for i in range(3):
            same(there[i], here[i].solve(**inputs(i, k)))
            assert pool.seconds[i] > 0


def test_pool_results_equal_in_process_bit_for_bit(pool):
    assert pool.processes == 2 and pool.shares == [[0, 2], [1]]
    _steps_equal_in_process(pool)


def _raises_as_alone(pool, k, index):
    """Step ``pool`` at step ``k`` with a negative wheel load on wheelset ``index`` (0-based):
    the pool raises the error that wheelset raises alone, noting which wheelset it was.
    Returns the inputs stepped."""
    bad = [inputs(i, k) for i in range(3)]
    bad[index]["loads"] = (-1.0, 83e3)
    with pytest.raises(RailContactError) as alone:
        description().build().solve(**bad[index])
    with pytest.raises(RailContactError) as raised:
        pool.step(bad)
    assert str(raised.value) == str(alone.value)
    assert any(f"wheelset {index + 1}" in note for note in raised.value.__notes__)
    return bad


def test_an_error_comes_back_and_the_pool_keeps_working(pool):
    _raises_as_alone(pool, 10, 1)
    with pytest.raises(TypeError, match="unexpected keyword"):
        pool.step([inputs(0, 11), inputs(1, 11), {**inputs(2, 11), "speed": 3.0}])
    with pytest.raises(Exception, match="pickle"):  # an input that cannot be sent
        pool.step([inputs(0, 11), inputs(1, 11), {**inputs(2, 11), "time": lambda: 0.0}])
    assert pool.alive
    out = pool.step([inputs(i, 12) for i in range(3)])
    assert all(r.status == rc.Status.OK for r in out), [r.status for r in out]
    with pytest.raises(RailContactError, match="3 wheelsets' inputs expected"):
        pool.step([inputs(0, 13)])


def test_close_ends_the_workers_and_bad_pools_are_refused():
    p = WheelsetPool([description(), description()], processes=5)
    assert p.processes == 2 and p.alive
    procs = list(p._processes)
    p.close()
    p.close()
    assert not p.alive and all(not q.is_alive() and q.exitcode == 0 for q in procs)
    with pytest.raises(RailContactError, match="closed"):
        p.step([inputs(0, 0), inputs(1, 0)])
    with pytest.raises(RailContactError, match="at least one wheelset"):
        WheelsetPool([])
    with pytest.raises(RailContactError, match="processes must be at least 1"):
        WheelsetPool([description()], processes=0)
    with pytest.raises(RailContactError, match="module's top level"):
        WheelsetPool([description()], reduce=lambda r: r.force)
    with pytest.raises(RailContactError, match="WheelsetDescription expected"):
        WheelsetPool([description().build()])
    d = description()
    # two wheel radii on one axle: refused when the worker builds the wheelset
    broken = WheelsetDescription(d.track, (d.wheelset, rc.Wheelset(d.wheelset.wheel, 0.45)),
                                 d.pair, d.settings)
    with pytest.raises(RailContactError) as here:
        broken.build()
    with pytest.raises(RailContactError) as there:
        WheelsetPool([d, broken], processes=2)
    assert str(there.value) == str(here.value) and "wheel radius" in str(here.value)


def test_vehicle_contact_in_processes_equals_in_process():
    d = description()
    n = 2
    with InProcessContact(d.track, d.wheelset, d.pair, d.settings, count=n) as here, \
            InProcessContact(d.track, d.wheelset, d.pair, d.settings, count=n,
                             processes=2) as there:
        assert here.pool is None and there.pool is not None
        for k in range(STEPS):
            a = [inputs(i, k) for i in range(n)]
            states = WheelsetStates(
                k * 1e-3, 30.0, np.array([x["pose"].lateral for x in a]),
                np.array([x["pose"].yaw for x in a]),
                np.array([x["kinematics"].lateral_velocity for x in a]), np.zeros(n),
                np.full(n, 30.0 / 0.46), np.array([x["loads"] for x in a]))
            fa, fb = here(states), there(states)
            for name in ("generalized", "lateral", "vertical", "normal",
                         "derailment_quotient", "status", "iterations"):
                assert getattr(fa, name).tobytes() == getattr(fb, name).tobytes(), name
            assert (fa.ok, fa.message) == (fb.ok, fb.message)
    assert not there.pool.alive


def test_reset_builds_new_wheelsets_in_the_same_workers(pool):
    pids = [p.pid for p in pool._processes]
    pool.reset()
    here = [description().build() for _ in range(3)]
    for k in range(2):
        there = pool.step([inputs(i, k) for i in range(3)])
        for i in range(3):
            same(there[i], here[i].solve(**inputs(i, k)))
    assert [p.pid for p in pool._processes] == pids
    with pytest.raises(RailContactError, match="3 wheelset descriptions expected"):
        pool.reset([description()])
    # a description that is not one: named before any wheelset is reset (was an
    # AttributeError from its worker, after the others were reset)
    assert all(m.wheel("left") for m in pool.memories())  # (warm after the steps)
    with pytest.raises(RailContactError,
                       match="wheelset 3: a WheelsetDescription expected, got str"):
        pool.reset([description(), description(), "nope"])
    assert all(m.wheel("left") for m in pool.memories())  # none was reset


def test_demo_vehicle_in_processes_runs_as_in_process(capsys, tmp_path):
    """``railcontact demo --vehicle --contact in-process --processes 2``: the vehicle's
    motion equal bit for bit to the run in this process; --processes without the
    in-process contact is refused (one line, exit status 2)."""
    from railcontact.cli import main
    from railcontact.sim.vehicle_demo import VehicleDemoOptions, run_vehicle_demo

    opts = dict(contact="in-process", duration=0.004, step=0.002, element_size=2e-3,
                plots=False)
    here = run_vehicle_demo(VehicleDemoOptions(**opts), progress=False)
    there = run_vehicle_demo(VehicleDemoOptions(**opts, processes=2), progress=False)
    assert here.sim.completed and there.sim.completed
    assert here.sim.wheelset_lateral().tobytes() == there.sim.wheelset_lateral().tobytes()
    assert "in 2 worker processes" in there.text
    assert main(["demo", "--vehicle", "--contact", "in-process", "--processes", "2",
                 "--duration", "0.002", "--step", "0.002", "--element-size", "2e-3",
                 "--no-plots", "--no-progress", "--output-dir", str(tmp_path)]) == 0
    assert "real-time factor" in capsys.readouterr().out
    assert main(["demo", "--vehicle", "--processes", "2", "--no-progress"]) == 2
    assert "processes" in capsys.readouterr().err


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads process states in /proc")
def test_workers_end_with_their_host(tmp_path):
    """A host that ends without closing its pool (``os._exit``: no atexit, no finaliser):
    its workers see their pipes close and end."""
    import os
    import subprocess
    import sys
    import time

    script = tmp_path / "host.py"
    script.write_text(
        "import os, sys\n"
        f"sys.path.insert(0, {str(Path(__file__).parent)!r})\n"
        "from test_pool import description\n"
        "from railcontact.timestep.pool import WheelsetPool\n"
        "if __name__ == '__main__':\n"
        "    pool = WheelsetPool([description(), description()], processes=2)\n"
        "    print(*[p.pid for p in pool._processes], flush=True)\n"
        "    os._exit(0)\n", encoding="utf-8")
    root = Path(__file__).resolve().parents[1]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(root), *filter(None, [os.environ.get("PYTHONPATH")])])}
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         env=env, timeout=300, check=True)
    pids = [int(x) for x in out.stdout.split()]
    assert len(pids) == 2

    def running(pid: int) -> bool:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().split()[2]
        except FileNotFoundError:
            return False
        return state != "Z"

    for _ in range(300):  # up to 30 s
        if not any(running(pid) for pid in pids):
            break
        time.sleep(0.1)
    assert not any(running(pid) for pid in pids)


def test_memories_round_trip_and_skipped_wheelsets(pool):
    """memories() read in the workers and set_memories() there: the steps after a memory
    set again repeat those after it was read, bit for bit (and equal the in-process
    wheelsets'); None forgets (the next step as a cold one: a fresh wheelset's). A None
    input skips its wheelset (its result None, its memory unchanged); errors="return"
    puts a wheelset's exception in its place, the others solved."""
    pool.reset()
    here = [description().build() for _ in range(3)]
    for k in range(2):
        pool.step([inputs(i, k) for i in range(3)])
        for i in range(3):
            here[i].solve(**inputs(i, k))
    kept = pool.memories()
    assert all(isinstance(m, StepMemory) and m.left for m in kept)
    first = pool.step([inputs(i, 2) for i in range(3)])
    pool.set_memories(kept)
    again = pool.step([inputs(i, 2) for i in range(3)])
    for i in range(3):
        same(again[i], first[i])
        same(again[i], here[i].solve(**inputs(i, 2)))
    pool.set_memories([kept[0], None, kept[2]])
    cold = pool.step([None, inputs(1, 2), None])
    assert cold[0] is None and cold[2] is None and pool.seconds[0] == 0.0
    same(cold[1], description().build().solve(**inputs(1, 2)))
    same(pool.step([inputs(0, 2), None, None])[0], first[0])  # (its memory unchanged)
    bad = [inputs(i, 3) for i in range(3)]
    bad[1]["loads"] = (-1.0, 83e3)
    out = pool.step(bad, errors="return")
    assert isinstance(out[1], RailContactError) and "wheelset 2" in out[1].__notes__[0]
    assert all(isinstance(out[i], rc.WheelsetResult) for i in (0, 2))
    with pytest.raises(RailContactError, match="3 wheelsets' memories expected"):
        pool.set_memories(kept[:2])
    with pytest.raises(RailContactError, match="a StepMemory or None expected"):
        pool.set_memories([kept[0], "memory", None])
    with pytest.raises(RailContactError, match='errors must be "raise" or "return"'):
        pool.step(bad, errors="ignore")


def test_worker_python_is_a_python_of_this_version(monkeypatch, tmp_path):
    """worker_python(): sys.executable when it is this Python; the environment's
    bin/python3 when sys.executable is another program (Python embedded in a C host);
    None when no Python of this version is found."""
    import os
    import sys

    from railcontact.timestep.pool import worker_python

    assert worker_python() == sys.executable
    monkeypatch.setattr(sys, "executable", "/bin/true")  # a program that is not Python
    assert worker_python() == os.path.join(sys.prefix, "bin", "python3")
    for name in ("prefix", "base_prefix", "_base_executable"):
        monkeypatch.setattr(sys, name, str(tmp_path / "nothing"))
    assert worker_python() is None


def test_workers_without_the_hosts_main_module(tmp_path):
    """A host script without the ``if __name__ == "__main__"`` guard: with main=False its
    workers do not run it again (its top level runs once) and step as usual; with the
    default, spawn runs it in the worker, where starting a pool again fails and the worker
    ends: the host's pool says so at once (no wait for ever)."""
    import os
    import subprocess
    import sys

    script = tmp_path / "host.py"
    root = Path(__file__).resolve().parents[1]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(root), *filter(None, [os.environ.get("PYTHONPATH")])])}
    for main, ok in ((False, True), (True, False)):
        script.write_text(
            "import sys\n"
            f"sys.path.insert(0, {str(Path(__file__).parent)!r})\n"
            "from test_pool import description, inputs\n"
            "from railcontact.timestep.pool import WheelsetPool\n"
            "print('top level', flush=True)\n"
            f"with WheelsetPool([description(), description()], 2, main={main}) as pool:\n"
            "    out = pool.step([inputs(0, 0), inputs(1, 0)])\n"
            "print('stepped', [int(r.status) for r in out], flush=True)\n", encoding="utf-8")
        out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                             env=env, timeout=300)
        if ok:
            assert out.returncode == 0, out.stderr[-2000:]
            assert out.stdout.splitlines() == ["top level", "stepped [0, 0]"], out.stdout
        else:
            assert out.returncode != 0 and out.stdout.count("top level") > 1
            assert "bootstrapping phase" in out.stderr
            assert "of the wheelset pool ended as it started" in out.stderr


def test_a_worker_that_does_not_answer_in_time_closes_the_pool():
    """timeout: a step that takes longer than it raises at once (the pool closed, its
    workers ended), not when the step ends; a timeout not above 0 is refused."""
    import time

    with WheelsetPool([description()], 1, timeout=1e-3) as p:
        t0 = time.perf_counter()
        with pytest.raises(RailContactError, match="did not answer within 0.001 s"):
            p.step([inputs(0, 0)])  # (a cold step: tens of milliseconds)
        assert time.perf_counter() - t0 < 30 and not p.alive
        assert all(not q.is_alive() for q in p._processes)
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(RailContactError, match="timeout must be above 0 s"):
            WheelsetPool([description()], timeout=bad)


def test_this_process_steps_its_share_as_a_worker_would():
    """here=True: this process steps the first share (wheelsets 1 and 3 of three in two
    processes), one worker process the other; the results equal the in-process
    wheelsets' bit for bit over warm steps, memories round trip here and there, an error
    of a wheelset stepped here comes back as a worker's does (its type, message and a note
    naming the wheelset; errors="return" puts it in its place), reset builds all anew,
    and a closed pool refuses every request."""
    with WheelsetPool([description() for _ in range(3)], processes=2, here=True) as p:
        assert p.here and p.processes == 2 and p.shares == [[0, 2], [1]]
        assert len(p._processes) == 1 and p.alive
        _steps_equal_in_process(p)
        kept = p.memories()
        assert all(isinstance(m, StepMemory) and m.left for m in kept)
        first = p.step([inputs(i, STEPS) for i in range(3)])
        p.set_memories(kept)
        again = p.step([inputs(i, STEPS) for i in range(3)])
        for i in range(3):
            same(again[i], first[i])
        bad = _raises_as_alone(p, STEPS + 1, 0)
        out = p.step(bad, errors="return")
        assert isinstance(out[0], RailContactError) and "wheelset 1" in out[0].__notes__[0]
        assert all(isinstance(out[i], rc.WheelsetResult) for i in (1, 2))
        p.reset()
        fresh = [description().build() for _ in range(3)]
        for i, r in enumerate(p.step([inputs(i, 0) for i in range(3)])):
            same(r, fresh[i].solve(**inputs(i, 0)))
    for request in (p.memories, lambda: p.set_memories(kept), p.reset,
                    lambda: p.step([inputs(i, 0) for i in range(3)])):
        with pytest.raises(RailContactError, match="closed"):
            request()
