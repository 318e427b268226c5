"""The benchmark scripts time the package's functions by name: every name they time must
exist in the package (a renamed function would otherwise break the benchmark, which the
suite does not run), and the breakdown must put a wrapped call's time into its stage."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _script(name: str):
    """The module of ``scripts/NAME.py``."""
    spec = importlib.util.spec_from_file_location(name, ROOT / "scripts" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _bench_step():
    return _script("bench_step")


def test_bench_step_times_functions_that_exist():
    bench = _bench_step()
    for stage, targets in bench.STAGES.items():
        present = [name for owner, name in targets if bench._has(owner, name)]
        missing = {name for owner, name in targets if not bench._has(owner, name)}
        assert present, f"stage {stage!r} times nothing"
        assert missing <= bench.LEGACY, f"stage {stage!r}: {sorted(missing)} not found"
        for owner, name in targets:
            if bench._has(owner, name):
                assert callable(bench._get(owner, name)), (stage, name)


def test_breakdown_restores_what_it_wrapped_and_charges_the_stage():
    bench = _bench_step()
    before = {(id(owner), name): bench._get(owner, name)
              for targets in bench.STAGES.values() for owner, name in targets
              if bench._has(owner, name)}
    bd = bench.Breakdown()
    with bd.installed():
        owner, name = bench.STAGES["normal BEM"][0]
        assert bench._get(owner, name) is not before[(id(owner), name)]
        bd.wrap("normal BEM", lambda: sum(range(10_000)))()
    assert bd.seconds["normal BEM"] > 0
    for targets in bench.STAGES.values():
        for owner, name in targets:
            if bench._has(owner, name):
                assert bench._get(owner, name) is before[(id(owner), name)], name


def test_timeline_finds_the_warm_steps_gil_free_calls_and_restores_the_package(capsys):
    """``bench_threads.py --timeline`` on a few steps: a warm step of the hunting run
    releases the GIL in eight calls (each wheel's search, frame, normal and tangential
    stage: the count docs/performance.md quotes), the short kernels keep it, and the
    package's kernels and ``WheelsetContact.solve`` are its own again afterwards."""
    import railcontact as rc
    from railcontact.geometry import kernels

    bench = _script("bench_threads")
    solve, search = rc.WheelsetContact.solve, kernels.search_wheel
    bench.timeline(6)
    out = capsys.readouterr().out
    assert rc.WheelsetContact.solve is solve and kernels.search_wheel is search
    assert "without it in 8 calls" in out, out
    rows = [line.split() for line in out.splitlines() if line[:13].strip()
            .replace(".", "", 1).isdigit()]
    free = [r[1] for r in rows if len(r) == 4 and r[2] == "free"]
    held = {r[1] for r in rows if len(r) == 4 and r[2] == "held"}
    assert free.count("search_wheel") == 2 and free.count("_warm_tangential") == 2, out
    assert held <= {"merge_saddles", "count_runs", "_moment_sums", "_span"}, out
