"""A time step's stages run in the step: reading its result solves nothing.

The rigid wheelset's vertical displacement and roll under load control are a stage of
:meth:`WheelsetContact.solve` when ``ContactSettings.rigid_wheelset`` asks for it; the
result's attributes are values. Reading every attribute of a result (and of its wheels)
must run no BEM solve and leave the contact's memory - the next step's warm start - as it
was.
"""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import math
from pathlib import Path

import pytest

import railcontact as rc
import railcontact.contact.wheelrail as wheelrail
import railcontact.timestep.wheel as wheel
from railcontact.geometry.search import ContactPoint
from railcontact.halfspace.operator import InfluenceOperator
from railcontact.timestep.wheelset import WheelContact, WheelsetContact

ROOT = Path(__file__).resolve().parents[1]
hertz_module = importlib.import_module("railcontact.halfspace.hertz")  # (the package's
# name hertz is the function)
STEEL = rc.Material(206e9, 0.28)
CREEP = ((1e-3, -5e-4, 0.3), (1e-3, -5e-4, -0.3))
WHEEL_RAIL_CASE = {
    "material": {"young": 206e9, "poisson": 0.28},
    "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                 "inclination": 0.025, "lateral_displacement": 2e-3, "side": "left"},
    "grid": {"dx": 1e-3, "dy": 1e-3}, "normal": {"load": 80e3},
    "tangential": {"friction": 0.3},
    "kinematics": {"speed": 20.0, "spin_speed": 20.0 / 0.4595}}
"""A left wheel on the tread with kinematic creepages (a case's solution to read)."""


def _contact(**settings) -> WheelsetContact:
    return WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
                           rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                           rc.ElasticPair.of(STEEL, STEEL),
                           rc.ContactSettings(element_size=1e-3, **settings))


@pytest.fixture
def solves(monkeypatch):
    """The number of solves run since the fixture was made: normal and tangential patch
    solves (BEM), Hertz's solutions, and products with an influence operator (the BEM's
    work, and a tangential result's slip)."""
    count = {"normal": 0, "tangential": 0, "hertz": 0, "operator": 0}

    def counted(kind, f):
        def wrapper(*args, **kwargs):
            count[kind] += 1
            return f(*args, **kwargs)
        return wrapper

    monkeypatch.setattr(wheelrail, "solve_patch_normal",
                        counted("normal", wheelrail.solve_patch_normal))
    monkeypatch.setattr(wheel, "solve_patch_tangential",
                        counted("tangential", wheel.solve_patch_tangential))
    # (a warm patch's stages in one compiled call each, timestep.compiled)
    monkeypatch.setattr(wheel, "warm_normal", counted("normal", wheel.warm_normal))
    monkeypatch.setattr(wheel, "warm_tangential",
                        counted("tangential", wheel.warm_tangential))
    monkeypatch.setattr(hertz_module, "semi_axes", counted("hertz", hertz_module.semi_axes))
    for cls in (InfluenceOperator, *InfluenceOperator.__subclasses__()):
        if "apply" in vars(cls):
            monkeypatch.setattr(cls, "apply", counted("operator", cls.apply))
    return count


def _read_everything(obj, seen=None) -> list:
    """Every dataclass field and every public property of ``obj``, and of every record
    it holds (its wheels, their patches, each patch's normal and tangential solutions,
    Hertz's, its grids), read once each."""
    seen = set() if seen is None else seen
    if id(obj) in seen:
        return []
    seen.add(id(obj))
    out = []
    names = {f.name for f in dataclasses.fields(obj)}
    names |= {n for cls in type(obj).__mro__ for n, v in vars(cls).items()
              if isinstance(v, property) and not n.startswith("_")}
    for n in sorted(names):
        value = getattr(obj, n)
        out.append(value)
        for v in value if isinstance(value, (list, tuple)) else (value,):
            if (dataclasses.is_dataclass(v) and not isinstance(v, type)
                    and type(v).__module__.startswith("railcontact")
                    and not isinstance(v, ContactPoint)):
                out.extend(_read_everything(v, seen))
    return out


