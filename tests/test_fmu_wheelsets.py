"""The FMU of several wheelsets (``railcontact fmu build --wheelsets N``), run by fmpy.

Its truth is the one-wheelset FMU (the default build, ``conftest.default_fmu``, itself
checked against the Python API in ``tests/test_fmu.py``): each wheelset of the N-wheelset
FMU has its own solver with the parameters shared, so its outputs must be those of a
one-wheelset instance given the same inputs, bit for bit. They are stepped in worker
processes (the default on two cores) or on threads of their own (distinct solvers stepping
at the same time give the results of stepping them one after the other bit for bit,
``tests/test_threads.py``, the thread-safety contract of ``docs/performance.md``), and the
two ways write the same outputs: no round-off is allowed. Two builds (N = 1 and N = 2,
without warming the kernels: the default build has them cached).
"""

from __future__ import annotations

import math
import zipfile
from pathlib import Path

import pytest

fmpy = pytest.importorskip("fmpy")
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.model_description import read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402
from test_fmu import Slave  # noqa: E402 - (tests/ is on the path: pytest's rootdir import)

from railcontact.errors import RailContactError  # noqa: E402
from railcontact.fmu import build_fmu  # noqa: E402
from railcontact.fmu import variables as V  # noqa: E402

STEP = 1e-3


class Instance(Slave):
    """An fmpy instance of an FMU unpacked next to it (``test_fmu.Slave``)."""

    def __init__(self, fmu: Path, name: str, **start) -> None:
        where = fmu.parent / f"{fmu.stem}-unpacked"
        if not where.exists():
            with zipfile.ZipFile(fmu) as z:
                z.extractall(where)
        super().__init__(fmu, where, read_model_description(str(fmu)), name, **start)

    def outputs_of(self, suffix: str = "") -> dict:
        """Every output of the one-wheelset FMU's names read with ``suffix`` (the wall
        time apart)."""
        return {n: self.get(n + suffix) for n in SINGLE_OUTPUTS if n != "solve_time"}


SINGLE_OUTPUTS = [v.name for v in V.table() if v.causality == "output"]
SINGLE_INPUTS = [v.name for v in V.table() if v.causality == "input"]


@pytest.fixture(scope="module")
def fmu1(default_fmu) -> Path:
    return build_fmu(default_fmu.parent.parent / "wheelsets1" / "RailContact1.fmu",
                     warm=False, wheelsets=1)


@pytest.fixture(scope="module")
def fmu2(default_fmu) -> Path:
    return build_fmu(default_fmu.parent.parent / "wheelsets2" / "RailContact2.fmu",
                     warm=False, wheelsets=2)


def _motion(k: int, amplitude: float, phase: float) -> dict:
    """Step ``k``'s kinematic inputs of a lateral sine at 1.5 Hz, 30 m/s."""
    w, t = 2 * math.pi * 1.5, k * STEP
    return {"lateral_displacement": amplitude * math.sin(w * t + phase),
            "lateral_velocity": amplitude * w * math.cos(w * t + phase),
            "yaw": 1e-3 * math.cos(w * t + phase), "speed": 30.0}


def _two_motions(k: int) -> dict:
    """Step ``k``'s inputs of the N = 2 FMU: wheelset 1 on a 3 mm sine, wheelset 2 on a
    2 mm one a radian later (:func:`_motion`)."""
    return {f"{n}_{j}": x for j, a in ((1, 3e-3), (2, 2e-3))
            for n, x in _motion(k, a, j).items()}


def test_variables_are_repeated_per_wheelset_and_the_parameters_shared(fmu2):
    """The N = 2 FMU: fmpy's validation clean; the default build's parameters once, the
    Integer parameter wheelsets = 2, each input and output of the default build with _1 and
    _2 (the issue's names: lateral_displacement_1, normal_force_left_1), the worst status;
    a variable's value reference does not depend on N."""
    assert validate_fmu(str(fmu2)) == []
    md = read_model_description(str(fmu2))
    names = {v.name: v for v in md.modelVariables}
    single = V.table()
    parameters = [v.name for v in single if v.causality == "parameter"]
    own = [v.name for v in single if v.causality != "parameter"]
    assert set(names) == ({*parameters, "wheelsets", "status", "solve_time"}
                          | {f"{n}_{k}" for n in own for k in (1, 2)})
    n = names["wheelsets"]
    assert (n.type, n.causality, n.variability, n.start) == ("Integer", "parameter",
                                                             "fixed", "2")
    assert {"lateral_displacement_1", "normal_force_left_1", "status_right_2"} <= set(names)
    for k in range(1, V.MAX_WHEELSETS):  # wheelset k's references, whatever N
        a = {v.name: (v.type, v.vr) for v in V.table(k)}
        b = {v.name: (v.type, v.vr) for v in V.table(V.MAX_WHEELSETS)}
        assert all(b[name] == ref for name, ref in a.items())
    for bad in (0, 9, 2.0, True):
        with pytest.raises(RailContactError, match="1 to 8"):
            V.table(bad)


