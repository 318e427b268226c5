"""Co-simulation of one wheelset with the railcontact FMU, driven through fmpy.

Python integrates the wheelset (:mod:`railcontact.sim.dynamics`); every communication step the
FMU gets the wheelset's lateral displacement, yaw, their rates and the speed (creepages
``kinematic``, wheel loads given) and returns the forces of the rails. Optional *shadow*
instances of the same FMU with other parameters (e.g. ``warm_start = none`` for the cold
start, or tight tolerances for a reference) receive the same inputs every k-th step and
only record their outputs: they see exactly the states of the main run, so iterations and
forces are compared step for step.

The interface Jacobian ``d(F_y, M_z, T_y)/d(dy/dt, dpsi/dt, Omega)`` for the implicit step
is measured by finite differences through the main FMU every ``jacobian_interval`` seconds:
save the FMU state, three perturbed steps, restore (``fmi2GetFMUstate``/
``fmi2SetFMUstate``). The axle torque is ``T_y = -(r_l F_X,l + r_r F_X,r)`` from the FMU's
per-wheel longitudinal forces and rolling radii.
"""

from __future__ import annotations

import shutil
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import RailContactError, check_count, check_finite, check_positive
from ..status import Status
from .dynamics import WheelsetModel, implicit_step

STATUS_OUT_OF_RANGE = Status.OUT_OF_RANGE
FMI_DISCARD = 2
INPUTS = ("lateral_displacement", "yaw", "lateral_velocity", "yaw_rate", "speed",
          "spin_speed", "load_left", "load_right")
JACOBIAN_PERTURBATION = 1e-4
"""Velocity perturbation for the Jacobian, as a creepage: d(dy/dt) = 1e-4 V,
d(dpsi/dt) = 1e-4 V / e and dOmega = 1e-4 V / r0 (about 2 kN of creep force change, far
above the solver noise, small enough for the linear creep range)."""


@dataclass(frozen=True)
class Run:
    """What to simulate (SI units).

    Attributes
    ----------
    speed
        Forward speed V [m/s].
    duration
        Simulated time [s].
    step
        Communication (and integration) step h [s].
    initial_lateral, initial_yaw
        Initial displacement [m] and yaw [rad]; the wheelset starts at rest laterally.
    load
        Vertical load per wheel [N].
    spin_speed
        Initial angular speed about the axle [rad/s]; 0 means V / r0 with r0 the rolling
        radius of the centred wheelset (pure rolling in the centre).
    model
        Mass, inertia and suspension.
    parameters
        FMU parameters (names as in the FMU: wheel_profile, warm_start, element_size, ...).
    shadows
        Name -> (FMU parameters overriding ``parameters``, every k-th step).
    jacobian_interval
        Time between Jacobian updates [s].
    """

    speed: float = 30.0
    duration: float = 1.5
    step: float = 1e-3
    initial_lateral: float = 4e-3
    initial_yaw: float = 0.0
    load: float = 83.3e3
    spin_speed: float = 0.0
    model: WheelsetModel = field(default_factory=WheelsetModel)
    parameters: Mapping[str, float | str] = field(default_factory=dict)
    shadows: Mapping[str, tuple[Mapping[str, float | str], int]] = field(default_factory=dict)
    jacobian_interval: float = 0.05

    def __post_init__(self) -> None:
        check_positive("speed", self.speed, "m/s")
        check_positive("duration", self.duration, "s")
        check_positive("step", self.step, "s")
        if self.step > self.duration:
            raise RailContactError(f"step [s] must not exceed duration, got step "
                                   f"{self.step:g} > duration {self.duration:g}")
        if self.step > 0.05:
            raise RailContactError(f"step [s] must be at most 0.05, got {self.step:g}")
        check_finite("initial_lateral", self.initial_lateral, "m")
        check_finite("initial_yaw", self.initial_yaw, "rad")
        check_positive("load", self.load, "N")
        check_positive("spin_speed", self.spin_speed, "rad/s", allow_zero=True)
        check_positive("jacobian_interval", self.jacobian_interval, "s")
        for name, (_, every) in self.shadows.items():
            check_count(f"shadows[{name!r}] step interval", every)

    @property
    def steps(self) -> int:
        """Number of communication steps."""
        return max(1, int(round(self.duration / self.step)))


