"""The Polonsky–Keer normal BEM against Hertz's analytic solution."""

import numpy as np
import pytest

from railcontact import ElasticPair, Grid, Material, RailContactError, hertz, solve_normal
from railcontact.halfspace.hertz import curvature_ratio
from railcontact.halfspace.operator import HAVE_PYFFTW, influence_operator

PAIR = ElasticPair.of(Material(206e9, 0.28))


def fitted_semi_axis(x: np.ndarray, p: np.ndarray) -> float:
    """Semi-axis from a centre line of a Hertz-like field: p^2 is linear in x^2 and
    vanishes at the patch edge, so the zero of the least-squares line is a^2."""
    c = p > 0
    slope, intercept = np.polyfit(x[c] ** 2, p[c] ** 2, 1)
    return float(np.sqrt(-intercept / slope))


def curvatures(ab: float) -> tuple[float, float]:
    """Curvatures (A, B) [1/m] whose Hertz ellipse has a/b = ab."""
    A = 1.0
    ratio = curvature_ratio(min(ab, 1 / ab))
    return A, A * ratio if ab >= 1 else A / ratio


def hertz_box(ab: float, nx: int, ny: int):
    """The Hertz problem of a/b = ``ab`` at 50 kN on an nx x ny grid over 1.15 times its
    ellipse: curvatures, Hertz solution, grid, element centres and undeformed gap [m]."""
    A, B = curvatures(ab)
    hz = hertz(A, B, PAIR, load=50e3)
    g = Grid.from_bounds(-1.15 * hz.a, 1.15 * hz.a, -1.15 * hz.b, 1.15 * hz.b, nx, ny)
    X, Y = g.mesh()
    return A, B, hz, g, X, Y, A * X**2 + B * Y**2


def solve_on_box(A, B, hz, n, **kw):
    g = Grid.from_bounds(-1.15 * hz.a, 1.15 * hz.a, -1.15 * hz.b, 1.15 * hz.b, n, n)
    X, Y = g.mesh()
    op = influence_operator(g, PAIR)
    return g, solve_normal(A * X**2 + B * Y**2, g, op, tolerance=1e-9, **kw)


def errors(g, res, hz):
    c = g.nx // 2  # odd grids: the centre lines x = 0 and y = 0 exist
    return {
        "force": abs(res.force / hz.load - 1),
        "max_pressure": abs(res.max_pressure / hz.max_pressure - 1),
        "a": abs(fitted_semi_axis(g.x, res.pressure[:, c]) / hz.a - 1),
        "b": abs(fitted_semi_axis(g.y, res.pressure[c, :]) / hz.b - 1),
        "area": abs(res.area / hz.area - 1),
    }


def assert_carried_and_hertz(res, h, op, g, hz):
    """The displacements the solver carried by updates (in its gap) equal a fresh product
    to round-off, and the solution is Hertz's to 1 %."""
    u = op.apply(res.pressure)
    carried = res.gap - h + res.penetration
    assert np.max(np.abs(carried - u)) < 1e-12 * np.max(np.abs(u))
    errs = errors(g, res, hz)
    for key in ("force", "max_pressure", "a", "b"):
        assert errs[key] < 0.01, (key, errs)


@pytest.mark.parametrize("ab", [0.2, 1.0, 5.0])
def test_bem_matches_hertz_and_converges(ab):
    """a/b = 1 is the sphere; 0.2 and 5 are slender ellipses across and along x."""
    A, B = curvatures(ab)
    hz = hertz(A, B, PAIR, load=50e3)
    assert hz.a / hz.b == pytest.approx(ab, rel=1e-9)
    errs = {}
    for n in (23, 45, 89):
        g, res = solve_on_box(A, B, hz, n, penetration=hz.penetration)
        assert res.converged and not res.touches_boundary
        errs[n] = errors(g, res, hz)
    # >= 40 elements across the patch (45 elements over 2.3 a): within 1 %
    assert 2 * hz.a / g.dx * 45 / 89 >= 39
    for key in ("force", "max_pressure", "a", "b"):
        assert errs[45][key] < 0.01, (key, errs[45])
    # the error falls under refinement
    for key in ("max_pressure", "a", "b", "area"):
        assert errs[89][key] < errs[45][key] < errs[23][key], (key, errs)
    assert errs[89]["force"] < errs[23]["force"]


