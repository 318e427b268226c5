"""Study: the three wheel-rail cases (paper Fig. 4, 5, 13 and 14).

S1002 on 60E1 at 1:40 (the paper: S1002CN on CN60), left wheel, lateral wheelset
displacements -2, 0 and 7.78 mm. As in the paper, the vertical approach that carries
83.3 kN is found first; every solve is then penetration-controlled with it.

Normal (Fig. 4, 5): the initial estimates Hertz, KP and INFCON on the BEM grid against the
converged BEM (eps_n = 1e-9): contact outlines, pressure across the patch (lateral, at the
element row nearest x = 0), and the BEM's convergence history (eps_n = 1e-3) from none /
Hertz / KP / INFCON, with railcontact's solver (Polonsky–Keer CG with the FFT
preconditioner) and with the paper's plain Polonsky–Keer CG.

Tangential (Fig. 13, 14), at -2 mm with the three creepage cases of the paper's Table 5
(xi = eta = c, phi = c /mm with c = 0.5e-4, 2e-4, 5e-4), mu = 0.4: FASTSIM and FaStrip
(equivalent-ellipse adaptation, on the BEM pressure) re-meshed onto the BEM grid against
the converged ConvexGS (eps_tau = 1e-8): adhesion/slip maps, longitudinal traction along
the rolling line, and the ConvexGS history (eps_tau = 1e-2) from none / FASTSIM / FaStrip.

Writes study_cases.csv, study_cases_normal.png and study_cases_tangential.png and prints
the iterations beside the paper's (Fig. 5 at -2 mm: 13 / 9 / 6 / 5; Fig. 14: none 29, 29,
16; FASTSIM 27, 23, 12; FaStrip 13, 8, 5) with measures of each estimate's error:
"set" = elements in the estimate's patch but not the BEM's or vice versa, per cent of the
BEM's contact elements; "L1" = sum |p_est - p_BEM| / sum p_BEM, per cent.

Usage: python scripts/study_cases.py [--out out/]   (about a minute)
"""

from __future__ import annotations

import argparse
import copy
import itertools
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
from _sweep import approach_for_load, paper_case, write_csv

import railcontact as rc
from railcontact.contact import normal_estimate, simplified_tangential
from railcontact.geometry.points import samples
from railcontact.io.plotting import _pyplot
from railcontact.settings import Control
from railcontact.settings.choices import NORMAL_ESTIMATES, TANGENTIAL_ESTIMATES
from railcontact.tangential.strips import remesh_strips

BASE = paper_case()
LOAD = 83.3e3
CASES_MM = (-2.0, 0.0, 7.78)
SOLVERS = {"fft": "runs", "none": "runs_pk"}  # normal preconditioner -> key of its runs
FRICTION = 0.4
CREEP = {"case1": 0.5e-4, "case2": 2e-4, "case3": 5e-4}
TANGENTIAL_DY_MM = -2.0
PAPER_NORMAL = {-2.0: (13, 9, 6, 5)}  # Fig. 5a; 5b, c: Hertz worse than none (no numbers)
PAPER_TANGENTIAL = {"case1": (29, 27, 13), "case2": (29, 23, 8), "case3": (16, 12, 5)}
MM, MPA = 1e3, 1e-6
COLOURS = {"none": "0.5", "hertz": "tab:red", "kp": "tab:orange", "infcon": "tab:blue",
           "bem": "k", "fastsim": "tab:red", "fastrip": "tab:blue"}


def penetration_case(dy: float, approach: float, tolerance: float, estimate: str,
                     preconditioner: str = "fft") -> dict:
    c = copy.deepcopy(BASE)
    c["geometry"]["lateral_displacement"] = dy
    c["normal"] = {"penetration": approach, "tolerance": tolerance, "estimate": estimate,
                   "max_iterations": 2000, "preconditioner": preconditioner}
    return c


def set_error(estimate: np.ndarray, reference: np.ndarray) -> float:
    """Elements in one patch but not the other, per cent of the reference's elements."""
    return 100.0 * float(np.sum(estimate ^ reference)) / max(int(reference.sum()), 1)


def l1_error(estimate: np.ndarray, reference: np.ndarray) -> float:
    """sum |estimate - reference| / sum |reference|, per cent."""
    return 100.0 * float(np.abs(estimate - reference).sum() / np.abs(reference).sum())


