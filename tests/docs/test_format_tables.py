"""The field tables of the format pages against the JSON Schemas of ``mjtvm/data/schema``.

Each field table of ``docs/grasp-format.md``, ``docs/state-format.md`` and
``docs/result-format.md`` follows a marker ``<!-- schema: FILE#POINTER -->``: the schema file
(in ``mjtvm/data/schema``) and the JSON pointer of the object whose keys the table documents
(``#`` for the top level, e.g. ``#/$defs/contact`` for a state's contact). The first column of
a row holds one or more field names as code spans; ``a.b`` documents the key ``b`` of the
object ``a``, or of each item of the list ``a`` (the grasp file's ``object.body``, the lift's
``poses.position``). The documented keys must be the schema's
``properties``, at the marker's object and at every object a dotted name reaches into. Where
a table has a ``required`` column, the rows that say ``yes`` must be the schema's
``required`` keys (the other values, such as "for F and S", are conditions the reader checks).
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCHEMAS = ROOT / "mjtvm" / "data" / "schema"
_MARKER = re.compile(r"<!--\s*schema:\s*([\w.-]+\.json)#(\S*)\s*-->")
_NAME = re.compile(r"`([^`]+)`")

#: The tables each page must mark: a page whose marker is lost fails here, not silently.
EXPECTED = {
    "grasp-format.md": [
        "grasp.schema.json#",
        "grasp.schema.json#/properties/contacts/items",
        "grasp.schema.json#/properties/contact_rules/items",
        "grasp.schema.json#/properties/configuration",
        "grasp.schema.json#/properties/refs",
        "grasp.schema.json#/properties/lift",
    ],
    "state-format.md": [
        "state.schema.json#",
        "state.schema.json#/$defs/joint",
        "state.schema.json#/$defs/contact",
        "state.schema.json#/$defs/transmission",
    ],
    "result-format.md": ["result.schema.json#", "result.schema.json#/$defs/witness", "tvms.schema.json#"],
}


def marked_tables(text: str) -> dict[str, list[str]]:
    """``{"FILE#POINTER": [documented name, ...]}``: the code spans of the first column of
    the table that follows each marker (blank lines may come between)."""
    return {key: [n for names, _ in rows for n in names] for key, rows in marked_rows(text).items()}


def marked_rows(text: str) -> dict[str, list[tuple[list[str], dict[str, str]]]]:
    """``{"FILE#POINTER": [(names of the first column, {header: cell}), ...]}`` for the table
    that follows each marker."""
    tables: dict[str, list[tuple[list[str], dict[str, str]]]] = {}
    lines = text.splitlines()
    for i, line in enumerate(lines):
        m = _MARKER.search(line)
        if not m:
            continue
        key = f"{m.group(1)}#{m.group(2)}"
        assert key not in tables, f"{key} is marked twice"
        j = i + 1
        while j < len(lines) and not lines[j].strip():
            j += 1
        assert j < len(lines) and lines[j].startswith("|"), f"no table after the marker {key}"
        header = [c.strip() for c in lines[j].strip().strip("|").split("|")]
        rows: list[tuple[list[str], dict[str, str]]] = []
        for row in lines[j + 2 :]:  # past the header and the |---| line
            if not row.startswith("|"):
                break
            cells = [c.strip() for c in row.strip().strip("|").split("|")]
            found = _NAME.findall(cells[0])
            assert found, f"{key}: a row without a field name: {row[:80]}"
            rows.append((found, dict(zip(header, cells))))
        tables[key] = rows
    return tables


def resolve(schema: dict[str, Any], pointer: str) -> dict[str, Any]:
    """The object at a JSON pointer (``/``-separated, ``~1`` and ``~0`` escapes), following a
    ``$ref`` inside the same schema."""
    node: Any = schema
    for part in [p for p in pointer.split("/") if p]:
        node = node[part.replace("~1", "/").replace("~0", "~")]
    if "$ref" in node:
        ref = node["$ref"]
        assert ref.startswith("#"), ref
        return resolve(schema, ref[1:])
    return node


def properties(schema: dict[str, Any], node: dict[str, Any]) -> dict[str, Any]:
    """An object schema's ``properties``, also when it is one branch of ``oneOf``/``anyOf``
    (e.g. an object or ``null``) or the items of an array (``poses.position``: the key
    ``position`` of each pose)."""
    if "$ref" in node:
        node = resolve(schema, node["$ref"][1:])
    if "properties" in node:
        return dict(node["properties"])
    if isinstance(node.get("items"), dict):
        return properties(schema, node["items"])
    for branch in node.get("oneOf", []) + node.get("anyOf", []):
        found = properties(schema, branch)
        if found:
            return found
    return {}


def disagreements(schema: dict[str, Any], node: dict[str, Any], names: list[str], where: str) -> list[str]:
    """What differs between the documented ``names`` and the properties of ``node``, and,
    for each dotted name, of the object it reaches into."""
    props = properties(schema, node)
    assert props, f"{where}: the schema has no properties there"
    top = {n.split(".", 1)[0] for n in names}
    out = [f"{where}: documented, not in the schema: {k!r}" for k in sorted(top - props.keys())]
    out += [f"{where}: in the schema, not documented: {k!r}" for k in sorted(props.keys() - top)]
    for parent, rest in _nested(names):
        if parent in props:
            out += disagreements(schema, props[parent], rest, f"{where}/properties/{parent}")
    return out


def _nested(names: list[str]) -> list[tuple[str, list[str]]]:
    """The dotted names ``a.b`` grouped by their first part: ``[("a", ["b", ...]), ...]``, sorted."""
    nested: dict[str, list[str]] = {}
    for n in names:
        if "." in n:
            parent, rest = n.split(".", 1)
            nested.setdefault(parent, []).append(rest)
    return sorted(nested.items())


def required_disagreements(
    schema: dict[str, Any], node: dict[str, Any], names: list[str], where: str
) -> list[str]:
    """What differs between the names documented as required and the schema's ``required``,
    at ``node`` and in the objects the dotted names reach into (``a.b`` required: ``a`` is a
    required key, ``b`` a required key of it)."""
    props = properties(schema, node)
    required = set(node.get("required", []))
    top = {n.split(".", 1)[0] for n in names}
    out = [
        f"{where}: documented as required, not required by the schema: {k!r}" for k in sorted(top - required)
    ]
    out += [
        f"{where}: required by the schema, not documented as required: {k!r}" for k in sorted(required - top)
    ]
    for parent, rest in _nested(names):
        if parent in props:
            out += required_disagreements(schema, props[parent], rest, f"{where}/properties/{parent}")
    return out


@pytest.mark.parametrize("page", sorted(EXPECTED))
def test_the_required_columns_are_the_schema(page: str) -> None:
    problems: list[str] = []
    for key, rows in marked_rows((ROOT / "docs" / page).read_text(encoding="utf-8")).items():
        if not rows or "required" not in rows[0][1]:
            continue
        file, pointer = key.split("#", 1)
        schema = json.loads((SCHEMAS / file).read_text(encoding="utf-8"))
        names = [n for found, cells in rows if cells["required"] == "yes" for n in found]
        problems += required_disagreements(schema, resolve(schema, pointer), names, key)
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("page", sorted(EXPECTED))
def test_the_field_tables_are_the_schema(page: str) -> None:
    tables = marked_tables((ROOT / "docs" / page).read_text(encoding="utf-8"))
    assert sorted(tables) == sorted(EXPECTED[page])
    problems: list[str] = []
    for key, names in tables.items():
        file, pointer = key.split("#", 1)
        schema = json.loads((SCHEMAS / file).read_text(encoding="utf-8"))
        problems += disagreements(schema, resolve(schema, pointer), names, key)
    assert not problems, "\n".join(problems)


def test_the_parser_reads_a_table_and_its_dotted_names() -> None:
    text = (
        "<!-- schema: x.schema.json#/$defs/a -->\n\n| key | meaning |\n|---|---|\n"
        "| `a`, `b.c` | two |\n| `b.d` | one |\n\ntext\n| `e` | not marked |\n"
    )
    assert marked_tables(text) == {"x.schema.json#/$defs/a": ["a", "b.c", "b.d"]}
    schema = {
        "$defs": {
            "a": {
                "properties": {
                    "a": {},
                    "b": {"oneOf": [{"type": "null"}, {"properties": {"c": {}, "d": {}, "f": {}}}]},
                }
            }
        }
    }
    assert disagreements(schema, resolve(schema, "/$defs/a"), ["a", "b.c", "b.d", "g"], "x") == [
        "x: documented, not in the schema: 'g'",
        "x/properties/b: in the schema, not documented: 'f'",
    ]
