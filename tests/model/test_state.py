"""The mjtvm.state/1 contract: round trip, and one clear error per kind of bad input."""

from __future__ import annotations

import copy
import json
import os
from dataclasses import replace

import numpy as np
import pytest

from mjtvm import GraspState, OutputError, StateError, dump_state, load_state, state_to_dict, tvmmp
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
    (("schema",), "mjtvm.state/3", r"^schema: expected 'mjtvm.state/1' or 'mjtvm.state/2'"),
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


# ------------------------------------------- issue 12: every failure class of the fuzz
BIG_INT = 2**1100  # does not fit a float: float(2**1100) raises OverflowError
BOUND_CASES = [
    # (path, value, field, message)
    (("joints", 0, "operation_range", 1, 0), BIG_INT, "joints[0].operation_range",
     r"expected \|x\| <= 1e\+12 \(the format's bound\), got an integer of 332 digits at \[1\]\[0\]$"),
    (("joints", 1, "operation_range", 2, 1), 1e154, "joints[1].operation_range", r"got 1e\+154 at \[2\]\[1\]$"),
    (("refs", 0, 2), BIG_INT, "refs", r"got an integer of 332 digits at \[0\]\[2\]$"),
    (("rvds", 1, 0), -1e308, "rvds", r"got -1e\+308 at \[1\]\[0\]$"),
    (("rvds", 0, 0), 1e154, "rvds", r"got 1e\+154 at \[0\]\[0\]$"),
    (("contacts", 1, "jacobian", 1, 3), 1e20, "contacts[1].jacobian", r"got 1e\+20 at \[1\]\[3\]$"),
    (("contacts", 0, "jacobian", 0, 0), BIG_INT, "contacts[0].jacobian", r"integer of 332 digits at \[0\]\[0\]$"),
    (("contacts", 0, "position", 1), 1e154, "contacts[0].position", r"got 1e\+154 at \[1\]$"),
    (("contacts", 1, "normal", 0), BIG_INT, "contacts[1].normal", r"integer of 332 digits at \[0\]$"),
    (("contacts", 1, "normal", 0), 1e154, "contacts[1].normal", r"got 1e\+154 at \[0\]$"),
    (("contacts", 0, "mu"), 10**400, "contacts[0].mu", r"got an integer of 401 digits$"),
    (("object_position", 1), "0.0", "object_position", r"expected a number, got the string '0.0' at \[1\]$"),
    (("object_position", 2), {"z": 0.1}, "object_position", r"expected a number, got an object at \[2\]$"),
    (("gravity_torque", 0), "1.5", "gravity_torque", r"expected a number, got the string '1.5' at \[0\]$"),
    (("gravity_torque", 3), {"a": 1}, "gravity_torque", r"expected a number, got an object at \[3\]$"),
    (("gravity_torque", 1), True, "gravity_torque", r"expected a number, got true at \[1\]$"),
    (("gravity_torque", 1), None, "gravity_torque", r"expected a number, got null at \[1\]$"),
    (("contacts", 0, "mu"), True, "contacts[0].mu", r"expected a number, got true$"),
    (("refs", 0), [0, 0, "-1", 0, 0, 0], "refs", r"expected a number, got the string '-1' at \[0\]\[2\]$"),
    (("refs", 0), [0, 0, [1], 0, 0, 0], "refs", r"expected a number, got a list of 1 at \[0\]\[2\]$"),
    (("friction_edges",), 10**12, "friction_edges", r"expected an integer in \[3, 256\], got 1000000000000$"),
    (("friction_edges",), 1e30, "friction_edges", r"expected an integer in \[3, 256\], got 1e\+30$"),
    (("friction_edges",), 10**6, "friction_edges", r"expected an integer in \[3, 256\], got 1000000$"),
    (("friction_edges",), 16.5, "friction_edges", r"expected an integer in \[3, 256\], got 16.5$"),
    (("friction_edges",), "16", "friction_edges", r"got the string '16'$"),
    (("friction_edges",), True, "friction_edges", r"got true$"),
    (("space",), 3.5, "space", r"expected 2 or 3, got 3.5$"),
    (("contacts", 0, "name"), "\ud800", "contacts[0].name", r"expected valid Unicode text"),
    (("joints", 0, "name"), "j" * 300, "joints[0].name", r"expected at most 256 characters, got 300$"),
    (("rvds",), None, "rvds", r"omit the key for no RVDS"),
]  # fmt: skip  # a table: one bad field per row


