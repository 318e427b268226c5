"""Contact search by the trace method: a wheel at a pose searched once
(:func:`search_wheel`), its record (:class:`~.points.WheelSearch`) what every contact point
and patch frame of the wheel at that pose is formed from (:mod:`.points`).

For a wheel with yaw ``psi`` the contact points lie on the *trace line*: the points of the
wheel surface whose normal has no component along the track (the rail is prismatic).
With the wheel surface ``(r sin t, eta, -r cos t)`` in the wheelset frame and
``r = r0 + F(S(eta))``, this gives ``sin t = -tan(psi) r'(eta)`` (``docs/algorithms.md`` 7.4;
Wang Kaiyun's trace method). The trace points are moved with the wheelset pose (roll after
yaw) into the side frame and compared with the placed rail: ``g(eta)`` is the vertical
distance from the rail to the wheel. For a rigid approach ``delta`` (vertical) every
connected interval of ``g - min g < delta`` is one contact patch, centred on its local
minimum of g: one-point or two-point (several-point) contact
(:func:`~.points.contact_points`).

The functions of a wheel given by track, wheelset, pose and side below
(:func:`contact_points`, :func:`at_reference` ...) search it (the trace remembered for the
last pose of each side) and call those of :mod:`.points`, for callers that do not keep
the search's record.
"""

from __future__ import annotations

import math
import threading

import numpy as np

from ..errors import RailContactError
from ..formed import FormedOnce
from . import kernels
from . import points as _points
from .points import (  # noqa: F401  (the search's records and constants, importable from here too)
    FAR,
    HALF_WIDTH,
    K0,
    N_S,
    WEIGHT_POWER,
    ContactPoint,
    ReferencePoint,
    Samples,
    TangentPlane,
    WheelSearch,
    gap_on_grid,
    lateral_extent,
    normal_penetration,
    overlap_box,
    overlap_on_rail,
    patch_run,
    reference_offset,
    reference_point,
    samples,
)
from .track import SIDES, Pose, Track, Wheelset

N_TRACE = 6001
N_RAIL = 8001
"""Rail samples from which a patch's tangent-plane gap is interpolated."""


def search_wheel(track: Track, ws: Wheelset, pose: Pose, side: str) -> WheelSearch:
    """The ``side`` wheel of the wheelset ``ws`` at ``pose`` over its rail placed on
    ``track``, searched: its trace and least gap, and the rail and the wheel as the kernels
    read them (:class:`~.points.WheelSearch`). Raises a :class:`RailContactError` when the
    wheel is beside its rail (the pose beyond the profiles)."""
    # (the kernel's least gap, sample, order and ties are a Python float, int, bool, int)
    trace, g_min, k, increasing, ties, first, rail, wheel, merges = _trace_of_pose(
        track, ws, pose, side)
    return WheelSearch(track, ws, pose, side, trace, g_min, k, increasing, ties, rail, wheel,
                       first, merges)


def vertical_gap(track: Track, ws: Wheelset, pose: Pose, side: str):
    """Vertical gap g(eta) between the wheel trace and the rail [m], with the trace points.

    Returns ``(eta, x, u, z, g)`` restricted to trace points above the rail.
    """
    return tuple(_trace(track, ws, pose, side)[0])


def least_gap(track: Track, ws: Wheelset, pose: Pose, side: str) -> float:
    """The least vertical gap [m] of the wheel's trace above its rail (the least of
    :func:`vertical_gap`'s ``g``), from the trace the search remembers for the pose."""
    return float(_trace_of_pose(track, ws, pose, side)[1])


def contact_points(track: Track, ws: Wheelset, pose: Pose, side: str,
                   approach: float = 0.0) -> list[ContactPoint]:
    """:func:`~.points.contact_points` of the wheel searched at ``pose``."""
    return _points.contact_points(search_wheel(track, ws, pose, side), approach)


def count_contacts(track: Track, ws: Wheelset, pose: Pose, side: str,
                   approach: float = 0.0) -> int:
    """:func:`~.points.count_contacts` of the wheel searched at ``pose``."""
    return _points.count_contacts(search_wheel(track, ws, pose, side), approach)


def merge_approaches(track: Track, ws: Wheelset, pose: Pose, side: str,
                     min_lobe: float = 0.0) -> np.ndarray:
    """:func:`~.points.merge_approaches` of the wheel searched at ``pose``."""
    return _points.merge_approaches(search_wheel(track, ws, pose, side), min_lobe)


def run_on_rail(track: Track, ws: Wheelset, pose: Pose, side: str, approach: float,
                rail_u: float) -> tuple[float, float]:
    """:func:`~.points.run_on_rail` of the wheel searched at ``pose``."""
    return _points.run_on_rail(search_wheel(track, ws, pose, side), approach, rail_u)


def at_reference(cp: ContactPoint, track: Track, ws: Wheelset, pose: Pose,
                 approach: float, turn: float = 0.0) -> ContactPoint | None:
    """:func:`~.points.at_reference` of the rigid contact point ``cp`` of the wheel
    searched at ``pose``."""
    return _points.at_reference(search_wheel(track, ws, pose, cp.side), cp, approach, turn)


_memo = threading.local()
"""This thread's memory of the search: ``traces``, the last trace of
:func:`_trace_of_pose` of each side (track, wheelset, pose, trace). Per thread, so that
wheelsets stepping on several threads neither share nor evict each other's memory."""


def forget(traces: bool = True) -> None:
    """Clear this thread's memory of the last pose (with ``traces``: the last trace of
    each side)."""
    if traces:
        _memo.traces = {}


