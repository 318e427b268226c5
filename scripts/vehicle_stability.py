"""Critical speed of the bogie vehicle: linear (eigenvalues) against nonlinear (the
co-simulation with the exact BEM contact), Manchester benchmark Vehicle 1 on S1002 / 60E1
at 1:40.

Linear: Kalker's coefficients at the nominal Hertz patches, the equivalent conicity and
the contact-angle parameter at the hunting amplitude (``--amplitude``), the lowest speed
at which an oscillatory eigenvalue's real part turns positive
(:mod:`railcontact.sim.stability`).

Nonlinear: the vehicle (:mod:`railcontact.sim.vehicle`) with four in-process
``WheelsetContact`` s, started on the linear model's hunting mode at that speed, scaled to
the amplitude (so the run starts at the amplitude the conicity was taken at, with little
of the other modes); its growth rate ``sigma`` is a line through the log of the leading
wheelset's lateral peaks after ``--settle`` seconds. Bisection on the speed between
``--low`` (must decay) and ``--high`` (must grow), ``--iterations`` times; the zero of
``sigma`` by linear interpolation between the bracket's ends is printed as well. The
step's first-order error biases ``sigma`` upwards by about h x 0.35 s^-1 per ms here
(measured on the linear model: ``--check-step``).

Usage: python scripts/vehicle_stability.py [--quick] [--element-size M] [--step S]
          [--duration S] [--low V] [--high V] [--iterations N] [--amplitude M]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from railcontact.geometry.profiles import builtin_profile  # noqa: E402
from railcontact.geometry.track import Track, Wheelset  # noqa: E402
from railcontact.settings import ContactSettings  # noqa: E402
from railcontact.settings.case import MaterialSettings  # noqa: E402
from railcontact.sim.linear_contact import linear_contact  # noqa: E402
from railcontact.sim.stability import critical_speed, hunting_mode  # noqa: E402
from railcontact.sim.vehicle import VehicleRun, measure_decay, simulate_vehicle  # noqa: E402
from railcontact.sim.vehicle_contact import InProcessContact, LinearContact  # noqa: E402
from railcontact.sim.vehicle_data import VehicleParameters  # noqa: E402

QUICK = {"element_size": 1.5e-3, "step": 2e-3, "duration": 0.8, "iterations": 2}


def nonlinear_growth(p, lin, track, ws, pair, speed, args):
    """(sigma [1/s], frequency [Hz], last peak [m], wall time [s], completed, message)."""
    mode = hunting_mode(p, lin, speed)
    q, v = mode.state(args.amplitude, speed, lin.radius)
    contact = InProcessContact(track, ws, pair, ContactSettings(element_size=args.element_size))
    run = VehicleRun(speed, args.duration, args.step, q, v, -lin.damping(speed), lin.radius)
    t0 = time.perf_counter()
    res = simulate_vehicle(p, contact, run)
    wall = time.perf_counter() - t0
    d = measure_decay(res.time, res.position[:, 0], args.settle)
    rate = d.rate
    if not res.completed:  # off the rail: growing
        rate = math.inf if not math.isfinite(rate) else max(rate, 0.0) + 1e-9
    return rate, d.frequency, d.amplitude, wall, res, mode


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help=f"coarse and short: {QUICK}")
    ap.add_argument("--element-size", type=float, default=None, help="BEM element [m] (1e-3)")
    ap.add_argument("--step", type=float, default=None, help="time step [s] (1e-3)")
    ap.add_argument("--duration", type=float, default=None, help="run length [s] (0.8)")
    ap.add_argument("--settle", type=float, default=0.1, help="skip this first [s] (0.1)")
    ap.add_argument("--iterations", type=int, default=None, help="bisection steps (5)")
    ap.add_argument("--low", type=float, default=None, help="lower speed [m/s] (0.7 V_lin)")
    ap.add_argument("--high", type=float, default=None, help="upper speed [m/s] (V_lin)")
    ap.add_argument("--amplitude", type=float, default=3e-3, help="hunting amplitude [m]")
    ap.add_argument("--check-step", action="store_true",
                    help="the linear model's growth rate from the integrator at the step "
                         "and at a fifth of it, beside the eigenvalue")
    args = ap.parse_args()
    base = QUICK if args.quick else {"element_size": 1e-3, "step": 1e-3, "duration": 0.8,
                                     "iterations": 5}
    for k, v in base.items():
        if getattr(args, k) is None:
            setattr(args, k, v)

    p = VehicleParameters()
    track, ws = Track(builtin_profile("60E1")), Wheelset(builtin_profile("S1002"))
    pair = MaterialSettings().elastic_pair()
    t0 = time.perf_counter()
    lin = linear_contact(track, ws, pair, p.wheel_load, args.amplitude)
    a, b = lin.semi_axes
    print(f"Manchester benchmark Vehicle 1, S1002 / 60E1 at 1:40, Q = {p.wheel_load / 1e3:.2f} "
          f"kN per wheel")
    print(f"linearised contact at {args.amplitude * 1e3:g} mm: conicity {lin.conicity:.4f}, "
          f"contact-angle parameter {lin.contact_angle_parameter:.2f} 1/m, r0 = "
          f"{lin.radius * 1e3:.1f} mm, e = {lin.half_distance * 1e3:.1f} mm, Hertz a, b = "
          f"{a * 1e3:.2f}, {b * 1e3:.2f} mm, f11 = {lin.f11 / 1e6:.2f} MN, f22 = "
          f"{lin.f22 / 1e6:.2f} MN, f23 = {lin.f23 / 1e3:.2f} kN m, f33 = {lin.f33:.1f} N m2")
    cs = critical_speed(p, lin)
    vlin = cs.speed
    print(f"LINEAR critical speed: {vlin:.2f} m/s ({vlin * 3.6:.1f} km/h), hunting at "
          f"{cs.mode.frequency:.2f} Hz  [{time.perf_counter() - t0:.1f} s]")
    sys.stdout.flush()
    if args.check_step:
        v = 1.05 * vlin
        m = hunting_mode(p, lin, v)
        for h in (args.step, args.step / 5):
            q, vv = m.state(1e-3, v, lin.radius)
            r = simulate_vehicle(p, LinearContact(lin), VehicleRun(
                v, 2.0, h, q, vv, -lin.damping(v), lin.radius))
            d = measure_decay(r.time, r.position[:, 0])
            print(f"  linear contact, integrator at {v:.1f} m/s, h = {h * 1e3:g} ms: sigma "
                  f"{d.rate:+.3f} 1/s, {d.frequency:.3f} Hz (eigenvalue "
                  f"{m.eigenvalue.real:+.3f} 1/s, {m.frequency:.3f} Hz)")

    low = args.low if args.low is not None else 0.7 * vlin
    high = args.high if args.high is not None else vlin
    print(f"NONLINEAR (BEM, element {args.element_size * 1e3:g} mm, step "
          f"{args.step * 1e3:g} ms, {args.duration:g} s per run, start on the hunting mode "
          f"at {args.amplitude * 1e3:g} mm):")
    ends = {}

    def run(v: float) -> float:
        rate, freq, amp, wall, res, mode = nonlinear_growth(p, lin, track, ws, pair, v, args)
        steps = len(res.forces)
        per = np.median(res.wall_time[:, 0]) * 1e3 if steps else math.nan
        print(f"  V = {v:7.3f} m/s: sigma {rate:+.3f} 1/s, {freq:.2f} Hz, last peak "
              f"{amp * 1e3:.2f} mm (linear mode there: {mode.eigenvalue.real:+.3f} 1/s, "
              f"{mode.frequency:.2f} Hz); {steps} steps, {per:.1f} ms contact per vehicle "
              f"step (median), {wall:.0f} s" + ("" if res.completed else f"; {res.message}"))
        sys.stdout.flush()
        ends[v] = rate
        return rate

    r_low, r_high = run(low), run(high)
    if not (r_low < 0 < r_high):
        print(f"the bracket [{low:g}, {high:g}] m/s does not straddle sigma = 0 "
              f"({r_low:+.3f}, {r_high:+.3f}); widen --low/--high")
        return
    for _ in range(args.iterations):
        mid = 0.5 * (low + high)
        if run(mid) < 0:
            low = mid
        else:
            high = mid
    rl, rh = ends[low], ends[high]
    interp = low + (high - low) * (-rl) / (rh - rl) if math.isfinite(rh) else 0.5 * (low + high)
    vnl = 0.5 * (low + high)
    print(f"NONLINEAR critical speed: bracket [{low:.3f}, {high:.3f}] m/s, midpoint "
          f"{vnl:.2f} m/s ({vnl * 3.6:.1f} km/h), zero of sigma by interpolation "
          f"{interp:.2f} m/s")
    print(f"LINEAR {vlin:.2f} m/s vs NONLINEAR {interp:.2f} m/s: difference "
          f"{interp - vlin:+.2f} m/s ({(interp - vlin) / vlin:+.1%} of the linear)")


if __name__ == "__main__":
    main()
