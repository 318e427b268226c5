"""The FMU's saved state (railcontact.fmu.state): numbers and arrays in a documented
format, read back without running code, the warm-start memory bit for bit."""

from __future__ import annotations

import io
import json
import math
import pickle
import struct

import numpy as np
import pytest

from railcontact.fmu import state as S
from railcontact.geometry.profiles import read_profile
from railcontact.geometry.track import Pose, Track, Wheelset
from railcontact.halfspace.materials import ElasticPair, Material
from railcontact.timestep import StepMemory
from railcontact.timestep.wheelset import ContactSettings, WheelsetContact

CREEP = ((1e-3, -5e-4, 0.3), (1e-3, -5e-4, -0.3))


def _contact() -> WheelsetContact:
    mat = Material(206e9, 0.28)
    return WheelsetContact(
        Track(read_profile("60E1", "rail"), math.atan(1 / 40), 1.435),
        Wheelset(read_profile("S1002", "wheel"), 0.46, 1.360), ElasticPair.of(mat, mat),
        ContactSettings(warm_start="previous", element_size=2e-3, rigid_wheelset="solve"))


def _step(contact: WheelsetContact, k: int, y: float):
    res = contact.solve(Pose(y, 0.0), loads=(83.3e3, 83.3e3), creepages=CREEP,
                        time=k * 1e-3)
    return res


def _state(memory) -> S.State:
    return S.State(guid="{g}", model="RailContact", initialised=True,
                   parameters={"friction": 0.4, "warm_start": "previous"},
                   real=np.arange(3.0), integer=np.arange(2, dtype=np.int32),
                   control=np.array([1e-3, 1e-3]), strings=["S1002"], memory=memory)


def _outputs(res) -> list:
    return [(w.normal_force, w.creep_force, w.spin_moment, w.normal_iterations,
             w.tangential_iterations, w.load_passes) for w in res.wheels] + [
        res.rigid_solution.vertical, res.rigid_solution.roll]


def test_memory_round_trips_bit_for_bit():
    """A warm step after the memory went through pack/unpack equals the step after the
    original memory, iterations included; what the memory shares stays shared."""
    contact = _contact()
    for k, y in enumerate((1e-3, 1.05e-3, 1.1e-3)):
        _step(contact, k, y)
    memory = contact.memory
    assert isinstance(memory, StepMemory) and memory.left and memory.rigid
    data = S.pack(_state(memory))
    restored = S.unpack(data).memory
    original = _step(contact, 3, 1.15e-3)
    contact.memory = restored
    again = _step(contact, 3, 1.15e-3)
    assert _outputs(again) == _outputs(original)
    # the same record reached twice is one record again; arrays keep dtype and order
    patch = memory.left[0]
    twice = S.unpack(S.pack(_state({"a": [patch, patch]}))).memory["a"]
    assert twice[0] is twice[1] and type(twice[0]) is type(patch)
    assert twice[0].pressure.dtype == patch.pressure.dtype
    np.testing.assert_array_equal(twice[0].pressure, patch.pressure)
    assert twice[0].grid == patch.grid


def test_layout_is_the_documented_one():
    data = S.pack(_state({"left": [], "right": [], "t": (1.0, float("nan"), None)}))
    magic, version, length = struct.unpack_from("<16sIQ", data)
    assert magic == S.MAGIC and version == S.VERSION
    header = json.loads(data[28:28 + length])
    assert header["format"] == S.FORMAT and header["guid"] == "{g}"
    assert header["memory"]["$dict"]["t"] == {"$tuple": [1.0, {"$float": "nan"}, None]}
    with np.load(io.BytesIO(data[28 + length:]), allow_pickle=False) as archive:
        assert {"real", "integer", "control"} <= set(archive.files)
    back = S.unpack(data)
    assert back.parameters == {"friction": 0.4, "warm_start": "previous"}
    assert math.isnan(back.memory["t"][1]) and back.strings == ["S1002"]


def _with_memory(tree) -> bytes:
    """A state whose header's memory is ``tree`` (crafted JSON)."""
    data = S.pack(_state(None))
    _, version, length = struct.unpack_from("<16sIQ", data)
    header = json.loads(data[28:28 + length])
    header["memory"] = tree
    text = json.dumps(header).encode()
    return struct.pack("<16sIQ", S.MAGIC, version, len(text)) + text + data[28 + length:]


@pytest.mark.parametrize("tree, words", [
    ({"$object": "system", "id": 0, "fields": {}}, "not a record"),
    ({"$object": "Grid", "id": 0, "fields": {"nx": 1}}, "missing"),
    ({"$object": "Displacement", "id": 0,
      "fields": {"values": None, "generations": 0, "__class__": "x"}}, "unknown"),
    ({"$array": "a99"}, "does not hold"),
    ({"$ref": 5}, "not a value"),
    ({"$reduce": ["os.system", "echo"]}, "not a value"),
])
def test_crafted_states_are_refused(tree, words):
    with pytest.raises(S.StateError, match=words):
        S.unpack(_with_memory(tree))


def test_pickle_and_damaged_bytes_are_refused(tmp_path):
    flag = tmp_path / "flag"

    class Exploit:
        def __reduce__(self):
            return (open, (str(flag), "w"))

    for data, words in ((pickle.dumps(Exploit()), "not a railcontact FMU state"),
                        (S.MAGIC + struct.pack("<I", S.VERSION) + b"\xff" * 8, "cut short"),
                        (S.pack(_state(None))[:-30], "its arrays")):
        with pytest.raises(S.StateError, match=words):
            S.unpack(data)
    assert not flag.exists()


def test_what_cannot_be_saved_is_named():
    with pytest.raises(S.StateError, match="memory\\['left'\\]\\[0\\].*Pose"):
        S.pack(_state({"left": [Pose(0.0, 0.0)], "right": []}))
    with pytest.raises(S.StateError, match="Python objects"):
        S.pack(_state({"left": [np.array([object()])]}))
