"""What a wheelset step returns: each wheel's :class:`WheelContact` and the wheelset's
:class:`WheelsetResult` - frozen records of values, formed once, that compute nothing when
read - and :func:`resultants`, the sums of a wheel's patches that its record is formed
from (frames and signs as in :mod:`railcontact.timestep.wheelset`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numba
import numpy as np

from ..contact.results import PatchSolution, Work, patches_work
from ..contact.wheelrail import vertical_approach
from ..geometry.track import SIDES, Pose
from ..halfspace.grid import Grid
from ..halfspace.sums import numpy_sum
from ..status import Status
from .rigid import RigidSolution
from .validity import Validity, derailment_quotient

OK, NOT_CONVERGED, NO_CONTACT, OUT_OF_RANGE, OUTSIDE_VALIDITY = (
    Status.OK, Status.NOT_CONVERGED, Status.NO_CONTACT, Status.OUT_OF_RANGE,
    Status.OUTSIDE_VALIDITY)
STATUS_NAMES = {s: s.label for s in Status if s != Status.NOT_COMPUTED}
"""A wheel's status (:class:`~railcontact.status.Status`) and its label: ok; not converged
(a BEM solve or the load loop; forces given, less accurate); no contact (zero forces); out
of range (the pose or a patch beyond the model: nothing solved, zero forces); outside
validity (solved, but beyond a limit of :mod:`.validity`: Y/Q, Nadal's limit, flange
climb, penetration, wheel load, an under-resolved patch)."""
SEVERITY = tuple(sorted(STATUS_NAMES, key=lambda s: s.severity))
"""The statuses from the least to the most severe (:attr:`Status.severity`): the
wheelset's status is its wheels' most severe."""


@dataclass(frozen=True)
class WheelContact:
    """Contact of one wheel at one time step (SI units; see the module docstring).

    Forces are summed over the wheel's patches; the contact-point quantities are those of
    the patch with the largest normal force. A frozen record: formed once, from the sums
    of :func:`resultants`; a later check gives a new record (:meth:`with_validity`).
    """

    side: str
    status: Status = NO_CONTACT
    message: str = "no contact"
    patches: list[PatchSolution] = field(default_factory=list)
    creepages: list[tuple[float, float, float]] = field(default_factory=list)
    normal_force: float = 0.0
    creep_force: tuple[float, float] = (0.0, 0.0)
    spin_moment: float = 0.0
    track_force: tuple[float, float, float] = (0.0, 0.0, 0.0)
    yaw_moment: float = 0.0
    wheel_position: float = 0.0
    rail_position: float = 0.0
    lateral_position: float = 0.0
    contact_angle: float = 0.0
    rolling_radius: float = 0.0
    area: float = 0.0
    max_pressure: float = 0.0
    slip_area_ratio: float = 0.0
    contact_point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """The rigid contact point of the main patch in the track frame (X, Y, Z) [m]."""
    load_unique: bool = True
    """False when the wheel load (counting the creep forces) has, or may have, more than
    one solution; the message says why. Two of the wheel's contact regions joining into
    one patch between two roots (:func:`~railcontact.contact.loadloop.first_root`): the
    step returns the smallest approach, from warm and cold starts alike. Several patches,
    one with ``mu tan(gamma) >= 1`` (:func:`~railcontact.contact.loadloop.load_unique`):
    the one continuous with the previous step, or, cold, the one reached from the normal
    share Q."""
    validity: int = 0
    """The limits of :mod:`~railcontact.timestep.validity` the solved wheel is beyond (bits
    Y_Q 1, NADAL 2, FLANGE_CLIMB 4, PENETRATION 8, LOAD 16, RESOLUTION 32; 0 within all);
    any makes an otherwise ok wheel's status OUTSIDE_VALIDITY."""
    derailment_quotient: float = 0.0
    """Y/Q [-]: the wheel's lateral force on the rail towards the field side over the
    vertical force (:func:`~railcontact.timestep.validity.derailment_quotient`)."""
    approach: float = 0.0
    """Vertical approach of the wheel into its rail beyond first contact [m]."""
    penetration: float = 0.0
    """Largest normal penetration of its patches [m]."""
    frictional_power_per_speed: float = 0.0
    """The creep forces' power per unit forward speed [N = W/(m/s)], summed over the
    patches: ``F_x xi + F_y eta + M_z phi`` with each patch's forces on the wheel and the
    creepages it was solved with (the traction times the slip integrated over the patch,
    in steady rolling; negative: dissipated)."""
    frictional_power: float | None = None
    """Frictional power of the wheel [W]: the forward speed V times
    :attr:`frictional_power_per_speed` when the step's kinematics give V; None when the
    creepages were given."""
    moment: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Moment of the rail's forces on the wheel about the point (0, y, 0) of the track
    frame (under the wheelset centre, at rail-top height), track components (X, Y, Z)
    [N m]: the pressure and traction over each patch (each element's force at its place
    in the patch's plane: the spin moment and the pressure's offsets from the contact
    point included)."""
    work: Work = field(default_factory=lambda: Work(load_passes=0))
    """The work of the wheel's solves this step (:class:`~railcontact.status.Work`:
    iterations, load passes, re-meshes, wall time [s]), as the solver results give
    theirs; the counts below read it."""

    @property
    def n_patches(self) -> int:
        return len(self.patches)

    @property
    def normal_iterations(self) -> int:
        """Normal CG iterations of the step, over all patches, load passes and re-meshes."""
        return self.work.normal_iterations

    @property
    def tangential_iterations(self) -> int:
        """Tangential sweeps of the step, over all patches, load passes and re-meshes."""
        return self.work.tangential_iterations

    @property
    def load_passes(self) -> int:
        """Solves of the wheel this step: 0 without contact, more than one when a wheel
        load counts the creep forces (:attr:`ContactSettings.load_includes_creep`) or
        several patches share it."""
        return self.work.load_passes

    @property
    def remeshes(self) -> int:
        """Normal solves repeated on a grown potential area."""
        return self.work.remeshes

    @property
    def seconds(self) -> float:
        """Wall time of the wheel's patch solves [s] (estimates included)."""
        return self.work.seconds

    def with_validity(self, validity: Validity) -> WheelContact:
        """This wheel with a validity check recorded: its bits in :attr:`validity`; an ok
        wheel beyond a limit becomes OUTSIDE_VALIDITY, its message naming each quantity
        and value (a wheel with another status keeps it, the limits added to its
        message). The wheel itself where it is within every limit."""
        if not validity.flags:
            return self
        if self.status == OK:
            note = self.message.removeprefix("ok")  # e.g. "; the load may have several ..."
            return replace(self, validity=validity.flags, status=OUTSIDE_VALIDITY,
                           message=f"outside validity: {validity.message}{note}")
        return replace(self, validity=validity.flags,
                       message=f"{self.message}; also outside validity: {validity.message}")


