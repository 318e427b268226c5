"""The public API the README and the docs show, and the settings: declared once, documented
from the declarations, and the docs (docs/case-files.md, docs/fmu.md, docs/settings.md) and
the FMU in step with them."""

from __future__ import annotations

import ast
import math
import re
from dataclasses import fields

import pytest

import railcontact as rc
from railcontact.cli import settings_reference
from railcontact.errors import CaseError, RailContactError
from railcontact.fmu import variables as V
from railcontact.settings import (
    Case,
    ContactSettings,
    FMUModes,
    MaterialSettings,
    NormalSettings,
    TangentialSettings,
    WheelRailGeometry,
)
from railcontact.settings.fields import default_of
from railcontact.settings.reference import case_keys


def _blocks(text: str, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", text, flags=re.S)


def _page(root, name: str) -> str:
    return (root / name).read_text(encoding="utf-8")


@pytest.mark.parametrize("page", ["README.md", "docs/getting-started.md", "docs/fmu.md"])
def test_every_import_the_readme_and_docs_show_works(root, page):
    """Each import statement of the page's Python blocks runs, and every ``rc.<name>`` it
    uses exists."""
    n = 0
    for block in _blocks(_page(root, page), "python"):
        for node in ast.walk(ast.parse(block)):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                exec(compile(ast.Module([node], []), f"<{page}>", "exec"), {})
                n += 1
        for name in re.findall(r"\brc\.(\w+)", block):
            assert hasattr(rc, name), f"{page} uses rc.{name}, which railcontact lacks"
    assert n >= 1


def test_public_names_of_the_issue_are_top_level():
    for name in ("solve", "solve_normal", "solve_tangential", "WheelsetContact",
                 "ContactSettings", "Kinematics", "load_case", "Case"):
        assert name in rc.__all__ and hasattr(rc, name)


def test_settings_reference_is_generated_and_current(root):
    """docs/settings.md is what ``railcontact settings`` prints (regenerate it with
    ``railcontact settings > docs/settings.md``)."""
    doc = (root / "docs" / "settings.md").read_text(encoding="utf-8")
    assert doc.strip() == settings_reference().strip()


def _case_keys_shown(text: str) -> set[tuple[str, str]]:
    keys = set()
    for block in _blocks(text, "toml"):
        table = ""
        for line in block.splitlines():
            if m := re.match(r"\s*\[(\w+)\]", line):
                table = m.group(1)
            elif m := re.match(r"\s*#?\s*(\w+)\s*=", line):
                keys.add((table, m.group(1)))
    return keys


def test_case_file_page_shows_exactly_the_declared_keys(root):
    page = _page(root, "docs/case-files.md")
    shown = _case_keys_shown(page) - {("", "name"), ("", "convention")}  # top level
    declared = case_keys()
    assert shown - declared == set(), "docs/case-files.md shows keys a case file does not accept"
    assert declared - shown == set(), "docs/case-files.md does not show these case-file keys"


def test_fmu_page_lists_exactly_the_fmu_parameters(root):
    page = _page(root, "docs/fmu.md")
    part = page.split("<!-- fmu-parameters")[1].split("<!-- /fmu-parameters -->")[0]
    listed = {w for w in re.findall(r"`([a-z_]+)`", part)}
    assert listed == {v.name for v in V.PARAMETERS}


def test_fmu_parameters_take_defaults_units_and_meaning_from_the_settings():
    for v, (name, record, key) in zip(V.PARAMETERS, V.PARAMETER_SOURCES, strict=True):
        f = next(f for f in fields(record) if f.name == key)
        default = default_of(f)
        assert v.name == name
        assert v.start == (default[0] if isinstance(default, tuple) else default)
        assert v.description.startswith(f.metadata["spec"].doc.split(" (one value")[0])
    start = V.parameter_settings({v.name: v.start for v in V.PARAMETERS})
    # the FMU finds the rigid wheelset's vertical and roll by default, the API on request
    assert start.contact == ContactSettings(rigid_wheelset="solve")
    assert start.geometry == WheelRailGeometry()
    assert start.material == MaterialSettings()
    assert start.modes == FMUModes()
    # the strings of a modelDescription are read as numbers
    text = V.parameter_settings({v.name: str(v.start) for v in V.PARAMETERS})
    assert text.contact == ContactSettings(rigid_wheelset="solve")


def test_fmu_parameter_errors_name_the_parameter():
    with pytest.raises(RailContactError, match="parameter flange_back_distance"):
        V.parameter_settings({"flange_back_distance": -1.0})
    with pytest.raises(RailContactError, match="parameter warm_start"):
        V.parameter_settings({"warm_start": "sometimes"})
    assert not V.parameter_settings({"load_definition": "normal"}).contact.load_includes_creep


@pytest.mark.parametrize("name", ["hertz_paper", "hertz_paper_rolling", "s1002_60e1_dy-2mm"])
def test_a_case_survives_its_dictionary(root, name):
    case = rc.load_case(root / "models" / "cases" / f"{name}.toml")
    assert Case.from_dict(case.to_dict()) == case
    assert rc.validate_case(case) is case


def test_a_case_reports_every_problem_at_once():
    bad = {"material": {"young": -1.0, "poisson": 0.3},
           "geometry": {"type": "quadratic", "A": 1.0},
           "normal": {"penetration": 1e-4, "tolerance": 0.0},
           "tangential": {"creepage": [0, 0, 0], "friction": 0.3, "strips": [1, 40]}}
    with pytest.raises(CaseError) as err:
        Case.from_dict(bad)
    msg = str(err.value)
    for part in ("4 problems", "[material] young", "[geometry] B", "[normal] tolerance",
                 "[tangential] strips[0]"):
        assert part in msg


@pytest.mark.parametrize("field, value, match", [
    ("element_size", 0.01, r"element_size \[m\] must be >= 1e-05 and <= 0.005"),
    ("element_size", -1e-4, "element_size"),
    ("friction", 0.0, "friction must be > 0 and <= 10"),
    ("normal_tolerance", 1.0, "normal_tolerance"),
    ("warm_start", "always", "warm_start must be one of"),
    ("estimate_grid", (3, 40), r"estimate_grid\[0\] must be an integer >= 4"),
    ("max_iterations_normal", 2.5, "max_iterations_normal"),
    ("spin_offset", float("nan"), "finite"),
    ("load_includes_creep", 1, "true or false"),
])
def test_contact_settings_reject_bad_values(field, value, match):
    with pytest.raises(RailContactError, match=match):
        ContactSettings(**{field: value})


def test_time_step_records_are_built_once_from_contact_settings():
    cs = ContactSettings(normal_tolerance=1e-4, tangential_tolerance=1e-3, friction=0.3,
                         element_size=1e-3, warm_start="previous")
    assert cs.normal_settings is cs.normal_settings  # cached, not rebuilt per pass
    assert cs.patch_settings.normal is cs.normal_settings
    assert cs.patch_settings.grid is cs.grid_settings and cs.patch_settings.tangential is None
    assert (cs.normal_settings.tolerance, cs.normal_settings.estimate) == (1e-4, "none")
    t = cs.tangential_settings
    assert (t.friction, t.tolerance, t.estimate, t.model) == (0.3, 1e-3, "none", "bem")
    g = cs.grid_settings
    assert (g.dx, g.dy, g.quantum, g.snap) == (1e-3, 1e-3, 4, True)
    with_estimate = ContactSettings(warm_start="previous+estimate")
    assert with_estimate.normal_settings.estimate == "infcon"
    assert with_estimate.tangential_settings.estimate == "fastrip"


def test_records_normalise_their_values():
    n = NormalSettings(estimate_grid=[30, 20], max_iterations=50.0, load=10)
    assert n.estimate_grid == (30, 20) and isinstance(n.max_iterations, int)
    assert isinstance(n.load, float) and n.control.kwargs() == {"load": 10.0}
    assert TangentialSettings(creepage=[1, 0, 0]).creepage == (1.0, 0.0, 0.0)
    pair = MaterialSettings(young=[210e9, 200e9], poisson=0.3).elastic_pair()
    assert pair == rc.ElasticPair.of(rc.Material(210e9, 0.3), rc.Material(200e9, 0.3))
    assert WheelRailGeometry().inclination == pytest.approx(math.atan(1 / 40))


def test_record_docstrings_carry_units_and_defaults():
    doc = NormalSettings.__doc__
    assert "Attributes" in doc and "load [N]" in doc and "tolerance [-]" in doc
    assert "default 0.001" in doc


def test_demo_flags_are_checked_as_settings_before_anything_runs():
    from railcontact.sim.demo import DemoOptions

    with pytest.raises(RailContactError, match=r"parameter element_size \[m\]"):
        DemoOptions(element_size=0.01).resolved()
    with pytest.raises(RailContactError, match="parameter warm_start"):
        DemoOptions(warm_start="sometimes").resolved()
    assert DemoOptions().resolved()["element_size"] == ContactSettings().element_size


@pytest.mark.parametrize("old, new", [
    ("railcontact.materials", "railcontact.halfspace.materials"),
    ("railcontact.wheelset", "railcontact.timestep.wheelset"),
    ("railcontact.pipeline", "railcontact.contact"),
    ("railcontact.case", "railcontact.settings"),
    ("railcontact.geometry.contact", "railcontact.geometry.search"),
])
def test_old_module_paths_still_import_with_a_warning(old, new):
    import importlib
    import sys

    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=f"{old} has moved to {new}"):
        module = importlib.import_module(old)
    target = importlib.import_module(new)
    for name in [n for n in dir(target) if not n.startswith("_")][:5]:
        assert getattr(module, name) is getattr(target, name)


