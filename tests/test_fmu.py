"""The FMU: built once into a temporary folder, then run by fmpy, libcosim and a bare C host.

The reference for the outputs is railcontact's own Python API (WheelsetContact) called with
the same inputs: the FMU must be a faithful shell around it. The physics of the API is
verified elsewhere (test_wheel_rail, test_tangential, test_wheelset).
"""

from __future__ import annotations

import math
import subprocess
import xml.etree.ElementTree as ET
import zipfile
from functools import partial
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
from fmpy import simulate_fmu  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402
from fmpy.model_description import read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from railcontact.geometry.profiles import read_profile  # noqa: E402
from railcontact.geometry.track import Pose, Track, Wheelset  # noqa: E402
from railcontact.halfspace.materials import ElasticPair, Material  # noqa: E402
from railcontact.status import Status  # noqa: E402
from railcontact.timestep.wheelset import ContactSettings, WheelsetContact  # noqa: E402

STEP = 1e-3
CREEP = {"xi_left": 1e-3, "eta_left": -5e-4, "phi_left": 0.3,
         "xi_right": 1e-3, "eta_right": -5e-4, "phi_right": -0.3}


@pytest.fixture(scope="module")
def fmu(default_fmu) -> Path:
    return default_fmu  # (conftest.py: built once, with models/profiles/S1002.txt)