def normal_case(dy: float) -> dict:
    """Estimates, converged BEM and histories of one displacement (all its patches)."""
    base = copy.deepcopy(BASE)
    base["geometry"]["lateral_displacement"] = dy
    approach = approach_for_load(base, LOAD)
    ref = rc.solve(penetration_case(dy, approach, 1e-9, "none"))
    if not ref.converged:  # (the estimates' errors are measured against it)
        raise rc.SolverError(f"{dy * MM:+.2f} mm: the normal reference did not converge")
    pair = ref.case.pair
    out = {"dy": dy, "approach": approach, "reference": ref, "patches": []}
    for rp in ref.patches:
        cp, grid = rp.geometry, rp.normal.grid
        control = Control(penetration=cp.normal_penetration(approach))
        patch = {"reference": rp, "estimates": {}, "runs": {}, "runs_pk": {}}
        for est in NORMAL_ESTIMATES[1:]:
            settings = replace(ref.case.normal, estimate=est)
            start = normal_estimate(settings, rp.hertz, *samples(cp)[:3], pair, control)
            p0 = start.pressure_on(grid).pressure
            patch["estimates"][est] = np.clip(p0, 0.0, None)
        out["patches"].append(patch)
    for est, (pre, runs) in itertools.product(NORMAL_ESTIMATES, SOLVERS.items()):
        sol = rc.solve(penetration_case(dy, approach, 1e-3, est, pre))
        if not sol.converged:  # (its iterations would be the limit's)
            raise rc.SolverError(f"{dy * MM:+.2f} mm, {est}, {pre}: did not converge")
        if len(sol.patches) != len(ref.patches):
            raise rc.RailContactError(f"{dy * MM:+.2f} mm: patch count depends on the estimate")
        for patch, sp in zip(out["patches"], sol.patches, strict=True):
            if sp.normal.grid.shape != patch["reference"].normal.grid.shape or not np.allclose(
                    sp.normal.grid.bounds, patch["reference"].normal.grid.bounds):
                raise rc.RailContactError("the potential area depends on the estimate")
            patch[runs][est] = sp.normal
    return out


def tangential_case(dy: float, approach: float, creepage: float) -> dict:
    """FASTSIM / FaStrip estimates, converged ConvexGS and histories (first patch)."""
    tspec = {"creepage": [creepage, creepage, creepage * 1e3], "friction": FRICTION,
             "solver": "convexgs"}  # the paper's solver
    c = penetration_case(dy, approach, 1e-9, "infcon")
    c["tangential"] = dict(tspec, tolerance=1e-8, max_iterations=5000)
    ref = rc.solve(c)
    if not ref.converged:
        raise rc.SolverError(f"{dy * MM:+.2f} mm: the tangential reference did not converge")
    rp = ref.patches[0]
    pair = ref.case.pair
    out = {"reference": rp, "estimates": {}, "runs": {}}
    for est in TANGENTIAL_ESTIMATES[1:]:
        strip = simplified_tangential(est, rp.hertz, pair, ref.case.tangential, rp.normal)
        out["estimates"][est] = remesh_strips(strip, rp.normal.grid)
    for est in TANGENTIAL_ESTIMATES:
        c = penetration_case(dy, approach, 1e-9, "infcon")
        c["tangential"] = dict(tspec, tolerance=1e-2, estimate=est)
        run = rc.solve(c)
        if not run.converged:
            raise rc.SolverError(f"{dy * MM:+.2f} mm, {est}: did not converge")
        out["runs"][est] = run.patches[0].tangential
    return out


def _edges(grid) -> tuple[np.ndarray, np.ndarray]:
    xmin, xmax, ymin, ymax = grid.bounds
    return (np.linspace(xmin, xmax, grid.nx + 1) * MM, np.linspace(ymin, ymax, grid.ny + 1) * MM)


def plot_histories(ax, runs: dict, tolerance: float, xlabel: str, ylabel: str) -> None:
    """Convergence history (error after each iteration) of the BEM from each start."""
    for est, run in runs.items():
        h = np.asarray(run.history)
        ax.semilogy(np.arange(1, len(h) + 1), h, "o-", ms=2.5, color=COLOURS[est],
                    label=f"{est}: {run.iterations}")
    ax.axhline(tolerance, color="k", lw=0.8, ls=":")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, title=f"start: {xlabel}s", title_fontsize=7)


