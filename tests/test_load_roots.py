"""One input, one answer: where a wheel's load is carried at two approaches, the wheel
returns the smallest and says that there is another.

S1002 on 60E1 at 1:40, the wheelset 5.37 mm to the left: the left wheel touches at the
flange root (17.8 deg) and, 37 um higher, on the tread (7.7 deg); the two regions of
vertical overlap join into one at a 61.55 um approach. Two patches, each in its own
tangent plane and blind to the other's pressure, then become one patch in one plane whose
lobes press on one another, and the vertical force falls there (by 11-17 %): a load
within that fall is carried on either side of the merge. Warm and cold starts must give
the same root, and the wheel must say that another exists.
"""

import math

import numpy as np
import pytest

import railcontact as rc
from railcontact.contact import WarmStart
from railcontact.contact.loadloop import vertical_force
from railcontact.contact.patch import solve_patch_normal
from railcontact.contact.wheelrail import solve_wheel_normal
from railcontact.geometry.points import samples
from railcontact.geometry.search import contact_points, merge_approaches, run_on_rail
from railcontact.settings import Control
from railcontact.timestep.wheelset import OK, WheelsetContact

STEEL = rc.Material(206e9, 0.28)
PAIR = rc.ElasticPair.of(STEEL, STEEL)
POSE = rc.Pose(0.005370366001954731, 0.0005363465486316496)


@pytest.fixture(scope="module")
def geometry():
    return (rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
            rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46))


def _normal_settings(geometry, frame):
    wc = WheelsetContact(*geometry, PAIR, rc.ContactSettings(
        element_size=1e-3, patch_frame=frame, warm_start="none"))
    return wc.settings.patch_settings


def _vertical(geometry, approach, frame):
    """The left wheel's vertical force [N] at the vertical ``approach`` [m]."""
    ps = solve_wheel_normal(*geometry, POSE, "left", Control(penetration=approach),
                            _normal_settings(geometry, frame), PAIR,
                            reference=frame == "reference")
    return vertical_force(ps), ps


def test_the_flange_root_and_the_tread_join_at_one_saddle(geometry):
    merges = merge_approaches(*geometry, POSE, "left", 0.05)
    assert merges.size == 1 and 60e-6 < merges[0] < 63e-6
    below = contact_points(*geometry, POSE, "left", merges[0] * (1 - 1e-6))
    above = contact_points(*geometry, POSE, "left", merges[0] * (1 + 1e-6))
    assert (len(below), len(above)) == (2, 1)


def test_a_merged_patch_carries_both_lobes_of_its_run(geometry):
    """At 62 um the run holds both lobes, but the rigid point's plane (17.8 deg) shows
    them apart (the tread's lobe beyond a saddle of its gap above the penetration): the
    patch solved on the potential area around its origin alone left the tread out (24.6
    against 28.9 kN). The patch's solution equals the one on an area holding the whole
    plane's overlap within the normal tolerance."""
    approach = 62e-6
    force, (patch,) = _vertical(geometry, approach, "rigid")
    cp = patch.geometry
    u_lo, u_hi = run_on_rail(*geometry, POSE, "left", approach, cp.rail_u)
    full = samples(cp)
    lobe = (full.f <= patch.normal.penetration) & (full.rail_u_of_s >= u_lo) & \
        (full.rail_u_of_s <= u_hi)
    s_lobes = cp.s[lobe]
    assert np.any(np.diff(np.flatnonzero(lobe)) > 1)  # two lobes in this plane
    xl = 1.5 * math.sqrt(patch.normal.penetration / cp.A)
    settings = _normal_settings(geometry, "rigid")
    wide, _ = solve_patch_normal(cp.gap_on_grid, (-xl, xl, s_lobes.min() - 3e-3,
                                                  s_lobes.max() + 3e-3),
                                 settings.grid, settings.normal, PAIR,
                                 Control(penetration=patch.normal.penetration),
                                 WarmStart("none"))
    assert patch.normal.force == pytest.approx(wide.force, rel=2e-3)
    loaded = patch.normal.grid.y[np.asarray(patch.normal.pressure).sum(axis=0) > 0]
    assert loaded.max() - loaded.min() > 10e-3  # the tread's lobe, 8-12 mm beside


@pytest.mark.parametrize("frame", ["reference", "rigid"])
def test_warm_and_cold_return_the_smallest_approach(geometry, frame):
    """A warm step from loads carried by the merged patch (40, then 36 kN) down to one
    carried on both sides of the merge returns the same root as a cold solve: the
    smallest approach. Below it the vertical force is less than the load; just beyond
    the merge, where another root lies when the wheel says so, it is not more."""
    base = dict(friction=0.3, element_size=1e-3, patch_frame=frame)
    warm = WheelsetContact(*geometry, PAIR, rc.ContactSettings(
        **base, warm_start="previous+estimate"))
    cold = WheelsetContact(*geometry, PAIR, rc.ContactSettings(**base, warm_start="none"))
    merge = float(merge_approaches(*geometry, POSE, "left", 0.05)[0])
    uniques = []
    for k, q in enumerate((40e3, 36e3, 34e3)):
        w = warm.solve(POSE, loads=(q, 39e3), time=1e-3 * (k + 1)).left
        c = cold.solve(POSE, loads=(q, 39e3)).left
        assert w.status == c.status == OK
        assert w.approach == pytest.approx(c.approach, rel=2e-3), (q, frame)
        assert len(w.patches) == len(c.patches)
        assert w.normal_force == pytest.approx(c.normal_force, rel=2e-3)
        assert w.load_unique == c.load_unique
        uniques.append(c.load_unique)
        # the smallest root: less than the load a little below it
        v_below, _ = _vertical(geometry, 0.98 * c.approach, frame)
        assert v_below < q
        if c.approach < merge:  # beyond the merge: another root when not yet carried
            v_beyond, ps = _vertical(geometry, merge * (1 + 1e-6), frame)
            assert len(ps) == 1
            assert c.load_unique == (v_beyond > q), (q, frame, v_beyond)
            if not c.load_unique:
                assert "more than one solution" in c.message
                # the other root, or the merge it lies beyond
                assert c.patches[0].load_other >= merge * (1 - 1e-9)
    assert not all(uniques)  # 34 kN lies within the fall at the merge


@pytest.mark.parametrize("rtol", [1e-3, 1e-8])
def test_two_patches_carry_the_load_to_the_settings_tolerance(geometry, rtol):
    """Below the merge the load is shared by two patches: the secant on the wheel's
    approach meets it to the tolerance it is given (the wheel settings'
    ``normal_load_tolerance``), a loose one in fewer passes."""
    q_ref, ps = _vertical(geometry, 40e-6, "reference")
    assert len(ps) == 2
    q = 0.93 * q_ref  # (not the approach the reference solve was at)
    settings = _normal_settings(geometry, "reference")
    ps = solve_wheel_normal(*geometry, POSE, "left", Control(load=q), settings, PAIR,
                            reference=True, load_tolerance=rtol, load_acceptance=1e-3)
    assert len(ps) == 2
    assert abs(vertical_force(ps) - q) <= rtol * q
    passes = ps[0].work.load_passes
    loose = solve_wheel_normal(*geometry, POSE, "left", Control(load=q), settings, PAIR,
                               reference=True, load_tolerance=1e-2, load_acceptance=1e-2)
    assert abs(vertical_force(loose) - q) <= 1e-2 * q
    assert loose[0].work.load_passes <= passes
    if rtol == 1e-8:
        assert loose[0].work.load_passes < passes
