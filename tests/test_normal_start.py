"""A warm normal solve's first product ``A p`` formed from the previous steps' displacements
(``timestep/warmstart.previous_start`` and ``solve_normal``'s ``initial_displacement``),
against the dense influence matrix of the same pressure (an independent truth: every
column of the half-space's influence coefficients, no FFT), and its fallbacks to the
convolution."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from railcontact import ElasticPair, Grid, Material, solve_normal
from railcontact.halfspace.grid import remesh
from railcontact.halfspace.operator import HAVE_PYFFTW, InfluenceOperator, influence_operator
from railcontact.normal.bem import CHANGE_LIMIT, REUSE_GENERATIONS, Displacement
from railcontact.timestep import compiled
from railcontact.timestep.warmstart import PatchMemory, previous_pressure, previous_start

PAIR = ElasticPair.of(Material(206e9, 0.28))
DX, DY = 0.5e-3, 0.4e-3
FFT = "pyfftw" if HAVE_PYFFTW else "scipy"


def dense(grid: Grid) -> np.ndarray:
    """The full influence matrix of ``grid`` [m/Pa] (nx ny, nx ny)."""
    return influence_operator(grid, PAIR, "z", "dense").dense()


def ellipse(grid: Grid, xc: float, yc: float, a: float, b: float, p0: float) -> np.ndarray:
    """A Hertz-like pressure [Pa] on ``grid``: ``p0 sqrt(1 - r^2)`` in the ellipse."""
    X, Y = grid.mesh()
    r2 = ((X - xc) / a) ** 2 + ((Y - yc) / b) ** 2
    return np.where(r2 < 1, p0 * np.sqrt(np.maximum(1 - r2, 0.0)), 0.0)


def memory(grid: Grid, pressure: np.ndarray, time: float, older=None, shown=True,
           generations=0) -> PatchMemory:
    """A remembered step whose displacement is the dense matrix times its pressure."""
    u = (dense(grid) @ pressure.ravel()).reshape(grid.shape) if shown else None
    return PatchMemory(grid, pressure, None, None, 0.0, 0.0, time=time, older=older,
                       displacement=None if u is None else Displacement(u, generations))


def two_steps(shown=(True, True), generations=(0, 0)):
    """Two remembered steps (t = 0 and 1 ms) of a patch moving 2 elements along x and
    shrinking across, on grids of one lattice with other origins and shapes; a new grid
    inside both that holds both pressures."""
    g0 = Grid(16, 14, DX, DY, -8 * DX, -7 * DY)
    g1 = Grid(15, 13, DX, DY, -6 * DX, -6 * DY)
    p0 = ellipse(g0, -1 * DX, 0.0, 4.1 * DX, 4.6 * DY, 1.0e9)
    p1 = ellipse(g1, 1 * DX, 0.2 * DY, 4.3 * DX, 4.2 * DY, 1.1e9)
    older = memory(g0, p0, 0.0, shown=shown[0], generations=generations[0])
    newer = memory(g1, p1, 1e-3, older=older, shown=shown[1], generations=generations[1])
    grid = Grid(13, 12, DX, DY, -5 * DX, -5 * DY)
    return newer, grid


@pytest.mark.parametrize("time", [1e-3, 1.5e-3, 2e-3])  # c = 0, 0.5, 1
def test_start_displacement_from_memory_equals_the_dense_product(time):
    """``A p`` of the extrapolated start ``p = p_k + c (p_k - p_{k-1})`` from the
    remembered ``u_k``, ``u_{k-1}`` (shifted by whole elements) equals the dense matrix of
    the new grid times ``p`` (its negative elements included)."""
    m, grid = two_steps()
    p, shown = previous_start(m, grid, time)
    assert shown is not None and shown.generations == 1
    c = m.extrapolation(time)
    want = remesh(m.pressure, m.grid, grid)
    if c > 0:
        want = want + c * (want - remesh(m.older.pressure, m.older.grid, grid))
        assert (want < 0).sum() > 5  # the clip of the old edge to come
    assert np.array_equal(p, want)  # the pressure bit for bit, before its floor
    assert np.array_equal(np.maximum(p, 0.0), previous_pressure(m, grid, time))
    u = (dense(grid) @ p.ravel()).reshape(grid.shape)
    assert np.max(np.abs(shown.values - u)) < 1e-13 * np.max(np.abs(u))


def _counted(monkeypatch):
    """Count every product of an influence operator (products and preconditioner)."""
    count = [0]
    bound = InfluenceOperator.bound

    def counted_bound(self, *args, **kwargs):
        product = bound(self, *args, **kwargs)

        def counted(x, out):
            count[0] += 1
            return product(x, out)

        return counted

    monkeypatch.setattr(InfluenceOperator, "bound", counted_bound)
    # the iterations run as Python, where every product is a call of a bound function
    # (the compiled run is the same loop: test_compiled_iterations_equal_the_python_run)
    monkeypatch.setattr(InfluenceOperator, "compiled_product", lambda self, floor=None: None)
    return count


def _gap(grid: Grid) -> np.ndarray:
    """A quadratic gap [m] whose contact at 2 kN fills about the remembered patches."""
    X, Y = grid.mesh()
    return 4.0 * (X - 0.5 * DX) ** 2 + 6.0 * Y ** 2


@pytest.mark.parametrize("control", [{"load": 2e3}, {"penetration": 2.6e-6}])
def test_a_solve_from_a_shown_displacement_saves_its_first_product(monkeypatch, control):
    """The normal solve started from the memory's ``A p`` (the floored elements' columns
    taken out) takes the same iterations as from a convolution, to the same pressure, with
    one product fewer; its result's displacement is the dense matrix times its pressure."""
    m, grid = two_steps()
    p, shown = previous_start(m, grid, 2e-3)
    floored = int((p < 0).sum())
    assert 0 < floored <= CHANGE_LIMIT
    op = influence_operator(grid, PAIR, "z", FFT)
    h = _gap(grid)
    ref = solve_normal(h, grid, op, initial_pressure=p, tolerance=1e-8, **control)
    count = _counted(monkeypatch)
    res = solve_normal(h, grid, op, initial_pressure=p, initial_displacement=shown,
                       tolerance=1e-8, **control)
    assert res.converged and ref.converged and res.iterations == ref.iterations > 1
    assert count[0] == 2 * res.iterations  # A t and the preconditioner: no start product
    assert np.max(np.abs(res.pressure - ref.pressure)) < 1e-10 * ref.max_pressure
    assert abs(res.penetration - ref.penetration) < 1e-10 * abs(ref.penetration)
    u = (dense(grid) @ res.pressure.ravel()).reshape(grid.shape)
    assert np.max(np.abs(res.displacement.values - u)) < 1e-12 * np.max(np.abs(u))
    assert res.displacement.generations == shown.generations
    assert ref.displacement.generations == 0


