"""Write the FMU's variable tables into docs/fmu.md (between the ``fmu-variables`` and the
``fmu-wheelsets`` markers).

The tables are :func:`railcontact.fmu.variables.variables_markdown` and
:func:`~railcontact.fmu.variables.wheelsets_markdown` (the FMU of several wheelsets), from the
one table the slave and the modelDescription share; ``tests/test_readme_fmu.py`` fails when
the page's copy is stale. Usage: ``python scripts/fmu_variables_table.py [--check]``.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from railcontact.fmu.variables import variables_markdown, wheelsets_markdown

PAGE = Path(__file__).resolve().parents[1] / "docs" / "fmu.md"
TABLES = {"fmu-variables": variables_markdown, "fmu-wheelsets": wheelsets_markdown}
"""Each block's marker and the function of its table."""


def with_table(text: str) -> str:
    """``text`` with the blocks between the markers replaced by the current tables."""
    for marker, table in TABLES.items():
        block = re.compile(rf"(<!-- {marker}[^>]*-->\n)(.*?)(<!-- /{marker} -->)", re.S)
        if not block.search(text):
            raise SystemExit(f"docs/fmu.md has no <!-- {marker} --> ... <!-- /{marker} --> "
                             "block")
        text = block.sub(lambda m, table=table: m.group(1) + table() + m.group(3), text,
                         count=1)
    return text


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="only say whether it is current")
    args = ap.parse_args(argv)
    text = PAGE.read_text(encoding="utf-8")
    new = with_table(text)
    if args.check:
        print("current" if new == text else "stale: run python scripts/fmu_variables_table.py")
        return 0 if new == text else 1
    PAGE.write_text(new, encoding="utf-8")
    print(f"wrote the FMU variable table into {PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
