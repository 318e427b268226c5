"""The rigid wheelset's vertical displacement and roll in a time loop, started in time
from the previous steps' roots (:mod:`railcontact.timestep.rigid`).

Truth: the two wheels' vertical positions at the roll found, from the load-controlled
solves of the same wheelset without memory (a cold step, its wheels rolled as the rigid
search rolls them): the rigid wheelset's condition
``m_L(phi) + delta_L(phi) = m_R(phi) + delta_R(phi) = -v`` must hold there to the search's
tolerance (:data:`~railcontact.timestep.rigid.RIGID_RTOL` of the larger approach, ~8 nm
here).

Measured over the 8 mm run at every step from 95 to 105 (the tread-to-flange
transition) the residual reaches 1.2 tol (main's search, which ends further below its
tolerance after 5-8 evaluations: 0.7 tol); there two memory-free solves that differ only
in their start (``warm_start`` = none against the default, patch frames to 1e-7) already
differ by up to 11 tol, the contact solves' own reproducibility at that level. The check
is at every 20th step.
"""

from __future__ import annotations

import math
import pickle
from dataclasses import replace

import pytest

from railcontact.contact.wheelrail import WARM_REFERENCE_RTOL
from railcontact.geometry.profiles import read_profile
from railcontact.geometry.roll import first_contact_gap
from railcontact.geometry.track import Pose, Track, Wheelset
from railcontact.halfspace.materials import ElasticPair, Material
from railcontact.timestep import StepMemory, rigid, rolled
from railcontact.timestep.rigid import RigidMemory, predicted_approaches, predicted_roll
from railcontact.timestep.wheelset import ContactSettings, WheelsetContact

Q = 83.3e3
CREEP = ((1e-3, 0.0, 0.0), (1e-3, 0.0, 0.0))


def contact(**settings) -> WheelsetContact:
    mat = Material(206e9, 0.28)
    return WheelsetContact(Track(read_profile("60E1", "rail"), math.atan(1 / 40)),
                           Wheelset(read_profile("S1002", "wheel"), 0.46),
                           ElasticPair.of(mat, mat),
                           ContactSettings(**{"rigid_wheelset": "solve", **settings}))


def hunting(amplitude: float, k: int) -> tuple[Pose, float]:
    """The pose and time of step ``k`` of bench_rigid's hunting run (1.5 Hz, 1 ms)."""
    t = k * 1e-3
    return Pose(amplitude * math.sin(2 * math.pi * 1.5 * t)), t


def residuals(wc: WheelsetContact, pose: Pose, t: float, vertical: float, roll: float
              ) -> tuple[float, float]:
    """(m_L + delta_L - m_R - delta_R, v + (h_L + h_R) / 2) [m] at ``roll``, the
    approaches from a cold solve of the same wheelset without memory (module doc)."""
    cold = contact(rigid_wheelset="skip")
    cold.solve(pose, loads=(Q, Q), creepages=CREEP, time=t)
    dl, dr = cold.rolled_approaches(pose, loads=(Q, Q), creepages=CREEP, time=t)(roll)
    p = Pose(pose.lateral, pose.yaw, roll)
    hl = first_contact_gap(wc.track, wc.wheelset, p, "left") + dl
    hr = first_contact_gap(wc.track, wc.wheelset, p, "right") + dr
    return hl - hr, vertical + 0.5 * (hl + hr)


@pytest.mark.parametrize(("amplitude", "steps", "every"), [(3e-3, 120, 30),
                                                           (8e-3, 200, 20)])
