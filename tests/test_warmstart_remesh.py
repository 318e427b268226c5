"""The warm start's one-pass re-meshing (timestep/warmstart.py) against its definition:
the previous fields re-meshed by :func:`railcontact.halfspace.grid.remesh` and
extrapolated linearly in time, ``p = max(p_k + c (p_k - p_{k-1}), 0)``."""

import numpy as np
import pytest

from railcontact.halfspace.grid import Grid, remesh
from railcontact.timestep.warmstart import (
    PatchMemory,
    _contact_box,
    previous_pressure,
    previous_tangential,
)

DX, DY = 0.5e-3, 0.4e-3


def _memory(rng, i, j, nx, ny, time, older=None, dx=DX):
    grid = Grid(nx, ny, dx, DY, i * dx, j * DY)
    p = np.where(rng.random((nx, ny)) < 0.6, rng.random((nx, ny)) * 1e9, 0.0)
    t = rng.normal(size=(2, nx, ny)) * 1e8
    st = rng.integers(0, 3, (nx, ny)).astype(np.int8)
    return PatchMemory(grid, p, t, st, 0.0, 0.0, time=time, older=older)


def _expected(m, grid, time):
    p = remesh(m.pressure, m.grid, grid)
    t = remesh(m.traction, m.grid, grid)
    c = m.extrapolation(time)
    if c > 0:
        p = np.maximum(p + c * (p - remesh(m.older.pressure, m.older.grid, grid)), 0.0)
        t = t + c * (t - remesh(m.older.traction, m.older.grid, grid))
    st = np.rint(remesh(m.state.astype(float), m.grid, grid, method="nearest"))
    return p, t, st.astype(np.int8)


@pytest.mark.parametrize("seed", range(40))
def test_warm_start_fields_equal_remesh_and_extrapolation(seed):
    rng = np.random.default_rng(seed)
    nx, ny = (int(n) for n in rng.integers(3, 20, 2))
    older = _memory(rng, *rng.integers(-8, 9, 2), *rng.integers(3, 20, 2), time=0.0)
    m = _memory(rng, *rng.integers(-8, 9, 2), *rng.integers(3, 20, 2), time=1e-3, older=older)
    grid = Grid(nx, ny, DX, DY, float(rng.integers(-8, 9)) * DX, float(rng.integers(-8, 9)) * DY)
    for time in (None, 1e-3, 1.7e-3, 2e-3, 9e-3):  # no extrapolation, c = 0, 0.7, 1, 2 (cap)
        p, t, st = _expected(m, grid, time)
        got_p = previous_pressure(m, grid, time)
        got_t, got_st = previous_tangential(m, grid, time)
        assert got_p.shape == grid.shape and got_p.dtype == float
        assert np.array_equal(got_p, p)  # bit for bit
        assert np.array_equal(got_t, t)
        assert got_st.dtype == np.int8 and np.array_equal(got_st, st)
    assert np.array_equal(previous_pressure(m, m.grid, 1.5e-3),
                          _expected(m, m.grid, 1.5e-3)[0])


def test_warm_start_off_the_lattice_interpolates():
    """Grids off one lattice (another element size) still go through the interpolation."""
    rng = np.random.default_rng(3)
    older = _memory(rng, 0, 0, 10, 8, time=0.0, dx=0.45e-3)
    m = _memory(rng, 1, 0, 10, 8, time=1e-3, older=older)
    grid = Grid(12, 8, DX, DY, 0.0, 0.0)
    p, t, st = _expected(m, grid, 1.5e-3)
    assert np.array_equal(previous_pressure(m, grid, 1.5e-3), p)
    got_t, got_st = previous_tangential(m, grid, 1.5e-3)
    assert np.array_equal(got_t, t) and np.array_equal(got_st, st)


def test_contact_box_of_the_elements_with_pressure():
    grid = Grid(6, 5, DX, DY, 1e-3, -2e-3)
    p = np.zeros(grid.shape)
    assert _contact_box(p, grid) is None
    p[2, 3] = 1.0
    p[4, 1] = np.nan  # (counts, as ndarray.any)
    x0, x1, y0, y1 = _contact_box(p, grid)
    assert np.allclose([x0, x1, y0, y1], [1e-3 + 1.5 * DX, 1e-3 + 4.5 * DX,
                                          -2e-3 + 0.5 * DY, -2e-3 + 3.5 * DY], rtol=0,
                       atol=1e-15)


