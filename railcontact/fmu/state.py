"""An FMU instance's saved state as bytes: numbers and arrays in a documented format.

``fmi2GetFMUstate`` keeps, and ``fmi2SerializeFMUstate`` hands out, the bytes of
:func:`pack`; ``fmi2SetFMUstate`` reads them back with :func:`unpack`, which runs no code
from them: no pickle, only JSON and NumPy arrays read with ``allow_pickle=False``, and
records only of the few types of :data:`TYPES`, made from their fields by their own
constructors (whose checks run: a record that is not one is a :class:`StateError`).

Layout (integers little-endian)::

    bytes 0-15    MAGIC, b"RAILCONTACTSTATE"
    bytes 16-19   format version, uint32 (VERSION)
    bytes 20-27   length L of the header [bytes], uint64
    L bytes       the header: JSON, UTF-8
    the rest      a NumPy ``.npz`` archive (numpy.savez, uncompressed) of the arrays the
                  header refers to by name

The header is an object with

``format``
    ``"railcontact-fmu-state"``.
``version``
    :data:`VERSION` again.
``guid``, ``model``
    The FMU's GUID (its modelDescription.xml's) and model identifier: a state is set only
    in an instance of the FMU that saved it.
``railcontact``
    The package version (for information).
``initialised``
    Whether the instance had built its solver (after ``fmi2ExitInitializationMode``).
``parameters``
    Every parameter's value by name (Real as numbers, the ``_choice`` enumerations as
    integers, Strings as strings): those the instance's solver was built with, else the
    values set so far.
``strings``
    The String variables' values, by value reference.
``memory``
    The solver's memory of the previous steps (the warm start), or null before
    initialisation, as a tree (below); in an FMU of several wheelsets a list of their
    memories, wheelset 1 first.

and the archive holds ``real`` (float64, the Real variables by value reference),
``integer`` (int32, the Integer variables), ``control`` (float64, the time [s] and
step size [s] of the last step asked for, and the last successful time [s]) and the
arrays of the memory, ``a0``, ``a1``, ...

The tree: JSON null, booleans, integers, strings and finite numbers stand for themselves;
a list for a list; objects with one key starting with ``$`` for the rest:
``{"$float": "nan" | "inf" | "-inf"}``, ``{"$tuple": [...]}``, ``{"$dict": {...}}``
(string keys), ``{"$array": "a3"}`` (an array of the archive), ``{"$scalar": "a4"}``
(a NumPy scalar: a 0-d array of the archive), ``{"$object": "PatchMemory", "id": 2,
"fields": {...}}`` (a record of :data:`TYPES`, its attributes by name) and ``{"$ref": 2}``
(the same record again: what two parts of the memory share stays shared, as in the
instance that saved it). A restored memory equals the saved one bit for bit, so a step
repeated after ``fmi2SetFMUstate`` repeats the original exactly.
"""

from __future__ import annotations

import io
import json
import math
import struct
import zipfile
from dataclasses import MISSING, dataclass, fields
from typing import Any

import numpy as np

from ..errors import RailContactError
from ..halfspace.grid import Grid
from ..normal.bem import Displacement
from ..timestep.memory import StepMemory
from ..timestep.rigid import RigidMemory
from ..timestep.warmstart import PatchMemory

MAGIC = b"RAILCONTACTSTATE"
VERSION = 3
FORMAT = "railcontact-fmu-state"
_PREFIX = struct.Struct("<16sIQ")
MAX_HEADER = 1 << 30
"""Largest header [bytes] read (a length beyond it is a damaged state)."""

TYPES: dict[str, type] = {cls.__name__: cls for cls in (StepMemory, PatchMemory, Grid,
                                                        Displacement, RigidMemory)}
"""The records a saved memory may hold, by name. A new kind of record in the time step's
memory (:attr:`railcontact.timestep.WheelsetContact.memory`) must be added here, or saving
a state says which one it is."""


class StateError(RailContactError):
    """Bytes that are no state of this FMU, or a state that cannot be saved."""


@dataclass(frozen=True)
class State:
    """A saved state, read back (:func:`unpack`).

    Attributes
    ----------
    guid, model
        The FMU's GUID and model identifier.
    initialised
        Whether the instance had built its solver.
    parameters
        Parameter values by name.
    real, integer, control
        The Real and Integer variables [SI units] by value reference, and (time [s], step
        size [s]) of the last step.
    strings
        The String variables by value reference.
    memory
        The solver's memory (the warm start), a list of the wheelsets' in an FMU of
        several, or None before initialisation.
    railcontact
        The package version that saved it.
    """

    guid: str
    model: str
    initialised: bool
    parameters: dict[str, Any]
    real: np.ndarray
    integer: np.ndarray
    control: np.ndarray
    strings: list[str]
    memory: Any
    railcontact: str = ""


