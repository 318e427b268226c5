"""One wheel's problem and solution: the records of :func:`~.wheelrail.solve_wheel`.

A wheel is solved at a pose in passes - a normal solve of its patches under a vertical load
or approach, then their tangential solve - repeated by the load loop when the creep forces
carry part of the wheel load (:func:`~.loadloop.creep_load`). :class:`WheelProblem` is what
stays the same across the passes, formed once at the pose (the wheel's first contact point
and the approaches where two of its contact regions join); :class:`WheelSettings` how it is
solved; a :class:`WheelStart` how each pass starts (the case's estimates and the pass
before, :class:`~.wheelrail.CaseStart`; a time step's previous step); and
:class:`WheelSolution` what comes out: the patches with a status and a message, never an
exception for a load that was not met (:meth:`WheelSolution.check` raises it for a caller
that wants one).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NamedTuple, Protocol

import numpy as np

from ..errors import ConvergenceError, RailContactError, SolverError
from ..geometry.points import ContactPoint, WheelSearch
from ..geometry.track import Pose, Track, Wheelset
from ..halfspace.materials import ElasticPair
from ..settings import Control, PatchSettings, TangentialSettings
from ..status import Status, Work
from .results import PatchSolution, patches_work

LOAD_RTOL = 1e-6
"""Relative tolerance on the vertical load carried by the normal forces of several patches
(:attr:`WheelSettings.normal_load_tolerance`'s default)."""
CREEP_LOAD_RTOL = 1e-5
"""Relative tolerance on the total vertical force when creep forces carry part of it, of a
case (``railcontact solve``, tables): :attr:`WheelSettings.load_tolerance`'s default."""
LOAD_ACCEPT_RTOL = 1e-3
"""A case's load loop that stops short of :data:`CREEP_LOAD_RTOL` (at the tangential BEM's
noise floor) is accepted when the wheel's vertical force meets its load to this
(:attr:`WheelSettings.load_acceptance`'s default)."""


class WheelProblem(NamedTuple):
    """A wheel at a pose, formed once for all the passes of its solve (a named tuple:
    one is formed per wheel and step).

    Attributes
    ----------
    track, wheelset
        The rail (placed) and the wheelset.
    pose
        The wheelset's pose.
    side
        "left" or "right".
    pair
        Combined elastic parameters of wheel and rail.
    control
        The vertical wheel load [N] or the vertical approach [m] beyond first contact.
    first
        The wheel's first rigid contact point (at approach 0; :func:`~railcontact.geometry.
        points.contact_points`): where a single patch's frame and a cold start's estimates
        are formed; None without a load or an approach (no contact: nothing searched).
    merges
        The vertical approaches [m] at which two of the wheel's contact regions join into
        one patch (:func:`~railcontact.geometry.points.merge_approaches`, the saddles of
        at least :data:`~railcontact.geometry.points.MIN_LOBE`), increasing; checked for
        another root of a load (:func:`~.loadloop.first_root`).
    found
        The wheel searched at the pose (:func:`~railcontact.geometry.search.search_wheel`):
        what its contact points and patch frames are formed from; None without a load or
        an approach.
    """

    track: Track
    wheelset: Wheelset
    pose: Pose
    side: str
    pair: ElasticPair
    control: Control
    first: ContactPoint | None
    merges: np.ndarray
    found: WheelSearch | None = None


class WheelSettings(NamedTuple):
    """How a wheel is solved (a named tuple: one is formed per wheel and step).

    Attributes
    ----------
    patch
        The patches' grid and normal BEM (and a case's tangential settings and kinematics).
    tangential
        The tangential problem's settings (friction, tolerance); None: normal contact only.
    reference
        Each patch in the frame at its reference point (else at its rigid contact point).
    load_tolerance
        Relative tolerance on a wheel load that counts the creep forces: the creep-load
        loop's target and the check of another root (:func:`~.loadloop.creep_load`).
    load_acceptance
        A load loop that stops short of ``load_tolerance`` (at the tangential BEM's noise
        floor) still gives an ok wheel when its vertical force meets the load to this, or
        to the accuracy of its creep forces (:func:`~.loadloop.load_met`); at least
        ``load_tolerance``. The normal forces' loop over several patches
        (``normal_load_tolerance``) that misses its load by more than this raises a
        :class:`~railcontact.errors.ConvergenceError`.
    load_includes_creep
        A wheel load is the total vertical force, creep forces included (else the normal
        forces alone carry it: one pass).
    normal_load_tolerance
        Relative tolerance on the vertical load that the normal forces of several patches
        carry: the secant on the wheel's vertical approach within each pass and the check
        of another root (:func:`~.wheelrail.solve_wheel_normal`).
    """

    patch: PatchSettings
    tangential: TangentialSettings | None = None
    reference: bool = True
    load_tolerance: float = CREEP_LOAD_RTOL
    load_acceptance: float = LOAD_ACCEPT_RTOL
    load_includes_creep: bool = True
    normal_load_tolerance: float = LOAD_RTOL


@dataclass(frozen=True, slots=True)
class WheelPass:
    """One solve of a wheel's patches under a normal control, then the tangential one.

    Attributes
    ----------
    patches
        The solved patches (normal force > 0).
    creepages
        The creepages (xi, eta, phi) each patch was solved with, as its start gave them
        (empty when the start does not report them).
    memory
        What the start keeps of the pass (a time step's patch memory), or None.
    """

    patches: list[PatchSolution]
    creepages: list = field(default_factory=list)
    memory: Any = None


class WheelStart(Protocol):
    """How the passes of a wheel's solve start (:func:`~.wheelrail.solve_wheel`)."""

    def share(self, problem: WheelProblem, settings: WheelSettings, load: float) -> float:
        """The first normal share [N] of the vertical ``load`` [N] the creep-load loop
        tries (the load less the creep forces' share expected)."""

    def solve_pass(self, problem: WheelProblem, settings: WheelSettings, control: Control,
                   before: WheelPass | None) -> WheelPass:
        """The wheel solved with its normal problem under ``control`` (a vertical load its
        normal forces carry, or a vertical approach [m]), then the tangential one;
        ``before``: the pass before in this solve (None for the first)."""


@dataclass(frozen=True, slots=True)
class WheelSolution:
    """A wheel solved at a pose.

    Attributes
    ----------
    patches
        The solved patches (the last pass's, each pass's work charged to them); empty
        without contact or when the solve failed.
    status
        ``OK`` (the load met, the BEM solves' own convergence is in each patch),
        ``NOT_CONVERGED`` (the load loop did not meet the load: :attr:`patches` the pass
        closest to it; or a solve raised a :class:`~railcontact.errors.SolverError`),
        ``NO_CONTACT``, ``OUT_OF_RANGE`` (a patch beyond the model: a
        :class:`~railcontact.errors.CaseError`).
    message
        Why, when not ok ("ok", "no contact").
    creepages, memory
        The last pass's (:class:`WheelPass`).
    load_other
        The vertical approach [m] of another root of the load, or of the merge beyond which
        one lies (:func:`~.loadloop.first_root`); None: none found.
    steep
        Several patches, one with ``mu tan(gamma) >= 1`` carrying a creep force, where the
        creep forces are in the load (:func:`~.loadloop.load_unique` False): the load may
        have another root.
    error
        The exception a pass raised (its :attr:`status` from it), or None.
    seconds
        Wall time [s] of the solve outside its passes (the creep-load loop's estimate of
        the creep forces' share of the load), counted in :attr:`work` beside the
        patches'.
    """

    patches: list[PatchSolution] = field(default_factory=list)
    status: Status = Status.NO_CONTACT
    message: str = "no contact"
    creepages: list = field(default_factory=list)
    memory: Any = None
    load_other: float | None = None
    steep: bool = False
    error: RailContactError | SolverError | None = None
    seconds: float = 0.0

    @property
    def work(self) -> Work:
        """The work of the wheel's solve (:class:`~railcontact.status.Work`): its
        patches' (each pass's charged to them) summed, their load passes once (the
        patches of a wheel share them), and the solve's own :attr:`seconds`."""
        work = patches_work(self.patches)
        return work.plus_seconds(self.seconds) if self.seconds else work

    @property
    def load_unique(self) -> bool:
        """Whether the wheel load has one solution (no other root, not steep)."""
        return self.load_other is None and not self.steep

    def check(self, side: str) -> WheelSolution:
        """This solution when ok or without contact; else raise: the exception a pass
        raised, or a :class:`~railcontact.errors.ConvergenceError` naming the ``side``
        wheel with the patches as its ``partial``."""
        if self.error is not None:
            raise self.error
        if self.status == Status.NOT_CONVERGED:
            raise ConvergenceError(f"{side} wheel: {self.message}", self.patches)
        return self


__all__ = ["CREEP_LOAD_RTOL", "LOAD_ACCEPT_RTOL", "LOAD_RTOL", "WheelPass", "WheelProblem",
           "WheelSettings", "WheelSolution", "WheelStart"]