@dataclass(frozen=True)
class WheelsetResult:
    """Both wheels at one time step, with the totals on the wheelset (track frame).

    A frozen record: its totals (:attr:`status`, :attr:`force`, :attr:`moment`,
    :attr:`yaw_moment`) are formed with it from its wheels and the rigid wheelset's
    solution; reading them computes nothing.
    """

    left: WheelContact
    right: WheelContact
    wall_time: float = 0.0
    wheelset_radius: float = 0.0
    """Nominal rolling radius r0 [m]: the centre's height above the rail tops at
    ``vertical = 0``."""
    vertical: float | None = None
    """Vertical displacement of the wheelset centre [m], positive up, from one nominal
    radius above the rail tops: the input under penetration control; under load control
    the rigid wheelset's at which both wheels, penetration-controlled, carry their loads,
    when :attr:`ContactSettings.rigid_wheelset` is "solve" (:mod:`~railcontact.timestep.
    rigid`; whether it was found: :attr:`rigid_solution`); None when not solved (skipped,
    or out of range)."""
    roll: float | None = None
    """Roll angle of the wheelset [rad] (positive: left side up): the pose's under
    penetration control, the rigid wheelset's under load control (as :attr:`vertical`)."""
    rigid_solution: RigidSolution | None = None
    """:attr:`vertical` and :attr:`roll` with whether they were found
    (:class:`~railcontact.timestep.rigid.RigidSolution`: under load control check its
    ``converged`` and ``message``); None where they were not solved."""
    rigid_work: tuple[Work, Work] = field(
        default_factory=lambda: (Work(load_passes=0), Work(load_passes=0)))
    """The work (:class:`~railcontact.status.Work`: iterations, load passes,
    re-meshes, wall time [s]) of the wheels' solves at the rolls the rigid wheelset's
    search evaluated, left and right; zero where it did not run. Not in the wheels' own
    counts: the step's whole work is the wheels' plus this."""

    status: Status = field(init=False)
    """The wheelset's status: the wheels' most severe (:data:`SEVERITY`), and
    ``NOT_CONVERGED`` at least where the rigid wheelset's :attr:`vertical` and :attr:`roll`
    were not found under load control (they, and the :attr:`moment` about the centre, are
    then the search's best iterate; :attr:`rigid_solution`'s ``message`` says by how much
    they miss), as the FMU's ``status``."""
    force: tuple[float, float, float] = field(init=False)
    """Total force (X, Y, Z) of the rails on the wheelset [N]."""
    moment: tuple[float, float, float] = field(init=False)
    """Moment of the rails' forces on the wheelset about its centre (0, y, r0 + vertical;
    r0 when :attr:`vertical` was not solved), track components (M_X roll, M_Y pitch, M_Z
    yaw) [N m]: right-handed about X forward, Y left, Z up (M_X > 0 lifts the left wheel,
    M_Z > 0 turns the nose to the left)."""
    yaw_moment: float = field(init=False)
    """Total moment about the vertical axis through the wheelset centre [N m]."""
    message: str = field(init=False)
    """What became of the step in words: "ok", else each wheel's message that is not
    plain "ok" (named by its side unless it names it) and, under load control, the rigid
    wheelset's when its vertical displacement and roll were not found."""
    work: Work = field(init=False)
    """The step's whole work (:class:`~railcontact.status.Work`): the wheels'
    iterations, load passes and re-meshes with those of the rigid wheelset's solves
    (:attr:`rigid_work`), and the step's wall time [s] (:attr:`wall_time`)."""

    def __post_init__(self) -> None:  # (the totals, formed once with the record)
        left, right = self.left, self.right
        status = Status.worst((left.status, right.status))
        rigid = self.rigid_solution
        if rigid is not None and not rigid.converged:
            status = Status.worst((status, Status.NOT_CONVERGED))
        force = tuple(float(left.track_force[k] + right.track_force[k]) for k in range(3))
        h = self.wheelset_radius + (self.vertical or 0.0)
        fx, fy, _ = force
        m = [left.moment[k] + right.moment[k] for k in range(3)]
        object.__setattr__(self, "status", status)
        object.__setattr__(self, "force", force)
        object.__setattr__(self, "moment", (m[0] + h * fy, m[1] - h * fx, m[2]))
        object.__setattr__(self, "yaw_moment", left.yaw_moment + right.yaw_moment)
        object.__setattr__(self, "message", _step_message(left, right, rigid))
        rigid_left, rigid_right = self.rigid_work
        object.__setattr__(self, "work", left.work.added(right.work).added(rigid_left)
                           .added(rigid_right).timed(self.wall_time))

    @property
    def wheels(self) -> tuple[WheelContact, WheelContact]:
        return (self.left, self.right)