@pytest.mark.parametrize("rigid", ["solve", "skip"])
def test_reading_a_result_solves_nothing(solves, rigid):
    contact = _contact(rigid_wheelset=rigid)
    for k, y in enumerate((2e-3, 2.5e-3)):
        r = contact.solve(rc.Pose(y), loads=(83.3e3, 80e3), creepages=CREEP, time=k * 1e-3)
    assert solves["normal"] > 0 and solves["tangential"] > 0  # (the counts see the step)
    before = dict(solves)
    memory = contact.memory
    values = _read_everything(r)
    assert dict(solves) == before
    assert contact.memory is memory  # (a frozen value: replaced only by a step)
    assert len(values) > 150  # (the wheels, their patches, solutions and grids)
    if rigid == "solve":  # a stage of the step: found, and its work counted apart
        assert r.rigid_solution.converged and r.vertical is not None and r.roll > 0
        assert sum(w.normal_iterations for w in r.rigid_work) > 0
    else:
        assert r.vertical is None and r.roll is None and r.rigid_solution is None
        assert all(w.normal_iterations == 0 for w in r.rigid_work)


def test_the_rigid_stage_carries_both_loads_at_one_vertical_position():
    """The stage's vertical displacement and roll put both wheels, penetration-controlled,
    at the loads (the rigid wheelset's definition): the penetration-controlled step there
    gives the wheel loads back."""
    loads = (83.3e3, 70e3)
    contact = _contact(rigid_wheelset="solve", warm_start="none")
    r = contact.solve(rc.Pose(3e-3), loads=loads, creepages=CREEP)
    assert r.rigid_solution.converged
    check = _contact(warm_start="none").solve(rc.Pose(3e-3, 0.0, r.roll), vertical=r.vertical,
                                              creepages=CREEP)
    for w, q in zip(check.wheels, loads, strict=True):
        assert w.track_force[2] == pytest.approx(q, rel=5e-3)


def test_no_rigid_wheelset_is_reported_for_wheels_out_of_range():
    """Wheels out of range (kinematic creepages beyond the solver's +-1e3 at a speed of
    1 um/s): the wheelset is out of range and the rigid stage does not run, so no
    vertical displacement or roll is reported (was: a "converged" rigid solution after
    one evaluation, balancing wheels that have no solution)."""
    contact = _contact(rigid_wheelset="solve")
    r = contact.solve(rc.Pose(0.0), loads=(80e3, 80e3), kinematics=rc.Kinematics(1e-6, 0.01))
    assert r.status == 3 and "beyond +-1000" in r.message
    assert all(w.status == 3 for w in r.wheels)
    assert r.vertical is None and r.roll is None and r.rigid_solution is None
    # a step at a speed the creepages allow solves the rigid wheelset again
    r = contact.solve(rc.Pose(0.0), loads=(80e3, 80e3), kinematics=rc.Kinematics(30.0, 0.01))
    assert r.status == 0 and r.rigid_solution.converged and r.vertical is not None


def test_a_wheel_contact_is_a_record_of_values():
    """A WheelContact's properties are read from its fields (no solver reference)."""
    w = WheelContact(side="left")
    assert _read_everything(w)
    assert not any(callable(getattr(w, f.name)) for f in dataclasses.fields(w))


def test_reading_a_case_solution_solves_nothing(solves):
    """The same for a case's solution (``railcontact solve``): its patches' frictional
    power is formed with the solution, and reading every attribute solves nothing."""
    d = WHEEL_RAIL_CASE
    sol = rc.solve(d)
    before = dict(solves)
    assert before["normal"] > 0 and before["operator"] > 0
    values = _read_everything(sol)
    assert dict(solves) == before
    assert len(values) > 60
    p = sol.patches[0]
    assert p.frictional_power_per_speed < 0 and p.frictional_power == pytest.approx(
        p.velocity * p.frictional_power_per_speed, rel=1e-15)


def _records(obj, seen=None) -> list:
    """Every record (a railcontact dataclass instance) ``obj`` holds, itself included,
    through its fields, lists and tuples."""
    seen = set() if seen is None else seen
    if id(obj) in seen or not (dataclasses.is_dataclass(obj) and not isinstance(obj, type)
                               and type(obj).__module__.startswith("railcontact")):
        return []
    seen.add(id(obj))
    out = [obj]
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        for v in value if isinstance(value, (list, tuple)) else (value,):
            out.extend(_records(v, seen))
    return out