def test_one_wheelset_equals_the_default_fmu_output_for_output(default_fmu, fmu1):
    """wheelsets = 1: every output x_1 equals the default FMU's x on the same steps (load
    control with the rigid wheelset solved, direct creepages, warm starts), bit for bit;
    status equals status_1."""
    one = Instance(default_fmu, "default")
    multi = Instance(fmu1, "wheelsets1")
    assert multi.get("wheelsets") == 1
    for k, y in enumerate((0.0, 1e-3, 1.5e-3, 2e-3)):
        inputs = {"lateral_displacement": y, "xi_left": 1e-3, "eta_right": -5e-4,
                  "phi_left": 0.3, "load_right": 80e3 + 1e3 * k}
        assert one.step(**inputs) == multi.step(**{f"{n}_1": x for n, x in inputs.items()})
        got = multi.outputs_of("_1")
        assert got == one.outputs_of()
        assert multi.get("status") == got["status"]
    assert got["normal_iterations"] > 0 and got["normal_force_left"] > 50e3
    one.free()
    multi.free()


def test_two_wheelsets_equal_two_single_runs(default_fmu, fmu2, monkeypatch):
    """Two wheelsets on two lateral sines (kinematic creepages) in one FMU equal two
    one-wheelset instances given the same inputs, every output bit for bit, step after step
    (the wheelsets run on two threads at once: RAILCONTACT_FMU_THREADS = 2 whatever the
    cores; the slave runs in this process's Python, fmpy's host, and reads this
    environment)."""
    import threading

    monkeypatch.setenv("RAILCONTACT_FMU_THREADS", "2")
    multi = Instance(fmu2, "two", creepage_input="kinematic")
    singles = [Instance(default_fmu, f"single{j}", creepage_input="kinematic")
               for j in (1, 2)]
    for k in range(5):
        motions = [_motion(k, 3e-3, 0.0), _motion(k, 2e-3, 0.9)]
        inputs = {f"{n}_{j}": x for j, m in enumerate(motions, start=1) for n, x in m.items()}
        assert multi.step(**inputs) == 0
        names = {t.name for t in threading.enumerate()}
        assert {"railcontact-two-0_0", "railcontact-two-1_0"} <= names, names
        for j, (s, m) in enumerate(zip(singles, motions, strict=True), start=1):
            assert s.step(**m) == 0
            assert multi.outputs_of(f"_{j}") == s.outputs_of(), (k, j)
    assert multi.outputs_of("_1") != multi.outputs_of("_2")
    multi.free()
    for s in singles:
        s.free()


def test_a_bad_input_on_one_wheelset_is_its_status(default_fmu, fmu2, capsys):
    """A NaN and an out-of-range yaw on wheelset 2: the step is fmi2Discard (the worst of
    the wheelsets'), wheelset 2's outputs zero with its statuses 3 and its message named,
    wheelset 1 solved as a single instance solves it (status 0); status 3. The next good
    step solves both again."""
    multi = Instance(fmu2, "bad", warm_start="none")
    single = Instance(default_fmu, "bad-single", warm_start="none")
    good = {"lateral_displacement": 2e-3, "xi_left": 1e-3, "xi_right": 1e-3}
    for bad, words in (({"lateral_displacement": float("nan")}, "lateral_displacement = nan"),
                       ({"yaw": 0.5}, "small angles")):
        inputs = {**{f"{n}_1": x for n, x in good.items()},
                  **{f"{n}_2": x for n, x in {**good, **bad}.items()}}
        assert multi.step(**inputs) == 2  # fmi2Discard
        assert single.step(**good) == 0
        assert multi.outputs_of("_1") == single.outputs_of()
        assert multi.get("status_1") == 0
        second = multi.outputs_of("_2")
        assert [second[n] for n in ("status", "status_left", "status_right")] == [3, 3, 3]
        assert all(second[n] == 0 for n in SINGLE_OUTPUTS
                   if n in second and not n.startswith("status"))
        assert multi.get("status") == 3
        log = capsys.readouterr().out
        assert "wheelset 2: " in log and words in log and "wheelset 1: " not in log, log
        multi.set(yaw_2=0.0, lateral_displacement_2=2e-3)
    assert multi.step() == 0
    assert multi.outputs_of("_2") == multi.outputs_of("_1") == single.outputs_of()
    assert multi.get("status") == 0
    multi.free()
    single.free()