@pytest.mark.parametrize(("path", "value", "field", "match"), BOUND_CASES, ids=[c[2] for c in BOUND_CASES])
def test_values_beyond_the_format_name_the_field(doc, path, value, field, match):
    with pytest.raises(StateError, match=match) as info:
        load_state(mutate(doc, path, value))
    assert info.value.field == field
    assert str(info.value).startswith(f"{field}: ")


@pytest.mark.parametrize(
    ("key", "size", "match"),
    [
        ("joints", 129, r"^joints: expected at most 128 joints, got 129$"),
        ("contacts", 129, r"^contacts: expected at most 128 contacts, got 129$"),
        ("refs", 257, r"^refs: expected at most 256 entries, got 257$"),
        ("rvds", 257, r"^rvds: expected at most 256 entries, got 257$"),
    ],
)
def test_sizes_are_bounded_and_the_bound_is_in_the_message(doc, key, size, match):
    doc[key] = [copy.deepcopy(doc[key][0]) for _ in range(size)]
    with pytest.raises(StateError, match=match) as info:
        load_state(doc)
    assert info.value.field == key


def test_operation_range_vertices_are_bounded(doc):
    def quarter_disc(n: int) -> list[list[float]]:  # n vertices: the origin, the axes, an arc
        arc = np.linspace(0.0, np.pi / 2, n - 1)[1:-1]
        return [[0.0, 0.0], [1.0, 0.0], *([np.cos(t), np.sin(t)] for t in arc), [0.0, 1.0]]

    doc["joints"][2]["operation_range"] = quarter_disc(257)
    with pytest.raises(
        StateError, match=r"^joints\[2\]\.operation_range: expected at most 256 entries, got 257"
    ):
        load_state(doc)
    doc["joints"][2]["operation_range"] = quarter_disc(256)  # the bound itself is fine
    assert len(load_state(doc).operation_ranges[2].vertices) == 256


def test_largest_valid_numbers_load_and_values_past_them_do_not(doc):
    doc["refs"] = [[0.0, 0.0, -1e12, 0.0, 0.0, 0.0]]
    assert load_state(doc).refs[0, 2] == -1e12
    doc["refs"] = [[0.0, 0.0, -1.000001e12, 0.0, 0.0, 0.0]]
    with pytest.raises(StateError, match=r"^refs: expected \|x\| <= 1e\+12"):
        load_state(doc)


def test_integral_float_friction_edges_counts_as_an_integer(doc):
    doc["friction_edges"] = 16.0
    state = load_state(doc)
    assert state.friction_edges == 16 and isinstance(state.friction_edges, int)
    doc["friction_edges"] = 256
    assert load_state(doc).friction_edges == 256
    doc["space"] = 3.0
    assert load_state(doc).space == 3


def test_states_built_in_python_get_the_same_checks(doc):
    state = load_state(doc)
    with pytest.raises(StateError, match=r"^friction_edges: expected an integer in \[3, 256\]"):
        state.with_(friction_edges=10**12)
    with pytest.raises(StateError, match=r"^refs: expected \|x\| <= 1e\+12") as info:
        state.with_(refs=np.array([[0, 0, 1e13, 0, 0, 0]]))
    assert info.value.field == "refs"
    with pytest.raises(StateError, match=r"^gravity_torque: expected a number, got the string 'a'"):
        state.with_(gravity_torque=[0.0, "a", 0.0, 0.0])
    with pytest.raises(StateError, match=r"^mu: expected \|x\| <= 1e\+12"):
        replace(state.contacts[0], mu=10**400)


def test_non_utf8_file_is_a_state_error(doc, tmp_path):
    path = tmp_path / "latin1.json"
    text = json.dumps(doc)
    path.write_bytes(text[:40].encode() + b"\xe9" + text[40:].encode())
    with pytest.raises(StateError, match=r"latin1.json' is not UTF-8 text: byte 0xe9 at offset 40$") as info:
        load_state(path)
    assert info.value.field == ""
    with pytest.raises(StateError, match=r"^the state is not UTF-8 text: byte 0xff at offset 0$"):
        load_state(b"\xff" + text.encode())


def test_utf8_bom_and_bytes_are_accepted(doc, tmp_path):
    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps(doc).encode())
    assert load_state(path).num_joints == 4
    assert load_state(json.dumps(doc).encode()).num_joints == 4


