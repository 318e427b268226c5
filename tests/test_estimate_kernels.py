"""The compiled pieces of the simplified models (INFCON/KP, FASTSIM/FaStrip) against their
definitions: numpy's interpolation, the rigid overlap's ends, Love's coefficients, the
strips of a contact mask."""

import dataclasses
import math

import numpy as np
import pytest

from railcontact import ElasticPair, Grid, Material, hertz
from railcontact.halfspace.influence import (
    coefficients_at,
    zz_displacement_at,
    zz_displacement_centred,
)
from railcontact.halfspace.interp import (
    interp_on_piece,
    interp_walk_sloped,
    slopes_of,
    uniform_piece,
)
from railcontact.normal.virtual import _half_width, virtual_penetration
from railcontact.tangential.strips import (
    equivalent_ellipse,
    sample_on_strips,
    strips_from_contact,
    strips_on_contact,
)

PAIR = ElasticPair.of(Material(206e9, 0.28))


def overlap_ends(s, f, level):
    """The definition of :func:`_half_width`: the run of samples with ``f <= level``
    through the sample nearest 0, each end moved to where ``f`` crosses ``level`` on the
    piece beyond it (linearly), or kept where that piece is outside or not finite."""
    k0 = int(np.argmin(np.abs(s)))
    lo = hi = k0
    while lo > 0 and f[lo - 1] <= level:
        lo -= 1
    while hi < len(s) - 1 and f[hi + 1] <= level:
        hi += 1

    def cross(i_in, i_out):
        if i_out < 0 or i_out >= len(s) or not np.isfinite(f[i_out]):
            return s[i_in]
        return s[i_in] + (level - f[i_in]) / (f[i_out] - f[i_in]) * (s[i_out] - s[i_in])

    return cross(lo, lo - 1), cross(hi, hi + 1)


def test_half_width_of_a_parabola_and_at_the_edges():
    """The rigid overlap of ``f = B s^2`` ends at ``+-sqrt(level/B)`` (within the chord's
    error), and the ends follow the definition where the run meets the arrays' ends,
    a gap that is not finite, or is one sample long."""
    s = np.linspace(-0.01, 0.012, 221)
    f = 3.0 * s**2
    lo, hi = _half_width(s, f, 3e-5)
    assert lo == pytest.approx(-math.sqrt(1e-5), rel=1e-3)
    assert hi == pytest.approx(math.sqrt(1e-5), rel=1e-3)
    cases = [
        (s, f, 1.0),  # the whole array: both ends are samples
        (s, np.where(s > 0.005, np.inf, f), 1e-4),  # infinite gap beyond the right end
        (s, np.where(s < -0.003, np.nan, f), 1e-4),  # NaN beyond the left end
        (s, f, 0.0),  # a single sample (s = 0) at the level
        (s, f + 1e-6, 0.0),  # no sample at or below the level: the nearest one alone
        (s, f, math.nan),
        (s[110:], f[110:], 1e-5),  # the nearest sample is the first
        (s[:101], f[:101], 1e-5),  # the nearest sample is the last
        (np.array([-1e-3, 1e-3]), np.array([0.0, 0.0]), 1e-6),
    ]
    for ss, ff, level in cases:
        got = _half_width(ss, ff, level)
        want = overlap_ends(ss, ff, level)
        assert np.array_equal(np.array(got), np.array(want, dtype=float), equal_nan=True), (
            level, got, want)


def test_interpolation_kernels_are_numpys():
    """The compiled ``np.interp`` (walking on, with given slopes, or from an equally
    spaced guess) gives numpy's values to the bit: between samples, on samples, beyond
    both ends, at NaN, with infinite and NaN samples, and for one sample."""
    rng = np.random.default_rng(7)
    xp = np.cumsum(rng.uniform(0.5, 1.5, 40))
    fp = rng.normal(size=40)
    fp[[5, 6, 20]] = [np.inf, np.inf, np.nan]
    x = np.sort(np.concatenate([rng.uniform(xp[0] - 3, xp[-1] + 3, 300), xp[::3],
                                [xp[0], xp[-1]]]))
    want = np.interp(x, xp, fp)
    sl = slopes_of(xp, fp)
    j = -1
    walked = []
    for v in x:
        value, j = interp_walk_sloped(v, xp, fp, sl, j)
        walked.append(value)
    guessed = [interp_on_piece(v, xp, fp, uniform_piece(v, xp, xp[0], 1.0)) for v in x]
    assert np.array_equal(walked, want, equal_nan=True)
    assert np.array_equal(guessed, want, equal_nan=True)
    assert math.isnan(interp_on_piece(math.nan, xp, fp, 0))
    one = np.array([2.0])
    assert interp_on_piece(5.0, one, np.array([3.0]), 0) == np.interp(5.0, one, [3.0])