def _moved(m: PatchMemory, **fields) -> PatchMemory:
    """``m`` with ``fields`` replaced and its element box formed again."""
    return replace(m, element_box=None, **fields)


def _fallbacks():
    """(name, memory, grid, time) for which the memory gives no ``A p``."""
    m, grid = two_steps()
    o = m.older
    yield "no displacement", two_steps(shown=(True, False))[0], grid, 2e-3
    yield "older without one", two_steps(shown=(False, True))[0], grid, 2e-3
    yield "generations", two_steps(generations=(0, REUSE_GENERATIONS))[0], grid, 2e-3
    yield "c > 1", m, grid, 2.5e-3
    yield "beyond the newer grid", m, Grid(13, 12, DX, DY, -7 * DX, -5 * DY), 2e-3
    yield "beyond the older grid", m, Grid(13, 14, DX, DY, -5 * DX, -7 * DY), 2e-3
    # a grid inside both that leaves out a remembered pressure's elements
    yield "cuts the pressure", m, Grid(10, 12, DX, DY, -4 * DX, -5 * DY), 2e-3
    yield "off the lattice", m, Grid(13, 12, DX, DY, -5 * DX, -5.5 * DY), 2e-3
    nan = m.displacement.values.copy()
    nan[3, 4] = np.nan
    yield "NaN", _moved(m, displacement=Displacement(nan)), grid, 2e-3
    gone = _moved(m, pressure=np.zeros(m.grid.shape), displacement=Displacement(
        np.zeros(m.grid.shape)))
    yield "no pressure left", gone, grid, 2e-3
    small = Displacement(m.displacement.values[:-1])
    yield "shape", _moved(m, displacement=small), grid, 2e-3
    assert o.displacement is not None


