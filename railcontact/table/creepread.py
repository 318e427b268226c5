"""Reading a normalised creep table (:mod:`.creep`): forces of a physical contact state by
interpolation (:class:`CreepTable`, as FASTSIM's USETAB reads Kalker's book of tables),
its summary, export and creep-curve plot.

The interpolation is multilinear in ``ln(a/b)`` and the normalised creepages (nu_x, nu_y,
psi), on the nodes of status ok; a state outside an axis follows the axis's
out-of-range policy (``status``: an error naming the axis; ``clamp``: the axis's nearest
end, the result saying which axes were clamped).
"""

from __future__ import annotations

import csv
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import RailContactError, check_number
from .creep import COEFFICIENT_STATUS, COEFFICIENTS, OUTPUTS
from .creepspec import CREEP_AXES, CREEPAGES, KIND, RATIO, scales
from .spec import DEFAULT_POLICY
from .store import IDENTITY, POLICY_ATTR, kind_of, open_dataset, reader_of

POISSON_TOLERANCE = 1e-6
"""Largest difference between a state's Poisson's ratio and the table's [-]."""
SYMBOLS = {"creepage_x": "nu_x", "creepage_y": "nu_y", "spin": "psi"}
EDGE = 1e-12
"""Relative distance beyond an axis's end still on it (round-off of the normalisation)."""


def is_creep_table(ds) -> bool:
    """Whether an opened table (xarray Dataset) is a creep table."""
    return kind_of(ds.attrs) == KIND


@dataclass(frozen=True)
class CreepForces:
    """The forces of one contact state from a creep table (SI units; forces on body 1).

    Attributes
    ----------
    force_x, force_y
        Longitudinal and lateral creep forces F_x, F_y [N].
    moment_z
        Spin moment M_z [N m].
    normalised
        (F_x/(mu N), F_y/(mu N), M_z/(mu N c)) [-] read from the table.
    creepages
        The state's normalised creepages (nu_x, nu_y, psi) [-] and ellipse ratio a/b.
    clamped
        The axes whose value was outside the table and clamped to its end.
    """

    force_x: float
    force_y: float
    moment_z: float
    normalised: tuple[float, float, float]
    creepages: dict[str, float]
    clamped: tuple[str, ...] = ()


