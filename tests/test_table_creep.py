"""Normalised creep tables (``[table] kind = "creep"``): the creep coefficients of the
exact solver's linear limit against Kalker's published Table E.3, the full-slip limit
|F| = mu N, the similarity the normalisation rests on (one table for every load, friction
and modulus: :class:`CreepTable` against ``railcontact solve`` of a physical state), the
out-of-range policies, show/export/plot, and bad specs."""

from __future__ import annotations

import csv
import math
import re

import numpy as np
import pytest

pytest.importorskip("xarray")
pytest.importorskip("zarr")

from railcontact.cli import main  # noqa: E402
from railcontact.contact.dispatch import solve  # noqa: E402
from railcontact.errors import CaseError, RailContactError  # noqa: E402
from railcontact.halfspace.hertz import hertz  # noqa: E402
from railcontact.halfspace.materials import ElasticPair, Material  # noqa: E402
from railcontact.table import ContactTable, CreepTable, GeometryTable, parse_spec  # noqa: E402
from railcontact.table.creep import build_creep_table, linear_coefficients  # noqa: E402
from railcontact.table.creepspec import curvatures, parse_creep_spec, scales  # noqa: E402
from railcontact.tangential.kalker import creep_coefficients  # noqa: E402

NU = 0.25
"""Kalker's Table E.3 has columns nu = 0, 0.25, 0.5: at 0.25 and at its rows g = a/b or
b/a = 0.2, 0.5, 1 the coefficients are his printed numbers, no interpolation."""
RATIOS = [0.2, 0.5, 1.0, 2.0, 5.0]
GRID = 64


def _raw(table=None, n=GRID, **case):
    raw = {"name": "creep", "material": {"young": 206e9, "poisson": NU},
           "grid": {"nx": n, "ny": n}, "tangential": {"friction": 0.3, "tolerance": 1e-4},
           "table": {"kind": "creep", "ellipse_ratio": {"values": RATIOS},
                     "creepage_x": {"values": [0.0, 0.25, 4.0]},
                     "spin": {"values": [0.0, 0.5]},
                     "out_of_range": {"creepage_x": "clamp"}}}
    raw["table"].update(table or {})
    raw.update(case)
    return raw


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    spec = parse_creep_spec(_raw())
    out = tmp_path_factory.mktemp("creep") / "creep.zarr"
    rep = build_creep_table(spec, out, progress=False)
    assert rep.not_converged == 0 and rep.points == 5 * 3 * 2
    return spec, out


def _errors(coefficients: dict[float, dict[str, float]]) -> np.ndarray:
    """Relative differences of C11, C22, C23 from Kalker's Table E.3 at each ratio."""
    out = []
    for r, c in coefficients.items():
        k = creep_coefficients(r, 1.0, NU)
        out += [c["c11"] / k.c11 - 1, c["c22"] / k.c22 - 1, c["c23"] / k.c23 - 1]
    return np.array(out)


def test_creep_coefficients_against_kalkers_table(table):
    """The table's C11, C22, C23 (the exact BEM's linear limit, 64 x 64 elements over the
    potential area) within 3 % of Kalker's Table E.3 at a/b = 0.2 .. 5, and closer than on
    32 x 32 elements. The tolerance is the discretisation error measured by refinement:
    the piecewise-constant BEM converges to Kalker's values from above, slowly (the
    no-slip traction is singular at the trailing edge); at 32, 64, 128 elements the
    differences at these ratios are 1.8-4.8 %, 0.7-2.6 %, 0.5-1.5 % (Kalker's numbers
    have three digits). C32 equals C23 by reciprocity, to the same discretisation."""
    import xarray as xr

    spec, out = table
    ds = xr.open_zarr(str(out), consolidated=False)
    fine = {r: {n: float(ds[n].values[k]) for n in ("c11", "c22", "c23", "c32")}
            for k, r in enumerate(RATIOS)}
    err = _errors(fine)
    assert np.all(err > 0) and np.abs(err).max() < 0.03, err
    for c in fine.values():
        assert c["c32"] == pytest.approx(c["c23"], rel=0.05)
    coarse_spec = parse_creep_spec(_raw(n=32))
    coarse = {r: linear_coefficients(coarse_spec, r) for r in RATIOS}
    assert np.sqrt(np.mean(err**2)) < np.sqrt(np.mean(_errors(coarse) ** 2))
    for n in ("kalker_c11", "kalker_c22", "kalker_c23"):  # the normalisation's
        assert ds[n].values == pytest.approx(
            [getattr(creep_coefficients(r, 1.0, NU), n[7:]) for r in RATIOS], rel=1e-12)


