"""The FMU's start-up in Python: copied to ``resources/python/fmu_bootstrap.py``.

Used four ways, all with what ``resources/python.cfg`` records (the FMU's package name,
railcontact's version and the dependency versions it needs):

- ``PYTHON -I fmu_bootstrap.py probe RESOURCES``: the C shim runs it with the Python it
  chose (``RAILCONTACT_PYTHON``, ``resources/python.txt``, the build interpreter) before it
  starts that Python in a C host; it prints ``key=value`` lines (version, prefix, shared
  libpython, site-packages) and ``end=1``;
- executed by the shim in the process's interpreter (``start``): checks the Python and the
  dependencies, makes the FMU's copy of railcontact importable and returns its slave module
  with a report of what it uses;
- ``PYTHON -I fmu_bootstrap.py check RESOURCES LOCATED``: the same ``start`` in a separate
  process, for ``railcontact fmu check`` (prints the report, exit status 0 when the FMU can
  start);
- ``PYTHON -I fmu_bootstrap.py warm RESOURCES LOCATED``: ``start``, then a few steps that
  compile the kernels into the per-user cache, for ``railcontact fmu build``.

It runs in whatever Python the FMU was given, so it uses the standard library only.
"""

import importlib
import os
import platform
import re
import site
import sys
import sysconfig

DEPENDENCIES = {"numpy": "numpy", "scipy": "scipy", "pyfftw": "pyfftw", "numba": "numba"}
"""The distributions the FMU imports, by module name (the others railcontact declares, e.g.
matplotlib and fmpy, are not needed inside the FMU)."""


class StartError(RuntimeError):
    """The FMU cannot run in this Python; the message says why and what to do."""


def read_config(resources):
    """``resources/python.cfg`` as a dict."""
    cfg = {}
    with open(os.path.join(resources, "python.cfg"), encoding="utf-8") as f:
        for line in f:
            key, sep, value = line.rstrip("\n").partition("=")
            if sep:
                cfg[key] = value
    return cfg


def parse_located(text):
    """The ``key=value`` lines the shim passes (which Python, where from, the probe)."""
    out = {}
    for line in text.splitlines():
        key, sep, value = line.partition("=")
        if sep:
            out[key] = value.replace("\x1f", "\n")  # line ends of a multi-line value
    return out


def _numbers(version):
    """The leading release numbers of a version string: '2.1.3rc1' -> (2, 1, 3)."""
    nums = []
    for part in version.split("."):
        m = re.match(r"\d+", part)
        if not m:
            break
        nums.append(int(m.group()))
        if m.end() < len(part):
            break
    return tuple(nums)


def at_least(version, minimum):
    """Whether ``version`` >= ``minimum`` (release numbers only)."""
    a, b = _numbers(version), _numbers(minimum)
    n = max(len(a), len(b))
    return a + (0,) * (n - len(a)) >= b + (0,) * (n - len(b))


def requirements(cfg):
    """``{module: minimum version}`` from ``requires`` in python.cfg (``numpy>=1.24, ...``)."""
    out = {}
    for item in cfg.get("requires", "").split(","):
        name, sep, minimum = item.partition(">=")
        if name.strip():
            out[name.strip()] = minimum.strip() if sep else ""
    return out


def python_problem(cfg):
    """Why this Python cannot run the FMU's copy of railcontact, or ''."""
    need = cfg.get("requires_python", "").strip()
    if need.startswith(">=") and not at_least(platform.python_version(), need[2:]):
        return (f"Python {platform.python_version()} ({sys.executable}) is older than "
                f"railcontact {cfg.get('railcontact', '')} needs ({need})")
    return ""


def find_libpython():
    """The shared CPython library of this interpreter, or '' (and why)."""
    names = [sysconfig.get_config_var(k) for k in ("INSTSONAME", "LDLIBRARY")]
    dirs = [sysconfig.get_config_var("LIBDIR"), os.path.join(sys.base_prefix, "lib"),
            f"/usr/lib/{sysconfig.get_config_var('MULTIARCH')}"]
    for d in dirs:
        for n in names:
            if d and n and ".so" in n and os.path.isfile(os.path.join(d, n)):
                return os.path.join(d, n), ""
    return "", (f"this Python ({sys.executable}) has no shared libpython (Py_ENABLE_SHARED = "
                f"{sysconfig.get_config_var('Py_ENABLE_SHARED')}); a C host needs one to start "
                f"Python (install libpython{sys.version_info[0]}.{sys.version_info[1]}, or "
                "use a Python built with --enable-shared)")


def site_dirs():
    """The site-packages folders of this Python's environment (as ``python -I`` sees it)."""
    return [d for d in site.getsitepackages() if os.path.isdir(d)]


