"""A time step's own records and the setups a contact keeps from step to step.

A :class:`~railcontact.timestep.warmstart.PatchMemory` forms its boxes from its pressure
(the next step's potential area starts from them). A contact keeps its wheels' setups (and
their solver settings) for the settings it was given: a contact whose settings are replaced
between steps must solve with the new ones, as a contact made with them does.
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


def test_patch_memory_boxes_are_the_edges_of_its_pressure():
    """A remembered patch's element box is the elements with pressure and its contact box
    their outer edges (rows 3:5, columns 4:7 of a 1 mm grid whose first element's centre
    is at (-5, -7) mm), and a memory without its older step keeps them."""
    grid = Grid(10, 12, 1e-3, 1e-3, -5e-3, -7e-3)
    pressure = np.zeros(grid.shape)
    pressure[3:5, 4:7] = 1e6
    older = PatchMemory(grid, pressure, None, None, 0.0, 0.0, time=0.0)
    memory = PatchMemory(grid, pressure, np.ones((2, *grid.shape)),
                         np.ones(grid.shape, np.int8), 0.1, -0.2, time=1e-3, older=older,
                         traction_rate=np.zeros((2, *grid.shape)))
    assert memory.element_box == (3, 5, 4, 7)
    assert np.allclose(memory.contact_box, (-2.5e-3, -0.5e-3, -3.5e-3, -0.5e-3),
                       rtol=0, atol=1e-12)
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
