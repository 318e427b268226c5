"""The FMU's variables: one table that the slave and the modelDescription.xml share.

SI units. Value references are numbered per type in the order of the table (Real,
Integer, String); Booleans are not used. Per-wheel quantities have a ``_left`` and a
``_right`` variable. Frames and signs as in :mod:`railcontact.wheelset`.
"""

from __future__ import annotations

from dataclasses import dataclass

SIDES = ("left", "right")


@dataclass(frozen=True)
class Variable:
    name: str
    type: str            # "Real" | "Integer" | "String"
    causality: str       # "parameter" | "input" | "output"
    start: object = None
    unit: str = ""
    description: str = ""
    vr: int = -1


def _wheel(name, type_, unit, description, causality="output", start=None):
    return [Variable(f"{name}_{s}", type_, causality, start, unit, f"{description}, {s} wheel")
            for s in SIDES]


PARAMETERS = [
    Variable("wheel_profile", "String", "parameter", "S1002", "",
             "wheel profile: built-in name (S1002) or a file in the FMU's resources"),
    Variable("rail_profile", "String", "parameter", "60E1", "",
             "rail profile: built-in name (60E1, UIC60, CN60) or a file in the resources"),
    Variable("profile_unit", "String", "parameter", "mm", "",
             "unit of two-column profile files: mm or m"),
    Variable("control", "String", "parameter", "load", "",
             "normal problem: load (wheel loads given) or penetration (vertical "
             "displacement and roll given)"),
    Variable("load_definition", "String", "parameter", "total", "",
             "what a wheel load is (control=load): total (vertical force of normal and creep "
             "forces, as CONTACT's FZ) or normal (normal forces only)"),
    Variable("creepage_input", "String", "parameter", "direct", "",
             "direct (creepages per wheel) or kinematic (from the wheelset velocities)"),
    Variable("normal_estimate", "String", "parameter", "infcon", "",
             "initial estimate of the normal BEM: none, hertz, kp, infcon"),
    Variable("tangential_estimate", "String", "parameter", "fastrip", "",
             "initial estimate of the tangential BEM: none, fastsim, fastrip"),
    Variable("warm_start", "String", "parameter", "previous+estimate", "",
             "none, estimate, previous, previous+estimate"),
    Variable("fft", "String", "parameter", "auto", "",
             "convolution backend: auto, pyfftw, scipy, dense"),
    Variable("inclination", "Real", "parameter", 0.024994793618920156, "rad",
             "rail inclination (1:40)"),
    Variable("gauge", "Real", "parameter", 1.435, "m", "track gauge, 14 mm below the rail top"),
    Variable("flange_back_distance", "Real", "parameter", 1.360, "m",
             "distance between the flange backs of the wheelset"),
    Variable("wheel_radius", "Real", "parameter", 0.46, "m", "nominal rolling radius"),
    Variable("young", "Real", "parameter", 206e9, "Pa", "Young's modulus of wheel and rail"),
    Variable("poisson", "Real", "parameter", 0.28, "1", "Poisson's ratio of wheel and rail"),
    Variable("friction", "Real", "parameter", 0.4, "1", "Coulomb friction coefficient"),
    Variable("element_size", "Real", "parameter", 0.5e-3, "m", "BEM element size dx = dy"),
    Variable("normal_tolerance", "Real", "parameter", 1e-3, "1",
             "eps_n, relative pressure change between iterations"),
    Variable("tangential_tolerance", "Real", "parameter", 1e-2, "1",
             "eps_tau, relative traction change between sweeps"),
    Variable("load_tolerance", "Real", "parameter", 1e-3, "1",
             "relative tolerance on a wheel load when the creep forces count "
             "(load_definition=total)"),
]

