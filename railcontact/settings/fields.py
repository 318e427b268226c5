"""How a setting is declared: default, unit, description and the rule it must obey, in one
place, next to the field it belongs to.

A settings record is a frozen dataclass whose fields are declared with :func:`setting`;
:class:`Record` validates and normalises every field once, in ``__post_init__`` (a list
becomes a tuple, an integer-valued float an int, a number a float), so that the solvers
receive checked, typed values and never a raw dictionary. The same declarations produce the
records' docstrings and the settings reference (:mod:`railcontact.settings.reference`).
"""

from __future__ import annotations

import difflib
import inspect
from collections.abc import Iterable, Mapping
from dataclasses import MISSING, dataclass, field, fields, replace
from typing import Any, ClassVar

from ..errors import CaseError, RailContactError, check_count, check_finite
from .friction import FrictionTable


@dataclass(frozen=True)
class Spec:
    """The rule, unit and description of one setting.

    Attributes
    ----------
    kind
        ``"float"``, ``"int"``, ``"bool"``, ``"str"``, ``"str?"`` (a string that may be
        empty: not set), ``"choice"``, ``"ints2"`` (a pair of
        counts), ``"range"`` ([min, max], increasing), ``"floats2"`` (two numbers: a vector in a
        plane, e.g. [y, z]), ``"floats3"`` (three numbers),
        ``"floats12"`` (one number, or one per body), ``"float|choice"`` (a number or one
        of ``choices``) or ``"float|friction"`` (a number, or a friction table:
        :class:`~railcontact.settings.friction.FrictionTable`).
    unit
        SI unit, ``"-"`` for dimensionless numbers, ``""`` for words.
    doc
        One line for the reference.
    minimum, maximum
        Bounds of a number (or of each element), None for none.
    open_min, open_max
        Whether the bound itself is excluded.
    choices
        The allowed words of a ``"choice"``.
    required
        A case file must give it (the default is then only the time-step/FMU default).
    case
        Whether it is a key of a case file (False: set by the code or the time step only).
    """

    kind: str
    unit: str = ""
    doc: str = ""
    minimum: float | None = None
    maximum: float | None = None
    open_min: bool = False
    open_max: bool = False
    choices: tuple[str, ...] = ()
    required: bool = False
    case: bool = True

    def admits(self, x: float) -> bool:
        """Whether the number ``x`` lies within the bounds (each element of a list)."""
        lo, hi = self.minimum, self.maximum
        if lo is not None and (x < lo or (self.open_min and x == lo)):
            return False
        return not (hi is not None and (x > hi or (self.open_max and x == hi)))

    def bounds_text(self) -> str:
        """The allowed values in words, for messages and the reference."""
        if self.kind == "choice":
            return "one of " + ", ".join(map(repr, self.choices))
        if self.kind == "float|choice":
            return "one of " + ", ".join(map(repr, self.choices)) + ", or a number"
        if self.kind == "float|friction":
            return (Spec("float", minimum=self.minimum, maximum=self.maximum,
                         open_min=self.open_min, open_max=self.open_max).bounds_text()
                    + ", or a table {angle = [...], mu = [...]} or {rail_y = [...], mu = "
                    "[...]} (docs/case-files.md)")
        parts = []
        if self.minimum is not None:
            parts.append(f"{'>' if self.open_min else '>='} {self.minimum:g}")
        if self.maximum is not None:
            parts.append(f"{'<' if self.open_max else '<='} {self.maximum:g}")
        return " and ".join(parts)


def setting(default: Any = MISSING, kind: str = "float", unit: str = "", doc: str = "",
            **rule: Any) -> Any:
    """A dataclass field carrying its :class:`Spec` (keywords as in :class:`Spec`)."""
    spec = Spec(kind, unit, doc, **rule)
    return field(default=default, metadata={"spec": spec})


def inherit(record: type, key: str, default: Any = MISSING, **rule: Any) -> Any:
    """A field declared as ``record.key`` is (kind, unit, meaning and rule), with its own
    default where given and its rule changed by the keywords of ``rule``: one declaration
    of a setting that two records share."""
    f = next(f for f in fields(record) if f.name == key)
    spec = replace(spec_of(f), required=False, case=True, **rule)
    return field(default=default_of(f) if default is MISSING else default,
                 metadata={"spec": spec})


def spec_of(f) -> Spec:
    return f.metadata["spec"]


