"""Solutions as strict JSON (RFC 8259: no NaN or Infinity)."""

from __future__ import annotations

import json
import math
from typing import Any

from ..contact import Solution


def solution_json(solution: Solution, indent: int | None = 2) -> str:
    """The JSON text of ``solution.to_dict()`` (SI units).

    A number that is not finite is written as ``null`` (JSON has no NaN); the solve that
    produced it is reported ``"converged": false``.
    """
    return json.dumps(finite(solution.to_dict()), indent=indent, allow_nan=False)


def finite(value: Any) -> Any:
    """``value`` with every non-finite float, at any depth, replaced by None."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite(v) for v in value]
    return value