@pytest.mark.parametrize("depth", [20, 999, 1001, 100_000])
def test_deep_nesting_in_json_text_is_a_state_error(depth):
    text = '{"schema": "mjtvm.state/1", "refs": ' + "[" * depth + "]" * depth + "}"
    with pytest.raises(StateError, match=r"nested (too deep|deeper than 8 levels)") as info:
        load_state(text)
    assert info.value.field in ("", "refs[0][0][0][0][0][0][0][0]")


def test_deep_or_cyclic_mappings_are_state_errors(doc):
    deep: list = []
    doc["object_position"] = deep
    for _ in range(5000):
        deep.append([])
        deep = deep[0]
    with pytest.raises(StateError, match=r"^object_position(\[0\]){8}: nested deeper than 8 levels"):
        load_state(doc)
    cyclic: dict = {"schema": "mjtvm.state/1"}
    cyclic["joints"] = [cyclic]
    with pytest.raises(StateError, match=r"nested deeper than 8 levels"):
        load_state(cyclic)
    with pytest.raises(StateError, match=r"^refs: expected a JSON value, got set$"):
        load_state({**doc, "object_position": [0, 0, 0.12], "refs": {1, 2}})


def test_number_literals_a_float_cannot_hold(doc):
    text = json.dumps(doc)
    with pytest.raises(StateError, match=r"^contacts\[0\]\.mu: expected finite numbers .* got inf$"):
        load_state(text.replace('"mu": 0.5', '"mu": 1e400', 1))
    with pytest.raises(StateError, match=r"^malformed JSON: Exceeds the limit \(4300 digits\)"):
        load_state(text.replace('"mu": 0.5', '"mu": ' + "9" * 5000, 1))
    with pytest.raises(
        StateError, match=r"^contacts\[0\]\.mu: expected \|x\| <= 1e\+12 .* integer of 400 digits$"
    ):
        load_state(text.replace('"mu": 0.5', '"mu": ' + "9" * 400, 1))


def test_repeated_key_is_a_state_error(doc):
    text = json.dumps(doc).replace('"mu": 0.5', '"mu": 0.5, "mu": 5.0', 1)
    with pytest.raises(StateError, match=r"^mu: repeated key in a JSON object"):
        load_state(text)


def test_unreadable_sources(tmp_path):
    with pytest.raises(StateError, match=r"^cannot read state file .*: Is a directory"):
        load_state(tmp_path)
    with pytest.raises(StateError, match=r"^cannot read state file .*embedded null"):
        load_state("a\x00b.json")
    with pytest.raises(StateError, match=r"^expected a path, JSON text or a mapping, got int$"):
        load_state(3)  # type: ignore[arg-type]


def test_operation_range_tolerance_is_per_axis(doc):
    """Torque 1.5 N m beside speed 1.5e9 rad/s (or 1.5e-9) is a valid range."""
    for speed in (1.5e9, 1.5e-9):
        doc["joints"][0]["operation_range"] = [[0, 0], [1.5, 0], [1.5, 0.8 * speed], [0, speed]]
        op = load_state(doc).operation_ranges[0]
        assert op.max_torque == 1.5 and op.max_speed == speed
        assert op.contains(1.5, 0.8 * speed, tol=0.0) and op.contains(0.75, 0.9 * speed, tol=0.0)
        assert not op.contains(1.5, 0.81 * speed, tol=0.0) and not op.contains(0.0, 1.01 * speed, tol=0.0)


# ---------------------------------------------------------------- dump_state to a file
def test_dump_state_writes_a_file_atomically(doc, tmp_path):
    state = load_state(doc)
    path = tmp_path / "state.json"
    path.write_text("old")
    text = dump_state(state, path)
    assert path.read_text(encoding="utf-8") == text + "\n"
    assert state_to_dict(load_state(path)) == state_to_dict(state)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["state.json"]  # no temporary file left
    assert path.stat().st_mode & 0o777 == 0o666 & ~_umask()
    assert dump_state(state, str(tmp_path / "one-line.json"), indent=None).count("\n") == 0
    assert dump_state(state) == text


def test_dump_state_failure_leaves_the_old_file(doc, tmp_path):
    state = load_state(doc)
    with pytest.raises(OutputError, match=r"^path: cannot write \(No such file or directory\): .*missing"):
        dump_state(state, tmp_path / "missing" / "state.json")
    target = tmp_path / "dir.json"
    target.mkdir()
    with pytest.raises(OutputError, match=r"^path: cannot replace \(Is a directory\): .*dir\.json$") as err:
        dump_state(state, target)
    assert err.value.path == str(target)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir.json"]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