# -- writing -------------------------------------------------------------------------------
class _Encoder:
    def __init__(self) -> None:
        self.arrays: dict[str, np.ndarray] = {}
        self._array_keys: dict[int, str] = {}
        self._object_ids: dict[int, int] = {}
        self._keep: list[Any] = []  # alive while encoding: ids stay unique

    def array(self, a: np.ndarray) -> str:
        key = self._array_keys.get(id(a))
        if key is None:
            if a.dtype.hasobject:
                raise StateError(f"cannot save an array of Python objects ({a.dtype})")
            key = f"a{len(self.arrays)}"
            self.arrays[key] = a
            self._array_keys[id(a)] = key
            self._keep.append(a)
        return key

    def encode(self, value: Any, where: str) -> Any:
        if value is None or isinstance(value, (bool, str)):
            return value
        if isinstance(value, int) and type(value) is int:
            return value
        if type(value) is float:
            return value if math.isfinite(value) else {"$float": repr(value)}
        if isinstance(value, np.ndarray):
            return {"$array": self.array(value)}
        if isinstance(value, np.generic):
            return {"$scalar": self.array(np.asarray(value))}
        if type(value) is list:
            return [self.encode(v, f"{where}[{k}]") for k, v in enumerate(value)]
        if type(value) is tuple:
            return {"$tuple": [self.encode(v, f"{where}[{k}]") for k, v in enumerate(value)]}
        if type(value) is dict:
            if not all(isinstance(k, str) for k in value):
                raise StateError(f"cannot save {where}: a dict with keys other than strings")
            return {"$dict": {k: self.encode(v, f"{where}[{k!r}]") for k, v in value.items()}}
        name = type(value).__name__
        if TYPES.get(name) is type(value):
            n = self._object_ids.get(id(value))
            if n is not None:
                return {"$ref": n}
            n = self._object_ids[id(value)] = len(self._object_ids)
            self._keep.append(value)
            attributes = {f.name: getattr(value, f.name) for f in fields(value) if f.init}
            return {"$object": name, "id": n,
                    "fields": {k: self.encode(v, f"{where}.{k}")
                               for k, v in attributes.items()}}
        raise StateError(
            f"cannot save {where}: a {type(value).__module__}.{type(value).__qualname__} "
            f"(a state holds numbers, arrays and the records of railcontact.fmu.state.TYPES)")


def pack(state: State) -> bytes:
    """``state`` as bytes (module docstring). Raises :class:`StateError` for a memory
    that holds anything but numbers, strings, arrays and the records of :data:`TYPES`."""
    enc = _Encoder()
    header = {
        "format": FORMAT, "version": VERSION, "guid": state.guid, "model": state.model,
        "railcontact": state.railcontact, "initialised": bool(state.initialised),
        "parameters": {k: enc.encode(_plain(v), f"parameter {k}")
                       for k, v in state.parameters.items()},
        "strings": [str(s) for s in state.strings],
        "memory": enc.encode(state.memory, "memory"),
    }
    arrays = {"real": np.asarray(state.real, dtype=np.float64),
              "integer": np.asarray(state.integer, dtype=np.int32),
              "control": np.asarray(state.control, dtype=np.float64), **enc.arrays}
    text = json.dumps(header, allow_nan=False, separators=(",", ":")).encode("utf-8")
    out = io.BytesIO()
    out.write(_PREFIX.pack(MAGIC, VERSION, len(text)))
    out.write(text)
    np.savez(out, **arrays)
    return out.getvalue()


def _plain(value: Any) -> Any:
    """A parameter value as a Python number or string (numpy scalars as Python's)."""
    if isinstance(value, np.generic):
        return value.item()
    return value