def test_c33_extrapolated_to_zero_element_size_matches_kalker(table):
    """C33 (the spin moment of spin) converges to the literature's C33 beside Kalker's
    Table E.3 at first order in the element size: at a/b = 0.2, 1, 5 (nu = 0.25) the
    64- and 128-element values differ from it by 3-36 % and 2-19 %, their Richardson
    extrapolation 2 C33(128) - C33(64) by < 2 % (3 % allowed: the extrapolation assumes
    the first order, seen at a/b = 5 where successive differences halve)."""
    import xarray as xr

    _, out = table
    ds = xr.open_zarr(str(out), consolidated=False)
    fine = parse_creep_spec(_raw(n=128))
    for r in (0.2, 1.0, 5.0):
        c64 = float(ds["c33"].sel(ellipse_ratio=r))
        c128 = linear_coefficients(fine, r)["c33"]
        kalker = creep_coefficients(r, 1.0, NU).c33
        assert abs(c128 - kalker) < abs(c64 - kalker)
        assert (2 * c128 - c64) == pytest.approx(kalker, rel=0.03), (r, c64, c128)


def test_full_slip_gives_coulomb_and_linear_theory_at_small_creepage(table):
    """At nu_x = 4 every element slips: F_x = -mu N (the sum of mu p) to the solver's
    tolerance, F_y = 0 by symmetry. At nu_x = 0.25 the force lies below the linear
    theory's 3 nu_x (saturation) and above Kalker's simplified theory's 1 - (1 - nu_x)^3
    scaled by the BEM's C11 excess (< 3 %)."""
    import xarray as xr

    _, out = table
    ds = xr.open_zarr(str(out), consolidated=False).sel(spin=0.0)
    slip = ds.sel(creepage_x=4.0)
    assert np.abs(slip["force_x"].values + 1.0).max() < 1e-3
    assert np.abs(slip["force_y"].values).max() < 1e-3
    assert np.all(slip["slip_area"].values == 1.0)
    small = -ds["force_x"].sel(creepage_x=0.25).values
    assert np.all(small < 0.75) and np.all(small > (1 - 0.75**3) * 0.97)
    assert np.all(ds["force_x"].sel(creepage_x=0.0).values == 0.0)


def _physical(ratio, load, friction, young, k_curv=7.0):
    """A physical Hertzian contact of ellipse ratio ``ratio``: its case dictionary (no
    creepage yet), semi-axes and shear modulus."""
    A, B = (k_curv * x / min(curvatures(ratio)) for x in curvatures(ratio))
    pair = ElasticPair.of(Material(young=young, poisson=NU))
    hz = hertz(A, B, pair, load=load)
    case = {"name": "state", "material": {"young": young, "poisson": NU},
            "geometry": {"type": "quadratic", "A": A, "B": B}, "grid": {"nx": GRID, "ny": GRID},
            "normal": {"load": load},
            "tangential": {"creepage": [0.0, 0.0, 0.0], "friction": friction,
                           "tolerance": 1e-4}}
    return case, hz.a, hz.b, pair.shear


@pytest.mark.parametrize("ratio", [1.0, 2.0])
def test_reader_at_a_node_equals_the_exact_solve_of_another_contact(table, ratio):
    """The similarity of Hertzian rolling: another load, friction, modulus and size than
    the build's, at a node's normalised creepages, gives the same F/(mu N) - the table's
    forces equal ``railcontact solve`` of that physical state to the solver's tolerance."""
    _, out = table
    tab = CreepTable(out)
    case, a, b, g = _physical(ratio, load=42e3, friction=0.45, young=190e9)
    sc = scales(a, b, 42e3, 0.45, g, NU)
    xi, _, phi = sc.physical([0.25, 0.0, 0.5])
    case["tangential"]["creepage"] = [xi, 0.0, phi]
    p = solve(case).patches[0]
    got = tab.forces(a, b, 42e3, 0.45, g, xi, 0.0, phi, poisson=NU)
    assert got.creepages["ellipse_ratio"] == pytest.approx(ratio, rel=1e-12)
    assert got.force_x == pytest.approx(p.tangential.force[0], rel=2e-3)
    assert got.force_y == pytest.approx(p.tangential.force[1], rel=2e-3)
    assert got.moment_z == pytest.approx(p.tangential.spin_moment, rel=2e-3)