@pytest.mark.parametrize("nx, ny", [(8, 6), (7, 5), (1, 1)])
def test_shared_corner_sums_are_loves_coefficients(nx, ny):
    """The displacement of a traction summed from the corners once each equals the sum of
    the zz coefficients (:func:`coefficients_at`) to round-off; on a uniform square of
    side 2c the corners telescope to Love's centre displacement 8 c asinh(1) [per
    (1-nu)/(pi G)], whatever the subdivision."""
    rng = np.random.default_rng(nx)
    dx, dy = 0.3e-3, 0.2e-3
    xmin, ymin = -0.5 * nx * dx, -1.1e-3
    g = Grid.from_bounds(xmin, xmin + nx * dx, ymin, ymin + ny * dy, nx, ny)
    w = rng.uniform(0.0, 2.0, (nx, ny))
    w[0, 0] = 0.0
    X, Y = g.mesh()
    for y in (0.0, 0.37e-3):
        dense = float(np.sum(coefficients_at("zz", -X, y - Y, dx, dy, ElasticPair(1.0, 0.0))
                             * w)) * math.pi
        assert zz_displacement_at(0.0, y, xmin, dx, ymin, dy, w) == pytest.approx(dense,
                                                                                 rel=1e-12)
        assert zz_displacement_centred(y, dx, ymin, dy, w) == pytest.approx(dense, rel=1e-12)
    c = 1.5e-3
    for n in (1, 4, 5):
        ones = np.ones((n, n))
        assert zz_displacement_centred(0.0, 2 * c / n, -c, 2 * c / n, ones) == pytest.approx(
            8 * c * math.asinh(1.0), rel=1e-13)


def test_infcon_on_a_grid_is_its_pressure_anywhere():
    """The estimate re-meshed onto a grid in one pass (:meth:`pressure_on`) is the model's
    pressure at the grid's element centres (:meth:`pressure_at`), to the bit, also where
    the grid reaches beyond the virtual patch; and it carries the load asked for."""
    s = np.linspace(-0.02, 0.02, 801)
    f = np.where(s < 0, 4.0 * s**2, 2.5 * s**2 + 30.0 * s**3)
    a = 1.1 + 5.0 * s
    est = virtual_penetration("infcon", s, f, a, PAIR, load=6e4)
    assert est.force == pytest.approx(6e4, rel=1e-6)
    for grid in (Grid.from_bounds(-8e-3, 8e-3, -9e-3, 7e-3, 33, 41),
                 Grid.from_bounds(-2e-3, 5e-3, 1e-3, 3e-3, 10, 4)):
        assert np.array_equal(est.pressure_on(grid), est.pressure_at(*grid.mesh()))


