"""Solutions as strict JSON (RFC 8259: no NaN or Infinity)."""

from __future__ import annotations

import json

from ..contact import Solution
from ..errors import RailContactError


def solution_json(solution: Solution, indent: int | None = 2) -> str:
    """The JSON text of ``solution.to_dict()`` (SI units).

    Raises
    ------
    RailContactError
        When the solution holds a non-finite number (not representable in JSON).
    """
    try:
        return json.dumps(solution.to_dict(), indent=indent, allow_nan=False)
    except ValueError as exc:
        raise RailContactError(f"the solution holds a non-finite number ({exc}); "
                               "no JSON written") from None