def test_force_and_penetration_control_agree():
    A, B = 1.0, 5.0
    hz = hertz(A, B, PAIR, penetration=1e-4)
    g, by_pen = solve_on_box(A, B, hz, 45, penetration=1e-4)
    _, by_force = solve_on_box(A, B, hz, 45, load=by_pen.force)
    assert by_force.penetration == pytest.approx(1e-4, rel=1e-7)
    assert np.array_equal(by_force.contact, by_pen.contact)
    assert np.max(np.abs(by_force.pressure - by_pen.pressure)) < 1e-6 * by_pen.max_pressure


def test_contact_box_holds_the_hertz_ellipse():
    """The result's box of the contact elements: the bounds of the contact mask, about
    2a x 2b wide (Hertz); None without contact."""
    A, B = curvatures(2.0)
    hz = hertz(A, B, PAIR, load=50e3)
    g, res = solve_on_box(A, B, hz, 45, load=50e3)
    rows, cols = np.nonzero(res.contact)
    assert res.contact_box == (rows.min(), rows.max() + 1, cols.min(), cols.max() + 1)
    i0, i1, j0, j1 = res.contact_box
    assert abs((i1 - i0) * g.dx - 2 * hz.a) < 2 * g.dx
    assert abs((j1 - j0) * g.dy - 2 * hz.b) < 2 * g.dy
    none = solve_normal(np.full(g.shape, 1e-3), g, influence_operator(g, PAIR),
                        penetration=1e-6)
    assert none.contact_box is None and not none.contact.any()


def test_dissimilar_materials_use_combined_modulus():
    pair = ElasticPair.of(Material(210e9, 0.3), Material(110e9, 0.34))
    hz = hertz(2.0, 2.0, pair, load=1e4)
    g = Grid.from_bounds(-1.15 * hz.a, 1.15 * hz.a, -1.15 * hz.b, 1.15 * hz.b, 45, 45)
    X, Y = g.mesh()
    res = solve_normal(2.0 * (X**2 + Y**2), g, influence_operator(g, pair), load=1e4,
                       tolerance=1e-9)
    assert res.penetration == pytest.approx(hz.penetration, rel=5e-3)
    assert res.max_pressure == pytest.approx(hz.max_pressure, rel=5e-3)


@pytest.mark.parametrize("backend", ["scipy", "dense"] + (["pyfftw"] if HAVE_PYFFTW else []))
def test_backends_give_same_solution(backend):
    hz = hertz(1.0, 5.0, PAIR, penetration=1e-4)
    g = Grid.from_bounds(-1.2 * hz.a, 1.2 * hz.a, -1.2 * hz.b, 1.2 * hz.b, 12, 12)
    X, Y = g.mesh()
    h = X**2 + 5 * Y**2
    ref = solve_normal(h, g, influence_operator(g, PAIR, "z", "dense"), load=hz.load)
    res = solve_normal(h, g, influence_operator(g, PAIR, "z", backend), load=hz.load)
    assert res.iterations == ref.iterations
    assert np.allclose(res.pressure, ref.pressure, rtol=1e-9, atol=1e-6 * ref.max_pressure)


def test_hertz_estimate_cuts_iterations_on_paper_case():
    """Paper Sec. 4.1.1 (A = 1/m, B = 5/m, delta = 0.1 mm, eps_n = 1e-3): the paper reports
    13 -> 3 iterations with the INFCON estimate; Hertz is exact here."""
    A, B, d = 1.0, 5.0, 1e-4
    hz = hertz(A, B, PAIR, penetration=d)
    xl, yl = np.sqrt(d / A), np.sqrt(d / B)
    g = Grid.from_bounds(-xl, xl, -yl, yl, 64, 64)
    X, Y = g.mesh()
    h = A * X**2 + B * Y**2
    op = influence_operator(g, PAIR)
    cold = solve_normal(h, g, op, penetration=d, tolerance=1e-3)
    warm = solve_normal(h, g, op, penetration=d, tolerance=1e-3,
                        initial_pressure=hz.pressure(X, Y))
    print(f"iterations: none {cold.iterations}, hertz {warm.iterations}")
    assert cold.converged and warm.converged
    assert warm.iterations <= cold.iterations / 3
    assert warm.force == pytest.approx(cold.force, rel=2e-3)