def test_strips_on_contact_carry_the_force_of_a_hertz_patch():
    """The strips of a Hertz contact mask: one a grid row, from the first to the last
    element edge in contact; the pressure sampled on them is numpy's interpolation along
    the row, scaled to carry the normal force exactly; the equivalent ellipse is
    :func:`equivalent_ellipse` (within 3 % of Hertz's semi-axes)."""
    hz = hertz(1.0, 5.0, PAIR, load=7e4)
    g = Grid.from_bounds(-1.2 * hz.a, 1.2 * hz.a, -1.2 * hz.b, 1.2 * hz.b, 41, 37)
    p = hz.pressure(*g.mesh())
    contact = p > 0
    strips, pn, (a, b) = strips_on_contact(g, contact, p, hz.load, 40)
    plain = strips_from_contact(g, contact, 40)
    for name in ("y", "width", "x_lo", "x_hi", "t", "w"):
        assert np.array_equal(getattr(strips, name), getattr(plain, name))
    rows = np.flatnonzero(contact.any(axis=0))
    assert np.array_equal(strips.y, g.y[rows])
    sampled = np.stack([np.interp(strips.x[k], g.x, p[:, j]) for k, j in enumerate(rows)])
    assert np.array_equal(sample_on_strips(p, g, strips), sampled)
    assert float((pn * strips.area).sum()) == pytest.approx(hz.load, rel=1e-12)
    assert np.array_equal(pn, sampled * (hz.load / float((sampled * strips.area).sum())))
    assert (a, b) == equivalent_ellipse(g, contact)
    assert a == pytest.approx(hz.a, rel=0.03) and b == pytest.approx(hz.b, rel=0.03)


def test_infcon_factor_is_hertzs_lateral_factor():
    """chi = B_e b^2 / delta of Hertz's solution for the curvatures (A, B_e) (at a unit
    penetration, any material), to the bit: wider and narrower than long, and a circle."""
    from railcontact.normal.virtual import infcon_factor

    unit = ElasticPair(shear=1.0, poisson=0.0)
    for A, B in ((1.0, 2.0), (2.0, 1.0), (0.7, 0.7), (1.0, 1e3), (3e2, 1.0), (5.0, 5.0001)):
        h = hertz(A, B, unit, penetration=1.0)
        assert infcon_factor(A, B) == B * h.b**2 / h.penetration
    # independent of hertz() (which shares semi_axes with infcon_factor): a circle's
    # penetration is a^2 (A + B), so chi = A a^2 / (2 A a^2) = 1/2
    for A in (0.7, 5.0, 1e3):
        assert infcon_factor(A, A) == pytest.approx(0.5, rel=1e-14)


def test_compiled_strip_passes_refuse_fields_of_another_shape():
    """The compiled passes read their fields by the strips' and the grid's counts: a field
    of another shape is a clear error, not a read past its end."""
    from railcontact.errors import RailContactError
    from railcontact.tangential.fastrip import fastrip
    from railcontact.tangential.strips import Strips, remesh_strips, summarise

    hz = hertz(1.0, 5.0, PAIR, load=7e4)
    strips = Strips.ellipse(hz.a, hz.b, 12, 10)
    g = Grid.from_bounds(-1.2 * hz.a, 1.2 * hz.a, -1.2 * hz.b, 1.2 * hz.b, 16, 14)
    p = hz.pressure(*g.mesh())
    with pytest.raises(RailContactError, match="strip shape"):
        fastrip(strips, np.ones((10, 13)), 7e4, hz.a, hz.b, PAIR, 0.3, (1e-3, 0, 0))
    with pytest.raises(RailContactError, match="strip shape"):
        summarise(strips, np.zeros((2, 12, 10)), np.zeros((10, 12), np.int8), None, "", 0.0)
    with pytest.raises(RailContactError, match="grid's shape"):
        sample_on_strips(p[:, :-1], g, strips_from_contact(g, p > 0, 12))
    with pytest.raises(RailContactError, match="grid's shape"):
        strips_on_contact(g, (p > 0)[:-1], p, 7e4, 12)
    good = fastrip(strips, np.ones((10, 12)), 7e4, hz.a, hz.b, PAIR, 0.3, (1e-3, 0, 0))
    good = dataclasses.replace(good, traction=good.traction[:, :, :-1])
    with pytest.raises(RailContactError, match="strip shape"):
        remesh_strips(good, g)


