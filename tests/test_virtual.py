"""Kik–Piotrowski and INFCON normal estimates, and re-meshing."""

import copy
import math

import numpy as np
import pytest

import railcontact as rc
from railcontact import ElasticPair, Grid, Material, hertz
from railcontact.geometry.points import samples
from railcontact.halfspace.grid import remesh
from railcontact.normal.virtual import infcon_factor, virtual_penetration

PAIR = ElasticPair.of(Material(206e9, 0.28))


def quadratic(A, B, half=0.02, n=4001):
    s = np.linspace(-half, half, n)
    return s, B * s**2, np.full_like(s, A)


def test_infcon_factor_circle_and_table():
    """chi = 1/2 for a circle; chi = n^2 B/(r (A+B)) against the m, n, r table (theta =
    30 deg: 0.3123, 60 deg: 0.4113, docs/algorithms.md 4.3)."""
    assert infcon_factor(2.0, 2.0) == pytest.approx(0.5, abs=1e-12)
    for theta, chi in ((30, 0.3123), (60, 0.4113)):
        c = np.cos(np.radians(theta))
        assert infcon_factor(1 - c, 1 + c) == pytest.approx(chi, abs=1e-4)


@pytest.mark.parametrize("A, B", [(1.0, 1.0), (1.0, 5.0), (5.0, 1.0)])
def test_infcon_is_hertz_for_quadratic_gaps(A, B):
    hz = hertz(A, B, PAIR, penetration=1e-4)
    e = virtual_penetration("infcon", *quadratic(A, B), PAIR, penetration=1e-4, nx=60, ny=60)
    assert e.force == pytest.approx(hz.load, rel=5e-3)
    assert e.max_pressure == pytest.approx(hz.max_pressure, rel=5e-3)
    assert e.area == pytest.approx(hz.area, rel=0.03)
    x = np.linspace(-hz.a, hz.a, 41)
    assert np.allclose(e.pressure_at(x, 0.0 * x), hz.pressure(x, 0.0 * x),
                       atol=5e-3 * hz.max_pressure)


@pytest.mark.parametrize("method", ["infcon", "kp"])
def test_estimate_centred_on_the_gaps_minimum_off_the_samples_origin(method):
    """Samples whose origin is not at the gap's minimum (a patch in the frame at CONTACT's
    reference point): the model is centred on the smallest gap, so for a quadratic gap
    B (s - c)^2 whose rigid overlap at the origin is less than the virtual penetration
    (B c^2 = 1.5 delta) INFCON is Hertz's pressure about (0, c), and KP the same estimate
    as for the gap centred on the origin, moved by c; its grid and pressure are in the
    samples' frame."""
    A, B, delta, c = 1.0, 5.0, 1e-4, math.sqrt(1.5e-4 / 5.0)
    s, f, a = quadratic(A, B, half=0.03, n=6001)
    f_off = B * (s - c) ** 2
    f_off -= f_off.min()  # (minimum 0, at the sample nearest c)
    e = virtual_penetration(method, s, f_off, a, PAIR, penetration=delta, nx=60, ny=60)
    assert e.offset == pytest.approx(c, abs=1e-5)  # (the sample nearest c)
    centred = virtual_penetration(method, s - e.offset, f_off, a, PAIR, penetration=delta,
                                  nx=60, ny=60)
    assert e.force == pytest.approx(centred.force, rel=1e-12)
    lo, hi = e.grid.bounds[2:]
    assert (lo - e.offset, hi - e.offset) == pytest.approx(centred.grid.bounds[2:], abs=1e-12)
    g = Grid.from_bounds(-0.01, 0.01, -0.01, 0.02, 48, 72)
    moved = Grid.from_bounds(-0.01, 0.01, -0.01 - e.offset, 0.02 - e.offset, 48, 72)
    np.testing.assert_allclose(e.pressure_on(g), centred.pressure_on(moved), rtol=1e-9,
                               atol=1e-9 * e.max_pressure)
    if method == "infcon":  # Hertz about (0, c)
        hz = hertz(A, B, PAIR, penetration=delta)
        assert e.force == pytest.approx(hz.load, rel=5e-3)
        X, Y = g.mesh()
        np.testing.assert_allclose(e.pressure_on(g), hz.pressure(X, Y - e.offset),
                                   atol=0.02 * hz.max_pressure)
    e_load = virtual_penetration(method, s, f_off, a, PAIR, load=e.force, nx=60, ny=60)
    assert e_load.offset == e.offset
    assert e_load.penetration == pytest.approx(delta, rel=1e-3)


