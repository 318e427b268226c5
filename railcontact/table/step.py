"""A wheelset step from a table: :class:`TableContact` is :class:`WheelsetContact` with the
exact solve replaced by interpolation in a :class:`ContactTable` (the FMU's
``contact_model = table``).

``TableContact.open(path).solve(pose, loads=..., creepages=... | kinematics=...)`` returns
the same :class:`~railcontact.timestep.WheelsetResult` as ``WheelsetContact.solve``, so
whatever reads one (the FMU's outputs, ``fmu.variables.OUTPUTS`` and ``APPENDED_OUTPUTS``)
reads the other. Each wheel is looked up at its own state: the lateral displacement and
yaw of the pose, its own
load, its creepages in its side frame (the right wheel's lateral and spin creepages change
sign, as in :mod:`railcontact.timestep.wheelset`; the table holds both wheels in their side
frames, as ``railcontact solve`` does). With ``kinematics`` the creepages are those of the
contact point the table gives at the wheel's pose and load (first looked up at the middle of
the creepage axes, then at the creepages found).

Friction: a table with a ``friction`` axis (``[table] friction``) is looked up at each
wheel's own coefficient of friction, ``solve(..., friction=(mu_left, mu_right))``, or
``settings.friction`` for both without it (the FMU: the inputs ``friction_left/right``, a
wheel whose input is <= 0 the parameter ``friction``); a value outside the axis follows its
out-of-range policy, as any axis. A table without a friction axis holds its case's
coefficient only: a friction per step is an error naming the axis.

Statuses: those of the table's nodes (the largest of the nodes used); a state outside an
axis of the table whose out-of-range policy is ``status`` (the default), or different
from the case's value on an axis the table does not have, is out of range (all outputs of
that wheel zero, the message says which input and the table's range); on an axis whose
policy is ``clamp`` (``[table] out_of_range``, kept in the store; or
``ContactTable.open(path, out_of_range=...)``) the value is moved to the axis's nearest
end and the wheel has that node's status, its message naming the axis clamped; a node
not computed is out of range too. Penetration control (``vertical``) is not in a table
(it is built by load), nor is a negative load: errors, as for bad input.

Validity: a wheel with forces has its Y/Q (``derailment_quotient``), its ``penetration``
and its ``validity`` bits checked against the limits as the exact step does
(:func:`~railcontact.timestep.validity.check_limits`, the same function): Y/Q above
``max_y_q`` or beyond Nadal's limit (with the wheel's coefficient of friction: the table's,
or the one looked up on its friction axis), flange climb,
penetration above ``max_penetration``, wheel load above ``max_wheel_load``; an ok wheel
beyond one is outside validity (status 4). All from the interpolated values: the rail's
force on the wheel, the largest penetration of the patches and the profile coordinate and
contact angle of the patch nearest the flange tip (the one that decides flange climb),
each stored per node. At a node the bits are the exact solve's; between nodes they are
those of the interpolated values. A table whose store lacks any of these (written by an
earlier railcontact) is refused, naming them.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from time import perf_counter
from types import SimpleNamespace

import numpy as np

from ..errors import RailContactError, check_positive
from ..geometry.track import SIDES, Pose
from ..settings import ContactSettings
from ..timestep.inputs import checked_inputs, per_wheel
from ..timestep.memory import EMPTY as EMPTY_MEMORY
from ..timestep.memory import StepMemory
from ..timestep.validity import check_limits, derailment_quotient
from ..timestep.wheelset import (
    NO_CONTACT,
    OK,
    OUT_OF_RANGE,
    Kinematics,
    WheelContact,
    WheelsetResult,
)
from .interpolate import ContactTable, check_method_fits
from .spec import AXES, CREEPAGE_AXES
from .variables import NOT_COMPUTED, VALIDITY_QUANTITIES

ABSENT_RTOL = 1e-9
"""How close an input must be to the case's value on an axis the table does not have."""


