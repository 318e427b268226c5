"""The Python side of the railcontact FMU: one object per FMU instance.

The C shim (``railcontact_fmu.c``) owns nothing but pointers: it reads and writes the Real
and Integer variables directly in this object's numpy buffers (``buffers()``), and calls the
methods below, each of which returns an FMI status (0 OK, 1 Warning, 2 Discard, 3 Error)
and never raises; what went wrong is kept for ``pop_log()``.

This file is copied into the FMU as ``<package>/_fmu_slave.py`` next to a copy of the
railcontact package, hence the relative imports.
"""

from __future__ import annotations

import math
import pickle
import time
import traceback
from dataclasses import replace
from pathlib import Path

import numpy as np

from .errors import RailContactError
from .fmu import variables as V
from .geometry.profiles import read_profile
from .geometry.track import Pose, Track, Wheelset
from .settings import FMUModes
from .table import TableContact  # (xarray, zarr: imported when a table is opened)
from .timestep import Kinematics, WheelsetContact, WheelsetResult
from .timestep.rigid import RigidSolution
from .timestep.wheelset import (
    NOT_CONVERGED,
    OUT_OF_RANGE,
    OUTSIDE_VALIDITY,
    SEVERITY,
    STATUS_NAMES,
)

FMI_OK, FMI_WARNING, FMI_DISCARD, FMI_ERROR = 0, 1, 2, 3
OUTPUT, INPUT, PARAMETER = 0, 1, 2
_CAUSALITY = {"output": OUTPUT, "input": INPUT, "parameter": PARAMETER}


