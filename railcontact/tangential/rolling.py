"""Steady-rolling discretisation of the tangential problem (rolling in +x).

For element ``I`` the slip per rolling step ``dq = dx`` is (Kalker; ``docs/algorithms.md`` 6.1)::

    S_I = W_I + u_I - u'_I,     W_I = dx (xi - phi y_I, eta + phi (x_I + dx/2))

where ``u = A p`` is the tangential displacement difference and ``u'_I`` the displacement
of the same material particle one step earlier, i.e. at ``x_I + dx`` (upstream, towards
the leading edge). In steady state ``S = W + B p`` with the kernel

    B[k] = A[k] - A[k + 1]            (k = i_I - i_J, element offsets in x)

so ``S`` is one more DC-FFT convolution. ``u_I - u'_I`` is a difference over the rolling
step from ``x_I + dx`` to ``x_I``, centred at ``x_I + dx/2``; the spin part of the rigid
slip is evaluated there too (as CONTACT does, ``facphi = 1/2``). Evaluating it at ``x_I``
instead shifts the lateral creepage by ``phi dx/2``, a first-order error that is large
for spin-dominated cases. ``A[k + 1]`` at the leading-edge row needs the
influence one element beyond the grid; it is computed, so the displacement there is
exact (CONTACT computes it separately as ``ubnd``). In continuous form ``S/dx -> w - du/dx``.

With ``p`` the traction on body 1 and ``u`` the displacement difference of body 1 relative
to body 2, Coulomb's law reads ``|p| <= mu p_n``, ``S = 0`` (adhesion) or
``p = -mu p_n S/|S|`` (slip); ``xi > 0`` then gives ``F_x < 0`` (Kalker's convention).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..errors import RailContactError, check_finite
from ..halfspace.grid import Grid
from ..halfspace.influence import coefficients_at
from ..halfspace.materials import ElasticPair
from ..halfspace.operator import InfluenceOperator, resolve_backend


def steady_rolling_kernels(nx: int, ny: int, dx: float, dy: float,
                           pair: ElasticPair) -> np.ndarray:
    """Kernels ``B = A - A'`` of the blocks xx, xy, yx, yy, shape (2, 2, 2nx-1, 2ny-1) [m/Pa]."""
    X, Y = np.meshgrid(dx * np.arange(-(nx - 1), nx + 1), dy * np.arange(-(ny - 1), ny),
                       indexing="ij")
    out = np.empty((2, 2, 2 * nx - 1, 2 * ny - 1))
    for a, ca in enumerate("xy"):
        for b, cb in enumerate("xy"):
            full = coefficients_at(ca + cb, X, Y, dx, dy, pair)  # offsets -(nx-1) .. nx
            out[a, b] = full[:-1] - full[1:]
    return out


@lru_cache(maxsize=16)
def _cached(nx: int, ny: int, dx: float, dy: float, pair: ElasticPair,
            backend: str) -> InfluenceOperator:
    grid = Grid(nx, ny, dx, dy, 0.0, 0.0)
    return InfluenceOperator(grid, pair, "xy", backend,
                             kernels=steady_rolling_kernels(nx, ny, dx, dy, pair))


def rolling_operator(grid: Grid, pair: ElasticPair, backend: str = "auto") -> InfluenceOperator:
    """The cached operator ``p -> B p`` (components x, y) for steady rolling in +x."""
    if pair.difference != 0.0:
        raise RailContactError(
            "dissimilar materials (K != 0) couple normal and tangential contact; the "
            "steady-rolling solver handles quasi-identical materials only")
    return _cached(grid.nx, grid.ny, float(grid.dx), float(grid.dy), pair,
                   resolve_backend(backend, grid.size))


def rigid_slip(grid: Grid, creepage: tuple[float, float, float],
               spin_offset: float = 1.0 / 6.0) -> np.ndarray:
    """Rigid slip per rolling step ``W = dx (xi - phi y, eta + phi (x + dx/2))`` [m],
    shape (2, nx, ny), at the midpoint of each element's rolling step.

    ``creepage = (xi, eta, phi)``: longitudinal and lateral creepage [-] and spin [1/m].
    """
    wx, wy = rigid_slip_lines(grid, creepage, spin_offset)
    out = np.empty((2, grid.nx, grid.ny))
    out[0] = wx[None, :]
    out[1] = wy[:, None]
    return out


def rigid_slip_lines(grid: Grid, creepage: tuple[float, float, float],
                     spin_offset: float = 1.0 / 6.0) -> tuple[np.ndarray, np.ndarray]:
    """The rigid slip of :func:`rigid_slip` [m] by its lines: ``W_x`` depends on y alone
    (shape (ny,)), ``W_y`` on x alone (shape (nx,)); the same values."""
    if len(creepage) != 3:
        raise RailContactError(f"creepage must be (xi, eta, phi), got {creepage!r}")
    xi, eta, phi = (check_finite(n, v, u) for n, v, u in
                    zip(("xi", "eta", "phi"), creepage, ("-", "-", "1/m"), strict=True))
    return (slip_x(grid.dx, xi, phi, grid.y),
            slip_y(grid.dx, eta, phi, grid.x, spin_offset * grid.dx))


def slip_x(dx, xi, phi, y):
    """The rigid slip per rolling step along x, ``W_x = dx (xi - phi y)`` [m], at the
    lateral position(s) ``y`` [m] (a float or an array; also compiled by numba into the
    solvers' set-up, :func:`~.convexgs._bound_layout`: this file names numba, so the
    kernels' cache is keyed on it, :mod:`railcontact._kernelcache`)."""
    return dx * (xi - phi * y)


def slip_y(dx, eta, phi, x, shift):
    """The rigid slip per rolling step along y, ``W_y = dx (eta + phi (x + shift))`` [m],
    at the longitudinal position(s) ``x`` [m], the spin taken ``shift`` [m] into the step."""
    return dx * (eta + phi * (x + shift))
