"""A bogie passenger vehicle on tangent track: car body, two bogie frames, four wheelsets,
primary and secondary suspension; its matrices and its co-simulated time step.

Degrees of freedom (21; track frame X forward, Y left, Z up; SI units):

* wheelset ``i`` (0 .. 3, front to back; 0 and 1 in the front bogie): lateral ``y``, yaw
  ``psi`` and rotation about its axle ``theta`` (velocity: the spin speed ``Omega``), as
  :mod:`railcontact.sim.dynamics`' wheelset; DOFs ``3 i .. 3 i + 2``;
* bogie frame ``j`` (0 front, 1 rear): lateral ``y``, yaw ``psi``, roll ``phi`` (left side
  up); DOFs ``12 + 3 j ..``;
* car body: lateral, yaw, roll; DOFs ``18, 19, 20``.

All coordinates are those of the centres of gravity; the wheelsets' roll and vertical
motion are left to the contact solver (wheel loads given). The suspension is linear (small
motions about the static position): each element ``k g g^T`` with ``g`` the influence
vector of its deflection. A lateral element at height ``h`` and longitudinal position
``x`` deflects with ``y + x psi - (h - h_cg) phi`` of each body it joins; yaw and roll
elements are the longitudinal and vertical springs at ``+-b`` (``2 k b^2``). Primary: per
wheelset lateral ``2 k_y1`` at axle height, yaw ``2 k_x1 b1^2``, and the frame's roll
``2 k_z1 b1^2`` (wheelset roll zero); secondary per bogie: lateral ``2 k_y2`` at
:attr:`~.vehicle_data.VehicleParameters.secondary_height`, yaw ``2 k_x2 b2^2``, roll
``2 k_z2 b2^2`` plus the anti-roll bar and the air springs' bending ``2 k_b``. Gravity
makes roll softer: the car body, carried at the secondary height, ``-m_c g (h_c - h_s)``;
a frame, loaded by half the car body at ``h_s`` and carried at axle height,
``-g (m_c / 2 (h_s - h_w) + m_b (h_b - h_w))``.

The time step is :mod:`railcontact.sim.dynamics`' linearly implicit one for the whole
vehicle: ``(M - h (D - C)) (v[n+1] - v[n]) = h (F_c(q[n], v[n]) - K q[n] - C v[n])``,
``q[n+1] = q[n] + h v[n+1]``, with ``F_c`` the wheelsets' contact forces from a
:class:`~railcontact.sim.vehicle_contact.VehicleContact` (wheelset states in, wheel forces
out: once per step) and ``D`` the contact's velocity Jacobian (block-diagonal, 3 x 3 per
wheelset; Kalker's linear one is close enough for stability).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ..errors import RailContactError, check_finite, check_positive
from .vehicle_contact import VehicleContact, WheelForces, WheelsetStates
from .vehicle_data import GRAVITY, VehicleParameters

WHEELSETS = 4
DOFS = 21
CARBODY = (18, 19, 20)
SPIN = tuple(3 * i + 2 for i in range(WHEELSETS))
POSITIONS = tuple(k for k in range(DOFS) if k not in SPIN)
"""The DOFs whose positions enter the forces (all but the wheelsets' axle rotations)."""
NAMES = tuple([f"wheelset{i + 1}_{n}" for i in range(WHEELSETS)
               for n in ("lateral", "yaw", "rotation")]
              + [f"bogie{j + 1}_{n}" for j in range(2) for n in ("lateral", "yaw", "roll")]
              + ["carbody_lateral", "carbody_yaw", "carbody_roll"])


def wheelset_dofs(i: int) -> tuple[int, int, int]:
    """(lateral, yaw, axle rotation) DOFs of wheelset ``i`` (0 .. 3)."""
    return (3 * i, 3 * i + 1, 3 * i + 2)


def bogie_dofs(j: int) -> tuple[int, int, int]:
    """(lateral, yaw, roll) DOFs of bogie frame ``j`` (0 front, 1 rear)."""
    return (12 + 3 * j, 13 + 3 * j, 14 + 3 * j)


def wheelset_offset(p: VehicleParameters, i: int) -> float:
    """Longitudinal position [m] of wheelset ``i`` from its bogie's centre (forward +)."""
    return p.semi_wheelbase if i % 2 == 0 else -p.semi_wheelbase


def bogie_offset(p: VehicleParameters, j: int) -> float:
    """Longitudinal position [m] of bogie ``j`` from the car body's centre."""
    return p.semi_bogie_distance if j == 0 else -p.semi_bogie_distance


@dataclass(frozen=True)
class VehicleMatrices:
    """Mass ``M``, stiffness ``K`` and damping ``C`` of the vehicle's suspension, 21 x 21
    (SI units), without the contact."""

    mass: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray


def _point(n: int, dofs: tuple[int, int, int], x: float, dz: float) -> np.ndarray:
    """Influence vector of the lateral displacement of a body's point at longitudinal
    position x and height dz above its centre of gravity (``y + x psi - dz phi``; a
    wheelset's third DOF is its axle rotation, which moves no point laterally)."""
    g = np.zeros(n)
    g[dofs[0]] += 1.0
    g[dofs[1]] += x
    if dofs[2] not in SPIN:
        g[dofs[2]] -= dz
    return g


def vehicle_matrices(p: VehicleParameters) -> VehicleMatrices:
    """Assemble M, K, C of :data:`DOFS` degrees of freedom (module docstring)."""
    n = DOFS
    m = np.zeros(n)
    k = np.zeros((n, n))
    c = np.zeros((n, n))

    def element(g: np.ndarray, stiffness: float, damping: float = 0.0) -> None:
        k[:] += stiffness * np.outer(g, g)
        c[:] += damping * np.outer(g, g)

    def unit(*pairs: tuple[int, float]) -> np.ndarray:
        g = np.zeros(n)
        for dof, w in pairs:
            g[dof] += w
        return g

    hw, hb, hc, hs = p.axle_height, p.bogie_height, p.carbody_height, p.secondary_height
    b1, b2 = p.primary_semi_spacing, p.secondary_semi_spacing
    for i in range(WHEELSETS):
        w = wheelset_dofs(i)
        b = bogie_dofs(i // 2)
        m[list(w)] = (p.wheelset_mass, p.wheelset_yaw_inertia, p.wheelset_spin_inertia)
        lateral = _point(n, w, 0.0, 0.0) - _point(n, b, wheelset_offset(p, i), hw - hb)
        element(lateral, 2 * p.primary_lateral_stiffness, 2 * p.primary_lateral_damping)
        element(unit((w[1], 1.0), (b[1], -1.0)), 2 * p.primary_longitudinal_stiffness * b1**2,
                2 * p.primary_longitudinal_damping * b1**2)
        element(unit((b[2], 1.0)), 2 * p.primary_vertical_stiffness * b1**2,
                2 * p.primary_vertical_damping * b1**2)
    body = CARBODY
    m[list(body)] = (p.carbody_mass, p.carbody_yaw_inertia, p.carbody_roll_inertia)
    for j in range(2):
        b = bogie_dofs(j)
        m[list(b)] = (p.bogie_mass, p.bogie_yaw_inertia, p.bogie_roll_inertia)
        lateral = _point(n, b, 0.0, hs - hb) - _point(n, body, bogie_offset(p, j), hs - hc)
        element(lateral, 2 * p.secondary_lateral_stiffness, 2 * p.secondary_lateral_damping)
        element(unit((b[1], 1.0), (body[1], -1.0)),
                2 * p.secondary_longitudinal_stiffness * b2**2)
        element(unit((b[2], 1.0), (body[2], -1.0)),
                2 * p.secondary_vertical_stiffness * b2**2 + p.antiroll_stiffness
                + 2 * p.secondary_bending_stiffness,
                2 * p.secondary_vertical_damping * b2**2)
        k[b[2], b[2]] -= GRAVITY * (p.carbody_mass / 2 * (hs - hw) + p.bogie_mass * (hb - hw))
    k[body[2], body[2]] -= GRAVITY * p.carbody_mass * (hc - hs)
    return VehicleMatrices(np.diag(m), k, c)


# -- the co-simulation ------------------------------------------------------------------
@dataclass(frozen=True)
class VehicleRun:
    """What to simulate (SI units).

    Attributes
    ----------
    speed
        Forward speed V [m/s].
    duration, step
        Simulated time and time step h [s].
    position, velocity
        Initial q and dq/dt (21 each; the wheelsets' spin speeds ``Omega``: 0 means
        ``V / r0``).
    jacobian
        d(F_Y, M_Z, T_y)/d(y_dot, psi_dot, Omega) of each wheelset's contact, (3, 3) for
        all or (4, 3, 3).
    radius
        r0 [m] for the default spin speed.
    """

    speed: float
    duration: float
    step: float
    position: np.ndarray
    velocity: np.ndarray
    jacobian: np.ndarray
    radius: float = 0.46

    def __post_init__(self) -> None:
        check_positive("speed", self.speed, "m/s")
        check_positive("duration", self.duration, "s")
        check_positive("step", self.step, "s")
        if self.step > self.duration:
            raise RailContactError(f"step [s] must not exceed duration, got {self.step:g} > "
                                   f"{self.duration:g}")
        for name in ("position", "velocity"):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.shape != (DOFS,) or not np.all(np.isfinite(a)):
                raise RailContactError(f"{name} must be {DOFS} finite values")
        jac = np.asarray(self.jacobian, dtype=float)
        if jac.shape not in ((3, 3), (WHEELSETS, 3, 3)) or not np.all(np.isfinite(jac)):
            raise RailContactError("jacobian must be finite, of shape (3, 3) or (4, 3, 3)")
        check_positive("radius", self.radius, "m")

    @property
    def steps(self) -> int:
        return max(1, int(round(self.duration / self.step)))


@dataclass
class VehicleResult:
    """A vehicle run's history.

    Attributes
    ----------
    time
        t at each recorded state [s], shape (n,).
    position, velocity
        q and dq/dt, (n, 21).
    forces
        The contact's :class:`~.vehicle_contact.WheelForces` at each step (n - 1 of them:
        the last state has none).
    wall_time
        Wall time of each step's contact call [s] and of the whole step [s], (n - 1, 2).
    completed, message
        Whether all steps ran; why not.
    """

    time: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    forces: list[WheelForces]
    wall_time: np.ndarray
    completed: bool
    message: str
    run: VehicleRun
    parameters: VehicleParameters = field(default_factory=VehicleParameters)

    def wheelset_lateral(self) -> np.ndarray:
        """Lateral displacements of the four wheelsets [m], (n, 4)."""
        return self.position[:, [3 * i for i in range(WHEELSETS)]]

    def stack(self, name: str) -> np.ndarray:
        """A :class:`WheelForces` field over the steps, (n - 1, ...)."""
        return np.array([getattr(f, name) for f in self.forces])


def wheelset_states(run_speed: float, t: float, q: np.ndarray, v: np.ndarray,
                    loads: np.ndarray) -> WheelsetStates:
    """The contact's input from the vehicle's state."""
    w = np.arange(WHEELSETS) * 3
    return WheelsetStates(time=t, speed=run_speed, lateral=q[w], yaw=q[w + 1],
                          lateral_velocity=v[w], yaw_rate=v[w + 1], spin_speed=v[w + 2],
                          loads=loads)


def simulate_vehicle(p: VehicleParameters, contact: VehicleContact, run: VehicleRun,
                     progress: Callable[[int, int], None] | None = None) -> VehicleResult:
    """Integrate the vehicle with the wheel forces of ``contact``.

    A contact call that fails (a wheelset off its rail, a solver error) ends the run:
    the history up to it is returned with ``completed = False`` and the reason.
    """
    mats = vehicle_matrices(p)
    h = run.step
    jac = np.asarray(run.jacobian, dtype=float)
    jac = np.broadcast_to(jac, (WHEELSETS, 3, 3))
    d = np.zeros((DOFS, DOFS))
    for i in range(WHEELSETS):
        s = slice(3 * i, 3 * i + 3)
        d[s, s] = jac[i]
    lu = scipy.linalg.lu_factor(mats.mass - h * (d - mats.damping))
    q = np.asarray(run.position, dtype=float).copy()
    v = np.asarray(run.velocity, dtype=float).copy()
    for k in SPIN:
        if v[k] == 0.0:
            v[k] = run.speed / run.radius
    loads = np.full((WHEELSETS, 2), p.wheel_load)
    ts, qs, vs, forces, walls = [0.0], [q.copy()], [v.copy()], [], []
    completed, message = True, "completed"
    n = run.steps
    for k in range(n):
        t = k * h
        t0 = time.perf_counter()
        try:
            out = contact(wheelset_states(run.speed, t, q, v, loads))
        except RailContactError as exc:
            completed, message = False, f"stopped at t = {t:.4f} s: {exc}"
            break
        t1 = time.perf_counter()
        if not out.ok:
            completed, message = False, f"stopped at t = {t:.4f} s: {out.message}"
            break
        f = -mats.stiffness @ q - mats.damping @ v
        f[:12] += out.generalized.reshape(-1)
        v = v + scipy.linalg.lu_solve(lu, h * f)
        q = q + h * v
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            completed, message = False, f"stopped at t = {t:.4f} s: non-finite state"
            break
        forces.append(out)
        walls.append((t1 - t0, time.perf_counter() - t0))
        ts.append(t + h)
        qs.append(q.copy())
        vs.append(v.copy())
        if progress is not None and k % 50 == 0:
            progress(k, n)
    return VehicleResult(time=np.array(ts), position=np.array(qs), velocity=np.array(vs),
                         forces=forces, wall_time=np.array(walls).reshape(-1, 2),
                         completed=completed, message=message, run=run, parameters=p)


# -- decay of an oscillation ------------------------------------------------------------
@dataclass(frozen=True)
class Decay:
    """Growth rate and frequency of a (nearly) exponentially growing or decaying
    oscillation.

    Attributes
    ----------
    rate
        sigma [1/s] of the envelope ``exp(sigma t)`` (negative: decaying), from a
        least-squares line through the logarithms of the peaks |y|; nan with fewer than
        three peaks.
    frequency
        [Hz] from the mean spacing of the zero crossings.
    amplitude
        The last peak |y|.
    peaks
        (time, |y|) of the peaks used.
    """

    rate: float
    frequency: float
    amplitude: float
    peaks: np.ndarray


def measure_decay(t: np.ndarray, y: np.ndarray, start: float = 0.0) -> Decay:
    """:class:`Decay` of ``y(t)`` over ``t >= start``: one peak (largest |y|) between
    successive zero crossings, its time and height refined by a parabola through the
    sample and its neighbours."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    check_finite("start", start, "s")
    keep = t >= start
    t, y = t[keep], y[keep]
    k = np.flatnonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)
    if len(k) < 3:
        return Decay(np.nan, np.nan, np.nan, np.zeros((0, 2)))
    cross = t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])
    peaks = []
    for a, b in zip(k[:-1], k[1:], strict=True):
        j = a + 1 + int(np.argmax(np.abs(y[a + 1:b + 1])))
        if 0 < j < len(y) - 1:
            y0, y1, y2 = np.abs(y[j - 1:j + 2])
            den = y0 - 2 * y1 + y2
            s = 0.5 * (y0 - y2) / den if den != 0 else 0.0
            peaks.append((t[j] + s * (t[j + 1] - t[j]), y1 - 0.25 * (y0 - y2) * s))
        else:
            peaks.append((t[j], abs(y[j])))
    pk = np.array(peaks)
    freq = 0.5 / float(np.mean(np.diff(cross)))
    if len(pk) < 3:
        return Decay(np.nan, freq, float(pk[-1, 1]), pk)
    rate = float(np.polyfit(pk[:, 0], np.log(pk[:, 1]), 1)[0])
    return Decay(rate, freq, float(pk[-1, 1]), pk)


__all__ = ["CARBODY", "DOFS", "Decay", "NAMES", "POSITIONS", "SPIN", "VehicleMatrices",
           "VehicleResult", "VehicleRun", "bogie_dofs", "measure_decay", "simulate_vehicle",
           "vehicle_matrices", "wheelset_dofs"]
