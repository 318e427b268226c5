"""The influence operator: tractions on a grid -> surface displacement differences.

``u_a[I] = sum_b sum_J A_ab[I - J] p_b[J]`` for traction components ``b`` and displacement
components ``a`` among ``x, y, z``. The sum is a 2-D linear (non-periodic) convolution,
evaluated by DC-FFT (Liu, Wang & Liu, Wear 243, 2000): the kernel over all offsets is laid
out in wrap-around order on a ``2nx * 2ny`` array and the traction is zero-padded to the
same size, so the circular convolution of the padded arrays equals the linear one on the
grid. The kernel spectra are computed once per operator; FFT plans are cached per padded
shape (and per thread, so concurrent solvers never share buffers), at most
:data:`MAX_PLANS` of them (least recently used dropped first). The products use pruned
transforms (per component count, padded shape and row count): the zero rows of the padded
input and the unused rows of the output are not transformed along y (about 20 % less
time per product). One and two components go through complex transforms
(:class:`_PackedPlan`: ``p_x + i p_y``, or one component's rows in pairs, with a real
linear map ``a z + b conj(z(-k))`` in Fourier space), whose estimated FFTW plans run
faster than those of the real transforms (about 15 % less time a normal product, 30 % a
tangential one); one component on an odd padded row count and three components use
real transforms (:class:`_PrunedPlan`, the 2x2 spectral multiply-add of two components
one compiled pass).

The padded shape is ``2nx x 2ny`` rounded up, per axis, to the next 5-smooth number
(2^a 3^b 5^c, :func:`fft_size`): a fixed set of sizes, so that the changing patches of a
time series share a few plans, and transforms at those sizes are 2-8x faster than at
sizes with large prime factors (76 x 118: 0.35 ms against 0.07 ms for 80 x 120). A larger
padding leaves the linear convolution exact (the offsets that wrap around land in the
zero padding).

FFTW plans with FFTW_ESTIMATE (about 2 ms per new shape, no measuring: the plan of a shape
is a function of the shape alone, so a step repeated after ``fmi2SetFMUstate``, or on a
plan made again after eviction, gives the same bits). Measured plans run 20-50 % faster:
:func:`save_wisdom` measures every size up to a bound once and writes FFTW's wisdom to a
file; with the environment variable ``RAILCONTACT_FFTW_WISDOM`` naming that file (or after
:func:`load_wisdom`), a shape covered by it gets its measured plan at no planning cost,
and any other shape its estimated plan.

Backends
--------
``"pyfftw"``  planned FFTW transforms (FFTW_MEASURE, one thread) — the fast path;
``"scipy"``   ``scipy.fft`` (one worker) — the fallback when pyfftw is missing;
``"dense"``   the full influence matrix — exact reference, and fastest on tiny grids;
``"auto"``    dense up to :data:`DENSE_MAX` elements, else pyfftw if importable, else scipy.
"""

from __future__ import annotations

import os
import threading
from collections import OrderedDict
from collections.abc import Callable, Sequence
from functools import lru_cache, partial

import numpy as np
import scipy.fft

from ..errors import RailContactError
from . import fftw as _fftw
from .fftw import HAVE_PYFFTW, pyfftw  # pyfftw imported without its dask interface
from .grid import Grid
from .influence import influence_kernel
from .materials import ElasticPair

try:
    import numba
except ImportError:  # pragma: no cover
    numba = None

BACKENDS = ("auto", "pyfftw", "scipy", "dense")
DENSE_MAX = 144
"""Largest grid (elements) on which ``"auto"`` uses the dense product."""
PRECONDITIONER_FLOOR = 1e-2
"""Eigenvalues of the circulant kernel below this fraction of the largest are raised to it
(:meth:`InfluenceOperator.preconditioner`). Stretched elements (dx != dy) give eigenvalues
down to about -0.008 of the largest; with 1e-2 the preconditioned matrix M A has a
condition number of 2-4 on square and 1:4 elements (1e-3 and 3e-2 give up to 9)."""

MAX_PLANS = 32
"""FFT plans kept per thread (each holds its buffers: ~10 nx ny complex numbers per
component); the least recently used one is dropped beyond this."""

WISDOM_ENV = "RAILCONTACT_FFTW_WISDOM"
"""Environment variable naming a wisdom file (:func:`save_wisdom`) loaded at import."""

_local = threading.local()


def fft_size(n: int) -> int:
    """The smallest 5-smooth number (2^a 3^b 5^c) >= ``n`` (>= 1)."""
    m = max(int(n), 1)
    while True:
        k = m
        for f in (2, 3, 5):
            while k % f == 0:
                k //= f
        if k == 1:
            return m
        m += 1


def padded_shape(nx: int, ny: int) -> tuple[int, int]:
    """The DC-FFT shape of an ``nx`` x ``ny`` grid: ``2n`` rounded up by :func:`fft_size`."""
    return fft_size(2 * nx), fft_size(2 * ny)


