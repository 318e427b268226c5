"""The bogie vehicle (railcontact.sim.vehicle): its suspension's free vibrations against
hand formulas, the linear model's eigenvalues against the time integration with the same
(linear) contact law, the kinematic (Klingel) limits of a wheelset and of a rigid bogie,
and the in-process BEM contact against Kalker's linear theory at small creepages."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

from railcontact.errors import RailContactError
from railcontact.sim.dynamics import WheelsetModel
from railcontact.sim.linear_contact import LinearWheelsetContact, harmonic_parameter
from railcontact.sim.stability import (
    critical_speed,
    hunting_mode,
    least_damped,
    wheelset_eigenvalues,
)
from railcontact.sim.vehicle import (
    CARBODY,
    VehicleRun,
    bogie_dofs,
    measure_decay,
    simulate_vehicle,
    vehicle_matrices,
    wheelset_dofs,
)
from railcontact.sim.vehicle_contact import LinearContact, WheelsetStates
from railcontact.sim.vehicle_data import GRAVITY, VehicleParameters, parameter_table

P = VehicleParameters()
# S1002 / 60E1 at 1:40 under the benchmark's wheel load, 3 mm amplitude, as
# railcontact.sim.linear_contact.linear_contact gives them (rounded; computing them takes
# seconds of contact search, which scripts/vehicle_stability.py prints)
LIN = LinearWheelsetContact(f11=12.63e6, f22=10.23e6, f23=20.64e3, f33=281.0, conicity=0.1757,
                            contact_angle_parameter=14.67, radius=0.4599,
                            half_distance=0.7532, normal_force=54.56e3)


def frequencies(m: np.ndarray, k: np.ndarray, dofs: list[int]) -> np.ndarray:
    """Undamped natural frequencies [rad/s] of the DOFs ``dofs``, all others held."""
    ix = np.ix_(dofs, dofs)
    return np.sqrt(np.sort(scipy.linalg.eigh(k[ix], m[ix], eigvals_only=True)))


# -- free vibrations of the suspension ------------------------------------------------------
def test_parameters_have_units_and_sources():
    rows = parameter_table()
    assert len(rows) == len(vars(P))
    assert all(unit and source and doc for _, _, unit, source, doc in rows)
    # the static wheel load: the vehicle's weight over its eight wheels
    total = P.carbody_mass + 2 * P.bogie_mass + 4 * P.wheelset_mass
    assert 8 * P.wheel_load == pytest.approx(total * GRAVITY)
    with pytest.raises(RailContactError, match="bogie_mass"):
        VehicleParameters(bogie_mass=-1.0)


def test_wheelset_on_a_held_frame():
    """Lateral and yaw of one wheelset on its two axleboxes: sqrt(2 k_y1 / m),
    sqrt(2 k_x1 b1^2 / I_z)."""
    mats = vehicle_matrices(P)
    w = wheelset_dofs(2)
    assert frequencies(mats.mass, mats.stiffness, [w[0]])[0] == pytest.approx(
        math.sqrt(2 * P.primary_lateral_stiffness / P.wheelset_mass), rel=1e-12)
    assert frequencies(mats.mass, mats.stiffness, [w[1]])[0] == pytest.approx(
        math.sqrt(2 * P.primary_longitudinal_stiffness * P.primary_semi_spacing**2
                  / P.wheelset_yaw_inertia), rel=1e-12)


def test_bogie_frame_yaw_on_held_wheelsets_and_car_body():
    """Yaw of a frame: its two wheelsets' lateral springs at +-l1, their yaw springs and the
    secondary's longitudinal springs."""
    mats = vehicle_matrices(P)
    b = bogie_dofs(1)
    k = (4 * P.primary_lateral_stiffness * P.semi_wheelbase**2
         + 4 * P.primary_longitudinal_stiffness * P.primary_semi_spacing**2
         + 2 * P.secondary_longitudinal_stiffness * P.secondary_semi_spacing**2)
    assert frequencies(mats.mass, mats.stiffness, [b[1]])[0] == pytest.approx(
        math.sqrt(k / P.bogie_yaw_inertia), rel=1e-12)


