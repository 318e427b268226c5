"""A time step's own records and the setups a contact keeps from step to step.

An FMU's saved state rebuilds a :class:`~railcontact.timestep.warmstart.PatchMemory` from
its fields by name, so each field must land where its name says and its boxes be formed
from its pressure. A contact keeps its wheels' setups (and their solver settings) for the
settings it was given: a contact whose settings are replaced between steps must solve with
the new ones, as a contact made with them does.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

import railcontact as rc
from railcontact.halfspace.grid import Grid
from railcontact.timestep.warmstart import PatchMemory

STEEL = rc.Material(206e9, 0.28)


def _contact(friction: float) -> rc.WheelsetContact:
    return rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
                              rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                              rc.ElasticPair.of(STEEL, STEEL),
                              rc.ContactSettings(friction=friction, element_size=1e-3))


def _fields(record) -> dict:
    return {f.name: getattr(record, f.name) for f in dataclasses.fields(record) if f.init}


def test_patch_memory_fields_by_name_and_its_boxes():
    """Every field given by name is read back under that name, and the contact box is the
    outer edges of the elements with pressure (rows 3:5, columns 4:7 of a 1 mm grid whose
    first element's centre is at (-5, -7) mm)."""
    grid = Grid(10, 12, 1e-3, 1e-3, -5e-3, -7e-3)
    pressure = np.zeros(grid.shape)
    pressure[3:5, 4:7] = 1e6
    older = PatchMemory(grid, pressure, None, None, 0.0, 0.0, time=0.0)
    given = dict(grid=grid, pressure=pressure, traction=np.ones((2, *grid.shape)),
                 state=np.ones(grid.shape, np.int8), u=0.1, z=-0.2, time=1e-3, older=older,
                 vertical_creep=5.0, approach=6e-5, vertical_normal=7e4,
                 traction_rate=np.zeros((2, *grid.shape)), displacement=None,
                 element_box=None)
    memory = PatchMemory(**given)
    read = _fields(memory)
    assert list(read) == list(given)
    for name, value in given.items():
        if name != "element_box":
            assert read[name] is value, name
    assert memory.element_box == (3, 5, 4, 7)
    assert np.allclose(memory.contact_box, (-2.5e-3, -0.5e-3, -3.5e-3, -0.5e-3))
    assert PatchMemory(**read) == memory  # (as a saved state rebuilds it)
    kept = memory.without_older()
    assert kept.older is None and kept.traction_rate is None
    assert kept.contact_box == memory.contact_box and kept.time == memory.time


def test_replaced_settings_solve_as_a_new_contact():
    """A contact whose friction is replaced between steps gives the creep forces of a
    contact made with that friction (saturated creepages: the forces follow mu)."""
    pose, loads = rc.Pose(2e-3), (80e3, 80e3)
    creep = ((5e-3, 0.0, 0.0), (5e-3, 0.0, 0.0))
    contact = _contact(0.4)
    high = contact.solve(pose, loads=loads, creepages=creep)
    contact.settings = dataclasses.replace(contact.settings, friction=0.2)
    contact.reset()
    low = contact.solve(pose, loads=loads, creepages=creep)
    fresh = _contact(0.2).solve(pose, loads=loads, creepages=creep)
    for side in ("left", "right"):
        a, b = getattr(low, side), getattr(fresh, side)
        assert a.creep_force == b.creep_force
        assert a.normal_force == b.normal_force
        # the creep force near saturation: about mu N, half of it at half the friction
        ratio = abs(getattr(high, side).creep_force[0]) / abs(a.creep_force[0])
        assert 1.7 < ratio < 2.1