@pytest.mark.parametrize("control", ["load", "penetration"])
def test_preconditioned_and_plain_cg_reach_the_same_hertz_solution(control):
    """The FFT preconditioner changes the path, not the solution: both solvers give Hertz's
    force, peak pressure and semi-axes within 1 % on 45 x 45 elements, and agree with each
    other to the tolerance."""
    A, B = curvatures(2.0)
    hz = hertz(A, B, PAIR, load=50e3)
    kw = {"load": hz.load} if control == "load" else {"penetration": hz.penetration}
    runs = {}
    for pre in ("fft", "none"):
        g, res = solve_on_box(A, B, hz, 45, preconditioner=pre, **kw)
        assert res.converged, res.message
        errs = errors(g, res, hz)
        for key in ("force", "max_pressure", "a", "b"):
            assert errs[key] < 0.01, (pre, key, errs)
        runs[pre] = res
    assert np.array_equal(runs["fft"].contact, runs["none"].contact)
    assert np.max(np.abs(runs["fft"].pressure - runs["none"].pressure)) < \
        1e-6 * hz.max_pressure
    assert runs["fft"].iterations < runs["none"].iterations


def test_fft_preconditioner_is_spd_and_conditions_the_influence_matrix():
    """M (the reciprocal spectrum of the circulant kernel) is symmetric positive definite and
    M A has a much smaller spread of eigenvalues than A: the half-space operator damps
    element-scale pressure modes (eigenvalues ~ 1/|k|), M amplifies them (~ |k|)."""
    g = Grid.from_bounds(-1e-3, 1e-3, -1.5e-3, 1.5e-3, 12, 16)
    op = influence_operator(g, PAIR, "z", "dense")
    A = op.dense()
    apply = op.preconditioner()
    M = np.column_stack([apply(e.reshape(g.shape)).ravel() for e in np.eye(g.size)])
    assert np.allclose(M, M.T, rtol=1e-9, atol=1e-9 * np.abs(M).max())
    assert np.linalg.eigvalsh(0.5 * (M + M.T)).min() > 0
    lam_a = np.linalg.eigvalsh(A)
    lam_ma = np.sort(np.linalg.eigvals(M @ A).real)  # similar to M^1/2 A M^1/2: real, > 0
    assert lam_ma.min() > 0
    cond_a, cond_ma = lam_a.max() / lam_a.min(), lam_ma.max() / lam_ma.min()
    print(f"condition number: A {cond_a:.1f}, M A {cond_ma:.2f}")
    assert cond_ma < 3.0 and cond_ma < cond_a / 5


def test_no_contact_and_zero_load():
    g = Grid.from_bounds(-1e-3, 1e-3, -1e-3, 1e-3, 8, 8)
    X, Y = g.mesh()
    h = 1.0 * X**2 + 1.0 * Y**2 + 1e-6
    op = influence_operator(g, PAIR)
    r = solve_normal(h, g, op, penetration=1e-7)
    assert r.force == 0.0 and r.converged and "no contact" in r.message
    r = solve_normal(h, g, op, load=0.0)
    assert r.force == 0.0 and not r.contact.any()


def test_too_small_area_is_flagged():
    hz = hertz(1.0, 1.0, PAIR, load=1e4)
    g = Grid.from_bounds(-0.5 * hz.a, 0.5 * hz.a, -0.5 * hz.a, 0.5 * hz.a, 16, 16)
    X, Y = g.mesh()
    r = solve_normal(X**2 + Y**2, g, influence_operator(g, PAIR), load=1e4)
    assert r.touches_boundary and "edge of the potential contact area" in r.message


def test_nonconvergence_is_reported():
    hz = hertz(1.0, 1.0, PAIR, load=1e4)
    g = Grid.from_bounds(-1.2 * hz.a, 1.2 * hz.a, -1.2 * hz.a, 1.2 * hz.a, 32, 32)
    X, Y = g.mesh()
    r = solve_normal(X**2 + Y**2, g, influence_operator(g, PAIR), load=1e4, max_iterations=2,
                     tolerance=1e-12)
    assert not r.converged and r.iterations == 2 and "not converged" in r.message
    assert np.all(np.isfinite(r.pressure))


def test_an_overflowing_solve_is_not_converged_and_shows_its_nan():
    """A penetration the arithmetic cannot carry (1e300 m: the pressures overflow) must not
    read "converged", and the result's NaN must show in every summary, never a 0."""
    g = Grid.from_bounds(-1e-3, 1e-3, -1e-3, 1e-3, 10, 10)
    X, Y = g.mesh()
    r = solve_normal((X**2 + Y**2) / 0.2, g, influence_operator(g, PAIR), penetration=1e300)
    assert not r.converged and "not converged" in r.message
    assert np.isnan(r.force) and np.isnan(r.max_pressure)


