"""How far a start of the normal BEM was from the solution it converged to."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np

from ..errors import RailContactError


@dataclass(frozen=True)
class EstimateError:
    """The error of an initial pressure against a BEM solution on the same grid.

    Attributes
    ----------
    l1
        ``sum |p0 - p| / sum p`` [-] (``p0`` the start, negative values taken as zero as
        the solver takes them; ``p`` the solution); None when the solution has no
        pressure.
    missing
        Elements in the solution's contact (``p > 0``) where the start has no pressure.
    extra
        Elements where the start has pressure outside the solution's contact.
    contact
        Elements in the solution's contact.
    """

    l1: float | None
    missing: int
    extra: int
    contact: int

    @property
    def missing_share(self) -> float | None:
        """:attr:`missing` over :attr:`contact` [-]; None without contact."""
        return self.missing / self.contact if self.contact else None

    @property
    def extra_share(self) -> float | None:
        """:attr:`extra` over :attr:`contact` [-]; None without contact."""
        return self.extra / self.contact if self.contact else None

    def to_dict(self) -> dict[str, Any]:
        """The fields (``l1`` left out when it is None: a JSON null reads as a value that
        is not finite)."""
        d: dict[str, Any] = {"missing": self.missing, "extra": self.extra,
                             "contact": self.contact}
        if self.l1 is not None:
            d = {"l1": self.l1, **d}
        return d


def estimate_error(start: np.ndarray, pressure: np.ndarray) -> EstimateError:
    """The :class:`EstimateError` of the initial pressure ``start`` [Pa] against the
    solution ``pressure`` [Pa] on the same grid (both (nx, ny)), in one pass."""
    p0 = np.ascontiguousarray(start, dtype=float)
    p = np.ascontiguousarray(pressure, dtype=float)
    if p0.shape != p.shape:
        raise RailContactError(f"the start's shape {p0.shape} is not the solution's {p.shape}")
    diff, total, missing, extra, contact = _compare(p0.reshape(-1), p.reshape(-1))
    if not (math.isfinite(diff) and math.isfinite(total)):
        raise RailContactError("the start or the solution holds values that are not finite")
    return EstimateError(l1=diff / total if total > 0 else None, missing=int(missing),
                         extra=int(extra), contact=int(contact))


@numba.njit(cache=True, nogil=True)
def _compare(p0, p):  # pragma: no cover - compiled
    """``(sum |max(p0, 0) - p|, sum p, missing, extra, contact)`` of flat arrays."""
    diff = total = 0.0
    missing = extra = contact = 0
    for i in range(p.size):
        a = max(p0[i], 0.0) if p0[i] == p0[i] else p0[i]
        b = p[i]
        diff += abs(a - b)
        total += b
        if b > 0.0:
            contact += 1
            if not a > 0.0:
                missing += 1
        elif a > 0.0:
            extra += 1
    return diff, total, missing, extra, contact
