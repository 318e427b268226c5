"""A contact table built in the test's own process (no cluster), as the build does it:
each batch solved by the build's ``solve_batch`` and written by its ``Store``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from railcontact.table.solve import solve_batch
from railcontact.table.store import Store, create_store


def build_here(spec, out: Path) -> Path:
    """The table of ``spec`` (a :class:`~railcontact.table.spec.TableSpec`) into the store
    ``out``, in this process; returns ``out``."""
    create_store(out, spec)
    store = Store(out, spec)
    for ix in np.ndindex(*spec.batch_shape):
        values = [{n: float(spec.axes[n][k]) for n, k in zip(spec.names, p, strict=True)}
                  for p in spec.batch_points(ix)]
        solve = getattr(spec, "solver", solve_batch)  # (another kind of table's)
        store.write_batches([(ix, solve(spec.case, spec.sides, values), [])])
    store.finish(True)
    return out
