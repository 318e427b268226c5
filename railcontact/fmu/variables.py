"""The FMU's variables: one table that the slave and the modelDescription.xml share.

SI units. Value references are numbered per type in the order of the table (Real,
Integer, String); Booleans are not used. Per-wheel quantities have a ``_left`` and a
``_right`` variable. Frames and signs as in :mod:`railcontact.timestep.wheelset`.

The parameters are not written here: each is a setting of :mod:`railcontact.settings`
(:data:`PARAMETER_SOURCES` says which), and takes its default, unit and description from
there; :func:`parameter_settings` turns the parameter values back into those records.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any

from ..errors import RailContactError
from ..geometry.track import MAX_RAIL_ROLL, MAX_RAIL_SHIFT
from ..settings import (
    ContactSettings,
    FMUModes,
    MaterialSettings,
    NormalSettings,
    TangentialSettings,
    WheelRailGeometry,
)
from ..settings.fields import Record, default_of, spec_of
from ..settings.friction import MAX_MU
from ..status import Status
from ..timestep.inputs import MAX_CURVATURE

SIDES = ("left", "right")
UNITS = {"-": "1", "": ""}
"""Settings units that FMI writes otherwise (dimensionless is "1")."""


@dataclass(frozen=True)
class Variable:
    """One FMU variable (SI units); an output knows how to read its value from a
    :class:`~railcontact.timestep.WheelsetResult`."""

    name: str
    type: str            # "Real" | "Integer" | "String"
    causality: str       # "parameter" | "input" | "output"
    start: object = None
    unit: str = ""
    description: str = ""
    value: Callable[[Any], float] | None = field(default=None, compare=False, repr=False)
    vr: int = -1
    items: tuple[str, ...] = ()
    """An Integer with items is an FMI Enumeration of type :attr:`enumeration_type`:
    value k (from 1) means ``items[k - 1]``."""

    @property
    def enumeration_type(self) -> str:
        """The modelDescription's SimpleType of an enumeration: the name in CamelCase,
        without the ``_choice`` suffix (warm_start_choice: WarmStart)."""
        base = self.name.removesuffix(CHOICE_SUFFIX)
        return "".join(w.capitalize() for w in base.split("_"))


MODELICA_KEYWORDS = frozenset((
    "algorithm", "and", "annotation", "block", "break", "class", "connect", "connector",
    "constant", "constrainedby", "der", "discrete", "each", "else", "elseif", "elsewhen",
    "encapsulated", "end", "enumeration", "equation", "expandable", "extends", "external",
    "false", "final", "flow", "for", "function", "if", "import", "impure", "in", "initial",
    "inner", "input", "loop", "model", "not", "operator", "or", "outer", "output",
    "package", "parameter", "partial", "protected", "public", "pure", "record",
    "redeclare", "replaceable", "return", "stream", "then", "true", "type", "when",
    "while", "within"))
"""Modelica's reserved words (Modelica Language Specification 3.6, section 2.3.3): not an
identifier, so no enumeration item's name."""
ITEM_ALIASES = {"in": "inch"}
"""Choice words whose item name is spelled out (the profile unit ``in``)."""


def item_name(word: str) -> str:
    """An enumeration item's name for a choice word (previous+estimate:
    previous_estimate, in: inch), a Modelica identifier as tools import them."""
    name = ITEM_ALIASES.get(word, re.sub(r"\W", "_", word))
    if name in MODELICA_KEYWORDS:  # a future choice word: spell it apart
        name += "_"
    return name


def _wheel(name, type_, unit, description, causality="output", start=None, value=None):
    """The ``_left`` and ``_right`` variables of a wheel quantity; ``value(wheel)`` reads an
    output from a :class:`~railcontact.timestep.WheelContact`."""
    return [Variable(f"{name}_{s}", type_, causality, start, unit, f"{description}, {s} wheel",
                     None if value is None else _of_wheel(value, s))
            for s in SIDES]


def _of_wheel(value: Callable[[Any], float], side: str) -> Callable[[Any], float]:
    return lambda result: value(getattr(result, side))