def probe(resources):
    """Print what the shim needs to start this Python (``key=value`` lines, then ``end=1``)."""
    cfg = read_config(resources)
    lib, why = find_libpython()
    values = {
        "version": platform.python_version(),
        "python_executable": sys.executable,
        "prefix": sys.prefix,
        "base_prefix": sys.base_prefix,
        "libpython": lib,
        "libpython_problem": why,
        "site": os.pathsep.join(site_dirs()),
        "problem": python_problem(cfg),
    }
    for k, v in values.items():
        print(f"{k}={v}")
    print("end=1")


def _describe_choice(loc):
    return f"{loc.get('executable', '?')} (from {loc.get('source', '?')})"


def check_dependencies(cfg):
    """Import each dependency the FMU needs; (report lines, problems)."""
    report, problems = [], []
    for module, minimum in requirements(cfg).items():
        need = f" (needs >={minimum})" if minimum else ""
        try:
            mod = importlib.import_module(module)
        except Exception as exc:  # noqa: BLE001 - any import failure is the message
            problems.append(f"{module}{need} cannot be imported: {type(exc).__name__}: {exc}")
            continue
        version = str(getattr(mod, "__version__", "?"))
        where = os.path.dirname(getattr(mod, "__file__", "") or "?")
        if minimum and not at_least(version, minimum):
            problems.append(f"{module} {version} ({where}) is older than the FMU needs "
                            f"(>={minimum})")
        else:
            report.append(f"  {module} {version}{need} from {where}")
    return report, problems


def start(resources, located):
    """Prepare this interpreter for the FMU's slave; returns (slave module, report, warning).

    ``located`` is the shim's text: ``mode`` (``started``: the FMU started this Python;
    ``host``: the process already ran Python; ``check``: ``railcontact fmu check``), which
    Python was chosen and from where, and that Python's probe (or ``locate_error``).
    Raises :class:`StartError` with the whole story when the FMU cannot run here.
    """
    cfg = read_config(resources)
    loc = parse_located(located)
    mode = loc.get("mode", "started")
    here = f"Python {platform.python_version()} ({sys.executable})"
    report, warnings = [], []
    if mode == "host":
        report.append(f"runs in the host's {here}, with the host's packages first on "
                      "sys.path")
        if loc.get("locate_error"):
            warnings.append("the FMU's own choice of Python is not usable, so only the host's "
                            "packages are available:\n" + loc["locate_error"])
        elif _numbers(loc.get("version", ""))[:2] != sys.version_info[:2]:
            warnings.append(f"the Python chosen for the FMU, {_describe_choice(loc)}, is "
                            f"Python {loc.get('version')}, the host's is "
                            f"{platform.python_version()}: its site-packages are not added")
        else:
            added = [d for d in loc.get("site", "").split(os.pathsep)
                     if d and os.path.isdir(d) and d not in sys.path]
            for d in added:
                site.addsitedir(d)  # appended: the host's own packages come first
            report.append(f"  chosen: {_describe_choice(loc)}; its site-packages "
                          + (f"added after the host's: {os.pathsep.join(added)}" if added
                             else "are already on the host's sys.path"))
    else:
        report.append(f"{here}, chosen from {loc.get('source', '?')}, started "
                      + ("by the FMU in this process" if mode == "started" else
                         "as `python -I` (as the FMU starts it in a C host)")
                      + f"; environment {sys.prefix} (base {sys.base_prefix}); only its "
                      "site-packages and the FMU's resources, no user site-packages, no "
                      "PYTHONPATH")
        for d in loc.get("site", "").split(os.pathsep):
            if d and os.path.isdir(d) and d not in sys.path:
                site.addsitedir(d)
        if loc.get("isolation_missing"):  # a newer Python without the C API the shim uses
            warnings.append(f"{here} has no {loc['isolation_missing']}: the FMU could not "
                            "start it fully isolated (PYTHONPATH, PYTHONHOME or the user "
                            "site-packages of the host's environment may count)")
    problem = python_problem(cfg)
    report.append(f"  sys.path: {os.pathsep.join(p for p in sys.path if p)}")
    deps, problems = check_dependencies(cfg)
    report += deps
    if problem:
        problems.insert(0, problem)
    if problems and mode == "host" and warnings:
        # the FMU's own choice of Python failed (named first: it is why the host's packages
        # had to do), and the host's packages lack what the FMU needs
        raise StartError(
            f"the railcontact FMU cannot start in this Python host: {warnings[0]}"
            + f"\nThe FMU runs in the host's {here} instead, whose packages cannot run it:"
            + "".join(f"\n  - {p}" for p in problems)
            + "\n" + "\n".join(report[1:])  # (the first line: the host's Python, said)
            + "\nFix the FMU's choice of Python (RAILCONTACT_PYTHON, or rebuild the FMU with "
            "`railcontact fmu build --python PATH`), or install railcontact's dependencies "
            "in the host's environment ("
            + " ".join(f"'{m}>={v}'" if v else m for m, v in requirements(cfg).items())
            + "); `railcontact fmu check FILE.fmu` prints what the FMU will use.")
    if problems:
        raise StartError(
            f"the railcontact FMU cannot run in {here}, chosen from "
            f"{loc.get('source', 'the host process') if mode != 'host' else 'the host process'}:"
            + "".join(f"\n  - {p}" for p in problems)
            + "\n" + "\n".join(report)
            + "\nInstall railcontact's dependencies in that environment ("
            + " ".join(f"'{m}>={v}'" if v else m for m, v in requirements(cfg).items())
            + "), or set RAILCONTACT_PYTHON to a Python or virtual environment that has them "
            "(or rebuild the FMU with `railcontact fmu build --python PATH`) and restart the "
            "host; `railcontact fmu check FILE.fmu` prints what the FMU will use.")
    python_dir = os.path.join(resources, "python")
    if python_dir not in sys.path:
        sys.path.insert(0, python_dir)
    try:
        module = importlib.import_module(cfg["package"] + "._fmu_slave")
    except Exception as exc:  # noqa: BLE001
        raise StartError(f"the FMU's copy of railcontact ({python_dir}) cannot be imported in "
                         f"{here}: {type(exc).__name__}: {exc}\n" + "\n".join(report)) from exc
    where = os.path.dirname(os.path.dirname(os.path.abspath(module.__file__)))
    report.append(f"  railcontact {cfg.get('railcontact', '?')}: the FMU's own copy "
                  f"({cfg['package']} in {where})")
    return module, "railcontact FMU: " + "\n".join(report), "\n".join(warnings)


