"""The quantities a table holds per grid point and wheel, read from a
:class:`~railcontact.timestep.WheelContact` (the time loop's and the FMU's per-wheel result)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..status import Status
from ..timestep.wheelset import NO_CONTACT, NOT_CONVERGED, OK, OUT_OF_RANGE


@dataclass(frozen=True)
class Quantity:
    """One stored quantity (SI units): ``read(wheel)`` gives its value."""

    name: str
    unit: str
    long_name: str
    read: Callable[[Any], float]
    geometric: bool = False
    """Undefined (NaN) without contact; the forces are then zero."""


QUANTITIES: tuple[Quantity, ...] = (
    Quantity("normal_force", "N", "normal force on the wheel (sum over patches)",
             lambda w: w.normal_force),
    Quantity("creep_force_x", "N", "longitudinal creep force on the wheel, contact frame",
             lambda w: w.creep_force[0]),
    Quantity("creep_force_y", "N", "lateral creep force on the wheel, contact frame",
             lambda w: w.creep_force[1]),
    Quantity("spin_moment", "N m", "spin moment on the wheel about the contact normal",
             lambda w: w.spin_moment),
    Quantity("force_longitudinal", "N", "force of the rail on the wheel, track X",
             lambda w: w.track_force[0]),
    Quantity("force_lateral", "N", "force of the rail on the wheel, track Y",
             lambda w: w.track_force[1]),
    Quantity("force_vertical", "N", "force of the rail on the wheel, track Z",
             lambda w: w.track_force[2]),
    Quantity("yaw_moment", "N m", "moment of the rail on the wheel about the vertical "
             "through the wheelset centre", lambda w: w.yaw_moment),
    Quantity("contact_x", "m", "contact point of the main patch, track X",
             lambda w: w.contact_point[0], True),
    Quantity("contact_y", "m", "contact point of the main patch, track Y",
             lambda w: w.contact_point[1], True),
    Quantity("contact_z", "m", "contact point of the main patch, track Z",
             lambda w: w.contact_point[2], True),
    Quantity("wheel_position", "m", "wheel profile coordinate of the contact",
             lambda w: w.wheel_position, True),
    Quantity("rail_position", "m", "rail profile coordinate of the contact",
             lambda w: w.rail_position, True),
    Quantity("contact_angle", "rad", "contact angle (positive towards the flange)",
             lambda w: w.contact_angle, True),
    Quantity("rolling_radius", "m", "wheel radius at the contact point",
             lambda w: w.rolling_radius, True),
    Quantity("area", "m2", "contact area (sum over patches)", lambda w: w.area),
    Quantity("max_pressure", "Pa", "maximum pressure", lambda w: w.max_pressure),
    Quantity("slip_area_ratio", "1", "slip area / contact area", lambda w: w.slip_area_ratio),
    Quantity("penetration", "m", "largest normal penetration of the patches",
             lambda w: w.penetration),
    Quantity("tip_position", "m", "wheel profile coordinate of the patch nearest the "
             "flange tip", lambda w: _tip(w).wheel_s, True),
    Quantity("tip_angle", "rad", "contact angle of the patch nearest the flange tip",
             lambda w: _tip(w).contact_angle, True),
)
"""The interpolated quantities (floats). ``penetration``, ``tip_position`` and
``tip_angle`` are what the validity of a table step needs besides the forces
(:mod:`.step`): the patch nearest the flange tip (smallest S) is the one that decides
flange climb. A store written before they were lacks them
(:attr:`~.interpolate.ContactTable.missing`)."""
VALIDITY_QUANTITIES = ("penetration", "tip_position", "tip_angle")
"""The quantities a table step's validity needs (a store without them is refused)."""


def _tip(wheel: Any) -> Any:
    """The contact point of the wheel's patch nearest the flange tip (smallest S; NaN
    without one)."""
    return min((p.geometry for p in wheel.patches if p.geometry is not None),
               key=lambda cp: cp.wheel_s, default=_NO_POINT)


_NO_POINT = SimpleNamespace(wheel_s=math.nan, contact_angle=math.nan)

COUNTS: tuple[Quantity, ...] = (
    Quantity("n_patches", "1", "number of contact patches", lambda w: w.n_patches),
    Quantity("normal_iterations", "1", "BEM normal iterations (all patches and passes)",
             lambda w: w.normal_iterations),
    Quantity("tangential_iterations", "1", "tangential BEM sweeps (all patches and passes)",
             lambda w: w.tangential_iterations),
    Quantity("load_passes", "1", "solves of the wheel (load loop)", lambda w: w.load_passes),
)
"""Work counters (integers, not interpolated)."""

NOT_COMPUTED = Status.NOT_COMPUTED
"""``status`` of a point not computed yet (its values are NaN)."""
STATUS_MEANINGS = {s: s.label for s in Status}
"""The ``status`` codes: those of the time loop and the FMU, and -1."""

FAILED = (NOT_CONVERGED, OUT_OF_RANGE, NOT_COMPUTED)
"""The statuses of a point without trustworthy values (a hole of the table: interpolation
there returns the status, not a value); no contact is an answer, not a failure."""


def failed_counts(status) -> dict[str, int]:
    """The number of point-wheels of each failed status (:data:`FAILED`) in the array
    ``status``, by the status's meaning; only those present."""
    st = np.asarray(status)
    out = {STATUS_MEANINGS[k]: int(np.count_nonzero(st == k)) for k in FAILED}
    return {k: v for k, v in out.items() if v}


def failed_text(counts: dict[str, int]) -> str:
    """``"N point-wheel(s) failed (a not converged, b out of range)"``."""
    return (f"{sum(counts.values())} point-wheel(s) failed ("
            + ", ".join(f"{v} {k}" for k, v in counts.items()) + ")")


__all__ = ["COUNTS", "FAILED", "NOT_COMPUTED", "NO_CONTACT", "NOT_CONVERGED", "OK", "OUT_OF_RANGE",
           "QUANTITIES", "STATUS_MEANINGS", "VALIDITY_QUANTITIES", "Quantity", "failed_counts",
           "failed_text"]