@dataclass
class CoSimResult:
    """A co-simulation's history (arrays over the steps that were run).

    Attributes
    ----------
    time
        t at the start of each step [s].
    distance
        V t [m].
    position, velocity
        (y, psi, theta) [m, rad, rad] and their rates (dy/dt, dpsi/dt, Omega) at t,
        shape (n, 3).
    outputs
        The main FMU's outputs at each step (every Real and Integer output by name).
    wall_time
        Wall time of each step's set + doStep + get [s].
    shadows
        Name -> {"step": indices into the main history, output name -> values}.
    jacobians
        Time [s] and matrix of each Jacobian update.
    completed
        Whether every step ran; if not, ``message`` says why.
    run, fmu
        What was run, with which FMU.
    radius, half_distance
        r0 and e of the centred wheelset [m] (from the FMU's profiles).
    parameters
        All FMU parameters of the main instance (start values and ``run.parameters``).
    track, wheelset
        The geometry the FMU was given.
    startup
        The main instance's start-up [s]: ``instantiate`` (the FMU's Python start-up and
        imports) and ``initialise`` (initialisation, which makes the first solve; with the
        kernels not yet compiled in this environment, their compilation).
    """

    time: np.ndarray
    distance: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    outputs: dict[str, np.ndarray]
    wall_time: np.ndarray
    shadows: dict[str, dict[str, np.ndarray]]
    jacobians: list[tuple[float, np.ndarray]]
    completed: bool
    message: str
    run: Run
    fmu: Path
    radius: float = 0.0
    half_distance: float = 0.0
    parameters: dict[str, Any] = field(default_factory=dict)
    track: Any = None
    wheelset: Any = None
    startup: dict[str, float] = field(default_factory=dict)

    @property
    def lateral(self) -> np.ndarray:
        """y [m]."""
        return self.position[:, 0]

    @property
    def yaw(self) -> np.ndarray:
        """psi [rad]."""
        return self.position[:, 1]

    def contact_model(self, warm_start: str = "none"):
        """An in-process :class:`~railcontact.timestep.WheelsetContact` with the FMU's
        geometry and settings (e.g. to look at the patches of a recorded state)."""
        from ..fmu.variables import parameter_settings
        from ..timestep import WheelsetContact

        ps = parameter_settings(self.parameters)
        return WheelsetContact(self.track, self.wheelset, ps.material.elastic_pair(),
                               replace(ps.contact, warm_start=warm_start))


class _Instance:
    """One FMU2Slave with named Real/Integer access; ``inputs`` names the Real inputs
    :meth:`step` sets, in its order."""

    def __init__(self, unzipdir: str, md, name: str,
                 parameters: Mapping[str, float | str],
                 inputs: tuple[str, ...] = INPUTS) -> None:
        from fmpy.fmi2 import FMU2Slave

        self.vars = {v.name: v for v in md.modelVariables}
        unknown = sorted(set(parameters) - {n for n, v in self.vars.items()
                                            if v.causality == "parameter"})
        if unknown:
            raise RailContactError(f"unknown FMU parameter(s): {', '.join(unknown)}")
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                             modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName=name)
        t0 = time.perf_counter()
        self.fmu.instantiate()
        t1 = time.perf_counter()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for k, value in parameters.items():
            v = self.vars[k]
            if v.type == "String":
                self.fmu.setString([v.valueReference], [str(value)])
            elif v.type == "Real":
                self.fmu.setReal([v.valueReference], [float(value)])
            else:
                self.fmu.setInteger([v.valueReference], [int(value)])
        self.fmu.exitInitializationMode()
        self.startup = {"instantiate": t1 - t0, "initialise": time.perf_counter() - t1}
        self.inputs = [self.vars[n].valueReference for n in inputs]
        self.real_out = [n for n, v in self.vars.items()
                         if v.causality == "output" and v.type == "Real"]
        self.int_out = [n for n, v in self.vars.items()
                        if v.causality == "output" and v.type == "Integer"]
        self._real_vr = [self.vars[n].valueReference for n in self.real_out]
        self._int_vr = [self.vars[n].valueReference for n in self.int_out]
        self.discarded = False

    def step(self, t: float, h: float, inputs: list[float]) -> dict[str, float]:
        """One communication step; its outputs by name. A step the FMU discards
        (fmi2Discard: a state beyond the model) sets :attr:`discarded` and returns the
        outputs, whose statuses say why; fmi2Error raises."""
        from fmpy.fmi1 import FMICallException

        self.fmu.setReal(self.inputs, inputs)
        try:
            self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            self.discarded = False
        except FMICallException as exc:
            if exc.status != FMI_DISCARD:
                raise
            self.discarded = True
        out = dict(zip(self.real_out, self.fmu.getReal(self._real_vr), strict=True))
        out.update(zip(self.int_out, self.fmu.getInteger(self._int_vr), strict=True))
        return out

    def close(self) -> None:
        try:
            self.fmu.terminate()
        finally:
            self.fmu.freeInstance()


