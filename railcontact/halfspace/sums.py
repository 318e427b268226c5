"""Sums in numpy's order, for compiled kernels.

``numpy.sum`` of a contiguous float array adds its elements in memory order by pairwise
summation (numpy's ``pairwise_sum``: blocks of at most 128 elements summed with eight
accumulators, larger runs split in halves at a multiple of 8). A kernel that forms the
terms of a sum can add them in that order itself, and so give numpy's sum to the bit
without the call (a per-step path: each ``ndarray.sum`` costs a microsecond or two of
calls around a few hundred nanoseconds of adding).
"""

from __future__ import annotations

import numba
import numpy as np

PAIRWISE_BLOCK = 128
"""numpy's ``PW_BLOCKSIZE``: runs up to this length are summed with eight accumulators."""


@numba.njit(cache=True, nogil=True)
def _block_sum(a, lo, n):  # pragma: no cover - compiled
    """numpy's sum of a run of at most :data:`PAIRWISE_BLOCK` elements ``a[lo:lo + n]``."""
    if n < 8:
        res = 0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    m = n - n % 8
    while i < m:
        k = lo + i
        r0 += a[k]
        r1 += a[k + 1]
        r2 += a[k + 2]
        r3 += a[k + 3]
        r4 += a[k + 4]
        r5 += a[k + 5]
        r6 += a[k + 6]
        r7 += a[k + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@numba.njit(cache=True, nogil=True)
def pairwise_sum(a, lo, n):  # pragma: no cover - compiled
    """The sum of ``a[lo:lo + n]`` (1-D, float) in numpy's pairwise order: a run longer
    than :data:`PAIRWISE_BLOCK` is the sum of its halves (the first ``n // 2`` rounded
    down to a multiple of 8), each summed so; here by an explicit stack (numba caches no
    recursive function)."""
    if n <= PAIRWISE_BLOCK:
        return _block_sum(a, lo, n)
    depth = 64  # halving from n < 2^63 down to a block
    los = np.empty(depth, dtype=np.int64)
    ns = np.empty(depth, dtype=np.int64)
    stage = np.zeros(depth, dtype=np.int8)  # 0: left half next, 1: right half, 2: add
    values = np.empty(depth)
    top = 0
    nv = 0
    los[0], ns[0] = lo, n
    while top >= 0:
        m = ns[top]
        if m <= PAIRWISE_BLOCK:
            values[nv] = _block_sum(a, los[top], m)
            nv += 1
            top -= 1
            continue
        half = m // 2
        half -= half % 8
        if stage[top] == 0:
            stage[top] = 1
            los[top + 1], ns[top + 1], stage[top + 1] = los[top], half, 0
            top += 1
        elif stage[top] == 1:
            stage[top] = 2
            los[top + 1], ns[top + 1], stage[top + 1] = los[top] + half, m - half, 0
            top += 1
        else:
            nv -= 1
            values[nv - 1] = values[nv - 1] + values[nv]
            top -= 1
    return values[0]


@numba.njit(cache=True)  # a few us: keeps the GIL (see the threads docs)
def numpy_sum(a):  # pragma: no cover - compiled
    """``a.sum()`` of a C-contiguous float64 array, as numpy adds it: the pairwise sum
    added to the reduction's start ``+0.0`` (which turns the -0.0 of a run of -0.0 into
    0.0, as numpy's)."""
    flat = a.reshape(a.size)
    return 0.0 + pairwise_sum(flat, 0, flat.size)


def array_sum(a: np.ndarray) -> float:
    """``a.sum()`` of a float64 array [its unit], the same bits: compiled
    (:func:`numpy_sum`, no numpy call) when ``a`` is C-contiguous."""
    return float(numpy_sum(a) if a.flags.c_contiguous else a.sum())