class Record:
    """Base of the settings records: validation from the field specs, docstrings, dicts.

    Subclasses are frozen dataclasses; ``TABLE`` is the case-file table (``""`` for
    records that are not one), ``ERROR`` the exception raised for a bad value.
    """

    TABLE: ClassVar[str] = ""
    ERROR: ClassVar[type[RailContactError]] = CaseError

    def __post_init__(self) -> None:
        problems = []
        for f in fields(self):  # type: ignore[arg-type]
            value = getattr(self, f.name)
            if value is None and f.default is None and not spec_of(f).required:
                continue
            try:
                object.__setattr__(self, f.name, self._validate(f.name, spec_of(f), value))
            except RailContactError as exc:
                problems.append(str(exc))
        if problems:  # every bad field at once
            raise self.ERROR("; ".join(problems))

    @classmethod
    def _where(cls, key: str) -> str:
        return f"[{cls.TABLE}] {key}" if cls.TABLE else key

    @classmethod
    def _fail(cls, message: str) -> None:
        raise cls.ERROR(message)

    @classmethod
    def check_value(cls, key: str, value: Any, where: str | None = None) -> Any:
        """``value`` checked and normalised as field ``key`` (``where`` names it in a
        message; default ``[table] key``)."""
        f = next(f for f in fields(cls) if f.name == key)  # type: ignore[arg-type]
        return cls._validate(key, spec_of(f), value, where)

    @classmethod
    def check_item(cls, key: str, value: Any, where: str) -> float:
        """One number ``value`` of the sequence field ``key`` (e.g. one creepage of
        ``creepage``) checked against the field's bounds, named ``where`` in a message."""
        f = next(f for f in fields(cls) if f.name == key)  # type: ignore[arg-type]
        return cls._number(where, "", spec_of(f), value)

    @classmethod
    def _validate(cls, key: str, spec: Spec, value: Any, where: str | None = None) -> Any:
        where = where or cls._where(key)
        unit = spec.unit if spec.unit != "-" else ""
        kind = spec.kind
        if kind == "float|choice":
            kind = "choice" if isinstance(value, str) else "float"
        if kind == "float|friction":
            if isinstance(value, FrictionTable):
                return value
            if isinstance(value, Mapping):
                try:
                    return FrictionTable.from_mapping(where, value)
                except RailContactError as exc:
                    cls._fail(str(exc))
            kind = "float"
        if kind == "choice":
            if value not in spec.choices:
                cls._fail(f"{where} must be {spec.bounds_text()}, got {value!r}")
            return value
        if kind == "str?":
            if not isinstance(value, str):
                cls._fail(f"{where} must be a string, got {value!r}")
            return value
        if kind == "str":
            if not isinstance(value, str) or not value:
                cls._fail(f"{where} must be a non-empty string, got {value!r}")
            return value
        if kind == "bool":
            if not isinstance(value, bool):
                cls._fail(f"{where} must be true or false, got {value!r}")
            return value
        if kind == "float":
            return cls._number(where, unit, spec, value)
        if kind == "int":
            return cls._integer(where, spec, value)
        if kind == "ints2":
            items = cls._sequence(where, value, 2, "[nx, ny]")
            return tuple(cls._integer(f"{where}[{i}]", spec, v) for i, v in enumerate(items))
        if kind == "floats2":
            items = cls._sequence(where, value, 2, f"of two numbers ({spec.unit})")
            return tuple(cls._number(f"{where}[{i}]", unit, spec, v)
                         for i, v in enumerate(items))
        if kind == "floats3":
            items = cls._sequence(where, value, 3, f"[xi, eta, phi] ({spec.unit})")
            return tuple(cls._number(f"{where}[{i}]", "", spec, v)
                         for i, v in enumerate(items))  # no unit: they differ
        if kind == "floats12":
            items = list(value) if isinstance(value, (list, tuple)) else [value]
            if len(items) not in (1, 2):
                cls._fail(f"{where} must be one value or two (body 1, body 2)")
            names = [where] if len(items) == 1 else [f"{where}[{i}]" for i in range(2)]
            return tuple(cls._number(n, unit, spec, v) for n, v in zip(names, items, strict=True))
        if kind == "range":
            items = cls._sequence(where, value, 2, "[min, max] in m")
            lo, hi = (cls._number(f"{where}[{i}]", unit, spec, v) for i, v in enumerate(items))
            if not hi > lo:
                cls._fail(f"{where} must be increasing, got {list(items)!r}")
            return (lo, hi)
        raise TypeError(f"unknown setting kind {spec.kind!r}")  # pragma: no cover

    @classmethod
    def _sequence(cls, where: str, value: Any, n: int, shape: str) -> list:
        if not isinstance(value, (list, tuple)) or len(value) != n:
            cls._fail(f"{where} must be a list {shape}, got {value!r}")
        return list(value)

    @classmethod
    def _number(cls, where: str, unit: str, spec: Spec, value: Any) -> float:
        try:
            x = check_finite(where, value, unit)
        except RailContactError as exc:
            cls._fail(str(exc))
        unit = f" [{unit}]" if unit else ""
        if not spec.admits(x):
            lo, hi = spec.minimum, spec.maximum
            word = ("positive" if spec.open_min else "non-negative") \
                if lo == 0 and hi is None else spec.bounds_text()
            hint = ""
            if spec.unit == "m" and spec.admits(x / 1000.0):
                hint = (f"; {x:g} looks like millimetres: {x:g} mm is {x / 1000.0:g} m "
                        "(lengths are in metres)")
            got = f"{x:g}"
            if any(b is not None and got == f"{b:g}" for b in (lo, hi)):
                got = repr(x)  # (%g would round it onto the bound it passes)
            cls._fail(f"{where}{unit} must be {word}, got {got}{hint}")
        return x

    @classmethod
    def _integer(cls, where: str, spec: Spec, value: Any) -> int:
        try:
            value = check_count(where, value, int(spec.minimum or 0))
        except RailContactError as exc:
            cls._fail(str(exc))
        if spec.maximum is not None and value > spec.maximum:
            cls._fail(f"{where} must be an integer <= {spec.maximum:g}, got {value!r}")
        return int(value)

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]):
        """The record from a table of a case file (or any mapping of its keys).

        Unknown keys and missing required keys are errors naming the table and key.
        """
        where = f"[{cls.TABLE}]" if cls.TABLE else cls.__name__
        if not isinstance(values, Mapping):
            raise cls.ERROR(f"{where} must be a table, got {values!r}")
        known = {f.name for f in fields(cls) if spec_of(f).case}  # type: ignore[arg-type]
        bad = set(values) - known
        if bad:
            raise cls.ERROR(f"unknown key(s) {sorted(bad)} in {where}{did_you_mean(bad, known)}"
                            f"; known: {sorted(known)}")
        problems = []
        for f in fields(cls):  # type: ignore[arg-type]
            s = spec_of(f)
            if s.required and f.name not in values:
                unit = f" ({s.doc} [{s.unit}])" if s.unit not in ("", "-") else f" ({s.doc})"
                problems.append(f"missing {where} {f.name}{unit}")
        if problems:  # with every bad value given beside them (all problems at once)
            for f in fields(cls):  # type: ignore[arg-type]
                if f.name in values:
                    try:
                        cls._validate(f.name, spec_of(f), values[f.name])
                    except RailContactError as exc:
                        problems.append(str(exc))
            raise cls.ERROR("; ".join(problems))
        return cls(**values)

    def to_dict(self) -> dict[str, Any]:
        """The case-file keys and their values (tuples as lists), None values left out."""
        out = {}
        for f in fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            if spec_of(f).case and v is not None:
                out[f.name] = (list(v) if isinstance(v, tuple) else
                               v.to_dict() if isinstance(v, FrictionTable) else v)
        return out


