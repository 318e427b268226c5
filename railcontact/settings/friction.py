"""Friction that varies across the profile: a table of the coefficient of friction against
the rail's surface inclination or against the rail profile coordinate.

``[tangential] friction`` of a case file is a number (one coefficient everywhere) or a
table, as CONTACT's variable friction (``VARFRC``, its V digit = 1: ``NVF`` rows of
``ALPHA, FSTAT, FKIN`` with FSTAT = FKIN)::

    friction = {angle = [-0.349, -0.175], mu = [0.2, 0.3]}      # [rad], [-]
    friction = {rail_y = [-0.03, -0.02], mu = [0.1, 0.35]}      # [m], [-]

``mu`` is interpolated linearly between the points and held constant beyond the first and
the last (as CONTACT's ``interp_1d``). ``angle`` is the inclination of the rail surface
against the track plane [rad], in the case's ``convention``: railcontact's side frame
(positive towards the flange, on either wheel), or with ``convention = "contact"``
CONTACT's ``ALPHA`` (its contact angle: positive towards the flange on the left wheel,
negative on the right), so that CONTACT's table is copied as it is. ``rail_y`` is the
rail profile coordinate of the rail profile file (the same on either side).

``at`` says where the coefficient is read: ``"row"`` (the default) gives each lateral
row of elements of a patch its own coefficient, from the rail's surface inclination (or
profile coordinate) at that row, so that a patch reaching from a dry top onto a
lubricated gauge face sees both; ``"patch"`` gives a patch one coefficient, at its
contact reference point, which is what CONTACT does for planar (non-conformal) contact:
its ``m_wr_solvecp`` interpolates the table once per patch at the reference point's
contact angle in the wheelset's frame (``deltcp_w``: the track-frame angle less the
wheelset roll; railcontact reads the rail's, against the track plane), and per element row
only in its conformal approach (at each row's surface inclination).

Where one number stands for a patch (the load loop's uniqueness check, the output) it is
the coefficient at the patch's reference point (:func:`friction_at_point`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import CaseError
from ..geometry.points import samples

FRICTION_AXES = ("angle", "rail_y")
"""What a friction table is given against: the rail's surface inclination [rad] or the
rail profile coordinate [m]."""
FRICTION_AT = ("row", "patch")
"""Where a friction table is read: per lateral element row, or once per patch."""
MAX_MU = 10.0
"""The largest coefficient of friction a case may give (as a number)."""


@dataclass(frozen=True)
class FrictionTable:
    """The coefficient of friction [-] against the rail's surface inclination [rad]
    (``axis = "angle"``) or the rail profile coordinate [m] (``axis = "rail_y"``),
    interpolated linearly and held constant beyond the ends.

    Attributes
    ----------
    axis
        ``"angle"`` or ``"rail_y"``.
    points
        The abscissae, strictly increasing [rad] or [m].
    mu
        The coefficients of friction at them, positive [-].
    at
        ``"row"``: per lateral row of elements; ``"patch"``: one per patch, at its contact
        reference point.
    """

    axis: str
    points: tuple[float, ...]
    mu: tuple[float, ...]
    at: str = "row"

    @classmethod
    def from_mapping(cls, where: str, value: Mapping[str, Any]) -> FrictionTable:
        """The table of a case file's ``friction = {angle|rail_y = [...], mu = [...]}``
        (``at`` optional), every problem a :class:`~railcontact.errors.CaseError` naming
        ``where``."""
        form = (f"{where} must be a number or a table {{angle = [...], mu = [...]}} [rad] or "
                f"{{rail_y = [...], mu = [...]}} [m]")
        keys = set(value)
        axes = [a for a in FRICTION_AXES if a in keys]
        bad = keys - {*FRICTION_AXES, "mu", "at"}
        if bad or len(axes) != 1 or "mu" not in keys:
            extra = f" (unknown key(s) {sorted(bad)})" if bad else ""
            raise CaseError(f"{form}, got {dict(value)!r}{extra}")
        axis = axes[0]
        at = value.get("at", "row")
        if at not in FRICTION_AT:
            raise CaseError(f"{where} at must be one of {', '.join(map(repr, FRICTION_AT))}, "
                            f"got {at!r}")
        unit = "rad" if axis == "angle" else "m"
        points = _numbers(f"{where} {axis}", value[axis], unit)
        mu = _numbers(f"{where} mu", value["mu"], "")
        if len(points) != len(mu):
            raise CaseError(f"{where}: {axis} and mu must have the same length, got "
                            f"{len(points)} and {len(mu)}")
        for k in range(1, len(points)):
            if not points[k] > points[k - 1]:
                raise CaseError(f"{where} {axis} must be strictly increasing, got "
                                f"{points[k - 1]:g} then {points[k]:g} [{unit}]")
        for m in mu:
            if not 0.0 < m <= MAX_MU:
                raise CaseError(f"{where} mu must be positive and <= {MAX_MU:g}, got {m:g}")
        if axis == "angle" and any(abs(a) > math.pi / 2 for a in points):
            raise CaseError(f"{where} angle must lie within [-pi/2, pi/2] rad (surface "
                            f"inclinations), got {list(points)!r}; angles are in radians")
        return cls(axis, points, mu, at)

    def __call__(self, x: float | np.ndarray) -> float | np.ndarray:
        """The coefficient of friction [-] at ``x`` (the table's abscissa: [rad] or [m])."""
        out = np.interp(x, self.points, self.mu)
        return float(out) if np.ndim(out) == 0 else out

    @property
    def constant(self) -> float | None:
        """The coefficient when every point of the table has the same, else None."""
        return self.mu[0] if all(m == self.mu[0] for m in self.mu) else None

    @property
    def largest(self) -> float:
        """The largest coefficient of the table [-]."""
        return max(self.mu)

    def to_dict(self) -> dict[str, Any]:
        """The table as a case file writes it."""
        d: dict[str, Any] = {self.axis: list(self.points), "mu": list(self.mu)}
        if self.at != "row":
            d["at"] = self.at
        return d


def _numbers(where: str, value: Any, unit: str) -> tuple[float, ...]:
    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__") \
            or len(value) < 1:
        raise CaseError(f"{where} must be a non-empty list of numbers, got {value!r}")
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise CaseError(f"{where} must hold numbers, got {v!r}")
        if not math.isfinite(v):
            raise CaseError(f"{where} must be finite{f' [{unit}]' if unit else ''}, got {v!r}")
        out.append(float(v))
    return tuple(out)


def angle_sign(side: str, convention: str) -> float:
    """The factor turning railcontact's side-frame inclination (positive towards the
    flange) into a friction table's ``angle`` in ``convention``: 1, or with CONTACT's
    convention +1 on the left and -1 on the right wheel (CONTACT's contact angle)."""
    if convention != "contact":
        return 1.0
    return 1.0 if side == "left" else -1.0


def friction_at_point(friction: float | FrictionTable, cp: Any, convention: str = "railcontact"
                      ) -> float:
    """The coefficient of friction [-] at a wheel-rail contact point ``cp``
    (:class:`~railcontact.geometry.points.ContactPoint`: its contact angle [rad] or rail
    profile coordinate [m]); ``friction`` itself when it is a number."""
    if not isinstance(friction, FrictionTable):
        return friction
    if friction.axis == "angle":
        return float(friction(angle_sign(cp.side, convention) * cp.contact_angle))
    return float(friction(cp.rail_y))


def side_friction(friction: float | FrictionTable, side: str, convention: str
                  ) -> float | FrictionTable:
    """``friction`` with a table against the ``angle`` read in ``convention`` and turned
    into railcontact's side frame of the ``side`` wheel (positive towards the flange): with
    CONTACT's convention the right wheel's angles change sign (the table reversed)."""
    if (not isinstance(friction, FrictionTable) or friction.axis != "angle"
            or angle_sign(side, convention) > 0):
        return friction
    return FrictionTable("angle", tuple(-a for a in reversed(friction.points)),
                         tuple(reversed(friction.mu)), friction.at)


def row_friction(table: FrictionTable, cp: Any, track: Any) -> Callable[[Any], np.ndarray]:
    """The coefficient of friction of each lateral element row of the patch of the contact
    point ``cp`` (:class:`~railcontact.geometry.points.ContactPoint`, its patch frame), as a
    function of the patch's grid: an array (1, ny) [-].

    A row at the lateral coordinate ``y`` of the patch's tangent plane lies over the rail
    surface point (u(y), Z(y)) (the point's samples ``rail_u_of_s``, ``rail_z_of_s``); its
    ``angle`` is the rail's surface inclination there, ``atan(dZ/du)`` in the side frame
    (positive towards the flange, as the contact angle), its ``rail_y`` the rail profile
    coordinate of that point (``track.rail_coordinate``). ``table`` is in the side frame
    (:func:`side_friction`). Rows beyond the ends of the profiles take the value of the
    nearest row over them."""
    full = samples(cp)
    s, u, z = np.asarray(full.s), np.asarray(full.rail_u_of_s), np.asarray(full.rail_z_of_s)
    ok = np.isfinite(u) & np.isfinite(z)
    if ok.sum() < 2:
        mu0 = friction_at_point(table, cp)
        return lambda grid: np.full((1, grid.ny), mu0)
    s, u, z = s[ok], u[ok], z[ok]
    if table.axis == "angle":
        inclination = np.arctan(np.gradient(z, u))

        def on_grid(grid: Any) -> np.ndarray:
            return np.asarray(table(np.interp(grid.y, s, inclination)))[None, :]
        return on_grid

    def on_rails(grid: Any) -> np.ndarray:
        y = np.asarray(grid.y)
        uy, zy = np.interp(y, s, u), np.interp(y, s, z)
        ry = np.array([track.rail_coordinate(a, b) for a, b in zip(uy, zy, strict=True)])
        return np.asarray(table(ry))[None, :]
    return on_rails
