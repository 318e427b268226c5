"""SteadyGS against Carter, Hertz/Kalker, CONTACT's reference output and ConvexGS."""

import dataclasses
import math

import numpy as np
import pytest
from test_tangential import CONTACT_G, STEEL, hertz_patch  # the Hertz patches of ConvexGS

import railcontact as rc
from railcontact import Grid, solve_normal
from railcontact.halfspace.operator import influence_operator
from railcontact.settings import Case
from railcontact.tangential import creep_coefficients, rolling_operator, solve_tangential
from railcontact.tangential.convexgs import HAVE_NUMBA
from railcontact.tangential.steadygs import solve_steadygs


def rel_l2(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


@pytest.fixture(scope="module")
def sphere():
    return hertz_patch(1.0, 31)


@pytest.fixture(scope="module")
def wheel_rail_patch():
    """The normal solution of a left S1002 wheel on 60E1 rail (tread contact, 4 mm off
    centre away from the flange), its elastic pair and creepages."""
    d = {"material": {"young": 2 * 82e9 * 1.28, "poisson": 0.28},
         "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1", "side": "left",
                      "lateral_displacement": -4e-3},
         "grid": {"dx": 0.5e-3, "dy": 0.5e-3},
         "normal": {"load": 83.3e3, "tolerance": 1e-5},
         "tangential": {"friction": 0.4, "creepage": [2e-4, 2e-4, 0.5], "tolerance": 1e-5}}
    nr = rc.solve(d).patches[0].normal
    return nr, Case.from_dict(d).pair, (2e-4, 2e-4, 0.5)


def test_carter_two_dimensional():
    """Carter's rolling cylinder (as CONTACT's carter2d, see test_tangential): Q/(mu P) =
    0.64, adhesion 1.2 mm at the leading edge; the traction is ConvexGS's."""
    n, dx = 110, 0.02e-3
    g = Grid(n, 1, dx, 0.2, -(n - 1) / 2 * dx, 0.0)
    X, _ = g.mesh()
    nr = solve_normal(1.0 * X**2, g, influence_operator(g, CONTACT_G), load=35780.0,
                      tolerance=1e-10)
    op = rolling_operator(g, CONTACT_G)
    r = solve_steadygs(g, op, nr.pressure, 0.3, (-2.4e-4, 0, 0), tolerance=1e-8)
    assert r.converged, r.message
    assert r.force[0] / (0.3 * 35780.0) == pytest.approx(0.64, rel=0.005)
    adhesion = g.x[r.state[:, 0] == 1]
    assert adhesion.max() - adhesion.min() + dx == pytest.approx(1.2e-3, rel=0.02)
    assert adhesion.max() > 0.95e-3  # adhesion at the leading edge (rolling in +x)
    s = solve_steadygs(g, op, nr.pressure, 0.3, (-2.4e-4, 0, 0), tolerance=1e-6)
    c = solve_tangential(g, op, nr.pressure, 0.3, (-2.4e-4, 0, 0), tolerance=1e-10,
                         max_iterations=20_000)
    assert s.converged and rel_l2(s.traction, c.traction) < 5e-6
    assert rel_l2(r.traction, c.traction) < 1e-7


@pytest.mark.parametrize("creepage", [(2e-4, -1e-4, 0.0), (0.0, 0.0, 2.0),
                                      (1e-4, 1e-4, 1.0)])
def test_hertz_same_traction_as_convexgs(sphere, creepage):
    """Creepage, spin and both: SteadyGS at eps 1e-6 is ConvexGS's converged traction
    within a few eps, in fewer sweeps (far fewer where adhesion matters, see the
    wheel-rail test)."""
    hz, g, nr = sphere
    op = rolling_operator(g, STEEL)
    s = solve_steadygs(g, op, nr.pressure, 0.3, creepage, tolerance=1e-6)
    c = solve_tangential(g, op, nr.pressure, 0.3, creepage, tolerance=1e-10,
                         max_iterations=20_000)
    c6 = solve_tangential(g, op, nr.pressure, 0.3, creepage, tolerance=1e-6)
    assert s.converged and c.converged, (s.message, c.message)
    assert rel_l2(s.traction, c.traction) < 5e-6
    assert np.array_equal(s.state, c.state)
    assert s.iterations < c6.iterations
    assert np.all(np.hypot(*s.traction) <= 0.3 * nr.pressure * (1 + 1e-12))


