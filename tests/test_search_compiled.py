"""The contact search's compiled passes (:func:`~railcontact.geometry.kernels.search_wheel`,
:func:`~railcontact.geometry.kernels.reference_patch`,
:func:`~railcontact.geometry.kernels.overlap_box_frame`) against the kernels and the Python
they take in, called one by one, bit for bit; and the points they form against the
profiles they are formed from (S1002 on 60E1 at 1:40)."""

import math

import numpy as np
import pytest

from railcontact import RailContactError
from railcontact.geometry import kernels, points, search
from railcontact.geometry.profiles import builtin_profile
from railcontact.geometry.track import Pose, Track, Wheelset

TRACK = Track(builtin_profile("60E1"))
WS = Wheelset(builtin_profile("S1002"))
POSES = [Pose(0.0), Pose(3e-3, 2e-3, 1e-3), Pose(7e-3), Pose(-5e-3, -4e-3), Pose(9e-3),
         Pose(-8e-3, 1e-3, -2e-3)]


def _same(a: float, b: float) -> bool:
    return a == b or (math.isnan(a) and math.isnan(b))


def _chain_first(found):
    """The first rigid point as the kernels one by one and the Python around them form
    it: rigid_point, rigid_curvature_samples, B from the three samples (Python's float
    arithmetic) and the rail coordinate."""
    trace, g_min, k = found.trace, found.least_gap, found.first_sample
    rail, wheel = found.rail, found.wheel
    row = kernels.rigid_point(trace[0], trace[1], trace[2], trace[4], g_min, k, k + 1,
                              *rail[2:4], *wheel[:2], *wheel[3:])
    eta_c, x_c, u_c, z_rail, gap_c, gamma, s_c, dr = row
    near = np.empty((5, points.N_S))
    a, lo, mid, hi = kernels.rigid_curvature_samples(
        trace[0], trace[2], trace[3], g_min, *rail[:2], *wheel, u_c, z_rail, gamma, eta_c,
        points.S_SAMPLES, points.K0, found.increasing, near)
    lo, mid, hi = float(lo), float(mid), float(hi)
    b = math.nan
    if math.isfinite(lo) and math.isfinite(mid) and math.isfinite(hi):
        b = (lo - 2 * mid + hi) / (2 * float(points.S_SAMPLES[5] - points.S_SAMPLES[0]) ** 2)
        b = b if math.isfinite(b) and b > 0 else math.nan
    return row, (float(a), b, TRACK.rail_coordinate(u_c, z_rail))


@pytest.mark.parametrize("pose", POSES)
def test_search_in_one_pass_is_the_kernels_one_by_one(pose):
    for side in ("left", "right"):
        found = search.search_wheel(TRACK, WS, pose, side)
        # the trace: trace_gap's
        sgn = 1 if side == "left" else -1
        psi, phi = sgn * pose.yaw, sgn * pose.roll
        eta, r, dr = search._wheel_samples(WS)
        out = np.empty((5, eta.size))
        n, g_min, k, inc, ties = kernels.trace_gap(
            eta, r, dr, psi != 0.0, math.tan(psi), math.cos(psi), math.sin(psi),
            math.cos(phi), math.sin(phi), float(sgn * pose.lateral), float(WS.radius),
            *search.rail_arrays(TRACK)[4:8], out)
        np.testing.assert_array_equal(found.trace, out[:, :n])
        assert (found.least_gap, found.first_sample, found.increasing, found.ties) == (
            g_min, k, inc, ties)
        # the first point
        assert found.first is not None and ties == 1
        row, rec = _chain_first(found)
        assert found.first[0] == row
        assert all(_same(x, y) for x, y in zip(found.first[1], rec, strict=True))
        cp = points.contact_points(found, 0.0)[0]
        assert (cp.A, cp.rail_y, cp.rail_u, cp.contact_angle) == (rec[0], rec[2], row[2],
                                                                   row[5])
        assert _same(cp.B, rec[1])


def test_search_without_one_least_sample_forms_the_point_from_the_trace():
    """A least gap on several samples: the point is formed by contact_points' scan (the
    search leaves it), as the search would on one."""
    found = search.search_wheel(TRACK, WS, Pose(2e-3), "left")
    tied = search.WheelSearch(found.track, found.wheelset, found.pose, found.side,
                              found.trace, found.least_gap, found.first_sample,
                              found.increasing, 1, found.rail, found.wheel, None)
    a, b = points.contact_points(found, 0.0)[0], points.contact_points(tied, 0.0)[0]
    for name in ("gap", "wheel_s", "rail_u", "rail_y", "position", "contact_angle",
                 "rolling_radius", "A", "B"):
        assert getattr(a, name) == getattr(b, name)