PARAMETER_SOURCES: tuple[tuple[str, type[Record], str], ...] = (
    ("wheel_profile", WheelRailGeometry, "wheel"),
    ("rail_profile", WheelRailGeometry, "rail"),
    ("profile_unit", WheelRailGeometry, "profile_unit"),
    ("control", FMUModes, "control"),
    ("load_definition", FMUModes, "load_definition"),
    ("creepage_input", FMUModes, "creepage_input"),
    ("normal_estimate", ContactSettings, "normal_estimate"),
    ("tangential_estimate", ContactSettings, "tangential_estimate"),
    ("warm_start", ContactSettings, "warm_start"),
    ("fft", ContactSettings, "fft"),
    ("inclination", WheelRailGeometry, "inclination"),
    ("gauge", WheelRailGeometry, "gauge"),
    ("flange_back_distance", WheelRailGeometry, "back_to_back"),
    ("wheel_radius", WheelRailGeometry, "wheel_radius"),
    ("young", MaterialSettings, "young"),
    ("poisson", MaterialSettings, "poisson"),
    ("friction", ContactSettings, "friction"),
    ("element_size", ContactSettings, "element_size"),
    ("normal_tolerance", ContactSettings, "normal_tolerance"),
    ("tangential_tolerance", ContactSettings, "tangential_tolerance"),
    ("load_tolerance", ContactSettings, "load_tolerance"),
    ("tangential_solver", ContactSettings, "tangential_solver"),
    ("max_y_q", ContactSettings, "max_y_q"),
    ("max_penetration", ContactSettings, "max_penetration"),
    ("max_wheel_load", ContactSettings, "max_wheel_load"),
    ("convention", FMUModes, "convention"),
    ("rigid_wheelset", FMUModes, "rigid_wheelset"),
    ("contact_model", FMUModes, "contact_model"),
    ("table_file", FMUModes, "table_file"),
    ("patch_frame", ContactSettings, "patch_frame"),
    ("wheel_profile_left", FMUModes, "wheel_profile_left"),
    ("wheel_profile_right", FMUModes, "wheel_profile_right"),
    ("rail_profile_left", FMUModes, "rail_profile_left"),
    ("rail_profile_right", FMUModes, "rail_profile_right"),
)
"""FMU parameter name, the settings record and the field it sets (wheel and rail share
one material in the FMU)."""
APPENDED = ("max_y_q", "max_penetration", "max_wheel_load", "convention", "rigid_wheelset",
            "contact_model", "table_file", "patch_frame")
APPENDED_TRACK = ("wheel_profile_left", "wheel_profile_right", "rail_profile_left",
                  "rail_profile_right")
"""Parameters of the real track (profiles per side), numbered after
:data:`APPENDED_OUTPUTS` with :data:`TRACK_INPUTS` and :data:`TRACK_OUTPUTS`, so that every
earlier value reference stays."""
"""Parameters added after the first published interface (commit 039db95): :func:`table`
numbers them after every variable of it, so that its value references stay (they are
numbered per type). A new parameter goes at the end of :data:`PARAMETER_SOURCES` and of
this list, a new output at the end of :data:`APPENDED_OUTPUTS`: :func:`table` numbers
those after every earlier variable. The Integer ``_choice`` enumerations (:data:`CHOICES`)
come before :data:`APPENDED_OUTPUTS`, so a new choice parameter's ``_choice`` must be
numbered after the appended outputs, not at the end of :data:`CHOICES` (it would move
them; ``tests/test_fmu_variables.py`` pins both)."""


def _parameter(name: str, record: type[Record], key: str) -> Variable:
    f = next(f for f in fields(record) if f.name == key)  # type: ignore[arg-type]
    s = spec_of(f)
    default = default_of(f)
    if isinstance(default, tuple):  # a material constant: one value for both bodies
        default = default[0]
    numeric = s.kind in ("float", "floats12")
    doc = s.doc.replace(" (one value, or [body 1, body 2])", " of wheel and rail")
    if s.kind == "choice":
        doc += " (" + " | ".join(s.choices) + ")"
    return Variable(name, "Real" if numeric else "String", "parameter", default,
                    UNITS.get(s.unit, s.unit), doc)


PARAMETERS = [_parameter(*source) for source in PARAMETER_SOURCES]
"""The parameters, one per setting; a choice among words is a String."""
CHOICE_SUFFIX = "_choice"


def _choice(name: str, record: type[Record], key: str) -> Variable | None:
    f = next(f for f in fields(record) if f.name == key)  # type: ignore[arg-type]
    s = spec_of(f)
    if s.kind != "choice":
        return None
    return Variable(f"{name}{CHOICE_SUFFIX}", "Integer", "parameter",
                    s.choices.index(default_of(f)) + 1, "",
                    f"{s.doc} (the String parameter {name} as an enumeration; set either)",
                    items=tuple(s.choices))


CHOICES = [v for v in (_choice(*source) for source in PARAMETER_SOURCES) if v is not None]
"""Every mode switch (a String choice parameter) also as an Integer enumeration,
``<name>_choice``, with the same default: FMI tools show it as a drop-down, and set it
before instantiation as they may not a String."""


