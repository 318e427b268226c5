"""Steady-rolling tangential contact against Kalker, Carter and CONTACT's reference output."""

import copy
import math

import numpy as np
import pytest

import railcontact as rc
from railcontact import ElasticPair, Grid, Material, hertz, solve_normal
from railcontact.halfspace.hertz import curvature_ratio
from railcontact.halfspace.operator import influence_operator
from railcontact.tangential import creep_coefficients, rolling_operator, solve_tangential
from railcontact.tangential.convexgs import HAVE_NUMBA
from railcontact.tangential.fastrip import fastrip_hertz
from railcontact.tangential.fastsim import fastsim_hertz, flexibilities
from railcontact.tangential.steadygs import solve_steadygs
from railcontact.tangential.strips import remesh_strips

STEEL = ElasticPair.of(Material(206e9, 0.28))
CONTACT_G = ElasticPair.from_shear(82e9, 0.28)


def hertz_patch(ab, n, pair=STEEL, load=1e5, margin=1.1):
    """BEM normal solution on an n x n grid around the Hertz ellipse with a/b = ab."""
    r = curvature_ratio(min(ab, 1 / ab))
    A, B = (1.0, r) if ab >= 1 else (r, 1.0)
    hz = hertz(A, B, pair, load=load)
    g = Grid.from_bounds(-margin * hz.a, margin * hz.a, -margin * hz.b, margin * hz.b, n, n)
    X, Y = g.mesh()
    nr = solve_normal(A * X**2 + B * Y**2, g, influence_operator(g, pair), load=load,
                      tolerance=1e-9)
    return hz, g, nr


@pytest.fixture(scope="module")
def sphere():
    return hertz_patch(1.0, 31)


@pytest.mark.parametrize("creepage, fx_sign, fy_sign, mz_sign", [
    ((1e-3, 0, 0), -1, 0, 0),
    ((-1e-3, 0, 0), 1, 0, 0),
    ((0, 1e-3, 0), 0, -1, 1),
    ((0, 0, 1.0), 0, -1, -1),
])
def test_kalker_sign_convention(sphere, creepage, fx_sign, fy_sign, mz_sign):
    """xi > 0 gives F_x < 0; eta > 0 gives F_y < 0 and M_z > 0 (F_y = -G c^2 C22 eta,
    M_z = G c^3 C23 eta); phi > 0 gives F_y < 0 and M_z < 0."""
    hz, g, nr = sphere
    r = solve_tangential(g, rolling_operator(g, STEEL), nr.pressure, 0.3, creepage,
                         tolerance=1e-4)
    small = 1e-6 * 0.3 * hz.load
    for value, sign in ((r.force[0], fx_sign), (r.force[1], fy_sign)):
        assert (abs(value) < small) if sign == 0 else (np.sign(value) == sign)
    if mz_sign:
        assert np.sign(r.spin_moment) == mz_sign


@pytest.mark.parametrize("creepage", [(0.05, 0, 0), (0, -0.05, 0), (0.03, 0.04, 0)])
def test_full_sliding(sphere, creepage):
    """|F| -> mu N, opposite to the rigid slip (xi, eta), all elements sliding."""
    hz, g, nr = sphere
    mu = 0.3
    r = solve_tangential(g, rolling_operator(g, STEEL), nr.pressure, mu, creepage,
                         tolerance=1e-6)
    f = np.array(r.force)
    assert np.linalg.norm(f) == pytest.approx(mu * nr.force, rel=5e-3)
    w = np.array(creepage[:2])
    assert np.dot(f, w) / (np.linalg.norm(f) * np.linalg.norm(w)) == pytest.approx(-1, abs=1e-6)
    assert r.slip_area_ratio == 1.0


