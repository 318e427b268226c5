"""Building a normalised creep table (:mod:`.creepspec`): the exact BEM (steady rolling,
the case's tangential solver) on the Hertzian patch of each ellipse ratio, at every node of
the normalised creepages, and the creep coefficients of the linear theory.

Each ellipse ratio is one batch (on a Dask client's workers when one is given, else in
this process). The creep coefficients are those of the exact solver's linear limit: the
forces at the normalised creepage :data:`LINEAR_CREEPAGE` (the patch in adhesion but for
less than an element at the trailing edge) divided by ``G c^2`` and ``G c^3`` times the
creepage, Kalker's definition (:mod:`railcontact.tangential.kalker`).

The store is an xarray Dataset in a Zarr store (format 2)::

    dims    ellipse_ratio, then the creepage axes given (creepage_x, creepage_y, spin)
    data    force_x = F_x/(mu N), force_y = F_y/(mu N), moment_z = M_z/(mu N c) [-],
            slip_area (the slipping fraction of the contact area [-]), status (int8: 0 ok,
            1 not converged: the values NaN); over ellipse_ratio alone the creep
            coefficients c11, c22, c23, c32, c33 of the exact solver (NaN where its
            coefficient_status is 1: a linear-limit solve did not converge), kalker_c11,
            kalker_c22, kalker_c23 (Table E.3, the normalisation's), kalker_c33
    attrs   railcontact_table (the identity, JSON), kind = "creep", poisson,
            out_of_range (JSON), railcontact_version, case_name, complete, seconds
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..contact.dispatch import solve
from ..errors import RailContactError
from ..tangential.kalker import creep_coefficients
from .creepspec import CREEP_AXES, CREEPAGES, KIND, RATIO, CreepSpec, case_scales
from .interpolate import TableHolesWarning
from .store import IDENTITY, POLICY_ATTR

KIND_ATTR = "kind"
"""A root attribute repeating the kind for readers of the store or its netCDF export
outside railcontact; railcontact reads a table's kind from its identity
(:func:`~.store.kind_of`)."""
LINEAR_CREEPAGE = 1e-4
"""The normalised creepage [-] of the linear-limit solves giving the creep coefficients."""
OUTPUTS: dict[str, tuple[str, str]] = {
    "force_x": ("1", "longitudinal creep force F_x / (mu N)"),
    "force_y": ("1", "lateral creep force F_y / (mu N)"),
    "moment_z": ("1", "spin moment M_z / (mu N c), c = sqrt(a b)"),
    "slip_area": ("1", "slipping fraction of the contact area"),
}
"""The values per node: name -> (unit, long name)."""
COEFFICIENTS: dict[str, str] = {
    "c11": "creep coefficient C11 = -F_x / (G c^2 xi), exact linear limit",
    "c22": "creep coefficient C22 = -F_y / (G c^2 eta), exact linear limit",
    "c23": "creep coefficient C23 = -F_y / (G c^3 phi), exact linear limit",
    "c32": "creep coefficient C32 = M_z / (G c^3 eta), exact linear limit (= C23)",
    "c33": "creep coefficient C33 = -M_z / (G c^4 phi), exact linear limit",
    "kalker_c11": "Kalker's C11 (Table E.3) of the normalisation of creepage_x",
    "kalker_c22": "Kalker's C22 (Table E.3) of the normalisation of creepage_y",
    "kalker_c23": "Kalker's C23 (Table E.3) of the normalisation of spin",
    "kalker_c33": "Kalker's C33 (the literature's column beside Table E.3; for comparison)",
}
"""The values per ellipse ratio: name -> long name (all dimensionless)."""
COEFFICIENT_STATUS = "coefficient_status"
"""The status of an ellipse ratio's exact creep coefficients (int8: 0 ok, 1 a linear-limit
solve not converged: the exact coefficients NaN)."""
EXACT = ("c11", "c22", "c23", "c32", "c33")
"""The creep coefficients of the exact solver among :data:`COEFFICIENTS`."""


@dataclass
class CreepReport:
    """What a creep table build did (seconds)."""

    points: int
    not_converged: int = 0
    coefficients_failed: int = 0
    seconds: float = 0.0
    messages: list[str] = field(default_factory=list)

    @property
    def rate(self) -> float:
        """Points per second."""
        return self.points / self.seconds if self.seconds > 0 else 0.0


def _solve(case: dict[str, Any]):
    """The patch of a quadratic case and whether it converged (with its message)."""
    sol = solve(case)
    p = sol.patches[0]
    msg = "" if sol.converged else (getattr(p.tangential, "message", "") or
                                    p.normal.message or "not converged")
    return p, sol.converged, msg


def linear_coefficients(spec: CreepSpec, ratio: float) -> dict[str, float]:
    """The creep coefficients C11, C22, C23, C32, C33 of the exact solver at the ellipse
    ratio ``ratio`` (a/b): its forces at the small normalised creepages
    :data:`LINEAR_CREEPAGE` over ``G c^2`` or ``G c^3`` times the creepage (Kalker's
    definition, :mod:`railcontact.tangential.kalker`).

    Raises
    ------
    RailContactError
        When a solve does not converge.
    """
    base = spec.case_at(ratio)
    sc = case_scales(base)
    xi, eta, phi = sc.physical([LINEAR_CREEPAGE] * 3)
    g, c = sc.shear, sc.c
    out = {}
    for k, cr in enumerate([(xi, 0.0, 0.0), (0.0, eta, 0.0), (0.0, 0.0, phi)]):
        p, ok, msg = _solve(spec.case_at(ratio, cr))
        if not ok:
            raise RailContactError(f"creep table, a/b = {ratio:g}: the linear-limit solve "
                                   f"did not converge: {msg}")
        (fx, fy), mz = p.tangential.force, p.tangential.spin_moment
        if k == 0:
            out["c11"] = -fx / (g * c**2 * xi)
        elif k == 1:
            out["c22"] = -fy / (g * c**2 * eta)
            out["c32"] = mz / (g * c**3 * eta)
        else:
            out["c23"] = -fy / (g * c**3 * phi)
            out["c33"] = -mz / (g * c**4 * phi)
    return {**out, **kalker_coefficients(spec, ratio)}


def kalker_coefficients(spec: CreepSpec, ratio: float) -> dict[str, float]:
    """Kalker's C11, C22, C23 (Table E.3, the normalisation's) and C33 at the ellipse ratio
    ``ratio`` (a/b) and the spec's Poisson's ratio (the ``kalker_`` :data:`COEFFICIENTS`)."""
    sc = case_scales(spec.case_at(ratio))
    out = dict(zip(("kalker_c11", "kalker_c22", "kalker_c23"), sc.coefficients,
                   strict=True))
    out["kalker_c33"] = creep_coefficients(sc.a, sc.b, spec.poisson).c33
    return out


def solve_ratio(spec: CreepSpec, ratio: float) -> dict[str, Any]:
    """Every node of the creepage axes at the ellipse ratio ``ratio``, and its creep
    coefficients: the arrays of :data:`OUTPUTS` and ``status`` over the creepage axes,
    the :data:`COEFFICIENTS` (the exact ones NaN when a linear-limit solve does not
    converge) and their :data:`COEFFICIENT_STATUS` with its ``coefficient_message``,
    ``messages`` (node index, text) and ``seconds``."""
    t0 = time.perf_counter()
    names = [n for n in spec.names if n != RATIO]
    shape = tuple(len(spec.axes[n]) for n in names)
    out: dict[str, Any] = {n: np.full(shape, np.nan) for n in OUTPUTS}
    out["status"] = np.zeros(shape, dtype=np.int8)
    out["messages"] = []
    sc = case_scales(spec.case_at(ratio))
    for index in np.ndindex(*shape):
        nodes = {n: float(spec.axes[n][i]) for n, i in zip(names, index, strict=True)}
        norm = [nodes.get(n, 0.0) for n in CREEPAGES]
        p, ok, msg = _solve(spec.case_at(ratio, tuple(sc.physical(norm))))
        if not ok:
            out["status"][index] = 1
            out["messages"].append((list(index), msg))
            continue
        t = p.tangential
        out["force_x"][index] = t.force[0] / sc.mu_n
        out["force_y"][index] = t.force[1] / sc.mu_n
        out["moment_z"][index] = t.spin_moment / (sc.mu_n * sc.c)
        out["slip_area"][index] = t.slip_area_ratio
    try:
        out["coefficients"] = linear_coefficients(spec, ratio)
        out[COEFFICIENT_STATUS], out["coefficient_message"] = 0, ""
    except RailContactError as exc:
        out["coefficients"] = {**dict.fromkeys(EXACT, np.nan),
                               **kalker_coefficients(spec, ratio)}
        out[COEFFICIENT_STATUS], out["coefficient_message"] = 1, str(exc)
    out["seconds"] = time.perf_counter() - t0
    return out


def build_creep_table(spec: CreepSpec, out: str | Path, *, client: Any = None,
                      progress: bool = True, say=None) -> CreepReport:
    """Solve every node of ``spec`` and write the table to the new Zarr store ``out``.

    Parameters
    ----------
    spec
        The creep table.
    out
        The store to create (an existing path is an error: a creep table is built whole).
    client
        A ``distributed.Client`` whose workers solve the ellipse ratios, or None: this
        process.
    progress
        A line per ellipse ratio on stderr.
    say
        Called with those lines; default: print to stderr.

    Raises
    ------
    RailContactError
        When ``out`` exists or its folder does not.

    Warns
    -----
    TableHolesWarning
        When a linear-limit solve does not converge: that ratio's exact creep coefficients
        are NaN (its nodes are kept).
    """
    say = say or (lambda msg: print(msg, file=sys.stderr))
    out = Path(out)
    if out.exists():
        raise RailContactError(f"{out} exists: not overwritten (a creep table is built "
                               "whole; remove it or choose another output)")
    if not out.parent.is_dir():
        raise RailContactError(f"folder {out.parent} does not exist")
    ratios = [float(r) for r in spec.axes[RATIO]]
    report = CreepReport(points=spec.size)
    t0 = time.perf_counter()
    if progress:
        say(f"creep table {out}: {spec.size} points, {len(ratios)} ellipse ratio(s) of "
            f"{spec.size // len(ratios)} point(s) each"
            + (" on the Dask cluster" if client is not None else " in this process"))
    if client is None:
        results = []
        for r in ratios:
            results.append(solve_ratio(spec, r))
            if progress:
                say(f"  a/b = {r:g}: {results[-1]['seconds']:.2f} s")
    else:
        from distributed import as_completed

        futures = {client.submit(solve_ratio, spec, r, pure=False): k
                   for k, r in enumerate(ratios)}
        results = [None] * len(ratios)
        for fut in as_completed(list(futures)):
            k = futures[fut]
            results[k] = fut.result()
            if progress:
                say(f"  a/b = {ratios[k]:g}: {results[k]['seconds']:.2f} s (on a worker)")
    report.seconds = time.perf_counter() - t0
    for r, res in zip(ratios, results, strict=True):
        report.not_converged += int(np.count_nonzero(res["status"]))
        report.messages += [f"a/b = {r:g}, node {ix}: {m}" for ix, m in res["messages"]]
        if res[COEFFICIENT_STATUS]:
            report.coefficients_failed += 1
            report.messages.append(f"{res['coefficient_message']}: its creep coefficients "
                                   "are NaN")
    write_store(spec, out, results, report.seconds)
    if report.coefficients_failed:
        warnings.warn(f"creep table {out}: the creep coefficients of "
                      f"{report.coefficients_failed} ellipse ratio(s) are NaN (a linear-limit "
                      "solve did not converge; 'railcontact table show' lists them)",
                      TableHolesWarning, stacklevel=2)
    return report


def write_store(spec: CreepSpec, out: Path, results: list[dict[str, Any]],
                seconds: float) -> None:
    """Write the solved ellipse ratios ``results`` as the Zarr store ``out``."""
    import xarray as xr

    names = list(spec.names)
    coords = {n: (n, np.asarray(v, dtype=float), {"units": CREEP_AXES[n][0],
                                                  "long_name": CREEP_AXES[n][1]})
              for n, v in spec.axes.items()}
    data = {}
    for n, (unit, long_name) in OUTPUTS.items():
        data[n] = (names, np.stack([r[n] for r in results]),
                   {"units": unit, "long_name": long_name})
    data["status"] = (names, np.stack([r["status"] for r in results]),
                      {"long_name": "status of the node", "flag_values": [0, 1],
                       "flag_meanings": "ok not_converged"})
    for n, long_name in COEFFICIENTS.items():
        data[n] = ([RATIO], np.array([r["coefficients"][n] for r in results]),
                   {"units": "1", "long_name": long_name})
    data[COEFFICIENT_STATUS] = (
        [RATIO], np.array([r[COEFFICIENT_STATUS] for r in results], dtype=np.int8),
        {"long_name": "status of the exact creep coefficients", "flag_values": [0, 1],
         "flag_meanings": "ok linear_limit_not_converged"})
    messages = [f"{RATIO} = {float(spec.axes[RATIO][k]):g}, node {ix}: {m}"
                for k, r in enumerate(results) for ix, m in r["messages"]]
    coefficient_messages = [r["coefficient_message"] for r in results
                            if r[COEFFICIENT_STATUS]]
    ds = xr.Dataset(data, coords=coords, attrs={
        IDENTITY: json.dumps(spec.identity()), KIND_ATTR: KIND,
        "poisson": spec.poisson, POLICY_ATTR: json.dumps(spec.policies()),
        "railcontact_version": __version__, "case_name": spec.case.get("name", "case"),
        "complete": 1, "seconds": seconds, "messages": json.dumps(messages),
        "coefficient_messages": json.dumps(coefficient_messages),
        "normalisation": "nu_x = G c^2 C11 xi/(3 mu N), nu_y = G c^2 C22 eta/(3 mu N), "
                         "psi = G c^3 C23 phi/(3 mu N), c = sqrt(a b), C from Kalker's "
                         "Table E.3 at a/b and poisson; force_x = F_x/(mu N), force_y = "
                         "F_y/(mu N), moment_z = M_z/(mu N c)"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zarr: format 2
        try:
            ds.to_zarr(str(out), mode="w-", zarr_format=2, consolidated=False)
        except (OSError, ValueError) as exc:
            raise RailContactError(f"cannot write {out}: {exc}") from None

