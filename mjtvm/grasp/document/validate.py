r"""The rules of ``mjtvm.grasp/1`` beyond its JSON Schema, and the schema's verdict on a document.

The schema (``mjtvm/data/schema/grasp.schema.json``) is the format's one definition of
structure, types, bounds and option pairs: `mjtvm.grasp.document.document.read_grasp_document()`
refuses every document it refuses ([`mjtvm.formats.schema`][mjtvm.formats.schema]). The field checks of
`mjtvm.grasp.document.checks` word most refusals and are alone only on `BEYOND_SCHEMA`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from mjtvm.formats.schema import schema_problem as _schema_problem
from mjtvm.grasp.document.checks import key_of, kind_of

__all__ = ["BEYOND_SCHEMA", "schema_problem"]

#: The rules of the format that JSON Schema cannot state, each checked by the field checks
#: (``GraspError.beyond_schema`` is true for their refusals); docs/grasp-format.md lists them.
BEYOND_SCHEMA = (
    "a quaternion has norm 1 within 1e-6 (also a free joint's 7 numbers in configuration.qpos)",
    "a direction (contacts[].slide, lift.direction, lift.twist) is not zero",
    "a [low, high] pair (configuration.ik.bounds, lift.bounds) has low < high",
    "a friction interval (mu_range) has mu_lo <= mu <= mu_hi for its mu, on an F or S contact",
    "the REFS is more than the origin (weight, or a non-zero wrench)",
    "keys and strings hold no NUL character and no lone surrogate; nesting is at most 16 deep",
)


def schema_problem(doc: Mapping[str, Any]) -> tuple[str, str] | None:
    """The field and the problem of the grasp schema's most relevant error, or None when the
    document is valid, worded as the field checks word theirs.

    Parameters
    ----------
    doc
        A raw grasp document (the parsed TOML or JSON).
    """
    return _schema_problem("grasp", doc, describe=kind_of, key=key_of)
