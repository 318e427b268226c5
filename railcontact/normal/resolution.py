"""Whether a patch's contact is resolved by enough elements.

A patch's normal solution is *under-resolved* when its contact set spans fewer than
:data:`MIN_ELEMENTS_ACROSS` elements along x or along y (from its first to its last
element in contact, gaps included). Against Hertz (a quadratic patch, the potential area
automatic, elements of equal aspect to the ellipse), the largest pressure's error by the
number of elements across the contact is about 48 % with 1 element, 4 to 12 % with 2 or
3, within 4 % with 4 and within 3 % with 5 or more; the total force is met whatever the
grid.

A patch long one way and narrow the other (a flange or flange-root patch at coarse
elements) counts by its narrow way. A Hertz ellipse of ratio 18 (A = 100, B = 1 /m, steel,
50 kN), square elements, its contact spanning 1, 3, 3, 5, 7, 9, 16 and 33 elements along
its narrow axis x (the rolling direction): the area is +19, +33, +13, +16, +9, +7, +3 and
+1 % off Hertz's, and the creep force at xi = 5e-4, mu = 0.3 is 45, 46, 20, 18, 11, 7, 2
and 0.4 % off its limit under refinement (the adhesion zone's growth along x is the
grid's until several elements span it). With fewer than 4 elements across either way the
pressure, the area and the tangential solution are the grid's, not the contact's; beyond,
the error falls as the elements shrink (a convergence study says how far).
"""

from __future__ import annotations

import numpy as np

MIN_ELEMENTS_ACROSS = 4
"""Fewest elements a patch's contact set must span along x and along y (module
docstring)."""


def elements_across(contact: np.ndarray) -> tuple[int, int]:
    """Elements the contact set spans along x and along y (first to last element in
    contact, inclusive); ``(0, 0)`` without contact.

    Parameters
    ----------
    contact
        The contact mask, shape (nx, ny).
    """
    c = np.asarray(contact, dtype=bool)
    if not c.any():
        return 0, 0
    rows, cols = np.flatnonzero(c.any(axis=1)), np.flatnonzero(c.any(axis=0))
    return int(rows[-1] - rows[0] + 1), int(cols[-1] - cols[0] + 1)


def under_resolved(contact: np.ndarray, dx: float, dy: float) -> str:
    """A message saying how a contact set is under-resolved (module docstring), ``""``
    when it spans at least :data:`MIN_ELEMENTS_ACROSS` elements along x and along y, or
    has no contact.

    Parameters
    ----------
    contact
        The contact mask, shape (nx, ny).
    dx, dy
        The element sizes along x and y [m].
    """
    nx, ny = elements_across(contact)
    if nx == 0 or min(nx, ny) >= MIN_ELEMENTS_ACROSS:
        return ""
    way = "either way" if max(nx, ny) < MIN_ELEMENTS_ACROSS else "its narrow way"  # (x or y)
    return (f"under-resolved patch: its contact spans {nx} x {ny} elements of "
            f"{dx * 1e3:.3g} x {dy * 1e3:.3g} mm (x by y), fewer than "
            f"{MIN_ELEMENTS_ACROSS} across {way}; its pressure, area and creep forces are the "
            "grid's (the largest pressure up to 50 %, the area up to 33 %, the creep force "
            "along a narrow x up to 45 % off); use smaller elements")


__all__ = ["MIN_ELEMENTS_ACROSS", "elements_across", "under_resolved"]