@pytest.mark.parametrize("case", list(_fallbacks()), ids=lambda c: c[0])
def test_previous_start_falls_back_to_the_floored_pressure(case):
    """Where ``A p`` cannot be formed from the memory exactly, the start has no
    displacement and its pressure is :func:`previous_pressure`'s, bit for bit."""
    _, m, grid, time = case
    p, shown = previous_start(m, grid, time)
    assert shown is None
    assert np.array_equal(p, previous_pressure(m, grid, time))


def test_a_step_without_extrapolation_needs_no_older_displacement():
    """``c = 0`` (a later load pass of the same step): ``A p`` is the newer step's alone."""
    m, grid = two_steps(shown=(False, True))
    p, shown = previous_start(m, grid, 1e-3)
    assert shown is not None
    u = (dense(grid) @ p.ravel()).reshape(grid.shape)
    assert np.max(np.abs(shown.values - u)) < 1e-13 * np.max(np.abs(u))


def _start_cases():
    m, grid = two_steps()
    p, shown = previous_start(m, grid, 2e-3)
    many = p.copy()
    many[many == 0] = -1.0  # more floored elements than CHANGE_LIMIT columns
    assert (many < 0).sum() > CHANGE_LIMIT
    u_many = (dense(grid) @ many.ravel()).reshape(grid.shape)
    bad = shown.values.copy()
    bad[0, 0] = np.inf
    yield "many floored", many, Displacement(u_many, 1), {}
    yield "not finite", p, Displacement(bad, 1), {}
    yield "too old", p, Displacement(shown.values, REUSE_GENERATIONS + 1), {}
    yield "wrong shape", p, Displacement(shown.values[:, :-1], 1), {}
    yield "initial contact", p, shown, {"initial_contact": np.ones(grid.shape, bool)}


@pytest.mark.parametrize("case", list(_start_cases()), ids=lambda c: c[0])
def test_solve_normal_convolves_a_start_it_cannot_take(monkeypatch, case):
    """A shown displacement that cannot be used as it is: the start's ``A p`` is
    convolved (one product more), the solve as without it."""
    _, p, shown, extra = case
    m, grid = two_steps()
    op = influence_operator(grid, PAIR, "z", FFT)
    h = _gap(grid)
    ref = solve_normal(h, grid, op, initial_pressure=p, load=2e3, tolerance=1e-8, **extra)
    count = _counted(monkeypatch)
    res = solve_normal(h, grid, op, initial_pressure=p, load=2e3, tolerance=1e-8,
                       initial_displacement=shown, **extra)
    assert count[0] == 1 + 2 * res.iterations
    assert res.iterations == ref.iterations
    assert np.array_equal(res.pressure, ref.pressure)  # the same operations
    assert res.displacement.generations == 0


