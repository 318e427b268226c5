"""Every setting in one list, generated from the records' declarations: the reference
that ``railcontact settings`` prints and ``docs/settings.md`` holds."""

from __future__ import annotations

from dataclasses import dataclass, fields

from .case import (
    GridSettings,
    KinematicsSettings,
    MaterialSettings,
    NormalSettings,
    QuadraticGeometry,
    TangentialSettings,
    WheelRailGeometry,
)
from .fields import Record, default_of, spec_of
from .timestep import ContactSettings, FMUModes

RECORDS: tuple[type[Record], ...] = (
    MaterialSettings, QuadraticGeometry, WheelRailGeometry, GridSettings, NormalSettings,
    TangentialSettings, KinematicsSettings, ContactSettings, FMUModes)
"""Every settings record, in the order of the reference."""


@dataclass(frozen=True)
class SettingRow:
    """One setting: where it is set, its default, unit, allowed values and meaning."""

    record: str
    table: str
    key: str
    default: object
    unit: str
    allowed: str
    doc: str
    required: bool
    case: bool


def setting_rows(records: tuple[type[Record], ...] = RECORDS) -> list[SettingRow]:
    """The settings of ``records``, one row per field."""
    rows = []
    for rec in records:
        for f in fields(rec):  # type: ignore[arg-type]
            s = spec_of(f)
            rows.append(SettingRow(rec.__name__, rec.TABLE, f.name, default_of(f), s.unit,
                                   s.bounds_text(), s.doc, s.required, s.case))
    return rows


def case_keys() -> set[tuple[str, str]]:
    """Every (table, key) a case file may hold (``type`` of ``[geometry]`` included)."""
    keys = {(r.table, r.key) for r in setting_rows() if r.table and r.case}
    return keys | {("geometry", "type")}


def _fmt(value: object) -> str:
    if value is None:
        return "—"
    if isinstance(value, tuple):
        value = list(value) if len(value) > 1 else value[0]
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, bool):
        return str(value).lower()  # as TOML writes it
    return repr(value) if isinstance(value, str) else str(value)


def markdown() -> str:
    """The settings reference as Markdown (one table per record)."""
    out = ["# Settings reference", "",
           "Generated from the declarations in `railcontact/settings/` by "
           "`railcontact settings`; do not edit by hand. SI units; `-` is dimensionless "
           "(`1` in the FMU's modelDescription). "
           "A case file holds the tables `[material]`, `[geometry]` (`type = \"quadratic\"` "
           "or `\"wheel-rail\"`), `[grid]`, `[normal]`, `[tangential]` and `[kinematics]`; "
           "`ContactSettings` and `FMUModes` are the time step's and the FMU's.", ""]
    for rec in RECORDS:
        title = f"`[{rec.TABLE}]` — `{rec.__name__}`" if rec.TABLE else f"`{rec.__name__}`"
        doc = (rec.__doc__ or "").split("\n\n")[0].replace("\n", " ").replace("``", "`")
        doc = " ".join(doc.split())
        out += [f"## {title}", "", doc, "",
                "| key | default | unit | allowed | meaning |", "|---|---|---|---|---|"]
        for r in setting_rows((rec,)):
            default = "required" if r.required and r.case else _fmt(r.default)
            doc = r.doc if r.case or not r.table else f"{r.doc} (set by the time step, not in "\
                "case files)"
            out.append(f"| `{r.key}` | {default} | {r.unit} | {r.allowed} | {doc} |")
        out.append("")
    return "\n".join(out)