def test_reader_between_ellipse_ratios(table):
    """Between the nodes a/b = 1 and 2 (at a/b = 1.4) in the linear range (nu_x = 0.25)
    the normalisation by Kalker's C11 makes F/(mu N) nearly independent of a/b (the three
    nodes 0.5, 1, 2 differ by < 1 %): the interpolated force is within 1 % of the exact
    solve there."""
    _, out = table
    tab = CreepTable(out)
    case, a, b, g = _physical(1.4, load=80e3, friction=0.3, young=206e9)
    xi = scales(a, b, 80e3, 0.3, g, NU).physical([0.25, 0.0, 0.0])[0]
    case["tangential"]["creepage"] = [xi, 0.0, 0.0]
    exact = solve(case).patches[0].tangential.force[0]
    assert tab.forces(a, b, 80e3, 0.3, g, xi, 0.0, 0.0).force_x == pytest.approx(exact,
                                                                                   rel=0.01)


def test_out_of_range_policies_and_bad_states(table):
    _, out = table
    tab = CreepTable(out)
    beyond, clamped = tab.normalised({"ellipse_ratio": 1.0, "creepage_x": 9.0})
    at_end, _ = tab.normalised({"ellipse_ratio": 1.0, "creepage_x": 4.0})
    assert clamped == ("creepage_x",) and np.array_equal(beyond, at_end)
    with pytest.raises(RailContactError, match=r"ellipse_ratio = 7 is outside the table "
                                               r"\[0.2, 5\]"):
        tab.normalised({"ellipse_ratio": 7.0})
    with pytest.raises(RailContactError, match="spin = 0.6 is outside"):
        tab.normalised({"ellipse_ratio": 1.0, "spin": 0.6})
    for bad in (math.nan, math.inf, -math.inf):  # rejected even on an axis to clamp
        with pytest.raises(RailContactError, match=r"creepage_x must be finite, got "
                                                   rf"{bad!r}"):
            tab.normalised({"ellipse_ratio": 1.0, "creepage_x": bad})
    with pytest.raises(RailContactError, match="ellipse_ratio must be finite, got nan"):
        tab.normalised({"ellipse_ratio": math.nan})
    with pytest.raises(RailContactError, match=r"give ellipse_ratio \(a/b\)"):
        tab.normalised({"creepage_x": 0.1})
    for bad in (0.0, -1.0):
        with pytest.raises(RailContactError, match=r"ellipse_ratio \(a/b\) must be > 0, "
                                                   rf"got {bad!r}"):
            tab.normalised({"ellipse_ratio": bad})
    with pytest.raises(RailContactError, match="no creepage_y axis"):
        tab.normalised({"ellipse_ratio": 1.0, "creepage_y": 0.1})
    with pytest.raises(RailContactError, match="Poisson's ratio 0.25; the state has 0.28"):
        tab.forces(0.006, 0.006, 1e5, 0.3, 8e10, 0.0, 0.0, 0.0, poisson=0.28)
    with pytest.raises(RailContactError, match="friction must be a finite number > 0"):
        tab.forces(0.006, 0.006, 1e5, 0.0, 8e10, 0.0, 0.0, 0.0)
    # what is not a number (was: TypeError from numpy, or a string taken as a number)
    with pytest.raises(RailContactError, match="creep table: friction must be a number, "
                                               "got None"):
        tab.forces(0.006, 0.006, 1e5, None, 8e10, 0.0, 0.0, 0.0)
    with pytest.raises(RailContactError, match="creep table: eta must be a number, got '0'"):
        tab.forces(0.006, 0.006, 1e5, 0.3, 8e10, 0.0, "0", 0.0)
    with pytest.raises(RailContactError, match="creep table: xi must be a number, got 1j"):
        tab.forces(0.006, 0.006, 1e5, 0.3, 8e10, 1j, 0.0, 0.0)
    with pytest.raises(RailContactError, match="creepage_x must be a number, got None"):
        tab.normalised({"ellipse_ratio": 1.0, "creepage_x": None})
    with pytest.raises(RailContactError, match="a state is a mapping of axis name to value"):
        tab.normalised([1.0, 0.0])
    with pytest.raises(RailContactError, match="not a contact table"):
        ContactTable.open(out)
    with pytest.raises(RailContactError, match=r"is a contact table, not a creep table: "
                                               r"read it with railcontact.table.ContactTable"):
        CreepTable(_store(out.parent, "{}"))
    with pytest.raises(RailContactError, match=r"is a geometry table, not a creep table: "
                                               r"read it with railcontact.table.GeometryTable"):
        CreepTable(_store(out.parent, '{"kind": "geometry"}'))
    with pytest.raises(RailContactError, match=r"is a creep table.*railcontact.table.CreepTable"):
        GeometryTable.open(out)
    # the kind is the identity's (store.kind_of), not a root attribute
    with pytest.raises(RailContactError, match="is a creep table, not a contact table"):
        ContactTable.open(_store(out.parent, '{"kind": "creep"}'))


