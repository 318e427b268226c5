"""railcontact installed the ordinary way builds an FMU that finds its Python.

An sdist is built from this checkout and ``pip install``-ed (not editable) into a fresh
virtual environment; that installation builds the FMU with ``--python`` naming the
environment, and the project's bare C host (``tests/fmu/host.c``) runs it with an empty
environment. Then the environment is moved away: the FMU must refuse to start with the whole
message (through the FMI logger, in pieces no host truncates) and run again when
``RAILCONTACT_PYTHON`` names the moved environment; ``railcontact fmu check`` must say the
same. No network: the fresh environment sees this interpreter's packages through a ``.pth``
file (its own site-packages come first, so ``railcontact`` is the installed copy).
"""

from __future__ import annotations

import os
import platform
import re
import shutil
import site
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest

import railcontact
from railcontact._kernelcache import cache_root

fmpy = pytest.importorskip("fmpy")

ROOT = Path(__file__).resolve().parents[1]
FMU_SOURCES = (*sorted(p.name for p in (ROOT / "fmu_src").glob("*.[ch]")), "slave.py", "build.py",
               "fmu_bootstrap.py")
LOG = re.compile(r"^\[host\|(\d)\|(\w+)\] ", re.M)

pytestmark = pytest.mark.slow


def _run(cmd, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([str(c) for c in cmd], capture_output=True, text=True,
                          timeout=300, **kw)


@pytest.fixture(scope="module")
def sdist(tmp_path_factory) -> Path:
    """An sdist built from a clean copy of the checkout (a stale ``*.egg-info/SOURCES.txt``
    here would add files the packaging configuration does not)."""
    out = tmp_path_factory.mktemp("sdist")
    src = out / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".git", ".venv", "*.egg-info", "build", "dist", "__pycache__", ".*cache", ".hypothesis",
        "railcontact_demo", "out"))
    r = _run([sys.executable, "-c", "import sys; from setuptools import build_meta as b; "
              "print(b.build_sdist(sys.argv[1]))", out], cwd=src)
    assert r.returncode == 0, r.stderr[-3000:]
    return out / r.stdout.strip().splitlines()[-1]


