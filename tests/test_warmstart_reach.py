"""A warm step finds every place its contact can reach.

A warm-started patch is meshed on the previous contact's box with a margin. A contact that
does not reach that box's edge can still miss a lobe of the rigid overlap beyond it: the
tread beside a flange-root contact (whose load the flange root then carries alone, at a
larger approach where the contact search sees one merged patch), or a second lobe of one
patch's gap across the flange root. The step checks the overlap beyond its grid against
the solved pressure's displacement and grows the area where the contact could be
(``contact.wheelrail._overlap_covered``). Each check here compares a warm step reported
ok with a cold solve of the same state at tight tolerances (1e-6), within what the
tolerances promise (:data:`railcontact.timestep.wheelset.WARM_PROMISE`).
"""

import math

import numpy as np
import pytest

import railcontact as rc
from railcontact.geometry.search import overlap_box
from railcontact.timestep.wheelset import OK, WARM_PROMISE, WheelsetContact

STEEL = rc.Material(206e9, 0.28)
PAIR = rc.ElasticPair.of(STEEL, STEEL)
TIGHT = {"warm_start": "none", "normal_tolerance": 1e-6, "tangential_tolerance": 1e-6,
         "load_tolerance": 1e-6}


@pytest.fixture(scope="module")
def geometry():
    return (rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
            rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46))


def _solve(wc, step, warm=True):
    pose, loads, creep, t = step
    return wc.solve(rc.Pose(*pose), loads=loads, creepages=creep,
                    time=t if warm else None)


def _off(warm, tight, mu):
    """(|dN| / N, max |dF| / (mu N)) of a warm wheel against the tight cold one."""
    n = tight.normal_force
    df = max(abs(a - b) for a, b in zip(warm.creep_force, tight.creep_force, strict=True))
    return abs(warm.normal_force - n) / n, df / (mu * n)


def _replay(geometry, settings, steps):
    """The last step solved warm after the others, and cold at tight tolerances."""
    warm = WheelsetContact(*geometry, PAIR, rc.ContactSettings(**settings))
    for step in steps:
        rw = _solve(warm, step)
    tight = WheelsetContact(*geometry, PAIR, rc.ContactSettings(**dict(settings, **TIGHT)))
    return rw, _solve(tight, steps[-1], warm=False)


def test_a_flange_root_step_keeps_the_tread_beside_it(geometry):
    """At y = -5.26 mm the right wheel touches at the flange root and, 16 um higher, on
    the tread. The warm step's area (the flange-root contact of the step before) left the
    tread out: the flange root carried the whole load at a 65 um approach, the creep
    force 8.5 % of mu N and the spin moment 13 N m off a cold solve, status 0."""
    settings = {"friction": 0.2, "element_size": 0.001, "warm_start": "previous+estimate",
                "normal_estimate": "none", "tangential_estimate": "fastrip",
                "tangential_solver": "steadygs", "load_includes_creep": False,
                "patch_frame": "rigid"}
    steps = [((-0.005577838354515834, -0.002230330502130562, 0.0),
              (36116.591848316966, 33546.80285873509),
              ((0.018929616430330923, 0.014874457118251621, 2.513738550432521),
               (0.018929616430330923, -0.014874457118251621, -2.513738550432521)), 0.005),
             ((-0.005255918111171427, 0.0012650720722957197, 0.0),
              (42270.27995839856, 27393.11474865349),
              ((-0.009499001344063314, -0.009692438040273003, -1.5366296523463423),
               (-0.008549101209656983, -0.009692438040273003, -1.6902926175809767)), 0.01)]
    rw, rt = _replay(geometry, settings, steps)
    w, t = rw.right, rt.right
    assert w.status == t.status == OK
    assert len(w.patches) == len(t.patches) == 2  # flange root and tread
    dn, df = _off(w, t, settings["friction"])
    assert dn <= WARM_PROMISE[0] and df <= WARM_PROMISE[1], (dn, df)
    assert w.spin_moment == pytest.approx(t.spin_moment, abs=0.05 * abs(t.spin_moment) + 0.5)
    # each patch carries its own lobe of the overlap only (the tread is not also carried
    # by the flange-root patch's grid, which reaches it)
    for p in (*w.patches, *t.patches):
        n, cp = p.normal, p.geometry
        lo, hi = overlap_box(cp, n.penetration)[2:]
        loaded = n.grid.y[np.asarray(n.pressure).sum(axis=0) > 0]
        assert lo <= loaded.min() and loaded.max() <= hi
    assert sum(p.normal.force for p in t.patches) == pytest.approx(t.normal_force)


