"""Build the railcontact FMU (FMI 2.0 Co-Simulation, Linux x86-64).

The FMU holds the compiled C shim (``binaries/linux64/<id>.so``), a copy of the railcontact
package under a module name derived from the model identifier (its variable table is
``railcontact.fmu.variables``), the Python slave and its bootstrap, ``python.cfg`` (the
Python it was built with, railcontact's version and the dependency versions it needs),
``python.txt`` when built with ``python=`` (``--python``: the Python to run in) and any
extra profile files, all in ``resources/``. No Python is bundled: the FMU runs in the Python
named by ``RAILCONTACT_PYTHON``, ``python.txt`` or ``python.cfg`` (in that order), with that
environment's numpy, scipy, pyfftw and numba.

The FMU's copy of railcontact keeps its numba kernels in the per-user cache
(``railcontact/_kernelcache.py``: ``$RAILCONTACT_CACHE_DIR``, else
``$XDG_CACHE_HOME/railcontact`` or ``~/.cache/railcontact``), not in the folder a host
unpacks it to; the build compiles them there in the Python the FMU will run in
(``fmu_bootstrap.py warm``), so that a freshly unpacked FMU's first step loads them.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile
from datetime import datetime, timezone
from pathlib import Path
from xml.sax.saxutils import quoteattr

HERE = Path(__file__).resolve().parent
MODEL_IDENTIFIER = "RailContact"

UNITS = {  # SI base-unit exponents
    "m": {"m": 1}, "rad": {"rad": 1}, "N": {"kg": 1, "m": 1, "s": -2},
    "Pa": {"kg": 1, "m": -1, "s": -2}, "N.m": {"kg": 1, "m": 2, "s": -2},
    "W": {"kg": 1, "m": 2, "s": -3},
    "m/s": {"m": 1, "s": -1}, "rad/s": {"rad": 1, "s": -1}, "1/m": {"m": -1},
    "m2": {"m": 2}, "s": {"s": 1}, "1": {},
}


class BuildError(RuntimeError):
    """The FMU cannot be built here (missing compiler, headers, Python library)."""


def _fmt(value) -> str:
    if isinstance(value, float):
        return repr(value)
    return str(value)


def model_description(guid: str, model_identifier: str = MODEL_IDENTIFIER,
                      version: str = "", wheelsets: int | None = None) -> str:
    """The modelDescription.xml text (``wheelsets``: the FMU of that many wheelsets,
    :func:`railcontact.fmu.variables.table`)."""
    from railcontact.fmu.variables import item_name, table

    variables = table(wheelsets)
    what = "a wheelset" if wheelsets is None else \
        f"{wheelsets} wheelsets, solved in worker processes or on threads"
    used = sorted({v.unit for v in variables if v.unit})
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<fmiModelDescription fmiVersion="2.0" modelName="{model_identifier}" '
        f'guid="{guid}" description="railcontact: exact wheel-rail rolling contact '
        f'(half-space BEM) of {what}, warm-started" generationTool="railcontact '
        f'{version}" generationDateAndTime="'
        f'{datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")}" '
        'variableNamingConvention="flat" numberOfEventIndicators="0">',
        f'  <CoSimulation modelIdentifier="{model_identifier}" '
        'canHandleVariableCommunicationStepSize="true" canGetAndSetFMUstate="true" '
        'canSerializeFMUstate="true" canNotUseMemoryManagementFunctions="true" '
        'canInterpolateInputs="false" maxOutputDerivativeOrder="0"/>',
        "  <UnitDefinitions>",
    ]
    for u in used:
        exps = " ".join(f'{k}="{e}"' for k, e in UNITS[u].items())
        lines.append(f'    <Unit name="{u}"><BaseUnit {exps}/></Unit>' if exps else
                     f'    <Unit name="{u}"><BaseUnit/></Unit>')
    lines.append("  </UnitDefinitions>")
    enumerations = {v.enumeration_type: v for v in variables if v.items}
    if enumerations:
        lines.append("  <TypeDefinitions>")
        for name, v in enumerations.items():
            lines += [f'    <SimpleType name="{name}">', "      <Enumeration>"]
            lines += [f'        <Item name="{item_name(w)}" value="{k}" '
                      f'description={quoteattr(w)}/>' for k, w in enumerate(v.items, start=1)]
            lines += ["      </Enumeration>", "    </SimpleType>"]
        lines.append("  </TypeDefinitions>")
    lines += [
        "  <LogCategories>",
        '    <Category name="logStatusWarning"/>',
        '    <Category name="logStatusDiscard"/>',
        '    <Category name="logStatusError"/>',
        '    <Category name="logAll"/>',
        "  </LogCategories>",
        '  <DefaultExperiment startTime="0" stopTime="0.1" stepSize="0.001"/>',
        "  <ModelVariables>",
    ]
    outputs = []
    for i, v in enumerate(variables, start=1):
        if v.causality == "parameter":
            attrs = 'causality="parameter" variability="fixed" initial="exact"'
        elif v.causality == "input":
            attrs = 'causality="input" variability="continuous"'
        else:
            var = "continuous" if v.type == "Real" else "discrete"
            attrs = f'causality="output" variability="{var}" initial="calculated"'
            outputs.append(i)
        lines.append(f'    <ScalarVariable name="{v.name}" valueReference="{v.vr}" {attrs} '
                     f'description={quoteattr(v.description)}>')
        inner = []
        if v.start is not None and v.causality != "output":
            inner.append(f"start={quoteattr(_fmt(v.start))}")
        if v.unit:
            inner.append(f'unit="{v.unit}"')
        if v.items:
            inner.insert(0, f'declaredType="{v.enumeration_type}"')
        kind = "Enumeration" if v.items else v.type
        lines.append(f"      <{kind} {' '.join(inner)}/>" if inner else f"      <{kind}/>")
        lines.append("    </ScalarVariable>")
    lines += ["  </ModelVariables>", "  <ModelStructure>", "    <Outputs>"]
    lines += [f'      <Unknown index="{i}"/>' for i in outputs]
    lines += ["    </Outputs>", "    <InitialUnknowns>"]
    lines += [f'      <Unknown index="{i}"/>' for i in outputs]
    lines += ["    </InitialUnknowns>", "  </ModelStructure>", "</fmiModelDescription>", ""]
    return "\n".join(lines)


def fmi_headers() -> Path:
    """The FMI 2 headers shipped with fmpy."""
    try:
        import fmpy
    except ImportError:
        raise BuildError("fmpy is needed for the FMI headers: pip install fmpy") from None
    d = Path(fmpy.__file__).parent / "c-code"
    if not (d / "fmi2Functions.h").is_file():
        raise BuildError(f"fmi2Functions.h not found in {d}")
    return d


def libpython() -> Path:
    """The shared CPython library of this interpreter (as the FMU's probe finds it)."""
    lib, why = _bootstrap().find_libpython()
    if not lib:
        raise BuildError(why)
    return Path(lib)


def shim_sources() -> list[Path]:
    """The C shim's files (``*.c`` of this folder, by job: see ``railcontact_fmu.h``), all
    compiled into the one binary."""
    return sorted(HERE.glob("*.c"))


def compile_shim(out: Path, model_identifier: str = MODEL_IDENTIFIER) -> Path:
    """Compile the C shim into ``binaries/linux64/<model_identifier>.so`` under ``out``;
    only the FMI functions and ``railcontact_fmu_locate``/``_free`` are exported."""
    cc = os.environ.get("CC", "gcc")
    if shutil.which(cc) is None:
        raise BuildError(f"C compiler {cc!r} not found (install gcc)")
    so = out / "binaries" / "linux64" / f"{model_identifier}.so"
    so.parent.mkdir(parents=True, exist_ok=True)
    cmd = [cc, "-shared", "-fPIC", "-O2", "-Wall", "-Wextra", "-std=gnu11",
           "-fvisibility=hidden", f"-I{fmi_headers()}", f"-I{HERE}",
           *(str(f) for f in shim_sources()), "-o", str(so), "-ldl", "-pthread",
           "-Wl,-z,nodelete"]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise BuildError(f"compiling the shim failed:\n{' '.join(cmd)}\n{r.stderr}")
    return so


def _copy_package(dst: Path, package: str) -> None:
    import railcontact

    src = Path(railcontact.__file__).resolve().parent
    shutil.copytree(src, dst / package,  # not _fmu_src: these sources, in a wheel install
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc",
                                                  "_fmu_src"))
    shutil.copy(HERE / "slave.py", dst / package / "_fmu_slave.py")
    shutil.copy(HERE / "fmu_bootstrap.py", dst / "fmu_bootstrap.py")
    from railcontact._kernelcache import USER_CACHE_MARKER

    (dst / package / USER_CACHE_MARKER).write_text(  # kernels compiled once per environment
        "This copy of railcontact is unpacked anew for each run: its numba kernels are cached "
        "in the per-user cache folder\n($RAILCONTACT_CACHE_DIR, else "
        "$XDG_CACHE_HOME/railcontact or ~/.cache/railcontact), see _kernelcache.py.\n",
        encoding="utf-8")


