"""Plot the time of a wheelset step and its breakdown, before and after (docs/performance.md).

Reads the ``--json`` files of ``scripts/bench_step.py`` (one per version, in the order
given) and draws, for the warm (``previous+estimate``) and the cold (``none``) start, the
mean step time as a ratio to the fixed workload of its own run, split by stage (the
stage shares are of the run's total time, so they split the mean exactly), the median as
a marker, and the targets (on the median) as lines.

Usage: python scripts/plot_performance.py BEFORE.json AFTER.json [--labels before after]
       [--out docs/performance_step.png]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

TARGETS = {"previous+estimate": 0.03, "none": 0.25}
"""The targets per step, as ratios to the fixed workload."""
STAGES = ["search", "meshing", "estimate", "normal BEM", "tangential BEM", "operators", "rest"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path, help="bench_step.py --json files")
    ap.add_argument("--labels", nargs="+", default=None)
    ap.add_argument("--out", type=Path, default=Path("docs/performance_step.png"))
    args = ap.parse_args()
    labels = args.labels or [p.stem for p in args.runs]
    data = [json.loads(p.read_text()) for p in args.runs]
    modes = list(TARGETS)
    fig, axes = plt.subplots(1, len(modes), figsize=(10, 5))
    colors = plt.get_cmap("tab10").colors
    for ax, mode in zip(axes, modes, strict=True):
        for i, d in enumerate(data):
            run = next(r for r in d["runs"] if r["mode"] == mode)
            total = run["mean"] / d["workload"]
            shares = dict(run["breakdown"])
            shares["rest"] = max(0.0, 1.0 - sum(shares.values()))
            bottom = 0.0
            for k, stage in enumerate(STAGES):
                h = total * shares.get(stage, 0.0)
                ax.bar(i, h, bottom=bottom, color=colors[k], width=0.6,
                       label=stage if i == 0 else None)
                bottom += h
            median = run["median"] / d["workload"]
            ax.plot([i - 0.3, i + 0.3], [median, median], color="k", lw=2,
                    label="median" if i == 0 else None)
            ax.text(i, bottom, f"mean {total:.3f}\nmedian {median:.3f}", ha="center",
                    va="bottom", fontsize=8)
        ax.axhline(TARGETS[mode], color="k", ls="--", lw=1, label="target (median)")
        ax.set_xticks(range(len(data)), labels)
        ax.set_ylim(0, ax.get_ylim()[1] * 1.12)
        ax.set_title(f"{mode} start: time per step")
        ax.set_ylabel("step time / fixed workload")
        ax.grid(axis="y", alpha=0.3)
    handles, names = axes[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=5, fontsize=8)
    fig.suptitle("Wheelset step (S1002/60E1, 0.5 mm, 83.3 kN with creep, 30 m/s, hunting)")
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    fig.savefig(args.out, dpi=110)
    print(f"written {args.out}")


if __name__ == "__main__":
    main()
