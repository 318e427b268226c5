"""The FMU page of the docs (docs/fmu.md) cannot drift from the FMU: its variable table is
the one the variables module generates, and it names every variable."""

from __future__ import annotations

import re

from railcontact.fmu import variables as V


def _block(page: str, marker: str = "fmu-variables") -> str:
    return page.split(f"<!-- {marker}")[1].split("-->", 1)[1].split(f"<!-- /{marker} -->")[0]


def test_docs_variable_table_is_current(root):
    """Regenerate with ``python scripts/fmu_variables_table.py``."""
    page = (root / "docs" / "fmu.md").read_text(encoding="utf-8")
    assert _block(page).strip() == V.variables_markdown().strip()
    assert _block(page, "fmu-wheelsets").strip() == V.wheelsets_markdown().strip()


def test_variable_table_names_every_variable_with_its_unit_and_default():
    table = V.variables_markdown()
    rows = {}
    for line in table.splitlines()[2:]:
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]]
        for name in re.findall(r"`([a-z_0-9]+)`", cells[0]):
            rows[name] = cells
    everything = (V.PARAMETERS + V.CHOICES + V.INPUTS + V.OUTPUTS + V.APPENDED_OUTPUTS
                  + V.TRACK_INPUTS + V.TRACK_OUTPUTS)
    for v in everything:
        row = rows.get(v.name) or rows[v.name.removesuffix("_right") + "_left"]
        assert row[1] == v.causality and row[3] == v.unit, v.name
        if v.causality != "output" and not v.items:
            assert row[4].strip("`") == (f"{v.start:.6g}" if isinstance(v.start, float)
                                          else str(v.start)), v.name
    assert len(rows) + sum(v.name.endswith("_right") for v in everything) >= len(everything)
