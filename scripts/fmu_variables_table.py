"""Write the FMU's variable table into docs/fmu.md (between the ``fmu-variables`` markers).

The table is :func:`railcontact.fmu.variables.variables_markdown`, from the one table the
slave and the modelDescription share; ``tests/test_readme_fmu.py`` fails when the page's
copy is stale. Usage: ``python scripts/fmu_variables_table.py [--check]``.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from railcontact.fmu.variables import variables_markdown

PAGE = Path(__file__).resolve().parents[1] / "docs" / "fmu.md"
BLOCK = re.compile(r"(<!-- fmu-variables[^>]*-->\n)(.*?)(<!-- /fmu-variables -->)", re.S)


def with_table(text: str) -> str:
    """``text`` with the block between the markers replaced by the current table."""
    if not BLOCK.search(text):
        raise SystemExit("docs/fmu.md has no <!-- fmu-variables --> ... "
                         "<!-- /fmu-variables --> block")
    return BLOCK.sub(lambda m: m.group(1) + variables_markdown() + m.group(3), text, count=1)


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