def resolve_choices(values: Mapping[str, Any]) -> dict[str, Any]:
    """``values`` by parameter name with each ``<name>_choice`` enumeration turned into
    its String parameter's word: the enumeration counts when it is set away from its
    default, the String otherwise; both set away from the default to different words is
    an error naming both."""
    out = dict(values)
    for v in CHOICES:
        if v.name not in out:
            continue
        raw = out.pop(v.name)
        try:
            k = int(raw)
            ok = k == float(raw) and 1 <= k <= len(v.items)
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise RailContactError(
                f"parameter {v.name} must be one of " + ", ".join(
                    f"{k} ({w})" for k, w in enumerate(v.items, start=1))
                + f", got {_plain(raw)!r}")
        base = v.name.removesuffix(CHOICE_SUFFIX)
        word, default = v.items[k - 1], v.items[v.start - 1]
        string = out.get(base, default)
        if word != default:
            if string not in (default, word):
                raise RailContactError(f"parameters {base} = {string!r} and {v.name} = {k} "
                                       f"({word!r}) disagree; set one of them")
            out[base] = word
    return out


def _plain(raw: Any) -> Any:
    """``raw`` as a Python number for a message (a numpy scalar shows as np.int32(5))."""
    try:
        return raw.item()
    except AttributeError:
        return raw


@dataclass(frozen=True)
class ParameterSettings:
    """The settings records that the FMU parameters set."""

    geometry: WheelRailGeometry
    material: MaterialSettings
    contact: ContactSettings
    modes: FMUModes


def parameter_settings(values: Mapping[str, Any]) -> ParameterSettings:
    """The settings records from FMU parameter values (by parameter name, numbers or the
    strings of a modelDescription; absent ones take their defaults; the ``_choice``
    enumerations as :func:`resolve_choices` says). Raises
    :class:`~railcontact.errors.RailContactError` naming a bad one.
    """
    values = resolve_choices(values)
    per_record: dict[type[Record], dict[str, Any]] = {}
    numeric = {v.name for v in PARAMETERS if v.type == "Real"}
    for name, record, key in PARAMETER_SOURCES:
        if name in values:
            value = values[name]
            if name in numeric and isinstance(value, str):  # a modelDescription start value
                try:
                    value = float(value)
                except ValueError:
                    pass  # reported as not a number below
            per_record.setdefault(record, {})[key] = record.check_value(
                key, value, f"parameter {name}")
    modes = FMUModes(**per_record.get(FMUModes, {}))
    contact = per_record.get(ContactSettings, {})
    contact["load_includes_creep"] = modes.load_definition == "total"
    contact["rigid_wheelset"] = modes.rigid_wheelset
    return ParameterSettings(WheelRailGeometry(**per_record.get(WheelRailGeometry, {})),
                             MaterialSettings(**per_record.get(MaterialSettings, {})),
                             ContactSettings(**contact), modes)


def _limits(record: type[Record], key: str) -> tuple[float, float]:
    """The (minimum, maximum) of a case-file setting: what a step's input of the same
    quantity may be."""
    s = spec_of(next(f for f in fields(record) if f.name == key))  # type: ignore[arg-type]
    return float(s.minimum), float(s.maximum)


LOAD_LIMITS = _limits(NormalSettings, "load")
"""The wheel loads [N] a step takes (control=load): a case file's ``[normal] load``
range; beyond it (a negative load among them) the step is discarded, status 3."""
CREEPAGE_LIMITS = _limits(TangentialSettings, "creepage")
"""The creepages a step takes, each of xi and eta [-] and phi [1/m] (given, or formed
from the kinematic inputs): a case file's ``[tangential] creepage`` range; beyond it the
step is discarded, status 3."""
_OUTSIDE = "; outside it the step is discarded (fmi2Discard, status 3)"
_LOADS = f"{LOAD_LIMITS[0]:g} to {LOAD_LIMITS[1]:g} N (0 lifts the wheel){_OUTSIDE}"
_CREEP = f"{CREEPAGE_LIMITS[0]:g} to {CREEPAGE_LIMITS[1]:g}{_OUTSIDE}"
_SHIFTS = f"within +-{MAX_RAIL_SHIFT:g}{_OUTSIDE}"