# -- reading -------------------------------------------------------------------------------
class _Decoder:
    def __init__(self, arrays: dict[str, np.ndarray]) -> None:
        self.arrays = arrays
        self.objects: dict[int, Any] = {}

    def array(self, key: Any) -> np.ndarray:
        if not isinstance(key, str) or key not in self.arrays:
            raise StateError(f"the state refers to an array {key!r} it does not hold")
        return self.arrays[key]

    def decode(self, value: Any) -> Any:
        if value is None or isinstance(value, (bool, str, int, float)):
            return value
        if isinstance(value, list):
            return [self.decode(v) for v in value]
        if not isinstance(value, dict) or len(value) not in (1, 3):
            raise StateError(f"not a value of a state: {_short(value)}")
        if len(value) == 1:
            (tag, body), = value.items()
            if tag == "$float" and body in ("nan", "inf", "-inf"):
                return float(body)
            if tag == "$tuple" and isinstance(body, list):
                return tuple(self.decode(v) for v in body)
            if tag == "$dict" and isinstance(body, dict):
                return {k: self.decode(v) for k, v in body.items()}
            if tag == "$array":
                return self.array(body)
            if tag == "$scalar":
                a = self.array(body)
                if a.ndim != 0:
                    raise StateError(f"the state's scalar {body!r} is an array")
                return a[()]
            if tag == "$ref" and type(body) is int and body in self.objects:
                return self.objects[body]
            raise StateError(f"not a value of a state: {_short(value)}")
        return self.record(value)

    def record(self, value: dict) -> Any:
        name, n, attributes = value.get("$object"), value.get("id"), value.get("fields")
        cls = TYPES.get(name) if isinstance(name, str) else None
        if cls is None or type(n) is not int or n in self.objects or not isinstance(
                attributes, dict):
            raise StateError(f"not a record a state may hold: {_short(value)}")
        given = [f for f in fields(cls) if f.init]
        names = {f.name for f in given}
        required = {f.name for f in given
                    if f.default is MISSING and f.default_factory is MISSING}
        missing = required - attributes.keys()
        unknown = [k for k in attributes if k not in names]
        if missing or unknown:
            raise StateError(f"a {name} of the state with attributes "
                             f"{sorted(attributes)} (missing {sorted(missing)}, unknown "
                             f"{unknown})")
        values = {k: self.decode(v) for k, v in attributes.items()}
        try:  # the record made as the solver makes it: its own checks run
            obj = cls(**values)
        except (RailContactError, TypeError, ValueError) as exc:
            raise StateError(f"a {name} of the state that is not one: {exc}") from None
        self.objects[n] = obj
        return obj


def _short(value: Any) -> str:
    text = json.dumps(value)[:80] if _jsonable(value) else repr(value)[:80]
    return text


def _jsonable(value: Any) -> bool:
    try:
        json.dumps(value)
    except (TypeError, ValueError):
        return False
    return True


def unpack(data: bytes) -> State:
    """The state in ``data`` (bytes of :func:`pack`). Runs no code from the bytes; raises
    :class:`StateError` for anything that is not such a state (another format, a later
    version, a damaged header or archive)."""
    data = bytes(data)
    if len(data) < _PREFIX.size or not data.startswith(MAGIC):
        raise StateError("not a railcontact FMU state (it does not start with "
                         f"{MAGIC.decode()}): a state of another FMU, or damaged bytes")
    _, version, length = _PREFIX.unpack_from(data)
    if version != VERSION:
        raise StateError(f"a railcontact FMU state of format version {version}; this FMU "
                         f"reads version {VERSION}")
    end = _PREFIX.size + length
    if length > MAX_HEADER or end > len(data):
        raise StateError("a damaged railcontact FMU state (its header is cut short)")
    try:
        header = json.loads(data[_PREFIX.size:end].decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise StateError(f"a damaged railcontact FMU state (its header: {exc})") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT or \
            header.get("version") != VERSION:
        raise StateError("a damaged railcontact FMU state (its header names no format "
                         f"{FORMAT!r}, version {VERSION})")
    try:
        with np.load(io.BytesIO(data[end:]), allow_pickle=False) as archive:
            arrays = {k: archive[k] for k in archive.files}
    except (ValueError, OSError, EOFError, zipfile.BadZipFile, KeyError) as exc:
        raise StateError(f"a damaged railcontact FMU state (its arrays: {exc})") from None
    for key, dtype in (("real", np.float64), ("integer", np.int32),
                       ("control", np.float64)):
        a = arrays.get(key)
        if a is None or a.dtype != dtype or a.ndim != 1:
            raise StateError(f"a damaged railcontact FMU state (no {key} variables)")
    strings, parameters = header.get("strings"), header.get("parameters")
    if not isinstance(strings, list) or not all(isinstance(s, str) for s in strings) or \
            not isinstance(parameters, dict):
        raise StateError("a damaged railcontact FMU state (its strings or parameters)")
    dec = _Decoder(arrays)
    return State(guid=str(header.get("guid", "")), model=str(header.get("model", "")),
                 initialised=bool(header.get("initialised")),
                 parameters={k: dec.decode(v) for k, v in parameters.items()},
                 real=arrays["real"], integer=arrays["integer"], control=arrays["control"],
                 strings=strings, memory=dec.decode(header.get("memory")),
                 railcontact=str(header.get("railcontact", "")))


__all__ = ["FORMAT", "MAGIC", "TYPES", "VERSION", "State", "StateError", "pack", "unpack"]
