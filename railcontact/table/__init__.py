"""Contact tables: exact BEM solves over a grid of wheelset states, built on Dask and
stored in Zarr (``railcontact table build``), and interpolated in a time loop
(:class:`ContactTable`).

Modules: ``spec`` (the ``[table]`` axes), ``solve`` (a batch of points, warm-started along
the fastest axis), ``store`` (the Zarr layout, resume, completeness), ``build`` (Dask),
``interpolate`` (:class:`ContactTable`), ``show`` (summary, plots), ``step`` (a wheelset
step from a table, as the FMU's ``contact_model = table``), ``check`` (the interpolation
error against the exact solver at random states), ``refine`` (nodes added where it errs or
the contact jumps), ``export`` (netCDF, CSV); ``geometry`` and ``geometry_table`` (geometry
tables, ``[table] kind = "geometry"``: :class:`GeometryTable`); ``creepspec``, ``creep``
and ``creepread`` (normalised creep tables, ``[table] kind = "creep"``: spec, build,
:class:`CreepTable`), ``kinds`` (a spec of any kind). Building needs the ``[tables]``
extra (dask[distributed], xarray, zarr, tqdm).
"""

from .creepread import CreepForces, CreepTable
from .geometry_table import GeometryTable
from .interpolate import ContactTable, Interpolated
from .kinds import load_any_spec
from .spec import AXES, TableSpec, load_spec, parse_spec
from .step import TableContact

__all__ = ["AXES", "ContactTable", "CreepForces", "CreepTable", "GeometryTable", "Interpolated",
           "TableContact", "TableSpec", "load_any_spec", "load_spec", "parse_spec"]
