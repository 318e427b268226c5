"""``railcontact demo --vehicle``: the bogie passenger vehicle
(:mod:`railcontact.sim.vehicle`, Manchester benchmark Vehicle 1) on tangent track, its
four wheelsets' contact solved by the exact BEM every step.

The four wheelsets start displaced laterally by the same amount, at rest laterally, the
frames and the car body centred; the vehicle runs at constant speed. The contact is
:class:`~railcontact.sim.vehicle_contact.InProcessContact` (four warm-started
``WheelsetContact`` s, one after the other); the integrator's contact Jacobian is
Kalker's at the nominal patches. The summary gives each wheelset's motion (peak, last
peak, growth rate and frequency), the wheel forces (lateral force, normal force, Y/Q
per wheel), the contact's time per vehicle step and the real-time factor (wall time over
simulated time: at most 1 is real time); a figure shows them against the distance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import RailContactError, check_positive
from ..geometry.profiles import read_profile
from ..geometry.track import Track, Wheelset
from ..io.plotting import _pyplot
from ..settings import ContactSettings
from ..settings.case import MaterialSettings
from .linear_contact import linear_contact
from .vehicle import (
    DOFS,
    VehicleResult,
    VehicleRun,
    measure_decay,
    simulate_vehicle,
    wheelset_dofs,
)
from .vehicle_contact import InProcessContact
from .vehicle_data import VehicleParameters

MM, KN = 1e3, 1e-3
QUICK = {"duration": 0.5, "step": 2e-3, "element_size": 1.5e-3}
DEFAULT = {"duration": 1.0, "step": 1e-3, "element_size": 1e-3}
SIDES = ("left", "right")
CONTACTS = ("fmu", "in-process")
VEHICLE_FMU = "dist/RailContact_4wheelsets.fmu"
"""Where ``railcontact demo --vehicle`` keeps its FMU of four wheelsets."""


@dataclass
class VehicleDemoOptions:
    """What ``railcontact demo --vehicle`` runs (SI units; None = the default, or
    ``--quick``'s)."""

    speed: float = 60.0
    duration: float | None = None
    step: float | None = None
    initial_lateral: float = 3e-3
    wheel_profile: str = "S1002"
    rail_profile: str = "60E1"
    profile_unit: str = "mm"
    element_size: float | None = None
    warm_start: str = "previous+estimate"
    quick: bool = False
    output_dir: str = "railcontact_demo"
    plots: bool = True
    contact: str = "fmu"
    """"fmu" (the FMU at :attr:`fmu` through fmpy) or "in-process" (four WheelsetContacts
    in this process)."""
    processes: int | None = None
    """``contact = "in-process"``: None, the four wheelsets one after the other in this
    process; N, stepped at the same time in N worker processes
    (:class:`~railcontact.timestep.pool.WheelsetPool`, the same forces)."""
    fmu: str = VEHICLE_FMU
    """The FMU of ``contact = "fmu"``: at :data:`VEHICLE_FMU` or a path that does not exist,
    one of four wheelsets built when missing or stale (one instance); another FMU that
    exists is used as it is, of four wheelsets or of one (one instance per wheelset)."""

    def resolved(self) -> dict[str, float]:
        base = QUICK if self.quick else DEFAULT
        out = {k: getattr(self, k) if getattr(self, k) is not None else v
               for k, v in base.items()}
        check_positive("speed", self.speed, "m/s")
        check_positive("initial_lateral", self.initial_lateral, "m")
        if self.contact not in CONTACTS:
            raise RailContactError(f"contact must be one of {', '.join(CONTACTS)}, got "
                                   f"{self.contact!r}")
        if self.processes is not None and (self.contact != "in-process"
                                           or self.processes < 1):
            raise RailContactError("processes must be at least 1 and needs contact = "
                                   f"'in-process', got {self.processes} with contact = "
                                   f"{self.contact!r}")
        for k, v in out.items():
            check_positive(k, v, "m" if k == "element_size" else "s")
        return out


@dataclass
class VehicleDemoResult:
    sim: VehicleResult
    summary: dict[str, Any]
    text: str
    files: list[Path] = field(default_factory=list)


def run_vehicle_demo(opts: VehicleDemoOptions, progress: bool = True) -> VehicleDemoResult:
    """Run the vehicle, summarise and plot."""
    from .cosim import print_progress

    cfg = opts.resolved()
    track = Track(read_profile(opts.rail_profile, "rail", opts.profile_unit))
    ws = Wheelset(read_profile(opts.wheel_profile, "wheel", opts.profile_unit))
    pair = MaterialSettings().elastic_pair()
    p = VehicleParameters()
    lin = linear_contact(track, ws, pair, p.wheel_load, opts.initial_lateral, samples=41)
    if opts.contact == "fmu":
        contact = _fmu_contact(opts, cfg, progress)
    else:
        settings = ContactSettings(element_size=cfg["element_size"],
                                   warm_start=opts.warm_start)
        contact = InProcessContact(track, ws, pair, settings, processes=opts.processes)
    q = np.zeros(DOFS)
    for i in range(4):
        q[wheelset_dofs(i)[0]] = opts.initial_lateral
    run = VehicleRun(opts.speed, cfg["duration"], cfg["step"], q, np.zeros(DOFS),
                     -lin.damping(opts.speed), lin.radius)
    try:
        sim = simulate_vehicle(p, contact, run, print_progress if progress else None)
    finally:
        if hasattr(contact, "close"):
            contact.close()
    if not sim.forces:
        raise RailContactError(f"the vehicle did not run: {sim.message}")
    summary = summarise(sim, lin)
    text = describe(sim, summary, opts, cfg)
    res = VehicleDemoResult(sim, summary, text)
    if opts.plots:
        res.files.append(plot_vehicle(sim, Path(opts.output_dir) / "demo_vehicle.png"))
    return res


def _fmu_contact(opts: VehicleDemoOptions, cfg: dict[str, float], progress: bool):
    """The FMU contact of ``--contact fmu`` (load control, kinematic creepages, no rigid
    wheelset search: as the in-process contact). The FMU at :attr:`~VehicleDemoOptions.fmu`:
    at :data:`VEHICLE_FMU`, or at a path that does not exist, one of four wheelsets built
    when missing or stale; an FMU the user names that exists is used as it is, of four
    wheelsets or one (then one instance per wheelset, :class:`~.vehicle_fmu.FMUContact`)."""
    from ..fmu import ensure_fmu
    from .demo import _note, _profile_files
    from .vehicle_fmu import FMUContact

    files, params = _profile_files(opts)
    if Path(opts.fmu) != Path(VEHICLE_FMU) and Path(opts.fmu).is_file():
        fmu = Path(opts.fmu).resolve()
    else:
        fmu, _ = ensure_fmu(opts.fmu, files, log=_note if progress else None, wheelsets=4)
    params.update(element_size=cfg["element_size"], warm_start=opts.warm_start,
                  rigid_wheelset="skip")
    return FMUContact(fmu, 4, cfg["step"], params)


def summarise(sim: VehicleResult, lin) -> dict[str, Any]:
    """Numbers of the summary (SI units)."""
    y = sim.wheelset_lateral()
    run = sim.run
    walls = sim.wall_time
    simulated = len(sim.forces) * run.step
    s: dict[str, Any] = {
        "speed": run.speed, "steps": len(sim.forces), "simulated": simulated,
        "conicity": lin.conicity, "amplitude": lin.amplitude,
        "contact_time_median": float(np.median(walls[:, 0])),
        "contact_time_mean": float(np.mean(walls[:, 0])),
        "contact_time_p99": float(np.percentile(walls[:, 0], 99)),
        "step_time_median": float(np.median(walls[:, 1])),
        "real_time_factor": float(walls[:, 1].sum() / simulated),
        "real_time_factor_warm": float(np.median(walls[:, 1]) / run.step),
        "iterations": float(np.mean(sim.stack("iterations")[1:])) if len(sim.forces) > 1
        else float(np.mean(sim.stack("iterations"))),
    }
    for i in range(4):
        d = measure_decay(sim.time, y[:, i], 0.0)
        s[f"wheelset{i + 1}"] = {"peak": float(np.max(np.abs(y[:, i]))), "last_peak": d.amplitude,
                                 "rate": d.rate, "frequency": d.frequency}
    lat, nor, yq = sim.stack("lateral"), sim.stack("normal"), sim.stack("derailment_quotient")
    s["peak_lateral_force"] = np.max(np.abs(lat), axis=0)  # (4, 2)
    s["normal_force_range"] = (np.min(nor, axis=0), np.max(nor, axis=0))
    s["peak_y_q"] = np.max(yq, axis=0)
    return s


def describe(sim: VehicleResult, s: dict[str, Any], opts: VehicleDemoOptions,
             cfg: dict[str, float]) -> str:
    run, p = sim.run, sim.parameters
    lines = [
        f"railcontact demo --vehicle: Manchester benchmark Vehicle 1 (car body, two bogies, "
        f"four wheelsets), {opts.wheel_profile} on {opts.rail_profile} at 1:40, V = "
        f"{run.speed:g} m/s ({run.speed * 3.6:.0f} km/h), {cfg['duration']:g} s in "
        f"{run.steps} steps of {run.step * 1e3:g} ms, element size "
        f"{cfg['element_size'] * MM:g} mm, {p.wheel_load * KN:.2f} kN per wheel",
        (f"contact: four in-process WheelsetContacts ({opts.warm_start}), one after the other"
         if opts.contact == "in-process" and opts.processes is None else
         f"contact: four WheelsetContacts ({opts.warm_start}) in {opts.processes} worker "
         f"processes, stepped at the same time"
         if opts.contact == "in-process" else
         f"contact: the FMU {opts.fmu} through fmpy ({opts.warm_start})")
        + f"; start: all wheelsets at y = {opts.initial_lateral * MM:g} mm (equivalent "
        f"conicity {s['conicity']:.3f} there)",
    ]
    if not sim.completed:
        lines.append(f"NOTE: {sim.message}")
    for i in range(4):
        w = s[f"wheelset{i + 1}"]
        rate = (f"growth rate {w['rate']:+.2f} 1/s at {w['frequency']:.2f} Hz"
                if math.isfinite(w["rate"]) else "fewer than three half-waves")
        lines.append(f"wheelset {i + 1}: peak |y| {w['peak'] * MM:.2f} mm, last peak "
                     f"{w['last_peak'] * MM:.2f} mm, {rate}")
    lat, (nmin, nmax), yq = s["peak_lateral_force"], s["normal_force_range"], s["peak_y_q"]
    lines.append("wheel forces (Y: rail on wheel along track Y; N: normal force; Q: the wheel "
                 "load, given):")
    for i in range(4):
        parts = [f"{side} |Y| {lat[i, k] * KN:.1f} kN, N {nmin[i, k] * KN:.1f}-"
                 f"{nmax[i, k] * KN:.1f} kN, Y/Q max {yq[i, k]:.3f}"
                 for k, side in enumerate(SIDES)]
        lines.append(f"wheelset {i + 1} wheels: " + "; ".join(parts))
    lines.append(
        f"time: contact {s['contact_time_median'] * 1e3:.1f} ms per vehicle step (median; "
        f"mean {s['contact_time_mean'] * 1e3:.1f}, 99th percentile "
        f"{s['contact_time_p99'] * 1e3:.1f}), {s['iterations']:.1f} BEM iterations per "
        f"wheelset step; real-time factor (wall / simulated time) "
        f"{s['real_time_factor']:.1f} over the run, {s['real_time_factor_warm']:.1f} for a "
        f"median step (1 or less is real time)")
    return "\n".join(lines)


def plot_vehicle(sim: VehicleResult, path: Path) -> Path:
    """Lateral motion of each wheelset, the lateral and normal wheel forces of the
    leading wheelset, Y/Q of every wheel and the time per step, against the distance."""
    plt = _pyplot()
    run = sim.run
    d = run.speed * sim.time
    df = d[:-1]
    y = sim.wheelset_lateral()
    lat, nor, yq = sim.stack("lateral"), sim.stack("normal"), sim.stack("derailment_quotient")
    fig, ax = plt.subplots(4, 1, figsize=(9, 11), sharex=True, constrained_layout=True)
    for i in range(4):
        ax[0].plot(d, y[:, i] * MM, label=f"wheelset {i + 1}")
    ax[0].set_ylabel("lateral displacement [mm]")
    ax[0].legend(fontsize=8, ncol=4)
    for k, (side, style) in enumerate(zip(SIDES, ("-", "--"), strict=True)):
        ax[1].plot(df, lat[:, 0, k] * KN, "C0" + style, label=f"Y {side}, wheelset 1")
        ax[1].plot(df, (nor[:, 0, k] - sim.parameters.wheel_load) * KN, "C1" + style,
                   label=f"N - Q {side}, wheelset 1")
    ax[1].set_ylabel("force [kN]")
    ax[1].legend(fontsize=7, ncol=2)
    for i in range(4):
        for k, style in enumerate(("-", "--")):
            ax[2].plot(df, yq[:, i, k], f"C{i}{style}", lw=0.8,
                       label=f"ws {i + 1} {SIDES[k]}")
    ax[2].set_ylabel("Y/Q [-]")
    ax[2].legend(fontsize=7, ncol=4)
    ax[3].plot(df, sim.wall_time[:, 0] * 1e3, "C2", lw=0.8, label="contact (4 wheelsets)")
    ax[3].axhline(run.step * 1e3, color="k", lw=0.8, ls=":", label="real time (the step)")
    ax[3].set_ylabel("wall time per step [ms]")
    ax[3].set_yscale("log")
    ax[3].legend(fontsize=8)
    ax[3].set_xlabel("distance [m]")
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(f"bogie vehicle, V = {run.speed:g} m/s, step {run.step * 1e3:g} ms",
                 fontsize=10)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


__all__ = ["VehicleDemoOptions", "VehicleDemoResult", "run_vehicle_demo"]