@pytest.mark.parametrize("ab", [0.5, 1.0, 2.0])
def test_kalker_linear_theory(ab):
    """C11, C22, C23 from small creepages (1e-5) within 3 % of Kalker's table (nu = 0.28) on
    the fine grid, the error falling under refinement."""
    errors = {}
    for n in (21, 41):
        hz, g, nr = hertz_patch(ab, n)
        c = creep_coefficients(hz.a, hz.b, 0.28)
        cab, gm = math.sqrt(hz.a * hz.b), STEEL.shear
        op = rolling_operator(g, STEEL)
        fx, fy, fs = (solve_tangential(g, op, nr.pressure, 0.3, cr, tolerance=1e-7).force
                      for cr in ((1e-5, 0, 0), (0, 1e-5, 0), (0, 0, 1e-5 / cab)))
        c11 = -fx[0] / (gm * cab**2 * 1e-5)
        c22 = -fy[1] / (gm * cab**2 * 1e-5)
        c23 = -fs[1] / (gm * cab**3 * 1e-5 / cab)
        errors[n] = np.abs([c11 / c.c11 - 1, c22 / c.c22 - 1, c23 / c.c23 - 1])
    assert np.all(errors[41] < 0.03), errors
    assert np.all(errors[41] < errors[21]), errors


def test_carter_two_dimensional():
    """Carter's rolling cylinder (CONTACT carter2d: R = 500 mm, P' = 178.9 N/mm, mu = 0.3,
    xi = -2.4e-4): Q/(mu P) = 1 - (a'/a)^2 = 0.64 with a' = 0.6 a. A 200 mm wide single
    row of elements is the plane-strain strip (constant kernel offsets cancel in A - A')."""
    n, dx = 110, 0.02e-3
    g = Grid(n, 1, dx, 0.2, -(n - 1) / 2 * dx, 0.0)
    X, _ = g.mesh()
    nr = solve_normal(1.0 * X**2, g, influence_operator(g, CONTACT_G), load=35780.0,
                      tolerance=1e-10)
    assert nr.contact.sum() * dx / 2 == pytest.approx(1.0e-3, rel=0.01)  # a = 1 mm
    r = solve_tangential(g, rolling_operator(g, CONTACT_G), nr.pressure, 0.3,
                         (-2.4e-4, 0, 0), tolerance=1e-8)
    assert r.force[0] / (0.3 * 35780.0) == pytest.approx(0.64, rel=0.005)
    adhesion = g.x[r.state[:, 0] == 1]
    assert adhesion.max() - adhesion.min() + dx == pytest.approx(1.2e-3, rel=0.02)
    assert adhesion.max() > 0.95e-3  # adhesion at the leading edge (rolling in +x)


def contact_fastsim_case():
    """CONTACT examples/fastsim.inp, case 1: a = 8 mm, b = 4 mm, N = 82 kN, G = 82 GPa,
    nu = 0.28, mu = 0.3, eta = -6.25e-4, phi = 6.25e-4 /mm, 44 x 44 elements of
    0.4 x 0.2 mm (40 x 40 in the patch)."""
    A, B, N = 0.84642, 2.40616, 82e3
    g = Grid(44, 44, 0.4e-3, 0.2e-3, -21.5 * 0.4e-3, -21.5 * 0.2e-3)
    X, Y = g.mesh()
    nr = solve_normal(A * X**2 + B * Y**2, g, influence_operator(g, CONTACT_G), load=N,
                      tolerance=1e-8)
    return g, nr


def test_contact_fastsim_example_bem():
    g, nr = contact_fastsim_case()
    assert nr.max_pressure == pytest.approx(1223e6, rel=2e-3)
    r = solve_tangential(g, rolling_operator(g, CONTACT_G), nr.pressure, 0.3,
                         (0.0, -6.25e-4, 0.625), tolerance=1e-5)
    assert r.converged
    assert r.force[1] / (0.3 * 82e3) == pytest.approx(-0.6074, rel=0.02)
    assert r.spin_moment == pytest.approx(-4.821e4 * 1e-3, rel=0.03)  # N mm -> N m


