"""The frames and sign conventions of WheelsetContact and the FMU, as a figure.

Writes ``docs/fmu_frames.png``: (a) the track frame from above with the wheelset's lateral
displacement, yaw and the longitudinal forces and yaw moment; (b) the view along the track
(from behind, looking forward) with roll, vertical displacement and the forces of the
rails on the wheels; (c) the left wheel's flange contact at 7 mm, to scale from the real
S1002 and 60E1 profiles, with the contact frame (x forward, y in the contact plane towards
+Y, n = x × y) and the forces on the wheel.

Usage: ``python scripts/fmu_frames_figure.py [--out docs/fmu_frames.png]``
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import FancyArrowPatch, Polygon, Rectangle  # noqa: E402

from railcontact.geometry.profiles import read_profile  # noqa: E402
from railcontact.geometry.search import contact_points, vertical_gap  # noqa: E402
from railcontact.geometry.track import Pose, Track, Wheelset  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
BLUE, RED, GREY = "#1f4e9c", "#c0392b", "#777777"


def arrow(ax, start, end, color="k", text="", offset=(0, 0), **kw):
    ax.add_patch(FancyArrowPatch(start, end, arrowstyle="-|>", mutation_scale=12,
                                 color=color, lw=1.6, **kw))
    if text:
        ax.annotate(text, end, xytext=offset, textcoords="offset points", color=color,
                    fontsize=9, ha="center", va="center")


def curved(ax, centre, radius, a0, a1, color, text):
    t = np.radians(np.linspace(a0, a1, 40))
    x, y = centre[0] + radius * np.cos(t), centre[1] + radius * np.sin(t)
    ax.plot(x[:-1], y[:-1], color=color, lw=1.4)
    arrow(ax, (x[-3], y[-3]), (x[-1], y[-1]), color)
    ax.text(x[len(x) // 2] * 1.0, y[len(y) // 2] + 0.06 * radius, text, color=color,
            fontsize=9, ha="center", va="bottom")


def top_view(ax) -> None:
    ax.set_title("(a) from above: track frame", fontsize=10)
    for y in (0.7175, -0.7175):
        ax.plot([-1.0, 1.0], [y, y], color=GREY, lw=3)
    ax.text(0.98, 0.76, "left rail", color=GREY, fontsize=8, ha="right")
    ax.text(0.98, -0.68, "right rail", color=GREY, fontsize=8, ha="right")
    psi, y0 = math.radians(8), 0.06
    c, s = math.cos(psi), math.sin(psi)

    def rot(x, y):
        return (x * c - y * s, x * s + y * c + y0)

    ax.plot(*zip(rot(0, -0.75), rot(0, 0.75), strict=True), color="k", lw=2)
    for side in (0.75, -0.75):
        corners = [rot(-0.45, side - 0.04), rot(0.45, side - 0.04), rot(0.45, side + 0.04),
                   rot(-0.45, side + 0.04)]
        ax.add_patch(Polygon(corners, closed=True, fc="#dddddd", ec="k"))
        p = rot(0, side)
        arrow(ax, p, (p[0] - 0.35, p[1]), RED, "F_X < 0 (rail on\nwheel, ξ > 0)",
              (-10, 14) if side > 0 else (-10, -16))
    arrow(ax, (-0.9, -0.25), (-0.55, -0.25), "k", "X forward", (0, -10))
    arrow(ax, (-0.9, -0.25), (-0.9, 0.1), "k", "Y left", (0, 8))
    ax.text(-0.93, -0.42, "Z up, out of the page", fontsize=8, va="top")
    ax.plot([0, 0], [0, y0], color=BLUE, lw=1)
    ax.annotate("y", (0.02, y0 / 2), color=BLUE, fontsize=9)
    curved(ax, (0, y0), 0.3, 20, 75, BLUE, "ψ, M_Z > 0\n(nose left)")
    ax.set_xlim(-1.0, 1.0)
    ax.set_ylim(-0.95, 0.95)
    ax.set_aspect("equal")
    ax.axis("off")


def rear_view(ax) -> None:
    ax.set_title("(b) along the track, from behind (X into the page)", fontsize=10)
    for y in (0.7175, -0.7175):
        ax.add_patch(Rectangle((-y - 0.035, -0.16), 0.07, 0.16, fc="#bbbbbb", ec=GREY))
    # the wheelset: axle at r0 = 0.46 above the rail tops (not to scale across)
    ax.plot([-0.75, 0.75], [0.46, 0.46], color="k", lw=3)
    for y in (0.75, -0.75):
        u = -y  # page x: Y to the left
        inner = u + (0.07 if y > 0 else -0.07)
        ax.add_patch(Polygon([(u - 0.06, 0.0), (u + 0.06, 0.0), (u + 0.06, 0.92),
                              (u - 0.06, 0.92)], closed=True, fc="#eeeeee", ec="k"))
        ax.add_patch(Polygon([(inner - 0.012, -0.03), (inner + 0.012, -0.03),
                              (inner + 0.012, 0.95), (inner - 0.012, 0.95)], closed=True,
                             fc="#cccccc", ec="k"))
    ax.plot(0, 0.46, "ko", ms=4)
    ax.annotate("centre, at r0 + vertical\nabove the rail tops", (0, 0.46),
                xytext=(-0.3, 0.75), ha="center", fontsize=8, arrowprops={"arrowstyle": "-"})
    arrow(ax, (0.25, -0.32), (-0.1, -0.32), "k", "Y left", (0, -10))
    arrow(ax, (0.25, -0.32), (0.25, 0.0), "k", "Z up", (18, 0))
    # forces of the rail on the left wheel, at its contact
    arrow(ax, (-0.72, 0.0), (-0.72, 0.3), RED, "F_Z (Q)", (22, 0))
    arrow(ax, (-0.72, 0.0), (-0.45, 0.0), RED, "F_Y < 0 on a\nflanging left wheel", (10, 14))
    ax.text(-0.72, -0.2, "Y/Q = −F_Y / F_Z\n(wheel on rail, to the field side)",
            fontsize=8, ha="center", va="top", color=RED)
    curved(ax, (0.0, 0.46), 0.3, 50, 5, BLUE, "roll φ, M_X > 0\n(left side up)")
    ax.set_xlim(-1.05, 1.05)
    ax.set_ylim(-0.5, 1.05)
    ax.set_aspect("equal")
    ax.axis("off")


def contact_detail(ax) -> None:
    ax.set_title("(c) left wheel on its flange, y = 7 mm (S1002 on 60E1, to scale)",
                 fontsize=10)
    track = Track(read_profile("60E1", "rail"), math.atan(1 / 40))
    ws = Wheelset(read_profile("S1002", "wheel"), 0.46)
    pose = Pose(7e-3)
    rail = track.side_rail
    u = np.linspace(*rail.bounds, 400)
    mm = 1e3
    ax.fill_between(-u * mm, rail.height(u) * mm, -40, color="#cccccc", ec=GREY)
    g_min = float(vertical_gap(track, ws, pose, "left")[4].min())
    s = np.linspace(*ws.wheel.bounds, 800)  # the wheel's lowest line (no yaw, no roll)
    uw = ws.axial_position(s) + pose.lateral
    zw = -ws.wheel.height(s) - g_min
    ax.fill(np.concatenate([-uw, [-uw[-1], -uw[0]]]) * mm,
            np.concatenate([zw, [0.05, 0.05]]) * mm, color="#eeeeee", ec="k")
    (cp, *_) = contact_points(track, ws, pose, "left")
    gamma = cp.contact_angle
    pu, pz = cp.rail_u * mm, cp.position[2] * mm
    p = (-pu, pz)  # page x = -Y (Y to the left)
    # side frame (u = Y on the left): y = (cos g, sin g), n = (-sin g, cos g) in (u, z)
    L = 12.0
    y_dir = (-math.cos(gamma), math.sin(gamma))
    n_dir = (math.sin(gamma), math.cos(gamma))
    arrow(ax, p, (p[0] + L * y_dir[0], p[1] + L * y_dir[1]), BLUE, "y", (-6, 6))
    arrow(ax, p, (p[0] + L * n_dir[0], p[1] + L * n_dir[1]), BLUE, "n", (8, 4))
    ax.plot(*p, "o", color=BLUE, ms=5)
    ax.annotate("x forward (into the page)", p, xytext=(p[0] - 18, p[1] - 16), fontsize=8,
                color=BLUE, arrowprops={"arrowstyle": "-", "color": BLUE})
    F = 20.0
    arrow(ax, (p[0] - F * n_dir[0], p[1] - F * n_dir[1]), p, RED)
    ax.text(p[0] - F * n_dir[0] + 1, p[1] - F * n_dir[1] - 2, "N: rail on wheel, along n",
            color=RED, fontsize=8, ha="left", va="top")
    ax.text(p[0] + 14, p[1] - 8, f"γ = {math.degrees(gamma):.0f}° (contact_angle,\n"
            "positive towards the flange)\nF_y, M_z: on the wheel,\nalong y and about n",
            fontsize=8)
    ax.text(-pu - 28, -36, "rail 60E1, canted 1:40", color=GREY, fontsize=8)
    ax.text(-pu - 28, 12, "wheel S1002", fontsize=8)
    ax.set_xlim(-pu - 30, -pu + 40)
    ax.set_ylim(-40, 20)
    ax.set_aspect("equal")
    ax.set_xlabel("−Y [mm] (Y to the left)", fontsize=8)
    ax.set_ylabel("Z [mm]", fontsize=8)
    ax.tick_params(labelsize=7)


def main(argv: list[str] | None = None) -> Path:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "docs" / "fmu_frames.png"))
    args = ap.parse_args(argv)
    fig, axes = plt.subplots(1, 3, figsize=(15, 5.2))
    top_view(axes[0])
    rear_view(axes[1])
    contact_detail(axes[2])
    fig.suptitle("railcontact FMU: frames and signs (SI; forces and moments are the rails' "
                 "on the wheelset)", fontsize=11)
    fig.tight_layout()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90)
    print(out)
    return out


if __name__ == "__main__":
    main()