def test_lattice_offset_as_remesh_takes_it():
    """The warm start's whole-element offset of a grid in the remembered one: the known
    whole-element offset when the element sizes agree to 1e-12 (relative) and the grids
    lie on one lattice to 1e-9 of an element, else None (sizes off by 1e-11 or 10 %, or
    origins off the lattice by about 2e-6 elements)."""
    from railcontact.timestep.warmstart import _on_lattice
    rng = np.random.default_rng(0)
    on = 0
    for _ in range(3000):
        factor = rng.choice([0.0, 1e-13, 1e-11, 0.1]) if rng.random() < 0.2 else 0.0
        dx = DX * (1 + factor)
        a = Grid(5, 6, DX, DY, float(rng.normal() * 1e-2), float(rng.normal() * 1e-2))
        k = rng.integers(-20, 20, 2)
        noisy = rng.random() < 0.2
        off = k * np.array([dx, DY]) + noisy * rng.normal(size=2) * 1e-9
        b = Grid(3, 4, dx, DY, float(a.x0 + off[0]), float(a.y0 + off[1]))
        m = PatchMemory(a, np.zeros(a.shape), None, None, 0.0, 0.0)
        want = (int(k[0]), int(k[1])) if factor <= 1e-13 and not noisy else None
        assert _on_lattice(m, b) == want
        on += want is not None
    assert 0 < on < 3000


@pytest.mark.parametrize("seed", range(12))
def test_traction_along_its_rate_equals_remesh_of_both(seed):
    """The traction advanced along the remembered rate, ``p_k + (t - t_k) v_k``, and the
    map, in one compiled pass on one lattice, equal the fields re-meshed by
    :func:`remesh` (nearest element for the map), bit for bit - for maps of int8, int64
    and bool."""
    rng = np.random.default_rng(100 + seed)
    older = _memory(rng, *rng.integers(-8, 9, 2), *rng.integers(3, 20, 2), time=0.0)
    m = _memory(rng, *rng.integers(-8, 9, 2), *rng.integers(3, 20, 2), time=1e-3, older=older)
    nx, ny = (int(n) for n in rng.integers(3, 20, 2))
    grid = Grid(nx, ny, DX, DY, float(rng.integers(-8, 9)) * DX, float(rng.integers(-8, 9)) * DY)
    rate = rng.normal(size=m.traction.shape) * 1e10
    kinds = (m.state, m.state.astype(np.int64), m.state > 1)
    for time in (1.7e-3, 2e-3, 9e-3):
        h = min((time - 1e-3) / 1e-3, 2.0) * 1e-3
        want_t = remesh(m.traction, m.grid, grid) + h * remesh(rate, m.grid, grid)
        for st in kinds:
            mk = PatchMemory(m.grid, m.pressure, m.traction, st, 0.0, 0.0, 1e-3, older,
                             traction_rate=rate)
            want_st = np.rint(remesh(st.astype(float), m.grid, grid, method="nearest"))
            got_t, got_st = previous_tangential(mk, grid, time)
            assert np.array_equal(got_t, want_t)  # bit for bit
            assert got_st.dtype == np.int8 and np.array_equal(got_st, want_st)


def test_compiled_lattice_offset_equals_its_definition():
    """The lattice offset the warm start's kernels find (compiled) is the one of the
    definition with ``math.isclose`` (sizes to 1e-12 relative, origins to 1e-9 of an
    element), also at the edges of both tolerances."""
    import math

    from railcontact.timestep.warmstart import _lattice_offset

    def definition(a, b):
        if not (math.isclose(a.dx, b.dx, rel_tol=1e-12)
                and math.isclose(a.dy, b.dy, rel_tol=1e-12)):
            return None
        fi, fj = (b.x0 - a.x0) / a.dx, (b.y0 - a.y0) / a.dy
        i, j = round(fi), round(fj)
        return None if abs(fi - i) > 1e-9 or abs(fj - j) > 1e-9 else (i, j)

    rng = np.random.default_rng(7)
    found = 0
    for _ in range(2000):
        rel = rng.choice([0.0, 0.9e-12, 1.1e-12, 1e-3])
        off = rng.choice([0.0, 0.9e-9, 1.1e-9, 0.5])
        a = Grid(4, 5, DX, DY, float(rng.normal() * 1e-2), float(rng.normal() * 1e-2))
        k = rng.integers(-30, 30, 2)
        dx = DX * (1 + rel * rng.choice([-1, 1]))
        b = Grid(3, 3, dx, DY, float(a.x0 + (k[0] + off) * DX), float(a.y0 + k[1] * DY))
        i, j, ok = _lattice_offset(a.dx, a.dy, a.x0, a.y0, b.dx, b.dy, b.x0, b.y0)
        want = definition(a, b)
        assert ((i, j) if ok else None) == want
        found += want is not None
    assert 0 < found < 2000