def source_digest(profiles: list[str | Path] = (),
                  model_identifier: str = MODEL_IDENTIFIER, python: str | None = None,
                  wheelsets: int | None = None) -> str:
    """SHA-1 of everything an FMU is built from: the railcontact package, ``fmu_src/``,
    the Python it runs in (``python``: the one named by ``--python``), the number of
    wheelsets (None: the one-wheelset FMU) and the profile files. A built FMU stores it in
    ``resources/source.sha1``; a different digest means the FMU is stale."""
    import railcontact

    digest = hashlib.sha1()
    digest.update(f"{model_identifier}\n{sys.executable}\n{sys.version}\n".encode())
    if wheelsets is not None:
        digest.update(f"wheelsets={wheelsets}\n".encode())
    if python is not None:
        digest.update(f"python.txt={python}\n".encode())
    pkg = Path(railcontact.__file__).resolve().parent
    for base, pattern in ((pkg, "*.py"), (HERE, "*.[pch]*")):
        for f in sorted(base.rglob(pattern)):
            if f.is_file() and not {"__pycache__", "_fmu_src"} & set(f.relative_to(base).parts):
                digest.update(f"{base.name}/{f.relative_to(base).as_posix()}".encode())
                digest.update(f.read_bytes())
    for p in profiles:
        p = Path(p)
        digest.update(p.name.encode())
        digest.update(p.read_bytes() if p.is_file() else b"missing")
    return digest.hexdigest()