def _store(folder, identity):
    """A store whose identity (JSON) is ``identity``, without values."""
    import zarr

    from railcontact.table.store import IDENTITY

    out = folder / f"store{abs(hash(identity))}.zarr"
    zarr.open_group(str(out), mode="w", zarr_format=2).attrs[IDENTITY] = identity
    return out


def test_show_export_and_plot(table, tmp_path, capsys):
    import xarray as xr

    _, out = table
    assert main(["table", "show", str(out), "--plot", str(tmp_path / "c.png")]) == 0
    text = capsys.readouterr().out
    assert "creep table" in text and "Poisson's ratio 0.25" in text
    assert "creep coefficients" in text and "creepage_x     [1]    3 from 0 to 4" in text
    assert (tmp_path / "c.png").stat().st_size > 0
    ds = xr.open_zarr(str(out), consolidated=False)
    assert main(["table", "export", str(out), str(tmp_path / "c.csv")]) == 0
    with (tmp_path / "c.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == ds["status"].size
    row = rows[-1]  # the last node: a/b = 5, nu_x = 4, psi = 0.5
    assert float(row["ellipse_ratio"]) == 5.0 and float(row["spin"]) == 0.5
    assert float(row["force_y"]) == float(ds["force_y"].values[-1, -1, -1])
    assert float(row["c11"]) == float(ds["c11"].values[-1])
    assert main(["table", "export", str(out), str(tmp_path / "c.nc")]) == 0
    nc = xr.open_dataset(tmp_path / "c.nc")
    assert np.array_equal(nc["force_x"].values, ds["force_x"].values)
    assert nc.attrs["kind"] == "creep"


@pytest.mark.parametrize("change, match", [
    ({"table": {"ellipse_ratio": None}}, "needs an ellipse_ratio axis"),
    ({"table": {"lateral_displacement": [0.0, 0.001, 2]}}, "unknown axis lateral_disp"),
    ({"table": {"ellipse_ratio": {"values": [0.01, 1.0]}}}, r"each a/b must lie in"),
    ({"table": {"creepage_x": {"values": [0.5, 0.1]}}}, "strictly increasing"),
    ({"table": {"out_of_range": {"load": "clamp"}}}, "load is not an axis"),
    ({"geometry": {"type": "quadratic", "A": 1.0, "B": 1.0}}, "remove \\[geometry\\]"),
    ({"normal": {"penetration": 1e-4}}, "not a penetration"),
    ({"tangential": {"friction": 0.3, "creepage": [0.001, 0, 0]}}, "remove \\[tangential\\] "
                                                                   "creepage"),
    ({"tangential": {"friction": 0.3, "model": "fastsim"}}, "model must be 'bem'"),
    ({"material": {"young": [206e9, 70e9], "poisson": [0.28, 0.33]}}, "quasi-identical"),
])
def test_bad_creep_specs(change, match):
    raw = _raw()
    for key, value in change.items():
        if key == "table":
            for k, v in value.items():
                if v is None:
                    raw["table"].pop(k)
                else:
                    raw["table"][k] = v
        else:
            raw[key] = value
    with pytest.raises(CaseError, match=match):
        parse_creep_spec(raw)


def test_kinds_in_a_contact_spec(tmp_path, capsys):
    """A contact spec's kind: absent or 'contact' the same table (identity); an unknown
    kind, or a creep spec given to the contact spec's parser, is an error naming it; the
    CLI builds a creep spec by its kind."""
    raw = {"name": "c", "material": {"young": 206e9, "poisson": 0.28},
           "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1"},
           "normal": {"load": 80e3},
           "tangential": {"creepage": [0.0, 0.0, 0.0], "friction": 0.3},
           "table": {"creepage_y": [0.0, 0.001, 2]}}
    plain = parse_spec(raw)
    named = parse_spec({**raw, "table": {**raw["table"], "kind": "contact"}})
    assert named.identity() == plain.identity()
    with pytest.raises(CaseError,
                       match="kind must be one of contact, geometry, creep, got 'usetab'"):
        parse_spec({**raw, "table": {**raw["table"], "kind": "usetab"}})
    with pytest.raises(CaseError, match="load_any_spec"):
        parse_spec({**raw, "table": {**raw["table"], "kind": "creep"}})
    spec = tmp_path / "c.toml"
    spec.write_text('[material]\nyoung = 206e9\npoisson = 0.28\n[grid]\nnx = 16\nny = 16\n'
                    '[tangential]\nfriction = 0.3\n[table]\nkind = "creep"\n'
                    'ellipse_ratio = { values = [1.0] }\ncreepage_x = [0.0, 2.0, 2]\n')
    assert main(["table", "build", str(spec), "-o", str(tmp_path / "c.zarr"), "--workers",
                 "0", "--quiet"]) == 0
    assert "creep table" in capsys.readouterr().out
    assert math.isclose(CreepTable(tmp_path / "c.zarr").normalised(
        {"ellipse_ratio": 1.0, "creepage_x": 2.0})[0][0], -1.0, abs_tol=1e-3)


