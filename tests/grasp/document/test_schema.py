"""The shipped JSON Schema of ``mjtvm.grasp/1`` (``mjtvm/data/schema/grasp.schema.json``): every
shipped grasp file passes it, and the loader refuses exactly what it refuses, plus the rules of
``BEYOND_SCHEMA`` (each refusal of those marked ``beyond_schema``)."""

from __future__ import annotations

import copy
import json
import tomllib
from importlib import resources
from typing import Any

import jsonschema
import pytest

from mjtvm.grasp.document.document import GraspError, read_grasp_document
from mjtvm.grasp.document.validate import schema_problem
from mjtvm.grasp.resolve.file import shipped_grasps
from tests.support.mutate import mutations

SCHEMA = json.loads(
    resources.files("mjtvm.data").joinpath("schema", "grasp.schema.json").read_text(encoding="utf-8")
)


@pytest.fixture(scope="module")
def validator() -> jsonschema.Draft202012Validator:
    jsonschema.Draft202012Validator.check_schema(SCHEMA)
    return jsonschema.Draft202012Validator(SCHEMA)


@pytest.mark.parametrize("name", sorted(shipped_grasps()))
def test_every_shipped_grasp_passes_the_schema(validator: jsonschema.Draft202012Validator, name: str) -> None:
    doc = tomllib.loads(shipped_grasps()[name].read_text(encoding="utf-8"))
    assert not list(validator.iter_errors(doc))
    read_grasp_document(doc)


def _case2() -> dict[str, Any]:
    return tomllib.loads(shipped_grasps()["case2"].read_text(encoding="utf-8"))


def _set(doc: dict[str, Any], path: tuple[Any, ...], value: Any) -> dict[str, Any]:
    out = copy.deepcopy(doc)
    node = out
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return out


@pytest.mark.parametrize(
    ("path", "value"),
    [
        (("schema",), "mjtvm.grasp/2"),
        (("object",), {"body": "object", "colour": "red"}),
        (("configuration",), {"keyframe": "a", "qpos": {}}),
        (("configuration",), {}),
        (("contacts", 0), {"geom": "palm"}),
        (("contacts", 0), {"geom": "palm", "body": "world", "type": "D"}),
        (("contacts", 0), {"geom": "palm", "type": "Q"}),
        (("contacts",), []),
        (("contact_rules",), []),
        (("contact_rules",), [{"geom": "*", "type": "S"}]),
        (("contact_rules",), [{"body": "*", "geom": "*", "type": "L"}]),
        (("contact_rules",), [{"body": "*", "type": "ignore", "mu": 0.5}]),
        (("mu",), -1.0),
        (("friction_edges",), 2),
        (("contact_tolerance",), 1.0),
        (("rvds",), [[1, 0, 0]]),
        (("ranges",), {"*": {}}),
        (("ranges",), {"*": {"actuator": True}}),
        (("ranges",), {"*": {"dcmotor": True, "polygon": [[0, 0]]}}),
        (("lift", "direction"), [0, 1]),
        (("refs",), {"weight": "yes"}),
    ],
)
def test_schema_and_loader_agree_on_invalid_documents(
    validator: jsonschema.Draft202012Validator, path: tuple[Any, ...], value: Any
) -> None:
    doc = _set(_case2(), path, value)
    assert list(validator.iter_errors(doc)), "the schema accepted it"
    with pytest.raises(GraspError):
        read_grasp_document(doc)


