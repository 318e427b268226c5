"""The load loop of a wheel: the vertical force of its patches, and the secant iteration
that makes normal and creep forces together carry a vertical wheel load.

A vertical wheel load Q [N] is the rail's total vertical force on the wheel, as CONTACT's
FZ: ``sum_k (N_k cos(gamma_k) + F_s,k sin(gamma_k)) = Q``, ``F_s,k`` the patch's creep
force across the track (in the contact plane, towards the field side). On a flange the
creep force carries a large part of it (``mu tan(gamma)`` ~ 0.8 at 70 deg with mu = 0.3),
and beyond Nadal's limit (``mu tan(gamma) > 1``, sliding up) no normal force carries it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import replace
from functools import lru_cache
from time import perf_counter
from typing import TypeVar

import numpy as np

from ..errors import RailContactError, SolverError
from ..geometry.points import ContactPoint
from ..halfspace.hertz import hertz
from ..halfspace.materials import ElasticPair
from ..settings import Control, GridSettings, PatchSettings
from ..settings.friction import FrictionTable, friction_at_point
from ..status import Status
from ..tangential.kalker import creep_coefficients
from .results import PatchSolution
from .wheel import (
    CREEP_LOAD_RTOL,  # noqa: F401  (its home is .wheel; read here too)
    WheelPass,
    WheelProblem,
    WheelSettings,
    WheelSolution,
    WheelStart,
)

T = TypeVar("T")
MAX_SECANT = 30
"""Secant steps at most, of the approach and of the normal share."""
MAX_STALLED = 3
"""Passes in a row that do not halve the smallest residual, after which the creep-load
iteration stops."""
LOAD_SLACK_CAP = 0.01
"""Largest relative miss of a wheel load accepted for the creep forces' noise (a wheel that
misses its load by more is not converged, whatever its creep forces)."""
MAX_SHARE = 100.0
"""Largest normal share of a vertical load the creep-load iteration tries: a flange near
Nadal's limit (``cos(gamma) - mu sin(gamma)`` -> 0) needs N >> Q; beyond it the load
cannot be carried (the wheel climbs)."""
PROBE_FACTOR = 10.0
"""A probe pass (a cold wheel's first normal solve, in a frame formed at Hertz's approach:
only the approach it gives is used, to form the frame again) is solved to this multiple of
the normal tolerance (at most :data:`PROBE_TOLERANCE`): 3.4 fewer CG iterations a cold step
on ``scripts/bench_step.py``, the same passes; 30 makes more passes."""
PROBE_TOLERANCE = 1e-2
"""The loosest normal tolerance of a probe pass."""
PROBE_COARSENING = 2
"""A probe pass whose start gives no pressure (no estimate: ``[normal] estimate = "none"``,
a time step's cold ``warm_start = "none"`` or ``"previous"``) is solved on elements this
many times as large along each axis (:func:`probe_grid`: a quarter of the elements; given
element counts, that many times fewer). From the uniform start its CG takes about ten
iterations, each a fifth of a full grid's. On ``scripts/bench_step.py``'s cold run (S1002
on 60E1, 0.5 mm elements) its approach is within 0.17 % of the full grid's (0.08 % at the
median), and the pass after it starts from its pressure interpolated onto the full grid.
A probe started from a pressure (an estimate, a table's previous point) takes a few
iterations on the full grid and stays there, and so does one at a normal tolerance tighter
than :data:`PROBE_COARSE_TOLERANCE`."""
PROBE_COARSE_TOLERANCE = 1e-3
"""The tightest normal tolerance at which a probe is coarsened. The frame formed at a coarse
probe's approach serves the pass after it within 1e-3 of the approach
(:data:`~.wheelrail.WARM_REFERENCE_RTOL`); a tighter solve needs its frame within its own
tolerance, which the coarse grid's approach (0.1 % off) misses, and the further pass costs
more than the coarse grid saves: on ``scripts/bench_wheelrail.py``'s cold cases at CONTACT's
tolerance (1e-5), 5.4 load and frame passes a case against 4.1, and 0.28 of the workload
against 0.25."""


def probe_settings(settings: PatchSettings) -> PatchSettings:
    """``settings`` with the normal tolerance of a probe pass (:data:`PROBE_FACTOR`, at most
    :data:`PROBE_TOLERANCE`); formed once per settings (and constants)."""
    try:
        hash(settings)
    except TypeError:  # (settings that do not hash: formed each time)
        return _probe_settings(settings, PROBE_FACTOR, PROBE_TOLERANCE)
    return _probe_settings_cached(settings, PROBE_FACTOR, PROBE_TOLERANCE)


def _probe_settings(settings: PatchSettings, factor: float, loosest: float) -> PatchSettings:
    tol = settings.normal.tolerance
    probe = max(min(factor * tol, loosest), tol)
    return replace(settings, normal=replace(settings.normal, tolerance=probe))


_probe_settings_cached = lru_cache(maxsize=64)(_probe_settings)


def probe_grid(settings: PatchSettings) -> GridSettings | None:
    """The grid of a probe pass whose start gives no pressure: the settings' grid with
    elements :data:`PROBE_COARSENING` times as large (element sizes) or that many times
    fewer (element counts) along each axis; formed once per grid (and constant). None
    (the settings' grid) at a normal tolerance tighter than
    :data:`PROBE_COARSE_TOLERANCE`."""
    if settings.normal.tolerance < PROBE_COARSE_TOLERANCE:
        return None
    return _probe_grid(settings.grid, PROBE_COARSENING)


@lru_cache(maxsize=64)
def _probe_grid(grid: GridSettings, c: int) -> GridSettings:
    return replace(grid, nx=max(2, grid.nx // c), ny=max(2, grid.ny // c),
                   dx=None if grid.dx is None else c * grid.dx,
                   dy=None if grid.dy is None else c * grid.dy)


def vertical_creep_estimate(cp: ContactPoint, load: float, creepage: tuple[float, float, float],
                            pair: ElasticPair, friction: float | FrictionTable) -> float:
    """An estimate of a patch's creep force share of a vertical wheel load [N],
    ``F_s sin(gamma)``: Kalker's linear theory on the Hertz ellipse of the contact point
    ``cp`` (its curvatures and contact angle) carrying the vertical ``load`` [N] by its normal
    force, with the patch's ``creepage`` (xi, eta, phi) [-, -, 1/m], saturated at
    ``friction`` mu as Shen, Hedrick & Elkins (1983) do (the force's magnitude ``F`` becomes
    ``mu N (u - u^2/3 + u^3/27)``, ``u = F / (mu N)``, and ``mu N`` beyond ``u = 3``; a
    friction table's mu at ``cp``); 0 where ``cp`` has no convex contact.

    The first normal share of a cold load loop (:func:`creep_load_secant`'s ``start``).
    With ``cp`` in the frame at the reference point that the normal solve forms first, on
    the hunting run of ``scripts/bench_step.py`` (83.3 kN, shares up to 380 N) it is within
    18 N of the BEM's at the median (114 N at most), so that the first pass mostly meets a
    load tolerance of 1e-3. FaStrip on the same ellipse is closer (60 N at most) but costs
    0.5-1 ms a call, about what the second pass it saves costs.
    """
    g = cp.contact_angle
    if not (load > 0 and math.isfinite(cp.B) and cp.B > 0 and cp.A > 0):
        return 0.0
    hz = hertz(cp.A, cp.B, pair, load=load / math.cos(g))
    if not (hz.a > 0 and hz.b > 0 and math.isfinite(hz.a * hz.b)):
        return 0.0  # (a load too small or large for floats: no estimate, the BEM decides)
    c = creep_coefficients(hz.a, hz.b, pair.poisson)
    ab = hz.a * hz.b
    xi, eta, phi = creepage
    fx = -pair.shear * ab * c.c11 * xi
    fy = -pair.shear * ab * (c.c22 * eta + math.sqrt(ab) * c.c23 * phi)
    linear = math.hypot(fx, fy)
    bound = friction_at_point(friction, cp) * hz.load
    if linear == 0.0 or bound <= 0.0:
        return 0.0
    u = linear / bound
    saturated = bound * (u - u * u / 3 + u ** 3 / 27 if u < 3 else 1.0)
    return fy * saturated / linear * math.sin(g)


def count_passes(final: list[PatchSolution],
                 passes: Iterable[list[PatchSolution]]) -> list[PatchSolution]:
    """The patches of ``final`` charged with the work of every discarded pass (new
    records).

    ``passes`` are the solves of one wheel (``final`` among them or not); the iterations,
    re-meshes and time of each patch of another pass go to the patch of ``final`` nearest to
    it on the rail, and the load passes add up, so that the totals over ``final`` are the
    totals of all the work done.
    """
    extra = 0
    out = final
    for ps in passes:
        if ps is final:
            continue
        extra += max((p.work.load_passes for p in ps), default=1)
        out = charge(out, ps)
    return [f.replaced(work=replace(f.work, load_passes=f.work.load_passes + extra))
            for f in out]


def charge(final: list[PatchSolution], others: Iterable[PatchSolution]
           ) -> list[PatchSolution]:
    """The patches of ``final`` with the iterations, re-meshes and time of ``others``
    (patches solved and left out, of the same pass or another) added to the nearest one
    (new records; lost when ``final`` is empty: no patch to report them)."""
    out = list(final)
    for p in others if final else ():
        k = _nearest(out, p)
        out[k] = out[k].replaced(work=out[k].work.absorbed(p.work))
    return out


def _nearest(patches: list[PatchSolution], p: PatchSolution) -> int:
    """The index of the patch of ``patches`` nearest to ``p`` on the rail."""
    if p.geometry is None:
        return 0
    u, z = p.geometry.rail_u, p.geometry.position[2]
    return min(range(len(patches)), key=lambda k: math.inf if patches[k].geometry is None
               else math.hypot(patches[k].geometry.rail_u - u,
                               patches[k].geometry.position[2] - z))


def vertical_approach(patches: list[PatchSolution]) -> float:
    """Vertical approach [m] of a wheel beyond first contact, from its solved patches."""
    if not patches:
        return 0.0
    p = patches[0] if len(patches) == 1 else min(patches, key=lambda q: q.geometry.gap)
    return p.normal.penetration / math.cos(p.geometry.contact_angle) + p.geometry.gap


def other_root(patches: list[PatchSolution]) -> float | None:
    """The approach [m] of another root of the wheel's load its patches name
    (:attr:`~.results.PatchSolution.load_other`), None when none does."""
    for p in patches:
        if p.load_other is not None:
            return p.load_other
    return None


def vertical_force(patches: list[PatchSolution]) -> float:
    """Vertical force of the rail on the wheel [N]: normal and (solved) creep forces."""
    total = 0.0
    for p in patches:
        g = p.geometry.contact_angle
        total += p.normal.force * math.cos(g)
        if p.tangential is not None:
            total += p.tangential.force[1] * math.sin(g)
    return total


def load_unique(patches: list[PatchSolution], friction: float | FrictionTable) -> bool:
    """Whether the wheel load has one solution: True unless the wheel has several patches
    and one of them, with a creep force across the track, is steeper than Nadal's angle
    (``mu tan(gamma) >= 1``, ``mu`` the patch's own at its reference point when friction
    varies across the profile).

    The argument, for patches that scale like Hertz's (the similarity the simplified
    theories rest on): a patch's creep force is ``F_s = -+ mu N f(s)`` with ``f`` a rising,
    concave function of the creepage scaled by the patch size, ``s ~ N^(-1/3)``, so
    ``f`` falls as ``N`` grows and ``d(N f)/dN = f - s f'/3 >= 0``. When the creep force
    pushes the wheel down, ``V = N cos(gamma) + mu N f sin(gamma)`` rises with ``N``.
    When it pulls the wheel up, ``V = N (cos(gamma) - mu f sin(gamma))`` is ``N`` times a
    rising function: negative up to some ``N_0`` (the creep force pulls more than the
    normal force pushes) and rising beyond it. Either way one patch carries a load
    ``Q > 0`` at one normal force at most (none beyond Nadal's limit in full sliding).
    For several patches, which share one approach, the sum of such functions rises when
    each one does everywhere - ``dV/dN >= cos(gamma) - mu sin(gamma) > 0`` when
    ``mu tan(gamma) < 1`` - but a steeper patch that pulls while another carries can make
    the sum fall over part of the approach, and a load may be met at several approaches.
    The load loop then returns the one its start leads to (the previous time step's creep
    share in a time series: the continuous one; the normal share Q from cold).

    Limitation: the check sees the patches of the returned solution. A steep patch that
    only appears at a larger approach than the returned one (a flange touching beyond a
    tread contact) could carry the load a second time there, unseen.
    """
    if len(patches) <= 1:  # (then one loaded patch at most)
        return True
    loaded = [p for p in patches if p.tangential is not None and p.geometry is not None]
    if len(loaded) <= 1:
        return True
    return all(_patch_mu(p, friction) * math.tan(abs(p.geometry.contact_angle)) < 1.0
               or p.tangential.force[1] == 0.0 for p in loaded)


def _patch_mu(patch: PatchSolution, friction: float | FrictionTable) -> float:
    """The coefficient of friction [-] a patch was solved with (at its reference point,
    :attr:`~.results.PatchSolution.friction`), else ``friction``'s there."""
    if patch.friction is not None:
        return patch.friction
    return friction_at_point(friction, patch.geometry)


def load_met(patches: list[PatchSolution], load: float, rtol: float,
             tangential_tolerance: float) -> bool:
    """Whether the wheel's vertical force is the ``load`` [N] to ``rtol``, or to the
    accuracy its creep forces have: ``eps_tau`` of their vertical components (on a flange
    near Nadal's limit N is many times the load, and so is the noise of ``F_s sin(gamma)``
    that the tangential BEM's tolerance leaves), but never looser than
    :data:`LOAD_SLACK_CAP` of the load."""
    creep = sum(abs(p.tangential.force[1] * math.sin(p.geometry.contact_angle))
                for p in patches if p.tangential is not None)
    slack = min(tangential_tolerance * creep, LOAD_SLACK_CAP * load)
    return abs(vertical_force(patches) - load) <= max(rtol * load, slack)


def creep_load_secant(residual: Callable[[float], tuple[float, T]], load: float, start: float,
                      rtol: float) -> tuple[T, str]:
    """Secant iteration on the normal forces' share of a vertical wheel load.

    Parameters
    ----------
    residual
        ``residual(qn)`` solves the wheel with its normal forces carrying the vertical load
        ``qn`` [N] and returns (total vertical force including creep forces - ``load`` [N],
        the solution).
    load
        The vertical wheel load Q [N].
    start
        First guess of the normal share [N] (Q, or Q less the previous time step's creep
        share).
    rtol
        Tolerance on ``|residual| / load``.

    Returns
    -------
    solution, message
        The pass closest to the load, and "" when it meets ``rtol``, else why not: beyond
        Nadal's limit (the vertical force is negative and falls as the normal share grows:
        the creep force pulls a sliding flange up more than the normal force pushes it,
        ``mu tan(gamma) > 1``; then the first pass's solution), or the tolerance not
        reached. The iteration stops when :data:`MAX_STALLED` passes in a row do not halve
        the smallest residual: the tangential BEM stops at ``eps_tau``, and an element
        changing between adhesion and slip moves the vertical force by steps (~1e-3 of the
        load on a flange at ``eps_tau = 1e-2``), so the residual has a noise floor. A step
        beyond the two shares before is damped to a factor 2; one between two that bracket
        the load is taken. Stalled further from the load than that floor
        (:data:`LOAD_SLACK_CAP`: near Nadal's limit, where the vertical force bends sharply
        with the normal share) with the load bracketed by two of its shares, it closes in
        on the bracket (:func:`_bracketed_share`).
    """
    tried: list[tuple[float, float]] = []  # (share, residual) of every pass

    def residual_of(q: float) -> tuple[float, T]:
        r, s = residual(q)
        tried.append((q, r))
        return r, s

    q0 = start
    r0, sol = residual_of(q0)
    if abs(r0) <= rtol * load:
        return sol, ""
    first = best = sol
    best_r, stalled = abs(r0), 0
    # First step as if the creep forces grew in proportion to the normal forces (as in
    # full slip); from then on secant steps.
    vertical = r0 + load
    q1 = q0 * load / vertical if vertical > 0 else 2.0 * q0
    q1 = min(max(q1, 0.05 * load), MAX_SHARE * load)
    r1, sol = residual_of(q1)
    for _ in range(MAX_SECANT):
        stalled = 0 if abs(r1) < 0.5 * best_r else stalled + 1
        if abs(r1) < best_r:
            best, best_r = sol, abs(r1)
        if best_r <= rtol * load or stalled >= MAX_STALLED or r1 == r0:
            break
        if r1 + load <= 0 and r0 + load <= 0 and (r1 - r0) * (q1 - q0) <= 0:
            return first, (f"beyond Nadal's limit: the creep forces pull the wheel up more "
                           f"than the normal forces push it (vertical force {r0 + load:.6g} "
                           f"N at a normal share of {q0:.6g} N, {r1 + load:.6g} N at "
                           f"{q1:.6g} N); no normal force carries the load {load:.6g} N")
        q2 = q1 - r1 * (q1 - q0) / (r1 - r0)
        # a step between two shares that bracket the load is taken as it is (it stays in
        # the bracket); beyond them it is damped to at most a factor 2
        bracketed = (r0 < 0.0 < r1 or r1 < 0.0 < r0) and min(q0, q1) < q2 < max(q0, q1)
        q0, r0 = q1, r1
        q1 = q2 if bracketed else min(max(q2, 0.5 * q1, 0.05 * load), 2.0 * q1,
                                      MAX_SHARE * load)
        r1, sol = residual_of(q1)
    if best_r > LOAD_SLACK_CAP * load:  # stalled far from the load (not at the creep
        # forces' noise floor), yet two shares bracket it: close in on it
        best, best_r = _bracketed_share(residual_of, tried, best, best_r, rtol * load)
    if best_r <= rtol * load:
        return best, ""
    return best, (f"the vertical load with creep forces did not converge (vertical force "
                  f"off by {best_r:.6g} N for load {load:.6g} N)")


MAX_BRACKETED = 12
"""Steps at most of the regula falsi on a bracket of the normal share after the secant
stalled (:func:`_bracketed_share`)."""


def _bracketed_share(residual: Callable[[float], tuple[float, T]],
                     tried: list[tuple[float, float]], best: T, best_r: float, tol: float
                     ) -> tuple[T, float]:
    """The creep-load iteration closed in on its root where the secant steps stalled
    (far from the load: near Nadal's limit the vertical force bends sharply with the
    normal share) but two of the shares ``tried`` (share, residual) bracket the load: the
    regula falsi on the tightest bracket (Illinois: an end kept twice has its residual
    halved), at most :data:`MAX_BRACKETED` passes, until a residual is within ``tol``
    [N]. Returns the best solution and its residual's magnitude (``best``, ``best_r``
    when no step improved on them, or no bracket)."""
    below = [(q, r) for q, r in tried if r < 0.0]
    above = [(q, r) for q, r in tried if r > 0.0]
    if not below or not above:
        return best, best_r
    lo, r_lo = max(below, key=lambda t: t[0])  # (the vertical force grows with the share
    hi, r_hi = min(above, key=lambda t: t[0])  # across the bracket: the tightest one)
    if not lo < hi:
        return best, best_r
    kept = 0  # which end was kept last: -1 the lower, +1 the upper
    for _ in range(MAX_BRACKETED):
        q = hi - r_hi * (hi - lo) / (r_hi - r_lo)
        if not lo < q < hi:
            q = 0.5 * (lo + hi)
        r, sol = residual(q)
        if abs(r) < best_r:
            best, best_r = sol, abs(r)
        if best_r <= tol or r == 0.0:
            break
        if r < 0.0:
            lo, r_lo = q, r
            r_hi = 0.5 * r_hi if kept == 1 else r_hi
            kept = 1
        else:
            hi, r_hi = q, r
            r_lo = 0.5 * r_lo if kept == -1 else r_lo
            kept = -1
    return best, best_r


MERGE_WINDOW = 1.3
"""Merges of a wheel's patches (:func:`~railcontact.geometry.points.merge_approaches`)
checked for another solution of its load (:func:`first_root`): those within this factor
of the root's vertical approach. The vertical force grows at least as the approach to the
power 3/2 (Hertz; faster where further patches join in), so a merge 1.3 times the
approach away is met at 1.48 times the load or more (or, below, at 1/1.48 or less): its
jump would have to be a third of the load to bring a second root. The jumps seen on
S1002/60E1 across the flange root are 11-17 % of the load. (1.3 rather than more: each
merge in the window costs a solve of the wheel.)"""
MERGE_STEP = 1e-6
"""Relative step [-] below and above a merge's approach at which the two patches and the
merged one are solved."""


def approach_secant(residual: Callable[[float], tuple[float, T]], a0: float, load: float,
                    rtol: float, below: float = math.inf, noisy: bool = False
                    ) -> tuple[T, float]:
    """Secant iteration on a wheel's vertical approach for its vertical ``load`` [N].

    ``residual(a)`` solves the wheel at the vertical approach ``a`` [m] and returns (its
    vertical force - ``load`` [N], the solution). Starts at ``a0`` [m]; every approach
    tried stays at most ``below`` [m]. Stops at ``|residual| <= rtol load``, after
    :data:`MAX_SECANT` steps, or, ``noisy`` (the creep forces in the load: their noise
    floor, :func:`creep_load_secant`), when :data:`MAX_STALLED` steps in a row do not halve
    the smallest residual. (The normal forces alone are smooth in the approach but for a
    kink where a patch appears, which the secant passes in a few more steps.) Returns the
    solution closest to the load and its residual [N]."""
    r0, sol = residual(a0)
    best, best_r = sol, r0
    if abs(r0) <= rtol * load:
        return best, best_r
    a1 = min(a0 * (0.9 if r0 > 0 else 1.1), below)
    stalled = 0
    for _ in range(MAX_SECANT):
        r1, sol = residual(a1)
        stalled = 0 if abs(r1) < 0.5 * abs(best_r) else stalled + 1
        if abs(r1) < abs(best_r):
            best, best_r = sol, r1
        if abs(r1) <= rtol * load or r1 == r0 or (noisy and stalled >= MAX_STALLED):
            break
        a2 = a1 - r1 * (a1 - a0) / (r1 - r0)
        a0, r0 = a1, r1
        a1 = min(max(a2, 0.5 * a1), 2.0 * a1, below)
    return best, best_r


def first_root(residual: Callable[[float], tuple[float, T]], solution: T, approach: float,
               merges: Iterable[float], load: float, rtol: float, noisy: bool = False
               ) -> tuple[T, float | None]:
    """The solution of a wheel's load with the smallest vertical approach, and the
    approach [m] of another solution (or of the merge of patches beyond which one lies),
    None when none was found: the wheel lowered onto its rail stops at the first
    approach whose vertical force is the load.

    Within one set of patches the vertical force rises with the approach (a half-space's
    pressure rises everywhere as its gap closes; the creep forces' share is bounded by
    :func:`load_unique`'s argument). Where two of the wheel's contact regions join into
    one patch (a saddle of the gap, ``merges`` [m]: the tread and the flange root) the
    model changes: two patches, each in its own tangent plane and blind to the other's
    pressure, become one patch in one plane whose lobes press on one another, and the
    vertical force jumps - down, on S1002/60E1 at 5.3 mm by 11-17 % of the load. A load
    within such a jump is carried at two approaches, one each side of the merge.

    ``solution`` is a root at ``approach`` [m], by whatever start reached it;
    ``residual(a)`` solves the wheel at the approach ``a`` (:func:`approach_secant`, with
    ``noisy``).
    The nearest merge each side within :data:`MERGE_WINDOW` is checked, the wheel solved
    just below and just above it: when the load is carried below a merge under
    ``approach``, the root there is found (to ``rtol``) and returned; when it is not yet
    carried just above a merge beyond, another root lies beyond it. Warm and cold starts
    so return the same root. A root below that the secant does not find (beyond
    :data:`LOAD_SLACK_CAP`) leaves ``solution``, said not to be the only one; a probe that
    raises (beyond the model) leaves it as it is."""
    if type(merges) is np.ndarray and merges.size == 0:  # (the common case: none)
        return solution, None
    m = [float(a) for a in merges]
    below = [a for a in m if approach / MERGE_WINDOW <= a < approach]
    above = [a for a in m if approach < a <= approach * MERGE_WINDOW]
    try:
        if approach > 0 and below:
            top = max(below) * (1.0 - MERGE_STEP)
            r, at_top = residual(top)
            if r >= 0:  # carried before the patches join: the root below is the first
                if abs(r) <= rtol * load:
                    return at_top, approach
                start = top * (load / (r + load)) ** (2 / 3)  # (as Hertz's)
                first, r = approach_secant(residual, start, load, rtol, below=top,
                                           noisy=noisy)
                # (missed within the noise: the caller's check; missed by far: the root
                # found stands, said not to be the only one)
                return (first, approach) if abs(r) <= LOAD_SLACK_CAP * load else \
                    (solution, top)
        if approach > 0 and above:
            bottom = min(above) * (1.0 + MERGE_STEP)
            r, _ = residual(bottom)
            if r <= 0:  # not carried just beyond the merge: a second root further on
                return solution, bottom
    except (RailContactError, SolverError):  # a probe beyond the model: none checked
        return solution, None
    return solution, None


def creep_load(problem: WheelProblem, settings: WheelSettings, start: WheelStart
               ) -> WheelSolution:
    """The wheel ``problem`` carrying its vertical load with normal and creep forces: the
    creep-load loop of every wheel solve (:func:`~.wheelrail.solve_wheel`).

    A secant iteration on the normal forces' share (:func:`creep_load_secant`, from the
    share ``start`` expects: :meth:`~.wheel.WheelStart.share`) until the vertical force
    meets the load to ``settings.load_tolerance``, then the smallest approach that carries
    it (:func:`first_root`, the problem's merges). Each pass is ``start``'s
    (:meth:`~.wheel.WheelStart.solve_pass`, started from the pass before); the work of
    every pass is charged to the patches returned, the time of the share's estimate is
    the solution's own (:attr:`~.wheel.WheelSolution.seconds`). The solution is not
    converged, with the loop's message, when the load is missed by more than
    ``settings.load_acceptance`` (and by more than the accuracy of the creep forces,
    :func:`load_met`); its patches say whether the load has another root
    (``load_other``, ``load_unique``)."""
    q = problem.control.load
    passes: list[WheelPass] = []

    def wheel_pass(value: float, by_load: bool = True) -> tuple[float, WheelPass]:
        """The pass with the normal forces carrying ``value`` [N] (``by_load``), else at
        the vertical approach ``value`` [m]: its vertical force less the load, and it."""
        normal = Control(load=value) if by_load else Control(penetration=value)
        passes.append(start.solve_pass(problem, settings, normal,
                                       passes[-1] if passes else None))
        return vertical_force(passes[-1].patches) - q, passes[-1]

    t0 = perf_counter()
    share = start.share(problem, settings, q)
    seconds = perf_counter() - t0
    first = min(max(q - share, 0.05 * q), MAX_SHARE * q)
    rtol, t = settings.load_tolerance, settings.tangential
    final, failure = creep_load_secant(wheel_pass, q, first, rtol)
    patches = final.patches
    if not patches:
        return WheelSolution(memory=final.memory)
    other = None
    merges = problem.merges
    if not failure and not (type(merges) is np.ndarray and merges.size == 0):
        # the smallest approach of the load with its creep forces (none other without
        # merges of patches: first_root)
        final, other = first_root(lambda a: wheel_pass(a, False), final,
                                  vertical_approach(patches), problem.merges, q, rtol,
                                  noisy=True)
        patches = final.patches
    one_root = load_unique(patches, t.friction)  # (of the patches returned)
    if len(passes) > 1:  # the work of every pass counts
        patches = count_passes(patches, [p.patches for p in passes])
    if not failure:
        # the total's roots, not the normal share's of a pass (new records where they
        # change it: a pass forms its patches with load_unique True)
        unique = other is None and one_root
        patches = [p if p.load_other == other and p.load_unique is unique
                   else p.replaced(load_other=other, load_unique=unique) for p in patches]
        if other is not None and not load_met(patches, q, rtol, t.tolerance):
            failure = ("the vertical load with creep forces did not converge at the "
                       "smallest approach that carries it (vertical force "
                       f"{vertical_force(patches):.6g} N for load {q:.6g} N)")
    accept = max(settings.load_acceptance, rtol)
    status, message = Status.OK, "ok"
    if failure and not load_met(patches, q, accept, t.tolerance):
        status, message = Status.NOT_CONVERGED, failure
    return WheelSolution(patches, status, message, final.creepages, final.memory,
                         load_other=other_root(patches), steep=not one_root,
                         seconds=seconds)  # (the share's estimate: the wheel's work)
