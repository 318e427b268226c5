"""Typed settings: one frozen record per concern, validated once, defaults and units where
they are declared.

- :mod:`.case`: the tables of a case file (:class:`Case`, :func:`load_case`);
- :mod:`.timestep`: :class:`ContactSettings` of the time-step solver and the FMU's modes;
- :mod:`.choices`: the words a setting can take;
- :mod:`.convention`: CONTACT's creepages and forces beside railcontact's;
- :mod:`.friction`: friction tables across the profile (CONTACT's VARFRC);
- :mod:`.reference`: every setting in one list (``railcontact settings``).

The solvers below this layer take plain keyword arguments; the patch and wheel-rail
solvers above it take these records, never dictionaries.
"""

from .case import (
    Case,
    Control,
    GridSettings,
    KinematicsSettings,
    MaterialSettings,
    NormalSettings,
    PatchSettings,
    QuadraticGeometry,
    TangentialSettings,
    WheelRailGeometry,
    load_case,
    validate_case,
)
from .reference import markdown, setting_rows
from .timestep import ContactSettings, FMUModes

__all__ = [
    "Case", "ContactSettings", "Control", "FMUModes", "GridSettings", "KinematicsSettings",
    "MaterialSettings",
    "NormalSettings", "PatchSettings", "QuadraticGeometry", "TangentialSettings",
    "WheelRailGeometry", "load_case", "markdown", "setting_rows", "validate_case",
]