class CreepTable:
    """A creep table read into memory, interpolated per state.

    Parameters
    ----------
    path
        The Zarr store of ``railcontact table build`` with a ``kind = "creep"`` spec.

    Raises
    ------
    RailContactError
        When there is no creep table at ``path``.
    """

    def __init__(self, path: str | Path):
        ds = open_dataset(path)
        if not is_creep_table(ds):
            kind = kind_of(ds.attrs)
            raise RailContactError(f"{path} is a {kind} table, not a creep table: read it "
                                   f"with {reader_of(kind)}")
        self.path = Path(path)
        self.names = list(json.loads(ds.attrs[IDENTITY])["axes"])
        self.axes = {n: np.asarray(ds[n].values, dtype=float) for n in self.names}
        self.poisson = float(ds.attrs["poisson"])
        pol = json.loads(ds.attrs.get(POLICY_ATTR, "{}"))
        self.policies = {n: pol.get(n, DEFAULT_POLICY) for n in self.names}
        self.values = {n: np.asarray(ds[n].values, dtype=float) for n in
                       ("force_x", "force_y", "moment_z")}
        self.status = np.asarray(ds["status"].values)
        self.coefficients = {n: np.asarray(ds[n].values, dtype=float) for n in COEFFICIENTS}

    def normalised(self, state: dict[str, float]) -> tuple[np.ndarray, tuple[str, ...]]:
        """(F_x/(mu N), F_y/(mu N), M_z/(mu N c)) at a normalised state (axis name ->
        value; ``ellipse_ratio`` a/b, the creepage axes [-]; an axis the table lacks must
        be 0 or absent), and the axes clamped.

        Raises
        ------
        RailContactError
            For a value not finite or an ellipse ratio not > 0 (whatever the policy), a
            value outside an axis of policy ``status``, a creepage the table has no axis
            for, or a node not ok around the state.
        """
        if not isinstance(state, Mapping):
            raise RailContactError(f"creep table {self.path}: a state is a mapping of axis "
                                   f"name to value, got {state!r}")
        state = {n: check_number(f"creep table {self.path}: {n}", v)
                 for n, v in state.items()}
        for n, v in state.items():
            if not np.isfinite(v):
                raise RailContactError(f"creep table {self.path}: {n} must be finite, "
                                       f"got {v!r}")
        if RATIO not in state:
            raise RailContactError(f"creep table {self.path}: give {RATIO} (a/b)")
        if not state[RATIO] > 0.0:
            raise RailContactError(f"creep table {self.path}: {RATIO} (a/b) must be > 0, "
                                   f"got {state[RATIO]!r}")
        for n, v in state.items():
            if n not in self.axes and v != 0.0:
                raise RailContactError(f"creep table {self.path}: no {n} axis (its value "
                                       f"is 0 in the table), got {v:g}")
        weights: list[tuple[int, int, float]] = []
        clamped = []
        for n in self.names:
            x = self.axes[n]
            v = float(state.get(n, 0.0))
            lo, hi = x[0], x[-1]
            tol = EDGE * max(abs(lo), abs(hi), 1.0)
            if not lo - tol <= v <= hi + tol:
                if self.policies[n] != "clamp":
                    raise RailContactError(
                        f"creep table {self.path}: {n} = {v:.6g} is outside the table "
                        f"[{lo:.6g}, {hi:.6g}] ({CREEP_AXES[n][1]}; out_of_range "
                        f"'{self.policies[n]}')")
                clamped.append(n)
            v = min(max(v, lo), hi)
            if len(x) == 1:
                weights.append((0, 0, 0.0))
                continue
            t = np.log(x) if n == RATIO else x
            u = np.log(v) if n == RATIO else v
            i = int(np.clip(np.searchsorted(t, u, side="right") - 1, 0, len(t) - 2))
            weights.append((i, i + 1, float((u - t[i]) / (t[i + 1] - t[i]))))
        out = np.zeros(3)
        for corner in np.ndindex(*(2,) * len(weights)):
            w, index = 1.0, []
            for (i, j, f), k in zip(weights, corner, strict=True):
                w *= f if k else 1.0 - f
                index.append(j if k else i)
            if w == 0.0:
                continue
            ix = tuple(index)
            if self.status[ix] != 0:
                at = ", ".join(f"{n} = {self.axes[n][k]:.6g}"
                               for n, k in zip(self.names, ix, strict=True))
                raise RailContactError(f"creep table {self.path}: the node {at} did not "
                                       "converge (a hole of the table)")
            out += w * np.array([self.values[q][ix] for q in ("force_x", "force_y",
                                                                 "moment_z")])
        return out, tuple(clamped)

    def forces(self, a: float, b: float, load: float, friction: float, shear: float,
               xi: float, eta: float, phi: float, poisson: float | None = None
               ) -> CreepForces:
        """The creep forces of a Hertzian contact.

        Parameters
        ----------
        a, b
            Semi-axes of the contact ellipse [m], a along the rolling direction.
        load
            Normal force N [N] (> 0).
        friction
            Coefficient of friction mu [-] (> 0).
        shear
            Combined shear modulus G [Pa].
        xi, eta, phi
            Longitudinal and lateral creepage [-], spin [1/m].
        poisson
            The contact's combined Poisson's ratio [-]: must be the table's (None: not
            checked).

        Raises
        ------
        RailContactError
            For a non-positive a, b, load, friction or shear, another Poisson's ratio,
            and as :meth:`normalised`.
        """
        a, b, load, friction, shear, xi, eta, phi = (
            check_number(f"creep table: {what}", v) for what, v in (
                ("a", a), ("b", b), ("load", load), ("friction", friction), ("shear", shear),
                ("xi", xi), ("eta", eta), ("phi", phi)))
        for what, v in (("a", a), ("b", b), ("load", load), ("friction", friction),
                        ("shear", shear)):
            if not (np.isfinite(v) and v > 0.0):
                raise RailContactError(f"creep table: {what} must be a finite number > 0, "
                                       f"got {v!r}")
        for what, v in (("xi", xi), ("eta", eta), ("phi", phi)):
            if not np.isfinite(v):
                raise RailContactError(f"creep table: {what} must be finite, got {v!r}")
        if poisson is not None:
            poisson = check_number("creep table: poisson", poisson)
        if poisson is not None and abs(poisson - self.poisson) > POISSON_TOLERANCE:
            raise RailContactError(f"creep table {self.path} holds Poisson's ratio "
                                   f"{self.poisson:g}; the state has {poisson:g}")
        sc = scales(a, b, load, friction, shear, self.poisson)
        norm = sc.normalised([xi, eta, phi])
        state = {RATIO: a / b, **dict(zip(CREEPAGES, map(float, norm), strict=True))}
        f, clamped = self.normalised(state)
        return CreepForces(force_x=float(f[0] * sc.mu_n), force_y=float(f[1] * sc.mu_n),
                           moment_z=float(f[2] * sc.mu_n * sc.c),
                           normalised=(float(f[0]), float(f[1]), float(f[2])),
                           creepages=state, clamped=clamped)