def test_started_in_time_meets_the_tolerance(amplitude, steps, every):
    """Over bench_rigid's hunting run (3 mm: tread; 8 mm: onto the flange at ~0.1 s, where
    the roll grows tenfold in 10 ms) the warm loop's vertical and roll, found mostly in one
    evaluation from the previous steps' roots, give both wheels their loads at the
    tolerance when checked with accurate, memory-free solves; and the start in time saves
    evaluations (a cold start needs at least two: G(phi0) and one solve)."""
    wc = contact()
    evaluations = []
    for k in range(steps):
        pose, t = hunting(amplitude, k)
        r = wc.solve(pose, loads=(Q, Q), creepages=CREEP, time=t)
        s = r.rigid_solution
        assert s.converged, s.message
        evaluations.append(s.evaluations)
        if k % every == 0:
            tol = rigid.RIGID_RTOL * max(r.left.approach, r.right.approach)
            g, dv = residuals(wc, pose, t, s.vertical, s.roll)
            assert abs(g) <= tol and abs(dv) <= tol, (k, g / tol, dv / tol)
    assert sum(evaluations[3:]) / len(evaluations[3:]) < 2.0
    assert wc.memory.rigid[0].time == t  # the last step's root is remembered


def test_the_root_is_part_of_the_saved_state():
    """The FMU saves ``WheelsetContact.memory`` (pickled): restoring it after a step
    repeats the next steps bit for bit, the rigid wheelset's vertical and roll and their
    evaluations included; without the remembered roots the same steps start from the
    pose's roll and need more evaluations, and find the same roll to the tolerance."""
    wc = contact()
    for k in range(4):
        pose, t = hunting(3e-3, k)
        wc.solve(pose, loads=(Q, Q), creepages=CREEP, time=t).rigid_solution  # noqa: B018
    saved = pickle.dumps(wc.memory, protocol=pickle.HIGHEST_PROTOCOL)
    assert [m.time for m in wc.memory.rigid] == [3e-3, 2e-3, 1e-3]  # newest first

    def steps(c: WheelsetContact) -> list[tuple[float, float, int, float, float]]:
        out = []
        for k in range(4, 8):
            pose, t = hunting(3e-3, k)
            r = c.solve(pose, loads=(Q, Q), creepages=CREEP, time=t)
            s = r.rigid_solution
            tol = rigid.RIGID_RTOL * max(r.left.approach, r.right.approach)
            out.append((s.vertical, s.roll, s.evaluations, s.slope, tol))
        return out

    first = steps(wc)
    wc.memory = pickle.loads(saved)
    assert steps(wc) == first
    other = contact()
    other.memory = pickle.loads(saved)
    assert steps(other) == first
    forgot = contact()
    forgot.memory = replace(pickle.loads(saved), rigid=())
    again = steps(forgot)
    assert again[0][2] > first[0][2]  # from the pose's roll: G(phi0) and a solve at least
    for (v, phi, _, slope, tol), (v2, phi2, _, _, _) in zip(first, again, strict=True):
        assert abs(phi - phi2) * slope <= 2 * tol and abs(v - v2) <= 2 * tol  # |G| <= tol


def test_no_memory_without_a_warm_start():
    """With ``warm_start = none`` nothing of a step carries over: no roots are kept and
    every step starts from the pose's roll."""
    wc = contact(warm_start="none")
    for k in range(3):
        pose, t = hunting(3e-3, k)
        wc.solve(pose, loads=(Q, Q), creepages=CREEP, time=t).rigid_solution  # noqa: B018
    assert wc.memory == StepMemory()


def test_predicted_roll_is_the_polynomial_in_time():
    """Through three roots the start is the quadratic in time (exact for a quadratic
    roll), through two the line; the last root when the times do not allow it."""
    def roll(t):
        return 1e-4 + 2e-3 * t - 5e-2 * t * t

    h = [RigidMemory(t, roll(t), 1.0) for t in (0.003, 0.002, 0.001)]
    assert predicted_roll(h, 0.004) == pytest.approx(roll(0.004), rel=1e-12)
    line = 2 * roll(0.003) - roll(0.002)
    assert predicted_roll(h[:2], 0.004) == pytest.approx(line, rel=1e-12)
    assert predicted_roll(h[:1], 0.004) == roll(0.003)
    assert predicted_roll(h, None) == roll(0.003)
    assert predicted_roll(h, 0.003) == roll(0.003)  # not later than the last root
    assert predicted_roll(h, 0.01) == roll(0.003)  # a step 7 times the last one
    assert predicted_roll([], 0.004) is None


