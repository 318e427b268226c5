"""Executed by the FMU's C shim (``__rc_resources__`` is set): check that this Python is the
one the FMU was built with, make the build environment's packages importable and define
``make_slave``. Everything it needs is in ``resources/python.cfg``."""

import importlib
import os
import site
import sys


def _config(resources):
    cfg = {}
    with open(os.path.join(resources, "python.cfg"), encoding="utf-8") as f:
        for line in f:
            key, sep, value = line.rstrip("\n").partition("=")
            if sep:
                cfg[key] = value
    return cfg


def _prepare(resources):
    cfg = _config(resources)
    here = f"{sys.version_info[0]}.{sys.version_info[1]}"
    if cfg.get("version") != here:
        raise RuntimeError(
            f"this FMU was built with Python {cfg.get('version')} ({cfg.get('executable')}); "
            f"the process runs Python {here} ({sys.executable}). Rebuild it with "
            "`railcontact fmu build` in the Python that will load it.")
    for d in cfg.get("site", "").split(os.pathsep):
        if d and os.path.isdir(d) and d not in sys.path:
            site.addsitedir(d)
    python_dir = os.path.join(resources, "python")
    if python_dir not in sys.path:
        sys.path.insert(0, python_dir)
    try:
        return importlib.import_module(cfg["package"] + "._fmu_slave")
    except ImportError as exc:
        raise RuntimeError(
            f"the FMU's Python code cannot be imported ({exc}). It needs the packages of the "
            f"environment it was built in ({cfg.get('site')}): numpy, scipy, pyfftw, numba. "
            f"Install railcontact's dependencies there, or rebuild the FMU.") from exc


_slave_module = _prepare(__rc_resources__)  # noqa: F821 - set by the shim


def make_slave(resources, instance_name):
    return _slave_module.make_slave(resources, instance_name)
