"""Solutions as strict JSON (RFC 8259: no NaN or Infinity)."""

from __future__ import annotations

import json
import math
from typing import Any

from ..contact import Solution
from .wheels import CaseWheel, case_wheels


def solution_json(solution: Solution, indent: int | None = 2, file: str | None = None,
                  wheels: list[CaseWheel] | None = None) -> str:
    """The JSON text of ``solution.to_dict()`` (SI units), with ``"file"`` first when the
    case ``file`` is given, and for a wheel-rail case ``"wheels"``: each loaded wheel's
    force in the track frame, Y/Q and validity (:func:`~.wheels.case_wheels`; ``wheels``
    when the caller formed them).

    A number that is not finite is written as ``null`` (JSON has no NaN); the solve that
    produced it is reported ``"converged": false``.
    """
    d = solution.to_dict() if file is None else {"file": file, **solution.to_dict()}
    wheels = case_wheels(solution) if wheels is None else wheels
    if wheels:
        d["wheels"] = [w.to_dict() for w in wheels]
    return json.dumps(finite(d), indent=indent, allow_nan=False)


def finite(value: Any) -> Any:
    """``value`` with every non-finite float, at any depth, replaced by None."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite(v) for v in value]
    return value