def test_car_body_yaw_lateral_and_roll_on_held_bogies():
    """The car body on its air springs, the bogies held: yaw alone,
    omega^2 = 4 (k_y2 l2^2 + k_x2 b2^2) / I_z; lateral and roll coupled (the sway modes):
    the roots of det(K - omega^2 M) of the 2 x 2 system with the four lateral springs at
    d = h_c - h_s below the centre of gravity, the roll springs, anti-roll bars and the
    gravitational roll stiffness -m g d."""
    mats = vehicle_matrices(P)
    y, psi, phi = CARBODY
    yaw = math.sqrt(4 * (P.secondary_lateral_stiffness * P.semi_bogie_distance**2
                         + P.secondary_longitudinal_stiffness * P.secondary_semi_spacing**2)
                    / P.carbody_yaw_inertia)
    assert frequencies(mats.mass, mats.stiffness, [psi])[0] == pytest.approx(yaw, rel=1e-12)
    k = 4 * P.secondary_lateral_stiffness
    d = P.carbody_height - P.secondary_height
    kr = (2 * (2 * P.secondary_vertical_stiffness * P.secondary_semi_spacing**2
               + P.antiroll_stiffness + 2 * P.secondary_bending_stiffness)
          - P.carbody_mass * GRAVITY * d)
    m, j = P.carbody_mass, P.carbody_roll_inertia
    # det([[k - w2 m, k d], [k d, k d^2 + kr - w2 j]]) = 0
    a, b, c = m * j, -(k * j + m * (k * d * d + kr)), k * kr
    w2 = np.sort([(-b - math.sqrt(b * b - 4 * a * c)) / (2 * a),
                  (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a)])
    np.testing.assert_allclose(frequencies(mats.mass, mats.stiffness, [y, phi]),
                               np.sqrt(w2), rtol=1e-10)
    # the yaw is decoupled from the lateral and the roll (bogies symmetric about the centre)
    assert mats.stiffness[psi, y] == 0.0 and mats.stiffness[psi, phi] == 0.0


# -- the kinematic limits -------------------------------------------------------------------
def test_free_wheelset_tends_to_klingel():
    """A free wheelset at low speed with the linear contact (no gravitational stiffness):
    the creep forces dominate the inertia and it oscillates with Klingel's frequency
    V sqrt(lambda / (r0 e)) / 2 pi."""
    lin = replace(LIN, contact_angle_parameter=0.0)
    model = WheelsetModel.free(mass=P.wheelset_mass, yaw_inertia=P.wheelset_yaw_inertia,
                               spin_inertia=P.wheelset_spin_inertia)
    for v in (1.0, 3.0):
        lam = wheelset_eigenvalues(model, lin, v)[0]
        klingel = v * math.sqrt(lin.conicity / (lin.radius * lin.half_distance))
        assert lam.imag == pytest.approx(klingel, rel=2e-3)
        assert abs(lam.real) < 0.02 * lam.imag


def test_rigid_bogie_tends_to_its_kinematic_wavelength():
    """Primary suspension made rigid, the car body's springs soft: at low speed the bogies
    hunt with the rigid bogie's kinematic wavelength (Wickens 1965)
    L_w sqrt(1 + f22 l1^2 / (f11 e^2)), L_w Klingel's."""
    lin = replace(LIN, contact_angle_parameter=0.0)
    p = replace(P, primary_lateral_stiffness=P.primary_lateral_stiffness * 1e3,
                primary_longitudinal_stiffness=P.primary_longitudinal_stiffness * 1e3,
                secondary_lateral_stiffness=1.0, secondary_longitudinal_stiffness=1.0)
    v = 2.0
    e = lin.half_distance
    lw = 2 * math.pi * math.sqrt(lin.radius * e / lin.conicity)
    lb = lw * math.sqrt(1 + lin.f22 * P.semi_wheelbase**2 / (lin.f11 * e**2))
    mode = hunting_mode(p, lin, v)
    assert mode.eigenvalue.imag == pytest.approx(2 * math.pi * v / lb, rel=0.01)


