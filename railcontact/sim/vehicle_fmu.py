"""The vehicle's contact through railcontact FMUs driven by fmpy
(:class:`~railcontact.sim.vehicle_contact.VehicleContact`).

An FMU of N wheelsets (``railcontact fmu build --wheelsets N``: the one-wheelset FMU's
inputs and outputs with the wheelset's number appended, ``lateral_displacement_2``,
``normal_force_left_2``, an Integer parameter ``wheelsets``) is one instance stepped once
per vehicle step; a one-wheelset FMU is one instance per wheelset, stepped one after the
other. The inputs are those of :mod:`railcontact.sim.cosim` (``creepage_input =
kinematic``, wheel loads given); the wheel forces are read from the outputs of the same
names as :class:`~railcontact.sim.vehicle_contact.InProcessContact` fills. A run stops
as it does with that contact (a wheelset status in
:data:`~railcontact.sim.vehicle_contact.STOPPING`), and on a step the FMU discards.
"""

from __future__ import annotations

import shutil
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..errors import RailContactError
from ..status import Status
from .cosim import INPUTS, _Instance
from .vehicle_contact import STOPPING, WheelForces, WheelsetStates

SIDES = ("left", "right")


class FMUContact:
    """Wheel forces of ``count`` wheelsets from a railcontact FMU.

    Parameters
    ----------
    fmu
        A railcontact FMU of ``count`` wheelsets, or of one (then ``count`` instances).
    count
        Number of wheelsets of the vehicle.
    step
        The communication step h [s] given to ``doStep``.
    parameters
        FMU parameters (``creepage_input`` is set to "kinematic").
    """

    def __init__(self, fmu: str | Path, count: int, step: float,
                 parameters: Mapping[str, float | str] | None = None) -> None:
        from fmpy import extract
        from fmpy.model_description import read_model_description

        md = read_model_description(str(fmu))
        params = {**(parameters or {}), "creepage_input": "kinematic"}
        starts = {v.name: v.start for v in md.modelVariables}
        self.step = step
        self.count = count
        self._unzipdir = extract(str(fmu))
        self.instances: list[tuple[_Instance, list[str]]] = []
        try:
            if "wheelsets" in starts:
                n = int(starts["wheelsets"])
                if n != count:
                    raise RailContactError(f"the FMU has {n} wheelsets, the vehicle {count}")
                suffixes = [f"_{k + 1}" for k in range(n)]
                names = tuple(f"{name}{s}" for s in suffixes for name in INPUTS)
                self.instances.append((_Instance(self._unzipdir, md, "vehicle", params, names),
                                       suffixes))
            else:
                for k in range(count):
                    self.instances.append((_Instance(self._unzipdir, md, f"wheelset{k + 1}",
                                                     params), [""]))
        except BaseException:
            self.close()
            raise

    def __call__(self, states: WheelsetStates) -> WheelForces:
        n = states.count
        if n != self.count:
            raise RailContactError(f"{self.count} wheelsets expected, got {n}")
        gen = np.zeros((n, 3))
        lat, vert, nor, yq = (np.zeros((n, 2)) for _ in range(4))
        status, secs, its = np.zeros(n, dtype=int), np.zeros(n), np.zeros(n)
        bad: list[str] = []
        k = 0
        for inst, suffixes in self.instances:
            inputs = []
            for j in range(len(suffixes)):
                i = k + j
                inputs += [states.lateral[i], states.yaw[i], states.lateral_velocity[i],
                           states.yaw_rate[i], states.speed, states.spin_speed[i],
                           states.loads[i, 0], states.loads[i, 1]]
            out = inst.step(states.time, self.step, [float(x) for x in inputs])
            named = len(bad)
            for s in suffixes:
                status[k] = int(out[f"status{s}"])
                if status[k] in STOPPING:
                    discard = " (the FMU discarded the step)" if inst.discarded else ""
                    bad.append(f"wheelset {k + 1}: {Status(int(status[k])).label}{discard}")
                gen[k] = (out[f"force_lateral{s}"], out[f"yaw_moment{s}"],
                          -sum(out[f"rolling_radius_{side}{s}"]
                               * out[f"force_longitudinal_{side}{s}"] for side in SIDES))
                for w, side in enumerate(SIDES):
                    lat[k, w] = out[f"force_lateral_{side}{s}"]
                    vert[k, w] = out[f"force_vertical_{side}{s}"]
                    nor[k, w] = out[f"normal_force_{side}{s}"]
                    yq[k, w] = out[f"derailment_quotient_{side}{s}"]
                secs[k] = out[f"solve_time{s}"]
                its[k] = out[f"normal_iterations{s}"] + out[f"tangential_iterations{s}"]
                k += 1
            if inst.discarded and len(bad) == named:  # discarded, no wheelset's status says why
                bad += [f"wheelset {k - len(suffixes) + j + 1}: the FMU discarded the step"
                        for j in range(len(suffixes))]
        return WheelForces(gen, lat, vert, nor, yq, status, secs, not bad,
                           "; ".join(bad) or "ok", its)

    def close(self) -> None:
        """Terminate and free the instances; remove the unpacked FMU."""
        for inst, _ in self.instances:
            try:
                inst.close()
            except Exception:  # noqa: BLE001 - closing the others must go on
                pass
        self.instances = []
        shutil.rmtree(self._unzipdir, ignore_errors=True)


__all__ = ["FMUContact"]