INPUTS = [
    Variable("lateral_displacement", "Real", "input", 0.0, "m",
             "wheelset lateral displacement, positive to the left"),
    Variable("yaw", "Real", "input", 0.0, "rad", "wheelset yaw angle"),
    Variable("load_left", "Real", "input", 83.3e3, "N",
             f"vertical wheel load, left (control=load): {_LOADS}"),
    Variable("load_right", "Real", "input", 83.3e3, "N",
             f"vertical wheel load, right (control=load): {_LOADS}"),
    Variable("vertical_displacement", "Real", "input", 0.0, "m",
             "wheelset vertical displacement, positive up (control=penetration)"),
    Variable("roll", "Real", "input", 0.0, "rad", "wheelset roll angle (control=penetration)"),
    Variable("speed", "Real", "input", 30.0, "m/s", "forward speed V (creepage_input="
             "kinematic: > 0, and the creepages it forms within "
             f"{CREEPAGE_LIMITS[0]:g} to {CREEPAGE_LIMITS[1]:g}{_OUTSIDE})"),
    *[v for s in SIDES for v in (
        Variable(f"xi_{s}", "Real", "input", 0.0, "1",
                 f"longitudinal creepage, {s} wheel (creepage_input=direct): {_CREEP}"),
        Variable(f"eta_{s}", "Real", "input", 0.0, "1",
                 f"lateral creepage, {s} wheel (creepage_input=direct): {_CREEP}"),
        Variable(f"phi_{s}", "Real", "input", 0.0, "1/m",
                 f"spin creepage, {s} wheel (creepage_input=direct): {CREEPAGE_LIMITS[0]:g} "
                 f"to {CREEPAGE_LIMITS[1]:g} 1/m{_OUTSIDE}"))],
    Variable("lateral_velocity", "Real", "input", 0.0, "m/s",
             "wheelset lateral velocity (creepage_input=kinematic)"),
    Variable("yaw_rate", "Real", "input", 0.0, "rad/s",
             "wheelset yaw rate (creepage_input=kinematic)"),
    Variable("spin_speed", "Real", "input", 0.0, "rad/s",
             "wheelset angular speed about the axle (creepage_input=kinematic); <= 0 means "
             "V / wheel_radius"),
]

_FMU_NOTES = {
    Status.NOT_CONVERGED: "none when the load loop found no solution: n_patches 0, "
                          "fmi2Discard",
    Status.OUT_OF_RANGE: "the step returns fmi2Discard: a pose beyond the model, or a used "
                         "input not finite or beyond its range, which zeroes every output",
    Status.OUTSIDE_VALIDITY: "validity_left/right says which limit",
}
STATUS = ", ".join(
    f"{int(s)} {s.label} ({s.description}" + (f"; {_FMU_NOTES[s]}" if s in _FMU_NOTES else "")
    + ")" for s in Status if s != Status.NOT_COMPUTED)
"""The status codes as the FMU's variables describe them
(:class:`~railcontact.status.Status`, with what the FMU does)."""


def _used(k: int):
    """The creepage ``k`` used on a wheel's main patch (0 without creepages)."""
    return lambda w: w.creepages[0][k] if w.creepages else 0.0


def _total(attribute: str):
    """The sum of a wheel quantity over both wheels."""
    return lambda r: sum(getattr(w, attribute) for w in r.wheels)


def _step_work(attribute: str):
    """A work count of the whole step (a :class:`~railcontact.status.Work`
    field), both wheels: their contact solves' plus their solves at the rolls the rigid
    wheelset's search evaluated."""
    return lambda r: sum(getattr(w, attribute) + getattr(x, attribute)
                         for w, x in zip(r.wheels, r.rigid_work, strict=True))


def _solved(attribute: str):
    """The result's ``vertical`` or ``roll``, 0 where it was not solved (None)."""
    return lambda r: getattr(r, attribute) or 0.0


def _rigid_work(attribute: str):
    """A work count of the rigid wheelset's solves alone, both wheels."""
    return lambda r: sum(getattr(w, attribute) for w in r.rigid_work)


def _work_note(name: str) -> str:
    """How a whole-step total ``name`` is made up (its description's end)."""
    return (f": the contact solves of both wheels ({name}_left + {name}_right) and, with "
            f"control=load and rigid_wheelset=solve, the rigid wheelset's solves at other "
            f"rolls (rigid_{name})")