# Documents on both sides of the format's edges: case2 with one field set to the value.
EDGES = [
    (("friction_edges",), 16.0),
    (("friction_edges",), 3),
    (("friction_edges",), 256),
    (("friction_edges",), 257),
    (("friction_edges",), 16.5),
    (("friction_edges",), "16"),
    (("friction_edges",), True),
    (("mu",), 0),
    (("mu",), 0.0),
    (("mu",), "0.3"),
    (("contact_tolerance",), 0.01),
    (("contact_tolerance",), 0.0),
    (("contact_tolerance",), -1e-4),
    (("max_penetration",), 0.01),
    (("max_penetration",), 0.0),
    (("max_penetration",), 0.0101),
    (("max_penetration",), -1e-3),
    (("max_penetration",), "1e-3"),
    (("slip",), "shared"),
    (("slip",), "both"),
    (("joint_losses",), "ignore"),
    (("joint_losses",), "keep"),
    (("contacts", 0, "type"), "D"),
    (("contacts", 0, "type"), "d"),
    (("contact_rules",), [{"body": "*", "type": "ignore"}]),
    (("contact_rules",), [{"geom": "f?_link*", "type": "F", "mu": 0.0}]),
    (("contact_rules",), [{"geom": "*", "type": "D", "mu": 0.5}]),
    (("contact_rules",), [{"geom": "*", "type": "F", "mu": -0.5}]),
    (("contact_rules",), [{"geom": "*", "type": "f"}]),
    (("rvds",), [[1, 0, 0, 0, 0, 0]]),
    (("rvds",), []),
    (("name",), ""),
    (("name",), 7),
    (("model",), 7),
    (("configuration", "qpos", "hand"), [0, 0, 0.1, 1, 0, 0, 0]),
    (("configuration", "qpos", "hand"), [0, 0, 0.1, 1, 0, 0]),
    (("configuration", "qpos", "hand"), [0, 0, 0.1, 1, 0, 0, "0"]),
    (("configuration", "qpos", "hand"), [0, 0, 0.1, 1, 0, 0, 0, 0]),
    (("configuration", "base"), {"body": "mount", "position": [0, 0, 0.1]}),
    (("configuration", "base"), {"body": "mount", "quaternion": [1, 0, 0, 0]}),
    (("configuration", "base"), {"body": "mount"}),
    (("configuration", "base"), {"position": [0, 0, 0.1]}),
    (("configuration", "base"), {"body": "mount", "position": [0, 0]}),
    (("configuration", "base"), {"body": "mount", "position": [0, 0, 0], "pose": 1}),
]


@pytest.mark.parametrize(("path", "value"), EDGES)
def test_schema_and_reader_accept_the_same_documents(
    validator: jsonschema.Draft202012Validator, path: tuple[Any, ...], value: Any
) -> None:
    doc = _set(_case2(), path, value)
    schema_accepts = not list(validator.iter_errors(doc))
    try:
        read_grasp_document(doc)
        reader_accepts = True
    except GraspError:
        reader_accepts = False
    assert schema_accepts == reader_accepts, f"schema accepts: {schema_accepts}, reader: {reader_accepts}"


def test_the_documented_example_is_a_valid_grasp_document(validator: jsonschema.Draft202012Validator) -> None:
    """The annotated example of docs/grasp-format.md parses as TOML, passes the schema and the reader."""
    from pathlib import Path

    text = (Path(__file__).resolve().parents[3] / "docs" / "grasp-format.md").read_text(encoding="utf-8")
    start = text.index("```toml\n") + len("```toml\n")
    doc = tomllib.loads(text[start : text.index("```\n", start)])
    assert not list(validator.iter_errors(doc))
    normalised, _ = read_grasp_document(doc)
    assert normalised["supports"][0]["shape"] == "plane" and normalised["contacts"][1]["select"] == "body"


@pytest.mark.parametrize("name", ["allegro-ik", "gripper3-box"])
def test_the_test_hands_grasps_pass_the_schema(validator: jsonschema.Draft202012Validator, name: str) -> None:
    doc = tomllib.loads(shipped_grasps()[name].read_text(encoding="utf-8"))
    assert not list(validator.iter_errors(doc))


def _documented_example() -> dict[str, Any]:
    from pathlib import Path

    text = (Path(__file__).resolve().parents[3] / "docs" / "grasp-format.md").read_text(encoding="utf-8")
    start = text.index("```toml\n") + len("```toml\n")
    return tomllib.loads(text[start : text.index("```\n", start)])


