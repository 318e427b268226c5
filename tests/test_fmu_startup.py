"""The FMU's start-up in a Python host (fmpy): fast in a fresh unpacking once its kernels
are cached, and a clear message when its Python is wrong.

fmpy and most hosts unpack an FMU into a new folder for every simulation. The FMU's copy of
railcontact keeps its numba kernels in the per-user cache (``RAILCONTACT_CACHE_DIR``, a
temporary folder here), which ``railcontact fmu build`` fills; each run below is a new
Python process, as a new simulation is.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest

pytest.importorskip("fmpy")

from railcontact.fmu import build_fmu  # noqa: E402

START_LIMIT = 20.0
"""Seconds allowed for a fresh unpacking's instantiate + initialisation + first step with
the kernels cached (measured 1.5-2 s, scripts/bench_fmu_startup.py; compiling them takes
40-100 s): generous, for a busy machine."""

RUN = r"""
import json, os, sys, time
from fmpy.fmi2 import FMU2Slave
from fmpy.model_description import read_model_description
d = sys.argv[1]
md = read_model_description(d + "/modelDescription.xml")
vr = {v.name: v.valueReference for v in md.modelVariables}
t0 = time.perf_counter()
s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
              instanceName="startup")
s.instantiate()
s.setupExperiment(startTime=0.0)
s.enterInitializationMode()
s.exitInitializationMode()
s.setReal([vr["lateral_displacement"], vr["xi_left"], vr["phi_right"]], [1e-3, 1e-3, -0.3])
s.doStep(0.0, 1e-3)
seconds = time.perf_counter() - t0
force = s.getReal([vr["normal_force_left"]])[0]
kc = [m for m in sys.modules if m.startswith("railcontact_fmu_") and m.endswith("_kernelcache")]
compiled, loaded = sys.modules[kc[0]].kernel_counts()
s.terminate()
s.freeInstance()
print(json.dumps({"seconds": seconds, "compiled": compiled, "loaded": loaded,
                  "force": force}))
"""

BLOCKED_HOST = r"""
import importlib.abc, sys

class Missing(importlib.abc.MetaPathFinder):
    # a host environment without railcontact's compiled dependencies
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in ("numba", "scipy", "pyfftw"):
            raise ModuleNotFoundError(f"No module named {name!r}")
        return None

sys.meta_path.insert(0, Missing())
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.model_description import read_model_description
d = sys.argv[1]
md = read_model_description(d + "/modelDescription.xml")
s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
              instanceName="blocked")
try:
    s.instantiate()
except Exception as exc:
    print("instantiate failed:", type(exc).__name__)
"""


@pytest.fixture(scope="module")
def cache(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("kernel-cache")


@pytest.fixture(scope="module")
def fmu(tmp_path_factory, cache) -> tuple[Path, list[str]]:
    """The FMU, built with its kernels warmed into ``cache``; (path, the build's lines)."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    lines: list[str] = []
    old = os.environ.get("RAILCONTACT_CACHE_DIR")
    os.environ["RAILCONTACT_CACHE_DIR"] = str(cache)
    try:
        path = build_fmu(tmp_path_factory.mktemp("startup") / "RailContact.fmu",
                         log=lines.append)
    finally:
        if old is None:
            os.environ.pop("RAILCONTACT_CACHE_DIR")
        else:
            os.environ["RAILCONTACT_CACHE_DIR"] = old
    return path, lines


def _unpack(fmu: Path, folder: Path) -> Path:
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return folder


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if k not in ("RAILCONTACT_PYTHON", "RAILCONTACT_CACHE_DIR")
           and not k.startswith("NUMBA_")}
    return {**env, **extra}


def _start(unpacked: Path, cache: Path) -> dict:
    r = subprocess.run([sys.executable, "-c", RUN, str(unpacked)], capture_output=True,
                       text=True, env=_env(RAILCONTACT_CACHE_DIR=str(cache)), timeout=900)
    assert r.returncode == 0, r.stdout + r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


def test_a_fresh_unpacking_starts_without_compiling(fmu, cache, tmp_path):
    """``fmu build`` compiled the kernels into the cache; two fresh unpackings of the same
    FMU, each in a new process: neither compiles a kernel, and the second one's
    instantiate + initialisation + first step stays far below the 40-100 s that compiling
    takes."""
    path, lines = fmu
    assert any(line.startswith("kernels warmed for ") and str(cache) in line
               for line in lines), lines
    with zipfile.ZipFile(path) as z:
        assert not [n for n in z.namelist() if "__pycache__" in n or n.endswith(".nbi")]
    first = _start(_unpack(path, tmp_path / "one"), cache)
    assert first["compiled"] == 0 and first["loaded"] > 20, first
    t0 = time.perf_counter()
    second = _start(_unpack(path, tmp_path / "two"), cache)
    wall = time.perf_counter() - t0
    assert second["compiled"] == 0, second
    assert second["force"] == first["force"] > 0
    assert second["seconds"] < START_LIMIT, second
    print(f"second unpacking: instantiate + initialisation + first step "
          f"{second['seconds']:.2f} s ({wall:.2f} s with the process's start)")


def test_a_second_build_finds_the_kernels_cached(fmu, cache, tmp_path, monkeypatch):
    """Building again in the same environment compiles nothing: the build's warm-up loads
    every kernel from the cache."""
    lines: list[str] = []
    monkeypatch.setenv("RAILCONTACT_CACHE_DIR", str(cache))
    build_fmu(tmp_path / "again.fmu", log=lines.append)
    assert any("already in the cache" in line for line in lines), lines


def test_a_bad_python_is_named_in_a_python_host(fmu, tmp_path):
    """fmpy runs the FMU in its own Python; when the FMU's own choice of Python does not
    exist (RAILCONTACT_PYTHON names a missing environment) and the host's packages lack
    numba, scipy and pyfftw, the error leads with the missing Python, not with the host's
    missing packages."""
    unpacked = _unpack(fmu[0], tmp_path / "unpacked")
    r = subprocess.run([sys.executable, "-c", BLOCKED_HOST, str(unpacked)],
                       capture_output=True, text=True, timeout=300,
                       env=_env(RAILCONTACT_PYTHON="/nonexistent/env"))
    out = r.stdout
    assert "instantiate failed" in out, out + r.stderr
    error = out[out.index("[ERROR]"):]
    first = error.splitlines()[0]
    assert first.startswith("[ERROR] the railcontact FMU cannot start in this Python host: "
                            "the FMU's own choice of Python is not usable"), first
    assert error.index("'/nonexistent/env' does not exist") \
        < error.index("numba (needs >=0.58) cannot be imported")
    assert "chosen from the environment variable RAILCONTACT_PYTHON" in error
    assert "runs in the host's Python" in error and "[WARNING]" not in out


def test_fmu_check_tells_whether_the_kernels_are_compiled(fmu, cache, tmp_path, monkeypatch):
    """``railcontact fmu check`` says where the kernels are cached, or that the first step
    will compile them."""
    from railcontact.fmu import check_fmu

    monkeypatch.delenv("RAILCONTACT_PYTHON", raising=False)
    monkeypatch.setenv("RAILCONTACT_CACHE_DIR", str(cache))
    report = check_fmu(fmu[0])
    assert report.ok, report.text
    assert "  kernels: " in report.text and f"compiled in {cache}" in report.text
    monkeypatch.setenv("RAILCONTACT_CACHE_DIR", str(tmp_path / "empty"))
    assert "kernels: none compiled yet in " in check_fmu(fmu[0]).text
