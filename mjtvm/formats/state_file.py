r"""The ``mjtvm.state/1`` and ``mjtvm.state/2`` JSON files of a [`GraspState`][mjtvm.model.state.GraspState]
(``docs/state-format.md``; JSON Schema ``mjtvm/data/schema/state.schema.json``).

Version 2 adds a ``transmission`` (actuators with their moment rows and operation ranges,
equality constraints, joint damping: [`mjtvm.model.transmission`][mjtvm.model.transmission]); a state without one
is written as version 1, and both versions are read.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mjtvm.errors import StateError
from mjtvm.formats.files import atomic_write
from mjtvm.formats.schema import schema_problem
from mjtvm.model.bounds import (
    MAX_CONTACTS,
    MAX_FILE_BYTES,
    MAX_JOINTS,
    check_json_tree,
    checked_name,
    describe,
    float_array,
    number,
)
from mjtvm.model.contacts import Contact
from mjtvm.model.limits import JointLimits
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import SCHEMA, SCHEMA_V2, GraspState
from mjtvm.model.transmission import transmission_from_dict, transmission_to_dict

__all__ = ["dump_state", "load_state", "parse_state", "state_to_dict"]

_TOP_KEYS = {
    "schema",
    "space",
    "object_position",
    "joints",
    "gravity_torque",
    "contacts",
    "refs",
    "rvds",
    "friction_edges",
    "slip",
    "transmission",
    "friction_margin",
    "joint_limits",
}
_REQUIRED_TOP = ("schema", "space", "object_position", "joints", "gravity_torque", "contacts", "refs")
_JOINT_KEYS = {"name", "operation_range"}
_LIMIT_KEYS = {"position", "range"}  # optional on every joint, together (mjtvm.model.limits)
_LIMIT_OPTION_KEYS = {"tolerance", "horizon"}
_CONTACT_KEYS = {
    "name",
    "type",
    "position",
    "normal",
    "mu",
    "jacobian",
    "tangent",
    "slide_direction",
    "preload",
    "mu_range",
}
_REQUIRED_CONTACT = ("name", "type", "position", "normal", "jacobian")


def _check_keys(obj: Any, allowed: set[str], required: Sequence[str], where: str) -> Mapping[str, Any]:
    if not isinstance(obj, Mapping):
        raise StateError(where, f"expected a JSON object, got {type(obj).__name__}")
    unknown = sorted(set(obj) - allowed)
    if unknown:
        prefix = f"{where}." if where else ""
        raise StateError(f"{prefix}{unknown[0]}", f"unknown key (allowed: {', '.join(sorted(allowed))})")
    for key in required:
        if key not in obj:
            prefix = f"{where}." if where else ""
            raise StateError(f"{prefix}{key}", "required key is missing")
    return obj


def _contact_from_dict(obj: Mapping[str, Any]) -> Contact:
    kwargs = {k: obj[k] for k in _CONTACT_KEYS if k in obj}
    return Contact(**kwargs)


def parse_state(data: Mapping[str, Any]) -> GraspState:
    """Validate a decoded ``mjtvm.state/1`` document and build a [`GraspState`][mjtvm.model.state.GraspState].

    ``data`` is expected to be plain JSON data (see [`load_state()`][mjtvm.formats.state_file.load_state], which also checks
    the nesting depth and the value types of a mapping before calling this).
    """
    _check_keys(data, _TOP_KEYS, _REQUIRED_TOP, "")
    if data["schema"] not in (SCHEMA, SCHEMA_V2):
        raise StateError(
            "schema", f"expected {SCHEMA!r} or {SCHEMA_V2!r}, got {describe(data['schema'])}", data["schema"]
        )
    driven = "transmission" not in data  # else the ranges belong to the transmission's actuators
    if not driven and data["schema"] == SCHEMA:
        raise StateError("transmission", f"a transmission needs {SCHEMA_V2!r}")
    joints = data["joints"]
    if not isinstance(joints, (list, tuple)):
        raise StateError("joints", f"expected a list of joints, got {describe(joints)}")
    if len(joints) > MAX_JOINTS:  # before building anything from them
        raise StateError("joints", f"expected at most {MAX_JOINTS} joints, got {len(joints)}")
    names, ranges = [], []
    for i, j in enumerate(joints):
        keys = _JOINT_KEYS if driven else {"name"}
        _check_keys(j, keys | _LIMIT_KEYS, tuple(sorted(keys)), f"joints[{i}]")
        names.append(checked_name(j["name"], f"joints[{i}].name"))
        if driven:
            try:
                ranges.append(OperationRange(j["operation_range"]))
            except StateError as e:
                raise e.under(f"joints[{i}].operation_range") from None
    if not driven:
        kwargs_t = transmission_from_dict(data["transmission"])
        ranges = list(kwargs_t[1])
    contacts_in = data["contacts"]
    if not isinstance(contacts_in, (list, tuple)):
        raise StateError("contacts", f"expected a list of contacts, got {describe(contacts_in)}")
    if len(contacts_in) > MAX_CONTACTS:
        raise StateError("contacts", f"expected at most {MAX_CONTACTS} contacts, got {len(contacts_in)}")
    contacts = []
    for i, c in enumerate(contacts_in):
        _check_keys(c, _CONTACT_KEYS, _REQUIRED_CONTACT, f"contacts[{i}]")
        try:
            contact = _contact_from_dict(c)
        except StateError as e:
            raise e.under(f"contacts[{i}]") from None
        contacts.append(contact)
    kwargs: dict[str, Any] = {} if driven else {"transmission": kwargs_t[0]}
    if "friction_edges" in data:
        kwargs["friction_edges"] = data["friction_edges"]
    if "slip" in data:
        kwargs["slip"] = data["slip"]
    if "friction_margin" in data:
        kwargs["friction_margin"] = data["friction_margin"]
    limits = _joint_limits(data, joints)
    if limits is not None:
        kwargs["joint_limits"] = limits
    if "rvds" in data:
        # JSON null would mean "absent" to GraspState: refuse it, the format says "omit the key".
        if data["rvds"] is None:
            raise StateError(
                "rvds", "expected a non-empty list of twists (omit the key for no RVDS), got null"
            )
        kwargs["rvds"] = data["rvds"]
    return GraspState(
        space=data["space"],
        object_position=data["object_position"],
        joint_names=tuple(names),
        operation_ranges=tuple(ranges),
        gravity_torque=data["gravity_torque"],
        contacts=tuple(contacts),
        refs=data["refs"],
        **kwargs,
    )


def _joint_limits(data: Mapping[str, Any], joints: Sequence[Any]) -> JointLimits | None:
    """The joints' ``position`` and ``range`` (both or neither on each joint) and the
    top-level ``joint_limits`` options, as `JointLimits`; ``None``
    when no joint has a range."""
    pos, lo, hi = [], [], []
    for i, j in enumerate(joints):
        has = [k in j for k in ("position", "range")]
        if has[0] != has[1]:
            missing = "range" if has[0] else "position"
            raise StateError(
                f"joints[{i}].{missing}", "required with the joint's " + ("position" if has[0] else "range")
            )
        if not has[0]:
            pos.append(0.0)
            lo.append(-float("inf"))
            hi.append(float("inf"))
            continue
        pos.append(number(j["position"], f"joints[{i}].position"))
        rng = float_array(j["range"], f"joints[{i}].range", ndim=1, max_len=2, what="[lower, upper]")
        if rng.shape != (2,):
            raise StateError(f"joints[{i}].range", f"expected [lower, upper], got {rng.shape[0]} numbers")
        lo.append(float(rng[0]))
        hi.append(float(rng[1]))
    options = data.get("joint_limits")
    if options is not None:
        _check_keys(options, _LIMIT_OPTION_KEYS, (), "joint_limits")
    if all(x == -float("inf") for x in lo):
        if options is not None:
            raise StateError("joint_limits", "needs at least one joint with a position and a range")
        return None
    opts = {k: options[k] for k in _LIMIT_OPTION_KEYS if options is not None and k in options}
    return JointLimits(np.array(pos), np.array(lo), np.array(hi), **opts)


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    # json keeps the last of repeated keys; a state with two "mu" would be silently half-read.
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise StateError(key, "repeated key in a JSON object (each key may appear once)")
        out[key] = value
    return out


def _decode(raw: bytes, what: str) -> str:
    if len(raw) > MAX_FILE_BYTES:
        raise StateError("", f"{what} is larger than {MAX_FILE_BYTES} bytes: not a state")
    try:
        return raw.decode("utf-8-sig")  # RFC 8259 JSON is UTF-8; a leading BOM is tolerated
    except UnicodeDecodeError as e:
        raise StateError(
            "", f"{what} is not UTF-8 text: byte 0x{raw[e.start]:02x} at offset {e.start}"
        ) from e


def load_state(source: str | bytes | os.PathLike[str] | Mapping[str, Any]) -> GraspState:
    """Read a ``mjtvm.state/1`` grasp state from a path, JSON text or bytes, or a mapping.

    Parameters
    ----------
    source
        A path (``str`` or path-like) of a UTF-8 JSON file; a ``str`` that starts with
        ``{`` (after white space) is JSON text; ``bytes`` are the content of a file; a
        mapping is an already decoded document (its values may be numpy arrays).

    Raises
    ------
    StateError
        Unreadable or non-UTF-8 file, malformed JSON, a repeated key, nesting deeper
        than a state can be, or any field that breaks the contract (the error names the
        field; ``docs/state-format.md`` lists the rules and bounds).
    """
    if isinstance(source, Mapping):
        check_json_tree(source)
        return _gated(source)
    if isinstance(source, (bytes, bytearray)):
        text = _decode(bytes(source), "the state")
    elif isinstance(source, str) and source.lstrip().startswith("{"):
        if len(source) > MAX_FILE_BYTES:
            raise StateError("", f"the state text is longer than {MAX_FILE_BYTES} characters: not a state")
        text = source
    elif isinstance(source, (str, os.PathLike)):
        path = Path(source)
        try:
            with path.open("rb") as f:
                raw = f.read(MAX_FILE_BYTES + 1)  # bounded: a device or a huge file is refused
        except OSError as e:
            raise StateError("", f"cannot read state file {str(path)!r}: {e.strerror or e}") from e
        except ValueError as e:  # e.g. an embedded NUL character in the path
            raise StateError("", f"cannot read state file {str(path)!r}: {e}") from e
        text = _decode(raw, f"state file {str(path)!r}")
    else:
        raise StateError("", f"expected a path, JSON text or a mapping, got {type(source).__name__}")
    try:
        # NaN and Infinity decode to floats here so that the field checks name the field.
        data = json.loads(text, object_pairs_hook=_unique_keys)
    except StateError:  # from _unique_keys
        raise
    except json.JSONDecodeError as e:
        raise StateError("", f"malformed JSON at line {e.lineno} column {e.colno}: {e.msg}") from e
    except RecursionError as e:
        raise StateError("", "malformed state: JSON nested too deep (a state needs at most 6 levels)") from e
    except ValueError as e:  # an integer literal of more than 4300 digits (int_max_str_digits)
        raise StateError("", f"malformed JSON: {str(e).split(':')[0]}") from e
    check_json_tree(data)
    return _gated(data)


def _gated(data: Mapping[str, Any]) -> GraspState:
    """The state, refused where ``state.schema.json`` refuses it ([`mjtvm.formats.schema`][mjtvm.formats.schema]):
    the field checks word the refusal when they see it; the schema has the last word."""
    problem = schema_problem("state", data)
    state = parse_state(data)
    if problem is not None:
        raise StateError(*problem)
    return state


def state_to_dict(state: GraspState) -> dict[str, Any]:
    """The ``mjtvm.state/1`` document of a state (``mjtvm.state/2`` with a transmission;
    JSON-ready, lossless floats)."""
    contacts = []
    for c in state.contacts:
        entry: dict[str, Any] = {
            "name": c.name,
            "type": c.type,
            "position": c.position.tolist(),
            "normal": c.normal.tolist(),
        }
        if c.mu is not None:
            entry["mu"] = c.mu
        entry["jacobian"] = c.jacobian.tolist()
        if c.tangent is not None:
            entry["tangent"] = c.tangent.tolist()
        if c.slide_direction is not None:
            entry["slide_direction"] = c.slide_direction.tolist()
        if c.preload > 0.0:
            entry["preload"] = c.preload
        if c.mu_range is not None:
            entry["mu_range"] = list(c.mu_range)
        contacts.append(entry)
    t = state.transmission
    out: dict[str, Any] = {
        "schema": SCHEMA if t is None else SCHEMA_V2,
        "space": state.space,
        "object_position": state.object_position.tolist(),
        "joints": _joints_to_list(state),
        "gravity_torque": state.gravity_torque.tolist(),
        "contacts": contacts,
        "refs": state.refs.tolist(),
    }
    if state.rvds is not None:
        out["rvds"] = state.rvds.tolist()
    out["friction_edges"] = state.friction_edges
    if state.slip != "per_contact":
        out["slip"] = state.slip
    if state.friction_margin > 0.0:
        out["friction_margin"] = state.friction_margin
    if t is not None:
        out["transmission"] = transmission_to_dict(t, state.operation_ranges)
    lim = state.joint_limits
    if lim is not None:
        out["joint_limits"] = {"tolerance": lim.tolerance, "horizon": lim.horizon}
    return out


def _joints_to_list(state: GraspState) -> list[dict[str, Any]]:
    """The ``joints`` list: names, operation ranges (without a transmission), and each
    limited joint's ``position`` and ``range``."""
    t, lim = state.transmission, state.joint_limits
    out: list[dict[str, Any]] = []
    for j, name in enumerate(state.joint_names):
        entry: dict[str, Any] = {"name": name}
        if t is None:
            entry["operation_range"] = state.operation_ranges[j].to_list()
        if lim is not None and lim.limited[j]:
            entry["position"] = float(lim.position[j])
            entry["range"] = [float(lim.lower[j]), float(lim.upper[j])]
        out.append(entry)
    return out


def dump_state(
    state: GraspState, path: str | os.PathLike[str] | None = None, *, indent: int | None = 1
) -> str:
    """Serialise a state as ``mjtvm.state/1`` JSON text, and write it to ``path`` if given.

    Parameters
    ----------
    state
        The state (validated at construction, so the text always loads again).
    path
        Optional file to write (UTF-8, with a final newline). The text goes to a
        temporary file in the same folder, which then replaces ``path`` in one step
        (``os.replace``): a reader sees the old file or the new one, never a part.
    indent
        JSON indentation (``None``: one line).

    Returns
    -------
    str
        The JSON text (without the final newline).

    Raises
    ------
    OutputError
        When ``path`` cannot be written (its ``path`` attribute names it); the previous
        file, if any, is left as it was.
    """
    text = json.dumps(state_to_dict(state), indent=indent, allow_nan=False)
    if path is not None:
        atomic_write(Path(path), text + "\n", option="path")
    return text
