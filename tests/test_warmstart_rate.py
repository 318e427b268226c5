"""The warm start's smoothed traction rate (timestep/warmstart.py, ``traction_rate``).

A traction field known in closed form - changing linearly or quadratically in time on a
patch grid that moves by whole elements from step to step - is remembered step by step as
the time step remembers it (``PatchMemory`` with the rate of ``traction_rate``), and the
warm start's prediction ``previous_tangential`` is compared with the exact field at the
next step:

* a field changing linearly in time is predicted exactly (as by the plain extrapolation
  ``2 p_k - p_{k-1}``);
* with independent iteration errors of standard deviation s added to every step's field,
  the plain extrapolation's error has the standard deviation ``sqrt(5) s`` and the smoothed
  rate's (gain 1/2) ``sqrt(7/3) s``: the noise in the variance sums of the two linear
  filters (module docstring of the test below);
* the price: a rate that itself changes (constant second derivative a, step dt) lags, and
  the prediction misses by ``(1 + (1 - g) / g) a dt^2`` instead of ``a dt^2``.
"""

import math

import numpy as np
import pytest

from railcontact.halfspace.grid import Grid, remesh
from railcontact.timestep.warmstart import (
    PatchMemory,
    previous_tangential,
    traction_rate,
)

DX, DY, DT = 0.5e-3, 0.4e-3, 1e-3
NX, NY = 24, 20


def _grid(k: int) -> Grid:
    """The patch grid of step k: moves by whole elements, as a warm step's grids do."""
    return Grid(NX, NY, DX, DY, (k % 3 - 1) * DX, (k % 2) * DY)


def _common(grid: Grid) -> np.ndarray:
    """The elements of ``grid`` that every step's grid covers (outside a grid the
    remembered fields are zero)."""
    x, y = grid.mesh()
    e = 1e-3 * DX
    return (x > DX - e) & (x < (NX - 2) * DX + e) & (y > DY - e) & (y < (NY - 1) * DY + e)


def _field(grid: Grid, t: float, accel: float = 0.0) -> np.ndarray:
    """A smooth traction (2, nx, ny) [Pa] changing linearly (and with ``accel`` [Pa/s^2]
    quadratically) in time at every point of the plane."""
    x, y = grid.mesh()
    a = 1e8 * np.cos(300 * x) * np.exp(-((y / 4e-3) ** 2))
    b = 2e10 * (1 + 100 * x - 50 * y)  # [Pa/s]
    return np.stack([a + b * t + 0.5 * accel * t**2, -0.5 * a + 0.3 * b * t])


def _run(steps: int, noise: float, gain: float | None, accel: float = 0.0,
         seed: int = 0) -> np.ndarray:
    """Errors (prediction - exact field) at steps 3 .. steps of a run in which every
    step's remembered traction is the exact field plus independent noise [Pa] (std
    ``noise``); ``gain`` None: the plain linear extrapolation (no rate remembered)."""
    rng = np.random.default_rng(seed)
    memory, errors = None, []
    for k in range(steps):
        grid, t = _grid(k), k * DT
        exact = _field(grid, t, accel)
        if memory is not None and k >= 3:
            start, _ = previous_tangential(memory, grid, t)
            errors.append((start - exact)[:, _common(grid)])
        solved = exact + rng.normal(scale=noise, size=exact.shape) if noise else exact
        older = None if memory is None else PatchMemory(
            memory.grid, memory.pressure, memory.traction, memory.state, 0.0, 0.0,
            time=memory.time, traction_rate=memory.traction_rate)  # (its own older dropped)
        rate = None if gain is None else traction_rate(solved, grid, t, older, gain)
        memory = PatchMemory(grid, np.ones(grid.shape), solved,
                             np.ones(grid.shape, dtype=np.int8), 0.0, 0.0, time=t,
                             older=older, traction_rate=rate)
    return np.stack(errors)  # (step, component, element)


@pytest.mark.parametrize("gain", [None, 0.5, 0.3, 1.0])
def test_linear_change_is_predicted_exactly(gain):
    scale = np.abs(_field(_grid(0), 20 * DT)).max()
    assert np.abs(_run(20, 0.0, gain)).max() < 1e-9 * scale


def test_iteration_noise_is_carried_less_than_by_the_plain_extrapolation():
    """Noise n_k (std s, independent): the plain start ``2 p_k - p_{k-1}`` carries
    ``2 n_k - n_{k-1}``, variance 5 s^2. The smoothed rate (gain 1/2),
    ``dt v_k = dt v_{k-1} / 2 + (p_k - p_{k-1}) / 2``, gives the start ``p_k + dt v_k``
    the noise ``3/2 n_k - sum_{m>=1} (1/2)^(m+1) n_{k-m}``, variance
    ``9/4 + (1/16) / (1 - 1/4) = 7/3`` s^2 (after the first steps)."""
    s = 1e6
    plain = _run(40, s, None)
    smoothed = _run(40, s, 0.5)
    assert np.std(plain) / s == pytest.approx(math.sqrt(5), rel=0.03)
    # (the first rates, formed from fewer steps, carry a little more of the noise)
    assert np.std(smoothed[5:]) / s == pytest.approx(math.sqrt(7 / 3), rel=0.03)
    assert np.std(smoothed) < 0.72 * np.std(plain)


