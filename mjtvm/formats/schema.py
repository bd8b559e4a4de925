r"""The shipped JSON Schemas (``mjtvm/data/schema/*.schema.json``) as the loaders' gate.

A format's schema is its one definition of structure, types, bounds and option pairs: the
state loader ([`mjtvm.formats.state_file.load_state()`][mjtvm.formats.state_file.load_state]) and the grasp loader
(`mjtvm.grasp.document.document.read_grasp_document()`) refuse every document the schema
refuses, so a tool that checks files with the schema refuses nothing mjtvm would accept. The
loaders' own field checks run as well, because they normalise the document and word most
refusals better; the rules JSON Schema cannot state are theirs alone (listed in each format's
page). [`schema_problem()`][mjtvm.formats.schema.schema_problem] words the validator's most relevant error in the loaders' form,
``field: expected ..., got ...``.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from functools import cache
from importlib import resources
from typing import TYPE_CHECKING, Any

import numpy as np

from mjtvm.model.bounds import describe

if TYPE_CHECKING:
    import jsonschema

__all__ = ["load_schema", "schema_problem"]

_TYPES = {
    "object": "a table (object)",
    "array": "a list",
    "number": "a number",
    "integer": "an integer",
    "string": "a string",
    "boolean": "true or false",
    "null": "null",
}


@cache
def load_schema(name: str) -> dict[str, Any]:
    """The shipped JSON Schema (Draft 2020-12) of ``mjtvm.<name>/1``, read once.

    Parameters
    ----------
    name
        ``"state"``, ``"grasp"``, ``"result"`` or ``"tvms"``.
    """
    text = resources.files("mjtvm.data").joinpath(f"schema/{name}.schema.json").read_text(encoding="utf-8")
    schema: dict[str, Any] = json.loads(text)
    return schema


@cache
def _validator(name: str) -> jsonschema.Draft202012Validator:
    import jsonschema  # 50 ms: only when a document is read

    return jsonschema.Draft202012Validator(load_schema(name))


def schema_problem(
    name: str,
    doc: Mapping[str, Any],
    *,
    describe: Callable[[Any], str] = describe,
    key: Callable[[Any], str] = str,
) -> tuple[str, str] | None:
    """The field and the problem of the schema's most relevant error; None for a valid document.

    Parameters
    ----------
    name
        The format, as for [`load_schema()`][mjtvm.formats.schema.load_schema].
    doc
        The decoded document; numpy arrays and scalars in it are read as JSON lists and numbers.
    describe, key
        How a value and a mapping key are written in the message (the loader's own words).

    Returns
    -------
    tuple of (str, str) or None
        e.g. ``("contacts[2].type", "expected one of F, L, S, D, got the string 'X'")``.
    """
    from jsonschema.exceptions import best_match

    error = best_match(_validator(name).iter_errors(_plain(doc)))
    if error is None:
        return None
    field = "".join(f"[{p}]" if isinstance(p, int) else f".{key(p)}" for p in error.absolute_path)
    return _explain(error, field.lstrip("."), describe, key)


def _plain(value: Any) -> Any:
    """The document as the JSON it stands for (numpy arrays as lists)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _explain(
    error: jsonschema.ValidationError, field: str, describe: Callable[[Any], str], key: Callable[[Any], str]
) -> tuple[str, str]:
    """One validator's error as (field, problem)."""
    rule, value, schema, got = error.validator, error.validator_value, error.schema, describe(error.instance)

    def join(k: Any) -> str:
        return f"{field}.{key(k)}" if field else key(k)

    if rule == "required":
        missing = [k for k in value if isinstance(error.instance, Mapping) and k not in error.instance]
        return join(missing[0] if missing else value[0]), "required"
    if rule == "dependentRequired":
        for have, needs in value.items():
            missing = [k for k in needs if have in error.instance and k not in error.instance]
            if missing:
                return join(missing[0]), f"required with {have}"
    if rule == "additionalProperties":
        allowed = set(schema.get("properties", {}))
        unknown = sorted(key(k) for k in error.instance if k not in allowed)
        return join(unknown[0]), f"unknown key (allowed: {', '.join(sorted(allowed))})"
    if rule == "type":
        kinds = [value] if isinstance(value, str) else value
        return field, f"expected {' or '.join(_TYPES.get(k, k) for k in kinds)}, got {got}"
    if rule == "enum":
        return field, f"expected one of {', '.join(map(str, value))}, got {got}"
    if rule == "const":
        return field, f"expected {json.dumps(value)}, got {got}"
    if rule in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        sign = {"minimum": ">=", "maximum": "<=", "exclusiveMinimum": ">", "exclusiveMaximum": "<"}[rule]
        return field, f"expected a number {sign} {value:g}, got {got}"
    if rule in ("minItems", "maxItems", "minLength", "maxLength", "minProperties", "maxProperties"):
        what = {"I": "items", "L": "characters", "P": "entries"}[rule[3]]
        low, high = schema.get(f"min{rule[3:]}", 0), schema.get(f"max{rule[3:]}")
        span = f"{low} to {high}" if high is not None else f"at least {low}"
        return field, f"expected {span} {what}, got {got}"
    if rule == "oneOf" and all(set(s) == {"required"} for s in value):
        return field, "expected exactly one of " + " / ".join(" + ".join(s["required"]) for s in value)
    if rule == "anyOf" and all(set(s) == {"required"} for s in value):
        keys = [k for s in value for k in s["required"]]
        return join(keys[0]), f"required (or {', '.join(map(key, keys[1:]))})"
    if rule == "not" and "required" in value:
        return join(value["required"][0]), schema.get("description", "not allowed here")
    if rule == "not" and "anyOf" in value:
        keys = sorted({k for s in value["anyOf"] for k in s.get("required", ())})
        return field, "expected at most one of " + ", ".join(keys)
    return field, f"breaks the format's {rule} rule, got {got}"