def test_search_beside_the_rail_is_an_error():
    with pytest.raises(RailContactError, match="beside its rail"):
        search.search_wheel(TRACK, WS, Pose(0.2), "left")


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("approach", [2e-5, 8e-5, 3e-4])
def test_reference_patch_in_one_pass_is_the_kernels_one_by_one(pose, approach):
    for side in ("left", "right"):
        found = search.search_wheel(TRACK, WS, pose, side)
        cp = points.contact_points(found, 0.0)[0]
        ref = points.at_reference(found, cp, approach)
        frame = np.empty((5, points.N_S))
        r = kernels.reference_frame(found.trace, found.least_gap, found.increasing,
                                    approach, cp.rail_u, *found.rail[:4], *found.wheel,
                                    points.S_SAMPLES, points.K0, points.WEIGHT_POWER, 0.0,
                                    frame)
        (ok, u_ref, z_ref, gamma, overlap, wheel_s, lo, hi, i0, i1, kw, kr, eta_c, g_lo,
         height, weight, u_a, z_a, u_b, z_b) = r
        if not ok:
            assert ref is None
            continue
        s = points.S_SAMPLES
        width = float(s[hi - 1] - s[lo]) + float(s[1] - s[0])
        if hi - lo >= 5:
            b = overlap / (0.5 * width) ** 2
        else:
            f3 = [float(frame[0, points.K0 + d]) for d in (-5, 0, 5)]
            b = (f3[0] - 2 * f3[1] + f3[2]) / (2 * float(s[5] - s[0]) ** 2)
            b = b if all(map(math.isfinite, f3)) and math.isfinite(b) and b > 0 else math.nan
        assert ref.B == (b if math.isfinite(b) else cp.B)
        assert ref.rail_y == TRACK.rail_coordinate(u_ref, z_ref)
        assert (ref.rail_u, ref.position[2], ref.contact_angle, ref.wheel_s, ref.A) == (
            u_ref, z_ref, gamma, wheel_s, float(frame[1, points.K0]))
        assert (ref.plane.i0, ref.plane.i1) == (i0, i1)
        np.testing.assert_array_equal(ref.plane.frame[:, i0:i1], frame[:, i0:i1])


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("approach", [3e-5, 8e-5, 2e-4, 6e-4])
def test_overlap_box_in_one_pass_is_the_python_one(pose, approach):
    """overlap_box_on_run (one compiled pass, the frame formed further where the overlap
    or the run reaches its edge) gives the box, and forms the samples, that overlap_box
    with run_on_rail's run gives, at penetrations within and beyond the frame's."""
    for side in ("left", "right"):
        found = search.search_wheel(TRACK, WS, pose, side)
        cp = points.contact_points(found, 0.0)[0]
        for pen_share in (0.3, 1.0, 3.0):
            a = points.at_reference(found, cp, approach)
            if a is None:
                continue
            b = points.at_reference(found, cp, approach)
            pen = pen_share * a.normal_penetration(approach)
            run_approach = pen / math.cos(a.contact_angle) + a.gap
            box = points.overlap_box_on_run(found, a, pen, run_approach)
            want = points.overlap_box(b, pen, points.run_on_rail(found, run_approach,
                                                                 b.rail_u))
            assert box == want
            assert (a.plane.i0, a.plane.i1) == (b.plane.i0, b.plane.i1)
            np.testing.assert_array_equal(a.plane.frame[:, a.plane.i0:a.plane.i1],
                                          b.plane.frame[:, b.plane.i0:b.plane.i1])


@pytest.mark.parametrize("y", [-6e-3, 0.0, 4e-3, 8e-3])
def test_first_point_is_on_the_profiles(y):
    """The search's first point is the placed rail's point of its profile coordinate
    (the profile canted and placed, within the placement's sample spacing) and its A is
    the wheel's Meusnier curvature there, cos(beta) / (2 r)."""
    found = search.search_wheel(TRACK, WS, Pose(y), "left")
    cp = points.contact_points(found, 0.0)[0]
    _, _, _, du, dz = TRACK.placement
    c, s = math.cos(TRACK.inclination), math.sin(TRACK.inclination)
    y = cp.rail_y
    h = float(TRACK.rail.height(y))
    spacing = float(np.diff(TRACK.placement[0]).max())
    tol = spacing * (1 + abs(float(TRACK.rail.slope(y))))  # (half a spacing along y)
    assert cp.rail_u == pytest.approx(y * c - h * s + du, abs=tol)
    assert cp.position[2] == pytest.approx(y * s + h * c + dz, abs=tol)
    slope = float(WS.wheel.slope(cp.wheel_s))
    r = WS.radius + float(WS.wheel.height(cp.wheel_s))
    assert cp.A == pytest.approx(1.0 / (math.sqrt(1 + slope * slope) * 2 * r), rel=1e-4)


def test_the_search_forms_the_merges_of_its_contact_regions():
    """The search's merges (:attr:`~railcontact.geometry.points.WheelSearch.merges`, formed
    in its compiled pass with MIN_LOBE) are merge_saddles of its trace's gap, bit for bit,
    on both wheels at poses on the tread and the flange, two of which have merges; read-only;
    merge_approaches returns them for MIN_LOBE and forms others for another lobe."""
    with_merges = 0
    for pose in POSES + [Pose(x * 1e-3) for x in (-8.0, -4.0, 4.5, 6.0, 6.6, 8.0)]:
        for side in ("left", "right"):
            try:
                found = search.search_wheel(TRACK, WS, pose, side)
            except RailContactError:  # (beside its rail)
                continue
            want = kernels.merge_saddles(found.trace[4], found.least_gap, points.MIN_LOBE)
            assert np.array_equal(found.merges, want)
            assert not found.merges.flags.writeable
            assert points.merge_approaches(found, points.MIN_LOBE) is found.merges
            assert np.array_equal(points.merge_approaches(found, 0.0),
                                  kernels.merge_saddles(found.trace[4], found.least_gap, 0.0))
            with_merges += found.merges.size > 0
    assert with_merges >= 2
