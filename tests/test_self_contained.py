"""The repository is self-contained: no file points at data outside it, and the data the
tests and scripts use is in it, unchanged.

The project once read its reference data from a folder beside the checkout; a fresh clone
then failed at collection and skipped ~45 tests. Every file of the repository (the files
git knows of, tracked or not ignored; without git, a walk that leaves out environments,
caches and build output) except ``CHANGELOG.md`` (history may name the old places) must
not name that folder: neither its relative path nor its sub-folders as path components,
nor a path built from its name in Python.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
from pathlib import Path

from conftest import CONTACT_REFERENCE, PROFILES, RELIABILITY, ROOT

_NAME = "sha" + "red"  # spelt in two pieces so that this file does not match itself
FORBIDDEN = [
    re.compile(r"\.\./" + _NAME + r"(?![\w-])"),  # the folder beside the checkout
    re.compile(r"(?<![\w.-])" + _NAME + r"[/\\](?:reference|profiles|reliability)\b"),
    re.compile(r"[\"']" + _NAME + r"[\"']\s*/"),  # parents[...] / "<name>" / ...
    re.compile(r"/\s*[\"']" + _NAME + r"[\"']"),
]
EXEMPT = {"CHANGELOG.md"}
SKIP_DIRS = {".git", ".venv", "venv", "build", "dist", "_build", "__pycache__",
             ".pytest_cache", ".ruff_cache", ".mypy_cache", ".hypothesis",
             ".import_linter_cache", "out", "railcontact_demo", "node_modules"}

SHA256 = {  # the files as their sources have them, byte for byte
    PROFILES / "MBench_S1002_v3.prw":
        "008c1aa6293ffc8a5141e78a663b21e39ba8daccd4774029f79cfde0c45e0d1d",
    PROFILES / "MBench_UIC60_v3.prr":
        "5a431b69bd7ae8418b641412da6fdf1d852f4d9865080875cf3f0f3e874e3588",
    CONTACT_REFERENCE / "wheelrail_dx0.5.csv":
        "d88f19eb00002a1d4c0a6cfecefb2cc1983dff9201a5288e6c760c7075460484",
    PROFILES / "MBench_S1002_coars.prw":
        "0b8764061f845882fe839c2048e88458a627aa187857cc872b047ff218f1ca04",
    PROFILES / "r300_wide.prr":
        "21a256c48c52ecd1cb1a531b56120c6a730135ed0e2afaea1b6a327555c3d13b",
    PROFILES / "worn_high_mileage.prw":
        "2fb3aad3cdbc044efe9aa21c94530116ed7343f71659dd5a4b8c8a817aa0020d",
    CONTACT_REFERENCE / "track" / "track_public.csv":
        "74a65ada6eaec33c826ce35e759b79f43a5f44c7d58f65dfac2fca8c45a338b1",
    **{CONTACT_REFERENCE / "track" / "inp" / name: digest for name, digest in (
        ("trk_A_left.inp", "ede7ca1c6678077cfd5cfe99126357c94e6be984f70d73956b46522d618200f3"),
        ("trk_A_right.inp", "981436676e7202c78feed287d541a23f2baefa98f3a8336e85c7152244d797c6"),
        ("trk_B_left.inp", "69d7077f50b98e7df2a00ac3877186d1e55d614eeae55769e5e6c8c9378ae0e4"),
        ("trk_B_right.inp", "f7d1c96f246e28efd30fa0dd9d807474f2d62439a9b1628338ee506bf072759d"),
        ("trk_C_C1_left_r300_wide.inp",
         "c2b583952000a7a02c2e85e5d8daaef68ff18bd03125d0128cfd7f2964089ed5"),
        ("trk_C_C1_right_UIC60_v3.inp",
         "55860d536a8a2b0950916aca67ee81382e7061fa26c8c3f36492dafe8961d8fb"),
        ("trk_C_C2_left_UIC60_v3.inp",
         "57f6339e67116ea04c53ff69c2be2e031dc87563a66e3e7b5e4531824154ca19"),
        ("trk_C_C2_right_r300_wide.inp",
         "45d1b3e7593d86623368032bc92c105c7bd349db0cd8712c6916f0b81f13aab2"),
    )},
    CONTACT_REFERENCE / "varfric" / "mbench_a22_varfric.inp":
        "6f2e8f3f8653ccdf3e970b770a669a171c17b7ecd4a3bc3f83bcc8f7b729b7f2",
    CONTACT_REFERENCE / "varfric" / "mbench_a22_varfric.ref_out":
        "d281079cc208bf069f3e884be66b16f41ddf0314a3eacf0235cf891259d08067",
}


def _git_files() -> list[str] | None:
    """The repository's files as git knows them (tracked, or new and not ignored), or None
    outside a git checkout."""
    if not (ROOT / ".git").exists() or shutil.which("git") is None:
        return None
    r = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                       cwd=ROOT, capture_output=True)
    if r.returncode != 0:
        return None
    return sorted({n for n in r.stdout.decode("utf-8", "surrogateescape").split("\0") if n})


def _walked_files() -> list[str]:
    out = []
    for folder, dirs, files in os.walk(ROOT):
        dirs[:] = [d for d in dirs if d not in SKIP_DIRS and not d.endswith(".egg-info")]
        out += [os.path.relpath(os.path.join(folder, f), ROOT) for f in files]
    return sorted(out)


def repository_files() -> list[str]:
    """Relative paths (with ``/``) of the repository's files."""
    names = _git_files()
    if names is None:
        names = _walked_files()
    return [n.replace(os.sep, "/") for n in names]