def _bootstrap():
    """``fmu_bootstrap.py`` (the FMU's start-up code) as a module."""
    name = "_railcontact_fmu_bootstrap"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, HERE / "fmu_bootstrap.py")
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
    return sys.modules[name]


def requirements() -> dict[str, str]:
    """``python.cfg``'s record of what the FMU needs: ``requires`` (railcontact's minimum
    versions of the packages the FMU imports, ``numpy>=1.24, ...``), ``requires_python`` and
    ``built_with`` (the versions in the building environment, for the log)."""
    from importlib import metadata

    try:
        declared = metadata.requires("railcontact") or []
        requires_python = metadata.metadata("railcontact").get("Requires-Python") or ""
    except metadata.PackageNotFoundError:  # a bare source tree: no minimum versions known
        declared, requires_python = [], ""
    minimum = dict.fromkeys(_bootstrap().DEPENDENCIES, "")
    for r in declared:
        m = re.fullmatch(r"\s*([A-Za-z0-9_.-]+)\s*(?:>=\s*([0-9][\w.]*))?\s*", r)
        if m and m.group(1).lower() in minimum:  # conditional ones (extras) do not match
            minimum[m.group(1).lower()] = m.group(2) or ""
    built_with = []
    for module in minimum:
        mod = importlib.import_module(module)
        built_with.append(f"{module} {getattr(mod, '__version__', '?')}")
    return {"requires": ", ".join(f"{k}>={v}" if v else k for k, v in minimum.items()),
            "requires_python": requires_python,
            "built_with": "; ".join(built_with)}


def named_python(path: str | Path) -> str:
    """``--python PATH`` as written to ``resources/python.txt``: absolute (symbolic links
    kept: a venv's ``bin/python`` is one), a python executable or a venv/prefix folder."""
    p = Path(os.path.abspath(Path(path).expanduser()))
    if p.is_dir():
        if not any(os.access(p / "bin" / n, os.X_OK) for n in ("python3", "python")):
            raise BuildError(f"--python {path}: the folder has no bin/python3 or bin/python")
    elif not (p.is_file() and os.access(p, os.X_OK)):
        raise BuildError(f"--python {path}: not a python executable or a venv/prefix folder")
    return str(p)


def _files(root: Path) -> list[Path]:
    """The files of the staged FMU, sorted; no ``__pycache__`` (the checks and the warm-up
    run the staged copy, and may write Python's or numba's caches into it)."""
    return [f for f in sorted(root.rglob("*"))
            if f.is_file() and "__pycache__" not in f.relative_to(root).parts]