def close_keys(bad: Iterable[str], known: Iterable[str]) -> dict[str, str]:
    """The known key each unknown one of ``bad`` is most likely a misspelling of (those
    that are close to one, :func:`difflib.get_close_matches`)."""
    known = sorted(known)
    out = {}
    for key in sorted(bad):
        match = difflib.get_close_matches(str(key), known, n=1, cutoff=0.75)
        if match:
            out[key] = match[0]
    return out


def did_you_mean(bad: Iterable[str], known: Iterable[str]) -> str:
    """" (did you mean 'load'?)" for the unknown keys ``bad`` close to a ``known`` one, else
    ""."""
    close = close_keys(bad, known)
    if not close:
        return ""
    return " (did you mean " + ", ".join(f"{v!r} for {k!r}" if len(close) > 1 else repr(v)
                                         for k, v in close.items()) + "?)"


def default_of(f) -> Any:
    """A field's default value (None when it has none)."""
    return None if f.default is MISSING else f.default


def document(cls):
    """Class decorator: append an ``Attributes`` section, from the field specs, to the
    docstring of a settings record (so that ``help()`` shows every unit and default)."""
    lines = [inspect.cleandoc(cls.__doc__ or ""), "", "Attributes", "----------"]
    for f in fields(cls):
        s = spec_of(f)
        unit = f" [{s.unit}]" if s.unit else ""
        lines.append(f"{f.name}{unit}")
        default = default_of(f)
        rule = s.bounds_text()
        extra = ", ".join(x for x in (f"default {default!r}" if not s.required else "required",
                                      rule) if x)
        lines.append(f"    {s.doc} ({extra}).")
    cls.__doc__ = "\n".join(lines) + "\n"
    return cls