def plot_normal(cases: list[dict], path: Path) -> None:
    plt = _pyplot()
    rows = [(c, k) for c in cases for k in range(len(c["patches"]))]
    fig, axs = plt.subplots(len(rows), 3, figsize=(14, 3.6 * len(rows)), squeeze=False)
    for (case, k), (a0, a1, a2) in zip(rows, axs, strict=True):
        patch = case["patches"][k]
        rp = patch["reference"]
        grid, p_ref = rp.normal.grid, rp.normal.pressure
        x, y = grid.x * MM, grid.y * MM
        xe, ye = _edges(grid)
        im = a0.pcolormesh(xe, ye, np.ma.masked_where(p_ref <= 0, p_ref).T * MPA,
                           cmap="Greys", shading="flat")
        fig.colorbar(im, ax=a0, label="BEM pressure [MPa]")
        for est, p0 in patch["estimates"].items():
            if np.any(p0 > 0):
                a0.contour(x, y, (p0 > 0).T.astype(float), levels=[0.5],
                           colors=COLOURS[est], linewidths=1.3)
            a0.plot([], [], color=COLOURS[est], label=est)
        a0.contour(x, y, rp.normal.contact.T.astype(float), levels=[0.5], colors="k",
                   linewidths=1.0, linestyles="--")
        a0.plot([], [], "k--", label="BEM")
        xmin, xmax, ymin, ymax = grid.bounds
        if (xmax - xmin) < 4 * (ymax - ymin):  # a long flange patch would be a sliver
            a0.set_aspect("equal")
        a0.set_xlabel("x (rolling) [mm]")
        a0.set_ylabel("s (lateral, along the rail) [mm]")
        a0.legend(fontsize=7, loc="upper right")
        title = f"dy = {case['dy'] * MM:+.2f} mm"
        if len(case["patches"]) > 1:
            title += f", patch {k}"
        angle = math.degrees(rp.geometry.contact_angle)
        a0.set_title(f"{title}: contact angle {angle:.1f} deg, N = "
                     f"{rp.normal.force / 1e3:.1f} kN", fontsize=9)
        i0 = int(np.argmin(np.abs(grid.x)))
        a1.step(y, p_ref[i0] * MPA, where="mid", color="k", lw=1.8, label="BEM")
        for est, p0 in patch["estimates"].items():
            a1.plot(y, p0[i0] * MPA, color=COLOURS[est], lw=1.2, label=est)
        a1.set_xlabel("s [mm]")
        a1.set_ylabel(f"pressure at x = {grid.x[i0] * MM:.2f} mm [MPa]")
        a1.grid(alpha=0.3)
        a1.legend(fontsize=7)
        plot_histories(a2, patch["runs"], 1e-3, "iteration", "eps_n (relative pressure change)")
        for est, run in patch["runs_pk"].items():
            h = np.asarray(run.history)
            a2.semilogy(np.arange(1, len(h) + 1), h, ":", lw=0.9, color=COLOURS[est])
        a2.set_title("solid: PK CG + FFT preconditioner; dotted: plain PK CG", fontsize=8)
    fig.suptitle("Normal estimates against the BEM (paper Fig. 4) and the BEM's convergence "
                 "from each (Fig. 5)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_tangential(cases: dict[str, dict], path: Path) -> None:
    from matplotlib.colors import ListedColormap

    plt = _pyplot()
    cmap = ListedColormap(["white", "tab:cyan", "tab:red"])
    fig, axs = plt.subplots(len(cases), 5, figsize=(19, 3.4 * len(cases)), squeeze=False)
    for (name, case), ax in zip(cases.items(), axs, strict=True):
        rp = case["reference"]
        grid = rp.normal.grid
        xe, ye = _edges(grid)
        maps = [("FASTSIM", case["estimates"]["fastsim"][1]),
                ("FaStrip", case["estimates"]["fastrip"][1]), ("BEM", rp.tangential.state)]
        for a, (label, state) in zip(ax[:3], maps, strict=True):
            a.pcolormesh(xe, ye, np.asarray(state).T, cmap=cmap, vmin=-0.5, vmax=2.5,
                         shading="flat")
            a.set_aspect("equal")
            a.set_title(f"{name}: {label} (cyan adhesion, red slip)", fontsize=8)
            a.set_xlabel("x [mm]")
        ax[0].set_ylabel("s [mm]")
        jc = int(np.argmax(rp.normal.contact.sum(axis=0)))
        x = grid.x * MM
        a = ax[3]
        a.step(x, rp.tangential.traction[0, :, jc] * MPA, where="mid", color="k", lw=1.8,
               label="BEM")
        for est in ("fastsim", "fastrip"):
            a.plot(x, case["estimates"][est][0][0, :, jc] * MPA, color=COLOURS[est],
                   label=est)
        bound = FRICTION * rp.normal.pressure[:, jc] * MPA
        a.plot(x, bound, "k:", lw=0.8, label="+- mu p")
        a.plot(x, -bound, "k:", lw=0.8)
        a.set_xlabel("x [mm]")
        a.set_ylabel(f"p_x at s = {grid.y[jc] * MM:.2f} mm [MPa]")
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
        plot_histories(ax[4], case["runs"], 1e-2, "sweep", "eps_tau")
    fig.suptitle(f"Tangential estimates against ConvexGS at dy = {TANGENTIAL_DY_MM:+.0f} mm, "
                 "Table 5 creepages (paper Fig. 13) and ConvexGS convergence (Fig. 14)",
                 fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out"))
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    rows: list[dict] = []

    print("normal, penetration control (approach for 83.3 kN), eps_n = 1e-3: iterations, "
          "and each estimate's error against the converged BEM")
    print("| dy [mm] | patch | contact angle [deg] | none | Hertz | KP | INFCON | plain PK CG "
          "| paper | Hertz set / L1 % | KP set / L1 % | INFCON set / L1 % |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    cases = []
    for dy_mm in CASES_MM:
        case = normal_case(dy_mm * 1e-3)
        cases.append(case)
        for k, patch in enumerate(case["patches"]):
            rp = patch["reference"].normal
            its = [patch["runs"][e].iterations for e in NORMAL_ESTIMATES]
            its_pk = [patch["runs_pk"][e].iterations for e in NORMAL_ESTIMATES]
            errs = {e: (set_error(p0 > 0, rp.contact), l1_error(p0, rp.pressure))
                    for e, p0 in patch["estimates"].items()}
            paper = PAPER_NORMAL.get(dy_mm)
            angle = math.degrees(patch["reference"].geometry.contact_angle)
            print(f"| {dy_mm:+.2f} | {k} | {angle:.1f} | " + " | ".join(map(str, its))
                  + f" | {' / '.join(map(str, its_pk))}"
                  + f" | {' / '.join(map(str, paper)) if paper else 'Hertz > none'} | "
                  + " | ".join(f"{s:.1f} / {e:.1f}" for s, e in errs.values()) + " |")
            row = {"problem": "normal", "dy_mm": dy_mm, "patch": k, "case": "",
                   "approach_m": case["approach"], "contact_angle_deg": angle}
            row.update({f"its_{e}": n for e, n in zip(NORMAL_ESTIMATES, its, strict=True)})
            row.update({f"its_pk_{e}": n for e, n in zip(NORMAL_ESTIMATES, its_pk,
                                                         strict=True)})
            for e, (s, l1) in errs.items():
                row[f"set_{e}_pct"], row[f"l1_{e}_pct"] = s, l1
            rows.append(row)
    plot_normal(cases, args.out / "study_cases_normal.png")

    dy = TANGENTIAL_DY_MM * 1e-3
    approach = next(c["approach"] for c in cases if c["dy"] == dy)
    print(f"\ntangential at {TANGENTIAL_DY_MM:+.0f} mm, mu = {FRICTION:g}, eps_tau = 1e-2: sweeps, "
          "and each estimate's error against the converged ConvexGS")
    print("| case | creepage | none | FASTSIM | FaStrip | paper | FASTSIM slip-set / L1 % | "
          "FaStrip slip-set / L1 % |")
    print("|---|---|---|---|---|---|---|---|")
    tcases = {}
    for name, cr in CREEP.items():
        case = tangential_case(dy, approach, cr)
        tcases[name] = case
        rt = case["reference"].tangential
        its = [case["runs"][e].iterations for e in TANGENTIAL_ESTIMATES]
        errs = {e: (set_error(st == 2, rt.state == 2), l1_error(q, rt.traction))
                for e, (q, st) in case["estimates"].items()}
        print(f"| {name} | {cr:g} | " + " | ".join(map(str, its))
              + f" | {' / '.join(map(str, PAPER_TANGENTIAL[name]))} | "
              + " | ".join(f"{s:.1f} / {e:.1f}" for s, e in errs.values()) + " |")
        row = {"problem": "tangential", "dy_mm": TANGENTIAL_DY_MM, "patch": 0, "case": name,
               "approach_m": approach, "contact_angle_deg":
               math.degrees(case["reference"].geometry.contact_angle)}
        row.update({f"its_{e}": n for e, n in zip(TANGENTIAL_ESTIMATES, its, strict=True)})
        for e, (s, l1) in errs.items():
            row[f"set_{e}_pct"], row[f"l1_{e}_pct"] = s, l1
        rows.append(row)
    plot_tangential(tcases, args.out / "study_cases_tangential.png")

    write_csv(args.out / "study_cases.csv", rows)
    print(f"\nwrote {args.out / 'study_cases.csv'}, study_cases_normal.png, "
          "study_cases_tangential.png")


if __name__ == "__main__":
    main()
