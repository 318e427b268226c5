"""numba's on-disk cache of this package's kernels, keyed on all the package's kernel sources.

numba keys a cached kernel (``cache=True``) on the source of its own file alone, yet the
compiled code holds every kernel it calls or inlines from other files: SteadyGS's block
inlines ConvexGS's element solve, many kernels call :func:`~.halfspace.sums.numpy_sum`.
After an edit of the callee's file alone (a ``git pull``, an upgrade that leaves the
caller's file as it was) numba would load the old code from ``__pycache__`` (numba's
documented limitation, numba/numba#1833). :func:`install` adds to the source stamp of
every kernel of this package a hash of all its files that use numba, so that an edit of
any of them compiles the package's kernels afresh, once (a plain function that a kernel
compiles or inlines must live in such a file, i.e. one that names numba).

A copy of the package that is unpacked anew for every run (the FMU's, which fmpy and other
hosts extract into a fresh folder each time) keeps its kernels in a per-user cache folder
instead (:func:`user_cache_folder`), so that they are compiled once per environment, not
once per unpacking. numba's own keys (its ``__pycache__`` folder, or ``NUMBA_CACHE_DIR``
with a hash of the folder's path; before numba 0.68 also the file's modification time and
size as its source stamp) would change with every unpacking. Such a copy holds the file
:data:`USER_CACHE_MARKER` (``railcontact fmu build`` writes it); its kernels are then keyed
on

- the package's module name (numba's cached code imports its module by name when it is
  loaded, so ``railcontact`` and the FMU's ``railcontact_fmu_<id>`` never share entries),
- :func:`package_stamp` (the content of the package's kernel sources, not their paths or
  modification times),
- the Python, numba and numpy versions (:func:`environment_tag`: environments with other
  versions keep their own entries instead of overwriting each other's),

and numba's own checks still apply within that folder (its version and the source stamp in
each index, the Python version in the file names, the signature, the CPU name and features
and the function's bytecode in each entry's key). Where that folder cannot be created or
written, numba's own locations are used (then each unpacking compiles again).

The installed package (a wheel or an editable install) keeps numba's ``__pycache__``
folders next to its sources: they persist, numba overwrites an entry in place when a source
changes (a per-content folder would keep every edited version), and where site-packages is
read-only numba falls back to its own per-user cache.

It relies on numba's caching internals (``numba.core.caching``); where they are not as
expected nothing is installed, and numba's own keys apply (then delete the ``*.nbi`` and
``*.nbc`` files in the package's ``__pycache__`` folders after such an edit).
"""

from __future__ import annotations

import hashlib
import os
import sys
from functools import lru_cache
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
"""The package's folder: its kernels' caches are keyed on its kernel sources."""
PACKAGE_NAME = __name__.rpartition(".")[0] or PACKAGE.name
"""The package's module name (``railcontact``, or ``railcontact_fmu_<id>`` in an FMU)."""
USER_CACHE_MARKER = "_kernelcache_user"
"""A file of this name in the package's folder puts its kernels into
:func:`user_cache_folder` (the FMU's copy of the package holds one)."""
CACHE_DIR_ENV = "RAILCONTACT_CACHE_DIR"
"""Environment variable naming the per-user cache folder (default
``$XDG_CACHE_HOME/railcontact``, else ``~/.cache/railcontact``)."""


@lru_cache(maxsize=1)
def package_stamp() -> str:
    """A hash (hex) of the package's ``.py`` files that use numba, their paths and bytes."""
    digest = hashlib.sha256()
    for path in sorted(PACKAGE.rglob("*.py")):
        data = path.read_bytes()
        if b"numba" in data:
            digest.update(path.relative_to(PACKAGE).as_posix().encode() + b"\0")
            digest.update(data)
    return digest.hexdigest()


def uses_user_cache() -> bool:
    """Whether this copy of the package keeps its kernels in :func:`user_cache_folder`."""
    return (PACKAGE / USER_CACHE_MARKER).is_file()


def cache_root() -> Path | None:
    """The per-user cache folder: ``$RAILCONTACT_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/railcontact``, else ``~/.cache/railcontact``; None when there is no
    home folder to put it in."""
    named = os.environ.get(CACHE_DIR_ENV, "")
    if named:
        return Path(named).expanduser().absolute()
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    if xdg and os.path.isabs(xdg):
        return Path(xdg) / "railcontact"
    try:
        home = Path.home()
    except (RuntimeError, KeyError):  # no HOME and no entry in the password database
        return None
    return home / ".cache" / "railcontact"


def environment_tag() -> str:
    """The versions compiled code depends on, as a folder name:
    ``py311-numba0.61.2-numpy2.2.6`` (CPython 3.11, numba 0.61.2, numpy 2.2.6)."""
    import numba
    import numpy

    impl = sys.implementation.name
    return (f"{'py' if impl == 'cpython' else impl}{sys.version_info[0]}{sys.version_info[1]}"
            f"{getattr(sys, 'abiflags', '')}-numba{numba.__version__}-"
            f"numpy{numpy.__version__}")


