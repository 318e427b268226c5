"""The warm step's compiled stages (railcontact/timestep/compiled.py) against its Python path.

A warm patch's normal stage (``warm_normal``: the gap on the grid, the remembered
pressure and displacement extrapolated onto it, the CG solve and the check of the rigid
overlap) and its tangential stage (``warm_tangential``) run as one compiled call each
where they can; they must give what the Python path gives - for the tangential stage
the traction start advanced along the remembered rate, SteadyGS on the contact's window,
the new traction rate - to the bit, so that a step's answer does not depend on which
path solved it. A normal stage whose solution the solver does not keep as it is (its
contact at the edge of its area, a place of the overlap beyond the grid that could touch)
hands it to the Python path, which goes on from it. The runs: a hunting
wheelset (S1002 on 60E1 at 1:40, 3 mm at 1.5 Hz, load control with kinematic creepages,
1 ms steps), a flange contact with two patches on the wheel, a run in which the
contact's window changes size and one solved on the whole grid (no window). Each run is
stepped twice, once with the compiled stage and once with it switched off
(``compiled.ENABLED``); every result and every remembered array must be equal. A stage
the call cannot run (no remembered rate, no extrapolation, zero creepage, ConvexGS) is
left to the Python path with the patch untouched.
"""

import copy
import math
from dataclasses import replace

import numpy as np
import pytest

import railcontact as rc
import railcontact.geometry.points as points
import railcontact.timestep.compiled as compiled
import railcontact.timestep.wheel as step_wheel

pytestmark = pytest.mark.skipif(
    compiled._steady_solve_c is None,
    reason="the compiled SteadyGS solve needs numba and FFTW's C interface")


def _contact(**settings) -> rc.WheelsetContact:
    return rc.WheelsetContact(
        rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
        rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
        rc.ElasticPair.of(rc.STEEL, rc.STEEL),
        rc.ContactSettings(friction=0.4, element_size=0.5e-3, **settings))


def _run(lateral, steps: int, **settings) -> list:
    """Each step's result and memory of a run along ``lateral(t)`` [m]."""
    wc = _contact(**settings)
    out = []
    for k in range(steps):
        t = k * 1e-3
        y, v = lateral(t)
        r = wc.solve(rc.Pose(y), loads=(83.3e3, 83.3e3), kinematics=rc.Kinematics(30.0, v),
                     time=t)
        out.append((r, wc.memory))
    return out


def _hunting(t):
    w = 2 * math.pi * 1.5
    return 3e-3 * math.sin(w * t), 3e-3 * w * math.cos(w * t)


def _flange(t):
    """Towards the flange: the flange root's second patch appears near 6.5 mm."""
    return 6.2e-3 + 0.5 * t, 0.5


def _sweep(t):
    """A fast lateral sweep: the contact's window and the patch grid change from step to
    step, and its area grows beyond the remembered one."""
    return -4e-3 + 0.4 * t, 0.4


def _arrays(memory) -> list[np.ndarray]:
    """Every array the step remembers (pressure, traction, map, rate, displacement)."""
    out = []
    for side in memory.left, memory.right:
        for m in side:
            for a in (m.pressure, m.traction, m.state, m.traction_rate,
                      None if m.displacement is None else m.displacement.values):
                if a is not None:
                    out.append(np.asarray(a))
    return out


