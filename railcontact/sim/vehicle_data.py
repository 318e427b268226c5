"""Parameters of the bogie passenger vehicle (SI units), with their sources.

The default is *Vehicle 1* of the Manchester benchmarks for rail vehicle simulation, a
conventional passenger coach with two two-axle bogies and air-spring secondary suspension:
S. Iwnicki, "The Manchester Benchmarks for Rail Vehicle Simulation", Vehicle System
Dynamics 30 (1998) 295-313, doi:10.1080/00423119808969454 (and the book of the same
title, Swets & Zeitlinger 1999). The benchmark paper's table itself was not consulted; the
values are those of two independent public transcriptions of it that agree where they
overlap:

* [T1] the TTB-2D train-track-bridge toolbox (D. Cantero, NTNU),
  ``TrainProp_Manchester_BenchMark.m``: masses, pitch inertias, vertical primary and
  secondary stiffness and damping, semi-wheelbase 1.28 m and half the bogie-centre
  distance 9.5 m, citing Iwnicki (1998);
* [T2] a public MATLAB vehicle-parameter file with a "Manchester Benchmark" case: all
  inertias, primary and secondary stiffness and damping per element in the three
  directions, the anti-roll bar, the air-spring bending stiffness, the lateral semi-
  spacings of the springs (1.0 m), the nominal rolling radius (0.46 m), the centre-of-
  gravity heights (car body 1.8 m, bogie frame 0.6 m above rail) and the air springs'
  lower and upper heights (0.525 m and 1.13 m).

Where [T1] and [T2] both give a value they agree (masses 32000 / 2615 / 1813 kg, vertical
primary stiffness 1.22 MN/m per axlebox ([T1] rounds it to 1.2), primary vertical damping
4 kN s/m, secondary vertical 430 kN/m and 20 kN s/m per side, car-body and frame pitch
inertias, geometry). The model's own choices (not benchmark data) are marked *model*:
the height of the secondary lateral elements (the air springs' mid-height) and the unit
of the anti-roll bar's stiffness (N m/rad about the roll axis, as its value implies).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from ..errors import check_positive

IWNICKI_1998 = ("S. Iwnicki, The Manchester Benchmarks for Rail Vehicle Simulation, "
                "Vehicle System Dynamics 30 (1998) 295-313 (Vehicle 1)")
GRAVITY = 9.81
"""Acceleration of gravity g [m/s^2]."""


def _p(default: float, unit: str, source: str, doc: str):
    from dataclasses import field

    return field(default=default, metadata={"unit": unit, "source": source, "doc": doc})


@dataclass(frozen=True)
class VehicleParameters:
    """Masses, inertias, suspension and geometry of a bogie vehicle (SI units).

    Every field carries ``metadata`` with its unit, source and meaning
    (:func:`parameter_table`). Stiffness and damping are per element as the benchmark
    gives them: primary per axlebox, secondary per bogie side.
    """

    # inertia
    carbody_mass: float = _p(32000.0, "kg", "T1, T2", "car body mass")
    carbody_roll_inertia: float = _p(56800.0, "kg m^2", "T2", "car body roll inertia Ixx")
    carbody_yaw_inertia: float = _p(1.97e6, "kg m^2", "T2", "car body yaw inertia Izz")
    bogie_mass: float = _p(2615.0, "kg", "T1, T2", "bogie frame mass")
    bogie_roll_inertia: float = _p(1722.0, "kg m^2", "T2", "bogie frame roll inertia Ixx")
    bogie_yaw_inertia: float = _p(3067.0, "kg m^2", "T2", "bogie frame yaw inertia Izz")
    wheelset_mass: float = _p(1813.0, "kg", "T1, T2", "wheelset mass")
    wheelset_yaw_inertia: float = _p(1120.0, "kg m^2", "T2", "wheelset yaw inertia Izz")
    wheelset_spin_inertia: float = _p(112.0, "kg m^2", "T2",
                                      "wheelset inertia about its axle Iyy")
    # primary suspension, per axlebox
    primary_lateral_stiffness: float = _p(3.884e6, "N/m", "T2", "primary lateral stiffness")
    primary_longitudinal_stiffness: float = _p(31.391e6, "N/m", "T2",
                                               "primary longitudinal stiffness")
    primary_vertical_stiffness: float = _p(1.22e6, "N/m", "T1, T2",
                                           "primary vertical stiffness")
    primary_lateral_damping: float = _p(2e3, "N s/m", "T2", "primary lateral damping")
    primary_longitudinal_damping: float = _p(15e3, "N s/m", "T2",
                                             "primary longitudinal damping")
    primary_vertical_damping: float = _p(4e3, "N s/m", "T1, T2", "primary vertical damping")
    primary_semi_spacing: float = _p(1.0, "m", "T2",
                                     "half the lateral distance between the axleboxes")
    # secondary suspension, per bogie side
    secondary_lateral_stiffness: float = _p(160e3, "N/m", "T2",
                                            "secondary lateral stiffness (air spring)")
    secondary_longitudinal_stiffness: float = _p(160e3, "N/m", "T2",
                                                 "secondary longitudinal stiffness")
    secondary_vertical_stiffness: float = _p(430e3, "N/m", "T1, T2",
                                             "secondary vertical stiffness")
    secondary_lateral_damping: float = _p(32e3, "N s/m", "T2", "secondary lateral damper")
    secondary_vertical_damping: float = _p(20e3, "N s/m", "T1, T2",
                                           "secondary vertical damper")
    secondary_bending_stiffness: float = _p(10.5e3, "N m/rad", "T2",
                                            "air-spring bending (tilt) stiffness")
    secondary_semi_spacing: float = _p(1.0, "m", "T2",
                                       "half the lateral distance between the air springs")
    antiroll_stiffness: float = _p(940e3, "N m/rad", "T2 (unit: model)",
                                   "anti-roll bar, per bogie")
    # geometry
    semi_wheelbase: float = _p(1.28, "m", "T1, T2", "half the bogie wheelbase")
    semi_bogie_distance: float = _p(9.5, "m", "T1, T2", "half the bogie-centre distance")
    carbody_height: float = _p(1.8, "m", "T2", "car body centre of gravity above rail")
    bogie_height: float = _p(0.6, "m", "T2", "bogie frame centre of gravity above rail")
    secondary_height: float = _p(0.8275, "m", "model (T2: springs 0.525-1.13 m)",
                                 "height of the secondary lateral elements above rail")
    axle_height: float = _p(0.46, "m", "T2", "axle (primary spring) height above rail, r0")

    def __post_init__(self) -> None:
        for f in fields(self):
            check_positive(f.name, getattr(self, f.name), f.metadata["unit"],
                           allow_zero=True)
        for name in ("carbody_mass", "bogie_mass", "wheelset_mass", "carbody_roll_inertia",
                     "carbody_yaw_inertia", "bogie_roll_inertia", "bogie_yaw_inertia",
                     "wheelset_yaw_inertia", "wheelset_spin_inertia"):
            check_positive(name, getattr(self, name), "kg or kg m^2")

    @property
    def wheel_load(self) -> float:
        """Static vertical load of one wheel Q [N]: the vehicle's weight over 8 wheels."""
        return GRAVITY * (self.carbody_mass / 8 + self.bogie_mass / 4
                          + self.wheelset_mass / 2)


def parameter_table(p: VehicleParameters | None = None) -> list[tuple[str, float, str, str,
                                                                        str]]:
    """(name, value, unit, source, meaning) of every parameter."""
    p = p or VehicleParameters()
    return [(f.name, getattr(p, f.name), f.metadata["unit"], f.metadata["source"],
             f.metadata["doc"]) for f in fields(p)]


__all__ = ["GRAVITY", "IWNICKI_1998", "VehicleParameters", "parameter_table"]