OUTPUTS = [
    *_wheel("normal_force", "Real", "N", "normal force on the wheel (sum over patches)",
            value=lambda w: w.normal_force),
    *_wheel("creep_force_x", "Real", "N", "longitudinal creep force on the wheel, contact frame",
            value=lambda w: w.creep_force[0]),
    *_wheel("creep_force_y", "Real", "N", "lateral creep force on the wheel, contact frame",
            value=lambda w: w.creep_force[1]),
    *_wheel("spin_moment", "Real", "N.m", "spin moment on the wheel about the contact normal",
            value=lambda w: w.spin_moment),
    *_wheel("force_longitudinal", "Real", "N", "force of the rail on the wheel, track X",
            value=lambda w: w.track_force[0]),
    *_wheel("force_lateral", "Real", "N", "force of the rail on the wheel, track Y",
            value=lambda w: w.track_force[1]),
    *_wheel("force_vertical", "Real", "N", "force of the rail on the wheel, track Z",
            value=lambda w: w.track_force[2]),
    *_wheel("wheel_contact_position", "Real", "m", "wheel profile coordinate of the contact",
            value=lambda w: w.wheel_position),
    *_wheel("rail_contact_position", "Real", "m", "rail profile coordinate of the contact",
            value=lambda w: w.rail_position),
    *_wheel("contact_lateral_position", "Real", "m", "contact point, track Y",
            value=lambda w: w.lateral_position),
    *_wheel("contact_angle", "Real", "rad", "contact angle (positive towards the flange)",
            value=lambda w: w.contact_angle),
    *_wheel("rolling_radius", "Real", "m", "wheel radius at the contact point",
            value=lambda w: w.rolling_radius),
    *_wheel("contact_area", "Real", "m2", "contact area (sum over patches)",
            value=lambda w: w.area),
    *_wheel("max_pressure", "Real", "Pa", "maximum pressure", value=lambda w: w.max_pressure),
    *_wheel("slip_area_ratio", "Real", "1", "slip area / contact area",
            value=lambda w: w.slip_area_ratio),
    *_wheel("xi_used", "Real", "1", "longitudinal creepage used (main patch)", value=_used(0)),
    *_wheel("eta_used", "Real", "1", "lateral creepage used (main patch)", value=_used(1)),
    *_wheel("phi_used", "Real", "1/m", "spin creepage used (main patch)", value=_used(2)),
    Variable("force_longitudinal", "Real", "output", None, "N",
             "total force of the rails on the wheelset, track X", lambda r: r.force[0]),
    Variable("force_lateral", "Real", "output", None, "N",
             "total force of the rails on the wheelset, track Y", lambda r: r.force[1]),
    Variable("force_vertical", "Real", "output", None, "N",
             "total force of the rails on the wheelset, track Z", lambda r: r.force[2]),
    Variable("yaw_moment", "Real", "output", None, "N.m",
             "moment of the rails on the wheelset about the vertical through its centre",
             lambda r: r.yaw_moment),
    Variable("solve_time", "Real", "output", None, "s", "wall time of the last step's solve",
             lambda r: r.wall_time),
    *_wheel("n_patches", "Integer", "", "number of contact patches",
            value=lambda w: w.n_patches),
    *_wheel("normal_iterations", "Integer", "", "BEM normal iterations of the wheel's "
            "contact solve in the last step (all patches, load passes and re-meshes)",
            value=lambda w: w.normal_iterations),
    *_wheel("tangential_iterations", "Integer", "", "tangential BEM sweeps of the wheel's "
            "contact solve in the last step (all patches, load passes and re-meshes)",
            value=lambda w: w.tangential_iterations),
    Variable("normal_iterations", "Integer", "output", None, "",
             "BEM normal iterations of the last step, all of its solves"
             + _work_note("normal_iterations"),
             _step_work("normal_iterations")),
    Variable("tangential_iterations", "Integer", "output", None, "",
             "tangential BEM sweeps of the last step, all of its solves"
             + _work_note("tangential_iterations"),
             _step_work("tangential_iterations")),
    Variable("status", "Integer", "output", None, "",
             f"the wheelset's status, the more severe of its wheels' "
             f"({Status.severity_order()}), "
             f"1 also when control=load found no wheelset_vertical_displacement and "
             f"wheelset_roll: {STATUS}",
             lambda r: r.status),
    *_wheel("load_passes", "Integer", "", "solves of the wheel in the last step's contact "
            "solve (load loop)", value=lambda w: w.load_passes),
    *_wheel("remeshes", "Integer", "", "normal solves of the wheel's contact solve repeated "
            "on a grown potential area in the last step", value=lambda w: w.remeshes),
    *_wheel("load_unique", "Integer", "", "1 when the wheel load has one solution, 0 when "
            "it has or may have several: two contact regions joining into one patch "
            "between two roots (the smallest approach is returned), or several patches "
            "with mu tan(gamma) >= 1 on one (the one continuous with the previous step); "
            "meaningful with status 0 or 1",
            value=lambda w: int(w.load_unique)),
    *_wheel("status", "Integer", "", f"the wheel's own status: {STATUS}",
            value=lambda w: w.status),
    *_wheel("contact_longitudinal_position", "Real", "m", "contact point, track X (ahead "
            "of the axle when the wheelset is yawed)", value=lambda w: w.contact_point[0]),
    *_wheel("contact_vertical_position", "Real", "m", "contact point, track Z (rail top "
            "at 0)", value=lambda w: w.contact_point[2]),
    Variable("wheelset_vertical_displacement", "Real", "output", None, "m",
             "wheelset centre's vertical displacement, positive up, from r0 above the rail "
             "tops: the input under control=penetration; under control=load the rigid "
             "wheelset's at which both wheels, penetration-controlled, carry their loads "
             "(status 1 when not found; 0 with rigid_wheelset=skip)", _solved("vertical")),
    Variable("wheelset_roll", "Real", "output", None, "rad",
             "wheelset roll angle, positive left side up: the input under "
             "control=penetration; under control=load the rigid wheelset's (0 with "
             "rigid_wheelset=skip)",
             _solved("roll")),
    Variable("roll_moment", "Real", "output", None, "N.m",
             "moment of the rails on the wheelset about the track X axis through its centre "
             "(positive lifts the left wheel)", lambda r: r.moment[0]),
    Variable("pitch_moment", "Real", "output", None, "N.m",
             "moment of the rails on the wheelset about the track Y axis through its centre "
             "(the axle; right-handed about Y, which points to the left)",
             lambda r: r.moment[1]),
    *_wheel("derailment_quotient", "Real", "1", "Y/Q: lateral force of the wheel on the "
            "rail towards the field side over the vertical force",
            value=lambda w: w.derailment_quotient),
    *_wheel("penetration", "Real", "m", "largest normal penetration of the patches",
            value=lambda w: w.penetration),
    *_wheel("validity", "Integer", "", "the limits the wheel is beyond, a sum of bits: 1 "
            "Y/Q above max_y_q, 2 beyond Nadal's limit, 4 flange climb, 8 penetration above "
            "max_penetration, 16 load above max_wheel_load, 32 a patch under-resolved (its "
            "contact fewer than 4 elements along x, the rolling direction) (0: within all)",
            value=lambda w: w.validity),
]
"""The outputs; ``value(result)`` reads each from a
:class:`~railcontact.timestep.WheelsetResult`."""