def test_kalker_linear_theory(sphere):
    """Small creepages: F_x, F_y and the spin's F_y within 5 % of Kalker's C11, C22, C23 on
    the 31 x 31 grid (ConvexGS's errors on it are the same, see test_tangential)."""
    hz, g, nr = sphere
    c = creep_coefficients(hz.a, hz.b, 0.28)
    cab, gm = math.sqrt(hz.a * hz.b), STEEL.shear
    op = rolling_operator(g, STEEL)
    fx, fy, fs = (solve_steadygs(g, op, nr.pressure, 0.3, cr, tolerance=1e-7).force
                  for cr in ((1e-5, 0, 0), (0, 1e-5, 0), (0, 0, 1e-5 / cab)))
    assert -fx[0] / (gm * cab**2 * 1e-5) == pytest.approx(c.c11, rel=0.05)
    assert -fy[1] / (gm * cab**2 * 1e-5) == pytest.approx(c.c22, rel=0.05)
    assert -fs[1] / (gm * cab**3 * 1e-5 / cab) == pytest.approx(c.c23, rel=0.05)


def test_contact_fastsim_example():
    """CONTACT examples/fastsim.inp, case 1 (eta and spin on a 44 x 44 grid): F_y/(mu N) =
    -0.6074 and M_z = -48.21 N m as CONTACT reports."""
    A, B, N = 0.84642, 2.40616, 82e3
    g = Grid(44, 44, 0.4e-3, 0.2e-3, -21.5 * 0.4e-3, -21.5 * 0.2e-3)
    X, Y = g.mesh()
    nr = solve_normal(A * X**2 + B * Y**2, g, influence_operator(g, CONTACT_G), load=N,
                      tolerance=1e-8)
    r = solve_steadygs(g, rolling_operator(g, CONTACT_G), nr.pressure, 0.3,
                       (0.0, -6.25e-4, 0.625), tolerance=1e-5)
    assert r.converged, r.message
    assert r.force[1] / (0.3 * N) == pytest.approx(-0.6074, rel=0.02)
    assert r.spin_moment == pytest.approx(-4.821e4 * 1e-3, rel=0.03)


def test_wheel_rail_patch_in_few_sweeps(wheel_rail_patch):
    """The wheel-rail patch at eps 1e-5 from zero traction: at most 30 sweeps and 0.4 of
    ConvexGS's, the same traction to the tolerance."""
    nr, pair, creepage = wheel_rail_patch
    g = nr.grid
    op = rolling_operator(g, pair, "auto")
    s = solve_steadygs(g, op, nr.pressure, 0.4, creepage, tolerance=1e-5)
    c = solve_tangential(g, op, nr.pressure, 0.4, creepage, tolerance=1e-5)
    ref = solve_tangential(g, op, nr.pressure, 0.4, creepage, tolerance=1e-9,
                           max_iterations=20_000)
    print(s.iterations, c.iterations)
    assert s.converged and c.converged
    assert s.iterations <= 30 and s.iterations <= 0.4 * c.iterations
    assert rel_l2(s.traction, ref.traction) < 1e-4
    assert s.force == pytest.approx(ref.force, rel=1e-4)


@pytest.mark.parametrize("creepage", [(0.05, 0, 0), (0.03, 0.04, 0)])
def test_full_sliding(sphere, creepage):
    """|F| = mu N opposite to the rigid slip, all elements sliding."""
    hz, g, nr = sphere
    r = solve_steadygs(g, rolling_operator(g, STEEL), nr.pressure, 0.3, creepage,
                       tolerance=1e-6)
    f = np.array(r.force)
    assert r.converged and r.slip_area_ratio == 1.0
    assert np.linalg.norm(f) == pytest.approx(0.3 * nr.force, rel=5e-3)
    w = np.array(creepage[:2])
    assert np.dot(f, w) / (np.linalg.norm(f) * np.linalg.norm(w)) == pytest.approx(-1, abs=1e-6)


