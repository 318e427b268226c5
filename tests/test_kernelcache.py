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
