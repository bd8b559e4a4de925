"""The shipped JSON Schema of ``mjtvm.state/1`` (``mjtvm/data/schema/state.schema.json``):
every shipped state passes it, and ``load_state`` refuses exactly what it refuses, plus the
rules a schema cannot express (docs/state-format.md, "What only the loader checks")."""

from __future__ import annotations

import copy
import json
import re
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from mjtvm import StateError, load_state, tvmmp
from mjtvm.paper_hand.scenario import scenario_document
from tests.support.mutate import mutations

DATA = resources.files("mjtvm.data")
EXAMPLES = sorted(p.name for p in DATA.joinpath("examples").iterdir() if p.name.endswith(".json"))
SCENARIOS = ("case1", "case1-s", "case2")


@pytest.fixture(scope="module")
def validator() -> jsonschema.Draft202012Validator:
    schema = json.loads(DATA.joinpath("schema").joinpath("state.schema.json").read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def example(name: str = "pinch.json") -> dict[str, Any]:
    out: dict[str, Any] = json.loads(DATA.joinpath("examples").joinpath(name).read_text(encoding="utf-8"))
    return out


def test_schema_is_draft_2020_12(validator):
    assert validator.schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert validator.schema["properties"]["schema"]["enum"] == ["mjtvm.state/1", "mjtvm.state/2"]


@pytest.mark.parametrize("name", EXAMPLES)
def test_every_shipped_example_passes_the_schema(validator, name):
    doc = example(name)
    assert list(validator.iter_errors(doc)) == []
    assert load_state(doc).num_joints == len(doc["joints"])


@pytest.mark.parametrize("name", SCENARIOS)
def test_every_exported_scenario_state_passes_the_schema(validator, name):
    doc = json.loads(json.dumps(scenario_document(name)))  # as another tool would read the file
    assert list(validator.iter_errors(doc)) == []
    assert load_state(doc).num_joints == len(doc["joints"])


def test_planar_state_passes_the_schema(validator):
    doc = {
        "schema": "mjtvm.state/1",
        "space": 2,
        "object_position": [0.0, 0.1],
        "joints": [{"name": "j", "operation_range": [[0, 0], [1, 0], [0, 2]]}],
        "gravity_torque": [0.0],
        "contacts": [
            {
                "name": "c",
                "type": "F",
                "position": [0.1, 0.1],
                "normal": [-1.0, 0.0],
                "mu": 0.5,
                "jacobian": [[0.0], [0.1]],
            }
        ],
        "refs": [[0.0, -1.0, 0.0]],
        "rvds": [[0.0, 1.0, 0.0]],
    }
    assert list(validator.iter_errors(doc)) == []
    assert load_state(doc).twist_dim == 3


def _set(doc: dict[str, Any], path: tuple[Any, ...], value: Any) -> dict[str, Any]:
    out = copy.deepcopy(doc)
    target: Any = out
    for key in path[:-1]:
        target = target[key]
    if value is _DELETE:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return out


_DELETE = object()
INVALID = [
    # (path, value, the loader's field)
    (("frobnicate",), 1, "frobnicate"),
    (("refs",), _DELETE, "refs"),
    (("schema",), "mjtvm.state/3", "schema"),
    (("space",), 4, "space"),
    (("space",), True, "space"),
    (("object_position",), [0.0, 0.0], "object_position"),
    (("object_position", 0), "0.0", "object_position"),
    (("gravity_torque", 0), True, "gravity_torque"),
    (("gravity_torque", 0), None, "gravity_torque"),
    (("refs", 0, 2), -1.5e12, "refs"),
    (("rvds", 0, 0), 2**1100, "rvds"),
    (("rvds",), [], "rvds"),
    (("contacts", 0, "jacobian", 0, 0), 1e20, "contacts[0].jacobian"),
    (("contacts", 0, "jacobian"), [[0.0] * 4] * 4, "contacts[0].jacobian"),
    (("contacts", 0, "mu"), -0.1, "contacts[0].mu"),
    (("contacts", 0, "mu"), _DELETE, "contacts[0].mu"),
    (("contacts", 0, "type"), "S", "contacts[0].slide_direction"),
    (("contacts", 0, "slide_direction"), [0.0, 1.0, 0.0], "contacts[0].slide_direction"),
    (("contacts", 0, "type"), "Q", "contacts[0].type"),
    (("contacts", 0, "name"), "", "contacts[0].name"),
    (("joints", 0, "name"), "j" * 257, "joints[0].name"),
    (("joints", 0, "operation_range", 1, 1), -0.5, "joints[0].operation_range"),
    (("joints", 0, "operation_range"), [[0, 0], [1, 0]], "joints[0].operation_range"),
    (("joints", 0, "gear"), 40, "joints[0].gear"),
    (("joints",), [], "joints"),
    (("friction_edges",), 2, "friction_edges"),
    (("friction_edges",), 257, "friction_edges"),
    (("friction_edges",), 16.5, "friction_edges"),
    (("friction_edges",), "16", "friction_edges"),
    (("slip",), "sometimes", "slip"),
    (("refs",), [[0, 0, -1, 0, 0, 0]] * 257, "refs"),
]


@pytest.mark.parametrize(
    ("path", "value", "field"), INVALID, ids=[f"{c[2]}-{i}" for i, c in enumerate(INVALID)]
)
def test_schema_and_loader_agree_on_invalid_documents(validator, path, value, field):
    doc = _set(example(), path, value)
    assert list(validator.iter_errors(doc)), "the schema accepted it"
    with pytest.raises(StateError) as info:
        load_state(doc)
    assert info.value.field == field


def test_schema_and_loader_agree_on_valid_edge_values(validator):
    """Integral floats count as integers (JSON Schema's rule); the bounds themselves are valid."""
    doc = example()
    doc["friction_edges"], doc["space"] = 16.0, 3.0
    doc["refs"] = [[0.0, 0.0, -1e12, 0.0, 0.0, 0.0]]
    doc["contacts"][0]["mu"] = 0
    assert list(validator.iter_errors(doc)) == []
    state = load_state(doc)
    assert (state.friction_edges, state.space, state.refs[0, 2]) == (16, 3, -1e12)


def test_the_documented_example_is_valid(validator):
    """The example in docs/state-format.md passes the schema, loads and solves."""
    text = (Path(__file__).parents[2] / "docs" / "state-format.md").read_text(encoding="utf-8")
    doc = json.loads(text.split("```json\n", 1)[1].split("```", 1)[0])
    assert list(validator.iter_errors(doc)) == []
    state = load_state(doc)
    assert (state.num_joints, len(state.contacts), state.friction_edges) == (2, 2, 16)
    result = tvmmp(state)
    # The fingertips move only along z (their Jacobians): up and down are reachable, the
    # sideways-and-up directions are not (alpha 0), so the TVMMP is 0.
    assert result.status == (("optimal",) * 4,)
    assert result.alpha[0, 0] > 1.0 and result.alpha[0, 3] > 1.0
    assert result.alpha[0, 1] == 0.0 and result.alpha[0, 2] == 0.0 and result.tvmmp == 0.0


# The rules only the loader checks (docs/state-format.md), as the loader words them.
BEYOND_SCHEMA = re.compile(
    r"(one per joint|one column per joint|rows of equal length|unit vector|"
    r"the origin \[0, 0\] must be a vertex|not down-closed|not convex|repeated vertex|winding|"
    r"tangent plane|orthogonal|non-zero|unique|finite|lower <= upper)"
)
VALUES: list[Any] = [
    "x",
    0,
    -1,
    0.5,
    2,
    16.0,
    1e300,
    True,
    None,
    [],
    {},
    [0, 0, 0],
    [[0, 0], [1, 0], [0, 2]],
    "S",
    "D",
]
EXTRA = {"slide_direction": [1, 0, 0], "preload": 1.0, "mu": 0.5, "zzz": 1, "friction_edges": 8}


@pytest.mark.parametrize("name", ["pinch.json", "case1-s"])
def test_load_state_refuses_what_the_schema_refuses_and_only_beyond_it_more(validator, name):
    doc = example(name) if name.endswith(".json") else json.loads(json.dumps(scenario_document(name)))
    counts = {"both accept": 0, "both refuse": 0, "beyond": 0}
    for mutated in mutations(doc, VALUES, EXTRA, every_item=False):
        schema_accepts = not list(validator.iter_errors(mutated))
        try:
            load_state(mutated)
        except StateError as e:
            assert "\n" not in str(e), str(e)
            assert not schema_accepts or BEYOND_SCHEMA.search(e.problem), f"only the loader refuses: {e}"
            counts["beyond" if schema_accepts else "both refuse"] += 1
        else:
            assert schema_accepts, "only the schema refuses"
            counts["both accept"] += 1
    assert min(counts.values()) > 0, counts
