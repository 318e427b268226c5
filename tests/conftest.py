import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PROFILES = ROOT / "models" / "profiles"
"""The profile files, among them the Manchester benchmark's ``MBench_S1002_v3.prw`` and
``MBench_UIC60_v3.prr`` (provenance and licence: its README.md)."""
CONTACT_REFERENCE = ROOT / "models" / "reference" / "contact"
"""CONTACT's results for its 34 wheel-rail cases, ``wheelrail_dx0.5.csv`` (its README.md)."""
RELIABILITY = ROOT / "tests" / "data" / "reliability"
"""The project's fuzzing reproducers (its README.md)."""


@pytest.fixture
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def default_fmu(tmp_path_factory) -> Path:
    """The default (one-wheelset) FMU, built once per session with a profile file in its
    resources (``tests/test_fmu.py`` runs it; ``tests/test_fmu_wheelsets.py`` compares the
    FMU of several wheelsets with it)."""
    pytest.importorskip("fmpy")
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    from railcontact.fmu import build_fmu

    return build_fmu(tmp_path_factory.mktemp("fmu") / "RailContact.fmu",
                     [PROFILES / "S1002.txt"])