def test_contact_fastsim_example_fastsim():
    r = fastsim_hertz(8e-3, 4e-3, 82e3, CONTACT_G, 0.3, (0.0, -6.25e-4, 0.625),
                      nx=40, ny=40, bound="elliptic")
    assert r.force[1] / (0.3 * 82e3) == pytest.approx(-0.6016, rel=0.02)
    assert r.max_traction <= 0.3 * r.pressure.max() * (1 + 1e-12)


def test_fastsim_flexibilities():
    """CONTACT's simpflex, a = 8, b = 4 mm, G = 82 GPa (unblended): mm^3/N -> m/Pa."""
    l1, l2, l3 = flexibilities(8e-3, 4e-3, CONTACT_G)
    assert (l1, l2, l3) == pytest.approx((4.9996e-14, 5.2331e-14, 4.0790e-14), rel=1e-4)


@pytest.mark.parametrize("creepage, block", [((1e-9, 0, 0), "c11"), ((0, 1e-9, 0), "c22")])
def test_fastsim_linear_limit_is_kalker(creepage, block):
    """L1, L2 are built to give Kalker's linear theory; with Gauss–Legendre strips the
    quadrature is exact, so the agreement is to round-off."""
    a, b, n = 6.304e-3, 12.61e-3, 106.7e3
    r = fastsim_hertz(a, b, n, CONTACT_G, 0.33, creepage, quadrature="gauss")
    c = creep_coefficients(a, b, 0.28)
    lin = -CONTACT_G.shear * a * b * getattr(c, block) * max(creepage)
    force = r.force[0] if block == "c11" else r.force[1]
    assert force == pytest.approx(lin, rel=1e-12)
    assert r.slip_area_ratio == 0.0


def test_fastsim_linear_limit_spin():
    """Spin: F_y = -G (ab)^(3/2) C23 phi; exact in x, the y-integral of (1-t^2)^(3/2) by
    Gauss–Legendre leaves 2e-8."""
    a, b = 8e-3, 4e-3
    r = fastsim_hertz(a, b, 82e3, CONTACT_G, 0.3, (0, 0, 1e-6), quadrature="gauss")
    c = creep_coefficients(a, b, 0.28)
    assert r.force[1] == pytest.approx(-CONTACT_G.shear * (a * b) ** 1.5 * c.c23 * 1e-6,
                                       rel=1e-7)


def test_fastrip_pure_creepage_is_carter_on_every_strip():
    """For pure xi FaStrip's adhesion zone on each strip is Carter's: its share of the strip
    is the same on every strip that is not fully sliding."""
    r = fastrip_hertz(6.304e-3, 12.61e-3, 106.7e3, CONTACT_G, 0.33, (5e-4, 0, 0))
    assert r.force[0] < 0 and abs(r.force[1]) < 1e-9 * abs(r.force[0])
    assert np.all(np.hypot(*r.traction) <= 0.33 * r.pressure * (1 + 1e-9))
    # the slip zone length 2d is the same on all strips (d independent of y for pure xi)
    x = r.strips.x
    slip_len = [(x[j][r.state[j] == 2].max() - r.strips.x_lo[j]) for j in range(len(x))
                if (r.state[j] == 1).any()]
    assert np.ptp(slip_len) < 2.5 * np.max(np.diff(x, axis=1))