INPUTS = [
    Variable("lateral_displacement", "Real", "input", 0.0, "m",
             "wheelset lateral displacement, positive to the left"),
    Variable("yaw", "Real", "input", 0.0, "rad", "wheelset yaw angle"),
    Variable("load_left", "Real", "input", 83.3e3, "N", "vertical wheel load, left (control=load)"),
    Variable("load_right", "Real", "input", 83.3e3, "N",
             "vertical wheel load, right (control=load)"),
    Variable("vertical_displacement", "Real", "input", 0.0, "m",
             "wheelset vertical displacement, positive up (control=penetration)"),
    Variable("roll", "Real", "input", 0.0, "rad", "wheelset roll angle (control=penetration)"),
    Variable("speed", "Real", "input", 30.0, "m/s", "forward speed V"),
    *[v for s in SIDES for v in (
        Variable(f"xi_{s}", "Real", "input", 0.0, "1",
                 f"longitudinal creepage, {s} wheel (creepage_input=direct)"),
        Variable(f"eta_{s}", "Real", "input", 0.0, "1",
                 f"lateral creepage, {s} wheel (creepage_input=direct)"),
        Variable(f"phi_{s}", "Real", "input", 0.0, "1/m",
                 f"spin creepage, {s} wheel (creepage_input=direct)"))],
    Variable("lateral_velocity", "Real", "input", 0.0, "m/s",
             "wheelset lateral velocity (creepage_input=kinematic)"),
    Variable("yaw_rate", "Real", "input", 0.0, "rad/s",
             "wheelset yaw rate (creepage_input=kinematic)"),
    Variable("spin_speed", "Real", "input", 0.0, "rad/s",
             "wheelset angular speed about the axle (creepage_input=kinematic); <= 0 means "
             "V / wheel_radius"),
]

OUTPUTS = [
    *_wheel("normal_force", "Real", "N", "normal force on the wheel (sum over patches)"),
    *_wheel("creep_force_x", "Real", "N", "longitudinal creep force on the wheel, contact frame"),
    *_wheel("creep_force_y", "Real", "N", "lateral creep force on the wheel, contact frame"),
    *_wheel("spin_moment", "Real", "N.m", "spin moment on the wheel about the contact normal"),
    *_wheel("force_longitudinal", "Real", "N", "force of the rail on the wheel, track X"),
    *_wheel("force_lateral", "Real", "N", "force of the rail on the wheel, track Y"),
    *_wheel("force_vertical", "Real", "N", "force of the rail on the wheel, track Z"),
    *_wheel("wheel_contact_position", "Real", "m", "wheel profile coordinate of the contact"),
    *_wheel("rail_contact_position", "Real", "m", "rail profile coordinate of the contact"),
    *_wheel("contact_lateral_position", "Real", "m", "contact point, track Y"),
    *_wheel("contact_angle", "Real", "rad", "contact angle (positive towards the flange)"),
    *_wheel("rolling_radius", "Real", "m", "wheel radius at the contact point"),
    *_wheel("contact_area", "Real", "m2", "contact area (sum over patches)"),
    *_wheel("max_pressure", "Real", "Pa", "maximum pressure"),
    *_wheel("slip_area_ratio", "Real", "1", "slip area / contact area"),
    *_wheel("xi_used", "Real", "1", "longitudinal creepage used (main patch)"),
    *_wheel("eta_used", "Real", "1", "lateral creepage used (main patch)"),
    *_wheel("phi_used", "Real", "1/m", "spin creepage used (main patch)"),
    Variable("force_longitudinal", "Real", "output", None, "N",
             "total force of the rails on the wheelset, track X"),
    Variable("force_lateral", "Real", "output", None, "N",
             "total force of the rails on the wheelset, track Y"),
    Variable("force_vertical", "Real", "output", None, "N",
             "total force of the rails on the wheelset, track Z"),
    Variable("yaw_moment", "Real", "output", None, "N.m",
             "moment of the rails on the wheelset about the vertical through its centre"),
    Variable("solve_time", "Real", "output", None, "s", "wall time of the last step's solve"),
    *_wheel("n_patches", "Integer", "", "number of contact patches"),
    *_wheel("normal_iterations", "Integer", "", "BEM normal iterations (sum over patches)"),
    *_wheel("tangential_iterations", "Integer", "", "ConvexGS sweeps (sum over patches)"),
    Variable("normal_iterations", "Integer", "output", None, "",
             "BEM normal iterations of the last step, both wheels"),
    Variable("tangential_iterations", "Integer", "output", None, "",
             "ConvexGS sweeps of the last step, both wheels"),
    Variable("status", "Integer", "output", None, "",
             "0 ok, 1 not converged, 2 no contact, 3 out of range (input rejected)"),
]


def table() -> list[Variable]:
    """All variables with their value references (numbered per type from 0)."""
    counters: dict[str, int] = {}
    out = []
    for v in PARAMETERS + INPUTS + OUTPUTS:
        k = counters.get(v.type, 0)
        counters[v.type] = k + 1
        out.append(Variable(v.name, v.type, v.causality, v.start, v.unit, v.description, k))
    return out
