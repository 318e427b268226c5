"""Hertz's solution against published values and closed forms."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from railcontact import ElasticPair, Material, RailContactError, hertz
from railcontact.halfspace.hertz import axis_ratio, curvature_ratio

# Hertz/Timoshenko m, n, r table (docs/algorithms.md Sec. 1.2; classical values at 30 and 45 deg).
TABLE = [  # theta [deg], m, n, r
    (5, 11.2381, 0.2381, 0.2969), (10, 6.6115, 0.3110, 0.4280), (30, 2.7306, 0.4931, 0.7263),
    (45, 1.9265, 0.6038, 0.8547), (60, 1.4858, 0.7171, 0.9376), (90, 1.0, 1.0, 1.0),
]


@pytest.mark.parametrize("theta, m, n, r", TABLE)
def test_mnr_table(theta, m, n, r):
    c = math.cos(math.radians(theta))  # cos(theta) = (B - A)/(A + B)
    A, B = 1.0 - c, 1.0 + c
    pair = ElasticPair.from_shear(80e9, 0.3)
    h = hertz(A, B, pair, load=1000.0)
    s = (3 * 1000.0 / (4 * pair.e_star * (A + B))) ** (1 / 3)
    assert h.a / s == pytest.approx(m, rel=1e-4)
    assert h.b / s == pytest.approx(n, rel=2e-4)
    d = h.penetration / ((3 * 1000.0 / (4 * pair.e_star)) ** (2 / 3) * (A + B) ** (1 / 3))
    assert d == pytest.approx(r, rel=2e-4)


def test_contact_fastsim_example():
    """CONTACT examples/fastsim: a = 8 mm, b = 4 mm, N = 82 kN, G = 82 GPa, nu = 0.28."""
    pair = ElasticPair.from_shear(82e9, 0.28)
    h = hertz(0.84642, 2.40616, pair, load=82e3)
    assert h.a == pytest.approx(8.000e-3, rel=1e-4)
    assert h.b == pytest.approx(4.000e-3, rel=1e-4)
    assert h.penetration == pytest.approx(0.092669e-3, rel=1e-4)
    assert h.max_pressure == pytest.approx(1223.5e6, rel=1e-4)


def test_contact_tractcurv_example():
    """CONTACT examples/tractcurv: A = 0.8e-3 /mm, B = 0.2814e-3 /mm, N = 106.7 kN."""
    h = hertz(0.8, 0.2814, ElasticPair.from_shear(82e9, 0.28), load=106.7e3)
    assert h.a == pytest.approx(6.304e-3, rel=5e-4)
    assert h.b == pytest.approx(12.61e-3, rel=5e-4)
    assert h.penetration == pytest.approx(7.652e-5, rel=5e-4)


def test_sphere_closed_form():
    """N = (4/3) E* sqrt(R) delta^(3/2), a = sqrt(R delta) for a sphere on a plane."""
    R, delta = 0.05, 2e-5
    mat = Material(210e9, 0.3)
    pair = ElasticPair.of(mat)
    e_star = mat.young / (2 * (1 - mat.poisson**2))
    h = hertz(1 / (2 * R), 1 / (2 * R), pair, penetration=delta)
    assert pair.e_star == pytest.approx(e_star, rel=1e-14)
    assert h.load == pytest.approx(4 / 3 * e_star * math.sqrt(R) * delta**1.5, rel=1e-12)
    assert h.a == pytest.approx(math.sqrt(R * delta), rel=1e-12)
    assert h.b == pytest.approx(h.a, rel=1e-12)


def test_two_materials_combined_modulus():
    """1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 for dissimilar bodies (Johnson)."""
    m1, m2 = Material(210e9, 0.3), Material(70e9, 0.33)
    pair = ElasticPair.of(m1, m2)
    expected = 1 / ((1 - 0.3**2) / 210e9 + (1 - 0.33**2) / 70e9)
    assert pair.e_star == pytest.approx(expected, rel=1e-12)
    assert pair.difference != 0.0
    assert ElasticPair.of(m1).difference == 0.0


@settings(max_examples=60, deadline=None)
@given(A=st.floats(0.05, 50.0), B=st.floats(0.05, 50.0), load=st.floats(1.0, 2e5))
def test_identities(A, B, load):
    pair = ElasticPair.of(Material(206e9, 0.28))
    h = hertz(A, B, pair, load=load)
    # A a^2 + B b^2 = delta, p0 = 3N/(2 pi a b), the long axis across the smaller curvature
    assert A * h.a**2 + B * h.b**2 == pytest.approx(h.penetration, rel=1e-9)
    assert h.max_pressure == pytest.approx(3 * load / (2 * math.pi * h.a * h.b), rel=1e-12)
    assert (h.a >= h.b) == (A <= B) or math.isclose(h.a, h.b, rel_tol=1e-9)
    back = hertz(A, B, pair, penetration=h.penetration)
    assert back.load == pytest.approx(load, rel=1e-9)


@given(g=st.floats(0.01, 1.0))
def test_axis_ratio_inverts_curvature_ratio(g):
    assert axis_ratio(curvature_ratio(g)) == pytest.approx(g, rel=1e-8)


def test_pressure_field():
    h = hertz(1.0, 5.0, ElasticPair.of(Material(206e9, 0.28)), penetration=1e-4)
    x = np.array([0.0, h.a / 2, h.a * 1.01])
    p = h.pressure(x, np.zeros(3))
    assert p[0] == h.max_pressure
    assert p[1] == pytest.approx(h.max_pressure * math.sqrt(0.75))
    assert p[2] == 0.0


@pytest.mark.parametrize("kwargs, match", [
    (dict(A=-1.0, B=5.0, load=1e3), "curvature A"),
    (dict(A=1.0, B=0.0, load=1e3), "curvature B"),
    (dict(A=1.0, B=5.0, load=-5.0), "load"),
    (dict(A=1.0, B=5.0, load=float("nan")), "load"),
    (dict(A=1.0, B=5.0, penetration=float("inf")), "penetration"),
    (dict(A=1.0, B=5.0), "exactly one"),
    (dict(A=1.0, B=5.0, load=1.0, penetration=1e-5), "exactly one"),
])
def test_bad_input(kwargs, match):
    pair = ElasticPair.of(Material(206e9, 0.28))
    with pytest.raises(RailContactError, match=match):
        hertz(pair=pair, **kwargs)


def test_bad_material():
    with pytest.raises(RailContactError, match="poisson"):
        Material(206e9, 0.5)
    with pytest.raises(RailContactError, match="young"):
        Material(-1.0, 0.3)


@pytest.mark.parametrize("r", [1.0 + 1e-9, 1.0 + 1e-4, 1.37, 4.2, 27.0, 950.0, 3.1e5, 1e9])
def test_axis_ratio_solves_the_shape_equation_to_round_off(r):
    # within the table that starts Newton's method (g >= 1e-4) and beyond it (Brent's): the
    # ratio of the root is r but for a few ulp of m (times the slope) or of r (evaluation)
    g = axis_ratio(r)
    m = 1.0 - g * g
    h = 1e-6 * min(m, 1.0 - m)
    slope = (curvature_ratio(math.sqrt(1.0 - m - h)) - curvature_ratio(math.sqrt(1.0 - m + h))
             ) / (2 * h)
    assert abs(curvature_ratio(g) - r) <= max(8 * np.spacing(m) * slope, 16 * np.spacing(r))
