"""``railcontact fmu check FILE.fmu``: which Python a built FMU will run in, and whether it
can.

The check asks the FMU's own binary which Python it chooses (``RAILCONTACT_PYTHON``, then
``resources/python.txt``, then the Python it was built with) and what that Python is (the
shim's ``railcontact_fmu_locate``, loaded with ctypes; it starts no Python in this process),
then runs the FMU's start-up (``resources/python/fmu_bootstrap.py check``) in that Python as
``python -I``, as a C host starts it: the versions of numpy, scipy, pyfftw and numba, the
FMU's copy of railcontact, a slave made. ``railcontact fmu build --python`` runs the same
check before it writes the FMU.
"""

from __future__ import annotations

import ctypes
import os
import platform
import subprocess
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

from ..errors import RailContactError

CHECK_TIMEOUT = 300.0
"""Seconds the start-up check may take in the chosen Python (numba's first import is slow
on a cold disk)."""


@dataclass(frozen=True)
class FMUCheck:
    """The outcome of a check.

    Attributes
    ----------
    ok
        Whether the FMU can start in a C host in this environment.
    text
        What the FMU will use (Python, where it was chosen from, environment, dependency
        versions) or, when not ``ok``, the whole message the FMU would log.
    """

    ok: bool
    text: str


def _binary(root: Path) -> Path:
    system = platform.system()
    if system != "Linux" or platform.machine() not in ("x86_64", "AMD64"):
        raise RailContactError(f"the FMU has a Linux x86-64 binary only; this is {system} "
                               f"{platform.machine()}")
    found = sorted((root / "binaries" / "linux64").glob("*.so"))
    if not found:
        raise RailContactError(f"no binaries/linux64/*.so in the FMU ({root})")
    return found[0]


def _locate(binary: Path, resources: Path, use_env: bool) -> tuple[bool, str]:
    """The shim's choice of Python and that Python's probe (or the shim's message)."""
    try:
        lib = ctypes.CDLL(str(binary))
        locate = lib.railcontact_fmu_locate
    except (OSError, AttributeError) as exc:
        raise RailContactError(f"cannot ask the FMU's binary {binary.name} which Python it "
                               f"uses ({exc}): rebuild the FMU with this railcontact") from None
    locate.restype = ctypes.c_void_p
    locate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.POINTER(ctypes.c_int)]
    lib.railcontact_fmu_free.argtypes = [ctypes.c_void_p]
    ok = ctypes.c_int(0)
    p = locate(os.fsencode(resources), int(use_env), ctypes.byref(ok))
    try:
        text = ctypes.string_at(p).decode("utf-8", "replace") if p else ""
    finally:
        lib.railcontact_fmu_free(p)
    return bool(ok.value), text


def _run_bootstrap(resources: Path, located: str, command: str,
                   timeout: float) -> tuple[str, subprocess.CompletedProcess]:
    """Run ``fmu_bootstrap.py COMMAND`` in the Python the shim located (as ``python -I``, as
    a C host starts it); returns (that Python's executable, the finished process). Raises
    OSError or subprocess.TimeoutExpired as :func:`subprocess.run` does."""
    values = dict(line.partition("=")[::2] for line in located.splitlines() if "=" in line)
    exe = values["executable"]
    r = subprocess.run(
        [exe, "-I", str(resources / "python" / "fmu_bootstrap.py"), command,
         str(resources), "mode=check\n" + located],
        capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL)
    return exe, r


def check_unpacked(root: str | Path, use_env: bool = True) -> FMUCheck:
    """Check an unpacked FMU (the folder holding ``binaries/`` and ``resources/``).

    Parameters
    ----------
    root
        The unpacked FMU.
    use_env
        Whether ``RAILCONTACT_PYTHON`` counts (False: check ``resources/python.txt`` or the
        build interpreter, as ``fmu build --python`` does).
    """
    root = Path(root)
    resources = root / "resources"
    ok, located = _locate(_binary(root), resources, use_env)
    if not ok:
        return FMUCheck(False, located)
    values = dict(line.partition("=")[::2] for line in located.splitlines() if "=" in line)
    exe = values["executable"]
    try:
        exe, r = _run_bootstrap(resources, located, "check", CHECK_TIMEOUT)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return FMUCheck(False, f"cannot run {exe}: {exc}")
    cfg = dict(line.partition("=")[::2] for line in
               (resources / "python.cfg").read_text(encoding="utf-8").splitlines())
    head = [f"FMU: railcontact {cfg.get('railcontact', '?')}, built with Python "
            f"{cfg.get('version', '?')} ({cfg.get('executable', '?')}; "
            f"{cfg.get('built_with', '?')})",
            f"Python: {exe}", f"  chosen from {values.get('source', '?')}"]
    if values.get("libpython"):
        head.append(f"  libpython (started in C hosts): {values['libpython']}")
    else:
        head.append(f"  no shared libpython, so C hosts cannot start it: "
                    f"{values.get('libpython_problem', '')}")
    out = (r.stdout + r.stderr).rstrip()
    good = r.returncode == 0 and bool(values.get("libpython"))
    tail = ("In a Python host (fmpy, libcosimpy) the FMU runs in the host's interpreter "
            "instead and adds these site-packages after the host's own.")
    if good:
        verdict = "The FMU will start."
    elif r.returncode == 0:
        verdict = "The FMU will NOT start in a C host (a Python host may still run it)."
    else:
        verdict = "The FMU will NOT start."
    return FMUCheck(good, "\n".join([*head, out, tail, verdict]))