def creep_summary(path: str | Path) -> str:
    """The text of ``railcontact table show`` for a creep table."""
    ds = open_dataset(path)
    names = list(json.loads(ds.attrs[IDENTITY])["axes"])
    pol = json.loads(ds.attrs.get(POLICY_ATTR, "{}"))
    status = ds["status"].values
    lines = [f"creep table {path}: case '{ds.attrs.get('case_name')}', railcontact "
             f"{ds.attrs.get('railcontact_version')}; Poisson's ratio "
             f"{float(ds.attrs['poisson']):g}",
             f"{status.size} points; normalisation: {ds.attrs.get('normalisation', '')}"]
    bad = int(np.count_nonzero(status))
    if bad:
        lines.append(f"WARNING: {bad} node(s) not converged: holes of the table, where "
                     "interpolation is an error (listed below)")
    lines.append("axes (out of range: the policy of a value outside the axis):")
    for n in names:
        v = ds[n].values
        lines.append(f"  {n:14s} [{CREEP_AXES[n][0]}] {len(v):4d} from {v[0]:.6g} to "
                     f"{v[-1]:.6g}; out of range: {pol.get(n, DEFAULT_POLICY)}")
    cstatus = (ds[COEFFICIENT_STATUS].values if COEFFICIENT_STATUS in ds
               else np.zeros(ds.sizes[RATIO], dtype=np.int8))
    cbad = int(np.count_nonzero(cstatus))
    if cbad:
        lines.append(f"WARNING: the creep coefficients of {cbad} ellipse ratio(s) are NaN: "
                     "a linear-limit solve did not converge (the nodes are kept)")
    lines.append("creep coefficients (exact linear limit; Kalker's Table E.3 in brackets):")
    lines.append(f"  {'a/b':>8s} {'C11':>16s} {'C22':>16s} {'C23':>16s} {'C32':>8s} "
                 f"{'C33':>16s}")
    for k, r in enumerate(ds[RATIO].values):
        c = {n: float(ds[n].values[k]) for n in COEFFICIENTS}
        lines.append(f"  {r:8.4g} " + " ".join(
            f"{c[n]:7.4f} ({c['kalker_' + n]:6.4f})" for n in ("c11", "c22", "c23"))
            + f" {c['c32']:8.4f} {c['c33']:7.4f} ({c['kalker_c33']:6.4f})"
            + ("  not converged" if cstatus[k] else ""))
    for m in json.loads(ds.attrs.get("coefficient_messages", "[]")):
        lines.append(f"  {m}")
    ok = status == 0
    lines.append("values (ok nodes):")
    for n in OUTPUTS:
        x = ds[n].values[ok]
        if x.size:
            lines.append(f"  {n:10s} [{OUTPUTS[n][0]}] from {x.min():.6g} to {x.max():.6g}"
                         f"  ({OUTPUTS[n][1]})")
    msgs = json.loads(ds.attrs.get("messages", "[]"))
    if msgs:
        lines.append(f"nodes not converged ({len(msgs)}; first {min(len(msgs), 10)}):")
        lines += [f"  {m}" for m in msgs[:10]]
    return "\n".join(lines)


