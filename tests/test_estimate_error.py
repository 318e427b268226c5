"""How good a start was: each patch's estimate error against its BEM solution."""

import copy

import numpy as np
import pytest

import railcontact as rc
from railcontact import ElasticPair, Grid, Material, hertz
from railcontact.contact.results import PatchSolution
from railcontact.halfspace.operator import influence_operator
from railcontact.normal import solve_normal
from railcontact.normal.starterror import estimate_error

PAIR = ElasticPair.of(Material(206e9, 0.28))


def hertz_problem(n=48):
    """A Hertz gap (A = 1, B = 5 /m) at 0.1 mm on a grid around its ellipse."""
    hz = hertz(1.0, 5.0, PAIR, penetration=1e-4)
    g = Grid.from_bounds(-1.3 * hz.a, 1.3 * hz.a, -1.3 * hz.b, 1.3 * hz.b, n, n)
    X, Y = g.mesh()
    return g, 1.0 * X**2 + 5.0 * Y**2, influence_operator(g, PAIR, "z")


def test_estimate_error_is_zero_for_a_start_equal_to_the_converged_solution():
    """A solve started from the solution converged to eps_n = 1e-12 (its own grid): the
    patch's estimate error against the new solve is zero - no element missing or extra,
    the L1 error at round-off - and the solve keeps the start it was given."""
    g, h, op = hertz_problem()
    ref = solve_normal(h, g, op, penetration=1e-4, tolerance=1e-12)
    assert ref.converged
    res = solve_normal(h, g, op, penetration=1e-4, tolerance=1e-3,
                       initial_pressure=ref.pressure.copy())
    assert res.converged and res.start is not None
    np.testing.assert_array_equal(res.start, ref.pressure)
    e = PatchSolution(normal=res, estimate="converged").estimate_error
    assert (e.missing, e.extra, e.contact) == (0, 0, int(ref.contact.sum()))
    assert e.l1 < 1e-9
    # and none without a start (the solver's own uniform pressure)
    cold = solve_normal(h, g, op, penetration=1e-4, tolerance=1e-3)
    assert cold.start is None and PatchSolution(normal=cold).estimate_error is None


def test_estimate_error_counts_missing_and_extra_elements():
    """Against a solution p: 1.1 p is 10 % off in L1 with the same contact; p without its
    edge ring (contact elements with a neighbour outside the contact, counted by an
    erosion) misses exactly those elements and is off by their share of the pressure; p
    with one more ring around it adds exactly that ring; negative start values count as
    no pressure."""
    g, h, op = hertz_problem()
    p = solve_normal(h, g, op, penetration=1e-4, tolerance=1e-10).pressure
    c = p > 0
    padded = np.pad(c, 1)
    inner = (padded[1:-1, 1:-1] & padded[:-2, 1:-1] & padded[2:, 1:-1]
             & padded[1:-1, :-2] & padded[1:-1, 2:])
    ring = c & ~inner
    e = estimate_error(1.1 * p, p)
    assert e.l1 == pytest.approx(0.1, rel=1e-12) and (e.missing, e.extra) == (0, 0)
    e = estimate_error(np.where(ring, -1.0, p), p)
    assert (e.missing, e.extra, e.contact) == (int(ring.sum()), 0, int(c.sum()))
    assert e.l1 == pytest.approx(p[ring].sum() / p.sum(), rel=1e-12)
    assert e.missing_share == pytest.approx(ring.sum() / c.sum())
    grown = np.pad(c, 1)
    outer = (grown[1:-1, 1:-1] | grown[:-2, 1:-1] | grown[2:, 1:-1] | grown[1:-1, :-2]
             | grown[1:-1, 2:]) & ~c
    e = estimate_error(np.where(outer, 1e6, p), p)
    assert (e.missing, e.extra) == (0, int(outer.sum()))
    assert e.l1 == pytest.approx(1e6 * outer.sum() / p.sum(), rel=1e-12)
    with pytest.raises(rc.RailContactError, match="shape"):
        estimate_error(p[:-1], p)


def test_estimate_error_in_the_json(root):
    """``solve --json``'s patches report it under ``normal``: the INFCON start of a
    penetration-controlled wheel-rail solve (one solve) against its solution, a start from
    the previous load pass under load control, and none without an estimate."""
    base = rc.load_case(root / "models" / "cases" / "s1002_60e1_dy-2mm.toml").to_dict()
    c = copy.deepcopy(base)
    c["normal"] = {"penetration": 1e-4, "estimate": "infcon", "tolerance": 1e-3}
    d = rc.solve(c).to_dict()["patches"][0]["normal"]["estimate_error"]
    assert d["start"] == "infcon" and 0 < d["l1"] < 0.05
    assert d["missing"] + d["extra"] < 0.15 * d["contact"]
    c["normal"]["estimate"] = "none"
    assert "estimate_error" not in rc.solve(c).to_dict()["patches"][0]["normal"]
    c = copy.deepcopy(base)
    c["normal"]["estimate"] = "infcon"
    d = rc.solve(c).to_dict()["patches"][0]["normal"]["estimate_error"]
    assert d["start"] == "previous load pass" and d["l1"] < 0.05
