"""The FMI 2.0 co-simulation unit: its variable table (:mod:`.variables`, the parameters
generated from :mod:`railcontact.settings`), its build and staleness check (:mod:`.build`)
and the check of which Python a built FMU runs in (:mod:`.check`; the C shim, the Python
slave and the builder are in the top-level ``fmu_src/``)."""

from .build import DEFAULT_OUTPUT, build_fmu, ensure_fmu, fmu_is_current, fmu_sources
from .check import FMUCheck, FMUWarm, check_fmu, warm_unpacked

__all__ = ["DEFAULT_OUTPUT", "FMUCheck", "FMUWarm", "build_fmu", "check_fmu", "ensure_fmu",
           "fmu_is_current", "fmu_sources", "warm_unpacked"]
