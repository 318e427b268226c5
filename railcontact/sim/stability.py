"""Linear stability of the bogie vehicle: eigenvalues against speed and the linear
critical speed.

With the suspension of :func:`~railcontact.sim.vehicle.vehicle_matrices` and the
linearised contact of :class:`~railcontact.sim.linear_contact.LinearWheelsetContact` on
every wheelset (``F = -K_c q - C_c(V) (v - v0)``), the vehicle's small motions about the
centred run obey ``M dv/dt = -(K + K_c) q - (C + C_c(V)) (v - v0)``. The state is the
positions that enter the forces (all but the axle rotations, :data:`~.vehicle.POSITIONS`)
and all 21 velocities (the spin speeds as their deviation from ``V / r0``); its first-order
matrix ``A(V)`` has 39 eigenvalues. The *linear critical speed* is the lowest speed at
which an oscillatory eigenvalue's real part crosses zero: found by scanning speeds and
refining the first sign change of the largest real part by Brent's method.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

from ..errors import RailContactError, check_positive
from .dynamics import WheelsetModel
from .linear_contact import LinearWheelsetContact
from .vehicle import CARBODY, DOFS, POSITIONS, WHEELSETS, vehicle_matrices
from .vehicle_data import VehicleParameters

OSCILLATORY = 1e-3
"""Smallest imaginary part [rad/s] of an eigenvalue counted as an oscillation."""


def contact_matrices(contact: LinearWheelsetContact, speed: float) -> tuple[np.ndarray,
                                                                            np.ndarray]:
    """K_c and C_c of the four wheelsets on the vehicle's 21 DOFs."""
    kc, cc = np.zeros((DOFS, DOFS)), np.zeros((DOFS, DOFS))
    k1, c1 = contact.stiffness(), contact.damping(speed)
    for i in range(WHEELSETS):
        s = slice(3 * i, 3 * i + 3)
        kc[s, s], cc[s, s] = k1, c1
    return kc, cc


def state_matrix(p: VehicleParameters, contact: LinearWheelsetContact,
                 speed: float) -> np.ndarray:
    """A(V) of the state (q[POSITIONS], v), 39 x 39 (module docstring)."""
    m = vehicle_matrices(p)
    kc, cc = contact_matrices(contact, speed)
    pos = list(POSITIONS)
    minv = np.diag(1.0 / np.diag(m.mass))
    npos = len(pos)
    a = np.zeros((npos + DOFS, npos + DOFS))
    a[np.arange(npos), npos + np.array(pos)] = 1.0
    a[npos:, :npos] = -minv @ (m.stiffness + kc)[:, pos]
    a[npos:, npos:] = -minv @ (m.damping + cc)
    return a


@dataclass(frozen=True)
class Mode:
    """One eigenvalue and its eigenvector.

    Attributes
    ----------
    eigenvalue
        lambda = sigma + i omega [1/s].
    vector
        The eigenvector of the state (q[POSITIONS], v), complex, scaled to a largest
        wheelset lateral displacement of 1 (unit phase there).
    """

    eigenvalue: complex
    vector: np.ndarray

    @property
    def frequency(self) -> float:
        """omega / 2 pi [Hz]."""
        return abs(self.eigenvalue.imag) / (2 * np.pi)

    @property
    def damping_ratio(self) -> float:
        """-sigma / |lambda| [-]."""
        return -self.eigenvalue.real / abs(self.eigenvalue)

    def state(self, amplitude: float, speed: float, radius: float) -> tuple[np.ndarray,
                                                                            np.ndarray]:
        """(q, v) of the vehicle (21 each) on this mode at phase 0, scaled to a largest
        wheelset lateral displacement ``amplitude`` [m]; the spin speeds about
        ``V / r0``."""
        x = np.real(self.vector) * amplitude
        q = np.zeros(DOFS)
        q[list(POSITIONS)] = x[:len(POSITIONS)]
        v = x[len(POSITIONS):].copy()
        v[[3 * i + 2 for i in range(WHEELSETS)]] += speed / radius
        return q, v


def modes(p: VehicleParameters, contact: LinearWheelsetContact, speed: float) -> list[Mode]:
    """The oscillatory modes (imaginary part > 0) at ``speed``, least damped first (the
    largest real part)."""
    lam, vec = scipy.linalg.eig(state_matrix(p, contact, speed))
    keep = lam.imag > OSCILLATORY
    lam, vec = lam[keep], vec[:, keep]
    order = np.argsort(-lam.real)
    pos = list(POSITIONS)
    lateral = [pos.index(3 * i) for i in range(WHEELSETS)]
    out = []
    for k in order:
        v = vec[:, k]
        j = lateral[int(np.argmax(np.abs(v[lateral])))]
        out.append(Mode(complex(lam[k]), v / v[j]))
    return out