def generalized_force(out: Mapping[str, float]) -> np.ndarray:
    """(F_y [N], M_z [N m], T_y [N m]) of the rails on the wheelset from the FMU outputs;
    ``T_y = -(r_l F_X,l + r_r F_X,r)`` is the moment about the axle."""
    torque = -(out["rolling_radius_left"] * out["force_longitudinal_left"]
               + out["rolling_radius_right"] * out["force_longitudinal_right"])
    return np.array([out["force_lateral"], out["yaw_moment"], torque])


def _jacobian(inst: _Instance, t: float, h: float, inputs: list[float],
              base: np.ndarray, speed: float, radius: float,
              half_distance: float) -> np.ndarray | None:
    """Finite-difference Jacobian at the state just solved; None if a perturbed state was
    rejected by the FMU."""
    state = inst.fmu.getFMUState()
    try:
        jac = np.zeros((3, 3))
        steps = (speed, speed / half_distance, speed / radius)
        for j, (slot, dv) in enumerate(zip((2, 3, 5), steps, strict=True)):
            dv *= JACOBIAN_PERTURBATION
            pert = list(inputs)
            pert[slot] += dv
            out = inst.step(t, h, pert)
            inst.fmu.setFMUState(state)
            if inst.discarded or out["status"] == STATUS_OUT_OF_RANGE:
                return None
            jac[:, j] = (generalized_force(out) - base) / dv
    finally:
        inst.fmu.freeFMUState(state)
    return jac


