"""The wheelset co-simulation through the FMU (``railcontact demo``), the equivalent
conicity and Klingel's kinematic wavelength."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from railcontact.cli import main
from railcontact.errors import RailContactError
from railcontact.fmu import ensure_fmu, fmu_is_current
from railcontact.geometry.conicity import (
    centred_contact,
    equivalent_conicity,
    klingel_wavelength,
    rolling_radius_difference,
)
from railcontact.geometry.profiles import Profile, builtin_profile
from railcontact.geometry.track import Track, Wheelset
from railcontact.sim.dynamics import WheelsetModel, implicit_step, measure_wavelength

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def fmu(tmp_path_factory) -> Path:
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    path, built = ensure_fmu(tmp_path_factory.mktemp("cosim") / "RailContact.fmu")
    assert built
    return path


def s1002_60e1() -> tuple[Track, Wheelset]:
    return Track(builtin_profile("60E1")), Wheelset(builtin_profile("S1002"))


# -- geometry: equivalent conicity --------------------------------------------------------
@pytest.mark.parametrize("cone", [0.05, 0.1])
def test_conical_wheel_has_its_cone_angle_as_equivalent_conicity(cone):
    """A conical wheel on a curved rail: the contact stays on the same rail point, so
    delta_r = 2 lambda y exactly and the equivalent conicity is lambda at every amplitude."""
    s = np.linspace(-0.07, 0.065, 541)
    track = Track(builtin_profile("60E1"))
    ws = Wheelset(Profile(s, -cone * s, "wheel", "cone"))
    for amplitude in (1e-3, 3e-3, 6e-3):
        assert equivalent_conicity(track, ws, amplitude) == pytest.approx(cone, rel=1e-3)


def test_s1002_60e1_conicity_and_centred_contact():
    """S1002 on 60E1 at 1:40, gauge 1435, flange backs 1360: published equivalent
    conicities at 3 mm amplitude lie around 0.15-0.2 (e.g. Polach, Wear 258 (2005)),
    higher at small amplitude; delta_r is odd in y; the centred contact points lie near
    the taping lines (e ~ 0.75 m, r0 ~ 0.46 m)."""
    track, ws = s1002_60e1()
    c = centred_contact(track, ws)
    assert c.radius == pytest.approx(0.46, abs=1e-3)
    assert c.half_distance == pytest.approx(0.75, abs=0.01)
    y = np.array([1e-3, 2e-3, 4e-3])
    np.testing.assert_allclose(rolling_radius_difference(track, ws, -y),
                               -rolling_radius_difference(track, ws, y), atol=1e-6)
    lam = [equivalent_conicity(track, ws, a) for a in (1e-3, 3e-3, 5e-3)]
    assert 0.12 < lam[1] < 0.25
    assert lam[0] > lam[1] > lam[2]


def test_klingel_formula_and_bad_input():
    assert klingel_wavelength(0.46, 0.75, 0.2) == pytest.approx(
        2 * math.pi * math.sqrt(0.46 * 0.75 / 0.2))
    with pytest.raises(RailContactError, match="conicity"):
        klingel_wavelength(0.46, 0.75, 0.0)
    track, ws = s1002_60e1()
    with pytest.raises(RailContactError, match="amplitude"):
        equivalent_conicity(track, ws, -1e-3)


# -- the time step and the wavelength measurement -----------------------------------------
def test_implicit_step_is_backward_euler_in_the_velocity():
    """With D the exact Jacobian of a linear damping force F = D v, one step gives the
    backward-Euler velocity (M - h D)^-1 M v, stable however stiff D is."""
    model = WheelsetModel.free()
    d = np.diag([-4e6, -2.4e6, -1e5])
    v = np.array([0.01, -0.002, 0.5])
    q = np.zeros(3)
    h = 5e-3
    q1, v1 = implicit_step(model, q, v, d @ v, d, h)
    expected = np.linalg.solve(model.inertia - h * d, model.inertia @ v)
    np.testing.assert_allclose(v1, expected, rtol=1e-12)
    np.testing.assert_allclose(q1, h * expected, rtol=1e-12)
    for _ in range(50):  # h |D| / m = 13: explicit Euler would blow up
        q, v = implicit_step(model, q, v, d @ v, d, h)
    assert np.all(np.abs(v) < 1e-6)


def test_suspension_forces_enter_the_step():
    model = WheelsetModel(lateral_stiffness=1e6, longitudinal_stiffness=1e6, semi_spacing=1.0)
    assert model.yaw_stiffness == pytest.approx(2e6)
    q = np.array([1e-3, 2e-3, 0.0])
    _, v1 = implicit_step(model, q, np.zeros(3), np.zeros(3), np.zeros((3, 3)), 1e-3)
    np.testing.assert_allclose(v1[:2], [-1e6 * 1e-3 * 1e-3 / 1500, -2e6 * 2e-3 * 1e-3 / 700])


def test_measure_wavelength_of_a_sine():
    x = np.linspace(0, 40, 4001)
    w = measure_wavelength(x, 3e-3 * np.sin(2 * math.pi * x / 9.0 + 0.3))
    assert w.wavelength == pytest.approx(9.0, rel=1e-4)
    assert w.amplitude == pytest.approx(3e-3, rel=1e-3)
    assert math.isnan(measure_wavelength(x[:100], np.ones(100)).wavelength)


# -- the FMU co-simulation ----------------------------------------------------------------
def test_fmu_staleness(fmu, tmp_path):
    assert fmu_is_current(fmu)
    profile = ROOT / "models" / "profiles" / "S1002.txt"
    assert not fmu_is_current(fmu, [profile])  # built without that file
    assert not fmu_is_current(tmp_path / "missing.fmu")
    (tmp_path / "broken.fmu").write_text("not a zip")
    assert not fmu_is_current(tmp_path / "broken.fmu")
    path, built = ensure_fmu(fmu)
    assert path == fmu and not built


def test_free_wheelset_follows_klingel(fmu):
    """A free wheelset at 10 m/s (inertia negligible: the linear theory's frequency is
    within 1 % of the kinematic one) oscillates with Klingel's wavelength for the
    equivalent conicity of railcontact's geometry at the simulated amplitude."""
    from railcontact.sim.cosim import Run, simulate

    run = Run(speed=10.0, duration=1.5, step=5e-3, initial_lateral=3e-3,
              model=WheelsetModel.free(),
              parameters={"creepage_input": "kinematic", "element_size": 1e-3})
    sim = simulate(fmu, run)
    assert sim.completed, sim.message
    w = measure_wavelength(sim.distance, sim.lateral)
    track, ws = s1002_60e1()
    lam = equivalent_conicity(track, ws, w.amplitude)
    klingel = klingel_wavelength(sim.radius, sim.half_distance, lam)
    print(f"simulated {w.wavelength:.3f} m at {w.amplitude * 1e3:.2f} mm, Klingel "
          f"{klingel:.3f} m (lambda {lam:.3f})")
    assert 2e-3 < w.amplitude < 4e-3
    assert w.wavelength == pytest.approx(klingel, rel=0.10)
    # the spin degree of freedom settles at pure rolling on the mean rolling radius
    assert sim.velocity[-1, 2] * sim.radius / run.speed == pytest.approx(1.0, abs=2e-3)


