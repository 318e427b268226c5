"""CONTACT's conventions for wheel-rail creepages and forces, and railcontact's.

railcontact solves a wheel-rail patch in its side frame (:mod:`railcontact.geometry.track`;
the right wheel is mirrored): x forward, y in the contact plane towards the field side, n
out of the rail; body 1 is the wheel, so the creepages ``(xi, eta, phi)`` are the wheel's
velocity relative to the rail over V and the forces ``(F_x, F_s, M_n)`` act on the wheel.

CONTACT's wheel-rail module (its user guide; ``models/reference/contact/``)
has the rail as body 1: its creepages ``(cksi, ceta, cphi)`` are the rail's velocity
relative to the wheel, its forces ``(FX, FS, MN)`` act on the rail, in a contact frame
whose normal points into the rail (z down), so that its y points the other way; and it
mirrors the right wheel, so that y-like quantities (``ceta``, ``cphi``, ``FS``, ``MN``)
change sign between the left and the right wheel. Together, with ``s = +1`` on the left
and ``-1`` on the right wheel::

    (xi, eta, phi)   = (-cksi, s ceta, s cphi)      (phi, cphi in rad/m)
    (FX, FS, MN)     = (-F_x,  s F_s,  s M_n)

(checked against CONTACT's own results for its 34 wheel-rail cases: with these signs the
normal, longitudinal and lateral forces and the spin moment agree on both wheels, on the
tread and on the flange, where the lateral creep force decides how much normal force
carries the wheel load). Both maps are their own inverse.
"""

from __future__ import annotations

from collections.abc import Sequence

SIDE_SIGN = {"left": 1.0, "right": -1.0}


def side_creepage(creepage: Sequence[float], side: str, convention: str
                  ) -> tuple[float, float, float]:
    """The creepages (xi [-], eta [-], phi [1/m]) of a patch in railcontact's side frame
    from ``creepage`` given in ``convention`` (``"railcontact"``: already so)."""
    c = tuple(float(v) for v in creepage)
    if convention != "contact":
        return c
    s = SIDE_SIGN[side]
    return (-c[0], s * c[1], s * c[2])


def reported_forces(fx: float, fs: float, mn: float, side: str, convention: str
                    ) -> tuple[float, float, float]:
    """The creep forces [N] and spin moment [N m] of a patch, solved in railcontact's side
    frame, as ``convention`` reports them."""
    if convention != "contact":
        return (fx, fs, mn)
    s = SIDE_SIGN[side]
    return (-fx, s * fs, s * mn)


def wheel_frame_creepage(creepage: Sequence[float]) -> tuple[float, float, float]:
    """Between CONTACT's creepages and those of :class:`~railcontact.WheelsetContact`
    (contact frame with y to the left and n up on both wheels, body 1 the wheel): the
    longitudinal one changes sign, the lateral and the spin do not (CONTACT's y and n both
    point the other way, and its mirroring of the right wheel is the wheelset frame's)."""
    c = tuple(float(v) for v in creepage)
    return (-c[0], c[1], c[2])
