"""DC-FFT convolution against the dense influence matrix."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from railcontact import ElasticPair, Grid, InfluenceOperator, Material, RailContactError
from railcontact.halfspace.influence import coefficients_at
from railcontact.halfspace.operator import HAVE_PYFFTW, influence_operator

FFT_BACKENDS = ["scipy"] + (["pyfftw"] if HAVE_PYFFTW else [])
STEEL = ElasticPair.of(Material(206e9, 0.28))


@pytest.mark.parametrize("backend", FFT_BACKENDS)
@pytest.mark.parametrize("shape", [(1, 7), (5, 5), (16, 9), (32, 20)])
def test_dcfft_equals_dense(backend, shape):
    g = Grid.from_bounds(-2e-3, 3e-3, -1e-3, 1e-3, *shape)
    p = np.random.default_rng(1).uniform(0, 1e9, shape)
    ref = InfluenceOperator(g, STEEL, "z", "dense").apply(p)
    u = InfluenceOperator(g, STEEL, "z", backend).apply(p)
    assert np.max(np.abs(u - ref)) <= 1e-13 * np.max(np.abs(ref))


@pytest.mark.parametrize("backend", FFT_BACKENDS)
def test_block_operator_equals_dense(backend):
    pair = ElasticPair.of(Material(210e9, 0.3), Material(70e9, 0.33))
    g = Grid.from_bounds(0, 1e-3, 0, 2e-3, 11, 8)
    p = np.random.default_rng(2).normal(size=(3, 11, 8))
    ref = InfluenceOperator(g, pair, "xyz", "dense").apply(p)
    u = InfluenceOperator(g, pair, "xyz", backend).apply(p)
    assert np.max(np.abs(u - ref)) <= 1e-13 * np.max(np.abs(ref))


@settings(max_examples=25, deadline=None)
@given(nx=st.integers(1, 12), ny=st.integers(1, 12), aspect=st.floats(0.1, 10.0))
def test_dense_is_the_direct_sum(nx, ny, aspect):
    """The dense matrix is sum_J A(x_I - x_J) p_J written out element by element."""
    g = Grid(nx, ny, 1e-4, 1e-4 * aspect, 0.0, 0.0)
    op = InfluenceOperator(g, STEEL, "z", "dense")
    X, Y = g.mesh()
    p = np.random.default_rng(nx * 13 + ny).uniform(size=(nx, ny))
    direct = np.zeros((nx, ny))
    for i in range(nx):
        for j in range(ny):
            direct += p[i, j] * coefficients_at("zz", X - X[i, j], Y - Y[i, j], g.dx, g.dy,
                                                STEEL)
    assert np.allclose(op.apply(p), direct, rtol=1e-12, atol=0)


def test_cache_returns_same_operator():
    a = influence_operator(Grid(8, 8, 1e-4, 1e-4, 0, 0), STEEL, "z", "scipy")
    b = influence_operator(Grid(8, 8, 1e-4, 1e-4, 5e-3, -1e-3), STEEL, "z", "scipy")
    assert a is b


def test_bad_backend_and_shape():
    g = Grid(4, 4, 1e-4, 1e-4, 0, 0)
    with pytest.raises(RailContactError, match="fft backend"):
        InfluenceOperator(g, STEEL, "z", "cufft")
    with pytest.raises(RailContactError, match="shape"):
        InfluenceOperator(g, STEEL, "z", "dense").apply(np.zeros((3, 4)))


@pytest.mark.skipif(not HAVE_PYFFTW, reason="pyfftw not installed")
def test_fft_plans_are_bounded_and_a_dropped_plan_is_made_again():
    """More grid shapes than MAX_PLANS keep at most MAX_PLANS plans (memory stays bounded
    in a time series of changing patches); an operator whose plan was dropped plans again
    and still equals the dense product."""
    import railcontact.halfspace.operator as operator_module

    g = Grid.from_bounds(-2e-3, 3e-3, -1e-3, 1e-3, 6, 5)
    op = InfluenceOperator(g, STEEL, "z", "pyfftw")
    p = np.random.default_rng(3).uniform(0, 1e9, (6, 5))
    ref = InfluenceOperator(g, STEEL, "z", "dense").apply(p)
    first = op.apply(p)
    for k in range(operator_module.MAX_PLANS + 3):
        operator_module._fftw_plan(1, (4, 2 * k + 2))
    plans = operator_module._local.plans
    assert len(plans) == operator_module.MAX_PLANS and (1, (12, 10)) not in plans
    again = op.apply(p)  # its plan was dropped: planned anew (FFTW's wisdom: same bits)
    assert np.max(np.abs(again - ref)) <= 1e-13 * np.max(np.abs(ref))
    assert np.array_equal(again, first)