def _compare(a: list, b: list) -> None:
    for (ra, ma), (rb, mb) in zip(a, b, strict=True):
        assert ra.status == rb.status
        for wa, wb in zip(ra.wheels, rb.wheels, strict=True):
            assert (wa.normal_force, wa.creep_force, wa.spin_moment) == (
                wb.normal_force, wb.creep_force, wb.spin_moment)
            assert (wa.tangential_iterations, wa.normal_iterations, wa.load_passes) == (
                wb.tangential_iterations, wb.normal_iterations, wb.load_passes)
            for pa, pb in zip(wa.patches, wb.patches, strict=True):
                na, nb = pa.normal, pb.normal
                np.testing.assert_array_equal(na.pressure, nb.pressure)
                np.testing.assert_array_equal(na.contact, nb.contact)
                assert (na.grid, na.penetration, na.iterations, na.converged, na.message,
                        na.touches_boundary, na.next_to_undefined, pa.work.remeshes) == (
                    nb.grid, nb.penetration, nb.iterations, nb.converged, nb.message,
                    nb.touches_boundary, nb.next_to_undefined, pb.work.remeshes)
                ta, tb = pa.tangential, pb.tangential
                np.testing.assert_array_equal(ta.traction, tb.traction)
                np.testing.assert_array_equal(ta.state, tb.state)
                assert (ta.iterations, ta.error, ta.converged) == (
                    tb.iterations, tb.error, tb.converged)
                np.testing.assert_array_equal(ta.slip_of(), tb.slip_of())
        xa, xb = _arrays(ma), _arrays(mb)
        assert len(xa) == len(xb)
        for u, v in zip(xa, xb, strict=True):
            np.testing.assert_array_equal(u, v)


@pytest.fixture
def calls(monkeypatch):
    """How many tangential stages ran compiled (``done``) and how many fell back; how many
    normal stages gave the patch's solution (``final``), handed their solve on to the
    Python path (``on``: ``uncovered`` of them with places beyond the grid that could
    touch) or solved nothing (``none``)."""
    seen = {"done": 0, "python": 0, "final": 0, "on": 0, "uncovered": 0, "none": 0}
    original, normal = step_wheel.warm_tangential, step_wheel.warm_normal

    def counted(*args, **kwargs):
        patch, done, rate = original(*args, **kwargs)
        seen["done" if done else "python"] += 1
        return patch, done, rate

    def counted_normal(*args, **kwargs):
        staged = normal(*args, **kwargs)
        seen["none" if staged is None else "final" if staged.final else "on"] += 1
        seen["uncovered"] += staged is not None and staged.uncovered is not None
        return staged
    monkeypatch.setattr(step_wheel, "warm_tangential", counted)
    monkeypatch.setattr(step_wheel, "warm_normal", counted_normal)
    return seen


def _python_path(monkeypatch) -> None:
    monkeypatch.setattr(compiled, "ENABLED", False)


@pytest.mark.parametrize("lateral, steps", [(_hunting, 40), (_flange, 40)])
def test_the_compiled_tangential_stage_gives_the_python_paths_bits(monkeypatch, calls,
                                                                    lateral, steps):
    fast = _run(lateral, steps, warm_start="previous+estimate")
    assert calls["done"] > steps  # (both wheels, nearly every step after the first two)
    assert calls["final"] > steps
    monkeypatch.undo()
    _python_path(monkeypatch)
    _compare(fast, _run(lateral, steps, warm_start="previous+estimate"))


def test_a_moving_window_and_the_older_steps_grid_keep_the_bits(monkeypatch, calls):
    """A fast lateral sweep: the contact's window and the patch grid change from step
    to step (the start and the rate formed across grids of one lattice)."""
    fast = _run(_sweep, 30, warm_start="previous")
    assert calls["done"] > 30
    # (the contact grows out of its remembered area: normal stages handed on, the area
    # grown to places of the overlap beyond it)
    assert calls["final"] > 30 and calls["uncovered"] > 0
    monkeypatch.undo()
    _python_path(monkeypatch)
    _compare(fast, _run(_sweep, 30, warm_start="previous"))


def test_a_solve_on_the_whole_grid_keeps_the_bits(monkeypatch, calls):
    """Without a window (the contact filling its grid) the solve's traction is the
    transpose of its sweep layout, and the next step starts from that view."""
    import railcontact.contact.patch as patch_module

    monkeypatch.setattr(compiled, "contact_window", lambda *a, **k: None)
    monkeypatch.setattr(patch_module, "contact_window", lambda *a, **k: None)
    fast = _run(_hunting, 20, warm_start="previous+estimate")
    assert calls["done"] > 20
    monkeypatch.setattr(compiled, "ENABLED", False)
    _compare(fast, _run(_hunting, 20, warm_start="previous+estimate"))