def test_compiled_estimate_and_strip_passes_refuse_counts_they_would_read_past():
    """The estimate grid's counts, strips beyond the grid sampled, inconsistent strips and
    strips with nothing to re-mesh: clear errors (the compiled passes read unchecked, so
    these were a numba ValueError or TypingError, a silent read past the grid's last row,
    a read past the strips' arrays and a segmentation fault)."""
    from railcontact.errors import RailContactError
    from railcontact.tangential.fastsim import fastsim
    from railcontact.tangential.strips import StripResult, Strips, remesh_strips

    s = np.linspace(-0.01, 0.01, 41)
    for nx, ny in ((0, 5), (5, 0), (-3, 5), (5.5, 5), (True, 5)):
        with pytest.raises(RailContactError, match="positive integer"):
            virtual_penetration("kp", s, 5 * s**2, np.full_like(s, 2.0), PAIR,
                                penetration=1e-5, nx=nx, ny=ny)
    # an integral float count is the integer's grid (as Grid.from_bounds takes it)
    for method in ("kp", "infcon"):
        a = virtual_penetration(method, s, 5 * s**2, np.full_like(s, 2.0), PAIR,
                                penetration=1e-5, nx=5.0, ny=4)
        b = virtual_penetration(method, s, 5 * s**2, np.full_like(s, 2.0), PAIR,
                                penetration=1e-5, nx=5, ny=4)
        assert a.grid == b.grid and np.array_equal(a.pressure, b.pressure)

    g = Grid.from_bounds(-0.01, 0.01, -0.005, 0.005, 20, 9)
    p = np.ones(g.shape)
    beyond = Strips(y=np.array([0.0, 0.02]), width=np.full(2, 1e-3),
                    x_lo=np.full(2, -5e-3), x_hi=np.full(2, 5e-3), t=np.array([-0.5, 0.5]),
                    w=np.ones(2))
    with pytest.raises(RailContactError, match="beyond the grid"):
        sample_on_strips(p, g, beyond)
    uneven = Strips(y=np.array([0.0]), width=np.full(3, 1e-3), x_lo=np.full(3, -1e-3),
                    x_hi=np.full(3, 1e-3), t=np.array([-0.5, 0.5]), w=np.ones(2))
    with pytest.raises(RailContactError, match="one length"):
        fastsim(uneven, np.ones((3, 2)), 0.3, (1e-3, 0.0, 0.0), (1e-9, 1e-9, 1e-9))
    for ns, nt in ((0, 1), (1, 0)):
        empty = Strips(y=np.zeros(ns), width=np.ones(ns), x_lo=-np.ones(ns), x_hi=np.ones(ns),
                       t=np.zeros(nt), w=np.ones(nt))
        result = StripResult(strips=empty, traction=np.zeros((2, ns, nt)),
                             state=np.zeros((ns, nt), np.int8), pressure=np.zeros((ns, nt)),
                             force=(0.0, 0.0), spin_moment=0.0, slip_area_ratio=0.0,
                             max_traction=0.0, message="", wall_time=0.0)
        with pytest.raises(RailContactError, match="no strips"):
            remesh_strips(result, g)


def test_strip_sums_are_numpys_with_a_nan_traction():
    """The compiled sums of a strip result: the largest ``|p|`` is numpy's
    ``max(hypot(p_x, p_y), initial=0)``, NaN wherever the NaN sample is (it was lost when
    a finite sample followed it), and the forces numpy's sums."""
    from railcontact.tangential.strips import Strips, summarise

    strips = Strips.ellipse(6e-3, 4e-3, 4, 3)
    rng = np.random.default_rng(18)
    for where in (None, (0, 0, 0), (1, 1, 2), (0, 2, 3)):
        traction = rng.normal(size=(2, 3, 4)) * 1e8
        if where is not None:
            traction[where] = np.nan
        r = summarise(strips, traction, np.ones((3, 4), np.int8), np.ones((3, 4)), "", 0.0)
        want = float(np.hypot(*traction).max(initial=0.0))
        assert np.array_equal(r.max_traction, want, equal_nan=True), (where, r.max_traction)
        da = strips.area
        assert np.array_equal(r.force, (float((traction[0] * da).sum()),
                                        float((traction[1] * da).sum())), equal_nan=True)


