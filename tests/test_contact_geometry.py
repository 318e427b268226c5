"""Trace-method contact search on S1002 / 60E1 at 1:40."""

import math

import numpy as np
import pytest

from railcontact import RailContactError
from railcontact.geometry.points import reference_offset, samples
from railcontact.geometry.profiles import builtin_profile
from railcontact.geometry.search import contact_points, vertical_gap
from railcontact.geometry.track import Pose, Track, Wheelset

TRACK = Track(builtin_profile("60E1"))
WS = Wheelset(builtin_profile("S1002"))


def first(y, side, yaw=0.0, approach=0.0):
    return contact_points(TRACK, WS, Pose(lateral=y, yaw=yaw), side, approach)[0]


def test_track_layout():
    rail = TRACK.side_rail
    # gauge point 14 mm below the top at gauge/2; the 1:40 canted crown rises to the field side
    u_g = np.interp(-0.014, rail.z[: np.argmax(rail.z)], rail.y[: np.argmax(rail.z)])
    assert u_g == pytest.approx(1.435 / 2, abs=1e-6)
    assert rail.slope(rail.y[np.argmax(rail.z)] - 0.0) == pytest.approx(0.0, abs=2e-3)
    # taping line at 750 mm from the wheelset centre
    assert WS.axial_position(0.0) == pytest.approx(0.750)


def test_left_right_symmetry_at_zero():
    left, right = first(0.0, "left"), first(0.0, "right")
    assert left.rolling_radius == pytest.approx(right.rolling_radius, abs=1e-9)
    assert left.contact_angle == pytest.approx(right.contact_angle, abs=1e-9)
    assert left.position[1] == pytest.approx(-right.position[1], abs=1e-9)
    assert left.B == pytest.approx(right.B, rel=1e-6)


@pytest.mark.parametrize("y", [1e-3, 3e-3, 4.5e-3, 6e-3])
def test_rolling_radius_difference_is_odd(y):
    def drr(v):
        return first(v, "left").rolling_radius - first(v, "right").rolling_radius

    assert drr(y) > 0  # moving left: the left wheel rolls on a larger radius
    assert drr(-y) == pytest.approx(-drr(y), abs=1e-9)


def test_flange_contact_at_large_displacement():
    c = first(8e-3, "left")
    assert math.degrees(c.contact_angle) > 60  # S1002 flange angle 70 deg
    assert -0.045 < c.wheel_s < -0.035  # on the flange flank
    tread = first(8e-3, "right")
    assert math.degrees(tread.contact_angle) < 5


def test_two_patches_for_two_gap_minima():
    """At 5.0 mm the gap has separate minima on the tread and at the gauge corner (0.03 mm
    apart): one patch for a small approach, two once the approach exceeds the gap."""
    one = contact_points(TRACK, WS, Pose(lateral=5.0e-3), "left", approach=0.02e-3)
    two = contact_points(TRACK, WS, Pose(lateral=5.0e-3), "left", approach=0.05e-3)
    assert len(one) == 1 and len(two) == 2
    assert two[1].gap == pytest.approx(0.0306e-3, abs=2e-6)
    assert two[1].contact_angle > two[0].contact_angle
    _, _, _, _, g = vertical_gap(TRACK, WS, Pose(lateral=5.0e-3), "left")
    minima = np.flatnonzero((g[1:-1] < g[:-2]) & (g[1:-1] <= g[2:]))
    assert len(minima) >= 2


@pytest.mark.parametrize("y", [0.0, -2e-3, 3e-3, 7.78e-3])  # 7.78 mm: flange, 70 deg
def test_gap_curvature_is_the_profiles_curvature(y):
    """B = f''(0)/2 equals half the relative curvature of the two profiles at the contact
    point, -(kappa_wheel + kappa_rail)/2 (curvature of Z = const - F(S) and of the rail,
    invariant under the rotation into the tangent plane); the even part of f is B s^2."""
    c = first(y, "left")
    kw = float(WS.wheel.curvature(c.wheel_s))
    kr = float(TRACK.side_rail.curvature(c.rail_u))
    assert c.B == pytest.approx(-(kw + kr) / 2, rel=0.02)
    s = c.s
    k0 = int(np.argmin(np.abs(s)))
    f = samples(c).f
    even = 0.5 * (f[k0 + 1:k0 + 6] + f[k0 - 1:k0 - 6:-1])
    assert np.allclose(even, c.B * s[k0 + 1:k0 + 6] ** 2, rtol=0.03)
    assert c.A == pytest.approx(math.cos(math.atan(WS.wheel.slope(c.wheel_s)))
                                / (2 * c.rolling_radius), rel=1e-3)