# -- the linear model against the integrator -------------------------------------------------
@pytest.mark.parametrize("speed", [70.0, 85.0])
def test_integrator_with_the_linear_contact_follows_the_eigenvalue(speed):
    """Started on the linear model's hunting mode, the vehicle integrated with the same
    linear contact law (``simulate_vehicle`` + ``LinearContact``) decays (70 m/s) or grows
    (85 m/s) at the eigenvalue's rate and frequency; the step's first-order error shrinks
    with the step (four times smaller from 1 ms to 0.25 ms, within 30 %), and
    extrapolated to a zero step it is gone."""
    mode = hunting_mode(P, LIN, speed)
    errors = []
    for h in (1e-3, 2.5e-4):
        q, v = mode.state(1e-3, speed, LIN.radius)
        run = VehicleRun(speed, 0.8, h, q, v, -LIN.damping(speed), LIN.radius)
        res = simulate_vehicle(P, LinearContact(LIN), run)
        assert res.completed
        d = measure_decay(res.time, res.position[:, 0])
        errors.append(d.rate - mode.eigenvalue.real)
        assert d.frequency == pytest.approx(mode.frequency, rel=0.01)
    assert errors[1] == pytest.approx(errors[0] / 4, rel=0.3)
    extrapolated = (4 * errors[1] - errors[0]) / 3  # Richardson: the first-order term gone
    print(f"rate error at 1 ms {errors[0]:+.4f}, 0.25 ms {errors[1]:+.4f}, extrapolated "
          f"{extrapolated:+.4f} 1/s (eigenvalue {mode.eigenvalue.real:+.4f})")
    assert abs(extrapolated) < 0.01
    cs = critical_speed(P, LIN, np.arange(60.0, 95.0, 5.0))
    assert (mode.eigenvalue.real < 0) == (speed < cs.speed)


def test_linear_critical_speed_is_a_root_of_the_least_damped_real_part():
    """The vehicle's critical speed: the least damped real part is zero there, negative
    1 m/s below, positive 1 m/s above (its value is checked on a case with a closed form,
    :func:`test_critical_speed_of_a_suspended_wheelset_is_wickens_closed_form`)."""
    cs = critical_speed(P, LIN, np.arange(60.0, 95.0, 5.0))
    assert abs(cs.mode.eigenvalue.real) < 1e-3
    assert least_damped(P, LIN, cs.speed - 1).eigenvalue.real < 0
    assert least_damped(P, LIN, cs.speed + 1).eigenvalue.real > 0
    with pytest.raises(RailContactError, match="speeds"):
        critical_speed(P, LIN, [50.0])