def test_an_unconverged_load_secant_gives_its_last_evaluation_whole(monkeypatch):
    """When the load secant stops without meeting the load (its 30 steps), the estimate is
    its last evaluation: the penetration the pressure was formed for (it was the next
    step's, never evaluated)."""
    from railcontact.normal import virtual

    calls = []
    evaluate = virtual._evaluate

    off_by = 10 * virtual.SCALED_LOAD  # (more than the secant's stop accepts)

    def off(method, samples, a0, delta, *args):  # a force always off the model's
        out = list(evaluate(method, samples, a0, delta, *args))
        out[8] *= 1 + off_by if len(calls) % 2 else 1 - off_by
        calls.append((delta, out[8]))
        return tuple(out)

    monkeypatch.setattr(virtual, "_evaluate", off)
    s = np.linspace(-0.01, 0.01, 201)
    est = virtual_penetration("infcon", s, 5 * s**2, np.full_like(s, 2.0), PAIR, load=5e4)
    assert len(calls) == 31  # the first and 30 secant steps, none converged
    assert (est.penetration, est.force) == calls[-1], (est.penetration, calls[-1][0])


def test_compiled_elliptic_integrals_are_scipys():
    """K(m) and (K - E)/K by the arithmetic-geometric mean against scipy's integrals (an
    independent implementation), from a circle to a slender ellipse; the shape equation
    against hertz's (Carlson's integrals)."""
    from scipy.special import ellipe, ellipk

    from railcontact.halfspace.ellipse import elliptic_k_excess, shape_ratio
    from railcontact.halfspace.hertz import _shape_ratio

    assert elliptic_k_excess(0.0) == (math.pi / 2, 0.0)
    for m in (1e-14, 1e-8, 1e-3, 0.1, 0.5, 0.9, 0.999, 1 - 1e-8):
        k, excess = elliptic_k_excess(m)
        assert k == pytest.approx(ellipk(m), rel=1e-14)
        assert excess == pytest.approx((ellipk(m) - ellipe(m)) / ellipk(m), rel=1e-12)
        assert shape_ratio(m) == pytest.approx(_shape_ratio(m), rel=1e-12)


def test_compiled_lateral_factor_and_penetration_are_hertzs():
    """INFCON's factor chi = B b^2 / delta and Hertz's penetration under a load, compiled,
    against hertz() (scipy's integrals) over curvature ratios 1e-4 .. 1e4, both ways
    round; a circle's chi is 1/2; no value (NaN) for curvatures that are not positive."""
    from railcontact.halfspace.ellipse import hertz_penetration, lateral_factor, shape_table

    table = shape_table()
    unit = ElasticPair(shear=1.0, poisson=0.0)
    for A in (0.5, 2.2, 10.0):
        for B in A * np.geomspace(1e-4, 1e4, 97):
            h = hertz(A, B, unit, penetration=1.0)
            assert lateral_factor(A, B, *table) == pytest.approx(B * h.b**2, rel=1e-12)
            for load in (10.0, 8e4):
                d = hertz(A, B, PAIR, load=load).penetration
                assert hertz_penetration(A, B, PAIR.e_star, load, *table) == pytest.approx(
                    d, rel=1e-12)
    assert lateral_factor(3.0, 3.0, *table) == pytest.approx(0.5, rel=1e-14)
    for A, B in ((0.0, 1.0), (1.0, -1.0), (math.inf, 1.0), (math.nan, 1.0)):
        assert math.isnan(lateral_factor(A, B, *table))
        assert math.isnan(hertz_penetration(A, B, PAIR.e_star, 1e4, *table))


def test_equivalent_hertz_start_is_hertz_for_a_quadratic_gap():
    """INFCON's secant start: for f = B s^2 the rigid overlap's parabola is the gap itself
    (B_e = B), so one pass from any penetration gives Hertz's penetration under the load."""
    from railcontact.halfspace.ellipse import shape_table
    from railcontact.normal.virtual import _equivalent_hertz

    s = np.linspace(-0.02, 0.02, 4001)
    for A, B in ((1.0, 5.0), (5.0, 1.0), (2.0, 2.0)):
        hz = hertz(A, B, PAIR, load=6e4)
        d = _equivalent_hertz(s, B * s**2, A, PAIR.e_star, 6e4, 3 * hz.penetration, 1,
                              *shape_table())
        assert d == pytest.approx(hz.penetration, rel=1e-5)  # (w read off the samples)
