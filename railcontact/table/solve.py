"""Solving the points of a table: one batch, run along the fastest axis, each point started
from the one before it.

A point is the case of ``railcontact solve`` with the axes' values, one wheel at a time (so
that each wheel has its own status), by :func:`railcontact.contact.wheelrail.solve_wheel_rail`.
The first point of a batch starts as the case says (its estimates), exactly as
``railcontact solve``; every later point starts from the previous point's solution, the
time loop's previous-step start (:mod:`railcontact.timestep.warmstart`): the pressure of
the patch at the nearest contact point in patch coordinates, re-meshed onto the new
patch's own grid (the grid is the one a cold solve meshes, so only the start differs),
and its traction and adhesion/slip map for the tangential BEM. A warm-started point
therefore equals a cold solve to the solvers' tolerances (``[normal] tolerance``,
``[tangential] tolerance``), not bit for bit; the batches are fixed by the spec (not by the
workers), so a table is the same however many workers build it and however often it is
resumed.

A point that fails from the previous point's start (not converged, or any failure but no
contact) is not stored so: it is solved again cold, as ``railcontact solve`` does, and when
that fails too, cold from the simplified models' estimates the exact step falls back on
(:class:`~railcontact.settings.ContactSettings`' ``normal_estimate`` and
``tangential_estimate``; on the flange the load loop meets the load from them where it
stalls at the tangential BEM's noise floor from the case's own start). Only a point that
fails all of these is stored with its failure; every start is deterministic, so the table
stays the same across workers and resumes. :data:`STARTS` names the starts.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from ..contact.patch import normal_estimate
from ..contact.start import NormalStart, TangentialStart, WarmStart
from ..contact.wheelrail import solve_wheel_rail
from ..errors import CaseError, RailContactError, SolverError
from ..geometry.points import samples
from ..settings import Case, ContactSettings
from ..status import status_of
from ..timestep.results import WheelContact, resultants
from ..timestep.warmstart import PatchMemory, match, previous_pressure, previous_tangential
from .spec import case_with
from .variables import COUNTS, NO_CONTACT, OK, OUT_OF_RANGE, QUANTITIES

STARTS = ("warm", "cold", "estimate")
"""The starts a point is solved from, in order, until one succeeds: the previous point's
solution (not for a batch's first point), the case's own (``railcontact solve``), the
exact step's simplified-model estimates (:func:`estimate_case`)."""


def _memory(patches) -> list[PatchMemory]:
    """What a solved point keeps to start the next (as a time step does)."""
    out = []
    for p in patches:
        t, cp = p.tangential, p.geometry
        out.append(PatchMemory(grid=p.normal.grid, pressure=p.normal.pressure,
                               traction=getattr(t, "traction", None),
                               state=getattr(t, "state", None),
                               u=cp.rail_u, z=cp.position[2],
                               element_box=p.normal.contact_box))
    return out


def _starts(case: Case, memory: list[PatchMemory]):
    """``starts(side)`` for :func:`solve_wheel_rail` from the previous point's patches."""
    normal, pair = case.normal, case.pair

    def estimate_for(cp, hz, control) -> WarmStart:
        m = match(memory, cp.rail_u, cp.position[2])
        cold = normal_estimate(normal, hz, *samples(cp)[:3], pair, control)
        if m is None:
            return cold

        def pressure_on(grid) -> NormalStart:
            p = previous_pressure(m, grid)
            return NormalStart(p) if p.sum() > 0 else cold.pressure_on(grid)

        def traction_on(grid) -> TangentialStart | None:
            t, st = previous_tangential(m, grid)
            return None if t is None else TangentialStart(t, st)
        return WarmStart("previous", pressure_on, traction_on=traction_on)

    return lambda side: estimate_for


def solve_point(case: dict[str, Any], side: str, memory: list[PatchMemory] | None = None
                ) -> tuple[WheelContact, list[PatchMemory]]:
    """One wheel of one grid point: its result with an honest status, and its memory.

    ``memory`` (the previous point's) starts the solve; None: a cold start, as
    ``railcontact solve``. A point that cannot be solved has status not converged
    (a load loop that failed) or out of range (any other error of the case, or any other
    exception of the solver, its message naming the exception), no contact when the wheel
    does not touch its rail; it is never an exception.
    """
    try:
        c = Case.from_dict(case_with(case, {}, side))
        patches, pose = solve_wheel_rail(c, _starts(c, memory) if memory else None,
                                          frictional_power=False)
    except (RailContactError, SolverError) as exc:  # a load loop, a case, the geometry
        text = str(exc)  # (a case's and a load loop's messages name the wheel already)
        return WheelContact(side=side, status=status_of(exc), message=(
            text if isinstance(exc, (CaseError, SolverError)) else f"{side} wheel: {text}")
        ), []
    except Exception as exc:  # a fault of the solver: this point lost, never the batch
        return WheelContact(side=side, status=OUT_OF_RANGE, message=(
            f"{side} wheel: the solver failed here ({type(exc).__name__}: {exc})")), []
    if not patches:
        return WheelContact(side=side), []
    values = resultants(side, patches, pose)
    if c.tangential is not None:
        values["creepages"] = [tuple(c.tangential.creepage)] * len(patches)
    return WheelContact(**values), _memory(patches)


def estimate_case(case: dict[str, Any]) -> dict[str, Any] | None:
    """The case with the estimates the exact step falls back on (the defaults of
    :class:`~railcontact.settings.ContactSettings`: the normal and, with creepages, the
    tangential one); None when the case already starts from them."""
    defaults = ContactSettings()
    want = {"normal": defaults.normal_estimate, "tangential": defaults.tangential_estimate}
    out = {k: dict(v) if isinstance(v, dict) else v for k, v in case.items()}
    changed = False
    for table, estimate in want.items():
        if isinstance(out.get(table), dict) and out[table].get("estimate") != estimate:
            out[table]["estimate"] = estimate
            changed = True
    return out if changed else None


def solve_recovering(case: dict[str, Any], side: str, memory: list[PatchMemory] | None = None
                     ) -> tuple[WheelContact, list[PatchMemory], str]:
    """:func:`solve_point` from each start of :data:`STARTS` in turn until the wheel is ok
    or has no contact: its result, its memory and the start that gave it (the last one
    tried when none succeeded; its failure is then the wheel's status and message)."""
    tries: list[tuple[str, dict[str, Any], list[PatchMemory] | None]] = []
    if memory:
        tries.append(("warm", case, memory))
    tries.append(("cold", case, None))
    est = estimate_case(case)
    if est is not None:
        tries.append(("estimate", est, None))
    for how, c, mem in tries:
        wheel, new = solve_point(c, side, mem)
        if wheel.status in (OK, NO_CONTACT):
            return wheel, new, how
    if len(tries) > 1:
        starts = ", ".join(t[0] for t in tries)
        wheel = replace(wheel, message=f"{wheel.message} (solved from each start: {starts})")
    return wheel, new, how


def solve_batch(case: dict[str, Any], sides: tuple[str, ...],
                points: list[dict[str, float]]) -> dict[str, Any]:
    """Solve the points (axis name -> value, in order along the fastest axis) for each wheel.

    Returns
    -------
    dict
        Each quantity of :data:`~.variables.QUANTITIES` and :data:`~.variables.COUNTS` as an
        array (points, sides); ``status`` (int8) likewise; ``messages``: the message of
        every point that is not ok, as ``(point, side, status, message)``; ``seconds``
        and ``cpu_seconds``: the batch's wall and CPU time in its worker [s];
        ``recovered``: the points that failed from the previous point's start (or, a
        batch's first, from the case's) and were solved from a later start of
        :data:`STARTS`, as ``(point, side, start)``. A quantity that a point does not define
        (its geometry without contact, anything after an error) is NaN, always with a
        non-zero status.
    """
    t0, c0 = time.perf_counter(), time.process_time()
    shape = (len(points), len(sides))
    out: dict[str, Any] = {q.name: np.full(shape, np.nan) for q in QUANTITIES}
    out.update({q.name: np.zeros(shape, dtype=np.int32) for q in COUNTS})
    out["status"] = np.zeros(shape, dtype=np.int8)
    out["messages"] = []
    out["recovered"] = []
    for j, side in enumerate(sides):
        memory: list[PatchMemory] = []
        for i, values in enumerate(points):
            first = "warm" if memory else "cold"
            wheel, memory, how = solve_recovering(case_with(case, values), side, memory)
            if how != first and wheel.status in (OK, NO_CONTACT):
                out["recovered"].append((i, side, how))
            out["status"][i, j] = wheel.status
            if wheel.status != 0:
                out["messages"].append((i, side, int(wheel.status), wheel.message))
            if wheel.patches or wheel.status == NO_CONTACT:
                for q in QUANTITIES:
                    if wheel.patches or not q.geometric:
                        out[q.name][i, j] = q.read(wheel)
            for q in COUNTS:
                out[q.name][i, j] = q.read(wheel)
    out["seconds"] = time.perf_counter() - t0
    out["cpu_seconds"] = time.process_time() - c0
    return out
