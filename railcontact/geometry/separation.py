"""CONTACT's turning of the contact angles of a wheel's neighbouring patches.

CONTACT (eve70a/CONTACT ``src/m_wr_locatecp.f90``, read in its stored versions of commits
21a2f8b5 and 034c31cb, the same rule in both: subroutine ``turn_cpatch_refangle``, called
from ``complete_patches`` after ``sort_cpatches_yvalue`` and ``combine_cpatches`` and
before each patch's reference marker is set in ``set_cpatch_reference``) inclines two
neighbouring patches that lie a little apart towards the angle their union would have.
Per pair of neighbouring patches (sorted from the field side towards the track centre):

* the distance ``dist`` is measured between the facing ends of their interpenetration
  regions on the rail, in the track's cross-section (``sqrt(dy^2 + dz^2)`` between the
  inner end of the outer patch and the outer end of the inner patch, each end where the
  vertical interpenetration along the contact locus is zero);
* nothing is done when the patches' contact angles (their weighted surface inclinations,
  ``wgt_agap``, before any turning) differ by more than ``A_SEP``, or when ``dist`` is
  below ``D_SEP`` (CONTACT has combined such patches into one already,
  ``combine_cpatches``) or above ``D_TURN``;
* otherwise ``angl_comb``, the mean of the two angles weighted by each patch's integrated
  weight (``totgap``: the squared interpenetration integrated over the region, the weight of
  its reference point), is the angle of the combined patch, and each angle moves towards
  it by ``fac = (D_TURN - dist) / (D_TURN - D_SEP)`` of the difference: at ``D_SEP`` both
  take the combined angle, at ``D_TURN`` neither turns. A patch between two others is
  moved by both of its pairs (each computed from the angles before turning).

Only the angle changes: ``set_cpatch_reference`` takes the patch's (turned) ``wgt_agap`` as
its contact angle ``delttr`` and rolls the reference marker by it at the unchanged weighted
centre (``wgt_xgap``, ``wgt_ygap`` and the rail's height there), and ``set_planar_potcon``
forms the potential contact area in that marker's plane. So the reference point stays
where it is, and the patch's plane - its potential contact area, gap, contact frame, and
what is read at its contact angle (the friction of a table across the profile, the spin) -
is inclined at the turned angle. The ends of a region (``ysta, zsta``, ``yend, zend``) are
set in ``locate_interpen_1d``: the lateral positions where the vertical gap along the
contact locus crosses zero (linear between the samples in and out) and the rail's height
there; the weight ``totgap`` in ``compute_wgt_center_1d``. ``D_TURN`` is CONTACT's optional
seventh discretisation value (``m_wr_input.f90``, the discretisation parameters); by
default ``2 D_SEP - D_COMB``. CONTACT turns nothing when ``D_TURN <= D_SEP``.

railcontact does not combine patches closer than ``D_SEP`` (each run of the wheel's
overlap stays its own patch); this module only turns the angles where CONTACT turns them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from ..errors import RailContactError

TINY_SEPARATION = 1e-15
"""[m]: ``D_TURN`` within this of ``D_SEP`` turns nothing (CONTACT's ``tiny_sep``, 1e-12 mm)."""


@dataclass(frozen=True)
class PatchSeparation:
    """CONTACT's patch separation parameters (its ``A_SEP, D_SEP, D_COMB`` and ``D_TURN``),
    SI units.

    Attributes
    ----------
    angle
        ``A_SEP`` [rad]: neighbouring patches whose contact angles differ by more are
        never turned.
    distance
        ``D_SEP`` [m]: below it CONTACT combines two patches, from it up to
        ``turn_distance`` it turns their angles.
    combine
        ``D_COMB`` [m]: sets the default ``turn_distance``.
    turn
        ``D_TURN`` [m], or None for ``2 D_SEP - D_COMB``.
    """

    angle: float = math.pi / 2
    distance: float = 0.008
    combine: float = 0.004
    turn: float | None = None

    def __post_init__(self) -> None:
        for name in ("angle", "distance", "combine"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise RailContactError(f"patch separation {name} must be a number >= 0, "
                                       f"got {v!r}")
        if self.turn is not None and not (math.isfinite(self.turn) and self.turn >= 0):
            raise RailContactError(f"patch separation turn distance must be a number >= 0, "
                                   f"got {self.turn!r}")

    @property
    def turn_distance(self) -> float:
        """``D_TURN`` [m] (CONTACT's default ``2 D_SEP - D_COMB`` when not given)."""
        return self.turn if self.turn is not None else 2 * self.distance - self.combine


class PatchRun(NamedTuple):
    """What the turning reads of one patch (SI units, side frame): the lateral position of
    its reference point on the rail ``u`` [m] (increasing towards the field side), its
    contact angle before turning [rad], its weight (the weighted interpenetration
    integrated across the rail, any unit common to the wheel's patches) and the two ends
    of its interpenetration on the rail, ``(u, Z)`` [m] each, the end of least u first.
    (A named tuple: one is formed with every frame at a reference point.)"""

    u: float
    angle: float
    weight: float
    low_end: tuple[float, float]
    high_end: tuple[float, float]


def turned_angles(runs: list[PatchRun], separation: PatchSeparation) -> list[float]:
    """The contact angle [rad] of each of a wheel's patches (``runs``, at one approach)
    after CONTACT's turning (module docstring), in the order given."""
    angles = [r.angle for r in runs]
    d_sep, d_turn = separation.distance, separation.turn_distance
    if len(runs) < 2 or d_turn <= d_sep + TINY_SEPARATION:
        return angles
    order = sorted(range(len(runs)), key=lambda k: -runs[k].u)  # field side first
    for i, j in zip(order[:-1], order[1:], strict=True):
        outer, inner = runs[i], runs[j]
        dist = math.hypot(outer.low_end[0] - inner.high_end[0],
                          outer.low_end[1] - inner.high_end[1])
        if (abs(outer.angle - inner.angle) > separation.angle or dist < d_sep
                or dist > d_turn):
            continue
        total = outer.weight + inner.weight
        if not total > 0:
            continue
        comb = (outer.angle * outer.weight + inner.angle * inner.weight) / total
        fac = (d_turn - dist) / (d_turn - d_sep)
        angles[i] += fac * (comb - outer.angle)
        angles[j] += fac * (comb - inner.angle)
    return angles
