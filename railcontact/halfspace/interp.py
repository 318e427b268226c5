"""``np.interp`` at one point, for compiled kernels (numpy's values to the bit).

The simplified models (INFCON's half lengths, the strips' samples of a pressure) read
sampled functions at many points; a kernel that reads them one point at a time finds the
piece (the last sample at or before the point) by walking on from the previous point's or
from a guess on equally spaced samples, and forms numpy's value there. (Written out in a
hot loop, the common case - a point between two samples - is several times faster than a
call of these helpers, which such loops keep for numpy's special cases.)
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def interp_walk_sloped(x, xp, fp, slopes, j):  # pragma: no cover - compiled
    """``(np.interp(x, xp, fp), j)`` for increasing ``xp``, with the pieces' slopes
    ``slopes[j] = (fp[j+1] - fp[j]) / (xp[j+1] - xp[j])`` given (:func:`slopes_of`;
    numpy forms them so too, once, when there are more points than samples): numpy's
    algorithm (the end values beyond ``xp``, the sample's value where ``x`` falls on
    one, the other end of the piece where the first gives NaN; one sample: its value),
    and the piece ``j`` (the last sample at or before ``x``; ``-1`` before the first),
    found by walking on from the piece ``j`` of an earlier point (``-1``: from the
    start; fast for increasing points)."""
    n = xp.size
    if n == 1:
        return fp[0], j
    if math.isnan(x):
        return x, j
    if x < xp[0]:
        return fp[0], -1
    if j < 0 or xp[j] > x:
        j = 0
    while j + 1 < n and xp[j + 1] <= x:
        j += 1
    if x > xp[n - 1] or j >= n - 1:
        return fp[n - 1], j
    f0 = fp[j]
    if xp[j] == x:
        return f0, j
    slope = slopes[j]
    v = slope * (x - xp[j]) + f0
    if math.isnan(v):
        f1 = fp[j + 1]
        v = slope * (x - xp[j + 1]) + f1
        if math.isnan(v) and f0 == f1:
            v = f0
    return v, j


def slopes_of(xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """The slopes ``(fp[j+1] - fp[j]) / (xp[j+1] - xp[j])`` of the pieces of a sampled
    function [fp's unit / xp's unit] (NaN or infinite where numpy's division gives it)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.ascontiguousarray((fp[1:] - fp[:-1]) / (xp[1:] - xp[:-1]))


@numba.njit(cache=True, nogil=True)
def interp_on_piece(x, xp, fp, j):  # pragma: no cover - compiled
    """``np.interp(x, xp, fp)`` for increasing ``xp`` when ``j`` is the last sample at or
    before ``x`` (any ``j`` when ``x`` is NaN or outside ``xp``; :func:`uniform_piece`
    finds it on equally spaced samples)."""
    n = xp.size
    if n == 1:
        return fp[0]
    if math.isnan(x):
        return x
    if x < xp[0]:
        return fp[0]
    if x > xp[n - 1] or j >= n - 1:
        return fp[n - 1]
    f0 = fp[j]
    if xp[j] == x:
        return f0
    f1 = fp[j + 1]
    slope = (f1 - f0) / (xp[j + 1] - xp[j])
    v = slope * (x - xp[j]) + f0
    if math.isnan(v):
        v = slope * (x - xp[j + 1]) + f1
        if math.isnan(v) and f0 == f1:
            v = f0
    return v


@numba.njit(cache=True, nogil=True)
def uniform_piece(x, xp, x0, h):  # pragma: no cover - compiled
    """The last sample ``j`` of increasing ``xp`` at or before ``x`` (0 before the first,
    ``xp.size - 1`` from the last on; NaN: 0), for samples spaced about ``h`` from ``x0``:
    guessed from the spacing, then checked against ``xp`` (so exact for any samples)."""
    n = xp.size
    t = (x - x0) / h
    if not t > 0.0:
        j = 0
    elif t >= n - 1:
        j = n - 1
    else:
        j = int(t)
    while j > 0 and xp[j] > x:
        j -= 1
    while j + 1 < n and xp[j + 1] <= x:
        j += 1
    return j