def test_predicted_approaches_follow_the_roll():
    """The approaches at the root are extrapolated with the roll's weights; a step that
    kept none (not converged, or a root at the pose's roll without a solve) gives none."""
    h = [RigidMemory(t, 0.0, 1.0, None, (7e-5 + t * 1e-3, 7.5e-5 - t * 1e-3))
         for t in (0.003, 0.002, 0.001)]
    a = predicted_approaches(h, 0.004)
    assert a == pytest.approx((7e-5 + 4e-6, 7.5e-5 - 4e-6), rel=1e-12)
    assert predicted_approaches([RigidMemory(0.003, 0.0, 1.0), *h[1:]], 0.004) is None
    assert predicted_approaches(h, None) == h[0].approaches


def test_a_start_out_of_range_falls_back_to_the_pose_roll():
    """A remembered root that puts the wheels out of range at this step (a pose far from
    the previous one) is not an error: the search starts again from the pose's roll and
    finds the root a memory-free step finds, to the tolerance."""
    wc = contact()
    pose, t = hunting(3e-3, 5)
    wc.solve(pose, loads=(Q, Q), creepages=CREEP, time=t)
    climbed = RigidMemory(t, 0.045, 1.0, (0.0, 0.0), (1e-4, 1e-4))
    wc.memory = replace(wc.memory, rigid=(climbed,))
    r = wc.solve(pose, loads=(Q, Q), creepages=CREEP, time=t + 1e-3)
    s = r.rigid_solution
    assert s.converged, s.message
    cold = contact(warm_start="none").solve(pose, loads=(Q, Q), creepages=CREEP,
                                            time=t + 1e-3).rigid_solution
    tol = rigid.RIGID_RTOL * max(r.left.approach, r.right.approach)
    assert abs(s.roll - cold.roll) * s.slope <= 2 * tol


class _Counting:
    """The CG iterations and sweeps of a rolled wheelset's solves (the step's wheel solves
    of :class:`~railcontact.timestep.rolled.RolledApproaches`), added up."""

    def __init__(self, monkeypatch):
        self.rolled_iterations = self.rolled_solves = 0
        solve = rolled.solve_step_wheel

        def counted(*args, **kwargs):
            wheel, mem, error = solve(*args, **kwargs)
            self.rolled_iterations += wheel.normal_iterations + wheel.tangential_iterations
            self.rolled_solves += 1
            return wheel, mem, error
        monkeypatch.setattr(rolled, "solve_step_wheel", counted)


def test_rolled_solves_start_from_the_previous_root(monkeypatch):
    """The wheels' solves at the root are kept with the step (:attr:`StepMemory.rolled`, at the
    step's time) and start the next step's solves at the rolled pose: over the 3 mm hunting
    run they take fewer iterations than the same solves started from the step's own
    solution at the pose's roll (the kept ones dropped before every step), and find the
    same roots to the tolerance."""
    base = contact()
    runs = {}
    for keep in (True, False):
        wc = WheelsetContact(base.track, base.wheelset, base.pair, base.settings)
        count = _Counting(monkeypatch)
        roots = []
        for k in range(120):
            if not keep:
                wc.memory = replace(wc.memory, rolled=None)
            pose, t = hunting(3e-3, k)
            r = wc.solve(pose, loads=(Q, Q), creepages=CREEP, time=t)
            s = r.rigid_solution
            assert s.converged, s.message
            tol = rigid.RIGID_RTOL * max(r.left.approach, r.right.approach)
            roots.append((s.roll, s.vertical, s.slope, tol))
            if keep and k > 1:  # (step 0 is centred: its root is the pose's roll)
                left, right = wc.memory.rolled
                assert [m.time for m in left + right] == [t, t]
                assert left[0].older.time == pytest.approx(t - 1e-3, abs=1e-12)
        runs[keep] = (count.rolled_iterations / count.rolled_solves, roots)
    assert runs[True][0] < 0.75 * runs[False][0], (runs[True][0], runs[False][0])
    for (phi, v, slope, tol), (phi2, v2, _, _) in zip(runs[True][1], runs[False][1],
                                                     strict=True):
        assert abs(phi - phi2) * slope <= 2 * tol and abs(v - v2) <= 2 * tol