APPENDED_OUTPUTS = [
    Variable("rigid_evaluations", "Integer", "output", None, "",
             "evaluations of the rigid wheelset's search in the last step (control=load, "
             "rigid_wheelset=solve; each at a roll other than the pose's solves both "
             "wheels again; 0 when not solved)",
             lambda r: 0 if r.rigid_solution is None else r.rigid_solution.evaluations),
    Variable("rigid_normal_iterations", "Integer", "output", None, "",
             "BEM normal iterations of the rigid wheelset's solves at other rolls in the "
             "last step, both wheels (part of normal_iterations)",
             _rigid_work("normal_iterations")),
    Variable("rigid_tangential_iterations", "Integer", "output", None, "",
             "tangential BEM sweeps of the rigid wheelset's solves at other rolls in the "
             "last step, both wheels (part of tangential_iterations)",
             _rigid_work("tangential_iterations")),
    Variable("rigid_load_passes", "Integer", "output", None, "",
             "load passes of the rigid wheelset's solves at other rolls in the last step, "
             "both wheels", _rigid_work("load_passes")),
    Variable("rigid_remeshes", "Integer", "output", None, "",
             "normal solves of the rigid wheelset's solves at other rolls repeated on a "
             "grown potential area in the last step, both wheels", _rigid_work("remeshes")),
]
"""Outputs numbered after the ``_choice`` enumerations: :func:`table` numbers them after
every other variable, so that the value references of the variables before them stay
those that hosts already use (:data:`APPENDED`)."""