def test_a_second_lobe_of_one_patch_beyond_the_warm_box_is_found(geometry):
    """A flange-root patch whose gap has a second lobe 8-12 mm beside the contact of the
    step before: the warm box missed it (p_max 947 against 1731 MPa, F_x 28 % of mu N
    off, status 0, and so at any tangential tolerance)."""
    settings = {"friction": 0.2, "element_size": 0.0005, "warm_start": "previous+estimate",
                "normal_estimate": "infcon", "tangential_estimate": "fastsim",
                "tangential_solver": "steadygs", "load_includes_creep": True,
                "patch_frame": "rigid", "normal_tolerance": 0.0001, "load_tolerance": 0.0001}
    poses = [(0.0024283731710255073, 0.001903174906088895, 0.0),
             (0.0031303590326935923, 0.0018495328453210294, 0.0),
             (0.0038101756698147725, 0.0017846616633830836, 0.0),
             (0.004463695692377574, 0.0017089552145200745, 0.0006157458557281147),
             (0.005086951365751602, 0.0016228731374401163, 0.0)]
    loads = [(40623.354508177996, 40340.04047727804), (40764.83801149782, 40198.55697395821),
             (40905.974703088024, 40057.42028236801), (41046.59170815012, 39916.80327730592),
             (41186.51678843664, 39776.878197019396)]
    creeps = [((0.020922995283044112, -0.011825808469211215, -2.373457759319084),
               (0.018830695754739703, -0.011825808469211215, -2.6108035352509926)),
              ((0.02618796462864257, -0.014728380104107363, -2.956008304320702),
               (0.02618796462864257, 0.014728380104107363, 2.956008304320702)),
              ((0.02100193039536902, -0.011753629815771743, -2.3589713937137953),
               (0.01890173735583212, -0.011753629815771743, -2.594868533085175)),
              ((0.010451857104868184, -0.005820768109123664, -1.1682370190389293),
               (0.010451857104868184, 0.005820768109123664, 1.1682370190389293)),
              ((0.015865391060309826, -0.008792802138305127, -1.764728772299297),
               (0.014278851954278844, -0.008792802138305127, -1.9412016495292268))]
    steps = [(p, q, c, 0.005 * (k + 1))
             for k, (p, q, c) in enumerate(zip(poses, loads, creeps, strict=True))]
    rw, rt = _replay(geometry, settings, steps)
    for w, t in zip(rw.wheels, rt.wheels, strict=True):
        assert w.status == t.status == OK
        dn, df = _off(w, t, settings["friction"])
        assert dn <= WARM_PROMISE[0] and df <= WARM_PROMISE[1], (w.side, dn, df)
        assert w.max_pressure == pytest.approx(t.max_pressure, rel=0.02)


