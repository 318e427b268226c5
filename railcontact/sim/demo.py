"""``railcontact demo``: a wheelset running on tangent track, its wheel-rail forces coming
from the railcontact FMU through fmpy every communication step.

The FMU is built (``dist/RailContact.fmu``) when it is missing or stale. The wheelset
(:mod:`railcontact.sim.dynamics`: lateral, yaw and spin degrees of freedom, primary suspension
to a frame moving at constant speed, 83.3 kN per wheel, S1002 on 60E1 at 1:40) starts from
a lateral offset; :mod:`railcontact.sim.cosim` integrates it. A second FMU instance with
``warm_start = none`` gets the same inputs every few steps, so the cold-start iterations are
measured on exactly the same states. The summary gives the speed, the wavelength beside
Klingel's (equivalent conicity from railcontact's own geometry at the simulated
amplitude), peak forces, iterations and time per step; two figures show the motion, forces
and iterations, and the contact patches at a few instants (re-solved in-process with the
same settings, to draw the pressure and the slip area).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import RailContactError, check_count, check_positive
from ..fmu import DEFAULT_OUTPUT, ensure_fmu
from ..fmu.variables import parameter_settings
from ..io.plotting import _pyplot
from ..settings import ContactSettings
from .cosim import CoSimResult, Run, print_progress, simulate
from .dynamics import WheelsetModel, measure_wavelength

MM, KN = 1e3, 1e-3
QUICK = {"duration": 0.6, "step": 2e-3, "element_size": 0.8e-3}
STARTUP = 0.05
"""The start-up transient [s] the summary's peaks leave out: the wheelset starts off centre
at rest laterally, spinning for pure rolling on the centred radius, so its first steps see
the rolling-radius difference as a longitudinal creepage (|F_x| near its saturation) until
the spin and the yaw adjust (about 10 ms at 30 m/s)."""
SOLVE_TIME_CLIP = 4.0
"""The solve-time panel's scale: this many times the 99th percentile of the steps after
:data:`STARTUP`; slower steps (the first solves, a kernel compiled on first use) are drawn
at the top edge and labelled with their time."""


@dataclass
class DemoOptions:
    """What ``railcontact demo`` runs (SI units; None = the default, or ``--quick``'s)."""

    speed: float = 30.0
    duration: float | None = None
    step: float | None = None
    initial_lateral: float = 4e-3
    wheel_profile: str = "S1002"
    rail_profile: str = "60E1"
    profile_unit: str = "mm"
    element_size: float | None = None
    warm_start: str = "previous+estimate"
    free: bool = False
    cold_every: int = 10
    quick: bool = False
    fmu: str = DEFAULT_OUTPUT
    output_dir: str = "railcontact_demo"
    plots: bool = True

    def resolved(self) -> dict[str, Any]:
        """duration, step, element_size with the defaults (or ``--quick``) filled in."""
        base = QUICK if self.quick else {"duration": 1.5, "step": 1e-3,
                                         "element_size": ContactSettings().element_size}
        out = {k: getattr(self, k) if getattr(self, k) is not None else v
               for k, v in base.items()}
        check_positive("speed", self.speed, "m/s")
        check_count("cold_every", self.cold_every, 0)
        for k, v in out.items():
            check_positive(k, v, "s" if k != "element_size" else "m")
        # the solver flags are FMU parameters: checked here, before the FMU is built
        parameter_settings({"element_size": out["element_size"], "warm_start": self.warm_start,
                            "profile_unit": self.profile_unit})
        return out


@dataclass
class DemoResult:
    """The co-simulation, its summary numbers and the files written."""

    sim: CoSimResult
    summary: dict[str, float]
    text: str
    built: bool
    files: list[Path] = field(default_factory=list)


def _profile_files(opts: DemoOptions) -> tuple[list[Path], dict[str, str]]:
    """Profile files to pack into the FMU, and the FMU parameters that name them."""
    files, params = [], {}
    for key, value in (("wheel_profile", opts.wheel_profile),
                       ("rail_profile", opts.rail_profile)):
        p = Path(value)
        if p.is_file():
            files.append(p.resolve())
            params[key] = p.name
        elif p.suffix or p.parent != Path("."):
            raise RailContactError(f"{key}: file {value!r} not found")
        else:
            params[key] = value  # a built-in profile name
    params["profile_unit"] = opts.profile_unit
    return files, params


def run_demo(opts: DemoOptions, progress: bool = True) -> DemoResult:
    """Build the FMU if needed, run the co-simulation, summarise and plot."""
    cfg = opts.resolved()
    files, params = _profile_files(opts)
    fmu, built = ensure_fmu(opts.fmu, files, log=_note if progress else None)
    params.update(creepage_input="kinematic", warm_start=opts.warm_start,
                  element_size=cfg["element_size"])
    shadows = {"cold": ({"warm_start": "none"}, opts.cold_every)} if opts.cold_every else {}
    model = WheelsetModel.free() if opts.free else WheelsetModel()
    run = Run(speed=opts.speed, duration=cfg["duration"], step=cfg["step"],
              initial_lateral=opts.initial_lateral, model=model, parameters=params,
              shadows=shadows)
    sim = simulate(fmu, run, print_progress if progress else None)
    if len(sim.time) == 0:
        raise RailContactError(f"the co-simulation did not run: {sim.message}")
    summary = summarise(sim)
    text = describe(sim, summary, opts, built)
    result = DemoResult(sim, summary, text, built)
    if opts.plots:
        out = Path(opts.output_dir)
        result.files.append(plot_motion(sim, out / "demo_motion.png"))
        result.files.append(plot_patches(sim, out / "demo_patches.png"))
    return result


def _note(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def after_startup(sim: CoSimResult) -> np.ndarray:
    """Which steps come after the start-up transient (t >= :data:`STARTUP`); all of them
    when the run is no longer than the transient."""
    keep = sim.time >= STARTUP - 1e-12
    return keep if keep.any() else np.ones_like(keep)


def summarise(sim: CoSimResult) -> dict[str, float]:
    """Numbers of the summary (SI units). The peaks are those after the start-up transient
    (``peak_from``: the first time [s] they cover, see :data:`STARTUP`); ``startup_creep_
    force_x`` is the transient's own peak |F_x| [N]."""
    from ..geometry.conicity import equivalent_conicity, klingel_wavelength

    o = sim.outputs
    w = measure_wavelength(sim.distance, sim.lateral)
    k = after_startup(sim)

    def peak(*names: str) -> float:
        return float(max(np.abs(o[n][k]).max() for n in names))

    fx = ("creep_force_x_left", "creep_force_x_right")
    s: dict[str, float] = {
        "speed": sim.run.speed, "steps": float(len(sim.time)),
        "wavelength": w.wavelength, "amplitude": w.amplitude,
        "frequency": sim.run.speed / w.wavelength if w.wavelength > 0 else math.nan,
        "radius": sim.radius, "half_distance": sim.half_distance,
        "peak_from": float(sim.time[k][0]),
        "peak_lateral": float(np.max(np.abs(sim.lateral[k]))),
        "peak_yaw": float(np.max(np.abs(sim.yaw[k]))),
        "peak_force_lateral": peak("force_lateral"),
        "peak_yaw_moment": peak("yaw_moment"),
        "peak_normal_force": peak("normal_force_left", "normal_force_right"),
        "peak_creep_force_x": peak(*fx),
        "peak_creep_force_y": peak("creep_force_y_left", "creep_force_y_right"),
        "startup_creep_force_x": float(max(np.abs(o[n][~k]).max() if (~k).any() else 0.0
                                           for n in fx)),
        "normal_iterations": float(o["normal_iterations"][1:].mean()) if len(sim.time) > 1
        else float(o["normal_iterations"][0]),
        "tangential_iterations": float(o["tangential_iterations"][1:].mean())
        if len(sim.time) > 1 else float(o["tangential_iterations"][0]),
        "time_per_step": float(np.median(sim.wall_time)),
        "solve_time": float(np.median(o["solve_time"])),
        "first_solve_time": float(o["solve_time"][0]),
        **{f"startup_{key}": value for key, value in sim.startup.items()},
    }
    cold = sim.shadows.get("cold")
    if cold is not None and len(cold["step"]) > 1:
        s["cold_normal_iterations"] = float(cold["normal_iterations"][1:].mean())
        s["cold_tangential_iterations"] = float(cold["tangential_iterations"][1:].mean())
        s["cold_solve_time"] = float(np.median(cold["solve_time"][1:]))
        k = cold["step"][1:]
        s["warm_normal_iterations_sampled"] = float(o["normal_iterations"][k].mean())
        s["warm_tangential_iterations_sampled"] = float(o["tangential_iterations"][k].mean())
    if math.isfinite(w.amplitude) and w.amplitude > 1e-5:
        lam = equivalent_conicity(sim.track, sim.wheelset, w.amplitude)
        s["conicity"] = lam
        s["klingel_wavelength"] = klingel_wavelength(sim.radius, sim.half_distance, lam)
    return s


def describe(sim: CoSimResult, s: dict[str, float], opts: DemoOptions, built: bool) -> str:
    """The summary as text."""
    run, m = sim.run, sim.run.model
    p = {**run.parameters}
    lines = [
        f"railcontact demo: one wheelset, {p.get('wheel_profile')} on {p.get('rail_profile')} "
        f"at 1:40, V = {run.speed:g} m/s ({run.speed * 3.6:.0f} km/h), {run.duration:g} s in "
        f"{run.steps} steps of {run.step * 1e3:g} ms, element size "
        f"{float(p['element_size']) * MM:g} mm",
        f"FMU {sim.fmu} ({'built now' if built else 'up to date'}), driven by fmpy",
        f"wheelset: m = {m.mass:g} kg, Iz = {m.yaw_inertia:g} kg m2, Iy = {m.spin_inertia:g} "
        f"kg m2, k_y = {m.lateral_stiffness / 1e6:g} MN/m, k_psi = {m.yaw_stiffness / 1e6:g} "
        f"MN m/rad{' (free wheelset)' if opts.free else ''}; {run.load * KN:g} kN per wheel; "
        f"start y = {run.initial_lateral * MM:g} mm",
    ]
    if not sim.completed:
        lines.append(f"NOTE: {sim.message}")
    if math.isfinite(s["wavelength"]):
        kl = (f"; Klingel (kinematic): {s['klingel_wavelength']:.2f} m with equivalent "
              f"conicity {s['conicity']:.3f} at {s['amplitude'] * MM:.2f} mm, r0 = "
              f"{s['radius'] * MM:.1f} mm, e = {s['half_distance'] * MM:.1f} mm"
              if "klingel_wavelength" in s else "")
        lines.append(f"motion: wavelength {s['wavelength']:.2f} m ({s['frequency']:.2f} Hz), "
                     f"mean amplitude {s['amplitude'] * MM:.2f} mm{kl}")
    else:
        lines.append("motion: fewer than three zero crossings of y - no wavelength "
                     "(run longer or start further off centre)")
    if s["peak_from"] > 0:
        window = (f"peaks after the start-up transient (t = {s['peak_from']:.3f}-"
                  f"{sim.time[-1]:.3f} s; in the first {STARTUP * 1e3:g} ms, while the "
                  f"spin adjusts to the off-centre start, |F_x| reaches "
                  f"{s['startup_creep_force_x'] * KN:.2f} kN)")
    else:
        window = (f"peaks over the whole run (t = 0-{sim.time[-1]:.3f} s, within the "
                  "start-up transient)")
    lines.append(f"{window}: |y| {s['peak_lateral'] * MM:.2f} mm, |yaw| "
                 f"{s['peak_yaw'] * MM:.2f} mrad, |F_Y| {s['peak_force_lateral'] * KN:.2f} kN, "
                 f"|M_Z| {s['peak_yaw_moment'] * KN:.2f} kN m, normal force "
                 f"{s['peak_normal_force'] * KN:.1f} kN, creep force |F_x| "
                 f"{s['peak_creep_force_x'] * KN:.2f} kN, |F_y| "
                 f"{s['peak_creep_force_y'] * KN:.2f} kN")
    lines.append(f"solver ({opts.warm_start}): {s['normal_iterations']:.2f} normal + "
                 f"{s['tangential_iterations']:.2f} tangential iterations per step (both "
                 f"wheels, the rigid wheelset's solves included), "
                 f"{s['solve_time'] * 1e3:.1f} ms solve, "
                 f"{s['time_per_step'] * 1e3:.1f} ms per step through fmpy (medians)")
    if "startup_instantiate" in s:
        lines.append(f"FMU start-up (unpacked afresh): instantiate "
                     f"{s['startup_instantiate']:.2f} s, initialisation (the first, cold "
                     f"solve) {s['startup_initialise']:.2f} s, first step's solve "
                     f"{s['first_solve_time'] * 1e3:.0f} ms")
    if "cold_normal_iterations" in s:
        cold = s["cold_normal_iterations"] + s["cold_tangential_iterations"]
        warm = s["warm_normal_iterations_sampled"] + s["warm_tangential_iterations_sampled"]
        lines.append(f"cold start (warm_start none, same states, every {opts.cold_every}th "
                     f"step): {s['cold_normal_iterations']:.2f} normal + "
                     f"{s['cold_tangential_iterations']:.2f} tangential, "
                     f"{s['cold_solve_time'] * 1e3:.1f} ms solve; warm start needs "
                     f"{cold / warm:.1f}x fewer iterations")
    return "\n".join(lines)


def plot_motion(sim: CoSimResult, path: Path) -> Path:
    """Lateral displacement and yaw, creep forces, and iterations (warm vs cold) against
    the distance travelled."""
    plt = _pyplot()
    o, d = sim.outputs, sim.distance
    fig, ax = plt.subplots(4, 1, figsize=(9, 11), sharex=True, constrained_layout=True)
    ax[0].plot(d, sim.lateral * MM, label="lateral displacement y [mm]")
    ax[0].plot(d, sim.yaw * MM, label="yaw [mrad]")
    ax[0].set_ylabel("y [mm], yaw [mrad]")
    ax[0].legend(fontsize=8)
    for side, style in (("left", "-"), ("right", "--")):
        ax[1].plot(d, o[f"creep_force_x_{side}"] * KN, "C0" + style, label=f"$F_x$ {side}")
        ax[1].plot(d, o[f"creep_force_y_{side}"] * KN, "C1" + style, label=f"$F_y$ {side}")
    ax[1].plot(d, o["force_lateral"] * KN, "k", lw=1.2, label="total lateral force $F_Y$")
    ax[1].set_ylabel("force [kN]")
    ax[1].set_title("creep forces (contact frame, on the wheel) and the total lateral force",
                    fontsize=9)
    ax[1].legend(fontsize=7, ncol=3)
    ax[2].plot(d, o["normal_iterations"], "C0", lw=0.8, label="normal, warm")
    ax[2].plot(d, o["tangential_iterations"], "C1", lw=0.8, label="tangential, warm")
    cold = sim.shadows.get("cold")
    if cold is not None and len(cold["step"]):
        k = cold["step"]
        ax[2].plot(d[k], cold["normal_iterations"], "C0o", ms=3, label="normal, cold")
        ax[2].plot(d[k], cold["tangential_iterations"], "C1o", ms=3,
                   label="tangential, cold")
    ax[2].set_ylabel("iterations per step")
    ax[2].set_title(f"both wheels; warm = {sim.run.parameters.get('warm_start')}", fontsize=9)
    ax[2].legend(fontsize=7, ncol=2)
    _plot_solve_time(ax[3], sim)
    ax[3].set_xlabel("distance [m]")
    start = sim.run.speed * STARTUP
    for a in ax:
        a.grid(alpha=0.3)
        if d[-1] > start:
            a.axvspan(d[0], start, color="0.85", zorder=0)
    if d[-1] > start:
        ax[1].annotate(f"start-up ({STARTUP * 1e3:g} ms)", (start, 1.0), xycoords=("data",
                       "axes fraction"), xytext=(3, -3), textcoords="offset points",
                       va="top", fontsize=7, color="0.4")
    fig.suptitle(f"wheelset co-simulation, V = {sim.run.speed:g} m/s, "
                 f"step {sim.run.step * 1e3:g} ms", fontsize=10)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _plot_solve_time(ax, sim: CoSimResult) -> None:
    """Solve time per step, warm and cold, on the scale of the steps after the start-up
    (:data:`SOLVE_TIME_CLIP`): slower steps are drawn at the top edge, labelled."""
    o, d = sim.outputs, sim.distance
    cold = sim.shadows.get("cold")
    series = [("warm", d, o["solve_time"], "C2", "-")]
    if cold is not None and len(cold["step"]):
        series.append(("cold", d[cold["step"]], cold["solve_time"], "C3", "o"))
    k = after_startup(sim)
    typical = np.concatenate([o["solve_time"][k]] + (
        [cold["solve_time"][k[cold["step"]]]] if len(series) > 1 else []))
    top = SOLVE_TIME_CLIP * float(np.percentile(typical, 99)) * 1e3
    above = []
    for label, x, t, colour, style in series:
        ms = t * 1e3
        if style == "-":
            ax.plot(x, np.minimum(ms, top), colour, lw=0.8, label=label)
        else:
            ax.plot(x, np.minimum(ms, top), colour + style, ms=3, label=label)
        for j in np.flatnonzero(ms > top):
            above.append((x[j], ms[j], colour))
    for x, ms, colour in above:
        ax.plot(x, top, "^", color=colour, ms=6, clip_on=False)
        ax.annotate(f"{ms:.0f} ms", (x, top), xytext=(4, -10), textcoords="offset points",
                    fontsize=7, color=colour)
    ax.set_ylim(0, top * 1.05)
    ax.set_ylabel("solve time per step [ms]")
    title = "FMU's solve time per step"
    if above:
        title += (f"; {len(above)} slower step{'s' if len(above) > 1 else ''} (first solves, "
                  "kernels compiled or loaded on first use) at the top edge, with their time")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)


def snapshot_instants(sim: CoSimResult, count: int = 3) -> list[int]:
    """Steps to draw: the start, the first zero crossing of y, the first opposite peak
    (or evenly spaced ones when the motion has no such points)."""
    y = sim.lateral
    n = len(y)
    ks = [0]
    cross = np.flatnonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)
    if len(cross):
        ks.append(int(cross[0]) + 1)
        after = y[cross[0] + 1:]
        stop = np.flatnonzero(np.sign(after[:-1]) * np.sign(after[1:]) < 0)
        end = int(stop[0]) + 1 if len(stop) else len(after)
        ks.append(int(cross[0]) + 1 + int(np.argmax(np.abs(after[:end]))))
    ks += [int(k) for k in np.linspace(0, n - 1, count)]
    return sorted(dict.fromkeys(ks))[:count]


