"""The result types of a contact solve: one patch, and a whole case."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..geometry.points import ContactPoint, ReferencePoint
from ..halfspace.hertz import HertzSolution
from ..normal import NormalResult
from ..normal.starterror import EstimateError, estimate_error
from ..settings import Case
from ..settings.convention import reported_forces, side_creepage
from ..status import Work
from ..tangential import TangentialResult
from ..tangential.strips import StripResult
from .start import WarmStart


@dataclass(frozen=True)
class PatchSolution:
    """Solution on one contact patch: a frozen record, each stage of a solve forming a
    new one (:func:`dataclasses.replace`).

    Attributes
    ----------
    normal
        The BEM normal solution.
    hertz
        Hertz's solution for the same curvatures and the same load (force control) or
        penetration (penetration control), for comparison and as an estimate.
    estimate
        The name of the initial estimate used.
    tangential
        The tangential solution (BEM, FASTSIM or FaStrip), or None.
    tangential_model, tangential_estimate
        The tangential model and the BEM's initial estimate.
    curvatures
        Relative curvatures (A, B) [1/m] of the gap at the patch origin.
    geometry
        The wheel-rail contact point of the patch, or None for a quadratic case.
    work
        The iterations, passes, re-meshes and time it took, over all passes (the
        ``iterations`` of ``normal`` and ``tangential`` are those of the last solve only).
    """

    normal: NormalResult
    hertz: HertzSolution | None = None
    estimate: str = "none"
    tangential: TangentialResult | StripResult | None = None
    tangential_model: str = "bem"
    tangential_estimate: str = "none"
    curvatures: tuple[float, float] | None = None
    geometry: ContactPoint | None = None
    work: Work = field(default_factory=Work)
    friction: float | None = None
    """The coefficient of friction [-] the tangential problem was solved with: with a
    friction table the one at the patch's reference point (per element row where the table
    says so, :class:`~railcontact.settings.friction.FrictionTable`); None without one."""
    load_unique: bool | None = None
    """Whether the wheel load has one solution: False when a steep patch's creep force
    (:func:`~.loadloop.load_unique`) or a merge of patches
    (:attr:`load_other`) may let it be carried at another approach too; None where no
    load loop ran."""
    load_other: float | None = None
    """The vertical approach [m] beyond first contact of another solution of the wheel's
    load (found below this one's), or of the merge of patches beyond which another lies
    (:func:`~railcontact.contact.loadloop.first_root`); None when none was found."""
    reference: ReferencePoint | None = None
    """CONTACT's contact reference point of the patch (wheel-rail cases)."""
    convention: str = "railcontact"
    """The convention :attr:`creep_forces` and the JSON report the forces in: railcontact's
    (on the wheel, side frame) or CONTACT's (on the rail, its frame and mirroring; the
    result arrays - tractions - stay railcontact's)."""
    started_from: str | None = None
    """What the last normal solve started from when it was not the estimate named by
    :attr:`estimate`: "previous load pass" (a load loop's pass before, on the same
    contact point); None: the estimate."""
    creepage: tuple[float, float, float] | None = None
    """The creepages (xi [-], eta [-], phi [1/m]) the tangential problem was solved with,
    railcontact's (side frame, body 1 the wheel; :attr:`reported_creepage` gives them in
    :attr:`convention`); None without a tangential solution."""
    velocity: float | None = None
    """The reference velocity [m/s] of the creepages (the patch's rolling speed, from the
    case's ``[kinematics]``: :mod:`railcontact.geometry.kinematics`); None when the case
    gives creepages, not velocities."""
    kinematic_radius: float | None = None
    """The rolling radius [m] where the ``[kinematics]`` creepages were taken: the distance
    of the wheel's point below the reference point from the axle (CONTACT's ``r(cp)``); None
    when the case gives creepages."""
    frictional_power_per_speed: float | None = None
    """The traction times the relative slip (slip velocity over the rolling speed)
    integrated over the patch [N = W per m/s]: the frictional power at unit rolling speed,
    negative (the traction opposes the slip); formed where a case's solution is made
    (:func:`with_frictional_power`). None without a BEM tangential solution (the strip
    models have no slip field) and in a time step's patches (its wheels sum the power from
    the energy balance: :attr:`~railcontact.timestep.WheelContact.frictional_power`)."""
    frictional_power: float | None = None
    """Frictional power of the patch [W]: the traction times the local slip velocity
    integrated over the patch, ``V_ref`` (:attr:`velocity`) times
    :attr:`frictional_power_per_speed`; negative, the power dissipated (CONTACT's sign; the
    same in both conventions). None without a rolling speed (creepages given) or without a
    slip field. In steady rolling it equals ``V_ref (F_x xi + F_y eta + M_z phi)`` with the
    forces and creepages of one convention (the energy balance; on a grid to the
    discretisation's accuracy)."""
    start: WarmStart | None = field(default=None, repr=False, compare=False)
    """The start the last normal solve was given (:class:`~.start.WarmStart`); its
    traction starts the patch's tangential BEM when no earlier load pass does. Not
    reported, and not pickled (a start holds the functions of its solve: a pickled
    solution is its values)."""

    def __getstate__(self) -> dict[str, Any]:
        return {k: v for k, v in self.__dict__.items() if k != "start"}

    def replaced(self, **changes: Any) -> PatchSolution:
        """This patch with ``changes`` to its fields: a new record, as
        :func:`dataclasses.replace` forms it, from the fields' values directly (a third of
        replace's cost: a solve's stages form each patch anew a few times a wheel)."""
        return PatchSolution(**{**vars(self), **changes})

    @property
    def estimate_error(self) -> EstimateError | None:
        """How good the start of the last normal solve (the one ``normal.iterations``
        counts) was: its L1 pressure error and the elements it missed and added, against
        that solve's solution on the same grid (converged to the case's tolerance when
        ``normal.converged``); None when the solve started from its own uniform pressure
        (no estimate). Formed when asked (the solve keeps only its start)."""
        start = self.normal.start
        return None if start is None else estimate_error(start, self.normal.pressure)

    @property
    def creep_forces(self) -> tuple[float, float, float] | None:
        """(F_x [N], F_s [N], M_n [N m]) of the tangential solution in :attr:`convention`
        (:mod:`railcontact.settings.convention`); None without one."""
        t = self.tangential
        if t is None:
            return None
        if self.geometry is None:  # a quadratic patch: Kalker's convention, as CONTACT's
            return (*t.force, t.spin_moment)
        return reported_forces(*t.force, t.spin_moment, self.geometry.side, self.convention)

    @property
    def reported_creepage(self) -> tuple[float, float, float] | None:
        """:attr:`creepage` in :attr:`convention` (CONTACT's: rail minus wheel, its
        mirroring; :mod:`railcontact.settings.convention`)."""
        if self.creepage is None:
            return None
        if self.geometry is None:
            return self.creepage
        return side_creepage(self.creepage, self.geometry.side, self.convention)

    @property
    def converged(self) -> bool:
        """Whether the patch's normal and tangential solutions converged."""
        t = self.tangential
        return self.normal.converged and (t is None or t.converged)

    @property
    def message(self) -> str:
        """"ok", else the message of its first solution (normal, then tangential) that did
        not converge."""
        for r in (self.normal, self.tangential):
            if r is not None and not r.converged:
                return r.message
        return "ok"

    def _estimate_error_dict(self) -> dict[str, Any] | None:
        e = self.estimate_error
        if e is None:
            return None
        return {**e.to_dict(), "start": self.started_from or self.estimate}

    def to_dict(self) -> dict[str, Any]:
        n = self.normal
        d: dict[str, Any] = {
            "normal": {
                "force": n.force, "penetration": n.penetration,
                "max_pressure": n.max_pressure, "area": n.area,
                "iterations": n.iterations, "converged": n.converged,
                "message": n.message, "wall_time": n.wall_time, "error": n.error,
                "estimate": self.estimate,
                "grid": {"nx": n.grid.nx, "ny": n.grid.ny, "dx": n.grid.dx, "dy": n.grid.dy,
                         "bounds": list(n.grid.bounds)},
            }
        }
        error = self._estimate_error_dict()
        if error is not None:  # (JSON's null is "not finite": none without a start)
            d["normal"]["estimate_error"] = error
        if self.geometry is not None:
            g = self.geometry
            d["side"] = g.side
            d["contact_point"] = list(g.position)
            d["contact_angle"] = g.contact_angle
            d["rolling_radius"] = g.rolling_radius
            d["wheel_profile_coordinate"] = g.wheel_s
            d["rail_profile_coordinate"] = g.rail_y
            d["curvatures"] = [g.A, g.B]
            d["gap"] = g.gap
        if self.reference is not None:
            r = self.reference
            d["reference_point"] = {
                "position": list(r.position), "rail_profile_coordinate": r.rail_y,
                "wheel_profile_coordinate": r.wheel_s, "contact_angle": r.contact_angle,
                "rolling_radius": r.rolling_radius, "offset": list(r.offset)}
        if self.tangential is not None:
            t = self.tangential
            fx, fs, mn = self.creep_forces
            d["tangential"] = {
                "force": [fx, fs], "spin_moment": mn,
                "slip_area_ratio": t.slip_area_ratio, "max_traction": t.max_traction,
                "iterations": t.iterations, "converged": t.converged, "message": t.message,
                "wall_time": t.wall_time, "model": self.tangential_model,
                "estimate": self.tangential_estimate,
            }
            if self.creepage is not None:
                d["tangential"]["creepage"] = list(self.reported_creepage)
                d["creepage"] = list(self.reported_creepage)
            per = self.frictional_power_per_speed
            if per is not None:
                d["tangential"]["frictional_power_per_speed"] = per
            if self.velocity is not None:
                d["tangential"]["velocity"] = self.velocity
                d["tangential"]["kinematic_radius"] = self.kinematic_radius
            if self.frictional_power is not None:
                d["frictional_power"] = self.frictional_power
            if self.friction is not None:
                d["tangential"]["friction"] = self.friction
        if self.hertz is not None:
            h = self.hertz
            d["hertz"] = {"a": h.a, "b": h.b, "force": h.load, "penetration": h.penetration,
                          "max_pressure": h.max_pressure, "area": h.area}
        if self.load_unique is not None:
            d["load_unique"] = self.load_unique
        if self.load_other is not None:
            d["load_other_approach"] = self.load_other
        d["work"] = self.work.to_dict()
        return d


def with_frictional_power(patch: PatchSolution) -> PatchSolution:
    """``patch`` with its :attr:`~PatchSolution.frictional_power_per_speed` and
    :attr:`~PatchSolution.frictional_power` formed from its BEM tangential solution's slip
    (one product with the operator, :meth:`~railcontact.tangential.TangentialResult.
    relative_slip`): a new record; ``patch`` itself without one."""
    t = patch.tangential
    if t is None or not hasattr(t, "relative_slip"):
        return patch
    g = t.grid
    per = float(np.sum(np.asarray(t.traction) * t.relative_slip())) * g.dx * g.dy
    return patch.replaced(frictional_power_per_speed=per, frictional_power=None
                          if patch.velocity is None else patch.velocity * per)


def patches_work(patches: list[PatchSolution]) -> Work:
    """The work of one wheel's (or one problem's) ``patches``: their iterations,
    re-meshes and time summed, their load passes once (the patches of a wheel share
    them)."""
    if len(patches) == 1:  # (the common case: the sums of one are its own values)
        return patches[0].work
    works = [p.work for p in patches]
    return Work(sum(w.normal_iterations for w in works),
                sum(w.tangential_iterations for w in works),
                max((w.load_passes for w in works), default=0),
                sum(w.remeshes for w in works), sum(w.seconds for w in works))


@dataclass(frozen=True)
class Solution:
    """The solution of a case: one entry per contact patch.

    ``roll`` [rad] is the wheelset roll the wheel-rail patches were solved at (resolved
    when the case gives ``roll = "rigid"`` or ``"equal-loads"``); None for a quadratic case.
    ``seconds`` is the wall time of the whole solve [s]; :attr:`work` the totals.
    """

    case: Case
    patches: list[PatchSolution] = field(default_factory=list)
    roll: float | None = None
    seconds: float = 0.0

    @property
    def converged(self) -> bool:
        """Whether every patch's normal and tangential solutions converged."""
        return all(p.normal.converged and (p.tangential is None or p.tangential.converged)
                   for p in self.patches)

    @property
    def message(self) -> str:
        """"ok", else the first patch's that did not converge (:attr:`PatchSolution.
        message`), with its number (from 0) and side."""
        for k, p in enumerate(self.patches):
            if not p.converged:
                side = "" if p.geometry is None else f" ({p.geometry.side} wheel)"
                return f"patch {k}{side}: {p.message}"
        return "ok"

    @property
    def work(self) -> Work:
        """The patches' work summed, with the wall time of the whole solve [s]; the load
        passes of each wheel (the patches of a wheel share them) added over the wheels."""
        passes: dict[str | None, int] = {}
        for p in self.patches:
            side = None if p.geometry is None else p.geometry.side
            passes[side] = max(passes.get(side, 0), p.work.load_passes)
        total = Work(load_passes=sum(passes.values()) if passes else 0, seconds=self.seconds)
        for p in self.patches:
            total = total.absorbed(replace(p.work, seconds=0.0))
        return total

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (SI units)."""
        d: dict[str, Any] = {"name": self.case.name, "convention": self.case.convention}
        if self.roll is not None:
            d["roll"] = self.roll
        d["patches"] = [p.to_dict() for p in self.patches]
        d["work"] = self.work.to_dict()
        return d