@pytest.mark.parametrize("gain", [0.5, 0.25])
def test_a_changing_rate_lags_by_the_documented_steps(gain):
    """p = a t^2 / 2: the plain extrapolation misses p_{k+1} by a dt^2; the exponential
    average of the changes lags them by (1 - g) / g steps, each a dt^2 behind: the miss
    tends to (1 + (1 - g) / g) a dt^2."""
    accel = 4e13  # [Pa/s^2]
    steps = 60
    plain = _run(steps, 0.0, None, accel)
    smoothed = _run(steps, 0.0, gain, accel)
    miss = accel * DT**2
    assert np.allclose(plain[:, 0], -miss, rtol=1e-6, atol=0)
    assert np.allclose(smoothed[-1, 0], -(1 + (1 - gain) / gain) * miss, rtol=1e-6, atol=0)
    assert np.allclose(smoothed[:, 1], 0.0, atol=1e-9 * miss)  # (no acceleration in y)


def test_rate_needs_an_older_step_with_traction_and_time():
    g = _grid(0)
    t = _field(g, 1e-3)
    older = PatchMemory(g, np.ones(g.shape), _field(g, 0.0), np.ones(g.shape, np.int8),
                        0.0, 0.0, time=0.0)
    assert traction_rate(t, g, 1e-3, None) is None
    assert traction_rate(t, g, None, older) is None
    assert traction_rate(t, g, 0.0, older) is None  # not after the older step
    no_traction = PatchMemory(g, np.ones(g.shape), None, None, 0.0, 0.0, time=0.0)
    assert traction_rate(t, g, 1e-3, no_traction) is None
    assert np.allclose(traction_rate(t, g, 1e-3, older), (t - older.traction) / 1e-3)


@pytest.mark.parametrize("seed", range(12))
def test_rate_on_one_lattice_equals_its_remeshed_definition(seed):
    """The one-pass form on one lattice against ``(1 - g) remesh(v) + g (p - remesh(p0))
    / dt``, and an off-lattice older grid through the interpolation."""
    rng = np.random.default_rng(seed)
    nx, ny = (int(n) for n in rng.integers(3, 15, 2))
    dx = DX if seed < 10 else 0.45e-3  # the last two: another lattice
    g0 = Grid(*(int(n) for n in rng.integers(3, 15, 2)), dx, DY,
              float(rng.integers(-5, 6)) * dx, float(rng.integers(-5, 6)) * DY)
    g = Grid(nx, ny, DX, DY, float(rng.integers(-5, 6)) * DX, float(rng.integers(-5, 6)) * DY)
    p0, v0 = rng.normal(size=(2, 2, *g0.shape)) * 1e8
    p = rng.normal(size=(2, nx, ny)) * 1e8
    for rate in (None, v0):
        older = PatchMemory(g0, np.ones(g0.shape), p0, np.ones(g0.shape, np.int8), 0.0, 0.0,
                            time=0.0, traction_rate=rate)
        change = (p - remesh(p0, g0, g)) / 2e-3
        want = change if rate is None else 0.5 * remesh(rate, g0, g) + 0.5 * change
        assert np.allclose(traction_rate(p, g, 2e-3, older, 0.5), want, rtol=1e-12,
                           atol=1e-12 * np.abs(want).max())


def test_a_traction_that_is_not_finite_forms_no_rate():
    """A solve whose traction is not finite leaves no rate (it would stay in every later
    step's average); the next finite step forms one again from the step before it."""
    g = _grid(0)
    ones, st = np.ones(g.shape), np.ones(g.shape, np.int8)
    p0, p1, p2 = (_field(g, k * DT) for k in range(3))
    bad = p1.copy()
    bad[1, 3, 4] = np.nan
    m0 = PatchMemory(g, ones, p0, st, 0.0, 0.0, time=0.0)
    assert traction_rate(bad, g, DT, m0) is None
    m1 = PatchMemory(g, ones, p1, st, 0.0, 0.0, time=DT,
                     traction_rate=np.full((2, *g.shape), np.inf))
    assert traction_rate(p2, g, 2 * DT, m1) is None
    m1 = PatchMemory(g, ones, p1, st, 0.0, 0.0, time=DT)
    assert np.allclose(traction_rate(p2, g, 2 * DT, m1), (p2 - p1) / DT)
