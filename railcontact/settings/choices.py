"""The words a setting can take, each list written once (the solvers that define a choice
own it: the FFT backends are the operator's, the preconditioners the normal BEM's)."""

from __future__ import annotations

from ..halfspace.operator import BACKENDS
from ..normal.bem import PRECONDITIONERS
from ..tangential import SOLVERS

FFT_BACKENDS = BACKENDS
"""Convolution backends of the influence operator."""
NORMAL_PRECONDITIONERS = PRECONDITIONERS
"""Preconditioners of the normal BEM's conjugate gradient."""
NORMAL_ESTIMATES = ("none", "hertz", "kp", "infcon")
"""Initial estimates of the normal BEM."""
TANGENTIAL_MODELS = ("bem", "fastsim", "fastrip")
"""Tangential models: the exact BEM or a simplified one."""
TANGENTIAL_SOLVERS = tuple(SOLVERS)
"""Exact steady-rolling solvers of the tangential BEM (the first the default)."""
TANGENTIAL_ESTIMATES = ("none", "fastsim", "fastrip")
"""Initial estimates of the tangential BEM."""
TRACTION_BOUNDS = ("elliptic", "parabolic")
"""FASTSIM's traction bound on a Hertz ellipse."""
GEOMETRY_TYPES = ("quadratic", "wheel-rail")
ROLL_MODES = ("rigid", "equal-loads")
CASE_SIDES = ("left", "right", "both")
CONVENTIONS = ("railcontact", "contact")
"""How creepages are read and forces written: railcontact's own roles and frames, or
CONTACT's (:mod:`railcontact.settings.convention`)."""
RIGID_WHEELSET = ("solve", "skip")
"""Under load control: find the rigid wheelset's vertical displacement and roll, or not
(the FMU's outputs then 0)."""
CONTACT_MODELS = ("bem", "table")
"""How the FMU finds a step's contact: the exact BEM, or interpolation in a contact table
(:mod:`railcontact.table`)."""
PATCH_FRAMES = ("reference", "rigid")
"""Where a wheel-rail patch's frame is placed: CONTACT's reference point, or the rigid
contact point."""
PROFILE_UNITS = ("m", "mm", "cm", "in")
WARM_STARTS = ("none", "estimate", "previous", "previous+estimate")
"""How a time step starts the BEM (:mod:`railcontact.timestep.warmstart`)."""
CONTROLS = ("load", "penetration")
"""FMU: what fixes the normal problem."""
CREEPAGE_INPUTS = ("direct", "kinematic")
"""FMU: creepages given per wheel, or computed from the wheelset velocities."""
LOAD_DEFINITIONS = ("total", "normal")
"""FMU: a wheel load is the total vertical force (with creep forces) or the normal share."""
