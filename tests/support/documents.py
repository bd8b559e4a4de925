"""Writers of grasp documents and scenarios, for the tests and ``tools/make_scenarios.py``.

The package reads TOML and JSON (``tomllib``, ``json``) but never writes a grasp file, so these
writers live with the test oracles: `format_toml()` writes a ``mjtvm.grasp/1`` mapping as TOML
that ``tomllib`` reads back to the same values, `format_document()` a scenario as compact JSON.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from typing import Any

__all__ = ["format_document", "format_toml"]


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        text = repr(float(value)) if isinstance(value, float) else str(value)
        return text if math.isfinite(float(value)) else "nan"  # the reader refuses nan
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)  # a JSON string is a TOML basic string
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"no TOML form for {type(value).__name__}")


def _toml_key(key: str) -> str:
    return key if key.replace("_", "").replace("-", "").isalnum() and key.isascii() else json.dumps(key)


def format_toml(doc: Mapping[str, Any]) -> str:
    """TOML text of a grasp document: scalars and lists at the top (a list of strings one item
    per line), then one ``[table]`` per mapping (a mapping of more than three entries inside
    it as its own ``[table.key]``), then ``[[array]]`` per list of mappings. Floats as
    ``repr``: ``tomllib`` reads back the same doubles."""
    head, tables, arrays = [], [], []
    for key, value in doc.items():
        k = _toml_key(key)
        if isinstance(value, Mapping):
            rows, subs = [], []
            for a, b in value.items():
                if isinstance(b, Mapping) and len(b) > 3:
                    body = "\n".join(f"{_toml_key(x)} = {_toml_value(y)}" for x, y in b.items())
                    subs.append(f"\n[{k}.{_toml_key(a)}]\n{body}\n")
                else:
                    rows.append(f"{_toml_key(a)} = {_toml_value(b)}")
            tables.append(f"\n[{k}]\n" + "".join(r + "\n" for r in rows) + "".join(subs))
        elif isinstance(value, list) and value and all(isinstance(v, Mapping) for v in value):
            for item in value:
                rows = [f"{_toml_key(a)} = {_toml_value(b)}\n" for a, b in item.items()]
                arrays.append(f"\n[[{k}]]\n" + "".join(rows))
        elif isinstance(value, list) and value and all(isinstance(v, (str, list)) for v in value):
            head.append(f"{k} = [\n" + "".join(f"  {_toml_value(v)},\n" for v in value) + "]")
        else:
            head.append(f"{k} = {_toml_value(value)}")
    return "\n".join(head) + "\n" + "".join(tables) + "".join(arrays)


def format_document(doc: Any, indent: int = 0) -> str:
    """JSON text; a list or object of scalars and flat lists fitting in 100 columns stays on one line."""
    text = json.dumps(doc)  # floats as repr: exact round trip
    if not isinstance(doc, (dict, list)):
        return text
    items = list(doc.values()) if isinstance(doc, dict) else doc
    flat = all(
        not isinstance(x, dict) and not any(isinstance(y, (dict, list)) for y in x)
        if isinstance(x, list)
        else not isinstance(x, dict)
        for x in items
    )
    if len(text) + indent <= 100 and flat:
        return text
    pad = " " * (indent + 1)
    if isinstance(doc, dict):
        rows = [f"{pad}{json.dumps(k)}: {format_document(v, indent + 1)}" for k, v in doc.items()]
        return "{\n" + ",\n".join(rows) + "\n" + " " * indent + "}"
    rows = [f"{pad}{format_document(x, indent + 1)}" for x in doc]
    return "[\n" + ",\n".join(rows) + "\n" + " " * indent + "]"
