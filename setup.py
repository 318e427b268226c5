"""The FMU's sources live in ``fmu_src/`` at the top of the repository; the wheel and the
sdist carry them as the package data ``railcontact/_fmu_src/`` (everything else is in
``pyproject.toml``), where :func:`railcontact.fmu.build.fmu_sources` finds them after a
non-editable install."""

from setuptools import find_packages, setup

setup(
    packages=[*find_packages(include=["railcontact", "railcontact.*"]), "railcontact._fmu_src"],
    package_dir={"railcontact._fmu_src": "fmu_src"},
    package_data={"railcontact._fmu_src": ["*.c", "*.h"]},
)
