"""Time-step warm-start study: what starting the BEM from the previous step buys.

The co-simulation of ``railcontact demo`` (one wheelset, lateral/yaw/spin, primary
suspension, 83.3 kN per wheel, S1002 on 60E1 1:40, V = 30 m/s, from 4 mm lateral offset;
the FMU driven by fmpy) is run for each warm_start mode - none, estimate (INFCON +
FaStrip), previous, previous+estimate - and each communication step (0.5, 1, 2, 5 ms).
A shadow FMU instance with tight tolerances (eps_n = 1e-6, eps_tau = 1e-5, cold) gets the
same inputs every few steps and gives the reference forces for exactly those states.

Printed and written (CSV, plot, a Markdown table for docs/warmstart.md): mean and maximum
normal and tangential iterations per step (both wheels, the first step - always cold -
left out), the median solve time and the median wall time per step through fmpy, the
iteration ratio to the cold start at the same step, and the largest force differences to
the reference: maximum pressure |dp| / p (the normal forces are the wheel loads, given),
creep force |dF| / (mu N) and |dF| relative to the peak creep force of the run.

With ``--per-step`` each run also writes its steps (``warmstart_steps_<mode>_<step>ms.csv``
in ``--out``: time, wheelset lateral displacement, each wheel's rail contact position and
iterations) and prints the iterations per step by band of lateral displacement: which
steps cost the iterations.

The iterations are the FMU's whole-step totals (``normal_iterations``,
``tangential_iterations``: the wheels' contact solves and the rigid wheelset's solves at
other rolls); ``--per-step``'s bands are the wheels' contact solves
(``normal_iterations_left`` ...).

Usage: python scripts/warmstart_study.py [--duration 0.6] [--steps 0.5e-3 1e-3 2e-3 5e-3]
       [--modes none estimate previous previous+estimate] [--out docs]
       [--element-size 0.5e-3] [--from-csv docs/warmstart_study.csv] [--per-step]
"""

from __future__ import annotations

import argparse
import csv
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODES = ("none", "estimate", "previous", "previous+estimate")
BANDS = (0.0, 1e-3, 2e-3, np.inf)
"""Bands of |lateral displacement| [m] for the per-step summary."""
REFERENCE = {"warm_start": "none", "normal_tolerance": 1e-6, "tangential_tolerance": 1e-5}
SIDES = ("left", "right")


def force_errors(sim, friction: float) -> dict[str, float]:
    """Largest differences of the main run's forces to the reference shadow."""
    ref = sim.shadows["reference"]
    k = ref["step"]
    o = sim.outputs
    dp, dmu, dpeak = 0.0, 0.0, 0.0
    peak = max(float(np.max(np.hypot(ref[f"creep_force_x_{s}"], ref[f"creep_force_y_{s}"])))
               for s in SIDES)
    for s in SIDES:
        n_ref = ref[f"normal_force_{s}"]
        p_ref = ref[f"max_pressure_{s}"]
        dp = max(dp, float(np.max(np.abs(o[f"max_pressure_{s}"][k] - p_ref) / p_ref)))
        df = np.hypot(o[f"creep_force_x_{s}"][k] - ref[f"creep_force_x_{s}"],
                      o[f"creep_force_y_{s}"][k] - ref[f"creep_force_y_{s}"])
        dmu = max(dmu, float(np.max(df / (friction * n_ref))))
        dpeak = max(dpeak, float(np.max(df)) / peak)
    return {"dp_rel": dp, "dF_muN": dmu, "dF_peak": dpeak,
            "reference_status": int(np.max(ref["status"]))}


def steps_of(sim) -> list[dict]:
    """Each step of a run (the first, always cold, left out): time [s], lateral
    displacement [m], each wheel's rail contact position [m] and iterations."""
    o = sim.outputs
    out = []
    for k in range(1, len(sim.time)):
        row = {"time": float(sim.time[k]), "lateral": float(sim.lateral[k])}
        for s in SIDES:
            row[f"rail_position_{s}"] = float(o[f"rail_contact_position_{s}"][k])
            row[f"normal_{s}"] = int(o[f"normal_iterations_{s}"][k])
            row[f"tangential_{s}"] = int(o[f"tangential_iterations_{s}"][k])
        out.append(row)
    return out


