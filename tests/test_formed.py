"""Frozen records are not written to after their construction: what is formed from them
on first use is held beside them (railcontact.formed), once per record, by a cache that
neither keeps a record alive nor hands two threads different values."""

from __future__ import annotations

import ast
import gc
import math
import threading
import weakref
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import railcontact
from railcontact.formed import FormedOnce, formed_once
from railcontact.geometry import search
from railcontact.geometry.profiles import builtin_profile
from railcontact.geometry.track import Track, Wheelset

PACKAGE = Path(railcontact.__file__).parent


@dataclass(frozen=True)
class _Record:
    values: np.ndarray  # (an array: the record is not hashable)

    @formed_once
    def total(self) -> float:
        """The sum of the values."""
        _Record.reads += 1
        return float(self.values.sum())


_Record.reads = 0


def _writes_outside_construction(tree: ast.AST) -> list[int]:
    """Lines that write into an object bypassing its ``__setattr__`` outside a
    ``__post_init__``: ``object.__setattr__``, ``object.__new__``, a write to or
    ``setdefault`` on a ``__dict__``, ``functools.cached_property`` (which writes the
    instance's ``__dict__``)."""
    lines = []

    def visit(node: ast.AST, in_post_init: bool) -> None:
        if isinstance(node, ast.FunctionDef):
            in_post_init = node.name == "__post_init__"
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
            if (node.value.id == "object" and node.attr in ("__setattr__", "__new__")
                    and not (in_post_init and node.attr == "__setattr__")):
                lines.append(node.lineno)
        if isinstance(node, ast.Attribute) and node.attr == "setdefault" and (
                isinstance(node.value, ast.Attribute) and node.value.attr == "__dict__"):
            lines.append(node.lineno)
        if isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Store) and (
                isinstance(node.value, ast.Attribute) and node.value.attr == "__dict__"):
            lines.append(node.lineno)
        if isinstance(node, (ast.Name, ast.Attribute)) and (
                getattr(node, "id", None) == "cached_property"
                or getattr(node, "attr", None) == "cached_property"):
            lines.append(node.lineno)
        for child in ast.iter_child_nodes(node):
            visit(child, in_post_init)

    visit(tree, False)
    return lines


def test_the_scan_finds_each_kind_of_write():
    source = '''
class A:
    def __post_init__(self):
        object.__setattr__(self, "a", 1)
    def later(self):
        object.__setattr__(self, "b", 1)
        self.__dict__["c"] = 1
        self.__dict__.setdefault("d", {})
        return object.__new__(A)
    @cached_property
    def e(self):
        return 1
'''
    assert _writes_outside_construction(ast.parse(source)) == [6, 7, 8, 9, 10]


def test_no_record_is_written_outside_its_construction():
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        lines = _writes_outside_construction(ast.parse(path.read_text(), str(path)))
        if lines:
            found[str(path.relative_to(PACKAGE))] = lines
    assert found == {}


def test_a_value_is_formed_once_per_record_and_goes_with_it():
    held = FormedOnce()
    a, b = _Record(np.arange(4.0)), _Record(np.arange(4.0))
    calls = []

    def form(record, scale):
        calls.append(scale)
        return record.values * scale

    first = held.get(a, form, 2.0)
    assert held.get(a, form, 2.0) is first
    np.testing.assert_array_equal(first, [0.0, 2.0, 4.0, 6.0])
    assert calls == [2.0]
    held.get(a, form, 3.0)  # other arguments, another value
    held.get(b, form, 2.0)  # an equal record is another record
    assert calls == [2.0, 3.0, 2.0] and len(held) == 2
    gone = weakref.ref(a)
    del a, first
    gc.collect()
    assert gone() is None  # the cache does not keep a record alive
    assert len(held) == 1


def test_a_formed_property_reads_the_same_value_without_writing_the_record():
    r = _Record(np.array([1.0, 2.0, 4.0]))
    before = _Record.reads
    assert r.total == 7.0 and r.total == 7.0
    assert _Record.reads == before + 1
    assert "total" not in vars(r)
    assert _Record.total.__doc__ == "The sum of the values."


def test_threads_forming_at_once_read_one_value():
    track = Track(builtin_profile("60E1"), math.atan(1 / 40))
    wheelset = Wheelset(builtin_profile("S1002"))
    barrier, out = threading.Barrier(6), []

    def first_use() -> None:
        barrier.wait()
        out.append((search.rail_arrays(track), search.wheel_arrays(wheelset),
                    track.side_rail))

    threads = [threading.Thread(target=first_use) for _ in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(out) == 6
    assert all(o[k] is out[0][k] for o in out for k in range(3))
    assert set(vars(track)) == {"rail", "inclination", "gauge", "gauge_depth", "shift", "tilt"}