def test_infcon_strips_solve_the_strip_wise_boussinesq_equations():
    """On a non-elliptic patch (a lateral gap with a steep flank and a flat one, A varying
    across) INFCON's pressure, one semi-ellipse along x per strip with its own amplitude,
    displaces each strip's centre (0, y_j) by the rigid interpenetration there, delta -
    f(y_j): summed here with Love's coefficients of the zz block (``coefficients_at``,
    independent of the estimate's compiled strip sums) on the estimate grid. A strip left
    without pressure (its amplitude would be negative) opens: its centre is displaced by
    more than the interpenetration. A strip whose semi-ellipse holds no element centre
    has no equation."""
    from railcontact.halfspace.influence import coefficients_at

    s = np.linspace(-0.02, 0.02, 801)
    f = np.where(s < 0, 4.0 * s**2, 1.5 * s**2 + 40.0 * s**3)
    a = 1.1 + 8.0 * s
    delta = 1.2e-4
    e = virtual_penetration("infcon", s, f, a, PAIR, penetration=delta, nx=40, ny=40)
    g = e.grid
    X, Y = g.mesh()
    shape = np.sqrt(np.clip(e.half_length(g.y) ** 2 - X**2, 0, None))
    strips = shape.any(axis=0)
    loaded = e.pressure.any(axis=0)
    assert not (loaded & ~strips).any() and loaded.sum() >= g.ny - 3
    # the strip amplitudes differ (one amplitude would not solve the equations)
    assert e.amplitude.max() > 1.2 * e.amplitude.min()
    u = np.array([float(np.sum(coefficients_at("zz", -X, yj - Y, g.dx, g.dy, PAIR)
                                * e.pressure)) for yj in g.y])
    want = delta - np.interp(g.y, s, f)
    np.testing.assert_allclose(u[loaded], want[loaded], rtol=1e-9, atol=0)
    assert np.all(u[strips & ~loaded] > want[strips & ~loaded])
    # the pressure is the semi-ellipse of the outline on each strip
    np.testing.assert_allclose(e.pressure, e.amplitude * shape, rtol=1e-12, atol=0)


@pytest.mark.parametrize("rail, lateral, bound", [("60E1", -0.002, 0.025),
                                                  ("CN60", 0.0, 0.06)])
def test_infcon_pressure_against_the_converged_bem(root, rail, lateral, bound):
    """S1002 on 60E1 at -2 mm (a nearly elliptic tread patch) and on CN60 at 0 mm (the
    patch runs across the rail's R300/R80 joint), 83.3 kN, 64 x 64 elements: INFCON at the
    converged solution's normal penetration, on its grid, is within the stated L1 bound
    of the BEM pressure converged to eps_n = 1e-9 (Sum |p_est - p| / Sum p), and KP's
    error there is at least twice INFCON's."""
    from railcontact.contact import normal_estimate
    from railcontact.settings import Control, NormalSettings

    c = rc.load_case(root / "models" / "cases" / "s1002_60e1_dy-2mm.toml").to_dict()
    c["geometry"].update(rail=rail, lateral_displacement=lateral)
    c["normal"].update(tolerance=1e-9, estimate="infcon")
    patch = rc.solve(c).patches[0]
    n, cp = patch.normal, patch.geometry
    assert n.converged
    error = {}
    for method in ("infcon", "kp"):
        est = normal_estimate(NormalSettings(estimate=method), None, *samples(cp)[:3],
                              PAIR, Control(penetration=n.penetration)).pressure_on(n.grid).pressure
        error[method] = float(np.abs(est - n.pressure).sum() / n.pressure.sum())
    print(rail, lateral, error)
    assert error["infcon"] <= bound
    assert error["kp"] >= 2 * error["infcon"]


def test_kp_is_close_to_hertz_for_quadratic_gaps():
    """KP's constant factor 0.55 gives a near-Hertz patch (exact shape only for eps = 1/2
    on a circle): force and maximum pressure within 10 %, area within 15 %."""
    hz = hertz(1.0, 5.0, PAIR, penetration=1e-4)
    e = virtual_penetration("kp", *quadratic(1.0, 5.0), PAIR, penetration=1e-4)
    assert e.factor == 0.55
    assert e.force == pytest.approx(hz.load, rel=0.10)
    assert e.max_pressure == pytest.approx(hz.max_pressure, rel=0.10)
    assert e.area == pytest.approx(hz.area, rel=0.15)


