"""The vehicle's contact: one call per vehicle step, the wheelsets' states in, their wheel
forces out.

:class:`VehicleContact` is the interface the vehicle (:mod:`railcontact.sim.vehicle`)
integrates against. Two implementations:

* :class:`InProcessContact`: one :class:`~railcontact.timestep.WheelsetContact` per
  wheelset (the exact BEM, warm-started step after step), called one after the other or
  stepped at the same time in worker processes;
* :class:`LinearContact`: the linearised contact of
  :mod:`railcontact.sim.linear_contact` (Kalker's linear creep forces), for the checks
  against the eigenvalue analysis.

Another host of the same wheelsets (a multi-wheelset FMU driven through fmpy) is an
adapter of the same shape: set the per-wheelset inputs from :class:`WheelsetStates`, one
``doStep``, read the outputs into :class:`WheelForces`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from ..errors import RailContactError
from ..geometry.track import Pose, Track, Wheelset
from ..halfspace.materials import ElasticPair
from ..settings import ContactSettings
from ..status import Status
from ..timestep import Kinematics, WheelsetContact, WheelsetResult
from ..timestep.pool import WheelsetDescription, WheelsetPool
from .linear_contact import LinearWheelsetContact


@dataclass(frozen=True)
class WheelsetStates:
    """The wheelsets' states at one step (track frame, SI units); arrays of one value per
    wheelset (front to back) unless stated.

    Attributes
    ----------
    time
        t [s].
    speed
        Forward speed V [m/s] (all wheelsets).
    lateral, yaw
        y [m] (positive to the left), psi [rad] (nose left).
    lateral_velocity, yaw_rate
        dy/dt [m/s], dpsi/dt [rad/s].
    spin_speed
        Omega [rad/s] about the axle.
    loads
        Wheel loads (left, right) [N], shape (n, 2).
    """

    time: float
    speed: float
    lateral: np.ndarray
    yaw: np.ndarray
    lateral_velocity: np.ndarray
    yaw_rate: np.ndarray
    spin_speed: np.ndarray
    loads: np.ndarray

    @property
    def count(self) -> int:
        return len(self.lateral)


@dataclass
class WheelForces:
    """The rails' forces on the wheelsets at one step (SI units).

    Attributes
    ----------
    generalized
        (F_Y [N], M_Z [N m], T_y [N m]) per wheelset, (n, 3): the total lateral force,
        the yaw moment about the wheelset centre and the moment about the axle
        ``-(r_l F_X,l + r_r F_X,r)``.
    lateral, vertical, normal
        Per wheel (left, right), (n, 2): the rail's force on the wheel along track Y and Z
        and the normal force [N].
    derailment_quotient
        Y/Q per wheel, (n, 2) [-].
    status
        Per wheelset (:class:`~railcontact.status.Status` values), (n,).
    solve_time
        Wall time of each wheelset's solve [s], (n,).
    ok, message
        False when a wheelset could not be solved (off its rail, a solver error).
    """

    generalized: np.ndarray
    lateral: np.ndarray
    vertical: np.ndarray
    normal: np.ndarray
    derailment_quotient: np.ndarray
    status: np.ndarray
    solve_time: np.ndarray
    ok: bool = True
    message: str = "ok"
    iterations: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Normal + tangential BEM iterations per wheelset (in-process contact), (n,)."""


STOPPING = (Status.OUT_OF_RANGE, Status.NO_CONTACT)
"""The wheelset statuses that stop a vehicle run (``WheelForces.ok`` False): a pose
beyond the model, and no contact (the wheelset off its rails). A contact names every
wheelset of such a status in ``WheelForces.message``; an FMU contact stops as well on a
step the FMU discards."""


class VehicleContact(Protocol):
    """Wheelset states in, wheel forces out, once per vehicle step."""

    def __call__(self, states: WheelsetStates) -> WheelForces: ...


@dataclass
class LinearContact:
    """Kalker's linear contact (:class:`~.linear_contact.LinearWheelsetContact`) on every
    wheelset. Its per-wheel forces split the linear totals: lateral ``F_Y / 2`` on each
    wheel, the normal force and vertical force the wheel load."""

    model: LinearWheelsetContact

    def __call__(self, states: WheelsetStates) -> WheelForces:
        n = states.count
        q = np.stack([states.lateral, states.yaw, np.zeros(n)], axis=1)
        v = np.stack([states.lateral_velocity, states.yaw_rate, states.spin_speed], axis=1)
        g = self.model.force(q, v, states.speed)
        loads = np.asarray(states.loads, dtype=float)
        lat = np.repeat(g[:, :1] / 2, 2, axis=1)
        yq = np.stack([-lat[:, 0], lat[:, 1]], axis=1) / loads
        return WheelForces(g, lat, loads.copy(), loads.copy(), yq, np.zeros(n, dtype=int),
                           np.zeros(n))