def test_yaw_moves_contact_along_track():
    a = first(7.5e-3, "left", yaw=5e-3)
    b = first(7.5e-3, "left", yaw=-5e-3)
    assert a.position[0] == pytest.approx(-b.position[0], rel=1e-3)
    assert abs(a.position[0]) > 1e-3  # flange contact leads/lags by millimetres


def test_beyond_the_profiles():
    with pytest.raises(RailContactError, match="beyond the profiles"):
        contact_points(TRACK, WS, Pose(lateral=0.2), "left")


def test_branch_interpolation_keeps_to_the_branch_through_the_sample():
    """A curve folding back over itself (x rises, falls, rises): interpolating along the
    rising branch through sample k uses that branch only (NaN beyond it). The compiled
    in-plane interpolation of the tangent frames, with the plane the x axis itself."""
    from railcontact.geometry.kernels import interp_in_plane

    def branch_interp(xs, x, y, k):
        out = np.empty((3, xs.size))
        interp_in_plane(xs, x, y, y, y, 0.0, 0.0, 1.0, 0.0, k, out)
        assert np.array_equal(out[0], out[1], equal_nan=True)  # n = z = y here
        return out[0]

    t = np.linspace(0.0, 3.0, 301)
    x = np.where(t < 1, t, np.where(t < 2, 2 - t, t - 2))  # up 0..1, down 1..0, up 0..1
    y = t  # tells the branches apart
    xs = np.array([0.25, 0.5, 0.75])
    np.testing.assert_allclose(branch_interp(xs, x, y, 50), xs, atol=1e-12)  # first
    np.testing.assert_allclose(branch_interp(xs, x, y, 250), 2 + xs, atol=1e-12)  # third
    assert np.isnan(branch_interp(np.array([1.5]), x, y, 250)).all()


@pytest.mark.parametrize("y", [0.0, 6e-3])
def test_lateral_extent_is_the_run_of_gap_below_delta_through_the_contact_point(y):
    """The potential area across the track: the samples around s = 0 where the
    tangent-plane gap f(s) is at most delta, one sample wider on each side; the patch
    gap on a grid is f(y) + A(y) x^2 at the element centres."""
    from railcontact.halfspace.grid import Grid

    cp = contact_points(TRACK, WS, Pose(y), "left")[0]
    f, a_of_s = samples(cp).f, samples(cp).a_of_s
    for delta in (2e-5, 1e-4, 5e-4):
        lo, hi = cp.lateral_extent(delta)
        ds = cp.s[1] - cp.s[0]
        inside = (cp.s > lo + 0.5 * ds) & (cp.s < hi - 0.5 * ds)
        assert np.all(f[inside] <= delta) and np.any(np.abs(cp.s[inside]) < ds)
        for edge, out in ((lo + ds, -1), (hi - ds, 1)):  # the next sample out: above delta
            k = int(np.argmin(np.abs(cp.s - edge))) + out
            assert f[k] > delta
        assert cp.lateral_extent(delta, 1.5) == pytest.approx((1.5 * lo, 1.5 * hi))
    g = Grid(6, 5, 1e-3, 2e-3, -2.5e-3, -4e-3)
    X, Y = g.mesh()
    want = np.interp(Y, cp.s, f) + np.interp(Y, cp.s, a_of_s) * X**2
    np.testing.assert_allclose(cp.gap_on_grid(g), want, rtol=1e-14, atol=0)