@pytest.mark.parametrize("ab", [1.0, 0.346, 2.89])
def test_fastrip_linear_limit_is_kalkers(ab):
    """FaStrip's scaled creepages make strip theory reproduce Kalker's linear theory:
    at a small creepage F_x = -G a b C11 xi and F_y = -G a b C22 eta (Kalker's table,
    interpolated in a/b). On the default 40 x 40 strips the samples carry the strips'
    exact integrals (the midpoint rule in y leaves about 0.1 %); values at the cells'
    midpoints miss the adhesion traction's peak next to the slip zone, 6 % low."""
    a, b = 6e-3 * math.sqrt(ab), 6e-3 / math.sqrt(ab)
    c = creep_coefficients(a, b, STEEL.poisson)
    g_ab = STEEL.shear * a * b
    for creepage, force, coefficient in (((1e-6, 0, 0), 0, c.c11), ((0, 1e-6, 0), 1, c.c22)):
        r = fastrip_hertz(a, b, 1e4, STEEL, 0.4, creepage)
        assert -r.force[force] / (g_ab * 1e-6) == pytest.approx(coefficient, rel=3e-3)
        assert abs(r.force[1 - force]) < 1e-9 * abs(r.force[force])


def test_fastrip_pure_creepage_force_is_the_strips_integral():
    """For pure xi every strip of the Hertz ellipse is Carter's, with the same slip zone
    length 2d (``d = a |xi'| / (1 - nu)``): its force is ``mu p0 pi / (2a) (a_y^2 -
    (a_y - d)^2)``, ``mu p0 pi a_y^2 / (2a)`` when it slides. Their integral across the
    patch (scipy's quad) is FaStrip's continuum force; the 40 x 40 samples carry it within
    1 % from the linear range to full slip (Polach's Eurosprinter patch, CONTACT's
    tractcurv example), 200 x 200 within 0.1 %."""
    from scipy.integrate import quad

    a, b, load, mu = 6.304e-3, 12.61e-3, 106.7e3, 0.33
    c = creep_coefficients(a, b, CONTACT_G.poisson)
    nu, g = CONTACT_G.poisson, CONTACT_G.shear
    p0 = 3 * load / (2 * math.pi * a * b)
    for xi in (1e-5, 1e-4, 3e-4, 1e-3, 3e-3):
        d = a / (1 - nu) * g * 4 * (1 - nu) * c.c11 * xi / (2 * mu * p0 * math.pi**2)

        def strip(y, d=d):
            ay = a * math.sqrt(max(1 - (y / b) ** 2, 0.0))
            return ay * ay - (ay - d) ** 2 if d < ay else ay * ay

        kink = b * math.sqrt(max(0.0, 1 - (d / a) ** 2))
        exact = -mu * p0 * math.pi / (2 * a) * quad(strip, -b, b, points=[-kink, kink],
                                                     limit=200)[0]
        coarse = fastrip_hertz(a, b, load, CONTACT_G, mu, (xi, 0, 0))
        fine = fastrip_hertz(a, b, load, CONTACT_G, mu, (xi, 0, 0), nx=200, ny=200)
        assert coarse.force[0] == pytest.approx(exact, rel=1e-2), xi
        assert fine.force[0] == pytest.approx(exact, rel=1e-3), xi
        assert np.all(np.hypot(*coarse.traction) <= mu * coarse.pressure * (1 + 1e-9))


def test_estimates_cut_iterations(root):
    """Paper Sec. 4.2.1 (hertz_paper_rolling.toml): the paper reports 31 -> 10 sweeps with
    FaStrip. The estimates must leave the converged forces unchanged (within eps_tau)."""
    case = rc.load_case(root / "models" / "cases" / "hertz_paper_rolling.toml").to_dict()
    out = {}
    for est in ("none", "fastsim", "fastrip"):
        c = copy.deepcopy(case)
        c["tangential"]["estimate"] = est
        out[est] = rc.solve(c).patches[0].tangential
    print({k: v.iterations for k, v in out.items()})
    assert all(v.converged for v in out.values())
    assert out["fastrip"].iterations < out["none"].iterations
    for est in ("fastsim", "fastrip"):
        assert out[est].force[0] == pytest.approx(out["none"].force[0], rel=1e-2)