def test_free_conical_wheelset_follows_klingel_exactly(fmu, tmp_path):
    """Conical wheels (lambda = 0.1, delta_r = 2 lambda y exactly) through the FMU: the
    co-simulated wavelength is Klingel's to 1 % - the dynamics, the implicit step and the
    FMU's kinematic creepages add nothing of their own. (S1002's 5 % above is the profile's
    doing.)"""
    from railcontact.sim.cosim import Run, simulate

    s = np.linspace(-0.07, 0.065, 541)
    cone = Profile(s, -0.1 * s, "wheel", "cone").write(tmp_path / "cone.txt")
    path, _ = ensure_fmu(tmp_path / "cone.fmu", [cone])
    sim = simulate(path, Run(speed=10.0, duration=1.5, step=5e-3, initial_lateral=3e-3,
                             model=WheelsetModel.free(),
                             parameters={"creepage_input": "kinematic", "element_size": 1e-3,
                                         "wheel_profile": "cone.txt"}))
    assert sim.completed, sim.message
    w = measure_wavelength(sim.distance, sim.lateral)
    assert w.wavelength == pytest.approx(
        klingel_wavelength(sim.radius, sim.half_distance, 0.1), rel=0.01)


def test_demo_quick_runs_and_its_outputs_are_finite(fmu, tmp_path, capsys):
    out = tmp_path / "demo"
    code = main(["demo", "--quick", "--duration", "0.3", "--no-progress", "--fmu", str(fmu),
                 "--output-dir", str(out)])
    text = capsys.readouterr().out
    assert code == 0, text
    assert "up to date" in text and "fewer iterations" in text
    for name in ("demo_motion.png", "demo_patches.png"):
        assert (out / name).stat().st_size > 10_000
    from railcontact.sim.demo import DemoOptions, run_demo

    res = run_demo(DemoOptions(quick=True, duration=0.1, fmu=str(fmu), plots=False),
                   progress=False)
    assert res.sim.completed
    for name, values in res.sim.outputs.items():
        assert np.all(np.isfinite(values)), name
    assert np.all(res.sim.outputs["status"] == 0)
    assert np.all(np.isfinite(res.sim.position)) and np.all(np.isfinite(res.sim.velocity))
    # the loads are the rails' vertical forces, normal and creep forces (load control,
    # CONTACT's FZ; the creep forces carry F_y sin(gamma), under 1 % here), to the FMU's
    # load_tolerance; and the warm start needs fewer iterations than the cold one
    o = res.sim.outputs
    for side in ("left", "right"):
        np.testing.assert_allclose(o[f"force_vertical_{side}"], 83.3e3, rtol=1e-3)
    np.testing.assert_allclose(o["force_vertical"], 2 * 83.3e3, rtol=1e-3)
    s = res.summary
    assert (s["normal_iterations"] + s["tangential_iterations"]
            < s["cold_normal_iterations"] + s["cold_tangential_iterations"])