@pytest.mark.parametrize("lateral", [0.0, 3e-3, 5e-3, 8e-3])
def test_a_frame_within_the_warm_tolerance_keeps_the_approach(lateral):
    """A rolled wheel's solve keeps the frame formed at its guessed approach when the
    approach found is within :data:`~railcontact.contact.wheelrail.WARM_REFERENCE_RTOL` of
    it (the solve's own frame tolerance from a start; there is no second solve at a
    tighter one): solved tightly (the normal problem, one load pass,
    so that only the frame differs), the approach with the frame formed 0.9e-3
    above or below the approach found is that of the frame formed at it to within a
    quarter of the rigid search's tolerance (measured: 0.005 on the tread and at 3 mm,
    0.11 at the flange root, 5 mm, 0.16 on the flange, 8 mm), far below the scatter of
    the solves themselves at the step's tolerances (module docstring: up to 11 tol). Each
    call is one pass a wheel: the frame is the guess's, not formed again inside the
    solve."""
    wc = contact(normal_tolerance=1e-9, rigid_wheelset="skip")
    wc.solve(Pose(lateral), loads=(Q, Q), time=0.0)
    at = wc.rolled_approaches(Pose(lateral), loads=(Q, Q), time=0.0)
    phi = 2e-4  # [rad], a root's size near the track centre
    found = at(phi, at(phi))  # the frame formed at the approach it gives
    for factor in (1 + 0.9 * WARM_REFERENCE_RTOL, 1 - 0.9 * WARM_REFERENCE_RTOL):
        passes = [at.work[s].load_passes for s in ("left", "right")]
        moved = at(phi, tuple(a * factor for a in found))
        assert [at.work[s].load_passes for s in ("left", "right")] == [n + 1 for n in passes]
        for a, b in zip(moved, found, strict=True):
            assert abs(a - b) <= 0.25 * rigid.RIGID_RTOL * b, (factor, (a - b) / b)


@pytest.mark.parametrize("lateral", [0.0, 8e-3])
def test_a_missed_guess_forms_the_frame_again_inside_the_one_solve(lateral):
    """A rolled wheel whose approach misses its guess by far more than
    :data:`~railcontact.contact.wheelrail.WARM_REFERENCE_RTOL` (2 %) is solved once: its
    solve forms the frame again at the approach it found (two passes a wheel, where a
    second solve after it would make three), and gives the
    approach of the frame formed at it to within a quarter of the rigid search's
    tolerance (solved tightly, the normal problem: only the frame differs)."""
    wc = contact(normal_tolerance=1e-9, rigid_wheelset="skip")
    wc.solve(Pose(lateral), loads=(Q, Q), time=0.0)
    at = wc.rolled_approaches(Pose(lateral), loads=(Q, Q), time=0.0)
    phi = 2e-4  # [rad]
    found = at(phi, at(phi))  # the frame formed at the approach it gives
    passes = [at.work[s].load_passes for s in ("left", "right")]
    moved = at(phi, tuple(a * 1.02 for a in found))
    assert [at.work[s].load_passes for s in ("left", "right")] == [n + 2 for n in passes]
    for a, b in zip(moved, found, strict=True):
        assert abs(a - b) <= 0.25 * rigid.RIGID_RTOL * b, (a - b) / b
