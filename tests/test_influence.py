"""Love's influence coefficients against numerical integration of the point-load kernels."""

import math

import numpy as np
import pytest
from scipy.integrate import dblquad

from railcontact import ElasticPair
from railcontact.halfspace.influence import coefficients_at

PAIR = ElasticPair(shear=1.0, poisson=0.28)

# dblquad values of docs/algorithms.md Sec. 5.1 (nu = 0.28, G = 1, unit squares).
@pytest.mark.parametrize("x, y, zz, xx, yx", [
    (1.0, 0.0, 0.237903, 0.321422, 0.0),
    (2.0, 1.0, 0.103382, 0.135168, 0.015527),
    (3.3, -2.2, 0.057941, 0.073496, -0.010290),
])
def test_published_values(x, y, zz, xx, yx):
    assert coefficients_at("zz", x, y, 1.0, 1.0, PAIR) == pytest.approx(zz, abs=2e-6)
    assert coefficients_at("xx", x, y, 1.0, 1.0, PAIR) == pytest.approx(xx, abs=2e-6)
    assert coefficients_at("yx", x, y, 1.0, 1.0, PAIR) == pytest.approx(yx, abs=2e-6)


KERNELS = {  # point-load kernels times pi G, for nu, at offset (X, Y)
    "zz": lambda X, Y, nu: (1 - nu) / math.hypot(X, Y),
    "xx": lambda X, Y, nu: (1 - nu) / math.hypot(X, Y) + nu * X**2 / math.hypot(X, Y) ** 3,
    "yy": lambda X, Y, nu: (1 - nu) / math.hypot(X, Y) + nu * Y**2 / math.hypot(X, Y) ** 3,
    "xy": lambda X, Y, nu: nu * X * Y / math.hypot(X, Y) ** 3,
}


@pytest.mark.parametrize("block", sorted(KERNELS))
@pytest.mark.parametrize("x, y", [(1.3, 0.1), (-2.0, 0.75), (0.4, -1.9)])
def test_rectangles_against_quadrature(block, x, y):
    """Non-square element 0.8 x 0.5 observed from outside: quadrature of the kernel."""
    dx, dy, nu = 0.8, 0.5, 0.3
    pair = ElasticPair(shear=2.0, poisson=nu)
    f = KERNELS[block]
    val, _ = dblquad(lambda eta, xi: f(x - xi, y - eta, nu), -dx / 2, dx / 2, -dy / 2, dy / 2,
                     epsabs=1e-12, epsrel=1e-10)
    expected = val / (math.pi * pair.shear)
    assert coefficients_at(block, x, y, dx, dy, pair) == pytest.approx(expected, rel=1e-7,
                                                                         abs=1e-12)


def test_self_influence():
    """A_zz(0, 0) = (1 - nu)/(pi G) 4 h ln(1 + sqrt 2) for a square of side h."""
    h = 0.37
    expected = (1 - 0.28) / math.pi * 4 * h * math.log(1 + math.sqrt(2))
    assert coefficients_at("zz", 0.0, 0.0, h, h, PAIR) == pytest.approx(expected, rel=1e-13)


def test_symmetries():
    X = np.array([1.0, -1.0, 1.0, -1.0]) * 2.5
    Y = np.array([1.0, 1.0, -1.0, -1.0]) * 1.5
    zz = coefficients_at("zz", X, Y, 1.0, 0.6, PAIR)
    xy = coefficients_at("xy", X, Y, 1.0, 0.6, PAIR)
    assert np.allclose(zz, zz[0], rtol=1e-13)
    assert np.allclose(xy, xy[0] * np.array([1, -1, -1, 1]), rtol=1e-12)


def test_coupling_blocks():
    """xz/yz vanish for identical materials; for dissimilar ones they are odd in X resp. Y
    and zx = -xz (reciprocity of the difference displacements)."""
    assert np.all(coefficients_at("xz", 2.0, 1.0, 1.0, 1.0, PAIR) == 0.0)
    pair = ElasticPair(shear=1.0, poisson=0.3, difference=0.1)
    a = coefficients_at("xz", np.array([2.0, -2.0]), np.array([1.0, 1.0]), 1.0, 1.0, pair)
    assert a[0] == pytest.approx(-a[1], rel=1e-12) and a[0] != 0.0
    assert coefficients_at("zx", 2.0, 1.0, 1.0, 1.0, pair) == pytest.approx(-a[0], rel=1e-14)
    # -K X/(pi G r^2) integrated over the element
    val, _ = dblquad(lambda eta, xi: -(2.0 - xi) / ((2.0 - xi) ** 2 + (1.0 - eta) ** 2),
                     -0.5, 0.5, -0.5, 0.5, epsabs=1e-12)
    assert a[0] == pytest.approx(0.1 * val / math.pi, rel=1e-8)