@pytest.mark.parametrize("kwargs, match", [
    (dict(load=-1.0), "load"),
    (dict(load=float("nan")), "load"),
    (dict(penetration=float("nan")), "penetration"),
    (dict(), "exactly one"),
    (dict(load=1.0, tolerance=0.0), "tolerance"),
    (dict(load=1.0, max_iterations=0), "max_iterations"),
    (dict(load=1.0, initial_pressure=np.zeros((3, 3))), "initial_pressure"),
    (dict(load=1.0, initial_pressure=np.full((8, 8), np.nan)), "NaN"),
    (dict(load=1.0, preconditioner="jacobi"), "preconditioner"),
])
def test_bad_input(kwargs, match):
    g = Grid.from_bounds(-1e-3, 1e-3, -1e-3, 1e-3, 8, 8)
    X, Y = g.mesh()
    with pytest.raises(RailContactError, match=match):
        solve_normal(X**2 + Y**2, g, influence_operator(g, PAIR), **kwargs)


def test_nan_gap_rejected():
    g = Grid.from_bounds(-1e-3, 1e-3, -1e-3, 1e-3, 8, 8)
    h = np.zeros((8, 8))
    h[2, 2] = np.nan
    with pytest.raises(RailContactError, match="gap"):
        solve_normal(h, g, influence_operator(g, PAIR), load=1.0)


@pytest.mark.parametrize("preconditioner", ["fft", "none"])
def test_a_start_on_two_symmetric_elements_still_reaches_hertz(preconditioner):
    """F04: force control started from the whole load on the two centre elements of a row
    (their gaps equal, so the CG step on that set is zero) used to stop at once, 'converged'
    with eps = 0 and the load on two elements. The elements that overlap outside the set
    must enter it: the result is the Hertz solution of the cold start."""
    A, B, hz, g, X, Y, h = hertz_box(1.0, 24, 23)
    op = influence_operator(g, PAIR)
    start = np.zeros(g.shape)
    start[11:13, 11] = 1e9  # symmetric about x = 0, on the centre line y = 0
    kw = dict(load=hz.load, tolerance=1e-9, preconditioner=preconditioner)
    res = solve_normal(h, g, op, initial_pressure=start, **kw)
    cold = solve_normal(h, g, op, **kw)
    assert res.converged and res.iterations > 1
    assert np.array_equal(res.contact, cold.contact)
    assert np.max(np.abs(res.pressure - cold.pressure)) < 1e-6 * cold.max_pressure
    assert res.max_pressure == pytest.approx(hz.max_pressure, rel=0.03)


def test_convergence_also_asks_that_nothing_overlaps_outside_the_contact():
    """The relative pressure change can be small far from the answer (F04); the CG also
    requires that no element outside the contact overlaps by more than the tolerance. The
    check sees the two-element start's overlap and passes the converged Hertz solution."""
    from railcontact.normal.bem import _overlaps

    A, B, hz, g, X, Y, h = hertz_box(1.0, 24, 23)
    op = influence_operator(g, PAIR)
    res = solve_normal(h, g, op, load=hz.load, tolerance=1e-6)
    assert not _overlaps(h, op.apply(res.pressure), res.pressure, True, 0.0, 1e-6)
    two = np.zeros(g.shape)
    two[11:13, 11] = hz.load / (2 * g.element_area)
    assert _overlaps(h, op.apply(two), two, True, 0.0, 1e-3)


def _counted_products(monkeypatch):
    """Count the convolutions of every influence operator (products and preconditioner)."""
    from railcontact.halfspace.operator import InfluenceOperator

    count = [0]
    convolve = InfluenceOperator._convolve
    bound = InfluenceOperator.bound

    def counted(self, *args, **kwargs):
        count[0] += 1
        return convolve(self, *args, **kwargs)

    def counted_bound(self, *args, **kwargs):  # a solve's products as bound functions
        product = bound(self, *args, **kwargs)
        # (a product through ``_convolve`` is counted there)
        via_convolve = getattr(getattr(product, "func", None), "__func__", None) is counted

        def counted_product(x, out):
            count[0] += not via_convolve
            return product(x, out)

        return counted_product

    monkeypatch.setattr(InfluenceOperator, "_convolve", counted)
    monkeypatch.setattr(InfluenceOperator, "bound", counted_bound)
    # the iterations run as Python, where every product is a call of a bound function
    # (the compiled run is the same loop: test_compiled_iterations_equal_the_python_run)
    monkeypatch.setattr(InfluenceOperator, "compiled_product", lambda self, floor=None: None)
    return count