def test_results_are_frozen_records_all_the_way_down():
    """A step's result and a case's solution hold only frozen records (the wheels, their
    patches, each patch's normal and tangential solutions and work): a caller cannot
    change a result, and no stage after the one that formed a record writes into it."""
    contact = _contact()
    for k, y in enumerate((2e-3, 2.5e-3)):  # (a warm step: the compiled stages' records)
        r = contact.solve(rc.Pose(y), loads=(83.3e3, 80e3), creepages=CREEP, time=k * 1e-3)
    d = WHEEL_RAIL_CASE
    quadratic = {"material": {"young": 206e9, "poisson": 0.28},
                 "geometry": {"type": "quadratic", "A": 1.0, "B": 5.0},
                 "grid": {"nx": 32, "ny": 32},
                 "normal": {"load": 1e4}, "tangential": {"friction": 0.3,
                                                         "creepage": [1e-3, 0.0, 0.0]}}
    for result in (r, rc.solve(d), rc.solve(quadratic)):
        records = _records(result)
        kinds = {type(x).__name__ for x in records}
        assert {"PatchSolution", "NormalResult", "TangentialResult", "Work"} <= kinds
        thawed = sorted({type(x).__name__ for x in records
                         if not type(x).__dataclass_params__.frozen})
        assert thawed == []
    patch = r.left.patches[0]
    for record, name in ((patch, "tangential"), (patch.normal, "converged"),
                         (patch.tangential, "message"), (patch.work, "seconds")):
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(record, name, getattr(record, name))


def _step_walk():
    """``scripts/step_walk.py``: its :func:`walk` profiles one step."""
    spec = importlib.util.spec_from_file_location("step_walk", ROOT / "scripts" / "step_walk.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("warm_start", ["previous+estimate", "none"])
def test_a_step_searches_each_wheel_once_and_climbs_back_at_most_six_times(warm_start):
    """The walk of a pose through a step: the contact search entered once per wheel (the
    load loops re-use the search's record at every approach they try), and at most six
    returns into :meth:`WheelsetContact.solve` (its stages), warm and cold, under load
    control with the creep forces counted and kinematic creepages."""
    walk = _step_walk().walk
    contact = _contact(friction=0.4, warm_start=warm_start)
    w = 2 * math.pi * 1.5

    def step(k: int) -> dict:
        t = k * 1e-3
        return dict(pose=rc.Pose(3e-3 * math.sin(w * t)), loads=(83.3e3, 83.3e3),
                    kinematics=rc.Kinematics(30.0, 3e-3 * w * math.cos(w * t)), time=t)

    for k in range(3):
        contact.solve(**step(k))
    entries, climbs, by, formed = walk(contact, **step(3))
    assert sum(entries.values()) == 2, entries  # (one search of each wheel)
    assert set(entries) == {"search_wheel"}
    assert 1 <= climbs <= 6, by
    assert formed["contact_points"] >= 2  # (the profile sees the step's calls)


def test_the_step_records_say_status_message_and_work():
    """The step's records carry the solver results' protocol: a status, a message and
    the work (a :class:`~railcontact.contact.results.Work`); the wheelset's work is its
    wheels' and the rigid wheelset's solves, its time the step's."""
    contact = _contact(rigid_wheelset="solve", friction=0.4)
    r = contact.solve(rc.Pose(3e-3), loads=(83.3e3, 83.3e3), creepages=CREEP)
    assert r.status == rc.Status.OK and r.message == "ok"
    for w in r.wheels:
        assert w.status == rc.Status.OK and w.message == "ok"
        # the wheel's work is its patches' (each pass charged to them), passes once
        assert w.work.normal_iterations == sum(p.work.normal_iterations for p in w.patches)
        assert w.work.tangential_iterations == sum(p.work.tangential_iterations
                                                   for p in w.patches)
        assert w.work.load_passes == max(p.work.load_passes for p in w.patches) >= 1
        assert w.work.normal_iterations >= sum(p.normal.iterations for p in w.patches) > 0
    parts = (*(w.work for w in r.wheels), *r.rigid_work)
    assert r.rigid_work[0].normal_iterations > 0  # (the rigid stage solved at other rolls)
    for name in ("normal_iterations", "tangential_iterations", "load_passes", "remeshes"):
        assert getattr(r.work, name) == sum(getattr(p, name) for p in parts), name
    assert r.work.seconds == r.wall_time > 0
    # a wheel beyond a limit: its message, named by its side; a wheelset off its rails:
    # one message for both wheels, said once
    r = contact.solve(rc.Pose(10e-3), loads=(83.3e3, 83.3e3), creepages=CREEP)
    assert r.left.status == rc.Status.OUTSIDE_VALIDITY
    assert r.message.startswith("left wheel: outside validity: ") and "right" not in r.message
    r = contact.solve(rc.Pose(2.0), loads=(83.3e3, 83.3e3), creepages=CREEP)
    assert r.status == rc.Status.OUT_OF_RANGE
    assert r.message == r.left.message == r.right.message
    assert r.message.startswith("wheelset out of range: ")
    assert r.work.normal_iterations == 0