@pytest.mark.parametrize("workers", ["2", "processes", "threads"])
def test_state_of_all_wheelsets_round_trips(fmu2, workers, monkeypatch):
    """fmi2GetFMUstate after two steps, three steps more, the state set again (kept and
    serialized): the three steps repeat every output of both wheelsets bit for bit,
    iterations included (the warm start of both wheelsets is in the state, read from and
    set in the worker processes when they step the wheelsets: two of them, or one beside
    the host's process stepping the other wheelset)."""
    monkeypatch.setenv("RAILCONTACT_FMU_WORKERS", workers)
    s = Instance(fmu2, "state", creepage_input="kinematic")
    for k in range(2):
        s.step(**{f"{n}_{j}": x for j, a in ((1, 3e-3), (2, 2e-3))
                  for n, x in _motion(k, a, j).items()})
    state = s.s.getFMUstate()
    serial = s.s.serializeFMUstate(state)
    t0 = s.t

    def run() -> list:
        out = []
        for k in range(2, 5):
            s.step(**{f"{n}_{j}": x for j, a in ((1, 3e-3), (2, 2e-3))
                      for n, x in _motion(k, a, j).items()})
            out.append([s.outputs_of(f"_{j}") for j in (1, 2)])
        return out

    first = run()
    for restore in (state, s.s.deSerializeFMUstate(serial)):
        s.s.setFMUstate(restore)
        s.t = t0
        assert run() == first
    assert first[0][1]["normal_iterations"] < 20  # warm, as the original
    s.s.freeFMUstate(state)
    s.free()


def test_the_wheelsets_parameter_is_fixed(fmu2, capsys):
    """wheelsets set to another number than the build's is an error at initialisation
    naming it."""
    with pytest.raises(FMICallException):
        Instance(fmu2, "three", wheelsets=3)
    assert "this FMU was built for 2 wheelsets" in capsys.readouterr().out


def _outputs(s: Instance) -> list[dict]:
    """Every output of both wheelsets but the wall times, and the worst status."""
    return [{n: x for n, x in s.outputs_of(f"_{j}").items()} for j in (1, 2)] + \
        [s.get("status")]


def _workers_of(instance: str) -> list:
    """The worker processes (multiprocessing's children of this process, fmpy's host) of
    the pools started since those in :data:`_SEEN` (``instance``'s, when it started the
    last): named railcontact-wheelsets-j."""
    import multiprocessing

    return [p for p in multiprocessing.active_children()
            if p.name.startswith("railcontact-wheelsets-") and p.pid not in _SEEN]


_SEEN: set[int] = set()