def test_zero_creepage_and_zero_pressure(sphere):
    hz, g, nr = sphere
    op = rolling_operator(g, STEEL)
    r = solve_steadygs(g, op, nr.pressure, 0.3, (0, 0, 0), tolerance=1e-6)
    assert r.converged and r.iterations == 0  # no creepage: no sweep
    assert not r.traction.any() and r.force == (0.0, 0.0)
    z = solve_steadygs(g, op, np.zeros(g.shape), 0.3, (1e-3, 0, 1.0))
    assert z.converged and z.iterations == 0 and "no contact" in z.message
    assert not z.traction.any()


def test_warm_start_converges_at_once(wheel_rail_patch):
    nr, pair, creepage = wheel_rail_patch
    g = nr.grid
    op = rolling_operator(g, pair, "auto")
    a = solve_steadygs(g, op, nr.pressure, 0.4, creepage, tolerance=1e-8)
    for state in (None, a.state):
        b = solve_steadygs(g, op, nr.pressure, 0.4, creepage, tolerance=1e-5,
                           initial_traction=a.traction, initial_state=state)
        assert b.converged and b.iterations <= 2
        assert rel_l2(b.traction, a.traction) < 1e-6


def test_not_converged_and_stalled(sphere):
    hz, g, nr = sphere
    op = rolling_operator(g, STEEL)
    r = solve_steadygs(g, op, nr.pressure, 0.3, (2e-4, 0, 1.0), tolerance=1e-6,
                       max_iterations=3)
    assert not r.converged and r.iterations == 3 and "not converged" in r.message
    r = solve_steadygs(g, op, nr.pressure, 0.3, (2e-4, 0, 1.0), tolerance=1e-30)
    assert not r.converged and "stalled" in r.message
    assert np.isfinite(r.traction).all()


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
def test_numba_and_numpy_sweeps_agree():
    hz, g, nr = hertz_patch(1.5, 17)
    op = rolling_operator(g, STEEL, "scipy")
    a = solve_steadygs(g, op, nr.pressure, 0.3, (2e-4, -1e-4, 0.5), engine="numba",
                       tolerance=1e-6)
    b = solve_steadygs(g, op, nr.pressure, 0.3, (2e-4, -1e-4, 0.5), engine="numpy",
                       tolerance=1e-6)
    assert a.converged and a.iterations == b.iterations
    assert np.allclose(a.traction, b.traction, rtol=0, atol=1e-9 * a.max_traction)


def test_bad_input(sphere):
    hz, g, nr = sphere
    op = rolling_operator(g, STEEL)
    bad = [
        ("friction", dict(friction=-0.1)),
        ("xi", dict(creepage=(float("nan"), 0, 0))),
        ("pressure", dict(pressure=-nr.pressure)),
        ("tolerance", dict(tolerance=0.0)),
        ("max_iterations", dict(max_iterations=0)),
        ("omega_h", dict(omega_h=2.0)),
        ("omega_s", dict(omega_s=0.0)),
        ("engine", dict(engine="fortran")),
        ("initial_traction", dict(initial_traction=np.zeros((2, 3, 3)))),
        ("initial_state", dict(initial_traction=np.zeros((2, *g.shape)),
                               initial_state=np.zeros((3, 3)))),
    ]
    for match, kw in bad:
        args = dict(pressure=nr.pressure, friction=0.3, creepage=(1e-4, 0, 0)) | kw
        with pytest.raises(rc.RailContactError, match=match):
            solve_steadygs(g, op, args.pop("pressure"), args.pop("friction"),
                           args.pop("creepage"), **args)
    normal_op = influence_operator(g, STEEL)
    with pytest.raises(rc.RailContactError, match="operator"):
        solve_steadygs(g, normal_op, nr.pressure, 0.3, (1e-4, 0, 0))


