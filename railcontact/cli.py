"""The ``railcontact`` command line.

``railcontact demo [--quick]`` co-simulates a wheelset with the FMU through fmpy;
``railcontact solve CASE.toml [--json] [--plot FILE]`` solves a case file;
``railcontact fmu build [-o dist/RailContact.fmu] [--python PATH] [--wheelsets N]`` builds
the FMU and ``railcontact fmu check FILE.fmu`` tells which Python it will run in;
``railcontact settings`` prints the reference of every setting; ``railcontact table
build|check|refine|show|export`` makes, checks, refines, summarises and exports contact
tables (docs/tables.md). Errors in the input are reported in one line (exit status 2),
never as a traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Sequence

from . import __version__
from .errors import RailContactError, SolverError
from .halfspace.hertz import MIN_LOAD
from .settings import ContactSettings
from .settings.choices import PROFILE_UNITS, WARM_STARTS
from .settings.friction import FrictionTable


def _summary(sol, wheels=()) -> str:
    """The text report of a solution ``sol`` and its loaded ``wheels``
    (:func:`~railcontact.io.wheels.case_wheels`)."""
    lines = [f"case: {sol.case.name}"]
    if sol.roll is not None:
        lines.append(f"wheelset roll   {sol.roll:12.6g} rad")
    if not sol.patches:
        lines.append("no contact")
    for k, ps in enumerate(sol.patches):
        n = ps.normal
        g = n.grid
        what = "BEM normal contact" if n.force > 0 else "no element in contact"
        lines.append(f"patch {k}: {what} on {g.nx} x {g.ny} elements "
                     f"({g.dx * 1e3:.4g} x {g.dy * 1e3:.4g} mm), estimate '{ps.estimate}'")
        if ps.geometry is not None:
            cp = ps.geometry
            lines.append(f"  {cp.side} wheel: contact at Y = {cp.position[1] * 1e3:.3f} mm, "
                         f"angle {math.degrees(cp.contact_angle):.3f} deg, rolling radius "
                         f"{cp.rolling_radius * 1e3:.3f} mm")
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
            fx, fy, mz = ps.creep_forces  # in the case's convention
            lines.append(f"  creep force    Fx = {fx:.6g} N, Fy = {fy:.6g} N"
                         + ("  (CONTACT's convention)" if ps.convention == "contact" else ""))
            lines.append(f"  spin moment    {mz:12.6g} N m")
            c = ps.reported_creepage
            if c is not None:
                lines.append(f"  creepages      xi = {c[0]:.6g}, eta = {c[1]:.6g}, phi = "
                             f"{c[2]:.6g} 1/m")
            if ps.frictional_power is not None:
                lines.append(f"  friction power {ps.frictional_power:12.6g} W   (at "
                             f"{ps.velocity:.6g} m/s)")
            table = sol.case.tangential.friction
            if isinstance(table, FrictionTable) and ps.friction is not None:
                rows = ", per element row" if table.at == "row" else ""
                lines.append(f"  friction       {ps.friction:12.6g}   (the table's at the "
                             f"reference point{rows})")
            lines.append(f"  slip area      {t.slip_area_ratio:12.4f} of the contact area")
            lines.append(f"  max traction   {t.max_traction:12.6g} Pa")
            lines.append(f"  iterations     {t.iterations:12d}   ({t.message})")
            lines.append(f"  wall time      {t.wall_time * 1e3:12.3f} ms")
        lines.append(f"  all work       {_work(ps.work)}")
    for w in wheels:
        within = (f"outside validity: {w.validity.message}" if w.validity.flags
                  else "within validity")
        lines.append(f"{w.side} wheel: Y/Q = {w.derailment_quotient:.4g}; {within}")
    lines.append(f"total: {_work(sol.work)}")
    return "\n".join(lines)


def _work(w) -> str:
    return (f"{w.normal_iterations} normal + {w.tangential_iterations} tangential iterations, "
            f"{w.load_passes} load pass(es), {w.remeshes} re-mesh(es), "
            f"{w.seconds * 1e3:.3g} ms")


NO_CONTACT_EXIT = 3
"""Exit code of ``solve`` when a case has no contact (nothing was solved)."""
EXIT_PRIORITY = (2, 1, NO_CONTACT_EXIT)
"""With several files the exit code is the first of these that occurred: an error, then a
case that did not converge, then one without contact."""


def _cmd_solve(args: argparse.Namespace) -> int:
    from .contact import solve
    from .io.jsonout import solution_json
    from .io.wheels import case_wheels

    several = len(args.case) > 1
    if args.plot:
        from .io.plotting import plot_path, plot_solution

        if several:
            raise RailContactError("--plot takes one case file")
        plot_path(args.plot)  # a bad file name is an error before the solve
    outcomes = set()
    for case in args.case:
        try:
            sol = solve(case)
        except (RailContactError, SolverError) as exc:
            text = str(exc)  # (named with its file, unless it names it already)
            print(f"railcontact: error: {text if str(case) in text else f'{case}: {text}'}",
                  file=sys.stderr)
            if args.json:  # an object for every file, in order (one line each of several)
                print(json.dumps({"file": str(case), "error": str(exc)},
                                 indent=None if several else 2))
            outcomes.add(2)
            continue
        wheels = case_wheels(sol)
        if args.json:  # several files: one JSON object per line, with its file
            print(solution_json(sol, indent=None if several else 2,
                                file=str(case) if several else None, wheels=wheels))
        else:
            text = _summary(sol, wheels)
            print(f"== {case}\n{text}" if several else text)
        for w in wheels:  # (solved as asked; the exit status is the solve's)
            if w.validity.flags:
                print(f"railcontact: warning: {case}: {w.side} wheel outside the model's "
                      f"validity: {w.validity.message}", file=sys.stderr)
        contact = any(p.normal.force > 0 for p in sol.patches)
        if args.plot:  # (one figure per patch: both sides, tread and flange)
            for k in range(len(sol.patches)):
                out = plot_solution(sol, args.plot, patch=k)
                if not args.json:
                    print(f"plot written to {out}")
        if not sol.converged:
            outcomes.add(1)
        if not contact and sol.converged:  # (else its message says why, and it exits 1)
            unplotted = "; no figure written" if args.plot and not sol.patches else ""
            print(f"railcontact: warning: {case}: no contact (zero load, a load below "
                  f"{MIN_LOAD:g} N, or a penetration below the gap): nothing was "
                  f"solved{unplotted}", file=sys.stderr)
            outcomes.add(NO_CONTACT_EXIT)
    return next((c for c in EXIT_PRIORITY if c in outcomes), 0)


def _cmd_settings(args: argparse.Namespace) -> int:
    print(settings_reference())
    return 0


def settings_reference() -> str:
    """Every setting (case files, time step, FMU modes) and the FMU parameters, as Markdown
    (the text of ``docs/settings.md``)."""
    from .fmu.variables import parameters_markdown
    from .settings import markdown

    return markdown() + "\n" + parameters_markdown()


def _cmd_fmu_build(args: argparse.Namespace) -> int:
    from .fmu import build_fmu

    out = build_fmu(args.output, args.profile or [], python=args.python,
                    warm=not args.no_warm, log=print, wheelsets=args.wheelsets)
    print(f"FMU written to {out}")
    return 0


def _cmd_fmu_check(args: argparse.Namespace) -> int:
    from .fmu import check_fmu

    report = check_fmu(args.fmu)
    print(report.text)
    return 0 if report.ok else 1


def _cmd_wisdom(args: argparse.Namespace) -> int:
    from .halfspace.operator import WISDOM_ENV, save_wisdom

    n = save_wisdom(args.file, args.max_elements)
    print(f"measured {n} FFT plans (padded shapes and pruned row counts of grids up to "
          f"{args.max_elements} elements per axis), wisdom written to {args.file}; use it with "
          f"{WISDOM_ENV}={args.file}")
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    if args.vehicle:
        return _cmd_demo_vehicle(args)
    from .fmu import DEFAULT_OUTPUT
    from .sim.demo import DemoOptions, run_demo

    opts = DemoOptions(
        speed=30.0 if args.speed is None else args.speed, duration=args.duration, step=args.step,
        initial_lateral=4e-3 if args.initial_lateral is None else args.initial_lateral,
        wheel_profile=args.wheel_profile,
        rail_profile=args.rail_profile, profile_unit=args.profile_unit,
        element_size=args.element_size, warm_start=args.warm_start, free=args.free,
        cold_every=args.cold_every, quick=args.quick,
        fmu=DEFAULT_OUTPUT if args.fmu is None else args.fmu,
        output_dir=args.output_dir, plots=not args.no_plots)
    res = run_demo(opts, progress=not args.no_progress)
    print(res.text)
    for f in res.files:
        print(f"plot written to {f}")
    return 0 if res.sim.completed else 1


def _cmd_demo_vehicle(args: argparse.Namespace) -> int:
    from .sim.vehicle_demo import VEHICLE_FMU, VehicleDemoOptions, run_vehicle_demo

    opts = VehicleDemoOptions(
        speed=60.0 if args.speed is None else args.speed, duration=args.duration,
        step=args.step,
        initial_lateral=3e-3 if args.initial_lateral is None else args.initial_lateral,
        wheel_profile=args.wheel_profile, rail_profile=args.rail_profile,
        profile_unit=args.profile_unit, element_size=args.element_size,
        warm_start=args.warm_start, quick=args.quick, output_dir=args.output_dir,
        plots=not args.no_plots, contact=args.contact, processes=args.processes,
        fmu=VEHICLE_FMU if args.fmu is None else args.fmu)
    res = run_vehicle_demo(opts, progress=not args.no_progress)
    print(res.text)
    for f in res.files:
        print(f"plot written to {f}")
    return 0 if res.sim.completed else 1


def _add_demo(sub) -> None:
    d = sub.add_parser("demo", help="co-simulate a wheelset on track with the FMU (fmpy)",
                       description="A wheelset (lateral, yaw, spin; primary suspension to a "
                       "frame at constant speed; 83.3 kN per wheel) from an initial lateral "
                       "offset, its wheel-rail forces from the railcontact FMU each step. "
                       "Builds the FMU when missing or stale, prints a summary and writes "
                       "plots.")
    d.add_argument("--quick", action="store_true",
                   help="short run: 0.6 s, 2 ms steps, 0.8 mm elements (under a minute)")
    d.add_argument("--vehicle", action="store_true",
                   help="a bogie passenger vehicle (Manchester benchmark Vehicle 1: car body, "
                   "two bogies, four wheelsets), its contact from an FMU of four wheelsets "
                   "(--contact); --quick: "
                   "0.5 s, 2 ms steps, 1.5 mm elements (defaults 1 s, 1 ms, 1 mm)")
    d.add_argument("--contact", default="fmu", choices=("fmu", "in-process"),
                   help="--vehicle: the wheelsets' contact: fmu, the FMU of --fmu run by "
                   "fmpy; in-process, four WheelsetContacts in this process (default: fmu)")
    d.add_argument("--processes", type=int, default=None,
                   help="--vehicle --contact in-process: step the four wheelsets at the same "
                   "time in N worker processes (default: one after the other in this process)")
    d.add_argument("--speed", type=float, help="forward speed [m/s] (30; --vehicle: 60)")
    d.add_argument("--duration", type=float, help="simulated time [s] (1.5)")
    d.add_argument("--step", type=float, help="communication step [s] (0.001)")
    d.add_argument("--initial-lateral", type=float,
                   help="initial lateral displacement [m] (0.004; --vehicle: 0.003, every "
                   "wheelset)")
    d.add_argument("--wheel-profile", default="S1002",
                   help="built-in wheel profile or a profile file (S1002)")
    d.add_argument("--rail-profile", default="60E1",
                   help="built-in rail profile (60E1, UIC60, CN60) or a profile file (60E1)")
    d.add_argument("--profile-unit", default="mm", choices=PROFILE_UNITS,
                   help="unit of two-column profile files (mm)")
    d.add_argument("--element-size", type=float,
                   help=f"BEM element size [m] ({ContactSettings().element_size:g})")
    d.add_argument("--warm-start", default="previous+estimate", choices=WARM_STARTS,
                   help="warm start of the BEM (previous+estimate)")
    d.add_argument("--free", action="store_true",
                   help="no suspension: Klingel's free wheelset (use a low speed)")
    d.add_argument("--cold-every", type=int, default=10,
                   help="solve every N-th state also cold, for comparison (0: never; 10)")
    d.add_argument("--fmu", default=None,
                   help="the FMU to use, built if missing or stale (dist/RailContact.fmu; "
                   "--vehicle: an FMU of four wheelsets, dist/RailContact_4wheelsets.fmu, "
                   "built if missing or stale; another FMU that exists, of four wheelsets "
                   "or of one, is used as it is)")
    d.add_argument("--output-dir", default="railcontact_demo",
                   help="folder for the plots (railcontact_demo)")
    d.add_argument("--no-plots", action="store_true", help="do not write plots")
    d.add_argument("--no-progress", action="store_true", help="no progress line on stderr")
    d.set_defaults(func=_cmd_demo)


def _cmd_table_build(args: argparse.Namespace) -> int:
    from .table.build import build_table
    from .table.kinds import load_any_spec
    from .table.spec import CREEP_KIND, DEFAULT_KIND

    spec = load_any_spec(args.spec)
    if getattr(spec, "kind", DEFAULT_KIND) == CREEP_KIND:
        return _build_creep(spec, args)
    try:
        rep = build_table(spec, args.output, scheduler=args.scheduler, workers=args.workers,
                          resume=args.resume, progress=not args.quiet,
                          check=args.check, check_seed=args.seed, check_method=args.method,
                          **({} if args.lost_timeout is None else
                             {"lost_timeout": args.lost_timeout}))
    except KeyboardInterrupt:
        print(f"railcontact: interrupted; the finished batches are in {args.output}: rerun "
              "with --resume to complete it", file=sys.stderr)
        return 130
    kinds = ", ".join(f"{n} {k}" for k, n in rep.statuses.items())
    print(f"table {args.output}: {rep.points} points x {len(spec.sides)} wheel(s); "
          f"computed {rep.computed} ({rep.rate:.3g} points/s on {rep.workers} worker(s)), "
          f"{rep.skipped} already there; {rep.not_ok} point-wheel(s) not ok"
          + (f" ({kinds})" if kinds else "")
          + (f"; {rep.recovered} solved again from another start" if rep.recovered else "")
          + " (see 'railcontact table show')")
    if rep.check is not None:
        _print_check(rep.check)
    for f in rep.failed_batches:
        print(f"railcontact: error: {f}", file=sys.stderr)
    if rep.failed_batches:
        print(f"railcontact: error: {len(rep.failed_batches)} batch(es) failed; rerun with "
              "--resume to compute them", file=sys.stderr)
        return 1
    return 0


def _build_creep(spec, args: argparse.Namespace) -> int:
    """``table build`` of a creep table: in this process with ``--workers 0``, else on a
    Dask cluster (local or ``--scheduler``)."""
    from .table.build import close_client, connect
    from .table.creep import build_creep_table

    if args.resume or args.check:
        raise RailContactError("a creep table is built whole: --resume and --check are for "
                               "contact tables")
    if args.scheduler and args.workers is not None:
        raise RailContactError("give --workers or --scheduler, not both")
    client = None if args.workers == 0 else connect(args.scheduler, args.workers)
    try:
        rep = build_creep_table(spec, args.output, client=client, progress=not args.quiet)
    finally:
        if client is not None:
            close_client(client)
    print(f"creep table {args.output}: {rep.points} points in {rep.seconds:.3g} s "
          f"({rep.rate:.3g} points/s); {rep.not_converged} not converged"
          + (f", the creep coefficients of {rep.coefficients_failed} ellipse ratio(s) NaN"
             if rep.coefficients_failed else "") + " (see 'railcontact table show')")
    for m in rep.messages[:10]:
        print(f"railcontact: warning: {m}", file=sys.stderr)
    return 0


def _print_check(chk) -> None:
    from .table.check import MEASURE_TEXT, MEASURES, overall

    tot = overall(chk)
    parts = []
    for m in MEASURES:
        st, scale = tot[m], 1e3 if m == "contact_angle" else 1.0
        if st["n"]:
            parts.append(f"{MEASURE_TEXT[m]} median {st['median'] * scale:.2e} max "
                         f"{st['max'] * scale:.2e}")
    print(f"check ({chk.method}) at {chk.size} random states x {len(chk.sides)} wheel(s) "
          f"against the exact solver ({chk.seconds:.1f} s): " + "; ".join(parts)
          + f"; {tot['holes']} in holes, {tot['unsolved']} not solved exactly "
          "(per interval: 'railcontact table show')")


def _cmd_table_check(args: argparse.Namespace) -> int:
    from .table.build import close_client, connect
    from .table.check import check_table

    if args.states < 1:
        raise RailContactError(f"the number of states must be at least 1, got {args.states}")
    if args.seed < 0:
        raise RailContactError(f"--seed must be a non-negative integer, got {args.seed}")
    if args.scheduler and args.workers is not None:
        raise RailContactError("give --workers or --scheduler, not both")
    from .table.store import open_dataset

    open_dataset(args.table)  # a table there, before any cluster
    client = None if args.workers == 0 else connect(args.scheduler, args.workers)
    try:
        chk = check_table(args.table, args.states, args.seed, args.method, client,
                          **({} if args.lost_timeout is None else
                             {"lost_timeout": args.lost_timeout}))
    finally:
        if client is not None:
            close_client(client)
    _print_check(chk)
    return 0


def _cmd_table_refine(args: argparse.Namespace) -> int:
    from .table.refine import parse_targets, refine_table

    if args.scheduler and args.workers is not None:
        raise RailContactError("give --workers or --scheduler, not both")
    targets = parse_targets(args.target, args.jump_angle)
    rep = refine_table(args.table, targets, axes=tuple(args.axes) if args.axes else None,
                       rounds=args.rounds, scheduler=args.scheduler, workers=args.workers,
                       progress=not args.quiet, lost_timeout=args.lost_timeout)
    for k, r in enumerate(rep.rounds, 1):
        added = "; ".join(f"{n} +{len(v)}" for n, v in r["added"].items())
        print(f"round {k}: {added} node(s) (by error: "
              + (", ".join(f"{n} {len(v)}" for n, v in r["by_error"].items()) or "none")
              + "; by contact jump: "
              + (", ".join(f"{n} {len(v)}" for n, v in r["by_jump"].items()) or "none")
              + f" interval(s)); {r['points']} points, {r['computed']} computed")
    if not rep.rounds:
        print(f"table {args.table}: nothing exceeds the targets; unchanged")
    if rep.before is not None and rep.after is not None:
        for m in ("normal_force", "creep_force", "contact_angle"):
            b, a = rep.before[m], rep.after[m]
            if b["n"] and a["n"]:
                print(f"checked {m} error: max {b['max']:.3g} -> {a['max']:.3g}, median "
                      f"{b['median']:.3g} -> {a['median']:.3g} (at the check's states)")
    return 0


def _cmd_table_export(args: argparse.Namespace) -> int:
    from .table.export import export_table

    print(f"table {args.table} written to {export_table(args.table, args.output, args.format)}")
    return 0


def _cmd_table_show(args: argparse.Namespace) -> int:
    from .table.show import plot_table, summary

    print(summary(args.table))
    if args.plot:
        print(f"plot written to {plot_table(args.table, args.plot)}")
    return 0


def _add_table(sub) -> None:
    t = sub.add_parser("table", help="contact tables: exact solves over a grid, on Dask")
    tsub = t.add_subparsers(dest="table_command", required=True)
    b = tsub.add_parser("build", help="build (or complete) a table in a Zarr store",
                        description="Solve a case file at every point of the axes of its "
                        "[table] (docs/tables.md) on a Dask cluster, writing an xarray "
                        "Dataset to a Zarr store. Points already in the store are not "
                        "computed again. A [table] kind = 'creep' spec builds a "
                        "normalised creep table (Hertzian patches; docs/tables.md).")
    b.add_argument("spec", help="the table spec: a wheel-rail case file with a [table], or "
                   "a creep table's spec")
    b.add_argument("-o", "--output", required=True, help="the Zarr store (OUT.zarr)")
    b.add_argument("--scheduler", metavar="ADDRESS",
                   help="a running Dask scheduler (tcp://host:8786); default: a local cluster")
    b.add_argument("--workers", type=int, help="local worker processes (default: the CPUs; "
                   "0: a creep table in this process)")
    b.add_argument("--resume", action="store_true",
                   help="complete an existing store (error when there is none)")
    b.add_argument("--quiet", action="store_true", help="no progress bar")
    b.add_argument("--lost-timeout", type=float, metavar="SECONDS",
                   help="stop with an error when the cluster has had no worker this long "
                   "(default 120 s); the finished batches are kept: resume")
    b.add_argument("--check", type=int, default=0, metavar="N",
                   help="then solve N random off-node states exactly and keep the "
                   "interpolation error per axis interval in the store (table show)")
    _check_options(b)
    b.set_defaults(func=_cmd_table_build)
    c = tsub.add_parser("check", help="measure a table's interpolation error at random "
                        "states against the exact solver",
                        description="Solve N random off-node states of the table exactly "
                        "and keep the interpolation error per interval of each axis in the "
                        "store (replacing an earlier check); 'railcontact table show' "
                        "prints it.")
    c.add_argument("table", help="the Zarr store")
    c.add_argument("states", type=int, help="the number of random states N")
    _check_options(c)
    c.add_argument("--scheduler", metavar="ADDRESS",
                   help="a running Dask scheduler (tcp://host:8786); default: a local cluster")
    c.add_argument("--workers", type=int,
                   help="local worker processes (default: the CPUs; 0: in this process)")
    c.add_argument("--lost-timeout", type=float, metavar="SECONDS",
                   help="stop with an error when the cluster has had no worker this long "
                   "(default 120 s)")
    c.set_defaults(func=_cmd_table_check)
    r = tsub.add_parser("refine", help="add nodes where the checked error or a contact jump "
                        "exceeds a target", description="Split the intervals of the axes "
                        "where the kept check's error or a contact jump between neighbouring "
                        "nodes exceeds its target at their middles, solve only the new points "
                        "and rewrite the store (docs/tables.md).")
    r.add_argument("table", help="the Zarr store (complete)")
    r.add_argument("--target", action="append", metavar="MEASURE=VALUE",
                   help="largest checked error accepted: normal_force (|dN|/max(N,Q), "
                   "default 0.01), creep_force (|dF|/(mu max(N,Q)), 0.05), contact_angle "
                   "(rad, 0.005); repeatable")
    r.add_argument("--jump-angle", type=float, metavar="RAD",
                   help="contact angle step between neighbouring nodes taken as a jump "
                   "(default 0.05 rad)")
    r.add_argument("--axes", nargs="+", metavar="AXIS",
                   help="the axes to refine (default: every axis of more than one node)")
    r.add_argument("--rounds", type=int, default=1, help="refinements at most (1)")
    r.add_argument("--scheduler", metavar="ADDRESS",
                   help="a running Dask scheduler (tcp://host:8786); default: a local cluster")
    r.add_argument("--workers", type=int, help="local worker processes (default: the CPUs)")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.add_argument("--lost-timeout", type=float, metavar="SECONDS",
                   help="stop with an error when the cluster has had no worker this long "
                   "(default 120 s)")
    r.set_defaults(func=_cmd_table_refine)
    e = tsub.add_parser("export", help="write a table as netCDF or CSV",
                        description="Write the table as netCDF (xarray; the axes and side as "
                        "coordinates) or as CSV (one row per node and wheel: the axes, side, "
                        "every quantity, status, the work counters; SI units).")
    e.add_argument("table", help="the Zarr store")
    e.add_argument("output", help="the file: OUT.nc or OUT.csv")
    e.add_argument("--format", choices=("netcdf", "csv"),
                   help="the format (default: from the suffix, .nc or .csv)")
    e.set_defaults(func=_cmd_table_export)
    s = tsub.add_parser("show", help="summary of a table (axes, ranges, failed points)")
    s.add_argument("table", help="the Zarr store")
    s.add_argument("--plot", metavar="FILE",
                   help="write the forces against each axis and a heat map to FILE")
    s.set_defaults(func=_cmd_table_show)


def _check_options(p) -> None:
    p.add_argument("--seed", type=int, default=0,
                   help="random seed of the check's states (0)")
    p.add_argument("--method", choices=("linear", "cubic"), default="linear",
                   help="the interpolation checked (linear)")


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="railcontact",
                                 description="Exact wheel-rail contact (half-space BEM).")
    ap.add_argument("--version", action="version", version=f"railcontact {__version__}")
    sub = ap.add_subparsers(dest="command", required=True)
    _add_demo(sub)
    s = sub.add_parser("solve", help="solve TOML case files",
                       description="Solve each case file in turn. Exit 2 when a file was in "
                       "error (the others are still solved), else 1 when a case did not "
                       "converge, else 3 when one had no contact (nothing solved), else 0.")
    s.add_argument("case", nargs="+", help="case file(s) (TOML, SI units)")
    s.add_argument("--json", action="store_true", help="print the result as JSON (several "
                   "files: one object per line)")
    s.add_argument("--plot", metavar="FILE",
                   help="write the patch/pressure figure to FILE (patch K >= 1 of a case "
                   "with several: FILE-patchK beside it)")
    s.set_defaults(func=_cmd_solve)
    st = sub.add_parser("settings", help="print every setting (case-file keys, time-step and "
                        "FMU settings) with default, unit and allowed values (Markdown)")
    st.set_defaults(func=_cmd_settings)
    w = sub.add_parser("wisdom", help="measure FFTW plans for every padded grid shape once "
                       "and save them (faster transforms for every later run)",
                       description="Measures the FFTW plans (FFTW_MEASURE) of the padded "
                       "shapes of all grids up to --max-elements per axis and writes FFTW's "
                       "wisdom to FILE. A process whose environment has "
                       "RAILCONTACT_FFTW_WISDOM=FILE plans those shapes from it at no cost "
                       "(without it, plans are estimated: ~2 ms each, 20-50 % slower "
                       "transforms).")
    w.add_argument("file", help="the wisdom file to write")
    w.add_argument("--max-elements", type=int, default=100,
                   help="largest element count per grid axis covered (100; 64 took about "
                   "9 minutes here, 100 takes longer)")
    w.set_defaults(func=_cmd_wisdom)
    f = sub.add_parser("fmu", help="the FMI 2.0 co-simulation unit")
    fsub = f.add_subparsers(dest="fmu_command", required=True)
    fb = fsub.add_parser("build", help="build the FMU (gcc and fmpy's FMI headers)")
    fb.add_argument("-o", "--output", default="dist/RailContact.fmu",
                    help="the .fmu to write (default dist/RailContact.fmu)")
    fb.add_argument("--profile", action="append", metavar="FILE",
                    help="a profile file to put into the FMU's resources (repeatable)")
    fb.add_argument("--python", metavar="PATH",
                    help="the Python the FMU is to run in: a python executable or a "
                    "venv/prefix folder with railcontact's dependencies, written to "
                    "resources/python.txt (default: this Python); RAILCONTACT_PYTHON "
                    "overrides it where the FMU runs")
    fb.add_argument("--no-warm", action="store_true",
                    help="do not compile the FMU's kernels into the per-user cache now "
                    "(the FMU's first run in an environment then compiles them: 40-100 s)")
    fb.add_argument("--wheelsets", type=int, metavar="N",
                    help="an FMU of N wheelsets (1 to 8), solved in worker processes or on "
                    "threads in each step: every input and output repeated with _1 ... _N "
                    "appended, the parameters once, the Integer parameter wheelsets = N "
                    "(default: the one-wheelset FMU, its variables without a suffix)")
    fb.set_defaults(func=_cmd_fmu_build)
    fc = fsub.add_parser("check", help="which Python an FMU will run in, and whether it can",
                         description="Asks the FMU which Python it chooses here "
                         "(RAILCONTACT_PYTHON, else resources/python.txt, else the Python "
                         "it was built with), starts the FMU's Python code in it as a C host "
                         "would and prints what it uses. Exit 0 when the FMU can start, 1 "
                         "when it cannot (with the message the FMU would log).")
    fc.add_argument("fmu", help="the .fmu file")
    fc.set_defaults(func=_cmd_fmu_check)
    _add_table(sub)
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        code = args.func(args)
        sys.stdout.flush()  # a failing write shows here, not at exit
        return code
    except (RailContactError, SolverError) as exc:
        print(f"railcontact: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # the reader stopped early (| head): nothing more to say
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1
    except OSError as exc:  # a full disk, a file that cannot be written
        where = f": {exc.filename}" if exc.filename else ""
        print(f"railcontact: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