def warm(resources, located):
    """Start as :func:`start` does, then run the kernels of a default step so that numba
    compiles them into the per-user cache (``railcontact fmu build`` runs this in the
    Python the FMU will use: a fresh unpacking then loads them instead of compiling).
    Prints ``key=value`` lines: ``compiled``, ``loaded`` (kernels), ``seconds`` [s],
    ``cache`` (the folder, or the reason there is none) and ``persistent`` (1 when the
    kernels went to the per-user cache), then ``end=1``. Raises :class:`StartError` when the
    FMU cannot start here."""
    cfg = read_config(resources)
    module, _, _ = start(resources, located)
    compiled, loaded, seconds = module.warm(resources)
    kernelcache = importlib.import_module(cfg["package"] + "._kernelcache")
    user = [f for f, kind in kernelcache.cache_locations().items() if kind == "user"]
    if user:
        where = user[0]
    elif kernelcache.cache_root() is None:
        where = "no per-user cache folder (no home folder; set RAILCONTACT_CACHE_DIR)"
    else:
        where = (f"the per-user cache folder {kernelcache.user_cache_folder()} cannot be "
                 "created or written (set RAILCONTACT_CACHE_DIR to a writable folder)")
    for key, value in (("compiled", compiled), ("loaded", loaded),
                       ("seconds", f"{seconds:.1f}"), ("cache", where),
                       ("persistent", int(bool(user)))):
        print(f"{key}={value}")
    print("end=1")


def kernel_cache(resources):
    """A line on the FMU's compiled kernels in this environment (after :func:`start`): how
    many the per-user cache holds, or that the first step will compile them."""
    cfg = read_config(resources)
    try:
        kc = importlib.import_module(cfg["package"] + "._kernelcache")
        folder = kc.user_cache_folder() if kc.uses_user_cache() else None
    except Exception as exc:  # noqa: BLE001 - a report line, not a failure
        return f"  kernels: cache not known ({type(exc).__name__}: {exc})"
    if folder is None:
        return ("  kernels: no per-user cache folder (no home folder; set "
                "RAILCONTACT_CACHE_DIR): each unpacking compiles them at its first step")
    count = len(list(folder.rglob("*.nbi"))) if folder.is_dir() else 0
    if count:
        return f"  kernels: {count} compiled in {folder} (loaded at the first step)"
    return (f"  kernels: none compiled yet in {folder}: the first step compiles them (about a "
            "minute, once; `railcontact fmu build` does it ahead)")


def _main(argv):
    if len(argv) >= 2 and argv[0] == "probe":
        probe(argv[1])
        return 0
    if len(argv) >= 3 and argv[0] == "check":
        resources, located = argv[1], argv[2]
        try:
            module, report, warning = start(resources, located)
            module.make_slave(resources, "check")
        except StartError as exc:
            print(exc)
            return 1
        print(report)
        print(kernel_cache(resources))
        if warning:
            print("warning: " + warning)
        return 0
    if len(argv) >= 3 and argv[0] == "warm":
        try:
            warm(argv[1], argv[2])
        except StartError as exc:
            print(f"error={exc}".replace("\n", "\x1f"))
            return 1
        except Exception as exc:  # noqa: BLE001 - warming is optional: say why it failed
            print(f"error={type(exc).__name__}: {exc}".replace("\n", "\x1f"))
            return 1
        return 0
    print("usage: fmu_bootstrap.py probe RESOURCES | check RESOURCES LOCATED | warm RESOURCES "
          "LOCATED", file=sys.stderr)
    return 2


if globals().get("__name__") == "__main__":
    sys.exit(_main(sys.argv[1:]))
