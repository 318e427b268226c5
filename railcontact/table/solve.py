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
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..contact.patch import labelled, normal_estimate
from ..contact.wheelrail import solve_wheel_rail
from ..errors import CaseError, RailContactError
from ..settings import Case
from ..status import status_of
from ..timestep.warmstart import PatchMemory, match, previous_pressure, previous_tangential
from ..timestep.wheelset import WheelContact, _resultants
from .spec import case_with
from .variables import COUNTS, NO_CONTACT, OUT_OF_RANGE, QUANTITIES


def _memory(patches) -> list[PatchMemory]:
    """What a solved point keeps to start the next (as a time step does)."""
    out = []
    for p in patches:
        t, cp = p.tangential, p.geometry
        out.append(PatchMemory(grid=p.normal.grid, pressure=p.normal.pressure,
                               traction=getattr(t, "traction", None),
                               state=getattr(t, "state", None),
                               u=cp.rail_u, z=cp.position[2]))
    return out


def _starts(case: Case, memory: list[PatchMemory]):
    """``starts(side)`` for :func:`solve_wheel_rail` from the previous point's patches."""
    normal, pair = case.normal, case.pair

    def estimate_for(cp, hz, control):
        m = match(memory, cp.rail_u, cp.position[2])
        cold = normal_estimate(normal, hz, cp.s, cp.f, cp.a_of_s, pair, control)
        if m is None:
            return cold

        def of(grid):
            p = previous_pressure(m, grid)
            return p if p.sum() > 0 else cold(grid)
        return labelled(of, "previous")

    def traction_for(patch):
        m = match(memory, patch.geometry.rail_u, patch.geometry.position[2])
        if m is None:
            return None
        t, st = previous_tangential(m, patch.normal.grid)
        return None if t is None else (t, st)

    return lambda side: (estimate_for, traction_for)


def solve_point(case: dict[str, Any], side: str, memory: list[PatchMemory] | None = None
                ) -> tuple[WheelContact, list[PatchMemory]]:
    """One wheel of one grid point: its result with an honest status, and its memory.

    ``memory`` (the previous point's) starts the solve; None: a cold start, as
    ``railcontact solve``. A point that cannot be solved has status not converged
    (a load loop that failed) or out of range (any other error of the case, or any other
    exception of the solver, its message naming the exception), no contact when the wheel
    does not touch its rail; it is never an exception.
    """
    wheel = WheelContact(side=side)
    try:
        c = Case.from_dict(case_with(case, {}, side))
        patches, pose = solve_wheel_rail(c, _starts(c, memory) if memory else None)
    except RailContactError as exc:  # a load loop, a CaseError, the geometry's own errors
        wheel.status = status_of(exc)
        wheel.message = str(exc) if isinstance(exc, CaseError) else f"{side} wheel: {exc}"
        return wheel, []
    except Exception as exc:  # a fault of the solver: this point lost, never the batch
        wheel.status = OUT_OF_RANGE
        wheel.message = (f"{side} wheel: the solver failed here "
                         f"({type(exc).__name__}: {exc})")
        return wheel, []
    if not patches:
        return wheel, []
    if c.tangential is not None:
        wheel.creepages = [tuple(c.tangential.creepage)] * len(patches)
    _resultants(wheel, patches, pose)
    return wheel, _memory(patches)


def solve_batch(case: dict[str, Any], sides: tuple[str, ...],
                points: list[dict[str, float]]) -> dict[str, Any]:
    """Solve the points (axis name -> value, in order along the fastest axis) for each wheel.

    Returns
    -------
    dict
        Each quantity of :data:`~.variables.QUANTITIES` and :data:`~.variables.COUNTS` as an
        array (points, sides); ``status`` (int8) likewise; ``messages``: the message of
        every point that is not ok, as ``(point, side, status, message)``; ``seconds``
        and ``cpu_seconds``: the batch's wall and CPU time in its worker [s]. A quantity
        that a point does not define (its geometry without contact, anything after an
        error) is NaN, always with a non-zero status.
    """
    t0, c0 = time.perf_counter(), time.process_time()
    shape = (len(points), len(sides))
    out: dict[str, Any] = {q.name: np.full(shape, np.nan) for q in QUANTITIES}
    out.update({q.name: np.zeros(shape, dtype=np.int32) for q in COUNTS})
    out["status"] = np.zeros(shape, dtype=np.int8)
    out["messages"] = []
    for j, side in enumerate(sides):
        memory: list[PatchMemory] = []
        for i, values in enumerate(points):
            wheel, memory = solve_point(case_with(case, values), side, memory)
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
