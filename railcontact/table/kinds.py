"""A table spec of any kind (``[table] kind``): a contact table (:mod:`.spec`, the
default), a geometry table (:mod:`railcontact.table.geometry`, through
:func:`~.spec.load_spec`) or a normalised creep table (:mod:`.creepspec`)."""

from __future__ import annotations

from pathlib import Path

from .creepspec import CreepSpec, parse_creep_spec
from .spec import CREEP_KIND, DEFAULT_KIND, TableSpec, read_spec_file, spec_of_file


def load_any_spec(path: str | Path) -> TableSpec | CreepSpec:
    """Read a TOML table spec of any kind (SI units): a :class:`~.creepspec.CreepSpec` for
    ``[table] kind = "creep"``, else :func:`~.spec.load_spec`'s :class:`~.spec.TableSpec`.

    Raises
    ------
    CaseError
        When the file does not exist, does not parse or is not a valid spec.
    """
    p, raw = read_spec_file(path)
    table = raw.get("table")
    kind = table.get("kind", DEFAULT_KIND) if isinstance(table, dict) else DEFAULT_KIND
    if kind == CREEP_KIND:
        return parse_creep_spec(raw)
    return spec_of_file(p, raw)