def test_a_window_around_the_contact_gives_the_whole_grid_answer():
    """The steady-rolling problem lives on the contact elements alone (zero traction bound
    elsewhere): the case solver's SteadyGS on the contact's window (counts in multiples of
    8, far fewer than the potential area's) gives the traction of a solve on the whole
    grid, zero outside the window."""
    from railcontact.contact.patch import contact_window

    d = {"material": {"young": 2 * 82e9 * 1.28, "poisson": 0.28},
         "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1", "side": "left",
                      "lateral_displacement": 2e-3},
         "grid": {"dx": 0.5e-3, "dy": 0.5e-3, "margin": 1.5},
         "normal": {"load": 83.3e3, "tolerance": 1e-8},
         "tangential": {"friction": 0.4, "creepage": [-1e-3, 5e-4, 0.3], "tolerance": 1e-9,
                        "solver": "steadygs", "estimate": "none"}}
    patch = rc.solve(d).patches[0]
    nr, t = patch.normal, patch.tangential
    sx, sy = contact_window(nr.contact)
    assert (sx.stop - sx.start) * (sy.stop - sy.start) < 0.5 * nr.grid.size
    full = solve_steadygs(nr.grid, rolling_operator(nr.grid, Case.from_dict(d).pair),
                          nr.pressure, 0.4, (-1e-3, 5e-4, 0.3), tolerance=1e-9)
    assert t.converged and full.converged
    assert rel_l2(t.traction, full.traction) < 1e-7
    np.testing.assert_array_equal(t.state, full.state)
    np.testing.assert_allclose(t.force, full.force, rtol=1e-7)
    assert t.spin_moment == pytest.approx(full.spin_moment, rel=1e-6)
    slip = t.state == 2
    ts, fs = t.relative_slip(), full.relative_slip()
    np.testing.assert_allclose(ts[:, slip], fs[:, slip], rtol=0, atol=1e-6 * np.abs(fs).max())


