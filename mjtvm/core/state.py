r"""Grasp states and the ``mjtvm.state/1`` JSON contract (``docs/state-format.md``).

A :class:`GraspState` is everything the TVM core needs at one instant: joints with
their operation ranges and gravity torques, contacts with Jacobians, the REFS and the
RVDS. Every vector is in the world frame, SI units. The JSON form is exact: unknown or
repeated keys, wrong shapes, NaN, numbers beyond the bounds of :mod:`mjtvm.core.bounds`,
non-unit normals, bad operation ranges each raise one :class:`~mjtvm.errors.StateError`
naming the field. The format is described in ``docs/state-format.md`` and, as a JSON
Schema, in ``mjtvm/data/schema/state.schema.json``.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from ..errors import StateError
from .bounds import (
    MAX_CONTACTS,
    MAX_FILE_BYTES,
    MAX_FRICTION_EDGES,
    MAX_JOINTS,
    MAX_NAME,
    MAX_REFS,
    MAX_RVDS,
    MIN_FRICTION_EDGES,
    check_json_tree,
    describe,
    float_array,
    integer,
)
from .contacts import Contact
from .files import atomic_write
from .operation_range import OperationRange
from .schema import schema_problem

__all__ = ["SCHEMA", "GraspState", "dump_state", "load_state", "parse_state", "state_to_dict"]

SCHEMA = "mjtvm.state/1"
SlipMode = Literal["per_contact", "shared"]
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
}
_REQUIRED_TOP = ("schema", "space", "object_position", "joints", "gravity_torque", "contacts", "refs")
_JOINT_KEYS = {"name", "operation_range"}
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
}
_REQUIRED_CONTACT = ("name", "type", "position", "normal", "jacobian")


def _matrix(value: Any, field: str, cols: int, max_rows: int) -> NDArray[np.float64]:
    what = f"a non-empty list of vectors of {cols} numbers"
    m = float_array(value, field, ndim=2, max_len=max_rows, max_width=cols, what=what)
    if m.shape[1:] != (cols,) or m.shape[0] == 0:
        raise StateError(field, f"expected {what}, got shape {m.shape}", value)
    return m


def _name(value: Any, field: str) -> str:
    if not isinstance(value, str) or not value:
        raise StateError(field, f"expected a non-empty string, got {describe(value)}", value)
    if len(value) > MAX_NAME:
        raise StateError(field, f"expected at most {MAX_NAME} characters, got {len(value)}", value)
    try:
        value.encode("utf-8")
    except UnicodeEncodeError as e:  # a lone surrogate from a JSON escape such as "\ud800"
        raise StateError(field, "expected valid Unicode text (no lone surrogates)", value) from e
    return value


@dataclass(frozen=True, eq=False)
class GraspState:
    r"""One grasp state: the data of Problems 1 and 2.

    Parameters
    ----------
    space
        3 (spatial: d = 3, D = 6) or 2 (planar: d = 2, D = 3).
    object_position
        ``(d,)`` :math:`p_O`, the point about which moments are taken (m).
    joint_names
        The M joints, in the order of every joint-indexed vector.
    operation_ranges
        One :class:`OperationRange` per joint (eq. 1).
    gravity_torque
        ``(M,)`` :math:`g_f` (N m): the joint torques that hold the fingers against gravity (eq. 19).
    contacts
        The L contacts.
    refs
        ``(K, D)`` REFS vertices :math:`w_k` = [force; moment about p_O] to balance (eq. 5).
    rvds
        ``(R, D)`` RVDS vertices :math:`\hat r_l` = [v of p_O; omega] (eq. 30), or ``None``.
    friction_edges
        Edges of each friction pyramid in space (ignored in the plane).
    slip
        ``"per_contact"`` (one slip speed per S contact) or ``"shared"`` (eq. 34 literally).
    """

    space: int
    object_position: NDArray[np.float64]
    joint_names: tuple[str, ...]
    operation_ranges: tuple[OperationRange, ...]
    gravity_torque: NDArray[np.float64]
    contacts: tuple[Contact, ...]
    refs: NDArray[np.float64]
    rvds: NDArray[np.float64] | None = None
    friction_edges: int = 16
    slip: SlipMode = "per_contact"

    def __post_init__(self) -> None:
        space = self.space
        if isinstance(space, float) and space in (2.0, 3.0):
            space = int(space)  # JSON 3.0, as for every integer of the format
        if not isinstance(space, (int, np.integer)) or isinstance(space, bool) or space not in (2, 3):
            raise StateError("space", f"expected 2 or 3, got {describe(self.space)}", self.space)
        object.__setattr__(self, "space", int(space))
        d, big_d = self.dim, self.twist_dim
        pos = float_array(self.object_position, "object_position", ndim=1, what=f"{d} finite numbers")
        if pos.shape != (d,):
            raise StateError(
                "object_position", f"expected {d} finite numbers, got {pos.shape[0]}", pos.tolist()
            )
        object.__setattr__(self, "object_position", pos)
        names = tuple(self.joint_names)
        if len(names) == 0:
            raise StateError("joints", "expected at least one joint")
        if len(names) > MAX_JOINTS:
            raise StateError("joints", f"expected at most {MAX_JOINTS} joints, got {len(names)}")
        for i, name in enumerate(names):
            _name(name, f"joints[{i}].name")
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise StateError("joints", f"joint names must be unique; repeated: {dup}")
        object.__setattr__(self, "joint_names", names)
        ranges = tuple(self.operation_ranges)
        if len(ranges) != len(names):
            raise StateError(
                "joints", f"expected one operation range per joint ({len(names)}), got {len(ranges)}"
            )
        for i, r in enumerate(ranges):
            if not isinstance(r, OperationRange):
                raise StateError(f"joints[{i}].operation_range", "expected an OperationRange")
        object.__setattr__(self, "operation_ranges", ranges)
        m = len(names)
        g = float_array(
            self.gravity_torque, "gravity_torque", ndim=1, what=f"{m} finite numbers (one per joint)"
        )
        if g.shape != (m,):
            raise StateError(
                "gravity_torque", f"expected {m} finite numbers (one per joint), got {g.shape[0]}", g.tolist()
            )
        object.__setattr__(self, "gravity_torque", g)
        contacts = tuple(self.contacts)
        if len(contacts) > MAX_CONTACTS:
            raise StateError("contacts", f"expected at most {MAX_CONTACTS} contacts, got {len(contacts)}")
        for i, c in enumerate(contacts):
            if not isinstance(c, Contact):
                raise StateError(f"contacts[{i}]", "expected a Contact")
            _name(c.name, f"contacts[{i}].name")
            if c.dim != d:
                raise StateError(f"contacts[{i}].position", f"expected {d} numbers in a space-{d} state")
            if c.num_joints != m:
                raise StateError(
                    f"contacts[{i}].jacobian",
                    f"expected {d} x {m} (one column per joint), got {c.jacobian.shape}",
                )
        cnames = [c.name for c in contacts]
        if len(set(cnames)) != len(cnames):
            dup = sorted({n for n in cnames if cnames.count(n) > 1})
            raise StateError("contacts", f"contact names must be unique; repeated: {dup}")
        object.__setattr__(self, "contacts", contacts)
        object.__setattr__(self, "refs", _matrix(self.refs, "refs", big_d, MAX_REFS))
        if self.rvds is not None:
            object.__setattr__(self, "rvds", _matrix(self.rvds, "rvds", big_d, MAX_RVDS))
        fe = integer(self.friction_edges, "friction_edges", MIN_FRICTION_EDGES, MAX_FRICTION_EDGES)
        object.__setattr__(self, "friction_edges", fe)
        if not isinstance(self.slip, str) or self.slip not in ("per_contact", "shared"):
            raise StateError(
                "slip", f"expected 'per_contact' or 'shared', got {describe(self.slip)}", self.slip
            )

    @property
    def dim(self) -> int:
        """d: 2 in the plane, 3 in space."""
        return int(self.space)

    @property
    def twist_dim(self) -> int:
        """D: 3 in the plane, 6 in space."""
        return 3 if self.space == 2 else 6

    @property
    def num_joints(self) -> int:
        """M."""
        return len(self.joint_names)

    def with_(self, **changes: Any) -> GraspState:
        """A validated copy with some fields replaced (``dataclasses.replace``)."""
        return replace(self, **changes)


# ---------------------------------------------------------------------- JSON
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
    """Validate a decoded ``mjtvm.state/1`` document and build a :class:`GraspState`.

    ``data`` is expected to be plain JSON data (see :func:`load_state`, which also checks
    the nesting depth and the value types of a mapping before calling this).
    """
    _check_keys(data, _TOP_KEYS, _REQUIRED_TOP, "")
    if data["schema"] != SCHEMA:
        raise StateError("schema", f"expected {SCHEMA!r}, got {describe(data['schema'])}", data["schema"])
    joints = data["joints"]
    if not isinstance(joints, (list, tuple)):
        raise StateError("joints", f"expected a list of joints, got {describe(joints)}")
    if len(joints) > MAX_JOINTS:  # before building anything from them
        raise StateError("joints", f"expected at most {MAX_JOINTS} joints, got {len(joints)}")
    names, ranges = [], []
    for i, j in enumerate(joints):
        _check_keys(j, _JOINT_KEYS, ("name", "operation_range"), f"joints[{i}]")
        names.append(_name(j["name"], f"joints[{i}].name"))
        try:
            ranges.append(OperationRange(j["operation_range"]))
        except StateError as e:
            raise e.under(f"joints[{i}].operation_range") from None
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
    kwargs: dict[str, Any] = {}
    if "friction_edges" in data:
        kwargs["friction_edges"] = data["friction_edges"]
    if "slip" in data:
        kwargs["slip"] = data["slip"]
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
        raise StateError("", "malformed state: JSON nested too deep (a state needs at most 5 levels)") from e
    except ValueError as e:  # an integer literal of more than 4300 digits (int_max_str_digits)
        raise StateError("", f"malformed JSON: {str(e).split(':')[0]}") from e
    check_json_tree(data)
    return _gated(data)


def _gated(data: Mapping[str, Any]) -> GraspState:
    """The state, refused where ``state.schema.json`` refuses it (:mod:`mjtvm.core.schema`):
    the field checks word the refusal when they see it; the schema has the last word."""
    problem = schema_problem("state", data)
    state = parse_state(data)
    if problem is not None:
        raise StateError(*problem)
    return state


def state_to_dict(state: GraspState) -> dict[str, Any]:
    """The ``mjtvm.state/1`` document of a state (JSON-ready, lossless floats)."""
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
        contacts.append(entry)
    out: dict[str, Any] = {
        "schema": SCHEMA,
        "space": state.space,
        "object_position": state.object_position.tolist(),
        "joints": [
            {"name": n, "operation_range": r.to_list()}
            for n, r in zip(state.joint_names, state.operation_ranges)
        ],
        "gravity_torque": state.gravity_torque.tolist(),
        "contacts": contacts,
        "refs": state.refs.tolist(),
    }
    if state.rvds is not None:
        out["rvds"] = state.rvds.tolist()
    out["friction_edges"] = state.friction_edges
    if state.slip != "per_contact":
        out["slip"] = state.slip
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
