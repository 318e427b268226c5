"""A warm step whose patches merge.

Two patches of the left wheel (S1002 on 60E1 at 1:40, 5 mm lateral, 2 mrad yaw, the
wheelset lowered for about 0.05 mm of approach: the gap has two minima) merge into one
as the approach grows. The warm step took the merged patch's potential area from the
remembered patch at the same contact point (``warmstart.previous_bounds``): the box of
one of the two old contacts. The other lobe lay wholly outside that box, the contact
inside did not reach its edge, so the area was not grown, and the lobe's load was lost
- in that step and every later one (34.8 kN warm against 40.3 kN cold). A patch whose
rigid overlap takes in another remembered patch (``warmstart.merged``) is now meshed on
the rigid overlap, as from cold. The cold step of the same state carries both lobes (the
two forces of the step before add up to it): the normal force of a state must not
depend on the start.
"""

import math

import pytest

import railcontact as rc
from railcontact.geometry.search import vertical_gap


def _contact(mode: str) -> rc.WheelsetContact:
    return rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=0.4, element_size=0.5e-3, warm_start=mode))


def test_merged_patches_carry_the_same_normal_force_warm_and_cold():
    warm, cold = _contact("previous+estimate"), _contact("none")
    g = float(vertical_gap(warm.track, warm.wheelset, rc.Pose(5e-3), "left")[4].min())
    counts = []
    for k in range(9):
        t = k * 1e-3
        pose = rc.Pose(5e-3 + 0.3e-3 * math.sin(2 * math.pi * 5 * t), 2e-3)
        v = -g - 4e-5 - 2e-5 * math.sin(2 * math.pi * 7 * t)  # penetration control
        w = warm.solve(pose, vertical=v, time=t).wheels[0]
        c = cold.solve(pose, vertical=v, time=t).wheels[0]
        counts.append(len(c.patches))
        assert len(w.patches) == len(c.patches)
        assert w.normal_force == pytest.approx(c.normal_force, rel=1e-3), (k, counts)
    assert counts[0] == 2 and counts[-1] == 1  # the patches did merge
