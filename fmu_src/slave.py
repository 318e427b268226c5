"""The Python side of the railcontact FMU: one object per FMU instance.

The C shim (the ``*.c`` files, their jobs listed in ``railcontact_fmu.h``) owns nothing but
pointers: it reads and writes the Real and Integer variables directly in this object's numpy
buffers (``buffers()``), and calls the methods below, each of which returns an FMI status
(0 OK, 1 Warning, 2 Discard, 3 Error) and never raises; what went wrong is kept for ``pop_log()``.

An FMU built with ``--wheelsets N`` (``resources/wheelsets.txt`` holds N) solves N
wheelsets, each with its own solver and its own variables (``_k`` appended to the names of
the one-wheelset FMU, :func:`railcontact.fmu.variables.table`), in one ``fmi2DoStep``, the
step's FMI status the worst of the wheelsets'. The wheelsets are shared among processes
(:class:`~railcontact.timestep.pool.WheelsetPool`, each wheelset's solver and its memory
always in the same process: this one and worker processes, which send back
:class:`~railcontact.fmu.outputs.StepOutputs`) or among threads of this process (each
wheelset always on the same thread; the kernels release the GIL, and distinct solvers
stepping on threads give the results of stepping them one after the other, bit for bit:
the thread-safety contract of ``docs/performance.md``): :func:`_workers`. Both ways write
the outputs from the same :class:`~railcontact.fmu.outputs.StepOutputs`, so that they
agree bit for bit.

This file is copied into the FMU as ``<package>/_fmu_slave.py`` next to a copy of the
railcontact package, hence the relative imports.
"""

from __future__ import annotations

import math
import os
import re
import sys
import time
import traceback
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from . import __version__
from .errors import RailContactError
from .fmu import state as S
from .fmu import variables as V
from .fmu.outputs import StepOutputs, WheelOutcome, step_outputs
from .geometry.profiles import read_profile
from .geometry.track import Pose, Track, Wheelset
from .settings import ContactSettings, FMUModes
from .status import Status
from .table import TableContact  # (xarray, zarr: imported when a table is opened)
from .timestep import Kinematics, RailDeviation, WheelsetContact
from .timestep.memory import EMPTY as EMPTY_MEMORY
from .timestep.memory import StepMemory
from .timestep.pool import RemoteError, WheelsetDescription, WheelsetPool, worker_python
from .timestep.wheelset import (
    NO_DEVIATION,
    NOT_CONVERGED,
    OUT_OF_RANGE,
    OUTSIDE_VALIDITY,
    STATUS_NAMES,
)

FMI_OK, FMI_WARNING, FMI_DISCARD, FMI_ERROR = 0, 1, 2, 3
OUTPUT, INPUT, PARAMETER = 0, 1, 2
REFUSED_UNKNOWN, REFUSED_OUTPUT, REFUSED_PARAMETER, REFUSED_ENDED, REFUSED_NULL = range(5)
"""Why the shim did not set a value (its ``REFUSED_*``, :meth:`Slave.refusal`)."""
_CAUSALITY = {"output": OUTPUT, "input": INPUT, "parameter": PARAMETER}
WHEELSETS_FILE = "wheelsets.txt"
"""The resources file of an FMU of several wheelsets: their number N (absent: the
one-wheelset FMU)."""


def wheelsets_of(resources: Path) -> int | None:
    """The number of wheelsets of the FMU whose resources folder this is
    (:data:`WHEELSETS_FILE`), None for the one-wheelset FMU."""
    try:
        text = (Path(resources) / WHEELSETS_FILE).read_text(encoding="utf-8")
    except FileNotFoundError:
        return None
    try:
        return V.check_wheelsets(int(text.strip()))
    except (ValueError, RailContactError):
        raise RailContactError(f"{WHEELSETS_FILE} of the FMU's resources holds {text!r}, not "
                               f"a number of wheelsets from 1 to {V.MAX_WHEELSETS}") from None


class _Wheelset:
    """One wheelset of an instance: the slots of its inputs and outputs in the instance's
    buffers (by the one-wheelset FMU's names), its solver and its messages.

    Parameters
    ----------
    slots
        (buffer, value reference) of every variable by name, the instance's.
    k
        The wheelset's number from 1 (its variables' suffix ``_k``), or None in the
        one-wheelset FMU (no suffix).
    variables
        The one-wheelset FMU's variables (their names, types and output functions).
    """

    def __init__(self, slots: dict, k: int | None, variables: list[V.Variable]) -> None:
        self.k = k
        suffix = "" if k is None else f"_{k}"
        own = [v for v in variables if v.causality != "parameter"]
        self.slots = {**slots, **{v.name: slots[v.name + suffix] for v in own}}
        outputs = [v for v in own if v.causality == "output"]
        self.zeroed = []  # (buffer, value references) of the Real and the Integer outputs
        for t in ("Real", "Integer"):  # (in the order of outputs.output_functions)
            mine = [v for v in outputs if v.type == t]
            buffer = slots[mine[0].name + suffix][0]
            vrs = np.array([slots[v.name + suffix][1] for v in mine], dtype=int)
            self.zeroed.append((buffer, vrs))
        self.real_outputs = self.zeroed[0][1]
        self.reads = np.zeros(0, dtype=np.intp)  # the inputs a step reads (Slave._reads)
        self.power = np.array([slots[f"frictional_power_{s}{suffix}"][1] for s in V.SIDES],
                              dtype=np.intp)  # (Real outputs)
        self.contact: WheelsetContact | TableContact | None = None
        self.log: list[str] = []

    def __getitem__(self, name: str):
        buffer, vr = self.slots[name]
        return buffer[vr]

    def __setitem__(self, name: str, value) -> None:
        buffer, vr = self.slots[name]
        buffer[vr] = value