TRACK_INPUTS = [
    Variable("curvature", "Real", "input", 0.0, "1/m",
             "track curvature, positive when the track turns left (creepage_input="
             "kinematic: the rails turn with -speed * curvature relative to the track frame; "
             f"within +-{MAX_CURVATURE:g}, a radius of {1 / MAX_CURVATURE:g} m or more"
             f"{_OUTSIDE})"),
    *[v for s in SIDES for v in (
        Variable(f"rail_offset_lateral_{s}", "Real", "input", 0.0, "m",
                 f"{s} rail's lateral offset from its place, positive to the left (an "
                 f"irregularity; a gauge change): {_SHIFTS}"),
        Variable(f"rail_offset_vertical_{s}", "Real", "input", 0.0, "m",
                 f"{s} rail's vertical offset from its place, positive up: {_SHIFTS}"),
        Variable(f"rail_roll_{s}", "Real", "input", 0.0, "rad",
                 f"{s} rail's roll about the track X axis (right-handed, Y to the left, Z "
                 f"up), about the rail profile's origin: within +-{MAX_RAIL_ROLL:g}"
                 f"{_OUTSIDE}"),
        Variable(f"friction_{s}", "Real", "input", 0.0, "1",
                 f"coefficient of friction on the {s} rail at this step (wet, contaminated, "
                 f"lubricated); <= 0 means the parameter friction; at most {MAX_MU:g}"
                 f"{_OUTSIDE}"))],
]
"""Inputs of the real track, numbered after :data:`APPENDED_OUTPUTS`."""
TRACK_OUTPUTS = [
    *_wheel("frictional_power", "Real", "W", "frictional power of the wheel's creep forces, "
            "speed * (F_x xi + F_y eta + M_z phi) over its patches (negative: dissipated; "
            "the traction times the slip integrated, in steady rolling); 0 where speed is "
            "not a finite number above 0 (creepage_input=direct: set speed to have it)",
            value=lambda w: w.frictional_power_per_speed),
]
"""Outputs of the real track, numbered after :data:`TRACK_INPUTS`; the slave multiplies
the per-speed power by the ``speed`` input."""


def parameters_markdown() -> str:
    """The FMU parameters as a Markdown table: the setting behind each, default, unit."""
    out = ["## FMU parameters", "",
           "Each parameter of the FMU sets one of the settings above (the material is one "
           "for wheel and rail).", "",
           "| parameter | type | setting | default | unit | meaning |", "|---|---|---|---|---|---|"]
    for v, (_, record, key) in zip(PARAMETERS, PARAMETER_SOURCES, strict=True):
        start = f"{v.start:.6g}" if isinstance(v.start, float) else repr(v.start)
        out.append(f"| `{v.name}` | {v.type} | `{record.__name__}.{key}` | {start} | "
                   f"{v.unit} | {v.description} |")
    return "\n".join(out) + "\n"


def _single_table() -> list[Variable]:
    """The variables of the one-wheelset FMU, numbered (:func:`table`)."""
    first = [v for v in PARAMETERS if v.name not in APPENDED + APPENDED_TRACK]
    appended = [next(v for v in PARAMETERS if v.name == name) for name in APPENDED]
    track = [next(v for v in PARAMETERS if v.name == name) for name in APPENDED_TRACK]
    return _numbered(first + INPUTS + OUTPUTS + appended + CHOICES + APPENDED_OUTPUTS + track
                     + TRACK_INPUTS + TRACK_OUTPUTS)


MAX_WHEELSETS = 8
"""The most wheelsets one FMU solves (``railcontact fmu build --wheelsets N``)."""


def _of_wheelset(v: Variable, k: int) -> Variable:
    """Wheelset ``k``'s copy of an input or output of the one-wheelset table: the name
    with ``_k`` appended (``normal_force_left_2``), the description naming the wheelset."""
    return replace(v, name=f"{v.name}_{k}", description=f"{v.description} (wheelset {k})")


def wheelset_count_parameter(wheelsets: int) -> Variable:
    """The Integer parameter ``wheelsets`` of an FMU of ``wheelsets`` wheelsets."""
    return Variable("wheelsets", "Integer", "parameter", wheelsets, "",
                    f"number of wheelsets this FMU solves, fixed when it was built (railcontact "
                    f"fmu build --wheelsets N, 1 to {MAX_WHEELSETS}); any other value is an "
                    f"error at initialisation")


VEHICLE_OUTPUTS = [
    Variable("status", "Integer", "output", None, "",
             f"the most severe of the wheelsets' status_k ({Status.severity_order()}); the "
             "step's FMI status is the worst of the wheelsets' steps"),
    Variable("solve_time", "Real", "output", None, "s",
             "wall time of the last step's solves of all wheelsets (in worker processes "
             "or on threads)"),
]
"""The outputs of an FMU of several wheelsets about all of them (the slave writes them)."""


def check_wheelsets(wheelsets: int) -> int:
    """``wheelsets`` as an int from 1 to :data:`MAX_WHEELSETS`; a
    :class:`~railcontact.errors.RailContactError` otherwise."""
    if isinstance(wheelsets, bool) or not isinstance(wheelsets, int) or \
            not 1 <= wheelsets <= MAX_WHEELSETS:
        raise RailContactError(f"wheelsets must be an integer from 1 to {MAX_WHEELSETS}, got "
                               f"{wheelsets!r}")
    return wheelsets