def user_cache_folder() -> Path | None:
    """The folder of this package's kernels in the per-user cache:
    ``<cache_root>/numba/<package>-<stamp[:16]>/<environment_tag>`` (a kernel of
    ``tangential/convexgs.py`` goes to its ``tangential`` subfolder); None without a cache
    root."""
    root = cache_root()
    if root is None:
        return None
    return (root / "numba" / f"{PACKAGE_NAME}-{package_stamp()[:16]}" / environment_tag())


def _in_package(py_file: str) -> bool:
    try:
        return Path(py_file).resolve().is_relative_to(PACKAGE)
    except (OSError, ValueError):
        return False


_LOCATION: dict[str, str] = {}
"""Where the kernels defined so far are cached: folder -> kind (``user`` for the per-user
cache, ``numba`` for numba's own locations); see :func:`cache_locations`."""


def cache_locations() -> dict[str, str]:
    """The folders the package's kernels defined so far are cached in (folder -> ``user``
    or ``numba``): for messages, e.g. ``railcontact fmu build``'s report."""
    return dict(_LOCATION)


def kernel_counts() -> tuple[int, int]:
    """(compilations, loads from the cache) of this package's kernels in this process so
    far: numba's cache misses and hits of the kernels its imported modules define (a kernel
    inlined into others has none of its own)."""
    try:
        from numba.core.dispatcher import Dispatcher
    except ImportError:  # pragma: no cover - numba missing
        return 0, 0
    compiled = loaded = 0
    seen: set[int] = set()
    for name, module in list(sys.modules.items()):
        if module is None or not (name == PACKAGE_NAME or name.startswith(PACKAGE_NAME + ".")):
            continue
        for obj in list(vars(module).values()):
            if isinstance(obj, Dispatcher) and id(obj) not in seen:
                seen.add(id(obj))
                compiled += sum(obj.stats.cache_misses.values())
                loaded += sum(obj.stats.cache_hits.values())
    return compiled, loaded


def install() -> bool:
    """Key the caches of the kernels defined from now on in this package also on
    :func:`package_stamp` (and, with :data:`USER_CACHE_MARKER`, keep them in
    :func:`user_cache_folder`); returns whether it is in place (False: numba missing or its
    internals not as expected)."""
    try:
        from numba.core import caching

        impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl  # (numba < 0.57)
        base = caching._CacheLocator
        classes = impl._locator_classes
    except (ImportError, AttributeError):  # pragma: no cover - numba missing or changed
        return False
    # one pair of locators per copy of the package: a Python host may hold railcontact and
    # the FMU's copy at once
    if any(getattr(c, "railcontact_package", None) == str(PACKAGE) for c in classes):
        return True

    class PackageLocator(base):
        """numba's own locator for a kernel of this package, with the package's stamp
        added to its file's."""

        railcontact_package = str(PACKAGE)

        def __init__(self, inner):
            self._inner = inner
            self._py_file = getattr(inner, "_py_file", None)  # (read by numba's warnings)

        def ensure_cache_path(self):
            self._inner.ensure_cache_path()

        def get_cache_path(self):
            return self._inner.get_cache_path()

        def get_source_stamp(self):
            return self._inner.get_source_stamp(), package_stamp()

        def get_disambiguator(self):
            return self._inner.get_disambiguator()

        @classmethod
        def from_function(cls, py_func, py_file):
            if not _in_package(py_file):
                return None
            for other in classes:
                if not hasattr(other, "railcontact_package"):
                    inner = other.from_function(py_func, py_file)
                    if inner is not None:
                        _LOCATION.setdefault(str(inner.get_cache_path()), "numba")
                        return cls(inner)
            return None

    class UserCacheLocator(base):
        """A kernel of this package in :func:`user_cache_folder`, stamped with
        :func:`package_stamp` alone (the same sources unpacked elsewhere, or later, find
        it)."""

        railcontact_package = str(PACKAGE)

        def __init__(self, py_func, py_file, path):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._cache_path = str(path)

        def get_cache_path(self):
            return self._cache_path

        def get_source_stamp(self):
            return package_stamp()

        def get_disambiguator(self):
            return str(self._lineno)

        @classmethod
        def from_function(cls, py_func, py_file):
            if not (uses_user_cache() and _in_package(py_file)):
                return None
            folder = user_cache_folder()
            if folder is None:
                return None
            sub = Path(py_file).resolve().parent.relative_to(PACKAGE)
            self = cls(py_func, py_file, folder / sub)
            try:
                self.ensure_cache_path()  # created, and a file can be written in it
            except OSError:
                return None  # numba's own locations (PackageLocator)
            _LOCATION.setdefault(str(folder), "user")
            return self

    classes.insert(0, PackageLocator)
    classes.insert(0, UserCacheLocator)
    return True


install()  # before any kernel of the package is defined (imported first by the package)
