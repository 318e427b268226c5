"""The settings of the time-step solver (:class:`railcontact.WheelsetContact`, the FMU).

:class:`ContactSettings` is what a dynamics code sets once: friction, element size,
tolerances, estimates, warm start. Most of its fields are declared by the case records
(:func:`~.fields.inherit`: same meaning, unit and rule, a default of its own), and the grid,
normal and tangential records that the patch solvers take are built from it once
(:attr:`ContactSettings.grid_settings` ...), not per step. :class:`FMUModes` are the FMU's
switches that are not solver settings.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..errors import RailContactError
from ..formed import formed_once
from .case import (
    MAX_ELEMENT_SIZE,
    GridSettings,
    NormalSettings,
    PatchSettings,
    TangentialSettings,
    WheelRailGeometry,
)
from .choices import (
    CONTACT_MODELS,
    CONTROLS,
    CONVENTIONS,
    CREEPAGE_INPUTS,
    LOAD_DEFINITIONS,
    RIGID_WHEELSET,
    WARM_STARTS,
)
from .fields import Record, document, inherit, setting

MIN_ELEMENT_SIZE = 1e-5
"""Finest element [m] (0.01 mm: a patch of 10 mm is then 1000 elements across)."""


@document
@dataclass(frozen=True)
class ContactSettings(Record):
    """Solver settings of :class:`~railcontact.timestep.WheelsetContact` (SI units).

    ``warm_start``: "none", every step cold (the estimates are not used); "estimate", the
    simplified models; "previous", the previous step's solution (cold when there is none);
    "previous+estimate", the previous step's, and the estimate for a patch that has none.
    ``load_includes_creep``: with wheel loads and creepages, True makes the load the total
    vertical force of the rail on the wheel (normal and creep forces, as CONTACT's FZ and
    :func:`railcontact.solve`; a secant iteration on the normal share), False lets the
    normal forces alone carry it (one pass).
    ``patch_frame``: "reference" solves each patch in the frame at CONTACT's reference point
    (the overlap's weighted centre; in a warm step formed at the previous step's approach),
    "rigid" at the rigid contact point (CONTACT's convention always uses the reference
    point).
    """

    ERROR: ClassVar[type[RailContactError]] = RailContactError
    friction: float = inherit(TangentialSettings, "friction", 0.4, open_min=True,
                              kind="float", doc="Coulomb coefficient mu")
    element_size: float = setting(0.5e-3, "float", "m", "BEM element size dx = dy",
                                  minimum=MIN_ELEMENT_SIZE, maximum=MAX_ELEMENT_SIZE)
    margin: float = inherit(GridSettings, "margin", 1.0)
    normal_tolerance: float = inherit(NormalSettings, "tolerance")
    tangential_tolerance: float = inherit(TangentialSettings, "tolerance")
    normal_estimate: str = inherit(NormalSettings, "estimate", "infcon")
    tangential_estimate: str = inherit(TangentialSettings, "estimate", "fastrip")
    tangential_solver: str = inherit(TangentialSettings, "solver")
    warm_start: str = setting("previous+estimate", "choice", "", "how a step starts the BEM",
                              choices=WARM_STARTS)
    fft: str = inherit(NormalSettings, "fft")
    max_iterations_normal: int = inherit(NormalSettings, "max_iterations")
    max_iterations_tangential: int = inherit(TangentialSettings, "max_iterations")
    estimate_grid: tuple[int, int] = inherit(NormalSettings, "estimate_grid")
    strips: tuple[int, int] = inherit(TangentialSettings, "strips")
    spin_offset: float = inherit(TangentialSettings, "spin_offset")
    quantum: int = inherit(GridSettings, "quantum", 4)
    load_includes_creep: bool = setting(True, "bool", "", "a wheel load is the total vertical "
                                        "force, creep forces included")
    load_tolerance: float = setting(1e-3, "float", "-", "relative tolerance on a wheel load "
                                    "when the creep forces count", minimum=0.0, open_min=True,
                                    maximum=1.0, open_max=True)
    # Validity limits: a solved wheel beyond one is reported "outside validity"
    # (railcontact.timestep.validity); its forces are still given.
    max_y_q: float = setting(0.8, "float", "-", "derailment quotient Y/Q of a wheel above "
                             "which it is outside validity (EN 14363's limit; Nadal's limit "
                             "of the flange is checked as well)", minimum=0.0, open_min=True)
    max_penetration: float = setting(0.5e-3, "float", "m", "normal penetration of a patch "
                                     "above which the wheel is outside validity (83 kN on a "
                                     "tread: 0.07 mm)", minimum=0.0, open_min=True)
    max_wheel_load: float = setting(400e3, "float", "N", "vertical wheel force above which "
                                    "the wheel is outside validity (twice a 40 t heavy-haul "
                                    "axle's static wheel load)", minimum=0.0, open_min=True)
    patch_frame: str = inherit(WheelRailGeometry, "patch_frame")
    rigid_wheelset: str = setting("skip", "choice", "", "under load control, a step's stage "
                                  "after the wheels: find the rigid wheelset's vertical "
                                  "displacement and roll at which both wheels carry their "
                                  "loads (solve: load-controlled solves of both wheels at "
                                  "other rolls, 1-2 a step warm) or not (skip: the result's "
                                  "vertical and roll None)", choices=RIGID_WHEELSET)

    @property
    def uses_estimate(self) -> bool:
        return self.warm_start in ("estimate", "previous+estimate")

    @property
    def uses_previous(self) -> bool:
        return self.warm_start in ("previous", "previous+estimate")

    @formed_once
    def grid_settings(self) -> GridSettings:
        """The patch grids: square elements of ``element_size`` on a shared lattice (in
        the frame at the reference point, the origin an element's centre, as in CONTACT's
        grids and :func:`railcontact.solve`)."""
        return GridSettings(dx=self.element_size, dy=self.element_size, margin=self.margin,
                            quantum=self.quantum, snap=True,
                            centred=self.patch_frame == "reference")

    @formed_once
    def normal_settings(self) -> NormalSettings:
        """The normal BEM's settings (the estimate only when the warm start uses it)."""
        return NormalSettings(
            estimate=self.normal_estimate if self.uses_estimate else "none",
            estimate_grid=self.estimate_grid, tolerance=self.normal_tolerance,
            max_iterations=self.max_iterations_normal, fft=self.fft)

    @formed_once
    def tangential_settings(self) -> TangentialSettings:
        """The tangential BEM's settings (creepages are given per patch and step)."""
        return TangentialSettings(
            friction=self.friction, model="bem",
            estimate=self.tangential_estimate if self.uses_estimate else "none",
            tolerance=self.tangential_tolerance, max_iterations=self.max_iterations_tangential,
            strips=self.strips, spin_offset=self.spin_offset, solver=self.tangential_solver)

    @formed_once
    def patch_settings(self) -> PatchSettings:
        """The grid and normal settings of a wheel's normal solve (the time step solves the
        tangential problem itself, patch by patch; Hertz's solution formed only where the
        solve needs it)."""
        return PatchSettings(self.grid_settings, self.normal_settings, hertz=False)