@pytest.mark.parametrize("method", ["kp", "infcon"])
def test_load_control(method):
    e = virtual_penetration(method, *quadratic(1.0, 5.0), PAIR, load=5e4)
    assert e.force == pytest.approx(5e4, rel=1e-5)


def test_remesh_conserves_force():
    hz = hertz(1.0, 5.0, PAIR, load=7e4)
    src = Grid.from_bounds(-hz.a, hz.a, -hz.b, hz.b, 40, 40)
    dst = Grid.from_bounds(-1.3 * hz.a, 1.3 * hz.a, -1.3 * hz.b, 1.3 * hz.b, 64, 57)
    p = hz.pressure(*src.mesh())
    q = remesh(p, src, dst, conserve=True)
    assert q.sum() * dst.element_area == pytest.approx(p.sum() * src.element_area, rel=1e-12)
    assert q.max() == pytest.approx(hz.max_pressure, rel=0.03)
    assert np.all(q >= 0)


def test_infcon_estimate_cuts_iterations_on_paper_case(root):
    """Paper Sec. 4.1.1: 13 -> 3 iterations with INFCON."""
    base = rc.load_case(root / "models" / "cases" / "hertz_paper.toml").to_dict()
    its = {}
    for est in ("none", "infcon"):
        c = copy.deepcopy(base)
        c["normal"]["estimate"] = est
        its[est] = rc.solve(c).patches[0].normal.iterations
    print(its)
    assert its["infcon"] <= its["none"] / 3


def test_wheel_rail_estimates_order(root):
    """-2 mm wheel-rail case: INFCON <= KP <= none (paper: 5 / 6 / 13 iterations), over
    all solves of the patch: the estimate starts the first, which forms the patch frame at
    Hertz's approach; the second, at the approach found, starts from the first (2
    iterations whatever the estimate)."""
    base = rc.load_case(root / "models" / "cases" / "s1002_60e1_dy-2mm.toml").to_dict()
    its = {}
    for est in ("none", "kp", "infcon"):
        c = copy.deepcopy(base)
        c["normal"]["estimate"] = est
        patch = rc.solve(c).patches[0]
        n = patch.normal
        assert n.force == pytest.approx(83.3e3 / np.cos(patch.geometry.contact_angle), rel=1e-9)
        its[est] = patch.work.normal_iterations
    print(its)
    assert its["infcon"] <= its["kp"] < its["none"]


def test_small_lateral_sweep_estimates_cut_iterations(root):
    """A handful of displacements (-4 .. 4 mm, 83.3 kN): mean iterations INFCON < none for
    the normal BEM and FaStrip < none for ConvexGS (xi = eta = 2e-4, phi = 0.2 /m), the
    sweeps of every load pass counted (the later passes start from the one before)."""
    base = rc.load_case(root / "models" / "cases" / "s1002_60e1_dy-2mm.toml").to_dict()
    its = {"none": [], "infcon": [], "t_none": [], "t_fastrip": []}
    for dy in (-0.004, -0.002, 0.0, 0.002, 0.004):
        for est in ("none", "infcon"):
            c = copy.deepcopy(base)
            c["geometry"]["lateral_displacement"] = dy
            c["normal"]["estimate"] = est
            if est == "none":
                its[est].append(rc.solve(c).patches[0].normal.iterations)
                continue
            for test in ("none", "fastrip"):
                c["tangential"] = {"creepage": [2e-4, 2e-4, 0.2], "friction": 0.4,
                                   "estimate": test}
                patch = rc.solve(c).patches[0]
                assert patch.tangential.converged
                its[f"t_{test}"].append(patch.work.tangential_iterations)  # all passes
            its[est].append(patch.normal.iterations)
    means = {k: float(np.mean(v)) for k, v in its.items()}
    print(means)
    assert means["infcon"] < means["none"]
    assert means["t_fastrip"] < means["t_none"]