def test_demo_bad_input_is_one_line(fmu, tmp_path, capsys):
    assert main(["demo", "--speed", "-3", "--fmu", str(fmu), "--no-plots"]) == 2
    assert "speed" in capsys.readouterr().err
    assert main(["demo", "--wheel-profile", str(tmp_path / "nope.txt"), "--fmu", str(fmu),
                 "--no-plots"]) == 2
    assert "not found" in capsys.readouterr().err


def _synthetic(duration: float = 0.6, step: float = 2e-3):
    """A CoSimResult without an FMU: a decaying sine of y, an F_x start-up transient of
    18 kN decaying within 10 ms, and two slow steps (a kernel compiled on first use)."""
    from railcontact.sim.cosim import CoSimResult, Run

    run = Run(speed=30.0, duration=duration, step=step,
              parameters={"wheel_profile": "S1002", "rail_profile": "60E1",
                          "element_size": 8e-4, "warm_start": "previous+estimate"})
    t = np.arange(run.steps) * step
    y = 4e-3 * np.cos(2 * math.pi * 3.2 * t) * np.exp(-t)
    fx = 2e3 * np.sin(2 * math.pi * 3.2 * t) + 18e3 * np.exp(-t / 2e-3)
    zeros = np.zeros_like(t)
    solve = np.full_like(t, 4e-3)
    solve[[0, 5]] = (2.6, 0.9)
    outputs = {"creep_force_x_left": fx, "creep_force_x_right": -fx,
               "creep_force_y_left": 5e3 + zeros, "creep_force_y_right": -5e3 + zeros,
               "force_lateral": 1e3 * np.sin(t), "yaw_moment": 3e3 + zeros,
               "normal_force_left": 83.3e3 + zeros, "normal_force_right": 83.3e3 + zeros,
               "normal_iterations": 8 + zeros, "tangential_iterations": 9 + zeros,
               "solve_time": solve}
    track, ws = s1002_60e1()
    position = np.column_stack([y, 1e-3 * np.sin(t), zeros])
    return CoSimResult(time=t, distance=30.0 * t, position=position,
                       velocity=np.zeros_like(position), outputs=outputs,
                       wall_time=solve + 1e-4, shadows={}, jacobians=[], completed=True,
                       message="completed", run=run, fmu=Path("RailContact.fmu"),
                       radius=0.46, half_distance=0.75, track=track, wheelset=ws,
                       startup={"instantiate": 1.1, "initialise": 0.3})


def test_demo_peaks_leave_out_the_start_up_transient_and_say_so(tmp_path):
    """The summary's peaks are those after the start-up transient (the window named); the
    transient's |F_x| is given apart; the solve-time panel keeps the steps' own scale and
    draws the slow first steps at its top edge, labelled."""
    from railcontact.sim.demo import (
        STARTUP,
        DemoOptions,
        describe,
        plot_motion,
        summarise,
    )

    sim = _synthetic()
    s = summarise(sim)
    assert s["peak_from"] == pytest.approx(STARTUP)
    assert s["startup_creep_force_x"] == pytest.approx(18e3, rel=1e-3)
    assert s["peak_creep_force_x"] < 2.1e3
    text = describe(sim, s, DemoOptions(quick=True), built=False)
    assert "peaks after the start-up transient (t = 0.050-0.598 s;" in text
    assert "|F_x| reaches 18.00 kN" in text and "creep force |F_x| 2.00 kN" in text
    assert "FMU start-up (unpacked afresh): instantiate 1.10 s" in text

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown = []
    real_close = plt.close
    plt.close = lambda fig=None: shown.append(fig)  # keep the figure to look at it
    try:
        plot_motion(sim, tmp_path / "motion.png")
    finally:
        plt.close = real_close
    panel = shown[0].axes[3]
    assert panel.get_ylim()[1] < 100  # [ms]: not flattened by the 2.6 s step
    labels = sorted(t.get_text() for t in panel.texts)
    assert labels == ["2600 ms", "900 ms"]
    assert "2 slower steps" in panel.get_title()
    real_close(shown[0])

    short = summarise(_synthetic(duration=0.04))  # shorter than the transient: all of it
    assert short["peak_from"] == 0.0 and short["startup_creep_force_x"] == 0.0