@pytest.mark.parametrize("solver", [solve_steadygs, solve_tangential])
def test_slip_formed_when_asked_obeys_coulomb(sphere, solver):
    """The result's slip costs a product with the operator only when asked for (each
    call, :meth:`TangentialResult.relative_slip`; reading the result's fields costs none); it is
    ``(W + B p)/dx`` of the returned traction (a dense product here, not the solver's
    FFT), zero outside the slip area, and in the slip area opposite to the traction
    (Coulomb), |p| = mu p_n. A pickled result carries it."""
    import pickle

    from railcontact.tangential.rolling import rigid_slip

    hz, g, nr = sphere
    op = rolling_operator(g, STEEL)
    products = []
    apply = op.apply
    op.apply = lambda p: products.append(1) or apply(p)  # count the products from here on
    try:
        creepage = (1e-4, -5e-5, 0.2)
        r = solver(g, op, nr.pressure, 0.3, creepage, tolerance=1e-9, max_iterations=5000)
        n = len(products)
        fields = [getattr(r, f.name) for f in dataclasses.fields(r)]
        assert len(products) == n and len(fields) > 10
        assert not hasattr(r, "slip")  # the slip is a call, not an attribute
        s = r.relative_slip()
        assert len(products) == n + 1
    finally:
        del op.apply
    assert r.converged and 0.1 < r.slip_area_ratio < 0.9
    dense = (op.dense() @ r.traction.reshape(-1)).reshape(r.traction.shape)
    expected = (rigid_slip(g, creepage) + dense) / g.dx
    slipping = r.state == 2
    np.testing.assert_allclose(s[:, slipping], expected[:, slipping], rtol=0,
                               atol=1e-9 * np.abs(expected).max())
    assert not s[:, ~slipping].any()
    p = r.traction[:, slipping]
    cos = -np.sum(p * s[:, slipping], axis=0) / (np.hypot(*p) * np.hypot(*s[:, slipping]))
    assert cos.min() > 1 - 1e-6
    np.testing.assert_allclose(np.hypot(*p), 0.3 * nr.pressure[slipping], rtol=1e-12)
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(r)).relative_slip(), s)


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
def test_non_reciprocal_operator_is_refused(sphere):
    """The compiled sweep takes B_yx = B_xy (reciprocity of quasi-identical materials):
    an operator whose kernels break it is refused with a clear error, not solved wrongly."""
    from railcontact.halfspace.operator import InfluenceOperator

    hz, g, nr = sphere
    k = rolling_operator(g, STEEL).kernels.copy()
    k[1, 0] *= 1.01
    op = InfluenceOperator(g, STEEL, "xy", "scipy", kernels=k)
    with pytest.raises(rc.RailContactError, match="reciprocal"):
        solve_steadygs(g, op, nr.pressure, 0.3, (1e-4, 0, 0), engine="numba")


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
def test_row_blocks_of_any_size_give_the_same_iterates(sphere, monkeypatch):
    """The shift is exact at every element update whatever the blocks: one block, the
    default blocks, many blocks (a DC-FFT product at each boundary) and the numpy sweep
    without blocks take the same sweeps to the same traction."""
    import railcontact.tangential.steadygs as steadygs
    from railcontact.tangential.convexgs import _blocks_of

    hz, g, nr = sphere
    op = rolling_operator(g, STEEL)
    per_row = (nr.pressure > 0).sum(axis=0)  # contact elements per row (rows along y)
    args = (g, op, nr.pressure, 0.3, (1e-4, -5e-5, 0.2))
    default = solve_steadygs(*args, tolerance=1e-6)
    monkeypatch.setattr(steadygs, "BLOCK_SCALE", 1e3)
    assert len(_blocks_of(per_row, steadygs.BLOCK_SCALE**2 * g.size)) == 1
    one = solve_steadygs(*args, tolerance=1e-6)
    monkeypatch.setattr(steadygs, "BLOCK_SCALE", 2.0)
    assert len(_blocks_of(per_row, steadygs.BLOCK_SCALE**2 * g.size)) >= 8
    many = solve_steadygs(*args, tolerance=1e-6)
    plain = solve_steadygs(*args, tolerance=1e-6, engine="numpy")
    assert one.converged
    assert one.iterations == default.iterations == many.iterations == plain.iterations
    for r in (default, many, plain):
        np.testing.assert_allclose(r.traction, one.traction, rtol=0,
                                   atol=1e-11 * one.max_traction)
        np.testing.assert_array_equal(r.state, one.state)


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
def test_rows_of_any_length_give_the_numpy_sweeps_iterates():
    """The compiled block adds the changes of a block's earlier rows to 16, 20, 24, 28 or
    32 targets of a row at a time (the row's last chunk the smallest that holds it): on a
    circle whose rows hold from a few to 37 contact elements (every chunk size, and rows
    longer than one chunk) it takes the plain numpy sweep's sweeps to its traction."""
    hz, g, nr = hertz_patch(1.0, 41)
    per_row = (nr.pressure > 0).sum(axis=0)
    lengths = per_row[per_row > 0]
    assert lengths.max() > 32 and lengths.min() <= 16
    for short, long in ((16, 20), (20, 24), (24, 28), (28, 32)):  # each chunk size
        assert ((lengths > short) & (lengths <= long)).any()
    op = rolling_operator(g, STEEL)
    args = (g, op, nr.pressure, 0.3, (1e-4, -5e-5, 0.2))
    a = solve_steadygs(*args, tolerance=1e-6, engine="numba")
    b = solve_steadygs(*args, tolerance=1e-6, engine="numpy")
    assert a.converged and a.iterations == b.iterations
    np.testing.assert_allclose(a.traction, b.traction, rtol=0, atol=1e-11 * b.max_traction)
    np.testing.assert_array_equal(a.state, b.state)


def test_row_blocks_hold_their_share_of_the_contact():
    """``_blocks_of``: the blocks cover the rows from the first to the last one with
    contact, in order and without gaps; their number is ``total / sqrt(work)`` rounded
    (at least 1, at most the rows with contact), and every block but the last ends at the
    first row where it holds ``total / nblocks`` elements (checked on random row counts
    against that definition written out)."""
    from railcontact.tangential.convexgs import _blocks_of

    rng = np.random.default_rng(7)
    assert _blocks_of(np.zeros(6, dtype=np.int64), 100.0) == []
    for _ in range(300):
        n = int(rng.integers(1, 60))
        per_row = rng.integers(0, 40, n) * (rng.random(n) < 0.7)
        work = float(rng.uniform(1.0, 2e4))
        blocks = _blocks_of(per_row, work)
        rows = [i for i in range(n) if per_row[i] > 0]
        if not rows:
            assert blocks == []
            continue
        total = int(per_row.sum())
        want = max(1, min(len(rows), round(total / work**0.5)))
        assert 1 <= len(blocks) <= want
        assert blocks[0][0] == rows[0] and blocks[-1][1] == rows[-1] + 1
        assert all(a[1] == b[0] for a, b in zip(blocks, blocks[1:], strict=False))
        target = total / want
        base = 0
        for start, stop in blocks[:-1]:
            assert int(per_row[:stop].sum()) - base >= target
            assert stop - 1 == start or int(per_row[:stop - 1].sum()) - base < target
            base = int(per_row[:stop].sum())


