"""The time step: what a dynamics code (and the FMU) calls every step.

- :mod:`.wheelset`: :class:`WheelsetContact`, both wheels of a wheelset per step,
  kinematic creepages, the load loop with creep forces;
- :mod:`.warmstart`: the previous steps' solutions as the next step's start;
- :mod:`.memory`: :class:`StepMemory`, what a step keeps for the next one (a value);
- :mod:`.validity`: where a solved wheel is beyond the model's validity (Y/Q, Nadal,
  flange climb, penetration, load);
- :mod:`.rigid`: the rigid wheelset's vertical displacement and roll under load control;
- :mod:`.pool`: :class:`WheelsetPool`, wheelsets stepped at the same time in worker
  processes.
"""

from ..settings import ContactSettings
from .memory import StepMemory
from .pool import WheelsetDescription, WheelsetPool
from .wheelset import (
    OUTSIDE_VALIDITY,
    STATUS_NAMES,
    Kinematics,
    RailDeviation,
    WheelContact,
    WheelsetContact,
    WheelsetResult,
)

__all__ = ["OUTSIDE_VALIDITY", "STATUS_NAMES", "ContactSettings", "Kinematics", "RailDeviation",
           "StepMemory", "WheelContact", "WheelsetContact", "WheelsetDescription", "WheelsetPool",
           "WheelsetResult"]