@pytest.mark.parametrize("backend", ["dense"] + (["pyfftw"] if HAVE_PYFFTW else ["scipy"]))
def test_warm_start_updates_displacements_without_convolving(monkeypatch, backend):
    """A warm start (the Hertz pressure of a 5 % larger load, as a time step's extrapolated
    pressure): each CG step convolves only for the preconditioner and ``A t``; ``A p`` of
    the new pressure is ``A p - tau A t`` plus the influence columns of the elements that
    the step clipped or let in. The displacements the solver carries (in its gap) equal a
    fresh product to round-off, and the pressure is Hertz's and the dense reference's."""
    A, B, hz, g, X, Y, h = hertz_box(2.0, 45, 45)
    start = hertz(A, B, PAIR, load=1.05 * hz.load).pressure(X, Y)
    op = influence_operator(g, PAIR, "z", backend)
    ref = solve_normal(h, g, influence_operator(g, PAIR, "z", "dense"), load=hz.load,
                       tolerance=1e-9, initial_pressure=start)
    count = _counted_products(monkeypatch)
    res = solve_normal(h, g, op, load=hz.load, tolerance=1e-9, initial_pressure=start)
    assert res.converged, res.message
    if backend != "dense":  # (the dense product is no convolution)
        # the start's A p, then the preconditioner and A t per step, nothing else
        assert count[0] == 1 + 2 * res.iterations
    assert_carried_and_hertz(res, h, op, g, hz)
    assert np.array_equal(res.contact, ref.contact)
    assert np.max(np.abs(res.pressure - ref.pressure)) < 1e-6 * hz.max_pressure


def test_updated_displacements_do_not_drift_over_many_steps(monkeypatch):
    """Plain CG from a uniform start takes dozens of steps at eps_n = 1e-10; with the
    renewal at convergence switched off, the displacements updated step by step still
    equal a fresh product to round-off, and the solution is Hertz's."""
    import railcontact.normal.bem as bem

    monkeypatch.setattr(bem, "REFRESH_ITERATIONS", 10**9)
    A, B, hz, g, X, Y, h = hertz_box(1.0, 45, 45)
    op = influence_operator(g, PAIR)
    count = _counted_products(monkeypatch)
    res = solve_normal(h, g, op, penetration=hz.penetration, tolerance=1e-10,
                       preconditioner="none")
    assert res.converged and res.iterations >= 30, res.message
    updated = 2 * res.iterations + 1 - count[0]  # steps whose A p was not convolved
    assert updated >= 0.8 * res.iterations  # (penetration control: one start product more)
    assert_carried_and_hertz(res, h, op, g, hz)


def test_a_problem_scaled_beyond_the_cg_range_is_not_converged():
    """Scaling gap, load (and so pressure) by lambda scales the answer, but the CG's inner
    products are sums of squares: at 1e-170 they underflowed and the solve "converged" in
    one iteration with a tenth of Hertz's peak pressure; under penetration control at 1e150
    with a wrong force. Such a solve now says it is not converged (SCALE_RANGE); the
    unscaled one is Hertz's to the discretisation."""
    A, B, hz, g, X, Y, h = hertz_box(1.0, 32, 32)
    op = influence_operator(g, PAIR)
    ok = solve_normal(h, g, op, load=50e3, tolerance=1e-9)
    assert ok.converged and ok.max_pressure == pytest.approx(hz.max_pressure, rel=0.03)
    for lam, kw in ((1e-170, {"load": 50e3 * 1e-170}),
                    (1e150, {"penetration": hz.penetration * 1e150})):
        r = solve_normal(h * lam, g, op, tolerance=1e-9, **kw)
        assert not r.converged and "under- or overflow" in r.message