def _trace(track: Track, ws: Wheelset, pose: Pose, side: str, formed: tuple | None = None):
    """:func:`vertical_gap` as one array (5, n), with the least gap, its first sample,
    whether the trace's u increase, how many samples have the least gap and the first
    rigid contact point (its row of :func:`~.kernels.rigid_point` and its
    :func:`~.kernels.rigid_record`; None where the least gap is not on one sample): one
    compiled pass (:func:`~.kernels.search_wheel`); then the rail and the wheel as it read
    them (:func:`rail_arrays`, :func:`wheel_arrays`), and the approaches at which the
    wheel's contact regions merge (:func:`~.points.merge_approaches` with
    :data:`~.points.MIN_LOBE`, formed in the same pass; read-only). ``formed``: the track's
    and the wheelset's part of that pass (:func:`_search_arguments`), when the caller holds
    it."""
    if side not in SIDES:
        raise RailContactError(f"side must be 'left' or 'right', got {side!r}")
    sgn = SIDES[side]
    psi, phi = sgn * pose.yaw, sgn * pose.roll
    eta, r, dr, tail, rail, wheel = formed or _search_arguments(track, ws)
    out = np.empty((5, eta.size))
    n, g_min, k, increasing, ties, merges, found, row, rec = kernels.search_wheel(
        eta, r, dr, psi != 0.0, math.tan(psi), math.cos(psi), math.sin(psi), math.cos(phi),
        math.sin(phi), float(sgn * pose.lateral), *tail, _points.MIN_LOBE, out)
    if n < 10:
        raise RailContactError(f"{side} wheel is beside its rail (lateral displacement "
                               f"{pose.lateral:g} m is beyond the profiles)")
    merges.flags.writeable = False
    return (out[:, :n], g_min, k, increasing, ties, (row, rec) if found else None, rail,
            wheel, merges)


def _search_arguments(track: Track, ws: Wheelset) -> tuple:
    """What :func:`~.kernels.search_wheel` reads of the track and the wheelset (formed once
    for each, :func:`_wheel_samples`, :func:`rail_arrays`, :func:`wheel_arrays`): the
    wheel's samples eta, r, dr, the arguments after the pose's (``tail``), and the rail
    and the wheel arrays as :class:`~.points.WheelSearch` holds them."""
    eta, r, dr = _wheel_samples(ws)
    rail, wheel = rail_arrays(track), wheel_arrays(ws)
    tail = (*rail[4:6], *rail[:4], *wheel, _points.S_SAMPLES, K0, _points.B_DENOMINATOR,
            *rail[8:])
    return eta, r, dr, tail, rail, wheel


def _trace_of_pose(track: Track, ws: Wheelset, pose: Pose, side: str):
    """:func:`_trace`, remembered for the last (track, wheelset, pose) of each side: a load
    iteration asks for the same wheel's contact several times, and the rigid wheelset's
    search for both wheels' least gaps after solving them (:func:`least_gap`); the
    track's and wheelset's arguments of the search (:func:`_search_arguments`) kept with
    it for the next pose of the same track and wheelset."""
    traces = getattr(_memo, "traces", None)
    if traces is None:
        traces = _memo.traces = {}
    last = traces.get(side)  # (a step passes one pose to every call: identity first)
    formed = None
    if last is not None and last[0] is track and last[1] is ws:
        if last[2] is pose or last[2] == pose:
            return last[3]
        formed = last[4]
    formed = formed or _search_arguments(track, ws)
    out = _trace(track, ws, pose, side, formed)
    out[0].flags.writeable = False  # (its rows too)
    traces[side] = (track, ws, pose, out, formed)
    return out


def _wheel_samples(ws: Wheelset) -> tuple[np.ndarray, ...]:
    """The pose-independent part of a wheel's trace: axial positions eta, radii r and
    dr/deta at the :data:`N_TRACE` samples [m], formed once per wheelset (read-only)."""
    return _formed.get(ws, _form_wheel_samples)


def _form_wheel_samples(ws: Wheelset) -> tuple[np.ndarray, ...]:
    s_lo, s_hi = ws.wheel.bounds
    eta = ws.axial_position(np.linspace(s_lo + 1e-6, s_hi - 1e-6, N_TRACE))
    S = ws.profile_coordinate(eta)
    r = ws.radius + ws.wheel.height(S)
    dr = ws.wheel.slope(S)
    for a in (eta, r, dr):
        a.flags.writeable = False
    return eta, r, dr


def rail_arrays(track: Track) -> tuple[np.ndarray, ...]:
    """The placed rail as the kernels read it: :data:`N_RAIL` samples (u, Z) and its
    spline's breakpoints and coefficients, then its extent (lo, hi) [m] and the same
    breakpoints and coefficients, then what its profile coordinate's search reads
    (:attr:`Track.placed_search`, five arrays) (formed once per track; read-only)."""
    return _formed.get(track, _form_rail_arrays)


def _form_rail_arrays(track: Track) -> tuple[np.ndarray, ...]:
    rail = track.side_rail
    return (*rail.samples(N_RAIL), *rail._pieces, *rail.bounds, *rail._pieces,
            *track.placed_search)


def wheel_arrays(ws: Wheelset) -> tuple:
    """The wheel as the kernels read it: its spline's breakpoints and coefficients, the
    nominal radius [m], and ``back_to_back / 2``, ``flange_back`` [m] (profile coordinate
    S = eta - back_to_back / 2 + flange_back, :meth:`Wheelset.profile_coordinate`);
    formed once per wheelset."""
    return _formed.get(ws, _form_wheel_arrays)


def _form_wheel_arrays(ws: Wheelset) -> tuple:
    return (*ws.wheel._pieces, float(ws.radius), ws.back_to_back / 2, float(ws.flange_back))


_formed = FormedOnce()
"""What the search forms once per track and per wheelset (keyed by the forming function:
a wheelset's trace samples and its kernel arrays), beside the frozen records."""