def test_critical_speed_of_a_suspended_wheelset_is_wickens_closed_form():
    """One wheelset on a lateral spring k_y and a yaw spring k_psi to a frame moving at V,
    Kalker's longitudinal and lateral creep (f11, f22; no spin, no gravitational stiffness):
    the characteristic quartic a4 s^4 + ... + a0 with a3, a1 ~ 1/V and a2 = C0 + D / V^2
    loses stability where Hurwitz's a1 a2 a3 - a1^2 a4 - a3^2 a0 = 0 (Wickens' analysis of
    the suspended wheelset), i.e. at 1/V_c^2 = (A^2 m I + B^2 a0 - A B C0) / (A B D) with
    A = 2 f22 k_psi + 2 e^2 f11 k_y, B = 2 m e^2 f11 + 2 I f22, C0 = m k_psi + I k_y,
    D = 4 e^2 f11 f22, a0 = k_y k_psi + 4 e f11 f22 lambda / r0. The largest real part of
    wheelset_eigenvalues changes sign there."""
    import scipy.optimize

    m, iz, ky, kx, b = 1250.0, 700.0, 2.0e6, 4.0e6, 1.0
    f11, f22, lam, r0, e = 8.0e6, 7.0e6, 0.2, 0.46, 0.75
    model = WheelsetModel(m, iz, ky, kx, b)
    kpsi = model.yaw_stiffness
    lin = LinearWheelsetContact(f11=f11, f22=f22, f23=0.0, f33=0.0, conicity=lam,
                                contact_angle_parameter=0.0, radius=r0, half_distance=e,
                                normal_force=80e3)
    a = 2 * f22 * kpsi + 2 * e**2 * f11 * ky
    bb = 2 * m * e**2 * f11 + 2 * iz * f22
    c0, d = m * kpsi + iz * ky, 4 * e**2 * f11 * f22
    a0 = ky * kpsi + 4 * e * f11 * f22 * lam / r0
    closed = 1 / math.sqrt((a**2 * m * iz + bb**2 * a0 - a * bb * c0) / (a * bb * d))
    vc = scipy.optimize.brentq(lambda v: wheelset_eigenvalues(model, lin, v)[0].real,
                               20.0, 400.0, xtol=1e-9)
    assert vc == pytest.approx(closed, rel=1e-6)


def test_measure_decay_of_a_damped_sine():
    t = np.linspace(0, 3, 3001)
    d = measure_decay(t, 2e-3 * np.exp(-0.7 * t) * np.sin(2 * math.pi * 4.0 * t + 0.4))
    assert d.rate == pytest.approx(-0.7, abs=2e-3)
    assert d.frequency == pytest.approx(4.0, rel=1e-3)


def test_harmonic_parameter_of_a_linear_and_a_cubic_difference():
    """For difference = 2 p y it is p; for 2 c y^3, (3/4) c A^2 (harmonic balance)."""
    y = np.linspace(-3e-3, 3e-3, 601)
    assert harmonic_parameter(y, 2 * 0.2 * y, 3e-3) == pytest.approx(0.2, rel=1e-6)
    assert harmonic_parameter(y, 2 * 5e4 * y**3, 3e-3) == pytest.approx(
        0.75 * 5e4 * 9e-6, rel=1e-4)


# -- the in-process BEM contact against Kalker --------------------------------------------
def test_in_process_contact_agrees_with_kalker_at_small_creepages():
    """Four centred wheelsets through InProcessContact (the BEM, 1 mm elements), three of
    them with one small velocity each (lateral, yaw rate, spin: creepage 1e-4), one more at
    y = 0.3 mm: the change of their forces from the unperturbed one is Kalker's linear
    theory at the nominal Hertz patch within 8 % on the diagonal terms (F_Y from y_dot,
    M_Z from psi_dot, T_y from Omega). The cross terms (F_Y and M_Z from y, M_Z from
    y_dot, F_Y from psi_dot) have the linear model's signs and its magnitude within a
    factor 2, M_Z from y_dot within a factor 5: they come from the spin coefficients f23
    and the contact angles' change, where the S1002/60E1 patches depart from the
    centred Hertz ellipse and its linear change with y."""
    from railcontact.geometry.profiles import builtin_profile
    from railcontact.geometry.track import Track, Wheelset
    from railcontact.settings import ContactSettings
    from railcontact.settings.case import MaterialSettings
    from railcontact.sim.vehicle_contact import InProcessContact

    contact = InProcessContact(Track(builtin_profile("60E1")),
                               Wheelset(builtin_profile("S1002")),
                               MaterialSettings().elastic_pair(),
                               ContactSettings(element_size=1e-3), count=5)
    v, e = 50.0, LIN.half_distance
    omega = v / LIN.radius
    states = WheelsetStates(
        0.0, v, np.array([0.0, 0.0, 0.0, 0.0, 3e-4]), np.zeros(5),
        np.array([0.0, 1e-4 * v, 0.0, 0.0, 0.0]), np.array([0.0, 0.0, 1e-4 * v / e, 0.0, 0.0]),
        np.array([omega, omega, omega, omega * (1 + 1e-4), omega]),
        np.full((5, 2), P.wheel_load))
    bem = contact(states)
    assert bem.ok and np.all(bem.status == 0)
    change = bem.generalized[1:] - bem.generalized[0]
    kalker = LinearContact(LIN)(states).generalized[1:]
    for k, dof in enumerate((0, 1, 2)):  # F_Y from y_dot, M_Z from psi_dot, T_y from Omega
        print(f"diagonal term {(k, dof)}: BEM {change[k, dof]:+.4g}, linear "
              f"{kalker[k, dof]:+.4g}, ratio {change[k, dof] / kalker[k, dof]:.3f}")
        assert change[k, dof] == pytest.approx(kalker[k, dof], rel=0.08)
    # (row of change: 0 y_dot, 1 psi_dot, 3 y; column: 0 F_Y, 1 M_Z)
    for (k, dof), factor in (((3, 0), 2.0), ((3, 1), 2.0), ((1, 0), 2.0), ((0, 1), 5.0)):
        ratio = change[k, dof] / kalker[k, dof]
        print(f"cross term {(k, dof)}: BEM {change[k, dof]:+.4g}, linear "
              f"{kalker[k, dof]:+.4g}, ratio {ratio:.3f}")
        assert 1 / factor < ratio < factor, (k, dof, change[k, dof], kalker[k, dof])
    np.testing.assert_allclose(bem.normal, P.wheel_load, rtol=0.01)


