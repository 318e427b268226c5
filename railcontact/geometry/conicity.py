"""Equivalent conicity and Klingel's kinematic wavelength from the contact geometry.

A wheelset rolling without slip on tangent track oscillates kinematically (Klingel 1883):
with ``y`` its lateral displacement, ``psi`` its yaw and ``x`` the distance travelled,

    dy/dx = psi,      dpsi/dx = -delta_r(y) / (2 e r0),

where ``delta_r(y) = r_left - r_right`` is the rolling radius difference, ``r0`` the rolling
radius and ``e`` half the lateral distance between the contact points of the centred
wheelset. For a linear ``delta_r = 2 lambda y`` the motion is harmonic with wavelength

    L = 2 pi sqrt(r0 e / lambda)            (Klingel's formula).

Real profiles give a nonlinear ``delta_r``; the *equivalent conicity* for an amplitude
``A`` is the ``lambda`` of the linear wheelset that best replaces it in an oscillation
``y = A sin(theta)``, by harmonic linearisation (first Fourier coefficient, as in
EN 15302's harmonic method):

    lambda(A) = 1 / (2 pi A) * integral_0^2pi delta_r(A sin theta) sin theta dtheta.

Everything here comes from railcontact's own contact search
(:func:`railcontact.geometry.search.contact_points`, first point of contact of each
wheel), so the conicity is the one the contact solver sees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import RailContactError, check_positive
from .search import contact_points
from .track import Pose, Track, Wheelset


def rolling_radii(track: Track, wheelset: Wheelset,
                  lateral: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Rolling radii of the left and right wheel at their first contact point [m].

    Parameters
    ----------
    lateral
        Wheelset lateral displacement(s) y [m], positive to the left (no yaw, no roll).
    """
    y = np.atleast_1d(np.asarray(lateral, dtype=float))
    left = np.array([contact_points(track, wheelset, Pose(lateral=float(v)), "left")[0]
                     .rolling_radius for v in y])
    right = np.array([contact_points(track, wheelset, Pose(lateral=float(v)), "right")[0]
                      .rolling_radius for v in y])
    return left, right


def rolling_radius_difference(track: Track, wheelset: Wheelset,
                              lateral: np.ndarray | float) -> np.ndarray:
    """``delta_r(y) = r_left - r_right`` [m] for lateral displacement(s) ``y`` [m]."""
    left, right = rolling_radii(track, wheelset, lateral)
    return left - right


@dataclass(frozen=True)
class CentredContact:
    """Contact of the centred wheelset: ``radius`` r0 [m] (mean rolling radius) and
    ``half_distance`` e [m] (half the lateral distance between the two contact points)."""

    radius: float
    half_distance: float


def centred_contact(track: Track, wheelset: Wheelset) -> CentredContact:
    """r0 and e of the centred wheelset (see :class:`CentredContact`)."""
    pose = Pose()
    left = contact_points(track, wheelset, pose, "left")[0]
    right = contact_points(track, wheelset, pose, "right")[0]
    return CentredContact(0.5 * (left.rolling_radius + right.rolling_radius),
                          0.5 * (left.position[1] - right.position[1]))


def equivalent_conicity(track: Track, wheelset: Wheelset, amplitude: float,
                        samples: int = 401) -> float:
    """Equivalent conicity lambda for a lateral amplitude [m], by harmonic linearisation.

    ``delta_r`` is sampled at ``samples`` displacements in [-A, A] and interpolated
    linearly; the Fourier integral uses 2000 points of theta.
    """
    a = check_positive("amplitude", amplitude, "m")
    if samples < 11:
        raise RailContactError(f"samples must be at least 11, got {samples}")
    y = np.linspace(-a, a, samples)
    dr = rolling_radius_difference(track, wheelset, y)
    theta = np.linspace(0.0, 2 * math.pi, 2000, endpoint=False)
    return float(np.mean(np.interp(a * np.sin(theta), y, dr) * np.sin(theta)) / a)


def klingel_wavelength(radius: float, half_distance: float, conicity: float) -> float:
    """Klingel's wavelength L = 2 pi sqrt(r0 e / lambda) [m].

    Parameters
    ----------
    radius
        Rolling radius r0 [m].
    half_distance
        Half the distance between the contact points e [m].
    conicity
        Equivalent conicity lambda [-] (positive).
    """
    r0 = check_positive("radius", radius, "m")
    e = check_positive("half_distance", half_distance, "m")
    lam = check_positive("conicity", conicity, "")
    return 2 * math.pi * math.sqrt(r0 * e / lam)