def test_equivalent_ellipse_of_a_hertz_patch():
    from railcontact.tangential.strips import equivalent_ellipse

    hz = hertz(1.0, 5.0, PAIR, load=7e4)
    g = Grid.from_bounds(-1.2 * hz.a, 1.2 * hz.a, -1.2 * hz.b, 1.2 * hz.b, 81, 81)
    a, b = equivalent_ellipse(g, hz.pressure(*g.mesh()) > 0)
    assert a == pytest.approx(hz.a, rel=0.03) and b == pytest.approx(hz.b, rel=0.03)


def test_two_patch_estimates_land_on_their_bem_patches(root):
    """5.0 mm, vertical approach 0.05 mm: tread and gauge-corner patches. Each patch's
    INFCON estimate, evaluated on that patch's BEM grid, covers that patch's BEM contact."""
    from railcontact.contact import normal_estimate
    from railcontact.halfspace.hertz import hertz as hertz_solution
    from railcontact.settings import Control, NormalSettings

    base = rc.load_case(root / "models" / "cases" / "s1002_60e1_dy-2mm.toml").to_dict()
    c = copy.deepcopy(base)
    c["geometry"]["lateral_displacement"] = 0.005
    c["normal"] = {"penetration": 5e-5, "estimate": "infcon", "tolerance": 1e-6}
    sol = rc.solve(c)
    assert len(sol.patches) == 2
    for p in sol.patches:
        cp, n = p.geometry, p.normal
        dn = cp.normal_penetration(5e-5)
        hz = hertz_solution(cp.A, cp.B, PAIR, penetration=dn)
        est = normal_estimate(NormalSettings(estimate="infcon", estimate_grid=(40, 40)), hz,
                              *samples(cp)[:3], PAIR, Control(penetration=dn)
                              ).pressure_on(n.grid).pressure
        overlap = np.logical_and(est > 0, n.contact).sum()
        assert overlap >= 0.8 * n.contact.sum()
        assert overlap >= 0.8 * np.count_nonzero(est > 0)
        assert n.force == pytest.approx(est.sum() * n.grid.element_area, rel=0.15)


def test_grid_coordinates_are_the_element_centres_shared_read_only():
    """x[i] = x0 + i dx, y[j] = y0 + j dy (the bounds' midpoints), formed once per grid and
    read-only (every reader shares them); a pickled grid forms them again."""
    import pickle

    g = Grid.from_bounds(-3e-3, 2e-3, 1e-3, 4.6e-3, 10, 9)
    lo_x, hi_x, lo_y, hi_y = g.bounds
    edges_x = np.linspace(lo_x, hi_x, g.nx + 1)
    edges_y = np.linspace(lo_y, hi_y, g.ny + 1)
    np.testing.assert_allclose(g.x, 0.5 * (edges_x[:-1] + edges_x[1:]), rtol=0, atol=1e-15)
    np.testing.assert_allclose(g.y, 0.5 * (edges_y[:-1] + edges_y[1:]), rtol=0, atol=1e-15)
    assert g.x is g.x and not g.x.flags.writeable and not g.y.flags.writeable
    with pytest.raises(ValueError):
        g.x[0] = 1.0
    h = pickle.loads(pickle.dumps(g))
    assert h == g and np.array_equal(h.x, g.x) and not h.x.flags.writeable
    big = Grid(3000, 2, 1e-4, 1e-4, 0.5, 0.0)  # beyond the shared index array
    np.testing.assert_array_equal(big.x, 0.5 + 1e-4 * np.arange(3000))