class Slave:
    """One FMU instance.

    Parameters
    ----------
    resources
        The FMU's resources folder (profile files are looked up there).
    instance_name
        For messages.
    wheelsets
        The number of wheelsets (their variables, :func:`railcontact.fmu.variables.table`);
        default: the FMU's (:func:`wheelsets_of` its resources).
    """

    def __init__(self, resources: str, instance_name: str = "railcontact",
                 wheelsets: int | None | str = "resources") -> None:
        self.resources = Path(resources)
        self.instance_name = instance_name
        self.wheelsets = wheelsets_of(self.resources) if wheelsets == "resources" \
            else wheelsets
        self.variables = V.table(self.wheelsets)
        self.by_name = {v.name: v for v in self.variables}
        reals = [v for v in self.variables if v.type == "Real"]
        ints = [v for v in self.variables if v.type == "Integer"]
        strs = [v for v in self.variables if v.type == "String"]
        self.real = np.zeros(len(reals))
        self.integer = np.zeros(len(ints), dtype=np.int32)
        # (the step's time and size, the last successful time [s]) written by the shim;
        # a saved state holds them
        self.control = np.zeros(3)
        self.strings = [""] * len(strs)
        self.string_flags = bytes(_CAUSALITY[v.causality] for v in strs)
        self.real_flags = bytes(_CAUSALITY[v.causality] for v in reals)
        self.integer_flags = bytes(_CAUSALITY[v.causality] for v in ints)
        # each variable's buffer (a stable object: states are restored in place) and slot
        buffer = {"Real": self.real, "Integer": self.integer, "String": self.strings}
        self._slots = {v.name: (buffer[v.type], v.vr) for v in self.variables}
        self._by_reference = {(v.type, v.vr): v for v in self.variables}
        outputs = [v for v in self.variables if v.causality == "output"]
        if not all(v.type in ("Real", "Integer") for v in outputs):
            raise TypeError("the FMU's outputs are Real or Integer variables")
        self.log: list[str] = []
        single = V.table()
        if self.wheelsets is None:
            self.units = [_Wheelset(self._slots, None, single)]
            self.units[0].log = self.log  # one wheelset: its messages are the instance's
        else:
            self.units = [_Wheelset(self._slots, k, single)
                          for k in range(1, self.wheelsets + 1)]
        self._threads: list[ThreadPoolExecutor] = []  # made at the first step (threads)
        self._pool: WheelsetPool | None = None  # the worker processes (processes)
        self._kept: list[StepMemory] | None = None  # the workers' memories at termination
        self.workers: tuple[str, int] | None = None
        """How the wheelsets are stepped (:func:`_workers`), set at initialisation; None:
        in this thread one after the other (one wheelset, table mode)."""
        self.settings: ContactSettings | None = None  # the solver settings built with
        self._fell_back = False  # threads: no Python found to start worker processes
        self._descriptions: list[WheelsetDescription] = []  # the workers' wheelsets
        self._here = True  # processes: this one steps a share of the wheelsets as well
        self.modes: FMUModes | None = None
        self._reads: tuple[tuple[str, ...], tuple[str, ...]] = ((), ())  # (_read_inputs)
        self.built: dict | None = None  # the parameters self.contact was built with
        self.guid, self.model = _identity(self.resources)
        self._start_values()

    # -- plumbing for the shim ------------------------------------------------------------
    def buffers(self) -> tuple:
        """Addresses and sizes of the buffers and the causality flags, for the shim."""
        return (self.real.ctypes.data, len(self.real), self.integer.ctypes.data,
                len(self.integer), self.control.ctypes.data, self.real_flags,
                self.integer_flags, self.string_flags)

    def refusal(self, type_: str, vr: int, reason: int) -> str:
        """The message of the shim's refusal to set the ``type_`` ("Real", "Integer",
        "String") variable of value reference ``vr`` for ``reason`` (:data:`REFUSED_UNKNOWN`
        ... :data:`REFUSED_NULL`), naming the variable."""
        v = self._by_reference.get((type_, vr))
        if v is None or reason == REFUSED_UNKNOWN:
            return f"no {type_} variable with value reference {vr}"
        what = f"{type_} variable {v.name} (value reference {vr})"
        if reason == REFUSED_OUTPUT:
            return f"{what} is an output: only inputs and parameters can be set"
        if reason == REFUSED_PARAMETER:
            return (f"{what} is a parameter: it can be set only before "
                    "fmi2ExitInitializationMode (again after fmi2Reset)")
        if reason == REFUSED_ENDED:
            return (f"{what} cannot be set after fmi2Terminate or a failed initialization "
                    "(fmi2Reset starts the instance again)")
        if reason == REFUSED_NULL:
            return f"{what}: the value given is NULL, not a string"
        return f"{what} cannot be set now"

    def pop_log(self) -> str:
        """The messages since the last call, one per line."""
        text = "\n".join(self.log)
        self.log.clear()
        return text

    @property
    def contact(self) -> WheelsetContact | TableContact | None:
        """The (first) wheelset's solver in this process; None before initialisation and
        when the wheelsets are stepped in worker processes."""
        return self.units[0].contact

    @property
    def initialised(self) -> bool:
        """Whether the wheelsets' solvers are built (initialisation done, no reset
        since)."""
        return self.built is not None

    def close(self) -> int:
        """fmi2FreeInstance: stop the wheelsets' threads (they are made again when needed)
        and end the worker processes."""
        threads, self._threads = getattr(self, "_threads", []), []  # (__init__ may have failed)
        for t in threads:
            t.shutdown(wait=False)
        pool, self._pool = getattr(self, "_pool", None), None
        if pool is not None:
            pool.close()
        return FMI_OK

    def terminate(self) -> int:
        """fmi2Terminate: end the worker processes, their wheelsets' memories kept here
        for fmi2GetFMUstate (no step follows before fmi2Reset)."""
        return self._guard("terminate", FMI_ERROR, self._terminate)

    def _terminate(self) -> int:
        if self._pool is not None and self._pool.alive and self.initialised:
            self._kept = self._pool.memories()
        self.close()
        return FMI_OK

    def __del__(self) -> None:
        self.close()

    def _guard(self, what: str, fail: int, fn, *args):
        try:
            return fn(*args)
        except Exception as exc:  # never let an exception reach the simulator
            self.log.append(f"{what}: {type(exc).__name__}: {exc}\n{traceback.format_exc()}")
            return fail

    def _start_values(self) -> None:
        for v in self.variables:
            if v.type == "Real":
                self.real[v.vr] = 0.0 if v.start is None else float(v.start)
            elif v.type == "Integer":
                self.integer[v.vr] = 0 if v.start is None else int(v.start)
            else:
                self.strings[v.vr] = "" if v.start is None else str(v.start)

    def __getitem__(self, name: str):
        buffer, vr = self._slots[name]
        return buffer[vr]

    def __setitem__(self, name: str, value) -> None:
        buffer, vr = self._slots[name]
        buffer[vr] = value

    # -- FMI calls ------------------------------------------------------------------------
    def get_string(self, vr: int) -> str:
        return self.strings[vr]

    def set_string(self, vr: int, value: str) -> int:
        if not 0 <= vr < len(self.strings):
            self.log.append(f"no String variable with value reference {vr}")
            return FMI_ERROR
        self.strings[vr] = value
        return FMI_OK

    def enter_initialization(self) -> int:
        return FMI_OK

    def exit_initialization(self) -> int:
        return self._guard("initialization", FMI_ERROR, self._exit_initialization)

    def do_step(self) -> int:
        status = self._guard("doStep", None, self._communication_step)
        if status is None:  # an unexpected error: nothing of the step is to be trusted
            self._discard_all()
            return FMI_DISCARD
        return status

    def reset(self) -> int:
        """fmi2Reset: the start values, no solver (the worker processes stay, their
        wheelsets built anew at the next initialisation)."""
        self._start_values()
        for u in self.units:
            u.contact = None
        self.built = None
        self._kept = None
        return FMI_OK

    def get_state(self) -> bytes:
        """The instance's state as bytes (:mod:`railcontact.fmu.state`): the variables,
        the parameters the solver was built with and its memory of the previous steps.
        Raises (the shim's fmi2GetFMUstate returns fmi2Error) with the reason in the
        log."""
        try:
            return S.pack(S.State(
                guid=self.guid, model=self.model, initialised=self.initialised,
                parameters=self.built if self.built is not None else self._parameters(
                    self.real, self.integer, self.strings),
                real=self.real, integer=self.integer, control=self.control,
                strings=list(self.strings), memory=self._memory(),
                railcontact=__version__))
        except Exception as exc:
            self.log.append(f"getFMUstate: {type(exc).__name__}: {exc}")
            raise

    def _memory(self):
        """The solvers' memory of the previous steps: the wheelset's (one wheelset), a list
        of the wheelsets' (several; read from the worker processes when they step them),
        None before initialisation."""
        if not self.initialised:
            return None
        if self.wheelsets is None:
            return self.contact.memory
        if self._pool is not None:
            return self._pool.memories()
        if self._kept is not None:
            return list(self._kept)
        return [u.contact.memory for u in self.units]

    def set_state(self, data: bytes) -> int:
        """Restore a state of :meth:`get_state`: fmi2Error, the instance unchanged, for
        bytes that are no state of this FMU, and for a state of another parameter set than
        this instance's solver was built with. An instance not initialised takes any
        state of this FMU: its variables, parameters included, from which initialisation
        builds the solver (without the state's warm start)."""
        return self._guard("setFMUstate", FMI_ERROR, self._set_state, data)

    def check_state(self, data: bytes) -> int:
        """fmi2DeSerializeFMUstate's check of the bytes: fmi2OK for a state of this FMU
        (the format, its version and lengths, the JSON header, an archive read without
        pickle, this FMU's GUID and model identifier, its variables), else fmi2Error with
        the reason in the log. Whether its parameters fit an instance is left to
        :meth:`set_state`."""
        return self._guard("deSerializeFMUstate", FMI_ERROR, self._check_bytes, data)

    def _check_bytes(self, data: bytes) -> int:
        try:
            self._check_own(S.unpack(data))
        except RailContactError as exc:
            self.log.append(f"deSerializeFMUstate refused: {exc}")
            return FMI_ERROR
        return FMI_OK

    def _set_state(self, data: bytes) -> int:
        try:
            state = S.unpack(data)
            self._check_state(state)
        except RailContactError as exc:
            self.log.append(f"setFMUstate refused, the instance is unchanged: {exc}")
            return FMI_ERROR
        np.copyto(self.real, state.real)  # in place: the shim holds these buffers' addresses
        np.copyto(self.integer, state.integer)
        np.copyto(self.control, state.control)
        self.strings[:] = state.strings
        if not self.initialised:  # the solver is built from the parameters just
            return FMI_OK         # restored at initialisation
        memories = [state.memory] if self.wheelsets is None else state.memory
        if not state.initialised:
            memories = [None] * len(self.units)  # (None: forget the previous steps)
        if self._pool is not None:
            if not self._pool.alive:  # a worker ended (the step said fmi2Error): new ones
                self._pool = self._new_pool(self._descriptions, self.workers[1])
            self._pool.set_memories(memories)
            return FMI_OK
        if self._kept is not None:  # terminated: the workers have ended
            self._kept = [m if m is not None else EMPTY_MEMORY for m in memories]
            return FMI_OK
        for k, u in enumerate(self.units):
            if memories[k] is not None:
                u.contact.memory = memories[k]
            else:
                u.contact.reset()
        return FMI_OK

    def _check_state(self, state: S.State) -> None:
        """Raise :class:`~railcontact.fmu.state.StateError` unless ``state`` is one of
        this FMU whose parameters are those this instance's solver was built with."""
        held = self._check_own(state)
        if self.built is not None:
            diff = _differences(held, self.built, ("the state", "this instance"))
            if diff:
                raise S.StateError(
                    f"the state belongs to another parameter set ({diff}); a state is set "
                    f"only in an instance initialised with its parameters, or in one not "
                    f"yet initialised")

    def _check_own(self, state: S.State) -> dict:
        """Raise :class:`~railcontact.fmu.state.StateError` unless ``state`` is one of
        this FMU (its GUID and model identifier, its variables, parameters that agree with
        them); the parameter values it holds by name."""
        if (state.guid, state.model) != (self.guid, self.model):
            raise S.StateError(f"a state of another FMU (model {state.model!r}, GUID "
                               f"{state.guid}; this one: model {self.model!r}, GUID "
                               f"{self.guid})")
        if state.initialised:
            memories = [state.memory] if self.wheelsets is None else state.memory
            if not isinstance(memories, list) or len(memories) != len(self.units):
                raise S.StateError(f"the state's memory is a {type(state.memory).__name__}, "
                                   f"not the memory of {len(self.units)} wheelsets")
            for m in memories:
                if not isinstance(m, StepMemory):
                    raise S.StateError(f"the state's memory is a {type(m).__name__}, not a "
                                       "time step's memory (StepMemory)")
        shapes = [(state.real.shape, self.real.shape), (state.integer.shape,
                                                        self.integer.shape),
                  (state.control.shape, self.control.shape),
                  ((len(state.strings),), (len(self.strings),))]
        if any(a != b for a, b in shapes):
            raise S.StateError("a damaged state (its variables are not this FMU's)")
        held = self._parameters(state.real, state.integer, state.strings)
        if state.initialised and _differences(held, state.parameters):
            raise S.StateError("a damaged state (its parameters and its variables differ: "
                               + _differences(held, state.parameters) + ")")
        return held

    def _parameters(self, real, integer, strings) -> dict:
        """The parameter values by name held in the buffers ``real``, ``integer`` and
        ``strings`` (Python numbers and strings)."""
        held = {"Real": (real, float), "Integer": (integer, int), "String": (strings, str)}
        out = {}
        for v in V.PARAMETERS + V.CHOICES:
            buffer, kind = held[v.type]
            out[v.name] = kind(buffer[self._slots[v.name][1]])
        if self.wheelsets is not None:
            out["wheelsets"] = int(integer[self._slots["wheelsets"][1]])
        return out

    # -- the model ------------------------------------------------------------------------
    def _profile(self, parameter: str, kind: str, unit: str):
        value = self[parameter]
        path = self.resources / value
        source = str(path) if value and path.is_file() else value
        try:
            return read_profile(source, kind, unit)
        except RailContactError as exc:
            raise RailContactError(f"parameter {parameter} = {value!r}: {exc}") from None

    def _build(self) -> None:
        """Each wheelset's solver from the parameters (the wheelsets share the profiles,
        the material and the settings, and in table mode the table)."""
        self.built = None
        self.workers = None
        for u in self.units:
            u.contact = None
        for v in V.PARAMETERS:
            if v.type == "Real" and not math.isfinite(self[v.name]):
                raise RailContactError(f"parameter {v.name} = {self[v.name]}: not finite")
        if self.wheelsets is not None and self["wheelsets"] != self.wheelsets:
            raise RailContactError(
                f"parameter wheelsets = {self['wheelsets']}: this FMU was built for "
                f"{self.wheelsets} wheelsets, fixed in its modelDescription (build another "
                f"with railcontact fmu build --wheelsets {self['wheelsets']})")
        built = self._parameters(self.real, self.integer, self.strings)
        ps = V.parameter_settings(built)
        self._show_choices(built)
        self.modes = ps.modes
        names = _read_inputs(ps.modes)  # (what a step reads, and where)
        self._reads = (names, tuple(n for n in names if n.startswith("load_")
                                    or n.split("_")[0] in ("xi", "eta", "phi")))
        for u in self.units:
            if any(u.slots[n][0] is not self.real for n in names):
                raise TypeError("the FMU's inputs are Real variables")
            u.reads = np.array([u.slots[n][1] for n in names], dtype=np.intp)
        self.settings = ps.contact
        if ps.modes.contact_model == "table":
            table = self._table(ps.modes, ps.contact)  # no memory: one for all wheelsets
            for u in self.units:
                u.contact = table
            self.close()  # (the workers of an earlier initialisation)
            self.built = built
            return
        g = ps.geometry  # profile_unit: the String or its enumeration
        made: dict[tuple[str, str], Track | Wheelset] = {}  # each profile read once
        per_side = {"track": [], "wheelset": []}
        for side in V.SIDES:  # a side's own profile where it is given, else the common one
            for kind, of in (("wheel", "wheelset"), ("rail", "track")):
                name = f"{kind}_profile_{side}" if self[f"{kind}_profile_{side}"] \
                    else f"{kind}_profile"
                key = (kind, self[name])
                if key not in made:
                    profile = self._profile(name, kind, g.profile_unit)
                    try:
                        made[key] = (Track(profile, g.inclination, g.gauge, g.gauge_depth)
                                     if kind == "rail" else
                                     Wheelset(profile, g.wheel_radius, g.back_to_back,
                                              g.flange_back))
                    except RailContactError as exc:
                        raise RailContactError(f"parameter {name}: {exc}") from None
                per_side[of].append(made[key])
        tracks, wheelsets = per_side["track"], per_side["wheelset"]
        track = tracks[0] if tracks[0] is tracks[1] else tuple(tracks)
        ws = wheelsets[0] if wheelsets[0] is wheelsets[1] else tuple(wheelsets)
        pair = ps.material.elastic_pair()
        self.workers = _workers(len(self.units)) if len(self.units) > 1 else None
        if self.workers is not None and self.workers[0] == "processes":
            self._here = _steps_here()
            self._descriptions = [WheelsetDescription(track, ws, pair, ps.contact,
                                                      convention=ps.modes.convention)
                                  for _ in self.units]
            self._start_pool(self.workers[1])
        if self.workers is None or self.workers[0] == "threads":
            self.close()  # (the workers of an earlier initialisation)
            for u in self.units:
                u.contact = WheelsetContact(track, ws, pair, ps.contact,
                                            convention=ps.modes.convention)
        self.built = built

    def _start_pool(self, processes: int) -> None:
        """The worker processes of the wheelsets (:attr:`_descriptions`): those of an
        earlier initialisation with the wheelsets built anew, or new ones; threads instead
        (:attr:`workers`, a message in the log) when no Python interpreter is found to
        start them with (:func:`~railcontact.timestep.pool.worker_python`) or they do not
        start (a wheelset that cannot be built is an error, as on threads)."""
        pool = self._pool
        if pool is not None and pool.alive and pool.processes == processes and \
                pool.here == self._here:
            pool.reset(self._descriptions)
            return
        self.close()
        python = worker_python()
        why = None
        if python is None:
            why = (f"no Python {sys.version.split()[0]} interpreter found to start them with "
                   f"(sys.executable = {sys.executable!r}, environment {sys.prefix!r})")
        else:
            try:
                self._pool = self._new_pool(self._descriptions, processes, python)
            except RailContactError as exc:
                if not isinstance(exc.__cause__, (EOFError, OSError)):
                    raise  # (the worker's own error building a wheelset)
                why = f"they did not start with {python}: {exc}"
            except (OSError, RuntimeError) as exc:
                why = f"they did not start with {python}: {type(exc).__name__}: {exc}"
        if why is not None:
            self.workers = ("threads", min(len(self.units), _threads()))
            self._fell_back = True  # (initialisation says so with fmi2Warning)
            self.log.append(f"the wheelsets are stepped on {self.workers[1]} threads, not in "
                            f"worker processes: {why}; set {WORKERS_ENV}=threads to choose "
                            "threads")

    def _new_pool(self, descriptions: list[WheelsetDescription], processes: int,
                  python: str | None = None) -> WheelsetPool:
        """``processes`` processes stepping ``descriptions``' wheelsets, this one among
        them when :attr:`_here` (:func:`_steps_here`), the others worker processes (their
        results reduced to :class:`~railcontact.fmu.outputs.StepOutputs`, as here;
        without the host's main module: the workers need the package only, and a host
        script is not run again in them)."""
        return WheelsetPool(descriptions, processes, reduce=step_outputs,
                            python=python or worker_python(), main=False,
                            timeout=_worker_timeout(), here=self._here)

    def _table(self, modes: FMUModes, contact: ContactSettings):
        """The contact table of ``table_file`` (looked up in the resources first, like a
        profile) as the step's contact (:class:`railcontact.table.TableContact`), with the
        limits of validity of ``contact`` (max_y_q, max_penetration, max_wheel_load)."""
        if modes.control != "load" or modes.load_definition != "total":
            raise RailContactError(
                "contact_model = table: a contact table is built by the total vertical wheel "
                f"load; set control = load and load_definition = total (got control = "
                f"{modes.control}, load_definition = {modes.load_definition})")
        if modes.convention != "railcontact":
            raise RailContactError(
                "contact_model = table reads and writes railcontact's frames only (the table "
                "has no CONTACT conversion); set convention = railcontact (got convention = "
                f"{modes.convention})")
        value = modes.table_file
        if not value:
            raise RailContactError("contact_model = table needs the parameter table_file "
                                   "(a store of railcontact table build)")
        path = self.resources / value
        try:
            table = TableContact.open(path if path.exists() else value, settings=contact)
        except RailContactError as exc:
            raise RailContactError(f"parameter table_file = {value!r}: {exc}") from None
        except Exception as exc:  # a folder that is no Zarr store, a damaged store
            raise RailContactError(f"parameter table_file = {value!r}: not a contact table "
                                   f"({type(exc).__name__}: {exc})") from None
        mu = table.table.axes.get("friction")  # the parameter: a wheel's input <= 0
        if mu is not None and table.table.out_of_range.get("friction") != "clamp" and \
                not mu[0] <= contact.friction <= mu[-1]:
            raise RailContactError(
                f"parameter friction = {contact.friction:g} is outside the friction axis "
                f"[{mu[0]:g}, {mu[-1]:g}] of table_file = {value!r}: it is the coefficient of "
                "friction of a wheel whose input friction_left/right is <= 0; set it within "
                "the axis")
        return table

    def _show_choices(self, values: dict) -> None:
        """Each String parameter with an enumeration (``<name>_choice``) and the
        enumeration set to the word the solver was built with (:func:`~railcontact.fmu.
        variables.resolve_choices` of the parameter ``values``): a host reads back the
        setting in force whichever of the two it set."""
        resolved = V.resolve_choices(values)
        for v in V.CHOICES:
            base = v.name.removesuffix(V.CHOICE_SUFFIX)
            word = resolved.get(base)
            if word in v.items:  # (the settings took it: one of them)
                self[base] = word
                self[v.name] = v.items.index(word) + 1

    def _exit_initialization(self) -> int:
        self._fell_back = False
        try:
            self._build()
        except RailContactError as exc:
            self.log.append(str(exc))
            return FMI_ERROR
        status = self._do_step()  # the outputs at the start values of the inputs
        # (initialisation has no Discard: inputs it cannot solve are a warning, its message
        # logged, the outputs and statuses saying so; threads instead of worker processes
        # are a warning)
        if status == FMI_DISCARD or (status == FMI_OK and self._fell_back):
            return FMI_WARNING
        return status

    def _inputs(self, u: _Wheelset) -> dict[str, float]:
        """The inputs of wheelset ``u`` its step reads (:func:`_read_inputs` of the modes)
        [SI units]; a :class:`RailContactError` naming each one not finite, and each load
        or direct creepage beyond its range (:data:`~railcontact.fmu.variables.LOAD_LIMITS`,
        :data:`~railcontact.fmu.variables.CREEPAGE_LIMITS`)."""
        names, limited = self._reads
        values = dict(zip(names, self.real[u.reads].tolist(), strict=True))
        bad = [f"{n} = {x}" for n, x in values.items() if not math.isfinite(x)]
        if bad:
            raise RailContactError("inputs not finite: " + ", ".join(bad))
        for n in limited:
            x = values[n]
            if n.startswith("load_") and not V.LOAD_LIMITS[0] <= x <= V.LOAD_LIMITS[1]:
                bad.append(f"{n} = {x:g} N: a wheel load must be within "
                           f"{V.LOAD_LIMITS[0]:g} to {V.LOAD_LIMITS[1]:g} N (0 lifts the "
                           f"wheel)")
            elif n.split("_")[0] in ("xi", "eta", "phi") and not abs(x) <= \
                    V.CREEPAGE_LIMITS[1]:
                bad.append(f"{n} = {x:g} {'1/m' if n.startswith('phi') else ''}: "
                           f"{_CREEPAGE_RANGE}")
        if bad:
            raise RailContactError("inputs out of range: " + "; ".join(bad))
        return values

    @staticmethod
    def _discard(u: _Wheelset) -> None:
        """Every output of wheelset ``u`` zero, its status and each wheel's out of range:
        what a discarded step shows (nothing solved)."""
        _write(u, None)
        for name in ("status", "status_left", "status_right"):
            u[name] = OUT_OF_RANGE

    def _discarded(self, u: _Wheelset, message: str) -> int:
        u.log.append(message)
        self._discard(u)
        return FMI_DISCARD

    def _communication_step(self) -> int:
        """fmi2DoStep: the step at the communication point (``control``: time [s], step
        size [s]); fmi2Error, nothing done, for a time not finite or a step size not
        above zero."""
        t, h = float(self.control[0]), float(self.control[1])
        if not (math.isfinite(t) and math.isfinite(h) and h > 0.0):
            self.log.append(f"doStep at currentCommunicationPoint = {t} s with "
                            f"communicationStepSize = {h} s: the time must be finite and "
                            f"the step size above 0 s; nothing was done (the outputs are "
                            f"the last step's)")
            return FMI_ERROR
        return self._do_step()

    def _discard_all(self) -> None:
        """Every wheelset's step discarded (:meth:`_discard`), and the outputs about all of
        them saying so."""
        for u in self.units:
            self._discard(u)
        if self.wheelsets is not None:
            self["status"], self["solve_time"] = OUT_OF_RANGE, 0.0

    def _do_step(self) -> int:
        """Solve the step of the inputs: each wheelset's, when there are several (in BEM
        mode) in the worker processes (:meth:`_pool_step`) or on the threads
        (:meth:`_step` on each) of :attr:`workers`; the FMI status the worst of theirs,
        each wheelset's messages named by its number."""
        if not self.initialised:
            self.log.append("doStep before initialization")
            return FMI_ERROR
        if self.wheelsets is None:
            return self._step(self.units[0])
        t0 = time.perf_counter()
        if self._pool is not None:
            statuses = self._pool_step()
        elif self.workers is not None:
            if not self._threads:  # as many threads as cores (_threads); each wheelset on its
                self._threads = [  # thread step after step (its FFT plans and search
                    ThreadPoolExecutor(1, f"railcontact-{self.instance_name}-{j}")  # memory
                    for j in range(self.workers[1])]  # stay with it)
            n = len(self._threads)
            running = [t.submit(self._step_group, self.units[j::n])
                       for j, t in enumerate(self._threads)]
            by_thread = [r.result() for r in running]
            statuses = [by_thread[k % n][k // n] for k in range(len(self.units))]
        else:
            statuses = [self._guarded_step(u) for u in self.units]
        for u in self.units:
            self.log.extend(f"wheelset {u.k}: {line}" for line in u.log)
            u.log.clear()
        self["status"] = Status.worst(u["status"] for u in self.units)
        self["solve_time"] = time.perf_counter() - t0
        return max(statuses)

    def _pool_step(self) -> list[int]:
        """The FMI statuses of the wheelsets' steps in the worker processes: each
        wheelset's inputs read and checked here (:meth:`_prepare`), solved in its process,
        its :class:`~railcontact.fmu.outputs.StepOutputs` written here (:meth:`_finish`);
        an error in a wheelset's solve discards its step as on a thread. A worker process
        that ended discards every wheelset's step with fmi2Error (its wheelsets' memories
        are lost; fmi2SetFMUstate starts new workers)."""
        prepared = [self._guard_unit(u, self._prepare, u) for u in self.units]
        try:
            outs = self._pool.step([p if isinstance(p, dict) else None
                                    for p in prepared], errors="return")
        except RailContactError as exc:
            self._discard_all()
            self.log.append(f"doStep: the wheelsets' worker processes: {exc}")
            return [FMI_ERROR] * len(self.units)
        statuses = []
        for u, p, out in zip(self.units, prepared, outs, strict=True):
            if not isinstance(p, dict):  # discarded before solving
                statuses.append(p)
            elif isinstance(out, RailContactError) and not isinstance(out, RemoteError):
                statuses.append(self._discarded(u, f"input out of range: {out}"))
            elif isinstance(out, BaseException):
                u.log.append(f"doStep: {type(out).__name__}: {out}\n"
                             + "\n".join(getattr(out, "__notes__", [])))
                self._discard(u)
                statuses.append(FMI_DISCARD)
            else:
                statuses.append(self._guard_unit(u, self._finish, u, out))
        return statuses

    def _guard_unit(self, u: _Wheelset, fn, *args):
        """``fn(*args)``; an unexpected error discards wheelset ``u``'s step (fmi2Discard)
        with the traceback in its messages."""
        try:
            return fn(*args)
        except Exception as exc:  # never let an exception reach the simulator
            u.log.append(f"doStep: {type(exc).__name__}: {exc}\n{traceback.format_exc()}")
            self._discard(u)
            return FMI_DISCARD

    def _step_group(self, units: list[_Wheelset]) -> list[int]:
        """The steps of ``units`` one after the other (one thread's share)."""
        return [self._guarded_step(u) for u in units]

    def _guarded_step(self, u: _Wheelset) -> int:
        """:meth:`_step` of wheelset ``u``; an unexpected error discards its step (nothing
        of it is to be trusted) with the traceback in its messages."""
        return self._guard_unit(u, self._step, u)

    def _step(self, u: _Wheelset) -> int:
        """Solve wheelset ``u``'s step of its inputs here (:meth:`_prepare`, the solve,
        :meth:`_finish`). fmi2Discard when nothing could be solved for a wheel in contact
        (the outputs and statuses say what was: a wheel not solved has zero forces and its
        own status 3 or 1, the wheelset's status 3 or 1; an input not finite or beyond its
        range zeroes every output, each status 3); fmi2Warning for a wheel not ok but
        solved; fmi2OK otherwise."""
        kw = self._prepare(u)
        if not isinstance(kw, dict):
            return kw
        try:
            res = u.contact.solve(**kw)
        except RailContactError as exc:
            return self._discarded(u, f"input out of range: {exc}")
        return self._finish(u, step_outputs(res))

    def _prepare(self, u: _Wheelset) -> dict | int:
        """Wheelset ``u``'s step from its inputs: the keyword arguments of its solve
        (:meth:`WheelsetContact.solve <railcontact.timestep.WheelsetContact.solve>`) from
        the inputs read [SI units]; or fmi2Discard, its step discarded (an input not finite
        or beyond its range, or a solve that cannot be set up)."""
        penetration = self.modes.control == "penetration"
        kinematic = self.modes.creepage_input == "kinematic"
        try:
            x = self._inputs(u)
        except RailContactError as exc:
            return self._discarded(u, str(exc))
        try:
            kw: dict = {"pose": Pose(x["lateral_displacement"], x["yaw"], x.get("roll", 0.0)),
                        "time": float(self.control[0])}
            if penetration:
                kw["vertical"] = x["vertical_displacement"]
            else:
                kw["loads"] = (x["load_left"], x["load_right"])
            if kinematic:
                spin = x["spin_speed"]
                kw["kinematics"] = Kinematics(x["speed"], x["lateral_velocity"], x["yaw_rate"],
                                              spin if spin > 0 else None, x["curvature"])
            else:
                kw["creepages"] = tuple(tuple(x[f"{c}_{s}"] for c in ("xi", "eta", "phi"))
                                        for s in V.SIDES)
            rails = tuple(RailDeviation((x[f"rail_offset_lateral_{s}"],
                                         x[f"rail_offset_vertical_{s}"]), x[f"rail_roll_{s}"])
                          for s in V.SIDES)
            if any(r != NO_DEVIATION for r in rails):
                kw["rails"] = rails
            mu = tuple(x[f"friction_{s}"] for s in V.SIDES)
            for s, m in zip(V.SIDES, mu, strict=True):
                if m > V.MAX_MU:
                    raise RailContactError(f"friction_{s} = {m:g} is above {V.MAX_MU:g} "
                                           "(<= 0: the parameter friction)")
            if any(m > 0 for m in mu):  # (<= 0: the parameter's)
                kw["friction"] = tuple(m if m > 0 else self.settings.friction for m in mu)
        except RailContactError as exc:
            return self._discarded(u, f"input out of range: {exc}")
        return kw

    def _finish(self, u: _Wheelset, out: StepOutputs) -> int:
        """Write wheelset ``u``'s outputs of its solved step ``out`` and check them (a
        creepage beyond the range that the kinematic inputs give is the wheel's own
        status, out of range, from the solve); its FMI status (:meth:`_step`)."""
        _write(u, out)  # (the rigid wheelset: a stage of the solve when asked for)
        speed = float(u["speed"])  # the frictional power: per unit speed times V
        self.real[u.power] *= speed if math.isfinite(speed) and speed > 0 else 0.0
        unfound = out.rigid is not None and not out.rigid[0]
        if unfound:  # not found: said (the result's status, the output, counts it)
            u.log.append(f"wheelset: {STATUS_NAMES[NOT_CONVERGED]}: {out.rigid[1]}")
        if not np.all(np.isfinite(self.real[u.real_outputs])):  # (inputs may be NaN)
            return self._discarded(u, "non-finite result; outputs set to zero")
        failed = [w for w in out.wheels if w.status in (NOT_CONVERGED, OUT_OF_RANGE,
                                                        OUTSIDE_VALIDITY)]
        logged = set()
        for w in failed:  # each wheel has its own status; the other is still solved
            name = STATUS_NAMES[w.status]  # (a message may name its status already)
            whole = w.message.startswith(f"wheelset {name}")  # (both wheels': said once)
            text = (w.message if whole or w.message.startswith(name)
                    else f"{name}: {w.message}")
            if text not in logged:
                logged.add(text)
                u.log.append(text if whole else f"{w.side} wheel: {text}")
        if any(_unsolved(w) for w in out.wheels):  # zero forces are no contact's only
            return FMI_DISCARD
        return FMI_WARNING if failed or unfound else FMI_OK


THREADS_ENV = "RAILCONTACT_FMU_THREADS"
"""The environment variable that sets the number of threads the wheelsets of an FMU of
several wheelsets are stepped on (default: the cores, :func:`_cores`)."""
WORKERS_ENV = "RAILCONTACT_FMU_WORKERS"
"""The environment variable that chooses how the wheelsets of an FMU of several wheelsets
are stepped: ``processes``, ``threads`` or a number of worker processes (:func:`_workers`)."""


TIMEOUT_ENV = "RAILCONTACT_FMU_WORKER_TIMEOUT"
"""The environment variable that limits the wait for a worker process's step [s]."""


def _worker_timeout() -> float | None:
    """The longest wait [s] for a worker process's answer (a step, a memory read or set),
    ``$RAILCONTACT_FMU_WORKER_TIMEOUT``; None (no limit) when unset. A worker that takes
    longer is taken as hung: the step is fmi2Error, as for a worker that ended.

    Raises
    ------
    RailContactError
        A value that is no number above 0.
    """
    given = os.environ.get(TIMEOUT_ENV, "").strip()
    if not given:
        return None
    try:
        seconds = float(given)
    except ValueError:
        seconds = math.nan
    if not (math.isfinite(seconds) and seconds > 0):
        raise RailContactError(f"{TIMEOUT_ENV} = {given!r}: the longest wait for a worker "
                               "process's step, a number of seconds above 0")
    return seconds


def _workers(wheelsets: int) -> tuple[str, int]:
    """How an FMU's ``wheelsets`` (at least 2) are stepped: ``("processes", P)``, in P
    processes (this one and P - 1 worker processes, or P worker processes:
    :func:`_steps_here`), or ``("threads", T)``, on T threads of this process (P, T at
    most ``wheelsets``).

    ``$RAILCONTACT_FMU_WORKERS``: ``processes`` (P the cores, :func:`_cores`, this one
    among them), a positive integer P (worker processes), or ``threads`` (T
    :func:`_threads`). Unset: threads when
    ``$RAILCONTACT_FMU_THREADS`` is set or the process has one core, else processes.

    Raises
    ------
    RailContactError
        Another value.
    """
    given = os.environ.get(WORKERS_ENV, "").strip().lower()
    if given == "threads" or (not given and (os.environ.get(THREADS_ENV, "").strip()
                                             or _cores() < 2)):
        return "threads", min(wheelsets, _threads())
    if given in ("", "processes"):
        return "processes", min(wheelsets, _cores())
    try:
        n = int(given)
    except ValueError:
        n = 0
    if n < 1:
        raise RailContactError(f"{WORKERS_ENV} = {os.environ[WORKERS_ENV]!r}: the wheelsets "
                               "are stepped in worker processes (processes, or their number, "
                               "a positive integer) or on threads (threads)")
    return "processes", min(wheelsets, n)


def _steps_here() -> bool:
    """Whether this process steps a share of the wheelsets itself when they are stepped
    in processes (:func:`_workers`): with ``$RAILCONTACT_FMU_WORKERS`` unset or
    ``processes`` the P processes are this one and P - 1 worker processes (no round trip
    for its share, no process more than cores); a number P is P worker processes, this
    one only reading the inputs and writing the outputs."""
    return os.environ.get(WORKERS_ENV, "").strip().lower() in ("", "processes")


def _threads() -> int:
    """The threads of a multi-wheelset step: ``$RAILCONTACT_FMU_THREADS`` (a positive
    integer), else the cores this process may run on."""
    given = os.environ.get(THREADS_ENV, "").strip()
    if given:
        try:
            n = int(given)
        except ValueError:
            n = 0
        if n >= 1:
            return n
    return _cores()


def _cores() -> int:
    """The cores this process may run on (the threads that can overlap)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def _read_inputs(modes: FMUModes) -> tuple[str, ...]:
    """The inputs a wheelset's step reads under ``modes`` (by the one-wheelset FMU's
    names): only those the modes use, so that a NaN elsewhere is no concern of ours."""
    names = ["lateral_displacement", "yaw"]
    names += (["vertical_displacement", "roll"] if modes.control == "penetration"
              else ["load_left", "load_right"])
    names += (["speed", "lateral_velocity", "yaw_rate", "spin_speed", "curvature"]
              if modes.creepage_input == "kinematic"
              else [f"{c}_{s}" for s in V.SIDES for c in ("xi", "eta", "phi")])
    names += [f"{q}_{s}" for s in V.SIDES for q in ("rail_offset_lateral",
                                                      "rail_offset_vertical", "rail_roll",
                                                      "friction")]
    return tuple(names)


def _write(u: _Wheelset, out: StepOutputs | None) -> None:
    """Wheelset ``u``'s outputs from ``out``; all zero (and no patches) for None."""
    if out is None:
        for buffer, vrs in u.zeroed:
            buffer[vrs] = 0
        return
    for (buffer, vrs), values in zip(u.zeroed, (out.real, out.integer), strict=True):
        buffer[vrs] = values


_CREEPAGE_RANGE = (f"creepages must be within {V.CREEPAGE_LIMITS[0]:g} to "
                   f"{V.CREEPAGE_LIMITS[1]:g} (xi, eta [-]; phi [1/m]), as a case file's")


def _unsolved(wheel: WheelOutcome) -> bool:
    """Whether ``wheel`` has no solution though it should carry load: out of range, or a
    load loop that found none (zero forces, status not converged, no patches)."""
    return wheel.status == OUT_OF_RANGE or (wheel.status == NOT_CONVERGED
                                            and not wheel.patches)


def _differences(mine: dict, other: dict, names: tuple[str, str] = ("variables", "header"),
                 most: int = 4) -> str:
    """The parameters in which ``mine`` and ``other`` differ (their ``_choice``
    enumerations resolved), as ``name = a (names[0]), b (names[1])``; "" when none."""
    try:
        a, b = V.resolve_choices(mine), V.resolve_choices(other)
    except RailContactError as exc:
        return str(exc)
    keys = sorted(a.keys() | b.keys())
    diff = [f"{k} = {a.get(k)!r} in {names[0]}, {b.get(k)!r} in {names[1]}" for k in keys
            if a.get(k) != b.get(k)]
    more = f", and {len(diff) - most} more" if len(diff) > most else ""
    return "; ".join(diff[:most]) + more


def _identity(resources: Path) -> tuple[str, str]:
    """(GUID, model identifier) of the FMU whose ``resources`` folder this is, from its
    modelDescription.xml beside it; ("", "") without one (the kernels' warm-up runs the
    slave before the FMU is zipped)."""
    try:
        text = (resources.parent / "modelDescription.xml").read_text(encoding="utf-8")
    except OSError:
        return "", ""
    guid = re.search(r'\sguid="([^"]*)"', text)
    model = re.search(r'\smodelIdentifier="([^"]*)"', text)
    return (guid.group(1) if guid else "", model.group(1) if model else "")


def make_slave(resources: str, instance_name: str) -> Slave:
    return Slave(resources, instance_name)


WARM_RUNS = (
    ({}, [{"lateral_displacement": y, "xi_left": 1e-3, "eta_left": -5e-4, "phi_left": 0.3,
           "xi_right": 1e-3, "eta_right": -5e-4, "phi_right": -0.3}
          for y in (0.0, 1e-3, 1.5e-3, 3e-3, 7e-3, -7e-3, 0.0)]),
    ({"creepage_input": "kinematic"},
     [{"lateral_displacement": y, "yaw": 1e-3 * y / 4e-3, "lateral_velocity": v,
       "yaw_rate": -v / 2, "speed": 30.0} for y, v in ((4e-3, 0.0), (3.9e-3, -0.02),
                                                       (3.6e-3, -0.05), (-2e-3, 0.05))]),
)
"""What :func:`warm` runs: (parameters, the inputs of each step) of a few instances, the
default settings with direct creepages, then kinematic creepages (as ``railcontact demo``);
tread and flange contact, cold and warm-started steps."""


def warm(resources: str) -> tuple[int, int, float]:
    """Run every kernel a default step uses, so that numba compiles them into its cache
    (or loads them from it): the steps of :data:`WARM_RUNS`, each instance initialised
    (its first, cold solve) and stepped by 1 ms.

    Parameters
    ----------
    resources
        The FMU's resources folder.

    Returns
    -------
    compiled, loaded, seconds
        Kernel compilations (numba's cache misses), kernels loaded from the cache, and the
        wall time [s] of the runs.

    Raises
    ------
    RailContactError
        A step failed (FMI status Error or Discard); the message is the slave's log.
    """
    from . import _kernelcache

    t0 = time.perf_counter()
    for parameters, steps in WARM_RUNS:
        s = Slave(resources, "warm", wheelsets=None)  # (the kernels of any FMU)
        for name, value in parameters.items():
            s[name] = value
        if s.exit_initialization() not in (FMI_OK, FMI_WARNING):
            raise RailContactError(f"warming the kernels: initialisation failed: {s.pop_log()}")
        for k, inputs in enumerate(steps):
            for name, value in inputs.items():
                s[name] = value
            s.control[:] = (k * 1e-3, 1e-3, k * 1e-3)
            if s.do_step() not in (FMI_OK, FMI_WARNING):
                raise RailContactError(f"warming the kernels: step {k} failed: {s.pop_log()}")
    compiled, loaded = _kernelcache.kernel_counts()
    return compiled, loaded, time.perf_counter() - t0


__all__ = ["Slave", "make_slave", "warm"]
