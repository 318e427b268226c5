"""A table's summary (axes, ranges, statuses, failed points, the interpolation error of
its check) and plots (forces against each
axis, a heat map over two axes)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import RailContactError
from .check import check_text
from .creepread import creep_figure, creep_summary, is_creep_table
from .geometry import KIND
from .geometry_table import plot_geometry, summary_lines
from .refine import Targets, jumps
from .spec import CREEPAGE_AXES, DEFAULT_POLICY, axis_info
from .store import (
    IDENTITY,
    check_contact_dataset,
    kind_of,
    open_dataset,
    read_messages,
    require_status,
)
from .variables import STATUS_MEANINGS, failed_counts, failed_text

SHOWN = ("normal_force", "creep_force_x", "creep_force_y", "spin_moment", "contact_angle",
         "max_pressure")
GEOMETRY_SHOWN = ("rolling_radius", "contact_angle", "wheel_position", "rail_position")
"""The per-wheel quantities a geometry table's summary shows."""
MAX_MESSAGES = 10


def summary(path: str | Path) -> str:
    """The text of ``railcontact table show``."""
    ds = open_dataset(path)
    if is_creep_table(ds):
        return creep_summary(path)
    require_status(path, ds)
    check_contact_dataset(path, ds)
    ident = json.loads(ds.attrs[IDENTITY])
    names = list(ident["axes"])
    done = ds["batch_done"].values
    status = ds["status"].values
    lines = [f"table {path}: case '{ds.attrs.get('case_name')}', railcontact "
             f"{ds.attrs.get('railcontact_version')}",
             f"{status[..., 0].size} points x {ds.sizes['side']} wheel(s) "
             f"({', '.join(ds['side'].values.tolist())}); batches done "
             f"{int(done.sum())}/{done.size} along '{names[-1]}' (fastest axis)"
             + ("" if done.all() else " - incomplete: rerun with --resume")]
    failed = failed_counts(status)
    if failed:
        lines.append(f"WARNING: {failed_text(failed)}: holes of the table, where "
                     "interpolation returns the status, not a value (listed below)")
    lines.append("axes (out of range: the policy of a value outside the axis):")
    policies = json.loads(ds.attrs.get("out_of_range", "{}"))
    for n in names:
        v = ds[n].values
        lines.append(f"  {n:22s} [{axis_info(n).unit}] {len(v):5d} from {v[0]:.6g} to {v[-1]:.6g}"
                     f"; out of range: {policies.get(n, DEFAULT_POLICY)}")
    lines.append("status:")
    for j, side in enumerate(ds["side"].values.tolist()):
        counts = {STATUS_MEANINGS[int(k)]: int(c)
                  for k, c in zip(*np.unique(status[..., j], return_counts=True), strict=True)}
        lines.append(f"  {side:6s} " + ", ".join(f"{k} {c}" for k, c in counts.items()))
    lines += _jump_lines(ds, names, status)
    if kind_of(ds.attrs) == KIND:
        lines += summary_lines(ds)
    lines.append("values (ok points):" if kind_of(ds.attrs) != KIND else
                 "values of the first contacts (ok wheels):")
    ok = status == 0
    for name in SHOWN if kind_of(ds.attrs) != KIND else GEOMETRY_SHOWN:
        x = ds[name].values[ok]
        if x.size:
            lines.append(f"  {name:16s} [{ds[name].attrs.get('units', '')}] from "
                         f"{x.min():.6g} to {x.max():.6g}")
    for k, r in enumerate(json.loads(ds.attrs.get("refinement", "[]")), 1):
        lines.append(f"refined, round {k}: " + "; ".join(
            f"{n} +{len(v)} node(s)" for n, v in r["added"].items()) + " (by error: "
            + (", ".join(f"{n} {c}" for n, c in r["by_error"].items()) or "none")
            + "; by contact jump: "
            + (", ".join(f"{n} {c}" for n, c in r["by_jump"].items()) or "none")
            + " interval(s))")
    lines += check_text(path)
    msgs = read_messages(path)
    if msgs:
        lines.append(f"points not ok ({len(msgs)}; first {min(len(msgs), MAX_MESSAGES)}):")
        for m in msgs[:MAX_MESSAGES]:
            at = ", ".join(f"{k} = {v:.6g}" for k, v in m["point"].items())
            lines.append(f"  {at}, {m['side']}: {STATUS_MEANINGS.get(m['status'])}: "
                         f"{m['message']}")
    return "\n".join(lines)