def test_remesh_on_a_shared_lattice_is_the_interpolation():
    """Grids on one lattice (same element size, centres a whole number of elements apart):
    the fast copy equals bilinear and nearest interpolation at the element centres, zero
    outside the source."""
    import railcontact.halfspace.grid as grid_module

    rng = np.random.default_rng(3)
    src = Grid(12, 9, 0.5e-3, 0.4e-3, -3e-3, 1e-3)
    v = rng.random(src.shape)
    for di, dj, nx, ny in [(0, 0, 12, 9), (3, -2, 10, 15), (-20, 0, 5, 5), (5, 4, 20, 20)]:
        dst = Grid(nx, ny, 0.5e-3, 0.4e-3, src.x0 + di * src.dx, src.y0 + dj * src.dy)
        fast = [remesh(v, src, dst), remesh(v, src, dst, method="nearest")]
        shift, grid_module._lattice_shift = grid_module._lattice_shift, lambda a, b: None
        try:
            slow = [remesh(v, src, dst), remesh(v, src, dst, method="nearest")]
        finally:
            grid_module._lattice_shift = shift
        for f, s in zip(fast, slow, strict=True):
            np.testing.assert_allclose(f, s, rtol=0, atol=1e-14)
    # half an element off the lattice: interpolated, not copied
    dst = Grid(12, 9, 0.5e-3, 0.4e-3, src.x0 + 0.25e-3, src.y0)
    assert grid_module._lattice_shift(src, dst) is None
    # the grid itself: a copy of the field
    same = remesh(v, src, src)
    assert np.array_equal(same, v) and not np.shares_memory(same, v)
    # several fields at once (a traction's two components): each as on its own, on and
    # off the lattice
    v2 = rng.random((2, *src.shape))
    for dst in (Grid(10, 15, 0.5e-3, 0.4e-3, src.x0 + 3 * src.dx, src.y0 - 2 * src.dy),
                Grid(12, 9, 0.5e-3, 0.4e-3, src.x0 + 0.25e-3, src.y0), src):
        both = remesh(v2, src, dst)
        assert both.shape == (2, *dst.shape) and not np.shares_memory(both, v2)
        for k in range(2):
            np.testing.assert_array_equal(both[k], remesh(v2[k], src, dst))


def test_remesh_off_the_lattice_is_scipys_bilinear_interpolation():
    """Off the lattice, remesh is bilinear interpolation between the source's element
    centres and a ring of zeros half an element outside them, zero beyond: scipy's
    RegularGridInterpolator on the padded nodes gives the same values (finer, coarser,
    shifted and partly outside targets, a source of one element along an axis)."""
    from scipy.interpolate import RegularGridInterpolator

    rng = np.random.default_rng(5)
    outside = 0
    for src, dst in [
        (Grid(12, 9, 0.5e-3, 0.4e-3, -3e-3, 1e-3), Grid(30, 21, 0.23e-3, 0.19e-3, -4e-3, 0.3e-3)),
        (Grid(40, 44, 1e-3, 1e-3, -20e-3, -21e-3), Grid(64, 72, 0.5e-3, 0.5e-3, -16e-3, -17e-3)),
        (Grid(20, 22, 1e-3, 1e-3, 0.0, 0.0), Grid(10, 10, 2.1e-3, 2.3e-3, 0.7e-3, -5e-3)),
        (Grid(1, 7, 1e-3, 1e-3, 0.0, 0.0), Grid(5, 9, 0.3e-3, 0.8e-3, -0.6e-3, -1e-3)),
    ]:
        v = rng.random(src.shape)
        x = np.concatenate([[src.x[0] - src.dx / 2], src.x, [src.x[-1] + src.dx / 2]])
        y = np.concatenate([[src.y[0] - src.dy / 2], src.y, [src.y[-1] + src.dy / 2]])
        want = RegularGridInterpolator((x, y), np.pad(v, 1), bounds_error=False,
                                       fill_value=0.0)(np.stack(dst.mesh(), axis=-1))
        assert np.count_nonzero(want) > 0
        outside += np.count_nonzero(want == 0)
        np.testing.assert_allclose(remesh(v, src, dst), want, rtol=1e-12, atol=1e-15)
    assert outside > 0  # (some targets beyond the ring)


def test_infcon_in_the_reference_frame_between_two_lobes(root):
    """S1002/60E1 at +5.48 mm, 83.3 kN, in the frame at CONTACT's reference point: the
    tread and the flange root have joined into one patch of two lobes, its reference point
    (the weighted centre) on the gap's hump between them, 68 um above the patch's smallest
    gap, more than INFCON's virtual penetration. The estimate is centred on the gap's
    minimum (4.2 mm away) and starts the BEM within 5 % L1 of its converged pressure."""
    c = rc.load_case(root / "models" / "cases" / "s1002_60e1_dy-2mm.toml").to_dict()
    c["geometry"].update(lateral_displacement=5.48e-3, patch_frame="reference")
    c["grid"] = {"nx": 64, "ny": 64}
    c["normal"] = {"load": 83.3e3, "tolerance": 1e-3, "estimate": "infcon"}
    (p,) = rc.solve(c).patches
    cp = p.geometry
    assert samples(cp).f[np.argmin(np.abs(cp.s))] > 5e-5
    assert p.estimate == "infcon"
    assert p.estimate_error.l1 < 0.05
