"""The warm step's compiled stages (railcontact/timestep/compiled.py) against its Python path.

A warm patch's tangential stage runs as one compiled call (``warm_tangential``) where it
can; it must give what the Python path gives - the traction start advanced along the
remembered rate, SteadyGS on the contact's window, the new traction rate - to the bit, so
that a step's answer does not depend on which path solved it. The runs: a hunting
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
    """How many tangential stages ran compiled (``done``) and how many fell back."""
    seen = {"done": 0, "python": 0}
    original = step_wheel.warm_tangential

    def counted(*args, **kwargs):
        done, rate = original(*args, **kwargs)
        seen["done" if done else "python"] += 1
        return done, rate
    monkeypatch.setattr(step_wheel, "warm_tangential", counted)
    return seen


def _python_path(monkeypatch) -> None:
    monkeypatch.setattr(compiled, "ENABLED", False)


@pytest.mark.parametrize("lateral, steps", [(_hunting, 40), (_flange, 40)])
def test_the_compiled_tangential_stage_gives_the_python_paths_bits(monkeypatch, calls,
                                                                    lateral, steps):
    fast = _run(lateral, steps, warm_start="previous+estimate")
    assert calls["done"] > steps  # (both wheels, nearly every step after the first two)
    monkeypatch.undo()
    _python_path(monkeypatch)
    _compare(fast, _run(lateral, steps, warm_start="previous+estimate"))


def test_a_moving_window_and_the_older_steps_grid_keep_the_bits(monkeypatch, calls):
    """A fast lateral sweep: the contact's window and the patch grid change from step
    to step (the start and the rate formed across grids of one lattice)."""
    def sweep(t):
        return -4e-3 + 0.4 * t, 0.4
    fast = _run(sweep, 30, warm_start="previous")
    assert calls["done"] > 30
    monkeypatch.undo()
    _python_path(monkeypatch)
    _compare(fast, _run(sweep, 30, warm_start="previous"))


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
        done, rate = original(patch, *args)
        seen.append((before, args, patch, done, rate))
        return done, rate
    monkeypatch.setattr(step_wheel, "warm_tangential", spy)
    _run(_hunting, 6, warm_start="previous+estimate")
    before, args, after, done, rate = seen[-1]
    assert done and rate is not None
    return before, args, after, rate


def test_the_stage_called_again_gives_its_answer(stage_call):
    before, args, after, rate = stage_call
    patch = copy.deepcopy(before)
    done, again = compiled.warm_tangential(patch, *args)
    assert done
    np.testing.assert_array_equal(again, rate)
    np.testing.assert_array_equal(patch.tangential.traction, after.tangential.traction)
    assert patch.creepage == after.creepage and patch.friction == after.friction


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
    patch = copy.deepcopy(before)
    assert compiled.warm_tangential(patch, settings, pair, fft, creepage, memory, factor,
                                    last, time, gain) == (False, None)
    assert patch.tangential is None and patch.creepage == before.creepage
    assert patch.work.tangential_iterations == before.work.tangential_iterations