def _step_message(left: WheelContact, right: WheelContact,
                  rigid: RigidSolution | None) -> str:
    """:attr:`WheelsetResult.message` of the wheels ``left`` and ``right`` and the rigid
    wheelset's solution ``rigid``."""
    said: list[str] = []
    for w in (left, right):
        m = w.message
        if m == "ok":
            continue
        if not m.startswith(("left", "right", "wheelset")):
            m = f"{w.side} wheel: {m}"
        if m not in said:  # (a wheelset-wide message is said once)
            said.append(m)
    if rigid is not None and not rigid.converged:
        said.append(f"rigid wheelset: {rigid.message}")
    return "; ".join(said) or "ok"


def _first_moments(grid: Grid, pressure: np.ndarray) -> tuple[float, float]:
    """The pressure's first moments ``sum x p dA``, ``sum y p dA`` [N m] about the grid's
    origin: ``(grid.x[:, None] * pressure).sum() * dA`` and the same with ``grid.y``, the
    products formed and added in numpy's order in one compiled pass (the same bits)."""
    da = grid.dx * grid.dy  # (Grid.element_area)
    if not pressure.flags.c_contiguous:  # (numpy's products would be laid out otherwise)
        return (float((grid.x[:, None] * pressure).sum() * da),
                float((grid.y[None, :] * pressure).sum() * da))
    sx, sy = _moment_sums(grid.x0, grid.dx, grid.y0, grid.dy, pressure)
    return sx * da, sy * da


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def _moment_sums(x0, dx, y0, dy, p):  # pragma: no cover - compiled
    """``sum x p`` and ``sum y p`` over the grid's element centres (as :attr:`Grid.x`,
    :attr:`Grid.y` form them: ``x0 + dx i``), each product array added as numpy adds it."""
    nx, ny = p.shape
    out = np.empty((2, nx, ny))
    for i in range(nx):
        x = x0 + dx * float(i)
        for j in range(ny):
            out[0, i, j] = x * p[i, j]
            out[1, i, j] = (y0 + dy * float(j)) * p[i, j]
    return numpy_sum(out[0]), numpy_sum(out[1])


