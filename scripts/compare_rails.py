"""The built-in CN60 head beside 60E1: both uncanted heads, their widths, height difference
and the surface angle of their slopes.

Usage: python scripts/compare_rails.py [--out docs/cn60_60e1.png]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from railcontact.geometry.profiles import builtin_profile
from railcontact.io.plotting import _pyplot

DOCS = Path(__file__).resolve().parents[1] / "docs"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=DOCS / "cn60_60e1.png")
    args = ap.parse_args()
    cn, e1 = builtin_profile("CN60"), builtin_profile("60E1")
    hi = min(cn.bounds[1], e1.bounds[1])
    y = np.linspace(0.0, hi, 2001)
    dz = cn.height(y) - e1.height(y)
    for name, p in (("CN60", cn), ("60E1", e1)):
        yp = np.linspace(0.0, p.bounds[1], 40001)
        flank = np.flatnonzero(p.slope(yp) <= -20.0 + 1e-3)  # the 1:20 flank: dz/dy = -20
        width = 2 * yp[flank[0]] * 1e3 if flank.size else float("nan")
        gauge = brentq(lambda v, p=p: float(p.height(v)) + 0.014, 0.02, p.bounds[1])
        print(f"{name}: head width at the 1:20 side's tangent point {width:.2f} mm, "
              f"14 mm below the crown {2 * gauge * 1e3:.2f} mm, widest (profile end, "
              f"{-p.height(p.bounds[1]) * 1e3:.1f} mm below the crown) "
              f"{2 * p.bounds[1] * 1e3:.2f} mm; height at |y| = 30 mm "
              f"{p.height(0.030) * 1e3:.3f} mm")
    for lim in (0.010, 0.020, 0.025, 0.030, 0.034):
        sel = y <= lim
        k = int(np.argmax(np.abs(dz[sel])))
        print(f"|y| <= {lim * 1e3:.0f} mm: largest height difference {dz[sel][k] * 1e3:.3f} mm "
              f"at |y| = {y[sel][k] * 1e3:.2f} mm")
    plt = _pyplot()
    fig, (a0, a1, a2) = plt.subplots(1, 3, figsize=(14, 4), constrained_layout=True)
    for name, p, st in (("CN60 (TB/T 2344 arcs)", cn, "-"), ("60E1", e1, "--")):
        yy = np.linspace(*p.bounds, 2001)
        a0.plot(yy * 1e3, p.height(yy) * 1e3, st, label=name)
        a2.plot(y * 1e3, np.degrees(np.arctan(-p.slope(y))), st, label=name)
    a0.set_aspect("equal")
    a0.set(xlabel="y [mm] (uncanted, field side > 0)", ylabel="z [mm]", title="rail heads")
    top = y <= 0.034  # beyond, the difference is that of two near-vertical sides
    a1.plot(y[top] * 1e3, dz[top] * 1e3)
    a1.set(xlabel="|y| [mm]", ylabel="z(CN60) - z(60E1) [mm]",
           title="height difference, |y| <= 34 mm")
    a2.set(xlabel="|y| [mm]", ylabel="surface angle [deg]", title="inclination of the head")
    for a in (a0, a1, a2):
        a.grid(alpha=0.3)
    a0.legend(fontsize=8)
    a2.legend(fontsize=8)
    fig.savefig(args.out, dpi=70)
    print(f"written {args.out}")


if __name__ == "__main__":
    main()
