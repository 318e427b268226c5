"""The ``railcontact`` command line.

``railcontact solve CASE.toml [--json] [--plot FILE]`` solves a case file;
``railcontact fmu build [-o dist/RailContact.fmu]`` builds the FMU. Errors in the input are
reported in one line (exit status 2), never as a traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from .errors import RailContactError


def _summary(sol) -> str:
    lines = [f"case: {sol.case.get('name', 'case')}"]
    for k, ps in enumerate(sol.patches):
        n = ps.normal
        g = n.grid
        lines.append(f"patch {k}: BEM normal contact on {g.nx} x {g.ny} elements "
                     f"({g.dx * 1e3:.4g} x {g.dy * 1e3:.4g} mm), estimate '{ps.estimate}'")
        lines.append(f"  force          {n.force:12.6g} N")
        lines.append(f"  penetration    {n.penetration:12.6g} m")
        lines.append(f"  max pressure   {n.max_pressure:12.6g} Pa")
        lines.append(f"  contact area   {n.area:12.6g} m^2")
        lines.append(f"  iterations     {n.iterations:12d}   ({n.message})")
        lines.append(f"  wall time      {n.wall_time * 1e3:12.3f} ms")
        if ps.hertz is not None:
            h = ps.hertz
            lines.append(f"  Hertz: a = {h.a:.6g} m, b = {h.b:.6g} m, N = {h.load:.6g} N, "
                         f"delta = {h.penetration:.6g} m, p0 = {h.max_pressure:.6g} Pa, "
                         f"area = {h.area:.6g} m^2")
        if ps.tangential is not None:
            t = ps.tangential
            lines.append(f"  tangential ({ps.tangential_model}, estimate "
                         f"'{ps.tangential_estimate}'):")
            lines.append(f"  creep force    Fx = {t.force[0]:.6g} N, Fy = {t.force[1]:.6g} N")
            lines.append(f"  spin moment    {t.spin_moment:12.6g} N m")
            lines.append(f"  slip area      {t.slip_area_ratio:12.4f} of the contact area")
            lines.append(f"  max traction   {t.max_traction:12.6g} Pa")
            lines.append(f"  iterations     {t.iterations:12d}   ({t.message})")
            lines.append(f"  wall time      {t.wall_time * 1e3:12.3f} ms")
    return "\n".join(lines)


def _cmd_solve(args: argparse.Namespace) -> int:
    from .pipeline import solve

    sol = solve(args.case)
    if args.json:
        print(json.dumps(sol.to_dict(), indent=2))
    else:
        print(_summary(sol))
    if args.plot:
        from .plotting import plot_solution

        out = plot_solution(sol, args.plot)
        if not args.json:
            print(f"plot written to {out}")
    ok = all(p.normal.converged and (p.tangential is None or p.tangential.converged)
             for p in sol.patches)
    return 0 if ok else 1


def _cmd_fmu_build(args: argparse.Namespace) -> int:
    from .fmu import build_fmu

    out = build_fmu(args.output, args.profile or [])
    print(f"FMU written to {out}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="railcontact",
                                 description="Exact wheel-rail contact (half-space BEM).")
    sub = ap.add_subparsers(dest="command", required=True)
    s = sub.add_parser("solve", help="solve a TOML case file")
    s.add_argument("case", help="case file (TOML, SI units)")
    s.add_argument("--json", action="store_true", help="print the result as JSON")
    s.add_argument("--plot", metavar="FILE", help="write the patch/pressure figure to FILE")
    s.set_defaults(func=_cmd_solve)
    f = sub.add_parser("fmu", help="the FMI 2.0 co-simulation unit")
    fsub = f.add_subparsers(dest="fmu_command", required=True)
    fb = fsub.add_parser("build", help="build the FMU (gcc and fmpy's FMI headers)")
    fb.add_argument("-o", "--output", default="dist/RailContact.fmu",
                    help="the .fmu to write (default dist/RailContact.fmu)")
    fb.add_argument("--profile", action="append", metavar="FILE",
                    help="a profile file to put into the FMU's resources (repeatable)")
    fb.set_defaults(func=_cmd_fmu_build)
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except RailContactError as exc:
        print(f"railcontact: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