def offending_lines(root: Path, names: list[str]) -> list[str]:
    """``path:line: text`` of every line that names the folder beside the checkout."""
    found = []
    for name in names:
        path = root / name
        if name in EXEMPT or path.is_symlink() or not path.is_file():
            continue
        text = path.read_bytes().decode("utf-8", "replace")
        for number, line in enumerate(text.splitlines(), 1):
            if any(p.search(line) for p in FORBIDDEN):
                found.append(f"{name}:{number}: {line.strip()[:160]}")
    return found


def test_the_patterns_catch_what_they_should(tmp_path):
    bad = [f"see ../{_NAME}/reference/algorithms.md", f"`../{_NAME}/`",
           f"data in /work/{_NAME}/profiles", f'HERE.parents[1] / "{_NAME}" / "profiles"',
           f"SHARED = ROOT.parent / '{_NAME}'", f"{_NAME}/reliability/random_steps_1.jsonl"]
    good = [f"a {_NAME} library", f"{_NAME}_memory", f"-{_NAME} -fPIC",
            "models/reference/contact", f"a {_NAME} lattice/grid", f"un{_NAME}/profiles"]
    (tmp_path / "a.txt").write_text("\n".join(bad + good) + "\n")
    (tmp_path / "CHANGELOG.md").write_text(bad[0] + "\n")
    found = offending_lines(tmp_path, ["a.txt", "CHANGELOG.md"])
    assert [int(f.split(":")[1]) for f in found] == list(range(1, len(bad) + 1)), found


def test_no_file_points_outside_the_repository():
    names = repository_files()
    assert "tests/test_self_contained.py" in names and "pyproject.toml" in names
    found = offending_lines(ROOT, names)
    assert not found, ("these lines name data outside the repository (use models/ and "
                       "tests/data/ instead):\n" + "\n".join(found))


def test_the_data_is_there_unchanged():
    for path, digest in SHA256.items():
        assert hashlib.sha256(path.read_bytes()).hexdigest() == digest, path
    for name in ("MBench_S1002_v3.prw", "MBench_UIC60_v3.prr"):  # F16 names these copies
        assert ((RELIABILITY.parent / "profiles" / name).read_bytes()
                == (PROFILES / name).read_bytes()), name