def band_summary(steps: list[dict]) -> str:
    """Iterations per step (both wheels) by band of |lateral displacement|, and each
    wheel's rail contact position move per step against the wheelset's."""
    y = np.array([r["lateral"] for r in steps])
    lines = []
    for lo, hi in zip(BANDS[:-1], BANDS[1:], strict=True):
        s = (np.abs(y) >= lo) & (np.abs(y) < hi)
        if not s.any():
            continue
        part = [r for r, k in zip(steps, s, strict=True) if k]
        cols = []
        for side in SIDES:
            n = np.mean([r[f"normal_{side}"] for r in part])
            t = np.mean([r[f"tangential_{side}"] for r in part])
            cols.append(f"{side} {n:.2f} + {t:.2f}")
        hi_mm = "" if not np.isfinite(hi) else f"{hi * 1e3:g}"
        lines.append(f"  |y| {lo * 1e3:g}-{hi_mm} mm: {int(s.sum()):4d} steps, CG + sweeps "
                     + ", ".join(cols))
    dy = np.abs(np.diff(y))
    for side in SIDES:
        du = np.abs(np.diff([r[f"rail_position_{side}"] for r in steps]))
        near = (np.abs(y[1:]) < BANDS[1]) & (dy > 0)
        if near.any():
            ratio = float(np.median(du[near] / dy[near]))
            lines.append(f"  {side} contact point on the rail moves {ratio:.1f}x the "
                         f"wheelset's lateral move (median, |y| < {BANDS[1] * 1e3:g} mm)")
    return "\n".join(lines)