def test_a_case_is_not_a_dictionary_and_says_so(root):
    case = rc.load_case(root / "models" / "cases" / "hertz_paper.toml")
    with pytest.raises(TypeError, match=r"use case\.normal"):
        case["normal"]


def test_api_reference_lists_every_public_name(root):
    """docs/api/index.rst names each of ``railcontact.__all__`` by the module it lives in."""
    text = _page(root, "docs/api/index.rst")
    listed = {name: module for module, name in re.findall(r"^   ~([\w.]+)\.(\w+)$", text,
                                                            flags=re.M)}
    assert set(listed) == set(rc.__all__)
    for name, module in listed.items():
        if name != "STEEL":  # an instance: its module is where it is defined
            assert getattr(rc, name).__module__ == module, name


def test_api_reference_documents_every_module_of_the_layers(root):
    """Each module of a layer documented in docs/api/ has its ``automodule``."""
    import pkgutil

    api = root / "docs" / "api"
    for page in api.glob("*.rst"):
        if page.stem in ("index", "layers", "errors"):
            continue
        package = root / "railcontact" / page.stem
        text = page.read_text(encoding="utf-8")
        for module in pkgutil.iter_modules([str(package)]):
            name = f"railcontact.{page.stem}.{module.name}"
            assert f".. automodule:: {name}\n" in text, f"{page.name} lacks {name}"


def test_invariants_survive_python_O(root):
    """The package states its invariants with explicit checks, not ``assert`` (which
    ``python -O`` removes)."""
    import ast

    found = []
    for path in [*(root / "railcontact").rglob("*.py"), *(root / "fmu_src").glob("*.py")]:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        found += [f"{path.relative_to(root)}:{n.lineno}" for n in ast.walk(tree)
                  if isinstance(n, ast.Assert)]
    assert not found, found
