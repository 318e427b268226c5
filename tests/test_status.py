"""One status vocabulary: the time step, the tables, the FMU's variables and docs and the
co-simulation read their statuses from :class:`railcontact.status.Status`."""

from __future__ import annotations

from pathlib import Path

import pytest

from railcontact.errors import CaseError, ConvergenceError, RailContactError
from railcontact.fmu import variables as V
from railcontact.sim import cosim
from railcontact.status import Status, status_of
from railcontact.table import variables as TV
from railcontact.timestep import wheelset as W

ROOT = Path(__file__).resolve().parents[1]


def test_the_time_step_tables_and_cosim_use_the_enum():
    assert (W.OK, W.NOT_CONVERGED, W.NO_CONTACT, W.OUT_OF_RANGE, W.OUTSIDE_VALIDITY) == (
        Status.OK, Status.NOT_CONVERGED, Status.NO_CONTACT, Status.OUT_OF_RANGE,
        Status.OUTSIDE_VALIDITY)
    assert all(isinstance(s, Status) for s in W.SEVERITY)
    assert TV.NOT_COMPUTED is Status.NOT_COMPUTED
    assert TV.STATUS_MEANINGS == {s: s.label for s in Status}
    assert cosim.STATUS_OUT_OF_RANGE is Status.OUT_OF_RANGE
    assert W.WheelContact(side="left").status is Status.NO_CONTACT


def test_severity_orders_the_wheelset_status():
    """ok < no contact < outside validity < not converged < out of range: a wheelset is as
    bad as its worst wheel."""
    order = [Status.OK, Status.NO_CONTACT, Status.OUTSIDE_VALIDITY, Status.NOT_CONVERGED,
             Status.OUT_OF_RANGE]
    assert [s.severity for s in order] == sorted(s.severity for s in order)
    assert list(W.SEVERITY) == order
    assert Status.worst([0, 4, 1]) is Status.NOT_CONVERGED
    assert Status.worst([]) is Status.OK
    # the order the FMU's variables state, generated: the same ranks
    said = [Status(int(c)) for c in Status.severity_order().split(" > ")]
    assert said == order[::-1]
    assert all(Status.severity_order() in v.description
               for v in [*V.OUTPUTS, *V.VEHICLE_OUTPUTS] if v.name == "status")
    r = W.WheelsetResult(W.WheelContact("left", Status.OUTSIDE_VALIDITY),
                         W.WheelContact("right", Status.NO_CONTACT))
    assert r.status is Status.OUTSIDE_VALIDITY


def test_one_map_from_exceptions_to_statuses():
    """A convergence failure is a solver's, not a bad value: not a ValueError."""
    assert not issubclass(ConvergenceError, ValueError)
    assert issubclass(CaseError, ValueError) and issubclass(RailContactError, ValueError)
    assert status_of(ConvergenceError("load loop")) is Status.NOT_CONVERGED
    assert status_of(CaseError("a patch beyond the model")) is Status.OUT_OF_RANGE
    assert status_of(RailContactError("beside its rail")) is Status.OUT_OF_RANGE
    with pytest.raises(ZeroDivisionError):  # a fault of the code is not a wheel's status
        status_of(ZeroDivisionError("bug"))


def test_the_fmu_describes_every_status_from_the_enum():
    """Python -> the FMU's variable descriptions (its modelDescription) -> the docs' table
    (generated from them): every status with its number, label and meaning. (The built
    FMU's modelDescription.xml, and its status outputs stepped against the API's:
    tests/test_fmu.py::test_status_round_trip_python_fmu_model_description, where the
    FMU is built once.)"""
    status_vars = [v for v in V.OUTPUTS if v.name.startswith("status")]
    assert {v.name for v in status_vars} >= {"status", "status_left", "status_right"}
    doc = (ROOT / "docs" / "fmu.md").read_text(encoding="utf-8")
    for s in Status:
        if s is Status.NOT_COMPUTED:
            continue
        words = f"{int(s)} {s.label} ({s.description}"
        for v in status_vars:
            assert words in v.description, (v.name, s)
        assert words in doc, s


def test_every_solver_result_says_converged_or_status_message_and_work():
    """One result protocol: a case's solution, its patches and their normal and
    tangential solutions, a wheel's solution and a step's records each say whether they
    converged (or their status), a message and their work (:class:`Work`), whose counts
    are the results' own."""
    import math

    import railcontact as rc
    from railcontact.contact.wheelrail import solve_wheel, wheel_problem
    from railcontact.status import Work
    from railcontact.timestep.inputs import solver_settings

    d = {"material": {"young": 206e9, "poisson": 0.28},
         "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1",
                      "inclination": 0.025, "lateral_displacement": 2e-3, "side": "left"},
         "grid": {"dx": 1e-3, "dy": 1e-3}, "normal": {"load": 80e3},
         "tangential": {"friction": 0.3, "creepage": [1e-3, 0.0, 0.0]}}
    sol = rc.solve(d)
    p = sol.patches[0]
    results = [sol, p, p.normal, p.tangential]
    for r in results:
        assert isinstance(r.converged, bool) and isinstance(r.message, str), r
        assert isinstance(r.work, Work), r
    assert sol.converged and sol.message == p.message == "ok"
    assert p.normal.work.normal_iterations == p.normal.iterations > 0
    assert p.tangential.work.tangential_iterations == p.tangential.iterations > 0
    assert p.normal.work.seconds == p.normal.wall_time
    assert sol.work.normal_iterations == p.work.normal_iterations >= p.normal.iterations
    # a wheel's solution and a step's records
    track = rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40))
    ws = rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46)
    pair = rc.ElasticPair.of(rc.Material(206e9, 0.28), rc.Material(206e9, 0.28))
    settings = rc.ContactSettings(element_size=1e-3, friction=0.3, warm_start="none")
    w = solve_wheel(wheel_problem(track, ws, rc.Pose(2e-3), "left", pair,
                                  rc.settings.Control(load=80e3)),
                    solver_settings(settings, False))
    assert w.status is Status.OK and w.message == "ok"
    assert w.work.normal_iterations == sum(q.work.normal_iterations for q in w.patches) > 0
    step = rc.WheelsetContact(track, ws, pair, settings).solve(rc.Pose(2e-3),
                                                               loads=(80e3, 80e3))
    for r in (step, *step.wheels):
        assert r.status is Status.OK and r.message == "ok" and isinstance(r.work, Work)
    # one that did not converge says so, in each record above it
    q = rc.solve({**d, "normal": {"load": 80e3, "max_iterations": 2}}).patches[0]
    assert not q.converged and not q.normal.converged
    assert q.message == q.normal.message and q.message.startswith("not converged")