def test_remesh_keeps_force():
    r = fastrip_hertz(7.9e-3, 2.7e-3, 74e3, STEEL, 0.4, (1e-3, 0, 0), nx=40, ny=40)
    g = Grid.from_bounds(-10e-3, 10e-3, -4.5e-3, 4.5e-3, 64, 64)
    p, st = remesh_strips(r, g)
    assert p[0].sum() * g.element_area == pytest.approx(r.force[0], rel=0.02)
    assert set(np.unique(st)) <= {0, 1, 2}


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
def test_numba_and_numpy_sweeps_agree(sphere):
    hz, g, nr = sphere
    op = rolling_operator(g, STEEL)
    a = solve_tangential(g, op, nr.pressure, 0.3, (2e-4, -1e-4, 0.5), engine="numba",
                         tolerance=1e-6)
    b = solve_tangential(g, op, nr.pressure, 0.3, (2e-4, -1e-4, 0.5), engine="numpy",
                         tolerance=1e-6)
    assert a.iterations == b.iterations
    assert np.allclose(a.traction, b.traction, rtol=0, atol=1e-9 * a.max_traction)


def test_bad_tangential_input(sphere):
    hz, g, nr = sphere
    op = rolling_operator(g, STEEL)
    with pytest.raises(rc.RailContactError, match="friction"):
        solve_tangential(g, op, nr.pressure, -0.1, (0, 0, 0))
    with pytest.raises(rc.RailContactError, match="xi"):
        solve_tangential(g, op, nr.pressure, 0.3, (float("nan"), 0, 0))
    with pytest.raises(rc.RailContactError, match="pressure"):
        solve_tangential(g, op, -nr.pressure, 0.3, (0, 0, 0))
    with pytest.raises(rc.RailContactError, match="dissimilar"):
        rolling_operator(g, ElasticPair.of(Material(210e9, 0.3), Material(70e9, 0.33)))


@pytest.mark.parametrize("solver", ["steadygs", "convexgs"])
def test_zero_creepage_is_zero_traction_at_once(solver):
    """Creepages set back to exactly zero after non-zero ones: with no creepage the steady
    state carries no traction, and both solvers return it with no sweep, whatever the start
    (iterating from the non-zero ones' traction would cost ConvexGS 213 sweeps for that
    zero answer); a time step too."""
    from railcontact.tangential import SOLVERS

    hz, g, nr = hertz_patch(1.0, 21)
    op = rolling_operator(g, STEEL)
    warm = SOLVERS[solver](g, op, nr.pressure, 0.3, (1e-3, 0.0, 0.0), tolerance=1e-6)
    r = SOLVERS[solver](g, op, nr.pressure, 0.3, (0.0, 0.0, 0.0), tolerance=1e-6,
                        initial_traction=warm.traction, initial_state=warm.state)
    assert r.converged and r.iterations == 0 and r.force == (0.0, 0.0)
    assert not r.traction.any() and r.spin_moment == 0.0
    wc = rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), 0.025),
                            rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                            rc.ElasticPair.of(rc.STEEL, rc.STEEL),
                            rc.ContactSettings(friction=0.4, tangential_solver=solver))
    wc.solve(rc.Pose(1e-3), loads=(8e4, 8e4), creepages=((1e-3, 1e-3, 0.1),) * 2)
    z = wc.solve(rc.Pose(1e-3), loads=(8e4, 8e4), creepages=((0.0, 0.0, 0.0),) * 2)
    assert all(w.tangential_iterations == 0 and w.creep_force == (0.0, 0.0) for w in z.wheels)