@pytest.fixture(scope="module")
def extracted(fmu, tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("unzipped")
    with zipfile.ZipFile(fmu) as z:
        z.extractall(d)
    return d


@pytest.fixture(scope="module")
def md(fmu):
    return read_model_description(str(fmu))


def api(warm_start="none", friction=0.4, rigid_wheelset="solve") -> WheelsetContact:
    """The API's wheelset contact with the FMU's default settings (the rigid wheelset
    solved under load control)."""
    mat = Material(206e9, 0.28)
    return WheelsetContact(
        Track(read_profile("60E1", "rail"), math.atan(1 / 40), 1.435),
        Wheelset(read_profile("S1002", "wheel"), 0.46, 1.360), ElasticPair.of(mat, mat),
        ContactSettings(friction=friction, warm_start=warm_start,
                        rigid_wheelset=rigid_wheelset))


class Slave:
    """FMU2Slave with names."""

    def __init__(self, fmu, extracted, md, name="rc", **start):
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.type = {v.name: v.type for v in md.modelVariables}
        self.s = FMU2Slave(guid=md.guid, unzipDirectory=str(extracted),
                           modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.s.instantiate()
        self.s.setupExperiment(startTime=0.0)
        self.s.enterInitializationMode()
        self.set(**start)
        self.s.exitInitializationMode()
        self.t = 0.0

    def set(self, **values):
        for k, v in values.items():
            if self.type[k] == "String":
                self.s.setString([self.vr[k]], [v])
            elif self.type[k] in ("Integer", "Enumeration"):
                self.s.setInteger([self.vr[k]], [int(v)])
            else:
                self.s.setReal([self.vr[k]], [float(v)])

    def get(self, *names):
        out = []
        for n in names:
            if self.type[n] in ("Integer", "Enumeration"):
                out.append(self.s.getInteger([self.vr[n]])[0])
            else:
                out.append(self.s.getReal([self.vr[n]])[0])
        return out if len(out) > 1 else out[0]

    def step(self, **inputs):
        """doStep; its FMI status (fmpy raises for Discard and worse)."""
        from fmpy.fmi1 import FMICallException

        self.set(**inputs)
        try:
            self.s.doStep(self.t, STEP)  # returns nothing for OK and Warning
        except FMICallException as exc:
            return exc.status
        self.t += STEP
        return 0

    def reset(self, **start):
        """fmi2Reset, then initialise again with the parameters ``start``: the instance as
        a new one, time 0."""
        self.s.reset()
        self.s.setupExperiment(startTime=0.0)
        self.s.enterInitializationMode()
        self.set(**start)
        self.s.exitInitializationMode()
        self.t = 0.0

    def free(self):
        self.s.terminate()
        self.s.freeInstance()


def test_validate(fmu):
    assert validate_fmu(str(fmu)) == []


def test_model_description_units_and_variables(md):
    names = {v.name: v for v in md.modelVariables}
    for n in ("lateral_displacement", "yaw", "load_left", "vertical_displacement", "roll",
              "speed", "xi_left", "lateral_velocity", "yaw_rate", "spin_speed",
              "normal_force_right", "creep_force_x_left", "force_lateral", "yaw_moment",
              "max_pressure_left", "slip_area_ratio_right", "n_patches_left", "status",
              "normal_iterations", "tangential_iterations", "solve_time", "warm_start",
              "element_size", "normal_tolerance", "tangential_tolerance", "fft"):
        assert n in names, n
    assert names["load_left"].unit == "N" and names["max_pressure_left"].unit == "Pa"
    assert names["status"].variability == "discrete"


def test_simulate_matches_python_api(fmu):
    """A structured input signal (lateral sweep +-6 mm, creepages) through
    fmpy.simulate_fmu; every row equals the API's solution for that row's inputs."""
    t = np.arange(0.0, 0.0125, 0.001)
    names = ["lateral_displacement", *CREEP]
    sig = np.zeros(len(t), dtype=[("time", float)] + [(n, float) for n in names])
    sig["time"] = t
    sig["lateral_displacement"] = 6e-3 * np.sin(2 * np.pi * t / t[-1])
    for k, v in CREEP.items():
        sig[k] = v * (1 + 0.5 * np.cos(2 * np.pi * t / t[-1]))
    outs = ["normal_force_left", "normal_force_right", "creep_force_x_left",
            "creep_force_y_right", "spin_moment_left", "force_lateral", "yaw_moment",
            "contact_angle_left", "max_pressure_right", "contact_longitudinal_position_left",
            "contact_lateral_position_right", "contact_vertical_position_left"]
    res = simulate_fmu(str(fmu), stop_time=t[-1], step_size=STEP, input=sig,
                       output=names + outs, start_values={"warm_start": "none"})
    ref = api("none")
    for row in res[1:]:
        creep = tuple(tuple(row[f"{c}_{s}"] for c in ("xi", "eta", "phi"))
                      for s in ("left", "right"))
        r = ref.solve(Pose(row["lateral_displacement"]), loads=(83.3e3, 83.3e3),
                      creepages=creep)
        want = [r.left.normal_force, r.right.normal_force, r.left.creep_force[0],
                r.right.creep_force[1], r.left.spin_moment, r.force[1], r.yaw_moment,
                r.left.contact_angle, r.right.max_pressure, r.left.contact_point[0],
                r.right.contact_point[1], r.left.contact_point[2]]
        np.testing.assert_allclose([row[n] for n in outs], want, rtol=1e-9, atol=1e-9)
    # the sweep reaches flange contact on both sides
    assert res["contact_angle_left"].max() > 0.3


def test_two_instances_with_different_parameters(fmu, extracted, md):
    a = Slave(fmu, extracted, md, "a", friction=0.4, warm_start="none")
    b = Slave(fmu, extracted, md, "b", friction=0.15, warm_start="none")
    inputs = dict(CREEP, lateral_displacement=1e-3, xi_left=3e-3)
    ra = api("none", 0.4).solve(Pose(1e-3), loads=(83.3e3, 83.3e3),
                                creepages=((3e-3, -5e-4, 0.3), (1e-3, -5e-4, -0.3)))
    rb = api("none", 0.15).solve(Pose(1e-3), loads=(83.3e3, 83.3e3),
                                 creepages=((3e-3, -5e-4, 0.3), (1e-3, -5e-4, -0.3)))
    for _ in range(2):  # interleaved
        a.step(**inputs)
        b.step(**inputs)
        assert a.get("creep_force_x_left") == pytest.approx(ra.left.creep_force[0], rel=1e-9)
        assert b.get("creep_force_x_left") == pytest.approx(rb.left.creep_force[0], rel=1e-9)
    # lower friction, smaller creep force, bounded by mu N
    assert abs(b.get("creep_force_x_left")) < abs(a.get("creep_force_x_left"))
    assert abs(b.get("creep_force_x_left")) <= 0.15 * b.get("normal_force_left") * 1.0001
    a.free()
    b.free()


def test_load_definition(fmu, extracted, md):
    """A wheel load is the total vertical force (normal and creep forces, as CONTACT's FZ)
    by default, the normal forces' share with load_definition = "normal"; on the 70 deg
    flange at 7 mm the two differ by a factor ~4. Near Nadal's limit (N ~ 15 Q) the
    vertical force is a small difference of large ones: eps_tau = 1e-5 makes the creep
    forces' noise small enough for the load tolerance 1e-3 (with the default 1e-2 the load
    loop accepts up to 1 %, :data:`~railcontact.contact.loadloop.LOAD_SLACK_CAP`).
    At the rigid point (patch_frame = "rigid"), whose angle is the flange's 70 deg (the
    frame at the reference point takes the overlap's weighted angle, which moves with N)."""
    q = 83.3e3
    inputs = dict(CREEP, lateral_displacement=7e-3, eta_left=5e-3, load_left=q, load_right=q)
    total = Slave(fmu, extracted, md, "total", warm_start="none", friction=0.3,
                  tangential_tolerance=1e-5, patch_frame="rigid")
    normal = Slave(fmu, extracted, md, "normal", warm_start="none", friction=0.3,
                   load_definition="normal", patch_frame="rigid")
    for s in (total, normal):
        assert s.step(**inputs) == 0
    assert total.get("force_vertical_left") == pytest.approx(q, rel=1e-3)
    assert total.get("force_vertical_right") == pytest.approx(q, rel=1e-3)
    n, g = normal.get("normal_force_left", "contact_angle_left")
    assert math.degrees(g) == pytest.approx(70.0, abs=0.5)
    assert n * math.cos(g) == pytest.approx(q, rel=1e-9)
    assert total.get("normal_force_left") > 2 * n
    total.free()
    normal.free()


def test_state_round_trip_is_bit_identical(fmu, extracted, md):
    s = Slave(fmu, extracted, md, "state", warm_start="previous")
    outs = ["normal_force_left", "creep_force_x_left", "creep_force_y_right",
            "normal_iterations", "tangential_iterations", "rigid_normal_iterations"]
    ys = [1e-3, 1.05e-3, 1.1e-3, 1.15e-3, 1.2e-3]
    for y in ys[:2]:
        s.step(lateral_displacement=y, **CREEP)
    state = s.s.getFMUstate()
    serial = s.s.serializeFMUstate(state)
    t0 = s.t
    first = []
    for y in ys[2:]:
        s.step(lateral_displacement=y, **CREEP)
        first.append(s.get(*outs))
    for restore in ("state", "serialized"):
        if restore == "state":
            s.s.setFMUstate(state)
        else:
            s.s.setFMUstate(s.s.deSerializeFMUstate(serial))
        s.t = t0
        again = []
        for y in ys[2:]:
            s.step(lateral_displacement=y, **CREEP)
            again.append(s.get(*outs))
        assert again == first  # bit-identical, iterations included
    # the warm start is part of the state: the repeated steps were warm (few iterations
    # in the contact step, the rigid wheelset's solves at other rolls apart)
    assert first[0][3] - first[0][5] <= 6
    s.s.freeFMUstate(state)
    s.free()


def _all_outputs(s: Slave, md) -> dict:
    return {v.name: s.get(v.name) for v in md.modelVariables if v.causality == "output"}


def test_discarded_step_statuses_agree_with_outputs(fmu, extracted, md, capsys):
    """After fmi2Discard every status agrees with the outputs: a NaN in a used input and an
    out-of-range pose (yaw 0.5) zero every output, each status 3 (not the previous step's
    forces beside status_left/right 0, nor zero forces with status 0 under fmi2Warning); a
    negative load and creepages beyond a case file's range are discarded, named; a time
    that is not finite and a step size not above 0 are fmi2Error, nothing done."""
    from fmpy.fmi1 import FMICallException

    s = Slave(fmu, extracted, md, "discard", warm_start="none", element_size=2e-3)
    assert s.step(lateral_displacement=2e-3, xi_left=1e-3, xi_right=1e-3) == 0
    good = _all_outputs(s, md)
    assert good["status"] == 0 and good["normal_force_left"] > 0
    zero_reals = [v.name for v in md.modelVariables
                  if v.causality == "output" and v.type == "Real"]
    for inputs, words in (({"load_left": float("nan")}, "load_left = nan"),
                          ({"load_left": 83.3e3, "yaw": 0.5}, "small angles"),
                          ({"yaw": 0.0, "load_left": -5.0}, "load_left = -5 N"),
                          ({"load_left": 83.3e3, "xi_right": 2e3}, "xi_right = 2000")):
        assert s.step(**inputs) == 2, inputs  # fmi2Discard
        out = _all_outputs(s, md)
        assert [out[n] for n in ("status", "status_left", "status_right")] == [3, 3, 3]
        assert all(out[n] == 0.0 for n in zero_reals), inputs
        assert words in capsys.readouterr().out
    assert s.step(xi_right=1e-3) == 0  # back in range: solved again (cold: the same)
    again = _all_outputs(s, md)
    assert {**again, "solve_time": 0.0} == {**good, "solve_time": 0.0}
    good = again
    for t, h in ((float("nan"), STEP), (s.t, 0.0), (s.t, -STEP), (s.t, float("inf"))):
        with pytest.raises(FMICallException) as err:
            s.s.doStep(t, h)
        assert err.value.status == 3  # fmi2Error, nothing done
        assert _all_outputs(s, md) == good
        assert "communicationStepSize" in capsys.readouterr().out
    s.free()
    # kinematic creepages: a speed that makes them beyond the range is discarded, named
    k = Slave(fmu, extracted, md, "kinematic_range", warm_start="none",
              creepage_input="kinematic", element_size=2e-3)
    assert k.step(lateral_displacement=2e-3, speed=30.0, lateral_velocity=0.01) == 0
    assert k.step(speed=1e-9) == 2
    assert k.get("status", "status_left", "status_right") == [3, 3, 3]
    assert k.get("normal_force_left") == 0.0 and "creepages" in capsys.readouterr().out
    assert k.step(speed=0.0) == 2 and "speed" in capsys.readouterr().out
    k.free()


def test_a_step_discarded_twice_as_it_was_asks_to_terminate(fmu, extracted, md, capsys):
    """A discarded step retried with the same time, step size and inputs is discarded
    again (the slave is deterministic): after the second, fmi2Terminated reads true, with a
    warning; a changed input goes on (solved), and a new discard starts the count again."""
    from fmpy.fmi2 import fmi2Terminated

    s = Slave(fmu, extracted, md, "terminate", warm_start="none", element_size=2e-3)
    assert s.step(lateral_displacement=2e-3) == 0
    assert s.s.getBooleanStatus(fmi2Terminated) is False  # (solved)
    assert s.step(load_left=-5.0) == 2
    assert s.s.getBooleanStatus(fmi2Terminated) is False  # a host may change an input
    assert s.step(load_left=-5.0) == 2  # set again to the same value: the same step
    assert s.s.getBooleanStatus(fmi2Terminated) is True
    assert "asks to terminate" in capsys.readouterr().out
    assert s.step(load_left=-6.0) == 2  # another input: another step
    assert s.s.getBooleanStatus(fmi2Terminated) is False
    assert s.step(load_left=83.3e3) == 0 and s.get("normal_force_left") > 0
    assert s.s.getBooleanStatus(fmi2Terminated) is False
    s.free()


def test_a_pose_beyond_the_profiles_is_said_once(fmu, extracted, md, capsys):
    """A lateral displacement beyond the profiles (2 m: given in mm) puts the wheelset out
    of range: its step is discarded with one message naming the wheel and the pose, not one
    a wheel each repeating the wheel's name."""
    s = Slave(fmu, extracted, md, "beside", warm_start="none", element_size=2e-3)
    assert s.step(lateral_displacement=2.0) == 2
    assert s.get("status", "status_left", "status_right") == [3, 3, 3]
    out = capsys.readouterr().out
    assert out.count("beside its rail") == 1, out
    assert "wheelset out of range: left wheel is beside its rail (lateral displacement 2 m" \
        in out and "wheel: left wheel" not in out
    s.free()


def test_simulate_fmu_ends_on_an_input_out_of_range(fmu):
    """fmpy's simulate_fmu retries a discarded step until the FMU asks to terminate: with
    a load out of range from the start it ends at the last good time (0) instead of
    retrying for ever (run in a process of its own, with a time limit)."""
    import sys

    code = ("import sys; from fmpy import simulate_fmu; "
            "r = simulate_fmu(sys.argv[1], stop_time=0.005, step_size=1e-3, "
            "start_values={'load_left': -83.3e3, 'element_size': 2e-3}, "
            "output=['status']); print('rows', len(r), 'last', r['time'][-1], "
            "'status', r['status'][-1])")
    run = subprocess.run([sys.executable, "-c", code, str(fmu)], capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "load_left = -83300 N" in run.stdout and "asks to terminate" in run.stdout
    assert "last 0.0 status 3" in run.stdout


def _stepped(fmu, extracted, md, name, **parameters) -> Slave:
    s = Slave(fmu, extracted, md, name, element_size=2e-3, **parameters)
    assert s.step(lateral_displacement=3e-3, xi_left=5e-3, xi_right=5e-3) == 0
    return s


def test_state_of_another_parameter_set_is_refused(fmu, extracted, md, capsys):
    """fmi2SetFMUstate with the state of an instance of other parameters (friction 0.1 in
    one of friction 0.6) is fmi2Error naming the parameter, the instance unchanged (not its
    buffers reading 0.1 while it computes with 0.6); the state of an instance of the same
    parameters is taken, and its next step equals that instance's bit for bit."""
    from fmpy.fmi1 import FMICallException

    outs = ["creep_force_x_left", "normal_force_left", "normal_iterations", "status"]
    a = _stepped(fmu, extracted, md, "a", friction=0.1)
    b = _stepped(fmu, extracted, md, "b", friction=0.6)
    c = _stepped(fmu, extracted, md, "c", friction=0.1)
    state_a, state_b = a.s.getFMUstate(), b.s.getFMUstate()
    with pytest.raises(FMICallException) as err:
        b.s.setFMUstate(state_a)
    assert err.value.status == 3
    log = capsys.readouterr().out
    assert "another parameter set" in log and "friction = 0.1 in the state, 0.6" in log
    assert b.get("friction") == 0.6
    b.step(lateral_displacement=3.2e-3)
    after_refusal = b.get(*outs)
    b.s.setFMUstate(state_b)
    b.t -= STEP
    b.step(lateral_displacement=3.2e-3)
    assert b.get(*outs) == after_refusal  # the refused state changed nothing
    fx, n = after_refusal[:2]
    assert abs(fx) / n > 0.3  # computes with its own friction 0.6 (0.5 of it here)
    # the same parameters in another instance: taken, the next step is a's
    c.s.setFMUstate(state_a)
    for s in (a, c):
        s.step(lateral_displacement=3.2e-3)
    assert c.get(*outs) == a.get(*outs)
    # an instance not initialised takes it: initialisation builds the solver from its
    # parameters (friction 0.1 read and used)
    d = FMU2Slave(guid=md.guid, unzipDirectory=str(extracted),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="d")
    d.instantiate()
    d.setFMUstate(state_a)
    d.setupExperiment(startTime=0.0)
    d.enterInitializationMode()
    d.exitInitializationMode()
    d.doStep(0.0, STEP)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    assert d.getReal([vr["friction"]]) == [0.1]
    fx, n = d.getReal([vr["creep_force_x_left"], vr["normal_force_left"]])
    assert 0.05 < abs(fx) / n <= 0.1 + 1e-9
    d.terminate()
    d.freeInstance()
    for s, st in ((a, state_a), (b, state_b)):
        s.s.freeFMUstate(st)
    for s in (a, b, c):
        s.free()


def test_serialized_state_runs_no_code(fmu, extracted, md, tmp_path, capsys):
    """fmi2DeSerializeFMUstate reads numbers and arrays only: a pickle that would run code
    is refused (fmi2Error) without running it, as are damaged bytes and a state of a later
    format version; the serialized bytes are the documented format
    (railcontact.fmu.state), and a good one is still taken."""
    import os
    import pickle
    import struct

    from fmpy.fmi1 import FMICallException

    from railcontact.fmu import state as S

    flag = tmp_path / "pickle_flag"

    class Exploit:
        def __reduce__(self):
            return (os.system, (f"echo EXECUTED > {flag}",))

    s = _stepped(fmu, extracted, md, "serial")
    kept = s.s.getFMUstate()
    good = s.s.serializeFMUstate(kept)
    s.s.freeFMUstate(kept)
    saved = S.unpack(good)
    assert saved.guid == md.guid and saved.model == md.coSimulation.modelIdentifier
    assert saved.initialised and saved.parameters["element_size"] == 2e-3
    assert saved.memory.left and saved.real.dtype == np.float64
    later = good[:16] + struct.pack("<I", S.VERSION + 1) + good[20:]
    for bad, words in ((pickle.dumps(Exploit()), "not a railcontact FMU state"),
                       (b"", "not a railcontact FMU state"),
                       (good[:200], "cut short"), (good[:-20], "its arrays"),
                       (later, "format version")):
        with pytest.raises(FMICallException) as err:
            s.s.deSerializeFMUstate(bad)
        assert err.value.status == 3 and "DeSerializeFMUstate" in str(err.value)
        log = capsys.readouterr().out
        assert "deSerializeFMUstate refused" in log and words in log
    assert not flag.exists()
    s.step(lateral_displacement=3.1e-3)
    first = s.get("creep_force_x_left", "normal_iterations")
    s.s.setFMUstate(s.s.deSerializeFMUstate(good))
    s.t -= STEP
    s.step(lateral_displacement=3.1e-3)
    assert s.get("creep_force_x_left", "normal_iterations") == first
    s.free()


def test_a_restored_state_brings_back_its_last_successful_time(fmu, extracted, md):
    """fmi2GetRealStatus(fmi2LastSuccessfulTime) after fmi2SetFMUstate is the restored
    state's time, not the time the instance had reached (the time travels with the state,
    serialized too, and a discarded step after a restore leaves it there)."""
    from fmpy.fmi2 import fmi2LastSuccessfulTime

    s = _stepped(fmu, extracted, md, "time")  # t = STEP
    kept = s.s.getFMUstate()
    data = s.s.serializeFMUstate(kept)
    for _ in range(3):
        assert s.step(lateral_displacement=3.1e-3) == 0
    assert s.s.getRealStatus(fmi2LastSuccessfulTime) == 4 * STEP
    s.s.setFMUstate(kept)
    assert s.s.getRealStatus(fmi2LastSuccessfulTime) == STEP
    s.t = STEP
    assert s.step(lateral_displacement=math.nan) == 2  # fmi2Discard: time stays
    assert s.s.getRealStatus(fmi2LastSuccessfulTime) == STEP
    assert s.step(lateral_displacement=3.1e-3) == 0
    assert s.s.getRealStatus(fmi2LastSuccessfulTime) == 2 * STEP
    s.s.setFMUstate(s.s.deSerializeFMUstate(data))
    assert s.s.getRealStatus(fmi2LastSuccessfulTime) == STEP
    s.s.freeFMUstate(kept)
    s.free()


def test_deserialize_refuses_what_is_no_state_of_this_fmu(fmu, extracted, md, capsys):
    """fmi2DeSerializeFMUstate itself is fmi2Error, the reason logged, for bytes that are
    no state of this FMU: another header, a damaged JSON header, an archive that would
    need pickle, another FMU's GUID or model identifier; a state handed in for reuse is
    left as it was. A good state round-trips bit for bit, and one of another parameter set
    is still deserialized and refused only by fmi2SetFMUstate."""
    import io
    from dataclasses import replace

    from fmpy.fmi1 import FMICallException

    from railcontact.fmu import state as S

    s = _stepped(fmu, extracted, md, "deser", friction=0.3)
    kept = s.s.getFMUstate()
    good = s.s.serializeFMUstate(kept)
    saved = S.unpack(good)
    start = S._PREFIX.size
    length = S._PREFIX.unpack_from(good)[2]
    header, archive = good[start:start + length], good[start + length:]
    assert header.startswith(b"{") and archive.startswith(b"PK")
    pickled = io.BytesIO()
    np.savez(pickled, real=np.array([object()] * len(saved.real)), integer=saved.integer,
             control=saved.control)
    bad = {
        "another header": (b"OTHERFMUSTATE123" + good[16:], "does not start with"),
        "damaged JSON": (good[:start] + b"[" + header[1:] + archive, "its header"),
        "pickled archive": (good[:start + length] + pickled.getvalue(), "its arrays"),
        "another GUID": (S.pack(replace(saved, guid="{00000000-0000-0000-0000-0000000000"
                                                     "00}")), "a state of another FMU"),
        "another model": (S.pack(replace(saved, model="OtherModel")),
                          "a state of another FMU"),
        "other variables": (S.pack(replace(saved, real=saved.real[:-1])),
                            "its variables are not this FMU's"),
    }
    capsys.readouterr()
    for name, (data, words) in bad.items():
        with pytest.raises(FMICallException) as err:
            s.s.deSerializeFMUstate(data)
        assert err.value.status == 3, name
        log = capsys.readouterr().out
        assert "deSerializeFMUstate refused" in log and words in log, (name, log)
        # a state given for reuse keeps its bytes
        with pytest.raises(FMICallException):
            s.s.deSerializeFMUstate(data, kept)
        assert s.s.serializeFMUstate(kept) == good, name
    # a good state: deserialized, serialized again bit for bit, and set
    restored = s.s.deSerializeFMUstate(good)
    assert s.s.serializeFMUstate(restored) == good
    s.step(lateral_displacement=3.1e-3)
    first = s.get("creep_force_x_left", "normal_iterations")
    s.s.setFMUstate(restored)
    s.t -= STEP
    s.step(lateral_displacement=3.1e-3)
    assert s.get("creep_force_x_left", "normal_iterations") == first
    # a state of this FMU with other parameters: deserialized, refused when set
    other = _stepped(fmu, extracted, md, "deser_other", friction=0.5)
    other_state = other.s.getFMUstate()
    foreign = s.s.deSerializeFMUstate(other.s.serializeFMUstate(other_state))
    with pytest.raises(FMICallException) as err:
        s.s.setFMUstate(foreign)
    assert err.value.status == 3 and "another parameter set" in capsys.readouterr().out
    for inst, st in ((s, kept), (s, restored), (s, foreign), (other, other_state)):
        inst.s.freeFMUstate(st)
    s.free()
    other.free()


def test_profile_file_in_resources(fmu, extracted, md):
    """wheel_profile names a file packed into the FMU (built with --profile): the tabulated
    S1002 gives the built-in S1002's contact (to the table's resolution)."""
    outs = ("normal_force_left", "contact_angle_left", "rolling_radius_left",
            "max_pressure_left")
    built_in = Slave(fmu, extracted, md, "builtin", warm_start="none")
    built_in.step(lateral_displacement=2e-3)
    filed = Slave(fmu, extracted, md, "file", warm_start="none", wheel_profile="S1002.txt",
                  profile_unit="mm")
    filed.step(lateral_displacement=2e-3)
    a, b = built_in.get(*outs), filed.get(*outs)
    np.testing.assert_allclose(b, a, rtol=2e-3)
    built_in.free()
    filed.free()


def test_reset(fmu, extracted, md):
    s = Slave(fmu, extracted, md, "reset", warm_start="none")
    s.step(lateral_displacement=2e-3, **CREEP)
    fresh = s.get("creep_force_x_left", "normal_force_left")
    s.step(lateral_displacement=-3e-3, **CREEP)
    s.reset(warm_start="none")
    s.step(lateral_displacement=2e-3, **CREEP)
    assert s.get("creep_force_x_left", "normal_force_left") == fresh
    s.free()


def test_bad_input_is_a_clean_status(fmu, extracted, md):
    s = Slave(fmu, extracted, md, "bad", warm_start="none")
    # NaN input: the step is discarded, outputs zero, every status "out of range"
    assert s.step(lateral_displacement=float("nan"), **CREEP) == 2
    assert s.get("status", "status_left", "status_right") == [3, 3, 3]
    # lift-off: zero forces, status "no contact"
    s.step(lateral_displacement=0.0, load_left=0.0, load_right=0.0, **CREEP)
    assert s.get("status") == 2
    assert s.get("normal_force_left", "force_vertical") == [0.0, 0.0]
    # beyond the profiles: discarded (not an error), zero forces, status "out of range"
    assert s.step(lateral_displacement=0.08, load_left=83.3e3, load_right=83.3e3) == 2
    assert s.get("status", "status_left", "status_right") == [3, 3, 3]
    assert s.get("normal_force_left") == 0.0
    # back in range
    assert s.step(lateral_displacement=0.0) == 0
    assert s.get("status") == 0 and s.get("normal_force_left") > 0
    s.free()


def test_inputs_the_modes_do_not_use_may_be_nan(fmu, extracted, md):
    """A NaN in an input the modes do not read (speed and velocities with direct
    creepages; creepages under kinematic input) changes nothing; a NaN in a used input is
    fmi2Discard with every output zero and every status out of range."""
    nan = float("nan")
    direct = Slave(fmu, extracted, md, "direct", warm_start="none")
    assert direct.step(lateral_displacement=1e-3, **CREEP) == 0
    before = direct.get("normal_force_left")
    assert direct.step(speed=nan, lateral_velocity=nan, yaw_rate=nan, spin_speed=nan) == 0
    assert direct.get("status") == 0 and direct.get("normal_force_left") == before
    assert direct.get("status_left") == direct.get("status_right") == 0
    assert direct.step(load_left=0.0) == 0  # the left wheel lifts off, the right one rolls
    assert direct.get("status_left", "status_right", "status") == [2, 0, 2]
    assert direct.step(load_left=83.3e3) == 0
    assert direct.step(xi_left=nan) == 2  # used: discarded, nothing solved
    assert direct.get("normal_force_left", "normal_force_right") == [0.0, 0.0]
    assert direct.get("status", "status_left", "status_right") == [3, 3, 3]
    direct.free()
    kinematic = Slave(fmu, extracted, md, "kinematic", warm_start="none",
                      creepage_input="kinematic")
    assert kinematic.step(lateral_displacement=1e-3, xi_left=nan, eta_right=nan,
                          phi_left=nan, speed=30.0) == 0
    assert kinematic.get("status") == 0 and kinematic.get("normal_force_left") > 0
    kinematic.free()


def test_bad_parameter_is_an_error_at_initialization(fmu, extracted, md, capsys):
    from fmpy.fmi1 import FMICallException

    for name, value, words in (("friction", -0.2, "friction"),
                               ("element_size", 0.05, "element_size"),
                               ("warm_start", "yesterday", "warm_start"),
                               ("rail_profile", "nonexistent.txt", "rail_profile")):
        s = FMU2Slave(guid=md.guid, unzipDirectory=str(extracted),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="badpar")
        s.instantiate()  # fmpy's logger prints "[ERROR] message"
        vr = {v.name: v.valueReference for v in md.modelVariables}
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        if isinstance(value, str):
            s.setString([vr[name]], [value])
        else:
            s.setReal([vr[name]], [value])
        with pytest.raises(FMICallException) as err:
            s.exitInitializationMode()
        assert err.value.status == 3  # fmi2Error, not fmi2Fatal
        s.freeInstance()
        log = capsys.readouterr().out
        assert "[ERROR]" in log and words in log, log


def _refused(capsys, call, *args) -> str:
    """What the FMU logged for ``call(*args)``, which must be fmi2Error."""
    from fmpy.fmi1 import FMICallException

    capsys.readouterr()
    with pytest.raises(FMICallException) as err:
        call(*args)
    assert err.value.status == 3
    return capsys.readouterr().out


def test_values_refused_are_named_with_the_reason(fmu, extracted, md, capsys):
    """A value the FMU does not set is fmi2Error with a message naming the variable and
    why: an output, a parameter after initialisation, an input after fmi2Terminate, a
    NULL string, a value reference of no variable (and no Boolean variables at all)."""
    import ctypes

    from fmpy.fmi2 import fmi2String, fmi2ValueReference

    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=str(extracted),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="refused")
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    refused = partial(_refused, capsys)

    out = refused(s.setReal, [vr["normal_force_left"]], [1.0])
    assert (f"Real variable normal_force_left (value reference {vr['normal_force_left']}) "
            "is an output: only inputs and parameters can be set") in out, out
    assert f"Integer variable status (value reference {vr['status']}) is an output" in \
        refused(s.setInteger, [vr["status"]], [1])
    assert "no Real variable with value reference 99999" in refused(s.setReal, [99999],
                                                                      [1.0])
    # a NULL string (fmpy encodes str: the C call itself)
    null = refused(s.fmi2SetString, s.component, (fmi2ValueReference * 1)(vr["warm_start"]),
                   1, (fmi2String * 1)(ctypes.c_char_p(None)))
    assert (f"String variable warm_start (value reference {vr['warm_start']}): the value "
            "given is NULL, not a string") in null, null
    assert "this FMU has no Boolean variables" in refused(s.setBoolean, [0], [True])
    s.exitInitializationMode()
    for setter, name, value in ((s.setReal, "friction", 0.3),
                                (s.setInteger, "warm_start_choice", 1),
                                (s.setString, "warm_start", "none")):
        out = refused(setter, [vr[name]], [value])
        assert (f"variable {name} (value reference {vr[name]}) is a parameter: it can be "
                "set only before fmi2ExitInitializationMode") in out, out
    assert "no String variable with value reference 99999" in refused(s.getString, [99999])
    s.setReal([vr["lateral_displacement"]], [1e-3])  # an input: settable while stepping
    s.terminate()
    out = refused(s.setReal, [vr["lateral_displacement"]], [2e-3])
    assert ("Real variable lateral_displacement (value reference "
            f"{vr['lateral_displacement']}) cannot be set after fmi2Terminate") in out, out
    s.freeInstance()


def test_calls_out_of_their_mode_say_why(fmu, extracted, md, capsys):
    """An FMI call the instance's mode does not allow is fmi2Error with a message naming
    the call, when it can be made and the mode the instance is in; a start time that is
    not finite is refused."""
    s = FMU2Slave(guid=md.guid, unzipDirectory=str(extracted),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="modes")
    s.instantiate()
    refused = partial(_refused, capsys)

    assert ("fmi2DoStep can be called only in step mode (after fmi2ExitInitializationMode); "
            "the instance is instantiated") in refused(s.doStep, 0.0, 1e-3)
    assert "startTime = nan s is not a finite number" in refused(
        lambda: s.setupExperiment(startTime=float("nan")))
    assert ("fmi2ExitInitializationMode can be called only in initialization mode; the "
            "instance is instantiated") in refused(s.exitInitializationMode)
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    assert ("fmi2EnterInitializationMode can be called only once after instantiation (or "
            "fmi2Reset); the instance is in initialization mode") in refused(
                s.enterInitializationMode)
    s.exitInitializationMode()
    assert ("fmi2SetupExperiment can be called only before fmi2EnterInitializationMode; "
            "the instance is in step mode") in refused(lambda: s.setupExperiment(startTime=0.0))
    s.terminate()
    assert "the instance is terminated (fmi2Reset starts it again)" in refused(
        s.doStep, 0.0, 1e-3)
    s.reset()  # (then it starts again)
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 1e-3)
    s.terminate()
    s.freeInstance()


def test_bare_c_host_clean_environment(extracted, md, tmp_path):
    """100 steps, three load/unload cycles, in a C program with an empty environment."""
    headers = Path(fmpy.__file__).parent / "c-code"
    host = tmp_path / "host"
    subprocess.run(["gcc", "-O2", f"-I{headers}", str(Path(__file__).parent / "fmu" / "host.c"),
                    "-o", str(host), "-ldl", "-lm"], check=True)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    binary = extracted / "binaries" / "linux64" / "RailContact.so"
    env = ["env", "-i", "PATH=/usr/bin:/bin", f"VR_LAT={vr['lateral_displacement']}",
           f"VR_OUT={vr['normal_force_left']}"]
    r = subprocess.run(env + [str(host), str(binary), (extracted / "resources").as_uri(),
                              md.guid, "100", "3"], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "ok: 3 cycles of 100 steps" in r.stdout


def test_threads_instantiating_at_once(extracted, md, tmp_path):
    """Four host threads instantiate the FMU at the same moment in a C host, the first
    instantiation of the process (it starts Python): one starts it, the others wait, and
    all four step their instances. (Without the start-up lock two threads could both start
    the interpreter.)"""
    headers = Path(fmpy.__file__).parent / "c-code"
    host = tmp_path / "threads"
    subprocess.run(["gcc", "-O2", f"-I{headers}",
                    str(Path(__file__).parent / "fmu" / "threads.c"), "-o", str(host),
                    "-ldl", "-pthread"], check=True)
    binary = extracted / "binaries" / "linux64" / "RailContact.so"
    for _ in range(3):  # a race: more than one chance to lose it
        r = subprocess.run(["env", "-i", "PATH=/usr/bin:/bin", str(host), str(binary),
                            (extracted / "resources").as_uri(), md.guid, "4", "3"],
                           capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr[-3000:]
        assert "ok: 4 threads" in r.stdout


def test_missing_isolation_symbols_are_a_warning(extracted):
    """A Python whose C API lacks what the shim isolates it with (Py_SetProgramName and the
    flags, to be removed in 3.15) starts with a warning naming them, not silently: the
    shim passes the missing names, the FMU's bootstrap turns them into the warning that the
    logger gets."""
    import runpy

    boot = runpy.run_path(str(extracted / "resources" / "python" / "fmu_bootstrap.py"))
    resources = str(extracted / "resources")
    _, _, warning = boot["start"](resources, "mode=started\nsource=test\n")
    assert "isolated" not in warning
    _, _, warning = boot["start"](
        resources, "mode=started\nsource=test\n"
        "isolation_missing=Py_SetProgramName, Py_NoUserSiteDirectory\n")
    assert "has no Py_SetProgramName, Py_NoUserSiteDirectory" in warning
    assert "not start it fully isolated" in warning


def test_libcosim(fmu):
    pytest.importorskip("libcosimpy")
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    ex = CosimExecution.from_step_size(step_size=int(1e6))  # 1 ms in ns
    i = ex.add_local_slave(local_slave=CosimLocalSlave(fmu_path=str(fmu), instance_name="rc"))
    obs = CosimObserver.create_last_value()
    ex.add_observer(observer=obs)
    vr = {v.name.decode(): v.reference for v in ex.slave_variables(slave_index=i)}
    ex.real_initial_value(slave_index=i, variable_reference=vr["lateral_displacement"],
                          value=2e-3)
    ex.real_initial_value(slave_index=i, variable_reference=vr["xi_left"], value=1e-3)
    ex.string_initial_value(slave_index=i, variable_reference=vr["warm_start"], value="none")
    assert ex.step(step_count=3)
    got = obs.last_real_values(slave_index=i, variable_references=[
        vr["normal_force_left"], vr["creep_force_x_left"], vr["force_lateral"]])
    r = api("none").solve(Pose(2e-3), loads=(83.3e3, 83.3e3),
                          creepages=((1e-3, 0, 0), (0, 0, 0)))
    np.testing.assert_allclose(got, [r.left.normal_force, r.left.creep_force[0], r.force[1]],
                               rtol=1e-9)


@pytest.fixture(scope="module")
def fuzz_slave(fmu, extracted, md):
    s = Slave(fmu, extracted, md, "fuzz", warm_start="previous+estimate")
    yield s
    s.free()


def _value(lo, hi):
    from hypothesis import strategies as st

    return st.one_of(st.floats(lo, hi), st.sampled_from([float("nan"), float("inf"),
                                                         -float("inf"), 0.0]))


def test_fuzz_step_inputs(fuzz_slave, md):
    """Whatever the step inputs: a clean FMI status, a valid status output, finite
    outputs."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    reals = [v.name for v in md.modelVariables if v.causality == "output" and v.type == "Real"]

    @settings(max_examples=25, deadline=None,
              suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(st.fixed_dictionaries({
        "lateral_displacement": _value(-0.03, 0.03), "yaw": _value(-0.15, 0.15),
        "load_left": _value(-5e4, 3e5), "load_right": _value(-5e4, 3e5),
        "xi_left": _value(-0.05, 0.05), "eta_right": _value(-0.05, 0.05),
        "phi_left": _value(-5.0, 5.0)}))
    def run(inputs):
        status = fuzz_slave.step(**inputs)
        assert status in (0, 2)  # OK/Warning, or Discard - never Error/Fatal
        assert fuzz_slave.get("status") in (0, 1, 2, 3, 4)
        out = [fuzz_slave.get(n) for n in reals]
        assert np.all(np.isfinite(out))

    run()


# -- enumerations, honest status, the validity outputs --------------------------------------

def _api_from(values: dict):
    """The settings and a WheelsetContact from FMU parameter values, as the slave builds
    them."""
    from railcontact.fmu.variables import parameter_settings

    ps = parameter_settings(values)
    g = ps.geometry
    track = Track(read_profile(g.rail, "rail", g.profile_unit), g.inclination, g.gauge,
                  g.gauge_depth)
    ws = Wheelset(read_profile(g.wheel, "wheel", g.profile_unit), g.wheel_radius,
                  g.back_to_back, g.flange_back)
    return ps, WheelsetContact(track, ws, ps.material.elastic_pair(), ps.contact,
                               convention=ps.modes.convention)


def _slave_named(name: str):
    """The Python slave of the fmpy instance ``name`` (fmpy is a Python host: the FMU's
    slave lives in this interpreter)."""
    import gc

    found = [o for o in gc.get_objects()
             if type(o).__name__ == "Slave" and getattr(o, "instance_name", None) == name]
    assert len(found) == 1, name
    return found[0]


def test_every_mode_switch_is_an_enumeration(md):
    """Each String choice parameter has an Integer enumeration ``<name>_choice``: type
    Enumeration, items 1.. the words (as identifiers, the word as description), start the
    String's default."""
    from railcontact.fmu.variables import CHOICES, PARAMETERS

    names = {v.name: v for v in md.modelVariables}
    types = {t.name: t for t in md.typeDefinitions}
    strings = [v for v in PARAMETERS if v.type == "String" and "(" in v.description
               and " | " in v.description]
    assert {v.name + "_choice" for v in strings} == {v.name for v in CHOICES}
    assert {"control_choice", "creepage_input_choice", "load_definition_choice",
            "warm_start_choice", "normal_estimate_choice", "tangential_estimate_choice",
            "fft_choice", "tangential_solver_choice"} <= set(names)
    for c in CHOICES:
        v = names[c.name]
        assert v.type == "Enumeration" and v.causality == "parameter"
        t = types[v.declaredType.name]
        assert [i.description for i in t.items] == list(c.items)
        assert [int(i.value) for i in t.items] == list(range(1, len(c.items) + 1))
        assert all(i.name.isidentifier() for i in t.items)
        word = c.items[int(v.start) - 1]
        assert word == names[c.name.removesuffix("_choice")].start


def _instantiate(md, extracted, name, integers, strings=None, reals=None):
    """OMSimulator's order: instantiate, set the start values, then set up, enter and exit
    initialisation. Returns the FMU2Slave, or the FMI status if initialisation failed."""
    from fmpy.fmi1 import FMICallException

    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=str(extracted),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    s.instantiate()
    for k, value in integers.items():  # before fmi2EnterInitializationMode
        s.setInteger([vr[k]], [value])
    for k, value in (strings or {}).items():
        s.setString([vr[k]], [value])
    for k, value in (reals or {}).items():
        s.setReal([vr[k]], [value])
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    try:
        s.exitInitializationMode()
    except FMICallException as exc:
        s.freeInstance()
        return exc.status
    return s


def _one_step(md, s, words: dict) -> dict:
    """One step at 2 mm with the inputs every mode needs; the outputs by name."""
    vr = {v.name: v.valueReference for v in md.modelVariables}
    inputs = dict(CREEP, lateral_displacement=2e-3, vertical_displacement=-2.2e-4,
                  speed=30.0, lateral_velocity=0.01)
    for k, x in inputs.items():
        s.setReal([vr[k]], [x])
    s.doStep(0.0, STEP)
    outs = ("normal_force_left", "creep_force_x_left", "creep_force_y_right",
            "force_vertical_left")
    got = dict(zip(outs, s.getReal([vr[n] for n in outs]), strict=True))
    ints = ("normal_iterations", "tangential_iterations", "status")
    got.update(zip(ints, s.getInteger([vr[n] for n in ints]), strict=True))
    return got


def _api_step(words: dict) -> dict:
    """The API's answer to :func:`_one_step`, after the step at the start values that the
    FMU solves in fmi2ExitInitializationMode (the warm start of the next)."""
    from railcontact.timestep import Kinematics

    ps, wc = _api_from(words)

    def solve(lateral, vertical, lateral_velocity, creep):
        kw: dict = {"time": 0.0}
        if ps.modes.control == "penetration":
            kw["vertical"] = vertical
        else:
            kw["loads"] = (83.3e3, 83.3e3)
        if ps.modes.creepage_input == "kinematic":
            kw["kinematics"] = Kinematics(30.0, lateral_velocity)
        else:
            kw["creepages"] = tuple(tuple(creep[f"{c}_{s}"] for c in ("xi", "eta", "phi"))
                                    for s in ("left", "right"))
        return wc.solve(Pose(lateral), **kw)

    solve(0.0, 0.0, 0.0, dict.fromkeys(CREEP, 0.0))
    r = solve(2e-3, -2.2e-4, 0.01, CREEP)

    def work(name):  # the contact step's and the rigid wheelset's solves, both wheels
        return sum(getattr(w, name) + getattr(x, name)
                   for w, x in zip(r.wheels, r.rigid_work, strict=True))

    return {"normal_force_left": r.left.normal_force,
            "creep_force_x_left": r.left.creep_force[0],
            "creep_force_y_right": r.right.creep_force[1],
            "force_vertical_left": r.left.track_force[2],
            "normal_iterations": work("normal_iterations"),
            "tangential_iterations": work("tangential_iterations"),
            "status": r.status}


def test_enumerations_set_before_initialization_take_effect(md, extracted):
    """OMSimulator sets start values right after fmi2Instantiate, and drops the
    String ones. Each item of each enumeration, set so: the step equals the Python API's
    with that word as the setting (forces to 1e-9, iterations exactly), and the three
    FMU modes change the answer from the default's. (1 mm elements, for time; the dense
    convolution is left out, as slow; profile_unit: next test; contact_model = table needs
    a table: tests/test_table.py sets it through this enumeration.)"""
    from railcontact.fmu.variables import CHOICES, PARAMETER_SOURCES
    from railcontact.settings import ContactSettings

    coarse = {"element_size": 1e-3}
    default = _api_step(coarse)
    sources = {name: (record, key) for name, record, key in PARAMETER_SOURCES}
    for c in CHOICES:
        base = c.name.removesuffix("_choice")
        for k, word in enumerate(c.items, start=1):
            if k == c.start or base == "profile_unit" or word in ("dense", "table"):
                continue
            s = _instantiate(md, extracted, f"{base}-{k}", {c.name: k}, reals=coarse)
            assert not isinstance(s, int), (c.name, word)
            # the String parameter reads back the word in force (was: its default)
            assert _string(md, s, base) == word, (c.name, word)
            assert s.getInteger([_vr(md, c.name)])[0] == k
            # the slave's own settings took the word (pyfftw and scipy answer alike)
            slave = _slave_named(f"{base}-{k}")
            record, key = sources[base]
            where = slave.contact.settings if record is ContactSettings else slave.modes
            assert getattr(where, key) == word, (c.name, word)
            if base == "convention":
                assert slave.contact.convention == word
            got = _one_step(md, s, {base: word})
            s.terminate()
            s.freeInstance()
            want = _api_step({base: word, **coarse})
            for n, x in want.items():
                assert got[n] == pytest.approx(x, rel=1e-9, abs=1e-9), (c.name, word, n)
            if base in ("control", "load_definition", "creepage_input"):
                assert want["normal_force_left"] != pytest.approx(
                    default["normal_force_left"], rel=1e-6), (c.name, word)


def test_enumeration_errors_name_the_parameters(md, extracted, capsys):
    """A tabulated S1002 in mm read as metres is an error at initialisation (the
    profile_unit enumeration took effect); a String and an enumeration set to different
    words disagree; an item out of range is named."""
    status = _instantiate(md, extracted, "unit", {"profile_unit_choice": 1},
                          {"wheel_profile": "S1002.txt"})
    assert status == 3 and "unit" in capsys.readouterr().out
    status = _instantiate(md, extracted, "both", {"warm_start_choice": 1},
                          {"warm_start": "estimate"})
    log = capsys.readouterr().out
    assert status == 3 and "warm_start = 'estimate' and warm_start_choice = 1" in log
    status = _instantiate(md, extracted, "range", {"control_choice": 3})
    assert status == 3 and "control_choice must be one of 1 (load), 2 (penetration)" in \
        capsys.readouterr().out
    # the same word twice is fine
    s = _instantiate(md, extracted, "same", {"warm_start_choice": 1}, {"warm_start": "none"})
    assert not isinstance(s, int)
    s.freeInstance()
    # the String alone: its enumeration reads back the word's number (was: its default)
    s = _instantiate(md, extracted, "string", {}, {"warm_start": "none"})
    assert s.getInteger([_vr(md, "warm_start_choice")])[0] == 1
    assert _string(md, s, "warm_start") == "none"
    s.freeInstance()


def _vr(md, name: str) -> int:
    return next(v.valueReference for v in md.modelVariables if v.name == name)


def _string(md, s, name: str) -> str:
    """The String variable ``name`` of the FMU2Slave ``s`` (fmpy gives bytes or str)."""
    value = s.getString([_vr(md, name)])[0]
    return value.decode() if isinstance(value, bytes) else value


def test_outside_validity_through_the_fmu(fmu, extracted, md, capsys):
    """A flange climb at 10 mm: status_left 4 (outside validity), validity bits
    Y/Q, Nadal and flange climb, Y/Q as the API's, a warning naming Y/Q and its value;
    the limits are parameters (max_y_q = 5 drops that bit). Back on the tread: ok."""
    s = Slave(fmu, extracted, md, "validity", warm_start="none")
    s.step(lateral_displacement=10e-3)
    r = api("none").solve(Pose(10e-3), loads=(83.3e3, 83.3e3),
                          creepages=((1e-3, -5e-4, 0.3), (1e-3, -5e-4, -0.3)))
    s.step(lateral_displacement=10e-3, **CREEP)
    assert s.get("status_left", "status_right", "status") == [4, 0, 4]
    assert s.get("validity_left", "validity_right") == [1 | 2 | 4, 0]
    yq = s.get("derailment_quotient_left")
    assert yq == pytest.approx(r.left.derailment_quotient, rel=1e-9) and yq > 1.12
    log = capsys.readouterr().out
    assert "[WARNING]" in log and f"Y/Q = {yq:.3g}" in log and "flange climb" in log
    assert s.step(lateral_displacement=0.0) == 0 and s.get("status") == 0
    s.free()
    loose = Slave(fmu, extracted, md, "loose", warm_start="none", max_y_q=5.0)
    loose.step(lateral_displacement=10e-3, **CREEP)
    assert loose.get("validity_left") == 2 | 4
    loose.free()


def test_status_round_trip_python_fmu_model_description(fmu, extracted, md):
    """The status enum's round trip, Python -> the built FMU's outputs -> its
    modelDescription. The modelDescription.xml in the FMU's zip declares status,
    status_left and status_right Integer outputs whose descriptions give every
    :class:`~railcontact.status.Status` (not computed, a table's, apart) with its number,
    label and meaning; stepped, the three outputs are the statuses the API (WheelsetContact
    with the FMU's defaults) gives for the same inputs: ok at 3 mm, outside validity on the
    left wheel only at 10 mm (a flange climb: the sides not swapped), and out of range
    beside the rail (2 m: the step discarded)."""
    names = ("status", "status_left", "status_right")
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    declared = {v.get("name"): v for v in root.iter("ScalarVariable")
                if v.get("name") in names}
    assert set(declared) == set(names)
    for name, v in declared.items():
        assert v.get("causality") == "output", name
        assert v[0].tag == "Integer", name
        for s in Status:
            if s is not Status.NOT_COMPUTED:
                assert f"{int(s)} {s.label} ({s.description}" in v.get("description"), \
                    (name, s)
    s = Slave(fmu, extracted, md, "status-round-trip", warm_start="none")
    ref = api("none")
    creep = ((1e-3, -5e-4, 0.3), (1e-3, -5e-4, -0.3))
    ok, out = Status.OK, Status.OUT_OF_RANGE
    try:
        for y, fmi, want in ((3e-3, 0, (ok, ok, ok)),
                             (10e-3, 0, (Status.OUTSIDE_VALIDITY,) * 2 + (ok,)),
                             (2.0, 2, (out, out, out))):
            r = ref.solve(Pose(y), loads=(83.3e3, 83.3e3), creepages=creep)
            assert (r.status, r.left.status, r.right.status) == want, y
            assert s.step(lateral_displacement=y, **CREEP) == fmi, y  # 2: fmi2Discard
            got = s.get(*names)
            assert got == [int(r.status), int(r.left.status), int(r.right.status)], y
            assert [Status(g) for g in got] == list(want), y
    finally:
        s.free()


def test_new_outputs_match_the_api(fmu, extracted, md):
    """Vertical displacement and roll of the rigid wheelset under load control, the
    moments about its centre, Y/Q and penetration: the API's, at 3 mm with creepages;
    under penetration control the vertical displacement and roll are the inputs."""
    s = Slave(fmu, extracted, md, "outputs", warm_start="none")
    s.step(lateral_displacement=3e-3, **CREEP)
    r = api("none").solve(Pose(3e-3), loads=(83.3e3, 83.3e3),
                          creepages=((1e-3, -5e-4, 0.3), (1e-3, -5e-4, -0.3)))
    names = ["wheelset_vertical_displacement", "wheelset_roll", "roll_moment",
             "pitch_moment", "yaw_moment", "derailment_quotient_right", "penetration_left"]
    want = [r.vertical, r.roll, *r.moment, r.right.derailment_quotient, r.left.penetration]
    np.testing.assert_allclose(s.get(*names), want, rtol=1e-9, atol=1e-12)
    assert r.roll > 0
    s.free()
    p = Slave(fmu, extracted, md, "pen", warm_start="none", control="penetration")
    p.step(lateral_displacement=3e-3, vertical_displacement=-1.9e-4, roll=1.7e-4, **CREEP)
    assert p.get("wheelset_vertical_displacement", "wheelset_roll") == [-1.9e-4, 1.7e-4]
    assert p.get("status") == 0 and p.get("normal_force_left") > 0
    p.free()


def test_enumerations_through_fmpy_start_values(fmu):
    """fmpy's start_values: the enumerations give what the Strings give (penetration
    control with kinematic creepages), not the default's."""
    outs = ["normal_force_left", "xi_used_left", "eta_used_left", "status"]
    inputs = {"vertical_displacement": -2e-4, "lateral_velocity": 0.01,
              "warm_start_choice": 1}
    runs = [simulate_fmu(str(fmu), stop_time=2 * STEP, step_size=STEP, output=outs,
                         start_values={**inputs, **modes})[-1]
            for modes in ({"control_choice": 2, "creepage_input_choice": 2},
                          {"control": "penetration", "creepage_input": "kinematic"}, {})]
    assert list(runs[0]) == list(runs[1]) and runs[0]["status"] == 0
    assert runs[0]["eta_used_left"] != 0.0 and runs[2]["eta_used_left"] == 0.0
    assert runs[0]["normal_force_left"] != pytest.approx(runs[2]["normal_force_left"])


def test_value_references_of_the_published_interface(md):
    """The value references of the FMU's first published interface (commit 039db95's
    modelDescription) are a published interface: a model built against them must keep
    working, so variables added later come after them. These numbers are written down,
    not computed."""
    published = {  # name: (type, valueReference) at 039db95
        ("wheel_profile", "String"): 0, ("tangential_solver", "String"): 10,
        ("inclination", "Real"): 0, ("young", "Real"): 4, ("load_tolerance", "Real"): 10,
        ("lateral_displacement", "Real"): 11, ("yaw", "Real"): 12,
        ("load_left", "Real"): 13, ("load_right", "Real"): 14,
        ("vertical_displacement", "Real"): 15, ("roll", "Real"): 16,
        ("speed", "Real"): 17, ("xi_left", "Real"): 18, ("spin_speed", "Real"): 26,
        ("normal_force_left", "Real"): 27, ("normal_force_right", "Real"): 28,
        ("creep_force_x_left", "Real"): 29, ("force_vertical", "Real"): 65,
        ("yaw_moment", "Real"): 66, ("solve_time", "Real"): 67,
        ("contact_vertical_position_right", "Real"): 71,
        ("n_patches_left", "Integer"): 0, ("status", "Integer"): 8,
        ("status_left", "Integer"): 15, ("status_right", "Integer"): 16,
    }
    got = {(v.name, v.type): v.valueReference for v in md.modelVariables}
    assert {k: got.get(k) for k in published} == published


def test_convention_contact_through_the_fmu(fmu, extracted, md):
    """convention = contact (the String, or convention_choice = 2): the creepage inputs
    and the creep forces are CONTACT's, in the wheelset's frames (y to the left on both
    wheels, railcontact.settings.convention.wheel_frame_creepage) (cksi, ceta, cphi) =
    (-xi, eta, phi) and FX = -F_x: the same physical state in both conventions gives F_x
    of opposite sign, equal to WheelsetContact(convention="contact")'s. (CONTACT poses
    each patch at its reference point, railcontact at the contact point: the magnitudes
    agree to the difference of the two frames, F_x to 0.5 % without spin, the lateral
    force to 2.2 %.)"""
    xi, eta, phi = 1e-3, -5e-4, 0.0
    ours = {"xi_left": xi, "eta_left": eta, "phi_left": phi,
            "xi_right": xi, "eta_right": eta, "phi_right": -phi}
    theirs = {"xi_left": -xi, "eta_left": eta, "phi_left": phi,
              "xi_right": -xi, "eta_right": eta, "phi_right": -phi}
    out = ["creep_force_x_left", "creep_force_x_right", "force_longitudinal_left",
           "force_lateral_right", "normal_force_left"]
    got = {}
    for name, start, creep in (("rc", {}, ours), ("contact", {"convention": "contact"}, theirs)):
        s = Slave(fmu, extracted, md, f"convention-{name}", warm_start="none", **start)
        assert s.step(lateral_displacement=3e-3, **creep) == 0
        got[name] = dict(zip(out, s.get(*out), strict=True))
        s.free()
    _, wc = _api_from({"warm_start": "none", "convention": "contact"})
    r = wc.solve(Pose(3e-3), loads=(83.3e3, 83.3e3),
                 creepages=((-xi, eta, phi), (-xi, eta, -phi)))
    fx = got["rc"]["creep_force_x_left"]
    assert fx < -100.0  # railcontact: F_x = -f11 xi on the wheel
    for side in ("left", "right"):
        k = f"creep_force_x_{side}"
        assert got["contact"][k] == pytest.approx(-got["rc"][k], rel=5e-3)
        assert got["contact"][k] == pytest.approx(getattr(r, side).creep_force[0], rel=1e-9)
    for k in ("force_longitudinal_left", "force_lateral_right", "normal_force_left"):
        assert got["contact"][k] == pytest.approx(got["rc"][k], rel=3e-2)
    s = _instantiate(md, extracted, "convention-enum", {"convention_choice": 2})
    assert _slave_named("convention-enum").contact.convention == "contact"
    s.terminate()
    s.freeInstance()


def _fmu_rigid_module(name: str):
    """The FMU's own copy of railcontact.timestep.rigid, as the slave ``name`` uses it."""
    import sys

    package = type(_slave_named(name)).__module__.rsplit(".", 1)[0]
    return sys.modules[f"{package}.timestep.rigid"]


def test_rigid_wheelset_not_found_is_a_status(fmu, extracted, md, capsys, monkeypatch):
    """Under load control the FMU reports the rigid wheelset's vertical displacement and
    roll; when they are not found (one evaluation allowed, on the flange) the step says so:
    status 1 (not converged), fmi2Warning, the message logged. An error in that solve is
    the same status and a message, not an exception (fmi2Discard)."""
    s = Slave(fmu, extracted, md, "rigid", warm_start="none")
    rigid = _fmu_rigid_module("rigid")
    assert s.step(lateral_displacement=8e-3) == 0 and s.get("status") in (0, 4)
    monkeypatch.setattr(rigid, "MAX_EVALUATIONS", 1)
    capsys.readouterr()
    assert s.step(lateral_displacement=8e-3) == 0  # fmi2Warning: fmpy does not raise
    assert s.get("status") == 1 and s.get("status_left") in (0, 4)
    assert "rigid wheelset's vertical displacement and roll not converged" in \
        capsys.readouterr().out

    def broken(self):
        raise rigid.RailContactError("a wheel beyond its profile at that roll")

    monkeypatch.setattr(rigid.RigidWheelset, "solve", broken)
    assert s.step(lateral_displacement=3e-3) == 0
    assert s.get("status") == 1
    assert "a wheel beyond its profile at that roll" in capsys.readouterr().out
    s.free()


def test_rigid_wheelset_can_be_skipped(fmu, extracted, md):
    """rigid_wheelset = skip (its enumeration 2): under load control the rigid wheelset's
    vertical displacement and roll are not solved (0), the moments are taken about the
    nominal centre height r0, as the API's with vertical 0; the forces are the same."""
    s = Slave(fmu, extracted, md, "skip", warm_start="none", rigid_wheelset="skip")
    assert s.step(lateral_displacement=3e-3, **CREEP) == 0
    pose, loads = Pose(3e-3), (83.3e3, 83.3e3)
    creep = ((1e-3, -5e-4, 0.3), (1e-3, -5e-4, -0.3))
    solved = api("none").solve(pose, loads=loads, creepages=creep)
    assert solved.vertical != 0.0 and solved.roll > 0  # solved by default
    r = api("none", rigid_wheelset="skip").solve(pose, loads=loads, creepages=creep)
    assert r.vertical is None and r.roll is None and r.rigid_solution is None
    assert s.get("wheelset_vertical_displacement", "wheelset_roll", "status") == [0, 0, 0]
    np.testing.assert_allclose(s.get("roll_moment", "pitch_moment", "normal_force_left"),
                               [r.moment[0], r.moment[1], r.left.normal_force], rtol=1e-9)
    s.free()


def test_real_track_inputs_and_profiles_per_side(fmu, extracted, md):
    """The real-track inputs (curvature, each rail's offsets and roll, friction per wheel)
    and a rail profile on one side only: the FMU's step equals the API's with the same
    values, and frictional_power is the speed times the API's power per unit speed."""
    from railcontact.timestep.wheelset import Kinematics, RailDeviation

    track = {"curvature": -1 / 800, "rail_offset_lateral_left": 1e-3,
             "rail_offset_vertical_left": -2e-4, "rail_roll_left": 2e-3,
             "rail_offset_lateral_right": 5e-4, "friction_left": 0.3, "friction_right": 0.0}
    s = Slave(fmu, extracted, md, "track", warm_start="none", rigid_wheelset="skip",
              creepage_input="kinematic", rail_profile_right="CN60")
    try:
        assert s.step(lateral_displacement=2e-3, speed=25.0, lateral_velocity=0.02,
                      **track) == 0
        got = s.get("normal_force_left", "creep_force_x_left", "creep_force_y_right",
                    "spin_moment_right", "contact_angle_right", "frictional_power_left",
                    "frictional_power_right", "status")
    finally:
        s.free()
    mat = Material(206e9, 0.28)
    wc = WheelsetContact(
        (Track(read_profile("60E1", "rail"), math.atan(1 / 40), 1.435),
         Track(read_profile("CN60", "rail"), math.atan(1 / 40), 1.435)),
        Wheelset(read_profile("S1002", "wheel"), 0.46, 1.360), ElasticPair.of(mat, mat),
        ContactSettings(friction=0.4, warm_start="none", rigid_wheelset="skip"))
    r = wc.solve(Pose(2e-3), loads=(83.3e3, 83.3e3),
                 kinematics=Kinematics(25.0, 0.02, curvature=-1 / 800),
                 rails=(RailDeviation((1e-3, -2e-4), 2e-3), RailDeviation((5e-4, 0.0))),
                 friction=(0.3, 0.4))
    want = [r.left.normal_force, r.left.creep_force[0], r.right.creep_force[1],
            r.right.spin_moment, r.right.contact_angle, r.left.frictional_power,
            r.right.frictional_power]
    np.testing.assert_allclose(got[:-1], want, rtol=1e-9, atol=1e-9)
    assert got[-1] == r.status == 0 and got[5] < 0
    assert got[5] == pytest.approx(25.0 * r.left.frictional_power_per_speed, rel=1e-12)


def test_track_inputs_beyond_their_ranges_discard_the_step_naming_them(fmu, extracted, md,
                                                                      capsys):
    """A friction input above its largest value is named with its input (and what <= 0
    means), not as a friction "> 0" when <= 0 is allowed; a rail deviation beyond its
    range is discarded too, as the variables' descriptions say (status 3, no forces)."""
    s = Slave(fmu, extracted, md, "limits", element_size=2e-3)
    try:
        capsys.readouterr()
        assert s.step(lateral_displacement=1e-3, friction_left=1000.0) == 2  # fmi2Discard
        log = capsys.readouterr().out
        assert "friction_left = 1000 is above 10 (<= 0: the parameter friction)" in log
        assert s.get("status", "normal_force_right") == [3, 0.0]
        assert s.step(friction_left=0.0, rail_offset_lateral_left=0.1) == 2
        assert "0.05 m" in capsys.readouterr().out
        assert s.step(rail_offset_lateral_left=0.0) == 0
    finally:
        s.free()
    described = {v.name: v.description for v in md.modelVariables}
    assert "at most 10; outside it the step is discarded" in described["friction_left"]
    assert "within +-0.05; outside it" in described["rail_offset_vertical_right"]
    assert "within +-0.1; outside it" in described["rail_roll_left"]
    assert "within +-0.1, a radius of 10 m or more; outside" in described["curvature"]
