"""The linearised wheel-rail contact of a wheelset: Kalker's linear creep forces at the
nominal patches, the equivalent conicity and the gravitational stiffness.

A wheelset with lateral displacement ``y`` (to the left), yaw ``psi`` and spin speed
``Omega = V / r0 + omega`` runs at speed ``V``. With the rolling radii
``r_l,r = r0 +- lambda y`` (``lambda`` the equivalent conicity), the contact angles
``gamma_l,r = gamma0 +- Gamma y`` (``Gamma`` the same harmonic linearisation of
``gamma_l - gamma_r``, :func:`contact_angle_parameter`) and the contact points at
``+-e`` from the wheelset centre, the creepages of :class:`~railcontact.timestep.Kinematics`
are to first order (track frame)

    xi_l,r  = -+ lambda y / r0 - omega r0 / V -+ e psi_dot / V
    eta     = y_dot / V - psi
    phi_l,r = psi_dot / V - Gamma y / r0      (less the centred wheelset's spin)

(the centred spins, of opposite signs on the two wheels, cancel in the sums; the contact
angles' change gives both wheels ``-Gamma y / r0``: ``phi_l + phi_r = 2 psi_dot / V -
2 Gamma y / r0``)
and Kalker's linear theory gives on each wheel (contact frame, on the wheel)
``F_x = -f11 xi``, ``F_y = -f22 eta - f23 phi``, ``M_z = f23 eta - f33 phi`` with
``f11 = G c^2 C11``, ``f22 = G c^2 C22``, ``f23 = G c^3 C23``, ``f33 = G c^4 C33``,
``c = sqrt(a b)`` of the Hertz ellipse of the centred wheelset's contact at the wheel
load (:func:`~railcontact.halfspace.hertz.hertz` with the curvatures of railcontact's own
contact search). The normal forces ``N`` lean with the contact angles: their lateral
components add ``-N (gamma_l - gamma_r) = -2 N Gamma y`` (the gravitational stiffness).
Summed over both wheels, the forces of the rails on the wheelset are

    F_Y = -2 f22 (y_dot / V - psi) - 2 f23 psi_dot / V - 2 Gamma (N - f23 / r0) y
    M_Z = -2 e f11 (lambda y / r0 + e psi_dot / V) + 2 f23 (y_dot / V - psi)
          - 2 f33 (psi_dot / V - Gamma y / r0)
    T_y = -2 r0^2 f11 omega / V

i.e. ``F = -K_c q - C_c (v - v0)`` with ``q = (y, psi, theta)``, ``v = (y_dot, psi_dot,
Omega)``, ``v0 = (0, 0, V / r0)``. Left out: the yaw gravitational stiffness (the normal
forces' longitudinal lean under yaw) and the dependence of the coefficients on the
patches' change with ``y``; the BEM includes both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import check_positive
from ..geometry.conicity import centred_contact, equivalent_conicity
from ..geometry.search import contact_points
from ..geometry.track import Pose, Track, Wheelset
from ..halfspace.hertz import hertz
from ..halfspace.materials import ElasticPair
from ..tangential.kalker import creep_coefficients


@dataclass(frozen=True)
class LinearWheelsetContact:
    """Coefficients of the linearised contact of one wheelset (SI units).

    Attributes
    ----------
    f11, f22
        Kalker's longitudinal and lateral creep coefficients of one wheel [N].
    f23
        Lateral-spin coefficient [N m].
    f33
        Spin coefficient [N m^2].
    conicity
        Equivalent conicity lambda [-].
    contact_angle_parameter
        Gamma [1/m]: ``gamma_l - gamma_r = 2 Gamma y``.
    radius
        Rolling radius r0 of the centred wheelset [m].
    half_distance
        e [m], half the distance between the centred contact points.
    normal_force
        Normal force N of one wheel [N].
    semi_axes
        (a, b) of the nominal Hertz patch [m].
    amplitude
        The lateral amplitude [m] lambda and Gamma were linearised at (0: given).
    """

    f11: float
    f22: float
    f23: float
    f33: float
    conicity: float
    contact_angle_parameter: float
    radius: float
    half_distance: float
    normal_force: float
    semi_axes: tuple[float, float] = (0.0, 0.0)
    amplitude: float = 0.0

    def stiffness(self) -> np.ndarray:
        """K_c, 3 x 3 on (y, psi, theta) (module docstring)."""
        r0, e, g = self.radius, self.half_distance, self.contact_angle_parameter
        k = np.zeros((3, 3))
        k[0, 0] = 2 * g * (self.normal_force - self.f23 / r0)
        k[0, 1] = -2 * self.f22
        k[1, 0] = 2 * e * self.f11 * self.conicity / r0 - 2 * self.f33 * g / r0
        k[1, 1] = 2 * self.f23
        return k

    def damping(self, speed: float) -> np.ndarray:
        """C_c, 3 x 3 on (y_dot, psi_dot, Omega) at forward speed V [m/s]."""
        v = check_positive("speed", speed, "m/s")
        e, r0 = self.half_distance, self.radius
        c = np.zeros((3, 3))
        c[0, 0] = 2 * self.f22 / v
        c[0, 1] = 2 * self.f23 / v
        c[1, 0] = -2 * self.f23 / v
        c[1, 1] = 2 * (e * e * self.f11 + self.f33) / v
        c[2, 2] = 2 * r0 * r0 * self.f11 / v
        return c

    def force(self, position: np.ndarray, velocity: np.ndarray, speed: float) -> np.ndarray:
        """(F_Y [N], M_Z [N m], T_y [N m]) on the wheelset(s): ``position`` and
        ``velocity`` of shape (3,) or (n, 3)."""
        q = np.asarray(position, dtype=float)
        v = np.asarray(velocity, dtype=float) - np.array([0.0, 0.0, speed / self.radius])
        return -(q @ self.stiffness().T) - v @ self.damping(speed).T


def harmonic_parameter(lateral: np.ndarray, difference: np.ndarray, amplitude: float) -> float:
    """The first Fourier coefficient of ``difference(A sin theta)`` over ``2 A``: the
    ``p`` of the linear ``difference = 2 p y`` that best replaces it in an oscillation of
    amplitude A (EN 15302's harmonic linearisation; ``difference`` sampled at
    ``lateral`` in [-A, A])."""
    theta = np.linspace(0.0, 2 * math.pi, 2000, endpoint=False)
    s = np.sin(theta)
    return float(np.mean(np.interp(amplitude * s, lateral, difference) * s) / amplitude)


def contact_angle_parameter(track: Track, wheelset: Wheelset, amplitude: float,
                            samples: int = 201) -> float:
    """Gamma [1/m] of ``gamma_l - gamma_r = 2 Gamma y`` at a lateral amplitude [m], by the
    harmonic linearisation of railcontact's contact angles (first points of contact)."""
    a = check_positive("amplitude", amplitude, "m")
    y = np.linspace(-a, a, samples)
    diff = np.array([contact_points(track, wheelset, Pose(lateral=float(v)), "left")[0]
                     .contact_angle
                     - contact_points(track, wheelset, Pose(lateral=float(v)), "right")[0]
                     .contact_angle for v in y])
    return harmonic_parameter(y, diff, a)