@pytest.mark.parametrize("solver", [solve_steadygs, solve_tangential])
def test_embed_gives_the_whole_grid_answer(solver):
    """``embed=(grid, window)``: a solve on the contact's window, returned on the whole
    grid, is the whole grid's solve (the problem lives on the contact elements alone):
    the same sweeps, traction, states, forces and slip, all zero outside the window."""
    from railcontact.contact.patch import contact_window

    hz, g, nr = hertz_patch(1.0, 33, margin=2.0)
    sx, sy = contact_window(nr.contact)
    assert sx.stop - sx.start < g.nx and sy.stop - sy.start < g.ny
    w = Grid(sx.stop - sx.start, sy.stop - sy.start, g.dx, g.dy, g.x0 + sx.start * g.dx,
             g.y0 + sy.start * g.dy)
    args = (0.3, (1e-4, -5e-5, 0.2))
    whole = solver(g, rolling_operator(g, STEEL), nr.pressure, *args, tolerance=1e-6)
    part = solver(w, rolling_operator(w, STEEL), nr.pressure[sx, sy], *args, tolerance=1e-6,
                  embed=(g, (sx, sy)))
    assert part.grid is g and part.converged and part.iterations == whole.iterations
    np.testing.assert_allclose(part.traction, whole.traction, rtol=0,
                               atol=1e-9 * whole.max_traction)
    np.testing.assert_array_equal(part.state, whole.state)
    outside = np.ones(g.shape, dtype=bool)
    outside[sx, sy] = False
    assert not part.traction[:, outside].any() and not part.state[outside].any()
    np.testing.assert_allclose(part.force, whole.force, rtol=1e-9)
    assert part.spin_moment == pytest.approx(whole.spin_moment, rel=1e-9)
    slip = whole.state == 2
    ps, ws = part.relative_slip(), whole.relative_slip()
    assert slip.any() and not ps[:, outside].any()
    np.testing.assert_allclose(ps[:, slip], ws[:, slip], rtol=0, atol=1e-7 * np.abs(ws).max())


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
def test_compiled_and_python_sweeps_agree(sphere, wheel_rail_patch, monkeypatch):
    """The sweeps and their measure as one compiled call (the operator's packed plan) and
    as the Python loop between the same kernels give the same result to the bit: one
    block and many, a warm start, a stalled solve; and the solve is ConvexGS's."""
    import railcontact.tangential.steadygs as steadygs
    from railcontact.halfspace.operator import InfluenceOperator

    hz, g, nr = sphere
    op = rolling_operator(g, STEEL, "pyfftw")
    assert op.compiled_product() is not None
    wr, pair, creepage = wheel_rail_patch
    wr_op = rolling_operator(wr.grid, pair, "pyfftw")
    warm = solve_steadygs(wr.grid, wr_op, wr.pressure, 0.4, creepage, tolerance=1e-8)

    def solves():
        out = [solve_steadygs(wr.grid, wr_op, wr.pressure, 0.4, creepage, tolerance=1e-5,
                              initial_traction=warm.traction, initial_state=warm.state),
               solve_steadygs(g, op, nr.pressure, 0.3, (2e-4, 0, 1.0), tolerance=1e-30)]
        for scale in (1e3, 2.0):  # one block; many
            monkeypatch.setattr(steadygs, "BLOCK_SCALE", scale)
            out.append(solve_steadygs(g, op, nr.pressure, 0.3, (1e-4, -5e-5, 0.2),
                                      tolerance=1e-6))
        monkeypatch.undo()
        return out

    compiled = solves()
    monkeypatch.setattr(InfluenceOperator, "compiled_product", lambda self, floor=None: None)
    python = solves()
    assert "stalled" in compiled[1].message
    for a, b in zip(compiled, python, strict=True):
        assert a.message == b.message and a.iterations == b.iterations
        assert a.force == b.force and a.spin_moment == b.spin_moment
        for f in ("traction", "state", "history"):
            np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
    ref = solve_tangential(g, op, nr.pressure, 0.3, (1e-4, -5e-5, 0.2), tolerance=1e-6)
    assert rel_l2(compiled[-1].traction, ref.traction) < 1e-3


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
def test_compiled_solve_on_a_window_agrees_with_python(wheel_rail_patch, monkeypatch):
    """The whole solve as one compiled call (set-up, sweeps, the result's fields and sums
    on the larger grid) and the Python solve around the same kernels give the same result
    to the bit on the contact's window: a warm start (the time step's solve), a cold one,
    no contact; the same errors, in the same order, for a start that is not finite and a
    negative pressure. The solution obeys Coulomb's law: ``|p| <= mu p_n``, equal in slip,
    where the slip opposes the traction."""
    from railcontact.contact.patch import contact_window
    from railcontact.halfspace.operator import InfluenceOperator

    wr, pair, creepage = wheel_rail_patch
    sx, sy = contact_window(wr.contact)
    w = Grid(sx.stop - sx.start, sy.stop - sy.start, wr.grid.dx, wr.grid.dy,
             wr.grid.x0 + sx.start * wr.grid.dx, wr.grid.y0 + sy.start * wr.grid.dy)
    op = rolling_operator(w, pair, "pyfftw")
    assert op.compiled_product() is not None and w.size < wr.grid.size
    pn = wr.pressure[sx, sy]
    warm = solve_steadygs(w, op, pn, 0.4, creepage, tolerance=1e-8)
    shifted = (creepage[0] * 1.05, creepage[1], creepage[2] * 0.95)  # the next step's
    embed = (wr.grid, (sx, sy))

    def solves():
        return [solve_steadygs(w, op, pn, 0.4, shifted, tolerance=1e-5, embed=embed,
                               initial_traction=warm.traction, initial_state=warm.state),
                solve_steadygs(w, op, pn, 0.4, shifted, tolerance=1e-5, embed=embed),
                solve_steadygs(w, op, np.zeros(w.shape), 0.4, shifted, embed=embed)]

    def errors():
        nan = warm.traction.copy()
        nan[0, 3, 4] = np.nan
        out = []
        for p in (pn, -pn):
            with pytest.raises(rc.RailContactError) as e:
                solve_steadygs(w, op, p, 0.4, shifted, initial_traction=nan)
            out.append(str(e.value))
        return out

    compiled, compiled_errors = solves(), errors()
    monkeypatch.setattr(InfluenceOperator, "compiled_product", lambda self, floor=None: None)
    python, python_errors = solves(), errors()
    assert compiled_errors == python_errors
    assert "initial_traction" in compiled_errors[0] and "pressure" in compiled_errors[1]
    assert compiled[0].converged and compiled[0].iterations < compiled[1].iterations
    assert compiled[2].iterations == 0 and "no contact" in compiled[2].message
    for a, b in zip(compiled, python, strict=True):
        assert a.grid is wr.grid and b.grid is wr.grid
        assert a.message == b.message and a.iterations == b.iterations
        assert (a.force, a.spin_moment, a.slip_area_ratio, a.max_traction, a.error) == (
            b.force, b.spin_moment, b.slip_area_ratio, b.max_traction, b.error)
        for f in ("traction", "state", "history"):
            np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
        np.testing.assert_array_equal(a.relative_slip(), b.relative_slip())
    r = compiled[0]
    bound = 0.4 * wr.pressure
    size = np.hypot(*r.traction)
    slip = r.state == 2
    assert slip.any() and (r.state == 1).any()
    assert np.all(size <= bound * (1 + 1e-12))
    np.testing.assert_allclose(size[slip], bound[slip], rtol=1e-12)
    s = r.relative_slip()[:, slip]
    cos = -np.sum(r.traction[:, slip] * s, axis=0) / (size[slip] * np.hypot(*s))
    assert cos.min() > 1 - 1e-3