def test_a_start_is_clipped_onto_the_traction_bound(sphere):
    """The start of the sweeps: inside the bound ``mu p_n`` unchanged, beyond it (or in
    slip) scaled onto it along its direction, zero outside the contact."""
    from railcontact.tangential.convexgs import SLIP, SweepProblem

    hz, g, nr = sphere
    mu = 0.3
    rng = np.random.default_rng(7)
    bound = mu * nr.pressure
    start = rng.normal(size=(2, *g.shape)) * 0.7 * bound.max()
    state = rng.integers(1, 3, g.shape).astype(np.int8)
    prob = SweepProblem.set_up(g, rolling_operator(g, STEEL), nr.pressure, mu,
                               (1e-3, 0.0, 0.0), start, state, 1e-3, 10, 0.5, 0.5, "auto",
                               1 / 6)
    p = prob.p.transpose(0, 2, 1)  # (2, nx, ny)
    size = np.hypot(*start)
    inside = (size <= bound) & (state != SLIP) & (bound > 0)
    assert inside.sum() > 50 and (~inside & (bound > 0)).sum() > 50
    assert np.array_equal(p[:, inside], start[:, inside])
    onto = (bound > 0) & ~inside
    assert np.allclose(np.hypot(*p)[onto], bound[onto], rtol=1e-14, atol=0)
    assert np.allclose((p * size)[:, onto], (start * np.hypot(*p))[:, onto], rtol=1e-12)
    assert not p[:, bound == 0].any()


def test_element_turns_and_angles_are_the_library_ones():
    """The slip element's trigonometry without library calls (series below SMALL_TURN):
    the turned unit vector and the angle between two directions equal cos, sin and atan2
    to round-off, on both sides of the series' bound."""
    from railcontact.tangential.convexgs import SMALL_TURN, _angle_c, _turn_c

    for t in (0.0, 1e-9, -3e-4, 0.02, -0.049, SMALL_TURN * (1 - 1e-12), SMALL_TURN,
              -0.3, 2.0, -3.1):
        a = 0.7
        c, s = _turn_c(math.cos(a), math.sin(a), t)
        assert abs(c - math.cos(a + t)) < 4e-16 and abs(s - math.sin(a + t)) < 4e-16
        assert abs(_angle_c(math.cos(t), math.sin(t)) - t) < 4e-16 * max(1.0, abs(t))
    assert _angle_c(-1.0, 0.0) == _angle_c(-1.0, -0.0) == -math.pi  # as (d + pi) % 2pi - pi


def test_slip_element_is_on_the_bound_against_its_slip():
    """A slip element (no relaxation, from zero traction): |p| = g and the slip
    S0 + C p anti-parallel to p (Coulomb's law), for anisotropic 2x2 coefficients."""
    from railcontact.tangential.convexgs import SLIP, _element_solve_c

    rng = np.random.default_rng(3)
    slips = 0
    for _ in range(200):
        a = rng.uniform(0.5, 2.0)
        b = rng.uniform(-0.3, 0.3)
        c11, c12, c21, c22 = 1e-11 * a, 1e-11 * b, 1e-11 * b, 1e-11 * rng.uniform(0.5, 2.0)
        g = rng.uniform(1e6, 1e9)
        s0 = rng.normal(size=2) * g * 1e-11 * rng.uniform(2.0, 50.0)  # beyond adhesion
        px, py, st = _element_solve_c(0.0, 0.0, s0[0], s0[1], g, c11, c12, c21, c22,
                                      1.0, 1.0)
        if st != SLIP:
            continue
        slips += 1
        sx = s0[0] + c11 * px + c12 * py
        sy = s0[1] + c21 * px + c22 * py
        assert math.hypot(px, py) == pytest.approx(g, rel=1e-14)
        assert abs(px * sy - py * sx) <= 1e-12 * g * math.hypot(sx, sy)  # parallel
        assert px * sx + py * sy < 0.0  # opposed
    assert slips > 150


