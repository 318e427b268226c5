"""How a patch's solves start: the :class:`WarmStart` record.

A patch's normal BEM starts from a pressure on its grid, which is known only when the
potential area is meshed (and meshed again when the contact reaches its edge); its
tangential BEM from a traction on the same grid. A start therefore gives its pressure and
traction as functions of the grid, and says what it is (its label, reported per patch) and
which potential area it knows (a time step's: where the contact was). The cold estimates
(Hertz, Kik-Piotrowski, INFCON), a time step's previous step, a table's previous point and
a load loop's previous pass are all one record.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..halfspace.grid import Grid
from ..normal.bem import Displacement, NormalResult

Bounds = tuple[float, float, float, float]
"""A potential contact area (xmin, xmax, ymin, ymax) [m]."""


class NormalStart(NamedTuple):
    """The start of a normal BEM solve on one grid.

    Attributes
    ----------
    pressure
        Initial pressure [Pa], (nx, ny), or None: the solver's own uniform start.
    displacement
        The displacement ``A p`` of ``pressure`` [m] when the start knows it (a time step's
        previous solution on the same lattice), else None: the solver convolves it.
    """

    pressure: np.ndarray | None
    displacement: Displacement | None = None


class TangentialStart(NamedTuple):
    """The start of a tangential BEM solve on one grid.

    Attributes
    ----------
    traction
        Tangential traction [Pa], (2, nx, ny).
    state
        Adhesion/slip map (0 exterior, 1 adhesion, 2 slip), (nx, ny), or None.
    """

    traction: np.ndarray
    state: np.ndarray | None = None


class StagedNormal(NamedTuple):
    """A patch's first normal solve made by a start's compiled stage
    (:attr:`WarmStart.normal_stage`).

    Attributes
    ----------
    result
        The solution on the grid meshed on the potential area.
    final
        Whether it is the patch's solution: the solver keeps it as it is (finite, neither
        at its area's edge nor next to an undefined gap) and the reach check found no
        place of the rigid overlap beyond the grid that could touch (or it has no force).
        Else the solver goes on from it (:func:`~.patch.solve_patch_normal`'s ``first``).
    uncovered
        The box (xmin, xmax, ymin, ymax) [m] around the places beyond the grid that
        could touch, where the reach check found some (the solver's first check then,
        :func:`~.wheelrail._overlap_covered`'s ``flagged``); else None.
    """

    result: NormalResult
    final: bool
    uncovered: Bounds | None = None


NO_NORMAL_START = NormalStart(None)
"""No initial pressure: the BEM starts from its own uniform pressure."""


def _no_pressure(grid: Grid) -> NormalStart:
    return NO_NORMAL_START


def _no_traction(grid: Grid) -> TangentialStart | None:
    return None


@dataclass(frozen=True, slots=True)
class WarmStart:
    """The start of one patch's BEM solves.

    Attributes
    ----------
    label
        What the start is, reported per patch (``PatchSolution.estimate``): "previous" (a
        time step's previous step, a table's previous point), "hertz", "kp", "infcon",
        "none", or why there is none.
    pressure_on
        ``pressure_on(grid) -> NormalStart``: the initial pressure [Pa] on a BEM grid.
    bounds
        The potential area (xmin, xmax, ymin, ymax) [m] the start knows (a time step's:
        where the contact was), checked after the solve; None: the rigid overlap's.
    traction_on
        ``traction_on(grid) -> TangentialStart | None``: the initial traction [Pa] on the
        patch's grid (None: the tangential settings' estimate).
    normal_stage
        ``normal_stage(cp, bounds, grid_settings, settings, pair, control) ->
        StagedNormal | None``: the first normal solve of the patch at the contact point
        ``cp`` on the grid meshed on ``bounds`` from this start, and the check of its
        rigid overlap on the wheel's run, made in one compiled call where the start has
        one (a time step's warm start, :func:`railcontact.timestep.compiled.warm_normal`;
        :class:`StagedNormal`); None: nothing was solved, the solver's own path. None:
        no such stage.
    """

    label: str
    pressure_on: Callable[[Grid], NormalStart] = _no_pressure
    bounds: Bounds | None = None
    traction_on: Callable[[Grid], TangentialStart | None] = _no_traction
    normal_stage: Callable[..., StagedNormal | None] | None = None

    @property
    def gives_pressure(self) -> bool:
        """Whether the start gives a pressure (else the BEM starts from its own uniform
        one: :func:`no_start`)."""
        return self.pressure_on is not _no_pressure


def no_start(label: str) -> WarmStart:
    """A start that gives no pressure and no traction, labelled ``label`` (e.g. why)."""
    return WarmStart(label)