def operator_bytes(nx: int, ny: int, components: int, backend: str) -> float:
    """Memory [bytes] an :class:`InfluenceOperator` of ``components`` (1-3) on an ``nx``
    x ``ny`` grid takes with the concrete ``backend`` (not ``"auto"``), estimated before
    anything is allocated: the kernels, and the dense matrix (``(components nx ny)^2``
    numbers, twice that while the blocks of several components are joined) or the
    kernels' spectra on the padded grid."""
    nc, n = float(components), float(nx) * float(ny)
    kernels = 8.0 * nc * nc * (2.0 * nx - 1.0) * (2.0 * ny - 1.0)
    if backend == "dense":
        return kernels + 8.0 * (nc * n) ** 2 * (2.0 if components > 1 else 1.0)
    px, py = padded_shape(nx, ny) if n < 1e12 else (2.0 * nx, 2.0 * ny)
    return kernels + 16.0 * nc * nc * px * (py // 2 + 1)


class _PrunedPlan:
    """The DC-FFT product of ``nc`` components with pruned transforms: of the padded input
    only the ``nx`` rows that hold the traction are transformed along y (the rest are
    zero), and of the product only those ``nx`` rows are transformed back along y; the
    transforms along x run over all rows. About 3/4 of the work of the full 2-D
    transforms, the same result to round-off. One component has 2-D buffers, several a
    leading component axis; their spectral 2x2 (nc x nc) multiply-add is one compiled
    pass. Used where :class:`_PackedPlan` is not (:func:`_packs`): one component on an
    odd padded row count, three components, or without numba."""

    def __init__(self, nx: int, shape: tuple[int, int], measure: bool = False,
                 nc: int = 1):
        m, n = shape
        k = n // 2 + 1
        lead = () if nc == 1 else (nc,)
        ax = len(lead)  # the x axis of the buffers
        self.rows_in = pyfftw.zeros_aligned(lead + (nx, n), dtype="float64")
        self.half = pyfftw.zeros_aligned(lead + (m, k), dtype="complex128")  # rows nx.. 0
        self.spec = pyfftw.empty_aligned(lead + (m, k), dtype="complex128")
        self.prod = pyfftw.empty_aligned(lead + (m, k), dtype="complex128")
        self.rows_out = pyfftw.empty_aligned(lead + (nx, n), dtype="float64")
        self.steps = (
            _plan(self.rows_in, self.half[..., :nx, :], "FFTW_FORWARD", (ax + 1,), measure),
            _plan(self.half, self.spec, "FFTW_FORWARD", (ax,), measure))
        self.back = (  # out of place, into ``spec`` (free after the multiply): in place,
            # FFTW's estimated plan along x took 2.5x as long at 80 and 96 rows
            _plan(self.prod, self.spec, "FFTW_BACKWARD", (ax,), measure),
            _plan(self.spec[..., :nx, :], self.rows_out, "FFTW_BACKWARD", (ax + 1,),
                  measure))
        self.rows_in[...] = 0.0  # (measuring overwrites the buffers)
        self.half[...] = 0.0
        self.ny = 0
        """The grid width last written into ``rows_in`` (its padding must stay zero)."""
        # per product: the executes as bound methods, the grid's columns of the row
        # buffers as views (formed when the width changes), a two-component spectrum's
        # operands as flat rows (the compiled multiply-add's arrays)
        self._fwd = tuple(step.execute for step in self.steps)
        self._bwd = tuple(step.execute for step in self.back)
        self._in = self._out = None
        self._flat = ((self.spec.reshape(nc, -1), self.prod.reshape(nc, -1))
                      if nc == 2 and _spectral_product_2c is not None else None)

    def convolve(self, spectrum: np.ndarray, p: np.ndarray, out: np.ndarray | None
                 ) -> np.ndarray:
        """``p`` (nx, ny), or (nc, nx, ny), convolved with the kernels of the (scaled)
        ``spectrum`` (m, n//2+1), or (nc, nc, m, n//2+1) (two components: also as its
        flat rows (4, m (n//2+1)), :func:`_flat_spectra`)."""
        ny = p.shape[-1]
        if ny != self.ny:
            self.rows_in[...] = 0.0
            self.ny = ny
            self._in, self._out = self.rows_in[..., :ny], self.rows_out[..., :ny]
        self._in[...] = p
        f0, f1 = self._fwd
        f0()
        f1()
        if self._flat is not None:
            _spectral_product_2c(spectrum.reshape(4, -1), *self._flat)
        elif self.spec.ndim == 2:
            np.multiply(spectrum, self.spec, out=self.prod)
        else:
            _spectral_product(spectrum, self.spec, self.prod)
        b0, b1 = self._bwd
        b0()
        b1()
        if out is None:
            return self._out.copy()
        out[...] = self._out
        return out


def _packs(nc: int, m: int) -> bool:
    """Whether the products of ``nc`` components on ``m`` padded rows use
    :class:`_PackedPlan` (one component: ``m`` even; two: always; compiled kernels)."""
    return numba is not None and (nc == 2 or (nc == 1 and m % 2 == 0))


def _row_stride(n: int) -> int:
    """The row stride (complex numbers) of a packed plan's buffers of ``n`` columns: ``n``,
    or ``n + 8`` when ``n`` is a multiple of 32 (rows 32 n bytes apart share a few cache
    sets: the column transforms along x at 128 columns took 51 us against 8.7 with 136)."""
    return n + 8 if n % 32 == 0 else n


class _PackedPlan:
    """The DC-FFT product of one or two real components through complex transforms.

    Two components: ``z = p_x + i p_y``; one component: the rows in pairs, ``z_j = p_2j +
    i p_2j+1`` (``m/2`` padded rows). The product of the real convolution is then a real
    linear map of ``z``, in Fourier space ``w(k) = a(k) z(k) + b(k) conj(z(-k))``
    (:func:`_packed_operands`), and ``w`` holds the result as ``u_x + i u_y`` (or ``u_2j
    + i u_2j+1``). The transforms are pruned as :class:`_PrunedPlan`'s (along y only the
    rows that hold ``z``, forward and back); FFTW's estimated plans of complex transforms
    run faster here than those of the real ones (r2c/c2r: 64 x 108 padded, 32 rows,
    5.9 us against 5.2 for the same data packed, 80 x 128: 6.6 against 2.5)."""

    def __init__(self, nx: int, shape: tuple[int, int], measure: bool = False,
                 nc: int = 1):
        m, n = shape
        h, r = (m // 2, (nx + 1) // 2) if nc == 1 else (m, nx)
        st = _row_stride(n)

        def buffer(rows: int) -> np.ndarray:  # (rows, st), aligned, zero
            return pyfftw.zeros_aligned((rows, st), dtype="complex128")

        self.z_in = buffer(r)   # the packed input (columns ny.. zero)
        self.z_y = buffer(h)    # transformed along y (rows r.. zero)
        self.z_s = buffer(h)    # the spectrum; then the product transformed back along x
        self.w_s = buffer(h)    # the product's spectrum
        self.w_out = buffer(r)  # the packed result
        self.nc, self.n = nc, n
        cut = np.s_[:, :n]
        transforms = (  # (from, into, axis, direction): forward along y, x; back along x, y
            (self.z_in[cut], self.z_y[:r, :n], 1, "FFTW_FORWARD"),
            (self.z_y[cut], self.z_s[cut], 0, "FFTW_FORWARD"),
            (self.w_s[cut], self.z_s[cut], 0, "FFTW_BACKWARD"),
            (self.z_s[:r, :n], self.w_out[cut], 1, "FFTW_BACKWARD"))
        self.compiled = _fftw.AVAILABLE
        """Whether the product is one compiled call (FFTW's plans executed inside it,
        :mod:`.fftw`), else pyfftw's executes between compiled kernels."""
        if self.compiled:
            self.plans = np.array([_c_plan(a, b, (ax,), d, measure)
                                   for a, b, ax, d in transforms], dtype=np.uintp)
            _fftw.destroy_when_gone(self, self.plans)
        else:
            steps = [_plan(a, b, d, (ax,), measure) for a, b, ax, d in transforms]
            self._fwd = tuple(step.execute for step in steps[:2])
            self._bwd = tuple(step.execute for step in steps[2:])
        self.z_in[...] = 0.0  # (measuring overwrites the buffers)
        self.z_y[...] = 0.0
        self.ny = 0
        """The grid width last written into ``z_in`` (its padding must stay zero)."""
        self._pack, self._unpack = ((_pack_rows, _unpack_rows) if nc == 1
                                    else (_pack_pair, _unpack_pair))
        self._product = _packed_rows if nc == 1 else _packed_pair

    def kernel_arguments(self, operands: tuple[np.ndarray, np.ndarray], ny: int) -> tuple:
        """The arguments ``(plans, z_in, z_s, w_s, w_out, a, b, n)`` of the compiled
        product (:func:`_packed_rows_py`, :func:`_packed_pair_py`: ``(plans, x, z_in,
        z_s, w_s, w_out, a, b, n, out)``) for grids of width ``ny``, for a compiled solver
        that runs the products itself (the plan compiled only; in its thread, within one
        solve)."""
        if ny != self.ny:
            self.z_in[...] = 0.0
            self.ny = ny
        return (self.plans, self.z_in, self.z_s, self.w_s, self.w_out, operands[0],
                operands[1], self.n)

    def convolve(self, operands: tuple[np.ndarray, np.ndarray], p: np.ndarray,
                 out: np.ndarray | None) -> np.ndarray:
        """``p`` (nx, ny), or (2, nx, ny), convolved: ``operands`` the plan's ``(a, b)``
        of the kernels (:func:`_packed_operands`)."""
        ny = p.shape[-1]
        if ny != self.ny:
            self.z_in[...] = 0.0
            self.ny = ny
        if self.compiled:
            if out is None:
                out = np.empty(p.shape)
            self._product(self.plans, p, self.z_in, self.z_s, self.w_s, self.w_out,
                          operands[0], operands[1], self.n, out)
            return out
        self._pack(p, self.z_in)
        f0, f1 = self._fwd
        f0()
        f1()
        _real_linear(operands[0], operands[1], self.z_s, self.w_s, self.n)
        b0, b1 = self._bwd
        b0()
        b1()
        if out is None:
            out = np.empty(p.shape)
        self._unpack(self.w_out, out)
        return out


def _packed_operands(spectra: np.ndarray, shape: tuple[int, int]
                     ) -> tuple[np.ndarray, np.ndarray]:
    """The operands ``(a, b)`` of :class:`_PackedPlan`'s ``w = a z + b conj(z(-k))`` for
    the scaled half spectra (nc, nc, m, n//2+1) of one or two components (any real
    kernels: neither symmetry nor reciprocity is assumed), complex (h, n) with the
    row stride of the plan's buffers (``h = m/2`` for one component, ``m`` for two).

    Two components, ``S`` the full spectra: ``a = (S_xx + S_yy + i (S_yx - S_xy))/2``,
    ``b = (S_xx - S_yy + i (S_xy + S_yx))/2``. One component, rows in pairs (``q <
    m/2``, ``S1 = S(q)``, ``S2 = S(q + m/2)``, ``t = 2 pi q / m``): ``a = S1 + S2 - (S1 -
    S2) sin t``, ``b = i (S1 - S2) cos t`` (twice the half-sum of the even and odd rows'
    spectra: the transforms of ``m/2`` rows take half of the 1/m of the scaling)."""
    nc = spectra.shape[0]
    m, n = shape
    k = n // 2 + 1
    full = np.empty((nc, nc, m, n), dtype=complex)
    full[..., :k] = spectra
    if n > k:  # the other half by the real kernels' symmetry S(-k) = conj(S(k))
        rows = -np.arange(m) % m
        full[..., k:] = np.conj(spectra[..., rows, :][..., n - np.arange(k, n)])
    if nc == 1:
        s1, s2 = full[0, 0, :m // 2], full[0, 0, m // 2:]
        t = 2 * np.pi * np.arange(m // 2)[:, None] / m
        a, b = (s1 + s2) - (s1 - s2) * np.sin(t), 1j * (s1 - s2) * np.cos(t)
    else:
        s = full
        a = ((s[0, 0] + s[1, 1]) + 1j * (s[1, 0] - s[0, 1])) / 2
        b = ((s[0, 0] - s[1, 1]) + 1j * (s[0, 1] + s[1, 0])) / 2
    st = _row_stride(n)
    out = []
    for x in (a, b):
        y = np.zeros((x.shape[0], st), dtype=complex)
        y[:, :n] = x
        out.append(y)
    return out[0], out[1]


def _real_linear_py(a: np.ndarray, b: np.ndarray, z: np.ndarray, w: np.ndarray, n: int
                    ) -> None:
    """``w(k) = a(k) z(k) + b(k) conj(z(-k))`` over the first ``n`` columns of (h, st)
    complex arrays, ``-k`` taken modulo (h, n). The indices are unsigned: numba skips its
    negative-index checks, and the reversed loop is vectorised (about the time of one
    complex multiply of the arrays, 3 against 8 us on 32 x 108 with signed ones)."""
    h = z.shape[0]
    un = np.uint64(n)
    for q in range(h):
        qm = h - q if q else 0
        ar, br, zr, zm, wr = a[q], b[q], z[q], z[qm], w[q]
        wr[0] = ar[0] * zr[0] + br[0] * zm[0].conjugate()
        for c in range(1, n):
            uc = np.uint64(c)
            wr[uc] = ar[uc] * zr[uc] + br[uc] * zm[un - uc].conjugate()


def _pack_rows_py(p: np.ndarray, z: np.ndarray) -> None:
    """``z[j, :ny] = p[2j] + i p[2j+1]`` (an odd last row with zero imaginary parts)."""
    nx, ny = p.shape
    for j in range(nx // 2):
        for c in range(ny):
            z[j, c] = complex(p[2 * j, c], p[2 * j + 1, c])
    if nx % 2:
        for c in range(ny):
            z[nx // 2, c] = complex(p[nx - 1, c], 0.0)


def _unpack_rows_py(w: np.ndarray, out: np.ndarray) -> None:
    """``out[2j] = Re w[j]``, ``out[2j+1] = Im w[j]`` over ``out``'s columns."""
    nx, ny = out.shape
    for j in range(nx // 2):
        for c in range(ny):
            v = w[j, c]
            out[2 * j, c] = v.real
            out[2 * j + 1, c] = v.imag
    if nx % 2:
        for c in range(ny):
            out[nx - 1, c] = w[nx // 2, c].real


def _pack_pair_py(p: np.ndarray, z: np.ndarray) -> None:
    """``z[:, :ny] = p[0] + i p[1]``."""
    _, nx, ny = p.shape
    for j in range(nx):
        for c in range(ny):
            z[j, c] = complex(p[0, j, c], p[1, j, c])


def _unpack_pair_py(w: np.ndarray, out: np.ndarray) -> None:
    """``out[0] = Re w``, ``out[1] = Im w`` over ``out``'s rows and columns."""
    _, nx, ny = out.shape
    for j in range(nx):
        for c in range(ny):
            v = w[j, c]
            out[0, j, c] = v.real
            out[1, j, c] = v.imag


if numba is not None:
    _real_linear, _pack_rows, _unpack_rows, _pack_pair, _unpack_pair = (
        numba.njit(cache=True, nogil=True)(f)
        for f in (_real_linear_py, _pack_rows_py, _unpack_rows_py, _pack_pair_py,
                  _unpack_pair_py))


def _packed_rows_py(plans, p, z_in, z_s, w_s, w_out, a, b, n, out):  # pragma: no cover
    """:class:`_PackedPlan`'s product of one component in one compiled call that releases
    the GIL once: the rows packed in pairs, FFTW's four transforms (``plans``, executed
    through FFTW's C interface, :mod:`.fftw`), the spectral map and the unpacking."""
    _pack_rows(p, z_in)
    _fftw.execute(plans[0])
    _fftw.execute(plans[1])
    _real_linear(a, b, z_s, w_s, n)
    _fftw.execute(plans[2])
    _fftw.execute(plans[3])
    _unpack_rows(w_out, out)


def _packed_pair_py(plans, p, z_in, z_s, w_s, w_out, a, b, n, out):  # pragma: no cover
    """:func:`_packed_rows_py` for two components (``p_x + i p_y``)."""
    _pack_pair(p, z_in)
    _fftw.execute(plans[0])
    _fftw.execute(plans[1])
    _real_linear(a, b, z_s, w_s, n)
    _fftw.execute(plans[2])
    _fftw.execute(plans[3])
    _unpack_pair(w_out, out)


if numba is not None and _fftw.AVAILABLE:
    _packed_rows, _packed_pair = (numba.njit(cache=True, nogil=True)(f)
                                  for f in (_packed_rows_py, _packed_pair_py))
else:  # pragma: no cover
    _packed_rows = _packed_pair = None
packed_product = {1: _packed_rows, 2: _packed_pair}
"""The compiled DC-FFT product of a packed plan of one or two components (None without
FFTW's C interface): ``packed_product[nc](plans, x, z_in, z_s, w_s, w_out, a, b, n,
out)`` with the arguments of :meth:`InfluenceOperator.compiled_product`, for compiled
solvers."""


def _spectral_product_2(s: np.ndarray, q: np.ndarray, u: np.ndarray) -> None:
    """``u[0] = s[0] q[0] + s[1] q[1]``, ``u[1] = s[2] q[0] + s[3] q[1]`` (complex, rows
    of flat arrays: ``s`` (4, N) the spectra s00, s01, s10, s11, ``q``, ``u`` (2, N)): the
    2x2 spectral multiply-add of a two-component product, one pass a component: loops
    over 1-D rows with three operands each, which LLVM vectorises (one loop over both
    components' eight arrays ran scalar: 64 x 55 elements 17 -> 10 us, the same bits)."""
    q0, q1 = q[0], q[1]
    for r in range(2):
        sa, sb, ur = s[2 * r], s[2 * r + 1], u[r]
        for i in range(ur.shape[0]):
            ur[i] = sa[i] * q0[i] + sb[i] * q1[i]


if numba is not None:
    _spectral_product_2c = numba.njit(cache=True, nogil=True)(_spectral_product_2)
else:  # pragma: no cover
    _spectral_product_2c = None


def _spectral_product(spectra: np.ndarray, spec: np.ndarray, prod: np.ndarray) -> None:
    """``prod[a] = sum_b spectra[a, b] spec[b]`` for ``spectra`` (nc, nc, m, k) and
    ``spec``, ``prod`` (nc, m, k), complex and C-contiguous (two components: one compiled
    pass; else a numpy multiply-add per pair)."""
    nc = spec.shape[0]
    if nc == 2 and _spectral_product_2c is not None:
        _spectral_product_2c(spectra.reshape(4, -1), spec.reshape(2, -1), prod.reshape(2, -1))
        return
    for a in range(nc):
        np.multiply(spectra[a, 0], spec[0], out=prod[a])
        for b in range(1, nc):
            prod[a] += spectra[a, b] * spec[b]


def _plan(a: np.ndarray, b: np.ndarray, direction: str, axes: tuple[int, ...] = (1, 2),
          measure: bool = False):
    """The measured plan if the wisdom has it, else the estimated one (``measure``:
    measured now, for :func:`save_wisdom`)."""
    kw = {"axes": axes, "direction": direction, "threads": 1}
    with _fftw.PLANNER_LOCK:  # (with the plans made through FFTW's C interface)
        if measure:
            return pyfftw.FFTW(a, b, flags=("FFTW_MEASURE",), **kw)
        try:
            return pyfftw.FFTW(a, b, flags=("FFTW_MEASURE", "FFTW_WISDOM_ONLY"), **kw)
        except RuntimeError:  # not in the wisdom
            return pyfftw.FFTW(a, b, flags=("FFTW_ESTIMATE",), **kw)


def _c_plan(a: np.ndarray, b: np.ndarray, axes: tuple[int, ...], direction: str,
            measure: bool = False) -> int:
    """:func:`_plan`'s plan of a complex transform made through FFTW's C interface (the
    same flags in the same order: the same plan), as an integer for compiled kernels."""
    if measure:
        plan = _fftw.plan_dft(a, b, axes, direction, ("FFTW_MEASURE",))
    else:
        plan = (_fftw.plan_dft(a, b, axes, direction, ("FFTW_MEASURE", "FFTW_WISDOM_ONLY"))
                or _fftw.plan_dft(a, b, axes, direction, ("FFTW_ESTIMATE",)))
    if not plan:  # pragma: no cover - FFTW plans any complex transform with ESTIMATE
        raise RailContactError(f"FFTW made no plan of a {a.shape} transform")
    return plan


def save_wisdom(path: str | os.PathLike, max_elements: int = 100, components: Sequence[int]
                = (1, 2)) -> int:
    """Measure the FFTW plans of every padded shape of grids up to ``max_elements`` per
    axis (the 5-smooth sizes: the products' plans of every row count, :func:`_new_plan`,
    for 1- and 2-component operators) and write FFTW's wisdom to ``path``; returns the
    number of plans. Every product is pruned, so only the pruned plans are measured; 64
    per axis (1,922 shapes) takes minutes on a 2-core machine, and the default, 100
    (3,042 shapes, larger ones), takes longer. The plans cached in this thread are
    dropped (the others are planned from the new wisdom)."""
    if not HAVE_PYFFTW:
        raise RailContactError("FFTW wisdom needs pyfftw")
    if not isinstance(max_elements, int) or max_elements < 2:
        raise RailContactError(f"max_elements must be an integer >= 2, got {max_elements!r}")
    sizes = sorted({fft_size(2 * n) for n in range(2, max_elements + 1)})
    count = 0
    for nc in components:
        for m in sizes:
            for n in sizes:
                # the products' pruned plans, of every grid with this padded shape
                for nx in range(2, max_elements + 1):
                    if fft_size(2 * nx) == m:
                        _new_plan(nc, (m, n), nx, measure=True)
                        count += 1
    with open(path, "wb") as f:
        f.write(repr(pyfftw.export_wisdom()).encode())
    getattr(_local, "plans", OrderedDict()).clear()
    return count


def load_wisdom(path: str | os.PathLike) -> None:
    """Add the wisdom of a file written by :func:`save_wisdom` (plans made from now on use
    it; cached plans are dropped so that every shape is planned the same way)."""
    if not HAVE_PYFFTW:
        raise RailContactError("FFTW wisdom needs pyfftw")
    import ast

    try:
        with open(path, "rb") as f:
            wisdom = ast.literal_eval(f.read().decode())
        if not (isinstance(wisdom, tuple) and len(wisdom) == 3
                and all(isinstance(w, bytes) for w in wisdom)):
            raise ValueError("not the wisdom tuple that save_wisdom writes")
        ok = pyfftw.import_wisdom(wisdom)
    except Exception as exc:  # a bad file is an error of ours, whatever pyfftw raised
        raise RailContactError(f"cannot read FFTW wisdom from {path}: {exc}") from None
    if not ok[0]:
        raise RailContactError(f"FFTW wisdom in {path} was not accepted (another FFTW?)")
    getattr(_local, "plans", OrderedDict()).clear()


def _new_plan(nc: int, shape: tuple[int, int], rows: int, measure: bool = False
              ) -> _PackedPlan | _PrunedPlan:
    """The plan of ``nc`` components on the padded ``shape`` for grids of ``rows`` rows:
    packed (:func:`_packs`), else pruned."""
    if _packs(nc, shape[0]):
        return _PackedPlan(rows, shape, measure, nc)
    return _PrunedPlan(rows, shape, measure, nc)


def _fftw_plan(nc: int, shape: tuple[int, int], rows: int) -> _PackedPlan | _PrunedPlan:
    """The cached plan (:func:`_new_plan`) of ``nc`` components on the padded ``shape``
    for grids of ``rows`` rows."""
    cache = getattr(_local, "plans", None)
    if cache is None:
        cache = _local.plans = OrderedDict()
    key = (nc, shape, rows)
    plan = cache.get(key)
    if plan is None:
        plan = cache[key] = _new_plan(nc, shape, rows)
        while len(cache) > MAX_PLANS:
            cache.popitem(last=False)
    else:
        cache.move_to_end(key)
    return plan


def _wraparound(kernel: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Lay the offset kernel (2nx-1, 2ny-1) out in DC-FFT wrap-around order on ``shape``
    (at least 2nx-1 x 2ny-1): offset k at index k mod the size."""
    mx, my = kernel.shape
    nx, ny = (mx + 1) // 2, (my + 1) // 2
    i = np.arange(-(nx - 1), nx) % shape[0]
    j = np.arange(-(ny - 1), ny) % shape[1]
    k = np.zeros(shape)
    k[np.ix_(i, j)] = kernel
    return k


def _scaled_spectra(kernels: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Spectra (nc, nc, m, n//2+1) of the kernels wrapped around on the padded ``shape``
    (m, n), with the 1/(m n) of the inverse transform folded in (FFTW does not scale)."""
    nc = kernels.shape[0]
    wrapped = np.stack([[_wraparound(kernels[a, b], shape) for b in range(nc)]
                        for a in range(nc)])
    return np.fft.rfft2(wrapped) / (shape[0] * shape[1])


def _dense_matrix(kernel: np.ndarray, nx: int, ny: int) -> np.ndarray:
    """Full (nx*ny, nx*ny) matrix A[I, J] = kernel[I - J] (row-major element order)."""
    i = np.arange(nx)
    j = np.arange(ny)
    di = (i[:, None] - i[None, :]) + nx - 1  # (nx, nx)
    dj = (j[:, None] - j[None, :]) + ny - 1  # (ny, ny)
    m = kernel[di[:, None, :, None], dj[None, :, None, :]]  # (nx, ny, nx, ny)
    return m.reshape(nx * ny, nx * ny)


def resolve_backend(backend: str, size: int) -> str:
    """The concrete backend that ``backend`` means for a grid of ``size`` elements."""
    if backend not in BACKENDS:
        raise RailContactError(f"fft backend must be one of {BACKENDS}, got {backend!r}")
    if backend == "auto":
        if size <= DENSE_MAX:
            return "dense"
        return "pyfftw" if HAVE_PYFFTW else "scipy"
    if backend == "pyfftw" and not HAVE_PYFFTW:
        raise RailContactError("fft backend 'pyfftw' requested but pyfftw is not installed; "
                               "pip install pyfftw, or choose 'scipy'")
    return backend


class InfluenceOperator:
    """Linear operator from traction components to displacement components on a grid.

    Parameters
    ----------
    grid
        The potential-contact grid (only element count and size matter).
    pair
        Combined elastic parameters of the two bodies.
    components
        Traction/displacement components handled, e.g. ``"z"`` (normal problem) or
        ``"xy"`` (tangential problem with quasi-identical materials) or ``"xyz"``.
    backend
        One of :data:`BACKENDS`.

    Notes
    -----
    ``apply`` takes an array of shape ``(nx, ny)`` for one component or
    ``(ncomp, nx, ny)`` for several, in Pa, and returns displacements in m.
    """

    def __init__(self, grid: Grid, pair: ElasticPair, components: str = "z",
                 backend: str = "auto", kernels: np.ndarray | None = None):
        if not components or any(c not in "xyz" for c in components) or len(
                set(components)) != len(components):
            raise RailContactError(f"components must be distinct letters of 'xyz', got "
                                   f"{components!r}")
        self.nx, self.ny = grid.nx, grid.ny
        self.dx, self.dy = grid.dx, grid.dy
        self.pair = pair
        self.components = components
        self.backend = resolve_backend(backend, grid.size)
        nc = len(components)
        if kernels is None:
            kernels = np.stack([
                np.stack([influence_kernel(a + b, self.nx, self.ny, self.dx, self.dy, pair)
                          for b in components]) for a in components])
        else:
            expected = (nc, nc, 2 * self.nx - 1, 2 * self.ny - 1)
            if kernels.shape != expected:
                raise RailContactError(f"kernels must have shape {expected}, "
                                       f"got {kernels.shape}")
        self.kernels = kernels  # (nc, nc, 2nx-1, 2ny-1)
        nx, ny = self.nx, self.ny
        first = kernels[0, 0]
        if first.dtype != np.float64 or not first.flags.carray:
            first = np.require(first, dtype=float, requirements="CW")
        self.first_kernel = (first, float(first[nx - 1, ny - 1]))
        """The kernel of the first component's block (2nx-1, 2ny-1) [m/Pa] (C-ordered,
        writeable: the compiled solvers' layout) and its centre, an element's influence
        on itself [m/Pa]."""
        self._padded = padded_shape(nx, ny)
        self._shapes = ((nc, nx, ny),) + (((nx, ny),) if nc == 1 else ())  # apply's inputs
        self._inverse: dict[tuple[float, bool], np.ndarray] = {}
        self._operands: dict[int, tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]] = {}
        if self.backend == "dense":
            self._matrix = self.dense()
        else:
            self._spectra = _scaled_spectra(self.kernels, self._padded)
            if self.backend == "pyfftw":  # plan now, not inside the first solve
                _fftw_plan(nc, self._padded, self.nx)

    @property
    def self_coefficient(self) -> np.ndarray:
        """The (nc, nc) block of an element's influence on itself [m/Pa]."""
        return self.kernels[:, :, self.nx - 1, self.ny - 1].copy()

    def kernel(self, block: str) -> np.ndarray:
        """Offset kernel of one block, e.g. ``"zz"``, shape (2nx-1, 2ny-1) [m/Pa]."""
        a, b = (self.components.index(c) for c in block)
        return self.kernels[a, b]

    def apply(self, traction: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Displacement differences [m] due to ``traction`` [Pa].

        ``out`` (the shape of the result, float) receives the result instead of a new
        array (an iterative solver's buffer)."""
        p = np.asarray(traction, dtype=float)
        if p.shape not in self._shapes:
            nc = len(self.components)
            raise RailContactError(f"traction must have shape {(nc, self.nx, self.ny)} "
                                   f"(or {(self.nx, self.ny)} for one component), got "
                                   f"{np.shape(traction)}")
        if self.backend == "dense":
            u = (self._matrix @ p.reshape(-1)).reshape(p.shape)
            if out is not None:
                out[...] = u
                u = out
            return u
        return self._convolve(self._spectra, p, out)

    def bound(self, floor: float | None = None) -> Callable[[np.ndarray, np.ndarray],
                                                             np.ndarray]:
        """The product (:meth:`apply`), or with a ``floor`` the FFT preconditioner
        (:meth:`preconditioner`), as one function ``f(x, out) -> out`` for the repeated
        products of one solve: ``x`` and ``out`` of the one shape ``apply`` returns, float,
        neither checked (a solver's own work arrays). The FFT plan is fetched once: use the
        function within the solve, in the thread that formed it (plans hold buffers and
        are kept per thread). The same values as ``apply``/``preconditioner``."""
        if floor is not None:
            spectra = self._inverse_spectra(floor, complex_=True)
        elif self.backend == "dense":
            return self.apply
        else:
            spectra = self._spectra
        if self.backend != "pyfftw":
            return partial(self._convolve, spectra)
        plan, operand = self._fftw(spectra)
        return partial(plan.convolve, operand)

    def compiled_product(self, floor: float | None = None) -> tuple | None:
        """The arguments ``(plans, z_in, z_s, w_s, w_out, a, b, n)`` of :data:`packed_product`
        for this operator's product (:meth:`_PackedPlan.kernel_arguments`), or with a
        ``floor`` for its FFT preconditioner's (:meth:`preconditioner`, one component),
        for a compiled solver that runs its products itself: ``packed_product[nc](plans,
        x, z_in, z_s, w_s, w_out, a, b, n, out)`` is :meth:`bound`'s ``(x, out)``, the
        same bits. None when the product is not one compiled call (not ``"pyfftw"``, a
        pruned plan, no FFTW C interface). As :meth:`bound`: within one solve, in the
        thread that formed it."""
        if self.backend != "pyfftw":
            return None
        spectra = (self._spectra if floor is None
                   else self._inverse_spectra(floor, complex_=True))
        plan, operand = self._fftw(spectra)
        if not isinstance(plan, _PackedPlan) or not plan.compiled:
            return None
        return plan.kernel_arguments(operand, self.ny)

    def preconditioner(self, floor: float = PRECONDITIONER_FLOOR
                       ) -> Callable[[np.ndarray], np.ndarray]:
        """An approximate inverse of a one-component operator, applied by FFT.

        The padded DC-FFT kernel is a circulant matrix; the reciprocal of its spectrum is
        the inverse of that periodic problem, an approximate inverse of the influence
        matrix (the role of CONTACT's FFT preconditioner, Vollebregt, JCP 257A, 2014). The
        half-space kernel falls off as 1/r, so its spectrum grows towards low wave numbers
        as ``1/|k|``; its inverse multiplies pressure errors by ``|k|``, which is what the
        conjugate gradients lack for element-scale errors. The circulant embedding of the
        (positive definite) Toeplitz matrix can have a few tiny or slightly negative
        eigenvalues; they are floored at ``floor`` times the largest one.

        Returns ``M(r)``: residual [m] on the grid -> pressure-like correction [Pa].
        """
        inverse = self._inverse_spectra(floor, complex_=True)

        def apply(residual: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
            return self._convolve(inverse, np.asarray(residual, dtype=float), out)

        return apply

    def _inverse_spectra(self, floor: float, complex_: bool = False) -> np.ndarray:
        """The preconditioner's spectra (1, 1, m, n//2+1) at ``floor``, formed once: real;
        with ``complex_`` for the FFTW products as complex numbers with zero imaginary
        parts (numpy's real-by-complex multiply casts the real factor so, at twice the
        cost of a complex-by-complex one: the same values)."""
        if len(self.components) != 1:
            raise RailContactError("the FFT preconditioner is for one-component operators")
        key = (floor, complex_ and self.backend == "pyfftw")
        inverse = self._inverse.get(key)
        if inverse is None:
            if key[1]:
                inverse = self._inverse_spectra(floor).astype(complex)
            else:
                spec = (self._spectra if self.backend != "dense"
                        else _scaled_spectra(self.kernels, self._padded))
                spec = spec.real  # the kernel is even: its spectrum is real
                inverse = 1.0 / np.maximum(spec, floor * spec.max())
                # _convolve folds 1/N into the spectra, so the inverse gets 1/N^2 of its own
                inverse /= (self._padded[0] * self._padded[1]) ** 2
            self._inverse[key] = inverse
        return inverse

    def _fftw(self, spectra: np.ndarray) -> tuple[_PackedPlan | _PrunedPlan, object]:
        """The FFTW plan of this operator's grid (this thread's) and its operand for the
        kernels of ``spectra`` (nc, nc, m, n//2+1): a packed plan's ``(a, b)``, formed
        once per spectra (:func:`_packed_operands`), or the spectra of a pruned plan."""
        nc = spectra.shape[0]
        plan = _fftw_plan(nc, self._padded, self.nx)
        if isinstance(plan, _PrunedPlan):
            return plan, spectra[0, 0] if nc == 1 else spectra
        held = self._operands.get(id(spectra))
        if held is None or held[0] is not spectra:
            held = self._operands[id(spectra)] = (spectra,
                                                  _packed_operands(spectra, self._padded))
        return plan, held[1]

    def _convolve(self, spectra: np.ndarray, p: np.ndarray, out: np.ndarray | None = None
                  ) -> np.ndarray:
        """Linear convolution of ``p`` (nc, nx, ny), or (nx, ny) for one component, with
        kernels given by their padded spectra (nc, nc, m, n//2+1), scaled by 1/(m n); into
        ``out`` (the shape of ``p``) if given."""
        if self.backend == "pyfftw":
            plan, operand = self._fftw(spectra)
            if p.ndim == 3 and p.shape[0] == 1:
                return plan.convolve(operand, p[0], None if out is None else out[0])[None]
            return plan.convolve(operand, p, out)
        single = p.ndim == 2
        q = p[None] if single else p
        nx, ny = self.nx, self.ny
        spec = scipy.fft.rfft2(q, s=self._padded, workers=1)  # (nc, m, n//2+1)
        prod = np.einsum("abij,bij->aij", spectra, spec)
        m, n = self._padded
        u = scipy.fft.irfft2(prod, s=self._padded, workers=1)[:, :nx, :ny] * (m * n)
        if single:
            u = u[0]
        if out is None:
            return u
        out[...] = u
        return out

    def dense(self) -> np.ndarray:
        """The full influence matrix (nc*nx*ny, nc*nx*ny) [m/Pa] (for tests and tiny grids)."""
        nc = len(self.components)
        return np.block([[_dense_matrix(self.kernels[a, b], self.nx, self.ny)
                          for b in range(nc)] for a in range(nc)])


@lru_cache(maxsize=32)
def _cached_operator(nx: int, ny: int, dx: float, dy: float, pair: ElasticPair,
                     components: str, backend: str) -> InfluenceOperator:
    return InfluenceOperator(Grid(nx, ny, dx, dy, 0.0, 0.0), pair, components, backend)


def influence_operator(grid: Grid, pair: ElasticPair, components: str | Sequence[str] = "z",
                       backend: str = "auto") -> InfluenceOperator:
    """A cached :class:`InfluenceOperator` for the element count and size of ``grid``.

    Repeated calls with the same element count, element size, materials, components and
    backend return the same object, so the influence coefficients and kernel spectra are
    computed once (the FMU and the studies call the solver thousands of times).
    """
    comps = "".join(components)
    return _cached_operator(grid.nx, grid.ny, float(grid.dx), float(grid.dy), pair, comps,
                            resolve_backend(backend, grid.size))


if HAVE_PYFFTW and os.environ.get(WISDOM_ENV):  # pragma: no cover - environment
    try:
        load_wisdom(os.environ[WISDOM_ENV])
    except Exception as _exc:  # a bad file costs speed, never the import
        import warnings

        warnings.warn(f"{WISDOM_ENV}: {_exc}; FFT plans are estimated", stacklevel=1)