@pytest.mark.parametrize("scale", [1e-170, 1e-300, 1e160])
def test_element_keeps_the_bound_whose_square_under_or_overflows(scale):
    """The element solve is homogeneous: the shift and the bound scaled by one factor
    scale its traction so, also where ``g**2`` under- or overflows (a traction ten times
    the bound stays in slip, on the bound; half of it stays in adhesion)."""
    from railcontact.tangential.convexgs import ADHESION, SLIP, _element_solve, _element_solve_c

    c = 1e-11
    for solve in (_element_solve_c, _element_solve):
        for k, want in ((10.0, SLIP), (0.5, ADHESION)):
            one = solve(0.0, 0.0, -k * c, 0.3 * k * c, 1.0, c, 0.0, 0.0, c, 1.0, 1.0)
            px, py, st = solve(0.0, 0.0, -k * c * scale, 0.3 * k * c * scale, scale, c,
                               0.0, 0.0, c, 1.0, 1.0)
            assert st == one[2] == want
            assert math.hypot(px, py) <= scale * (1 + 1e-15)
            rel = 1e-6 if scale < 1e-290 else 1e-14  # (1e-300 Pa: subnormal tractions)
            assert px == pytest.approx(one[0] * scale, rel=rel)
            assert py == pytest.approx(one[1] * scale, rel=rel)


def test_sweep_problem_rigid_slip_is_rigid_slip_lines(sphere):
    """The set-up's compiled rigid slip (sweep layout (ny, nx)) is
    :func:`~railcontact.tangential.rolling.rigid_slip_lines`' to the bit: ``W_x`` by rows
    of y, ``W_y`` by columns of x (the spin offset included)."""
    from railcontact.tangential.convexgs import SweepProblem
    from railcontact.tangential.rolling import rigid_slip_lines

    hz, g, nr = sphere
    creepage = (1.3e-3, -7e-4, 0.9)
    prob = SweepProblem.set_up(g, rolling_operator(g, STEEL), nr.pressure, 0.3, creepage,
                               None, None, 1e-3, 10, 0.5, 0.5, "auto", 0.37)
    lx, ly = rigid_slip_lines(g, creepage, 0.37)
    assert np.array_equal(prob.wx, np.broadcast_to(lx[:, None], prob.wx.shape))
    assert np.array_equal(prob.wy, np.broadcast_to(ly[None, :], prob.wy.shape))


def test_slip_element_relaxation_turns_by_a_share_of_the_angle():
    """The relaxation of a slip element (CONTACT's ``a_I + omega_s (a - a_I)``, the angle
    difference wrapped to [-pi, pi)): the traction's angle against atan2's of the old and
    the unrelaxed new tractions, on the bound, for turns small and large."""
    from railcontact.tangential.convexgs import SLIP, _element_solve_c

    rng = np.random.default_rng(11)
    c = 1e-11
    seen = 0
    for _ in range(300):
        g = rng.uniform(1e6, 1e9)
        s0 = rng.normal(size=2) * g * c * rng.uniform(2.0, 50.0)
        new = _element_solve_c(0.0, 0.0, s0[0], s0[1], g, c, 0.0, 0.0, c, 1.0, 1.0)
        a_new = math.atan2(new[1], new[0])
        a_old = a_new + rng.choice([rng.uniform(-0.04, 0.04), rng.uniform(-3.1, 3.1)])
        old = g * math.cos(a_old), g * math.sin(a_old)
        px, py, st = _element_solve_c(*old, s0[0], s0[1], g, c, 0.0, 0.0, c, 1.0, 0.5)
        if new[2] != SLIP or st != SLIP:
            continue
        seen += 1
        d = (a_new - a_old + math.pi) % (2 * math.pi) - math.pi
        want = a_old + 0.5 * d
        assert math.hypot(px, py) == pytest.approx(g, rel=1e-14)
        assert abs(math.remainder(math.atan2(py, px) - want, 2 * math.pi)) < 1e-14
    assert seen > 200


