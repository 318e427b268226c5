"""Values formed from a frozen record once and kept beside it while it lives.

A frozen record (a wheel profile, a track, a wheelset, the settings) is not written to
after its construction; what is formed from it on first use (a profile's samples, the
arrays the kernels read, a placed rail) is held here instead, keyed by the record's
identity (records that hold arrays are not hashable) with a weak reference to it: an
entry is read only for the record it was formed from, does not keep the record alive, and
goes with it.

Thread safety: the records are shared by threads stepping distinct wheelsets. Each entry
is read and added with one dictionary operation each (no iteration), and the first value
stored for a record and key is the one every thread reads (two threads forming the same
value at once form equal values; the later one is dropped).
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from functools import update_wrapper
from typing import Any


class FormedOnce:
    """Values formed from records, one per record, forming function and arguments, held
    while the record lives (:meth:`get`). The records must be weak-referenceable (a dataclass
    without ``slots=True``)."""

    __slots__ = ("_held",)

    def __init__(self) -> None:
        self._held: dict[int, tuple[weakref.ref, dict]] = {}

    def get(self, record: Any, form: Callable[..., Any], *args: Any) -> Any:
        """``form(record, *args)``, formed on the first call for ``record``, ``form`` and
        ``args`` (hashable) and the same object on every later one."""
        held = self._held.get(id(record))
        if held is None or held[0]() is not record:
            held = self._hold(record)
        values, key = held[1], (form, *args) if args else form
        value = values.get(key, _NONE)
        if value is _NONE:
            value = values.setdefault(key, form(record, *args))
        return value

    def __len__(self) -> int:
        """The number of records held (live ones: an entry goes with its record)."""
        return len(self._held)

    def _hold(self, record: Any) -> tuple[weakref.ref, dict]:
        """The entry of ``record``, added (the first added for it is kept)."""
        key, held = id(record), self._held

        def drop(ref: weakref.ref) -> None:  # (the record goes: its entry with it)
            if held.get(key, (None,))[0] is ref:
                held.pop(key, None)

        entry = (weakref.ref(record, drop), {})
        kept = held.setdefault(key, entry)
        if kept[0]() is not record:  # an entry of a record gone whose drop has not run
            held[key] = kept = entry
        return kept


_NONE = object()


def formed_once(method: Callable[[Any], Any]) -> property:
    """A read-only property of a frozen record whose value ``method(record)`` forms on
    the first read, held by a :class:`FormedOnce` (not written into the record)."""
    held = FormedOnce()
    entries = held._held

    def read(record: Any) -> Any:  # (a value formed: read here, one call less a read)
        entry = entries.get(id(record))
        if entry is not None and entry[0]() is record:
            value = entry[1].get(method, _NONE)
            if value is not _NONE:
                return value
        return held.get(record, method)

    update_wrapper(read, method)
    return property(read)
