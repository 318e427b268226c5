"""FFTW for the DC-FFT products: pyfftw imported without its dask interface, and FFTW's C
interface for compiled kernels (plans executed without Python in between).

pyfftw plans and executes FFTW transforms from Python; each ``execute`` is a call from
Python that releases and takes back the GIL. A DC-FFT product is four such transforms with
compiled packing, spectral and unpacking kernels between them, so it hands the GIL over six
times. Here the same FFTW library that pyfftw loaded (its copy in the wheel) is opened with
:mod:`ctypes`; plans are made through its guru interface with the very dimensions, strides
and flags pyfftw passes (so FFTW picks the same algorithm: the same bits), and
:data:`execute` is FFTW's ``fftw_execute`` as a numba external function, so that one
compiled kernel can run a whole product with the GIL released once
(:class:`railcontact.halfspace.operator._PackedPlan`).

Thread safety: FFTW's planner is not thread-safe, its ``fftw_execute`` is. Plans are made
and destroyed under :data:`PLANNER_LOCK`, which :func:`railcontact.halfspace.operator._plan`
also holds around its pyfftw plans, and FFTW's own planner lock is switched on
(``fftw_make_planner_thread_safe``) when the library has it, for pyfftw's planning in other
threads. A plan is executed by one thread at a time (plans are kept per thread).

:data:`AVAILABLE` is False when pyfftw, its FFTW library or numba cannot be found (another
packaging of pyfftw): the products then run through pyfftw's ``execute``, with the
same results.
"""

from __future__ import annotations

import ctypes
import os
import re
import sys
import threading
import weakref
from collections.abc import Sequence

import numpy as np

try:
    import numba
    from llvmlite import binding as _llvm
except ImportError:  # pragma: no cover
    numba = None

FFTW_FORWARD = -1
FFTW_BACKWARD = 1
FFTW_MEASURE = 0
FFTW_UNALIGNED = 1 << 1
FFTW_ESTIMATE = 1 << 6
FFTW_WISDOM_ONLY = 1 << 21
FLAGS = {"FFTW_MEASURE": FFTW_MEASURE, "FFTW_ESTIMATE": FFTW_ESTIMATE,
         "FFTW_WISDOM_ONLY": FFTW_WISDOM_ONLY}
"""The planner flags by pyfftw's names (those the operator uses)."""

PLANNER_LOCK = threading.Lock()
"""Held around every plan made or destroyed by railcontact (here and through pyfftw)."""

class _LeftOut:
    """A meta path finder that makes the import of one module fail in one thread (others
    import it as usual)."""

    def __init__(self, name: str, thread: int):
        self.name, self.thread = name, thread

    def find_spec(self, name, path=None, target=None):
        if name == self.name and threading.get_ident() == self.thread:
            raise ModuleNotFoundError(f"{name} left out while pyfftw is imported", name=name)
        return None


def _import_pyfftw():
    """pyfftw, imported without its dask interface (None when pyfftw is missing).

    pyfftw's package imports ``pyfftw.interfaces``, which imports ``dask.array.fft``
    whenever dask is installed (the ``table`` extra installs it): about a second of
    dask.array and its dependencies at every import of railcontact - every FMU instance's
    start, every ``railcontact solve`` - for an interface railcontact does not use (it
    plans ``pyfftw.FFTW`` objects alone). While pyfftw is imported, the first of
    ``dask``, ``dask.array``, ``dask.array.fft`` not imported yet fails to import in this
    thread (:class:`_LeftOut`, first on ``sys.meta_path``), so pyfftw leaves out
    ``pyfftw.interfaces.dask_fft`` as it does without dask; other threads import dask as
    usual meanwhile (a ``sys.modules[name] = None`` marker, used before, refused their
    ``import dask.array``), a process that imported dask.array before is left as it is,
    and ``import pyfftw.interfaces.dask_fft`` works afterwards as usual."""
    name = next((n for n in ("dask", "dask.array", "dask.array.fft")
                 if n not in sys.modules), None)
    finder = None if name is None else _LeftOut(name, threading.get_ident())
    if finder is not None:
        sys.meta_path.insert(0, finder)
    try:
        import pyfftw as module
    except ImportError:  # pragma: no cover
        return None
    finally:
        if finder is not None:
            sys.meta_path.remove(finder)
    return module


pyfftw = _import_pyfftw()
HAVE_PYFFTW = pyfftw is not None


_SYMBOL = __name__.replace(".", "_") + "_execute"
"""The name compiled kernels call ``fftw_execute`` by (per copy of the package: the FMU's
``railcontact_fmu_<id>`` registers its own)."""
_DOUBLE = re.compile(r"^libfftw3([-.][0-9a-f]+)?\.(so|dylib|dll)|^libfftw3-3\.dll$")
_THREADS = re.compile(r"^libfftw3_(omp|threads)([-.][0-9a-f]+)?\.(so|dylib|dll)")


class _IODim(ctypes.Structure):
    """FFTW's ``fftw_iodim``: a dimension's length and its input and output strides
    (elements)."""

    _fields_ = [("n", ctypes.c_int), ("is_", ctypes.c_int), ("os", ctypes.c_int)]