# Values of every JSON type, the format's enums and edges, put in place of every field.
VALUES: list[Any] = [
    "x",
    "",
    "F",
    "S",
    "D",
    "plane",
    "box",
    "shared",
    0,
    -1,
    0.5,
    16.0,
    1e300,
    True,
    False,
    [],
    {},
    [0, 0, 0],
    [1, 0, 0, 0],
    [0, 0, 0, 0],
    [[1, 0], [0, 1]],
    [1, 2, 3, 4, 5, 6],
    {"geom": "g"},
]
# Keys added to every table: each is legal somewhere, and paired with another key in some rule.
EXTRA = {
    "slide": [1, 0, 0],
    "preload": 1.0,
    "mg": 1.0,
    "gear_ratio": 2.0,
    "speed_limit": 1.0,
    "twist": [0, 0, 1, 0, 0, 0],
    "direction": [0, 0, 1],
    "size": [0.01],
    "mass": 0.1,
    "shape": "box",
    "point": [0, 0, 0],
    "mu": 0.5,
    "zzz": 1,
}


@pytest.mark.parametrize("name", ["documented example", "allegro-ik", "case2"])
def test_the_loader_refuses_what_the_schema_refuses_and_only_beyond_it_more(
    validator: jsonschema.Draft202012Validator, name: str
) -> None:
    """Every field of a document set to values of every type, deleted, or joined by a key of a
    paired rule: the schema refuses => the loader refuses (a one-line message naming a field);
    the loader refuses a document the schema accepts only for a rule of ``BEYOND_SCHEMA``."""
    doc = _documented_example() if name == "documented example" else _case(name)
    counts = {"both accept": 0, "both refuse": 0, "beyond": 0}
    for mutated in mutations(doc, VALUES, EXTRA):
        schema_accepts = not list(validator.iter_errors(mutated))
        try:
            read_grasp_document(mutated)
        except GraspError as e:
            assert "\n" not in str(e) and e.field, str(e)
            assert schema_accepts is not True or e.beyond_schema, f"only the loader refuses: {e}"
            counts["beyond" if schema_accepts else "both refuse"] += 1
        else:
            assert schema_accepts, f"only the schema refuses: {schema_problem(mutated)}"
            counts["both accept"] += 1
    assert min(counts.values()) > 0, counts  # each side of the rule was exercised


def _case(name: str) -> dict[str, Any]:
    return tomllib.loads(shipped_grasps()[name].read_text(encoding="utf-8"))


@pytest.mark.parametrize(
    ("path", "value", "field", "problem"),
    [
        (
            ("object",),
            {"body": "object", "shape": "box", "size": [0.1], "mass": 1.0},
            "object.size",
            "expected 3 to 3 items, got a list of 1",
        ),
        (("contacts", 0, "type"), "X", "contacts[0].type", "expected one of F, L, S, D, got the string 'X'"),
        (
            ("contacts", 0, "colour"),
            "red",
            "contacts[0].colour",
            "unknown key (allowed: body, geom, geom_id, mu, mu_range, preload, slide, type)",
        ),
        (("mu",), -1, "mu", "expected a number >= 0, got the number -1"),
        (("friction_edges",), "16", "friction_edges", "expected an integer, got the string '16'"),
        (("configuration",), {}, "configuration", "expected exactly one of keyframe / qpos / ik"),
        (
            ("refs",),
            {"weight": False, "mg": 1.0, "wrenches": [[0, 0, 1, 0, 0, 0]]},
            "refs.mg",
            "only with weight = true",
        ),
        (
            ("lift",),
            {"direction": [0, 0, 1], "twist": [0, 0, 1, 0, 0, 0]},
            "lift",
            "expected at most one of direction, poses, twist",
        ),
        (("object",), {"body": "object", "shape": "box"}, "object.size", "required with shape"),
    ],
)
def test_the_schema_error_is_worded_as_one_field_and_its_problem(
    path: tuple[Any, ...], value: Any, field: str, problem: str
) -> None:
    assert schema_problem(_set(_case2(), path, value)) == (field, problem)
