"""What a warm wheelset step does outside its solvers: no Hertz solution where a bound shows
the patch within the model, and the step's contact points freed without the garbage
collector."""

import gc
import math
import weakref

import numpy as np
import pytest

from railcontact import ElasticPair, Material, hertz
from railcontact.geometry.points import reference_offset, samples
from railcontact.geometry.profiles import builtin_profile
from railcontact.geometry.search import at_reference, contact_points
from railcontact.geometry.track import Pose, Track, Wheelset
from railcontact.halfspace.hertz import semi_axis_bound

PAIR = ElasticPair.of(Material(210e9, 0.28))


def test_semi_axis_bound_is_above_hertzs_larger_semi_axis():
    """The bound that lets a warm step skip Hertz's solution holds for curvature ratios
    over 1 ... 1e6, loads over 10 N ... 10 MN and the penetrations they give, and it is
    not loose by more than a small factor (it decides nothing where it is huge)."""
    rng = np.random.default_rng(18)
    ratios = []
    for _ in range(3000):
        A = 10 ** rng.uniform(-2, 3)
        r = 10 ** rng.uniform(0, 6) if rng.random() < 0.9 else 1 + 10 ** rng.uniform(-12, -1)
        B = A * r if rng.random() < 0.5 else A / r
        q = 10 ** rng.uniform(1, 7)
        h = hertz(A, B, PAIR, load=q)
        bound = semi_axis_bound(A, B, PAIR, load=q)
        assert bound >= max(h.a, h.b)
        d = hertz(A, B, PAIR, penetration=h.penetration)
        bound_d = semi_axis_bound(A, B, PAIR, penetration=h.penetration)
        assert bound_d >= max(d.a, d.b)
        ratios.append(bound / max(h.a, h.b))
    assert max(ratios) < 6.0


@pytest.mark.parametrize("args", [(0.0, 1.0, {"load": 1.0}), (1.0, math.inf, {"load": 1.0}),
                                  (1.0, 2.0, {"load": math.nan}), (1.0, 2.0, {}),
                                  (1.0, 2.0, {"load": 1.0, "penetration": 1e-4}),
                                  (1.0, 2e7, {"load": 1.0}),
                                  (1.0, 2.0, {"penetration": -1e-4})])
def test_semi_axis_bound_is_infinite_where_hertz_is_to_be_solved_at_once(args):
    """Arguments :func:`hertz` might reject (or a ratio beyond the bound's range) give no
    bound: the caller then solves at once, and an error is raised where it was."""
    A, B, kw = args
    assert semi_axis_bound(A, B, PAIR, **kw) == math.inf


def test_a_steps_contact_points_are_freed_without_the_garbage_collector():
    """A rigid contact point and its frame at the reference point hold their arrays (the
    trace, the frame) until they are dropped: not kept in a reference cycle, which only a
    collection frees (as the points' lazily formed fields did, ~59 objects and their
    arrays a warm step, and a young collection every ~16 steps), with their samples
    formed in part or in full."""
    track, ws = Track(builtin_profile("60E1")), Wheelset(builtin_profile("S1002"))
    pose = Pose(lateral=2e-3)
    # a first call compiles the kernels (numba keeps what its compilation raised, and with
    # it the calling frames and their points, once a process): done before the check
    cp = contact_points(track, ws, pose, "left")[0]
    samples(at_reference(cp, track, ws, pose, 8e-5)), samples(cp)
    del cp
    gc.collect()
    gc.disable()
    try:
        for read in (False, True):
            cp = contact_points(track, ws, pose, "left")[0]
            ref = at_reference(cp, track, ws, pose, 8e-5)
            if read:  # every sample formed
                assert np.isfinite(samples(cp).f).any() and np.isfinite(samples(ref).f).any()
                assert reference_offset(ref) is not None
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
    wheel, rail = search.wheel_arrays(ws), search.rail_arrays(track)[2:4]
    for _ in range(100):
        pose = Pose(lateral=rng.uniform(-9e-3, 9e-3), yaw=rng.uniform(-8e-3, 8e-3),
                    roll=rng.uniform(-3e-3, 3e-3) if rng.random() < 0.7 else 0.0)
        for side in ("left", "right"):
            trace, g_min, k, _, ties = search._trace(track, ws, pose, side)[:5]
            assert ties == np.count_nonzero(trace[4] == trace[4].min())
            rows = kernels.rigid_points(trace, g_min, k, 0.0, *rail, *wheel[:2], *wheel[3:])
            search.forget(traces=False)
            points = contact_points(track, ws, pose, side, 0.0)
            assert len(points) == len(rows) == 1
            cp, row = points[0], rows[0]
            assert (cp.rail_u, cp.position[0], cp.position[2], cp.gap, cp.contact_angle,
                    cp.wheel_s, cp.rolling_radius) == (
                row[2], row[1], row[3], row[4], row[5], row[6], ws.radius + row[7])
