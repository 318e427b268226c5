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