class TableContact:
    """A wheelset's contact from a table, step by step (same interface as
    :class:`~railcontact.timestep.WheelsetContact`: ``solve``, ``reset``).

    Parameters
    ----------
    table
        The :class:`ContactTable` (both wheels, or the wheel a state asks for).
    method
        ``"linear"`` or ``"cubic"``.
    settings
        The validity limits read from it: ``max_y_q`` [-], ``max_penetration`` [m],
        ``max_wheel_load`` [N] (None: :class:`~railcontact.settings.ContactSettings`'s
        defaults); and, on a table with a friction axis, ``friction``: the coefficient of
        friction of a step given none. The friction coefficient of Nadal's limit is the
        one the wheel's forces were solved with (the table's, or the wheel's on the
        friction axis), whatever ``settings.friction`` says.

    Raises
    ------
    RailContactError
        For a ``table`` or ``settings`` of another type, an unknown method, ``cubic`` on
        a table with an axis of fewer than 4 nodes,
        a table without ``penetration`` (an earlier store) or
        whose wheel flange is neither stored nor readable from its wheel profile.
    """

    def __init__(self, table: ContactTable, method: str = "linear",
                 settings: ContactSettings | None = None) -> None:
        if not isinstance(table, ContactTable):
            raise RailContactError("table must be a ContactTable (ContactTable.open(path)), "
                                   f"got {table!r}")
        if settings is not None and not isinstance(settings, ContactSettings):
            raise RailContactError(f"settings must be ContactSettings, got {settings!r}")
        check_method_fits(table.axes, method)  # (cubic on short axes: every step out of range)
        lacking = [n for n in VALIDITY_QUANTITIES if n in table.missing]
        if lacking:
            raise RailContactError(
                f"the table {table.path} was built by an earlier railcontact without "
                f"{', '.join(lacking)}, which a table step needs for its validity "
                "(penetration, flange climb); build it anew with railcontact table build")
        self.table, self.method = table, method
        case = table.case
        tangential = case.get("tangential") or {}
        settings = ContactSettings() if settings is None else settings
        self.settings = settings
        """The settings given (their ``friction``: a step's without one, on a table with a
        friction axis)."""
        self.limits = replace(settings, friction=tangential.get("friction", settings.friction))
        """The validity limits (with the table's friction coefficient)."""
        self.flange = table.flange
        """S [m] and angle [rad] of the steepest point of the wheel's flange."""
        creep = tangential.get("creepage", (0.0, 0.0, 0.0))
        fixed = {"lateral_displacement": case["geometry"]["lateral_displacement"],
                 "yaw": case["geometry"]["yaw"], "load": case["normal"].get("load"),
                 "creepage_x": creep[0], "creepage_y": creep[1], "spin": creep[2],
                 "friction": tangential.get("friction")}
        self.fixed = fixed
        order = list(_STATE)
        self._take = [order.index(n) for n in table.axes]
        self._absent = [(order.index(n), n, fixed[n]) for n in order if n not in table.axes]
        self._j = {s: table.sides.index(s) for s in table.sides}
        self.memory: StepMemory = EMPTY_MEMORY
        """Always empty (a table keeps nothing between steps); there so that the FMU's
        get/set state handles a table as it handles ``WheelsetContact``."""
        if table.names != _FIELDS:  # _fill unpacks the values in this order
            raise RailContactError(f"table quantities {table.names} are not {_FIELDS}")

    @classmethod
    def open(cls, path: str | Path, method: str = "linear",
             settings: ContactSettings | None = None,
             out_of_range: dict[str, str] | str | None = None) -> TableContact:
        """The table step of the store at ``path`` (arguments as the class's;
        ``out_of_range`` overrides the store's policies, as
        :meth:`ContactTable.open`)."""
        return cls(ContactTable.open(path, out_of_range), method, settings)

    def reset(self) -> None:
        """Nothing to forget: a table has no memory between steps."""
        self.memory = EMPTY_MEMORY

    def solve(self, pose: Pose, *, loads: tuple[float, float] | None = None,
              vertical: float | None = None,
              creepages: tuple[tuple[float, float, float], tuple[float, float, float]]
              | None = None, kinematics: Kinematics | None = None,
              time: float | None = None, remember: bool = True,
              rails: tuple | None = None, friction: tuple[float, float] | None = None
              ) -> WheelsetResult:
        """Both wheels from the table (arguments as ``WheelsetContact.solve``; ``time`` and
        ``remember`` are accepted and unused). Without creepages and kinematics the
        creepages are zero. A table has no axes for rail deviations, a friction per step or
        a track curvature: given, they are an error. ``friction`` (left, right) [-] is
        looked up on the table's friction axis (None: ``settings.friction`` on both); a
        table without one refuses it."""
        t0 = perf_counter()
        if vertical is not None or loads is None:
            raise RailContactError("a contact table is built by wheel load: give loads "
                                   "(left, right) [N] (penetration control is not in a table)")
        # the inputs checked as WheelsetContact checks them (each named where it is not a
        # number of its kind: a pose that is not a Pose, a load or creepage not a finite
        # float, a creepage not three of them)
        pose, (ql, qr), _, creepages, kinematics, _ = checked_inputs(
            pose, loads, None, creepages, kinematics, time, "railcontact")
        if rails is not None or (kinematics is not None and kinematics.curvature != 0.0):
            raise RailContactError("a contact table has no axes for rail deviations or the "
                                   "track curvature; solve with the exact contact "
                                   "(contact_model = bem)")
        mus = self._friction(friction)
        if creepages is not None:
            (xl, el, pl), (xr, er, pr) = creepages
        else:
            xl = el = pl = xr = er = pr = 0.0
        kin = kinematics if creepages is None else None
        left = self._wheel("left", pose, ql, (xl, el, pl), kin, mus[0])
        right = self._wheel("right", pose, qr, (xr, -er, -pr), kin, mus[1])
        return WheelsetResult(left, right, perf_counter() - t0)

    def _friction(self, friction: tuple[float, float] | None) -> tuple:
        """Each wheel's coefficient of friction at a step: ``friction`` (checked), else
        ``settings.friction`` on a table with a friction axis, else the table's."""
        if "friction" not in self.table.axes:
            if friction is not None:
                raise RailContactError(
                    f"the table has no friction axis ([table] friction = [...]): it holds "
                    f"friction = {self.fixed['friction']} only; build a table with a "
                    "friction axis for a friction per step, or solve with the exact contact "
                    "(contact_model = bem)")
            return (self.fixed["friction"],) * 2
        if friction is None:
            return (float(self.settings.friction),) * 2
        return tuple(check_positive(f"{s} friction", float(mu), "")
                     for s, mu in zip(SIDES, per_wheel("friction", friction, 1,
                                                       "(left, right) [-]"), strict=True))

    def _lookup(self, j: int, state: tuple[float, ...]):
        """(values, status, message) at ``state`` (in :data:`_STATE` order); values None
        when out of range."""
        for k, name, fixed in self._absent:
            v = state[k]
            if v != fixed and (fixed is None or not math.isclose(
                    v, fixed, rel_tol=ABSENT_RTOL, abs_tol=1e-12)):
                return None, OUT_OF_RANGE, (f"{name} = {v:g} {AXES[name].unit}: the "
                                            f"table has no {name} axis; it holds "
                                            f"{name} = {fixed} only")
        x, clamped = self.table.clamp([state[k] for k in self._take])
        if self.method == "linear":
            try:
                vals, status = self.table.linear(x, j)
            except RailContactError as exc:  # outside an axis
                return None, OUT_OF_RANGE, str(exc)
        else:
            try:
                r = self.table(dict(zip(self.table.axes, x)),  # noqa: B905 - same length
                               self.table.sides[j], self.method)
            except RailContactError as exc:
                return None, OUT_OF_RANGE, str(exc)
            vals, status = np.array([r.values[n] for n in self.table.names]), r.status
        if status == NOT_COMPUTED:
            return None, OUT_OF_RANGE, "the table's nodes around this state are not computed"
        if not clamped:
            return vals, status, ""
        return vals, status, "; ".join(
            f"{n} = {state[k]:g} {AXES[n].unit} clamped to {v:g}"
            for n, k, v in ((n, self._take[a], x[a]) for a, n in enumerate(self.table.axes))
            if n in clamped)

    def _wheel(self, side: str, pose: Pose, load: float, creep: tuple[float, float, float],
               kin: Kinematics | None, mu: float | None) -> WheelContact:
        """One wheel; ``creep`` in its side frame, ``mu`` its coefficient of friction."""
        j = self._j.get(side)
        if j is None:
            return WheelContact(side=side, status=OUT_OF_RANGE,
                                message=f"the table has no {side} wheel")
        if load <= 0.0:
            return WheelContact(side=side)
        if kin is not None:  # the creepages of the table's contact point
            mid = {n: 0.5 * (v[0] + v[-1]) for n, v in self.table.axes.items()
                   if n in CREEPAGE_AXES}
            state = (pose.lateral, pose.yaw, load, mid.get("creepage_x", self.fixed[
                "creepage_x"]), mid.get("creepage_y", self.fixed["creepage_y"]),
                mid.get("spin", self.fixed["spin"]), mu)
            vals, status, msg = self._lookup(j, state)
            if vals is None:
                return WheelContact(side=side, status=status, message=msg)
            g = dict(zip(self.table.names, vals.tolist(), strict=True))
            cp = SimpleNamespace(side=side, contact_angle=g["contact_angle"],
                                 rolling_radius=g["rolling_radius"],
                                 position=(0.0, g["contact_y"], 0.0))
            xi, eta, phi = kin.creepage(cp, pose, self.table.case["geometry"]["wheel_radius"])
            s = SIDES[side]
            creep = (xi, s * eta, s * phi)
        vals, status, msg = self._lookup(j, (pose.lateral, pose.yaw, load, *creep, mu))
        if vals is None:
            return WheelContact(side=side, status=status, message=msg)
        limits = self.limits
        if "friction" in self.table.axes:  # Nadal's limit with the value looked up
            x, _ = self.table.clamp([mu if n == "friction" else self.table.axes[n][0]
                                     for n in self.table.axes])
            limits = replace(limits, friction=x[list(self.table.axes).index("friction")])
        wheel = self._fill(side, vals, status, creep, limits)
        if msg:  # clamped (out_of_range = clamp)
            wheel = replace(wheel, message=f"{wheel.message}; {msg} (the table's "
                                           "out_of_range policy)")
        return wheel

    def _fill(self, side: str, vals: np.ndarray, status: int, creep, limits: ContactSettings
              ) -> WheelContact:
        (fn, fx, fy, mz, tx, ty, tz, ym, cx, cy, cz, ws, rs, ga, rr, ar, pm, sl,
         pen, ts, ta) = vals.tolist()
        if status != OK:
            forces = (fn, fx, fy, mz, tx, ty, tz, ym, ar, pm, sl, pen)
            if status == NO_CONTACT or not all(map(math.isfinite, forces)):
                return WheelContact(side=side, status=status, message=(
                    "no contact" if status == NO_CONTACT else
                    "the table has no value here (a node around it is not ok)"))
            cx, cy, cz, ws, rs, ga, rr = (0.0 if not math.isfinite(a) else a
                                          for a in (cx, cy, cz, ws, rs, ga, rr))
            ts, ta = (ws, ga) if not math.isfinite(ts + ta) else (ts, ta)
        s = SIDES[side]
        c = (creep[0], s * creep[1], s * creep[2])
        wheel = WheelContact(
            side=side, status=status,
            message="ok (table)" if status == OK else "a node of the table did not converge",
            creepages=[c], normal_force=fn,
            creep_force=(fx, fy), spin_moment=mz, track_force=(tx, ty, tz), yaw_moment=ym,
            wheel_position=ws, rail_position=rs, lateral_position=cy, contact_angle=ga,
            rolling_radius=rr, area=ar, max_pressure=pm, slip_area_ratio=sl,
            contact_point=(cx, cy, cz), penetration=pen,
            derailment_quotient=derailment_quotient(s, (tx, ty, tz)),
            # the creep forces' power per unit speed, as an exact step's
            frictional_power_per_speed=fx * c[0] + fy * c[1] + mz * c[2])
        if fn > 0.0:
            wheel = wheel.with_validity(check_limits(s, wheel.track_force, [(ts, ta)], pen,
                                                     self.flange, limits))
        return wheel


_STATE = ("lateral_displacement", "yaw", "load", "creepage_x", "creepage_y", "spin",
          "friction")
"""The order of a wheel's state in :meth:`TableContact._lookup`."""
_FIELDS = ("normal_force", "creep_force_x", "creep_force_y", "spin_moment",
           "force_longitudinal", "force_lateral", "force_vertical", "yaw_moment",
           "contact_x", "contact_y", "contact_z", "wheel_position", "rail_position",
           "contact_angle", "rolling_radius", "area", "max_pressure", "slip_area_ratio",
           "penetration", "tip_position", "tip_angle")
_GEOMETRIC = ("contact_x", "contact_y", "contact_z", "wheel_position", "rail_position",
              "contact_angle", "rolling_radius")

__all__ = ["TableContact"]