@pytest.fixture
def stage_call(monkeypatch):
    """The arguments of a compiled stage's call at the sixth step of the hunting run, a
    copy of its patch taken before the call, and the patch after it."""
    seen = []
    original = step_wheel.warm_tangential

    def spy(patch, *args):
        before = copy.deepcopy(patch)
        after, done, rate = original(patch, *args)
        seen.append((before, args, after, done, rate))
        return after, done, rate
    monkeypatch.setattr(step_wheel, "warm_tangential", spy)
    _run(_hunting, 6, warm_start="previous+estimate")
    before, args, after, done, rate = seen[-1]
    assert done and rate is not None
    return before, args, after, rate


def test_the_stage_is_the_python_paths_start_solve_and_rate(stage_call):
    """The stage's traction, map, sweeps and rate are those of the Python path's three
    calls on a copy of the same patch: the remembered traction advanced along its rate
    (previous_tangential), SteadyGS (solve_patch_tangential), the new rate
    (traction_rate)."""
    from railcontact.contact.patch import solve_patch_tangential
    from railcontact.timestep.warmstart import _previous_tangential, traction_rate

    before, args, after, rate = stage_call
    settings, pair, fft, creepage, memory, factor, last, time, gain = args
    grid = before.normal.grid
    patch = solve_patch_tangential(copy.deepcopy(before), settings, pair, fft,
                                   creepage=list(creepage),
                                   previous=_previous_tangential(memory, factor, grid))
    t, c = patch.tangential, after.tangential
    np.testing.assert_array_equal(t.traction, c.traction)
    np.testing.assert_array_equal(t.state, c.state)
    assert (t.iterations, t.error, t.force, t.spin_moment) == (
        c.iterations, c.error, c.force, c.spin_moment)
    assert patch.creepage == after.creepage and patch.friction == after.friction
    assert patch.work.tangential_iterations == after.work.tangential_iterations
    np.testing.assert_array_equal(traction_rate(t.traction, grid, time, last, gain), rate)


@pytest.mark.parametrize("change", ["no rate", "factor 0", "zero creepage", "convexgs",
                                    "switched off"])
def test_a_stage_it_cannot_run_is_left_to_the_python_path_untouched(stage_call, change,
                                                                     monkeypatch):
    before, args, after, rate = stage_call
    settings, pair, fft, creepage, memory, factor, last, time, gain = args
    if change == "no rate":
        memory = replace(memory, traction_rate=None)
    elif change == "factor 0":
        factor = 0.0
    elif change == "zero creepage":
        creepage = (0.0, 0.0, 0.0)
    elif change == "convexgs":
        settings = replace(settings, solver="convexgs")
    else:
        monkeypatch.setattr(compiled, "ENABLED", False)
    patch, done, rate = compiled.warm_tangential(copy.deepcopy(before), settings, pair, fft,
                                                 creepage, memory, factor, last, time, gain)
    assert (done, rate) == (False, None)
    assert patch.tangential is None and patch.creepage == before.creepage
    assert patch.work.tangential_iterations == before.work.tangential_iterations


def _normal_calls(monkeypatch, lateral, steps: int) -> list:
    """Each compiled normal stage's call of a run: a copy of its contact point taken
    before it (its frame's samples as they were), the point, the arguments and the
    answer."""
    seen = []
    original = step_wheel.warm_normal

    def spy(cp, *args):
        before = copy.deepcopy(cp)
        staged = original(cp, *args)
        seen.append((before, cp, args, staged))
        return staged
    monkeypatch.setattr(step_wheel, "warm_normal", spy)
    _run(lateral, steps, warm_start="previous")
    monkeypatch.undo()
    return seen


@pytest.mark.parametrize("lateral, steps, which", [(_hunting, 6, "final"),
                                                   (_sweep, 30, "uncovered")])
