"""The FMU's variable table without building an FMU: enumeration item names and messages."""

from __future__ import annotations

import re

import numpy as np
import pytest

from railcontact.errors import RailContactError
from railcontact.fmu import variables as V
from railcontact.fmu.variables import CHOICES, item_name, resolve_choices

# Modelica's reserved words that a short choice word could hit (Modelica Language
# Specification 3.6, 2.3.3)
RESERVED = {"in", "and", "or", "not", "if", "end", "for", "type", "model", "input", "output",
            "final", "flow", "loop", "then", "when", "true", "false", "each", "inner", "outer"}


def test_enumeration_items_are_modelica_identifiers():
    """Tools import an enumeration as a Modelica type: each item's name must be an
    identifier and not a reserved word (the profile unit ``in`` is ``inch``), and the
    names of one enumeration distinct."""
    for v in CHOICES:
        names = [item_name(w) for w in v.items]
        assert len(set(names)) == len(names), v.name
        for n in names:
            assert re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", n), (v.name, n)
            assert n not in RESERVED, (v.name, n)
    units = next(v for v in CHOICES if v.name == "profile_unit_choice")
    assert "in" in units.items and item_name("in") == "inch"
    assert item_name("previous+estimate") == "previous_estimate"


def test_a_bad_enumeration_value_is_shown_as_a_plain_number():
    """The value an FMU buffer holds is a numpy integer: the message shows it as 5."""
    with pytest.raises(RailContactError) as err:
        resolve_choices({"control_choice": np.int32(5)})
    assert "got 5" in str(err.value) and "np." not in str(err.value)


def test_choice_enumerations_keep_their_value_references():
    """The Integer ``_choice`` enumerations are a published interface as well: outputs
    added after them (``APPENDED_OUTPUTS``: the rigid wheelset's work) are numbered after
    them, so that adding an output never moves a published value reference. These numbers
    are written down, not computed."""
    published = {"profile_unit_choice": 19, "control_choice": 20,
                 "load_definition_choice": 21, "creepage_input_choice": 22,
                 "normal_estimate_choice": 23, "tangential_estimate_choice": 24,
                 "warm_start_choice": 25, "fft_choice": 26, "tangential_solver_choice": 27,
                 "convention_choice": 28, "rigid_wheelset_choice": 29,
                 "contact_model_choice": 30, "patch_frame_choice": 31}
    table = {v.name: v for v in V.table()}
    assert {k: (table[k].type, table[k].vr) for k in published} == {
        k: ("Integer", vr) for k, vr in published.items()}
    appended = {"rigid_evaluations": 32, "rigid_normal_iterations": 33,
                "rigid_tangential_iterations": 34, "rigid_load_passes": 35,
                "rigid_remeshes": 36}  # appended after the enumerations
    assert {k: (table[k].type, table[k].vr) for k in appended} == {
        k: ("Integer", vr) for k, vr in appended.items()}
