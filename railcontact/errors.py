"""Exceptions raised by railcontact.

Every error that a user can cause (a bad case file, a bad parameter, a grid that is too
small) is a :class:`RailContactError`, a :class:`ValueError` whose message names the
offending quantity, its unit and the value received. A solve of valid input that does not
reach its goal (a load loop that misses its tolerance) is a :class:`SolverError`, not a
``ValueError``: the input was fine, the answer is not good enough to report as one. A time
step, a table and the FMU turn either into a wheel's status
(:func:`railcontact.status.status_of`).
"""

from __future__ import annotations

import math


class RailContactError(ValueError):
    """Invalid input to a railcontact model; the message says which input and why."""


class CaseError(RailContactError):
    """A case file or case dictionary that cannot be solved as given."""


class SolverError(Exception):
    """A solve of valid input that did not reach its goal; the message says what was
    missed."""


class ConvergenceError(SolverError):
    """An iteration (a load loop) that did not reach its tolerance: the input is valid, the
    answer is not good enough to report as one.

    ``partial`` is the last iterate (e.g. a wheel's patches at the last load pass), None
    when there is none: a caller that reports several results (both wheels) reports it as
    not converged instead of losing the others."""

    def __init__(self, message: str, partial: object = None):
        super().__init__(message)
        self.partial = partial


def check_finite(name: str, value: object, unit: str = "") -> float:
    """Return ``value`` as a float, or raise if it is not a finite real number.

    Parameters
    ----------
    name
        Name of the quantity as the user wrote it (e.g. ``"normal.load"``).
    value
        The value to check.
    unit
        Unit shown in the message (e.g. ``"N"``).
    """
    if type(value) is float and value - value == 0.0:  # the common case, at once
        return value  # (x - x is 0 for a finite float, NaN for inf and NaN)
    x = check_number(name, value, unit)
    if not math.isfinite(x):
        raise RailContactError(f"{name}{f' [{unit}]' if unit else ''} must be finite, "
                               f"got {x}")
    return x


def check_number(name: str, value: object, unit: str = "") -> float:
    """Return ``value`` as a float, or raise if it is not a real number (NaN and the
    infinities pass: for a check that names them in its own words, e.g. a table's range).

    Parameters
    ----------
    name, value, unit
        As :func:`check_finite`.
    """
    if type(value) is float:
        return value
    suffix = f" [{unit}]" if unit else ""
    if isinstance(value, (bool, str)):
        raise RailContactError(f"{name}{suffix} must be a number, got {value!r}")
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):  # e.g. None, a list, an array of several values
        raise RailContactError(f"{name}{suffix} must be a number, got {value!r}") from None
    except OverflowError:  # an int beyond the floats, e.g. 10**400
        raise RailContactError(f"{name}{suffix} must be finite, got an integer of about "
                               f"{_digits(value)} digits") from None


def _digits(value: int) -> int:
    """Decimal digits of a huge int, without forming its decimal text (Python refuses to
    for more than 4300 digits)."""
    return int(abs(value).bit_length() * 0.30103) + 1


def check_positive(name: str, value: object, unit: str = "", allow_zero: bool = False) -> float:
    """Return ``value`` as a float, or raise if it is not finite and positive."""
    x = check_finite(name, value, unit)
    if x > 0.0 or (x == 0.0 and allow_zero):
        return x
    suffix = f" [{unit}]" if unit else ""
    if x < 0 or (x == 0 and not allow_zero):
        bound = "non-negative" if allow_zero else "positive"
        raise RailContactError(f"{name}{suffix} must be {bound}, got {x:g}")
    return x


def check_count(name: str, value: object, minimum: int = 1) -> int:
    """Return ``value`` as an int, or raise if it is not an integer >= ``minimum``."""
    ok = isinstance(value, int) and not isinstance(value, bool) or (
        isinstance(value, float) and math.isfinite(value) and value == int(value))
    if not ok or value < minimum:
        shown = value if not isinstance(value, int) or abs(value) < 10**30 else \
            f"an integer of about {_digits(value)} digits"
        raise RailContactError(f"{name} must be an integer >= {minimum}, got {shown!r}")
    return int(value)