def export_creep_csv(ds, out: Path) -> Path:
    """Write the creep table ``ds`` (xarray Dataset) to ``out`` as CSV: a row per node, the
    axes, the values, status, then the creep coefficients of its ellipse ratio."""
    names = list(json.loads(ds.attrs[IDENTITY])["axes"])
    values = {n: ds[n].transpose(*names).values for n in [*OUTPUTS, "status"]}
    coefs = {n: ds[n].values for n in COEFFICIENTS}
    with out.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow([*names, *OUTPUTS, "status", *COEFFICIENTS])
        for index in np.ndindex(*values["status"].shape):
            row = [repr(float(ds[n].values[i])) for n, i in zip(names, index, strict=True)]
            row += [repr(float(values[n][index])) for n in OUTPUTS]
            row.append(str(int(values["status"][index])))
            row += [repr(float(coefs[n][index[0]])) for n in COEFFICIENTS]
            w.writerow(row)
    return out


def creep_figure(ds, ratios: int = 5):
    """The creep curves of the creep table ``ds`` (xarray Dataset; a matplotlib figure, the
    Agg backend chosen by the caller): F_x/(mu N) against nu_x, F_y/(mu N) against nu_y and
    against psi (a panel per creepage axis, the other creepages at their nodes nearest 0),
    one line per ellipse ratio (at most ``ratios``, spread over the axis), with the linear
    theory's ``-3 nu`` dashed."""
    import matplotlib.pyplot as plt

    panels = [(n, q) for n, q in (("creepage_x", "force_x"), ("creepage_y", "force_y"),
                                  ("spin", "force_y")) if n in ds.dims and ds.sizes[n] > 1]
    if not panels:
        raise RailContactError("the creep table has no creepage axis of more than one node: "
                               "no creep curve to plot")
    r = ds[RATIO].values
    pick = sorted({int(round(k)) for k in np.linspace(0, len(r) - 1, min(ratios, len(r)))})
    fig, axs = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 3.6), squeeze=False)
    ok = ds["status"] == 0
    for ax, (n, q) in zip(axs[0], panels, strict=True):
        others = {m: int(np.argmin(np.abs(ds[m].values))) for m in CREEPAGES
                  if m in ds.dims and m != n}
        x = ds[n].values
        for k in pick:
            y = ds[q].where(ok).isel({**others, RATIO: k}).values
            ax.plot(x, y, "o-", ms=3, label=f"a/b = {r[k]:.3g}")
        lin = np.clip(-3.0 * x, -1.0, 1.0)
        ax.plot(x, lin, "k--", lw=0.8, label="linear theory -3 nu (to |f| = 1)")
        at = ", ".join(f"{m} = {float(ds[m].values[i]):.3g}" for m, i in others.items())
        ax.set_xlabel(f"{n} [-] ({SYMBOLS[n]})")
        ax.set_ylabel(f"{q} = F/(mu N) [-]")
        ax.set_title(at or "creep curve", fontsize=8)
        ax.grid(alpha=0.3)
    axs[0, 0].legend(fontsize=7, loc="lower left")
    fig.suptitle(f"creep curves, Poisson's ratio {float(ds.attrs['poisson']):g}", fontsize=9)
    fig.tight_layout()
    return fig
