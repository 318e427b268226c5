"""Lateral dynamics of one wheelset on tangent track: the model, its time step, and the
wavelength of the motion.

The wheelset has three degrees of freedom: lateral displacement ``y`` [m] (positive to the
left), yaw ``psi`` [rad] (positive nose left) and rotation about its axle ``theta`` [rad],
with velocities ``v = (dy/dt, dpsi/dt, Omega)``. It runs at constant forward speed ``V``
and is tied by its primary suspension to a frame that moves with it (no lateral or yaw
motion of the frame):

    m  d2y/dt2    = F_y(y, psi, v) - k_y y     - c_y dy/dt
    Iz d2psi/dt2  = M_z(y, psi, v) - k_psi psi - c_psi dpsi/dt
    Iy dOmega/dt  = T_y(y, psi, v)

``F_y``, ``M_z`` are the total lateral force and yaw moment of the rails on the wheelset
(creep forces *and* the lateral components of the normal forces, i.e. the gravitational
stiffness), from the contact solver; ``T_y = -(r_l F_x,l + r_r F_x,r)`` is the moment of the
longitudinal forces about the axle (no traction or braking torque). The spin degree of
freedom matters: with ``Omega`` held at ``V / r0`` the wheelset is driven or braked
whenever its mean rolling radius differs from ``r0`` (S1002 on 60E1: 0.35 mm at 3 mm
displacement), and the resulting common longitudinal creepage, on two patches of different
size, adds a differential creepage: for a free wheelset at 5 m/s the wavelength came out
9.72 m with Omega held, 9.32 m with it free (Klingel: 8.8 m).
Vertical equilibrium is imposed by the contact solver (wheel loads given); the frame takes
the longitudinal forces.

Time step (co-simulation)
-------------------------
The creep forces are very stiff in the velocities: ``dF_y/d(dy/dt) ~ -2 f22 / V`` with
``f22 ~ 10 MN``, i.e. a time constant ``m V / (2 f22)`` of about 2 ms at 30 m/s and 0.4 ms at
5 m/s, and ``Iy V / (2 f11 r0^2)`` for the spin is shorter still - shorter than a
communication step. An explicit step is unstable; the step here is *linearly implicit in
the velocities* (semi-implicit Euler with an interface Jacobian):

    (M - h D) (v[n+1] - v[n]) = h F(q[n], v[n]),     q[n+1] = q[n] + h v[n+1],

with ``D = dF/dv`` (3 x 3, contact plus suspension damping). The Jacobian only has to be
roughly right for stability (a ``D`` between half and several times the true one is
stable); the scheme is first-order accurate whatever ``D`` is. :mod:`railcontact.sim.cosim`
measures ``D`` by finite differences through the FMU (state saved and restored).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import RailContactError, check_positive


@dataclass(frozen=True)
class WheelsetModel:
    """Mass, inertia and primary suspension of the wheelset (SI units).

    Attributes
    ----------
    mass
        Wheelset mass m [kg].
    yaw_inertia
        Yaw moment of inertia Iz [kg m^2].
    lateral_stiffness
        Total lateral stiffness of the primary suspension k_y [N/m] (both axleboxes).
    longitudinal_stiffness
        Longitudinal stiffness of one axlebox k_x [N/m].
    semi_spacing
        Half the lateral distance between the axlebox springs b [m]; the yaw stiffness is
        ``k_psi = 2 k_x b^2``.
    lateral_damping, yaw_damping
        Viscous damping c_y [N s/m] and c_psi [N m s/rad] of the suspension.
    spin_inertia
        Moment of inertia about the axle Iy [kg m^2].
    """

    mass: float = 1500.0
    yaw_inertia: float = 700.0
    lateral_stiffness: float = 1.0e6
    longitudinal_stiffness: float = 1.0e6
    semi_spacing: float = 1.0
    lateral_damping: float = 0.0
    yaw_damping: float = 0.0
    spin_inertia: float = 120.0

    def __post_init__(self) -> None:
        check_positive("mass", self.mass, "kg")
        check_positive("yaw_inertia", self.yaw_inertia, "kg m^2")
        check_positive("spin_inertia", self.spin_inertia, "kg m^2")
        for name, unit in (("lateral_stiffness", "N/m"), ("longitudinal_stiffness", "N/m"),
                           ("semi_spacing", "m"), ("lateral_damping", "N s/m"),
                           ("yaw_damping", "N m s/rad")):
            check_positive(name, getattr(self, name), unit, allow_zero=True)

    @classmethod
    def free(cls, mass: float = 1500.0, yaw_inertia: float = 700.0,
             spin_inertia: float = 120.0) -> WheelsetModel:
        """A wheelset without suspension (Klingel's free wheelset)."""
        return cls(mass, yaw_inertia, 0.0, 0.0, 0.0, spin_inertia=spin_inertia)

    @property
    def yaw_stiffness(self) -> float:
        """k_psi = 2 k_x b^2 [N m/rad]."""
        return 2.0 * self.longitudinal_stiffness * self.semi_spacing**2

    @property
    def inertia(self) -> np.ndarray:
        """diag(m, Iz, Iy)."""
        return np.diag([self.mass, self.yaw_inertia, self.spin_inertia])

    @property
    def stiffness(self) -> np.ndarray:
        """diag(k_y, k_psi, 0)."""
        return np.diag([self.lateral_stiffness, self.yaw_stiffness, 0.0])

    @property
    def damping(self) -> np.ndarray:
        """diag(c_y, c_psi, 0)."""
        return np.diag([self.lateral_damping, self.yaw_damping, 0.0])


def implicit_step(model: WheelsetModel, position: np.ndarray, velocity: np.ndarray,
                  contact_force: np.ndarray, contact_jacobian: np.ndarray,
                  step: float) -> tuple[np.ndarray, np.ndarray]:
    """One linearly implicit step of the wheelset (see the module docstring).

    Parameters
    ----------
    position
        (y [m], psi [rad], theta [rad]) at t.
    velocity
        (dy/dt [m/s], dpsi/dt [rad/s], Omega [rad/s]) at t.
    contact_force
        (F_y [N], M_z [N m], T_y [N m]) of the rails on the wheelset at t.
    contact_jacobian
        d(F_y, M_z, T_y) / d(dy/dt, dpsi/dt, Omega), 3 x 3 (SI units).
    step
        Time step h [s].

    Returns
    -------
    position, velocity
        At t + h.
    """
    h = check_positive("step", step, "s")
    x = np.asarray(position, dtype=float)
    v = np.asarray(velocity, dtype=float)
    force = np.asarray(contact_force, dtype=float) - model.stiffness @ x - model.damping @ v
    jac = np.asarray(contact_jacobian, dtype=float) - model.damping
    lhs = model.inertia - h * jac
    if not (np.all(np.isfinite(force)) and np.all(np.isfinite(lhs))):
        raise RailContactError("non-finite force or Jacobian in the wheelset step")
    v_new = v + np.linalg.solve(lhs, h * force)
    return x + h * v_new, v_new


@dataclass(frozen=True)
class Wavelength:
    """Wavelength of an oscillation measured from its zero crossings.

    Attributes
    ----------
    wavelength
        Mean distance between crossings in the same direction [m] (nan if fewer than two).
    amplitude
        Mean of |y| at the extrema between the crossings used [m].
    crossings
        Positions of all zero crossings [m].
    """

    wavelength: float
    amplitude: float
    crossings: np.ndarray


def measure_wavelength(distance: np.ndarray, signal: np.ndarray,
                       start: float = 0.0) -> Wavelength:
    """Wavelength of ``signal(distance)`` from its zero crossings beyond ``start`` [m].

    Crossings are located by linear interpolation; the wavelength is twice the mean
    spacing of successive crossings (half-waves), the amplitude the mean |peak| between
    the first and last crossing.
    """
    s = np.asarray(distance, dtype=float)
    y = np.asarray(signal, dtype=float)
    keep = s >= start
    s, y = s[keep], y[keep]
    k = np.flatnonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)
    cross = s[k] - y[k] * (s[k + 1] - s[k]) / (y[k + 1] - y[k])
    if len(cross) < 3:
        return Wavelength(math.nan, math.nan, cross)
    wavelength = 2.0 * float(np.mean(np.diff(cross)))
    peaks = [np.max(np.abs(y[(s > a) & (s < b)])) for a, b in zip(cross[:-1], cross[1:],
                                                                    strict=True)]
    return Wavelength(wavelength, float(np.mean(peaks)), cross)
