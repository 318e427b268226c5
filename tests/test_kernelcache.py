"""numba's cache of the package's kernels follows edits of the files they call
(railcontact._kernelcache)."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import railcontact

PROBE = """
import sys
sys.path.insert(0, {root!r})
import numpy as np
import railcontact
assert railcontact.__file__.startswith({root!r}), railcontact.__file__
from railcontact.tangential.convexgs import _squares
a = np.ones((4, 5))
print(_squares(a, a, np.empty_like(a)), sum(_squares.stats.cache_hits.values()))
"""


def test_an_edit_of_a_called_kernels_file_is_compiled_afresh(tmp_path):
    """ConvexGS's ``_squares`` (convexgs.py) calls ``numpy_sum`` (sums.py): numba's own
    key (convexgs.py's source) would load the old sum from the cache after an edit of
    sums.py alone; the package's key compiles it afresh, and a run with nothing edited
    still loads the cache."""
    shutil.copytree(Path(railcontact.__file__).parent, tmp_path / "railcontact",
                    ignore=shutil.ignore_patterns("__pycache__"))
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}

    def run():
        out = subprocess.run([sys.executable, "-c", PROBE.format(root=str(tmp_path))],
                             env=env, capture_output=True, text=True, check=True).stdout
        value, hits = out.split()
        return float(value), int(hits)

    assert run() == (40.0, 0)  # 4 x 5 elements of 1 + 1: compiled and cached
    assert run() == (40.0, 1)  # loaded from the cache
    sums = tmp_path / "railcontact" / "halfspace" / "sums.py"
    text = sums.read_text()
    old = "pairwise_sum(flat, 0, flat.size)"  # numpy_sum's return
    assert text.count(old) == 1
    sums.write_text(text.replace(old, "2.0 * " + old))
    assert run() == (80.0, 0)  # the edited sum, compiled afresh


COPY_PROBE = """
import sys
sys.path.insert(0, {root!r})
import numpy as np
import {name}
from {name} import _kernelcache
from {name}.tangential.convexgs import _squares
assert {name}.__file__.startswith({root!r}), {name}.__file__
a = np.ones((4, 5))
print(_squares(a, a, np.empty_like(a)), sum(_squares.stats.cache_hits.values()),
      sorted(set(_kernelcache.cache_locations().values())))
"""


def _copy(tmp_path: Path, folder: str, name: str, marked: bool = True) -> Path:
    """The package copied to ``tmp_path/folder/name`` (as the FMU packs it: another module
    name, the relative imports unchanged), with the per-user cache marker if ``marked``."""
    from railcontact._kernelcache import USER_CACHE_MARKER

    root = tmp_path / folder
    shutil.copytree(Path(railcontact.__file__).parent, root / name,
                    ignore=shutil.ignore_patterns("__pycache__"))
    if marked:
        (root / name / USER_CACHE_MARKER).write_text("test\n")
    return root


def _probe(root: Path, name: str, **env: str) -> tuple[float, int, list[str]]:
    clean = {k: v for k, v in os.environ.items()
             if not k.startswith("NUMBA_") and k != "RAILCONTACT_CACHE_DIR"}
    out = subprocess.run([sys.executable, "-c", COPY_PROBE.format(root=str(root), name=name)],
                         env={**clean, **env}, capture_output=True, text=True, check=True
                         ).stdout
    value, hits, kinds = out.split(maxsplit=2)
    return float(value), int(hits), eval(kinds)  # noqa: S307 - our own printed list


def test_a_copy_unpacked_elsewhere_loads_the_kernels_of_the_first(tmp_path):
    """The FMU's copy of the package is unpacked into a new folder for each run: marked
    (``_kernelcache_user``), its kernels go to the per-user cache, keyed by module name and
    the sources' content, so a second copy in another folder (its files newer) loads them;
    the cache holds them under ``numba/<name>-<stamp>/<python-numba-numpy>/<subfolder>``,
    nothing goes to the copies' ``__pycache__`` folders."""
    cache = tmp_path / "cache"
    first = _copy(tmp_path, "one", "railcontact_fmu_T")
    second = _copy(tmp_path, "two", "railcontact_fmu_T")
    assert _probe(first, "railcontact_fmu_T", RAILCONTACT_CACHE_DIR=str(cache)) == \
        (40.0, 0, ["user"])  # compiled
    assert _probe(second, "railcontact_fmu_T", RAILCONTACT_CACHE_DIR=str(cache)) == \
        (40.0, 1, ["user"])  # loaded: the first copy's
    (folder,) = (cache / "numba").iterdir()
    assert folder.name.startswith("railcontact_fmu_T-")
    (versions,) = folder.iterdir()
    assert versions.name.startswith(f"py{sys.version_info[0]}{sys.version_info[1]}-numba")
    assert sorted(p.name for p in (versions / "tangential").glob("convexgs._squares-*")) \
        and not list(first.rglob("*.nbi")) and not list(second.rglob("*.nbi"))
    # another module name (the installed package's, another FMU's) has entries of its own:
    # numba's cached code imports its module by name
    other = _copy(tmp_path, "three", "railcontact_fmu_U")
    assert _probe(other, "railcontact_fmu_U", RAILCONTACT_CACHE_DIR=str(cache))[1] == 0
    assert len(list((cache / "numba").iterdir())) == 2


def test_an_unwritable_cache_folder_falls_back_to_numbas_own(tmp_path):
    """A cache folder that cannot be created (here a file is in its place): numba's own
    ``__pycache__`` next to the sources, still keyed on the package's sources; an unmarked
    copy (the installed package) uses numba's own too."""
    blocked = tmp_path / "not-a-folder"
    blocked.write_text("")
    marked = _copy(tmp_path, "one", "railcontact_fmu_T")
    assert _probe(marked, "railcontact_fmu_T", RAILCONTACT_CACHE_DIR=str(blocked)) == \
        (40.0, 0, ["numba"])
    assert _probe(marked, "railcontact_fmu_T", RAILCONTACT_CACHE_DIR=str(blocked)) == \
        (40.0, 1, ["numba"])
    assert list((marked / "railcontact_fmu_T" / "tangential" / "__pycache__").glob("*.nbi"))
    plain = _copy(tmp_path, "two", "railcontact", marked=False)
    cache = tmp_path / "cache"
    assert _probe(plain, "railcontact", RAILCONTACT_CACHE_DIR=str(cache))[2] == ["numba"]
    assert not cache.exists()
