"""The compiled sums in numpy's order (railcontact.halfspace.sums) against numpy's own."""

import numpy as np
import pytest

from railcontact.halfspace.sums import numpy_sum, pairwise_sum


@pytest.mark.parametrize("seed", range(4))
def test_numpy_sum_is_numpys_to_the_bit(seed):
    rng = np.random.default_rng(seed)
    for _ in range(300):
        shape = tuple(int(v) for v in rng.integers(1, 120, rng.integers(1, 4)))
        a = rng.normal(size=shape) * 10.0 ** rng.integers(-8, 9)
        a[rng.random(shape) < rng.random()] = 0.0  # contact-like fields: many zeros
        assert np.float64(numpy_sum(a)).tobytes() == a.sum().tobytes()  # (the sign of 0 too)


@pytest.mark.parametrize("n", [0, 1, 7, 8, 9, 127, 128, 129, 130, 1000, 4097, 70_001])
def test_pairwise_sum_of_runs(n):
    rng = np.random.default_rng(n)
    a = rng.normal(size=n + 5) * 1e6
    assert pairwise_sum(a, 3, n) == a[3:3 + n].sum()


@pytest.mark.parametrize("shape", [(1,), (5,), (8,), (300,), (3, 200)])
def test_sum_of_negative_zeros_is_numpys_zero(shape):
    """numpy's reduction adds the pairwise sum to +0.0: a field of -0.0 sums to +0.0."""
    a = np.full(shape, -0.0)
    assert np.float64(numpy_sum(a)).tobytes() == a.sum().tobytes() == np.float64(0.0).tobytes()


def test_sum_sees_nan_and_infinity():
    a = np.ones((40, 30))
    a[7, 3] = np.nan
    assert np.isnan(numpy_sum(a))
    a[7, 3] = np.inf
    assert numpy_sum(a) == np.inf


def test_array_sum_is_numpys_sum_contiguous_or_not():
    """``array_sum``: numpy's sum, compiled for a C-contiguous array, numpy's own for a
    strided view (a transpose), the same bits either way."""
    from railcontact.halfspace.sums import array_sum

    a = np.random.default_rng(5).normal(size=(37, 53)) * 1e6
    for v in (a, a.T, a[::2]):
        assert np.float64(array_sum(v)).tobytes() == np.float64(v.sum()).tobytes()
