"""The module paths from before the layers (railcontact 0.1) still import, with a
DeprecationWarning naming the new place (``docs/architecture.md``, "Where things moved").

``import railcontact.wheelset`` gives a small module that forwards every attribute to
``railcontact.timestep.wheelset``; the classes and functions are the new ones themselves.
Signatures that changed with the typed settings (the patch solvers take settings records
instead of dictionaries) are not adapted.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import types
import warnings

MOVED = {
    "railcontact.materials": "railcontact.halfspace.materials",
    "railcontact.grid": "railcontact.halfspace.grid",
    "railcontact.influence": "railcontact.halfspace.influence",
    "railcontact.operator": "railcontact.halfspace.operator",
    "railcontact.hertz": "railcontact.halfspace.hertz",
    "railcontact.pipeline": "railcontact.contact",
    "railcontact.wheelrail": "railcontact.contact.wheelrail",
    "railcontact.case": "railcontact.settings",
    "railcontact.wheelset": "railcontact.timestep.wheelset",
    "railcontact.warmstart": "railcontact.timestep.warmstart",
    "railcontact.dynamics": "railcontact.sim.dynamics",
    "railcontact.cosim": "railcontact.sim.cosim",
    "railcontact.demo": "railcontact.sim.demo",
    "railcontact.plotting": "railcontact.io.plotting",
    "railcontact.geometry.contact": "railcontact.geometry.search",
}
"""Old module path -> the module that holds its contents now."""


class _Forward(types.ModuleType):
    """A module that forwards attribute access to the module that replaced it."""

    def __getattr__(self, name: str):
        return getattr(sys.modules[self.__moved_to__], name)

    def __dir__(self):
        return dir(sys.modules[self.__moved_to__])


class _MovedFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    def find_spec(self, fullname, path=None, target=None):
        if fullname in MOVED:
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        new = MOVED[spec.name]
        warnings.warn(f"{spec.name} has moved to {new}; import it from there (or from "
                      "railcontact)", DeprecationWarning, stacklevel=2)
        importlib.import_module(new)
        module = _Forward(spec.name, f"moved to {new}")
        module.__moved_to__ = new
        return module

    def exec_module(self, module) -> None:
        """Nothing to run: the attributes are the new module's."""


def install() -> None:
    """Let the old paths import (once per process)."""
    if not any(isinstance(f, _MovedFinder) for f in sys.meta_path):
        sys.meta_path.append(_MovedFinder())
