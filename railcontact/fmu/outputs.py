"""What the FMU's slave takes from a wheelset's step: its output values and what its checks
read, a few hundred bytes in place of the whole
:class:`~railcontact.timestep.WheelsetResult` (about 1 MB with its patches).

:func:`step_outputs` is the ``reduce`` of the
:class:`~railcontact.timestep.pool.WheelsetPool` the FMU of several wheelsets steps its
wheelsets in (a module-level function of the package: the worker processes import it by
name), and the slave applies it to the results it solves itself, so that both ways write
the same values.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

from ..timestep import WheelsetResult
from . import variables as V


@dataclass(frozen=True)
class WheelOutcome:
    """A wheel's step as the slave checks it.

    Attributes
    ----------
    side
        "left" or "right".
    status
        The wheel's status (:class:`~railcontact.status.Status` as an int).
    message
        Its message.
    creepages
        Per patch (xi, eta [-], phi [1/m]) it was solved with.
    patches
        Number of contact patches.
    """

    side: str
    status: int
    message: str
    creepages: tuple[tuple[float, float, float], ...]
    patches: int


@dataclass(frozen=True)
class StepOutputs:
    """A wheelset's step reduced to what the FMU's slave writes and checks.

    Attributes
    ----------
    real, integer
        The values of the one-wheelset FMU's Real and Integer outputs in the order of
        :func:`output_functions` (SI units).
    wheels
        Both wheels' :class:`WheelOutcome` (left, right).
    rigid
        The rigid wheelset's search, (converged, message); None when it did not run.
    """

    real: list[float]
    integer: list[int]
    wheels: tuple[WheelOutcome, ...]
    rigid: tuple[bool, str] | None


@cache
def output_functions() -> tuple[tuple, tuple]:
    """The value functions (of a :class:`~railcontact.timestep.WheelsetResult`) of the
    one-wheelset FMU's Real and of its Integer outputs, in the order of its variable
    table (:func:`railcontact.fmu.variables.table`)."""
    outputs = [v for v in V.table() if v.causality == "output"]
    return tuple(tuple(v.value for v in outputs if v.type == t) for t in ("Real", "Integer"))


def step_outputs(result: WheelsetResult) -> StepOutputs:
    """The :class:`StepOutputs` of a wheelset's step: every output's value as the
    variable table computes it from ``result``, the wheels' statuses, messages, creepages
    and patch counts, and the rigid wheelset's convergence."""
    real, integer = output_functions()
    rigid = result.rigid_solution
    return StepOutputs(
        [value(result) for value in real], [value(result) for value in integer],
        tuple(WheelOutcome(w.side, int(w.status), w.message,
                           tuple(tuple(c) for c in w.creepages), len(w.patches))
              for w in result.wheels),
        None if rigid is None else (bool(rigid.converged), rigid.message))


__all__ = ["StepOutputs", "WheelOutcome", "output_functions", "step_outputs"]