@document
@dataclass(frozen=True)
class FMUModes(Record):
    """The FMU's switches: which inputs it reads and what a wheel load means."""

    ERROR: ClassVar[type[RailContactError]] = RailContactError
    control: str = setting("load", "choice", "", "normal problem: load (wheel loads given) or "
                           "penetration (vertical displacement and roll given)",
                           choices=CONTROLS)
    load_definition: str = setting("total", "choice", "", "a wheel load is the total vertical "
                                   "force (normal and creep forces, CONTACT's FZ) or the "
                                   "normal forces' share", choices=LOAD_DEFINITIONS)
    creepage_input: str = setting("direct", "choice", "", "creepages per wheel (direct) or "
                                  "from the wheelset velocities (kinematic)",
                                  choices=CREEPAGE_INPUTS)
    convention: str = setting("railcontact", "choice", "", "creepage inputs, creep forces "
                              "and spin moments in railcontact's frames (body 1 the wheel) "
                              "or CONTACT's (body 1 the rail, right wheel mirrored; "
                              "railcontact.settings.convention); the track-frame outputs "
                              "are railcontact's in both", choices=CONVENTIONS)
    rigid_wheelset: str = setting("solve", "choice", "", "under control=load, solve the "
                                  "rigid wheelset's vertical displacement and roll at which "
                                  "both wheels carry their loads (load-controlled solves "
                                  "of both wheels with creep at other rolls: 1-2 a step "
                                  "warm, about 2 cold, counted in rigid_normal_iterations "
                                  "...; scripts/bench_rigid.py) or skip them (those "
                                  "outputs 0, the moments taken about the nominal centre "
                                  "height r0)", choices=RIGID_WHEELSET)
    contact_model: str = setting("bem", "choice", "", "each step's contact: the exact BEM "
                                 "(bem) or interpolation in the contact table table_file "
                                 "(table; made by railcontact table build, control = load "
                                 "and load_definition = total only; vertical displacement "
                                 "and roll outputs 0)", choices=CONTACT_MODELS)
    table_file: str = setting("", "str?", "", "the contact table (a Zarr store of railcontact "
                              "table build) for contact_model = table: a folder in the FMU's "
                              "resources or a path; an input outside a table axis gives, by "
                              "that axis's out_of_range policy kept in the table (railcontact "
                              "table show), status 3 with zero outputs (status, the default) "
                              "or the axis's end node (clamp)")
    wheel_profile_left: str = setting("", "str?", "", "the left wheel's profile when the "
                                      "wheels differ (a worn wheelset), as wheel_profile; "
                                      "empty: wheel_profile")
    wheel_profile_right: str = setting("", "str?", "", "the right wheel's profile when the "
                                       "wheels differ, as wheel_profile; empty: "
                                       "wheel_profile")
    rail_profile_left: str = setting("", "str?", "", "the left rail's profile when the rails "
                                     "differ, as rail_profile; empty: rail_profile")
    rail_profile_right: str = setting("", "str?", "", "the right rail's profile when the "
                                      "rails differ, as rail_profile; empty: rail_profile")