WARM_TIMEOUT = 900.0
"""Seconds the kernels' warm-up may take in the chosen Python (compiling them all takes
40-100 s on a desktop machine, longer on a busy one)."""


@dataclass(frozen=True)
class FMUWarm:
    """The outcome of warming an FMU's kernels (:func:`warm_unpacked`).

    Attributes
    ----------
    ok
        Whether the warm-up ran and its kernels went to the per-user cache (a fresh
        unpacking in this environment then loads them instead of compiling them).
    text
        One paragraph for the user: what was compiled and where it was cached, or why
        nothing was.
    compiled, loaded
        Kernel compilations and kernels loaded from the cache in the warm-up.
    seconds
        Wall time of the warm-up's steps [s] (the Python's start-up not included).
    """

    ok: bool
    text: str
    compiled: int = 0
    loaded: int = 0
    seconds: float = 0.0


def warm_unpacked(root: str | Path, use_env: bool = False,
                  timeout: float = WARM_TIMEOUT) -> FMUWarm:
    """Compile the kernels of an unpacked FMU's copy of railcontact into the per-user cache
    (``resources/python/fmu_bootstrap.py warm``), in the Python the FMU chooses, started as
    ``python -I`` as a C host starts it; never raises for a Python that cannot do it (the
    result says why).

    Parameters
    ----------
    root
        The unpacked (or staged) FMU.
    use_env
        Whether ``RAILCONTACT_PYTHON`` counts (False: ``resources/python.txt`` or the
        build interpreter, as ``railcontact fmu build`` checks it).
    timeout
        Seconds before the warm-up is given up [s].
    """
    root = Path(root)
    resources = root / "resources"
    not_warmed = "the kernels were not compiled ahead: the FMU's first run compiles them"
    try:
        ok, located = _locate(_binary(root), resources, use_env)
    except RailContactError as exc:
        return FMUWarm(False, f"{not_warmed} ({exc})")
    if not ok:
        return FMUWarm(False, f"{not_warmed} (its Python cannot start: "
                              f"{located.splitlines()[0] if located else '?'})")
    exe = dict(line.partition("=")[::2] for line in located.splitlines() if "=" in line)[
        "executable"]
    try:
        exe, r = _run_bootstrap(resources, located, "warm", timeout)
    except subprocess.TimeoutExpired:
        return FMUWarm(False, f"{not_warmed} (the warm-up in {exe} took longer than "
                              f"{timeout:g} s)")
    except OSError as exc:
        return FMUWarm(False, f"{not_warmed} (cannot run {exe}: {exc})")
    out = {k: v.replace("\x1f", "\n") for k, v in
           (line.partition("=")[::2] for line in r.stdout.splitlines() if "=" in line)}
    if r.returncode != 0 or out.get("end") != "1":
        why = out.get("error") or (r.stdout + r.stderr).strip()[-2000:] or \
            f"exit status {r.returncode}"
        return FMUWarm(False, f"{not_warmed} (the warm-up in {exe} failed: {why})")
    compiled, loaded = int(out["compiled"]), int(out["loaded"])
    seconds = float(out["seconds"])
    if out.get("persistent") != "1":
        return FMUWarm(False, f"{not_warmed} (in {exe}: {out['cache']}; each unpacking "
                              "compiles them again)", compiled, loaded, seconds)
    what = (f"{compiled} compiled, {loaded} loaded from the cache" if compiled else
            f"all {loaded} already in the cache")
    return FMUWarm(True, f"kernels warmed for {exe} in {seconds:.0f} s ({what}): "
                         f"{out['cache']}", compiled, loaded, seconds)


def check_fmu(path: str | Path) -> FMUCheck:
    """Check the FMU file at ``path`` in this environment (``railcontact fmu check``)."""
    path = Path(path)
    if not path.is_file():
        raise RailContactError(f"FMU {path} not found")
    with tempfile.TemporaryDirectory(prefix="railcontact-check-") as tmp:
        try:
            with zipfile.ZipFile(path) as z:
                z.extractall(tmp)
        except zipfile.BadZipFile:
            raise RailContactError(f"{path} is not an FMU (not a zip file)") from None
        if not (Path(tmp) / "resources" / "python.cfg").is_file():
            raise RailContactError(f"{path} is not a railcontact FMU (no resources/python.cfg)")
        return check_unpacked(tmp)