@pytest.mark.parametrize("solver", [solve_tangential, solve_steadygs])
def test_the_convergence_measure_holds_at_any_traction_scale(sphere, solver):
    """The problem is homogeneous: pressure and creepages times lambda give the traction
    times lambda. Its convergence measure (squared sums of the tractions) is scaled by a
    power of two beyond MEASURED_RANGE: at lambda = 1e-170 every square underflowed to 0
    and ConvexGS said "converged" after one sweep with 59 % of the force; at 1e150 the
    squares overflowed (not converged, NaN measure)."""
    hz, g, nr = sphere
    op = rolling_operator(g, STEEL)
    creep = (1e-3, 0.5e-3, 0.0)
    ref = solver(g, op, nr.pressure, 0.3, creep, tolerance=1e-8)
    assert ref.converged and ref.iterations > 5
    for lam in (1e-170, 1e150):
        r = solver(g, op, nr.pressure * lam, 0.3, tuple(c * lam for c in creep),
                   tolerance=1e-8)
        assert r.converged and abs(r.iterations - ref.iterations) <= 1
        np.testing.assert_allclose(np.asarray(r.force) / lam, ref.force, rtol=1e-10)


@pytest.mark.parametrize("model,solver", [("bem", "steadygs"), ("bem", "convexgs"),
                                          ("fastsim", "steadygs")])
@pytest.mark.parametrize("mu", [0.0, 5e-324, 1e-310])
def test_no_friction_slides_the_whole_contact(root, model, solver, mu):
    """mu = 0 (a case file allows it): zero traction, and every loaded element slides -
    not "no contact: zero normal pressure" with a slip area of 0 beside a normal force of
    tens of kN (the solvers' bound mu p is zero everywhere, so they see no contact; FASTSIM
    tells the contact by that bound too). The same for a mu so small that its bounds mu p
    are subnormal numbers (Coulomb's |F| <= mu N: below 1e-300 N), which gave NaN
    tractions ("not finite") or a crash (an OverflowError in ConvexGS's measure)."""
    case = rc.load_case(root / "models/cases/hertz_paper_rolling.toml").to_dict()
    case["tangential"].update(friction=mu, solver=solver, model=model)
    case["grid"].update(nx=24, ny=24)
    ps = rc.solve(case).patches[0]
    t, n = ps.tangential, ps.normal
    assert n.force > 1e4 and t.force == (0.0, 0.0) and t.spin_moment == 0.0
    assert t.slip_area_ratio == 1.0 and "no friction" in t.message and t.converged
    if model == "bem":
        np.testing.assert_array_equal(t.state == 2, n.pressure > 0)
    else:  # (FASTSIM's strips on the Hertz ellipse: every sample slides)
        assert (t.state == 2).sum() > 100 and not (t.state == 1).any()


@pytest.mark.parametrize("solver", ["steadygs", "convexgs"])
def test_tiny_friction_above_the_negligible_bound_saturates(root, solver):
    """mu = 1e-290 (bounds mu p about 1e-281 Pa, normal numbers): solved, and at creepage
    1e-3 the whole contact slides with Coulomb's force F_x = -mu N (Carter: saturation
    once xi exceeds 3 mu a / R-like thresholds, here mu ~ 0)."""
    case = rc.load_case(root / "models/cases/hertz_paper_rolling.toml").to_dict()
    case["tangential"].update(friction=1e-290, solver=solver)
    case["grid"].update(nx=24, ny=24)
    ps = rc.solve(case).patches[0]
    t, n = ps.tangential, ps.normal
    assert t.converged and t.slip_area_ratio == 1.0 and "no friction" not in t.message
    assert t.force[0] == pytest.approx(-1e-290 * n.force, rel=1e-9)
    assert abs(t.force[1]) <= 1e-9 * 1e-290 * n.force


def test_measure_of_a_subnormal_bound_is_a_finite_power_of_two():
    """ConvexGS's and SteadyGS's convergence measure for a largest bound below 2**-1022
    (friction near 1e-320 on the low-level solvers): a finite power of two, not an
    OverflowError."""
    from railcontact.tangential.convexgs import _measure

    for bound in (5e-324, 1e-315, 2.0**-1000):
        m = _measure(bound)
        assert math.isfinite(m) and math.frexp(m)[0] == 0.5
        assert 2.0**-80 < bound * m < 1.0