def plot_patches(sim: CoSimResult, path: Path, count: int = 3) -> Path:
    """Pressure and slip area of both wheels at a few instants. The states are re-solved
    in-process (WheelsetContact with the FMU's settings, cold), the patch drawn over the
    rail profile coordinate."""
    from matplotlib.colors import ListedColormap

    from ..geometry.track import Pose
    from ..timestep import Kinematics

    plt = _pyplot()
    contact = sim.contact_model()
    ks = snapshot_instants(sim, count)
    fig, axes = plt.subplots(2, len(ks), figsize=(4.2 * len(ks), 7.5), squeeze=False,
                             constrained_layout=True)
    pmax = 1.0
    solved = []
    for k in ks:
        q, v = sim.position[k], sim.velocity[k]
        res = contact.solve(Pose(q[0], q[1]), loads=(sim.run.load, sim.run.load),
                            kinematics=Kinematics(sim.run.speed, v[0], v[1], v[2]),
                            remember=False)
        solved.append(res)
        pmax = max(pmax, *(w.max_pressure for w in res.wheels))
    slip = ListedColormap(["none", "tab:orange"])
    im = None
    for col, (k, res) in enumerate(zip(ks, solved, strict=True)):
        for row, w in enumerate(res.wheels):
            ax = axes[row, col]
            for ps in w.patches:
                g, cp = ps.normal.grid, ps.geometry
                xe = np.linspace(g.bounds[0], g.bounds[1], g.nx + 1) * MM
                ye = (cp.rail_y + np.linspace(g.bounds[2], g.bounds[3], g.ny + 1)) * MM
                pm = np.ma.masked_where(~ps.normal.contact, ps.normal.pressure)
                im = ax.pcolormesh(xe, ye, pm.T * 1e-6, cmap="viridis", vmin=0,
                                   vmax=pmax * 1e-6, shading="flat")
                t = ps.tangential
                if t is not None and hasattr(t, "state"):
                    sl = np.ma.masked_where(t.state != 2, np.ones_like(t.state, float))
                    ax.pcolormesh(xe, ye, sl.T, cmap=slip, vmin=0, vmax=1, alpha=0.45,
                                  shading="flat")
            ax.set_title(f"{w.side}, t = {sim.time[k]:.3f} s, y = "
                         f"{sim.lateral[k] * MM:.2f} mm\nN = {w.normal_force * KN:.1f} kN, "
                         f"slip {w.slip_area_ratio:.0%}, {w.n_patches} patch"
                         f"{'es' if w.n_patches != 1 else ''}", fontsize=9)
            ax.set_xlabel("x (rolling) [mm]")
            ax.set_ylabel("rail profile coordinate [mm]")
            ax.set_aspect("equal", adjustable="datalim")
            ax.grid(alpha=0.3)
    if im is not None:
        fig.colorbar(im, ax=axes, label="pressure [MPa] (orange: slip area)", shrink=0.7)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
