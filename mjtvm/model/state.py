r"""Grasp states and the ``mjtvm.state/1`` JSON contract (``docs/state-format.md``).

A [`GraspState`][mjtvm.model.state.GraspState] is everything the TVM core needs at one instant: joints with
their operation ranges and gravity torques, contacts with Jacobians, the REFS and the
RVDS. Every vector is in the world frame, SI units. The JSON form is exact: unknown or
repeated keys, wrong shapes, NaN, numbers beyond the bounds of `mjtvm.model.bounds`,
non-unit normals, bad operation ranges each raise one [`StateError`][mjtvm.errors.StateError]
naming the field. The format is described in ``docs/state-format.md`` and, as a JSON
Schema, in ``mjtvm/data/schema/state.schema.json``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import StateError
from mjtvm.model.bounds import (
    MAX_CONTACTS,
    MAX_FRICTION_EDGES,
    MAX_JOINTS,
    MAX_REFS,
    MAX_RVDS,
    MIN_FRICTION_EDGES,
    checked_name,
    describe,
    float_array,
    integer,
    number,
)
from mjtvm.model.contacts import Contact
from mjtvm.model.limits import JointLimits
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.transmission import Transmission

__all__ = ["SCHEMA", "SCHEMA_V2", "GraspState"]

SCHEMA = "mjtvm.state/1"  # a state whose joints are each driven by their own actuator
SCHEMA_V2 = "mjtvm.state/2"  # version 1 and a transmission (mjtvm.model.transmission)
SlipMode = Literal["per_contact", "shared"]


def _matrix(value: Any, field: str, cols: int, max_rows: int) -> NDArray[np.float64]:
    what = f"a non-empty list of vectors of {cols} numbers"
    m = float_array(value, field, ndim=2, max_len=max_rows, max_width=cols, what=what)
    if m.shape[1:] != (cols,) or m.shape[0] == 0:
        raise StateError(field, f"expected {what}, got shape {m.shape}", value)
    return m


@dataclass(frozen=True, eq=False)
class GraspState:
    r"""One grasp state: the data of Problems 1 and 2.

    Parameters
    ----------
    space
        3 (spatial: d = 3, D = 6) or 2 (planar: d = 2, D = 3).
    object_position
        ``(d,)`` $p_O$, the point about which moments are taken (m).
    joint_names
        The M joints, in the order of every joint-indexed vector.
    operation_ranges
        One `OperationRange` per joint (eq. 1), or per actuator of ``transmission``.
    gravity_torque
        ``(M,)`` $g_f$ (N m): the joint torques that hold the fingers against gravity (eq. 19).
    contacts
        The L contacts.
    refs
        ``(K, D)`` REFS vertices $w_k$ = [force; moment about p_O] to balance (eq. 5).
    rvds
        ``(R, D)`` RVDS vertices $\hat r_l$ = [v of p_O; omega] (eq. 30), or ``None``.
    friction_edges
        Edges of each friction pyramid in space (ignored in the plane).
    slip
        ``"per_contact"`` (one slip speed per S contact) or ``"shared"`` (eq. 34 literally).
    transmission
        How actuators and equality constraints act on the joints
        ([`Transmission`][mjtvm.model.transmission.Transmission]), or ``None``: each joint is driven
        by its own actuator, as in the paper.
    friction_margin
        $\delta \in [0, 1)$ (default 0): the LPs use $(1 - \delta) \mu$ for every
        F contact's friction pyramid (eq. 24), so that the witness forces keep a distance from
        the cone (`mjtvm.model.friction`; S contacts keep ``mu``, ``docs/state-format.md``).
    joint_limits
        The joints' positions and position ranges (`JointLimits`:
        a joint on its limit cannot move further into it), or ``None``: no position limits,
        the paper's LPs.
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
    transmission: Transmission | None = None
    friction_margin: float = 0.0
    joint_limits: JointLimits | None = None

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
            checked_name(name, f"joints[{i}].name")
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise StateError("joints", f"joint names must be unique; repeated: {dup}")
        object.__setattr__(self, "joint_names", names)
        ranges = tuple(self.operation_ranges)
        t = self.transmission
        if t is not None and not isinstance(t, Transmission):
            raise StateError("transmission", f"expected a Transmission or None, got {describe(t)}")
        if t is not None and t.num_joints != len(names):
            raise StateError(
                "transmission.moment", f"expected {len(names)} columns (one per joint), got {t.num_joints}"
            )
        if len(ranges) != (len(names) if t is None else len(t.actuator_names)):
            per = f"joint ({len(names)})" if t is None else f"actuator ({len(t.actuator_names)})"
            raise StateError("joints", f"expected one operation range per {per}, got {len(ranges)}")
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
            checked_name(c.name, f"contacts[{i}].name")
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
        margin = number(self.friction_margin, "friction_margin")
        if not 0.0 <= margin < 1.0:
            raise StateError(
                "friction_margin", f"expected a number in [0, 1), got {margin!r}", self.friction_margin
            )
        object.__setattr__(self, "friction_margin", margin)
        lim = self.joint_limits
        if lim is not None and not isinstance(lim, JointLimits):
            raise StateError("joint_limits", f"expected JointLimits or None, got {describe(lim)}")
        if lim is not None and lim.num_joints != m:
            raise StateError("joints", f"expected {m} joint positions and ranges, got {lim.num_joints}")

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

    @property
    def actuator_names(self) -> tuple[str, ...]:
        """The names of `operation_ranges`: the actuators, or the joints without a
        transmission."""
        return self.joint_names if self.transmission is None else self.transmission.actuator_names

    def actuator_speeds(self, qd: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(A,)`` the actuator speeds ``P qd`` of joint speeds ``qd`` (``qd`` itself
        without a transmission)."""
        return np.asarray(qd, dtype=float) if self.transmission is None else self.transmission.moment @ qd

    def with_(self, **changes: Any) -> GraspState:
        """A validated copy with some fields replaced (``dataclasses.replace``)."""
        return replace(self, **changes)