def _jump_lines(ds, names: list[str], status: np.ndarray) -> list[str]:
    """Where the contact jumps between neighbouring nodes (:func:`~.refine.jumps` at the
    default :class:`~.refine.Targets`): a line per axis, none without jumps."""
    if "n_patches" not in ds or "contact_angle" not in ds:
        return []
    limit = Targets().jump_angle
    found = jumps({n: ds[n].values for n in names}, status, ds["n_patches"].values,
                  ds["contact_angle"].values, limit)
    out = []
    for n, flags in found.items():
        k = np.flatnonzero(flags)
        if k.size:
            v = ds[n].values
            where = ", ".join(f"{v[i]:.6g}..{v[i + 1]:.6g}" for i in k[:4])
            out.append(f"  {n}: {k.size} of {flags.size} interval(s) ({where}"
                       + (", ..." if k.size > 4 else "") + f") [{axis_info(n).unit}]")
    if out:
        out.insert(0, f"contact jumps between neighbouring nodes (patch count, contact angle "
                      f"step > {limit * 1e3:g} mrad, contact appearing): the interpolation "
                      "there is coarse " + (
                          "(more nodes there: a finer axis in the spec):"
                          if kind_of(ds.attrs) == KIND else
                          "('railcontact table check' measures it, 'railcontact "
                          "table refine' adds nodes):"))
    return out


def plot_table(path: str | Path, out: str | Path) -> Path:
    """Write the forces of the left (first) wheel against each axis (the other axes at
    their middle nodes) and a heat map over two axes (the first two creepage axes, else the
    first two axes) of the creep force's magnitude (of the normal force without
    creepages) to ``out``; of a creep table, its creep curves
    (:func:`~.creepread.creep_figure`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ds = open_dataset(path)
    out = Path(out)
    if not out.parent.is_dir():
        raise RailContactError(f"--plot: folder {out.parent} does not exist")
    if is_creep_table(ds):
        return _save(creep_figure(ds), out, plt)
    names = list(json.loads(ds.attrs[IDENTITY])["axes"])
    if kind_of(ds.attrs) == KIND:
        fig = plot_geometry(ds, names, out)
        return _save(fig, out, plt)
    ok = ds["status"] == 0
    side = ds["side"].values[0]
    multi = [n for n in names if ds.sizes[n] > 1]
    ncols = len(multi) + (1 if len(multi) >= 2 else 0)
    if not ncols:
        raise RailContactError("the table has one point: nothing to plot")
    fig, axs = plt.subplots(1, ncols, figsize=(4.2 * ncols, 3.6), squeeze=False)
    for k, n in enumerate(multi):
        ax = axs[0, k]
        mid = {m: ds.sizes[m] // 2 for m in names if m != n}
        for q in ("normal_force", "creep_force_x", "creep_force_y"):
            y = ds[q].where(ok).isel(mid).sel(side=side)
            ax.plot(ds[n].values, y.values, "o-", ms=3, label=q)
        ax.set_xlabel(f"{n} [{axis_info(n).unit}]")
        ax.set_ylabel("force [N]")
        ax.set_title(f"{side} wheel; others at middle", fontsize=8)
        ax.grid(alpha=0.3)
    axs[0, 0].legend(fontsize=7)
    if len(multi) >= 2:
        creep = [n for n in multi if n in CREEPAGE_AXES]
        a, b = (creep[0], creep[1]) if len(creep) >= 2 else (multi[0], multi[1])
        mid = {m: ds.sizes[m] // 2 for m in names if m not in (a, b)}
        cut = ds.where(ok).isel(mid).sel(side=side)
        if creep:  # the creep force's magnitude
            z, q = np.hypot(cut["creep_force_x"], cut["creep_force_y"]), "|F| creep"
        else:
            z, q = cut["normal_force"], "normal force"
        z = z.transpose(b, a)
        ax = axs[0, -1]
        m = ax.pcolormesh(ds[a].values, ds[b].values, z.values, shading="nearest")
        fig.colorbar(m, ax=ax, label=f"{q} [N]")
        ax.set_xlabel(f"{a} [{axis_info(a).unit}]")
        ax.set_ylabel(f"{b} [{axis_info(b).unit}]")
        ax.set_title(f"{q}, {side} wheel; others at middle", fontsize=8)
    fig.tight_layout()
    return _save(fig, out, plt)


def _save(fig, out: Path, plt) -> Path:
    try:
        fig.savefig(out, dpi=90)
    except (ValueError, OSError) as exc:
        raise RailContactError(f"--plot: cannot write {out}: {exc}") from None
    finally:
        plt.close(fig)
    return out