def test_processes_equal_threads_bit_for_bit(fmu2, monkeypatch):
    """RAILCONTACT_FMU_WORKERS = 2 (two worker processes), = processes (on two cores or
    more: this process steps wheelset 1, one worker process wheelset 2) and = threads on
    the same steps (two lateral sines with kinematic creepages and warm starts; a
    wheelset beyond the profiles; a NaN input; back): every FMI status, every output of
    both wheelsets (the wall times apart) and status equal bit for bit. fmi2FreeInstance
    ends the workers."""
    import os
    import threading

    _SEEN.update(p.pid for p in _workers_of(""))
    monkeypatch.setenv("RAILCONTACT_FMU_WORKERS", "threads")
    threads = Instance(fmu2, "threads", creepage_input="kinematic")
    assert not _workers_of("threads")
    monkeypatch.setenv("RAILCONTACT_FMU_WORKERS", "2")
    procs = Instance(fmu2, "procs", creepage_input="kinematic")
    workers = _workers_of("procs")
    assert sorted(p.name for p in workers) == ["railcontact-wheelsets-0",
                                               "railcontact-wheelsets-1"]
    _SEEN.update(p.pid for p in workers)
    monkeypatch.setenv("RAILCONTACT_FMU_WORKERS", "processes")
    mixed = Instance(fmu2, "mixed", creepage_input="kinematic")
    theirs = _workers_of("mixed")
    if len(os.sched_getaffinity(0)) >= 2:
        assert [p.name for p in theirs] == ["railcontact-wheelsets-0"]
    workers += theirs
    for k in range(7):
        motions = [_motion(k, 3e-3, 0.0), _motion(k, 2e-3, 0.9)]
        if k == 3:
            motions[1]["lateral_displacement"] = 0.08  # beyond the profiles
        if k == 4:
            motions[0]["speed"] = float("nan")
        inputs = {f"{n}_{j}": x for j, m in enumerate(motions, start=1) for n, x in m.items()}
        assert procs.step(**inputs) == threads.step(**inputs) == mixed.step(**inputs), k
        assert _outputs(procs) == _outputs(threads) == _outputs(mixed), k
    assert {t.name for t in threading.enumerate()} >= {"railcontact-threads-0_0",
                                                       "railcontact-threads-1_0"}
    assert not any(t.name.startswith("railcontact-procs") for t in threading.enumerate())
    assert _outputs(procs)[0]["normal_iterations"] > 0
    procs.s.freeInstance()  # (without fmi2Terminate)
    mixed.s.freeInstance()
    for w in workers:
        w.join(30)
        assert not w.is_alive() and w.exitcode == 0
    threads.free()


def test_a_worker_that_ends_is_an_error_and_a_state_restarts_them(fmu2, monkeypatch):
    """A worker process killed: the next fmi2DoStep returns fmi2Error at once (no hang),
    every output zero and every status 3, naming the worker; fmi2SetFMUstate of a state
    saved before starts new workers with the state's memories, and the steps after it
    repeat those of an instance that never lost its workers, bit for bit. fmi2Terminate
    ends the workers; fmi2GetFMUstate still holds both wheelsets' memories."""
    _SEEN.update(p.pid for p in _workers_of(""))
    monkeypatch.setenv("RAILCONTACT_FMU_WORKERS", "2")

    s = Instance(fmu2, "killed", creepage_input="kinematic")
    mine = _workers_of("killed")
    _SEEN.update(p.pid for p in mine)
    truth = Instance(fmu2, "kept", creepage_input="kinematic")
    _SEEN.update(p.pid for p in _workers_of("kept"))
    assert len(mine) == 2
    for k in range(2):
        assert s.step(**_two_motions(k)) == truth.step(**_two_motions(k)) == 0
    state = s.s.getFMUstate()
    mine[1].kill()
    mine[1].join(10)
    assert s.step(**_two_motions(2)) == 3  # fmi2Error
    out = _outputs(s)
    assert [out[j][n] for j in (0, 1) for n in ("status", "status_left")] == [3] * 4
    assert all(x == 0 for j in (0, 1) for n, x in out[j].items() if "status" not in n)
    assert out[2] == 3
    s.s.setFMUstate(state)
    new = _workers_of("restarted")
    assert len(new) == 2
    for k in range(2, 5):
        assert s.step(**_two_motions(k)) == truth.step(**_two_motions(k)) == 0
        assert _outputs(s) == _outputs(truth), k
    s.s.terminate()
    for p in new:
        p.join(30)
        assert not p.is_alive() and p.exitcode == 0
    after = s.s.getFMUstate()  # the memories the workers had at fmi2Terminate
    ref = truth.s.getFMUstate()
    got = []
    for restore in (after, ref):
        truth.s.setFMUstate(restore)
        truth.t = 5 * STEP
        assert truth.step(**_two_motions(5)) == 0
        got.append(_outputs(truth))
    assert got[0] == got[1] and got[0][0]["normal_iterations"] < 20  # warm
    truth.s.freeFMUstate(ref)
    s.s.freeFMUstate(state)
    s.s.freeFMUstate(after)
    s.s.freeInstance()
    truth.free()


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads process states in /proc")
def test_bare_c_host_starts_the_workers_with_python(fmu2, tmp_path):
    """The N = 2 FMU in a C program (``tests/fmu/host.c``: 200 steps of wheelset 1's
    lateral sine, every output read finite; an environment of PATH and HOME only, the
    kernels' per-user cache): the FMU starts Python inside the host, whose program is
    not Python, and steps wheelset 1 there, its worker process (on two cores or more)
    wheelset 2: the worker runs the FMU's Python (the interpreter that built it), not
    the host program; it ends with the instance."""
    import os
    import subprocess
    import sys
    import time

    headers = Path(fmpy.__file__).parent / "c-code"
    host = tmp_path / "host"
    subprocess.run(["gcc", "-O2", f"-I{headers}", str(Path(__file__).parent / "fmu" / "host.c"),
                    "-o", str(host), "-ldl", "-lm"], check=True)
    where = fmu2.parent / f"{fmu2.stem}-unpacked"
    if not where.exists():
        with zipfile.ZipFile(fmu2) as z:
            z.extractall(where)
    md = read_model_description(str(fmu2))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    binary = where / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    env = ["env", "-i", "PATH=/usr/bin:/bin", f"HOME={os.environ.get('HOME', '/')}",
           f"VR_LAT={vr['lateral_displacement_1']}", f"VR_OUT={vr['normal_force_left_1']}"]
    run = subprocess.Popen(env + [str(host), str(binary), (where / "resources").as_uri(),
                                  md.guid, "200", "1"], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)

    def workers() -> dict[int, str]:
        """The host's child processes that run multiprocessing's spawn_main: their
        programs (the host's other children: the shim's probe of its Python, the check of
        the interpreter to start the workers with)."""
        out = {}
        for d in Path("/proc").iterdir():
            try:
                if d.name.isdigit() and int((d / "stat").read_text().rsplit(")", 1)[1]
                                            .split()[1]) == run.pid and \
                        b"spawn_main" in (d / "cmdline").read_bytes():
                    out[int(d.name)] = os.path.realpath(d / "exe")
            except (OSError, IndexError, ValueError):
                continue
        return out

    seen: dict[int, str] = {}
    while run.poll() is None:
        seen.update(workers())
        time.sleep(0.05)
    out, err = run.communicate()
    assert run.returncode == 0, err[-3000:]
    assert "ok: 1 cycles of 200 steps" in out
    assert len(seen) == min(2, len(os.sched_getaffinity(0))) - 1, seen
    assert set(seen.values()) == {os.path.realpath(sys.executable)}, seen
    for pid in seen:  # (ended at fmi2FreeInstance; reaped by the host or init)
        state = Path(f"/proc/{pid}/stat")
        assert not state.exists() or state.read_text().rsplit(")", 1)[1].split()[0] == "Z"