def table(wheelsets: int | None = None) -> list[Variable]:
    """All variables with their value references (numbered per type from 0).

    Parameters
    ----------
    wheelsets
        None: the FMU of one wheelset (the default build; its value references are a
        published interface). 1 to :data:`MAX_WHEELSETS`: the FMU of that many wheelsets.
        Its parameters are the default build's, once and shared by the wheelsets, and the
        Integer parameter ``wheelsets``; then the outputs about all wheelsets
        (:data:`VEHICLE_OUTPUTS`); then, per wheelset k = 1..N, every input and output of
        the default build with ``_k`` appended, in the default build's order. A variable's
        value reference does not depend on N.
    """
    single = _single_table()
    if wheelsets is None:
        return single
    n = check_wheelsets(wheelsets)
    own = [v for v in single if v.causality != "parameter"]
    layout = ([v for v in single if v.causality == "parameter"]
              + [wheelset_count_parameter(n)] + VEHICLE_OUTPUTS
              + [_of_wheelset(v, k) for k in range(1, n + 1) for v in own])
    return _numbered(layout)


def _numbered(variables: list[Variable]) -> list[Variable]:
    counters: dict[str, int] = {}
    out = []
    for v in variables:
        k = counters.get(v.type, 0)
        counters[v.type] = k + 1
        out.append(replace(v, vr=k))
    return out


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def _default(v: Variable) -> str:
    if v.causality == "output" or v.start is None:
        return ""
    if v.items:
        return f"{v.start} ({v.items[v.start - 1]})"
    if isinstance(v.start, float):
        return f"{v.start:.6g}"
    return f"`{v.start}`" if isinstance(v.start, str) else str(v.start)


def variables_markdown() -> str:
    """Every FMU variable as a Markdown table: name, causality, type, unit, default and
    meaning, in the order parameters, enumerations, inputs, outputs; a ``_left``/``_right``
    pair is one row. The table of docs/fmu.md is this (``scripts/fmu_variables_table.py``
    writes it; ``tests/test_readme_fmu.py`` checks it)."""
    everything = (PARAMETERS + CHOICES + INPUTS + TRACK_INPUTS + OUTPUTS + APPENDED_OUTPUTS
                  + TRACK_OUTPUTS)
    names = {v.name for v in everything}
    out = ["| name | causality | type | unit | default | meaning |",
           "|---|---|---|---|---|---|"]
    for v in everything:
        if v.name.endswith("_right") and v.name[:-6] + "_left" in names:
            continue
        name, meaning = f"`{v.name}`", v.description
        if v.name.endswith("_left") and v.name[:-5] + "_right" in names:
            name = f"`{v.name[:-5]}_left`, `_right`"
            meaning = (meaning.replace(", left wheel", "").replace("the left wheel's",
                                                                  "each wheel's")
                       .replace("the left rail's", "each rail's")
                       .replace("on the left rail", "on each rail")
                       .replace("left wheel", "each wheel").replace(", left (", " ("))
        kind = v.type
        if v.items:
            kind = "Enumeration: " + ", ".join(f"{k} {w}" for k, w in
                                                enumerate(v.items, start=1))
        out.append(f"| {name} | {v.causality} | {_cell(kind)} | {v.unit} | "
                   f"{_cell(_default(v))} | {_cell(meaning)} |")
    return "\n".join(out) + "\n"


def wheelsets_markdown() -> str:
    """The variables of an FMU of N wheelsets (``railcontact fmu build --wheelsets N``)
    beyond the parameters of the one-wheelset FMU, as a Markdown table: ``wheelsets``, the
    outputs about all wheelsets, and a row for every input and output repeated per
    wheelset. The table of docs/fmu.md's section on it is this
    (``scripts/fmu_variables_table.py`` writes it; ``tests/test_readme_fmu.py`` checks
    it)."""
    out = ["| name | causality | type | unit | default | meaning |",
           "|---|---|---|---|---|---|"]
    for v in [wheelset_count_parameter(2), *VEHICLE_OUTPUTS]:
        start = "N" if v.name == "wheelsets" else ""
        out.append(f"| `{v.name}` | {v.causality} | {v.type} | {v.unit} | {start} | "
                   f"{_cell(v.description)} |")
    out.append("| `<name>_1` ... `<name>_N` | input, output | as `<name>` | as `<name>` | as "
               "`<name>` | every input and output `<name>` of the one-wheelset FMU (the "
               "table above), of wheelset k: `lateral_displacement_2`, "
               "`normal_force_left_2`, `status_2`, `status_left_2`, `solve_time_2` |")
    return "\n".join(out) + "\n"