def test_the_normal_stage_is_the_python_paths_first_solve_and_check(monkeypatch, lateral,
                                                                    steps, which):
    """The stage's solution is the patch solver's on the same grid from the same start
    (solve_patch_normal with the start's pressure_on), its reach check finds what the
    Python path's first check finds (nothing; or the same places beyond the grid), and
    the frame's samples are formed as the Python path forms them, from a copy of the
    contact point as it was before the stage."""
    import railcontact.contact.patch as patch_module

    calls = [c for c in _normal_calls(monkeypatch, lateral, steps) if c[3] is not None
             and (c[3].final if which == "final" else c[3].uncovered is not None)]
    assert calls
    before, cp, args, staged = calls[-1]
    bounds, grid_settings, settings, pair, control, found, memory, factor = args
    start = step_wheel.PatchStart(
        step_wheel.PassStart((memory,), memory.time, None, pair, factor, found), before,
        None, control, memory)
    est = rc.contact.start.WarmStart("previous", start.pressure_on, bounds)
    python, work = patch_module.solve_patch_normal(before.gap_on_grid, bounds, grid_settings,
                                                   settings, pair, control, est)
    res = staged.result
    assert python.grid == res.grid and work.remeshes == 0
    np.testing.assert_array_equal(python.pressure, res.pressure)
    np.testing.assert_array_equal(python.displacement.values, res.displacement.values)
    assert (python.force, python.penetration, python.iterations, python.message) == (
        res.force, res.penetration, res.iterations, res.message)
    box = points.overlap_box_on_run(
        found, before, python.penetration,
        python.penetration / math.cos(before.contact_angle) + before.gap)
    assert patch_module.uncovered(before.gap_on_grid, python, pair, box) == staged.uncovered
    assert (before.plane.i0, before.plane.i1) == (cp.plane.i0, cp.plane.i1)
    np.testing.assert_array_equal(before.plane.frame[:, cp.plane.i0:cp.plane.i1],
                                  cp.plane.frame[:, cp.plane.i0:cp.plane.i1])


@pytest.fixture
def normal_call(monkeypatch):
    """The arguments of a compiled normal stage's call at the sixth step of the hunting
    run (its frame's samples formed before it) and its answer."""
    seen = []
    original = step_wheel.warm_normal

    def spy(cp, *args):
        staged = original(cp, *args)
        seen.append((cp, args, staged))
        return staged
    monkeypatch.setattr(step_wheel, "warm_normal", spy)
    _run(_hunting, 6, warm_start="previous+estimate")
    cp, args, staged = seen[-1]
    assert staged is not None and staged.final
    return cp, args, staged.result


@pytest.mark.parametrize("change", ["penetration control", "rigid frame", "no frame found",
                                    "switched off", "start off the lattice",
                                    "start without pressure", "no compiled product"])
def test_a_normal_stage_it_cannot_run_solves_nothing(normal_call, change, monkeypatch):
    """Where the stage is not one call it answers None (the Python path solves the patch,
    as it would without the stage), the frame's formed samples unchanged."""
    cp, args, res = normal_call
    bounds, grid_settings, settings, pair, control, found, memory, factor = args
    g = memory.grid
    if change == "start off the lattice":
        memory = replace(memory, grid=replace(g, x0=g.x0 + 0.5 * g.dx))
    elif change == "start without pressure":
        memory = replace(memory, pressure=np.zeros_like(memory.pressure),
                         displacement=None)
    elif change == "no compiled product":
        monkeypatch.setattr(compiled, "compiled_products", lambda *a: None)
    elif change == "penetration control":
        control = rc.settings.Control(penetration=res.penetration)
    elif change == "rigid frame":
        cp = cp.rigid
    elif change == "no frame found":
        found = None
    else:
        monkeypatch.setattr(compiled, "ENABLED", False)
    plane = cp.plane
    i0, i1 = plane.i0, plane.i1
    formed = None if plane.frame is None else plane.frame[:, i0:i1].copy()
    assert compiled.warm_normal(cp, bounds, grid_settings, settings, pair, control, found,
                                memory, factor) is None
    if formed is not None:
        np.testing.assert_array_equal(plane.frame[:, i0:i1], formed)