@pytest.fixture(scope="module")
def installed(sdist, tmp_path_factory) -> Path:
    """A fresh venv with railcontact pip-installed from the sdist (a wheel built by pip)."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    venv = tmp_path_factory.mktemp("install") / "env"
    r = _run([sys.executable, "-m", "venv", "--without-pip", venv])
    assert r.returncode == 0, r.stderr
    purelib = _run([venv / "bin" / "python", "-c",
                    "import sysconfig; print(sysconfig.get_path('purelib'))"]).stdout.strip()
    # this interpreter's packages (numpy, ..., pip, setuptools), after the venv's own
    Path(purelib, "_test_dependencies.pth").write_text(
        "\n".join(site.getsitepackages()) + "\n", encoding="utf-8")
    r = _run([venv / "bin" / "python", "-m", "pip", "install", "--no-deps",
              "--no-build-isolation", "--no-index", "--disable-pip-version-check", "-q",
              sdist], cwd=venv.parent)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-3000:]
    return venv


@pytest.fixture(scope="module")
def host(tmp_path_factory) -> Path:
    exe = tmp_path_factory.mktemp("host") / "host"
    headers = Path(fmpy.__file__).parent / "c-code"
    subprocess.run(["gcc", "-O2", f"-I{headers}", str(ROOT / "tests" / "fmu" / "host.c"),
                    "-o", str(exe), "-ldl", "-lm"], check=True)
    return exe


def run_host(host: Path, unzipped: Path, logging: bool = True,
             **env) -> tuple[int, str, list[tuple[int, str]]]:
    """The C host with an empty environment (plus ``env``), 5 steps; (exit code, stdout and
    the host's own last line, logged messages as (status, text) with the pieces of one
    message joined)."""
    from fmpy.model_description import read_model_description

    md = read_model_description(str(unzipped / "modelDescription.xml"))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    r = _run(["env", "-i", "PATH=/usr/bin:/bin", f"LOGGING={int(logging)}",
              f"VR_LAT={vr['lateral_displacement']}", f"VR_OUT={vr['normal_force_left']}",
              *(f"{k}={v}" for k, v in env.items()),
              host, unzipped / "binaries" / "linux64" / "RailContact.so",
              (unzipped / "resources").as_uri(), md.guid, "5", "1"])
    err, out = r.stderr, r.stdout
    if err.endswith("instantiate failed\n"):  # the host's own words, after the log
        err, out = err[:-len("instantiate failed\n")], out + "instantiate failed\n"
    pieces = []  # (status, category, text) of each logger call
    starts = list(LOG.finditer(err))
    for m, nxt in zip(starts, [*starts[1:], None], strict=True):
        end = nxt.start() if nxt else len(err)
        pieces.append((int(m.group(1)), m.group(2), err[m.end():end].rstrip("\n")))
    assert all(len(t.encode()) <= 1000 for _, _, t in pieces), "a piece beyond 1000 bytes"
    messages = []  # consecutive pieces of one status are one message
    for status, _, text in pieces:
        if messages and messages[-1][0] == status:
            messages[-1] = (status, messages[-1][1] + "\n" + text)
        else:
            messages.append((status, text))
    return r.returncode, out, messages


def test_sdist_carries_the_fmu_sources(sdist):
    with tarfile.open(sdist) as t:
        names = {Path(n).relative_to(Path(n).parts[0]).as_posix() for n in t.getnames()}
    for f in FMU_SOURCES:
        assert f"fmu_src/{f}" in names, f


def test_wheel_install_builds_and_runs_the_fmu_then_a_moved_venv_is_reported(
        installed, host, tmp_path):
    """The non-editable install builds the FMU (its sources are package data), the FMU runs
    in the venv named by --python, a moved venv is a clear error, RAILCONTACT_PYTHON fixes it.
    """
    site_packages = Path(_run([installed / "bin" / "python", "-c",
                               "import sysconfig; print(sysconfig.get_path('purelib'))"]
                              ).stdout.strip())
    (dist_info,) = site_packages.glob("railcontact-*.dist-info")
    record = (dist_info / "RECORD").read_text()
    for f in FMU_SOURCES:  # the wheel pip built from the sdist carries them
        assert f"railcontact/_fmu_src/{f}," in record, f
    assert "__editable__" not in " ".join(os.listdir(site_packages))

    fmu = tmp_path / "RailContact.fmu"
    r = _run([installed / "bin" / "railcontact", "fmu", "build", "-o", fmu, "--python",
              installed], cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    kernel_cache = cache_root()  # where the build (this process's environment) warmed them
    assert "kernels warmed for " in r.stdout and str(kernel_cache) in r.stdout, \
        r.stdout
    with zipfile.ZipFile(fmu) as z:
        assert z.read("resources/python.txt").decode().strip() == str(installed)
        # the FMU's copy of railcontact is the installed one, not this checkout
        copied = z.read("resources/python/railcontact_fmu_RailContact/fmu/build.py")
        z.extractall(tmp_path / "unzipped")
    assert copied == (site_packages / "railcontact" / "fmu" / "build.py").read_bytes()
    unzipped = tmp_path / "unzipped"

    r = _run([installed / "bin" / "railcontact", "fmu", "check", fmu], cwd=tmp_path,
             env={k: v for k, v in os.environ.items() if k != "RAILCONTACT_PYTHON"})
    assert r.returncode == 0, r.stdout + r.stderr
    assert f"Python: {installed}/bin/python3" in r.stdout
    assert f"FMU: railcontact {railcontact.__version__}, built with Python " \
           f"{sys.version_info[0]}.{sys.version_info[1]} ({installed}/bin/python;" in r.stdout
    assert "chosen from resources/python.txt" in r.stdout
    assert re.search(r"numpy [\d.]+ \(needs >=[\d.]+\)", r.stdout)
    assert str(site_packages) in r.stdout and "The FMU will start." in r.stdout

    # isolated from the host's environment: a numpy on PYTHONPATH and one in the user's
    # site-packages that would fail to import, a PYTHONHOME that does not exist
    for d in (tmp_path / "pythonpath", tmp_path / "home" / ".local" / "lib" /
              f"python{sys.version_info[0]}.{sys.version_info[1]}" / "site-packages"):
        (d / "numpy").mkdir(parents=True)
        (d / "numpy" / "__init__.py").write_text("raise ImportError('not this numpy')\n")
    # (the other HOME would move the per-user kernel cache too: it names the one the build
    # warmed, else this start would compile every kernel; tests/test_fmu_startup.py checks
    # that a fresh unpacking loads them)
    code, out, log = run_host(host, unzipped, PYTHONPATH=tmp_path / "pythonpath",
                              HOME=tmp_path / "home", PYTHONHOME="/nonexistent",
                              RAILCONTACT_CACHE_DIR=kernel_cache)
    assert code == 0 and "ok: 1 cycles of 5 steps" in out, log
    info = log[0][1]
    assert "pythonpath" not in info and str(tmp_path / "home") not in info
    assert log[0][0] == 0 and f"({installed}/bin/python3), chosen from resources/python.txt" \
        in info, log
    assert "started by the FMU in this process" in info and str(site_packages) in info

    moved = installed.with_name("moved")
    installed.rename(moved)
    try:
        code, out, log = run_host(host, unzipped)
        assert code == 4 and "instantiate failed" in out
        assert [s for s, _ in log] == [3], log  # one error message, nothing else
        msg = log[0][1]
        assert msg.startswith(f"cannot start the FMU's Python: '{installed}' does not exist")
        assert "chosen from resources/python.txt" in msg
        assert "RAILCONTACT_PYTHON" in msg and "railcontact fmu build --python PATH" in msg
        assert msg.endswith("`railcontact fmu check FILE.fmu` prints what the FMU will use.")

        r = _run([sys.executable, "-m", "railcontact", "fmu", "check", fmu],
                 env={k: v for k, v in os.environ.items() if k != "RAILCONTACT_PYTHON"})
        assert r.returncode == 1 and r.stdout.strip() == msg, r.stdout + r.stderr

        code, out, log = run_host(host, unzipped, logging=False, RAILCONTACT_PYTHON=moved)
        assert code == 0 and "ok: 1 cycles of 5 steps" in out, log
        # without loggingOn: one line, which Python and where from
        assert len(log) == 1 and log[0][0] == 0 and "\n" not in log[0][1], log
        assert f"({moved}/bin/python3), chosen from the environment variable " \
               "RAILCONTACT_PYTHON" in log[0][1]
        r = _run([sys.executable, "-m", "railcontact", "fmu", "check", fmu],
                 env=dict(os.environ, RAILCONTACT_PYTHON=str(moved)))
        assert r.returncode == 0 and f"Python: {moved}/bin/python3" in r.stdout, r.stdout
    finally:
        moved.rename(installed)


@pytest.fixture(scope="module")
def plain_fmu(installed, tmp_path_factory) -> Path:
    """The FMU the installed railcontact builds without --python, unpacked."""
    d = tmp_path_factory.mktemp("plain")
    r = _run([installed / "bin" / "railcontact", "fmu", "build", "-o", d / "RailContact.fmu"],
             cwd=d)
    assert r.returncode == 0, r.stdout + r.stderr
    with zipfile.ZipFile(d / "RailContact.fmu") as z:
        assert "resources/python.txt" not in z.namelist()
        cfg = z.read("resources/python.cfg").decode()
        z.extractall(d / "unzipped")
    assert f"executable={installed}/bin/python\n" in cfg
    return d / "unzipped"


def test_a_long_message_reaches_the_host_whole(plain_fmu, host):
    """A message longer than the 4096 bytes a host's logger may hold arrives complete, in
    pieces: here RAILCONTACT_PYTHON names a 3.4 kB path that does not exist."""
    far = "/nonexistent/" + "/".join(f"{k:02d}" + "d" * 198 for k in range(17))
    code, _, log = run_host(host, plain_fmu, RAILCONTACT_PYTHON=far)
    assert code == 4 and [s for s, _ in log] == [3], log
    msg = log[0][1]
    assert len(msg.encode()) > 4096
    # pieces were cut inside the path: join them without the cuts' line ends
    assert msg.replace("\n", "").count(far) == 2
    assert msg.endswith("`railcontact fmu check FILE.fmu` prints what the FMU will use.")


def test_dependencies_are_checked(plain_fmu, host, tmp_path):
    """A Python whose numba is older than railcontact requires, or that has no numpy at all:
    the C host's instantiate fails naming the package, the version and the requirement;
    ``fmu check`` prints the same; ``fmu build --python`` refuses such a Python."""
    old = tmp_path / "old"
    _run([sys.executable, "-m", "venv", "--without-pip", old]).check_returncode()
    purelib = Path(_run([old / "bin" / "python", "-c",
                         "import sysconfig; print(sysconfig.get_path('purelib'))"]
                        ).stdout.strip())
    (purelib / "numba").mkdir()
    (purelib / "numba" / "__init__.py").write_text('__version__ = "0.50.1"\n')
    (purelib / "_test_dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    code, out, log = run_host(host, plain_fmu, RAILCONTACT_PYTHON=old)
    assert code == 4 and [s for s, _ in log] == [3], log
    msg = log[0][1]
    assert f"numba 0.50.1 ({purelib / 'numba'}) is older than the FMU needs (>=0.58)" in msg
    assert re.search(r"numpy [\d.]+ \(needs >=1\.24\) from ", msg)  # the others are fine
    assert "chosen from the environment variable RAILCONTACT_PYTHON" in msg
    assert "Install railcontact's dependencies in that environment" in msg

    bare = tmp_path / "bare"
    _run([sys.executable, "-m", "venv", "--without-pip", bare]).check_returncode()
    unzipped_fmu = plain_fmu.parent / "RailContact.fmu"
    r = _run([sys.executable, "-m", "railcontact", "fmu", "check", unzipped_fmu],
             env=dict(os.environ, RAILCONTACT_PYTHON=str(bare)))
    assert r.returncode == 1, r.stdout + r.stderr
    assert "numpy (needs >=1.24) cannot be imported: ModuleNotFoundError" in r.stdout
    assert r.stdout.rstrip().endswith("The FMU will NOT start.")

    r = _run([sys.executable, "-m", "railcontact", "fmu", "build", "-o",
              tmp_path / "x.fmu", "--python", bare])
    assert r.returncode == 2 and not (tmp_path / "x.fmu").exists()
    assert "the Python given with --python cannot run the FMU" in r.stderr
    assert "numba (needs >=0.58) cannot be imported" in r.stderr


def test_in_a_python_host_a_broken_choice_is_a_warning(plain_fmu, monkeypatch, capsys):
    """fmpy already runs Python: the FMU runs in it, says so, and warns that the Python
    named for it does not exist (the host's packages suffice here)."""
    from fmpy.fmi2 import FMU2Slave
    from fmpy.model_description import read_model_description

    monkeypatch.setenv("RAILCONTACT_PYTHON", "/nonexistent/env")
    md = read_model_description(str(plain_fmu / "modelDescription.xml"))
    s = FMU2Slave(guid=md.guid, unzipDirectory=str(plain_fmu),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="py")
    s.instantiate(loggingOn=True)
    log = capsys.readouterr().out
    s.freeInstance()
    assert "[WARNING] the FMU's own choice of Python is not usable" in log
    assert "'/nonexistent/env' does not exist" in log
    assert f"railcontact FMU: runs in the host's Python {platform.python_version()} " \
           f"({sys.executable})" in log


def test_fmu_check_of_a_file_that_is_no_fmu(tmp_path, capsys):
    from railcontact.cli import main

    assert main(["fmu", "check", str(tmp_path / "missing.fmu")]) == 2
    assert "missing.fmu not found" in capsys.readouterr().err
    (tmp_path / "text.fmu").write_text("not a zip")
    assert main(["fmu", "check", str(tmp_path / "text.fmu")]) == 2
    assert "is not an FMU (not a zip file)" in capsys.readouterr().err
    with zipfile.ZipFile(tmp_path / "other.fmu", "w") as z:
        z.writestr("modelDescription.xml", "<fmiModelDescription/>")
    assert main(["fmu", "check", str(tmp_path / "other.fmu")]) == 2
    assert "is not a railcontact FMU" in capsys.readouterr().err
