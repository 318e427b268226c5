"""Figure of the bogie vehicle's stability: the linear model's least damped real part and
its frequency against speed (eigenvalues), with the nonlinear co-simulation's measured
growth rates and frequencies read from ``scripts/vehicle_stability.py``'s printed output.

Usage: python scripts/vehicle_stability_figure.py LOG [LOG ...] [-o docs/vehicle_stability.png]
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from railcontact.io.plotting import _pyplot  # noqa: E402
from railcontact.sim.linear_contact import LinearWheelsetContact  # noqa: E402
from railcontact.sim.stability import hunting_mode, least_damped  # noqa: E402
from railcontact.sim.vehicle_data import VehicleParameters  # noqa: E402

RUN = re.compile(r"V =\s*([\d.]+) m/s: sigma ([+-][\d.]+) 1/s, ([\d.]+) Hz")
STEP = re.compile(r"step ([\d.]+) ms")
LIN = re.compile(r"f11 = ([\d.]+) MN, f22 = ([\d.]+) MN, f23 = ([\d.]+) kN m, f33 = ([\d.]+)")
GEO = re.compile(r"conicity ([\d.]+), contact-angle parameter ([\d.]+) 1/m, r0 = ([\d.]+) mm, "
                 r"e = ([\d.]+) mm")


def read_log(path: Path) -> tuple[str, np.ndarray, LinearWheelsetContact | None]:
    text = path.read_text()
    step = STEP.search(text)
    runs = np.array([[float(x) for x in m.groups()] for m in RUN.finditer(text)])
    lin = None
    m, g = LIN.search(text), GEO.search(text)
    if m and g:
        f11, f22, f23, f33 = (float(x) for x in m.groups())
        lam, gam, r0, e = (float(x) for x in g.groups())
        q = VehicleParameters().wheel_load
        lin = LinearWheelsetContact(f11 * 1e6, f22 * 1e6, f23 * 1e3, f33, lam, gam, r0 * 1e-3,
                                    e * 1e-3, q)
    return (f"nonlinear, step {step.group(1)} ms" if step else path.stem), runs, lin


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("logs", nargs="+", type=Path)
    ap.add_argument("-o", "--output", type=Path, default=Path("docs/vehicle_stability.png"))
    args = ap.parse_args()
    logs = [read_log(p) for p in args.logs]
    lin = next(lc for _, _, lc in logs if lc is not None)
    p = VehicleParameters()
    vs = np.linspace(40, 95, 111)
    least = [least_damped(p, lin, v) for v in vs]
    hunt = [hunting_mode(p, lin, v) for v in vs]
    plt = _pyplot()
    fig, ax = plt.subplots(2, 1, figsize=(7.5, 7), sharex=True, constrained_layout=True)
    ax[0].plot(vs, [m.eigenvalue.real for m in hunt], "k", label="linear: bogie hunting mode")
    ax[0].plot(vs, [m.eigenvalue.real for m in least], "k:", lw=1,
               label="linear: least damped mode")
    ax[1].plot(vs, [m.frequency for m in hunt], "k", label="linear: bogie hunting mode")
    for k, (label, runs, _) in enumerate(logs):
        if len(runs):
            o = np.argsort(runs[:, 0])
            ax[0].plot(runs[o, 0], runs[o, 1], f"C{k}o", label=label)
            ax[1].plot(runs[o, 0], runs[o, 2], f"C{k}o", label=label)
    ax[0].axhline(0, color="0.5", lw=0.8)
    ax[0].set_ylabel("growth rate sigma [1/s]")
    ax[0].legend(fontsize=8)
    ax[1].set_ylabel("frequency [Hz]")
    ax[1].set_xlabel("speed [m/s]")
    ax[1].legend(fontsize=8)
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle("Manchester Vehicle 1, S1002 / 60E1 1:40: linear eigenvalues and the "
                 "BEM co-simulation's growth at 3 mm", fontsize=9)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.output, dpi=110)
    print(f"written {args.output}")


if __name__ == "__main__":
    main()
