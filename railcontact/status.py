"""The one status vocabulary of a solved wheel: the time step, the tables, the FMU and the
co-simulation all say what became of a wheel with a :class:`Status`; and the one record of
the work a solve took, :class:`Work`.

A status is an integer (the FMU's ``status`` outputs, the tables' ``status`` variable) with
a label, a description and a severity: a wheelset's status is its wheels' most severe
(:meth:`Status.worst`). :func:`status_of` is the one map from an exception raised while
solving a wheel to the status the wheel is given.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

from .errors import RailContactError, SolverError


class Status(IntEnum):
    """What became of a wheel (or a table point).

    The values are those of the FMU's ``status`` outputs and of a table's ``status``
    variable; :attr:`label` and :attr:`description` are their words (the FMU's
    modelDescription and docs are generated from them).
    """

    NOT_COMPUTED = -1
    OK = 0
    NOT_CONVERGED = 1
    NO_CONTACT = 2
    OUT_OF_RANGE = 3
    OUTSIDE_VALIDITY = 4

    @property
    def label(self) -> str:
        """The status in words ("ok", "not converged", ...)."""
        return _LABELS[self]

    @property
    def description(self) -> str:
        """What the status means for the forces given."""
        return _DESCRIPTIONS[self]

    @property
    def severity(self) -> int:
        """Rank from the least severe (0, ok) to the most (out of range)."""
        return _SEVERITY.index(self)

    @classmethod
    def worst(cls, statuses: Iterable[int]) -> Status:
        """The most severe of ``statuses`` (ok for none)."""
        return max((cls(s) for s in statuses), key=_SEVERITY.index, default=cls.OK)

    @classmethod
    def severity_order(cls) -> str:
        """The solved statuses' codes from the most severe to the least, as the FMU's
        variables say it: ``"3 > 1 > 4 > 2 > 0"``."""
        return " > ".join(str(int(s)) for s in reversed(_SEVERITY)
                          if s is not cls.NOT_COMPUTED)


_LABELS = {Status.NOT_COMPUTED: "not computed", Status.OK: "ok",
           Status.NOT_CONVERGED: "not converged", Status.NO_CONTACT: "no contact",
           Status.OUT_OF_RANGE: "out of range", Status.OUTSIDE_VALIDITY: "outside validity"}
_DESCRIPTIONS = {
    Status.NOT_COMPUTED: "a table point not computed yet (its values NaN)",
    Status.OK: "solved within the tolerances and every limit of validity",
    Status.NOT_CONVERGED: "a BEM solve or the load loop missed its tolerance: forces given, "
                          "less accurate",
    Status.NO_CONTACT: "no contact: zero forces",
    Status.OUT_OF_RANGE: "the pose or a patch beyond the model: nothing solved, zero forces",
    Status.OUTSIDE_VALIDITY: "solved, but beyond a limit of validity (Y/Q, Nadal's limit, "
                             "flange climb, penetration, wheel load, an under-resolved "
                             "patch): forces given",
}
_SEVERITY = (Status.NOT_COMPUTED, Status.OK, Status.NO_CONTACT, Status.OUTSIDE_VALIDITY,
             Status.NOT_CONVERGED, Status.OUT_OF_RANGE)
"""The statuses from the least to the most severe."""


def status_of(exc: BaseException) -> Status:
    """The status of a wheel whose solve raised ``exc``: not converged for a
    :class:`~railcontact.errors.SolverError` (a :class:`~railcontact.errors.
    ConvergenceError`: an iteration that missed its tolerance), out of range for a
    :class:`~railcontact.errors.RailContactError` (the pose, a patch or an input beyond
    the model). Raises ``exc`` itself for anything else (a fault of the code, not of the
    wheel)."""
    if isinstance(exc, SolverError):
        return Status.NOT_CONVERGED
    if isinstance(exc, RailContactError):
        return Status.OUT_OF_RANGE
    raise exc


@dataclass(frozen=True, slots=True)
class Work:
    """The work a result took, counted over all its load passes and re-meshes: a value,
    added up into new records (:meth:`absorbed`, :func:`dataclasses.replace`).

    Every solver result says what became of it with the same words: ``converged`` (or a
    :class:`Status`, ``status``), a ``message`` and its ``work``, this record.

    Attributes
    ----------
    normal_iterations
        Normal CG iterations, every solve included (grown potential areas, load passes).
    tangential_iterations
        Tangential Gauss-Seidel sweeps, every solve included.
    load_passes
        Solves of the wheel (or quadratic patch) that the result took: the passes of the
        load loops (approach secant with several patches, the patch frame formed again at
        the reference point, creep-load secant, equal-loads roll), 1 when the first solve
        was the answer.
    remeshes
        Normal solves repeated on a grown potential area because the contact reached the
        edge of the previous one.
    seconds
        Wall time [s]: of the patch's solves (estimates included) for a patch, of the
        whole ``solve()`` (geometry and contact search included) for a solution.
    """

    normal_iterations: int = 0
    tangential_iterations: int = 0
    load_passes: int = 1
    remeshes: int = 0
    seconds: float = 0.0

    def added(self, other: Work) -> Work:
        """This work and ``other``'s, every count and the time summed (two solves that
        both count: the two wheels of a search, a wheel's solves at several rolls)."""
        return Work(self.normal_iterations + other.normal_iterations,
                    self.tangential_iterations + other.tangential_iterations,
                    self.load_passes + other.load_passes, self.remeshes + other.remeshes,
                    self.seconds + other.seconds)

    def absorbed(self, other: Work) -> Work:
        """This work with the iterations, re-meshes and time of ``other`` (a discarded
        pass) added; the load passes this one's."""
        return Work(self.normal_iterations + other.normal_iterations,
                    self.tangential_iterations + other.tangential_iterations,
                    self.load_passes, self.remeshes + other.remeshes,
                    self.seconds + other.seconds)

    def timed(self, seconds: float) -> Work:
        """This work with its wall time ``seconds`` [s]."""
        return Work(self.normal_iterations, self.tangential_iterations, self.load_passes,
                    self.remeshes, seconds)

    def plus_seconds(self, seconds: float) -> Work:
        """This work with ``seconds`` [s] of wall time added."""
        return Work(self.normal_iterations, self.tangential_iterations, self.load_passes,
                    self.remeshes, self.seconds + seconds)

    def to_dict(self) -> dict[str, Any]:
        return {"normal_iterations": self.normal_iterations,
                "tangential_iterations": self.tangential_iterations,
                "load_passes": self.load_passes, "remeshes": self.remeshes,
                "seconds": self.seconds}


__all__ = ["Status", "Work", "status_of"]
