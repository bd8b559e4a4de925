r"""Reading and checking a ``mjtvm.grasp/1`` document (``docs/grasp-format.md``).

`read_grasp_document()` reads a TOML or JSON grasp file (or takes a mapping) and checks
its structure field by field: unknown keys, wrong types, missing or conflicting choices
(one of ``keyframe``/``qpos``/``ik``; one selector per contact; one source per operation
range) and numbers outside the format's bounds are each one `GraspError` naming the
field, e.g. ``contacts[2].type: expected one of F, L, S, D, got 'X'``. Names are checked
against the model later ([`mjtvm.grasp.resolve.file`][mjtvm.grasp.resolve.file]). Every document is also validated
with the JSON Schema ``mjtvm/data/schema/grasp.schema.json`` ([`mjtvm.grasp.document.validate`][mjtvm.grasp.document.validate]):
what it refuses is refused, so the two cannot disagree.
"""

from __future__ import annotations

import json
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from mjtvm.grasp.document.checks import (
    MAX_ITEMS,
    REQUIRED_KEYS,
    SCHEMA,
    SHAPES,
    SUPPORT_SHAPES,
    TOP_KEYS,
    Checker,
    GraspError,
    check_text,
    kind_of,
)
from mjtvm.grasp.document.sections import (
    check_configuration,
    check_contact_rules,
    check_contacts,
    check_joint_limits,
    check_lift,
    check_quaternion,
    check_ranges,
    check_refs,
    check_shape,
    mu_range,
)
from mjtvm.grasp.document.validate import schema_problem
from mjtvm.model.bounds import MAX_FILE_BYTES, MAX_FRICTION_EDGES, MIN_FRICTION_EDGES

__all__ = ["SCHEMA", "GraspError", "read_grasp_document"]


def _load(source: str | Path | Mapping[str, Any]) -> tuple[dict[str, Any], Path | None, str]:
    """The raw document, its path (None for a mapping) and a label for messages."""
    if isinstance(source, Mapping):
        return dict(source), None, "grasp"
    path = Path(source)
    label = str(path)
    if path.suffix.lower() not in (".toml", ".json"):
        raise GraspError(label, "", f"expected a .toml or .json file, got {path.suffix or 'no suffix'!r}")
    try:
        with path.open("rb") as f:
            raw = f.read(MAX_FILE_BYTES + 1)
    except (OSError, ValueError) as e:
        raise GraspError(label, "", f"cannot read the grasp file: {getattr(e, 'strerror', None) or e}") from e
    if len(raw) > MAX_FILE_BYTES:
        raise GraspError(label, "", f"larger than {MAX_FILE_BYTES} bytes: not a grasp file")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise GraspError(label, "", f"not UTF-8 text: byte 0x{raw[e.start]:02x} at offset {e.start}") from e
    if path.suffix.lower() == ".toml":
        try:
            doc: Any = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise GraspError(label, "", f"malformed TOML: {e}") from e
    else:
        try:
            doc = json.loads(text)
        except (json.JSONDecodeError, RecursionError, ValueError) as e:
            raise GraspError(label, "", f"malformed JSON: {e}") from e
    if not isinstance(doc, dict):
        raise GraspError(label, "", "expected a table (JSON object) at the top level")
    return doc, path, label


def read_grasp_document(source: str | Path | Mapping[str, Any]) -> tuple[dict[str, Any], Path | None]:
    r"""The checked grasp document and the file's path (``None`` for a mapping).

    The returned document is normalised: selectors as ``{"select": "geom"|"body"|"geom_id",
    "target": ...}``; numbers as floats; defaults filled in (``mu`` None, ``friction_edges``
    16, ``slip`` ``"per_contact"``, ``contact_tolerance`` 1e-4 m, ``max_penetration`` 1e-3 m,
    ``refs`` the weight, ``rvds`` None, ``ranges`` {}, ``lift`` None, ``ignore``, ``contacts``
    and ``contact_rules`` []).

    Raises
    ------
    GraspError
        Unreadable file, malformed TOML/JSON, or a field breaking the format (named).
    """
    raw, path, label = _load(source)
    c = Checker(label)
    check_text(raw, c)  # before the validator: it recurses as deep as the document
    problem = schema_problem(raw)
    doc = _normalise(raw, path, c)  # its refusal is worded for the field; the schema refuses too
    if problem is not None:
        raise GraspError(label, *problem)
    return doc, path


