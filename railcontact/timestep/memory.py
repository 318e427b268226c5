"""What a wheelset's time step keeps for the next one: the :class:`StepMemory` value.

A step reads the memory of the step before and returns its own; nothing else writes it.
An FMU's ``fmi2GetFMUstate`` stores it as it is (:mod:`railcontact.fmu.state`), and a step
repeated from a restored memory repeats the original bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

from .rigid import RigidMemory
from .warmstart import PatchMemory

Patches = tuple[PatchMemory, ...]
"""One wheel's remembered patches."""


@dataclass(frozen=True, slots=True)
class StepMemory:
    """A wheelset step's memory (empty: the next step starts cold).

    Attributes
    ----------
    left, right
        Each wheel's remembered patches (:class:`~.warmstart.PatchMemory`): the next
        step's warm start.
    rigid
        The rigid wheelset's roots of the last steps, newest first
        (:class:`~.rigid.RigidMemory`): the start in time of the next step's search; empty
        when the stage did not run or did not converge.
    rolled
        The wheels' patches (left, right) solved at the rigid wheelset's root (the wheelset
        rolled there), where the next step's solves at other rolls start; None: none kept.
    """

    left: Patches = ()
    right: Patches = ()
    rigid: tuple[RigidMemory, ...] = ()
    rolled: tuple[Patches, Patches] | None = None

    def wheel(self, side: str) -> Patches:
        """The remembered patches of the ``side`` ("left" or "right") wheel."""
        return self.left if side == "left" else self.right

    def rolled_wheel(self, side: str) -> Patches:
        """The patches of the ``side`` wheel at the rigid wheelset's root (empty: none)."""
        if self.rolled is None:
            return ()
        return self.rolled[0] if side == "left" else self.rolled[1]


EMPTY = StepMemory()
"""No memory: the next step starts cold."""