def linear_contact(track: Track, wheelset: Wheelset, pair: ElasticPair, wheel_load: float,
                   amplitude: float, samples: int = 201) -> LinearWheelsetContact:
    """The linearised contact of a wheelset on ``track`` carrying ``wheel_load`` [N] per
    wheel, its conicity and contact-angle parameter taken at ``amplitude`` [m].

    The nominal patch is Hertz's at the centred wheelset's contact point (its curvatures
    from railcontact's contact search, the normal force ``Q / cos(gamma0)``); Kalker's
    coefficients for its axis ratio and the pair's Poisson's ratio
    (:func:`~railcontact.tangential.kalker.creep_coefficients`). ``samples``: lateral
    displacements in [-A, A] the conicity and the contact-angle parameter sample.
    """
    q = check_positive("wheel_load", wheel_load, "N")
    centre = centred_contact(track, wheelset)
    cp = contact_points(track, wheelset, Pose(), "left")[0]
    normal = q / math.cos(cp.contact_angle)
    hz = hertz(cp.A, cp.B, pair, load=normal)
    k = creep_coefficients(hz.a, hz.b, pair.poisson)
    c = math.sqrt(hz.a * hz.b)
    g = pair.shear
    return LinearWheelsetContact(
        f11=g * c * c * k.c11, f22=g * c * c * k.c22, f23=g * c**3 * k.c23,
        f33=g * c**4 * k.c33,
        conicity=equivalent_conicity(track, wheelset, amplitude, samples),
        contact_angle_parameter=contact_angle_parameter(track, wheelset, amplitude, samples),
        radius=centre.radius, half_distance=centre.half_distance, normal_force=normal,
        semi_axes=(hz.a, hz.b), amplitude=amplitude)


__all__ = ["LinearWheelsetContact", "contact_angle_parameter", "harmonic_parameter",
           "linear_contact"]