def resultants(side: str, patches: list[PatchSolution], pose: Pose) -> dict[str, Any]:
    """The fields of the :class:`WheelContact` of the ``side`` wheel whose ``patches``
    were solved at ``pose``: their sums (module docstring for the frames), the main
    patch's contact point, the work, the status and message of their solves.

    Scalars and 3-vectors in plain floats (a per-step path: numpy's calls cost more than
    their arithmetic here), in the order of operations the array forms had."""
    sgn = SIDES[side]
    u_ws = sgn * pose.lateral
    fx = fs = mn = n_tot = 0.0
    fu = fz = mz = 0.0
    m0 = m1 = m2 = 0.0
    converged = True
    for p in patches:
        cp, n = p.geometry, p.normal
        g = cp.contact_angle
        cos_g, sin_g = math.cos(g), math.sin(g)
        t = p.tangential
        px, ps, pm = (0.0, 0.0, 0.0) if t is None else (*t.force, t.spin_moment)
        n_tot += n.force
        fx, fs, mn = fx + px, fs + ps, mn + pm
        f_u = ps * cos_g - n.force * sin_g
        fu += f_u
        f_z = ps * sin_g + n.force * cos_g
        fz += f_z
        # the pressure's first moments about the patch's origin (the contact point) along
        # x and s: the normal force acts at the pressure's centroid, not at the point
        first_x, first_s = _first_moments(n.grid, n.pressure)
        x, y, z = cp.position
        mz += (x * f_u - (cp.rail_u - u_ws) * px + pm * cos_g - first_x * sin_g)
        # track frame, about (0, y, 0): r x F, plus the spin couple (sgn pm) n (the
        # traction's moment about n through the origin), plus the pressure's offsets
        # x e_x + s e_s crossed with its normal n; e_s = (0, sgn cos(g), sin(g)),
        # n = (0, -sgn sin(g), cos(g)): e_x x n = (0, -cos(g), -sgn sin(g)), e_s x n =
        # (sgn, 0, 0)
        lx, ly, lz = float(x), float(y - pose.lateral), float(z)  # the lever r
        gx, gy, gz = float(px), float(sgn * f_u), float(f_z)  # the force F
        m0 += (ly * gz - lz * gy) + sgn * first_s
        m1 += (lz * gx - lx * gz) + (-pm * sin_g - first_x * cos_g)
        m2 += (lx * gy - ly * gx) + sgn * (pm * cos_g - first_x * sin_g)
        converged &= n.converged and (t is None or t.converged)
    single = len(patches) == 1  # (the common case: no generators)
    main = patches[0] if single else max(patches, key=lambda p: p.normal.force)
    cp = main.geometry
    track_force = (fx, sgn * fu, fz)
    if single:
        area, max_pressure = float(main.normal.area), float(main.normal.max_pressure)
    else:
        area = float(sum(p.normal.area for p in patches))
        max_pressure = float(max(p.normal.max_pressure for p in patches))
    ts = ([] if main.tangential is None else [main.tangential]) if single else [
        p.tangential for p in patches if p.tangential is not None]
    slip_area_ratio = 0.0
    if len(ts) == 1:  # one patch: its own ratio, the same count (slip over non-exterior)
        slip_area_ratio = ts[0].slip_area_ratio
    elif ts:
        n_el = [int(np.count_nonzero(t.state)) for t in ts]
        n_slip = [int(np.count_nonzero(t.state == 2)) for t in ts]
        slip_area_ratio = sum(n_slip) / max(sum(n_el), 1)
    if converged:
        status, message = OK, "ok"
    else:
        failed = [r.message for p in patches for r in (p.normal, p.tangential)
                  if r is not None and not r.converged]
        status, message = NOT_CONVERGED, f"a BEM solve did not converge: {failed[0]}"
    return dict(
        side=side, status=status, message=message, patches=patches,
        normal_force=n_tot, creep_force=(fx, sgn * fs), spin_moment=sgn * mn,
        track_force=track_force, yaw_moment=sgn * mz, moment=(float(m0), float(m1), float(m2)),
        derailment_quotient=derailment_quotient(sgn, track_force),
        approach=vertical_approach(patches),
        penetration=float(main.normal.penetration if single else
                          max(p.normal.penetration for p in patches)),
        wheel_position=cp.wheel_s, rail_position=cp.rail_y, lateral_position=cp.position[1],
        contact_point=cp.position, contact_angle=cp.contact_angle,
        rolling_radius=cp.rolling_radius, area=area, max_pressure=max_pressure,
        slip_area_ratio=slip_area_ratio, work=patches_work(patches))