def test_no_python_to_start_the_workers_is_threads_and_a_warning(fmu2, monkeypatch, capsys):
    """When no Python interpreter is found to start the worker processes with
    (worker_python() None: Python embedded in a program, its environment gone), the
    wheelsets are stepped on threads: initialisation returns fmi2Warning saying why and
    how to choose threads, the steps are solved (status 0) on the instance's threads."""
    import sys
    import threading

    monkeypatch.setenv("RAILCONTACT_FMU_WORKERS", "threads")
    Instance(fmu2, "loaded").free()  # (the FMU's slave module imported in this process)
    for name, module in list(sys.modules.items()):  # (FMUs of one model identifier
        if name.startswith("railcontact_fmu_") and name.endswith("._fmu_slave"):  # share it)
            monkeypatch.setattr(module, "worker_python", lambda: None)
    monkeypatch.setenv("RAILCONTACT_FMU_WORKERS", "processes")
    capsys.readouterr()
    _SEEN.update(p.pid for p in _workers_of(""))
    s = Instance(fmu2, "nopython", creepage_input="kinematic")
    log = capsys.readouterr().out
    assert "[WARNING]" in log and "not in worker processes: no Python" in log, log
    assert "RAILCONTACT_FMU_WORKERS=threads" in log
    assert s.step(**{f"{n}_{j}": x for j in (1, 2) for n, x in _motion(1, 2e-3, j).items()}) == 0
    assert {"railcontact-nopython-0_0", "railcontact-nopython-1_0"} <= \
        {t.name for t in threading.enumerate()}
    assert not _workers_of("nopython")
    s.free()