def least_damped(p: VehicleParameters, contact: LinearWheelsetContact,
                 speed: float) -> Mode:
    """The oscillatory mode with the largest real part at ``speed``."""
    return modes(p, contact, speed)[0]


@dataclass(frozen=True)
class CriticalSpeed:
    """The linear critical speed and the mode that becomes unstable there.

    Attributes
    ----------
    speed
        V_c [m/s] (nan when no mode is unstable in the scanned range).
    mode
        The least damped mode at V_c.
    scan
        (speed [m/s], largest real part [1/s], its frequency [Hz]) over the scan.
    """

    speed: float
    mode: Mode | None
    scan: np.ndarray


def critical_speed(p: VehicleParameters, contact: LinearWheelsetContact,
                   speeds: np.ndarray | None = None, tolerance: float = 1e-3) -> CriticalSpeed:
    """The lowest speed at which the largest real part of an oscillatory eigenvalue turns
    positive: scan ``speeds`` [m/s] (default 5 .. 150 m/s every 2.5 m/s), then Brent's
    method on the first sign change to ``tolerance`` [m/s]."""
    vs = np.arange(5.0, 150.01, 2.5) if speeds is None else np.asarray(speeds, dtype=float)
    if vs.ndim != 1 or len(vs) < 2 or np.any(vs <= 0) or np.any(np.diff(vs) <= 0):
        raise RailContactError("speeds must be at least two increasing positive values [m/s]")
    check_positive("tolerance", tolerance, "m/s")

    def growth(v: float) -> float:
        return least_damped(p, contact, v).eigenvalue.real

    rows = []
    for v in vs:
        m = least_damped(p, contact, v)
        rows.append((v, m.eigenvalue.real, m.frequency))
    scan = np.array(rows)
    up = np.flatnonzero((scan[:-1, 1] < 0) & (scan[1:, 1] >= 0))
    if len(up) == 0:
        return CriticalSpeed(float("nan"), None, scan)
    k = int(up[0])
    vc = float(scipy.optimize.brentq(growth, vs[k], vs[k + 1], xtol=tolerance))
    return CriticalSpeed(vc, least_damped(p, contact, vc), scan)




def hunting_mode(p: VehicleParameters, contact: LinearWheelsetContact, speed: float) -> Mode:
    """The least damped mode in which the wheelsets move more than the car body (the
    car body's lateral displacement over the bogie centres, ``|y_c| + l_2 |psi_c|``, below
    the largest wheelset's): the bogies' hunting, not the car body's low-frequency sway
    and yaw."""
    pos = list(POSITIONS)
    y, psi = pos.index(CARBODY[0]), pos.index(CARBODY[1])
    for m in modes(p, contact, speed):
        if abs(m.vector[y]) + p.semi_bogie_distance * abs(m.vector[psi]) < 1.0:
            return m
    raise RailContactError(f"no wheelset mode at {speed:g} m/s")


def wheelset_eigenvalues(model: WheelsetModel, contact: LinearWheelsetContact,
                         speed: float) -> np.ndarray:
    """Eigenvalues [1/s] of one wheelset (:class:`~railcontact.sim.dynamics.WheelsetModel`:
    lateral, yaw, spin; suspension to a frame moving at V) with the linearised contact,
    state (y, psi, y_dot, psi_dot, omega); the oscillatory ones (imaginary part > 0),
    least damped first."""
    kc, cc = contact.stiffness()[:, :2], contact.damping(speed)
    a = np.zeros((5, 5))
    a[0, 2] = a[1, 3] = 1.0
    minv = np.linalg.inv(model.inertia)
    a[2:, :2] = -minv @ (model.stiffness[:, :2] + kc)
    a[2:, 2:] = -minv @ (model.damping + cc)
    lam = np.linalg.eigvals(a)
    lam = lam[lam.imag > OSCILLATORY]
    return lam[np.argsort(-lam.real)]


__all__ = ["CriticalSpeed", "Mode", "contact_matrices", "critical_speed", "hunting_mode",
           "least_damped", "modes", "state_matrix",
           "wheelset_eigenvalues"]
