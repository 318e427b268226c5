"""The rigid wheelset's stage of a load-controlled step: the wheels solved at other rolls
(:class:`RolledApproaches`, the function the search of :mod:`.rigid` evaluates) and the
stage itself (:func:`rigid_stage`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..contact.results import Work
from ..errors import RailContactError, SolverError
from ..geometry.points import WheelSearch
from ..geometry.track import Pose
from ..halfspace.hertz import negligible_load
from ..halfspace.materials import ElasticPair
from ..settings import Control
from .inputs import Kinematics, WheelSetup
from .memory import EMPTY as EMPTY_MEMORY
from .memory import StepMemory
from .results import NOT_CONVERGED, WheelContact
from .rigid import RigidSolution, RigidWheelset
from .warmstart import PatchMemory
from .wheel import solve_step_wheel


@dataclass(frozen=True)
class RolledApproaches:
    """``phi -> (delta_L, delta_R)``: the vertical approaches [m] at which the wheels,
    the wheelset rolled to ``phi``, carry the step's loads with its creepages (the step's
    solve of each wheel, :func:`~.wheel.solve_step_wheel`, which leaves the contact's
    memory as it is; :mod:`.rigid`).

    With a warm start each wheel's solve starts from the solution nearest in pose: this
    step's last rolled solve of the wheel, else the previous step's at its root
    (``rolled``: its memory, :attr:`StepMemory.rolled`), else this step's
    own at the pose's roll; the older step it remembers is the previous step's at its root
    (else this step's). The solves at the root found are what the next step keeps
    (:meth:`memory_at`)."""

    pose: Pose
    loads: tuple[float, float]
    creepages: tuple | None
    kinematics: Kinematics | None
    time: float | None
    pair: ElasticPair
    convention: str
    """The contact's convention (:class:`~railcontact.timestep.WheelsetContact`)."""
    step: StepMemory = EMPTY_MEMORY
    """The memory of the wheels' solves at the step's own roll (the step's, or the
    previous step's when the step is not remembered)."""
    rolled: tuple[tuple[PatchMemory, ...], tuple[PatchMemory, ...]] | None = None
    """The previous step's memory of its wheels (left, right) at its root; None: none
    kept."""
    setups: tuple[WheelSetup, WheelSetup] | None = None
    """The wheels' rails, wheelsets and settings at the step (:class:`WheelSetup`)."""
    solved: dict = field(default_factory=dict, repr=False, compare=False)
    """The last call's roll [rad] and memory of its solves (``"roll"``, ``"memory"``)."""
    work: dict[str, Work] = field(
        default_factory=lambda: {"left": Work(load_passes=0), "right": Work(load_passes=0)},
        repr=False, compare=False)
    """The work of every wheel solve of the calls so far, per wheel (iterations, load
    passes, re-meshes, wall time [s]): a running count over this step's searches
    (:attr:`RigidSolution.wheel_work` is the part one search added)."""

    def __call__(self, phi: float, guess: tuple[float, float] | None = None,
                 found: tuple[WheelSearch, WheelSearch] | None = None) -> tuple[float, float]:
        """``found``: the wheels (left, right) searched at the roll ``phi``
        (:func:`~railcontact.geometry.search.search_wheel`; None: searched in their solves).
        ``guess``: the approaches [m] expected, at which each wheel's first pass forms
        its frame (scaled to the pass's load as Hertz's: the ``start`` of
        :func:`~railcontact.contact.wheelrail.solve_wheel_normal`). The solve forms the
        frame again while its approach misses the one the frame was formed at by more than
        :data:`~railcontact.contact.wheelrail.WARM_REFERENCE_RTOL`, as every solve started
        from an earlier one's approach does; within that the frame moves the approach by
        at most about a fifth of the rigid search's tolerance (:data:`~.rigid.RIGID_RTOL`
        of the approach; 0.16 for a frame 0.9e-3 off, solved tightly on the flange; 0.005
        on the tread), far below the solves' own scatter at the step's tolerances. So a
        wheel is not solved a second time when its approach misses the guess by more than
        :data:`~railcontact.contact.wheelrail.REFERENCE_RTOL`: that repeat would cost a
        solve in every second warm step, and in cold ones, where a solve without memory
        forms its frame from Hertz's approach, it would repeat the same solve."""
        pose = Pose(self.pose.lateral, self.pose.yaw, phi)
        out = []
        last = self.solved.get("memory")
        memory: list[tuple[PatchMemory, ...]] = []
        self.solved.clear()  # (a call that raises leaves none)
        for k, side in enumerate(("left", "right")):
            if negligible_load(self.loads[k]):
                out.append(0.0)
                memory.append(())
                continue
            older = (self.rolled[k] if self.rolled else ()) or self.step.wheel(side)
            start = (last[k] if last else ()) or older
            creep = None if self.creepages is None else self.creepages[k]
            wheel, mem, error = solve_step_wheel(
                self.setups[k], pose, Control(load=self.loads[k]), creep, self.kinematics,
                self.time, self.pair, self.convention, (older, start, self.step.wheel(side)),
                None if guess is None else guess[k], None if found is None else found[k])
            if error is not None:  # (a patch beyond the model, a load loop that raised)
                raise error
            self.work[side] = counted(self.work[side], wheel)
            if not wheel.patches or wheel.status == NOT_CONVERGED:  # no approach to give
                raise RailContactError(f"{side} wheel at roll {phi:.6g} rad: "
                                       + (wheel.message if wheel.patches else "no contact"))
            out.append(wheel.approach)
            memory.append(tuple(mem))
        self.solved.update(roll=phi, memory=(memory[0], memory[1]))
        return out[0], out[1]

    def memory_at(self, phi: float
                  ) -> tuple[tuple[PatchMemory, ...], tuple[PatchMemory, ...]] | None:
        """The memory of the wheels' solves (left, right) at roll ``phi`` [rad] when the
        last call was there (what the next step starts from), else None."""
        return self.solved["memory"] if self.solved.get("roll") == phi else None


def rigid_stage(rigid: RigidWheelset) -> RigidSolution:
    """The rigid wheelset's vertical displacement and roll (:meth:`RigidWheelset.solve`),
    or, when a wheel cannot be solved at a roll its search tries, a solution not
    converged that says why, with the work done until then."""
    try:
        return rigid.solve()
    except (RailContactError, SolverError) as exc:  # a wheel not solved at a roll
        done = rigid.approach_at.work  # (this step's: all of it is this search's)
        return RigidSolution(0.0, 0.0, converged=False,
                             message=f"rigid wheelset's vertical displacement and roll: {exc}",
                             wheel_work=(done["left"], done["right"]))


def counted(work: Work, wheel: WheelContact) -> Work:
    """``work`` with a wheel solve's iterations, load passes, re-meshes and time added."""
    return work.added(wheel.work)