def _normalise(raw: Mapping[str, Any], path: Path | None, c: Checker) -> dict[str, Any]:
    """The document with defaults filled in, selectors and numbers normalised; a
    `GraspError` for the first field breaking the format."""
    doc = dict(c.table(raw, "", TOP_KEYS, REQUIRED_KEYS))
    if doc["schema"] != SCHEMA:
        raise c.fail("schema", f"expected {SCHEMA!r}, got {doc['schema']!r}")
    doc["name"] = c.string(doc.get("name", path.stem if path else "grasp"), "name")
    for key in ("description", "source"):
        if key in doc and not isinstance(doc[key], str):
            raise c.fail(key, f"expected a string, got {kind_of(doc[key])}")
    if "notes" in doc and not (
        isinstance(doc["notes"], list) and all(isinstance(n, str) for n in doc["notes"])
    ):
        raise c.fail("notes", f"expected a list of strings, got {kind_of(doc['notes'])}")
    doc["model"] = c.string(doc["model"], "model")
    obj = c.table(
        doc["object"], "object", {"body", "position", "quaternion", "shape", "size", "mass"}, ("body",)
    )
    doc["object"] = {
        "body": c.string(obj["body"], "object.body"),
        "position": c.vector(obj["position"], "object.position", 3) if "position" in obj else None,
        "quaternion": check_quaternion(c, obj["quaternion"], "object.quaternion")
        if "quaternion" in obj
        else None,
        **check_shape(c, obj, "object", SHAPES, mass=True),
    }
    supports = doc.get("supports", [])
    if not isinstance(supports, list) or len(supports) > MAX_ITEMS:
        raise c.fail("supports", f"expected a list of support geoms to add, got {kind_of(supports)}")
    doc["supports"] = []
    for i, item in enumerate(supports):
        t = c.table(
            item,
            f"supports[{i}]",
            {"name", "shape", "size", "position", "quaternion"},
            ("name", "shape", "size"),
        )
        doc["supports"].append(
            {
                "name": c.string(t["name"], f"supports[{i}].name"),
                "position": c.vector(t["position"], f"supports[{i}].position", 3)
                if "position" in t
                else [0.0] * 3,
                "quaternion": check_quaternion(c, t["quaternion"], f"supports[{i}].quaternion")
                if "quaternion" in t
                else [1.0, 0.0, 0.0, 0.0],
                **check_shape(c, t, f"supports[{i}]", SUPPORT_SHAPES, mass=False),
            }
        )
    doc["configuration"] = check_configuration(c, doc["configuration"])
    doc["joints"] = c.names(doc["joints"], "joints") if "joints" in doc else None
    doc["mu"] = c.number(doc["mu"], "mu", low=0.0) if "mu" in doc else None
    doc["friction_margin"] = c.number(doc.get("friction_margin", 0.0), "friction_margin", low=0.0)
    if doc["friction_margin"] >= 1.0:
        raise c.fail("friction_margin", f"expected a number in [0, 1), got {doc['friction_margin']!r}")
    doc["mu_range"] = mu_range(c, doc["mu_range"], "mu_range") if "mu_range" in doc else None
    if doc["mu_range"] is not None and (
        doc["mu"] is None or not doc["mu_range"][0] <= doc["mu"] <= doc["mu_range"][1]
    ):
        raise c.beyond("mu_range", f"expected [mu_lo, mu_hi] around the top-level mu ({doc['mu']!r})")
    doc["cone"] = doc.get("cone", "elliptic")
    if doc["cone"] not in ("elliptic", "pyramidal", "model"):
        raise c.fail("cone", f"expected 'elliptic', 'pyramidal' or 'model', got {doc['cone']!r}")
    doc["friction_edges"] = c.integer(
        doc.get("friction_edges", 16), "friction_edges", MIN_FRICTION_EDGES, MAX_FRICTION_EDGES
    )
    doc["slip"] = doc.get("slip", "per_contact")
    if doc["slip"] not in ("per_contact", "shared"):
        raise c.fail("slip", f"expected 'per_contact' or 'shared', got {doc['slip']!r}")
    doc["contact_tolerance"] = c.number(doc.get("contact_tolerance", 1e-4), "contact_tolerance", low=0.0)
    if doc["contact_tolerance"] > 0.01:
        raise c.fail("contact_tolerance", f"expected at most 0.01 m, got {doc['contact_tolerance']:g}")
    doc["max_penetration"] = c.number(doc.get("max_penetration", 1e-3), "max_penetration", low=0.0)
    if doc["max_penetration"] > 0.01:
        raise c.fail("max_penetration", f"expected at most 0.01 m, got {doc['max_penetration']:g}")
    if "contacts" not in doc and "contact_rules" not in doc:
        raise c.fail("contacts", "required (or contact_rules)")
    doc["contacts"] = check_contacts(c, doc["contacts"]) if "contacts" in doc else []
    ignore = doc.get("ignore", [])
    if not isinstance(ignore, list) or len(ignore) > MAX_ITEMS:
        raise c.fail(
            "ignore", f"expected a list of selections (geom, body or geom_id), got {kind_of(ignore)}"
        )
    doc["ignore"] = [c.selector(s, f"ignore[{i}]", set()) for i, s in enumerate(ignore)]
    doc["contact_rules"] = check_contact_rules(c, doc["contact_rules"]) if "contact_rules" in doc else []
    doc["refs"] = check_refs(c, doc.get("refs", {}))
    doc["rvds"] = c.vectors(doc["rvds"], "rvds", 6) if doc.get("rvds") is not None else None
    doc["ranges"] = check_ranges(c, doc.get("ranges", {}))
    doc["joint_losses"] = doc.get("joint_losses", "fold")
    if doc["joint_losses"] not in ("fold", "ignore"):
        raise c.fail("joint_losses", f"expected 'fold' or 'ignore', got {doc['joint_losses']!r}")
    doc["lift"] = check_lift(c, doc["lift"]) if "lift" in doc else None
    doc["joint_limits"] = check_joint_limits(c, doc.get("joint_limits", {}))
    return doc