def build(output: str | Path = "dist/RailContact.fmu", profiles: list[str | Path] = (),
          model_identifier: str = MODEL_IDENTIFIER, python: str | Path | None = None,
          warm: bool = True, log=None, wheelsets: int | None = None) -> Path:
    """Build the FMU and return its path.

    Parameters
    ----------
    output
        The .fmu file to write.
    profiles
        Profile files to put into ``resources/`` (the parameters ``wheel_profile`` and
        ``rail_profile`` then name them by file name).
    python
        The Python the FMU is to run in (a python executable or a venv/prefix folder),
        written to ``resources/python.txt``; it is checked here as ``railcontact fmu check``
        does (it must have railcontact's dependencies). Default: the Python building it.
    warm
        Whether to compile the FMU's kernels into the per-user cache in that Python
        (``fmu_bootstrap.py warm``), so that a fresh unpacking's first step does not
        compile them (40-100 s once; seconds when they are cached already). The build does
        not fail when that is not possible: ``log`` says why.
    log
        Called with a line of text for the user (what the warm-up did), or None.
    wheelsets
        None: the FMU of one wheelset. 1 to 8: the FMU of that many wheelsets (their
        variables repeated with ``_k`` appended, solved in worker processes or on threads), the
        number written to
        ``resources/wheelsets.txt`` and fixed in the modelDescription.
    """
    import railcontact
    from railcontact.errors import RailContactError
    from railcontact.fmu.variables import check_wheelsets

    if wheelsets is not None:
        try:
            wheelsets = check_wheelsets(wheelsets)
        except RailContactError as exc:
            raise BuildError(str(exc)) from None
    output = Path(output).resolve()
    package = f"railcontact_fmu_{model_identifier}"
    named = named_python(python) if python is not None else None
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        compile_shim(root, model_identifier)
        res = root / "resources"
        (res / "python").mkdir(parents=True)
        _copy_package(res / "python", package)
        for p in profiles:
            p = Path(p)
            if not p.is_file():
                raise BuildError(f"profile file {p} not found")
            shutil.copy(p, res / p.name)
        if named is None:
            libpython()  # the build interpreter must be able to start in a C host
        cfg = {
            "version": f"{sys.version_info[0]}.{sys.version_info[1]}",
            "executable": sys.executable,
            "package": package,
            "railcontact": getattr(railcontact, "__version__", ""),
            **requirements(),
        }
        (res / "source.sha1").write_text(
            source_digest(profiles, model_identifier, named, wheelsets) + "\n",
            encoding="utf-8")
        if wheelsets is not None:  # (the slave's variables: fmu_src/slave.py, wheelsets_of)
            (res / "wheelsets.txt").write_text(f"{wheelsets}\n", encoding="utf-8")
        (res / "python.cfg").write_text("".join(f"{k}={v}\n" for k, v in cfg.items()),
                                        encoding="utf-8")
        if named is not None:
            (res / "python.txt").write_text(named + "\n", encoding="utf-8")
            from railcontact.fmu.check import check_unpacked

            report = check_unpacked(root, use_env=False)
            if not report.ok:
                raise BuildError(f"the Python given with --python cannot run the FMU:\n"
                                 f"{report.text}")
        if warm:
            from railcontact.fmu.check import warm_unpacked

            if log is not None:
                log("warming the FMU's kernels in the per-user cache (compiled once per "
                    "environment: a few minutes the first time) ...")
            result = warm_unpacked(root, use_env=False)
            if log is not None:
                log(result.text)
        digest = hashlib.sha1()
        for f in _files(root):
            digest.update(f.relative_to(root).as_posix().encode())
            digest.update(f.read_bytes())
        h = digest.hexdigest()
        guid = f"{{{h[:8]}-{h[8:12]}-{h[12:16]}-{h[16:20]}-{h[20:32]}}}"
        (root / "modelDescription.xml").write_text(
            model_description(guid, model_identifier, cfg["railcontact"], wheelsets),
            encoding="utf-8")
        output.parent.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(output, "w", zipfile.ZIP_DEFLATED) as z:
            for f in _files(root):
                z.write(f, f.relative_to(root).as_posix())
    return output


if __name__ == "__main__":  # pragma: no cover
    print(build(*sys.argv[1:2]))
