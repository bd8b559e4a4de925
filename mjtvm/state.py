r"""Grasp states and the ``mjtvm.state/1`` JSON contract (``shared/state-schema.md``).

A :class:`GraspState` is everything the TVM core needs at one instant: joints with
their operation ranges and gravity torques, contacts with Jacobians, the REFS and the
RVDS. Every vector is in the world frame, SI units. The JSON form is exact: unknown
keys, wrong shapes, NaN, non-unit normals, bad operation ranges each raise one
:class:`~mjtvm.errors.StateError` naming the field.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from .contacts import Contact
from .errors import StateError
from .operation_range import OperationRange

__all__ = ["SCHEMA", "GraspState", "dump_state", "json_floats", "load_state", "parse_state", "state_to_dict"]

SCHEMA = "mjtvm.state/1"
SlipMode = Literal["per_contact", "shared"]
_TOP_KEYS = {
    "schema", "space", "object_position", "joints", "gravity_torque", "contacts",
    "refs", "rvds", "friction_edges", "slip",
}  # fmt: skip
_REQUIRED_TOP = ("schema", "space", "object_position", "joints", "gravity_torque", "contacts", "refs")
_JOINT_KEYS = {"name", "operation_range"}
_CONTACT_KEYS = {"name", "type", "position", "normal", "mu", "jacobian", "tangent", "slide_direction"}
_REQUIRED_CONTACT = ("name", "type", "position", "normal", "jacobian")


def _matrix(value: Any, field: str, cols: int) -> NDArray[np.float64]:
    try:
        m = np.array(value, dtype=float)
    except (TypeError, ValueError) as e:
        raise StateError(field, f"expected a list of vectors of {cols} numbers", value) from e
    if m.ndim != 2 or m.shape[1] != cols or m.shape[0] == 0:
        raise StateError(
            field, f"expected a non-empty list of vectors of {cols} numbers, got shape {m.shape}", value
        )
    if not np.all(np.isfinite(m)):
        raise StateError(field, "expected finite numbers (no NaN or infinity)", value)
    m.setflags(write=False)
    return m


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
        if isinstance(self.space, bool) or self.space not in (2, 3):
            raise StateError("space", f"expected 2 or 3, got {self.space!r}", self.space)
        d, big_d = self.dim, self.twist_dim
        pos = np.array(self.object_position, dtype=float)
        if pos.shape != (d,) or not np.all(np.isfinite(pos)):
            raise StateError("object_position", f"expected {d} finite numbers", self.object_position)
        pos.setflags(write=False)
        object.__setattr__(self, "object_position", pos)
        names = tuple(self.joint_names)
        if len(names) == 0:
            raise StateError("joints", "expected at least one joint")
        for i, name in enumerate(names):
            if not isinstance(name, str) or not name:
                raise StateError(f"joints[{i}].name", "expected a non-empty string", name)
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
        g = np.array(self.gravity_torque, dtype=float)
        if g.shape != (m,) or not np.all(np.isfinite(g)):
            raise StateError(
                "gravity_torque", f"expected {m} finite numbers (one per joint)", self.gravity_torque
            )
        g.setflags(write=False)
        object.__setattr__(self, "gravity_torque", g)
        contacts = tuple(self.contacts)
        for i, c in enumerate(contacts):
            if not isinstance(c, Contact):
                raise StateError(f"contacts[{i}]", "expected a Contact")
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
        object.__setattr__(self, "refs", _matrix(self.refs, "refs", big_d))
        if self.rvds is not None:
            object.__setattr__(self, "rvds", _matrix(self.rvds, "rvds", big_d))
        fe = self.friction_edges
        if isinstance(fe, bool) or not isinstance(fe, (int, np.integer)) or fe < 3:
            raise StateError("friction_edges", f"expected an integer >= 3, got {fe!r}", fe)
        object.__setattr__(self, "friction_edges", int(fe))
        if self.slip not in ("per_contact", "shared"):
            raise StateError("slip", f"expected 'per_contact' or 'shared', got {self.slip!r}", self.slip)

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
    """Validate a decoded ``mjtvm.state/1`` document and build a :class:`GraspState`."""
    _check_keys(data, _TOP_KEYS, _REQUIRED_TOP, "")
    if data["schema"] != SCHEMA:
        raise StateError("schema", f"expected {SCHEMA!r}, got {data['schema']!r}", data["schema"])
    joints = data["joints"]
    if not isinstance(joints, list):
        raise StateError("joints", "expected a list of joints")
    names, ranges = [], []
    for i, j in enumerate(joints):
        _check_keys(j, _JOINT_KEYS, ("name", "operation_range"), f"joints[{i}]")
        names.append(j["name"])
        try:
            ranges.append(OperationRange(j["operation_range"]))
        except StateError as e:
            raise e.under(f"joints[{i}].operation_range") from None
    contacts_in = data["contacts"]
    if not isinstance(contacts_in, list):
        raise StateError("contacts", "expected a list of contacts")
    contacts = []
    space = data["space"]
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
        kwargs["rvds"] = data["rvds"]
    return GraspState(
        space=space,
        object_position=data["object_position"],
        joint_names=tuple(names),
        operation_ranges=tuple(ranges),
        gravity_torque=data["gravity_torque"],
        contacts=tuple(contacts),
        refs=data["refs"],
        **kwargs,
    )


def load_state(source: str | Path | Mapping[str, Any]) -> GraspState:
    """Read a ``mjtvm.state/1`` grasp state from a path, a JSON string or a mapping.

    Raises
    ------
    StateError
        Malformed JSON, or any field that breaks the contract (the error names it).
    """
    if isinstance(source, Mapping):
        return parse_state(source)
    text = str(source)
    if isinstance(source, Path) or not text.lstrip().startswith("{"):
        path = Path(source)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as e:
            raise StateError("", f"cannot read state file {str(path)!r}: {e.strerror}") from e
    try:
        # NaN and Infinity decode to floats here so that the field checks name the field.
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise StateError("", f"malformed JSON at line {e.lineno} column {e.colno}: {e.msg}") from e
    return parse_state(data)


def json_floats(values: Any) -> Any:
    """Nested lists of floats for JSON, with signed zeros printed as 0.0 (-0.0 + 0.0 == +0.0)."""
    return (np.asarray(values, dtype=float) + 0.0).tolist()


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


def dump_state(state: GraspState, *, indent: int | None = 1) -> str:
    """Serialise a state as ``mjtvm.state/1`` JSON text."""
    return json.dumps(state_to_dict(state), indent=indent)
