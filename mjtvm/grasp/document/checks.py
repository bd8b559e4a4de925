r"""The value checks of a ``mjtvm.grasp/1`` document: the format's constants, `GraspError`
and the checker of values (types, bounds, unknown keys, text); the checks of each section of
the format are in [`mjtvm.grasp.document.sections`][mjtvm.grasp.document.sections], and `mjtvm.grasp.document.document` runs them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from mjtvm.errors import ModelError
from mjtvm.model.bounds import MAX_ABS

__all__ = [
    "CONTACT_TYPES",
    "MAX_DEPTH",
    "MAX_ITEMS",
    "RANGE_SOURCES",
    "REQUIRED_KEYS",
    "SCHEMA",
    "SELECTORS",
    "SHAPES",
    "SUPPORT_SHAPES",
    "TOP_KEYS",
    "Checker",
    "GraspError",
    "NoContactError",
    "check_text",
    "key_of",
    "kind_of",
]

SCHEMA = "mjtvm.grasp/1"
CONTACT_TYPES = ("F", "L", "S", "D")
SELECTORS = ("geom", "body", "geom_id")
RANGE_SOURCES = ("dcmotor", "datasheet", "actuator", "polygon")
MAX_ITEMS = 256  # contacts, targets, joints, poses, wrenches, RVDS vertices
MAX_DEPTH = 16  # a grasp document nests 6 levels (ranges.<pattern>.datasheet.<key>)

TOP_KEYS = {  # the keys a grasp document may have at the top level
    "schema",
    "name",
    "description",
    "notes",
    "source",
    "model",
    "object",
    "configuration",
    "joints",
    "mu",
    "friction_edges",
    "slip",
    "contact_tolerance",
    "max_penetration",
    "contacts",
    "ignore",
    "contact_rules",
    "refs",
    "rvds",
    "ranges",
    "lift",
    "supports",
    "joint_losses",
    "friction_margin",
    "mu_range",
    "cone",
    "joint_limits",
}
SHAPES = {"sphere": 1, "capsule": 2, "ellipsoid": 3, "cylinder": 2, "box": 3}  # geom size entries used
SUPPORT_SHAPES = {**SHAPES, "plane": 3}
REQUIRED_KEYS = ("schema", "model", "object", "configuration")  # and contacts or contact_rules


class GraspError(ModelError):
    """A grasp file breaks the ``mjtvm.grasp/1`` format or does not fit its model.

    Attributes
    ----------
    file
        The grasp file (or ``"grasp"`` for a mapping).
    field
        The offending field, e.g. ``"contacts[2].geom"``.
    beyond_schema
        True when the broken rule is one JSON Schema cannot state
        (`mjtvm.grasp.document.validate.BEYOND_SCHEMA`): the schema accepts the document.
    """

    def __init__(self, file: str, field: str, problem: str, *, beyond_schema: bool = False) -> None:
        self.file, self.field, self.beyond_schema = file, field, beyond_schema
        super().__init__(f"{file}: {field}" if field else file, problem)


class NoContactError(GraspError):
    """No contact the grasp needs touches the object within ``contact_tolerance``.

    Attributes
    ----------
    nearest
        m: the smallest signed distance between a geom outside the object and the object
        (up to 0.1 m), ``None`` when nothing is that close.
    """

    def __init__(self, file: str, field: str, problem: str, *, nearest: float | None) -> None:
        self.nearest = nearest
        super().__init__(file, field, problem)


class Checker:
    """Field checks that raise `GraspError` naming the field.

    Parameters
    ----------
    file
        The grasp file (or ``"grasp"`` for a mapping), named by every error.
    """

    def __init__(self, file: str) -> None:
        self.file = file

    def fail(self, field: str, problem: str) -> GraspError:
        return GraspError(self.file, field, problem)

    def beyond(self, field: str, problem: str) -> GraspError:
        """A rule of `BEYOND_SCHEMA` broken."""
        return GraspError(self.file, field, problem, beyond_schema=True)

    def table(
        self, value: Any, field: str, allowed: set[str], required: Sequence[str] = ()
    ) -> Mapping[str, Any]:
        if not isinstance(value, Mapping):
            raise self.fail(field, f"expected a table (object), got {kind_of(value)}")
        unknown = sorted(key_of(k) for k in value if k not in allowed)
        if unknown:
            raise self.fail(
                f"{field}.{unknown[0]}" if field else unknown[0],
                f"unknown key (allowed: {', '.join(sorted(allowed))})",
            )
        for key in required:
            if key not in value:
                raise self.fail(f"{field}.{key}" if field else key, "required")
        return value

    def string(self, value: Any, field: str) -> str:
        if not isinstance(value, str) or not value or len(value) > 1000:
            raise self.fail(field, f"expected a non-empty string, got {kind_of(value)}")
        return value

    def number(self, value: Any, field: str, *, low: float | None = None, positive: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(field, f"expected a number, got {kind_of(value)}")
        x = float(value) if abs(value) < 1e300 else math.inf
        if not math.isfinite(x) or abs(x) > MAX_ABS:
            raise self.fail(field, f"expected a finite number with |x| <= {MAX_ABS:g}, got {value!r}")
        if (low is not None and x < low) or (positive and x <= 0):
            raise self.fail(field, f"expected a number {'> 0' if positive else f'>= {low:g}'}, got {value!r}")
        return x

    def integer(self, value: Any, field: str, low: int, high: int) -> int:
        # JSON Schema counts 16.0 as an integer; the reader does too, so that it and
        # grasp.schema.json accept the same documents
        whole = isinstance(value, int) or (isinstance(value, float) and value.is_integer())
        if isinstance(value, bool) or not whole or not low <= value <= high:
            raise self.fail(field, f"expected an integer in [{low}, {high}], got {value!r}")
        return int(value)

    def vector(self, value: Any, field: str, n: int) -> list[float]:
        if not isinstance(value, list) or len(value) != n:
            raise self.fail(field, f"expected a list of {n} numbers, got {kind_of(value)}")
        return [self.number(x, f"{field}[{i}]") for i, x in enumerate(value)]

    def vectors(self, value: Any, field: str, n: int) -> list[list[float]]:
        if not isinstance(value, list) or not value or len(value) > MAX_ITEMS:
            raise self.fail(field, f"expected a list of 1 to {MAX_ITEMS} vectors of {n} numbers")
        return [self.vector(v, f"{field}[{i}]", n) for i, v in enumerate(value)]

    def names(self, value: Any, field: str) -> list[str]:
        if not isinstance(value, list) or not value or len(value) > MAX_ITEMS:
            raise self.fail(field, f"expected a list of 1 to {MAX_ITEMS} names")
        return [self.string(v, f"{field}[{i}]") for i, v in enumerate(value)]

    def number_map(self, value: Any, field: str) -> dict[str, float]:
        if not isinstance(value, Mapping) or len(value) > MAX_ITEMS:
            raise self.fail(field, f"expected a table of name = number, got {kind_of(value)}")
        return {str(k): self.number(v, f"{field}.{key_of(k)}") for k, v in value.items()}

    def bounds(self, value: Any, field: str) -> dict[str, tuple[float, float]]:
        if not isinstance(value, Mapping) or len(value) > MAX_ITEMS:
            raise self.fail(field, f"expected a table of joint = [low, high], got {kind_of(value)}")
        out = {}
        for k, v in value.items():
            lo, hi = self.vector(v, f"{field}.{key_of(k)}", 2)
            if not lo < hi:
                raise self.beyond(f"{field}.{key_of(k)}", f"expected low < high, got [{lo:g}, {hi:g}]")
            out[str(k)] = (lo, hi)
        return out

    def selector(self, value: Any, field: str, extra: set[str]) -> dict[str, Any]:
        t = self.table(value, field, {*SELECTORS, *extra})
        chosen = [k for k in SELECTORS if k in t]
        if len(chosen) != 1:
            raise self.fail(field, f"expected exactly one of {', '.join(SELECTORS)}, got {len(chosen)}")
        key = chosen[0]
        target = (
            self.integer(t[key], f"{field}.{key}", 0, 10**6)
            if key == "geom_id"
            else self.string(t[key], f"{field}.{key}")
        )
        return {"select": key, "target": target, **{k: v for k, v in t.items() if k not in SELECTORS}}


def key_of(key: Any) -> str:
    """A key of the document as a field name: as written when it prints on one line, else its
    ``repr`` (``'fro\\nbnicate'``), so that an error naming it stays one line."""
    text = str(key)
    return text if text.isprintable() and text == text.strip() and text else repr(text)


def check_text(doc: Mapping[str, Any], c: Checker) -> None:
    """Refuse a lone surrogate (JSON's ``"\\ud800"``) or a NUL character in any key or string:
    neither reaches MuJoCo's C names (nor a UTF-8 stream) intact.

    Parameters
    ----------
    doc
        The raw document, as read.
    c
        The checker naming the file.

    Raises
    ------
    GraspError
        The first such key or string (beyond the schema), or nesting deeper than `MAX_DEPTH`.
    """
    stack: list[tuple[Any, str, int]] = [(doc, "", 0)]
    while stack:
        node, field, depth = stack.pop()
        if depth > MAX_DEPTH and isinstance(node, (Mapping, list)):  # also a mapping that holds itself
            raise c.beyond(field, f"nested deeper than {MAX_DEPTH} levels")
        if isinstance(node, Mapping):
            for key, value in node.items():
                name = f"{field}.{key_of(key)}" if field else key_of(key)
                _check_string(str(key), name, c, "key")
                stack.append((value, name, depth + 1))
        elif isinstance(node, list):
            stack.extend((value, f"{field}[{i}]", depth + 1) for i, value in enumerate(node))
        elif isinstance(node, str):
            _check_string(node, field, c, "string")


def _check_string(text: str, field: str, c: Checker, what: str) -> None:
    if "\0" in text:
        raise c.beyond(field, f"expected a {what} without NUL characters, got {text[:40]!r}")
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as e:
        raise c.beyond(
            field,
            f"expected a {what} of valid Unicode text, got a lone surrogate {text[e.start]!r} in {text[:40]!r}",
        ) from e


def kind_of(value: Any) -> str:
    """What ``value`` is, for a message: ``"nothing"``, ``"a boolean (true)"``, ``"the number 3"``,
    ``"the string 'x'"`` (its first 40 characters), ``"a list of 2"``, ``"a table"`` or its type's
    name.

    Parameters
    ----------
    value
        A value of the document.

    Returns
    -------
    str
        Its description.
    """
    if value is None:
        return "nothing"
    if isinstance(value, bool):
        return f"a boolean ({str(value).lower()})"
    if isinstance(value, (int, float)):
        return f"the number {value!r}"
    if isinstance(value, str):
        return f"the string {value[:40]!r}"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    if isinstance(value, Mapping):
        return "a table"
    return type(value).__name__
