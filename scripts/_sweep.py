"""Shared by the study scripts: the displacements of the lateral sweep, a loop over them
with a progress bar, the approach that carries a wheel load, the report of failed cases, the
CSV writer and the figure's common finish (``from _sweep import ...`` in a script run from
``scripts/``)."""

from __future__ import annotations

import copy
import csv
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

import railcontact as rc


def paper_case() -> dict:
    """The studies' wheel-rail case without its ``[normal]`` table: S1002 on 60E1 (1:40),
    the left wheel, 64 x 64 elements, steel, each patch at its rigid contact point as the
    paper poses it (a fresh dictionary each call)."""
    return {
        "material": {"young": 206e9, "poisson": 0.28},
        "geometry": {"type": "wheel-rail", "wheel": "S1002", "rail": "60E1", "side": "left",
                     "patch_frame": "rigid"},
        "grid": {"nx": 64, "ny": 64},
    }


def displacements(step_mm: float) -> np.ndarray:
    """Lateral wheelset displacements -8 .. 8 mm in steps of ``step_mm`` [m]."""
    return np.round(np.arange(-8.0, 8.0 + 1e-9, step_mm), 6) * 1e-3


def run_sweep(dys: np.ndarray, one_case: Callable[[float], list[dict]]
              ) -> tuple[list[dict], list[tuple[float, str]]]:
    """``one_case(dy)`` for every displacement, with a progress bar on stderr; returns the
    rows and the (displacement, message) of the cases that raised a RailContactError."""
    rows, failed = [], []
    t0 = time.perf_counter()
    for i, dy in enumerate(dys):
        try:
            rows += one_case(float(dy))
        except (rc.RailContactError, rc.SolverError) as exc:
            failed.append((float(dy), str(exc)))
        done = (i + 1) / len(dys)
        eta = (time.perf_counter() - t0) * (1 / done - 1)
        print(f"\r[{'#' * int(30 * done):<30}] {i + 1}/{len(dys)} cases, ~{eta:.0f} s left",
              end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    return rows, failed


def approach_for_load(case: dict, load: float) -> float:
    """Vertical approach [m] at which the wheel of ``case`` (without a ``[normal]`` table)
    carries the vertical ``load`` [N]: its first patch's normal penetration, load-controlled
    to eps_n = 1e-9, divided by the cosine of its contact angle. The paper's cases are
    penetration-controlled with this approach."""
    c = copy.deepcopy(case)
    c["normal"] = {"load": load, "tolerance": 1e-9, "estimate": "infcon"}
    main = rc.solve(c).patches[0]
    return main.normal.penetration / math.cos(main.geometry.contact_angle)


def report_failed(failed: list[tuple[float, str]]) -> None:
    """Print the displacements whose case raised, with the reason."""
    for dy, msg in failed:
        print(f"  failed at {dy * 1e3:+.2f} mm: {msg}")


def save_figure(fig, axes, out: Path, name: str, xlabel: str = "lateral displacement [mm]",
                ylabel: str = "iterations", legend_size: float | None = 8) -> None:
    """Label, grid and legend on every axis, the figure saved as ``out/name.png``, and the
    CSV and PNG paths printed (the CSV written before by :func:`write_csv`)."""
    for a in axes:
        a.set_xlabel(xlabel)
        a.set_ylabel(ylabel)
        a.grid(alpha=0.3)
        a.legend(fontsize=legend_size)
    fig.savefig(out / f"{name}.png", dpi=120)
    print(out / f"{name}.csv", out / f"{name}.png")


def write_csv(path: Path, rows: list[dict]) -> None:
    """Rows as a CSV file with a header (columns in first-seen order; missing cells empty)."""
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