class Slave:
    """One FMU instance.

    Parameters
    ----------
    resources
        The FMU's resources folder (profile files are looked up there).
    instance_name
        For messages.
    """

    def __init__(self, resources: str, instance_name: str = "railcontact") -> None:
        self.resources = Path(resources)
        self.instance_name = instance_name
        self.variables = V.table()
        self.by_name = {v.name: v for v in self.variables}
        reals = [v for v in self.variables if v.type == "Real"]
        ints = [v for v in self.variables if v.type == "Integer"]
        strs = [v for v in self.variables if v.type == "String"]
        self.real = np.zeros(len(reals))
        self.integer = np.zeros(len(ints), dtype=np.int32)
        self.control = np.zeros(2)  # (current time, step size) written by the shim
        self.strings = [""] * len(strs)
        self.string_flags = bytes(_CAUSALITY[v.causality] for v in strs)
        self.real_flags = bytes(_CAUSALITY[v.causality] for v in reals)
        self.real_outputs = np.array([v.vr for v in reals if v.causality == "output"],
                                     dtype=int)
        self.integer_flags = bytes(_CAUSALITY[v.causality] for v in ints)
        # each variable's buffer (a stable object: states are restored in place) and slot
        buffer = {"Real": self.real, "Integer": self.integer, "String": self.strings}
        self._slots = {v.name: (buffer[v.type], v.vr) for v in self.variables}
        outputs = [v for v in self.variables if v.causality == "output"]
        self._zeroed = [(buffer[t], np.array([v.vr for v in outputs if v.type == t],
                                             dtype=int)) for t in ("Real", "Integer")]
        # the Real and the Integer outputs each written by one assignment of their values
        self._outputs = [(buffer[t], vrs, [v.value for v in outputs if v.type == t])
                         for t, (_, vrs) in zip(("Real", "Integer"), self._zeroed, strict=True)]
        assert all(v.type in ("Real", "Integer") for v in outputs)
        self.log: list[str] = []
        self.contact: WheelsetContact | None = None
        self.modes: FMUModes | None = None
        self._start_values()

    # -- plumbing for the shim ------------------------------------------------------------
    def buffers(self) -> tuple:
        """Addresses and sizes of the buffers and the causality flags, for the shim."""
        return (self.real.ctypes.data, len(self.real), self.integer.ctypes.data,
                len(self.integer), self.control.ctypes.data, self.real_flags,
                self.integer_flags, self.string_flags)

    def pop_log(self) -> str:
        """The messages since the last call, one per line."""
        text, self.log = "\n".join(self.log), []
        return text

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
        return self._guard("doStep", FMI_DISCARD, self._do_step)

    def reset(self) -> int:
        self._start_values()
        self.contact = None
        return FMI_OK

    def get_state(self) -> bytes:
        memory = None if self.contact is None else self.contact.memory
        return pickle.dumps((self.real.copy(), self.integer.copy(), list(self.strings),
                             self.control.copy(), memory), protocol=pickle.HIGHEST_PROTOCOL)

    def set_state(self, state: bytes) -> int:
        def restore():
            real, integer, strings, control, memory = pickle.loads(state)
            np.copyto(self.real, real)  # in place: the shim holds these buffers' addresses
            np.copyto(self.integer, integer)
            np.copyto(self.control, control)
            self.strings[:] = strings
            if memory is not None:
                if self.contact is None:
                    self._build()
                self.contact.memory = memory
            elif self.contact is not None:
                self.contact.reset()
            return FMI_OK
        return self._guard("setFMUstate", FMI_ERROR, restore)

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
        for v in V.PARAMETERS:
            if v.type == "Real" and not math.isfinite(self[v.name]):
                raise RailContactError(f"parameter {v.name} = {self[v.name]}: not finite")
        ps = V.parameter_settings({v.name: self[v.name] for v in V.PARAMETERS + V.CHOICES})
        self.modes = ps.modes
        if ps.modes.contact_model == "table":
            self.contact = self._table(ps.modes)
            return
        g = ps.geometry  # profile_unit: the String or its enumeration
        wheel = self._profile("wheel_profile", "wheel", g.profile_unit)
        rail = self._profile("rail_profile", "rail", g.profile_unit)
        try:
            track = Track(rail, g.inclination, g.gauge, g.gauge_depth)
            ws = Wheelset(wheel, g.wheel_radius, g.back_to_back, g.flange_back)
        except RailContactError as exc:
            raise RailContactError(f"parameter error: {exc}") from None
        self.contact = WheelsetContact(track, ws, ps.material.elastic_pair(), ps.contact,
                                       convention=ps.modes.convention)

    def _table(self, modes: FMUModes):
        """The contact table of ``table_file`` (looked up in the resources first, like a
        profile) as the step's contact (:class:`railcontact.table.TableContact`)."""
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
            return TableContact.open(path if path.exists() else value)
        except RailContactError as exc:
            raise RailContactError(f"parameter table_file = {value!r}: {exc}") from None
        except Exception as exc:  # a folder that is no Zarr store, a damaged store
            raise RailContactError(f"parameter table_file = {value!r}: not a contact table "
                                   f"({type(exc).__name__}: {exc})") from None

    def _exit_initialization(self) -> int:
        try:
            self._build()
        except RailContactError as exc:
            self.log.append(str(exc))
            return FMI_ERROR
        status = self._do_step()
        return FMI_OK if status == FMI_DISCARD else status

    def _inputs(self, names: list[str]) -> dict[str, float]:
        values = {n: float(self[n]) for n in names}
        bad = [f"{n} = {x}" for n, x in values.items() if not math.isfinite(x)]
        if bad:
            raise ValueError("inputs not finite: " + ", ".join(bad))
        return values

    def _do_step(self) -> int:
        if self.contact is None:
            self.log.append("doStep before initialization")
            return FMI_ERROR
        # only the inputs the modes use are read: a NaN elsewhere is no concern of ours
        names = ["lateral_displacement", "yaw"]
        penetration = self.modes.control == "penetration"
        names += ["vertical_displacement", "roll"] if penetration else ["load_left",
                                                                        "load_right"]
        kinematic = self.modes.creepage_input == "kinematic"
        names += (["speed", "lateral_velocity", "yaw_rate", "spin_speed"] if kinematic else
                  [f"{c}_{s}" for s in V.SIDES for c in ("xi", "eta", "phi")])
        try:
            x = self._inputs(names)
        except ValueError as exc:
            self.log.append(str(exc))
            self["status"] = OUT_OF_RANGE
            return FMI_DISCARD
        try:
            pose = Pose(x["lateral_displacement"], x["yaw"], x.get("roll", 0.0))
            kw: dict = {"time": float(self.control[0])}
            if penetration:
                kw["vertical"] = x["vertical_displacement"]
            else:
                kw["loads"] = (max(x["load_left"], 0.0), max(x["load_right"], 0.0))
            if kinematic:
                spin = x["spin_speed"]
                kw["kinematics"] = Kinematics(x["speed"], x["lateral_velocity"], x["yaw_rate"],
                                              spin if spin > 0 else None)
            else:
                kw["creepages"] = tuple(tuple(x[f"{c}_{s}"] for c in ("xi", "eta", "phi"))
                                        for s in V.SIDES)
            res = self.contact.solve(pose, **kw)
        except RailContactError as exc:
            self.log.append(f"input out of range: {exc}")
            self._write(None)
            self["status"] = OUT_OF_RANGE
            return FMI_WARNING
        t0 = time.perf_counter()  # the rigid wheelset's vertical and roll are found lazily
        if not penetration and self.modes.rigid_wheelset == "skip":  # not asked for
            res.rigid_solution = RigidSolution(0.0, 0.0, message="skipped")
        try:
            rigid = res.rigid_solution
        except RailContactError as exc:  # e.g. a wheel not solvable at another roll
            # the work before the error: the step's rolled solves are counted by an
            # approach_at made for this step (WheelsetContact.solve), so all of it is this
            # search's
            done = getattr(getattr(res.rigid, "approach_at", None), "work", None)
            rigid = res.rigid_solution = RigidSolution(
                0.0, 0.0, converged=False,
                message=f"rigid wheelset's vertical displacement and roll: {exc}",
                **({} if done is None else {"work": (replace(done["left"]),
                                                     replace(done["right"]))}))
        res.wall_time += time.perf_counter() - t0  # solve_time: all of the step's solving
        self._write(res)
        if not rigid.converged:  # not found: the wheelset's status says so
            self.log.append(f"wheelset: {STATUS_NAMES[NOT_CONVERGED]}: {rigid.message}")
            if SEVERITY.index(NOT_CONVERGED) > SEVERITY.index(int(self["status"])):
                self["status"] = NOT_CONVERGED
        if not np.all(np.isfinite(self.real[self.real_outputs])):  # (inputs may be NaN)
            self.log.append("non-finite result; outputs set to zero")
            self._write(None)
            self["status"] = OUT_OF_RANGE
            return FMI_DISCARD
        failed = [w for w in res.wheels if w.status in (NOT_CONVERGED, OUT_OF_RANGE,
                                                        OUTSIDE_VALIDITY)]
        for w in failed:  # each wheel has its own status; the other is still solved
            name = STATUS_NAMES[w.status]  # (a message may name its status already)
            text = w.message if w.message.startswith(name) else f"{name}: {w.message}"
            self.log.append(f"{w.side} wheel: {text}")
        return FMI_WARNING if failed or not rigid.converged else FMI_OK

    def _write(self, res: WheelsetResult | None) -> None:
        """Outputs from ``res``; all zero (and no patches) for None."""
        if res is None:
            for buffer, vrs in self._zeroed:
                buffer[vrs] = 0
            return
        for buffer, vrs, values in self._outputs:
            buffer[vrs] = [value(res) for value in values]


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
        s = Slave(resources, "warm")
        for name, value in parameters.items():
            s[name] = value
        if s.exit_initialization() not in (FMI_OK, FMI_WARNING):
            raise RailContactError(f"warming the kernels: initialisation failed: {s.pop_log()}")
        for k, inputs in enumerate(steps):
            for name, value in inputs.items():
                s[name] = value
            s.control[:] = (k * 1e-3, 1e-3)
            if s.do_step() not in (FMI_OK, FMI_WARNING):
                raise RailContactError(f"warming the kernels: step {k} failed: {s.pop_log()}")
    compiled, loaded = _kernelcache.kernel_counts()
    return compiled, loaded, time.perf_counter() - t0


__all__ = ["Slave", "make_slave", "warm"]