@pytest.mark.skipif(not HAVE_PYFFTW, reason="the compiled iterations need pyfftw's FFTW")
def test_compiled_iterations_equal_the_python_run(monkeypatch):
    """The solve as one compiled call (its checks and start, the kernels called through
    pointers, the products the packed plan's) and the same source run as Python between
    the same kernels give the same result to the bit: a warm wheel-rail patch (its
    start's displacement given), cold solves under penetration and load control, with and
    without the preconditioner, one that reaches its iteration limit, one that stalls, the
    history handed back in chunks; and the answers are Hertz's and the dense reference's."""
    import math

    import railcontact as rc
    import railcontact.contact.patch as patch
    import railcontact.normal.bem as bem
    from railcontact.halfspace.operator import InfluenceOperator
    from railcontact.normal.bem import Displacement

    if bem.packed_product[1] is None:
        pytest.skip("no FFTW C interface: the iterations run as Python only")
    d = {"material": {"young": 2 * 82e9 * 1.28, "poisson": 0.28},
         "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1", "side": "left",
                      "lateral_displacement": -4e-3},
         "grid": {"dx": 0.5e-3, "dy": 0.5e-3}, "normal": {"load": 83.3e3, "tolerance": 1e-5}}
    wr = rc.solve(d).patches[0].normal
    assert wr.contact_box[1] < 36
    # its first 36 rows (37 pad to 75, an odd count, which the packed plan cannot hold)
    wg = Grid(36, wr.grid.ny, wr.grid.dx, wr.grid.dy, wr.grid.x[0], wr.grid.y[0])
    pair = rc.Case.from_dict(d).pair
    wr_op = influence_operator(wg, pair, "z", "pyfftw")
    wr_h = (wr.gap - wr.displacement.values + wr.penetration)[:36]  # the undeformed gap
    warm = np.roll(1.02 * wr.pressure[:36], 1, axis=0)  # (a time step's extrapolated start)
    A, B, hz, g, X, Y, h = hertz_box(1.5, 40, 36)
    op = influence_operator(g, PAIR, "z", "pyfftw")
    assert op.compiled_product() is not None and wr_op.compiled_product() is not None
    # the normal solves of a wheelset's first two steps from cold starts (the step's
    # windows, its estimates as starts, their displacements given)
    steps = []
    monkeypatch.setattr(patch, "solve_normal",
                        lambda *a, **kw: steps.append((a, kw)) or solve_normal(*a, **kw))
    wc = rc.WheelsetContact(rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
                            rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
                            rc.ElasticPair.of(rc.STEEL, rc.STEEL),
                            rc.ContactSettings(friction=0.4, element_size=0.5e-3,
                                               warm_start="none"))
    for t in (0.0, 1e-3):
        w = 2 * math.pi * 1.5
        wc.solve(rc.Pose(3e-3 * math.sin(w * t)), loads=(83.3e3, 83.3e3),
                 kinematics=rc.Kinematics(30.0, 3e-3 * w * math.cos(w * t)), time=t)
    monkeypatch.undo()

    def solves():
        out = [solve_normal(wr_h, wg, wr_op, load=0.98 * 83.3e3, tolerance=1e-5,
                            initial_pressure=warm,
                            initial_displacement=Displacement(wr_op.apply(warm), 1))]
        out += [solve_normal(*a, **kw) for a, kw in steps]
        for pre in ("fft", "none"):
            out += [solve_normal(h, g, op, penetration=hz.penetration, tolerance=1e-9,
                                 preconditioner=pre),
                    solve_normal(h, g, op, load=hz.load, tolerance=1e-9, preconditioner=pre),
                    solve_normal(h, g, op, load=hz.load, tolerance=1e-9, max_iterations=7,
                                 preconditioner=pre)]
        monkeypatch.setattr(bem, "HISTORY_CHUNK", 3)
        out += [solve_normal(h, g, op, load=hz.load, tolerance=1e-30)]
        monkeypatch.setattr(bem, "HISTORY_CHUNK", 512)
        return out

    calls = [0]
    solve = bem._solve_compiled

    def counted(*args):
        calls[0] += 1
        return solve(*args)

    monkeypatch.setattr(bem, "_solve_compiled", counted)
    compiled = solves()
    assert calls[0] == len(compiled)  # (all compiled, one call each)
    assert len(steps) >= 6 and all(r.converged for r in compiled[1:len(steps) + 1])
    monkeypatch.setattr(InfluenceOperator, "compiled_product", lambda self, floor=None: None)
    python = solves()
    assert calls[0] == len(compiled)  # (none compiled)
    assert all(not r.converged and r.iterations == 7 for r in (compiled[-5], compiled[-2]))
    assert "stalled" in compiled[-1].message and compiled[-1].iterations > 100
    for a, b in zip(compiled, python, strict=True):
        assert a.message == b.message and a.iterations == b.iterations
        assert a.converged == b.converged and a.error == b.error
        assert a.force == b.force and a.penetration == b.penetration
        for f in ("pressure", "gap", "history"):
            np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
        np.testing.assert_array_equal(a.displacement.values, b.displacement.values)
        assert a.displacement.generations == b.displacement.generations
    ref = solve_normal(wr_h, wg, influence_operator(wg, pair, "z", "dense"),
                       load=0.98 * 83.3e3, tolerance=1e-9)
    assert compiled[0].converged and np.array_equal(compiled[0].contact, ref.contact)
    assert np.max(np.abs(compiled[0].pressure - ref.pressure)) < 1e-3 * ref.max_pressure
    for r in compiled[-7:-5] + compiled[-4:-2]:
        assert r.converged and r.max_pressure == pytest.approx(hz.max_pressure, rel=0.02)