@pytest.mark.parametrize("axis, nodes, words", [
    ("creepage_x", [0.0, 1e6, 2], "[table] creepage_x: the node 1e+06 is, at ellipse_ratio "
     "= 0.5 and the reference load, a longitudinal creepage of "),
    ("spin", [-1e7, 0.0, 2], "[table] spin: the node -1e+07 is, at ellipse_ratio = "),
])
def test_a_creepage_axis_beyond_the_solver_is_refused_by_name(axis, nodes, words):
    """A normalised creepage node whose physical creepage at the reference load exceeds
    the solver's bound (1e3): refused when the spec is read, naming the axis, the node, the
    ellipse ratio and the physical value (was: "[tangential] creepage[0] must be >= -1000
    and <= 1000, got 8700.08" at the build, naming neither the axis nor the node)."""
    raw = {"material": {"young": 206e9, "poisson": 0.28}, "tangential": {"friction": 0.3},
           "table": {"kind": "creep", "ellipse_ratio": {"values": [0.5, 2.0]}, axis: nodes}}
    with pytest.raises(CaseError, match=re.escape(words)) as err:
        parse_creep_spec(raw)
    assert "the solver takes at most +-1000" in str(err.value)
    physical = float(str(err.value).split(" of ")[1].split(";")[0].split()[0])
    assert abs(physical) > 1e3


def test_a_failed_linear_limit_keeps_the_table(tmp_path, monkeypatch, capsys):
    """A linear-limit solve that does not converge (forced at a/b = 2) leaves that ratio's
    exact creep coefficients NaN with status 1, warns, and keeps every node; the nodes
    still read (full slip), and Kalker's coefficients stay."""
    from railcontact.table import creep
    from railcontact.table.interpolate import TableHolesWarning

    real = creep.linear_coefficients

    def failing(spec, ratio):
        if ratio == 2.0:
            raise RailContactError(f"creep table, a/b = {ratio:g}: the linear-limit solve "
                                   "did not converge: forced")
        return real(spec, ratio)

    monkeypatch.setattr(creep, "linear_coefficients", failing)
    spec = parse_creep_spec(_raw({"ellipse_ratio": {"values": [0.5, 2.0]},
                                  "creepage_x": {"values": [0.0, 4.0]},
                                  "spin": {"values": [0.0]}}, n=16))
    out = tmp_path / "creep.zarr"
    with pytest.warns(TableHolesWarning, match="coefficients of 1 ellipse ratio"):
        rep = build_creep_table(spec, out, progress=False)
    assert rep.not_converged == 0 and rep.coefficients_failed == 1
    assert any("forced: its creep coefficients are NaN" in m for m in rep.messages)
    import xarray as xr

    ds = xr.open_zarr(str(out), consolidated=False)
    assert list(ds["coefficient_status"].values) == [0, 1]
    assert np.isfinite(ds["c11"].values[0]) and np.isnan(ds["c11"].values[1])
    k = creep_coefficients(2.0, 1.0, NU)
    assert ds["kalker_c11"].values[1] == pytest.approx(k.c11, rel=1e-12)
    assert (ds["status"].values == 0).all()
    # full slip at nu_x = 4 (> 3): |F_x| = mu N at the ratio without coefficients too
    f, _ = CreepTable(out).normalised({"ellipse_ratio": 2.0, "creepage_x": 4.0})
    assert f[0] == pytest.approx(-1.0, abs=1e-3)
    assert main(["table", "show", str(out)]) == 0
    text = capsys.readouterr().out
    assert "WARNING: the creep coefficients of 1 ellipse ratio(s) are NaN" in text
    row = next(line for line in text.splitlines() if line.split()[:1] == ["2"])
    assert row.count("nan") == 5 and row.endswith("not converged")
    assert "a/b = 2: the linear-limit solve did not converge: forced" in text