def run_case(fmu: Path, mode: str, step: float, duration: float, element_size: float,
             samples: int, steps: list | None = None) -> dict:
    from railcontact.sim.cosim import Run, simulate

    n = int(round(duration / step))
    every = max(1, n // samples)
    run = Run(speed=30.0, duration=duration, step=step, initial_lateral=4e-3,
              parameters={"creepage_input": "kinematic", "warm_start": mode,
                          "element_size": element_size},
              shadows={"reference": ({**REFERENCE}, every)})
    t0 = time.perf_counter()
    sim = simulate(fmu, run)
    wall = time.perf_counter() - t0
    if not sim.completed:
        raise SystemExit(f"{mode} at {step * 1e3:g} ms: {sim.message}")
    if steps is not None:
        steps.extend(steps_of(sim))
    o = sim.outputs
    ni, nt = o["normal_iterations"][1:], o["tangential_iterations"][1:]
    row = {"warm_start": mode, "step_ms": step * 1e3, "steps": n,
           "normal_mean": float(ni.mean()), "normal_max": int(ni.max()),
           "tangential_mean": float(nt.mean()), "tangential_max": int(nt.max()),
           "solve_ms": 1e3 * float(np.median(o["solve_time"][1:])),
           "step_wall_ms": 1e3 * float(np.median(sim.wall_time[1:])),
           "not_converged_steps": int(np.sum(o["status"] == 1)),
           "run_wall_s": wall, **force_errors(sim, float(sim.parameters["friction"]))}
    return row


def table(rows: list[dict]) -> str:
    cold = {r["step_ms"]: r["normal_mean"] + r["tangential_mean"] for r in rows
            if r["warm_start"] == "none"}
    out = ["| step [ms] | warm_start | normal mean / max | tangential mean / max | "
           "ratio to cold | solve [ms] | per step [ms] | max dp/p | max dF/(mu N) | "
           "max dF/peak |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        total = r["normal_mean"] + r["tangential_mean"]
        c = cold.get(r["step_ms"])  # the ratio needs the cold run of the same step
        ratio = "n/a" if c is None or total <= 0 else f"{c / total:.1f}x"
        out.append(f"| {r['step_ms']:g} | {r['warm_start']} | {r['normal_mean']:.2f} / "
                   f"{r['normal_max']} | {r['tangential_mean']:.2f} / {r['tangential_max']} | "
                   f"{ratio} | {r['solve_ms']:.1f} | {r['step_wall_ms']:.1f} | "
                   f"{100 * r['dp_rel']:.3f} % | {100 * r['dF_muN']:.3f} % | "
                   f"{100 * r['dF_peak']:.3f} % |")
    return "\n".join(out)


def plot(rows: list[dict], path: Path) -> None:
    from railcontact.io.plotting import _pyplot

    plt = _pyplot()

    fig, ax = plt.subplots(1, 3, figsize=(14, 4.2), constrained_layout=True)
    for j, mode in enumerate(MODES):
        rs = [r for r in rows if r["warm_start"] == mode]
        if not rs:  # a mode not run: not in the legend either
            continue
        h = [r["step_ms"] for r in rs]
        ax[0].plot(h, [r["normal_mean"] for r in rs], f"C{j}o-", label=mode)
        ax[1].plot(h, [r["tangential_mean"] for r in rs], f"C{j}o-", label=mode)
        ax[2].plot(h, [r["solve_ms"] for r in rs], f"C{j}o-", label=mode)
    for a, title in zip(ax, ("normal iterations per step", "tangential sweeps per step",
                             "solve time per step [ms] (median)"), strict=True):
        a.set_xscale("log")
        a.minorticks_off()
        a.set_xticks([0.5, 1, 2, 5], ["0.5", "1", "2", "5"])
        a.set_xlabel("communication step [ms]")
        a.set_title(title, fontsize=10)
        a.set_ylim(bottom=0)
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    fig.suptitle("wheelset co-simulation through the FMU, V = 30 m/s, both wheels", fontsize=10)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.6, help="simulated time [s] (0.6)")
    ap.add_argument("--steps", type=float, nargs="+", default=[0.5e-3, 1e-3, 2e-3, 5e-3],
                    help="communication steps [s]")
    ap.add_argument("--modes", nargs="+", default=list(MODES), choices=MODES)
    ap.add_argument("--element-size", type=float, default=0.5e-3, help="[m] (0.0005)")
    ap.add_argument("--samples", type=int, default=25,
                    help="reference solves per run (default 25)")
    ap.add_argument("--out", default=str(ROOT / "docs"),
                    help="folder for warmstart_study.csv/.png/.md")
    ap.add_argument("--per-step", action="store_true",
                    help="also write each run's steps and print iterations by lateral band")
    ap.add_argument("--from-csv", metavar="FILE",
                    help="no runs: table and plot from an earlier CSV")
    args = ap.parse_args()

    from railcontact.fmu import build_fmu

    rows = []
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    summaries = []
    if args.from_csv:
        with open(args.from_csv, newline="") as f:
            for r in csv.DictReader(f):
                rows.append({k: (v if k == "warm_start" else float(v)) for k, v in r.items()})
        for r in rows:
            for k in ("normal_max", "tangential_max", "steps", "not_converged_steps",
                      "reference_status"):
                r[k] = int(r[k])
        args.steps = []
    with tempfile.TemporaryDirectory() as tmp:
        fmu = build_fmu(Path(tmp) / "RailContact.fmu") if args.steps else None
        for step in args.steps:
            for mode in args.modes:
                print(f"  {mode} at {step * 1e3:g} ms ...", file=sys.stderr, flush=True)
                steps = [] if args.per_step else None
                rows.append(run_case(fmu, mode, step, args.duration, args.element_size,
                                     args.samples, steps))
                if steps:
                    path = out / f"warmstart_steps_{mode.replace('+', '_')}_{step * 1e3:g}ms.csv"
                    with path.open("w", newline="") as f:
                        w = csv.DictWriter(f, fieldnames=list(steps[0]))
                        w.writeheader()
                        w.writerows(steps)
                    summaries.append(f"{mode} at {step * 1e3:g} ms (steps in {path.name}):\n"
                                     + band_summary(steps))
    with (out / "warmstart_study.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    md = table(rows)
    (out / "warmstart_study.md").write_text(md + "\n", encoding="utf-8")
    plot(rows, out / "warmstart_study.png")
    print(f"warm-start study: {args.duration:g} s at V = 30 m/s, element size "
          f"{args.element_size * 1e3:g} mm; reference eps_n = {REFERENCE['normal_tolerance']:g}, "
          f"eps_tau = {REFERENCE['tangential_tolerance']:g}")
    print(md)
    for text in summaries:
        print(text)
    bad = [r for r in rows if r["not_converged_steps"] or r["reference_status"]]
    for r in bad:
        print(f"note: {r['warm_start']} at {r['step_ms']:g} ms: {r['not_converged_steps']} "
              f"steps not converged, reference status {r['reference_status']}")
    print(f"written: {out / 'warmstart_study.csv'}, {out / 'warmstart_study.png'}, "
          f"{out / 'warmstart_study.md'}")


if __name__ == "__main__":
    main()
