"""The benchmark scripts time the package's functions by name: every name they time must
exist in the package (a renamed function would otherwise break the benchmark, which the
suite does not run), and the breakdown must put a wrapped call's time into its stage."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _bench_step():
    spec = importlib.util.spec_from_file_location("bench_step",
                                                  ROOT / "scripts" / "bench_step.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


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