def simulate(fmu: str | Path, run: Run,
             progress: Callable[[int, int], None] | None = None) -> CoSimResult:
    """Run the wheelset co-simulation with the FMU at ``fmu``.

    Raises :class:`~railcontact.errors.RailContactError` for parameters or profiles that
    cannot be used, before any step; never for a failing step: the history up to it is
    returned with ``completed = False`` and the reason in ``message`` (a wheelset that
    climbs off the rail, an FMU error).

    Parameters
    ----------
    fmu
        A railcontact FMU (:func:`railcontact.fmu.ensure_fmu`).
    run
        What to simulate.
    progress
        Called as ``progress(step, steps)`` every 50 steps.
    """
    from fmpy import extract
    from fmpy.fmi1 import FMICallException
    from fmpy.model_description import read_model_description

    from ..geometry.conicity import centred_contact
    from ..geometry.profiles import read_profile
    from ..geometry.track import Track, Wheelset

    fmu = Path(fmu).resolve()
    md = read_model_description(str(fmu))
    unzipdir = extract(str(fmu))
    starts = {v.name: v.start for v in md.modelVariables if v.causality == "parameter"}
    params = {**starts, **run.parameters}
    res_dir = Path(unzipdir) / "resources"
    try:
        profiles = []
        for key, kind in (("wheel_profile", "wheel"), ("rail_profile", "rail")):
            name = str(params[key])
            f = res_dir / name
            profiles.append(read_profile(str(f) if f.is_file() else name, kind,
                                         str(params["profile_unit"])))
        track = Track(profiles[1], float(params["inclination"]), float(params["gauge"]))
        ws = Wheelset(profiles[0], float(params["wheel_radius"]),
                      float(params["flange_back_distance"]))
        centre = centred_contact(track, ws)
    except (RailContactError, ValueError, KeyError):
        shutil.rmtree(unzipdir, ignore_errors=True)
        raise

    n = run.steps
    h = run.step
    jac_every = max(1, int(round(run.jacobian_interval / h)))
    instances: dict[str, _Instance] = {}
    x = np.array([run.initial_lateral, run.initial_yaw, 0.0])
    v = np.array([0.0, 0.0, run.spin_speed or run.speed / centre.radius])
    rec_t, rec_x, rec_v, rec_wall, rows = [], [], [], [], []
    shadow_rows: dict[str, list] = {k: [] for k in run.shadows}
    jacobians: list[tuple[float, np.ndarray]] = []
    jac = np.zeros((3, 3))
    completed, message = True, "completed"
    try:
        instances["main"] = _Instance(unzipdir, md, "main", run.parameters)
        for name, (over, _) in run.shadows.items():
            instances[name] = _Instance(unzipdir, md, name, {**run.parameters, **over})
        main = instances["main"]
        for k in range(n):
            t = k * h
            inputs = [x[0], x[1], v[0], v[1], run.speed, v[2], run.load, run.load]
            t0 = time.perf_counter()
            out = main.step(t, h, inputs)
            wall = time.perf_counter() - t0
            if main.discarded or out["status"] == STATUS_OUT_OF_RANGE:
                completed = False
                message = (f"stopped at t = {t:.4f} s: the contact solver rejected the state "
                           f"(y = {x[0] * 1e3:.2f} mm, yaw = {x[1] * 1e3:.2f} mrad)")
                break
            for name, (_, every) in run.shadows.items():
                if k % every == 0:
                    shadow_rows[name].append((k, instances[name].step(t, h, inputs)))
            force = generalized_force(out)
            if k % jac_every == 0:
                new = _jacobian(main, t, h, inputs, force, run.speed, centre.radius,
                                centre.half_distance)
                if new is not None:
                    jac = new
                    jacobians.append((t, jac))
            rec_t.append(t)
            rec_x.append(x.copy())
            rec_v.append(v.copy())
            rec_wall.append(wall)
            rows.append(out)
            x, v = implicit_step(run.model, x, v, force, jac, h)
            if not (np.all(np.isfinite(x)) and np.all(np.isfinite(v))):
                completed, message = False, f"stopped at t = {t:.4f} s: non-finite state"
                break
            if progress is not None and k % 50 == 0:
                progress(k, n)
    except (FMICallException, RailContactError, np.linalg.LinAlgError) as exc:
        completed = False
        message = f"stopped at t = {len(rec_t) * h:.4f} s: {exc}"
    finally:
        for inst in instances.values():
            try:
                inst.close()
            except Exception:  # noqa: BLE001 - closing must not mask the result
                pass
        shutil.rmtree(unzipdir, ignore_errors=True)

    names = list(rows[0]) if rows else []
    outputs = {name: np.array([r[name] for r in rows]) for name in names}
    shadows = {}
    for name, recs in shadow_rows.items():
        recs = [(k, r) for k, r in recs if k < len(rows)]
        d = {"step": np.array([k for k, _ in recs], dtype=int)}
        for key in (recs[0][1] if recs else {}):
            d[key] = np.array([r[key] for _, r in recs])
        shadows[name] = d
    t_arr = np.array(rec_t)
    return CoSimResult(time=t_arr, distance=run.speed * t_arr,
                       position=np.array(rec_x).reshape(-1, 3),
                       velocity=np.array(rec_v).reshape(-1, 3), outputs=outputs,
                       wall_time=np.array(rec_wall), shadows=shadows, jacobians=jacobians,
                       completed=completed, message=message, run=run, fmu=fmu,
                       radius=centre.radius, half_distance=centre.half_distance,
                       parameters=params, track=track, wheelset=ws,
                       startup=dict(instances["main"].startup) if "main" in instances else {})


def print_progress(k: int, n: int) -> None:
    """A progress line on stderr."""
    print(f"\r  step {k:6d} / {n}", end="", file=sys.stderr, flush=True)
    if k + 50 >= n:
        print("\r" + " " * 30 + "\r", end="", file=sys.stderr, flush=True)


__all__ = ["CoSimResult", "Run", "print_progress", "simulate"]
