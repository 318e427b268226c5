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

It relies on numba's caching internals (``numba.core.caching``); where they are not as
expected nothing is installed, and numba's own keys apply (then delete the ``*.nbi`` and
``*.nbc`` files in the package's ``__pycache__`` folders after such an edit).
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
"""The package's folder: its kernels' caches are keyed on its kernel sources."""


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


def _in_package(py_file: str) -> bool:
    try:
        return Path(py_file).resolve().is_relative_to(PACKAGE)
    except (OSError, ValueError):
        return False


def install() -> bool:
    """Key the caches of the kernels defined from now on in this package also on
    :func:`package_stamp`; returns whether it is in place (False: numba missing or its
    internals not as expected)."""
    try:
        from numba.core import caching

        impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl  # (numba < 0.57)
        base = caching._CacheLocator
        classes = impl._locator_classes
    except (ImportError, AttributeError):  # pragma: no cover - numba missing or changed
        return False
    if any(getattr(c, "railcontact_stamp", False) for c in classes):
        return True

    class PackageLocator(base):
        """numba's own locator for a kernel of this package, with the package's stamp
        added to its file's."""

        railcontact_stamp = True

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
                if other is not cls:
                    inner = other.from_function(py_func, py_file)
                    if inner is not None:
                        return cls(inner)
            return None

    classes.insert(0, PackageLocator)
    return True


install()  # before any kernel of the package is defined (imported first by the package)