@pytest.mark.skipif(not HAVE_PYFFTW, reason="the compiled solve needs pyfftw's FFTW")
def test_compiled_solve_equals_the_python_run_at_its_edges(monkeypatch):
    """The compiled solve and the same source run as Python agree to the bit where the
    start is not the plain one: a start with negative elements and its displacement given
    (their columns taken out), one without any pressure (the least gap's elements start),
    penetration below the least gap (no contact), a zero load; and the undefined-gap
    check: elements of an undefined gap beside the Hertz ellipse (x = +-a) are next to the
    contact, those two elements beyond it are not."""
    import railcontact.normal.bem as bem
    from railcontact.halfspace.operator import InfluenceOperator
    from railcontact.normal.bem import Displacement

    if bem.packed_product[1] is None:
        pytest.skip("no FFTW C interface: the solve runs as Python only")
    A, B, hz, g, X, Y, h = hertz_box(1.0, 24, 24)
    op = influence_operator(g, PAIR, "z", "pyfftw")
    rough = hz.pressure(X, Y) * (1.0 + 0.3 * np.cos(7 * X / hz.a)) - 0.1 * hz.max_pressure
    far = np.abs(X) > 1.02 * hz.a + g.dx  # at least one element beyond the ellipse
    near = np.abs(X) > hz.a - 0.5 * g.dx  # the first elements outside (and on) its edge
    cases = [dict(load=hz.load, initial_pressure=rough,
                  initial_displacement=Displacement(op.apply(rough), 2)),
             dict(load=hz.load, initial_pressure=-np.ones(g.shape)),
             dict(penetration=0.5 * float(h.min()) if h.min() > 0 else -0.0),
             dict(penetration=hz.penetration, initial_pressure=rough),
             dict(load=0.0)]

    def solves():
        out = [solve_normal(h, g, op, tolerance=1e-9, **kw) for kw in cases]
        for mark in (far, near):
            marked = np.where(mark & (np.abs(Y) < 0.3 * hz.b), 1.0, h)
            out.append(solve_normal(marked, g, op, load=hz.load, tolerance=1e-9,
                                    undefined_gap=0.5))
        return out

    compiled = solves()
    monkeypatch.setattr(InfluenceOperator, "compiled_product", lambda self, floor=None: None)
    python = solves()
    for a, b in zip(compiled, python, strict=True):
        assert a.message == b.message and a.iterations == b.iterations
        assert a.converged == b.converged and a.error == b.error
        assert a.force == b.force and a.penetration == b.penetration
        assert a.next_to_undefined == b.next_to_undefined
        for f in ("pressure", "gap", "contact", "history"):
            np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
    assert all(r.converged for r in compiled)
    for r in compiled[:2]:
        assert r.force == pytest.approx(hz.load, rel=1e-9)
        assert r.max_pressure == pytest.approx(hz.max_pressure, rel=0.03)
    assert compiled[2].area == 0.0 and "below the smallest gap" in compiled[2].message
    assert compiled[3].force == pytest.approx(hz.load, rel=0.03)
    assert compiled[4].force == 0.0 and "zero load" in compiled[4].message
    assert not compiled[5].next_to_undefined and compiled[6].next_to_undefined
    assert not any(r.next_to_undefined for r in compiled[:5])  # (none asked for)
