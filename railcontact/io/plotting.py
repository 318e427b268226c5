"""Figures. matplotlib is imported lazily (headless Agg backend)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..contact import Solution, simplified_tangential
from ..errors import RailContactError

MM, MPA = 1e3, 1e-6


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _pressure_panels(fig, ax0, ax1, ps) -> None:
    res, hz = ps.normal, ps.hertz
    g = res.grid
    xmin, xmax, ymin, ymax = g.bounds
    xe = np.linspace(xmin, xmax, g.nx + 1) * MM
    ye = np.linspace(ymin, ymax, g.ny + 1) * MM
    pm = np.ma.masked_where(~res.contact, res.pressure)
    im = ax0.pcolormesh(xe, ye, pm.T * MPA, cmap="viridis", shading="flat")
    fig.colorbar(im, ax=ax0, label="pressure [MPa]")
    if hz is not None and hz.load > 0:
        t = np.linspace(0, 2 * np.pi, 200)
        ax0.plot(hz.a * np.cos(t) * MM, hz.b * np.sin(t) * MM, "r--", lw=1.2, label="Hertz")
        ax0.legend(loc="upper right", fontsize=8)
    ax0.set_xlabel("x (rolling) [mm]")
    ax0.set_ylabel("y (lateral) [mm]")
    ax0.set_aspect("equal")
    ax0.set_title(f"BEM patch: {res.iterations} iterations, "
                  f"N = {res.force / 1e3:.2f} kN, estimate {ps.estimate}", fontsize=10)
    j0 = int(np.argmin(np.abs(g.y)))
    ax1.step(g.x * MM, res.pressure[:, j0] * MPA, where="mid", label="BEM (element values)")
    if hz is not None:
        xf = np.linspace(xmin, xmax, 400)
        ax1.plot(xf * MM, hz.pressure(xf, np.full_like(xf, g.y[j0])) * MPA, "k--",
                 label="Hertz")
    ax1.set_xlabel("x [mm]")
    ax1.set_ylabel("pressure [MPa]")
    ax1.set_title(f"pressure at y = {g.y[j0] * MM:.3f} mm", fontsize=10)
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)


def _traction_panels(fig, ax0, ax1, sol: Solution, ps) -> None:
    from matplotlib.colors import ListedColormap

    tan, res = ps.tangential, ps.normal
    tangential = sol.case.tangential
    g = res.grid
    xmin, xmax, ymin, ymax = g.bounds
    # a friction table's mu at the patch's reference point
    mu = tangential.friction if ps.friction is None else ps.friction
    if ps.tangential_model == "bem":
        xe = np.linspace(xmin, xmax, g.nx + 1) * MM
        ye = np.linspace(ymin, ymax, g.ny + 1) * MM
        cmap = ListedColormap(["white", "tab:blue", "tab:orange"])
        ax0.pcolormesh(xe, ye, tan.state.T, cmap=cmap, vmin=-0.5, vmax=2.5, shading="flat")
        X, Y = g.mesh()
        step = max(1, g.nx // 24), max(1, g.ny // 16)
        sl = (slice(None, None, step[0]), slice(None, None, step[1]))
        inside = tan.state[sl] != 0
        ax0.quiver(X[sl][inside] * MM, Y[sl][inside] * MM, tan.traction[0][sl][inside] * MPA,
                   tan.traction[1][sl][inside] * MPA,
                   pivot="mid", scale_units="xy", angles="xy",
                   scale=max(float(np.abs(tan.traction).max()) * MPA, 1e-12)
                   / (2.5 * max(step[0] * g.dx, step[1] * g.dy) * MM))
        ax0.set_title(f"BEM: adhesion (blue) / slip (orange), {tan.iterations} sweeps, "
                      f"slip {tan.slip_area_ratio:.0%}", fontsize=10)
    else:
        s = tan.strips
        ax0.scatter(s.x.ravel() * MM, np.repeat(s.y, s.nx) * MM, c=tan.state.ravel(),
                    cmap=ListedColormap(["white", "tab:blue", "tab:orange"]), vmin=-0.5,
                    vmax=2.5, s=6)
        ax0.set_title(f"{ps.tangential_model}: adhesion (blue) / slip (orange)", fontsize=10)
    ax0.set_xlim(xmin * MM, xmax * MM)
    ax0.set_ylim(ymin * MM, ymax * MM)
    ax0.set_aspect("equal")
    ax0.set_xlabel("x (rolling) [mm]")
    ax0.set_ylabel("y (lateral) [mm]")

    # traction along y = 0: BEM vs FASTSIM vs FaStrip (on the Hertz ellipse of the BEM force)
    j0 = int(np.argmin(np.abs(g.y)))
    if ps.tangential_model == "bem":
        ax1.step(g.x * MM, tan.traction[0, :, j0] * MPA, where="mid", label="BEM $p_x$")
    ax1.step(g.x * MM, mu * res.pressure[:, j0] * MPA, "k:", where="mid", label=r"$\mu p_n$")
    ax1.step(g.x * MM, -mu * res.pressure[:, j0] * MPA, "k:", where="mid")
    if res.force > 0:
        from ..halfspace.hertz import hertz

        pair = sol.case.pair
        hz = hertz(*ps.curvatures, pair, load=res.force)
        for model, style in (("fastsim", "--"), ("fastrip", "-.")):
            r = simplified_tangential(model, hz, pair, tangential,
                                      res if ps.geometry is not None else None, friction=mu)
            k = int(np.argmin(np.abs(r.strips.y)))
            ax1.plot(r.strips.x[k] * MM, r.traction[0, k] * MPA, style,
                     label=f"{'FASTSIM' if model == 'fastsim' else 'FaStrip'} $p_x$")
    ax1.set_xlabel("x [mm]")
    ax1.set_ylabel("traction [MPa]")
    cr = tangential.creepage
    ax1.set_title(f"traction near y = 0; creepage ({cr[0]:g}, {cr[1]:g}, {cr[2]:g} 1/m), "
                  f"mu = {mu:g}", fontsize=10)
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)


def plot_solution(solution: Solution, path: str | Path, patch: int = 0) -> Path:
    """Patch and pressure map with the y = 0 cut against Hertz; with a tangential solution
    also the adhesion/slip map with traction arrows and the traction along y = 0 for the
    BEM, FASTSIM and FaStrip.

    Parameters
    ----------
    solution
        A solved case.
    path
        Output image file (format from the extension, e.g. ``.png``, ``.pdf``); patch K >= 1
        is drawn to ``NAME-patchK.EXT`` beside it (:func:`patch_plot_path`).
    patch
        Index of the patch to draw.

    Returns
    -------
    Path
        The file written.
    """
    plt = _pyplot()
    ps = solution.patches[patch]
    if ps.tangential is None:
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
        _pressure_panels(fig, *axes, ps)
    else:
        fig, axes = plt.subplots(2, 2, figsize=(12, 8.5), constrained_layout=True)
        _pressure_panels(fig, axes[0, 0], axes[0, 1], ps)
        _traction_panels(fig, axes[1, 0], axes[1, 1], solution, ps)
    if len(solution.patches) > 1:  # (which one this is: each patch has its own figure)
        side = "" if ps.geometry is None else f", {ps.geometry.side} wheel"
        fig.suptitle(f"patch {patch} of {len(solution.patches)}{side}", fontsize=11)
    # (room between the columns: the colour bar's label beside the right panel's axis label)
    fig.get_layout_engine().set(wspace=0.08)
    out = patch_plot_path(path, patch)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def patch_plot_path(path: str | Path, patch: int) -> Path:
    """The file of patch ``patch``'s figure for ``path`` (:func:`plot_path`): ``path``
    itself for patch 0, ``NAME-patchK.EXT`` beside it for patch K >= 1 (a case with
    several patches: two sides, or tread and flange)."""
    out = plot_path(path)
    return out if patch == 0 else out.with_name(f"{out.stem}-patch{patch}{out.suffix}")


def plot_path(path: str | Path) -> Path:
    """The file a figure for ``path`` is written to (``.png`` added when it has no
    extension), checked before anything is solved.

    Raises
    ------
    RailContactError
        For a directory, or an extension matplotlib cannot write.
    """
    out = Path(path)
    if out.is_dir():
        raise RailContactError(f"--plot {path}: is a directory; give a file name such as "
                               f"{out / 'patch.png'}")
    if not out.suffix:
        out = out.with_suffix(".png")
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    formats = FigureCanvasAgg.get_supported_filetypes()
    if out.suffix[1:].lower() not in formats:
        raise RailContactError(f"--plot {path}: cannot write {out.suffix!r} figures; use one "
                               f"of {', '.join('.' + f for f in sorted(formats))}")
    return out

