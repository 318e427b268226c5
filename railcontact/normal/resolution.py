"""Whether a patch's contact is resolved by enough elements.

A patch's normal solution is *under-resolved* when its contact set spans fewer than
:data:`MIN_ELEMENTS_ACROSS` elements along x, the rolling direction, whatever it spans
along y (from its first to its last element in contact, gaps included; the message says
whether y is narrow too). Against Hertz (a
quadratic patch, the potential area automatic, elements of equal aspect to the ellipse),
the largest pressure's error by the number of elements across the contact is about 48 %
with 1 element, 4 to 12 % with 2 or 3, within 4 % with 4 and within 3 % with 5 or more;
the total force is met whatever the grid.

A patch long one way and narrow the other (a flange or flange-root patch at coarse
elements) differs by its narrow way. A Hertz ellipse of ratio 18 (steel, 50 kN), square
elements: narrow along x (A = 100, B = 1 /m), its contact spanning 1, 3, 3, 5, 7, 9, 16
and 33 elements along x, the area is +19, +33, +13, +16, +9, +7, +3 and +1 % off Hertz's,
and the creep force at xi = 5e-4, mu = 0.3 is 45, 46, 20, 18, 11, 7, 2 and 0.4 % off its
limit under refinement (the adhesion zone's growth along x is the grid's until several
elements span it): under-resolved. Narrow along y (A = 1, B = 100 /m), 1 to 16 elements
across y: the creep forces of xi, eta (5e-4) and spin (0.5 /m) are within 2, 2 and 3 % of
the finest grid's - the forces a dynamics code takes are resolved, and the patch is not
flagged, though its largest pressure and area are as far off as the elements across y
say (the table above).
"""

from __future__ import annotations

import numba
import numpy as np

from ..errors import RailContactError

MIN_ELEMENTS_ACROSS = 4
"""Fewest elements a patch's contact set must span along x, the rolling direction,
whatever it spans along y (module docstring)."""


def elements_across(contact: np.ndarray) -> tuple[int, int]:
    """Elements the contact set spans along x and along y (first to last element in
    contact, inclusive); ``(0, 0)`` without contact.

    Parameters
    ----------
    contact
        The contact mask, shape (nx, ny).
    """
    c = np.ascontiguousarray(contact, dtype=bool)
    if c.ndim != 2:
        raise RailContactError(f"the contact mask must be 2-D (nx, ny), got shape {c.shape}")
    nx, ny = _span(c)
    return int(nx), int(ny)


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def _span(c):
    """:func:`elements_across` of a C-contiguous 2-D boolean mask (one pass)."""
    r0, r1, c0, c1 = c.shape[0], -1, c.shape[1], -1
    for i in range(c.shape[0]):
        for j in range(c.shape[1]):
            if c[i, j]:
                r0 = min(r0, i)
                r1 = i
                c0 = min(c0, j)
                c1 = max(c1, j)
    if r1 < 0:
        return 0, 0
    return r1 - r0 + 1, c1 - c0 + 1


def under_resolved(contact: np.ndarray, dx: float, dy: float) -> str:
    """A message saying how a contact set is under-resolved (module docstring), ``""``
    when it spans at least :data:`MIN_ELEMENTS_ACROSS` elements along x (the rolling
    direction), or has no contact.

    Parameters
    ----------
    contact
        The contact mask, shape (nx, ny).
    dx, dy
        The element sizes along x and y [m].
    """
    nx, ny = elements_across(contact)
    if nx == 0 or nx >= MIN_ELEMENTS_ACROSS:
        return ""
    if ny < MIN_ELEMENTS_ACROSS:
        return (f"under-resolved patch: its contact spans {nx} x {ny} elements of "
                f"{dx * 1e3:.3g} x {dy * 1e3:.3g} mm (x by y), fewer than "
                f"{MIN_ELEMENTS_ACROSS} across either way; its pressure and area are the "
                "grid's (the largest pressure 4 % to 50 % off Hertz's); use smaller elements")
    return (f"under-resolved patch: its contact spans {nx} x {ny} elements of "
            f"{dx * 1e3:.3g} x {dy * 1e3:.3g} mm (x by y), fewer than "
            f"{MIN_ELEMENTS_ACROSS} along x, the rolling direction; its creep forces and area "
            "are the grid's (the creep force up to 45 %, the area up to 33 % off); use "
            "smaller elements")


__all__ = ["MIN_ELEMENTS_ACROSS", "elements_across", "under_resolved"]