def test_demo_vehicle_command(capsys, tmp_path):
    """``railcontact demo --vehicle``: two steps of the vehicle with the BEM contact print
    each wheelset's motion, the wheel forces and the real-time factor; bad input is one
    line and exit status 2."""
    from railcontact.cli import main

    rc = main(["demo", "--vehicle", "--contact", "in-process", "--duration", "0.004",
               "--step", "0.002", "--element-size", "2e-3", "--no-plots", "--no-progress",
               "--output-dir", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 0, out
    for text in ("wheelset 4: peak |y| 3.00 mm", "wheelset 1 wheels: left |Y|", "Y/Q max",
                 "real-time factor"):
        assert text in out
    assert main(["demo", "--vehicle", "--speed", "-1", "--no-progress"]) == 2
    assert "speed" in capsys.readouterr().err


def test_demo_vehicle_uses_an_fmu_the_user_names_as_it_is(tmp_path, monkeypatch):
    """``--fmu`` naming an FMU that exists: the vehicle's contact is that FMU, never
    rebuilt (a one-wheelset FMU is not overwritten by one of four); the default path and a
    path that does not exist are built (ensure_fmu) as an FMU of four wheelsets."""
    import railcontact.fmu
    import railcontact.sim.demo  # noqa: F401 - imported before ensure_fmu is replaced
    import railcontact.sim.vehicle_fmu
    from railcontact.sim.vehicle_demo import VEHICLE_FMU, VehicleDemoOptions, _fmu_contact

    built, used = [], []
    monkeypatch.setattr(railcontact.fmu, "ensure_fmu",
                        lambda path, files, log=None, wheelsets=None:
                        built.append((str(path), wheelsets)) or (Path(path), True))
    monkeypatch.setattr(railcontact.sim.vehicle_fmu, "FMUContact",
                        lambda fmu, count, step, params: used.append((Path(fmu), count)))
    mine = tmp_path / "RailContact.fmu"
    mine.write_bytes(b"an FMU")
    cfg = {"element_size": 1e-3, "step": 1e-3}
    _fmu_contact(VehicleDemoOptions(fmu=str(mine)), cfg, False)
    assert built == [] and used == [(mine.resolve(), 4)] and mine.read_bytes() == b"an FMU"
    for path in (VEHICLE_FMU, str(tmp_path / "new.fmu")):
        _fmu_contact(VehicleDemoOptions(fmu=path), cfg, False)
        assert built[-1] == (path, 4)