def test_time_steps_reuse_the_displacements_and_solve_as_from_a_convolution():
    """The hunting wheelset's warm steps (S1002/60E1, 1 ms): normal solves start from the
    remembered displacements, and each such solve, repeated with its start's ``A p``
    convolved, takes the same iterations to the same pressure (to round-off)."""
    import railcontact.contact.patch as patch_module
    from railcontact.geometry.profiles import read_profile
    from railcontact.geometry.track import Pose, Track, Wheelset
    from railcontact.timestep.wheelset import ContactSettings, Kinematics, WheelsetContact

    calls = []
    solve = patch_module.solve_normal
    step = [0]

    def recorded(gap, grid, op, **kw):
        res = solve(gap, grid, op, **kw)
        calls.append((gap, grid, op, kw, res, step[0]))
        return res

    wc = WheelsetContact(Track(read_profile("60E1", "rail"), math.atan(1 / 40)),
                         Wheelset(read_profile("S1002", "wheel"), 0.46),
                         ElasticPair.of(Material(206e9, 0.28), Material(206e9, 0.28)),
                         ContactSettings(friction=0.4, element_size=0.5e-3))
    w = 2 * math.pi * 1.5
    mp = pytest.MonkeyPatch()
    mp.setattr(patch_module, "solve_normal", recorded)
    # (the Python path, whose solves pass through solve_normal: the compiled normal stage
    # forms the same start with the same kernel, bit for bit, test_compiled_stages.py)
    mp.setattr(compiled, "ENABLED", False)
    try:
        for k in range(12):
            t = step[0] = k * 1e-3
            wc.solve(Pose(3e-3 * math.sin(w * t)), loads=(83.3e3, 83.3e3),
                     kinematics=Kinematics(30.0, 3e-3 * w * math.cos(w * t)), time=t)
    finally:
        mp.undo()
    warm = [c for c in calls if c[5] >= 2e-3]  # (steps 0 and 1: no older step yet)
    shown = [c for c in warm if c[3].get("initial_displacement") is not None]
    # (the rest mesh beyond a remembered grid: here the lateral motion is at its fastest;
    # over bench_step's 300 steps 3 of 4 warm solves reuse the displacements)
    assert len(warm) >= 20 and len(shown) >= len(warm) // 3
    for gap, grid, op, kw, res, _ in shown:
        ref = solve(gap, grid, op, **{**kw, "initial_displacement": None})
        assert res.iterations == ref.iterations
        assert np.max(np.abs(res.pressure - ref.pressure)) < 1e-11 * ref.max_pressure


def test_two_patch_and_penetration_control_steps_start_from_exact_displacements():
    """Warm steps the hunting test does not reach - a wheel with two
    patches (flange root and tread, S1002/60E1 at 5.1 mm, 12 kN), then penetration control
    with the time restarted (the memory's step lies ahead: no extrapolation). Every start
    given with a displacement has ``A p`` of its pressure as the operator convolves it, and
    its solve takes the iterations of the one from a convolved start, to its pressure."""
    import railcontact.contact.patch as patch_module
    from railcontact.geometry.profiles import read_profile
    from railcontact.geometry.track import Pose, Track, Wheelset
    from railcontact.timestep.wheelset import ContactSettings, Kinematics, WheelsetContact

    calls = []
    solve = patch_module.solve_normal

    def recorded(gap, grid, op, **kw):
        res = solve(gap, grid, op, **kw)
        calls.append((gap, grid, op, kw, res))
        return res

    wc = WheelsetContact(Track(read_profile("60E1", "rail"), math.atan(1 / 40)),
                         Wheelset(read_profile("S1002", "wheel"), 0.46),
                         ElasticPair.of(Material(206e9, 0.28), Material(206e9, 0.28)),
                         ContactSettings(friction=0.4, element_size=0.5e-3))
    mp = pytest.MonkeyPatch()
    mp.setattr(patch_module, "solve_normal", recorded)
    mp.setattr(compiled, "ENABLED", False)  # (the Python path, as above)
    try:
        for k in range(6):
            t = k * 1e-3
            wc.solve(Pose(5.1e-3 + 0.1e-3 * math.sin(2 * math.pi * 20 * t)),
                     loads=(12e3, 12e3), kinematics=Kinematics(30.0, 0.0), time=t)
            assert len(wc.memory.left) == 2
        loaded = len(calls)
        for k in range(4):
            wc.solve(Pose(2e-3 + 0.1e-4 * k), vertical=-3e-4,
                     kinematics=Kinematics(30.0, 0.0), time=k * 1e-3)
    finally:
        mp.undo()
    shown = [(i, c) for i, c in enumerate(calls)
             if c[3].get("initial_displacement") is not None]
    assert sum(i < loaded for i, _ in shown) >= 8 and sum(i >= loaded for i, _ in shown) >= 4
    for _, (gap, grid, op, kw, res) in shown:
        start = np.ascontiguousarray(kw["initial_pressure"])
        u = op.apply(start)
        assert np.max(np.abs(kw["initial_displacement"].values - u)) < 1e-12 * np.max(
            np.abs(u))
        ref = solve(gap, grid, op, **{**kw, "initial_displacement": None})
        assert res.iterations == ref.iterations
        assert np.max(np.abs(res.pressure - ref.pressure)) < 1e-11 * ref.max_pressure