def test_warm_steps_across_the_flange_root_and_flange_equal_tight_cold_solves(geometry):
    """Seeded random trajectories of a wheelset between 4.5 and 9 mm lateral (either
    side: the flange root, the flange, tread beside either), random yaw, loads and
    creepages, at the rigid point and the reference point, with and without the creep
    forces' share of the load: every wheel a warm step reports ok equals a cold solve of
    the same state at tight tolerances within the promise (1 mm elements: the same
    lattices and the same check as 0.5 mm, at a quarter of the cost)."""
    rng = np.random.default_rng(20261128)
    compared = 0
    for k in range(16):
        base = {"friction": float(rng.uniform(0.15, 0.4)), "element_size": 1e-3,
                "patch_frame": ("rigid", "reference")[k % 2],
                "load_includes_creep": bool(k // 2 % 2)}
        warm = WheelsetContact(*geometry, PAIR, rc.ContactSettings(
            **base, warm_start="previous+estimate"))
        tight = WheelsetContact(*geometry, PAIR, rc.ContactSettings(**base, **TIGHT))
        y = float(rng.uniform(4.5e-3, 8.5e-3)) * float(rng.choice([-1.0, 1.0]))
        dy = 0.0
        for j in range(20):
            dy = 0.6 * dy + float(rng.normal(0.0, 0.25e-3))
            y = float(np.clip(y + dy, -9e-3, 9e-3))
            pose = (y, float(rng.normal(0.0, 2e-3)), 0.0)
            loads = tuple(float(q) for q in rng.uniform(25e3, 45e3, 2))
            xi, eta = (float(c) for c in rng.uniform(-0.01, 0.01, 2))
            creep = ((xi, eta, float(rng.uniform(-2.5, 2.5))),
                     (xi, -eta, float(rng.uniform(-2.5, 2.5))))
            step = (pose, loads, creep, (j + 1) * 5e-3)
            rw = _solve(warm, step)
            if j == 0:  # (cold: no previous step)
                continue
            rt = _solve(tight, step, warm=False)
            for w, t in zip(rw.wheels, rt.wheels, strict=True):
                if w.status != OK:
                    continue
                assert t.patches, (k, j, w.side)
                dn, df = _off(w, t, base["friction"])
                assert dn <= WARM_PROMISE[0] and df <= WARM_PROMISE[1], (k, j, w.side, y,
                                                                          dn, df)
                compared += 1
    assert compared >= 300, compared


TWO_PATCH_STEPS = [
    ((-0.0050871387596757075, -0.0012417698266580263, -0.000622073280553165),
     (22979.223208682404, 22818.96228407336),
     ((-0.003954645720115737, -0.00317412830416792, 0.14925007547827818),
      (-0.0035591811481041633, -0.00317412830416792, 0.164175083026106)), 0.005),
    ((-0.005141565518338859, -0.000983675332288675, 0.0),
     (23059.255521190673, 22738.929971565092),
     ((-0.003974306240370612, -0.00317412830416792, 0.14925007547827818),
      (-0.003974306240370612, 0.00317412830416792, -0.14925007547827818)), 0.01),
    ((-0.0051827862410068724, -0.000701790787006861, 0.0010971124291334969),
     (23139.09165432767, 22659.093838428096),
     ((-0.00399394217857123, -0.00317412830416792, 0.14925007547827818),
      (-0.00399394217857123, 0.00317412830416792, -0.14925007547827818)), 0.015),
    ((-0.005209804010242937, -0.0004029335292814571, -0.0018328799221901898),
     (23218.633818813563, 22579.551673942202),
     ((-0.004013541262895394, -0.00317412830416792, 0.14925007547827818),
      (-0.0036121871366058544, -0.00317412830416792, 0.164175083026106)), 0.02),
    ((-0.0052219654050609104, -9.433138026794613e-05, 0.0),
     (23297.78458544337, 22500.400907312396),
     ((-0.004033091244553377, -0.00317412830416792, 0.14925007547827818),
      (-0.004033091244553377, 0.00317412830416792, -0.14925007547827818)), 0.025),
    ((-0.005218976303820869, 0.00021655216003957635, 0.0),
     (23376.44700442553, 22421.738488330233),
     ((-0.004052579905443026, -0.00317412830416792, 0.14925007547827818),
      (-0.0036473219148987234, -0.00317412830416792, 0.164175083026106)), 0.030000000000000002),
    ((-0.005200908997520002, 0.000522198416516306, 0.0),
     (23454.52472413329, 22343.660768622474),
     ((-0.004071995065785664, -0.00317412830416792, 0.14925007547827818),
      (-0.004071995065785664, 0.00317412830416792, -0.14925007547827818)), 0.035),
    ((-0.005168200441444918, 0.0008152153770174766, 0.0),
     (23531.922109123385, 22266.263383632377),
     ((-0.004091324591738072, -0.00317412830416792, 0.14925007547827818),
      (-0.003682192132564265, -0.00317412830416792, 0.164175083026106)), 0.04),
    ((-0.00512164168746889, 0.0010885164671625752, 0.0),
     (23608.54435727752, 22189.641135478243),
     ((-0.004110556402975729, -0.00317412830416792, 0.14925007547827818),
      (-0.003699500762678156, -0.00317412830416792, 0.164175083026106)), 0.045),
]


def test_a_two_patch_flange_root_sequence_ends_where_a_cold_solve_does(geometry):
    """Nine steps of a wheelset near 5.2 mm lateral, the right wheel at the flange root
    with the tread beside it (ConvexGS, eps_tau = 0.05, the reference point): the warm
    step ended on the flange-root patch alone at a larger approach (N 4 % and the creep
    force 11.7 % of mu N off a cold solve, spin moment 31.7 against -0.7 N m, status 0)."""
    settings = {"friction": 0.5, "element_size": 0.0005, "warm_start": "previous+estimate",
                "normal_estimate": "hertz", "tangential_estimate": "fastrip",
                "tangential_solver": "convexgs", "load_includes_creep": True,
                "patch_frame": "reference", "tangential_tolerance": 0.05}
    rw, rt = _replay(geometry, settings, TWO_PATCH_STEPS)
    for w, t in zip(rw.wheels, rt.wheels, strict=True):
        assert w.status == t.status == OK
        assert len(w.patches) == len(t.patches)
        dn, df = _off(w, t, settings["friction"])
        assert dn <= WARM_PROMISE[0] and df <= WARM_PROMISE[1], (w.side, dn, df)
        assert w.spin_moment == pytest.approx(t.spin_moment, abs=1.0)


def _solved(gap_of, bounds, h, load):
    from railcontact import Grid, solve_normal
    from railcontact.halfspace.operator import influence_operator
    x0, x1, y0, y1 = bounds
    nx, ny = round((x1 - x0) / h), round((y1 - y0) / h)
    grid = Grid(nx, ny, h, h, x0 + h / 2, y0 + h / 2)
    return solve_normal(gap_of(grid), grid, influence_operator(grid, PAIR, "z", "auto"),
                        load=load, tolerance=1e-8)


def test_uncovered_finds_a_second_lobe_and_leaves_a_hertz_contact_alone():
    """A gap ``A x^2 + f(y)`` with a second dip of ``f`` 10 mm beside the first: solved on
    a box around the first lobe (the contact inside, off its edges), the scan flags the
    second lobe, and a solve on a grid holding both (the independent truth) carries load
    there. Without the dip the same box around a Hertz contact is left as it is: its
    overlap's rim clears the bound."""
    from railcontact.contact.patch import uncovered

    a_x, b_y, h, load = 1 / (2 * 0.46), 1 / (2 * 0.3), 0.5e-3, 20e3

    def gap(dip):
        def of(grid):
            x, y = grid.mesh()
            f = b_y * y ** 2 - dip * np.exp(-(((y - 10e-3) / 1.5e-3) ** 2))
            return a_x * x ** 2 + f
        return of

    for dip, lobe in ((0.0, False), (160e-6, True)):
        small = _solved(gap(dip), (-8e-3, 8e-3, -5e-3, 5e-3), h, load)
        assert not small.touches_boundary
        pen = small.penetration
        xl = math.sqrt(pen / a_x)
        overlap = (-xl, xl, -14e-3, 14e-3)  # (holds the rigid overlap of both lobes)
        flagged = uncovered(gap(dip), small, PAIR, overlap)
        large = _solved(gap(dip), (-12e-3, 12e-3, -6e-3, 14e-3), h, load)
        far = large.grid.y > 5e-3
        carried = float(np.asarray(large.pressure)[:, far].sum()) * h * h
        if lobe:
            assert carried > 0.05 * load  # the second lobe carries load ...
            assert flagged is not None and flagged[2] < 10e-3 < flagged[3]  # ... and is found
        else:
            assert carried == 0.0 and flagged is None
            assert large.force == pytest.approx(small.force, rel=1e-6)