def _library_dirs(pyfftw) -> list[str]:
    """The folders where a pyfftw wheel keeps its FFTW libraries."""
    here = os.path.dirname(os.path.abspath(pyfftw.__file__))
    return [here, os.path.join(here, ".dylibs"), os.path.join(here, os.pardir, "pyfftw.libs")]


def _find(pyfftw, pattern: re.Pattern) -> str | None:
    for folder in _library_dirs(pyfftw):
        if os.path.isdir(folder):
            for name in sorted(os.listdir(folder)):
                if pattern.match(name):
                    return os.path.join(folder, name)
    return None


def _open(pyfftw):
    """(the double-precision FFTW library pyfftw loaded, or None; whether its planner was
    made thread-safe)."""
    path = _find(pyfftw, _DOUBLE)
    if path is None:
        return None, False
    try:
        lib = ctypes.CDLL(path)
        plan = lib.fftw_plan_guru_dft
        lib.fftw_execute, lib.fftw_destroy_plan  # noqa: B018 - all three must exist
    except (OSError, AttributeError):
        return None, False
    plan.restype = ctypes.c_void_p
    plan.argtypes = [ctypes.c_int, ctypes.POINTER(_IODim), ctypes.c_int,
                     ctypes.POINTER(_IODim), ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                     ctypes.c_uint]
    lib.fftw_destroy_plan.argtypes = [ctypes.c_void_p]
    lib.fftw_destroy_plan.restype = None
    safe = False
    threads = _find(pyfftw, _THREADS)
    for holder in (lib, threads):  # (one library with threads, or a threads library)
        try:
            if isinstance(holder, str):
                holder = ctypes.CDLL(holder)
            if holder is not None:
                holder.fftw_make_planner_thread_safe()
                safe = True
                break
        except (OSError, AttributeError):
            pass
    return lib, safe


def _load():
    if pyfftw is None or numba is None:
        return None, False, None
    lib, safe = _open(pyfftw)
    if lib is None:
        return None, False, None
    address = ctypes.cast(lib.fftw_execute, ctypes.c_void_p).value
    _llvm.add_symbol(_SYMBOL, address)
    return lib, safe, int(pyfftw.simd_alignment)


_lib, PLANNER_THREAD_SAFE, _ALIGNMENT = _load()
AVAILABLE = _lib is not None
"""Whether plans can be made here and executed by compiled kernels."""

if AVAILABLE:
    execute = numba.types.ExternalFunction(_SYMBOL, numba.types.void(numba.types.uintp))
    """``fftw_execute(plan)`` for compiled kernels (the plan as an unsigned integer)."""
else:  # pragma: no cover
    execute = None


_DIMS = {n: _IODim * n for n in (1, 2, 3)}
"""The array types of 1-3 dimensions, held for good: ctypes keeps ``_IODim * n`` only while
the type is alive, and a type is a reference cycle, so a plan formed after the garbage
collector freed the last one formed a new type, which left another cycle behind."""


def _dims(a: np.ndarray, b: np.ndarray, axes: Sequence[int]) -> ctypes.Array:
    size = a.itemsize
    n = max(len(axes), 1)
    kind = _DIMS.get(n) or _IODim * n
    return kind(*[_IODim(a.shape[x], a.strides[x] // size, b.strides[x] // size)
                  for x in axes])


def plan_dft(a: np.ndarray, b: np.ndarray, axes: Sequence[int], direction: str,
             flags: Sequence[str]) -> int:
    """A complex-to-complex plan from ``a`` into ``b`` (complex128 views of the same shape)
    along ``axes``, the other axes as repeated transforms, as pyfftw's ``FFTW(a, b, axes,
    direction, flags, threads=1)`` plans it; 0 when FFTW made no plan (``FFTW_WISDOM_ONLY``
    without wisdom). Destroy it with :func:`destroy` (or :func:`destroy_when_gone`)."""
    if not AVAILABLE:  # pragma: no cover
        raise RuntimeError("FFTW's C interface is not available")
    if a.dtype != np.complex128 or b.dtype != np.complex128 or a.shape != b.shape:
        raise ValueError("plan_dft needs complex128 arrays of one shape")
    code = 0
    for flag in flags:
        code |= FLAGS[flag]
    if a.ctypes.data % _ALIGNMENT or b.ctypes.data % _ALIGNMENT:
        code |= FFTW_UNALIGNED  # as pyfftw adds it
    rest = [x for x in range(a.ndim) if x not in axes]
    sign = FFTW_FORWARD if direction == "FFTW_FORWARD" else FFTW_BACKWARD
    with PLANNER_LOCK:
        plan = _lib.fftw_plan_guru_dft(len(axes), _dims(a, b, axes), len(rest),
                                       _dims(a, b, rest), a.ctypes.data, b.ctypes.data,
                                       sign, code)
    return int(plan or 0)


def destroy(plans: Sequence[int]) -> None:
    """Destroy FFTW plans made by :func:`plan_dft` (zeros are skipped)."""
    with PLANNER_LOCK:
        for plan in plans:
            if plan:
                _lib.fftw_destroy_plan(plan)


def destroy_when_gone(owner: object, plans: Sequence[int]) -> None:
    """Destroy ``plans`` when ``owner`` (which holds their arrays) is collected."""
    weakref.finalize(owner, destroy, tuple(int(p) for p in plans))