def test_points_with_samples_formed_in_part_survive_pickling():
    """A frame at the reference point pickled with its samples formed over its overlap
    only (and its rigid point with none formed) forms the others after unpickling: the
    same values as the original's."""
    import pickle

    from railcontact.geometry import search

    pose = Pose(lateral=3e-3, yaw=2e-3, roll=1e-3)
    cp = contact_points(TRACK, WS, pose, "left")[0]
    ref = search.at_reference(cp, TRACK, WS, pose, 8e-5)
    copy = pickle.loads(pickle.dumps(ref))
    assert reference_offset(copy) == reference_offset(ref) and abs(reference_offset(ref)[1]) < 5e-3
    for a, b in zip(samples(copy), samples(ref), strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(samples(copy.rigid).f, samples(cp).f)
    f = samples(cp).f
    assert f[np.argmin(np.abs(cp.s))] == 0.0 and np.isfinite(cp.B) and cp.B > 0
    with pytest.raises(AttributeError):
        cp.no_such_field  # noqa: B018


def test_branch_interpolation_over_part_of_the_samples_is_the_same():
    """The in-plane interpolation at the samples s[i0:i1] only gives the values over all
    of s, bit for bit: on folded curves, with samples that fall exactly on points of the
    curve (the segment a sample on a point is taken in), with NaN points."""
    from railcontact.geometry.kernels import interp_in_plane, interp_in_plane_range

    rng = np.random.default_rng(5)
    for trial in range(400):
        n = int(rng.integers(2, 40))
        t = np.sort(rng.uniform(0.0, 1.0, n))
        u = (t, np.where(t < 0.4, t, np.where(t < 0.6, 0.8 - t, t - 0.4)),
             np.round(t * 8) / 8)[trial % 3]  # rising; folded; with plateaus
        z = rng.uniform(-0.1, 0.1, n)
        if trial % 7 == 0:
            z[rng.integers(0, n)] = np.nan
        a, b = rng.uniform(size=n), rng.uniform(size=n)
        ang = rng.uniform(-0.3, 0.3)
        cg, sg = math.cos(ang), math.sin(ang)
        u_c, z_c = rng.uniform(0.0, 1.0), rng.uniform(-0.05, 0.05)
        on_points = ((u - u_c) * cg + (z - z_c) * sg)[rng.integers(0, n, 4)]
        s = np.unique(np.concatenate([rng.uniform(-1.2, 1.2, 20), on_points]))
        s = s[np.isfinite(s)]
        k = int(rng.integers(0, n))
        full = np.empty((3, s.size))
        interp_in_plane(s, u, z, a, b, u_c, z_c, cg, sg, k, full)
        for _ in range(3):
            i0 = int(rng.integers(0, s.size))
            i1 = int(rng.integers(i0 + 1, s.size + 1))
            part = np.empty((3, i1 - i0))
            interp_in_plane_range(s, i0, i1, u, z, 0.0, 0.0, a, b, True, u_c, z_c, cg, sg, k,
                                  part, i0)
            np.testing.assert_array_equal(part, full[:, i0:i1])


@pytest.mark.parametrize("pose", [Pose(0.0), Pose(3e-3, 2e-3, 1e-3), Pose(7e-3),
                                  Pose(-5e-3, -4e-3)])
def test_frame_at_the_reference_point_formed_in_part_is_the_full_frame(pose):
    """The frame at the reference point is formed over the overlap's samples first; a
    grid's gap read from that part, and the samples formed in full later, equal the
    frame formed over all samples at once (the frame at the same point, formed in one
    pass by the rigid point's kernel at the same plane and lowered wheel)."""
    from railcontact.geometry import kernels, points, search
    from railcontact.halfspace.grid import Grid

    for side in ("left", "right"):
        cp = contact_points(TRACK, WS, pose, side, 0.0)[0]
        ref = search.at_reference(cp, TRACK, WS, pose, 8e-5)
        i0, i1, what = ref.plane.i0, ref.plane.i1, ref.plane.what
        assert 0 < i0 and i1 < search.N_S  # part of the samples
        grids = [Grid.from_bounds(-4e-3, 4e-3, y0, y1, nx=9, ny=ny)
                 for y0, y1, ny in ((-3e-3, 3e-3, 13), (-14e-3, 15e-3, 59), (-3e-2, 3e-2, 99))]
        gaps = [ref.gap_on_grid(g) for g in grids]  # the last one forms all samples
        # the same frame formed over all samples in one pass
        eta, u, z, za, zb, ur, zr, wx, wc, radius, half_bb, flange_back, u_c, z_c, gamma, \
            eta_c, kw, kr, s, overlap = points._frame_arguments(what)
        full = np.empty((5, search.N_S))
        kernels.frame_samples(eta, u, z, za, zb, ur, zr, wx, wc, radius, half_bb, flange_back,
                              u_c, z_c, gamma, eta_c, kw, kr, s, 0, search.N_S, full)
        f = full[0]
        full[0] = np.where(np.isfinite(f), f + overlap, np.inf)
        for name, row in zip(("f", "a_of_s", "wheel_s_of_s", "rail_u_of_s", "rail_z_of_s"),
                             full, strict=True):
            np.testing.assert_array_equal(getattr(samples(ref), name), row)
        assert ref.A == full[1, search.K0] and samples(ref).f[search.K0] >= 0.0
        for g, gap in zip(grids, gaps, strict=True):
            want = np.empty((g.nx, g.ny))
            kernels.gap_on_grid(s, samples(ref).f, samples(ref).a_of_s, float(g.x0),
                                float(g.dx), g.nx,
                                float(g.y0), float(g.dy), g.ny, search.FAR, want)
            np.testing.assert_array_equal(gap, want)
        assert search.count_contacts(TRACK, WS, pose, side, 3e-4) == len(
            contact_points(TRACK, WS, pose, side, 3e-4))


@pytest.mark.parametrize("y", [-6e-3, 0.0, 4e-3, 8e-3])
def test_rail_coordinate_is_the_nearest_placed_rail_point(y):
    cp = first(y, "left")
    pu, pz = TRACK._placed_points
    nearest = int(np.argmin((pu - cp.rail_u) ** 2 + (pz - cp.position[2]) ** 2))
    assert cp.rail_y == TRACK.placement[0][nearest]


@pytest.mark.parametrize("u, z", [(math.nan, 0.0), (0.0, math.inf), (-math.inf, math.nan)])
def test_rail_coordinate_of_a_non_finite_point_is_an_error(u, z):
    with pytest.raises(RailContactError, match="not finite"):
        TRACK.rail_coordinate(u, z)


def test_overlap_half_length_is_the_largest_root_of_the_overlap():
    """The compiled half length of the overlap ``f + A x^2 <= delta`` over a run of samples
    is ``sqrt(max((delta - f) / A))`` over the samples with ``delta > f`` and ``A > 0``
    (0 without any), NaN samples left out, the same bits as the numpy form."""
    from railcontact.geometry import kernels

    rng = np.random.default_rng(1)
    for t in range(2000):
        n = int(rng.integers(3, 60))
        f, a = rng.normal(0, 1e-4, n), rng.normal(1.0, 2.0, n)
        if t % 7 == 0:
            f[rng.integers(0, n)] = np.nan
        if t % 11 == 0:
            a[rng.integers(0, n)] = np.nan
        lo = int(rng.integers(0, n))
        hi = int(rng.integers(lo, n))
        delta = float(rng.normal(0, 1e-4))
        depth, aa = delta - f[lo:hi + 1], a[lo:hi + 1]
        ok = (depth > 0) & (aa > 0)
        expected = math.sqrt(float(np.max(depth[ok] / aa[ok]))) if ok.any() else 0.0
        assert kernels.overlap_half_length(f, a, lo, hi, delta) == expected
    # a parabola's overlap: f = 0, A = 2 over the run, delta = 8e-4 -> x = 0.02 exactly
    assert kernels.overlap_half_length(np.zeros(5), np.full(5, 2.0), 1, 3, 8e-4) == \
        pytest.approx(0.02, rel=1e-15)
