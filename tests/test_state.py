"""The mjtvm.state/1 contract: round trip, and one clear error per kind of bad input."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from mjtvm import GraspState, StateError, dump_state, load_state, state_to_dict, tvmmp
from mjtvm.cli import example_path


@pytest.fixture
def doc() -> dict:
    with open(example_path()) as f:
        return json.load(f)


def test_round_trip_is_lossless(doc):
    state = load_state(doc)
    again = load_state(dump_state(state))
    assert state_to_dict(again) == state_to_dict(state)
    np.testing.assert_array_equal(tvmmp(again).alpha, tvmmp(state).alpha)


def test_load_from_path_string_and_mapping(doc, tmp_path):
    path = tmp_path / "s.json"
    path.write_text(json.dumps(doc))
    for source in (path, str(path), json.dumps(doc), doc):
        assert isinstance(load_state(source), GraspState)


def test_optional_keys_are_honoured(doc):
    doc["slip"] = "shared"
    doc["friction_edges"] = 4
    doc["contacts"][0]["tangent"] = [0.0, 1.0, 0.0]
    state = load_state(doc)
    assert state.slip == "shared" and state.friction_edges == 4
    assert state_to_dict(state)["contacts"][0]["tangent"] == [0.0, 1.0, 0.0]


def mutate(doc, path, value):
    """Set doc[path...] = value; value DELETE removes the key."""
    out = copy.deepcopy(doc)
    target = out
    for key in path[:-1]:
        target = target[key]
    if value is DELETE:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return out


DELETE = object()
CASES = [
    (("frobnicate",), 1, r"^frobnicate: unknown key"),
    (("contacts", 0, "frobnicate"), 1, r"^contacts\[0\]\.frobnicate: unknown key"),
    (("joints", 1, "gear"), 40, r"^joints\[1\]\.gear: unknown key"),
    (("refs",), DELETE, r"^refs: required key is missing"),
    (("contacts", 1, "jacobian"), DELETE, r"^contacts\[1\]\.jacobian: required key is missing"),
    (("schema",), "mjtvm.state/2", r"^schema: expected 'mjtvm.state/1'"),
    (("space",), 4, r"^space: expected 2 or 3"),
    (("object_position",), [0, 0], r"^object_position: expected 3 finite numbers"),
    (("refs",), [[0, 0, -1]], r"^refs: expected a non-empty list of vectors of 6 numbers"),
    (("rvds",), [[1, 0, 0, 0, 0]], r"^rvds: expected a non-empty list of vectors of 6 numbers"),
    (("gravity_torque",), [0.0], r"^gravity_torque: expected 4 finite numbers"),
    (("contacts", 0, "jacobian"), [[0.0] * 3] * 3, r"^contacts\[0\]\.jacobian: expected 3 x 4"),
    (("contacts", 0, "jacobian"), [[0.0] * 4] * 2, r"^contacts\[0\]\.jacobian: expected 3 rows"),
    (("contacts", 0, "normal"), [0.9, 0.4, 0.1], r"^contacts\[0\]\.normal: expected a unit vector"),
    (("contacts", 0, "position"), [0.0, float("nan"), 0.1], r"^contacts\[0\]\.position: expected finite"),
    (("refs",), [[0, 0, float("inf"), 0, 0, 0]], r"^refs: expected finite"),
    (("contacts", 0, "type"), "Q", r"^contacts\[0\]\.type: expected one of F, L, S, D"),
    (("contacts", 1, "type"), "S", r"^contacts\[1\]\.slide_direction: required for an S contact"),
    (("contacts", 1, "mu"), "lots", r"^contacts\[1\]\.mu: expected a number"),
    (
        ("joints", 0, "operation_range"),
        [[0, 0], [1, 0], [0.3, 0.3], [0, 1]],
        r"^joints\[0\]\.operation_range: not convex",
    ),
    (
        ("joints", 2, "operation_range"),
        [[0, 0], [1, 0], [1.2, 1], [0, 1]],
        r"^joints\[2\]\.operation_range: not down-closed",
    ),
    (
        ("joints", 3, "operation_range"),
        [[0, 0], [1, -1], [1, 1], [0, 1]],
        r"^joints\[3\]\.operation_range: .*negative",
    ),
    (
        ("joints", 3, "operation_range"),
        [[0.1, 0.1], [1, 0], [1, 1], [0, 1]],
        r"^joints\[3\]\.operation_range: the origin",
    ),
    (("joints", 1, "name"), "f1_pitch0", r"^joints: joint names must be unique"),
    (("contacts", 1, "name"), "f1_tip", r"^contacts: contact names must be unique"),
    (("friction_edges",), 2, r"^friction_edges: expected an integer in \[3, 256\], got 2$"),
    (("slip",), "sometimes", r"^slip: expected 'per_contact' or 'shared'"),
    (("joints",), [], r"^joints: expected at least one joint"),
    (("contacts",), {"a": 1}, r"^contacts: expected a list"),
]


@pytest.mark.parametrize(("path", "value", "match"), CASES, ids=[c[2][1:40] for c in CASES])
def test_bad_input_names_the_field(doc, path, value, match):
    with pytest.raises(StateError, match=match):
        load_state(mutate(doc, path, value))


def test_nan_literal_in_json_names_the_field(doc):
    text = json.dumps(doc).replace('"mu": 0.5', '"mu": NaN', 1)
    with pytest.raises(StateError, match=r"^contacts\[0\]\.mu: expected a finite number"):
        load_state(text)


def test_malformed_json_and_missing_file(tmp_path):
    with pytest.raises(StateError, match="malformed JSON at line 1 column"):
        load_state('{"schema": ')
    with pytest.raises(StateError, match="cannot read state file"):
        load_state(tmp_path / "missing.json")
    with pytest.raises(StateError, match="expected a JSON object"):
        load_state(tmp_path.joinpath("list.json")) if tmp_path.joinpath("list.json").write_text(
            "[1]"
        ) else None
