"""A table spec of any kind (``[table] kind``): a contact table (:mod:`.spec`, the
default), a geometry table (:mod:`railcontact.table.geometry`, through
:func:`~.spec.load_spec`) or a normalised creep table (:mod:`.creepspec`)."""

from __future__ import annotations

import sys
from pathlib import Path

from ..errors import CaseError
from .creepspec import CreepSpec, parse_creep_spec
from .spec import CREEP_KIND, DEFAULT_KIND, TableSpec, load_spec

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def load_any_spec(path: str | Path) -> TableSpec | CreepSpec:
    """Read a TOML table spec of any kind (SI units): a :class:`~.creepspec.CreepSpec` for
    ``[table] kind = "creep"``, else :func:`~.spec.load_spec`'s :class:`~.spec.TableSpec`.

    Raises
    ------
    CaseError
        When the file does not exist, does not parse or is not a valid spec.
    """
    p = Path(path)
    if not p.is_file():
        raise CaseError(f"table spec not found: {p}")
    try:
        with p.open("rb") as f:
            raw = tomllib.load(f)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, ValueError) as exc:
        raise CaseError(f"table spec {p} is not valid TOML: {exc}") from None
    table = raw.get("table")
    kind = table.get("kind", DEFAULT_KIND) if isinstance(table, dict) else DEFAULT_KIND
    if kind == CREEP_KIND:
        raw.setdefault("name", p.stem)
        return parse_creep_spec(raw)
    return load_spec(p)
