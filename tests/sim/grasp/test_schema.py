"""The shipped JSON Schema of ``mjtvm.grasp/1`` (``mjtvm/data/schema/grasp.schema.json``): every
shipped grasp file passes it, and the schema and the loader agree on invalid documents."""

from __future__ import annotations

import copy
import json
import tomllib
from importlib import resources
from typing import Any

import jsonschema
import pytest

from mjtvm.sim.grasp.document import GraspError, read_grasp_document
from mjtvm.sim.grasp.file import shipped_grasps

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
    (("slip",), "shared"),
    (("slip",), "both"),
    (("joint_losses",), "ignore"),
    (("joint_losses",), "keep"),
    (("contacts", 0, "type"), "D"),
    (("contacts", 0, "type"), "d"),
    (("rvds",), [[1, 0, 0, 0, 0, 0]]),
    (("rvds",), []),
    (("name",), ""),
    (("name",), 7),
    (("model",), 7),
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
