"""What a warm wheelset step does outside its solvers: the step's contact points freed
without the garbage collector."""

import gc
import weakref

import numpy as np

from railcontact.geometry.profiles import builtin_profile
from railcontact.geometry.search import at_reference, contact_points
from railcontact.geometry.track import Pose, Track, Wheelset


def test_a_steps_contact_points_are_freed_without_the_garbage_collector():
    """A rigid contact point and its frame at the reference point hold their arrays (the
    trace, the frame) until they are dropped: not kept in a reference cycle, which only a
    collection frees (as the points' lazily formed fields did, ~59 objects and their
    arrays a warm step, and a young collection every ~16 steps)."""
    track, ws = Track(builtin_profile("60E1")), Wheelset(builtin_profile("S1002"))
    pose = Pose(lateral=2e-3)
    # a first call compiles the kernels (numba keeps what its compilation raised, and with
    # it the calling frames and their points, once a process): done before the check
    cp = contact_points(track, ws, pose, "left")[0]
    at_reference(cp, track, ws, pose, 8e-5).f, cp.f, cp.rail_y  # noqa: B018
    del cp
    gc.collect()
    gc.disable()
    try:
        for read in (False, True):
            cp = contact_points(track, ws, pose, "left")[0]
            ref = at_reference(cp, track, ws, pose, 8e-5)
            if read:  # every lazily formed field formed
                assert np.isfinite(cp.f).any() and np.isfinite(ref.f).any()
                assert ref.offset is not None and cp.rail_y is not None
            alive = weakref.ref(ref), weakref.ref(cp)
            contact_points(track, ws, Pose(lateral=1e-3), "left")  # (the last call is kept)
            del cp, ref
            assert [r() for r in alive] == [None, None]
    finally:
        gc.enable()


def test_first_contact_of_one_least_sample_is_the_scans_point():
    """``contact_points`` at approach 0 takes the least gap's sample as its run when no
    other sample has that gap (``trace_gap`` counts them): the same rows, to the bit, as
    the scans of :func:`~railcontact.geometry.kernels.rigid_points`, over random poses
    of both wheels; and the count of least samples is numpy's."""
    from railcontact.geometry import kernels, search

    track, ws = Track(builtin_profile("60E1")), Wheelset(builtin_profile("S1002"))
    rng = np.random.default_rng(7)
    wheel, rail = search._wheel_arrays(ws), search._rail_arrays(track)[2:4]
    for _ in range(100):
        pose = Pose(lateral=rng.uniform(-9e-3, 9e-3), yaw=rng.uniform(-8e-3, 8e-3),
                    roll=rng.uniform(-3e-3, 3e-3) if rng.random() < 0.7 else 0.0)
        for side in ("left", "right"):
            trace, g_min, k, _, ties = search._trace(track, ws, pose, side)
            assert ties == np.count_nonzero(trace[4] == trace[4].min())
            rows = kernels.rigid_points(trace, g_min, k, 0.0, *rail, *wheel[:2], *wheel[3:])
            search.forget(traces=False)
            points = contact_points(track, ws, pose, side, 0.0)
            assert len(points) == len(rows) == 1
            cp, row = points[0], rows[0]
            assert (cp.rail_u, cp.position[0], cp.position[2], cp.gap, cp.contact_angle,
                    cp.wheel_s, cp.rolling_radius) == (
                row[2], row[1], row[3], row[4], row[5], row[6], ws.radius + row[7])