def test_libcosim_processes_equal_threads(fmu2, monkeypatch):
    """The N = 2 FMU in libcosim (its own threads call the FMU; the slave in this
    process's Python): with worker processes (two, running while it steps) the wheel
    forces of both wheelsets after three steps equal those with threads bit for bit."""
    pytest.importorskip("libcosimpy")
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    def run(workers: str) -> tuple[list[float], list]:
        monkeypatch.setenv("RAILCONTACT_FMU_WORKERS", workers)
        _SEEN.update(p.pid for p in _workers_of(""))
        ex = CosimExecution.from_step_size(step_size=int(1e6))  # 1 ms in ns
        i = ex.add_local_slave(local_slave=CosimLocalSlave(fmu_path=str(fmu2),
                                                           instance_name=workers))
        obs = CosimObserver.create_last_value()
        ex.add_observer(observer=obs)
        vr = {v.name.decode(): v.reference for v in ex.slave_variables(slave_index=i)}
        for k in (1, 2):
            ex.real_initial_value(slave_index=i, variable_reference=vr[f"xi_left_{k}"],
                                  value=1e-3)
            ex.real_initial_value(slave_index=i,
                                  variable_reference=vr[f"lateral_displacement_{k}"],
                                  value=1.5e-3 * k)
        assert ex.step(step_count=3)
        names = [f"{n}_{k}" for k in (1, 2) for n in ("normal_force_left", "creep_force_x_left",
                                                       "force_lateral")]
        got = obs.last_real_values(slave_index=i, variable_references=[vr[n] for n in names])
        return got, _workers_of(workers)

    there, workers = run("2")
    here, none = run("threads")
    assert len(workers) == 2 and not none
    assert there == here and there[0] > 50e3 and there[1] != 0.0


def test_worker_timeout_is_an_error_not_a_wait(fmu2, monkeypatch, capsys):
    """RAILCONTACT_FMU_WORKER_TIMEOUT: a worker that does not answer within it (1 ms
    against the tens of milliseconds of the first, cold step at initialisation) is an
    fmi2Error naming the timeout, the workers ended; a value that is no number above 0 is
    an error at initialisation naming the variable."""
    monkeypatch.setenv("RAILCONTACT_FMU_WORKERS", "2")
    _SEEN.update(p.pid for p in _workers_of(""))
    monkeypatch.setenv("RAILCONTACT_FMU_WORKER_TIMEOUT", "0.001")
    with pytest.raises(FMICallException):
        Instance(fmu2, "hurried")
    assert "did not answer within 0.001 s" in capsys.readouterr().out
    for w in _workers_of("hurried"):
        w.join(30)
        assert not w.is_alive()
    monkeypatch.setenv("RAILCONTACT_FMU_WORKER_TIMEOUT", "soon")
    with pytest.raises(FMICallException):
        Instance(fmu2, "soon")
    assert "RAILCONTACT_FMU_WORKER_TIMEOUT = 'soon'" in capsys.readouterr().out


def test_reset_keeps_the_workers_and_builds_their_wheelsets_anew(fmu2, monkeypatch,
                                                                 capsys):
    """fmi2Reset and a new initialisation: the same worker processes, their wheelsets
    built anew (the steps equal a new instance's bit for bit: no memory of the steps
    before the reset). RAILCONTACT_FMU_WORKERS that is neither processes, threads nor a
    positive integer is an error at initialisation naming it."""
    monkeypatch.setenv("RAILCONTACT_FMU_WORKERS", "2")
    _SEEN.update(p.pid for p in _workers_of(""))

    s = Instance(fmu2, "reset", creepage_input="kinematic")
    mine = _workers_of("reset")
    _SEEN.update(p.pid for p in mine)
    for k in range(3):
        s.step(**_two_motions(k))
    s.reset(creepage_input="kinematic")
    fresh = Instance(fmu2, "fresh", creepage_input="kinematic")
    for k in range(1, 3):
        assert s.step(**_two_motions(k)) == fresh.step(**_two_motions(k)) == 0
        assert _outputs(s) == _outputs(fresh), k
    assert all(p.is_alive() for p in mine) and len(mine) == 2
    s.free()
    fresh.free()
    monkeypatch.setenv("RAILCONTACT_FMU_WORKERS", "many")
    with pytest.raises(FMICallException):
        Instance(fmu2, "many")
    assert "RAILCONTACT_FMU_WORKERS = 'many'" in capsys.readouterr().out