def test_a_discarded_step_is_reported_not_raised():
    """A step the FMU discards (fmi2Discard: a state beyond the model, zero forces, status
    3) comes back with ``discarded`` set and its outputs, so that the run stops with its
    message; fmi2Error raises."""
    pytest.importorskip("fmpy")
    from fmpy.fmi1 import FMICallException

    from railcontact.sim.cosim import _Instance

    class FakeFMU:
        status = 2

        def setReal(self, vrs, values):  # noqa: N802 - fmpy's names
            pass

        def doStep(self, currentCommunicationPoint, communicationStepSize):  # noqa: N802, N803
            if self.status:
                raise FMICallException(function="fmi2DoStep", status=self.status)

        def getReal(self, vrs):  # noqa: N802
            return [0.0] * len(vrs)

        def getInteger(self, vrs):  # noqa: N802
            return [3] * len(vrs)

    inst = object.__new__(_Instance)
    inst.fmu, inst.inputs, inst.discarded = FakeFMU(), [0], False
    inst.real_out, inst.int_out, inst._real_vr, inst._int_vr = ["force_lateral"], ["status"], \
        [0], [1]
    out = inst.step(0.0, 1e-3, [0.0])
    assert inst.discarded and out == {"force_lateral": 0.0, "status": 3}
    inst.fmu.status = 0
    inst.step(1e-3, 1e-3, [0.0])
    assert not inst.discarded
    inst.fmu.status = 3
    with pytest.raises(FMICallException):
        inst.step(2e-3, 1e-3, [0.0])


def test_vehicle_contact_through_the_fmu_equals_the_in_process_one(fmu):
    """FMUContact (one one-wheelset FMU instance per wheelset, through fmpy) gives the
    vehicle the same wheel forces as InProcessContact with the FMU's settings, step for
    step (cold: the FMU's initialisation solves a state of its own, from which a warm
    step would start)."""
    from railcontact.fmu.variables import parameter_settings
    from railcontact.sim.vehicle_contact import InProcessContact, WheelsetStates
    from railcontact.sim.vehicle_fmu import FMUContact

    params = {"element_size": 2e-3, "rigid_wheelset": "skip", "warm_start": "none"}
    through = FMUContact(fmu, 2, 1e-3, params)
    try:
        ps = parameter_settings({**{v.name: v.start for v in _parameters(fmu)}, **params,
                                 "creepage_input": "kinematic"})
        track, ws = s1002_60e1()
        here = InProcessContact(track, ws, ps.material.elastic_pair(), ps.contact, count=2)
        v, r0 = 40.0, 0.46
        for k, y in enumerate((2e-3, 2.2e-3)):
            states = WheelsetStates(k * 1e-3, v, np.array([y, -y]), np.array([1e-4, 0.0]),
                                    np.array([0.01, -0.02]), np.array([0.0, 0.003]),
                                    np.array([v / r0, v / r0 * 1.0001]),
                                    np.full((2, 2), 60e3))
            a, b = through(states), here(states)
            assert a.ok and b.ok
            np.testing.assert_allclose(a.generalized, b.generalized, rtol=1e-9, atol=1e-6)
            np.testing.assert_allclose(a.derailment_quotient, b.derailment_quotient,
                                       rtol=1e-9, atol=1e-12)
            np.testing.assert_array_equal(a.status, b.status)
    finally:
        through.close()


def _parameters(fmu):
    from fmpy.model_description import read_model_description

    return [v for v in read_model_description(str(fmu)).modelVariables
            if v.causality == "parameter"]


def test_vehicle_contact_through_the_fmu_stops_as_the_in_process_one(fmu):
    """A wheelset without load (no contact) and one at a yaw beyond the small angles (the
    FMU discards the step, status out of range): FMUContact stops the run as InProcessContact
    does on no contact, and names both wheelsets; the good wheelset between them is not
    named."""
    from railcontact.sim.vehicle_contact import WheelsetStates
    from railcontact.sim.vehicle_fmu import FMUContact

    v, r0 = 40.0, 0.46
    through = FMUContact(fmu, 3, 1e-3, {"element_size": 2e-3, "warm_start": "none"})
    try:
        states = WheelsetStates(0.0, v, np.array([0.0, 1e-3, 0.0]), np.array([0.0, 0.0, 0.5]),
                                np.zeros(3), np.zeros(3), np.full(3, v / r0),
                                np.array([[0.0, 0.0], [60e3, 60e3], [60e3, 60e3]]))
        out = through(states)
        assert through.instances[2][0].discarded and not through.instances[1][0].discarded
    finally:
        through.close()
    assert not out.ok
    assert list(out.status) == [2, 0, 3]
    assert out.message.startswith("wheelset 1: no contact; wheelset 3: out of range"), \
        out.message
    assert "wheelset 2" not in out.message