def wheelset_inputs(states: WheelsetStates, i: int) -> dict[str, Any]:
    """The keyword arguments of :meth:`WheelsetContact.solve
    <railcontact.timestep.WheelsetContact.solve>` for wheelset ``i`` (load control,
    kinematic creepages)."""
    return dict(pose=Pose(float(states.lateral[i]), float(states.yaw[i])),
                loads=(float(states.loads[i, 0]), float(states.loads[i, 1])),
                kinematics=Kinematics(states.speed, float(states.lateral_velocity[i]),
                                      float(states.yaw_rate[i]),
                                      float(states.spin_speed[i])),
                time=states.time)


@dataclass(frozen=True)
class WheelsetRow:
    """What the vehicle reads of one wheelset's result (SI units): a
    :class:`WheelForces` row.

    Attributes
    ----------
    generalized
        (F_Y [N], M_Z [N m], T_y [N m]).
    lateral, vertical, normal, derailment_quotient
        Per wheel (left, right): track Y and Z forces [N], normal force [N], Y/Q [-].
    status
        The wheelset's :class:`~railcontact.status.Status` value.
    stop
        Why the wheelset stops the run (:data:`STOPPING`), else None.
    iterations
        Normal + tangential BEM iterations of both wheels.
    """

    generalized: tuple[float, float, float]
    lateral: tuple[float, float]
    vertical: tuple[float, float]
    normal: tuple[float, float]
    derailment_quotient: tuple[float, float]
    status: int
    stop: str | None
    iterations: int


def wheelset_row(r: WheelsetResult) -> WheelsetRow:
    """The :class:`WheelsetRow` of a wheelset's result (a module-level function: a
    :class:`~railcontact.timestep.pool.WheelsetPool` applies it in its workers)."""
    wl, wr = r.wheels
    stop = None
    if r.status in STOPPING:
        stop = "; ".join(w.message for w in r.wheels if w.status == r.status)
    return WheelsetRow(
        (r.force[1], r.yaw_moment,
         -(wl.rolling_radius * wl.track_force[0] + wr.rolling_radius * wr.track_force[0])),
        (wl.track_force[1], wr.track_force[1]), (wl.track_force[2], wr.track_force[2]),
        (wl.normal_force, wr.normal_force), (wl.derailment_quotient, wr.derailment_quotient),
        int(r.status), stop,
        sum(w.normal_iterations + w.tangential_iterations for w in r.wheels))


class InProcessContact:
    """One :class:`~railcontact.timestep.WheelsetContact` per wheelset, solved in this
    process one after the other, or in worker processes at the same time
    (:class:`~railcontact.timestep.pool.WheelsetPool`).

    Parameters
    ----------
    track, wheelset, pair, settings
        As :class:`~railcontact.timestep.WheelsetContact` (the same for all wheelsets).
    count
        Number of wheelsets.
    processes
        None: in this process, one after the other. Else the number of worker processes
        the wheelsets are stepped in (at most ``count``; each wheelset stays in its
        process); the results are the same bit for bit. Call :meth:`close` (or use as a
        context manager) to end them.
    """

    def __init__(self, track: Track, wheelset: Wheelset, pair: ElasticPair,
                 settings: ContactSettings | None = None, count: int = 4,
                 processes: int | None = None) -> None:
        self.count = count
        self.solvers: list[WheelsetContact] = []
        self.pool: WheelsetPool | None = None
        if processes is None:
            self.solvers = [WheelsetContact(track, wheelset, pair, settings)
                            for _ in range(count)]
        else:
            d = WheelsetDescription(track, wheelset, pair, settings)
            self.pool = WheelsetPool([d] * count, processes, reduce=wheelset_row)

    def _rows(self, states: WheelsetStates) -> tuple[list[WheelsetRow], np.ndarray]:
        n = states.count
        if self.pool is not None:
            rows = self.pool.step([wheelset_inputs(states, i) for i in range(n)])
            return rows, np.array(self.pool.seconds)
        rows, secs = [], np.zeros(n)
        for i, solver in enumerate(self.solvers):
            t0 = time.perf_counter()
            rows.append(wheelset_row(solver.solve(**wheelset_inputs(states, i))))
            secs[i] = time.perf_counter() - t0
        return rows, secs

    def __call__(self, states: WheelsetStates) -> WheelForces:
        n = states.count
        if n != self.count:
            raise RailContactError(f"{self.count} wheelsets expected, got {n}")
        rows, secs = self._rows(states)
        bad = [f"wheelset {i + 1}: {r.stop}" for i, r in enumerate(rows) if r.stop is not None]
        return WheelForces(
            np.array([r.generalized for r in rows]), np.array([r.lateral for r in rows]),
            np.array([r.vertical for r in rows]), np.array([r.normal for r in rows]),
            np.array([r.derailment_quotient for r in rows]),
            np.array([r.status for r in rows], dtype=int), secs, not bad,
            "; ".join(bad) or "ok", np.array([r.iterations for r in rows], dtype=float))

    def close(self) -> None:
        """End the worker processes, if any (idempotent)."""
        if self.pool is not None:
            self.pool.close()

    def __enter__(self) -> InProcessContact:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


__all__ = ["STOPPING", "InProcessContact", "LinearContact", "VehicleContact", "WheelForces",
           "WheelsetRow", "WheelsetStates", "wheelset_inputs", "wheelset_row"]
