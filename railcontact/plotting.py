"""Figures. matplotlib is imported lazily (headless Agg backend)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .pipeline import Solution


def plot_normal(solution: Solution, path: str | Path, patch: int = 0) -> Path:
    """Contact patch and pressure map, and the y = 0 pressure cut against Hertz.

    Parameters
    ----------
    solution
        A solved case.
    path
        Output image file (format from the extension, e.g. ``.png``, ``.pdf``).
    patch
        Index of the patch to draw.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ps = solution.patches[patch]
    res, hz = ps.normal, ps.hertz
    g = res.grid
    xmin, xmax, ymin, ymax = g.bounds
    mm, mpa = 1e3, 1e-6
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    xe = np.linspace(xmin, xmax, g.nx + 1) * mm
    ye = np.linspace(ymin, ymax, g.ny + 1) * mm
    pm = np.ma.masked_where(~res.contact, res.pressure)
    im = ax0.pcolormesh(xe, ye, pm.T * mpa, cmap="viridis", shading="flat")
    fig.colorbar(im, ax=ax0, label="pressure [MPa]")
    if hz is not None and hz.load > 0:
        t = np.linspace(0, 2 * np.pi, 200)
        ax0.plot(hz.a * np.cos(t) * mm, hz.b * np.sin(t) * mm, "r--", lw=1.2, label="Hertz")
        ax0.legend(loc="upper right", fontsize=8)
    ax0.set_xlabel("x (rolling) [mm]")
    ax0.set_ylabel("y (lateral) [mm]")
    ax0.set_aspect("equal")
    ax0.set_title(f"BEM patch: {res.iterations} iterations, "
                  f"N = {res.force / 1e3:.2f} kN, estimate {ps.estimate}")

    j0 = int(np.argmin(np.abs(g.y)))
    ax1.step(g.x * mm, res.pressure[:, j0] * mpa, where="mid", label="BEM (element values)")
    if hz is not None:
        xf = np.linspace(xmin, xmax, 400)
        ax1.plot(xf * mm, hz.pressure(xf, np.full_like(xf, g.y[j0])) * mpa, "k--",
                 label="Hertz")
    ax1.set_xlabel("x [mm]")
    ax1.set_ylabel("pressure [MPa]")
    ax1.set_title(f"cut at y = {g.y[j0] * mm:.3f} mm")
    ax1.legend()
    ax1.grid(alpha=0.3)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=130)
    plt.close(fig)
    return out
