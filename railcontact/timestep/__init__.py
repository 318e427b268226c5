"""The time step: what a dynamics code (and the FMU) calls every step.

- :mod:`.wheelset`: :class:`WheelsetContact`, both wheels of a wheelset per step,
  kinematic creepages, the load loop with creep forces;
- :mod:`.warmstart`: the previous steps' solutions as the next step's start.
"""

from ..settings import ContactSettings
from .wheelset import (
    STATUS_NAMES,
    Kinematics,
    WheelContact,
    WheelsetContact,
    WheelsetResult,
)

__all__ = ["STATUS_NAMES", "ContactSettings", "Kinematics", "WheelContact", "WheelsetContact",
           "WheelsetResult"]
