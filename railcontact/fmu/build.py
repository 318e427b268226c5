"""Building the railcontact FMU from ``fmu_src/`` (the C shim, the Python slave, the
modelDescription generator): ``railcontact fmu build [-o dist/RailContact.fmu]``. The
variable table is :mod:`railcontact.fmu.variables`.

The sources are ``fmu_src/`` at the top of a source checkout (``pip install -e .``); a wheel
or sdist carries them as ``railcontact/_fmu_src/`` (``setup.py``). The built FMU runs in the
Python named by ``RAILCONTACT_PYTHON``, by ``--python`` at build time, or else the one that
built it (``railcontact fmu check FILE.fmu`` tells which). The build compiles the FMU's numba
kernels into the per-user cache in that Python (once per environment and railcontact
version; ``--no-warm`` skips it), so that a freshly unpacked FMU starts in seconds.
"""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Callable
from pathlib import Path

from ..errors import RailContactError

DEFAULT_OUTPUT = "dist/RailContact.fmu"


def fmu_sources() -> Path:
    """The FMU's sources: ``railcontact/_fmu_src`` of an installed wheel, or ``fmu_src`` of
    the source checkout an editable install points at."""
    package = Path(__file__).resolve().parents[1]
    places = (package / "_fmu_src", package.parent / "fmu_src")
    for d in places:
        if (d / "railcontact_fmu.h").is_file():
            return d
    raise RailContactError(f"FMU sources not found (looked in {places[0]} and {places[1]}): "
                           "reinstall railcontact (`pip install railcontact`, or "
                           "`pip install .` in a source checkout)")


def _builder():
    name = "_railcontact_fmu_build"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, fmu_sources() / "build.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def build_fmu(output: str | Path = DEFAULT_OUTPUT, profiles: list[str | Path] = (),
              python: str | Path | None = None, warm: bool = True,
              log: Callable[[str], None] | None = None, wheelsets: int | None = None) -> Path:
    """Build the FMU (gcc + fmpy's FMI 2 headers) and return its path.

    Parameters
    ----------
    output
        The .fmu file to write.
    profiles
        Profile files to put into the FMU's resources.
    python
        The Python it is to run in (a python executable or a venv/prefix folder; default:
        this one), checked before the FMU is written.
    warm
        Whether to compile the FMU's numba kernels into the per-user cache in that Python
        (the first build in an environment takes 40-100 s longer; then a freshly unpacked
        FMU starts in seconds). Not possible there: the build still succeeds, ``log`` says
        why.
    log
        Called with lines for the user (the warm-up's outcome); None: silent.
    wheelsets
        None (default): the FMU of one wheelset. N from 1 to 8: the FMU of N wheelsets,
        every input and output repeated per wheelset with ``_k`` appended
        (``normal_force_left_2``), the parameters once, the Integer parameter ``wheelsets``
        = N; the wheelsets are solved in worker processes or on threads within each step
        (:func:`railcontact.fmu.variables.table`, ``docs/fmu.md``).
    """
    b = _builder()
    try:
        return b.build(output, list(profiles), python=python, warm=warm, log=log,
                       wheelsets=wheelsets)
    except b.BuildError as exc:
        raise RailContactError(f"cannot build the FMU: {exc}") from None


def fmu_is_current(path: str | Path, profiles: list[str | Path] = (),
                   wheelsets: int | None = None) -> bool:
    """Whether the FMU at ``path`` exists and was built from the present sources, Python,
    profile files and number of wheelsets (its ``resources/source.sha1``, see
    ``fmu_src/build.py``)."""
    import zipfile

    path = Path(path)
    if not path.is_file():
        return False
    try:
        with zipfile.ZipFile(path) as z:
            stored = z.read("resources/source.sha1").decode().strip()
    except (KeyError, OSError, zipfile.BadZipFile):
        return False
    return stored == _builder().source_digest(list(profiles), wheelsets=wheelsets)


def ensure_fmu(path: str | Path = DEFAULT_OUTPUT, profiles: list[str | Path] = (),
               log: Callable[[str], None] | None = None,
               wheelsets: int | None = None) -> tuple[Path, bool]:
    """Build the FMU at ``path`` (of ``wheelsets`` wheelsets, see :func:`build_fmu`) if it
    is missing or stale (its kernels warmed; ``log`` gets the build's lines); returns
    (path, built)."""
    if fmu_is_current(path, profiles, wheelsets):
        return Path(path).resolve(), False
    return build_fmu(path, profiles, log=log, wheelsets=wheelsets), True
